"""TAPP I through the simulate path: normal matrices, re-epoching, visibility, partials."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s, WGS84_A_km
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tape.t13 import T13
from tapp.measurements import wrap_angle_rad
from tapp.measurements.stations import Station
from tapp.tracking.scenario import Scenario
from tapp.tracking.scenario_build import parse_scenario, read_scenario
from tapp.tracking.simulate import miss_partials, simulate
from tests.tapp.tracking.helpers import A_KM, leo_document, leo_scenario, scaled_close

# Sums of a few hundred products in another order: round-off, on the scale sqrt(J_aa J_bb).
SUM_ORDER = 1e-10
# Restarting the integration at an epoch time: local error ~1e-13, amplified over 2 h.
RESTART = 1e-8
# Central differences of the observables (steps below): truncation and round-off.
FD_EXACT = 2e-6
# First-order light-time partials neglect dτ/dx: relative O(|ρ̇|/c) ~ 3e-5 in LEO.
FD_LIGHT_TIME = 1e-4
# Miss partials vs central differences through the propagation (row-relative): the
# differences carry the integrator's noise and the 1e-6 steps of G.
MISS_FD = 1e-6
DEEP_SPACE = EXAMPLES / "deep_space.toml"


@pytest.fixture(scope="module")
def reepoched() -> T13:
    return simulate(leo_scenario(times={"epochs": [3600.0]}), raw=True).tape


def _groups(tape: T13):
    """(record indices, pair mask, raw-row mask) of each epoch j."""
    for j in np.unique(tape.records.j):
        ks = tape.records.k[tape.records.j == j]
        yield ks, np.isin(tape.pairs.k, ks), np.isin(tape.raw.record, ks)


def test_records_follow_the_seed_epoch_rule(reepoched: T13) -> None:
    rec = reepoched.records
    np.testing.assert_array_equal(rec.times_s, [0.0, 3600.0, 7200.0, 10800.0])
    np.testing.assert_array_equal(rec.is_epoch, [True, True, False, False])
    np.testing.assert_array_equal(rec.j, [0, 1, 1])  # j stays, or changes to k-1
    np.testing.assert_array_equal(rec.k, [1, 2, 3])
    assert reepoched.n_o == 6 + 2 + 5 * 3
    assert reepoched.raw.t_s.size == reepoched.pairs.n_obs.sum() > 100


def test_sum_of_dJ_equals_AtWA_of_the_raw_rows(reepoched: T13) -> None:
    raw = reepoched.raw
    for _, pairs, rows in _groups(reepoched):
        a, w = raw.A[rows], raw.weight[rows]
        scaled_close(reepoched.pairs.dJ[pairs].sum(axis=0), a.T @ (w[:, None] * a), SUM_ORDER)
    for k, s, n_obs in zip(reepoched.pairs.k, reepoched.pairs.station, reepoched.pairs.n_obs,
                           strict=True):
        assert np.count_nonzero((raw.record == k) & (raw.station == s)) == n_obs


def test_correlated_dJt_equals_the_brute_force_product_with_the_full_M(reepoched: T13) -> None:
    raw = reepoched.raw
    for _, pairs, rows in _groups(reepoched):
        t, seg = raw.t_s[rows], raw.segment[rows]
        same = seg[:, None] == seg[None, :]
        corr = np.sqrt(raw.m_corr_var[rows][:, None] * raw.m_corr_var[rows][None, :])
        tau = raw.m_tau_s[rows][:, None]
        m = same * (raw.m_bias_var[rows][:, None]
                    + corr * np.exp(-np.abs(t[:, None] - t[None, :]) / tau))
        m += np.diag(raw.m_white_var[rows])
        wa = raw.weight[rows][:, None] * raw.A[rows]
        scaled_close(reepoched.pairs.dJt[pairs].sum(axis=0), wa.T @ m @ wa, SUM_ORDER)
    # The raw rows carry the scenario's real world: range-rate σ_c = 10 mm/s, τ = 90 s.
    rr = raw.kind == raw.kinds.index("range_rate")
    np.testing.assert_allclose(raw.m_corr_var[rr], (10e-6) ** 2)
    np.testing.assert_allclose(raw.m_tau_s[rr], 90.0)
    assert np.unique(raw.segment).size > reepoched.passes.station.size  # split at records


def test_real_world_equal_to_fit_and_k_times_the_fit_sigma() -> None:
    same = simulate(leo_scenario(noise={"real": {}})).tape
    scaled_close(same.pairs.dJt, same.pairs.dJ, SUM_ORDER)
    tripled = simulate(leo_scenario(noise={"real": {"sigma_range_m": 45.0,
                                                    "sigma_range_rate_mm_s": 60.0}})).tape
    scaled_close(tripled.pairs.dJt, 9.0 * tripled.pairs.dJ, SUM_ORDER)


def test_reepoched_information_is_the_transformed_information_at_t0(reepoched: T13) -> None:
    at_t0 = simulate(leo_scenario(), raw=False).tape
    n_o, n_p = at_t0.n_o, at_t0.n_p
    # Ψ(t_1, t_0): p-rows from U of record 1 (referred to t_0), identity on q.
    psi = np.eye(n_o)
    psi[:n_p] = at_t0.records.U[0]
    later = reepoched.pairs.k >= 2
    np.testing.assert_array_equal(at_t0.pairs.k, reepoched.pairs.k)
    scaled_close(at_t0.pairs.dJ[later], psi.T @ reepoched.pairs.dJ[later] @ psi, RESTART)
    scaled_close(at_t0.pairs.dJt[later], psi.T @ reepoched.pairs.dJt[later] @ psi, RESTART)
    np.testing.assert_array_equal(at_t0.pairs.dJ[~later], reepoched.pairs.dJ[~later])
    u_again = reepoched.records.U[1:] @ psi
    np.testing.assert_allclose(u_again, at_t0.records.U[1:], rtol=RESTART,
                               atol=RESTART * np.abs(at_t0.records.U).max())


def test_visibility_of_a_hand_checked_geometry() -> None:
    """Circular equatorial orbit over an equatorial station, two-body motion.

    The station (radius R = WGS84 a) sees the spacecraft (radius a) above the mask ε while
    their central angle is below λ = arccos(R cos ε / a) - ε; the angle changes at n - ω_E.
    The pass is centred when n t = lon + θ0 + ω_E t, which fixes the longitude chosen (the
    gmst Earth orientation: the station rotates about the inertial z axis, in the orbit plane).
    """
    a_km, mask_deg, dt_s, t_centre_s = 7000.0, 10.0, 5.0, 1500.0
    n = math.sqrt(GM_EARTH_km3_s2 / a_km**3)
    rate = n - OMEGA_EARTH_rad_s
    half = math.acos(WGS84_A_km * math.cos(math.radians(mask_deg)) / a_km) \
        - math.radians(mask_deg)
    base = leo_scenario()
    lon_rad = rate * t_centre_s - base.epoch.gmst_rad()
    doc = leo_document(
        earth_orientation="gmst",
        injection={"r_km": [a_km, 0.0, 0.0], "v_km_s": [0.0, a_km * n, 0.0]},
        model={"gravity": "J0", "var_gravity": "J0"},
        parameters={"dynamic": [], "station_location": "none", "station_biases": []},
        stations={"EQ": {"lat_deg": 0.0, "lon_deg": math.degrees(lon_rad), "h_km": 0.0,
                         "elev_mask_deg": mask_deg}},
        tracking={"stations": ["EQ"], "data_interval_s": dt_s, "station": {}},
        times={"input": [3000.0], "input_step_s": None, "end": None})
    tape = simulate(parse_scenario(doc, "hand.toml")).tape
    rise, set_ = t_centre_s - half / rate, t_centre_s + half / rate
    assert tape.passes.station.size == 1
    assert rise < tape.passes.t_start_s[0] <= rise + dt_s
    assert set_ - dt_s <= tape.passes.t_end_s[0] < set_
    assert tape.passes.n_obs[0] == 2 * (1 + round((tape.passes.t_end_s[0]
                                                    - tape.passes.t_start_s[0]) / dt_s))


# --- partials through the simulate path -----------------------------------------------------

STEP = {"r": 1e-3, "v": 1e-6, "GM": 1e-2, "J2": 1e-8, "loc_km": 1e-2, "lon_rad": 1e-6,
        "range_bias_km": 1e-3, "range_rate_bias_km_s": 1e-6}


ANGLES = {"tracking": {"observables": ["range", "azimuth", "elevation"]},
          "parameters": {"station_biases": ["range"]},
          "noise": {"fit": {"sigma_range_m": 15.0, "sigma_azimuth_deg": 0.01,
                            "sigma_elevation_deg": 0.01}, "real": None}}


def _observed(scenario: Scenario) -> dict[tuple[int, int, float], float]:
    raw = simulate(scenario, raw=True).tape.raw
    return {(int(s), int(k), float(t)): float(v)
            for s, k, t, v in zip(raw.station, raw.kind, raw.t_s, raw.value, strict=True)}


def _with_station(scenario: Scenario, number: int, station: Station) -> Scenario:
    stations = tuple(dataclasses.replace(ts, station=station) if ts.number == number else ts
                     for ts in scenario.stations)
    return dataclasses.replace(scenario, stations=stations)


def _document(light_time: str, angles: bool) -> dict:
    doc = leo_document(**(ANGLES if angles else {}))
    doc["tracking"]["light_time"] = light_time
    return doc


def _perturbed(name: str, sign: float, light_time: str, angles: bool
               ) -> tuple[Scenario, float]:
    """The scenario with parameter ``name`` moved by sign * step, and the step."""
    doc = _document(light_time, angles)
    if name in ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s"):
        i = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s").index(name)
        key, h = ("r_km", STEP["r"]) if i < 3 else ("v_km_s", STEP["v"])
        doc["injection"][key][i % 3] += sign * h
        return parse_scenario(doc, "fd.toml"), h
    if name in ("GM_km3_s2", "J2"):
        short = name.removesuffix("_km3_s2")
        base = {p.name: p.nominal for p in parse_scenario(doc, "fd.toml").parameters}
        h = STEP[short]
        doc["parameters"]["values"] = {name: base[name] + sign * h}
        return parse_scenario(doc, "fd.toml"), h
    station, pname = name.split(".")
    if pname.endswith("bias_km") or pname.endswith("bias_km_s"):
        h = STEP[pname]
        edge = "range_bias_m" if pname == "range_bias_km" else "range_rate_bias_mm_s"
        factor = 1e3 if pname == "range_bias_km" else 1e6
        own = doc["tracking"]["station"].setdefault(station, {})
        own[edge] = sign * h * factor
        return parse_scenario(doc, "fd.toml"), h
    scenario = parse_scenario(doc, "fd.toml")
    ts = next(t for t in scenario.stations if t.station.name == station)
    st = ts.station
    if ts.location == "cylindrical":
        values = list(st.location("cylindrical"))
        i = ("spin_radius_km", "lon_rad", "z_km").index(pname)
        h = STEP["lon_rad"] if pname == "lon_rad" else STEP["loc_km"]
        values[i] += sign * h
        new = Station.from_cylindrical(st.name, *values, st.elev_mask_rad)
    else:
        values = st.location("ecef")
        i = ("x_km", "y_km", "z_km").index(pname)
        h = STEP["loc_km"]
        values[i] += sign * h
        new = Station.from_ecef(st.name, values, st.elev_mask_rad)
    return _with_station(scenario, ts.number, new), h


ALL = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s", "GM_km3_s2", "J2",
       "QUITO.spin_radius_km", "QUITO.lon_rad", "QUITO.z_km", "KOUROU.x_km", "KOUROU.y_km",
       "KOUROU.z_km", "QUITO.range_bias_km", "QUITO.range_rate_bias_km_s")


SOME = ("x_km", "vy_km_s", "GM_km3_s2", "QUITO.lon_rad", "KOUROU.z_km")


@pytest.mark.parametrize(("light_time", "angles", "names", "tol"), [
    ("none", False, ALL, FD_EXACT),
    # Angles: no location parameters. tapp.measurements holds a station's ENU axes fixed
    # under a location error (Station's notes), while a moved Station re-derives its axes:
    # the two differ by the axis rotation, δ/R_earth against δ/range (2-15 % here).
    ("none", True, ("x_km", "vy_km_s", "GM_km3_s2", "QUITO.range_bias_km"), FD_EXACT),
    ("two_way", False, SOME, FD_LIGHT_TIME),
])
def test_observation_partials_match_finite_differences(light_time: str, angles: bool,
                                                       names: tuple, tol: float) -> None:
    nominal = simulate(parse_scenario(_document(light_time, angles), "fd.toml"),
                       raw=True).tape
    raw = nominal.raw
    keys = [(int(s), int(k), float(t)) for s, k, t in zip(raw.station, raw.kind, raw.t_s,
                                                           strict=True)]
    columns = {n: i for i, n in enumerate(nominal.parameters.name)}
    worst = {}
    for name in names:
        plus_s, h = _perturbed(name, +1.0, light_time, angles)
        minus_s, _ = _perturbed(name, -1.0, light_time, angles)
        plus, minus = _observed(plus_s), _observed(minus_s)
        common = [i for i, key in enumerate(keys) if key in plus and key in minus]
        assert len(common) > 0.9 * len(keys)
        diff = np.array([plus[keys[i]] - minus[keys[i]] for i in common])
        azimuth = raw.kind[common] == raw.kinds.index("azimuth")
        diff[azimuth] = wrap_angle_rad(diff[azimuth])
        fd = diff / (2 * h)
        col = raw.A[common, columns[name]]
        for kind in np.unique(raw.kind[common]):
            sel = raw.kind[common] == kind
            scale = max(np.abs(col[sel]).max(), np.abs(fd[sel]).max())
            if scale == 0.0:
                continue
            worst[name, kind] = float(np.abs(fd[sel] - col[sel]).max() / scale)
    assert max(worst.values()) < tol, worst


# --- miss partials ------------------------------------------------------------------------


def _b_by_differences(scenario: Scenario, names: tuple[str, ...], steps: dict[str, float]
                      ) -> np.ndarray:
    cols = []
    for name in names:
        out = []
        for sign in (+1.0, -1.0):
            if name in ("vx_km_s", "vy_km_s", "vz_km_s", "x_km"):
                i = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s").index(name)
                x0 = np.array(scenario.x0)
                x0[i] += sign * steps[name]
                s = dataclasses.replace(scenario, x0=x0)
            else:
                nominal = {p.name: p.nominal for p in scenario.parameters}[name]
                s = dataclasses.replace(scenario, dynamic_values=(
                    *scenario.dynamic_values, (name, nominal + sign * steps[name])))
            out.append(miss_partials(s)[0])
        diff = out[0] - out[1]
        angles = np.array([u == "rad" for u in scenario.miss.units])
        diff[angles] = (diff[angles] + np.pi) % (2 * np.pi) - np.pi
        cols.append(diff / (2 * steps[name]))
    return np.stack(cols, axis=1)


def test_equinoctial_miss_partials_match_finite_differences() -> None:
    scenario = leo_scenario()
    nominal, big_b = miss_partials(scenario)
    np.testing.assert_allclose(nominal[0], A_KM, rtol=1e-3)
    names = ("x_km", "vx_km_s", "vy_km_s", "vz_km_s", "GM_km3_s2", "J2")
    # J2 moves the osculating a by ~0.6 km per unit: a step of 1e-5 keeps the difference
    # (6e-6 km) far above the integrator's noise (~1e-10 km); the response is linear in J2.
    steps = {"x_km": 1e-3, "vx_km_s": 1e-6, "vy_km_s": 1e-6, "vz_km_s": 1e-6,
             "GM_km3_s2": 1e-3, "J2": 1e-5}
    columns = [[p.name for p in scenario.parameters].index(n) for n in names]
    fd = _b_by_differences(scenario, names, steps)
    rel = np.abs(fd - big_b[:, columns]) / np.abs(fd).max(axis=1, keepdims=True)
    assert rel.max() < MISS_FD, rel


def test_bplane_miss_partials_of_the_deep_space_scenario() -> None:
    """The shipped scenario (SRP with the Earth's and the Moon's shadows in both models) hits
    the aim point, and its miss partials match central differences through the propagation:
    the state, GM and C_r columns (measured 8e-8 and 1.3e-7 at a C_r step of 0.05, where
    x is linear in C_r to 1e-7). Before the integration events located the shadow
    boundaries, the differenced trajectories agreed to 2e-4 only, and the C_r partials of a
    variational model without shadows were 1.6-11 % off."""
    scenario = read_scenario(DEEP_SPACE)
    nominal, big_b = miss_partials(scenario)
    # tapp search converged this injection to B·R = -2000 km, B·T = 5300 km (1 km tolerance).
    np.testing.assert_allclose(nominal[:2], [-2000.0, 5300.0], atol=1.0)
    assert nominal[2] == pytest.approx(scenario.miss.t_s, abs=1e-2)  # miss time at periapsis
    names = ("vx_km_s", "vy_km_s", "vz_km_s", "GM_km3_s2", "GM_moon_km3_s2", "Cr")
    steps = {"vx_km_s": 1e-7, "vy_km_s": 1e-7, "vz_km_s": 1e-7, "GM_km3_s2": 1e-3,
             "GM_moon_km3_s2": 1e-4, "Cr": 0.05}
    columns = [[p.name for p in scenario.parameters].index(n) for n in names]
    fd = _b_by_differences(scenario, names, steps)
    rel = np.abs(fd - big_b[:, columns]) / np.abs(fd).max(axis=1, keepdims=True)
    assert rel.max() < MISS_FD, rel


def test_classical_miss_partials_of_an_eccentric_orbit() -> None:
    scenario = leo_scenario(injection={"r_km": None, "v_km_s": None, "a_km": 8000.0, "e": 0.1,
                                       "i_deg": 30.0, "raan_deg": 40.0, "argp_deg": 50.0,
                                       "M_deg": 10.0},
                            miss={"kind": "classical"})
    nominal, big_b = miss_partials(scenario)
    assert nominal[1] == pytest.approx(0.1, abs=2e-3)  # e, moved a little by J2
    names = ("x_km", "vx_km_s", "vz_km_s", "GM_km3_s2")
    steps = {"x_km": 1e-3, "vx_km_s": 1e-6, "vz_km_s": 1e-6, "GM_km3_s2": 1e-3}
    columns = [[p.name for p in scenario.parameters].index(n) for n in names]
    fd = _b_by_differences(scenario, names, steps)
    rel = np.abs(fd - big_b[:, columns]) / np.abs(fd).max(axis=1, keepdims=True)
    assert rel.max() < MISS_FD, rel
