"""Station locations as full 3 x 3 a priori blocks with correlations between stations
(``[real.apriori.stations]`` / ``[fit.apriori.stations]``: :mod:`tapp.processor.station_apriori`,
files :mod:`tapp.io.station_covariance`).

References, all written here independently of the package:

- the map of the tape's parameters from Earth-fixed metres, exactly: r_s = hypot(x, y),
  lon = atan2(y, x), z (km), and its Jacobian by central differences;
- the common-frame error as a 7-parameter Helmert transformation with an exact rotation
  (Rodrigues' formula), δr = T + (Rot(θ) − I) r + s r;
- a Monte Carlo of Cartesian draws (local errors plus frame errors) through the exact maps,
  against the first-order covariance the package builds: every entry's |z| < 5;
- TAPP III on the LEO test tape against the closed form of the regression from the tape's raw
  rows: e = (I − K A) δx − K δm, K = (S₀ + AᵀWA)⁻¹AᵀW, so
  Λ' = (I − K A) Λ̄ (I − K A)ᵀ + K M Kᵀ (the consider covariance of a fit that estimates all
  parameters with white weights W against the real noise M and the real a priori Λ̄).

The SINEX excerpt (``_SINEX``) is written for these tests: plausible ITRF positions of DSS-14,
DSS-43 and DSS-63 (to ~1 m) with made-up mm-level σ's and correlations, not a published
solution.
"""

from __future__ import annotations

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.io.station_covariance import parse_csv, parse_sinex, read_station_covariance
from tapp.processor.station_apriori import (
    RAD_PER_MAS,
    frame_partials,
    parameter_covariance,
    parameter_jacobian,
)
from tests.tapp.processor.helpers import (
    deck,
    final,
    leo_tape,
    run,
    scaled_err,
    segment_factors,
    sigmas,
)

#: Approximate ITRF positions of three DSN antennas, m (Goldstone, Canberra, Madrid).
DSN_M = {"DS14": (-2353621.4, -4641341.5, 3677052.3),
         "DS43": (-4460894.9, 2682361.5, -3674748.1),
         "DS63": (4849092.5, -360180.3, 4115109.3)}
#: Monte Carlo draws, and the bound on every entry's |z| (Gaussian sample covariance).
N_DRAWS = 40_000
Z_LIMIT = 5.0
#: Central differences of the parameter map with a 10 m step: truncation (h/r)² ~ 3e-12,
#: rounding ε r/h ~ 1e-10 of the derivative: 1e-8 bounds both with margin.
CENTRAL_REL = 1e-8
#: A covariance mapped by :func:`_mapped` (central differences with 100 m steps: rounding
#: ε r/h ~ 1.4e-11, truncation (h/r)² ~ 2.5e-10 of each derivative) against the package's
#: analytic map: measured 1.8e-10 (the SINEX excerpt at k = 0).
MAPPED = 1e-8
#: TAPP III (the tape's square-root factors, sequential) against the closed form from the
#: raw rows, on the scale √(C_ii C_jj): both in float64 from the same rows, Λ̄ through
#: :func:`_mapped`; measured 3.8e-10 (real world), 4.0e-10 (fit world) (the diagonal a priori
#: of the same σ's is 0.27-0.39 away).
CLOSED_FORM = 1e-8
#: Largest |Σ source variances − total| / total of an error budget: measured 1.9e-14.
BUDGET = 1e-12

