"""Manoeuvres in TAPP I: the scenario tables, the execution-error partials and the transition
through the burns against restarted propagations, and bad input.

The reference flies the burns itself (:func:`_flown`): state-only propagations restarted at
every burn, an impulsive burn applied with the test's own NumPy axes and Gates' *physical*
errors (the magnitude scaled, the direction turned: tests/tapp/dynamics/burn_reference.py), a
finite burn's thrust turned and scaled the same way (its fixed errors a constant acceleration
over the burn, as the model defines them). Partials are Richardson-extrapolated central
differences (steps h and h/2: the O(h²) of the turned directions cancels).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np
import pytest
import spiceypy
import tomli_w
from astropy.time import Time, TimeDelta
from oem import OrbitEphemerisMessage
from typer.testing import CliRunner

import tapp.cli.simulate_cmd  # noqa: F401  (registers the commands until tapp.cli imports it)
from tapp.cli.common import app
from tapp.dynamics import Propagator
from tapp.dynamics.gates import pointing_axes
from tapp.dynamics.manoeuvres import THRUST_PARAMETERS, ImpulsiveBurn
from tapp.errors import InputError, TapeError
from tapp.io.ccsds.oem import (
    INTERPOLATION,
    INTERPOLATION_DEGREE,
    INTERPOLATION_TOL_KM,
    INTERPOLATION_TOL_KM_S,
    format_oem,
)
from tapp.io.tape.t13 import summary, validate
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.orbit.equinoctial import equinoctial_elements
from tapp.tracking.oem_states import oem_trajectory, segment_comments, write_trajectory_spk
from tapp.tracking.simulate import simulate
from tests.tapp.dynamics.burn_reference import axes, executed, turned
from tests.tapp.tracking.helpers import leo_document, leo_scenario

#: Gates' four σ of both burns: 1 %, 5 mm/s, 10 mrad, 5 mm/s.
SIGMAS = {"sigma_magnitude_proportional": 0.01, "sigma_magnitude_fixed_mm_s": 5.0,
          "sigma_pointing_proportional_mrad": 10.0, "sigma_pointing_fixed_mm_s": 5.0}
#: A 2.3 m/s impulsive burn in VNB axes before the epoch at 5300 s, and a 24 mm/s finite burn
#: in RIC axes that the epoch cuts (partials referred to it count [5300, 5600) s only).
MANOEUVRES = [
    {"name": "TCM1", "kind": "impulsive", "time": 2000.0, "axes": "vnb",
     "dv_m_s": [2.0, 0.5, -1.0], **SIGMAS},
    {"name": "BURN", "kind": "finite", "start": 5000.0, "duration_s": 600.0, "axes": "ric",
     "direction": [0.0, 1.0, 0.2], "thrust_N": 20.0, "mass_kg": 500.0,
     "mass_flow_kg_s": 0.01, **SIGMAS},
]
TIMES = {"epochs": [5300.0]}
#: Impulsive burns where the arc restarts: one at the injection (RIC), one at the epoch
#: (inertial; the state at 5300 s is the one before it, the partials referred to it count it).
AT_RESTARTS = [
    {"name": "START", "kind": "impulsive", "time": 0.0, "axes": "ric",
     "dv_m_s": [0.5, -1.0, 0.3], **SIGMAS},
    {"name": "EPOCH", "kind": "impulsive", "time": 5300.0, "axes": "inertial",
     "dv_km_s": [1e-3, 2e-3, -1e-3], **SIGMAS},
]
#: Agreement of ∂x(t_k)/∂e on the tape with the differences, relative to the largest partial
#: of the burn's parameters of the same unit at that record: the integrator's noise over the
#: steps (rtol 1e-13 of 7000 km against displacements of 0.1-10 km) and O(h⁴) of the turned
#: directions (measured 1.2e-8 in moving axes, 3.2e-9 at the restarts).
FD_TOL = 1e-7
#: The transition through the burns, each column relative to its largest entry (steps 1 km,
#: 1 m/s; measured 3.5e-10 in moving axes, 2.7e-9 at the restarts).
PHI_TOL = 1e-7
#: The miss partials carry G = ∂m/∂x(t_m) by central differences (tapp.tracking.simulate),
#: as the stochastic accelerations' (tests/tapp/tracking/test_stochastic.py; measured 9.1e-9
#: on the scale of the burn's partials of the same unit).
MISS_TOL = 5e-5

runner = CliRunner()


@pytest.fixture(scope="module")
def simulation():
    return simulate(leo_scenario(manoeuvre=MANOEUVRES, times=TIMES))


@pytest.fixture(scope="module", params=["moving axes", "at restarts"])
def simulations(request, simulation):
    """The two cases: burns in moving axes (one cut by the epoch), burns where the arc
    restarts (the injection, the epoch)."""
    if request.param == "moving axes":
        return simulation
    return simulate(leo_scenario(manoeuvre=AT_RESTARTS, times=TIMES))


def _flown(sc, x: np.ndarray, t0: float, t1: float, errors: dict[str, np.ndarray]
           ) -> np.ndarray:
    """The state at t1 from (t0, x), flying the scenario's burns with Gates' six errors
    ``errors[name]`` taken physically (module docstring)."""
    cuts = sorted({t0, t1} | {t for b in sc.manoeuvres for t in (b.t_start_s, b.t_end_s)
                              if t0 < t < t1})
    x = np.array(x, dtype=float)
    for a, b in zip(cuts, cuts[1:], strict=False):
        prop, values = Propagator(sc.state_model), {}
        for burn in sc.manoeuvres:
            q = errors.get(burn.name, np.zeros(6))
            if isinstance(burn, ImpulsiveBurn):
                if burn.t_s == a:
                    x[3:] += axes(x[:3], x[3:], burn.axes) @ executed(np.array(burn.dv_km_s), q)
            elif burn.t_start_s <= a < burn.t_end_s:
                names = THRUST_PARAMETERS[burn.axes]
                prop = Propagator(sc.state_model, params=names)
                d = np.array(burn.direction)
                u, e1, e2 = pointing_axes(d)
                w = burn.thrust_N / burn.mass_kg * 1e-3 * (1 + q[0]) * turned(d, q[2], q[3])
                c = (q[1] * u + q[4] * e1 + q[5] * e2) / burn.duration_s
                values = dict(zip(names, [*w, *c, burn.mass_flow_kg_s / burn.mass_kg,
                                          burn.t_start_s], strict=True))
        x = prop.propagate(x, np.array([b]), t0_s=a, stm=False, param_values=values,
                           orientation=sc.orientation, epoch_jd_utc=sc.epoch.jd).states[-1]
    return x


def _richardson(f, h: float) -> np.ndarray:
    """(4 D(h/2) − D(h)) / 3 of the central differences D of f at 0."""
    d1 = (f(h) - f(-h)) / (2 * h)
    d2 = (f(h / 2) - f(-h / 2)) / h
    return (4 * d2 - d1) / 3


def _records(simulation):
    """(k, t_k, t_j, state at t_j) of every record of the tape."""
    tape = simulation.tape
    times = np.concatenate([[0.0], tape.records.t_s])
    for k, (t_k, j) in enumerate(zip(tape.records.t_s, tape.records.j, strict=True)):
        t_j = times[j]
        yield k, t_k, t_j, simulation.states[np.searchsorted(simulation.t_s, t_j)]


def test_each_error_source_is_a_parameter_of_kind_execution(simulation):
    tape = simulation.tape
    at = [i for i, kind in enumerate(tape.parameters.kind) if kind == "execution"]
    assert [tape.parameters.name[i] for i in at[:6]] == [
        "TCM1.mag_prop", "TCM1.mag_fixed_km_s", "TCM1.point_prop_1_rad", "TCM1.point_prop_2_rad",
        "TCM1.point_fixed_1_km_s", "TCM1.point_fixed_2_km_s"]
    assert at == list(range(tape.n_o - 12, tape.n_o))  # last, after the stations
    assert [tape.parameters.unit[i] for i in at[6:]] == ["1", "km/s", "rad", "rad", "km/s",
                                                          "km/s"]
    assert np.all(tape.parameters.nominal[at] == 0)
    # a source with σ = 0 is no parameter
    sc = leo_scenario(manoeuvre=[{**MANOEUVRES[0], "sigma_pointing_proportional_mrad": 0.0,
                                  "sigma_magnitude_fixed_mm_s": 0.0}])
    assert [p.name for p in sc.parameters if p.kind == "execution"] == [
        "TCM1.mag_prop", "TCM1.point_fixed_1_km_s", "TCM1.point_fixed_2_km_s"]


def test_execution_partials_on_the_tape_match_restarted_propagations(simulations):
    simulation = simulations
    sc, tape = simulation.scenario, simulation.tape
    names = list(tape.parameters.name)
    worst = 0.0
    for k, t_k, t_j, x_j in _records(simulation):
        for burn in sc.manoeuvres:
            params = burn.parameters()
            u = tape.records.U[k][:, [names.index(n) for n, _, _ in params]]
            if t_j > burn.t_end_s or t_k <= burn.t_start_s or (
                    t_j == burn.t_end_s and burn.kind == "finite"):  # before x(t_j), or after
                assert np.all(u == 0), (k, burn.name)
                continue
            for i, (_, unit, sigma) in enumerate(params):
                def flown(s, i=i, burn=burn, t_j=t_j, t_k=t_k, x_j=x_j):
                    e = np.zeros(6)
                    e[i] = s
                    return _flown(sc, x_j, t_j, t_k, {burn.name: e})
                fd = _richardson(flown, sigma)
                same_unit = [c for c, p in enumerate(params) if p[1] == unit]
                err = np.max(np.abs(fd - u[:, i])) / np.max(np.abs(u[:, same_unit]))
                worst = max(worst, err)
    assert worst < FD_TOL, worst


def test_the_transition_through_the_burns_matches_central_differences(simulations):
    """Φ(t_k, t_j) across the VNB and RIC burns (their axes move with x: ∂Δv/∂x) and across
    the RIC thrust (∂a/∂r, ∂a/∂v), against differences of the reference flown from
    x(t_j) ± h."""
    simulation = simulations
    sc, tape = simulation.scenario, simulation.tape
    worst = 0.0
    for k, t_k, t_j, x_j in _records(simulation):
        phi = tape.records.U[k][:, :6]
        for i in range(6):
            def flown(s, i=i, t_j=t_j, t_k=t_k, x_j=x_j):
                e = np.zeros(6)
                e[i] = s
                return _flown(sc, x_j + e, t_j, t_k, {})
            fd = _richardson(flown, 1.0 if i < 3 else 1e-3)
            worst = max(worst, np.max(np.abs(fd - phi[:, i])) / np.max(np.abs(phi[:, i])))
    assert worst < PHI_TOL, worst


def test_miss_partials_of_the_execution_errors_match_central_differences(simulations):
    simulation = simulations
    sc, tape = simulation.scenario, simulation.tape
    names = list(tape.parameters.name)
    gm = float(tape.parameters.nominal[names.index("GM_km3_s2")])
    for burn in sc.manoeuvres:
        params = burn.parameters()
        b = tape.miss.B[:, [names.index(n) for n, _, _ in params]]
        for i, (_, unit, sigma) in enumerate(params):
            def miss(s, i=i, burn=burn):
                e = np.zeros(6)
                e[i] = s
                return equinoctial_elements(_flown(sc, sc.x0, 0.0, tape.miss.t_s,
                                                   {burn.name: e}), gm)
            same_unit = [c for c, p in enumerate(params) if p[1] == unit]
            err = np.max(np.abs(_richardson(miss, sigma) - b[:, i]) / np.max(
                np.abs(b[:, same_unit]), axis=1))
            assert err < MISS_TOL, (burn.name, i, err)


def _manoeuvre(i: int = 0, **changes) -> list[dict]:
    tables = [dict(m) for m in MANOEUVRES]
    tables[i].update(changes)
    return [{k: v for k, v in t.items() if v is not None} for t in tables]


BAD = [
    (_manoeuvre(0, time=20000.0), "manoeuvre[0].time: expected a time in the arc, [0, 10800) s "
     "(the injection to the last T13 time) (got 20000.0)"),
    (_manoeuvre(1, duration_s=6000.0), "manoeuvre[1].duration_s: expected a burn that ends in "
     "the arc, by the last T13 time 10800 s (at most 5800 s from its start 5000 s) (got "
     "6000.0)"),
    (_manoeuvre(1, start=-10.0), "manoeuvre[1].start: expected an ignition at or after the "
     "injection (>= 0 s) (got -10.0)"),
    ([*MANOEUVRES, {**MANOEUVRES[1], "name": "LATE", "start": 5500.0}],
     "manoeuvre[2].start: expected a burn that does not overlap manoeuvre[1] (BURN, 5000 to "
     "5600 s) (got 5500.0)"),
    ([*MANOEUVRES, {**MANOEUVRES[0], "name": "INSIDE", "time": 5100.0}],
     "manoeuvre[2].time: expected a burn that does not overlap manoeuvre[1] (BURN, 5000 to "
     "5600 s) (got 5100.0)"),
    (_manoeuvre(1, thrust_N=0.0), "manoeuvre[1].thrust_N: expected a finite number > 0 (got "
     "0.0)"),
    (_manoeuvre(1, mass_flow_kg_s=-0.01), "manoeuvre[1].mass_flow_kg_s: expected a finite "
     "number > 0 (got -0.01)"),
    (_manoeuvre(1, mass_flow_kg_s=1.0), "manoeuvre[1].mass_flow_kg_s: expected a mass flow "
     "that leaves mass at cut-off (below mass_kg / duration_s = 0.833333 kg/s) (got 1.0)"),
    (_manoeuvre(0, axes="lvlh"), "manoeuvre[0].axes: expected one of 'inertial', 'ric' or "
     "'vnb' (got 'lvlh')"),
    (_manoeuvre(0, sigma_magnitude_proportional=1.5), "manoeuvre[0].sigma_magnitude_"
     "proportional: expected a finite number < 1 (got 1.5)"),
    (_manoeuvre(1, sigma_pointing_proportional_mrad=-1.0), "manoeuvre[1].sigma_pointing_"
     "proportional_mrad: expected a finite number >= 0 (got -1.0)"),
    (_manoeuvre(0, sigma_pointing_fixed_mm_s=2e6), "manoeuvre[0].sigma_pointing_fixed_mm_s: "
     "expected a finite number <= 1e+06 (got 2000000.0)"),
    (_manoeuvre(0, dv_m_s=[0.0, 0.0, 0.0]), "manoeuvre[0].dv_m_s: expected a non-zero velocity "
     "change (got [0.0, 0.0, 0.0])"),
    (_manoeuvre(0, thrust_N=10.0), "manoeuvre[0].thrust_N: expected no thrust_N for a burn of "
     "kind \"impulsive\" (its keys: time, dv_m_s, dv_km_s) (got 10.0)"),
    (_manoeuvre(1, name="TCM1"), "manoeuvre[1].name: expected a name of its own (names its "
     "parameters) (got 'TCM1')"),
]


@pytest.mark.parametrize(("tables", "message"), BAD)
def test_bad_manoeuvres_are_input_errors_naming_the_field(tables, message):
    with pytest.raises(InputError) as info:
        leo_scenario(manoeuvre=tables, times=TIMES)
    assert str(info.value) == f"test_scenario.toml: {message}"


def test_a_thrust_parameter_is_no_model_parameter_of_the_file():
    with pytest.raises(InputError, match=r"parameters.dynamic\[2\]: expected a model parameter "
                       r"\(a burn's thrust is set by its \[\[manoeuvre\]\] table\)"):
        leo_scenario(parameters={"dynamic": ["GM_km3_s2", "J2", "thr_ric_1"]})


def test_rkn12_takes_a_thrust_in_inertial_axes_only():
    model = {"gravity": "J2", "var_gravity": "J2", "method": "rkn12"}
    tables = _manoeuvre(1, axes="inertial")
    assert leo_scenario(manoeuvre=tables, model=model).manoeuvres[1].axes == "inertial"
    with pytest.raises(InputError) as info:
        leo_scenario(manoeuvre=MANOEUVRES, model=model)
    assert str(info.value) == (
        "test_scenario.toml: manoeuvre[1].axes: expected \"inertial\" with model.method = "
        "\"rkn12\" (a thrust in RIC or VNB axes depends on the velocity; rkn12 integrates "
        "r'' = a(t, r) only) (got 'ric')")


def test_the_command_says_it_in_one_line_and_exits_2(tmp_path: Path):
    path = tmp_path / "burns.toml"
    path.write_text(tomli_w.dumps(leo_document(manoeuvre=_manoeuvre(1, thrust_N=-20.0))))
    out = tmp_path / "burns.t13.h5"
    res = runner.invoke(app, ["simulate", str(path), "-o", str(out)])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [f"error: {path}: manoeuvre[1].thrust_N: expected a "
                                       "finite number > 0 (got -20.0)"]
    assert not out.exists()


def test_the_tape_keeps_the_burns_and_refuses_a_mismatch(simulation, tmp_path: Path):
    tape = simulation.tape
    path = write_t13(tmp_path / "b.t13.h5", tape)
    back = read_t13(path)
    assert back.manoeuvres == tape.manoeuvres == simulation.scenario.manoeuvres
    assert summary(back)["manoeuvres"][1] == {
        "name": "BURN", "kind": "finite", "axes": "ric", "t_start_s": 5000.0,
        "t_end_s": 5600.0, "execution_errors": 6}
    with pytest.raises(TapeError, match="parameters/kind: expected the 6 execution errors"):
        validate(replace(tape, manoeuvres=tape.manoeuvres[:1]))
    with h5py.File(path, "r+") as f:
        sigma = f["manoeuvres/sigma"][...]
        sigma[0, 2] = 0.5  # a pointing σ beyond Gates' small angles
        del f["manoeuvres/sigma"]
        f.create_dataset("manoeuvres/sigma", data=sigma, fletcher32=True)
        f["manoeuvres/sigma"].attrs["units"] = "1, km/s, rad, km/s"
    with pytest.raises(TapeError, match="manoeuvres/sigma: expected a finite number >= 0 and "
                       "<= 0.2 rad"):
        read_t13(path)


def test_without_burns_nothing_changes(tmp_path: Path):
    """A scenario without [[manoeuvre]] gives the tape it gave before: no manoeuvres/ group,
    no parameter of kind execution, the same partials."""
    tape = simulate(leo_scenario(times=TIMES)).tape
    with h5py.File(write_t13(tmp_path / "p.t13.h5", tape), "r") as f:
        assert "manoeuvres" not in f
    assert "execution" not in tape.parameters.kind and tape.manoeuvres == ()


def test_an_oem_flies_a_finite_burn_in_a_segment_of_its_own():
    """At ignition and cut-off the acceleration jumps: the OEM's segments end there (the same
    state on both sides), so the states need no halving about them, the interpolation holds
    (1 mm, 1 µm/s), and they are the simulation's trajectory."""
    finite = leo_scenario(manoeuvre=MANOEUVRES[1:], times=TIMES)
    oem = oem_trajectory(finite, 10800.0)
    assert oem.error_km <= INTERPOLATION_TOL_KM and oem.error_km_s <= INTERPOLATION_TOL_KM_S
    assert oem.min_step_s == oem.max_step_s == 20.0
    assert [(oem.t_s[s][0], oem.t_s[s][-1]) for s in oem.spans] == [
        (0.0, 5000.0), (5000.0, 5600.0), (5600.0, 10800.0)]
    for end, start in zip(oem.spans, oem.spans[1:], strict=False):
        np.testing.assert_array_equal(oem.states[end][-1], oem.states[start][0])
    sim = simulate(finite)
    t, once = np.unique(oem.t_s, return_index=True)  # a cut's state (the same twice) once
    at = np.isin(sim.t_s, t)
    np.testing.assert_allclose(oem.states[once][np.isin(t, sim.t_s[at])], sim.states[at],
                               rtol=0, atol=1e-9)


