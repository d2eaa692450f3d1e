"""T32 tapes: the schema as written, round trips, the validations, corruption, atomic writes.

Version 2 carries every symmetric matrix as its upper-triangular factor (``<name>_factor``)
and each transition's adjoint; version 1, which carried the matrices, is still read (checked
as version 1 did, then factored, the adjoints solved for, with a warning).
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.io.tape import format_t32_summary, hdf5io, t32, t32_hdf5
from tapp.io.tape.files import describe, verify
from tapp.io.tape.packing import tr_size
from tapp.io.tape.t32 import SYMMETRIC, T32, T32Entity, T32Partition
from tapp.io.tape.t32_hdf5 import read_t32, write_t32
from tests.tapp.io.tape.legacy import (
    EPS,
    T32_V1_WARNING,
    gram,
    refactored_tol,
    symmetric_from_rows,
    t32_matrices,
    upper_by_rows,
    write_t32_version_1,
)
from tests.tapp.io.tape.synthetic import t32_tape
from tests.tapp.tracking.helpers import scaled_close

N_O = 9  # parameters of the synthetic tape
# A matrix of a version-1 tape against the Gram KᵀK of the factor read from it, on the scale
# sqrt(M_aa M_bb): n_o² ε, 1.8e-14 (legacy.refactored_tol). Measured: 3.9e-16.
REFACTORED = refactored_tol(N_O)
# The adjoint a version-1 reader solves for against its closed form Q diag(1/d) (synthetic.
# transition), relative to its largest entry, and the residual (T⁻ᵀ)ᵀT − I: n_o ε times the
# condition number of T = Q diag(d) (<= e², d in [1/e, e]), 1.5e-14: the size of the error
# of an LU solve, backward stable, in a matrix of that condition. Measured: 7.8e-16.
SOLVED = N_O * np.e**2 * EPS
# The rounding a version-1 tape's Σ = Λ'J̃Λ' can carry on a variance that cancels: −1.5e-9
# Λ̄'_ii was measured with a station switched off (tapp.io.tape.t32.SIGMA_ROUNDING).
ROUNDING = 1.5e-9


@pytest.fixture(scope="module")
def tape() -> T32:
    return t32_tape(np.random.default_rng(32))


@pytest.fixture
def written(tmp_path: Path, tape: T32) -> Path:
    return write_t32(tmp_path / "run.t32.h5", tape)


def _recycle(tape: T32, i: int = 0, **changes) -> T32:
    recycles = list(tape.recycles)
    recycles[i] = dataclasses.replace(recycles[i], **changes)
    return dataclasses.replace(tape, recycles=tuple(recycles))


def _assert_equal(a: object, b: object, where: str) -> None:
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.shape == b.shape, where
        np.testing.assert_array_equal(b, a, err_msg=where)
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            _assert_equal(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_equal(x, y, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert sorted(a) == sorted(b), where
        for key in a:
            _assert_equal(a[key], b[key], f"{where}[{key}]")
    else:
        assert a == b, where


def test_round_trip_is_exact(written: Path, tape: T32) -> None:
    back = read_t32(written)
    for f in dataclasses.fields(T32):
        if f.name != "provenance":
            _assert_equal(getattr(tape, f.name), getattr(back, f.name), f.name)
    for key, value in tape.provenance.items():
        assert back.provenance[key] == value
    assert {"tapp_version", "git_commit", "created_utc"} <= set(back.provenance)
    assert back.recycles[0].entities[1].matrix.shape == (6, 0)  # an empty partition's output
    assert back.partition("f2").names == () and back.partition("fq").names == ("q3_km",
                                                                                 "q2_km")
    assert back.recycles[1].L.flags.writeable is False
    for rc, mine in zip(back.recycles, tape.recycles, strict=True):  # named, all the same
        for name, _, _ in SYMMETRIC:
            np.testing.assert_array_equal(getattr(rc, f"{name}_factor"),
                                          getattr(mine, f"{name}_factor"), err_msg=name)
        np.testing.assert_array_equal(rc.transition_adjoint, mine.transition_adjoint)


def test_schema_attributes_groups_and_storage(written: Path, tape: T32) -> None:
    n_o = tape.n_o
    with h5py.File(written, "r") as f:
        attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f.attrs.items()}
        assert attrs["format"] == "T32" and attrs["version"] == 2
        assert (attrs["n_o"], attrs["n_p"], attrs["n_m"], attrs["n_recycles"],
                attrs["n_partitions"]) == (n_o, 6, 3, 3, 7)
        assert attrs["epoch"] == "2026-03-10T12:00:00.000000"
        assert attrs["deck_source"] == "deck.toml" and attrs["t13_iden"] == "SYNTHETIC"
        assert [k.decode() for k in f.attrs["provenance_keys"]] == [
            "deck", "deck_source", "t13_source", "t13_iden"]
        assert sorted(f["apriori"]) == ["Lambda0_real_factor", "S0_fit_factor"]
        assert sorted(f["recycles/2"]) == sorted(
            [f"{name}_factor" for name, _, _ in SYMMETRIC]
            + ["B", "L", "entities", "transition", "transition_adjoint"])
        for name, what, _ in SYMMETRIC:
            ds = f[f"recycles/2/{name}_factor"]
            assert ds.shape == (tr_size(n_o),), name
            assert (ds.attrs["packing"], ds.attrs["order"], ds.attrs["form"]) == (
                b"TR", n_o, b"factor"), name
            assert ds.attrs["units"] == {"normal": b"1/u_b", "covariance": b"u_b"}[what], name
            # the upper triangle of the factor by rows, as stored
            np.testing.assert_array_equal(
                ds[()], upper_by_rows(getattr(tape.recycles[1], f"{name}_factor")))
        assert f["apriori/Lambda0_real_factor"].attrs["units"] == b"u_b"
        assert f["recycles/2/transition_adjoint"].shape == (n_o, n_o)
        assert f["recycles/2/transition_adjoint"].attrs["units"] == b"u_b/u_a"
        assert f["recycles/2/L"].shape == (n_o, n_o) and f["recycles/2/B"].shape == (3, n_o)
        assert f["recycles/info"].shape == (3, 6)
        np.testing.assert_array_equal(f["recycles/k"][()], [2, 4, 6])
        ent = f["recycles/3/entities/1"]
        assert ent.attrs["command"] == b"I; 0,-,pk; 1,2,fp"
        assert list(ent["cols"].asstr()[()]) == list(tape.system_names["fit"][:6])
        assert sorted(f["recycles/3/entities"]) == ["1", "3", "4"]
        assert list(f["partitions/names"].asstr()[()][:6]) == list(tape.parameters.name[:6])
        assert sorted(f["systems"]) == ["common", "fit", "real"]
        datasets: list[str] = []
        f.visititems(lambda name, obj: datasets.append(name) if isinstance(obj, h5py.Dataset)
                     else None)
        for name in datasets:
            ds = f[name]
            assert ds.fletcher32 and ds.chunks and "units" in ds.attrs, name
    assert sorted(verify(written)) == sorted(datasets)
    assert [p.name for p in written.parent.iterdir()] == ["run.t32.h5"]  # no temporary
    assert written.stat().st_mode & 0o777 == 0o644


# ---------------------------------------------------------------------------------------------
# Validation in memory: the writer refuses, naming the dataset, and writes nothing
# ---------------------------------------------------------------------------------------------


def _lower(m: np.ndarray) -> np.ndarray:
    """A factor with a small entry below its diagonal: not upper triangular."""
    out = m.copy()
    out[1, 0] = 1e-6 * out[0, 0]
    return out


def _neg_diag(m: np.ndarray) -> np.ndarray:
    out = m.copy()
    out[2, 2] = -1.0
    return out


BAD_TAPES = [
    (lambda t: dataclasses.replace(t, n_p=0), "attrs/n_p"),
    (lambda t: dataclasses.replace(t, miss_unit=("km",)), "miss/unit"),
    (lambda t: dataclasses.replace(t, systems={"fit": t.systems["fit"]}), "systems"),
    (lambda t: dataclasses.replace(t, systems={**t.systems, "fit": t.systems["fit"][:, :3]}),
     "systems/fit/chain"),
    (lambda t: dataclasses.replace(t, system_names={**t.system_names, "real": ("x_km",)}),
     "systems/real/names"),
    (lambda t: dataclasses.replace(t, partitions=(*t.partitions, T32Partition(
        "fx", "fit", 3, 10, t.system_names["fit"][3:10]))), "partitions/tail[7]"),
    (lambda t: dataclasses.replace(t, partitions=(*t.partitions, T32Partition(
        "pk", "standard", 0, 1, ("x_km",)))), "partitions/name[7]"),
    (lambda t: dataclasses.replace(t, partitions=(*t.partitions, T32Partition(
        "bogus", "other", 0, 1, ("x_km",)))), "partitions/system[7]"),
    (lambda t: dataclasses.replace(t, partitions=(*t.partitions, T32Partition(
        "fq2", "fit", 6, 8, ("q1_km", "q2_km")))), "partitions/names[7]"),
    (lambda t: dataclasses.replace(t, S0_fit_factor=_neg_diag(t.S0_fit_factor)),
     "apriori/S0_fit_factor"),
    (lambda t: dataclasses.replace(t, Lambda0_real_factor=t.Lambda0_real_factor[:4]),
     "apriori/Lambda0_real_factor"),
    (lambda t: dataclasses.replace(t, Lambda0_real_factor=_lower(t.Lambda0_real_factor)),
     "apriori/Lambda0_real_factor"),
    (lambda t: _recycle(t, 0, Lambda_fit_factor=_lower(t.recycles[0].Lambda_fit_factor)),
     "recycles/1/Lambda_fit_factor"),
    (lambda t: _recycle(t, 1, Lambda_real_factor=_neg_diag(t.recycles[1].Lambda_real_factor)),
     "recycles/2/Lambda_real_factor"),
    (lambda t: _recycle(t, 2, Sigma_factor=np.full_like(t.recycles[2].Sigma_factor, np.nan)),
     "recycles/3/Sigma_factor"),
    (lambda t: _recycle(t, 0, J_factor=_lower(t.recycles[0].J_factor)), "recycles/1/J_factor"),
    # the matrix in place of its factor, by mistake: symmetric, not upper triangular
    (lambda t: _recycle(t, 2, Jt_factor=t.recycles[2].Jt), "recycles/3/Jt_factor"),
    (lambda t: _recycle(t, 1, S_fit_factor=_neg_diag(t.recycles[1].S_fit_factor)),
     "recycles/2/S_fit_factor"),
    (lambda t: _recycle(t, 0, L=t.recycles[0].L[:, :2]), "recycles/1/L"),
    (lambda t: _recycle(t, 0, B=t.recycles[0].B.T), "recycles/1/B"),
    (lambda t: _recycle(t, 0, transition=np.full((9, 9), np.inf)), "recycles/1/transition"),
    (lambda t: _recycle(t, 1, transition_adjoint=np.full((9, 9), np.nan)),
     "recycles/2/transition_adjoint"),
    (lambda t: _recycle(t, 2, transition_adjoint=t.recycles[2].transition_adjoint[:8]),
     "recycles/3/transition_adjoint"),
    (lambda t: _recycle(t, 0, info=np.zeros(5)), "recycles/info"),
    (lambda t: _recycle(t, 1, number=5), "recycles/number"),
    (lambda t: _recycle(t, 1, k=2), "recycles/k"),
    (lambda t: _recycle(t, 1, l=1), "recycles/l"),
    (lambda t: _recycle(t, 0, j=3), "recycles/j"),  # j = k is allowed (an epoch at t_k)
    (lambda t: _recycle(t, 2, t_l_s=1.0), "recycles/t_l_s"),
    (lambda t: _recycle(t, 0, entities=t.recycles[0].entities[::-1]), "recycles/1/entities"),
    (lambda t: _recycle(t, 0, entities=(T32Entity(1, "I; 0,-,pk; 1,2,fp", "", ("a",),
                                                  ("b", "c"), np.zeros((2, 2))),)),
     "recycles/1/entities/1/matrix"),
    (lambda t: _recycle(t, 0, entities=(T32Entity(2, " ", "", (), (), np.zeros((0, 0))),)),
     "recycles/1/entities/2.attrs/command"),
    (lambda t: dataclasses.replace(t, provenance={"format": "T13"}), "attrs/format"),
]


@pytest.mark.parametrize(("make", "dataset"), BAD_TAPES)
def test_writer_refuses_an_invalid_tape_naming_the_dataset(tmp_path: Path, tape: T32, make,
                                                           dataset: str) -> None:
    with pytest.raises(TapeError) as err:
        write_t32(tmp_path / "bad.t32.h5", make(tape))
    assert str(err.value).startswith(f"{tmp_path / 'bad.t32.h5'}: {dataset}: expected"), \
        str(err.value)
    assert list(tmp_path.iterdir()) == []


def test_messages_say_what_was_expected_and_got(tape: T32) -> None:
    bad = _recycle(tape, 0, Lambda_fit_factor=_lower(tape.recycles[0].Lambda_fit_factor))
    with pytest.raises(TapeError, match=r"^T32: recycles/1/Lambda_fit_factor: expected an "
                                        r"upper-triangular factor \(zero below the "
                                        r"diagonal\)$"):
        t32.validate(bad)
    bad = _recycle(tape, 1, Sigma_factor=_neg_diag(tape.recycles[1].Sigma_factor))
    with pytest.raises(TapeError, match=r"^T32: recycles/2/Sigma_factor: expected a factor "
                                        r"with a non-negative diagonal \(got -1 in row 2\)$"):
        t32.validate(bad)
    bad = dataclasses.replace(tape, partitions=(*tape.partitions, T32Partition(
        "fx", "fit", 3, 10, ())))
    with pytest.raises(TapeError, match=r"partitions/tail\[7\]: expected 0 <= tail <= head <= "
                                        r"9 \(rows of the fit system\) for fx \(got tail = 3, "
                                        r"head = 10\)"):
        t32.validate(bad)


# ---------------------------------------------------------------------------------------------
# Validation on reading a file
# ---------------------------------------------------------------------------------------------


def _replace(f: h5py.File, name: str, data, *, text: bool = False) -> None:
    """Replace a dataset by ``data``, checksummed as the writer does, keeping its attrs."""
    attrs = dict(f[name].attrs)
    del f[name]
    parent, _, leaf = name.rpartition("/")
    if text:
        hdf5io.write_strings(f[parent], leaf, data)
    else:
        hdf5io.write_numbers(f[parent] if parent else f, leaf, np.asarray(data), "")
    f[name].attrs.update(attrs)


def _full_factor(f: h5py.File, name: str, *, lower: bool) -> None:
    """Store a TR-packed factor with "full" packing (n² entries), with (``lower``) a non-zero
    entry (1, 0) below its diagonal."""
    n = int(f[name].attrs["order"])
    rows, cols = np.triu_indices(n)
    full = np.zeros((n, n))
    full[rows, cols] = f[name][()]
    if lower:
        full[1, 0] = 1e-6 * full[0, 0]
    _replace(f, name, full.reshape(n * n))
    f[name].attrs["packing"] = "full"


def _plain(f: h5py.File, name: str) -> None:
    data = f[name][()]
    del f[name]
    f[name] = data


BAD_FILES = [
    (lambda f: f.attrs.__setitem__("format", "T13"), "attrs/format"),
    (lambda f: f.attrs.__setitem__("version", 3), "attrs/version"),
    (lambda f: f.attrs.__setitem__("version", 0), "attrs/version"),
    (lambda f: f.attrs.__setitem__("n_o", 8), "attrs/n_o"),
    (lambda f: f.attrs.__delitem__("n_recycles"), "attrs/n_recycles"),
    (lambda f: f.__delitem__("recycles/2/L"), "recycles/2/L"),
    (lambda f: _replace(f, "recycles/number", [1, 3, 2]), "recycles/number"),
    (lambda f: _replace(f, "recycles/k", [2, 6, 4]), "recycles/k"),
    (lambda f: _replace(f, "recycles/t_s", [1200.0, np.nan, 3600.0]), "recycles/t_l_s"),
    (lambda f: _replace(f, "recycles/info", np.zeros((3, 5))), "recycles/info"),
    (lambda f: _replace(f, "recycles/1/S_fit_factor",
                        -np.abs(f["recycles/1/S_fit_factor"][()])), "recycles/1/S_fit_factor"),
    (lambda f: _replace(f, "recycles/2/Jt_factor", f["recycles/2/Jt_factor"][()][:-1]),
     "recycles/2/Jt_factor"),
    (lambda f: _replace(f, "recycles/3/Lambda_real_factor",
                        np.full(f["recycles/3/Lambda_real_factor"].shape, np.inf)),
     "recycles/3/Lambda_real_factor"),
    # a Σ scaled by 1e300 made tapp guide fail in LAPACK: numbers are bounded by 1e60
    (lambda f: _replace(f, "recycles/1/Sigma_factor", 1e300 * f["recycles/1/Sigma_factor"][()]),
     "recycles/1/Sigma_factor"),
    (lambda f: _replace(f, "recycles/2/B", -1e61 * np.ones(f["recycles/2/B"].shape)),
     "recycles/2/B"),
    (lambda f: f.__delitem__("recycles/2/Sigma_factor"), "recycles/2/Sigma_factor"),
    (lambda f: f.__delitem__("recycles/3/transition_adjoint"), "recycles/3/transition_adjoint"),
    (lambda f: _replace(f, "recycles/1/transition_adjoint", np.zeros((9, 8))),
     "recycles/1/transition_adjoint"),
    (lambda f: _full_factor(f, "recycles/2/J_factor", lower=True), "recycles/2/J_factor"),
    (lambda f: _replace(f, "recycles/1/entities/4/matrix", np.zeros((8, 7))),
     "recycles/1/entities/4/matrix"),
    (lambda f: f.move("recycles/1/entities/4", "recycles/1/entities/x"), "recycles/1/entities"),
    (lambda f: _replace(f, "systems/fit/chain", np.eye(8)), "systems/fit/chain"),
    (lambda f: _replace(f, "partitions/head", [6, 6, 8, 9, 9, 9, 4]), "partitions/names"),
    (lambda f: _replace(f, "partitions/head", [6, 6, 8, 9, 9, 10, 1]), "partitions/tail[5]"),
    (lambda f: _replace(f, "partitions/system", ["standard", "fit", "fit", "fit", "fit",
                                                 "real", "common"], text=True),
     "partitions/names[6]"),
    (lambda f: _replace(f, "apriori/S0_fit_factor", f["apriori/S0_fit_factor"][()][None]),
     "apriori/S0_fit_factor"),
    (lambda f: f["apriori/S0_fit_factor"].attrs.__setitem__("packing", "LT"),
     "apriori/S0_fit_factor.attrs/packing"),
    (lambda f: _full_factor(f, "apriori/Lambda0_real_factor", lower=True),
     "apriori/Lambda0_real_factor"),
    (lambda f: _plain(f, "recycles/2/B"), "recycles/2/B"),
    (lambda f: f["recycles/2/entities/1"].attrs.__setitem__("command", np.bytes_(b"I;\xff")),
     "recycles/2/entities/1.attrs/command"),
]


@pytest.mark.parametrize(("edit", "dataset"), BAD_FILES)
def test_reader_rejects_a_bad_tape_naming_the_dataset(written: Path, edit, dataset: str
                                                      ) -> None:
    with h5py.File(written, "r+") as f:
        edit(f)
    with pytest.raises(TapeError) as err:
        read_t32(written)
    assert str(err.value).startswith(f"{written}: {dataset}: expected"), str(err.value)


def test_missing_and_truncated_files(tmp_path: Path, written: Path) -> None:
    with pytest.raises(InputError, match="file: expected an existing T32 tape file"):
        read_t32(tmp_path / "none.h5")
    data = written.read_bytes()
    written.write_bytes(data[: len(data) // 2])
    with pytest.raises(TapeError, match=f"{written}: file: expected a readable HDF5 file"):
        read_t32(written)


# ---------------------------------------------------------------------------------------------
# Corruption, atomic writes
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("dataset", ["recycles/1/S_fit_factor", "recycles/2/entities/1/matrix",
                                     "partitions/names", "recycles/k", "systems/fit/chain",
                                     "apriori/Lambda0_real_factor",
                                     "recycles/3/transition_adjoint"])
def test_a_flipped_byte_fails_its_checksum(written: Path, dataset: str) -> None:
    with h5py.File(written, "r") as f:
        offset = f[dataset].id.get_chunk_info(0).byte_offset
    with written.open("r+b") as fh:
        fh.seek(offset + 5)
        byte = fh.read(1)[0]
        fh.seek(offset + 5)
        fh.write(bytes([byte ^ 0x10]))
    expected = (f"{written}: {dataset}: expected data matching its Fletcher-32 checksum "
                "(got checksum mismatch (corrupt file))")
    for read in (read_t32, verify, describe):
        with pytest.raises(TapeError) as err:
            read(written)
        assert str(err.value) == expected


def test_a_failed_write_leaves_no_temporary_and_the_old_tape(tmp_path: Path, tape: T32,
                                                             monkeypatch) -> None:
    path = write_t32(tmp_path / "run.t32.h5", tape)
    before = path.read_bytes()
    calls = []

    def failing(*args, **kwargs):
        calls.append(args[1])
        if len(calls) == 5:
            raise RuntimeError("simulated failure in the middle of the write")
        return original(*args, **kwargs)

    original = hdf5io.write_packed
    monkeypatch.setattr(hdf5io, "write_packed", failing)
    other = dataclasses.replace(tape, iden="OTHER")
    with pytest.raises(RuntimeError, match="simulated failure"):
        write_t32(path, other)
    assert [p.name for p in tmp_path.iterdir()] == ["run.t32.h5"]
    assert path.read_bytes() == before
    calls.clear()
    with pytest.raises(RuntimeError, match="simulated failure"):
        write_t32(tmp_path / "new.t32.h5", other)
    assert [p.name for p in tmp_path.iterdir()] == ["run.t32.h5"]


def test_file_writer_validates_first_and_writes_a_complete_tape(tmp_path: Path, tape: T32
                                                                ) -> None:
    with pytest.raises(TapeError, match=r"^T32: recycles/k: expected"):
        t32_hdf5.t32_file_writer(_recycle(tape, 1, k=2))
    writer = t32_hdf5.t32_file_writer(tape)
    writer(tmp_path / "plain.h5")
    assert read_t32(tmp_path / "plain.h5").recycles[2].k == 6


def test_writer_stamps_its_own_provenance(tmp_path: Path, tape: T32) -> None:
    again = dataclasses.replace(tape, provenance={**tape.provenance, "tapp_version": "0.0.1",
                                                  "created_utc": "yesterday"})
    back = read_t32(write_t32(tmp_path / "x.h5", again))
    assert back.provenance["tapp_version"] != "0.0.1"
    assert back.provenance["created_utc"] != "yesterday"


# ---------------------------------------------------------------------------------------------
# Summary
# ---------------------------------------------------------------------------------------------


def test_describe_and_text_summary(written: Path, tape: T32) -> None:
    info = describe(written)
    assert info["format"] == "T32" and info["version"] == 2
    assert info["dimensions"] == {"n_o": 9, "n_p": 6, "n_m": 3, "n_recycles": 3,
                                  "n_partitions": 7}
    assert info["verified_datasets"] == len(verify(written))
    fq = next(p for p in info["partitions"] if p["name"] == "fq")
    assert fq == {"name": "fq", "system": "fit", "tail": 6, "head": 8,
                  "names": ["q3_km", "q2_km"]}
    rc = info["recycles"][1]
    assert (rc["number"], rc["k"], rc["l"], rc["t_s"]) == (2, 4, 2, 2400.0)
    assert rc["utc"] == "2026-03-10T12:40:00.000"
    lam_fit, lam_real = tape.recycles[1].Lambda_fit, tape.recycles[1].Lambda_real
    assert rc["sigma_position_km"]["fit"] == pytest.approx(math.sqrt(np.trace(lam_fit[:3, :3])))
    assert rc["sigma_velocity_km_s"]["real"] == pytest.approx(
        math.sqrt(np.trace(lam_real[3:6, 3:6])))
    assert [e["command"] for e in rc["entities"]] == [
        "I; 0,-,pk; 1,2,fp", "I; 0,-,pk; 1,2,f2", "J; 1,2,f1; 1,2,f1"]
    assert "deck" not in info["provenance"] and info["provenance"]["t13_iden"] == "SYNTHETIC"
    text = format_t32_summary(info)
    for expected in ("T32 v2  iden SYNTHETIC", "fq    fit       rows 6..7      q3_km, q2_km",
                     "ω  1: I; 0,-,pk; 1,2,fp  (partials pk wrt fp@recycle)  6 x 6",
                     "2026-03-10T12:40:00.000", "from deck.toml and run.t13.h5"):
        assert expected in text, expected
    assert f"{rc['sigma_position_km']['fit']:10.4g}" in text


# ---------------------------------------------------------------------------------------------
# Version 1 (the matrices themselves) still read
# ---------------------------------------------------------------------------------------------

FACTORED = {name for name, _, _ in SYMMETRIC}


def test_version_1_is_read_with_a_warning_as_factors(tmp_path: Path, tape: T32) -> None:
    """The matrices of a version-1 tape come back as factors whose Grams are those matrices
    (to REFACTORED on the scale sqrt(M_aa M_bb)), each transition's adjoint as its inverse
    transpose (to SOLVED of the closed form), everything else as it was."""
    path = write_t32_version_1(tmp_path / "v1.t32.h5", tape)
    with h5py.File(path, "r") as f:
        assert f.attrs["version"] == 1
        assert sorted(f["apriori"]) == ["Lambda0_real", "S0_fit"]
        assert "transition_adjoint" not in f["recycles/1"] and "Sigma_factor" not in f[
            "recycles/1"]
        stored = {name: symmetric_from_rows(f[name][()], N_O) for name in t32_matrices(tape)}
    with pytest.warns(UserWarning, match=T32_V1_WARNING):
        back = read_t32(path)
    factors = t32_matrices(back)
    assert sorted(factors) == sorted(stored)
    for name, m in stored.items():
        k = factors[name][0]
        assert not np.any(np.tril(k, -1)) and np.all(np.diagonal(k) >= 0), name
        scaled_close(gram(k), m, REFACTORED)
    for rc, mine in zip(back.recycles, tape.recycles, strict=True):
        np.testing.assert_array_equal(rc.transition, mine.transition)
        scale = np.max(np.abs(mine.transition_adjoint))
        err = np.max(np.abs(rc.transition_adjoint - mine.transition_adjoint)) / scale
        assert err <= SOLVED, (rc.number, err)
        residual = np.max(np.abs(rc.transition_adjoint.T @ rc.transition - np.eye(N_O)))
        assert residual <= SOLVED, (rc.number, residual)  # (T⁻ᵀ)ᵀ T = I
        for f in dataclasses.fields(rc):
            if f.name.removesuffix("_factor") not in FACTORED and f.name != "transition_adjoint":
                _assert_equal(getattr(mine, f.name), getattr(rc, f.name), f.name)
    for f in dataclasses.fields(T32):
        if f.name not in ("S0_fit_factor", "Lambda0_real_factor", "recycles", "provenance"):
            _assert_equal(getattr(tape, f.name), getattr(back, f.name), f.name)
    assert {"apriori/S0_fit", "recycles/3/Sigma"} <= set(verify(path))  # every dataset read


def _full_symmetric(f: h5py.File, name: str, skew: float) -> None:
    """Store a TR-packed symmetric matrix with "full" packing, entry (0, 1) times 1 + skew."""
    n = int(f[name].attrs["order"])
    m = symmetric_from_rows(f[name][()], n)
    m[0, 1] *= 1.0 + skew
    _replace(f, name, m.reshape(n * n))
    f[name].attrs["packing"] = "full"


def _diagonal_entry(f: h5py.File, name: str, row: int, value: float) -> None:
    n = int(f[name].attrs["order"])
    data = f[name][()]
    data[tr_size(n) - tr_size(n - row)] = value  # entry (row, row), the upper triangle by rows
    _replace(f, name, data)


BAD_VERSION_1 = [
    (lambda f: _full_symmetric(f, "recycles/1/Lambda_fit", 1e-6),
     r"recycles/1/Lambda_fit: expected symmetric matrix \(relative asymmetry <= 1e-12\)"),
    (lambda f: _diagonal_entry(f, "apriori/S0_fit", 2, -1.0),
     r"apriori/S0_fit: expected a non-negative diagonal \(matrix\) \(got -1, row 2\)"),
    (lambda f: _replace(f, "recycles/3/Lambda_real", np.full(f["recycles/3/Lambda_real"].shape,
                                                             np.inf)),
     r"recycles/3/Lambda_real: expected finite values"),
    (lambda f: _replace(f, "recycles/2/transition", np.zeros((9, 9))),
     r"recycles/2/transition: expected an invertible transition"),
    (lambda f: f.__delitem__("recycles/2/J"), r"recycles/2/J: expected this dataset present"),
    # symmetric with a non-negative diagonal, and a correlation of 1.5: guide clipped the
    # negative eigenvalue and exited 0
    (lambda f: _correlated(f, "apriori/Lambda0_real", 1.5),
     r"apriori/Lambda0_real: expected a positive semi-definite matrix \(to 0.001 of its "
     r"scale\)"),
    (lambda f: _diagonal_entry(f, "recycles/1/Lambda_real", 0, 1e121),
     r"recycles/1/Lambda_real: expected finite values of magnitude <= 1e\+120"),
]


def _correlated(f: h5py.File, name: str, rho: float) -> None:
    """Entry (0, 1) of a TR-packed symmetric matrix set to ``rho`` √(M_00 M_11)."""
    n = int(f[name].attrs["order"])
    m = symmetric_from_rows(f[name][()], n)
    m[0, 1] = m[1, 0] = rho * np.sqrt(m[0, 0] * m[1, 1])
    _replace(f, name, upper_by_rows(m))


@pytest.mark.parametrize(("edit", "message"), BAD_VERSION_1)
def test_version_1_matrices_are_checked_as_version_1_did(tmp_path: Path, tape: T32, edit,
                                                         message: str) -> None:
    path = write_t32_version_1(tmp_path / "v1.t32.h5", tape)
    with h5py.File(path, "r+") as f:
        edit(f)
    with pytest.warns(UserWarning, match=T32_V1_WARNING), pytest.raises(
            TapeError, match=f"^{re.escape(str(path))}: {message}"):
        read_t32(path)


def _near_null_sigma(tape: T32, row: int, relative: float) -> np.ndarray:
    """Σ of recycle 1 with its row and column ``row`` cancelled to zero (a parameter the data
    do not reach), and its variance the rounding ``relative`` times Λ̄'_row,row."""
    rc = tape.recycles[0]
    k = rc.Sigma_factor.copy()
    k[:, row] = 0.0
    sigma = gram(k)
    sigma[row, row] = relative * rc.Lambda_real[row, row]
    return sigma


