"""The T13 tape (TAPP I -> TAPP III): schema, atomic HDF5 writer, validating readers.

Seed TAPP III §4.1 fixes the content; DESIGN.md ("Tapes") fixes the HDF5 form. Notation of
the seed: n_o TAPP I parameters x = [p; q] (p: the n_p orbit parameters at the epoch, q: the
constants and biases), n_m miss parameters, n_ts tracking stations, n_it records; T13 times
t_0 < t_1 < ... < t_{n_it} (the union of the input times and the epoch times, t_0 = 0 the
injection); record k covers (t_{k-1}, t_k] and is referred to the epoch t_j, where j either
stays the same from one record to the next or changes to k-1.

HDF5 layout, version 2 (every dataset has a ``units`` attribute and a Fletcher-32 checksum,
:mod:`tapp.tape.hdf5io`):

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
pairs/k, pairs/station      (n_pairs,) int         (record, station) pairs with data, each
                                                   once, sorted by (k, station)
pairs/n_obs                 (n_pairs,) int         scalar observations in the pair
pairs/dJ, pairs/dJt         (n_pairs, L)           AᵀWA, AᵀWMWA over (t_{k-1}, t_k] referred
                                                   to t_j; L = n_o(n_o+1)/2 ("TR", upper
                                                   triangle by rows) or n_o² ("full"); attrs
                                                   packing, order (= n_o)
pairs/dJt_parts (optional)  (n_pairs, 3, L)        AᵀWMWA split into its white-noise, per-pass
                                                   bias and exponentially correlated parts
                                                   (attr ``parts`` = white, bias, correlated:
                                                   the terms of ``normal_matrix_parts`` of
                                                   tapp.tracking.noise), summing to dJt
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
B entries in (unit of row)/(unit of column). Every dataset is chunked (whole rows) with a
Fletcher-32 checksum, text (of datasets and attributes: h5py reads text attributes as bytes)
is fixed-length UTF-8, and large datasets are gzip-compressed. Version 1 (still read, with a
``UserWarning``) has the same layout without checksums and without ``pairs/dJt_parts``; its
text is variable-length.

The writer writes to a temporary file beside the target and renames it: no half-written tape.
The readers reject a wrong format or version, a missing dataset, a wrong shape, a non-finite
value, a non-symmetric ("full") or negative-diagonal normal matrix, parts that do not sum to
dJt, an inconsistent epoch index and a checksum mismatch, with a
:class:`~tapp.errors.TapeError` naming the file and the dataset. :func:`read_t13` loads the
whole tape; :func:`open_t13` loads everything but the pair matrices and reads those record
range by record range (:meth:`T13File.pair_block`), for tapes too large to unpack at once;
:func:`memory_pairs` offers the same interface over a tape in memory.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path

import h5py
import numpy as np

from tapp.atomic import atomic_write
from tapp.constants import SECONDS_PER_DAY
from tapp.errors import InputError, TapeError
from tapp.frames.time import Epoch
from tapp.tape import hdf5io
from tapp.tape.hdf5io import PACKINGS, SYMMETRY_TOL, Checker, Reader, frozen
from tapp.tape.packing import (
    pack_tr,
    scaled_difference,
    scaled_difference_tr,
    tr_diagonal,
    tr_size,
)

#: Provenance attributes the simulator stamps: the scenario (JSON) and its file, the Earth
#: orientation model ("iau2006" or "gmst") and the EOP source of the run.
SCENARIO_PROVENANCE = ("scenario", "scenario_source", "earth_orientation", "eop")


def frame_of(provenance: dict[str, str]) -> str:
    """The inertial frame of a run: GCRS under iau2006, EME2000 under gmst (or unstated)."""
    return "GCRS" if provenance.get("earth_orientation") == "iau2006" else "EME2000"

FORMAT = "T13"
VERSION = 2
SUPPORTED_VERSIONS = (1, 2)
#: Names of the parts of ``pairs/dJt_parts``, in order (as tapp.tracking.noise.PARTS).
PARTS = ("white", "bias", "correlated")
#: Largest relative difference max |Σ parts - dJt| / sqrt(dJt_aa dJt_bb) accepted (round-off
#: of sums of a few thousand terms in another order).
PARTS_TOL = 1e-10
#: Names of the state in ``records/info`` (km, km/s, EME2000).
INFO_COLUMNS = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s")
UNITS_NOTE = ("km, km/s, s, rad; normal matrices in 1/(u_a u_b), partials in (row unit)/"
              "(column unit), with u the units of parameters/unit and miss/unit")
#: Budget of one block of :meth:`T13File.blocks` (bytes of packed matrices).
BLOCK_BYTES = 1 << 25

__all__ = ["FORMAT", "INFO_COLUMNS", "PACKINGS", "PARTS", "PARTS_TOL", "SUPPORTED_VERSIONS",
           "SYMMETRY_TOL", "T13", "VERSION", "MemoryPairs", "PairBlock", "T13File",
           "TapeMiss", "TapePairs", "TapeParameters", "TapePasses", "TapeRaw", "TapeRecords",
           "TapeStations", "memory_pairs", "open_t13", "read_t13", "summary",
           "t13_file_writer", "utc_at", "validate", "write_t13"]

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
    """(record, station) pairs with data and their normal matrices, full in memory.

    Attributes
    ----------
    k, station, n_obs : (n_pairs,) int record index, station number, observations; sorted by
        (k, station).
    dJ, dJt : (n_pairs, n_o, n_o) AᵀWA and AᵀWMWA, 1/(u_a u_b); None in the header of a
        lazily read tape (:attr:`T13File.header`).
    dJt_parts : (n_pairs, 3, n_o, n_o) the :data:`PARTS` of dJt (white, bias, correlated),
        or None (not on the tape, or a header).
    """

    k: np.ndarray
    station: np.ndarray
    n_obs: np.ndarray
    dJ: np.ndarray | None
    dJt: np.ndarray | None
    dJt_parts: np.ndarray | None = None


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


@dataclass(frozen=True, slots=True, eq=False)
class PairBlock:
    """Pairs of records k_first..k_last (inclusive), normal matrices packed TR.

    L = n_o (n_o + 1) / 2 (:func:`tapp.tape.packing.pack_tr`; unpack with
    :func:`tapp.tape.packing.unpack_tr`).

    Attributes
    ----------
    k : (m,) int record index, ascending.
    station : (m,) int station number, ascending within a record.
    n_obs : (m,) int scalar observations of each pair.
    dJ, dJt : (m, L) AᵀWA and AᵀWMWA, 1/(u_a u_b).
    dJt_parts : (m, 3, L) the :data:`PARTS` of dJt, or None when the tape has no parts.
    """

    k: np.ndarray
    station: np.ndarray
    n_obs: np.ndarray
    dJ: np.ndarray
    dJt: np.ndarray
    dJt_parts: np.ndarray | None


# ---------------------------------------------------------------------------------------------
# Validation (shared by the writer and the readers)
# ---------------------------------------------------------------------------------------------


def validate(tape: T13, source: str = "T13") -> None:
    """Check the dimensions and invariants of a tape; raise TapeError naming the dataset.

    Checks: shapes against n_o, n_p, n_m, n_ts, n_it; finiteness; T13 times strictly
    ascending from t_0 = 0, each an epoch or an input time; k = 1..n_it; j_1 = 0 and j_k
    either j_{k-1} or k-1, k-1 exactly when t_{k-1} is an epoch time; pairs each once and
    sorted by (k, station), with known records and stations and at least one observation;
    normal matrices present, symmetric with a non-negative diagonal; the parts of dJt (when
    present) summing to dJt within :data:`PARTS_TOL`; raw rows consistent.
    """
    c = Checker(source)
    _validate_header(c, tape)
    pairs, n_pairs, n_o = tape.pairs, tape.pairs.k.size, tape.n_o
    for name in ("dJ", "dJt"):
        m = getattr(pairs, name)
        if m is None:
            c.fail(f"pairs/{name}", "the normal matrices (a complete tape)",
                   "None: a header without pair matrices")
        c.shape(f"pairs/{name}", m, (n_pairs, n_o, n_o))
        c.finite(f"pairs/{name}", m)
        c.symmetric(f"pairs/{name}", m)
    if pairs.dJt_parts is not None:
        c.shape("pairs/dJt_parts", pairs.dJt_parts, (n_pairs, len(PARTS), n_o, n_o))
        c.finite("pairs/dJt_parts", pairs.dJt_parts)
        _check_parts_sum(c, scaled_difference(pairs.dJt_parts.sum(axis=1), pairs.dJt), 0)
    if tape.raw is not None:
        _validate_raw(c, tape.raw, n_o, tape.n_ts, tape.n_it)


def _check_parts_sum(c: Checker, defect: np.ndarray, offset: int) -> None:
    if np.any(defect > PARTS_TOL):
        first = int(np.argmax(defect > PARTS_TOL))
        c.fail("pairs/dJt_parts", f"parts summing to pairs/dJt (relative difference <= "
                                  f"{PARTS_TOL:g})", f"{defect[first]:.3g} in pair "
                                                     f"{first + offset}")


def check_parameters(c: Checker, par: TapeParameters, n_p: int) -> None:
    """Check the n_o parameters x = [p; q] of a tape (T13 or T32): 1 <= n_p <= n_o, one
    unit, kind, station number and finite nominal value each, unique names."""
    n_o = len(par.name)
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


def _validate_header(c: Checker, tape: T13) -> None:
    """Everything of :func:`validate` but the pair matrices and the raw rows."""
    n_o, n_p, n_m, n_ts, n_it = tape.n_o, tape.n_p, tape.n_m, tape.n_ts, tape.n_it
    par = tape.parameters
    check_parameters(c, par, n_p)

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
    keys = pairs.k * (n_ts + 1) + pairs.station
    if np.any(np.diff(keys) <= 0):
        first = int(np.argmax(np.diff(keys) <= 0)) + 1
        c.fail("pairs/k", "each (record, station) pair once, sorted by (k, station)",
               f"pair {first} = ({pairs.k[first]}, {pairs.station[first]}) after "
               f"({pairs.k[first - 1]}, {pairs.station[first - 1]})")

    ps = tape.passes
    n_passes = ps.station.size
    for name in ("station", "t_start_s", "t_end_s", "n_obs"):
        c.shape(f"passes/{name}", getattr(ps, name), (n_passes,))
    c.finite("passes/t_start_s", ps.t_start_s)
    c.finite("passes/t_end_s", ps.t_end_s)
    if np.any((ps.station < 1) | (ps.station > n_ts)) or np.any(ps.t_end_s < ps.t_start_s):
        c.fail("passes/station", f"station numbers in 1..{n_ts} and t_start_s <= t_end_s")


def _validate_raw(c: Checker, raw: TapeRaw, n_o: int, n_ts: int, n_it: int) -> None:
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


def _write(f: h5py.File, tape: T13, packing: str, version: int = VERSION) -> None:
    """Write ``tape`` into the open file ``f``.

    ``version=1`` writes the version-1 layout (no checksums, no ``pairs/dJt_parts``): kept
    so that the reader of version-1 tapes stays tested.
    """
    cs = version >= 2

    def strings(group: h5py.Group, name: str, values, units: str = "") -> None:
        hdf5io.write_strings(group, name, values, units, checksums=cs)

    def numbers(group: h5py.Group, name: str, values, units: str, *, big: bool = False
                ) -> h5py.Dataset:
        return hdf5io.write_numbers(group, name, values, units, big=big, checksums=cs)

    hdf5io.write_attrs(f, dict(
        format=FORMAT, version=version, iden=tape.iden, n_o=tape.n_o, n_p=tape.n_p,
        n_m=tape.n_m, n_ts=tape.n_ts, n_it=tape.n_it, epoch=tape.epoch.iso(6),
        epoch_jd_whole=tape.epoch.jd_whole, epoch_jd_fraction=tape.epoch.jd_fraction,
        time_scale="UTC", frame=frame_of(tape.provenance), center="earth", units=UNITS_NOTE,
        packing=packing, **hdf5io.provenance_attrs()), checksums=cs)
    hdf5io.write_attrs(f, {key: tape.provenance.get(key, "") for key in SCENARIO_PROVENANCE},
                       checksums=cs)

    par = tape.parameters
    g = f.create_group("parameters")
    strings(g, "name", par.name)
    strings(g, "unit", par.unit)
    strings(g, "kind", par.kind)
    numbers(g, "station", par.station, "")
    numbers(g, "nominal", par.nominal, "see unit")

    st = tape.stations
    g = f.create_group("stations")
    numbers(g, "id", st.id, "")
    strings(g, "name", st.name)
    strings(g, "observables", st.observables)
    numbers(g, "lat_deg", st.lat_deg, "deg")
    numbers(g, "lon_deg", st.lon_deg, "deg")
    numbers(g, "h_km", st.h_km, "km")
    numbers(g, "elev_mask_deg", st.elev_mask_deg, "deg")

    miss = tape.miss
    g = f.create_group("miss")
    strings(g, "name", miss.name)
    strings(g, "unit", miss.unit)
    ds = numbers(g, "nominal", miss.nominal, "see unit")
    hdf5io.write_attrs(ds, {"kind": miss.kind, "t_s": miss.t_s}, checksums=cs)
    numbers(f, "B", miss.B, "miss/unit per parameters/unit")

    rec = tape.records
    g = f.create_group("times")
    numbers(g, "t_s", rec.times_s, "s")
    numbers(g, "is_epoch", rec.is_epoch, "")
    numbers(g, "is_input", rec.is_input, "")
    g = f.create_group("records")
    numbers(g, "j", rec.j, "")
    numbers(g, "k", rec.k, "")
    numbers(g, "t_s", rec.t_s, "s")
    ds = numbers(g, "info", rec.info, "km, km/s")
    hdf5io.write_attrs(ds, {"columns": list(INFO_COLUMNS)}, checksums=cs)
    numbers(g, "U", rec.U, "parameters/unit of p(t_k) per parameters/unit of x(t_j)", big=True)

    pairs = tape.pairs
    g = f.create_group("pairs")
    numbers(g, "k", pairs.k, "")
    numbers(g, "station", pairs.station, "")
    numbers(g, "n_obs", pairs.n_obs, "")
    units = "1/(u_a u_b), u = parameters/unit"
    for name in ("dJ", "dJt"):
        hdf5io.write_symmetric(g, name, getattr(pairs, name), units, packing, big=True,
                               checksums=cs)
    if cs and pairs.dJt_parts is not None:
        ds = hdf5io.write_symmetric(g, "dJt_parts", pairs.dJt_parts, units, packing, big=True)
        hdf5io.write_attrs(ds, {"parts": list(PARTS)})

    ps = tape.passes
    g = f.create_group("passes")
    numbers(g, "station", ps.station, "")
    numbers(g, "t_start_s", ps.t_start_s, "s")
    numbers(g, "t_end_s", ps.t_end_s, "s")
    numbers(g, "n_obs", ps.n_obs, "")

    if tape.raw is not None:
        raw = tape.raw
        g = f.create_group("raw")
        hdf5io.write_attrs(g, {"kinds": list(raw.kinds)}, checksums=cs)
        for name, units in (("t_s", "s"), ("station", ""), ("kind", "code into attr kinds"),
                            ("record", ""), ("segment", ""), ("value", "km, km/s or rad"),
                            ("A", "observable unit per parameters/unit"),
                            ("weight", "1/(observable unit)^2"),
                            ("m_white_var", "(observable unit)^2"),
                            ("m_bias_var", "(observable unit)^2"),
                            ("m_corr_var", "(observable unit)^2"), ("m_tau_s", "s")):
            numbers(g, name, getattr(raw, name), units, big=True)


def t13_file_writer(tape: T13, packing: str = "TR", *, source: str = "T13"
                    ) -> Callable[[Path], None]:
    """Validate ``tape`` now; return a function that writes it, complete, at a given path.

    For committing several outputs together (:func:`tapp.atomic.atomic_write` of each);
    :func:`write_t13` is ``atomic_write(path, t13_file_writer(tape, packing))``.

    Parameters
    ----------
    tape : T13
    packing : "TR" (upper triangle by rows, the default) or "full" (n_o² per matrix).
    source : name of the tape in the messages of :func:`validate`.

    Raises
    ------
    TapeError
        If the tape fails :func:`validate`.
    InputError
        For an unknown packing.
    """
    if packing not in PACKINGS:
        raise InputError("write_t13", "packing", f"one of {', '.join(PACKINGS)}", packing)
    validate(tape, source)

    def write(path: Path) -> None:
        with hdf5io.create(Path(path)) as f:
            _write(f, tape, packing)

    return write


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
    path = Path(path)
    return atomic_write(path, t13_file_writer(tape, packing, source=str(path)))


# ---------------------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------------------


def _reader(f: h5py.File, source: str) -> tuple[Reader, int]:
    """Check format and version; return the reader (checksums required from version 2)."""
    r = Reader(f, source, checksums=False)
    fmt = r.attr("format", str)
    if fmt != FORMAT:
        r.check.fail("attrs/format", f"format = {FORMAT!r}", repr(fmt))
    version = r.attr("version", int)
    if version not in SUPPORTED_VERSIONS:
        r.check.fail("attrs/version", f"a supported version {SUPPORTED_VERSIONS}", version)
    if version == 1:
        warnings.warn(f"{source}: T13 version 1 carries no checksums: corruption cannot be "
                      "detected", UserWarning, stacklevel=3)
    r.checksums = version >= 2
    return r, version


def _parts_attr(r: Reader) -> None:
    parts = r.attr("parts", list, owner="pairs/dJt_parts", default=())
    if parts != PARTS:
        r.check.fail("pairs/dJt_parts.attrs/parts", f"the parts {', '.join(PARTS)}",
                     ", ".join(parts) or "none")


def _read(r: Reader, *, raw: bool, matrices: bool) -> tuple[T13, np.ndarray]:
    """Return the tape (pair matrices None unless ``matrices``; their stored shapes checked
    all the same) and records/t_s (checked against times/t_s once those are valid)."""
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
    miss = TapeMiss(r.attr("kind", str, owner="miss/nominal", default=""),
                    r.attr("t_s", float, owner="miss/nominal", default=math.nan),
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
    n_pairs, n_o = k.size, dims["n_o"]
    has_parts = r.has("pairs/dJt_parts")
    if has_parts:
        _parts_attr(r)
    if matrices:
        dj = r.symmetric("pairs/dJ", (n_pairs,), n_o)
        djt = r.symmetric("pairs/dJt", (n_pairs,), n_o)
        parts = r.symmetric("pairs/dJt_parts", (n_pairs, len(PARTS)), n_o) if has_parts else None
    else:
        r.stored_shape("pairs/dJ", (n_pairs,), n_o)
        r.stored_shape("pairs/dJt", (n_pairs,), n_o)
        if has_parts:
            r.stored_shape("pairs/dJt_parts", (n_pairs, len(PARTS)), n_o)
        dj = djt = parts = None
    pairs = TapePairs(k, r.read("pairs/station", "i"), r.read("pairs/n_obs", "i"), dj, djt,
                      parts)
    passes = TapePasses(r.read("passes/station", "i"), r.read("passes/t_start_s"),
                        r.read("passes/t_end_s"), r.read("passes/n_obs", "i"))
    tape_raw = None
    if raw and r.has("raw"):
        kinds = r.attr("kinds", list, owner="raw", default=())
        tape_raw = TapeRaw(kinds, *(r.read(f"raw/{name}", kind) for name, kind in (
            ("t_s", "f"), ("station", "i"), ("kind", "i"), ("record", "i"), ("segment", "i"),
            ("value", "f"), ("A", "f"), ("weight", "f"), ("m_white_var", "f"),
            ("m_bias_var", "f"), ("m_corr_var", "f"), ("m_tau_s", "f"))))
    provenance = {key: r.attr(key, str) for key in ("tapp_version", "git_commit",
                                                    "created_utc", *SCENARIO_PROVENANCE)
                  if r.has_attr(key)}
    tape = T13(r.attr("iden", str), epoch, dims["n_p"], parameters, stations, miss, records,
               pairs, passes, tape_raw, provenance)
    return tape, r.read("records/t_s")


def _check_record_times(source: str, record_times: np.ndarray, tape: T13) -> None:
    if not np.array_equal(record_times, tape.records.t_s):
        raise TapeError(f"{source}: records/t_s: expected the record times t_k = "
                        "times/t_s[1:]")


def read_t13(path: Path | str, *, raw: bool = True) -> T13:
    """Read and validate a whole T13 tape (every pair matrix unpacked in memory).

    For tapes too large for that, :func:`open_t13` reads the pair matrices record range by
    record range.

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

    Warns
    -----
    UserWarning
        For a version-1 tape (no checksums: corruption cannot be detected).
    """
    path = Path(path)
    with hdf5io.open_tape(path, "T13 tape") as f:
        r, _ = _reader(f, str(path))
        tape, record_times = _read(r, raw=raw, matrices=True)
    validate(tape, str(path))
    _check_record_times(str(path), record_times, tape)
    return tape


def _record_range(header: T13, k_first: int, k_last: int) -> tuple[int, int]:
    """Pair indices [lo, hi) of records k_first..k_last (pairs sorted by k)."""
    n_it = header.n_it
    if not (isinstance(k_first, int | np.integer) and isinstance(k_last, int | np.integer)
            and 1 <= k_first <= k_last <= n_it):
        raise InputError("pair_block", "k_first, k_last",
                         f"record indices 1 <= k_first <= k_last <= {n_it}", (k_first, k_last))
    k = header.pairs.k
    return (int(np.searchsorted(k, k_first, side="left")),
            int(np.searchsorted(k, k_last, side="right")))


def _header(tape: T13) -> T13:
    pairs = tape.pairs
    return replace(tape, pairs=TapePairs(pairs.k, pairs.station, pairs.n_obs, None, None, None),
                   raw=None)


class _PairSource:
    """What :class:`T13File` and :class:`MemoryPairs` share: the header, blocks of pairs."""

    __slots__ = ()

    header: T13

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True
                   ) -> PairBlock:  # pragma: no cover
        raise NotImplementedError

    def blocks(self, max_pairs: int | None = None) -> Iterator[PairBlock]:
        """Yield the pair blocks of consecutive record ranges covering records 1..n_it.

        Each block holds whole records and at most ``max_pairs`` pairs (default: packed
        matrices of about :data:`BLOCK_BYTES`), unless one record alone has more.
        """
        header = self.header
        if max_pairs is None:
            row_bytes = 8 * tr_size(header.n_o) * (2 + len(PARTS))
            max_pairs = max(1, BLOCK_BYTES // row_bytes)
        if max_pairs < 1:
            raise InputError("blocks", "max_pairs", "at least 1", max_pairs)
        per_record = np.bincount(header.pairs.k, minlength=header.n_it + 1)[1:]
        k = 1
        while k <= header.n_it:
            last, count = k, int(per_record[k - 1])
            while last < header.n_it and count + per_record[last] <= max_pairs:
                count += int(per_record[last])
                last += 1
            yield self.pair_block(k, last)
            k = last + 1


class T13File(_PairSource):
    """A T13 tape open for lazy reading of its pair matrices (from :func:`open_t13`).

    A context manager (``with open_t13(path) as tape:``); :meth:`close` closes the file.

    Attributes
    ----------
    header : T13
        Everything of the tape but the pair matrices (``header.pairs.dJ``, ``dJt`` and
        ``dJt_parts`` are None) and the raw rows (``header.raw`` is None), validated.
    path : Path
    version : int
        Version of the tape.
    packing : str
        Storage of the pair matrices on the tape ("TR" or "full").
    has_parts : bool
        Whether the tape has ``pairs/dJt_parts``.
    """

    __slots__ = ("_file", "_reader", "has_parts", "header", "packing", "path", "version")

    def __init__(self, path: Path | str):
        self.path = Path(path)
        self._file = hdf5io.open_tape(self.path, "T13 tape")
        try:
            self._reader, self.version = _reader(self._file, str(self.path))
            tape, record_times = _read(self._reader, raw=False, matrices=False)
            c = self._reader.check
            _validate_header(c, tape)
            _check_record_times(str(self.path), record_times, tape)
            self.packing = self._reader.packing("pairs/dJ")
            if self._reader.packing("pairs/dJt") != self.packing:
                c.fail("pairs/dJt.attrs/packing", f"the packing of pairs/dJ ({self.packing})")
            self.has_parts = self._reader.has("pairs/dJt_parts")
            if self.has_parts and self._reader.packing("pairs/dJt_parts") != self.packing:
                c.fail("pairs/dJt_parts.attrs/packing",
                       f"the packing of pairs/dJ ({self.packing})")
        except BaseException:
            self._file.close()
            raise
        self.header = tape

    def __enter__(self) -> T13File:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the file (:meth:`pair_block` then fails)."""
        self._file.close()

    def _matrices(self, name: str, lo: int, hi: int, lead: tuple[int, ...]) -> np.ndarray:
        """Read rows lo..hi-1 of a pair-matrix dataset, checked, packed TR (m, *lead, L)."""
        n_o = self.header.n_o
        c = self._reader.check
        stored = self._reader.read(name, selection=np.s_[lo:hi])
        c.finite(name, stored)
        if self.packing == "full":  # as read_t13 + validate: dJ, dJt symmetric; parts as stored
            full = stored.reshape(hi - lo, *lead, n_o, n_o)
            if not lead:
                c.symmetric(name, full, offset=lo)
            stored = frozen(pack_tr(full))
        if not lead:
            diag = stored[:, tr_diagonal(n_o)]
            if np.any(diag < 0):
                i, col = (int(v) for v in np.argwhere(diag < 0)[0])
                c.fail(name, "a non-negative diagonal (normal matrices)",
                       f"{diag[i, col]:.3g} in pair {i + lo}, row {col}")
        return stored

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True) -> PairBlock:
        """Return the pairs of records k_first..k_last (inclusive), read and checked now.

        ``parts=False`` skips ``pairs/dJt_parts`` (``dJt_parts`` is then None): TAPP III needs
        them only for its error budget, and they are 3/5 of the bytes.

        Only the rows of ``pairs/dJ``, ``pairs/dJt`` (and ``pairs/dJt_parts``) of those
        records are read (and their checksums checked); they are checked finite, with a
        non-negative diagonal, symmetric (a "full" tape, then packed TR) and the parts
        summing to dJt.

        Raises
        ------
        InputError
            Record indices outside 1 <= k_first <= k_last <= n_it.
        TapeError
            A check fails (naming the file and the dataset; pairs numbered from 0 over the
            whole tape).
        """
        if not self._file:
            raise InputError(str(self.path), "file", "an open T13 tape (pair_block after "
                                                     "close)")
        lo, hi = _record_range(self.header, k_first, k_last)
        pairs = self.header.pairs
        dj = self._matrices("pairs/dJ", lo, hi, ())
        djt = self._matrices("pairs/dJt", lo, hi, ())
        split = None
        if parts and self.has_parts:
            split = self._matrices("pairs/dJt_parts", lo, hi, (len(PARTS),))
            _check_parts_sum(self._reader.check,
                             scaled_difference_tr(split.sum(axis=1), djt), lo)
        return PairBlock(pairs.k[lo:hi], pairs.station[lo:hi], pairs.n_obs[lo:hi], dj, djt,
                         split)


