"""Shell-style patterns of parameter names in the deck's σ tables and budget groups
(:func:`fnmatch.fnmatchcase`; the rule is in the module docstring of
:mod:`tapp.processor.deck`): a deck with patterns runs exactly as the deck with every name
spelled out, an explicit key beats a pattern, and patterns that match nothing or disagree are
refused naming their field. Everything here binds or runs the 3-hour LEO tape of the helpers
(23 parameters: the orbit, GM_km3_s2, J2, and QUITO, KOUROU, MALINDI with location and biases).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind
from tapp.processor.printout import o3_text, run_dict
from tests.tapp.processor.helpers import deck, leo_tape, run, sigmas

#: What the runs print: the real-world covariance of the orbit (with its error budget) at
#: every print time, and all 23 parameters mapped to the epoch.
PRINTS = {"times": {"print": [1, 2, 3]},
          "commands": {"print": ["cov real orbit@current", "cov-real o@epoch"]}}
#: The σ's of the helpers (tests.tapp.processor.helpers.SIGMA, SIGMA_STATION), with 5 m for
#: the stations' Cartesian components (:data:`STATION_XYZ`; 1 km in the helpers, whose tables
#: take the orbit's σ for them), by explicit names and patterns. The fit world: GM held fixed
#: (σ = 0), explicit names for what differs from 5 m, and "*" for the rest (the stations'
#: location components other than longitudes, and the range biases).
FIT_PATTERNS = {"GM_km3_s2": 0.0, "x_km": 1.0, "y_km": 1.0, "z_km": 1.0, "vx_km_s": 1e-3,
                "vy_km_s": 1e-3, "vz_km_s": 1e-3, "J2": 1e-8, "QUITO.lon_rad": 1e-6,
                "MALINDI.lon_rad": 1e-6, "QUITO.range_rate_bias_km_s": 1e-6,
                "KOUROU.range_rate_bias_km_s": 1e-6, "MALINDI.range_rate_bias_km_s": 1e-6,
                "*": 0.005}
#: The real world: patterns only, two of them overlapping with one σ, and the range-rate
#: biases certain (σ = 0: three parameters moved to the end of the real system, in tape order).
REAL_PATTERNS = {"?_km": 1.0, "v?_km_s": 1e-3, "GM_km3_s2": 0.01, "J2": 1e-8,
                 "*.range_rate_bias_km_s": 0.0, "*.lon_rad": 1e-6, "*.[xyz]_km": 0.005,
                 "*.*_km": 0.005}
STATION_XYZ = ("QUITO.z_km", "KOUROU.x_km", "KOUROU.y_km", "KOUROU.z_km", "MALINDI.z_km")
RATE_BIASES = ("QUITO.range_rate_bias_km_s", "KOUROU.range_rate_bias_km_s",
               "MALINDI.range_rate_bias_km_s")
#: Budget groups by pattern, and the same groups spelled out in the order the patterns give
#: (each pattern's matches in tape order, at its place).
GROUPS_PATTERNS = {"locations": ["*.spin_radius_km", "*.lon_rad", "*.z_km", "KOUROU.[xy]_km"],
                   "biases": ["*bias*"]}
GROUPS_NAMES = {"locations": ["QUITO.spin_radius_km", "MALINDI.spin_radius_km",
                              "QUITO.lon_rad", "MALINDI.lon_rad", "QUITO.z_km", "KOUROU.z_km",
                              "MALINDI.z_km", "KOUROU.x_km", "KOUROU.y_km"],
                "biases": ["QUITO.range_bias_km", "QUITO.range_rate_bias_km_s",
                           "KOUROU.range_bias_km", "KOUROU.range_rate_bias_km_s",
                           "MALINDI.range_bias_km", "MALINDI.range_rate_bias_km_s"]}


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


def _bind(tape, doc: dict):
    return bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


def _refused(tape, doc: dict) -> InputError:
    with pytest.raises(InputError) as info:
        _bind(tape, doc)
    return info.value


def _printed(tape, doc: dict) -> tuple[str, str]:
    """The O3 printout and the JSON of a run of ``doc``: every printed number."""
    header = memory_pairs(tape).header
    out = run(tape, doc)
    return (o3_text(out, header, "deck.toml", "tape.t13"),
            json.dumps(run_dict(out, header, "deck.toml", "tape.t13")))


def _apriori_sigma(tape, fit: dict) -> np.ndarray:
    """The fit world's a priori σ's of a σ table with no σ = 0 (tape order)."""
    doc = deck(tape, fit=fit)
    doc["tape"] = {"parameters": list(tape.parameters.name)}  # positions may be used
    return 1.0 / np.sqrt(np.diag(_bind(tape, doc).S0))


def test_patterns_print_exactly_what_the_names_spelled_out_print(tape):
    five_m = dict.fromkeys(STATION_XYZ, 0.005)
    spelled = deck(tape, fit=sigmas(tape, GM_km3_s2=0.0, **five_m),
                   real=sigmas(tape, **five_m, **dict.fromkeys(RATE_BIASES, 0.0)), **PRINTS)
    patterns = deck(tape, fit=FIT_PATTERNS, real=REAL_PATTERNS, **PRINTS)
    a, b = _bind(tape, spelled), _bind(tape, patterns)
    np.testing.assert_array_equal(a.S0, b.S0)
    np.testing.assert_array_equal(a.Lambda0, b.Lambda0)
    assert a.systems.system_names(6) == b.systems.system_names(6)
    assert b.systems.system_names(6)[-3:] == list(RATE_BIASES)
    assert _printed(tape, patterns) == _printed(tape, spelled)


def test_an_explicit_name_or_position_beats_a_pattern(tape):
    names = list(tape.parameters.name)
    got = _apriori_sigma(tape, {"*": 1.0, "x_km": 7.0, "2": 3.0, "*.x_km": 2.0,
                                "KOUROU.x_km": 5.0})
    want = np.ones(len(names))
    want[[0, 1, names.index("KOUROU.x_km")]] = [7.0, 3.0, 5.0]
    np.testing.assert_array_equal(got, want)


def test_two_patterns_with_one_sigma_for_a_parameter_are_accepted(tape):
    np.testing.assert_array_equal(_apriori_sigma(tape, {"*": 1.0, "*_km": 1.0}),
                                  np.ones(tape.n_o))


def test_the_deck_is_left_as_given_and_binds_again_the_same(tape):
    doc = validate(Deck, deck(tape, fit=FIT_PATTERNS, real=REAL_PATTERNS), "deck.toml")
    header = memory_pairs(tape).header
    first, second = (bind(doc, header, "deck.toml") for _ in range(2))
    assert doc.fit.apriori.sigma == FIT_PATTERNS
    np.testing.assert_array_equal(first.Lambda0, second.Lambda0)


@pytest.mark.parametrize("world", ["fit", "real"])
def test_a_pattern_that_matches_no_parameter_is_refused(tape, world):
    doc = deck(tape, **{world: {**sigmas(tape), "*.zenith_wet_km": 1e-3}})
    err = _refused(tape, doc)
    assert err.field == f"{world}.apriori.sigma.*.zenith_wet_km"
    assert err.expected.startswith("a pattern that matches at least one parameter of the tape")
    assert err.got == "*.zenith_wet_km"


@pytest.mark.parametrize("world", ["fit", "real"])
def test_two_patterns_with_different_sigmas_for_a_parameter_are_refused(tape, world):
    err = _refused(tape, deck(tape, **{world: {"*": 1.0, "*_km": 2.0}}))
    assert err.field == f"{world}.apriori.sigma.*_km"
    assert "x_km" in err.expected and "'*'" in err.expected and "'*_km'" in err.expected
    assert err.got == 2.0


def test_a_pattern_keeps_the_station_blocks_refusal(tape):
    doc = deck(tape, real={"*": 1e-3})
    doc["real"]["apriori"]["stations"] = {"station": {"QUITO": {"sigma_m": [0.03, 0.03, 0.05]}}}
    err = _refused(tape, doc)
    assert err.field == "real.apriori.sigma.QUITO.spin_radius_km"
    assert err.expected.startswith("no σ for a station location given by real.apriori.stations")


def test_budget_groups_by_pattern_are_the_groups_by_name(tape):
    by_name = deck(tape, budget={"groups": GROUPS_NAMES}, **PRINTS)
    by_pattern = deck(tape, budget={"groups": GROUPS_PATTERNS}, **PRINTS)
    assert _bind(tape, by_pattern).budget_groups == _bind(tape, by_name).budget_groups
    budgets = [[e.budget for b in run(tape, doc).blocks for e in b.entities if e.budget]
               for doc in (by_name, by_pattern)]
    assert len(budgets[0]) == len(budgets[1]) > 0
    for a, b in zip(*budgets, strict=True):
        assert a.sources == b.sources and "biases (a priori)" in a.sources
        np.testing.assert_array_equal(a.variances, b.variances)


def test_a_budget_group_counts_a_parameter_once_whatever_matches_it(tape):
    groups = {"QUITO": ["QUITO.range_bias_km", "QUITO.*", "*.lon_rad"]}
    spelled = {"QUITO": ["QUITO.range_bias_km", "QUITO.spin_radius_km", "QUITO.lon_rad",
                         "QUITO.z_km", "QUITO.range_rate_bias_km_s", "MALINDI.lon_rad"]}
    assert (_bind(tape, deck(tape, budget={"groups": groups})).budget_groups
            == _bind(tape, deck(tape, budget={"groups": spelled})).budget_groups)


def test_a_budget_pattern_that_matches_no_parameter_is_refused(tape):
    err = _refused(tape, deck(tape, budget={"groups": {"media": ["*.zenith_wet_km"]}}))
    assert err.field == "budget.groups.media"
    assert err.expected.startswith("a pattern that matches at least one parameter of the tape")


@pytest.mark.parametrize(("table", "field"), [
    ({"real": {"apriori": {"correlation": [["*.lon_rad", "x_km", 0.1]]}}},
     "real.apriori.correlation[0]"),
    ({"fit": {"permutation": [[8, "*.lon_rad"]]}}, "fit.permutation[0]"),
    ({"fit": {"fixed": ["GM*"]}}, "fit.fixed[0]"),
])
def test_correlations_permutations_and_lists_take_no_patterns(tape, table, field):
    doc = deck(tape)
    for world, change in table.items():
        doc[world]["apriori"].update(change.get("apriori", {}))
        doc[world].update({k: v for k, v in change.items() if k != "apriori"})
    err = _refused(tape, doc)
    assert err.field == field
    assert err.expected.startswith("a parameter name of the tape")
