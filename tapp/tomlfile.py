"""Reading scenario files (TOML), with errors that name the file.

Every file type is then validated against its declared schema (:mod:`tapp.schema`), which
checks the numbers, the types and the keys, and names the field.
"""

from __future__ import annotations

import tomllib
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
