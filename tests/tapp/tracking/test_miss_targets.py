"""``[miss]`` targets of issue 31 from the file to the tape: the B-plane in the body's own
equator (``reference = "body_equator"``) and the entry flight-path angle (``entry_fpa_rad`` at
``entry_radius_km``), with their refusals.

The scenario is the shipped lunar swing-by (``deep_space.toml``), tracked for 2 days instead of
30 (no stochastic accelerations), with its miss two hours before the periapsis: the spacecraft
is then 10,630 km from the Moon, inbound, on a hyperbola of periapsis radius 2,200.7 km, so an
interface sphere of 2,500 km lies ahead of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.tomlfile import read_toml
from tapp.tracking.scenario import Scenario
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import miss_partials, simulate

DEEP_SPACE = EXAMPLES / "deep_space.toml"
SOURCE = "targets.toml"
#: The shipped miss time, the targeted flyby's periapsis (s from the epoch), and ours.
PERIAPSIS_s = 309958.384
MISS_s = PERIAPSIS_s - 7200.0
ENTRY_RADIUS_km = 2500.0
QUANTITIES = ["b_dot_r_km", "b_dot_t_km", "entry_fpa_rad"]
# Miss partials vs central differences through the propagation, row-relative (as in
# test_simulate): the differences carry the integrator's noise (rtol 1e-13 over 3.5 days,
# ~1e-9 of the row at these steps) and the 1e-6 relative steps of G (truncation ~1e-12).
MISS_FD = 1e-6
# Central-difference steps of the injection state and of GM_moon: large enough that the
# integrator's noise (~1e-10 km at the Moon) is far below the differences, small enough that
# the curvature is (the deep-space test's steps).
STEPS = {"x_km": 1e-4, "vx_km_s": 1e-7, "vy_km_s": 1e-7, "vz_km_s": 1e-7,
         "GM_moon_km3_s2": 1e-4}


def _document(**miss: object) -> dict:
    """deep_space.toml, 2 days of tracking, the miss of the module docstring (entries of
    ``miss`` replace its keys; None removes one)."""
    data = read_toml(DEEP_SPACE)
    data["tracking"]["end"] = 2 * 86400.0
    data["times"] = {"input_step_s": 86400.0, "end": 4 * 86400.0}
    del data["stochastic"]
    data["miss"].update({"time": MISS_s, "reference": "body_equator",
                         "entry_radius_km": ENTRY_RADIUS_km, "quantities": QUANTITIES})
    data["miss"].update(miss)
    data["miss"] = {k: v for k, v in data["miss"].items() if v is not None}
    return data


@pytest.fixture(scope="module")
def scenario() -> Scenario:
    return parse_scenario(_document(), SOURCE)


def _perturbed(scenario: Scenario, name: str, delta: float) -> Scenario:
    if name.endswith("_km3_s2"):
        nominal = {p.name: p.nominal for p in scenario.parameters}[name]
        return dataclasses.replace(scenario, dynamic_values=(
            *scenario.dynamic_values, (name, nominal + delta)))
    x0 = np.array(scenario.x0)
    x0[("x_km", "y_km", "z_km", "vx_km_s", "vy_km_s", "vz_km_s").index(name)] += delta
    return dataclasses.replace(scenario, x0=x0)


def test_tape_miss_rows_in_the_moon_equator_match_central_differences(scenario) -> None:
    """The tape carries entry_fpa_rad (rad) beside B·R, B·T, and all three rows of its B
    match central differences of the miss through re-propagated trajectories (measured
    1.3e-7, 1.6e-8 and 2.6e-8 of the rows B·R, B·T, entry_fpa_rad)."""
    tape = simulate(scenario).tape
    assert tape.miss.name == tuple(QUANTITIES)
    assert tape.miss.unit == ("km", "km", "rad")
    fpa = tape.miss.nominal[2]
    assert -np.pi / 2 < fpa < 0.0  # descending through the interface
    names = tuple(STEPS)
    columns = [[p.name for p in scenario.parameters].index(n) for n in names]
    fd = np.stack([(miss_partials(_perturbed(scenario, n, STEPS[n]))[0]
                    - miss_partials(_perturbed(scenario, n, -STEPS[n]))[0]) / (2 * STEPS[n])
                   for n in names], axis=1)
    big_b = tape.miss.B[:, columns]
    rel = np.abs(fd - big_b) / np.abs(fd).max(axis=1, keepdims=True)
    assert rel.max() < MISS_FD, rel


def test_body_equator_only_turns_b_within_the_b_plane(scenario) -> None:
    """Another reference plane turns (B·T, B·R) about S: |B| is the same to rounding, and
    the Moon's equator (18 to 29 deg from the Earth's) turns it by 14.5 deg here, which
    moves the components by hundreds of km (1,400 km in B·R)."""
    moon = miss_partials(scenario)[0][:2]
    earth_miss = dataclasses.replace(scenario.miss, reference="earth_equator")
    earth = miss_partials(dataclasses.replace(scenario, miss=earth_miss))[0][:2]
    # |B| ~ 5,700 km from the same state: rounding ~1e-12 km.
    assert np.hypot(*moon) == pytest.approx(np.hypot(*earth), abs=1e-8)
    assert np.linalg.norm(moon - earth) > 100.0


def test_an_interface_below_the_periapsis_is_refused_with_the_periapsis_radius() -> None:
    scenario = parse_scenario(_document(entry_radius_km=2000.0), SOURCE)
    with pytest.raises(InputError, match=r"periapsis radius .*2,200\.7\d\d km") as info:
        simulate(scenario)
    assert info.value.field == "miss.entry_radius_km"
    assert info.value.source == SOURCE


def test_an_interface_beyond_the_spacecraft_is_refused() -> None:
    scenario = parse_scenario(_document(entry_radius_km=20_000.0), SOURCE)
    with pytest.raises(InputError, match=r"distance from the moon's centre") as info:
        miss_partials(scenario)
    assert info.value.field == "miss.entry_radius_km"


@pytest.mark.parametrize(("miss", "field", "message"), [
    ({"body": "sun"}, "miss.reference", r"a body with a pole model .*earth, mars, moon, venus"),
    ({"quantities": ["b_dot_r_km", "b_dot_t_km"]}, "miss.entry_radius_km",
     r"no entry radius without entry_fpa_rad"),
    ({"entry_radius_km": None}, "miss.entry_radius_km", r"interface radius"),
    ({"entry_radius_km": 0.0}, "miss.entry_radius_km", r"> 0"),
    ({"kind": "equinoctial", "body": None, "reference": None, "quantities": None},
     "miss.entry_radius_km", r"no body, reference or entry radius"),
])
def test_miss_refusals_name_the_field(miss, field, message) -> None:
    with pytest.raises(InputError, match=message) as info:
        parse_scenario(_document(**miss), SOURCE)
    assert info.value.field == field
    assert info.value.source == SOURCE


def test_the_default_quantities_leave_out_the_entry_angle() -> None:
    scenario = parse_scenario(_document(quantities=None, entry_radius_km=None), SOURCE)
    assert scenario.miss.quantities == ("b_dot_r_km", "b_dot_t_km", "ltof_s")


def test_the_moons_ephemeris_offset_moves_the_miss_as_central_differences_say() -> None:
    """dr_moon_x|y|z (km) as dynamic parameters: the tape names them with their unit, and the
    miss rows of their columns (the swing-by's response through the dynamics plus the direct
    −G term of a B-plane measured from the offset Moon) match central differences of the miss
    through re-propagated trajectories with the Moon offset, row-relative (measured 2.9e-7;
    the largest partial 0.91 km/km)."""
    doc = _document()
    doc["parameters"]["dynamic"] = [*doc["parameters"]["dynamic"], "dr_moon_x_km", "dr_moon_y_km",
                                    "dr_moon_z_km"]
    scenario = parse_scenario(doc, SOURCE)
    names = ("dr_moon_x_km", "dr_moon_y_km", "dr_moon_z_km")
    units = {p.name: p.unit for p in scenario.parameters}
    assert [units[n] for n in names] == ["km"] * 3
    columns = [[p.name for p in scenario.parameters].index(n) for n in names]
    big_b = miss_partials(scenario)[1][:, columns]

    def offset(name: str, delta: float) -> Scenario:
        return dataclasses.replace(scenario, dynamic_values=(
            *scenario.dynamic_values, (name, delta)))

    step_km = 0.01
    fd = np.stack([(miss_partials(offset(n, step_km))[0] - miss_partials(offset(n, -step_km))[0])
                   / (2 * step_km) for n in names], axis=1)
    assert np.abs(fd).max() > 0.1  # a kilometre of the Moon moves B by hundreds of metres
    rel = np.abs(fd - big_b) / np.abs(fd).max(axis=1, keepdims=True)
    assert rel.max() < MISS_FD, rel


def test_the_offset_of_the_earth_is_refused() -> None:
    """The Earth, the centre of deep_space.toml, is the stations' frame: no offset."""
    body = "earth"
    doc = _document()
    doc["parameters"]["dynamic"] = [*doc["parameters"]["dynamic"], f"dr_{body}_x_km"]
    with pytest.raises(InputError) as info:
        parse_scenario(doc, SOURCE)
    assert info.value.field.startswith("parameters.dynamic[")
