"""The drop-in cases: a stock MRPT app config as Debian ships it, run once as shipped and once with
its COccupancyGridMap2D section renamed to rtog's type and nothing else changed; the two runs must
give the same path (or estimates)."""
import json
import math
import os
import re
import subprocess
import sys

from app_common import PDF_RE, SENA, fail

STOCK = "/usr/share/mrpt/config_files"


def ini_set(text, key, value):
    """Sets `key = value` wherever the key stands (MRPT keys ignore case)."""
    pat = re.compile(r"^(\s*)" + re.escape(key) + r"\s*=.*$", re.M | re.I)
    if not pat.search(text):
        fail("the stock config has no key " + key)
    return pat.sub(lambda m: m.group(1) + key + " = " + str(value), text)


def renamed(text, maptype):
    """A stock config's grid, pasted as rtog's map type and nothing else changed."""
    return text.replace("occupancyGrid_count", maptype + "_count").replace("_occupancyGrid_00_", "_%s_00_" % maptype)


def stock_pair(r, name, stock_cfg, app, args, overrides, maptype="rtreeGridMap2D", seed=1):
    """Runs `app` with a stock MRPT config as shipped, then with its grid renamed to `maptype` (or
    to each of a tuple of types) and the plugin preloaded. `overrides` only switch off windows and
    logs, the same in every run. Returns (stock run directory, stock output, our directory, our
    output, ...), one pair per run."""
    with open(os.path.join(STOCK, stock_cfg)) as f:
        text = f.read()
    for k, v in overrides.items():
        text = ini_set(text, k, v)
    runs = []
    types = maptype if isinstance(maptype, tuple) else (maptype,)
    for tag, cfg_text, preload in [("stock", text, False)] + [(t, renamed(text, t), True) for t in types]:
        d = r.run_dir(os.path.join(name, tag))
        cfg = os.path.join(d, os.path.basename(stock_cfg))
        with open(cfg, "w") as f:
            f.write(cfg_text)
        rc, out = r.app([app, cfg] + list(args), d, preload=preload, seed=seed)
        if rc != 0:
            fail("%s (%s, %s) exited %d:\n%s" % (app, stock_cfg, tag, rc, out[-3000:]))
        runs += [d, out]
    return runs


def read_path(path):
    with open(path) as f:
        return [tuple(float(v) for v in line.split()[1:3]) for line in f if line.strip()]


def compare_paths(ref, ours, label, tol):
    if not ref or len(ref) != len(ours):
        fail("%s: %d poses against the stock grid's %d" % (label, len(ours), len(ref)))
    d = [math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in zip(ref, ours)]
    mean = sum(d) / len(d)
    print("%s: %d poses; distance to the stock grid's path: mean %.6f m, max %.6f m" % (label, len(d), mean, max(d)))
    if mean > tol:
        fail("%s departs from the stock grid's path by %.3f m on average (tolerance %.2f)" % (label, mean, tol))


def case_icp_slam_dropin(r):
    """icp-slam matching against the grid, the stock classic-gridmatch config on SENA: the grid
    pasted as rtreeGridMap2D gives the stock grid's path."""
    out_dir = {"logOutput_dir": "OUT", "SHOW_PROGRESS_3D_REAL_TIME": 0, "SAVE_3D_SCENE": 0, "LOG_FREQUENCY": 0}
    d0, _, d1, out = stock_pair(r, "icp_slam_dropin", "icp-slam/icp-slam_demo_classic_gridmatch.ini", "icp-slam",
                                [os.path.join(r.a.datasets, SENA)], out_dir)
    print("ICP results rejected as low quality: %d" % out.count("low quality"))
    compare_paths(read_path(os.path.join(d0, "OUT", "log_estimated_path.txt")),
                  read_path(os.path.join(d1, "OUT", "log_estimated_path.txt")), "icp-slam, rtreeGridMap2D", 0.05)


def case_rbpf_slam_dropin(r):
    """rbpf-slam, the stock optimal-sampling config (auxiliary particle filter, 25 particles) on
    SENA, on the same seed: both map types give the stock grid's path exactly. (rtreeOccupancyGrid
    weighs particles on the empty map before the first scan, as the grid does, and copies of it
    share bricks and view tiles: what it computes is the grid's.)"""
    out_dir = {"logOutput_dir": "OUT", "SHOW_PROGRESS_IN_WINDOW": 0, "SAVE_3D_SCENE": 0, "SAVE_MAP_IMAGES": 0,
               "LOG_FREQUENCY": 0}
    types = ("rtreeGridMap2D", "rtreeOccupancyGrid")
    runs = stock_pair(r, "rbpf_slam_dropin", "rbpf-slam/gridmapping_optimal_sampling.ini", "rbpf-slam",
                      [os.path.join(r.a.datasets, SENA)], out_dir, maptype=types)
    ref = read_path(os.path.join(runs[0], "OUT", "log_estimated_path.txt"))
    for i, t in enumerate(types):
        compare_paths(ref, read_path(os.path.join(runs[2 + 2 * i], "OUT", "log_estimated_path.txt")),
                      "rbpf-slam, " + t, 0.0)


