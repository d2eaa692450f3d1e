"""The approximate-STM study report: Markdown tables, PNG plots, raw numbers as JSON."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.od.batch import rms_tail_probability
from tapp.od.setup import describe_orientation
from tapp.od.study import DCRun, StudyResults
from tapp.orbit.elements import cartesian_to_elements
from tapp.report.figures import subplots
from tapp.report.markdown import table


def _rms_at(run: DCRun, k: int) -> str:
    rms = run.result.rms
    return f"{rms[k - 1]:.4g}" if len(rms) >= k else "—"


def _converged_at(run: DCRun) -> str:
    k = run.result.converged_at
    return "—" if k is None else str(k)


def _elements(run: DCRun) -> list[str]:
    a, e, i, raan, argp, mean = np.asarray(cartesian_to_elements(run.result.x0, GM_EARTH_km3_s2))
    return [f"{a:.4f}", f"{e:.6f}", f"{math.degrees(i):.5f}"]


def _rho(run: DCRun) -> str:
    if run.rate is None:
        return "—"
    return f"{run.rate.rho:.3g}" + (" (osc.)" if run.rate.oscillating else "")


def _q(run: DCRun) -> str:
    q = run.result.contraction_factor
    return "—" if not np.isfinite(q) else f"{q:.3g}"


def _reason(run: DCRun) -> str:
    return f"- {run.orbit} ({run.truth},{run.stm}) {run.arc_h:g} h: {run.result.reason}"


def dc_section(results: StudyResults) -> str:
    """Tables of every DC block: outcome, iteration of convergence, RMS at 1/6/12/last,
    observed factor q and predicted ρ, state reached."""
    out = []
    for title in results.dc_blocks:
        runs = [r for r in results.dc if r.block == title]
        rows = [[r.orbit, f"({r.truth},{r.stm})", f"{r.arc_h:g}", r.result.status,
                 _converged_at(r), str(len(r.result.iterations)), _rms_at(r, 1),
                 _rms_at(r, 6), _rms_at(r, 12), f"{r.result.rms[-1]:.4g}",
                 f"{r.result.rms_bound:.4g}", _q(r), _rho(r),
                 *_elements(r), f"{r.position_error_km * 1e3:.3g}"]
                for r in runs]
        out.append(f"### {title}\n\n" + table(
            ["orbit", "(J_N,J_M)", "arc (h)", "outcome", "converged at", "iterations",
             "RMS 1", "RMS 6", "RMS 12", "RMS last", "99.9 % bound", "observed q",
             "predicted ρ", "a (km)",
             "e", "i (deg)", "epoch pos. error (m)"], rows))
        out.append("\n".join(_reason(r) for r in runs) + "\n")
    return "\n".join(out)


def _eigenvalues(run: DCRun, n: int = 2) -> str:
    if run.rate is None:
        return "—"
    vals = run.rate.eigenvalues[:n]
    return ", ".join(f"{v.real:.3g}" if abs(v.imag) <= 1e-9 * max(abs(v), 1e-300)
                     else f"{v.real:.3g}{v.imag:+.3g}i" for v in vals)


def _agreement(run: DCRun) -> str:
    """(q - ρ)/ρ, where q measures a linear rate: ρ >= 0.05 and 5 iterations or more."""
    q = run.result.contraction_factor
    if run.rate is None or not np.isfinite(q) or run.rate.rho < 0.05 or \
            len(run.result.iterations) < 5:
        return "—"
    return f"{100 * (q - run.rate.rho) / run.rate.rho:+.1f} %"


def rate_section(results: StudyResults) -> str:
    """ρ beside the observed factor, the outcome and R_M/R_N for every truncated-STM run."""
    runs = [r for r in results.dc if r.stm != r.truth]
    rows = [[r.orbit, f"({r.truth},{r.stm})", f"{r.arc_h:g}", _rho(r), _eigenvalues(r),
             _q(r), _agreement(r), f"{r.result.status} ({len(r.result.iterations)})",
             f"{r.r_ratio:.3g}"] for r in runs]
    exact = [r for r in results.dc if r.stm == r.truth and r.rate is not None]
    largest = max((r.rate.rho for r in exact), default=float("nan"))
    return (
        "Every DC run with a truncated variational model, with its predicted rate ρ (the "
        "spectral radius of M = I − (H̃ᵀWH̃)⁻¹H̃ᵀWH at the true state, from the run's "
        "observation times, stations and weights; `tapp.od.rate`), the two largest "
        "eigenvalues of M (a complex pair, \"osc.\", makes the error rotate and the RMS "
        "oscillate), the observed contraction factor q of the iterations (the pace at which "
        "the corrections shrink, measured over the last half of the iterations), the outcome "
        "with the number of iterations run, and the study's own predictor, R_M/R_N = R(t) of "
        "the variational model over R(t) of the state model at the end of the arc. With the "
        f"exact variational model (J_M = J_N) M = 0: ρ ≤ {largest:.1g} (rounding) in the "
        f"{len(exact)} runs of the tables above, which converge quadratically. \"q vs ρ\" "
        "is given where q can measure a linear rate (ρ ≥ 0.05, 5 iterations or more); in the "
        "diverging runs q is measured far from the solution, where the iteration is no "
        "longer linear: there ρ > 1 says that the error grows, not how fast.\n\n"
        + table(["orbit", "(J_N,J_M)", "arc (h)", "predicted ρ", "largest eigenvalues of M",
                 "observed q", "q vs ρ", "outcome (iterations)", "R_M/R_N at arc end"],
                rows))


def _extent(values: list[float]) -> list[float] | None:
    """[smallest, largest] of the finite ``values``, or None."""
    vals = [v for v in values if np.isfinite(v)]
    return [min(vals), max(vals)] if vals else None


def _intervals(x: np.ndarray, mask: np.ndarray, after: int = 0) -> list[tuple[float, float]]:
    """Contiguous runs of ``mask`` (from index ``after`` on) as (first x, last x) pairs."""
    out, start = [], None
    for k in range(after, len(x)):
        if mask[k] and start is None:
            start = k
        if start is not None and (not mask[k] or k == len(x) - 1):
            stop = k if mask[k] else k - 1
            out.append((float(x[start]), float(x[stop])))
            start = None
    return out


def _label(r: DCRun) -> str:
    return f"{r.orbit} ({r.truth},{r.stm}) {r.arc_h:g} h"


def _run_finding(r: DCRun) -> dict:
    """One truncated-STM run as the findings quote it."""
    return {"label": _label(r), "orbit": r.orbit, "truth": r.truth, "stm": r.stm,
            "arc_h": r.arc_h, "r_ratio": r.r_ratio, "rho": r.rate.rho,
            "status": r.result.status, "iterations": len(r.result.iterations)}


def rate_findings(results: StudyResults) -> dict | None:
    """Where ρ and R(t) agree and where they do not, as numbers (JSON-ready; ``results.json``
    ``"rate_findings"``; :func:`rate_discussion` words them), or None without a truncated-STM
    run that has both.

    ``predicted`` of ``runs`` truncated-STM outcomes foretold by ρ (ρ < 1: the iteration
    converges); ``linear_worst_relative`` the largest |q − ρ|/ρ over the ``linear_runs`` runs
    with 0.1 < ρ < 1 that converge in 8 iterations or more; ``series`` the longest series of
    arcs of one orbit and model pair (R_M/R_N and ρ along it); ``r_ratio_converging`` and
    ``r_ratio_failing`` the [smallest, largest] R_M/R_N of the runs that converge (or are
    converging) and of those that do not; ``large_r_converging`` the converging runs whose
    R_M/R_N exceeds 1; ``same_r_pair`` the two runs within 15 % in R_M/R_N that differ most
    in ρ; ``inclination`` the inclinations (deg) of ρ < 1 on the first truncated curve;
    ``arc`` where ρ first exceeds 1 along the arc curve, the arcs (h) of ρ < 1 after it and
    the DC runs past that point.
    """
    runs = [r for r in results.dc if r.stm != r.truth and r.rate is not None and
            np.isfinite(r.r_ratio)]
    if not runs:
        return None
    linear = [r for r in runs if 0.1 < r.rate.rho < 1 and r.result.iteration_converges and
              len(r.result.iterations) >= 8]
    worst = max((abs(r.result.contraction_factor - r.rate.rho) / r.rate.rho for r in linear),
                default=float("nan"))
    out: dict = {"runs": len(runs),
                 "predicted": sum((r.rate.rho < 1) == r.result.iteration_converges
                                  for r in runs),
                 "linear_runs": len(linear), "linear_worst_relative": _finite(worst)}
    # agreement: one orbit and model pair over several arcs
    by_pair: dict[tuple[str, str, str, str], list[DCRun]] = {}
    for r in runs:  # one block's arcs of one orbit and model pair
        by_pair.setdefault((r.block, r.orbit, r.truth, r.stm), []).append(r)
    series = max(by_pair.values(), key=lambda rs: len({r.arc_h for r in rs}))
    series = sorted({r.arc_h: r for r in series}.values(), key=lambda r: r.arc_h)
    out["series"] = [_run_finding(r) for r in series] if len(series) >= 2 else None
    # disagreement: R cannot separate the outcomes
    conv = [r for r in runs if r.result.iteration_converges]
    out["r_ratio_converging"] = _extent([r.r_ratio for r in conv])
    out["r_ratio_failing"] = _extent([r.r_ratio for r in runs
                                      if not r.result.iteration_converges])
    out["large_r_converging"] = [_run_finding(r) for r in conv if r.r_ratio > 1]
    pairs = [(a, b) for i, a in enumerate(runs) for b in runs[i + 1:]
             if abs(np.log(a.r_ratio / b.r_ratio)) < np.log(1.15)]
    out["same_r_pair"] = [_run_finding(r) for r in max(
        pairs, key=lambda p: abs(np.log(p[0].rate.rho / p[1].rate.rho)))] if pairs else None
    out["inclination"] = None
    if results.rate_vs_inclination:
        c = next((c for c in results.rate_vs_inclination if c.truth != c.stm),
                 results.rate_vs_inclination[0])
        below = _intervals(c.x, c.rho < 1)
        if below:
            out["inclination"] = {"truth": c.truth, "stm": c.stm,
                                  "arc_h": results.inclination_arc_h,
                                  "below_one_deg": below}
    out["arc"] = None
    arc_curve = next((c for c in results.rate_vs_arc if c.truth != c.stm), None)
    if arc_curve is not None:
        above = np.flatnonzero(arc_curve.rho > 1)
        later = _intervals(arc_curve.x, arc_curve.rho < 1, after=above[0]) if above.size \
            else []
        if later:
            first_h = float(arc_curve.x[above[0]])
            checks = [r for r in runs if (r.orbit, r.truth, r.stm) ==
                      (arc_curve.orbit, arc_curve.truth, arc_curve.stm) and r.arc_h > first_h]
            out["arc"] = {"orbit": arc_curve.orbit, "truth": arc_curve.truth,
                          "stm": arc_curve.stm, "first_above_one_h": first_h,
                          "below_one_again_h": later,
                          "checks": [_run_finding(r) for r in
                                     sorted(checks, key=lambda r: r.arc_h)]}
    return out


def _ranges(extent: list[float] | None) -> str:
    return f"{extent[0]:.2g} .. {extent[1]:.2g}" if extent else "—"


def _span_text(intervals: list[tuple[float, float]], unit: str) -> str:
    return ", ".join(f"{a:g}-{b:g}{unit}" if b > a else f"{a:g}{unit}" for a, b in intervals)


def rate_discussion(results: StudyResults) -> str:
    """Where ρ and R(t) agree and where they do not, every number from the runs
    (:func:`rate_findings`)."""
    f = rate_findings(results)
    if f is None:
        return ""
    worst = f["linear_worst_relative"]
    out = ["### Where ρ and R(t) agree, and where they do not",
           f"ρ predicts the outcome of {f['predicted']} of the {f['runs']} truncated-STM runs "
           "before any iteration (ρ < 1: the iteration converged, its residuals consistent "
           "with the noise model or not, or is converging; ρ > 1: diverged or stalled). In "
           f"the {f['linear_runs']} runs that spend 8 iterations or more in the linear regime "
           "with 0.1 < ρ < 1, the observed factor q matches ρ within "
           f"{100 * (float('nan') if worst is None else worst):.1f} %: "
           "near the solution the DC is the fixed-point iteration e_(k+1) = M e_k."]
    if f["series"]:
        s0 = f["series"][0]
        steps = "; ".join(f"{r['arc_h']:g} h: R_M/R_N {r['r_ratio']:.2g}, ρ {r['rho']:.2g}"
                          for r in f["series"])
        out.append(
            "They agree on the trend the study read R(t) for: along one orbit, the longer "
            "the arc, the further the truncated STM departs from the true one, and both "
            f"signal it ({s0['orbit']} ({s0['truth']},{s0['stm']}), {steps}).")
    out.append(
        "They part company across orbits, because R(t) knows nothing of the data. R is the "
        "size of the STM's position rows; ρ weighs the STM error in the directions the "
        "tracking determines, with the weights the normal equations give them "
        "(M = (H̃ᵀWH̃)⁻¹H̃ᵀW(H̃ − H)). Among the runs that converge or are converging "
        f"R_M/R_N spans {_ranges(f['r_ratio_converging'])}, among those that do not "
        f"{_ranges(f['r_ratio_failing'])}: no threshold on R separates them.")
    big = f["large_r_converging"]
    if big:
        out.append(
            f"In {len(big)} converging runs ({', '.join(r['label'] for r in big)}) the "
            f"truncated model's R is {min(r['r_ratio'] for r in big):.2g} to "
            f"{max(r['r_ratio'] for r in big):.2g} times the true one, which R reads as a "
            f"badly wrong STM, yet ρ is {min(r['rho'] for r in big):.2g} to "
            f"{max(r['rho'] for r in big):.2g} and they converge, in "
            f"{min(r['iterations'] for r in big)} to "
            f"{max(r['iterations'] for r in big)} iterations.")
    if f["same_r_pair"]:
        a, b = f["same_r_pair"]
        out.append(
            f"{a['label']} and {b['label']} have nearly the same R_M/R_N ({a['r_ratio']:.3g} "
            f"and {b['r_ratio']:.3g}) but ρ = {a['rho']:.3g} and {b['rho']:.3g} "
            f"({a['status']} in {a['iterations']}, {b['status']} in {b['iterations']} "
            "iterations).")
    inc = f["inclination"]
    if inc:
        out.append(
            f"The inclination curve makes the same point: with the same stations and a "
            f"{inc['arc_h']:g} h arc, ρ of ({inc['truth']},{inc['stm']}) is below 1 "
            f"only over {_span_text(inc['below_one_deg'], '°')} and above 1 at the low and "
            "the near-retrograde-equatorial inclinations, a dependence on the geometry of the "
            "orbit and the network that R(t) does not have.")
    arc = f["arc"]
    if arc:
        told = "; ".join(f"{r['arc_h']:g} h: ρ {r['rho']:.3g}, {r['status']}"
                         for r in arc["checks"])
        out.append(
            "Nor does ρ grow steadily with the arc length, as R(t) does: for "
            f"{arc['orbit']} ({arc['truth']},{arc['stm']}) it first exceeds 1 at "
            f"{arc['first_above_one_h']:g} h, yet falls below 1 again over "
            f"{_span_text(arc['below_one_again_h'], ' h')}; the DC runs past that point do "
            f"what ρ says ({told}).")
    return out[0] + "\n\n" + out[1] + "\n\n" + " ".join(out[2:]) + "\n"


def ekf_section(results: StudyResults) -> str:
    """Largest |O-C| of the last passes per (model, a priori)."""
    n = results.last_passes
    rows = []
    for run in results.ekf:
        last = run.result.passes[-n:]
        rows.append([f"({run.truth},{run.stm})", run.apriori,
                     " / ".join(f"{p.max_abs[0] * 1e3:.1f}" for p in last),
                     " / ".join(f"{p.max_abs[1] * 1e6:.1f}" for p in last)])
    stations = ", ".join(p.station for p in results.ekf[0].result.passes[-n:]) if results.ekf \
        else ""
    return (f"### {results.ekf_title}\n\nLast {n} passes ({stations}); largest |O-C| per "
            "pass, prefit.\n\n" + table(["(J_N,J_M)", "a priori", "range (m)",
                                         "range-rate (mm/s)"], rows))


def rsig_section(results: StudyResults, png: str) -> str:
    """R(t) every 6 hours and the plot."""
    if not results.rsig:
        return ""
    t = results.rsig[0].signature.t_s
    idx = [int(k) for k in np.searchsorted(t, np.arange(0, t[-1] + 1, 6 * 3600.0))]
    rows = [[f"({r.truth},{r.stm})", *(f"{r.signature.r[k]:.4g}" for k in idx)]
            for r in results.rsig]
    return (f"### R(t) over {t[-1] / 3600:g} h, {results.rsig[0].orbit}\n\n"
            + table(["(J_N,J_M)", *(f"{t[k] / 3600:g} h" for k in idx)], rows)
            + f"\n![R(t)]({png})\n")


def plot_rsig(results: StudyResults, path: Path) -> None:
    fig, ax = subplots(figsize=(8, 5))
    for r in results.rsig:
        ax.plot(r.signature.t_s / 3600.0, r.signature.r, label=f"({r.truth},{r.stm})")
    ax.set_xlabel("time (h)")
    ax.set_ylabel("R(t) = sqrt(Σ φ_ij², i ≤ 3, j ≤ 6)")
    ax.set_yscale("log")
    ax.set_title(f"Error-growth signature, {results.rsig[0].orbit}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _observed_points(results: StudyResults, curve, x_of) -> tuple[list, list]:
    """(x, q) of the study's DC runs that belong on ``curve``: same models, x from x_of."""
    xs, qs = [], []
    for r in results.dc:
        x = x_of(r)
        if (r.truth, r.stm) == (curve.truth, curve.stm) and x is not None and \
                np.isfinite(r.result.contraction_factor):
            xs.append(x)
            qs.append(r.result.contraction_factor)
    return xs, qs


