"""One vocabulary across input files: the same table has the same keys everywhere, and an old
spelling is refused in one line that names the new key.

Each case edits a shipped example back to an old spelling and reads it with the program's own
reader (the CLI's path to the file).
"""

from __future__ import annotations

from pathlib import Path
from typing import get_args

import pytest

from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.models_file import ModelTable
from tapp.io.orbits import OrbitTable
from tapp.io.tomlfile import read_toml
from tapp.od.study_file import read_study
from tapp.targeting.searchfile import SearchFile, scenario_search
from tapp.tracking.scenario_build import parse_scenario, read_scenario
from tapp.tracking.scenario_file import ScenarioFile


def _search(path: Path) -> object:
    return scenario_search(read_toml(path), str(path))


@pytest.mark.parametrize(("example", "new", "old", "read", "field", "renamed_to"), [
    ("search_bplane.toml", 'var_gravity = "J2"', 'stm_gravity = "J2"', _search,
     "model.stm_gravity", "var_gravity"),
    ("search_bplane.toml", 'var_third_bodies = ["sun", "moon"]',
     'stm_third_bodies = ["sun", "moon"]', _search, "model.stm_third_bodies",
     "var_third_bodies"),
    ("deep_space.toml", 'var_gravity = "J2"', 'stm_gravity = "J2"', read_scenario,
     "model.stm_gravity", "var_gravity"),
    ("approx_stm.toml", 'gravity = "J2"\nvar_gravity = ["J2", "J0"]',
     'truth = "J2"\nvar_gravity = ["J2", "J0"]', read_study, "dc[0].truth", "gravity"),
    ("approx_stm.toml", 'var_gravity = ["J2", "J0"]', 'stm = ["J2", "J0"]', read_study,
     "dc[0].stm", "var_gravity"),
    ("approx_stm.toml", "seed = 1969", "seed = 1969\nsigma_range_m = 15.0", read_study,
     "tracking.sigma_range_m", "[noise.fit] sigma_range_m"),
    ("approx_stm.toml", "[orbits.SATORB1]\n", "[orbits.SATORB1]\nx_km = 6550.524\n",
     read_study, "orbits.SATORB1.x_km", "r_km = [x_km, y_km, z_km]"),
    ("search_bplane.toml", "v_km_s = [", "vy_km_s = 1.0\nv_km_s = [", _search,
     "injection.vy_km_s", "v_km_s = [vx_km_s, vy_km_s, vz_km_s]"),
])
def test_an_old_spelling_is_refused_naming_the_new_key(
        tmp_path: Path, example: str, new: str, old: str, read, field: str,
        renamed_to: str) -> None:
    text = (EXAMPLES / example).read_text()
    assert new in text
    path = tmp_path / example
    path.write_text(text.replace(new, old, 1))
    with pytest.raises(InputError) as info:
        read(path)
    assert (info.value.source, info.value.field) == (str(path), field)
    assert info.value.expected == f"{renamed_to} in its place (the key was renamed)"
    assert "\n" not in str(info.value)


def test_scenario_and_search_files_share_the_injection_and_model_tables() -> None:
    for schema in (ScenarioFile, SearchFile):
        assert schema.model_fields["model"].annotation is ModelTable
    assert SearchFile.model_fields["injection"].annotation is OrbitTable
    # a scenario's [injection] may give way to a [reference] trajectory
    assert get_args(ScenarioFile.model_fields["injection"].annotation) == (OrbitTable,
                                                                          type(None))


def test_a_search_injection_may_be_given_by_elements_as_a_scenario_s(tmp_path: Path) -> None:
    """The SEARCH file reads the scenario's [injection]: classical elements give the same
    state as the scenario's own reading of them."""
    text = (EXAMPLES / "search_bplane.toml").read_text()
    start, end = text.index("[injection]"), text.index("[model]")
    elements = ("[injection]\na_km = 200000.0\ne = 0.96\ni_deg = 28.5\nraan_deg = 10.0\n"
                "argp_deg = 20.0\nM_deg = 0.0\n\n")
    path = tmp_path / "search.toml"
    path.write_text(text[:start] + elements + text[end:])
    search = _search(path)
    leo = read_toml(EXAMPLES / "leo_equatorial.toml")
    leo["injection"] = read_toml(path)["injection"]
    x0 = parse_scenario(leo, "leo.toml").x0
    assert search.program.r0_km.tolist() == x0[:3].tolist()
    assert search.v0_km_s.tolist() == x0[3:].tolist()
