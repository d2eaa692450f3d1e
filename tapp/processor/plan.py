"""A TAPP III run bound to its tape: what the deck asks for, in the tape's indices.

:func:`tapp.processor.deck_bind.bind` builds a :class:`Plan` from a deck file and a T13 header;
the sequencer (:mod:`tapp.processor.sequencing`) runs it. Indices here are 0-based positions
and T13 time indices k (0 = injection, record k covers (t_{k-1}, t_k]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapp.processor.commands import ROC, Command, Side
from tapp.processor.representations import Systems


@dataclass(frozen=True, slots=True)
class StationOff:
    """Time-station flags Δ_TS(k, s) = 0 for station ``station`` and records
    ``k_first``..``k_last`` (inclusive, 1-based record indices; seed §4.3.4)."""

    station: int
    k_first: int
    k_last: int


@dataclass(frozen=True, slots=True, eq=False)
class Plan:
    """Everything a run needs besides the tape (seed Appendix A.1, "program inputs").

    Attributes
    ----------
    systems : the coded systems and partition sizes.
    S0 : (n_f1, n_f1) fit-world a priori normal matrix of the fitted parameters x^{f1}
        at injection (entries 0 where a σ is infinite: no a priori information).
    Lambda0 : (n_r1, n_r1) real-world a priori covariance of the uncertain parameters x^{r1}.
    print_k : T13 time indices of the print outputs (POT); 0, the a priori, comes first.
    recycle_k : T13 time indices of the recycles (RET), after the initial one at k = 0.
    print_statistics, recycle_print, recycle_tape : the mode flags δ_PM, δ_P, δ_T.
    print_commands, recycle_commands : the POC and ROC lists.
    stations_off : time-station flags.
    budget : whether real-world covariances get their error budget.
    budget_groups : (name, 0-based positions in r1) of a priori error sources; r1 positions
        not named are their own source (orbit: the whole rp block).
    history : the partition whose σ's, fit and real, are recorded at every statistics time
        (for the σ-against-time plots), e.g. ``p@current``.
    frames : the axes orbit covariances are given in: "inertial" (the tape's), and "ric"
        (radial, in-track, cross-track of the nominal state, :mod:`tapp.frames.ric`) for a
        second copy of every covariance entity of an orbit set and the RIC σ history.
    """

    systems: Systems
    S0: np.ndarray
    Lambda0: np.ndarray
    print_k: tuple[int, ...] = (0,)
    recycle_k: tuple[int, ...] = ()
    print_statistics: bool = True
    recycle_print: bool = True
    recycle_tape: bool = True
    print_commands: tuple[Command, ...] = ()
    recycle_commands: tuple[Command, ...] = ROC
    stations_off: tuple[StationOff, ...] = ()
    budget: bool = True
    budget_groups: tuple[tuple[str, tuple[int, ...]], ...] = ()
    history: Side = Side(0, 1, "p")
    frames: tuple[str, ...] = ("inertial",)
