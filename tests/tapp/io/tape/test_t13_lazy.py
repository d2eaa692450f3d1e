"""The lazy pair reader (open_t13) and its in-memory twin (memory_pairs): same header, same
blocks (the pair factors packed "TR"), checks of each block when it is read, memory bounded by
the block."""

from __future__ import annotations

import dataclasses
import tracemalloc
from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.io.tape import hdf5io, memory_pairs, t13, t13_hdf5
from tapp.io.tape.packing import pack_tr, tr_diagonal, tr_size
from tapp.io.tape.t13 import T13, PairBlock, T13Header
from tapp.io.tape.t13_hdf5 import open_t13, write_t13
from tapp.tracking.simulate import simulate
from tests.tapp.io.tape.legacy import (
    gram,
    refactored_tol,
    t13_read_warnings,
    upper_from_rows,
    write_t13_version,
)
from tests.tapp.io.tape.synthetic import t13_tape
from tests.tapp.tracking.helpers import leo_scenario, scaled_close

BLOCK_FIELDS = [f.name for f in dataclasses.fields(PairBlock)]
# A normal matrix of a version-1 tape against the Gram of the factor read from it, on the
# scale sqrt(J_aa J_bb): n_o² ε, n_o = 23 (legacy.refactored_tol).
REFACTORED = refactored_tol(23)


@pytest.fixture(scope="module")
def tape() -> T13:
    return simulate(leo_scenario(times={"epochs": [3600.0]}), raw=True).tape


def _assert_same_block(a: PairBlock, b: PairBlock) -> None:
    for name in BLOCK_FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if x is None or y is None:
            assert x is None and y is None, name
            continue
        assert x.dtype == y.dtype and x.shape == y.shape, name
        np.testing.assert_array_equal(x, y, err_msg=name)


def _assert_same_header(a: T13Header, b: T13Header) -> None:
    assert a.iden == b.iden and a.epoch == b.epoch and a.n_p == b.n_p
    assert type(a) is T13Header and type(b) is T13Header  # no raw rows, no factors
    for group in ("parameters", "stations", "miss", "records", "pairs", "passes"):
        for f in dataclasses.fields(getattr(a, group)):
            x, y = getattr(getattr(a, group), f.name), getattr(getattr(b, group), f.name)
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y, err_msg=f"{group}/{f.name}")
            else:
                assert x == y, f"{group}/{f.name}"
    for name in ("R", "Rt", "Rt_parts"):
        assert getattr(a.pairs, name) is None and getattr(b.pairs, name) is None
    for key, value in b.provenance.items():
        assert a.provenance[key] == value


@pytest.mark.parametrize("version", [3, t13.VERSION])
@pytest.mark.parametrize("packing", ["TR", "full"])
def test_file_and_memory_give_identical_headers_and_blocks(tmp_path: Path, tape: T13,
                                                           packing: str, version: int) -> None:
    path = write_t13_version(tmp_path / "run.t13.h5", tape, version, packing)
    mem = memory_pairs(tape)
    with open_t13(path) as f:
        assert f.packing == packing and f.has_parts and f.version == version
        assert f.names == ("pairs/R", "pairs/Rt", "pairs/Rt_parts")
        _assert_same_header(f.header, mem.header)
        n_it = f.header.n_it
        for k_first in range(1, n_it + 1):
            for k_last in range(k_first, n_it + 1):
                block = f.pair_block(k_first, k_last)
                _assert_same_block(block, mem.pair_block(k_first, k_last))
                assert np.all((block.k >= k_first) & (block.k <= k_last))
        whole = f.pair_block(1, n_it)
    # the block of every record is the tape's pairs, factors packed TR
    np.testing.assert_array_equal(whole.k, tape.pairs.k)
    for name in ("R", "Rt", "Rt_parts"):
        np.testing.assert_array_equal(getattr(whole, name), pack_tr(getattr(tape.pairs, name)),
                                      err_msg=name)
    assert whole.R.shape == (tape.pairs.k.size, tr_size(tape.n_o))
    assert whole.Rt_parts.shape == (tape.pairs.k.size, 3, tr_size(tape.n_o))


