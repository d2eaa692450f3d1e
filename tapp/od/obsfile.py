"""Observation files: HDF5 (self-contained) and CSV (stations and σ from the scenario).

HDF5 layout: datasets ``t_s`` (M,), ``station`` (M,) int, ``values`` (M, k) with attribute
``kinds`` and ``units``; ``sigma`` (k,); group ``stations`` with ``name``, ``lat_deg``,
``lon_deg``, ``h_km``, ``elev_mask_deg``; root attributes format="tapp-observations",
version, creation time. CSV: a header ``t_s,station,range_km,range_rate_km_s`` (any subset
of the kind columns ``range_km``, ``range_rate_km_s``, ``azimuth_rad``, ``elevation_rad``)
and one row per observation time and station. Files are written to a temporary name and
renamed; readers name the file and the field at fault.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from tapp import __version__
from tapp.atomic import atomic_write
from tapp.errors import InputError
from tapp.measurements.stations import Station
from tapp.od.observations import Observations

_COLUMNS = {"range": "range_km", "range_rate": "range_rate_km_s", "azimuth": "azimuth_rad",
            "elevation": "elevation_rad"}
FORMAT = "tapp-observations"
VERSION = 1


def observations_file_writer(path: Path, obs: Observations) -> Callable[[Path], None]:
    """Return ``write(at)``, which writes ``obs`` as a complete file at ``at`` in the format
    ``path``'s suffix asks for (.csv as CSV, otherwise HDF5); for
    :class:`tapp.outputs.OutputSet`, which passes a temporary beside ``path``."""
    path = Path(path)
    kinds = [str(k) for k in obs.kinds]
    if path.suffix == ".csv":
        def write(tmp: Path) -> None:
            with tmp.open("w", newline="") as fh:
                out = csv.writer(fh)
                out.writerow(["t_s", "station", *(_COLUMNS[k] for k in kinds)])
                for t, s, row in zip(obs.t_s, obs.station, obs.values, strict=True):
                    out.writerow([repr(float(t)), obs.stations[s].name,
                                  *(repr(float(v)) for v in row)])
    else:
        def write(tmp: Path) -> None:
            with h5py.File(tmp, "w") as f:
                f.attrs.update(format=FORMAT, version=VERSION, tapp_version=__version__,
                               created_utc=datetime.now(UTC).isoformat())
                f.create_dataset("t_s", data=obs.t_s).attrs["units"] = "s"
                f.create_dataset("station", data=obs.station)
                v = f.create_dataset("values", data=obs.values)
                v.attrs["kinds"] = kinds
                v.attrs["units"] = [_COLUMNS[k].split("_")[-1] for k in kinds]
                f.create_dataset("sigma", data=obs.sigma)
                g = f.create_group("stations")
                g["name"] = [s.name for s in obs.stations]
                g["lat_deg"] = [math.degrees(s.lat_rad) for s in obs.stations]
                g["lon_deg"] = [math.degrees(s.lon_rad) for s in obs.stations]
                g["h_km"] = [s.h_km for s in obs.stations]
                g["elev_mask_deg"] = [math.degrees(s.elev_mask_rad) for s in obs.stations]
    return write


def write_observations(path: Path, obs: Observations) -> None:
    """Write ``obs`` to ``path`` (.h5/.hdf5 as HDF5, .csv as CSV), atomically."""
    atomic_write(path, observations_file_writer(path, obs))


def read_observations(path: Path, stations: dict[str, Station] | None = None,
                      sigma: np.ndarray | None = None) -> Observations:
    """Read an observation file; a CSV needs the ``stations`` by name and ``sigma``."""
    path = Path(path)
    if not path.exists():
        raise InputError(str(path), "file", "an existing observation file")
    if path.suffix == ".csv":
        return _read_csv(path, stations or {}, sigma)
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise InputError(str(path), "format", f"attribute format={FORMAT!r}",
                                 f.attrs.get("format"))
            for name in ("t_s", "station", "values", "sigma", "stations"):
                if name not in f:
                    raise InputError(str(path), name, "this dataset present")
            g = f["stations"]
            st = tuple(Station.from_degrees(n.decode() if isinstance(n, bytes) else str(n),
                                            lat, lon, h, mask)
                       for n, lat, lon, h, mask in zip(g["name"][()], g["lat_deg"][()],
                                                       g["lon_deg"][()], g["h_km"][()],
                                                       g["elev_mask_deg"][()], strict=True))
            kinds = tuple(str(k) for k in f["values"].attrs["kinds"])
            t, s, v, sg = f["t_s"][()], f["station"][()], f["values"][()], f["sigma"][()]
    except OSError as exc:
        raise InputError(str(path), "file", f"a readable HDF5 file ({exc})") from None
    _check(path, t, v)
    return Observations(t, s.astype(int), v, st, kinds, sg)


def _check(path: Path, t: np.ndarray, values: np.ndarray) -> None:
    if not np.all(np.isfinite(t)) or not np.all(np.isfinite(values)):
        raise InputError(str(path), "values", "finite numbers")
    if np.any(np.diff(t) < 0):
        k = int(np.flatnonzero(np.diff(t) < 0)[0]) + 1
        raise InputError(str(path), "t_s", "non-decreasing times", f"row {k + 1}: {t[k]}")


def _read_csv(path: Path, stations: dict[str, Station], sigma: np.ndarray | None
              ) -> Observations:
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise InputError(str(path), "header", "t_s,station and observable columns")
    header = [h.strip() for h in rows[0]]
    by_column = {v: k for k, v in _COLUMNS.items()}
    kinds = tuple(by_column[h] for h in header[2:] if h in by_column)
    if header[:2] != ["t_s", "station"] or not kinds or len(kinds) != len(header) - 2:
        raise InputError(str(path), "header", "t_s,station then columns among "
                         f"{', '.join(_COLUMNS.values())}", ",".join(header))
    if sigma is None or len(sigma) != len(kinds):
        n = "no" if sigma is None else len(sigma)
        raise InputError(str(path), "header", f"one observable column per standard deviation "
                         f"of the scenario ({n} given)", ",".join(header))
    names = sorted({r[1] for r in rows[1:] if len(r) > 1})
    unknown = [n for n in names if n not in stations]
    if unknown:
        raise InputError(str(path), "station", "stations defined in the scenario", unknown[0])
    index = {n: i for i, n in enumerate(names)}
    t, s, v = [], [], []
    for line, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(str(path), f"line {line}", f"{len(header)} columns", len(r))
        try:
            t.append(float(r[0]))
            v.append([float(x) for x in r[2:]])
        except ValueError:
            raise InputError(str(path), f"line {line}", "numbers in t_s and value columns",
                             r) from None
        s.append(index[r[1]])
    t_arr, v_arr = np.array(t), np.array(v).reshape(len(t), len(kinds))
    _check(path, t_arr, v_arr)
    return Observations(t_arr, np.array(s, dtype=int), v_arr,
                        tuple(stations[n] for n in names), kinds, np.asarray(sigma, float))
