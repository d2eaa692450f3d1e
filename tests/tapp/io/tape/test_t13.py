"""T13 tapes: the schema as written, round trips, and the reader's refusals.

Version 3 carries square-root information: upper-triangular factors R, R̃ (RᵀR = AᵀWA,
R̃ᵀR̃ = AᵀWMWA) and the factors of R̃'s parts. Versions 1 and 2 carried the normal matrices;
they are still read (checked as those versions were, then factored, with a warning).
"""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
from pathlib import Path

import h5py
import hdf5plugin
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.io.tape import t13, t13_hdf5
from tapp.io.tape.files import describe, verify
from tapp.io.tape.hdf5io import write_numbers
from tapp.io.tape.packing import tr_size
from tapp.io.tape.t13 import T13, VERSION
from tapp.io.tape.t13_hdf5 import open_t13, read_t13, write_t13
from tapp.measurements.noise import PARTS
from tapp.tracking.simulate import simulate
from tests.tapp.io.tape.legacy import (
    EPS,
    bits,
    gram,
    refactored_tol,
    symmetric_from_rows,
    t13_read_warnings,
    upper_by_rows,
    write_t13_version,
)
from tests.tapp.tracking.helpers import leo_scenario, scaled_close

# Sums of a few hundred products in another order: round-off, on the scale sqrt(J_aa J_bb).
SUM_ORDER = 1e-10
# A normal matrix of a version-1 or -2 tape against the Gram RᵀR of the factor read from it,
# on the scale sqrt(J_aa J_bb): n_o² ε with n_o = 23, 1.2e-13 (legacy.refactored_tol; the
# matrices of the LEO tape are semi-definite, of rank 6 or 7). Measured: 4.6e-15.
REFACTORED = refactored_tol(23)


@pytest.fixture(scope="module")
def tape() -> T13:
    return simulate(leo_scenario(times={"epochs": [3600.0]}), raw=True).tape


@pytest.fixture
def written(tmp_path: Path, tape: T13) -> Path:
    return write_t13(tmp_path / "run.t13.h5", tape)


def _filters(ds: h5py.Dataset) -> list[int]:
    """The HDF5 filter pipeline of a dataset, in the order applied on writing."""
    dcpl = ds.id.get_create_plist()
    return [dcpl.get_filter(i)[0] for i in range(dcpl.get_nfilters())]


