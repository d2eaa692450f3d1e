"""Benchmark of the TAPP III matrix processor on synthetic T13 tapes.

The issue's targets: n_o = 50, 2,000 records, 10 stations, 20 print times with 10 entities
each and 3 recycles in under 2 s on the 2-core machine; the square-root processor within
1.5x of the normal-matrix one it replaced and within 2x of a plain NumPy peer. The tapes are
built directly (not by TAPP I), in factor form: per (record, station) pair R = triangularize(G),
G with 3 random rows over the columns the pair observes (the orbit, the dynamic constants and
that station's own parameters, as in a tracking tape; a dense variant fills every column), so
ΔJ = RᵀR = GᵀG; R̃ = √2 R (ΔJ̃ = 2 ΔJ) with the factors R, √0.6 R, √0.4 R of its white,
bias and correlated parts (:data:`PART_SHARES` of ΔJ, so the error budget has its input);
3 of the 10 stations per record, epochs at 3 times, the orbit block of U the
exponential of a Hamiltonian matrix (exactly symplectic, as a TAPP I STM is to its
integration error). Each tape is written three times to a temporary folder (not timed): as
version 4 (the factors, LZ4) with :func:`tapp.io.tape.t13_hdf5.write_t13`, and with the
writer's private ``_write(..., version=)`` as version 3 (the same factors, gzip: the layout
before version 4) and as version 2 (the normal matrices RᵀR, R̃ᵀR̃ and the parts' Grams,
gzip).

Measured (wall clock, best of :data:`REPEATS` after a warm-up): open + bind + process of the
full deck on the version-4 tape through the lazy reader :func:`tapp.io.tape.t13_hdf5.open_t13`,
and on the version-3 tape (its outputs checked bit for bit against the version-4 run's); the
same with one print (at the end) and no recycles (per record = that time / n_IT); the
normal-matrix processor of commit :data:`tests.bench.legacy.NORMAL_MATRIX_COMMIT` on the
version-2 tape, the same two decks timed the same way in a child process
(:func:`normal_form`); the print commands evaluated alone on the last record's statistics (per
entity); reading every pair block alone (the I/O floor), of either tape; a plain NumPy/h5py peer
(:func:`numpy_peer`) that reads the version-2 tape's packed normal matrices, sums them per
print interval and does one Cholesky regression per print time (BLAS on one thread, as
TAPP III); the peak of the processing's allocations by tracemalloc; ``tapp process`` end
to end in a child process, with the default BLAS threads and with one (its peak RSS:
VmHWM). The n_o scaling runs the same tape shape at n_o = 25, 50, 100."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
from scipy import linalg
from threadpoolctl import threadpool_limits

from tapp.estimation.factors import triangularize
from tapp.frames.time import Epoch
from tapp.io.tape import hdf5io
from tapp.io.tape.packing import tr_size, unpack_tr
from tapp.io.tape.t13 import (
    T13,
    TapeMiss,
    TapePairs,
    TapeParameters,
    TapePasses,
    TapeRecords,
    TapeStations,
)
from tapp.io.tape.t13_hdf5 import _write, open_t13, write_t13
from tapp.measurements.noise import PARTS
from tapp.processor.deck import read_deck
from tapp.processor.deck_bind import bind
from tapp.processor.sequencing import Processor, Run, process
from tests.bench import legacy
from tests.bench.common import (
    REPO_ROOT,
    Section,
    logger,
    markdown_table,
    time_calls,
    traced_peak_mb,
)

NAME = "processor"
N_O = 50
SCALING_N_O = (25, 50, 100)
N_P = 6
N_DYNAMIC = 4
N_RECORDS = 2000
N_STATIONS = 10
STATIONS_PER_RECORD = 3
RECORD_STEP_S = 60.0
N_EPOCHS = 3
N_PRINTS = 20
N_RECYCLES = 3
TARGET_S = 2.0
#: The issue's targets for the square-root processor: at most this many times the
#: normal-matrix processor (commit legacy.NORMAL_MATRIX_COMMIT) and the NumPy peer.
TARGET_NORMAL_RATIO = 1.5
TARGET_PEER_RATIO = 2.0
#: Shares of ΔJ in the white, bias and correlated parts of ΔJ̃ = 2 ΔJ (factors √share R).
PART_SHARES = (1.0, 0.6, 0.4)
REPEATS = 3
SEED = 20261123
#: Fit-world a priori σ of every parameter, and the real world's (units of the parameter).
SIGMA_FIT = 10.0
SIGMA_REAL = 20.0
#: Constants held fixed in the fit world (σ = 0): the "couple of fixed parameters".
FIXED = ("d1_km", "d2_km")
PRINT_COMMANDS = (
    "cov real orbit@current",
    "cov fit orbit@current",
    "Lb'; 0,0,rq; 0,0,rq",
    "L'; 0,0,f1; 0,0,f1",
    "J; 1,0,f1; 1,0,f1",
    "S'; 1,0,f1; 1,0,f1",
    "I; 0,-,pk; 1,2,fp",
    "I; 0,-,m1; 1,1,fq",
    "Sigma; 0,1,p; 0,1,p",
    "Lb'; 0,-,m; 0,-,m",
)
ORBIT = (("x_km", "km"), ("y_km", "km"), ("z_km", "km"), ("vx_km_s", "km/s"),
         ("vy_km_s", "km/s"), ("vz_km_s", "km/s"))
MISS = (("a_km", "km"), ("ex", "1"), ("ey", "1"), ("hx", "1"), ("hy", "1"),
        ("lambda_m_rad", "rad"))
_GAMMA = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
log = logger(NAME)


# ---------------------------------------------------------------- the synthetic tape


def _parameters(n_o: int) -> TapeParameters:
    """The orbit (6), :data:`N_DYNAMIC` dynamic constants, then station parameters dealt to
    the stations in turn (station s owns those with ``station == s``)."""
    n_st = n_o - N_P - N_DYNAMIC
    owner = np.arange(n_st) % N_STATIONS + 1
    order = np.argsort(owner, kind="stable")
    owner = owner[order]
    count = np.zeros(N_STATIONS + 1, dtype=int)
    st_names = []
    for s in owner:
        count[s] += 1
        st_names.append(f"ST{s:02d}.b{count[s]}_km")
    names = [n for n, _ in ORBIT] + [f"d{i}_km" for i in range(1, N_DYNAMIC + 1)] + st_names
    units = [u for _, u in ORBIT] + ["km"] * (n_o - N_P)
    kinds = ["orbit"] * N_P + ["dynamic"] * N_DYNAMIC + ["bias"] * n_st
    station = np.concatenate([np.zeros(N_P + N_DYNAMIC, dtype=int), owner])
    return TapeParameters(tuple(names), tuple(units), tuple(kinds), station,
                          np.linspace(1.0, 2.0, n_o))


def _factors(rng: np.random.Generator, station: np.ndarray, owner: np.ndarray, dense: bool
             ) -> np.ndarray:
    """(n_pairs, n_o, n_o) upper-triangular R = triangularize(G), G (3, n_cols) random on the
    columns a pair observes: the orbit, the dynamic constants and its own station's parameters
    (all columns if dense). R sits on those rows and columns (ascending, so it stays upper
    triangular) and ΔJ = RᵀR = GᵀG."""
    n_o = owner.size
    r = np.zeros((station.size, n_o, n_o))
    for s in range(1, N_STATIONS + 1):
        rows = np.flatnonzero(station == s)
        cols = np.arange(n_o) if dense else np.flatnonzero((owner == 0) | (owner == s))
        g = rng.normal(size=(rows.size, 3, cols.size))
        at = np.ix_(cols, cols)
        for row, g_pair in zip(rows, g, strict=True):
            r[row][at] = triangularize(g_pair)
    return r


def _transition(rng: np.random.Generator, times_s: np.ndarray, epoch_of: np.ndarray,
                n_o: int) -> np.ndarray:
    """(n_it, n_p, n_o) U = [Φ, Q]: Φ = expm(ΓH τ) with H symmetric (symplectic), τ the time
    since the record's epoch over the segment's length; Q grows linearly with τ."""
    h = rng.normal(size=(N_P, N_P))
    gen = _GAMMA @ (0.5 * (h + h.T)) * 0.5
    q = rng.normal(size=(N_P, n_o - N_P)) * 0.1
    span_s = times_s[-1] / N_EPOCHS
    u = np.empty((times_s.size - 1, N_P, n_o))
    for i in range(times_s.size - 1):
        tau = (times_s[i + 1] - times_s[epoch_of[i]]) / span_s
        u[i, :, :N_P] = linalg.expm(gen * tau)
        u[i, :, N_P:] = q * tau
    return u


def synthetic_tape(n_o: int, rng: np.random.Generator, *, dense: bool = False) -> T13:
    """A valid T13 tape of :data:`N_RECORDS` records (module docstring), full in memory.

    ``dense``: every ΔJ full (no zero for the compression to find), the worst case; by
    default a pair's ΔJ touches only the orbit, the dynamic constants and its station.
    """
    n_it = N_RECORDS
    times = np.arange(n_it + 1) * RECORD_STEP_S
    is_epoch = np.zeros(n_it + 1, dtype=bool)
    is_epoch[(np.arange(N_EPOCHS) * n_it) // N_EPOCHS] = True
    j = np.maximum.accumulate(np.where(is_epoch[:-1], np.arange(n_it), 0))
    # about STATIONS_PER_RECORD of the stations per record, sorted by (k, station)
    chosen = np.argsort(rng.random((n_it, N_STATIONS)), axis=1)[:, :STATIONS_PER_RECORD]
    keep = np.zeros((n_it, N_STATIONS), dtype=bool)
    np.put_along_axis(keep, chosen, True, axis=1)
    k, station = (v + 1 for v in np.nonzero(keep))
    n_pairs = k.size
    params = _parameters(n_o)
    r = _factors(rng, station, params.station, dense)
    parts = np.stack([r * math.sqrt(share) for share in PART_SHARES], axis=1)
    n_obs = rng.integers(10, 60, n_pairs)
    per_station = np.bincount(station, weights=n_obs, minlength=N_STATIONS + 1)[1:]
    return T13(
        iden=f"SYNTHETIC-N{n_o}", epoch=Epoch.from_calendar(2026, 3, 10, 12), n_p=N_P,
        parameters=params,
        stations=TapeStations(np.arange(1, N_STATIONS + 1),
                              tuple(f"ST{i:02d}" for i in range(1, N_STATIONS + 1)),
                              ("range,range_rate",) * N_STATIONS,
                              np.linspace(-60.0, 60.0, N_STATIONS),
                              np.linspace(-170.0, 170.0, N_STATIONS),
                              np.full(N_STATIONS, 0.1), np.full(N_STATIONS, 5.0)),
        miss=TapeMiss("equinoctial", float(times[-1]), tuple(n for n, _ in MISS),
                      tuple(u for _, u in MISS), np.array([7000.0, 0, 0, 0, 0, 1.0]),
                      rng.normal(size=(len(MISS), n_o))),
        records=TapeRecords(times, is_epoch, np.ones(n_it + 1, dtype=bool), j,
                            np.arange(1, n_it + 1), rng.normal(size=(n_it, 6)),
                            _transition(rng, times, j, n_o)),
        pairs=TapePairs(k, station, n_obs, r, math.sqrt(2.0) * r, parts),
        passes=TapePasses(np.arange(1, N_STATIONS + 1), np.full(N_STATIONS, times[1]),
                          np.full(N_STATIONS, times[-1]), per_station.astype(np.int64)),
        provenance={"scenario": "{}", "scenario_source": "tests/bench/processor.py"},
    )


# ---------------------------------------------------------------- the deck


def print_k() -> list[int]:
    """T13 indices of the :data:`N_PRINTS` print times, spread over the tape."""
    return [int(v) for v in np.linspace(N_RECORDS / N_PRINTS, N_RECORDS, N_PRINTS)]


def recycle_k() -> list[int]:
    """T13 indices of the :data:`N_RECYCLES` recycles."""
    return [int(v) for v in np.linspace(0, N_RECORDS, N_RECYCLES + 2)[1:-1]]


def deck_text(names: tuple[str, ...], *, prints: bool = True, recycles: bool = True) -> str:
    """The TOML deck: σ tables over every parameter, :data:`FIXED` held fixed, the print
    commands at the print times and the standard recycle commands at the recycles.

    Without ``prints``, one print at the last record remains: the sequencer reads pending
    records only when it needs statistics, so a deck without a late print never reads the
    tape's tail.
    """
    fit = "\n".join(f'"{n}" = {0.0 if n in FIXED else SIGMA_FIT}' for n in names)
    real = "\n".join(f'"{n}" = {SIGMA_REAL}' for n in names)
    cmds = ", ".join(f'"{c}"' for c in PRINT_COMMANDS)
    return "\n".join([
        'title = "synthetic benchmark deck"',
        "[times]",
        f"print = {print_k() if prints else [N_RECORDS]}",
        f"recycle = {recycle_k() if recycles else []}",
        "[commands]",
        f"print = [{cmds}]",
        'recycle = "standard"',
        "[fit.apriori.sigma]", fit,
        "[real.apriori.sigma]", real, ""])


def process_tape(tape_path: Path, deck_path: Path) -> Run:
    """Open the tape lazily, bind the deck and run TAPP III (what is timed)."""
    deck = read_deck(deck_path)
    with open_t13(tape_path) as data:
        plan = bind(deck, data.header, str(deck_path))
        return process(data, plan, source=str(deck_path))


def entity_time_s(tape_path: Path, deck_path: Path) -> float:
    """Best time of evaluating the deck's print commands once (with their error budgets) on
    the statistics of the last record: the executive's cost per print time.

    Uses the sequencer's own entity step (a private method) after a complete run, so that
    the time is that of the entities alone, free of the run's read-in.
    """
    deck = read_deck(deck_path)
    with open_t13(tape_path) as data:
        plan = bind(deck, data.header, str(deck_path))
        proc = Processor(data, plan, str(deck_path))
        proc.run()
        cur = proc._statistics(proc.n_it)
        return time_calls(lambda: proc._entities(plan.print_commands, cur),
                          5 * REPEATS)[0].best_s


def read_all_blocks(tape_path: Path) -> int:
    """Read every pair block through the lazy reader (the I/O floor); return the pairs."""
    n = 0
    with open_t13(tape_path) as data:
        for blk in data.blocks():
            n += blk.k.size
    return n


# ---------------------------------------------------------------- the NumPy peer


@dataclass(frozen=True, slots=True)
class PeerResult:
    """The peer's fit covariance of the fitted parameters at each print time."""

    fit_cov: list[np.ndarray]


