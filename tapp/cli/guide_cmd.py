"""``tapp guide``: TAPP II on a T32 tape and a guidance file -> ΔV and miss statistics.

The Monte Carlo runs in shards: in this process below
:data:`tapp.guidance.shards.DASK_MIN_SAMPLES` samples and on a local Dask cluster from there
(by default; ``--serial``, ``--workers`` and ``--scheduler`` choose), and prints Markdown
tables, Monte Carlo beside linear covariance, with the linear values the Monte Carlo
contradicts marked (:mod:`tapp.guidance.agreement`); ``--json`` writes every statistic and
check, ``--plots`` the B-plane scatter and the ΔV histograms. Bad input (the tape, the
guidance file or its fields, a corridor on a component not targeted, an option, an output
path that is an input, a scheduler that does not answer) is one line on stderr naming the
file or option and the field, exit 2; all outputs are written together or none
(:class:`tapp.io.outputs.OutputSet`).
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
    execution_options,
    json_file,
    progress_bar,
    run_guarded,
    scheduler_error,
)

if TYPE_CHECKING:
    from iter.execute import Execution
    from tapp.api.guidance import GuideResult


def _study(tape: Path, guide: Path, samples: int, seed: int, execution: Execution,
           shard_size: int | None, quiet: bool) -> GuideResult:
    from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

    from iter import SchedulerError
    from tapp.api.guidance import guide as run_guide

    columns = (TextColumn("{task.description:<8}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("samples"), TimeElapsedColumn())
    with progress_bar(*columns, quiet=quiet) as bar:
        task = bar.add_task("TAPP II", total=samples)

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        try:
            return run_guide(tape, guide, samples=samples, seed=seed, execution=execution,
                             shard_samples=shard_size, progress=progress)
        except SchedulerError as exc:
            raise scheduler_error(exc) from None


@app.command("guide")
def guide_cmd(
    tape: Annotated[Path, typer.Argument(help="T32 tape (RUN.t32.h5) from tapp process "
                                         "--tape.")],
    guide: Annotated[Path, typer.Argument(help="Guidance file (TOML): targets, manoeuvres, "
                                          "execution errors, corridor.")],
    samples: Annotated[int, typer.Option("--samples", help="Monte Carlo samples.")],
    seed: Annotated[int, typer.Option("--seed", help="Root seed (numpy SeedSequence).")],
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    serial: SerialOpt = False,
    connect_timeout_s: ConnectTimeoutOpt = CONNECT_TIMEOUT_S,
    shard_size: Annotated[int | None, typer.Option(
        "--shard-size", help="Samples per Dask task, a multiple of 1,000 [default: auto]; "
                             "the results do not depend on it.")] = None,
    json_out: JsonOpt = None,
    plots: Annotated[Path | None, typer.Option(
        "--plots", help="Write the PNG plots into this folder.")] = None,
) -> None:
    """TAPP II: Monte Carlo midcourse guidance from a T32 tape, beside linear covariance.

    Samples: 2 to 5,000,000. In this process below 10,000,000 samples (so every run: a local
    Dask cluster repays none on 2 cores), unless --workers or --scheduler says otherwise; the
    numbers are the same wherever they run.
    """

    def body() -> None:
        from tapp.guidance.statistics import bplane_rows
        from tapp.guidance.study import check_samples, check_seed, check_shard_samples
        from tapp.io.outputs import OutputSet, check_paths
        from tapp.report import HISTOGRAM_PNG, SCATTER_PNG
        from tapp.report.guidance import plot_bplane_scatter, plot_dv_histograms

        pngs = {} if plots is None else {f"--plots ({name})": plots / name
                                         for name in (SCATTER_PNG, HISTOGRAM_PNG)}
        check_paths({"TAPE": tape, "GUIDE": guide}, {"--json": json_file(json_out), **pngs})
        check_samples(samples, "--samples")
        check_seed(seed, "--seed")
        check_shard_samples(shard_size, "--shard-size")
        execution = execution_options(scheduler, workers, connect_timeout_s, serial)
        guided = _study(tape, guide, samples, seed, execution, shard_size,
                        quiet=json_out == STDOUT)
        result = guided.result
        outputs = OutputSet()
        if plots is not None:
            title = f"{result.tape_iden}: {result.title}" if result.title else result.tape_iden
            if bplane_rows(result.miss_name) is not None:
                outputs.add("--plots", plots / SCATTER_PNG, lambda tmp: plot_bplane_scatter(
                    result, tmp, f"{title}: final B-plane miss"))
            outputs.add("--plots", plots / HISTOGRAM_PNG, lambda tmp: plot_dv_histograms(
                result, tmp, f"{title}: ΔV per manoeuvre"))
        with delivering(json_out, guided.to_json(), outputs) as report:
            if report:
                typer.echo(guided.markdown(), nl=False)

    run_guarded(body)
