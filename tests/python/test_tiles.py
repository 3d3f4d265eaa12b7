"""`rtog build --tiles`: the tiled map equals the single build leaf for leaf, built by one process
or by 2 MPI ranks (mpirun), in both presets with clamping on; a failed rank leaves no index."""
import os
import shutil
import subprocess

import numpy as np
import pytest

import rtog
from conftest import RTOG_EXE, TUM_DIR, leaf_table

SENA = os.path.join(os.environ["RTOG_MRPT_DATASETS"], "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog")
MPIRUN = shutil.which("mpirun")
GRID_INI = """[MappingApplication]
rtreeOccupancyGrid_count=1
[MappingApplication_rtreeOccupancyGrid_00_creationOpts]
resolution=0.05
[MappingApplication_rtreeOccupancyGrid_00_insertOpts]
sensorModelPreset=mrpt_grid
"""


def mpi(n):
    cmd = [MPIRUN, "-np", str(n), "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    return cmd


def build(args, tmp_path, name, launcher=()):
    out = tmp_path / name
    r = subprocess.run([*launcher, RTOG_EXE, "build", *args, "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return out, r.stdout


def sources(tmp_path):
    ini = tmp_path / "grid.ini"
    ini.write_text(GRID_INI)
    return {
        "tum-octomap": ["--tum", TUM_DIR, "--stride", "4", "--max-range", "0"],
        "sena-mrpt_grid": ["--rawlog", SENA, "--ini", str(ini), "--scans", ":120"],
    }


@pytest.mark.parametrize("source", ["tum-octomap", "sena-mrpt_grid"])
def test_tiles_equal_the_single_build(tmp_path, source):
    args = sources(tmp_path)[source]
    whole, _ = build(args, tmp_path, "whole.rtog")
    want = leaf_table(rtog.Map.load(str(whole)))
    runs = [("serial", ["--tiles", "3"], ())]
    if MPIRUN:
        runs.append(("mpi", ["--tiles", "auto"], mpi(2)))
    for name, tiles, launcher in runs:
        out, log = build(args + tiles, tmp_path, name, launcher)
        assert (out / "tiles.index").exists(), log
        n_tiles = len([f for f in os.listdir(out) if f.startswith("tile_")])
        assert n_tiles == (3 if name == "serial" else 8)  # auto: four tiles a rank
        got = leaf_table(rtog.Map.load(str(out)))
        assert np.array_equal(got["lo"], want["lo"]) and np.array_equal(got["hi"], want["hi"]), name
        assert np.array_equal(got["v"].view(np.uint32), want["v"].view(np.uint32)), name
        if name == "mpi":
            assert "rank 0:" in log and "rank 1:" in log


def test_commands_read_a_tiled_map(tmp_path):
    out, _ = build(sources(tmp_path)["tum-octomap"] + ["--tiles", "2"], tmp_path, "tiles")
    info = subprocess.run([RTOG_EXE, "info", str(out)], capture_output=True, text=True, check=True).stdout
    assert "leaves (cuboids)" in info
    png = tmp_path / "slice.png"
    subprocess.run([RTOG_EXE, "export", str(out), "--png", str(png), "--slice-z", "0.5"], check=True, capture_output=True)
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_a_failed_rank_leaves_no_map(tmp_path):
    out = tmp_path / "broken"
    out.mkdir()
    (out / "tile_0001.rtog").mkdir()  # the second tile cannot be written
    launcher = mpi(2) if MPIRUN else ()
    tiles = ["--tiles", "auto"] if MPIRUN else ["--tiles", "2"]
    r = subprocess.run([*launcher, RTOG_EXE, "build", *sources(tmp_path)["tum-octomap"], *tiles, "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "tile_0001.rtog" in r.stdout + r.stderr and "no tile index written" in r.stdout + r.stderr
    assert not (out / "tiles.index").exists()
    with pytest.raises(RuntimeError, match="directory"):
        rtog.Map.load(str(out))


def test_python_loads_the_tiles_around_a_point(tmp_path):
    out, _ = build(sources(tmp_path)["tum-octomap"] + ["--tiles", "4"], tmp_path, "tiles")
    whole = rtog.Map.load(str(out))
    near = rtog.Map.load_tiles(str(out), (-2.6, -2.6, 0.0), (-2.2, -2.2, 1.0))
    assert 0 < len(near) < len(whole)
    # What it holds, it holds as the whole map does.
    lo, hi, v = near.leaves()
    pts = (lo + 0.5) * near.resolution
    assert np.array_equal(whole.log_odds(pts).view(np.uint32), v.view(np.uint32))


def test_an_output_that_is_not_a_directory_fails_every_rank(tmp_path):
    out = tmp_path / "a_file"
    out.write_text("not a directory")
    launcher = mpi(2) if MPIRUN else ()
    r = subprocess.run([*launcher, RTOG_EXE, "build", *sources(tmp_path)["tum-octomap"], "--tiles", "auto",
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "is not a directory" in r.stdout + r.stderr
    assert out.read_text() == "not a directory"
