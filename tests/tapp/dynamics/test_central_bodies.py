"""The zonal J2 of the Moon, Mars and Venus as integration centres, about their IAU poles.

References, independent of the compiled path: the acceleration against central differences
of the potential (the shared recursion, evaluated in NumPy) and against the closed form
written here in NumPy; the secular node and periapsis rates of osculating elements against
first-order theory (Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed., 2013,
eq. 9-41); the STM against central differences of whole propagations.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.constants import J2_CENTRE, GM_km3_s2, J2_RADIUS_km
from tapp.dynamics import Propagator
from tapp.dynamics.forces import central_potential, default_parameters
from tapp.dynamics.poles import pole_ra_dec_deg, pole_unit
from tapp.dynamics.spec import ForceModel, parse_gravity
from tapp.errors import InputError
from tapp.orbit.elements import cartesian_to_elements
from tests.tapp.dynamics.conftest import periapsis_state

EPOCH_JD_UTC = 2461041.5  # 2026-01-01 00:00 UTC
EPOCH_JD_TDB = EPOCH_JD_UTC + 69.184 / 86400.0  # TAI - UTC = 37 s, TT - TAI = 32.184 s
#: Acceleration vs central differences of U, h = 50 m: truncation h² |∇³U| / 6 ~ 5e-13 and
#: rounding ε U / h ~ 5e-14 km/s² against |a| ~ 3e-3 km/s² at Mars: 2e-10 relative.
FD_REL = 1e-9
#: Acceleration vs the closed form: two expressions of the same field, rounding only.
DIRECT_REL = 1e-13
#: Secular rates vs first-order theory: the neglected terms are O(J2) ~ 2e-3 of the rates.
RATE_REL = 0.01
#: STM vs fourth-order central differences (five points) of propagations at rtol 1e-14,
#: steps 300 m and 0.3 m/s: the two-point difference found its best step at 10 m, 8.5e-8, a
#: narrow optimum between the integrator's noise (1 m: 8e-7) and its h² truncation (30 m:
#: 6e-7); the h⁴ truncation allows 30x larger steps, where the noise over h is 30x smaller:
#: measured 7.4e-9 (dop853) and 3.6e-9 (rkn12) of the worst column (100 m: 1.3e-8, 1.7e-9).
STM_REL = 1e-7


def _model(center: str, spec: str = "J2") -> ForceModel:
    return ForceModel(parse_gravity(spec), center=center)


def _acceleration(model: ForceModel, r: np.ndarray, k: np.ndarray) -> np.ndarray:
    eqs, _ = Propagator(model).compiled()
    assert eqs.oriented == "body_pole"
    out = eqs.f_state(0.0, np.concatenate([r, np.zeros(3)]), np.zeros(0), [0.0], k)
    return np.asarray(out).ravel()[3:]


def _direct(center: str, r: np.ndarray, k: np.ndarray) -> np.ndarray:
    """a = -μ r̂/r² - (3/2) J2 μ R²/r⁴ [(1 - 5 (r̂·k)²) r̂ + 2 (r̂·k) k]."""
    mu, j2, radius = GM_km3_s2[center], J2_CENTRE[center], J2_RADIUS_km[center]
    rn = np.linalg.norm(r)
    u = r / rn
    s = u @ k
    return -mu * u / rn**2 - 1.5 * j2 * mu * radius**2 / rn**4 * ((1 - 5 * s * s) * u
                                                                  + 2 * s * k)


@pytest.mark.parametrize("center", ["mars", "moon", "venus"])
def test_acceleration_is_the_gradient_of_the_potential_and_the_closed_form(center) -> None:
    model = _model(center)
    k = pole_unit(center, EPOCH_JD_TDB)[0]
    radius = J2_RADIUS_km[center]
    mu = GM_km3_s2[center]
    coefficients = {("C", 2, 0): -J2_CENTRE[center] / np.sqrt(5.0)}
    for r in (np.array([1.1, -0.2, 0.4]) * radius, np.array([-0.3, 0.5, -1.2]) * radius,
              radius * 1.05 * k):  # over the pole, where r̂·k = 1
        acc = _acceleration(model, r, k)

        def u(x: np.ndarray) -> float:
            return float(central_potential(model, np.array([0.0, 0.0, x @ k]), mu,
                                           coefficients, np.sqrt, r2=x @ x))

        h = 0.05 * radius / 3396.0
        fd = np.array([(u(r + h * e) - u(r - h * e)) / (2 * h) for e in np.eye(3)])
        scale = np.linalg.norm(acc)
        assert np.linalg.norm(acc - fd) < FD_REL * scale, (acc - fd) / scale
        assert np.linalg.norm(acc - _direct(center, r, k)) < DIRECT_REL * scale
        # the J2 part is there, with its sign: without it the closed form differs by J2 R²/r²
        kepler = -mu * r / np.linalg.norm(r) ** 3
        assert np.linalg.norm(acc - kepler) > 1e-3 * J2_CENTRE[center] * scale


def _equatorial_frame(k: np.ndarray) -> np.ndarray:
    """Columns: the body equator's ascending node on the ICRF equator (z × k), k × that, k
    (the IAU convention for the prime meridian's reference node)."""
    x = np.cross([0.0, 0.0, 1.0], k)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(k, x), k])


