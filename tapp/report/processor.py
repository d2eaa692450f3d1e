"""Plots of a TAPP III run: σ against time (fit beside real), the same in RIC axes, and
B-plane dispersion ellipses.

All take the run's history (:class:`tapp.processor.sequencing.HistoryRow`, one per print or
recycle time) and write PNG files (the RIC σ also as CSV). The ellipses are the 1σ and 3σ
contours of the 2 x 2 covariance of (B·T, B·R): semi-axes √λ of its eigenvalues along its
eigenvectors (:mod:`tapp.estimation.ellipse`), the numbers the O3 printout states.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.estimation.ellipse import error_ellipse
from tapp.frames.ric import RIC_NAMES
from tapp.report.figures import subplots

RIC_AXES = ("R", "I", "C")


def ellipse_points(cov: np.ndarray, scale: float, n: int = 181) -> np.ndarray:
    """Return (n, 2) points of the contour xᵀ C⁻¹ x = scale² of a 2 x 2 covariance (the
    ellipse the O3 printout states, :func:`tapp.estimation.ellipse.error_ellipse`)."""
    return error_ellipse(cov).points(scale, n)


def ric_rows(history) -> list:
    """The history rows that carry RIC σ (the deck's ``[output] frames`` has "ric")."""
    return [h for h in history if h.ric_real is not None]


def plot_ric_history(history, path: Path, title: str) -> Path:
    """σ of the orbit along R, I, C against time, fit (dashed) and real (solid): position in
    m, velocity in mm/s, time in days from the tape epoch."""
    rows = ric_rows(history)
    t = np.array([h.t_s for h in rows]) / SECONDS_PER_DAY
    real = np.array([h.ric_real for h in rows])
    fits = [(tt, h.ric_fit) for tt, h in zip(t, rows, strict=True) if h.ric_fit is not None]
    fig, axes = subplots(1, 2, figsize=(10.0, 4.0))
    colors = ("tab:red", "tab:green", "tab:blue")
    for ax, first, scale, unit in ((axes[0], 0, 1e3, "m"), (axes[1], 3, 1e6, "mm/s")):
        for i, (axis, color) in enumerate(zip(RIC_AXES, colors, strict=True)):
            ax.semilogy(t, real[:, first + i] * scale, "o-", color=color,
                        label=f"{axis} real")
            if fits:
                ax.semilogy([f[0] for f in fits], [f[1][first + i] * scale for f in fits],
                            "s--", color=color, alpha=0.7, label=f"{axis} fit")
        kind = "position" if first == 0 else "velocity"
        ax.set_xlabel("t from the tape epoch (days)")
        ax.set_ylabel(f"σ {kind} ({unit})")
        ax.set_title(f"{kind}: radial R, in-track I, cross-track C", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    return path


def ric_csv(history) -> str:
    """The RIC σ history as CSV: kind, k, t (s, days), then σ fit and σ real of
    :data:`tapp.frames.ric.RIC_NAMES` (km, km/s); empty fields where the fit world has no
    covariance."""
    head = ["kind", "k", "t_s", "t_days", *(f"sigma_fit_{n}" for n in RIC_NAMES),
            *(f"sigma_real_{n}" for n in RIC_NAMES)]
    lines = [",".join(head)]
    for h in ric_rows(history):
        fit = [""] * len(RIC_NAMES) if h.ric_fit is None else [f"{v:.10e}" for v in h.ric_fit]
        days = h.t_s / SECONDS_PER_DAY
        lines.append(",".join([h.kind, str(h.k), f"{h.t_s:.6f}", f"{days:.9f}", *fit,
                               *(f"{v:.10e}" for v in h.ric_real)]))
    return "\n".join(lines) + "\n"


def plot_sigma_history(history, labels: tuple[str, ...], path: Path, title: str) -> Path:
    """σ of each component of the history partition against time, fit (dashed) and real."""
    rows = [h for h in history if h.k > 0]
    n = len(labels)
    cols = 3 if n > 4 else n
    nrows = int(np.ceil(n / max(cols, 1)))
    fig, axes = subplots(nrows, cols, figsize=(4.2 * cols, 3.0 * nrows), squeeze=False)
    t = np.array([h.t_s for h in rows]) / SECONDS_PER_DAY
    for i, label in enumerate(labels):
        ax = axes[i // cols][i % cols]
        real = np.array([h.sigma_real[i] for h in rows])
        ax.semilogy(t, real, "o-", color="tab:red", label="real world")
        fit = [(tt, h.sigma_fit[i]) for tt, h in zip(t, rows, strict=True)
               if h.sigma_fit is not None]
        if fit:
            ax.semilogy(*zip(*fit, strict=True), "s--", color="tab:blue", label="fit world")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("t (days)")
        ax.grid(True, which="both", alpha=0.3)
        if i == 0:
            ax.legend(fontsize=8)
    for j in range(n, nrows * cols):
        axes[j // cols][j % cols].axis("off")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    return path


def bplane_rows(history, miss_names: tuple[str, ...]) -> list:
    """The history rows the ellipse plot shows: the recycles and the last print time; none
    when the miss set has no B·T and B·R."""
    if "b_dot_t_km" not in miss_names or "b_dot_r_km" not in miss_names:
        return []
    rows = [h for h in history if h.kind == "recycle"]
    last = [h for h in history if h.kind == "print" and h.k > 0][-1:]
    return rows + [h for h in last if all(h.k != r.k for r in rows)]


def draw_bplane_ellipses(ax, h, miss_names: tuple[str, ...]) -> None:
    """Draw on ``ax`` the 1σ/3σ (B·T, B·R) ellipses (km), fit and real world, of one history
    row, with their semi-axes and angle in the legend."""
    ix = [miss_names.index("b_dot_t_km"), miss_names.index("b_dot_r_km")]
    for cov, color, name in ((h.miss_real, "tab:red", "real"), (h.miss_fit, "tab:blue", "fit")):
        if cov is None:
            continue
        ell = error_ellipse(cov[np.ix_(ix, ix)])
        for scale, style in ((1.0, "-"), (3.0, ":")):
            pts = ell.points(scale)
            axes_km = (f": {scale * ell.semi_major:.3g} x {scale * ell.semi_minor:.3g} km, "
                       f"{ell.angle_deg:+.1f}°")
            ax.plot(pts[:, 0], pts[:, 1], style, color=color,
                    label=f"{name} {scale:g}σ{axes_km}")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("δB·T (km)")
    ax.set_ylabel("δB·R (km)")
    ax.set_title(f"{h.kind} k = {h.k}, t = {h.t_s / SECONDS_PER_DAY:.2f} d (angle: major axis "
                 "from T towards R)", fontsize=8)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)


def plot_bplane_ellipses(history, miss_names: tuple[str, ...], path: Path, title: str) -> Path:
    """1σ/3σ (B·T, B·R) ellipses, fit vs real, at the times of :func:`bplane_rows`."""
    rows = bplane_rows(history, miss_names)
    fig, axes = subplots(1, len(rows), figsize=(4.2 * len(rows), 4.2), squeeze=False)
    for ax, h in zip(axes[0], rows, strict=True):
        draw_bplane_ellipses(ax, h, miss_names)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    return path
