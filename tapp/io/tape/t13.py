"""The T13 tape (TAPP I -> TAPP III) in memory: types, validation, pair blocks, summary.

Seed TAPP III §4.1 fixes the content; DESIGN.md ("Tapes") fixes the HDF5 form. Notation of
the seed: n_o TAPP I parameters x = [p; q] (p: the n_p orbit parameters at the epoch, q: the
constants and biases), n_m miss parameters, n_ts tracking stations, n_it records; T13 times
t_0 < t_1 < ... < t_{n_it} (the union of the input times and the epoch times, t_0 = 0 the
injection); record k covers (t_{k-1}, t_k] and is referred to the epoch t_j, where j either
stays the same from one record to the next or changes to k-1.

A tape (:class:`T13`) holds the n_o parameters with their nominal values at t_0
(:class:`TapeParameters`), the n_ts stations (:class:`TapeStations`), the n_m miss parameters
and B = ∂m/∂x at injection (:class:`TapeMiss`), the T13 times and, per record, its epoch
index j, the state at t_k and U = ∂p(t_k)/∂x(t_j) (:class:`TapeRecords`), the (record,
station) pairs with data and their square-root information over (t_{k-1}, t_k] referred to
t_j: upper-triangular factors R, R̃ with RᵀR = AᵀWA and R̃ᵀR̃ = AᵀWMWA, R̃ optionally split
into the factors of its white-noise, per-pass bias and exponentially correlated parts
(:class:`TapePairs`; the normal matrices are their Gram matrices, :attr:`TapePairs.dJ`), the
tracking passes (:class:`TapePasses`), optionally what the tracking schedule asked for and
what each rule that removes data removed, per station (:class:`TapeEditing`), optionally the
definition of the stochastic accelerations among the parameters (kind "stochastic": frame,
components, interval boundaries, σ, τ; :class:`tapp.estimation.gauss_markov.
StochasticAccelerations`, from which TAPP III builds their a priori), optionally the burns
whose execution errors are parameters (kind "execution": :mod:`tapp.dynamics.manoeuvres`,
with Gates' σ's, from which TAPP III builds their a priori), and, optionally, one row per
scalar observation (:class:`TapeRaw`). Units: factor entry (r, b) in 1/u_b with
u the parameters' units (normal matrices 1/(u_a u_b)); U and B entries in (unit of row)/(unit
of column).

Versions 3 and 4 carry the factors (4 differs from 3 only in how the HDF5 form compresses
them). Versions 1 and 2 carried the normal matrices themselves; their readers turn each into
a factor (:func:`factor_normal_matrices`), which can keep only the digits the formed matrix
kept (about 16 − 2 log₁₀ of the condition number of the data).

:func:`validate` checks the dimensions and invariants of a tape; :class:`PairBlock` holds the
pairs of a record range, factors packed TR (the upper triangle by rows); :func:`memory_pairs`
serves a tape in memory record range by record range, through the interface of the lazy file
reader
:class:`tapp.io.tape.t13_hdf5.T13File`; :func:`summary` summarises a tape. NumPy only: the HDF5
layout, the writer and the readers are in :mod:`tapp.io.tape.t13_hdf5`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field, fields

import numpy as np

from tapp.dynamics.empirical import COMPONENTS
from tapp.dynamics.manoeuvres import KIND as EXECUTION
from tapp.dynamics.manoeuvres import Burn
from tapp.errors import InputError
from tapp.estimation.factors import psd_factor
from tapp.estimation.gauss_markov import FRAMES, KIND, UNIT, StochasticAccelerations
from tapp.frames.orientation import INERTIAL_FRAME
from tapp.frames.time import Epoch
from tapp.io.tape.checks import PACKINGS, SYMMETRY_TOL, Checker, frozen
from tapp.io.tape.layout import T13_LAYOUT, rows, sourced
from tapp.io.tape.packing import pack_tr, scaled_difference, tr_diagonal, tr_rows, tr_size
from tapp.measurements.noise import PARTS

#: Provenance attributes the simulator stamps: the scenario (JSON) and its file, the Earth
#: orientation model ("iau2006" or "gmst"), the EOP source of the run and, when SEARCH
#: retargeted the injection (a ``[targeting]`` table), its record (JSON: aim point, achieved
#: values, first and targeted injection velocities, cases; empty otherwise) and the pass
#: schedule it tracked by (``FILE (sha256 HEX)``; empty by visibility).
SCENARIO_PROVENANCE = ("scenario", "scenario_source", "earth_orientation", "eop", "relativity",
                       "targeting", "schedule")


def frame_of(provenance: dict[str, str]) -> str:
    """The inertial frame of a run: GCRS under iau2006, EME2000 under gmst (or unstated)."""
    return INERTIAL_FRAME.get(provenance.get("earth_orientation", "gmst"), "EME2000")

FORMAT = "T13"
VERSION = 4
SUPPORTED_VERSIONS = (1, 2, 3, 4)
#: Versions that carry normal matrices, not factors (read with a warning).
NORMAL_MATRIX_VERSIONS = (1, 2)
#: Largest relative difference between the diagonal of R̃ᵀR̃ and the sum of its parts'
#: (column norms squared) accepted: the rounding of a QR of a few thousand rows.
PARTS_TOL = 1e-10
#: Names of the state in ``records/info`` (km, km/s, EME2000).
INFO_COLUMNS = ("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s")
UNITS_NOTE = ("km, km/s, s, rad; normal matrices in 1/(u_a u_b), partials in (row unit)/"
              "(column unit), with u the units of parameters/unit and miss/unit")
#: Budget of one block of ``blocks()`` (:class:`MemoryPairs`,
#: :class:`tapp.io.tape.t13_hdf5.T13File`; bytes of packed matrices).
BLOCK_BYTES = 1 << 25

__all__ = ["FORMAT", "INFO_COLUMNS", "NORMAL_MATRIX_VERSIONS", "PACKINGS", "PARTS_TOL",
           "SUPPORTED_VERSIONS", "SYMMETRY_TOL", "T13", "T13Header", "VERSION", "MemoryPairs",
           "PairBlock",
           "LEGACY_PSD_TOL", "TapeEditing", "TapeMiss", "TapePairs", "TapeParameters",
           "TapePasses", "TapeRaw", "TapeRecords", "TapeStations", "check_factors",
           "check_parts_sum", "column_norms2", "factor_normal_matrices", "memory_pairs",
           "packed_column_norms2", "packed_column_sums", "summary", "validate"]

@dataclass(frozen=True, slots=True, eq=False)
class TapeParameters:
    """The n_o TAPP I parameters x = [p; q]: names (with units), units, kinds, nominal values.

    ``kind`` is "orbit" (p), "dynamic" (model constants), "location", "bias", "troposphere"
    or "ionosphere" (station parameters, with ``station`` their station number; 0 otherwise:
    the media's are a station's zenith dry and wet delays, km, and zenith TEC, TECU:
    :mod:`tapp.measurements.media`), "stochastic" (the accelerations of :attr:`T13.stochastic`),
    "execution" (the execution errors of the burns of :attr:`T13.manoeuvres`), "eop" (constant
    offsets of UT1 − UTC and the pole coordinates from the IERS values, ``eop.ut1_s`` s,
    ``eop.xp_rad``, ``eop.yp_rad`` rad, station 0) or "quasar" (a ΔDOR baseline's quasar
    position error, ``A-B.quasar_ra_rad``, ``A-B.quasar_dec_rad``, station: the baseline's
    entry number). The kind is free text on the tape: a tape of any of these kinds reads.
    """

    name: tuple[str, ...]
    unit: tuple[str, ...]
    kind: tuple[str, ...]
    station: np.ndarray
    nominal: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeStations:
    """The n_ts tracking stations: numbers s = 1..n_ts, names, geodetic positions (deg, km).

    ΔDOR baselines (:mod:`tapp.tracking.ddor`) follow the stations as entries of their own
    (name ``A-B``, observables ``ddor``, the position and mask of A), so that time-station
    flags act on a baseline's ΔDOR apart from either station's data.
    """

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
    """(record, station) pairs with data and their square-root information, full in memory.

    Attributes
    ----------
    k, station, n_obs : (n_pairs,) int record index, station number, observations; sorted by
        (k, station).
    R, Rt : (n_pairs, n_o, n_o) upper-triangular factors, diagonal >= 0, with RᵀR = AᵀWA and
        R̃ᵀR̃ = AᵀWMWA, 1/u_b; None in the header of a lazily read tape
        (:attr:`tapp.io.tape.t13_hdf5.T13File.header`).
    Rt_parts : (n_pairs, 3, n_o, n_o) the factors of the parts of AᵀWMWA (white, bias,
        correlated: :data:`tapp.measurements.noise.PARTS`), their Gram matrices summing to
        R̃ᵀR̃; or None (not on the tape, or a header).
    """

    k: np.ndarray
    station: np.ndarray
    n_obs: np.ndarray
    R: np.ndarray | None
    Rt: np.ndarray | None
    Rt_parts: np.ndarray | None = None

    @property
    def dJ(self) -> np.ndarray:
        """AᵀWA = RᵀR, (n_pairs, n_o, n_o), 1/(u_a u_b)."""
        return np.swapaxes(self.R, -1, -2) @ self.R

    @property
    def dJt(self) -> np.ndarray:
        """AᵀWMWA = R̃ᵀR̃, (n_pairs, n_o, n_o), 1/(u_a u_b)."""
        return np.swapaxes(self.Rt, -1, -2) @ self.Rt

    @property
    def dJt_parts(self) -> np.ndarray | None:
        """The parts' Gram matrices (n_pairs, 3, n_o, n_o), 1/(u_a u_b), summing to AᵀWMWA;
        None without parts."""
        parts = self.Rt_parts
        return None if parts is None else np.swapaxes(parts, -1, -2) @ parts


@dataclass(frozen=True, slots=True, eq=False)
class TapePasses:
    """Tracking passes: station number, first and last observation time (s), observations."""

    station: np.ndarray
    t_start_s: np.ndarray
    t_end_s: np.ndarray
    n_obs: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class TapeEditing:
    """What the tracking schedule asked of each station and what each rule removed.

    Counts are scalar observations (a sample of a station that measures m observables is m
    observations) and passes. Every scheduled observation is either on the tape (in
    ``pairs/n_obs``) or counted under exactly one rule, the first that removed it:

    .. math:: \\text{scheduled}_s = \\sum_k n_{obs}(k, s) + \\sum_r \\text{removed}_{s,r}

    Attributes
    ----------
    rule : (n_rules,) names of the rules, in the order they apply (the simulator's: TAPP I's
        are in :data:`tapp.tracking.simulate.EDITING_RULES`).
    scheduled_obs : (n_ts,) int observations on the schedule's sample times.
    removed_obs : (n_ts, n_rules) int observations removed by each rule.
    removed_passes : (n_ts, n_rules) int passes removed whole by each rule (0 for a rule that
        acts on samples before passes are formed).
    added_passes : (n_ts,) int passes added by splitting passes longer than the longest pass
        (no observation removed).
    """

    rule: tuple[str, ...]
    scheduled_obs: np.ndarray
    removed_obs: np.ndarray
    removed_passes: np.ndarray
    added_passes: np.ndarray

    def kept_obs(self, pairs: TapePairs) -> np.ndarray:
        """Observations on the tape per station, (n_ts,) int (from the pairs)."""
        n_ts = self.scheduled_obs.size
        return np.bincount(pairs.station - 1, weights=pairs.n_obs, minlength=n_ts
                           ).astype(np.int64)


@dataclass(frozen=True, slots=True, eq=False)
class TapeRaw:
    """One row per scalar observation, for validation (columns: :mod:`tapp.io.tape.t13_hdf5`).

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
class T13Header:
    """Everything of a T13 tape but its pair factors and raw rows: what TAPP III binds its
    deck to and sequences by (:attr:`tapp.io.tape.t13_hdf5.T13File.header`,
    :attr:`MemoryPairs.header`). A whole tape (:class:`T13`) is a header too.

    Attributes
    ----------
    iden : identification of the run (text).
    epoch : the tape epoch t_0 = 0 s (injection), UTC.
    n_p : number of orbit parameters p (the first n_p of the n_o parameters).
    parameters : the n_o parameters x = [p; q], names with units, nominal values at t_0 in
        their ``unit``.
    stations : the n_ts stations, geodetic positions (deg, km) and elevation masks (deg).
    miss : the n_m miss parameters (in their ``unit``) at ``t_s`` (s) and B = ∂m/∂x(t_0),
        (n_m, n_o) in (row unit)/(column unit).
    records : the T13 times (s from the epoch) and the n_it records: epoch index j, state at
        t_k (km, km/s), U = ∂p(t_k)/∂x(t_j) (n_it, n_p, n_o).
    pairs : the (record, station) pairs with data and their observation counts; the factors
        ``R``, ``Rt``, ``Rt_parts`` are None in a header (1/u_b in a :class:`T13`).
    passes : tracking passes: station, first and last observation times (s), observations.
    provenance : the root attributes that describe how the tape was made (text: scenario
        JSON and source on writing; plus tapp_version, git_commit, created_utc on reading).
    editing : what the schedule asked for and each rule removed (None on tapes written
        before it was recorded).
    stochastic : the definition of the parameters of kind "stochastic" (σ km/s², τ s,
        interval boundaries s), or None without them.
    manoeuvres : the burns TAPP I flew, ascending in time, whose execution errors are the
        parameters of kind "execution".
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
    provenance: dict[str, str] = field(default_factory=dict)
    editing: TapeEditing | None = None
    stochastic: StochasticAccelerations | None = None
    manoeuvres: tuple[Burn, ...] = ()

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
class T13(T13Header):
    """A T13 tape in memory: what TAPP I writes and TAPP III reads: its header
    (:class:`T13Header`) with the pair factors (``pairs.R``, ``pairs.Rt``, optionally
    ``pairs.Rt_parts``) and, optionally, one row per scalar observation (``raw``).
    """

    raw: TapeRaw | None = None


@dataclass(frozen=True, slots=True, eq=False)
class PairBlock:
    """Pairs of records k_first..k_last (inclusive), factors packed TR (upper triangle by
    rows, L = n_o (n_o + 1) / 2: :func:`tapp.io.tape.packing.pack_tr`).

    Attributes
    ----------
    k : (m,) int record index, ascending.
    station : (m,) int station number, ascending within a record.
    n_obs : (m,) int scalar observations of each pair.
    R, Rt : (m, L) factors of AᵀWA and AᵀWMWA, 1/u_b.
    Rt_parts : (m, 3, L) the factors of the parts (:data:`tapp.measurements.noise.PARTS`), or
        None when the tape has none.
    """

    k: np.ndarray
    station: np.ndarray
    n_obs: np.ndarray
    R: np.ndarray
    Rt: np.ndarray
    Rt_parts: np.ndarray | None


# ---------------------------------------------------------------------------------------------
# Validation (shared by the writer and the readers)
# ---------------------------------------------------------------------------------------------


def validate(tape: T13, source: str = "T13") -> None:
    """Check the dimensions and invariants of a tape; raise TapeError naming the dataset.

    Checks: shapes against n_o, n_p, n_m, n_ts, n_it; finite numbers within
    :data:`tapp.io.tape.checks.MAX_MAGNITUDE`; T13 times strictly
    ascending from t_0 = 0, each an epoch or an input time; k = 1..n_it; j_1 = 0 and j_k
    either j_{k-1} or k-1, k-1 exactly when t_{k-1} is an epoch time; pairs each once and
    sorted by (k, station), with known records and stations and at least one observation;
    factors present, upper triangular with a non-negative diagonal; the parts' Gram matrices
    (when present) summing to R̃ᵀR̃ on the diagonal within :data:`PARTS_TOL`; raw rows
    consistent.
    """
    c = Checker(source)
    _validate_header(c, tape)
    pairs, n_pairs, n_o = tape.pairs, tape.pairs.k.size, tape.n_o
    for name in ("R", "Rt"):
        m = getattr(pairs, name)
        if m is None:
            c.fail(f"pairs/{name}", "the pair factors (a complete tape)",
                   "None: a header without pair factors")
        c.shape(f"pairs/{name}", m, (n_pairs, n_o, n_o))
        c.finite(f"pairs/{name}", m)
        check_factors(c, f"pairs/{name}", pack_tr(m), n_o, lower=np.tril(m, -1))
    if pairs.Rt_parts is not None:
        c.shape("pairs/Rt_parts", pairs.Rt_parts, (n_pairs, len(PARTS), n_o, n_o))
        c.finite("pairs/Rt_parts", pairs.Rt_parts)
        check_factors(c, "pairs/Rt_parts", pack_tr(pairs.Rt_parts), n_o,
                      lower=np.tril(pairs.Rt_parts, -1))
        check_parts_sum(c, column_norms2(pairs.Rt_parts).sum(axis=1), column_norms2(pairs.Rt),
                        0)
    if tape.raw is not None:
        _validate_raw(c, tape.raw, n_o, tape.n_ts, tape.n_it)


def column_norms2(factors: np.ndarray) -> np.ndarray:
    """The diagonal of KᵀK of factors (..., m, n): their columns' squared norms, (..., n)."""
    return np.einsum("...ij,...ij->...j", factors, factors)