def test_blocks_cover_the_records_in_order_with_whole_records(tmp_path: Path) -> None:
    tape = t13_tape(np.random.default_rng(11), n_it=9, n_ts=4)
    path = write_t13(tmp_path / "syn.h5", tape)
    mem = memory_pairs(tape)
    with open_t13(path) as f:
        for max_pairs in (1, 3, 5, 100, None):
            blocks = list(f.blocks(max_pairs))
            for a, b in zip(blocks, mem.blocks(max_pairs), strict=True):
                _assert_same_block(a, b)
            np.testing.assert_array_equal(np.concatenate([b.k for b in blocks]), tape.pairs.k)
            for b in blocks:
                assert b.k.size <= (max_pairs or 10**9) or np.unique(b.k).size == 1
            ends = [b.k for b in blocks if b.k.size]
            assert all(x[-1] < y[0] for x, y in zip(ends, ends[1:], strict=False))
        with pytest.raises(InputError, match="max_pairs"):
            next(f.blocks(0))


@pytest.mark.parametrize("k_range", [(0, 1), (2, 1), (1, 99), (1.0, 2)])
def test_bad_record_ranges_are_refused_alike(tmp_path: Path, tape: T13, k_range) -> None:
    mem = memory_pairs(tape)
    with open_t13(write_t13(tmp_path / "run.h5", tape)) as f:
        for source in (f, mem):
            with pytest.raises(InputError, match=r"k_first, k_last: expected record indices "
                                                 r"1 <= k_first <= k_last <= 3"):
                source.pair_block(*k_range)


def test_a_record_without_pairs_gives_an_empty_block(tmp_path: Path) -> None:
    tape = t13_tape(np.random.default_rng(2), n_it=5, n_ts=2, skip=0.0)
    keep = tape.pairs.k != 3
    p = tape.pairs
    tape = dataclasses.replace(tape, pairs=t13.TapePairs(
        p.k[keep], p.station[keep], p.n_obs[keep], p.R[keep], p.Rt[keep],
        p.Rt_parts[keep]))
    with open_t13(write_t13(tmp_path / "gap.h5", tape)) as f:
        block = f.pair_block(3, 3)
        _assert_same_block(block, memory_pairs(tape).pair_block(3, 3))
    assert block.k.size == 0 and block.R.shape == (0, tr_size(tape.n_o))
    assert block.Rt.shape == (0, tr_size(tape.n_o))
    assert block.Rt_parts.shape == (0, 3, tr_size(tape.n_o))


@pytest.mark.parametrize(("version", "dataset", "message"), [
    (3, "pairs/R", r"expected factors with a non-negative diagonal \(the canonical sign of a "
                   r"QR\) \(got -1 in pair {pair}, row 2\)"),
    (2, "pairs/dJ", r"expected a non-negative diagonal \(normal matrices\) \(got -1 in pair "
                    r"{pair}, row 2\)"),
])
def test_a_bad_matrix_fails_only_the_block_that_reads_it(tmp_path: Path, tape: T13,
                                                         version: int, dataset: str,
                                                         message: str) -> None:
    path = write_t13_version(tmp_path / "run.h5", tape, version)
    bad_pair = int(np.flatnonzero(tape.pairs.k == 3)[0])
    message = f"run.h5: {dataset}: " + message.format(pair=bad_pair)

    def negative(f: h5py.File) -> None:
        data = f[dataset][()]
        data[bad_pair, tr_diagonal(tape.n_o)[2]] = -1.0
        attrs = dict(f[dataset].attrs)
        del f[dataset]
        hdf5io.write_numbers(f["pairs"], dataset.removeprefix("pairs/"), data, "")
        f[dataset].attrs.update(attrs)

    with h5py.File(path, "r+") as f:
        negative(f)
    with t13_read_warnings(version), open_t13(path) as f:  # the header is fine
        f.pair_block(1, 2)
        with pytest.raises(TapeError, match=message):
            f.pair_block(2, 3)
    with t13_read_warnings(version), pytest.raises(TapeError, match=message):
        t13_hdf5.read_t13(path)