_SINEX = """%=SNX 2.02 TST 26:100:00000 TST 26:100:00000 26:100:00000 P 00009 2 S
* Written for tests/tapp/processor/test_station_covariance.py: not a published solution.
+SOLUTION/ESTIMATE
*INDEX TYPE__ CODE PT SOLN _REF_EPOCH__ UNIT S __ESTIMATED VALUE____ _STD_DEV___
     1 STAX   DS14  A    1 26:100:00000 m    2 -2.35362140000000e+06 3.00000e-03
     2 STAY   DS14  A    1 26:100:00000 m    2 -4.64134150000000e+06 4.00000e-03
     3 STAZ   DS14  A    1 26:100:00000 m    2  3.67705230000000e+06 5.00000e-03
     4 VELX   DS14  A    1 26:100:00000 m/y  2 -1.00000000000000e-02 1.00000e-04
     5 STAX   DS43  A    1 26:100:00000 m    2 -4.46089490000000e+06 3.00000e-03
     6 STAY   DS43  A    1 26:100:00000 m    2  2.68236150000000e+06 3.00000e-03
     7 STAZ   DS43  A    1 26:100:00000 m    2 -3.67474810000000e+06 4.00000e-03
     8 STAX   DS63  A    1 26:100:00000 m    2  4.84909250000000e+06 4.00000e-03
     9 STAY   DS63  A    1 26:100:00000 m    2 -3.60180300000000e+05 2.00000e-03
    10 STAZ   DS63  A    1 26:100:00000 m    2  4.11510930000000e+06 4.00000e-03
-SOLUTION/ESTIMATE
+SOLUTION/MATRIX_ESTIMATE L COVA
*PARA1 PARA2 ____PARA2+0__________ ____PARA2+1__________ ____PARA2+2__________
     1     1  9.00000000000000e-06
     2     1  3.60000000000000e-06  1.60000000000000e-05
     3     1 -1.50000000000000e-06  4.00000000000000e-06  2.50000000000000e-05
     4     1  1.00000000000000e-09  0.00000000000000e+00  0.00000000000000e+00
     4     4  1.00000000000000e-08
     5     1  2.70000000000000e-06  0.00000000000000e+00  0.00000000000000e+00
     5     4  0.00000000000000e+00  9.00000000000000e-06
     6     1  0.00000000000000e+00  1.20000000000000e-06  0.00000000000000e+00
     6     4  0.00000000000000e+00  1.80000000000000e-06  9.00000000000000e-06
     7     1  0.00000000000000e+00  0.00000000000000e+00  4.00000000000000e-06
     7     4  0.00000000000000e+00 -2.40000000000000e-06  3.60000000000000e-06
     7     7  1.60000000000000e-05
     8     1  1.20000000000000e-06  0.00000000000000e+00  0.00000000000000e+00
     8     4  0.00000000000000e+00  1.20000000000000e-06  0.00000000000000e+00
     8     7  0.00000000000000e+00  1.60000000000000e-05
     9     8  8.00000000000000e-07  4.00000000000000e-06
    10     8  4.80000000000000e-06  0.00000000000000e+00  1.60000000000000e-05
-SOLUTION/MATRIX_ESTIMATE L COVA
%ENDSNX
"""


def _sinex_matrix() -> np.ndarray:
    """The excerpt's station covariance, m², written out (rows DS14 x y z, DS43, DS63)."""
    c = np.zeros((9, 9))
    lower = {(0, 0): 9e-6, (1, 0): 3.6e-6, (1, 1): 1.6e-5, (2, 0): -1.5e-6, (2, 1): 4e-6,
             (2, 2): 2.5e-5, (3, 0): 2.7e-6, (3, 3): 9e-6, (4, 1): 1.2e-6, (4, 3): 1.8e-6,
             (4, 4): 9e-6, (5, 2): 4e-6, (5, 3): -2.4e-6, (5, 4): 3.6e-6, (5, 5): 1.6e-5,
             (6, 0): 1.2e-6, (6, 3): 1.2e-6, (6, 6): 1.6e-5, (7, 6): 8e-7, (7, 7): 4e-6,
             (8, 6): 4.8e-6, (8, 8): 1.6e-5}
    for (i, j), v in lower.items():
        c[i, j] = c[j, i] = v
    return c


# --- the maps, independently ----------------------------------------------------------------


def _exact(r_m: np.ndarray, parameters: str) -> np.ndarray:
    """The tape's location parameters (km, rad) of Earth-fixed positions (..., 3), m."""
    x, y, z = np.moveaxis(np.asarray(r_m) / 1000.0, -1, 0)
    if parameters == "cylindrical":
        return np.stack([np.hypot(x, y), np.arctan2(y, x), z], axis=-1)
    return np.stack([x, y, z], axis=-1)


