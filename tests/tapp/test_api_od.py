"""The front door's estimators (:mod:`tapp.api.od`: ``tapp.fit``, ``tapp.ekf``, ``tapp.rsig``)
against ``tapp dc``, ``tapp ekf`` and ``tapp rsig`` on the same inputs (short arcs of SATORB1
of the shipped study): the same JSON and printout, paths the same as objects in memory, the
commands' errors, plots on the axes they are given, and the DC's internals (its last
iteration's STM against central differences of re-propagated trajectories)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure
from typer.testing import CliRunner

import tapp
import tapp.cli  # noqa: F401  (registers every command)
from tapp.cli.common import app
from tapp.dynamics import Propagator
from tapp.errors import InputError
from tapp.examples import STUDY_FILE
from tapp.io.obsfile import read_observations
from tapp.io.stations_file import load_stations
from tapp.od.batch import DCOutcome
from tapp.od.ekf import process_noise
from tapp.od.exits import EXIT_CODES, ILL_CONDITIONED
from tapp.od.runs import IllConditionedFit
from tapp.od.study_file import KINDS, epoch, read_study, shipped_study, tracking
from tapp.report.od_runs import ill_conditioned_json

runner = CliRunner()

DC_ARGS = ("--orbit", "SATORB1", "--arc", "6h")
EKF_ARGS = ("--orbit", "SATORB1", "--arc", "3h", "--apriori", "2")
RSIG_ARGS = ("--orbit", "SATORB1", "--truth", "J0", "--stm", "J0", "--span", "2h", "--step",
             "600s")
#: Central-difference steps of the epoch state: 10 m in position, 1 cm/s in velocity. The
#: integrator's error (tolerance 1e-13) over the step dominates the difference's error and
#: falls as the step grows: measured 6e-8 of a column here (3.5e-7 at 1 m and 1 mm/s, 4e-5 at
#: 1 cm and 10 µm/s); the truncation error (h² of the third derivative) is below it.
STEP_KM, STEP_KM_S = 1e-2, 1e-5
#: How far a central difference may fall from the variational STM, relative to the largest
#: entry of its column (a J0 STM in a J2 field, the study's truncation, falls 0.58 off).
FD_AGREEMENT = 1e-6
#: The RMS of the recomputed residuals against the iteration's, relative (rounding).
ROUNDING = 1e-12


def _cli(args: list[str] | tuple[str, ...], code: int = 0):
    res = runner.invoke(app, list(args))
    assert res.exit_code == code, (res.output, res.exception)
    return res


def _plain(content: dict) -> dict:
    """A result's JSON as the commands write it (arrays as lists)."""
    return json.loads(json.dumps(content, default=lambda a: a.tolist()))


@pytest.fixture(scope="module")
def dc() -> tapp.FitResult:
    return tapp.fit("SATORB1", arc="6h")


@pytest.fixture(scope="module")
def ekf() -> tapp.FilterResult:
    return tapp.ekf("SATORB1", arc="3h", apriori="2")


@pytest.fixture(scope="module")
def rsig() -> tapp.RSigResult:
    return tapp.rsig("SATORB1", truth="J0", stm="J0", span="2h", step="600s")


def test_the_front_door_writes_the_commands_json(dc, ekf, rsig) -> None:
    for result, command, args in ((dc, "dc", DC_ARGS), (ekf, "ekf", EKF_ARGS),
                                  (rsig, "rsig", RSIG_ARGS)):
        printed = json.loads(_cli([command, *args, "--json", "-"]).stdout)
        assert _plain(result.to_json()) == printed, command
    assert dc.status == "converged" and dc.exit_code == 0
    assert dc.to_json()["iterations"] == len(dc.iterations) > 1


def test_the_front_door_prints_the_commands_printout(dc, ekf, rsig) -> None:
    for result, command, args in ((dc, "dc", DC_ARGS), (ekf, "ekf", EKF_ARGS),
                                  (rsig, "rsig", RSIG_ARGS)):
        assert result.text() == _cli([command, *args]).stdout, command
    assert "DC SATORB1, 6h, (J2,J2), gmst: converged" in dc.text()


def test_paths_and_objects_give_the_same_run(dc, tmp_path: Path) -> None:
    """The study as a path, as text, or read; the observations as a file or in memory (read
    with the study's station table, as ``--obs`` reads them)."""
    for study in (STUDY_FILE, str(STUDY_FILE), read_study(STUDY_FILE)):
        assert _plain(tapp.fit("SATORB1", arc="6h", study=study).to_json()) == \
            _plain(dc.to_json())
    saved = tmp_path / "obs.h5"
    _cli(["dc", *DC_ARGS, "--save-obs", str(saved)])
    study = shipped_study()
    observations = read_observations(saved, load_stations(study.data, str(study.path)),
                                      tracking(study).sigma, epoch=epoch(study),
                                      sigma_kinds=KINDS)
    by_path = tapp.fit("SATORB1", arc=6 * 3600.0, obs=saved)
    in_memory = tapp.fit("SATORB1", arc="6h", obs=observations)
    assert _plain(by_path.to_json()) == _plain(in_memory.to_json()) == json.loads(
        _cli(["dc", *DC_ARGS, "--obs", str(saved), "--json", "-"]).stdout)
    assert by_path.run.notes == in_memory.run.notes == ()  # they state the run's model
    heard: list[str] = []
    unstated = tapp.fit("SATORB1", arc="6h", obs=dataclasses.replace(observations,
                                                                     made_under=None),
                        notify=heard.append)
    assert heard == list(unstated.run.notes) and len(heard) == 1
    assert heard[0].startswith("observations states no Earth orientation")
    assert _plain(tapp.ekf("SATORB1", arc="3h", apriori="2", obs=observations).to_json()) == \
        json.loads(_cli(["ekf", *EKF_ARGS, "--obs", str(saved), "--json", "-"]).stdout)


