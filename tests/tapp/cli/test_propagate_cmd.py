"""``tapp propagate`` end to end through the typer app."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli import app
from tapp.constants import GM_EARTH_km3_s2

runner = CliRunner()


def test_json_output_has_grid_states_and_stm() -> None:
    result = runner.invoke(app, ["propagate", "--orbit", "a=6550.524,e=0,i=30,raan=0,argp=0,M=0",
                                 "--arc", "1h", "--step", "600s", "--truth", "J2", "--stm", "J0",
                                 "--json", "-"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    t = np.array(out["t_s"])
    np.testing.assert_array_equal(t, np.arange(0.0, 3601.0, 600.0))
    states = np.array(out["state"])
    stm = np.array(out["stm"])
    assert states.shape == (7, 6) and stm.shape == (7, 6, 6)
    np.testing.assert_array_equal(stm[0], np.eye(6))
    # circular orbit of radius a: the first state is at a on the x axis, speed sqrt(mu/a)
    assert states[0, 0] == pytest.approx(6550.524, abs=1e-9)
    assert np.linalg.norm(states[0, 3:]) == pytest.approx(np.sqrt(GM_EARTH_km3_s2 / 6550.524))


def test_method_option_selects_the_integrator_and_both_agree() -> None:
    base = ["propagate", "--orbit", "SATORB7", "--arc", "2h", "--step", "600s", "--json", "-"]
    dop = runner.invoke(app, base)
    rkn = runner.invoke(app, [*base, "--method", "rkn12"])
    assert dop.exit_code == 0 and rkn.exit_code == 0, rkn.output
    a, b = (np.array(json.loads(r.stdout)["state"]) for r in (dop, rkn))
    # both at tolerance 1e-13 on an e = 0.1 orbit: within a millimetre over 2 h
    assert np.abs(a[:, :3] - b[:, :3]).max() < 1e-6
    bad = runner.invoke(app, [*base, "--method", "rk4"])
    assert bad.exit_code == 2 and "--method" in bad.stderr


def test_named_orbit_equals_its_elements() -> None:
    by_name = runner.invoke(app, ["propagate", "--orbit", "SATORB7", "--arc", "0.5h",
                                  "--json", "-"])
    by_elems = runner.invoke(app, ["propagate", "--orbit",
                                   "a=7278.360,e=0.1,i=0,raan=0,argp=0,M=0", "--arc", "0.5h",
                                   "--json", "-"])
    assert by_name.exit_code == 0 and by_elems.exit_code == 0
    assert json.loads(by_name.stdout)["state"] == json.loads(by_elems.stdout)["state"]


@pytest.mark.parametrize(("args", "option"), [
    (["--truth", "J12"], "--truth"),
    (["--stm", "2x3"], "--stm"),
    (["--truth", "Z2"], "--truth"),
    (["--arc", "-1h"], "--arc"),
    (["--tol", "0"], "--tol"),
    (["--step", "nans"], "--step"),
    (["--orbit", "x=1,y=2,z=inf,vx=0,vy=1,vz=0"], "--orbit"),
    (["--orbit", "a=7000,e=0"], "--orbit"),
    (["--orbit", "SATORB99"], "--orbit"),
])
def test_bad_input_gives_one_clear_line_and_nonzero_exit(args: list[str], option: str) -> None:
    base = ["propagate", "--orbit", "SATORB1", "--arc", "0.1h"]
    # later options override earlier ones in click, so appending replaces the default
    result = runner.invoke(app, base + args)
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {option}")


def test_version() -> None:
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and result.stdout.startswith("tapp ")


def test_the_earlier_spellings_still_run_with_the_new_one_named() -> None:
    """--hours 0.5 and a bare --step 600 (seconds) give the numbers of --arc 0.5h --step
    600s, and a warning on stderr for each naming the spelling to use; both spans at once are
    refused in one line."""
    new = runner.invoke(app, ["propagate", "--orbit", "SATORB1", "--arc", "0.5h", "--step",
                              "600s", "--json", "-"])
    old = runner.invoke(app, ["propagate", "--orbit", "SATORB1", "--hours", "0.5", "--step",
                              "600", "--json", "-"])
    assert new.exit_code == old.exit_code == 0, old.output
    assert json.loads(new.stdout) == json.loads(old.stdout)
    assert new.stderr == ""
    assert "--hours 0.5 is deprecated: write --arc 0.5h" in old.stderr
    assert "--step 600 (seconds) is deprecated: write --step 600s" in old.stderr
    both = runner.invoke(app, ["propagate", "--orbit", "SATORB1", "--arc", "1h", "--hours",
                               "1"])
    assert both.exit_code == 2 and len(both.stderr.strip().splitlines()) == 1
    assert both.stderr.startswith("error: --arc: value: expected --arc or the deprecated --hours")
