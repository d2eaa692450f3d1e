"""The report modules draw without pyplot: importing them and writing a plot leaves the
process's Matplotlib backend as it was (a notebook's inline backend was switched to Agg at
import before) and loads no pyplot."""

import subprocess
import sys

_PROBE = """
import sys
import matplotlib
matplotlib.use("svg")
import numpy as np
import tapp.report.guidance, tapp.report.od, tapp.report.processor
from tapp.report.sweeps import plot_departure_sweep
day = np.arange(5.0)
plot_departure_sweep(day, 1e-3 * (1 + day), 86400.0 * (3 + day), day != 2, sys.argv[1])
print(matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules)
"""


def test_plots_leave_the_backend_alone_and_load_no_pyplot(tmp_path):
    png = tmp_path / "sweep.png"
    out = subprocess.run([sys.executable, "-c", _PROBE, str(png)], capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == ["svg", "False"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
