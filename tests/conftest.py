"""How the suite runs in parallel (``make test`` runs it on pytest-xdist's workers).

A module in :data:`TOGETHER` runs whole on one worker: its tests share something expensive
that each process builds once (a module- or session-scoped fixture, or a cache of the module),
and split between workers each would build it again. Every other test goes, one at a time, to
whichever worker is free. The modules go first, those with the most tests first, so the long
ones start at once and the single tests fill in around them.

(xdist's own ``--dist loadgroup`` would do this with marks, but it renames the tests'
``_nodeid``, which pytest 9.2 no longer reads: the marks were ignored.)

Without xdist (a plain ``pytest``) nothing here changes how the tests run.
"""

from __future__ import annotations

import os

import pytest

#: Modules kept on one worker, and what their tests share (built in seconds of CPU).
TOGETHER = {
    "tests/test_install.py": "the wheel, its virtual environment and the commands' run",
    "tests/test_tutorial.py": "the tutorial followed once",
    "tests/test_fuzz.py": "the tapes each TAPP III deck and the guidance file are fuzzed on",
    "tests/test_kill.py": "the 3-day deep-space T32 tape",
    "tests/test_faults.py": "the tapes the full-disk runs start from",
    "tests/tapp/cli/test_pipeline_cmd.py": "a pipeline run and a Dask cluster",
    "tests/tapp/cli/test_guide_cmd.py": "the T32 tape and a Dask cluster",
    "tests/tapp/cli/test_process_cmd.py": "the LEO tape",
    "tests/tapp/cli/test_simulate_cmd.py": "the retargeted simulation",
    "tests/tapp/cli/test_search_cmd.py": "the search that writes a scenario",
    "tests/tapp/cli/test_od_cmd.py": "the observations and the README's TDM",
    "tests/tapp/test_api.py": "the 3-day deep-space simulate -> process -> guide",
    "tests/tapp/test_api_od.py": "the DC, EKF and R(t) runs of SATORB1",
    "tests/tapp/processor/test_reference.py": "the deep-space runs and their exact reference",
    "tests/tapp/guidance/test_agreement.py": "the Monte Carlo studies",
    "tests/tapp/guidance/test_monte_carlo.py": "the Monte Carlo samples",
    "tests/tapp/guidance/test_shards.py": "the guidance problem",
    "tests/tapp/report/test_guidance.py": "the guidance studies",
    "tests/iter/test_iter_execute.py": "a Dask cluster",
}


#: Most workers ``-n auto`` starts: the tests start Dask clusters and processes of their own.
MAX_WORKERS = 4


@pytest.hookimpl(optionalhook=True)  # a hook of pytest-xdist
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """``-n auto``: one worker per CPU this process may run on, at most :data:`MAX_WORKERS`
    (xdist counts physical cores, 1 on a machine of two hyperthreads; or every CPU of the
    host, whatever the affinity). ``PYTEST_XDIST_AUTO_NUM_WORKERS`` still decides if set."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None  # xdist's own hook reads it
    return max(1, min(len(os.sched_getaffinity(0)), MAX_WORKERS))


def module_of(nodeid: str) -> str:
    """The module part of a test id (``tests/test_x.py::test_y[1]`` -> ``tests/test_x.py``)."""
    return nodeid.split("::", 1)[0]


@pytest.hookimpl(optionalhook=True)  # a hook of pytest-xdist, absent without it
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    from xdist.scheduler import LoadScopeScheduling

    class ModulesTogether(LoadScopeScheduling):
        """xdist's ``loadscope`` with a module in :data:`TOGETHER` as one unit of work and
        every other test as one of its own."""

        def _split_scope(self, nodeid: str) -> str:
            module = module_of(nodeid)
            return module if module in TOGETHER else nodeid

    return ModulesTogether(config, log)
