"""Batch differential correction: the study's contrast, exact recovery, covariance realism."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from tapp.dynamics import Propagator, earth_model
from tapp.od import setup
from tapp.od.batch import DCSettings, differential_correction
from tapp.od.observations import simulate

TEN_METRES_km = 1e-2
ONE_CM_km = 1e-5


@pytest.fixture(scope="module")
def satorb1() -> tuple[np.ndarray, np.ndarray]:
    x_true = setup.true_orbit("SATORB1")
    return x_true, setup.initial_estimate(x_true, setup.offset())


def _network(x_true):
    return setup.network_for(x_true, None)


def test_ci_contrast_j2j2_converges_j2j0_diverges(satorb1) -> None:
    """The brief's one outcome: SATORB1, 24 h: (J2,J2) converges (in about 4 iterations)
    to the true orbit; (J2,J0) diverges."""
    x_true, x_start = satorb1
    obs = setup.simulated_observations(x_true, "J2", _network(x_true)).window(86400.0)
    theta0 = setup.tracking().theta0_rad
    good = differential_correction(obs, Propagator(earth_model("J2"), earth_model("J2")),
                                   x_start, theta0_rad=theta0)
    assert good.converged and len(good.iterations) <= 6
    assert np.linalg.norm(good.x0[:3] - x_true[:3]) < TEN_METRES_km
    assert good.rms[-1] == pytest.approx(1.0, abs=0.1)  # weighted RMS at the noise level
    bad = differential_correction(obs, Propagator(earth_model("J2"), earth_model("J0")),
                                  x_start, theta0_rad=theta0)
    assert not bad.converged
    assert bad.rms[-1] > bad.rms[0]


def test_noise_free_matching_models_recover_truth(satorb1) -> None:
    x_true, x_start = satorb1
    prop = Propagator(earth_model("J2"))
    t = np.arange(0.0, 86400.0 + 1, 30.0)
    obs = simulate(prop, x_true, _network(x_true), t, setup.tracking().sigma, None, 0.4)
    result = differential_correction(obs, prop, x_start, theta0_rad=0.4,
                                     settings=DCSettings(rms_rel_tol=1e-6))
    assert result.converged
    assert np.linalg.norm(result.x0[:3] - x_true[:3]) < ONE_CM_km


def test_formal_covariance_matches_scatter_of_noisy_runs() -> None:
    """NEES = Σ (x̂-x)ᵀ P⁻¹ (x̂-x) over N runs is χ²(6N) when P is the true covariance;
    accept at the two-sided 99.9 % level. 120 runs of a 6-hour SATORB2 arc."""
    x_true = setup.true_orbit("SATORB2")
    prop = Propagator(earth_model("J2"))
    stations = _network(x_true)
    t = np.arange(0.0, 6 * 3600.0 + 1, 30.0)
    sigma = setup.tracking().sigma
    root = np.random.SeedSequence(2024)
    n_runs = 120
    nees = 0.0
    for child in root.spawn(n_runs):
        obs = simulate(prop, x_true, stations, t, sigma, np.random.default_rng(child), 0.0)
        res = differential_correction(obs, prop, x_true, settings=DCSettings(rms_rel_tol=1e-4))
        err = res.iterations[-1].x0 - x_true
        nees += err @ np.linalg.solve(res.covariance, err)
    lo, hi = chi2.ppf([0.0005, 0.9995], 6 * n_runs)
    assert lo < nees < hi, (lo, nees, hi)


def test_settings_are_validated() -> None:
    from tapp.errors import InputError

    with pytest.raises(InputError, match="max_iterations"):
        DCSettings(max_iterations=0)
    with pytest.raises(InputError, match="divergence_ratio"):
        DCSettings(divergence_ratio=1.0)
