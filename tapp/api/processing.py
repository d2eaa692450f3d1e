"""``process``: TAPP III on a T13 tape (in memory or a file) with a deck (validated or a
file), the result rendering ``tapp process``'s O3 printout, JSON, T32 tape and B-plane plot."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from tapp.errors import TappError
from tapp.io.tape.t13 import T13, T13Header
from tapp.io.tape.t32 import T32
from tapp.io.tape.t32_hdf5 import write_t32
from tapp.pipeline.steps import process_tape
from tapp.processor.deck import Deck, read_deck
from tapp.processor.plan import Plan
from tapp.processor.printout import o3_text, run_dict
from tapp.processor.sequencing import Run
from tapp.processor.tape32 import build_t32, t32_provenance
from tapp.report.figures import subplots
from tapp.report.processor import bplane_rows, draw_bplane_ellipses

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ProcessResult", "process"]

#: Names of inputs given in memory, in the printout, the JSON and errors.
MEMORY_TAPE, MEMORY_DECK = "T13", "deck"


@dataclass(frozen=True, slots=True)
class ProcessResult:
    """A TAPP III run with what rendering it needs: the run (entities, budgets, history),
    the bound deck, the tape header, the deck, the sources named in the outputs, and the wall
    time (s)."""

    run: Run
    plan: Plan
    header: T13Header
    deck: Deck
    deck_source: str
    tape_source: str
    wall_s: float

    def to_json(self) -> dict:
        """What ``tapp process --json`` writes (:func:`tapp.processor.printout.run_dict` and
        ``wall_s``)."""
        return {**run_dict(self.run, self.header, self.deck_source, self.tape_source),
                "wall_s": self.wall_s}

    def o3(self) -> str:
        """The O3 printout (:func:`tapp.processor.printout.o3_text`), as ``tapp process``
        prints it."""
        return o3_text(self.run, self.header, self.deck_source, self.tape_source)

    def t32(self) -> T32:
        """The T32 tape for TAPP II (:func:`tapp.processor.tape32.build_t32`)."""
        return build_t32(self.run, self.plan, self.header, t32_provenance(
            self.header, self.deck, self.deck_source, self.tape_source))

    def write_t32(self, path: Path | str) -> Path:
        """Write the T32 tape at ``path`` atomically; return the path."""
        return write_t32(path, self.t32())

    def plot(self, ax: Axes | None = None) -> Axes:
        """Draw the 1σ/3σ (δB·T, δB·R) ellipses, fit and real world, at the last time of the
        B-plane plot of ``tapp process --plots`` (the last recycle or print time), on ``ax``
        or on a new figure's axes (:func:`tapp.report.figures.subplots`); return the axes.

        Raises
        ------
        TappError
            The miss has no B·T and B·R.
        """
        names = tuple(self.header.miss.name)
        rows = bplane_rows(self.run.history, names)
        if not rows:
            raise TappError(f"{self.tape_source}: the miss ({', '.join(names)}) has no B·T "
                            "and B·R to plot")
        if ax is None:
            _, ax = subplots(figsize=(4.2, 4.2))
        draw_bplane_ellipses(ax, rows[-1], names)
        return ax


def process(tape: T13 | Path | str, deck: Deck | Path | str, *,
            progress: Callable[[int, int], None] | None = None) -> ProcessResult:
    """Run TAPP III on a T13 tape with a deck; return the run and its renderings.

    Parameters
    ----------
    tape : a T13 tape in memory, or its file (read lazily,
        :func:`tapp.io.tape.t13_hdf5.open_t13`).
    deck : a validated deck (:func:`tapp.processor.deck.read_deck`), or its TOML file.
    progress : called with (k, n_IT) after each cycle.

    Raises
    ------
    InputError
        A bad deck file or field, or a deck that does not fit the tape (naming the deck file
        and the field), as ``tapp process`` reports it.
    TapeError
        An unreadable or corrupt tape.
    """
    deck_source = MEMORY_DECK if isinstance(deck, Deck) else str(deck)
    if not isinstance(deck, Deck):
        deck = read_deck(deck)
    start = time.perf_counter()
    run, plan, header = process_tape(tape, deck, deck_source, progress)
    tape_source = MEMORY_TAPE if isinstance(tape, T13) else str(tape)
    return ProcessResult(run, plan, header, deck, deck_source, tape_source,
                         time.perf_counter() - start)
