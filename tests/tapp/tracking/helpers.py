"""Small scenarios for the TAPP I tests: a 3-hour LEO arc that simulates in well under 1 s."""

from __future__ import annotations

import copy
import math

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.tracking.scenario import Scenario, parse_scenario

SOURCE = "test_scenario.toml"
A_KM = 6550.524
INCLINATION_DEG = 2.0
V_CIRC_KM_S = math.sqrt(GM_EARTH_km3_s2 / A_KM)

_BASE = {
    "title": "short LEO arc",
    "iden": "TEST-LEO",
    "epoch": "2026-01-01T00:00:00",
    "injection": {
        "r_km": [A_KM, 0.0, 0.0],
        "v_km_s": [0.0, V_CIRC_KM_S * math.cos(math.radians(INCLINATION_DEG)),
                   V_CIRC_KM_S * math.sin(math.radians(INCLINATION_DEG))],
    },
    "model": {"gravity": "J2", "var_gravity": "J2"},
    "parameters": {"dynamic": ["GM", "J2"], "station_location": "cylindrical",
                   "station_biases": ["range", "range_rate"]},
    "stations": {
        "QUITO": {"lat_deg": -0.6226, "lon_deg": -78.5786, "h_km": 3.55, "elev_mask_deg": 5.0},
        "KOUROU": {"lat_deg": 5.2514, "lon_deg": -52.8047, "h_km": 0.015,
                   "elev_mask_deg": 5.0},
        "MALINDI": {"lat_deg": -2.9956, "lon_deg": 40.1945, "h_km": 0.012,
                    "elev_mask_deg": 5.0},
    },
    "tracking": {
        "stations": ["QUITO", "KOUROU", "MALINDI"],
        "observables": ["range", "range_rate"],
        "data_interval_s": 20.0,
        "station": {"KOUROU": {"location": "ecef"}},
    },
    "noise": {
        "fit": {"sigma_range_m": 15.0, "sigma_range_rate_mm_s": 20.0},
        "real": {"sigma_range_m": 20.0, "bias_range_m": 5.0, "sigma_range_rate_mm_s": 15.0,
                 "correlated_range_rate_mm_s": 10.0, "tau_range_rate_s": 90.0},
    },
    "times": {"input_step_s": 3600.0, "end": 10800.0},
    "miss": {"kind": "equinoctial"},
}


def leo_document(**tables) -> dict:
    """Return a copy of the base document with top-level tables replaced or merged.

    A dict value is merged into the base table of that name (one level; a None entry removes
    that key); None removes the table.
    """
    doc = copy.deepcopy(_BASE)
    for key, value in tables.items():
        if value is None:
            doc.pop(key, None)
        elif isinstance(value, dict) and isinstance(doc.get(key), dict):
            merged = {**doc[key], **value}
            doc[key] = {k: v for k, v in merged.items() if v is not None}
        else:
            doc[key] = value
    return doc


def leo_scenario(**tables) -> Scenario:
    """Return the parsed base scenario with :func:`leo_document` changes."""
    return parse_scenario(leo_document(**tables), SOURCE)


def scaled_close(a: np.ndarray, b: np.ndarray, tol: float) -> float:
    """Return max |a_ij - b_ij| / sqrt(b_ii b_jj) (the natural scale of a normal matrix) and
    assert it is below ``tol``."""
    d = np.sqrt(np.abs(np.diagonal(b, axis1=-2, axis2=-1)))
    scale = d[..., :, None] * d[..., None, :]
    err = float(np.max(np.abs(a - b) / np.where(scale > 0, scale, 1.0)))
    assert err <= tol, err
    return err
