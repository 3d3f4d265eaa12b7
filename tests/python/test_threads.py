"""Queries release the GIL and share the map; insertions take it alone. Threads see the serial results."""
import threading

import numpy as np

import rtog


def test_parallel_queries_equal_serial(tum_map, rng):
    pts = rng.uniform([-8, -7, 0], [0.4, 8, 3], size=(200000, 3))
    want = tum_map.log_odds(pts)
    got = [None] * 4

    def work(i):
        got[i] = tum_map.log_odds(pts)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for g in got:
        assert np.array_equal(g.view(np.uint32), want.view(np.uint32))


def test_insertions_and_queries_interleave(tum_frames):
    """One thread inserts the frames while others query: every answer is a whole map's (no crash,
    no torn state), and the end map equals the serial build."""
    m = rtog.Map(0.05)
    serial = rtog.Map(0.05)
    for depth, pose in tum_frames:
        serial.insert_depth_image(depth, pose, stride=4)
    stop = threading.Event()
    errors = []

    def reader():
        while not stop.is_set():
            try:
                assert m.check_invariants() == ""
                m.occupancy(np.zeros((1000, 3)))
            except Exception as e:  # noqa: BLE001 - reported below
                errors.append(e)

    readers = [threading.Thread(target=reader) for _ in range(2)]
    for t in readers:
        t.start()
    for depth, pose in tum_frames:
        m.insert_depth_image(depth, pose, stride=4)
    stop.set()
    for t in readers:
        t.join()
    assert not errors
    a, b = m.leaves(), serial.leaves()
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
