"""Tropospheric and ionospheric delays (tapp.measurements.media) and their place in the
measurement model: published values, derivatives and partials against central differences,
and the range-rate against the time derivative of the range delay. Orekit's side:
test_media_orekit.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.measurements import LightTime, MeasurementModel, Station
from tapp.measurements.bands import BANDS
from tapp.measurements.media import (
    MediaModel,
    check_meteorology,
    day_of_year,
    marini,
    niell_hydrostatic,
    niell_wet,
    single_layer,
    standard_atmosphere,
    vapour_pressure_hpa,
    zenith_hydrostatic_delay_m,
    zenith_wet_delay_m,
)
from tapp.measurements.stations import station_state_eci
from tests.tapp.measurements.helpers import central_differences

#: DSS-63 (Madrid): geodetic latitude, longitude deg, height km.
MADRID = Station.from_degrees("DSS63", 40.4313, -4.2480, 0.865, 5.0)
GMST0_rad = 0.3
KINDS = ("range", "range_rate", "elevation")


def _media(**kwargs) -> MediaModel:
    base = dict(zenith_tec_tecu=25.0, band="S")
    base.update(kwargs)
    return MediaModel.from_meteorology(MADRID.lat_rad, MADRID.h_km, 70.25, 930.0, 283.0, 0.7,
                                       **base)


def _passing(t_s: np.ndarray) -> np.ndarray:
    """Spacecraft states (N, 6) on a straight line (no force: states at any t are exact)
    that crosses Madrid's sky from 8 to 70 deg elevation and back over t in [-300, 300] s."""
    t = np.asarray(t_s, dtype=float)
    station = MADRID.state_eci(GMST0_rad, np.array([0.0]))[0]
    enu_to_eci = MADRID.enu_from_eci(
        MeasurementModel(MADRID, GMST0_rad).orientation.attitude(np.array([0.0])))[0].T
    r0 = station[:3] + enu_to_eci @ np.array([0.0, 0.0, 700.0])
    v = enu_to_eci @ np.array([6.5, 2.0, 0.3])
    return np.concatenate([r0 + t[:, None] * v, np.broadcast_to(v, t.shape + (3,))], axis=-1)


# ---------------------------------------------------------------------------------------------
# Zenith delays and meteorology: published values
# ---------------------------------------------------------------------------------------------


def test_zenith_hydrostatic_delay_at_sea_level_is_the_published_2_3_m():
    # Davis et al. (1985): 2.2768 mm/hPa at 45 deg and sea level: 2.3070 m at 1013.25 hPa
    # (Orekit's Saastamoinen variants differ from the Davis form, so this is the reference).
    assert zenith_hydrostatic_delay_m(1013.25, np.radians(45.0), 0.0) == pytest.approx(
        2.3070, abs=1e-4)
    # The gravity term: 0.27 % more at the equator than at 45 deg, 0.28 per mil per km up.
    assert (zenith_hydrostatic_delay_m(1013.25, 0.0, 0.0)
            / zenith_hydrostatic_delay_m(1013.25, np.radians(45.0), 0.0)) == pytest.approx(
        1.0 / (1.0 - 0.00266), rel=1e-12)


def test_saturation_pressure_matches_the_published_table():
    # WMO / Smithsonian tables: saturation vapour pressure over water 17.04 hPa at 15 C,
    # 6.11 hPa at 0 C, 42.43 hPa at 30 C.
    for t_c, e_s in ((15.0, 17.04), (0.0, 6.11), (30.0, 42.43)):
        assert vapour_pressure_hpa(273.15 + t_c, 1.0) == pytest.approx(e_s, abs=0.05)


def test_standard_atmosphere_follows_the_international_standard():
    # ISA (ICAO 1993): 1013.25 hPa, 288.15 K at sea level; 898.76 hPa, 281.65 K at 1 km.
    assert standard_atmosphere(0.0) == (1013.25, 288.15, 0.5)
    p, t, rh = standard_atmosphere(1.0)
    assert p == pytest.approx(898.76, abs=0.05)
    assert t == pytest.approx(281.65, abs=1e-9)


