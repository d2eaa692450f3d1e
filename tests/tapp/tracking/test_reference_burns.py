"""A mission's trajectory with burns as TAPP I's reference (tapp.tracking.reference, issue 29):
the fit over each arc between burns.

- round trip: ``tapp simulate`` of the LEO with two impulsive burns writes its OEM (a segment
  per arc) and SPK (a type 13 segment per arc); scenarios that read each back with the same
  ``[[manoeuvre]]`` list fit x₀ on the first arc and each burn's Δv on the arc after it, to
  under 1 mm RMS per arc, and fly the same tape;
- a finite burn's thrust is fitted on its arc from a first guess 5 % and 3° off;
- bad input: a burn at t = 0 or outside the span, an arc without 3 reference states, a burn
  flown as given (``fit_manoeuvres = false``) or one missing from the list, each fit worse
  than the limit naming its arc: one line, exit 2, nothing written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import tapp.cli.simulate_cmd  # noqa: F401  (registers the command)
from tapp.cli.common import app
from tapp.io.ccsds.oem import INTERPOLATION, INTERPOLATION_DEGREE, format_oem
from tapp.io.tape.t13_hdf5 import read_t13
from tapp.tracking.oem_states import oem_trajectory
from tapp.tracking.reference import fitted
from tapp.tracking.scenario_build import parse_scenario
from tests.tapp.tracking.helpers import leo_document
from tests.tapp.tracking.test_reference import (
    B_JITTER,
    SAME_TAPE,
    ONE_MM_m,
    simulate_json,
    tape_differences,
    write_toml,
)

runner = CliRunner()

#: Gates' proportional magnitude and fixed pointing σ: the tape's execution columns depend on
#: the fitted Δv.
SIGMAS = {"sigma_magnitude_proportional": 0.01, "sigma_pointing_fixed_mm_s": 5.0}
#: Two impulsive burns of the 3 h LEO: 2.3 m/s in VNB axes at 2000 s, 3.2 m/s inertial at
#: 6500 s (arcs of 2000, 4500 and 4300 s).
BURNS = [{"name": "TCM1", "kind": "impulsive", "time": 2000.0, "axes": "vnb",
          "dv_m_s": [2.0, 0.5, -1.0], **SIGMAS},
         {"name": "TCM2", "kind": "impulsive", "time": 6500.0, "axes": "inertial",
          "dv_m_s": [-1.0, 3.0, 0.4], **SIGMAS}]
#: The fitted Δv against the one flown, relative to |Δv|: the positions' µm noise (the
#: integrator's, rtol 1e-13 of 6500 km; the OEM's 1 µm printing) over the arc (measured
#: 1.7e-10 from the OEM, 6.7e-11 from the SPK).
DV_FIT = 1e-8
#: The execution columns of the information carry ∂Δx/∂q = [0; M G(Δv)], G turned and scaled
#: by the fitted Δv: 2e-10 of |Δv| moves their scaled information by up to 3.0e-9 (OEM) and
#: 8.6e-10 (SPK), where the other columns stay within SAME_TAPE (measured 5.8e-11; every other
#: dataset at most 3.3e-10, miss/nominal from the OEM; B 4.7e-9 from the SPK, its jitter).
EXECUTION_INFORMATION = 1e-8


def _from(reference: dict, burns: list[dict] = BURNS) -> dict:
    """The LEO scenario reading ``reference`` instead of its injection, with ``burns``."""
    return leo_document(injection=None, reference=reference, manoeuvre=burns)


@pytest.fixture(scope="module")
def round_trip(tmp_path_factory) -> dict:
    """The LEO with BURNS flown, its OEM and SPK written, and flown again from each."""
    d = tmp_path_factory.mktemp("burns")
    simulate_json(write_toml(d / "leo.toml", leo_document(manoeuvre=BURNS)), "-o", d / "leo.t13.h5",
              "--oem", d / "leo.oem", "--spk", d / "leo.bsp")
    runs = {}
    for kind, table in (("OEM", {"file": "leo.oem"}),
                        ("SPK", {"file": "leo.bsp", "object": -999})):
        info = simulate_json(write_toml(d / f"from_{kind}.toml", _from(table)), "-o",
                         d / f"from_{kind}.t13.h5", "--oem", d / f"from_{kind}.oem")
        runs[kind] = (d / f"from_{kind}.t13.h5", info)
    return {"folder": d, "runs": runs}


@pytest.mark.parametrize("kind", ["OEM", "SPK"])
def test_the_fit_per_arc_between_burns_is_under_a_millimetre(round_trip, kind: str) -> None:
    """x₀ on [0, 2000] s, TCM1's Δv on [2000, 6500] s, TCM2's on [6500, 10800] s; each arc
    RMS and largest difference under 1 mm (measured at most 1.6 µm), the Δv as flown."""
    _, info = round_trip["runs"][kind]
    arcs = info["reference"]["arcs"]
    assert [(a["t_start_s"], a["t_end_s"], a["burn"], a["fitted"]) for a in arcs] == [
        (0.0, 2000.0, None, "state"), (2000.0, 6500.0, "TCM1", "dv_km_s"),
        (6500.0, 10800.0, "TCM2", "dv_km_s")]
    for arc, burn in zip(arcs[1:], BURNS, strict=True):
        flown = 1e-3 * np.array(burn["dv_m_s"])
        np.testing.assert_array_equal(arc["given"], flown)
        assert np.abs(np.array(arc["value"]) - flown).max() < DV_FIT * np.linalg.norm(flown)
    for arc in arcs:
        assert arc["rms_m"] < ONE_MM_m and arc["max_m"] < ONE_MM_m and arc["converged"]


@pytest.mark.parametrize("kind", ["OEM", "SPK"])
def test_the_round_trip_with_burns_flies_the_same_tape(round_trip, kind: str) -> None:
    original = read_t13(round_trip["folder"] / "leo.t13.h5")
    tape = read_t13(round_trip["runs"][kind][0])
    for name in ("k", "station", "n_obs"):
        np.testing.assert_array_equal(getattr(tape.pairs, name), getattr(original.pairs, name))
    execution = np.array([k == "execution" for k in original.parameters.kind])
    assert execution.sum() == 6
    differences = tape_differences(original, tape, columns=~execution)
    jitter = differences.pop("miss/B")
    assert max(differences.values()) < SAME_TAPE, differences
    assert jitter < B_JITTER
    whole = tape_differences(original, tape)
    assert max(whole[k] for k in ("pairs/R", "pairs/Rt", "pairs/Rt_parts")) \
        < EXECUTION_INFORMATION


def test_the_oem_says_the_segments_the_burns_and_the_fit(round_trip) -> None:
    text = (round_trip["folder"] / "from_OEM.oem").read_text()
    lines = text.splitlines()
    assert lines.count("META_START") == 3
    assert ("COMMENT MANOEUVRE TCM1 impulsive at 2026-01-01T00:33:20.000000 UTC: dv = [2, 0.5, "
            "-1] m/s in vnb axes (VNB); fitted to the reference (the scenario gives dv = [2, "
            "0.5, -1] m/s)") in lines
    arc = next(line for line in lines if line.startswith("COMMENT Arc 3 "))
    assert arc.startswith("COMMENT Arc 3 2026-01-01T01:48:20.000 to 2026-01-01T03:00:00.000 "
                          "UTC, after TCM2: dv fitted [")
    assert "m/s (the scenario gives [-1, 3, 0.4]): " in arc


# --- a finite burn ----------------------------------------------------------------------------

#: A 24 mm/s finite burn in RIC axes over [5000, 5600) s (tests/tapp/tracking/test_manoeuvres).
FINITE = {"name": "BURN", "kind": "finite", "start": 5000.0, "duration_s": 600.0,
          "axes": "ric", "direction": [0.0, 1.0, 0.2], "thrust_N": 20.0, "mass_kg": 500.0,
          "mass_flow_kg_s": 0.01}
#: The fitted thrust against the one flown, relative, and its direction, rad (measured 4.7e-13
#: and 1.8e-12): the positions' µm noise over the 5800 s arc against the burn's 24 mm/s.
THRUST_FIT = 1e-9


def test_a_finite_burns_thrust_and_direction_are_fitted_on_its_arc(tmp_path: Path) -> None:
    """The OEM of the LEO with BURN, read back with a burn of 21 N along a direction 3° off:
    the fit recovers 20 N and the direction, the arc under 1 mm; ignition, duration, mass and
    flow are the scenario's."""
    flown = parse_scenario(leo_document(manoeuvre=[FINITE]), str(tmp_path / "leo.toml"))
    traj = oem_trajectory(flown, 10800.0)
    (tmp_path / "leo.oem").write_text(format_oem(
        flown.epoch, traj.t_s, traj.states, object_name="SC", object_id="SC",
        ref_frame=traj.ref_frame, interpolation=INTERPOLATION,
        interpolation_degree=INTERPOLATION_DEGREE, segment=traj.segment))
    off = {**FINITE, "thrust_N": 21.0, "direction": [0.0, 1.0, 0.2 + np.radians(3.0)]}
    scenario = parse_scenario(_from({"file": "leo.oem"}, [off]), str(tmp_path / "s.toml"))
    _, fit = fitted(scenario)
    first, arc = fit.arcs
    (burn,) = fit.burns
    assert (arc.burn, arc.fitted, arc.t_start_s) == ("BURN", "thrust_km_s2", 5000.0)
    assert max(first.max_m, arc.max_m) < ONE_MM_m
    assert abs(burn.thrust_N - 20.0) < THRUST_FIT * 20.0
    want = np.array(FINITE["direction"]) / np.linalg.norm(FINITE["direction"])
    assert np.abs(np.array(burn.direction) - want).max() < THRUST_FIT
    assert (burn.t_start_s, burn.duration_s, burn.mass_kg, burn.mass_flow_kg_s) == (
        5000.0, 600.0, 500.0, 0.01)


