"""Where a sweep's cases run: serially, on a local Dask cluster, or on a running Dask cluster.

An :class:`Execution` that asks for none of these (no ``serial``, ``scheduler`` or
``workers``) is *automatic*: its work runs in this process unless the caller's projection of
it is large enough to repay a local cluster's start (:data:`DASK_MIN_WORK_S`; the caller
passes the verdict to :func:`open_executor`). A local cluster's workers are spawned with one
BLAS thread each and without Dask's malloc trim threshold (:func:`local_cluster`).

Cases are grouped into chunks (one Dask task per chunk) so the scheduling cost is paid per
chunk, not per case. Chunks complete in any order; a chunk lost on Dask (a worker died)
records each of its cases as FAILED, as a case whose body fails is. Running a whole sweep
(resuming, checkpoints, the results table) is :mod:`iter.run`: this module writes no results
file, so a program that only runs its work on these executors loads no h5py.

Workers, local or remote, must be able to import ``iter`` and the body's module.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol
from urllib.parse import urlsplit

from .errors import ClusterError, SchedulerError, SweepInputError

if TYPE_CHECKING:
    from distributed import Client

    from .body import Body
    from .loops import Case
    from .table import CaseResult

#: Default connect timeout for a scheduler address, s.
CONNECT_TIMEOUT_S = 5.0
#: Extra time the whole scheduler probe gets beyond the connect timeout, s, so that a failed
#: connect reports its own reason rather than racing the overall deadline.
PROBE_MARGIN_S = 0.5
#: Chunks per worker slot when the chunk size is chosen automatically (load balance).
CHUNKS_PER_SLOT = 4
#: Largest automatic chunk, cases (keeps progress and checkpoints moving).
MAX_CHUNK_CASES = 256
#: Source named in errors about execution settings.
OPTIONS_SOURCE = "options"
#: Most local-cluster worker processes per available core (more only thrash, and starting
#: thousands takes minutes); a running cluster (``scheduler``) has no such limit.
MAX_WORKERS_PER_CORE = 4
#: Time a local cluster is given to stop when its block ends, s (then it is killed).
CLUSTER_STOP_S = 10.0
#: Address schemes accepted for ``scheduler``.
SCHEDULER_SCHEMES = ("tcp", "tls")
#: Projected serial work, s, below which an automatic execution runs in this process: on 2
#: cores a local cluster of 2 workers costs 3 to 7 s more than this process (starting and
#: stopping it, the body imported in the workers) and saves at most half of every second of
#: work; it paid from 5.4, 11.9 and 13.9 s of work in three runs of ``make bench``
#: (section ``cli``, cases of 0.07-0.1 s, the machine's load average 3 to 7).
DASK_MIN_WORK_S = 10.0
#: Settings of Dask's ``distributed.nanny.pre-spawn-environ`` for a local cluster's workers:
#: one BLAS thread each (the workers share the cores: more threads only compete for them,
#: which made small solves up to 10x slower on a loaded machine), and no
#: ``MALLOC_TRIM_THRESHOLD_`` (Dask's 64 kB also fixes glibc's mmap threshold at 128 kB,
#: so every temporary array above that is a fresh mmap whose pages fault in again: a
#: Monte Carlo block ran 1.3-1.4x slower in a worker than in this process).
WORKER_ENVIRON = {"OMP_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1, "MKL_NUM_THREADS": 1,
                  "MALLOC_TRIM_THRESHOLD_": None}


def available_cores() -> int:
    """Return the number of CPU cores this process may use."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


