"""A command's outputs: never one of its inputs, and all of them written or none.

Two mechanisms, used by every command that writes files:

* :func:`check_paths`, called before any work: no output may resolve to an input or to
  another output (relative paths, ``..`` and symbolic links resolved, hard links caught by
  :func:`os.path.samefile`), and every output must be creatable (not a folder, in a folder
  that is writable). It raises :class:`~tapp.errors.InputError` naming both options, as the
  user typed them (``-o/--output``, ``--oem``, ``SCENARIO``).
* :func:`new_directory`, for a command whose output is a whole folder (``tapp pipeline``,
  ``tapp examples``): the folder must be new or empty; its content is written into a hidden
  folder beside it, renamed to it only once complete, and removed on any failure.
* :class:`OutputSet`, which writes a command's outputs together: each to a hidden temporary
  ``.NAME.<random>.tmp`` beside its target, and only once every temporary is complete are
  they renamed over their targets, one after the other, at the end. If any write fails every
  temporary is removed and every old output is left untouched; errors name the requested
  path and its option, never the temporary. Temporaries of the same target left behind by an
  earlier run that was killed are removed before writing.

:func:`tapp.atomic.atomic_write` is the one-output use of :class:`OutputSet`.

What is left on disk when a run is killed: the old outputs, or the new ones, each complete
(a rename is atomic); at worst, a kill between two renames (microseconds) leaves some new
outputs beside old ones. A killed run can leave temporaries; the next write of the same
target removes them.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from tapp.errors import InputError

#: Permissions of written files (the temporaries are created 0600).
FILE_MODE = 0o644
#: Hexadecimal digits of the random part of a temporary's name.
_RANDOM_HEX = 16
#: Random part of a temporary's name: ours (hex) or tempfile.mkstemp's (8 characters), so
#: temporaries of earlier versions are cleaned up too.
_RANDOM = r"(?:[0-9a-f]{16}|[A-Za-z0-9_]{8})"


def temporary_name(target: Path) -> Path:
    """Return a new hidden temporary path ``.NAME.<random>.tmp`` beside ``target``."""
    return target.with_name(f".{target.name}.{secrets.token_hex(_RANDOM_HEX // 2)}.tmp")


def _stale_pattern(name: str) -> re.Pattern[str]:
    # ``.NAME.<random>.tmp``, and a temporary of that temporary (a writer that is itself
    # atomic, called on our temporary: ``..NAME.<random>.tmp.<random>.tmp``).
    return re.compile(rf"^\.\.?{re.escape(name)}\.{_RANDOM}\.tmp(?:\.{_RANDOM}\.tmp)?$")


def stale_temporaries(target: Path) -> list[Path]:
    """Return the temporaries of ``target`` in its folder (left there by a killed run)."""
    target = Path(target)
    folder = target.parent
    if not folder.is_dir():
        return []
    pattern = _stale_pattern(target.name)
    return sorted(p for p in folder.iterdir() if pattern.match(p.name))


def remove_stale_temporaries(target: Path) -> None:
    """Remove the temporaries of ``target`` left in its folder by an earlier, killed run."""
    for path in stale_temporaries(target):
        path.unlink(missing_ok=True)


def same_file(a: Path, b: Path) -> bool:
    """Return True if ``a`` and ``b`` name the same file (symbolic and hard links included).

    Paths are compared once resolved (relative parts and symbolic links, also for files that
    do not exist yet); two existing paths are also compared by device and inode.
    """
    a, b = Path(a), Path(b)
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet): then they differ
        return False


def _nearest_existing(path: Path) -> Path:
    for parent in path.resolve().parents:
        if parent.exists():
            return parent
    return Path(path.anchor or "/")


def check_writable(option: str, path: Path) -> None:
    """Raise InputError naming ``option`` unless ``path`` can be created or replaced.

    ``path`` must not be a folder, and the nearest existing folder above it must be a
    writable folder (missing folders are created when the output is written).
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(option, str(path), "a file path, not a folder")
    folder = _nearest_existing(path)
    if not folder.is_dir():
        raise InputError(option, str(path), f"a path inside a folder ({folder} is a file)")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(option, str(path), f"a path in a writable folder ({folder} is not "
                         "writable)")


