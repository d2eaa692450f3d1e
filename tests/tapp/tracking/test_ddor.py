"""ΔDOR in TAPP I: the [ddor] table, the rows on the tape, the noise units and the errors.

The geometry is the GEO track of :func:`helpers.geo_document` (both stations see the
spacecraft for the whole 12 h: one mutual-visibility window), with station locations in q.
"""

import math

import numpy as np
import pytest

from tapp.constants import C_LIGHT_km_s
from tapp.errors import InputError
from tapp.io.tape.t13 import T13
from tapp.measurements import LightTime
from tapp.measurements.ddor import DdorModel, quasar_direction
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate
from tests.tapp.processor.helpers import deck, final, run, scaled_err
from tests.tapp.tracking.helpers import SOURCE, geo_document, leo_document, scaled_close

SIGMA_NS = 0.1
BIAS_NS = 0.05
SIGMA_NRAD = 2.0
INTERVAL_S = 3600.0
#: Sums of products of a few dozen rows against their QR factor's Gram matrix: rounding.
SUM_ORDER = 1e-12


def _document(**ddor) -> dict:
    doc = geo_document()
    doc["parameters"]["station_location"] = "cylindrical"
    doc["ddor"] = {"baselines": [["UNDER", "EAST"]], "interval_s": INTERVAL_S,
                   "fit": {"sigma_ns": SIGMA_NS}, "real": {"bias_ns": BIAS_NS}, **ddor}
    return doc


def _simulate(doc: dict) -> T13:
    return simulate(parse_scenario(doc, SOURCE), raw=True).tape


@pytest.fixture(scope="module")
def tape() -> T13:
    return _simulate(_document())


def _ddor_rows(tape: T13) -> np.ndarray:
    return tape.raw.kind == tape.raw.kinds.index("ddor")


def test_the_baseline_is_a_tape_entry_after_the_stations(tape: T13) -> None:
    assert tape.stations.name == ("UNDER", "EAST", "UNDER-EAST")
    assert tape.stations.observables[2] == "ddor"
    assert tape.stations.lat_deg[2] == tape.stations.lat_deg[0]  # A's position
    rows = _ddor_rows(tape)
    assert np.all(tape.raw.station[rows] == 3)
    # Every hour on the 600 s grid from 600 s while both see the spacecraft: 600, ..., 40200.
    np.testing.assert_allclose(tape.raw.t_s[rows], 600.0 + INTERVAL_S * np.arange(12))
    assert tape.pairs.n_obs[tape.pairs.station == 3].sum() == 12
    assert tape.editing.scheduled_obs[2] == 12 and tape.editing.removed_obs[2].sum() == 0


def test_rows_are_the_model_and_its_partials(tape: T13) -> None:
    """Values and location columns are DdorModel's at the trajectory's states (the orbit
    columns H Φ, H S go through the same code as the stations' rows, tested there)."""
    sc = parse_scenario(_document(), SOURCE)
    sim = simulate(sc, raw=True)
    raw, rows = sim.tape.raw, _ddor_rows(sim.tape)
    t = raw.t_s[rows]
    x = sim.states[np.searchsorted(sim.t_s, t)]
    under, east = (s.station for s in sc.stations)
    model = DdorModel(under, east, sc.orientation)  # light_time "none" in this scenario
    quasar = quasar_direction(x[:, :3], math.radians(5.0), 0.0)
    np.testing.assert_allclose(raw.value[rows], model.compute(t, x, quasar)[:, 0], rtol=1e-15)
    names = list(sim.tape.parameters.name)
    wrt_under, wrt_east = model.station_partials(t, x, quasar, "cylindrical")
    for prefix, wrt in (("UNDER", wrt_under), ("EAST", wrt_east)):
        first = names.index(f"{prefix}.spin_radius_km")
        np.testing.assert_allclose(raw.A[rows][:, first:first + 3], wrt[:, 0], rtol=1e-15)
    # No bias parameter of either station in a ΔDOR row.
    for prefix in ("UNDER", "EAST"):
        assert np.all(raw.A[rows][:, names.index(f"{prefix}.range_bias_km")] == 0.0)


