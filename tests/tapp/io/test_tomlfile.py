"""Rewriting tables of a TOML file with its comments and layout kept (replace_tables)."""

from __future__ import annotations

import tomllib

import pytest

from tapp.errors import InputError
from tapp.io.tomlfile import replace_tables

TEXT = """# a scenario
title = "t"                 # kept

[injection]                 # the header's comment stays
r_km = [1.0, 2.0, 3.0]      # old
v_km_s = [4.0, 5.0, 6.0]

[injection.extra]
a = 1

# the table below goes, with this line
[targeting]
b = 2

[targeting.targets]
c = 3.5

[model]
gravity = "J2"              # kept too
"""


def test_replaced_and_removed_tables_and_nothing_else() -> None:
    new = {"r_km": [1.5, -2.0, 1e-05], "v_km_s": [0.1, 0.2, 0.30000000000000004],
           "allow_subsurface": True}
    out = replace_tables(TEXT, "s.toml", {"injection": new, "targeting": None},
                         comment="two\nlines")
    doc = tomllib.loads(out)
    assert doc == {"title": "t", "injection": new, "model": {"gravity": "J2"}}
    assert out.splitlines()[:6] == [
        "# a scenario", 'title = "t"                 # kept', "",
        "[injection]                 # the header's comment stays", "# two", "# lines"]
    assert "the table below goes" not in out and 'gravity = "J2"              # kept too' in out


def test_a_sub_table_by_its_dotted_name() -> None:
    out = replace_tables(TEXT, "s.toml", {"targeting.targets": {"c": -1.0, "d": "x"},
                                          "injection.extra": None})
    doc = tomllib.loads(out)
    assert doc["targeting"] == {"b": 2, "targets": {"c": -1.0, "d": "x"}}
    assert doc["injection"] == {"r_km": [1.0, 2.0, 3.0], "v_km_s": [4.0, 5.0, 6.0]}


@pytest.mark.parametrize("text", [
    'injection = {r_km = [1.0, 2.0, 3.0]}\n',          # an inline table
    'injection.r_km = [1.0, 2.0, 3.0]\n',              # dotted keys
])
def test_a_table_that_is_not_a_header_block_is_refused(text: str) -> None:
    with pytest.raises(InputError) as info:
        replace_tables(text, "s.toml", {"injection": {"r_km": [0.0, 0.0, 1.0]}})
    assert (info.value.source, info.value.field) == ("s.toml", "injection")
