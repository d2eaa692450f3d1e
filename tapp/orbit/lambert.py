r"""Lambert's problem: the two-body conic from r1 to r2 in a given time (zero revolutions).

Universal-variable formulation (R. R. Bate, D. D. Mueller, J. E. White, *Fundamentals of
Astrodynamics* (1971), section 5.3; H. D. Curtis, *Orbital Mechanics for Engineering
Students*, 3rd ed. (2014), Algorithm 5.2, whose names are kept). With the transfer angle
:math:`\Delta\nu` between r1 and r2, taken in the direction of motion about ``pole``
(prograde: :math:`(\mathbf r_1\times\mathbf r_2)\cdot\hat n > 0` means
:math:`\Delta\nu < \pi`),

.. math::

    A = \sin\Delta\nu\,\sqrt{\frac{r_1 r_2}{1-\cos\Delta\nu}},\qquad
    y(z) = r_1 + r_2 + A\,\frac{z\,S(z) - 1}{\sqrt{C(z)}},

    F(z) = \Big(\frac{y}{C}\Big)^{3/2} S + A\sqrt{y} - \sqrt{\mu}\,\Delta t = 0,

with the Stumpff functions S, C; z > 0 is an ellipse, z < 0 a hyperbola, and
:math:`z < 4\pi^2` keeps the transfer within one revolution. F increases with z, so its root
is bracketed and found by Brent's method. Then the Lagrange coefficients give the velocities:

.. math::

    f = 1 - \frac{y}{r_1},\quad g = A\sqrt{\frac{y}{\mu}},\quad \dot g = 1 - \frac{y}{r_2},
    \qquad \mathbf v_1 = \frac{\mathbf r_2 - f\,\mathbf r_1}{g},\quad
    \mathbf v_2 = \frac{\dot g\,\mathbf r_2 - \mathbf r_1}{g}.

Conditioning: at :math:`\Delta\nu = \pi` the plane of the transfer is undefined (A = 0 and
the out-of-plane part of v1 grows as :math:`1/\sin\Delta\nu`); positions closer than
:data:`MIN_SIN_TRANSFER` to collinear are refused. Frames: any inertial frame (the pole and
the positions in the same one). Units: km, km/s, s.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

from tapp.constants import C_LIGHT_km_s
from tapp.errors import InputError

#: |sin Δν| below this: r1 and r2 collinear, the transfer plane undefined (refused).
MIN_SIN_TRANSFER = 1e-6
#: Below |z| = 1 the Stumpff functions are summed as their series (no cancellation).
_SERIES_BELOW = 1.0
_SERIES_TERMS = 12
#: Just below the one-revolution limit z = 4π², where F -> +inf; C stays resolvable there.
_Z_HIGH = 4.0 * math.pi**2 * (1.0 - 1e-6)
#: Most negative z tried (sqrt(-z) = 600 keeps cosh finite); a flight that needs a root below
#: it is refused with the too-fast ones.
_Z_LOW = -600.0**2


def _stumpff(z: float) -> tuple[float, float]:
    """Return the Stumpff functions (S(z), C(z)) (Curtis eqs. 3.52, 3.53)."""
    if abs(z) < _SERIES_BELOW:
        # S = sum (-z)^k / (2k+3)!, C = sum (-z)^k / (2k+2)!
        s_sum = c_sum = 0.0
        s_term, c_term = 1.0 / 6.0, 0.5
        for k in range(_SERIES_TERMS):
            s_sum += s_term
            c_sum += c_term
            s_term *= -z / ((2 * k + 4) * (2 * k + 5))
            c_term *= -z / ((2 * k + 3) * (2 * k + 4))
        return s_sum, c_sum
    if z > 0.0:
        root = math.sqrt(z)
        return (root - math.sin(root)) / root**3, (1.0 - math.cos(root)) / z
    root = math.sqrt(-z)
    return (math.sinh(root) - root) / root**3, (math.cosh(root) - 1.0) / -z


def _vector(name: str, value: ArrayLike) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.any(v):
        raise InputError("lambert", name, "3 finite numbers, not all zero", v.tolist())
    return v


def lambert(r1_km: ArrayLike, r2_km: ArrayLike, tof_s: float, mu_km3_s2: float, *,
            pole: ArrayLike = (0.0, 0.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Return (v1, v2), km/s, shapes (3,): the zero-revolution conic from r1 to r2 in tof_s.

    Equations in the module docstring.

    Parameters
    ----------
    r1_km, r2_km : array_like, shape (3,)
        Departure and arrival positions relative to the attracting body, km, inertial.
    tof_s : float
        Time of flight, s, > 0.
    mu_km3_s2 : float
        Gravitational parameter of the attracting body, km^3/s^2, > 0.
    pole : array_like, shape (3,), optional
        Direction of the angular momentum of the transfer (default +z: prograde in the
        equator's frame); only its side of the plane of r1 and r2 matters.

    Raises
    ------
    InputError
        Positions that are not 3 finite numbers or are zero, collinear positions (the plane
        is undefined), a time of flight <= 0, or one that no zero-revolution conic matches
        (longer than the one-revolution limit, or so short that the conic would be faster
        than light).

    Examples
    --------
    Curtis (2014), Example 5.2: from (5000, 10000, 2100) km to (-14600, 2500, 7000) km in one
    hour about the Earth (printed answer v1 = (-5.9925, 1.9254, 3.2456) km/s):

    >>> v1, v2 = lambert([5000.0, 10000.0, 2100.0], [-14600.0, 2500.0, 7000.0], 3600.0,
    ...                  398600.0)
    >>> [round(float(c), 4) for c in v1]
    [-5.9925, 1.9254, 3.2456]
    """
    r1, r2, n_hat = _vector("r1_km", r1_km), _vector("r2_km", r2_km), _vector("pole", pole)
    if not (math.isfinite(tof_s) and tof_s > 0.0):
        raise InputError("lambert", "tof_s", "a finite time of flight > 0 (s)", tof_s)
    if not (math.isfinite(mu_km3_s2) and mu_km3_s2 > 0.0):
        raise InputError("lambert", "mu_km3_s2", "a finite GM > 0 (km^3/s^2)", mu_km3_s2)
    n1, n2 = float(np.linalg.norm(r1)), float(np.linalg.norm(r2))
    normal = np.cross(r1, r2)
    sin_abs = float(np.linalg.norm(normal)) / (n1 * n2)
    if sin_abs < MIN_SIN_TRANSFER:
        raise InputError("lambert", "r2_km", "a position not collinear with r1_km (a transfer "
                         "of 0 or 180 deg has no defined plane)", f"|sin dnu| = {sin_abs:.2e}")
    cos_dnu = float(np.clip(np.dot(r1, r2) / (n1 * n2), -1.0, 1.0))
    sin_dnu = sin_abs if float(np.dot(normal, n_hat)) >= 0.0 else -sin_abs
    a = sin_dnu * math.sqrt(n1 * n2 / (1.0 - cos_dnu))
    root_mu_t = math.sqrt(mu_km3_s2) * tof_s

    def y_of(z: float) -> float:
        s, c = _stumpff(z)
        return n1 + n2 + a * (z * s - 1.0) / math.sqrt(c)

    def f_of(z: float) -> float:
        y = y_of(z)
        if y < 0.0:  # only for A > 0, below the root: F is continuous at y = 0 with this value
            return -root_mu_t
        s, c = _stumpff(z)
        return (y / c) ** 1.5 * s + a * math.sqrt(y) - root_mu_t

    if f_of(_Z_HIGH) <= 0.0:
        raise InputError("lambert", "tof_s", "a time of flight within one revolution of the "
                         "transfer conic", tof_s)
    low = -1.0
    while f_of(low) > 0.0 and low > _Z_LOW:  # F < 0 far enough down (A > 0: y < 0; A < 0:
        low = max(4.0 * low, _Z_LOW)          # A sqrt(y) -> -inf)
    v1 = v2 = np.full(3, np.inf)
    if f_of(low) <= 0.0:
        z = brentq(f_of, low, _Z_HIGH, xtol=1e-14, rtol=4.0 * np.finfo(float).eps,
                   maxiter=500)
        y = y_of(z)
        if y > 0.0:  # y -> 0 only for absurdly short flights
            f, g, g_dot = 1.0 - y / n1, a * math.sqrt(y / mu_km3_s2), 1.0 - y / n2
            v1, v2 = (r2 - f * r1) / g, (g_dot * r2 - r1) / g
    speed = max(float(np.linalg.norm(v1)), float(np.linalg.norm(v2)))
    if not speed < C_LIGHT_km_s:
        raise InputError("lambert", "tof_s", "a time of flight that a conic flies below the "
                         "speed of light", f"{tof_s:g} s, needing {speed:.3g} km/s")
    return v1, v2
