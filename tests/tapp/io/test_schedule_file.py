"""Pass schedules (CSV) read for ``[tracking] schedule`` (issue 29, item 3): what a row
means, and one error naming the file, the row and the field for each kind of bad input."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.time import parse_epoch
from tapp.io.schedule_file import (
    MAX_SCHEDULE_BYTES,
    MAX_SCHEDULE_SAMPLES,
    SAMPLE_MATCH_S,
    PassSchedule,
    parse_schedule,
    read_schedule,
)

EPOCH = parse_epoch("2026-01-01T00:00:00")
STATIONS = {"QUITO": ("range", "range_rate"), "KOUROU": ("range",)}
HEADER = "station,start,end,data_types,data_interval_s,uplink_station\n"


def _parse(text: str, clock_s: float = 0.0, epoch=EPOCH) -> PassSchedule:
    return parse_schedule(text, "passes.csv", epoch=epoch, stations=STATIONS,
                          data_interval_s=20.0, clock_s=clock_s)


def test_a_row_is_a_pass_on_the_scenario_sample_clock() -> None:
    """By hand: clock 10 s, interval 20 s: 10 + 20 i within [100, 200] is 110..190 (5); the
    other pass every 60 s from 3600 (the date) to 3700 s: 3610, 3670; defaults from the
    scenario (interval) and the station (observables, in its order); comments, blank lines
    and a byte-order mark skipped; rows numbered as the file's lines."""
    text = ("\ufeff# a comment\n" + HEADER + "\n"
            "QUITO,100,200,,,\n"
            "QUITO,2026-01-01T01:00:00,3700,range_rate range,60,QUITO\n")
    sch = _parse(text, clock_s=10.0)
    first, second = sch.of("QUITO")
    assert (first.row, first.kinds, first.data_interval_s) == (4, ("range", "range_rate"),
                                                              20.0)
    np.testing.assert_array_equal(first.sample_times_s(10.0), [110, 130, 150, 170, 190])
    assert (second.row, second.start_s, second.kinds) == (5, 3600.0, ("range", "range_rate"))
    np.testing.assert_array_equal(second.sample_times_s(10.0), [3610.0, 3670.0])
    assert sch.stations == {"QUITO"}


def test_the_ends_of_a_pass_catch_a_sample_within_a_microsecond() -> None:
    """A date written to the microsecond beside a grid time still holds it; 2 µs does not."""
    inside = f"{100 - 0.5 * SAMPLE_MATCH_S!r},{200 + 0.5 * SAMPLE_MATCH_S!r}"
    outside = f"{100 + 2 * SAMPLE_MATCH_S!r},{200 - 2 * SAMPLE_MATCH_S!r}"
    for ends, expected in ((inside, [100, 120, 140, 160, 180, 200]),
                           (outside, [120, 140, 160, 180])):
        (p,) = _parse(f"station,start,end\nQUITO,{ends}\n").passes
        np.testing.assert_array_equal(p.sample_times_s(0.0), expected)


def test_a_date_across_a_leap_second_counts_it() -> None:
    """2016-12-31T23:59:60 was inserted: from 23:59:00 to 00:01:00 is 121 SI seconds."""
    epoch = parse_epoch("2016-12-31T23:59:00")
    (p,) = _parse("station,start,end\nQUITO,2017-01-01T00:00:00,2017-01-01T00:01:00\n",
                  epoch=epoch).passes
    # the dates' rounding through Julian dates stays within what a pass's ends catch
    assert (p.start_s, p.end_s) == pytest.approx((61.0, 121.0), rel=0, abs=SAMPLE_MATCH_S)
    np.testing.assert_array_equal(p.sample_times_s(1.0), [61.0, 81.0, 101.0, 121.0])


def test_passes_are_ordered_by_station_then_start() -> None:
    sch = _parse("station,start,end\nKOUROU,500,600\nQUITO,700,800\nQUITO,100,200\n")
    assert [(p.station, p.row) for p in sch.passes] == [("QUITO", 4), ("QUITO", 3),
                                                        ("KOUROU", 2)]


