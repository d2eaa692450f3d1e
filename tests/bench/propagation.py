"""Propagation benchmark: tapp against heyoka and SciPy on the canonical workload.

Workload (the issue): circular orbit a = 6550.524 km, i = 0° and 30°, 24 h, output every
60 s, EGM96 J2 and 5x5 fields (θ0 = 0), tolerance 1e-12, state only and state + STM, for
tapp under each of its integration methods (DOP853 and RKN12(10)), heyoka (Taylor, LLVM JIT)
and SciPy ``solve_ivp`` DOP853 with a NumPy right-hand side, all in one process and one run.

Targets (ratios of best times taken in this run; "tapp" is its faster method on the row):

- every case (issue 22): tapp no slower than heyoka at tolerance 1e-12;
- state + STM, J2: tapp at most 3x heyoka's time; state + STM, 5x5: no slower (earlier
  issues, implied by the first);
- every case: tapp at least 50x faster than SciPy;
- final position within 0.1 mm of heyoka at machine-precision tolerance (1 mm before issue
  22), STM within 1e-10 relative of heyoka's over the grid, and every tool within 1 m of
  every other over the whole grid.

heyoka is timed in each compact mode whose JIT is practical and its faster time is used
(non-compact 5x5 + STM is skipped: its JIT took 14 min in a trial). The
one-time costs (tapp's C compile, heyoka's JIT) are reported separately, cold (empty
caches) and warm (a second process/build reading the on-disk cache).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import heyoka as hy
import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator, Trajectory, earth_model
from tapp.dynamics.compiled import METHODS
from tapp.dynamics.equations import build_equations
from tests.bench.baselines import (
    HeyokaPropagator,
    J2Field,
    Run,
    casadi_rhs,
    check_j2_field,
    heyoka_system,
    numpy_j2_rhs,
    scipy_propagate,
)
from tests.bench.common import (
    REPO_ROOT,
    Section,
    Timing,
    logger,
    markdown_table,
    time_calls,
    timed_once,
)

NAME = "propagation"

SMA_km = 6550.524
INCLINATIONS_deg = (0.0, 30.0)
FIELDS = ("J2", "5x5")
DURATION_s = 86400.0
OUTPUT_STEP_s = 60.0
THETA0_rad = 0.0
TIMED_TOL = 1e-12
DEFAULT_TOL = Propagator(earth_model("J0")).rtol  # tapp's default (rtol = atol)

# Targets from the issues.
MAX_TIME_RATIO = 1.0  # tapp (faster method) / heyoka, every case (issue 22)
J2_STM_MAX_TIME_RATIO = 3.0  # tapp / heyoka
FIELD_5X5_STM_MAX_TIME_RATIO = 1.0  # tapp / heyoka
SCIPY_MIN_SPEEDUP = 50.0  # SciPy / tapp
STM_MAX_REL = 1e-10  # max ||ΔΦ||_F / ||Φ||_F against heyoka over the grid (issue 22)
tenth_mm_km = 1e-7
one_m_km = 1e-3

REPEATS_FAST = 21
REPEATS_SCIPY = 3
SCIPY_BUDGET_s = 5.0  # stop repeating a SciPy case (after 2 runs) beyond this total

# heyoka compact modes timed per (field, stm); the faster one is compared with tapp.
HEYOKA_MODES = {("J2", False): (False, True), ("J2", True): (False, True),
                ("5x5", False): (False, True), ("5x5", True): (True,)}
# One-off trial (not re-run by the bench): non-compact 5x5 + STM, tol 1e-12, 2-CPU AMD EPYC,
# heyoka 7.13.2: JIT 861 s, best run 55.8 ms (i = 0°) and 55.0 ms (i = 30°), 291/286 steps.
HEYOKA_5X5_STM_NONCOMPACT_TRIAL = {"jit_s": 861.0, "run_ms": 55.0}
log = logger(NAME)


def output_grid_s() -> np.ndarray:
    """(1441,) output times 0, 60, ..., 86400 s."""
    return np.arange(0.0, DURATION_s + 0.5 * OUTPUT_STEP_s, OUTPUT_STEP_s)


def circular_state(inclination_deg: float) -> np.ndarray:
    """(6,) km, km/s: on the x axis (ascending node), circular speed in the inclined plane."""
    i = np.radians(inclination_deg)
    v = np.sqrt(GM_EARTH_km3_s2 / SMA_km)
    return np.array([SMA_km, 0.0, 0.0, 0.0, v * np.cos(i), v * np.sin(i)])


# ---------------------------------------------------------------- one-time costs

_COMPILE_PROBE = """
import json, sys, time
from tapp.dynamics import Propagator, earth_model
from tapp.dynamics.compiled import generate_source
from tapp.dynamics.equations import build_equations, second_order
model, method = earth_model(sys.argv[1]), sys.argv[2]
t0 = time.perf_counter()
Propagator(model, method=method).compiled()
t1 = time.perf_counter()
eqs = build_equations(model, model)
if method == "rkn12":
    eqs = second_order(eqs)
