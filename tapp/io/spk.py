"""SPICE SPK files through spiceypy: a spacecraft's states read, a trajectory written (type 13).

Reading: any SPK segment type the SPICE toolkit reads, for a body named by its NAIF id or
by a name SPICE knows. States are asked of SPICE relative to the Earth (399) in the
``J2000`` frame, at ET (TDB seconds past J2000: :mod:`tapp.frames.timesystems`), without
aberration corrections: SPICE chains the file's segments to the Earth and rotates their
frames (any built-in inertial frame). JPL DE421 (``de421.bsp`` in ``skyfield-data``, the
ephemeris the force models read) is loaded first, so a file whose segments are relative to
the Moon, the Sun or a barycentre still reaches the Earth; the file's own segments take
precedence over it. In SPICE, ``J2000`` is the ICRF as the JPL ephemerides realise it
(NAIF, *Frames Required Reading*: the two are not distinguished), which is the GCRS's axes
(a gmst scenario's EME2000 differs from them by the frame bias: :mod:`tapp.frames.file_frames`).

Writing (:func:`write_spk`): type 13 segments (Hermite interpolation, unequal time steps,
NAIF *SPK Required Reading* §"Type 13"), centre the Earth, frame ``J2000``, one per coast arc
of a trajectory with impulsive burns: segments that meet at a burn's epoch both hold it, and
SPICE, which searches the segments last written first, gives the later one's state there (the
state after the burn); comment lines are added to the file's comment area (``commnt`` shows
them) by :func:`add_comments`.

SPICE keeps loaded kernels in one global pool and is not thread-safe: every call here holds
one lock, loads what it needs, and unloads it again before returning. SPICE's own errors
(a file that is not a kernel, a frame it cannot rotate, data missing for the chain to the
Earth) become :class:`~tapp.errors.InputError` naming the file and quoting SPICE's short
message; a file SPICE cannot name (over :data:`MAX_PATH_CHARS` characters) is refused first.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import spiceypy
from spiceypy.utils.exceptions import NotFoundError, SpiceyError

from tapp.dynamics.ephemeris import de421_path
from tapp.errors import InputError
from tapp.frames.time import JD_J2000, Epoch

#: NAIF id of the Earth, the centre of every state read, and of those written unless the
#: scenario integrates about another body (:data:`NAIF_IDS`).
EARTH_ID = 399
#: NAIF ids of the DE421 bodies an integration may be centred on (the outer planets by their
#: system barycentres, as DE421 holds them).
NAIF_IDS = {"sun": 10, "mercury": 199, "venus": 299, "earth": EARTH_ID, "moon": 301,
            "mars": 499, "jupiter": 5, "saturn": 6, "uranus": 7, "neptune": 8}
#: The inertial frame of the states (SPICE's name for the ICRF axes).
FRAME = "J2000"
#: Longest file name SPICE accepts (FILEN in the toolkit).
MAX_PATH_CHARS = 255
#: Hermite degree of the written type 13 segments: 7, through 4 states (positions and
#: velocities), the degree SPICE's own examples use.
SPK_DEGREE = 7
#: Characters reserved for comments in a written file (more are added as needed).
_COMMENT_CHARS = 4000
#: Longest comment line SPICE stores (``dafac``).
_COMMENT_LINE_CHARS = 1000
_LOCK = threading.RLock()


def _spice_path(path: Path, source: str, field: str) -> str:
    text = str(Path(path).resolve())
    if len(text) > MAX_PATH_CHARS:
        raise InputError(source, field, f"a path of at most {MAX_PATH_CHARS} characters once "
                         "resolved (SPICE's limit)", text)
    return text


def _spice_error(exc: SpiceyError) -> str:
    """SPICE's short message and the first line of its long one."""
    long = " ".join(str(getattr(exc, "value", "")).split())
    return f"{exc.short} {long}".strip()


@contextmanager
def _loaded(paths: Sequence[tuple[str, str]], source: str, field: str) -> Iterator[None]:
    """Load kernels (path, what it is) in order, holding the lock; unload them after."""
    done: list[str] = []
    with _LOCK:
        try:
            for path, what in paths:
                try:
                    spiceypy.furnsh(path)
                except SpiceyError as exc:
                    raise InputError(source, field, f"{what} SPICE can read",
                                     _spice_error(exc)) from None
                done.append(path)
            yield
        finally:
            for path in reversed(done):
                spiceypy.unload(path)


def body_id(body: int | str, source: str, field: str,
            expected: str = "a NAIF id (integer) or a body name SPICE knows") -> int:
    """Return the NAIF id of ``body``: an integer, an integer as text, or a name SPICE knows
    (``"MOON"``, ``"EARTH BARYCENTER"``).

    Raises
    ------
    InputError
        A name SPICE does not know (saying ``expected``).
    """
    if isinstance(body, int):
        return body
    text = body.strip()
    if text.lstrip("+-").isdigit():
        return int(text)
    with _LOCK:
        try:
            return int(spiceypy.bodn2c(text))
        except NotFoundError:
            raise InputError(source, field, expected, body) from None


def _objects(path: str) -> list[int]:
    cell = spiceypy.spkobj(path)
    return [int(cell[i]) for i in range(spiceypy.card(cell))]


def _coverage(path: str, body: int) -> np.ndarray:
    """The ET windows (K, 2) for which ``path`` has data of ``body``."""
    cell = spiceypy.spkcov(path, body)
    n = spiceypy.wncard(cell)
    return np.array([spiceypy.wnfetd(cell, i) for i in range(n)]).reshape(n, 2)


