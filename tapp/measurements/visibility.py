"""Visibility above a station's elevation mask, and the grouping of visible samples into passes.

Noise models and the EKF work pass by pass; a pass is a maximal run of consecutive visible
samples (optionally also broken where the time step exceeds a gap). Passes are half-open index
ranges [start, stop), so ``x[start:stop]`` selects one.
"""

from __future__ import annotations

import numpy as np

from tapp.errors import InputError


def is_visible(elevation_rad, elev_mask_rad: float):
    """Return True where the elevation is strictly above the mask, shape (N,) bool.

    Parameters
    ----------
    elevation_rad : array_like, shape (N,)
        Elevation of the spacecraft seen from the station, rad.
    elev_mask_rad : float
        The station's elevation mask, rad (a spacecraft exactly on the mask is not visible).
    """
    return np.asarray(elevation_rad, dtype=float) > elev_mask_rad


def find_passes(visible, t_s=None, max_gap_s: float | None = None):
    """Return the passes as half-open index ranges [start, stop), shape (P, 2) int.

    Parameters
    ----------
    visible : array_like, shape (N,)
        Visibility of each sample (time-ordered).
    t_s : array_like, shape (N,), optional
        Sample times, s; needed with ``max_gap_s``.
    max_gap_s : float, optional
        Also split a run of visible samples where consecutive times differ by more than this.

    Examples
    --------
    >>> find_passes([False, True, True, False, True])
    array([[1, 3],
           [4, 5]])
    """
    vis = np.asarray(visible, dtype=bool).ravel()
    edges = np.diff(vis.astype(np.int8), prepend=np.int8(0), append=np.int8(0))
    split = np.zeros(vis.size + 1, dtype=bool)
    if max_gap_s is not None:
        if t_s is None:
            raise InputError("find_passes", "t_s", "sample times when max_gap_s is given")
        gap = np.diff(np.asarray(t_s, dtype=float)) > max_gap_s
        # A gap between two visible samples ends one pass and starts the next.
        split[1:-1] = gap & vis[:-1] & vis[1:]
    starts = np.flatnonzero((edges == 1) | split)
    stops = np.flatnonzero((edges[:] == -1) | split)
    return np.stack([starts, stops], axis=-1).astype(np.int64)


def pass_labels(visible, t_s=None, max_gap_s: float | None = None):
    """Return the pass number of each sample (0, 1, ...), -1 where not visible, shape (N,) int."""
    vis = np.asarray(visible, dtype=bool).ravel()
    labels = np.full(vis.size, -1, dtype=np.int64)
    for number, (start, stop) in enumerate(find_passes(vis, t_s, max_gap_s)):
        labels[start:stop] = number
    return labels
