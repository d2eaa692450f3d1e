"""CCSDS TDM (KVN): the two published examples of the standard, the refusals of what tapp
cannot use, and the round trip of tapp's own observations.

The examples are those of CCSDS 503.0-B (TDM Blue Book) as shipped in Orekit's test resources
(src/test/resources/ccsds/tdm/kvn/, Apache License 2.0), copied from the workplace's
``shared/data/ccsds-tdm/`` into ``tests/data/ccsds-tdm/`` with their README, so the tests need
nothing outside the repository. Expected record counts are read off the files
by eye: TDMExample2 has one TRANSMIT_FREQ_2 and six RECEIVE_FREQ_1 records; TDMExample8 has
three epochs per segment, segment 1 with DOPPLER_INTEGRATED, ANGLE_1, ANGLE_2 and segment 2
with RANGE besides.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.time import Epoch, parse_epoch
from tapp.io.ccsds.tdm import (
    StationTrack,
    format_tdm,
    parse_epoch_jd,
    parse_tdm,
    read_tracks,
    tdm_from_tracks,
    tracks_from_rows,
)

EXAMPLES = Path(__file__).resolve().parents[3] / "data" / "ccsds-tdm"
EPOCH = parse_epoch("2026-01-01T00:00:00")
#: Written epochs carry 1 ns; a split Julian date holds about 1e-11 s.
ONE_NANOSECOND_s = 1e-9
#: Angles are written in degrees and read back in radians: a few ulps.
ANGLE_ROUNDING_rad = 1e-14


def _example(name: str) -> str:
    path = EXAMPLES / name
    assert path.is_file(), f"the published TDM examples are expected in {EXAMPLES}"
    return path.read_text()


def test_example_2_parses_into_its_records() -> None:
    tdm = parse_tdm(_example("TDMExample2.txt"), "TDMExample2.txt")
    assert tdm.version == "1.0" and len(tdm.segments) == 1
    seg = tdm.segments[0]
    assert seg.counts() == {"TRANSMIT_FREQ_2": 1, "RECEIVE_FREQ_1": 6}
    assert seg.meta("PARTICIPANT_1").value == "DSS-25" and seg.meta("PATH").value == "2,1"
    assert [kv.value for kv in tdm.header if kv.keyword == "ORIGINATOR"] == ["NASA/JPL"]
    # day-of-year epochs: 2005-159 is 8 June 2005
    assert (seg.jd_whole[2], seg.jd_fraction[2]) == parse_epoch_jd("2005-06-08T17:41:01")
    assert seg.value[-1] == -218.7951


def test_example_8_parses_into_its_records() -> None:
    tdm = parse_tdm(_example("TDMExample8.txt"), "TDMExample8.txt")
    assert [s.counts() for s in tdm.segments] == [
        {"DOPPLER_INTEGRATED": 3, "ANGLE_1": 3, "ANGLE_2": 3},
        {"RANGE": 3, "DOPPLER_INTEGRATED": 3, "ANGLE_1": 3, "ANGLE_2": 3}]
    second = tdm.segments[1]
    assert second.meta("RANGE_UNITS").value == "s" and second.meta("ANGLE_TYPE").value == "AZEL"
    assert second.value[0] == pytest.approx(4.00165248953670e4)


def _refusal(text: str, stations=("DSS-25", "HBSTK", "WHM1")) -> str:
    with pytest.raises(InputError) as info:
        read_tracks(parse_tdm(text, "x.tdm"), EPOCH, set(stations))
    message = str(info.value)
    assert "\n" not in message and message.startswith("x.tdm: ")
    return message


def test_example_2_is_refused_naming_the_frequency_keyword() -> None:
    message = _refusal(_example("TDMExample2.txt"))
    assert message.startswith("x.tdm: TRANSMIT_FREQ_2 (segment 1 DATA, line 24): expected ")
    assert "frequencies are not modelled" in message


def test_example_8_is_refused_naming_integrated_doppler() -> None:
    message = _refusal(_example("TDMExample8.txt"))
    assert message.startswith("x.tdm: DOPPLER_INTEGRATED (segment 1 DATA, line 21)")
    assert "integrated Doppler" in message


def _segment_2_without_doppler() -> str:
    """TDMExample8's segment 2 alone, its DOPPLER_INTEGRATED records removed: range in
    seconds with a modulus, and AZEL angles."""
    text = _example("TDMExample8.txt")
    header, _, rest = text.partition("META_START")
    second = "META_START" + rest.split("META_START")[-1]
    return header + "\n".join(line for line in second.splitlines()
                              if "DOPPLER_INTEGRATED" not in line) + "\n"


def test_range_in_seconds_with_a_modulus_is_refused() -> None:
    message = _refusal(_segment_2_without_doppler())
    assert message.startswith("x.tdm: RANGE_MODULUS (segment 1 META, line 17): expected 0")
    text = _segment_2_without_doppler().replace("RANGE_MODULUS = 1.000000E+07",
                                                "RANGE_MODULUS = 0")
    assert _refusal(text).startswith("x.tdm: RANGE_UNITS (segment 1 META, line 18): expected "
                                     "km (range in seconds or range units")


@pytest.mark.parametrize(("old", "new", "keyword"), [
    ("TIME_SYSTEM = UTC", "TIME_SYSTEM = TAI", "TIME_SYSTEM"),
    ("RANGE_UNITS = s", "RANGE_UNITS = RU", "RANGE_UNITS"),
    ("ANGLE_TYPE = AZEL", "ANGLE_TYPE = XEYN", "ANGLE_TYPE"),
    ("MODE = SEQUENTIAL", "MODE = SINGLE_DIFF", "MODE"),
])
def test_metadata_tapp_cannot_use_is_refused(old: str, new: str, keyword: str) -> None:
    text = _segment_2_without_doppler()
    text = text.replace("RANGE_MODULUS = 1.000000E+07", "RANGE_MODULUS = 0")
    if keyword != "RANGE_UNITS":
        text = text.replace("RANGE_UNITS = s", "RANGE_UNITS = km")
    text = text.replace(old, new)
    assert new in text
    message = _refusal(text)
    assert message.startswith(f"x.tdm: {keyword} (segment 1 META, line ")


def test_unknown_keyword_and_xml_are_refused() -> None:
    text = _example("TDMExample2.txt").replace("DATA_QUALITY = RAW",
                                                "DATA_QUALITY = RAW\n\tFOO_BAR = 3")
    with pytest.raises(InputError, match=r"line 21: FOO_BAR: expected a TDM metadata keyword"):
        parse_tdm(text, "x.tdm")
    with pytest.raises(InputError, match="XML form"):
        parse_tdm('<?xml version="1.0"?>\n<tdm/>', "x.tdm")
    with pytest.raises(InputError, match="RANGE belongs in the data block"):
        parse_tdm(_example("TDMExample2.txt").replace("MODE = SEQUENTIAL", "RANGE = 1"),
                  "x.tdm")


def _tracks() -> list[StationTrack]:
    t = np.array([0.0, 30.0, 60.0, 90.5])
    values = np.array([[1500.0, -6.5, 0.1, 0.2], [1400.123456789, -6.1, 1.0, 0.3],
                       [1300.0, 0.0, 6.2, 0.4], [1200.0, 6.9, 3.14159, 1.5]])
    return [StationTrack("QUITO", "SATORB1", ("range", "range_rate", "azimuth", "elevation"),
                         t, values, 172800.0),
            StationTrack("KOUROU", "SATORB1", ("range", "range_rate", "azimuth", "elevation"),
                         t + 1000.0, values[::-1], 172800.0)]


def test_round_trip_of_tapp_observations() -> None:
    text = format_tdm(tdm_from_tracks(_tracks(), EPOCH, comments=("round trip",)))
    tdm = parse_tdm(text, "rt.tdm")
    assert tdm.version == "2.0" and tdm.comments == ("round trip",)
    assert tdm.segments[0].meta("PARTICIPANT_1").value == "QUITO"
    assert tdm.segments[0].meta("ANGLE_TYPE").value == "AZEL"
    back = read_tracks(tdm, EPOCH, {"QUITO", "KOUROU"})
    for got, sent in zip(back, _tracks(), strict=True):
        assert (got.station, got.spacecraft, got.kinds) == (sent.station, sent.spacecraft,
                                                            sent.kinds)
        np.testing.assert_allclose(got.t_s, sent.t_s, rtol=0, atol=ONE_NANOSECOND_s)
        np.testing.assert_array_equal(got.values[:, :2], sent.values[:, :2])
        np.testing.assert_allclose(got.values[:, 2:], sent.values[:, 2:], rtol=0,
                                   atol=ANGLE_ROUNDING_rad)
        assert got.span_end_s == pytest.approx(172800.0, abs=ONE_NANOSECOND_s)


def test_rows_group_into_tracks() -> None:
    t = np.array([0.0, 0.0, 30.0, 30.0, 10.0])
    station = np.array([0, 0, 0, 0, 1])
    kind = np.array([0, 1, 0, 1, 0])
    value = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    tracks = tracks_from_rows(t, station, kind, value, ("range", "range_rate"),
                              ("A", "B"), "SC")
    assert [(tr.station, tr.kinds) for tr in tracks] == [("A", ("range", "range_rate")),
                                                         ("B", ("range",))]
    np.testing.assert_array_equal(tracks[0].values, [[1.0, 2.0], [3.0, 4.0]])


def test_every_epoch_must_carry_every_observable() -> None:
    text = format_tdm(tdm_from_tracks(_tracks()[:1], EPOCH))
    lines = text.splitlines()
    cut = next(i for i, s in enumerate(lines) if s.startswith("DOPPLER_INSTANTANEOUS"))
    message = _refusal("\n".join(lines[:cut] + lines[cut + 1:]), ("QUITO",))
    assert "DOPPLER_INSTANTANEOUS (segment 1 DATA" in message


def test_a_participant_must_be_a_known_station() -> None:
    text = format_tdm(tdm_from_tracks(_tracks()[:1], EPOCH))
    message = _refusal(text, ("KOUROU",))
    assert "PARTICIPANT_n (segment 1 META" in message and "stations: KOUROU" in message


def test_epochs_before_the_scenario_epoch_are_refused() -> None:
    text = format_tdm(tdm_from_tracks(_tracks()[:1], EPOCH))
    later = Epoch(EPOCH.jd_whole + 1.0, EPOCH.jd_fraction)
    with pytest.raises(InputError, match="at or after the scenario's epoch"):
        read_tracks(parse_tdm(text, "x.tdm"), later, {"QUITO"})


@pytest.mark.parametrize(("text", "expected"), [
    ("2026-001T00:00:00", parse_epoch_jd("2026-01-01T00:00:00")),
    ("2024-366T23:59:59.5Z", parse_epoch_jd("2024-12-31T23:59:59.5")),
    ("2026-02-29T00:00:00", None),
    ("2025-366T00:00:00", None),
    ("2026-01-01T24:00:00", None),
    ("2026-01-01 00:00:00", None),
])
def test_epoch_forms(text: str, expected) -> None:
    assert parse_epoch_jd(text) == expected


def test_azimuth_is_read_into_zero_to_two_pi() -> None:
    track = StationTrack("QUITO", "SC", ("azimuth", "elevation"), np.array([0.0]),
                         np.array([[math.radians(359.5), 0.1]]))
    text = format_tdm(tdm_from_tracks([track], EPOCH)).replace("ANGLE_1 = 2026-01-01T00:00:"
                                                                "00.000000000 359.5",
                                                                "ANGLE_1 = 2026-01-01T00:00:"
                                                                "00.000000000 -0.5")
    back = read_tracks(parse_tdm(text, "x.tdm"), EPOCH, {"QUITO"})[0]
    assert back.values[0, 0] == pytest.approx(math.radians(359.5))
