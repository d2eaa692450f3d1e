"""B-plane targeting through the integrator: values, analytic partials, failures, scenario.

The scenario is the example ``search_bplane.toml``: a trans-lunar injection from a 185 km
parking orbit (2026-03-10 12:00 UTC, J2 + Sun + Moon from DE421) targeted to B·R = -2000 km,
B·T = 5300 km and the first guess's flight time + 1 h.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from search import solve
from tapp.constants import SECONDS_PER_DAY, GM_km3_s2
from tapp.dynamics import Propagator
from tapp.dynamics.ephemeris import position_km
from tapp.errors import InputError, NotHyperbolicError
from tapp.examples import FOLDER as EXAMPLES
from tapp.orbit.bplane import b_plane
from tapp.targeting.program import BPlaneProgram, FailedCaseError, TargetMissedError, run_search
from tapp.targeting.searchfile import scenario_search

SCENARIO = EXAMPLES / "search_bplane.toml"

# Named tolerances (STYLE 7).
one_metre_km = 1e-3
ten_ms_s = 1e-2
# Analytic vs central-difference partials, relative to each row's largest element. Central
# differences with h = 1 mm/s have truncation ~(h / 0.02 km/s)^2 ~ 3e-9 (0.02 km/s is the
# scale over which the partials change, seen in the forward-difference test below) and
# integration noise ~1e-8 km / (2 h) / 1e6 ~ 1e-8; observed <= 1.3e-8. 1e-6 leaves margin and
# still fails if the periapsis-time term is wrong (leaving out the Earth's direct
# acceleration in z-dot gives 4.5e-4; the Moon's acceleration, 0.12).
partials_rtol = 1e-6
central_step_km_s = 1e-6
# SEARCH's forward differences (h = 1 cm/s, the scenario's increments) are first order:
# error ~ h / (2 x 0.02 km/s) ~ 3e-4 of the row scale (observed 2.8e-4).
forward_rtol = 1e-3


def _load(**edits: dict) -> dict:
    data = tomllib.loads(SCENARIO.read_text())
    for table, values in edits.items():
        data[table].update(values)
    return data


@pytest.fixture(scope="module")
def problem():
    return scenario_search(_load(), str(SCENARIO))


@pytest.fixture(scope="module")
def targeted(problem):
    return run_search(problem)


def _row_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.max(np.abs(a - b), axis=1) / np.max(np.abs(b), axis=1)


def _central_partials(program: BPlaneProgram, v0: np.ndarray, h: float) -> np.ndarray:
    cols = []
    for j in range(3):
        dv = np.zeros(3)
        dv[j] = h
        cols.append((program(v0 + dv) - program(v0 - dv)) / (2.0 * h))
    return np.stack(cols, axis=1)


def test_search_converges_and_uses_theta_for_the_flight_time(problem, targeted) -> None:
    result = targeted.result
    assert result.status == "converged"
    nominal = result.history.cases[0]
    # y_T3 = y_03 + theta_3 (seed section II); B.R and B.T targets as given.
    assert result.targets[2] == nominal.y[2] + 3600.0
    np.testing.assert_array_equal(result.targets[:2], [-2000.0, 5300.0])
    assert np.all(np.abs(result.miss) <= problem.tolerances)
    assert targeted.trajectories == result.n_cases == len(result.history.cases)
    # a lunar flyby above the surface, hyperbolic
    assert 1737.4 < float(targeted.encounter.b_plane.periapsis_radius_km) < 5000.0


def test_targeted_trajectory_flown_again_independently_hits_the_targets(problem,
                                                                        targeted) -> None:
    """Re-fly the converged injection with a fresh propagator at 1e-14 on a 1 s grid, find
    periapsis by interpolating r·v = 0 relative to the Moon (Moon velocity by a plain
    central difference of DE421), and compare with the targets."""
    program = problem.program
    result = targeted.result
    t_e = targeted.encounter.t_periapsis_s
    fresh = Propagator(program.propagator.state_model, rtol=1e-14, atol=1e-14)
    t = np.arange(np.floor(t_e) - 120.0, np.floor(t_e) + 121.0, 1.0)
    orientation = program.orientation
    assert orientation.model == "iau2006"  # the scenario's default: the Moon is read at TDB
    traj = fresh.propagate(np.concatenate([program.r0_km, result.x]), t, stm=False,
                           orientation=orientation, epoch_jd_utc=program.epoch.jd)
    tdb = orientation.scales.tdb
    moon = position_km("moon", "earth", *tdb(t))
    moon_v = (position_km("moon", "earth", *tdb(t + 0.5))
              - position_km("moon", "earth", *tdb(t - 0.5)))
    r = traj.states[:, :3] - moon
    v = traj.states[:, 3:] - moon_v
    rdotv = np.sum(r * v, axis=1)
    k = int(np.flatnonzero((rdotv[:-1] < 0) & (rdotv[1:] >= 0))[0])
    t_peri = t[k] - rdotv[k] * (t[k + 1] - t[k]) / (rdotv[k + 1] - rdotv[k])
    nearest = k if t_peri - t[k] < 0.5 else k + 1
    bp = b_plane(r[nearest], v[nearest], GM_km3_s2["moon"])
    flown = np.array([float(bp.b_dot_r_km), float(bp.b_dot_t_km), t_peri])
    assert np.all(np.abs(flown - result.targets) <= problem.tolerances), flown - result.targets
    # and the program's own values to a metre and 10 ms
    assert np.all(np.abs(flown[:2] - result.y[:2]) <= one_metre_km)
    assert abs(flown[2] - result.y[2]) <= ten_ms_s


@pytest.mark.parametrize("where", ["first guess", "converged"])
def test_analytic_partials_agree_with_central_differences(problem, targeted, where) -> None:
    v0 = np.array(problem.v0_km_s if where == "first guess" else targeted.result.x)
    analytic = problem.program.partials(v0)
    central = _central_partials(problem.program, v0, central_step_km_s)
    assert np.all(_row_error(analytic, central) <= partials_rtol), _row_error(analytic, central)


def test_body_equator_partials_carry_the_turning_pole() -> None:
    """In the Moon's equator the reference pole turns with the periapsis time t_e (up to
    3e-9 rad/s): the analytic partials carry that term (measured 1.3e-8 of the B·R row
    against central differences; 1.0e-4 without it), to the same partials_rtol."""
    program = scenario_search(_load(target={"reference": "body_equator"}),
                              str(SCENARIO)).program
    v0 = np.array(_load()["injection"]["v_km_s"])
    analytic = program.partials(v0)
    central = _central_partials(program, v0, central_step_km_s)
    assert np.all(_row_error(analytic, central) <= partials_rtol), _row_error(analytic, central)


def test_analytic_partials_agree_with_search_forward_differences(problem) -> None:
    """SEARCH's own differenced A (partials_only) vs the STM, and its error is first order."""
    program = problem.program
    v0 = np.array(problem.v0_km_s)
    analytic = program.partials(v0)
    errors = []
    for h in (problem.increments, problem.increments / 2.0):
        r = solve(program, v0, problem.targets, tolerances=problem.tolerances, increments=h,
                  partials_only=True)
        assert r.status == "converged" and r.n_perturbed == 3
        errors.append(_row_error(r.history.partial_sets[0].partials, analytic))
    assert np.all(errors[0] <= forward_rtol), errors[0]
    # halving the increment halves the forward-difference error (first order): ratio 2 +- 25 %
    np.testing.assert_allclose(errors[0] / errors[1], 2.0, rtol=0.25)


