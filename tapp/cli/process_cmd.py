"""``tapp process``: TAPP III on a T13 tape and a deck -> O3 printout, JSON, plots, T32 tape.

Bad input (the tape, the deck or its fields, an output path that is an input) is one line on
stderr naming the file and the field, exit 2; all outputs are written together or none
(:class:`tapp.io.outputs.OutputSet`). The run ends with one line saying what was written and
the largest real-world over fit-world σ (:func:`tapp.processor.printout.largest_sigma_ratio`),
on standard output, or on stderr when standard output carries the O3 printout or the JSON.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import (
    STDOUT,
    JsonOpt,
    app,
    delivering,
    json_file,
    progress_bar,
    run_guarded,
)

if TYPE_CHECKING:
    from tapp.api.processing import ProcessResult
    from tapp.processor.printout import SigmaRatio



def _run(tape: Path, deck: Path, quiet: bool) -> ProcessResult:
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    from tapp.api.processing import process

    columns = (TextColumn("{task.description:<12}"), BarColumn(),
               TextColumn("record {task.completed}/{task.total}"), TimeElapsedColumn())
    with progress_bar(*columns, quiet=quiet) as bar:
        task = bar.add_task("TAPP III", total=None)

        def progress(k: int, n_it: int) -> None:
            bar.update(task, completed=k, total=n_it)

        return process(tape, deck, progress=progress)


def summary_line(written: list[str], worst: SigmaRatio | None) -> str:
    """The last line of ``tapp process``: what was written, the largest real/fit σ ratio.

    >>> from tapp.processor.printout import SigmaRatio
    >>> summary_line(["O3 printout o3.txt", "T32 tape run.t32.h5"],
    ...              SigmaRatio(380.1, "vx_km_s@current", "print", 30 * 86400.0))
    'TAPP III: wrote O3 printout o3.txt, T32 tape run.t32.h5; largest real/fit σ ratio 380.1 \
(vx_km_s@current, print at t = 30.000 d)'
    """
    from tapp.constants import SECONDS_PER_DAY  # here: the module loads numpy

    ratio = ("no fit-world σ to compare" if worst is None else
             f"largest real/fit σ ratio {worst.ratio:.4g} ({worst.name}, {worst.kind} at t = "
             f"{worst.t_s / SECONDS_PER_DAY:.3f} d)")
    return f"TAPP III: wrote {', '.join(written)}; {ratio}"


@app.command("process")
def process_cmd(
    tape: Annotated[Path, typer.Argument(help="T13 tape (RUN.t13.h5) from tapp simulate.")],
    deck: Annotated[Path, typer.Argument(help="TAPP III deck (TOML).")],
    print_path: Annotated[Path | None, typer.Option("--print", help="Write the O3 printout "
                                                    "here [default: standard output].")] = None,
    tape_out: Annotated[Path | None, typer.Option("--tape", help="Write the T32 tape "
                                                  "(RUN.t32.h5) for TAPP II.")] = None,
    json_out: JsonOpt = None,
    plots: Annotated[Path | None, typer.Option("--plots", help="Write the PNG plots into "
                                               "this folder (σ against time; the B-plane "
                                               "ellipses; RIC σ, with a CSV, when the deck "
                                               "asks for RIC axes).")] = None,
) -> None:
    """TAPP III: process a T13 tape with a deck (fit world vs real world)."""

    def body() -> None:
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.io.tape.t32_hdf5 import t32_file_writer
        from tapp.processor.printout import largest_sigma_ratio
        from tapp.report import BPLANE_PNG, RIC_CSV, RIC_PNG, SIGMA_PNG

        pngs = {} if plots is None else {f"--plots ({name})": plots / name
                                         for name in (SIGMA_PNG, BPLANE_PNG, RIC_PNG, RIC_CSV)}
        check_paths({"TAPE": tape, "DECK": deck}, {"--print": print_path, "--tape": tape_out,
                                                   "--json": json_file(json_out), **pngs})
        result = _run(tape, deck, quiet=print_path is None or json_out == STDOUT)
        run, header, deck_obj = result.run, result.header, result.deck
        text = result.o3()
        content = result.to_json()
        outputs = OutputSet()
        written: list[str] = []
        if print_path is not None:
            outputs.add("--print", print_path, lambda tmp: tmp.write_text(text, "utf-8"))
            written.append(f"O3 printout {print_path}")
        elif json_out != STDOUT:
            written.append("O3 printout on standard output")
        if json_out is not None:
            written.append(f"JSON {'on standard output' if json_out == STDOUT else json_out}")
        if tape_out is not None:
            outputs.add("--tape", tape_out, t32_file_writer(result.t32(),
                                                            source=str(tape_out)))
            written.append(f"T32 tape {tape_out}")
        if plots is not None:
            # matplotlib only when plots are asked for (it costs ~0.5 s to import)
            from tapp.report.processor import (
                bplane_rows,
                plot_bplane_ellipses,
                plot_ric_history,
                plot_sigma_history,
                ric_csv,
                ric_rows,
            )

            title = f"{header.iden}: {deck_obj.title}" if deck_obj.title else header.iden
            outputs.add("--plots", plots / SIGMA_PNG, lambda tmp: plot_sigma_history(
                run.history, run.history_labels, tmp, f"{title}: σ, fit vs real world"))
            n_plots = 1
            if bplane_rows(run.history, tuple(header.miss.name)):
                outputs.add("--plots", plots / BPLANE_PNG, lambda tmp: plot_bplane_ellipses(
                    run.history, tuple(header.miss.name), tmp, f"{title}: B-plane 1σ/3σ"))
                n_plots += 1
            if ric_rows(run.history):
                outputs.add("--plots", plots / RIC_PNG, lambda tmp: plot_ric_history(
                    run.history, tmp, f"{title}: σ in RIC axes, fit vs real world"))
                outputs.add("--plots", plots / RIC_CSV, lambda tmp: tmp.write_text(
                    ric_csv(run.history), "utf-8"))
                n_plots += 1
            written.append(f"plots into {plots} ({n_plots} PNG"
                           + (f", {RIC_CSV})" if ric_rows(run.history) else ")"))
        with delivering(json_out, content, outputs) as report:
            if report and print_path is None:
                typer.echo(text, nl=False)
            typer.echo(summary_line(written, largest_sigma_ratio(run, tuple(header.miss.name))),
                       err=print_path is None or json_out == STDOUT)

    run_guarded(body)
