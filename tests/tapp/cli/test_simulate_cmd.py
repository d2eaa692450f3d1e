"""``tapp simulate`` and ``tapp tape info`` end to end through the typer app."""

from __future__ import annotations

import hashlib
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from astropy.time import Time, TimeDelta
from oem import OrbitEphemerisMessage
from typer.testing import CliRunner

import tapp.cli.simulate_cmd  # noqa: F401  (registers the commands until tapp.cli imports it)
from tapp.cli.common import app
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.ccsds.oem import INTERPOLATION_TOL_KM, INTERPOLATION_TOL_KM_S
from tapp.io.schedule_file import MAX_SCHEDULE_BYTES
from tapp.io.tape.t13_hdf5 import read_t13
from tapp.tracking.scenario_build import parse_scenario, read_scenario
from tapp.tracking.simulate import EDITING_RULES, simulate
from tests.tapp.frames.conftest import EPOCH_LINE, put_field, user_eop_table
from tests.tapp.tracking.encounter_reference import (
    AIM,
    TARGETING,
    Reference,
    moved_deep_space,
)
from tests.tapp.tracking.helpers import NORTH, geo_document, leo_document, schedule_text

SCENARIOS = EXAMPLES
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
                              "--json", "-"])
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
    assert "n_o = 69" in res.stdout and "n_ts = 3" in res.stdout  # 24 + 45 stochastic
    info = runner.invoke(app, ["tape", "info", str(out), "--json", "-"])
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
    ('observables = ["range", "range_rate"]', 'observables = ["range", "phase"]',
     "tracking.observables[1]"),
    ('dynamic = ["GM_km3_s2", "J2"]', 'dynamic = ["GM_km3_s2", "J9"]', "parameters.dynamic[1]"),
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


def test_a_user_eop_table_is_used_when_sound_and_refused_naming_its_line_when_not(
        tmp_path: Path) -> None:
    user_eop_table(tmp_path / "finals2000A.user")
    path = _edited(tmp_path, '\nepoch = ', '\neop = "finals2000A.user"\nepoch = ')
    good = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "good.t13.h5")])
    assert good.exit_code == 0, good.output
    assert read_t13(tmp_path / "good.t13.h5").provenance["eop"] == "finals2000A.user"

    def pole(lines: list[str]) -> list[str]:  # 1e300" at the epoch: a tape was written
        lines[EPOCH_LINE - 1] = put_field(lines[EPOCH_LINE - 1], "xp_a", "1e300")
        return lines

    user_eop_table(tmp_path / "finals2000A.bad", pole)  # another name: tables are cached
    path.write_text(path.read_text().replace("finals2000A.user", "finals2000A.bad"))
    out = tmp_path / "bad.t13.h5"
    res = runner.invoke(app, ["simulate", str(path), "-o", str(out)])
    assert res.exit_code == 2
    assert res.stderr.strip() == (f"error: {tmp_path / 'finals2000A.bad'}: line 16, x_p "
                                  "(Bulletin A): expected a pole within 1 arcsec (got 1e+300)")
    assert not out.exists()


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
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(out), "--json", "-"])
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


def test_a_station_without_data_is_one_warning_line_and_in_the_json(tmp_path: Path) -> None:
    """Issue 28: a station that never sees the spacecraft while others do was silent."""
    scenario, out = tmp_path / "north.toml", tmp_path / "north.t13.h5"
    scenario.write_text(tomli_w.dumps(leo_document(**NORTH)))
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(out), "--json", "-"])
    assert res.exit_code == 0, res.output
    warning = (f"{scenario}: tracking.stations[3]: NORTH yields no observation while other "
               "stations do (0 of its 1082 scheduled observations kept; removed: "
               "outside_tape 2, elevation_mask 1080, blackout 0, min_pass 0)")
    assert res.stderr.splitlines() == [f"warning: {warning}"]
    assert json.loads(res.stdout)["warnings"] == [warning]


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


# --- encounters and [targeting] (tapp.tracking.encounter) -----------------------------------

