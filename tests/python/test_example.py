"""The example of doc/python.md runs as a user runs it and draws the band it builds."""
import os
import subprocess
import sys

from conftest import TUM_DIR


def test_example_plots_a_slice(tmp_path):
    out = tmp_path / "slice.png"
    r = subprocess.run([sys.executable, os.environ["RTOG_EXAMPLE"], TUM_DIR, str(out)],
                       check=True, capture_output=True, text=True)
    assert "leaves for" in r.stdout
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10000
