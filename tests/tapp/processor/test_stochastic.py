"""TAPP III with stochastic accelerations: the deck's modes, and the real-world covariance
against a Monte Carlo of the same process on the raw rows.

Monte Carlo (as test_monte_carlo.py): draw the a priori errors δx ~ N(0, Λ̄) (the
accelerations from their Gauss-Markov covariance, written here from the closed form
σ² exp(−|t̄_j − t̄_k|/τ) over the intervals' mid-times, independently of the package) and the
real-world noise δm ~ N(0, M); form the data errors A δx + δm by the raw partial rows; run the
fit-world estimator (batch least squares with white weights, GM held fixed, the accelerations
ignored = held at 0, or estimated with the a priori information P⁻¹); compare the sample
covariance of δx − μ'δx with TAPP III's real-world covariance at every print time.
Statistical test: each entry's z-score |Ĉ − C| / sd(Ĉ), sd² = (C_ii C_jj + C_ij²)/N, must be
< 5; over the 2 modes x 3 prints x 496 distinct entries = 2,976 entries the family-wise
false-alarm probability is below 2,976 x 5.7e-7 = 1.7e-3 (Bonferroni).
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.io.tape.t32 import validate as validate_t32
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind
from tapp.processor.sequencing import process
from tapp.processor.tape32 import build_t32
from tests.tapp.processor.helpers import (
    Z_LIMIT,
    deck,
    edit_deck,
    leo_tape,
    real_world_monte_carlo,
    sigmas,
)

#: 1e-5 m/s² over 3600 s intervals moves the LEO state by ~0.5 a t² = 65 m per interval, 3 to
#: 4 times the range noise: large enough for the test to tell a covariance without them.
STOCHASTIC = {"frame": "ric", "interval_s": 3600.0, "sigma_m_s2": 1e-5, "tau_s": 5400.0}
SIGMA_KM_S2 = 1e-8
TAU_S = 5400.0


@pytest.fixture(scope="module")
def tape():
    return leo_tape(stochastic=STOCHASTIC)


def _prior(tape) -> np.ndarray:
    """The accelerations' covariance from the closed form, interval-major (R, I, C)."""
    b = np.asarray(tape.stochastic.boundaries_s)
    mid = 0.5 * (b[:-1] + b[1:])
    time = SIGMA_KM_S2**2 * np.exp(-np.abs(mid[:, None] - mid[None, :]) / TAU_S)
    return np.kron(time, np.eye(3))


def _base_sigmas(tape) -> dict[str, float]:
    return {k: v for k, v in sigmas(tape).items() if not k.startswith("acc_")}


def _deck(tape, fit_mode: str, real_mode: str, **tables) -> dict:
    base = _base_sigmas(tape)
    doc = deck(tape, fit={**base, "GM_km3_s2": 0.0}, real=base, **tables)
    doc["fit"]["stochastic"] = fit_mode
    doc["real"]["stochastic"] = real_mode
    return doc


def _plan(tape, doc):
    return bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


def test_the_modes_give_the_gauss_markov_block_to_the_worlds_that_have_them(tape):
    names = list(tape.parameters.name)
    stoch = [i for i, k in enumerate(tape.parameters.kind) if k == "stochastic"]
    assert len(stoch) == 9 and names[stoch[0]] == "acc_R_001"
    p = _prior(tape)
    plan = _plan(tape, _deck(tape, "estimate", "include"))
    order_f = plan.systems.system_names(4)[:plan.systems.n_f1]
    at = [order_f.index(names[i]) for i in stoch]
    # P⁻¹ against the inverse of the closed form (its condition ~1e2: rounding 1e-13)
    np.testing.assert_allclose(plan.S0[np.ix_(at, at)] @ p, np.eye(9), atol=1e-12)
    order_r = plan.systems.system_names(6)[:plan.systems.n_r1]
    at = [order_r.index(names[i]) for i in stoch]
    np.testing.assert_allclose(plan.Lambda0[np.ix_(at, at)], p, rtol=1e-14, atol=0)
    ignore = _plan(tape, _deck(tape, "ignore", "ignore"))
    assert ignore.systems.n_f1 == plan.systems.n_f1 - 9
    assert ignore.systems.n_r1 == plan.systems.n_r1 - 9
    assert ("stochastic accelerations", tuple(at)) in plan.budget_groups


@pytest.mark.parametrize(("change", "message"), [
    ({"fit": {"stochastic": "estimate", "apriori": {"sigma": {"acc_R_001": 1e-9}}}},
     "fit.apriori.sigma.acc_R_001: expected no σ for a stochastic"),
    ({"real": {"stochastic": "include", "apriori": {"correlation": [["acc_R_001", "x_km",
                                                                       0.1]]}}},
     "real.apriori.correlation\\[0\\]: expected no stochastic"),
    ({"fit": {"stochastic": "estimate"}, "common": {"eliminated": ["acc_I_002"]}},
     "fit.stochastic: expected the stochastic accelerations in the fit world's set"),
    ({"real": {"stochastic": "include", "apriori": {"covariance": [[1.0]]}}},
     "real.apriori.sigma: expected a σ table"),
])
def test_bad_stochastic_decks_are_input_errors(tape, change, message):
    with pytest.raises(InputError, match=message):
        _plan(tape, edit_deck(_deck(tape, "ignore", "ignore"), change))


def test_a_tape_without_them_refuses_the_modes():
    plain = leo_tape()
    doc = deck(plain, fit=sigmas(plain), real=sigmas(plain))
    doc["real"]["stochastic"] = "include"
    with pytest.raises(InputError, match="real.stochastic: expected \"ignore\" \\(the tape "
                       "has no stochastic"):
        _plan(plain, doc)


def test_real_world_covariance_matches_a_monte_carlo_with_stochastic_accelerations(tape):
    assert tape.raw is not None and np.all(tape.records.j == 0)
    stoch = [i for i, k in enumerate(tape.parameters.kind) if k == "stochastic"]
    worst = real_world_monte_carlo(tape, stoch, _prior(tape), _base_sigmas(tape),
                                   lambda f, r, **t: _deck(tape, f, r, **t), seed=20261126)
    for mode, (z, without) in worst.items():
        assert z < Z_LIMIT, (mode, z)
        # power: the real world without the accelerations fails the same sample
        assert without > 10 * Z_LIMIT, (mode, without)


def test_the_t32_transition_and_its_adjoint_agree_past_an_ended_interval(tape):
    """Recycles at 2 h and 3 h, after the first interval [0, 1 h) ended: the transition's
    column of acc_*_001 is exactly 0 but for the cancellation of sensitivities of ~1e7 km per
    km/s²; the tape's check |TᵀA − I| <= 1e-6 of the terms holds (with the adjoint formed from
    the two recycles' representations apart it failed: 4e-5 here, 0.86 on the deep-space
    example)."""
    doc = _deck(tape, "ignore", "include", times={"recycle": [2, 3]})
    data = memory_pairs(tape)
    plan = bind(validate(Deck, doc, "deck.toml"), data.header, "deck.toml")
    t32 = build_t32(process(data, plan), plan, data.header, {"deck_source": "deck.toml"})
    validate_t32(t32, "t.t32.h5")
    for rc in t32.recycles:
        n = rc.transition.shape[0]
        np.testing.assert_allclose(rc.transition.T @ rc.transition_adjoint, np.eye(n),
                                   rtol=0, atol=1e-6)
