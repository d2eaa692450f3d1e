"""TAPP I with relativistic light time, three-way tracking and count-based Doppler.

The 12 h GEO track of :func:`tests.tapp.tracking.helpers.geo_document` (both stations see the
spacecraft all the time): EAST receives the three-way signal UNDER transmits. The rows on the
tape are checked against the measurement model (tests/tapp/measurements/test_relativity.py
checks the model against an mpmath solution of Moyer's equations and central differences).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tapp.constants import C_LIGHT_km_s
from tapp.dynamics.ephemeris import position_km, utc_to_tdb_jd
from tapp.errors import InputError
from tapp.frames.time import parse_epoch
from tapp.measurements.bands import BANDS
from tapp.measurements.doppler import hz_per_km_s
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import _measurement_model, relativity_choice, simulate
from tests.tapp.tracking.helpers import SOURCE, geo_document, leo_document

SIGMA_HZ = 0.003


def _document(relativity="auto", **station) -> dict:
    doc = geo_document()
    doc["parameters"].update(station_location="cylindrical",
                             station_biases=["range", "doppler"])
    doc["tracking"].update(observables=["range", "doppler"], light_time="two_way",
                           count_time_s=60.0, relativity=relativity,
                           station={"EAST": {"uplink": "UNDER", **station}})
    doc["noise"] = {"fit": {"sigma_range_m": 10.0, "sigma_doppler_hz": SIGMA_HZ},
                    "real": {"bias_range_m": 5.0, "correlated_doppler_mm_s": 0.05,
                             "tau_doppler_s": 600.0}}
    return doc


@pytest.fixture(scope="module")
def run():
    scenario = parse_scenario(_document(relativity=True), SOURCE)
    return scenario, simulate(scenario, raw=True)


def test_three_way_rows_are_the_model_and_the_up_leg_goes_to_the_uplink(run):
    scenario, sim = run
    raw = sim.tape.raw
    names = list(sim.tape.parameters.name)
    east = scenario.stations[1]
    assert east.uplink is not None and east.uplink.name == "UNDER"
    relativity, _ = relativity_choice(scenario, sim.t_s, sim.states)
    model = _measurement_model(east, scenario, scenario.propagator(), relativity)
    rows = raw.station == east.number
    t = np.unique(raw.t_s[rows])
    x = sim.states[np.searchsorted(sim.t_s, t)]
    values = model.compute(t, x)
    own = model.station_partials(t, x, "cylindrical")
    up = model.uplink_station_partials(t, x, "cylindrical")
    for column, kind in enumerate(("range", "doppler")):
        k = rows & (raw.kind == raw.kinds.index(kind))
        assert np.allclose(raw.value[k], values[:, column], rtol=1e-14, atol=0.0)
        first_east = names.index("EAST.spin_radius_km")
        first_under = names.index("UNDER.spin_radius_km")
        assert np.allclose(raw.A[k, first_east:first_east + 3], own[:, column], rtol=1e-12)
        assert np.allclose(raw.A[k, first_under:first_under + 3], up[:, column], rtol=1e-12)
        assert np.all(np.abs(raw.A[k, first_under]) > 0.0)
        bias = raw.A[k, names.index("EAST.doppler_bias_km_s")]
        assert np.all(bias == (1.0 if kind == "doppler" else 0.0))


def test_a_nominal_doppler_bias_adds_to_the_doppler():
    scenario = parse_scenario(_document(doppler_bias_mm_s=0.5), SOURCE)
    east = scenario.stations[1]
    assert east.doppler_bias_km_s == pytest.approx(0.5e-6)
    model = _measurement_model(east, scenario, scenario.propagator(), None)
    t = np.array([3600.0])
    x = model.light_time.state_at(t)
    plain = replace(model, doppler_bias_km_s=0.0)
    assert (model.compute(t, x) - plain.compute(t, x))[0] == pytest.approx([0.0, 0.5e-6])


def test_doppler_sigma_in_hz_is_converted_at_the_band(run):
    """σ = 3 mHz at X-band: 3e-3 / (2 M₂ f_T / c) km/s = 0.0534 mm/s; W = 1/σ²."""
    _, sim = run
    raw = sim.tape.raw
    doppler = raw.kind == raw.kinds.index("doppler")
    sigma_km_s = SIGMA_HZ / hz_per_km_s(BANDS["X"])
    assert sigma_km_s * 1e6 == pytest.approx(0.0534, abs=1e-4)
    assert np.allclose(raw.weight[doppler], 1.0 / sigma_km_s**2, rtol=1e-12)
    assert np.allclose(raw.m_white_var[doppler], sigma_km_s**2, rtol=1e-12)


def test_count_doppler_is_the_mean_range_rate_over_the_count():
    """Newtonian, three-way: the count is the mean of ρ̇ over T_c = 60 s,
    ρ̇(t) + ρ⃛ T_c² / 24 + O(ρ⁽⁵⁾ T_c⁴ / 1920 ~ 1e-13 km/s), ρ⃛ by a central second
    difference of ρ̇ (60 s steps), to 1e-10 km/s. Under the gmst Earth orientation: under
    iau2006 the instantaneous ρ̇ takes the stations' velocities as a rigid rotation about
    the CIP (:func:`tapp.measurements.stations.station_state_eci`), which leaves out the
    precession-nutation rates: 1.4e-8 km/s here (2.9e-8 two-way), that the count has."""
    doc = _document(relativity=False)
    doc["earth_orientation"] = "gmst"
    scenario = parse_scenario(doc, SOURCE)
    model = _measurement_model(scenario.stations[1], scenario, scenario.propagator(), None)
    t = np.arange(600.0, 43200.0, 3000.0)
    rate = replace(model, kinds=("range_rate",))

    def rate_at(dt):
        return rate.compute(t + dt, model.light_time.state_at(t + dt))[:, 0]

    jerk = (rate_at(60.0) - 2.0 * rate_at(0.0) + rate_at(-60.0)) / 3600.0
    mean = rate_at(0.0) + jerk * 60.0**2 / 24.0
    doppler = replace(model, kinds=("doppler",)).compute(t, model.light_time.state_at(t))
    assert np.max(np.abs(doppler[:, 0] - mean)) < 1e-10


def test_relativistic_three_way_range_rate_holds_the_stations_clock_rates(run):
    """Relativistic three-way: the two stations' TDB - TT rates differ by up to
    |v_E| ω R_E / c² (their clocks read TT, the light times are solved in TDB), (c / 2) x that
    ~ 2e-5 km/s of range-rate. The instantaneous range-rate carries the term; the count,
    which differences two solutions, has it by construction: the two agree as the Newtonian
    ones do, to the rigid-rotation station velocity's 1.4e-8 km/s (see the test above), here
    within 5e-8 km/s, while the term alone is > 5e-6 km/s."""
    scenario, sim = run
    raw = sim.tape.raw
    east = scenario.stations[1]
    relativity, _ = relativity_choice(scenario, sim.t_s, sim.states)
    model = _measurement_model(east, scenario, scenario.propagator(), relativity)
    k = (raw.station == east.number) & (raw.kind == raw.kinds.index("doppler"))
    t = raw.t_s[k]
    rate = replace(model, kinds=("range_rate",))

    def rate_at(dt):
        return rate.compute(t + dt, model.light_time.state_at(t + dt))[:, 0]

    mean = rate_at(0.0) + (rate_at(60.0) - 2.0 * rate_at(0.0) + rate_at(-60.0)) / 24.0
    assert np.max(np.abs(raw.value[k] - mean)) < 5e-8
    clocks = 0.5 * C_LIGHT_km_s * (relativity.tdb_rate(t, east.uplink.r_ecef_km)
                                   - relativity.tdb_rate(t, east.station.r_ecef_km))
    assert np.max(np.abs(clocks)) > 5e-6


def test_the_tape_states_the_relativity_used(run):
    _, sim = run
    assert sim.tape.provenance["relativity"].startswith("on (relativity = true")
    auto = parse_scenario(_document(), SOURCE)
    relativity, note = relativity_choice(auto, sim.t_s, sim.states)
    assert relativity is None
    assert note.startswith("off (auto") and "42,16" in note  # the GEO radius, km
    far = sim.states.copy()
    far[:, :3] *= 10.0  # 421,640 km: beyond the Moon's distance
    relativity, note = relativity_choice(auto, sim.t_s, far)
    assert relativity is not None and note.startswith("on (auto")


@pytest.mark.parametrize(("change", "field", "expected"), [
    ({"tracking": {"count_time_s": 900.0}}, "tracking.count_time_s", "at most data_interval_s"),
    ({"tracking": {"light_time": "one_way"}}, "tracking.light_time", '"two_way"'),
    ({"station": {"uplink": "NOWHERE"}}, "tracking.station.EAST.uplink", "another"),
    ({"station": {"uplink": "EAST"}}, "tracking.station.EAST.uplink", "another"),
    ({"noise": {"sigma_doppler_mm_s": 0.1}}, "noise.fit.sigma_doppler_hz", "not both"),
])
def test_scenario_errors(change, field, expected):
    doc = _document(**change.get("station", {}))
    doc["tracking"].update(change.get("tracking", {}))
    doc["noise"]["fit"].update(change.get("noise", {}))
    with pytest.raises(InputError) as info:
        parse_scenario(doc, SOURCE)
    assert info.value.field == field
    assert expected in info.value.expected


def test_a_solar_conjunction_shows_the_suns_shapiro_delay_on_the_tape():
    """A spacecraft 2.4 AU away, 1.5 deg from the Sun (two-body, one day of QUITO's range):
    relativistic minus Newtonian two-way range is the Sun's Shapiro delay, (1 + γ) μ_S / c³
    ln((r_E + r_p + ρ) / (r_E + r_p - ρ)) per leg ~ 90 µs one way, 27 km, less the ~3 km of the
    barycentric/TDB terms (test_relativity.py measures both): between 15 and 40 km."""
    epoch = parse_epoch("2026-01-01T00:00:00")
    sun = position_km("sun", "earth", utc_to_tdb_jd(epoch.jd))[0]
    u = sun / np.linalg.norm(sun)
    side = np.cross(u, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    sep = np.radians(1.5)
    r = 2.4 * 149597870.7 * (np.cos(sep) * u + np.sin(sep) * side)
    doc = leo_document(
        injection={"r_km": list(r), "v_km_s": list(side)},
        model={"gravity": "J0", "var_gravity": "J0"},
        parameters={"dynamic": [], "station_location": "none", "station_biases": []},
        tracking={"stations": ["QUITO"], "observables": ["range"], "light_time": "two_way",
                  "data_interval_s": 1800.0, "station": {}},
        noise={"fit": {"sigma_range_m": 1.0}, "real": {}},
        times={"input": [86400.0], "input_step_s": None, "end": None},
        miss={"kind": "classical", "quantities": ["e"]})
    ranges = {}
    for relativity in (True, False):
        doc["tracking"]["relativity"] = relativity
        tape = simulate(parse_scenario(doc, SOURCE), raw=True).tape
        ranges[relativity] = tape.raw.value
        assert tape.provenance["relativity"].startswith("on" if relativity else "off")
    assert ranges[True].size > 10
    excess = ranges[True] - ranges[False]
    assert np.all((excess > 15.0) & (excess < 40.0))