def packed_column_norms2(packed: np.ndarray, n: int) -> np.ndarray:
    """:func:`column_norms2` of upper-triangular factors packed TR, (..., L) -> (..., n)."""
    return packed_column_sums(packed * packed, n)


def packed_column_sums(packed: np.ndarray, n: int) -> np.ndarray:
    """The column sums of upper-triangular matrices packed TR, (..., L) -> (..., n): each row
    added into the columns it spans (n slice additions; 2x faster than a product with the
    0/1 matrix of the packing, and no unpacking)."""
    out = np.zeros(packed.shape[:-1] + (n,))
    for i, start, stop in tr_rows(n):
        out[..., i:] += packed[..., start:stop]
    return out


def check_factors(c: Checker, name: str, packed: np.ndarray, n: int,
                  lower: np.ndarray | None = None, offset: int = 0) -> None:
    """Factors packed TR (..., L): zero below the diagonal when given full (``lower``, the
    strictly lower parts), and a non-negative diagonal (the canonical sign of a QR)."""
    if lower is not None and np.any(lower != 0):
        first = np.argwhere(lower != 0)[0]
        c.fail(name, "upper-triangular factors (zero below the diagonal)",
               f"{lower[tuple(first)]:.3g} in pair {int(first[0]) + offset}, row "
               f"{int(first[-2])}, column {int(first[-1])}")
    diag = packed[..., tr_diagonal(n)]
    if np.any(diag < 0):
        first = np.argwhere(diag < 0)[0]
        c.fail(name, "factors with a non-negative diagonal (the canonical sign of a QR)",
               f"{diag[tuple(first)]:.3g} in pair {int(first[0]) + offset}, row "
               f"{int(first[-1])}")