#: OEM states are printed to 1e-9 km and 1e-12 km/s: rounding of half of that.
PRINTED_KM, PRINTED_KM_S = 0.5e-9, 0.5e-12
#: SPICE's state at a burn's epoch is the later segment's: within what the ET's rounding and
#: the TDB rate move a velocity (3.3e-10 of 7.6 km/s, and 6e-8 s of 8e-3 km/s²) of the state
#: after the burn, 2.3 m/s from the one before.
ET_RATE_km_s = 1e-8


@pytest.fixture(scope="module")
def segmented(simulation, tmp_path_factory):
    """The OEM (as text, read by the ``oem`` package) and SPK of the scenario with the
    impulsive TCM1 at 2000 s and the finite BURN."""
    d = tmp_path_factory.mktemp("segmented")
    sc = simulation.scenario
    traj = oem_trajectory(sc, 10800.0)
    text = format_oem(sc.epoch, traj.t_s, traj.states, object_name="SC", object_id="SC",
                      ref_frame=traj.ref_frame, interpolation=INTERPOLATION,
                      interpolation_degree=INTERPOLATION_DEGREE, meta_comments=traj.comments,
                      segment=traj.segment, segment_comments=segment_comments(traj, sc))
    (d / "s.oem").write_text(text)
    write_trajectory_spk(d / "s.bsp", sc, traj, -5)
    return traj, OrbitEphemerisMessage.open(d / "s.oem"), d / "s.bsp"


