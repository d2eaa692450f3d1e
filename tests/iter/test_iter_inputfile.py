"""Opening input files (iter.inputfile): regular files only, text of bounded size, checked
before a byte is read. The CLI's readers are tested in tests/tapp/cli/test_input_files.py."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest

from iter import ResultFileError, SweepInputError, load_sweep, read_hdf5
from iter.inputfile import MAX_TOML_BYTES, read_bytes, read_text, read_toml, regular_file
from tests.deadline import guarded


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _zero(path: Path) -> None:
    path.symlink_to("/dev/zero")


def _folder(path: Path) -> None:
    path.mkdir()


def _socket(path: Path) -> None:
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(path))
    server.close()  # the socket file stays


NOT_REGULAR = {"fifo": (_fifo, "a FIFO (named pipe)"),
               "symlink to /dev/zero": (_zero, "a character device"),
               "directory": (_folder, "a directory"),
               "socket": (_socket, "a socket")}


@pytest.mark.parametrize("kind", NOT_REGULAR)
@pytest.mark.parametrize("reader", ["regular_file", "read_bytes", "read_text", "read_toml"])
def test_anything_but_a_regular_file_is_refused_before_reading(tmp_path: Path, kind: str,
                                                               reader: str) -> None:
    make, described = NOT_REGULAR[kind]
    path = tmp_path / "input.toml"
    make(path)
    call = {"regular_file": lambda: regular_file(path, "deck file"),
            "read_bytes": lambda: read_bytes(path, "deck file", max_bytes=100),
            "read_text": lambda: read_text(path, "deck file", max_bytes=100),
            "read_toml": lambda: read_toml(path, "deck file")}[reader]
    with guarded(), pytest.raises(SweepInputError) as info:
        call()
    assert str(info.value) == (f"{path}: file: expected a regular file (deck file) "
                               f"(got '{described}')")


def test_a_symlink_to_a_regular_file_is_read(tmp_path: Path) -> None:
    target = tmp_path / "real.toml"
    target.write_text("a = 1\n")
    link = tmp_path / "link.toml"
    link.symlink_to(target)
    assert read_toml(link, "deck file") == {"a": 1}
    assert regular_file(link, "deck file") == link


def test_a_missing_or_unreadable_file_names_what_was_expected(tmp_path: Path) -> None:
    missing = tmp_path / "none.toml"
    with pytest.raises(SweepInputError, match=f"^{missing}: file: expected an existing deck "
                                              "file$"):
        read_text(missing, "deck file", max_bytes=100)
    dangling = tmp_path / "dangling.toml"
    dangling.symlink_to(missing)
    with pytest.raises(SweepInputError, match="expected an existing deck file"):
        regular_file(dangling, "deck file")
    locked = tmp_path / "locked.toml"
    locked.write_text("a = 1\n")
    locked.chmod(0)
    if os.access(locked, os.R_OK):  # root reads any file: nothing to test there
        return
    with pytest.raises(SweepInputError, match="expected a readable deck file .got "
                                              "'Permission denied'"):
        read_text(locked, "deck file", max_bytes=100)


def test_the_size_bound_is_checked_from_the_size_then_while_reading(tmp_path: Path) -> None:
    path = tmp_path / "obs.csv"
    path.write_bytes(b"x" * 100)
    assert read_bytes(path, "CSV file", max_bytes=100) == b"x" * 100  # at the bound: read
    with pytest.raises(SweepInputError) as info:
        read_bytes(path, "CSV file", max_bytes=99)
    assert str(info.value).endswith("expected a CSV file of at most 99 bytes (got '100 bytes')")
    # /proc files report a size of 0 and are read no further than the bound
    with pytest.raises(SweepInputError, match="of at most 10 bytes .got 'more than 10 bytes'"):
        read_bytes("/proc/self/status", "status file", max_bytes=10)


def test_text_that_is_not_utf8_names_the_byte(tmp_path: Path) -> None:
    path = tmp_path / "binary.tdm"
    path.write_bytes(b"CCSDS_TDM_VERS = 2.0\n\xff\xfe")
    with pytest.raises(SweepInputError, match="expected a TDM in UTF-8 text .got 'byte 0xff "
                                              "at offset 21'.$"):
        read_text(path, "TDM", max_bytes=1000)


def test_toml_nested_too_deep_for_the_parser_is_one_error(tmp_path: Path) -> None:
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000)  # tomllib recursed and raised RecursionError
    with pytest.raises(SweepInputError, match="TOML: expected valid TOML .arrays or tables "
                                              "nested too deep for the parser."):
        read_toml(path, "deck file")
    assert MAX_TOML_BYTES == 4 * 2**20


def test_iter_refuses_a_fifo_as_its_sweep_file_or_its_results(tmp_path: Path) -> None:
    fifo = tmp_path / "sweep.toml"
    os.mkfifo(fifo)
    with guarded(), pytest.raises(SweepInputError, match="expected a regular file .sweep "
                                                          "file. .got 'a FIFO"):
        load_sweep(fifo)
    results = tmp_path / "r.h5"
    results.symlink_to("/dev/zero")
    with guarded(), pytest.raises(ResultFileError, match="expected a regular file .HDF5 "
                                                          "results file. .got 'a character"):
        read_hdf5(results)