def check_parts_sum(c: Checker, parts: np.ndarray, total: np.ndarray, offset: int) -> None:
    """The parts' squared column norms, summed over the parts (m, n), equal to the total's
    (m, n) within :data:`PARTS_TOL` (the diagonal of the normal matrices)."""
    ref = np.where(total > 0, total, 1.0)
    defect = np.max(np.abs(parts - total) / ref, axis=-1) if total.size else total
    if np.any(defect > PARTS_TOL):
        first = int(np.argmax(defect > PARTS_TOL))
        c.fail("pairs/Rt_parts", f"parts whose Gram matrices sum to R̃ᵀR̃ (diagonal, relative "
                                 f"difference <= {PARTS_TOL:g})",
               f"{defect[first]:.3g} in pair {first + offset}")


#: Largest scaled difference between a version-1 or -2 normal matrix and the Gram matrix of
#: its factor: a sum of AᵀWA terms is PSD to its rounding (~1e-15 of its scale), so anything
#: beyond this is a matrix that is not a normal matrix.
LEGACY_PSD_TOL = 1e-8


def factor_normal_matrices(m: np.ndarray, c: Checker, name: str, offset: int = 0
                           ) -> np.ndarray:
    """Upper-triangular factors (..., n, n) of symmetric PSD normal matrices (..., n, n): the
    reading of a version-1 or -2 tape (:func:`tapp.estimation.factors.psd_factor` of each;
    rounding that makes one indefinite is set to zero). A matrix whose factor's Gram matrix
    departs from it by more than :data:`LEGACY_PSD_TOL` of its scale (indefinite beyond
    rounding) is refused, naming ``name`` and the pair (numbered from ``offset``)."""
    flat = m.reshape(-1, *m.shape[-2:])
    factors = np.array([psd_factor(0.5 * (x + x.T)) for x in flat])
    defect = scaled_difference(np.swapaxes(factors, -1, -2) @ factors, flat)
    if np.any(defect > LEGACY_PSD_TOL):
        first = int(np.argmax(defect > LEGACY_PSD_TOL))
        per_pair = flat.shape[0] // m.shape[0] if m.ndim > 2 else 1  # the parts: 3 a pair
        pair = first // per_pair + offset
        c.fail(name, f"positive semi-definite normal matrices (to {LEGACY_PSD_TOL:g} of "
                     "their scale)", f"{defect[first]:.3g} in pair {pair}")
    return factors.reshape(m.shape)


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


