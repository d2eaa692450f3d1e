"""Benchmark of the ``tapp`` command itself: how fast it answers.

Start-up: ``tapp --help``, ``tapp --version`` and ``tapp CMD --help`` for every command,
each a whole process (the console script next to this interpreter) timed from outside,
in turn with ``python -c "import typer"`` (the floor of any typer program) so that each
ratio is taken pair by pair on a machine whose speed drifts. Target: every one within
:data:`TARGET_S`.

Where the work runs: ``tapp guide`` (the shipped deep-space T32 tape and guidance file) and
``tapp iter`` (a sweep of :func:`iter.bench.cpu_bound_body` cases, about 0.1 s each) end to
end, each size in this process (``--serial``) and on a local cluster of :data:`WORKERS`
workers (``--workers``) as tapp starts it, and with Dask's ``MALLOC_TRIM_THRESHOLD_`` put
back in the workers' environment (as they were started before), then with no option (the
automatic choice). A straight line a + b·size through each set of times gives the crossover,
the size from which the cluster is faster: the basis of
:data:`tapp.guidance.shards.DASK_MIN_SAMPLES` and :data:`iter.execute.DASK_MIN_WORK_S`.

BLAS threads: small kernels of tapp's shapes (a TAPP II block product, a TAPP I pass QR, a
TAPP III solve) with OpenBLAS's default threads and with one (what every command and every
local worker now uses), on the idle machine and with :data:`HOGS` processes spinning (a
loaded machine).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import typer
from threadpoolctl import threadpool_info, threadpool_limits

from iter.bench import CPU_BOUND_ITERATIONS
from iter.execute import DASK_MIN_WORK_S, available_cores
from tapp.cli import app
from tapp.guidance.shards import DASK_MIN_SAMPLES
from tests.bench.common import Section, logger, markdown_table
from tests.bench.guidance import GUIDE, MALLOC_TRIM, SEED, write_tapes

NAME = "cli"
#: Wall time within which every help and ``--version`` must answer, s (2-core machine).
TARGET_S = 0.3
#: Runs of each command (and as many of the baseline, in turn with it).
REPEATS = 7
BASELINE = (sys.executable, "-c", "import typer")
#: Local-cluster workers of the Dask runs (one per core of the 2-core machine).
WORKERS = 2
#: Sample counts of the ``tapp guide`` runs.
GUIDE_SAMPLES = (100_000, 1_000_000, 3_000_000)
#: Case counts of the ``tapp iter`` runs (cases of about 0.1 s).
ITER_CASES = (10, 50, 150)
#: Dask's own value of ``MALLOC_TRIM_THRESHOLD_`` in the workers it spawns.
DASK_MALLOC_TRIM = "65536"
#: Processes spinning on the cores while the loaded kernels are timed.
HOGS = 2

log = logger(NAME)


def tapp_command() -> tuple[str, ...]:
    """The ``tapp`` console script of this environment (``python -m tapp.cli`` without one)."""
    script = Path(sys.executable).with_name("tapp")
    return (str(script),) if script.exists() else (sys.executable, "-m", "tapp.cli")


def command_paths() -> list[tuple[str, ...]]:
    """Every command of the app, as the words that name it (``("tape", "info")``)."""
    paths: list[tuple[str, ...]] = []

    def walk(group, prefix: tuple[str, ...]) -> None:
        for name, command in group.commands.items():
            path = (*prefix, name)
            if hasattr(command, "commands"):
                walk(command, path)
            else:
                paths.append(path)

    walk(typer.main.get_command(app), ())
    return paths


def _wall_s(argv: tuple[str, ...]) -> float:
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, check=False)
    wall_s = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {done.returncode}: {done.stderr[-400:]!r}")
    return wall_s


def time_startup(argv: tuple[str, ...], repeats: int = REPEATS) -> dict[str, float]:
    """Wall times of ``argv`` and of the baseline, run in turn after one warm-up of each:
    median and best of ``argv``, the baseline's median, the median of the paired ratios."""
    _wall_s(argv), _wall_s(BASELINE)
    walls, bases = [], []
    for _ in range(repeats):
        walls.append(_wall_s(argv))
        bases.append(_wall_s(BASELINE))
    return {"median_s": statistics.median(walls), "best_s": min(walls),
            "baseline_median_s": statistics.median(bases),
            "ratio": statistics.median(w / b for w, b in zip(walls, bases, strict=True))}


