"""The T13 tape's HDF5 form (through h5py): layout, atomic writer, validating readers.

The tape in memory (its types, notation and validation) is :mod:`tapp.io.tape.t13`;
DESIGN.md ("Tapes") fixes this form.

HDF5 layout, version 4 (every dataset has a ``units`` attribute and a Fletcher-32 checksum,
:mod:`tapp.io.tape.hdf5io`; the large datasets are compressed by :data:`COMPRESSION_OF_VERSION`):

==========================  =====================  ===========================================
path                        shape                  content
==========================  =====================  ===========================================
attrs                                              format="T13", version, iden, n_o, n_p, n_m,
                                                   n_ts, n_it, epoch (ISO UTC), epoch_jd_whole,
                                                   epoch_jd_fraction, time_scale, frame, center,
                                                   units, packing; provenance: tapp_version,
                                                   git_commit, created_utc, scenario (JSON),
                                                   scenario_source, earth_orientation, eop,
                                                   relativity, targeting, schedule
                                                   (t13.SCENARIO_PROVENANCE)
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
pairs/R, pairs/Rt           (n_pairs, L)           square-root information over (t_{k-1},
                                                   t_k] referred to t_j: upper-triangular
                                                   R, R̃ (diagonal >= 0) with RᵀR = AᵀWA,
                                                   R̃ᵀR̃ = AᵀWMWA; L = n_o(n_o+1)/2 ("TR",
                                                   upper triangle by rows) or n_o² ("full",
                                                   zero below the diagonal); attrs packing,
                                                   order (= n_o), form = "factor"
pairs/Rt_parts (optional)   (n_pairs, 3, L)        the factors of the white-noise, per-pass
                                                   bias and exponentially correlated parts of
                                                   AᵀWMWA (attr ``parts`` = white, bias,
                                                   correlated: the rows of ``pass_rows`` of
                                                   tapp.measurements.noise), whose Gram matrices
                                                   sum to R̃ᵀR̃
passes/station, t_start_s,  (n_passes,)            tracking passes (before any split at T13
t_end_s, n_obs                                     times)
editing/ (optional)                                what the schedule asked for and what each
                                                   rule removed (tapp.io.tape.t13.TapeEditing):
editing/rule                (n_rules,) str         the rules, in the order they apply
editing/scheduled_obs       (n_ts,) int            scalar observations on the schedule's
                                                   sample times
editing/removed_obs,        (n_ts, n_rules) int    observations, passes removed by each rule
removed_passes                                     (each observation under the first rule that
                                                   removed it: scheduled_obs = kept (sum of
                                                   pairs/n_obs) + sum of removed_obs)
editing/added_passes        (n_ts,) int            passes added by splitting passes longer
                                                   than the scenario's max_pass_s
stochastic/ (optional)                             the parameters of kind "stochastic" (tapp.
                                                   estimation.gauss_markov): attrs frame,
                                                   components, sigma_km_s2, tau_s
stochastic/boundaries_s     (K+1,) float           interval boundaries, s
manoeuvres/ (optional)                             the burns whose execution errors are the
                                                   parameters of kind "execution" (tapp.
                                                   dynamics.manoeuvres), ascending in time:
manoeuvres/name, kind, axes (n_b,) str             name, "impulsive" or "finite", "inertial",
                                                   "ric" or "vnb"
manoeuvres/t_start_s,       (n_b,) float           time (ignition), s; duration (0: impulsive)
duration_s
manoeuvres/vector           (n_b, 3) float         Δv (km/s, impulsive) or the thrust's unit
                                                   direction (finite), in the burn's axes
manoeuvres/thrust_N,        (n_b,) float           thrust (N), mass at ignition (kg), mass flow
mass_kg, mass_flow_kg_s                            (kg/s) of a finite burn; 0 for impulsive
manoeuvres/sigma            (n_b, 4) float         Gates' σ₁..σ₄ (1, km/s, rad, km/s: tapp.
                                                   dynamics.gates)
raw/... (optional)          (N, ...)               one row per scalar observation: t_s,
                                                   station, kind (code into attr ``kinds``),
                                                   record, segment, value, A (N, n_o) referred
                                                   to t_j of the record, weight = 1/σ²,
                                                   m_white_var, m_bias_var, m_corr_var,
                                                   m_tau_s (the real-world M of each segment,
                                                   :func:`tapp.measurements.noise.covariance_block`)
==========================  =====================  ===========================================

Units of the factors: entry (r, b) in 1/u_b with u the parameters' units (of the normal
matrices RᵀR: 1/(u_a u_b)); U and B entries in (unit of row)/(unit of column). Every dataset is
chunked (whole rows) with a Fletcher-32 checksum, text (of datasets and attributes: h5py reads
text attributes as bytes) is fixed-length UTF-8, and the large datasets (``records/U``, the
pair factors and ``raw/``) are LZ4-compressed (HDF5 filter 32004: plain h5py reads them after
``import hdf5plugin``; the others need no filter).

Version 3 is version 4 with its large datasets gzip-compressed (after a byte shuffle), which
any HDF5 library reads, at a tenth of the speed.

Versions 1 and 2 (still read, with a ``UserWarning`` that says their precision is limited)
carry the normal matrices themselves, ``pairs/dJ`` = AᵀWA and ``pairs/dJt`` = AᵀWMWA (packed
the same way, symmetric), and version 2 ``pairs/dJt_parts``; the readers turn each into a
factor (:func:`tapp.io.tape.t13.factor_normal_matrices`). Version 1 has no checksums and no parts,
and variable-length text.

The writer writes to a temporary file beside the target and renames it: no half-written tape.
The readers reject a wrong format or version, a missing dataset, a wrong shape, a non-finite
value or one beyond :data:`tapp.io.tape.checks.MAX_MAGNITUDE`, a factor with a negative diagonal
(or, "full", non-zero below it; a normal matrix of version 1 or 2 that is not symmetric or
has a negative diagonal), parts whose Gram matrices do not sum to R̃ᵀR̃, an inconsistent epoch
index and a checksum mismatch, with a :class:`~tapp.errors.TapeError` naming the file and the
dataset. :func:`read_t13` loads the
whole tape; :func:`open_t13` loads everything but the pair factors and reads those record
range by record range (:meth:`T13File.pair_block`), for tapes too large to unpack at once;
:func:`tapp.io.tape.t13.memory_pairs` offers the same interface over a tape in memory.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from tapp.dynamics.gates import GatesErrors, GatesRangeError
from tapp.dynamics.manoeuvres import AXES, BURN_KINDS, Burn, FiniteBurn, ImpulsiveBurn
from tapp.errors import InputError, TapeError
from tapp.estimation.gauss_markov import StochasticAccelerations
from tapp.frames.time import Epoch
from tapp.io.atomic import atomic_write
from tapp.io.tape import hdf5io
from tapp.io.tape.checks import PACKINGS, frozen
from tapp.io.tape.hdf5io import Reader
from tapp.io.tape.packing import pack_tr, scaled_difference, unpack_tr
from tapp.io.tape.t13 import (
    FORMAT,
    INFO_COLUMNS,
    NORMAL_MATRIX_VERSIONS,
    PARTS_TOL,
    SCENARIO_PROVENANCE,
    SUPPORTED_VERSIONS,
    T13,
    UNITS_NOTE,
    VERSION,
    PairBlock,
    TapeEditing,
    TapeMiss,
    TapePairs,
    TapeParameters,
    TapePasses,
    TapeRaw,
    TapeRecords,
    TapeStations,
    _PairSource,
    _record_range,
    _validate_header,
    check_factors,
    check_parts_sum,
    factor_normal_matrices,
    frame_of,
    packed_column_norms2,
    packed_column_sums,
    validate,
)
from tapp.measurements.noise import PARTS

__all__ = ["COMPRESSION_OF_VERSION", "T13File", "open_t13", "read_t13", "t13_file_writer",
           "write_t13"]

#: The compression of the large datasets (a key of :data:`tapp.io.tape.hdf5io.COMPRESSION`)
#: by the version whose layout is written.
COMPRESSION_OF_VERSION = {1: "gzip", 2: "gzip", 3: "gzip", 4: "lz4"}


# ---------------------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------------------


def _write(f: h5py.File, tape: T13, packing: str, version: int = VERSION) -> None:
    """Write ``tape`` into the open file ``f``.

    ``version`` 1, 2 or 3 writes the layout of that version (1 and 2: the normal matrices
    RᵀR of the factors, version 1 without checksums and parts; 3: gzip for LZ4): kept so
    that the readers of those versions stay tested.
    """
    cs = version >= 2
    compression = COMPRESSION_OF_VERSION[version]

    def strings(group: h5py.Group, name: str, values, units: str = "") -> None:
        hdf5io.write_strings(group, name, values, units, checksums=cs)

    def numbers(group: h5py.Group, name: str, values, units: str, *, big: bool = False
                ) -> h5py.Dataset:
        return hdf5io.write_numbers(group, name, values, units, big=big, checksums=cs,
                                    compression=compression)

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
    names = _pair_datasets(version)
    if version in NORMAL_MATRIX_VERSIONS:
        units = "1/(u_a u_b), u = parameters/unit"
        matrices = (pairs.dJ, pairs.dJt,
                    None if pairs.Rt_parts is None else gram_stack(pairs.Rt_parts))
        form = "symmetric"
    else:
        units = "1/u_b, u = parameters/unit"
        matrices = (pairs.R, pairs.Rt, pairs.Rt_parts)
        form = "factor"
    for name, m in zip(names[:2], matrices[:2], strict=True):
        hdf5io.write_packed(g, name.removeprefix("pairs/"), m, units, packing, form, big=True,
                            checksums=cs, compression=compression)
    if cs and matrices[2] is not None:
        ds = hdf5io.write_packed(g, names[2].removeprefix("pairs/"), matrices[2], units,
                                 packing, form, big=True, compression=compression)
        hdf5io.write_attrs(ds, {"parts": list(PARTS)})

    ps = tape.passes
    g = f.create_group("passes")
    numbers(g, "station", ps.station, "")
    numbers(g, "t_start_s", ps.t_start_s, "s")
    numbers(g, "t_end_s", ps.t_end_s, "s")
    numbers(g, "n_obs", ps.n_obs, "")

    if tape.editing is not None:
        ed = tape.editing
        g = f.create_group("editing")
        strings(g, "rule", ed.rule)
        numbers(g, "scheduled_obs", ed.scheduled_obs, "scalar observations")
        numbers(g, "removed_obs", ed.removed_obs, "scalar observations")
        numbers(g, "removed_passes", ed.removed_passes, "passes")
        numbers(g, "added_passes", ed.added_passes, "passes")

    if tape.stochastic is not None:
        sto = tape.stochastic
        g = f.create_group("stochastic")
        hdf5io.write_attrs(g, {"frame": sto.frame, "components": list(sto.components),
                               "sigma_km_s2": sto.sigma_km_s2, "tau_s": sto.tau_s},
                           checksums=cs)
        numbers(g, "boundaries_s", np.asarray(sto.boundaries_s), "s")

    if tape.manoeuvres:
        _write_manoeuvres(f.create_group("manoeuvres"), tape.manoeuvres, strings, numbers)

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

    For committing several outputs together (:func:`tapp.io.atomic.atomic_write` of each);
    :func:`write_t13` is ``atomic_write(path, t13_file_writer(tape, packing))``.

    Parameters
    ----------
    tape : T13
    packing : "TR" (upper triangle by rows, the default) or "full" (n_o² per matrix).
    source : name of the tape in the messages of :func:`tapp.io.tape.t13.validate`.

    Raises
    ------
    TapeError
        If the tape fails :func:`tapp.io.tape.t13.validate`.
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
        If the tape fails :func:`tapp.io.tape.t13.validate`.
    InputError
        For an unknown packing.
    """
    path = Path(path)
    return atomic_write(path, t13_file_writer(tape, packing, source=str(path)))


