"""``tapp examples DIR``: copy the shipped example input files into a folder to start from."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from tapp.cli.common import app, run_guarded


@app.command("examples")
def examples_cmd(
    directory: Annotated[Path, typer.Argument(help="Folder to create (new or empty).")],
) -> None:
    """Copy every example input file (scenarios, decks, guidance, pipeline, sweeps, SEARCH,
    the study) into DIRECTORY, and list them with their kind (tapp schema KIND)."""
    from tapp.examples import FILES, copy_examples

    def body() -> None:
        copied = copy_examples(directory)
        width = max(len(kind) for kind in FILES.values())
        typer.echo(f"{len(copied)} example files copied into {directory}:")
        for path in copied:
            typer.echo(f"  {FILES[path.name]:<{width}}  {path}")

    run_guarded(body)