def spk_states(path: Path | str, body: int, et_s, source: str, field: str = "file",
               body_field: str = "object", spans: Sequence[tuple[float, float, str]] = (),
               center: int = EARTH_ID) -> np.ndarray:
    """Return the states (N, 6) of ``body`` relative to ``center`` (the Earth) in J2000 (km,
    km/s) at ET values ``et_s`` (N,) from the SPK at ``path`` (module docstring).

    ``spans`` lists (ET start, ET end, what it is) that the file's coverage of the body must
    hold whole, each named in the error when it does not (the scenario's arcs); the times
    themselves must lie in the coverage too.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``: a file SPICE cannot read, a span or time outside
        its coverage, or a state SPICE cannot compute (a frame or a centre it cannot reach
        the Earth from); naming ``body_field``: a file without data of the body (listing the
        bodies it has).
    """
    name = _spice_path(Path(path), source, field)
    et = np.asarray(et_s, dtype=float)
    with _loaded(((str(de421_path()), "the DE421 ephemeris"), (name, "an SPK file")),
                 source, field):
        try:
            objects = _objects(name)
        except SpiceyError as exc:
            raise InputError(source, field, "an SPK file SPICE can read",
                             _spice_error(exc)) from None
        if body not in objects:
            raise InputError(source, body_field, f"a body whose data {Path(path).name} holds "
                             f"({', '.join(map(str, objects)) or 'none'})", body)
        windows = _coverage(name, body)
        for start, end, what in (*spans, (float(et.min()), float(et.max()), "the times")):
            if not np.any((windows[:, 0] <= start) & (windows[:, 1] >= end)):
                have = "; ".join(f"{_et_text(a)} to {_et_text(b)}" for a, b in windows)
                raise InputError(source, field, f"an SPK whose data of body {body} covers "
                                 f"{what}, {_et_text(start)} to {_et_text(end)} (it covers "
                                 f"{have})", str(path))
        try:
            states, _ = spiceypy.spkezr(str(body), et, FRAME, "NONE", str(center))
        except SpiceyError as exc:
            raise InputError(source, field, f"an SPK from which SPICE computes body {body}'s "
                             f"state relative to body {center}", _spice_error(exc)) from None
    return np.asarray(states, dtype=float).reshape(et.size, 6)


def body_states(body: int, et_s, source: str, field: str) -> np.ndarray:
    """Return the states (N, 6) of ``body`` relative to the Earth in J2000 (km, km/s) at ET
    values (N,), from DE421 (the centre of a trajectory file).

    Raises
    ------
    InputError
        A body DE421 does not hold, or a time outside it.
    """
    et = np.asarray(et_s, dtype=float)
    with _loaded(((str(de421_path()), "the DE421 ephemeris"),), source, field):
        try:
            states, _ = spiceypy.spkezr(str(body), et, FRAME, "NONE", str(EARTH_ID))
        except SpiceyError as exc:
            raise InputError(source, field, "a centre whose state DE421 gives (the Sun, the "
                             "Moon, the planets' barycentres, the solar-system barycentre) "
                             "at the file's times", _spice_error(exc)) from None
    return np.asarray(states, dtype=float).reshape(et.size, 6)


def _et_text(et: float) -> str:
    """An ET as a TDB calendar date (no leap-second kernel needed), for messages."""
    days = et / 86400.0
    whole = np.floor(JD_J2000 + days - 0.5) + 0.5
    return Epoch(float(whole), float(JD_J2000 - whole + days)).iso(3) + " TDB"


def write_spk(path: Path | str, body: int, segments: Sequence[tuple[np.ndarray, np.ndarray]],
              *, segment_id: str = "tapp", degree: int = SPK_DEGREE, option: str = "--spk",
              center: int = EARTH_ID) -> None:
    """Write an SPK file holding type 13 segments of ``body`` relative to ``center`` (the
    Earth) in J2000,
    one per (ET (N,), states (N, 6) km, km/s) of ``segments``, in time order: ET strictly
    increasing within each, Hermite of odd ``degree`` through (degree + 1) / 2 states.

    ``path`` must not exist (an :class:`tapp.io.outputs.OutputSet` temporary); comments are
    added by :func:`add_comments`.

    Raises
    ------
    InputError
        A path SPICE cannot name, or a segment SPICE refuses (naming ``option``).
    """
    name = _spice_path(Path(path), option, "path")
    with _LOCK:
        try:
            handle = spiceypy.spkopn(name, "tapp", _COMMENT_CHARS)
            try:
                for et_s, states in segments:
                    et = np.ascontiguousarray(et_s, dtype=float)
                    x = np.ascontiguousarray(states, dtype=float)
                    spiceypy.spkw13(handle, body, center, FRAME, float(et[0]),
                                    float(et[-1]), segment_id[:40], degree, et.size, x, et)
            finally:
                spiceypy.spkcls(handle)
        except SpiceyError as exc:
            raise InputError(option, str(path), "an SPK SPICE can write",
                             _spice_error(exc)) from None


def add_comments(path: Path | str, comments: Sequence[str], option: str = "--spk") -> None:
    """Append lines to the comment area of the SPK at ``path`` (SPICE's ``commnt`` shows
    them); lines longer than SPICE stores are wrapped.

    Raises
    ------
    InputError
        A file SPICE cannot open for writing (naming ``option``).
    """
    name = _spice_path(Path(path), option, "path")
    lines = [text[i:i + _COMMENT_LINE_CHARS] or " " for text in comments
             for i in range(0, max(len(text), 1), _COMMENT_LINE_CHARS)]
    with _LOCK:
        try:
            handle = spiceypy.dafopw(name)
            try:
                spiceypy.dafac(handle, lines)
            finally:
                spiceypy.dafcls(handle)
        except SpiceyError as exc:
            raise InputError(option, str(path), "an SPK SPICE can add comments to",
                             _spice_error(exc)) from None