def test_version_1_sigma_may_carry_a_rounding_negative_variance_and_no_more(
        tmp_path: Path, tape: T32) -> None:
    """Σ <= Λ̄' in exact arithmetic: on a version-1 tape Σ_ii down to −1e-6 Λ̄'_ii is rounding
    of a variance that cancels (measured −1.5e-9 with a station switched off), read as a
    factor whose Gram has that variance 0 and the rest of Σ; below is refused."""
    row = 4
    lam = tape.recycles[0].Lambda_real
    rounding = _near_null_sigma(tape, row, -ROUNDING)
    path = write_t32_version_1(tmp_path / "ok.t32.h5", tape, {"recycles/1/Sigma": rounding})
    with pytest.warns(UserWarning, match=T32_V1_WARNING):
        sigma = read_t32(path).recycles[0].Sigma
    assert 0.0 <= sigma[row, row] <= ROUNDING * lam[row, row]
    d = np.sqrt(np.diagonal(lam))
    err = np.max(np.abs(sigma - rounding) / np.outer(d, d))  # on the scale of Λ̄'
    assert err <= ROUNDING + REFACTORED, err
    path = write_t32_version_1(tmp_path / "bad.t32.h5", tape,
                            {"recycles/1/Sigma": _near_null_sigma(tape, row, -1e-3)})
    with pytest.warns(UserWarning, match=T32_V1_WARNING), pytest.raises(
            TapeError, match=r"recycles/1/Sigma: expected a non-negative diagonal \(matrix\) "
                             rf"\(got [0-9.e-]+, row {row}\)"):
        read_t32(path)


def test_an_adjoint_that_is_not_the_transitions_inverse_transpose_is_refused(tape: T32
                                                                             ) -> None:
    rc = tape.recycles[0]
    with pytest.raises(TapeError, match=r"recycles/1/transition_adjoint: expected the inverse "
                                        r"transpose of the transition"):
        t32.validate(_recycle(tape, 0, transition_adjoint=7.0 * np.eye(rc.L.shape[0])))
    t32.validate(tape)


def test_a_factor_has_no_rounding_floor(tape: T32) -> None:
    """Version 2: Σ is the Gram of its factor, non-negative by construction; a factor's
    diagonal below zero, however small, is refused."""
    k = tape.recycles[0].Sigma_factor.copy()
    k[4, 4] = -1e-300
    with pytest.raises(TapeError, match=r"recycles/1/Sigma_factor: expected a factor with a "
                                        r"non-negative diagonal"):
        t32.validate(_recycle(tape, 0, Sigma_factor=k))
