"""The regression algorithm (seed §2.5) against the textbook and its own identities."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.processor import SingularFitError, regression

#: Rounding of products of well-conditioned matrices of order 10.
TIGHT = 1e-12


def _spd(rng: np.random.Generator, n: int, rows: int | None = None) -> np.ndarray:
    g = rng.standard_normal((rows or 2 * n, n))
    return g.T @ g


def _scaled_err(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.abs(np.diag(b)))
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def test_outputs_follow_the_seed_formulas_and_are_exactly_symmetric():
    rng = np.random.default_rng(1)
    n_o, n_1 = 8, 6
    e1 = np.vstack([np.eye(n_1), rng.standard_normal((n_o - n_1, n_1)) * 0.1])
    s00, j00, jt00 = _spd(rng, n_o), _spd(rng, n_o), _spd(rng, n_o)
    lam_bar = np.linalg.inv(_spd(rng, n_o))
    r = regression(e1, s00, j00, lam_bar, jt00)
    s1_11 = e1.T @ (s00 + j00) @ e1
    lam11 = np.linalg.inv(s1_11)
    lam00 = e1 @ lam11 @ e1.T
    big_l = np.eye(n_o) - lam00 @ j00
    assert np.allclose(r.S1_11, s1_11, rtol=TIGHT, atol=0)
    assert np.allclose(r.Lambda1_11, lam11, rtol=1e-10, atol=0)
    assert np.allclose(r.L, big_l, rtol=0, atol=1e-10)
    expected = big_l @ lam_bar @ big_l.T + lam00 @ jt00 @ lam00
    assert _scaled_err(r.Lambda_real, expected) < 1e-10
    for m in (r.S1_00, r.S1_11, r.Lambda1_11, r.Lambda1_00, r.Lambda_real):
        assert np.array_equal(m, m.T)


def test_consider_covariance_equals_tapley_schutz_born():
    """Fit world estimates x and holds c fixed; real world gives c its σ_c (TSB §6.3).

    P_x = (P̄_x⁻¹ + H_xᵀWH_x)⁻¹, S_xc = −P_x H_xᵀ W H_c, P_c = P_x + S_xc P_cc S_xcᵀ,
    cross covariance S_xc P_cc, the constant's own block P_cc: computed here from the
    normal-matrix blocks, independently of the regression algorithm.
    """
    rng = np.random.default_rng(7)
    n_x, n_c = 6, 2
    n_o = n_x + n_c
    h = rng.standard_normal((40, n_o))
    w = np.diag(rng.uniform(0.5, 2.0, 40))
    j = h.T @ w @ h
    p_bar_x = np.diag(rng.uniform(1.0, 4.0, n_x))
    p_cc = np.diag([0.3, 0.05]) @ np.array([[1.0, 0.4], [0.4, 1.0]]) @ np.diag([0.3, 0.05])
    # fit world: orbit fitted with a priori P̄_x, c held fixed (E1 = first n_x columns)
    e1 = np.eye(n_o)[:, :n_x]
    s00 = np.zeros((n_o, n_o))
    s00[:n_x, :n_x] = np.linalg.inv(p_bar_x)
    lam_bar = np.zeros((n_o, n_o))
    lam_bar[:n_x, :n_x] = p_bar_x
    lam_bar[n_x:, n_x:] = p_cc
    r = regression(e1, s00, j, lam_bar, j)  # real noise = fit noise: J̃ = J
    hx, hc = h[:, :n_x], h[:, n_x:]
    p_x = np.linalg.inv(np.linalg.inv(p_bar_x) + hx.T @ w @ hx)
    s_xc = -p_x @ hx.T @ w @ hc
    assert _scaled_err(r.Lambda_real[:n_x, :n_x], p_x + s_xc @ p_cc @ s_xc.T) < 1e-10
    assert np.allclose(r.Lambda_real[:n_x, n_x:], s_xc @ p_cc, rtol=0, atol=1e-10)
    assert np.allclose(r.Lambda_real[n_x:, n_x:], p_cc, rtol=0, atol=1e-14)
    assert _scaled_err(r.Lambda1_11, p_x) < 1e-10


def test_fit_world_equal_to_real_world_gives_equal_covariances():
    rng = np.random.default_rng(3)
    n = 7
    s00, j00 = _spd(rng, n), _spd(rng, n)
    r = regression(np.eye(n), s00, j00, np.linalg.inv(s00), j00)
    assert _scaled_err(r.Lambda_real, r.Lambda1_00) < 1e-10


def test_a_singular_fit_normal_matrix_is_refused_with_its_null_direction():
    n = 4
    j = np.zeros((n, n))
    j[:3, :3] = np.eye(3)
    j[1, 2] = j[2, 1] = 1.0  # parameters 2 and 3 seen only as their sum
    j[1, 1] = j[2, 2] = 1.0
    with pytest.raises(SingularFitError) as err:
        regression(np.eye(n)[:, :3], np.zeros((n, n)), j, np.eye(n), j)
    v = err.value.direction
    assert abs(abs(v[1]) - abs(v[2])) < 1e-8 and abs(v[0]) < 1e-8
    assert err.value.rcond < 1e-13