def open_t13(path: Path | str) -> T13File:
    """Open a T13 tape for reading its pair matrices record range by record range.

    Everything but the pair matrices (and the raw rows) is read and validated now, as by
    :func:`read_t13`; the pair matrices are read and checked block by block
    (:meth:`T13File.pair_block`, :meth:`T13File.blocks`), so a tape of 20,000 pairs of
    n_o = 50 needs no more memory than one block.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        As :func:`read_t13`, for everything but the values of the pair matrices (their
        stored shapes are checked).

    Warns
    -----
    UserWarning
        For a version-1 tape.

    Examples
    --------
    >>> with open_t13("run.t13.h5") as tape:  # doctest: +SKIP
    ...     for block in tape.blocks():
    ...         ...
    """
    return T13File(path)


class MemoryPairs(_PairSource):
    """The interface of :class:`T13File` over a tape in memory (from :func:`memory_pairs`).

    Attributes
    ----------
    header : T13
        The tape without its pair matrices and raw rows.
    """

    __slots__ = ("_tape", "header")

    def __init__(self, tape: T13, source: str = "T13"):
        validate(tape, source)
        self._tape = tape
        self.header = _header(tape)

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True) -> PairBlock:
        """Return the pairs of records k_first..k_last (inclusive), matrices packed TR.

        Raises
        ------
        InputError
            Record indices outside 1 <= k_first <= k_last <= n_it.
        """
        lo, hi = _record_range(self.header, k_first, k_last)
        pairs = self._tape.pairs
        split = None if pairs.dJt_parts is None or not parts else frozen(
            pack_tr(pairs.dJt_parts[lo:hi]))
        return PairBlock(frozen(pairs.k[lo:hi], np.int64), frozen(pairs.station[lo:hi], np.int64),
                         frozen(pairs.n_obs[lo:hi], np.int64), frozen(pack_tr(pairs.dJ[lo:hi])),
                         frozen(pack_tr(pairs.dJt[lo:hi])), split)


