"""Force models as CasADi symbolic expressions; their Jacobians come from differentiation.

Central field: the geopotential of a body of gravitational parameter GM and reference radius R,

.. math::
    U(\\mathbf r) = \\frac{GM}{R} \\sum_{n=0}^{N} \\sum_{m=0}^{\\min(n, M)}
        \\left(\\bar C_{nm} \\bar V_{nm} + \\bar S_{nm} \\bar W_{nm}\\right),

with the fully normalised solid harmonics \\bar V_{nm}, \\bar W_{nm} of the Earth-fixed position
built by the Cunningham recursion in Cartesian coordinates (Montenbruck & Gill, *Satellite
Orbits*, 2000, eqs. 3.27-3.31), normalised with N_nm = sqrt((2-δ_m0)(2n+1)(n-m)!/(n+m)!) so
the recursion factors stay O(1) at any degree:

.. math::
    \\bar V_{mm} = \\sqrt{k_m\\frac{2m+1}{2m}}\\,\\frac{R}{r^2}
        (x \\bar V_{m-1,m-1} - y \\bar W_{m-1,m-1}),\\quad k_1 = 2,\\ k_{m>1} = 1,

    \\bar V_{nm} = \\sqrt{\\frac{(2n-1)(2n+1)}{(n-m)(n+m)}}\\,\\frac{zR}{r^2}\\bar V_{n-1,m}
        - \\sqrt{\\frac{(2n+1)(n+m-1)(n-m-1)}{(2n-3)(n+m)(n-m)}}\\,\\frac{R^2}{r^2}\\bar V_{n-2,m}

(the same for \\bar W), \\bar V_{00} = R/r, \\bar W_{00} = 0. The acceleration is ∇U, taken
by CasADi. The Earth-fixed position is r_f = M(t) r with M the inertial → Earth-fixed rotation
of the model's ``earth_orientation`` (:mod:`tapp.frames.orientation`): for ``"iau2006"`` the
full W R3(ERA) C, built symbolically from the Chebyshev series of its slow terms (X, Y, s,
x_p, y_p, s', UT1 drift Δ) that the driver evaluates beside the ephemeris, with
ERA = ERA_0 + ω_ERA (t + Δ); for ``"gmst"`` R3(θ0 + ω_E t) with tesserals and the identity for a
zonal field (symmetric about the inertial z axis). U(M r) with M orthogonal gives
∇_r U = Mᵀ ∇_f U: the gradient w.r.t. the inertial position is already the inertial
acceleration.

The Moon, Mars and Venus have their zonal J2 only (:data:`tapp.constants.J2_CENTRE`, the same
potential with \\bar C_{20} = -J2/\\sqrt 5 and the field's radius), about the body's IAU
pole k(t) in inertial axes (:mod:`tapp.dynamics.poles`), which the driver evaluates beside the
ephemeris: r_fixed = (0, 0, k·r) and r² = |r|², that is

.. math::
    U = \\frac{GM}{r}\\left(1 - J_2 \\left(\\frac{R}{r}\\right)^2
        \\frac{3 (\\hat r\\cdot k)^2 - 1}{2}\\right),\\quad
    \\mathbf a = \\nabla U = -\\frac{GM}{r^2}\\hat r - \\frac{3}{2} J_2 \\frac{GM R^2}{r^4}
        \\left[(1 - 5 (\\hat r\\cdot k)^2)\\,\\hat r + 2 (\\hat r\\cdot k)\\, k\\right]

(the direct form is written out in the tests). Not yet validated against an independent
propagator for these bodies; the tests check the gradient, the secular J2 rates and the STM.

Third bodies (point masses, relative to a possibly accelerated centre; Montenbruck & Gill
eq. 3.37):

.. math::
    \\mathbf a = -GM_b\\left(\\frac{\\mathbf r - \\mathbf s}{|\\mathbf r - \\mathbf s|^3}
        + \\frac{\\mathbf s}{|\\mathbf s|^3}\\right).

Surface forces of a cannonball spacecraft (:class:`tapp.dynamics.spec.SurfaceForces`): solar
radiation pressure with Earth and Moon shadows (:mod:`tapp.dynamics.radiation`) and drag in a
co-rotating atmosphere (:mod:`tapp.dynamics.atmosphere`, Earth centre only); drag makes the
acceleration depend on v.

Model parameters (values in :func:`default_parameters`) may be symbols so that their
sensitivities come out of the variational equations, named as :mod:`tapp.dynamics.parameters`
says: ``GM_km3_s2`` (centre, km^3/s^2), ``Jn`` (unnormalised zonal,
\\bar C_{n0} = -J_n/\\sqrt{2n+1}), ``Cnm``/``Snm`` (normalised, single digits n, m),
``GM_<body>_km3_s2`` for a third body, ``dr_<body>_x_km``, ... its ephemeris offset
(:mod:`tapp.dynamics.ephemeris_offsets`), ``Cr`` (radiation pressure coefficient) and ``Cd``
(drag coefficient), dimensionless; the constant empirical accelerations of
:mod:`tapp.dynamics.empirical` (``acc_R``, ``acc_x``, ..., km/s², nominal 0) and the thrust of
a finite burn (:data:`tapp.dynamics.manoeuvres.THRUST_PARAMETERS`, nominal 0: set by TAPP I
on the burn's arc), whose terms :mod:`tapp.dynamics.equations` adds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import casadi as ca

from tapp.constants import (
    J2_CENTRE,
    GM_km3_s2,
    J2_RADIUS_km,
    OMEGA_EARTH_rad_s,
    R_EARTH_km,
    egm96_coefficients,
)
from tapp.dynamics.atmosphere import density_kg_m3, drag_acceleration
from tapp.dynamics.ephemeris_offsets import offset_bodies
from tapp.dynamics.parameters import gm_name, meaning, model_parameter
from tapp.dynamics.radiation import srp_acceleration
from tapp.dynamics.spec import ForceModel, check_surface_value
from tapp.errors import InputError
from tapp.frames.orientation import OMEGA_ERA_rad_s, itrs_from_gcrs_elements


def default_parameters(model: ForceModel, names: tuple[str, ...]) -> dict[str, float]:
    """Return the nominal value of each named model parameter (units as in the module doc),
    by its one spelling (:mod:`tapp.dynamics.parameters`; an earlier one is read with a
    warning).

    Raises
    ------
    InputError
        For a name the model does not contain (a harmonic outside its truncation, a third
        body it does not have, Cr without SRP, Cd without drag, an unknown name).
    """
    c_bar, s_bar = egm96_coefficients()
    values: dict[str, float] = {}
    for name in names:
        p = model_parameter(name)
        kind = None if p is None else p.kind
        if kind == "gm" and not p.body:
            values[p.canonical] = model.gm_center_km3_s2
        elif kind in ("empirical", "thrust"):
            values[p.canonical] = 0.0
        elif kind == "gm" and p.body in model.third_bodies:
            values[p.canonical] = GM_km3_s2[p.body]
        elif kind == "ephemeris_offset" and (p.body in model.third_bodies
                                             or p.body == model.center):
            values[p.canonical] = 0.0  # km (tapp.dynamics.ephemeris_offsets)
        elif kind in ("radiation", "drag") and (model.srp if kind == "radiation"
                                                else model.drag):
            values[p.canonical] = getattr(model.surface, p.surface_field)
        elif kind == "zonal" and _in_field(model, p.degree, 0):
            values[p.canonical] = (-math.sqrt(2 * p.degree + 1) * c_bar[p.degree, 0]
                                   if model.center == "earth" else J2_CENTRE[model.center])
        elif kind == "harmonic" and model.center == "earth" and _in_field(
                model, p.degree, p.order):
            if p.coefficient == "S" and p.order == 0:
                raise InputError("model", "parameters", "no S_n0 (identically zero)", name)
            values[p.canonical] = (c_bar if p.coefficient == "C" else s_bar)[p.degree, p.order]
        else:
            raise InputError("model", "parameters",
                             f"GM_km3_s2, Jn, Cnm, Snm within {model.gravity.name}, "
                             "GM_<third body>_km3_s2, dr_<third body>_x_km|y_km|z_km, Cr (with "
                             "srp), Cd (with an atmosphere) or acc_R, acc_I, acc_C, acc_x, "
                             "acc_y, acc_z", name)
    return values


def check_parameter_value(name: str, value: float, source: str = "model",
                          field: str = "parameters") -> float:
    """Return a model parameter's value as a float: finite, and > 0 for a GM.

    A gravitational parameter GM (``GM_km3_s2``, ``GM_<body>_km3_s2``, km^3/s^2) <= 0 would
    make the body repel or vanish: it is refused with the value and the limit. ``Cr`` and
    ``Cd`` must lie in the ranges of :func:`tapp.dynamics.spec.check_surface_value`.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``.
    """
    p = model_parameter(name, source, field)
    if p is not None and p.surface_field:
        return check_surface_value(p.canonical, value, source, field)
    gm = p is not None and p.kind == "gm"
    ok = (isinstance(value, int | float) and not isinstance(value, bool)
          and math.isfinite(value) and (value > 0 or not gm))
    if not ok:
        raise InputError(source, field, f"a finite GM > 0 km^3/s^2 for {name}" if gm
                         else f"a finite value of {name}", value)
    return float(value)


def _in_field(model: ForceModel, n: int, m: int) -> bool:
    """True when the harmonic (n, m) is in the model's field (only J2 about another centre)."""
    if model.center != "earth":
        return model.pole_field and (n, m) == (2, 0)
    return 2 <= n <= model.gravity.degree and m <= min(n, model.gravity.order)


