"""TAPP III report pieces: the RIC σ plot and CSV, and the Markdown tables of the ellipses and
RIC σ built from a run's JSON history."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tapp.processor.printout import run_dict
from tapp.processor.sequencing import HistoryRow, Run
from tapp.report.pipeline import bplane_ellipse_table, ric_sigma_table
from tapp.report.processor import ellipse_points, plot_ric_history, ric_csv

_DAY_S = 86400.0
MISS = ("b_dot_r_km", "b_dot_t_km")
COV = np.array([[0.04, 0.03], [0.03, 0.09]])  # (B·R, B·T), km²


def _rows() -> tuple[HistoryRow, ...]:
    ric = np.array([1e-3, 5e-3, 2e-3, 1e-6, 2e-7, 3e-7])  # km, km/s
    return (HistoryRow("print", 0, 0.0, None, np.ones(1), None, 4 * COV, 12.0, None, 10 * ric),
            HistoryRow("recycle", 2, _DAY_S, np.ones(1), np.ones(1), COV / 4, COV, 11.0, ric,
                       2 * ric))


class _Header:
    """The few header fields run_dict reads."""

    iden = "TEST"

    class miss:  # noqa: N801 (mirrors the tape's attribute)
        name = MISS

    class epoch:  # noqa: N801
        @staticmethod
        def iso(_digits: int) -> str:
            return "2026-01-01T00:00:00.000"


def _content() -> dict:
    return run_dict(Run((), _rows(), ("x_km",), (), np.eye(1), np.eye(1)), _Header, "d", "t")


def test_csv_has_one_row_per_time_with_fit_and_real_sigmas():
    lines = ric_csv(_rows()).splitlines()
    assert lines[0].startswith("kind,k,t_s,t_days,sigma_fit_R_km")
    assert lines[0].endswith("sigma_real_vC_km_s")
    first = lines[1].split(",")
    assert first[:2] == ["print", "0"] and first[4:10] == [""] * 6  # no fit-world covariance
    second = lines[2].split(",")
    assert float(second[3]) == 1.0  # days
    np.testing.assert_allclose([float(v) for v in second[4:]],
                               np.concatenate([_rows()[1].ric_fit, _rows()[1].ric_real]),
                               rtol=1e-10)


def test_ric_plot_is_written(tmp_path: Path):
    path = plot_ric_history(_rows(), tmp_path / "ric.png", "test")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_markdown_tables_from_the_json_history():
    content = _content()
    ellipses = bplane_ellipse_table(content)
    # the real ellipse at the recycle: σ_T = 0.3, σ_R = 0.2, ρ = 0.5 (closed form, T first)
    a, b, c = COV[1, 1], COV[0, 1], COV[0, 0]
    major = np.sqrt(0.5 * (a + c) + np.hypot(0.5 * (a - c), b))
    assert f"| recycle | 2 | 1.000 | {major / 2:.4g} / {major:.4g} |" in ellipses
    ric = ric_sigma_table(content)
    assert "| print | 0 | 0.000 | - / 10 | - / 50 | - / 20 |" in ric
    assert "| recycle | 2 | 1.000 | 1 / 2 | 5 / 10 | 2 / 4 |" in ric


def test_tables_are_empty_without_bplane_or_ric():
    content = _content()
    for row in content["history"]["rows"]:
        row.update(bplane_ellipse_fit=None, bplane_ellipse_real=None, ric_sigma_fit=None,
                   ric_sigma_real=None)
    assert bplane_ellipse_table(content) == "" and ric_sigma_table(content) == ""


def test_plotted_ellipse_is_the_printed_one():
    pts = ellipse_points(COV, 3.0)
    q = np.einsum("ni,ij,nj->n", pts, np.linalg.inv(COV), pts)
    np.testing.assert_allclose(q, 9.0, rtol=1e-12)
