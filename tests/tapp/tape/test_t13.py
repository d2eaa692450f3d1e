"""T13 tapes: the schema as written, round trips, and the reader's refusals."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.tape import t13, t13_hdf5
from tapp.tape.files import describe, verify
from tapp.tape.hdf5io import write_numbers
from tapp.tape.packing import tr_size
from tapp.tape.t13 import PARTS, T13
from tapp.tape.t13_hdf5 import read_t13, write_t13
from tapp.tracking.noise import PARTS as NOISE_PARTS
from tapp.tracking.simulate import simulate
from tests.tapp.tracking.helpers import leo_scenario, scaled_close

# Sums of a few hundred products in another order: round-off, on the scale sqrt(J_aa J_bb).
SUM_ORDER = 1e-10


@pytest.fixture(scope="module")
def tape() -> T13:
    return simulate(leo_scenario(times={"epochs": [3600.0]}), raw=True).tape


@pytest.fixture
def written(tmp_path: Path, tape: T13) -> Path:
    return write_t13(tmp_path / "run.t13.h5", tape)


def test_schema_attributes_groups_and_storage(written: Path, tape: T13) -> None:
    with h5py.File(written, "r") as f:
        # text attributes are fixed-length UTF-8 (in the checksummed object header): bytes
        attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f.attrs.items()}
        for key in ("format", "version", "iden", "n_o", "n_p", "n_m", "n_ts", "n_it", "epoch",
                    "units", "tapp_version", "git_commit", "created_utc", "scenario"):
            assert key in attrs, key
        assert attrs["format"] == "T13" and attrs["version"] == 2
        assert (attrs["n_o"], attrs["n_p"], attrs["n_m"], attrs["n_ts"], attrs["n_it"]) == (
            tape.n_o, 6, 6, 3, 3)
        assert attrs["epoch"] == "2026-01-01T00:00:00.000000"
        assert '"iden": "TEST-LEO"' in attrs["scenario"]
        dj = f["pairs/dJ"]
        assert dj.shape == (tape.pairs.k.size, tr_size(tape.n_o))
        assert dj.attrs["packing"] == b"TR" and dj.compression == "gzip" and dj.chunks
        assert f["raw/A"].compression == "gzip"
        parts = f["pairs/dJt_parts"]
        assert parts.shape == (tape.pairs.k.size, 3, tr_size(tape.n_o))
        assert list(parts.attrs["parts"]) == [b"white", b"bias", b"correlated"]
        datasets: list[h5py.Dataset] = []
        f.visititems(lambda _, obj: datasets.append(obj) if isinstance(obj, h5py.Dataset)
                     else None)
        assert len(datasets) > 40
        for ds in datasets:  # every dataset chunked and checksummed, with its units
            assert ds.fletcher32 and ds.chunks and "units" in ds.attrs, ds.name
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
    """Replace a dataset by ``data``, checksummed as the writer does, keeping its attrs."""
    attrs = dict(f[name].attrs)
    del f[name]
    parent, _, leaf = name.rpartition("/")
    write_numbers(f[parent] if parent else f, leaf, np.asarray(data), "")
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
    with pytest.raises(TapeError, match=f"{written}: pairs/dJ: expected data matching its "
                                        "Fletcher-32 checksum"):
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
        f.attrs["format"] = "OBS"
        f["J"] = np.zeros((3, 6))
    assert describe(other) == {"format": "OBS", "attributes": {"format": "OBS"},
                               "datasets": {"J": {"shape": [3, 6], "dtype": "float64"}},
                               "verified_datasets": 1}


# ---------------------------------------------------------------------------------------------
# Version 2: checksums, text, version 1 still read
# ---------------------------------------------------------------------------------------------


def _flip_byte(path: Path, dataset: str, at: int = 0) -> None:
    """Flip one byte of a dataset's stored data (its first chunk, or contiguous storage)."""
    with h5py.File(path, "r") as f:
        ds = f[dataset]
        offset = ds.id.get_chunk_info(0).byte_offset if ds.chunks else ds.id.get_offset()
    with path.open("r+b") as fh:
        fh.seek(offset + at)
        byte = fh.read(1)[0]
        fh.seek(offset + at)
        fh.write(bytes([byte ^ 0x5A]))


@pytest.mark.parametrize("dataset", ["pairs/n_obs", "records/info", "B", "pairs/dJ",
                                     "pairs/dJt_parts", "parameters/name", "raw/A"])