t2 = time.perf_counter()
generate_source(eqs.f_state, eqs.f_var, eqs.f_event)
t3 = time.perf_counter()
print(json.dumps({"compiled_s": t1 - t0, "equations_s": t2 - t1, "c_source_s": t3 - t2}))
"""


def tapp_compile_cost(field: str, method: str, cache_dir: Path) -> dict[str, float]:
    """First ``Propagator.compiled()`` in a fresh process with ``TAPP_CACHE_DIR=cache_dir``.

    Also times, in the same process, the CasADi equation build and the C source generation,
    which every process pays (the cache skips only the compiler).
    """
    env = dict(os.environ, TAPP_CACHE_DIR=str(cache_dir))
    before = set(cache_dir.glob("*.so"))
    proc = subprocess.run([sys.executable, "-c", _COMPILE_PROBE, field, method], env=env,
                          cwd=REPO_ROOT, capture_output=True, text=True, check=True)
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out["libraries_written"] = len(set(cache_dir.glob("*.so")) - before)
    return out


def tapp_compile_costs() -> dict[str, dict]:
    """Cold (empty cache directory) and warm (second process) compile cost per field and
    method (keys ``"<field> <method>"``)."""
    costs = {}
    with tempfile.TemporaryDirectory(prefix="tapp-bench-cache-") as tmp:
        for field in FIELDS:
            for method in METHODS:
                cold = tapp_compile_cost(field, method, Path(tmp))
                warm = tapp_compile_cost(field, method, Path(tmp))
                assert cold["libraries_written"] == 1 and warm["libraries_written"] == 0
                costs[f"{field} {method}"] = {"cold": cold, "warm": warm}
                log(f"tapp compile {field} {method}: cold {cold['compiled_s']:.2f} s, "
                    f"warm {warm['compiled_s']:.3f} s")
    return costs


@dataclass(slots=True)
class HeyokaSet:
    """heyoka integrators keyed by (field, stm, compact_mode) at TIMED_TOL, and the
    machine-precision references keyed by (field, stm); with their JIT costs."""

    timed: dict[tuple[str, bool, bool], HeyokaPropagator]
    reference: dict[tuple[str, bool], HeyokaPropagator]
    jit: list[dict]


def build_heyoka(cache_dir: Path) -> HeyokaSet:
    """Build every heyoka integrator; time each construction cold and warm.

    Cold: empty in-memory cache and a fresh on-disk cache directory. Warm: in-memory cache
    cleared again, so the code comes from heyoka's on-disk cache (what a second run pays).
    """
    previous = hy.llvm_state.get_diskcache_path()
    hy.llvm_state.set_diskcache_path(str(cache_dir))
    timed, reference, jit = {}, {}, []
    try:
        for field in FIELDS:
            model = earth_model(field)
            system_s, system = timed_once(lambda m=model: heyoka_system(m, THETA0_rad))
            configs = [(stm, mode, TIMED_TOL) for stm in (False, True)
                       for mode in HEYOKA_MODES[field, stm]]
            configs += [(False, True, None), (True, True, None)]
            for stm, mode, tol in configs:
                def build(system=system, stm=stm, mode=mode, tol=tol):
                    return HeyokaPropagator(system, stm=stm, tol=tol, compact_mode=mode)
                hy.llvm_state.clear_memcache()
                cold_s, _ = timed_once(build)
                hy.llvm_state.clear_memcache()
                warm_s, prop = timed_once(build)
                jit.append({"field": field, "stm": stm, "compact_mode": mode,
                            "tol": tol, "cold_s": cold_s, "warm_s": warm_s,
                            "expression_build_s": system_s})
                if tol is None:
                    reference[field, stm] = prop
                else:
                    timed[field, stm, mode] = prop
                log(f"heyoka JIT {field} {'state+STM' if stm else 'state'} "
                    f"compact={mode} tol={tol or 'eps'}: cold {cold_s:.2f} s, warm {warm_s:.2f} s")
    finally:
        hy.llvm_state.set_diskcache_path(previous)
    return HeyokaSet(timed, reference, jit)


# ---------------------------------------------------------------- comparisons


def max_position_diff_km(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |Δr| (km) over the grid between two (N, 6) state arrays."""
    return float(np.max(np.linalg.norm(a[:, :3] - b[:, :3], axis=1)))


