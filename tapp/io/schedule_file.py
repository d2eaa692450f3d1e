"""Pass schedules (CSV): one row per tracking pass, for a scenario's ``[tracking] schedule``.

::

    # DSN passes of the first week (comment lines and blank lines are skipped)
    station,start,end,data_types,data_interval_s,uplink_station
    GOLDSTONE,2026-03-10T14:00:00,2026-03-10T22:00:00,range range_rate,60,
    CANBERRA,2026-03-10T23:00:00,2026-03-11T06:30:00,range_rate,,CANBERRA
    MADRID,86400,100800,,,

Columns (named by the header, in any order; the first three required, each at most once):

- ``station``: a station of the scenario's ``tracking.stations``;
- ``start``, ``end``: the pass, end after start: a UTC date (ISO 8601, as the scenario's
  ``epoch``) or seconds from the scenario's epoch (a number); within 100 years of the epoch;
- ``data_types``: observables the station measures (its ``observables``), separated by
  spaces; empty: all of them;
- ``data_interval_s``: seconds between samples, at least :data:`MIN_INTERVAL_S`; empty: the
  scenario's ``tracking.data_interval_s``;
- ``uplink_station``: empty, the station itself (two-way) or, for a station the scenario
  tracks three-way (``[tracking.station.NAME] uplink``), that uplink station: a station's
  passes all share its link (one measurement model per station), so any other station is
  refused.

The samples of a pass fall on the scenario's sample clock, t = ``tracking.start`` + i Δt with
Δt the pass's interval, from its start to its end (both ends catch a sample time within
:data:`SAMPLE_MATCH_S`): passes sampled at the scenario's interval share its grid, so a
schedule that lists the passes visibility tracking found gives back the same samples, bit
for bit. A pass must hold a sample; two passes of one station must not overlap (the later
one must start after the earlier one ends).

Rows are numbered as the file's lines, so an error names the line an editor shows:
``FILE: row N: FIELD: expected WHAT (got VALUE)``. The file is read as bounded text
(:func:`iter.inputfile.read_text`): a regular file of at most :data:`MAX_SCHEDULE_BYTES`
in UTF-8 (a byte-order mark, as spreadsheets write, is skipped), one row per line (no line
breaks inside quoted cells).
"""

from __future__ import annotations

import csv
import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from iter.inputfile import read_text
from tapp.errors import InputError
from tapp.frames.time import Epoch, parse_epoch
from tapp.frames.timescales import seconds_after
from tapp.measurements import Observable

#: Largest schedule file, bytes: about 40,000 passes (a year of a dozen passes a day is 4,400).
MAX_SCHEDULE_BYTES = 4 * 2**20
#: Most samples a schedule may ask for over all its passes (the grids' bound, 1e6 samples).
MAX_SCHEDULE_SAMPLES = 1_000_000
#: Shortest data interval of a pass, s (it must exceed twice :data:`SAMPLE_MATCH_S`).
MIN_INTERVAL_S = 1e-3
#: A pass's start or end catches a sample time this close, s: dates to the microsecond and
#: seconds converted through Julian dates (rounding ~1e-11 s) still land on the clock.
SAMPLE_MATCH_S = 1e-6
#: Farthest a pass may lie from the epoch, s (100 Julian years).
MAX_OFFSET_S = 100 * 365.25 * 86400.0
#: The columns, the required ones first.
REQUIRED = ("station", "start", "end")
COLUMNS = (*REQUIRED, "data_types", "data_interval_s", "uplink_station")
_KINDS = tuple(o.value for o in Observable)


@dataclass(frozen=True, slots=True)
class ScheduledPass:
    """One row of a schedule: ``station`` tracks from ``start_s`` to ``end_s`` (s from the
    scenario's epoch), measuring ``kinds`` every ``data_interval_s`` (s); ``row`` is the
    file's line."""

    row: int
    station: str
    start_s: float
    end_s: float
    kinds: tuple[str, ...]
    data_interval_s: float

    def sample_times_s(self, clock_s: float) -> np.ndarray:
        """Return the pass's sample times clock_s + i Δt in [start, end] (ends within
        :data:`SAMPLE_MATCH_S`), s, (n,) ascending; ``clock_s`` is ``tracking.start``."""
        dt_s = self.data_interval_s
        first = math.ceil((self.start_s - clock_s - SAMPLE_MATCH_S) / dt_s)
        last = math.floor((self.end_s - clock_s + SAMPLE_MATCH_S) / dt_s)
        # i Δt with i a float of an integer, as the scenario's grid start + Δt arange(n)
        return clock_s + dt_s * np.arange(first, last + 1, dtype=float)


