"""TAPP I tracking by a pass schedule, ``[tracking] schedule`` (issue 29, item 3): the passes
visibility found, given back as a schedule, give the same tape; a pass the station cannot see
is an error naming the row, or (``allow_partial``) is cut and counted; per-pass data types
and intervals; how the schedule meets ``use``, blackouts and min_pass_s."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.tape.t13 import T13
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.tracking.editing import EDITING_RULES
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import Simulation, simulate
from tests.tapp.tracking.helpers import (
    geo_document,
    hand_document,
    leo_document,
    scaled_close,
    schedule_text,
)

EXAMPLES = Path(__file__).parents[3] / "tapp" / "examples"
#: Partials and values computed for two observables at once and for one differ in their
#: last bits (matrix products of other shapes): relative to a row's norm, or to a Gram's
#: sqrt(J_aa J_bb).
ROUND_OFF = 1e-13
MASK = EDITING_RULES.index("elevation_mask")
BLACKOUT = EDITING_RULES.index("blackout")
OUTSIDE = EDITING_RULES.index("outside_tape")


def _with_schedule(doc: dict, folder: Path, text: str, header: str = "station,start,end",
                   **tracking) -> tuple[dict, str]:
    """The document tracking by ``text`` written to ``folder``/passes.csv, named relative to
    a scenario in ``folder``, and that scenario's source."""
    (folder / "passes.csv").write_text(f"{header}\n{text}")
    doc = copy.deepcopy(doc)
    doc["tracking"] = {**doc["tracking"], "schedule": "passes.csv", **tracking}
    return doc, str(folder / "scenario.toml")


def _run(doc: dict, source: str) -> Simulation:
    return simulate(parse_scenario(doc, source), raw=True)


def _datasets(path: Path) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
    return out


def assert_same_tape_but_editing(a: T13, b: T13, folder: Path) -> None:
    """Every dataset of the two tapes' files equal, bit for bit, but ``editing/``."""
    files = [write_t13(folder / name, tape) for name, tape in (("a.h5", a), ("b.h5", b))]
    first, second = (_datasets(f) for f in files)
    assert first.keys() == second.keys()
    compared = [name for name in first if not name.startswith("editing/")]
    assert {"pairs/R", "pairs/Rt", "passes/t_start_s", "raw/A", "records/U"} <= set(compared)
    for name in compared:
        np.testing.assert_array_equal(first[name], second[name], err_msg=name)


def _example(name: str) -> tuple[dict, str]:
    path = EXAMPLES / f"{name}.toml"
    return tomllib.loads(path.read_text()), str(path)


CASES = {"leo": lambda: (leo_document(), "leo.toml"),
        "leo_rkn12": lambda: (leo_document(model={"method": "rkn12"}), "leo.toml"),
        "geo_split_at_max_pass": lambda: (geo_document(), "geo.toml"),
        "geo_with_ddor_on_its_own_grid": lambda: (geo_with_ddor(), "geo.toml"),
        "blackouts_min_pass_outside_tape": lambda: (hand_document(), "hand.toml"),
        **{name: (lambda name=name: _example(name))
           for name in ("leo_equatorial", "leo_drag", "tapp1_table_d1")}}


def geo_with_ddor() -> dict:
    """The GEO track with a ΔDOR point every hour on its baseline (which keeps its own
    schedule, on the scenario's grid, whatever tracks the stations)."""
    doc = geo_document()
    doc["ddor"] = {"baselines": [["UNDER", "EAST"]], "interval_s": 3600.0,
                   "fit": {"sigma_ns": 0.1}}
    return doc


def _visibility_then_schedule(case, folder: Path, dates: bool = True
                              ) -> tuple[Simulation, Simulation]:
    doc, source = case()
    seen = _run(doc, source)
    scheduled = _run(*_with_schedule(doc, folder, schedule_text(seen.tape, dates=dates)))
    return seen, scheduled


@pytest.mark.parametrize(("case", "dates"), [
    *((case, True) for case in CASES.values()), (CASES["leo"], False)],
    ids=[*CASES, "leo_in_seconds"])
def test_a_schedule_of_the_passes_visibility_kept_gives_the_same_tape(
        case, dates: bool, tmp_path: Path) -> None:
    """Issue 29's check: every dataset equal but ``editing/``, which counts the schedule's
    samples: all kept (none of its passes is short, blacked out or below a mask), as many
    as visibility kept. Times as UTC dates to the microsecond (or seconds)."""
    seen, scheduled = _visibility_then_schedule(case, tmp_path, dates)
    assert_same_tape_but_editing(seen.tape, scheduled.tape, tmp_path)
    ed = scheduled.tape.editing
    kept = seen.tape.editing.kept_obs(seen.tape.pairs)
    np.testing.assert_array_equal(ed.scheduled_obs, kept)
    np.testing.assert_array_equal(ed.removed_obs, 0)
    np.testing.assert_array_equal(ed.kept_obs(scheduled.tape.pairs), kept)


