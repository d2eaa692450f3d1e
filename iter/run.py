"""Run a sweep on an executor of :mod:`iter.execute`, into a results table and files.

Before any case runs or anything is written, the first case to run is checked
(:meth:`iter.sweep.Sweep.check_case`): an input error there would be every case's, so it
stops the sweep. Chunks complete in any order; the table is always sorted by case index. A
case whose body fails is recorded as FAILED with its message and the sweep goes on; a chunk
lost on Dask (a worker died) records each of its cases as FAILED the same way. A sweep whose
every case failed gives no answer: :meth:`SweepResult.raise_if_all_failed` says so.

Where the cases run (:class:`~iter.execute.Execution`): an automatic execution first runs
:data:`PROBE_CASES` cases in this process, projects the rest's serial work from the cheaper
of them (the first also pays for importing the body) and runs the rest in this process too
when that work is below :data:`~iter.execute.DASK_MIN_WORK_S`, on a local cluster
otherwise; the summary's ``mode`` says which, and why.

With an output file the sweep is resumable: completed rows are written to the HDF5 file as
chunks finish (at most every ``checkpoint_interval_s``, and at the end, also on an error or
Ctrl-C), each time atomically. Running the same sweep again with the same file skips every
case already OK and runs the rest (cases that failed are tried again).
"""

from __future__ import annotations

import time
from contextlib import ExitStack
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .errors import AllCasesFailed, SweepInputError
from .execute import (
    DASK_MIN_WORK_S,
    Execution,
    SerialExecutor,
    chunk_cases,
    default_chunk_size,
    open_executor,
    too_small,
)
from .results import read_hdf5, write_csv, write_hdf5
from .sweep import Sweep
from .table import CaseResult, CaseStatus, ResultTable

#: Cases an automatic execution runs in this process to project the serial work of the rest.
PROBE_CASES = 2


@dataclass(frozen=True, slots=True)
class SweepSummary:
    """Counts and timing of one run of a sweep.

    Parameters
    ----------
    n_cases : int
        Cases in the sweep.
    n_succeeded, n_failed : int
        Cases OK and FAILED in the table after this run (resumed cases included).
    n_resumed : int
        Cases found OK in the results file and not run again.
    wall_s : float
        Wall time of this run, s.
    mode : str
        Where the cases ran (``serial``, ``local cluster (2 workers)``, ...).
    output_h5, output_csv : str or None
        The files written.
    source : str
        The sweep (its file path).
    """

    n_cases: int
    n_succeeded: int
    n_failed: int
    n_resumed: int
    wall_s: float
    mode: str
    output_h5: str | None
    output_csv: str | None
    source: str


@dataclass(frozen=True, slots=True)
class SweepResult:
    """The results table and the summary of a run."""

    table: ResultTable
    summary: SweepSummary

    def raise_if_all_failed(self) -> None:
        """Raise unless at least one case of the table succeeded.

        Raises
        ------
        AllCasesFailed
            Every case failed; the message gives the first case's error and the results
            file that records every failure.
        """
        if self.table.n_succeeded == 0:
            first = self.table.rows[0]
            raise AllCasesFailed(self.summary.source, self.summary.n_cases, first.index,
                                 first.error, self.summary.output_h5)


def _utc_now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _resume(sweep: Sweep, output_h5: Path) -> tuple[dict[int, CaseResult], str]:
    """Return the OK rows already in ``output_h5`` and its creation time."""
    if not output_h5.exists():
        return {}, _utc_now()
    stored = read_hdf5(output_h5)
    if stored.definition_json != sweep.definition_json():
        raise SweepInputError(str(output_h5), "definition_json",
                              f"results of the same sweep as {sweep.source} to resume (the "
                              "loops or the body differ: remove the file or choose another "
                              "output)")
    done = {row.index: row for row in stored.table.rows if row.status is CaseStatus.OK}
    return done, stored.created_utc


