"""Ground stations and networks from scenario files (TOML tables).

::

    [stations.KOUROU]
    lat_deg = 5.2514
    lon_deg = -52.8047
    h_km = 0.015
    elev_mask_deg = 5.0

    [networks]
    equatorial = ["QUITO", "KOUROU", ...]

Angles are geodetic (WGS84) degrees, east longitude; the height is above the WGS84 ellipsoid
and must be that of a ground station (``tapp.measurements.stations.HEIGHT_RANGE_km``).
The tables are validated by the schemas :class:`StationTable` and :class:`StationsSection`
(``tapp.io.schema``); every error names the file and the table.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated

from pydantic import Field, model_validator

from tapp.errors import InputError
from tapp.io.schema import Invalid, Schema, validate
from tapp.measurements.stations import HEIGHT_RANGE_km, Station

#: Station fields (radians, as the kernel names them) and the scenario keys they come from.
_EDGE_KEYS = {"lat_rad": "lat_deg", "lon_rad": "lon_deg", "h_km": "h_km",
              "elev_mask_rad": "elev_mask_deg"}


class StationTable(Schema):
    """``[stations.NAME]``: a ground station, geodetic on WGS84, named by its table.

    (The kernel's own checks, :class:`tapp.measurements.stations.Station`'s height band, run
    here too, so they are reported with the file and the key.)
    """

    lat_deg: Annotated[float, Field(ge=-90.0, le=90.0)] = Field(
        description="Geodetic latitude.")
    lon_deg: float = Field(description="East longitude.")
    h_km: float = Field(description="Height above the WGS84 ellipsoid.",
                        json_schema_extra={"allowed": f"{HEIGHT_RANGE_km[0]:g} to "
                                           f"{HEIGHT_RANGE_km[1]:g}"})
    elev_mask_deg: Annotated[float, Field(ge=0.0, lt=90.0)] = Field(
        0.0, description="No data below this elevation.")

    @model_validator(mode="after")
    def _a_station(self) -> StationTable:
        self.station("station")
        return self

    def station(self, name: str) -> Station:
        """The :class:`Station` of this table, named ``name``."""
        try:
            return Station.from_degrees(name, self.lat_deg, self.lon_deg, self.h_km,
                                        self.elev_mask_deg)
        except InputError as exc:
            raise Invalid(exc.expected, exc.got, _EDGE_KEYS.get(exc.field, exc.field)) from None


class StationsSection(Schema):
    """Schema of the ``[stations.*]`` tables and ``[networks]`` of a file (other keys apart);
    the files that have them (tracking scenarios, the study) derive their schema from it."""

    stations: dict[str, StationTable] = Field({}, description="Ground stations, by name.")
    networks: dict[str, list[str]] = Field(
        {}, description="Named lists of stations (names of [stations.NAME] tables); the "
        "study's runs track from \"equatorial\" or \"global\" when they name none.")

    @model_validator(mode="after")
    def _networks_name_stations(self) -> StationsSection:
        for network, names in self.networks.items():
            for i, name in enumerate(names):
                if name not in self.stations:
                    raise Invalid(f"names of [stations.*] tables ({', '.join(self.stations)})",
                                  name, f"networks.{network}[{i}]")
        return self


def _section(data: Mapping, source: str) -> StationsSection:
    part = {k: data[k] for k in ("stations", "networks") if k in data}
    return validate(StationsSection, part, source)


def load_stations(data: Mapping, source: str) -> dict[str, Station]:
    """Return the ``[stations.*]`` tables of parsed TOML ``data`` as Stations by name."""
    return {name: table.station(name) for name, table in _section(data, source).stations.items()}


def load_network(data: Mapping, source: str, network: str) -> tuple[Station, ...]:
    """Return the stations of ``[networks].<network>``, or the single station so named."""
    section = _section(data, source)
    if network in section.networks:
        names = section.networks[network]
    elif network in section.stations:
        names = [network]
    else:
        raise InputError(source, "networks", f"a network or station name among "
                         f"{', '.join([*section.networks, *section.stations]) or 'none'}",
                         network)
    return tuple(section.stations[n].station(n) for n in names)
