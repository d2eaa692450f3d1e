"""TAPP I about another centre (``[model] center``): a spacecraft 1.7e6 km from the Earth
tracked by Goldstone and Canberra for 2 days, integrated about the Sun (the Earth a third
body) and about the Earth (the Sun a third body), each with the Moon and Mercury to Saturn.
The stations observe the same geocentric states either way (tapp.tracking.centre), so the
two tapes agree but for what the two frames' dynamics do not share: the Earth's heliocentric
motion comes from DE421 about the Sun, with the Sun's first post-Newtonian acceleration of
the Earth, (μ/r²)(4μ/(r c²) − v²/c²) = 1.75e-13 km/s², which the Earth-centred Newtonian
model's indirect term leaves out: ½ a t² = 2.6 m and a t = 3.0e-8 km/s after 2 days
(measured 2.9 m and 2.9e-8 km/s)."""

import numpy as np
import pytest

from tapp.constants import C_LIGHT_km_s, GM_km3_s2
from tapp.dynamics.ephemeris import barycentric_state
from tapp.errors import InputError
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate

SOURCE = "centre.toml"
SPAN_s = 172800.0
BODIES = ["mercury", "venus", "mars", "jupiter", "saturn", "moon"]
#: The geocentric injection, km and km/s.
GEOCENTRIC = np.array([1.5e6, 0.8e6, 0.3e6, 0.3, -0.2, 0.1])


def _document(center: str, x0: np.ndarray) -> dict:
    return {
        "title": "about another centre", "iden": "CENTRE", "epoch": "2026-03-10T00:00:00",
        "injection": {"r_km": list(x0[:3]), "v_km_s": list(x0[3:])},
        "model": {"center": center, "gravity": "J0", "var_gravity": "J0",
                  "third_bodies": (["earth"] if center == "sun" else ["sun"]) + BODIES},
        "parameters": {"dynamic": [], "station_location": "none", "station_biases": []},
        "stations": {"GOLDSTONE": {"lat_deg": 35.4267, "lon_deg": -116.89, "h_km": 1.0,
                                   "elev_mask_deg": 10.0},
                     "CANBERRA": {"lat_deg": -35.4014, "lon_deg": 148.9817, "h_km": 0.69,
                                  "elev_mask_deg": 10.0}},
        "tracking": {"stations": ["GOLDSTONE", "CANBERRA"],
                     "observables": ["range", "range_rate"], "light_time": "two_way",
                     "data_interval_s": 600.0},
        "noise": {"fit": {"sigma_range_m": 1.0, "sigma_range_rate_mm_s": 0.1}, "real": {}},
        "times": {"input": [86400.0, SPAN_s]}, "miss": {"kind": "equinoctial"}}


def _earth_from_sun() -> np.ndarray:
    """The Earth's heliocentric state at the epoch (DE421 at the scenario's TDB)."""
    scales = parse_scenario(_document("earth", GEOCENTRIC), SOURCE).orientation.scales
    jd, jd2 = scales.tdb(np.array([0.0]))
    return (barycentric_state("earth", jd, jd2) - barycentric_state("sun", jd, jd2))[0]


@pytest.fixture(scope="module")
def tapes():
    about_earth = simulate(parse_scenario(_document("earth", GEOCENTRIC), SOURCE), raw=True)
    about_sun = simulate(parse_scenario(_document("sun", GEOCENTRIC + _earth_from_sun()),
                                        SOURCE), raw=True)
    return about_earth, about_sun


def test_the_stations_see_the_same_spacecraft_about_either_centre(tapes):
    earth, sun = (sim.tape.raw for sim in tapes)
    np.testing.assert_array_equal(earth.t_s, sun.t_s)
    assert earth.t_s.size > 100
    x = _earth_from_sun()
    r, v = np.linalg.norm(x[:3]), np.linalg.norm(x[3:])
    mu = GM_km3_s2["sun"]
    post_newtonian = mu / r**2 * (4 * mu / (r * C_LIGHT_km_s**2) - v**2 / C_LIGHT_km_s**2)
    for kind, bound in (("range", 0.5 * post_newtonian * SPAN_s**2),
                        ("range_rate", post_newtonian * SPAN_s)):
        rows = earth.kind == earth.kinds.index(kind)
        assert np.max(np.abs(sun.value[rows] - earth.value[rows])) < 2.0 * bound, kind
    # the partials of the observables (per unit of the state about either centre)
    scale = np.max(np.abs(earth.A), axis=0)
    assert np.max(np.abs(sun.A - earth.A) / np.where(scale > 0, scale, 1.0)) < 1e-4


