"""Observation files: HDF5 (self-contained), CSV and CCSDS TDM (stations and σ from the
scenario).

HDF5 layout: datasets ``t_s`` (M,), ``station`` (M,) int, ``values`` (M, k) with attribute
``kinds`` and ``units``; ``sigma`` (k,); group ``stations`` with ``name``, ``lat_deg``,
``lon_deg``, ``h_km``, ``elev_mask_deg``; root attributes format="tapp-observations",
version, creation time, ``span_s`` (the end of the data span), ``comments`` (provenance, e.g.
the Earth orientation the data were simulated with). CSV: a header
``t_s,station,range_km,range_rate_km_s`` (any subset of the kind columns ``range_km``,
``range_rate_km_s``, ``azimuth_rad``, ``elevation_rad``) and one row per observation time and
station. TDM (``.tdm``, or any file whose first line is ``CCSDS_TDM_VERS``): the KVN Tracking
Data Message of :mod:`tapp.io.ccsds.tdm`, one segment per station, epochs in UTC (the scenario's
epoch is t = 0), participants the station and the spacecraft; read back, the participants
must name stations of the scenario and the observables must have a σ in it. Files are written
to a temporary name and renamed; readers name the file and the field at fault.

The Earth orientation the data were made under (:class:`tapp.measurements.observations.MadeUnder`:
``earth_orientation``, ``eop``, ``frame``) is recorded when known, as three statements
``KEY = VALUE``: HDF5 root attributes of those names; CSV lines ``# KEY = VALUE`` before the
header; TDM header lines ``COMMENT tapp: KEY = VALUE`` (the TDM standard has no keyword for
it; REFERENCE_FRAME is the frame of RADEC angles). Read back, a file states all three or
none (:attr:`~tapp.measurements.observations.Observations.made_under` None, e.g. a file written by
another tool); a file stating some but not all, or an unknown model, is refused.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from iter.inputfile import read_text, regular_file
from tapp import __version__
from tapp.errors import InputError
from tapp.frames.orientation import check_model
from tapp.frames.time import Epoch
from tapp.io.atomic import atomic_write
from tapp.io.ccsds.tdm import (
    KEYWORD_OF_KIND,
    format_tdm,
    parse_tdm,
    read_tracks,
    tdm_from_tracks,
)
from tapp.io.ccsds.tdm import StationTrack as _Track
from tapp.io.tape import hdf5io
from tapp.measurements.observations import MADE_UNDER_KEYS, MadeUnder, Observations
from tapp.measurements.stations import Station

_COLUMNS = {"range": "range_km", "range_rate": "range_rate_km_s", "azimuth": "azimuth_rad",
            "elevation": "elevation_rad"}
FORMAT = "tapp-observations"
VERSION = 1
#: Prefixes of the ``KEY = VALUE`` statements of the Earth orientation in CSV lines and in
#: TDM header comments (module docstring).
CSV_PREFIX = "# "
TDM_PREFIX = "tapp: "
#: Largest TDM or CSV observation file read, bytes: about a million observation lines (a TDM
#: of 64 MiB parses in ~9 s with ~650 MB at the peak); HDF5 files are not bounded (h5py
#: reads them by dataset).
MAX_TEXT_BYTES = 64 * 2**20
_STATEMENT = re.compile(r"^(" + "|".join(MADE_UNDER_KEYS) + r")\s*=\s*(.*?)\s*$")


def made_under_statements(made: MadeUnder | None, prefix: str) -> tuple[str, ...]:
    """Return the ``PREFIX KEY = VALUE`` lines recording ``made`` (none for None)."""
    if made is None:
        return ()
    return tuple(f"{prefix}{key} = {value}" for key, value in made.as_dict().items())


def _made_under(lines: list[str], prefix: str, source: str) -> MadeUnder | None:
    """Return the MadeUnder stated by the ``PREFIX KEY = VALUE`` among ``lines`` (None when
    none is), or raise InputError naming ``source`` for a partial statement or an unknown
    model."""
    found = {}
    for line in lines:
        m = _STATEMENT.match(line.removeprefix(prefix)) if line.startswith(prefix) else None
        if m is not None:
            found[m.group(1)] = m.group(2)
    return _made_under_of(found, source)


def _made_under_of(found: dict[str, str], source: str) -> MadeUnder | None:
    if not found:
        return None
    missing = [key for key in MADE_UNDER_KEYS if key not in found]
    if missing:
        raise InputError(source, missing[0], "the Earth orientation, EOP source and frame "
                         "the data were made under, stated together (" + ", ".join(
                             MADE_UNDER_KEYS) + ")", f"only {', '.join(found)}")
    check_model(found["earth_orientation"], source, "earth_orientation")
    return MadeUnder(**{key: found[key] for key in MADE_UNDER_KEYS})


def is_tdm(path: Path) -> bool:
    """True for a ``.tdm`` path, or a file whose first non-blank text is ``CCSDS_TDM_VERS``."""
    path = Path(path)
    if path.suffix.lower() == ".tdm":
        return True
    if path.suffix in (".csv", ".h5", ".hdf5") or not path.is_file():
        return False
    with path.open("rb") as fh:
        return fh.read(4096).lstrip().startswith(b"CCSDS_TDM_VERS")


def tdm_text(obs: Observations, epoch: Epoch, spacecraft: str,
             comments: tuple[str, ...] = ()) -> str:
    """Return ``obs`` as the KVN text of a TDM: one segment per station, t = 0 at ``epoch``."""
    tracks = []
    for s, st in enumerate(obs.stations):
        rows = obs.station == s
        if not np.any(rows):
            continue
        where = (f"station {st.name}: geodetic lat {math.degrees(st.lat_rad):.6f} deg, lon "
                 f"{math.degrees(st.lon_rad):.6f} deg, h {st.h_km:.4f} km (WGS84), mask "
                 f"{math.degrees(st.elev_mask_rad):g} deg")
        tracks.append(_Track(st.name, spacecraft, tuple(obs.kinds), obs.t_s[rows],
                             obs.values[rows], obs.end_s, "1,2,1", (where,)))
    sigma = ", ".join(f"{KEYWORD_OF_KIND[k]} {v:g}" for k, v in zip(obs.kinds, obs.sigma,
                                                                   strict=True))
    notes = (*comments, *made_under_statements(obs.made_under, TDM_PREFIX),
             f"standard deviations (km, km/s, rad): {sigma}",
             "values are instantaneous at the receive time (no light time)")
    return format_tdm(tdm_from_tracks(tracks, epoch, comments=notes))


def observations_file_writer(path: Path, obs: Observations, *, epoch: Epoch | None = None,
                             spacecraft: str = "SPACECRAFT", comments: tuple[str, ...] = ()
                             ) -> Callable[[Path], None]:
    """Return ``write(at)``, which writes ``obs`` as a complete file at ``at`` in the format
    ``path``'s suffix asks for (.csv as CSV, .tdm as a CCSDS TDM, otherwise HDF5); for
    :class:`tapp.io.outputs.OutputSet`, which passes a temporary beside ``path``.

    A TDM needs the ``epoch`` of t = 0 (UTC) and names the ``spacecraft``; ``comments`` go
    to its header (HDF5: the root attribute ``comments``; CSV has no place for them). Every
    format records ``obs.made_under`` when it is known (module docstring).
    """
    path = Path(path)
    kinds = [str(k) for k in obs.kinds]
    if path.suffix.lower() == ".tdm":
        if epoch is None:
            raise InputError(str(path), "epoch", "the UTC epoch of t = 0 to write a TDM")
        text = tdm_text(obs, epoch, spacecraft, comments)

        def write(tmp: Path) -> None:
            tmp.write_text(text, encoding="utf-8")
    elif path.suffix == ".csv":
        def write(tmp: Path) -> None:
            with tmp.open("w", newline="") as fh:
                fh.writelines(f"{line}\n" for line in made_under_statements(obs.made_under,
                                                                           CSV_PREFIX))
                out = csv.writer(fh)
                out.writerow(["t_s", "station", *(_COLUMNS[k] for k in kinds)])
                for t, s, row in zip(obs.t_s, obs.station, obs.values, strict=True):
                    out.writerow([repr(float(t)), obs.stations[s].name,
                                  *(repr(float(v)) for v in row)])
    else:
        def write(tmp: Path) -> None:
            with hdf5io.create(tmp) as f:
                f.attrs.update(format=FORMAT, version=VERSION, tapp_version=__version__,
                               created_utc=datetime.now(UTC).isoformat(), span_s=obs.end_s)
                if comments:
                    f.attrs["comments"] = list(comments)
                if obs.made_under is not None:
                    f.attrs.update(obs.made_under.as_dict())
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


def write_observations(path: Path, obs: Observations, *, epoch: Epoch | None = None,
                       spacecraft: str = "SPACECRAFT") -> None:
    """Write ``obs`` to ``path`` (.h5/.hdf5 as HDF5, .csv as CSV, .tdm as a TDM with t = 0 at
    ``epoch``), atomically."""
    atomic_write(path, observations_file_writer(path, obs, epoch=epoch,
                                                spacecraft=spacecraft))


def read_observations(path: Path, stations: dict[str, Station] | None = None,
                      sigma: np.ndarray | None = None, *, epoch: Epoch | None = None,
                      sigma_kinds: tuple[str, ...] = ("range", "range_rate")
                      ) -> Observations:
    """Read an observation file; a CSV or a TDM needs the ``stations`` by name and ``sigma``.

    For a CSV ``sigma`` (k,) goes with the columns in order; for a TDM with ``sigma_kinds``
    (the file's observables must be among them) and the TDM's epochs are counted from
    ``epoch`` (UTC).
    """
    path = regular_file(path, "observation file", error=InputError)
    if is_tdm(path):
        if epoch is None:
            raise InputError(str(path), "epoch", "the scenario's epoch to read a TDM")
        return _read_tdm(path, stations or {}, sigma, sigma_kinds, epoch)
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
            span = f.attrs.get("span_s")
            stated = {key: str(f.attrs[key]) for key in MADE_UNDER_KEYS if key in f.attrs}
    except OSError as exc:
        raise InputError(str(path), "file", f"a readable HDF5 file ({exc})") from None
    _check(path, t, v)
    span_s = float(span) if span is not None and np.isfinite(span) else None
    return Observations(t, s.astype(int), v, st, kinds, sg, span_s,
                        _made_under_of(stated, str(path)))


def _read_tdm(path: Path, stations: dict[str, Station], sigma: np.ndarray | None,
              sigma_kinds: tuple[str, ...], epoch: Epoch) -> Observations:
    text = read_text(path, "text (KVN) TDM", max_bytes=MAX_TEXT_BYTES, error=InputError)
    tdm = parse_tdm(text, str(path))
    tracks = read_tracks(tdm, epoch, stations)
    if not tracks:
        raise InputError(str(path), "data", "at least one observation")
    kinds = tracks[0].kinds
    for i, tr in enumerate(tracks[1:], start=2):
        if tr.kinds != kinds:
            raise InputError(str(path), f"track {i} ({tr.station})", "the observables of the "
                             f"first ({', '.join(KEYWORD_OF_KIND[k] for k in kinds)})",
                             ", ".join(KEYWORD_OF_KIND[k] for k in tr.kinds))
    if sigma is None or len(sigma) != len(sigma_kinds):
        raise InputError(str(path), "sigma", f"a standard deviation for each of "
                         f"{', '.join(sigma_kinds)} from the scenario")
    missing = [k for k in kinds if k not in sigma_kinds]
    if missing:
        raise InputError(str(path), KEYWORD_OF_KIND[missing[0]], "observables with a standard "
                         "deviation in the scenario (" + ", ".join(
                             KEYWORD_OF_KIND[k] for k in sigma_kinds) + ")")
    names = list(dict.fromkeys(tr.station for tr in tracks))
    index = {n: i for i, n in enumerate(names)}
    t = np.concatenate([tr.t_s for tr in tracks])
    s = np.concatenate([np.full(tr.t_s.size, index[tr.station]) for tr in tracks])
    v = np.concatenate([tr.values for tr in tracks])
    order = np.lexsort((s, t))
    ends = [tr.span_end_s for tr in tracks if tr.span_end_s is not None]
    span = max([*ends, float(t.max())])
    sg = np.array([sigma[sigma_kinds.index(k)] for k in kinds], dtype=float)
    return Observations(t[order], s[order], v[order], tuple(stations[n] for n in names), kinds,
                        sg, span, _made_under(list(tdm.comments), TDM_PREFIX, str(path)))


def _check(path: Path, t: np.ndarray, values: np.ndarray) -> None:
    if not np.all(np.isfinite(t)) or not np.all(np.isfinite(values)):
        raise InputError(str(path), "values", "finite numbers")
    if np.any(np.diff(t) < 0):
        k = int(np.flatnonzero(np.diff(t) < 0)[0]) + 1
        raise InputError(str(path), "t_s", "non-decreasing times", f"row {k + 1}: {t[k]}")


def _read_csv(path: Path, stations: dict[str, Station], sigma: np.ndarray | None
              ) -> Observations:
    lines = read_text(path, "CSV observation file", max_bytes=MAX_TEXT_BYTES,
                      error=InputError).splitlines()
    # the statements of the Earth orientation (module docstring) come before the header
    lead = next((i for i, line in enumerate(lines) if not line.startswith(CSV_PREFIX[0])),
                len(lines))
    rows = list(csv.reader(lines[lead:]))
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
    for line, r in enumerate(rows[1:], start=lead + 2):
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
                        tuple(stations[n] for n in names), kinds, np.asarray(sigma, float),
                        made_under=_made_under(lines[:lead], CSV_PREFIX, str(path)))
