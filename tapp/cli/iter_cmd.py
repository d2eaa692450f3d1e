"""``tapp iter``: run an ITER sweep file, in this process, on a local Dask cluster or on a
running one.

The engine is the ``iter`` package; this module only turns options into an
:class:`iter.Execution`, maps ``iter``'s errors onto tapp's (so bad input, including a results
file that is corrupt or cannot be written, is one line on stderr and exit code 2) and prints
the summary. Before anything runs, the results file and the CSV must be distinct from the sweep
file and from each other (:func:`tapp.io.outputs.check_paths`), and the first case's inputs must
pass the body's checks (:meth:`iter.Sweep.check_case`: a file the body reads missing or
invalid, a bad body reference, an argument the body does not take: exit 2, nothing written).
The results file is a checkpoint, rewritten atomically as cases complete so that a killed
sweep resumes; the CSV is written atomically at the end. A sweep whose every case failed
prints its summary, then exits 1 with the first case's error (the results file records every
failure).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from iter.execute import CONNECT_TIMEOUT_S
from tapp.cli.common import (
    STDOUT,
    ConnectTimeoutOpt,
    JsonOpt,
    SchedulerOpt,
    SerialOpt,
    WorkersOpt,
    app,
    delivering,
    json_file,
    run_guarded,
    scheduler_error,
)
from tapp.errors import InputError, TappError

if TYPE_CHECKING:
    from iter import SweepResult

#: Failed cases listed under the summary table (the rest are in the results file).
MAX_FAILURES_SHOWN = 10


@app.command("iter")
def iter_command(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep file (TOML): [body] and [[loop]]s.")],
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o",
                     help="HDF5 results file, resumed if it exists [default: SWEEP.h5 in the "
                          "current directory]."),
    ] = None,
    csv: Annotated[Path | None, typer.Option("--csv", help="Also write the table as CSV.")]
    = None,
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    serial: SerialOpt = False,
    chunk_size: Annotated[
        int | None, typer.Option("--chunk-size", help="Cases per Dask task [default: auto].")
    ] = None,
    connect_timeout_s: ConnectTimeoutOpt = CONNECT_TIMEOUT_S,
    json_out: JsonOpt = None,
) -> None:
    """Run every case of SWEEP_FILE (seed section VI, ITER) and write the results table.

    Paths in the sweep file are taken from its folder. Failing cases are recorded with their
    message and do not stop the sweep; if every case fails, the command exits 1 with the
    first case's error. Running again with the same results file resumes: cases already OK
    are skipped. --json: the summary. At most 1,000,000 cases. By default the first two
    cases run in this process, and the rest too unless their serial work, projected from
    those, reaches 10 s: then on a local Dask cluster (--serial, --workers and --scheduler
    choose).
    """
    h5_path = output if output is not None else Path(sweep_file.stem + ".h5")
    options = {"-o/--output": h5_path, "--csv": csv}

    def run() -> None:
        from iter import (
            Execution,
            IterError,
            ResultFileError,
            ResultWriteError,
            SchedulerError,
            SweepInputError,
            load_sweep,
            run_sweep,
        )
        from tapp.io.outputs import check_paths, make_folders, remove_empty_folders, unwritable

        check_paths({"SWEEP_FILE": sweep_file}, {**options, "--json": json_file(json_out)})
        created = []
        try:
            execution = Execution(serial=serial, scheduler=scheduler, workers=workers,
                                  chunk_size=chunk_size, connect_timeout_s=connect_timeout_s)
            sweep = load_sweep(sweep_file)
            created = [*make_folders(h5_path.parent),
                       *(make_folders(csv.parent) if csv is not None else ())]
            result = run_sweep(sweep, output_h5=h5_path, output_csv=csv, execution=execution,
                               progress=json_out != STDOUT)
            with delivering(json_out, _summary_dict(result)) as report:
                if report:
                    _print_summary(result)
            result.raise_if_all_failed()
        except SweepInputError as exc:
            source = "command line" if exc.source == "options" else exc.source
            field = f"--{exc.field.replace('_', '-')}" if exc.source == "options" else exc.field
            raise InputError(source, field, exc.expected, exc.got) from exc
        except SchedulerError as exc:
            raise scheduler_error(exc, "command line", "--scheduler") from exc
        except ResultWriteError as exc:  # the option as typed; a full disk is exit 1
            option = next((o for o, p in options.items() if str(p) == exc.path), "-o/--output")
            raise unwritable(option, Path(exc.path), exc.error) from exc
        except ResultFileError as exc:
            raise InputError(exc.path, exc.field, exc.expected, exc.got) from exc
        except IterError as exc:  # AllCasesFailed among them: exit 1
            raise TappError(str(exc)) from exc
        finally:
            remove_empty_folders(created)  # made for results that were never written

    run_guarded(run)


def _summary_dict(result: SweepResult) -> dict[str, object]:
    from iter import CaseStatus

    summary = result.summary
    return {
        "n_cases": summary.n_cases, "n_succeeded": summary.n_succeeded,
        "n_failed": summary.n_failed, "n_resumed": summary.n_resumed,
        "wall_s": summary.wall_s, "mode": summary.mode, "output_h5": summary.output_h5,
        "output_csv": summary.output_csv,
        "failed_cases": {row.index: row.error for row in result.table.rows
                         if row.status is CaseStatus.FAILED},
    }


def _print_summary(result: SweepResult) -> None:
    from rich.console import Console
    from rich.table import Table

    from iter import CaseStatus

    summary = result.summary
    table = Table(title="ITER sweep", show_header=False)
    table.add_column("item", style="bold")
    table.add_column("value")
    table.add_row("cases", str(summary.n_cases))
    table.add_row("succeeded", f"[green]{summary.n_succeeded}[/]")
    table.add_row("failed", f"[red]{summary.n_failed}[/]" if summary.n_failed else "0")
    table.add_row("resumed (skipped)", str(summary.n_resumed))
    table.add_row("ran on", summary.mode)
    table.add_row("wall time", f"{summary.wall_s:.2f} s")
    table.add_row("results", summary.output_h5 or "-")
    if summary.output_csv:
        table.add_row("csv", summary.output_csv)
    console = Console()
    console.print(table)
    failed = [row for row in result.table.rows if row.status is CaseStatus.FAILED]
    for row in failed[:MAX_FAILURES_SHOWN]:
        console.print(f"case {row.index}: {row.error}", markup=False, highlight=False)
    if len(failed) > MAX_FAILURES_SHOWN:
        console.print(f"... and {len(failed) - MAX_FAILURES_SHOWN} more failed cases")