@dataclass(frozen=True, slots=True)
class PassSchedule:
    """A schedule file's passes, ordered by station (the scenario's order) then start, and
    the SHA-256 of its text (hex; the tape's provenance)."""

    source: str
    passes: tuple[ScheduledPass, ...]
    sha256: str

    @property
    def stations(self) -> frozenset[str]:
        """The stations with at least one pass."""
        return frozenset(p.station for p in self.passes)

    def of(self, station: str) -> tuple[ScheduledPass, ...]:
        """The passes of ``station``, by start."""
        return tuple(p for p in self.passes if p.station == station)


class _Rows:
    """Conversions of the cells of one file, each failure naming the file, the row and the
    column."""

    def __init__(self, source: str, epoch: Epoch, stations: Mapping[str, tuple[str, ...]],
                 data_interval_s: float, uplinks: Mapping[str, str] | None = None):
        self.source = source
        self.epoch = epoch
        self.stations = stations
        self.data_interval_s = data_interval_s
        self.uplinks = {} if uplinks is None else uplinks

    def fail(self, row: int, column: str, expected: str, got: object = None) -> InputError:
        return InputError(self.source, f"row {row}: {column}", expected, got)

    def time_s(self, row: int, column: str, cell: str) -> float:
        try:
            value = float(cell)
        except ValueError:
            try:
                value = seconds_after(self.epoch, parse_epoch(cell, self.source), self.source)
            except InputError as exc:
                raise self.fail(row, column, f"seconds from the epoch or {exc.expected}",
                                cell) from None
        if not abs(value) <= MAX_OFFSET_S:  # NaN too
            raise self.fail(row, column, "a time within 100 years of the epoch (seconds from "
                            "it, finite, or an ISO 8601 UTC date)", cell)
        return value

    def station(self, row: int, cell: str) -> str:
        if cell not in self.stations:
            raise self.fail(row, "station", "a station of tracking.stations ("
                            + ", ".join(self.stations) + ")", cell)
        return cell

    def kinds(self, row: int, station: str, cell: str) -> tuple[str, ...]:
        takes = self.stations[station]
        names = cell.split()
        if not names:
            return takes
        for name in names:
            if name not in _KINDS:
                raise self.fail(row, "data_types", "observables among " + ", ".join(_KINDS)
                                + ", separated by spaces", cell)
            if name not in takes:
                raise self.fail(row, "data_types", f"observables that {station} measures ("
                                + ", ".join(takes) + "; tracking.observables or "
                                f"tracking.station.{station}.observables)", cell)
        if len(set(names)) != len(names):
            raise self.fail(row, "data_types", "each observable once", cell)
        return tuple(k for k in takes if k in names)  # the station's order

    def interval_s(self, row: int, cell: str) -> float:
        if not cell:
            return self.data_interval_s
        try:
            value = float(cell)
        except ValueError:
            value = math.nan
        if not MIN_INTERVAL_S <= value < math.inf:
            raise self.fail(row, "data_interval_s", f"a number of seconds >= {MIN_INTERVAL_S:g} "
                            "(empty: tracking.data_interval_s)", cell)
        return value

    def uplink(self, row: int, station: str, cell: str) -> None:
        uplink = self.uplinks.get(station)
        if uplink is None and cell and cell != station:
            raise self.fail(row, "uplink_station", f"empty or {station}, the pass's own "
                            "station (three-way tracking from another station: that station "
                            f"as tracking.station.{station}.uplink)", cell)
        if uplink is not None and cell and cell != uplink:
            raise self.fail(row, "uplink_station", f"empty or {uplink}, the uplink of "
                            f"{station} (tracking.station.{station}.uplink: its passes share "
                            "its link)", cell)


def _header(rows: _Rows, line: int, cells: list[str]) -> dict[str, int]:
    """The column of each name; every required name present, every name known, once."""
    if (any(c not in COLUMNS for c in cells) or len(set(cells)) != len(cells)
            or any(c not in cells for c in REQUIRED)):
        raise rows.fail(line, "header", "the columns " + ", ".join(REQUIRED) + " (optional: "
                        + ", ".join(COLUMNS[len(REQUIRED):]) + "), each once, comma-separated",
                        ",".join(cells))
    return {name: cells.index(name) for name in cells}


