"""The departure-day body: SEARCH converges and the ΔV agrees with the vis-viva estimate."""

from __future__ import annotations

import math

import pytest

from tapp.constants import GM_EARTH_km3_s2, R_EARTH_km
from tapp.frames.time import parse_epoch
from tapp.targeting.lunar_departure import lunar_departure_case, shifted_epoch


def test_shifted_epoch_keeps_the_split() -> None:
    base = parse_epoch("2026-03-10T12:00:00")
    later = shifted_epoch(base, 2.75)
    assert later.iso(0) == "2026-03-13T06:00:00"
    assert 0.0 <= later.jd_fraction < 1.0


@pytest.mark.parametrize("day", [2.0, 17.0])
def test_departure_case_converges_with_a_tli_sized_dv(day: float) -> None:
    out = lunar_departure_case(day)
    assert out["flag"] == 1.0
    assert math.hypot(out["b_dot_r_km"], out["b_dot_t_km"]) == pytest.approx(5600.0, abs=1.5)
    # Patched-conic estimate: perigee speed of a 185 km x ~1.1 lunar-distance ellipse minus
    # the circular speed (about 3.1 km/s); the targeted ΔV is within 3 % of it.
    r_p = R_EARTH_km + 185.0
    r_a = 1.1 * 384400.0
    dv_est = math.sqrt(2 * GM_EARTH_km3_s2 * r_a / (r_p * (r_p + r_a))) - math.sqrt(
        GM_EARTH_km3_s2 / r_p)
    assert out["dv_km_s"] == pytest.approx(dv_est, rel=0.03)
    assert 2.5 * 86400 < out["flight_time_s"] < 5 * 86400
