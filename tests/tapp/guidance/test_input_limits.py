"""Guidance inputs at the edge (issue "Hardening, second round", item 3).

The audit, on main: ``sigma_fixed_mm_s`` had no upper bound (1e300 overflowed in Python,
1e150 failed in LAPACK); a T32 Σ scaled by 1e300 failed in LAPACK. Now the field is bounded,
the tape's numbers are (tests/tapp/io/tape/test_t32.py), and what the bounds let through
together is caught before any sample is drawn (:func:`physical_linear_covariance`).
"""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest
from scipy import integrate, stats

from iter.execute import Execution
from tapp.errors import InputError
from tapp.guidance.guidefile import MAX_FIXED_MM_S
from tapp.guidance.magnitude import CDF_TOL, SERIES_BELOW, quadratic_cdf
from tapp.guidance.study import guidance_study
from tapp.io.tape.checks import MAX_MAGNITUDE
from tapp.io.tape.t32 import validate as validate_t32
from tapp.report.guidance import guidance_dict
from tests.tapp.guidance.helpers import EXECUTION, deep_space_t32, guide, with_recycles

ALL = ["b_dot_r_km", "b_dot_t_km", "flight_time_s"]
#: Ruben's series against closed forms and quadrature: the CDF's absolute error target is
#: 1e-10 (CDF_TOL); they agree to ~1e-16 relative where the CDF is small.
SERIES_REL = 1e-9


@pytest.mark.parametrize("value", [1e300, 1e150, MAX_FIXED_MM_S * (1 + 1e-15) + 1])
def test_a_fixed_execution_error_beyond_its_bound_is_refused(value: float) -> None:
    with pytest.raises(InputError) as info:
        guide(targets={"miss": ALL}, execution={**EXECUTION, "sigma_fixed_mm_s": value})
    assert str(info.value) == (f"guide.toml: execution.sigma_fixed_mm_s: expected a finite "
                               f"number <= 1e+06 (got {value!r})")


def _study(tape, samples: int = 1000, **tables):
    return guidance_study(tape, guide(targets={"miss": ALL}, **tables), samples=samples,
                          seed=1, execution=Execution(serial=True), tape_source="t.t32.h5")


def test_at_the_top_of_the_fixed_error_the_linear_corridor_agrees_with_the_samples() -> None:
    # 1 km/s per axis leaves a miss ~1e6 times the 5 km corridor: Imhof's integral gave
    # P(inside) = 0.257 (and an IntegrationWarning) where it is 3e-7
    result = _study(deep_space_t32(), execution={**EXECUTION, "sigma_fixed_mm_s":
                                                 MAX_FIXED_MM_S},
                    corridor={"radius_km": 5.0})
    assert result.monte_carlo.outside.bplane == 1.0
    assert result.linear.outside.bplane > 1.0 - 1e-6
    text = json.dumps(guidance_dict(result))
    assert not re.search(r"\bNaN\b|Infinity", text)


@pytest.mark.parametrize("lam", [[1.0, 1.0], [1.0, 1.0, 1.0], [1.64e6, 1.50e6], [3.0, 0.2],
                                 [1.0, 1e-6]])
def test_small_quadratic_cdfs_come_from_rubens_series(lam: list[float]) -> None:
    lam = np.array(lam)
    for x in (1e-9, 1e-6, 0.5 * SERIES_BELOW, 2.0 * SERIES_BELOW):
        q = x * lam.max()
        got = quadratic_cdf(q, lam)
        if np.all(lam == lam[0]):  # λ χ²_r: closed form
            want = stats.chi2.cdf(q / lam[0], lam.size)
        else:  # two terms, conditioned on the first: ∫ P(λ₁ χ²₁ ≤ q − λ₀ a) dF(a)
            want = integrate.quad(lambda a, q=q: stats.chi2.cdf((q - lam[0] * a) / lam[1], 1)
                                  * stats.chi2.pdf(a, 1), 0.0, q / lam[0], epsabs=0.0,
                                  epsrel=1e-12, limit=200)[0]
        # the series is relative to the (small) CDF; Imhof's integral, above, absolute
        tol = SERIES_REL * want if x < SERIES_BELOW else CDF_TOL
        assert abs(got - want) <= tol, (lam, x, got, want)


def test_guidance_faster_than_light_is_refused_naming_the_recycle() -> None:
    tape = deep_space_t32()
    ok = _study(tape, execution=EXECUTION)
    assert max(m.magnitude.mean_km_s for m in ok.linear.manoeuvres) < 1.0
    far = dataclasses.replace(tape, Lambda0_real_factor=tape.Lambda0_real_factor * 1e25)
    validate_t32(far, "t.t32.h5")  # within the tapes' bound: only the physics refuses it
    with pytest.raises(InputError, match=r"^t.t32.h5: recycles/1: expected a manoeuvre whose "
                                         r"Δv σ is below the speed of light \(299,792.458 km/s\)"
                                         r" \(got '1.19e\+24 km/s'\)$"):
        _study(far, execution=EXECUTION)


def test_a_final_miss_beyond_its_bound_is_refused_naming_the_component() -> None:
    tape = deep_space_t32()
    last = len(tape.recycles)
    wide = with_recycles(tape, B=lambda r: r.B * (1e40 if r.number == last else 1.0))
    with pytest.raises(InputError, match=r"^t.t32.h5: miss/b_dot_r_km: expected a final miss "
                                         r"σ within 1e\+30 km"):
        _study(wide, execution=EXECUTION)


def test_products_that_overflow_are_refused_before_any_sample() -> None:
    # L and Σ each at the tapes' bound: valid alone, their products overflow a double
    tape = deep_space_t32()

    def top(a: np.ndarray) -> np.ndarray:
        return a * (MAX_MAGNITUDE / np.abs(a).max())

    both = with_recycles(tape, L=lambda r: top(r.L), Sigma_factor=lambda r: top(r.Sigma_factor))
    validate_t32(both, "t.t32.h5")
    with pytest.raises(InputError) as info:
        _study(both, execution=EXECUTION)
    assert str(info.value) == ("t.t32.h5: recycles: expected covariances and partials whose "
                               "products are finite (the linear covariance of the guidance) "
                               "(got 'overflow encountered in matmul')")
