"""The O3 printout of TAPP III (seed §4.3.2) and the same content as a JSON-ready dict.

Each output block has the seed's heading ``i, j, l, k, INFO`` (block number, program epoch,
last recycle time and current time as T13 indices, and the state at t_k) and, for each entity,
its number ω, its command in both notations, and the matrix with rows and columns labelled by
parameter names (which carry their units: ``x_km``, ``GM_km3_s2``; ``@current`` etc. tag the
time of an orbit set, a trailing ``'`` a parameter changed by a constraint link). A
covariance also gets its σ's, its correlation matrix and the number of significant digits it
holds (on the scale √(C_ii C_jj), estimated from the condition of the factors it came from:
:attr:`tapp.processor.executive.Entity.digits`); a real-world covariance its error budget:
the σ of each source (signed: a negative variance, from correlations between sources, prints
as −√|v|), whose variances add up to the printed total.

When the deck asks for RIC axes (``[output] frames``), a covariance of an orbit set is followed
by the same in radial / in-track / cross-track axes of the nominal state at its time
(:attr:`tapp.processor.executive.Entity.ric`), budget included. A covariance whose rows hold
B·T and B·R gets its B-plane dispersion ellipses (1σ and 3σ semi-axes in km, the major axis's
angle from T towards R: :mod:`tapp.estimation.ellipse`). After the blocks, two summary tables
over the print and recycle times, fit / real: the RIC σ of the orbit and the B-plane ellipses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.estimation.ellipse import ErrorEllipse, error_ellipse, probability_inside
from tapp.estimation.factors import gram
from tapp.frames.ric import RIC_NAMES
from tapp.frames.time import Epoch
from tapp.io.tape.t13 import INFO_COLUMNS, T13Header
from tapp.processor.executive import Entity
from tapp.processor.sequencing import Block, HistoryRow, Run

_WIDTH = 12
_MAX_COL = 30
#: The miss components whose covariance gives the B-plane dispersion ellipse (T first).
BPLANE_AXES = ("b_dot_t_km", "b_dot_r_km")
#: The k of the k-σ ellipses printed (each holds 1 − exp(−k²/2) of a Gaussian miss).
ELLIPSE_SCALES = (1.0, 3.0)
ELLIPSE_NOTE = "semi-axes, and the angle of the major axis from T towards R"
RIC_NOTE = ("RIC axes of the nominal state at the set's time (R = r/|r|, C = (r x v)/|r x v|, "
            "I = C x R; velocity components along the same axes, without the ω x r term)")


def sigmas(matrix: np.ndarray) -> np.ndarray:
    """Standard deviations √diag of a covariance (negative rounding clipped to 0)."""
    return np.sqrt(np.maximum(np.diagonal(matrix), 0.0))


def correlation(matrix: np.ndarray) -> np.ndarray:
    """Correlation matrix of a covariance (rows of zero σ give 0 off the diagonal)."""
    s = sigmas(matrix)
    scale = np.outer(s, s)
    out = np.divide(matrix, scale, out=np.zeros_like(matrix), where=scale > 0)
    np.fill_diagonal(out, np.where(s > 0, 1.0, 0.0))
    return out


def signed_sigma(variance: np.ndarray) -> np.ndarray:
    """σ of a variance share, signed: −√|v| for a negative share."""
    return np.sign(variance) * np.sqrt(np.abs(variance))


def _grid(rows: tuple[str, ...], cols: tuple[str, ...], m: np.ndarray, fmt: str) -> list[str]:
    width = max([len(r) for r in rows] + [8])
    col = max([_WIDTH] + [min(len(c), _MAX_COL) + 2 for c in cols])
    out = [" " * width + "".join(f"{c[:col - 2]:>{col}}" for c in cols)]
    for label, row in zip(rows, m, strict=True):
        out.append(f"{label:<{width}}" + "".join(f"{v:>{col}{fmt}}" for v in row))
    return out


def bplane_ellipse(ent: Entity) -> ErrorEllipse | None:
    """The 1σ (B·T, B·R) dispersion ellipse of a covariance entity whose rows hold both
    (:data:`BPLANE_AXES`); None otherwise."""
    if not (ent.command.is_covariance and ent.rows == ent.cols
            and all(n in ent.rows for n in BPLANE_AXES)):
        return None
    ix = [ent.rows.index(n) for n in BPLANE_AXES]
    return error_ellipse(ent.matrix[np.ix_(ix, ix)])


def ellipse_lines(ellipse: ErrorEllipse) -> list[str]:
    """The O3 lines of a B-plane dispersion ellipse: 1σ and 3σ semi-axes, km, and angle."""
    lines = [f"    B-plane dispersion ellipse of (B·T, B·R): {ELLIPSE_NOTE}:"]
    for k in ELLIPSE_SCALES:
        lines.append(f"      {k:g}σ ({100 * probability_inside(k):.2f} %): semi-major "
                     f"{k * ellipse.semi_major:.4e} km, semi-minor {k * ellipse.semi_minor:.4e}"
                     f" km, angle {ellipse.angle_deg:+.3f} deg")
    return lines


def ellipse_dict(ellipse: ErrorEllipse) -> dict:
    """A B-plane dispersion ellipse as a JSON-ready dict (1σ and 3σ, km; angle, deg)."""
    return {"axes": list(BPLANE_AXES), "angle_deg": ellipse.angle_deg,
            "angle_convention": "major axis, from T towards R, in (-90, 90]",
            **{f"sigma{k:g}": {"semi_major_km": k * ellipse.semi_major,
                               "semi_minor_km": k * ellipse.semi_minor,
                               "probability": probability_inside(k)} for k in ELLIPSE_SCALES}}


def entity_lines(ent: Entity) -> list[str]:
    """The O3 lines of one entity (and of its copy in RIC axes, when there is one)."""
    cmd = ent.command
    held = "" if ent.digits is None else f"   holds ~{ent.digits:.1f} digits"
    lines = [f"  ω = {ent.omega}   {cmd.seed()}   [{cmd.alias()}]   "
             f"({len(ent.rows)} x {len(ent.cols)}){held}"]
    lines += _matrix_lines(ent)
    ellipse = bplane_ellipse(ent)
    if ellipse is not None:
        lines += ellipse_lines(ellipse)
    if ent.ric is not None:
        lines.append(f"    in {RIC_NOTE}:")
        lines += _matrix_lines(ent.ric)
    return lines


def _matrix_lines(ent: Entity) -> list[str]:
    """The matrix of an entity, its σ and correlations (a covariance) and its budget."""
    cmd = ent.command
    lines = ["    " + line for line in _grid(ent.rows, ent.cols, ent.matrix, ".4e")]
    if cmd.is_covariance and ent.rows == ent.cols:
        lines.append("    σ:")
        lines += ["    " + line for line in _grid(("σ",), ent.rows, sigmas(ent.matrix)[None],
                                                   ".4e")]
        lines.append("    correlation:")
        lines += ["    " + line for line in _grid(ent.rows, ent.cols,
                                                   correlation(ent.matrix), ".4f")]
    if ent.budget is not None:
        b = ent.budget
        lines.append("    error budget (σ of each source; variances add up to the total):")
        table = np.vstack([signed_sigma(b.variances), sigmas(np.diag(b.total))])
        lines += ["    " + line for line in _grid((*b.sources, "total"), ent.rows, table,
                                                   ".4e")]
        lines.append(f"    closure: max |Σ variances − total| / total = {closure(b):.2g} "
                     "(rounding)")
    return lines


def closure(budget) -> float:
    """Largest relative residual of a budget: max_i |Σ_s v_si − total_i| / total_i."""
    if budget.total.size == 0:  # an empty partition (e.g. c2 with nothing eliminated)
        return 0.0
    total = np.where(budget.total > 0, budget.total, 1.0)
    return float(np.max(np.abs(budget.variances.sum(axis=0) - budget.total) / total))


def block_lines(block: Block, epoch: Epoch, info_names: tuple[str, ...]) -> list[str]:
    """The O3 lines of one output block: heading i, j, l, k, INFO and its entities."""
    title = "PRINT OUTPUT" if block.kind == "print" else "RECYCLE OUTPUT"
    lines = ["", "=" * 100,
             f"{title} {block.number}   i = {block.number}, j = {block.j}, l = {block.l}, "
             f"k = {block.k}   t_k = {block.t_s:.3f} s ({epoch.iso_after(block.t_s, 3)} UTC)",
             "INFO: " + ", ".join(f"{n} = {v:.9g}" for n, v in
                                  zip(info_names, block.info, strict=True)),
             "-" * 100]
    for ent in block.entities:
        lines += entity_lines(ent)
        lines.append("")
    return lines


def o3_text(run: Run, header: T13Header, deck_source: str, tape_source: str) -> str:
    """The whole O3 printout of a run."""
    lines = [f"TAPP III O3 printout   tape {tape_source} (iden {header.iden}, epoch "
             f"{header.epoch.iso(3)} UTC)   deck {deck_source}",
             f"n_o = {len(header.parameters.name)}, n_p = {header.n_p}, "
             f"n_m = {len(header.miss.name)}, n_ts = {len(header.stations.name)}, "
             f"n_IT = {header.records.k.size}; {len(run.blocks)} output blocks, "
             f"{len(run.recycles)} recycles"]
    for block in run.blocks:
        lines += block_lines(block, header.epoch, INFO_COLUMNS)
    lines += history_lines(run, tuple(header.miss.name))
    return "\n".join(lines) + "\n"


def entity_dict(ent: Entity) -> dict:
    """One entity as a JSON-ready dict: command, alias, labels, matrix (+ σ, budget, the
    B-plane ellipse of a miss covariance, the same in RIC axes under ``ric``)."""
    out = {"omega": ent.omega, "command": ent.command.seed(), "alias": ent.command.alias(),
           **_matrix_dict(ent)}
    ellipse = bplane_ellipse(ent)
    if ellipse is not None:
        out["bplane_ellipse"] = ellipse_dict(ellipse)
    if ent.ric is not None:
        out["ric"] = {"frame": RIC_NOTE, **_matrix_dict(ent.ric)}
    return out


def _matrix_dict(ent: Entity) -> dict:
    """Labels, matrix, σ and correlations (a covariance), digits and budget of an entity."""
    out = {"rows": list(ent.rows), "cols": list(ent.cols), "matrix": ent.matrix.tolist()}
    if ent.command.is_covariance and ent.rows == ent.cols:
        out["sigma"] = sigmas(ent.matrix).tolist()
        out["correlation"] = correlation(ent.matrix).tolist()
    if ent.digits is not None:
        out["digits"] = ent.digits
    if ent.budget is not None:
        out["budget"] = {"sources": list(ent.budget.sources),
                         "variance": ent.budget.variances.tolist(),
                         "sigma": signed_sigma(ent.budget.variances).tolist(),
                         "total_variance": ent.budget.total.tolist(),
                         "closure": closure(ent.budget)}
    return out


def run_dict(run: Run, header: T13Header, deck_source: str, tape_source: str) -> dict:
    """The run as a JSON-ready dict (the O3 content, the σ history, the recycles)."""
    return {
        "tape": tape_source, "iden": header.iden, "deck": deck_source,
        "epoch_utc": header.epoch.iso(3),
        "blocks": [{"kind": b.kind, "number": b.number, "j": b.j, "l": b.l, "k": b.k,
                    "t_s": b.t_s, "utc": header.epoch.iso_after(b.t_s, 3), "info": b.info.tolist(),
                    "entities": [entity_dict(e) for e in b.entities]} for b in run.blocks],
        "history": {"labels": list(run.history_labels), "miss": list(header.miss.name),
                    "ric_labels": list(RIC_NAMES),
                    "rows": [_history_dict(h, tuple(header.miss.name)) for h in run.history]},
        "recycles": [{"number": r.number, "k": r.k, "l": r.l, "t_s": r.t_s,
                      "miss_sigma_fit": sigmas(gram(r.Lambda_fit_factor, r.B)).tolist(),
                      "miss_sigma_real": sigmas(gram(r.Lambda_real_factor, r.B)).tolist(),
                      "digits": next(h.digits for h in run.history
                                     if h.kind == "recycle" and h.k == r.k)}
                     for r in run.recycles],
    }


def history_ellipses(h: HistoryRow, miss_names: Sequence[str]
                     ) -> tuple[ErrorEllipse | None, ErrorEllipse | None]:
    """The (fit, real) 1σ B-plane ellipses of a history row's miss covariances; None where
    the miss set has no B·T and B·R or the fit covariance is not defined."""
    if not all(n in miss_names for n in BPLANE_AXES):
        return None, None
    ix = [list(miss_names).index(n) for n in BPLANE_AXES]
    return tuple(None if c is None else error_ellipse(c[np.ix_(ix, ix)])
                 for c in (h.miss_fit, h.miss_real))


def _history_dict(h: HistoryRow, miss_names: tuple[str, ...]) -> dict:
    def listed(a: np.ndarray | None) -> list | None:
        return None if a is None else a.tolist()

    fit, real = history_ellipses(h, miss_names)
    return {"kind": h.kind, "k": h.k, "t_s": h.t_s, "digits": h.digits,
            "sigma_fit": listed(h.sigma_fit), "sigma_real": h.sigma_real.tolist(),
            "miss_sigma_fit": None if h.miss_fit is None else sigmas(h.miss_fit).tolist(),
            "miss_sigma_real": sigmas(h.miss_real).tolist(),
            "ric_sigma_fit": listed(h.ric_fit), "ric_sigma_real": listed(h.ric_real),
            "bplane_ellipse_fit": None if fit is None else ellipse_dict(fit),
            "bplane_ellipse_real": None if real is None else ellipse_dict(real)}


def history_lines(run: Run, miss_names: tuple[str, ...]) -> list[str]:
    """The O3 summary tables after the blocks: the RIC σ of the orbit and the B-plane
    ellipses, fit world / real world, at each print and recycle time (when there are any)."""

    def pair(fit: float | None, real: float, fmt: str) -> str:
        return f"{'-' if fit is None else format(fit, fmt)} / {format(real, fmt)}"

    lines = []
    rows = [h for h in run.history if h.ric_real is not None]
    if rows:
        lines += ["", "=" * 100, f"RIC σ OF THE ORBIT AT EACH STATISTICS TIME, fit / real "
                  f"({RIC_NOTE})", "-" * 100]
        head = f"{'kind':<8}{'k':>5}{'t (d)':>11}" + "".join(f"{n:>26}" for n in RIC_NAMES)
        lines.append(head)
        for h in rows:
            fit = [None] * len(RIC_NAMES) if h.ric_fit is None else h.ric_fit
            lines.append(f"{h.kind:<8}{h.k:>5}{h.t_s / SECONDS_PER_DAY:>11.4f}" + "".join(
                f"{pair(f, r, '.4e'):>26}" for f, r in zip(fit, h.ric_real, strict=True)))
    ellipses = [(h, *history_ellipses(h, miss_names)) for h in run.history]
    ellipses = [e for e in ellipses if e[2] is not None]
    if ellipses:
        lines += ["", "=" * 100, "B-PLANE DISPERSION ELLIPSES OF (B·T, B·R), 1σ, fit / real: "
                  f"{ELLIPSE_NOTE} (3σ: 3 times the semi-axes; 1σ holds "
                  f"{100 * probability_inside(1.0):.2f} %, 3σ "
                  f"{100 * probability_inside(3.0):.2f} % of a Gaussian miss)", "-" * 100,
                  f"{'kind':<8}{'k':>5}{'t (d)':>11}{'semi-major (km)':>26}"
                  f"{'semi-minor (km)':>26}{'angle (deg)':>22}"]
        for h, fit, real in ellipses:
            lines.append(
                f"{h.kind:<8}{h.k:>5}{h.t_s / SECONDS_PER_DAY:>11.4f}"
                f"{pair(fit and fit.semi_major, real.semi_major, '.4e'):>26}"
                f"{pair(fit and fit.semi_minor, real.semi_minor, '.4e'):>26}"
                f"{pair(fit and fit.angle_deg, real.angle_deg, '+.3f'):>22}")
    return lines


@dataclass(frozen=True, slots=True)
class SigmaRatio:
    """A real-world σ over the fit world's claim for it: the ratio, the quantity (a history
    label or a miss component), the kind of statistics time and the time, s."""

    ratio: float
    name: str
    kind: str
    t_s: float


def largest_sigma_ratio(run: Run, miss_names: Sequence[str]) -> SigmaRatio | None:
    """The σ whose real-world value most exceeds the fit world's claim, over the run's
    history (the history partition and the miss set, at every print and recycle time).

    A σ the fit world holds at 0 (a parameter it holds fixed) makes no claim to compare and
    is passed over; None when the fit world has no σ > 0 anywhere (no covariance yet).
    """
    best = None
    names = (*run.history_labels, *miss_names)
    for h in run.history:
        if h.sigma_fit is None:
            continue
        real = np.concatenate([h.sigma_real, sigmas(h.miss_real)])
        fit = np.concatenate([h.sigma_fit, sigmas(h.miss_fit)])
        ratio = np.divide(real, fit, out=np.full_like(real, -np.inf), where=fit > 0)
        i = int(np.argmax(ratio))
        if np.isfinite(ratio[i]) and (best is None or ratio[i] > best.ratio):
            best = SigmaRatio(float(ratio[i]), names[i], h.kind, h.t_s)
    return best
