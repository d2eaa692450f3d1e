"""Propagation: STM and sensitivities vs finite differences, composition, symplecticity,
conservation laws, J2 secular rates and the two-body Kepler solution."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

from tapp.constants import GM_EARTH_km3_s2, OMEGA_EARTH_rad_s, R_EARTH_km, unnormalised_zonal_j
from tapp.dynamics import Propagator, earth_model
from tapp.dynamics.forces import central_potential, field_coefficients
from tests.tapp.dynamics.conftest import periapsis_state

MU = GM_EARTH_km3_s2
ONE_MM_km = 1e-6
# STM columns vs central differences: step 10 m / 1 cm/s keeps truncation error (~(δ/r)^2)
# and integration noise (~1e-11 km / δ) both below 1e-8 relative; the issue asks < 1e-6.
STM_REL = 1e-6
DELTA = np.array([1e-2, 1e-2, 1e-2, 1e-5, 1e-5, 1e-5])
TIGHT = dict(rtol=1e-13, atol=1e-13)


def _fd_stm(prop: Propagator, x0: np.ndarray, t_s: np.ndarray, **kw) -> np.ndarray:
    cols = []
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = DELTA[j]
        plus = prop.propagate(x0 + dx, t_s, stm=False, **kw).states[-1]
        minus = prop.propagate(x0 - dx, t_s, stm=False, **kw).states[-1]
        cols.append((plus - minus) / (2 * DELTA[j]))
    return np.array(cols).T


@pytest.mark.parametrize("spec", ["J2", "5x5"])
@pytest.mark.parametrize("i_deg", [0.0, 30.0, 98.0])
@pytest.mark.parametrize("e", [0.0, 0.3])
def test_stm_matches_central_differences(method: str, spec: str, i_deg: float, e: float) -> None:
    a = 6550.524 if e == 0 else 9357.89143
    x0 = periapsis_state(a, e, i_deg, raan_deg=20.0, argp_deg=40.0)
    prop = Propagator(earth_model(spec), **TIGHT, method=method)
    t = np.array([0.0, 3 * 3600.0])
    phi = prop.propagate(x0, t, theta0_rad=0.7).stm[-1]
    fd = _fd_stm(prop, x0, t, theta0_rad=0.7)
    rel = np.linalg.norm(phi - fd, axis=0) / np.linalg.norm(fd, axis=0)
    assert rel.max() < STM_REL, rel


def test_stm_at_t0_is_identity_and_composes(method: str) -> None:
    prop = Propagator(earth_model("4x4"), **TIGHT, method=method)
    x0 = periapsis_state(7000.0, 0.05, 51.6)
    t1, t2 = 2000.0, 5000.0
    tr = prop.propagate(x0, [0.0, t1, t2])
    np.testing.assert_array_equal(tr.stm[0], np.eye(6))
    second = prop.propagate(tr.states[1], [t2], t0_s=t1)
    composed = second.stm[-1] @ tr.stm[1]
    assert np.abs(composed - tr.stm[2]).max() < 1e-9 * np.abs(tr.stm[2]).max()
    np.testing.assert_allclose(second.states[-1], tr.states[2], rtol=0, atol=ONE_MM_km)


@pytest.mark.parametrize(("state_spec", "var_spec"),
                         [("J2", "J2"), ("J2", "J0"), ("5x5", "5x5"), ("5x5", "J2")])
def test_stm_is_symplectic(method: str, state_spec: str, var_spec: str) -> None:
    """Φᵀ Γ Φ = Γ for any Hamiltonian variational model, truncated ones included."""
    prop = Propagator(earth_model(state_spec), earth_model(var_spec), **TIGHT, method=method)
    x0 = periapsis_state(6550.524, 0.0, 30.0)
    phi = prop.propagate(x0, np.linspace(0, 86400.0, 5)).stm
    gamma = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    defect = np.einsum("kji,jl,klm->kim", phi, gamma, phi) - gamma
    # Normalised by |Φ|^2, the scale of the products whose cancellation leaves Γ.
    scale = np.abs(phi).max(axis=(1, 2)) ** 2
    assert (np.abs(defect).max(axis=(1, 2)) / scale).max() < 1e-9


def _potential(spec: str) -> ca.Function:
    model = earth_model(spec)
    r = ca.SX.sym("r", 3)
    return ca.Function("u", [r], [central_potential(model, r, MU, field_coefficients(model, {}))])


def test_energy_conserved_zonal_field(method: str) -> None:
    prop = Propagator(earth_model("J4"), method=method)
    x0 = periapsis_state(7278.36, 0.1, 45.0)
    tr = prop.propagate(x0, np.linspace(0, 86400.0, 97), stm=False)
    u = np.array(_potential("J4").map(tr.states.shape[0])(tr.states[:, :3].T)).ravel()
    energy = 0.5 * np.sum(tr.states[:, 3:] ** 2, axis=1) - u
    assert np.abs(energy / energy[0] - 1).max() < 1e-10


def test_jacobi_integral_conserved_tesseral_field(method: str) -> None:
    """C = v²/2 - U(R3(θ) r) - ω (x v_y - y v_x) is constant in a uniformly rotating field."""
    theta0 = 1.1
    prop = Propagator(earth_model("5x5"), method=method)
    x0 = periapsis_state(6800.0, 0.02, 63.0, raan_deg=10.0)
    tr = prop.propagate(x0, np.linspace(0, 86400.0, 97), stm=False, theta0_rad=theta0)
    th = theta0 + OMEGA_EARTH_rad_s * tr.t_s
    r = tr.states[:, :3]
    r_fixed = np.stack([np.cos(th) * r[:, 0] + np.sin(th) * r[:, 1],
                        -np.sin(th) * r[:, 0] + np.cos(th) * r[:, 1], r[:, 2]])
    u = np.array(_potential("5x5").map(r.shape[0])(r_fixed)).ravel()
    v = tr.states[:, 3:]
    jacobi = 0.5 * np.sum(v**2, axis=1) - u - OMEGA_EARTH_rad_s * (r[:, 0] * v[:, 1]
                                                                   - r[:, 1] * v[:, 0])
    assert np.abs(jacobi / jacobi[0] - 1).max() < 1e-10


def _raan_argp(states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r, v = states[:, :3], states[:, 3:]
    h = np.cross(r, v)
    node = np.stack([-h[:, 1], h[:, 0], np.zeros(len(h))], axis=1)
    e_vec = np.cross(v, h) / MU - r / np.linalg.norm(r, axis=1)[:, None]
    raan = np.unwrap(np.arctan2(h[:, 0], -h[:, 1]))
    cos_w = np.sum(node * e_vec, axis=1) / (np.linalg.norm(node, axis=1)
                                             * np.linalg.norm(e_vec, axis=1))
    sin_w = np.sum(np.cross(node, e_vec) * h, axis=1) / (
        np.linalg.norm(node, axis=1) * np.linalg.norm(e_vec, axis=1) * np.linalg.norm(h, axis=1))
    return raan, np.unwrap(np.arctan2(sin_w, cos_w))


@pytest.mark.parametrize("i_deg", [30.0, 63.4, 98.0])
def test_j2_secular_rates_match_first_order_theory(method: str, i_deg: float) -> None:
    """Ω̇ = -3/2 k cos i, ω̇ = 3/4 k (5 cos² i - 1), k = n J2 (R/p)² (Vallado eq. 9-41).

    Osculating Ω and ω are averaged over each revolution (100 samples per period), which
    removes the first-order short-period terms, and a line is fitted to the averages over
    10 days. First-order theory neglects O(J2²) terms and the mean/osculating difference in
    a, e (relative O(J2) ~ 1e-3): both rates must agree to 1% of k, the natural rate scale
    (ω̇ itself vanishes at the critical inclination 63.4 deg).
    """
    a, e = 7278.36, 0.1
    x0 = periapsis_state(a, e, i_deg, raan_deg=30.0, argp_deg=60.0)
    n = math.sqrt(MU / a**3)
    period = 2 * math.pi / n
    per_rev = 100
    t = np.arange(0.0, 10 * 86400.0, period / per_rev)
    tr = Propagator(earth_model("J2"), method=method).propagate(x0, t, stm=False)
    raan, argp = _raan_argp(tr.states)
    revs = len(t) // per_rev
    windows = slice(0, revs * per_rev)
    t_mean = t[windows].reshape(revs, per_rev).mean(axis=1)
    raan_dot = np.polyfit(t_mean, raan[windows].reshape(revs, per_rev).mean(axis=1), 1)[0]
    argp_dot = np.polyfit(t_mean, argp[windows].reshape(revs, per_rev).mean(axis=1), 1)[0]
    j2 = unnormalised_zonal_j(2)
    k = n * j2 * (R_EARTH_km / (a * (1 - e**2))) ** 2
    cos_i = math.cos(math.radians(i_deg))
    assert abs(raan_dot - (-1.5 * k * cos_i)) < 0.01 * k
    assert abs(argp_dot - 0.75 * k * (5 * cos_i**2 - 1)) < 0.01 * k


def test_two_body_matches_kepler_solution(method: str) -> None:
    a, e = 9357.89143, 0.3
    x0 = periapsis_state(a, e, 0.0)
    t = np.linspace(0.0, 86400.0, 49)
    tr = Propagator(earth_model("J0"), **TIGHT, method=method).propagate(x0, t, stm=False)
    n = math.sqrt(MU / a**3)
    ecc_anom = [brentq(lambda E, M=n * tk: E - e * math.sin(E) - M, n * tk - 1.0, n * tk + 1.0,
                       xtol=1e-15) for tk in t]
    ecc_anom = np.array(ecc_anom)
    b = a * math.sqrt(1 - e**2)
    ref = np.stack([a * (np.cos(ecc_anom) - e), b * np.sin(ecc_anom)], axis=1)
    err = np.linalg.norm(tr.states[:, :2] - ref, axis=1)
    assert err.max() < ONE_MM_km
    assert np.abs(tr.states[:, 2]).max() == 0.0


def test_truncated_variational_model_changes_stm_not_trajectory(method: str) -> None:
    x0 = periapsis_state(6550.524, 0.0, 0.0)
    t = np.linspace(0, 86400.0, 25)
    full = Propagator(earth_model("J2"), earth_model("J2"), method=method).propagate(x0, t)
    trunc = Propagator(earth_model("J2"), earth_model("J0"), method=method).propagate(x0, t)
    np.testing.assert_array_equal(full.states, trunc.states)
    rel = np.abs(full.stm[-1] - trunc.stm[-1]).max() / np.abs(full.stm[-1]).max()
    assert rel > 1e-2


def test_parameter_sensitivities_match_central_differences(method: str) -> None:
    params = ("GM_km3_s2", "J2", "C22", "S22")
    prop = Propagator(earth_model("4x4"), params=params, **TIGHT, method=method)
    x0 = periapsis_state(7000.0, 0.1, 40.0)
    t = np.array([0.0, 4 * 3600.0])
    tr = prop.propagate(x0, t, theta0_rad=0.3)
    nominal = dict(zip(params, [MU, unnormalised_zonal_j(2), 0.0, 0.0], strict=True))
    nominal.update({k: v for k, v in prop._nominal.items() if k in ("C22", "S22")})
    steps = {"GM_km3_s2": 1e-2, "J2": 1e-7, "C22": 1e-7, "S22": 1e-7}
    for j, name in enumerate(params):
        hi = prop.propagate(x0, t, stm=False, theta0_rad=0.3,
                            param_values={name: nominal[name] + steps[name]}).states[-1]
        lo = prop.propagate(x0, t, stm=False, theta0_rad=0.3,
                            param_values={name: nominal[name] - steps[name]}).states[-1]
        fd = (hi - lo) / (2 * steps[name])
        col = tr.sensitivity[-1, :, j]
        assert np.linalg.norm(col - fd) < 1e-6 * np.linalg.norm(fd), name
