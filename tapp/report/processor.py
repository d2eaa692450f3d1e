"""Plots of a TAPP III run: σ against time (fit beside real) and B-plane dispersion ellipses.

Both take the run's history (:class:`tapp.processor.sequencing.HistoryRow`, one per print or
recycle time) and write PNG files. The ellipses are the 1σ and 3σ contours of the 2 x 2
covariance of (B·T, B·R): semi-axes √λ of its eigenvalues along its eigenvectors.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

_DAY_S = 86400.0


def ellipse_points(cov: np.ndarray, scale: float, n: int = 181) -> np.ndarray:
    """Return (n, 2) points of the contour xᵀ C⁻¹ x = scale² of a 2 x 2 covariance."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    angle = np.linspace(0.0, 2.0 * np.pi, n)
    unit = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    return scale * (unit * np.sqrt(np.maximum(w, 0.0))) @ v.T


def plot_sigma_history(history, labels: tuple[str, ...], path: Path, title: str) -> Path:
    """σ of each component of the history partition against time, fit (dashed) and real."""
    rows = [h for h in history if h.k > 0]
    n = len(labels)
    cols = 3 if n > 4 else n
    nrows = int(np.ceil(n / max(cols, 1)))
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.0 * nrows), squeeze=False)
    t = np.array([h.t_s for h in rows]) / _DAY_S
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
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)
    return path


def bplane_rows(history, miss_names: tuple[str, ...]) -> list:
    """The history rows the ellipse plot shows: the recycles and the last print time; none
    when the miss set has no B·T and B·R."""
    if "b_dot_t_km" not in miss_names or "b_dot_r_km" not in miss_names:
        return []
    rows = [h for h in history if h.kind == "recycle"]
    last = [h for h in history if h.kind == "print" and h.k > 0][-1:]
    return rows + [h for h in last if all(h.k != r.k for r in rows)]


def plot_bplane_ellipses(history, miss_names: tuple[str, ...], path: Path, title: str) -> Path:
    """1σ/3σ (B·T, B·R) ellipses, fit vs real, at the times of :func:`bplane_rows`."""
    rows = bplane_rows(history, miss_names)
    ix = [miss_names.index("b_dot_t_km"), miss_names.index("b_dot_r_km")]
    fig, axes = plt.subplots(1, len(rows), figsize=(4.2 * len(rows), 4.2), squeeze=False)
    for ax, h in zip(axes[0], rows, strict=True):
        for cov, color, name in ((h.miss_real, "tab:red", "real"),
                                 (h.miss_fit, "tab:blue", "fit")):
            if cov is None:
                continue
            c2 = cov[np.ix_(ix, ix)]
            for scale, style in ((1.0, "-"), (3.0, ":")):
                pts = ellipse_points(c2, scale)
                ax.plot(pts[:, 0], pts[:, 1], style, color=color,
                        label=f"{name} {scale:g}σ")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("δB·T (km)")
        ax.set_ylabel("δB·R (km)")
        ax.set_title(f"{h.kind} k = {h.k}, t = {h.t_s / _DAY_S:.2f} d", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)
    return path