def final_position_diff_km(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a[-1, :3] - b[-1, :3]))


def max_relative_stm_diff(a: np.ndarray, b: np.ndarray) -> float:
    """max over the grid of ||ΔΦ||_F / ||Φ||_F."""
    return float(np.max(np.linalg.norm(a - b, axis=(1, 2)) / np.linalg.norm(b, axis=(1, 2))))


def _case_label(inc_deg: float, field: str, stm: bool) -> str:
    return f"i={inc_deg:g}°, {field}, {'state+STM' if stm else 'state'}"


def run_case(inc_deg: float, field: str, stm: bool, heyoka: HeyokaSet,
             reference: Run, scipy_rhs: tuple[str, object]) -> dict:
    """Time and compare the three tools on one case; return the raw numbers."""
    x0 = circular_state(inc_deg)
    grid = output_grid_s()
    model = earth_model(field)
    case: dict = {"inclination_deg": inc_deg, "field": field, "stm": stm,
                  "label": _case_label(inc_deg, field, stm), "best_method": {}}

    tapp_runs: dict[tuple[str, float], tuple[Timing, Trajectory]] = {}
    for method in METHODS:
        for tol in (TIMED_TOL, DEFAULT_TOL):
            prop = Propagator(model, rtol=tol, atol=tol, method=method)
            prop.propagate(x0, grid, stm=stm, theta0_rad=THETA0_rad)  # warm-up (load, page-in)
            tapp_runs[method, tol] = time_calls(lambda p=prop: p.propagate(
                x0, grid, stm=stm, theta0_rad=THETA0_rad), REPEATS_FAST)

    hy_runs: dict[bool, tuple[Timing, Run]] = {}
    for mode in HEYOKA_MODES[field, stm]:
        ta = heyoka.timed[field, stm, mode]
        ta.propagate(x0, grid)
        hy_runs[mode] = time_calls(lambda ta=ta: ta.propagate(x0, grid), REPEATS_FAST)
    best_mode = min(hy_runs, key=lambda m: hy_runs[m][0].best_s)
    hy_timing, hy_run = hy_runs[best_mode]

    rhs_label, rhs = scipy_rhs
    sp_timing, sp_run = time_calls(lambda: scipy_propagate(rhs, x0, grid, stm=stm,
                                                           tol=TIMED_TOL),
                                   REPEATS_SCIPY, budget_s=SCIPY_BUDGET_s)

    case["heyoka"] = {"best_compact_mode": best_mode, "modes": {
        ("compact" if m else "non-compact"): {
            "timing": t, "steps": r.steps, "taylor_order": heyoka.timed[field, stm, m].ta.order,
            "decomposition_size": len(heyoka.timed[field, stm, m].ta.decomposition)}
        for m, (t, r) in hy_runs.items()}}
    case["heyoka_vs_reference_final_mm"] = 1e6 * final_position_diff_km(hy_run.states,
                                                                        reference.states)
    case["scipy"] = {"timing": sp_timing, "rhs": rhs_label,
                     "rhs_evaluations": sp_run.rhs_evaluations,
                     "vs_reference_final_mm": 1e6 * final_position_diff_km(sp_run.states,
                                                                           reference.states),
                     "vs_heyoka_max_m": 1e3 * max_position_diff_km(sp_run.states,
                                                                    hy_run.states)}
    if stm:
        case["scipy"]["stm_vs_heyoka_rel"] = max_relative_stm_diff(sp_run.stm, hy_run.stm)
        case["heyoka_stm_vs_reference_rel"] = max_relative_stm_diff(hy_run.stm, reference.stm)

    case["tapp"] = {}
    for (method, tol), (timing, traj) in tapp_runs.items():
        entry = {
            "method": method, "tol": tol, "timing": timing, "steps": traj.steps,
            "rhs_evaluations": traj.rhs_evaluations,
            "us_per_rhs": 1e6 * timing.best_s / traj.rhs_evaluations,
            "ratio_to_heyoka": timing.best_s / hy_timing.best_s,
            "scipy_speedup": sp_timing.best_s / timing.best_s,
            "vs_heyoka_max_m": 1e3 * max_position_diff_km(traj.states, hy_run.states),
            "vs_scipy_max_m": 1e3 * max_position_diff_km(traj.states, sp_run.states),
            "vs_reference_final_mm": 1e6 * final_position_diff_km(traj.states,
                                                                  reference.states),
        }
        if stm:
            entry["stm_vs_heyoka_rel"] = max_relative_stm_diff(traj.stm, hy_run.stm)
            entry["stm_vs_reference_rel"] = max_relative_stm_diff(traj.stm, reference.stm)
        entry["all_tools_max_m"] = max(entry["vs_heyoka_max_m"], entry["vs_scipy_max_m"],
                                       case["scipy"]["vs_heyoka_max_m"])
        case["tapp"][f"{method} {tol!r}"] = entry
    for tol in (TIMED_TOL, DEFAULT_TOL):
        best = min(METHODS, key=lambda m, tol=tol: case["tapp"][f"{m} {tol!r}"]["timing"].best_s)
        case["best_method"][repr(tol)] = best
        entry = case["tapp"][f"{best} {tol!r}"]
        entry["targets"] = targets(field, stm, tol, entry)
    return case


