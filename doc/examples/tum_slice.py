"""Builds a map from the bundled TUM depth frames and plots a height band with matplotlib.

    python3 doc/examples/tum_slice.py share/rtog/data/tum_fr2_pioneer_slam2 slice.png
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import rtog  # noqa: E402


def main(tum_dir, out_png):
    m = rtog.Map(0.05)  # OctoMap's rule, as `rtog build`
    for depth_png, pose in rtog.read_tum(tum_dir):
        m.insert_depth_image(rtog.read_depth_png(depth_png), pose, stride=2)
    s = m.stats()
    print(f"{s['leaves']} leaves for {s['cells']} cells, {s['memory_bytes'] / 1e6:.1f} MB")

    band = m.band(0.1, 0.5)  # P(occupied) per column, NaN where unknown
    h, w = band.p.shape
    x0, y1 = band.to_metres(-0.5, -0.5)  # the image's upper-left corner [m]
    x1, y0 = band.to_metres(w - 0.5, h - 0.5)
    fig, ax = plt.subplots(figsize=(6, 8))
    ax.set_facecolor("lightsteelblue")  # unknown
    im = ax.imshow(np.ma.masked_invalid(band.p), cmap="gray_r", vmin=0, vmax=1, extent=(x0, x1, y0, y1))
    fig.colorbar(im, ax=ax, label="P(occupied)")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("TUM fr2/pioneer_slam2, z in [0.1, 0.5] m")
    fig.savefig(out_png, dpi=100)
    print(f"wrote {out_png}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
