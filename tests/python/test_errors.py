"""Bad input: a Python exception with the C++ message, never a crash; counted skips stay counted."""
import math

import numpy as np
import pytest

import rtog


def test_bad_options_name_the_option():
    with pytest.raises(ValueError, match="unknown map option 'resolutoin'"):
        rtog.Map(0.05, resolutoin=0.1)
    with pytest.raises(ValueError, match="sensorModelPreset"):
        rtog.Map(0.05, sensorModelPreset="bonxai")
    with pytest.raises(ValueError, match="rangeNoiseCutoff"):
        rtog.Map(0.05, rangeNoiseCutoff=50)
    with pytest.raises(ValueError, match="resolution"):
        rtog.Map(-1.0)


def test_bad_arrays_are_value_errors():
    m = rtog.Map(0.05)
    with pytest.raises(ValueError, match=r"points: expected an array of shape \(N, 3\)"):
        m.insert_point_cloud(np.zeros((4, 2), np.float32), (0, 0, 0))
    with pytest.raises(ValueError, match="origin"):
        m.insert_point_cloud(np.zeros((4, 3), np.float32), (0, 0))
    with pytest.raises(ValueError, match="not finite"):
        m.insert_point_cloud(np.ones((4, 3), np.float32), (math.nan, 0, 0))
    with pytest.raises(ValueError, match="rigid"):
        m.insert_depth_image(np.zeros((4, 4), np.uint16), np.eye(4) * 2)
    with pytest.raises(ValueError, match="uint16"):
        m.insert_depth_image(np.zeros((4, 4), np.complex64), np.eye(4))
    with pytest.raises(ValueError, match="is_hit"):
        m.insert_point_cloud(np.ones((4, 3), np.float32), (0, 0, 0), is_hit=np.ones(3, np.uint8))
    assert len(m) == 0


def test_non_finite_points_are_counted_not_inserted():
    m = rtog.Map(0.05)
    pts = np.array([[1, 0, 0], [math.nan, 0, 0], [math.inf, 1, 1], [0, 0, 0], [1e9, 0, 0]], np.float32)
    s = m.insert_point_cloud(pts, (0, 0, 0))
    assert s["rays_hit"] == 1 and s["skipped_non_finite"] == 2
    assert s["skipped_zero_length"] == 1 and s["skipped_out_of_range"] == 1


def test_pose_covariance_needs_the_option():
    m = rtog.Map(0.05)
    with pytest.raises(ValueError, match="poseUncertainty"):
        m.insert_scan_2d(np.ones(10, np.float32), (0, 0, 0), pose_cov=np.eye(3) * 0.01)
    m = rtog.Map(0.05, poseUncertainty="on")
    with pytest.raises(ValueError, match="covariance"):
        m.insert_scan_2d(np.ones(10, np.float32), (0, 0, 0), pose_cov=-np.eye(3))


def test_files(tmp_path):
    with pytest.raises(RuntimeError, match="cannot open map file"):
        rtog.Map.load(str(tmp_path / "missing.rtog"))
    bad = tmp_path / "bad.rtog"
    bad.write_bytes(b"\x1f\x8b\x08\x00garbage")
    with pytest.raises(RuntimeError, match="bad.rtog"):
        rtog.Map.load(str(bad))
    m = rtog.Map(0.05)
    m.insert_point_cloud(np.array([[1, 0, 0]], np.float32), (0, 0, 0))
    m.save(str(tmp_path / "m.rtog"), format="core")
    data = (tmp_path / "m.rtog").read_bytes()
    (tmp_path / "cut.rtog").write_bytes(data[: len(data) // 2])
    with pytest.raises(RuntimeError, match="cut.rtog"):
        rtog.Map.load(str(tmp_path / "cut.rtog"))
    with pytest.raises(ValueError, match="format"):
        m.save(str(tmp_path / "x"), format="pcd")
    with pytest.raises(RuntimeError, match="cannot read depth image"):
        rtog.read_depth_png(str(tmp_path / "none.png"))


def test_map_operations_refuse_what_would_corrupt():
    m = rtog.Map(0.05)
    with pytest.raises(ValueError, match="itself"):
        m.fuse(m)
    with pytest.raises(ValueError):
        m.set_cells(np.zeros((2, 3), np.int32), np.ones((2, 3), np.int32), np.zeros(2, np.float32))  # overlap
    with pytest.raises(ValueError):
        m.set_cells(np.zeros((1, 3), np.int32), np.zeros((1, 3), np.int32), np.array([50.0], np.float32))  # beyond clamping
    assert len(m) == 0 and m.check_invariants() == ""
