"""Earth orientation offsets and ΔDOR quasar positions as TAPP I parameters: the scenario
keys, the tape's columns (the models' partials), the HDF5 round trip, and TAPP III decks
that consider σ(UT1) = 0.5 ms, σ(x_p, y_p) = 5 nrad with "eop" in the error budget.

The geometry is the GEO track of :func:`helpers.geo_document` (two stations, one ΔDOR
baseline, iau2006 with the IERS EOP), and the lunar transfer of the deep_space example.
"""

import math

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.tape.t13 import T13
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.io.tomlfile import read_toml
from tapp.measurements import MeasurementModel
from tapp.measurements.ddor import DdorModel, quasar_direction
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate
from tests.tapp.guidance.helpers import SCENARIOS
from tests.tapp.processor.helpers import deck, run, sigmas
from tests.tapp.tracking.helpers import SOURCE, geo_document

EOP = ("eop.ut1_s", "eop.xp_rad", "eop.yp_rad")
QUASAR = ("UNDER-EAST.quasar_ra_rad", "UNDER-EAST.quasar_dec_rad")
#: The consider σ's of the brief: 0.5 ms of UT1 (23 cm at the equator), 5 nrad of pole
#: (1 mas, 3 cm at the surface); a quasar catalogue error of 1 nrad (0.2 mas, ICRF3-class).
SIGMA_EOP = {"eop.ut1_s": 0.5e-3, "eop.xp_rad": 5e-9, "eop.yp_rad": 5e-9}
SIGMA_QUASAR = 1e-9


def _document(earth_orientation=True, quasar_position=True) -> dict:
    doc = geo_document()
    doc["parameters"]["earth_orientation"] = earth_orientation
    doc["ddor"] = {"baselines": [["UNDER", "EAST"]], "interval_s": 3600.0,
                   "quasar_position": quasar_position, "fit": {"sigma_ns": 0.1}}
    return doc


@pytest.fixture(scope="module")
def simulated():
    scenario = parse_scenario(_document(), SOURCE)
    return scenario, simulate(scenario, raw=True)


def test_parameters_on_the_tape(simulated) -> None:
    _, sim = simulated
    par = sim.tape.parameters
    names = list(par.name)
    for name, unit in zip(EOP, ("s", "rad", "rad"), strict=True):
        i = names.index(name)
        assert (par.kind[i], par.unit[i], par.station[i], par.nominal[i]) == ("eop", unit, 0,
                                                                               0.0)
    for name in QUASAR:
        i = names.index(name)
        assert (par.kind[i], par.unit[i], par.station[i]) == ("quasar", "rad", 3)


def test_columns_are_the_models_partials(simulated) -> None:
    """Every station's and the baseline's rows carry MeasurementModel.eop_partials and
    DdorModel.eop_partials / quasar_partials at the trajectory's states."""
    scenario, sim = simulated
    raw, names = sim.tape.raw, list(sim.tape.parameters.name)
    eop = [names.index(n) for n in EOP]
    for number, ts in enumerate(scenario.stations, start=1):
        rows = (raw.station == number) & (raw.kind == raw.kinds.index("range"))
        t = raw.t_s[rows]
        x = sim.states[np.searchsorted(sim.t_s, t)]
        model = MeasurementModel(ts.station, scenario.orientation, ts.kinds)
        expected = model.eop_partials(t, x)[:, ts.kinds.index("range")]
        np.testing.assert_allclose(raw.A[rows][:, eop], expected, rtol=1e-14, atol=0)
    rows = raw.kind == raw.kinds.index("ddor")
    t = raw.t_s[rows]
    x = sim.states[np.searchsorted(sim.t_s, t)]
    under, east = (s.station for s in scenario.stations)
    model = DdorModel(under, east, scenario.orientation)
    quasar = quasar_direction(x[:, :3], math.radians(5.0), 0.0)
    np.testing.assert_allclose(raw.A[rows][:, eop], model.eop_partials(t, x, quasar)[:, 0],
                               rtol=1e-14, atol=0)
    q = [names.index(n) for n in QUASAR]
    np.testing.assert_allclose(raw.A[rows][:, q], model.quasar_partials(t, x, quasar)[:, 0],
                               rtol=1e-14, atol=0)
    # The columns are live: > 1 m of range per ms of UT1 somewhere (EAST, 40° off the
    # sub-spacecraft point), > 0.1 mm per nrad of pole.
    assert np.max(np.abs(raw.A[:, eop[0]])) > 1e-3
    assert np.all(np.max(np.abs(raw.A[:, eop[1:]]), axis=0) > 1e2)  # km/rad
    # Stations' rows have no quasar columns.
    assert np.all(raw.A[~rows][:, q] == 0.0)


def test_tape_round_trip(simulated, tmp_path) -> None:
    _, sim = simulated
    back = read_t13(write_t13(tmp_path / "eop.t13.h5", sim.tape))
    assert back.parameters.kind == sim.tape.parameters.kind
    assert back.parameters.name == sim.tape.parameters.name