def _rotation(theta: np.ndarray) -> np.ndarray:
    """Rot(θ) (..., 3, 3), the rotation by |θ| about θ (Rodrigues), v ↦ v + θ × v + ..."""
    angle = np.linalg.norm(theta, axis=-1)[..., None, None]
    k = theta / np.where(angle[..., 0] > 0, angle[..., 0], 1.0)
    kx = np.zeros(theta.shape[:-1] + (3, 3))
    kx[..., 0, 1], kx[..., 0, 2], kx[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    kx = kx - np.swapaxes(kx, -1, -2)
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx


def _helmert(r_m: np.ndarray, f: np.ndarray) -> np.ndarray:
    """δr (m) of a station at r (3,) by frame errors f (..., 7) = (T m, θ rad, s)."""
    return f[..., :3] + np.einsum("...ij,j->...i", _rotation(f[..., 3:6]) - np.eye(3), r_m) \
        + f[..., 6:7] * r_m


@pytest.mark.parametrize("parameters", ["cylindrical", "ecef"])
@pytest.mark.parametrize("site", sorted(DSN_M))
def test_parameter_jacobian_is_the_central_difference_of_the_exact_map(site, parameters):
    r = np.array(DSN_M[site])
    h = 10.0
    numeric = np.stack([(_exact(r + h * e, parameters) - _exact(r - h * e, parameters))
                        / (2 * h) for e in np.eye(3)], axis=-1)
    got = parameter_jacobian(r / 1000.0, parameters)
    scale = np.max(np.abs(numeric), axis=1, keepdims=True)
    assert np.max(np.abs(got - numeric) / scale) < CENTRAL_REL


def test_frame_partials_are_the_central_difference_of_the_helmert_transformation():
    """H = ∂δr/∂(T, θ, s) at f = 0 against the exact transformation, steps 1 mm, 1e-9 rad,
    1e-9: the second-order terms are ~|θ|² r = 6e-12 m of the 6e-3 m differences."""
    for r in map(np.array, DSN_M.values()):
        steps = np.array([1e-3] * 3 + [1e-9] * 4)
        numeric = np.stack([(_helmert(r, s * e) - _helmert(r, -s * e)) / (2 * s)
                            for s, e in zip(steps, np.eye(7), strict=True)], axis=-1)
        got = frame_partials(r / 1000.0)
        assert np.max(np.abs(got - numeric) / np.max(np.abs(numeric))) < CENTRAL_REL


def test_first_order_covariance_matches_a_monte_carlo_of_the_exact_maps():
    """Local errors (the SINEX excerpt, 3-5 mm, correlated across complexes) plus a frame
    error (T 2 cm, θ 0.5 mas, s 1 ppb) through the exact Helmert transformation and the exact
    parameter maps (DS14, DS63 cylindrical, DS43 ecef), N = 40,000 draws: every entry's
    |z| = |Ĉ − C| / sd(Ĉ) < 5 (45 distinct entries)."""
    names = sorted(DSN_M)
    r_m = np.array([DSN_M[n] for n in names])
    kinds = ("cylindrical", "ecef", "cylindrical")
    local = _sinex_matrix()
    frame = np.array([0.02, 0.02, 0.02, *(3 * [0.5 * RAD_PER_MAS]), 1e-9])
    c = parameter_covariance(r_m / 1000.0, kinds, ("ecef",) * 3, local, frame)
    rng = np.random.default_rng(20261128)
    eps = rng.standard_normal((N_DRAWS, 9)) @ np.linalg.cholesky(local).T
    f = rng.standard_normal((N_DRAWS, 7)) * frame
    p = np.concatenate([_exact(r + eps[:, 3 * i:3 * i + 3] + _helmert(r, f), kind)
                        - _exact(r, kind) for i, (r, kind) in enumerate(zip(r_m, kinds,
                                                                              strict=True))],
                       axis=1)
    sample = p.T @ p / N_DRAWS
    d = np.diag(c)
    z = np.abs(sample - c) / np.sqrt((np.outer(d, d) + c * c) / N_DRAWS)
    assert np.max(z) < Z_LIMIT
    # the frame error correlates the complexes: DS14's z with DS63's z
    corr = c / np.sqrt(np.outer(d, d))
    assert abs(corr[2, 8]) > 0.3


def test_cylindrical_axes_are_rotated_to_the_tape_parameters():
    """A station's covariance in its cylindrical axes (spin radius, east arc, z; m) gives,
    for a cylindrical tape parameterisation, σ(r_s) = σ1/1000 km, σ(lon) = σ2/r_s rad,
    σ(z) = σ3/1000 km and no correlations (the axes are those of the parameters)."""
    r = np.array(DSN_M["DS14"]) / 1000.0
    c = parameter_covariance(r[None], ("cylindrical",), ("cylindrical",),
                             np.diag([0.03, 0.05, 0.07]) ** 2, np.zeros(7))
    spin_km = np.hypot(r[0], r[1])
    expected = np.diag([3e-5, 0.05e-3 / spin_km, 7e-5]) ** 2
    assert scaled_err(c, expected) < 1e-12


# --- files --------------------------------------------------------------------------------


def test_sinex_excerpt_gives_the_whole_station_covariance():
    got = parse_sinex(_SINEX, "dsn.snx")
    assert got.stations == ("DS14", "DS43", "DS63")
    assert got.axes == ("ecef",) * 3
    np.testing.assert_array_equal(got.covariance_m2, _sinex_matrix())


def test_csv_rows_give_sigma_and_correlation_blocks():
    text = ("# test\nstation,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
            "DS14,ecef,0.03,0.04,0.05,0.5,0.0,-0.2\nDS43,cylindrical,0.01,0.02,0.03,0,0,0\n")
    got = parse_csv(text, "dsn.csv")
    assert got.stations == ("DS14", "DS43") and got.axes == ("ecef", "cylindrical")
    assert got.covariance_m2[0, 1] == pytest.approx(0.5 * 0.03 * 0.04)
    assert got.covariance_m2[1, 2] == pytest.approx(-0.2 * 0.04 * 0.05)
    assert got.covariance_m2[4, 4] == pytest.approx(0.02**2)
    assert np.all(got.covariance_m2[:3, 3:] == 0)


@pytest.mark.parametrize(("text", "field"), [
    ("station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
     "DS14,ecef,0.03,0.04,0.05,0.9,0.9,-0.9\n", "station.DS14"),
    ("station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
     "DS14,ecef,0.03,0.04,0.05,1.5,0,0\n", "DS14.rho"),
    ("station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
     "DS14,ecef,-0.03,0.04,0.05,0,0,0\n", "DS14.sigma"),
    ("station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
     "DS14,enu,0.03,0.04,0.05,0,0,0\n", "row 2.axes"),
])
def test_csv_refuses_what_no_network_has(text, field):
    with pytest.raises(InputError) as err:
        parse_csv(text, "dsn.csv")
    assert err.value.source == "dsn.csv" and err.value.field == field


def test_sinex_refuses_a_matrix_that_is_not_positive_semi_definite():
    bad = _SINEX.replace("     2     1  3.60000000000000e-06", "     2     1  3.60000000000000e-05")
    with pytest.raises(InputError, match="DS14.*positive semi-definite"):
        parse_sinex(bad, "dsn.snx")


def test_sinex_refuses_a_site_without_its_three_coordinates():
    bad = _SINEX.replace("     7 STAZ   DS43", "     7 VELZ   DS43")
    with pytest.raises(InputError, match="DS43.*STAZ"):
        parse_sinex(bad, "dsn.snx")


# --- TAPP III ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tape():
    return leo_tape()


def _location_names(tape) -> list[str]:
    par = tape.parameters
    return [n for n, k in zip(par.name, par.kind, strict=True) if k == "location"]


#: The LEO tape's stations: QUITO and MALINDI cylindrical, KOUROU ecef (tests/tapp/tracking/
#: helpers.py), each given here in another set of axes than some of the others.
STATIONS = {"QUITO": {"sigma_m": [3.0, 4.0, 5.0], "correlation": [0.3, 0.1, -0.2]},
            "KOUROU": {"axes": "cylindrical", "sigma_m": [2.0, 6.0, 4.0],
                       "correlation": [0.0, 0.4, 0.0]},
            "MALINDI": {"covariance_m2": [[16.0, 4.0, 0.0], [4.0, 9.0, -3.0],
                                          [0.0, -3.0, 25.0]]}}
FRAME = {"translation_m": [3.0, 3.0, 5.0], "rotation_mas": [0.2, 0.2, 0.3], "scale_ppb": 1.0}


def _tape_stations(tape) -> tuple[list[int], list[str], np.ndarray, list[str]]:
    """The tape's location parameters (positions), its stations with a location, their
    nominal Earth-fixed positions (m) and parameterisations, from the nominal values."""
    par = tape.parameters
    loc = [i for i, k in enumerate(par.kind) if k == "location"]
    names = [par.name[i] for i in loc]
    stations = list(dict.fromkeys(n.split(".")[0] for n in names))
    r_m, kinds = [], []
    for s in stations:
        values = [par.nominal[par.name.index(n)] for n in names if n.startswith(s + ".")]
        cyl = f"{s}.lon_rad" in names
        r_m.append((np.array([values[0] * np.cos(values[1]), values[0] * np.sin(values[1]),
                              values[2]]) if cyl else np.array(values)) * 1000.0)
        kinds.append("cylindrical" if cyl else "ecef")
    return loc, stations, np.array(r_m), kinds


def _mapped(tape, cart: np.ndarray) -> np.ndarray:
    """A Cartesian covariance (m², the tape's stations in order) in the tape's location
    parameters, by the exact map's Jacobian from central differences (step 100 m)."""
    _, _, r_m, kinds = _tape_stations(tape)
    g = np.zeros_like(cart)
    for i, (r, kind) in enumerate(zip(r_m, kinds, strict=True)):
        g[3 * i:3 * i + 3, 3 * i:3 * i + 3] = np.stack(
            [(_exact(r + 100.0 * e, kind) - _exact(r - 100.0 * e, kind)) / 200.0
             for e in np.eye(3)], axis=-1)
    return g @ cart @ g.T


def _apriori_independent(tape) -> tuple[list[int], np.ndarray]:
    """The real-world station block of :data:`STATIONS` and :data:`FRAME` over the tape's
    location parameters (tape order), built here: Cartesian covariance in m² from the tables,
    frame error by H = [I, -[r×], r], then :func:`_mapped`."""
    loc, stations, r_m, _ = _tape_stations(tape)
    cart = np.zeros((3 * len(stations), 3 * len(stations)))
    for i, (s, r) in enumerate(zip(stations, r_m, strict=True)):
        t = STATIONS[s]
        if "covariance_m2" in t:
            c = np.array(t["covariance_m2"])
        else:
            r12, r13, r23 = t["correlation"]
            corr = np.array([[1, r12, r13], [r12, 1, r23], [r13, r23, 1]])
            c = corr * np.outer(t["sigma_m"], t["sigma_m"])
        if t.get("axes") == "cylindrical":
            lon = np.arctan2(r[1], r[0])
            axes = np.array([[np.cos(lon), -np.sin(lon), 0], [np.sin(lon), np.cos(lon), 0],
                             [0, 0, 1]])
            c = axes @ c @ axes.T
        cart[3 * i:3 * i + 3, 3 * i:3 * i + 3] = c
    sigma_f = np.array([*FRAME["translation_m"],
                        *(np.array(FRAME["rotation_mas"]) * np.pi / 648e6),
                        FRAME["scale_ppb"] * 1e-9])
    h = np.vstack([np.hstack([np.eye(3), [[0, r[2], -r[1]], [-r[2], 0, r[0]],
                                          [r[1], -r[0], 0]], r[:, None]]) for r in r_m])
    return loc, _mapped(tape, cart + h @ np.diag(sigma_f**2) @ h.T)


def _real_deck(tape, *, stations: dict | None, print_: list[str]):
    """All parameters fitted (the σ table of the helpers) and uncertain; the real world's
    station locations from ``stations`` (or the helpers' σ's when None)."""
    loc = set(_location_names(tape))
    real = {k: v for k, v in sigmas(tape).items() if stations is None or k not in loc}
    doc = deck(tape, fit=sigmas(tape), real=real, times={"print": [1, 2, 3]},
               commands={"print": print_})
    if stations is not None:
        doc["real"]["apriori"]["stations"] = stations
    return doc


def _closed_form(tape, lam_bar: np.ndarray, k: int, s0: np.ndarray | None = None
                 ) -> np.ndarray:
    """Λ' = (I − KA) Λ̄ (I − KA)ᵀ + K M Kᵀ over the raw rows up to record k (module
    docstring), S₀ = diag(1/σ²) of the fit world's σ table unless given."""
    raw = tape.raw
    if s0 is None:
        s0 = np.diag([1.0 / sigmas(tape)[n] ** 2 for n in tape.parameters.name])
    rows = raw.record <= k
    a, w = raw.A[rows], raw.weight[rows]
    gain = np.linalg.solve(s0 + a.T @ (w[:, None] * a), (w[:, None] * a).T)  # K
    t = np.eye(tape.n_o) - gain @ a
    noise = np.zeros((tape.n_o, tape.n_o))
    for seg_rows, chol in segment_factors(raw):
        if not rows[seg_rows].any():
            continue
        assert rows[seg_rows].all()  # segments are split at the T13 times
        kc = gain[:, np.searchsorted(np.flatnonzero(rows), seg_rows)] @ chol
        noise += kc @ kc.T
    return t @ lam_bar @ t.T + noise


def test_correlated_blocks_give_the_closed_form_real_world_covariance(tape):
    """Every print time, all 23 parameters at the epoch: TAPP III with the station blocks
    against the closed form (module docstring) with Λ̄ built independently
    (:func:`_apriori_independent`), within :data:`CLOSED_FORM`; the diagonal a priori of the
    same σ's gives a covariance that differs from it by far more."""
    loc, block = _apriori_independent(tape)
    base = sigmas(tape)
    lam_bar = np.diag([base[n] ** 2 for n in tape.parameters.name])
    lam_bar[np.ix_(loc, loc)] = block
    lam_diag = lam_bar.copy()
    lam_diag[np.ix_(loc, loc)] = np.diag(np.diag(block))
    with_blocks = run(tape, _real_deck(tape, stations={"station": STATIONS, "frame": FRAME},
                                       print_=["cov-real o@epoch"]))
    assert final(with_blocks, "cov-real o@epoch").shape == (tape.n_o, tape.n_o)
    for b in (b for b in with_blocks.blocks if b.kind == "print" and b.k > 0):
        got = b.entities[0].matrix
        assert scaled_err(got, _closed_form(tape, lam_bar, b.k)) < CLOSED_FORM
        assert scaled_err(got, _closed_form(tape, lam_diag, b.k)) > 1e3 * CLOSED_FORM


def test_the_error_budget_closes_with_correlated_blocks(tape):
    """Station locations are one source (every correlation inside it); split by station in
    [budget.groups], the correlations between the groups are one more source: the variances
    add up to the printed diagonal either way."""
    doc = _real_deck(tape, stations={"station": STATIONS, "frame": FRAME},
                     print_=["cov real orbit@current"])
    one = _last_entity(run(tape, doc))
    doc["budget"] = {"groups": {s: [n for n in _location_names(tape) if n.startswith(s)]
                                for s in STATIONS}}
    split = _last_entity(run(tape, doc))
    for entity, present in ((one, "station locations (a priori)"),
                            (split, "correlations between a priori groups")):
        b = entity.budget
        assert present in b.sources
        assert np.max(np.abs(b.variances.sum(axis=0) - b.total) / b.total) < BUDGET


def _last_entity(run_):
    return [b for b in run_.blocks if b.kind == "print"][-1].entities[0]


# --- refusals ----------------------------------------------------------------------------------


def _refused(tape, doc, match: str, source: str = "deck.toml") -> InputError:
    with pytest.raises(InputError, match=match) as err:
        run(tape, doc, source)
    return err.value


def test_refuses_a_station_not_on_the_tape(tape):
    doc = _real_deck(tape, stations={"station": {**STATIONS, "DS14": STATIONS["QUITO"]}},
                     print_=[])
    err = _refused(tape, doc, "a station of the tape")
    assert err.field == "real.apriori.stations.station.DS14"


def test_refuses_a_sigma_given_both_ways(tape):
    doc = _real_deck(tape, stations={"station": STATIONS}, print_=[])
    doc["real"]["apriori"]["sigma"]["QUITO.lon_rad"] = 1e-6
    err = _refused(tape, doc, "no σ for a station location")
    assert err.field == "real.apriori.sigma.QUITO.lon_rad"


def test_refuses_a_block_that_is_not_positive_semi_definite(tape):
    bad = {**STATIONS, "MALINDI": {"covariance_m2": [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0],
                                                     [0.0, 0.0, 1.0]]}}
    err = _refused(tape, _real_deck(tape, stations={"station": bad}, print_=[]),
                   "positive semi-definite")
    assert err.field == "real.apriori.stations.station.MALINDI"


