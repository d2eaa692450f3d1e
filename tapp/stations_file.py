"""Ground stations and networks from scenario files (TOML tables).

::

    [stations.KOUROU]
    lat_deg = 5.2514
    lon_deg = -52.8047
    h_km = 0.015
    elev_mask_deg = 5.0

    [networks]
    equatorial = ["QUITO", "KOUROU", ...]

Angles are geodetic (WGS84) degrees, east longitude; every error names the file and table.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from tapp.errors import InputError
from tapp.measurements.stations import Station

_KEYS = ("lat_deg", "lon_deg", "h_km")


def load_stations(data: Mapping, source: str) -> dict[str, Station]:
    """Return the ``[stations.*]`` tables of parsed TOML ``data`` as Stations by name."""
    out = {}
    for name, table in data.get("stations", {}).items():
        field = f"stations.{name}"
        if not isinstance(table, Mapping):
            raise InputError(source, field, "a table with lat_deg, lon_deg, h_km")
        unknown = set(table) - {*_KEYS, "elev_mask_deg"}
        if unknown:
            raise InputError(source, f"{field}.{sorted(unknown)[0]}",
                             "only lat_deg, lon_deg, h_km, elev_mask_deg")
        values = {}
        for key in (*_KEYS, "elev_mask_deg"):
            value = table.get(key, 0.0 if key == "elev_mask_deg" else None)
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise InputError(source, f"{field}.{key}", "a finite number", value)
            values[key] = float(value)
        if not -90.0 <= values["lat_deg"] <= 90.0:
            raise InputError(source, f"{field}.lat_deg", "a latitude in [-90, 90]",
                             values["lat_deg"])
        if not 0.0 <= values["elev_mask_deg"] < 90.0:
            raise InputError(source, f"{field}.elev_mask_deg", "a mask in [0, 90)",
                             values["elev_mask_deg"])
        out[name] = Station.from_degrees(name, values["lat_deg"], values["lon_deg"],
                                         values["h_km"], values["elev_mask_deg"])
    return out


def load_network(data: Mapping, source: str, network: str) -> tuple[Station, ...]:
    """Return the stations of ``[networks].<network>``, or the single station so named."""
    stations = load_stations(data, source)
    networks = data.get("networks", {})
    if network in networks:
        names = networks[network]
    elif network in stations:
        names = [network]
    else:
        raise InputError(source, "networks", f"a network or station name among "
                         f"{', '.join([*networks, *stations]) or 'none'}", network)
    missing = [n for n in names if n not in stations]
    if missing:
        raise InputError(source, f"networks.{network}", "names of [stations.*] tables",
                         missing[0])
    return tuple(stations[n] for n in names)
