"""The ``[ddor]`` table of tracking scenarios: ΔDOR baselines, their schedule and noise.

ΔDOR (:mod:`tapp.measurements.ddor`) is measured on a baseline, an ordered pair of tracked
stations; each baseline is its own entry on the T13 tape after the stations (number
n_ts + 1, ...; name ``A-B``; observables ``ddor``; the geodetic position of A), so TAPP III's
time-station flags turn a baseline's ΔDOR on and off apart from either station's own data.
Its partials w.r.t. the two stations' locations go to those stations' parameters::

    [ddor]
    baselines = [["GOLDSTONE", "CANBERRA"], ["GOLDSTONE", "MADRID"]]
    interval_s = 21600.0          # a point every 6 h while both stations see the spacecraft
                                  # (a multiple of tracking.data_interval_s); without it, one
                                  # point per mutual-visibility window, at its middle sample
    min_window_s = 1800.0         # mutual windows shorter than this give no point
    quasar_separation_deg = 5.0   # the reference quasar's angle from the spacecraft ...
    quasar_position_angle_deg = 0.0   # ... and its direction (north through east)
    quasar_position = true        # the quasar's (Δα cos δ, Δδ) as parameters of each baseline
    [ddor.fit]
    sigma_ns = 0.06               # or sigma_nrad (× the projected baseline length)
    [ddor.real]
    sigma_ns = 0.06               # white σ (default: the fit σ)
    bias_ns = 0.03                # constant over each mutual-visibility window, σ

With ``quasar_position = true`` each baseline has two parameters in q, ``A-B.quasar_ra_rad``
and ``A-B.quasar_dec_rad`` (kind "quasar", nominal 0, the baseline's tape number as their
station): the error of its reference quasar's catalogue position, Δα cos δ and Δδ in rad,
constant over the arc (one quasar's error, though the model keeps the quasar at its stated
angle from the moving spacecraft), with the partials of
:meth:`tapp.measurements.ddor.DdorModel.quasar_partials`.

Noise in ns is a delay, c σ km; noise in nrad is an angle, whose delay σ |b_proj| km grows
with the baseline length seen from the spacecraft
(:func:`tapp.measurements.ddor.projected_baseline_km`). Fit and real tables use the same of
the two. The windows are those of the tracking grid (``tracking.data_interval_s``,
``start``, ``end``) where both stations see the spacecraft above their masks and outside
their blackouts; the points of one window share its real-world bias.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, NoReturn

import numpy as np
from pydantic import Field

from tapp.constants import C_LIGHT_km_s
from tapp.errors import InputError
from tapp.io.noise_file import NonNegative, Positive
from tapp.io.schema import Schema
from tapp.measurements.ddor import DDOR_KIND, QUASAR_PARAMETER_NAMES
from tapp.measurements.noise import FitNoise, RealNoise
from tapp.measurements.stations import Station

#: Factors from the edge units to the noise units: ns -> km (× c), nrad -> rad.
NS_km = C_LIGHT_km_s * 1e-9
NRAD_rad = 1e-9
#: The kind of the quasar-position parameters on the tape.
QUASAR_KIND = "quasar"
#: Largest quasar separation accepted, deg: ΔDOR's reference sources are within ~10 deg.
MAX_SEPARATION_deg = 30.0


class DdorFitTable(Schema):
    """``[ddor.fit]``: the white-noise σ the fit assumes, in ns or in nrad (one of them)."""

    sigma_ns: Positive | None = Field(None, description="σ of a ΔDOR point as a delay.")
    sigma_nrad: Positive | None = Field(
        None, description="σ of a ΔDOR point as an angle (delay σ = it × the projected "
        "baseline length).")


class DdorRealTable(Schema):
    """``[ddor.real]``: the noise the ΔDOR points truly have, in the unit of [ddor.fit]."""

    sigma_ns: NonNegative | None = Field(None, description="White σ; default: the fit σ.")
    sigma_nrad: NonNegative | None = Field(None, description="White σ; default: the fit σ.")
    bias_ns: NonNegative | None = Field(
        None, description="σ of a bias constant over each mutual-visibility window.")
    bias_nrad: NonNegative | None = Field(
        None, description="σ of a bias constant over each mutual-visibility window.")


class DdorTable(Schema):
    """``[ddor]``: ΔDOR on baselines of tracked stations (tapp.tracking.ddor)."""

    baselines: Annotated[list[Annotated[list[str], Field(min_length=2, max_length=2)]],
                         Field(min_length=1)] = Field(
        description="Ordered station pairs [A, B] of tracking.stations; ΔDOR is B's arrival "
        "time minus A's.")
    interval_s: Positive | None = Field(
        None, description="A point every this many seconds while both stations see the "
        "spacecraft (a multiple of tracking.data_interval_s); default: one point per "
        "mutual-visibility window.")
    min_window_s: NonNegative = Field(0.0, description="Mutual-visibility windows shorter "
                                      "than this give no point.")
    quasar_separation_deg: Annotated[float, Field(ge=0.0, le=MAX_SEPARATION_deg)] = Field(
        5.0, description="Angle between the spacecraft and its reference quasar.")
    quasar_position_angle_deg: float = Field(
        0.0, description="Direction of the quasar from the spacecraft, from north through "
        "east.")
    quasar_position: bool = Field(
        False, description="The reference quasar's position error (Δα cos δ, Δδ, rad) as two "
        "parameters of each baseline in q.")
    fit: DdorFitTable = Field(description="Fit-world σ (ns or nrad).")
    real: DdorRealTable = Field(DdorRealTable(), description="Real-world noise; default: the "
                                "fit world's white noise.")


@dataclass(frozen=True, slots=True)
class TrackingBaseline:
    """A ΔDOR baseline as tracked in the scenario.

    Attributes
    ----------
    number : its entry on the tape, after the stations (n_ts + 1, ...).
    station_a, station_b : the tape numbers (1-based) of its stations in the scenario.
    name : ``A-B``.
    kinds : ("ddor",), as a station's observables.
    fit, real : the noise of the one kind, in the noise unit (km for ns, rad for nrad).
    per_nrad : True when σ is an angle (its delay is σ × the projected baseline).
    interval_s : a point every this many seconds, or None: one per window.
    min_window_s : windows shorter than this give no point.
    separation_rad, position_angle_rad : where the quasar is from the spacecraft.
    quasar_position : whether the quasar's position error is in q (:attr:`quasar_parameters`).
    """

    number: int
    station_a: int
    station_b: int
    name: str
    kinds: tuple[str, ...]
    fit: tuple[FitNoise, ...]
    real: tuple[RealNoise, ...]
    per_nrad: bool
    interval_s: float | None
    min_window_s: float
    separation_rad: float
    position_angle_rad: float
    quasar_position: bool = False

    @property
    def quasar_parameters(self) -> tuple[str, ...]:
        """Names of its quasar-position parameters in q (``A-B.quasar_ra_rad``, ...), rad."""
        return (tuple(f"{self.name}.{n}" for n in QUASAR_PARAMETER_NAMES)
                if self.quasar_position else ())


def _fail(source: str, field: str, expected: str, got: object = None) -> NoReturn:
    raise InputError(source, field, expected, got)


def _noise(source: str, table: DdorTable) -> tuple[FitNoise, RealNoise, bool]:
    fit = table.fit
    if (fit.sigma_ns is None) == (fit.sigma_nrad is None):
        _fail(source, "ddor.fit", "one of sigma_ns or sigma_nrad",
              {"sigma_ns": fit.sigma_ns, "sigma_nrad": fit.sigma_nrad})
    per_nrad = fit.sigma_nrad is not None
    unit, factor, other = ("nrad", NRAD_rad, "ns") if per_nrad else ("ns", NS_km, "nrad")
    real = table.real
    for key in (f"sigma_{other}", f"bias_{other}"):
        if getattr(real, key) is not None:
            _fail(source, f"ddor.real.{key}", f"ddor.real in {unit}, the unit of ddor.fit",
                  getattr(real, key))
    sigma = getattr(fit, f"sigma_{unit}")
    white = getattr(real, f"sigma_{unit}")
    bias = getattr(real, f"bias_{unit}")
    return (FitNoise(DDOR_KIND, sigma * factor),
            RealNoise(DDOR_KIND, (sigma if white is None else white) * factor,
                      (0.0 if bias is None else bias) * factor), per_nrad)


def tracking_baselines(source: str, table: DdorTable | None, stations: tuple[Station, ...],
                       data_interval_s: float) -> tuple[TrackingBaseline, ...]:
    """Build the baselines of a ``[ddor]`` table (none without one), numbered after the
    ``stations`` (those of tracking.stations, in order).

    Raises
    ------
    InputError
        A station not in tracking.stations, a baseline of one station or of two at the same
        place, a baseline given twice (in either order), noise in neither or both units (or
        mixed between fit and real), an interval that is not a multiple of the data interval.
    """
    if table is None:
        return ()
    fit, real, per_nrad = _noise(source, table)
    interval = table.interval_s
    if interval is not None:
        ratio = interval / data_interval_s
        if ratio < 1 - 1e-12 or abs(ratio - round(ratio)) > 1e-9 * ratio:
            _fail(source, "ddor.interval_s", "a multiple of tracking.data_interval_s = "
                  f"{data_interval_s:g} s (the points fall on the tracking grid)", interval)
    names = tuple(station.name for station in stations)
    out: list[TrackingBaseline] = []
    seen: set[frozenset[str]] = set()
    for i, (a, b) in enumerate(table.baselines):
        field = f"ddor.baselines[{i}]"
        for name in (a, b):
            if name not in names:
                _fail(source, field, f"stations of tracking.stations ({', '.join(names)})",
                      name)
        if a == b:
            _fail(source, field, "two different stations", [a, b])
        if np.array_equal(*(stations[names.index(name)].r_ecef_km for name in (a, b))):
            _fail(source, field, "two stations at different places (a baseline of zero "
                  "length measures nothing)", [a, b])
        if frozenset((a, b)) in seen:
            _fail(source, field, "each baseline once (in either order)", [a, b])
        seen.add(frozenset((a, b)))
        out.append(TrackingBaseline(
            number=len(names) + i + 1, station_a=names.index(a) + 1,
            station_b=names.index(b) + 1, name=f"{a}-{b}", kinds=(DDOR_KIND,), fit=(fit,),
            real=(real,), per_nrad=per_nrad, interval_s=interval,
            min_window_s=table.min_window_s,
            separation_rad=math.radians(table.quasar_separation_deg),
            position_angle_rad=math.radians(table.quasar_position_angle_deg),
            quasar_position=table.quasar_position))
    return tuple(out)
