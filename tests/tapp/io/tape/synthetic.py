"""Synthetic tapes of any size for the tape tests (random values of the right structure).

The tapes carry square-root information: every normal matrix or covariance is given by an
upper-triangular factor K with a non-negative diagonal (KᵀK = M), made here as the
triangularised stack of random rows (:func:`tapp.estimation.factors.triangularize`).
"""

from __future__ import annotations

import numpy as np

from tapp.estimation.factors import triangularize
from tapp.frames.time import Epoch
from tapp.io.tape.t13 import (
    T13,
    TapeMiss,
    TapePairs,
    TapeParameters,
    TapePasses,
    TapeRecords,
    TapeStations,
)
from tapp.io.tape.t32 import T32, T32Entity, T32Partition, T32Recycle

EPOCH = Epoch.from_calendar(2026, 3, 10, 12)
ORBIT = (("x_km", "km"), ("y_km", "km"), ("z_km", "km"), ("vx_km_s", "km/s"),
         ("vy_km_s", "km/s"), ("vz_km_s", "km/s"))


def parameters(n_o: int) -> TapeParameters:
    """Six orbit parameters, then constants q1_km.. (n_o >= 6)."""
    names = [n for n, _ in ORBIT] + [f"q{i}_km" for i in range(1, n_o - 5)]
    units = [u for _, u in ORBIT] + ["km"] * (n_o - 6)
    kinds = ["orbit"] * 6 + ["dynamic"] * (n_o - 6)
    return TapeParameters(tuple(names), tuple(units), tuple(kinds), np.zeros(n_o, dtype=int),
                          np.linspace(1.0, 2.0, n_o))


def factors(rng: np.random.Generator, lead: tuple[int, ...], n: int, rank: int = 4,
            scale: float = 1.0) -> np.ndarray:
    """Random upper-triangular factors (*lead, n, n), diagonal >= 0: the triangularised
    ``rank`` rows of ``scale`` times N(0, 1) entries (so KᵀK is positive semi-definite of that
    rank, the rows of K below ``rank`` zero when rank < n)."""
    rows = scale * rng.normal(size=(*lead, rank, n))
    flat = rows.reshape(-1, rank, n)
    return np.array([triangularize(a) for a in flat]).reshape(*lead, n, n)


