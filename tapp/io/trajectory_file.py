"""A mission's trajectory from a file (SPICE SPK or CCSDS OEM), in scenario time and frame.

A scenario's ``[reference]`` names the file (:mod:`tapp.tracking.reference` fits TAPP I's force
model to it). :func:`read_reference` returns its states as a :class:`ReferenceTrajectory`:
Earth-centred, in the scenario's inertial frame (GCRS under iau2006, EME2000 under gmst), at
scenario times (SI seconds from the UTC epoch):

- **SPK** (a DAF file, told by its first bytes ``DAF/SPK``; :mod:`tapp.io.spk`): sampled by
  SPICE every ``step_s`` over the scenario's span, and at the arc boundaries; ET from
  scenario time, each state moved by the sub-ulp remainder its rounded ET leaves out (up to
  6e-8 s, 0.45 mm at 7.5 km/s) and its velocity taken from TDB to scenario seconds
  (:func:`tapp.frames.timesystems.from_et`); ``J2000`` axes are the GCRS's (rotated by the
  frame bias for gmst).
- **OEM** (KVN or XML; :mod:`tapp.io.ccsds.oem_read`): every state of the segments of the
  object (``object`` matches ``OBJECT_NAME`` or ``OBJECT_ID``; without it, the file must hold
  one object), within each segment's ``USEABLE_START_TIME`` .. ``USEABLE_STOP_TIME`` when
  given. The header is honoured: epochs in ``TIME_SYSTEM`` (:mod:`tapp.frames.timesystems`),
  axes ``REF_FRAME`` (:mod:`tapp.frames.file_frames`), ``CENTER_NAME`` the Earth or a body
  whose state DE421 gives (added, read through SPICE; not with an Earth-fixed frame), and
  states at the arc boundaries by the segment's ``INTERPOLATION`` of its degree, in the
  file's own frame and time, before they are turned.

The states must cover the scenario's span [0, last T13 time] without a gap between segments;
each boundary is inside one segment (the later one where two meet). Every failure is an
:class:`~tapp.errors.InputError`: in the file (an OEM's line or element) naming the file, or
in the scenario naming ``reference.file`` / ``reference.object``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import Field

from tapp.errors import InputError
from tapp.frames.file_frames import is_earth_fixed, to_scenario_frame
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tapp.frames.timesystems import et_from_scenario, from_et, scenario_seconds
from tapp.io.ccsds.oem_read import OemMessage, OemSegment, interpolate, read_oem
from tapp.io.noise_file import Positive
from tapp.io.schema import Schema
from tapp.io.spk import body_id, body_states, spk_states

#: The first bytes of an SPK (a DAF file of the SPK architecture).
SPK_MAGIC = b"DAF/SPK"
#: Largest position difference accepted by default between TAPP I's fitted trajectory and the
#: reference, m. TAPP I's partials are linear about its nominal: a nominal 100 m off moves
#: the observation geometry by 1e-4 of the closest range it sees (1000 km, a LEO at its
#: horizon) and a pass by 0.013 s at 7.5 km/s, far below the noise the covariance describes;
#: a worse fit is a different trajectory (another force model, a manoeuvre the scenario does
#: not know, a wrong frame or time system) and its covariance is not the mission's.
MAX_FIT_ERROR_M = 100.0
#: Spacing of the states sampled from an SPK for the fit, s, by default.
SPK_STEP_S = 60.0
#: What an OEM's CENTER_NAME may be (the bodies DE421 gives are its centres).
_CENTRES = ("EARTH, or a body whose state DE421 gives: MOON, SUN, EARTH BARYCENTER, SOLAR "
            "SYSTEM BARYCENTER, a planet's BARYCENTER")
#: Most reference states a scenario may read: each is a row of the fit's least squares
#: (an OEM every second over 2.3 days; an SPK's step_s sets its number).
MAX_REFERENCE_STATES = 200_000


@dataclass(frozen=True, slots=True)
class ReferenceTrajectory:
    """A mission's trajectory as read (module docstring).

    Attributes
    ----------
    source : the file, as the scenario names it (resolved from the scenario's folder).
    kind : ``"SPK"`` or ``"OEM"``.
    body : the object: an SPK's NAIF id, an OEM's ``OBJECT_NAME``.
    t_s : (N,) scenario times of the states, s, ascending (a boundary epoch two segments
        share appears twice).
    states : (N, 6) km, km/s, Earth-centred, the scenario's inertial frame.
    segment : (N,) int, the file's segment of each state (0 for an SPK's samples).
    boundaries_s : (K,) the arc boundaries asked for, s; ``boundary_states`` (K, 6) there.
    notes : what was read and how it was turned (frame, centre, time system, interpolation).
    """

    source: str
    kind: str
    body: str
    t_s: np.ndarray
    states: np.ndarray
    segment: np.ndarray
    boundaries_s: np.ndarray
    boundary_states: np.ndarray
    notes: tuple[str, ...]

    def state_at_boundary(self, t_s: float) -> np.ndarray:
        """The reference state (6,) at an arc boundary asked for when reading."""
        k = int(np.flatnonzero(self.boundaries_s == t_s)[0])
        return self.boundary_states[k]


@dataclass(frozen=True, slots=True)
class Reference:
    """A scenario's ``[reference]``: the trajectory read, the largest position difference its
    fit may leave (``max_fit_error_m``, m) and whether the fit adjusts the burns
    (``fit_manoeuvres``; :mod:`tapp.tracking.reference`)."""

    trajectory: ReferenceTrajectory
    max_fit_error_m: float
    fit_manoeuvres: bool = True


class ReferenceTable(Schema):
    """``[reference]``: the mission's own trajectory, to which TAPP I fits its force model over
    each arc (the fitted trajectory is then the nominal of the observables and the
    variational equations); a fit worse than ``max_fit_error_m`` is refused. Replaces
    ``[injection]``. The arcs are separated by the ``[[manoeuvre]]`` burns: the first fits
    the state at t = 0, each later one the burn it starts with."""

    file: str = Field(description="The trajectory file, relative to this file: a SPICE SPK "
                      "(any segment type SPICE reads) or a CCSDS OEM (KVN or XML; its "
                      "REF_FRAME, CENTER_NAME, TIME_SYSTEM and INTERPOLATION are honoured).")
    object: int | str | None = Field(
        None, description="The spacecraft: its NAIF id or a name SPICE knows, in an SPK "
        "(required); its OBJECT_NAME or OBJECT_ID in an OEM (needed when the OEM holds "
        "several objects).")
    max_fit_error_m: Positive = Field(
        MAX_FIT_ERROR_M, description="Largest position difference accepted between the fitted "
        "trajectory and the reference, on any arc (`tapp simulate --force` accepts a worse "
        "fit, printing it).")
    fit_manoeuvres: bool = Field(
        True, description="Fit each burn on the arc it starts: an impulsive burn's dv, a "
        "finite burn's thrust and direction (its ignition, duration, mass and flow as given); "
        "false flies the burns as the [[manoeuvre]] tables give them and compares those arcs "
        "only.")
    step_s: Positive | None = Field(
        None, description=f"Spacing of the SPK states the fit compares with; default "
        f"{SPK_STEP_S:g} s (an OEM's own states are used).")

    def read(self, source: str, *, epoch: Epoch, orientation: EarthOrientation,
             span_s: tuple[float, float], boundaries_s: tuple[float, ...]) -> Reference:
        """Read the file (relative to the folder of ``source``, the scenario file) for the
        scenario's span and arc boundaries (:func:`read_reference`)."""
        path = Path(self.file)
        if not path.is_absolute():
            path = Path(os.path.normpath(Path(source).parent / path))
        spk = path.is_file() and is_spk(path)
        if self.step_s is not None and not spk:
            raise InputError(source, "reference.step_s", "no step_s for an OEM (its own states "
                             "are used)", self.step_s)
        trajectory = read_reference(path, body=self.object, epoch=epoch,
                                    orientation=orientation, span_s=span_s,
                                    boundaries_s=boundaries_s,
                                    step_s=SPK_STEP_S if self.step_s is None else self.step_s,
                                    source=source)
        return Reference(trajectory, self.max_fit_error_m, self.fit_manoeuvres)