def test_wet_delay_of_a_humid_day_is_some_centimetres():
    # 20 C at 80 %: e = 18.7 hPa; Saastamoinen: 2.277e-3 (1255 / 293.15 + 0.05) 18.7 = 0.184 m
    e = vapour_pressure_hpa(293.15, 0.8)
    assert e == pytest.approx(0.8 * 23.39, abs=0.05)
    assert zenith_wet_delay_m(293.15, e) == pytest.approx(
        0.002277 * (1255.0 / 293.15 + 0.05) * e, rel=1e-15)


def test_impossible_meteorology_is_refused_by_key():
    with pytest.raises(InputError, match="pressure_hpa"):
        check_meteorology("s.toml", "tracking.station.X", 93000.0, 283.0, 0.5)  # Pa for hPa
    with pytest.raises(InputError, match="temperature_k"):
        check_meteorology("s.toml", "tracking.station.X", 930.0, 10.0, 0.5)  # C for K
    with pytest.raises(InputError, match="relative_humidity"):
        check_meteorology("s.toml", "tracking.station.X", 930.0, 283.0, 50.0)  # % for a fraction


def test_day_of_year_counts_from_one_at_new_year():
    assert day_of_year(Epoch.from_calendar(2026, 1, 1)) == 1.0
    assert day_of_year(Epoch.from_calendar(2026, 3, 10, 12)) == 69.5
    assert day_of_year(Epoch.from_calendar(2024, 12, 31, 18)) == 366.75


# ---------------------------------------------------------------------------------------------
# Mapping functions: limits and derivatives
# ---------------------------------------------------------------------------------------------


def test_mapping_functions_are_one_at_the_zenith_and_grow_towards_the_horizon():
    s = np.sin(np.radians([90.0, 30.0, 10.0, 5.0]))
    for m in (niell_hydrostatic(s, MADRID.lat_rad, 70.0, 0.0).m, niell_wet(s, 0.7).m,
              single_layer(s).m):
        assert m[0] == pytest.approx(1.0, abs=1e-14)
        assert np.all(np.diff(m) > 0)
    # Niell at 5 deg: about 10 (his fig. 2); at 30 deg, near 1 / sin E = 2.
    dry = niell_hydrostatic(s, MADRID.lat_rad, 70.0, 0.0).m
    assert 9.5 < dry[3] < 10.5
    assert dry[1] == pytest.approx(2.0, abs=0.01)
    # The thin shell at 350 km: 1 / sqrt(1 - (6371 cos 5 / 6721)^2) = 2.98 at 5 deg
    assert single_layer(s).m[3] == pytest.approx(
        1.0 / np.sqrt(1.0 - (6371.0 * np.cos(np.radians(5.0)) / 6721.0) ** 2), rel=1e-14)


@pytest.mark.parametrize("mapping", [
    lambda s: marini(s, 1.2e-3, 2.9e-3, 62.8e-3),
    lambda s: niell_hydrostatic(s, -0.6, 200.0, 2.0),
    lambda s: niell_wet(s, 0.3),
    lambda s: single_layer(s, 450.0),
], ids=["marini", "niell_hydrostatic", "niell_wet", "single_layer"])
def test_mapping_derivatives_match_central_differences(mapping):
    # Step 1e-5 in s: truncation h² m''' / 6 and rounding eps m / h are both < 1e-8 of m_s;
    # the relative tolerance 1e-7 is the brief's.
    s = np.sin(np.radians([5.0, 12.0, 40.0, 85.0]))
    h = 1e-5
    up, down, at = mapping(s + h), mapping(s - h), mapping(s)
    np.testing.assert_allclose(at.m_s, (up.m - down.m) / (2 * h), rtol=1e-7)
    np.testing.assert_allclose(at.m_ss, (up.m_s - down.m_s) / (2 * h), rtol=1e-7)
    e = np.arcsin(s)
    de = 1e-6
    np.testing.assert_allclose(
        at.per_elevation(s), (mapping(np.sin(e + de)).m - mapping(np.sin(e - de)).m) / (2 * de),
        rtol=1e-7)