def check_paths(inputs: Mapping[str, Path | None], outputs: Mapping[str, Path | None]) -> None:
    """Refuse outputs that would overwrite an input or another output, or cannot be written.

    Call it before any work. Keys are the options as the user typed them (``"-o/--output"``,
    ``"--oem"``, ``"SCENARIO"`` for a positional argument); None values are options not
    given.

    Raises
    ------
    InputError
        An output resolves to an input or to another output (naming both options), or an
        output path is a folder or lies in a folder that cannot be written.
    """
    given_in = [(name, Path(p)) for name, p in inputs.items() if p is not None]
    given_out = [(name, Path(p)) for name, p in outputs.items() if p is not None]
    for name, out in given_out:
        for in_name, inp in given_in:
            if same_file(out, inp):
                raise InputError(name, str(out), f"a file other than the input {in_name} "
                                 "(it would be overwritten)")
    for k, (name, out) in enumerate(given_out):
        for other_name, other in given_out[:k]:
            if same_file(out, other):
                raise InputError(name, str(out), f"a file other than the output {other_name} "
                                 "(one would overwrite the other)")
    for name, out in given_out:
        check_writable(name, out)


def check_new_directory(out_dir: Path, option: str, why: str) -> Path:
    """Return ``out_dir`` if it does not exist or is an empty folder, else raise.

    Raises
    ------
    InputError
        Naming ``option``: a file, or a folder with something in it (never overwritten;
        ``why`` says so in the command's words).
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())):
        raise InputError(option, "directory", f"a new or empty directory ({why})",
                         str(out_dir))
    return out_dir


@contextmanager
def new_directory(out_dir: Path, option: str, why: str) -> Iterator[Path]:
    """Yield a hidden folder beside ``out_dir`` to write into; rename it to ``out_dir`` when
    the block completes, remove it if the block raises.

    ``out_dir`` must be new or empty (:func:`check_new_directory`); a missing parent is
    created.

    Examples
    --------
    >>> folder = Path(tempfile.mkdtemp())
    >>> with new_directory(folder / "run", "-o", "never overwritten") as work:
    ...     _ = (work / "a.txt").write_text("a")
    >>> [p.name for p in (folder / "run").iterdir()], [p.name for p in folder.iterdir()]
    (['a.txt'], ['run'])
    >>> shutil.rmtree(folder)
    """
    out_dir = check_new_directory(out_dir, option, why)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.tmp-", dir=out_dir.parent))
    try:
        yield work
        if out_dir.exists():
            out_dir.rmdir()
        work.rename(out_dir)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise


@dataclass(frozen=True, slots=True)
class _Output:
    option: str
    path: Path
    write: Callable[[Path], None]


@dataclass(slots=True)
class OutputSet:
    """A command's outputs, written all together or not at all.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> outputs = OutputSet()
    >>> outputs.add("-o/--output", folder / "a.txt", lambda tmp: tmp.write_text("a"))
    >>> outputs.add("--copy", folder / "b.txt", lambda tmp: tmp.write_text("b"))
    >>> [p.name for p in outputs.commit()]
    ['a.txt', 'b.txt']
    >>> sorted(p.name for p in folder.iterdir())
    ['a.txt', 'b.txt']
    >>> import shutil; shutil.rmtree(folder)
    """

    _outputs: list[_Output] = field(default_factory=list)

    def add(self, option: str, path: Path | str, write: Callable[[Path], None]) -> None:
        """Register an output: ``write(tmp)`` must write the complete file at ``tmp``.

        Parameters
        ----------
        option : str
            The option that named the output, as typed (``--oem``); used in errors.
        path : Path or str
            The requested output path.
        write : callable
            Writes the whole file at the path it is given (a temporary beside ``path``).
        """
        self._outputs.append(_Output(option, Path(path), write))

    def commit(self) -> tuple[Path, ...]:
        """Write every output to its temporary, then rename them all over their targets.

        Returns
        -------
        tuple of Path
            The outputs written, in the order added.

        Raises
        ------
        InputError
            A file or folder cannot be written (names the option and the requested path).
        Exception
            Whatever a ``write`` raises; then no output has been replaced and no temporary
            is left.
        """
        written: list[tuple[_Output, Path]] = []
        current = None
        try:
            for out in self._outputs:
                current = out
                out.path.parent.mkdir(parents=True, exist_ok=True)
                remove_stale_temporaries(out.path)
            for out in self._outputs:
                current = out
                tmp = temporary_name(out.path)
                written.append((out, tmp))
                out.write(tmp)
                os.chmod(tmp, FILE_MODE)
            for out, tmp in written:
                current = out
                os.replace(tmp, out.path)
        except OSError as exc:
            assert current is not None
            raise InputError(current.option, str(current.path), "a writable file",
                             exc.strerror or type(exc).__name__) from None
        finally:
            for _, tmp in written:
                tmp.unlink(missing_ok=True)
            self._outputs.clear()
        return tuple(out.path for out, _ in written)
