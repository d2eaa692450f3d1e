"""The geopotential under the IAU 2006 Earth orientation (the field rotates with the ITRS).

References are independent of the compiled path: the acceleration against central
differences of U(M(t) r) in NumPy with M straight from ERFA (no Chebyshev series, no CasADi
gradient); the pole-only zonal field against the full rotation; the STM against central
differences of whole propagations.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.constants import egm96_coefficients
from tapp.dynamics import Propagator, earth_model
from tapp.dynamics.forces import central_potential
from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import Epoch
from tests.tapp.dynamics.conftest import periapsis_state

EPOCH = Epoch.from_calendar(2026, 1, 1, 5, 17, 3.25)  # off 0h UTC on purpose
#: Acceleration vs central differences of the potential, h = 50 m: truncation
#: h² |∇³U| / 6 ~ 2.5e-3 · 1e-9 / 6 = 4e-13 and rounding ε U / h ~ 1.1e-16 · 57 / 0.05
#: = 1.3e-13 km/s²; allow 2e-12 km/s², 2e-10 of |a| and 2e-7 of the J2 part (a wrong pole,
#: 0.36 deg, would be off by 6e-3 of it).
ACC_KM_S2 = 2e-12
#: Pole-only and full rotation integrate the same field by different expressions: a day at
#: rtol 1e-13 agrees to 0.1 mm (measured 0.007 mm).
POLE_VS_FULL_KM = 1e-7
#: STM vs central differences of propagations (steps 1 m, 1 mm/s): 1e-6 relative per column.
STM_REL = 1e-6


@pytest.fixture(scope="module")
def orientation() -> EarthOrientation:
    return EarthOrientation.iau2006(EPOCH)


def _coefficients(degree: int, order: int) -> dict[tuple[str, int, int], float]:
    c_bar, s_bar = egm96_coefficients()
    out = {}
    for n in range(2, degree + 1):
        for m in range(0, min(n, order) + 1):
            out["C", n, m] = float(c_bar[n, m])
            if m:
                out["S", n, m] = float(s_bar[n, m])
    return out


@pytest.mark.parametrize("spec", ["J3", "4x4"])
def test_acceleration_is_the_gradient_of_the_rotated_potential(orientation, spec) -> None:
    model = earth_model(spec, earth_orientation="iau2006")
    prop = Propagator(model)
    eqs, _ = prop.compiled()
    coefficients = _coefficients(model.gravity.degree, model.gravity.order)
    gm = model.gm_center_km3_s2
    for t_s, r in ((0.0, np.array([7000.0, -1200.0, 2500.0])),
                   (50_000.0, np.array([-3000.0, 6100.0, -4200.0]))):
        table = orientation.series(t_s, t_s + 1.0, eqs.oriented)
        rb = table.evaluate([t_s])[:, 0, :].ravel()
        acc = np.asarray(eqs.f_state(t_s, np.concatenate([r, np.zeros(3)]), np.zeros(0),
                                     [orientation.theta0_rad], rb)).ravel()[3:]
        m = orientation.attitude_exact([t_s]).itrs_from_gcrs[0]

        def u(x: np.ndarray, m: np.ndarray = m) -> float:
            return float(central_potential(model, m @ x, gm, coefficients, np.sqrt))

        h = 0.05
        fd = np.array([(u(r + h * e) - u(r - h * e)) / (2 * h) for e in np.eye(3)])
        assert np.max(np.abs(acc - fd)) < ACC_KM_S2, acc - fd


def test_a_zonal_field_needs_only_the_pole(method: str, orientation) -> None:
    x0 = periapsis_state(7000.0, 0.01, 51.6, 30.0)
    t = np.linspace(0.0, 86400.0, 49)
    zonal = Propagator(earth_model("J2", earth_orientation="iau2006"), method=method)
    assert zonal.compiled()[0].oriented == "pole"
    names = ("C21", "S21", "C22", "S22")
    full = Propagator(earth_model("2x2", earth_orientation="iau2006"), params=names, method=method)
    assert full.compiled()[0].oriented == "full"
    a = zonal.propagate(x0, t, stm=False, orientation=orientation).states
    b = full.propagate(x0, t, stm=False, orientation=orientation,
                       param_values=dict.fromkeys(names, 0.0)).states
    assert np.max(np.abs(a[:, :3] - b[:, :3])) < POLE_VS_FULL_KM
    # and the orientation matters: the gmst pole is 0.36 deg from the CIP in 2026
    g = Propagator(earth_model("J2"), method=method).propagate(x0, t, stm=False,
                                                theta0_rad=EPOCH.gmst_rad()).states
    assert np.max(np.abs(a[:, :3] - g[:, :3])) > 0.1


@pytest.mark.parametrize("spec", ["J3", "4x4"])
def test_stm_against_central_differences(method: str, orientation, spec) -> None:
    model = earth_model(spec, earth_orientation="iau2006")
    prop = Propagator(model, method=method)
    x0 = periapsis_state(7200.0, 0.05, 30.0, 40.0, 50.0)
    t = np.array([21600.0])
    phi = prop.propagate(x0, t, orientation=orientation).stm[0]
    for j, h in enumerate([1e-3] * 3 + [1e-6] * 3):
        dx = np.zeros(6)
        dx[j] = h
        plus = prop.propagate(x0 + dx, t, stm=False, orientation=orientation).states[0]
        minus = prop.propagate(x0 - dx, t, stm=False, orientation=orientation).states[0]
        fd = (plus - minus) / (2 * h)
        assert np.linalg.norm(fd - phi[:, j]) < STM_REL * np.linalg.norm(phi[:, j]), j