def test_schema_attributes_groups_and_storage(written: Path, tape: T13) -> None:
    n_pairs, n_o = tape.pairs.k.size, tape.n_o
    with h5py.File(written, "r") as f:
        # text attributes are fixed-length UTF-8 (in the checksummed object header): bytes
        attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f.attrs.items()}
        for key in ("format", "version", "iden", "n_o", "n_p", "n_m", "n_ts", "n_it", "epoch",
                    "units", "tapp_version", "git_commit", "created_utc", "scenario"):
            assert key in attrs, key
        assert attrs["format"] == "T13" and attrs["version"] == VERSION
        assert (attrs["n_o"], attrs["n_p"], attrs["n_m"], attrs["n_ts"], attrs["n_it"]) == (
            tape.n_o, 6, 6, 3, 3)
        assert attrs["epoch"] == "2026-01-01T00:00:00.000000"
        assert '"iden": "TEST-LEO"' in attrs["scenario"]
        assert sorted(f["pairs"]) == ["R", "Rt", "Rt_parts", "k", "n_obs", "station"]
        for name in ("pairs/R", "pairs/Rt"):
            ds = f[name]
            assert ds.shape == (n_pairs, tr_size(n_o)), name
            assert (ds.attrs["packing"], ds.attrs["order"], ds.attrs["form"]) == (
                b"TR", n_o, b"factor"), name
            assert ds.attrs["units"] == b"1/u_b, u = parameters/unit", name
            assert ds.chunks, name
        for name in ("records/U", "pairs/R", "pairs/Rt", "pairs/Rt_parts", "raw/A"):
            # LZ4, then the checksum of the stored (compressed) bytes; no shuffle
            assert _filters(f[name]) == [hdf5plugin.LZ4_ID, h5py.h5z.FILTER_FLETCHER32], name
        assert _filters(f["records/info"]) == [h5py.h5z.FILTER_FLETCHER32]
        parts = f["pairs/Rt_parts"]
        assert parts.shape == (n_pairs, 3, tr_size(n_o))
        assert parts.attrs["form"] == b"factor"
        assert list(parts.attrs["parts"]) == [b"white", b"bias", b"correlated"]
        # "TR": the upper triangle of each factor by rows, every bit of it
        for name in ("R", "Rt", "Rt_parts"):
            np.testing.assert_array_equal(bits(f[f"pairs/{name}"][()]),
                                          bits(upper_by_rows(getattr(tape.pairs, name))),
                                          err_msg=name)
        datasets: list[h5py.Dataset] = []
        f.visititems(lambda _, obj: datasets.append(obj) if isinstance(obj, h5py.Dataset)
                     else None)
        assert len(datasets) > 40
        for ds in datasets:  # every dataset chunked and checksummed, with its units
            assert ds.fletcher32 and ds.chunks and "units" in ds.attrs, ds.name
        assert f["B"].shape == (6, tape.n_o) and f["records/U"].shape == (3, 6, tape.n_o)
        assert list(f["parameters/name"].asstr()[:2]) == ["x_km", "y_km"]
        for name in ("B", "records/U", "pairs/Rt", "times/t_s", "stations/lat_deg"):
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
    # the factors bit for bit on and above the diagonal ("TR" stores those), zero below
    for name in ("R", "Rt", "Rt_parts"):
        mine, theirs = getattr(tape.pairs, name), getattr(back.pairs, name)
        assert theirs.dtype == np.float64 and theirs.shape == mine.shape, name
        np.testing.assert_array_equal(bits(upper_by_rows(theirs)),
                                      bits(upper_by_rows(mine)), err_msg=name)
        assert not np.any(np.tril(theirs, -1)), name
    np.testing.assert_array_equal(back.miss.B, tape.miss.B)
    assert back.provenance["scenario_source"] == "test_scenario.toml"
    assert read_t13(written, raw=False).raw is None


def test_full_packing_round_trip(tmp_path: Path, tape: T13) -> None:
    path = write_t13(tmp_path / "full.h5", tape, packing="full")
    n_o = tape.n_o
    with h5py.File(path, "r") as f:
        ds = f["pairs/R"]
        assert ds.shape == (tape.pairs.k.size, n_o**2)
        assert (ds.attrs["packing"], ds.attrs["form"]) == (b"full", b"factor")
        assert f["pairs/Rt_parts"].shape == (tape.pairs.k.size, 3, n_o**2)
        assert not np.any(np.tril(ds[()].reshape(-1, n_o, n_o), -1))  # zero below
    back = read_t13(path)
    for name in ("R", "Rt", "Rt_parts"):  # every bit of the n_o² entries
        np.testing.assert_array_equal(bits(getattr(back.pairs, name)),
                                      bits(getattr(tape.pairs, name)), err_msg=name)


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


def test_an_entry_below_the_diagonal_of_a_full_factor_is_rejected(tmp_path: Path, tape: T13
                                                                   ) -> None:
    """With "full" packing the zeros below the diagonal are stored: a factor with anything
    there is not upper triangular."""
    path = write_t13(tmp_path / "full.h5", tape, packing="full")
    n = tape.n_o

    def lower(f: h5py.File) -> None:
        data = f["pairs/R"][()]
        assert data[0, n] == 0.0
        data[0, n] = 1e-6 * data[0, 0]  # entry (1, 0) of the first pair
        _replace(f, "pairs/R", data)

    _edit(path, lower)
    with pytest.raises(TapeError) as err:
        read_t13(path)
    assert str(err.value) == (f"{path}: pairs/R: expected upper-triangular factors (zero "
                              "below the diagonal)")


def test_non_symmetric_dJ_of_version_2_is_rejected_naming_the_dataset(tmp_path: Path,
                                                                      tape: T13) -> None:
    path = write_t13_version(tmp_path / "full.h5", tape, 2, "full")

    def skew(f: h5py.File) -> None:
        data = f["pairs/dJ"][()]
        data[0, 1] *= 1.0 + 1e-6  # entry (0, 1) of the first pair, not (1, 0)
        _replace(f, "pairs/dJ", data)

    _edit(path, skew)
    with t13_read_warnings(2), pytest.raises(
            TapeError, match=r"full.h5: pairs/dJ: expected symmetric normal matrices") as err:
        read_t13(path)
    assert "pair 0" in str(err.value)


