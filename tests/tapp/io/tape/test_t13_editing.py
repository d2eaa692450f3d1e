"""The optional ``editing/`` group of T13 (from version 3): what the schedule asked for and
what each rule removed, written, read back, checked, and optional on read."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import TapeError
from tapp.io.tape.files import describe
from tapp.io.tape.hdf5io import write_numbers
from tapp.io.tape.t13 import T13
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.tracking.simulate import simulate
from tests.tapp.io.tape.legacy import write_t13_version
from tests.tapp.tracking.helpers import leo_scenario

EDITING = ("rule", "scheduled_obs", "removed_obs", "removed_passes", "added_passes")


@pytest.fixture(scope="module")
def tape() -> T13:
    """The 3 h LEO arc with passes of at least 100 s and at most 120 s, a blackout."""
    return simulate(leo_scenario(tracking={"min_pass_s": 100.0, "max_pass_s": 120.0,
                                           "blackouts": [[300.0, 400.0]]})).tape


def test_editing_is_written_with_units_and_checksums_and_read_back(tmp_path: Path, tape: T13
                                                                   ) -> None:
    ed = tape.editing
    assert ed.added_passes.sum() > 0 and ed.removed_obs[:, 2].sum() > 0  # split, blacked out
    path = write_t13(tmp_path / "run.t13.h5", tape)
    with h5py.File(path, "r") as f:
        for name in EDITING:
            ds = f[f"editing/{name}"]
            assert ds.fletcher32 and "units" in ds.attrs, name
    back = read_t13(path).editing
    assert back.rule == ed.rule
    for name in EDITING[1:]:
        np.testing.assert_array_equal(getattr(back, name), getattr(ed, name), err_msg=name)
    stations = describe(path)["stations"]
    np.testing.assert_array_equal([s["scheduled_observations"] for s in stations],
                                  ed.scheduled_obs)
    for s, removed in zip(stations, ed.removed_obs, strict=True):
        assert s["observations"] + sum(r["observations"] for r in s["removed"].values()) \
            == s["scheduled_observations"]
        assert [r["observations"] for r in s["removed"].values()] == removed.tolist()


def test_a_version_3_tape_without_editing_still_reads(tmp_path: Path, tape: T13) -> None:
    path = write_t13_version(tmp_path / "old.t13.h5", dataclasses.replace(tape, editing=None),
                             3)
    with h5py.File(path, "r") as f:
        assert "editing" not in f and f.attrs["version"] == 3
    assert read_t13(path).editing is None
    assert "removed" not in describe(path)["stations"][0]


def _rewrite(path: Path, name: str, data: np.ndarray) -> None:
    """Replace a dataset by ``data``, checksummed as the writer does."""
    with h5py.File(path, "r+") as f:
        del f[name]
        parent, _, leaf = name.rpartition("/")
        write_numbers(f[parent], leaf, data, "")


@pytest.mark.parametrize(("name", "change", "message"), [
    ("editing/removed_obs", lambda x: x + np.eye(*x.shape, dtype=x.dtype),
     r"editing/scheduled_obs: expected the observations kept \(pairs/n_obs\) plus those "
     r"removed \(editing/removed_obs\) at every station \(got \d+ scheduled at station 1, "),
    ("editing/added_passes", lambda x: x - 100, r"editing/added_passes: expected counts >= 0"),
    ("editing/removed_passes", lambda x: x[:, :2], r"editing/removed_passes: expected shape"),
])
def test_counts_that_do_not_add_up_are_refused(tmp_path: Path, tape: T13, name: str, change,
                                               message: str) -> None:
    path = write_t13(tmp_path / "run.t13.h5", tape)
    with h5py.File(path, "r") as f:
        data = f[name][()]
    _rewrite(path, name, change(data))
    with pytest.raises(TapeError, match=rf"^{path}: {message}"):
        read_t13(path)
