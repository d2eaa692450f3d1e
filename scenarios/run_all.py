"""`make scenario`: every reproduction run, results under results/.

1. The propagation demo (foundation): SATORB2 with (J2,J2) and (J2,J0), 24 h.
2. The approximate-STM study: every run of the brief -> results/approx_stm/report.md.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from tapp.od.study import planned_cases, run_study
from tapp.report.approx_stm import write_report

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"


def propagation_demo() -> None:
    out = RESULTS / "propagate"
    out.mkdir(parents=True, exist_ok=True)
    for stm in ("J2", "J0"):
        cmd = [sys.executable, "-m", "tapp.cli", "propagate", "--orbit", "SATORB2", "--hours",
               "24", "--step", "60", "--truth", "J2", "--stm", stm, "--json"]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
        (out / f"satorb2_J2_{stm}.json").write_text(proc.stdout)
    print(f"propagation demo -> {out}")


def approx_stm_study() -> None:
    start = time.perf_counter()
    with Progress(TextColumn("{task.description:<40}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn()) as bar:
        task = bar.add_task("approximate-STM study", total=planned_cases())
        results = run_study(advance=lambda label: bar.update(task, advance=1,
                                                             description=label))
    report = write_report(results, RESULTS / "approx_stm", time.perf_counter() - start)
    print(f"approximate-STM study -> {report}")


def main() -> None:
    propagation_demo()
    approx_stm_study()


if __name__ == "__main__":
    main()
