"""Report of a TAPP II guidance study: Markdown tables, a JSON-ready dict, PNG plots.

:func:`guidance_markdown` sets the Monte Carlo beside the linear covariance (ΔV per manoeuvre
and in total, final miss, B-plane ellipse, corridor) and marks with ✗ every linear value the
Monte Carlo of the run contradicts (:mod:`tapp.guidance.agreement`), listing them with the
Monte Carlo's value and sampling error, the one to use; :func:`guidance_dict` holds every
statistic in the code's units (km, km/s, s, rad; angles of ellipses in degrees, named so) and
every check under ``"agreement"``, keyed by the statistic's place in ``"linear"``. A section
whose quantities the tape or the guidance file does not have (the B-plane ellipse without
B·T and B·R, the flight-time σ without a flight time, the corridor without a ``[corridor]``)
is left out of both, with one line saying why (:func:`left_out`). The plots,
:func:`plot_bplane_scatter` (samples with the 1σ/3σ ellipses of both methods and the
corridor) and :func:`plot_dv_histograms` (|Δv| per manoeuvre with the 99 % of both methods),
import matplotlib only when called.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.guidance.agreement import EXACT, MIN_MOMENT_SAMPLES, Check, Key, clopper_pearson
from tapp.guidance.statistics import (
    BPLANE,
    FLIGHT_TIME,
    Magnitude,
    Outcome,
    bplane_rows,
    flight_time_row,
)
from tapp.guidance.study import GuidanceResult
from tapp.report.figures import subplots
from tapp.report.markdown import table

_M_PER_KM = 1000.0
_NAVIGATION = {"tape": "the tape's estimator (its a priori ignores the execution errors)",
               "inflate": "a priori inflated by the execution-error covariance, regression "
                          "re-run"}
#: Samples drawn in the B-plane scatter (the first ones: a deterministic subset).
SCATTER_SAMPLES = 20_000
#: The mark of a linear value the Monte Carlo contradicts.
CONTRADICTED = "✗"
#: The sections that can be left out (their keys in an outcome's JSON), for a reader.
_SECTIONS = {"bplane_ellipse": "B-plane dispersion ellipse",
             "flight_time_sigma_s": "flight-time dispersion",
             "outside_corridor": "corridor"}
#: Units the report shows for the checks' units: (unit, factor).
_SHOWN = {"km/s": ("m/s", _M_PER_KM)}


def left_out(r: GuidanceResult) -> dict[str, str]:
    """The sections of the report the study cannot fill, each with why, keyed as in an
    outcome's JSON (``bplane_ellipse``, ``flight_time_sigma_s``, ``outside_corridor``)."""
    names = ", ".join(r.miss_name)
    out = {}
    if bplane_rows(r.miss_name) is None:
        out["bplane_ellipse"] = (f"the tape has no B-plane miss components "
                                 f"({', '.join(BPLANE)}); its miss components: {names}")
    if flight_time_row(r.miss_name) is None:
        out["flight_time_sigma_s"] = (f"the tape has no flight-time miss component "
                                      f"({' or '.join(FLIGHT_TIME)}); its miss components: "
                                      f"{names}")
    if r.corridor is None:
        out["outside_corridor"] = "the guidance file has no [corridor] table"
    return out


def key_path(key: Key) -> str:
    """The JSON path of a statistic in ``"linear"``.

    >>> key_path(("manoeuvres", 1, "magnitude", "percentiles_km_s", "99"))
    'manoeuvres[1].magnitude.percentiles_km_s.99'
    """
    text = ""
    for part in key:
        text += f"[{part}]" if isinstance(part, int) else f".{part}" if text else part
    return text


def _check_dict(c: Check) -> dict:
    return {"label": c.label, "unit": c.unit, "test": c.test, "linear": c.linear,
            "monte_carlo": c.monte_carlo, "sampling_error": c.sampling_error, "z": c.z,
            "interval": None if c.interval is None else list(c.interval),
            "resolved": c.resolved, "contradicted_by_monte_carlo": c.contradicted}


def _agreement_dict(r: GuidanceResult) -> dict:
    a = r.agreement
    return {"family_false_alarm": a.family_false_alarm, "statistics": len(a.checks),
            "false_alarm_each": a.level.alpha, "z_limit": a.level.z_limit,
            "min_moment_samples": MIN_MOMENT_SAMPLES,
            "exact": list(EXACT), "contradicted": [key_path(c.key) for c in a.contradicted],
            "checks": {key_path(c.key): _check_dict(c) for c in a.checks}}


