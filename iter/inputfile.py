"""Opening input files: regular files only, and text of bounded size, before a byte is read.

Every reader of an input file goes through here: :func:`regular_file` for files another
library opens by name (HDF5 tapes, observation and results files, which h5py opens and reads
chunk by chunk), :func:`read_bytes` and :func:`read_text` for text read whole (TDM and CSV
observation files, EOP tables), :func:`read_toml` for TOML files. A FIFO, a character or block
device (a symbolic link to ``/dev/zero``), a socket or a directory is refused from its
``stat`` before it is read, so that no reader blocks in ``open()`` waiting for a writer that
never comes nor reads an endless device until memory runs out. A text input larger than its
bound is refused from its size, and is never read past the bound even if it grows meanwhile
(or is a file whose size the system reports as 0).

Text is checked with ``stat``, then opened with ``O_NONBLOCK`` and checked again with
``fstat`` on the open descriptor, so that a file swapped for a FIFO between the check and the
open cannot block either.

This is the mechanism behind ``tapp``'s readers as well (``iter`` may not import ``tapp``):
each function takes the error class to raise, called ``error(source, field, expected, got)``
(:class:`~iter.errors.SweepInputError` by default; ``tapp`` passes its ``InputError``).

>>> import tempfile, os
>>> fifo = os.path.join(tempfile.mkdtemp(), "deck.toml")
>>> os.mkfifo(fifo)
>>> read_text(fifo, "deck file", max_bytes=1024)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
iter.errors.SweepInputError: ...deck.toml: file: expected a regular file (deck file) (got ...)
"""

from __future__ import annotations

import os
import stat
import tomllib
from pathlib import Path

from .errors import SweepInputError

__all__ = ["MAX_TOML_BYTES", "read_bytes", "read_text", "read_toml", "regular_file"]

#: Largest TOML input (scenario, deck, guidance, pipeline, study or sweep file), bytes: a
#: deck with a 400 x 400 a priori matrix written out is ~4 MB, the shipped files 1 to 12 kB.
#: Measured at the bound on 2 shared cores (load ~5): tomllib parsed 4 MiB of numbers in
#: 2.2 s and a million empty inline tables, the worst, in 6.4 s; ``tapp process`` refused
#: either deck (an unknown key) in 11 to 14 s with 160 to 230 MB at its peak.
MAX_TOML_BYTES = 4 * 2**20

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _check_stat(st: os.stat_result, source: str, what: str, max_bytes: int | None,
                error: type[Exception]) -> None:
    if not stat.S_ISREG(st.st_mode):
        raise error(source, "file", f"a regular file ({what})", _kind(st.st_mode))
    if max_bytes is not None and st.st_size > max_bytes:
        raise error(source, "file", f"a {what} of at most {max_bytes:,} bytes",
                    f"{st.st_size:,} bytes")


def _os_error(exc: OSError, source: str, what: str, error: type[Exception]) -> Exception:
    if isinstance(exc, FileNotFoundError):
        return error(source, "file", f"an existing {what}", None)
    return error(source, "file", f"a readable {what}", exc.strerror or type(exc).__name__)


def regular_file(path: str | Path, what: str, *, source: str | None = None,
                 max_bytes: int | None = None, error: type[Exception] = SweepInputError
                 ) -> Path:
    """Return ``path`` if it names (through any symbolic links) a regular file; else raise.

    Parameters
    ----------
    path : the file.
    what : what the file should be, for the message ("T32 tape file").
    source : the name in the message (default: ``path``).
    max_bytes : largest size accepted, or None.
    error : the exception class raised, ``error(source, "file", expected, got)``.
    """
    source = str(path) if source is None else source
    try:
        st = os.stat(path)
    except OSError as exc:
        raise _os_error(exc, source, what, error) from None
    _check_stat(st, source, what, max_bytes, error)
    return Path(path)


def read_bytes(path: str | Path, what: str, *, max_bytes: int, source: str | None = None,
               error: type[Exception] = SweepInputError) -> bytes:
    """Return the content of the regular file ``path``, at most ``max_bytes`` bytes; else
    raise (:func:`regular_file`'s refusals, and a file that holds more)."""
    source = str(path) if source is None else source
    regular_file(path, what, source=source, max_bytes=max_bytes, error=error)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise _os_error(exc, source, what, error) from None
    try:
        _check_stat(os.fstat(fd), source, what, max_bytes, error)
        with os.fdopen(fd, "rb", closefd=False) as stream:
            data = stream.read(max_bytes + 1)
    except OSError as exc:
        raise _os_error(exc, source, what, error) from None
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise error(source, "file", f"a {what} of at most {max_bytes:,} bytes",
                    f"more than {max_bytes:,} bytes")
    return data


def read_text(path: str | Path, what: str, *, max_bytes: int, source: str | None = None,
              error: type[Exception] = SweepInputError) -> str:
    """Return the UTF-8 text of the regular file ``path`` (:func:`read_bytes`); a file that
    is not UTF-8 text is refused too."""
    source = str(path) if source is None else source
    data = read_bytes(path, what, max_bytes=max_bytes, source=source, error=error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(source, "file", f"a {what} in UTF-8 text",
                    f"byte 0x{data[exc.start]:02x} at offset {exc.start}") from None


def read_toml(path: str | Path, what: str, *, error: type[Exception] = SweepInputError
              ) -> dict:
    """Return the parsed TOML document of the regular file ``path``, at most
    :data:`MAX_TOML_BYTES` (:func:`read_text`); a document that is not valid TOML (arrays
    nested too deep for the parser included) is refused, field ``TOML``."""
    source = str(path)
    text = read_text(path, what, max_bytes=MAX_TOML_BYTES, error=error)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(source, "TOML", f"valid TOML ({exc})", None) from None
    except RecursionError:
        raise error(source, "TOML", "valid TOML (arrays or tables nested too deep for the "
                    "parser)", None) from None