def test_a_flipped_byte_in_any_dataset_fails_its_checksum(written: Path, dataset: str) -> None:
    _flip_byte(written, dataset, at=3)
    expected = (f"{written}: {dataset}: expected data matching its Fletcher-32 checksum "
                "(got checksum mismatch (corrupt file))")
    with pytest.raises(TapeError) as err:
        read_t13(written)
    assert str(err.value) == expected
    with pytest.raises(TapeError) as err:
        verify(written)
    assert str(err.value) == expected
    with pytest.raises(TapeError, match=f"{dataset}: expected data matching"):
        describe(written)


def test_verify_reads_every_dataset(written: Path) -> None:
    names = verify(written)
    with h5py.File(written, "r") as f:
        expected: list[str] = []
        f.visititems(lambda name, obj: expected.append(name)
                     if isinstance(obj, h5py.Dataset) else None)
    assert sorted(names) == sorted(expected) and "raw/A" in names and "pairs/dJ" in names


def test_a_dataset_without_checksum_is_refused_in_version_2(written: Path) -> None:
    def plain(f: h5py.File) -> None:
        data = f["records/info"][()]
        del f["records/info"]
        f["records/info"] = data

    _edit(written, plain)
    with pytest.raises(TapeError, match=r"records/info: expected a Fletcher-32 checksum filter "
                                        r"on the dataset \(got none\)"):
        read_t13(written)


def test_text_that_is_not_utf8_is_a_tape_error(written: Path) -> None:
    def bad_name(f: h5py.File) -> None:
        names = [n.encode() for n in f["parameters/name"].asstr()[()]]
        names[1] = b"\xff\xfe_km"
        del f["parameters/name"]
        f["parameters"].create_dataset("name", data=np.array(names, dtype="S8"), chunks=True,
                                       fletcher32=True)

    _edit(written, bad_name)
    message = f"{written}: parameters/name: expected UTF-8 text (got b'\\xff\\xfe_km')"
    with pytest.raises(TapeError) as err:
        read_t13(written)
    assert str(err.value) == message
    with pytest.raises(TapeError) as err:
        verify(written)
    assert str(err.value) == message


def test_attribute_that_is_not_utf8_is_a_tape_error(written: Path) -> None:
    _edit(written, lambda f: f.attrs.__setitem__("iden", np.bytes_(b"LEO\xff")))
    for read in (read_t13, verify, describe):
        with pytest.raises(TapeError, match=r"attrs/iden: expected UTF-8 text"):
            read(written)


def _write_v1(path: Path, tape: T13) -> Path:
    with h5py.File(path, "w") as f:
        t13_hdf5._write(f, tape, "TR", version=1)
    return path


def test_version_1_is_read_with_a_warning(tmp_path: Path, tape: T13) -> None:
    path = _write_v1(tmp_path / "v1.h5", tape)
    with h5py.File(path, "r") as f:
        assert f.attrs["version"] == 1 and "dJt_parts" not in f["pairs"]
        assert not f["B"].fletcher32 and not f["pairs/dJ"].fletcher32
        assert h5py.check_string_dtype(f["parameters/name"].dtype).length is None  # vlen
    with pytest.warns(UserWarning, match="T13 version 1 carries no checksums: corruption "
                                         "cannot be detected"):
        back = read_t13(path)
    np.testing.assert_array_equal(back.pairs.dJt, tape.pairs.dJt)
    np.testing.assert_array_equal(back.raw.A, tape.raw.A)
    assert back.pairs.dJt_parts is None and back.parameters.name == tape.parameters.name
    with pytest.warns(UserWarning, match="version 1"):
        assert describe(path)["version"] == 1
    # Without checksums a flipped byte of data goes unnoticed: the reason for version 2.
    _flip_byte(path, "records/info")
    assert "records/info" in verify(path)


def test_version_1_reader_still_validates(tmp_path: Path, tape: T13) -> None:
    path = _write_v1(tmp_path / "v1.h5", tape)
    _edit(path, lambda f: _replace(f, "records/U", np.full(f["records/U"].shape, np.nan)))
    with pytest.warns(UserWarning, match="version 1"), pytest.raises(
            TapeError, match=f"{path}: records/U: expected finite values"):
        read_t13(path)


# ---------------------------------------------------------------------------------------------
# The parts of dJt
# ---------------------------------------------------------------------------------------------


