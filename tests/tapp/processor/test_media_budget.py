"""Considering a zenith troposphere error moves the deep-space B-plane σ by what a Monte Carlo
on the raw rows says (issue 30's budget check).

The tape: deep_space.toml's trans-lunar trajectory tracked by the three DSN complexes for its
first 2.5 days (range 1 m, range-rate 0.1 mm/s, one sample every 10 min, two-way light time,
the troposphere on every link: Saastamoinen-Davis zenith delays mapped by Niell), the Moon's
B-plane at the periapsis (day 3.59) as the miss, and each complex's zenith dry and wet delays
in q. The fit world estimates the injection state and holds the zenith delays at their nominal
values; the real world's wet zenith delays are wrong by σ = 5 cm at each complex,
independently (the classic calibration error of a water-vapour radiometer-less site). TAPP
III's real-world covariance of the miss, B C Bᵀ at each print time, is compared with the
sample covariance of B e over 20,000 draws of the fit-world estimator's error e on the raw
rows (:func:`tests.tapp.processor.helpers.fit_error_moments`: a priori errors, white noise and
the zenith errors drawn, the estimator run as a batch least squares), entry by entry with
|z| < 5 (Bonferroni over 3 prints x 6 entries: a false alarm below 1e-5). The test has power:
the covariance without the troposphere error fails the same sample.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from tapp.examples import FOLDER
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate
from tests.tapp.processor.helpers import N_DRAWS, PRINTS, Z_LIMIT, fit_error_moments, run, z_scores

#: The real world's zenith wet error per complex, km (5 cm), and the orbit's a priori σ.
WET_SIGMA_km = 5e-5
ORBIT_SIGMA = {"x_km": 10.0, "y_km": 10.0, "z_km": 10.0, "vx_km_s": 0.01, "vy_km_s": 0.01,
               "vz_km_s": 0.01}
END = "2026-03-13T00:00:00"


@pytest.fixture(scope="module")
def tape():
    doc = tomllib.loads((FOLDER / "deep_space.toml").read_text())
    del doc["stochastic"]
    doc["model"]["srp"] = False
    doc["tracking"].update(end=END, data_interval_s=600.0)
    doc["times"] = {"input_step_s": 43200.0, "end": END}
    doc["parameters"] = {"dynamic": [], "station_location": "none", "station_biases": [],
                         "media": ["troposphere"]}
    doc["media"] = {"troposphere": True}
    doc["noise"]["real"] = dict(doc["noise"]["fit"])
    return simulate(parse_scenario(doc, "deep_space.toml"), raw=True).tape


def _sigmas(tape, wet_km: float) -> dict[str, float]:
    return {n: ORBIT_SIGMA.get(n, wet_km if n.endswith("zenith_wet_km") else 0.0)
            for n in tape.parameters.name}


def _miss_covariances(tape, real_wet_km: float) -> dict[int, np.ndarray]:
    doc = {"fit": {"apriori": {"sigma": _sigmas(tape, 0.0)}},
           "real": {"apriori": {"sigma": _sigmas(tape, real_wet_km)}},
           "times": {"print": list(PRINTS)}, "commands": {"print": ["cov-real m"]}}
    return {b.k: b.entities[0].matrix for b in run(tape, doc).blocks if b.kind == "print"}


def test_a_5_cm_zenith_wet_error_moves_the_b_plane_sigma_as_the_monte_carlo_says(tape):
    names = list(tape.parameters.name)
    fitted = [i for i, n in enumerate(names) if n in ORBIT_SIGMA]
    real = _sigmas(tape, WET_SIGMA_km)
    chol_bar = np.diag([real[n] for n in names])
    s0 = np.diag([1.0 / ORBIT_SIGMA[names[i]] ** 2 for i in fitted])
    moments = fit_error_moments(tape.raw, s0, fitted, chol_bar, seed=20261128)
    b = tape.miss.B
    with_wet, without = _miss_covariances(tape, WET_SIGMA_km), _miss_covariances(tape, 0.0)
    moved = []
    for k in PRINTS:
        sample = b @ moments[k] @ b.T
        assert np.max(z_scores(sample, with_wet[k], N_DRAWS)) < Z_LIMIT, k
        # power: the covariance without the zenith error is refused by the same sample
        assert np.max(z_scores(sample, without[k], N_DRAWS)) > 2 * Z_LIMIT, k
        moved.append(np.sqrt(np.diag(with_wet[k])) / np.sqrt(np.diag(without[k])) - 1.0)
    # the error moves σ(B·R), σ(B·T) by more than the sampling error of a σ (0.5 % at N_DRAWS)
    assert np.max(moved) > 0.05