DEEP = SCENARIOS / "deep_space.toml"
#: The brief's 1 km on the aim point; the closest approach's time is refined to 1 s and its
#: distance printed to 0.1 km; the tape's miss and the reference agree to 1e-4 km, 1e-4 s.
ONE_KM = 1.0
TWO_SECONDS = 2.0
LAST_PRINTED_DIGIT_km = 0.1
ONE_METRE_km = 1e-3
ONE_MILLISECOND_s = 1e-3
#: The retargeting of the moved epoch moves the injection velocity by 1.2 km/s (measured).
A_HUNDRED_M_PER_S_km_s = 0.1


def _moved(tmp_path: Path, targeting: str | None = None, name: str = "moved.toml") -> Path:
    path = tmp_path / name
    path.write_text(moved_deep_space(DEEP.read_text(), targeting=targeting))
    return path


def test_moved_epoch_is_refused_naming_the_closest_approach(tmp_path: Path) -> None:
    """deep_space.toml one day later with its injection unchanged: exit 2, one line naming
    the file, the miss and the closest approach (km from the Moon's centre, UTC, s from the
    epoch) as the reference trajectory has it, and how to retarget; nothing written."""
    path = _moved(tmp_path)
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "run.t13.h5")])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: miss: expected a moon "
                                                   "encounter at the miss time"), lines
    assert "[targeting]" in lines[0]
    found = re.search(r"closest approach ([\d,.]+) km from the moon's centre at (\S+) UTC "
                      r"\(t = (\d+) s from the epoch\)", lines[0])
    distance_km, utc, t_s = float(found[1].replace(",", "")), found[2], float(found[3])
    scenario = read_scenario(path)
    ref = Reference(scenario, np.array(scenario.x0), t_s + 3600.0)
    fine = np.arange(t_s - 1800.0, t_s + 1800.0, 0.5)
    distance = ref.distance_km(fine)
    assert distance_km == pytest.approx(distance.min(), abs=LAST_PRINTED_DIGIT_km)
    assert t_s == pytest.approx(fine[np.argmin(distance)], abs=TWO_SECONDS)
    assert utc == scenario.epoch.iso_after(t_s, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["moved.toml"]


@pytest.fixture(scope="module")
def retargeted_run(tmp_path_factory) -> tuple[Path, dict, str]:
    """``tapp simulate`` of the moved scenario with a [targeting] table: (tape, JSON, text)."""
    folder = tmp_path_factory.mktemp("retarget")
    path = _moved(folder, TARGETING)
    res = runner.invoke(app, ["simulate", str(path), "-o", str(folder / "run.t13.h5"),
                              "--json", "-"])
    assert res.exit_code == 0, res.output
    text = runner.invoke(app, ["simulate", str(path), "-o", str(folder / "text.t13.h5")])
    assert text.exit_code == 0, text.output
    return folder / "run.t13.h5", json.loads(res.stdout), text.stdout


def test_retargeted_tape_lands_on_the_aim_point(retargeted_run) -> None:
    """The tape's injection (its orbit parameters' nominal values), flown by the reference
    trajectory, has its periapsis B-plane within 1 km of the aim point; the tape's own miss
    agrees with the reference and the tape records the retargeting."""
    tape_path, out, _ = retargeted_run
    tape = read_t13(tape_path)
    record = json.loads(tape.provenance["targeting"])
    assert out["targeting"] == record and record["status"] == "converged"
    x0 = tape.parameters.nominal[:6]
    np.testing.assert_array_equal(x0[3:], record["v0_targeted_km_s"])
    assert np.linalg.norm(x0[3:] - record["v0_file_km_s"]) > A_HUNDRED_M_PER_S_km_s
    scenario = read_scenario(tape.provenance["scenario_source"])
    ref = Reference(scenario, x0, tape.miss.t_s + 7200.0)
    t_p, b_r, b_t = ref.periapsis_b_plane(tape.miss.t_s)
    assert abs(b_r - AIM["b_dot_r_km"]) < ONE_KM and abs(b_t - AIM["b_dot_t_km"]) < ONE_KM
    np.testing.assert_allclose(tape.miss.nominal[:2], [b_r, b_t], rtol=0, atol=ONE_METRE_km)
    assert tape.miss.nominal[2] == pytest.approx(t_p, abs=ONE_MILLISECOND_s)
    assert out["miss"]["names"] == ["b_dot_r_km", "b_dot_t_km", "flight_time_s"]


def test_simulate_prints_the_targeted_injection_and_the_miss(retargeted_run) -> None:
    _, out, text = retargeted_run
    v0 = out["targeting"]["v0_targeted_km_s"]
    assert "Injection retargeted by SEARCH (conic first guess" in text
    assert f"v0 = [{v0[0]:.9f}, {v0[1]:.9f}, {v0[2]:.9f}] km/s" in text
    assert f"b_dot_t_km = {out['miss']['nominal'][1]:.10g} (aim 5300)" in text


@pytest.mark.parametrize(("edit", "field"), [
    (("b_dot_r_km = -2000.0", 'b_dot_r_km = "-2000"'), "targeting.targets.b_dot_r_km"),
    (("flight_time_s = 309958.384", "flight_time_s = -1.0"),
     "targeting.targets.flight_time_s"),
    (("flight_time_s = 309958.384", "flight_time_s = 9e9"), "targeting.targets.flight_time_s"),
    (("flight_time_s = 309958.384", ""), "targeting.vary"),
    (('first_guess = "conic"', 'first_guess = "conic"\nvary = ["vx_km_s", "vw_km_s"]'),
     "targeting.vary[1]"),
    (('first_guess = "conic"', 'first_guess = "conic"\nvary = ["vx_km_s", "vy_km_s"]'),
     "targeting.vary"),
    (('first_guess = "conic"', 'first_guess = "lambert"'), "targeting.first_guess"),
    (('first_guess = "conic"', 'first_guess = "conic"\npartial_sets = 0'),
     "targeting.partial_sets"),
    (('first_guess = "conic"', 'first_guess = "conic"\nscan_step_s = 1e9'),
     "targeting.scan_step_s"),
    (('first_guess = "conic"', 'first_guess = "conic"\naim = 1.0'), "targeting.aim"),
    (("b_dot_r_km = 0.1", "b_dot_r_km = 0.0"), "targeting.tolerances.b_dot_r_km"),
    (("[targeting.tolerances]", "[targeting.increments]\nvz_km_s = 0.0\n\n"
      "[targeting.tolerances]"), "targeting.increments.vz_km_s"),
    (('time = "periapsis"', 'time = "2026-03-15T02:05:58.384"'), "miss.time"),
    (('dynamic = ["GM_km3_s2", "GM_moon_km3_s2"]',
      'dynamic = ["GM_km3_s2", "GM_moon_km3_s2"]\nvalues = {GM_moon_km3_s2 = 4900.0}'),
     "parameters.values"),
])
def test_bad_targeting_fields_are_one_line_naming_the_field(tmp_path: Path, edit, field: str
                                                            ) -> None:
    old, new = edit
    text = moved_deep_space(DEEP.read_text(), targeting=TARGETING)
    assert old in text, old
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "run.t13.h5")])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: {field}: expected"), lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_targeting_needs_a_b_plane_miss(tmp_path: Path) -> None:
    path = tmp_path / "leo.toml"
    path.write_text(LEO.read_text() + TARGETING)
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "run.t13.h5")])
    assert res.exit_code == 2
    assert res.stderr.startswith(f"error: {path}: miss.kind: expected \"bplane\" with")