def _magnitude_dict(m: Magnitude) -> dict:
    return {"mean_km_s": m.mean_km_s, "sigma_km_s": m.sigma_km_s,
            "percentiles_km_s": None if m.percentiles_km_s is None
            else {f"{p:g}": v for p, v in m.percentiles_km_s}}


def _outcome_dict(o: Outcome, absent: dict[str, str]) -> dict:
    content = {
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
    return {k: v for k, v in content.items() if k not in absent}


def guidance_dict(r: GuidanceResult) -> dict:
    """The study as a JSON-ready dict (plain lists and floats): the sections the study
    cannot fill are left out and named under ``"left_out"`` with why, the checks of the
    linear statistics are under ``"agreement"`` (module docstring)."""
    c = r.corridor
    absent = left_out(r)
    corridor = {} if c is None else {"corridor": {
        "semi_axes_km": list(c.semi_axes_km), "angle_rad": c.angle_rad,
        "flight_time_s": c.flight_time_s}}
    return {
        "title": r.title, "tape": r.tape_source, "iden": r.tape_iden, "guide": r.guide_source,
        "targets": list(r.targets), "navigation": r.navigation,
        "miss_name": list(r.miss_name),
        "miss_unit": list(r.miss_unit),
        "execution": {"sigma_proportional": r.errors.sigma_proportional,
                      "sigma_pointing_rad": r.errors.sigma_pointing_rad,
                      "sigma_fixed_km_s": r.errors.sigma_fixed_km_s},
        **corridor,
        "samples": r.n_samples, "seed": r.seed, "block_samples": r.block_samples,
        "shard_samples": r.shard_samples, "where": r.where, "wall_s": r.wall_s,
        "monte_carlo": _outcome_dict(r.monte_carlo, absent),
        "linear": _outcome_dict(r.linear, absent),
        "agreement": _agreement_dict(r), "left_out": absent,
    }


def _ms(value: float | None) -> str:
    return "—" if value is None else f"{value * _M_PER_KM:.3f}"


def _marked(text: str, r: GuidanceResult, key: Key | None) -> str:
    """``text``, marked if it is the linear value at ``key`` and the Monte Carlo
    contradicts it (``key`` None: a Monte Carlo value)."""
    c = None if key is None else r.agreement.check(key)
    return f"{text} {CONTRADICTED}" if c is not None and c.contradicted else text


def _magnitude_row(r: GuidanceResult, m: Magnitude, key: Key | None) -> list[str]:
    """Mean, σ, 50/90/99 % (m/s); ``key``: the place of a linear magnitude, None for the
    Monte Carlo's."""
    pct = [(None, None)] * 3 if m.percentiles_km_s is None else [
        (v, ("percentiles_km_s", f"{p:g}")) for p, v in m.percentiles_km_s]
    cells = [(m.mean_km_s, ("mean_km_s",)), (m.sigma_km_s, ("sigma_km_s",)), *pct]
    return [_marked(_ms(v), r, None if key is None or place is None else (*key, *place))
            for v, place in cells]


def _fraction(value: float | None) -> str:
    if value is None:
        return "—"
    return f"{value:.4f}" if value == 0 or value >= 1e-3 else f"{value:.2e}"


def _dv_table(r: GuidanceResult) -> str:
    rows = []
    for i, (mc, lin) in enumerate(zip(r.monte_carlo.manoeuvres, r.linear.manoeuvres,
                                      strict=True)):
        when = [str(mc.number), f"{mc.t_s / SECONDS_PER_DAY:.3f}"]
        rows += [[*when, r.monte_carlo.method, *_magnitude_row(r, mc.magnitude, None)],
                 [*when, r.linear.method,
                  *_magnitude_row(r, lin.magnitude, ("manoeuvres", i, "magnitude"))]]
    rows += [["total", "", r.monte_carlo.method, *_magnitude_row(r, r.monte_carlo.total, None)],
             ["total", "", r.linear.method, *_magnitude_row(r, r.linear.total, ("total",))]]
    return table(["recycle", "t (d)", "method", "mean", "σ", "50 %", "90 %", "99 %"], rows)


def _miss_table(r: GuidanceResult) -> str:
    mc, lin = r.monte_carlo, r.linear
    rows = [[name, unit, f"{mc.miss_mean[i]:.4g}", f"{math.sqrt(mc.miss_cov[i, i]):.4g}",
             f"{math.sqrt(max(lin.miss_cov[i, i], 0.0)):.4g}"]
            for i, (name, unit) in enumerate(zip(r.miss_name, r.miss_unit, strict=True))]
    return table(["component", "unit", "mean (MC)", "σ (MC)", "σ (linear)"], rows)


def _dispersion(r: GuidanceResult, absent: dict[str, str]) -> list[str]:
    """The B-plane ellipse and the flight-time σ of both methods, the columns the tape has,
    and one line for each left out (with neither, no table)."""
    notes = [f"No {_SECTIONS[k]}: {absent[k]}." for k in ("bplane_ellipse",
                                                          "flight_time_sigma_s")
             if k in absent]
    with_ellipse = "bplane_ellipse" not in absent
    with_time = "flight_time_sigma_s" not in absent
    if not (with_ellipse or with_time):
        return [f"{n}\n" for n in notes]
    header = ["method"]
    if with_ellipse:
        header += ["1σ semi-major (km)", "1σ semi-minor (km)",
                   "major axis from T toward R (deg)"]
    if with_time:
        header.append("σ flight time (s)")
    rows = []
    for o in (r.monte_carlo, r.linear):
        e = o.ellipse
        row = [o.method]
        if with_ellipse:
            row += [f"{e.semi_major_km:.4g}", f"{e.semi_minor_km:.4g}", f"{e.angle_deg:.2f}"]
        if with_time:
            row.append(f"{o.flight_time_sigma_s:.4g}")
        rows.append(row)
    title = "B-plane dispersion" if with_ellipse else "Flight-time dispersion"
    return [f"## {title} (1σ)", "", table(header, rows), *(f"{n}\n" for n in notes)]


def _corridor(r: GuidanceResult) -> list[str]:
    c = r.corridor
    a, b = c.semi_axes_km
    shape = (f"circle of radius {a:g} km" if a == b else
             f"ellipse of semi-axes {a:g} km x {b:g} km, the first "
             f"{math.degrees(c.angle_rad):g}° from T toward R")
    limit = "" if c.flight_time_s is None else f", |Δt_f| <= {c.flight_time_s:g} s"
    parts = ["bplane"] if c.flight_time_s is None else ["bplane", "flight_time", "either"]
    names = {"bplane": "outside B-plane", "flight_time": "outside Δt_f limit",
             "either": "outside either"}
    mc, lin = r.monte_carlo, r.linear
    rows = [[mc.method, *(_fraction(getattr(mc.outside, p)) for p in parts)],
            [lin.method, *(_marked(_fraction(getattr(lin.outside, p)), r,
                                   ("outside_corridor", p)) for p in parts)]]
    n, alpha = r.n_samples, r.agreement.level.alpha
    k = round(mc.outside.either * n)
    low, high = clopper_pearson(k, n, alpha)
    return ["## Corridor", "",
            f"Corridor: B-plane {shape} about the aim point{limit}. Monte Carlo: {k:,} of "
            f"{n:,} samples outside{' either' if c.flight_time_s is not None else ''}, a "
            f"fraction from {_fraction(low)} to {_fraction(high)} at confidence "
            f"1 − {alpha:.1e} (Clopper-Pearson). The linear fractions take the final miss "
            "as Gaussian; \"outside either\" has no closed form for it.", "",
            table(["method", *(names[p] for p in parts)], rows)]


def _shown(c: Check, value: float | None) -> str:
    """A value of a check in the report's units."""
    if value is None:
        return "—"
    factor = _SHOWN[c.unit][1] if c.unit in _SHOWN else 1.0
    return f"{value * factor:.4g}"


def _evidence(c: Check) -> str:
    """The sampling error of a check and its test: ± the standard error and z, or the
    interval."""
    if c.test == "z":
        return f"± {_shown(c, c.sampling_error)} (z = {c.z:+.1f})"
    low, high = c.interval
    return f"{_shown(c, low)} to {_shown(c, high)} ({c.test})"


def _agreement(r: GuidanceResult) -> list[str]:
    """Which linear values the Monte Carlo contradicts, and what to use instead."""
    a = r.agreement
    lines = ["## Linear covariance against the Monte Carlo", "",
             "The linear covariance's means and covariances of each Δv and of the final miss, "
             "and with them the miss σ's, the B-plane ellipse and the flight-time σ, are "
             "exact (the samples go through the same linear maps): use them. Its |Δv| "
             "statistics take each Δv as Gaussian (true of the first manoeuvre only) and its "
             f"corridor fractions the miss: these {len(a.checks)} statistics are set against "
             f"the Monte Carlo of this run, at a family-wise false-alarm rate of "
             f"{a.family_false_alarm:g} (Bonferroni: each at {a.level.alpha:.1e}; means and "
             f"σ's by their z-score from the sample moments, |z| > {a.level.z_limit:.2f}; "
             "percentiles by the order statistics that bracket them and fractions by the "
             "Clopper-Pearson interval of their count, both at confidence "
             f"1 − {a.level.alpha:.1e})."]
    untested = a.unresolved
    if untested:
        lines.append(f"Not tested by this run, and so not marked whatever their values: "
                     f"{', '.join(c.label for c in untested)} (a z-score needs "
                     f"{MIN_MOMENT_SAMPLES:,} samples or more, a percentile an order "
                     "statistic on one side at least).")
    bad = a.contradicted
    if not bad:
        return [*lines, "None is contradicted: the linear values agree with the Monte Carlo "
                "within its sampling error.", ""]
    rows = [[c.label.replace("|", "\\|"),
             _SHOWN[c.unit][0] if c.unit in _SHOWN else c.unit or "fraction",
             _shown(c, c.linear), _shown(c, c.monte_carlo), _evidence(c)] for c in bad]
    return [*lines, f"{len(bad)} contradicted ({CONTRADICTED} above): for these, use the "
            "Monte Carlo value, with the sampling error given here (± one standard error, or "
            "the interval at the test's confidence).", "",
            table(["statistic", "unit", "linear", "Monte Carlo", "sampling error"], rows)]


def guidance_markdown(r: GuidanceResult) -> str:
    """The study as Markdown: the Monte Carlo beside the linear covariance (module docstring).
    """
    e = r.errors
    absent = left_out(r)
    corridor = (_corridor(r) if r.corridor is not None
                else [f"No {_SECTIONS['outside_corridor']}: {absent['outside_corridor']}.", ""])
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
        "total's σ and percentiles need the joint law of the magnitudes (Monte Carlo only). "
        f"{CONTRADICTED}: contradicted by the Monte Carlo of this run (last section).",
        "", "## Final miss after the last correction", "", _miss_table(r),
        "The linear model's mean is zero; the sampling σ of a Monte Carlo mean is σ/√N.", "",
        *_dispersion(r, absent), *corridor, *_agreement(r),
    ]
    return "\n".join(lines).rstrip("\n") + "\n"


