"""The troposphere and ionosphere in TAPP I: the [media] table, the stations' zenith parameters
in q, their rows on the tape, and TAPP III considering a zenith wet delay error.

The geometry is the 3-hour LEO arc of :func:`helpers.leo_document` (three equatorial stations).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.measurements import MeasurementModel
from tapp.measurements.media import standard_atmosphere
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import _measurement_model, simulate
from tests.tapp.processor.helpers import SIGMA, SIGMA_STATION, run
from tests.tapp.tracking.helpers import SOURCE, geo_document, leo_document

#: The real world's zenith wet delay error TAPP III considers, km (5 cm).
WET_SIGMA_km = 5e-5
MEDIA = {"troposphere": True, "ionosphere": True, "zenith_tec_tecu": 20.0}
ZENITH = ("zenith_dry_km", "zenith_wet_km", "zenith_tec_tecu")


def _document(**changes) -> dict:
    doc = leo_document(media=dict(MEDIA), **changes)
    doc["parameters"]["media"] = ["troposphere", "ionosphere"]
    doc["tracking"]["station"]["QUITO"] = {"pressure_hpa": 650.0, "temperature_k": 285.0,
                                           "relative_humidity": 0.6, "zenith_tec_tecu": 35.0}
    return doc


@pytest.fixture(scope="module")
def simulation():
    return simulate(parse_scenario(_document(), SOURCE), raw=True)


def test_zenith_parameters_are_station_parameters_on_the_tape(simulation, tmp_path):
    tape = simulation.tape
    names = tape.parameters.name
    for number, station in enumerate(("QUITO", "KOUROU", "MALINDI"), start=1):
        at = [names.index(f"{station}.{z}") for z in ZENITH]
        assert [tape.parameters.kind[i] for i in at] == ["troposphere", "troposphere",
                                                         "ionosphere"]
        assert [tape.parameters.unit[i] for i in at] == ["km", "km", "TECU"]
        assert np.all(tape.parameters.station[at] == number)
        # after the station's location and biases
        assert at[0] == names.index(f"{station}.range_rate_bias_km_s") + 1
    media = {ts.station.name: ts.media for ts in simulation.scenario.stations}
    nominal = dict(zip(names, tape.parameters.nominal, strict=True))
    assert nominal["QUITO.zenith_tec_tecu"] == 35.0 and nominal["KOUROU.zenith_tec_tecu"] == 20.0
    # Quito's weather (650 hPa at 3.55 km: 1.48 m dry); Kourou's standard atmosphere at 15 m.
    assert nominal["QUITO.zenith_dry_km"] == pytest.approx(1.48e-3, abs=0.01e-3)
    assert nominal["KOUROU.zenith_dry_km"] == media["KOUROU"].zenith_dry_km
    assert standard_atmosphere(0.015)[0] == pytest.approx(1011.4, abs=0.1)
    assert nominal["KOUROU.zenith_dry_km"] == pytest.approx(2.31e-3, abs=0.01e-3)
    # The tape with the new kinds writes and reads back.
    back = read_t13(write_t13(tmp_path / "media.t13.h5", tape))
    assert back.parameters.kind == tape.parameters.kind
    np.testing.assert_array_equal(back.parameters.station, tape.parameters.station)


def test_rows_are_the_media_partials_and_values_carry_the_delays(simulation):
    tape, scenario = simulation.tape, simulation.scenario
    raw = tape.raw
    names = tape.parameters.name
    for ts in scenario.stations:
        rows = raw.station == ts.number
        t = np.unique(raw.t_s[rows])
        x = simulation.states[np.searchsorted(simulation.t_s, t)]
        with_media = MeasurementModel(ts.station, scenario.orientation, ts.kinds,
                                      media=ts.media)
        bare = MeasurementModel(ts.station, scenario.orientation, ts.kinds)
        cols = [names.index(f"{ts.station.name}.{z}") for z in ZENITH]
        a = raw.A[rows][:, cols].reshape(t.size, len(ts.kinds), 3)
        np.testing.assert_array_equal(a, with_media.media_partials(t, x))
        values = raw.value[rows].reshape(t.size, len(ts.kinds))
        # (with - without) of ranges of 1e3 km: rounding 1e-13 km (measured 6e-14)
        np.testing.assert_allclose(values - bare.compute(t, x),
                                   with_media.media_corrections(t, x), rtol=0, atol=1e-12)
        # range delays of metres above 5 deg (measured 2.6 to 23 m; X band, 20-35 TECU)
        delay_m = 1e3 * (values - bare.compute(t, x))[:, 0]
        assert 1.0 < delay_m.min() and delay_m.max() < 40.0


def test_tapp3_considers_a_zenith_wet_delay_error(simulation):
    # The fit holds the zenith parameters fixed (σ = 0); the real world has a 5 cm zenith wet
    # error at each station: the budget shows each as a source, adding to the real variance.
    tape = simulation.tape
    fit, real = {}, {}
    for name in tape.parameters.name:
        key = name.split(".", 1)[1] if "." in name else name
        fit[name] = 0.0 if key in ZENITH else SIGMA.get(key, SIGMA_STATION.get(key))
        real[name] = (WET_SIGMA_km if key == "zenith_wet_km" else fit[name])
    doc = {"fit": {"apriori": {"sigma": fit}}, "real": {"apriori": {"sigma": real}},
           "times": {"print": [3]}, "commands": {"print": ["cov-real o@current"]}}
    ent = run(tape, doc).blocks[-1].entities[0]
    budget = ent.budget
    held = budget.total > 0  # the certain parameters' rows are zero
    closure = np.max(np.abs(budget.variances.sum(axis=0) - budget.total)[held]
                     / budget.total[held])
    assert closure < 1e-9, closure
    shares = []
    for station in ("QUITO", "KOUROU", "MALINDI"):
        source = f"{station}.zenith_wet_km (a priori)"
        assert source in budget.sources
        shares.append(np.max(budget.variances[budget.sources.index(source)][:3]
                             / budget.total[:3]))
    # 5 cm of wet delay, mapped up to 10x at 5 deg, against 15 m range noise: a visible
    # share of the position variance (measured 0.3 to 1.5 % per station)
    assert min(shares) > 1e-3, shares
    assert "QUITO.zenith_dry_km (a priori)" not in budget.sources  # certain: no source


@pytest.mark.parametrize("change, field, expected", [
    ({"media": {"troposphere": False, "ionosphere": True}}, "parameters.media[0]",
     "media.troposphere = true"),
    ({"media": None}, "parameters.media[0]", "media.troposphere = true"),
])
def test_media_parameters_need_the_media_on(change, field, expected):
    doc = _document()
    if change["media"] is None:
        doc.pop("media")
    else:
        doc["media"] = change["media"]
    with pytest.raises(InputError, match=re.escape(f"{field}: expected {expected}")):
        parse_scenario(doc, SOURCE)


@pytest.mark.parametrize("key, value", [("pressure_hpa", 65000.0), ("temperature_k", 12.0),
                                        ("relative_humidity", 60.0)])
def test_impossible_weather_names_the_station_key(key, value):
    doc = _document()
    doc["tracking"]["station"]["QUITO"][key] = value
    with pytest.raises(InputError, match=f"tracking.station.QUITO.{key}"):
        parse_scenario(doc, SOURCE)


def test_media_off_leaves_the_tape_as_before():
    plain = parse_scenario(leo_document(), SOURCE)
    assert all(ts.media is None for ts in plain.stations)
    assert not any(p.kind in ("troposphere", "ionosphere") for p in plain.parameters)


def test_three_way_doppler_rows_carry_both_stations_media():
    """On the GEO track EAST receives UNDER's uplink, ranging and counting Doppler: its
    rows' zenith columns are the down-leg's media partials, UNDER's zenith columns in them
    the up-leg's (each station's own weather and TEC), and the values carry both legs'."""
    doc = geo_document()
    doc["media"] = dict(MEDIA)
    doc["parameters"].update(media=["troposphere", "ionosphere"], station_biases=[])
    doc["tracking"].update(light_time="two_way", observables=["range", "doppler"])
    doc["tracking"]["station"]["EAST"] = {"uplink": "UNDER", "temperature_k": 300.0,
                                          "relative_humidity": 0.8, "zenith_tec_tecu": 45.0}
    doc["noise"]["fit"]["sigma_doppler_mm_s"] = 0.1
    sim = simulate(parse_scenario(doc, SOURCE), raw=True)
    scenario, raw, names = sim.scenario, sim.tape.raw, sim.tape.parameters.name
    under, east = scenario.stations
    assert east.uplink_media == under.media != east.media
    rows = raw.station == east.number
    t = np.unique(raw.t_s[rows])
    assert t.size > 10
    x = sim.states[np.searchsorted(sim.t_s, t)]
    model = _measurement_model(east, scenario, scenario.propagator())
    bare = dataclasses.replace(model, media=None, uplink_media=None)

    def block(station):
        cols = [names.index(f"{station}.{z}") for z in ZENITH]
        return raw.A[rows][:, cols].reshape(t.size, 2, 3)

    np.testing.assert_array_equal(block("EAST"), model.media_partials(t, x))
    np.testing.assert_array_equal(block("UNDER"), model.uplink_media_partials(t, x))
    assert np.abs(block("UNDER")[:, 0, :2]).min() > 0.4  # half the up-leg's mapping
    values = raw.value[rows].reshape(t.size, 2)
    # (with - without) of ranges of 3.8e4 km: rounding 4 eps x 3.8e4 = 3.4e-11 km, and of
    # Doppler, two such ranges differenced over the 60 s count, 1.1e-12 km/s
    np.testing.assert_allclose(values - bare.compute(t, x), model.media_corrections(t, x),
                               rtol=0, atol=3.4e-11)
    np.testing.assert_allclose((values - bare.compute(t, x))[:, 1],
                               model.media_corrections(t, x)[:, 1], rtol=0, atol=1.1e-12)


