#!/usr/bin/env python3
"""The real MRPT apps with the stock grid and with rtog's two map types: wall time, peak RSS and
the estimated path, side by side (issue #39's app rows).

Each run takes a stock config as Debian ships it, switches off its windows and its periodic logs,
points it at the rawlog and (for the particle filters) sets the particle count; the rtog runs
then rename its grid section exactly as the drop-in app tests do (tests/mrpt/app_dropin.py), and
nothing else changes. Every run has MRPT's clock-seeded generator pinned by the tests' seed shim
(RTOG_TEST_SEED=1); the rtog runs also preload the plugin. Time and memory are /usr/bin/time's
"%e %M"; with --repeats N the median of N runs. The path of each map is compared with the stock
grid's path of the same app, log and particle count: the running estimate at every step
(OUT/log_estimated_path.txt, written by both rbpf-slam and icp-slam) and rbpf-slam's final path,
its most likely particle's in hindsight (OUT/most_likely_path.txt).

  app_rows.py --plugin build/libs/rtog_mrpt/librtog_mrpt.so \\
      --seed-shim build/tests/mrpt/librtog_test_seed.so --rawlog LOG.rawlog \\
      --app rbpf-slam rbpf-slam/gridmapping_optimal_sampling.ini 1,5 \\
      --app icp-slam icp-slam/icp-slam_demo_classic_gridmatch.ini - [--json rows.json]
"""
import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "mrpt"))
from app_dropin import STOCK, ini_set, read_path, renamed  # noqa: E402

MAPS = ("COccupancyGridMap2D", "rtreeOccupancyGrid", "rtreeGridMap2D")
# What each app must not do while measured: open windows, save scenes and images, write its
# periodic logs. Keys a config does not have are left alone.
QUIET = {"logOutput_dir": "OUT", "SHOW_PROGRESS_IN_WINDOW": 0, "SHOW_PROGRESS_3D_REAL_TIME": 0, "SAVE_3D_SCENE": 0,
         "SAVE_MAP_IMAGES": 0, "LOG_FREQUENCY": 0}
PATH_FILE = os.path.join("OUT", "log_estimated_path.txt")  # "i x y z yaw pitch roll t": the running estimate
# rbpf-slam's final path, "x y phi" per filter step: the most likely particle's, in hindsight.
FINAL_PATH_FILE = os.path.join("OUT", "most_likely_path.txt")
# The class each map type makes. An app whose config names a map type nobody registered (the
# plugin not loaded) runs on without that map, quietly and fast: its row would be a lie.
MAP_CLASS = {"COccupancyGridMap2D": "mrpt::maps::COccupancyGridMap2D", "rtreeOccupancyGrid": "rtog::CRTreeOccupancyGridMap",
             "rtreeGridMap2D": "rtog::CRTreeBackedGridMap2D"}


def has_key(text, key):
    return re.search(r"^\s*" + re.escape(key) + r"\s*=", text, re.M | re.I) is not None


def config_text(stock_cfg, rawlog, particles, maptype):
    path = stock_cfg if os.path.isabs(stock_cfg) else os.path.join(STOCK, stock_cfg)
    with open(path) as f:
        text = f.read()
    for k, v in dict(QUIET, rawlog_file=rawlog).items():
        if has_key(text, k):
            text = ini_set(text, k, v)
    if particles is not None:
        if not has_key(text, "sampleSize"):
            sys.exit("app_rows: %s has no sampleSize: give '-' as its particle counts" % stock_cfg)
        text = ini_set(text, "sampleSize", particles)
    return text if maptype == MAPS[0] else renamed(text, maptype)


def run_once(a, app, cfg_text, rawlog, maptype, run_dir):
    shutil.rmtree(run_dir, ignore_errors=True)
    os.makedirs(run_dir)
    cfg = os.path.join(run_dir, "app.ini")
    with open(cfg, "w") as f:
        f.write(cfg_text)
    env = dict(os.environ, RTOG_TEST_SEED="1")
    env["LD_PRELOAD"] = " ".join(a.preload_first + [a.seed_shim] + ([a.plugin] if maptype != MAPS[0] else []))
    env.pop("DISPLAY", None)
    timing = os.path.join(run_dir, "time.txt")
    with open(os.path.join(run_dir, "app.log"), "w") as log:
        # stdin closed: an MRPT app that fails waits for a key.
        p = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", timing, app, cfg, rawlog], cwd=run_dir, env=env,
                           stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, timeout=a.timeout)
    if p.returncode != 0:
        return "exit %d: %s" % (p.returncode, why(os.path.join(run_dir, "app.log")))
    with open(os.path.join(run_dir, "app.log"), errors="replace") as f:
        if "C++ Class: '%s'" % MAP_CLASS[maptype] not in f.read():
            return "the app made no %s (is the plugin loaded? does the config hold a grid?)" % MAP_CLASS[maptype]
    with open(timing) as f:
        wall, rss_kb = f.read().split()[-2:]
    return float(wall), float(rss_kb) / 1024.0


def why(log_path):
    """The message of the MRPT exception that ended a run (the line after its banner)."""
    with open(log_path, errors="replace") as f:
        lines = [l.strip() for l in f]
    for i, line in enumerate(lines[:-1]):
        if line == "==== MRPT exception ====":
            return re.sub(r"^Message:\s*", "", lines[i + 1])[:200]
    return next((l for l in reversed(lines) if l), "")[:200]


def read_final_path(path):
    with open(path) as f:
        return [tuple(float(v) for v in line.split()[0:2]) for line in f if line.strip()]