def case_pf_localization_dropin(r):
    """pf-localization, the stock localization_demo config (its map built from the simplemap), on
    the same seed: the same estimates at every step."""
    datasets = os.path.join(r.a.datasets, "")
    over = {"SHOW_PROGRESS_3D_REAL_TIME": "false", "logOutput_dir": "OUT",
            "map_file": datasets + "localization_demo.simplemap.gz", "rawlog_file": datasets + "localization_demo.rawlog"}
    _, out0, _, out1 = stock_pair(r, "pf_localization_dropin", "pf-localization/localization_demo.ini",
                                  "pf-localization", [], over)
    ref = [(float(a), float(b)) for a, b, _ in PDF_RE.findall(out0)]
    ours = [(float(a), float(b)) for a, b, _ in PDF_RE.findall(out1)]
    if len(ref) < 20:
        fail("pf-localization printed only %d estimates" % len(ref))
    compare_paths(ref, ours, "pf-localization, rtreeGridMap2D", 0.05)


def case_app_rows(r):
    """apps/rtog-bench/app_rows.py on SENA, short: rbpf-slam with one particle on the three maps,
    icp-slam on the two it can match against (rtreeOccupancyGrid is no COccupancyGridMap2D).
    Every row measured, and rtreeGridMap2D on the stock grid's path."""
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "apps", "rtog-bench", "app_rows.py")
    d = r.run_dir("app_rows")
    rows = []
    for app, cfg, counts, maps in (
            ("rbpf-slam", "rbpf-slam/gridmapping_optimal_sampling.ini", "1",
             "COccupancyGridMap2D,rtreeOccupancyGrid,rtreeGridMap2D"),
            ("icp-slam", "icp-slam/icp-slam_demo_classic_gridmatch.ini", "-", "COccupancyGridMap2D,rtreeGridMap2D")):
        out_json = os.path.join(d, app + ".json")
        args = [sys.executable, script, "--plugin", r.a.plugin, "--seed-shim", r.a.seed_shim,
                "--rawlog", os.path.join(r.a.datasets, SENA), "--app", app, cfg, counts, "--maps", maps,
                "--work-dir", os.path.join(d, "runs"), "--json", out_json]
        for lib in r.a.preload_first:
            args += ["--preload-first", lib]
        p = subprocess.run(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=280)
        out = p.stdout.decode(errors="replace")
        print(out)
        if p.returncode != 0:
            fail("app_rows.py (%s) exited %d" % (app, p.returncode))
        table = [line for line in out.splitlines() if line.startswith("| %s |" % app)]
        with open(out_json) as f:
            got = json.load(f)
        if len(table) != len(maps.split(",")) or len(got) != len(table):
            fail("app_rows.py (%s): %d table rows, %d JSON rows for %d maps" % (app, len(table), len(got), len(maps.split(","))))
        rows += got
    # A library that registers no map type in place of the plugin: the app runs on without the
    # map; the row must say so, not report its (short) time.
    args = [sys.executable, script, "--plugin", r.a.seed_shim, "--seed-shim", r.a.seed_shim, "--rawlog",
            os.path.join(r.a.datasets, SENA), "--app", "rbpf-slam", "rbpf-slam/gridmapping_optimal_sampling.ini", "1",
            "--maps", "COccupancyGridMap2D,rtreeGridMap2D", "--work-dir", os.path.join(d, "runs_no_plugin")]
    p = subprocess.run(args + sum((["--preload-first", lib] for lib in r.a.preload_first), []), stdin=subprocess.DEVNULL,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=280)
    out = p.stdout.decode(errors="replace")
    print(out)
    if p.returncode != 1 or "made no rtog::CRTreeBackedGridMap2D" not in out:
        fail("app_rows.py measured rbpf-slam without the plugin as if it had run rtreeGridMap2D (exit %d)" % p.returncode)
    for row in rows:
        if not (row["ok"] and row["wall_s"] > 0 and row["peak_rss_mb"] > 0):
            fail("a row without figures: %s" % row)
        if row["map"] != "COccupancyGridMap2D" and not ("wall_ratio" in row and "rss_ratio" in row and "path_mean_m" in row):
            fail("a row without its comparison to the stock grid: %s" % row)
        if row["map"] == "rtreeGridMap2D" and row["path_mean_m"] > 0.05:
            fail("%s with rtreeGridMap2D departs from the stock grid's path by %.3f m" % (row["app"], row["path_mean_m"]))
        if row["map"] == "rtreeGridMap2D" and row["app"] == "rbpf-slam" and not row.get("final_path_mean_m", 1) <= 0.05:
            fail("rbpf-slam's final path with rtreeGridMap2D is not the stock grid's: %s" % row)
