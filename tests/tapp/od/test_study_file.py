"""The study file follows one declared schema (issue 10, class 5): a typo, an unknown section,
a boolean or a string where a number belongs is one line naming the file and the field."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import pytest

from tapp.constants import GM_EARTH_km3_s2
from tapp.errors import InputError
from tapp.examples import STUDY_FILE
from tapp.od import setup
from tapp.od.study_file import epoch, offset, read_study, shipped_study, tracking
from tapp.od.study_schema import StudyFile
from tapp.orbit.elements import cartesian_to_elements

SHIPPED = STUDY_FILE.read_text()


def _study(tmp_path: Path, old: str, new: str) -> Path:
    assert old in SHIPPED
    path = tmp_path / "study.toml"
    path.write_text(SHIPPED.replace(old, new, 1))
    return path


def _error(path: Path) -> InputError:
    with pytest.raises(InputError) as info:
        read_study(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(f"{path}: ")
    return info.value


def test_the_shipped_study_file_validates() -> None:
    study = shipped_study().file
    assert study.tracking.seed == 1969 and len(study.orbits) == 8
    assert [b.gravity for b in study.dc] == ["J2", "5x5", "J2", "J2", "J2"]
    assert study.ekf.apriori["1"][0] == 0.68 and study.rsig.cases[0] == ["J0", "J0"]
    shipped = shipped_study()
    assert tracking(shipped).seed == 1969 and shipped.data["tracking"]["seed"] == 1969
    assert study.dc_settings.max_iterations == 100
    # the paper's model (see the file's comment); iau2006 is the default for new files
    assert (study.earth_orientation, study.eop) == ("gmst", "iers")
    assert StudyFile.model_fields["earth_orientation"].default == "iau2006"
    arcs = study.rate_vs_arc.arcs_h.values()
    assert (arcs[0], arcs[-1]) == (6.0, 48.0)
    incs = study.rate_vs_inclination.inclinations_deg.values()
    assert (incs[0], incs[-1]) == (0.0, 180.0)


def test_the_offset_is_added_to_e() -> None:
    """The brief: the same error added to every orbit, +0.00012 on e (SATORB7 starts at
    e = 0.10012, SATORB8 at 0.30012, the circular orbits at 0.00012)."""
    off = offset(shipped_study())
    assert (off.de, off.e) == (0.00012, None)
    for name, e0 in (("SATORB1", 0.0), ("SATORB7", 0.1), ("SATORB8", 0.3)):
        x = setup.initial_estimate(setup.true_orbit(name, shipped_study()), off)
        a, e, i = cartesian_to_elements(x, GM_EARTH_km3_s2)[:3]
        true = shipped_study().file.orbits[name]
        assert e == pytest.approx(e0 + 0.00012, abs=1e-12)
        assert a == pytest.approx(true.a_km + 0.1, abs=1e-9)
        assert math.degrees(i) == pytest.approx(true.i_deg + 0.002, abs=1e-9)


def test_the_earlier_reading_e_set_still_reads_and_one_of_the_two_is_required(
        tmp_path: Path) -> None:
    path = _study(tmp_path, "de = 0.00012", "e = 0.00012")
    study = read_study(path)
    off = offset(study)
    x = setup.initial_estimate(setup.true_orbit("SATORB7", study), off)
    assert cartesian_to_elements(x, GM_EARTH_km3_s2)[1] == pytest.approx(0.00012, abs=1e-12)
    (tmp_path / "both").mkdir()
    both = _error(_study(tmp_path / "both", "de = 0.00012", "de = 0.00012\ne = 0.00012"))
    assert both.field == "initial_offset.de" and both.expected.startswith("either de")
    (tmp_path / "neither").mkdir()
    neither = _error(_study(tmp_path / "neither", "de = 0.00012", ""))
    assert neither.field == "initial_offset.de"


def test_a_misspelled_seed_is_named_with_the_allowed_keys(tmp_path: Path) -> None:
    # The example: `sed = 1969` silently used seed 0.
    err = _error(_study(tmp_path, "seed = 1969", "sed = 1969"))
    assert (err.field, err.got) == ("tracking.sed", 1969)
    assert err.expected == ("no such key (allowed: data_interval_s, span_days, seed, "
                            "equatorial_below_deg)")


def test_an_unknown_section_is_refused(tmp_path: Path) -> None:
    err = _error(_study(tmp_path, "[initial_offset]", "[extras]\nx = 1\n\n[initial_offset]"))
    assert err.field == "extras" and err.expected.startswith(
        "no such key (allowed: stations, networks, epoch, ")


@pytest.mark.parametrize(("old", "new", "field", "expected"), [
    ("seed = 1969", "seed = true", "tracking.seed", "an integer"),
    ("seed = 1969", "seed = -1", "tracking.seed", "a finite number >= 0"),
    ("span_days = 5.0", 'span_days = "5"', "tracking.span_days", "a number"),
    ("span_days = 5.0", "span_days = nan", "tracking.span_days", "a finite number"),
    ("data_interval_s = 30.0", "data_interval_s = 0.0", "tracking.data_interval_s",
     "a finite number > 0"),
    ("lat_deg = -0.6226", "lat_deg = true", "stations.QUITO.lat_deg", "a number"),
    ("h_km = 3.55", "h_km = 1e9", "stations.QUITO.h_km", "a ground-station height in"),
    ("da_m = 100.0", "da_m = inf", "initial_offset.da_m", "a finite number"),
    ("max_iterations = 100", "max_iterations = 12.5", "dc_settings.max_iterations",
     "an integer"),
    ("max_iterations = 100", "max_iterations = 1", "dc_settings.max_iterations",
     "a finite number >= 2"),
    ("max_iterations = 100", "max_iterations = 100000", "dc_settings.max_iterations",
     "a finite number <= 10000"),
    ("de = 0.00012", "de = true", "initial_offset.de", "a number"),
    ("step = 0.5 }", "step = 0.0 }", "rate_vs_arc.arcs_h.step", "a finite number > 0"),
    ('network = "global"', 'network = "galactic"', "rate_vs_inclination.network",
     "a network of [networks]"),
    ("last = 180.0", "last = 190.0", "rate_vs_inclination.inclinations_deg.last",
     "inclinations within 0..180 deg"),
    ("rms_rel_tol = 1e-3", "rms_rel_tl = 1e-3", "dc_settings.rms_rel_tl", "no such key"),
    ('gravity = "J2"', 'gravity = "J42"', "dc[0].gravity", "degree <= 8"),
    ('var_gravity = ["J2", "J0"]', 'var_gravity = ["J2", "J0x"]', "dc[0].var_gravity[1]",
     "a gravity model"),
    ("sigma_range_m = 15.0", "sigma_range_m = 0.0", "noise.fit.sigma_range_m",
     "a finite number > 0"),
    ("sigma_range_m = 15.0", "sigma_azimuth_deg = 15.0", "noise.fit.sigma_azimuth_deg",
     "no angle σ"),
    ('orbits = ["SATORB1"]', 'orbits = ["SATORB9"]', "dc[0].orbits[0]", "an orbit of"),
    ("arcs_h = [24.0, 12.0, 6.0]", 'arcs_h = [24.0, "12", 6.0]', "dc[0].arcs_h[1]",
     "a number"),
    ("1 = [0.68, 1e-5, 1e-5, 1e-5, 0.87e-3, 0.27e-3]", "1 = [0.68, 1e-5]", "ekf.apriori.1",
     "at least 6 items"),
    ('cases = [["J0", "J0"],', 'cases = [["J0"],', "rsig.cases[0]", "at least 2 items"),
    ('equatorial = ["QUITO",', 'equatorial = ["QUITOO",', "networks.equatorial[0]",
     "names of [stations.*] tables"),
    ('epoch = "2026-01-01T00:00:00"', "epoch = 2026", "epoch", "a UTC date (ISO 8601 string"),
    ('earth_orientation = "gmst"', 'earth_orientation = "GMST"', "earth_orientation",
     "one of"),
    ('eop = "iers"', 'eop = ""', "eop", '"iers" (the shipped IERS table)'),
])
def test_bad_entries_name_file_and_field(tmp_path: Path, old: str, new: str, field: str,
                                         expected: str) -> None:
    err = _error(_study(tmp_path, old, new))
    assert err.field == field
    assert err.expected.startswith(expected)


def test_the_runner_and_the_commands_read_the_validated_file(tmp_path: Path) -> None:
    path = _study(tmp_path, "seed = 1969", "sed = 1969")
    with pytest.raises(InputError, match=r"tracking\.sed: expected no such key"):
        read_study(path)


def test_the_orientation_follows_the_file_or_the_override() -> None:
    """One EarthOrientation per file and model (cached: its slow-term series are fitted once
    per run); the override names --earth-orientation when it is unknown."""
    shipped = shipped_study()
    assert setup.orientation(shipped).model == "gmst"
    assert setup.orientation(shipped).theta0_rad == epoch(shipped).gmst_rad()  # the study's angle
    iau = setup.orientation(shipped, model="iau2006")
    assert iau.model == "iau2006" and iau is setup.orientation(shipped, model="iau2006")
    with pytest.raises(InputError) as info:
        setup.orientation(shipped, model="itrf")
    assert (info.value.source, info.value.got) == ("--earth-orientation", "itrf")


def _two_days_before_the_table_ends() -> str:
    last_mjd = float(setup.orientation(shipped_study(), model="iau2006").scales.eop.mjd[-1])
    when = dt.datetime(1858, 11, 17) + dt.timedelta(days=last_mjd - 2)  # MJD 0
    return f"{when:%Y-%m-%dT%H:%M:%S}"


@pytest.mark.parametrize("outside", ["the epoch", "the 5-day tracking span"])
def test_an_epoch_or_span_outside_the_eop_table_names_file_and_epoch(
        tmp_path: Path, outside: str) -> None:
    epoch = "2060-01-01T00:00:00" if outside == "the epoch" else _two_days_before_the_table_ends()
    path = _study(tmp_path, 'epoch = "2026-01-01T00:00:00"', f'epoch = "{epoch}"')
    path.write_text(path.read_text().replace('earth_orientation = "gmst"',
                                             'earth_orientation = "iau2006"'))
    with pytest.raises(InputError) as info:
        setup.orientation(read_study(path))
    err = info.value
    assert (err.source, err.field) == (str(path), "epoch") and "\n" not in str(err)
    assert "IERS EOP table" in err.expected
    assert setup.orientation(read_study(path), "gmst").model == "gmst"  # gmst needs no EOP