def test_refuses_station_parameters_outside_the_world(tape):
    doc = _real_deck(tape, stations={"station": STATIONS}, print_=[])
    doc["real"]["certain"] = ["KOUROU.y_km"]
    err = _refused(tape, doc, "in the real world's set")
    assert err.field == "real.apriori.stations" and err.got == "KOUROU.y_km"


def test_fit_world_blocks_give_the_a_priori_information_of_the_closed_form(tape):
    """The blocks in the fit world: its a priori information over the station parameters is
    the inverse of the block (closed form with that S₀, the real world diagonal), within
    :data:`CLOSED_FORM`; a block that is only semi-definite is refused there."""
    loc, block = _apriori_independent(tape)
    base = sigmas(tape)
    s0 = np.diag([1.0 / base[n] ** 2 for n in tape.parameters.name])
    s0[np.ix_(loc, loc)] = np.linalg.inv(block)
    lam_bar = np.diag([base[n] ** 2 for n in tape.parameters.name])
    doc = _real_deck(tape, stations=None, print_=["cov-real o@epoch"])
    names = set(_location_names(tape))
    doc["fit"]["apriori"] = {"sigma": {k: v for k, v in base.items() if k not in names},
                             "stations": {"station": STATIONS, "frame": FRAME}}
    for b in (b for b in run(tape, doc).blocks if b.kind == "print" and b.k > 0):
        assert scaled_err(b.entities[0].matrix,
                          _closed_form(tape, lam_bar, b.k, s0)) < CLOSED_FORM
    doc["fit"]["apriori"]["stations"]["station"] = {
        **STATIONS, "QUITO": {"sigma_m": [3.0, 0.0, 5.0]}}
    doc["fit"]["apriori"]["stations"]["frame"] = {}
    err = _refused(tape, doc, "positive definite")
    assert err.field == "fit.apriori.stations"


