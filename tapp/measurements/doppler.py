"""Count-based (integrated) two-way and three-way Doppler: conversions and the local transition.

The observable (``"doppler"`` in :class:`tapp.measurements.observables.MeasurementModel`) is
Moyer's (2003, DESCANSO Monograph 2, ch. 13) two-/three-way Doppler, the change of the
round-trip light time ρ = t_3 - t_1 (station clock) over a count interval T_c centred on the
sample time t, expressed as an equivalent range-rate, km/s:

.. math::

    \\dot\\rho_D(t) = \\frac{c}{2}\\,\\frac{\\rho(t_e) - \\rho(t_s)}{T_c}
                  = \\frac{R(t_e) - R(t_s)}{T_c},\\qquad t_{s,e} = t \\mp T_c/2,

R = c ρ / 2 the two-/three-way range of the light-time model (Newtonian or relativistic).
Sign: positive when the round trip lengthens (the spacecraft recedes).

In Hz at the station's band (:mod:`tapp.measurements.bands`: uplink f_T, turnaround M₂): the
DSN's Doppler observable with a constant (unramped) uplink is F₂ = M₂ f_T - f_R =
M₂ f_T (ρ_e - ρ_s) / T_c (Moyer ch. 13, the received frequency f_R = M₂ f_T (1 - dρ/dt) counted
over T_c), so

.. math:: F_2 = \\frac{2 M_2 f_T}{c}\\,\\dot\\rho_D,

positive when receding: 56.2 Hz per m/s at X-band (1 mHz = 0.0178 mm/s). Three-way: f_T and
M₂ of the uplink station's band.
"""

from __future__ import annotations

import numpy as np

from tapp.constants import C_LIGHT_km_s
from tapp.measurements.bands import Band

#: Default count interval T_c, s.
DEFAULT_COUNT_TIME_s = 60.0


def hz_per_km_s(band: Band) -> float:
    """Return dF₂ / d(equivalent range-rate), Hz per km/s: 2 M₂ f_T / c (module docstring)."""
    return 2.0 * band.downlink_hz / C_LIGHT_km_s


def doppler_hz(range_rate_km_s, band: Band):
    """Return the Doppler F₂ = M₂ f_T - f_R, Hz, of an equivalent range-rate (km/s)."""
    return hz_per_km_s(band) * np.asarray(range_rate_km_s, dtype=float)


def range_rate_from_hz(doppler_hz_, band: Band):
    """Return the equivalent range-rate, km/s, of a Doppler F₂ in Hz (inverse of
    :func:`doppler_hz`): e.g. a noise σ given in Hz."""
    return np.asarray(doppler_hz_, dtype=float) / hz_per_km_s(band)


def local_transition(state_eci, dt_s: float, mu_km3_s2: float):
    """Return Φ(t + dt, t) ≈ exp(F dt) to second order, shape (N, 6, 6).

    .. math::

        \\Phi \\approx \\begin{pmatrix} I + G\\,dt^2/2 & I\\,dt \\\\ G\\,dt & I + G\\,dt^2/2
        \\end{pmatrix},\\qquad G = \\frac{\\mu}{r^3}\\,(3\\hat{\\mathbf r}\\hat{\\mathbf r}^T - I),

    the transition of the central body's field about the state at t: what maps the partials at
    the ends of a count interval to the state at its centre. Neglected: the change of G over dt
    and the third-order terms (relative O(G dt² · v dt / r): 3e-5 of a Doppler partial in LEO
    with dt = 30 s, 1e-12 at the Moon's distance) and the perturbing accelerations' gradients.

    Parameters
    ----------
    state_eci : array_like, shape (N, 6)
        States at t, [km, km/s].
    dt_s : float
        The step, s.
    mu_km3_s2 : float
        The central body's GM.
    """
    x = np.asarray(state_eci, dtype=float)
    r_norm = np.linalg.norm(x[..., :3], axis=-1)[..., None, None]
    r_hat = x[..., :3, None] / r_norm
    eye = np.eye(3)
    g = mu_km3_s2 / r_norm**3 * (3.0 * r_hat * np.swapaxes(r_hat, -1, -2) - eye)
    phi = np.zeros(x.shape[:-1] + (6, 6))
    phi[..., :3, :3] = eye + 0.5 * dt_s * dt_s * g
    phi[..., :3, 3:] = dt_s * eye
    phi[..., 3:, :3] = dt_s * g
    phi[..., 3:, 3:] = eye + 0.5 * dt_s * dt_s * g
    return phi
