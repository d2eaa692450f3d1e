"""The programs' steps on tape files: open or read a tape, then run TAPP III or TAPP II on it.

TAPP III (:mod:`tapp.processor`) and TAPP II (:mod:`tapp.guidance`) compute on tapes in
memory and import no h5py (an import-linter contract checks it): reading tape files belongs to
the orchestration. :func:`process_tape` opens a T13 tape lazily
(:func:`tapp.io.tape.t13_hdf5.open_t13`) and runs TAPP III on it, for ``tapp process`` and the
pipeline (:mod:`tapp.pipeline.run`); :func:`run_guidance` reads a T32 tape
(:func:`tapp.io.tape.t32_hdf5.read_t32`) and a guidance file and runs a TAPP II study.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import nullcontext
from pathlib import Path

from iter.execute import Execution
from tapp.guidance.guidefile import read_guide
from tapp.guidance.study import GuidanceResult, guidance_study
from tapp.io.tape.t13 import T13, T13Header, memory_pairs
from tapp.io.tape.t13_hdf5 import open_t13
from tapp.io.tape.t32_hdf5 import read_t32
from tapp.processor.deck_bind import bind
from tapp.processor.plan import Plan
from tapp.processor.sequencing import Run, process

__all__ = ["process_tape", "run_guidance"]


def process_tape(tape: T13 | Path | str, deck, source: str,
                 progress: Callable[[int, int], None] | None = None
                 ) -> tuple[Run, Plan, T13Header]:
    """Run TAPP III on a T13 tape with a validated deck: (run, plan, the tape header).

    A tape file is read lazily (:func:`tapp.io.tape.t13_hdf5.open_t13`), a tape in memory
    through :func:`tapp.io.tape.t13.memory_pairs`, and the deck bound to it
    (:func:`tapp.processor.deck_bind.bind`): what ``tapp process``,
    :func:`tapp.api.processing.process` and the pipeline do. ``source`` (the deck file) is
    named in errors.
    """
    opened = nullcontext(memory_pairs(tape)) if isinstance(tape, T13) else open_t13(tape)
    with opened as data:
        plan = bind(deck, data.header, source)
        return process(data, plan, source=source, progress=progress), plan, data.header


def run_guidance(t32_path: Path | str, guide_path: Path | str, *, samples: int, seed: int,
                 execution: Execution | None = None, shard_samples: int | None = None,
                 progress: Callable[[int, int], None] | None = None) -> GuidanceResult:
    """Run a guidance study from a T32 tape file and a guidance file (:mod:`tapp.guidance.study`).

    See :func:`tapp.guidance.study.guidance_study` for the parameters and errors; the tape and
    the guidance file are read and validated first (errors name them).
    """
    guide = read_guide(guide_path)
    t32 = read_t32(t32_path)
    return guidance_study(t32, guide, samples=samples, seed=seed, execution=execution,
                          shard_samples=shard_samples, progress=progress,
                          guide_source=str(guide_path), tape_source=str(t32_path))
