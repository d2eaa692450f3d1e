"""The ``tapp`` console command: one typer app, one module per command, named after it
(``<command>_cmd``; ``od_cmd`` holds the study's ``dc``, ``ekf`` and ``rsig``, which share
their options and set-up).

Only this package imports typer. Each submodule defines its commands on ``app`` (or on a
sub-app it adds); every command turns a ``TappError`` into one line on stderr and a non-zero
exit code through :func:`tapp.cli.common.run_guarded`.
"""

from __future__ import annotations

from tapp.cli import examples_cmd as _examples_cmd  # noqa: F401  (each import registers its commands)
from tapp.cli import guide_cmd as _guide_cmd  # noqa: F401
from tapp.cli import info_cmd as _info_cmd  # noqa: F401
from tapp.cli import iter_cmd as _iter_cmd  # noqa: F401
from tapp.cli import od_cmd as _od_cmd  # noqa: F401
from tapp.cli import pipeline_cmd as _pipeline_cmd  # noqa: F401
from tapp.cli import process_cmd as _process_cmd  # noqa: F401
from tapp.cli import propagate_cmd as _propagate_cmd  # noqa: F401
from tapp.cli import schema_cmd as _schema_cmd  # noqa: F401
from tapp.cli import search_cmd as _search_cmd  # noqa: F401
from tapp.cli import simulate_cmd as _simulate_cmd  # noqa: F401
from tapp.cli import tape_cmd as _tape_cmd  # noqa: F401
from tapp.cli.common import app


def main() -> None:
    """Entry point of the ``tapp`` console script."""
    app()
