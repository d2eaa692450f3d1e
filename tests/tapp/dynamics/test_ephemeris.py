"""DE421 access, time scales and the Chebyshev tables the compiled driver evaluates."""

from __future__ import annotations

import numpy as np
import pytest

from tapp.constants import AU_km
from tapp.dynamics import Propagator
from tapp.dynamics.ephemeris import chebyshev_table, position_km, tai_minus_utc_s, utc_to_tdb_jd
from tapp.dynamics.spec import earth_model
from tapp.errors import InputError
from tests.tapp.dynamics.conftest import periapsis_state

JD_2026 = 2461041.5  # 2026-01-01T00:00 UTC
ONE_METRE_km = 1e-3


def test_leap_seconds_and_tdb_offset() -> None:
    assert tai_minus_utc_s(JD_2026) == 37.0
    assert tai_minus_utc_s(2451544.5) == 32.0  # 2000-01-01: 32 s (IERS Bulletin C)
    # TT - UTC = 37 + 32.184 s; one float JD resolves ~40 us
    assert (utc_to_tdb_jd(JD_2026) - JD_2026) * 86400.0 == pytest.approx(69.184, abs=1e-4)
    with pytest.raises(InputError, match="1972"):
        tai_minus_utc_s(2440000.5)


def test_geocentric_distances_are_physical() -> None:
    jd, days = utc_to_tdb_jd(JD_2026), np.arange(0.0, 30.0)
    moon = np.linalg.norm(position_km("moon", "earth", jd, days), axis=1)
    sun = np.linalg.norm(position_km("sun", "earth", jd, days), axis=1)
    assert moon.min() > 356_000 and moon.max() < 407_000  # perigee/apogee bounds of the Moon
    assert np.all(np.abs(sun / AU_km - 1) < 0.0175)  # Earth's orbit e = 0.0167


def _eval_table(table, t_s: np.ndarray) -> np.ndarray:
    u = (t_s - table.t0_s) / table.h_s
    seg = np.minimum(np.floor(u).astype(int), table.n_segments - 1)
    tau = 2 * (u - seg) - 1
    return np.stack([np.polynomial.chebyshev.chebval(tau[k], table.coeffs[0, seg[k]].T)
                     for k in range(len(t_s))])


@pytest.mark.parametrize("body", ["moon", "sun"])
def test_chebyshev_table_reproduces_de421(body: str) -> None:
    table = chebyshev_table((body,), "earth", JD_2026, 0.0, 5 * 86400.0)
    t = np.linspace(0.0, 5 * 86400.0, 997)
    ref = position_km(body, "earth", utc_to_tdb_jd(JD_2026), t / 86400.0)
    assert np.abs(_eval_table(table, t) - ref).max() < ONE_METRE_km


def test_lunisolar_stm_matches_central_differences(method: str) -> None:
    model = earth_model("J2", ("sun", "moon"))
    prop = Propagator(model, method=method)
    x0 = periapsis_state(42164.0, 0.001, 5.0)
    t = np.array([0.0, 2 * 86400.0])
    kw = dict(epoch_jd_utc=JD_2026)
    phi = prop.propagate(x0, t, **kw).stm[-1]
    delta = np.array([1e-1] * 3 + [1e-5] * 3)
    fd = np.empty((6, 6))
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = delta[j]
        fd[:, j] = (prop.propagate(x0 + dx, t, stm=False, **kw).states[-1]
                    - prop.propagate(x0 - dx, t, stm=False, **kw).states[-1]) / (2 * delta[j])
    rel = np.linalg.norm(phi - fd, axis=0) / np.linalg.norm(fd, axis=0)
    assert rel.max() < 1e-6
    # the Moon and Sun move a GEO satellite by kilometres in two days
    two_body = Propagator(earth_model("J2"), method=method).propagate(x0, t, stm=False).states[-1]
    shift = np.linalg.norm(prop.propagate(x0, t, stm=False, **kw).states[-1][:3] - two_body[:3])
    assert 1.0 < shift < 100.0


def test_third_bodies_need_an_epoch() -> None:
    prop = Propagator(earth_model("J0", ("moon",)))
    with pytest.raises(InputError, match="epoch"):
        prop.propagate(periapsis_state(7000.0, 0.0, 0.0), [0.0, 60.0])
