"""A run of the approximate-STM study built from its study file: Earth orientation, force
models, true orbits, initial estimates, station networks and simulated observations.

Everything a DC, EKF or R(t) run needs besides the estimator: the CLI commands, the front door
(:mod:`tapp.api.od`) and the study runner (:mod:`tapp.od.study`) share these functions so a
single run and the full study use the same data. Every function takes the study
(:class:`tapp.od.study_file.Study`, read once by :func:`tapp.od.study_file.read_study`)
explicitly.

Earth orientation: the study file's ``earth_orientation`` and ``eop``. One model serves
everything a run computes: the stations of the simulated data and of the estimator, and the
geopotential of every force model built here (:func:`force_model`). :func:`orientation`
builds it once per study and model (a CLI's ``--earth-orientation`` passes its model in place
of the file's) and checks that the EOP table covers the epoch and the tracking span.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.dynamics import ForceModel, Propagator, earth_model
from tapp.errors import InputError
from tapp.frames.orientation import EarthOrientation, check_model
from tapp.io.eop_file import orientation_for
from tapp.io.orbits import parse_orbit
from tapp.io.stations_file import load_network
from tapp.measurements.observations import MadeUnder, Observations, simulate
from tapp.measurements.stations import Station
from tapp.od.study_file import Offset, Study, epoch, tracking
from tapp.orbit.elements import cartesian_to_elements, elements_to_cartesian


def earth_orientation_name(study: Study, model: str | None = None) -> str:
    """Return the Earth orientation model of a run: ``model`` (a CLI override) or the file's."""
    if model is not None:
        return check_model(model, "--earth-orientation", "value")
    return study.file.earth_orientation


@cache
def _orientation(study: Study, model: str) -> EarthOrientation:
    source = str(study.path)
    orient = orientation_for(model, epoch(study), study.file.eop, study.path.parent, source)
    # the simulated tracking span (observations read from a file are checked as they are used)
    orient.check_covers(np.array([0.0, tracking(study).span_s]), source)
    return orient


def orientation(study: Study, model: str | None = None) -> EarthOrientation:
    """Return the study's Earth orientation (cached per study and model; module docstring).

    ``model`` overrides the file's ``earth_orientation`` (the CLI's ``--earth-orientation``).

    Raises
    ------
    InputError
        An unknown model (naming ``--earth-orientation``), an unreadable EOP file, or an epoch
        or tracking span outside the EOP table (naming the file and the epoch).
    """
    model = earth_orientation_name(study, model)
    return _orientation(study, model)


def orientation_record(orient: EarthOrientation, t_s: np.ndarray | None = None) -> dict:
    """The orientation for reports and JSON: ``model``, ``eop`` (its source, "" for gmst) and
    ``predicted_eop`` (True if any time t_s, s from the epoch, lies past the measured EOP)."""
    return {"model": orient.model, "eop": orient.eop_note,
            "predicted_eop": bool(t_s is not None and orient.uses_predicted_eop(t_s))}


def describe_orientation(record: dict) -> str:
    """One line for reports from an :func:`orientation_record`."""
    if record["model"] == "gmst":
        return "gmst (GMST IAU-82 + ω t, UT1 = UTC; no precession, nutation or polar motion)"
    predicted = "; predicted EOP used" if record["predicted_eop"] else ""
    return f"iau2006 (IAU 2006/2000A; EOP {record['eop']}{predicted})"


def _describe_made_under(made: MadeUnder) -> str:
    return f"{made.earth_orientation} (EOP {made.eop}, frame {made.frame})"