def _validate_stochastic(c: Checker, spec: StochasticAccelerations | None,
                         par: TapeParameters) -> None:
    """The parameters of kind "stochastic" are exactly the accelerations ``spec`` defines,
    named and ordered as it names them, nominal 0, in km/s²; its definition is sound."""
    at = [i for i, kind in enumerate(par.kind) if kind == KIND]
    if spec is None:
        if at:
            c.fail("stochastic", "the definition of the stochastic parameters",
                   "parameters of kind stochastic and no stochastic/ group")
        return
    if spec.frame not in FRAMES:
        c.fail("stochastic.attrs/frame", f"one of {', '.join(FRAMES)}", spec.frame)
    allowed = COMPONENTS[spec.frame]
    if not spec.components or any(x not in allowed for x in spec.components) or \
            len(set(spec.components)) != len(spec.components):
        c.fail("stochastic.attrs/components", f"distinct components among {allowed}",
               list(spec.components))
    bounds = np.asarray(spec.boundaries_s, dtype=float)
    if bounds.size < 2 or not np.all(np.isfinite(bounds)) or np.any(np.diff(bounds) <= 0):
        c.fail("stochastic/boundaries_s", "at least 2 finite, strictly ascending times",
               bounds[:8].tolist())
    for name in ("sigma_km_s2", "tau_s"):
        value = getattr(spec, name)
        if not (math.isfinite(value) and value > 0):
            c.fail(f"stochastic.attrs/{name}", "a finite number > 0", value)
    names = tuple(par.name[i] for i in at)
    if names != spec.names:
        c.fail("parameters/kind", f"the {len(spec.names)} stochastic parameters of stochastic/ "
               "in order", f"{len(names)}: {', '.join(names[:4])}")
    if any(par.unit[i] != UNIT for i in at) or np.any(par.nominal[at] != 0):
        c.fail("parameters/unit", f"stochastic accelerations in {UNIT}, nominal 0")