def numpy_peer(tape_path: Path, names: tuple[str, ...]) -> PeerResult:
    """The same statistics without the machinery: h5py reads the packed ΔJ, ΔJ̃ of each print
    interval, sums and unpacks them, and one Cholesky regression per print time gives the
    fit and real covariances, L, and the products of the 10 print entities.

    Simplifications (cost-neutral): one representation (the injection; no re-referencing at
    epoch changes and no recycles: the batch form, equal to the sequential one for a linear
    regression), no error budget, the tape's ΔJ̃ parts not read.

    BLAS runs on one thread, as in TAPP III (:meth:`tapp.processor.sequencing.Processor.run`):
    on matrices of order n_o, two threads on the shared machine cost the peer 3x its time
    (n_o = 50: 1.63 s against 0.55 s in the same minute, load average 3; n_o = 100: 5.1 s
    against 1.8 s; n_o = 25: the same), which would flatter the processor.
    """
    n_o = len(names)
    fit = np.array([n not in FIXED for n in names])
    e1 = np.eye(n_o)[:, fit]
    s0 = np.eye(int(fit.sum())) / SIGMA_FIT**2
    lam0 = np.eye(n_o) * SIGMA_REAL**2
    out = []
    with threadpool_limits(limits=1, user_api="blas"), h5py.File(tape_path, "r") as f:
        k = f["pairs/k"][...]
        u_all = f["records/U"]
        b = f["B"][...]
        dj_sum = np.zeros(f["pairs/dJ"].shape[1])
        djt_sum = np.zeros_like(dj_sum)
        lo = 0
        for kp in print_k():
            hi = int(np.searchsorted(k, kp, side="right"))
            if hi > lo:
                dj_sum += f["pairs/dJ"][lo:hi].sum(axis=0)
                djt_sum += f["pairs/dJt"][lo:hi].sum(axis=0)
            lo = hi
            j, jt = unpack_tr(dj_sum, n_o), unpack_tr(djt_sum, n_o)
            s11 = s0 + e1.T @ j @ e1                                    # (2-35)
            cho = linalg.cho_factor(s11)
            lam11 = linalg.cho_solve(cho, np.eye(s11.shape[0]))         # (2-28)
            lam00 = e1 @ lam11 @ e1.T                                   # (2-31)
            l_mat = np.eye(n_o) - e1 @ linalg.cho_solve(cho, e1.T @ j)  # (2-37)
            real = l_mat @ lam0 @ l_mat.T + lam00 @ jt @ lam00          # (2-46)
            u = u_all[kp - 1]
            sigma = lam00 @ jt @ lam00
            _entities = (u @ real @ u.T, u @ lam00 @ u.T, real[N_P:, N_P:], lam11,
                         e1.T @ j @ e1, s11, u[:, :N_P], b[:, N_P:], u @ sigma @ u.T,
                         b @ real @ b.T)
            out.append(lam11)
    return PeerResult(out)