@pytest.mark.parametrize(("edit", "dataset"), [
    (lambda f: f.attrs.__setitem__("format", "T32"), "attrs/format"),
    (lambda f: f.attrs.__setitem__("version", 99), "attrs/version"),
    (lambda f: f.attrs.__setitem__("version", VERSION + 1), "attrs/version"),
    (lambda f: f.attrs.__setitem__("n_o", 5), "attrs/n_o"),
    (lambda f: f.__delitem__("B"), "B"),
    (lambda f: f.__delitem__("pairs/Rt"), "pairs/Rt"),
    (lambda f: _replace(f, "records/U", np.full(f["records/U"].shape, np.nan)), "records/U"),
    (lambda f: _replace(f, "records/j", np.array([0, 1, 0])), "records/j"),
    (lambda f: _replace(f, "records/t_s", f["records/t_s"][()] + 1.0), "records/t_s"),
    (lambda f: _replace(f, "times/t_s", f["times/t_s"][()][::-1]), "times/t_s"),
    (lambda f: _replace(f, "pairs/R", -np.abs(f["pairs/R"][()])), "pairs/R"),
    (lambda f: _replace(f, "pairs/Rt", f["pairs/Rt"][()][:, :-1]), "pairs/Rt"),
    (lambda f: _replace(f, "pairs/Rt", np.full(f["pairs/Rt"].shape, np.inf)), "pairs/Rt"),
    (lambda f: _replace(f, "pairs/Rt_parts", -np.abs(f["pairs/Rt_parts"][()])),
     "pairs/Rt_parts"),
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


def test_a_negative_diagonal_is_rejected_naming_the_pair_and_row(written: Path, tape: T13
                                                                 ) -> None:
    """The canonical sign of a QR: a factor's diagonal is >= 0 (the row times -1 is a factor
    of the same matrix, so the tape fixes the sign)."""
    at = tr_size(tape.n_o) - tr_size(tape.n_o - 4)  # the diagonal entry of row 4, "TR"

    def negative(f: h5py.File) -> None:
        data = f["pairs/Rt"][()]
        assert data[2, at] > 0
        data[2, at] = -data[2, at]
        _replace(f, "pairs/Rt", data)

    _edit(written, negative)
    with pytest.raises(TapeError, match=rf"^{re.escape(str(written))}: pairs/Rt: expected "
                                        r"factors with a non-negative diagonal \(the canonical "
                                        r"sign of a QR\) \(got -[0-9.e+-]+ in pair 2, row 4\)$"):
        read_t13(written)


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
        info = f["pairs/R"].id.get_chunk_info(0)
    with written.open("r+b") as fh:
        fh.seek(info.byte_offset + 8)
        fh.write(b"\xff" * 64)
    with pytest.raises(TapeError, match=f"{written}: pairs/R: expected data matching its "
                                        "Fletcher-32 checksum"):
        read_t13(written)


def test_writer_refuses_an_invalid_tape_and_leaves_nothing(tmp_path: Path, tape: T13) -> None:
    bad = dataclasses.replace(tape, records=dataclasses.replace(
        tape.records, j=np.array([0, 0, 1])))
    with pytest.raises(TapeError, match="records/j"):
        write_t13(tmp_path / "bad.h5", bad)
    assert list(tmp_path.iterdir()) == []


def test_writer_refuses_factors_that_are_not_upper_triangular(tmp_path: Path, tape: T13
                                                              ) -> None:
    """A symmetric normal matrix in place of its factor (the version-2 field, by mistake)."""
    bad = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, R=tape.pairs.dJ))
    with pytest.raises(TapeError, match=r"bad.h5: pairs/R: expected upper-triangular factors "
                                        r"\(zero below the diagonal\)"):
        write_t13(tmp_path / "bad.h5", bad)
    header = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, Rt=None))
    with pytest.raises(TapeError, match=r"bad.h5: pairs/Rt: expected the pair factors \(a "
                                        r"complete tape\) \(got None: a header"):
        write_t13(tmp_path / "bad.h5", header)
    assert list(tmp_path.iterdir()) == []


