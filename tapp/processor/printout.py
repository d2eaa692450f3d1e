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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.estimation.factors import gram
from tapp.frames.time import Epoch
from tapp.io.tape.t13 import INFO_COLUMNS
from tapp.processor.executive import Entity
from tapp.processor.sequencing import Block, Run

_WIDTH = 12
_MAX_COL = 30


def _utc(epoch: Epoch, t_s: float) -> str:
    return Epoch(epoch.jd_whole, epoch.jd_fraction + t_s / SECONDS_PER_DAY).iso(3)


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


def entity_lines(ent: Entity) -> list[str]:
    """The O3 lines of one entity."""
    cmd = ent.command
    held = "" if ent.digits is None else f"   holds ~{ent.digits:.1f} digits"
    lines = [f"  ω = {ent.omega}   {cmd.seed()}   [{cmd.alias()}]   "
             f"({len(ent.rows)} x {len(ent.cols)}){held}"]
    lines += ["    " + line for line in _grid(ent.rows, ent.cols, ent.matrix, ".4e")]
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
             f"k = {block.k}   t_k = {block.t_s:.3f} s ({_utc(epoch, block.t_s)} UTC)",
             "INFO: " + ", ".join(f"{n} = {v:.9g}" for n, v in
                                  zip(info_names, block.info, strict=True)),
             "-" * 100]
    for ent in block.entities:
        lines += entity_lines(ent)
        lines.append("")
    return lines


def o3_text(run: Run, header, deck_source: str, tape_source: str) -> str:
    """The whole O3 printout of a run."""
    lines = [f"TAPP III O3 printout   tape {tape_source} (iden {header.iden}, epoch "
             f"{header.epoch.iso(3)} UTC)   deck {deck_source}",
             f"n_o = {len(header.parameters.name)}, n_p = {header.n_p}, "
             f"n_m = {len(header.miss.name)}, n_ts = {len(header.stations.name)}, "
             f"n_IT = {header.records.k.size}; {len(run.blocks)} output blocks, "
             f"{len(run.recycles)} recycles"]
    for block in run.blocks:
        lines += block_lines(block, header.epoch, INFO_COLUMNS)
    return "\n".join(lines) + "\n"


def entity_dict(ent: Entity) -> dict:
    """One entity as a JSON-ready dict: command, alias, labels, matrix (+ σ, budget)."""
    out = {"omega": ent.omega, "command": ent.command.seed(), "alias": ent.command.alias(),
           "rows": list(ent.rows), "cols": list(ent.cols), "matrix": ent.matrix.tolist()}
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


def run_dict(run: Run, header, deck_source: str, tape_source: str) -> dict:
    """The run as a JSON-ready dict (the O3 content, the σ history, the recycles)."""
    return {
        "tape": tape_source, "iden": header.iden, "deck": deck_source,
        "epoch_utc": header.epoch.iso(3),
        "blocks": [{"kind": b.kind, "number": b.number, "j": b.j, "l": b.l, "k": b.k,
                    "t_s": b.t_s, "utc": _utc(header.epoch, b.t_s), "info": b.info.tolist(),
                    "entities": [entity_dict(e) for e in b.entities]} for b in run.blocks],
        "history": {"labels": list(run.history_labels), "miss": list(header.miss.name),
                    "rows": [{"kind": h.kind, "k": h.k, "t_s": h.t_s, "digits": h.digits,
                              "sigma_fit": None if h.sigma_fit is None else h.sigma_fit.tolist(),
                              "sigma_real": h.sigma_real.tolist(),
                              "miss_sigma_fit": None if h.miss_fit is None
                              else sigmas(h.miss_fit).tolist(),
                              "miss_sigma_real": sigmas(h.miss_real).tolist()}
                             for h in run.history]},
        "recycles": [{"number": r.number, "k": r.k, "l": r.l, "t_s": r.t_s,
                      "miss_sigma_fit": sigmas(gram(r.Lambda_fit_factor, r.B)).tolist(),
                      "miss_sigma_real": sigmas(gram(r.Lambda_real_factor, r.B)).tolist(),
                      "digits": next(h.digits for h in run.history
                                     if h.kind == "recycle" and h.k == r.k)}
                     for r in run.recycles],
    }


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