# ---------------------------------------------------------------- measurements


def _best_s(fn) -> float:
    return time_calls(fn, REPEATS)[0].best_s


#: The entity compared with the peer and with the normal-matrix form: Λ' of the fitted set.
CHECK_ENTITY = "Λ'; 0,0,f1; 0,0,f1"


def fit_cov_at(run: Run, k: int) -> np.ndarray:
    """The matrix of :data:`CHECK_ENTITY` printed at record k."""
    block = next(b for b in run.blocks if b.kind == "print" and b.k == k)
    return next(e for e in block.entities if e.command.seed() == CHECK_ENTITY).matrix


def relative_difference(a: np.ndarray, ref: np.ndarray) -> float:
    """max |a − ref| / max |ref|."""
    return float(np.max(np.abs(np.asarray(a) - ref)) / np.max(np.abs(ref)))


def _agreement(run: Run, peer: PeerResult) -> float:
    """Max relative difference of the fit covariance of f1 at the first print time (before
    the first epoch change and recycle, where both use the same representation)."""
    return relative_difference(fit_cov_at(run, print_k()[0]), peer.fit_cov[0])


#: The child of :func:`normal_form`, after :mod:`tests.bench.legacy`'s prelude and the source
#: of :func:`process_tape` (run there on the normal-matrix commit's library): checks that the
#: tape is version 2, then times each deck as :func:`measure` does; it replies the best times
#: and the matrices of the check entity at the asked print times.
_NORMAL_FORM_CHILD = """
from tapp.processor.deck import bind, read_deck
from tapp.processor.sequencing import process
from tapp.tape.t13_hdf5 import open_t13

with open_t13(ARGS["tape"]) as data:
    if data.version != 2:
        raise SystemExit(f"expected a version-2 tape, read version {data.version}")
run = process_tape(ARGS["tape"], ARGS["decks"]["full"])  # warm-up
checked = {}
for block in run.blocks:
    if block.kind == "print" and block.k in ARGS["check_k"]:
        entity = next(e for e in block.entities if e.command.seed() == ARGS["entity"])
        checked[str(block.k)] = entity.matrix.tolist()
times = {kind: common.time_calls(lambda p=p: process_tape(ARGS["tape"], p),
                                 ARGS["repeats"])[0].best_s
         for kind, p in ARGS["decks"].items()}
reply({"times_s": times, "fit_cov": checked})
"""