@dataclass(frozen=True, slots=True)
class Execution:
    """Where and how the cases run.

    Parameters
    ----------
    serial : bool
        Run every case in this process, no Dask.
    scheduler : str or None
        ``tcp://HOST:PORT`` of a running dask.distributed scheduler.
    workers : int or None
        Worker processes of a local cluster (one thread each), at most
        :data:`MAX_WORKERS_PER_CORE` per available core. With none of ``serial``,
        ``scheduler`` and ``workers`` the execution is automatic (:attr:`automatic`): in this
        process when the work is too small to repay a local cluster, else on a local cluster
        of one worker per core.
    chunk_size : int or None
        Cases per Dask task; None chooses about :data:`CHUNKS_PER_SLOT` chunks per worker
        (serial runs use 1, which only sets the checkpoint granularity).
    connect_timeout_s : float
        How long to wait for a scheduler to answer, s.
    checkpoint_interval_s : float
        Least time between two rewrites of the results file, s; 0 writes after every chunk.

    Raises
    ------
    SweepInputError
        Conflicting or out-of-range settings (source ``"options"``).
    """

    serial: bool = False
    scheduler: str | None = None
    workers: int | None = None
    chunk_size: int | None = None
    connect_timeout_s: float = CONNECT_TIMEOUT_S
    checkpoint_interval_s: float = 1.0

    def __post_init__(self) -> None:
        # Each value on its own first, then how they combine: `--workers 0 --serial` is a
        # bad worker count before it is a conflict.
        for name in ("workers", "chunk_size"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                                      or value < 1):
                raise SweepInputError(OPTIONS_SOURCE, name, "a whole number >= 1", value)
        max_workers = MAX_WORKERS_PER_CORE * available_cores()
        if self.workers is not None and self.workers > max_workers:
            raise SweepInputError(OPTIONS_SOURCE, "workers",
                                  f"at most {max_workers} local workers ({MAX_WORKERS_PER_CORE}"
                                  f" per core, {available_cores()} cores; give --scheduler to "
                                  "use a larger cluster)", self.workers)
        if self.scheduler is not None:
            parts = urlsplit(self.scheduler)
            if (parts.scheme not in SCHEDULER_SCHEMES or not parts.hostname
                    or _port(self.scheduler) is None):
                raise SweepInputError(OPTIONS_SOURCE, "scheduler",
                                      "an address tcp://HOST:PORT", self.scheduler)
        if not self.connect_timeout_s > 0:
            raise SweepInputError(OPTIONS_SOURCE, "connect_timeout_s", "a positive time, s",
                                  self.connect_timeout_s)
        if not self.checkpoint_interval_s >= 0:
            raise SweepInputError(OPTIONS_SOURCE, "checkpoint_interval_s",
                                  "a time >= 0, s", self.checkpoint_interval_s)
        if self.serial and (self.scheduler is not None or self.workers is not None):
            raise SweepInputError(OPTIONS_SOURCE, "serial",
                                  "no scheduler or workers with a serial run",
                                  {"scheduler": self.scheduler, "workers": self.workers})
        if self.scheduler is not None and self.workers is not None:
            raise SweepInputError(OPTIONS_SOURCE, "workers",
                                  "no worker count with a scheduler address (the running "
                                  "cluster has its own workers)", self.workers)


    @property
    def automatic(self) -> bool:
        """Whether neither a serial run, a scheduler nor a worker count was asked for: the
        work then runs in this process unless it repays a local cluster."""
        return not self.serial and self.scheduler is None and self.workers is None


def _port(address: str) -> int | None:
    try:
        return urlsplit(address).port
    except ValueError:
        return None


class Executor(Protocol):
    """Runs chunks of cases and yields each chunk's rows as the chunk completes."""

    description: str
    slots: int

    def run(self, body: Body, chunks: Sequence[Sequence[Case]]) -> Iterator[list[CaseResult]]:
        """Yield the rows of each chunk, in completion order."""
        ...


class SerialExecutor:
    """Runs every chunk in this process, in order.

    Parameters
    ----------
    description : str
        How the run is described in the summary.
    """

    slots = 1

    def __init__(self, description: str = "serial"):
        self.description = description

    def run(self, body: Body, chunks: Sequence[Sequence[Case]]) -> Iterator[list[CaseResult]]:
        """Yield the rows of each chunk, in order."""
        from .body import run_chunk

        for chunk in chunks:
            yield run_chunk(body, chunk)


