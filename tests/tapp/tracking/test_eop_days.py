"""Earth orientation offsets per UTC day (``earth_orientation_per = "day"``): the days of the
tracking window, each day's columns on the tape, and TAPP III: fully correlated days give the
constant offset's covariance, as they must. The geometry is the GEO track of
:func:`helpers.geo_document` started at 18h UTC, so that its 12 hours span two UTC days."""

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.time import Epoch
from tapp.tracking.eop_days import eop_days
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import simulate
from tests.tapp.processor.helpers import deck, run, sigmas
from tests.tapp.tracking.helpers import SOURCE, geo_document

EOP = ("ut1_s", "xp_rad", "yp_rad")
DAYS = ("2026-01-01", "2026-01-02")
SIGMA = {"ut1_s": 0.5e-3, "xp_rad": 5e-9, "yp_rad": 5e-9}


def _document(per: str) -> dict:
    doc = geo_document()
    doc["epoch"] = "2026-01-01T18:00:00"
    doc["parameters"].update(earth_orientation=True, earth_orientation_per=per)
    return doc


@pytest.fixture(scope="module")
def runs():
    return {per: simulate(parse_scenario(_document(per), SOURCE), raw=True)
            for per in ("arc", "day")}


def test_the_days_of_a_window_count_leap_seconds():
    days = eop_days(Epoch.from_calendar(2016, 12, 31, 12), 0.0, 86400.0)
    assert days.dates == ("2016-12-31", "2017-01-01")
    assert days.bounds_s == (-43200.0, 43201.0, 129601.0)  # 23:59:60 on 31 December
    np.testing.assert_array_equal(days.index([0.0, 43200.5, 43201.0]), [0, 0, 1])
    with pytest.raises(ValueError, match="outside"):
        days.index([129601.0])


def test_each_day_has_its_offsets_in_q(runs):
    names = list(runs["day"].tape.parameters.name)
    expected = [f"eop.{n}.{d}" for d in DAYS for n in EOP]
    assert [n for n in names if n.startswith("eop.")] == expected
    assert "eop.ut1_s" in runs["arc"].tape.parameters.name


def test_a_days_columns_are_the_constant_offsets_in_its_rows_only(runs):
    """Per day, the constant offset's columns split by the rows' UTC day: their sum is the
    constant offset's column (exactly), and each day's is zero outside its rows."""
    arc, day = runs["arc"].tape.raw, runs["day"].tape.raw
    names_arc, names_day = list(runs["arc"].tape.parameters.name), list(
        runs["day"].tape.parameters.name)
    np.testing.assert_array_equal(arc.t_s, day.t_s)
    first_day = arc.t_s < 6 * 3600.0  # 18h + 6h: midnight
    assert first_day.any() and (~first_day).any()
    for n in EOP:
        constant = arc.A[:, names_arc.index(f"eop.{n}")]
        split = [day.A[:, names_day.index(f"eop.{n}.{d}")] for d in DAYS]
        np.testing.assert_array_equal(split[0] + split[1], constant)
        assert np.all(split[0][~first_day] == 0.0) and np.all(split[1][first_day] == 0.0)
        assert np.any(split[0] != 0.0) and np.any(split[1] != 0.0)


def test_fully_correlated_days_are_the_constant_offset_in_tapp3(runs):
    """Real world: σ's of the brief per day, the two days' offsets correlated by ρ = 1 (one
    offset), the fit holding them at 0: the printed real covariance is the constant
    offset's, to the rounding of the consider terms; with independent days it differs."""
    out = ["cov-real p@current"]
    printed = {}
    for per, correlation in (("arc", []), ("day", [[f"eop.{n}.{DAYS[0]}", f"eop.{n}.{DAYS[1]}",
                                                    1.0] for n in EOP]),
                             ("independent", [])):
        tape = runs["arc" if per == "arc" else "day"].tape
        eop = [n for n in tape.parameters.name if n.startswith("eop.")]
        real = sigmas(tape, **{n: SIGMA[n.split(".")[1]] for n in eop})
        doc = deck(tape, fit=sigmas(tape, **dict.fromkeys(eop, 0.0)), real=real,
                   times={"print": [1]}, commands={"print": out})
        doc["real"]["apriori"]["correlation"] = correlation
        block = [b for b in run(tape, doc).blocks if b.kind == "print"][-1]
        printed[per] = block.entities[0].matrix
    scale = np.sqrt(np.outer(np.diag(printed["arc"]), np.diag(printed["arc"])))
    assert np.max(np.abs(printed["day"] - printed["arc"]) / scale) < 1e-9
    assert np.max(np.abs(printed["independent"] - printed["arc"]) / scale) > 1e-6


def test_a_misspelt_span_is_refused():
    with pytest.raises(InputError, match="earth_orientation_per"):
        parse_scenario(_document("week"), SOURCE)
