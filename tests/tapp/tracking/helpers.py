"""Small scenarios for the TAPP I tests: a 3-hour LEO arc that simulates in well under 1 s, and
a 12-hour GEO track."""

from __future__ import annotations

import copy
import math

import numpy as np

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s
from tapp.io.tape.t13 import T13
from tapp.tracking.scenario import Scenario
from tapp.tracking.scenario_build import parse_scenario

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
    "parameters": {"dynamic": ["GM_km3_s2", "J2"], "station_location": "cylindrical",
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


#: :func:`leo_document` changes: a fourth station, 70° north, which the 2°-inclined LEO never
#: rises above.
NORTH = {"stations": {"NORTH": {"lat_deg": 70.0, "lon_deg": 0.0, "h_km": 0.0,
                                "elev_mask_deg": 5.0}},
         "tracking": {"stations": ["QUITO", "KOUROU", "MALINDI", "NORTH"]}}


def leo_scenario(**tables) -> Scenario:
    """Return the parsed base scenario with :func:`leo_document` changes."""
    return parse_scenario(leo_document(**tables), SOURCE)


# A 12 h GEO track longer than max_pass_s (issue 18: the passes were cut, the rest dropped).
GEO_A_KM = (GM_EARTH_km3_s2 / OMEGA_EARTH_rad_s**2) ** (1.0 / 3.0)  # one sidereal day
GEO_DT_S = 600.0
GEO_MAX_PASS_S = 28800.0
GEO_END_S = 43200.0
GEO_BIAS_M = 5.0


def geo_document() -> dict:
    """A geostationary spacecraft (two-body) seen all the time by two stations, one under it
    at t = 0 and one 40° east at 30° N (elevation about 34°), sampled every 600 s from 600 s
    to 12 h, passes of at most 8 h, one T13 record (so that the real world's blocks are the
    passes alone)."""
    v = math.sqrt(GM_EARTH_km3_s2 / GEO_A_KM)
    base = leo_scenario()
    lon_deg = math.degrees(-base.orientation.theta0_rad)  # under the spacecraft at t = 0
    doc = leo_document(
        injection={"r_km": [GEO_A_KM, 0.0, 0.0], "v_km_s": [0.0, v, 0.0]},
        model={"gravity": "J0", "var_gravity": "J0"},
        parameters={"dynamic": [], "station_location": "none", "station_biases": ["range"]},
        stations={"UNDER": {"lat_deg": 0.0, "lon_deg": lon_deg, "h_km": 0.0,
                            "elev_mask_deg": 10.0},
                  "EAST": {"lat_deg": 30.0, "lon_deg": lon_deg + 40.0, "h_km": 0.5,
                           "elev_mask_deg": 10.0}},
        tracking={"stations": ["UNDER", "EAST"], "data_interval_s": GEO_DT_S,
                  "start": GEO_DT_S, "max_pass_s": GEO_MAX_PASS_S, "station": {}},
        noise={"fit": {"sigma_range_m": 10.0, "sigma_range_rate_mm_s": 1.0},
               "real": {"bias_range_m": GEO_BIAS_M}},
        times={"input": [GEO_END_S], "input_step_s": None, "end": None})
    return doc


HAND_A_KM = 12000.0
HAND_MASK_DEG = 10.0
HAND_CENTRE_S = 3000.0
HAND_DT_S = 60.0



def hand_document() -> dict:
    """Samples every 60 s from 0 to 6600 s, the tape ending at 6000 s, of a two-body circular
    equatorial orbit (a = 12000 km) over two stations on the equator where it culminates at
    3000 s: EQ (range, range rate) blacked out over [1100, 1300] s, passes of at least 300 s
    and at most 2400 s; EQ2 at the same place (range only) blacked out throughout."""
    n = math.sqrt(GM_EARTH_km3_s2 / HAND_A_KM**3)
    base = leo_scenario(earth_orientation="gmst")
    lon_deg = math.degrees((n - OMEGA_EARTH_rad_s) * HAND_CENTRE_S - base.epoch.gmst_rad())
    station = {"lat_deg": 0.0, "lon_deg": lon_deg, "h_km": 0.0,
               "elev_mask_deg": HAND_MASK_DEG}
    doc = leo_document(
        earth_orientation="gmst",
        injection={"r_km": [HAND_A_KM, 0.0, 0.0], "v_km_s": [0.0, HAND_A_KM * n, 0.0]},
        model={"gravity": "J0", "var_gravity": "J0"},
        parameters={"dynamic": [], "station_location": "none", "station_biases": []},
        stations={"EQ": station, "EQ2": station},
        tracking={"stations": ["EQ", "EQ2"], "data_interval_s": HAND_DT_S, "end": 6600.0,
                  "min_pass_s": 300.0, "max_pass_s": 2400.0,
                  "station": {"EQ": {"blackouts": [[1100.0, 1300.0]]},
                              "EQ2": {"observables": ["range"],
                                      "blackouts": [[0.0, 6600.0]]}}},
        times={"input": [6000.0], "input_step_s": None, "end": None})
    return doc


def schedule_text(tape: T13, *, dates: bool = True) -> str:
    """The tape's passes (station, first and last sample) as the rows of a schedule: UTC
    dates to the microsecond, or seconds (a ΔDOR baseline's windows left out)."""
    p = tape.passes
    lines = []
    for s, a, b in zip(p.station, p.t_start_s, p.t_end_s, strict=True):
        if tape.stations.observables[s - 1] == "ddor":  # a ΔDOR baseline's window
            continue
        ends = [tape.epoch.iso_after(float(t), 6) if dates else repr(float(t)) for t in (a, b)]
        lines.append(",".join([tape.stations.name[s - 1], *ends]))
    return "\n".join(lines) + "\n"


def scaled_close(a: np.ndarray, b: np.ndarray, tol: float) -> float:
    """Return max |a_ij - b_ij| / sqrt(b_ii b_jj) (the natural scale of a normal matrix) and
    assert it is below ``tol``."""
    d = np.sqrt(np.abs(np.diagonal(b, axis1=-2, axis2=-1)))
    scale = d[..., :, None] * d[..., None, :]
    err = float(np.max(np.abs(a - b) / np.where(scale > 0, scale, 1.0)))
    assert err <= tol, err
    return err