# ---------------------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------------------


def _pair_datasets(version: int) -> tuple[str, str, str]:
    """The pair datasets of a version: (AᵀWA, AᵀWMWA, its parts) as factors or matrices."""
    if version in NORMAL_MATRIX_VERSIONS:
        return "pairs/dJ", "pairs/dJt", "pairs/dJt_parts"
    return "pairs/R", "pairs/Rt", "pairs/Rt_parts"


def gram_stack(factors: np.ndarray) -> np.ndarray:
    """KᵀK of each factor of a stack (..., m, n) -> (..., n, n)."""
    return np.swapaxes(factors, -1, -2) @ factors


def _reader(f: h5py.File, source: str) -> tuple[Reader, int]:
    """Check format and version; return the reader (checksums required from version 2)."""
    r = Reader(f, source, checksums=False)
    version = r.format_version(FORMAT, SUPPORTED_VERSIONS)
    if version == 1:
        warnings.warn(f"{source}: T13 version 1 carries no checksums: corruption cannot be "
                      "detected", UserWarning, stacklevel=3)
    if version in NORMAL_MATRIX_VERSIONS:
        warnings.warn(f"{source}: T13 version {version} carries normal matrices, not "
                      "square-root information: its factors are formed from them and hold "
                      "only the digits they kept (about 16 - 2 log10 of the condition number "
                      f"of the data); simulate it again for version {VERSION}", UserWarning,
                      stacklevel=3)
    r.checksums = version >= 2
    return r, version


