"""``tapp schema KIND``: the JSON Schema, or the reference page, of a kind of input file."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from tapp.cli.common import JsonOpt, app, delivering, json_file, run_guarded


@app.command("schema")
def schema_cmd(
    kind: Annotated[str, typer.Argument(help="scenario, deck, guidance, pipeline, sweep, "
                                        "search or study.")],
    markdown: Annotated[bool, typer.Option("--markdown", help="Print the reference page "
                                           "(docs/reference/KIND.md) instead.")] = False,
    json_out: JsonOpt = None,
) -> None:
    """Print the JSON Schema of an input file kind: every key with its type, unit, default,
    allowed values and meaning (the schema tapp validates the file against)."""
    from tapp.io import reference
    from tapp.io.outputs import check_paths

    def body() -> None:
        check_paths({}, {"--json": json_file(json_out)})
        reference.check_kind(kind)
        with delivering(json_out, reference.json_schema(kind)) as report:
            if report:
                typer.echo(reference.markdown(kind) if markdown else json.dumps(
                    reference.json_schema(kind), indent=2, ensure_ascii=False) + "\n", nl=False)

    run_guarded(body)