def test_refuses_a_station_whose_location_is_not_a_parameter():
    """KOUROU tracked with location = "none": its location is not in q."""
    tape = leo_tape(tracking={"station": {"KOUROU": {"location": "none"}}})
    doc = _real_deck(tape, stations={"station": {"KOUROU": STATIONS["KOUROU"]}}, print_=[])
    err = _refused(tape, doc, "location is a parameter of the tape")
    assert err.field == "real.apriori.stations.station.KOUROU"


def test_a_station_file_relative_to_the_deck(tape, tmp_path):
    """The CSV form, relative to the deck, gives the same run as the same blocks inline; a
    file station also inline is refused."""
    (tmp_path / "net.csv").write_text(
        "station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
        "QUITO,ecef,3.0,4.0,5.0,0.3,0.1,-0.2\nKOUROU,cylindrical,2.0,6.0,4.0,0.0,0.4,0.0\n")
    source = str(tmp_path / "deck.toml")
    inline = {k: STATIONS[k] for k in ("QUITO", "KOUROU")}
    rest = {"MALINDI": STATIONS["MALINDI"]}
    a = _real_deck(tape, stations={"file": "net.csv", "station": rest, "frame": FRAME},
                   print_=["cov-real o@epoch"])
    b = _real_deck(tape, stations={"station": {**inline, **rest}, "frame": FRAME},
                   print_=["cov-real o@epoch"])
    got = final(run(tape, a, source), "cov-real o@epoch")
    assert scaled_err(got, final(run(tape, b, source), "cov-real o@epoch")) < 1e-12
    a["real"]["apriori"]["stations"]["station"] = {"QUITO": STATIONS["QUITO"]}
    err = _refused(tape, a, "not also in the file", source)
    assert err.field == "real.apriori.stations.station.QUITO"
    assert read_station_covariance(tmp_path / "net.csv").stations == ("QUITO", "KOUROU")