def test_parts_are_the_three_noise_terms_of_the_raw_rows(tape: T13) -> None:
    raw, parts = tape.raw, tape.pairs.dJt_parts
    assert PARTS == NOISE_PARTS
    scaled_close(parts.sum(axis=1), tape.pairs.dJt, 1e-13)
    for j in np.unique(tape.records.j):
        ks = tape.records.k[tape.records.j == j]
        pairs, rows = np.isin(tape.pairs.k, ks), np.isin(raw.record, ks)
        t, seg = raw.t_s[rows], raw.segment[rows]
        same = seg[:, None] == seg[None, :]
        corr = np.sqrt(raw.m_corr_var[rows][:, None] * raw.m_corr_var[rows][None, :])
        m_parts = (np.diag(raw.m_white_var[rows]),
                   same * raw.m_bias_var[rows][:, None],
                   same * corr * np.exp(-np.abs(t[:, None] - t[None, :])
                                        / raw.m_tau_s[rows][:, None]))
        wa = raw.weight[rows][:, None] * raw.A[rows]
        total = tape.pairs.dJt[pairs].sum(axis=0)
        for i, m in enumerate(m_parts):
            # each part on the scale of the whole AᵀWMWA (a part may vanish on a parameter)
            d = np.sqrt(np.diag(total))
            err = np.abs(parts[pairs, i].sum(axis=0) - wa.T @ m @ wa) / np.outer(d, d)
            assert err.max() < SUM_ORDER, (PARTS[i], err.max())
            assert np.abs(parts[pairs, i]).max() > 0, PARTS[i]  # the scenario has all three


def test_parts_that_do_not_sum_to_dJt_are_refused(tmp_path: Path, tape: T13, written: Path
                                                  ) -> None:
    bad = dataclasses.replace(tape, pairs=dataclasses.replace(
        tape.pairs, dJt_parts=tape.pairs.dJt_parts * np.array([1.0, 1.0, 1.001])[:, None, None]))
    with pytest.raises(TapeError, match=r"bad.h5: pairs/dJt_parts: expected parts summing to "
                                        r"pairs/dJt \(relative difference <= 1e-10\)"):
        write_t13(tmp_path / "bad.h5", bad)
    assert not (tmp_path / "bad.h5").exists()

    def scale(f: h5py.File) -> None:
        data = f["pairs/dJt_parts"][()]
        data[4, 0] *= 1.0 + 1e-8
        _replace(f, "pairs/dJt_parts", data)

    _edit(written, scale)
    with pytest.raises(TapeError, match=r"pairs/dJt_parts: expected parts summing.*in pair 4"):
        read_t13(written)


def test_parts_attribute_and_shape_are_checked(written: Path) -> None:
    _edit(written, lambda f: f["pairs/dJt_parts"].attrs.__setitem__("parts", ["a", "b", "c"]))
    with pytest.raises(TapeError, match=r"pairs/dJt_parts.attrs/parts: expected the parts "
                                        r"white, bias, correlated \(got a, b, c\)"):
        read_t13(written)


def test_a_tape_without_parts_is_valid(tmp_path: Path, tape: T13) -> None:
    bare = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, dJt_parts=None))
    back = read_t13(write_t13(tmp_path / "bare.h5", bare))
    assert back.pairs.dJt_parts is None


def test_unsorted_pairs_are_refused(tmp_path: Path, tape: T13) -> None:
    order = np.array([1, 0, 2, 3, 4, 5])
    p = tape.pairs
    swapped = dataclasses.replace(tape, pairs=t13.TapePairs(
        p.k[order], p.station[order], p.n_obs[order], p.dJ[order], p.dJt[order],
        p.dJt_parts[order]))
    with pytest.raises(TapeError, match=r"pairs/k: expected each \(record, station\) pair "
                                        r"once, sorted by \(k, station\) \(got pair 1 = \(1, 1\)"):
        write_t13(tmp_path / "x.h5", swapped)


def test_file_writer_writes_a_complete_tape_at_any_path(tmp_path: Path, tape: T13) -> None:
    writer = t13_hdf5.t13_file_writer(tape, "full")
    writer(tmp_path / "direct.h5")
    np.testing.assert_array_equal(read_t13(tmp_path / "direct.h5").pairs.dJt_parts,
                                  tape.pairs.dJt_parts)
    bad = dataclasses.replace(tape, records=dataclasses.replace(
        tape.records, j=np.array([0, 0, 1])))
    with pytest.raises(TapeError, match="T13: records/j"):  # validated before any file
        t13_hdf5.t13_file_writer(bad)
    with pytest.raises(InputError, match="packing"):
        t13_hdf5.t13_file_writer(tape, "LR")
