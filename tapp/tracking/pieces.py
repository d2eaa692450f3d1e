"""A trajectory in pieces: restarts at the stochastic accelerations' bounds and at the burns.

What TAPP I adds to its force model on pieces of the arc (:class:`Forcing`): the
piecewise-constant stochastic accelerations (:mod:`tapp.estimation.gauss_markov`), a_k constant
in interval k = [t_k, t_{k+1}), and the manoeuvres (:mod:`tapp.dynamics.manoeuvres`): a finite
burn's thrust over [t₀, t₀ + Δt), an impulsive burn's jump at t_b. Their parameters (the
accelerations a, the execution errors e of the burns) are the *segment parameters* s, the last
n_s columns of x. Referred to an epoch t̂ (the state x(t̂) held fixed), their partials
S(t) = ∂x(t)/∂s are integrals of Φ(t, τ) over the pieces where they act, plus the impulsive
jumps.

The propagation from t̂ restarts at every boundary b_m inside the arc (a stochastic bound, a
burn's ignition or cut-off, an impulsive burn), from the state reached there, with Φ = I and
S = 0, and with the model parameters of what acts on that piece appended to the scenario's
(the empirical accelerations, nominal 0, when there are stochastic ones; a finite burn's
thrust, :data:`tapp.dynamics.manoeuvres.THRUST_PARAMETERS`): a segment m gives
Φ_m(t) = Φ(t, b_m) and, through the map C_m of its own parameters to the columns they move
(the interval's accelerations; ∂(w, c)/∂e of the burn), G_m(t) = ∂x(t)/∂(own) C_m. An
impulsive burn at b_m jumps first: x⁺ = x⁻ + Δx, J_m = I + ∂Δx/∂x⁻ and ∂Δx/∂e
(:meth:`tapp.dynamics.manoeuvres.ImpulsiveBurn.apply`). Then, only by products forward in time
(no inverse of a transition: after a lunar swing-by Φ(t, t_0) has condition ~1e17 and
Φ(t, t_0) Φ(b, t_0)⁻¹ keeps no digit),

.. math::
    S(b_m^+) = J_m S(b_m^-) + [\\text{jump}]\\,\\frac{\\partial \\Delta x}{\\partial e},\\quad
    S(t) = \\Phi_m(t)\\, S(b_m^+) + G_m(t),\\quad
    \\Phi(t, \\hat t) = \\Phi_m(t)\\, J_m \\Phi(b_m^-, \\hat t),\\quad
    S_q(t) = \\Phi_m(t)\\, J_m S_q(b_m^-) + S_{q,m}(t)

with S(t̂) = 0 and S_q the model-parameter sensitivities. The S are kept compactly
(:class:`SegmentPartials`): Φ_m (N, 6, 6), G_m (N, 6, ≤ L) with the columns it fills, and the
(n_seg, 6, n_s) at the segments' starts, not (N, 6, n_s). An output at b_m belongs to the
segment that ends there: the state before an impulsive burn at b_m.

The products are BLAS-free, so the tape does not depend on the BLAS kernel: the transitions
are composed by :func:`tapp.estimation.factors.accurate_stacked` (as if in twice the working
precision: Φ(b_m, t̂) has norm ~1e8 after the swing-by and its products cancel), the rows
H S(t) by ``numpy.einsum``. With BLAS products the deep-space study's day-30 real-world
miss covariance moved by 4.5e-6 of its scale between OpenBLAS kernels with and without FMA.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag

from tapp.dynamics import Propagator, Trajectory
from tapp.dynamics.events import Events
from tapp.dynamics.manoeuvres import THRUST_COLUMNS, Burn, FiniteBurn, ImpulsiveBurn
from tapp.estimation.factors import accurate_stacked
from tapp.estimation.gauss_markov import StochasticAccelerations
from tapp.frames.orientation import EarthOrientation


@dataclass(frozen=True, slots=True)
class Forcing:
    """What acts on pieces of the arc: stochastic accelerations and burns (module docstring).

    The segment parameters s are the accelerations (``stochastic.names``), then each burn's
    execution errors (:meth:`tapp.dynamics.manoeuvres.ImpulsiveBurn.parameters`), in the
    order of ``burns`` (ascending in time, not overlapping).
    """

    stochastic: StochasticAccelerations | None = None
    burns: tuple[Burn, ...] = ()

    def __bool__(self) -> bool:
        return self.stochastic is not None or bool(self.burns)

    @property
    def names(self) -> tuple[str, ...]:
        """The segment parameters' names, in column order."""
        own = () if self.stochastic is None else self.stochastic.names
        return own + tuple(name for b in self.burns for name, _, _ in b.parameters())

    def burn_columns(self, burn: Burn) -> np.ndarray:
        """Columns of ``burn``'s execution errors among the segment parameters."""
        first = 0 if self.stochastic is None else len(self.stochastic.names)
        for b in self.burns:
            n = len(b.parameters())
            if b is burn:
                return np.arange(first, first + n)
            first += n
        raise ValueError(f"{burn.name} is not a burn of this forcing")

    def breaks(self, t0_s: float, t_end_s: float) -> np.ndarray:
        """Segment starts in [t0_s, t_end_s): t0_s, then every stochastic bound, ignition,
        cut-off and impulsive burn strictly inside."""
        cuts = [t for b in self.burns for t in (b.t_start_s, b.t_end_s)]
        if self.stochastic is not None:
            cuts += list(self.stochastic.boundaries_s)
        cuts = np.asarray(cuts, dtype=float)
        return np.unique(np.concatenate([[t0_s], cuts[(cuts > t0_s) & (cuts < t_end_s)]]))

    def impulse_at(self, t_s: float) -> ImpulsiveBurn | None:
        """The impulsive burn at ``t_s`` (applied at the start of the segment there)."""
        return next((b for b in self.burns if isinstance(b, ImpulsiveBurn) and b.t_s == t_s),
                    None)

    def thrust_on(self, t_s: float) -> FiniteBurn | None:
        """The finite burn firing on the segment that starts at ``t_s``."""
        return next((b for b in self.burns if isinstance(b, FiniteBurn)
                     and b.t_start_s <= t_s < b.t_end_s), None)

    def segment(self, prop: Propagator, values: Mapping[str, float], t_s: float,
                differentiate: bool = True
                ) -> tuple[Propagator, dict[str, float], np.ndarray, np.ndarray]:
        """The propagator of the segment that starts at ``t_s``, its parameter values, the
        columns its own parameters move and C (n_own, n_cols) mapping them there.

        ``prop`` is the scenario's (model parameters only). Without ``differentiate`` the
        stochastic accelerations (nominal 0, no force) are left out.
        """
        params, values = list(prop.params), dict(values)
        blocks: list[tuple[np.ndarray, np.ndarray]] = []  # (C of the block, its columns)
        sto = self.stochastic
        if sto is not None and differentiate:
            params += sto.model_parameters
            n_c = len(sto.components)
            k = int(np.searchsorted(sto.boundaries_s, t_s, side="right")) - 1
            if 0 <= k < sto.n_intervals:
                blocks.append((np.eye(n_c), np.arange(k * n_c, (k + 1) * n_c)))
            else:
                blocks.append((np.zeros((n_c, 0)), np.zeros(0, dtype=int)))
        burn = self.thrust_on(t_s)
        if burn is not None:
            params += burn.thrust_parameters()
            values.update(burn.thrust_values())
            c_map = np.zeros((len(burn.thrust_parameters()), len(burn.parameters())))
            c_map[:THRUST_COLUMNS] = burn.thrust_map()  # β and t₀ move no column
            blocks.append((c_map, self.burn_columns(burn)))
        columns = np.concatenate([c for _, c in blocks]) if blocks else np.zeros(0, int)
        c_map = block_diag(*(m for m, _ in blocks)) if blocks else np.zeros((0, 0))
        seg_prop = prop if params == list(prop.params) else dataclasses.replace(
            prop, params=tuple(params))
        return seg_prop, values, columns.astype(int), c_map


