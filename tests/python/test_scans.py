"""2D range scans and sonar readings through both presets and every sensor model. The scans are
real geometry: rays cast in the TUM map from a pose inside it."""
import math

import numpy as np
import pytest

import rtog
from conftest import leaf_table

POSE = (-2.33, -2.38, -2.77)  # x, y, yaw: a TUM camera position, looking as it did
N = 361


@pytest.fixture(scope="module")
def ranges(tum_map):
    """A 361-beam scan of the TUM map's walls at z = 0.25 m (NaN where no wall within 8 m)."""
    angles = POSE[2] + np.linspace(-math.pi / 2, math.pi / 2, N)
    dirs = np.stack([np.cos(angles), np.sin(angles), np.zeros(N)], axis=1)
    hit, dist, _ = tum_map.cast_rays([POSE[0], POSE[1], 0.25], dirs, 8.0)
    assert hit.sum() > 200
    return np.where(hit, dist + 0.5 * tum_map.resolution, np.nan).astype(np.float32)


def scan_map(ranges, pose_cov=None, **options):
    m = rtog.Map(0.05, **options)
    stats = m.insert_scan_2d(ranges, (*POSE[:2], 0.25, POSE[2], 0, 0), max_range=8.0, pose_cov=pose_cov)
    return m, stats


def end_points(ranges):
    a = POSE[2] + np.linspace(-math.pi / 2, math.pi / 2, N)
    ok = np.isfinite(ranges)
    r = ranges[ok].astype(np.float64)
    return np.stack([POSE[0] + r * np.cos(a[ok]), POSE[1] + r * np.sin(a[ok]), np.full(ok.sum(), 0.25)], axis=1)


@pytest.mark.parametrize("preset", ["octomap", "mrpt_grid"])
def test_scan_marks_end_cells_and_clears_the_beams(ranges, preset):
    m, stats = scan_map(ranges, sensorModelPreset=preset)
    ends = end_points(ranges)
    assert stats["rays_hit"] == len(ends)
    # The grid's raster rounds end points its own way and a later beam may cross an earlier end
    # cell (a step per beam, in beam order), so fewer of the metric end points read occupied there.
    assert (m.state(ends) == rtog.OCCUPIED).mean() > (0.95 if preset == "octomap" else 0.85)
    mid = np.array([POSE[0], POSE[1], 0.25]) + 0.5 * (ends - np.array([POSE[0], POSE[1], 0.25]))
    assert (m.state(mid) == rtog.FREE).mean() > 0.95
    _, _, v = m.leaves()
    if preset == "mrpt_grid":
        # COccupancyGridMap2D's int8 lattice: every value a whole multiple of the grid's unit (1/16),
        # within the int8 range.
        assert np.array_equal(v * 16, np.round(v * 16)) and np.abs(v * 16).max() <= 127
    else:
        free, occ = math.log(0.4 / 0.6), math.log(0.7 / 0.3)
        assert np.allclose(np.unique(v), [free, occ], atol=1e-6)


@pytest.mark.parametrize("preset", ["octomap", "mrpt_grid"])
def test_zero_covariance_is_the_plain_update(ranges, preset):
    a, _ = scan_map(ranges, sensorModelPreset=preset)
    b, _ = scan_map(ranges, pose_cov=np.zeros((3, 3)), sensorModelPreset=preset, poseUncertainty="on")
    ta, tb = leaf_table(a), leaf_table(b)
    assert np.array_equal(ta["lo"], tb["lo"]) and np.array_equal(ta["v"], tb["v"])


@pytest.mark.parametrize("preset", ["octomap", "mrpt_grid"])
def test_pose_covariance_blurs(ranges, preset):
    plain, _ = scan_map(ranges, sensorModelPreset=preset)
    cov = np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2])
    blurred, _ = scan_map(ranges, pose_cov=cov, sensorModelPreset=preset, poseUncertainty="on")
    ends = end_points(ranges)
    # Evidence spreads: more cells, and the end cells less certain than without blur.
    assert blurred.cell_count > plain.cell_count
    assert np.nanmean(blurred.log_odds(ends)) < np.nanmean(plain.log_odds(ends))
    if preset == "mrpt_grid":  # graded changes land on the grid's int8 lattice too (rounded to 1/16)
        v = blurred.leaves()[2]
        assert np.array_equal(v * 16, np.round(v * 16)) and len(np.unique(v)) > len(np.unique(plain.leaves()[2]))


@pytest.mark.parametrize("preset", ["octomap", "mrpt_grid"])
def test_range_noise_with_zero_sigma_is_the_beam_model(ranges, preset):
    beam, _ = scan_map(ranges, sensorModelPreset=preset)
    noise0, _ = scan_map(ranges, sensorModelPreset=preset, sensorModel="rangeNoise", rangeNoiseStd=0.0)
    ta, tb = leaf_table(beam), leaf_table(noise0)
    assert np.array_equal(ta["lo"], tb["lo"]) and np.array_equal(ta["v"], tb["v"])
    graded, _ = scan_map(ranges, sensorModelPreset=preset, sensorModel="rangeNoise", rangeNoiseStd=0.1)
    assert len(np.unique(graded.leaves()[2])) > len(np.unique(ta["v"]))


def test_endpoint_model_marks_no_free_space(ranges):
    m, _ = scan_map(ranges, sensorModel="endpoint")
    assert (m.leaves()[2] > 0).all()


@pytest.mark.parametrize("weighting", ["uniform", "elfes"])
def test_sonar_readings_mark_the_arc(weighting):
    m = rtog.Map(0.05, sonarConeWeighting=weighting)
    yaws = np.radians([0.0, 90.0, 180.0, 270.0])
    sensors = np.array([[0.1 * math.cos(a), 0.1 * math.sin(a), 0.2, a, 0, 0] for a in yaws])
    m.insert_range_readings(np.array([2.0, 1.5, 2.5, 1.0], dtype=np.float32), sensors, (0.0, 0.0, 0.0), max_range=5.0)
    arc = np.array([[2.1, 0.0, 0.2], [0.0, 1.6, 0.2], [-2.6, 0.0, 0.2], [0.0, -1.1, 0.2]])
    assert (m.state(arc) == rtog.OCCUPIED).all()
    assert (m.state([[1.0, 0.0, 0.2]]) == rtog.FREE).all()
