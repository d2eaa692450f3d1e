"""The T13 tape (TAPP I -> TAPP III): schema, atomic HDF5 writer, validating reader.

Seed TAPP III §4.1 fixes the content; DESIGN.md ("Tapes") fixes the HDF5 form. Notation of
the seed: n_o TAPP I parameters x = [p; q] (p: the n_p orbit parameters at the epoch, q: the
constants and biases), n_m miss parameters, n_ts tracking stations, n_it records; T13 times
t_0 < t_1 < ... < t_{n_it} (the union of the input times and the epoch times, t_0 = 0 the
injection); record k covers (t_{k-1}, t_k] and is referred to the epoch t_j, where j either
stays the same from one record to the next or changes to k-1.

HDF5 layout, version 1 (every dataset has a ``units`` attribute):

==========================  =====================  ===========================================
path                        shape                  content
==========================  =====================  ===========================================
attrs                                              format="T13", version, iden, n_o, n_p, n_m,
                                                   n_ts, n_it, epoch (ISO UTC), epoch_jd_whole,
                                                   epoch_jd_fraction, time_scale, frame, center,
                                                   units, packing; provenance: tapp_version,
                                                   git_commit, created_utc, scenario (JSON),
                                                   scenario_source
parameters/name, unit, kind (n_o,) str             names carry units (``x_km``, ``GM_km3_s2``)
parameters/station          (n_o,) int             station number s of a station parameter, 0
parameters/nominal          (n_o,) float           values of x at t_0, units ``unit``
stations/id                 (n_ts,) int            station number s = 1..n_ts
stations/name, observables  (n_ts,) str            observables comma-separated
stations/lat_deg, lon_deg,  (n_ts,) float          geodetic WGS84, height km, mask deg
h_km, elev_mask_deg
miss/name, unit             (n_m,) str
miss/nominal                (n_m,) float           attrs: kind, t_s (time of the miss, s)
B                           (n_m, n_o)             ∂m/∂x at injection (t_0)
times/t_s                   (n_it+1,) float        T13 times t_0..t_{n_it}, s from the epoch
times/is_epoch, is_input    (n_it+1,) bool         which list each time came from
records/j, records/k        (n_it,) int            epoch index j, current index k = 1..n_it
records/t_s                 (n_it,) float          t_k, s (= times/t_s[1:])
records/info                (n_it, 6) float        state at t_k (km, km/s), EME2000
records/U                   (n_it, n_p, n_o)       ∂p(t_k)/∂x(t_j)
pairs/k, pairs/station      (n_pairs,) int         (record, station) pairs with data
pairs/n_obs                 (n_pairs,) int         scalar observations in the pair
pairs/dJ, pairs/dJt         (n_pairs, L)           AᵀWA, AᵀWMWA over (t_{k-1}, t_k] referred
                                                   to t_j; L = n_o(n_o+1)/2 ("TR", upper
                                                   triangle by rows) or n_o² ("full")
passes/station, t_start_s,  (n_passes,)            tracking passes (before any split at T13
t_end_s, n_obs                                     times)
raw/... (optional)          (N, ...)               one row per scalar observation: t_s,
                                                   station, kind (code into attr ``kinds``),
                                                   record, segment, value, A (N, n_o) referred
                                                   to t_j of the record, weight = 1/σ²,
                                                   m_white_var, m_bias_var, m_corr_var,
                                                   m_tau_s (the real-world M of each segment,
                                                   :func:`tapp.tracking.noise.covariance_block`)
==========================  =====================  ===========================================

Units of the normal matrices: entry (a, b) in 1/(u_a u_b) with u the parameters' units; U and
B entries in (unit of row)/(unit of column). Large datasets are chunked and gzip-compressed.
The writer writes to a temporary file beside the target and renames it: no half-written tape.
The reader rejects a wrong format or version, a missing dataset, a wrong shape, a non-finite
value, a non-symmetric ("full") or negative-diagonal normal matrix, and an inconsistent epoch
index, with a :class:`~tapp.errors.TapeError` naming the file and the dataset.
"""

from __future__ import annotations

import math
import subprocess
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from tapp import __version__
from tapp.atomic import atomic_write
from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError, TapeError
from tapp.frames.time import Epoch
from tapp.tape.packing import pack_tr, symmetry_defect, tr_size, unpack_tr