def _recursion_factors(n: int, m: int) -> tuple[float, float]:
    """Return (alpha_nm, beta_nm) of the normalised vertical recursion (module docstring)."""
    alpha = math.sqrt((2 * n - 1) * (2 * n + 1) / ((n - m) * (n + m)))
    if n - m < 2:
        return alpha, 0.0
    beta = math.sqrt((2 * n + 1) * (n + m - 1) * (n - m - 1) / ((2 * n - 3) * (n + m) * (n - m)))
    return alpha, beta


def central_potential(model: ForceModel, r_fixed, gm, coefficients: Mapping[tuple[str, int, int],
                      object], sqrt: Callable = ca.sqrt, r2=None):
    """Return U(r) (km^2/s^2) of the centre's truncated field at body-fixed position r (km).

    ``r2`` is |r|² when given (a zonal field then needs only r_fixed's z: pass (0, 0, z)).

    ``coefficients`` maps ('C'|'S', n, m) to the value or symbol of each normalised
    coefficient present in the truncation (degree >= 2); missing entries are zero. The
    recursion uses only arithmetic and ``sqrt``, so any expression system with those
    (CasADi by default; heyoka in the benchmark) can build the same field.
    """
    deg, order = model.gravity.degree, model.gravity.order
    x, y, z = r_fixed[0], r_fixed[1], r_fixed[2]
    if r2 is None:
        r2 = x * x + y * y + z * z
    if deg < 2:
        return gm / sqrt(r2)
    radius = R_EARTH_km if model.center == "earth" else J2_RADIUS_km[model.center]
    rr = radius / r2
    v = {(0, 0): radius / sqrt(r2)}
    w = {(0, 0): 0.0}
    for m in range(0, order + 1):
        if m > 0:
            k = 2.0 if m == 1 else 1.0
            g = math.sqrt(k * (2 * m + 1) / (2 * m))
            v[m, m] = g * rr * (x * v[m - 1, m - 1] - y * w[m - 1, m - 1])
            w[m, m] = g * rr * (x * w[m - 1, m - 1] + y * v[m - 1, m - 1])
        for n in range(m + 1, deg + 1):
            alpha, beta = _recursion_factors(n, m)
            v[n, m] = alpha * z * rr * v[n - 1, m]
            w[n, m] = alpha * z * rr * w[n - 1, m]
            if beta:
                v[n, m] -= beta * radius * rr * v[n - 2, m]
                w[n, m] -= beta * radius * rr * w[n - 2, m]
    total = v[0, 0]
    for n in range(2, deg + 1):
        for m in range(0, min(n, order) + 1):
            total += coefficients.get(("C", n, m), 0.0) * v[n, m]
            if m > 0:
                total += coefficients.get(("S", n, m), 0.0) * w[n, m]
    return gm / radius * total


