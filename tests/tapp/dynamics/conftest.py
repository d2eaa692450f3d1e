"""Shared fixtures: states built independently of tapp.frames (periapsis of a conic), and
the integration methods the propagation tests run under."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics.compiled import METHODS


def periapsis_state(a_km: float, e: float, i_deg: float, raan_deg: float = 0.0,
                    argp_deg: float = 0.0, mu: float = GM_EARTH_km3_s2) -> np.ndarray:
    """Cartesian state (km, km/s) at periapsis: r = a(1-e) P, v = sqrt(mu(1+e)/r_p) Q."""
    rp = a_km * (1.0 - e)
    vp = np.sqrt(mu * (1.0 + e) / rp)
    i, o, w = np.radians([i_deg, raan_deg, argp_deg])
    p_hat = np.array([np.cos(o) * np.cos(w) - np.sin(o) * np.sin(w) * np.cos(i),
                      np.sin(o) * np.cos(w) + np.cos(o) * np.sin(w) * np.cos(i),
                      np.sin(w) * np.sin(i)])
    q_hat = np.array([-np.cos(o) * np.sin(w) - np.sin(o) * np.cos(w) * np.cos(i),
                      -np.sin(o) * np.sin(w) + np.cos(o) * np.cos(w) * np.cos(i),
                      np.cos(w) * np.sin(i)])
    return np.concatenate([rp * p_hat, vp * q_hat])


@pytest.fixture(params=list(METHODS))
def method(request: pytest.FixtureRequest) -> str:
    """Each integration method in turn: the propagation tests hold for all of them."""
    return request.param
