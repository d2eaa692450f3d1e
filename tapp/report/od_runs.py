"""What ``tapp dc``, ``tapp ekf`` and ``tapp rsig`` report of a run (:mod:`tapp.od.runs`): the
JSON content of ``--json``, the printout (rich tables and lines, as :class:`Printout`) and a
figure drawn on given Matplotlib axes.

The printout is a list of rich renderables and a console width: the commands print it on
their console (styled on a terminal), :meth:`Printout.text` renders it as plain text, the same
characters the commands write when their output is not a terminal.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from tapp.constants import GM_EARTH_km3_s2
from tapp.od.batch import (
    N_STATE,
    NOISE_MODEL_PROBABILITY,
    STATE_NAMES,
    DCOutcome,
    DCResult,
    describe_direction,
)
from tapp.od.exits import EXIT_ILL_CONDITIONED, ILL_CONDITIONED, exit_code
from tapp.od.rate import PredictedRate
from tapp.od.runs import FilterRun, FitRun, IllConditionedFit, SignatureRun
from tapp.od.setup import describe_orientation
from tapp.orbit.elements import cartesian_to_elements

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from rich.console import Console

    from tapp.measurements.observations import Observations


@dataclass(frozen=True, slots=True)
class Printout:
    """A command's printout: rich renderables (tables, lines of console markup), each printed
    on its own, on a console ``width`` characters wide."""

    width: int
    items: tuple[Any, ...]

    def print(self, console: Console) -> None:
        """Print every item on ``console``."""
        for item in self.items:
            console.print(item)

    def text(self) -> str:
        """The printout as plain text (no styles), as the command writes it to a file or a
        pipe."""
        from rich.console import Console

        buffer = io.StringIO()
        self.print(Console(file=buffer, width=self.width, force_terminal=False,
                           force_jupyter=False, color_system=None))
        return buffer.getvalue()


def _table(title: str, columns: tuple[str, ...]):
    from rich.table import Table

    table = Table(title=title)
    for column in columns:
        table.add_column(column, justify="right")
    return table


def made_under_json(data: Observations) -> dict[str, str] | None:
    """What the observations state they were made under (None: their file states none)."""
    return None if data.made_under is None else data.made_under.as_dict()


def elements_json(x: np.ndarray) -> dict[str, float]:
    """The osculating elements of x (6,) km, km/s: a (km), e, angles (deg)."""
    a, e, i, raan, argp, mean = np.asarray(cartesian_to_elements(x, GM_EARTH_km3_s2), float)
    return {"a_km": a, "e": e, "i_deg": math.degrees(i), "raan_deg": math.degrees(raan),
            "argp_deg": math.degrees(argp), "M_deg": math.degrees(mean)}


def _eigen_json(rate: PredictedRate | None) -> list[dict[str, float]] | None:
    if rate is None:
        return None
    return [{"re": float(v.real), "im": float(v.imag), "abs": float(abs(v))}
            for v in rate.eigenvalues]


def dc_json(run: FitRun) -> dict:
    """What ``tapp dc --json`` writes of a DC that iterated."""
    result, rate = run.result, run.rate
    q = result.contraction_factor
    return {
        "converged": result.converged, "status": result.status,
        "exit_code": exit_code(result.status), "reason": result.reason,
        "iterations": len(result.iterations), "converged_at": result.converged_at,
        "rms": result.rms, "rms_bound": result.rms_bound,
        "noise_model_probability": NOISE_MODEL_PROBABILITY,
        "contraction_factor": q if np.isfinite(q) else None,
        "projected_iterations": result.projected_iterations,
        "predicted_rate": None if rate is None else rate.rho,
        "eigenvalues": _eigen_json(rate), "final_elements": elements_json(result.x0),
        "position_error_km": run.position_error_km, "measurements": result.n_measurements,
        "earth_orientation": run.earth_orientation,
        "observations_made_under": made_under_json(run.window)}


def noise_model_line(result: DCResult) -> str:
    """The last RMS against the noise model's bound, and the verdict where there is an
    estimate to judge (the RMS settled within the fit limit: :mod:`tapp.od.batch`).

    A stalled DC's RMS settled too, above the fit limit: its one verdict is its outcome
    (the data are not fitted), and the line gives the numbers only.
    """
    verdict = {DCOutcome.CONVERGED: ": consistent with the noise model",
               DCOutcome.INCONSISTENT: ": inconsistent with the noise model",
               DCOutcome.STALLED: ""}.get(
        DCOutcome(result.status), f": not judged ({result.status}: no settled estimate)")
    return (f"residuals: RMS {result.rms[-1]:.5g} against {result.rms_bound:.5g}, the "
            f"{100 * NOISE_MODEL_PROBABILITY:g} % χ² bound of {result.n_measurements} "
            f"residuals and {N_STATE} estimated parameters{verdict}")


def dc_printout(run: FitRun) -> Printout:
    """What ``tapp dc`` prints of a DC that iterated: the iterations, the outcome, the
    residuals against the noise model, the predicted and observed rates, the error."""
    result, rate, s = run.result, run.rate, run.setup
    table = _table(f"DC {s.orbit}, {run.arc}, ({s.truth},{s.stm}), {s.orientation.model}: "
                   f"{result.status}", ("iteration", "RMS", "|δr| (m)", "|δx|_N"))
    for it in result.iterations:
        table.add_row(str(it.index), f"{it.rms:.4f}",
                      f"{np.linalg.norm(it.correction[:3]) * 1e3:.3f}", f"{it.step:.4g}")
    q = result.contraction_factor
    observed = f"observed contraction factor q = {q:.4g}" if np.isfinite(q) else \
        "no contraction factor (one iteration)"
    if rate is None:
        predicted = "predicted rate ρ: none (singular normal matrix at the true state)"
    else:
        lead = ", ".join(f"{v.real:.4g}{v.imag:+.4g}i" if abs(v.imag) > 0 else f"{v.real:.4g}"
                         for v in rate.eigenvalues[:2])
        predicted = f"predicted rate ρ = {rate.rho:.4g} (largest eigenvalues of M: {lead})"
    return Printout(100, (
        table, f"{result.status}: {result.reason}", noise_model_line(result),
        f"{predicted}; {observed}",
        f"{result.n_measurements} measurements; epoch position error "
        f"{run.position_error_km * 1e3:.3f} m",
        f"Earth orientation: {describe_orientation(run.earth_orientation)}"))


def ill_conditioned_json(exc: IllConditionedFit) -> dict:
    """What ``tapp dc --json`` writes of a DC refused as ill-conditioned."""
    return {"converged": False, "status": ILL_CONDITIONED,
            "exit_code": EXIT_ILL_CONDITIONED, "reason": str(exc),
            "condition_number": exc.condition if np.isfinite(exc.condition) else None,
            "max_condition": exc.limit, "measurements": exc.n_measurements,
            "undetermined_directions": [
                {"relative_eigenvalue": float(lam),
                 **{n: float(c) for n, c in zip(STATE_NAMES, d, strict=True)}}
                for d, lam in zip(exc.directions, exc.eigenvalues, strict=True)],
            "earth_orientation": exc.earth_orientation}


def ill_conditioned_printout(exc: IllConditionedFit) -> Printout:
    """What ``tapp dc`` prints of a DC refused as ill-conditioned: the condition number and
    the state directions the data do not determine."""
    return Printout(100, (
        f"ill-conditioned: the normal matrix of the first iteration has condition number "
        f"{exc.condition:.3g} (scaled to a unit diagonal; limit {exc.limit:.3g}) with "
        f"{exc.n_measurements} measurements; not iterated",
        "state directions the data do not determine (unit vectors of the scaled state, "
        "relative eigenvalue):",
        *(f"  {describe_direction(d)}   ({lam:.3g})"
          for d, lam in zip(exc.directions, exc.eigenvalues, strict=True)),
        f"Earth orientation: {describe_orientation(exc.earth_orientation)}"))


def _per_pass(run: FilterRun) -> list[dict[str, float]]:
    return [{"range_m": p.max_abs[0] * 1e3, "range_rate_mm_s": p.max_abs[1] * 1e6}
            for p in run.result.passes]


def ekf_json(run: FilterRun) -> dict:
    """What ``tapp ekf --json`` writes: the passes and the largest |O-C| of each."""
    return {"passes": [{"station": p.station, "t_start_s": p.t_start_s, "t_end_s": p.t_end_s}
                       for p in run.result.passes],
            "max_abs_residual_per_pass": _per_pass(run),
            "earth_orientation": run.earth_orientation,
            "observations_made_under": made_under_json(run.window)}


def ekf_printout(run: FilterRun) -> Printout:
    """What ``tapp ekf`` prints: the largest prefit |O-C| of each pass."""
    s = run.setup
    table = _table(f"EKF {s.orbit}, {run.arc}, ({s.truth},{s.stm}), a priori {run.apriori}, "
                   f"{s.orientation.model}", ("pass", "station", "start (h)",
                                              "max|O-C| range (m)",
                                              "max|O-C| range-rate (mm/s)"))
    for k, (p, r) in enumerate(zip(run.result.passes, _per_pass(run), strict=True), start=1):
        table.add_row(str(k), p.station, f"{p.t_start_s / 3600:.2f}", f"{r['range_m']:.1f}",
                      f"{r['range_rate_mm_s']:.1f}")
    return Printout(110, (table, "Earth orientation: "
                          f"{describe_orientation(run.earth_orientation)}"))


def rsig_json(run: SignatureRun) -> dict:
    """What ``tapp rsig --json`` writes: R on the grid."""
    return {"t_s": run.signature.t_s, "R": run.signature.r,
            "earth_orientation": run.earth_orientation}


def rsig_printout(run: SignatureRun) -> Printout:
    """What ``tapp rsig`` prints: R at nine times of the grid."""
    s, t, r = run.setup, run.signature.t_s, run.signature.r
    table = _table(f"R(t) {s.orbit} ({s.truth},{s.stm}), {s.orientation.model}",
                   ("t (h)", "R"))
    for k in np.linspace(0, len(t) - 1, 9).astype(int):
        table.add_row(f"{t[k] / 3600:.1f}", f"{r[k]:.6g}")
    return Printout(80, (table, "Earth orientation: "
                         f"{describe_orientation(run.earth_orientation)}"))


def draw_dc_rms(ax: Axes, run: FitRun) -> None:
    """The weighted RMS of each iteration (log scale) and the noise model's bound."""
    result, s = run.result, run.setup
    ax.plot(np.arange(1, len(result.rms) + 1), result.rms, marker="o", ms=3,
            label=f"({s.truth},{s.stm})")
    ax.axhline(result.rms_bound, color="k", lw=0.8, ls="--",
               label=f"{100 * NOISE_MODEL_PROBABILITY:g} % χ² bound")
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel("weighted RMS")
    ax.set_title(f"DC {s.orbit}, {run.arc}: {result.status}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)


def draw_ekf_residuals(ax: Axes, run: FilterRun) -> None:
    """The prefit residuals of each kind in units of their σ against time (h)."""
    data, s = run.window, run.setup
    for j, kind in enumerate(data.kinds):
        ax.plot(data.t_s / 3600.0, run.result.prefit[:, j] / data.sigma[j], ".", ms=2,
                label=kind)
    ax.set_xlabel("time (h)")
    ax.set_ylabel("prefit residual (σ)")
    ax.set_title(f"EKF {s.orbit}, {run.arc}, ({s.truth},{s.stm}), a priori {run.apriori}",
                 fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def draw_rsig(ax: Axes, run: SignatureRun) -> None:
    """R(t) against time (h), log scale."""
    s = run.setup
    ax.plot(run.signature.t_s / 3600.0, run.signature.r, label=f"({s.truth},{s.stm})")
    ax.set_xlabel("time (h)")
    ax.set_ylabel("R(t) = sqrt(Σ φ_ij², i ≤ 3, j ≤ 6)")
    ax.set_yscale("log")
    ax.set_title(f"Error-growth signature, {s.orbit}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