def test_an_impulsive_burn_ends_a_segment_and_starts_the_next(simulation, segmented):
    """The OEM of TCM1 (2.3 m/s in VNB axes at 2000 s) and BURN: segments meeting at 2000 s,
    the first ending with the state before the burn (the simulation's), the second starting
    with it plus Δv in the VNB axes of this test's own NumPy; each interpolates within its
    tolerances at every mid-point."""
    traj, _, _ = segmented
    first, second = traj.spans[:2]
    assert [(traj.t_s[s][0], traj.t_s[s][-1]) for s in traj.spans] == [
        (0.0, 2000.0), (2000.0, 5000.0), (5000.0, 5600.0), (5600.0, 10800.0)]
    assert traj.error_km <= INTERPOLATION_TOL_KM and traj.error_km_s <= INTERPOLATION_TOL_KM_S
    before = simulation.states[np.searchsorted(simulation.t_s, 2000.0)]
    np.testing.assert_allclose(traj.states[first][-1], before, rtol=0, atol=1e-12)
    burn = simulation.scenario.manoeuvres[0]
    jump = axes(before[:3], before[3:], "vnb") @ np.array(burn.dv_km_s)
    np.testing.assert_allclose(traj.states[second][0], before + np.r_[0, 0, 0, jump], rtol=0,
                               atol=1e-15)
    last = np.r_[np.diff(traj.segment) > 0, True]  # the state before each cut, and the end
    at = last | ~np.isin(traj.t_s, traj.t_s[last])
    at &= np.isin(traj.t_s, simulation.t_s)
    np.testing.assert_allclose(traj.states[at], simulation.states[np.isin(
        simulation.t_s, traj.t_s[at])], rtol=0, atol=1e-9)


