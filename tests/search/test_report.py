"""The plain-text report in the spirit of the seed's Figs. 4 and 5."""

from __future__ import annotations

import re

import numpy as np
import pytest

from search import SearchInputError, format_report, solve

A = np.array([[2.0, 1.0], [0.5, 3.0]])


def _f(x):
    return A @ x + 0.01 * x**2


def _result(f=_f, **kwargs):
    return solve(
        f, [0.0, 0.0], [1.0, 2.0], tolerances=[1e-9, 1e-9], increments=[1e-4, 1e-4], **kwargs
    )


def test_report_restates_inputs_like_fig_4():
    text = format_report(_result(), x_names=["DX", "DY"], y_names=["B.R", "B.T"])
    lines = text.splitlines()
    assert lines[0] == "SEARCH PROGRAM PARAMETERS"
    assert lines[1].split()[-2:] == ["DX", "DY"]
    assert lines[2].split()[-2:] == ["B.R", "B.T"]
    assert re.fullmatch(r"TARGET VALUES\s+\+1\.00000000E\+00\s+\+2\.00000000E\+00", lines[3])
    assert "PERMISSIBLE ERROR VECTOR" in text and "GENERATIVE INCREMENTS" in text
    assert "THE ORDER IS 2, WITH 3 SETS OF PARTIALS OF 3 ITERATIONS EACH." in text
    assert "T. V. MODIFICATIONS" not in text  # printed only when some theta != 0


def test_report_shows_every_case_partials_and_increments_like_fig_5():
    r = _result()
    text = format_report(r)
    assert len(re.findall(r"^CASE \d+: ", text, flags=re.M)) == r.n_cases
    assert text.count("THE MATRIX OF PARTIALS IS") == len(r.history.partial_sets)
    assert text.count("THE INVERSE PARTIAL MATRIX IS") == len(r.history.partial_sets)
    n_steps = sum(len(ps.steps) for ps in r.history.partial_sets)
    assert text.count("I.V. INCREMENTS (DELTAS) ARE") == n_steps
    assert text.count("TOTAL INCREMENTS ARE") == n_steps
    # default names IV1.., DV1..; the partials follow the last perturbed case of set 1
    assert "IV1" in text and "DV2" in text
    order = [text.index(s) for s in ("CASE 3: PERTURBED 2", "THE MATRIX OF PARTIALS", "CASE 4:")]
    assert order == sorted(order)
    assert f"EXIT: CONVERGED (FLAG 1) AFTER 1 NOMINAL, {r.n_perturbed} PERTURBED AND " in text
    # the printed partials are the numbers in the history (9 significant digits)
    row = r.history.partial_sets[0].partials[0]
    assert f"{row[0]:+.8E}" in text and f"{row[1]:+.8E}" in text


def test_report_of_theta_mass_and_singular_runs():
    r = _result(
        lambda x, mass: _f(x),
        target_increments=[0.0, 0.5],
        mass=(500.0, 2.0),
        partials=[[1.0, 1.0], [1.0, 1.0]],
    )
    text = format_report(r)
    assert "T. V. MODIFICATIONS" in text and "COMPUTED TARGET VALUES" in text
    assert "MASS M'" in text and "M' = M - K*DELTA" in text
    assert "ANALYTIC PARTIALS USED FOR THE FIRST SET." in text
    assert "THE MATRIX OF PARTIALS IS SINGULAR" in text
    assert "EXIT: SINGULAR (FLAG 3)" in text


def test_report_rejects_names_of_the_wrong_length():
    with pytest.raises(SearchInputError, match="x_names: expected 2 names"):
        format_report(_result(), x_names=["DX"])
