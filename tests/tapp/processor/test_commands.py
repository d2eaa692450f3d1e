"""Output entities: the seed's notation and the aliases parse to the same commands."""

from __future__ import annotations

import pytest

from tapp.errors import InputError
from tapp.processor import ROC, UPC, parse_command


@pytest.mark.parametrize("cmd", UPC + ROC, ids=lambda c: c.seed())
def test_every_table_b5_command_round_trips_through_both_notations(cmd):
    output = cmd in ROC
    assert parse_command(cmd.seed(), output=output) == cmd
    assert parse_command(cmd.alias(), output=output) == cmd


@pytest.mark.parametrize(("seed", "alias"), [
    ("I; 0,-,pk; 1,2,fp", "partials pk wrt fp@recycle"),
    ("Lb'; 0,1,p; 0,1,p", "cov real orbit@current"),
    ("Λ'; 0,3,f1; 0,3,f1", "cov-fit fitted@injection"),
    ("J~; 1,2,f1; 1,2,fz", "info real f1@recycle x fz@recycle"),
    ("Sigma; 0,-,m1; 0,-,m1", "cov noise m1"),
    ("I; 1,2,fp; 0,-,pk", "partials pk wrt fp@recycle transposed"),
    ("S'; 1,0,fp; 1,0,fp", "normal-fit fp@epoch"),
])
def test_readable_aliases_mean_the_seed_commands(seed, alias):
    assert parse_command(seed) == parse_command(alias)


@pytest.mark.parametrize(("text", "fragment"), [
    ("Lb'; 1,1,p; 1,1,p", "parity"),            # a covariance with normal-matrix parity
    ("J; 0,1,o; 0,1,o", "parity"),              # a normal matrix with covariance parity
    ("I; 0,1,o; 0,1,o", "parity"),              # identity needs (0,1) or (1,0)
    ("J; 1,-,pk; 1,-,pk", "isolated set"),      # normal matrices have no isolated sets
    ("Lb'; 0,1,pk; 0,1,pk", "'-' as the orbit set"),
    ("Lb'; 0,7,p; 0,7,p", "orbit set"),
    ("Lb'; 0,1,zz; 0,1,zz", "set partition"),
    ("S'; 1,1,q; 1,1,q", "fitted parameters"),  # extended normal matrix outside f1 (§3.4.2)
    ("cov real orbit", "@<time>"),
    ("covariance p@current", "alias"),
    ("X; 0,1,p; 0,1,p", "matrix option"),
])
def test_meaningless_commands_are_refused_naming_the_command(text, fragment):
    with pytest.raises(InputError, match=fragment) as err:
        parse_command(text)
    assert text in str(err.value)


def test_the_update_commands_may_use_the_extended_normal_matrix_everywhere():
    assert parse_command("S; 1,1,o; 1,1,o", output=False).sigma == "S"


def test_the_reference_pages_command_examples_parse_to_what_they_say() -> None:
    """docs/reference/deck.md's command language (written from the parser's own tables): each
    readable example parses, and the seed example is the readable one it is said to equal."""
    import re

    from tapp.processor.commands import command_language_markdown, parse_command

    text = command_language_markdown()
    examples = re.findall(r'`"([^"`]+)"`', text)
    readable = [e for e in examples if ";" not in e and "<" not in e]
    assert {"cov real orbit@current", "cov-real-prior constants@current",
            "info f1@recycle x fz@recycle", "partials m wrt fp@current"} <= set(readable)
    for example in readable:
        parse_command(example)
    assert parse_command("Lb'; 0,1,p; 0,1,p") == parse_command("cov real orbit@current")
