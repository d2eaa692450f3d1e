"""``tapp pipeline``: simulate -> process -> guide from one pipeline file into one directory.

The pipeline file names (or inlines) the TAPP I scenario, the TAPP III deck and the TAPP II
guidance file (:mod:`tapp.pipeline.spec`); the run writes the T13 and T32 tapes, the O3
printout, the JSON of both studies, the plots and ``report.md`` into ``-o DIR``, which must be
new or empty and appears only when the run is complete. Bad input in any part is one line
naming the file (or the pipeline file and the part) and the field, exit 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from iter.execute import CONNECT_TIMEOUT_S
from tapp.cli.common import (
    STDOUT,
    ConnectTimeoutOpt,
    EarthOrientationOpt,
    JsonOpt,
    SchedulerOpt,
    SerialOpt,
    WorkersOpt,
    app,
    delivering,
    earth_orientation_option,
    echo_warning,
    execution_options,
    json_file,
    progress_bar,
    run_guarded,
    scheduler_error,
)


@app.command("pipeline")
def pipeline_cmd(
    pipeline: Annotated[Path, typer.Argument(help="Pipeline file (TOML): scenario, deck, "
                                             "guidance, [simulate], [guide].")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Directory to create (new or "
                                         "empty).")],
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    serial: SerialOpt = False,
    connect_timeout_s: ConnectTimeoutOpt = CONNECT_TIMEOUT_S,
    earth_orientation: EarthOrientationOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """TAPP I -> TAPP III -> TAPP II in one run, with DIR/report.md.

    --json: the trade-study numbers and the wall time of each stage.
    """

    def body() -> None:
        from contextlib import ExitStack
        from dataclasses import replace

        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

        from iter import SchedulerError
        from tapp.io.outputs import check_paths
        from tapp.pipeline.run import OUTPUTS, check_out_dir, running_pipeline, trade_outputs
        from tapp.pipeline.spec import read_pipeline

        check_paths({"PIPELINE": pipeline}, {"--json": json_file(json_out)})
        check_out_dir(output)
        pipe = read_pipeline(pipeline)
        override = earth_orientation_option(earth_orientation)
        if override is not None:
            pipe = replace(pipe, earth_orientation=override)
        execution = execution_options(scheduler, workers, connect_timeout_s, serial)
        columns = (TextColumn("{task.description:<28}"), BarColumn(), MofNCompleteColumn(),
                   TimeElapsedColumn())
        # the directory appears when the stack closes: after the report, as the --json file
        with ExitStack() as stack:
            with progress_bar(*columns, quiet=json_out == STDOUT) as bar:
                task = bar.add_task("pipeline", total=None)

                def progress(stage: str, done: int, total: int) -> None:
                    bar.update(task, description=stage, completed=done, total=total)

                try:
                    result = stack.enter_context(running_pipeline(
                        pipe, output, execution=execution, progress=progress))
                except SchedulerError as exc:
                    raise scheduler_error(exc) from None
            numbers = trade_outputs(result)
            with delivering(json_out, {"directory": str(output), **numbers,
                                       "wall_s": result.wall_s,
                                       "warnings": list(result.warnings)}) as report:
                if report:
                    console = Console(width=100)
                    console.print(f"pipeline {pipeline} -> {output}/{OUTPUTS['report']} ("
                                  + ", ".join(f"{k} {v:.1f} s" for k, v in
                                              result.wall_s.items()) + ")")
                    console.print(", ".join(f"{k} = {v:.4g}" for k, v in numbers.items()))
        for warning in result.warnings:  # last: a failed run's one line is its error
            echo_warning(warning)

    run_guarded(body)