def test_the_oem_package_reads_a_segment_per_arc(simulation, segmented):
    """Read by the ``oem`` package: a segment per arc, each interpolated by it (Lagrange,
    degree 7, within its own states) at the simulation's times within the OEM's tolerances."""
    _, message, _ = segmented
    epoch = Time("2026-01-01T00:00:00", scale="utc")
    for segment, (a, b) in zip(message.segments, [(0.0, 2000.0), (2000.0, 5000.0),
                                                  (5000.0, 5600.0), (5600.0, 10800.0)],
                               strict=True):
        assert abs((segment.metadata["START_TIME"] - epoch).sec - a) < 1e-6
        assert abs((segment.metadata["STOP_TIME"] - epoch).sec - b) < 1e-6
        take = (simulation.t_s > a) & (simulation.t_s < b)
        for t, x in zip(simulation.t_s[take][::5], simulation.states[take][::5], strict=True):
            got = segment(epoch + TimeDelta(t, format="sec"))
            np.testing.assert_allclose(got.position, x[:3], rtol=0,
                                       atol=INTERPOLATION_TOL_KM + PRINTED_KM)
            np.testing.assert_allclose(got.velocity, x[3:], rtol=0,
                                       atol=INTERPOLATION_TOL_KM_S + PRINTED_KM_S)


