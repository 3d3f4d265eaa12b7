"""The TUM map through Python is the map `rtog build` makes, leaf for leaf and byte for byte."""
import subprocess

import numpy as np

import rtog
from conftest import RTOG_EXE, TUM_DIR, build_tum, leaf_table


def test_tum_map_equals_rtog_build(tmp_path, tum_frames):
    cli = tmp_path / "cli.rtog"
    subprocess.run([RTOG_EXE, "build", "--tum", TUM_DIR, "--resolution", "0.05", "--stride", "2",
                    "--max-range", "0", "--out", str(cli)], check=True, capture_output=True)
    m = build_tum(tum_frames, stride=2)
    mine = leaf_table(m)
    theirs = leaf_table(rtog.Map.load(str(cli)))
    assert len(mine) > 100000
    assert np.array_equal(mine["lo"], theirs["lo"]) and np.array_equal(mine["hi"], theirs["hi"])
    assert np.array_equal(mine["v"].view(np.uint32), theirs["v"].view(np.uint32))  # bit for bit
    core = tmp_path / "py.rtog"
    m.save(str(core), format="core")
    assert core.read_bytes() == cli.read_bytes()
    assert m.check_invariants() == ""


def test_point_cloud_equals_depth_image(tum_frames):
    """The depth image's points given as an (N, 3) array make the same map (float32 read in place)."""
    a = build_tum(tum_frames[:3], stride=4)
    b = rtog.Map(0.05)
    for depth, pose in tum_frames[:3]:
        v, u = np.nonzero(depth[::4, ::4])
        v, u = v * 4, u * 4
        z = depth[v, u] / 5000.0
        pc = np.stack([(u - 325.1) * z / 520.9, (v - 249.7) * z / 521.0, z], axis=1)
        pts = (pc.astype(np.float32) @ pose[:3, :3].T.astype(np.float32) + pose[:3, 3].astype(np.float32))
        b.insert_point_cloud(pts.astype(np.float32), pose[:3, 3])
    ta, tb = leaf_table(a), leaf_table(b)
    # The back-projection in NumPy rounds like the C++ one except for a few end points on cell faces.
    same = np.isin(ta["lo"].view([("", "i4", 3)]).ravel(), tb["lo"].view([("", "i4", 3)]).ravel())
    assert same.mean() > 0.999


def test_save_load_round_trip(tmp_path, tum_map):
    for fmt in ("mrpt", "core"):
        path = tmp_path / f"m.{fmt}"
        tum_map.save(str(path), format=fmt)
        back = rtog.Map.load(str(path))
        assert back.resolution == tum_map.resolution
        a, b = leaf_table(tum_map), leaf_table(back)
        assert np.array_equal(a["v"], b["v"]) and np.array_equal(a["lo"], b["lo"])
    assert rtog.Map.load(str(tmp_path / "m.mrpt")).options == tum_map.options


def test_copy_is_independent(tum_map, tum_frames):
    c = tum_map.copy()
    before = leaf_table(tum_map)
    c.clear()
    assert len(c) == 0 and len(tum_map) == len(before)
    assert np.array_equal(leaf_table(tum_map)["v"], before["v"])
