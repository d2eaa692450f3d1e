"""Reading scenario files (TOML), with errors that name the file; rewriting some tables.

Every file type is then validated against its declared schema (:mod:`tapp.io.schema`), which
checks the numbers, the types and the keys, and names the field. :func:`replace_tables`
rewrites a file's text with some tables replaced or removed and everything else (comments,
layout) kept, as ``tapp search --write-scenario`` needs.
"""

from __future__ import annotations

import copy
import json
import math
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

from iter import inputfile
from tapp.errors import InputError


def read_toml(path: Path | str) -> dict:
    """Return the parsed TOML document at ``path``.

    Raises
    ------
    InputError
        The file is missing, not a regular file (a FIFO, a device), larger than
        :data:`iter.inputfile.MAX_TOML_BYTES`, unreadable, not UTF-8 text, or not valid TOML,
        naming the file (:func:`iter.inputfile.read_toml`).
    """
    return inputfile.read_toml(path, "TOML file", error=InputError)


#: A table header line ``[name]`` or ``[[name]]`` (bare keys and dots), with a comment.
_HEADER = re.compile(r"^\s*\[\[?\s*([A-Za-z0-9_\-]+(?:\s*\.\s*[A-Za-z0-9_\-]+)*)\s*\]\]?"
                     r"\s*(?:#.*)?$")


def _toml_value(value: object) -> str:
    """TOML text of a number, boolean, string, list or mapping (inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"not a finite number: {value!r}")
        return repr(value)  # the shortest text that reads back to the same float
    if isinstance(value, int | str):
        return json.dumps(value)  # ints as digits, strings with TOML-compatible escapes
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise ValueError(f"no TOML text for {type(value).__name__}")


def replace_tables(text: str, source: str, tables: Mapping[str, Mapping | None], *,
                   comment: str = "") -> str:
    """Return TOML ``text`` with tables replaced (a mapping) or removed (None).

    Tables are named by their dotted path (``injection``, ``search.targets``). A replaced
    table keeps its ``[name]`` header line and gets the new keys (``key = value``; the first
    one replaced after ``comment`` as comment lines); its sub-tables ``[name.*]``, and a
    removed table with its sub-tables and the comment lines right above their headers, go.
    Everything else is kept as it was. The result is read back and must equal the document
    read from ``text`` with those tables changed.

    Raises
    ------
    InputError
        Naming ``source`` and the tables, when one is not written as a ``[name]`` header
        followed by its keys (an inline table, dotted keys), so it cannot be replaced.
    """
    expected = copy.deepcopy(tomllib.loads(text))
    for name, value in tables.items():
        *parents, last = name.split(".")
        table = expected
        for part in parents:
            table = table.setdefault(part, {})
        if value is None:
            table.pop(last, None)
        else:
            table[last] = dict(value)
    out: list[str] = []
    dropping = False
    for line in text.splitlines():
        match = _HEADER.match(line)
        if match:
            key = re.sub(r"\s*\.\s*", ".", match.group(1))
            dropping = (key in tables and tables[key] is None) or any(
                key.startswith(f"{name}.") for name in tables)
            while dropping and out and out[-1].lstrip().startswith("#"):
                out.pop()  # the comment that introduces a table removed
            if key in tables and tables[key] is not None:
                out.append(line)
                out.extend(f"# {part}" for part in comment.splitlines())
                comment = ""  # in the first table replaced only
                out.extend(f"{k} = {_toml_value(v)}" for k, v in tables[key].items())
                out.append("")
                dropping = True  # the old keys of the replaced table
                continue
        if not dropping:
            out.append(line)
    result = "\n".join(out) + "\n"
    if tomllib.loads(result) != expected:
        names = ", ".join(f"[{name}]" for name in tables)
        raise InputError(source, "/".join(tables), f"tables {names} written as a header "
                         "followed by their keys (not inline or as dotted keys), so that they "
                         "can be rewritten")
    return result