def _secular_rates(center: str, a_km: float, e: float, i_deg: float, days: float,
                   method: str) -> tuple[np.ndarray, np.ndarray]:
    """(measured, first-order) dΩ/dt and dω/dt (rad/s) of an orbit whose elements are
    given in the body's equatorial frame at the epoch: orbit averages of the osculating
    elements (64 samples an orbit), then a straight-line fit."""
    mu = GM_km3_s2[center]
    frame = _equatorial_frame(pole_unit(center, EPOCH_JD_TDB)[0])
    x_eq = periapsis_state(a_km, e, i_deg, 20.0, 30.0, mu=mu)
    x0 = np.concatenate([frame @ x_eq[:3], frame @ x_eq[3:]])
    period = 2 * np.pi * np.sqrt(a_km**3 / mu)
    n_orbits = int(days * 86400.0 / period)
    t = np.arange(n_orbits * 64) * period / 64
    traj = Propagator(_model(center), method=method).propagate(x0, t, stm=False,
                                                               epoch_jd_utc=EPOCH_JD_UTC)
    states_eq = np.concatenate([traj.states[:, :3] @ frame, traj.states[:, 3:] @ frame], axis=1)
    el = cartesian_to_elements(states_eq, mu)
    node = np.unwrap(el[:, 3]).reshape(n_orbits, 64).mean(axis=1)
    argp = np.unwrap(el[:, 4]).reshape(n_orbits, 64).mean(axis=1)
    a_mean = el[:, 0].mean()
    e_mean = el[:, 1].mean()
    i_mean = el[:, 2].mean()
    t_mid = t.reshape(n_orbits, 64).mean(axis=1)
    measured = np.array([np.polyfit(t_mid, node, 1)[0], np.polyfit(t_mid, argp, 1)[0]])
    # Vallado eq. 9-41, first order in J2
    n = np.sqrt(mu / a_mean**3)
    factor = n * J2_CENTRE[center] * (J2_RADIUS_km[center] / (a_mean * (1 - e_mean**2))) ** 2
    theory = np.array([-1.5 * factor * np.cos(i_mean),
                       0.75 * factor * (5 * np.cos(i_mean) ** 2 - 1)])
    return measured, theory


def test_low_mars_orbit_node_and_periapsis_rates_follow_first_order_j2(method: str) -> None:
    """a = 3800 km, e = 0.01, i = 60° to Mars's equator, 10 days, no third bodies: measured
    rel. differences 3.0e-4 (node, -5.14°/day) and 2.0e-3 (periapsis, +1.29°/day), both
    methods."""
    measured, theory = _secular_rates("mars", 3800.0, 0.01, 60.0, 10.0, method)
    assert np.all(np.abs(measured / theory - 1) < RATE_REL), measured / theory - 1


