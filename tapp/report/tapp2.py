"""Report of a TAPP II guidance study: Markdown tables, a JSON-ready dict, PNG plots.

:func:`guidance_markdown` sets the Monte Carlo beside the linear covariance (ΔV per manoeuvre
and in total, final miss, B-plane ellipse, corridor); :func:`guidance_dict` holds every
statistic in the code's units (km, km/s, s, rad; angles of ellipses in degrees, named so).
The plots, :func:`plot_bplane_scatter` (samples with the 1σ/3σ ellipses of both methods and
the corridor) and :func:`plot_dv_histograms` (|Δv| per manoeuvre with the 99 % of both
methods), import matplotlib only when called.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from tapp.guidance.statistics import Magnitude, Outcome, bplane_rows
from tapp.guidance.study import GuidanceResult
from tapp.report.markdown import table

_DAY_S = 86400.0
_M_PER_KM = 1000.0
_NAVIGATION = {"tape": "the tape's estimator (its a priori ignores the execution errors)",
               "inflate": "a priori inflated by the execution-error covariance, regression "
                          "re-run"}
#: Samples drawn in the B-plane scatter (the first ones: a deterministic subset).
SCATTER_SAMPLES = 20_000


def _magnitude_dict(m: Magnitude) -> dict:
    return {"mean_km_s": m.mean_km_s, "sigma_km_s": m.sigma_km_s,
            "percentiles_km_s": None if m.percentiles_km_s is None
            else {f"{p:g}": v for p, v in m.percentiles_km_s}}


def _outcome_dict(o: Outcome) -> dict:
    return {
        "method": o.method,
        "manoeuvres": [{"recycle": m.number, "t_s": m.t_s,
                        "dv_mean_km_s": m.dv_mean_km_s.tolist(),
                        "dv_cov_km2_s2": m.dv_cov.tolist(),
                        "magnitude": _magnitude_dict(m.magnitude)}
                       for m in o.manoeuvres],
        "total": _magnitude_dict(o.total),
        "miss_mean": o.miss_mean.tolist(), "miss_cov": o.miss_cov.tolist(),
        "bplane_ellipse": None if o.ellipse is None else {
            "semi_major_km": o.ellipse.semi_major_km, "semi_minor_km": o.ellipse.semi_minor_km,
            "angle_from_t_deg": o.ellipse.angle_deg},
        "flight_time_sigma_s": o.flight_time_sigma_s,
        "outside_corridor": None if o.outside is None else {
            "bplane": o.outside.bplane, "flight_time": o.outside.flight_time,
            "either": o.outside.either},
    }


def guidance_dict(r: GuidanceResult) -> dict:
    """The study as a JSON-ready dict (plain lists and floats)."""
    c = r.corridor
    return {
        "title": r.title, "tape": r.tape_source, "iden": r.tape_iden, "guide": r.guide_source,
        "targets": list(r.targets), "navigation": r.navigation,
        "miss_name": list(r.miss_name),
        "miss_unit": list(r.miss_unit),
        "execution": {"sigma_proportional": r.errors.sigma_proportional,
                      "sigma_pointing_rad": r.errors.sigma_pointing_rad,
                      "sigma_fixed_km_s": r.errors.sigma_fixed_km_s},
        "corridor": None if c is None else {
            "semi_axes_km": list(c.semi_axes_km), "angle_rad": c.angle_rad,
            "flight_time_s": c.flight_time_s},
        "samples": r.n_samples, "seed": r.seed, "block_samples": r.block_samples,
        "shard_samples": r.shard_samples, "where": r.where, "wall_s": r.wall_s,
        "monte_carlo": _outcome_dict(r.monte_carlo), "linear": _outcome_dict(r.linear),
    }


def _ms(value: float | None) -> str:
    return "—" if value is None else f"{value * _M_PER_KM:.3f}"


def _magnitude_row(m: Magnitude) -> list[str]:
    pct = [None] * 3 if m.percentiles_km_s is None else [v for _, v in m.percentiles_km_s]
    return [_ms(m.mean_km_s), _ms(m.sigma_km_s), *(_ms(v) for v in pct)]


def _fraction(value: float | None) -> str:
    if value is None:
        return "—"
    return f"{value:.4f}" if value == 0 or value >= 1e-3 else f"{value:.2e}"


def _dv_table(r: GuidanceResult) -> str:
    rows = []
    for mc, lin in zip(r.monte_carlo.manoeuvres, r.linear.manoeuvres, strict=True):
        when = [str(mc.number), f"{mc.t_s / _DAY_S:.3f}"]
        rows += [[*when, o.method, *_magnitude_row(m.magnitude)]
                 for o, m in ((r.monte_carlo, mc), (r.linear, lin))]
    rows += [["total", "", o.method, *_magnitude_row(o.total)]
             for o in (r.monte_carlo, r.linear)]
    return table(["recycle", "t (d)", "method", "mean", "σ", "50 %", "90 %", "99 %"], rows)


def _miss_table(r: GuidanceResult) -> str:
    mc, lin = r.monte_carlo, r.linear
    rows = [[name, unit, f"{mc.miss_mean[i]:.4g}", f"{math.sqrt(mc.miss_cov[i, i]):.4g}",
             f"{math.sqrt(max(lin.miss_cov[i, i], 0.0)):.4g}"]
            for i, (name, unit) in enumerate(zip(r.miss_name, r.miss_unit, strict=True))]
    return table(["component", "unit", "mean (MC)", "σ (MC)", "σ (linear)"], rows)


def _ellipse_table(r: GuidanceResult) -> str:
    rows = []
    for o in (r.monte_carlo, r.linear):
        e = o.ellipse
        rows.append([o.method, *(["—"] * 3 if e is None else
                                 [f"{e.semi_major_km:.4g}", f"{e.semi_minor_km:.4g}",
                                  f"{e.angle_deg:.2f}"]),
                     "—" if o.flight_time_sigma_s is None else f"{o.flight_time_sigma_s:.4g}"])
    return table(["method", "1σ semi-major (km)", "1σ semi-minor (km)",
                  "major axis from T toward R (deg)", "σ flight time (s)"], rows)


def _corridor_text(r: GuidanceResult) -> str:
    c = r.corridor
    a, b = c.semi_axes_km
    shape = (f"circle of radius {a:g} km" if a == b else
             f"ellipse of semi-axes {a:g} km x {b:g} km, the first "
             f"{math.degrees(c.angle_rad):g}° from T toward R")
    limit = "" if c.flight_time_s is None else f", |Δt_f| <= {c.flight_time_s:g} s"
    n = r.n_samples
    rows = []
    for o in (r.monte_carlo, r.linear):
        out = o.outside
        rows.append([o.method, _fraction(out.bplane), _fraction(out.flight_time),
                     _fraction(out.either)])
    se = math.sqrt(max(r.monte_carlo.outside.either * (1 - r.monte_carlo.outside.either), 0.0)
                   / n)
    return (f"Corridor: B-plane {shape} about the aim point{limit}. Monte Carlo fractions "
            f"have a binomial standard error of {se:.1e} (either).\n\n"
            + table(["method", "outside B-plane", "outside Δt_f limit", "outside either"], rows))


def guidance_markdown(r: GuidanceResult) -> str:
    """The study as Markdown: the Monte Carlo beside the linear covariance (module docstring).
    """
    e = r.errors
    corridor = [] if r.corridor is None else ["## Corridor", "", _corridor_text(r)]
    lines = [
        f"# TAPP II guidance study{': ' + r.title if r.title else ''}", "",
        f"Tape {r.tape_iden} ({r.tape_source}); guidance file {r.guide_source}.",
        f"Targets: {', '.join(r.targets)}. Execution errors (1σ, Gates-type): "
        f"{e.sigma_proportional * 100:g} % of |Δv| along Δv, "
        f"{e.sigma_pointing_rad * 1e3:g} mrad pointing per perpendicular axis, "
        f"{e.sigma_fixed_km_s * 1e6:g} mm/s fixed per axis.",
        f"Navigation after a manoeuvre: {_NAVIGATION[r.navigation]}.",
        f"Monte Carlo: {r.n_samples:,} samples, seed {r.seed} (RNG blocks of "
        f"{r.block_samples:,}, shards of {r.shard_samples:,}), {r.where}, "
        f"{r.wall_s:.2f} s.", "",
        "## ΔV magnitude per manoeuvre (m/s)", "", _dv_table(r),
        "Linear covariance: |Δv| of a Gaussian Δv of the propagated covariance (Imhof's "
        "formula), exact for the first manoeuvre; later Δv's are not Gaussian (execution "
        "errors scale with |Δv|), so their percentiles are the Gaussian approximation. The "
        "total's σ and percentiles need the joint law of the magnitudes (Monte Carlo only).",
        "", "## Final miss after the last correction", "", _miss_table(r),
        "The linear model's mean is zero; the sampling σ of a Monte Carlo mean is σ/√N.", "",
        "## B-plane dispersion (1σ)", "", _ellipse_table(r), *corridor,
    ]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------------------------


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_bplane_scatter(r: GuidanceResult, path: Path, title: str) -> Path:
    """Final (δB·T, δB·R) of the first :data:`SCATTER_SAMPLES` samples, with the 1σ and 3σ
    ellipses of the Monte Carlo (solid) and the linear covariance (dashed) and the
    corridor; needs the B-plane miss components."""
    from tapp.report.tapp3 import ellipse_points

    plt = _pyplot()
    bp = bplane_rows(r.miss_name)
    miss = r.samples.miss[:SCATTER_SAMPLES]
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    ax.plot(miss[:, bp[0]], miss[:, bp[1]], ".", ms=1.5, alpha=0.3, color="0.6",
            label=f"samples ({len(miss):,})", zorder=1)
    for o, color, style in ((r.monte_carlo, "tab:red", "-"), (r.linear, "tab:blue", "--")):
        cov = o.miss_cov[np.ix_(bp, bp)]
        for scale in (1.0, 3.0):
            pts = ellipse_points(cov, scale) + o.miss_mean[bp]
            ax.plot(pts[:, 0], pts[:, 1], style, color=color, lw=1.4 if scale == 1 else 0.9,
                    label=f"{o.method} {scale:g}σ", zorder=3)
    if r.corridor is not None:
        a, b = r.corridor.semi_axes_km
        t = np.linspace(0.0, 2.0 * np.pi, 361)
        c, s = math.cos(r.corridor.angle_rad), math.sin(r.corridor.angle_rad)
        u, v = a * np.cos(t), b * np.sin(t)
        ax.plot(c * u - s * v, s * u + c * v, color="k", lw=1.0, label="corridor")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("δB·T (km)")
    ax.set_ylabel("δB·R (km)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(textwrap.fill(title, 70), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)
    return path


def plot_dv_histograms(r: GuidanceResult, path: Path, title: str) -> Path:
    """Histogram of |Δv| (m/s) of each manoeuvre, with the 99 % of both methods."""
    plt = _pyplot()
    mans = r.monte_carlo.manoeuvres
    fig, axes = plt.subplots(1, len(mans), figsize=(4.2 * len(mans), 3.4), squeeze=False)
    dv = r.samples.dv_km_s
    mags = np.sqrt(np.einsum("smi,smi->sm", dv, dv)) * _M_PER_KM
    for i, (ax, mc, lin) in enumerate(zip(axes[0], mans, r.linear.manoeuvres, strict=True)):
        ax.hist(mags[:, i], bins=80, color="0.6", density=True)
        for m, method, color, style in ((mc, "Monte Carlo", "tab:red", "-"),
                                        (lin, "linear", "tab:blue", "--")):
            p99 = dict(m.magnitude.percentiles_km_s)[99.0] * _M_PER_KM
            ax.axvline(p99, color=color, ls=style, label=f"{method}: 99 % {p99:.3g} m/s")
        ax.set_xlabel("|Δv| (m/s)")
        ax.set_title(f"recycle {mc.number}, t = {mc.t_s / _DAY_S:.2f} d", fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)
    return path


__all__ = ["SCATTER_SAMPLES", "guidance_dict", "guidance_markdown",
           "plot_bplane_scatter", "plot_dv_histograms"]
