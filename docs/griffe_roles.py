"""A Griffe extension for the reference site: the docstrings' reST cross-reference roles
(``:func:`name```, ``:class:`~pkg.mod.Name```, ``:mod:``, ``:data:``, ``:attr:``, ``:meth:``)
become MkDocs autorefs, resolved as Sphinx resolves them (the object's class, then its module,
then each enclosing package, then the name as written), and doctest blocks become code blocks.

A reference to a first-party object (``tapp``, ``search``, ``iter``) that exists nowhere is
logged as a Griffe warning naming the docstring, which ``mkdocs build --strict`` turns into a
failed build: this is the broken-reference check of the site. A reference to a private or
otherwise undocumented object that does exist renders as code without a link; one to another
library (``numpy``, ``fnmatch``, ...) likewise. ``:math:`` renders as code.
"""

from __future__ import annotations

import ast
import re
import sys

import griffe

FIRST_PARTY = ("tapp", "search", "iter")
#: First-party modules whose pages the site does not render (docs/hooks.py documents the
#: library, not the command line or the example files).
UNDOCUMENTED = ("tapp.cli", "tapp.examples")

_ROLE = re.compile(r":(?P<role>func|class|mod|data|attr|meth|exc|obj|math):"
                   r"`(?P<body>[^`]+)`")
_TITLED = re.compile(r"^(?P<title>.*?)\s*<(?P<target>[^<>]+)>$", re.DOTALL)
_DOCTEST = re.compile(r"^(?P<indent>[ \t]*)>>> ")
_PARAMETER = re.compile(r"^(?P<indent>[ \t]*)(?P<names>\*{0,2}\w+(?:, \*{0,2}\w+)*) : "
                        r"(?P<text>.*)$")


class SphinxRoles(griffe.Extension):
    """Rewrite every docstring of the first-party packages (see the module docstring), once
    the first of them is loaded: the others are loaded then too, for the references across
    them, and rewritten at once (Griffe announces only the packages its loader was asked
    for)."""

    def __init__(self) -> None:
        super().__init__()
        self.rewritten: set[str] = set()

    def on_package(self, *, pkg: griffe.Module, **kwargs: object) -> None:
        if pkg.name not in FIRST_PARTY:
            return
        collection = pkg.modules_collection
        for root in FIRST_PARTY:
            if root not in collection:
                griffe.load(root, modules_collection=collection,
                            search_paths=[str(pkg.filepath.parent.parent)])
        roots = [root for root in FIRST_PARTY if root not in self.rewritten]
        self.rewritten.update(roots)
        comment_docstrings(collection, roots)  # first, so a reference knows its target's
        for root in roots:
            for obj in _walk(collection[root]):
                if obj.docstring is not None:
                    obj.docstring.value = _described_parameters(_fenced_doctests(_ROLE.sub(
                        lambda m, o=obj: _link(m, o, collection), obj.docstring.value)))


def comment_docstrings(collection: griffe.ModulesCollection, roots: list[str]) -> None:
    """Give every attribute of the ``roots`` packages without a docstring its ``#:`` comments
    (:func:`_comment_docstring`)."""
    for root in roots:
        for obj in _walk(collection[root]):
            if obj.docstring is None and obj.is_attribute:
                _comment_docstring(obj)


def _comment_docstring(obj: griffe.Attribute) -> None:
    """Give an attribute documented by ``#:`` comments above it (the Sphinx convention this
    project uses for constants and fields) those comments as its docstring."""
    lines = obj.module.lines
    if obj.lineno is None or not lines:
        return
    comments = []
    for line in reversed(lines[:obj.lineno - 1]):
        stripped = line.strip()
        if not stripped.startswith("#:"):
            break
        comments.append(stripped[2:].strip())
    if comments:
        obj.docstring = griffe.Docstring("\n".join(reversed(comments)), parent=obj)


def _walk(obj: griffe.Object):
    """``obj`` and every object defined in it (aliases, i.e. imports, left out)."""
    yield obj
    for member in obj.members.values():
        if not member.is_alias:
            yield from _walk(member)


def _link(match: re.Match, obj: griffe.Object, collection: griffe.ModulesCollection) -> str:
    """The Markdown of one role: an autoref where the target is documented, code otherwise."""
    role, body = match["role"], " ".join(match["body"].split())
    if role == "math":
        return f"`{body}`"
    titled = _TITLED.match(body)
    target = "".join((titled["target"] if titled else body).split())
    short = target.startswith("~")
    target = target.lstrip("~!.")
    title = titled["title"] if titled else (target.rsplit(".", 1)[-1] if short else target)
    path = _resolve(target, obj, collection)
    if path is None:
        if target.split(".")[0] in FIRST_PARTY or _local(target, obj):
            griffe.logger.warning(
                "%s:%s: broken reference :%s:`%s` in the docstring of %s", obj.relative_filepath,
                obj.lineno, role, body, obj.path)
        return f"`{title}`"
    if _documented(path, collection):
        return f"[`{title}`][{path}]"
    return f"`{title}`"


