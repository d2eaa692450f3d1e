"""Stochastic accelerations in TAPP I: the scenario table, the partials against central
differences, the unchanged transition, and the tape's record of them.

The partials on the tape come from one propagation restarted at the interval boundaries and
composed forward (tapp.tracking.pieces). The reference here differences whole trajectories
instead: propagated state-only, restarted at t_k and t_{k+1} with the acceleration ±ε switched on
in interval k alone, from the epoch state the tape's partials are referred to.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tapp.dynamics import Propagator
from tapp.dynamics.empirical import PARAMETERS
from tapp.errors import InputError, TapeError
from tapp.io.tape.t13 import validate
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.orbit.equinoctial import equinoctial_elements
from tapp.tracking.simulate import simulate
from tests.tapp.tracking.helpers import leo_scenario

#: 3000 s intervals over the 3 h arc (the last 1800 s), an epoch at 5400 s inside interval 2,
#: so that partials referred to it count only [5400, 6000) of that interval.
STOCHASTIC = {"frame": "ric", "interval_s": 3000.0, "sigma_m_s2": 1e-6, "tau_s": 7200.0}
TIMES = {"epochs": [5400.0]}
#: Difference step, km/s²: moves the state by ~0.5 ε (600-3000 s)² = 2e-3 to 4e-2 km, far above
#: the integrator's ~1e-9 km (rtol 1e-13 of 7000 km), while the O(ε²) terms cancel in central
#: differences and the O(ε³) are ~1e-16 relative.
EPS_KM_S2 = 1e-8
#: Agreement of partials with their central differences, relative to the largest entry of
#: the column: the integrator's error over the step, ~1e-10 km / 2e-3 km (measured 2.6e-8).
FD_TOL = 1e-6
#: The miss partials B = G S(t_m) carry the error of G = ∂m/∂x(t_m), which TAPP I takes by
#: central differences (~1e-10 relative, tapp.tracking.simulate), amplified by cancellation:
#: ∂a/∂r S_r and ∂a/∂v S_v are each ~2e7 km per km/s² and sum to ~100 (measured 9.4e-6).
MISS_TOL = 5e-5


@pytest.fixture(scope="module")
def simulation():
    sc = leo_scenario(stochastic=STOCHASTIC, times=TIMES)
    return simulate(sc, raw=True)


def _piecewise(sc, x_start, t0, t_end, k, component, eps):
    """State at t_end from (t0, x_start) with acceleration eps on one component in interval k
    only: state-only propagations restarted at the boundaries inside (t0, t_end)."""
    bounds = sc.stochastic.boundaries_s
    names = PARAMETERS[sc.stochastic.frame]
    prop = Propagator(sc.state_model, params=names, rtol=sc.rtol, atol=sc.atol)
    cuts = sorted({t0, t_end} | {b for b in bounds if t0 < b < t_end})
    x = np.asarray(x_start, dtype=float)
    for a, b in zip(cuts, cuts[1:], strict=False):
        on = bounds[k] <= a < bounds[k + 1]
        values = {n: (eps if on and i == component else 0.0) for i, n in enumerate(names)}
        x = prop.propagate(x, np.array([b]), t0_s=a, stm=False, param_values=values,
                           orientation=sc.orientation, epoch_jd_utc=sc.epoch.jd).states[-1]
    return x


def test_the_table_appends_one_parameter_per_interval_and_component():
    sc = leo_scenario(stochastic=STOCHASTIC, times=TIMES)
    spec = sc.stochastic
    assert spec.boundaries_s == (0.0, 3000.0, 6000.0, 9000.0, 10800.0)
    assert spec.sigma_km_s2 == pytest.approx(1e-9)
    tail = sc.parameters[-12:]
    assert [p.name for p in tail[:4]] == ["acc_R_001", "acc_I_001", "acc_C_001", "acc_R_002"]
    assert {(p.kind, p.unit, p.nominal) for p in tail} == {("stochastic", "km/s^2", 0.0)}
    inertial = leo_scenario(stochastic={"frame": "inertial", "components": ["z", "x"],
                                        "boundaries": [0.0, 5000.0, 10800.0],
                                        "sigma_km_s2": 1e-12, "tau_s": 1e5}).stochastic
    assert inertial.components == ("x", "z") and inertial.names[-1] == "acc_z_002"


@pytest.mark.parametrize(("table", "message"), [
    ({"frame": "lvlh"}, "stochastic.frame"),
    ({"components": ["x"]}, "stochastic.components\\[0\\]: expected components of the ric"),
    ({"sigma_km_s2": 1e-12}, "exactly one of sigma_km_s2 or sigma_m_s2"),
    ({"sigma_m_s2": None}, "exactly one of sigma_km_s2 or sigma_m_s2"),
    ({"boundaries": [0.0, 100.0]}, "either interval_s .* or boundaries"),
    ({"interval_s": None, "boundaries": [0.0, 200.0, 100.0]}, "strictly ascending"),
    ({"interval_s": None, "boundaries": [0.0, 20000.0]}, "intervals within \\[0, 10800\\]"),
    ({"end": 20000.0}, "stochastic.end: expected intervals within"),
    ({"interval_s": 10.0}, "at most 300"),
    ({"tau_s": -1.0}, "stochastic.tau_s"),
])
def test_bad_tables_are_input_errors_naming_the_field(table, message):
    with pytest.raises(InputError, match=message):
        leo_scenario(stochastic={**STOCHASTIC, **table})


def test_record_partials_match_central_differences_referred_to_each_epoch(simulation):
    sc, tape = simulation.scenario, simulation.tape
    rec = tape.records
    first = list(tape.parameters.name).index("acc_R_001")
    states = np.vstack([sc.x0, rec.info])          # state at every T13 time
    for k_rec in (2, 4):                           # t = 5400 (epoch 0), 10800 (epoch 5400)
        j = int(rec.j[k_rec - 1])
        t0, t = float(rec.times_s[j]), float(rec.times_s[k_rec])
        u = rec.U[k_rec - 1][:, first:]
        for col in range(u.shape[1]):
            k, c = divmod(col, 3)
            plus = _piecewise(sc, states[j], t0, t, k, c, EPS_KM_S2)
            minus = _piecewise(sc, states[j], t0, t, k, c, -EPS_KM_S2)
            fd = (plus - minus) / (2 * EPS_KM_S2)
            scale = max(np.max(np.abs(fd)), 1.0)   # columns of intervals not yet begun are 0
            assert np.max(np.abs(u[:, col] - fd)) <= FD_TOL * scale, (k_rec, col)
    # referred to the epoch 5400 s, the first interval [0, 3000) has no effect any more
    assert np.all(rec.U[3][:, first:first + 3] == 0)


def test_miss_partials_match_central_differences(simulation):
    sc, tape = simulation.scenario, simulation.tape
    first = list(tape.parameters.name).index("acc_R_001")
    mu = [p.nominal for p in sc.parameters if p.name == "GM_km3_s2"][0]
    b = tape.miss.B[:, first:]
    for col in (1, 4, 9, 11):
        k, c = divmod(col, 3)
        plus = equinoctial_elements(_piecewise(sc, sc.x0, 0.0, tape.miss.t_s, k, c, EPS_KM_S2), mu)
        minus = equinoctial_elements(_piecewise(sc, sc.x0, 0.0, tape.miss.t_s, k, c,
                                                -EPS_KM_S2), mu)
        fd = (plus - minus) / (2 * EPS_KM_S2)
        np.testing.assert_allclose(b[:, col], fd, rtol=0, atol=MISS_TOL * np.max(np.abs(fd)))


def test_the_restarts_leave_the_transition_and_other_partials_unchanged(simulation):
    """Φ and the GM, J2 sensitivities composed across the interval restarts against one
    integration per epoch segment (no stochastic table): the integrator's own agreement,
    1e-11 of each column's largest entry (measured 4e-13)."""
    plain = simulate(leo_scenario(times=TIMES)).tape
    n = 8                                          # the state, GM and J2 (stations: 0 in U)
    u, ref = simulation.tape.records.U[:, :, :n], plain.records.U[:, :, :n]
    scale = np.max(np.abs(ref), axis=(0, 1))
    assert np.all(simulation.tape.records.U[:, :, n:plain.n_o] == 0)
    assert np.max(np.abs(u - ref) / scale) < 1e-11
    np.testing.assert_allclose(simulation.tape.records.info, plain.records.info, rtol=0,
                               atol=1e-9)


def test_the_tape_keeps_the_definition_and_refuses_a_mismatch(simulation, tmp_path: Path):
    tape = simulation.tape
    back = read_t13(write_t13(tmp_path / "s.t13.h5", tape))
    assert back.stochastic == tape.stochastic
    assert back.parameters.kind[-1] == "stochastic"
    with pytest.raises(TapeError, match="stochastic: expected the definition"):
        validate(replace(tape, stochastic=None))
    other = replace(tape.stochastic, components=("R", "I"))
    with pytest.raises(TapeError, match="parameters/kind: expected the 8 stochastic"):
        validate(replace(tape, stochastic=other))
