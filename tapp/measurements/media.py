"""Tropospheric and ionospheric delays of a ground-station link, with their partials.

Troposphere (non-dispersive, the same on range and on the phase-derived range-rate): the
slant delay Z_h m_h(E) + Z_w m_w(E), with

- the zenith hydrostatic delay of Saastamoinen (1972) in the form of Davis et al. (1985),
  Radio Science 20(6) 1593-1607, eq. A11 (P hPa, φ geodetic latitude, h km):

  .. math:: Z_h = \\frac{0.0022768\\,P}{1 - 0.00266\\cos 2\\varphi - 0.00028\\,h}\\ \\text{m}

- the zenith wet delay of Saastamoinen (1972), "Atmospheric correction for the troposphere
  and stratosphere in radio ranging of satellites", Geophys. Monogr. 15, 247-251
  (T K, e hPa the water-vapour pressure):

  .. math:: Z_w = 0.002277\\,(1255 / T + 0.05)\\,e\\ \\text{m}

  with e = RH e_s(T), e_s the saturation pressure over water of Murray (1967), J. Appl.
  Meteor. 6, 203-204: e_s = 6.1078 exp(17.2693882 (T - 273.16) / (T - 35.86)) hPa;
- a station without meteorology takes the standard atmosphere of Berg (1948) from its height
  h (m), as RTKLIB's and Orekit's standard Saastamoinen models do:
  P = 1013.25 (1 - 2.2557e-5 h)^5.2568 hPa, T = 288.15 - 6.5e-3 h K, RH = 50 %;
- the mapping functions of Niell (1996), "Global mapping functions for the atmosphere delay
  at radio wavelengths", J. Geophys. Res. 101(B2) 3227-3246: Marini's continued fraction
  normalised at the zenith,

  .. math:: m(E) = \\frac{1 + \\frac{a}{1 + \\frac{b}{1 + c}}}
                          {\\sin E + \\frac{a}{\\sin E + \\frac{b}{\\sin E + c}}},

  the hydrostatic coefficients a(φ, t) = ā(φ) - a_A(φ) cos(2π (DOY - 28) / 365.25) (half a
  year later in the southern hemisphere) from Niell's table 3, linear in |φ| between 15° and
  75° and constant beyond, plus the height correction (1 / sin E - m(E; a_ht, b_ht, c_ht)) h;
  the wet coefficients (table 4) without season or height terms. Niell fitted them down to
  3° elevation; below, they are extrapolated (a station's mask should stay above 3°).

Ionosphere (dispersive): a thin shell at height H over a sphere of radius R (the Earth's mean
radius, 6371 km, as Orekit's single-layer model), mapping the zenith total electron content
TEC (TECU, 1e16 electrons/m²) to the slant by

.. math:: m_I(E) = 1 / \\sqrt{1 - (R \\cos E / (R + H))^2},\\qquad
          \\delta_I = 40.3\\,\\mathrm{TEC}\\,m_I(E) / f^2\\ \\text{m (SI)},

at the leg's own carrier f (uplink f_T, downlink f_R: :mod:`tapp.measurements.bands`), a group
delay on range (+) and a phase advance on range-rate and on the count-based Doppler's phase
ranges (-, :attr:`MediaModel.phase`). H defaults to 350 km
(:data:`SHELL_HEIGHT_km`), the nominal TEC to 10 TECU (:data:`ZENITH_TEC_TECU`): the night-time
floor of Klobuchar's broadcast model (5 ns at L1 = 9.2 TECU; Klobuchar 1987, IEEE Trans.
Aerosp. Electron. Syst. AES-23(3) 325-331); a mid-latitude day reaches 20-50 TECU.

Range-rate. The correction of a leg's range-rate is the time derivative of its range delay,
Z m'(E) Ė summed over the terms (negative for the ionosphere), with the zenith values constant
in time. Every mapping function is written in s = sin E, so that s = U / |p| for the
station-to-spacecraft vector p in the station's East-North-Up axes and ṡ = (U̇ - s p̂·ṗ) / |p|,
ṗ the rate of p seen from the rotating Earth: M_enu [(v - v_st) - ω ĉ × (r - r_st)]. A
two-way leg's rate is taken at the leg's geometry with dt_leg/dt = 1 (the O(ρ̇ / c) ~ 1e-4
relative terms of the light-time rate are left out, as are the Earth's precession rates).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError
from tapp.frames.time import Epoch, calendar_to_jd, jd_to_calendar
from tapp.measurements.bands import BANDS, DEFAULT_BAND

#: Names (with units) of a station's zenith parameters, in the order of the partials' last
#: axis: dry (hydrostatic) and wet zenith delays, km, and the zenith TEC, TECU.
MEDIA_PARAMETER_NAMES = ("zenith_dry_km", "zenith_wet_km", "zenith_tec_tecu")
#: The kind of each zenith parameter on the tape.
MEDIA_KINDS = ("troposphere", "troposphere", "ionosphere")
#: Default height of the ionosphere's thin shell, km (a common single-layer choice; the IGS
#: maps use 450 km).
SHELL_HEIGHT_km = 350.0
#: Default zenith TEC, TECU (module docstring: Klobuchar's night-time floor).
ZENITH_TEC_TECU = 10.0
#: 40.3 m³/s² (the ionospheric constant: delay = 40.3 TEC / f², SI) times 1 TECU (1e16 /m²)
#: in km Hz² per TECU.
IONO_KM_HZ2_PER_TECU = 40.3e16 * 1e-3
#: Standard atmosphere at sea level (Berg 1948): pressure hPa, temperature K, relative humidity.
STANDARD_PRESSURE_hPa = 1013.25
STANDARD_TEMPERATURE_K = 288.15
STANDARD_HUMIDITY = 0.5
#: Plausible station meteorology, inclusive (a value outside is a unit slip: Pa for hPa, C for K).
PRESSURE_RANGE_hPa = (300.0, 1100.0)
TEMPERATURE_RANGE_K = (180.0, 340.0)

# Niell (1996) table 3 (hydrostatic: average and amplitude) and table 4 (wet), at |φ| = 15, 30,
# 45, 60, 75 deg; rows a, b, c.
_NIELL_LAT_deg = np.array([15.0, 30.0, 45.0, 60.0, 75.0])
_NIELL_DRY_AVERAGE = np.array([
    [1.2769934e-3, 1.2683230e-3, 1.2465397e-3, 1.2196049e-3, 1.2045996e-3],
    [2.9153695e-3, 2.9152299e-3, 2.9288445e-3, 2.9022565e-3, 2.9024912e-3],
    [62.610505e-3, 62.837393e-3, 63.721774e-3, 63.824265e-3, 64.258455e-3]])
_NIELL_DRY_AMPLITUDE = np.array([
    [0.0, 1.2709626e-5, 2.6523662e-5, 3.4000452e-5, 4.1202191e-5],
    [0.0, 2.1414979e-5, 3.0160779e-5, 7.2562722e-5, 11.723375e-5],
    [0.0, 9.0128400e-5, 4.3497037e-5, 84.795348e-5, 170.37206e-5]])
_NIELL_WET = np.array([
    [5.8021897e-4, 5.6794847e-4, 5.8118019e-4, 5.9727542e-4, 6.1641693e-4],
    [1.4275268e-3, 1.5138625e-3, 1.4572752e-3, 1.5007428e-3, 1.7599082e-3],
    [4.3472961e-2, 4.6729510e-2, 4.3908931e-2, 4.4626982e-2, 5.4736038e-2]])
_NIELL_HEIGHT = (2.53e-5, 5.49e-3, 1.14e-3)
_DAYS_PER_YEAR = 365.25
#: The Earth's mean radius, km (IUGG mean radius R1 = 6371.0088 km, rounded as the
#: single-layer models of Schaer 1999 and Orekit take it): the thin shell's sphere.
MEAN_RADIUS_km = 6371.0


# ---------------------------------------------------------------------------------------------
# Zenith delays and meteorology
# ---------------------------------------------------------------------------------------------


def zenith_hydrostatic_delay_m(pressure_hpa, lat_rad, h_km):
    """Return the zenith hydrostatic delay of Saastamoinen-Davis, m (module docstring)."""
    return 0.0022768 * pressure_hpa / (1.0 - 0.00266 * np.cos(2.0 * lat_rad) - 0.00028 * h_km)


def zenith_wet_delay_m(temperature_k, vapour_pressure_hpa):
    """Return the zenith wet delay of Saastamoinen, m (module docstring)."""
    return 0.002277 * (1255.0 / temperature_k + 0.05) * vapour_pressure_hpa


def vapour_pressure_hpa(temperature_k, relative_humidity):
    """Return the water-vapour pressure RH e_s(T), hPa (Murray 1967; module docstring)."""
    t = np.asarray(temperature_k, dtype=float)
    return relative_humidity * 6.1078 * np.exp(17.2693882 * (t - 273.16) / (t - 35.86))


def standard_atmosphere(h_km: float) -> tuple[float, float, float]:
    """Return (pressure hPa, temperature K, relative humidity) at height h_km (Berg 1948)."""
    h_m = 1e3 * h_km
    return (STANDARD_PRESSURE_hPa * (1.0 - 2.2557e-5 * h_m) ** 5.2568,
            STANDARD_TEMPERATURE_K - 6.5e-3 * h_m, STANDARD_HUMIDITY)


def check_meteorology(source: str, where: str, pressure_hpa: float, temperature_k: float,
                      relative_humidity: float) -> None:
    """Refuse meteorology out of :data:`PRESSURE_RANGE_hPa`, :data:`TEMPERATURE_RANGE_K` or a
    relative humidity out of [0, 1]: an InputError naming ``source`` and ``where.<key>``."""
    for key, value, (lo, hi), unit in (
            ("pressure_hpa", pressure_hpa, PRESSURE_RANGE_hPa, "hPa"),
            ("temperature_k", temperature_k, TEMPERATURE_RANGE_K, "K"),
            ("relative_humidity", relative_humidity, (0.0, 1.0), "(a fraction)")):
        if not lo <= value <= hi:
            raise InputError(source, f"{where}.{key}",
                             f"a station's value in [{lo:g}, {hi:g}] {unit}", value)


def day_of_year(epoch: Epoch) -> float:
    """Return the day of the year of a UTC instant, 1.0 at 0h on 1 January (fractional)."""
    year = jd_to_calendar(epoch.jd_whole, epoch.jd_fraction)[0]
    whole, fraction = calendar_to_jd(year, 1, 1)
    return 1.0 + (epoch.jd_whole - whole) + (epoch.jd_fraction - fraction)


# ---------------------------------------------------------------------------------------------
# Mapping functions: values and first and second derivatives w.r.t. s = sin E
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Mapping:
    """A mapping function m and its derivatives m_s = dm/ds, m_ss = d²m/ds² at s = sin E,
    each shaped like s. dm/dE = m_s cos E (:meth:`per_elevation`)."""

    m: np.ndarray
    m_s: np.ndarray
    m_ss: np.ndarray

    def per_elevation(self, sin_e):
        """Return dm/dE = m_s cos E, per rad, shaped like s."""
        return self.m_s * np.sqrt(1.0 - np.asarray(sin_e, dtype=float) ** 2)


def marini(sin_e, a, b, c) -> Mapping:
    """Return Marini's continued fraction normalised at the zenith (module docstring).

    With q = s + c, B = s + b / q, D = s + a / B and N = 1 + a / (1 + b / (1 + c)): m = N / D,
    m_s = -N D' / D², m_ss = -N (D'' / D² - 2 D'² / D³), where B' = 1 - b / q²,
    B'' = 2 b / q³, D' = 1 - a B' / B², D'' = -a (B'' / B² - 2 B'² / B³).
    """
    s = np.asarray(sin_e, dtype=float)
    q = s + c
    big_b = s + b / q
    b1, b2 = 1.0 - b / q**2, 2.0 * b / q**3
    d = s + a / big_b
    d1 = 1.0 - a * b1 / big_b**2
    d2 = -a * (b2 / big_b**2 - 2.0 * b1**2 / big_b**3)
    n = 1.0 + a / (1.0 + b / (1.0 + c))
    return Mapping(n / d, -n * d1 / d**2, -n * (d2 / d**2 - 2.0 * d1**2 / d**3))


def _niell_table(table: np.ndarray, lat_rad: float) -> np.ndarray:
    """Niell's coefficients (a, b, c) at |φ|, linear between the rows, constant beyond."""
    lat = abs(np.degrees(lat_rad))
    return np.array([np.interp(lat, _NIELL_LAT_deg, row) for row in table])


def niell_hydrostatic(sin_e, lat_rad: float, day_of_year, h_km: float) -> Mapping:
    """Return Niell's hydrostatic mapping function with its height correction (module
    docstring) at s = sin E (shape (N,)), geodetic latitude (rad), day of year (UTC, 1.0 at
    0h on 1 January; scalar or (N,)) and height (km)."""
    s = np.asarray(sin_e, dtype=float)
    phase = np.asarray(day_of_year, dtype=float) - 28.0 + (0.5 * _DAYS_PER_YEAR if lat_rad < 0
                                                          else 0.0)
    season = np.cos(2.0 * np.pi * phase / _DAYS_PER_YEAR)
    avg, amp = _niell_table(_NIELL_DRY_AVERAGE, lat_rad), _niell_table(_NIELL_DRY_AMPLITUDE,
                                                                       lat_rad)
    a, b, c = (avg[i] - amp[i] * season for i in range(3))
    base, ht = marini(s, a, b, c), marini(s, *_NIELL_HEIGHT)
    return Mapping(base.m + (1.0 / s - ht.m) * h_km, base.m_s + (-1.0 / s**2 - ht.m_s) * h_km,
                   base.m_ss + (2.0 / s**3 - ht.m_ss) * h_km)


def niell_wet(sin_e, lat_rad: float) -> Mapping:
    """Return Niell's wet mapping function at s = sin E (shape (N,)), latitude (rad)."""
    return marini(sin_e, *_niell_table(_NIELL_WET, lat_rad))


def single_layer(sin_e, shell_height_km: float = SHELL_HEIGHT_km,
                 radius_km: float = MEAN_RADIUS_km) -> Mapping:
    """Return the thin-shell ionospheric mapping 1 / sqrt(1 - (R cos E / (R + H))²).

    With k = R / (R + H) and g = 1 - k² + k² s²: m = g^(-1/2), m_s = -k² s g^(-3/2),
    m_ss = -k² g^(-3/2) + 3 k⁴ s² g^(-5/2).
    """
    s = np.asarray(sin_e, dtype=float)
    k2 = (radius_km / (radius_km + shell_height_km)) ** 2
    g = 1.0 - k2 + k2 * s * s
    return Mapping(g**-0.5, -k2 * s * g**-1.5, -k2 * g**-1.5 + 3.0 * k2 * k2 * s * s * g**-2.5)


# ---------------------------------------------------------------------------------------------
# Elevation geometry in s = sin E
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class SineGeometry:
    """s = sin E = U / |p| and its rate ṡ from the ENU vector p and its rate ṗ (km, km/s),
    with their gradients: ``s_p`` = ds/dp = ∂ṡ/∂ṗ (N, 3) and ``sdot_p`` = ∂ṡ/∂p at fixed ṗ
    (N, 3), per km.

    .. math::

        \\frac{\\partial s}{\\partial p} = \\frac{\\hat z - s\\,\\hat p}{|p|},\\qquad
        \\frac{\\partial \\dot s}{\\partial p} = -\\frac{(\\hat p\\cdot\\dot p)\\,
        \\partial s/\\partial p + s\\,(\\dot p - (\\hat p\\cdot\\dot p)\\,\\hat p)/|p|
        + \\dot s\\,\\hat p}{|p|}
    """

    s: np.ndarray
    s_dot: np.ndarray
    s_p: np.ndarray
    sdot_p: np.ndarray

    @classmethod
    def from_enu(cls, p_enu_km, p_dot_enu_km_s) -> SineGeometry:
        p = np.asarray(p_enu_km, dtype=float)
        p_dot = np.asarray(p_dot_enu_km_s, dtype=float)
        rho = np.linalg.norm(p, axis=-1)[..., None]
        p_hat = p / rho
        s = p[..., 2] / rho[..., 0]
        radial = np.sum(p_hat * p_dot, axis=-1)
        s_dot = (p_dot[..., 2] - s * radial) / rho[..., 0]
        up = np.zeros_like(p)
        up[..., 2] = 1.0
        s_p = (up - s[..., None] * p_hat) / rho
        sdot_p = -(radial[..., None] * s_p
                   + s[..., None] * (p_dot - radial[..., None] * p_hat) / rho
                   + s_dot[..., None] * p_hat) / rho
        return cls(s, s_dot, s_p, sdot_p)


@dataclass(frozen=True, slots=True)
class LegMedia:
    """A leg's media terms at N times (km, km/s): the range delay and range-rate correction,
    their gradients w.r.t. the ENU vector p and its rate ṗ (N, 3) (``range_p``; ``rate_p``,
    ``rate_pdot``; the range delay does not depend on ṗ), and their partials w.r.t. the zenith
    parameters :data:`MEDIA_PARAMETER_NAMES` (N, 3)."""

    range_km: np.ndarray
    rate_km_s: np.ndarray
    range_p: np.ndarray
    rate_p: np.ndarray
    rate_pdot: np.ndarray
    range_zenith: np.ndarray
    rate_zenith: np.ndarray


#: The links a leg may be: the downlink (f_R), the uplink (f_T), or a two-way range taken
#: without light time (half the round trip: the mean of the two carriers' 1 / f²).
LINKS = ("down", "up", "two_way")


@dataclass(frozen=True, slots=True)
class MediaModel:
    """The troposphere and ionosphere of one station's links (module docstring).

    Attributes
    ----------
    zenith_dry_km, zenith_wet_km : float
        Nominal zenith hydrostatic and wet delays, km.
    zenith_tec_tecu : float
        Nominal zenith total electron content, TECU (1e16 electrons/m²).
    lat_rad, h_km : float
        The station's geodetic latitude (rad) and height (km).
    day_of_year : float
        Day of the year (UTC) at t = 0, 1.0 at 0h on 1 January; the Niell season follows
        t_s / 86400 from it.
    band : str
        The station's band (:data:`tapp.measurements.bands.BANDS`), the carriers f_T, f_R.
    troposphere, ionosphere : bool
        Which effects are on (an effect off adds nothing, and its partials are zero).
    shell_height_km : float
        Height of the ionosphere's thin shell, km.
    phase : bool
        The range of a phase-derived observable (count-based Doppler's ends): the ionosphere
        a phase advance, subtracted from the range as from the range-rate; False: a group
        delay on the range (ranging).
    """

    zenith_dry_km: float
    zenith_wet_km: float
    zenith_tec_tecu: float
    lat_rad: float
    h_km: float
    day_of_year: float
    band: str = DEFAULT_BAND
    troposphere: bool = True
    ionosphere: bool = True
    shell_height_km: float = SHELL_HEIGHT_km
    phase: bool = False

    @classmethod
    def from_meteorology(cls, lat_rad: float, h_km: float, day_of_year: float,
                         pressure_hpa: float, temperature_k: float, relative_humidity: float,
                         **kwargs) -> MediaModel:
        """Build with the zenith delays of Saastamoinen-Davis from the station's weather
        (hPa, K, fraction); ``kwargs`` are the other fields (TEC, band, switches)."""
        dry = zenith_hydrostatic_delay_m(pressure_hpa, lat_rad, h_km)
        wet = zenith_wet_delay_m(temperature_k,
                                 vapour_pressure_hpa(temperature_k, relative_humidity))
        return cls(float(dry) * 1e-3, float(wet) * 1e-3, lat_rad=lat_rad, h_km=h_km,
                   day_of_year=day_of_year, **kwargs)

    @property
    def zenith(self) -> np.ndarray:
        """The nominal zenith parameters, named by :data:`MEDIA_PARAMETER_NAMES`, (3,)."""
        return np.array([self.zenith_dry_km, self.zenith_wet_km, self.zenith_tec_tecu])

    def iono_km_per_tecu(self, link: str) -> float:
        """Return the zenith ionospheric delay per TECU, 40.3e16 / f² (SI) in km, at a link's
        carrier (:data:`LINKS`); 0 with the ionosphere off."""
        if not self.ionosphere:
            return 0.0
        band = BANDS[self.band]
        per_f2 = {"down": band.downlink_hz**-2, "up": band.uplink_hz**-2,
                  "two_way": 0.5 * (band.downlink_hz**-2 + band.uplink_hz**-2)}[link]
        return IONO_KM_HZ2_PER_TECU * per_f2

    def mappings(self, sin_e, t_s) -> tuple[Mapping, Mapping, Mapping]:
        """Return the (hydrostatic, wet, ionospheric) mapping functions at s = sin E, t_s."""
        doy = self.day_of_year + np.asarray(t_s, dtype=float) / 86400.0
        return (niell_hydrostatic(sin_e, self.lat_rad, doy, self.h_km),
                niell_wet(sin_e, self.lat_rad), single_layer(sin_e, self.shell_height_km))

    def leg(self, t_s, p_enu_km, p_dot_enu_km_s, link: str) -> LegMedia:
        """Return a leg's media terms (:class:`LegMedia`) from its station-to-spacecraft ENU
        vector p (N, 3) km and its rate ṗ (N, 3) km/s seen from the rotating Earth.

        Range: Z_h m_h + Z_w m_w ± κ TEC m_I (+ group delay, - with ``phase``); range-rate:
        (Z_h m_h' + Z_w m_w' - κ TEC m_I') ṡ, κ = :meth:`iono_km_per_tecu` (primes: d/ds).
        """
        geo = SineGeometry.from_enu(p_enu_km, p_dot_enu_km_s)
        maps = self.mappings(geo.s, t_s)
        tropo = 1.0 if self.troposphere else 0.0
        # The range delay's and the rate's coefficient of each mapping function (per zenith
        # unit), the ionosphere's sign flipped on the phase-derived rate.
        kappa = self.iono_km_per_tecu(link)
        unit_range = np.array([tropo, tropo, -kappa if self.phase else kappa])
        unit_rate = np.array([tropo, tropo, -kappa])
        m = np.stack([mp.m for mp in maps], axis=-1)
        m_s = np.stack([mp.m_s for mp in maps], axis=-1)
        m_ss = np.stack([mp.m_ss for mp in maps], axis=-1)
        range_zenith = m * unit_range
        rate_zenith = m_s * geo.s_dot[..., None] * unit_rate
        zenith = self.zenith
        k_s = m_s @ (unit_range * zenith)  # d range / ds
        k_rate_s = m_s @ (unit_rate * zenith)  # d rate / d ṡ
        k_rate_ss = m_ss @ (unit_rate * zenith)
        return LegMedia(
            range_km=range_zenith @ zenith, rate_km_s=rate_zenith @ zenith,
            range_p=k_s[..., None] * geo.s_p,
            rate_p=(k_rate_ss * geo.s_dot)[..., None] * geo.s_p + k_rate_s[..., None] * geo.sdot_p,
            rate_pdot=k_rate_s[..., None] * geo.s_p,
            range_zenith=range_zenith, rate_zenith=rate_zenith)