# ---------------------------------------------------------------------------------------------
# In the measurement model
# ---------------------------------------------------------------------------------------------


def _models(light_time=None, media=None):
    media = _media() if media is None else media
    return (MeasurementModel(MADRID, GMST0_rad, KINDS, light_time, media=media),
            MeasurementModel(MADRID, GMST0_rad, KINDS, light_time))


def test_delays_have_the_size_and_signs_of_the_physics():
    t = np.array([-250.0, 0.0])
    x = _passing(t)
    with_media, _ = _models()
    media = with_media.media
    el = with_media.elevation_rad(t, x)
    corr = with_media.media_corrections(t, x)
    s = np.sin(el)
    dry = niell_hydrostatic(s, MADRID.lat_rad, media.day_of_year + t / 86400.0, MADRID.h_km).m
    iono = single_layer(s).m * 40.3e16 * 25.0 * 0.5 * (
        BANDS["S"].uplink_hz**-2 + BANDS["S"].downlink_hz**-2) * 1e-3
    expected = media.zenith_dry_km * dry + media.zenith_wet_km * niell_wet(s, MADRID.lat_rad).m
    np.testing.assert_allclose(corr[:, 0], expected + iono, rtol=1e-14)
    assert np.all(corr[:, 2] == 0.0)  # no refraction of the angles
    # Rising spacecraft: the delays shrink (troposphere's rate < 0) and the phase advance of
    # the ionosphere shrinks too (its rate > 0).
    tropo, ionos = (_models(media=_media(ionosphere=False))[0],
                    _models(media=_media(troposphere=False))[0])
    assert tropo.media_corrections(t, x)[0, 1] < 0 < ionos.media_corrections(t, x)[0, 1]
    assert ionos.media_corrections(t, x)[0, 0] > 0


@pytest.mark.parametrize("which", ["troposphere", "ionosphere"])
def test_range_rate_correction_is_the_time_derivative_of_the_range_delay(which):
    # Straight-line states are exact at every t; central differences in t with h = 0.02 s:
    # truncation h² d³δ/dt³ / 6 < 2e-8 of the rate (measured; 1e-5 at h = 0.5 s, falling as
    # h²). The ionosphere's sign flips (phase advance).
    other = "ionosphere" if which == "troposphere" else "troposphere"
    model, _ = _models(media=_media(**{other: False}))
    t = np.array([-250.0, -100.0, 40.0, 200.0])
    h = 0.02
    rate = model.media_corrections(t, _passing(t))[:, 1]
    diff = (model.media_corrections(t + h, _passing(t + h))[:, 0]
            - model.media_corrections(t - h, _passing(t - h))[:, 0]) / (2 * h)
    sign = 1.0 if which == "troposphere" else -1.0
    np.testing.assert_allclose(rate, sign * diff, rtol=1e-7)


def test_state_partials_of_the_media_match_central_differences():
    # The media's share of H (with - without) against central differences of the media's
    # share of h: steps 1e-2 km and 1e-5 km/s (truncation ~ (h/ρ)² = 2e-10 at ρ > 700 km,
    # 1e-6 with 1 km steps; the rate is linear in v), relative 1e-7 of each row's size.
    with_media, without = _models()
    t = np.array([-250.0, -60.0, 120.0])
    x = _passing(t)
    h_media = with_media.state_partials(t, x) - without.state_partials(t, x)
    numeric = central_differences(lambda y: with_media.media_corrections(t, y), x,
                       [1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5])
    scale = np.abs(numeric).max(axis=-1, keepdims=True)
    assert np.all(np.abs(h_media - numeric) <= 1e-7 * scale)
    assert np.all(scale[:, :2] > 0)


def test_state_partials_with_two_way_light_time_are_first_order():
    # With light time, each leg at its own geometry and carrier; the partials are those of
    # the first-order light-time model (observables.py: the neglected d tau/dx terms are
    # O(v/c) ~ 3e-5 relative).
    light = LightTime(two_way=True)
    with_media, without = _models(light)
    t = np.array([-200.0, 100.0])
    x = _passing(t)
    h_media = with_media.state_partials(t, x) - without.state_partials(t, x)
    numeric = central_differences(lambda y: with_media.media_corrections(t, y), x,
                       [1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5])
    scale = np.abs(numeric).max(axis=-1, keepdims=True)
    assert np.all(np.abs(h_media - numeric) <= 1e-4 * scale)