def _local(target: str, obj: griffe.Object) -> bool:
    """Whether ``target`` reads as a name of this project (not another library's): a bare
    name other than a standard-library module's, or a dotted one whose first part the
    object's module defines or imports from this project."""
    head, _, rest = target.partition(".")
    if not rest:
        return head not in sys.stdlib_module_names
    member = obj.module.members.get(head)
    if member is None:
        return False
    return not member.is_alias or member.target_path.split(".")[0] in FIRST_PARTY


def _scopes(obj: griffe.Object) -> list[str]:
    """Where a relative name is looked up, innermost first: the class (for a method, its
    class), the module, then each enclosing package."""
    scopes = []
    node = obj if obj.is_class or obj.is_module else obj.parent
    while node is not None:
        scopes.append(node.path)
        node = node.parent
    return scopes


def _resolve(target: str, obj: griffe.Object, collection: griffe.ModulesCollection
             ) -> str | None:
    """The canonical path of ``target`` seen from ``obj``, or None where nothing first-party
    has that name."""
    for candidate in [f"{scope}.{target}" for scope in _scopes(obj)] + [target]:
        if candidate.split(".")[0] not in FIRST_PARTY:
            continue
        found = _member(collection, candidate)
        if found is None:
            lazy = _lazy_target(candidate, collection)
            if lazy is None:
                continue
            return lazy
        return found.path
    return None


def _lazy_target(path: str, collection: griffe.ModulesCollection) -> str | None:
    """``path`` through a package's lazy exports (PEP 562: ``tapp._LAZY`` maps a name to
    ``"module:attribute"``, ``iter._HOMES`` a name to its module in the package), the rest of
    the path (a method, an attribute) looked up in what the export names; or None."""
    parts = path.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        package, name, rest = ".".join(parts[:cut]), parts[cut], parts[cut + 1:]
        module = _member(collection, package)
        if module is None:
            continue
        home = _lazy_homes(module).get(name)
        if home is None:
            continue
        target = home.replace(":", ".") if ":" in home else f"{package}.{home}.{name}"
        found = _member(collection, ".".join([target, *rest]))
        return None if found is None else found.path
    return None


def _lazy_homes(module: griffe.Object) -> dict[str, str]:
    """The module's table of lazy exports (``_LAZY`` or ``_HOMES``, a dict literal), or {}."""
    for table in ("_LAZY", "_HOMES"):
        attribute = module.members.get(table)
        if attribute is not None and not attribute.is_alias and attribute.value is not None:
            return ast.literal_eval(str(attribute.value))
    return {}


def _documented(path: str, collection: griffe.ModulesCollection) -> bool:
    """Whether the site renders ``path`` (its mkdocstrings heading is an autoref anchor):
    a first-party object outside :data:`UNDOCUMENTED` with no private name on its path and a
    docstring (its own, its ``#:`` comments' or a member's: the site shows only those)."""
    if path.split(".")[0] not in FIRST_PARTY:
        return False
    if any(path == u or path.startswith(u + ".") for u in UNDOCUMENTED):
        return False
    parts = path.split(".")
    if any(p.startswith("_") and not (p.startswith("__") and p.endswith("__")) for p in parts):
        return False
    obj = _member(collection, path)
    return (obj is not None and obj.has_docstrings
            and not (obj.parent is not None and obj.parent.is_function))


def _member(collection: griffe.ModulesCollection, path: str) -> griffe.Object | None:
    """The object at ``path`` in the loaded packages (an import: what it imports; a class's
    member: inherited ones too), or None (no such name, or a path through an import of
    another library, which Griffe has not loaded)."""
    head, *parts = path.split(".")
    try:
        found = collection[head]
        for part in parts:
            members = found.all_members if found.is_class else found.members
            found = members[part]
            found = found.final_target if found.is_alias else found
    except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None
    return found


def _fenced_doctests(text: str) -> str:
    """Each doctest block (``>>>`` lines and their output, up to a blank line) fenced as a
    Python console code block, so Markdown leaves its brackets and asterisks alone."""
    out, block, indent = [], False, ""
    for line in text.split("\n"):
        doctest = _DOCTEST.match(line)
        if doctest and not block:
            indent = doctest["indent"]
            out.append(f"{indent}```pycon")
            block = True
        elif block and not line.strip():
            out.append(f"{indent}```")
            block = False
        out.append(line)
    if block:
        out.append(f"{indent}```")
    return "\n".join(out)


def _described_parameters(text: str) -> str:
    """The house's ``name : what it is`` lines of a Parameters section, read by the NumPy
    convention as ``name : type``, rewritten as a name and an indented description (the
    types are in the signature)."""
    lines = text.split("\n")
    out, inside = [], False
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and set(lines[i + 1].strip()) == {"-"} and line.strip():
            inside = line.strip() in ("Parameters", "Other Parameters")
        parameter = _PARAMETER.match(line) if inside else None
        if parameter and " " in parameter["text"].strip():
            indent = parameter["indent"]
            out += [f"{indent}{parameter['names']}", f"{indent}    {parameter['text']}"]
        else:
            out.append(line)
    return "\n".join(out)
