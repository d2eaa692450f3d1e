"""``guide``: TAPP II on a T32 tape (in memory or a file) with a guidance file (validated or
a file), the result rendering ``tapp guide``'s Markdown tables, JSON and B-plane scatter."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from iter.execute import Execution
from tapp.errors import TappError
from tapp.guidance.guidefile import GuideFile, read_guide
from tapp.guidance.statistics import bplane_rows
from tapp.guidance.study import GuidanceResult, guidance_study
from tapp.io.tape.t32 import T32
from tapp.io.tape.t32_hdf5 import read_t32
from tapp.report.figures import subplots
from tapp.report.guidance import draw_bplane_scatter, guidance_dict, guidance_markdown

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["GuideResult", "guide"]

#: Names of inputs given in memory, in the result and errors (the study's defaults).
MEMORY_GUIDE, MEMORY_TAPE = "guidance", "T32"


@dataclass(frozen=True, slots=True)
class GuideResult:
    """A TAPP II study (:class:`tapp.guidance.study.GuidanceResult`: ΔV and miss statistics,
    Monte Carlo beside linear covariance, and their agreement checks)."""

    result: GuidanceResult

    def to_json(self) -> dict:
        """What ``tapp guide --json`` writes (:func:`tapp.report.guidance.guidance_dict`)."""
        return guidance_dict(self.result)

    def markdown(self) -> str:
        """The Markdown tables ``tapp guide`` prints
        (:func:`tapp.report.guidance.guidance_markdown`)."""
        return guidance_markdown(self.result)

    def plot(self, ax: Axes | None = None) -> Axes:
        """Draw the final (δB·T, δB·R) miss of the samples with the 1σ/3σ ellipses of the
        Monte Carlo and the linear covariance (and the corridor), as ``tapp guide --plots``
        does, on ``ax`` or on a new figure's axes (:func:`tapp.report.figures.subplots`);
        return the axes.

        Raises
        ------
        TappError
            The miss has no B·T and B·R.
        """
        r = self.result
        if bplane_rows(r.miss_name) is None:
            raise TappError(f"{r.tape_iden}: the miss ({', '.join(r.miss_name)}) has no B·T "
                            "and B·R to plot")
        if ax is None:
            _, ax = subplots(figsize=(6.4, 6.0))
        draw_bplane_scatter(ax, r)
        return ax


def guide(t32: T32 | Path | str, guidance: GuideFile | Path | str, *, samples: int,
          seed: int, execution: Execution | None = None, shard_samples: int | None = None,
          progress: Callable[[int, int], None] | None = None) -> GuideResult:
    """Run a TAPP II guidance study; return its statistics and their renderings.

    Parameters
    ----------
    t32 : a T32 tape in memory, or its file (:func:`tapp.io.tape.t32_hdf5.read_t32`).
    guidance : a validated guidance file (:func:`tapp.guidance.guidefile.read_guide`), or
        its TOML file.
    samples, seed, execution, shard_samples, progress : as
        :func:`tapp.guidance.study.guidance_study` takes them (the numbers do not depend on
        ``execution`` or ``shard_samples``).

    Raises
    ------
    InputError
        A bad guidance file or field, a guidance file that does not fit the tape, bad sizes
        or seed, as ``tapp guide`` reports them (naming the file and the field).
    TapeError
        An unreadable or corrupt tape.
    iter.SchedulerError
        A Dask scheduler that does not answer.
    """
    guide_source = MEMORY_GUIDE if isinstance(guidance, GuideFile) else str(guidance)
    if not isinstance(guidance, GuideFile):
        guidance = read_guide(guidance)
    tape_source = MEMORY_TAPE if isinstance(t32, T32) else str(t32)
    if not isinstance(t32, T32):
        t32 = read_t32(t32)
    return GuideResult(guidance_study(t32, guidance, samples=samples, seed=seed,
                                      execution=execution, shard_samples=shard_samples,
                                      progress=progress, guide_source=guide_source,
                                      tape_source=tape_source))
