"""The Monte Carlo against the linear covariance, on the deep-space tape (three manoeuvres,
either navigation after a manoeuvre).

Statistical levels (N samples, every test independent of the others' outcome):

- means (Δv components of each manoeuvre, final miss components: 3 x 3 + 3 = 12 values):
  z = mean / (σ_linear / √N), |z| < 4.5: P(|z| > 4.5) = 6.8e-6 each, family-wise < 1e-4;
- covariance entries (6 per Δv, 6 of the miss: 24 values) as zero-mean second moments
  mean(x_i x_j) against the linear covariance, each z-score from the entry's own sampling σ
  (the sample σ of x_i x_j over √N: valid whatever the law, the later Δv's being
  heavy-tailed), |z| < 5: family-wise < 24 x 5.7e-7 = 1.4e-5;
- the first manoeuvre's 99 % ΔV (its Δv is Gaussian, so the linear value is exact): the
  number of samples below it is Binomial(N, 0.99) when it is right, |z| < 5; equivalently it
  lies between the order statistics N·0.99 ∓ 5√(N·0.99·0.01) of the sample.

Each navigation is a separate family at these levels. A model error the size of one
execution-error term moves these by tens of σ at this N (checked by
:func:`test_the_checks_see_a_missing_execution_error`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from iter.execute import Execution
from tapp.guidance.guidefile import bind
from tapp.guidance.linear import linear_covariance
from tapp.guidance.shards import run_shards
from tapp.guidance.statistics import linear_outcome
from tests.tapp.guidance.helpers import deep_space_t32, guide

N = 50_000
MEAN_Z = 4.5
COV_Z = 5.0
SERIAL = Execution(serial=True)


@pytest.fixture(scope="module", params=["tape", "inflate"])
def problem(request):
    """Both navigations after a manoeuvre (tapp.guidance.navigation)."""
    return bind(guide(navigation={"after_manoeuvre": request.param}), deep_space_t32(),
                "guide.toml").problem


@pytest.fixture(scope="module")
def samples(problem):
    return run_shards(problem, 2026, N, SERIAL).samples


def _outcomes(samples) -> list[np.ndarray]:
    """Per-sample vectors: Δv of each manoeuvre, then the final miss."""
    return [samples.dv_km_s[:, i] for i in range(samples.dv_km_s.shape[1])] + [samples.miss]


def _z_scores(problem, samples) -> tuple[np.ndarray, np.ndarray]:
    lin = linear_covariance(problem)
    covs = [*lin.dv_cov, lin.miss_cov]
    mean_z, cov_z = [], []
    for x, c in zip(_outcomes(samples), covs, strict=True):
        mean_z.append(x.mean(axis=0) / np.sqrt(np.diag(c) / N))
        iu = np.triu_indices(c.shape[0])
        prod = (x[:, :, None] * x[:, None, :])[:, iu[0], iu[1]]
        cov_z.append((prod.mean(axis=0) - c[iu]) / (prod.std(axis=0) / np.sqrt(N)))
    return np.concatenate(mean_z), np.concatenate(cov_z)


def test_means_and_covariances_agree_within_sampling_error(problem, samples):
    mean_z, cov_z = _z_scores(problem, samples)
    assert mean_z.size == 12 and cov_z.size == 24
    assert np.all(np.abs(mean_z) < MEAN_Z), mean_z
    assert np.all(np.abs(cov_z) < COV_Z), cov_z


def test_the_99_percent_dv_of_the_first_manoeuvre_agrees(problem, samples):
    lin = linear_outcome(problem, linear_covariance(problem), None)
    p99 = dict(lin.manoeuvres[0].magnitude.percentiles_km_s)[99.0]
    mags = np.linalg.norm(samples.dv_km_s[:, 0], axis=1)
    below = int(np.count_nonzero(mags <= p99))
    assert abs(below - 0.99 * N) / np.sqrt(N * 0.99 * 0.01) < COV_Z
    mean = lin.manoeuvres[0].magnitude.mean_km_s
    assert abs(mags.mean() - mean) / (mags.std() / np.sqrt(N)) < MEAN_Z


def test_the_checks_see_a_missing_execution_error(problem, samples):
    """The same samples against a linear covariance without the execution errors of the
    first manoeuvre's σ_p: the later covariances are far outside the sampling error."""
    weaker = dataclasses.replace(problem, errors=dataclasses.replace(
        problem.errors, sigma_proportional=0.0))
    _, cov_z = _z_scores(weaker, samples)
    assert np.max(np.abs(cov_z)) > 10 * COV_Z
