"""Surface forces in tracking scenarios: the [model] keys build the state and variational
models, Cr and Cd become parameters, and every bad value is one InputError naming the file
and the key (exit code 2 on the CLI)."""

from __future__ import annotations

from pathlib import Path

import pytest
import tomli_w
from typer.testing import CliRunner

from tapp.cli import app
from tapp.errors import InputError
from tapp.tracking.scenario_build import parse_scenario
from tests.tapp.tracking.helpers import SOURCE, leo_document, leo_scenario

SURFACE = {"area_to_mass_m2_kg": 0.01, "srp": True, "c_r": 1.4,
           "atmosphere": "harris_priester", "c_d": 2.1}


def test_surface_keys_build_both_models_and_the_parameters() -> None:
    sc = leo_scenario(model={**SURFACE, "var_srp": False},
                      parameters={"dynamic": ["GM_km3_s2", "Cr", "Cd"], "values": {"Cd": 2.3}})
    assert sc.state_model.name == "J2+srp+drag(harris_priester)"
    assert sc.var_model.name == "J2+drag(harris_priester)"  # var_srp = false, drag inherited
    assert sc.state_model.surface.area_to_mass_m2_kg == 0.01
    named = {p.name: (p.unit, p.nominal) for p in sc.parameters if p.kind == "dynamic"}
    assert named["Cr"] == ("1", 1.4) and named["Cd"] == ("1", 2.3)


def test_the_exponential_layer_keys_reach_both_models() -> None:
    sc = leo_scenario(model={"area_to_mass_m2_kg": 0.01, "atmosphere": "exponential",
                             "rho0_kg_m3": 2.07e-9, "h0_km": 150.0, "scale_height_km": 22.523})
    for model in (sc.state_model, sc.var_model):
        layer = model.surface.exponential
        assert (layer.rho0_kg_m3, layer.h0_km, layer.scale_height_km) == (2.07e-9, 150.0,
                                                                           22.523)


def test_without_surface_keys_the_models_have_none() -> None:
    sc = leo_scenario()
    assert sc.state_model.surface is None and sc.var_model.surface is None


@pytest.mark.parametrize(("model", "parameters", "field", "words"), [
    ({"srp": True}, {}, "model.area_to_mass_m2_kg", "area-to-mass ratio"),
    ({**SURFACE, "area_to_mass_m2_kg": 0.0}, {}, "model.area_to_mass_m2_kg", "(0, 50]"),
    ({**SURFACE, "area_to_mass_m2_kg": 120.0}, {}, "model.area_to_mass_m2_kg", "unit slip"),
    ({**SURFACE, "c_r": 3.0}, {}, "model.c_r", "1 + reflectivity"),
    ({**SURFACE, "c_r": -0.1}, {}, "model.c_r", "[0, 2.5]"),
    ({**SURFACE, "c_d": 0.0}, {}, "model.c_d", "(0, 5]"),
    ({**SURFACE, "atmosphere": "jacchia"}, {}, "model.atmosphere", "harris_priester"),
    ({**SURFACE, "var_atmosphere": "msis"}, {}, "model.var_atmosphere", "exponential"),
    ({**SURFACE, "srp": False}, {"dynamic": ["Cr"]}, "parameters.dynamic[0]", "Cr (with srp)"),
    ({**SURFACE, "atmosphere": "none"}, {"dynamic": ["Cd"]}, "parameters.dynamic[0]",
     "Cd (with an atmosphere)"),
    (SURFACE, {"dynamic": ["Cd"], "values": {"Cd": -1.0}}, "parameters.values.Cd", "(0, 5]"),
    (SURFACE, {"dynamic": ["Cr"], "values": {"Cr": 9.0}}, "parameters.values.Cr", "[0, 2.5]"),
    ({**SURFACE, "rho0_kg_m3": 0.0}, {}, "model.rho0_kg_m3", "sea level"),
    ({**SURFACE, "h0_km": -5.0}, {}, "model.h0_km", "[0, 2500]"),
    ({**SURFACE, "scale_height_km": 5e3}, {}, "model.scale_height_km", "(0, 1000]"),
])
def test_bad_surface_input_is_one_line_naming_file_and_key(model, parameters, field,
                                                          words) -> None:
    with pytest.raises(InputError) as err:
        parse_scenario(leo_document(model=model, parameters=parameters), SOURCE)
    text = str(err.value)
    assert (err.value.source, err.value.field) == (SOURCE, field)
    assert "\n" not in text and words in text, text


def test_drag_about_another_centre_is_refused() -> None:
    from tapp.dynamics.spec import ForceModel, SurfaceForces, parse_gravity

    with pytest.raises(InputError, match="drag only about the Earth"):
        ForceModel(parse_gravity("J0"), "moon",
                   surface=SurfaceForces(0.01, atmosphere="exponential"))


def test_the_cli_exits_2_on_a_bad_drag_coefficient(tmp_path: Path) -> None:
    scenario = tmp_path / "bad.toml"
    scenario.write_text(tomli_w.dumps(leo_document(model={**SURFACE, "c_d": 7.0})))
    res = CliRunner().invoke(app, ["simulate", str(scenario), "-o", str(tmp_path / "o.h5")])
    assert res.exit_code == 2, res.output
    assert res.stderr.strip().startswith(f"error: {scenario}: model.c_d: expected a value in")
    assert not (tmp_path / "o.h5").exists()
