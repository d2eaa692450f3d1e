"""The approximate-STM study file's schema: its tables, as declared types.

The study file (the shipped ``approx_stm.toml``, :data:`tapp.examples.STUDY_FILE`) is
validated as a whole against one schema, :class:`StudyFile` (``tapp.io.schema``: unknown keys
and sections are errors, booleans are not numbers, ...): ``epoch``, ``[orbits.NAME]``
(:class:`tapp.io.orbits.OrbitTable`), ``[stations.NAME]`` and ``[networks]``
(:mod:`tapp.io.stations_file`), ``[tracking]``, ``[noise.fit]`` (:mod:`tapp.io.noise_file`),
``[initial_offset]``, ``[dc_settings]``, ``[[dc]]``, ``[ekf]`` with ``[ekf.apriori]``,
``[rsig]``, ``[rate_vs_arc]`` and ``[rate_vs_inclination]`` (reference:
``docs/reference/study.md``). The runs name their models as every file does: ``gravity`` (the
state model, which simulates the data) and ``var_gravity`` (the variational models, one run
each); ``truth``, ``stm`` and ``[tracking]``'s σ keys are refused, naming the new key. Gravity
specs are checked by :func:`tapp.dynamics.parse_gravity`, orbit and station names against
their tables. Top-level ``earth_orientation`` ("iau2006", the default, or "gmst") and ``eop``
("iers", the default, "none" or a finals2000A file path relative to the study file) choose
the Earth orientation of every run (:mod:`tapp.od.setup`).

Reading the file into a value is :mod:`tapp.od.study_file`'s job; building a run's models,
orbits and data from it, :mod:`tapp.od.setup`'s.
"""

from __future__ import annotations

import math
from typing import Annotated

import numpy as np
from pydantic import Field, model_validator

from tapp.io.models_file import GravityName
from tapp.io.noise_file import FitTable
from tapp.io.orbits import OrbitTable
from tapp.io.schema import EarthOrientationName, EopSource, Invalid, Schema, UtcDate
from tapp.io.stations_file import StationsSection
from tapp.od.batch import MAX_ITERATIONS

Positive = Annotated[float, Field(gt=0)]


class StudyTracking(Schema):
    """``[tracking]``: the study's simulated tracking (its DATASIM): a file per orbit and
    gravity model, sampled while a station sees the spacecraft above its mask."""

    renamed_keys = {key: f"[noise.fit] {key}" for key in ("sigma_range_m",
                                                            "sigma_range_rate_mm_s")}

    data_interval_s: Positive = Field(description="Time between samples of each station.")
    span_days: Positive = Field(description="Span of each simulated observation file, from "
                                "the epoch; a run's arc is cut from it.")
    seed: Annotated[int, Field(ge=0)] = Field(0, description="Seed of the simulated noise "
                                              "(numpy SeedSequence).")
    equatorial_below_deg: Annotated[float, Field(gt=0, le=180)] = Field(
        description="Orbits inclined below this track from the network 'equatorial', the "
        "others from 'global', when a run names no network.")


class StudyNoise(Schema):
    """``[noise]``: the white noise of the simulated data, which every fit also assumes."""

    fit: FitTable = Field(description="σ of range and range rate (the study tracks no angles).")

    @model_validator(mode="after")
    def _range_and_range_rate(self) -> StudyNoise:
        for key in ("sigma_azimuth_deg", "sigma_elevation_deg"):
            if getattr(self.fit, key) is not None:
                raise Invalid("no angle σ (the study tracks range and range rate)",
                              getattr(self.fit, key), f"fit.{key}")
        for key in ("sigma_range_m", "sigma_range_rate_mm_s"):
            if getattr(self.fit, key) is None:
                raise Invalid("a value (the study tracks range and range rate)", None,
                              f"fit.{key}")
        return self


