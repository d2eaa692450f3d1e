"""Relativistic light time, three-way tracking and count-based Doppler vs an mpmath reference.

The reference is written here from Moyer (2003), DESCANSO Monograph 2, ch. 8 (the light-time
equations ET_3 - ET_2 = r_23 / c + RLT_23 and ET_2 - ET_1 = r_12 / c + RLT_12 in TDB, the
Shapiro delay of eq. 8-38 with γ = 1), ch. 11 (the round-trip light time ρ = t_3 - t_1 in
station time) and ch. 13 (Doppler as the change of ρ over the count interval), iterated
in 40-digit mpmath. It shares no code with tapp: the DE421 states come from jplephem, TT and
TDB - TT (with the stations' topocentric terms) from ERFA, station positions from ERFA's WGS84
geodetic conversion and the gmst rotation θ(t) = θ_0 + ω t written out here; the spacecraft
moves on a straight line (tapp: the light-time Taylor expansion with μ = 0, exact for it).
Tolerances: 1 mm in range, 0.01 mm/s in Doppler (the brief's); the two solutions should agree
to ~1e-8 km, the floating-point resolution of 1e8 km distances.
"""

from __future__ import annotations

import importlib.util
import math
from dataclasses import replace
from pathlib import Path

import erfa
import mpmath as mp
import numpy as np
import pytest
from jplephem.spk import SPK

from tapp.dynamics.ephemeris import barycentric_state
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import parse_epoch
from tapp.measurements import LightTime, MeasurementModel, Station
from tapp.measurements.bands import BANDS
from tapp.measurements.doppler import doppler_hz, hz_per_km_s, range_rate_from_hz
from tapp.measurements.relativity import Relativity, shapiro_delay_s
from tests.tapp.measurements.helpers import central_differences

ONE_MM_km = 1e-6
HUNDREDTH_MM_S_km_s = 1e-8
EPOCH = "2026-03-10T12:00:00"
#: TAI - UTC since 2017-01-01 (IERS Bulletin C 64: no leap second announced through 2026).
TAI_MINUS_UTC_s = 37.0
THETA0_rad = 1.0
OMEGA_rad_s = 7.292115e-5  # IERS Conventions (2010) Table 1.1
C_km_s = mp.mpf("299792.458")
#: GM, km^3/s^2: DE430 (Folkner et al. 2014, Table 8).
GM = {"sun": mp.mpf("132712440041.9394"), "earth": mp.mpf("398600.4415"),
      "moon": mp.mpf("4902.800066")}
AU_km = 149597870.7
#: Geodetic (lat, east lon deg, h m) of DSS-14 and DSS-63 (approximate, any site serves).
GOLDSTONE = (35.4259, -116.8895, 1002.0)
MADRID = (40.4314, -4.2481, 865.0)

mp.mp.dps = 40


def _kernel() -> SPK:
    spec = importlib.util.find_spec("skyfield_data")
    folder = Path(next(iter(spec.submodule_search_locations)))
    return SPK.open(str(folder / "data" / "de421.bsp"))


KERNEL = _kernel()
TT1, TT2 = erfa.taitt(*erfa.utctai(*erfa.dtf2d("UTC", 2026, 3, 10, 12, 0, 0.0)))
PATHS = {"sun": ((0, 10),), "earth": ((0, 3), (3, 399)), "moon": ((0, 3), (3, 301))}


def bary(body: str, tdb_s) -> mp.matrix:
    """Barycentric position of ``body``, km, at TDB = TT(epoch) + tdb_s seconds."""
    frac = TT2 + float(tdb_s) / 86400.0
    total = sum(KERNEL[a, b].compute(TT1, frac) for a, b in PATHS[body])
    return mp.matrix([mp.mpf(float(c)) for c in total])


def dtdb(t_s, site_km=None):
    """TDB - TT at scenario time t_s, s (ERFA), at the geocentre or an Earth-fixed site."""
    frac = TT2 + float(t_s) / 86400.0
    if site_km is None:
        return mp.mpf(erfa.dtdb(TT1, frac, 0.0, 0.0, 0.0, 0.0))
    ut = math.fmod(TT1 - 0.5 + frac - (TAI_MINUS_UTC_s + 32.184) / 86400.0, 1.0)
    x, y, z = (float(c) for c in site_km)
    return mp.mpf(erfa.dtdb(TT1, frac, ut, math.atan2(y, x), math.hypot(x, y), z))


def site_km(lat_deg, lon_deg, h_m):
    return np.asarray(erfa.gd2gc(1, math.radians(lon_deg), math.radians(lat_deg), h_m)) / 1e3


