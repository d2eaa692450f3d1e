"""Classical (Keplerian) elements <-> Cartesian state for every non-parabolic conic.

Element arrays are ``(..., 6)`` = ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]``:

- ellipse (0 <= e < 1): a > 0, M the mean anomaly (E - e sin E);
- hyperbola (e > 1): a < 0, M the hyperbolic mean anomaly (e sinh H - H), negative before
  periapsis;
- parabola (e = 1): not representable with a (a is infinite). Both conversions raise
  :class:`~tapp.errors.InputError` when |1 - e| < ``PARABOLIC_TOL``; near-parabolic orbits on
  either side are handled, with the accuracy loss noted in :func:`cartesian_to_elements`.

Special cases (as Vallado's rv2coe, Fundamentals of Astrodynamics and Applications, Algorithm 9,
but with the element slots kept, so that every output goes back through
:func:`elements_to_cartesian` to the same state):

==========================  =====================  ==============================================
case                        test                   returned
==========================  =====================  ==============================================
circular inclined           e < E_CIRCULAR_TOL     argp = 0, nu = argument of latitude u
elliptical equatorial       sin i < I_EQUAT._TOL   raan = 0, argp = longitude of periapsis
circular equatorial         both                   raan = argp = 0, nu = true longitude
==========================  =====================  ==============================================

Longitudes are measured from the x axis in the direction of motion (for a retrograde equatorial
orbit, i = pi, that is clockwise seen from +z, the convention under which the rotation
R3(-raan) R1(-i) R3(-argp) rebuilds the state). M is then the mean anomaly of that nu (equal
to it within 2e). Setting argp = 0 (or raan = 0) below the tolerance moves the rebuilt state by
at most about 2 e r (or r sin i), i.e. < 2e-13 r.

Frames: the inertial frame of the state (EME2000 in this project). Units: km, km/s, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.errors import DivergenceError, InputError

#: Below this eccentricity the periapsis direction is taken as undefined (circular orbit). A
#: circular state carries e ~ 1e-15 of rounding noise; the fallback moves the rebuilt state by
#: at most ~2 e r, so the threshold is kept just above the noise.
E_CIRCULAR_TOL = 1e-13
#: Below this sin(i) the node is taken as undefined (equatorial orbit); same reasoning.
I_EQUATORIAL_TOL = 1e-13
#: |1 - e| below this is a parabola, which these elements (a finite) cannot hold.
PARABOLIC_TOL = 1e-12
#: Newton stops when the anomaly step is below this times |anomaly| (relative convergence).
KEPLER_STEP_TOL = 4.0 * np.finfo(float).eps
KEPLER_MAX_ITERATIONS = 100


# ---------------------------------------------------------------------------------------------
# Anomalies
# ---------------------------------------------------------------------------------------------


def _kepler_newton(f_and_fprime, x0, what: str):
    """Vectorised Newton from a start above a root of an increasing convex f.

    In exact arithmetic every step is positive and the iterates decrease monotonically to the
    root. A step that is not positive (rounding noise once the root is reached) is not taken and
    ends that element's iteration, as does a step below KEPLER_STEP_TOL |x|. The callers
    evaluate f without cancellation (series for x - sin x and sinh x - x), so this stops
    cleanly even where f' is tiny (e -> 1 near periapsis).
    """
    x = np.array(x0, dtype=float)
    active = np.ones(x.shape, dtype=bool)
    for _ in range(KEPLER_MAX_ITERATIONS):
        f, fprime = f_and_fprime(x)
        step = f / fprime
        take = active & (step > 0.0)
        x = np.where(take, x - step, x)
        active = take & (step > KEPLER_STEP_TOL * np.abs(x))
        if not active.any():
            return x
    raise DivergenceError(
        f"Kepler solver ({what}): {int(active.sum())} of {active.size} anomalies unconverged",
        KEPLER_MAX_ITERATIONS,
    )


def _x_minus_sin_x(x):
    """Return x - sin x without cancellation: Taylor series for |x| < 1 (terms to x^19)."""
    x = np.asarray(x, dtype=float)
    x2 = x * x
    series = np.zeros_like(x)
    for k in range(8, -1, -1):  # x^3 sum_k (-1)^k x^(2k) / (2k+3)!, in Horner form
        series = (-1) ** k / math.factorial(2 * k + 3) + x2 * series
    return np.where(np.abs(x) < 1.0, x * x2 * series, x - np.sin(x))


def _sinh_x_minus_x(x):
    """Return sinh x - x without cancellation: Taylor series for |x| < 1 (terms to x^19)."""
    x = np.asarray(x, dtype=float)
    x2 = x * x
    series = np.zeros_like(x)
    for k in range(8, -1, -1):  # x^3 sum_k x^(2k) / (2k+3)!, in Horner form
        series = 1.0 / math.factorial(2 * k + 3) + x2 * series
    return np.where(np.abs(x) < 1.0, x * x2 * series, np.sinh(x) - x)


def mean_to_eccentric_anomaly(mean_anomaly_rad, e):
    """Return the eccentric anomaly E (rad) solving Kepler's equation M = E - e sin E.

    Parameters
    ----------
    mean_anomaly_rad : array_like, shape (...)
        Mean anomaly, rad, any value (E keeps the revolution count of M).
    e : array_like, shape (...)
        Eccentricity, 0 <= e < 1.

    Returns
    -------
    numpy.ndarray, shape (...)
        E, rad, with E - M in [-e, e].

    Notes
    -----
    M is reduced to m in [-pi, pi) and solved for |m| in [0, pi], where f(E) = E - e sin E - |m|
    is increasing and convex. Newton started at a point where f >= 0,
    E0 = min(|m| + e, (12 |m|)^(1/3), |m| / (1 - e), pi) (each term bounds the root from above:
    E - |m| <= e; E - e sin E >= E - sin E >= E^3/12 and >= (1 - e) E for E <= pi), then
    decreases monotonically to the root with no overshoot, for every e < 1 (including e -> 1,
    |m| -> 0); the last bound keeps the start within a factor of the root for tiny |m|, where a
    far start would cancel to zero. Vallado, Algorithm 2, with this start instead of Danby's.
    """
    m_all, e_b = np.broadcast_arrays(np.asarray(mean_anomaly_rad, float), np.asarray(e, float))
    # Reduce only when needed: pi + m would round away the low bits of a small m.
    m_red = np.where(
        np.abs(m_all) <= np.pi, m_all, np.remainder(m_all + np.pi, 2.0 * np.pi) - np.pi
    )
    m_abs = np.abs(m_red)
    start = np.minimum.reduce(
        [m_abs + e_b, np.cbrt(12.0 * m_abs), m_abs / (1.0 - e_b), np.full_like(m_abs, np.pi)]
    )

    one_minus_e = 1.0 - e_b

    def f_and_fprime(big_e):
        # E - e sin E = (1 - e) E + e (E - sin E) and 1 - e cos E = (1 - e) + 2 e sin^2(E/2):
        # no cancellation for e -> 1 near periapsis.
        f = one_minus_e * big_e + e_b * _x_minus_sin_x(big_e) - m_abs
        return f, one_minus_e + 2.0 * e_b * np.sin(0.5 * big_e) ** 2

    big_e = _kepler_newton(f_and_fprime, start, "elliptic")
    return np.sign(m_red) * big_e + (m_all - m_red)


def mean_to_hyperbolic_anomaly(mean_anomaly_rad, e):
    """Return the hyperbolic anomaly H (rad) solving M = e sinh H - H.

    Parameters
    ----------
    mean_anomaly_rad : array_like, shape (...)
        Hyperbolic mean anomaly, rad (negative before periapsis).
    e : array_like, shape (...)
        Eccentricity, e > 1.

    Notes
    -----
    For |M|, f(H) = e sinh H - H - |M| is increasing (f' = e cosh H - 1 > 0) and convex on
    H >= 0. Newton starts above the root, at min((6|M|)^(1/3), |M| / (e - 1), asinh(2|M|/e))
    (e sinh H - H >= H^3/6 and >= (e - 1) H; the last only for |M| >= 3, where
    asinh(2|M|/e) <= |M|), so it decreases monotonically to it without overshoot, also for
    e -> 1 where f'(0) = e - 1 -> 0. Vallado, Algorithm 4, with this start.
    """
    m_all, e_b = np.broadcast_arrays(np.asarray(mean_anomaly_rad, float), np.asarray(e, float))
    m_abs = np.abs(m_all)
    start = np.minimum(np.cbrt(6.0 * m_abs), m_abs / (e_b - 1.0))
    large = m_abs >= 3.0
    start = np.where(large, np.minimum(start, np.arcsinh(2.0 * m_abs / e_b)), start)

    e_minus_one = e_b - 1.0

    def f_and_fprime(big_h):
        # e sinh H - H = (e - 1) sinh H + (sinh H - H), e cosh H - 1 = (e - 1) + 2 e sinh^2(H/2).
        f = e_minus_one * np.sinh(big_h) + _sinh_x_minus_x(big_h) - m_abs
        return f, e_minus_one + 2.0 * e_b * np.sinh(0.5 * big_h) ** 2

    return np.sign(m_all) * _kepler_newton(f_and_fprime, start, "hyperbolic")


def eccentric_to_mean_anomaly(eccentric_anomaly_rad, e):
    """Return M = E - e sin E, rad (Kepler's equation), as (1 - e) E + e (E - sin E).

    The second form does not cancel for e -> 1 near periapsis.
    """
    big_e = np.asarray(eccentric_anomaly_rad, dtype=float)
    return (1.0 - e) * big_e + e * _x_minus_sin_x(big_e)


def hyperbolic_to_mean_anomaly(hyperbolic_anomaly_rad, e):
    """Return M = e sinh H - H, rad, as (e - 1) sinh H + (sinh H - H) (no cancellation)."""
    big_h = np.asarray(hyperbolic_anomaly_rad, dtype=float)
    return (e - 1.0) * np.sinh(big_h) + _sinh_x_minus_x(big_h)


def eccentric_to_true_anomaly(eccentric_anomaly_rad, e):
    """Return nu = 2 atan2(sqrt(1+e) sin(E/2), sqrt(1-e) cos(E/2)), rad, same revolution as E."""
    big_e = np.asarray(eccentric_anomaly_rad, dtype=float)
    half = 0.5 * big_e
    turns = np.round(big_e / (2.0 * np.pi))
    half = half - np.pi * turns
    nu = 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(half), np.sqrt(1.0 - e) * np.cos(half))
    return nu + 2.0 * np.pi * turns


def true_to_eccentric_anomaly(true_anomaly_rad, e):
    """Return E = 2 atan2(sqrt(1-e) sin(nu/2), sqrt(1+e) cos(nu/2)), rad, same revolution."""
    nu = np.asarray(true_anomaly_rad, dtype=float)
    turns = np.round(nu / (2.0 * np.pi))
    half = 0.5 * nu - np.pi * turns
    big_e = 2.0 * np.arctan2(np.sqrt(1.0 - e) * np.sin(half), np.sqrt(1.0 + e) * np.cos(half))
    return big_e + 2.0 * np.pi * turns


def hyperbolic_to_true_anomaly(hyperbolic_anomaly_rad, e):
    """Return nu = 2 atan(sqrt((e+1)/(e-1)) tanh(H/2)), rad, in (-nu_inf, nu_inf)."""
    big_h = np.asarray(hyperbolic_anomaly_rad, dtype=float)
    return 2.0 * np.arctan(np.sqrt((e + 1.0) / (e - 1.0)) * np.tanh(0.5 * big_h))


def true_to_hyperbolic_anomaly(true_anomaly_rad, e):
    """Return H = asinh(sqrt(e^2-1) sin nu / (1 + e cos nu)), rad (Vallado eq. 2-35).

    nu must lie inside the asymptotes, 1 + e cos nu > 0.
    """
    nu = np.asarray(true_anomaly_rad, dtype=float)
    return np.arcsinh(np.sqrt(e * e - 1.0) * np.sin(nu) / (1.0 + e * np.cos(nu)))


def mean_to_true_anomaly(mean_anomaly_rad, e):
    """Return the true anomaly nu (rad) of any non-parabolic conic, shape broadcast(M, e).

    Elliptic rows (e < 1) go through E and keep M's revolution count; hyperbolic rows (e > 1)
    through H. Raises :class:`InputError` for a parabola (|1 - e| < PARABOLIC_TOL).
    """
    m, e = np.broadcast_arrays(np.asarray(mean_anomaly_rad, float), np.asarray(e, float))
    _check_not_parabolic(e, "mean_to_true_anomaly")
    nu = np.empty(m.shape)
    ell = e < 1.0
    if ell.any():
        nu[ell] = eccentric_to_true_anomaly(mean_to_eccentric_anomaly(m[ell], e[ell]), e[ell])
    hyp = ~ell
    if hyp.any():
        nu[hyp] = hyperbolic_to_true_anomaly(mean_to_hyperbolic_anomaly(m[hyp], e[hyp]), e[hyp])
    return nu


def true_to_mean_anomaly(true_anomaly_rad, e):
    """Return the mean anomaly M (rad) of any non-parabolic conic, shape broadcast(nu, e).

    Elliptic M keeps the revolution count of nu; hyperbolic M is negative before periapsis.
    """
    nu, e = np.broadcast_arrays(np.asarray(true_anomaly_rad, float), np.asarray(e, float))
    _check_not_parabolic(e, "true_to_mean_anomaly")
    m = np.empty(nu.shape)
    ell = e < 1.0
    if ell.any():
        m[ell] = eccentric_to_mean_anomaly(true_to_eccentric_anomaly(nu[ell], e[ell]), e[ell])
    hyp = ~ell
    if hyp.any():
        m[hyp] = hyperbolic_to_mean_anomaly(true_to_hyperbolic_anomaly(nu[hyp], e[hyp]), e[hyp])
    return m


def _check_not_parabolic(e, source: str) -> None:
    parabolic = np.abs(1.0 - e) < PARABOLIC_TOL
    if parabolic.any():
        raise InputError(
            source,
            "e",
            f"a non-parabolic orbit, |1 - e| >= {PARABOLIC_TOL:g} (a parabola has no finite a; "
            f"{int(parabolic.sum())} of {parabolic.size} rows are parabolic)",
            float(np.asarray(e)[parabolic].flat[0]),
        )


# ---------------------------------------------------------------------------------------------
# Elements <-> Cartesian
# ---------------------------------------------------------------------------------------------


def _orientation(i_rad, raan_rad, argp_rad):
    """Return P, Q (periapsis and 90 deg ahead), each (..., 3): columns of R3(-W) R1(-i) R3(-w)."""
    ci, si = np.cos(i_rad), np.sin(i_rad)
    co, so = np.cos(raan_rad), np.sin(raan_rad)
    cw, sw = np.cos(argp_rad), np.sin(argp_rad)
    p_hat = np.stack([co * cw - so * sw * ci, so * cw + co * sw * ci, sw * si], -1)
    q_hat = np.stack([-co * sw - so * cw * ci, -so * sw + co * cw * ci, cw * si], -1)
    return p_hat, q_hat


def elements_to_cartesian(elements, mu_km3_s2: float = GM_EARTH_km3_s2):
    """Return the Cartesian state [r km, v km/s], shape (..., 6), of classical elements.

    .. math::

        p = a (1 - e^2),\\quad r = \\frac{p}{1 + e\\cos\\nu},\\quad
        \\mathbf r = r(\\cos\\nu\\,\\hat P + \\sin\\nu\\,\\hat Q),\\quad
        \\mathbf v = \\sqrt{\\mu/p}\\,(-\\sin\\nu\\,\\hat P + (e + \\cos\\nu)\\,\\hat Q)

    with [P Q W] = R3(-raan) R1(-i) R3(-argp) and nu from M (see :func:`mean_to_true_anomaly`).

    Parameters
    ----------
    elements : array_like, shape (..., 6)
        ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]`` (module docstring for the conventions).
    mu_km3_s2 : float
        Gravitational parameter, km^3/s^2.

    Raises
    ------
    InputError
        Parabolic rows, e < 0, or a whose sign does not match e (a > 0 needs e < 1).

    Notes
    -----
    Vallado, Fundamentals of Astrodynamics and Applications, Algorithm 10 (coe2rv), eqs. 2-110
    to 2-112 (4th ed. numbering). Special-case elements (circular, equatorial) need no branch:
    the formulas hold with argp = 0 and/or raan = 0.
    """
    el = np.asarray(elements, dtype=float)
    a, e, i, raan, argp, m = np.moveaxis(el, -1, 0)
    if (e < 0.0).any():
        raise InputError("elements_to_cartesian", "e", "e >= 0", float(e[e < 0.0].flat[0]))
    _check_not_parabolic(e, "elements_to_cartesian")
    wrong_sign = (a > 0.0) != (e < 1.0)
    if wrong_sign.any():
        raise InputError(
            "elements_to_cartesian",
            "a_km",
            "a > 0 for e < 1 and a < 0 for e > 1",
            float(a[wrong_sign].flat[0]),
        )
    nu = mean_to_true_anomaly(m, e)
    p = a * (1.0 - e * e)
    p_hat, q_hat = _orientation(i, raan, argp)
    cn, sn = np.cos(nu)[..., None], np.sin(nu)[..., None]
    r_mag = (p / (1.0 + e * np.cos(nu)))[..., None]
    r = r_mag * (cn * p_hat + sn * q_hat)
    v = np.sqrt(mu_km3_s2 / p)[..., None] * (-sn * p_hat + (e[..., None] + cn) * q_hat)
    return np.concatenate([r, v], axis=-1)


def _angle_in_plane(vec, n_hat, m_hat):
    """Angle of vec from n_hat towards m_hat, rad in [0, 2 pi)."""
    ang = np.arctan2(np.sum(vec * m_hat, -1), np.sum(vec * n_hat, -1))
    return np.mod(ang, 2.0 * np.pi)


def cartesian_to_elements(state, mu_km3_s2: float = GM_EARTH_km3_s2):
    """Return classical elements ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]``, shape (..., 6).

    .. math::

        \\mathbf h = \\mathbf r \\times \\mathbf v,\\quad
        \\mathbf e = \\frac{(v^2 - \\mu/r)\\,\\mathbf r - (\\mathbf r\\cdot\\mathbf v)\\,
        \\mathbf v}{\\mu},\\quad a = -\\frac{\\mu}{2\\varepsilon},\\quad
        \\varepsilon = \\frac{v^2}{2} - \\frac{\\mu}{r}

    Parameters
    ----------
    state : array_like, shape (..., 6)
        Position km and velocity km/s in an inertial frame.
    mu_km3_s2 : float
        Gravitational parameter, km^3/s^2.

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        i in [0, pi]; raan, argp in [0, 2 pi); elliptic M in [0, 2 pi); hyperbolic M real.
        Special cases as in the module docstring.

    Raises
    ------
    InputError
        For a parabola (|1 - e| < PARABOLIC_TOL) or a rectilinear state (h = 0).

    Notes
    -----
    Vallado, Fundamentals of Astrodynamics and Applications, Algorithm 9 (rv2coe), but angles
    come from atan2 in the orbit plane instead of arccos plus a quadrant test, which keeps full
    precision near 0 and pi. With node unit vector n = (cos raan, sin raan, 0) (raan = 0 when
    equatorial) and m = h_hat x n: u = atan2(r.m, r.n), argp = atan2(e.m, e.n) (0 when
    circular), nu = u - argp. Near e = 1, a (from the energy) and 1 - e carry relative errors
    ~ eps / |1 - e| from cancellation, which the state round trip does not feel; an element set
    without a (e.g. periapsis distance q) would be needed to hold them better.
    """
    x = np.asarray(state, dtype=float)
    r_vec, v_vec = x[..., :3], x[..., 3:]
    r = np.linalg.norm(r_vec, axis=-1)
    v2 = np.sum(v_vec * v_vec, -1)
    rv = np.sum(r_vec * v_vec, -1)
    h_vec = np.cross(r_vec, v_vec)
    h = np.linalg.norm(h_vec, axis=-1)
    if (h == 0.0).any():
        raise InputError("cartesian_to_elements", "state", "r x v != 0 (not rectilinear)", 0.0)
    h_hat = h_vec / h[..., None]
    e_vec = ((v2 - mu_km3_s2 / r)[..., None] * r_vec - rv[..., None] * v_vec) / mu_km3_s2
    e = np.linalg.norm(e_vec, axis=-1)
    _check_not_parabolic(e, "cartesian_to_elements")
    a = -mu_km3_s2 / (2.0 * (0.5 * v2 - mu_km3_s2 / r))

    h_xy = np.hypot(h_hat[..., 0], h_hat[..., 1])
    i = np.arctan2(h_xy, h_hat[..., 2])
    equatorial = h_xy < I_EQUATORIAL_TOL
    raan = np.where(equatorial, 0.0, np.mod(np.arctan2(h_hat[..., 0], -h_hat[..., 1]), 2 * np.pi))
    n_hat = np.stack([np.cos(raan), np.sin(raan), np.zeros_like(raan)], -1)
    m_hat = np.cross(h_hat, n_hat)
    u = _angle_in_plane(r_vec, n_hat, m_hat)
    circular = e < E_CIRCULAR_TOL
    argp = np.where(circular, 0.0, _angle_in_plane(e_vec, n_hat, m_hat))
    nu = np.mod(u - argp, 2.0 * np.pi)
    hyp = e > 1.0
    # A hyperbola's nu lies in (-nu_inf, nu_inf): move it from [0, 2 pi) to (-pi, pi].
    nu = np.where(hyp & (nu > np.pi), nu - 2.0 * np.pi, nu)
    m = true_to_mean_anomaly(nu, e)
    m = np.where(hyp, m, np.mod(m, 2.0 * np.pi))
    return np.stack([a, e, i, raan, argp, m], -1)


@dataclass(frozen=True, slots=True)
class Elements:
    """Classical osculating elements of one orbit (km, rad), conventions of this module.

    Attributes
    ----------
    a_km : float
        Semi-major axis, km (negative for a hyperbola).
    e : float
        Eccentricity.
    i_rad, raan_rad, argp_rad : float
        Inclination, right ascension of the ascending node, argument of periapsis, rad.
    M_rad : float
        Mean anomaly (hyperbolic mean anomaly when e > 1), rad.
    """

    a_km: float
    e: float
    i_rad: float
    raan_rad: float
    argp_rad: float
    M_rad: float

    @classmethod
    def from_degrees(
        cls, a_km: float, e: float, i_deg: float, raan_deg: float, argp_deg: float, M_deg: float
    ) -> Elements:
        """Build from angles in degrees (the form of scenario files)."""
        i, raan, argp, m = np.radians([i_deg, raan_deg, argp_deg, M_deg])
        return cls(float(a_km), float(e), float(i), float(raan), float(argp), float(m))

    @classmethod
    def from_array(cls, elements) -> Elements:
        """Build from ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]``, shape (6,)."""
        return cls(*(float(v) for v in np.asarray(elements, dtype=float).reshape(6)))

    @classmethod
    def from_cartesian(cls, state, mu_km3_s2: float = GM_EARTH_km3_s2) -> Elements:
        """Return the elements of one state (6,) [km, km/s] (see :func:`cartesian_to_elements`)."""
        return cls.from_array(cartesian_to_elements(np.asarray(state).reshape(6), mu_km3_s2))

    def to_array(self) -> np.ndarray:
        """Return ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]``, shape (6,)."""
        return np.array([self.a_km, self.e, self.i_rad, self.raan_rad, self.argp_rad, self.M_rad])

    def to_cartesian(self, mu_km3_s2: float = GM_EARTH_km3_s2) -> np.ndarray:
        """Return the state [r km, v km/s], shape (6,) (see :func:`elements_to_cartesian`)."""
        return elements_to_cartesian(self.to_array(), mu_km3_s2)

    @property
    def p_km(self) -> float:
        """Semi-latus rectum a (1 - e^2), km."""
        return self.a_km * (1.0 - self.e * self.e)

    @property
    def true_anomaly_rad(self) -> float:
        """True anomaly, rad."""
        return float(mean_to_true_anomaly(self.M_rad, self.e))

    def mean_motion_rad_s(self, mu_km3_s2: float = GM_EARTH_km3_s2) -> float:
        """Mean motion sqrt(mu / |a|^3), rad/s (M advances at this rate in two-body motion)."""
        return float(np.sqrt(mu_km3_s2 / abs(self.a_km) ** 3))

    def propagated(self, dt_s: float, mu_km3_s2: float = GM_EARTH_km3_s2) -> Elements:
        """Return the two-body elements dt_s seconds later (M advanced by n dt)."""
        m = self.M_rad + self.mean_motion_rad_s(mu_km3_s2) * dt_s
        return Elements(self.a_km, self.e, self.i_rad, self.raan_rad, self.argp_rad, m)


def kepler_states(elements, t_s, mu_km3_s2: float = GM_EARTH_km3_s2):
    """Return two-body states [r km, v km/s], shape (N, 6), at t_s (N,) seconds after elements.

    A closed-form Keplerian arc (mean anomaly advanced by sqrt(mu/|a|^3) t): the reference
    trajectory of tests and the light-time callback of simple scenarios.

    Parameters
    ----------
    elements : array_like, shape (6,)
        ``[a_km, e, i_rad, raan_rad, argp_rad, M_rad]`` at t = 0.
    t_s : array_like, shape (N,)
        Times, s.
    mu_km3_s2 : float
        Gravitational parameter, km^3/s^2.
    """
    el = np.asarray(elements, dtype=float).reshape(6)
    t = np.asarray(t_s, dtype=float)
    n_rad_s = np.sqrt(mu_km3_s2 / abs(el[0]) ** 3)
    arc = np.broadcast_to(el, t.shape + (6,)).copy()
    arc[..., 5] = el[5] + n_rad_s * t
    return elements_to_cartesian(arc, mu_km3_s2)
