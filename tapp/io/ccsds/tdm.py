"""CCSDS Tracking Data Message (TDM) in KVN: parse, write, and the observables tapp uses.

Layout per CCSDS 503.0-B-2 (Tracking Data Message, Blue Book, Issue 2, 2020; version 1.0
files of 503.0-B-1, 2007, read the same): a header (``CCSDS_TDM_VERS``, ``COMMENT``,
``CREATION_DATE``, ``ORIGINATOR``, ``MESSAGE_ID``), then segments, each a metadata block
``META_START`` .. ``META_STOP`` and a data block ``DATA_START`` .. ``DATA_STOP`` of lines
``KEYWORD = epoch value``. Epochs are ``YYYY-MM-DDThh:mm:ss[.d...][Z]`` or day-of-year
``YYYY-DDDThh:mm:ss[.d...][Z]``. Blank lines, tabs and spaces around ``=`` are free.

Two layers:

1. :func:`parse_tdm` reads any KVN TDM into :class:`Tdm` (every standard keyword of the
   header, metadata and data blocks; an unknown keyword, a keyword in the wrong block, a
   malformed epoch or number is an :class:`~tapp.errors.InputError` naming the line).
   :func:`format_tdm` writes one.
2. :func:`read_tracks` turns a :class:`Tdm` into per-station :class:`StationTrack` of the
   observables tapp models, and :func:`tdm_from_tracks` does the reverse:

   =======================  =====================  ===================================
   tapp kind                TDM keyword            unit in the TDM (tapp)
   =======================  =====================  ===================================
   ``range``                RANGE                  km, RANGE_UNITS = km (km)
   ``range_rate``           DOPPLER_INSTANTANEOUS  km/s, positive receding (km/s)
   ``azimuth``              ANGLE_1                deg, ANGLE_TYPE = AZEL (rad)
   ``elevation``            ANGLE_2                deg, ANGLE_TYPE = AZEL (rad)
   =======================  =====================  ===================================

   Epochs become seconds from a reference epoch (the scenario's t = 0, to 1 ns);
   participants are the station (a name the scenario knows) and the spacecraft; the values
   are taken as instantaneous observables at the receive time (tapp's measurement model of
   the study has no light time). What tapp cannot use is refused with one line naming the
   keyword, its block (segment N, META or DATA) and its line, never turned into a wrong
   number:

   - data keywords other than the four above: DOPPLER_INTEGRATED (a count over an
     interval), frequencies, phase counts, DOR, VLBI_DELAY, media and weather data, ...;
   - TIME_SYSTEM other than UTC; TIMETAG_REF = TRANSMIT; MODE other than SEQUENTIAL and the
     single-difference PATH_1/PATH_2; a PATH that is not station-spacecraft-station
     (two-way) or spacecraft-station (one-way down);
   - with RANGE: RANGE_UNITS other than km (seconds or range units), a non-zero
     RANGE_MODULUS, non-zero TRANSMIT_DELAY_n/RECEIVE_DELAY_n (hardware delays to calibrate);
   - with angles: ANGLE_TYPE other than AZEL;
   - CORRECTION_* values other than 0 unless CORRECTIONS_APPLIED = YES.

   Within a segment the data keywords are checked first, then the metadata in file order.
   Informational keywords (START_TIME/STOP_TIME, which also give the data span, TRACK_ID,
   DATA_TYPES, DATA_QUALITY, bands, turnaround ratio, integration interval and reference,
   FREQ_OFFSET, RANGE_MODE, REFERENCE_FRAME, INTERPOLATION*, DOPPLER_COUNT_*,
   EPHEMERIS_NAME_n) are accepted and ignored.

The XML form of the TDM is not read: the one maintained Python library that reads both
(``ccsds-ndm``) is GPL-3.0 (tapp is MIT), parsed a 40,000-record file in 17 s and accepted
an unknown metadata keyword without a word; the KVN grammar is small enough to read here.
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError
from tapp.frames.time import Epoch, calendar_to_jd

#: TDM versions read (1.0: CCSDS 503.0-B-1; 2.0: 503.0-B-2) and the one written.
VERSIONS = ("1.0", "2.0")
VERSION_WRITTEN = "2.0"
#: Digits of the seconds of written epochs (1 ns).
EPOCH_DECIMALS = 9

HEADER_KEYWORDS = frozenset({"CCSDS_TDM_VERS", "CREATION_DATE", "ORIGINATOR", "MESSAGE_ID"})
METADATA_KEYWORDS = frozenset({
    "TRACK_ID", "DATA_TYPES", "TIME_SYSTEM", "START_TIME", "STOP_TIME",
    *(f"PARTICIPANT_{n}" for n in range(1, 6)), "MODE", "PATH", "PATH_1", "PATH_2",
    *(f"EPHEMERIS_NAME_{n}" for n in range(1, 6)), "TRANSMIT_BAND", "RECEIVE_BAND",
    "TURNAROUND_NUMERATOR", "TURNAROUND_DENOMINATOR", "TIMETAG_REF", "INTEGRATION_INTERVAL",
    "INTEGRATION_REF", "FREQ_OFFSET", "RANGE_MODE", "RANGE_MODULUS", "RANGE_UNITS",
    "ANGLE_TYPE", "REFERENCE_FRAME", "INTERPOLATION", "INTERPOLATION_DEGREE",
    "DOPPLER_COUNT_BIAS", "DOPPLER_COUNT_SCALE", "DOPPLER_COUNT_ROLLOVER",
    *(f"TRANSMIT_DELAY_{n}" for n in range(1, 6)), *(f"RECEIVE_DELAY_{n}" for n in range(1, 6)),
    "DATA_QUALITY", "CORRECTION_ANGLE_1", "CORRECTION_ANGLE_2", "CORRECTION_DOPPLER",
    "CORRECTION_MAG", "CORRECTION_RANGE", "CORRECTION_RCS", "CORRECTION_RECEIVE",
    "CORRECTION_TRANSMIT", "CORRECTION_ABERRATION_YEARLY", "CORRECTION_ABERRATION_DIURNAL",
    "CORRECTIONS_APPLIED"})
DATA_KEYWORDS = frozenset({
    "ANGLE_1", "ANGLE_2", "CARRIER_POWER", "CLOCK_BIAS", "CLOCK_DRIFT", "DOPPLER_COUNT",
    "DOPPLER_INSTANTANEOUS", "DOPPLER_INTEGRATED", "DOR", "MAG", "PC_N0", "PR_N0", "PRESSURE",
    "RANGE", "RCS", "RECEIVE_FREQ", *(f"RECEIVE_FREQ_{n}" for n in range(1, 6)),
    *(f"RECEIVE_PHASE_CT_{n}" for n in range(1, 6)), "RHUMIDITY", "STEC", "TEMPERATURE",
    *(f"TRANSMIT_FREQ_{n}" for n in range(1, 6)),
    *(f"TRANSMIT_FREQ_RATE_{n}" for n in range(1, 6)),
    *(f"TRANSMIT_PHASE_CT_{n}" for n in range(1, 6)), "TROPO_DRY", "TROPO_WET",
    "VLBI_DELAY"})

#: The TDM keyword of each tapp observable kind, in tapp's kind order.
KEYWORD_OF_KIND = {"range": "RANGE", "range_rate": "DOPPLER_INSTANTANEOUS",
                   "azimuth": "ANGLE_1", "elevation": "ANGLE_2"}
KIND_OF_KEYWORD = {v: k for k, v in KEYWORD_OF_KIND.items()}
_USED = ", ".join(f"{k} ({'km' if k == 'RANGE' else 'km/s' if k.startswith('D') else 'deg'})"
                  for k in KEYWORD_OF_KIND.values())
_WHY_NOT = {
    "DOPPLER_INTEGRATED": "integrated Doppler (a range difference over the integration "
                          "interval) is not modelled, only instantaneous range-rate",
    "DOPPLER_COUNT": "Doppler counts are not modelled",
    "CLOCK_BIAS": "clock data are not modelled", "CLOCK_DRIFT": "clock data are not modelled",
    "DOR": "differenced one-way range is not modelled",
    "VLBI_DELAY": "VLBI delays are not modelled",
}
_CORRECTIONS = ("CORRECTION_ANGLE_1", "CORRECTION_ANGLE_2", "CORRECTION_DOPPLER",
                "CORRECTION_MAG", "CORRECTION_RANGE", "CORRECTION_RCS", "CORRECTION_RECEIVE",
                "CORRECTION_TRANSMIT", "CORRECTION_ABERRATION_YEARLY",
                "CORRECTION_ABERRATION_DIURNAL")

_EPOCH = re.compile(r"^(\d{4})-(?:(\d{2})-(\d{2})|(\d{3}))T(\d{2}):(\d{2}):(\d{2}(?:\.\d*)?)Z?$")
_KEY = re.compile(r"^([A-Z][A-Z0-9_]*)\s*=\s*(.*?)\s*$")


@dataclass(frozen=True, slots=True)
class KeyValue:
    """One ``KEYWORD = value`` line of a header or metadata block (``line`` 1-based)."""

    keyword: str
    value: str
    line: int


@dataclass(frozen=True, slots=True, eq=False)
class TdmSegment:
    """One metadata block and its data block.

    Attributes
    ----------
    metadata : the ``KEYWORD = value`` lines of the metadata block, in file order.
    comments : COMMENT texts of the metadata and data blocks.
    keyword : (N,) data keyword of each record, file order.
    jd_whole, jd_fraction : (N,) epoch of each record, Julian date split as in
        :class:`tapp.frames.time.Epoch` (in the segment's TIME_SYSTEM).
    value : (N,) value of each record, in the keyword's TDM unit.
    line : (N,) line of each record.
    meta_line, data_line : lines of META_START and DATA_START.
    """

    metadata: tuple[KeyValue, ...]
    comments: tuple[str, ...]
    keyword: np.ndarray
    jd_whole: np.ndarray
    jd_fraction: np.ndarray
    value: np.ndarray
    line: np.ndarray
    meta_line: int
    data_line: int

    def meta(self, keyword: str) -> KeyValue | None:
        """Return the metadata line of ``keyword``, or None."""
        return next((kv for kv in self.metadata if kv.keyword == keyword), None)

    def counts(self) -> dict[str, int]:
        """Return the number of records per data keyword, in order of first appearance."""
        out: dict[str, int] = {}
        for k in self.keyword.tolist():
            out[k] = out.get(k, 0) + 1
        return out


@dataclass(frozen=True, slots=True)
class Tdm:
    """A parsed TDM: version, header lines, segments, and the file it came from."""

    version: str
    header: tuple[KeyValue, ...]
    comments: tuple[str, ...]
    segments: tuple[TdmSegment, ...]
    source: str = "TDM"


@dataclass(frozen=True, slots=True, eq=False)
class StationTrack:
    """The observations of one station in one segment, in tapp's kinds and units.

    ``kinds`` (k,) tapp observable kinds; ``t_s`` (n,) receive times, s from the reference
    epoch, non-decreasing; ``values`` (n, k) km, km/s, rad; ``span_end_s`` the end of the
    time span the segment declares (STOP_TIME), s from the reference epoch, or None;
    ``path`` the TDM PATH (``"1,2,1"``: participant 1 the station; ``"2,1"`` one-way down);
    ``comments`` written before the segment's metadata.
    """

    station: str
    spacecraft: str
    kinds: tuple[str, ...]
    t_s: np.ndarray
    values: np.ndarray
    span_end_s: float | None = None
    path: str = "1,2,1"
    comments: tuple[str, ...] = field(default=())


# --------------------------------------------------------------------------------------------
# Layer 1: KVN syntax
# --------------------------------------------------------------------------------------------


def parse_epoch_jd(text: str) -> tuple[float, float] | None:
    """Return (jd_whole, jd_fraction) of a TDM epoch, calendar or day-of-year form, or None
    when the text is not such an epoch (fields out of range included)."""
    m = _EPOCH.match(text)
    if m is None:
        return None
    year = int(m.group(1))
    hour, minute, second = int(m.group(5)), int(m.group(6)), float(m.group(7))
    if hour > 23 or minute > 59 or second >= 60.0:
        return None
    if m.group(4) is not None:
        doy = int(m.group(4))
        leap = year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)
        if not 1 <= doy <= (366 if leap else 365):
            return None
        whole, _ = calendar_to_jd(year, 1, 1)
        whole += doy - 1
    else:
        month, day = int(m.group(2)), int(m.group(3))
        if not 1 <= month <= 12 or not 1 <= day <= 31:
            return None
        whole, _ = calendar_to_jd(year, month, day)
        if jd_to_date(whole) != (year, month, day):  # 31 April, 29 February 2026, ...
            return None
    return whole, (3600.0 * hour + 60.0 * minute + second) / SECONDS_PER_DAY


def jd_to_date(jd_whole: float) -> tuple[int, int, int]:
    """Return (year, month, day) of the 0h Julian date ``jd_whole``."""
    return Epoch(jd_whole, 0.0).calendar()[:3]


def _fail(source: str, line: int, what: str, expected: str, got: object = None) -> InputError:
    return InputError(source, f"line {line}: {what}" if what else f"line {line}", expected, got)


def parse_tdm(text: str, source: str = "TDM") -> Tdm:
    """Parse the KVN text of a TDM.

    Raises
    ------
    InputError
        ``source: line N: ...`` for a line out of place, an unknown keyword or a keyword in the
        wrong block, a malformed epoch or value, a missing header keyword, an unsupported
        version, or an XML file.
    """
    lines = text.splitlines()
    first = next((s.strip() for s in lines if s.strip()), "")
    if first.startswith("<"):
        raise InputError(source, "format", "the KVN form of a TDM (the XML form is not read)",
                         first[:40])
    header: list[KeyValue] = []
    head_comments: list[str] = []
    segments: list[TdmSegment] = []
    state = "header"
    meta: list[KeyValue] = []
    comments: list[str] = []
    rec_key: list[str] = []
    rec_whole: list[float] = []
    rec_frac: list[float] = []
    rec_val: list[float] = []
    rec_line: list[int] = []
    meta_line = data_line = 0
    for n, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s:
            continue
        if s == "META_START":
            if state not in ("header", "between"):
                raise _fail(source, n, "META_START", f"it after a header or DATA_STOP (in "
                            f"{state} block)")
            if state == "header":
                _check_header(header, source, n)
            state, meta, comments, meta_line = "meta", [], [], n
            rec_key, rec_whole, rec_frac, rec_val, rec_line = [], [], [], [], []
            continue
        if s == "META_STOP":
            if state != "meta":
                raise _fail(source, n, "META_STOP", "it after META_START")
            state = "after_meta"
            continue
        if s == "DATA_START":
            if state != "after_meta":
                raise _fail(source, n, "DATA_START", "it after META_STOP")
            state, data_line = "data", n
            continue
        if s == "DATA_STOP":
            if state != "data":
                raise _fail(source, n, "DATA_STOP", "it after DATA_START")
            segments.append(TdmSegment(tuple(meta), tuple(comments), np.array(rec_key, str),
                                       np.array(rec_whole), np.array(rec_frac),
                                       np.array(rec_val), np.array(rec_line, int), meta_line,
                                       data_line))
            state = "between"
            continue
        if s.startswith("COMMENT"):
            if s[7:8] not in ("", " ", "\t"):
                raise _fail(source, n, s.split()[0], "a TDM keyword")
            text_ = s[7:].strip()
            if state == "header":
                head_comments.append(text_)
            elif state in ("meta", "data"):
                comments.append(text_)
            else:
                raise _fail(source, n, "COMMENT", "a comment inside the header, a metadata "
                            "or a data block (it is between blocks)")
            continue
        m = _KEY.match(s)
        if m is None:
            raise _fail(source, n, "", "KEYWORD = value", s[:60])
        key, value = m.group(1), m.group(2)
        if state == "header":
            if key not in HEADER_KEYWORDS:
                raise _fail(source, n, key, "a header keyword (" + ", ".join(
                    sorted(HEADER_KEYWORDS)) + ")" + _elsewhere(key))
            header.append(KeyValue(key, value, n))
        elif state == "meta":
            if key not in METADATA_KEYWORDS:
                raise _fail(source, n, key, "a TDM metadata keyword" + _elsewhere(key))
            meta.append(KeyValue(key, value, n))
        elif state == "data":
            if key not in DATA_KEYWORDS:
                raise _fail(source, n, key, "a TDM data keyword" + _elsewhere(key))
            parts = value.split()
            if len(parts) != 2:
                raise _fail(source, n, key, "'epoch value'", value)
            jd = parse_epoch_jd(parts[0])
            if jd is None:
                raise _fail(source, n, key, "an epoch YYYY-MM-DDThh:mm:ss[.d] or "
                            "YYYY-DDDThh:mm:ss[.d]", parts[0])
            try:
                v = float(parts[1])
            except ValueError:
                raise _fail(source, n, key, "a number", parts[1]) from None
            if not math.isfinite(v):
                raise _fail(source, n, key, "a finite number", parts[1])
            rec_key.append(key)
            rec_whole.append(jd[0])
            rec_frac.append(jd[1])
            rec_val.append(v)
            rec_line.append(n)
        else:
            raise _fail(source, n, key, "a line inside a metadata or data block (it is "
                        "between blocks)")
    if state == "header":
        _check_header(header, source, len(lines))
        raise InputError(source, "segments", "at least one META_START .. DATA_STOP segment")
    if state != "between":
        raise InputError(source, f"line {len(lines)}", "the last block closed (META_STOP or "
                         "DATA_STOP missing)")
    version = next(kv.value for kv in header if kv.keyword == "CCSDS_TDM_VERS")
    return Tdm(version, tuple(header), tuple(head_comments), tuple(segments), source)


def _elsewhere(key: str) -> str:
    for name, block in ((HEADER_KEYWORDS, "header"), (METADATA_KEYWORDS, "metadata block"),
                        (DATA_KEYWORDS, "data block")):
        if key in name:
            return f" ({key} belongs in the {block})"
    return f" ({key} is not a TDM keyword)"


def _check_header(header: list[KeyValue], source: str, line: int) -> None:
    keys = [kv.keyword for kv in header]
    if not keys or keys[0] != "CCSDS_TDM_VERS":
        raise InputError(source, "line 1", "CCSDS_TDM_VERS = 1.0 or 2.0 first (a TDM)",
                         keys[0] if keys else None)
    version = header[0].value
    if version not in VERSIONS:
        raise _fail(source, header[0].line, "CCSDS_TDM_VERS", f"one of {', '.join(VERSIONS)}",
                    version)
    for required in ("CREATION_DATE", "ORIGINATOR"):
        if required not in keys:
            raise InputError(source, "header", f"{required} before META_START (line {line})")


def format_tdm(tdm: Tdm) -> str:
    """Return the KVN text of ``tdm`` (records in their order; epochs to 1 ns)."""
    out = [f"{kv.keyword} = {kv.value}" for kv in tdm.header[:1]]
    out += [f"COMMENT {c}" for c in tdm.comments]
    out += [f"{kv.keyword} = {kv.value}" for kv in tdm.header[1:]]
    for seg in tdm.segments:
        out += ["", "META_START"]
        out += [f"COMMENT {c}" for c in seg.comments]
        out += [f"{kv.keyword} = {kv.value}" for kv in seg.metadata]
        out += ["META_STOP", "", "DATA_START"]
        out += [f"{k} = {_iso(w, f)} {repr(float(v))}" for k, w, f, v in
                zip(seg.keyword.tolist(), seg.jd_whole.tolist(), seg.jd_fraction.tolist(),
                    seg.value.tolist(), strict=True)]
        out += ["DATA_STOP"]
    return "\n".join(out) + "\n"


def _iso(jd_whole: float, jd_fraction: float) -> str:
    return Epoch(jd_whole, jd_fraction).iso(EPOCH_DECIMALS)


# --------------------------------------------------------------------------------------------
# Layer 2: tapp's observables
# --------------------------------------------------------------------------------------------


def _where(i: int, block: str, line: int) -> str:
    return f"segment {i} {block}, line {line}"


def _refuse(tdm: Tdm, kv_key: str, where: str, expected: str, got: object = None
            ) -> InputError:
    return InputError(tdm.source, f"{kv_key} ({where})", expected, got)


def _number(tdm: Tdm, kv: KeyValue, where: str) -> float:
    try:
        return float(kv.value)
    except ValueError:
        raise _refuse(tdm, kv.keyword, where, "a number", kv.value) from None


def _check_segment(tdm: Tdm, i: int, seg: TdmSegment) -> None:
    """Refuse what tapp cannot use in segment ``i`` (1-based): data keywords, then metadata."""
    used = set()
    for key, line in zip(seg.keyword.tolist(), seg.line.tolist(), strict=True):
        if key not in KIND_OF_KEYWORD:
            why = _WHY_NOT.get(key) or ("frequencies are not modelled" if "FREQ" in key else
                                        "phase counts are not modelled" if "PHASE" in key else
                                        "not an observable tapp models")
            raise _refuse(tdm, key, _where(i, "DATA", line), f"one of {_USED}: {why}")
        used.add(key)
    has_range = "RANGE" in used
    has_angles = bool(used & {"ANGLE_1", "ANGLE_2"})
    applied = (seg.meta("CORRECTIONS_APPLIED") or KeyValue("", "NO", 0)).value == "YES"
    for kv in seg.metadata:
        where = _where(i, "META", kv.line)
        k, v = kv.keyword, kv.value
        if k == "TIME_SYSTEM" and v != "UTC":
            raise _refuse(tdm, k, where, "UTC (other time scales are not converted)", v)
        if k == "TIMETAG_REF" and v != "RECEIVE":
            raise _refuse(tdm, k, where, "RECEIVE (tapp's observations are tagged at "
                          "reception)", v)
        if k == "MODE" and v != "SEQUENTIAL":
            raise _refuse(tdm, k, where, "SEQUENTIAL (single differences are not modelled)",
                          v)
        if k in ("PATH_1", "PATH_2"):
            raise _refuse(tdm, k, where, "PATH (single differences are not modelled)", v)
        if has_range and k == "RANGE_UNITS" and v != "km":
            raise _refuse(tdm, k, where, "km (range in seconds or range units, with its "
                          "modulus, is not converted)", v)
        if has_range and k == "RANGE_MODULUS" and _number(tdm, kv, where) != 0:
            raise _refuse(tdm, k, where, "0 (an ambiguous range modulo a modulus is not "
                          "resolved)", v)
        if has_range and k.startswith(("TRANSMIT_DELAY_", "RECEIVE_DELAY_")) and \
                _number(tdm, kv, where) != 0:
            raise _refuse(tdm, k, where, "0 (hardware delays are not calibrated out of the "
                          "range)", v)
        if has_angles and k == "ANGLE_TYPE" and v != "AZEL":
            raise _refuse(tdm, k, where, "AZEL (azimuth, elevation; other angle types are "
                          "not modelled)", v)
        if k in _CORRECTIONS and not applied and _number(tdm, kv, where) != 0:
            raise _refuse(tdm, k, where, "0, or CORRECTIONS_APPLIED = YES (corrections are "
                          "not applied by tapp)", v)
        if k == "CORRECTIONS_APPLIED" and v not in ("YES", "NO"):
            raise _refuse(tdm, k, where, "YES or NO", v)
        if k in ("START_TIME", "STOP_TIME") and parse_epoch_jd(v) is None:
            raise _refuse(tdm, k, where, "an epoch YYYY-MM-DDThh:mm:ss[.d]", v)


def _participants(tdm: Tdm, i: int, seg: TdmSegment, stations: Collection[str]
                  ) -> tuple[str, str, str]:
    """Return (station, spacecraft, path) of segment ``i``; refuse any other geometry."""
    names = {int(kv.keyword[-1]): kv.value for kv in seg.metadata
             if kv.keyword.startswith("PARTICIPANT_")}
    at = _where(i, "META", seg.meta_line)
    ground = [n for n, name in names.items() if name in stations]
    if len(ground) != 1:
        known = ", ".join(sorted(stations)) or "none"
        raise _refuse(tdm, "PARTICIPANT_n", at, f"exactly one station of the scenario among "
                      f"the participants (stations: {known})", ", ".join(names.values()))
    other = [n for n in names if n not in ground]
    if len(other) != 1:
        raise _refuse(tdm, "PARTICIPANT_n", at, "one station and one spacecraft",
                      ", ".join(names.values()))
    s, c = ground[0], other[0]
    path = seg.meta("PATH")
    text = "" if path is None else path.value.replace(" ", "")
    if text not in (f"{s},{c},{s}", f"{c},{s}"):
        raise _refuse(tdm, "PATH", _where(i, "META", path.line if path else seg.meta_line),
                      f"{s},{c},{s} (two-way) or {c},{s} (one-way down) between the station "
                      f"{names[s]} and the spacecraft {names[c]}", text or None)
    return names[s], names[c], text


def _seconds(jd_whole: np.ndarray, jd_fraction: np.ndarray, epoch: Epoch) -> np.ndarray:
    """Seconds from ``epoch``, resolved to 1 ns (the resolution of written epochs: a time
    written and read back is the same float)."""
    t = ((np.asarray(jd_whole) - epoch.jd_whole) + (np.asarray(jd_fraction)
                                                     - epoch.jd_fraction)) * SECONDS_PER_DAY
    return np.round(t * 1e9) / 1e9


def read_tracks(tdm: Tdm, epoch: Epoch, stations: Collection[str]) -> list[StationTrack]:
    """Return the observations of each segment of ``tdm`` in tapp's kinds and units.

    ``epoch`` is t = 0 (UTC); ``stations`` the names of the stations the scenario knows.
    Every epoch of a segment must carry every observable of the segment (one row per epoch).

    Raises
    ------
    InputError
        What tapp cannot use (module docstring), a participant that is not a known station,
        an epoch before ``epoch``, an epoch missing an observable, a repeated record.
    """
    tracks = []
    for i, seg in enumerate(tdm.segments, start=1):
        _check_segment(tdm, i, seg)
        station, spacecraft, path = _participants(tdm, i, seg, stations)
        if seg.keyword.size == 0:
            continue
        kinds = tuple(k for k, key in KEYWORD_OF_KIND.items() if key in set(seg.keyword))
        t = _seconds(seg.jd_whole, seg.jd_fraction, epoch)
        if np.any(t < 0):
            k = int(np.argmax(t < 0))
            raise _refuse(tdm, str(seg.keyword[k]), _where(i, "DATA", int(seg.line[k])),
                          f"an epoch at or after the scenario's epoch {epoch.iso(3)}",
                          f"{t[k]:.3f} s before it")
        times, row = np.unique(t, return_inverse=True)
        values = np.full((times.size, len(kinds)), np.nan)
        col = {KEYWORD_OF_KIND[k]: j for j, k in enumerate(kinds)}
        for r, key, v, line in zip(row.tolist(), seg.keyword.tolist(), seg.value.tolist(),
                                   seg.line.tolist(), strict=True):
            j = col[key]
            if not np.isnan(values[r, j]):
                raise _refuse(tdm, key, _where(i, "DATA", line), "one record per keyword "
                              "and epoch (this epoch has two)")
            values[r, j] = _to_tapp(key, v)
        missing = np.argwhere(np.isnan(values))
        if missing.size:
            r, j = missing[0]
            line = int(seg.line[np.flatnonzero(row == r)[0]])
            raise _refuse(tdm, KEYWORD_OF_KIND[kinds[j]], _where(i, "DATA", line),
                          "a record at every epoch of the segment (tapp's observations "
                          f"carry {', '.join(KEYWORD_OF_KIND[k] for k in kinds)} at each)")
        stop = seg.meta("STOP_TIME")
        end = None
        if stop is not None:
            jd = parse_epoch_jd(stop.value)
            end = float(_seconds(np.array([jd[0]]), np.array([jd[1]]), epoch)[0])
        tracks.append(StationTrack(station, spacecraft, kinds, times, values, end, path,
                                   seg.comments))
    return tracks


def _to_tapp(keyword: str, value: float) -> float:
    if keyword == "ANGLE_1":
        return math.radians(value) % (2.0 * math.pi)
    if keyword == "ANGLE_2":
        return math.radians(value)
    return value


def _to_tdm(kind: str, value: float) -> float:
    return math.degrees(value) if kind in ("azimuth", "elevation") else value


def tdm_from_tracks(tracks: Sequence[StationTrack], epoch: Epoch, *,
                    originator: str = "TAPP", comments: Iterable[str] = (),
                    message_id: str | None = None, created: datetime | None = None) -> Tdm:
    """Return a :class:`Tdm` (version 2.0) of one segment per track.

    ``epoch`` is t = 0 (UTC). Each segment: TIME_SYSTEM = UTC, START_TIME/STOP_TIME (the
    first observation; the track's ``span_end_s`` or its last observation), PARTICIPANT_1 =
    the station, PARTICIPANT_2 = the spacecraft, MODE = SEQUENTIAL, PATH, TIMETAG_REF =
    RECEIVE, RANGE_UNITS = km with range, ANGLE_TYPE = AZEL with angles, DATA_TYPES; one
    record per observable and epoch.

    Raises
    ------
    InputError
        A track with no observation, an unknown kind, mismatched shapes, non-finite values,
        times not non-decreasing or before the epoch, an empty name.
    """
    created = created or datetime.now(UTC)
    header = (KeyValue("CCSDS_TDM_VERS", VERSION_WRITTEN, 0),
              KeyValue("CREATION_DATE", created.strftime("%Y-%m-%dT%H:%M:%S"), 0),
              KeyValue("ORIGINATOR", originator, 0))
    if message_id:
        header += (KeyValue("MESSAGE_ID", message_id, 0),)
    segments = []
    for tr in tracks:
        _check_track(tr)
        t = np.asarray(tr.t_s, dtype=float)
        n, k = t.size, len(tr.kinds)
        whole = np.full(n * k, epoch.jd_whole)
        frac = np.repeat(epoch.jd_fraction + t / SECONDS_PER_DAY, k)
        keys = np.tile(np.array([KEYWORD_OF_KIND[kind] for kind in tr.kinds]), n)
        vals = np.array([_to_tdm(kind, v) for row in tr.values.tolist()
                         for kind, v in zip(tr.kinds, row, strict=True)])
        end = float(t[-1]) if tr.span_end_s is None else max(float(tr.span_end_s), float(t[-1]))
        meta = [("TIME_SYSTEM", "UTC"),
                ("START_TIME", epoch.iso_after(float(t[0]), EPOCH_DECIMALS)),
                ("STOP_TIME", epoch.iso_after(end, EPOCH_DECIMALS)), ("PARTICIPANT_1", tr.station),
                ("PARTICIPANT_2", tr.spacecraft), ("MODE", "SEQUENTIAL"), ("PATH", tr.path),
                ("TIMETAG_REF", "RECEIVE")]
        if "range" in tr.kinds:
            meta.append(("RANGE_UNITS", "km"))
        if {"azimuth", "elevation"} & set(tr.kinds):
            meta.append(("ANGLE_TYPE", "AZEL"))
        meta.append(("DATA_TYPES", ",".join(KEYWORD_OF_KIND[kind] for kind in tr.kinds)))
        segments.append(TdmSegment(tuple(KeyValue(a, b, 0) for a, b in meta), tr.comments,
                                   keys, whole, frac, vals, np.zeros(n * k, int), 0, 0))
    if not segments:
        raise InputError("TDM", "tracks", "at least one station with observations")
    return Tdm(VERSION_WRITTEN, header, tuple(comments), tuple(segments))




def _check_track(tr: StationTrack) -> None:
    t = np.asarray(tr.t_s, dtype=float)
    v = np.asarray(tr.values, dtype=float)
    bad = [k for k in tr.kinds if k not in KEYWORD_OF_KIND]
    if bad:
        raise InputError("TDM", "kinds", f"kinds among {', '.join(KEYWORD_OF_KIND)}", bad[0])
    if t.ndim != 1 or t.size == 0 or v.shape != (t.size, len(tr.kinds)):
        raise InputError("TDM", f"track {tr.station}", "times (n >= 1,) and values (n, k)",
                         (t.shape, v.shape))
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InputError("TDM", f"track {tr.station}", "finite times and values")
    if np.any(np.diff(t) < 0) or t[0] < 0:
        raise InputError("TDM", f"track {tr.station}", "non-decreasing times >= 0")
    for what, name in (("station", tr.station), ("spacecraft", tr.spacecraft)):
        if not name.strip() or name != name.strip() or "\n" in name:
            raise InputError("TDM", what, "a non-empty one-line name", name)


def tracks_from_rows(t_s: np.ndarray, station: np.ndarray, kind: np.ndarray,
                     value: np.ndarray, kinds: Sequence[str], station_names: Sequence[str],
                     spacecraft: str, *, path: str = "1,2,1",
                     span_end_s: float | None = None) -> list[StationTrack]:
    """Group scalar observation rows into one :class:`StationTrack` per station.

    ``t_s``, ``station`` (index into ``station_names``), ``kind`` (index into ``kinds``),
    ``value`` are (N,) rows (e.g. a T13 tape's ``raw/`` group, stations numbered from 0);
    every time of a station must carry the same kinds.

    Raises
    ------
    InputError
        A station's times do not all carry the same observables.
    """
    t_s, station, kind, value = (np.asarray(a) for a in (t_s, station, kind, value))
    tracks = []
    for s, name in enumerate(station_names):
        rows = np.flatnonzero(station == s)
        if rows.size == 0:
            continue
        codes = sorted(set(kind[rows].tolist()), key=lambda c: list(KEYWORD_OF_KIND).index(
            kinds[c]))
        times = np.unique(t_s[rows])
        values = np.full((times.size, len(codes)), np.nan)
        column = {code: j for j, code in enumerate(codes)}
        r = np.searchsorted(times, t_s[rows])
        c = np.array([column[k] for k in kind[rows].tolist()])
        values[r, c] = value[rows]
        if np.isnan(values).any():
            raise InputError("TDM", f"station {name}", "the same observables at every time")
        tracks.append(StationTrack(name, spacecraft, tuple(kinds[k] for k in codes), times,
                                   values, span_end_s, path))
    return tracks