def is_spk(path: Path) -> bool:
    """Return True if the file at ``path`` begins as an SPK does."""
    with open(path, "rb") as f:
        return f.read(len(SPK_MAGIC)) == SPK_MAGIC


def read_reference(path: Path, *, body: int | str | None, epoch: Epoch,
                   orientation: EarthOrientation, span_s: tuple[float, float],
                   boundaries_s: tuple[float, ...], step_s: float, source: str,
                   field: str = "reference.file", body_field: str = "reference.object"
                   ) -> ReferenceTrajectory:
    """Read the trajectory file at ``path`` for a scenario (module docstring).

    Parameters
    ----------
    path : the file (SPK or OEM).
    body : the object: required for an SPK (NAIF id or name), optional for an OEM.
    epoch, orientation : the scenario's UTC epoch and Earth orientation.
    span_s : (start, end) the scenario's span the states must cover, s.
    boundaries_s : arc boundaries within the span, where states are interpolated, s.
    step_s : the spacing of an SPK's samples, s.
    source, field, body_field : the scenario file and its keys, for the errors.

    Raises
    ------
    InputError
        A missing or unreadable file, an SPK without the object, a span not covered, an
        unknown frame, centre or time system, epochs not increasing, too many states.
    """
    if not path.is_file():
        raise InputError(source, field, "an SPK or OEM file that exists", str(path))
    if is_spk(path):
        if body is None:
            raise InputError(source, body_field, "the spacecraft's NAIF id or name for an SPK")
        return _read_spk(path, body, epoch, span_s, boundaries_s, step_s, source, field,
                         body_field, orientation)
    return _read_oem(path, body, epoch, orientation, span_s, boundaries_s, source, body_field)


