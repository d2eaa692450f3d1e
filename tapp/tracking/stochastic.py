"""Partials of piecewise-constant stochastic accelerations, by restarts at the interval bounds.

The accelerations (:mod:`tapp.estimation.gauss_markov`) are a_k, constant in interval k =
[t_k, t_{k+1}), along B(t) = [0; R(t)] (R the RIC → inertial rotation of the trajectory, or I:
:mod:`tapp.dynamics.empirical`). Referred to an epoch t̂ (the state x(t̂) held fixed), their
partials are

.. math::
    S_k(t) = \\frac{\\partial x(t)}{\\partial a_k} = \\int_{\\max(t_k, \\hat t)}^{\\min(t,
    t_{k+1})} \\Phi(t, \\tau) B(\\tau)\\, d\\tau \\quad (0 \\text{ for } t \\le t_k).

The propagation from t̂ restarts at every boundary b_m inside the arc, from the state reached
there, with Φ = I and S = 0, and the empirical accelerations as three extra model parameters
(nominal 0): a segment m gives Φ_m(t) = Φ(t, b_m) and G_m(t) = ∫_{b_m}^t Φ(t, τ) B(τ) dτ
directly. Then, only by products forward in time (no inverse of a transition: after a lunar
swing-by Φ(t, t_0) has condition ~1e17 and Φ(t, t_0) Φ(b, t_0)⁻¹ keeps no digit),

.. math::
    S_k(t) = \\Phi_m(t)\\, S_k(b_m) + [k = k(m)]\\, G_m(t),\\qquad
    \\Phi(t, \\hat t) = \\Phi_m(t)\\, \\Phi(b_m, \\hat t),\\qquad
    S_q(t) = \\Phi_m(t)\\, S_q(b_m) + S_{q,m}(t)

with k(m) the interval segment m lies in, S_k(t̂) = 0 and S_q the model-parameter
sensitivities. The S_k are kept compactly (:class:`BatchPartials`): the (N, 6, 6 + n_c) of the
segments and the (n_seg, 6, n_s) at their starts, not (N, 6, n_s).

The products are BLAS-free, so the tape does not depend on the BLAS kernel: the transitions
are composed by :func:`tapp.estimation.factors.accurate_matmul` (as if in twice the working
precision: Φ(b_m, t̂) has norm ~1e8 after the swing-by and its products cancel), the rows
H S_k(t) by ``numpy.einsum``. With BLAS products the deep-space study's day-30 real-world
miss covariance moved by 4.5e-6 of its scale between OpenBLAS kernels with and without FMA.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from tapp.dynamics import Propagator
from tapp.estimation.factors import accurate_matmul
from tapp.estimation.gauss_markov import StochasticAccelerations
from tapp.frames.orientation import EarthOrientation


@dataclass(frozen=True, slots=True)
class BatchPartials:
    """S(t) = ∂x(t)/∂a of every stochastic acceleration, (6, n_s) at each of N times, kept as
    S(t) = Φ_m(t) S(b_m) + G_m(t) in the columns of the interval of t's segment m.

    Attributes
    ----------
    phi_seg : (N, 6, 6) Φ(t, b_m) of each time's segment.
    sens_seg : (N, 6, n_c) G_m(t), km/s per km/s² (module docstring).
    segment : (N,) int segment m of each time.
    start : (n_seg, 6, n_s) S(b_m) at the start of each segment.
    interval : (n_seg,) int interval k(m) of each segment (-1 outside the intervals).
    n_c : components per interval.
    """

    phi_seg: np.ndarray
    sens_seg: np.ndarray
    segment: np.ndarray
    start: np.ndarray
    interval: np.ndarray
    n_c: int

    def rows(self, index: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Return H S(t) at the times ``index``, (n, m, n_s), for H (n, m, 6)."""
        seg = self.segment[index]
        out = np.einsum("nmj,njs->nms", np.einsum("nmi,nij->nmj", h, self.phi_seg[index]),
                        self.start[seg])
        for m in np.unique(seg):
            k = int(self.interval[m])
            if k >= 0:
                at = seg == m
                cols = slice(k * self.n_c, (k + 1) * self.n_c)
                out[at, :, cols] += np.einsum("nmi,nic->nmc", h[at], self.sens_seg[index[at]])
        return out

    @staticmethod
    def join(parts: list[BatchPartials]) -> BatchPartials:
        """Concatenate the partials of consecutive arcs (segment numbers offset)."""
        offsets = np.cumsum([0] + [p.start.shape[0] for p in parts[:-1]])
        return BatchPartials(
            np.concatenate([p.phi_seg for p in parts]),
            np.concatenate([p.sens_seg for p in parts]),
            np.concatenate([p.segment + o for p, o in zip(parts, offsets, strict=True)]),
            np.concatenate([p.start for p in parts]),
            np.concatenate([p.interval for p in parts]), parts[0].n_c)