class InitialOffset(Schema):
    """``[initial_offset]``: the brief's initial estimate, an error added to the true
    elements of every orbit: Δa (m), Δe, Δi (deg).

    ``de`` is added to each orbit's e (the brief: e = 0.00012 for the circular orbits,
    0.10012 for SATORB7). ``e`` instead *sets* e for every orbit: the earlier reading of the
    brief, kept so that study files written for it still read; give one of the two.
    """

    da_m: float = Field(description="Error added to the semi-major axis.")
    de: float | None = Field(None, description="Error added to the eccentricity (or e).",
                             json_schema_extra={"unit": "1"})
    e: Annotated[float, Field(ge=0, lt=1)] | None = Field(
        None, description="The eccentricity every initial estimate starts from, in place of "
        "de (an earlier reading of the brief).", json_schema_extra={"unit": "1"})
    di_deg: float = Field(description="Error added to the inclination.")

    @model_validator(mode="after")
    def _one_e(self) -> InitialOffset:
        if (self.de is None) == (self.e is None):
            raise Invalid("either de (added to e) or e (replacing it), not both",
                          "both" if self.de is not None else "neither", "de")
        return self


class DCSettingsTable(Schema):
    """``[dc_settings]``: the iteration control of every DC run
    (:class:`tapp.od.batch.DCSettings`)."""

    max_iterations: Annotated[int, Field(ge=2, le=MAX_ITERATIONS)] = Field(
        15, description="Iterations at most; a DC still converging then ends as such.")
    rms_rel_tol: Positive = Field(1e-3, description="The weighted RMS has settled when it "
                                  "changes by less than this, relative.",
                                  json_schema_extra={"unit": "1"})
    divergence_ratio: Annotated[float, Field(gt=1)] = Field(
        10.0, description="Diverged when the RMS exceeds this times its smallest value so far.",
        json_schema_extra={"unit": "1"})
    rms_floor: Positive = Field(1e-6, description="Converged when the RMS falls below this "
                                "(a noise-free fit).", json_schema_extra={"unit": "1"})
    rms_fit_limit: Positive = Field(3.0, description="A settled RMS above this is a stall: "
                                    "the data are not fitted.", json_schema_extra={"unit": "1"})
    trend_window: Annotated[int, Field(ge=2)] = Field(
        10, description="Iterations over which the contraction factor is measured (at least).")
    max_condition: Annotated[float, Field(gt=1)] = Field(
        1e10, description="A normal matrix (scaled to a unit diagonal) of a larger condition "
        "number at the first iteration is diagnosed, not iterated on.",
        json_schema_extra={"unit": "1"})


class StudyModels(Schema):
    """The two models of a study run, named as in every other file (the study's own
    ``truth`` and ``stm`` are refused, naming the new key)."""

    renamed_keys = {"truth": "gravity", "stm": "var_gravity"}

    gravity: GravityName = Field(
        description="The Earth's gravity field of the state model: the data are simulated "
        "with it and every fit's trajectory moves under it.")
    var_gravity: Annotated[list[GravityName], Field(min_length=1)] = Field(
        description="The variational models, one run (or curve) each: the Earth field whose "
        "Jacobian drives the fit's STM (the truncated variational equations).")


class DCBlock(StudyModels):
    """One ``[[dc]]`` block: a batch DC for every orbit x variational model x arc."""

    title: str | None = Field(None, description="Heading of the block's table in the report.")
    orbits: Annotated[list[str], Field(min_length=1)] = Field(
        description="Names of [orbits.NAME] tables.")
    arcs_h: Annotated[list[Positive], Field(min_length=1)] = Field(
        description="Arc lengths, from the epoch.")


class EKFBlock(StudyModels):
    """``[ekf]``: an extended Kalman filter for one orbit, every variational model x a priori."""

    title: str = Field("EKF", description="Heading of the EKF table in the report.")
    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    arc_h: Positive = Field(description="Arc length, from the epoch.")
    last_passes: Annotated[int, Field(ge=1)] = Field(
        6, description="Passes at the end of the arc whose largest |O-C| the report shows.")
    apriori: dict[str, Annotated[list[Positive], Field(min_length=6, max_length=6)]] = Field(
        {}, description="A priori σ by label: x, y, z (km), vx, vy, vz (km/s).",
        json_schema_extra={"unit": "km, km/s"})


class RSigBlock(Schema):
    """``[rsig]``: the error-growth signature R(t) of (state, variational) model pairs."""

    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    hours: Positive = Field(description="Span of the curves, from the epoch.",
                            json_schema_extra={"unit": "h"})
    step_s: Positive = Field(description="Sampling of the curves.")
    cases: list[Annotated[list[GravityName], Field(min_length=2, max_length=2)]] = Field(
        description="[gravity, var_gravity] pairs, one curve each.")