# --- bad input --------------------------------------------------------------------------------

def _moved(dv_m_s: list[float]) -> list[dict]:
    """BURNS with TCM2's Δv replaced."""
    return [BURNS[0], {**BURNS[1], "dv_m_s": dv_m_s}]


#: (reference table changes, [[manoeuvre]] list, field, expected, got or None).
CASES = {
    "a burn at t = 0": ({}, [{**BURNS[0], "time": 0.0}, BURNS[1]], "manoeuvre[0].time",
                        "a burn after t = 0 with [reference]", "0.0"),
    "a burn after the span": ({}, [BURNS[0], {**BURNS[1], "time": 11000.0}],
                              "manoeuvre[1].time", "a time in the arc, [0, 10800) s", "11000.0"),
    "an arc without 3 states": ({}, [BURNS[0], {**BURNS[1], "time": 2010.0}],
                                "reference.file", "at least 3 reference states in each arc "
                                "(2026-01-01T00:33:20.000 to 2026-01-01T00:33:30.000 UTC, after "
                                "TCM1)", "1"),
    "a burn flown as given, 10 cm/s off": (
        {"fit_manoeuvres": False}, _moved([-1.0, 3.1, 0.4]), "reference.max_fit_error_m",
        "TAPP I's force model within 100 m of the reference", None),
    "a burn missing": ({}, BURNS[:1], "reference.max_fit_error_m",
                       "TAPP I's force model within 100 m of the reference", None),
}
#: The arc each poor fit names.
NAMED = {"a burn flown as given, 10 cm/s off": "arc 3 (after TCM2) from "
         "2026-01-01T01:48:20.000 to 2026-01-01T03:00:00.000 UTC",
         "a burn missing": "arc 2 (after TCM1) from 2026-01-01T00:33:20.000 to "
         "2026-01-01T03:00:00.000 UTC"}


