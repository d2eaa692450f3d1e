"""CCSDS Orbit Ephemeris Message (OEM) 2.0 in KVN form: the trajectory of a simulation.

Layout per CCSDS 502.0-B-2 (Orbit Data Messages, Blue Book, 2009), §5: a header
(``CCSDS_OEM_VERS = 2.0``, ``CREATION_DATE``, ``ORIGINATOR``), one metadata block between
``META_START`` and ``META_STOP`` (``OBJECT_NAME``, ``OBJECT_ID``, ``CENTER_NAME``,
``REF_FRAME``, ``TIME_SYSTEM``, ``START_TIME``, ``STOP_TIME``), then one data line per epoch:
the epoch (ISO, UTC) and x, y, z (km), x_dot, y_dot, z_dot (km/s). Epochs must increase.
The file is written to a temporary name and renamed.
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from tapp.atomic import atomic_write
from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError
from tapp.frames.time import Epoch

#: Digits of the seconds of the epochs (1 us).
EPOCH_DECIMALS = 6


def _utc(epoch: Epoch, t_s: float) -> str:
    return Epoch(epoch.jd_whole, epoch.jd_fraction + t_s / SECONDS_PER_DAY).iso(EPOCH_DECIMALS)


def format_oem(epoch: Epoch, t_s, states, *, object_name: str, object_id: str,
               originator: str = "TAPP", comments: tuple[str, ...] = ()) -> str:
    """Return the text of an OEM 2.0 (KVN) of an Earth-centred EME2000 trajectory.

    Parameters
    ----------
    epoch : Epoch
        UTC of t = 0.
    t_s : array_like, shape (N,)
        Strictly increasing times, s from the epoch.
    states : array_like, shape (N, 6)
        Position km and velocity km/s, EME2000, Earth-centred.
    object_name, object_id : str
        Spacecraft name and identifier (non-empty).
    originator : str
        Creating agency.
    comments : tuple of str
        COMMENT lines placed after the header.

    Raises
    ------
    InputError
        Mismatched shapes, non-finite values, times not strictly increasing, empty names.
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(states, dtype=float)
    if t.ndim != 1 or t.size == 0 or x.shape != (t.size, 6):
        raise InputError("OEM", "states", "times (N,) and states (N, 6)", (t.shape, x.shape))
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise InputError("OEM", "states", "finite times and states")
    if np.any(np.diff(t) <= 0):
        raise InputError("OEM", "t_s", "strictly increasing times")
    for field, value in (("OBJECT_NAME", object_name), ("OBJECT_ID", object_id)):
        if not value.strip():
            raise InputError("OEM", field, "a non-empty name", value)
    created = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S")
    lines = ["CCSDS_OEM_VERS = 2.0", f"CREATION_DATE = {created}",
             f"ORIGINATOR = {originator}", ""]
    if comments:
        lines += [*(f"COMMENT {c}" for c in comments), ""]
    lines += ["META_START",
              f"OBJECT_NAME = {object_name}",
              f"OBJECT_ID = {object_id}",
              "CENTER_NAME = EARTH",
              "REF_FRAME = EME2000",
              "TIME_SYSTEM = UTC",
              f"START_TIME = {_utc(epoch, float(t[0]))}",
              f"STOP_TIME = {_utc(epoch, float(t[-1]))}",
              "META_STOP", ""]
    for ti, row in zip(t, x, strict=True):
        lines.append(f"{_utc(epoch, float(ti))} " + " ".join(
            [f"{v:.9f}" for v in row[:3]] + [f"{v:.12f}" for v in row[3:]]))
    return "\n".join(lines) + "\n"


def write_oem(path: Path | str, text: str) -> Path:
    """Write OEM text to ``path`` atomically (temporary file in the same folder, rename)."""
    return atomic_write(path, lambda tmp: tmp.write_text(text))
