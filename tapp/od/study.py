"""The approximate-STM study end to end: every run of the brief, as data.

The runs are read from the study's scenario file (``[[dc]]``, ``[ekf]``, ``[rsig]``,
``[rate_vs_arc]``, ``[rate_vs_inclination]``; see ``approx_stm.toml``, validated by
:class:`tapp.od.study_schema.StudyFile`); each DC run uses the brief's offset initial estimate
and the 5-day simulated observation file of its orbit and truth model, cut to the run's arc.
Beside each DC run go the predicted convergence rate ρ of its (J_N, J_M) pair on the same
observations at the true state (:mod:`tapp.od.rate`) and the study's own predictor, the ratio
R_M / R_N of the error-growth signatures (:mod:`tapp.od.rsig`) of the variational and the state
model at the end of the arc. The ρ curves use noise-free observations (ρ depends on the times,
stations and weights only). Every run uses the study's one Earth orientation
(``earth_orientation`` and ``eop`` of the file, or the model passed in), for the data and the
estimators alike; the results record it. The results are plain dataclasses;
:mod:`tapp.report.od` turns them into the report.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import Propagator
from tapp.errors import TooFewMeasurementsError
from tapp.io.stations_file import load_network
from tapp.od import setup
from tapp.od.batch import DCResult, DCSettings, differential_correction
from tapp.od.ekf import EKFResult, extended_kalman_filter
from tapp.od.rate import PredictedRate, predicted_rate
from tapp.od.rsig import RSignature, r_signature
from tapp.od.study_file import Offset, Study, offset, tracking
from tapp.orbit.elements import cartesian_to_elements, elements_to_cartesian


@dataclass(frozen=True, slots=True)
class DCRun:
    """One DC case: which block, orbit, (truth, STM) models and arc, and its outcome.

    ``rate`` is the predicted rate at the true state (None when the normal matrix is
    singular); ``r_ratio`` = R_M / R_N at the end of the arc (the study's signature of the
    variational model over that of the state model); ``x_true`` (6,) the true epoch state.
    """

    block: str
    orbit: str
    truth: str
    stm: str
    arc_h: float
    result: DCResult
    position_error_km: float
    rate: PredictedRate | None = None
    r_ratio: float = float("nan")
    x_true: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class RateCurve:
    """ρ of one (truth, STM) pair along a swept quantity ``x`` (arc h or inclination deg).

    ``rho`` (n,) NaN where the data were too few; ``oscillating`` (n,) a complex dominant
    pair.
    """

    orbit: str
    truth: str
    stm: str
    x: np.ndarray
    rho: np.ndarray
    oscillating: np.ndarray


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
    rate_vs_arc: tuple[RateCurve, ...] = ()
    rate_vs_inclination: tuple[RateCurve, ...] = ()
    inclination_arc_h: float = float("nan")
    inclination_network: str = ""
    settings: DCSettings = DCSettings()
    offset: Offset | None = None
    #: :func:`tapp.od.setup.orientation_record` over the tracking span
    earth_orientation: dict = field(default_factory=dict)


def planned_cases(study: Study) -> int:
    """Number of runs the study will make (for a progress bar)."""
    file = study.file
    n = sum(len(b.orbits) * len(b.var_gravity) * len(b.arcs_h) for b in file.dc)
    if file.ekf:
        n += len(file.ekf.var_gravity) * len(file.ekf.apriori)
    if file.rate_vs_arc:
        n += len(file.rate_vs_arc.var_gravity)
    if file.rate_vs_inclination:
        n += len(file.rate_vs_inclination.var_gravity)
    return n + (len(file.rsig.cases) if file.rsig else 0)


def _rate_or_none(obs, truth, stm, x_true, orient) -> PredictedRate | None:
    try:
        return predicted_rate(obs, truth, stm, x_true, orient)
    except (np.linalg.LinAlgError, TooFewMeasurementsError):
        return None


def _curve(orbit: str, truth: str, stm: str, x: np.ndarray,
           rates: list[PredictedRate | None]) -> RateCurve:
    rho = np.array([np.nan if r is None else r.rho for r in rates])
    osc = np.array([r is not None and r.oscillating for r in rates])
    return RateCurve(orbit, truth, stm, np.asarray(x, dtype=float), rho, osc)


def with_inclination(x: np.ndarray, inclination_rad: float) -> np.ndarray:
    """Return the state (6,) of the orbit of x (6,) with its inclination replaced."""
    el = np.array(cartesian_to_elements(x, GM_EARTH_km3_s2), dtype=float)
    el[2] = inclination_rad
    return np.asarray(elements_to_cartesian(el, GM_EARTH_km3_s2), dtype=float)


def run_study(study: Study, advance: Callable[[str], None] = lambda _: None,
              earth_orientation: str | None = None) -> StudyResults:
    """Run every case of ``study`` (read once by :func:`tapp.od.study_file.read_study`);
    ``advance(label)`` is called after each case.

    ``earth_orientation`` overrides the file's model ("iau2006" or "gmst").

    Raises
    ------
    InputError
        A bad study file, an unknown model, an epoch or span outside the EOP table.
    """
    file, path = study.file, study.path
    settings = DCSettings(**file.dc_settings.model_dump())
    orient = setup.orientation(study, earth_orientation)

    def model(spec: str, where: str):
        return setup.force_model(spec, orient, str(path), where)

    off = offset(study)
    network: dict[str, tuple[str, ...]] = {}
    obs_cache: dict[tuple[str, str], object] = {}

    def observations(orbit: str, truth: str):
        if (orbit, truth) not in obs_cache:
            x_true = setup.true_orbit(orbit, study)
            stations = setup.network_for(x_true, None, study)
            network[orbit] = tuple(s.name for s in stations)
            obs_cache[orbit, truth] = setup.simulated_observations(x_true, truth, stations,
                                                                   study, orient=orient)
        return obs_cache[orbit, truth]

    dc_runs, blocks = [], []
    r_end: dict[tuple[str, str, str, float], float] = {}

    def r_at_end(orbit: str, truth: str, stm: str, arc_h: float) -> float:
        if (orbit, truth, stm, arc_h) not in r_end:
            prop = Propagator(model(truth, "dc.gravity"), model(stm, "dc.var_gravity"))
            sig = r_signature(prop, setup.true_orbit(orbit, study),
                              np.array([0.0, arc_h * 3600.0]), orient)
            r_end[orbit, truth, stm, arc_h] = float(sig.r[-1])
        return r_end[orbit, truth, stm, arc_h]

    for index, block in enumerate(file.dc):
        title = block.title if block.title is not None else f"block {len(blocks) + 1}"
        blocks.append(title)
        for orbit in block.orbits:
            x_true = setup.true_orbit(orbit, study)
            x_start = setup.initial_estimate(x_true, off)
            truth = block.gravity
            obs = observations(orbit, truth)
            for stm in block.var_gravity:
                state_model = model(truth, "dc.gravity")
                var_model = model(stm, "dc.var_gravity")
                prop = Propagator(state_model, var_model)
                for arc_h in block.arcs_h:
                    data = obs.arc(arc_h * 3600.0, str(path), f"dc[{index}].arcs_h", arc_h)
                    res = differential_correction(data, prop, x_start, orientation=orient,
                                                  settings=settings)
                    err = float(np.linalg.norm(res.x0[:3] - x_true[:3]))
                    rate = _rate_or_none(data, state_model, var_model, x_true, orient)
                    ratio = r_at_end(orbit, truth, stm, arc_h) / r_at_end(orbit, truth,
                                                                        truth, arc_h)
                    dc_runs.append(DCRun(title, orbit, truth, stm, float(arc_h), res, err,
                                         rate, ratio, x_true))
                    advance(f"DC {orbit} ({truth},{stm}) {arc_h:g} h")

    ekf_runs = []
    ekf = file.ekf
    if ekf:
        orbit, truth = ekf.orbit, ekf.gravity
        x_true = setup.true_orbit(orbit, study)
        x_start = setup.initial_estimate(x_true, off)
        obs = observations(orbit, truth).arc(ekf.arc_h * 3600.0, str(path), "ekf.arc_h",
                                             ekf.arc_h)
        for stm in ekf.var_gravity:
            prop = Propagator(model(truth, "ekf.gravity"), model(stm, "ekf.var_gravity"))
            for label, sig in ekf.apriori.items():
                p0 = np.diag(np.square(np.asarray(sig, dtype=float)))
                res = extended_kalman_filter(obs, prop, x_start, p0, orientation=orient)
                ekf_runs.append(EKFRun(orbit, truth, stm, label, res))
                advance(f"EKF ({truth},{stm}) a priori {label}")

    r_runs = []
    rs = file.rsig
    if rs:
        x_true = setup.true_orbit(rs.orbit, study)
        t = np.arange(0.0, rs.hours * 3600.0 + 0.5 * rs.step_s, rs.step_s)
        for truth, stm in rs.cases:
            prop = Propagator(model(truth, "rsig.cases"), model(stm, "rsig.cases"))
            r_runs.append(RRun(rs.orbit, truth, stm, r_signature(prop, x_true, t, orient)))
            advance(f"R(t) ({truth},{stm})")

    arc_curves = []
    ra = file.rate_vs_arc
    if ra:
        x_true = setup.true_orbit(ra.orbit, study)
        arcs_h = ra.arcs_h.values()
        state_model = model(ra.gravity, "rate_vs_arc.gravity")
        obs = setup.simulated_observations(x_true, ra.gravity, setup.network_for(x_true, None,
                                                                               study),
                                           study, span_s=float(arcs_h[-1]) * 3600.0,
                                           noise=False, orient=orient)
        for stm in ra.var_gravity:
            var_model = model(stm, "rate_vs_arc.var_gravity")
            rates = [_rate_or_none(obs.window(a * 3600.0), state_model, var_model, x_true,
                                   orient) for a in arcs_h]
            arc_curves.append(_curve(ra.orbit, ra.gravity, stm, arcs_h, rates))
            advance(f"rho vs arc ({ra.gravity},{stm})")

    inc_curves = []
    ri = file.rate_vs_inclination
    if ri:
        x_orbit = setup.true_orbit(ri.orbit, study)
        stations = load_network(study.data, str(path), ri.network)
        incs = ri.inclinations_deg.values()
        state_model = model(ri.gravity, "rate_vs_inclination.gravity")
        data = []
        for inc in incs:
            x_i = with_inclination(x_orbit, np.radians(inc))
            try:
                o = setup.simulated_observations(x_i, ri.gravity, stations, study,
                                                 span_s=ri.arc_h * 3600.0, noise=False,
                                                 orient=orient)
            except TooFewMeasurementsError:
                o = None
            data.append((x_i, o))
        for stm in ri.var_gravity:
            var_model = model(stm, "rate_vs_inclination.var_gravity")
            rates = [None if o is None else _rate_or_none(o, state_model, var_model, x_i,
                                                          orient) for x_i, o in data]
            inc_curves.append(_curve(ri.orbit, ri.gravity, stm, incs, rates))
            advance(f"rho vs inclination ({ri.gravity},{stm})")

    trk = tracking(study)
    return StudyResults(tuple(dc_runs), tuple(blocks), tuple(ekf_runs),
                        ekf.title if ekf else "", ekf.last_passes if ekf else 0, tuple(r_runs),
                        trk.sigma, network, tuple(arc_curves),
                        tuple(inc_curves), ri.arc_h if ri else float("nan"),
                        ri.network if ri else "", settings, off,
                        setup.orientation_record(orient, np.array([0.0, trk.span_s])))