def test_analytic_and_differenced_searches_agree(problem, targeted) -> None:
    analytic = run_search(problem, analytic_partials=True)
    assert analytic.result.status == "converged"
    assert analytic.result.n_perturbed == 0
    assert analytic.trajectories < targeted.trajectories
    # both meet the same targets; the solutions differ by less than what the tolerances allow
    np.testing.assert_array_equal(analytic.result.targets, targeted.result.targets)
    dy = np.abs(analytic.result.y - targeted.result.y)
    assert np.all(dy <= 2.0 * problem.tolerances)


def test_program_is_a_plain_function_of_the_injection_velocity(problem) -> None:
    program = problem.program
    v0 = np.array(problem.v0_km_s)
    encounter = program.evaluate(v0)
    np.testing.assert_array_equal(program(v0), encounter.y)
    assert encounter.partials is None
    # evaluated at periapsis: r.v = 0 to within the Newton tolerance (|t_p| <= 1 ms)
    r, v = encounter.state_rel[:3], encounter.state_rel[3:]
    assert abs(float(r @ v)) <= 1e-3 * float(v @ v)
    assert abs(encounter.y[2] - encounter.t_periapsis_s) <= program.periapsis_time_tol_s


def test_trajectory_that_misses_the_moon_raises_with_the_numbers(problem) -> None:
    v0 = np.array(problem.v0_km_s)
    slow = v0 * (1.0 - 0.1 / np.linalg.norm(v0))  # 100 m/s short: apogee below the Moon
    with pytest.raises(TargetMissedError, match="sphere of influence") as info:
        problem.program(slow)
    assert isinstance(info.value, NotHyperbolicError)
    assert "closest approach" in str(info.value)


