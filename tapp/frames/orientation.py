"""Earth orientation: the rotation from the inertial frame (GCRS) to the Earth-fixed (ITRS).

Two models, chosen by name (``earth_orientation`` in every scenario file, ``--earth-orientation``
on the CLI):

``"iau2006"`` (the default for new scenarios): the IERS Conventions (2010) CIO-based
transformation,

.. math::
    [ITRS] = W(t)\\,R_3(ERA)\\,C(t)\\,[GCRS],

with C the GCRS → CIRS matrix of the CIP coordinates X, Y (IAU 2006 precession, IAU 2000A
nutation, ERFA ``xy06`` series, plus the IERS offsets dX, dY) and the CIO locator s; ERA the Earth
rotation angle of UT1 (ERFA ``era00``); W = R_1(−y_p) R_2(−x_p) R_3(s') the polar motion (ERFA
``pom00``, s' from ``sp00``). C is built from X, Y, s in closed form (IERS Conventions eq. 5.10,
ERFA ``c2ixys``): C = R_3(−s) [[1 − aX², −aXY, −X], [−aXY, 1 − aY², −Y], [X, Y, Z]],
Z = √(1 − X² − Y²), a = 1/(1 + Z). The inertial axes of the project ("EME2000") are then the
GCRS; DE421's ICRF agrees with it to ~0.1 mas.

``"gmst"`` (the approximate-STM study's model, kept so that study reproduces what it
reproduces): W = C = I and the angle is θ(t) = GMST_82(epoch, UT1 = UTC) + ω_E t with
ω_E = 7.292115e-5 rad/s. It leaves out precession and nutation since J2000 (31.5 km at
Goldstone on 2026-01-01) and is self-consistent only in a study that simulates and fits with
it.

Speed: the slow parts of the iau2006 model (X, Y, s, x_p, y_p, s' and the UT1 − TAI drift Δ)
are evaluated by ERFA at Chebyshev nodes and held as 12 h, 14-coefficient series
(:mod:`tapp.frames.chebyshev`); the angle is ERA(t) = ERA_0 + ω_ERA (t + Δ(t)),
ω_ERA = 2π · 1.00273781191135448 / 86400 s. The same series drive the geopotential inside the
compiled integrator. Their error against direct ERFA calls is below 1e-13 rad (0.6 μm at the
surface; measured in the tests). For stations, the series are sampled every 60 s and
interpolated linearly (cheap for 1e5 observation epochs): the error h²/8 max|f''| is below
3e-15 rad for the nutation (largest curvature: the 13.66 d term, 5e-18 rad/s²), and exact
for the EOP, which are themselves linear between 0h UTC nodes.

Station velocity (both models) is a rigid rotation about the spin axis at the nominal rate,
v = ω (ĉ × r), ĉ the CIP (or z) in the inertial frame, as astropy's ``get_gcrs_posvel``: the
CIP's own motion (precession-nutation, ≤ 4e-5 m/s) and the length-of-day excess (≤ 1e-5 m/s)
are left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import erfa
import numpy as np

from tapp.constants import OMEGA_EARTH_rad_s
from tapp.errors import InputError
from tapp.frames.chebyshev import ChebyshevTable, fit_chebyshev
from tapp.frames.eop import EopTable
from tapp.frames.iers import shipped_finals2000a
from tapp.frames.rotation import earth_rotation_angle_rad, r3
from tapp.frames.time import Epoch
from tapp.frames.timescales import TimeScales

#: Earth orientation models, the default first.
MODELS = ("iau2006", "gmst")
#: The inertial frame of the orbits under each model: the GCRS under iau2006 (module
#: docstring); the mean equator and equinox of J2000 under gmst, which rotates it to the
#: Earth-fixed frame with no precession or nutation since J2000.
INERTIAL_FRAME = {"iau2006": "GCRS", "gmst": "EME2000"}
#: Rate of the Earth rotation angle in TT-uniform seconds of UT1, rad/s (IERS Conventions 5.15).
OMEGA_ERA_rad_s = 2.0 * math.pi * 1.00273781191135448 / 86400.0
#: Segments and degree of the slow-term series.
SERIES_SEGMENT_s = 43200.0
SERIES_N_COEF = 14
#: The slow terms, as three 3-vector series: (X, Y, s), (x_p, y_p, s') rad and (Δ s, 0, 0).
N_SLOW_SERIES = 3
#: Node spacing of the stations' linear interpolation of the slow terms, s (divides 12 h).
NODE_STEP_s = 60.0

def check_model(name: str, source: str = "scenario", field_name: str = "earth_orientation"
                ) -> str:
    """Return ``name`` if it is one of :data:`MODELS`, else raise InputError."""
    if name not in MODELS:
        raise InputError(source, field_name, " or ".join(f'"{m}"' for m in MODELS), name)
    return name


def _mul(a: list, b: list) -> list:
    return [[a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] for j in range(3)]
            for i in range(3)]


def _rot(axis: int, angle, ops) -> list:
    """Frame rotation R_axis(angle) (SOFA sense: R_3(α) = [[c, s, 0], [−s, c, 0], [0, 0, 1]])."""
    c, s = ops.cos(angle), ops.sin(angle)
    zero, one = 0.0 * c, 0.0 * c + 1.0
    i, j = [(1, 2), (2, 0), (0, 1)][axis - 1]
    m = [[zero, zero, zero], [zero, zero, zero], [zero, zero, zero]]
    m[axis - 1][axis - 1] = one
    m[i][i], m[i][j], m[j][i], m[j][j] = c, s, -s, c
    return m


def _c2i_core(x, y) -> list:
    """The CIP part of C (before R3(−s)): [[1 − aX², −aXY, −X], [−aXY, 1 − aY², −Y],
    [X, Y, Z]], Z = √(1 − X² − Y²), a = 1/(1 + Z) (IERS Conventions eq. 5.10)."""
    z = (1.0 - x * x - y * y) ** 0.5
    a = 1.0 / (1.0 + z)
    return [[1.0 - a * x * x, -a * x * y, -x], [-a * x * y, 1.0 - a * y * y, -y], [x, y, z]]


def itrs_from_gcrs_elements(x, y, s, xp, yp, sp, era, ops) -> list:
    """Return the GCRS → ITRS matrix as nested 3x3 lists of expressions (module docstring).

    W R3(ERA) C = R1(−y_p) R2(−x_p) R3(s' + ERA − s) C₀ (the three rotations about z add).
    Any arithmetic with ``ops.sin`` and ``ops.cos`` works (``ops`` = casadi for the
    integrator's geopotential); :func:`itrs_from_gcrs_stack` is the vectorised NumPy form.
    """
    return _mul(_rot(1, -yp, ops), _mul(_rot(2, -xp, ops),
                                        _mul(_rot(3, sp + era - s, ops), _c2i_core(x, y))))


def _rot_stack(axis: int, angle: np.ndarray) -> np.ndarray:
    """Frame rotations R_axis(angle), (N, 3, 3), SOFA sense (as :func:`_rot`)."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis - 1]
    m = np.zeros(angle.shape + (3, 3))
    m[..., axis - 1, axis - 1] = 1.0
    m[..., i, i], m[..., i, j], m[..., j, i], m[..., j, j] = c, s, -s, c
    return m


def itrs_from_gcrs_stack(x, y, s, xp, yp, sp, era) -> np.ndarray:
    """:func:`itrs_from_gcrs_elements` for arrays (N,): the matrices (N, 3, 3)."""
    core = np.moveaxis(np.array(_c2i_core(x, y)), (0, 1), (-2, -1))
    return _rot_stack(1, -yp) @ _rot_stack(2, -xp) @ _rot_stack(3, sp + era - s) @ core


@dataclass(frozen=True, slots=True)
class EarthAttitude:
    """The Earth's orientation at N instants.

    Attributes
    ----------
    itrs_from_gcrs : (N, 3, 3) rotation inertial → Earth-fixed.
    spin_axis : (N, 3) unit rotation axis (CIP; z for gmst) in inertial axes.
    omega_rad_s : rotation rate about it, rad/s.
    """

    itrs_from_gcrs: np.ndarray
    spin_axis: np.ndarray
    omega_rad_s: float

    @property
    def gcrs_from_itrs(self) -> np.ndarray:
        """(N, 3, 3) rotation Earth-fixed → inertial."""
        return np.swapaxes(self.itrs_from_gcrs, -1, -2)


@dataclass(frozen=True, slots=True)
class EarthOrientation:
    """One Earth orientation model bound to a scenario epoch (build with the classmethods).

    Attributes
    ----------
    model : "iau2006" or "gmst".
    theta0_rad : the angle at t = 0: ERA (iau2006) or GMST (gmst), rad.
    scales : the scenario's time scales (iau2006), None for gmst.
    """

    model: str
    theta0_rad: float
    scales: TimeScales | None = None
    #: Fitted segments, their 60 s nodes and the last attitude asked for (per instance).
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def gmst(cls, epoch: Epoch) -> EarthOrientation:
        """The study's model: GMST IAU-82 at the epoch (UT1 = UTC) plus ω_E t."""
        return cls("gmst", epoch.gmst_rad())

    @classmethod
    def gmst_angle(cls, theta0_rad: float) -> EarthOrientation:
        """The gmst model from its angle at t = 0, rad (for tests and notebooks)."""
        return cls("gmst", float(theta0_rad))

    @classmethod
    def iau2006(cls, epoch: Epoch, eop: EopTable | None = None,
                source: str = "epoch") -> EarthOrientation:
        """The IAU 2006/2000A model with the IERS EOP (default: astropy-iers-data's table).

        Raises
        ------
        InputError
            For an epoch before 1972 or outside the EOP table.
        """
        scales = TimeScales.of(epoch, shipped_finals2000a() if eop is None else eop, source)
        whole, fraction = scales.ut1(np.zeros(1), source)
        return cls("iau2006", float(erfa.era00(whole[0], fraction[0])), scales)

    @classmethod
    def of(cls, model: str, epoch: Epoch, eop: EopTable | None = None,
           source: str = "scenario") -> EarthOrientation:
        """Build the named model (:data:`MODELS`) for ``epoch``."""
        if check_model(model, source) == "gmst":
            return cls.gmst(epoch)
        return cls.iau2006(epoch, eop, source)

    @property
    def frame(self) -> str:
        """The inertial frame of the orbits under this model (:data:`INERTIAL_FRAME`)."""
        return INERTIAL_FRAME[self.model]

    @property
    def eop_note(self) -> str:
        """Where the EOP came from, for reports and tapes ("" for gmst)."""
        if self.scales is None:
            return ""
        eop = self.scales.eop
        return "none (UT1 = UTC, no polar motion)" if eop.is_zero else Path(eop.source).name

    def uses_predicted_eop(self, t_s) -> bool:
        """True if any time lies past the last measured EOP value (predictions used)."""
        return self.scales is not None and self.scales.eop.uses_predictions(
            self.scales.utc_mjd(t_s))

    def check_covers(self, t_s, source: str = "epoch") -> None:
        """Raise InputError naming the first time outside the EOP table (iau2006)."""
        if self.scales is not None:
            self.scales.eop.check_covers(self.scales.utc_mjd(t_s), source)

    # --- the slow terms ------------------------------------------------------------------

    def slow_terms(self, t_s, source: str = "epoch") -> np.ndarray:
        """Return the iau2006 slow terms at t_s (M,) by ERFA, shape (3, M, 3).

        Series 0: X, Y (with dX, dY), s; 1: x_p, y_p, s' (rad); 2: (Δ, 0, 0) with
        Δ(t) = (UT1 − TAI)(t) − (UT1 − TAI)(0), s.
        """
        scales = self._require_scales()
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        tt1, tt2 = scales.tt(t)
        x, y = erfa.xy06(tt1, tt2)
        s = erfa.s06(tt1, tt2, x, y)  # before the offsets, as the SOFA cookbook does
        eop = scales.eop.at(scales.utc_mjd(t), source)
        x, y = x + eop.dx_rad, y + eop.dy_rad
        sp = erfa.sp00(tt1, tt2)
        drift = scales.ut1_minus_tai_s(t, source) - scales.ut1_minus_tai_s(np.zeros(1))[0]
        out = np.zeros((N_SLOW_SERIES, t.size, 3))
        out[0] = np.stack([x, y, s], -1)
        out[1] = np.stack([eop.xp_rad, eop.yp_rad, sp], -1)
        out[2, :, 0] = drift
        return out

    @property
    def segment_origin_s(self) -> float:
        """Scenario time of the 0h or 12h UTC at or before the epoch, s: the series' grid.

        The EOP are daily values interpolated linearly, with a kink at each 0h UTC; segments
        of 12 h on this grid put every kink on a boundary, where a Chebyshev fit loses nothing
        (a segment across one errs by up to 1e-10 rad).
        """
        if self.scales is None:
            return 0.0
        return -float(np.mod(self.scales.epoch.jd_fraction * 86400.0, SERIES_SEGMENT_s))

    def series(self, t_start_s: float, t_end_s: float, kind: str = "full") -> ChebyshevTable:
        """Chebyshev series covering [t_start, t_end]: the cached 12 h segments on the UTC
        grid (:attr:`segment_origin_s`), fitted on first use.

        ``kind``: "full", the slow terms (:meth:`slow_terms`, 3 series); "pole", the ITRS pole
        in the GCRS (:meth:`pole`, 1 series: all a zonal field needs).
        """
        self.check_covers(np.array([t_start_s, t_end_s]))
        return self._table(np.array([t_start_s, t_end_s]), kind)

    def _table(self, t: np.ndarray, kind: str = "full") -> ChebyshevTable:
        """The cached segments holding every time of t, joined into one table."""
        k = self._segment_index(t)
        segments = [self._segment(j, kind) for j in range(int(k.min()), int(k.max()) + 1)]
        return ChebyshevTable(np.ascontiguousarray(np.concatenate(
            [seg.coeffs for seg in segments], axis=1)), segments[0].t0_s, SERIES_SEGMENT_s)

    def _segment_index(self, t: np.ndarray) -> np.ndarray:
        """Index k of the 12 h segment [origin + k h, origin + (k+1) h] holding each time; a
        time on a boundary takes the segment that ends there (the last EOP row is usable)."""
        return (np.ceil((t - self.segment_origin_s) / SERIES_SEGMENT_s) - 1).astype(int)

    def _segment(self, k: int, kind: str = "full") -> ChebyshevTable:
        """The fitted segment k of the slow terms or of the pole (cached)."""
        key = k if kind == "full" else (kind, k)
        if key not in self._cache:
            start = self.segment_origin_s + k * SERIES_SEGMENT_s
            fn = self.slow_terms if kind == "full" else self.pole
            self._cache[key] = fit_chebyshev(fn, start, start + SERIES_SEGMENT_s,
                                             SERIES_SEGMENT_s, SERIES_N_COEF)
        return self._cache[key]

    def pole(self, t_s) -> np.ndarray:
        """The ITRS z axis in the GCRS (the third row of M) at t_s (M,), (1, M, 3), from the
        cached slow-term series (no further ERFA calls).

        It carries polar motion, which the Earth rotation turns once a day: a 12 h series of
        14 terms follows that daily wobble (1.5e-6 rad) to ~1e-15 rad.
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        slow = self._table(t).evaluate(t)
        return self._attitude_of(t, slow).itrs_from_gcrs[None, :, 2, :]

    def _require_scales(self) -> TimeScales:
        if self.scales is None:
            raise InputError("earth orientation", "model", "iau2006 for slow terms", self.model)
        return self.scales

    def _cached_slow_terms(self, t: np.ndarray) -> np.ndarray:
        """Slow terms at times t (M,), shape (3, M, 3): linear interpolation between values
        every NODE_STEP_s taken from the cached segments' series (module docstring)."""
        k = self._segment_index(t)
        first, last = int(k.min()), int(k.max())
        nodes = np.concatenate([self._segment_nodes(j)[:-1] for j in range(first, last + 1)]
                               + [self._segment_nodes(last)[-1:]])
        u = (t - (self.segment_origin_s + first * SERIES_SEGMENT_s)) / NODE_STEP_s
        i = np.clip(np.floor(u).astype(int), 0, nodes.shape[0] - 2)
        w = (u - i)[:, None]
        values = nodes[i] * (1.0 - w) + nodes[i + 1] * w  # (M, 9)
        return np.moveaxis(values.reshape(t.size, N_SLOW_SERIES, 3), 1, 0)

    def _segment_nodes(self, k: int) -> np.ndarray:
        """Slow terms of segment k at its nodes every NODE_STEP_s, (n + 1, 9) (cached)."""
        key = ("nodes", k)
        if key not in self._cache:
            seg = self._segment(k)
            t = seg.t0_s + NODE_STEP_s * np.arange(int(SERIES_SEGMENT_s / NODE_STEP_s) + 1)
            self._cache[key] = np.moveaxis(seg.evaluate(t), 0, 1).reshape(t.size, -1)
        return self._cache[key]

    # --- the attitude --------------------------------------------------------------------

    def angle_rad(self, t_s, drift_s=0.0) -> np.ndarray:
        """The rotation angle at t_s: GMST_0 + ω_E t, or ERA_0 + ω_ERA (t + Δ), rad."""
        if self.model == "gmst":
            return earth_rotation_angle_rad(self.theta0_rad, t_s)
        return self.theta0_rad + OMEGA_ERA_rad_s * (np.asarray(t_s, dtype=float) + drift_s)

    @property
    def omega_rad_s(self) -> float:
        """The rotation rate of the model, rad/s."""
        return OMEGA_EARTH_rad_s if self.model == "gmst" else OMEGA_ERA_rad_s

    def attitude(self, t_s, source: str = "epoch") -> EarthAttitude:
        """Return the attitude at scenario times t_s (N,) s (iau2006 by the cached series).

        Raises
        ------
        InputError
            For a time outside the EOP table (iau2006).
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        if self.model == "gmst":
            axis = np.zeros(t.shape + (3,))
            axis[..., 2] = 1.0
            return EarthAttitude(r3(self.angle_rad(t)), axis, OMEGA_EARTH_rad_s)
        key = ("attitude", t.shape, t.tobytes())
        if key not in self._cache:  # the last grid asked for: observables and partials
            self.check_covers(t, source)  # of one geometry ask for the same times in turn
            self._cache.pop(self._cache.pop("last attitude", None), None)
            self._cache[key] = self._attitude_of(t, self._cached_slow_terms(t.ravel()))
            self._cache["last attitude"] = key
        return self._cache[key]

    def attitude_exact(self, t_s, source: str = "epoch") -> EarthAttitude:
        """As :meth:`attitude`, with the slow terms straight from ERFA (no series)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        if self.model == "gmst":
            return self.attitude(t)
        return self._attitude_of(t, self.slow_terms(t.ravel(), source))

    def _attitude_of(self, t: np.ndarray, slow: np.ndarray) -> EarthAttitude:
        (x, y, s), (xp, yp, sp), (drift, _, _) = (np.moveaxis(slow[i], -1, 0)
                                                  for i in range(N_SLOW_SERIES))
        era = self.angle_rad(t.ravel(), drift)
        matrix = itrs_from_gcrs_stack(x, y, s, xp, yp, sp, era).reshape(t.shape + (3, 3))
        axis = np.stack([x, y, np.sqrt(1.0 - x * x - y * y)], -1).reshape(t.shape + (3,))
        return EarthAttitude(matrix, axis, OMEGA_ERA_rad_s)


def as_orientation(value: EarthOrientation | float) -> EarthOrientation:
    """Return ``value`` if it is an EarthOrientation; a float is the gmst model's angle."""
    if isinstance(value, EarthOrientation):
        return value
    return EarthOrientation.gmst_angle(float(value))


# --- partials w.r.t. constant offsets of the Earth orientation parameters ------------------

#: The Earth orientation parameters whose constant offsets from the IERS values (or, under
#: gmst, from UT1 = UTC) are differentiable: UT1 − UTC (s) and the pole coordinates (rad).
EOP_PARAMETERS = ("ut1_s", "xp_rad", "yp_rad")
#: Their units, and the kind of the parameters (``eop.<name>``) on the T13 tape.
EOP_UNITS = {"ut1_s": "s", "xp_rad": "rad", "yp_rad": "rad"}
EOP_KIND = "eop"


def check_eop_parameters(model: str, names, source: str = "earth orientation",
                         field_name: str = "eop") -> tuple[str, ...]:
    """Return ``names`` as a tuple if each is one of :data:`EOP_PARAMETERS` and has a meaning
    under ``model``; else raise InputError naming ``field_name``.

    The gmst model has no polar motion (W = I): only "ut1_s" is offered there.
    """
    names = tuple(names)
    allowed = EOP_PARAMETERS if model == "iau2006" else EOP_PARAMETERS[:1]
    for name in names:
        if name not in allowed:
            why = "" if name not in EOP_PARAMETERS else " (the gmst model has no polar motion)"
            raise InputError(source, field_name, " or ".join(f'"{n}"' for n in allowed)
                             + f" under earth_orientation = \"{model}\"{why}", name)
    return names


def eop_parameters_of(model: str, setting: bool | list[str], source: str = "scenario",
                      field_name: str = "parameters.earth_orientation") -> tuple[str, ...]:
    """Return the EOP parameters a scenario's ``setting`` asks for: none (False), every one
    that has a meaning under ``model`` (True: the three under iau2006, "ut1_s" under gmst)
    or the listed ones, checked by :func:`check_eop_parameters`."""
    if setting is True:
        return EOP_PARAMETERS if model == "iau2006" else EOP_PARAMETERS[:1]
    if setting is False:
        return ()
    return check_eop_parameters(model, setting, source, field_name)


def eop_generators(attitude: EarthAttitude, names=EOP_PARAMETERS) -> np.ndarray:
    """Return the inertial rotation vectors g_p of constant EOP offsets, (N, k, 3), rad per
    unit of each parameter (s for ``ut1_s``, rad for ``xp_rad``, ``yp_rad``).

    Any Earth-fixed point r_f, at inertial r = Mᵀ r_f, moves by dr/dp = g_p × r.

    .. math::

        \\frac{\\partial M}{\\partial p} = -[\\mathbf a_p\\times]\\,M,\\quad
        \\mathbf g_p = M^T\\mathbf a_p,\\qquad
        \\mathbf a_{UT1} = \\omega\\,W\\hat{\\mathbf z},\\quad
        \\mathbf a_{x_p} = -R_1(-y_p)\\,\\hat{\\mathbf y},\\quad
        \\mathbf a_{y_p} = -\\hat{\\mathbf x}

    from M = W R_3(ERA) C, W = R_1(−y_p) R_2(−x_p) R_3(s') (IERS Conventions 2010, ch. 5,
    eqs. 5.1, 5.3, 5.15) and dR_k(α)/dα = −[ê_k×] R_k(α): the ERA of UT1 grows at
    ω = dERA/dUT1 = 2π · 1.00273781191135448 / 86400 rad/s (the gmst model: ω_E, its own
    rate: a UT1 offset δ turns its angle by ω_E δ, 1.2e-7 below GMST-82's rate), so
    g_UT1 = ω ĉ, the spin axis (CIP) in inertial axes, and dr/dUT1 is the station's velocity.
    W ẑ = (sin x_p, −sin y_p cos x_p, cos y_p cos x_p) is the CIP in the ITRS, = M ĉ; so
    R_1(−y_p) ŷ = (0, cos y_p, sin y_p) comes from the attitude alone. Under gmst
    (W = I) only the UT1 column means anything (:func:`check_eop_parameters`).

    Parameters
    ----------
    attitude : EarthAttitude
        The Earth's orientation at N instants.
    names : sequence of str
        Columns, among :data:`EOP_PARAMETERS`.
    """
    m = attitude.itrs_from_gcrs
    cip_itrs = np.einsum("...ij,...j->...i", m, attitude.spin_axis)  # W ẑ
    axes = {"ut1_s": attitude.omega_rad_s * cip_itrs,
            "xp_rad": -np.stack([np.zeros_like(cip_itrs[..., 0]), cip_itrs[..., 2],
                                 -cip_itrs[..., 1]], -1)
            / np.hypot(cip_itrs[..., 1], cip_itrs[..., 2])[..., None],
            "yp_rad": np.broadcast_to([-1.0, 0.0, 0.0], cip_itrs.shape)}
    a = np.stack([axes[name] for name in names], axis=-2)  # (N, k, 3), ITRS
    return np.einsum("...ji,...kj->...ki", m, a)  # g = Mᵀ a
