"""The coding example of seed TAPP III Appendix D (Table D-1, n_o = 29) on a simulated tape.

The example ``tapp1_table_d1.toml`` gives a T13 tape with n_o = 29; ``tapp3_table_d1.toml``
codes its systems exactly as Table D-1 does (P_c with the reconstruction (12, 27), chosen
constraint coefficients; see the deck's comments). The expected orders, links and variances
here are derived by hand from the table's pairs and triples, not from the code under test.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tapp.cli.common import app
from tapp.errors import InputError
from tapp.examples import FOLDER as EXAMPLES
from tapp.io.schema import validate
from tapp.io.tape.t13 import memory_pairs
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tomlfile import read_toml
from tapp.processor.deck import Deck, read_deck
from tapp.processor.deck_bind import bind
from tapp.processor.links import Constraint, Permutation
from tapp.processor.sequencing import Processor, Run
from tapp.tracking.scenario_build import read_scenario
from tapp.tracking.simulate import simulate

SCENARIOS = EXAMPLES
TAPP1 = SCENARIOS / "tapp1_table_d1.toml"
DECK = SCENARIOS / "tapp3_table_d1.toml"

# Table D-1 (seed TAPP III Appendix D), 1-based positions as printed; P_c with (12, 27) in
# place of the scan's (12, 19) (the scan's list is not a permutation, see the deck).
N_O, N_P, N_C1, N_F1, N_R1 = 29, 6, 18, 13, 14
P_C = [(10, 14), (12, 27), (13, 18), (14, 25), (15, 26), (16, 22), (18, 19), (19, 10),
       (22, 12), (25, 13), (26, 15), (27, 16)]
K_C = [(22, 7), (22, 11), (22, 14), (23, 11), (23, 16), (25, 8), (25, 10)]
K_F = [(15, 11), (17, 8), (17, 9), (18, 9)]
P_R = [(11, 17), (13, 15), (15, 11), (17, 13)]
K_R = [(15, 13), (16, 11), (18, 9), (18, 10)]

#: Relative rounding of products of a few links and a 29 x 29 inverse (a few ulps times the
#: largest coefficient ratio of the deck, 3e5).
ROUNDING = 1e-12
#: Relative accuracy of the orbit link's adjoint ΓPΓᵀ (3-13): exact for a symplectic P, but
#: the tape's STM is symplectic only to its integration error (rtol 1e-13) amplified by
#: |Φ| ~ 5e4 over 12 h; measured 8e-11 (gmst) and 1.8e-10 (iau2006, the time-dependent
#: field) here, where a wrong adjoint is off by O(1).
SYMPLECTIC_DEFECT = 1e-9
#: Smallest eigenvalue accepted for a correlation matrix (rounding of the regression's
#: symmetric products, whose diagonal scaling spans 16 decades).
PSD_ROUNDING = 1e-9


@pytest.fixture(scope="module")
def tape():
    return simulate(read_scenario(TAPP1)).tape


@pytest.fixture(scope="module")
def processed(tape) -> tuple[Processor, Run]:
    data = memory_pairs(tape)
    plan = bind(read_deck(DECK), data.header, str(DECK))
    proc = Processor(data, plan, str(DECK))
    return proc, proc.run()


def _permuted(order: list, pairs: list[tuple[int, int]]) -> list:
    """Seed (3-4): u(a) = v(b) for each pair (1-based); other rows unchanged."""
    out = list(order)
    for a, b in pairs:
        out[a - 1] = order[b - 1]
    return out


def _permutation_matrix(pairs: list[tuple[int, int]]) -> np.ndarray:
    m = np.eye(N_O)
    for a, _ in pairs:
        m[a - 1] = 0.0
    for a, b in pairs:
        m[a - 1, b - 1] = 1.0
    return m


def _constraint_matrix(triples: list[tuple[int, int, float]]) -> np.ndarray:
    """Seed (3-5): K = I - E with E[a, b] = e."""
    k = np.eye(N_O)
    for a, b, e in triples:
        k[a - 1, b - 1] -= e
    return k


def _deck_triples(section: list) -> list[tuple[int, int, float]]:
    return [(int(a), int(b), float(e)) for a, b, e in section]


def test_the_tape_has_the_dimensions_of_table_d1(tape) -> None:
    assert (tape.n_o, tape.n_p) == (N_O, N_P)


def test_the_lists_obey_the_ip_and_ik_rules() -> None:
    # links.py: permutations name the same set of positions as a and as b, each once;
    # constraints have rows a and columns b disjoint; all positions are constants (> n_p).
    for pairs in (P_C, P_R):
        a, b = zip(*pairs, strict=True)
        assert sorted(a) == sorted(b) and len(set(a)) == len(a)
        assert min(a) > N_P
    for triples in (K_C, K_F, K_R):
        a, b = zip(*triples, strict=True)
        assert not set(a) & set(b) and min(a + b) > N_P
    # The scan's own P_c is not a permutation: 19 twice as b, 27 never.
    scanned = [(12, 19) if p == (12, 27) else p for p in P_C]
    assert sorted(b for _, b in scanned) != sorted(a for a, _ in scanned)
    # The alternative reading (18, 27) in place of (18, 19) is one as well.
    alternative = [(12, 19) if p == (12, 27) else (18, 27) if p == (18, 19) else p
                   for p in P_C]
    assert sorted(b for _, b in alternative) == sorted(a for a, _ in alternative)


def test_the_bound_systems_have_the_sizes_and_links_of_table_d1(processed) -> None:
    proc, _ = processed
    sy = proc.plan.systems
    assert (sy.n_o, sy.n_p, sy.n_c1, sy.n_f1, sy.n_r1) == (N_O, N_P, N_C1, N_F1, N_R1)
    assert sy.P_f is None
    assert isinstance(sy.P_c, Permutation) and sy.P_c.target.size == len(P_C) == 12
    assert isinstance(sy.K_c, Constraint) and sy.K_c.a.size == len(K_C) == 7
    assert isinstance(sy.K_f, Constraint) and sy.K_f.a.size == len(K_F) == 4
    assert isinstance(sy.P_r, Permutation) and sy.P_r.target.size == len(P_R) == 4
    assert isinstance(sy.K_r, Constraint) and sy.K_r.a.size == len(K_R) == 4
    assert proc.plan.S0.shape == (N_F1, N_F1) and proc.plan.Lambda0.shape == (N_R1, N_R1)


def test_the_fit_system_puts_the_fitted_parameters_first_in_the_coded_order(tape, processed
                                                                           ) -> None:
    proc, _ = processed
    names = list(tape.parameters.name)
    common = _permuted(names, P_C)
    # Derived by hand (deck comments): positions 10..13 of the common system take tape
    # parameters 14, 11 (unchanged), 27 and 18.
    by_hand = names[:9] + ["QUITO.range_rate_bias_km_s", "QUITO.lon_rad", "SINGAPORE.z_km",
                           "KOUROU.range_bias_km"]
    assert common[:N_F1] == by_hand
    fit = proc.plan.systems.system_names(4)
    assert fit[:N_F1] == by_hand  # no constraint acts on the fitted rows
    primed = sorted({a for a, _ in K_F} | {a for a, _ in K_C})
    assert [i + 1 for i, n in enumerate(fit) if n.endswith("'")] == primed
    assert [n.rstrip("'") for n in fit] == common
    real = _permuted(common, P_R)
    assert real[:N_R1] == names[:9] + [names[i - 1] for i in (14, 17, 27, 26, 25)]
    assert [n.rstrip("'") for n in proc.plan.systems.system_names(6)] == real


def test_the_system_chains_are_the_products_of_the_coded_links(processed) -> None:
    proc, _ = processed
    deck = read_deck(DECK)
    k_c = _constraint_matrix(_deck_triples(deck.common.constraints))
    p_c = _permutation_matrix(P_C)
    d_fit = _constraint_matrix(_deck_triples(deck.fit.constraints)) @ k_c @ p_c
    d_real = (_constraint_matrix(_deck_triples(deck.real.constraints))
              @ _permutation_matrix(P_R) @ k_c @ p_c)
    acc = proc.acc
    for chi, expected in ((3, k_c @ p_c), (4, d_fit), (6, d_real)):
        np.testing.assert_allclose(acc.transformation(0, 0, chi), expected, rtol=0,
                                   atol=ROUNDING * np.max(np.abs(expected)))


def _within(residual: np.ndarray, scale: np.ndarray, tol: float) -> bool:
    """|residual| <= tol * scale entry by entry (scale: |A||B| of a product, plus I)."""
    return bool(np.all(np.abs(residual) <= tol * scale))


@pytest.mark.parametrize("tau", [0, 1, 2])
def test_the_fit_world_transformation_matrices_satisfy_2_15(processed, tau: int) -> None:
    # Seed (2-15): D = ∂x^f/∂x (here ⟨0, τ, 4⟩) split into D1 (fitted rows) and D2 (the rest),
    # E = D⁻¹ (numpy) split into E1, E2. E1 is what the accumulator gives as (1, τ, f1|ᵀ; the
    # identities are checked with the accumulator's adjoint chain, not only with the inverse.
    # τ = 1, 2 take the orbit link of the last record and recycle (U, V ≠ I).
    proc, _ = processed
    acc = proc.acc
    tol = ROUNDING if tau == 0 else SYMPLECTIC_DEFECT
    d = acc.transformation(0, tau, 4)
    e = np.linalg.inv(d)
    e_acc = acc.transformation(1, tau, 4).T
    column = np.max(np.abs(e), axis=0)
    assert _within(e[:, :N_F1] - acc.partials(1, tau, "f1").T, column[:N_F1], tol)
    assert _within(e - e_acc, column, tol)
    np.testing.assert_array_equal(acc.partials(0, tau, "f1"), d[:N_F1])
    d1, d2, e1, e2 = d[:N_F1], d[N_F1:], e_acc[:, :N_F1], e_acc[:, N_F1:]
    n2 = N_O - N_F1
    for product, a, b, expected in (
            (d1 @ e1, d1, e1, np.eye(N_F1)),                           # (2-15a)
            (d1 @ e2, d1, e2, np.zeros((N_F1, n2))),                  # (2-15b)
            (d2 @ e1, d2, e1, np.zeros((n2, N_F1))),                  # (2-15c)
            (d2 @ e2, d2, e2, np.eye(n2))):                            # (2-15d)
        assert _within(product - expected, np.abs(a) @ np.abs(b) + expected, tol)
    assert _within(e1 @ d1 + e2 @ d2 - np.eye(N_O),                    # (2-15e)
                   np.abs(e1) @ np.abs(d1) + np.abs(e2) @ np.abs(d2), tol)


def test_the_eliminated_rows_carry_the_a_priori_through_k_c(processed) -> None:
    # At k = 0 the real-world covariance is E₃Λ₀E₃ᵀ. QUITO.z' (common row 22) is eliminated,
    # i.e. held at QUITO.z = 2.5 GM + 2500 QUITO.lon - 0.25 SINGAPORE.spin_radius, and the
    # real world's K_r holds QUITO.lon = SINGAPORE.lon (σ 1e-6 rad): var = (2.5·1e-3)² +
    # (2500·1e-6)² + (0.25·0.005)² km².
    _, run = processed
    block = run.blocks[0]
    assert block.k == 0
    ent = next(e for e in block.entities if e.command.seed() == "Λ̄'; 0,0,q; 0,0,q")
    row = {name: i for i, name in enumerate(ent.rows)}
    cov = ent.matrix
    z, rho = row["QUITO.z_km"], row["SINGAPORE.spin_radius_km"]
    assert cov[z, z] == pytest.approx(2.5e-3**2 + 2.5e-3**2 + 1.25e-3**2, rel=ROUNDING)
    assert cov[z, rho] == pytest.approx(-0.25 * 0.005**2, rel=ROUNDING)
    lon_q, lon_s = row["QUITO.lon_rad"], row["SINGAPORE.lon_rad"]
    assert cov[lon_q, lon_s] == pytest.approx(1e-12, rel=ROUNDING)
    # The fit world's K_f holds SINGAPORE.lon - QUITO.lon fixed instead (fz row 15): in the
    # common system c1, rows 11 (QUITO.lon) and 15 (SINGAPORE.lon) are fully correlated.
    fit = next(e for e in block.entities if e.command.seed() == "Λ'; 0,0,c1; 0,0,c1")
    np.testing.assert_allclose(fit.matrix[np.ix_([10, 14], [10, 14])], 1e-12, rtol=ROUNDING)


def _is_psd(cov: np.ndarray) -> bool:
    """Every variance >= 0 exactly (a Gram matrix of a factor: the square-root form
    guarantees it, where the normal-matrix form let held-fixed rows round to ±ε), and the
    correlation matrix (rows of zero variance left unscaled) PSD to rounding."""
    var = np.diagonal(cov)
    if np.any(var < 0):
        return False
    d = np.sqrt(var)
    scale = np.where(var > 0, d, 1.0)
    return float(np.linalg.eigvalsh(cov / np.outer(scale, scale))[0]) >= -PSD_ROUNDING


def test_every_printed_covariance_is_symmetric_and_positive_semi_definite(processed) -> None:
    proc, run = processed
    checked = 0
    for block in run.blocks:
        for ent in block.entities:
            cmd = ent.command
            if cmd.is_covariance and cmd.rows == cmd.cols:
                assert np.array_equal(ent.matrix, ent.matrix.T), (block.k, cmd.seed())
                assert _is_psd(ent.matrix), (block.k, cmd.seed())
                checked += 1
    assert checked == 6 * 15  # 15 square covariances at each of the 6 print times


def test_every_partition_family_was_printed(processed) -> None:
    _, run = processed
    rhos = {side.rho for block in run.blocks for ent in block.entities
            for side in (ent.command.rows, ent.command.cols)}
    assert {"o", "p", "q", "c", "c1", "cp", "cq", "c2", "f", "f0", "f1", "fp", "fq", "fz",
            "r", "r0", "r1", "rp", "rq", "r2", "pj", "pk", "pl", "pi", "m", "m1"} <= rhos
    kinds = [b.kind for b in run.blocks]
    assert kinds.count("print") == 6 and kinds.count("recycle") == 2
    assert [r.k for r in run.recycles] == [2, 4]


def test_tapp_process_runs_the_deck_end_to_end(tape, tmp_path: Path) -> None:
    path = write_t13(tmp_path / "d1.t13.h5", tape)
    out = tmp_path / "d1.json"
    res = CliRunner().invoke(app, ["process", str(path), str(DECK), "--print",
                                   str(tmp_path / "d1.o3.txt"), "--json", str(out)])
    assert res.exit_code == 0, res.output
    content = json.loads(out.read_text())
    assert [b["k"] for b in content["blocks"] if b["kind"] == "print"] == [0, 1, 2, 3, 5, 6]
    assert "Λ̄'; 0,0,rq; 0,0,r2" in (tmp_path / "d1.o3.txt").read_text()


# --- a deck that fits its tape only by position (issue "Hardening, second round") ---------

def _without_tape_table(**tape) -> Deck:
    doc = read_toml(DECK)
    doc.pop("tape")
    if tape:
        doc["tape"] = tape
    return validate(Deck, doc, "d1.toml")


@pytest.fixture(scope="module")
def leo_header():
    return memory_pairs(simulate(read_scenario(SCENARIOS / "leo_equatorial.toml")).tape).header


def test_positions_without_a_tape_table_are_refused_on_any_tape(tape, leo_header) -> None:
    # without its [tape] table the deck ran on the LEO tape (n_o = 38 >= 29) and exited 0
    assert len(leo_header.parameters.name) >= N_O
    for header in (leo_header, memory_pairs(tape).header):
        with pytest.raises(InputError) as info:
            bind(_without_tape_table(), header, "d1.toml")
        assert str(info.value) == (
            "d1.toml: common.permutation: expected parameter names, or positions with a [tape] "
            "table that names the tape they refer to (parameters = its parameter names in "
            "order, or iden) (got 'positions, and no [tape] parameters or iden')")


def test_positions_are_checked_against_the_parameter_names_given(tape, leo_header) -> None:
    names = list(tape.parameters.name)
    plan = bind(_without_tape_table(parameters=names), memory_pairs(tape).header, "d1.toml")
    assert plan.systems.n_c1 == N_C1
    with pytest.raises(InputError) as info:
        bind(_without_tape_table(parameters=names), leo_header, "d1.toml")
    assert str(info.value) == ("d1.toml: tape.parameters: expected the tape's 38 parameter "
                               "names in order (position 9: QUITO.spin_radius_km) (got 'J3')")