def test_low_lunar_orbit_node_rate_follows_first_order_j2() -> None:
    """100 km, i = 75°, 10 days: J2 only (the Moon's C22, a tenth of J2, and its mascons are
    absent here; a real low lunar orbit is dominated by them). The pole moves under the
    orbit (the IAU series: ~0.004°/day); measured rel. difference 1.1e-4 (-0.31°/day)."""
    measured, theory = _secular_rates("moon", 1838.0, 0.001, 75.0, 10.0, "dop853")
    assert abs(measured[0] / theory[0] - 1) < RATE_REL, measured[0] / theory[0] - 1


def test_stm_of_a_low_mars_orbit_matches_central_differences(method: str) -> None:
    x0 = periapsis_state(3800.0, 0.01, 60.0, mu=GM_km3_s2["mars"])
    prop = Propagator(_model("mars"), rtol=1e-14, atol=1e-14, method=method)
    t = np.array([86400.0])
    phi = prop.propagate(x0, t, epoch_jd_utc=EPOCH_JD_UTC).stm[-1]
    steps = np.array([0.3] * 3 + [3e-4] * 3)

    def final(x: np.ndarray) -> np.ndarray:
        return prop.propagate(x, t, stm=False, epoch_jd_utc=EPOCH_JD_UTC).states[-1]

    for j in range(6):
        dx = np.zeros(6)
        dx[j] = steps[j]
        fd = (8.0 * (final(x0 + dx) - final(x0 - dx))
              - (final(x0 + 2 * dx) - final(x0 - 2 * dx))) / (12.0 * steps[j])
        err = np.linalg.norm(phi[:, j] - fd) / np.linalg.norm(phi[:, j])
        assert err < STM_REL, (j, err)


def test_j2_is_a_parameter_of_the_centre() -> None:
    assert default_parameters(_model("mars"), ("J2", "GM_km3_s2")) == {
        "J2": J2_CENTRE["mars"], "GM_km3_s2": GM_km3_s2["mars"]}
    with pytest.raises(InputError, match="parameters"):
        default_parameters(_model("mars"), ("C20",))
    with pytest.raises(InputError, match="parameters"):
        default_parameters(_model("mars", "J0"), ("J2",))


@pytest.mark.parametrize(("center", "spec", "accepted"), [
    ("mars", "J3", "J0 or J2 for centre mars"),
    ("mars", "2x2", "J0 or J2 for centre mars"),
    ("moon", "J4", "J0 or J2 for centre moon"),
    ("sun", "J2", "J0 for centre sun"),
    ("jupiter", "J2", "J0 for centre jupiter"),
])
def test_fields_beyond_the_shipped_j2_are_refused(center, spec, accepted) -> None:
    with pytest.raises(InputError, match=accepted) as err:
        _model(center, spec)
    assert err.value.field == "gravity"


def test_a_moving_pole_needs_an_epoch() -> None:
    with pytest.raises(InputError, match="epoch"):
        Propagator(_model("venus")).propagate(periapsis_state(
            6500.0, 0.0, 30.0, mu=GM_km3_s2["venus"]), [60.0])


def test_constants_follow_their_normalised_c20() -> None:
    """J2 = -sqrt(5) C20: GL0660B's C20 = -9.0880e-5; GMM-3's -8.7450e-4 within 5e-6 of
    MRO120D's J2."""
    assert J2_CENTRE["moon"] == pytest.approx(np.sqrt(5) * 9.0880e-5, rel=1e-15)
    assert J2_CENTRE["mars"] == pytest.approx(np.sqrt(5) * 8.7450e-4, rel=5e-6)


def test_poles_at_j2000_are_the_iau_values() -> None:
    """At J2000 (T = 0) the series reduce to their constants plus periodic terms at their
    phases: Mars 317.681°, 52.886° (the IAU 2009 constants, which the 2015 long-period
    terms reproduce); the Moon 266.858°, 65.641° (E1 = 125.045°)."""
    alpha, delta = pole_ra_dec_deg("mars", 2451545.0)
    assert (alpha[0], delta[0]) == pytest.approx((317.681, 52.886), abs=1e-3)
    alpha, delta = pole_ra_dec_deg("moon", 2451545.0)
    assert (alpha[0], delta[0]) == pytest.approx((266.858, 65.641), abs=1e-3)