@pytest.mark.slow
def test_the_deep_space_example_by_its_passes_gives_the_same_tape(tmp_path: Path) -> None:
    """The lunar transfer: two-way light time, 30 days, 90 passes (10 s)."""
    seen, scheduled = _visibility_then_schedule(lambda: _example("deep_space"), tmp_path)
    assert_same_tape_but_editing(seen.tape, scheduled.tape, tmp_path)


@pytest.fixture(scope="module")
def leo() -> Simulation:
    """The 3-hour LEO arc tracked by visibility (5° masks, samples every 20 s)."""
    return simulate(parse_scenario(leo_document(), "leo.toml"), raw=True)


def _widened(tape: T13, early_s: float = 0.0, late_s: float = 0.0) -> str:
    """The tape's passes as a schedule in seconds, the first one starting ``early_s`` before
    its first sample and ending ``late_s`` after its last."""
    p = tape.passes
    lines = []
    for i, (s, a, b) in enumerate(zip(p.station, p.t_start_s, p.t_end_s, strict=True)):
        a, b = (float(a) - early_s, float(b) + late_s) if i == 0 else (float(a), float(b))
        lines.append(f"{tape.stations.name[s - 1]},{a!r},{b!r}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(("early_s", "late_s", "field"), [(100.0, 0.0, "start"),
                                                          (0.0, 60.0, "end")])