def normal_form(checkout: legacy.Checkout, tape_v2: Path, decks: dict[str, Path],
                cache_dir: Path) -> dict:
    """The normal-matrix processor (the checkout's) on the version-2 tape, in a child: best
    of :data:`REPEATS` of open + bind + process after a warm-up, per deck; and
    :data:`CHECK_ENTITY` at the first and last print times ({k: matrix})."""
    check_k = [print_k()[0], print_k()[-1]]
    reply = legacy.run_child(checkout, _NORMAL_FORM_CHILD, {
        "tape": str(tape_v2), "decks": {kind: str(p) for kind, p in decks.items()},
        "repeats": REPEATS, "check_k": check_k, "entity": CHECK_ENTITY},
        cache_dir=cache_dir, functions=(process_tape,))
    return {"times_s": reply["times_s"],
            "fit_cov": {int(k): np.array(m) for k, m in reply["fit_cov"].items()}}


def write_version(path: Path, tape: T13, version: int) -> Path:
    """Write ``tape`` in the layout of an earlier ``version`` (2: normal matrices; 3: the
    factors, gzip) by the writer's private ``_write``, not atomically (a benchmark input)."""
    with hdf5io.create(path) as f:
        _write(f, tape, "TR", version=version)
    return path


def same_outputs(a: Run, b: Run) -> bool:
    """Whether two runs printed the same entities, bit for bit."""
    pairs = zip((e.matrix for blk in a.blocks for e in blk.entities),
                (e.matrix for blk in b.blocks for e in blk.entities), strict=True)
    return all(x.shape == y.shape and x.tobytes() == y.tobytes() for x, y in pairs)