def _plot_curves(ax, curves, results: StudyResults, x_of, legend: str = "upper left") -> None:
    for c in curves:
        exact = c.truth == c.stm
        label = f"({c.truth},{c.stm})" + (f": ρ < {np.nanmax(c.rho):.0e}, zero to rounding"
                                           if exact else "")
        line, = ax.plot(c.x, c.rho, marker="o", ms=3, label=label)
        if not exact:  # the exact model's M is rounding: its eigenvalues mean nothing
            osc = c.oscillating & np.isfinite(c.rho)
            ax.plot(c.x[osc], c.rho[osc], "o", ms=7, mfc="none", color=line.get_color())
            xs, qs = _observed_points(results, c, x_of)
            ax.plot(xs, qs, "x", ms=9, mew=2, color="k")
    ax.plot([], [], "x", ms=9, mew=2, color="k",
            label="observed factor q of the study's DC runs")
    ax.plot([], [], "o", mfc="none", color="grey", label="complex dominant pair (oscillates)")
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.set_ylim(bottom=0)
    ax.set_ylabel("predicted rate ρ (spectral radius of M)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc=legend)


def _inclination_deg(x: np.ndarray) -> float:
    h = np.cross(x[:3], x[3:])
    return float(np.degrees(np.arccos(np.clip(h[2] / np.linalg.norm(h), -1, 1))))


def _same_orbit_shape(a: np.ndarray, b: np.ndarray) -> bool:
    """Same a and e (the curve's orbit with another inclination)."""
    ea = np.asarray(cartesian_to_elements(a, GM_EARTH_km3_s2))
    eb = np.asarray(cartesian_to_elements(b, GM_EARTH_km3_s2))
    return bool(abs(ea[0] - eb[0]) < 1e-6 and abs(ea[1] - eb[1]) < 1e-9)


def plot_rate_vs_arc(results: StudyResults, path: Path) -> None:
    """ρ against arc length for each (truth, STM) pair, with the study's observed factors."""
    fig, ax = subplots(figsize=(8, 5))
    orbit = results.rate_vs_arc[0].orbit
    _plot_curves(ax, results.rate_vs_arc, results,
                 lambda r: r.arc_h if r.orbit == orbit else None)
    ax.set_xlabel("arc length (h)")
    ax.set_title(f"Predicted DC convergence rate against arc length, {orbit} (ρ > 1 "
                 "diverges)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def plot_rate_vs_inclination(results: StudyResults, path: Path,
                             x_orbit: np.ndarray | None = None) -> None:
    """ρ against inclination for each (truth, STM) pair, with the study's observed factors
    of the runs of the same a and e over the same arc."""
    fig, ax = subplots(figsize=(8, 5))
    arc = results.inclination_arc_h
    c0 = results.rate_vs_inclination[0]
    ref = next((r.x_true for r in results.dc if r.orbit == c0.orbit and
                r.x_true is not None), x_orbit)

    def x_of(r):
        if r.arc_h != arc or r.x_true is None or ref is None or \
                not _same_orbit_shape(r.x_true, ref):
            return None
        return _inclination_deg(r.x_true)

    _plot_curves(ax, results.rate_vs_inclination, results, x_of, legend="lower left")
    ax.set_xlabel("inclination (deg)")
    ax.set_xticks(np.arange(0, 181, 30))
    ax.set_title(f"Predicted DC convergence rate against inclination ({c0.orbit}'s a, e; "
                 f"{arc:g} h, {results.inclination_network} network)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def rate_curves_section(results: StudyResults) -> str:
    """The two ρ plots with a line each on how they were made."""
    out = []
    if results.rate_vs_arc:
        c = results.rate_vs_arc[0]
        out.append(f"ρ against arc length, {c.orbit}, "
                   f"{', '.join(f'({k.truth},{k.stm})' for k in results.rate_vs_arc)}, arcs "
                   f"{c.x[0]:g} to {c.x[-1]:g} h every {c.x[1] - c.x[0]:g} h (noise-free "
                   "observation times of the study's network; crosses: the observed factor q "
                   "of the study's DC runs of this orbit):\n\n![rho vs arc](rho_vs_arc.png)\n")
    if results.rate_vs_inclination:
        c = results.rate_vs_inclination[0]
        out.append(f"ρ against inclination, {c.orbit}'s other elements, {c.x[0]:g} to "
                   f"{c.x[-1]:g} deg every {c.x[1] - c.x[0]:g} deg, "
                   f"{results.inclination_arc_h:g} h arc seen from the "
                   f"{results.inclination_network} network at every inclination (crosses: "
                   "the observed factor q of the study's DC runs of the same a and e over the "
                   "same arc):\n\n"
                   "![rho vs inclination](rho_vs_inclination.png)\n")
    return "\n".join(out)


def plot_dc_rms(results: StudyResults, path: Path) -> None:
    blocks = results.dc_blocks
    fig, axes = subplots(len(blocks), 1, figsize=(8, 3.2 * len(blocks)), squeeze=False)
    for ax, title in zip(axes[:, 0], blocks, strict=True):
        for r in (r for r in results.dc if r.block == title):
            ax.plot(np.arange(1, len(r.result.rms) + 1), r.result.rms, marker="o", ms=3,
                    label=f"{r.orbit} ({r.truth},{r.stm}) {r.arc_h:g} h")
        ax.set_yscale("log")
        ax.set_xlabel("iteration")
        ax.set_ylabel("weighted RMS")
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def write_report(results: StudyResults, out_dir: Path, elapsed_s: float) -> Path:
    """Write report.md, rsig.png, dc_rms.png, rho_vs_arc.png, rho_vs_inclination.png and
    results.json into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_rsig(results, out_dir / "rsig.png")
    plot_dc_rms(results, out_dir / "dc_rms.png")
    if results.rate_vs_arc:
        plot_rate_vs_arc(results, out_dir / "rho_vs_arc.png")
    if results.rate_vs_inclination:
        plot_rate_vs_inclination(results, out_dir / "rho_vs_inclination.png")
    nets = "\n".join(f"- {orbit}: {', '.join(names)}" for orbit, names in
                     results.network.items())
    text = [
        "# Orbit estimation with an approximate STM: the study reproduced\n",
        f"Generated by `make scenario` in {elapsed_s:.1f} s. Scenario: "
        "`approx_stm.toml` (the shipped study file, `tapp examples`); brief: "
        "`shared/seeds/approx-stm-study-brief.md`.\n",
        f"Observations: range σ = {results.sigma[0] * 1e3:g} m, range-rate σ = "
        f"{results.sigma[1] * 1e6:g} mm/s, 5-day files, 30 s sampling above a 5° mask. "
        "Weighted RMS = sqrt(Σ (O-C)² w / m) with w = 1/σ² (≈ 1 at the noise level). "
        "Iteration k's RMS is that of the estimate it starts from. " + _offset_text(results)
        + "\n",
        "Outcomes (`tapp.od.batch`): **converged** (the RMS settled within the fit limit "
        f"{results.settings.rms_fit_limit:g} and within the 99.9 % χ² bound of its residuals "
        "and 6 estimated parameters, the column \"99.9 % bound\"), **converged, residuals "
        "inconsistent with the noise model** (the RMS settled within the fit limit but above "
        "that bound: the data are not explained by the models and their σ), "
        "**converging** (the iteration limit was "
        "reached while the RMS was still falling geometrically: the observed factor and the "
        "projected iterations are in the notes), **stalled** (the RMS settled above the fit "
        "limit) and **diverged** (the RMS grew or failed to settle). Each DC iterates to "
        f"convergence or to {results.settings.max_iterations} iterations; the tables keep "
        "the RMS at iterations 1, 6 and 12 of the brief.\n",
        _orientation_text(results),
        "Stations per orbit:\n\n" + nets + "\n",
        "## Batch differential correction\n",
        dc_section(results),
        "![RMS against iteration](dc_rms.png)\n",
        "## Predicted convergence rate ρ\n",
        rate_section(results),
        rate_curves_section(results),
        rate_discussion(results),
        "## Extended Kalman filter\n",
        ekf_section(results),
        "## Error-growth signature\n",
        rsig_section(results, "rsig.png"),
    ]
    report = out_dir / "report.md"
    report.write_text("\n".join(text))
    raw = {
        "elapsed_s": elapsed_s,
        "earth_orientation": results.earth_orientation,
        "sigma_range_km": float(results.sigma[0]),
        "sigma_range_rate_km_s": float(results.sigma[1]),
        "last_passes": results.last_passes,
        "rate_findings": rate_findings(results),
        "dc": [{"block": r.block, "orbit": r.orbit, "truth": r.truth, "stm": r.stm,
                "arc_h": r.arc_h, "status": r.result.status, "reason": r.result.reason,
                "converged_at": r.result.converged_at, "rms": r.result.rms.tolist(),
                "rms_bound": r.result.rms_bound,
                # the study's DC has no a priori: 6 estimated parameters
                "rms_tail_probability": rms_tail_probability(r.result.rms[-1],
                                                             r.result.n_measurements),
                "steps": r.result.steps.tolist(),
                "contraction_factor": _finite(r.result.contraction_factor),
                "projected_iterations": r.result.projected_iterations,
                "predicted_rate": None if r.rate is None else r.rate.rho,
                "oscillating": None if r.rate is None else bool(r.rate.oscillating),
                "eigenvalues": None if r.rate is None else
                [[v.real, v.imag] for v in r.rate.eigenvalues],
                "r_ratio": _finite(r.r_ratio), "x0": r.result.x0.tolist(),
                "position_error_km": r.position_error_km} for r in results.dc],
        "ekf": [{"truth": r.truth, "stm": r.stm, "apriori": r.apriori,
                 "passes": [{"station": p.station, "t_start_s": p.t_start_s,
                             "max_abs": p.max_abs.tolist()} for p in r.result.passes]}
                for r in results.ekf],
        "rsig": [{"truth": r.truth, "stm": r.stm, "t_s": r.signature.t_s.tolist(),
                  "R": r.signature.r.tolist()} for r in results.rsig],
        "rate_vs_arc": [_curve_json(c, "arc_h") for c in results.rate_vs_arc],
        "rate_vs_inclination": [_curve_json(c, "inclination_deg")
                                for c in results.rate_vs_inclination],
    }
    (out_dir / "results.json").write_text(json.dumps(raw))
    return report


def _orientation_text(results: StudyResults) -> str:
    """The Earth orientation of the data and the estimators (stations and field)."""
    if not results.earth_orientation:
        return ""
    return ("Earth orientation of the simulated data and of every estimator (stations and "
            f"geopotential): {describe_orientation(results.earth_orientation)}.\n")


def _offset_text(results: StudyResults) -> str:
    off = results.offset
    if off is None:
        return ""
    da, di = off.da_km * 1e3, math.degrees(off.di_rad)
    if off.e is not None:
        return (f"Initial estimate of every run: the true elements + {da:g} m on a, e set to "
                f"{off.e:g}, + {di:g}° on i.")
    return (f"Initial estimate of every run: the true elements + {da:g} m on a, + {off.de:g} "
            f"on e, + {di:g}° on i (added, so an orbit of e = 0.1 starts at "
            f"e = {0.1 + off.de:g}).")


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _curve_json(c, name: str) -> dict:
    return {"orbit": c.orbit, "truth": c.truth, "stm": c.stm, name: c.x.tolist(),
            "rho": [_finite(v) for v in c.rho], "oscillating": c.oscillating.tolist()}
