"""``tapp schema KIND``: the JSON Schema, or the reference page, of a kind of input file."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from tapp.cli.common import app, run_guarded


@app.command("schema")
def schema_cmd(
    kind: Annotated[str, typer.Argument(help="scenario, deck, guidance, pipeline, sweep, "
                                        "search or study.")],
    markdown: Annotated[bool, typer.Option("--markdown", help="Print the reference page "
                                           "(docs/reference/KIND.md) instead.")] = False,
) -> None:
    """Print the JSON Schema of an input file kind: every key with its type, unit, default,
    allowed values and meaning (the schema tapp validates the file against)."""
    from tapp import reference

    def body() -> None:
        reference.check_kind(kind)
        if markdown:
            typer.echo(reference.markdown(kind), nl=False)
        else:
            typer.echo(json.dumps(reference.json_schema(kind), indent=2, ensure_ascii=False))

    run_guarded(body)
