"""`make scenario`: every reproduction run, results under results/.

The input files are the examples shipped in the package (:mod:`tapp.examples`, the files
`tapp examples DIR` copies).

1. The propagation demo (foundation): SATORB2 with (J2,J2) and (J2,J0), 24 h.
2. The approximate-STM study: every run of the brief -> results/approx_stm/report.md.
3. SEARCH: the lunar B-plane targeting of search_bplane.toml, differenced and
   analytic partials -> results/search/ (the seed's report, and the same run as JSON).
4. TAPP I: tracking simulations of leo_equatorial, deep_space and leo_drag.toml -> T13 tapes,
   their summaries and trajectories (CCSDS OEM) in results/tapp1/.
5. TAPP III: each TAPP I tape through its deck (tapp3_*.toml) -> O3 printouts, JSON,
   plots, T32 tapes and results/tapp3/report.md (fit vs real σ of the miss at each recycle, the
   error budget of the final miss covariance), and deep_space.toml with ΔDOR added
   (:data:`DDOR_TABLE`) through the same deck: the miss σ with and without ΔDOR.
6. The whole pipeline (TAPP I -> TAPP III -> TAPP II) of pipeline_deep_space.toml
   -> results/pipeline/ (report.md: fit vs real σ of the miss at each midcourse time, ΔV and
   final-miss statistics, Monte Carlo beside linear covariance, plots).
7. ITER: the seed's examples (five azimuths, type 1 and 2; 30 days x 5 azimuths), the
   departure-day sweep with SEARCH as the body, and the tracking trade study with the whole
   pipeline as the body, on a local Dask cluster -> results/iter/ (report.md; summary.json:
   the cases, failures and wall time of each sweep).
8. Your own mission: the examples' mission folder (its OEM with a deterministic burn, its
   booked DSN passes) through TAPP I, III and II -> results/mission/ (the tape, the OEM
   flown, the O3 printout, the T32 tape, the guidance report and every JSON); and the Mars
   2028 transfer (tapp/examples/mars/): its pipeline and its trade study (ΔDOR x passes per
   week) -> results/mars/ (report.md).
9. The README's figures: read from results/ into results/readme_figures.json and a README
   rendered from them (results/README.md), compared with the committed ones, and the claims
   of the prose around them checked (scenarios/readme.py); the tracked files are left alone:
   ``make readme`` takes the run's figures into them.

Steps 1, 3-6, 8 (its two runs) and the first four sweeps of 7 are independent of one another
(5 reads 4's tapes) and run side by side (:func:`side_by_side`), as do the commands inside
4 and 5: each runs tapp's commands, or its sweep's Dask cluster, as processes of their own.
Step 2 and the tracking sweep then run alone, one after the other, as before: the README
quotes their wall times (the study's, the tracking sweep's on 2 workers), which would grow
with the machine shared. The numbers are those of the runs one at a time.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from iter import CaseStatus, Execution, load_sweep, run_sweep
from scenarios import readme
from tapp.examples import FOLDER as EXAMPLES
from tapp.od.study import planned_cases, run_study
from tapp.od.study_file import shipped_study
from tapp.report.markdown import table
from tapp.report.od import write_report
from tapp.report.pipeline import ellipse_and_ric_sections, recycle_sigma_table
from tapp.report.sweeps import plot_departure_sweep

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"


def side_by_side(*steps: Callable[[], object]) -> list:
    """Run the steps at once, each in a thread of its own, and return their results in order.

    The steps run tapp's commands as processes of their own (a thread only waits for them),
    so they run in parallel. A step that fails (SystemExit with the command's error) is
    raised once all have ended."""
    with ThreadPoolExecutor(max_workers=len(steps)) as pool:
        futures = [pool.submit(step) for step in steps]
    return [future.result() for future in futures]


def propagation_demo() -> None:
    out = RESULTS / "propagate"
    out.mkdir(parents=True, exist_ok=True)
    for stm in ("J2", "J0"):
        cmd = [sys.executable, "-m", "tapp.cli", "propagate", "--orbit", "SATORB2", "--arc",
               "24h", "--step", "60s", "--truth", "J2", "--stm", stm, "--json", "-"]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
        (out / f"satorb2_J2_{stm}.json").write_text(proc.stdout)
    print(f"propagation demo -> {out}")


def approx_stm_study() -> None:
    start = time.perf_counter()
    with Progress(TextColumn("{task.description:<40}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn()) as bar:
        study = shipped_study()
        task = bar.add_task("approximate-STM study", total=planned_cases(study))
        results = run_study(study, advance=lambda label: bar.update(task, advance=1,
                                                                    description=label))
    report = write_report(results, RESULTS / "approx_stm", time.perf_counter() - start)
    print(f"approximate-STM study -> {report}")


def _tapp(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tapp.cli", *args], capture_output=True,
                          text=True, check=False)


def search_targeting() -> None:
    out = RESULTS / "search"
    out.mkdir(parents=True, exist_ok=True)
    for mode, extra in (("differenced", ()), ("analytic", ("--analytic-partials",))):
        for suffix, form in (("txt", ()), ("json", ("--json", "-"))):  # the seed's report; numbers
            proc = _tapp("search", str(EXAMPLES / "search_bplane.toml"), *extra, *form)
            (out / f"report_{mode}.{suffix}").write_text(proc.stdout)
            if proc.returncode != 0:
                raise SystemExit(f"tapp search ({mode}) exited {proc.returncode}: "
                                 f"{proc.stderr}")
    print(f"SEARCH lunar B-plane targeting -> {out}")


def _simulate(name: str, out: Path) -> None:
    tape = out / f"{name}.t13.h5"
    proc = _tapp("simulate", str(EXAMPLES / f"{name}.toml"), "-o", str(tape),
                 "--oem", str(out / f"{name}.oem"))
    if proc.returncode != 0:
        raise SystemExit(f"tapp simulate {name} exited {proc.returncode}: {proc.stderr}")
    info = _tapp("tape", "info", str(tape))
    (out / f"{name}.info.txt").write_text(info.stdout)


def tracking_simulations() -> None:
    out = RESULTS / "tapp1"
    out.mkdir(parents=True, exist_ok=True)
    side_by_side(*(partial(_simulate, name, out)
                   for name in ("leo_equatorial", "deep_space", "leo_drag")))
    print(f"TAPP I tapes -> {out}")


#: (TAPP I scenario, TAPP III deck) pairs of the matrix-processor reproduction.
TAPP3_RUNS = (("leo_equatorial", "tapp3_leo_equatorial"), ("deep_space", "tapp3_deep_space"),
              ("leo_drag", "tapp3_leo_drag"), ("tapp1_table_d1", "tapp3_table_d1"))


def _budget_section(name: str, content: dict) -> list[str]:
    block = [b for b in content["blocks"] if b["kind"] == "print"][-1]
    ent = next((e for e in block["entities"] if e.get("budget") and e["alias"] == "cov-real m"),
               None)
    if ent is None:
        return []
    b = ent["budget"]
    rows = [[src, *(f"{v:.3g}" for v in sig)] for src, sig in zip(b["sources"], b["sigma"],
                                                                 strict=True)]
    rows.append(["**total**", *(f"{v:.3g}" for v in ent["sigma"])])
    return [f"### {name}: error budget of the miss at t = {block['t_s'] / 86400:.2f} d "
            f"(σ per source, signed; closure {b['closure']:.1g})", "",
            table(["source", *ent["rows"]], rows)]


#: ΔDOR added to deep_space.toml for the with/without comparison (the shipped file stays
#: without it, its figures the README's): one point per mutual-visibility window of
#: Goldstone-Canberra and Goldstone-Madrid, 0.06 ns (1.8 cm) white in the fit, plus a 0.03 ns
#: bias per window in the real world (Thornton & Border 2003, ch. 7: DSN ΔDOR ~0.05-0.1 ns).
DDOR_TABLE = """
[ddor]
baselines = [["GOLDSTONE", "CANBERRA"], ["GOLDSTONE", "MADRID"]]
min_window_s = 1800.0
quasar_separation_deg = 5.0
[ddor.fit]
sigma_ns = 0.06
[ddor.real]
sigma_ns = 0.06
bias_ns = 0.03
"""


def _miss_sigmas(content: dict) -> dict[float, dict[str, list[float]]]:
    """{print time (s): {"cov-fit m" / "cov-real m": σ of each miss parameter}}."""
    return {b["t_s"]: {e["alias"]: e["sigma"] for e in b["entities"]
                       if e["alias"] in ("cov-fit m", "cov-real m")}
            for b in content["blocks"] if b["kind"] == "print"}


def _ddor_run(out: Path) -> None:
    """Run deep_space.toml + :data:`DDOR_TABLE` through TAPP I and the deep-space deck."""
    scenario = out / "deep_space_ddor.toml"
    scenario.write_text((EXAMPLES / "deep_space.toml").read_text() + DDOR_TABLE)
    tape = RESULTS / "tapp1" / "deep_space_ddor.t13.h5"
    for args in (("simulate", str(scenario), "-o", str(tape)),
                 ("process", str(tape), str(EXAMPLES / "tapp3_deep_space.toml"),
                  "--print", str(out / "deep_space_ddor.o3.txt"),
                  "--json", str(out / "deep_space_ddor.json"))):
        proc = _tapp(*args)
        if proc.returncode != 0:
            raise SystemExit(f"tapp {args[0]} deep_space_ddor exited {proc.returncode}: "
                             f"{proc.stderr}")


def ddor_comparison(out: Path) -> tuple[list[str], dict]:
    """The report's section of the ΔDOR run (:func:`_ddor_run`, run first): σ of B·R, B·T at
    each print time without and with ΔDOR; and the run's JSON content."""
    scenario = out / "deep_space_ddor.toml"
    contents = [json.loads((out / f"{name}.json").read_text())
                for name in ("deep_space", "deep_space_ddor")]
    without, with_ddor = (_miss_sigmas(c) for c in contents)
    miss = contents[0]["history"]["miss"]
    shown = [i for i, name in enumerate(miss) if name in ("b_dot_r_km", "b_dot_t_km")]
    rows = []
    for t_s in sorted(without):
        if t_s == 0.0:
            continue
        cells = [f"{t_s / 86400:.3f}"]
        for i in shown:
            for world in ("cov-fit m", "cov-real m"):
                cells.append(f"{1e3 * without[t_s][world][i]:.4g} / "
                             f"{1e3 * with_ddor[t_s][world][i]:.4g}")
        rows.append(cells)
    label = {"b_dot_r_km": "B·R", "b_dot_t_km": "B·T"}
    headers = ["t (d)", *(f"σ {label[miss[i]]} {world} (m): without / with ΔDOR"
                          for i in shown for world in ("fit", "real"))]
    return [f"## deep_space with ΔDOR (`{scenario.name}`: deep_space.toml + [ddor])", "",
            "Goldstone-Canberra and Goldstone-Madrid, one ΔDOR point per mutual-visibility "
            "window, σ 0.06 ns (fit and real white) + 0.03 ns per window (real); same deck. "
            "Miss σ at each print time:", "", table(headers, rows), ""], contents[1]


def _process(scenario: str, deck: str, out: Path) -> float:
    """Process the TAPP I tape of ``scenario`` (simulated first if results/tapp1 has none)
    with ``deck``; return the wall time of the processing, s."""
    tape = RESULTS / "tapp1" / f"{scenario}.t13.h5"
    if not tape.exists():
        proc = _tapp("simulate", str(EXAMPLES / f"{scenario}.toml"), "-o",
                     str(tape))
        if proc.returncode != 0:
            raise SystemExit(f"tapp simulate {scenario} exited {proc.returncode}: "
                             f"{proc.stderr}")
    start = time.perf_counter()
    proc = _tapp("process", str(tape), str(EXAMPLES / f"{deck}.toml"),
                 "--print", str(out / f"{scenario}.o3.txt"), "--tape",
                 str(out / f"{scenario}.t32.h5"), "--json", str(out / f"{scenario}.json"),
                 "--plots", str(out / "plots" / scenario))
    if proc.returncode != 0:
        raise SystemExit(f"tapp process {scenario} exited {proc.returncode}: {proc.stderr}")
    return time.perf_counter() - start


def matrix_processor() -> None:
    out = RESULTS / "tapp3"
    out.mkdir(parents=True, exist_ok=True)
    lines = ["# TAPP III: fit world vs real world\n",
             "Each TAPP I tape of results/tapp1 (and the Table D-1 coding example) processed "
             "with its deck from the shipped examples: O3 printouts (`*.o3.txt`), JSON, T32 "
             "tapes and plots (`plots/<name>/`).\n"]
    budgets: list[str] = []
    *walls, _ = side_by_side(*(partial(_process, scenario, deck, out)
                               for scenario, deck in TAPP3_RUNS), partial(_ddor_run, out))
    for (scenario, deck), wall in zip(TAPP3_RUNS, walls, strict=True):
        content = json.loads((out / f"{scenario}.json").read_text())
        lines += [f"## {scenario} (deck `{deck}.toml`, {wall:.1f} s)", "",
                  f"Miss parameters {', '.join(content['history']['miss'])}; σ at each "
                  "recycle (TAPP II's midcourse times), fit world vs real world:", ""]
        lines += [recycle_sigma_table(content)]
        lines += ["", *ellipse_and_ric_sections(content)]
        plots = sorted((out / "plots" / scenario).glob("*.png"))
        lines += [f"![{p.stem}](plots/{scenario}/{p.name})" for p in plots] + [""]
        budgets += _budget_section(scenario, content)
    section, content = ddor_comparison(out)
    lines += section
    budgets += _budget_section("deep_space_ddor", content)
    (out / "report.md").write_text("\n".join(lines + ["## Error budgets", ""] + budgets))
    print(f"TAPP III -> {out / 'report.md'}")


def pipeline_run() -> None:
    out = RESULTS / "pipeline"
    shutil.rmtree(out, ignore_errors=True)  # a pipeline never overwrites: this is a re-run
    proc = _tapp("pipeline", str(EXAMPLES / "pipeline_deep_space.toml"), "-o",
                 str(out), "--workers", "2")
    if proc.returncode != 0:
        raise SystemExit(f"tapp pipeline exited {proc.returncode}: {proc.stderr}")
    print(f"pipeline -> {out / 'report.md'}")


def mission_run() -> None:
    """The mission folder (tapp/examples/mission/) as the tutorial's "Your own mission" runs
    it, into results/mission/."""
    out, mission = RESULTS / "mission", EXAMPLES / "mission"
    out.mkdir(parents=True, exist_ok=True)
    steps = (("simulate", str(mission / "mission.toml"), "-o", str(out / "mission.t13.h5"),
              "--oem", str(out / "flown.oem"), "--json", str(out / "simulate.json")),
             ("process", str(out / "mission.t13.h5"), str(mission / "mission_deck.toml"),
              "--print", str(out / "mission.o3.txt"), "--tape", str(out / "mission.t32.h5"),
              "--json", str(out / "process.json")),
             ("guide", str(out / "mission.t32.h5"), str(mission / "mission_guidance.toml"),
              "--samples", "100000", "--seed", "1", "--json", str(out / "guide.json")))
    for args in steps:
        proc = _tapp(*args)
        if proc.returncode != 0:
            raise SystemExit(f"tapp {args[0]} mission exited {proc.returncode}: {proc.stderr}")
        (out / f"{args[0]}.txt").write_text(proc.stdout)
    print(f"your own mission -> {out}")


#: The Mars example's files (tapp/examples/mars/), copied beside its tape for the trade study.
MARS_FILES = ("mars.toml", "mars_deck.toml", "mars_guidance.toml", "mars_pipeline.toml",
              "mars_trade.toml")


def mars_run() -> None:
    """The Mars 2028 transfer: the whole pipeline into results/mars/pipeline/ (B-plane
    ellipses, TCM ΔV), then its trade study (ΔDOR x passes per week) on that run's tape, both
    in this process's own processes, serially (a case is 1.6 s: a cluster's start-up would
    cost more than its second worker saves, and the other steps use the second core), with
    the example's files copied beside it into results/mars/trade/ (the sweep reads its tape
    from its own folder), and results/mars/report.md."""
    out = RESULTS / "mars"
    shutil.rmtree(out, ignore_errors=True)  # a pipeline never overwrites: this is a re-run
    proc = _tapp("pipeline", str(EXAMPLES / "mars" / "mars_pipeline.toml"), "-o",
                 str(out / "pipeline"), "--serial")
    if proc.returncode != 0:
        raise SystemExit(f"tapp pipeline (Mars) exited {proc.returncode}: {proc.stderr}")
    trade = out / "trade"
    trade.mkdir()
    for name in MARS_FILES:
        shutil.copy(EXAMPLES / "mars" / name, trade / name)
    shutil.copy(out / "pipeline" / "run.t13.h5", trade / "mars.t13.h5")
    start = time.perf_counter()
    res = run_sweep(load_sweep(trade / "mars_trade.toml"), output_h5=trade / "mars_trade.h5",
                    output_csv=trade / "mars_trade.csv", execution=Execution(serial=True))
    wall_s = time.perf_counter() - start
    res.raise_if_all_failed()
    (trade / "mars.t13.h5").unlink()  # the pipeline's own copy stays
    (out / "report.md").write_text("\n".join(_mars_report(res.table, wall_s)) + "\n")
    print(f"Mars 2028 -> {out / 'report.md'}")


def _mars_report(tab, wall_s: float) -> list[str]:
    """results/mars/report.md: the pipeline's report by reference, the trade study's table."""
    ok = tab.column("status") == int(CaseStatus.OK)
    rows = []
    for i in range(len(ok)):
        case = ["on" if tab.column("ddor")[i] else "off",
                f"{float(tab.column('passes_per_week')[i]):g}"]
        if not ok[i]:
            rows.append([*case, "failed", "", "", ""])
            continue
        v = {n: float(tab.column(n)[i]) for n in ("bplane_semi_major_km",
                                                  "bplane_semi_minor_km",
                                                  "sigma_flight_time_s", "dv_total_99_m_s")}
        rows.append([*case, f"{v['bplane_semi_major_km']:.2f}",
                     f"{v['bplane_semi_minor_km']:.2f}", f"{v['sigma_flight_time_s']:.2f}",
                     f"{v['dv_total_99_m_s']:.2f}"])
    return ["# Mars 2028 transfer", "",
            "The whole pipeline: [pipeline/report.md](pipeline/report.md) (TAPP I, III, II; "
            "the B-plane ellipses at each TCM, the TCM ΔV statistics).", "",
            "## Trade study: ΔDOR x DSN passes per week (TAPP III and II on one tape)", "",
            f"Final miss after TCM-4 (Monte Carlo, 5,000 samples per case), {len(ok)} cases "
            f"in {wall_s:.0f} s, serially ([trade/mars_trade.csv](trade/mars_trade.csv)).",
            "",
            table(["ΔDOR", "passes per week", "1σ B-plane semi-major (km)",
                   "1σ semi-minor (km)", "σ arrival time (s)", "99 % total ΔV (m/s)"], rows)]


def _tracking_section(tab) -> list[str]:
    """The tracking trade study: final-miss σ and 99 % ΔV against data interval x network."""
    networks = ("GOLDSTONE, CANBERRA, MADRID", "GOLDSTONE, CANBERRA", "GOLDSTONE")
    ok = tab.column("status") == int(CaseStatus.OK)
    rows = []
    for i in range(len(ok)):
        net = networks[int(tab.column("network")[i])]
        dt = f"{float(tab.column('data_interval_s')[i]):g}"
        if not ok[i]:
            rows.append([net, dt, "failed", "", "", "", ""])
            continue
        value = {name: float(tab.column(name)[i]) for name in (
            "sigma_b_dot_r_km", "sigma_b_dot_t_km", "sigma_flight_time_s",
            "dv_total_99_m_s", "outside_corridor")}
        rows.append([net, dt, f"{value['sigma_b_dot_r_km']:.3f}",
                     f"{value['sigma_b_dot_t_km']:.3f}", f"{value['sigma_flight_time_s']:.3f}",
                     f"{value['dv_total_99_m_s']:.1f}", f"{value['outside_corridor']:.2%}"])
    return ["", "## Tracking trade study (the whole pipeline as the body)", "",
            "Final miss after the third correction (Monte Carlo, 5,000 samples per case) "
            "against the DSN network and the data interval; stations outside the network are "
            "switched off in TAPP III for the whole run. The fit world weights white noise and "
            "holds GM of the Moon fixed, so denser data do not always help: the real world's "
            "per-pass biases and correlated noise do not average down.", "",
            table(["network", "data interval (s)", "σ B·R (km)", "σ B·T (km)",
                   "σ t_f (s)", "99 % total ΔV (m/s)", "outside corridor"], rows)]


#: The sweeps of step 7, in the report's order. The last, the tracking trade study, is the
#: one whose wall time the README quotes.
SWEEPS = ("iter_azimuth_type1", "iter_azimuth_type2", "iter_days_azimuths",
          "iter_lunar_departure", "iter_pipeline_tracking")


def run_sweeps(names: tuple[str, ...]) -> dict[str, tuple]:
    """Run the sweeps ``names`` one after the other, each on a local cluster of 2 workers;
    return {name: (results, wall time in s)} for :func:`sweeps_report`."""
    out = RESULTS / "iter"
    out.mkdir(parents=True, exist_ok=True)
    done = {}
    for name in names:
        sweep = load_sweep(EXAMPLES / f"{name}.toml")
        h5 = out / f"{name}.h5"
        h5.unlink(missing_ok=True)  # a fresh run, not a resume
        start = time.perf_counter()
        res = run_sweep(sweep, output_h5=h5, output_csv=out / f"{name}.csv",
                        execution=Execution(workers=2), progress=True)
        wall_s = time.perf_counter() - start
        res.raise_if_all_failed()  # no answer to report: stop here, the failures recorded
        done[name] = (res, wall_s)
    return done


def sweeps_report(done: dict[str, tuple]) -> None:
    """results/iter/summary.json and report.md from the runs of every sweep of
    :data:`SWEEPS` (:func:`run_sweeps`)."""
    out = RESULTS / "iter"
    lines = ["# ITER sweeps\n"]
    tables, summary = {}, {}
    for name in SWEEPS:
        res, wall_s = done[name]
        tables[name] = res.table
        summary[name] = {"cases": res.summary.n_cases, "succeeded": res.summary.n_succeeded,
                         "failed": res.summary.n_failed, "workers": 2, "wall_s": wall_s}
        lines.append(f"- `{name}`: {res.summary.n_cases} cases, {res.summary.n_succeeded} "
                     f"succeeded, {res.summary.n_failed} failed in {wall_s:.0f} s on 2 "
                     f"workers -> `{name}.csv`")
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    tab = tables["iter_lunar_departure"]
    day = np.asarray(tab.column("departure_day"), dtype=float)
    ok = tab.column("status") == int(CaseStatus.OK)
    dv = np.asarray(tab.column("dv_km_s"), dtype=float)
    tof = np.asarray(tab.column("flight_time_s"), dtype=float)
    plot_departure_sweep(day, dv, tof, ok, out / "lunar_departure.png")
    rows = [[f"{d:g}", f"{v * 1e3:.1f}" if k else "failed", f"{t / 86400:.3f}" if k else "—"]
            for d, v, t, k in zip(day, dv, tof, ok, strict=True)]
    lines += ["", "## Departure-day sweep (SEARCH as the body)", "",
              table(["day", "ΔV (m/s)", "flight time (d)"], rows),
              "![ΔV per day](lunar_departure.png)", ""]
    lines += _tracking_section(tables["iter_pipeline_tracking"])
    (out / "report.md").write_text("\n".join(lines))
    print(f"ITER sweeps -> {out / 'report.md'}")


def sweeps() -> None:
    sweeps_report(run_sweeps(SWEEPS))


def readme_figures() -> None:
    if readme.main(["--compare"]) != 0:
        raise SystemExit("a claim of the README's prose no longer holds (listed above)")
    print(f"README figures -> {readme.RUN_README} ({readme.RUN_DATA})")


def main() -> None:
    # Side by side: the steps whose wall times the README does not quote (module docstring).
    *_, first_sweeps = side_by_side(propagation_demo, search_targeting,
                                    lambda: (tracking_simulations(), matrix_processor()),
                                    pipeline_run, mission_run, mars_run,
                                    partial(run_sweeps, SWEEPS[:-1]))
    # Alone: the README quotes their wall times.
    approx_stm_study()
    sweeps_report({**first_sweeps, **run_sweeps(SWEEPS[-1:])})
    readme_figures()


if __name__ == "__main__":
    main()