# ---------------------------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------------------------


def draw_bplane_scatter(ax, r: GuidanceResult) -> None:
    """Draw on ``ax`` the final (δB·T, δB·R) (km) of the first :data:`SCATTER_SAMPLES`
    samples, with the 1σ and 3σ ellipses of the Monte Carlo (solid) and the linear covariance
    (dashed) and the corridor; needs the B-plane miss components."""
    from tapp.report.processor import ellipse_points

    bp = bplane_rows(r.miss_name)
    miss = r.samples.miss[:SCATTER_SAMPLES]
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


def plot_bplane_scatter(r: GuidanceResult, path: Path, title: str) -> Path:
    """The figure of :func:`draw_bplane_scatter`, titled, written as a PNG at ``path``."""
    fig, ax = subplots(figsize=(6.4, 6.0))
    draw_bplane_scatter(ax, r)
    ax.set_title(textwrap.fill(title, 70), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    return path


def plot_dv_histograms(r: GuidanceResult, path: Path, title: str) -> Path:
    """Histogram of |Δv| (m/s) of each manoeuvre, with the 99 % of both methods (the linear
    one labelled when the Monte Carlo contradicts it)."""
    mans = r.monte_carlo.manoeuvres
    fig, axes = subplots(1, len(mans), figsize=(4.2 * len(mans), 3.4), squeeze=False)
    mags = r.samples.dv_magnitude_km_s * _M_PER_KM
    for i, (ax, mc, lin) in enumerate(zip(axes[0], mans, r.linear.manoeuvres, strict=True)):
        ax.hist(mags[:, i], bins=80, color="0.6", density=True)
        check = r.agreement.check(("manoeuvres", i, "magnitude", "percentiles_km_s", "99"))
        wrong = ", contradicted" if check.contradicted else ""
        for m, method, color, style in ((mc, "Monte Carlo", "tab:red", "-"),
                                        (lin, f"linear{wrong}", "tab:blue", "--")):
            p99 = dict(m.magnitude.percentiles_km_s)[99.0] * _M_PER_KM
            ax.axvline(p99, color=color, ls=style, label=f"{method}: 99 % {p99:.3g} m/s")
        ax.set_xlabel("|Δv| (m/s)")
        ax.set_title(f"recycle {mc.number}, t = {mc.t_s / SECONDS_PER_DAY:.2f} d", fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    return path


__all__ = ["CONTRADICTED", "SCATTER_SAMPLES", "draw_bplane_scatter", "guidance_dict",
           "guidance_markdown", "key_path", "left_out", "plot_bplane_scatter",
           "plot_dv_histograms"]