def t13_tape(rng: np.random.Generator, *, n_o: int = 8, n_it: int = 6, n_ts: int = 3,
             skip: float = 0.3) -> T13:
    """A valid T13 tape; each (record, station) pair has data with probability 1 - skip."""
    n_p, n_m = 6, 3
    keep = rng.random((n_it, n_ts)) >= skip
    keep[0, 0] = True
    k, station = (v + 1 for v in np.nonzero(keep))  # row-major: sorted by (k, station)
    n_pairs = k.size
    parts = factors(rng, (n_pairs, 3), n_o)
    parts[:, 1] *= np.sqrt(0.1)  # the bias part a tenth of the others
    total = np.array([triangularize(*p) for p in parts])  # R̃ᵀR̃ = the sum of the parts'
    times = np.arange(n_it + 1) * 600.0
    is_epoch = np.zeros(n_it + 1, dtype=bool)
    is_epoch[[0, n_it // 2]] = True
    j = np.maximum.accumulate(np.where(is_epoch[:-1], np.arange(n_it), 0))
    return T13(
        iden="SYNTHETIC", epoch=EPOCH, n_p=n_p, parameters=parameters(n_o),
        stations=TapeStations(np.arange(1, n_ts + 1), tuple(f"S{i}" for i in range(n_ts)),
                              ("range",) * n_ts, np.zeros(n_ts), np.linspace(0, 90, n_ts),
                              np.zeros(n_ts), np.full(n_ts, 5.0)),
        miss=TapeMiss("equinoctial", 3600.0, ("a_km", "ex", "ey"), ("km", "", ""),
                      np.ones(n_m), rng.normal(size=(n_m, n_o))),
        records=TapeRecords(times, is_epoch, ~is_epoch | (times == 0), j,
                            np.arange(1, n_it + 1), rng.normal(size=(n_it, 6)),
                            rng.normal(size=(n_it, n_p, n_o))),
        pairs=TapePairs(k, station, rng.integers(1, 100, n_pairs),
                        factors(rng, (n_pairs,), n_o), total, parts),
        passes=TapePasses(np.array([1]), np.array([10.0]), np.array([500.0]), np.array([20])),
        provenance={"scenario": "{}", "scenario_source": "synthetic"},
    )


def symmetric(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    """A random symmetric positive-definite n x n matrix, exactly symmetric."""
    a = rng.normal(size=(n + 2, n))
    m = scale * (a.T @ a)
    return 0.5 * (m + m.T)


def factor(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    """A random upper-triangular n x n factor, diagonal > 0, of a positive-definite matrix:
    the triangularised n + 2 rows of N(0, ``scale``) entries (KᵀK about ``scale`` times that
    of unit rows, as :func:`symmetric` of the same scale)."""
    return factors(rng, (), n, rank=n + 2, scale=np.sqrt(scale))


def transition(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A random invertible n x n transition T = Q diag(d) and its adjoint T⁻ᵀ = Q diag(1/d),
    Q orthogonal, d in [1/e, e] (condition number <= e²): the adjoint in closed form, not by
    the solve the version-1 reader uses."""
    q = np.linalg.qr(rng.normal(size=(n, n)))[0]
    d = np.exp(rng.uniform(-1.0, 1.0, n))
    return q * d, q / d


def t32_tape(rng: np.random.Generator, *, n_o: int = 9, n_recycles: int = 3) -> T32:
    """A valid T32 tape: six orbit parameters and n_o - 6 constants, three miss parameters,
    the fit system permuting the constants, recycles at k = 2, 4, 6, ..."""
    par = parameters(n_o)
    perm = np.r_[np.arange(6), 6 + np.arange(n_o - 6)[::-1]]
    chain_fit = np.eye(n_o)[perm]
    names = {"common": par.name, "fit": tuple(par.name[i] for i in perm), "real": par.name}
    miss = ("a_km", "ex", "ey")
    partitions = (
        T32Partition("pk", "standard", 0, 6, par.name[:6]),
        T32Partition("fp", "fit", 0, 6, names["fit"][:6]),
        T32Partition("fq", "fit", 6, n_o - 1, names["fit"][6:n_o - 1]),
        T32Partition("fz", "fit", n_o - 1, n_o, names["fit"][n_o - 1:]),
        T32Partition("f2", "fit", n_o, n_o, ()),
        T32Partition("r1", "real", 0, n_o, par.name),
        T32Partition("m1", "miss", 0, 2, miss[:2]),
    )
    recycles = []
    for i in range(n_recycles):
        k, last = 2 * (i + 1), 2 * i
        t, t_adjoint = transition(rng, n_o)
        entities = (
            T32Entity(1, "I; 0,-,pk; 1,2,fp", "partials pk wrt fp@recycle", par.name[:6],
                      names["fit"][:6], rng.normal(size=(6, 6))),
            T32Entity(3, "I; 0,-,pk; 1,2,f2", "partials pk wrt f2@recycle", par.name[:6], (),
                      np.zeros((6, 0))),
            T32Entity(4, "J; 1,2,f1; 1,2,f1", "J f1", names["fit"][:n_o - 1],
                      names["fit"][:n_o - 1], symmetric(rng, n_o - 1)),
        )
        recycles.append(T32Recycle(
            number=i + 1, k=k, l=last, j=max(0, last - 1), t_s=600.0 * k, t_l_s=600.0 * last,
            info=rng.normal(size=6), S_fit_factor=factor(rng, n_o),
            Lambda_fit_factor=factor(rng, n_o), Lambda_real_factor=factor(rng, n_o, 2.0),
            L=rng.normal(size=(n_o, n_o)), Sigma_factor=factor(rng, n_o, 0.1),
            J_factor=factor(rng, n_o), Jt_factor=factor(rng, n_o), B=rng.normal(size=(3, n_o)),
            transition=t, transition_adjoint=t_adjoint, entities=entities))
    return T32(
        iden="SYNTHETIC", epoch=EPOCH, n_p=6, parameters=par, miss_name=miss,
        miss_unit=("km", "", ""),
        systems={"common": np.eye(n_o), "fit": chain_fit, "real": np.eye(n_o)},
        system_names=names, partitions=partitions, S0_fit_factor=factor(rng, n_o, 1e-3),
        Lambda0_real_factor=factor(rng, n_o, 1e3), recycles=tuple(recycles),
        provenance={"deck": '{"recycle": [2, 4, 6]}', "deck_source": "deck.toml",
                    "t13_source": "run.t13.h5", "t13_iden": "SYNTHETIC"})