def test_the_spk_holds_a_segment_per_arc_and_gives_the_later_at_the_burn(segmented):
    """The SPK has a type 13 segment per arc, consecutive ones meeting at an ET; SPICE gives
    the state after TCM1 at its ET."""
    traj, _, path = segmented
    first, second = traj.spans[:2]
    handle = spiceypy.dafopr(str(path))
    try:
        spiceypy.dafbfs(handle)
        spans = []
        while spiceypy.daffna():
            et, ints = spiceypy.dafus(spiceypy.dafgs(), 2, 6)
            assert tuple(ints[:4]) == (-5, 399, 1, 13)  # body, centre, J2000, type 13
            spans.append(tuple(et))
    finally:
        spiceypy.dafcls(handle)
    assert len(spans) == 4
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:], strict=False))
    assert abs(spans[0][1] - spans[0][0] - 2000.0) < 1e-6
    spiceypy.furnsh(str(path))
    try:
        state, _ = spiceypy.spkezr("-5", spans[1][0], "J2000", "NONE", "399")
    finally:
        spiceypy.unload(str(path))
    after, before = traj.states[second][0], traj.states[first][-1]
    assert np.abs(np.array(state[3:]) - after[3:]).max() < ET_RATE_km_s
    assert np.abs(np.array(state[3:]) - before[3:]).max() > 1e3 * ET_RATE_km_s
