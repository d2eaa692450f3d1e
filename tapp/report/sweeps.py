"""Plots of sweep results (the departure-day sweep): ΔV and flight time per day."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tapp.report.figures import subplots


def plot_departure_sweep(day: np.ndarray, dv_km_s: np.ndarray, flight_time_s: np.ndarray,
                         ok: np.ndarray, path: Path) -> None:
    """ΔV (m/s) and flight time (days) against departure day; failed cases marked."""
    fig, (ax1, ax2) = subplots(2, 1, figsize=(8, 6), sharex=True)
    ax1.plot(day[ok], dv_km_s[ok] * 1e3, "o-", ms=4, label="targeted (SEARCH converged)")
    for d in day[~ok]:
        ax1.axvline(d, color="tab:red", ls=":", lw=1)
        ax2.axvline(d, color="tab:red", ls=":", lw=1)
    ax1.set_ylabel("injection ΔV (m/s)")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    ax2.plot(day[ok], flight_time_s[ok] / 86400.0, "o-", ms=4, color="tab:green")
    ax2.set_ylabel("flight time (d)")
    ax2.set_xlabel("departure day (days after 2026-03-10T12:00 UTC); red: failed case")
    ax2.grid(alpha=0.3)
    fig.suptitle("Trans-lunar injection targeted to the lunar B-plane, per departure day")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