def measure(n_o: int, folder: Path, rng: np.random.Generator, *, dense: bool = False,
            checkout: legacy.Checkout | None = None) -> dict:
    """Build and write one tape of n_o parameters (versions 3 and 2), then time the
    processor, the normal-matrix processor of ``checkout`` (None: not timed) and the peer."""
    label = f"n{n_o}{'_dense' if dense else ''}"
    t0 = time.perf_counter()
    tape = synthetic_tape(n_o, rng, dense=dense)
    tape_path = write_t13(folder / f"synthetic_{label}.t13.h5", tape)
    v3_path = write_version(folder / f"synthetic_{label}_v3.t13.h5", tape, 3)
    v2_path = write_version(folder / f"synthetic_{label}_v2.t13.h5", tape, 2)
    names, n_pairs = tape.parameters.name, int(tape.pairs.k.size)
    del tape
    packed_mb = n_pairs * tr_size(n_o) * 8 * (2 + len(PARTS)) / 1e6
    log(f"{label}: tape of {n_pairs} pairs built and written in {time.perf_counter() - t0:.1f}"
        f" s ({tape_path.stat().st_size / 1e6:.0f} MB on disk as version 4, "
        f"{v3_path.stat().st_size / 1e6:.0f} MB as version 3, "
        f"{v2_path.stat().st_size / 1e6:.0f} MB as version 2, {packed_mb:.0f} MB packed)")
    decks = {}
    for kind, flags in (("full", {}), ("records_only", {"prints": False, "recycles": False})):
        decks[kind] = folder / f"deck_{label}_{kind}.toml"
        decks[kind].write_text(deck_text(names, **flags))
    run = process_tape(tape_path, decks["full"])  # warm-up; its outputs are checked below
    same_v3 = same_outputs(run, process_tape(v3_path, decks["full"]))
    times = {kind: _best_s(lambda p=p: process_tape(tape_path, p)) for kind, p in decks.items()}
    v3_s = _best_s(lambda: process_tape(v3_path, decks["full"]))
    n_print_entities = sum(len(b.entities) for b in run.blocks if b.kind == "print"
                           and b.k != 0)
    entities_s = entity_time_s(tape_path, decks["full"])
    io_s = _best_s(lambda: read_all_blocks(tape_path))
    io_v3_s = _best_s(lambda: read_all_blocks(v3_path))
    peer_s = _best_s(lambda: numpy_peer(v2_path, names))
    check = _agreement(run, numpy_peer(v2_path, names))
    peak_mb = traced_peak_mb(lambda: process_tape(tape_path, decks["full"]))
    normal = {"normal_s": None, "normal_records_only_s": None, "ratio_to_normal": None,
              "normal_per_record_us": None, "normal_agreement": None}
    if checkout is not None:
        nf = normal_form(checkout, v2_path, decks, folder / "normal-form-cache")
        normal = {
            "normal_s": nf["times_s"]["full"],
            "normal_records_only_s": nf["times_s"]["records_only"],
            "ratio_to_normal": times["full"] / nf["times_s"]["full"],
            "normal_per_record_us": 1e6 * nf["times_s"]["records_only"] / N_RECORDS,
            "normal_agreement": {k: relative_difference(fit_cov_at(run, k), m)
                                 for k, m in nf["fit_cov"].items()}}
    result = {
        "label": label, "n_o": n_o, "dense": dense, "n_records": N_RECORDS, "n_pairs": n_pairs,
        "tape_mb": tape_path.stat().st_size / 1e6, "tape_v3_mb": v3_path.stat().st_size / 1e6,
        "tape_v2_mb": v2_path.stat().st_size / 1e6,
        "packed_mb": packed_mb, "full_s": times["full"], "entities_s": entities_s,
        "records_only_s": times["records_only"], "io_floor_s": io_s, "peer_s": peer_s,
        "ratio_to_peer": times["full"] / peer_s, "v3_s": v3_s, "io_floor_v3_s": io_v3_s,
        "v3_ratio_to_peer": v3_s / peer_s, "v3_bit_identical": same_v3, **normal,
        "per_record_us": 1e6 * times["records_only"] / N_RECORDS,
        "per_entity_ms": 1e3 * entities_s / len(PRINT_COMMANDS),
        "print_entities": n_print_entities,
        "all_entities": sum(len(b.entities) for b in run.blocks),
        "tracemalloc_peak_mb": peak_mb, "peer_agreement": check,
        "tape_path": tape_path, "v3_path": v3_path, "v2_path": v2_path,
        "deck_path": decks["full"],
    }
    versus = ("" if checkout is None else
              f"normal form {normal['normal_s']:.3f} s ({normal['ratio_to_normal']:.2f}x), ")
    log(f"{label}: full {times['full']:.3f} s, {versus}{len(PRINT_COMMANDS)} entities "
        f"{1e3 * entities_s:.1f} ms, "
        f"records only {times['records_only']:.3f} s, peer {peer_s:.3f} s, I/O {io_s:.3f} s, "
        f"on version 3 {v3_s:.3f} s (I/O {io_v3_s:.3f} s, outputs "
        f"{'bit-identical' if same_v3 else 'DIFFERENT'}), "
        f"peak {peak_mb:.0f} MB, first print Λ' vs peer {check:.1e}")
    return result


