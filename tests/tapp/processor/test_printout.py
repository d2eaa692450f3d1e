"""The run's largest real/fit σ ratio (the last line of ``tapp process``)."""

from __future__ import annotations

import numpy as np

from tapp.processor.printout import SigmaRatio, largest_sigma_ratio
from tapp.processor.sequencing import HistoryRow, Run

_DAY_S = 86400.0


def _row(kind: str, t_s: float, fit, real, miss_fit, miss_real) -> HistoryRow:
    return HistoryRow(kind, 1, t_s, None if fit is None else np.array(fit), np.array(real),
                      None if miss_fit is None else np.diag(np.square(miss_fit)),
                      np.diag(np.square(miss_real)), 9.0)


def _run(*rows: HistoryRow) -> Run:
    return Run((), rows, ("x_km", "GM_km3_s2"), (), np.eye(2), np.eye(2))


def test_the_largest_ratio_over_times_history_and_miss():
    run = _run(_row("print", 0.0, [1.0, 2.0], [1.5, 2.0], [1.0], [1.0]),
               _row("recycle", _DAY_S, [1.0, 2.0], [2.0, 2.0], [0.5], [2.5]),  # miss: 5
               _row("print", 2 * _DAY_S, [1.0, 2.0], [4.0, 2.0], [1.0], [1.0]))
    assert largest_sigma_ratio(run, ("b_dot_r_km",)) == SigmaRatio(5.0, "b_dot_r_km",
                                                                   "recycle", _DAY_S)


def test_a_sigma_the_fit_world_holds_at_zero_makes_no_claim():
    # GM held fixed in the fit world (σ 0) with a real σ: passed over, not an infinite ratio
    run = _run(_row("print", 0.0, [1.0, 0.0], [3.0, 1.0], [1.0], [1.0]))
    assert largest_sigma_ratio(run, ("b_dot_r_km",)) == SigmaRatio(3.0, "x_km", "print", 0.0)


def test_no_fit_world_covariance_gives_no_ratio():
    run = _run(_row("print", 0.0, None, [3.0, 1.0], None, [1.0]),
               _row("print", 1.0, [0.0, 0.0], [3.0, 1.0], [0.0], [1.0]))
    assert largest_sigma_ratio(run, ("b_dot_r_km",)) is None