@pytest.mark.parametrize(("text", "field", "expected", "got"), [
    ("station,start\nQUITO,100\n", "row 1: header", "the columns station, start, end",
     "station,start"),
    ("station,begin,end\nQUITO,100,200\n", "row 1: header", "(optional: data_types, "
     "data_interval_s, uplink_station), each once", "station,begin,end"),
    ("station,start,end,end\nQUITO,100,200,300\n", "row 1: header", "each once",
     "station,start,end,end"),
    ("# only a comment\n", "row 1: header", "on the first line that is not a comment", ""),
    ("station,start,end\nQUITO,100\n", "row 2: cells", "3 comma-separated cells", 2),
    ("station,start,end\nGOLDSTONE,100,200\n", "row 2: station",
     "a station of tracking.stations (QUITO, KOUROU)", "GOLDSTONE"),
    ("station,start,end\nQUITO,200,100\n", "row 2: end",
     "a time after the pass's start (200.000000 s from the epoch)", "100"),
    ("station,start,end\nQUITO,100,100\n", "row 2: end", "a time after the pass's start",
     "100"),
    ("station,start,end\nQUITO,yesterday,100\n", "row 2: start",
     "seconds from the epoch or an ISO 8601 UTC date", "yesterday"),
    ("station,start,end\nQUITO,2026-02-30T00:00:00,1e9\n", "row 2: start",
     "with a valid calendar date", "2026-02-30T00:00:00"),
    ("station,start,end\nQUITO,1969-01-01,100\n", "row 2: start",
     "seconds from the epoch or a UTC date on or after 1972-01-01", "1969-01-01"),
    ("station,start,end\nQUITO,100,nan\n", "row 2: end", "a time within 100 years", "nan"),
    ("station,start,end\nQUITO,100,1e300\n", "row 2: end", "a time within 100 years",
     "1e300"),
    ("station,start,end,data_types\nQUITO,100,200,phase\n", "row 2: data_types",
     "observables among range, range_rate, azimuth, elevation, doppler, separated by spaces",
     "phase"),
    ("station,start,end,data_types\nQUITO,100,200,doppler\n", "row 2: data_types",
     "observables that QUITO measures (range, range_rate;", "doppler"),
    ("station,start,end,data_types\nKOUROU,100,200,range range_rate\n", "row 2: data_types",
     "observables that KOUROU measures (range; tracking.observables or "
     "tracking.station.KOUROU.observables)", "range range_rate"),
    ("station,start,end,data_types\nQUITO,100,200,range range\n", "row 2: data_types",
     "each observable once", "range range"),
    ("station,start,end,data_interval_s\nQUITO,100,200,0\n", "row 2: data_interval_s",
     "a number of seconds >= 0.001", "0"),
    ("station,start,end,data_interval_s\nQUITO,100,200,inf\n", "row 2: data_interval_s",
     "a number of seconds >= 0.001", "inf"),
    ("station,start,end,uplink_station\nQUITO,100,200,KOUROU\n", "row 2: uplink_station",
     "empty or QUITO, the pass's own station (three-way tracking from another station: "
     "that station as tracking.station.QUITO.uplink)", "KOUROU"),
    ("station,start,end\nQUITO,105,115\n", "row 2: end", "a pass holding a sample time "
     "tracking.start + i × 20 s (none between its start and end)", "115"),
    ("station,start,end\nQUITO,100,200\nKOUROU,0,50\nQUITO,200,300\n", "row 4: start",
     "a time after the end of QUITO's pass on row 2 (2026-01-01T00:03:20.000 UTC): passes of "
     "a station do not overlap", "2026-01-01T00:03:20.000"),
    ("station,start,end,data_interval_s\nQUITO,0,999999,1\nQUITO,2e6,2000010,1\n",
     "row 3: data_interval_s", f"at most {MAX_SCHEDULE_SAMPLES:,} samples over the "
     "schedule (1,000,000 before this row", "1"),
])
def test_bad_input_is_one_error_naming_the_file_the_row_and_the_field(
        text: str, field: str, expected: str, got: object) -> None:
    with pytest.raises(InputError) as err:
        _parse(text)
    assert (err.value.source, err.value.field, err.value.got) == ("passes.csv", field, got)
    assert expected in err.value.expected
    assert str(err.value).startswith(f"passes.csv: {field}: expected ")


def test_a_schedule_without_a_pass_is_refused() -> None:
    with pytest.raises(InputError) as err:
        _parse(HEADER + "# nothing scheduled yet\n")
    assert str(err.value) == ("passes.csv: rows: expected at least one pass after the header "
                              "(got 'none')")


def _read(path: Path) -> PassSchedule:
    return read_schedule(path, epoch=EPOCH, stations=STATIONS, data_interval_s=20.0,
                         clock_s=0.0)


def test_the_file_is_read_bounded_and_must_be_a_regular_file(tmp_path: Path) -> None:
    good = tmp_path / "passes.csv"
    good.write_text("station,start,end\nQUITO,100,200\n")
    assert _read(good).source == str(good)
    big = tmp_path / "big.csv"
    big.write_bytes(b"#" * (MAX_SCHEDULE_BYTES + 1))
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    for path, expected, got in (
            (big, f"a pass schedule (CSV) of at most {MAX_SCHEDULE_BYTES:,} bytes",
             f"{MAX_SCHEDULE_BYTES + 1:,} bytes"),
            (fifo, "a regular file (pass schedule (CSV))", "a FIFO (named pipe)"),
            (tmp_path, "a regular file (pass schedule (CSV))", "a directory"),
            (tmp_path / "missing.csv", "an existing pass schedule (CSV)", None)):
        with pytest.raises(InputError) as err:
            _read(path)
        assert (err.value.source, err.value.field, err.value.expected, err.value.got) == (
            str(path), "file", expected, got)


def test_a_three_way_station_takes_its_uplink_and_no_other() -> None:
    """[tracking.station.QUITO] uplink = "KOUROU": its rows may name KOUROU (or nothing);
    itself or MALINDI is refused, naming the row."""
    ok = "station,start,end,uplink_station\nQUITO,100,200,KOUROU\nQUITO,300,400,\n"
    passes = parse_schedule(ok, "passes.csv", epoch=EPOCH, stations=STATIONS,
                            data_interval_s=20.0, clock_s=0.0, uplinks={"QUITO": "KOUROU"})
    assert len(passes.passes) == 2
    for other in ("QUITO", "MALINDI"):
        with pytest.raises(InputError) as err:
            parse_schedule(f"station,start,end,uplink_station\nQUITO,100,200,{other}\n",
                           "passes.csv", epoch=EPOCH, stations=STATIONS,
                           data_interval_s=20.0, clock_s=0.0, uplinks={"QUITO": "KOUROU"})
        assert err.value.field == "row 2: uplink_station"
        assert "empty or KOUROU, the uplink of QUITO" in err.value.expected