@pytest.mark.parametrize(("table", "code", "says"), [
    (TARGETING.replace('first_guess = "conic"', 'first_guess = "conic"\n'
                       "iterations_per_partials = 1\npartial_sets = 1"), 3, "SEARCH diverged"),
    (TARGETING.replace('first_guess = "conic"', 'first_guess = "injection"'), 1,
     'SEARCH failed: search case'),
])
def test_a_search_that_does_not_converge_writes_no_tape(tmp_path: Path, table: str, code: int,
                                                        says: str) -> None:
    """Diverged: SEARCH's exit 3; a case that left the Moon's sphere of influence (from the
    stale injection): exit 1. One line each, no tape."""
    path = _moved(tmp_path, table)
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "run.t13.h5")])
    assert res.exit_code == code, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}: targeting: {says}"), lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["moved.toml"]


def test_tape_info_says_the_injection_was_retargeted(retargeted_run, tmp_path: Path) -> None:
    tape_path, out, _ = retargeted_run
    res = runner.invoke(app, ["tape", "info", str(tape_path)])
    assert res.exit_code == 0, res.output
    assert (f"injection retargeted by SEARCH (converged in {out['targeting']['cases']} cases) "
            "to b_dot_r_km = -2000, b_dot_t_km = 5300") in " ".join(res.stdout.split())
    plain = tmp_path / "leo.t13.h5"
    assert runner.invoke(app, ["simulate", str(LEO), "-o", str(plain)]).exit_code == 0
    assert "retargeted" not in runner.invoke(app, ["tape", "info", str(plain)]).stdout


