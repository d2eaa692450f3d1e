"""Shared pieces of the benchmark sections: timing, machine facts, Markdown and result files.

Each section module (``propagation``, later tracking, DC, targeting, sweeps) exposes
``run() -> Section``; ``run.py`` prints the header once and then every section, and each
section writes ``results/bench/<name>.md`` and ``results/bench/<name>.json``.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

REPO_ROOT = Path(__file__).resolve().parents[2]
RESULTS_DIR = REPO_ROOT / "results" / "bench"


@dataclass(frozen=True, slots=True)
class Timing:
    """Wall-clock times (s) of repeated calls, by ``time.perf_counter``."""

    best_s: float
    median_s: float
    repeats: int

    @property
    def best_ms(self) -> float:
        return 1e3 * self.best_s

    @property
    def median_ms(self) -> float:
        return 1e3 * self.median_s


def time_calls(fn: Callable[[], Any], repeats: int, *, budget_s: float | None = None
               ) -> tuple[Timing, Any]:
    """Call ``fn`` ``repeats`` times; return the timing and the last result.

    With ``budget_s``, stop early (after at least 2 calls) once the total exceeds it, so a
    slow baseline does not dominate the whole benchmark.
    """
    times: list[float] = []
    result = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        if budget_s is not None and len(times) >= 2 and sum(times) > budget_s:
            break
    return Timing(min(times), statistics.median(times), len(times)), result


def timed_once(fn: Callable[[], Any]) -> tuple[float, Any]:
    """Return (seconds, result) of one call."""
    t0 = time.perf_counter()
    result = fn()
    return time.perf_counter() - t0, result


def traced_peak_mb(fn: Callable[[], Any]) -> float:
    """Return the peak of the memory allocated during one call of ``fn``, MB (tracemalloc:
    Python objects and NumPy buffers; it slows the call, so time it elsewhere)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def logger(section: str) -> Callable[[str], None]:
    """Return a function that writes a progress line ``[section] message`` to stderr."""

    def log(message: str) -> None:
        print(f"[{section}] {message}", file=sys.stderr, flush=True)

    return log


def machine_info() -> dict[str, Any]:
    """CPU model, logical CPUs (total and usable by this process), OS and Python."""
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return {"cpu_model": cpu, "nproc": os.cpu_count(), "nproc_usable": usable,
            "platform": platform.platform(), "python": platform.python_version()}


def versions(names: Sequence[str] = ("tapp", "heyoka", "scipy", "casadi", "numpy")
             ) -> dict[str, str]:
    """Installed distribution versions (``"absent"`` when not installed)."""
    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "absent"
    return out


def environment() -> dict[str, Any]:
    """Machine facts, package versions and the date of the run."""
    return {"date_utc": datetime.now(UTC).isoformat(timespec="seconds"),
            "machine": machine_info(), "versions": versions()}


def environment_markdown(env: dict[str, Any]) -> str:
    """The environment as a short Markdown block."""
    m = env["machine"]
    vers = ", ".join(f"{k} {v}" for k, v in env["versions"].items())
    return (f"Run {env['date_utc']} on {m['cpu_model']}, {m['nproc']} logical CPUs "
            f"({m['nproc_usable']} usable), {m['platform']}, Python {m['python']}.  \n"
            f"Versions: {vers}.")


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub-flavoured Markdown table; cells are formatted with ``str``."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


@dataclass(slots=True)
class Section:
    """One benchmark section: its name, Markdown report and raw numbers (JSON-serialisable)."""

    name: str
    markdown: str
    data: dict[str, Any] = field(default_factory=dict)

    def write(self, environment: dict[str, Any], directory: Path = RESULTS_DIR
              ) -> tuple[Path, Path]:
        """Write ``<name>.md`` and ``<name>.json`` under ``directory``; return both paths.

        Both files carry ``environment`` (see :func:`environment`), so each stands alone.
        """
        directory.mkdir(parents=True, exist_ok=True)
        md = directory / f"{self.name}.md"
        js = directory / f"{self.name}.json"
        md.write_text(environment_markdown(environment) + "\n\n" + self.markdown + "\n")
        payload = {"environment": environment, **self.data}
        js.write_text(json.dumps(payload, indent=2, default=_jsonable) + "\n")
        return md, js


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, Timing):
        return asdict(obj)
    if hasattr(obj, "tolist"):
        return obj.tolist()
    raise TypeError(f"not JSON-serialisable: {type(obj)}")
