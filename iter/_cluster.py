"""Run a local Dask cluster for a parent process (``python -m iter._cluster WORKERS DIR``).

Used by :func:`iter.execute.local_cluster`, which starts this process in a session of its
own: a Ctrl-C at the parent's terminal, sent to the parent's process group, then reaches
neither this process nor the workers it starts, only the parent, which stops the cluster
(otherwise every worker printed its own KeyboardInterrupt traceback). ``WORKERS`` processes,
one thread each, keep their scratch space in ``DIR``. The scheduler's address is written on
stdout, one line; the cluster then runs until stdin closes (the parent is done, or gone),
and stops. The workers are spawned with :data:`iter.execute.WORKER_ENVIRON`.
"""

from __future__ import annotations

import logging
import sys


def main() -> None:
    """Start the cluster, write its address, run until stdin closes, stop it."""
    workers, scratch = int(sys.argv[1]), sys.argv[2]
    import dask
    from distributed import LocalCluster

    from .execute import WORKER_ENVIRON

    environ = {f"distributed.nanny.pre-spawn-environ.{name}": value
               for name, value in WORKER_ENVIRON.items()}

    # The dashboard, which Dask starts even when asked for none, on a free port (":0"), so
    # that a second cluster on the machine does not clash with the first on 8787.
    with (dask.config.set(environ),
          LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                       dashboard_address=":0", silence_logs=logging.ERROR,
                       local_directory=scratch) as cluster):
        sys.stdout.write(f"{cluster.scheduler_address}\n")
        sys.stdout.flush()
        sys.stdin.buffer.read()


if __name__ == "__main__":
    main()