def test_missing_file_and_describe(tmp_path: Path, written: Path) -> None:
    with pytest.raises(InputError, match="file: expected an existing T13 tape"):
        read_t13(tmp_path / "none.h5")
    info = describe(written)
    assert (info["format"], info["version"], info["dimensions"]["n_ts"]) == ("T13", VERSION, 3)
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
# Version 3 (gzip) still read; version 4 (LZ4) with plain h5py
# ---------------------------------------------------------------------------------------------


def test_version_3_is_gzip_and_reads_as_version_4_to_the_bit(tmp_path: Path, tape: T13
                                                            ) -> None:
    v3 = write_t13_version(tmp_path / "v3.t13.h5", tape, 3)
    v4 = write_t13(tmp_path / "v4.t13.h5", tape)
    with h5py.File(v3, "r") as f:
        assert f.attrs["version"] == 3
        for name in ("records/U", "pairs/R", "pairs/Rt_parts", "raw/A"):
            assert _filters(f[name]) == [h5py.h5z.FILTER_SHUFFLE, h5py.h5z.FILTER_DEFLATE,
                                         h5py.h5z.FILTER_FLETCHER32], name
    old, new = read_t13(v3), read_t13(v4)
    for group in ("records", "pairs", "raw"):
        for field in dataclasses.fields(getattr(new, group)):
            a, b = getattr(getattr(old, group), field.name), getattr(getattr(new, group),
                                                                     field.name)
            if isinstance(b, np.ndarray):
                same = bits if b.dtype.kind == "f" else np.asarray
                np.testing.assert_array_equal(same(a), same(b), err_msg=field.name)
    assert verify(v3) == verify(v4)


#: Run by a plain interpreter: h5py alone reads a version-4 tape but for its LZ4 datasets,
#: and those too once hdf5plugin is imported.
_PLAIN_H5PY = """
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    print(f.attrs["version"], len(f["parameters/name"][()]), f["pairs/k"].shape[0])
    try:
        f["pairs/R"][()]
    except OSError:
        print("pairs/R needs hdf5plugin")
    import hdf5plugin
    print(f["pairs/R"][()].shape == f["pairs/R"].shape)
"""


def test_plain_h5py_reads_version_4_and_its_lz4_datasets_after_hdf5plugin(written: Path,
                                                                          tape: T13) -> None:
    env = {k: v for k, v in os.environ.items() if k != "HDF5_PLUGIN_PATH"}
    done = subprocess.run([sys.executable, "-c", _PLAIN_H5PY, str(written)], env=env,
                          capture_output=True, text=True, check=True)
    assert done.stdout.splitlines() == [f"{VERSION} {tape.n_o} {tape.pairs.k.size}",
                                        "pairs/R needs hdf5plugin", "True"]


# ---------------------------------------------------------------------------------------------
# Checksums, text; versions 1 and 2 still read
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


@pytest.mark.parametrize("dataset", ["pairs/n_obs", "records/info", "B", "pairs/R",
                                     "pairs/Rt_parts", "parameters/name", "raw/A"])
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
    assert sorted(names) == sorted(expected)
    assert {"raw/A", "pairs/R", "pairs/Rt", "pairs/Rt_parts"} <= set(names)


@pytest.mark.parametrize("version", [2, 3])
def test_a_dataset_without_checksum_is_refused_from_version_2(tmp_path: Path, tape: T13,
                                                              version: int) -> None:
    path = write_t13_version(tmp_path / f"v{version}.h5", tape, version)

    def plain(f: h5py.File) -> None:
        data = f["records/info"][()]
        del f["records/info"]
        f["records/info"] = data

    _edit(path, plain)
    with t13_read_warnings(version), pytest.raises(
            TapeError, match=r"records/info: expected a Fletcher-32 checksum filter on the "
                             r"dataset \(got none\)"):
        read_t13(path)


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


