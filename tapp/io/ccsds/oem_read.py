"""CCSDS Orbit Ephemeris Messages read: KVN and XML, every segment, and their interpolation.

Layout per CCSDS 502.0-B-2 (Orbit Data Messages, 2009) §5 (KVN) and 505.0-B-1 (XML): a header
(``CCSDS_OEM_VERS``, ``CREATION_DATE``, ``ORIGINATOR``, ``MESSAGE_ID``), then segments, each
a metadata block (``META_START`` .. ``META_STOP``; XML ``<metadata>``) and its data: one line
(``<stateVector>``) per epoch, the epoch then x, y, z (km), x_dot, y_dot, z_dot (km/s) and
optionally three accelerations (km/s², ignored); covariance blocks are skipped. Versions
1.0, 2.0 and 3.0 read alike. Epochs are ``YYYY-MM-DDThh:mm:ss[.d...][Z]`` or day-of-year
``YYYY-DDDThh:mm:ss[.d...]``, in the segment's ``TIME_SYSTEM``; values of ``CENTER_NAME``,
``REF_FRAME``, ``TIME_SYSTEM`` and ``INTERPOLATION`` are read without regard to case
(``Earth``, ``Lagrange``).

This module checks the message itself: every required keyword present and once, numbers and
epochs well formed, epochs strictly increasing within a segment and within its
``START_TIME`` .. ``STOP_TIME``, segments in time order, XML units (when given) km and km/s,
an interpolation it can carry out. A problem is an :class:`~tapp.errors.InputError` naming the
file and ``line N: KEYWORD`` (KVN) or ``segment[i].metadata.KEYWORD``,
``segment[i].stateVector[j].EPOCH`` (XML). What the frame, centre and time system mean for a
scenario is :mod:`tapp.io.trajectory_file`'s business.

Interpolation (:func:`interpolate`): ``LAGRANGE`` of degree d through d + 1 states,
``HERMITE`` of odd degree d through (d + 1) / 2 states with their velocities as derivatives
(the velocity is the polynomial's derivative), ``LINEAR`` (Lagrange of degree 1); the window
is the one whose centre is nearest the time, as the ``oem`` package chooses it. A segment
without ``INTERPOLATION`` is interpolated by :data:`DEFAULT_INTERPOLATION`.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.io.ccsds.oem import INTERPOLATIONS, interpolation_window, lagrange_interpolate
from tapp.io.ccsds.tdm import parse_epoch_jd
from tapp.io.text import finite_number

#: OEM versions read.
VERSIONS = ("1.0", "2.0", "3.0")
#: Metadata keywords every segment must give, and those it may.
REQUIRED_METADATA = ("OBJECT_NAME", "OBJECT_ID", "CENTER_NAME", "REF_FRAME", "TIME_SYSTEM",
                     "START_TIME", "STOP_TIME")
OPTIONAL_METADATA = ("REF_FRAME_EPOCH", "USEABLE_START_TIME", "USEABLE_STOP_TIME",
                     "INTERPOLATION", "INTERPOLATION_DEGREE")
#: Keywords whose values are read without regard to case.
_UPPER = frozenset({"CENTER_NAME", "REF_FRAME", "TIME_SYSTEM", "INTERPOLATION"})
HEADER_KEYWORDS = ("CCSDS_OEM_VERS", "CREATION_DATE", "ORIGINATOR", "MESSAGE_ID")
#: The interpolation of a segment that names none: Hermite of degree 7 (4 states).
DEFAULT_INTERPOLATION = ("HERMITE", 7)
#: Units an XML state vector may declare (CCSDS 505.0-B-1: km, km/s).
_XML_UNITS = {"X": "km", "Y": "km", "Z": "km", "X_DOT": "km/s", "Y_DOT": "km/s",
              "Z_DOT": "km/s"}
_KEY = re.compile(r"^([A-Z][A-Z0-9_]*)\s*=\s*(.*?)\s*$")


@dataclass(frozen=True, slots=True)
class OemSegment:
    """One segment: metadata, and the states with their epochs in its time system.

    Attributes
    ----------
    metadata : keyword -> value (upper case for :data:`_UPPER` keywords), as written.
    fields : keyword -> where it was written (``line 12: REF_FRAME``), for messages; also
        ``"data"`` (where the states start).
    jd_whole, jd_fraction : (N,) epochs as two-part Julian dates in ``TIME_SYSTEM`` (the
        calendar date read as is), days.
    states : (N, 6) km, km/s, relative to ``CENTER_NAME`` in ``REF_FRAME``.
    epoch_fields : (N,) where each epoch was written, for messages.
    """

    metadata: Mapping[str, str]
    fields: Mapping[str, str]
    jd_whole: np.ndarray
    jd_fraction: np.ndarray
    states: np.ndarray
    epoch_fields: tuple[str, ...]

    def date(self, keyword: str) -> tuple[float, float] | None:
        """The (jd_whole, jd_fraction) of a date keyword (``START_TIME``, ...), or None."""
        text = self.metadata.get(keyword)
        return None if text is None else parse_epoch_jd(text)

    @property
    def interpolation(self) -> tuple[str, int]:
        """(method, degree): the segment's, or :data:`DEFAULT_INTERPOLATION`."""
        if "INTERPOLATION" not in self.metadata:
            return DEFAULT_INTERPOLATION
        degree = self.metadata.get("INTERPOLATION_DEGREE")
        method = self.metadata["INTERPOLATION"]
        return method, 1 if method == "LINEAR" else int(degree)


