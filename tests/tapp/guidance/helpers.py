"""A small deep-space T32 tape for the TAPP II tests, and guidance files.

The tape is the example ``deep_space.toml`` cut to its first 3 days (the injection, DSN tracking,
the lunar B-plane miss at periapsis, day 3.59) processed with
the example ``tapp3_deep_space.toml`` (GM of the Moon held fixed in the fit world, white-noise
weights against biased and correlated real noise; recycles at days 1, 2 and 3): the same
physics as the shipped study but for its stochastic accelerations (tested in
tests/tapp/tracking and tests/tapp/processor), made in well under a second.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

from tapp.examples import FOLDER as EXAMPLES
from tapp.guidance.guidefile import GuideFile
from tapp.io.schema import validate
from tapp.io.tape.t13 import T13, memory_pairs
from tapp.io.tape.t32 import T32
from tapp.io.tomlfile import read_toml
from tapp.processor.deck import Deck
from tapp.processor.deck_bind import bind
from tapp.processor.sequencing import process
from tapp.processor.tape32 import build_t32
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate

SCENARIOS = EXAMPLES
DAY_S = 86400.0
#: Execution errors of the tests (1σ): 2 %, 10 mrad, 1 mm/s.
EXECUTION = {"sigma_proportional": 0.02, "sigma_pointing_mrad": 10.0, "sigma_fixed_mm_s": 1.0}
#: A miss without B-plane or flight-time components: classical elements about the Earth.
ELEMENTS = ("a_km", "e", "i_rad")


@lru_cache(maxsize=2)
def deep_space_t13(elements: bool = False) -> T13:
    """The deep-space T13 tape of the first 3 days (module docstring); ``elements``: with
    the geocentric :data:`ELEMENTS` at the time of the periapsis as its miss instead."""
    doc = read_toml(SCENARIOS / "deep_space.toml")
    doc["tracking"]["end"] = 3 * DAY_S
    doc["times"]["end"] = 3 * DAY_S
    doc["times"]["epochs"] = []
    doc.pop("stochastic")  # TAPP II's tests, without the example's stochastic accelerations
    if elements:
        doc["miss"] = {"kind": "classical", "time": doc["miss"]["time"],
                       "quantities": list(ELEMENTS)}
    return simulate(parse_scenario(doc, "deep_space.toml")).tape


@lru_cache(maxsize=2)
def deep_space_t32(elements: bool = False) -> T32:
    """Its T32 tape: recycles 1, 2, 3 at days 1, 2, 3 (module docstring)."""
    deck = read_toml(SCENARIOS / "tapp3_deep_space.toml")
    deck["tape"].pop("n_o")  # the study's 24 parameters, without the stochastic accelerations
    deck["fit"]["stochastic"] = deck["real"]["stochastic"] = "ignore"
    deck["times"]["print"] = [1, 2, 3]
    deck["commands"]["print"] = []
    data = memory_pairs(deep_space_t13(elements))
    plan = bind(validate(Deck, deck, "deck.toml"), data.header, "deck.toml")
    return build_t32(process(data, plan), plan, data.header, {"deck_source": "deck.toml"})


def guide_doc(**tables) -> dict:
    """A guidance document: B·T, B·R targeted at every recycle, :data:`EXECUTION`; tables
    given replace the defaults (None removes one)."""
    doc = {"title": "test", "targets": {"miss": ["b_dot_t_km", "b_dot_r_km"]},
           "execution": dict(EXECUTION)}
    doc.update(tables)
    return {k: v for k, v in doc.items() if v is not None}


def guide(**tables) -> GuideFile:
    """:func:`guide_doc` validated."""
    return validate(GuideFile, guide_doc(**tables), "guide.toml")


def with_recycles(t32: T32, **changes) -> T32:
    """The tape with every recycle's fields replaced (e.g. ``L=zeros``) by callables of the
    recycle or values."""
    recycles = tuple(dataclasses.replace(r, **{k: v(r) if callable(v) else v
                                               for k, v in changes.items()})
                     for r in t32.recycles)
    return dataclasses.replace(t32, recycles=recycles)