def _compose(phi: np.ndarray, m: np.ndarray, c: np.ndarray | None = None) -> np.ndarray:
    """Return C_i + Φ_i M for stacked Φ (N, 6, 6), M (6, p) and C (N, 6, p) or None, each
    entry as if computed in twice the working precision (module docstring)."""
    n, p = phi.shape[0], m.shape[1]
    flat = accurate_matmul(phi.reshape(n * 6, 6), m, None if c is None else c.reshape(n * 6, p))
    return flat.reshape(n, 6, p)


@dataclass(frozen=True, slots=True)
class BatchArc:
    """An arc propagated with restarts at the interval boundaries (module docstring).

    Attributes
    ----------
    states : (N, 6) km, km/s, inertial.
    phi : (N, 6, 6) Φ(t, t̂).
    sens : (N, 6, n_q) ∂x(t)/∂q of the model parameters referred to t̂.
    batches : ∂x(t)/∂a_k referred to t̂.
    """

    states: np.ndarray
    phi: np.ndarray
    sens: np.ndarray
    batches: BatchPartials


def propagate_batches(prop: Propagator, spec: StochasticAccelerations, x0: np.ndarray,
                      t_s: np.ndarray, *, t0_s: float, param_values: Mapping[str, float],
                      orientation: EarthOrientation, epoch_jd_utc: float) -> BatchArc:
    """Propagate from (t0_s, x0) to the ascending times ``t_s`` (> t0_s), restarting at the
    boundaries of ``spec`` in between (module docstring).

    ``prop.params`` must end with ``spec.model_parameters`` (the n_c empirical accelerations,
    nominal 0); the sensitivities of the parameters before them are returned in ``sens``.
    """
    n_c = len(spec.components)
    n_q = len(prop.params) - n_c
    if prop.params[n_q:] != spec.model_parameters:
        raise ValueError(f"propagator parameters {prop.params} do not end with "
                         f"{spec.model_parameters}")
    n_s = spec.n_intervals * n_c
    bounds = np.asarray(spec.boundaries_s, dtype=float)
    t_end = float(t_s[-1])
    starts = np.concatenate([[t0_s], bounds[(bounds > t0_s) & (bounds < t_end)]])
    ends = np.append(starts[1:], t_end)
    x_start = np.asarray(x0, dtype=float)
    phi0, sq0, sa0 = np.eye(6), np.zeros((6, n_q)), np.zeros((6, n_s))
    out = {key: [] for key in ("states", "phi", "sens", "phi_seg", "sens_seg", "segment")}
    start_rows, intervals = [], []
    for m, (a, b) in enumerate(zip(starts, ends, strict=True)):
        take = (t_s > a) & (t_s <= b)
        grid = np.unique(np.append(t_s[take], b))
        traj = prop.propagate(x_start, grid, t0_s=float(a), stm=True,
                              param_values=param_values, orientation=orientation,
                              epoch_jd_utc=epoch_jd_utc)
        k = int(np.searchsorted(bounds, a, side="right")) - 1
        k = k if 0 <= k < spec.n_intervals else -1
        keep = np.isin(grid, t_s[take])
        phi_m, s_m = traj.stm, traj.sensitivity
        out["states"].append(traj.states[keep])
        out["phi"].append(_compose(phi_m[keep], phi0))
        out["sens"].append(_compose(phi_m[keep], sq0, s_m[keep, :, :n_q]))
        out["phi_seg"].append(phi_m[keep])
        out["sens_seg"].append(s_m[keep, :, n_q:])
        out["segment"].append(np.full(int(np.count_nonzero(keep)), m))
        start_rows.append(sa0)
        intervals.append(k)
        # carry everything to b, the next segment's start
        sa0 = _compose(phi_m[-1:], sa0)[0]
        if k >= 0:
            sa0[:, k * n_c:(k + 1) * n_c] += s_m[-1, :, n_q:]
        phi0, sq0 = _compose(phi_m[-1:], phi0)[0], _compose(phi_m[-1:], sq0, s_m[-1:, :, :n_q])[0]
        x_start = traj.states[-1]
    cat = {key: np.concatenate(value) for key, value in out.items()}
    return BatchArc(cat["states"], cat["phi"], cat["sens"], BatchPartials(
        cat["phi_seg"], cat["sens_seg"], cat["segment"], np.array(start_rows),
        np.array(intervals, dtype=int), n_c))
