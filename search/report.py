"""Plain-text report of a SEARCH result, in the spirit of the seed's Figs. 4 and 5.

Fig. 4 ("output from the initial entry to SEARCH") restates the inputs: variable names,
target values, target-value modifications theta, permissible errors, generative increments and
"THE ORDER IS n, WITH s SETS OF PARTIALS OF i ITERATIONS EACH". Fig. 5 ("output from subsequent
entries") shows, case by case, the dependent variables just computed and, once a set of
partials is complete, "THE MATRIX OF PARTIALS IS", "THE INVERSE PARTIAL MATRIX IS", the
"I.V. INCREMENTS (DELTAS)" and the "TOTAL INCREMENTS". This module prints the same items, in
the order they happened, plus the exit taken.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from search.errors import SearchInputError
from search.solver import Case, PartialSet, SearchResult, Step

_LABEL = 30  # width of the label column
_FIELD = 17  # width of one number, e.g. "+1.55900000E+04"


def _row(label: str, values: Sequence[float] | np.ndarray) -> str:
    return f"{label:<{_LABEL}}" + "".join(f"{v:>+{_FIELD}.8E}" for v in values)


def _names_row(label: str, names: Sequence[str]) -> str:
    return f"{label:<{_LABEL}}" + "".join(f"{name:>{_FIELD}}" for name in names)


def _names(argument: str, names: Sequence[str] | None, default: str, n: int) -> list[str]:
    if names is None:
        return [f"{default}{i}" for i in range(1, n + 1)]
    names = list(names)
    if len(names) != n:
        raise SearchInputError(argument, f"{n} names, one per variable", f"{len(names)} names")
    return [str(name) for name in names]


def _case_lines(case: Case) -> list[str]:
    if case.kind == "nominal":
        what = "NOMINAL"
    elif case.kind == "perturbed":
        what = f"PERTURBED {case.index}"
    else:
        halved = f", STEP HALVED {case.halving}x" if case.halving else ""
        what = f"APPLIED {case.index}{halved}"
    lines = [
        f"CASE {case.number}: {what}, SET OF PARTIALS {case.partial_set}",
        _row("  INDEPENDENT VARIABLES", case.x),
        _row("  DEPENDENT VARIABLES", case.y),
    ]
    if case.mass is not None:
        lines.append(_row("  MASS M'", [case.mass]))
    return lines


def _partials_lines(ps: PartialSet) -> list[str]:
    how = {"differenced": "DIFFERENCED", "analytic": "ANALYTIC", "broyden": "BROYDEN UPDATE"}
    tag = f"SET {ps.number}" + (f", UPDATE {ps.update}" if ps.update else "")
    lines = [f"THE MATRIX OF PARTIALS IS ({tag}, {how[ps.source]})"]
    lines += [_row("", row) for row in ps.partials]
    if ps.inverse is None:
        lines.append("THE MATRIX OF PARTIALS IS SINGULAR")
    else:
        lines.append("THE INVERSE PARTIAL MATRIX IS")
        lines += [_row("", row) for row in ps.inverse]
        lines.append(_row("DETERMINANT", [ps.determinant]))
    return lines


def _step_lines(step: Step) -> list[str]:
    return [
        _row("I.V. INCREMENTS (DELTAS) ARE", step.step),
        _row("TOTAL INCREMENTS ARE", step.total_step),
    ]


def format_report(
    result: SearchResult,
    x_names: Sequence[str] | None = None,
    y_names: Sequence[str] | None = None,
) -> str:
    """Return a plain-text report of a search: inputs, every case, partials, steps, exit.

    Parameters
    ----------
    result : SearchResult
        What :func:`search.solve` returned.
    x_names, y_names : sequence of str, optional
        Names of the independent and dependent variables (the seed's IV1N.., DV1N..); default
        ``IV1..IVn`` and ``DV1..DVn``.

    Returns
    -------
    str
        The report, lines separated by newlines; numbers in ``+d.dddddddddE+xx`` form.

    Raises
    ------
    SearchInputError
        If ``x_names`` or ``y_names`` does not have n entries.
    """
    inputs = result.inputs
    n = inputs.x0.size
    xn = _names("x_names", x_names, "IV", n)
    yn = _names("y_names", y_names, "DV", n)
    lines = [
        "SEARCH PROGRAM PARAMETERS",
        _names_row("INDEPENDENT VARIABLE NAMES", xn),
        _names_row("DEPENDENT VARIABLE NAMES", yn),
        _row("TARGET VALUES", inputs.targets),
    ]
    if np.any(inputs.target_increments != 0.0):
        lines.append(_row("T. V. MODIFICATIONS", inputs.target_increments))
        lines.append(_row("COMPUTED TARGET VALUES", result.targets))
    lines += [
        _row("PERMISSIBLE ERROR VECTOR", inputs.tolerances),
        _row("GENERATIVE INCREMENTS", inputs.increments),
        _row("INITIAL VALUES", inputs.x0),
        f"THE ORDER IS {n}, WITH {inputs.partial_sets} SETS OF PARTIALS OF "
        f"{inputs.iterations_per_partials} ITERATIONS EACH.",
    ]
    if inputs.analytic_partials != "none":
        lines.append(f"ANALYTIC PARTIALS USED FOR THE {inputs.analytic_partials.upper()}.")
    if inputs.partials_only:
        lines.append("PARTIALS ONLY: NO SEARCH IS MADE.")
    if inputs.mass is not None:
        m, k = inputs.mass
        lines.append(f"AUXILIARY CALCULATION M' = M - K*DELTA WITH M = {m:+.8E}, K = {k:+.8E}")
    options = [
        name
        for name, on in (("BROYDEN UPDATES", inputs.broyden), ("STEP HALVING", inputs.step_halving))
        if on
    ]
    if options:
        lines.append("IMPROVEMENTS: " + ", ".join(options) + ".")

    steps_by_case = {step.case: step for ps in result.history.partial_sets for step in ps.steps}
    sets_after: dict[int, list[PartialSet]] = {}
    for ps in result.history.partial_sets:
        sets_after.setdefault(ps.after_case, []).append(ps)
    for case in result.history.cases:
        lines.append("")
        if case.number in steps_by_case:
            lines += _step_lines(steps_by_case[case.number])
        lines += _case_lines(case)
        for ps in sets_after.get(case.number, []):
            lines += _partials_lines(ps)

    lines += [
        "",
        f"EXIT: {result.status.upper()} (FLAG {result.flag}) AFTER {result.n_nominal} NOMINAL, "
        f"{result.n_perturbed} PERTURBED AND {result.n_applied} APPLIED CASES",
        _row("FINAL INDEPENDENT VARIABLES", result.x),
        _row("FINAL DEPENDENT VARIABLES", result.y),
        _row("MISS (Y - YT)", result.miss),
    ]
    return "\n".join(lines) + "\n"
