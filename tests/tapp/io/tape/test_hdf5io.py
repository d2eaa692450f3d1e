"""The shared dataset helper: checksummed storage of every shape, the reader's refusals,
verify, and corrupt files that fail as TapeError (never another exception, never a hang)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from tapp.errors import InputError, TapeError
from tapp.io.tape import hdf5io
from tapp.io.tape.files import verify
from tapp.io.tape.hdf5io import Reader
from tapp.io.tape.t13_hdf5 import read_t13, write_t13
from tapp.io.tape.t32_hdf5 import read_t32, write_t32
from tests.tapp.io.tape.synthetic import t13_tape, t32_tape


def _reader(path: Path) -> Reader:
    return Reader(h5py.File(path, "r"), str(path))


@pytest.mark.parametrize("data", [np.zeros((0, 3)), np.zeros((4, 0)), np.zeros(0, dtype=int),
                                  np.arange(5.0), np.ones((3, 2, 2), dtype=bool),
                                  np.arange(200_000.0).reshape(-1, 4)])
def test_every_shape_is_stored_chunked_with_a_checksum(tmp_path: Path, data: np.ndarray
                                                       ) -> None:
    path = tmp_path / "x.h5"
    with hdf5io.create(path) as f:
        hdf5io.write_numbers(f, "d", data, "km", big=data.size > 1000)
    with h5py.File(path, "r") as f:
        ds = f["d"]
        assert ds.fletcher32 and ds.chunks and ds.attrs["units"] == b"km"
        assert np.prod(ds.chunks) * data.itemsize <= max(hdf5io.CHUNK_BYTES,
                                                         data[:1].nbytes or 1)
        np.testing.assert_array_equal(ds[()], data)
    assert verify(path) == ["d"]


def test_text_round_trip_and_empty_lists(tmp_path: Path) -> None:
    path = tmp_path / "s.h5"
    with hdf5io.create(path) as f:
        hdf5io.write_strings(f, "names", ["x_km", "Δv_km_s", ""])
        hdf5io.write_strings(f, "none", [])
        hdf5io.write_attrs(f, {"title": "σ of ΔV", "kinds": ["range", "range_rate"],
                               "empty": "", "n": 3})
    r = _reader(path)
    assert r.strings("names") == ("x_km", "Δv_km_s", "") and r.strings("none") == ()
    assert r.attr("title") == "σ of ΔV" and r.attr("kinds", list) == ("range", "range_rate")
    assert r.attr("empty") == "" and r.attr("n", int) == 3
    assert r.attr("missing", default=None) is None
    r.f.close()


@pytest.mark.parametrize(("value", "kind", "expected"), [
    (-1, int, "an integer >= 0"), (True, int, "an integer >= 0"), (2.5, int, "an integer"),
    (np.nan, float, "a finite number"), ("1.0", float, "a finite number"),
    (np.bytes_(b"\xff"), str, "UTF-8 text"), (np.array([1, 2]), str, "a text"),
])
def test_attributes_of_the_wrong_kind_are_named(tmp_path: Path, value, kind, expected: str
                                                ) -> None:
    path = tmp_path / "a.h5"
    with h5py.File(path, "w") as f:
        f.attrs["x"] = value
    r = _reader(path)
    with pytest.raises(TapeError, match=rf"a.h5: attrs/x: expected {expected}"):
        r.attr("x", kind)
    r.f.close()


def test_a_surrogate_in_a_utf8_attribute_is_refused(tmp_path: Path) -> None:
    """h5py hands undecodable bytes of a variable-length UTF-8 attribute back as surrogates."""
    path = tmp_path / "v.h5"
    with h5py.File(path, "w") as f:
        f.attrs.create("note", data=np.array(b"ok\xff", dtype=h5py.string_dtype("utf-8")))
    with pytest.raises(TapeError, match=r"v.h5: attrs/note: expected UTF-8 text \(got b'ok"):
        verify(path)


def test_verify_reads_other_hdf5_files_and_refuses_missing_ones(tmp_path: Path) -> None:
    path = tmp_path / "obs.h5"
    with h5py.File(path, "w") as f:  # no checksums: read all the same
        f["g/t_s"] = np.arange(10.0)
        f["g/name"] = np.array(["a", "b"], dtype=h5py.string_dtype())
        f["scalar"] = 3.0
        f.attrs["format"] = "OBS"
    assert sorted(verify(path)) == ["g/name", "g/t_s", "scalar"]
    with pytest.raises(InputError, match="file: expected an existing tape file"):
        verify(tmp_path / "none.h5")
    path.write_bytes(b"not an HDF5 file at all")
    with pytest.raises(TapeError, match="file: expected a readable HDF5 file"):
        verify(path)


def _flip_everywhere(path: Path, step: int, stop: int, readers) -> dict[str, int]:
    """Flip one byte at offsets 0, step, ... < stop, each in a fresh copy; every reader must
    succeed or raise TapeError."""
    data = path.read_bytes()
    copy = path.with_name("flipped.h5")
    outcomes = {"ok": 0, "TapeError": 0}
    for offset in range(0, min(stop, len(data)), step):
        flipped = bytearray(data)
        flipped[offset] ^= 0x5A
        copy.write_bytes(bytes(flipped))
        for read in readers:
            try:
                read(copy)
            except TapeError:
                outcomes["TapeError"] += 1
            else:
                outcomes["ok"] += 1
    return outcomes


# (step, bytes covered): a quick sample of the metadata at the head of the file, and every
# 17th byte of the whole file (slow: HDF5 retries a metadata read that fails its checksum).
SAMPLES = [pytest.param(197, 6000, id="sample"),
           pytest.param(17, 10**9, id="whole-file", marks=pytest.mark.slow)]


@pytest.mark.parametrize(("step", "stop"), SAMPLES)
def test_flipped_bytes_in_a_t13_are_tape_errors(tmp_path: Path, step: int, stop: int) -> None:
    """Superblock, object headers, B-trees, attributes: the HDF5 1.8 formats checksum them,
    and whatever h5py raises becomes a TapeError naming the object (a byte that still reads
    is unused space)."""
    path = write_t13(tmp_path / "run.h5", t13_tape(np.random.default_rng(3)))
    outcomes = _flip_everywhere(path, step, stop, (verify, read_t13))
    assert outcomes["TapeError"] > outcomes["ok"] / 10, outcomes


@pytest.mark.parametrize(("step", "stop"), SAMPLES)
def test_flipped_bytes_in_a_t32_are_tape_errors(tmp_path: Path, step: int, stop: int) -> None:
    path = write_t32(tmp_path / "run.h5", t32_tape(np.random.default_rng(4)))
    outcomes = _flip_everywhere(path, step, stop, (verify, read_t32))
    assert outcomes["TapeError"] > outcomes["ok"] / 10, outcomes