def test_station_partials_carry_the_media_as_minus_the_spacecraft_partials():
    with_media, without = _models()
    t = np.array([-150.0, 90.0])
    x = _passing(t)
    moved = (with_media.station_partials(t, x, "ecef")
             - without.station_partials(t, x, "ecef"))
    by_state = with_media.state_partials(t, x) - without.state_partials(t, x)
    expected = -by_state @ MADRID.state_partials(GMST0_rad, t, "ecef")
    # (with - without) of partials of size 1: rounding 1e-16 absolute, 1e-10 of the media's
    np.testing.assert_allclose(moved, expected, rtol=1e-9, atol=1e-15)
    assert np.abs(moved[:, :2]).min() > 1e-9


@pytest.mark.parametrize("light", [None, LightTime(two_way=False), LightTime(two_way=True)],
                         ids=["instantaneous", "one_way", "two_way"])
def test_zenith_partials_match_central_differences(light):
    # The observables are linear in the zenith parameters: differences are exact to rounding
    # (steps 1e-4 km, 1e-4 km, 1 TECU).
    with_media, _ = _models(light)
    t = np.array([-220.0, 30.0])
    x = _passing(t)
    base = with_media.media
    names = ("zenith_dry_km", "zenith_wet_km", "zenith_tec_tecu")
    steps = (1e-4, 1e-4, 1.0)
    cols = []
    for name, h in zip(names, steps, strict=True):
        def shifted(d, name=name):
            model = dataclasses.replace(with_media, media=dataclasses.replace(
                base, **{name: getattr(base, name) + d}))
            return model.media_corrections(t, x)
        cols.append((shifted(h) - shifted(-h)) / (2 * h))
    numeric = np.stack(cols, axis=-1)
    np.testing.assert_allclose(with_media.media_partials(t, x), numeric, rtol=1e-7,
                               atol=1e-7 * np.abs(numeric).max())
    assert np.all(with_media.media_partials(t, x)[:, 2] == 0.0)


def test_one_way_ionosphere_is_at_the_downlink_carrier_and_two_way_halves_both():
    t = np.array([0.0])
    x = _passing(t)
    iono = _media(troposphere=False)
    one = MeasurementModel(MADRID, GMST0_rad, ("range",), LightTime(two_way=False), media=iono)
    two = MeasurementModel(MADRID, GMST0_rad, ("range",), LightTime(two_way=True), media=iono)
    f_t, f_r = BANDS["S"].uplink_hz, BANDS["S"].downlink_hz
    ratio = two.media_corrections(t, x)[0, 0] / one.media_corrections(t, x)[0, 0]
    # The up-leg's elevation differs by Ė 2τ (~1e-7 rad here): ratio to 1e-6.
    assert ratio == pytest.approx(0.5 * (1.0 + (f_r / f_t) ** 2), rel=1e-6)


def test_media_partials_need_a_media_model():
    with pytest.raises(InputError, match="media"):
        MeasurementModel(MADRID, GMST0_rad, KINDS).media_partials(np.array([0.0]),
                                                                  _passing(np.array([0.0])))


# ---------------------------------------------------------------------------------------------
# Count-based Doppler and three-way links
# ---------------------------------------------------------------------------------------------

#: DSS-14 (Goldstone), the three-way uplink of Madrid's passes below.
GOLDSTONE = Station.from_degrees("DSS14", 35.4259, -116.8895, 1.002, 5.0)
#: The passing straight line, exact at any time: Doppler's count ends need no expansion.
EXACT = LightTime(two_way=True, state_at=_passing)
COUNT_s = 60.0


def _doppler(media=None, **kwargs) -> MeasurementModel:
    return MeasurementModel(MADRID, GMST0_rad, ("range", "range_rate", "doppler"), EXACT,
                            media=_media() if media is None else media,
                            count_time_s=COUNT_s, **kwargs)


