r"""B-plane parameters of a hyperbolic approach: B·T, B·R, LTOF and their velocity Jacobian.

The B-plane (Kizner 1961) passes through the target body's centre, perpendicular to the
incoming asymptote direction :math:`\hat S`. :math:`\hat T` lies in a chosen reference plane
and :math:`\hat R` completes the right-handed triad:

.. math::

    \hat T = \frac{\hat S \times \hat N}{|\hat S \times \hat N|}, \qquad
    \hat R = \hat S \times \hat T

with :math:`\hat N` the pole (unit normal) of the reference plane: the Earth's mean equator of
J2000 (the EME2000 z axis, as nyx does with the frame's z axis), the ecliptic of J2000, or the
target body's equator given by its pole (by name ``"body_equator"`` in the files and programs,
:data:`REFERENCE_PLANES`, which resolve it to a pole vector at the evaluation time:
:meth:`tapp.targeting.program.BPlaneProgram.reference_pole`). The B vector points from the
body's centre to where the incoming asymptote pierces the B-plane; its length is the impact
parameter :math:`b = |a|\sqrt{e^2 - 1} = h / v_\infty`.

Everything is computed from the two-body state relative to the target body, in km, km/s and s
(STYLE section 3). Arrays broadcast over leading axes: positions and velocities are (..., 3),
scalars come back with shape (...).

References
----------
W. Kizner, "A method of describing miss distances for lunar and interplanetary trajectories",
Planetary and Space Science 7 (1961) 125-131 (the B-plane and its T, R axes).
D. A. Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed. (2013), ch. 2 (the
eccentricity vector, the hyperbolic Kepler equation, the flight-path angle
:math:`\cos\phi_{fpa} = h / (r v)` from the local horizontal, and the vis-viva energy).
J. H. Lieske et al., "Expressions for the precession quantities based upon the IAU (1976)
system of astronomical constants", A&A 58 (1977) 1-16 (obliquity of the ecliptic at J2000).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tapp.errors import InputError, NotHyperbolicError

# Mean obliquity of the ecliptic at J2000, IAU 1976 value (Lieske et al. 1977, A&A 58, 1):
# 23 deg 26' 21.448" = 84381.448 arcsec.
OBLIQUITY_J2000_IAU1976_arcsec = 84381.448
OBLIQUITY_J2000_IAU1976_rad = OBLIQUITY_J2000_IAU1976_arcsec * np.pi / (180.0 * 3600.0)

#: Pole of the Earth's mean equator of J2000 (EME2000 z axis), in EME2000.
EARTH_EQUATOR_POLE_EME2000 = np.array([0.0, 0.0, 1.0])
EARTH_EQUATOR_POLE_EME2000.setflags(write=False)

#: Pole of the ecliptic of J2000 in EME2000: the EME2000 z axis rotated about x by the
#: obliquity, (0, -sin eps, cos eps).
ECLIPTIC_POLE_EME2000 = np.array(
    [0.0, -np.sin(OBLIQUITY_J2000_IAU1976_rad), np.cos(OBLIQUITY_J2000_IAU1976_rad)]
)
ECLIPTIC_POLE_EME2000.setflags(write=False)

#: Reference planes selectable by name in :func:`b_plane`.
REFERENCE_POLES = {"earth_equator": EARTH_EQUATOR_POLE_EME2000, "ecliptic": ECLIPTIC_POLE_EME2000}
#: The target body's own equator: its pole moves with time, so the programs that know the body
#: and the time pass it to :func:`b_plane` as a vector.
BODY_EQUATOR = "body_equator"
#: Reference planes a file or a program may name: the fixed ones and the body's equator.
REFERENCE_PLANES = (*REFERENCE_POLES, BODY_EQUATOR)

# The Jacobian is taken by complex step: df/dv_k = Im f(v + i h e_k) / h, exact to rounding
# for any h small enough that h^2 terms vanish (Squire & Trapp 1998, SIAM Review 40, 110).
_COMPLEX_STEP_km_s = 1e-20

# T-hat is undefined when S-hat is parallel to the reference pole; refuse angles below this.
_MIN_S_POLE_ANGLE_rad = 1e-6


def pole_from_ra_dec(ra_rad: ArrayLike, dec_rad: ArrayLike) -> np.ndarray:
    r"""Return the unit pole vector (..., 3) from its right ascension and declination (rad).

    .. math:: \hat N = (\cos\alpha\cos\delta,\ \sin\alpha\cos\delta,\ \sin\delta)

    Use it with the IAU WGCCRE pole (alpha_0, delta_0) of a target body to take its equator as
    the B-plane reference plane (Archinal et al. 2018, Celest. Mech. Dyn. Astron. 130:22).
    The result is in the frame the angles refer to (ICRF/EME2000 for WGCCRE poles).
    """
    ra = np.asarray(ra_rad, dtype=np.float64)
    dec = np.asarray(dec_rad, dtype=np.float64)
    return np.stack(
        np.broadcast_arrays(np.cos(ra) * np.cos(dec), np.sin(ra) * np.cos(dec), np.sin(dec)),
        axis=-1,
    )


@dataclass(frozen=True, slots=True)
class BPlane:
    r"""B-plane parameters of one or many hyperbolic states; shapes (...) or (..., 3).

    Attributes
    ----------
    s_hat, t_hat, r_hat : numpy.ndarray, shape (..., 3)
        Unit vectors of the B-plane triad, in the frame of the input state.
    b_vec_km : numpy.ndarray, shape (..., 3)
        B vector, km: :math:`\mathbf B = \hat S \times \mathbf h / v_\infty`.
    b_dot_t_km, b_dot_r_km : numpy.ndarray, shape (...)
        B·T and B·R, km.
    b_mag_km : numpy.ndarray, shape (...)
        |B| = b, the impact parameter, km.
    b_angle_rad : numpy.ndarray, shape (...)
        atan2(B·R, B·T), rad, in (-pi, pi].
    ltof_s : numpy.ndarray, shape (...)
        Linearised time of flight, s: :math:`-\mathbf r\cdot\hat S / v_\infty` (see
        :func:`b_plane`, Notes, for the definition and its conditioning).
    time_to_periapsis_s : numpy.ndarray, shape (...)
        Two-body time from the state to periapsis, s (negative after periapsis).
    v_inf_km_s : numpy.ndarray, shape (...)
        Hyperbolic excess speed, km/s: :math:`\sqrt{2\varepsilon}`.
    eccentricity : numpy.ndarray, shape (...)
        e > 1.
    periapsis_radius_km : numpy.ndarray, shape (...)
        :math:`r_p = \mu (e - 1) / v_\infty^2`, km.
    jacobian_v : numpy.ndarray, shape (..., 3, 3)
        :math:`\partial(B\cdot R, B\cdot T, \mathrm{LTOF}) / \partial(v_x, v_y, v_z)` at fixed
        position: rows 1-2 in km/(km/s) = s, row 3 in s/(km/s). Row order (B·R, B·T, LTOF)
        is nyx's ``BPlane::jacobian``.
    """

    s_hat: np.ndarray
    t_hat: np.ndarray
    r_hat: np.ndarray
    b_vec_km: np.ndarray
    b_dot_t_km: np.ndarray
    b_dot_r_km: np.ndarray
    b_mag_km: np.ndarray
    b_angle_rad: np.ndarray
    ltof_s: np.ndarray
    time_to_periapsis_s: np.ndarray
    v_inf_km_s: np.ndarray
    eccentricity: np.ndarray
    periapsis_radius_km: np.ndarray
    jacobian_v: np.ndarray


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # Not np.linalg.norm / abs: those are not complex-analytic and would break the complex step.
    return np.sum(a * b, axis=-1)


def _energy_and_e_vec(r: np.ndarray, v: np.ndarray, mu: np.ndarray):
    """Specific energy (km^2/s^2) and eccentricity vector: e = ((v^2 - mu/r) r - (r.v) v) / mu."""
    r_mag = np.sqrt(_dot(r, r))
    v2 = _dot(v, v)
    energy = 0.5 * v2 - mu / r_mag
    e_vec = ((v2 - mu / r_mag)[..., None] * r - _dot(r, v)[..., None] * v) / mu[..., None]
    return energy, e_vec


def _asymptote(r: np.ndarray, v: np.ndarray, mu: np.ndarray):
    """Return (energy, e_vec, e, v_inf, h, s_hat); complex-analytic in v. Shapes as _core."""
    energy, e_vec = _energy_and_e_vec(r, v, mu)
    h = np.cross(r, v)  # km^2/s
    e2 = _dot(e_vec, e_vec)
    v_inf = np.sqrt(2.0 * energy)
    # Incoming asymptote: S = e_hat / e + sqrt(1 - 1/e^2) (h_hat x e_hat). With
    # v_inf h / mu = sqrt(e^2 - 1) this is S = (e_vec + (v_inf / mu) h x e_vec) / e^2, which
    # needs no division by h (and no unit vector of h).
    s_hat = (e_vec + (v_inf / mu)[..., None] * np.cross(h, e_vec)) / e2[..., None]
    return energy, e_vec, np.sqrt(e2), v_inf, h, s_hat


def _core(r: np.ndarray, v: np.ndarray, mu: np.ndarray, pole: np.ndarray):
    """Two-body B-plane quantities; complex-analytic in v so it serves the complex step.

    Shapes: r, v (..., 3); mu (...); pole (..., 3). Returns a dict of arrays.
    """
    energy, e_vec, ecc, v_inf, h, s_hat = _asymptote(r, v, mu)
    # B = b (S x h_hat) with b = h / v_inf, i.e. B = S x h / v_inf.
    b_vec = np.cross(s_hat, h) / v_inf[..., None]
    t_vec = np.cross(s_hat, pole)
    t_hat = t_vec / np.sqrt(_dot(t_vec, t_vec))[..., None]
    r_hat = np.cross(s_hat, t_hat)
    # Hyperbolic anomaly F from r.v = sqrt(mu |a|) e sinh F, |a| = mu / v_inf^2; F < 0 inbound.
    sinh_f = _dot(r, v) * v_inf / (mu * ecc)
    f_anom = np.arcsinh(sinh_f)
    # Hyperbolic Kepler equation: time since periapsis (e sinh F - F) / n, n = v_inf^3 / mu.
    time_to_periapsis = (f_anom - ecc * sinh_f) * mu / v_inf**3
    return {
        "ecc": ecc,
        "v_inf": v_inf,
        "s_hat": s_hat,
        "t_hat": t_hat,
        "r_hat": r_hat,
        "b_vec": b_vec,
        "b_dot_t": _dot(b_vec, t_hat),
        "b_dot_r": _dot(b_vec, r_hat),
        "ltof": -_dot(r, s_hat) / v_inf,
        "time_to_periapsis": time_to_periapsis,
    }


def _state_array(name: str, value: ArrayLike) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.ndim < 1 or a.shape[-1] != 3:
        raise InputError("b_plane", name, "an array of shape (..., 3)", a.shape)
    if not np.all(np.isfinite(a)):
        raise InputError("b_plane", name, "finite values", a.tolist())
    return a


def b_plane(
    r_km: ArrayLike,
    v_km_s: ArrayLike,
    gm_km3_s2: ArrayLike,
    *,
    reference: str | ArrayLike = "earth_equator",
) -> BPlane:
    r"""Return the B-plane parameters (km, s) of a hyperbolic state relative to the target body.

    .. math::

        \mathbf e = \frac{(v^2 - \mu/r)\,\mathbf r - (\mathbf r\cdot\mathbf v)\,\mathbf v}{\mu},
        \quad v_\infty = \sqrt{v^2 - 2\mu/r},

        \hat S = \frac{\mathbf e + (v_\infty/\mu)\,\mathbf h\times\mathbf e}{e^2}, \quad
        \mathbf B = \frac{\hat S\times\mathbf h}{v_\infty}, \quad
        \hat T = \frac{\hat S\times\hat N}{|\hat S\times\hat N|}, \quad
        \hat R = \hat S\times\hat T,

        \mathrm{LTOF} = -\frac{\mathbf r\cdot\hat S}{v_\infty}, \qquad
        t_p = \frac{\mu}{v_\infty^3}\,(F - e\sinh F), \quad
        \sinh F = \frac{(\mathbf r\cdot\mathbf v)\, v_\infty}{\mu e}

    Parameters
    ----------
    r_km : array_like, shape (..., 3)
        Position relative to the target body's centre, km.
    v_km_s : array_like, shape (..., 3)
        Velocity relative to the target body, km/s; broadcasts with ``r_km``.
    gm_km3_s2 : array_like, shape (...)
        Gravitational parameter of the target body, km^3/s^2, > 0 (e.g.
        ``tapp.constants.GM_km3_s2["mars"]``).
    reference : {"earth_equator", "ecliptic"} or array_like of shape (..., 3), optional
        Reference plane for T-hat, by name or by its pole in the frame of the state:
        ``"earth_equator"``: EME2000 xy-plane (pole (0, 0, 1)), the default, as nyx (z axis
        of the state's frame); ``"ecliptic"``: ecliptic of J2000 with the IAU 1976 obliquity
        (state in EME2000); a vector: the pole of any plane, e.g. a body's equator from
        :func:`pole_from_ra_dec` or :func:`tapp.dynamics.poles.equator_pole` at the time of
        the state (normalised here). ``"body_equator"`` needs the body and the time, so the
        programs resolve it to that vector (the name is refused here).

    Returns
    -------
    BPlane
        Frozen result; see its attributes for units and shapes.

    Raises
    ------
    NotHyperbolicError
        If any state has e <= 1 or specific energy <= 0; the message gives e and the energy
        (km^2/s^2) of the first such state and its index.
    InputError
        For arrays of the wrong shape, non-finite values, a GM <= 0, an unknown reference
        name, or an S-hat within 1e-6 rad of the reference pole (T-hat undefined).

    Notes
    -----
    **Linearised time of flight.** LTOF is the time to closest approach of the *rectilinear*
    motion that replaces the hyperbola by its asymptote, as in Kizner's linearisation: a body
    at r moving at v_inf along S-hat reaches the B-plane (its closest approach) after
    :math:`-\mathbf r\cdot\hat S / v_\infty`. With F the hyperbolic anomaly it is related
    exactly to the two-body time to periapsis :math:`t_p` by

    .. math:: \mathrm{LTOF} - t_p = \frac{\mu}{v_\infty^3}\left(\frac{e^F}{e} - 1 - F\right)

    (derived from the perifocal state; tested). On approach F -> -inf, so the difference grows
    like :math:`(\mu/v_\infty^3)\ln(2r/(e|a|))`: LTOF is a far-field proxy for the arrival time
    that is not the time to periapsis, and at periapsis it equals
    :math:`(\mu/v_\infty^3)(1/e - 1) < 0`. nyx (``cosmic/bplane.rs``) writes LTOF as
    :math:`\mathbf B\cdot\hat S/|\mathbf v|`, which is identically zero since B is perpendicular
    to S; ODTBX (``bplane.m``) subtracts two Kepler times. Compare definitions before
    comparing numbers.

    **Ill-conditioning of LTOF (read before targeting it).** (1) LTOF and B are nearly
    decoupled in velocity far from the body (LTOF moves with the speed along S, B with the
    transverse components), but their rows have different units (s/(km/s) vs km/(km/s)), so
    the 3x3 Jacobian's condition number is meaningful only after scaling each row by its
    tolerance. (2) :math:`\partial\,\mathrm{LTOF}/\partial v` scales as
    :math:`r/v_\infty^2` and blows up as e -> 1+ (v_inf -> 0), where S-hat itself is
    ill-defined. (3) Targeting LTOF with a two-body Jacobian on a perturbed trajectory is
    "historically super finicky" (nyx ``BPlane::ltof``); nyx recommends cascading a B·R/B·T
    search with a separate time search instead.

    The Jacobian is taken by complex step in v (exact to rounding; Squire & Trapp 1998) and is
    tested against central differences.
    """
    r = _state_array("r_km", r_km)
    v = _state_array("v_km_s", v_km_s)
    mu = np.asarray(gm_km3_s2, dtype=np.float64)
    if not np.all(np.isfinite(mu) & (mu > 0.0)):
        raise InputError("b_plane", "gm_km3_s2", "a finite GM > 0 in km^3/s^2", mu.tolist())
    if isinstance(reference, str):
        if reference not in REFERENCE_POLES:
            raise InputError(
                "b_plane",
                "reference",
                f"one of {sorted(REFERENCE_POLES)} or a pole vector (for the body's equator: "
                "its pole at the state's time, tapp.dynamics.poles.equator_pole)",
                reference,
            )
        pole = REFERENCE_POLES[reference]
    else:
        pole = _state_array("reference", reference)
        pole_norm = np.sqrt(_dot(pole, pole))
        if np.any(pole_norm == 0.0):
            raise InputError("b_plane", "reference", "a non-zero pole vector", pole.tolist())
        pole = pole / pole_norm[..., None]

    shape = np.broadcast_shapes(r.shape, v.shape, mu.shape + (3,), pole.shape)
    r = np.broadcast_to(r, shape)
    v = np.broadcast_to(v, shape)
    mu = np.broadcast_to(mu, shape[:-1])
    pole = np.broadcast_to(pole, shape)

    # Hyperbolic check before any square root of a negative energy.
    if np.any(_dot(r, r) == 0.0):
        raise InputError("b_plane", "r_km", "a position away from the body's centre", "|r| = 0")
    energy, e_vec = _energy_and_e_vec(r, v, mu)
    ecc = np.linalg.norm(e_vec, axis=-1)
    bad = ~((ecc > 1.0) & (energy > 0.0))
    if np.any(bad):
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        raise NotHyperbolicError(
            f"B-plane needs a hyperbolic state (e > 1, energy > 0); state {first} has "
            f"e = {float(ecc[first]):.12g}, energy = {float(energy[first]):.6g} km^2/s^2 "
            f"({int(np.count_nonzero(bad))} of {bad.size} states are not hyperbolic)"
        )

    s_hat = _asymptote(r, v, mu)[-1]
    s_pole_sin = np.linalg.norm(np.cross(s_hat, pole), axis=-1)
    if np.any(s_pole_sin < _MIN_S_POLE_ANGLE_rad):
        first = tuple(int(i) for i in np.argwhere(s_pole_sin < _MIN_S_POLE_ANGLE_rad)[0])
        raise InputError(
            "b_plane",
            "reference",
            "a reference pole not parallel to the incoming asymptote S (T-hat is undefined)",
            f"angle {float(np.arcsin(s_pole_sin[first])):.3e} rad at state {first}",
        )

    q = _core(r, v, mu, pole)
    # Complex step: one evaluation per velocity component, stacked on a new axis (..., 3, 3)
    # whose second-to-last axis k is the perturbed component.
    v_cs = v[..., None, :] + 1j * _COMPLEX_STEP_km_s * np.eye(3)
    q_cs = _core(r[..., None, :], v_cs, mu[..., None], pole[..., None, :])
    rows = np.stack([q_cs["b_dot_r"], q_cs["b_dot_t"], q_cs["ltof"]], axis=-2)
    jacobian = rows.imag / _COMPLEX_STEP_km_s

    b_dot_t = q["b_dot_t"]
    b_dot_r = q["b_dot_r"]
    return BPlane(
        s_hat=q["s_hat"],
        t_hat=q["t_hat"],
        r_hat=q["r_hat"],
        b_vec_km=q["b_vec"],
        b_dot_t_km=b_dot_t,
        b_dot_r_km=b_dot_r,
        b_mag_km=np.sqrt(b_dot_t**2 + b_dot_r**2),
        b_angle_rad=np.arctan2(b_dot_r, b_dot_t),
        ltof_s=q["ltof"],
        time_to_periapsis_s=q["time_to_periapsis"],
        v_inf_km_s=q["v_inf"],
        eccentricity=q["ecc"],
        periapsis_radius_km=mu * (q["ecc"] - 1.0) / q["v_inf"] ** 2,
        jacobian_v=jacobian,
    )


def entry_flight_path_angle(
    r_km: ArrayLike, v_km_s: ArrayLike, gm_km3_s2: ArrayLike, entry_radius_km: ArrayLike
) -> np.ndarray:
    r"""Return the flight-path angle (rad, shape (...)) where the incoming two-body conic of a
    state crosses the sphere of radius ``entry_radius_km`` about the body's centre.

    The flight-path angle :math:`\gamma` is the angle from the local horizontal (the plane
    perpendicular to :math:`\mathbf r`) to the velocity, negative while the distance decreases
    (Vallado 2013, ch. 2: :math:`\cos\phi_{fpa} = h / (r v)`). The angular momentum h and the
    energy are constants of the conic, so at the interface radius :math:`r_e`

    .. math::

        h = |\mathbf r\times\mathbf v|, \qquad
        v_\infty^2 = v^2 - \frac{2\mu}{r}, \qquad
        v_e = \sqrt{v_\infty^2 + \frac{2\mu}{r_e}}, \qquad
        \gamma_e = -\arccos\frac{h}{r_e v_e}

    (vis-viva for :math:`v_e`; the minus sign takes the incoming branch, whatever the sign of
    :math:`\mathbf r\cdot\mathbf v` of the state). The conic reaches :math:`r_e` if and only
    if its periapsis radius :math:`r_p \le r_e`: :math:`(r v)^2 = v_\infty^2 r^2 + 2\mu r`
    grows with r and equals :math:`h^2` at periapsis. At :math:`r_p = r_e` the angle is 0.

    Parameters
    ----------
    r_km, v_km_s : array_like, shape (..., 3)
        Position (km) and velocity (km/s) relative to the body's centre.
    gm_km3_s2 : array_like, shape (...)
        The body's GM, km^3/s^2, > 0.
    entry_radius_km : array_like, shape (...)
        Radius of the atmosphere interface, km: > 0 and below the state's distance.

    Raises
    ------
    InputError
        Shapes or non-finite values as :func:`b_plane`; an entry radius <= 0 or not below the
        state's distance; a conic whose periapsis is above the entry radius (it does not
        enter; the message gives the periapsis radius, km, of the first such state).
    """
    r = _state_array("r_km", r_km)
    v = _state_array("v_km_s", v_km_s)
    mu = np.asarray(gm_km3_s2, dtype=np.float64)
    r_e = np.asarray(entry_radius_km, dtype=np.float64)
    if not np.all(np.isfinite(mu) & (mu > 0.0)):
        raise InputError("entry_flight_path_angle", "gm_km3_s2", "a finite GM > 0 in km^3/s^2",
                         mu.tolist())
    shape = np.broadcast_shapes(r.shape, v.shape, mu.shape + (3,), r_e.shape + (3,))
    r, v = np.broadcast_to(r, shape), np.broadcast_to(v, shape)
    mu, r_e = np.broadcast_to(mu, shape[:-1]), np.broadcast_to(r_e, shape[:-1])
    r_mag = np.sqrt(_dot(r, r))
    if not np.all(np.isfinite(r_e) & (r_e > 0.0) & (r_e < r_mag)):
        raise InputError("entry_flight_path_angle", "entry_radius_km",
                         "a finite radius > 0 km below the state's distance from the centre",
                         f"{r_e.tolist()} km at distances {r_mag.tolist()} km")
    h_vec = np.cross(r, v)
    h2 = _dot(h_vec, h_vec)
    v_e = np.sqrt(_dot(v, v) + 2.0 * mu * (1.0 / r_e - 1.0 / r_mag))
    cos_gamma = np.sqrt(h2) / (r_e * v_e)
    misses = cos_gamma > 1.0
    if np.any(misses):
        first = tuple(int(i) for i in np.argwhere(misses)[0])
        e_vec = _energy_and_e_vec(r, v, mu)[1][first]
        r_p = h2[first] / (mu[first] * (1.0 + np.sqrt(e_vec @ e_vec)))  # p / (1 + e), p = h^2/mu
        raise InputError("entry_flight_path_angle", "entry_radius_km",
                         "a radius at or above the conic's periapsis radius (else it does not "
                         "enter)", f"{r_e[first]:.3f} km, periapsis radius {r_p:.3f} km at "
                         f"state {first}")
    return -np.arccos(cos_gamma)
