"""Reading scenario files (TOML) and their numbers, with errors that name file and field."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from pathlib import Path

from tapp.errors import InputError


def read_toml(path: Path | str) -> dict:
    """Return the parsed TOML document at ``path``.

    Raises
    ------
    InputError
        The file is missing, unreadable, not text, or not valid TOML (naming the file).
    """
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise InputError(str(path), "file", "an existing scenario file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(str(path), "file", f"a readable text file ({exc})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(str(path), "TOML", f"valid TOML ({exc})") from None


def finite_number(table: Mapping, key: str, source: str, where: str, *,
                  default: float | None = None, positive: bool = False,
                  nonzero: bool = False) -> float:
    """Return ``table[key]`` (or ``default``) as a float, checked finite (and > 0, != 0).

    ``where`` is the field named in the error (e.g. ``"tracking.data_interval_s"``); booleans
    are not numbers here.
    """
    value = table.get(key, default)
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if ok and positive:
        ok = value > 0
    if ok and nonzero:
        ok = value != 0
    if not ok:
        what = "a finite number" + (" > 0" if positive else "") + (" != 0" if nonzero else "")
        raise InputError(source, where, what, value)
    return float(value)