def test_failed_case_stops_the_search_naming_the_case(problem) -> None:
    data = _load(target={"max_flight_time_s": 2.0 * SECONDS_PER_DAY})
    short = scenario_search(data, "short.toml")
    with pytest.raises(FailedCaseError, match=r"search case 1 at v0 = \[-9\.66") as info:
        run_search(short)
    assert info.value.case == 1
    assert isinstance(info.value.__cause__, TargetMissedError)


@pytest.mark.parametrize(("table", "values", "field"), [
    ("injection", {"r_km": [1.0, 2.0]}, "injection.r_km"),
    ("injection", {"v_km_s": [1.0, "a", 2.0]}, "injection.v_km_s[1]"),
    ("injection", {"r_km": [100.0, 0.0, 0.0]}, "injection"),
    ("injection", {"v_km_s": [0.0, 0.0, 1.0]}, "injection"),
    ("model", {"gravity": "J99"}, "model.gravity"),
    ("model", {"third_bodies": ["sun", "pluto"]}, "model.third_bodies[1]"),
    ("model", {"third_bodies": ["sun", "moon", "sun"]}, "model.third_bodies"),
    ("model", {"rtol": 1.0}, "model.rtol"),
    ("search", {"analytic_partials": 1}, "search.analytic_partials"),
    ("search", {"partial_sets": True}, "search.partial_sets"),
    ("target", {"scan_step_s": "600"}, "target.scan_step_s"),
    ("model", {"third_bodies": ["sun"]}, "target.body"),
    ("model", {"rtol": 0.0}, "model.rtol"),
    ("target", {"reference": "galactic"}, "target.reference"),
    ("target", {"body": "sun", "reference": "body_equator"}, "target.reference"),
    ("target", {"scan_step_s": 1e9}, "target.scan_step_s"),
    ("target", {"max_flight_time_s": -1.0}, "target.max_flight_time_s"),
    ("search", {"partial_sets": 0}, "search.partial_sets"),
    ("search", {"iterations_per_partials": 1.5}, "search.iterations_per_partials"),
    ("search", {"analytic_partials": "yes"}, "search.analytic_partials"),
    ("search", {"tolerances": {"b_dot_r_km": 1.0, "b_dot_t_km": 0.0, "flight_time_s": 1.0}},
     "search.tolerances.b_dot_t_km"),
    ("search", {"increments": {"vx_km_s": 1e-5, "vy_km_s": 0.0, "vz_km_s": 1e-5}},
     "search.increments.vy_km_s"),
    ("search", {"targets": {"b_dot_r_km": 1.0, "b_dot_t_km": 2.0}},
     "search.targets.flight_time_s"),
    ("search", {"targets": {"b_dot_r_km": 1.0, "b_dot_t_km": 2.0, "flight_time_s": 0.0,
                            "bdotr_km": 3.0}}, "search.targets.bdotr_km"),
    ("search", {"tolerence": 1.0}, "search.tolerence"),
])
def test_scenario_fields_are_validated_by_name(table, values, field) -> None:
    with pytest.raises(InputError) as info:
        scenario_search(_load(**{table: values}), "bad.toml")
    assert info.value.source == "bad.toml"
    assert info.value.field == field


def test_scenario_unknown_top_level_keys_and_wrong_types_are_one_line() -> None:
    data = _load()
    data["titel"] = "typo"
    with pytest.raises(InputError, match=r"^bad\.toml: titel: expected no such key \(allowed: "
                       r"title, epoch, earth_orientation, eop, injection, model, target, search\) "
                       r"\(got 'typo'\)$"):
        scenario_search(data, "bad.toml")
    data = _load()
    data["title"] = 3
    with pytest.raises(InputError, match=r"^bad\.toml: title: expected text"):
        scenario_search(data, "bad.toml")


def test_scenario_epoch_is_validated() -> None:
    data = _load()
    data["epoch"] = "2026-13-01"
    with pytest.raises(InputError, match=r"^bad\.toml: epoch"):
        scenario_search(data, "bad.toml")