def best_entry(case: dict, tol: float) -> dict:
    """tapp's entry with its faster method at ``tol`` on this case."""
    return case["tapp"][f"{case['best_method'][repr(tol)]} {tol!r}"]


def targets(field: str, stm: bool, tol: float, entry: dict) -> dict[str, bool]:
    """Each target of the issues that applies to the case, and whether it is met. Issue 22's
    ≤ 1x heyoka is defined on the 1e-12 workload (both tools at 1e-12), not at tapp's
    tighter default."""
    met = {}
    if tol == TIMED_TOL:
        met[f"≤{MAX_TIME_RATIO:g}x heyoka"] = entry["ratio_to_heyoka"] <= MAX_TIME_RATIO
    if stm:
        limit = J2_STM_MAX_TIME_RATIO if field == "J2" else FIELD_5X5_STM_MAX_TIME_RATIO
        met[f"≤{limit:g}x heyoka (STM)"] = entry["ratio_to_heyoka"] <= limit
        met[f"STM <{STM_MAX_REL:g}"] = entry["stm_vs_reference_rel"] < STM_MAX_REL
    met[f"≥{SCIPY_MIN_SPEEDUP:g}x SciPy"] = entry["scipy_speedup"] >= SCIPY_MIN_SPEEDUP
    met["<0.1 mm final"] = entry["vs_reference_final_mm"] < tenth_mm_km * 1e6
    met["tools <1 m"] = entry["all_tools_max_m"] < one_m_km * 1e3
    return met