def test_a_ddor_scenario_writes_its_baseline_and_a_tdm_of_the_stations(tmp_path: Path) -> None:
    """The baseline is the tape's third entry (its raw rows read back with kind "ddor"); the
    TDM carries the stations' range and range-rate only (ΔDOR has no keyword there)."""
    doc = geo_document()
    doc["ddor"] = {"baselines": [["UNDER", "EAST"]], "interval_s": 3600.0,
                   "fit": {"sigma_ns": 0.1}}
    scenario, tape, tdm = tmp_path / "geo.toml", tmp_path / "geo.t13.h5", tmp_path / "geo.tdm"
    scenario.write_bytes(tomli_w.dumps(doc).encode())
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(tape), "--tdm", str(tdm),
                              "--raw"])
    assert res.exit_code == 0, res.output
    back = read_t13(tape)
    assert back.stations.name[2] == "UNDER-EAST"
    rows = back.raw.kind == back.raw.kinds.index("ddor")
    assert np.all(back.raw.station[rows] == 3) and rows.sum() == 12
    text = tdm.read_text()
    assert text.count("META_START") == 2 and "UNDER-EAST" not in text


@pytest.fixture(scope="module")
def leo_passes(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The tape of leo_equatorial.toml by visibility and its passes as a schedule's rows."""
    out = tmp_path_factory.mktemp("visibility") / "leo.t13.h5"
    res = runner.invoke(app, ["simulate", str(LEO), "-o", str(out)])
    assert res.exit_code == 0, res.output
    return out, schedule_text(read_t13(out, raw=False))


def _scheduled(tmp_path: Path, text: str) -> tuple[Path, Path]:
    """leo_equatorial.toml in ``tmp_path`` tracking by ``passes.csv`` beside it."""
    schedule = tmp_path / "passes.csv"
    schedule.write_text(text)
    return _edited(tmp_path, "blackouts = []", 'blackouts = []\nschedule = "passes.csv"'), \
        schedule


def test_a_schedule_of_the_visibility_passes_through_the_cli(
        leo_passes: tuple[Path, str], tmp_path: Path) -> None:
    """The schedule's path is relative to the scenario's folder; the tape keeps every
    observation of the visibility one, and the editing table counts them as scheduled."""
    seen, rows = leo_passes
    path, _ = _scheduled(tmp_path, "station,start,end\n" + rows)
    out = tmp_path / "scheduled.t13.h5"
    res = runner.invoke(app, ["simulate", str(path), "-o", str(out), "--json", "-"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    before = read_t13(seen, raw=False)
    assert info["observations"] == int(before.pairs.n_obs.sum())
    assert [s["scheduled_observations"] for s in info["stations"]] == [
        s["observations"] for s in info["stations"]]
    after = read_t13(out, raw=False)
    np.testing.assert_array_equal(after.pairs.R, before.pairs.R)
    digest = hashlib.sha256((tmp_path / "passes.csv").read_bytes()).hexdigest()
    assert after.provenance["schedule"] == f"{tmp_path / 'passes.csv'} (sha256 {digest})"
    assert before.provenance["schedule"] == ""  # tracked by visibility


@pytest.mark.parametrize(("edit", "expected"), [
    (lambda rows: "station,begin,end\n" + rows,
     "row 1: header: expected the columns station, start, end (optional: data_types, "
     "data_interval_s, uplink_station), each once, comma-separated (got 'station,begin,end')"),
    (lambda rows: "station,start,end\nGOLDSTONE,0,100\n" + rows,
     "row 2: station: expected a station of tracking.stations (QUITO, KOUROU, ASCENSION, "
     "MALINDI, SINGAPORE, KWAJALEIN) (got 'GOLDSTONE')"),
    (lambda rows: "station,start,end\nQUITO,2026-01-01T05:00:00,2026-01-01T04:00:00\n" + rows,
     "row 2: end: expected a time after the pass's start (18000.000000 s from the epoch) "
     "(got '2026-01-01T04:00:00')"),
    (lambda rows: "station,start,end\nQUITO,2026-01-01T25:00:00,90000\n" + rows,
     "row 2: start: expected seconds from the epoch or an ISO 8601 UTC date "
     "YYYY-MM-DD[Thh:mm[:ss[.fff]]][Z] with hh<24, mm<60, ss<60 (got '2026-01-01T25:00:00')"),
    (lambda rows: "station,start,end,data_types\nQUITO,0,100,azimuth\n" + rows.replace(
        "\n", ",\n"),
     "row 2: data_types: expected observables that QUITO measures (range, range_rate; "
     "tracking.observables or tracking.station.QUITO.observables) (got 'azimuth')"),
    (lambda rows: "station,start,end,uplink_station\nQUITO,0,100,KOUROU\n" + rows.replace(
        "\n", ",\n"),
     "row 2: uplink_station: expected empty or QUITO, the pass's own station (three-way "
     "tracking from another station: that station as tracking.station.QUITO.uplink) "
     "(got 'KOUROU')"),
])
def test_a_bad_schedule_is_one_line_naming_the_row_exit_2_and_nothing_written(
        leo_passes: tuple[Path, str], tmp_path: Path, edit, expected: str) -> None:
    path, schedule = _scheduled(tmp_path, edit(leo_passes[1]))
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "bad.t13.h5")])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [f"error: {schedule}: {expected}"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["edited.toml", "passes.csv"]


def test_a_scheduled_pass_the_station_cannot_see_exits_2_and_writes_nothing(
        leo_passes: tuple[Path, str], tmp_path: Path) -> None:
    """The last pass begun 10 min early (20 samples of 30 s below the mask)."""
    tape = read_t13(leo_passes[0], raw=False)
    rows = leo_passes[1].splitlines()
    station, _, end = rows[-1].split(",")
    rows[-1] = ",".join([station, tape.epoch.iso_after(float(tape.passes.t_start_s[-1])
                                                       - 600.0, 6), end])
    path, schedule = _scheduled(tmp_path, "station,start,end\n" + "\n".join(rows) + "\n")
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "bad.t13.h5")])
    assert res.exit_code == 2
    (line,) = res.stderr.splitlines()
    assert line.startswith(f"error: {schedule}: row {len(rows) + 1}: start: expected a pass "
                           f"that {station} sees above its ")
    assert "(got '20 of its " in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["edited.toml", "passes.csv"]


def test_a_schedule_beyond_its_size_bound_is_refused_from_its_size(tmp_path: Path) -> None:
    """(A FIFO or a device: tests/tapp/cli/test_input_files.py.)"""
    path, schedule = _scheduled(tmp_path, "")
    schedule.write_bytes(b"#" * (MAX_SCHEDULE_BYTES + 1))
    res = runner.invoke(app, ["simulate", str(path), "-o", str(tmp_path / "bad.t13.h5")])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [
        f"error: {schedule}: file: expected a pass schedule (CSV) of at most "
        f"{MAX_SCHEDULE_BYTES:,} bytes (got '{MAX_SCHEDULE_BYTES + 1:,} bytes')"]
    assert not (tmp_path / "bad.t13.h5").exists()


def test_an_output_over_the_schedule_is_refused(leo_passes: tuple[Path, str],
                                                tmp_path: Path) -> None:
    text = "station,start,end\n" + leo_passes[1]
    path, schedule = _scheduled(tmp_path, text)
    res = runner.invoke(app, ["simulate", str(path), "-o", str(schedule)])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [
        f"error: -o/--output: {schedule}: expected a file other than the input "
        "tracking.schedule (it would be overwritten)"]
    assert schedule.read_text() == text