def _validate_manoeuvres(c: Checker, burns: tuple[Burn, ...], par: TapeParameters) -> None:
    """The parameters of kind "execution" are exactly the burns' execution errors, named,
    ordered and in the units the burns give them, nominal 0; the burns are in the arc's order
    and do not overlap."""
    at = [i for i, kind in enumerate(par.kind) if kind == EXECUTION]
    want = [p for b in burns for p in b.parameters()]
    if tuple(par.name[i] for i in at) != tuple(n for n, _, _ in want):
        c.fail("parameters/kind", f"the {len(want)} execution errors of the manoeuvres/ burns "
               "in order", f"{len(at)}: {', '.join(par.name[i] for i in at[:4])}")
    if any(par.unit[i] != u for i, (_, u, _) in zip(at, want, strict=True)) or \
            np.any(par.nominal[at] != 0):
        c.fail("parameters/unit", "execution errors in the units of Gates' model "
               "(tapp.dynamics.gates), nominal 0")
    starts = np.array([b.t_start_s for b in burns])
    ends = np.array([b.t_end_s for b in burns])
    if not (np.all(np.isfinite(starts)) and np.all(ends >= starts)
            and np.all(starts[1:] >= ends[:-1]) and np.all(np.diff(starts) > 0)):
        c.fail("manoeuvres/t_start_s", "finite times of burns in order, not overlapping",
               starts.tolist())


