"""The regression algorithm (seed §2.5) on factors, against the textbook and its identities."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from tapp.estimation import FitSystem, SingularFitError, gram, regression

#: Rounding of products and solves of well-conditioned matrices of order 10.
TIGHT = 1e-12


def _factor(rng: np.random.Generator, n: int, rows: int | None = None) -> np.ndarray:
    return rng.standard_normal((rows or 2 * n, n))


def _scaled_err(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.abs(np.diag(b)))
    return float(np.max(np.abs(a - b) / np.outer(d, d)))


def _constrained(rng: np.random.Generator, n_o: int = 8, n_1: int = 6) -> np.ndarray:
    return np.vstack([np.eye(n_1), rng.standard_normal((n_o - n_1, n_1)) * 0.1])


def test_outputs_follow_the_seed_formulas_and_are_positive_semi_definite():
    """a)–f) against the seed's normal-matrix formulas (well conditioned here)."""
    rng = np.random.default_rng(1)
    n_o = 8
    e1 = _constrained(rng)
    ks, kj, kt, ku = (_factor(rng, n_o) for _ in range(4))
    r = regression(FitSystem.from_columns(e1), ks, kj, ku, kt)
    s00, j00, jt00, lam_bar = gram(ks), gram(kj), gram(kt), gram(ku)
    s1_11 = e1.T @ (s00 + j00) @ e1
    lam11 = np.linalg.inv(s1_11)
    lam00 = e1 @ lam11 @ e1.T
    big_l = np.eye(n_o) - lam00 @ j00
    assert _scaled_err(r.S1_00, s00 + j00) < TIGHT
    assert _scaled_err(r.S1_11, s1_11) < TIGHT
    assert _scaled_err(r.Lambda1_11, lam11) < TIGHT
    assert np.allclose(r.L, big_l, rtol=0, atol=TIGHT)
    assert _scaled_err(r.Sigma, lam00 @ jt00 @ lam00) < TIGHT
    assert _scaled_err(r.Lambda_real, big_l @ lam_bar @ big_l.T + r.Sigma) < TIGHT
    for m in (r.S1_00, r.S1_11, r.Lambda1_11, r.Lambda1_00, r.Lambda_real, r.Sigma):
        assert np.array_equal(m, m.T) and np.all(np.diag(m) >= 0)


def test_the_estimator_map_does_not_depend_on_the_completion_of_the_fit_system():
    rng = np.random.default_rng(4)
    n_o, n_1 = 8, 6
    e1 = _constrained(rng, n_o, n_1)
    ks, kj = _factor(rng, n_o), _factor(rng, n_o)
    e = np.hstack([e1, rng.standard_normal((n_o, n_o - n_1))])
    other = FitSystem(np.linalg.inv(e), e, n_1)
    a = regression(FitSystem.from_columns(e1), ks, kj)
    b = regression(other, ks, kj)
    assert np.allclose(a.L, b.L, rtol=0, atol=TIGHT)
    m = rng.standard_normal((n_o, 3))
    assert np.allclose(a.apply_L(m), a.L @ m, rtol=0, atol=TIGHT)


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
    w = rng.uniform(0.5, 2.0, 40)
    data = np.sqrt(w)[:, None] * h                     # W^½ H: its Gram is HᵀWH
    sigma_x = rng.uniform(1.0, 2.0, n_x)
    p_cc = np.diag([0.3, 0.05]) @ np.array([[1.0, 0.4], [0.4, 1.0]]) @ np.diag([0.3, 0.05])
    # fit world: orbit fitted with a priori σ_x, c held fixed (E1 = first n_x columns)
    r_s = np.zeros((n_x, n_o))
    r_s[:, :n_x] = np.diag(1.0 / sigma_x)
    u = np.zeros((n_o, n_o))
    u[:n_x, :n_x] = np.diag(sigma_x)
    u[n_x:, n_x:] = np.linalg.cholesky(p_cc).T
    r = regression(FitSystem.from_columns(np.eye(n_o)[:, :n_x]), r_s, data, u, data)
    hx, hc = h[:, :n_x], h[:, n_x:]
    p_x = np.linalg.inv(np.diag(sigma_x ** -2) + hx.T @ (w[:, None] * hx))
    s_xc = -p_x @ hx.T @ (w[:, None] * hc)
    real = r.Lambda_real
    assert _scaled_err(real[:n_x, :n_x], p_x + s_xc @ p_cc @ s_xc.T) < 1e-10
    assert np.allclose(real[:n_x, n_x:], s_xc @ p_cc, rtol=0, atol=1e-10)
    assert np.allclose(real[n_x:, n_x:], p_cc, rtol=0, atol=1e-14)
    assert _scaled_err(r.Lambda1_11, p_x) < 1e-10


def test_fit_world_equal_to_real_world_gives_equal_covariances():
    rng = np.random.default_rng(3)
    n = 7
    ks, kj = _factor(rng, n), _factor(rng, n)
    u = np.linalg.inv(np.linalg.qr(ks, mode="r"))   # Λ̄ = S⁻¹: U = R⁻ᵀ as rows
    r = regression(FitSystem.from_columns(np.eye(n)), ks, kj, u.T, kj)
    assert _scaled_err(r.Lambda_real, r.Lambda1_00) < 1e-10


def test_an_ill_conditioned_fit_keeps_the_digits_of_its_factor():
    """Data of condition κ = 1.8e7: normal matrices square it and the real-world covariance
    formed from them in double precision is off by 5e-3 of its scale; from the factors it is
    off by 2.4e-11 (ε κ = 4e-9). Both against 40-digit arithmetic on the same factors."""
    rng = np.random.default_rng(11)
    n = 6
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    data = rng.standard_normal((3 * n, n)) @ (q * np.logspace(0, -7, n)) @ q.T
    ks = 1e-9 * np.eye(n)
    kt = 1.3 * data
    ku = 1e3 * np.eye(n)
    r = regression(FitSystem.from_columns(np.eye(n)), ks, data, ku, kt)
    with mpmath.workdps(40):
        s1 = mpmath.matrix((ks.T @ ks).tolist()) + _mp_gram(data)
        lam = mpmath.inverse(s1)
        big_l = mpmath.eye(n) - lam * _mp_gram(data)
        real = big_l * mpmath.matrix((ku.T @ ku).tolist()) * big_l.T + lam * _mp_gram(kt) * lam
        want = np.array(real.tolist(), dtype=float)
    assert r.kappa > 1e6
    assert _scaled_err(r.Lambda_real, want) < 1e-8
    # the same formula on formed normal matrices in double precision: digits lost
    s1 = ks.T @ ks + data.T @ data
    lam = np.linalg.inv(s1)
    big_l = np.eye(n) - lam @ data.T @ data
    normal = big_l @ ku.T @ ku @ big_l.T + lam @ kt.T @ kt @ lam
    assert _scaled_err(normal, want) > 1e-4


def _mp_gram(k: np.ndarray) -> mpmath.matrix:
    m = mpmath.matrix(k.tolist())
    return m.T * m


def test_a_singular_fit_normal_matrix_is_refused_with_its_null_direction():
    n = 4
    data = np.zeros((3, n))
    data[0, 0] = 1.0
    data[1, 1] = data[1, 2] = 1.0   # parameters 2 and 3 seen only as their sum
    with pytest.raises(SingularFitError) as err:
        regression(FitSystem.from_columns(np.eye(n)[:, :3]), np.zeros((0, n)), data)
    v = err.value.direction
    assert abs(abs(v[1]) - abs(v[2])) < 1e-8 and abs(v[0]) < 1e-8
    assert err.value.rcond < 1e-12
