"""MkDocs hooks of the reference site (docs/mkdocs.yml): the pages that live elsewhere in the
repository (the tutorial, the file reference of docs/reference/) and one API page per package,
each listing its modules for mkdocstrings, are added at build time, so nothing is copied."""

from __future__ import annotations

import pkgutil
from importlib.util import find_spec
from pathlib import Path

from mkdocs.structure.files import File, Files

DOCS = Path(__file__).parent
ROOT = DOCS.parent
#: The packages of the API reference, in the order of the navigation: the front door first,
#: then the programs' layers from the top down, then the two generic engines.
PACKAGES = ("tapp", "tapp.api", "tapp.pipeline", "tapp.report", "tapp.tracking",
            "tapp.processor", "tapp.guidance", "tapp.targeting", "tapp.od", "tapp.io",
            "tapp.frames", "tapp.orbit", "tapp.dynamics", "tapp.measurements",
            "tapp.estimation", "search", "iter")
#: Packages documented on their parent's page rather than their own.
SUBPACKAGES_INLINE = ("tapp.io.tape", "tapp.io.ccsds")


def _modules(package: str) -> list[str]:
    """The modules of ``package`` (found on disk, not imported), sub-packages inlined where
    :data:`SUBPACKAGES_INLINE` says so, the ``__main__`` and CLI modules left out."""
    spec = find_spec(package)
    names = []
    for info in pkgutil.iter_modules(spec.submodule_search_locations):
        name = f"{package}.{info.name}"
        if info.name.startswith("_"):
            continue
        if info.ispkg:
            if name in SUBPACKAGES_INLINE:
                names.append(name)
                names.extend(_modules(name))
            continue
        names.append(name)
    return names


def _api_page(package: str) -> str:
    """The Markdown of one package's page: its own docstring, then each module's."""
    lines = [f"# `{package}`", "", f"::: {package}", "    options:",
             "      members: false", "      show_root_heading: false", ""]
    for module in _modules(package):
        lines += [f"::: {module}", ""]
    return "\n".join(lines)


def on_config(config):
    config.nav = [
        {"Home": "index.md"},
        {"Tutorial": "tutorial.md"},
        {"Input files": [f"reference/{p.name}" for p in sorted((DOCS / "reference").glob("*.md"))]},
        {"API": [{name: f"api/{name}.md"} for name in PACKAGES]},
    ]
    return config


def on_files(files: Files, config) -> Files:
    for path in [DOCS / "tutorial.md", *sorted((DOCS / "reference").glob("*.md"))]:
        uri = path.relative_to(DOCS).as_posix()
        files.append(File.generated(config, uri, abs_src_path=str(path)))
    for package in PACKAGES:
        files.append(File.generated(config, f"api/{package}.md", content=_api_page(package)))
    return files