@dataclass(frozen=True, slots=True)
class OemMessage:
    """An OEM: its source, form (``"KVN"`` or ``"XML"``), version, header and segments."""

    source: str
    form: str
    version: str
    header: Mapping[str, str]
    segments: tuple[OemSegment, ...]


def _epoch(source: str, where: str, text: str) -> tuple[float, float]:
    jd = parse_epoch_jd(text.strip())
    if jd is None:
        raise InputError(source, where, "a CCSDS epoch YYYY-MM-DDThh:mm:ss[.d] or "
                         "YYYY-DDDThh:mm:ss[.d] (hh < 24, mm < 60, ss < 60)", text)
    return jd


# --------------------------------------------------------------------------------------------
# KVN
# --------------------------------------------------------------------------------------------


def _kvn(text: str, source: str) -> OemMessage:
    header: dict[str, str] = {}
    header_at: dict[str, int] = {}
    segments: list[OemSegment] = []
    meta: dict[str, str] | None = None
    fields: dict[str, str] = {}
    rows: list[tuple[int, str, list[str]]] = []
    state = "header"  # header -> meta -> data -> (covariance) -> meta ...

    def close() -> None:
        if meta is not None:
            segments.append(_segment(source, meta, fields, rows, f"line {fields['META_START']}"))

    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("COMMENT"):
            continue
        if line == "META_START":
            if state == "meta":
                raise InputError(source, f"line {n}", "META_STOP before the next META_START",
                                 line)
            close()
            meta, fields, rows, state = {}, {"META_START": str(n)}, [], "meta"
            continue
        if state == "meta":
            if line == "META_STOP":
                fields["data"] = f"line {n + 1}"
                state = "data"
                continue
            _meta_line(source, n, line, meta, fields)
            continue
        if line == "COVARIANCE_START" and state == "data":
            state = "covariance"
        elif state == "covariance":
            state = "data" if line == "COVARIANCE_STOP" else state
        elif state == "data":
            rows.append((n, raw, line.split()))
        else:
            match = _KEY.match(line)
            if match is None or match.group(1) not in HEADER_KEYWORDS:
                raise InputError(source, f"line {n}", "a header keyword ("
                                 f"{', '.join(HEADER_KEYWORDS)}), COMMENT or META_START", line)
            header[match.group(1)] = match.group(2)
            header_at[match.group(1)] = n
    if state == "meta":
        raise InputError(source, f"line {fields['META_START']}: META_START",
                         "a metadata block closed by META_STOP")
    if state == "covariance":
        raise InputError(source, "COVARIANCE_START", "a covariance block closed by "
                         "COVARIANCE_STOP")
    close()
    version = header.get("CCSDS_OEM_VERS")
    where = f"line {header_at['CCSDS_OEM_VERS']}: CCSDS_OEM_VERS" if version else \
        "CCSDS_OEM_VERS"
    return _message(source, "KVN", version, where, header, segments)


