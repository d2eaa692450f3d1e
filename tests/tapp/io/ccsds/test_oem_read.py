"""CCSDS OEM reading (tapp.io.ccsds.oem_read): another tool's KVN file, its XML form written by
the ``oem`` package, several segments, the declared interpolation, and bad messages refused
naming the line or element."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from oem import OrbitEphemerisMessage

from tapp.errors import InputError
from tapp.io.ccsds.oem_read import hermite_interpolate, interpolate, parse_oem, read_oem

DATA = Path(__file__).parents[3] / "data" / "ccsds-oem"
LEO_60S = DATA / "LEO_60s.oem"
#: The oem package writes XML numbers with 15 significant digits: 1e-11 km of 4700 km.
XML_DIGITS_KM = 1e-11
#: A polynomial of the interpolation's degree comes back to rounding (values ~1e7 at t ~ 10).
POLY_ROUNDING = 1e-8


def _seconds(seg) -> np.ndarray:
    return ((seg.jd_whole - seg.jd_whole[0]) + (seg.jd_fraction - seg.jd_fraction[0])) * 86400.0


def test_another_tools_kvn_file_reads_as_the_oem_package_reads_it() -> None:
    msg = read_oem(LEO_60S)
    (seg,) = msg.segments
    assert (msg.form, msg.version, msg.header["ORIGINATOR"]) == ("KVN", "2.0", "Test")
    meta = seg.metadata
    assert (meta["CENTER_NAME"], meta["REF_FRAME"], meta["TIME_SYSTEM"]) == ("EARTH", "ICRF",
                                                                            "UTC")
    assert seg.interpolation == ("LAGRANGE", 7)  # "Lagrange" in the file
    assert seg.fields["REF_FRAME"] == "line 12: REF_FRAME"
    (theirs,) = OrbitEphemerisMessage.open(LEO_60S).segments
    states = list(theirs.states)
    assert seg.states.shape == (len(states), 6) == (61, 6)
    np.testing.assert_array_equal(seg.states, [np.concatenate([s.position, s.velocity])
                                               for s in states])
    start = Time("2020-06-01T12:00:00", scale="utc")
    np.testing.assert_allclose(_seconds(seg), [(s.epoch - start).sec for s in states],
                               rtol=0, atol=1e-6)


def test_its_xml_form_reads_the_same(tmp_path: Path) -> None:
    xml = tmp_path / "leo.xml"
    OrbitEphemerisMessage.open(LEO_60S).save_as(xml, file_format="xml")
    kvn, xmsg = read_oem(LEO_60S), read_oem(xml)
    assert xmsg.form == "XML"
    (a,), (b,) = kvn.segments, xmsg.segments
    assert dict(a.metadata) == dict(b.metadata)
    np.testing.assert_allclose(b.states, a.states, rtol=0, atol=XML_DIGITS_KM)
    np.testing.assert_array_equal(b.jd_fraction, a.jd_fraction)
    assert b.fields["REF_FRAME"] == "segment[0].metadata.REF_FRAME"


SEGMENTS = """CCSDS_OEM_VERS = 2.0
CREATION_DATE = 2026-01-01T00:00:00
ORIGINATOR = TEST

META_START
OBJECT_NAME = SC
OBJECT_ID = 2026-001A
CENTER_NAME = EARTH
REF_FRAME = EME2000
TIME_SYSTEM = TT
START_TIME = 2026-01-01T00:00:00
STOP_TIME = 2026-01-01T00:02:00
INTERPOLATION = HERMITE
INTERPOLATION_DEGREE = 3
META_STOP
COMMENT the first arc
2026-01-01T00:00:00 7000 0 0 0 7.5 0
2026-01-01T00:01:00 6999 450 0 -0.03 7.49 0
2026-001T00:02:00.000 6996 900 0 -0.06 7.48 0 0.0 0.0 0.0

COVARIANCE_START
EPOCH = 2026-01-01T00:02:00
COV_REF_FRAME = EME2000
1.0
0.0 1.0
COVARIANCE_STOP