def _parts_attr(r: Reader, name: str) -> None:
    parts = r.attr("parts", list, owner=name, default=())
    if parts != PARTS:
        r.check.fail(f"{name}.attrs/parts", f"the parts {', '.join(PARTS)}",
                     ", ".join(parts) or "none")


def _factors_of_matrices(c, names: tuple[str, str, str], dj, djt, parts):
    """Version 1, 2: check the normal matrices as the tape had them, then factor them."""
    for name, m in zip(names[:2], (dj, djt), strict=True):
        c.symmetric(name, m)
    if parts is not None:
        _check_legacy_parts(c, names[2], parts, djt, 0)
    return tuple(None if m is None else factor_normal_matrices(m, c, name)
                 for name, m in zip(names, (dj, djt, parts), strict=True))


def _check_legacy_parts(c, name: str, parts: np.ndarray, total: np.ndarray, offset: int
                        ) -> None:
    """The parts of a version-2 tape summing to its AᵀWMWA, as that version was checked."""
    defect = scaled_difference(parts.sum(axis=1), total)
    if np.any(defect > PARTS_TOL):
        first = int(np.argmax(defect > PARTS_TOL))
        c.fail(name, f"parts summing to pairs/dJt (relative difference <= {PARTS_TOL:g})",
               f"{defect[first]:.3g} in pair {first + offset}")


