"""T13 tapes: the schema as written, round trips, and the reader's refusals."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.tape import describe, read_t13, write_t13
from tapp.tape.packing import tr_size
from tapp.tape.t13 import T13
from tapp.tracking.simulate import simulate
from tests.tapp.tracking.helpers import leo_scenario


@pytest.fixture(scope="module")
def tape() -> T13:
    return simulate(leo_scenario(times={"epochs": [3600.0]}), raw=True).tape


@pytest.fixture
def written(tmp_path: Path, tape: T13) -> Path:
    return write_t13(tmp_path / "run.t13.h5", tape)


def test_schema_attributes_groups_and_storage(written: Path, tape: T13) -> None:
    with h5py.File(written, "r") as f:
        attrs = dict(f.attrs)
        for key in ("format", "version", "iden", "n_o", "n_p", "n_m", "n_ts", "n_it", "epoch",
                    "units", "tapp_version", "git_commit", "created_utc", "scenario"):
            assert key in attrs, key
        assert attrs["format"] == "T13" and attrs["version"] == 1
        assert (attrs["n_o"], attrs["n_p"], attrs["n_m"], attrs["n_ts"], attrs["n_it"]) == (
            tape.n_o, 6, 6, 3, 3)
        assert attrs["epoch"] == "2026-01-01T00:00:00.000000"
        assert '"iden": "TEST-LEO"' in attrs["scenario"]
        dj = f["pairs/dJ"]
        assert dj.shape == (tape.pairs.k.size, tr_size(tape.n_o))
        assert dj.attrs["packing"] == "TR" and dj.compression == "gzip" and dj.chunks
        assert f["raw/A"].compression == "gzip"
        assert f["B"].shape == (6, tape.n_o) and f["records/U"].shape == (3, 6, tape.n_o)
        assert list(f["parameters/name"].asstr()[:2]) == ["x_km", "y_km"]
        for name in ("B", "records/U", "pairs/dJt", "times/t_s", "stations/lat_deg"):
            assert "units" in f[name].attrs
    assert not [p for p in written.parent.iterdir() if p.name.startswith(".")]  # no temp
    assert written.stat().st_mode & 0o777 == 0o644


def test_round_trip_is_exact(written: Path, tape: T13) -> None:
    back = read_t13(written)
    assert back.iden == tape.iden and back.epoch == tape.epoch
    assert back.parameters.name == tape.parameters.name
    for group in ("records", "pairs", "passes", "raw"):
        for f in dataclasses.fields(getattr(tape, group)):
            mine, theirs = getattr(getattr(tape, group), f.name), getattr(getattr(back, group),
                                                                         f.name)
            if isinstance(mine, np.ndarray):
                np.testing.assert_array_equal(theirs, mine, err_msg=f"{group}/{f.name}")
            else:
                assert theirs == mine
    np.testing.assert_array_equal(back.miss.B, tape.miss.B)
    assert back.provenance["scenario_source"] == "test_scenario.toml"
    assert read_t13(written, raw=False).raw is None


def test_full_packing_round_trip(tmp_path: Path, tape: T13) -> None:
    path = write_t13(tmp_path / "full.h5", tape, packing="full")
    with h5py.File(path, "r") as f:
        assert f["pairs/dJ"].shape == (tape.pairs.k.size, tape.n_o**2)
    np.testing.assert_array_equal(read_t13(path).pairs.dJt, tape.pairs.dJt)


def _edit(path: Path, fn) -> None:
    with h5py.File(path, "r+") as f:
        fn(f)


def _replace(f: h5py.File, name: str, data) -> None:
    attrs = dict(f[name].attrs)
    del f[name]
    f[name] = data
    f[name].attrs.update(attrs)


def test_non_symmetric_dJ_is_rejected_naming_the_dataset(tmp_path: Path, tape: T13) -> None:
    path = write_t13(tmp_path / "full.h5", tape, packing="full")
    n = tape.n_o

    def skew(f: h5py.File) -> None:
        data = f["pairs/dJ"][()]
        data[0, 1] *= 1.0 + 1e-6  # entry (0, 1) of the first pair, not (1, 0)
        _replace(f, "pairs/dJ", data)

    _edit(path, skew)
    with pytest.raises(TapeError, match=r"full.h5: pairs/dJ: expected symmetric") as err:
        read_t13(path)
    assert "pair 0" in str(err.value)
    assert n > 1


@pytest.mark.parametrize(("edit", "dataset"), [
    (lambda f: f.attrs.__setitem__("format", "T32"), "attrs/format"),
    (lambda f: f.attrs.__setitem__("version", 99), "attrs/version"),
    (lambda f: f.attrs.__setitem__("n_o", 5), "attrs/n_o"),
    (lambda f: f.__delitem__("B"), "B"),
    (lambda f: _replace(f, "records/U", np.full(f["records/U"].shape, np.nan)), "records/U"),
    (lambda f: _replace(f, "records/j", np.array([0, 1, 0])), "records/j"),
    (lambda f: _replace(f, "records/t_s", f["records/t_s"][()] + 1.0), "records/t_s"),
    (lambda f: _replace(f, "times/t_s", f["times/t_s"][()][::-1]), "times/t_s"),
    (lambda f: _replace(f, "pairs/dJ", -np.abs(f["pairs/dJ"][()])), "pairs/dJ"),
    (lambda f: _replace(f, "pairs/dJt", f["pairs/dJt"][()][:, :-1]), "pairs/dJt"),
    (lambda f: _replace(f, "pairs/station", np.full(f["pairs/station"].shape, 9)),
     "pairs/station"),
    (lambda f: _replace(f, "raw/A", f["raw/A"][()][:, :3]), "raw/A"),
])
def test_reader_rejects_a_bad_tape_naming_the_dataset(written: Path, edit, dataset: str
                                                      ) -> None:
    _edit(written, edit)
    with pytest.raises(TapeError) as err:
        read_t13(written)
    assert str(err.value).startswith(f"{written}: {dataset}: expected"), str(err.value)


def test_truncated_tape_is_rejected(written: Path) -> None:
    size = written.stat().st_size
    os.truncate(written, size // 2)
    with pytest.raises(TapeError, match="truncated") as err:
        read_t13(written)
    assert str(err.value).startswith(f"{written}: file: expected a readable HDF5 file")
    with pytest.raises(TapeError):
        describe(written)


def test_corrupt_chunk_is_rejected_naming_the_dataset(written: Path) -> None:
    with h5py.File(written, "r") as f:
        info = f["pairs/dJ"].id.get_chunk_info(0)
    with written.open("r+b") as fh:
        fh.seek(info.byte_offset + 8)
        fh.write(b"\xff" * 64)
    with pytest.raises(TapeError, match=f"{written}: pairs/dJ: expected readable data"):
        read_t13(written)


def test_writer_refuses_an_invalid_tape_and_leaves_nothing(tmp_path: Path, tape: T13) -> None:
    bad = dataclasses.replace(tape, records=dataclasses.replace(
        tape.records, j=np.array([0, 0, 1])))
    with pytest.raises(TapeError, match="records/j"):
        write_t13(tmp_path / "bad.h5", bad)
    assert list(tmp_path.iterdir()) == []


def test_missing_file_and_describe(tmp_path: Path, written: Path) -> None:
    with pytest.raises(InputError, match="file: expected an existing T13 tape"):
        read_t13(tmp_path / "none.h5")
    info = describe(written)
    assert info["format"] == "T13" and info["dimensions"]["n_ts"] == 3
    assert sum(s["observations"] for s in info["stations"]) == info["observations"]
    assert [e["t_s"] for e in info["epochs"]] == [0.0, 3600.0]
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.attrs["format"] = "T32"
        f["J"] = np.zeros((3, 6))
    assert describe(other) == {"format": "T32", "attributes": {"format": "T32"},
                               "datasets": {"J": {"shape": [3, 6], "dtype": "float64"}}}
