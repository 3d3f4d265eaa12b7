# Debian packages (`cpack -G DEB` in the build tree): one package, rtog, with the libraries (the
# MRPT plugin librtog_mrpt.so among them), the headers and CMake config, the tools (rtog,
# rtog-simlog, the rtog-mrpt launcher), share/rtog and the Python module (in Debian's
# dist-packages, for the python3 it was built against). Installed under /usr; the shared
# libraries' dependencies come from dpkg-shlibdeps, the headers' (Eigen, MRPT, OpenCV for the
# image library) and the module's interpreter and NumPy are named.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rtog)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION "A probabilistic occupancy grid stored as an R-tree of cuboids, with MRPT map types (rtreeOccupancyGrid, rtreeGridMap2D), the rtog tool and the rtog-mrpt launcher for MRPT's apps.")
set(CPACK_PACKAGE_CONTACT "rtog maintainers <rtog@invalid>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libeigen3-dev, libmrpt-dev, libopencv-dev, libpng-dev")
if(RTOG_BUILD_PYTHON)
  # The extension's ABI tag (cpython-3XY) is one interpreter's.
  set(py "${Python3_VERSION_MAJOR}.${Python3_VERSION_MINOR}")
  math(EXPR next_minor "${Python3_VERSION_MINOR} + 1")
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS
         ", python3 (>= ${py}), python3 (<< ${Python3_VERSION_MAJOR}.${next_minor}), python3-numpy")
endif()
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "mrpt-apps")
include(CPack)