def station_geo(site, t) -> mp.matrix:
    th = THETA0_rad + OMEGA_rad_s * t
    x, y, z = (mp.mpf(float(c)) for c in site)
    return mp.matrix([x * mp.cos(th) - y * mp.sin(th), x * mp.sin(th) + y * mp.cos(th), z])


def norm(v) -> mp.mpf:
    return mp.sqrt(sum(c * c for c in v))


def rlt(r_i, e_i, r_j, e_j, bodies) -> mp.mpf:
    """Moyer eq. 8-38, γ = 1: ends r_i (TDB e_i), r_j (TDB e_j); bodies at their ends' times."""
    total = mp.mpf(0)
    for body in bodies:
        a, b = r_i - bary(body, e_i), r_j - bary(body, e_j)
        ri, rj, rij = norm(a), norm(b), norm(b - a)
        eps = 2 * GM[body] / C_km_s**2 if body == "sun" else 0
        total += 2 * GM[body] / C_km_s**3 * mp.log((ri + rj + rij + eps) / (ri + rj - rij + eps))
    return total


def round_trip_s(t3, x, rx, tx, bodies=("sun", "earth", "moon")) -> mp.mpf:
    """ρ = t_3 - t_1 (station clock) for the straight-line spacecraft x = (r, v) at t3."""
    t3 = mp.mpf(t3)
    r0, v0 = mp.matrix([mp.mpf(float(c)) for c in x[:3]]), mp.matrix([mp.mpf(float(c))
                                                                       for c in x[3:]])
    e3 = t3 + dtdb(t3, rx)
    r3 = bary("earth", e3) + station_geo(rx, t3)

    def spacecraft(t2):
        e2 = t2 + dtdb(t2)
        return bary("earth", e2) + r0 + (t2 - t3) * v0, e2

    t2 = t3
    for _ in range(12):  # ET_2 = ET_3 - r_23 / c - RLT_23
        r2, e2 = spacecraft(t2)
        t2 += e3 - norm(r2 - r3) / C_km_s - rlt(r2, e2, r3, e3, bodies) - e2
    r2, e2 = spacecraft(t2)
    t1 = t2
    for _ in range(12):  # ET_1 = ET_2 - r_12 / c - RLT_12
        e1 = t1 + dtdb(t1, tx)
        r1 = bary("earth", e1) + station_geo(tx, t1)
        t1 += e2 - norm(r2 - r1) / C_km_s - rlt(r1, e1, r2, e2, bodies) - e1
    return t3 - t1


def _model(kinds, relativity=True, uplink=None, bodies=("sun", "earth", "moon")):
    rel = Relativity.at(parse_epoch(EPOCH), bodies) if relativity else None
    gold = Station("G", math.radians(GOLDSTONE[0]), math.radians(GOLDSTONE[1]),
                   GOLDSTONE[2] / 1e3)
    up = None if uplink is None else Station("M", math.radians(MADRID[0]),
                                             math.radians(MADRID[1]), MADRID[2] / 1e3)
    return MeasurementModel(gold, EarthOrientation.gmst_angle(THETA0_rad), kinds,
                            LightTime(True, None, 0.0, rel), uplink=up)