META_START
OBJECT_NAME = SC
OBJECT_ID = 2026-001A
CENTER_NAME = MOON
REF_FRAME = ICRF
TIME_SYSTEM = TDB
START_TIME = 2026-01-01T00:02:00
STOP_TIME = 2026-01-01T00:03:00
META_STOP
2026-01-01T00:02:00 6996 900 0 -0.06 7.48 0
2026-01-01T00:03:00 6990 1350 0 -0.09 7.47 0
"""


def test_several_segments_with_covariance_and_day_of_year_epochs() -> None:
    msg = parse_oem(SEGMENTS, "two.oem")
    first, second = msg.segments
    assert first.interpolation == ("HERMITE", 3)
    assert second.interpolation == ("HERMITE", 7)  # none declared: the default
    np.testing.assert_allclose(_seconds(first), [0.0, 60.0, 120.0], rtol=0, atol=1e-9)
    assert (second.metadata["CENTER_NAME"], second.metadata["TIME_SYSTEM"]) == ("MOON", "TDB")
    assert first.epoch_fields[2] == "line 19: epoch" and first.states.shape == (3, 6)


def test_hermite_is_exact_to_its_degree_and_velocity_is_its_derivative() -> None:
    rng = np.random.default_rng(11)
    nodes = np.cumsum(rng.uniform(0.5, 1.5, 12))
    coeffs = rng.normal(size=(8, 3))  # degree 7 in each coordinate
    pos = lambda t: np.stack([np.polyval(c, t) for c in coeffs.T], -1)  # noqa: E731
    vel = lambda t: np.stack([np.polyval(np.polyder(c), t) for c in coeffs.T], -1)  # noqa: E731
    states = np.concatenate([pos(nodes), vel(nodes)], axis=1)
    at = np.concatenate([nodes[:3], rng.uniform(nodes[0], nodes[-1], 100)])
    want = np.concatenate([pos(at), vel(at)], axis=1)
    got = hermite_interpolate(nodes, states, at, 7)
    np.testing.assert_allclose(got, want, rtol=0, atol=POLY_ROUNDING * np.abs(want).max())
    # one degree short (5: three nodes) misses a degree-7 polynomial
    assert np.abs(interpolate("HERMITE", 5, nodes, states, at) - want).max() > 1e-3
    # LINEAR: the mean of the two nodes at their mid-point
    lin = interpolate("LINEAR", 1, nodes, states, 0.5 * (nodes[4] + nodes[5]))
    np.testing.assert_allclose(lin[0], 0.5 * (states[4] + states[5]), rtol=1e-15)


def _edit(old: str, new: str) -> str:
    assert old in SEGMENTS, old
    return SEGMENTS.replace(old, new, 1)


@pytest.mark.parametrize(("text", "field", "says"), [
    (_edit("2026-01-01T00:01:00 6999", "2025-12-31T23:59:00 6999"), "line 18: epoch",
     "epochs strictly increasing within a segment"),
    (_edit("OBJECT_ID = 2026-001A\n", ""), "line 5: OBJECT_ID", "OBJECT_ID in every segment"),
    (_edit("ORIGINATOR = TEST", "ORIGINATOR = TEST\nCOLOUR = RED"), "line 4",
     "a header keyword"),
    (_edit("7.49 0", "7.49 zero"), "line 18: Z_DOT", "a number"),
    (_edit("INTERPOLATION_DEGREE = 3", "INTERPOLATION_DEGREE = 4"),
     "line 14: INTERPOLATION_DEGREE", "an odd degree for HERMITE"),
    (_edit("INTERPOLATION_DEGREE = 3", "INTERPOLATION_DEGREE = 9"),
     "line 14: INTERPOLATION_DEGREE", "a degree the segment's 3 states can carry"),
    (_edit("INTERPOLATION = HERMITE", "INTERPOLATION = SPLINE"), "line 13: INTERPOLATION",
     "one of HERMITE, LAGRANGE, LINEAR"),
    (_edit("2026-01-01T00:01:00 6999", "2026-01-01T00:61:00 6999"), "line 18: epoch",
     "a CCSDS epoch"),
    (_edit("STOP_TIME = 2026-01-01T00:02:00", "STOP_TIME = 2026-01-01T00:01:30"),
     "line 19: epoch", "epochs within STOP_TIME"),
    (_edit("START_TIME = 2026-01-01T00:02:00", "START_TIME = 2026-01-01T00:01:00"),
     "line 34: START_TIME", "segments in time order"),
    (_edit("CCSDS_OEM_VERS = 2.0", "CCSDS_OEM_VERS = 9.9"), "line 1: CCSDS_OEM_VERS",
     "an OEM version"),
    (_edit("7000 0 0 0 7.5 0", "7000 0 0 0 7.5"), "line 17", "an epoch and 6 numbers"),
])
def test_bad_messages_are_refused_naming_the_line(text: str, field: str, says: str) -> None:
    with pytest.raises(InputError) as err:
        parse_oem(text, "bad.oem")
    assert (err.value.source, err.value.field) == ("bad.oem", field)
    assert err.value.expected.startswith(says), err.value.expected


def test_xml_units_other_than_km_are_refused(tmp_path: Path) -> None:
    xml = tmp_path / "leo.xml"
    OrbitEphemerisMessage.open(LEO_60S).save_as(xml, file_format="xml")
    text = xml.read_text().replace("<X>", '<X units="m">', 1)
    with pytest.raises(InputError) as err:
        parse_oem(text, "m.xml")
    assert err.value.field == "segment[0].stateVector[0].X"
    assert err.value.expected == 'units="km" (or none)'