def _validate_header(c: Checker, tape: T13Header) -> None:
    """Everything of :func:`validate` but the pair matrices and the raw rows."""
    n_o, n_p, n_m, n_ts, n_it = tape.n_o, tape.n_p, tape.n_m, tape.n_ts, tape.n_it
    par = tape.parameters
    check_parameters(c, par, n_p)

    _validate_stochastic(c, tape.stochastic, par)
    _validate_manoeuvres(c, tape.manoeuvres, par)

    dims = {"n_o": n_o, "n_p": n_p, "n_m": n_m, "n_ts": n_ts, "n_it": n_it,
            "n_pairs": tape.pairs.k.size, "n_passes": tape.passes.station.size}

    def check(*prefixes: str) -> None:
        """The shapes (and finite numbers) of the layout's rows under ``prefixes``."""
        for prefix in prefixes:
            c.rows(rows(T13_LAYOUT, VERSION, prefix), lambda f: sourced(tape, f.source), dims)

    st = tape.stations
    check("stations/")
    if not np.array_equal(st.id, np.arange(1, n_ts + 1)):
        c.fail("stations/id", f"station numbers 1..{n_ts}", st.id.tolist())
    if np.any((par.station < 0) | (par.station > n_ts)):
        c.fail("parameters/station", f"station numbers in 0..{n_ts}", par.station.tolist())

    miss = tape.miss
    check("miss/", "B")
    if not math.isfinite(miss.t_s):
        c.fail("miss/nominal.attrs/t_s", "a finite time (s)", miss.t_s)

    rec = tape.records
    check("times/", "records/")
    if rec.times_s[0] != 0.0 or np.any(np.diff(rec.times_s) <= 0):
        c.fail("times/t_s", "strictly ascending times from t_0 = 0 s", rec.times_s[:8].tolist())
    if not rec.is_epoch[0] or not np.all(rec.is_epoch | rec.is_input):
        c.fail("times/is_epoch", "t_0 an epoch and every time an epoch or an input time")
    if not np.array_equal(rec.k, np.arange(1, n_it + 1)):
        c.fail("records/k", f"1..{n_it} in order", rec.k[:8].tolist())
    expected_j = np.maximum.accumulate(np.where(rec.is_epoch[:-1], np.arange(n_it), 0))
    if not np.array_equal(rec.j, expected_j):
        k = int(np.argmax(rec.j != expected_j)) + 1
        c.fail("records/j", "j_k = the last epoch index <= k-1 (j stays or changes to k-1)",
               f"j_{k} = {rec.j[k - 1]}, expected {expected_j[k - 1]}")

    pairs = tape.pairs
    check("pairs/")
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
    check("passes/")
    if np.any((ps.station < 1) | (ps.station > n_ts)) or np.any(ps.t_end_s < ps.t_start_s):
        c.fail("passes/station", f"station numbers in 1..{n_ts} and t_start_s <= t_end_s")
    if tape.editing is not None:
        _validate_editing(c, tape.editing, pairs, n_ts)