FORMAT = "T13"
VERSION = 1
SUPPORTED_VERSIONS = (1,)
#: Storage of the normal matrices: "TR" (upper triangle by rows, the default) or "full".
PACKINGS = ("TR", "full")
#: Relative asymmetry max |M_ij - M_ji| / sqrt(M_ii M_jj) above which a normal matrix is
#: rejected (:func:`tapp.tape.packing.symmetry_defect`).
SYMMETRY_TOL = 1e-12
#: Names of the state in ``records/info`` (km, km/s, EME2000).
INFO_COLUMNS = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s")
UNITS_NOTE = ("km, km/s, s, rad; normal matrices in 1/(u_a u_b), partials in (row unit)/"
              "(column unit), with u the units of parameters/unit and miss/unit")
_COMPRESSION = {"compression": "gzip", "compression_opts": 4, "shuffle": True}


def _frozen(a, dtype=float) -> np.ndarray:
    out = np.array(a, dtype=dtype)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, slots=True, eq=False)
class TapeParameters:
    """The n_o TAPP I parameters x = [p; q]: names (with units), units, kinds, nominal values.

    ``kind`` is "orbit" (p), "dynamic" (model constants), "location" or "bias" (station
    parameters, with ``station`` their station number; 0 otherwise).
    """

    name: tuple[str, ...]
    unit: tuple[str, ...]
    kind: tuple[str, ...]
    station: np.ndarray
    nominal: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeStations:
    """The n_ts tracking stations: numbers s = 1..n_ts, names, geodetic positions (deg, km)."""

    id: np.ndarray
    name: tuple[str, ...]
    observables: tuple[str, ...]
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    h_km: np.ndarray
    elev_mask_deg: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeMiss:
    """The n_m miss parameters at time ``t_s`` and B = ∂m/∂x(t_0), shape (n_m, n_o)."""

    kind: str
    t_s: float
    name: tuple[str, ...]
    unit: tuple[str, ...]
    nominal: np.ndarray
    B: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeRecords:
    """T13 times and the n_it records (time-major arrays).

    Attributes
    ----------
    times_s : (n_it + 1,) T13 times t_0 = 0 < t_1 < ... < t_{n_it}, s from the epoch.
    is_epoch, is_input : (n_it + 1,) bool, whether each time is an epoch / an input time.
    j : (n_it,) epoch index of record k (0-based T13 time index).
    k : (n_it,) record index 1..n_it.
    info : (n_it, 6) state at t_k, km and km/s, EME2000 (columns :data:`INFO_COLUMNS`).
    U : (n_it, n_p, n_o) ∂p(t_k)/∂x(t_j).
    """

    times_s: np.ndarray
    is_epoch: np.ndarray
    is_input: np.ndarray
    j: np.ndarray
    k: np.ndarray
    info: np.ndarray
    U: np.ndarray

    @property
    def t_s(self) -> np.ndarray:
        """Times t_k of the records, (n_it,) s."""
        return self.times_s[1:]


@dataclass(frozen=True, slots=True, eq=False)
class TapePairs:
    """(record, station) pairs with data and their normal matrices, full (n_pairs, n_o, n_o)."""

    k: np.ndarray
    station: np.ndarray
    n_obs: np.ndarray
    dJ: np.ndarray
    dJt: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapePasses:
    """Tracking passes: station number, first and last observation time (s), observations."""

    station: np.ndarray
    t_start_s: np.ndarray
    t_end_s: np.ndarray
    n_obs: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeRaw:
    """One row per scalar observation, for validation (module docstring for the columns).

    ``kind`` indexes ``kinds``; ``segment`` numbers the blocks of M (a pass, one kind, split
    at the T13 times); ``A`` is referred to the epoch t_j of the row's record.
    """

    kinds: tuple[str, ...]
    t_s: np.ndarray
    station: np.ndarray
    kind: np.ndarray
    record: np.ndarray
    segment: np.ndarray
    value: np.ndarray
    A: np.ndarray
    weight: np.ndarray
    m_white_var: np.ndarray
    m_bias_var: np.ndarray
    m_corr_var: np.ndarray
    m_tau_s: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class T13:
    """A T13 tape in memory: what TAPP I writes and TAPP III reads.

    ``provenance`` holds the root attributes that describe how the tape was made
    (scenario JSON and source on writing; plus tapp_version, git_commit, created_utc on
    reading).
    """

    iden: str
    epoch: Epoch
    n_p: int
    parameters: TapeParameters
    stations: TapeStations
    miss: TapeMiss
    records: TapeRecords
    pairs: TapePairs
    passes: TapePasses
    raw: TapeRaw | None = None
    provenance: dict[str, str] = field(default_factory=dict)

    @property
    def n_o(self) -> int:
        """Number of TAPP I parameters."""
        return len(self.parameters.name)

    @property
    def n_m(self) -> int:
        """Number of miss parameters."""
        return len(self.miss.name)

    @property
    def n_ts(self) -> int:
        """Number of tracking stations."""
        return len(self.stations.name)

    @property
    def n_it(self) -> int:
        """Number of records."""
        return int(self.records.k.size)


