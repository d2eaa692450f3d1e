"""``tapp process`` (TAPP III) end to end: outputs, the T32 tape, and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tape.t32_hdf5 import read_t32
from tests.tapp.processor.helpers import leo_tape, sigmas

runner = CliRunner()


def _toml_value(v) -> str:
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and np.isinf(v):
        return "inf"
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def _deck_text(tape, *, fit=None, real=None, extra: str = "") -> str:
    fit = fit or sigmas(tape, GM_km3_s2=0.0)
    real = real or sigmas(tape, GM_km3_s2=0.01)
    lines = ['title = "LEO test"', "[times]", "print = [1, 2, 3]", "recycle = [1, 2]",
             "[commands]",
             'print = ["cov real orbit@current", "Lb\'; 0,-,m; 0,-,m", "I; 0,-,pk; 1,2,fp"]',
             extra, "[fit.apriori.sigma]"]
    lines += [f'"{k}" = {_toml_value(v)}' for k, v in fit.items()]
    lines += ["[real.apriori.sigma]"]
    lines += [f'"{k}" = {_toml_value(v)}' for k, v in real.items()]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tapp3")
    tape = leo_tape()
    path = folder / "leo.t13.h5"
    write_t13(path, tape)
    deck = folder / "deck.toml"
    deck.write_text(_deck_text(tape))
    return tape, path, deck


def test_process_writes_the_printout_json_plots_and_a_t32_tape(files, tmp_path: Path):
    tape, path, deck = files
    o3, t32, js, plots = (tmp_path / "o3.txt", tmp_path / "run.t32.h5", tmp_path / "o.json",
                          tmp_path / "plots")
    res = runner.invoke(app, ["process", str(path), str(deck), "--print", str(o3), "--tape",
                              str(t32), "--json", str(js), "--plots", str(plots)])
    assert res.exit_code == 0, res.output
    text = o3.read_text()
    assert text.count("PRINT OUTPUT") == 4 and text.count("RECYCLE OUTPUT") == 2
    assert "Λ̄'; 0,1,p; 0,1,p   [cov-real p@current]" in text
    assert "error budget" in text and "GM_km3_s2 (a priori)" in text
    content = json.loads(js.read_text())
    last = content["blocks"][-1]
    assert (last["kind"], last["k"]) == ("print", 3)
    ent = last["entities"][0]
    assert ent["command"] == "Λ̄'; 0,1,p; 0,1,p" and ent["alias"] == "cov-real p@current"
    assert ent["rows"][0] == "x_km@current" and len(ent["matrix"]) == 6
    assert np.allclose(np.sqrt(np.diag(ent["matrix"])), ent["sigma"])
    t = read_t32(t32)
    assert [r.k for r in t.recycles] == [1, 2] and t.recycles[0].entities[0].command == (
        "I; 0,-,pk; 1,2,fp")
    names = {p.name: p.names for p in t.partitions}
    assert "GM_km3_s2" in names["fz"] and "GM_km3_s2" not in names["f1"]
    assert sorted(p.name for p in plots.iterdir()) == ["sigma_history.png"]
    info = runner.invoke(app, ["tape", "info", str(t32), "--json", "-"])
    assert info.exit_code == 0 and json.loads(info.stdout)["format"] == "T32"
    # the last line: what was written, and the largest real/fit σ ratio of the JSON history
    ratio, name, kind, t_s = _largest_ratio(content["history"])
    assert res.stdout.splitlines() == [
        f"TAPP III: wrote O3 printout {o3}, JSON {js}, T32 tape {t32}, plots into {plots} "
        f"(1 PNG); largest real/fit σ ratio {ratio:.4g} ({name}, {kind} at t = "
        f"{t_s / 86400:.3f} d)"]


def test_process_with_ric_axes_writes_their_plot_and_table(files, tmp_path: Path):
    tape, path, _ = files
    deck = tmp_path / "ric.toml"
    deck.write_text(_deck_text(tape, extra='[output]\nframes = ["inertial", "ric"]'))
    js, plots = tmp_path / "o.json", tmp_path / "plots"
    res = runner.invoke(app, ["process", str(path), str(deck), "--print", str(tmp_path / "o3"),
                              "--json", str(js), "--plots", str(plots)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in plots.iterdir()) == ["sigma_history.png", "sigma_ric.csv",
                                                       "sigma_ric.png"]
    assert "(2 PNG, sigma_ric.csv)" in res.stdout
    rows = [r for r in json.loads(js.read_text())["history"]["rows"]]
    csv = (plots / "sigma_ric.csv").read_text().splitlines()
    assert csv[0].split(",")[4:7] == ["sigma_fit_R_km", "sigma_fit_I_km", "sigma_fit_C_km"]
    assert len(csv) == 1 + len(rows)
    last = csv[-1].split(",")
    assert np.allclose([float(v) for v in last[-6:]], rows[-1]["ric_sigma_real"], rtol=1e-9)


def _largest_ratio(history: dict) -> tuple[float, str, str, float]:
    """The largest real/fit σ of a run's JSON history (fit σ > 0), by hand."""
    names = history["labels"] + history["miss"]
    candidates = [(real / fit, name, row["kind"], row["t_s"]) for row in history["rows"]
                  if row["sigma_fit"] is not None
                  for name, real, fit in zip(names, row["sigma_real"] + row["miss_sigma_real"],
                                             row["sigma_fit"] + row["miss_sigma_fit"],
                                             strict=True) if fit > 0]
    return max(candidates, key=lambda c: c[0])


