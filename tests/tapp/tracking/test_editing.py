"""TAPP I keeps or counts every scheduled observation: pass limits, masks, blackouts, the
tape's span (issue 18, "No silent wrong answers", item 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s, WGS84_A_km
from tapp.errors import InputError
from tapp.io.tape.t13 import T13
from tapp.tracking.scenario_build import parse_scenario
from tapp.tracking.simulate import EDITING_RULES, simulate
from tests.tapp.tracking.helpers import (
    GEO_BIAS_M,
    HAND_A_KM,
    HAND_CENTRE_S,
    HAND_MASK_DEG,
    NORTH,
    geo_document,
    hand_document,
    leo_scenario,
    scaled_close,
)

# Sums of a few hundred products in another order: round-off, on the scale sqrt(J_aa J_bb).
SUM_ORDER = 1e-10

# --- a 12 h GEO track longer than max_pass_s -------------------------------------------------

@pytest.fixture(scope="module")
def geo() -> T13:
    return simulate(parse_scenario(geo_document(), "geo.toml"), raw=True).tape


def test_a_12_h_geo_track_longer_than_max_pass_keeps_every_sample_in_two_passes(geo: T13
                                                                               ) -> None:
    """By hand: samples at 600, 1200, ..., 43200 s, 72 of them, all above the 10° masks
    (elevation 90° and about 34°). Cut at 8 h after the first: 600..29400 s (49 samples),
    then 30000..43200 s (23). Two observables: 144 observations per station (the truncation
    this replaces kept the first 49 samples, 98 observations, and dropped the rest)."""
    for s in (1, 2):
        mine = geo.passes.station == s
        np.testing.assert_array_equal(geo.passes.t_start_s[mine], [600.0, 30000.0])
        np.testing.assert_array_equal(geo.passes.t_end_s[mine], [29400.0, 43200.0])
        np.testing.assert_array_equal(geo.passes.n_obs[mine], [2 * 49, 2 * 23])
        assert geo.pairs.n_obs[geo.pairs.station == s].sum() == 2 * 72
    ed = geo.editing
    np.testing.assert_array_equal(ed.scheduled_obs, [144, 144])
    np.testing.assert_array_equal(ed.removed_obs, np.zeros((2, len(EDITING_RULES))))
    np.testing.assert_array_equal(ed.added_passes, [1, 1])


def test_each_piece_of_a_split_pass_has_its_own_bias(geo: T13) -> None:
    """The bias part of AᵀWMWA is σ_b² Σ_pass (Σ_i w a_i)ᵀ(Σ_i w a_i) over the two passes
    cut by hand at 29400 / 30000 s; one 12 h pass would give another matrix."""
    raw = geo.raw
    sigma_b_km = GEO_BIAS_M * 1e-3
    for s in (1, 2):
        rows = (raw.station == s) & (raw.kind == raw.kinds.index("range"))
        wa = raw.weight[rows][:, None] * raw.A[rows]
        first = raw.t_s[rows] <= 29400.0
        sums = [wa[first].sum(axis=0), wa[~first].sum(axis=0)]
        expected = sigma_b_km**2 * sum(np.outer(v, v) for v in sums)
        bias = geo.pairs.Rt_parts[geo.pairs.station == s][0, 1]
        scaled_close(bias.T @ bias, expected, SUM_ORDER)
        one_pass = sigma_b_km**2 * np.outer(wa.sum(axis=0), wa.sum(axis=0))
        with pytest.raises(AssertionError):  # one 12 h pass: another matrix
            scaled_close(bias.T @ bias, one_pass, 0.1)


# --- every rule, counted by hand -------------------------------------------------------------

def _rise_set_s() -> tuple[float, float]:
    """Rise and set of a circular equatorial orbit over an equatorial station, two-body:
    visible while the central angle is below λ = arccos(R cos ε / a) - ε, which changes at
    n - ω_E (as in test_simulate's hand-checked geometry)."""
    n = math.sqrt(GM_EARTH_km3_s2 / HAND_A_KM**3)
    half = math.acos(WGS84_A_km * math.cos(math.radians(HAND_MASK_DEG)) / HAND_A_KM) \
        - math.radians(HAND_MASK_DEG)
    half_s = half / (n - OMEGA_EARTH_rad_s)
    return HAND_CENTRE_S - half_s, HAND_CENTRE_S + half_s


@pytest.fixture(scope="module")
def hand() -> T13:
    """:func:`hand_document` simulated."""
    return simulate(parse_scenario(hand_document(), "hand.toml")).tape


def test_each_rule_removes_what_is_counted_by_hand(hand: T13) -> None:
    """By hand, samples at 0, 60, ..., 6600 s (111); rise at 924.7 s, set at 5075.3 s.

    outside the tape: t = 0 and 6060..6600 (10): 11. In the tape, 60..6000 (100), above the
    mask 960..5040 (69): 31 below. EQ: blackout 1140, 1200, 1260: 3; then 960..1080 is a pass
    of 120 s < 300 s: 3 samples and 1 pass; 1320..5040 (63 samples, 3720 s) is split after
    2400 s into 1320..3720 (41) and 3780..5040 (22): 1 pass added. EQ2 (one observable): its
    69 samples above the mask all blacked out, 1 pass.
    """
    rise, set_ = _rise_set_s()
    assert 900.0 < rise < 960.0 and 5040.0 < set_ < 5100.0  # the premise of the counts
    ed = hand.editing
    assert ed.rule == EDITING_RULES == ("outside_tape", "elevation_mask", "blackout",
                                        "min_pass")
    np.testing.assert_array_equal(ed.scheduled_obs, [2 * 111, 111])
    np.testing.assert_array_equal(ed.removed_obs, [[2 * 11, 2 * 31, 2 * 3, 2 * 3],
                                                   [11, 31, 69, 0]])
    np.testing.assert_array_equal(ed.removed_passes, [[0, 0, 0, 1], [0, 0, 1, 0]])
    np.testing.assert_array_equal(ed.added_passes, [1, 0])
    np.testing.assert_array_equal(ed.kept_obs(hand.pairs), [2 * 63, 0])
    np.testing.assert_array_equal(hand.passes.station, [1, 1])
    np.testing.assert_array_equal(hand.passes.t_start_s, [1320.0, 3780.0])
    np.testing.assert_array_equal(hand.passes.t_end_s, [3720.0, 5040.0])
    np.testing.assert_array_equal(hand.passes.n_obs, [2 * 41, 2 * 22])


def test_a_schedule_with_no_observation_left_says_what_removed_them() -> None:
    with pytest.raises(InputError) as err:
        simulate(leo_scenario(tracking={"blackouts": [[0.0, 20000.0]]}))
    message = str(err.value)
    assert message.startswith("test_scenario.toml: tracking: expected a schedule")
    assert "0 observations kept of the 3246 scheduled over the stations" in message
    # 3 stations, 2 observables: t = 0 outside the tape; every sample above a mask blacked out
    assert "outside_tape 6, elevation_mask" in message and "min_pass 0" in message


def test_a_station_that_never_sees_the_spacecraft_is_a_warning_saying_what_removed_them(
        ) -> None:
    """The others have data: the run goes on, and says so (issue 28: it was silent), as a
    ΔDOR baseline with no point does (an error there: a baseline is asked for its points)."""
    sim = simulate(leo_scenario(**NORTH))
    assert sim.warnings == (
        "test_scenario.toml: tracking.stations[3]: NORTH yields no observation while other "
        "stations do (0 of its 1082 scheduled observations kept; removed: outside_tape 2, "
        "elevation_mask 1080, blackout 0, min_pass 0)",)
    assert simulate(leo_scenario()).warnings == ()
