"""Initial orbits from text: element lists, Cartesian lists, or names in a scenario file.

Grammar of an orbit spec (the ``--orbit`` option):

- ``a=6550.524,e=0,i=30,raan=0,argp=0,M=0``: classical elements, a in km, angles in degrees
  (M is the mean anomaly; ``nu=`` may replace it with the true anomaly);
- ``x=..,y=..,z=..,vx=..,vy=..,vz=..``: Cartesian position (km) and velocity (km/s);
- ``NAME``: an orbit of the ``[orbits.NAME]`` tables of a scenario file, whose keys are
  ``a_km, e, i_deg, raan_deg, argp_deg, M_deg`` or ``x_km, ..., vz_km_s``.

All states are EME2000 inertial, centred on the Earth, with the EGM96 GM.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.errors import InputError
from tapp.frames.elements import elements_to_cartesian, true_to_mean_anomaly
from tapp.tomlfile import read_toml

_ELEMENT_KEYS = ("a", "e", "i", "raan", "argp")
_CART_KEYS = ("x", "y", "z", "vx", "vy", "vz")
#: The study's scenario file, found beside the package in a source checkout.
DEFAULT_SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "approx_stm.toml"


def _parse_pairs(text: str, source: str, field: str) -> dict[str, float]:
    pairs: dict[str, float] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not key or not math.isfinite(number):
            raise InputError(source, field, "comma-separated key=number pairs with finite "
                             "numbers", item.strip())
        if key in pairs:
            raise InputError(source, field, "each key once", key)
        pairs[key] = number
    return pairs


def state_from_elements(a_km: float, e: float, i_deg: float, raan_deg: float, argp_deg: float,
                        anomaly_deg: float, *, true_anomaly: bool = False,
                        source: str = "orbit", field: str = "orbit") -> np.ndarray:
    """Return the Cartesian state (6,) km, km/s of classical elements given in degrees."""
    if not e >= 0 or (e < 1 and a_km <= 0) or (e > 1 and a_km >= 0):
        raise InputError(source, field, "e >= 0 with a > 0 (ellipse) or a < 0 (hyperbola)",
                         f"a={a_km}, e={e}")
    anomaly = math.radians(anomaly_deg)
    if true_anomaly:
        anomaly = float(true_to_mean_anomaly(anomaly, e))
    elems = np.array([a_km, e, *np.radians([i_deg, raan_deg, argp_deg]), anomaly])
    return np.asarray(elements_to_cartesian(elems, GM_EARTH_km3_s2), dtype=float)


def _from_mapping(values: Mapping[str, float], source: str, field: str) -> np.ndarray:
    keys = set(values)
    if keys == set(_CART_KEYS):
        return np.array([values[k] for k in _CART_KEYS], dtype=float)
    anomaly = {"M", "nu"} & keys
    if keys - {"M", "nu"} == set(_ELEMENT_KEYS) and len(anomaly) == 1:
        which = anomaly.pop()
        return state_from_elements(*(values[k] for k in _ELEMENT_KEYS), values[which],
                                   true_anomaly=which == "nu", source=source, field=field)
    raise InputError(source, field, "keys a,e,i,raan,argp and M (or nu), or x,y,z,vx,vy,vz",
                     ",".join(sorted(keys)))


def named_orbits(path: Path) -> dict[str, np.ndarray]:
    """Return the states of every ``[orbits.NAME]`` table of a scenario file."""
    orbits = read_toml(path).get("orbits", {})
    out = {}
    for name, table in orbits.items():
        renamed = {k.removesuffix("_km_s").removesuffix("_km").removesuffix("_deg"): v
                   for k, v in table.items()}
        out[name] = _from_mapping(renamed, str(path), f"orbits.{name}")
    return out


def parse_orbit(text: str, *, scenario: Path | None = None, source: str = "--orbit"
                ) -> np.ndarray:
    """Return the initial state (6,) of an orbit spec (module docstring grammar)."""
    text = text.strip()
    if "=" in text:
        return _from_mapping(_parse_pairs(text, source, "orbit"), source, "orbit")
    path = scenario or DEFAULT_SCENARIO
    orbits = named_orbits(path)
    if text not in orbits:
        raise InputError(source, "orbit", f"elements, a Cartesian state or an orbit named in "
                         f"{path} ({', '.join(orbits) or 'none'})", text)
    return orbits[text]
