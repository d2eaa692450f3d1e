"""EKF at the noise level with matching models; R(t) against the analytic two-body STM."""

from __future__ import annotations

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator, earth_model
from tapp.od import setup
from tapp.od.ekf import extended_kalman_filter
from tapp.od.rsig import r_of_stm, r_signature
from tapp.od.study_file import offset, shipped_study
from tapp.orbit.elements import cartesian_to_elements, kepler_states

#: The shipped study file, read once: every case here is one of its orbits.
STUDY = shipped_study()


def test_ekf_with_matching_models_reaches_the_noise_level() -> None:
    x_true = setup.true_orbit("SATORB1", STUDY)
    x_start = setup.initial_estimate(x_true, offset(STUDY))
    apriori = STUDY.data["ekf"]["apriori"]["1"]
    obs = setup.simulated_observations(x_true, "J2", setup.network_for(x_true, None, STUDY), STUDY)
    obs = obs.window(18 * 3600.0)
    res = extended_kalman_filter(obs, Propagator(earth_model("J2")), x_start,
                                 np.diag(np.square(apriori)),
                                 orientation=setup.orientation(STUDY))
    late = obs.t_s > 9 * 3600.0
    normalised = res.prefit[late] / obs.sigma
    rms = np.sqrt(np.mean(normalised**2, axis=0))
    # prefit residuals include the (small) state uncertainty: RMS between 0.8 and 1.3 σ
    assert np.all((rms > 0.8) & (rms < 1.3)), rms
    assert np.linalg.norm(res.x[:3] - Propagator(earth_model("J2")).propagate(
        x_true, [res.t_s], stm=False).states[-1, :3]) < 0.05  # 50 m after 18 h


def test_r_signature_j0_matches_analytic_kepler_stm_and_grows_linearly() -> None:
    x0 = setup.true_orbit("SATORB1", STUDY)
    period = 2 * np.pi * np.sqrt(6550.524**3 / GM_EARTH_km3_s2)
    t = np.arange(0.0, 48 * 3600.0, period)  # same orbital phase: the periodic part drops out
    sig = r_signature(Propagator(earth_model("J0")), x0, t, setup.orientation(STUDY))
    # analytic STM: central differences of the closed-form Kepler solution (Kepler's equation)
    el0 = np.asarray(cartesian_to_elements(x0, GM_EARTH_km3_s2))
    delta = np.array([1e-3] * 3 + [1e-6] * 3)
    cols = []
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = delta[j]
        plus = kepler_states(np.asarray(cartesian_to_elements(x0 + dx, GM_EARTH_km3_s2)), t)
        minus = kepler_states(np.asarray(cartesian_to_elements(x0 - dx, GM_EARTH_km3_s2)), t)
        cols.append((plus - minus) / (2 * delta[j]))
    phi = np.stack(cols, axis=-1)
    assert el0[0] > 0
    np.testing.assert_allclose(sig.r, r_of_stm(phi), rtol=1e-5)
    slope, intercept = np.polyfit(t[1:], sig.r[1:], 1)
    fit = slope * t[1:] + intercept
    assert np.abs(fit - sig.r[1:]).max() < 1e-3 * sig.r[-1]
