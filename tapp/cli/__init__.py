"""The ``tapp`` console command: one typer app, one module per subcommand group.

Only this package imports typer. Each submodule defines its commands on ``app`` (or on a
sub-app it adds); every command turns a ``TappError`` into one line on stderr and a non-zero
exit code through :func:`tapp.cli.common.run_guarded`.
"""

from __future__ import annotations

from tapp.cli import examples_cmd as _examples_cmd  # noqa: F401
from tapp.cli import guide_cmd as _guide_cmd  # noqa: F401
from tapp.cli import info as _info  # noqa: F401  (each import registers its commands)
from tapp.cli import od as _od  # noqa: F401
from tapp.cli import pipeline_cmd as _pipeline_cmd  # noqa: F401
from tapp.cli import process_cmd as _process_cmd  # noqa: F401
from tapp.cli import propagate as _propagate  # noqa: F401
from tapp.cli import schema_cmd as _schema_cmd  # noqa: F401
from tapp.cli import search_cmd as _search_cmd  # noqa: F401
from tapp.cli import sweep as _sweep  # noqa: F401
from tapp.cli import tracking_cmd as _tracking_cmd  # noqa: F401
from tapp.cli.common import app


def main() -> None:
    """Entry point of the ``tapp`` console script."""
    app()