def startup() -> tuple[str, dict]:
    """Time every help and ``--version``; return the Markdown table and the numbers."""
    tapp = tapp_command()
    cases = [("--help",), ("--version",), *((*path, "--help") for path in command_paths())]
    results = {}
    for args in cases:
        results[" ".join(args)] = r = time_startup((*tapp, *args))
        log(f"tapp {' '.join(args)}: {r['median_s'] * 1e3:.0f} ms (x{r['ratio']:.2f} import "
            "typer)")
    rows = [[f"`tapp {label}`", f"{r['median_s'] * 1e3:.0f}", f"{r['best_s'] * 1e3:.0f}",
             f"{r['ratio']:.2f}", "yes" if r["median_s"] <= TARGET_S else "NO"]
            for label, r in results.items()]
    base_ms = 1e3 * statistics.median(r["baseline_median_s"] for r in results.values())
    md = "\n".join([
        "### Start-up", "",
        f"Whole processes of the console script `{Path(tapp[-1]).name}`, {REPEATS} runs each "
        f"in turn with `python -c \"import typer\"` (median {base_ms:.0f} ms in this run); "
        f"ratio: the median of the paired ratios. Target: within {TARGET_S} s.", "",
        markdown_table(["command", "median (ms)", "best (ms)", "x import typer",
                        f"<= {TARGET_S} s"], rows)])
    return md, {"startup": results, "baseline_median_ms": base_ms}


def _run_cli(args: list[str], env: dict[str, str] | None = None) -> tuple[float, dict]:
    """Wall time of ``tapp ARGS --json -`` (a whole process) and its JSON."""
    argv = (*tapp_command(), *args, "--json", "-")
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, check=False,
                          env={**os.environ, **(env or {})})
    wall_s = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"tapp {' '.join(args)} exited {done.returncode}: "
                           f"{done.stderr[-400:]}")
    return wall_s, json.loads(done.stdout)


#: The executions timed: options, extra environment, label.
EXECUTIONS = (
    (["--serial"], {}, "this process (--serial)"),
    (["--workers", str(WORKERS)], {}, f"local cluster, {WORKERS} workers"),
    (["--workers", str(WORKERS)], {MALLOC_TRIM: DASK_MALLOC_TRIM},
     f"local cluster, {WORKERS} workers, Dask's {MALLOC_TRIM} (as before)"),
)


def _line(sizes: list[float], walls: list[float]) -> tuple[float, float]:
    """Least-squares a, b of wall = a + b * size."""
    b, a = np.polyfit(np.asarray(sizes, float), np.asarray(walls, float), 1)
    return float(a), float(b)


def _crossover(serial: tuple[float, float], cluster: tuple[float, float]) -> float:
    """The size from which the cluster's line is below this process's (inf: never)."""
    (a_s, b_s), (a_d, b_d) = serial, cluster
    return (a_d - a_s) / (b_s - b_d) if b_s > b_d else float("inf")