def test_version_1_is_read_with_a_warning(tmp_path: Path, tape: T13) -> None:
    path = write_t13_version(tmp_path / "v1.h5", tape, 1)
    with h5py.File(path, "r") as f:
        assert f.attrs["version"] == 1 and "dJt_parts" not in f["pairs"]
        assert "R" not in f["pairs"] and "Rt" not in f["pairs"]
        assert not f["B"].fletcher32 and not f["pairs/dJ"].fletcher32
        assert h5py.check_string_dtype(f["parameters/name"].dtype).length is None  # vlen
    with t13_read_warnings(1):
        back = read_t13(path)
    np.testing.assert_array_equal(back.raw.A, tape.raw.A)
    np.testing.assert_array_equal(back.records.U, tape.records.U)
    assert back.pairs.Rt_parts is None and back.parameters.name == tape.parameters.name
    with t13_read_warnings(1):
        assert describe(path)["version"] == 1
    # Without checksums a flipped byte of data goes unnoticed: the reason for version 2.
    _flip_byte(path, "records/info")
    assert "records/info" in verify(path)


def test_version_1_reader_still_validates(tmp_path: Path, tape: T13) -> None:
    path = write_t13_version(tmp_path / "v1.h5", tape, 1)
    _edit(path, lambda f: _replace(f, "records/U", np.full(f["records/U"].shape, np.nan)))
    with t13_read_warnings(1), pytest.raises(
            TapeError, match=f"{path}: records/U: expected finite values"):
        read_t13(path)


@pytest.mark.parametrize("lazy", [False, True])
def test_an_old_normal_matrix_that_is_not_semi_definite_is_refused(tmp_path: Path, tape: T13,
                                                                    lazy: bool) -> None:
    """Symmetric with a non-negative diagonal, yet indefinite beyond rounding (a 2 x 2 block
    [[4, 3], [3, 1]], eigenvalues 5.2 and −0.2): a version-2 reader must refuse it rather than
    read the positive part it would factor (the Gram would come back as [[5, 2.5], [2.5,
    1.25]] on that block), naming the dataset and the pair."""
    path = write_t13_version(tmp_path / "v2.h5", tape, 2)
    n_o = tape.n_o

    def indefinite(f: h5py.File) -> None:
        dj = symmetric_from_rows(f["pairs/dJ"][()], n_o)
        dj[2] = 0.0
        dj[2, :2, :2] = [[4.0, 3.0], [3.0, 1.0]]
        _replace(f, "pairs/dJ", upper_by_rows(dj))

    _edit(path, indefinite)
    with t13_read_warnings(2), pytest.raises(
            TapeError, match=rf"{path}: pairs/dJ: expected positive semi-definite normal "
                             r"matrices \(to 1e-08 of their scale\) \(got [0-9.e-]+ in pair 2\)"):
        if lazy:
            with open_t13(path) as data:
                for _ in data.blocks():
                    pass
        else:
            read_t13(path)


def _stored_matrices(stored: np.ndarray, n: int, packing: str) -> np.ndarray:
    """The symmetric (..., n, n) of a version-1 or -2 pair dataset: the upper triangle by rows
    mirrored ("TR"), or the n² entries as they are ("full")."""
    if packing == "full":
        return stored.reshape(*stored.shape[:-1], n, n)
    return symmetric_from_rows(stored, n)


