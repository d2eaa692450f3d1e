"""Shared by the measurement tests."""

from __future__ import annotations

import numpy as np


def central_differences(f, x, steps):
    """Return the central-difference Jacobian of ``f`` at ``x`` (..., n): column i is
    (f(x + h_i e_i) - f(x - h_i e_i)) / (2 h_i), stacked on a new last axis."""
    cols = []
    for i, h in enumerate(steps):
        e = np.zeros_like(x)
        e[..., i] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)