def test_a_full_factor_non_zero_below_its_diagonal_fails_its_block(tmp_path: Path, tape: T13
                                                                   ) -> None:
    n = tape.n_o
    path = write_t13(tmp_path / "full.h5", tape, packing="full")
    with h5py.File(path, "r+") as f:
        ds = f["pairs/Rt"]
        row = ds[5]
        assert row[n] == 0.0
        row[n] = 1e-6 * row[0]  # entry (1, 0) of pair 5 (record 3)
        ds[5] = row
    with open_t13(path) as f:
        f.pair_block(1, 2)
        with pytest.raises(TapeError, match=r"full.h5: pairs/Rt: expected upper-triangular "
                                            r"factors \(zero below the diagonal\) \(got .* in "
                                            r"pair 5, row 1, column 0\)$"):
            f.pair_block(3, 3)


def test_an_asymmetric_full_matrix_of_version_2_fails_its_block(tmp_path: Path, tape: T13
                                                                ) -> None:
    path = write_t13_version(tmp_path / "full.h5", tape, 2, "full")
    with h5py.File(path, "r+") as f:
        ds = f["pairs/dJt"]
        row = ds[5]
        row[1] *= 1.0 + 1e-6  # entry (0, 1) of pair 5 (record 3), not (1, 0)
        ds[5] = row
    with t13_read_warnings(2), open_t13(path) as f:
        f.pair_block(1, 2)
        with pytest.raises(TapeError, match=r"full.h5: pairs/dJt: expected symmetric normal "
                                            r"matrices .* in pair 5\)"):
            f.pair_block(3, 3)


@pytest.mark.parametrize(("version", "dataset", "message"), [
    (3, "pairs/Rt_parts", r"expected parts whose Gram matrices sum to R̃ᵀR̃ \(diagonal, "
                          r"relative difference <= 1e-10\) \(got [0-9.e-]+ in pair 5\)$"),
    (2, "pairs/dJt_parts", r"expected parts summing to pairs/dJt \(relative difference <= "
                           r"1e-10\) \(got [0-9.e-]+ in pair 5\)$"),
])
def test_parts_not_summing_fail_their_block(tmp_path: Path, tape: T13, version: int,
                                            dataset: str, message: str) -> None:
    path = write_t13_version(tmp_path / "run.h5", tape, version)
    with h5py.File(path, "r+") as f:
        ds = f[dataset]
        row = ds[5]
        row[2] *= 1.001  # the correlated part of pair 5 (record 3)
        ds[5] = row
    with t13_read_warnings(version), open_t13(path) as f:
        f.pair_block(1, 2)
        f.pair_block(3, 3, parts=False)  # the parts unread: nothing to check
        with pytest.raises(TapeError, match=f"{dataset}: {message}"):
            f.pair_block(3, 3)


def test_a_corrupt_chunk_fails_only_the_blocks_that_read_it(tmp_path: Path, tape: T13,
                                                           monkeypatch) -> None:
    monkeypatch.setattr(hdf5io, "CHUNK_BYTES", 8)  # one pair per chunk
    path = write_t13(tmp_path / "run.h5", tape)
    with h5py.File(path, "r") as f:
        assert f["pairs/R"].chunks[0] == 1
        offset = f["pairs/R"].id.get_chunk_info(5).byte_offset
    with path.open("r+b") as fh:
        fh.seek(offset + 2)
        byte = fh.read(1)[0]
        fh.seek(offset + 2)
        fh.write(bytes([byte ^ 0x01]))
    with open_t13(path) as f:
        assert f.header.pairs.k[5] == 3
        f.pair_block(1, 2)
        with pytest.raises(TapeError, match=r"run.h5: pairs/R: expected data matching its "
                                            r"Fletcher-32 checksum"):
            f.pair_block(3, 3)


def test_open_checks_the_header_and_the_stored_shapes(tmp_path: Path, tape: T13) -> None:
    path = write_t13(tmp_path / "run.h5", tape)
    with h5py.File(path, "r+") as f:
        data = f["pairs/Rt"][()][:, :-1]
        attrs = dict(f["pairs/Rt"].attrs)
        del f["pairs/Rt"]
        hdf5io.write_numbers(f["pairs"], "Rt", data, "")
        f["pairs/Rt"].attrs.update(attrs)
    with pytest.raises(TapeError, match=r"run.h5: pairs/Rt: expected shape \(6, 276\) \(TR "
                                        r"packing, order 23\) \(got \(6, 275\)\)"):
        open_t13(path)
    with pytest.raises(InputError, match="expected an existing T13 tape file"):
        open_t13(tmp_path / "none.h5")