def parse_schedule(text: str, source: str, *, epoch: Epoch,
                   stations: Mapping[str, tuple[str, ...]], data_interval_s: float,
                   clock_s: float, uplinks: Mapping[str, str] | None = None) -> PassSchedule:
    """Return the passes of a schedule's text, validated (module docstring).

    Parameters
    ----------
    text : the CSV text.
    source : the file, for messages.
    epoch : the scenario's epoch (UTC), t = 0.
    stations : the observables of each station of ``tracking.stations``, in its order.
    data_interval_s : the scenario's data interval, s (a pass's default).
    clock_s : the scenario's ``tracking.start``, s: the sample clock.
    uplinks : the uplink station of each three-way station (others: two-way).

    Raises
    ------
    InputError
        ``FILE: row N: FIELD: expected WHAT (got VALUE)``: a header without a required
        column or with an unknown one, a row with another number of cells, an unknown
        station, an unreadable time, an end not after the start, an unknown data type or
        one the station does not measure, an interval below the least, another uplink
        station, a pass without a sample, passes of one station that overlap, more than
        :data:`MAX_SCHEDULE_SAMPLES` samples; a file without a pass.
    """
    rows = _Rows(source, epoch, stations, data_interval_s, uplinks)
    lines = [(n, line) for n, line in enumerate(text.removeprefix("\ufeff").splitlines(),
                                                 start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise rows.fail(1, "header", "the columns " + ", ".join(REQUIRED) + " (and optional "
                        "ones) on the first line that is not a comment", "")
    columns = _header(rows, lines[0][0], [c.strip() for c in next(csv.reader([lines[0][1]]))])
    passes: list[ScheduledPass] = []
    samples = 0
    for n, line in lines[1:]:
        cells = [c.strip() for c in next(csv.reader([line]))]
        if len(cells) != len(columns):
            raise rows.fail(n, "cells", f"{len(columns)} comma-separated cells, one per column "
                            "of the header", len(cells))

        def cell(name: str, cells: list[str] = cells) -> str:
            return cells[columns[name]] if name in columns else ""

        station = rows.station(n, cell("station"))
        start = rows.time_s(n, "start", cell("start"))
        end = rows.time_s(n, "end", cell("end"))
        if end <= start:
            raise rows.fail(n, "end", f"a time after the pass's start ({start:.6f} s from the "
                            "epoch)", cell("end"))
        rows.uplink(n, station, cell("uplink_station"))
        p = ScheduledPass(n, station, start, end, rows.kinds(n, station, cell("data_types")),
                          rows.interval_s(n, cell("data_interval_s")))
        if (end - start) / p.data_interval_s + 1 > MAX_SCHEDULE_SAMPLES - samples:
            raise rows.fail(n, "data_interval_s", f"at most {MAX_SCHEDULE_SAMPLES:,} samples "
                            f"over the schedule ({samples:,} before this row; a longer "
                            "interval)", cell("data_interval_s") or p.data_interval_s)
        count = p.sample_times_s(clock_s).size
        if count == 0:
            raise rows.fail(n, "end", f"a pass holding a sample time tracking.start + i × "
                            f"{p.data_interval_s:g} s (none between its start and end)",
                            cell("end"))
        samples += count
        passes.append(p)
    if not passes:
        raise InputError(source, "rows", "at least one pass after the header", "none")
    order = list(stations)
    passes.sort(key=lambda p: (order.index(p.station), p.start_s))
    for before, after in zip(passes, passes[1:], strict=False):
        if after.station == before.station and after.start_s <= before.end_s:
            raise rows.fail(after.row, "start", f"a time after the end of {after.station}'s "
                            f"pass on row {before.row} ({epoch.iso_after(before.end_s, 3)} "
                            "UTC): passes of a station do not overlap",
                            epoch.iso_after(after.start_s, 3))
    return PassSchedule(source, tuple(passes), hashlib.sha256(text.encode()).hexdigest())


def read_schedule(path: Path | str, *, epoch: Epoch, stations: Mapping[str, tuple[str, ...]],
                  data_interval_s: float, clock_s: float,
                  uplinks: Mapping[str, str] | None = None) -> PassSchedule:
    """Read and validate a schedule file (:func:`parse_schedule`); a FIFO, a device, a
    directory or a file larger than :data:`MAX_SCHEDULE_BYTES` is refused unread."""
    text = read_text(path, "pass schedule (CSV)", max_bytes=MAX_SCHEDULE_BYTES,
                     error=InputError)
    return parse_schedule(text, str(path), epoch=epoch, stations=stations,
                          data_interval_s=data_interval_s, clock_s=clock_s, uplinks=uplinks)
