"""Tracking observations: the data set, its simulation (the study's DATASIM) and prediction.

An :class:`Observations` holds M time-tagged rows, each from one station, with the
observable kinds of the set (range km, range-rate km/s by default) and their standard
deviations, and, when known, the Earth orientation they were made under
(:class:`MadeUnder`). Simulated data and data read from a file (:mod:`tapp.io.obsfile`) are
the same type, so real tracking data could be processed the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from tapp.dynamics import Propagator
from tapp.errors import InputError, TooFewMeasurementsError
from tapp.frames.orientation import EarthOrientation
from tapp.measurements.observables import MeasurementModel
from tapp.measurements.stations import Station
from tapp.measurements.visibility import find_passes

#: The EOP source recorded for observations made under gmst, which uses none.
NO_EOP = "not used"


@dataclass(frozen=True, slots=True)
class MadeUnder:
    """The Earth orientation observations were made under: what a station's place in the
    inertial frame, and so every computed observable, depends on.

    Attributes
    ----------
    earth_orientation : the model, "iau2006" or "gmst" (:mod:`tapp.frames.orientation`).
    eop : the EOP source: the IERS table's file name (``finals2000A.all``), "none (UT1 = UTC,
        no polar motion)", or :data:`NO_EOP` under gmst
        (:attr:`tapp.frames.orientation.EarthOrientation.eop_note`).
    frame : the inertial frame of the orbit, "GCRS" (iau2006) or "EME2000" (gmst).
    """

    earth_orientation: str
    eop: str
    frame: str

    @classmethod
    def of(cls, orientation: EarthOrientation) -> MadeUnder:
        """The record of data made under ``orientation``."""
        return cls(orientation.model, orientation.eop_note or NO_EOP, orientation.frame)

    def as_dict(self) -> dict[str, str]:
        """The fields by name, in order (:data:`MADE_UNDER_KEYS`)."""
        return {key: getattr(self, key) for key in MADE_UNDER_KEYS}


#: The names under which files record a :class:`MadeUnder`, in order.
MADE_UNDER_KEYS = tuple(f.name for f in fields(MadeUnder))


@dataclass(frozen=True, slots=True)
class Observations:
    """M observations, time-ordered.

    Attributes
    ----------
    t_s : (M,) receive times, seconds from the epoch, non-decreasing.
    station : (M,) int, index into ``stations``.
    values : (M, k) observed values, units of ``kinds`` (km, km/s, rad).
    stations : the stations, in index order.
    kinds : observable kinds of the columns.
    sigma : (k,) standard deviations of the columns, same units.
    span_s : end of the time span the data set covers, s from the epoch (the end of the
        tracking schedule: a station may see nothing in its last minutes); None when not
        known, then the last observation time stands for it (:attr:`end_s`).
    made_under : the Earth orientation the data were made under; None when not known (a
        file that states none, e.g. one written by another tool).
    """

    t_s: np.ndarray
    station: np.ndarray
    values: np.ndarray
    stations: tuple[Station, ...]
    kinds: tuple[str, ...]
    sigma: np.ndarray
    span_s: float | None = None
    made_under: MadeUnder | None = None

    def __post_init__(self) -> None:
        m = self.t_s.shape[0]
        if self.station.shape != (m,) or self.values.shape != (m, len(self.kinds)):
            raise InputError("observations", "shape", f"t_s (M,), station (M,), values "
                             f"(M, {len(self.kinds)})", (self.station.shape, self.values.shape))
        if np.any(np.diff(self.t_s) < 0):
            raise InputError("observations", "t_s", "non-decreasing times")
        if np.any(self.sigma <= 0) or self.sigma.shape != (len(self.kinds),):
            raise InputError("observations", "sigma", f"{len(self.kinds)} values > 0", self.sigma)

    @property
    def count(self) -> int:
        """Number of scalar measurements, M k."""
        return int(self.values.size)

    @property
    def end_s(self) -> float:
        """End of the data span, s from the epoch: ``span_s``, else the last observation
        time (0 without observations)."""
        if self.span_s is not None:
            return float(self.span_s)
        return float(self.t_s[-1]) if self.t_s.size else 0.0

    def window(self, t_end_s: float) -> Observations:
        """Return the observations with t <= t_end_s (an arc of the data set)."""
        keep = self.t_s <= t_end_s
        return Observations(self.t_s[keep], self.station[keep], self.values[keep],
                            self.stations, self.kinds, self.sigma,
                            min(self.end_s, float(t_end_s)), self.made_under)

    def arc(self, arc_s: float, source: str = "--arc", field: str = "value",
            got: object = None) -> Observations:
        """Return the first ``arc_s`` seconds of the data.

        Raises
        ------
        InputError
            ``arc_s`` is longer than the data span (:attr:`end_s`, with 1 ms of slack): names
            ``source`` (the option or file that asked for the arc), ``field`` and the span.
        """
        end = self.end_s
        if arc_s > end + 1e-3:
            raise InputError(source, field, f"an arc no longer than the data span, 0 .. "
                             f"{end:.0f} s from the epoch ({end / 3600:.4g} h = "
                             f"{end / 86400:.4g} d)", arc_s if got is None else got)
        return self.window(arc_s)

    def passes(self) -> list[np.ndarray]:
        """Return the row indices of each pass (contiguous visibility of one station)."""
        out = []
        for s in range(len(self.stations)):
            rows = np.flatnonzero(self.station == s)
            if rows.size == 0:
                continue
            # a gap of more than 3 sampling intervals ends a pass
            dt = np.diff(self.t_s[rows])
            step = np.median(dt) if dt.size else 0.0
            for start, stop in find_passes(np.ones(rows.size, bool), self.t_s[rows],
                                           max_gap_s=3 * step if step > 0 else None):
                out.append(rows[start:stop])
        out.sort(key=lambda r: self.t_s[r[0]])
        return out


def predict(obs: Observations, states: np.ndarray, orientation: EarthOrientation
            ) -> tuple[np.ndarray, np.ndarray]:
    """Return computed observables h (M, k) and H = ∂h/∂x (M, k, 6) at states (M, 6), the
    stations placed by ``orientation``."""
    h = np.empty_like(obs.values)
    big_h = np.empty(obs.values.shape + (6,))
    for s, station in enumerate(obs.stations):
        rows = obs.station == s
        if not np.any(rows):
            continue
        model = MeasurementModel(station, orientation, obs.kinds)
        h[rows] = model.compute(obs.t_s[rows], states[rows])
        big_h[rows] = model.state_partials(obs.t_s[rows], states[rows])
    return h, big_h


def residuals(obs: Observations, computed: np.ndarray) -> np.ndarray:
    """Return O - C (M, k), angles wrapped, through the measurement model's residual."""
    # the residual (O - C, angles wrapped) does not depend on where the station is
    model = MeasurementModel(obs.stations[0], EarthOrientation.gmst_angle(0.0), obs.kinds)
    return model.residual(obs.values, computed)


