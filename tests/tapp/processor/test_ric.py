"""TAPP III output in RIC axes and B-plane ellipses: the processor, the O3 printout and JSON.

The RIC axes are rebuilt here from each block's INFO (the nominal state at t_k, from the
tape) with plain NumPy: R = r/|r|, C = (r x v)/|r x v|, I = C x R; the RIC entity must be
T̄ Z T̄ᵀ of the printed inertial one, and its error budget must add up to its own diagonal.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.processor.commands import parse_command
from tapp.processor.deck import MAX_ENTITY_NUMBERS, Deck
from tapp.processor.deck_bind import bind
from tapp.processor.executive import Entity
from tapp.processor.printout import (
    entity_dict,
    entity_lines,
    history_lines,
    o3_text,
    run_dict,
    sigmas,
)
from tapp.processor.sequencing import HistoryRow, Run
from tests.tapp.processor.helpers import deck, leo_tape, run

#: Covariances of the 3-hour LEO arc hold ~11 digits (the printout says so); a rotation adds
#: a few ε. Compared on the scale √(C_ii C_jj).
HELD = 1e-10
COMMANDS = ["cov real orbit@current", "cov fit orbit@current", "cov-real r1@current",
            "cov-real pk", "cov-real-prior r1@injection", "partials pk wrt fp@current",
            "cov-real q@current"]


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


@pytest.fixture(scope="module")
def ric_run(tape):
    doc = deck(tape, times={"print": [1, 2, 3], "recycle": [2]},
               commands={"print": COMMANDS}, output={"frames": ["inertial", "ric"]})
    return run(tape, doc)


def _axes(state: np.ndarray) -> np.ndarray:
    r, v = state[:3], state[3:6]
    c = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
    rr = r / np.linalg.norm(r)
    return np.array([rr, np.cross(c, rr), c])


def _full(state: np.ndarray, n: int) -> np.ndarray:
    t = np.eye(n)
    t[:3, :3] = t[3:6, 3:6] = _axes(state)
    return t


def _scaled(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.diag(b))
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def _entity(block, alias: str) -> Entity:
    return next(e for e in block.entities if e.command.alias() == alias)


def _prints(run_: Run) -> list:
    return [b for b in run_.blocks if b.kind == "print"]


def test_orbit_covariances_come_in_ric_axes_of_the_nominal_state(ric_run):
    for block in _prints(ric_run):
        for alias in ("cov-real p@current", "cov-fit p@current", "cov-real r1@current",
                      "cov-real pk"):
            ent = _entity(block, alias)
            assert ent.ric is not None, alias
            t = _full(block.info, len(ent.rows))
            assert _scaled(ent.ric.matrix, t @ ent.matrix @ t.T) < HELD
            # the trace of the position block is kept
            assert np.trace(ent.ric.matrix[:3, :3]) == pytest.approx(
                np.trace(ent.matrix[:3, :3]), rel=1e-12)
            assert ent.ric.rows[:6] == ("R_km@current", "I_km@current", "C_km@current",
                                        "vR_km_s@current", "vI_km_s@current",
                                        "vC_km_s@current")
            assert ent.ric.rows[6:] == ent.rows[6:]


def test_injection_set_uses_the_state_at_injection(ric_run, tape):
    ent = _entity(_prints(ric_run)[-1], "cov-real-prior r1@injection")
    t = _full(np.asarray(tape.parameters.nominal[:6]), len(ent.rows))
    assert ent.ric.rows[0] == "R_km@injection"
    assert _scaled(ent.ric.matrix, t @ ent.matrix @ t.T) < HELD


def test_ric_budget_adds_up_to_the_ric_diagonal(ric_run):
    ent = _entity(_prints(ric_run)[-1], "cov-real r1@current")
    b = ent.ric.budget
    assert b is not None and b.sources == ent.budget.sources
    np.testing.assert_allclose(b.variances.sum(axis=0), np.diag(ent.ric.matrix), rtol=1e-10)
    # sources' variances are rotated, not copied: the radial and x shares differ
    assert not np.allclose(b.variances[:, 0], ent.budget.variances[:, 0])


def test_no_ric_copy_of_non_covariances_constants_or_without_the_deck_asking(ric_run, tape):
    block = _prints(ric_run)[-1]
    assert _entity(block, "partials pk wrt fp@current").ric is None
    assert _entity(block, "cov-real q@current").ric is None
    plain = run(tape, deck(tape, times={"print": [3]}, commands={"print": COMMANDS[:1]}))
    assert all(e.ric is None for b in plain.blocks for e in b.entities)
    assert all(h.ric_real is None for h in plain.history)


def test_history_has_the_ric_sigmas_of_the_printed_covariances(ric_run):
    prints = [h for h in ric_run.history if h.kind == "print"]
    for h, block in zip(prints, _prints(ric_run), strict=True):
        real = sigmas(_entity(block, "cov-real p@current").ric.matrix)
        fit = sigmas(_entity(block, "cov-fit p@current").ric.matrix)
        np.testing.assert_allclose(h.ric_real, real, rtol=1e-10)
        np.testing.assert_allclose(h.ric_fit, fit, rtol=1e-10)


def test_printout_and_json_carry_the_ric_blocks(ric_run, tape):
    text = o3_text(ric_run, tape, "deck.toml", "leo.t13.h5")
    assert "in RIC axes of the nominal state" in text
    assert "RIC σ OF THE ORBIT AT EACH STATISTICS TIME" in text
    assert "R_km@current" in text
    content = json.loads(json.dumps(run_dict(ric_run, tape, "deck.toml", "leo.t13.h5")))
    ent = [b for b in content["blocks"] if b["kind"] == "print"][-1]["entities"][0]
    assert ent["ric"]["rows"][0] == "R_km@current"
    assert {"matrix", "sigma", "correlation", "budget"} <= set(ent["ric"])
    assert content["history"]["ric_labels"] == ["R_km", "I_km", "C_km", "vR_km_s", "vI_km_s",
                                                "vC_km_s"]
    assert len(content["history"]["rows"][-1]["ric_sigma_real"]) == 6


@pytest.mark.parametrize("frames, fragment", [
    (["ric"], "output.frames"),
    (["inertial", "ric", "ric"], "output.frames"),
    (["inertial", "polar"], "output.frames"),
])
def test_deck_errors_name_the_field(tape, frames, fragment):
    doc = deck(tape, output={"frames": frames})
    with pytest.raises(InputError, match=fragment):
        bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


# --- B-plane ellipses in the printout (a synthetic miss covariance) ----------------------------

#: (B·R, B·T) covariance, km², in the tape's order (R first): σ_T = 0.3, σ_R = 0.2, ρ = 0.5.
MISS = ("b_dot_r_km", "b_dot_t_km", "flight_time_s")
COV = np.array([[0.04, 0.03, 0.0], [0.03, 0.09, 0.0], [0.0, 0.0, 4.0]])


def _closed_form_tr() -> tuple[float, float, float]:
    """Axes (km) and angle (deg, from T towards R) with T as the first axis."""
    a, b, c = COV[1, 1], COV[0, 1], COV[0, 0]
    mean, half = 0.5 * (a + c), np.hypot(0.5 * (a - c), b)
    return np.sqrt(mean + half), np.sqrt(mean - half), np.degrees(0.5 * np.arctan2(2 * b, a - c))


def test_miss_covariance_entity_prints_its_bplane_ellipse():
    ent = Entity(1, parse_command("cov-real m"), MISS, MISS, COV)
    major, minor, angle = _closed_form_tr()
    lines = "\n".join(entity_lines(ent))
    assert "B-plane dispersion ellipse" in lines
    assert f"semi-major {major:.4e} km" in lines and f"semi-major {3 * major:.4e} km" in lines
    assert f"angle {angle:+.3f} deg" in lines
    out = entity_dict(ent)["bplane_ellipse"]
    assert out["sigma1"]["semi_major_km"] == pytest.approx(major, rel=1e-12)
    assert out["sigma3"]["semi_minor_km"] == pytest.approx(3 * minor, rel=1e-12)
    assert out["angle_deg"] == pytest.approx(angle, abs=1e-9)
    assert out["sigma3"]["probability"] == pytest.approx(0.9889, abs=5e-5)


def test_history_tables_give_fit_and_real_ellipses():
    row = HistoryRow("recycle", 2, 86400.0, None, np.ones(1), COV / 4.0, COV, 11.0)
    run_ = Run((), (row,), ("x_km",), (), np.eye(1), np.eye(1))
    text = "\n".join(history_lines(run_, MISS))
    major, _, angle = _closed_form_tr()
    assert "B-PLANE DISPERSION ELLIPSES" in text
    assert f"{major / 2:.4e} / {major:.4e}" in text
    assert f"{angle:+.3f} / {angle:+.3f}" in text
    assert history_lines(run_, ("a_km", "ex", "ey")) == []


def test_ric_copies_count_in_the_output_bound(tape):
    """The covariances of the n_o standard parameters at epoch (o begins with the orbit) as
    many times as the number bound allows at 4 print times: accepted in inertial axes only;
    with their RIC copies twice the numbers, refused before any is computed."""
    n_o = len(tape.parameters.name)
    n = MAX_ENTITY_NUMBERS // (4 * n_o * n_o)
    doc = deck(tape, times={"print": [1, 2, 3]}, commands={"print": ["Lb'; 0,0,o; 0,0,o"] * n})
    header = memory_pairs(tape).header
    bind(validate(Deck, doc, "deck.toml"), header, "deck.toml")
    doc["output"] = {"frames": ["inertial", "ric"]}
    with pytest.raises(InputError, match="commands.print: expected at most"):
        bind(validate(Deck, doc, "deck.toml"), header, "deck.toml")
