"""Orbit specs: an orbit that passes below the Earth's surface is refused unless allowed
(issue 10, class 4), and the ``[orbits.NAME]`` tables follow one schema (class 5)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli import app
from tapp.constants import GM_EARTH_km3_s2, R_EARTH_km
from tapp.errors import InputError
from tapp.io.orbits import check_perigee, named_orbits, parse_orbit, perigee_radius_km

runner = CliRunner()
BELOW = "a=7000,e=0.2,i=0,raan=0,argp=0,M=180"   # apogee 8400 km, perigee 5600 km


def test_perigee_radius_of_an_ellipse_is_a_times_one_minus_e() -> None:
    x = parse_orbit("a=7500,e=0.1,i=30,raan=0,argp=0,M=90")
    assert perigee_radius_km(x) == pytest.approx(6750.0, rel=1e-12)


def test_an_orbit_whose_perigee_is_below_the_surface_is_refused_with_radius_and_limit() -> None:
    with pytest.raises(InputError) as info:
        parse_orbit(BELOW)
    assert (info.value.source, info.value.field, info.value.got) == ("--orbit", "orbit", 5600.0)
    assert info.value.expected.startswith(f"a perigee radius r_p >= {R_EARTH_km} km")
    assert "778.1 km below it; --allow-subsurface if you mean it" in info.value.expected
    x = parse_orbit(BELOW, allow_subsurface=True)
    assert np.linalg.norm(x[:3]) == pytest.approx(8400.0)


def test_a_start_below_the_surface_is_refused() -> None:
    with pytest.raises(InputError, match=r"a start radius \|r\| >= 6378.1363 km"):
        parse_orbit("x=6000,y=0,z=0,vx=0,vy=8,vz=0")


def test_an_outbound_escape_from_low_perigee_is_accepted_an_inbound_one_is_not() -> None:
    r = R_EARTH_km + 200.0
    v_radial = 1.2 * np.sqrt(2 * GM_EARTH_km3_s2 / r)   # hyperbolic, straight up
    out = np.array([r, 0.0, 0.0, v_radial, 0.1, 0.0])
    assert check_perigee(out, "s", "f") is out
    with pytest.raises(InputError, match="a perigee radius"):
        check_perigee(out * np.array([1, 1, 1, -1, 1, 1]), "s", "f")


def test_named_orbits_honour_their_table_and_the_flag(tmp_path: Path) -> None:
    path = tmp_path / "orbits.toml"
    path.write_text("[orbits.LOW]\na_km = 7000.0\ne = 0.2\ni_deg = 0.0\nraan_deg = 0.0\n"
                    "argp_deg = 0.0\nM_deg = 180.0\n")
    with pytest.raises(InputError) as info:
        parse_orbit("LOW", scenario=path)
    assert (info.value.source, info.value.field) == (str(path), "orbits.LOW")
    assert "orbits.LOW.allow_subsurface = true or --allow-subsurface" in info.value.expected
    assert parse_orbit("LOW", scenario=path, allow_subsurface=True).shape == (6,)
    path.write_text(path.read_text() + "allow_subsurface = true\n")
    assert named_orbits(path)["LOW"].shape == (6,)


@pytest.mark.parametrize(("table", "field", "expected"), [
    ("a_km = true\ne = 0.0\ni_deg = 0.0\nraan_deg = 0.0\nargp_deg = 0.0\nM_deg = 0.0\n",
     "orbits.X.a_km", "a number"),
    ("a_km = 7000.0\ne = 0.0\ni_deg = 0.0\nraan_deg = 0.0\nargp_deg = 0.0\nM = 0.0\n",
     "orbits.X.M", "no such key (allowed: r_km, v_km_s, a_km, e, i_deg, "),
    ("a_km = 7000.0\ne = 0.0\ni_deg = 0.0\nraan_deg = 0.0\nargp_deg = 0.0\n",
     "orbits.X", "r_km and v_km_s, or a_km, e, i_deg, raan_deg, argp_deg and M_deg (or "
     "nu_deg)"),
    ('r_km = ["7000", 0.0, 0.0]\nv_km_s = [0.0, 7.5, 0.0]\n', "orbits.X.r_km[0]", "a number"),
    ("r_km = [7000.0, 0.0, 0.0]\n", "orbits.X", "r_km and v_km_s, or a_km"),
])
def test_orbit_tables_follow_their_schema(tmp_path: Path, table: str, field: str,
                                          expected: str) -> None:
    path = tmp_path / "orbits.toml"
    path.write_text("[orbits.X]\n" + table)
    with pytest.raises(InputError) as info:
        named_orbits(path)
    assert (info.value.source, info.value.field) == (str(path), field)
    assert info.value.expected.startswith(expected)


@pytest.mark.parametrize("command", ["propagate", "dc", "ekf", "rsig"])
def test_the_commands_refuse_a_subsurface_orbit_in_one_line(command: str) -> None:
    result = runner.invoke(app, [command, "--orbit", BELOW])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and "--orbit: orbit: expected a perigee radius" in lines[0]


def test_propagate_accepts_a_subsurface_orbit_when_told() -> None:
    result = runner.invoke(app, ["propagate", "--orbit", BELOW, "--allow-subsurface",
                                 "--arc", "0.1h", "--json", "-"])
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize(("options", "message"), [
    (["--tol", "1"], "--tol: value: expected an integrator tolerance in [1e-15, 1e-06]"),
    (["--tol", "1e-20"], "--tol: value: expected an integrator tolerance in [1e-15, 1e-06]"),
    (["--third-body", "sun", "--third-body", "sun"],
     "third_bodies: expected each body once (sun given 2 times"),
])
def test_propagate_refuses_impossible_integration_settings(options: list, message: str) -> None:
    result = runner.invoke(app, ["propagate", "--orbit", "a=7000,e=0,i=0,raan=0,argp=0,M=0",
                                 "--arc", "1h", *options])
    assert result.exit_code == 2
    assert message in result.output and len(result.output.strip().splitlines()) == 1


@pytest.mark.parametrize(("spec", "expected"), [
    ("x=1e300,y=0,z=0,vx=0,vy=1,vz=0", "position components within 1e+09 km"),
    ("x=7000,y=0,z=0,vx=0,vy=1e5,vz=0", "velocity components within 1000 km/s"),
    ("a=-1e300,e=2,i=0,raan=0,argp=0,M=0", "|a| <= 1e+09 km"),
    ("a=-7000,e=1e300,i=0,raan=0,argp=0,M=0", "e <= 1e+06"),
    ("a=-7000,e=3,i=0,raan=0,argp=0,nu=170", "a true anomaly within the asymptotes"),
])
def test_states_no_earth_orbit_can_have_are_refused_not_overflowed(spec: str,
                                                                   expected: str) -> None:
    with pytest.raises(InputError) as info:
        parse_orbit(spec, allow_subsurface=True)
    assert info.value.expected.startswith(expected)


def test_angles_are_taken_modulo_one_turn() -> None:
    a = parse_orbit("a=7000,e=0.01,i=30,raan=-30,argp=0,M=10")
    b = parse_orbit("a=7000,e=0.01,i=390,raan=330,argp=720,M=370")
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    assert np.all(np.isfinite(parse_orbit("a=7000,e=0.01,i=0,raan=0,argp=0,M=1e300")))
