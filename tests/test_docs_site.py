"""The reference site (docs/mkdocs.yml, ``make docs``): it builds with ``--strict``, so a
broken reference in a docstring or a page fails ``make test``; and the check that makes a
reference broken (docs/griffe_roles.py) finds what it should and nothing else."""

from __future__ import annotations

import importlib.util
import logging
import os
import subprocess
import sys
from pathlib import Path

import griffe
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _roles():
    spec = importlib.util.spec_from_file_location("griffe_roles", DOCS / "griffe_roles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def rewrite():
    """``rewrite(text, path)``: ``text`` as the docstring of the object at ``path``, rewritten
    by the extension, with the warnings it logged."""
    roles = _roles()
    collection = griffe.ModulesCollection()
    for root in roles.FIRST_PARTY:
        griffe.load(root, modules_collection=collection, search_paths=[str(ROOT)])
    roles.comment_docstrings(collection, list(roles.FIRST_PARTY))

    def run(text: str, path: str, caplog: pytest.LogCaptureFixture) -> tuple[str, list[str]]:
        obj = collection.get_member(path)
        caplog.clear()
        with caplog.at_level(logging.WARNING):
            out = roles._ROLE.sub(lambda m: roles._link(m, obj, collection), text)
        return roles._fenced_doctests(out), [r.getMessage() for r in caplog.records]

    return run


def test_a_name_is_resolved_as_sphinx_resolves_it(rewrite, caplog):
    """Relative to the module, then absolute; ``~`` shows the last part; an import shows
    where the object lives; a lazy export (``iter``'s, ``tapp``'s) likewise."""
    text, warned = rewrite(":func:`check_paths` and :class:`~tapp.errors.InputError`",
                           "tapp.io.outputs", caplog)
    assert text == ("[`check_paths`][tapp.io.outputs.check_paths] and "
                    "[`InputError`][tapp.errors.InputError]")
    assert warned == []
    text, warned = rewrite(":class:`iter.SweepResult` :meth:`iter.SweepResult.raise_if_all_failed` "
                           ":func:`tapp.simulate`", "tapp.api", caplog)
    assert text == ("[`iter.SweepResult`][iter.run.SweepResult] "
                    "[`iter.SweepResult.raise_if_all_failed`]"
                    "[iter.run.SweepResult.raise_if_all_failed] "
                    "[`tapp.simulate`][tapp.api.tracking.simulate]")
    assert warned == []


def test_a_method_finds_its_class_first(rewrite, caplog):
    text, warned = rewrite(":meth:`to_json`", "tapp.api.tracking.SimulateResult.write", caplog)
    assert text == "[`to_json`][tapp.api.tracking.SimulateResult.to_json]"
    assert warned == []


def test_a_constant_documented_by_its_comments_is_linked(rewrite, caplog):
    """``#:`` comments above a constant are its docstring on the site, so it is linked; an
    attribute with neither is not rendered, so it is code without a link (not broken)."""
    text, warned = rewrite(":data:`PARTS`", "tapp.measurements.noise", caplog)
    assert text == "[`PARTS`][tapp.measurements.noise.PARTS]"
    assert warned == []


def test_a_broken_reference_is_a_warning(rewrite, caplog):
    """A first-party name that exists nowhere: mkdocs --strict fails on the warning."""
    text, warned = rewrite(":func:`no_such_function` :mod:`tapp.no_such_module`",
                           "tapp.io.outputs", caplog)
    assert text == "`no_such_function` `tapp.no_such_module`"
    assert len(warned) == 2
    assert "no_such_function" in warned[0] and "tapp.io.outputs" in warned[0]


def test_other_libraries_and_private_names_are_code_without_a_link(rewrite, caplog):
    text, warned = rewrite(":func:`numpy.linalg.qr` :mod:`tempfile` :math:`a^2` "
                           ":func:`_read`", "tapp.io.tape.t13_hdf5", caplog)
    assert text == "`numpy.linalg.qr` `tempfile` `a^2` `_read`"
    assert warned == []


def test_doctests_are_fenced(rewrite, caplog):
    text, _ = rewrite("Sum.\n\n>>> [1][0]\n1\n\nAfter.", "tapp.errors", caplog)
    assert text == "Sum.\n\n```pycon\n>>> [1][0]\n1\n```\n\nAfter."


def test_the_site_builds_strictly(tmp_path):
    """Every docstring's references resolve, every page's links too (mkdocs --strict)."""
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                          "-f", str(DOCS / "mkdocs.yml"), "-d", str(tmp_path / "site")],
                         capture_output=True, text=True, env=env, cwd=ROOT, check=False)
    assert run.returncode == 0, run.stderr[-4000:]
    assert (tmp_path / "site" / "api" / "tapp.api" / "index.html").is_file()
    page = (tmp_path / "site" / "reference" / "deck" / "index.html").read_text()
    assert "command language" in page.lower()


def test_a_parameter_line_is_a_description_not_a_type():
    """``name : what it is`` (the house's Parameters lines) becomes a name and its
    description; ``name : Type`` (one word) stays the NumPy convention's type."""
    roles = _roles()
    text = ("Sum.\n\nParameters\n----------\nraw : also keep the rows.\n    More.\n"
            "scenario : Scenario\n\nReturns\n-------\nx : the tape")
    assert roles._described_parameters(text) == (
        "Sum.\n\nParameters\n----------\nraw\n    also keep the rows.\n    More.\n"
        "scenario : Scenario\n\nReturns\n-------\nx : the tape")
