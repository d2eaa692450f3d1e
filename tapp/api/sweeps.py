"""``sweep``: an ITER sweep file run in this process, on a local Dask cluster or on a running
one (:mod:`iter`), the result being ITER's own (:class:`iter.SweepResult`)."""

from __future__ import annotations

from pathlib import Path

from iter import Execution, SweepResult, load_sweep, run_sweep

__all__ = ["sweep"]


def sweep(path: Path | str, *, output_h5: Path | str | None = None,
          output_csv: Path | str | None = None, execution: Execution | None = None,
          progress: bool = False) -> SweepResult:
    """Run every case of the sweep file at ``path`` not already in ``output_h5``; return the
    table (one row per case, sorted by index) and the summary.

    Parameters
    ----------
    path : the sweep file (TOML: ``[body]`` and ``[[loop]]``; paths in it are taken from
        its folder).
    output_h5 : the HDF5 results file, a checkpoint that a later call resumes; None: none.
    output_csv : also write the table as CSV.
    execution : where the cases run (:class:`iter.Execution`); None: ITER's automatic choice.
    progress : show ITER's progress bar.

    Raises
    ------
    iter.SweepInputError, iter.ResultFileError, iter.SchedulerError, iter.ResultWriteError
        As ``tapp iter`` reports them (it maps them onto tapp's errors); failed cases do not
        raise (:meth:`iter.SweepResult.raise_if_all_failed`).
    """
    return run_sweep(load_sweep(path), output_h5=output_h5, output_csv=output_csv,
                     execution=execution, progress=progress)