def test_scenario_keys() -> None:
    names = [p.name for p in parse_scenario(_document(["ut1_s"], False), SOURCE).parameters]
    assert "eop.ut1_s" in names and "eop.xp_rad" not in names
    assert not any(n.endswith("quasar_ra_rad") for n in names)
    doc = _document(True, False)
    doc["earth_orientation"] = "gmst"
    assert [p.name for p in parse_scenario(doc, SOURCE).parameters if p.kind == "eop"] == [
        "eop.ut1_s"]
    doc["parameters"]["earth_orientation"] = ["ut1_s", "yp_rad"]
    with pytest.raises(InputError, match="no polar motion") as err:
        parse_scenario(doc, SOURCE)
    assert err.value.field == "parameters.earth_orientation"
    doc = _document(["ut1_s", "lod_s"], False)
    with pytest.raises(InputError, match="earth_orientation"):
        parse_scenario(doc, SOURCE)


def test_tapp3_considers_eop_and_the_budget_shows_it(simulated) -> None:
    """Fit world: the EOP and quasar offsets held at 0 (σ = 0); real world: σ(UT1) = 0.5 ms,
    σ(x_p, y_p) = 5 nrad, σ(quasar) = 1 nrad. The orbit's real covariance grows by the
    consider terms, and the budget carries "eop" and "quasar" as sources that add up."""
    _, sim = simulated
    tape: T13 = sim.tape
    fit = sigmas(tape, **dict.fromkeys(EOP + QUASAR, 0.0))
    real = sigmas(tape, **SIGMA_EOP, **dict.fromkeys(QUASAR, SIGMA_QUASAR))
    certain = sigmas(tape, **dict.fromkeys(EOP + QUASAR, 0.0))
    out = ["cov-real p@current"]
    common = {"times": {"print": [1]}, "commands": {"print": out},
              "budget": {"groups": {"eop": list(EOP), "quasar": list(QUASAR)}}}
    considered = run(tape, deck(tape, fit=fit, real=real, **common))
    block = [b for b in considered.blocks if b.kind == "print"][-1]
    entity = block.entities[0]
    budget = entity.budget
    assert "eop (a priori)" in budget.sources and "quasar (a priori)" in budget.sources
    eop_share = budget.variances[budget.sources.index("eop (a priori)")]
    assert np.all(eop_share[:3] > 0.0)
    np.testing.assert_allclose(budget.variances.sum(axis=0), budget.total, rtol=1e-9)
    reference = run(tape, deck(tape, fit=fit, real=certain, times={"print": [1]},
                               commands={"print": out}))
    ref = [b for b in reference.blocks if b.kind == "print"][-1].entities[0].matrix
    assert np.all(np.diag(entity.matrix)[:3] > np.diag(ref)[:3])


@pytest.mark.slow
def test_deep_space_with_eop_and_ddor_through_tapp3() -> None:
    """A reproduction (slow: 30 days with relativistic light time); the fast test that guards
    its contract, EOP columns on the tape and "eop" a source of TAPP III's budget, is
    :func:`test_tapp3_considers_eop_and_the_budget_shows_it`. The example deep_space.toml
    (without its stochastic accelerations, as the fast tests
    of test_reference) with ``earth_orientation = true`` and ΔDOR on Goldstone-Canberra with
    its quasar position: the tape has the three EOP columns, and tapp3_deep_space.toml with
    σ(UT1) = 0.5 ms, σ(x_p, y_p) = 5 nrad, σ(quasar) = 1 nrad considered (fit σ = 0) runs,
    with "eop" a source of the orbit's budget: measured 6.4, 1.7, 0.6 m in x, y, z at day 1
    (of σ 60, 48, 95 m), falling to < 1 mm once the range biases and the lunar-distance
    Doppler take over; the quasar's share is 2.4 and 5.3 m in y, z at day 30."""
    doc = read_toml(SCENARIOS / "deep_space.toml")
    doc.pop("stochastic")
    doc["parameters"]["earth_orientation"] = True
    doc["ddor"] = {"baselines": [["GOLDSTONE", "CANBERRA"]], "interval_s": 21600.0,
                   "min_window_s": 1800.0, "quasar_position": True, "fit": {"sigma_ns": 0.06}}
    tape = simulate(parse_scenario(doc, str(SCENARIOS / "deep_space.toml"))).tape
    kinds = dict(zip(tape.parameters.name, tape.parameters.kind, strict=True))
    assert [n for n, k in kinds.items() if k == "eop"] == list(EOP)
    quasar = ("GOLDSTONE-CANBERRA.quasar_ra_rad", "GOLDSTONE-CANBERRA.quasar_dec_rad")
    deck_doc = read_toml(SCENARIOS / "tapp3_deep_space.toml")
    deck_doc["tape"].pop("n_o")
    deck_doc["fit"]["stochastic"] = deck_doc["real"]["stochastic"] = "ignore"
    deck_doc["fit"]["apriori"]["sigma"].update(dict.fromkeys(EOP + quasar, 0.0))
    deck_doc["real"]["apriori"]["sigma"].update(
        {**SIGMA_EOP, **dict.fromkeys(quasar, SIGMA_QUASAR)})
    deck_doc["budget"] = {"groups": {"eop": list(EOP), "quasar": list(quasar)}}
    result = run(tape, deck_doc)
    day1 = next(e for b in result.blocks if b.kind == "print" and b.k == 1
                for e in b.entities if e.command.alias() == "cov-real p@current")
    budget = day1.budget
    eop_m = np.sqrt(budget.variances[budget.sources.index("eop (a priori)")][:3]) * 1e3
    assert np.all(eop_m > 0.1) and np.all(eop_m < 0.2 * np.sqrt(budget.total[:3]) * 1e3)
    np.testing.assert_allclose(budget.variances.sum(axis=0), budget.total, rtol=1e-9)
