"""The approximate-STM study file read into a value, and the plain settings it states.

:func:`read_study` reads and validates a study file once (schema:
:class:`tapp.od.study_schema.StudyFile`) into a :class:`Study`; every function of this
module and of :mod:`tapp.od.setup` takes that value, explicitly: none falls back to the
shipped study, so that a user's file cannot be silently ignored. The shipped study
(:func:`shipped_study`) is the default only where a user sees it: the front door
(:mod:`tapp.api.od`) and the commands' ``--scenario``.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from tapp.examples import STUDY_FILE
from tapp.frames.time import Epoch, parse_epoch
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml
from tapp.od.study_schema import StudyFile

#: The observable kinds of the study's tracking, in the order of ``Tracking.sigma``.
KINDS = ("range", "range_rate")


@dataclass(frozen=True, slots=True)
class Tracking:
    """Simulated tracking: sampling (s), span (s), noise (km, km/s), seed, and the
    inclination (rad) below which the equatorial network is the default."""

    data_interval_s: float
    span_s: float
    sigma: np.ndarray
    seed: int
    equatorial_below_rad: float


@dataclass(frozen=True, slots=True)
class Offset:
    """The brief's initial estimate: Δa (km), Δe added (or e set, when ``e`` is given), Δi
    (rad)."""

    da_km: float
    de: float
    di_rad: float
    e: float | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Study:
    """A study file, read and validated once (:func:`read_study`): what every function of this
    module and of :mod:`tapp.od.setup` takes.

    Compared and hashed by identity, so that :func:`tapp.od.setup.orientation` builds the
    Earth orientation of one study once per model.

    Attributes
    ----------
    path : Path
        The file: errors name it, and an ``eop`` file path is taken from its folder.
    data : dict
        The parsed TOML (the tables :func:`tapp.io.stations_file.load_network` reads, the
        EKF's a priori).
    file : StudyFile
        The same, validated.
    """

    path: Path
    data: dict
    file: StudyFile


def read_study(path: Path | str) -> Study:
    """Read and validate a study file; errors name the file and the field."""
    data = read_toml(path)
    return Study(Path(path), data, validate(StudyFile, data, str(path)))


@cache
def shipped_study() -> Study:
    """The shipped study file (:data:`tapp.examples.STUDY_FILE`), read once: the default
    study of the front door and the commands."""
    return read_study(STUDY_FILE)


def epoch(study: Study) -> Epoch:
    """Return the study's epoch (UTC), the t = 0 of its observations."""
    text = study.file.epoch
    if isinstance(text, dt.datetime):
        text = text.isoformat().removesuffix("+00:00")
    return parse_epoch(text, source=str(study.path))


def tracking(study: Study) -> Tracking:
    """Return the ``[tracking]`` settings."""
    file = study.file
    table, fit = file.tracking, file.noise.fit
    sigma = np.array([fit.sigma_range_m * 1e-3, fit.sigma_range_rate_mm_s * 1e-6])
    return Tracking(table.data_interval_s, table.span_days * 86400.0, sigma, table.seed,
                    math.radians(table.equatorial_below_deg))


def offset(study: Study) -> Offset:
    """Return the ``[initial_offset]`` of the brief."""
    table = study.file.initial_offset
    return Offset(table.da_m * 1e-3, table.de or 0.0, math.radians(table.di_deg), table.e)
