"""TAPP III's real-world covariance against a Monte Carlo of the fit-world estimator.

The tape's raw rows (one per observation: partials A referred to the epoch, fit weight w,
real-world noise model of its segment) let the test simulate what TAPP III only predicts:
draw the a priori error δx ~ N(0, Λ̄) and correlated noise δm ~ N(0, M) (white + per-pass
bias + exponentially correlated, M block-diagonal over segments as TAPP I models it), run
the fit-world estimator on each draw (batch least squares with GM held fixed and white
weights: the estimate μ'δx = Λ' Aᵀ W (A δx + δm)), and compare the sample covariance of the
actual error δx − μ'δx with the processor's Λ̄' at every print time, through two recycles.

Statistical test: for N draws of a zero-mean Gaussian vector, the sample covariance entry
Ĉ_ij has variance (C_ii C_jj + C_ij²)/N; each entry's z-score must satisfy |z| < 5. Over the
~800 entries checked the family-wise false-alarm probability is below 5e-4 (Bonferroni,
P(|z| > 5) = 5.7e-7 per entry).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.tapp.processor.helpers import (
    N_DRAWS,
    PRINTS,
    Z_LIMIT,
    deck,
    fit_error_moments,
    leo_tape,
    run,
    sigmas,
    z_scores,
)


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


def test_real_world_covariance_matches_a_monte_carlo_of_the_fit_estimator(tape):
    raw = tape.raw
    assert raw is not None and np.all(tape.records.j == 0)
    names = list(tape.parameters.name)
    gm = names.index("GM_km3_s2")
    fit_sigma = sigmas(tape, GM_km3_s2=0.0)
    real_sigma = sigmas(tape, GM_km3_s2=0.01)
    out = run(tape, deck(tape, fit=fit_sigma, real=real_sigma,
                         times={"print": list(PRINTS), "recycle": [1, 2]},
                         commands={"print": ["cov-real o@epoch", "cov-fit o@epoch"]}))
    predicted = {b.k: b.entities[0].matrix for b in out.blocks if b.kind == "print"}
    fit_world = {b.k: b.entities[1].matrix for b in out.blocks if b.kind == "print"}

    # the fit-world estimator at each print time, from the raw rows alone
    n_o = tape.n_o
    fitted = [i for i in range(n_o) if i != gm]
    s0 = np.diag([1.0 / fit_sigma[names[i]] ** 2 for i in fitted])
    lam_bar = np.diag([real_sigma[n] ** 2 for n in names])
    moments = fit_error_moments(raw, s0, fitted, np.linalg.cholesky(lam_bar), seed=20261123)
    for k in PRINTS:
        z = z_scores(moments[k], predicted[k], N_DRAWS)
        assert np.max(z) < Z_LIMIT, (k, np.unravel_index(np.argmax(z), z.shape), np.max(z))
        # the test has power: the fit world's own covariance (GM known, white noise) fails it
        assert np.max(z_scores(moments[k], fit_world[k], N_DRAWS, skip=gm)) > 10 * Z_LIMIT