def _validate_editing(c: Checker, ed: TapeEditing, pairs: TapePairs, n_ts: int) -> None:
    """Shapes, counts >= 0, and every scheduled observation kept or removed by one rule."""
    n_rules = len(ed.rule)
    if len(set(ed.rule)) != n_rules or not all(ed.rule):
        c.fail("editing/rule", "unique, non-empty rule names", list(ed.rule))
    for name, value, shape in (("scheduled_obs", ed.scheduled_obs, (n_ts,)),
                               ("removed_obs", ed.removed_obs, (n_ts, n_rules)),
                               ("removed_passes", ed.removed_passes, (n_ts, n_rules)),
                               ("added_passes", ed.added_passes, (n_ts,))):
        c.shape(f"editing/{name}", value, shape)
        if np.any(value < 0):
            c.fail(f"editing/{name}", "counts >= 0", value.tolist())
    kept = ed.kept_obs(pairs)
    accounted = kept + ed.removed_obs.sum(axis=1)
    if not np.array_equal(accounted, ed.scheduled_obs):
        s = int(np.argmax(accounted != ed.scheduled_obs))
        c.fail("editing/scheduled_obs", "the observations kept (pairs/n_obs) plus those "
               "removed (editing/removed_obs) at every station",
               f"{ed.scheduled_obs[s]} scheduled at station {s + 1}, {kept[s]} kept + "
               f"{accounted[s] - kept[s]} removed")


def _validate_raw(c: Checker, raw: TapeRaw, n_o: int, n_ts: int, n_it: int) -> None:
    # shapes of the layout's rows, finite numbers but m_tau_s (inf: no correlated noise)
    c.rows(rows(T13_LAYOUT, VERSION, "raw/"), lambda f: getattr(raw, f.name),
           {"N": raw.t_s.size, "n_o": n_o})
    if np.any(raw.weight <= 0):
        c.fail("raw/weight", "weights 1/σ² > 0")
    if np.any((raw.kind < 0) | (raw.kind >= len(raw.kinds))):
        c.fail("raw/kind", f"codes 0..{len(raw.kinds) - 1} into attr kinds {raw.kinds}")
    if np.any((raw.record < 1) | (raw.record > n_it)):
        c.fail("raw/record", f"record indices in 1..{n_it}")
    if np.any((raw.station < 1) | (raw.station > n_ts)):
        c.fail("raw/station", f"station numbers in 1..{n_ts}")


# ---------------------------------------------------------------------------------------------
# Pair blocks (shared by the lazy file reader and the tape in memory)
# ---------------------------------------------------------------------------------------------


def _record_range(header: T13Header, k_first: int, k_last: int) -> tuple[int, int]:
    """Pair indices [lo, hi) of records k_first..k_last (pairs sorted by k)."""
    n_it = header.n_it
    if not (isinstance(k_first, int | np.integer) and isinstance(k_last, int | np.integer)
            and 1 <= k_first <= k_last <= n_it):
        raise InputError("pair_block", "k_first, k_last",
                         f"record indices 1 <= k_first <= k_last <= {n_it}", (k_first, k_last))
    k = header.pairs.k
    return (int(np.searchsorted(k, k_first, side="left")),
            int(np.searchsorted(k, k_last, side="right")))


def header_of(tape: T13Header) -> T13Header:
    """The header of a tape: its fields but the pair factors (and the raw rows)."""
    values = {f.name: getattr(tape, f.name) for f in fields(T13Header)}
    pairs = tape.pairs
    values["pairs"] = TapePairs(pairs.k, pairs.station, pairs.n_obs, None, None, None)
    return T13Header(**values)


class _PairSource:
    """What :class:`tapp.io.tape.t13_hdf5.T13File` and :class:`MemoryPairs` share: the header,
    blocks of pairs."""

    __slots__ = ()

    header: T13Header

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