def test_the_trajectory_files_name_the_centre(tapes, tmp_path):
    from tapp.io.ccsds.oem import format_oem

    sun = tapes[1]
    text = format_oem(sun.tape.epoch, sun.t_s[:10], sun.states[:10], object_name="C",
                      object_id="C", ref_frame="ICRF", interpolation="HERMITE",
                      interpolation_degree=5, center_name=sun.scenario.state_model.center.upper())
    assert "CENTER_NAME = SUN" in text
    assert np.linalg.norm(sun.states[0, :3]) > 1e8  # heliocentric


@pytest.mark.parametrize("change, field", [
    ({"third_bodies": ["sun"]}, "model.third_bodies"),
    ({"gravity": "J2"}, "model.gravity"),
])
def test_a_model_the_centre_has_not_is_refused(change, field):
    doc = _document("sun", GEOCENTRIC + _earth_from_sun())
    doc["model"].update(change)
    with pytest.raises(InputError) as info:
        parse_scenario(doc, SOURCE)
    assert info.value.field == field


def test_an_injection_inside_the_centre_is_refused():
    with pytest.raises(InputError, match="the Sun's equatorial radius") as info:
        parse_scenario(_document("sun", np.array([1e5, 0, 0, 0, 1.0, 0])), SOURCE)
    assert info.value.field == "injection"


def _about_earth(doc: dict, x0: np.ndarray) -> dict:
    doc["injection"] = {"center": "earth", "r_km": list(x0[:3]), "v_km_s": list(x0[3:])}
    return doc


def test_an_injection_about_the_earth_is_translated_to_the_centre():
    """[injection] center = "earth" in a Sun-centred scenario: the state the test translates
    itself (the Earth's DE421 state at the scenario's TDB, from TimeScales, not the reader the
    scenario uses) to the rounding of heliocentric positions (1.5e8 km: 3e-8 km)."""
    sun = parse_scenario(_about_earth(_document("sun", GEOCENTRIC), GEOCENTRIC), SOURCE)
    expected = GEOCENTRIC + _earth_from_sun()
    np.testing.assert_allclose(sun.x0[:3], expected[:3], rtol=0, atol=1e-7)
    np.testing.assert_allclose(sun.x0[3:], expected[3:], rtol=0, atol=1e-12)
    # about its own centre, the state is kept as given
    earth = parse_scenario(_about_earth(_document("earth", GEOCENTRIC), GEOCENTRIC), SOURCE)
    np.testing.assert_array_equal(earth.x0, GEOCENTRIC)


def test_an_injection_below_its_own_bodys_surface_is_refused():
    """The periapsis check is about the body the state is given about (a departure 100 km
    from the Earth's centre is inside the Earth, whatever the integration's centre)."""
    inside = np.array([100.0, 0.0, 0.0, 0.0, 1.0, 0.0])
    with pytest.raises(InputError, match="Earth's equatorial radius") as info:
        parse_scenario(_about_earth(_document("sun", GEOCENTRIC), inside), SOURCE)
    assert info.value.field == "injection"


def test_an_orbit_about_another_body_needs_a_scenario_epoch():
    """A study's named orbits have no epoch to read the ephemeris at: another body refused."""
    from tapp.io.orbits import OrbitTable

    table = OrbitTable(center="mars", r_km=[4000.0, 0.0, 0.0], v_km_s=[0.0, 3.5, 0.0])
    with pytest.raises(InputError) as info:
        table.state("study.toml", "orbits.MARS")
    assert info.value.field == "orbits.MARS.center"


def test_centre_changes_reach_the_propagator_with_their_times():
    # [model] centre_changes: a time in s and one as a UTC date (one day after the epoch)
    from tapp.dynamics.centres import CentreChange

    doc = _document("earth", GEOCENTRIC)
    doc["model"]["centre_changes"] = [{"time": 3600.0, "center": "sun"},
                                      {"time": "2026-03-11T00:00:00", "center": "earth"}]
    scenario = parse_scenario(doc, SOURCE)
    assert scenario.propagator().centre_changes == (CentreChange(3600.0, "sun"),
                                                    CentreChange(86400.0, "earth"))


@pytest.mark.parametrize("rows, field", [
    ([{"time": 3600.0, "center": "uranus"}], "model.centre_changes[0].center"),  # not a body
    ([{"time": 7200.0, "center": "sun"}, {"time": 3600.0, "center": "earth"}],
     "model.centre_changes[1].time"),
])
def test_a_bad_centre_change_is_named(rows, field):
    doc = _document("earth", GEOCENTRIC)
    doc["model"]["centre_changes"] = rows
    with pytest.raises(InputError) as info:
        parse_scenario(doc, SOURCE)
    assert info.value.field == field