#: The child of :func:`cli_once`: ``tapp process`` that reports its own peak RSS (VmHWM of
#: its address space; getrusage's ru_maxrss of a child also counts the parent's pages at the
#: fork, before the exec).
_CLI_CHILD = """
import atexit, sys
def _hwm():
    with open("/proc/self/status") as f:
        kb = next(line.split()[1] for line in f if line.startswith("VmHWM:"))
    sys.stderr.write(f"VmHWM_kB {kb}\\n")
atexit.register(_hwm)
sys.argv = ["tapp", *sys.argv[1:]]
from tapp.cli import main
main()
"""


def cli_once(tape_path: Path, deck_path: Path, folder: Path, *, one_thread: bool) -> dict:
    """``tapp process`` end to end in a child process (with the O3 printout and JSON): wall
    time and peak RSS; ``one_thread`` runs it with OPENBLAS_NUM_THREADS=1."""
    cmd = [sys.executable, "-c", _CLI_CHILD, "process", str(tape_path), str(deck_path),
           "--print", str(folder / "o3.txt"), "--json", str(folder / "o3.json")]
    env = dict(os.environ)
    env.pop("OPENBLAS_NUM_THREADS", None)
    if one_thread:
        env["OPENBLAS_NUM_THREADS"] = "1"
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO_ROOT, env=env,
                          check=False)
    wall_s = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(f"tapp process exited {done.returncode}: {done.stderr.strip()}")
    hwm = [line.split()[1] for line in done.stderr.splitlines()
           if line.startswith("VmHWM_kB ")]
    o3_mb = (folder / "o3.txt").stat().st_size / 1e6
    for name in ("o3.txt", "o3.json"):
        (folder / name).unlink()
    return {"wall_s": wall_s, "one_thread": one_thread, "o3_mb": o3_mb,
            "peak_rss_mb": int(hwm[-1]) / 1024 if hwm else float("nan")}


def _fmt(value: float | None, spec: str) -> str:
    return "n/a" if value is None else format(value, spec)


