"""The deck names parameters as the scenario and the tape do (:mod:`tapp.dynamics.parameters`):
an earlier spelling (``GM`` for ``GM_km3_s2``) in a σ table, a fixed list or a correlation
triple binds to the same parameter, with a warning naming the field and the new spelling; a
name of no parameter of the tape is refused as before. Binds the 3-hour LEO tape of the
helpers (the orbit, GM_km3_s2, J2 and three stations)."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import DeprecatedSpelling, InputError
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind
from tests.tapp.processor.helpers import deck, leo_tape, sigmas


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


def _bind(tape, doc: dict):
    return bind(validate(Deck, doc, "deck.toml"), memory_pairs(tape).header, "deck.toml")


def _renamed(table: dict, old: str, new: str) -> dict:
    """``table`` with the key ``old`` spelled ``new``, in its place."""
    return {new if k == old else k: v for k, v in table.items()}


def test_an_earlier_spelling_in_the_deck_binds_the_same_parameter(tape):
    fit, real = sigmas(tape, GM_km3_s2=0.0), sigmas(tape, GM_km3_s2=0.01)
    extra = {"real": {"apriori": {"correlation": [["GM_km3_s2", "J2", 0.3]]}}}
    new = deck(tape, fit=fit, real=real)
    new["real"]["apriori"].update(extra["real"]["apriori"])
    old = deck(tape, fit=_renamed(fit, "GM_km3_s2", "GM"), real=_renamed(real, "GM_km3_s2", "GM"))
    old["real"]["apriori"]["correlation"] = [["GM", "J2", 0.3]]
    a = _bind(tape, new)
    with pytest.warns(DeprecatedSpelling) as record:
        b = _bind(tape, old)
    fields = {str(w.message).split(": 'GM'")[0] for w in record}
    assert fields == {"deck.toml: fit.apriori.sigma.GM", "deck.toml: real.apriori.sigma.GM",
                      "deck.toml: real.apriori.correlation[0]"}
    assert all(str(w.message).endswith("write 'GM_km3_s2'") for w in record)
    np.testing.assert_array_equal(a.S0, b.S0)
    np.testing.assert_array_equal(a.Lambda0, b.Lambda0)
    assert a.systems.system_names(6) == b.systems.system_names(6)


def test_a_name_of_no_parameter_of_the_tape_is_refused(tape):
    fit = _renamed(sigmas(tape), "GM_km3_s2", "GM_moon_km3_s2")
    with pytest.raises(InputError) as info:
        _bind(tape, deck(tape, fit=fit))
    assert info.value.field.startswith("fit.")
    assert "GM_moon_km3_s2" in str(info.value) and "\n" not in str(info.value)