# ---------------------------------------------------------------------------------------------
# Zenith parameters per pass
# ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def per_pass():
    doc = _document()
    doc["parameters"]["media_per"] = "pass"
    return simulate(parse_scenario(doc, SOURCE), raw=True)


def _pass_names(tape, station: str) -> dict[int, list[str]]:
    """{pass number: its zenith parameter names} of a station on a per-pass tape."""
    out: dict[int, list[str]] = {}
    for name in tape.parameters.name:
        head, _, suffix = name.rpartition(".")
        if head.startswith(f"{station}.zenith_") and suffix.startswith("p"):
            out.setdefault(int(suffix[1:]), []).append(name)
    return out


def test_each_pass_has_its_zenith_parameters(per_pass, simulation):
    """One (dry, wet, TEC) set per pass of each station, numbered in its pass order, with
    the station's nominal values; the tape's pass table has as many passes."""
    tape = per_pass.tape
    nominal = dict(zip(tape.parameters.name, tape.parameters.nominal, strict=True))
    station_level = dict(zip(simulation.tape.parameters.name,
                             simulation.tape.parameters.nominal, strict=True))
    for number, station in enumerate(("QUITO", "KOUROU", "MALINDI"), start=1):
        by_pass = _pass_names(tape, station)
        n_passes = int(np.count_nonzero(tape.passes.station == number))
        assert sorted(by_pass) == list(range(1, n_passes + 1)) and n_passes >= 1
        for names in by_pass.values():
            assert [n.rsplit(".", 1)[0] for n in names] == [f"{station}.{z}" for z in ZENITH]
            assert [nominal[n] for n in names] == [station_level[f"{station}.{z}"]
                                                   for z in ZENITH]
        assert f"{station}.zenith_wet_km" not in nominal