def test_normal_matrices_of_the_window(tape: T13) -> None:
    """One window, one record: AᵀWA with W = 1/(c σ)², and AᵀWMWA with
    M = σ² I + σ_b² 1 1ᵀ (the window's bias), formed here from the raw rows."""
    raw, rows = tape.raw, _ddor_rows(tape)
    a = raw.A[rows]
    sigma_km, bias_km = C_LIGHT_km_s * SIGMA_NS * 1e-9, C_LIGHT_km_s * BIAS_NS * 1e-9
    np.testing.assert_allclose(raw.weight[rows], 1.0 / sigma_km**2, rtol=1e-15)
    m = sigma_km**2 * np.eye(a.shape[0]) + bias_km**2
    wa = a / sigma_km**2
    pair = tape.pairs.station == 3
    scaled_close(tape.pairs.dJ[pair][0], a.T @ a / sigma_km**2, SUM_ORDER)
    scaled_close(tape.pairs.dJt[pair][0], wa.T @ m @ wa, SUM_ORDER)


def test_sigma_in_nrad_scales_with_the_projected_baseline() -> None:
    doc = _document(fit={"sigma_nrad": SIGMA_NRAD}, real={"bias_nrad": 1.0})
    sc = parse_scenario(doc, SOURCE)
    sim = simulate(sc, raw=True)
    raw, rows = sim.tape.raw, _ddor_rows(sim.tape)
    t = raw.t_s[rows]
    x = sim.states[np.searchsorted(sim.t_s, t)]
    r_a, r_b = (s.station.state_eci(sc.orientation, t)[:, :3] for s in sc.stations)
    b, s_hat = r_b - r_a, x[:, :3] / np.linalg.norm(x[:, :3], axis=1)[:, None]
    length = np.linalg.norm(b - np.sum(b * s_hat, axis=1)[:, None] * s_hat, axis=1)
    sigma_km = SIGMA_NRAD * 1e-9 * length
    np.testing.assert_allclose(raw.weight[rows], 1.0 / sigma_km**2, rtol=1e-12)
    np.testing.assert_allclose(raw.m_bias_var[rows], (1e-9 * length) ** 2, rtol=1e-12)
    a = raw.A[rows]
    pair = sim.tape.pairs.station == 3
    scaled_close(sim.tape.pairs.dJ[pair][0], a.T @ (a / sigma_km[:, None] ** 2), SUM_ORDER)
    # M: white σ² and the window's bias (1 nrad × the projected baseline, in delay) outer.
    wmwa = (a / sigma_km[:, None] ** 2).T @ (np.diag(sigma_km**2) + np.outer(
        1e-9 * length, 1e-9 * length)) @ (a / sigma_km[:, None] ** 2)
    scaled_close(sim.tape.pairs.dJt[pair][0], wmwa, SUM_ORDER)


def test_one_point_per_window() -> None:
    tape = _simulate(_document(interval_s=None))
    rows = _ddor_rows(tape)
    # The window is the whole grid 600 .. 43200 s (72 samples): its middle sample.
    np.testing.assert_allclose(tape.raw.t_s[rows], [600.0 + 35 * 600.0])
    assert tape.editing.scheduled_obs[2] == 1


@pytest.mark.parametrize(("ddor", "field", "expected"), [
    ({"baselines": [["UNDER", "NOWHERE"]]}, "ddor.baselines[0]", "tracking.stations"),
    ({"baselines": [["EAST", "EAST"]]}, "ddor.baselines[0]", "two different stations"),
    ({"baselines": [["UNDER", "EAST"], ["EAST", "UNDER"]]}, "ddor.baselines[1]", "once"),
    ({"fit": {"sigma_ns": 0.1, "sigma_nrad": 1.0}}, "ddor.fit", "one of sigma_ns"),
    ({"fit": {}}, "ddor.fit", "one of sigma_ns"),
    ({"real": {"sigma_nrad": 1.0}}, "ddor.real.sigma_nrad", "in ns"),
    ({"interval_s": 1000.0}, "ddor.interval_s", "multiple of tracking.data_interval_s"),
    ({"quasar_separation_deg": 45.0}, "ddor.quasar_separation_deg", "30"),
])
def test_scenario_errors(ddor: dict, field: str, expected: str) -> None:
    with pytest.raises(InputError, match=expected) as err:
        parse_scenario(_document(**ddor), SOURCE)
    assert err.value.field == field


