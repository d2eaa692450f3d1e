"""Bad input to search.solve: one clear SearchInputError (a ValueError) naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

from search import SearchInputError, solve


def _identity(x):
    return np.asarray(x, dtype=float)


GOOD = dict(x0=[1.0, 2.0], targets=[0.0, 0.0], tolerances=[1e-6, 1e-6], increments=[1e-3, 1e-3])


def _solve(f=_identity, **changes):
    kwargs = {**GOOD, **changes}
    return solve(f, kwargs.pop("x0"), kwargs.pop("targets"), **kwargs)


@pytest.mark.parametrize(
    ("changes", "argument", "fragment"),
    [
        ({"targets": [0.0]}, "targets", "length 2"),
        ({"tolerances": [1e-6] * 3}, "tolerances", "length 2"),
        ({"increments": [1e-3]}, "increments", "length 2"),
        ({"target_increments": [0.0, 1.0, 2.0]}, "target_increments", "length 2"),
        ({"x0": []}, "x0", "non-empty"),
        ({"x0": [[1.0, 2.0]]}, "x0", "1-D"),
        ({"x0": [1.0, np.nan]}, "x0", "finite"),
        ({"targets": [0.0, np.inf]}, "targets", "finite"),
        ({"increments": [1e-3, 0.0]}, "increments", "non-zero"),
        ({"tolerances": [1e-6, 0.0]}, "tolerances", "> 0"),
        ({"tolerances": [-1e-6, 1e-6]}, "tolerances", "> 0"),
        ({"iterations_per_partials": 0}, "iterations_per_partials", ">= 1"),
        ({"partial_sets": 2.5}, "partial_sets", "integer"),
        ({"partial_sets": True}, "partial_sets", "integer"),
        ({"partials": np.eye(3)}, "partials", "shape (2, 2)"),
        ({"partials": [[1.0, np.nan], [0.0, 1.0]]}, "partials", "finite"),
        ({"mass": (100.0,)}, "mass", "(m, k)"),
        ({"pivot_rtol": -1.0}, "pivot_rtol", ">= 0"),
    ],
)
def test_bad_arguments_name_the_argument_and_expectation(changes, argument, fragment):
    with pytest.raises(SearchInputError) as info:
        _solve(**changes)
    assert isinstance(info.value, ValueError)
    assert info.value.argument == argument
    assert str(info.value).startswith(f"{argument}: expected")
    assert fragment in str(info.value)


def test_non_finite_output_names_the_case_kind_index_and_x():
    def f(x):
        # finite at the nominal, NaN as soon as the second variable is perturbed
        return np.array([x[0], np.nan if x[1] != 2.0 else x[1]])

    with pytest.raises(SearchInputError) as info:
        _solve(f)
    message = str(info.value)
    assert info.value.argument == "f"
    assert "finite outputs for the perturbed case 2 of partial set 1" in message
    assert "x=[1.0, 2.001]" in message
    assert "nan" in message


def test_non_finite_output_of_an_applied_case_is_named():
    def f(x):
        return np.array([np.inf, 0.0]) if x[0] < 0.5 else np.asarray(x)

    with pytest.raises(SearchInputError, match=r"applied case 1 of partial set 1 at x=\[0\.0, "):
        _solve(f)


def test_output_of_the_wrong_shape_is_named():
    with pytest.raises(SearchInputError, match=r"shape \(2,\) for the nominal case 0"):
        _solve(lambda x: np.zeros(3))


def test_callable_partials_of_the_wrong_shape_are_named():
    with pytest.raises(SearchInputError, match=r"partials: expected shape \(2, 2\) from partials"):
        _solve(partials=lambda x: np.eye(3))


def test_exceptions_of_f_propagate_unchanged():
    class Boom(RuntimeError):
        pass

    def f(x):
        raise Boom("trajectory integrator failed")

    with pytest.raises(Boom, match="integrator"):
        _solve(f)


def test_the_search_package_imports_nothing_from_tapp():
    # The import-linter contract "Generic engines know nothing of tapp", checked here too.
    import subprocess
    import sys

    code = (
        "import sys, search; "
        "bad = sorted(m for m in sys.modules if m == 'tapp' or m.startswith('tapp.')); "
        "print(bad); sys.exit(1 if bad else 0)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
