"""Two-body orbit kernels (the ``orbit/`` floor of the layout in DESIGN.md): Lambert's problem.

Plain float64 arrays in and out, km, km/s, s; no I/O. The conversions between elements and
states, and Kepler's equation, are in :mod:`tapp.frames.elements`.
"""

from tapp.orbit.lambert import lambert

__all__ = ["lambert"]