class DaskExecutor:
    """Runs one Dask task per chunk on a dask.distributed client.

    Parameters
    ----------
    client : distributed.Client
        Connected to a cluster with at least one worker.
    description : str
        How the cluster is described in the summary.
    """

    def __init__(self, client: Client, description: str):
        self.client = client
        self.description = description
        self.slots = max(1, sum(client.nthreads().values()))

    def run(self, body: Body, chunks: Sequence[Sequence[Case]]) -> Iterator[list[CaseResult]]:
        """Submit every chunk; yield each chunk's rows as it completes."""
        from distributed import as_completed

        from .body import run_chunk

        pending = {self.client.submit(run_chunk, body, chunk, pure=False): chunk
                   for chunk in chunks}
        try:
            for future in as_completed(list(pending), loop=self.client.loop):
                chunk = pending.pop(future)
                if future.status == "finished":
                    yield future.result()
                else:
                    reason = future.status
                    if future.status == "error":
                        exc = future.exception()
                        reason = f"{type(exc).__name__}: {exc}"
                    yield [_lost(case, reason) for case in chunk]
                future.release()
        finally:
            if pending:
                self.client.cancel(list(pending))


def _lost(case: Case, reason: str) -> CaseResult:
    from .table import CaseResult, CaseStatus

    return CaseResult(index=case.index, values=case.values, outputs={},
                      status=CaseStatus.FAILED, error=f"chunk lost on Dask: {reason}")


def probe_scheduler(address: str, timeout_s: float) -> Mapping[str, object]:
    """Return the identity of the Dask scheduler at ``address``, within ``timeout_s``.

    The whole exchange (connect, handshake, one ``identity`` request) is bounded by
    ``timeout_s`` + :data:`PROBE_MARGIN_S`: a plain ``Client(address, timeout=...)`` bounds
    only the connect, and hangs when something else (say, a web server) accepts the
    connection and never answers.

    Raises
    ------
    SchedulerError
        Nothing answered in time, the connection was refused, or what answered is not a
        Dask scheduler.
    """
    import asyncio

    from distributed.comm import connect

    async def identity() -> object:
        comm = await connect(address, timeout=timeout_s)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        reply = asyncio.run(asyncio.wait_for(identity(), timeout_s + PROBE_MARGIN_S))
    except TimeoutError:
        raise SchedulerError(address, timeout_s, "timed out") from None
    except OSError as exc:
        raise SchedulerError(address, timeout_s, str(exc) or type(exc).__name__) from None
    except (MemoryError, ValueError) as exc:
        # What answered is not speaking Dask's protocol: its bytes read as an absurd frame
        # length (MemoryError) or as malformed msgpack (ValueError).
        raise SchedulerError(address, timeout_s,
                             f"not a Dask scheduler ({type(exc).__name__})") from None
    if not isinstance(reply, Mapping) or reply.get("type") != "Scheduler":
        raise SchedulerError(address, timeout_s, f"not a Dask scheduler (answered {reply!r})")
    return reply