def run_sweep(sweep: Sweep, *, output_h5: str | Path | None = None,
              output_csv: str | Path | None = None, execution: Execution | None = None,
              progress: bool = False) -> SweepResult:
    """Run every case of ``sweep`` not already done; return the table, sorted by case index.

    Parameters
    ----------
    sweep : Sweep
        Loops and body.
    output_h5 : str or Path or None
        HDF5 results file; written as cases complete and resumed from if it exists.
    output_csv : str or Path or None
        CSV copy of the table, written at the end.
    execution : Execution or None
        Where to run; None for an automatic execution (module docstring).
    progress : bool
        Show a rich progress bar on stderr.

    Returns
    -------
    SweepResult
        The table (every case, resumed ones included) and the summary.

    Raises
    ------
    SweepInputError
        ``output_h5`` holds results of a different sweep, or the first case to run cannot
        run (:meth:`Sweep.check_case`: the body's reference, a file, an argument); nothing is
        written and no case runs.
    Exception
        Whatever the body's own input check raises on the first case to run (the same
        guarantees).
    SchedulerError
        The scheduler address does not answer within the connect timeout.
    ResultFileError
        A results file cannot be read or written.
    """
    execution = Execution() if execution is None else execution
    start_s = time.perf_counter()
    h5_path = None if output_h5 is None else Path(output_h5)
    results, created_utc = ({}, _utc_now()) if h5_path is None else _resume(sweep, h5_path)
    n_resumed = len(results)
    pending = [case for case in sweep.cases() if case.index not in results]
    if pending:
        sweep.check_case(pending[0])

    def checkpoint() -> None:
        if h5_path is not None:
            write_hdf5(h5_path, ResultTable.from_results(sweep.names, results),
                       sweep_json=sweep.contents_json(),
                       definition_json=sweep.definition_json(), source=sweep.source,
                       n_cases=sweep.n_cases, created_utc=created_utc,
                       updated_utc=_utc_now())

    console = Console(stderr=True)  # the bar on a terminal only: elsewhere it adds lines
    bar = Progress(TextColumn("[bold]iter"), BarColumn(), MofNCompleteColumn(),
                   TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(),
                   TimeRemainingColumn(), console=console,
                   disable=not progress or not console.is_terminal)
    with ExitStack() as stack:
        # an executor asked for opens first: a scheduler that does not answer is said before
        # any progress is shown
        executor = None if execution.automatic else stack.enter_context(
            open_executor(execution))
        stack.enter_context(bar)
        task = bar.add_task("iter", total=sweep.n_cases, completed=n_resumed, failed=0)
        n_failed_now = 0
        checkpoint()  # fails fast on an unwritable output, before any case runs
        last_checkpoint_s = time.perf_counter()

        def record(rows: list[CaseResult]) -> None:
            nonlocal n_failed_now, last_checkpoint_s
            results.update((row.index, row) for row in rows)
            n_failed_now += sum(row.status is CaseStatus.FAILED for row in rows)
            bar.update(task, advance=len(rows), failed=n_failed_now)
            if time.perf_counter() - last_checkpoint_s >= execution.checkpoint_interval_s:
                checkpoint()
                last_checkpoint_s = time.perf_counter()

        try:
            probed = ""
            if executor is None:  # automatic (no case left to run: no work, no cluster)
                probe, pending = pending[:PROBE_CASES], pending[PROBE_CASES:]
                for rows in SerialExecutor().run(sweep.body, chunk_cases(probe, 1)):
                    record(rows)
                case_s = min((results[case.index].elapsed_s for case in probe), default=0.0)
                executor = stack.enter_context(open_executor(execution, small=too_small(
                    "s of work", case_s * len(pending), DASK_MIN_WORK_S)))
                if not isinstance(executor, SerialExecutor):
                    probed = f", after {len(probe)} cases in this process"
            mode = executor.description + probed
            chunk_size = execution.chunk_size or (
                1 if isinstance(executor, SerialExecutor)
                else default_chunk_size(len(pending), executor.slots))
            for rows in executor.run(sweep.body, chunk_cases(pending, chunk_size)):
                record(rows)
        finally:
            checkpoint()
    table = ResultTable.from_results(sweep.names, results)
    if output_csv is not None:
        write_csv(output_csv, table)
    summary = SweepSummary(n_cases=sweep.n_cases, n_succeeded=table.n_succeeded,
                           n_failed=table.n_failed, n_resumed=n_resumed,
                           wall_s=time.perf_counter() - start_s, mode=mode,
                           output_h5=None if h5_path is None else str(h5_path),
                           output_csv=None if output_csv is None else str(output_csv),
                           source=sweep.source)
    return SweepResult(table=table, summary=summary)
