"""ITER: run a body over nested loops of cases, serially or on Dask (seed section VI).

A *loop* varies n named parameters over ``sets`` cases, either from a full table (type 1) or
from a first row plus increments (type 2); loops nest to any depth, inner loops restarting
for every outer case. The *body* is a Python callable (``"module:function"``) or a command-line
program; each case gives one row of a results table (varied values, outputs, status, error),
written to HDF5 and CSV. See :mod:`iter.sweepfile` for the sweep-file format, the rule for
the paths in it (taken from the sweep file's folder) and the checks made before any case runs.

This package knows nothing of ``tapp`` and never imports it. Inside it, use relative imports:
``import iter`` would shadow the builtin ``iter()``; from outside, ``from iter import ...`` or
``import iter as sweeps``. Every public name is imported from its module on first use, so
that a program using only part of the package loads only what that part needs: the executors
of :mod:`iter.execute` load neither h5py (which only :mod:`iter.results` and :mod:`iter.run`
load), pydantic (the sweep-file schema) nor NumPy, and a command line that only shows its
help and the defaults it takes from here (``tapp iter --help``) loads none of them.

>>> from iter import Loop, generate_cases
>>> azimuths = Loop(type=2, names=("azimuth_deg",), sets=5, vary=(96.0,), delta=(3.0,))
>>> [case.values[0] for case in generate_cases([azimuths])]
[96.0, 99.0, 102.0, 105.0, 108.0]
"""

import importlib

#: Every public name and the module it lives in, imported on first use (module docstring).
_HOMES = {
    "AllCasesFailed": "errors", "CallableBody": "body", "Case": "loops",
    "CaseResult": "table", "CaseStatus": "table", "ClusterError": "errors",
    "Execution": "execute",
    "IterError": "errors", "Loop": "loops", "ProgramBody": "body",
    "ResultFileError": "errors", "ResultTable": "table", "ResultWriteError": "errors",
    "SchedulerError": "errors",
    "Sweep": "sweep", "SweepInputError": "errors", "SweepResult": "run",
    "SweepSummary": "run", "case_count": "loops", "generate_cases": "loops",
    "input_check": "body", "load_sweep": "sweepfile", "parse_sweep": "sweepfile",
    "probe_scheduler": "execute", "read_hdf5": "results", "resolve_callable": "body",
    "run_case": "body", "run_sweep": "run", "write_csv": "results", "write_hdf5": "results",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> object:
    if name in _HOMES:
        return getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
