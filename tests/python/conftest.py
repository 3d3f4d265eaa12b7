"""Fixtures of the Python module's tests: the real TUM frames, the rtog tool, fixed seeds."""
import os

import numpy as np
import pytest

import rtog

TUM_DIR = os.environ["RTOG_TUM_DIR"]
RTOG_EXE = os.environ["RTOG_EXE"]


@pytest.fixture(scope="session")
def tum_frames():
    """The bundled TUM frames: (uint16 depth image, 4x4 camera-to-map pose), read once."""
    return [(rtog.read_depth_png(path), pose) for path, pose in rtog.read_tum(TUM_DIR)]


def build_tum(frames, stride=4, **options):
    m = rtog.Map(0.05, **options)
    for depth, pose in frames:
        m.insert_depth_image(depth, pose, stride=stride)
    return m


@pytest.fixture(scope="session")
def tum_map(tum_frames):
    return build_tum(tum_frames)


@pytest.fixture
def rng():
    return np.random.default_rng(20261207)


def leaf_table(m):
    """The leaves as one sorted structured array (min keys, max keys, log-odds)."""
    lo, hi, v = m.leaves()
    t = np.zeros(len(v), dtype=[("lo", "i4", 3), ("hi", "i4", 3), ("v", "f4")])
    t["lo"], t["hi"], t["v"] = lo, hi, v
    order = np.lexsort((lo[:, 0], lo[:, 1], lo[:, 2]))
    return t[order]