def _meta_line(source: str, n: int, line: str, meta: dict[str, str],
               fields: dict[str, str]) -> None:
    match = _KEY.match(line)
    known = REQUIRED_METADATA + OPTIONAL_METADATA
    if match is None or match.group(1) not in known:
        raise InputError(source, f"line {n}", f"a metadata keyword ({', '.join(known)}), "
                         "COMMENT or META_STOP", line)
    key, value = match.groups()
    if key in meta:
        raise InputError(source, f"line {n}: {key}", f"{key} once per segment (also on "
                         f"{fields[key].split(':')[0]})", value)
    meta[key] = value.upper() if key in _UPPER else value
    fields[key] = f"line {n}: {key}"


def _segment(source: str, meta: Mapping[str, str], fields: Mapping[str, str],
             rows: list[tuple[int, str, list[str]]], opening: str) -> OemSegment:
    """A KVN segment from its metadata and data lines (line number, text, tokens)."""
    if not rows:
        raise InputError(source, fields.get("data", opening), "at least one state line "
                         "after META_STOP")
    whole, fraction, states, where = [], [], [], []
    for n, raw, tokens in rows:
        if len(tokens) not in (7, 10):
            raise InputError(source, f"line {n}", "an epoch and 6 numbers (x, y, z km, "
                             "x_dot, y_dot, z_dot km/s), optionally 3 accelerations", raw.strip())
        jd = _epoch(source, f"line {n}: epoch", tokens[0])
        whole.append(jd[0])
        fraction.append(jd[1])
        states.append([finite_number(tok, source, f"line {n}: {name}") for name, tok in
                       zip(_XML_UNITS, tokens[1:7], strict=True)])
        where.append(f"line {n}: epoch")
    return _checked(source, meta, fields, opening, np.array(whole), np.array(fraction),
                    np.array(states), tuple(where))


# --------------------------------------------------------------------------------------------
# XML
# --------------------------------------------------------------------------------------------


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _children(node: ET.Element, name: str) -> list[ET.Element]:
    return [child for child in node if _local(child.tag) == name]


def _xml(text: str, source: str) -> OemMessage:
    try:
        root = ET.fromstring(text.lstrip())
    except ET.ParseError as exc:
        raise InputError(source, "XML", "a well-formed XML document", str(exc)) from None
    if _local(root.tag) != "oem":
        raise InputError(source, "XML", "an <oem> root element", _local(root.tag))
    header = {}
    for head in _children(root, "header"):
        header = {_local(c.tag): (c.text or "").strip() for c in head
                  if _local(c.tag) in HEADER_KEYWORDS}
    segments = []
    for body in _children(root, "body"):
        for i, seg in enumerate(_children(body, "segment")):
            segments.append(_xml_segment(source, seg, f"segment[{i}]"))
    return _message(source, "XML", root.get("version"), "oem.version", header, segments)


def _xml_segment(source: str, seg: ET.Element, where: str) -> OemSegment:
    meta: dict[str, str] = {}
    fields: dict[str, str] = {"data": f"{where}.data"}
    for block in _children(seg, "metadata"):
        for child in block:
            key = _local(child.tag)
            if key == "COMMENT":
                continue
            if key not in REQUIRED_METADATA + OPTIONAL_METADATA:
                raise InputError(source, f"{where}.metadata.{key}", "a metadata element ("
                                 f"{', '.join(REQUIRED_METADATA + OPTIONAL_METADATA)})")
            value = (child.text or "").strip()
            meta[key] = value.upper() if key in _UPPER else value
            fields[key] = f"{where}.metadata.{key}"
    vectors = [v for data in _children(seg, "data") for v in _children(data, "stateVector")]
    if not vectors:
        raise InputError(source, f"{where}.data", "at least one <stateVector>")
    whole, fraction, states, epochs = [], [], [], []
    for j, vec in enumerate(vectors):
        at = f"{where}.stateVector[{j}]"
        values = {_local(c.tag): c for c in vec}
        for key in ("EPOCH", *_XML_UNITS):
            if key not in values:
                raise InputError(source, f"{at}.{key}", f"<{key}> in every <stateVector>")
        jd = _epoch(source, f"{at}.EPOCH", values["EPOCH"].text or "")
        whole.append(jd[0])
        fraction.append(jd[1])
        row = []
        for key, unit in _XML_UNITS.items():
            given = values[key].get("units")
            if given is not None and given.strip().lower() != unit:
                raise InputError(source, f"{at}.{key}", f"units=\"{unit}\" (or none)", given)
            row.append(finite_number(values[key].text or "", source, f"{at}.{key}"))
        states.append(row)
        epochs.append(f"{at}.EPOCH")
    return _checked(source, meta, fields, where, np.array(whole), np.array(fraction),
                    np.array(states), tuple(epochs))


