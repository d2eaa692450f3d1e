"""A command's outputs: never one of its inputs, and all of them written or none.

Two mechanisms, used by every command that writes files:

* :func:`check_paths`, called before any work: no output may resolve to an input or to
  another output (relative paths, ``..`` and symbolic links resolved, hard links caught by
  :func:`os.path.samefile`), and every output must be creatable (not a folder, in a folder
  that is writable). It raises :class:`~tapp.errors.InputError` naming both options, as the
  user typed them (``-o/--output``, ``--oem``, ``SCENARIO``).
* :func:`new_directory`, for a command whose output is a whole folder (``tapp pipeline``,
  ``tapp examples``): the folder must be new or empty (not a symbolic link); its content is
  written into a hidden folder ``.NAME.<random>.tmp`` beside it, renamed to it only once
  complete, and removed on any failure or signal, with any folder made to hold it.
* :class:`OutputSet`, which writes a command's outputs together: each to a hidden temporary
  ``.NAME.<random>.tmp`` beside its target, and only once every temporary is complete are
  they renamed over their targets, one after the other, at the end. If any write fails (or
  a signal stops the run) every temporary is removed, and so is every folder made for the
  outputs, and every old output is left untouched; errors name the requested path and its
  option, never the temporary (:func:`unwritable`: a path at fault is bad input, a full disk
  or a device error is a :class:`~tapp.errors.WriteError`). Temporaries of the same target
  left behind by an earlier run that was killed are removed before writing; so are hidden
  temporary folders (``tapp pipeline``'s, :func:`temporary_name`), whole. An output that
  names a device or a pipe (``--json /dev/null``) is written into it, last, never renamed
  over (:func:`written_in_place`).
  :meth:`OutputSet.staged` runs a block (a command's report) between the writing and the
  renaming: if the block fails, nothing is renamed.

:func:`tapp.io.atomic.atomic_write` is the one-output use of :class:`OutputSet`.

What is left on disk when a run is killed: the old outputs, or the new ones, each complete
(a rename is atomic); at worst, a kill between two renames (microseconds) leaves some new
outputs beside old ones. A killed run can leave temporaries; the next write of the same
target removes them.
"""

from __future__ import annotations

import contextlib
import errno
import itertools
import os
import re
import secrets
import shutil
import stat
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from tapp.errors import InputError, TappError, WriteError

#: Permissions of written files (the temporaries are created 0600).
FILE_MODE = 0o644
#: Hexadecimal digits of the random part of a temporary's name.
_RANDOM_HEX = 16
#: Random part of a temporary's name: ours (hex) or tempfile.mkstemp's (8 characters), so
#: temporaries of earlier versions are cleaned up too.
_RANDOM = r"(?:[0-9a-f]{16}|[A-Za-z0-9_]{8})"
#: errno values of a write that fails because of the path asked for (bad input, exit 2);
#: any other (a full disk, a quota, a device error) is the machine's (exit 1).
_PATH_ERRNOS = frozenset({errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOTDIR,
                          errno.EISDIR, errno.EEXIST, errno.ENOENT, errno.ENAMETOOLONG,
                          errno.ELOOP})


def temporary_name(target: Path) -> Path:
    """Return a new hidden temporary path ``.NAME.<random>.tmp`` beside ``target``."""
    return target.with_name(f".{target.name}.{secrets.token_hex(_RANDOM_HEX // 2)}.tmp")


def _stale_pattern(name: str) -> re.Pattern[str]:
    # ``.NAME.<random>.tmp``, a temporary of that temporary (a writer that is itself atomic,
    # called on our temporary: ``..NAME.<random>.tmp.<random>.tmp``), and the pipeline
    # folders of earlier versions (tempfile.mkdtemp's ``.NAME.tmp-<random>``).
    n = re.escape(name)
    return re.compile(rf"^(?:\.\.?{n}\.{_RANDOM}\.tmp(?:\.{_RANDOM}\.tmp)?"
                      rf"|\.{n}\.tmp-[a-z0-9_]{{8}})$")