def _timed_sizes(label: str, sizes: tuple[int, ...], args: Callable[[int], list[str]],
                 where: Callable[[dict], str]) -> dict:
    """Every size under every execution of :data:`EXECUTIONS`, then the automatic choice at
    the smallest and the largest size: wall times, lines, crossovers."""
    runs: dict[str, dict] = {}
    for options, env, name in EXECUTIONS:
        walls = []
        for size in sizes:
            wall_s, _ = _run_cli([*args(size), *options], env)
            walls.append(wall_s)
            log(f"{label} {size:,}, {name}: {wall_s:.2f} s")
        runs[name] = {"wall_s": walls, "line": _line(sizes, walls)}
    serial = runs[EXECUTIONS[0][2]]["line"]
    for _, _, name in EXECUTIONS[1:]:
        runs[name]["crossover"] = _crossover(serial, runs[name]["line"])
    automatic = []
    for size in (sizes[0], sizes[-1]):
        wall_s, out = _run_cli(args(size))
        automatic.append({"size": size, "wall_s": wall_s, "where": where(out)})
        log(f"{label} {size:,}, automatic: {wall_s:.2f} s, {where(out)}")
    return {"sizes": list(sizes), "runs": runs, "automatic": automatic}


def _sizes_table(unit: str, data: dict) -> str:
    rows = [[name, *(f"{w:.2f}" for w in r["wall_s"]),
             f"{r['line'][0]:.2f} + {r['line'][1]:.3g}·n",
             "—" if "crossover" not in r else f"{r['crossover']:,.3g}"]
            for name, r in data["runs"].items()]
    rows += [[f"automatic ({a['where']})", *("" if s != a["size"] else f"{a['wall_s']:.2f}"
                                              for s in data["sizes"]), "", ""]
             for a in data["automatic"]]
    return markdown_table(["execution", *(f"{s:,} {unit} (s)" for s in data["sizes"]),
                           "line (s)", "crossover"], rows)


def _fresh(path: Path) -> Path:
    """``path``, removed: a results file left by the previous run would be resumed."""
    path.unlink(missing_ok=True)
    return path


def _sweep_file(folder: Path, cases: int) -> Path:
    path = folder / f"cpu_{cases}.toml"
    path.write_text(f'[body]\ncallable = "iter.bench:cpu_bound_body"\n\n[body.constants]\n'
                    f"n_iterations = {CPU_BOUND_ITERATIONS}\n\n[[loop]]\ntype = 2\n"
                    f'names = ["x"]\nsets = {cases}\nvary = [0.0]\ndelta = [1.0]\n')
    return path


def where_work_runs() -> tuple[str, dict]:
    """``tapp guide`` and ``tapp iter`` at several sizes, in this process and on a local
    cluster; the crossovers; the Markdown and the numbers."""
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="tapp-cli-bench-") as tmp:
        folder = Path(tmp)
        t32, _ = write_tapes(folder)
        guide = _timed_sizes(
            "tapp guide", GUIDE_SAMPLES,
            lambda n: ["guide", str(t32), str(GUIDE), "--samples", str(n), "--seed",
                       str(SEED)],
            lambda out: out["where"])
        iter_runs = _timed_sizes(
            "tapp iter", ITER_CASES,
            lambda n: ["iter", str(_sweep_file(folder, n)), "-o", str(_fresh(folder / "r.h5"))],
            lambda out: out["mode"])
    load_after = os.getloadavg()[0]
    case_s = iter_runs["runs"][EXECUTIONS[0][2]]["line"][1]
    cluster = EXECUTIONS[1][2]
    before = EXECUTIONS[2][2]
    work_s = iter_runs["runs"][cluster]["crossover"] * case_s
    md = "\n".join([
        "### Where the work runs: Dask only when it pays", "",
        f"Whole `tapp` processes with `--json -`; a local cluster of {WORKERS} workers as tapp "
        f"starts it (one BLAS thread each, no {MALLOC_TRIM}) and, for the record, with Dask's "
        f"{MALLOC_TRIM}={DASK_MALLOC_TRIM} put back in the workers (as before). The line "
        "a + b·n is a least-squares fit through each row; the crossover is where the "
        "cluster's line meets this process's. One run each; load average (1 min) "
        f"{load_before:.1f} before and {load_after:.1f} after ({available_cores()} cores: "
        "other work slows the cluster most, and moves the crossover up).", "",
        "`tapp guide` (deep-space T32 tape, `tapp2_deep_space.toml`):", "",
        _sizes_table("samples", guide), "",
        f"**Crossover: {guide['runs'][cluster]['crossover']:,.3g} samples** "
        f"({guide['runs'][before]['crossover']:,.3g} with Dask's trim threshold); "
        f"`DASK_MIN_SAMPLES` = {DASK_MIN_SAMPLES:,}.", "",
        f"`tapp iter` (cases of `iter.bench:cpu_bound_body`, {case_s:.3f} s each in this "
        "process):", "",
        _sizes_table("cases", iter_runs), "",
        f"**Crossover: {iter_runs['runs'][cluster]['crossover']:,.3g} cases, {work_s:.3g} s of "
        f"serial work**; `DASK_MIN_WORK_S` = {DASK_MIN_WORK_S:g} s (automatic runs project it "
        "from their first cases)."])
    return md, {"load_average": [load_before, load_after], "guide": guide,
                "iter": iter_runs, "iter_case_s": case_s,
                "iter_crossover_work_s": work_s, "dask_min_samples": DASK_MIN_SAMPLES,
                "dask_min_work_s": DASK_MIN_WORK_S}