class Grid(Schema):
    """A grid ``first``, ``first + step``, ... up to ``last`` (inclusive), in the field's
    units."""

    first: Annotated[float, Field(ge=0)] = Field(description="The first point.")
    last: Annotated[float, Field(ge=0)] = Field(description="The last point (inclusive).")
    step: Positive = Field(description="The spacing (at most 1000 points).")

    @model_validator(mode="after")
    def _ordered(self) -> Grid:
        if self.last < self.first:
            raise Invalid(f"last >= first ({self.first:g})", self.last, "last")
        if (self.last - self.first) / self.step > 1000:
            raise Invalid("at most 1000 grid points", (self.last - self.first) / self.step,
                          "step")
        return self

    def values(self) -> np.ndarray:
        """The grid points (n,)."""
        n = int(math.floor((self.last - self.first) / self.step + 1e-9))
        return self.first + self.step * np.arange(n + 1)


class RateVsArcBlock(StudyModels):
    """``[rate_vs_arc]``: the predicted DC rate ρ against arc length, for one orbit."""

    orbit: str = Field(description="Name of an [orbits.NAME] table.")
    arcs_h: Grid = Field(description="The arc lengths, as a grid {first, last, step} (h).")


class RateVsInclinationBlock(StudyModels):
    """``[rate_vs_inclination]``: ρ against inclination (deg) of ``orbit``'s elements over one
    arc, seen from one ``network`` (the same stations at every inclination)."""

    orbit: str = Field(description="Name of an [orbits.NAME] table given by elements.")
    arc_h: Positive = Field(description="Arc length, from the epoch.")
    network: str = Field(description="A network of [networks], or a station name.")
    inclinations_deg: Grid = Field(description="The inclinations, as a grid {first, last, "
                                   "step} within 0..180 (deg).")

    @model_validator(mode="after")
    def _range(self) -> RateVsInclinationBlock:
        if self.inclinations_deg.last > 180:
            raise Invalid("inclinations within 0..180 deg", self.inclinations_deg.last,
                          "inclinations_deg.last")
        return self


class StudyFile(StationsSection):
    """Schema of the study file."""

    epoch: UtcDate = Field(description="UTC at t = 0: the orbits' epoch and the "
                                     "start of the simulated tracking.")
    earth_orientation: EarthOrientationName = "iau2006"
    eop: EopSource = "iers"
    orbits: dict[str, OrbitTable] = Field({}, description="The true orbits, by name (--orbit "
                                          "NAME).")
    tracking: StudyTracking = Field(description="The simulated tracking.")
    noise: StudyNoise = Field(description="The noise of the simulated data.")
    initial_offset: InitialOffset = Field(description="The error of every initial estimate.")
    dc_settings: DCSettingsTable = Field(DCSettingsTable(), description="Iteration control "
                                         "of every DC.")
    dc: list[DCBlock] = Field([], description="Batch DC runs.")
    ekf: EKFBlock | None = Field(None, description="EKF runs.")
    rsig: RSigBlock | None = Field(None, description="R(t) curves.")
    rate_vs_arc: RateVsArcBlock | None = Field(None, description="ρ against arc length.")
    rate_vs_inclination: RateVsInclinationBlock | None = Field(
        None, description="ρ against inclination.")

    @model_validator(mode="after")
    def _names_exist(self) -> StudyFile:
        known = ", ".join(self.orbits) or "none"
        for i, block in enumerate(self.dc):
            for j, orbit in enumerate(block.orbits):
                if orbit not in self.orbits:
                    raise Invalid(f"an orbit of [orbits.*] ({known})", orbit,
                                  f"dc[{i}].orbits[{j}]")
        for key, block in (("ekf", self.ekf), ("rsig", self.rsig),
                           ("rate_vs_arc", self.rate_vs_arc),
                           ("rate_vs_inclination", self.rate_vs_inclination)):
            if block is not None and block.orbit not in self.orbits:
                raise Invalid(f"an orbit of [orbits.*] ({known})", block.orbit, f"{key}.orbit")
        inc = self.rate_vs_inclination
        if inc is not None and inc.network not in self.networks and inc.network not in \
                self.stations:
            raise Invalid(f"a network of [networks] ({', '.join(self.networks)}) or a station",
                          inc.network, "rate_vs_inclination.network")
        return self
