"""CCSDS OEM 2.0 (KVN): the writer, the Lagrange interpolation it declares, and the states of a
simulation read back by the third-party ``oem`` package."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tapp.errors import InputError, TappError
from tapp.frames.time import parse_epoch
from tapp.io.ccsds.oem import (
    INTERPOLATION_DEGREE,
    INTERPOLATION_TOL_KM,
    INTERPOLATION_TOL_KM_S,
    format_oem,
    lagrange_interpolate,
    write_oem,
)
from tapp.tracking import oem_states as oem_module
from tapp.tracking.oem_states import oem_trajectory
from tests.tapp.tracking.helpers import leo_scenario

EPOCH = parse_epoch("2026-03-10T12:00:00")
# A polynomial of degree <= 7 through 8 nodes is reproduced to rounding (values ~1e3).
POLY_ROUNDING = 1e-9


def test_header_metadata_and_data_lines(tmp_path: Path) -> None:
    t = np.array([0.0, 60.0, 86400.5])
    x = np.arange(18.0).reshape(3, 6) + 7000.0
    text = format_oem(EPOCH, t, x, object_name="SC", object_id="2026-001A", ref_frame="GCRF",
                      interpolation="LAGRANGE", interpolation_degree=2, comments=("test",),
                      meta_comments=("how", "well"))
    lines = text.splitlines()
    # CCSDS 502.0-B-2 Table 5-2: header comments right after the version line
    assert lines[:2] == ["CCSDS_OEM_VERS = 2.0", "COMMENT test"]
    assert lines[2].startswith("CREATION_DATE = ")
    meta = lines[lines.index("META_START") + 1:lines.index("META_STOP")]
    assert meta == ["COMMENT how", "COMMENT well", "OBJECT_NAME = SC",
                    "OBJECT_ID = 2026-001A", "CENTER_NAME = EARTH", "REF_FRAME = GCRF",
                    "TIME_SYSTEM = UTC", "START_TIME = 2026-03-10T12:00:00.000000",
                    "STOP_TIME = 2026-03-11T12:00:00.500000", "INTERPOLATION = LAGRANGE",
                    "INTERPOLATION_DEGREE = 2"]
    data = [line.split() for line in lines[lines.index("META_STOP") + 2:]]
    assert [d[0] for d in data] == ["2026-03-10T12:00:00.000000", "2026-03-10T12:01:00.000000",
                                    "2026-03-11T12:00:00.500000"]
    np.testing.assert_allclose(np.array([d[1:] for d in data], dtype=float), x, rtol=0,
                               atol=1e-9)
    path = write_oem(tmp_path / "out.oem", text)
    assert path.read_text() == text and path.stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize(("t", "x", "frame", "method", "degree", "field"), [
    ([0.0, 0.0], np.zeros((2, 6)), "GCRF", "LAGRANGE", 1, "t_s"),
    ([0.0, 1.0], np.zeros((2, 5)), "GCRF", "LAGRANGE", 1, "states"),
    ([0.0, np.nan], np.zeros((2, 6)), "GCRF", "LAGRANGE", 1, "states"),
    ([0.0, 1.0], np.zeros((2, 6)), " ", "LAGRANGE", 1, "REF_FRAME"),
    ([0.0, 1.0], np.zeros((2, 6)), "GCRF", "SPLINE", 1, "INTERPOLATION"),
    ([0.0, 1.0], np.zeros((2, 6)), "GCRF", "LAGRANGE", 2, "INTERPOLATION_DEGREE"),
])
def test_bad_trajectories_are_refused(t, x, frame: str, method: str, degree: int,
                                      field: str) -> None:
    with pytest.raises(InputError) as err:
        format_oem(EPOCH, t, x, object_name="SC", object_id="X", ref_frame=frame,
                   interpolation=method, interpolation_degree=degree)
    assert err.value.field == field


def test_lagrange_is_exact_to_its_degree_and_no_further() -> None:
    rng = np.random.default_rng(7)
    nodes = np.cumsum(rng.uniform(0.5, 1.5, 20))
    at = np.concatenate([nodes[:1], rng.uniform(nodes[0], nodes[-1], 200), nodes[-1:]])
    coeffs = rng.normal(size=(INTERPOLATION_DEGREE + 1, 2))
    values = np.stack([np.polyval(c, nodes) for c in coeffs.T], axis=-1)
    exact = np.stack([np.polyval(c, at) for c in coeffs.T], axis=-1)
    got = lagrange_interpolate(nodes, values, at, INTERPOLATION_DEGREE)
    np.testing.assert_allclose(got, exact, rtol=0, atol=POLY_ROUNDING * np.abs(exact).max())
    higher = nodes ** (INTERPOLATION_DEGREE + 1)
    miss = lagrange_interpolate(nodes, higher[:, None], at, INTERPOLATION_DEGREE)[:, 0]
    assert np.abs(miss - at ** (INTERPOLATION_DEGREE + 1)).max() > 1e-3


def test_the_states_interpolate_to_their_tolerance_even_at_a_low_perigee() -> None:
    """An orbit of perigee 200 km and apogee 20000 km (altitudes), sampled every 300 s: the
    steps are halved around perigee only, and the interpolant holds everywhere (not only at
    the mid-points it was checked at)."""
    scenario = leo_scenario(injection={"r_km": None, "v_km_s": None, "a_km": 16478.137,
                                       "e": 0.6008, "i_deg": 30.0, "raan_deg": 0.0,
                                       "argp_deg": 0.0, "M_deg": 0.0},
                            tracking={"data_interval_s": 300.0})
    traj = oem_trajectory(scenario, 10800.0)
    assert traj.t_s[0] == 0.0 and traj.t_s[-1] == 10800.0
    assert traj.max_step_s == 300.0 and traj.min_step_s < 300.0
    np.testing.assert_array_equal(traj.states[0], scenario.x0)
    at = np.random.default_rng(3).uniform(0.0, 10800.0, 2000)
    at.sort()
    truth = scenario.propagator().propagate(scenario.x0, at, stm=False,
                                            orientation=scenario.orientation,
                                            epoch_jd_utc=scenario.epoch.jd).states
    err = np.abs(lagrange_interpolate(traj.t_s, traj.states, at, INTERPOLATION_DEGREE) - truth)
    assert err[:, :3].max() <= INTERPOLATION_TOL_KM
    assert err[:, 3:].max() <= INTERPOLATION_TOL_KM_S


def test_a_trajectory_that_needs_too_many_states_is_refused(monkeypatch) -> None:
    monkeypatch.setattr(oem_module, "MAX_STATES", 100)
    with pytest.raises(TappError, match=r"^test_scenario.toml: OEM: the trajectory needs more "
                                        r"than 100 states"):
        oem_trajectory(leo_scenario(), 10800.0)