def _kernels() -> dict[str, tuple[Callable[[], object], int]]:
    """Small kernels of tapp's shapes, and how many calls make one timing."""
    rng = np.random.default_rng(SEED)
    block, orbit = rng.standard_normal((1000, 23)), rng.standard_normal((23, 23))
    rows = rng.standard_normal((400, 100))
    s = rng.standard_normal((60, 60))
    s = s @ s.T + 60 * np.eye(60)
    rhs = rng.standard_normal((60, 10))
    return {"TAPP II block product (1000x23)(23x23)": (lambda: block @ orbit, 200),
            "TAPP I pass QR (400x100, R only)": (lambda: np.linalg.qr(rows, mode="r"), 20),
            "TAPP III solve (60x60, 10 columns)": (lambda: np.linalg.solve(s, rhs), 200)}


def _per_call_us(fn: Callable[[], object], calls: int, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, time.perf_counter() - start)
    return 1e6 * best / calls


def blas_threads() -> tuple[str, dict]:
    """The kernels with the default BLAS threads and with one, idle and loaded."""
    default = max(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas")
    results: dict[str, dict] = {}
    for loaded in (False, True):
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                for _ in range(HOGS if loaded else 0)]
        try:
            for name, (fn, calls) in _kernels().items():
                row = results.setdefault(name, {})
                for threads in (default, 1):
                    with threadpool_limits(limits=threads, user_api="blas"):
                        row[f"{'loaded' if loaded else 'idle'}, {threads}"] = _per_call_us(
                            fn, calls)
        finally:
            for hog in hogs:
                hog.kill()
                hog.wait()
    rows = [[name, *(f"{r[f'{state}, {default}']:.0f} / {r[f'{state}, 1']:.0f} "
                     f"({r[f'{state}, {default}'] / r[f'{state}, 1']:.1f}x)"
                     for state in ("idle", "loaded"))] for name, r in results.items()]
    md = "\n".join([
        "### BLAS threads", "",
        f"Per call, best of 5, µs: OpenBLAS's default ({default} threads on "
        f"{available_cores()} cores) / one thread (every command and local worker now); "
        f"loaded: {HOGS} processes spinning meanwhile.", "",
        markdown_table(["kernel", "idle", "loaded"], rows)])
    return md, {"default_threads": default, "kernels_us": results}


def run() -> Section:
    """Run the CLI section; return its Markdown and raw numbers."""
    startup_md, startup_data = startup()
    threads_md, threads_data = blas_threads()
    where_md, where_data = where_work_runs()
    md = "\n".join(["## The tapp command", "", startup_md, "", where_md, "", threads_md])
    return Section(NAME, md, {"target_s": TARGET_S, "repeats": REPEATS, **startup_data,
                              "where_work_runs": where_data, "blas_threads": threads_data})


if __name__ == "__main__":
    print(run().markdown)
