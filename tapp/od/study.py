"""The approximate-STM study end to end: every run of the brief, as data.

The runs are read from the study's scenario file (``[[dc]]``, ``[ekf]``, ``[rsig]``; see
``scenarios/approx_stm.toml``, validated by :class:`tapp.od.setup.StudyFile`); each DC run
uses the brief's offset initial estimate and the 5-day simulated observation file of its orbit
and truth model, cut to the run's arc. The results are plain dataclasses;
:mod:`tapp.report.approx_stm` turns them into the report.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tapp.dynamics import Propagator, earth_model
from tapp.od import setup
from tapp.od.batch import DCResult, DCSettings, differential_correction
from tapp.od.ekf import EKFResult, extended_kalman_filter
from tapp.od.rsig import RSignature, r_signature
from tapp.orbits import DEFAULT_SCENARIO


@dataclass(frozen=True, slots=True)
class DCRun:
    """One DC case: which block, orbit, (truth, STM) models and arc, and its outcome."""

    block: str
    orbit: str
    truth: str
    stm: str
    arc_h: float
    result: DCResult
    position_error_km: float


@dataclass(frozen=True, slots=True)
class EKFRun:
    """One EKF case: (truth, STM) models, a priori label and the filter output."""

    orbit: str
    truth: str
    stm: str
    apriori: str
    result: EKFResult


@dataclass(frozen=True, slots=True)
class RRun:
    """One R(t) curve."""

    orbit: str
    truth: str
    stm: str
    signature: RSignature


@dataclass(frozen=True, slots=True)
class StudyResults:
    """Everything the report shows."""

    dc: tuple[DCRun, ...]
    dc_blocks: tuple[str, ...]
    ekf: tuple[EKFRun, ...]
    ekf_title: str
    last_passes: int
    rsig: tuple[RRun, ...]
    sigma: np.ndarray
    network: dict[str, tuple[str, ...]]


def planned_cases(path: Path = DEFAULT_SCENARIO) -> int:
    """Number of runs the study will make (for a progress bar)."""
    study = setup.study_file(path)
    n = sum(len(b.orbits) * len(b.stm) * len(b.arcs_h) for b in study.dc)
    if study.ekf:
        n += len(study.ekf.stm) * len(study.ekf.apriori)
    return n + (len(study.rsig.cases) if study.rsig else 0)


def run_study(path: Path = DEFAULT_SCENARIO, advance: Callable[[str], None] = lambda _: None
              ) -> StudyResults:
    """Run every case of the study; ``advance(label)`` is called after each case."""
    study = setup.study_file(path)
    src = str(path)
    settings = DCSettings(**study.dc_settings.model_dump())
    theta0 = setup.tracking(path).theta0_rad
    off = setup.offset(path)
    network: dict[str, tuple[str, ...]] = {}
    obs_cache: dict[tuple[str, str], object] = {}

    def observations(orbit: str, truth: str):
        if (orbit, truth) not in obs_cache:
            x_true = setup.true_orbit(orbit, path)
            stations = setup.network_for(x_true, None, path)
            network[orbit] = tuple(s.name for s in stations)
            obs_cache[orbit, truth] = setup.simulated_observations(x_true, truth, stations, path)
        return obs_cache[orbit, truth]

    dc_runs, blocks = [], []
    for block in study.dc:
        title = block.title if block.title is not None else f"block {len(blocks) + 1}"
        blocks.append(title)
        for orbit in block.orbits:
            x_true = setup.true_orbit(orbit, path)
            x_start = setup.initial_estimate(x_true, off)
            truth = block.truth
            obs = observations(orbit, truth)
            for stm in block.stm:
                prop = Propagator(earth_model(truth, source=src, field="dc.truth"),
                                  earth_model(stm, source=src, field="dc.stm"))
                for arc_h in block.arcs_h:
                    res = differential_correction(obs.window(arc_h * 3600.0), prop, x_start,
                                                  theta0_rad=theta0, settings=settings)
                    err = float(np.linalg.norm(res.x0[:3] - x_true[:3]))
                    dc_runs.append(DCRun(title, orbit, truth, stm, float(arc_h), res, err))
                    advance(f"DC {orbit} ({truth},{stm}) {arc_h:g} h")

    ekf_runs = []
    ekf = study.ekf
    if ekf:
        orbit, truth = ekf.orbit, ekf.truth
        x_true = setup.true_orbit(orbit, path)
        x_start = setup.initial_estimate(x_true, off)
        obs = observations(orbit, truth).window(ekf.arc_h * 3600.0)
        for stm in ekf.stm:
            prop = Propagator(earth_model(truth, source=src, field="ekf.truth"),
                              earth_model(stm, source=src, field="ekf.stm"))
            for label, sig in ekf.apriori.items():
                p0 = np.diag(np.square(np.asarray(sig, dtype=float)))
                res = extended_kalman_filter(obs, prop, x_start, p0, theta0_rad=theta0)
                ekf_runs.append(EKFRun(orbit, truth, stm, label, res))
                advance(f"EKF ({truth},{stm}) a priori {label}")

    r_runs = []
    rs = study.rsig
    if rs:
        x_true = setup.true_orbit(rs.orbit, path)
        t = np.arange(0.0, rs.hours * 3600.0 + 0.5 * rs.step_s, rs.step_s)
        for truth, stm in rs.cases:
            prop = Propagator(earth_model(truth, source=src, field="rsig.cases"),
                              earth_model(stm, source=src, field="rsig.cases"))
            r_runs.append(RRun(rs.orbit, truth, stm, r_signature(prop, x_true, t, theta0)))
            advance(f"R(t) ({truth},{stm})")

    return StudyResults(tuple(dc_runs), tuple(blocks), tuple(ekf_runs),
                        ekf.title if ekf else "", ekf.last_passes if ekf else 0, tuple(r_runs),
                        setup.tracking(path).sigma, network)
