"""Fusion, priors from arrays and files, planning and the image operations, on the TUM map."""
import math

import numpy as np
import pytest

import rtog
from conftest import build_tum, leaf_table

UNCLAMPED = dict(clampingMin=0.0001, clampingMax=0.9999)


def test_fusing_two_halves_gives_the_whole_log(tum_frames):
    """Without clamping, the opinion pool of two halves is the map of the whole log (float sums)."""
    whole = build_tum(tum_frames, **UNCLAMPED, mergePolicy="off")
    first = build_tum(tum_frames[:5], **UNCLAMPED, mergePolicy="off")
    second = build_tum(tum_frames[5:], **UNCLAMPED, mergePolicy="off")
    first.fuse(second)
    a, b = leaf_table(whole), leaf_table(first)
    assert np.array_equal(a["lo"], b["lo"])
    assert np.allclose(a["v"], b["v"], atol=1e-4)


def test_fuse_places_the_other_map(tum_map):
    m = rtog.Map(0.05)
    m.fuse(tum_map, (1.0, 0.0, 0.0))  # a shift by whole cells: cell for cell
    lo, _, v = tum_map.leaves()
    occ = (lo[v > 0][:200] + 0.5) * 0.05
    assert (m.state(occ + [1.0, 0.0, 0.0]) == rtog.OCCUPIED).all()


def test_set_cells_is_an_exact_prior(tum_map):
    lo, hi, v = tum_map.leaves()
    m = rtog.Map(0.05)
    m.set_cells(lo, hi, v)
    a, b = leaf_table(tum_map), leaf_table(m)
    pts = (a["lo"] + 0.5) * 0.05
    assert np.array_equal(m.log_odds(pts), tum_map.log_odds(pts))
    assert m.cell_count == tum_map.cell_count


def test_prior_from_a_gridmap_file():
    import os
    gridmap = os.path.join(os.environ["RTOG_MRPT_DATASETS"], "2006-MalagaCampus.gridmap.gz")
    if not os.path.exists(gridmap):
        pytest.skip("mrpt-common's .gridmap not installed")
    m = rtog.Map(0.05)
    m.load_prior(gridmap, confidence=0.7)
    s = m.stats()
    assert s["occupied_cells"] > 1000 and s["free_cells"] > 10000
    # A prior at confidence c holds no cell beyond c.
    _, _, v = m.leaves()
    assert v.max() <= math.log(0.7 / 0.3) + 1e-5


def test_plan_is_risk_aware(tum_map, tum_frames):
    pose = tum_frames[0][1]
    start = pose[:2, 3]
    ahead = pose[:2, 2] / np.linalg.norm(pose[:2, 2])
    goal = start + 1.5 * ahead  # free floor 1.5 m in front of the first camera
    res = tum_map.resolution
    for te in (1.0, 50.0):
        p = tum_map.plan(start, goal, te=te, ta=1.0, min_z=0.1, max_z=0.4)
        assert p["found"] and p["path"].shape[1] == 2
        assert p["cost"] == pytest.approx(te * p["risk"] + p["length"])
        assert np.abs(p["path"][0] - start).max() <= res and np.abs(p["path"][-1] - goal).max() <= res
        cells = np.concatenate([p["path"], np.full((len(p["path"]), 1), 0.25)], axis=1)
        assert (tum_map.state(cells) != rtog.OCCUPIED).all()
    three = tum_map.plan_3d((*start, 0.25), (*goal, 0.25))
    assert three["found"] and three["path"].shape[1] == 3


def test_image_operations(tum_map):
    band = tum_map.band(0.1, 0.4)
    mask = rtog.image.threshold(band, 0.6)
    assert mask.dtype == np.uint8 and mask.shape == band.p.shape
    assert (mask[np.isnan(band.p)] == 0).all() and mask.any()
    blurred = rtog.image.blur(band, 0.1)
    assert np.array_equal(np.isnan(blurred.p), np.isnan(band.p))
    assert np.nanstd(blurred.p) < np.nanstd(band.p)
    assert not np.isnan(rtog.image.blur_with_prior(band, 0.1).p).any()
    closed = rtog.image.close(mask, 3)
    assert (closed >= mask).all()
    n_labels, areas = rtog.image.connected_regions(closed)
    assert n_labels.max() == len(areas) - 1
    segs = rtog.image.hough_segments(closed, band, 0.3, 0.1)
    assert segs.ndim == 2 and segs.shape[1] == 4
    ranges = np.full(181, 2.0, dtype=np.float32)
    img = rtog.image.polar_to_cartesian(ranges, math.pi, 4.0, 0.02)
    back = rtog.image.cartesian_to_polar(img, 181, math.pi, 4.0, 0.02)
    assert np.allclose(back[back > 0], 2.0, atol=0.05)
