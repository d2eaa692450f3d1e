"""The pipeline file (TOML): TAPP I -> TAPP III -> TAPP II in one run.

Layout::

    title = "..."
    scenario = "deep_space.toml"        # the TAPP I scenario: a path (relative to this file)
    deck = "tapp3_deep_space.toml"      # the TAPP III deck: a path, or
    guidance = "tapp2_deep_space.toml"  # the TAPP II guidance file: a path, or
    # [scenario] / [deck] / [guidance]  # ... any of the three inlined as a table
    [simulate]
    earth_orientation = "iau2006"       # optional: overrides the scenario's model
    [guide]
    samples = 20000                     # Monte Carlo samples
    seed = 1                            # root seed of the spawned seed sequences
    shard_size = 5000                   # optional, samples per shard (multiple of 1,000)

Each part is validated by its own schema (the scenario by
:class:`tapp.tracking.scenario_file.ScenarioFile`, the deck by :class:`tapp.processor.deck.Deck`,
the guidance file by :class:`tapp.guidance.guidefile.GuideFile`); an error in an inlined part
names this file and the part (``pipe.toml [deck]: times.print: ...``), one in a referenced
file names that file.

:func:`with_overrides` changes entries of the parts by dotted keys
(``scenario.tracking.data_interval_s``): the hook a parameter sweep varies (ITER's body
:func:`tapp.pipeline.run.tracking_case`).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from pydantic import Field

from tapp.errors import InputError
from tapp.guidance.study import (
    MAX_SAMPLES,
    MIN_SAMPLES,
    check_samples,
    check_seed,
    check_shard_samples,
)
from tapp.io.schema import EarthOrientationName, Schema, validate
from tapp.io.tomlfile import read_toml

#: The three parts of a pipeline, in run order.
PARTS = ("scenario", "deck", "guidance")


class SimulateTable(Schema):
    """``[simulate]``: options of the TAPP I step."""

    earth_orientation: EarthOrientationName | None = None


class GuideTable(Schema):
    """``[guide]``: options of the TAPP II step."""

    samples: int = Field(20000, description="Monte Carlo samples.", json_schema_extra={
        "minimum": MIN_SAMPLES, "maximum": MAX_SAMPLES})
    seed: int = Field(0, description="Root seed of the samples' random streams (the same "
                      "numbers on any number of workers).", json_schema_extra={"minimum": 0})
    shard_size: int | None = Field(None, gt=0, description="Samples per shard, a multiple of "
                                   "1,000; default: chosen from the workers.")


_PART = "The {}: a path (relative to this file) or an inline table of its keys."


class PipelineFile(Schema):
    """Schema of a pipeline file (module docstring)."""

    title: str = Field("", description="Free text, in the report's heading.")
    scenario: str | dict[str, Any] = Field(description=_PART.format("tracking scenario"))
    deck: str | dict[str, Any] = Field(description=_PART.format("TAPP III deck"))
    guidance: str | dict[str, Any] = Field(description=_PART.format("TAPP II guidance file"))
    simulate: SimulateTable = Field(SimulateTable(), description="Options of TAPP I.")
    guide: GuideTable = Field(GuideTable(), description="Options of TAPP II.")


@dataclass(frozen=True, slots=True)
class Part:
    """One part of a pipeline: its parsed TOML document and where it came from.

    ``source`` is the file (a referenced part) or ``"<pipeline> [part]"`` (an inlined one);
    relative paths inside the part are taken from the directory of ``source``.
    """

    document: dict
    source: str


@dataclass(frozen=True, slots=True)
class Pipeline:
    """A validated pipeline file: the three parts and the step options."""

    source: str
    title: str
    scenario: Part
    deck: Part
    guidance: Part
    earth_orientation: str | None
    samples: int
    seed: int
    shard_size: int | None


def _part(value: str | dict, name: str, path: Path) -> Part:
    if isinstance(value, dict):
        return Part(copy.deepcopy(value), f"{path} [{name}]")
    if not value.strip():
        raise InputError(str(path), name, f"the path of the {name} file or an inline "
                         f"[{name}] table", value)
    target = Path(value)
    target = target if target.is_absolute() else path.parent / target
    return Part(read_toml(target), str(target))


def read_pipeline(path: Path | str) -> Pipeline:
    """Read and validate a pipeline file and read the files its parts name.

    The parts themselves are validated when the steps bind them (their own schemas).

    Raises
    ------
    InputError
        Naming the file and the field: an unknown key, a missing part, a part file that
        cannot be read, a sample count, seed or shard size out of range.
    """
    path = Path(path)
    doc = validate(PipelineFile, read_toml(path), str(path))
    source = str(path)
    for field, check, value in (("guide.samples", check_samples, doc.guide.samples),
                                ("guide.seed", check_seed, doc.guide.seed),
                                ("guide.shard_size", check_shard_samples, doc.guide.shard_size)):
        try:
            check(value)
        except InputError as exc:
            raise InputError(source, field, exc.expected, value) from None
    parts = {name: _part(getattr(doc, name), name, path) for name in PARTS}
    return Pipeline(source, doc.title, parts["scenario"], parts["deck"], parts["guidance"],
                    doc.simulate.earth_orientation, doc.guide.samples, doc.guide.seed,
                    doc.guide.shard_size)


def with_overrides(pipeline: Pipeline, overrides: Mapping[str, object]) -> Pipeline:
    """Return the pipeline with entries of its parts replaced by dotted keys.

    ``{"scenario.tracking.data_interval_s": 120.0, "deck.stations_off": [...]}``: the first
    component names the part, the rest the (possibly new) entry of its document; a part
    whose entry changes is then named ``"<source> (overridden: key, ...)"`` in errors.

    Raises
    ------
    InputError
        A key that does not start with a part name, or runs through a non-table entry.
    """
    parts = {name: getattr(pipeline, name) for name in PARTS}
    changed: dict[str, list[str]] = {}
    documents = {name: copy.deepcopy(part.document) for name, part in parts.items()}
    for key, value in overrides.items():
        part, *path = key.split(".")
        if part not in PARTS or not path:
            raise InputError("overrides", key, f"a dotted key starting with one of "
                             f"{', '.join(PARTS)}", value)
        table = documents[part]
        for step in path[:-1]:
            table = table.setdefault(step, {})
            if not isinstance(table, dict):
                raise InputError("overrides", key, f"a path through tables of the {part}",
                                 value)
        table[path[-1]] = value
        changed.setdefault(part, []).append(".".join(path))
    new = {name: Part(documents[name], f"{parts[name].source} (overridden: "
                      f"{', '.join(changed[name])})")
           if name in changed else parts[name] for name in PARTS}
    return replace(pipeline, **new)