@pytest.mark.parametrize("packing", ["TR", "full"])
@pytest.mark.parametrize("version", [1, 2])
def test_normal_matrices_of_versions_1_and_2_are_read_as_their_factors(
        tmp_path: Path, tape: T13, version: int, packing: str) -> None:
    """The matrices a version-1 or -2 tape carries come back as upper-triangular factors
    whose Grams are those matrices (to REFACTORED on the scale sqrt(J_aa J_bb)), the same
    from the whole-tape and the lazy reader, with the warning that their precision is that
    of the matrices."""
    path = write_t13_version(tmp_path / f"v{version}.h5", tape, version, packing)
    n_o = tape.n_o
    with h5py.File(path, "r") as f:
        assert f.attrs["version"] == version
        assert not {"R", "Rt", "Rt_parts"} & set(f["pairs"])
        stored = {name: _stored_matrices(f[f"pairs/{name}"][()], n_o, packing)
                  for name in ("dJ", "dJt", "dJt_parts") if name in f["pairs"]}
    assert sorted(stored) == (["dJ", "dJt", "dJt_parts"] if version == 2 else ["dJ", "dJt"])
    # the writer of the old layouts stores the normal matrices of the tape's factors
    scaled_close(stored["dJt"], gram(tape.pairs.Rt), REFACTORED)
    with t13_read_warnings(version):
        back = read_t13(path)
    read = {"dJ": back.pairs.R, "dJt": back.pairs.Rt, "dJt_parts": back.pairs.Rt_parts}
    for name, factors in read.items():
        if name not in stored:
            assert factors is None, name
            continue
        assert factors.shape == stored[name].shape, name
        assert not np.any(np.tril(factors, -1)), name
        assert np.all(np.diagonal(factors, axis1=-2, axis2=-1) >= 0), name
        assert scaled_close(gram(factors), stored[name], REFACTORED) >= 0, name
    with t13_read_warnings(version), open_t13(path) as lazy:
        assert lazy.version == version and lazy.has_parts == (version == 2)
        block = lazy.pair_block(1, lazy.header.n_it)
    for name, packed in (("R", block.R), ("Rt", block.Rt), ("Rt_parts", block.Rt_parts)):
        if getattr(back.pairs, name) is None:
            assert packed is None, name
        else:
            np.testing.assert_array_equal(packed, upper_by_rows(getattr(back.pairs, name)),
                                          err_msg=name)


# ---------------------------------------------------------------------------------------------
# The parts of R̃
# ---------------------------------------------------------------------------------------------


def test_parts_are_the_three_noise_terms_of_the_raw_rows(tape: T13) -> None:
    raw, parts, dJt = tape.raw, gram(tape.pairs.Rt_parts), gram(tape.pairs.Rt)
    scaled_close(parts.sum(axis=1), dJt, 1e-13)
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
        total = dJt[pairs].sum(axis=0)
        for i, m in enumerate(m_parts):
            # each part on the scale of the whole AᵀWMWA (a part may vanish on a parameter)
            d = np.sqrt(np.diag(total))
            err = np.abs(parts[pairs, i].sum(axis=0) - wa.T @ m @ wa) / np.outer(d, d)
            assert err.max() < SUM_ORDER, (PARTS[i], err.max())
            assert np.abs(parts[pairs, i]).max() > 0, PARTS[i]  # the scenario has all three


PARTS_MESSAGE = re.escape("pairs/Rt_parts: expected parts whose Gram matrices sum to R̃ᵀR̃ "
                          "(diagonal, relative difference <= 1e-10)")


def test_parts_that_do_not_sum_to_Rt_are_refused(tmp_path: Path, tape: T13, written: Path
                                                 ) -> None:
    bad = dataclasses.replace(tape, pairs=dataclasses.replace(
        tape.pairs, Rt_parts=tape.pairs.Rt_parts * np.array([1.0, 1.0, 1.001])[:, None, None]))
    with pytest.raises(TapeError, match=r"bad.h5: " + PARTS_MESSAGE):
        write_t13(tmp_path / "bad.h5", bad)
    assert not (tmp_path / "bad.h5").exists()

    def scale(f: h5py.File) -> None:
        data = f["pairs/Rt_parts"][()]
        data[4, 0] *= 1.0 + 1e-8  # the white part of pair 4: its Gram by 1 + 2e-8
        _replace(f, "pairs/Rt_parts", data)

    _edit(written, scale)
    with pytest.raises(TapeError, match=PARTS_MESSAGE + r" \(got [0-9.e-]+ in pair 4\)$"):
        read_t13(written)


def test_parts_of_version_2_that_do_not_sum_to_dJt_are_refused(tmp_path: Path, tape: T13
                                                               ) -> None:
    path = write_t13_version(tmp_path / "v2.h5", tape, 2)

    def scale(f: h5py.File) -> None:
        data = f["pairs/dJt_parts"][()]
        data[4, 0] *= 1.0 + 1e-8
        _replace(f, "pairs/dJt_parts", data)

    _edit(path, scale)
    with t13_read_warnings(2), pytest.raises(
            TapeError, match=r"pairs/dJt_parts: expected parts summing to pairs/dJt \(relative "
                             r"difference <= 1e-10\) \(got [0-9.e-]+ in pair 4\)$"):
        read_t13(path)