def test_the_printout_goes_to_standard_output_by_default(files):
    _, path, deck = files
    res = runner.invoke(app, ["process", str(path), str(deck)])
    assert res.exit_code == 0 and res.stdout.startswith("TAPP III O3 printout")
    # the summary keeps out of the printout's way, on stderr
    assert "TAPP III: wrote" not in res.stdout
    assert res.stderr.startswith("TAPP III: wrote O3 printout on standard output; largest "
                                 "real/fit σ ratio ")


def _bad(tmp_path: Path, files, deck_text: str) -> tuple[int, str, list[str]]:
    _, path, _ = files
    deck = tmp_path / "bad.toml"
    deck.write_text(deck_text)
    before = sorted(p.name for p in tmp_path.iterdir())
    res = runner.invoke(app, ["process", str(path), str(deck), "--print",
                              str(tmp_path / "o3.txt"), "--tape", str(tmp_path / "o.t32.h5")])
    return res.exit_code, res.stderr, sorted(set(p.name for p in tmp_path.iterdir()) -
                                              set(before))


@pytest.mark.parametrize(("edit", "fragment"), [
    (lambda t: t.replace("cov real orbit@current", "cov real zz@current"), "commands.print[0]"),
    (lambda t: t.replace("Lb'; 0,-,m; 0,-,m", "Lb'; 1,-,m; 1,-,m"), "parity"),
    (lambda t: t.replace("[times]", "[tape]\nn_o = 29\n[times]"), "tape.n_o"),
    (lambda t: t.replace('"J2" = 1e-08', '"J3" = 1e-08', 1), "fit.apriori.sigma.J3"),
    (lambda t: t.replace("print = [1, 2, 3]", "print = [1, 2, 7]"), "times.print[2]"),
    (lambda t: t.replace("print = [1, 2, 3]", "print = [1, 2, 1000.0]"), "nearest"),
    (lambda t: t.replace("[times]", "[times]\nprnt = [1]"), "prnt"),
    (lambda t: t + '\n[real.apriori]\ncorrelation = [["x_km", "y_km", 0.9], '
                   '["x_km", "z_km", 0.9], ["y_km", "z_km", -0.9]]\n',
     "positive semi-definite"),
    (lambda t: t.replace("[commands]", '[[stations_off]]\nstation = "NOWHERE"\n[commands]'),
     "stations_off[0].station"),
])
def test_bad_decks_are_one_line_exit_2_and_write_nothing(tmp_path, files, edit, fragment):
    tape = files[0]
    text = edit(_deck_text(tape))
    if "correlation" in text:  # a second [real.apriori] table: fold the key into the first
        text = text.replace("\n[real.apriori]\ncorrelation", "\n# folded\n")
        body, corr = text.split("# folded\n")
        text = body.replace("[real.apriori.sigma]", "[real.apriori]\ncorrelation"
                            + corr.rstrip() + "\n[real.apriori.sigma]")
    code, err, new = _bad(tmp_path, files, text)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and fragment in err, err
    assert "bad.toml" in err
    assert new == []