def test_doppler_carries_the_phase_of_the_media_over_its_count():
    """Doppler's media share is (δφ(t + T_c/2) - δφ(t - T_c/2)) / T_c of the phase range, the
    troposphere delaying it and the ionosphere advancing it: built here from the ranging
    model's group delays of each effect alone (the ionosphere's sign flipped by hand), and
    the mean of the range-rate's share over the count (Gauss-Legendre, 8 nodes: exact far
    below the O(v/c) ~ 3e-5 by which a two-way leg's rate is taken at dt_leg/dt = 1)."""
    t = np.array([-200.0, -30.0, 150.0])
    x = _passing(t)
    share = _doppler().media_corrections(t, x)
    ends = []
    for sign in (-1.0, 1.0):
        te = t + sign * 0.5 * COUNT_s
        ranging = [MeasurementModel(MADRID, GMST0_rad, ("range",), EXACT, media=_media(**off))
                   .media_corrections(te, _passing(te))[:, 0]
                   for off in ({"ionosphere": False}, {"troposphere": False})]
        ends.append(ranging[0] - ranging[1])
    np.testing.assert_allclose(share[:, 2], (ends[1] - ends[0]) / COUNT_s, rtol=1e-9)
    nodes, weights = np.polynomial.legendre.leggauss(8)
    mean_rate = sum(0.5 * w * _doppler().media_corrections(t + 0.5 * COUNT_s * u,
                                                           _passing(t + 0.5 * COUNT_s * u))[:, 1]
                    for u, w in zip(nodes, weights, strict=True))
    np.testing.assert_allclose(share[:, 2], mean_rate, rtol=0,
                               atol=1e-4 * np.abs(mean_rate).max())
    assert np.all(np.abs(share[:, 2]) > 1e-9)  # km/s: metres of delay change per minute


def test_doppler_media_partials_match_central_differences():
    # Zenith parameters: linear, differences exact to rounding (steps as above). State:
    # first order in the light time, 1e-4 of each row (the two-way range's tolerance).
    model = _doppler()
    t = np.array([-220.0, 30.0])
    x = _passing(t)
    base = model.media
    cols = []
    for name, h in zip(("zenith_dry_km", "zenith_wet_km", "zenith_tec_tecu"),
                       (1e-4, 1e-4, 1.0), strict=True):
        def shifted(d, name=name):
            return dataclasses.replace(model, media=dataclasses.replace(
                base, **{name: getattr(base, name) + d})).compute(t, x)
        cols.append((shifted(h) - shifted(-h)) / (2 * h))
    numeric = np.stack(cols, axis=-1)
    analytic = model.media_partials(t, x)
    np.testing.assert_allclose(analytic, numeric, rtol=1e-7, atol=1e-7 * np.abs(numeric).max())
    assert np.all(analytic[:, 2, 2] * analytic[:, 1, 2] > 0)  # both from the carrier phase
    # The count ends moved with the state: the Taylor ends of the light-time model, without
    # a central body, exact on the straight line, as is the local transition then.
    taylor = dataclasses.replace(model, light_time=LightTime(two_way=True, mu_km3_s2=0.0))
    h_media = (taylor.state_partials(t, x)
               - dataclasses.replace(taylor, media=None).state_partials(t, x))
    numeric = central_differences(lambda y: taylor.media_corrections(t, y), x,
                                  [1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5])
    scale = np.abs(numeric).max(axis=-1, keepdims=True)
    assert np.all(np.abs(h_media[:, 2] - numeric[:, 2]) <= 1e-4 * scale[:, 2])


def _over_the_atlantic(t_s: np.ndarray) -> np.ndarray:
    """Spacecraft states (N, 6) on a straight line 26,000 km above 35 N 60 W at t = 0,
    moving 3 km/s: Madrid sees it at about 25 deg and Goldstone at about 35 deg."""
    t = np.asarray(t_s, dtype=float)
    lat, lon = np.radians(35.0), np.radians(-60.0)
    r_ecef = 32378.0 * np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon),
                                 np.sin(lat)])
    r0 = station_state_eci(r_ecef, MeasurementModel(MADRID, GMST0_rad).orientation.attitude(
        np.array([0.0])))[0, :3]
    v = np.array([1.0, -2.0, 2.0])
    return np.concatenate([r0 + t[:, None] * v, np.broadcast_to(v, t.shape + (3,))], axis=-1)