# --------------------------------------------------------------------------------------------
# Both forms: the checks
# --------------------------------------------------------------------------------------------


def _checked(source: str, meta: Mapping[str, str], fields: Mapping[str, str], opening: str,
             whole: np.ndarray, fraction: np.ndarray, states: np.ndarray,
             epoch_fields: tuple[str, ...]) -> OemSegment:
    """The segment, once its metadata is complete and its epochs increase within its span."""
    for key in REQUIRED_METADATA:
        if not meta.get(key):
            raise InputError(source, f"{opening}: {key}", f"{key} in every segment's metadata")
    seg = OemSegment(meta, fields, whole, fraction, states, epoch_fields)
    for key in ("START_TIME", "STOP_TIME", "USEABLE_START_TIME", "USEABLE_STOP_TIME"):
        if key in meta:
            _epoch(source, fields[key], meta[key])
    _check_interpolation(source, seg, opening)
    days = (whole - whole[0]) + (fraction - fraction[0])
    step = np.diff(days)
    if np.any(step <= 0):
        k = int(np.argmax(step <= 0)) + 1
        raise InputError(source, epoch_fields[k], "epochs strictly increasing within a segment "
                         f"(after {_text(whole[k - 1], fraction[k - 1])})",
                         _text(whole[k], fraction[k]))
    start, stop = seg.date("START_TIME"), seg.date("STOP_TIME")
    for k, (bound, key, sign) in enumerate(((start, "START_TIME", 1.0),
                                            (stop, "STOP_TIME", -1.0))):
        i = 0 if k == 0 else -1
        if sign * ((whole[i] - bound[0]) + (fraction[i] - bound[1])) < -_EPOCH_SLACK_d:
            raise InputError(source, epoch_fields[i], f"epochs within {key} = {meta[key]}",
                             _text(whole[i], fraction[i]))
    return seg


#: Epochs may lie this far outside START_TIME .. STOP_TIME (rounding of the dates), days (1 µs).
_EPOCH_SLACK_d = 1e-6 / 86400.0


def _text(whole: float, fraction: float) -> str:
    return Epoch(float(whole), float(fraction)).iso(6)


def _check_interpolation(source: str, seg: OemSegment, opening: str) -> None:
    meta = seg.metadata
    if "INTERPOLATION" not in meta:
        return
    where = seg.fields["INTERPOLATION"]
    method = meta["INTERPOLATION"]
    if method not in INTERPOLATIONS:
        raise InputError(source, where, f"one of {', '.join(INTERPOLATIONS)}", method)
    if method == "LINEAR":
        return
    text = meta.get("INTERPOLATION_DEGREE")
    if text is None:
        raise InputError(source, f"{opening}: INTERPOLATION_DEGREE",
                         f"INTERPOLATION_DEGREE with INTERPOLATION = {method}")
    where = seg.fields["INTERPOLATION_DEGREE"]
    if not text.isdigit() or int(text) < 1:
        raise InputError(source, where, "an integer >= 1", text)
    degree = int(text)
    if method == "HERMITE" and degree % 2 == 0:
        raise InputError(source, where, "an odd degree for HERMITE (2n - 1 through n states)",
                         degree)
    needed = degree + 1 if method == "LAGRANGE" else (degree + 1) // 2
    if needed > seg.states.shape[0]:
        raise InputError(source, where, f"a degree the segment's {seg.states.shape[0]} states "
                         f"can carry ({method} of degree {degree} needs {needed})", degree)


def _message(source: str, form: str, version: str | None, where: str, header: dict,
             segments: list[OemSegment]) -> OemMessage:
    if version not in VERSIONS:
        raise InputError(source, where, f"an OEM version {', '.join(VERSIONS)}", version)
    if not segments:
        raise InputError(source, "META_START" if form == "KVN" else "segment",
                         "at least one segment")
    for before, seg in zip(segments, segments[1:], strict=False):
        start, stop = seg.date("START_TIME"), before.date("STOP_TIME")
        if (start[0] - stop[0]) + (start[1] - stop[1]) < -_EPOCH_SLACK_d:
            raise InputError(source, seg.fields["START_TIME"], "segments in time order, each "
                             f"starting at or after the STOP_TIME of the one before "
                             f"({before.metadata['STOP_TIME']})", seg.metadata["START_TIME"])
    return OemMessage(source, form, version, header, tuple(segments))


