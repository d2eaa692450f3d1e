"""Numbers read from the text of input files (CSV, SINEX, OEM), refused with the file and the
field named when they are not finite numbers."""

from __future__ import annotations

import math

from tapp.errors import InputError


def finite_number(text: str, source: str, field: str) -> float:
    """Return ``text`` as a float.

    Raises
    ------
    InputError
        ``text`` is not a number, or is NaN or infinite (naming ``source`` and ``field``).
    """
    try:
        value = float(text)
    except ValueError:
        raise InputError(source, field, "a number", text) from None
    if not math.isfinite(value):
        raise InputError(source, field, "a finite number", text)
    return value
