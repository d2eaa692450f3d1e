"""``tapp process``: TAPP III on a T13 tape and a deck -> O3 printout, JSON, plots, T32 tape.

Bad input (the tape, the deck or its fields, an output path that is an input) is one line on
stderr naming the file and the field, exit 2; all outputs are written together or none
(:class:`tapp.outputs.OutputSet`).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

from tapp.cli.common import app, print_json, progress_bar, run_guarded
from tapp.outputs import OutputSet, check_paths
from tapp.pipeline.steps import process_tape
from tapp.processor.deck import read_deck
from tapp.processor.printout import o3_text, run_dict
from tapp.processor.sequencing import Run
from tapp.processor.tape32 import build_t32, t32_provenance
from tapp.report import BPLANE_PNG, SIGMA_PNG
from tapp.tape.t32_hdf5 import t32_file_writer


def _run(tape: Path, deck_path: Path, quiet: bool) -> tuple[Run, object, object, float]:
    deck = read_deck(deck_path)
    start = time.perf_counter()
    columns = (TextColumn("{task.description:<12}"), BarColumn(),
               TextColumn("record {task.completed}/{task.total}"), TimeElapsedColumn())
    with progress_bar(*columns, quiet=quiet) as bar:
        task = bar.add_task("TAPP III", total=None)

        def progress(k: int, n_it: int) -> None:
            bar.update(task, completed=k, total=n_it)

        run, plan, header = process_tape(tape, deck, str(deck_path), progress)
    return run, plan, (header, deck), time.perf_counter() - start


@app.command("process")
def process_cmd(
    tape: Annotated[Path, typer.Argument(help="T13 tape (RUN.t13.h5) from tapp simulate.")],
    deck: Annotated[Path, typer.Argument(help="TAPP III deck (TOML).")],
    print_path: Annotated[Path | None, typer.Option("--print", help="Write the O3 printout "
                                                    "here (default: standard output).")] = None,
    tape_out: Annotated[Path | None, typer.Option("--tape", help="Write the T32 tape "
                                                  "(RUN.t32.h5) for TAPP II.")] = None,
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the O3 content as "
                                                   "JSON here ('-' for standard output).")
                         ] = None,
    plots: Annotated[Path | None, typer.Option("--plots", help="Write the PNG plots into "
                                               "this folder.")] = None,
) -> None:
    """TAPP III: process a T13 tape with a deck (fit world vs real world)."""

    def body() -> None:
        json_file = None if json_path is None or str(json_path) == "-" else json_path
        pngs = {} if plots is None else {f"--plots ({name})": plots / name
                                         for name in (SIGMA_PNG, BPLANE_PNG)}
        check_paths({"TAPE": tape, "DECK": deck},
                    {"--print": print_path, "--tape": tape_out, "--json": json_file, **pngs})
        quiet = print_path is None or (json_path is not None and json_file is None)
        run, plan, (header, deck_obj), wall_s = _run(tape, deck, quiet)
        text = o3_text(run, header, str(deck), str(tape))
        content = run_dict(run, header, str(deck), str(tape))
        content["wall_s"] = wall_s
        outputs = OutputSet()
        if print_path is not None:
            outputs.add("--print", print_path, lambda tmp: tmp.write_text(text, "utf-8"))
        if json_file is not None:
            outputs.add("--json", json_file,
                        lambda tmp: tmp.write_text(json.dumps(content), "utf-8"))
        if tape_out is not None:
            t32 = build_t32(run, plan, header,
                            t32_provenance(header, deck_obj, str(deck), str(tape)))
            outputs.add("--tape", tape_out, t32_file_writer(t32, source=str(tape_out)))
        if plots is not None:
            # matplotlib only when plots are asked for (it costs ~0.5 s to import)
            from tapp.report.tapp3 import bplane_rows, plot_bplane_ellipses, plot_sigma_history

            title = f"{header.iden}: {deck_obj.title}" if deck_obj.title else header.iden
            outputs.add("--plots", plots / SIGMA_PNG, lambda tmp: plot_sigma_history(
                run.history, run.history_labels, tmp, f"{title}: σ, fit vs real world"))
            if bplane_rows(run.history, tuple(header.miss.name)):
                outputs.add("--plots", plots / BPLANE_PNG, lambda tmp: plot_bplane_ellipses(
                    run.history, tuple(header.miss.name), tmp, f"{title}: B-plane 1σ/3σ"))
        outputs.commit()
        if json_path is not None and json_file is None:
            print_json(content)
        elif print_path is None:
            typer.echo(text, nl=False)

    run_guarded(body)