def parse_oem(text: str, source: str = "OEM") -> OemMessage:
    """Parse the text of an OEM, KVN or XML (told apart by a leading ``<``).

    Raises
    ------
    InputError
        Naming ``source`` and where in it (module docstring).
    """
    if text.lstrip().startswith("<"):
        return _xml(text, source)
    return _kvn(text, source)


def read_oem(path: Path | str, source: str | None = None) -> OemMessage:
    """Read and parse the OEM file at ``path`` (errors name ``source``, default the path).

    Raises
    ------
    InputError
        A file that cannot be read as UTF-8 text, or any problem :func:`parse_oem` finds.
    """
    source = str(path) if source is None else source
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(source, "file", "an OEM (UTF-8 text)",
                         f"a byte {exc.object[exc.start]:#04x} at offset {exc.start}") from None
    return parse_oem(text, source)


# --------------------------------------------------------------------------------------------
# Interpolation
# --------------------------------------------------------------------------------------------


def hermite_interpolate(t_nodes, states, t, degree: int) -> np.ndarray:
    """Return states (M, 6) at ``t`` by Hermite interpolation of odd ``degree`` of the
    positions, with the velocities as their derivatives; the velocity is the derivative of the
    position polynomial.

    Through n = (degree + 1) / 2 nodes t_j (the window nearest each time):

    .. math::
        H(t) = \\sum_j \\big[(1 - 2 \\ell_j'(t_j)(t - t_j))\\, r_j + (t - t_j)\\, v_j\\big]
               \\ell_j(t)^2

    with ℓ_j the Lagrange basis polynomials of the window (Hildebrand, *Introduction to
    Numerical Analysis*, 2nd ed., §8.2).

    Parameters
    ----------
    t_nodes : (N,) strictly increasing times, s.
    states : (N, 6) positions and velocities at the nodes.
    t : (M,) times within [t_nodes[0], t_nodes[-1]], s.
    degree : odd, with (degree + 1) / 2 <= N.
    """
    tn = np.asarray(t_nodes, dtype=float)
    x = np.asarray(states, dtype=float)
    tq = np.atleast_1d(np.asarray(t, dtype=float))
    idx = interpolation_window(tn, tq, (degree + 1) // 2)
    tw = tn[idx]  # (M, n)
    d = tq[:, None] - tw  # t - t_j
    n = idx.shape[1]
    other = ~np.eye(n, dtype=bool)  # [j, k]: k != j
    gap = np.where(other, tw[:, :, None] - tw[:, None, :], 1.0)  # t_j - t_k (1 on the diagonal)
    ratio = np.where(other, d[:, None, :] / gap, 1.0)  # (t - t_k) / (t_j - t_k)
    ell = np.prod(ratio, axis=2)  # ℓ_j(t)
    slope = np.sum(np.where(other, 1.0 / gap, 0.0), axis=2)  # ℓ_j'(t_j)
    dell = np.zeros_like(ell)  # ℓ_j'(t): one factor differentiated at a time (t may be a node)
    for k in range(n):
        rest = ratio.copy()
        rest[:, :, k] = 1.0
        dell += np.where(other[:, k], np.prod(rest, axis=2) / gap[:, :, k], 0.0)
    a = (1.0 - 2.0 * slope * d) * ell**2
    b = d * ell**2
    da = -2.0 * slope * ell**2 + 2.0 * (1.0 - 2.0 * slope * d) * ell * dell
    db = ell**2 + 2.0 * d * ell * dell
    r, v = x[idx, :3], x[idx, 3:]
    pos = np.einsum("mj,mjc->mc", a, r) + np.einsum("mj,mjc->mc", b, v)
    vel = np.einsum("mj,mjc->mc", da, r) + np.einsum("mj,mjc->mc", db, v)
    return np.concatenate([pos, vel], axis=1)


def interpolate(method: str, degree: int, t_nodes, states, t) -> np.ndarray:
    """Return states (M, 6) at ``t`` by a segment's interpolation (module docstring).

    ``method`` is one of :data:`tapp.io.ccsds.oem.INTERPOLATIONS`; the nodes must number at
    least what the degree needs (checked when the segment was read).
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if method == "HERMITE":
        return hermite_interpolate(t_nodes, states, t, degree)
    return lagrange_interpolate(t_nodes, states, t, 1 if method == "LINEAR" else degree)