def test_a_pass_the_station_cannot_see_is_one_error_naming_the_file_and_the_row(
        leo: Simulation, tmp_path: Path, early_s: float, late_s: float, field: str) -> None:
    """The first pass begun 100 s (5 samples) early or ended 60 s (3 samples) late: those
    samples are at or below the mask (the pass's first and last samples are the first and
    last above it). Row 2: the first row after the header."""
    tape = leo.tape
    doc, source = _with_schedule(leo_document(), tmp_path, _widened(tape, early_s, late_s))
    with pytest.raises(InputError) as err:
        _run(doc, source)
    name = tape.stations.name[tape.passes.station[0] - 1]
    t_below = (tape.passes.t_start_s[0] - early_s if early_s
               else tape.passes.t_end_s[0] + 20.0)
    n = int(tape.passes.n_obs[0] // 2 + (early_s + late_s) // 20.0)
    assert (err.value.source, err.value.field) == (str(tmp_path / "passes.csv"),
                                                   f"row 2: {field}")
    assert err.value.expected == (
        f"a pass that {name} sees above its 5° elevation mask throughout ([tracking] "
        "allow_partial = true drops the samples it cannot see, counted under elevation_mask)")
    assert err.value.got.startswith(
        f"{int((early_s + late_s) // 20)} of its {n} samples at or below the mask, "
        f"{tape.epoch.iso_after(t_below, 3)} to ")


def test_allow_partial_drops_what_the_station_cannot_see_and_counts_it(
        leo: Simulation, tmp_path: Path) -> None:
    """The first pass widened by 5 samples before and 3 after: the tape is the visibility
    one; the 8 samples (16 observations) are counted under elevation_mask."""
    doc, source = _with_schedule(leo_document(), tmp_path, _widened(leo.tape, 100.0, 60.0),
                                 allow_partial=True)
    cut = _run(doc, source).tape
    assert_same_tape_but_editing(leo.tape, cut, tmp_path)
    first = leo.tape.passes.station[0] - 1
    removed = np.zeros_like(cut.editing.removed_obs)
    removed[first, MASK] = 2 * 8
    np.testing.assert_array_equal(cut.editing.removed_obs, removed)
    np.testing.assert_array_equal(cut.editing.scheduled_obs,
                                  leo.tape.editing.kept_obs(leo.tape.pairs) + removed[:, MASK])


def test_a_pass_cut_in_two_by_a_blackout_is_two_passes_and_min_pass_does_not_apply(
        leo: Simulation, tmp_path: Path) -> None:
    """The schedule of the visibility passes with a blackout of the first pass's 3rd to 5th
    samples at its station, and min_pass_s longer than any pass: the blackout removes those
    3 samples (counted), the pass becomes two on the tape (1st-2nd, 6th-last sample), and
    every other pass stays (min_pass_s drops only visibility's grazing passes)."""
    tape = leo.tape
    station = tape.stations.name[tape.passes.station[0] - 1]
    t0 = float(tape.passes.t_start_s[0])
    doc = leo_document(tracking={"min_pass_s": 1e5, "station": {
        **leo_document()["tracking"]["station"],
        station: {"blackouts": [[t0 + 40.0, t0 + 80.0]]}}})
    cut = _run(*_with_schedule(doc, tmp_path, schedule_text(tape))).tape
    starts = np.sort(np.append(tape.passes.t_start_s, t0 + 100.0))
    np.testing.assert_array_equal(cut.passes.t_start_s, starts)
    assert cut.passes.t_end_s[0] == t0 + 20.0
    assert cut.editing.removed_obs[tape.passes.station[0] - 1, BLACKOUT] == 2 * 3
    assert cut.editing.removed_obs.sum() == 2 * 3


def test_per_pass_data_types_and_interval_are_the_visibility_tape_of_those_settings(
        tmp_path: Path) -> None:
    """QUITO's passes measuring range only, every 40 s, in a scenario of range and range
    rate every 20 s, give QUITO the factors, passes and rows of a visibility run where QUITO
    measures range only every 40 s; the other stations, without passes, yield nothing."""
    biases = {"parameters": {**leo_document()["parameters"], "station_biases": ["range"]}}
    alone = leo_document(**biases, tracking={"data_interval_s": 40.0, "station": {
        "KOUROU": {"location": "ecef"}, "QUITO": {"observables": ["range"]}}})
    seen = _run(alone, "alone.toml").tape
    quito = seen.passes.station == 1
    rows = schedule_text(seen).splitlines()
    text = "\n".join(r + ",range,40" for r, q in zip(rows, quito, strict=True) if q) + "\n"
    doc = leo_document(**biases)
    sim = _run(*_with_schedule(doc, tmp_path, text,
                               header="station,start,end,data_types,data_interval_s"))
    tape = sim.tape
    assert set(tape.pairs.station) == {1}
    mine = seen.pairs.station == 1
    for name in ("k", "n_obs"):
        np.testing.assert_array_equal(getattr(tape.pairs, name), getattr(seen.pairs, name)[mine])
    for name in ("R", "Rt"):  # their Grams, AᵀWA and AᵀWMWA
        r, expected = getattr(tape.pairs, name), getattr(seen.pairs, name)[mine]
        scaled_close(np.swapaxes(r, -1, -2) @ r,
                     np.swapaxes(expected, -1, -2) @ expected, ROUND_OFF)
    for name in ("t_start_s", "t_end_s", "n_obs"):
        np.testing.assert_array_equal(getattr(tape.passes, name),
                                      getattr(seen.passes, name)[quito], err_msg=name)
    raw = seen.raw.station == 1
    assert set(tape.raw.kind) == {tape.raw.kinds.index("range")}
    for name in ("t_s", "weight", "m_white_var", "m_bias_var"):
        np.testing.assert_array_equal(getattr(tape.raw, name), getattr(seen.raw, name)[raw],
                                      err_msg=name)
    np.testing.assert_allclose(tape.raw.value, seen.raw.value[raw], rtol=ROUND_OFF)
    a, expected = tape.raw.A, seen.raw.A[raw]
    row_norm = np.linalg.norm(expected, axis=1, keepdims=True)
    assert np.max(np.abs(a - expected) / row_norm) <= ROUND_OFF
    # scheduled: the range samples QUITO's passes ask for; KOUROU and MALINDI: nothing
    np.testing.assert_array_equal(tape.editing.scheduled_obs, [seen.passes.n_obs[quito].sum(),
                                                                0, 0])
    assert sim.warnings == tuple(
        f"{tmp_path / 'scenario.toml'}: tracking.stations[{i}]: {name} yields no observation "
        "while other stations do (no pass in the schedule)"
        for i, name in ((1, "KOUROU"), (2, "MALINDI")))


def test_use_both_tracks_the_stations_without_passes_by_visibility(
        leo: Simulation, tmp_path: Path) -> None:
    """A schedule of QUITO's visibility passes alone, with use = "both": the visibility
    tape; only QUITO's editing counts its schedule."""
    tape = leo.tape
    rows = schedule_text(tape).splitlines()
    text = "\n".join(r for r, s in zip(rows, tape.passes.station, strict=True) if s == 1)
    both = _run(*_with_schedule(leo_document(), tmp_path, text + "\n", use="both")).tape
    assert_same_tape_but_editing(tape, both, tmp_path)
    np.testing.assert_array_equal(both.editing.scheduled_obs[1:], tape.editing.scheduled_obs[1:])
    assert both.editing.scheduled_obs[0] == tape.passes.n_obs[tape.passes.station == 1].sum()


def test_samples_outside_the_tape_are_counted_not_checked(leo: Simulation,
                                                          tmp_path: Path) -> None:
    """A pass of QUITO from -100 s to 0 (6 samples: at or before t = 0) and one after the
    tape's end (10800 s; 10820..11000: 10 samples), whatever QUITO sees then: outside_tape."""
    text = schedule_text(leo.tape) + "QUITO,-100,0\nQUITO,10810,11000\n"
    sim = _run(*_with_schedule(leo_document(), tmp_path, text)).tape
    assert sim.editing.removed_obs[0, OUTSIDE] == 2 * 16
    assert sim.editing.removed_obs.sum() == 2 * 16


def test_use_schedule_needs_a_schedule() -> None:
    with pytest.raises(InputError) as err:
        parse_scenario(leo_document(tracking={"use": "schedule"}), "leo.toml")
    assert str(err.value) == ('leo.toml: tracking.schedule: expected a pass schedule file with '
                              'use = "schedule"')


def test_use_visibility_does_not_read_the_schedule(leo: Simulation) -> None:
    sc = parse_scenario(leo_document(tracking={"use": "visibility",
                                               "schedule": "no/such/file.csv"}), "leo.toml")
    assert sc.schedule.passes is None and sc.schedule.use == "visibility"
