"""Run tapp commands in one process of an installed tapp; print their outcomes as JSON.

The driver of ``tests/test_install.py``: it runs in the virtual environment the wheel was
installed into (``venv/bin/python -I tests/install_smoke.py < commands.json``: isolated, so
that the script's folder is not on the path), from an empty folder, so it imports nothing of
the repository. stdin: a JSON list of ``[name, argv]``;
stdout: ``{"modules": {name: file}, "results": {name: {"exit_code", "output", "wall_s"}}}``.
The commands run in order, in one process: the start-up cost (casadi, dask, matplotlib) is
paid once, not per command.
"""

from __future__ import annotations

import json
import sys
import time


def main() -> None:
    from typer.testing import CliRunner

    import iter as sweeps
    import search
    import tapp
    from tapp.cli import app

    runner = CliRunner()
    results = {}
    for name, argv in json.load(sys.stdin):
        start = time.perf_counter()
        outcome = runner.invoke(app, argv)
        results[name] = {"exit_code": outcome.exit_code, "output": outcome.output,
                         "wall_s": time.perf_counter() - start}
    modules = {m.__name__: m.__file__ for m in (tapp, search, sweeps)}
    json.dump({"modules": modules, "results": results}, sys.stdout)


if __name__ == "__main__":
    main()