@pytest.mark.parametrize(("excess", "accepted"), [(0.5 * t13.PARTS_TOL, True),
                                                   (2.0 * t13.PARTS_TOL, False)])
def test_parts_sum_to_Rt_within_PARTS_TOL_on_the_diagonal(tape: T13, excess: float,
                                                          accepted: bool) -> None:
    """Every part's factor times sqrt(1 + excess): the parts' squared column norms sum to
    (1 + excess) times R̃'s, a relative difference of ``excess`` (the rounding of the scaling,
    1e-16, is far below the 0.5e-10 between the two cases)."""
    scaled = dataclasses.replace(tape, pairs=dataclasses.replace(
        tape.pairs, Rt_parts=tape.pairs.Rt_parts * np.sqrt(1.0 + excess)))
    if accepted:
        t13.validate(scaled)
    else:
        with pytest.raises(TapeError, match=PARTS_MESSAGE + r" \(got 2e-10 in pair 0\)$"):
            t13.validate(scaled)


def test_column_norms_of_full_and_packed_factors(tape: T13) -> None:
    """column_norms2 and packed_column_norms2, the diagonal of KᵀK that the parts are checked
    on, against the sum of squares down each column (summed by NumPy in another order: to
    n_o ε relative)."""
    n = tape.n_o
    k = tape.pairs.Rt_parts
    expected = (k * k).sum(axis=-2)
    np.testing.assert_allclose(t13.column_norms2(k), expected, rtol=n * EPS, atol=0)
    np.testing.assert_allclose(t13.packed_column_norms2(upper_by_rows(k), n), expected,
                               rtol=n * EPS, atol=0)
    np.testing.assert_allclose(np.diagonal(gram(k), axis1=-2, axis2=-1), expected,
                               rtol=n * EPS, atol=0)


def test_parts_attribute_and_shape_are_checked(written: Path) -> None:
    _edit(written, lambda f: f["pairs/Rt_parts"].attrs.__setitem__("parts", ["a", "b", "c"]))
    with pytest.raises(TapeError, match=r"pairs/Rt_parts.attrs/parts: expected the parts "
                                        r"white, bias, correlated \(got a, b, c\)"):
        read_t13(written)


def test_a_tape_without_parts_is_valid(tmp_path: Path, tape: T13) -> None:
    bare = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, Rt_parts=None))
    path = write_t13(tmp_path / "bare.h5", bare)
    with h5py.File(path, "r") as f:
        assert "Rt_parts" not in f["pairs"]
    assert read_t13(path).pairs.Rt_parts is None


def test_unsorted_pairs_are_refused(tmp_path: Path, tape: T13) -> None:
    order = np.array([1, 0, 2, 3, 4, 5])
    p = tape.pairs
    swapped = dataclasses.replace(tape, pairs=t13.TapePairs(
        p.k[order], p.station[order], p.n_obs[order], p.R[order], p.Rt[order],
        p.Rt_parts[order]))
    with pytest.raises(TapeError, match=r"pairs/k: expected each \(record, station\) pair "
                                        r"once, sorted by \(k, station\) \(got pair 1 = \(1, 1\)"):
        write_t13(tmp_path / "x.h5", swapped)


def test_file_writer_writes_a_complete_tape_at_any_path(tmp_path: Path, tape: T13) -> None:
    writer = t13_hdf5.t13_file_writer(tape, "full")
    writer(tmp_path / "direct.h5")
    np.testing.assert_array_equal(read_t13(tmp_path / "direct.h5").pairs.Rt_parts,
                                  tape.pairs.Rt_parts)
    bad = dataclasses.replace(tape, records=dataclasses.replace(
        tape.records, j=np.array([0, 0, 1])))
    with pytest.raises(TapeError, match="T13: records/j"):  # validated before any file
        t13_hdf5.t13_file_writer(bad)
    with pytest.raises(InputError, match="packing"):
        t13_hdf5.t13_file_writer(tape, "LR")