def test_a_sinex_file_gives_the_cross_station_terms(tape, tmp_path):
    """The excerpt with the tape's stations for its sites (QUITO, KOUROU, MALINDI for DS14,
    DS43, DS63): at the epoch (k = 0, no data yet) the real-world covariance of the station
    parameters is the excerpt's whole matrix mapped here (:func:`_mapped`), cross-station
    terms included; the same blocks without them give another orbit covariance at k = 3."""
    stations = ("QUITO", "KOUROU", "MALINDI")
    text = _SINEX
    for site, name in zip(("DS14", "DS43", "DS63"), stations, strict=True):
        text = text.replace(site, name)
    (tmp_path / "net.snx").write_text(text)
    source = str(tmp_path / "deck.toml")
    c = _sinex_matrix()
    blocks = {s: {"covariance_m2": c[3 * i:3 * i + 3, 3 * i:3 * i + 3].tolist()}
              for i, s in enumerate(stations)}
    whole = run(tape, _real_deck(tape, stations={"file": "net.snx"},
                                 print_=["cov-real o@epoch"]), source)
    loc, _, _, _ = _tape_stations(tape)
    epoch = next(b for b in whole.blocks if b.kind == "print" and b.k == 0).entities[0].matrix
    assert scaled_err(epoch[np.ix_(loc, loc)], _mapped(tape, c)) < MAPPED
    inline = run(tape, _real_deck(tape, stations={"station": blocks},
                                  print_=["cov-real o@epoch"]), source)
    a, b = (final(r, "cov-real o@epoch") for r in (whole, inline))
    # mm-level σ's move the LEO orbit little (measured 1.7e-7 of its scale), but far beyond
    # the rounding of two runs of one a priori (< 1e-12: test_a_station_file_relative_...)
    assert scaled_err(a[:6, :6], b[:6, :6]) > 1e-8
    with pytest.raises(InputError) as err:
        run(tape, _real_deck(tape, stations={"file": "missing.snx"}, print_=[]), source)
    assert "missing.snx" in str(err.value)