def _row(r: dict) -> list[str]:
    agree = r["normal_agreement"]
    return [f"{r['n_o']}{' (dense G)' if r['dense'] else ''}", str(r["n_pairs"]),
            f"{r['tape_mb']:.0f} / {r['tape_v3_mb']:.0f} / {r['tape_v2_mb']:.0f} / "
            f"{r['packed_mb']:.0f}",
            f"{r['full_s']:.3f}", _fmt(r["normal_s"], ".3f"),
            _fmt(r["ratio_to_normal"], ".2f"),
            f"{r['per_record_us']:.0f} / {_fmt(r['normal_per_record_us'], '.0f')}",
            f"{r['per_entity_ms']:.2f}", f"{r['io_floor_s']:.3f}",
            f"{r['peer_s']:.3f}", f"{r['ratio_to_peer']:.1f}",
            f"{r['v3_s']:.3f} / {r['io_floor_v3_s']:.3f} / {r['v3_ratio_to_peer']:.1f}"
            f"{'' if r['v3_bit_identical'] else ' (outputs DIFFER)'}",
            f"{r['tracemalloc_peak_mb']:.0f}", f"{r['peer_agreement']:.0e}",
            "n/a" if agree is None else " / ".join(f"{v:.0e}" for v in agree.values())]


def _verdict(value: float | None, target: float) -> str:
    if value is None:
        return "n/a"
    return "yes" if value <= target else "NO"