def test_a_baseline_of_two_stations_at_one_place_names_the_file_and_the_baseline() -> None:
    """Two names for one antenna: a baseline of zero length, refused where the file is read
    (issue 28: "DdorModel: station_b: ..." once the simulation started)."""
    doc = _document(baselines=[["EAST", "TWIN"]])
    doc["stations"]["TWIN"] = dict(doc["stations"]["EAST"])
    doc["tracking"]["stations"].append("TWIN")
    with pytest.raises(InputError) as err:
        parse_scenario(doc, SOURCE)
    assert str(err.value) == (f"{SOURCE}: ddor.baselines[0]: expected two stations at different "
                              "places (a baseline of zero length measures nothing) (got "
                              "['EAST', 'TWIN'])")


def test_a_baseline_that_never_sees_the_spacecraft_is_an_error() -> None:
    """LEO at 170 km: Quito and Malindi (119 deg apart) never see it together."""
    doc = leo_document(ddor={"baselines": [["QUITO", "MALINDI"]], "fit": {"sigma_ns": 1.0}})
    with pytest.raises(InputError, match="0 points on QUITO-MALINDI") as err:
        simulate(parse_scenario(doc, SOURCE))
    assert err.value.field == "ddor.baselines[0]"


def test_flagging_the_baseline_off_in_tapp3_equals_the_tape_without_ddor() -> None:
    """TAPP III's time-station flag acts on the baseline's entry: its ΔDOR alone leaves the
    run, which is then the run of the scenario without [ddor] (same normal matrices)."""
    with_ddor = _simulate(_document())
    doc = _document()
    del doc["ddor"]
    without = _simulate(doc)
    assert with_ddor.n_o == without.n_o
    outputs = ["cov-real o@current", "cov-fit o@current"]
    d = deck(without, times={"print": [1]}, commands={"print": outputs})
    reference = run(without, d)
    flagged = run(with_ddor, {**d, "stations_off": [{"station": "UNDER-EAST"}]})
    kept = run(with_ddor, d)
    for alias in outputs:
        # The stations' pairs are the same on both tapes: equal to rounding.
        assert scaled_err(final(flagged, alias), final(reference, alias)) < 1e-9
    # With the ΔDOR points the fit's covariance shrinks.
    fit_with, fit_without = final(kept, outputs[1]), final(reference, outputs[1])
    assert np.trace(fit_with[:3, :3]) < np.trace(fit_without[:3, :3])


def test_a_two_way_scenario_takes_one_way_legs_for_ddor() -> None:
    """ΔDOR is one-way whatever the stations' light time: the values are DdorModel's with a
    one-way light time on the propagated trajectory (the simulator's bounce states)."""
    doc = _document()
    doc["tracking"]["light_time"] = "two_way"
    sc = parse_scenario(doc, SOURCE)
    sim = simulate(sc, raw=True)
    raw, rows = sim.tape.raw, _ddor_rows(sim.tape)
    t = raw.t_s[rows]
    x = sim.states[np.searchsorted(sim.t_s, t)]

    def state_at(t_s):
        return sc.propagator().propagate(sc.x0, t_s, stm=False, orientation=sc.orientation,
                                         epoch_jd_utc=sc.epoch.jd).states

    under, east = (s.station for s in sc.stations)
    model = DdorModel(under, east, sc.orientation, LightTime(two_way=False, state_at=state_at))
    quasar = quasar_direction(x[:, :3], math.radians(5.0), 0.0)
    np.testing.assert_allclose(raw.value[rows], model.compute(t, x, quasar)[:, 0], rtol=1e-14)
    instantaneous = DdorModel(under, east, sc.orientation).compute(t, x, quasar)[:, 0]
    # The light time matters: 35 m here (GEO, τ ≈ 0.12 s), far above 1 m.
    assert np.abs(raw.value[rows] - instantaneous).max() > 1e-3