def test_unsorted_pairs_on_a_file_are_refused_on_open(tmp_path: Path, tape: T13) -> None:
    path = write_t13(tmp_path / "run.h5", tape)
    with h5py.File(path, "r+") as f:
        f["pairs/station"][0:2] = f["pairs/station"][0:2][::-1]
    with pytest.raises(TapeError, match=r"pairs/k: expected each \(record, station\) pair once, "
                                        r"sorted by \(k, station\)"):
        open_t13(path)


def test_closed_file_and_version_1(tmp_path: Path, tape: T13) -> None:
    f = open_t13(write_t13(tmp_path / "run.h5", tape))
    with f:
        f.pair_block(1, 1)
    with pytest.raises(InputError, match="pair_block after close"):
        f.pair_block(1, 1)
    path = write_t13_version(tmp_path / "v1.h5", tape, 1)
    bare = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, Rt_parts=None))
    with t13_read_warnings(1), open_t13(path) as old:
        assert old.version == 1 and not old.has_parts
        assert old.names == ("pairs/dJ", "pairs/dJt", "pairs/dJt_parts")
        block = old.pair_block(1, 3)
    mine = memory_pairs(bare).pair_block(1, 3)
    # the same pairs; the factors those of the normal matrices the tape carries, RᵀR = dJ
    for name in ("k", "station", "n_obs"):
        np.testing.assert_array_equal(getattr(block, name), getattr(mine, name), err_msg=name)
    assert block.Rt_parts is None and mine.Rt_parts is None
    for name in ("R", "Rt"):
        packed = getattr(block, name)
        assert packed.shape == getattr(mine, name).shape, name
        assert np.all(packed[:, tr_diagonal(tape.n_o)] >= 0), name
        scaled_close(gram(upper_from_rows(packed, tape.n_o)),
                     gram(upper_from_rows(getattr(mine, name), tape.n_o)), REFACTORED)


def test_memory_pairs_validates_the_tape(tape: T13) -> None:
    bad = dataclasses.replace(tape, pairs=dataclasses.replace(
        tape.pairs, R=-tape.pairs.R))
    with pytest.raises(TapeError, match="T13: pairs/R: expected factors with a non-negative "
                                        "diagonal"):
        memory_pairs(bad)
    lower = tape.pairs.Rt_parts.copy()
    lower[1, 2, 3, 0] = 1e-300  # below the diagonal of a part's factor
    bad = dataclasses.replace(tape, pairs=dataclasses.replace(tape.pairs, Rt_parts=lower))
    with pytest.raises(TapeError, match=r"T13: pairs/Rt_parts: expected upper-triangular "
                                        r"factors \(zero below the diagonal\)"):
        memory_pairs(bad)


def test_open_reads_no_pair_matrix_and_a_block_only_its_rows(tmp_path: Path) -> None:
    """n_o = 40, 1200 pairs: 39 MB of packed factors (R, Rt, 3 parts); opening, and the
    block of two records (40 pairs), stay below a tenth of it (the case of 20,000 pairs of
    n_o = 50, 800 MB unpacked, is this scaled up)."""
    tape = t13_tape(np.random.default_rng(5), n_o=40, n_it=60, n_ts=20, skip=0.0)
    path = write_t13(tmp_path / "big.h5", tape)
    packed_bytes = tape.pairs.k.size * tr_size(40) * 8 * 5
    assert packed_bytes > 35_000_000
    tracemalloc.start()
    try:
        with open_t13(path) as f:
            _, opened = tracemalloc.get_traced_memory()
            tracemalloc.reset_peak()
            block = f.pair_block(30, 31)
            _, one_block = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert block.k.size == 40
    assert opened < packed_bytes / 10, opened
    assert one_block < packed_bytes / 10, one_block
