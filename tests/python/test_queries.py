"""Vectorised queries against the leaves they must agree with (a brute-force lookup in NumPy)."""
import math

import numpy as np
import pytest

import rtog
from conftest import leaf_table


def cell_centres(lo, hi, res, rng, n):
    """n random cells of the given leaves, as metric cell centres and the leaf index."""
    idx = rng.integers(0, len(lo), n)
    keys = lo[idx] + (rng.random((n, 3)) * (hi[idx] - lo[idx] + 1)).astype(np.int32)
    return (keys + 0.5) * res, idx


def test_values_at_points_are_the_leaves(tum_map, rng):
    lo, hi, v = tum_map.leaves()
    res = tum_map.resolution
    pts, idx = cell_centres(lo, hi, res, rng, 20000)
    assert np.array_equal(tum_map.log_odds(pts).view(np.uint32), v[idx].view(np.uint32))
    p = tum_map.occupancy(pts)
    assert np.allclose(p, 1.0 / (1.0 + np.exp(-v[idx].astype(np.float64))), rtol=0, atol=1e-6)
    s = tum_map.state(pts)
    assert set(np.unique(s)) <= {rtog.FREE, rtog.OCCUPIED}
    assert np.array_equal(s == rtog.OCCUPIED, v[idx] > 0)  # occupiedThreshold 0.5: log-odds > 0


def test_unknown_and_keyless_points(tum_map):
    far = np.array([[100.0, 100.0, 100.0], [1e7, 0.0, 0.0], [math.nan, 0.0, 0.0]])
    assert np.isnan(tum_map.log_odds(far)).all()
    p = tum_map.occupancy(far)
    assert p[0] == 0.5 and np.isnan(p[1:]).all()
    assert (tum_map.state(far) == rtog.UNKNOWN).all()


def test_leaves_in_region_is_an_rtree_query(tum_map):
    lo, hi, v = tum_map.leaves()
    region = np.array([[-60, -20, 0], [-20, 20, 30]], dtype=np.int32)
    rlo, rhi, rv = tum_map.leaves(region)
    meets = np.all((lo <= region[1]) & (hi >= region[0]), axis=1)
    assert 0 < len(rv) == meets.sum() < len(v)
    want = np.sort(lo[meets].view([("", "i4", 3)]).ravel())
    got = np.sort(rlo.view([("", "i4", 3)]).ravel())
    assert np.array_equal(want, got)


def test_cast_rays_stop_at_occupied_cells(tum_map, rng):
    lo, hi, v = tum_map.leaves()
    occ = np.nonzero(v > 0)[0][:500]
    res = tum_map.resolution
    target = (lo[occ] + 0.5) * res
    origin = np.array([-2.0, 0.0, 1.0])
    hit, dist, cell = tum_map.cast_rays(origin, target - origin, 30.0)
    assert hit.all()
    # Each hit is an occupied cell no farther than the target's centre.
    assert (dist <= np.linalg.norm(target - origin, axis=1) + 1e-9).all()
    assert (tum_map.state((cell + 0.5) * res) == rtog.OCCUPIED).all()
    miss, d, _ = tum_map.cast_rays(origin, [[0.0, 0.0, 1.0]], 0.01)
    assert not miss[0] and math.isinf(d[0])


def test_nearest_occupied(tum_map):
    lo, hi, v = tum_map.leaves()
    res = tum_map.resolution
    occ = (lo[v > 0][:100] + 0.5) * res
    assert (tum_map.nearest_occupied(occ, 1.0) == 0.0).all()
    assert math.isinf(tum_map.nearest_occupied([[500.0, 500.0, 500.0]], 1.0)[0])


def test_field_is_the_cells_value_at_their_centres(tum_map, rng):
    lo, hi, v = tum_map.leaves()
    pts, idx = cell_centres(lo, hi, tum_map.resolution, rng, 2000)
    p, grad = tum_map.field(pts)
    assert np.allclose(p, 1.0 / (1.0 + np.exp(-v[idx].astype(np.float64))), atol=1e-6)
    assert grad.shape == (2000, 3) and np.isfinite(grad).all()


def test_band_and_slice(tum_map):
    band = tum_map.band(0.1, 0.3)
    p = band.p
    assert p.dtype == np.float32 and p.ndim == 2
    known = ~np.isnan(p)
    assert known.sum() > 1000 and ((p[known] >= 0) & (p[known] <= 1)).all()
    # A known pixel's column holds a known cell in the band.
    r, c = np.argwhere(known)[0]
    x, y = band.to_metres(c, r)
    zs = np.arange(0.1, 0.3, tum_map.resolution) + 0.5 * tum_map.resolution
    col = np.stack([np.full(len(zs), x), np.full(len(zs), y), zs], axis=1)
    assert np.nanmax(tum_map.occupancy(col)[tum_map.state(col) != rtog.UNKNOWN]) == pytest.approx(p[r, c], abs=1e-6)
    s = tum_map.slice(0.2)
    assert s.dtype == np.uint8 and set(np.unique(s)) <= {0, 128, 255}
    assert tum_map.slice(0.2, probability=True).shape[2] == 3