# ---------------------------------------------------------------- report


def _ms(t: Timing) -> str:
    return f"{t.best_ms:.3g} ({t.median_ms:.3g})"


def _met(checks: dict[str, bool]) -> str:
    failed = [name for name, ok in checks.items() if not ok]
    return "yes" if not failed else "NO: " + ", ".join(failed)


def render(data: dict) -> str:
    main_rows, detail_rows = [], []
    for case in data["cases"]:
        hy_best = case["heyoka"]["modes"]["compact" if case["heyoka"]["best_compact_mode"]
                                          else "non-compact"]
        sp = case["scipy"]
        for tol in (TIMED_TOL, DEFAULT_TOL):
            e = best_entry(case, tol)
            dop = case["tapp"][f"dop853 {tol!r}"]
            main_rows.append([
                case["label"], f"{tol:.0e}", e["method"], _ms(e["timing"]),
                _ms(dop["timing"]), _ms(hy_best["timing"]), _ms(sp["timing"]),
                f"{e['ratio_to_heyoka']:.2f}", f"{dop['ratio_to_heyoka']:.2f}",
                f"{e['scipy_speedup']:.0f}", f"{e['vs_heyoka_max_m']:.1e}",
                f"{e['vs_reference_final_mm']:.4f}",
                f"{e['steps']} / {e['rhs_evaluations']}",
                f"{dop['steps']} / {dop['rhs_evaluations']}", hy_best["steps"],
                sp["rhs_evaluations"], _met(e["targets"])])
        e = best_entry(case, TIMED_TOL)
        per_rhs = ", ".join(f"{m} {case['tapp'][f'{m} {TIMED_TOL!r}']['us_per_rhs']:.3f}"
                            for m in METHODS)
        modes = " / ".join(f"{k} {v['timing'].best_ms:.3g} ms, {v['steps']} steps"
                           for k, v in case["heyoka"]["modes"].items())
        hy_us_step = 1e3 * hy_best["timing"].best_ms / hy_best["steps"]
        detail_rows.append([
            case["label"], modes, f"{hy_us_step:.1f}",
            f"{hy_best['taylor_order']} / {hy_best['decomposition_size']}",
            per_rhs, f"{sp['rhs']}: {sp['rhs_evaluations']} RHS", f"{e['all_tools_max_m']:.1e}",
            f"{case['heyoka_vs_reference_final_mm']:.4f}",
            f"{sp['vs_reference_final_mm']:.3f}",
            f"{e['stm_vs_heyoka_rel']:.1e}" if case["stm"] else "—",
            f"{e['stm_vs_reference_rel']:.1e}" if case["stm"] else "—",
            f"{case['heyoka_stm_vs_reference_rel']:.1e}" if case["stm"] else "—",
            f"{sp['stm_vs_heyoka_rel']:.1e}" if case["stm"] else "—"])
    main = markdown_table(
        ["case", "tol", "tapp method", "tapp ms best (median)", "tapp DOP853 ms",
         "heyoka ms best (median)", "SciPy ms best (median)", "tapp/heyoka",
         "DOP853/heyoka", "SciPy/tapp", "max Δr tapp–heyoka(1e-12) over grid (m)",
         "final Δr tapp–heyoka(eps) (mm)", "tapp steps / RHS", "DOP853 steps / RHS",
         "heyoka steps", "SciPy RHS", "targets met"], main_rows)
    detail = markdown_table(
        ["case", "heyoka tol 1e-12 by mode", "heyoka µs/step (best mode)",
         "heyoka Taylor order / decomposition size",
         "tapp µs/RHS (1e-12, whole call)", "SciPy", "max Δr any two tools over grid (m)",
         "final Δr heyoka(1e-12)–heyoka(eps) (mm)", "final Δr SciPy–heyoka(eps) (mm)",
         "max ‖ΔΦ‖/‖Φ‖ tapp–heyoka", "max ‖ΔΦ‖/‖Φ‖ tapp–heyoka(eps)",
         "max ‖ΔΦ‖/‖Φ‖ heyoka–heyoka(eps)", "max ‖ΔΦ‖/‖Φ‖ SciPy–heyoka"], detail_rows)

    jit_rows = []
    for key, c in data["tapp_compile"].items():
        jit_rows.append([
            "tapp", f"{key} (state and state+STM, one library)",
            f"{c['cold']['compiled_s']:.2f}", f"{c['warm']['compiled_s']:.3f}",
            f"warm = CasADi equations {c['warm']['equations_s']:.3f} s + C source "
            f"{c['warm']['c_source_s']:.3f} s + hash + dlopen; no compiler call"])
    for j in data["heyoka_jit"]:
        jit_rows.append([
            "heyoka", f"{j['field']} {'state+STM' if j['stm'] else 'state'}, "
            f"{'compact' if j['compact_mode'] else 'non-compact'}, tol "
            f"{'eps' if j['tol'] is None else format(j['tol'], '.0e')}",
            f"{j['cold_s']:.2f}", f"{j['warm_s']:.3f}",
            f"expressions + diff {j['expression_build_s']:.3f} s (not included)"])
    jit = markdown_table(["tool", "model", "cold (s)", "warm, second run (s)", "notes"],
                         jit_rows)

    all_met = data["summary"]["all_targets_met_at_1e-12"]
    lines = [
        "## Propagation",
        "",
        f"Workload: circular a = {SMA_km} km, i = 0° and 30°, {DURATION_s / 3600:g} h, "
        f"output every {OUTPUT_STEP_s:g} s ({output_grid_s().size} points), EGM96 fields, "
        f"θ0 = 0. Times: best (median) of {REPEATS_FAST} runs for tapp and heyoka, of "
        f"up to {REPEATS_SCIPY} for SciPy; ratios use best times. heyoka runs at tol 1e-12 in "
        "its faster compact mode (see details); its machine-precision run (tol = eps, "
        "compact, with the STM for the STM rows) is the accuracy reference. SciPy: "
        "solve_ivp DOP853, rtol = atol = 1e-12, "
        "error on every component (with the STM too), t_eval = grid. tapp controls the "
        "step on the 6 state components only (its default); each row shows its faster "
        f"method ({', '.join(METHODS)}) and DOP853 beside it; steps / RHS counts right-hand "
        "side calls (rkn12: accelerations of the second-order form).",
        "",
        main,
        "",
        f"Targets: every row ≤ {MAX_TIME_RATIO:g}x heyoka (issue 22), state+STM J2 ≤ "
        f"{J2_STM_MAX_TIME_RATIO:g}x heyoka, state+STM 5x5 ≤ "
        f"{FIELD_5X5_STM_MAX_TIME_RATIO:g}x heyoka, ≥ {SCIPY_MIN_SPEEDUP:g}x SciPy, final "
        f"position < 0.1 mm from heyoka(eps), STM within {STM_MAX_REL:g} of heyoka(eps)'s "
        "over the grid, all tools within 1 m over the grid. The speed "
        "targets are defined at 1e-12; rows at tapp's default tolerance "
        f"({DEFAULT_TOL:.0e}) are held to the same STM and SciPy ratios against the tools at "
        "1e-12 (not to issue 22's ≤ 1x, a 1e-12 target).",
        "",
        f"**All targets met at 1e-12: {'yes' if all_met else 'NO'}**; at tapp's default "
        f"tolerance: {'yes' if data['summary']['all_targets_met_at_default'] else 'NO'}.",
        "",
        "### Details",
        "",
        detail,
        "",
        "### One-time costs (compile / JIT)",
        "",
        jit,
        "",
        "Non-compact heyoka with the 5x5 state+STM system is not run here: in a one-off trial "
        f"on this machine its JIT took {HEYOKA_5X5_STM_NONCOMPACT_TRIAL['jit_s']:.0f} s and "
        f"it then ran the case in {HEYOKA_5X5_STM_NONCOMPACT_TRIAL['run_ms']:.0f} ms "
        "(i = 0° and 30°), still slower than tapp.",
    ]
    return "\n".join(lines)


