"""SPICE SPK files (tapp.io.spk): a type 13 segment written and read back by spiceypy's own
calls, names and ids, comments, and the errors, with SPICE's kernel pool left as found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import spiceypy
from jplephem.spk import SPK

from tapp.dynamics.ephemeris import de421_path
from tapp.errors import InputError
from tapp.io.spk import add_comments, body_id, spk_states, write_spk

ET0 = 8.2e8  # 2025-12-27 TDB
BODY = -77
#: States come back from SPICE's evaluation at their own epochs to rounding (7000 km).
ROUNDING_KM = 1e-11


def _circle(et: np.ndarray) -> np.ndarray:
    n, r = 2 * np.pi / 5400.0, 7000.0
    t = et - ET0
    return np.stack([r * np.cos(n * t), r * np.sin(n * t), 0 * t, -r * n * np.sin(n * t),
                     r * n * np.cos(n * t), 0 * t], axis=1)


@pytest.fixture
def spk(tmp_path: Path) -> Path:
    path = tmp_path / "circle.bsp"
    et = ET0 + np.arange(0.0, 3601.0, 60.0)
    write_spk(path, BODY, [(et, _circle(et))])
    return path


def test_written_segment_is_read_by_spice_itself(spk: Path) -> None:
    et = ET0 + np.array([0.0, 600.0, 3600.0])
    spiceypy.furnsh(str(spk))
    try:
        states, _ = spiceypy.spkezr(str(BODY), et, "J2000", "NONE", "399")
        ids = spiceypy.spkobj(str(spk))
        assert [ids[i] for i in range(spiceypy.card(ids))] == [BODY]
    finally:
        spiceypy.unload(str(spk))
    np.testing.assert_allclose(np.array(states), _circle(et), rtol=0, atol=ROUNDING_KM)
    np.testing.assert_allclose(spk_states(spk, BODY, et, "s.toml"), _circle(et), rtol=0,
                               atol=ROUNDING_KM)


def test_comments_are_in_the_comment_area(spk: Path) -> None:
    add_comments(spk, ("first line", "x" * 1500))
    handle = spiceypy.dafopr(str(spk))
    try:
        _, lines, _ = spiceypy.dafec(handle, 10, 1001)
    finally:
        spiceypy.dafcls(handle)
    assert lines[:3] == ["first line", "x" * 1000, "x" * 500]


@pytest.mark.parametrize(("body", "naif"), [(-999, -999), ("-82", -82), ("MOON", 301),
                                            ("earth barycenter", 3)])
def test_bodies_by_id_or_by_a_name_spice_knows(body, naif: int) -> None:
    assert body_id(body, "s.toml", "reference.object") == naif


def test_errors_name_the_field_and_leave_the_kernel_pool_as_found(spk: Path,
                                                                  tmp_path: Path) -> None:
    loaded = spiceypy.ktotal("ALL")
    with pytest.raises(InputError) as err:
        body_id("NO SUCH CRAFT", "s.toml", "reference.object")
    assert err.value.field == "reference.object"
    with pytest.raises(InputError) as err:
        spk_states(spk, -78, [ET0], "s.toml", "reference.file", "reference.object")
    assert str(err.value) == ("s.toml: reference.object: expected a body whose data "
                              "circle.bsp holds (-77) (got -78)")
    with pytest.raises(InputError) as err:
        spk_states(spk, BODY, [ET0 + 7200.0], "s.toml", "reference.file")
    assert err.value.expected.startswith("an SPK whose data of body -77 covers the times, ")
    junk = tmp_path / "junk.bsp"
    junk.write_text("not a kernel")
    with pytest.raises(InputError) as err:
        spk_states(junk, BODY, [ET0], "s.toml", "reference.file")
    assert err.value.expected == "an SPK file SPICE can read"
    assert spiceypy.ktotal("ALL") == loaded


#: A Moon-centred segment read about the Earth through DE421 (jplephem here, SPICE in tapp):
#: measured 3.1e-11 km; 1e-8 km allowed (rounding of 4e5 km Moon distances).
THROUGH_DE421_KM = 1e-8


def test_a_segment_about_the_moon_is_read_about_the_earth(tmp_path: Path) -> None:
    et = ET0 + np.arange(0.0, 3601.0, 60.0)
    kernel = SPK.open(str(de421_path()))
    try:
        whole = np.floor(et / 86400.0)  # a two-part TDB date: whole days, then the fraction
        jd = (2451545.0 + whole, (et - 86400.0 * whole) / 86400.0)
        moon = [kernel[3, 301].compute_and_differentiate(*jd)[k]
                - kernel[3, 399].compute_and_differentiate(*jd)[k] for k in (0, 1)]
    finally:
        kernel.close()
    moon_state = np.concatenate([moon[0].T, moon[1].T / 86400.0], axis=1)
    path = str(tmp_path / "about_moon.bsp")
    handle = spiceypy.spkopn(path, "test", 0)
    spiceypy.spkw13(handle, BODY, 301, "J2000", et[0], et[-1], "moon", 7, et.size,
                    _circle(et) - moon_state, et)
    spiceypy.spkcls(handle)
    got = spk_states(path, BODY, et[::7], "s.toml")
    np.testing.assert_allclose(got, _circle(et[::7]), rtol=0, atol=THROUGH_DE421_KM)
