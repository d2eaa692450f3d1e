"""TAPP I's editing rules: which scheduled samples become observations, in which passes, and
what each rule removed (the T13 tape's ``editing/``, :class:`tapp.io.tape.t13.TapeEditing`).

A station's samples, time-ordered, come either from the scenario's grid (visibility tracking)
or from the passes of a schedule (:mod:`tapp.tracking.schedule`); the same rules edit both.
A sample is counted under the first of :data:`EDITING_RULES` that removes it; the samples
left form passes (runs of consecutive samples, split at gaps of more than
:data:`GAP_INTERVALS` data intervals), and a pass longer than max_pass_s is split into
consecutive passes of at most max_pass_s, none of its samples removed. Counts are scalar
observations: a sample of a station that measures m observables is m observations.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from tapp.measurements import find_passes

#: Passes split where consecutive samples are more than this many data intervals apart.
GAP_INTERVALS = 1.5
#: The rules that remove scheduled samples, in the order they apply; a sample is counted
#: under the first that removes it. "outside_tape": at or before t = 0 or after the last
#: T13 time (no record holds it; counted whatever the spacecraft's elevation);
#: "elevation_mask": at or below the station's mask; "blackout": in one of the station's
#: blackouts (passes: the passes above the mask left without a sample); "min_pass": in a pass
#: shorter than min_pass_s (passes: those passes).
EDITING_RULES = ("outside_tape", "elevation_mask", "blackout", "min_pass")


@dataclass(frozen=True, slots=True)
class Editing:
    """What the rules did at one station: observations and passes removed per rule (in the
    order of :data:`EDITING_RULES`), passes added by splitting at max_pass_s, of
    ``scheduled`` observations (a ΔDOR baseline's: the points its schedule asks for)."""

    removed_obs: tuple[int, ...]
    removed_passes: tuple[int, ...]
    added_passes: int
    scheduled: int

    @classmethod
    def total(cls, parts: Iterable[Editing]) -> Editing:
        """The sum of ``parts`` (the passes of one station's schedule); none: all zero."""
        n = len(EDITING_RULES)
        removed, passes, added, scheduled = np.zeros(n, int), np.zeros(n, int), 0, 0
        for e in parts:
            removed += e.removed_obs
            passes += e.removed_passes
            added += e.added_passes
            scheduled += e.scheduled
        return cls(tuple(int(v) for v in removed), tuple(int(v) for v in passes), added,
                   scheduled)


def removed_text(counts: Iterable[int]) -> str:
    """``RULE N, ...``: what each editing rule removed (:data:`EDITING_RULES`)."""
    return ", ".join(f"{rule} {n}" for rule, n in zip(EDITING_RULES, counts, strict=True))


def split_pass(t: np.ndarray, start: int, stop: int, max_pass_s: float
               ) -> list[tuple[int, int]]:
    """Cut the pass [start, stop) of the times ``t`` (s) into consecutive passes of at most
    ``max_pass_s`` each (first to last sample), every sample kept."""
    out = []
    while start < stop:
        end = start + int(np.count_nonzero(t[start:stop] - t[start] <= max_pass_s))
        out.append((start, end))
        start = end
    return out


def outside_blackouts(above: np.ndarray, t: np.ndarray,
                      blackouts_s: tuple[tuple[float, float], ...]) -> np.ndarray:
    """``above`` where t (s) is in none of the blackouts (inclusive windows, s), (N,) bool."""
    visible = above.copy()
    for start, end in blackouts_s:
        visible &= ~((t >= start) & (t <= end))
    return visible


def edited_passes(above: np.ndarray, blackouts_s: tuple[tuple[float, float], ...],
                  min_pass_s: float, max_pass_s: float, data_interval_s: float, t: np.ndarray,
                  n_scheduled: int, obs_per_sample: int = 1
                  ) -> tuple[list[tuple[int, int]], Editing]:
    """Return the passes and what each rule removed (:data:`EDITING_RULES`).

    Parameters
    ----------
    above : (N,) bool, whether the station sees the spacecraft above its mask at ``t``.
    blackouts_s : ((start, end), ...) s, the station's blackouts.
    min_pass_s, max_pass_s : shortest pass kept and longest pass before splitting, s.
    data_interval_s : the time between samples, s (passes split at gaps of more than
        :data:`GAP_INTERVALS` of it).
    t : (N,) the sample times within the tape's span, s, ascending.
    n_scheduled : the samples scheduled, ``t`` and those outside the tape's span.
    obs_per_sample : observations per sample (the observables measured).

    Returns
    -------
    passes : index ranges [start, stop) into ``t``, at least ``min_pass_s`` long and split
        at ``max_pass_s``.
    editing : the counts, in observations.
    """
    gap_s = GAP_INTERVALS * data_interval_s
    visible = outside_blackouts(above, t, blackouts_s)
    blacked_out = sum(not visible[a:b].any() for a, b in find_passes(above, t, gap_s))
    long_enough = []
    short = [0, 0]  # samples, passes
    for start, stop in find_passes(visible, t, gap_s):
        if t[stop - 1] - t[start] < min_pass_s:
            short[0] += int(stop - start)
            short[1] += 1
        else:
            long_enough.append((int(start), int(stop)))
    out = [piece for start, stop in long_enough
           for piece in split_pass(t, start, stop, max_pass_s)]
    n_above, n_visible = int(np.count_nonzero(above)), int(np.count_nonzero(visible))
    removed = (n_scheduled - t.size, t.size - n_above, n_above - n_visible, short[0])
    return out, Editing(tuple(obs_per_sample * n for n in removed),
                        (0, 0, blacked_out, short[1]), len(out) - len(long_enough),
                        obs_per_sample * n_scheduled)
