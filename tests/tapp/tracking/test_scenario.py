"""Scenario files: what they parse to, and one clear error naming file and field otherwise."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.tracking.scenario_build import parse_scenario, read_scenario
from tapp.tracking.simulate import simulate
from tests.tapp.tracking.helpers import SOURCE, leo_document, leo_scenario

SCENARIOS = EXAMPLES


def test_the_base_scenario_parses_to_named_parameters_with_units() -> None:
    sc = leo_scenario()
    names = [p.name for p in sc.parameters]
    assert names[:8] == ["x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s", "GM_km3_s2",
                         "J2"]
    assert names[8:13] == ["QUITO.spin_radius_km", "QUITO.lon_rad", "QUITO.z_km",
                           "QUITO.range_bias_km", "QUITO.range_rate_bias_km_s"]
    assert names[13:16] == ["KOUROU.x_km", "KOUROU.y_km", "KOUROU.z_km"]  # per-station ecef
    units = {p.name: p.unit for p in sc.parameters}
    assert units["GM_km3_s2"] == "km^3/s^2" and units["QUITO.lon_rad"] == "rad"
    assert units["QUITO.range_rate_bias_km_s"] == "km/s" and units["J2"] == "1"
    fit = sc.stations[0].fit
    assert [f.kind for f in fit] == ["range", "range_rate"]
    assert fit[0].sigma == pytest.approx(0.015) and fit[1].sigma == pytest.approx(20e-6)
    real = sc.stations[0].real[1]
    assert (real.sigma_white, real.sigma_correlated, real.tau_s) == pytest.approx(
        (15e-6, 10e-6, 90.0))
    np.testing.assert_array_equal(sc.times.t13_s, [0.0, 3600.0, 7200.0, 10800.0])


def test_times_as_utc_text_or_toml_dates_equal_seconds() -> None:
    sc = leo_scenario(times={"input": ["2026-01-01T01:00:00", dt.datetime(2026, 1, 1, 2)],
                             "input_step_s": None, "end": None,
                             "epochs": ["2026-01-01T00:30:00Z"]})
    assert sc.times.input_s == (3600.0, 7200.0)
    assert sc.times.epochs_s == (0.0, 1800.0)


def test_the_shipped_scenarios_parse() -> None:
    leo = read_scenario(SCENARIOS / "leo_equatorial.toml")
    assert leo.n_o == 38 and leo.var_model.gravity.name == "J2"
    assert leo.state_model.gravity.name == "5x5"
    deep = read_scenario(SCENARIOS / "deep_space.toml")
    assert deep.n_o == 24 + 45     # 15 two-day intervals x 3 stochastic accelerations
    assert deep.stochastic.n_intervals == 15 and deep.stochastic.frame == "ric"
    assert deep.dynamic == ("GM_km3_s2", "GM_moon_km3_s2", "Cr")
    assert deep.state_model.name == "J2+sun+moon+srp"
    assert deep.var_model.name == "J2+sun+moon+srp"
    drag = read_scenario(SCENARIOS / "leo_drag.toml")
    assert drag.n_o == 13 and drag.dynamic == ("GM_km3_s2", "J2", "Cd")
    assert drag.state_model.name == drag.var_model.name == "J2+drag(harris_priester)"
    assert [s.station.name for s in deep.stations] == ["GOLDSTONE", "CANBERRA", "MADRID"]
    assert deep.miss.quantities == ("b_dot_r_km", "b_dot_t_km", "flight_time_s")
    assert deep.schedule.end_s == pytest.approx(30 * 86400.0)


def _with(path: tuple[str, ...], value) -> dict:
    doc = leo_document()
    table = doc
    for key in path[:-1]:
        table = table.setdefault(key, {})
    if value is None:
        table.pop(path[-1], None)
    else:
        table[path[-1]] = value
    return doc


@pytest.mark.parametrize(("path", "value", "field"), [
    (("tracking", "stations"), ["QUITO", "NOWHERE"], "tracking.stations[1]"),
    (("tracking", "observables"), ["range", "phase"], "tracking.observables[1]"),
    (("tracking", "station", "KOUROU", "observables"), ["angle"],
     "tracking.station.KOUROU.observables[0]"),
    (("tracking", "station", "NOWHERE"), {}, "tracking.station.NOWHERE"),
    (("tracking", "light_time"), "three_way", "tracking.light_time"),
    (("tracking", "data_interval_s"), 0.0, "tracking.data_interval_s"),
    (("parameters", "dynamic"), ["GM_km3_s2", "J9"], "parameters.dynamic[1]"),
    (("parameters", "dynamic"), ["GM_mars_km3_s2"], "parameters.dynamic[0]"),
    (("parameters", "values"), {"GM_moon_km3_s2": 4902.8},
     "parameters.values.GM_moon_km3_s2"),
    (("parameters", "station_location"), "polar", "parameters.station_location"),
    (("parameters", "station_biases"), ["azimuth"], "parameters.station_biases[0]"),
    (("noise", "fit", "sigma_range_m"), 0.0, "noise.fit.sigma_range_m"),
    (("noise", "fit", "sigma_range_rate_mm_s"), -1.0, "noise.fit.sigma_range_rate_mm_s"),
    (("noise", "fit", "sigma_range_rate_mm_s"), None, "noise.fit.sigma_range_rate_mm_s"),
    (("noise", "real", "sigma_range_m"), -2.0, "noise.real.sigma_range_m"),
    (("noise", "real", "tau_range_rate_s"), None, "noise.real.tau_range_rate_s"),
    (("noise", "real", "bias_doppler_m"), 1.0, "noise.real.bias_doppler_m"),
    (("times", "epochs"), [7200.0, 3600.0], "times.epochs"),
    (("times", "epochs"), [0.0], "times.epochs"),
    (("times", "epochs"), [20000.0], "times.epochs"),
    (("times", "input_step_s"), -60.0, "times.input_step_s"),
    (("times", "end"), "2026-13-01", "times.end"),
    (("miss", "body"), "moon", "miss.body"),
    (("miss", "kind"), "delaunay", "miss.kind"),
    (("miss", "quantities"), ["a_km", "b_dot_t_km"], "miss.quantities[1]"),
    (("epoch",), "yesterday", "epoch"),
    (("injection", "r_km"), [1000.0, 0.0, 0.0], "injection"),
    (("injection", "v_km_s"), [1.0, "fast", 0.0], "injection.v_km_s[1]"),
    (("model", "gravity"), "J42", "model.gravity"),
    (("model", "var_third_bodies"), ["pluto"], "model.var_third_bodies[0]"),
    (("schedule",), {}, "schedule"),
])
def test_bad_input_names_file_and_field(path: tuple, value, field: str) -> None:
    with pytest.raises(InputError) as err:
        parse_scenario(_with(path, value), SOURCE)
    assert (err.value.source, err.value.field) == (SOURCE, field)
    assert str(err.value).startswith(f"{SOURCE}: {field}: expected")


def test_input_times_not_ascending() -> None:
    doc = leo_document(times={"input": [7200.0, 3600.0], "input_step_s": None, "end": None})
    with pytest.raises(InputError, match="times.input: expected times in strictly ascending"):
        parse_scenario(doc, SOURCE)


def test_bias_of_an_observable_the_station_does_not_measure() -> None:
    doc = leo_document(tracking={"station": {"QUITO": {"observables": ["range"]}}})
    with pytest.raises(InputError) as err:
        parse_scenario(doc, SOURCE)
    assert err.value.field == "parameters.station_biases" and err.value.got == "range_rate"


def test_a_schedule_that_yields_no_observation_is_an_input_error() -> None:
    sc = leo_scenario(tracking={"blackouts": [[0.0, 20000.0]]})
    with pytest.raises(InputError) as err:
        simulate(sc)
    assert (err.value.source, err.value.field) == (SOURCE, "tracking")
    assert "0 observations" in str(err.value)


def test_classical_miss_elements_of_a_circular_orbit_are_refused() -> None:
    # Two-body motion keeps e = 0 (with J2 the osculating e reaches 1e-3 and is accepted).
    sc = leo_scenario(miss={"kind": "classical"}, model={"gravity": "J0", "var_gravity": "J0"},
                      parameters={"dynamic": ["GM_km3_s2"]})
    with pytest.raises(InputError, match="miss.kind: expected equinoctial"):
        simulate(sc)


def test_files_that_cannot_be_read(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="none.toml: file: expected an existing"):
        read_scenario(tmp_path / "none.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("title = \n")
    with pytest.raises(InputError, match="broken.toml: TOML: expected valid TOML"):
        read_scenario(broken)


def test_default_real_world_is_white_noise_of_the_fit_sigma() -> None:
    sc = leo_scenario(noise={"real": None})
    for st in sc.stations:
        for fit, real in zip(st.fit, st.real, strict=True):
            assert (real.sigma_white, real.sigma_pass_bias, real.sigma_correlated) == (
                fit.sigma, 0.0, 0.0) and math.isinf(real.tau_s)


# --- issue 10, class 5: one declared schema; class 4: physically impossible scenarios -----------


def _message(doc: dict) -> str:
    with pytest.raises(InputError) as err:
        parse_scenario(doc, SOURCE)
    text = str(err.value)
    assert "\n" not in text and text.startswith(f"{SOURCE}: ")
    return text


def test_booleans_are_not_numbers_in_a_scenario() -> None:
    doc = _with(("stations", "QUITO", "lat_deg"), True)
    assert _message(doc) == f"{SOURCE}: stations.QUITO.lat_deg: expected a number (got True)"


def test_a_string_where_a_number_belongs_is_one_line_not_a_traceback() -> None:
    doc = _with(("tracking", "data_interval_s"), "30")
    assert _message(doc) == f"{SOURCE}: tracking.data_interval_s: expected a number (got '30')"
    doc = _with(("injection", "r_km"), "6550.524, 0, 0")
    assert "injection.r_km: expected a list" in _message(doc)


def test_a_misspelled_key_is_named_with_the_allowed_keys() -> None:
    doc = _with(("tracking", "data_intervl_s"), 30.0)
    text = _message(doc)
    assert text.startswith(f"{SOURCE}: tracking.data_intervl_s: expected no such key (allowed: "
                           "stations, observables, light_time, band, data_interval_s, ")
    assert _message(_with(("noise", "extra"), {})).startswith(
        f"{SOURCE}: noise.extra: expected no such key (allowed: fit, real)")


def test_an_orbit_below_the_surface_is_refused_unless_the_file_says_it_means_it() -> None:
    elements = {"r_km": None, "v_km_s": None, "a_km": 7000.0, "e": 0.2, "i_deg": 2.0,
                "raan_deg": 0.0, "argp_deg": 0.0, "M_deg": 180.0}
    text = _message(leo_document(injection=elements))
    assert text.startswith(f"{SOURCE}: injection: expected a perigee radius r_p >= 6378.1363 km")
    assert "injection.allow_subsurface = true" in text and text.endswith("(got 5600.0)")
    sc = leo_scenario(injection={**elements, "allow_subsurface": True})
    assert np.linalg.norm(sc.x0[:3]) == pytest.approx(8400.0)


def test_tolerances_outside_the_documented_range_are_refused() -> None:
    assert _message(leo_document(model={"rtol": 1.0})) == (
        f"{SOURCE}: model.rtol: expected an integrator tolerance in [1e-15, 1e-06] (looser than "
        "1e-6 drifts by km per day; tighter than 1e-15 is below double precision) (got 1.0)")
    assert "model.atol: expected an integrator tolerance" in _message(
        leo_document(model={"atol": 1e-18}))


def test_the_integration_method_is_chosen_in_the_model_table() -> None:
    assert leo_scenario().propagator().method == "dop853"
    assert leo_scenario(model={"method": "rkn12"}).propagator().method == "rkn12"
    assert _message(leo_document(model={"method": "rk4"})).startswith(
        f"{SOURCE}: model.method: expected one of")
    # the simulated trajectory does not depend on the method beyond the tolerance (1e-13)
    dop, rkn = (simulate(leo_scenario(model={"method": m})).states for m in ("dop853", "rkn12"))
    one_mm_km = 1e-6
    assert np.abs(dop[:, :3] - rkn[:, :3]).max() < one_mm_km


def test_rkn12_with_forces_that_depend_on_the_velocity_names_the_model_method() -> None:
    """Drag, and stochastic accelerations in RIC axes, depend on the velocity, which rkn12
    does not integrate: the file's model.method is at fault (issue 28: "propagator: method"
    once the simulation started, or no message at all before it)."""
    expected = (f"{SOURCE}: model.method: expected 'dop853' for a model with velocity-"
                "dependent forces ('rkn12' integrates r'' = a(t, r) only) (got 'rkn12')")
    assert _message(leo_document(model={"method": "rkn12", "area_to_mass_m2_kg": 0.01,
                                        "atmosphere": "exponential"})) == expected
    assert _message(leo_document(model={"method": "rkn12"}, stochastic={
        "frame": "ric", "interval_s": 3600.0, "sigma_m_s2": 1e-6, "tau_s": 7200.0})) == expected


def test_a_third_body_listed_twice_is_refused() -> None:
    text = _message(leo_document(model={"third_bodies": ["sun", "moon", "sun"]}))
    assert text == (f"{SOURCE}: model.third_bodies: expected each item once ('sun' is repeated) "
                    "(got ['sun', 'moon', 'sun'])")


def test_a_station_height_outside_the_ground_band_is_refused() -> None:
    text = _message(_with(("stations", "QUITO", "h_km"), 1e9))
    assert text == (f"{SOURCE}: stations.QUITO.h_km: expected a ground-station height in "
                    "[-0.5, 10] km above the WGS84 ellipsoid (got 1000000000.0)")


def test_a_non_positive_gm_is_refused() -> None:
    text = _message(leo_document(parameters={"values": {"GM_km3_s2": -398600.0}}))
    assert text == (f"{SOURCE}: parameters.values.GM_km3_s2: expected a finite GM > 0 km^3/s^2 "
                    "for GM_km3_s2 (got -398600.0)")


def test_the_noise_schema_declares_every_kind_in_its_edge_unit() -> None:
    from tapp.io.noise_file import FitTable, RealTable
    from tapp.measurements.noise import EDGE_UNITS
    from tapp.tracking.scenario import KINDS

    assert set(EDGE_UNITS) == set(KINDS)
    fit = {f"sigma_{k}_{EDGE_UNITS[k][0]}" for k in KINDS}
    real = fit | {f"{pre}_{k}_{EDGE_UNITS[k][0]}" for pre in ("bias", "correlated")
                  for k in KINDS} | {f"tau_{k}_s" for k in KINDS}
    hz = {f"{pre}_doppler_hz" for pre in ("sigma", "bias", "correlated")}  # Doppler in Hz too
    assert set(FitTable.model_fields) == fit | {"sigma_doppler_hz"}
    assert set(RealTable.model_fields) == real | hz
