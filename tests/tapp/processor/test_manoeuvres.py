"""TAPP III with manoeuvres: the deck's modes for the execution errors, each burn a source of
the error budget, and the real-world covariance against a Monte Carlo of the burns' errors on
the raw rows.

Monte Carlo (as test_stochastic.py, with its machinery: tests/tapp/processor/helpers.py): draw
the a priori errors δx ~ N(0, Λ̄), the execution errors of each burn from Gates' σ's as
written here from the scenario (independent unit normals times σ₁, σ₂, σ₃, σ₃, σ₄, σ₄, not the
tape's a priori), and the real-world noise δm ~ N(0, M); form the data errors A δx + δm by the
raw partial rows; run the fit-world estimator (batch least squares with white weights, GM held
fixed, the execution errors ignored = held at 0, or estimated with the a priori information
diag(1/σ²): the manoeuvres reconstructed); compare the sample covariance of δx − μ'δx with
TAPP III's real-world covariance at every print time. Statistical test: each entry's z-score
|Ĉ − C| / sd(Ĉ), sd² = (C_ii C_jj + C_ij²)/N, must be < 5; over the 2 modes x 3 prints x 630
distinct entries (n_o = 35) = 3,780 entries the family-wise false-alarm probability is below
3,780 x 5.7e-7 = 2.2e-3 (Bonferroni). Measured: largest |z| 3.2; against the real world without
the execution errors the same sample gives z up to 1.2e8 (their errors ignored by the fit) and
196 (estimated).
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind
from tests.tapp.processor.helpers import (
    Z_LIMIT,
    deck,
    edit_deck,
    leo_tape,
    real_world_monte_carlo,
    run,
    sigmas,
)
from tests.tapp.tracking.test_manoeuvres import MANOEUVRES

#: Gates' σ's of both burns in the scenario's units (test_manoeuvres.SIGMAS), in the tape's:
#: 1 %, 5 mm/s, 10 mrad, 5 mm/s.
GATES = (0.01, 5e-6, 0.01, 5e-6)
#: The six parameters of a burn draw σ₁, σ₂, σ₃, σ₃, σ₄, σ₄ (Gates' pointing on two axes).
SIX = np.array([GATES[0], GATES[1], GATES[2], GATES[2], GATES[3], GATES[3]])


@pytest.fixture(scope="module")
def tape():
    return leo_tape(manoeuvre=MANOEUVRES)


def _execution(tape) -> list[int]:
    return [i for i, k in enumerate(tape.parameters.kind) if k == "execution"]


def _base_sigmas(tape) -> dict[str, float]:
    return {k: v for k, v in sigmas(tape).items() if not k.startswith(("TCM1.", "BURN."))}


def _deck(tape, fit_mode: str, real_mode: str, **tables) -> dict:
    base = _base_sigmas(tape)
    doc = deck(tape, fit={**base, "GM_km3_s2": 0.0}, real=base, **tables)
    doc["fit"]["manoeuvres"] = fit_mode
    doc["real"]["manoeuvres"] = real_mode
    return doc


def _plan(tape, doc):
    return bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


def test_the_modes_give_gates_a_priori_to_the_worlds_that_have_them(tape):
    names = list(tape.parameters.name)
    ex = _execution(tape)
    assert len(ex) == 12 and names[ex[0]] == "TCM1.mag_prop"
    plan = _plan(tape, _deck(tape, "estimate", "include"))
    order_f = plan.systems.system_names(4)[:plan.systems.n_f1]
    at = [order_f.index(names[i]) for i in ex]
    # (5 mm/s × 1e-6 is 5e-6 km/s to rounding)
    np.testing.assert_allclose(plan.S0[np.ix_(at, at)], np.diag(1.0 / np.tile(SIX, 2) ** 2),
                               rtol=1e-15, atol=0)
    order_r = plan.systems.system_names(6)[:plan.systems.n_r1]
    at = [order_r.index(names[i]) for i in ex]
    np.testing.assert_allclose(plan.Lambda0[np.ix_(at, at)], np.diag(np.tile(SIX, 2) ** 2),
                               rtol=1e-15, atol=0)
    assert ("manoeuvre TCM1", tuple(at[:6])) in plan.budget_groups
    assert ("manoeuvre BURN", tuple(at[6:])) in plan.budget_groups
    ignore = _plan(tape, _deck(tape, "ignore", "ignore"))
    assert ignore.systems.n_f1 == plan.systems.n_f1 - 12
    assert ignore.systems.n_r1 == plan.systems.n_r1 - 12
    assert not any(label.startswith("manoeuvre") for label, _ in ignore.budget_groups)


@pytest.mark.parametrize(("change", "message"), [
    ({"fit": {"manoeuvres": "estimate", "apriori": {"sigma": {"TCM1.mag_prop": 0.01}}}},
     'fit.apriori.sigma.TCM1.mag_prop: expected no σ for an execution error \\(its a priori '
     'comes from the tape with fit.manoeuvres = "estimate"\\)'),
    ({"real": {"manoeuvres": "include", "apriori": {"correlation": [["BURN.mag_prop", "x_km",
                                                                       0.1]]}}},
     "real.apriori.correlation\\[0\\]: expected no execution error \\(Gates' errors are "
     "independent\\)"),
    ({"real": {"manoeuvres": "include", "certain": ["TCM1.mag_prop"]}},
     "real.manoeuvres: expected the execution errors in the real world's set"),
])
def test_bad_manoeuvre_decks_are_input_errors(tape, change, message):
    with pytest.raises(InputError, match=message):
        _plan(tape, edit_deck(_deck(tape, "ignore", "ignore"), change))


def test_a_tape_without_burns_refuses_the_modes():
    plain = leo_tape()
    doc = deck(plain, fit=sigmas(plain), real=sigmas(plain))
    doc["fit"]["manoeuvres"] = "estimate"
    with pytest.raises(InputError, match='fit.manoeuvres: expected "ignore" \\(the tape has no '
                       'manoeuvres with execution errors\\)'):
        _plan(plain, doc)


def test_each_burn_is_a_source_of_the_error_budget_and_the_budget_closes(tape):
    out = run(tape, _deck(tape, "ignore", "include", times={"print": [2, 3]},
                          commands={"print": ["cov-real o@epoch"]}))
    ent = out.blocks[-1].entities[0]
    sources = ent.budget.sources
    assert "manoeuvre TCM1 (a priori)" in sources and "manoeuvre BURN (a priori)" in sources
    b = ent.budget
    closure = np.max(np.abs(b.variances.sum(axis=0) - b.total) / b.total)
    assert closure < 1e-9, closure  # measured 6.9e-16
    # ignored by the fit, the first burn's errors are a visible share of the epoch state's
    # error (measured 0.7 % of a position variance)
    burn = b.variances[sources.index("manoeuvre TCM1 (a priori)")]
    assert np.max(burn[:3] / b.total[:3]) > 1e-3


def test_real_world_covariance_matches_a_monte_carlo_of_the_burns(tape):
    assert tape.raw is not None and np.all(tape.records.j == 0)
    worst = real_world_monte_carlo(tape, _execution(tape), np.diag(np.tile(SIX, 2) ** 2),
                                   _base_sigmas(tape), lambda f, r, **t: _deck(tape, f, r, **t),
                                   seed=20261203)
    for mode, (z, without) in worst.items():
        assert 1.0 < z < Z_LIMIT, (mode, z)  # a sample, that agrees
        # power: the real world without the execution errors fails the same sample
        assert without > 10 * Z_LIMIT, (mode, without)