def test_a_deck_for_another_tape_is_refused_for_the_tape_first(tmp_path, files):
    """The shipped deep-space deck on the LEO test tape: wrong in many ways, refused for the
    first, its [tape] iden (issue 28: for its real.stochastic = "include")."""
    code, err, new = _bad(tmp_path, files, (EXAMPLES / "tapp3_deep_space.toml").read_text())
    assert (code, new) == (2, [])
    assert err.splitlines() == [f"error: {tmp_path / 'bad.toml'}: tape.iden: expected the "
                                "tape's iden 'TEST-LEO' (got 'DSN-LUNAR-2026-03-10')"]


def test_a_fit_normal_matrix_that_cannot_be_inverted_is_bad_input(tmp_path, files):
    tape = files[0]
    fit = sigmas(tape, GM_km3_s2=0.0, **{"KOUROU.x_km": float("inf")})
    text = _deck_text(tape, fit=fit, extra='[[stations_off]]\nstation = "KOUROU"')
    text = text.replace('"cov real orbit@current", ', "")
    text = text.replace('"Lb\'; 0,-,m; 0,-,m", ', "")
    code, err, new = _bad(tmp_path, files, text.replace("[commands]", "[commands]", 1))
    assert code == 2 and "k = 1" in err and "KOUROU.x_km" in err, err
    assert new == []


def test_a_tape_of_the_wrong_format_or_version_is_refused(tmp_path, files):
    _, path, deck = files
    wrong = tmp_path / "wrong.t13.h5"
    wrong.write_bytes(path.read_bytes())
    with h5py.File(wrong, "r+") as f:
        f.attrs["version"] = 99
    res = runner.invoke(app, ["process", str(wrong), str(deck)])
    assert res.exit_code == 2 and "attrs/version" in res.stderr
    not_tape = tmp_path / "deck_as_tape.h5"
    not_tape.write_text("not hdf5")
    res = runner.invoke(app, ["process", str(not_tape), str(deck)])
    assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1


def test_an_output_that_is_an_input_is_refused_before_any_work(files):
    _, path, deck = files
    before = path.read_bytes()
    res = runner.invoke(app, ["process", str(path), str(deck), "--tape", str(path)])
    assert res.exit_code == 2 and "TAPE" in res.stderr
    assert path.read_bytes() == before


def test_an_a_priori_sigma_beyond_double_range_is_bad_input(tmp_path, files):
    tape = files[0]
    code, err, new = _bad(tmp_path, files, _deck_text(tape, fit=sigmas(tape, GM_km3_s2=0.0,
                                                                       x_km=1e308)))
    assert code == 2 and "fit.apriori.sigma" in err and "x_km" in err, err
    assert new == []


def test_an_empty_partition_prints_with_an_empty_budget(tmp_path, files):
    _, path, _ = files
    tape = files[0]
    deck = tmp_path / "c2.toml"
    deck.write_text(_deck_text(tape).replace('"I; 0,-,pk; 1,2,fp"]',
                                             '"I; 0,-,pk; 1,2,fp", "cov-real c2@current"]'))
    res = runner.invoke(app, ["process", str(path), str(deck), "--json", "-"])
    assert res.exit_code == 0, res.output
    ent = json.loads(res.stdout)["blocks"][-1]["entities"][-1]
    assert ent["alias"] == "cov-real c2@current" and ent["matrix"] == []