def test_tapp_process_reads_the_tables_and_a_bad_file_is_exit_2(tape, tmp_path):
    """The deck's TOML as documented (station tables, frame, a CSV beside the deck) runs with
    ``tapp process``; a CSV row that is not positive semi-definite is one line, exit 2,
    naming the CSV file and the station."""
    from typer.testing import CliRunner

    import tapp.cli  # noqa: F401  (registers every command)
    from tapp.cli.common import app
    from tapp.io.tape.t13_hdf5 import write_t13

    write_t13(tmp_path / "leo.t13.h5", tape)
    (tmp_path / "net.csv").write_text(
        "station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
        "QUITO,ecef,3.0,4.0,5.0,0.3,0.1,-0.2\n")
    names = set(_location_names(tape))
    real = "\n".join(f'"{k}" = {v!r}' for k, v in sigmas(tape).items() if k not in names)
    fit = "\n".join(f'"{k}" = {v!r}' for k, v in sigmas(tape).items())
    (tmp_path / "deck.toml").write_text(
        '[times]\nprint = [1, 2, 3]\n[commands]\nprint = ["cov real orbit@current"]\n'
        f"[fit.apriori.sigma]\n{fit}\n[real.apriori.sigma]\n{real}\n"
        '[real.apriori.stations]\nfile = "net.csv"\n'
        'station.KOUROU = { axes = "cylindrical", sigma_m = [2.0, 6.0, 4.0] }\n'
        "station.MALINDI = { covariance_m2 = [[16.0, 4.0, 0.0], [4.0, 9.0, -3.0], "
        "[0.0, -3.0, 25.0]] }\n"
        "frame = { translation_m = [3.0, 3.0, 5.0], rotation_mas = [0.2, 0.2, 0.3] }\n")
    args = ["process", str(tmp_path / "leo.t13.h5"), str(tmp_path / "deck.toml"),
            "--print", str(tmp_path / "o3.txt"), "--tape", str(tmp_path / "o.t32.h5")]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    assert "station locations" in (tmp_path / "o3.txt").read_text()
    (tmp_path / "net.csv").write_text(
        "station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23\n"
        "QUITO,ecef,3.0,4.0,5.0,0.9,0.9,-0.9\n")
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2
    assert len(res.stderr.strip().splitlines()) == 1
    assert "net.csv" in res.stderr and "station.QUITO" in res.stderr