def memory_pairs(tape: T13) -> MemoryPairs:
    """Return the :class:`T13File` interface (``header``, ``pair_block``, ``blocks``) over a
    tape in memory, validated now.

    Raises
    ------
    TapeError
        If the tape fails :func:`validate`.
    """
    return MemoryPairs(tape)


def summary(tape: T13, *, version: int = VERSION) -> dict:
    """Return a JSON-ready summary: dimensions, parameters, stations with their passes and
    observations, epoch times, records and provenance (``version``: of the tape read)."""
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
        "format": FORMAT, "version": version, "iden": tape.iden, "epoch_utc": tape.epoch.iso(3),
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
                    "utc": utc_at(tape.epoch, float(t))}
                   for i, t in zip(np.flatnonzero(rec.is_epoch), epoch_times, strict=True)],
        "input_times": int(np.count_nonzero(rec.is_input)),
        "miss": {"kind": tape.miss.kind, "t_s": tape.miss.t_s,
                 "names": list(tape.miss.name), "units": list(tape.miss.unit),
                 "nominal": tape.miss.nominal.tolist()},
        "provenance": {k: v for k, v in tape.provenance.items() if k != "scenario"},
    }


def utc_at(epoch: Epoch, t_s: float, decimals: int = 3) -> str:
    """Return the UTC date (ISO, ``decimals`` digits of seconds) ``t_s`` seconds after
    ``epoch``."""
    return Epoch(epoch.jd_whole, epoch.jd_fraction + t_s / SECONDS_PER_DAY).iso(decimals)