def test_a_pass_column_is_the_stations_column_in_that_pass_only(per_pass, simulation):
    """Summed over a station's passes, the per-pass columns are the per-station column
    (exactly); each is zero outside its own pass's rows, and not zero in them."""
    raw_pass, raw_station = per_pass.tape.raw, simulation.tape.raw
    np.testing.assert_array_equal(raw_pass.t_s, raw_station.t_s)
    names_pass = list(per_pass.tape.parameters.name)
    names_station = list(simulation.tape.parameters.name)
    for station in ("QUITO", "KOUROU", "MALINDI"):
        by_pass = _pass_names(per_pass.tape, station)
        for j, z in enumerate(ZENITH):
            columns = [raw_pass.A[:, names_pass.index(by_pass[k][j])] for k in sorted(by_pass)]
            np.testing.assert_array_equal(sum(columns),
                                          raw_station.A[:, names_station.index(
                                              f"{station}.{z}")])
            nonzero = [c != 0.0 for c in columns]
            assert all(m.any() for m in nonzero)
            assert not np.any(np.sum(nonzero, axis=0) > 1)  # one pass per row


def test_fully_correlated_passes_are_the_stations_zenith_error_in_tapp3(per_pass, simulation):
    """Real world: 5 cm of zenith wet error per pass, the fit holding the zenith parameters
    at 0: with every two passes of a station correlated by ρ = 1 (one error over the arc) the
    printed real covariance is the per-station one's to the rounding of the consider terms;
    with independent passes it is not."""
    out = {"times": {"print": [3]}, "commands": {"print": ["cov-real p@current"]}}
    printed = {}
    for label, sim, correlated in (("station", simulation, False), ("one", per_pass, True),
                                   ("independent", per_pass, False)):
        tape = sim.tape
        fit, real = {}, {}
        for name in tape.parameters.name:
            key = name.split(".")[1] if "." in name else name
            fit[name] = 0.0 if key in ZENITH else SIGMA.get(key, SIGMA_STATION.get(key))
            real[name] = WET_SIGMA_km if key == "zenith_wet_km" else fit[name]
        doc = {"fit": {"apriori": {"sigma": fit}}, "real": {"apriori": {"sigma": real}}, **out}
        if correlated:
            doc["real"]["apriori"]["correlation"] = [
                [a, b, 1.0] for station in ("QUITO", "KOUROU", "MALINDI")
                for names in [[n for n in tape.parameters.name
                               if n.startswith(f"{station}.zenith_wet_km.p")]]
                for i, a in enumerate(names) for b in names[i + 1:]]
        printed[label] = run(tape, doc).blocks[-1].entities[0].matrix
    scale = np.sqrt(np.outer(np.diag(printed["station"]), np.diag(printed["station"])))
    assert np.max(np.abs(printed["one"] - printed["station"]) / scale) < 1e-9
    assert np.max(np.abs(printed["independent"] - printed["station"]) / scale) > 1e-6


@pytest.mark.parametrize("change, field", [
    ({"media": []}, "parameters.media_per"),
    ({"uplink": "KOUROU"}, "tracking.station.QUITO.uplink"),
])
def test_per_pass_zenith_parameters_that_would_not_exist_or_fit_are_refused(change, field):
    doc = _document()
    doc["parameters"]["media_per"] = "pass"
    if "media" in change:
        doc["parameters"]["media"] = change["media"]
    else:
        doc["tracking"]["light_time"] = "two_way"
        doc["tracking"]["station"]["QUITO"]["uplink"] = change["uplink"]
    with pytest.raises(InputError) as info:
        parse_scenario(doc, SOURCE)
    assert info.value.field == field