def stale_temporaries(target: Path) -> list[Path]:
    """Return the temporaries of ``target`` in its folder (left there by a killed run)."""
    target = Path(target)
    folder = target.parent
    if not folder.is_dir():
        return []
    pattern = _stale_pattern(target.name)
    return sorted(p for p in folder.iterdir() if pattern.match(p.name))


def remove_stale_temporaries(target: Path) -> None:
    """Remove the temporaries of ``target`` (files, or folders with what they hold) left in
    its folder by an earlier, killed run."""
    for path in stale_temporaries(target):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink(missing_ok=True)


def make_folders(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return the folders created.

    Give the list to :func:`remove_empty_folders` once the outputs are written or have
    failed: the folders of outputs that were not written are removed again. If a folder
    cannot be made (OSError), those made before it are removed again.
    """
    folder = Path(folder)
    missing = list(itertools.takewhile(lambda p: not p.exists(), (folder, *folder.parents)))
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        remove_empty_folders(missing)
        raise
    return missing


def remove_empty_folders(folders: Iterable[Path]) -> None:
    """Remove those of ``folders`` that are empty, deepest first (a folder that holds an
    output, or anything else, is kept)."""
    for folder in sorted(folders, key=lambda p: len(p.parts), reverse=True):
        with contextlib.suppress(OSError):  # not empty (or already gone): kept
            folder.rmdir()


def unwritable(option: str, path: Path, exc: OSError, expected: str = "a writable file"
               ) -> TappError:
    """Return the one-line error of output ``path`` (named by ``option``) whose writing raised
    ``exc``: an InputError (exit 2) when the path is at fault (a folder that is read-only or
    immutable, a file where a folder should be), else a WriteError (exit 1: a full disk, a
    device error). Either names the path asked for, never a temporary."""
    reason = exc.strerror or type(exc).__name__
    if exc.errno in _PATH_ERRNOS:
        return InputError(option, str(path), expected, reason)
    return WriteError(option, str(path), reason)


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


def written_in_place(path: Path) -> bool:
    """Whether ``path`` is an existing device, pipe or socket (``/dev/null``, a FIFO,
    ``/dev/stdout`` on a pipe), which an output is written into, never renamed over: a rename
    would replace the device itself with a regular file (``--json /dev/null`` run as root
    did that to the machine's ``/dev/null``)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def check_writable(option: str, path: Path) -> None:
    """Raise InputError naming ``option`` unless ``path`` can be created or replaced.

    ``path`` must not be a folder, and the nearest existing folder above it must be a
    writable folder (missing folders are created when the output is written); a device or a
    pipe (:func:`written_in_place`) must be writable itself.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(option, str(path), "a file path, not a folder")
    if written_in_place(path):
        if not os.access(path, os.W_OK):
            raise InputError(option, str(path), "a device or pipe this user can write")
        return
    check_folder(option, path)


def check_folder(option: str, path: Path) -> None:
    """Raise InputError naming ``option`` unless the nearest existing folder above ``path``
    is a folder that can be written (``path`` itself, a file or a folder, is not checked)."""
    path = Path(path)
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
    """Return ``out_dir`` if it does not exist or is an empty folder, in a folder that can be
    written, else raise.

    Raises
    ------
    InputError
        Naming ``option``: a file, a folder with something in it (never overwritten; ``why``
        says so in the command's words), a symbolic link (the finished folder is renamed
        into place: it would replace the link), or a path in a folder that is a file or
        cannot be written.
    """
    out_dir = Path(out_dir)
    if out_dir.is_symlink():
        raise InputError(option, "directory", "a new or empty directory, not a symbolic link "
                         "(the finished run is renamed into place)", str(out_dir))
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())):
        raise InputError(option, "directory", f"a new or empty directory ({why})",
                         str(out_dir))
    check_folder(option, out_dir)
    return out_dir


@contextmanager
def new_directory(out_dir: Path, option: str, why: str) -> Iterator[Path]:
    """Yield a hidden folder beside ``out_dir`` to write into; rename it to ``out_dir`` when
    the block completes, remove it if the block raises (or a signal stops it).

    ``out_dir`` must be new or empty (:func:`check_new_directory`); missing parents are
    created, and removed again unless the block completes. The hidden folder is named
    :func:`temporary_name` of ``out_dir``: those that runs killed outright left are removed
    first (:func:`remove_stale_temporaries`).

    Raises
    ------
    InputError
        ``out_dir`` is not new or empty, or its folder cannot be written (names ``option``).
    WriteError
        The folder could not be written for want of room, or a device error (an OSError
        that names no file, or one in the hidden folder: :func:`unwritable`).

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with new_directory(folder / "run", "-o", "never overwritten") as work:
    ...     _ = (work / "a.txt").write_text("a")
    >>> [p.name for p in (folder / "run").iterdir()], [p.name for p in folder.iterdir()]
    (['a.txt'], ['run'])
    >>> shutil.rmtree(folder)
    """
    out_dir = check_new_directory(out_dir, option, why)
    work = temporary_name(out_dir)
    created: list[Path] = []
    try:
        try:
            created += make_folders(out_dir.parent)
            remove_stale_temporaries(out_dir)
            work.mkdir()
        except OSError as exc:
            raise unwritable(option, out_dir, exc, "a writable directory") from None
        yield work
        if out_dir.exists():
            out_dir.rmdir()
        work.rename(out_dir)
    except OSError as exc:
        # A failed write() names no file; a file read on the way (elsewhere) is not ours.
        if exc.filename is not None and not any(
                Path(exc.filename).is_relative_to(p) for p in (work, out_dir)):
            raise
        raise unwritable(option, out_dir, exc, "a writable directory") from None
    finally:
        shutil.rmtree(work, ignore_errors=True)  # renamed away when the block completed
        remove_empty_folders(created)  # the one holding out_dir is not empty: kept


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
            A file or folder cannot be written: the path is at fault (names the option and
            the requested path; :func:`unwritable`).
        WriteError
            A file cannot be written for want of room, or a device error (the same names).
        Exception
            Whatever a ``write`` raises; then no output has been replaced, and no temporary
            and no folder made for the outputs is left.
        """
        with self.staged() as paths:
            return paths

    @contextmanager
    def staged(self) -> Iterator[tuple[Path, ...]]:
        """Write every output to its temporary, run the block, then rename them all over
        their targets: :meth:`commit` with a block between the writing and the renaming.

        The block runs once every output is complete and none is in place yet: what it does
        (print the report that says the outputs are written) can still fail, and then, as
        when a ``write`` fails, no output is replaced, and no temporary and no folder made
        for the outputs is left. Yields the outputs' paths, in the order added; raises as
        :meth:`commit`, and whatever the block raises.
        """
        written: list[tuple[_Output, Path]] = []
        created: list[Path] = []
        in_place: list[_Output] = []
        files: list[_Output] = []
        for out in self._outputs:
            (in_place if written_in_place(out.path) else files).append(out)
        current = None
        try:
            for out in files:
                current = out
                created += make_folders(out.path.parent)
                remove_stale_temporaries(out.path)
            for out in files:
                current = out
                tmp = temporary_name(out.path)
                written.append((out, tmp))
                out.write(tmp)
                os.chmod(tmp, FILE_MODE)
            current = None  # what the block raises is its own, not an output's
            yield tuple(out.path for out in self._outputs)
            for out, tmp in written:
                current = out
                os.replace(tmp, out.path)
            for out in in_place:  # last: what a device or pipe takes cannot be taken back
                current = out
                out.write(out.path)
        except OSError as exc:
            if current is None:
                raise
            raise unwritable(current.option, current.path, exc) from None
        finally:
            for _, tmp in written:
                tmp.unlink(missing_ok=True)
            remove_empty_folders(created)  # those of outputs written hold them: kept
            self._outputs.clear()
