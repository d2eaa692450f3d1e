"""Ephemeris offsets (tapp.dynamics.ephemeris_offsets): the sensitivities to a constant
offset of the Moon's DE421 position along a lunar swing-by, against central differences of
the propagation with the offset applied, about the Earth throughout and with the
integration moved to the Moon for the day around the periapsis (the translations' ±E).

The trajectory is deep_space.toml's (injection 2026-03-10T12:00 UTC, periapsis ~2200 km from
the Moon's centre at 3.59 days), point masses of the Earth, Moon and Sun, to 4 days. An offset
of 1 km moves the state at 4 days by ~10 km (the swing-by's bending). Central differences
with steps of 0.03 km: their truncation, (h/r_p)² ~ 2e-10, and their noise, ~1e-9 km / h,
are below what separates them from the variational equations after the swing-by, the
integration's own error of the derivative at rtol 1e-13 (1.8e-8 of a column at the
periapsis, 7e-8 at 4 days, the same with steps of 0.1 km; at rtol 1e-14 rounding makes it
3e-7): the issue's 1e-7 holds, relative to each column's largest norm over the arc."""

import numpy as np
import pytest

from tapp.dynamics import Propagator
from tapp.dynamics.centres import CentreChange
from tapp.dynamics.ephemeris_offsets import offset_names, selector
from tapp.dynamics.spec import ForceModel, GravitySpec
from tapp.errors import InputError

JD_UTC = 2461110.0  # 2026-03-10T12:00 UTC
X0 = np.array([-3071.526044, 5152.940305, 2662.271974, -9.640685636421, -4.480280264441,
               -2.575159697447])
PERIAPSIS_s = 309958.384
T_s = np.array([2 * 86400.0, PERIAPSIS_s, 4 * 86400.0])
MOON = offset_names("moon")
STEP_km = 0.03
COLUMN = 1e-7


def _propagator(changes: tuple[CentreChange, ...] = ()) -> Propagator:
    model = ForceModel(GravitySpec(0, 0), "earth", ("moon", "sun"))
    return Propagator(model, model, MOON, rtol=1e-13, atol=1e-13, centre_changes=changes)


def _central_differences(prop: Propagator) -> np.ndarray:
    columns = []
    for name in MOON:
        plus, minus = (prop.propagate(X0, T_s, stm=False, epoch_jd_utc=JD_UTC,
                                      param_values={name: sign * STEP_km}).states
                       for sign in (1.0, -1.0))
        columns.append((plus - minus) / (2 * STEP_km))
    return np.stack(columns, axis=-1)


SWING_BY = (CentreChange(PERIAPSIS_s - 43200.0, "moon"),
            CentreChange(PERIAPSIS_s + 43200.0, "earth"))


@pytest.mark.parametrize("changes", [(), SWING_BY],
                         ids=["about the Earth", "about the Moon at the swing-by"])
def test_offset_sensitivities_match_central_differences(changes) -> None:
    """Each column against central differences, relative to its largest norm over the arc
    (measured 7.1e-8 about the Earth, 5.7e-8 with the Moon's interval)."""
    prop = _propagator(changes)
    traj = prop.propagate(X0, T_s, epoch_jd_utc=JD_UTC)
    fd = _central_differences(prop)
    scale = np.linalg.norm(fd, axis=1).max(axis=0)  # each column's largest norm
    assert scale.min() > 1.0  # a kilometre of the Moon moves the swing-by by kilometres
    error = np.linalg.norm(traj.sensitivity - fd, axis=1) / scale
    assert error.max() < COLUMN, error


def test_either_centre_sees_the_same_offset() -> None:
    """About the Earth throughout, or about the Moon for the day of the swing-by: the same
    physics of an offset Moon (the Moon-centred interval moves the other bodies by −δ, and the
    translations in and out carry ∓δ), so the two sensitivities agree to the two frames' own
    difference, far below the columns (measured 2.8e-7 of the column; the nominal
    trajectories differ by 2 m at the periapsis: DE421's Earth-Moon motion is not the model's
    Newtonian one). Had the indirect terms moved with δ the frames would differ by 2.5e-3 (the
    Moon's acceleration by the Earth, 7e-12 km/s² per km over the day)."""
    about_earth = _propagator().propagate(X0, T_s, epoch_jd_utc=JD_UTC).sensitivity
    about_moon = _propagator(SWING_BY).propagate(X0, T_s, epoch_jd_utc=JD_UTC).sensitivity
    scale = np.linalg.norm(about_earth, axis=1).max(axis=0)
    assert (np.linalg.norm(about_moon - about_earth, axis=1) / scale).max() < 1e-5


def test_the_translation_terms_are_there() -> None:
    """On the Moon's interval the outputs about the Earth carry +E; leaving out the
    translations' ±E (E the selector) would misplace S by the identity at the periapsis,
    far beyond the columns' agreement above."""
    params = MOON + ("GM_moon_km3_s2",)
    e = selector(params, "moon")
    assert e[:3, :3].tolist() == np.eye(3).tolist() and not e[3:].any() and not e[:, 3].any()
    assert not selector(params, "mars").any()


def test_offsets_of_a_body_the_model_has_not_are_refused() -> None:
    model = ForceModel(GravitySpec(0, 0), "earth", ("moon", "sun"))
    with pytest.raises(InputError):
        Propagator(model, model, ("dr_mars_x_km",)).propagate(X0, T_s[:1], epoch_jd_utc=JD_UTC)