@dataclass(frozen=True, slots=True)
class SegmentPartials:
    """S(t) = ∂x(t)/∂s of the segment parameters, (6, n_s) at each of N times, kept as
    S(t) = Φ_m(t) S(b_m⁺) + G_m(t) in the columns of t's segment m (module docstring).

    Attributes
    ----------
    phi_seg : (N, 6, 6) Φ(t, b_m) of each time's segment.
    sens_seg : (N, 6, L) G_m(t) in its first ``len(columns[m])`` columns, (unit of x) per
        (unit of s).
    segment : (N,) int segment m of each time.
    start : (n_seg, 6, n_s) S(b_m⁺) at the start of each segment (after its jump).
    columns : (n_seg, L) int the columns of s that G_m fills, -1 past its own.
    """

    phi_seg: np.ndarray
    sens_seg: np.ndarray
    segment: np.ndarray
    start: np.ndarray
    columns: np.ndarray

    def rows(self, index: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Return H S(t) at the times ``index``, (n, m, n_s), for H (n, m, 6)."""
        seg = self.segment[index]
        out = np.einsum("nmj,njs->nms", np.einsum("nmi,nij->nmj", h, self.phi_seg[index]),
                        self.start[seg])
        for m in np.unique(seg):
            cols = self.columns[m][self.columns[m] >= 0]
            if cols.size:
                at = np.flatnonzero(seg == m)
                local = np.einsum("nmi,nic->nmc", h[at], self.sens_seg[index[at], :, :cols.size])
                out[np.ix_(at, np.arange(h.shape[1]), cols)] += local
        return out

    @staticmethod
    def join(parts: list[SegmentPartials]) -> SegmentPartials:
        """Concatenate the partials of consecutive arcs (segment numbers offset)."""
        offsets = np.cumsum([0] + [p.start.shape[0] for p in parts[:-1]])
        width = max(p.columns.shape[1] for p in parts)

        def pad(a: np.ndarray, value: float) -> np.ndarray:
            extra = [(0, 0)] * (a.ndim - 1) + [(0, width - a.shape[-1])]
            return np.pad(a, extra, constant_values=value)

        return SegmentPartials(
            np.concatenate([p.phi_seg for p in parts]),
            np.concatenate([pad(p.sens_seg, 0.0) for p in parts]),
            np.concatenate([p.segment + o for p, o in zip(parts, offsets, strict=True)]),
            np.concatenate([p.start for p in parts]),
            np.concatenate([pad(p.columns, -1) for p in parts]))


@dataclass(frozen=True, slots=True)
class PieceArc:
    """An arc propagated in pieces (module docstring).

    Attributes
    ----------
    states : (N, 6) km, km/s, inertial.
    phi : (N, 6, 6) Φ(t, t̂).
    sens : (N, 6, n_q) ∂x(t)/∂q of the model parameters referred to t̂.
    partials : ∂x(t)/∂s of the segment parameters referred to t̂.
    """

    states: np.ndarray
    phi: np.ndarray
    sens: np.ndarray
    partials: SegmentPartials


def propagate_pieces(prop: Propagator, forcing: Forcing, x0: np.ndarray, t_s: np.ndarray, *,
                     t0_s: float, param_values: Mapping[str, float],
                     orientation: EarthOrientation, epoch_jd_utc: float) -> PieceArc:
    """Propagate from (t0_s, x0) to the ascending times ``t_s`` (> t0_s) with the model
    parameters of ``prop`` and the segment parameters of ``forcing`` (module docstring)."""
    n_q, n_s = len(prop.params), len(forcing.names)
    t_end = float(t_s[-1])
    starts = forcing.breaks(float(t0_s), t_end)
    ends = np.append(starts[1:], t_end)
    x_start = np.asarray(x0, dtype=float)
    phi0, sq0, sa0 = np.eye(6), np.zeros((6, n_q)), np.zeros((6, n_s))
    out = {key: [] for key in ("states", "phi", "sens", "phi_seg", "sens_seg", "segment")}
    start_rows, columns = [], []
    for m, (a, b) in enumerate(zip(starts, ends, strict=True)):
        burn = forcing.impulse_at(float(a))
        if burn is not None:
            x_start, jump, d_burn = burn.apply(x_start)
            phi0, sq0, sa0 = (accurate_stacked(jump[None], v)[0] for v in (phi0, sq0, sa0))
            sa0[:, forcing.burn_columns(burn)] += d_burn
        seg_prop, values, cols, c_map = forcing.segment(prop, param_values, float(a))
        take = (t_s > a) & (t_s <= b)
        grid = np.unique(np.append(t_s[take], b))
        traj = seg_prop.propagate(x_start, grid, t0_s=float(a), stm=True, param_values=values,
                                  orientation=orientation, epoch_jd_utc=epoch_jd_utc)
        keep = np.isin(grid, t_s[take])
        phi_m, s_m = traj.stm, traj.sensitivity
        own = s_m[:, :, n_q:]
        local = own if np.array_equal(c_map, np.eye(own.shape[-1])) else own @ c_map
        out["states"].append(traj.states[keep])
        out["phi"].append(accurate_stacked(phi_m[keep], phi0))
        out["sens"].append(accurate_stacked(phi_m[keep], sq0, s_m[keep, :, :n_q]))
        out["phi_seg"].append(phi_m[keep])
        out["sens_seg"].append(local[keep])
        out["segment"].append(np.full(int(np.count_nonzero(keep)), m))
        start_rows.append(sa0)
        columns.append(cols)
        # carry everything to b, the next segment's start
        sa0 = accurate_stacked(phi_m[-1:], sa0)[0]
        sa0[:, cols] += local[-1]
        phi0 = accurate_stacked(phi_m[-1:], phi0)[0]
        sq0 = accurate_stacked(phi_m[-1:], sq0, s_m[-1:, :, :n_q])[0]
        x_start = traj.states[-1]
    width = max(c.size for c in columns)
    out["sens_seg"] = [np.pad(s, [(0, 0), (0, 0), (0, width - s.shape[-1])])
                       for s in out["sens_seg"]]
    cat = {key: np.concatenate(value) for key, value in out.items()}
    cols = np.array([np.pad(c, (0, width - c.size), constant_values=-1) for c in columns],
                    dtype=int).reshape(len(columns), width)
    return PieceArc(cat["states"], cat["phi"], cat["sens"], SegmentPartials(
        cat["phi_seg"], cat["sens_seg"], cat["segment"], np.array(start_rows), cols))


def fly(prop: Propagator, burns: tuple[Burn, ...], x0: np.ndarray, t_s: np.ndarray, *,
        param_values: Mapping[str, float], orientation: EarthOrientation,
        epoch_jd_utc: float, t0_s: float = 0.0) -> Trajectory:
    """The states (no partials) from ``x0`` at ``t0_s`` (the injection, t = 0, by default) at
    the times ``t_s`` (s, any order; before ``t0_s`` too), flying the ``burns``, and the events
    met up to the last time. An impulsive burn at ``t0_s`` acts after the output there."""
    t_s = np.atleast_1d(np.asarray(t_s, dtype=float))
    if not burns:
        return prop.propagate(x0, t_s, t0_s=t0_s, stm=False, param_values=param_values,
                              orientation=orientation, epoch_jd_utc=epoch_jd_utc)
    forcing = Forcing(None, burns)
    order = np.argsort(t_s, kind="stable")
    ts = t_s[order]
    states = np.empty((ts.size, 6))
    before = ts < t0_s  # no burn acts before the start
    if before.any():
        states[before] = prop.propagate(x0, ts[before][::-1], t0_s=t0_s, stm=False,
                                        param_values=param_values, orientation=orientation,
                                        epoch_jd_utc=epoch_jd_utc).states[::-1]
    last = max(float(ts[-1]), t0_s)
    starts = forcing.breaks(t0_s, last)
    ends = np.append(starts[1:], last)
    x_start = np.asarray(x0, dtype=float)
    events, steps, rhs = [], 0, 0
    states[ts == t0_s] = x_start
    for a, b in zip(starts, ends, strict=True):
        burn = forcing.impulse_at(float(a))
        if burn is not None:
            x_start = burn.apply(x_start)[0]
        if b == a:  # nothing after the last time
            continue
        seg_prop, values, _, _ = forcing.segment(prop, param_values, float(a), False)
        take = (ts > a) & (ts <= b)
        grid = np.unique(np.append(ts[take], b))
        traj = seg_prop.propagate(x_start, grid, t0_s=float(a), stm=False, param_values=values,
                                  orientation=orientation, epoch_jd_utc=epoch_jd_utc)
        states[take] = traj.states[np.searchsorted(grid, ts[take])]
        events.append(traj.events)
        steps, rhs = steps + traj.steps, rhs + traj.rhs_evaluations
        x_start = traj.states[-1]
    unsorted = np.empty_like(states)
    unsorted[order] = states
    return Trajectory(t_s, unsorted, None, None, prop.params, steps, rhs, Events.join(events))