def _geometry(name: str) -> np.ndarray:
    """Straight-line spacecraft states at t = 5 h: lunar distance, 1.5 AU, and beyond the
    Sun 1.5 deg from its limb direction (a solar conjunction)."""
    sun = np.array([float(c) for c in bary("sun", 18000.0) - bary("earth", 18000.0)])
    u_sun = sun / np.linalg.norm(sun)
    side = np.cross(u_sun, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    if name == "lunar":
        r = 380000.0 * np.array([0.6, 0.7, 0.2]) / np.linalg.norm([0.6, 0.7, 0.2])
    elif name == "mars":
        r = 1.5 * AU_km * np.array([0.2, -0.9, -0.3]) / np.linalg.norm([0.2, -0.9, -0.3])
    else:
        sep = math.radians(1.5)
        r = 2.4 * AU_km * (math.cos(sep) * u_sun + math.sin(sep) * side)
    return np.array([np.r_[r, 0.8, -0.4, 0.3]])


T3 = np.array([18000.0])
GOLD_SITE = site_km(*GOLDSTONE)
MAD_SITE = site_km(*MADRID)


@pytest.mark.parametrize("name", ["lunar", "mars", "conjunction"])
def test_two_way_range_matches_mpmath_moyer(name):
    x = _geometry(name)
    computed = _model(("range",)).compute(T3, x)[0, 0]
    reference = float(C_km_s * round_trip_s(T3[0], x[0], GOLD_SITE, GOLD_SITE) / 2)
    assert abs(computed - reference) < ONE_MM_km


def test_three_way_range_matches_mpmath_moyer():
    x = _geometry("mars")
    computed = _model(("range",), uplink=True).compute(T3, x)[0, 0]
    reference = float(C_km_s * round_trip_s(T3[0], x[0], GOLD_SITE, MAD_SITE) / 2)
    assert abs(computed - reference) < ONE_MM_km


@pytest.mark.parametrize(("name", "uplink"), [("lunar", None), ("mars", True)])
def test_count_doppler_matches_mpmath_moyer(name, uplink):
    """Equivalent range-rate c (ρ(t + T_c/2) - ρ(t - T_c/2)) / (2 T_c), T_c = 60 s."""
    x = _geometry(name)
    model = _model(("doppler",), uplink=uplink)
    computed = model.compute(T3, x)[0, 0]
    tx = GOLD_SITE if uplink is None else MAD_SITE
    ends = [round_trip_s(T3[0] + s * 30.0, np.r_[x[0, :3] + s * 30.0 * x[0, 3:], x[0, 3:]],
                         GOLD_SITE, tx) for s in (-1.0, 1.0)]
    reference = float(C_km_s * (ends[1] - ends[0]) / 120)
    assert abs(computed - reference) < HUNDREDTH_MM_S_km_s


def test_sun_shapiro_at_conjunction_shows_in_range():
    """1.5 deg from the Sun: its delay is tens of µs one way, km in the two-way range."""
    x = _geometry("conjunction")
    full = _model(("range",)).compute(T3, x)[0, 0]
    without_sun = _model(("range",), bodies=("earth", "moon")).compute(T3, x)[0, 0]
    delay_s = (full - without_sun) / float(C_km_s)  # one-way mean of the two legs
    assert 30e-6 < delay_s < 200e-6
    newtonian = _model(("range",), relativity=False).compute(T3, x)[0, 0]
    assert full - newtonian > 5.0  # km


def test_shapiro_delay_of_a_grazing_ray_is_shapiros_value():
    """Earth-Sun-Mars at superior conjunction, ray grazing the Sun: the round-trip delay is
    ~250 µs (Shapiro 1964; 247 µs quoted for Mars by Reasenberg et al. 1979)."""
    earth = np.array([[-AU_km, 0.0, 0.0]])
    mars = np.array([[1.524 * AU_km, 0.0, 0.0]])
    # A ray grazing the limb: the end points offset by the solar radius.
    offset = np.array([[0.0, 695700.0, 0.0]])
    one_way = shapiro_delay_s(earth + offset, mars + offset, np.zeros((1, 3)),
                              np.zeros((1, 3)), 132712440041.9394, sun=True)
    assert 2 * one_way[0] == pytest.approx(247e-6, rel=0.03)


def test_doppler_hz_conversion_at_x_band():
    """F₂ = 2 M₂ f_T ρ̇ / c: X-band (749/880, 7167.5 MHz) 56.2 Hz per m/s, and back."""
    band = BANDS["X"]
    assert hz_per_km_s(band) * 1e-3 == pytest.approx(2 * 7167.5e6 * 880 / 749 / 299792458.0)
    assert doppler_hz(1e-3, band) == pytest.approx(56.18, abs=0.01)
    assert range_rate_from_hz(doppler_hz(0.123, band), band) == pytest.approx(0.123)


@pytest.mark.parametrize("relativity", [False, True])
def test_range_and_doppler_state_partials_vs_central_differences(relativity):
    """Range: the first-order light-time partials (light times' own dependence kept);
    Doppler: their difference over T_c, mapped to the centre by the local transition. Steps
    1 km and 0.1 km/s: the barycentric solution resolves ~1e-8 km (float64 positions of
    1.5e8 km), so smaller steps measure its rounding; truncation h² ∂³ρ / 6 ~ 1e-12. Bound:
    1e-7 of the row's largest element (measured 2e-10 Newtonian, 2e-8 barycentric: what is
    left out, Shapiro's and TDB's gradients and the rounding)."""
    x = _geometry("lunar")
    model = _model(("range", "doppler"), relativity=relativity)
    model = MeasurementModel(model.station, model.orientation, model.kinds,
                             LightTime(True, None, 398600.4415, model.light_time.relativity))
    h = model.state_partials(T3, x)[0]
    numeric = central_differences(lambda s: model.compute(T3, s), x, [10.0] * 3 + [1.0] * 3)[0]
    for row in range(2):
        assert np.max(np.abs(h[row] - numeric[row])) < 1e-7 * np.max(np.abs(numeric[row]))


@pytest.mark.parametrize("relativity", [False, True])
def test_three_way_station_partials_vs_central_differences(relativity):
    """Receiver: the down-leg part; uplink: the up-leg part, each with its clock's TDB - TT
    term in the relativistic model (Earth-fixed xyz, step 100 km: Doppler's station partials
    are ~4e-5 (km/s)/km, and the barycentric Doppler resolves ~5e-10 km/s, so smaller steps
    measure the rounding; truncation (h / rho)² / 6 ~ 1e-8). Bound 1e-7 of the row's
    largest element, as the state partials."""
    x = _geometry("lunar")
    model = _model(("range", "doppler"), relativity=relativity, uplink=True)
    computed = {"station": model.station_partials(T3, x, "ecef")[0],
                "uplink": model.uplink_station_partials(T3, x, "ecef")[0]}
    for which, station in (("station", model.station), ("uplink", model.uplink)):

        def moved(r_ecef, which=which, station=station):
            # The station's Earth-fixed position shifted as it is (a 100 km step leaves the
            # heights a Station accepts); range and Doppler read only r_ecef_km.
            shifted = replace(station)
            object.__setattr__(shifted, "r_ecef_km", r_ecef[0])
            return replace(model, **{which: shifted}).compute(T3, x)[0]

        numeric = central_differences(moved, station.r_ecef_km[None, :], [100.0] * 3)
        for row in range(2):
            scale = np.max(np.abs(numeric[row]))
            assert np.max(np.abs(computed[which][row] - numeric[row])) < 1e-7 * scale


def test_uplink_needs_two_way_light_time():
    model = _model(("range",), relativity=False)
    with pytest.raises(InputError, match="uplink"):
        MeasurementModel(model.station, model.orientation, ("range",), None,
                         uplink=model.station)
    with pytest.raises(InputError, match="doppler"):
        MeasurementModel(model.station, model.orientation, ("doppler",),
                         LightTime(two_way=False))


def test_tdb_tables_interpolate_erfa_to_its_own_rounding():
    """TDB - TT from the cached tables and the closed-form site terms against ERFA's series
    called at each time, at the geocentre and at Goldstone, over a month of random times (and
    the rate used by Doppler): the tables' bound is 5e-16 s; the reference itself rounds UT (a
    Julian date of 2.46e6 days plus a fraction: 4.7e-5 s of UT, 5.7e-15 s of the 1.7 us
    diurnal term), hence 1e-14 s."""
    rel = Relativity.at(parse_epoch(EPOCH))
    t = np.sort(np.random.default_rng(1).uniform(-3600.0, 31 * 86400.0, 20_000))
    site = np.array([-2353.6, -4641.3, 3677.0])
    lon, u = math.atan2(site[1], site[0]), math.hypot(site[0], site[1])

    def series(times, at):
        fraction = rel.tt0_jd[1] + times / 86400.0
        if at is None:
            return erfa.dtdb(rel.tt0_jd[0], fraction, 0.0, 0.0, 0.0, 0.0)
        ut = np.mod(rel.tt0_jd[0] - 0.5 + fraction + rel.ut_minus_tt_s / 86400.0, 1.0)
        return erfa.dtdb(rel.tt0_jd[0], fraction, ut, lon, u, at[2])

    for at in (None, site):
        np.testing.assert_allclose(rel.tdb_minus_tt_s(t, at), series(t, at), rtol=0, atol=1e-14)
        rate = 0.5 * (series(t + 1.0, at) - series(t - 1.0, at))
        np.testing.assert_allclose(rel.tdb_rate(t, at), rate, rtol=0, atol=1e-14)


@pytest.mark.parametrize("body", ["earth", "sun", "moon", "jupiter"])
def test_body_tables_interpolate_de421_to_its_rounding(body):
    """The Hermite tables against jplephem at each time over a month: the interpolation's own
    bound is 7e-9 km (the Moon); what shows is the rounding of barycentric positions of up to
    8e8 km (2 ulp: 1.2e-7 km at Jupiter, 6e-8 km at the Earth), velocities 1e-9 km/s."""
    rel = Relativity.at(parse_epoch(EPOCH))
    t = np.random.default_rng(2).uniform(-3600.0, 31 * 86400.0, 5_000)
    dt = rel.tdb_minus_tt_s(t)
    got = rel.body_state(body, t, dt)
    ref = barycentric_state(body, rel.tt0_jd[0], rel.tt0_jd[1] + (t + dt) / 86400.0)
    scale = np.linalg.norm(ref[:, :3], axis=1).max()
    np.testing.assert_allclose(got[:, :3], ref[:, :3], rtol=0,
                               atol=max(4 * np.spacing(scale), 1e-8))
    np.testing.assert_allclose(got[:, 3:], ref[:, 3:], rtol=0, atol=1e-9)