def _span_text(epoch: Epoch, span_s: tuple[float, float]) -> str:
    return (f"the scenario's span {epoch.iso_after(span_s[0], 3)} to "
            f"{epoch.iso_after(span_s[1], 3)} UTC")


def _gcrs_to_scenario(states: np.ndarray, t_s: np.ndarray, orientation: EarthOrientation,
                      source: str, field: str) -> np.ndarray:
    """States with the GCRS's (ICRF, SPICE J2000) axes in the scenario's inertial frame."""
    return to_scenario_frame("GCRF", t_s, states, orientation, source, field)


def _read_spk(path: Path, body: int | str, epoch: Epoch, span_s: tuple[float, float],
              boundaries_s: tuple[float, ...], step_s: float, source: str, field: str,
              body_field: str, orientation: EarthOrientation) -> ReferenceTrajectory:
    naif = body_id(body, source, body_field)
    start, end = span_s
    count = int(np.ceil((end - start) / step_s))
    if count + 1 > MAX_REFERENCE_STATES:
        raise InputError(source, "reference.step_s", f"at most {MAX_REFERENCE_STATES:,} "
                         f"samples over {_span_text(epoch, span_s)} (a larger step)", step_s)
    t = np.unique(np.concatenate([np.minimum(start + step_s * np.arange(count + 1), end),
                                  boundaries_s]))
    span_et = et_from_scenario(np.array(span_s), epoch)
    states = spk_states(path, naif, et_from_scenario(t, epoch), source, field, body_field,
                        spans=((float(span_et[0]), float(span_et[1]),
                                _span_text(epoch, span_s)),))
    states = _gcrs_to_scenario(from_et(t, states, epoch), t, orientation, source, field)
    at = np.searchsorted(t, np.asarray(boundaries_s, dtype=float))
    note = (f"SPK {path.name}, body {naif}: SPICE states relative to the Earth in J2000 "
            f"(ICRF axes) every {step_s:g} s, ET = TDB seconds past J2000")
    return ReferenceTrajectory(str(path), "SPK", str(naif), t, states, np.zeros(t.size, int),
                               np.asarray(boundaries_s, dtype=float), states[at], (note,))


