"""Extended Kalman filter with an STM time update and the (J_N, J_M) choice.

Time update from t_{k-1} to t_k (Tapley, Schutz & Born 2004, Sec. 4.7): the reference
trajectory is propagated from the current estimate with the state model, the covariance
with the variational model's STM,

.. math::
    P_k^- = \\Phi_M(t_k, t_{k-1}) P_{k-1} \\Phi_M^T + Q_k,\\qquad
    Q_k = q\\begin{pmatrix} \\Delta t^3/3\\, I & \\Delta t^2/2\\, I \\\\
                          \\Delta t^2/2\\, I & \\Delta t\\, I \\end{pmatrix}

(white-noise acceleration of spectral density q km²/s³; q = 0 by default, as in the study).
Measurement update: filterpy's ``kalman.update`` (Joseph form) on the state deviation
δx = 0 with the prefit residual y = z - h(x_ref) and H̃ = ∂h/∂x; then the reference is reset,
x_ref ← x_ref + δx (the "extended" step). Simultaneous rows (several stations at one time)
are processed one after another.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from filterpy.kalman import update

from tapp.dynamics import Propagator
from tapp.errors import InputError, TooFewMeasurementsError
from tapp.frames.orientation import EarthOrientation
from tapp.measurements.observables import MeasurementModel
from tapp.measurements.observations import Observations


@dataclass(frozen=True, slots=True)
class PassResidual:
    """Largest |O - C| (prefit) of one pass, per observable kind (units of the kinds)."""

    station: str
    t_start_s: float
    t_end_s: float
    max_abs: np.ndarray


@dataclass(frozen=True, slots=True)
class EKFResult:
    """Filter output: the final estimate and what each measurement row did to it.

    M rows of k kinds (``obs.kinds``, their units: km, km/s, rad), processed in order.

    Attributes
    ----------
    prefit : (M, k) prefit residuals y = z − h(x⁻).
    x, P : final estimate (6,) km, km/s and its covariance (6, 6), at ``t_s``.
    t_s : time of the last row, s from the epoch.
    passes : per pass, the largest |prefit|.
    states : (M, 6) the estimate after each row's update.
    covariances : (M, 6, 6) its covariance P⁺ after each row's update.
    gains : (M, 6, k) the Kalman gain K of each row.
    process_noise : (M, 6, 6) Q added in the time update to each row's time (zero for a row
        at the time of the one before).
    """

    prefit: np.ndarray
    x: np.ndarray
    P: np.ndarray
    t_s: float
    passes: tuple[PassResidual, ...]
    states: np.ndarray
    covariances: np.ndarray
    gains: np.ndarray
    process_noise: np.ndarray


def process_noise(q_km2_s3: float, dt_s: float) -> np.ndarray:
    """Return Q (6, 6) of white-noise acceleration of spectral density q over dt (s)."""
    dt = abs(dt_s)
    eye = np.eye(3)
    return q_km2_s3 * np.block([[dt**3 / 3 * eye, dt**2 / 2 * eye],
                                [dt**2 / 2 * eye, dt * eye]])


def extended_kalman_filter(obs: Observations, prop: Propagator, x0: np.ndarray, P0: np.ndarray,
                           *, orientation: EarthOrientation, q_km2_s3: float = 0.0
                           ) -> EKFResult:
    """Filter ``obs`` from the estimate (x0 (6,), P0 (6, 6)) at t = 0, the stations placed
    and the field oriented by ``orientation``.

    Raises
    ------
    TooFewMeasurementsError
        No measurement in ``obs`` (the arc holds no pass): nothing to filter.
    InputError
        P0 not symmetric positive-definite, or q < 0.
    """
    if obs.count == 0:
        raise TooFewMeasurementsError(1, 0)
    P0 = np.asarray(P0, dtype=float)
    if P0.shape != (6, 6) or not np.allclose(P0, P0.T) or np.any(np.linalg.eigvalsh(P0) <= 0):
        raise InputError("ekf", "apriori", "a symmetric positive-definite 6x6 covariance")
    if q_km2_s3 < 0:
        raise InputError("ekf", "process_noise", "q >= 0", q_km2_s3)
    models = [MeasurementModel(s, orientation, obs.kinds) for s in obs.stations]
    R = np.diag(obs.sigma**2)
    x, P, t_prev = np.asarray(x0, dtype=float).copy(), P0.copy(), 0.0
    m, k = obs.values.shape
    prefit = np.empty_like(obs.values)
    states, covariances = np.empty((m, 6)), np.empty((m, 6, 6))
    gains, noise = np.empty((m, 6, k)), np.zeros((m, 6, 6))
    for row in range(m):
        t = float(obs.t_s[row])
        if t != t_prev:
            seg = prop.propagate(x, [t], t0_s=t_prev, orientation=orientation)
            phi = seg.stm[-1]
            x = seg.states[-1]
            noise[row] = process_noise(q_km2_s3, t - t_prev)
            # P⁻ = Φ P Φᵀ + Q
            P = phi @ P @ phi.T + noise[row]
            t_prev = t
        model = models[obs.station[row]]
        h = model.compute(obs.t_s[row:row + 1], x[None, :])[0]
        H = model.state_partials(obs.t_s[row:row + 1], x[None, :])[0]
        y = model.residual(obs.values[row:row + 1], h[None, :])[0]
        prefit[row] = y
        # K = P⁻ Hᵀ S⁻¹, S = H P⁻ Hᵀ + R: the gain update() applies (P⁻ symmetric)
        gains[row] = np.linalg.solve(H @ P @ H.T + R, H @ P).T
        dx, P = update(np.zeros(6), P, y, R, H)
        P = 0.5 * (P + P.T)
        x = x + dx
        states[row], covariances[row] = x, P
    passes = tuple(
        PassResidual(obs.stations[obs.station[rows[0]]].name, float(obs.t_s[rows[0]]),
                     float(obs.t_s[rows[-1]]), np.abs(prefit[rows]).max(axis=0))
        for rows in obs.passes())
    return EKFResult(prefit, x, P, t_prev, passes, states, covariances, gains, noise)
