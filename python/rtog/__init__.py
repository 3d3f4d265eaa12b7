"""rtog: a probabilistic occupancy map stored as an R-tree of cuboids, from Python.

The map is the C++ library's MRPT map type (rtreeOccupancyGrid); its options are the .ini
names of doc/mrpt_map.md. Arrays go in and out as NumPy arrays, in place where the layout allows.

    import rtog
    m = rtog.Map(0.05)                               # OctoMap's rule, as `rtog build`
    for depth_png, pose in rtog.read_tum("share/rtog/data/tum_fr2_pioneer_slam2"):
        m.insert_depth_image(rtog.read_depth_png(depth_png), pose, stride=4)
    band = m.band(0.2, 0.4)                          # band.p: P(occupied), NaN unknown
    lo, hi, log_odds = m.leaves()

See doc/python.md.
"""
from ._rtog import (  # noqa: F401
    FREE,
    OCCUPIED,
    UNKNOWN,
    Band,
    Map,
    image,
    read_depth_png,
    read_tum,
)

__all__ = ["Map", "Band", "image", "read_tum", "read_depth_png", "UNKNOWN", "FREE", "OCCUPIED"]