def run() -> Section:
    """Run the processor section; return its Markdown and raw numbers."""
    rng = np.random.default_rng(SEED)
    load_before = os.getloadavg()
    blas_threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    results: list[dict] = []
    cli: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="tapp3-bench-") as tmp:
        folder = Path(tmp)
        checkout, skipped = legacy.extract(folder)
        if checkout is None:
            log(f"normal-matrix form not timed: {skipped}")
        for n_o, dense in [(n, False) for n in SCALING_N_O] + [(N_O, True)]:
            r = measure(n_o, folder, rng, dense=dense, checkout=checkout)
            if n_o == N_O and not dense:
                cli = [cli_once(r["tape_path"], r["deck_path"], folder, one_thread=flag)
                       for flag in (False, True)]
                log("tapp process: " + ", ".join(f"{c['wall_s']:.2f} s" for c in cli))
            r.pop("tape_path").unlink()
            r.pop("v3_path").unlink()
            r.pop("v2_path").unlink()
            r.pop("deck_path")
            results.append(r)
        compiled = legacy.cache_files(folder / "normal-form-cache")
    load_after = os.getloadavg()
    main = next(r for r in results if r["n_o"] == N_O and not r["dense"])
    scaling = [r for r in results if not r["dense"]]
    growth = ", ".join(f"{r['full_s'] / scaling[0]['full_s']:.1f}x at n_o = {r['n_o']}"
                       for r in scaling[1:])
    if checkout is None:
        normal_note = f"Normal-matrix form not timed: {skipped}."
    else:
        normal_note = (
            f"Normal-matrix form: the processor of commit {checkout.commit[:7]} "
            "(`git archive` of tapp, search, iter into a temporary folder) in a child "
            "process with only that folder on its path, on the version-2 tape of the same "
            "data, the same decks, timed the same way (the child's imports excluded); "
            + ("it compiled nothing." if not compiled else
               f"NOTE: it compiled {', '.join(compiled)}."))
    targets = {
        "full_s": (main["full_s"], TARGET_S),
        "ratio_to_normal": (main["ratio_to_normal"], TARGET_NORMAL_RATIO),
        "ratio_to_peer": (main["ratio_to_peer"], TARGET_PEER_RATIO)}
    md = "\n".join([
        "## TAPP III: matrix processor on synthetic T13 tapes",
        "",
        f"Synthetic tapes: {N_RECORDS} records of {RECORD_STEP_S:.0f} s, {N_STATIONS} stations, "
        f"{STATIONS_PER_RECORD} stations per record, epochs at {N_EPOCHS} times; per pair "
        "R = triangularize(G), G: 3 random rows over the orbit, "
        f"{N_DYNAMIC} dynamic constants and the pair's own station parameters (ΔJ = RᵀR), "
        "R̃ = √2 R with parts R, √0.6 R, √0.4 R, symplectic U; written as version 4 (the "
        "factors, LZ4: the writer's default), version 3 (the factors, gzip: the layout "
        "before) and version 2 (their normal matrices, gzip), TR packing, read lazily. "
        "Deck: σ tables over all parameters, "
        f"{len(FIXED)} fixed in the fit world, {N_PRINTS} print times x {len(PRINT_COMMANDS)} "
        "entities (covariances with error budgets, normal matrices, partials), "
        f"{N_RECYCLES} recycles with the 9 standard commands. Wall time of open + bind + "
        f"process, best of {REPEATS} after a warm-up. Targets at n_o = {N_O}: < "
        f"{TARGET_S:.0f} s, square-root / normal-matrix form <= {TARGET_NORMAL_RATIO}x, "
        f"square-root / NumPy peer <= {TARGET_PEER_RATIO:.0f}x. Load average (1 min) "
        f"{load_before[0]:.1f} before and {load_after[0]:.1f} after the section (2 logical "
        "CPUs; other work inflates times).",
        "",
        f"**n_o = {N_O}: square root {main['full_s']:.3f} s (< {TARGET_S:.0f} s: "
        f"{_verdict(main['full_s'], TARGET_S)}); normal-matrix form "
        f"{_fmt(main['normal_s'], '.3f')} s, ratio {_fmt(main['ratio_to_normal'], '.2f')}x "
        f"(<= {TARGET_NORMAL_RATIO}x: "
        f"{_verdict(main['ratio_to_normal'], TARGET_NORMAL_RATIO)}); NumPy peer "
        f"{main['peer_s']:.3f} s, ratio {main['ratio_to_peer']:.1f}x (<= "
        f"{TARGET_PEER_RATIO:.0f}x: {_verdict(main['ratio_to_peer'], TARGET_PEER_RATIO)})**; "
        f"{main['per_record_us']:.0f} us per record, {main['per_entity_ms']:.2f} ms per print "
        f"entity (with its budget), {main['all_entities']} entities in all; I/O floor "
        f"{main['io_floor_s']:.3f} s; on the version-3 tape {main['v3_s']:.3f} s, "
        f"{main['v3_ratio_to_peer']:.1f}x the peer (I/O floor {main['io_floor_v3_s']:.3f} s). "
        "`tapp process` end to end (child process, interpreter start, O3 printout and JSON "
        f"written, {cli[0]['o3_mb']:.1f} MB of O3): " + ", ".join(
            f"{c['wall_s']:.2f} s with "
            f"{'one BLAS thread' if c['one_thread'] else 'default BLAS threads'}"
            f" (peak RSS {c['peak_rss_mb']:.0f} MB)" for c in cli) + ". In-process runs: "
        f"OPENBLAS_NUM_THREADS={blas_threads}.",
        "",
        markdown_table(["n_o", "pairs", "tape v4 / v3 / v2 / packed (MB)", "square root (s)",
                        "normal form (s)", "sqrt / normal", "per record (us) sqrt / normal",
                        "per entity (ms)", "I/O floor (s)", "NumPy peer (s)", "sqrt / peer",
                        "on v3: sqrt (s) / I/O floor (s) / sqrt / peer",
                        "tracemalloc peak (MB)", "Λ' vs peer",
                        "Λ' vs normal form (first / last print)"],
                       [_row(r) for r in results]),
        "",
        f"Growth of the square-root wall time with n_o (from n_o = {scaling[0]['n_o']}): "
        f"{growth}. {normal_note} Per record: the run with one print (at the last record) "
        "and no recycles / n_IT. Per "
        f"entity: the {len(PRINT_COMMANDS)} print commands evaluated on the last record's "
        f"statistics (with their error budgets), / {len(PRINT_COMMANDS)}. I/O floor: "
        "reading and checking every pair block (R, R̃ and its parts) of the version-4 tape "
        "through the lazy reader. On v3: the same processor and reader on the version-3 "
        "tape of the same data (outputs bit-identical to the version-4 run's unless marked). "
        "NumPy peer: h5py reads of the version-2 tape's ΔJ, ΔJ̃ per "
        "print interval, one Cholesky regression and the ten products per print time, in one "
        "representation, without recycles, budget or parts (2/5 of the bytes), BLAS on one "
        "thread as in TAPP III. Λ' vs peer: "
        "max relative difference of the fit covariance of the fitted parameters at the first "
        "print time; Λ' vs normal form: the same against the normal-matrix form's, at the "
        "first and the last print time (after the epoch changes and recycles). Dense G: "
        "every column observed (R: 3 full rows), the worst case for the compression (and "
        "the reading).",
    ])
    data = {"target_s": TARGET_S, "target_ratio_to_normal": TARGET_NORMAL_RATIO,
            "target_ratio_to_peer": TARGET_PEER_RATIO, "n_o": N_O,
            "on_target": {key: (None if v is None else v <= t)
                          for key, (v, t) in targets.items()},
            "normal_form": {"commit": None if checkout is None else checkout.commit,
                            "skipped": skipped or None, "compiled": compiled},
            "results": results, "cli": cli,
            "openblas_num_threads": blas_threads, "load_average": [load_before, load_after],
            "config": {"n_records": N_RECORDS, "n_stations": N_STATIONS,
                       "stations_per_record": STATIONS_PER_RECORD, "n_epochs": N_EPOCHS,
                       "n_dynamic": N_DYNAMIC, "n_prints": N_PRINTS,
                       "print_commands": list(PRINT_COMMANDS), "n_recycles": N_RECYCLES,
                       "part_shares": list(PART_SHARES), "fixed": list(FIXED),
                       "repeats": REPEATS, "seed": SEED}}
    return Section(NAME, md, data)


if __name__ == "__main__":
    print(run().markdown)