def path_distance(ref_dir, dir_, name=PATH_FILE, read=read_path):
    """(mean, max) distance of the poses of two runs, pose by pose; a string if they cannot be
    paired (rbpf-slam's filter steps depend on its estimate, so two maps may take a different
    number of them)."""
    try:
        ref, ours = read(os.path.join(ref_dir, name)), read(os.path.join(dir_, name))
    except OSError:
        return None
    if not ref or len(ref) != len(ours):
        return "%d vs %d poses" % (len(ours), len(ref))
    d = [math.hypot(p[0] - q[0], p[1] - q[1]) for p, q in zip(ref, ours)]
    return sum(d) / len(d), max(d)


def measure(a):
    rows, failed = [], 0
    for rawlog in a.rawlog:
        log_name = os.path.basename(rawlog)
        for app, stock_cfg, counts in a.app:
            for particles in [None] if counts == "-" else [int(c) for c in counts.split(",")]:
                stock_dir = None
                stock = None
                for maptype in a.maps:
                    tag = "%s_%s_%s_%s" % (app, os.path.splitext(log_name)[0], particles or "na", maptype)
                    text = config_text(stock_cfg, os.path.abspath(rawlog), particles, maptype)
                    runs, run_dir = [], None
                    for rep in range(a.repeats):
                        run_dir = os.path.join(a.work_dir, re.sub(r"[^\w.-]", "_", tag), "run%d" % rep)
                        r = run_once(a, app, text, os.path.abspath(rawlog), maptype, run_dir)
                        if isinstance(r, str):
                            print("%s r%d: FAILED, %s (%s/app.log)" % (tag, rep, r, run_dir), file=sys.stderr)
                            failed += 1
                            break
                        print("%s r%d: %.2f s %.0f MB" % ((tag, rep) + r), file=sys.stderr)
                        runs.append(r)
                    row = {"app": app, "config": stock_cfg, "log": log_name, "particles": particles, "map": maptype,
                           "repeats": len(runs), "ok": len(runs) == a.repeats}
                    if not row["ok"]:
                        row["error"] = r
                    if row["ok"]:
                        row["wall_s"] = statistics.median(r[0] for r in runs)
                        row["peak_rss_mb"] = statistics.median(r[1] for r in runs)
                    if maptype == MAPS[0]:
                        stock, stock_dir = (row if row["ok"] else None), run_dir
                    elif stock and row["ok"]:
                        row["wall_ratio"] = row["wall_s"] / stock["wall_s"]
                        row["rss_ratio"] = row["peak_rss_mb"] / stock["peak_rss_mb"]
                        for key, dist in (("path", path_distance(stock_dir, run_dir)),
                                          ("final_path", path_distance(stock_dir, run_dir, FINAL_PATH_FILE, read_final_path))):
                            if isinstance(dist, str):
                                row[key + "_unpaired"] = dist
                            elif dist:
                                row[key + "_mean_m"], row[key + "_max_m"] = dist
                    rows.append(row)
    return rows, failed


def markdown(rows):
    out = ["| app | log | particles | map | wall | peak RSS | path vs stock (mean / max) | final path vs stock |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if not r["ok"]:
            cells = ["failed (%s)" % r["error"].replace("|", "/"), "–", "–", "–"]
        else:
            ratio = lambda k: " (%.2f×)" % r[k] if k in r else ""  # noqa: E731
            def path(k):
                if k + "_unpaired" in r:
                    return "unpaired: " + r[k + "_unpaired"]
                return "%.3f m / %.3f m" % (r[k + "_mean_m"], r[k + "_max_m"]) if k + "_mean_m" in r else "–"
            cells = ["%.2f s%s" % (r["wall_s"], ratio("wall_ratio")), "%.0f MB%s" % (r["peak_rss_mb"], ratio("rss_ratio")),
                     path("path"), path("final_path")]
        out.append("| %s | %s | %s | `%s` | %s |" % (r["app"], r["log"], r["particles"] if r["particles"] else "–", r["map"],
                                                    " | ".join(cells)))
    return "\n".join(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--plugin", required=True, help="librtog_mrpt.so of the build")
    p.add_argument("--seed-shim", required=True, help="librtog_test_seed.so of the build (tests/mrpt)")
    p.add_argument("--rawlog", required=True, action="append", help="a rawlog (repeatable)")
    p.add_argument("--app", required=True, action="append", nargs=3, metavar=("APP", "STOCK_CONFIG", "PARTICLES"),
                   help="an app, its stock config (relative to %s, or absolute) and its particle counts "
                        "(comma-separated; '-' for an app without particles); repeatable" % STOCK)
    p.add_argument("--maps", default=",".join(MAPS), help="map types, the stock grid first (default: all three)")
    p.add_argument("--repeats", type=int, default=1, help="runs of each row, the median reported (default: 1)")
    p.add_argument("--work-dir", default="app_rows_runs", help="where the runs happen (default: ./app_rows_runs)")
    p.add_argument("--timeout", type=float, default=3600, help="seconds before a run is killed (default: 3600)")
    p.add_argument("--json", help="also write the rows as JSON here")
    # A sanitized build's libraries need the sanitizer's runtime loaded first (tests/mrpt).
    p.add_argument("--preload-first", action="append", default=[], help=argparse.SUPPRESS)
    a = p.parse_args()
    a.maps = a.maps.split(",")
    if a.maps[0] != MAPS[0] or any(m not in MAPS for m in a.maps):
        p.error("--maps: a comma-separated list of %s, %s first (the rows' reference)" % (", ".join(MAPS), MAPS[0]))
    if a.repeats < 1:
        p.error("--repeats must be at least 1")
    for f in [a.plugin, a.seed_shim] + a.rawlog:
        if not os.path.isfile(f):
            p.error("no such file: " + f)
    a.plugin, a.seed_shim, a.work_dir = (os.path.abspath(x) for x in (a.plugin, a.seed_shim, a.work_dir))
    rows, failed = measure(a)
    print(markdown(rows))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
