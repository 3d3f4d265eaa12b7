# The Debian package of the build tree (cmake/packaging.cmake): made by cpack, unpacked into a
# scratch root, its tools run from there, and a stock MRPT app run with its plugin through its
# launcher, on SENA with the icp-slam config it ships.
set(root "${WORK_DIR}/root")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
execute_process(COMMAND ${CMAKE_CPACK_COMMAND} -G DEB -B "${WORK_DIR}/deb" WORKING_DIRECTORY "${BUILD_DIR}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
file(GLOB debs "${WORK_DIR}/deb/*.deb")
list(LENGTH debs n)
if(rc OR NOT n EQUAL 1)
  message(FATAL_ERROR "cpack -G DEB: exit ${rc}, ${n} packages:\n${out}")
endif()
execute_process(COMMAND dpkg-deb -f ${debs} Package Version Depends OUTPUT_VARIABLE fields RESULT_VARIABLE rc)
if(rc OR NOT fields MATCHES "Package: rtog" OR NOT fields MATCHES "libmrpt-maps2.5")
  message(FATAL_ERROR "the package's control fields:\n${fields}")
endif()
execute_process(COMMAND dpkg-deb -x ${debs} "${root}" RESULT_VARIABLE rc)
foreach(f usr/bin/rtog usr/bin/rtog-mrpt usr/lib/librtog_mrpt.so usr/include/rtog/core/occupancy_map.hpp
          usr/lib/cmake/rtog/rtogConfig.cmake usr/share/rtog/config/icp-slam_rtog.ini)
  if(rc OR NOT EXISTS "${root}/${f}")
    message(FATAL_ERROR "the package lacks ${f}")
  endif()
endforeach()
execute_process(COMMAND "${root}/usr/bin/rtog-mrpt" --which OUTPUT_VARIABLE plugin RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
if(rc OR NOT EXISTS "${plugin}")
  message(FATAL_ERROR "the packaged rtog-mrpt does not find the packaged plugin: '${plugin}'")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env LD_LIBRARY_PATH=${root}/usr/lib "${root}/usr/bin/rtog" --help
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "the packaged rtog --help: exit ${rc}")
endif()
# icp-slam writes into the run directory; the config names the datasets directory.
file(READ "${root}/usr/share/rtog/config/icp-slam_rtog.ini" ini)
string(REPLACE "/usr/share/mrpt/datasets" "${DATASETS}" ini "${ini}")
file(WRITE "${WORK_DIR}/run/icp-slam_rtog.ini" "${ini}")
execute_process(COMMAND "${root}/usr/bin/rtog-mrpt" icp-slam icp-slam_rtog.ini
                        "${DATASETS}/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"
                WORKING_DIRECTORY "${WORK_DIR}/run" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
file(GLOB maps "${WORK_DIR}/run/LOG_ICP-SLAM_RTOG/_finalmaps_*CRTreeOccupancyGridMap_*.rtog")
if(rc OR NOT maps)
  string(LENGTH "${out}" len)
  math(EXPR from "${len} - 3000")
  if(from LESS 0)
    set(from 0)
  endif()
  string(SUBSTRING "${out}" ${from} -1 tail)
  message(FATAL_ERROR "icp-slam through the packaged launcher: exit ${rc}, no rtog map saved\n${tail}")
endif()
if(PYTHON)
  # The module from the package's dist-packages, its library from the package's lib.
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${root}/usr/lib/python3/dist-packages LD_LIBRARY_PATH=${root}/usr/lib
                          ${PYTHON} -c "import rtog, numpy as np; m = rtog.Map(0.05); m.insert_point_cloud(np.ones((1, 3), np.float32), (0, 0, 0)); assert len(m) > 0; print(rtog.__file__)"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(rc OR NOT out MATCHES "${root}/usr/lib/python3/dist-packages/rtog/__init__.py")
    message(FATAL_ERROR "import rtog from the package: exit ${rc}\n${out}")
  endif()
endif()
message(STATUS "package ${debs}: tools, headers, config, plugin and Python module in place; icp-slam ran with the packaged plugin")