def simulate(truth: Propagator, x0: np.ndarray, stations: tuple[Station, ...],
             t_grid_s: np.ndarray, sigma: np.ndarray, rng: np.random.Generator | None,
             orientation: EarthOrientation,
             kinds: tuple[str, ...] = ("range", "range_rate"),
             epoch_jd_utc: float | None = None) -> Observations:
    """Simulate tracking: the truth trajectory seen by each station above its mask.

    Every grid time at which a station sees the spacecraft gives one row; white Gaussian
    noise of ``sigma`` (k,) is added when ``rng`` is given (noise-free otherwise).
    ``orientation`` places the stations and orients ``truth``'s field (its model must be
    that of ``truth``'s force model); the data record it (``made_under``).

    Raises
    ------
    TooFewMeasurementsError
        When no station sees the spacecraft on the grid.
    """
    traj = truth.propagate(x0, t_grid_s, stm=False, epoch_jd_utc=epoch_jd_utc,
                           orientation=orientation)
    rows_t, rows_s, rows_v = [], [], []
    for s, station in enumerate(stations):
        model = MeasurementModel(station, orientation, kinds)
        visible = model.elevation_rad(traj.t_s, traj.states) > station.elev_mask_rad
        if not np.any(visible):
            continue
        rows_t.append(traj.t_s[visible])
        rows_s.append(np.full(int(visible.sum()), s))
        rows_v.append(model.compute(traj.t_s[visible], traj.states[visible]))
    if not rows_t:
        raise TooFewMeasurementsError(6, 0)
    t = np.concatenate(rows_t)
    order = np.argsort(t, kind="stable")
    values = np.concatenate(rows_v)[order]
    sigma = np.asarray(sigma, dtype=float)
    if rng is not None:
        values = values + rng.standard_normal(values.shape) * sigma
    return Observations(t[order], np.concatenate(rows_s)[order], values, tuple(stations),
                        tuple(kinds), sigma, float(traj.t_s[-1]), MadeUnder.of(orientation))
