"""Small tapes and decks for the TAPP III tests (the 3-hour LEO arc of the TAPP I tests)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tapp.io.schema import validate
from tapp.io.tape.t13 import T13, memory_pairs
from tapp.measurements.noise import RealNoise, covariance_block
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind, observations_used
from tapp.processor.sequencing import Run, process
from tapp.tracking.simulate import simulate
from tests.tapp.tracking.helpers import leo_scenario

#: The Monte Carlo tests of the real-world covariance (test_monte_carlo, test_stochastic):
#: draws, drawn in chunks of CHUNK, every entry's |z| below Z_LIMIT, at these print times.
N_DRAWS = 20_000
CHUNK = 2_000
Z_LIMIT = 5.0
PRINTS = (1, 2, 3)

#: A priori σ by parameter kind (km, km/s, km³/s², 1, rad, km/s biases).
SIGMA = {"x_km": 1.0, "y_km": 1.0, "z_km": 1.0, "vx_km_s": 1e-3, "vy_km_s": 1e-3,
         "vz_km_s": 1e-3, "GM_km3_s2": 0.01, "J2": 1e-8}
SIGMA_STATION = {"spin_radius_km": 0.005, "lon_rad": 1e-6, "z_km": 0.005, "x_km": 0.005,
                 "y_km": 0.005, "range_bias_km": 0.005, "range_rate_bias_km_s": 1e-6}
WHITE = {"sigma_range_m": 15.0, "sigma_range_rate_mm_s": 20.0}


def leo_tape(**tables) -> T13:
    """Simulate the LEO test scenario with :func:`leo_scenario` changes (raw rows kept)."""
    return simulate(leo_scenario(**tables), raw=True).tape


def sigmas(tape: T13, **overrides: float) -> dict[str, float]:
    """A σ table over every parameter of the tape (:data:`SIGMA`), with overrides."""
    out = {}
    for name in tape.parameters.name:
        key = name.split(".", 1)[1] if "." in name else name
        out[name] = overrides.get(name, SIGMA.get(key, SIGMA_STATION.get(key)))
    return out


def deck(tape: T13, *, fit: Mapping | None = None, real: Mapping | None = None,
         **tables) -> dict:
    """A deck document: a priori σ tables (fit and real) plus other tables."""
    doc = {"fit": {"apriori": {"sigma": dict(fit or sigmas(tape))}},
           "real": {"apriori": {"sigma": dict(real or sigmas(tape))}}}
    doc.update(tables)
    return doc


def run(tape: T13, doc: Mapping, source: str = "deck.toml") -> Run:
    """Bind a deck document to a tape and process it."""
    data = memory_pairs(tape)
    plan = bind(validate(Deck, doc, source), data.header, source)
    return process(data, plan, source=source)


def used(tape: T13, doc: Mapping) -> int:
    """The scalar observations of ``tape`` that a run with the deck document ``doc`` reads
    (:func:`tapp.processor.deck_bind.observations_used`)."""
    plan = bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")
    return observations_used(plan, tape.pairs.k, tape.pairs.station, tape.pairs.n_obs)


def final(run_: Run, alias: str) -> np.ndarray:
    """The matrix of the entity ``alias`` in the last print block."""
    block = [b for b in run_.blocks if b.kind == "print"][-1]
    return next(e.matrix for e in block.entities if e.command.alias() == alias
                or e.command.seed() == alias)


def scaled_err(a: np.ndarray, b: np.ndarray) -> float:
    """max |a_ij − b_ij| / √(b_ii b_jj): the natural scale of a covariance."""
    d = np.sqrt(np.abs(np.diag(b)))
    scale = np.outer(d, d)
    return float(np.max(np.abs(a - b) / np.where(scale > 0, scale, 1.0)))


def segment_factors(raw) -> list[tuple[np.ndarray, np.ndarray]]:
    """(rows, Cholesky factor of M) of every noise segment of the raw rows."""
    out = []
    for seg in np.unique(raw.segment):
        rows = np.flatnonzero(raw.segment == seg)
        real = RealNoise("range", float(np.sqrt(raw.m_white_var[rows[0]])),
                         float(np.sqrt(raw.m_bias_var[rows[0]])),
                         float(np.sqrt(raw.m_corr_var[rows[0]])), float(raw.m_tau_s[rows[0]]))
        m = covariance_block(raw.t_s[rows], real)
        out.append((rows, np.linalg.cholesky(m + 1e-30 * np.eye(rows.size))))
    return out


def fit_error_moments(raw, s0: np.ndarray, fitted: list[int], chol_bar: np.ndarray,
                      seed: int) -> dict[int, np.ndarray]:
    """E[e eᵀ] over N_DRAWS of the fit-world estimator's error at each print time k of PRINTS.

    Each draw takes δx = chol_bar ξ (the real world's a priori) and correlated noise δm per
    segment of the raw rows (:func:`segment_factors`), forms the residuals δz = A δx + δm, and
    the fit-world estimate from the rows up to record k with a priori information ``s0`` over
    the ``fitted`` parameters: e = δx − μ'δz on them, e = δx on the others.
    """
    n_o = raw.A.shape[1]
    wa = raw.weight[:, None] * raw.A
    gain = {}
    for k in PRINTS:
        rows = raw.record <= k
        j = raw.A[rows].T @ wa[rows]
        gain[k] = (rows, np.linalg.inv(s0 + j[np.ix_(fitted, fitted)]))
    factors = segment_factors(raw)
    rng = np.random.default_rng(seed)
    sums = {k: np.zeros((n_o, n_o)) for k in PRINTS}
    for _ in range(N_DRAWS // CHUNK):
        dx = rng.standard_normal((CHUNK, n_o)) @ chol_bar.T
        dm = np.empty((CHUNK, raw.t_s.size))
        for rows, chol in factors:
            dm[:, rows] = rng.standard_normal((CHUNK, rows.size)) @ chol.T
        dz = dx @ raw.A.T + dm                                   # residuals, (CHUNK, N_obs)
        for k in PRINTS:
            rows, lam = gain[k]
            rhs = dz[:, rows] @ wa[rows]                          # Aᵀ W δz per draw
            err = dx.copy()
            err[:, fitted] -= rhs[:, fitted] @ lam.T
            sums[k] += err.T @ err
    return {k: sums[k] / N_DRAWS for k in PRINTS}


def z_scores(sample: np.ndarray, c: np.ndarray, n_draws: int, skip: int | None = None
             ) -> np.ndarray:
    """|Ĉ − C| / sd(Ĉ) entry by entry, sd² = (C_ii C_jj + C_ij²)/N (Gaussian, zero mean)."""
    d = np.diag(c)
    sd = np.sqrt((np.outer(d, d) + c * c) / n_draws)
    z = np.divide(np.abs(sample - c), sd, out=np.zeros_like(c), where=sd > 0)
    if skip is not None:
        z[skip, :] = z[:, skip] = 0.0
    return z


def edit_deck(doc: dict, change: Mapping) -> dict:
    """Apply ``{table: changes}`` to a deck document :func:`deck` made: ``common`` is replaced;
    in a world's table the keys are set and its ``apriori`` entries applied (``sigma`` merged
    into the σ table, ``covariance`` replacing the a priori, others set)."""
    for world, table in change.items():
        if world == "common":
            doc[world] = table
            continue
        table = dict(table)
        apriori = table.pop("apriori", {})
        doc[world].update(table)
        for key, value in apriori.items():
            if key == "sigma":
                doc[world]["apriori"]["sigma"].update(value)
            elif key == "covariance":
                doc[world]["apriori"] = {"covariance": value}
            else:
                doc[world]["apriori"][key] = value
    return doc


def real_world_monte_carlo(tape: T13, generated: list[int], prior: np.ndarray,
                           base: Mapping[str, float], deck_of, seed: int
                           ) -> dict[str, tuple[float, float]]:
    """The Monte Carlo of a kind of parameters whose a priori the deck generates (stochastic
    accelerations, execution errors), at the indices ``generated`` of the tape with the
    covariance ``prior``: for each fit mode ("ignore", "estimate": a priori information
    prior⁻¹) with GM held fixed and the other parameters' σ from ``base``, the largest |z| of
    the sample covariance of the fit-world estimator's error (:func:`fit_error_moments`)
    against TAPP III's real world with them, over every entry and print time, and the largest
    against the real world without them (orbit rows). ``deck_of(fit_mode, real_mode,
    **tables)`` writes the deck."""
    names = list(tape.parameters.name)
    gm = names.index("GM_km3_s2")
    lam_bar = np.diag([base.get(n, 0.0) ** 2 for n in names])
    lam_bar[np.ix_(generated, generated)] = prior
    chol_bar = np.linalg.cholesky(lam_bar)
    tables = {"times": {"print": list(PRINTS)}, "commands": {"print": ["cov-real o@epoch"]}}

    def predicted(fit_mode: str, real_mode: str) -> dict[int, np.ndarray]:
        out = run(tape, deck_of(fit_mode, real_mode, **tables))
        return {b.k: b.entities[0].matrix for b in out.blocks if b.kind == "print"}

    out = {}
    for mode in ("ignore", "estimate"):
        fitted = [i for i in range(tape.n_o) if i != gm
                  and (mode == "estimate" or i not in generated)]
        s0 = np.diag([1.0 / base[names[i]] ** 2 if i not in generated else 0.0 for i in fitted])
        if mode == "estimate":
            at = [fitted.index(i) for i in generated]
            s0[np.ix_(at, at)] = np.linalg.inv(prior)
        moments = fit_error_moments(tape.raw, s0, fitted, chol_bar, seed=seed)
        real, without = predicted(mode, "include"), predicted(mode, "ignore")
        out[mode] = (max(float(np.max(z_scores(moments[k], real[k], N_DRAWS))) for k in PRINTS),
                     max(float(np.max(z_scores(moments[k], without[k], N_DRAWS, skip=None)
                                      [:6, :6])) for k in PRINTS))
    return out
