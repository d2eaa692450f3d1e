"""Results files: HDF5 round trip, CSV cells, units from names, unreadable files."""

from __future__ import annotations

import csv
import math

import h5py
import numpy as np
import pytest

from iter import CaseResult, CaseStatus, ResultFileError, ResultTable, read_hdf5, write_csv
from iter.results import units_of, write_hdf5

NAMES = ("launch_day", "azimuth_deg")
ROWS = (
    CaseResult(index=0, values=(5730.0, 96.0), outputs={"i_deg": 29.07, "site": "cape"},
               status=CaseStatus.OK, elapsed_s=0.25),
    CaseResult(index=1, values=(5730.0, 99.0), outputs={}, status=CaseStatus.FAILED,
               error="ValueError: math domain error", elapsed_s=0.5),
    CaseResult(index=3, values=(5731.0, 96.0), outputs={"i_deg": 29.5, "site": "vafb"},
               status=CaseStatus.OK, elapsed_s=0.125),
)
TABLE = ResultTable(names=NAMES, rows=ROWS)


def _write(path):
    write_hdf5(path, TABLE, sweep_json='{"a": 1}', definition_json='{"b": 2}', source="s.toml",
               n_cases=4, created_utc="2026-01-01T00:00:00Z", updated_utc="2026-01-01T00:00:01Z")


def test_hdf5_round_trip_keeps_rows_and_provenance(tmp_path):
    path = tmp_path / "r.h5"
    _write(path)
    stored = read_hdf5(path)
    assert stored.table == TABLE
    assert [row.elapsed_s for row in stored.table.rows] == [0.25, 0.5, 0.125]
    assert (stored.sweep_json, stored.definition_json, stored.n_cases) == (
        '{"a": 1}', '{"b": 2}', 4)
    assert stored.created_utc == "2026-01-01T00:00:00Z"
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["outputs/i_deg"][()], [29.07, np.nan, 29.5])
        assert list(f["outputs/site"].asstr()[()]) == ["cape", "", "vafb"]
        assert list(f["status"][()]) == [0, 1, 0]
        assert f["error"].asstr()[1] == "ValueError: math domain error"
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_an_empty_table_round_trips(tmp_path):
    # What a sweep interrupted before its first chunk leaves behind.
    path = tmp_path / "empty.h5"
    write_hdf5(path, ResultTable(names=NAMES, rows=()), sweep_json="{}", definition_json="{}",
               source="s.toml", n_cases=4, created_utc="t0", updated_utc="t1")
    assert read_hdf5(path).table == ResultTable(names=NAMES, rows=())


def test_csv_cells(tmp_path):
    path = tmp_path / "r.csv"
    write_csv(path, TABLE)
    with path.open() as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == ["case", "launch_day", "azimuth_deg", "i_deg", "site", "status", "error",
                       "elapsed_s"]
    assert rows[1] == ["0", "5730.0", "96.0", "29.07", "cape", "ok", "", "0.25"]
    assert rows[2] == ["1", "5730.0", "99.0", "", "", "failed",
                       "ValueError: math domain error", "0.5"]


def test_table_columns_and_counts():
    assert TABLE.columns == ("case", *NAMES, "i_deg", "site", "status", "error", "elapsed_s")
    assert (TABLE.n_succeeded, TABLE.n_failed) == (2, 1)
    assert math.isnan(TABLE.column("i_deg")[1])
    assert list(TABLE.column("case")) == [0, 1, 3]
    with pytest.raises(KeyError, match="no column 'x'"):
        TABLE.column("x")
    with pytest.raises(ValueError, match="sorted by case index"):
        ResultTable(names=NAMES, rows=(ROWS[2], ROWS[0]))


@pytest.mark.parametrize(("name", "units"), [
    ("v_inf_km_s", "km/s"), ("azimuth_deg", "deg"), ("r_km[2]", "km"), ("gm_km3_s2", "km^3/s^2"),
    ("launch_day", "day"), ("tof_s", "s"), ("count", ""),
])
def test_units_come_from_the_name(name, units):
    assert units_of(name) == units


def test_unwritable_and_foreign_files_are_typed_errors(tmp_path):
    write_csv(tmp_path / "new_dir" / "r.csv", TABLE)  # parents are created
    (tmp_path / "a_file").touch()
    with pytest.raises(ResultFileError, match="expected a writable file"):
        write_csv(tmp_path / "a_file" / "r.csv", TABLE)
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = 1
    with pytest.raises(ResultFileError, match="format: expected an iter-results file"):
        read_hdf5(foreign)
    text = tmp_path / "text.h5"
    text.write_text("not hdf5")
    with pytest.raises(ResultFileError, match="expected a readable HDF5 results file"):
        read_hdf5(text)


def _flip_byte(path, dataset: str) -> None:
    with h5py.File(path, "r") as f:
        offset, size = f[dataset].id.get_offset(), f[dataset].id.get_storage_size()
    data = bytearray(path.read_bytes())
    data[offset + size // 2] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("dataset", ["case", "inputs/azimuth_deg", "outputs/i_deg", "status",
                                     "elapsed_s"])
def test_a_flipped_byte_in_any_numeric_column_is_an_error_naming_it(tmp_path, dataset):
    """Issue 10, class 3: every dataset carries a sha256 digest, checked on read."""
    path = tmp_path / "r.h5"
    _write(path)
    _flip_byte(path, dataset)
    with pytest.raises(ResultFileError, match=f"{dataset}: expected values matching its "
                       "sha256"):
        read_hdf5(path)


def test_a_changed_text_cell_is_an_error_naming_its_column(tmp_path):
    path = tmp_path / "r.h5"
    _write(path)
    with h5py.File(path, "r+") as f:
        f["error"][1] = "ValueError: something else"
    with pytest.raises(ResultFileError, match="error: expected values matching its sha256"):
        read_hdf5(path)


def test_version_1_files_without_digests_are_read_with_a_warning(tmp_path):
    from iter.results import ResultFileWarning

    path = tmp_path / "r.h5"
    _write(path)
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = 1

        def strip(name, obj):
            if isinstance(obj, h5py.Dataset):
                del obj.attrs["sha256"]

        f.visititems(strip)
    with pytest.warns(ResultFileWarning, match="format_version 1 results carry no checksums"):
        assert read_hdf5(path).table == TABLE


def test_a_csv_into_a_pipe_leaves_the_pipe_a_pipe(tmp_path):
    """A results file named by a device or pipe (``--output-csv /dev/null``) is written into,
    never renamed over (a rename replaces the device with a regular file)."""
    import os
    import stat
    import threading

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    received: list[str] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_text()))
    reader.start()
    write_csv(fifo, TABLE)
    reader.join(timeout=10)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    plain = tmp_path / "plain.csv"
    write_csv(plain, TABLE)
    assert received == [plain.read_text()]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "plain.csv"]