def test_the_last_iterations_stm_is_the_derivative_of_the_trajectory(dc) -> None:
    """Φ(t_i, t0) of the final linearisation against central differences of trajectories
    re-propagated from the final estimate ± a step in each component; the residuals it
    recomputes give the last iteration's RMS."""
    lin = dc.linearisation()
    s = dc.run.setup
    x0 = dc.result.x0
    truth = Propagator(s.propagator.state_model)
    for j, h in enumerate((STEP_KM,) * 3 + (STEP_KM_S,) * 3):
        dx = np.zeros(6)
        dx[j] = h
        plus, minus = (truth.propagate(x0 + sign * dx, lin.t_s, stm=False,
                                       orientation=s.orientation).states for sign in (1, -1))
        column = (plus - minus) / (2 * h)
        scale = np.max(np.abs(lin.stm[:, :, j]))
        assert np.max(np.abs(column - lin.stm[:, :, j])) < FD_AGREEMENT * scale, j
    np.testing.assert_allclose(lin.partials, np.einsum("mkj,mjl->mkl", lin.state_partials,
                                                       lin.stm))
    w = 1.0 / dc.run.window.sigma**2
    rms = np.sqrt(np.mean(w * lin.residuals**2))
    assert rms == pytest.approx(dc.iterations[-1].rms, rel=ROUNDING)


def test_the_filter_keeps_every_rows_estimate_gain_and_noise(ekf) -> None:
    r = ekf.result
    m, k = r.prefit.shape
    assert r.gains.shape == (m, 6, k) and r.covariances.shape == (m, 6, 6)
    np.testing.assert_array_equal(r.states[-1], r.x)
    np.testing.assert_array_equal(r.covariances[-1], r.P)
    assert not np.any(r.process_noise)  # q = 0, as in the study
    q_km2_s3 = 1e-12
    noisy = tapp.ekf("SATORB1", arc="1h", apriori="2", process_noise=q_km2_s3)
    t_s = noisy.run.window.t_s
    # Q over the time since the row before (none for a row at the same time)
    dt = np.diff(t_s, prepend=0.0)
    expected = np.array([process_noise(q_km2_s3, d) for d in dt])
    np.testing.assert_allclose(noisy.result.process_noise, expected, rtol=ROUNDING, atol=0)
    assert np.all(noisy.result.process_noise[:, 0, 0] > 0)


def test_plots_draw_on_the_given_axes_and_leave_the_backend(dc, ekf, rsig) -> None:
    backend = matplotlib.get_backend()
    ax = Figure().subplots()
    assert dc.plot(ax) is ax
    rms_line = ax.get_lines()[0]
    np.testing.assert_array_equal(rms_line.get_ydata(), dc.to_json()["rms"])
    ax = Figure().subplots()
    assert rsig.plot(ax) is ax
    np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), rsig.to_json()["R"])
    own = ekf.plot()
    assert isinstance(own.figure, Figure) and len(own.get_lines()) == len(KINDS)
    assert matplotlib.get_backend() == backend


def _error_line(exc: pytest.ExceptionInfo) -> str:
    return "error: " + " ".join(str(exc.value).split())


@pytest.mark.parametrize(("verb", "kwargs", "args"), [
    (tapp.fit, {"arc": "24"}, ["dc", "--orbit", "SATORB1", "--arc", "24"]),
    (tapp.fit, {"arc": "60s"}, ["dc", "--orbit", "SATORB1", "--arc", "60s"]),
    (tapp.fit, {"stations": "NOWHERE"}, ["dc", "--orbit", "SATORB1", "--stations",
                                         "NOWHERE"]),
    (tapp.ekf, {"apriori": "7"}, ["ekf", "--orbit", "SATORB1", "--apriori", "7"]),
    (tapp.rsig, {"span": "1000d", "step": "1s"}, ["rsig", "--orbit", "SATORB1", "--span",
                                                  "1000d", "--step", "1s"]),
])
def test_bad_input_is_the_commands_error(verb, kwargs: dict, args: list[str]) -> None:
    with pytest.raises(InputError) as exc:
        verb("SATORB1", **kwargs)
    assert _error_line(exc) == _cli(args, code=2).stderr.strip()


def test_a_bad_study_file_is_named(tmp_path: Path) -> None:
    bad = tmp_path / "study.toml"
    bad.write_text(STUDY_FILE.read_text().replace("seed = 1969", "sed = 1969"))
    with pytest.raises(InputError, match=r"tracking\.sed: expected no such key") as exc:
        tapp.rsig("SATORB1", study=bad)
    assert str(bad) in str(exc.value)


def test_an_ill_conditioned_fit_raises_with_the_commands_report() -> None:
    with pytest.raises(IllConditionedFit) as exc:
        tapp.fit("SATORB1", arc="10m")
    res = _cli(["dc", "--orbit", "SATORB1", "--arc", "10m", "--json", "-"],
               code=EXIT_CODES[ILL_CONDITIONED])
    assert _plain(ill_conditioned_json(exc.value)) == json.loads(res.stdout)


def test_the_estimators_are_on_the_front_door() -> None:
    assert {"fit", "ekf", "rsig", "FitResult", "FilterResult", "RSigResult",
            "IllConditionedFit"} <= set(tapp.__all__) <= set(dir(tapp))
    assert set(EXIT_CODES) == {*DCOutcome, ILL_CONDITIONED}  # every outcome has its code
