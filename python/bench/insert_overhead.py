"""Benchmark row: inserting the TUM frames through Python against the C++ call.

    PYTHONPATH=build/python python3 python/bench/insert_overhead.py build/apps/rtog/rtog \
        share/rtog/data/tum_fr2_pioneer_slam2 [--runs 9] [--stride 1]

C++: `rtog build --tum` times exactly its OccupancyMap::insertPointCloud calls ("inserted ... in X s").
Python: Map.insert_point_cloud on the same frames' points (back-projected beforehand, in NumPy),
timed around the calls; and Map.insert_depth_image (back-projection included), what a user calls.
Each figure from a fresh process, as the tool's is: the three processes run in turn, `runs`
times; medians reported. Same options (OctoMap's rule, 0.05 m, no range cut, the machine's
threads).
"""
import argparse
import re
import statistics
import subprocess
import sys
import time

import numpy as np

import rtog


def world_points(depth, pose, stride):
    v, u = np.nonzero(depth[::stride, ::stride])
    v, u = v * stride, u * stride
    z = depth[v, u] / 5000.0
    pc = np.stack([(u - 325.1) * z / 520.9, (v - 249.7) * z / 521.0, z], axis=1).astype(np.float32)
    return np.ascontiguousarray(pc @ pose[:3, :3].T.astype(np.float32) + pose[:3, 3].astype(np.float32))


def child(kind, tum_dir, stride):
    """One timed pass in this process: seconds inside the insertion calls, and the beams."""
    frames = [(rtog.read_depth_png(p), pose) for p, pose in rtog.read_tum(tum_dir)]
    m, t = rtog.Map(0.05), 0.0
    if kind == "points":
        clouds = [(world_points(d, pose, stride), pose[:3, 3].copy()) for d, pose in frames]
        for pts, origin in clouds:
            t0 = time.perf_counter()
            m.insert_point_cloud(pts, origin)
            t += time.perf_counter() - t0
    else:
        for d, pose in frames:
            t0 = time.perf_counter()
            m.insert_depth_image(d, pose, stride=stride)
            t += time.perf_counter() - t0
    print(t, m.total_insert_stats["rays_hit"] + m.total_insert_stats["rays_truncated"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rtog")
    ap.add_argument("tum_dir")
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--stride", type=int, default=1)
    ap.add_argument("--child", choices=["points", "depth"])
    a = ap.parse_args()
    if a.child:
        return child(a.child, a.tum_dir, a.stride)
    cpp, py_points, py_depth, beams = [], [], [], 0
    for _ in range(a.runs):
        out = subprocess.run([a.rtog, "build", "--tum", a.tum_dir, "--resolution", "0.05", "--max-range", "0",
                              "--stride", str(a.stride)], check=True, capture_output=True, text=True).stdout
        cpp.append(float(re.search(r"scans in ([0-9.]+) s", out).group(1)))
        for kind, into in (("points", py_points), ("depth", py_depth)):
            out = subprocess.run([sys.executable, __file__, a.rtog, a.tum_dir, "--stride", str(a.stride),
                                  "--child", kind], check=True, capture_output=True, text=True).stdout.split()
            into.append(float(out[0]))
            beams = int(out[1])
    c, p, d = (statistics.median(x) for x in (cpp, py_points, py_depth))
    print(f"| TUM, 10 frames, stride {a.stride} ({beams / 1e6:.2f} M beams) | {c:.3f} s | "
          f"{p:.3f} s ({p / c:.3f}x) | {d:.3f} s ({d / c:.3f}x) |")


if __name__ == "__main__":
    main()