def _segments(msg: OemMessage, body: int | str | None, body_field: str, source: str
              ) -> tuple[OemSegment, ...]:
    """The segments of the object (all when the file holds one object)."""
    names = [(s.metadata["OBJECT_NAME"], s.metadata["OBJECT_ID"]) for s in msg.segments]
    objects = sorted(set(names))
    if body is None:
        if len(objects) > 1:
            raise InputError(source, body_field, "the object (OBJECT_NAME or OBJECT_ID) of an "
                             "OEM that holds several (" + "; ".join(
                                 f"{n} / {i}" for n, i in objects) + ")")
        return msg.segments
    wanted = str(body).strip().upper()
    chosen = tuple(s for s, (n, i) in zip(msg.segments, names, strict=True)
                   if wanted in (n.upper(), i.upper()))
    if not chosen:
        raise InputError(source, body_field, f"an object {Path(msg.source).name} holds ("
                         + "; ".join(f"{n} / {i}" for n, i in objects) + ")", body)
    return chosen


def _segment_times(seg: OemSegment, epoch: Epoch, source: str) -> np.ndarray:
    system = seg.metadata["TIME_SYSTEM"]
    return scenario_seconds(seg.jd_whole, seg.jd_fraction, system, epoch, source,
                            seg.fields["TIME_SYSTEM"])


def _useable(seg: OemSegment, t: np.ndarray, epoch: Epoch, source: str) -> np.ndarray:
    """Mask (N,) of the states within the segment's useable span."""
    keep = np.ones(t.size, dtype=bool)
    system = seg.metadata["TIME_SYSTEM"]
    for key, sign in (("USEABLE_START_TIME", 1.0), ("USEABLE_STOP_TIME", -1.0)):
        date = seg.date(key)
        if date is not None:
            bound = float(scenario_seconds(np.array([date[0]]), np.array([date[1]]), system,
                                           epoch, source, seg.fields["TIME_SYSTEM"])[0])
            keep &= sign * (t - bound) >= -1e-6
    return keep


def _to_earth(seg: OemSegment, t: np.ndarray, states: np.ndarray, epoch: Epoch,
              orientation: EarthOrientation, source: str) -> np.ndarray:
    """States of the segment (in its frame, about its centre) at scenario times t, Earth-
    centred in the scenario's frame."""
    frame, centre = seg.metadata["REF_FRAME"], seg.metadata["CENTER_NAME"]
    out = to_scenario_frame(frame, t, states, orientation, source, seg.fields["REF_FRAME"])
    if centre == "EARTH":
        return out
    if is_earth_fixed(frame):
        raise InputError(source, seg.fields["CENTER_NAME"], f"EARTH with REF_FRAME = {frame} "
                         "(an Earth-fixed frame)", centre)
    naif = body_id(centre, source, seg.fields["CENTER_NAME"], _CENTRES)
    offset = from_et(t, body_states(naif, et_from_scenario(t, epoch), source,
                                    seg.fields["CENTER_NAME"]), epoch)
    return out + _gcrs_to_scenario(offset, t, orientation, source, seg.fields["CENTER_NAME"])


