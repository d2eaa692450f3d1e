"""CCSDS Orbit Ephemeris Message (OEM) 2.0 in KVN form: the trajectory of a simulation.

Layout per CCSDS 502.0-B-2 (Orbit Data Messages, Blue Book, 2009), §5: a header
(``CCSDS_OEM_VERS = 2.0``, ``COMMENT`` lines, ``CREATION_DATE``, ``ORIGINATOR``), then one or
more segments (§5.2.1: several are allowed, in time order), each a metadata block between
``META_START`` and ``META_STOP`` (``COMMENT`` lines, ``OBJECT_NAME``, ``OBJECT_ID``,
``CENTER_NAME``, ``REF_FRAME``, ``TIME_SYSTEM``, ``START_TIME``, ``STOP_TIME``,
``INTERPOLATION``, ``INTERPOLATION_DEGREE``) and one data line per epoch: the epoch (ISO, UTC)
and x, y, z (km), x_dot, y_dot, z_dot (km/s). Epochs increase within a segment; a segment
starts where the one before stops or later. The file is written to a temporary name and
renamed.

What the OEM of a simulation says (:func:`tapp.tracking.oem_states.oem_trajectory`):

- ``REF_FRAME`` is the frame the states are in: ``GCRF`` under the ``iau2006`` Earth
  orientation (the states are GCRS: IAU 2006/2000A with IERS EOP), ``EME2000`` under ``gmst``
  (:data:`REF_FRAMES`).
- The states run from the injection (t = 0) to the end of the simulation, every data
  interval, halved (repeatedly) around the intervals where the interpolation below would not
  hold: near a low perigee, in a swing-by.
- One segment per smooth arc between burns: an impulsive burn (a jump of the velocity) and a
  finite burn's ignition and cut-off (jumps of the acceleration), which no polynomial
  interpolates, end a segment with the state before them, and the next segment starts at the
  same epoch with the state after them. The burns themselves are header ``COMMENT`` lines
  (:mod:`tapp.tracking.oem_states`).
- ``INTERPOLATION = LAGRANGE`` with ``INTERPOLATION_DEGREE = 7``: a Lagrange polynomial
  through the 8 states nearest the time (the window centred on it, shifted inwards at the
  ends, as the ``oem`` package chooses it) reproduces the propagated trajectory at
  every mid-point between states of each segment within :data:`INTERPOLATION_TOL_KM` and
  :data:`INTERPOLATION_TOL_KM_S`; the largest errors found are stated in a ``COMMENT``.
- Every integration event met (a shadow entry or exit, a Harris-Priester table height:
  :mod:`tapp.dynamics.events`) is a ``COMMENT`` of the metadata of its segment, with its time
  (:func:`event_comments`).
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from tapp.dynamics.events import Events
from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.atomic import atomic_write

#: Digits of the seconds of the epochs (1 us).
EPOCH_DECIMALS = 6
#: OEM ``REF_FRAME`` (CCSDS SANA name) of the inertial frame of each Earth orientation model.
REF_FRAMES = {"iau2006": "GCRF", "gmst": "EME2000"}
#: Interpolation methods an OEM may declare (CCSDS 502.0-B-2 Table 5-3).
INTERPOLATIONS = ("HERMITE", "LAGRANGE", "LINEAR")
#: The interpolation the OEM of a simulation declares, and its degree (degree + 1 states).
INTERPOLATION = "LAGRANGE"
INTERPOLATION_DEGREE = 7
#: Largest interpolation error accepted at the mid-points between states: 1 mm in position,
#: 1 um/s in velocity (the integrator's own noise, rtol 1e-13 of the state, is far below).
INTERPOLATION_TOL_KM = 1e-6
INTERPOLATION_TOL_KM_S = 1e-9


@dataclass(frozen=True, slots=True)
class OemTrajectory:
    """States for an OEM and how well they interpolate.

    Attributes
    ----------
    t_s : (N,) times, s from the epoch, from 0 to the end
        (:func:`tapp.tracking.oem_states.oem_trajectory`), increasing within a segment; the
        time of an impulsive burn ends one segment and starts the next.
    states : (N, 6) km and km/s, Earth-centred, in ``ref_frame``.
    segment : (N,) int, the segment of each state: 0, 1, ... in time order (one per smooth
        arc between burns).
    ref_frame : OEM ``REF_FRAME`` (:data:`REF_FRAMES`).
    min_step_s, max_step_s : shortest and longest spacing of the states within a segment, s.
    error_km, error_km_s : largest interpolation error at the mid-points between states of
        each segment (:data:`INTERPOLATION` of degree :data:`INTERPOLATION_DEGREE`), position
        and velocity.
    events : the integration events of the trajectory.
    """

    t_s: np.ndarray
    states: np.ndarray
    segment: np.ndarray
    ref_frame: str
    min_step_s: float
    max_step_s: float
    error_km: float
    error_km_s: float
    events: Events

    @property
    def spans(self) -> tuple[slice, ...]:
        """The states of each segment, in order."""
        return segment_slices(self.segment)

    @property
    def comments(self) -> tuple[str, ...]:
        """COMMENT lines that say where the states are and how well they interpolate."""
        steps = (f"every {self.max_step_s:g} s" if self.min_step_s == self.max_step_s else
                 f"every {self.max_step_s:g} s, down to {self.min_step_s:g} s where the "
                 "motion is fast")
        n = len(self.spans)
        arcs = ("" if n == 1 else f" in {n} segments, one per arc between burns (a segment "
                "ends with the state before a burn, ignition or cut-off, the next starts at "
                "the same epoch with the state after it)")
        return (f"States from the injection (t = 0) to the end of the simulation{arcs}, "
                f"{steps}.",
                f"{INTERPOLATION.capitalize()} interpolation of degree {INTERPOLATION_DEGREE} "
                f"({INTERPOLATION_DEGREE + 1} states of the segment, the window centred on the "
                "time) reproduces the propagated trajectory at every mid-point between states "
                f"to {self.error_km * 1e6:.2g} mm and {self.error_km_s * 1e6:.2g} mm/s "
                f"(required: {INTERPOLATION_TOL_KM * 1e6:g} mm, "
                f"{INTERPOLATION_TOL_KM_S * 1e6:g} mm/s).")


def segment_slices(segment: np.ndarray) -> tuple[slice, ...]:
    """The runs of equal values of ``segment`` (N,) int, as slices, in order."""
    cuts = [0, *(np.flatnonzero(np.diff(segment)) + 1).tolist(), int(np.size(segment))]
    return tuple(slice(a, b) for a, b in zip(cuts, cuts[1:], strict=False))


def event_comments(epoch: Epoch, events: Events) -> tuple[str, ...]:
    """COMMENT lines of the integration events: their number, then one line each,
    ``EVENT <UTC> <label>`` (the time as the data lines write theirs)."""
    if not len(events):
        return ()
    lines = [f"Integration events ({len(events)}: shadow entries and exits, atmosphere table "
             "heights), where the force model has a kink and the integrator restarted:"]
    lines += [f"EVENT {epoch.iso_after(float(t), EPOCH_DECIMALS)} {label}"
              for t, label in zip(events.t_s, events.labels(), strict=True)]
    return tuple(lines)


def interpolation_window(t_nodes: np.ndarray, t: np.ndarray, n: int) -> np.ndarray:
    """Return the indices (M, n) of the n consecutive nodes whose mean is nearest each time
    (the window centred on it, shifted inwards at the ends, as the ``oem`` package chooses
    it): t_nodes (N,) increasing, t (M,), n <= N."""
    centres = np.convolve(t_nodes, np.full(n, 1.0 / n), mode="valid")  # mean of each window
    above = np.searchsorted(centres, t)  # centres[above - 1] < t <= centres[above]
    lo = np.clip(above - 1, 0, centres.size - 1)
    hi = np.clip(above, 0, centres.size - 1)
    first = np.where(t - centres[lo] <= centres[hi] - t, lo, hi)
    return first[:, None] + np.arange(n)


def lagrange_interpolate(t_nodes, y_nodes, t, degree: int) -> np.ndarray:
    """Return the Lagrange interpolant of degree ``degree`` of (t_nodes, y_nodes) at ``t``.

    At each time the polynomial runs through the degree + 1 nodes of the window whose centre
    is nearest to it (centred on it, shifted inwards at the ends):

    .. math:: y(t) = \\sum_j y_j \\prod_{k \\ne j} \\frac{t - t_k}{t_j - t_k}

    Parameters
    ----------
    t_nodes : (N,) strictly increasing times, s (N > degree).
    y_nodes : (N, m) values at the nodes.
    t : (M,) times to interpolate at, s, within [t_nodes[0], t_nodes[-1]].
    degree : int, >= 1.

    Returns
    -------
    (M, m) interpolated values.
    """
    tn = np.asarray(t_nodes, dtype=float)
    y = np.asarray(y_nodes, dtype=float)
    tq = np.asarray(t, dtype=float)
    n = degree + 1
    idx = interpolation_window(tn, tq, n)  # (M, n)
    tw = tn[idx]
    weights = np.ones(idx.shape)  # weight of node j: prod over k != j of (t - t_k)/(t_j - t_k)
    for k in range(n):
        others = np.arange(n) != k
        weights[:, others] *= ((tq - tw[:, k])[:, None] / (tw[:, others] - tw[:, k:k + 1]))
    return np.einsum("mj,mjc->mc", weights, y[idx])


def format_oem(epoch: Epoch, t_s, states, *, object_name: str, object_id: str,
               ref_frame: str, interpolation: str, interpolation_degree: int,
               originator: str = "TAPP", comments: tuple[str, ...] = (),
               meta_comments: tuple[str, ...] = (), segment=None,
               segment_comments: tuple[tuple[str, ...], ...] = (),
               center_name: str = "EARTH") -> str:
    """Return the text of an OEM 2.0 (KVN) of an inertial trajectory about ``center_name``
    (the Earth unless the scenario integrates about another body).

    Parameters
    ----------
    epoch : Epoch
        UTC of t = 0.
    t_s : array_like, shape (N,)
        Times, s from the epoch, strictly increasing within a segment; a segment starts at or
        after the last time of the one before.
    states : array_like, shape (N, 6)
        Position km and velocity km/s, Earth-centred, in ``ref_frame``.
    object_name, object_id : str
        Spacecraft name and identifier (non-empty).
    ref_frame : str
        ``REF_FRAME`` (CCSDS SANA name: "GCRF", "EME2000", ...).
    interpolation, interpolation_degree : str, int
        ``INTERPOLATION`` (one of :data:`INTERPOLATIONS`) and ``INTERPOLATION_DEGREE``
        (>= 1; Lagrange needs degree + 1 <= the states of each segment).
    originator : str
        Creating agency.
    comments, meta_comments : tuple of str
        COMMENT lines of the header (after ``CCSDS_OEM_VERS``) and of every segment's
        metadata (after ``META_START``).
    segment : array_like of int, shape (N,), optional
        The segment of each state, 0, 1, ... in order (default: one segment).
    segment_comments : tuple of tuple of str
        COMMENT lines of each segment's metadata, after ``meta_comments`` (none when empty).

    Raises
    ------
    InputError
        Mismatched shapes, non-finite values, times not increasing as above, segments not
        numbered 0, 1, ..., empty names or frame, an unknown interpolation or a degree the
        states of a segment cannot carry.
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(states, dtype=float)
    seg = np.zeros(t.shape, dtype=int) if segment is None else np.asarray(segment)
    if t.ndim != 1 or t.size == 0 or x.shape != (t.size, 6) or seg.shape != t.shape:
        raise InputError("OEM", "states", "times (N,), states (N, 6) and segments (N,)",
                         (t.shape, x.shape, seg.shape))
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise InputError("OEM", "states", "finite times and states")
    steps = np.diff(seg)
    if seg[0] != 0 or np.any((steps != 0) & (steps != 1)):
        raise InputError("OEM", "segment", "segments numbered 0, 1, ... in order")
    dt = np.diff(t)
    if np.any((dt <= 0) & (steps == 0)) or np.any((dt < 0) & (steps == 1)):
        raise InputError("OEM", "t_s", "times strictly increasing within a segment, each "
                         "segment starting at or after the end of the one before")
    spans = segment_slices(seg)
    if segment_comments and len(segment_comments) != len(spans):
        raise InputError("OEM", "segment_comments", f"one tuple per segment ({len(spans)})",
                         len(segment_comments))
    for field, value in (("OBJECT_NAME", object_name), ("OBJECT_ID", object_id),
                         ("REF_FRAME", ref_frame)):
        if not value.strip():
            raise InputError("OEM", field, "a non-empty name", value)
    if interpolation not in INTERPOLATIONS:
        raise InputError("OEM", "INTERPOLATION", f"one of {', '.join(INTERPOLATIONS)}",
                         interpolation)
    fewest = min(s.stop - s.start for s in spans)
    if not 1 <= interpolation_degree < fewest:
        raise InputError("OEM", "INTERPOLATION_DEGREE", "a degree from 1 to the number of "
                         f"states of a segment less one ({fewest - 1})", interpolation_degree)
    created = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S")
    lines = ["CCSDS_OEM_VERS = 2.0", *(f"COMMENT {c}" for c in comments),
             f"CREATION_DATE = {created}", f"ORIGINATOR = {originator}", ""]
    for k, span in enumerate(spans):
        own = segment_comments[k] if segment_comments else ()
        lines += ["META_START", *(f"COMMENT {c}" for c in (*meta_comments, *own)),
                  f"OBJECT_NAME = {object_name}",
                  f"OBJECT_ID = {object_id}",
                  f"CENTER_NAME = {center_name}",
                  f"REF_FRAME = {ref_frame}",
                  "TIME_SYSTEM = UTC",
                  f"START_TIME = {epoch.iso_after(float(t[span][0]), EPOCH_DECIMALS)}",
                  f"STOP_TIME = {epoch.iso_after(float(t[span][-1]), EPOCH_DECIMALS)}",
                  f"INTERPOLATION = {interpolation}",
                  f"INTERPOLATION_DEGREE = {interpolation_degree}",
                  "META_STOP", ""]
        for ti, row in zip(t[span], x[span], strict=True):
            lines.append(f"{epoch.iso_after(float(ti), EPOCH_DECIMALS)} " + " ".join(
                [f"{v:.9f}" for v in row[:3]] + [f"{v:.12f}" for v in row[3:]]))
        lines.append("")
    return "\n".join(lines[:-1]) + "\n"


def write_oem(path: Path | str, text: str) -> Path:
    """Write OEM text to ``path`` atomically (temporary file in the same folder, rename)."""
    return atomic_write(path, lambda tmp: tmp.write_text(text))