@contextmanager
def local_cluster(workers: int | None = None) -> Iterator[str]:
    """Start a dask.distributed LocalCluster; yield its scheduler address; stop it on exit.

    One process per worker (``workers``, default one per core), one thread each, spawned
    with :data:`WORKER_ENVIRON` (a variable this process's environment sets is passed on as
    it is); the dashboard on a free port. The cluster runs in a process of its own
    (``python -m iter._cluster``), in a session of its own, so that a Ctrl-C at a terminal,
    sent to the whole process group, reaches only this process (whose exit stops the
    cluster), never the workers, at any moment, their start included. The cluster's scratch
    space (the workers' ``local_directory``, and its ``TMPDIR``) is a new folder of
    :mod:`tempfile`'s (the run's own, under ``tapp``'s CLI), removed with the cluster. On
    leaving the block normally the cluster is asked to stop (its stdin is closed) and given
    :data:`CLUSTER_STOP_S`; on an error or a signal, or after that time, its session is
    killed. A parent killed outright closes the cluster's stdin too: it stops by itself.
    The cluster and its workers import from this process's ``sys.path`` (passed on as
    ``PYTHONPATH``), as workers spawned by this process itself would: a body's module found
    here is found there.

    Raises
    ------
    ClusterError
        The cluster did not start (the last line of its log says why).
    """
    from .body import kill_session

    n_workers = workers or available_cores()
    with tempfile.TemporaryDirectory(prefix="dask-cluster-") as scratch:
        log_path = os.path.join(scratch, "cluster.log")
        with (open(log_path, "wb") as log,
              subprocess.Popen([sys.executable, "-m", "iter._cluster", str(n_workers), scratch],
                               stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log,
                               start_new_session=True, env={
                                   **os.environ, "TMPDIR": scratch,
                                   "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)})
              as proc):
            try:
                address = proc.stdout.readline().decode("utf-8", "replace").strip()
                if not address:
                    proc.wait()
                    raise ClusterError(n_workers, proc.returncode, _last_line(log_path))
                yield address
                proc.stdin.close()
                with suppress(subprocess.TimeoutExpired):
                    proc.wait(timeout=CLUSTER_STOP_S)
            finally:
                if proc.poll() is None:
                    kill_session(proc)


def _last_line(path: str) -> str:
    with open(path, "rb") as stream:
        lines = stream.read().decode("utf-8", "replace").strip().splitlines()
    return lines[-1] if lines else "(nothing logged)"


def too_small(unit: str, projected: float, crossover: float) -> str | None:
    """Why ``projected`` work (in ``unit``: "samples", "s of work") is too small for a local
    cluster to repay its start, or None when it is not: the verdict an automatic
    :func:`open_executor` takes (e.g. "0.44 s of work, below the 6 s of work a local
    cluster repays"). On one core a local cluster never pays.
    """
    if available_cores() < 2:
        return "one core"
    if projected < crossover:
        return (f"{_amount(projected)} {unit}, below the {_amount(crossover)} {unit} a local "
                "cluster repays")
    return None


def _amount(x: float) -> str:
    return f"{x:,.0f}" if x >= 100 else f"{x:.2g}"


@contextmanager
def open_executor(execution: Execution, *, small: str | None = None) -> Iterator[Executor]:
    """Yield the executor ``execution`` asks for; shut down what was started on exit.

    An automatic execution (:attr:`Execution.automatic`) runs in this process when ``small``
    says why the work is too small for a local cluster (:func:`too_small`), and on a local
    cluster of one worker per core otherwise.

    Raises
    ------
    SchedulerError
        The scheduler address does not answer, or its cluster has no worker, within
        ``execution.connect_timeout_s``.
    """
    if execution.serial:
        yield SerialExecutor()
        return
    if execution.automatic and small is not None:
        yield SerialExecutor(f"this process ({small})")
        return
    from distributed import Client

    if execution.scheduler is None:
        n_workers = execution.workers or available_cores()
        with (local_cluster(n_workers) as address,
              Client(address, set_as_default=False) as client):
            yield DaskExecutor(client, f"local cluster ({n_workers} workers)")
        return
    address, timeout_s = execution.scheduler, execution.connect_timeout_s
    probe_scheduler(address, timeout_s)
    try:
        client = Client(address, timeout=timeout_s, set_as_default=False)
    except OSError as exc:
        raise SchedulerError(address, timeout_s, str(exc)) from None
    with client:
        try:
            client.wait_for_workers(1, timeout=timeout_s)
        except TimeoutError:
            raise SchedulerError(address, timeout_s, "the cluster has no worker") from None
        yield DaskExecutor(client, f"scheduler {address} ({len(client.nthreads())} workers)")


def chunk_cases(cases: Sequence[Case], chunk_size: int) -> list[tuple[Case, ...]]:
    """Return ``cases`` split into consecutive chunks of at most ``chunk_size``."""
    return [tuple(cases[k:k + chunk_size]) for k in range(0, len(cases), chunk_size)]


def default_chunk_size(n_cases: int, slots: int) -> int:
    """Return about :data:`CHUNKS_PER_SLOT` chunks per slot, 1 to :data:`MAX_CHUNK_CASES`."""
    return max(1, min(MAX_CHUNK_CASES, math.ceil(n_cases / (CHUNKS_PER_SLOT * slots))))
