"""Compare two ``make scenario`` result folders, file by file: "behaviour unchanged" checked.

    python -m scenarios.compare BEFORE AFTER

Every file of either folder is compared with its namesake in the other: JSON field by field,
CSV cell by cell, HDF5 (the tapes, the sweeps' tables) dataset by dataset and attribute by
attribute, PNG pixel by pixel, text line by line. Numbers must be equal exactly (a refactoring
repeats the same IEEE arithmetic; the runs are reproducible for any worker count), except
what measures the run rather than the result, named in :data:`VOLATILE` (wall times, file
sizes, creation dates, the versions and paths written as provenance). Prints one line per
file that differs, with its first differences, and a summary; exits 1 if any file differs
or is missing on one side, 0 otherwise.
"""

from __future__ import annotations

import csv
import json
import re
import sys
from collections.abc import Iterator
from difflib import SequenceMatcher
from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401  (registers the tapes' LZ4 filter with HDF5)
import numpy as np
from matplotlib.image import imread

#: Keys, HDF5 attributes and text lines that measure the run, not its result: compared by
#: presence only. A key matches if any of these patterns is found in it.
VOLATILE = re.compile(r"wall|elapsed|seconds_per|per_s$|^bytes$|created|creation|CREATION"
                      r"|started|finished|updated|git_commit|python|version|platform|host"
                      r"|workers|timing|speed")
#: The run's clock in a text: when the file was written.
STAMP = re.compile(r"CREATION_DATE\s*=\s*\S+|\b[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:.]+ ?(UTC|Z)?")
#: A time measured in a text line ("0.17 s", "3.86 S", "1:44"): masked before lines are
#: compared, so that a line differing only there is the same line.
TIME = re.compile(r"\b[0-9]+(\.[0-9]+)? ?(s|S|ms|min)\b|\b[0-9]+:[0-9]{2}(:[0-9]{2})?\b")
#: An absolute path: the folders differ between two checkouts, the file's name must not.
ABSOLUTE_PATH = re.compile(r"(?<![\w.])/(?:[\w.+-]+/)+")
#: Differences shown per file.
SHOWN = 4


def _same_text(a: str, b: str) -> bool:
    """Whether two strings are equal once their absolute paths are reduced to the files'
    names."""
    return ABSOLUTE_PATH.sub("", a) == ABSOLUTE_PATH.sub("", b)


def json_differences(a: object, b: object, where: str = "") -> Iterator[str]:
    """The paths where two JSON values differ (volatile keys compared by presence only;
    absolute paths by the file's name)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key not in a or key not in b:
                yield f"{where}.{key}: only in {'after' if key in b else 'before'}"
            elif not VOLATILE.search(key):
                yield from json_differences(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            yield f"{where}: {len(a)} items before, {len(b)} after"
        else:
            for i, (x, y) in enumerate(zip(a, b, strict=True)):
                yield from json_differences(x, y, f"{where}[{i}]")
    elif isinstance(a, str) and isinstance(b, str):
        if not _same_text(a, b):
            yield f"{where}: {a!r} -> {b!r}"
    elif a != b and not (isinstance(a, float) and isinstance(b, float)
                         and np.isnan(a) and np.isnan(b)):
        yield f"{where}: {a!r} -> {b!r}"


def _arrays_differ(a: np.ndarray, b: np.ndarray) -> str | None:
    """What differs between two arrays (strings: once their absolute paths are names), or
    None."""
    if a.dtype.kind in "OSU" and b.dtype.kind in "OSU" and a.shape == b.shape == ():
        x, y = (v.decode() if isinstance(v, bytes) else str(v) for v in (a.item(), b.item()))
        if x[:1] in ("{", "[") and y[:1] in ("{", "["):  # JSON held in an attribute
            found = list(json_differences(json.loads(x), json.loads(y)))
            return "; ".join(found[:SHOWN]) or None
        return None if _same_text(x, y) else f"{x[:60]!r} -> {y[:60]!r}"
    if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
        return f"shape/dtype {a.shape} {a.dtype} -> {b.shape} {b.dtype}"
    if a.dtype.kind in "fc":
        same = (a == b) | (np.isnan(a) & np.isnan(b))
    else:
        same = a == b
    if np.all(same):
        return None
    if a.dtype.kind in "fc":
        scale = np.max(np.abs(a[np.isfinite(a)]), initial=0.0)
        diff = np.max(np.abs(np.where(same, 0.0, a - b)))
        return f"{np.count_nonzero(~same)} values differ, max |Δ| {diff:.3g} (scale {scale:.3g})"
    return f"{np.count_nonzero(~same)} values differ"


def hdf5_differences(path_a: Path, path_b: Path) -> Iterator[str]:
    """Datasets and attributes that differ between two HDF5 files (volatile attributes
    compared by presence only)."""
    with h5py.File(path_a, "r") as fa, h5py.File(path_b, "r") as fb:
        items_a, items_b = {}, {}
        fa.visititems(lambda name, obj: items_a.__setitem__(name, obj))
        fb.visititems(lambda name, obj: items_b.__setitem__(name, obj))
        for name in sorted(set(items_a) | set(items_b) | {""}):
            if name and (name not in items_a or name not in items_b):
                yield f"/{name}: only in {'after' if name in items_b else 'before'}"
                continue
            obj_a = items_a[name] if name else fa
            obj_b = items_b[name] if name else fb
            if VOLATILE.search(name.rsplit("/")[-1]):
                continue  # a run's measure: its data and attributes (a checksum) alike
            for key in sorted(set(obj_a.attrs) | set(obj_b.attrs)):
                if key not in obj_a.attrs or key not in obj_b.attrs:
                    yield f"/{name}@{key}: only on one side"
                elif not VOLATILE.search(key):
                    a, b = np.asarray(obj_a.attrs[key]), np.asarray(obj_b.attrs[key])
                    if (found := _arrays_differ(a, b)) is not None:
                        yield f"/{name}@{key}: {found}"
            if isinstance(obj_a, h5py.Dataset):
                if (found := _arrays_differ(obj_a[()], obj_b[()])) is not None:
                    yield f"/{name}: {found}"


def csv_differences(path_a: Path, path_b: Path) -> Iterator[str]:
    """Cells that differ between two CSV files (columns named volatile skipped, absolute
    paths compared by the file's name)."""
    rows_a = list(csv.reader(path_a.read_text().splitlines()))
    rows_b = list(csv.reader(path_b.read_text().splitlines()))
    if len(rows_a) != len(rows_b) or (rows_a and rows_a[0] != rows_b[0]):
        yield f"{len(rows_a)} rows before, {len(rows_b)} after (or another header)"
        return
    header = rows_a[0] if rows_a else []
    for i, (ra, rb) in enumerate(zip(rows_a[1:], rows_b[1:], strict=True), start=2):
        for column, x, y in zip(header, ra, rb, strict=True):
            if not _same_text(x, y) and not VOLATILE.search(column):
                yield f"line {i}, {column}: {x} -> {y}"


def _tokens(text: str) -> list[str]:
    """The words of a text once the run's dates, times measured and absolute paths are
    masked: a line wrapped elsewhere (a longer path) is the same text."""
    return ABSOLUTE_PATH.sub("", TIME.sub("<time>", STAMP.sub("<date>", text))).split()


def text_differences(path_a: Path, path_b: Path) -> Iterator[str]:
    """The passages where two texts differ, word by word (:func:`_tokens`)."""
    a, b = _tokens(path_a.read_text()), _tokens(path_b.read_text())
    matcher = SequenceMatcher(None, a, b, autojunk=False)
    for op, i1, i2, j1, j2 in matcher.get_opcodes():
        if op != "equal":
            yield (f"word {i1 + 1}: ...{' '.join(a[max(i1 - 4, 0):i2 + 2])[:90]!r} -> "
                   f"{' '.join(b[max(j1 - 4, 0):j2 + 2])[:90]!r}")


def png_differences(path_a: Path, path_b: Path) -> Iterator[str]:
    """Pixels that differ between two PNG images."""
    found = _arrays_differ(imread(path_a), imread(path_b))
    if found is not None:
        yield f"pixels: {found}"


def differences(path_a: Path, path_b: Path) -> Iterator[str]:
    """The differences of two files of the same name, by their kind."""
    suffix = path_a.suffix
    if suffix == ".json":
        yield from json_differences(json.loads(path_a.read_text()),
                                    json.loads(path_b.read_text()))
    elif suffix == ".h5":
        yield from hdf5_differences(path_a, path_b)
    elif suffix == ".csv":
        yield from csv_differences(path_a, path_b)
    elif suffix == ".png":
        yield from png_differences(path_a, path_b)
    else:
        yield from text_differences(path_a, path_b)


def compare(before: Path, after: Path) -> int:
    """Print the files that differ; return how many differ or exist on one side only."""
    names = sorted({p.relative_to(before) for p in before.rglob("*") if p.is_file()}
                   | {p.relative_to(after) for p in after.rglob("*") if p.is_file()})
    bad = 0
    for name in names:
        a, b = before / name, after / name
        if not (a.is_file() and b.is_file()):
            print(f"{name}: only {'after' if b.is_file() else 'before'}")
            bad += 1
            continue
        found = list(differences(a, b))
        if found:
            bad += 1
            print(f"{name}: {len(found)} differences")
            for line in found[:SHOWN]:
                print(f"    {line}")
    print(f"{len(names)} files compared, {bad} differ")
    return bad


def main(argv: list[str]) -> int:
    if len(argv) != 2 or not all(Path(a).is_dir() for a in argv):
        print("usage: python -m scenarios.compare BEFORE AFTER  (two results folders)",
              file=sys.stderr)
        return 2
    return 1 if compare(Path(argv[0]), Path(argv[1])) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