@pytest.mark.parametrize("case", CASES)
def test_bad_burns_with_a_reference_are_one_line_exit_2_and_nothing_written(
        round_trip, tmp_path: Path, case: str) -> None:
    table, burns, field, expected, got = CASES[case]
    (tmp_path / "leo.oem").write_text((round_trip["folder"] / "leo.oem").read_text())
    scenario = write_toml(tmp_path / "s.toml", _from({"file": "leo.oem", **table}, burns))
    before = sorted(p.name for p in tmp_path.iterdir())
    res = runner.invoke(app, ["simulate", str(scenario), "-o", str(tmp_path / "out.t13.h5"),
                              "--oem", str(tmp_path / "out.oem")])
    assert res.exit_code == 2, res.output
    (line,) = res.stderr.strip().splitlines()
    assert line.startswith(f"error: {scenario}: {field}: expected {expected}"), line
    if got is not None:
        assert line.endswith(f"(got {got})"), line
    if case in NAMED:
        assert line.endswith(f", {NAMED[case]}')"), line
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_burn_off_by_10_cm_s_is_fitted_back(round_trip, tmp_path: Path) -> None:
    """The case refused above with ``fit_manoeuvres = false`` flies when the burn is fitted:
    TCM2's Δv comes back as flown."""
    scenario = parse_scenario(_from({"file": str(round_trip["folder"] / "leo.oem")},
                                    _moved([-1.0, 3.1, 0.4])), str(tmp_path / "s.toml"))
    _, fit = fitted(scenario)
    flown = 1e-3 * np.array(BURNS[1]["dv_m_s"])
    assert np.abs(fit.arcs[2].value - flown).max() < DV_FIT * np.linalg.norm(flown)
    assert fit.worst.max_m < ONE_MM_m
