"""Run one callable body's case in a child process (``python -m iter._child``).

Used by :class:`iter.body.CallableBody` when it has a ``timeout_s``: a function that never
returns can then be stopped by killing this process. The parent writes a pickled
``(sys_path, target, kwargs)`` on stdin; this process answers on its original stdout with a
pickled ``("ok", outputs)`` (outputs already flattened into named scalars) or
``("error", exception type name, message)``. Anything the function prints goes to stderr.
"""

from __future__ import annotations

import os
import pickle
import sys


def main() -> None:
    """Read the case from stdin, run it, write the pickled answer to the original stdout."""
    sys_path, target, kwargs = pickle.load(sys.stdin.buffer)
    answer_fd = os.dup(1)
    os.dup2(2, 1)  # the function's own output, even from C or subprocesses, goes to stderr
    sys.stdout = sys.stderr
    for entry in reversed(sys_path):
        if entry not in sys.path:
            sys.path.insert(0, entry)
    from iter.body import flatten_outputs, resolve_callable

    try:
        answer: tuple = ("ok", flatten_outputs(resolve_callable(target)(**kwargs)))
    except Exception as exc:  # noqa: BLE001 - a failing case is data: sent to the parent
        answer = ("error", type(exc).__name__, str(exc))
    with os.fdopen(answer_fd, "wb") as stream:
        pickle.dump(answer, stream)


if __name__ == "__main__":
    main()
