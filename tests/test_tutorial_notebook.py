"""The tutorial notebook (docs/tutorial.ipynb) runs: every code cell in order, in one
namespace, in a scratch folder (the notebook saves its figures there), as a reader running it
top to bottom would; and it is kept without outputs in git.

The cells run in this process rather than in a Jupyter kernel: what is checked is the
notebook's code against the front door it teaches, which a kernel would not change, and no
Jupyter stack enters the test install. Each printed line is checked against the numbers the
objects hold, so a cell that printed nonsense would fail."""

import contextlib
import io
import json
import os
from pathlib import Path

import matplotlib
import numpy as np

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "tutorial.ipynb"


def _cells() -> list[dict]:
    return json.loads(NOTEBOOK.read_text("utf-8"))["cells"]


def test_the_notebook_is_stored_without_outputs() -> None:
    code = [c for c in _cells() if c["cell_type"] == "code"]
    assert code and all(c["outputs"] == [] and c["execution_count"] is None for c in code)


def test_every_cell_runs_and_says_what_its_objects_hold(tmp_path: Path) -> None:
    backend = matplotlib.get_backend()
    namespace: dict = {}
    printed = io.StringIO()
    here = Path.cwd()
    os.chdir(tmp_path)
    try:
        for cell in (c for c in _cells() if c["cell_type"] == "code"):
            with contextlib.redirect_stdout(printed):
                exec(compile("".join(cell["source"]), str(NOTEBOOK), "exec"), namespace)
    finally:
        os.chdir(here)
    text = printed.getvalue()
    tape, mc = namespace["tape"], namespace["mc"]
    assert f"n_o = {tape.n_o}," in text
    assert len(mc.manoeuvres) == 3 and "TCM-3: mean" in text
    total_99 = dict(mc.total.percentiles_km_s)[99.0] * 1e3
    assert f"total: 99 % {total_99:.1f} m/s" in text
    sigma = namespace["miss"]["sigma"]
    assert f"'B·R km': {round(sigma[0], 4)}" in text and sigma[0] > 0
    frame, budget = namespace["frame"], namespace["miss"]["budget"]
    assert list(frame.index) == budget["sources"]  # a DataFrame of the budget, every source
    assert np.allclose(np.sqrt((frame.to_numpy() ** 2).sum(axis=0)), sigma,
                       rtol=10 * budget["closure"] + 1e-12)
    top = frame["B·R km"].abs().idxmax()
    assert text.count(top) >= 1  # the largest source printed first
    assert {p.name for p in tmp_path.iterdir()} == {"bplane_ellipses.png", "bplane_scatter.png"}
    assert matplotlib.get_backend() == backend  # the plots chose no backend
