"""Atomic file writing: write to a temporary file beside the target, then rename.

Every writer of tapes, observation files and trajectories goes through :func:`atomic_write`,
so a crash or an error never leaves a half-written file behind. It is the one-output use of
:class:`tapp.io.outputs.OutputSet` (the mechanism commands use to write several outputs all
together or not at all), not a second implementation.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from tapp.io.outputs import FILE_MODE, OutputSet

__all__ = ["FILE_MODE", "atomic_write"]


def atomic_write(path: Path | str, write: Callable[[Path], None], *,
                 option: str = "output") -> Path:
    """Call ``write(tmp)`` on a temporary path in ``path``'s folder, then rename it to ``path``.

    Temporaries of ``path`` left by an earlier, killed run are removed first. The temporary
    is removed if ``write`` raises; the exception propagates.

    Raises
    ------
    InputError
        The file or its folder cannot be written (names ``option`` and ``path``).
    """
    outputs = OutputSet()
    outputs.add(option, path, write)
    return outputs.commit()[0]