def check_made_under(obs: Observations, orient: EarthOrientation, source: str,
                     study: Study, chosen: bool = False) -> str | None:
    """Check observations read from ``source`` against the run's Earth orientation
    ``orient``; return a note for the user (one line) or None, or raise InputError.

    Where data meet a model: observations made under one Earth orientation and fitted under
    another are off by the difference of the station places (31.5 km at Goldstone between
    iau2006 and gmst on 2026-01-01), and a DC on them settles tens of km from the orbit
    (41.5 km for ``tapp simulate``'s TDM of ``leo_equatorial.toml`` fitted under
    the study's gmst). The file's record (``obs.made_under``, :mod:`tapp.io.obsfile`):

    - states the run's model, EOP source and frame: None;
    - states another, and the run's model is the study file's (``chosen`` False): refused,
      naming the file, the first field that differs, both values and ``--earth-orientation``
      (the option that sets the run's model);
    - states another, and ``--earth-orientation`` chose the run's model (``chosen``): the
      analyst asked for this fit; a note saying what the file states and what is used (a
      DC whose data its model does not explain then fails the noise-model test, exit 7);
    - states nothing: a note, and the data are taken as made under the run's model. Not
      refused, because files written by other tools (the CCSDS examples of
      ``tests/data/ccsds-tdm``, real tracking data) state no model: real data are made by
      the Earth itself, and the model that reduces them is the analyst's choice, which the
      study file or the option makes. Not assumed wrong either, which would be a silent
      answer of its own. A wrong choice still shows in the DC, whose residuals then fail
      the noise-model test (:func:`tapp.od.batch.rms_bound`, exit 7).

    Raises
    ------
    InputError
        A mismatch when not ``chosen`` (above).
    """
    run = MadeUnder.of(orient)
    made = obs.made_under
    if made is None:
        return (f"{source} states no Earth orientation its observations were made under "
                f"(earth_orientation, eop, frame); taken as the fit's, "
                f"{_describe_made_under(run)}")
    if made == run:
        return None
    if chosen:
        return (f"{source} states observations made under {_describe_made_under(made)}; "
                f"fitted under {_describe_made_under(run)} as --earth-orientation asks")
    model, path = run.earth_orientation, study.path
    rows = (("earth_orientation", "Earth orientation model", f"{path}'s earth_orientation; "
             f"--earth-orientation {made.earth_orientation} fits them under theirs, "
             f"--earth-orientation {model} under {model} regardless"),
            ("eop", "EOP source", f"{path}'s eop; set it to theirs, or "
             f"--earth-orientation {model} fits them regardless"),
            ("frame", "inertial frame", f"that of {model}; --earth-orientation {model} fits "
             "them regardless"))
    # the first field that differs (made != run: there is one)
    key, what, how = next(row for row in rows if getattr(made, row[0]) != getattr(run, row[0]))
    raise InputError(source, key, f"observations made under the fit's {what} "
                     f"{getattr(run, key)} ({how})", getattr(made, key))


def force_model(spec: str, orient: EarthOrientation, source: str, field: str) -> ForceModel:
    """Return the Earth force model of a gravity spec under the run's Earth orientation (a bad
    spec names ``source`` and ``field``)."""
    return earth_model(spec, source=source, field=field, earth_orientation=orient.model)



def initial_estimate(x_true: np.ndarray, off: Offset) -> np.ndarray:
    """Return the brief's initial estimate: the elements of x_true (6,) with a + Δa,
    e + Δe (or e := ``off.e`` when set), i + Δi, the other elements unchanged.

    Raises
    ------
    InputError
        The offset makes e negative or >= 1.
    """
    el = np.array(cartesian_to_elements(x_true, GM_EARTH_km3_s2), dtype=float)
    el[0] += off.da_km
    el[1] = el[1] + off.de if off.e is None else off.e
    el[2] += off.di_rad
    if not 0 <= el[1] < 1:
        raise InputError("initial_offset", "de", "an offset leaving 0 <= e < 1", el[1])
    return np.asarray(elements_to_cartesian(el, GM_EARTH_km3_s2), dtype=float)


def true_orbit(spec: str, study: Study, *, allow_subsurface: bool = False) -> np.ndarray:
    """Return the true initial state of an orbit name (of the study's ``[orbits]``) or spec
    (see :mod:`tapp.io.orbits`).

    ``allow_subsurface`` accepts an orbit whose perigee is below the Earth's surface.
    """
    return parse_orbit(spec, scenario=study.path, orbits=study.file.orbits,
                       allow_subsurface=allow_subsurface)


def network_for(x_true: np.ndarray, name: str | None, study: Study) -> tuple[Station, ...]:
    """Return the named network/station, or the default for the orbit's inclination."""
    if name is None:
        h = np.cross(x_true[:3], x_true[3:])
        inc = math.acos(abs(h[2]) / np.linalg.norm(h))
        name = "equatorial" if inc < tracking(study).equatorial_below_rad else "global"
    return load_network(study.data, str(study.path), name)


def simulated_observations(x_true: np.ndarray, truth_spec: str, stations: tuple[Station, ...],
                           study: Study, seed: int | None = None,
                           span_s: float | None = None, noise: bool = True,
                           orient: EarthOrientation | None = None) -> Observations:
    """Simulate the study's 5-day observation file for one orbit and truth model.

    ``span_s`` shortens the file (default: the scenario's span); ``noise=False`` gives the
    noise-free values (for a prediction that needs only the times and the stations);
    ``orient`` is the Earth orientation of the stations and of the truth's field (default: the
    file's, :func:`orientation`).
    """
    orient = orientation(study) if orient is None else orient
    trk = tracking(study)
    span = trk.span_s if span_s is None else min(span_s, trk.span_s)
    t = np.arange(0.0, span + 0.5 * trk.data_interval_s, trk.data_interval_s)
    t = t[t <= span + 1e-9 * max(span, 1.0)]
    rng = np.random.default_rng(trk.seed if seed is None else seed) if noise else None
    truth = Propagator(force_model(truth_spec, orient, str(study.path), "truth"))
    return simulate(truth, x_true, stations, t, trk.sigma, rng, orient)
