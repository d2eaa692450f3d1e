"""Tracking by a pass schedule: ``[tracking] schedule = "passes.csv"`` (the file:
:mod:`tapp.io.schedule_file`), instead of or beside visibility tracking.

How a schedule combines with the scenario's other ``[tracking]`` keys:

- ``use = "schedule"`` (the default with a schedule): every station of ``tracking.stations``
  is tracked in its passes of the schedule and nowhere else; a station without a pass stays
  on the tape (its parameters, a ΔDOR baseline) and yields no observation, a warning as for
  a station that never sees the spacecraft. ``use = "both"``: the stations with passes are
  tracked in them, the others by visibility as before. ``use = "visibility"``: the schedule
  is not read. ΔDOR baselines keep their own schedule (``[ddor]``, on the scenario's grid).
- A pass's samples fall on the scenario's sample clock ``tracking.start`` + i Δt, Δt its own
  ``data_interval_s`` (default ``tracking.data_interval_s``), and measure its ``data_types``
  (default: all the station's observables). ``tracking.end`` bounds the visibility grid
  only.
- The rules of :mod:`tapp.tracking.editing` apply in their order, and the editing table
  counts what the schedule asked (scheduled) against what was kept, per station:
  ``outside_tape`` counts the samples at or before t = 0 or after the last T13 time (a
  schedule may run past the tape); a sample at or below the station's mask is an error
  naming the file, the row and the samples (``expected a pass that S sees above its mask``),
  unless ``allow_partial = true``, when it is dropped and counted under ``elevation_mask``;
  the blackouts (``tracking.blackouts``, the station's own) still remove samples, counted
  under ``blackout``. ``min_pass_s`` does not apply: it drops the grazing passes visibility
  tracking finds, and a scheduled pass is kept however short. ``max_pass_s`` splits a pass as
  it splits any.
- The samples kept of one pass form passes on the tape (runs of consecutive samples, each
  with its own per-pass bias in the real world): a pass cut by a blackout, or by the mask
  under ``allow_partial``, becomes two.

The station "sees" the spacecraft where its geometric elevation is above its mask, the test
of visibility tracking (occultation by the Moon is not modelled, in either). A schedule that
lists the passes visibility tracking kept (``passes/`` of its tape: station, first and last
sample) therefore gives a tape whose datasets equal that tape's, but ``editing/``, which then
counts that schedule's samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.schedule_file import ScheduledPass
from tapp.tracking.editing import Editing, edited_passes
from tapp.tracking.scenario import Schedule, TrackingStation


def by_schedule(schedule: Schedule, station: str) -> bool:
    """Whether ``station`` is tracked in the schedule's passes (module docstring: ``use``)."""
    if schedule.passes is None:
        return False
    return schedule.use == "schedule" or station in schedule.passes.stations


def schedule_provenance(schedule: Schedule) -> dict[str, str]:
    """The tape's ``schedule`` provenance, ``FILE (sha256 HEX)``; none by visibility."""
    if schedule.passes is None:
        return {}
    return {"schedule": f"{schedule.passes.source} (sha256 {schedule.passes.sha256})"}


@dataclass(frozen=True, slots=True)
class StationSamples:
    """The samples one station's passes ask for within the tape's span (0, last T13 time].

    Attributes
    ----------
    passes : the station's passes, by start.
    t_s : (n,) sample times, s, ascending.
    index : (n,) the pass of each sample, an index into ``passes``.
    asked : the samples each pass asks for, inside the span or not.
    """

    passes: tuple[ScheduledPass, ...]
    t_s: np.ndarray
    index: np.ndarray
    asked: tuple[int, ...]


def station_samples(schedule: Schedule, station: str, last_s: float) -> StationSamples:
    """Return the samples of ``station``'s passes in (0, ``last_s``] (s)."""
    passes = schedule.passes.of(station)
    times = [p.sample_times_s(schedule.start_s) for p in passes]
    inside = [t[(t > 0.0) & (t <= last_s)] for t in times]
    return StationSamples(
        passes, np.concatenate([np.zeros(0), *inside]),
        np.concatenate([np.zeros(0, int), *(np.full(t.size, i) for i, t in enumerate(inside))]),
        tuple(t.size for t in times))


def _invisible(p: ScheduledPass, t: np.ndarray, above: np.ndarray, ts: TrackingStation,
               epoch: Epoch, source: str) -> InputError:
    """The error for a pass with samples ``t`` of which the station sees only ``above``."""
    below = t[~above]
    field = "start" if not above[0] else "end"
    mask_deg = math.degrees(ts.station.elev_mask_rad)
    return InputError(source, f"row {p.row}: {field}",
                      f"a pass that {ts.station.name} sees above its {mask_deg:g}° elevation "
                      "mask throughout ([tracking] allow_partial = true drops the samples it "
                      "cannot see, counted under elevation_mask)",
                      f"{below.size} of its {t.size} samples at or below the mask, "
                      f"{epoch.iso_after(float(below[0]), 3)} to "
                      f"{epoch.iso_after(float(below[-1]), 3)} UTC")


def scheduled_passes(samples: StationSamples, above: np.ndarray, ts: TrackingStation,
                     schedule: Schedule, epoch: Epoch
                     ) -> tuple[list[tuple[int, int]], np.ndarray, Editing]:
    """Edit one station's scheduled samples (module docstring).

    Parameters
    ----------
    samples : the station's samples (:func:`station_samples`).
    above : (n,) bool, whether the station sees the spacecraft above its mask at each.
    ts : the station.
    schedule : the scenario's schedule (blackouts come from ``ts``).
    epoch : the scenario's epoch (UTC), for messages.

    Returns
    -------
    passes : index ranges [start, stop) into ``samples.t_s`` of the passes kept.
    taken : (n, m) bool, which of the station's m observables each sample measures.
    editing : the counts, in observations.

    Raises
    ------
    InputError
        Naming the schedule file and the row: a pass with a sample the station cannot see,
        unless ``schedule.allow_partial``.
    """
    out: list[tuple[int, int]] = []
    parts = []
    for i, p in enumerate(samples.passes):
        where = np.flatnonzero(samples.index == i)
        t, sees = samples.t_s[where], above[where]
        if not (schedule.allow_partial or sees.all()):
            raise _invisible(p, t, sees, ts, epoch, schedule.passes.source)
        first = int(where[0]) if where.size else 0
        kept, editing = edited_passes(sees, ts.blackouts_s, 0.0, schedule.max_pass_s,
                                      p.data_interval_s, t, samples.asked[i], len(p.kinds))
        out.extend((first + a, first + b) for a, b in kept)
        parts.append(editing)
    measures = np.array([[k in p.kinds for k in ts.kinds] for p in samples.passes],
                        dtype=bool).reshape(-1, len(ts.kinds))
    return out, measures[samples.index], Editing.total(parts)