def _three_way(receiver: MediaModel, uplink: MediaModel) -> MeasurementModel:
    return MeasurementModel(MADRID, GMST0_rad, ("range", "range_rate", "doppler"),
                            LightTime(two_way=True, state_at=_over_the_atlantic),
                            media=receiver, uplink=GOLDSTONE, uplink_media=uplink,
                            count_time_s=COUNT_s)


def _goldstone_media(**kwargs) -> MediaModel:
    base = dict(zenith_tec_tecu=40.0, band="X")
    base.update(kwargs)
    return MediaModel.from_meteorology(GOLDSTONE.lat_rad, GOLDSTONE.h_km, 70.25, 900.0, 300.0,
                                       0.2, **base)


def test_a_three_way_up_leg_crosses_the_uplink_stations_atmosphere():
    """With the receiver's media off, the three-way range's media share is half the up-leg's
    slant troposphere at Goldstone's own elevation and latitude (Niell's functions evaluated
    here), and none of it is a partial of Madrid's zenith parameters."""
    t = np.array([-120.0, 60.0])
    x = _over_the_atlantic(t)
    up = _goldstone_media(ionosphere=False)
    model = _three_way(_media(troposphere=False, ionosphere=False), up)
    s = np.sin(model.uplink_elevation_rad(t, x))
    # Niell's season at the receive time (the up-leg left 2τ = 0.2 s before: 1e-13 of m)
    doy = up.day_of_year + t / 86400.0
    slant = (up.zenith_dry_km * niell_hydrostatic(s, GOLDSTONE.lat_rad, doy, GOLDSTONE.h_km).m
             + up.zenith_wet_km * niell_wet(s, GOLDSTONE.lat_rad).m)
    np.testing.assert_allclose(model.media_corrections(t, x)[:, 0], 0.5 * slant, rtol=1e-12)
    assert np.all(model.media_partials(t, x) == 0.0)
    assert np.abs(model.uplink_media_partials(t, x)[:, 0, :2]).min() > 0.1


@pytest.mark.parametrize("which", ["media", "uplink_media"])
def test_three_way_zenith_partials_match_central_differences(which):
    model = _three_way(_media(), _goldstone_media())
    t = np.array([-200.0, 40.0])
    x = _over_the_atlantic(t)
    base = getattr(model, which)
    cols = []
    for name, h in zip(("zenith_dry_km", "zenith_wet_km", "zenith_tec_tecu"),
                       (1e-4, 1e-4, 1.0), strict=True):
        def shifted(d, name=name):
            return dataclasses.replace(model, **{which: dataclasses.replace(
                base, **{name: getattr(base, name) + d})}).compute(t, x)
        cols.append((shifted(h) - shifted(-h)) / (2 * h))
    numeric = np.stack(cols, axis=-1)
    analytic = (model.media_partials(t, x) if which == "media"
                else model.uplink_media_partials(t, x))
    np.testing.assert_allclose(analytic, numeric, rtol=1e-7, atol=1e-7 * np.abs(numeric).max())
    assert np.abs(analytic[:, :2, :]).min() > 0.0


def test_three_way_media_need_the_uplink_stations_media():
    with pytest.raises(InputError, match="uplink_media"):
        MeasurementModel(MADRID, GMST0_rad, ("range",), EXACT, media=_media(), uplink=GOLDSTONE)
    with pytest.raises(InputError, match="uplink_media"):
        MeasurementModel(MADRID, GMST0_rad, ("range",), EXACT, uplink_media=_media())
    with pytest.raises(InputError, match="uplink_media"):
        MeasurementModel(MADRID, GMST0_rad, ("range",), EXACT,
                         media=_media()).uplink_media_partials(np.zeros(1),
                                                               _passing(np.zeros(1)))
