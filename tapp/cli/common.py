"""Shared pieces of the CLI: the app object, error handling, JSON output."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable
from typing import Annotated, TypeVar

import numpy as np
import typer

from tapp import __version__
from tapp.errors import InputError, TappError

app = typer.Typer(
    name="tapp",
    help="Tracking accuracy prediction: trajectories, tracking, matrix processing, guidance, "
    "targeting and sweeps.",
    rich_markup_mode="rich",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

T = TypeVar("T")

#: Exit code for bad input (typer's own usage errors also exit 2).
EXIT_INPUT = 2
#: Exit code for any other TappError.
EXIT_FAILURE = 1


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"tapp {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version_callback, is_eager=True,
                     help="Print the version and exit."),
    ] = False,
) -> None:
    """Tracking accuracy prediction and orbit-determination analysis."""


def positive_option(name: str, value: float) -> float:
    """Return ``value`` if finite and > 0, else raise InputError naming the option."""
    if not (math.isfinite(value) and value > 0):
        raise InputError(name, "value", "a finite number > 0", value)
    return value


def run_guarded(fn: Callable[[], T]) -> T:
    """Run ``fn``; a TappError becomes one line on stderr and a non-zero exit."""
    try:
        return fn()
    except InputError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(EXIT_INPUT) from None
    except TappError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(EXIT_FAILURE) from None


def _to_jsonable(obj: object) -> object:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def print_json(obj: object) -> None:
    """Write one JSON object on stdout (NumPy arrays and scalars converted)."""
    sys.stdout.write(json.dumps(obj, default=_to_jsonable))
    sys.stdout.write("\n")
