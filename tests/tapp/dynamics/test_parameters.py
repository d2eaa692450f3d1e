"""The parameter registry (:mod:`tapp.dynamics.parameters`): every name the shipped examples
write or their tapes carry parses to itself with the tape's unit and kind; the earlier
spellings (GM, GM_<body>, dr_<body>_<axis>) are read with a warning naming the new one and
give the same parameters and arrays as the new spelling; unknown names are refused naming the
file and the field."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tapp.dynamics import ForceModel, GravitySpec, Propagator
from tapp.dynamics.parameters import KINDS, canonical, meaning, parse
from tapp.errors import DeprecatedSpelling, InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.tracking.scenario_build import parse_scenario, read_scenario

#: The shipped TAPP I scenarios (every example with a [parameters] table).
SCENARIOS = sorted(p for p in EXAMPLES.rglob("*.toml")
                   if "parameters" in tomllib.loads(p.read_text()))
#: The shipped decks (σ tables by name).
DECKS = sorted(p for p in EXAMPLES.rglob("*.toml")
               if {"fit", "real"} <= set(tomllib.loads(p.read_text())))
#: Earlier spelling -> the one spelling.
LEGACY = {"GM": "GM_km3_s2", "GM_moon": "GM_moon_km3_s2", "GM_mars": "GM_mars_km3_s2",
          "dr_moon_x": "dr_moon_x_km", "dr_mars_z": "dr_mars_z_km"}
#: One name of each kind in its one spelling, with its unit.
ONE_OF_EACH = {
    "x_km": ("orbit", "km"), "vz_km_s": ("orbit", "km/s"),
    "GM_km3_s2": ("gm", "km^3/s^2"), "GM_sun_km3_s2": ("gm", "km^3/s^2"),
    "J3": ("zonal", "1"), "C22": ("harmonic", "1"), "S31": ("harmonic", "1"),
    "Cr": ("radiation", "1"), "Cd": ("drag", "1"),
    "dr_mars_y_km": ("ephemeris_offset", "km"), "acc_I": ("empirical", "km/s^2"),
    "thr_vnb_2": ("thrust", "km/s^2"), "thr_start_s": ("thrust", "s"),
    "acc_C_012": ("stochastic", "km/s^2"),
    "DSS-14.spin_radius_km": ("location", "km"), "QUITO.lon_rad": ("location", "rad"),
    "QUITO.range_rate_bias_km_s": ("bias", "km/s"),
    "MADRID.zenith_wet_km.p3": ("troposphere", "km"),
    "MADRID.zenith_tec_tecu": ("ionosphere", "TECU"),
    "GOLDSTONE-MADRID.quasar_dec_rad": ("quasar", "rad"),
    "TCM1.mag_fixed_km_s": ("execution", "km/s"),
    "eop.xp_rad.2031-07-22": ("eop", "rad"), "eop.ut1_s": ("eop", "s"),
}


def _deck_names(path: Path) -> list[str]:
    """The parameter names a deck's σ tables and groups spell out (no patterns, no
    positions)."""
    doc = tomllib.loads(path.read_text())
    names = [k for world in ("fit", "real") for k in
             doc[world].get("apriori", {}).get("sigma", {}) or {}]
    names += [n for refs in doc.get("budget", {}).get("groups", {}).values() for n in refs]
    return [n for n in names if isinstance(n, str) and not n.isdigit()
            and not set("*?[") & set(n)]


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_every_name_of_a_shipped_scenario_parses_to_its_tape_name_unit_and_kind(path: Path
                                                                                ) -> None:
    scenario = read_scenario(path)  # with warnings as errors: no earlier spelling is shipped
    assert scenario.parameters
    for p in scenario.parameters:
        found = parse(p.name)
        assert (found.canonical, found.unit, found.tape_kind) == (p.name, p.unit, p.kind)


@pytest.mark.parametrize("path", DECKS, ids=lambda p: p.name)
def test_every_name_a_shipped_deck_spells_out_is_in_its_one_spelling(path: Path) -> None:
    names = _deck_names(path)
    assert [canonical(n, str(path)) for n in names] == names


def test_the_shipped_files_were_found() -> None:
    assert len(SCENARIOS) >= 6 and len(DECKS) >= 5
    assert sum(bool(_deck_names(p)) for p in DECKS) >= 4  # one deck is by position only


@pytest.mark.parametrize("name", ONE_OF_EACH)
def test_the_one_spelling_round_trips_with_its_kind_and_unit(name: str) -> None:
    found = parse(name)
    assert (found.kind, found.unit) == ONE_OF_EACH[name]
    assert found.canonical == name and parse(found.canonical) == found
    assert meaning(name) == found
    assert found.dynamic == (found.tape_kind == "dynamic")


def test_every_kind_is_exercised() -> None:
    assert {kind for kind, _ in ONE_OF_EACH.values()} == set(KINDS)


def test_the_description_carries_body_degree_order_axis_owner() -> None:
    assert (parse("GM_moon_km3_s2").body, parse("GM_km3_s2").body) == ("moon", "")
    assert (parse("S31").coefficient, parse("S31").degree, parse("S31").order) == ("S", 3, 1)
    assert (parse("dr_mars_z_km").body, parse("dr_mars_z_km").axis) == ("mars", 2)
    zenith = parse("MADRID.zenith_wet_km.p3")
    assert (zenith.owner, zenith.label, zenith.span) == ("MADRID", "zenith_wet_km", "p3")
    assert parse("Cr").surface_field == "c_r" and parse("Cd").surface_field == "c_d"


@pytest.mark.parametrize(("old", "new"), LEGACY.items())
def test_an_earlier_spelling_warns_naming_the_new_one(old: str, new: str) -> None:
    with pytest.warns(DeprecatedSpelling) as record:
        found = parse(old, "s.toml", "parameters.dynamic[0]")
    assert found == parse(new)
    assert [str(w.message) for w in record] == [
        f"s.toml: parameters.dynamic[0]: {old!r} is an earlier spelling: write {new!r}"]
    assert meaning(old) is None  # the kernels' own names are the one spelling


@pytest.mark.parametrize("name", ["GMX", "GM_km3", "J", "J12", "C2", "dr_mars_w_km", "acc_Q",
                                  "acc_R_x", "eop.ut2_s", "eop.ut1_s.p1", "QUITO.lon_rad.p1",
                                  "QUITO.range_bias_m", "", "x_m"])
def test_an_unknown_name_is_refused_naming_the_source_and_field(name: str) -> None:
    with pytest.raises(InputError) as info:
        parse(name, "deck.toml", "fit.apriori.sigma")
    assert (info.value.source, info.value.field, info.value.got) == (
        "deck.toml", "fit.apriori.sigma", name)
    assert "GM_<body>_km3_s2" in info.value.expected and "\n" not in str(info.value)


def test_the_cli_shows_an_earlier_spelling_as_one_warning_line() -> None:
    """In a clean interpreter (Python hides a DeprecationWarning raised outside __main__)."""
    code = ("from tapp.cli.common import one_line_warnings\n"
            "from tapp.dynamics.parameters import parse\n"
            "with one_line_warnings():\n"
            "    parse('GM_moon', 's.toml', 'parameters.dynamic[1]')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONWARNINGS": ""})
    assert out.stderr == ("warning: s.toml: parameters.dynamic[1]: 'GM_moon' is an earlier "
                          "spelling: write 'GM_moon_km3_s2'\n")


# --- the same parameters and arrays from either spelling -----------------------------------


def _legacy(doc: dict) -> dict:
    old = {new: old for old, new in LEGACY.items()}
    out = copy.deepcopy(doc)
    par = out["parameters"]
    par["dynamic"] = [old.get(n, n) for n in par["dynamic"]]
    par["values"] = {old.get(n, n): v for n, v in par.get("values", {}).items()}
    return out


def test_a_scenario_in_the_earlier_spelling_gives_the_same_parameters_and_values() -> None:
    path = EXAMPLES / "deep_space.toml"
    doc = tomllib.loads(path.read_text())
    doc["parameters"]["dynamic"] += ["dr_moon_x_km"]
    doc["parameters"]["values"] = {"GM_moon_km3_s2": 4902.8, "dr_moon_x_km": 0.5}
    new = parse_scenario(doc, str(path))
    with pytest.warns(DeprecatedSpelling) as record:
        old = parse_scenario(_legacy(doc), str(path))
    assert {str(w.message) for w in record} == {
        f"{path}: {field}: {o!r} is an earlier spelling: write {LEGACY[o]!r}"
        for field, o in (("parameters.dynamic[0]", "GM"), ("parameters.dynamic[1]", "GM_moon"),
                         ("parameters.dynamic[3]", "dr_moon_x"),
                         ("parameters.values.GM_moon", "GM_moon"),
                         ("parameters.values.dr_moon_x", "dr_moon_x"))}
    assert old.parameters == new.parameters
    assert old.dynamic == new.dynamic == ("GM_km3_s2", "GM_moon_km3_s2", "Cr", "dr_moon_x_km")
    assert old.dynamic_values == new.dynamic_values == (("GM_moon_km3_s2", 4902.8),
                                                        ("dr_moon_x_km", 0.5))


def test_a_propagator_in_the_earlier_spelling_gives_array_equal_sensitivities() -> None:
    """A day about the Earth with the Moon and the Sun: Φ and S of (GM, GM_moon, dr_moon_x)
    equal those of the one spelling, element for element, and so do the states with a
    value other than nominal."""
    model = ForceModel(GravitySpec(2, 0), "earth", ("moon", "sun"))
    x0 = np.array([7000.0, 0.0, 0.0, 0.0, 7.5, 1.0])
    t_s = np.array([0.0, 3600.0, 86400.0])
    new = Propagator(model, params=("GM_km3_s2", "GM_moon_km3_s2", "dr_moon_x_km"))
    with pytest.warns(DeprecatedSpelling) as record:
        old = Propagator(model, params=("GM", "GM_moon", "dr_moon_x"))
    assert [str(w.message).split(" is ")[0] for w in record] == [
        "propagator: params[0]: 'GM'", "propagator: params[1]: 'GM_moon'",
        "propagator: params[2]: 'dr_moon_x'"]
    assert old.params == new.params
    a = new.propagate(x0, t_s, param_values={"dr_moon_x_km": 10.0}, epoch_jd_utc=2461000.5)
    with pytest.warns(DeprecatedSpelling, match="propagate: param_values: 'dr_moon_x'"):
        b = old.propagate(x0, t_s, param_values={"dr_moon_x": 10.0}, epoch_jd_utc=2461000.5)
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.stm, b.stm)
    np.testing.assert_array_equal(a.sensitivity, b.sensitivity)
    assert a.params == b.params


def test_one_parameter_in_both_spellings_is_refused() -> None:
    model = ForceModel(GravitySpec(2, 0), "earth", ("moon",))
    with pytest.warns(DeprecatedSpelling), pytest.raises(InputError, match="each parameter once"):
        Propagator(model, params=("GM_moon", "GM_moon_km3_s2"))
