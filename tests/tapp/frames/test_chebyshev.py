"""Piecewise Chebyshev tables (tapp.frames.chebyshev): exactness, the interpolation error bound,
the span check and stacking."""

import math

import numpy as np
import pytest

from tapp.frames.chebyshev import ChebyshevTable, fit_chebyshev

#: A polynomial of degree < n_coef is reproduced to rounding: 64 ulp of its largest value
#: (measured: 8 ulp for degree 8 over six segments).
POLYNOMIAL_ROUNDING_rel = 64 * np.finfo(float).eps
OMEGA_rad_s = 2.0 * math.pi / 86400.0


def _chebyshev_interpolation_bound(derivative_bound: float, h_s: float, n_coef: int) -> float:
    """max |f − p| for interpolation at the n first-kind Chebyshev nodes of a segment h long.

    |f − p| ≤ max|f⁽ⁿ⁾| (h/2)ⁿ / (2ⁿ⁻¹ n!)  (e.g. Trefethen, Approximation Theory and
    Approximation Practice, ch. 11; Burden & Faires, Numerical Analysis, Cor. 8.11).
    """
    return derivative_bound * (h_s / 2.0) ** n_coef / (2 ** (n_coef - 1) * math.factorial(n_coef))


def _trig(t):
    """Two series of 3-vectors: (sin ωt, cos ωt, sin 2ωt) and (t/1e5, 1, −cos ωt)."""
    t = np.asarray(t, dtype=float)
    wt = OMEGA_rad_s * t
    return np.stack([np.stack([np.sin(wt), np.cos(wt), np.sin(2 * wt)], -1),
                     np.stack([t / 1e5, np.ones_like(t), -np.cos(wt)], -1)])


def test_polynomial_of_lower_degree_is_reproduced_to_rounding():
    rng = np.random.default_rng(20240611)
    n_coef = 9
    c = rng.normal(size=(2, 3, n_coef - 1))  # degree 7 < 9 coefficients

    def poly(t):
        x = (np.asarray(t) - 1000.0) / 3000.0
        return np.stack([np.stack([np.polynomial.polynomial.polyval(x, c[s, i])
                                   for i in range(3)], -1) for s in range(2)])

    # Reversed limits are accepted: segments run from the smaller time.
    table = fit_chebyshev(poly, 7000.0, -2000.0, 1500.0, n_coef)
    assert (table.n_series, table.n_segments, table.n_coef) == (2, 6, n_coef)
    assert (table.t0_s, table.h_s, table.t_end_s) == (-2000.0, 1500.0, 7000.0)
    t = np.concatenate([np.linspace(-2000.0, 7000.0, 1001), rng.uniform(-2000.0, 7000.0, 500)])
    expected = poly(t)
    assert table.evaluate(t).shape == (2, t.size, 3)
    assert np.abs(table.evaluate(t) - expected).max() <= (
        POLYNOMIAL_ROUNDING_rel * np.abs(expected).max())


@pytest.mark.parametrize("n_coef", [6, 8, 10, 12])
def test_sine_within_the_chebyshev_interpolation_bound(n_coef):
    h_s = 43200.0
    table = fit_chebyshev(_trig, 0.0, 5 * 86400.0, h_s, n_coef)
    t = np.linspace(0.0, 5 * 86400.0, 20001)
    got = table.evaluate(t)
    want = _trig(t)
    bound_1w = _chebyshev_interpolation_bound(OMEGA_rad_s**n_coef, h_s, n_coef)
    bound_2w = _chebyshev_interpolation_bound((2 * OMEGA_rad_s) ** n_coef, h_s, n_coef)
    err_sin = np.abs(got[0, :, 0] - want[0, :, 0]).max()
    assert err_sin <= bound_1w
    # Near-minimax: the bound is nearly reached (measured 0.94-0.96 of it), so the test would
    # notice a fit at the wrong nodes or a wrong coefficient weight.
    assert err_sin >= 0.5 * bound_1w
    assert np.abs(got[0, :, 1] - want[0, :, 1]).max() <= bound_1w
    assert np.abs(got[0, :, 2] - want[0, :, 2]).max() <= bound_2w
    assert np.abs(got[1, :, 2] - want[1, :, 2]).max() <= bound_1w
    # The linear and constant components are exact to rounding.
    assert np.abs(got[1, :, :2] - want[1, :, :2]).max() <= POLYNOMIAL_ROUNDING_rel * 5 * 0.864


def test_evaluate_raises_outside_the_span_and_accepts_its_ends():
    table = fit_chebyshev(_trig, 100.0, 100.0 + 3 * 3600.0, 3600.0, 8)
    ends = table.evaluate([100.0, 100.0 + 3 * 3600.0])
    bound = _chebyshev_interpolation_bound((2 * OMEGA_rad_s) ** 8, 3600.0, 8)
    assert np.abs(ends - _trig(np.array([100.0, 10900.0]))).max() <= bound
    with pytest.raises(ValueError, match="outside the Chebyshev table"):
        table.evaluate([50.0])
    with pytest.raises(ValueError, match="outside the Chebyshev table"):
        table.evaluate(np.array([200.0, 100.0 + 3 * 3600.0 + 1.0]))


def test_segments_do_not_stop_short_of_the_end():
    # 10 000 s in 3 600 s segments: three segments, the last one running past the end.
    table = fit_chebyshev(_trig, 0.0, 10000.0, 3600.0, 10)
    assert table.n_segments == 3 and table.t_end_s == 10800.0
    table.evaluate([10000.0])


def test_stacked_concatenates_series_and_requires_equal_segments():
    a = fit_chebyshev(_trig, 0.0, 86400.0, 43200.0, 10)
    b = fit_chebyshev(lambda t: _trig(t)[:1] * 2.0, 0.0, 86400.0, 43200.0, 10)
    ab = a.stacked(b)
    assert ab.n_series == 3
    t = np.linspace(0.0, 86400.0, 97)
    assert np.array_equal(ab.evaluate(t), np.concatenate([a.evaluate(t), b.evaluate(t)]))
    assert ab.coeffs.flags.c_contiguous  # the compiled driver reads this layout
    empty = ChebyshevTable.empty()
    assert empty.n_series == 0
    assert empty.stacked(a) is a and a.stacked(empty) is a
    for other in (fit_chebyshev(_trig, 0.0, 86400.0, 21600.0, 10),  # other length
                  fit_chebyshev(_trig, 60.0, 86460.0, 43200.0, 10),  # other start
                  fit_chebyshev(_trig, 0.0, 86400.0, 43200.0, 12),  # other degree
                  fit_chebyshev(_trig, 0.0, 3 * 86400.0, 43200.0, 10)):  # more segments
        with pytest.raises(ValueError, match="share their segments"):
            a.stacked(other)