def run() -> Section:
    """Run the propagation section; return its Markdown and raw numbers."""
    grid = output_grid_s()
    equations = {f: build_equations(earth_model(f), earth_model(f)) for f in FIELDS}
    j2_field = J2Field.of(earth_model("J2"))
    gradient_error = check_j2_field(j2_field, equations["J2"])
    log(f"NumPy J2 gradient vs central differences: relative error {gradient_error:.1e}")

    compile_costs = tapp_compile_costs()
    with tempfile.TemporaryDirectory(prefix="heyoka-bench-cache-") as tmp:
        heyoka = build_heyoka(Path(tmp))

    cases = []
    for inc in INCLINATIONS_deg:
        x0 = circular_state(inc)
        for field in FIELDS:
            references = {stm: heyoka.reference[field, stm].propagate(x0, grid)
                          for stm in (False, True)}
            for stm in (False, True):
                if field == "J2":
                    rhs = ("NumPy closed-form J2", numpy_j2_rhs(j2_field, stm))
                else:
                    rhs = ("CasADi RHS called from Python",
                           casadi_rhs(equations[field], stm, THETA0_rad))
                case = run_case(inc, field, stm, heyoka, references[stm], rhs)
                e = best_entry(case, TIMED_TOL)
                log(f"{case['label']}: tapp {e['method']} {e['timing'].best_ms:.3f} ms, ratio "
                    f"to heyoka {e['ratio_to_heyoka']:.2f}, SciPy {e['scipy_speedup']:.0f}x "
                    "slower")
                cases.append(case)

    def all_met(tol: float) -> bool:
        return all(all(best_entry(c, tol)["targets"].values()) for c in cases)

    data = {
        "workload": {"sma_km": SMA_km, "inclinations_deg": list(INCLINATIONS_deg),
                     "fields": list(FIELDS), "duration_s": DURATION_s,
                     "output_step_s": OUTPUT_STEP_s, "theta0_rad": THETA0_rad,
                     "timed_tol": TIMED_TOL, "tapp_default_tol": DEFAULT_TOL},
        "targets": {"max_time_ratio": MAX_TIME_RATIO,
                    "j2_stm_max_time_ratio": J2_STM_MAX_TIME_RATIO,
                    "5x5_stm_max_time_ratio": FIELD_5X5_STM_MAX_TIME_RATIO,
                    "scipy_min_speedup": SCIPY_MIN_SPEEDUP, "final_position_max_mm": 0.1,
                    "stm_max_rel": STM_MAX_REL, "tools_agree_max_m": 1.0},
        "numpy_j2_gradient_rel_error": gradient_error,
        "tapp_compile": compile_costs,
        "heyoka_jit": heyoka.jit,
        "heyoka_5x5_stm_noncompact_trial": HEYOKA_5X5_STM_NONCOMPACT_TRIAL,
        "cases": cases,
        "summary": {"all_targets_met_at_1e-12": all_met(TIMED_TOL),
                    "all_targets_met_at_default": all_met(DEFAULT_TOL)},
    }
    return Section(NAME, render(data), data)
