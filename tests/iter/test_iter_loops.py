"""ITER loops: type 1 and type 2 tables, nesting order (seed section VI), validation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from iter import Case, Loop, SweepInputError, case_count, generate_cases

# Seed VI, CASE 1: "The azimuths to be used are 96, 99, 102, 105, and 108."
SEED_AZIMUTHS_deg = (96.0, 99.0, 102.0, 105.0, 108.0)


def test_type_1_and_type_2_give_the_seed_azimuths_in_order():
    type_1 = Loop(type=1, names=("azimuth_deg",), sets=5, vary=SEED_AZIMUTHS_deg)
    # Seed: "VARY = 96. DELTA = 3. TYPE = 2 ... the increment DELTA added four successive times".
    type_2 = Loop(type=2, names=("azimuth_deg",), sets=5, vary=(96.0,), delta=(3.0,))
    expected = tuple(Case(index=k, names=("azimuth_deg",), values=(a,))
                     for k, a in enumerate(SEED_AZIMUTHS_deg))
    assert generate_cases([type_1]) == expected
    assert generate_cases([type_2]) == expected


def test_type_1_table_is_read_row_wise():
    loop = Loop(type=1, names=("x_km", "y_km"), sets=3, vary=(1, 2, 3, 4, 5, 6))
    np.testing.assert_array_equal(loop.table(), [[1, 2], [3, 4], [5, 6]])
    assert [c.kwargs() for c in generate_cases([loop])] == [
        {"x_km": 1.0, "y_km": 2.0}, {"x_km": 3.0, "y_km": 4.0}, {"x_km": 5.0, "y_km": 6.0}]


def test_nested_30_days_by_5_azimuths_is_outer_major():
    # Seed VI, CASE 2: outer TYPE = 2 SETS = 30 VARY = 5730. DELTA = 1.;
    # nested TYPE = 2 SETS = 5 VARY = 96 DELTA = 3.; "a total of 150 runs".
    days = Loop(type=2, names=("launch_day",), sets=30, vary=(5730.0,), delta=(1.0,))
    azimuths = Loop(type=2, names=("azimuth_deg",), sets=5, vary=(96.0,), delta=(3.0,))
    cases = generate_cases([days, azimuths])
    assert len(cases) == case_count([days, azimuths]) == 150
    assert [c.index for c in cases] == list(range(150))
    # Hand-computed: case k is day 5730 + k // 5 at azimuth 96 + 3 (k % 5).
    assert cases[0].values == (5730.0, 96.0)
    assert cases[4].values == (5730.0, 108.0)
    assert cases[5].values == (5731.0, 96.0)
    assert cases[77].values == (5745.0, 102.0)
    assert cases[149].values == (5759.0, 108.0)
    assert cases[77].names == ("launch_day", "azimuth_deg")


@st.composite
def loop_nests(draw):
    loops = []
    for level in range(draw(st.integers(1, 3))):
        n = draw(st.integers(1, 2))
        sets = draw(st.integers(1, 4))
        names = tuple(f"p{level}_{j}_km" for j in range(n))
        numbers = st.integers(-1000, 1000).map(float)
        if draw(st.booleans()):
            vary = tuple(draw(st.lists(numbers, min_size=sets * n, max_size=sets * n)))
            loops.append(Loop(type=1, names=names, sets=sets, vary=vary))
        else:
            vary = tuple(draw(st.lists(numbers, min_size=n, max_size=n)))
            delta = tuple(draw(st.lists(numbers, min_size=n, max_size=n)))
            loops.append(Loop(type=2, names=names, sets=sets, vary=vary, delta=delta))
    return loops


@given(loop_nests())
def test_nesting_is_like_nested_do_loops(loops):
    cases = generate_cases(loops)
    expected = []
    # Nested DO loops, written out: the innermost row index varies fastest.
    for rows in itertools.product(*(range(loop.sets) for loop in loops)):
        values = []
        for loop, k in zip(loops, rows, strict=True):
            if loop.type == 1:
                values += loop.vary[k * loop.n:(k + 1) * loop.n]
            else:
                values += [a + k * d for a, d in zip(loop.vary, loop.delta, strict=True)]
        expected.append(tuple(values))
    assert [c.values for c in cases] == expected


@given(st.integers(1, 50), st.floats(-1e3, 1e3), st.floats(-10, 10))
def test_type_2_matches_the_seed_recursion(sets, start, delta):
    # Seed: a_kj = a_(k-1)j + delta_j. Closed form agrees to rounding (a few ulp of the sum).
    table = Loop(type=2, names=("x_km",), sets=sets, vary=(start,), delta=(delta,)).table()
    recursive = [start]
    for _ in range(sets - 1):
        recursive.append(recursive[-1] + delta)
    one_nm_km = 1e-12
    np.testing.assert_allclose(table[:, 0], recursive, rtol=0, atol=one_nm_km * sets)


@pytest.mark.parametrize(("kwargs", "field", "fragment"), [
    ({"type": 1, "sets": 3, "vary": (1.0, 2.0)}, "vary", "3 x 1 = 3 values"),
    ({"type": 3, "sets": 1, "vary": (1.0,)}, "type", "1 (table) or 2"),
    ({"type": 2, "sets": 4, "vary": (1.0,)}, "delta", "increments for type 2"),
    ({"type": 2, "sets": 4, "vary": (1.0, 2.0), "delta": (1.0,)}, "vary", "first row"),
    ({"type": 1, "sets": 1, "vary": (1.0,), "delta": (1.0,)}, "delta", "no delta for type 1"),
    ({"type": 1, "sets": 0, "vary": ()}, "sets", ">= 1"),
    ({"type": 1, "sets": 1, "vary": ("96",)}, "vary[0]", "a number"),
    ({"type": 1, "sets": 1, "vary": (float("nan"),)}, "vary[0]", "finite"),
])
def test_bad_loops_name_the_field(kwargs, field, fragment):
    with pytest.raises(SweepInputError) as info:
        Loop(names=("azimuth_deg",), **kwargs)
    assert info.value.field == field
    assert fragment in info.value.expected


def test_bad_names_are_rejected():
    with pytest.raises(SweepInputError, match="names\\[0\\]"):
        Loop(type=1, names=("azimuth deg",), sets=1, vary=(1.0,))
    with pytest.raises(SweepInputError, match="distinct"):
        Loop(type=1, names=("a_km", "a_km"), sets=1, vary=(1.0, 2.0))
    outer = Loop(type=1, names=("a_km",), sets=1, vary=(1.0,))
    with pytest.raises(SweepInputError, match=r"loop\[1\]\.names"):
        generate_cases([outer, outer])
    with pytest.raises(SweepInputError, match="at least one loop"):
        generate_cases([])