class MemoryPairs(_PairSource):
    """The interface of :class:`tapp.io.tape.t13_hdf5.T13File` over a tape in memory (from
    :func:`memory_pairs`).

    Attributes
    ----------
    header : T13Header
        The tape without its pair factors and raw rows.
    """

    __slots__ = ("_tape", "header")

    def __init__(self, tape: T13, source: str = "T13"):
        validate(tape, source)
        self._tape = tape
        self.header = header_of(tape)

    def pair_block(self, k_first: int, k_last: int, *, parts: bool = True) -> PairBlock:
        """Return the pairs of records k_first..k_last (inclusive), factors packed TR.

        Raises
        ------
        InputError
            Record indices outside 1 <= k_first <= k_last <= n_it.
        """
        lo, hi = _record_range(self.header, k_first, k_last)
        pairs = self._tape.pairs
        split = None if pairs.Rt_parts is None or not parts else frozen(
            pack_tr(pairs.Rt_parts[lo:hi]))
        return PairBlock(frozen(pairs.k[lo:hi], np.int64), frozen(pairs.station[lo:hi], np.int64),
                         frozen(pairs.n_obs[lo:hi], np.int64), frozen(pack_tr(pairs.R[lo:hi])),
                         frozen(pack_tr(pairs.Rt[lo:hi])), split)


def memory_pairs(tape: T13) -> MemoryPairs:
    """Return the :class:`tapp.io.tape.t13_hdf5.T13File` interface (``header``, ``pair_block``,
    ``blocks``) over a tape in memory, validated now.

    Raises
    ------
    TapeError
        If the tape fails :func:`validate`.
    """
    return MemoryPairs(tape)


def summary(tape: T13Header, *, version: int = VERSION) -> dict:
    """Return a JSON-ready summary: dimensions, parameters, stations with their passes and
    observations (and, when the tape has them, the observations scheduled and removed by each
    rule: :class:`TapeEditing`), epoch times, records and provenance (``version``: of the tape
    read)."""
    rec = tape.records
    epoch_times = rec.times_s[rec.is_epoch]
    editing = tape.editing
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
            "records_with_data": int(np.count_nonzero(mine)),
            **({} if editing is None else _editing_summary(editing, int(sid) - 1))})
    return {
        "format": FORMAT, "version": version, "iden": tape.iden, "epoch_utc": tape.epoch.iso(3),
        "dimensions": {"n_o": tape.n_o, "n_p": tape.n_p, "n_m": tape.n_m, "n_ts": tape.n_ts,
                       "n_it": tape.n_it, "pairs": int(tape.pairs.k.size),
                       "passes": int(tape.passes.station.size),
                       "raw_rows": int(tape.raw.t_s.size) if isinstance(tape, T13)
                       and tape.raw is not None else None},
        "span_s": [float(rec.times_s[0]), float(rec.times_s[-1])],
        "parameters": [{"name": n, "unit": u, "kind": k}
                       for n, u, k in zip(tape.parameters.name, tape.parameters.unit,
                                          tape.parameters.kind, strict=True)],
        "stations": stations,
        "observations": int(tape.pairs.n_obs.sum()),
        "epochs": [{"index": int(i), "t_s": float(t),
                    "utc": tape.epoch.iso_after(float(t), 3)}
                   for i, t in zip(np.flatnonzero(rec.is_epoch), epoch_times, strict=True)],
        "input_times": int(np.count_nonzero(rec.is_input)),
        "miss": {"kind": tape.miss.kind, "t_s": tape.miss.t_s,
                 "names": list(tape.miss.name), "units": list(tape.miss.unit),
                 "nominal": tape.miss.nominal.tolist()},
        "manoeuvres": [{"name": b.name, "kind": b.kind, "axes": b.axes,
                        "t_start_s": b.t_start_s, "t_end_s": b.t_end_s,
                        "execution_errors": len(b.parameters())} for b in tape.manoeuvres],
        "provenance": {k: v for k, v in tape.provenance.items() if k != "scenario"},
    }


def _editing_summary(ed: TapeEditing, i: int) -> dict:
    """The editing counts of station index ``i``, for :func:`summary`."""
    return {"scheduled_observations": int(ed.scheduled_obs[i]),
            "removed": {rule: {"observations": int(n), "passes": int(p)}
                        for rule, n, p in zip(ed.rule, ed.removed_obs[i], ed.removed_passes[i],
                                              strict=True)},
            "passes_added_by_split": int(ed.added_passes[i])}