def field_coefficients(model: ForceModel, q: Mapping[str, ca.SX]
                       ) -> dict[tuple[str, int, int], ca.SX | float]:
    """Return the normalised coefficients of the truncation, symbols where ``q`` names them."""
    c_bar, s_bar = egm96_coefficients()
    coeffs: dict[tuple[str, int, int], ca.SX | float] = {}
    if model.pole_field:
        coeffs["C", 2, 0] = -J2_CENTRE[model.center] / math.sqrt(5)
    elif model.center == "earth":
        for n in range(2, model.gravity.degree + 1):
            for m in range(0, min(n, model.gravity.order) + 1):
                coeffs["C", n, m] = float(c_bar[n, m])
                if m > 0:
                    coeffs["S", n, m] = float(s_bar[n, m])
    for name, sym in q.items():
        p = meaning(name)
        if p is not None and p.kind == "zonal":
            if ("C", p.degree, 0) in coeffs:
                coeffs["C", p.degree, 0] = -sym / math.sqrt(2 * p.degree + 1)
        elif p is not None and p.kind == "harmonic":
            key = (p.coefficient, p.degree, p.order)
            if key in coeffs:
                coeffs[key] = sym
    return coeffs


def body_fixed_position(model: ForceModel, r: ca.SX, t: ca.SX, theta0: ca.SX,
                        slow: ca.SX | None = None) -> tuple[ca.SX, ca.SX | None]:
    """Rotate inertial r (km) into the body-fixed frame (module docstring): (r_fixed, r2).

    ``slow`` holds the iau2006 slow terms (X, Y, s, x_p, y_p, s', Δ, 0, 0) at t, or, with 3
    entries, the ITRS pole k in the GCRS or the IAU pole of another centre
    (:attr:`ForceModel.pole_field`) (all a zonal field needs: r_fixed = (0, 0, k·r) and
    r2 = |r|²; r2 is None when r_fixed is the whole position); ``theta0`` is ERA (iau2006) or
    GMST (gmst) at t = 0, rad. A gmst zonal field is symmetric about the inertial z axis, so no
    rotation is applied (and the model stays autonomous).
    """
    if model.pole_field or (model.oriented_field and slow.numel() == 3):
        return ca.vertcat(0.0, 0.0, ca.dot(slow, r)), ca.dot(r, r)
    if model.oriented_field:
        era = theta0 + OMEGA_ERA_rad_s * (t + slow[6])
        m = itrs_from_gcrs_elements(slow[0], slow[1], slow[2], slow[3], slow[4], slow[5], era,
                                    ca)
        return ca.vertcat(*(m[i][0] * r[0] + m[i][1] * r[1] + m[i][2] * r[2]
                            for i in range(3))), None
    if model.gravity.order == 0:
        return r, None
    theta = theta0 + OMEGA_EARTH_rad_s * t
    c, s = ca.cos(theta), ca.sin(theta)
    return ca.vertcat(c * r[0] + s * r[1], -s * r[0] + c * r[1], r[2]), None


