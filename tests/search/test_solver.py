"""SEARCH (seed TM 33-203 sections II-III): exits, options and the history, on models whose
answers are known in closed form."""

from __future__ import annotations

import numpy as np
import pytest

from search import EXIT_FLAG, SearchResult, solve

EPS = np.finfo(np.float64).eps


# --------------------------------------------------------------------------- linear model
def _linear_model(n: int = 3, seed: int = 3):
    """y = y0 + A (x - x0) with a fixed random, well-conditioned A."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) + 3.0 * np.eye(n)
    x0 = rng.normal(size=n)
    y0 = rng.normal(size=n) * 10.0
    return (lambda x: y0 + A @ (x - x0)), A, x0, y0


def test_linear_model_converges_after_one_applied_case_with_the_exact_step():
    f, A, x0, y0 = _linear_model()
    y_T = np.array([1.0, -2.0, 3.0])
    # Forward differences of a linear model are exact up to rounding of y (|y| ~ 30) divided
    # by the increment (1e-3): about 1e-11 relative in A; with cond(A) ~ 10 the step is good
    # to ~1e-10 relative. 1e-8 on y is therefore met by the first applied case.
    tol_y = 1e-8
    step_rtol = 1e-9  # relative accuracy asked of the first step (see above)
    r = solve(f, x0, y_T, tolerances=[tol_y] * 3, increments=[1e-3] * 3)
    assert r.status == "converged" and r.flag == EXIT_FLAG["converged"] == 1
    assert (r.n_nominal, r.n_perturbed, r.n_applied) == (1, 3, 1)
    expected_step = np.linalg.solve(A, y_T - y0)  # independent of DINV
    first = r.history.partial_sets[0]
    np.testing.assert_allclose(first.steps[0].step, expected_step, rtol=step_rtol)
    np.testing.assert_allclose(first.steps[0].total_step, expected_step, rtol=step_rtol)
    np.testing.assert_allclose(first.partials, A, rtol=1e-9)  # ~1e-11 expected, see above
    np.testing.assert_allclose(first.inverse @ A, np.eye(3), atol=1e-9)
    assert first.determinant == pytest.approx(np.linalg.det(A), rel=1e-9)
    assert np.all(np.abs(r.y - y_T) <= tol_y)
    np.testing.assert_array_equal(r.miss, r.y - r.targets)


def test_already_converged_nominal_takes_the_converged_exit_without_partials():
    f, _, x0, y0 = _linear_model()
    r = solve(f, x0, y0 + 0.5, tolerances=[1.0] * 3, increments=[1e-3] * 3)
    assert r.status == "converged"
    assert (r.n_nominal, r.n_perturbed, r.n_applied) == (1, 0, 0)
    assert r.history.partial_sets == ()


# ----------------------------------------------------------------- Newton convergence rate
def _f2(x):
    return np.array([np.exp(x[0]) - 1.0 + x[1] ** 2, x[0] + np.sin(x[1]) + 0.5 * x[0] * x[1]])


def _jac2(x):
    return np.array([[np.exp(x[0]), 2.0 * x[1]], [1.0 + 0.5 * x[1], np.cos(x[1]) + 0.5 * x[0]]])


X_STAR = np.array([0.7, -0.4])
# The Newton constant |J^-1 f''| / 2 of _f2 near X_STAR is about 0.7 (measured ratios 0.53 to
# 1.52 from x0 = (0.3, 0)); 2.0 bounds it. Stale partials give ratios of 1e3 and more.
QUADRATIC_BOUND = 2.0
# Below this error the next error approaches the rounding floor (~1e-16), so e_{k+1}/e_k^2 says
# nothing about the method; with e_k >= 1e-7, e_{k+1} ~ 1e-14 is still 100 eps above it.
RATE_FLOOR = 1e-7


def _error_ratios(r: SearchResult) -> list[float]:
    points = [c.x for c in r.history.cases if c.kind != "perturbed"]
    e = [float(np.max(np.abs(x - X_STAR))) for x in points]
    return [e[k + 1] / e[k] ** 2 for k in range(len(e) - 1) if e[k] >= RATE_FLOOR]


@pytest.mark.parametrize("partials", [_jac2, None], ids=["analytic", "differenced"])
def test_fresh_partials_every_iteration_converge_quadratically(partials):
    r = solve(
        _f2,
        [0.3, 0.0],
        _f2(X_STAR),
        tolerances=[1e-14, 1e-14],
        increments=[1e-8, 1e-8],
        iterations_per_partials=1,
        partial_sets=10,
        partials=partials,
    )
    assert r.status == "converged"
    ratios = _error_ratios(r)
    assert len(ratios) >= 4  # enough iterations to see the rate
    assert max(ratios) <= QUADRATIC_BOUND
    np.testing.assert_allclose(r.x, X_STAR, atol=1e-13)


def test_stale_partials_are_not_quadratic():
    # The contrast that shows the rate test can fail: with partials reused 3 times the error
    # ratio e_{k+1}/e_k^2 grows without bound (linear convergence).
    r = solve(
        _f2,
        [0.3, 0.0],
        _f2(X_STAR),
        tolerances=[1e-14, 1e-14],
        increments=[1e-8, 1e-8],
        iterations_per_partials=3,
        partial_sets=10,
    )
    assert r.status == "converged"
    assert max(_error_ratios(r)) > 100.0 * QUADRATIC_BOUND


# ----------------------------------------------------------------------------- the exits
def test_cube_root_reaches_the_diverged_exit():
    # Newton on y = x^(1/3), y_T = 0 gives x_{k+1} = -2 x_k: it diverges from any x0 != 0.
    r = solve(
        np.cbrt,
        [1.0],
        [0.0],
        tolerances=[1e-6],
        increments=[1e-6],
        iterations_per_partials=1,
        partial_sets=4,
    )
    assert r.status == "diverged" and r.flag == 2
    assert (r.n_nominal, r.n_perturbed, r.n_applied) == (1, 4, 4)
    applied = [float(c.x[0]) for c in r.history.cases if c.kind == "applied"]
    ratios = np.array(applied[1:]) / np.array(applied[:-1])
    # forward differences with increment 1e-6 shift each ratio from -2 by < 1e-5
    np.testing.assert_allclose(ratios, -2.0, rtol=1e-5)
    assert r.x[0] == applied[-1]


def test_rank_deficient_model_reaches_the_singular_exit():
    # y depends on x1 + x2 only: the two columns of A are equal.
    def f(x):
        s = x[0] + x[1]
        return np.array([np.sin(s), s**2])

    r = solve(f, [0.3, 0.2], [0.1, 0.2], tolerances=[1e-9] * 2, increments=[1e-4] * 2)
    assert r.status == "singular" and r.flag == 3
    assert (r.n_nominal, r.n_perturbed, r.n_applied) == (1, 2, 0)
    (ps,) = r.history.partial_sets
    assert ps.inverse is None and ps.steps == ()
    np.testing.assert_array_equal(r.x, [0.3, 0.2])


def test_singular_analytic_partials_take_the_singular_exit():
    f, _, x0, y0 = _linear_model(n=2)
    r = solve(
        f,
        x0,
        y0 + 1.0,
        tolerances=[1e-9] * 2,
        increments=[1e-3] * 2,
        partials=[[1.0, 2.0], [2.0, 4.0]],
    )
    assert r.status == "singular" and r.n_perturbed == 0


# --------------------------------------------------------------------------- the options
def test_target_increments_theta_shift_targets_from_the_first_nominal():
    f, _, x0, y0 = _linear_model()
    theta = np.array([0.0, 5.0, -2.5])
    targets = np.array([1.0, 99.0, 99.0])  # ignored where theta != 0
    r = solve(f, x0, targets, tolerances=[1e-8] * 3, increments=[1e-3] * 3, target_increments=theta)
    np.testing.assert_array_equal(r.targets, [1.0, y0[1] + 5.0, y0[2] - 2.5])
    assert r.status == "converged"
    assert np.all(np.abs(r.y - r.targets) <= 1e-8)


def test_partials_only_computes_the_first_matrix_and_takes_the_converged_exit():
    f, A, x0, y0 = _linear_model()
    r = solve(f, x0, y0 + 10.0, tolerances=[1e-8] * 3, increments=[1e-3] * 3, partials_only=True)
    assert r.status == "converged"
    assert (r.n_nominal, r.n_perturbed, r.n_applied) == (1, 3, 0)
    np.testing.assert_array_equal(r.x, x0)
    (ps,) = r.history.partial_sets
    np.testing.assert_allclose(ps.partials, A, rtol=1e-9)  # as in the linear-model test
    assert ps.inverse is not None and ps.steps == ()


def test_mass_auxiliary_calculation_is_passed_to_f_and_recorded():
    f_lin, _, x0, y0 = _linear_model()
    m, k = 1000.0, 12.5
    received = []

    def f(x, mass):
        received.append(mass)
        return f_lin(x)

    r = solve(f, x0, y0 + 1.0, tolerances=[1e-8] * 3, increments=[1e-3] * 3, mass=(m, k))
    assert r.status == "converged"
    masses = [c.mass for c in r.history.cases]
    assert masses == received
    assert masses[0] == m  # Delta = 0 for the first nominal case
    for case in r.history.cases:
        # m' = m - k |x_j - x0| (seed section II); one rounding of k * Delta
        expected = m - k * np.linalg.norm(case.x - x0)
        assert case.mass == pytest.approx(expected, rel=0.0, abs=4 * EPS * m)
    assert r.mass == masses[-1] < m


def test_analytic_partials_matrix_replaces_the_first_perturbations():
    f, A, x0, y0 = _linear_model()
    r = solve(f, x0, y0 + 1.0, tolerances=[1e-8] * 3, increments=[1e-3] * 3, partials=A)
    assert r.status == "converged"
    assert (r.n_perturbed, r.n_applied) == (0, 1)
    assert r.history.partial_sets[0].source == "analytic"


def test_analytic_partials_matrix_is_used_for_the_first_set_only():
    # A constant (wrong at x*) matrix for set 1; set 2 must then be differenced.
    r = solve(
        _f2,
        [0.3, 0.0],
        _f2(X_STAR),
        tolerances=[1e-12] * 2,
        increments=[1e-7] * 2,
        iterations_per_partials=1,
        partial_sets=10,
        partials=_jac2([0.3, 0.0]),
    )
    assert r.status == "converged"
    sources = [ps.source for ps in r.history.partial_sets]
    assert sources[0] == "analytic" and set(sources[1:]) == {"differenced"}
    assert all(c.partial_set >= 2 for c in r.history.cases if c.kind == "perturbed")
    assert r.n_perturbed == 2 * (len(sources) - 1)


def test_analytic_partials_callable_is_used_for_every_set():
    r = solve(
        _f2,
        [0.3, 0.0],
        _f2(X_STAR),
        tolerances=[1e-12] * 2,
        increments=[1e-7] * 2,
        iterations_per_partials=1,
        partial_sets=10,
        partials=_jac2,
    )
    assert r.status == "converged" and r.n_perturbed == 0
    for ps in r.history.partial_sets:
        assert ps.source == "analytic"
        np.testing.assert_array_equal(ps.partials, _jac2(ps.x_nominal))


# A mildly nonlinear model on which partials held for 10 applied cases converge only linearly.
def _f_broyden(x):
    return np.array([x[0] + 0.5 * np.sin(x[1]) + 0.2 * x[0] ** 2, x[1] + 0.5 * x[0] ** 2])


def test_broyden_updates_converge_where_stale_partials_do_not():
    x_star = np.array([1.0, 1.0])
    kwargs = dict(
        tolerances=[1e-10, 1e-10],
        increments=[1e-7, 1e-7],
        iterations_per_partials=10,
        partial_sets=1,
    )
    plain = solve(_f_broyden, [0.0, 0.0], _f_broyden(x_star), **kwargs)
    updated = solve(_f_broyden, [0.0, 0.0], _f_broyden(x_star), broyden=True, **kwargs)
    assert plain.status == "diverged"
    assert updated.status == "converged"
    np.testing.assert_allclose(updated.x, x_star, atol=1e-9)
    # Each applied case but the last is followed by a rank-one update and its own record.
    sources = [ps.source for ps in updated.history.partial_sets]
    assert sources[0] == "differenced" and set(sources[1:]) == {"broyden"}
    assert len(sources) == updated.n_applied
    # the secant condition A_new dx = dy holds for every update
    sets = updated.history.partial_sets
    for before, after in zip(sets[:-1], sets[1:], strict=True):
        dx = after.x_nominal - before.x_nominal
        dy = after.y_nominal - before.y_nominal
        np.testing.assert_allclose(after.partials @ dx, dy, rtol=1e-9, atol=1e-12)


def test_step_halving_converges_where_newton_overshoots():
    # Newton on atan(x) = 0 from |x0| > 1.39 overshoots further each time.
    kwargs = dict(tolerances=[1e-12], increments=[1e-7])
    plain = solve(np.arctan, [2.0], [0.0], **kwargs)
    halved = solve(np.arctan, [2.0], [0.0], step_halving=True, **kwargs)
    assert plain.status != "converged"
    assert halved.status == "converged"
    assert abs(halved.x[0]) <= 1e-12  # |atan x| <= 1e-12 implies |x| <= 1e-12 near 0
    first_halvings = [c.halving for c in halved.history.cases if c.kind == "applied"][:2]
    assert first_halvings == [0, 1]  # the full step from 2 overshoots to -3.54; half is kept
    steps = [s for ps in halved.history.partial_sets for s in ps.steps]
    np.testing.assert_allclose(steps[1].step, steps[0].step / 2.0, rtol=4 * EPS)


def test_step_halving_that_finds_no_descent_moves_to_fresh_partials():
    # A constant wrong-signed analytic A: every step goes uphill, halving cannot help, and the
    # set is abandoned after MAX_STEP_HALVINGS + 1 trials; set 2 is differenced at x0.
    from search import MAX_STEP_HALVINGS

    r = solve(
        lambda x: x**3 + x,
        [1.0],
        [0.0],
        tolerances=[1e-10],
        increments=[1e-7],
        partials=[[-4.0]],
        step_halving=True,
        partial_sets=6,
    )
    first, second = r.history.partial_sets[:2]
    assert len(first.steps) == MAX_STEP_HALVINGS + 1
    assert [s.halving for s in first.steps] == list(range(MAX_STEP_HALVINGS + 1))
    np.testing.assert_array_equal(second.x_nominal, [1.0])
    assert second.source == "differenced"
    assert r.status == "converged"


# --------------------------------------------------------------------------- the history
def test_history_records_every_case_and_step_in_order():
    r = solve(
        _f2,
        [0.3, 0.0],
        _f2(X_STAR),
        tolerances=[1e-12] * 2,
        increments=[1e-7] * 2,
        iterations_per_partials=2,
        partial_sets=10,
    )
    cases = r.history.cases
    assert [c.number for c in cases] == list(range(1, len(cases) + 1))
    assert r.n_cases == len(cases)
    assert cases[0].kind == "nominal" and cases[0].index == 0
    # Each set: 2 perturbed cases (j = 1, 2), then up to 2 applied cases (1, 2).
    pattern = [(c.kind, c.index) for c in cases[1:7]]
    assert pattern == [
        ("perturbed", 1),
        ("perturbed", 2),
        ("applied", 1),
        ("applied", 2),
        ("perturbed", 1),
        ("perturbed", 2),
    ]
    assert [c.partial_set for c in cases[1:7]] == [1, 1, 1, 1, 2, 2]
    by_number = {c.number: c for c in cases}
    x_prev = np.asarray(cases[0].x)
    for ps in r.history.partial_sets:
        # a set's nominal is x0 or the last applied case of the previous set
        np.testing.assert_array_equal(ps.x_nominal, x_prev)
        for step in ps.steps:
            case = by_number[step.case]
            assert case.kind == "applied" and case.index == step.index
            np.testing.assert_allclose(case.x, x_prev + step.step, rtol=0, atol=4 * EPS)
            np.testing.assert_allclose(step.total_step, case.x - cases[0].x, rtol=0, atol=4 * EPS)
            x_prev = case.x
    # perturbed cases move one variable by its increment from the set's nominal
    for c in cases:
        if c.kind == "perturbed":
            nominal = r.history.partial_sets[c.partial_set - 1].x_nominal
            delta = np.asarray(c.x) - nominal
            np.testing.assert_allclose(delta, 1e-7 * np.eye(2)[c.index - 1], atol=1e-16)


def test_result_arrays_are_read_only():
    f, _, x0, y0 = _linear_model()
    r = solve(f, x0, y0 + 1.0, tolerances=[1e-8] * 3, increments=[1e-3] * 3)
    with pytest.raises(ValueError):
        r.x[0] = 0.0
    with pytest.raises(ValueError):
        r.history.cases[0].y[0] = 0.0