def _read(r: Reader, version: int, *, raw: bool, matrices: bool) -> tuple[T13, np.ndarray]:
    """Return the tape (pair factors None unless ``matrices``; their stored shapes checked
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
    names = _pair_datasets(version)
    has_parts = r.has(names[2])
    if has_parts:
        _parts_attr(r, names[2])
    leads = ((n_pairs,), (n_pairs,), (n_pairs, len(PARTS)))
    factors = (None, None, None)
    if matrices and version in NORMAL_MATRIX_VERSIONS:
        stored = [r.symmetric(name, lead, n_o) if i < 2 or has_parts else None
                  for i, (name, lead) in enumerate(zip(names, leads, strict=True))]
        factors = _factors_of_matrices(r.check, names, *stored)
    elif matrices:
        factors = tuple(r.triangular(name, lead, n_o) if i < 2 or has_parts else None
                        for i, (name, lead) in enumerate(zip(names, leads, strict=True)))
    else:
        for i, (name, lead) in enumerate(zip(names, leads, strict=True)):
            if i < 2 or has_parts:
                r.stored_shape(name, lead, n_o)
    pairs = TapePairs(k, r.read("pairs/station", "i"), r.read("pairs/n_obs", "i"), *factors)
    passes = TapePasses(r.read("passes/station", "i"), r.read("passes/t_start_s"),
                        r.read("passes/t_end_s"), r.read("passes/n_obs", "i"))
    editing = None
    if r.has("editing"):
        editing = TapeEditing(r.strings("editing/rule"),
                              *(r.read(f"editing/{name}", "i") for name in (
                                  "scheduled_obs", "removed_obs", "removed_passes",
                                  "added_passes")))
    stochastic = None
    if r.has("stochastic"):
        stochastic = StochasticAccelerations(
            r.attr("frame", str, owner="stochastic"),
            tuple(r.attr("components", list, owner="stochastic")),
            tuple(float(t) for t in r.read("stochastic/boundaries_s")),
            r.attr("sigma_km_s2", float, owner="stochastic"),
            r.attr("tau_s", float, owner="stochastic"))
    manoeuvres = _read_manoeuvres(r) if r.has("manoeuvres") else ()
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
               pairs, passes, tape_raw, provenance, editing, stochastic, manoeuvres)
    return tape, r.read("records/t_s")


#: The numbers of a burn on the tape beside its name, kind, axes, vector and σ's, with their
#: units (those an impulsive burn has not are 0 on the tape).
_BURN_NUMBERS = (("t_start_s", "s"), ("duration_s", "s"), ("thrust_N", "N"), ("mass_kg", "kg"),
                 ("mass_flow_kg_s", "kg/s"))


def _write_manoeuvres(g: h5py.Group, burns: tuple[Burn, ...], strings, numbers) -> None:
    """The ``manoeuvres/`` group (module docstring)."""
    for name in ("name", "kind", "axes"):
        strings(g, name, [getattr(b, name) for b in burns])
    for name, units in _BURN_NUMBERS:
        numbers(g, name, np.array([getattr(b, name, 0.0) for b in burns]), units)
    numbers(g, "vector", np.array([b.dv_km_s if b.kind == "impulsive" else b.direction
                                   for b in burns]), "km/s (impulsive) or 1 (finite), in the "
            "burn's axes")
    numbers(g, "sigma", np.array([b.errors.sources for b in burns]), "1, km/s, rad, km/s")


def _read_manoeuvres(r: Reader) -> tuple[Burn, ...]:
    """The burns of the ``manoeuvres/`` group, checked as the scenario's were."""
    names, kinds, axes = (r.strings(f"manoeuvres/{n}") for n in ("name", "kind", "axes"))
    n_b = len(names)
    values = {name: r.read(f"manoeuvres/{name}") for name, *_ in _BURN_NUMBERS}
    vector, sigma = r.read("manoeuvres/vector"), r.read("manoeuvres/sigma")
    for name, a, shape in (("kind", kinds, n_b), ("axes", axes, n_b)):
        if len(a) != shape:
            r.check.fail(f"manoeuvres/{name}", f"{n_b} entries", len(a))
    for name, a in values.items():
        r.check.shape(f"manoeuvres/{name}", a, (n_b,))
        r.check.finite(f"manoeuvres/{name}", a)
    r.check.shape("manoeuvres/vector", vector, (n_b, 3))
    r.check.finite("manoeuvres/vector", vector)
    r.check.shape("manoeuvres/sigma", sigma, (n_b, 4))
    out = []
    for i in range(n_b):
        if kinds[i] not in BURN_KINDS:
            r.check.fail("manoeuvres/kind", f"one of {', '.join(BURN_KINDS)}", kinds[i])
        if axes[i] not in AXES:
            r.check.fail("manoeuvres/axes", f"one of {', '.join(AXES)}", axes[i])
        try:
            errors = GatesErrors(*(float(x) for x in sigma[i]))
        except GatesRangeError as exc:
            r.check.fail("manoeuvres/sigma", exc.expected, exc.got)
        common = {"name": names[i], "axes": axes[i], "errors": errors}
        v = tuple(float(x) for x in vector[i])
        if kinds[i] == "impulsive":
            out.append(ImpulsiveBurn(**common, t_s=float(values["t_start_s"][i]), dv_km_s=v))
        else:
            if min(values[n][i] for n in ("duration_s", "thrust_N", "mass_kg",
                                          "mass_flow_kg_s")) <= 0 or \
                    values["mass_flow_kg_s"][i] * values["duration_s"][i] >= values["mass_kg"][i]:
                r.check.fail("manoeuvres/duration_s", "a finite burn's positive duration, "
                             "thrust, mass and mass flow, mass left at cut-off", names[i])
            out.append(FiniteBurn(**common, direction=v, **{
                name: float(values[name][i]) for name, *_ in _BURN_NUMBERS}))
    return tuple(out)