def acceleration(model: ForceModel, t: ca.SX, r: ca.SX, theta0: ca.SX, q: Mapping[str, ca.SX],
                 r_bodies: Mapping[str, ca.SX], slow: ca.SX | None = None,
                 v: ca.SX | None = None) -> ca.SX:
    """Return the inertial acceleration (km/s^2) of ``model`` as a CasADi expression.

    Parameters
    ----------
    t : SX (1,)  seconds from the epoch.
    r : SX (3,)  inertial position relative to the centre, km.
    theta0 : SX (1,)  Earth rotation angle at the epoch, rad.
    q : mapping of parameter name to symbol; absent names take their nominal values.
    r_bodies : mapping of body name to its position relative to the centre (km): the third
        bodies and :attr:`ForceModel.ephemeris_bodies`.
    slow : SX (9,) or (3,), the iau2006 slow terms or the pole at t
        (:func:`body_fixed_position`), if oriented or a :attr:`ForceModel.pole_field`.
    v : SX (3,) inertial velocity, km/s; needed by drag only.
    """
    gm = q.get(gm_name(), model.gm_center_km3_s2)
    r_fixed, r2 = body_fixed_position(model, r, t, theta0, slow)
    u = central_potential(model, r_fixed, gm, field_coefficients(model, q), r2=r2)
    acc = ca.gradient(u, r)
    # The spacecraft sees the bodies where their ephemeris offsets put them; the centre's own
    # acceleration (the indirect term) is its ephemeris path's, which a constant offset does
    # not change (tapp.dynamics.ephemeris_offsets).
    seen = offset_bodies(r_bodies, q, model.center)
    for body in model.third_bodies:
        s = r_bodies[body]
        d = r - seen[body]
        gm_b = q.get(gm_name(body), GM_km3_s2[body])
        acc = acc - gm_b * (d / ca.norm_2(d) ** 3 + s / ca.norm_2(s) ** 3)
    return surface_acceleration(model, acc, r, v, q, seen)


def surface_acceleration(model: ForceModel, acc: ca.SX, r: ca.SX, v: ca.SX | None,
                         q: Mapping[str, ca.SX], r_bodies: Mapping[str, ca.SX]) -> ca.SX:
    """Return ``acc`` plus the SRP and drag accelerations of ``model`` (km/s^2).

    Other arguments as in :func:`acceleration`; the centre's own position is the origin. A
    model without them returns ``acc`` itself (the expression graph is unchanged).
    """
    surface = model.surface
    if surface is None:
        return acc

    def position(body: str) -> ca.SX:
        return ca.SX.zeros(3) if body == model.center else r_bodies[body]

    if surface.srp:
        occulters = {b: position(b) for b in model.occulters}
        acc = acc + srp_acceleration(r, position("sun"), occulters, q.get("Cr", surface.c_r),
                                     surface.area_to_mass_m2_kg)
    if surface.drag:
        sun = position("sun") if surface.atmosphere == "harris_priester" else None
        rho = density_kg_m3(surface.atmosphere, r, sun, surface.exponential)
        acc = acc + drag_acceleration(r, v, rho, q.get("Cd", surface.c_d),
                                      surface.area_to_mass_m2_kg)
    return acc