# ---------------------------------------------------------------------------------------------
# Validation (shared by the writer and the reader)
# ---------------------------------------------------------------------------------------------


class _Checker:
    """Raises TapeError naming the file and the dataset."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, dataset: str, expected: str, got: object = None) -> None:
        detail = "" if got is None else f" (got {got})"
        raise TapeError(f"{self.source}: {dataset}: expected {expected}{detail}")

    def shape(self, dataset: str, a: np.ndarray, shape: tuple[int, ...]) -> None:
        if a.shape != shape:
            self.fail(dataset, f"shape {shape}", a.shape)

    def finite(self, dataset: str, a: np.ndarray) -> None:
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
            self.fail(dataset, "finite values", f"{a[bad]} at index {bad}")

    def normal(self, dataset: str, m: np.ndarray) -> None:
        defect = symmetry_defect(m) if m.size else np.zeros(0)
        if np.any(defect > SYMMETRY_TOL):
            first = int(np.argmax(defect > SYMMETRY_TOL))
            self.fail(dataset, f"symmetric normal matrices (relative asymmetry <= "
                               f"{SYMMETRY_TOL:g})", f"{defect[first]:.3g} in pair {first}")
        diag = np.diagonal(m, axis1=-2, axis2=-1)
        if np.any(diag < 0):
            pair, col = (int(i) for i in np.argwhere(diag < 0)[0])
            self.fail(dataset, "a non-negative diagonal (sums of squares)",
                      f"{diag[pair, col]:.3g} in pair {pair}, parameter {col}")


def validate(tape: T13, source: str = "T13") -> None:
    """Check the dimensions and invariants of a tape; raise TapeError naming the dataset.

    Checks: shapes against n_o, n_p, n_m, n_ts, n_it; finiteness; T13 times strictly
    ascending from t_0 = 0, each an epoch or an input time; k = 1..n_it; j_1 = 0 and j_k
    either j_{k-1} or k-1, k-1 exactly when t_{k-1} is an epoch time; pairs unique, with
    known records and stations and at least one observation; normal matrices symmetric with
    a non-negative diagonal; raw rows consistent.
    """
    c = _Checker(source)
    n_o, n_p, n_m, n_ts, n_it = tape.n_o, tape.n_p, tape.n_m, tape.n_ts, tape.n_it
    par = tape.parameters
    if not 1 <= n_p <= n_o:
        c.fail("attrs/n_p", f"1 <= n_p <= n_o = {n_o}", n_p)
    for name in ("unit", "kind"):
        if len(getattr(par, name)) != n_o:
            c.fail(f"parameters/{name}", f"{n_o} entries", len(getattr(par, name)))
    for name in ("station", "nominal"):
        c.shape(f"parameters/{name}", getattr(par, name), (n_o,))
    c.finite("parameters/nominal", par.nominal)
    if len(set(par.name)) != n_o:
        c.fail("parameters/name", "unique names", sorted(par.name))

    st = tape.stations
    c.shape("stations/id", st.id, (n_ts,))
    if not np.array_equal(st.id, np.arange(1, n_ts + 1)):
        c.fail("stations/id", f"station numbers 1..{n_ts}", st.id.tolist())
    for name in ("lat_deg", "lon_deg", "h_km", "elev_mask_deg"):
        c.shape(f"stations/{name}", getattr(st, name), (n_ts,))
        c.finite(f"stations/{name}", getattr(st, name))
    if len(st.observables) != n_ts:
        c.fail("stations/observables", f"{n_ts} entries", len(st.observables))
    if np.any((par.station < 0) | (par.station > n_ts)):
        c.fail("parameters/station", f"station numbers in 0..{n_ts}", par.station.tolist())

    miss = tape.miss
    if len(miss.unit) != n_m:
        c.fail("miss/unit", f"{n_m} entries", len(miss.unit))
    c.shape("miss/nominal", miss.nominal, (n_m,))
    c.finite("miss/nominal", miss.nominal)
    c.shape("B", miss.B, (n_m, n_o))
    c.finite("B", miss.B)
    if not math.isfinite(miss.t_s):
        c.fail("miss/nominal.attrs/t_s", "a finite time (s)", miss.t_s)

    rec = tape.records
    for dataset, values in (("times/t_s", rec.times_s), ("times/is_epoch", rec.is_epoch),
                            ("times/is_input", rec.is_input)):
        c.shape(dataset, values, (n_it + 1,))
    c.finite("times/t_s", rec.times_s)
    if rec.times_s[0] != 0.0 or np.any(np.diff(rec.times_s) <= 0):
        c.fail("times/t_s", "strictly ascending times from t_0 = 0 s", rec.times_s[:8].tolist())
    if not rec.is_epoch[0] or not np.all(rec.is_epoch | rec.is_input):
        c.fail("times/is_epoch", "t_0 an epoch and every time an epoch or an input time")
    c.shape("records/k", rec.k, (n_it,))
    if not np.array_equal(rec.k, np.arange(1, n_it + 1)):
        c.fail("records/k", f"1..{n_it} in order", rec.k[:8].tolist())
    c.shape("records/j", rec.j, (n_it,))
    expected_j = np.maximum.accumulate(np.where(rec.is_epoch[:-1], np.arange(n_it), 0))
    if not np.array_equal(rec.j, expected_j):
        k = int(np.argmax(rec.j != expected_j)) + 1
        c.fail("records/j", "j_k = the last epoch index <= k-1 (j stays or changes to k-1)",
               f"j_{k} = {rec.j[k - 1]}, expected {expected_j[k - 1]}")
    c.shape("records/info", rec.info, (n_it, 6))
    c.finite("records/info", rec.info)
    c.shape("records/U", rec.U, (n_it, n_p, n_o))
    c.finite("records/U", rec.U)

    pairs = tape.pairs
    n_pairs = pairs.k.size
    for name in ("k", "station", "n_obs"):
        c.shape(f"pairs/{name}", getattr(pairs, name), (n_pairs,))
    if np.any((pairs.k < 1) | (pairs.k > n_it)):
        c.fail("pairs/k", f"record indices in 1..{n_it}", pairs.k.tolist())
    if np.any((pairs.station < 1) | (pairs.station > n_ts)):
        c.fail("pairs/station", f"station numbers in 1..{n_ts}", pairs.station.tolist())
    if np.any(pairs.n_obs < 1):
        c.fail("pairs/n_obs", "at least one observation per pair", pairs.n_obs.tolist())
    if np.unique(pairs.k * (n_ts + 1) + pairs.station).size != n_pairs:
        c.fail("pairs/k", "each (record, station) pair once")
    for name in ("dJ", "dJt"):
        m = getattr(pairs, name)
        c.shape(f"pairs/{name}", m, (n_pairs, n_o, n_o))
        c.finite(f"pairs/{name}", m)
        c.normal(f"pairs/{name}", m)

    ps = tape.passes
    n_passes = ps.station.size
    for name in ("station", "t_start_s", "t_end_s", "n_obs"):
        c.shape(f"passes/{name}", getattr(ps, name), (n_passes,))
    c.finite("passes/t_start_s", ps.t_start_s)
    c.finite("passes/t_end_s", ps.t_end_s)
    if np.any((ps.station < 1) | (ps.station > n_ts)) or np.any(ps.t_end_s < ps.t_start_s):
        c.fail("passes/station", f"station numbers in 1..{n_ts} and t_start_s <= t_end_s")
    if tape.raw is not None:
        _validate_raw(c, tape.raw, n_o, n_ts, n_it)


def _validate_raw(c: _Checker, raw: TapeRaw, n_o: int, n_ts: int, n_it: int) -> None:
    n = raw.t_s.size
    for name in ("t_s", "station", "kind", "record", "segment", "value", "weight",
                 "m_white_var", "m_bias_var", "m_corr_var", "m_tau_s"):
        c.shape(f"raw/{name}", getattr(raw, name), (n,))
        if name != "m_tau_s":  # inf: no correlated noise
            c.finite(f"raw/{name}", getattr(raw, name))
    c.shape("raw/A", raw.A, (n, n_o))
    c.finite("raw/A", raw.A)
    if np.any(raw.weight <= 0):
        c.fail("raw/weight", "weights 1/σ² > 0")
    if np.any((raw.kind < 0) | (raw.kind >= len(raw.kinds))):
        c.fail("raw/kind", f"codes 0..{len(raw.kinds) - 1} into attr kinds {raw.kinds}")
    if np.any((raw.record < 1) | (raw.record > n_it)):
        c.fail("raw/record", f"record indices in 1..{n_it}")
    if np.any((raw.station < 1) | (raw.station > n_ts)):
        c.fail("raw/station", f"station numbers in 1..{n_ts}")


# ---------------------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------------------


def _git_commit() -> str:
    """Commit of the source checkout tapp runs from, or "unknown"."""
    try:
        proc = subprocess.run(["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent,
                              capture_output=True, text=True, check=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return proc.stdout.strip()


def _strings(group: h5py.Group, name: str, values, units: str = "") -> None:
    ds = group.create_dataset(name, data=np.array(list(values), dtype=h5py.string_dtype()))
    ds.attrs["units"] = units


def _numbers(group: h5py.Group, name: str, values, units: str, *, big: bool = False
             ) -> h5py.Dataset:
    data = np.asarray(values)
    options = {}
    if big and data.size:
        chunk = list(data.shape)
        chunk[0] = max(1, min(data.shape[0], max(1, (1 << 18) // max(1, data[0].nbytes))))
        options = {"chunks": tuple(chunk), **_COMPRESSION}
    ds = group.create_dataset(name, data=data, **options)
    ds.attrs["units"] = units
    return ds


def _write(f: h5py.File, tape: T13, packing: str) -> None:
    f.attrs.update(
        format=FORMAT, version=VERSION, iden=tape.iden, n_o=tape.n_o, n_p=tape.n_p,
        n_m=tape.n_m, n_ts=tape.n_ts, n_it=tape.n_it, epoch=tape.epoch.iso(6),
        epoch_jd_whole=tape.epoch.jd_whole, epoch_jd_fraction=tape.epoch.jd_fraction,
        time_scale="UTC", frame="EME2000", center="earth", units=UNITS_NOTE, packing=packing,
        tapp_version=__version__, git_commit=_git_commit(),
        created_utc=datetime.now(UTC).isoformat(timespec="seconds"))
    for key in ("scenario", "scenario_source"):
        f.attrs[key] = tape.provenance.get(key, "")

    par = tape.parameters
    g = f.create_group("parameters")
    _strings(g, "name", par.name)
    _strings(g, "unit", par.unit)
    _strings(g, "kind", par.kind)
    _numbers(g, "station", par.station, "")
    _numbers(g, "nominal", par.nominal, "see unit")

    st = tape.stations
    g = f.create_group("stations")
    _numbers(g, "id", st.id, "")
    _strings(g, "name", st.name)
    _strings(g, "observables", st.observables)
    _numbers(g, "lat_deg", st.lat_deg, "deg")
    _numbers(g, "lon_deg", st.lon_deg, "deg")
    _numbers(g, "h_km", st.h_km, "km")
    _numbers(g, "elev_mask_deg", st.elev_mask_deg, "deg")

    miss = tape.miss
    g = f.create_group("miss")
    _strings(g, "name", miss.name)
    _strings(g, "unit", miss.unit)
    ds = _numbers(g, "nominal", miss.nominal, "see unit")
    ds.attrs.update(kind=miss.kind, t_s=miss.t_s)
    _numbers(f, "B", miss.B, "miss/unit per parameters/unit")

    rec = tape.records
    g = f.create_group("times")
    _numbers(g, "t_s", rec.times_s, "s")
    _numbers(g, "is_epoch", rec.is_epoch, "")
    _numbers(g, "is_input", rec.is_input, "")
    g = f.create_group("records")
    _numbers(g, "j", rec.j, "")
    _numbers(g, "k", rec.k, "")
    _numbers(g, "t_s", rec.t_s, "s")
    ds = _numbers(g, "info", rec.info, "km, km/s")
    ds.attrs["columns"] = list(INFO_COLUMNS)
    _numbers(g, "U", rec.U, "parameters/unit of p(t_k) per parameters/unit of x(t_j)",
             big=True)

    pairs = tape.pairs
    g = f.create_group("pairs")
    _numbers(g, "k", pairs.k, "")
    _numbers(g, "station", pairs.station, "")
    _numbers(g, "n_obs", pairs.n_obs, "")
    for name in ("dJ", "dJt"):
        m = getattr(pairs, name)
        stored = pack_tr(m) if packing == "TR" else m.reshape(m.shape[0], -1)
        ds = _numbers(g, name, stored, "1/(u_a u_b), u = parameters/unit", big=True)
        ds.attrs.update(packing=packing, order=tape.n_o)

    ps = tape.passes
    g = f.create_group("passes")
    _numbers(g, "station", ps.station, "")
    _numbers(g, "t_start_s", ps.t_start_s, "s")
    _numbers(g, "t_end_s", ps.t_end_s, "s")
    _numbers(g, "n_obs", ps.n_obs, "")

    if tape.raw is not None:
        raw = tape.raw
        g = f.create_group("raw")
        g.attrs["kinds"] = list(raw.kinds)
        for name, units in (("t_s", "s"), ("station", ""), ("kind", "code into attr kinds"),
                            ("record", ""), ("segment", ""), ("value", "km, km/s or rad"),
                            ("A", "observable unit per parameters/unit"),
                            ("weight", "1/(observable unit)^2"),
                            ("m_white_var", "(observable unit)^2"),
                            ("m_bias_var", "(observable unit)^2"),
                            ("m_corr_var", "(observable unit)^2"), ("m_tau_s", "s")):
            _numbers(g, name, getattr(raw, name), units, big=True)


def write_t13(path: Path | str, tape: T13, *, packing: str = "TR") -> Path:
    """Validate ``tape`` and write it to ``path`` atomically (temporary file, then rename).

    Parameters
    ----------
    path : path of the tape (conventionally ``*.t13.h5``).
    tape : T13
    packing : "TR" (upper triangle by rows, the default) or "full" (n_o² per matrix).

    Raises
    ------
    TapeError
        If the tape fails :func:`validate`.
    InputError
        For an unknown packing.
    """
    if packing not in PACKINGS:
        raise InputError("write_t13", "packing", f"one of {', '.join(PACKINGS)}", packing)
    path = Path(path)
    validate(tape, str(path))

    def write(tmp: Path) -> None:
        with h5py.File(tmp, "w") as f:
            _write(f, tape, packing)

    return atomic_write(path, write)


# ---------------------------------------------------------------------------------------------
# Reader
# ---------------------------------------------------------------------------------------------


class _Reader:
    """Reads datasets of an open file, naming the file and the dataset on failure."""

    def __init__(self, f: h5py.File, source: str):
        self.f = f
        self.check = _Checker(source)

    def attr(self, name: str, kind: type):
        if name not in self.f.attrs:
            self.check.fail(f"attrs/{name}", "this root attribute present")
        value = self.f.attrs[name]
        if kind is int:
            if not (isinstance(value, int | np.integer) and value >= 0):
                self.check.fail(f"attrs/{name}", "an integer >= 0", value)
            return int(value)
        if kind is float:
            if not (isinstance(value, float | np.floating) and np.isfinite(value)):
                self.check.fail(f"attrs/{name}", "a finite number", value)
            return float(value)
        return value.decode() if isinstance(value, bytes) else str(value)

    def read(self, name: str, kind: str = "f") -> np.ndarray:
        """Read dataset ``name``; kind "f" float, "i" integer, "b" bool, "s" strings."""
        if name not in self.f or not isinstance(self.f[name], h5py.Dataset):
            self.check.fail(name, "this dataset present")
        ds = self.f[name]
        try:
            data = ds.asstr()[()] if kind == "s" and ds.dtype.kind in "OS" else ds[()]
        except (OSError, TypeError, ValueError) as exc:
            self.check.fail(name, "readable data (truncated or corrupt file?)", exc)
        data = np.asarray(data)
        ok = {"f": "fiu", "i": "iu", "b": "b", "s": "OU"}[kind]
        if data.dtype.kind not in ok or data.ndim == 0 and kind != "f":
            self.check.fail(name, {"f": "numbers", "i": "integers", "b": "booleans",
                                   "s": "strings"}[kind], data.dtype)
        if kind == "s":
            return data
        return _frozen(data, {"f": float, "i": np.int64, "b": bool}[kind])

    def strings(self, name: str) -> tuple[str, ...]:
        return tuple(str(s) for s in self.read(name, "s"))

    def normal(self, name: str, n_pairs: int, n_o: int) -> np.ndarray:
        stored = self.read(name)
        packing = self.f[name].attrs.get("packing", "TR")
        packing = packing.decode() if isinstance(packing, bytes) else str(packing)
        if packing == "TR":
            self.check.shape(name, stored, (n_pairs, tr_size(n_o)))
            return _frozen(unpack_tr(stored, n_o))
        if packing != "full":
            self.check.fail(f"{name}.attrs/packing", f"one of {', '.join(PACKINGS)}", packing)
        self.check.shape(name, stored, (n_pairs, n_o * n_o))
        return _frozen(stored.reshape(n_pairs, n_o, n_o))


def _read(r: _Reader, *, raw: bool) -> tuple[T13, np.ndarray]:
    """Return the tape and records/t_s (checked against times/t_s once those are valid)."""
    fmt = r.attr("format", str)
    if fmt != FORMAT:
        r.check.fail("attrs/format", f"format = {FORMAT!r}", repr(fmt))
    version = r.attr("version", int)
    if version not in SUPPORTED_VERSIONS:
        r.check.fail("attrs/version", f"a supported version {SUPPORTED_VERSIONS}", version)
    dims = {name: r.attr(name, int) for name in ("n_o", "n_p", "n_m", "n_ts", "n_it")}
    epoch = Epoch(r.attr("epoch_jd_whole", float), r.attr("epoch_jd_fraction", float))

    parameters = TapeParameters(r.strings("parameters/name"), r.strings("parameters/unit"),
                                r.strings("parameters/kind"), r.read("parameters/station", "i"),
                                r.read("parameters/nominal"))
    stations = TapeStations(r.read("stations/id", "i"), r.strings("stations/name"),
                            r.strings("stations/observables"), r.read("stations/lat_deg"),
                            r.read("stations/lon_deg"), r.read("stations/h_km"),
                            r.read("stations/elev_mask_deg"))
    nominal = r.read("miss/nominal")
    attrs = r.f["miss/nominal"].attrs
    miss = TapeMiss(str(attrs.get("kind", "")), float(attrs.get("t_s", math.nan)),
                    r.strings("miss/name"), r.strings("miss/unit"), nominal, r.read("B"))
    records = TapeRecords(r.read("times/t_s"), r.read("times/is_epoch", "b"),
                          r.read("times/is_input", "b"), r.read("records/j", "i"),
                          r.read("records/k", "i"), r.read("records/info"),
                          r.read("records/U"))
    for name, value in (("n_o", len(parameters.name)), ("n_m", len(miss.name)),
                        ("n_ts", len(stations.name)), ("n_it", records.k.size)):
        if dims[name] != value:
            r.check.fail(f"attrs/{name}", f"{name} = {value} as the datasets have", dims[name])
    k = r.read("pairs/k", "i")
    pairs = TapePairs(k, r.read("pairs/station", "i"), r.read("pairs/n_obs", "i"),
                      r.normal("pairs/dJ", k.size, dims["n_o"]),
                      r.normal("pairs/dJt", k.size, dims["n_o"]))
    passes = TapePasses(r.read("passes/station", "i"), r.read("passes/t_start_s"),
                        r.read("passes/t_end_s"), r.read("passes/n_obs", "i"))
    tape_raw = None
    if raw and "raw" in r.f:
        kinds = tuple(str(s) for s in r.f["raw"].attrs.get("kinds", ()))
        tape_raw = TapeRaw(kinds, *(r.read(f"raw/{name}", kind) for name, kind in (
            ("t_s", "f"), ("station", "i"), ("kind", "i"), ("record", "i"), ("segment", "i"),
            ("value", "f"), ("A", "f"), ("weight", "f"), ("m_white_var", "f"),
            ("m_bias_var", "f"), ("m_corr_var", "f"), ("m_tau_s", "f"))))
    provenance = {key: r.attr(key, str) for key in ("tapp_version", "git_commit",
                                                    "created_utc", "scenario",
                                                    "scenario_source") if key in r.f.attrs}
    tape = T13(r.attr("iden", str), epoch, dims["n_p"], parameters, stations, miss, records,
               pairs, passes, tape_raw, provenance)
    return tape, r.read("records/t_s")


def read_t13(path: Path | str, *, raw: bool = True) -> T13:
    """Read and validate a T13 tape.

    Parameters
    ----------
    path : the tape file.
    raw : also load the optional ``raw/`` group when present.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        If it is not a readable HDF5 file (truncated, corrupt), or not a valid T13 tape; the
        message names the file and the dataset (or attribute) at fault.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(str(path), "file", "an existing T13 tape file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise TapeError(f"{path}: file: expected a readable HDF5 file (truncated or corrupt: "
                        f"{exc})") from None
    with f:
        tape, record_times = _read(_Reader(f, str(path)), raw=raw)
    validate(tape, str(path))
    if not np.array_equal(record_times, tape.records.t_s):
        raise TapeError(f"{path}: records/t_s: expected the record times t_k = times/t_s[1:]")
    return tape


def summary(tape: T13) -> dict:
    """Return a JSON-ready summary: dimensions, parameters, stations with their passes and
    observations, epoch times, records and provenance."""
    rec = tape.records
    epoch_times = rec.times_s[rec.is_epoch]
    stations = []
    for sid, name, obs, lat, lon, h in zip(tape.stations.id, tape.stations.name,
                                           tape.stations.observables, tape.stations.lat_deg,
                                           tape.stations.lon_deg, tape.stations.h_km,
                                           strict=True):
        mine = tape.pairs.station == sid
        stations.append({
            "id": int(sid), "name": name, "observables": obs, "lat_deg": float(lat),
            "lon_deg": float(lon), "h_km": float(h),
            "passes": int(np.count_nonzero(tape.passes.station == sid)),
            "observations": int(tape.pairs.n_obs[mine].sum()),
            "records_with_data": int(np.count_nonzero(mine))})
    return {
        "format": FORMAT, "version": VERSION, "iden": tape.iden, "epoch_utc": tape.epoch.iso(3),
        "dimensions": {"n_o": tape.n_o, "n_p": tape.n_p, "n_m": tape.n_m, "n_ts": tape.n_ts,
                       "n_it": tape.n_it, "pairs": int(tape.pairs.k.size),
                       "passes": int(tape.passes.station.size),
                       "raw_rows": None if tape.raw is None else int(tape.raw.t_s.size)},
        "span_s": [float(rec.times_s[0]), float(rec.times_s[-1])],
        "parameters": [{"name": n, "unit": u, "kind": k}
                       for n, u, k in zip(tape.parameters.name, tape.parameters.unit,
                                          tape.parameters.kind, strict=True)],
        "stations": stations,
        "observations": int(tape.pairs.n_obs.sum()),
        "epochs": [{"index": int(i), "t_s": float(t),
                    "utc": _utc(tape.epoch, float(t))}
                   for i, t in zip(np.flatnonzero(rec.is_epoch), epoch_times, strict=True)],
        "input_times": int(np.count_nonzero(rec.is_input)),
        "miss": {"kind": tape.miss.kind, "t_s": tape.miss.t_s,
                 "names": list(tape.miss.name), "units": list(tape.miss.unit),
                 "nominal": tape.miss.nominal.tolist()},
        "provenance": {k: v for k, v in tape.provenance.items() if k != "scenario"},
    }


def _utc(epoch: Epoch, t_s: float) -> str:
    return Epoch(epoch.jd_whole, epoch.jd_fraction + t_s / SECONDS_PER_DAY).iso(3)