def _check_record_times(source: str, record_times: np.ndarray, tape: T13) -> None:
    if not np.array_equal(record_times, tape.records.t_s):
        raise TapeError(f"{source}: records/t_s: expected the record times t_k = "
                        "times/t_s[1:]")


def read_t13(path: Path | str, *, raw: bool = True) -> T13:
    """Read and validate a whole T13 tape (every pair factor unpacked in memory).

    For tapes too large for that, :func:`open_t13` reads the pair factors record range by
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
        For a version-1 or -2 tape (normal matrices, whose factors hold only the digits they
        kept; version 1 without checksums: corruption cannot be detected).
    """
    path = Path(path)
    with hdf5io.open_tape(path, "T13 tape") as f:
        r, version = _reader(f, str(path))
        tape, record_times = _read(r, version, raw=raw, matrices=True)
    validate(tape, str(path))
    _check_record_times(str(path), record_times, tape)
    return tape



class T13File(_PairSource):
    """A T13 tape open for lazy reading of its pair factors (from :func:`open_t13`).

    A context manager (``with open_t13(path) as tape:``); :meth:`close` closes the file.

    Attributes
    ----------
    header : T13
        Everything of the tape but the pair factors (``header.pairs.R``, ``Rt`` and
        ``Rt_parts`` are None) and the raw rows (``header.raw`` is None), validated.
    path : Path
    version : int
        Version of the tape.
    names : the pair datasets of its version (factors, or normal matrices before version 3).
    packing : str
        Storage of the pair datasets on the tape ("TR" or "full").
    has_parts : bool
        Whether the tape has the parts (``pairs/Rt_parts``, ``pairs/dJt_parts``).
    """

    __slots__ = ("_file", "_reader", "has_parts", "header", "names", "packing", "path",
                 "version")

    def __init__(self, path: Path | str):
        self.path = Path(path)
        self._file = hdf5io.open_tape(self.path, "T13 tape")
        try:
            self._reader, self.version = _reader(self._file, str(self.path))
            tape, record_times = _read(self._reader, self.version, raw=False, matrices=False)
            c = self._reader.check
            _validate_header(c, tape)
            _check_record_times(str(self.path), record_times, tape)
            self.names = _pair_datasets(self.version)
            self.packing = self._reader.packing(self.names[0])
            self.has_parts = self._reader.has(self.names[2])
            for name in self.names[1:] if self.has_parts else self.names[1:2]:
                if self._reader.packing(name) != self.packing:
                    c.fail(f"{name}.attrs/packing",
                           f"the packing of {self.names[0]} ({self.packing})")
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

    def _stored(self, name: str, lo: int, hi: int, lead: tuple[int, ...]) -> np.ndarray:
        """Rows lo..hi-1 of a pair dataset, finite, as full matrices (m, *lead, n_o, n_o) for
        "full" packing or packed TR (m, *lead, L)."""
        n_o = self.header.n_o
        stored = self._reader.read(name, selection=np.s_[lo:hi])
        self._reader.check.finite(name, stored)
        if self.packing == "full":
            return stored.reshape(hi - lo, *lead, n_o, n_o)
        return stored

    def _factors(self, name: str, lo: int, hi: int, lead: tuple[int, ...]) -> np.ndarray:
        """Version 3: read and check factors, packed TR (m, *lead, L)."""
        n_o = self.header.n_o
        stored = self._stored(name, lo, hi, lead)
        lower = None
        if self.packing == "full":
            lower = np.tril(stored, -1)
            stored = frozen(pack_tr(stored))
        check_factors(self._reader.check, name, stored, n_o, lower=lower, offset=lo)
        return stored

    def _legacy(self, lo: int, hi: int, parts: bool) -> tuple:
        """Versions 1, 2: read the normal matrices, check them as their version was checked,
        and return their factors packed TR."""
        n_o = self.header.n_o
        full = []
        for name, lead in zip(self.names, ((), (), (len(PARTS),)), strict=True):
            if lead and not parts:
                full.append(None)
                continue
            stored = self._stored(name, lo, hi, lead)
            full.append(stored if self.packing == "full" else unpack_tr(stored, n_o))
        c = self._reader.check
        for name, m in zip(self.names[:2], full[:2], strict=True):
            c.symmetric(name, m, offset=lo)
        if full[2] is not None:
            _check_legacy_parts(c, self.names[2], full[2], full[1], lo)
        return tuple(None if m is None else frozen(pack_tr(factor_normal_matrices(m, c, name,
                                                                                  lo)))
                     for name, m in zip(self.names, full, strict=True))

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True) -> PairBlock:
        """Return the pairs of records k_first..k_last (inclusive), read and checked now.

        ``parts=False`` skips ``pairs/Rt_parts`` (``Rt_parts`` is then None): TAPP III needs
        them only for its error budget, and they are 3/5 of the bytes.

        Only the rows of ``pairs/R``, ``pairs/Rt`` (and ``pairs/Rt_parts``) of those records
        are read (and their checksums checked); they are checked finite, upper triangular
        with a non-negative diagonal, and the parts' Gram matrices summing to R̃ᵀR̃ on the
        diagonal. A version-1 or -2 tape's normal matrices are checked as that version was,
        then factored (:func:`tapp.io.tape.t13.factor_normal_matrices`).

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
        parts = parts and self.has_parts
        if self.version in NORMAL_MATRIX_VERSIONS:
            r, rt, split = self._legacy(lo, hi, parts)
        else:
            r, rt = (self._factors(name, lo, hi, ()) for name in self.names[:2])
            split = None
            if parts:
                split = self._factors(self.names[2], lo, hi, (len(PARTS),))
                n_o = self.header.n_o
                # the parts' squares summed first: one pass over the columns, not three
                parts2 = packed_column_sums(np.einsum("mpl,mpl->ml", split, split), n_o)
                check_parts_sum(self._reader.check, parts2, packed_column_norms2(rt, n_o), lo)
        return PairBlock(pairs.k[lo:hi], pairs.station[lo:hi], pairs.n_obs[lo:hi], r, rt,
                         split)


def open_t13(path: Path | str) -> T13File:
    """Open a T13 tape for reading its pair factors record range by record range.

    Everything but the pair factors (and the raw rows) is read and validated now, as by
    :func:`read_t13`; the pair factors are read and checked block by block
    (:meth:`T13File.pair_block`, :meth:`T13File.blocks`), so a tape of 20,000 pairs of
    n_o = 50 needs no more memory than one block.

    Raises
    ------
    InputError
        If the file does not exist.
    TapeError
        As :func:`read_t13`, for everything but the values of the pair factors (their
        stored shapes are checked).

    Warns
    -----
    UserWarning
        For a version-1 or -2 tape (normal matrices; version 1 without checksums).

    Examples
    --------
    >>> with open_t13("run.t13.h5") as tape:  # doctest: +SKIP
    ...     for block in tape.blocks():
    ...         ...
    """
    return T13File(path)
