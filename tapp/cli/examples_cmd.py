"""``tapp examples DIR``: copy the shipped example input files into a folder to start from."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from tapp.cli.common import JsonOpt, app, delivering, json_file, run_guarded


@contextmanager
def copying_examples(out_dir: Path, option: str = "DIR") -> Iterator[tuple[Path, ...]]:
    """Copy every shipped file (:data:`tapp.examples.FILES`, some in a folder of their own)
    into ``out_dir``, a new or empty folder.

    The files are written into a hidden folder beside ``out_dir`` and renamed to it once
    the block has run (the report of the copies printed): nothing is left half-copied, and
    nothing at all if the block raises.

    Yields
    ------
    tuple of Path
        The copies, in the order of :data:`tapp.examples.FILES`.

    Raises
    ------
    InputError
        Naming ``option``: ``out_dir`` is a file or a folder with something in it.
    """
    from tapp.examples import FILES, FOLDER
    from tapp.io.outputs import new_directory

    with new_directory(out_dir, option, "examples are copied into a folder of their own, "
                       "never over files") as work:
        for name in FILES:
            (work / name).parent.mkdir(exist_ok=True)  # the mission/ and mars/ folders
            shutil.copyfile(FOLDER / name, work / name)
        yield tuple(Path(out_dir) / name for name in FILES)


@app.command("examples")
def examples_cmd(
    directory: Annotated[Path, typer.Argument(help="Folder to create (new or empty).")],
    json_out: JsonOpt = None,
) -> None:
    """Copy every example input file (scenarios, decks, guidance, pipeline, sweeps, SEARCH,
    the study, a mission folder with its own OEM and pass schedule, and a Mars transfer) into
    DIRECTORY, and
    list them with their kind (tapp schema KIND)."""
    from tapp.examples import FILES
    from tapp.io.outputs import check_paths

    def body() -> None:
        check_paths({}, {"--json": json_file(json_out)})
        with copying_examples(directory) as copied:
            files = [{"kind": kind, "path": str(path)}
                     for kind, path in zip(FILES.values(), copied, strict=True)]
            with delivering(json_out, {"directory": str(directory), "files": files}) as report:
                if report:
                    width = max(len(kind) for kind in FILES.values())
                    typer.echo(f"{len(copied)} example files copied into {directory}:")
                    for file in files:
                        typer.echo(f"  {file['kind']:<{width}}  {file['path']}")

    run_guarded(body)