def _read_oem(path: Path, body: int | str | None, epoch: Epoch,
              orientation: EarthOrientation, span_s: tuple[float, float],
              boundaries_s: tuple[float, ...], source: str, body_field: str
              ) -> ReferenceTrajectory:
    msg = read_oem(path)
    file = str(path)
    segments = _segments(msg, body, body_field, source)
    parts, boundary_states = [], {}
    for k, seg in enumerate(segments):
        t_all = _segment_times(seg, epoch, file)
        keep = _useable(seg, t_all, epoch, file)
        t, raw = t_all[keep], seg.states[keep]
        if t.size == 0:
            raise InputError(file, seg.fields["data"], "states within the segment's "
                             "USEABLE_START_TIME .. USEABLE_STOP_TIME")
        parts.append((k, seg, t, raw))
    _check_cover(parts, epoch, span_s, file)
    count = sum(int(np.count_nonzero((t >= span_s[0]) & (t <= span_s[1])))
                for _, _, t, _ in parts)
    if count > MAX_REFERENCE_STATES:
        raise InputError(source, "reference.file", f"an OEM of at most "
                         f"{MAX_REFERENCE_STATES:,} states over {_span_text(epoch, span_s)}",
                         f"{count:,} states")
    for b in boundaries_s:  # the later segment where two meet
        k, seg, t, raw = next(p for p in reversed(parts) if p[2][0] <= b <= p[2][-1])
        method, degree = seg.interpolation
        state = interpolate(method, degree, t, raw, [b])
        boundary_states[b] = _to_earth(seg, np.array([b]), state, epoch, orientation, file)[0]
    t = np.concatenate([p[2] for p in parts])
    states = np.concatenate([_to_earth(seg, tk, raw, epoch, orientation, file)
                             for _, seg, tk, raw in parts])
    segment = np.concatenate([np.full(p[2].size, p[0]) for p in parts])
    first = segments[0].metadata
    notes = (f"OEM {path.name} ({msg.form} {msg.version}), {len(segments)} segment"
             f"{'s' if len(segments) > 1 else ''} of {first['OBJECT_NAME']} "
             f"({first['OBJECT_ID']}): " + "; ".join(sorted({
                 f"REF_FRAME {s.metadata['REF_FRAME']} about {s.metadata['CENTER_NAME']}, "
                 f"TIME_SYSTEM {s.metadata['TIME_SYSTEM']}, {s.interpolation[0]} of degree "
                 f"{s.interpolation[1]}" for s in segments})) + f", turned to the "
             f"{orientation.frame} (Earth-centred) and UTC scenario time",)
    bounds = np.asarray(boundaries_s, dtype=float)
    return ReferenceTrajectory(file, "OEM", first["OBJECT_NAME"], t, states, segment, bounds,
                               np.array([boundary_states[b] for b in boundaries_s]), notes)


def _check_cover(parts: list, epoch: Epoch, span_s: tuple[float, float], file: str) -> None:
    """The segments' states cover the span, without a gap between consecutive segments."""
    (_, first, t_first, _), (_, last, t_last, _) = parts[0], parts[-1]
    start, end = span_s
    if t_first[0] > start + 1e-6:
        key = "USEABLE_START_TIME" if "USEABLE_START_TIME" in first.metadata else "START_TIME"
        raise InputError(file, first.fields[key], f"states from {_span_text(epoch, span_s)} "
                         "on", epoch.iso_after(float(t_first[0]), 3) + " UTC")
    if t_last[-1] < end - 1e-6:
        key = "USEABLE_STOP_TIME" if "USEABLE_STOP_TIME" in last.metadata else "STOP_TIME"
        raise InputError(file, last.fields[key], f"states up to the end of "
                         f"{_span_text(epoch, span_s)}",
                         epoch.iso_after(float(t_last[-1]), 3) + " UTC")
    for (_, _, t_a, _), (_, seg, t_b, _) in zip(parts, parts[1:], strict=False):
        gap = (t_a[-1], t_b[0])
        if gap[1] > gap[0] + 1e-6 and gap[1] > start and gap[0] < end:
            raise InputError(file, seg.fields["START_TIME"], "segments whose states meet "
                             f"within {_span_text(epoch, span_s)} (no state from "
                             f"{epoch.iso_after(float(gap[0]), 3)} UTC to the next segment)",
                             epoch.iso_after(float(gap[1]), 3) + " UTC")
