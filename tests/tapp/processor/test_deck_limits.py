"""A deck's matrices and numbers at the edge (issue "Hardening, second round", item 3): checked
on each entry's own scale, within ranges whose top works, and the size of a run bounded
before it starts.

The audit, on main: an asymmetric or indefinite a priori normal matrix passed (tolerances
scaled with the largest entry or diagonal), the indefinite one then reported as "not
invertible ... give an a priori σ"; σ = 1e149 (inside the documented 1e-150..1e150), a real
covariance of 1e300 and a constraint coefficient of 1e200 exited 0 with NaN in the JSON;
10,000 print commands took 71 s and 3.3 GB.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli.common import app
from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.io.tape.t32 import validate as validate_t32
from tapp.processor.deck import (
    COVARIANCE_RANGE,
    MAX_COMMANDS,
    MAX_CONSTRAINT,
    MAX_ENTITIES,
    MAX_ENTITY_NUMBERS,
    SIGMA_RANGE,
    Deck,
)
from tapp.processor.deck_bind import bind
from tapp.processor.printout import o3_text, run_dict
from tapp.processor.tape32 import build_t32
from tests.tapp.processor.helpers import deck, leo_tape, run, sigmas
from tests.test_fuzz import dumps_toml

SCENARIOS = EXAMPLES
runner = CliRunner()


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


def _bind(tape, doc: dict):
    return bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


def _refused(tape, doc: dict) -> str:
    with pytest.raises(InputError) as info:
        _bind(tape, doc)
    return str(info.value)


def _normal(tape) -> np.ndarray:
    """The fit a priori normal matrix of the σ table, diag(1/σ²), in tape order (n_o x n_o)."""
    return np.diag([1.0 / s**2 for s in sigmas(tape).values()])


def _with_normal(tape, s0: np.ndarray) -> dict:
    """A deck giving the fit a priori as a matrix (positional: it names its tape)."""
    doc = deck(tape)
    doc["tape"] = {"parameters": list(tape.parameters.name)}
    doc["fit"]["apriori"] = {"normal": s0.tolist()}
    return doc


def test_the_normal_matrix_of_the_sigma_table_binds(tape) -> None:
    plan = _bind(tape, _with_normal(tape, _normal(tape)))
    np.testing.assert_array_equal(plan.S0, _normal(tape))


def test_asymmetry_is_measured_on_each_entrys_own_scale(tape) -> None:
    # x_km and y_km have 1/σ² = 1; the largest entry is 4e12 (lon_rad, σ = 5e-7... 1e-6),
    # so the old tolerance 1e-12 max|S| let 0.5 against √(S_xx S_yy) = 1 pass
    s0 = _normal(tape)
    s0[0, 1], s0[1, 0] = 0.5, 0.0
    assert 0.5 < 1e-12 * np.abs(s0).max()
    assert _refused(tape, _with_normal(tape, s0)) == (
        "deck.toml: fit.apriori.normal: expected a symmetric matrix (|a_ij − a_ji| <= 1e-12 "
        "√(a_ii a_jj)) (got '0.5 √(a_ii a_jj)')")
    s0[1, 0] = 0.5 * (1 + 1e-14)  # rounding: accepted, and symmetrised
    assert _bind(tape, _with_normal(tape, s0)).S0[1, 0] == _bind(
        tape, _with_normal(tape, s0)).S0[0, 1]


def test_an_indefinite_normal_matrix_is_refused_naming_its_key(tape) -> None:
    # a correlation of 2 between x and y: eigenvalue −1 of the scaled matrix, which passed the
    # old check (tolerance 1e-10 of the largest diagonal, 4e12) and failed later as "not
    # invertible ... give these parameters an a priori σ"
    s0 = _normal(tape)
    s0[0, 1] = s0[1, 0] = 2.0
    assert _refused(tape, _with_normal(tape, s0)) == (
        "deck.toml: fit.apriori.normal: expected a positive semi-definite normal matrix "
        "(eigenvalues of the matrix scaled to a unit diagonal >= -1e-10) (got 'smallest -1')")
    s0[0, 1] = s0[1, 0] = 1.0  # exactly correlated: semi-definite, accepted
    _bind(tape, _with_normal(tape, s0))


@pytest.mark.parametrize(("value", "why"), [(-1.0, "negative"), (1e61, "beyond 1/σ_min²")])
def test_a_normal_diagonal_out_of_range_names_the_parameter(tape, value: float, why: str
                                                            ) -> None:
    s0 = _normal(tape)
    s0[6, 6] = value
    lo, hi = SIGMA_RANGE[1] ** -2, SIGMA_RANGE[0] ** -2
    assert _refused(tape, _with_normal(tape, s0)) == (
        f"deck.toml: fit.apriori.normal: expected a diagonal of 0 or 1/σ² between {lo:g} and "
        f"{hi:g} (σ within 1e-30 .. 1e+30) (got {{'GM_km3_s2': {value!r}}})")


def _with_covariance(tape, lam: np.ndarray) -> dict:
    doc = deck(tape)
    doc["tape"] = {"iden": tape.iden}
    doc["real"]["apriori"] = {"covariance": lam.tolist()}
    return doc


def test_a_real_covariance_of_1e300_or_indefinite_is_refused_naming_its_key(tape) -> None:
    lam = np.diag([s**2 for s in sigmas(tape).values()])
    _bind(tape, _with_covariance(tape, lam))
    huge = lam.copy()
    huge[7, 7] = 1e300  # gave NaN in the JSON after RuntimeWarnings
    assert _refused(tape, _with_covariance(tape, huge)).startswith(
        f"deck.toml: real.apriori.covariance: expected a diagonal of 0 or σ² between "
        f"{COVARIANCE_RANGE[0]:g} and {COVARIANCE_RANGE[1]:g}")
    bad = lam.copy()
    bad[0, 1] = bad[1, 0] = 1.5  # ρ = 1.5 between x and y (σ = 1 km)
    assert "expected a positive semi-definite covariance matrix" in _refused(
        tape, _with_covariance(tape, bad))


@pytest.mark.parametrize("sigma", [1e149, 1e-149, 1e31])
def test_a_sigma_outside_the_range_is_refused(tape, sigma: float) -> None:
    # 1e149 was inside the old documented range and printed negative variances as σ = 0
    doc = deck(tape, real=sigmas(tape, x_km=sigma))
    assert _refused(tape, doc) == (
        "deck.toml: real.apriori.sigma: expected σ between 1e-30 and 1e+30 (or inf: no a "
        f"priori information) (got {{'x_km': {sigma!r}}})")


def test_a_constraint_coefficient_of_1e200_is_refused(tape) -> None:
    doc = deck(tape, real={**sigmas(tape), "KOUROU.range_bias_km": 0.0},
               fit={**sigmas(tape)})
    doc["real"]["constraints"] = [["KOUROU.range_bias_km", "QUITO.range_bias_km", 1e200]]
    assert _refused(tape, doc) == (
        "deck.toml: real.constraints[0]: expected a coefficient |e| <= 1e+10 (e σ_b is a σ of "
        "the constrained system) (got 1e+200)")


def _all_finite(result) -> bool:
    return all(np.all(np.isfinite(e.matrix)) for b in result.blocks for e in b.entities)


@pytest.mark.parametrize("sigma", SIGMA_RANGE)
def test_at_either_end_of_the_sigma_range_every_output_is_finite(tape, sigma: float) -> None:
    # the position's σ at the bound in both worlds (the audit's σ = 1e149 on x, y, z), a
    # constraint at its bound too: no RuntimeWarning (the suite runs with warnings as
    # errors), no NaN, no negative variance, and the T32 tape it makes is within the tapes'
    # bound
    position = {"x_km": sigma, "y_km": sigma, "z_km": sigma}
    doc = deck(tape, fit=sigmas(tape, **position),
               real=sigmas(tape, **position, **{"KOUROU.range_bias_km": 0.0}),
               times={"print": [1, 2, 3], "recycle": [2]},
               commands={"print": ["cov-real o@current", "cov-fit o@current",
                                   "Lb'; 0,-,m; 0,-,m", "partials m wrt fp@current"]})
    doc["real"]["constraints"] = [["KOUROU.range_bias_km", "QUITO.range_bias_km",
                                   MAX_CONSTRAINT]]
    data = memory_pairs(tape)
    plan = _bind(tape, doc)
    result = run(tape, doc)
    assert _all_finite(result)
    for block in result.blocks:
        for ent in block.entities:
            if ent.command.is_covariance and ent.rows == ent.cols:
                assert np.all(np.diagonal(ent.matrix) >= 0)
    validate_t32(build_t32(result, plan, data.header, {}), "T32")
    text = json.dumps(run_dict(result, data.header, "deck.toml", "tape"))  # the printout's
    assert not re.search(r"\bNaN\b|Infinity", text)                    # σ, ρ, budgets
    assert "nan" not in o3_text(result, data.header, "deck.toml", "tape")


def test_the_leo_deck_at_the_top_of_the_range_writes_json_without_nan(tmp_path: Path,
                                                                      leo_t13: Path) -> None:
    import tomllib

    doc = tomllib.loads((SCENARIOS / "tapp3_leo_equatorial.toml").read_text())
    for world in ("fit", "real"):
        table = doc[world]["apriori"]["sigma"]
        table.update({k: SIGMA_RANGE[1] for k, v in table.items() if v > 0})
    path = tmp_path / "top.toml"
    path.write_text(dumps_toml(doc))
    out = tmp_path / "top.json"
    res = runner.invoke(app, ["process", str(leo_t13), str(path), "--json", str(out),
                              "--print", str(tmp_path / "o3.txt")])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert not re.search(r"\bNaN\b|Infinity", text)
    assert json.loads(text)["blocks"]


@pytest.fixture(scope="module")
def leo_t13(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("leo") / "leo.t13.h5"
    res = runner.invoke(app, ["simulate", str(SCENARIOS / "leo_equatorial.toml"), "-o",
                              str(path)])
    assert res.exit_code == 0, res.output
    return path


# --- the size of a run ----------------------------------------------------------------------


def test_more_commands_than_the_bound_are_refused_by_the_schema(tape) -> None:
    doc = deck(tape, commands={"print": ["cov-real orbit@current"] * (MAX_COMMANDS + 1)})
    assert _refused(tape, doc).startswith(
        f"deck.toml: commands.print: expected at most {MAX_COMMANDS} items")
    doc["commands"]["print"] = doc["commands"]["print"][:MAX_COMMANDS]
    _bind(tape, doc)


def _entity_counts(plan) -> tuple[int, int]:
    def size(cmd) -> int:
        rows, cols = (plan.systems.bounds(s.rho) for s in (cmd.rows, cmd.cols))
        return (rows[2] - rows[1]) * (cols[2] - cols[1])

    n_print, n_recycle = len(plan.print_k), len(plan.recycle_k)
    return (n_print * len(plan.print_commands) + n_recycle * len(plan.recycle_commands),
            n_print * sum(map(size, plan.print_commands))
            + n_recycle * sum(map(size, plan.recycle_commands)))


def test_entities_and_numbers_are_bounded_before_any_is_computed(tape) -> None:
    # 4 print times (k = 0..3), one recycle: 6 x 6 orbit covariances up to MAX_ENTITIES
    times = {"print": [1, 2, 3], "recycle": [2]}
    doc = deck(tape, times=times, commands={"print": ["cov-real orbit@current"]})
    one = _entity_counts(_bind(tape, doc))
    n = (MAX_ENTITIES - (one[0] - 4)) // 4
    doc["commands"]["print"] = ["cov-real orbit@current"] * n
    assert _entity_counts(_bind(tape, doc))[0] <= MAX_ENTITIES  # at the bound: accepted
    doc["commands"]["print"].append("cov-real orbit@current")
    entities, numbers = 4 * (n + 1) + one[0] - 4, 36 * 4 * (n + 1) + one[1] - 36 * 4
    assert entities > MAX_ENTITIES
    assert _refused(tape, doc) == (
        f"deck.toml: commands.print: expected at most {MAX_ENTITIES:,} output entities with at "
        f"most {MAX_ENTITY_NUMBERS:,} numbers in all (print times x print commands + recycles "
        f"x recycle commands) (got '{entities:,} entities, {numbers:,} numbers')")
    # numbers: the covariance of the 23 standard parameters is 529 numbers
    big = "Lb'; 0,0,o; 0,0,o"
    doc["commands"]["print"] = [big] * (MAX_ENTITY_NUMBERS // (4 * 529) + 1)
    message = _refused(tape, doc)
    assert message.startswith("deck.toml: commands.print: expected at most 2,000 output")
    assert int(re.search(r"entities, ([\d,]+) numbers", message)[1].replace(",", "")) > (
        MAX_ENTITY_NUMBERS)


@pytest.mark.slow
def test_a_run_at_the_entity_bound_finishes_in_bounded_time_and_memory(tmp_path: Path,
                                                                        leo_t13: Path) -> None:
    # the cost stated at tapp.processor.deck.MAX_ENTITIES: ~8 s, ~330 MB, a 24 MB JSON
    import resource
    import subprocess
    import sys
    import time
    import tomllib

    doc = tomllib.loads((SCENARIOS / "tapp3_leo_equatorial.toml").read_text())
    # 4 print times (k = 0, 2, 4, 8) and the 9 standard recycle commands at k = 4
    doc["commands"]["print"] = ["cov-real orbit@current"] * ((MAX_ENTITIES - 9) // 4)
    doc["times"]["print"] = [2, 4, 8]
    path = tmp_path / "bound.toml"
    path.write_text(dumps_toml(doc))
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "tapp.cli", "process", str(leo_t13),
                           str(path), "--json", str(tmp_path / "o.json"), "--print",
                           str(tmp_path / "o3.txt")], capture_output=True, text=True)
    wall_s = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    assert wall_s < 60 and peak_mb < 1000, (wall_s, peak_mb)
    assert (tmp_path / "o.json").stat().st_size < 100e6
