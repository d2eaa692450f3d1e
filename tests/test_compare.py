"""``python -m scenarios.compare``: two results folders compared file by file, the measure
of "behaviour unchanged" for a refactoring (every number equal, what times the run aside)."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
from matplotlib.figure import Figure

from scenarios.compare import compare, main


def _folder(root: Path, *, value: float = 1.5, wall_s: float = 3.0, pixel: float = 0.0,
            dataset: float = 2.0, extra: bool = False) -> Path:
    root.mkdir()
    (root / "run.json").write_text(json.dumps({"sigma": [value, 2.0], "wall_s": wall_s,
                                               "nested": {"n": 3}}))
    (root / "table.csv").write_text(f"case,dv_m_s,wall_s\n1,{value},{wall_s}\n")
    (root / "report.md").write_text(f"σ {value}\nran in {wall_s} s\n")
    with h5py.File(root / "tape.h5", "w") as f:
        f.attrs["format"] = "T13"
        f.attrs["created_utc"] = str(wall_s)
        f["R"] = np.array([[dataset, 0.0], [0.0, 1.0]])
    fig = Figure(figsize=(1, 1), dpi=20)
    fig.figimage(np.full((4, 4), pixel), cmap="gray", vmin=0, vmax=1)
    fig.savefig(root / "plot.png")
    if extra:
        (root / "more.txt").write_text("x\n")
    return root


def test_identical_results_but_their_timings(tmp_path, capsys):
    before = _folder(tmp_path / "a")
    after = _folder(tmp_path / "b", wall_s=9.0)
    assert compare(before, after) == 0
    assert "5 files compared, 0 differ" in capsys.readouterr().out


def test_every_kind_of_difference_is_found(tmp_path, capsys):
    before = _folder(tmp_path / "a")
    after = _folder(tmp_path / "b", value=1.5000000000000002, pixel=1.0, dataset=2.5,
                    extra=True)
    assert compare(before, after) == 6  # json, csv, md, h5, png and the extra file
    out = capsys.readouterr().out
    assert ".sigma[0]: 1.5 -> 1.5000000000000002" in out
    assert "/R: 1 values differ, max |Δ| 0.5" in out
    assert "more.txt: only after" in out
    assert "pixels:" in out
    assert main([str(before), str(after)]) == 1
    assert main([str(before)]) == 2
