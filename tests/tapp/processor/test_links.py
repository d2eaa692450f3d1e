"""Permutation and constraint links, the transformation accumulator and (2-15)."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tapp.errors import InputError
from tapp.processor.links import Constraint, Permutation
from tapp.processor.representations import (
    Accumulator,
    Stored,
    Systems,
    orbit_link,
    orbit_link_adjoint,
)

N_P, N_O = 6, 14
#: A double-double from the exact value, rounded twice, and Dot2 for −Qᵀ P*: within a few
#: ε² of each entry (ε² = 4.9e-32).
TWO_ULPS_OF_ULPS = 4.0 * np.finfo(float).eps ** 2


@st.composite
def permutations(draw):
    rows = list(range(N_P, N_O))
    perm = draw(st.permutations(rows))
    return Permutation.from_pairs([(a, b) for a, b in zip(rows, perm, strict=True) if a != b],
                                  N_O, N_P, "test")


@st.composite
def constraints(draw):
    rows = list(range(N_P, N_O))
    a_rows = draw(st.lists(st.sampled_from(rows), min_size=1, max_size=4, unique=True))
    b_pool = [r for r in rows if r not in a_rows]
    triples = []
    for a in a_rows:
        for b in draw(st.lists(st.sampled_from(b_pool), min_size=1, max_size=3, unique=True)):
            triples.append((a, b, draw(st.floats(-3, 3, allow_nan=False))))
    return Constraint.from_triples(triples, N_O, N_P, "test")


@settings(max_examples=40, deadline=None)
@given(link=st.one_of(permutations(), constraints()))
def test_adjoint_of_every_link_is_its_inverse_transposed(link):
    """(L*)ᵀ L = I: P*ᵀP = PᵀP = I (3-21), (I + Eᵀ)ᵀ(I − E) = I − E² = I (3-22, 3-23)."""
    m = link.matrix(N_O)
    m_star = link.apply(np.eye(N_O), adjoint=True)
    assert np.allclose(m_star.T @ m, np.eye(N_O), rtol=0, atol=1e-12)


def test_constraint_link_subtracts_e_times_b_from_a():
    k = Constraint.from_triples([(7, 9, 0.5)], N_O, N_P, "test")
    v = np.arange(N_O, dtype=float)[:, None]
    assert k.apply(v)[7, 0] == 7.0 - 0.5 * 9.0
    assert np.array_equal(np.delete(k.apply(v), 7), np.delete(v, 7))


@pytest.mark.parametrize(("pairs", "fragment"), [
    ([(7, 8), (8, 8)], "at most once"),
    ([(7, 8)], "a permutation"),
    ([(2, 8), (8, 2)], "never permuted"),
])
def test_bad_permutations_are_refused(pairs, fragment):
    with pytest.raises(InputError, match=fragment):
        Permutation.from_pairs(pairs, N_O, N_P, "deck.toml: common.permutation")


def test_a_row_that_is_both_a_and_b_is_refused():
    with pytest.raises(InputError, match="no position in common"):
        Constraint.from_triples([(7, 8, 1.0), (8, 9, 1.0)], N_O, N_P, "deck")


def _kepler_stm(dt: float) -> np.ndarray:
    """A symplectic 6 x 6 matrix: Φ = exp(t Γ H) with H symmetric, the transition of a linear
    Hamiltonian flow (what (3-13) needs; the two-body STM is one such)."""
    from scipy.linalg import expm
    gamma = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    rng = np.random.default_rng(5)
    h = rng.standard_normal((6, 6))
    h = h + h.T
    return expm(dt * gamma @ h)  # Φ = exp(t Γ H), symplectic for symmetric H


def test_orbit_link_adjoint_of_a_symplectic_transition_is_the_inverse_transpose():
    phi = _kepler_stm(0.7)
    partials = np.hstack([phi, np.random.default_rng(2).standard_normal((6, 4))])
    link, adj = orbit_link(partials, 10, False), orbit_link(partials, 10, True)
    assert np.allclose(adj, np.linalg.inv(link).T, rtol=0, atol=1e-10)
    gamma = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    assert np.allclose(adj[:6, :6], gamma @ phi @ gamma.T, rtol=0, atol=1e-10)  # (3-13)


def _systems() -> Systems:
    names = tuple(f"x{i}" for i in range(N_O))
    p_c = Permutation.from_pairs([(6, 9), (9, 12), (12, 6)], N_O, N_P, "t")
    k_c = Constraint.from_triples([(13, 6, 0.4), (12, 7, -1.5)], N_O, N_P, "t")
    k_f = Constraint.from_triples([(10, 6, 2.0), (11, 8, 0.3)], N_O, N_P, "t")
    p_r = Permutation.from_pairs([(7, 10), (10, 7)], N_O, N_P, "t")
    k_r = Constraint.from_triples([(11, 9, 0.25)], N_O, N_P, "t")
    return Systems(N_O, N_P, 12, 10, 11, names, 3, p_c, k_c, None, k_f, p_r, k_r)


def _accumulator(systems: Systems) -> Accumulator:
    eye = np.eye(N_P, N_O)
    u = np.hstack([_kepler_stm(0.3), np.random.default_rng(4).standard_normal((6, N_O - 6))])
    return Accumulator(systems, Stored(eye, u, eye.copy(), eye.copy(), np.ones((3, N_O))))


@pytest.mark.parametrize("chi", [2, 3, 4, 5, 6])
@pytest.mark.parametrize("tau", [0, 1])
def test_transformation_pairs_are_adjoint(chi, tau):
    """⟨1, τ, χ⟩ = ⟨0, τ, χ⟩⁻ᵀ for every system and orbit set (3-9)."""
    acc = _accumulator(_systems())
    t0, t1 = acc.transformation(0, tau, chi), acc.transformation(1, tau, chi)
    assert np.allclose(t1.T @ t0, np.eye(N_O), rtol=0, atol=1e-10)


def test_fit_world_transformation_matrices_satisfy_the_identities_2_15():
    sy = _systems()
    acc = _accumulator(sy)
    d = acc.transformation(0, 0, 4)
    e = np.linalg.inv(d)
    n1 = sy.n_f1
    d1, d2, e1, e2 = d[:n1], d[n1:], e[:, :n1], e[:, n1:]
    assert np.allclose(e1, acc.partials(1, 0, "f1").T, rtol=0, atol=1e-12)
    eye = np.eye(N_O)
    assert np.allclose(d1 @ e1, eye[:n1, :n1], atol=1e-12)             # (2-15a)
    assert np.allclose(d1 @ e2, 0.0, atol=1e-12)                        # (2-15b)
    assert np.allclose(d2 @ e1, 0.0, atol=1e-12)                        # (2-15c)
    assert np.allclose(d2 @ e2, eye[n1:, n1:], atol=1e-12)             # (2-15d)
    assert np.allclose(e1 @ d1 + e2 @ d2, eye, atol=1e-12)             # (2-15e)


def test_system_names_follow_the_permutations_and_mark_constrained_rows():
    sy = _systems()
    common = sy.system_names(3)
    assert common[6] == "x9" and common[9] == "x12" and common[12] == "x6'"
    assert common[13] == "x13'"
    real = sy.system_names(6)
    assert real[7] == "x10" and real[10] == "x7"


def test_miss_sets_as_orbit_sets_need_the_rows_and_transform_like_orbits():
    """τ = 4, 5: rows n_p..2n_p and 2n_p..3n_p of B (the seed's UDC and DCA sets)."""
    sy = _systems()
    eye = np.eye(N_P, N_O)
    rng = np.random.default_rng(8)
    b = np.vstack([rng.standard_normal((N_P, N_O)),
                   np.hstack([_kepler_stm(0.2), rng.standard_normal((N_P, N_O - N_P))]),
                   np.hstack([_kepler_stm(0.9), rng.standard_normal((N_P, N_O - N_P))])])
    acc = Accumulator(sy, Stored(eye, eye.copy(), eye.copy(), eye.copy(), b))
    for tau in (4, 5):
        t0, t1 = acc.transformation(0, tau, 4), acc.transformation(1, tau, 4)
        assert np.allclose(t1.T @ t0, np.eye(N_O), rtol=0, atol=1e-10)
        assert np.allclose(acc.partials(0, tau, "p"), b[(tau - 3) * N_P:(tau - 2) * N_P])
    short = Accumulator(sy, Stored(eye, eye.copy(), eye.copy(), eye.copy(), b[:N_P]))
    with pytest.raises(InputError, match="miss set has"):
        short.transformation(0, 4, 1)


def test_the_adjoint_of_a_rounded_ill_conditioned_transition_is_its_exact_inverse():
    """A symplectic transition of condition ~1e13 rounded to float64 (as the tape's U is) is
    symplectic only to its rounding, so Γ P Γᵀ (3-13) is not its inverse: the adjoint is the
    exact inverse of the rounded [[P, Q], [0, I]], transposed, as a double-double (against
    mpmath at 80 digits: P* within a few ε² of each entry, −Qᵀ P* of its terms |Q|ᵀ|P*|),
    which Γ P Γᵀ misses by far more.
    Also a block that is not symplectic at all (2 S)."""
    phi = _kepler_stm(9.0)
    assert np.linalg.cond(phi) > 1e10
    partials = np.hstack([phi, 1e3 * np.random.default_rng(4).standard_normal((6, 4))])
    hi, lo = orbit_link_adjoint(partials, 10)
    q = partials[:, 6:]
    gamma = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    poisson = gamma @ phi @ gamma.T
    with mpmath.workdps(80):
        exact = mpmath.inverse(mpmath.matrix(orbit_link(partials, 10, False).tolist())).T
        err = np.array([[float(abs(exact[i, j] - mpmath.mpf(hi[i, j]) - mpmath.mpf(lo[i, j])))
                         for j in range(10)] for i in range(10)])
        p_star = np.array([[float(abs(exact[i, j])) for j in range(6)] for i in range(6)])
        err_poisson = max(float(abs(exact[i, j] - mpmath.mpf(poisson[i, j])) / abs(exact[i, j]))
                          for i in range(6) for j in range(6))
    assert np.all(err[:6, :6] <= TWO_ULPS_OF_ULPS * p_star)
    assert np.all(err[6:, :6] <= TWO_ULPS_OF_ULPS * (np.abs(q.T) @ p_star))  # Dot2 of −Qᵀ P*
    assert not np.any(err[:, 6:])
    assert err_poisson > 1e6 * TWO_ULPS_OF_ULPS
    s = np.eye(6)
    s[:3, 3:] = 1e4 * np.eye(3)
    for p in (2.0 * s, s):
        assert np.allclose(orbit_link(p, 6, True), np.linalg.inv(p).T, rtol=1e-12, atol=0)
