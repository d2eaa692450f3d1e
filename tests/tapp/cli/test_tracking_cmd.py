"""``tapp simulate`` and ``tapp tape info`` end to end through the typer app."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from astropy.time import Time, TimeDelta
from oem import OrbitEphemerisMessage
from typer.testing import CliRunner

import tapp.cli.tracking_cmd  # noqa: F401  (registers the commands until tapp.cli imports it)
from tapp.cli.common import app
from tapp.tape.t13_hdf5 import read_t13
from tapp.tracking.oem import INTERPOLATION_TOL_KM, INTERPOLATION_TOL_KM_S
from tapp.tracking.scenario import parse_scenario
from tapp.tracking.simulate import EDITING_RULES, simulate
from tests.tapp.tracking.helpers import geo_document, leo_document

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
LEO = SCENARIOS / "leo_equatorial.toml"
runner = CliRunner()


def _edited(tmp_path: Path, old: str, new: str, source: Path = LEO) -> Path:
    text = source.read_text()
    assert old in text, old
    path = tmp_path / "edited.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def test_leo_scenario_to_tape_with_raw_rows_and_oem(tmp_path: Path) -> None:
    out, oem = tmp_path / "leo.t13.h5", tmp_path / "leo.oem"
    res = runner.invoke(app, ["simulate", str(LEO), "-o", str(out), "--raw", "--oem", str(oem),
                              "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    assert (info["n_o"], info["n_p"], info["n_m"], info["n_ts"], info["n_it"]) == (
        38, 6, 6, 6, 8)
    assert info["bytes"] == out.stat().st_size and info["observations"] > 500
    tape = read_t13(out)
    assert tape.raw is not None and tape.raw.t_s.size == info["observations"]
    lines = oem.read_text().splitlines()
    assert lines[0] == "CCSDS_OEM_VERS = 2.0" and "REF_FRAME = GCRF" in lines  # iau2006
    data = lines[lines.index("META_STOP") + 2:]
    assert len(data) == 2881  # t = 0 and every 30 s over 24 h
    assert data[0].startswith("2026-01-01T00:00:00.000000 6550.524000000")


def test_deep_space_scenario_through_the_cli(tmp_path: Path) -> None:
    out = tmp_path / "deep.t13.h5"
    res = runner.invoke(app, ["simulate", str(SCENARIOS / "deep_space.toml"), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "n_o = 23" in res.stdout and "n_ts = 3" in res.stdout
    info = runner.invoke(app, ["tape", "info", str(out), "--json"])
    summary = json.loads(info.stdout)
    assert [s["name"] for s in summary["stations"]] == ["GOLDSTONE", "CANBERRA", "MADRID"]
    assert all(s["passes"] >= 25 and s["observations"] > 20000 for s in summary["stations"])
    assert [e["utc"] for e in summary["epochs"]] == [
        "2026-03-10T12:00:00.000", "2026-03-14T02:05:58.384", "2026-03-25T12:00:00.000"]
    assert summary["miss"]["names"] == ["b_dot_r_km", "b_dot_t_km", "flight_time_s"]


def test_tape_info_text(tmp_path: Path) -> None:
    out = tmp_path / "leo.t13.h5"
    assert runner.invoke(app, ["simulate", str(LEO), "-o", str(out)]).exit_code == 0
    res = runner.invoke(app, ["tape", "info", str(out)])
    assert res.exit_code == 0, res.output
    for text in ("T13", "KWAJALEIN.range_rate_bias_km_s", "Stations", "Epoch times",
                 "2026-01-01T12:00:00.000", "lambda_m_rad"):
        assert text in res.stdout, text


@pytest.mark.parametrize(("old", "new", "field"), [
    ('stations = ["QUITO", "KOUROU"', 'stations = ["QUITO", "NOWHERE"', "tracking.stations[1]"),
    ('observables = ["range", "range_rate"]', 'observables = ["range", "doppler"]',
     "tracking.observables[1]"),
    ('dynamic = ["GM", "J2"]', 'dynamic = ["GM", "J9"]', "parameters.dynamic[1]"),
    ("sigma_range_m = 15.0", "sigma_range_m = 0.0", "noise.fit.sigma_range_m"),
    ("epochs = [43200.0]", "epochs = [43200.0, 21600.0]", "times.epochs"),
    ("blackouts = []", "blackouts = [[0.0, 90000.0]]", "tracking"),
])
def test_bad_input_is_one_line_naming_file_and_field_and_no_tape(
        tmp_path: Path, old: str, new: str, field: str) -> None:
    path = _edited(tmp_path, old, new)
    out = tmp_path / "bad.t13.h5"
    res = runner.invoke(app, ["simulate", str(path), "-o", str(out)])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: {field}: expected"), lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["edited.toml"]


def test_unreadable_tapes(tmp_path: Path) -> None:
    out = tmp_path / "leo.t13.h5"
    assert runner.invoke(app, ["simulate", str(LEO), "-o", str(out)]).exit_code == 0
    os.truncate(out, out.stat().st_size // 3)
    res = runner.invoke(app, ["tape", "info", str(out)])
    assert res.exit_code == 2  # a corrupt tape is bad input (tapp.cli.common)
    assert res.stderr.strip().startswith(f"error: {out}: file: expected a readable HDF5")
    missing = runner.invoke(app, ["tape", "info", str(tmp_path / "none.h5")])
    assert missing.exit_code == 2 and "none.h5: file: expected an existing" in missing.stderr
    scenario = runner.invoke(app, ["simulate", str(tmp_path / "none.toml"), "-o", str(out)])
    assert scenario.exit_code == 2 and "none.toml: file:" in scenario.stderr


def test_geo_track_counts_printed_and_on_the_tape_add_up(tmp_path: Path) -> None:
    """The 12 h GEO track with max_pass_s = 8 h: every sample kept in 2 passes per station
    (tests/tapp/tracking/test_editing.py counts them by hand), and what simulate prints is
    what the tape says."""
    scenario, out = tmp_path / "geo.toml", tmp_path / "geo.t13.h5"
    scenario.write_text(tomli_w.dumps(geo_document()))
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(out), "--json"])
    assert res.exit_code == 0, res.output
    printed = json.loads(res.stdout)["stations"]
    editing = read_t13(out).editing
    for i, s in enumerate(printed):
        removed = [s["removed"][rule]["observations"] for rule in EDITING_RULES]
        assert s["observations"] + sum(removed) == s["scheduled_observations"] == 144
        assert (s["observations"], s["passes"], s["passes_added_by_split"]) == (144, 2, 1)
        assert removed == editing.removed_obs[i].tolist() == [0, 0, 0, 0]
    text = runner.invoke(app, ["simulate", str(scenario), "-o", str(out)])
    info = runner.invoke(app, ["tape", "info", str(out)])
    for res in (text, info):
        assert res.exit_code == 0, res.output
        assert "Observations: scheduled = kept + removed by each rule" in res.stdout
        cells = [[c.strip() for c in line.split("│")[1:-1]] for line in res.stdout.splitlines()]
        rows = [c[1:] for c in cells if len(c) == 5 + len(EDITING_RULES)]
        # name, scheduled, kept, removed by each rule, passes (+ added by splitting)
        assert rows == [[name, "144", "144", "0", "0", "0", "0", "2 (+1)"]
                        for name in ("UNDER", "EAST")]


# OEM states are printed to 1e-9 km and 1e-12 km/s: rounding of half of that.
PRINTED_KM, PRINTED_KM_S = 0.5e-9, 0.5e-12


def _read_oem(path: Path):
    """The single segment of an OEM read by the ``oem`` package, and its metadata."""
    message = OrbitEphemerisMessage.open(path)
    (segment,) = message.segments
    return segment, segment.metadata


@pytest.mark.parametrize(("orientation", "frame"), [("iau2006", "GCRF"), ("gmst", "EME2000")])
def test_oem_read_by_the_oem_package_is_the_simulated_trajectory(
        tmp_path: Path, orientation: str, frame: str) -> None:
    """Tracking starts 30 min after injection; the OEM runs from the injection (t = 0) to the
    last T13 time, says its frame and interpolation, and the ``oem`` package's own Lagrange
    interpolation of it gives the simulation's states at every simulated time."""
    doc = leo_document(tracking={"start": 1800.0})
    scenario, out, oem = tmp_path / "leo.toml", tmp_path / "leo.t13.h5", tmp_path / "leo.oem"
    scenario.write_text(tomli_w.dumps(doc))
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(out), "--oem", str(oem),
                              "--earth-orientation", orientation])
    assert res.exit_code == 0, res.output
    sim = simulate(parse_scenario(doc, str(scenario), orientation))
    segment, meta = _read_oem(oem)
    assert (meta["REF_FRAME"], meta["CENTER_NAME"], meta["TIME_SYSTEM"]) == (frame, "EARTH",
                                                                             "UTC")
    assert (meta["INTERPOLATION"], meta["INTERPOLATION_DEGREE"]) == ("LAGRANGE", 7)
    epoch = Time("2026-01-01T00:00:00", scale="utc")
    assert abs((meta["START_TIME"] - epoch).sec) < 1e-6
    assert abs((meta["STOP_TIME"] - epoch).sec - 10800.0) < 1e-6
    states = list(segment.states)
    assert abs((states[0].epoch - epoch).sec) < 1e-6
    np.testing.assert_allclose(states[0].position, sim.states[0, :3], rtol=0, atol=PRINTED_KM)
    gaps = np.diff([(s.epoch - epoch).sec for s in states])
    assert gaps.max() <= 20.0 + 1e-6  # the data interval, also before tracking starts
    for t, x in zip(sim.t_s[::7], sim.states[::7], strict=True):
        got = segment(epoch + TimeDelta(t, format="sec"))
        np.testing.assert_allclose(got.position, x[:3], rtol=0,
                                   atol=INTERPOLATION_TOL_KM + PRINTED_KM)
        np.testing.assert_allclose(got.velocity, x[3:], rtol=0,
                                   atol=INTERPOLATION_TOL_KM_S + PRINTED_KM_S)
