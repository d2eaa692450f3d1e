"""The schema mechanism: one line naming file and field for every bad entry, never a traceback."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path
from typing import Annotated, Literal

import pytest
from pydantic import Field

from tapp.errors import InputError
from tapp.io.schema import InfFloat, Invalid, Schema, load, validate


class Station(Schema):
    lat_deg: float
    h_km: float = 0.0


class Model(Schema):
    gravity: Literal["J2", "J0"] = "J2"
    tol: Annotated[float, Field(gt=0)] = 1e-12
    max_pass_s: InfFloat = math.inf


class Study(Schema):
    seed: int = 0
    title: str = ""
    epoch: str | dt.datetime = "2026-01-01T00:00:00"
    model: Model = Model()
    stations: dict[str, Station] = {}
    sigmas_m: list[float] = []

    def model_post_init(self, context: object) -> None:
        if self.seed < 0:
            raise Invalid("a seed >= 0", self.seed, "seed")


def message(data: dict) -> str:
    with pytest.raises(InputError) as info:
        validate(Study, data, "study.toml")
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith("study.toml: ")
    return text


def test_a_valid_document_gives_a_frozen_model_with_defaults() -> None:
    study = validate(Study, {"seed": 7, "stations": {"Q": {"lat_deg": 1}}}, "study.toml")
    assert study.seed == 7 and study.model.gravity == "J2"
    assert study.stations["Q"].lat_deg == 1.0 and isinstance(study.stations["Q"].lat_deg, float)
    with pytest.raises(ValueError):
        study.seed = 8  # type: ignore[misc]


def test_an_unknown_key_is_named_with_the_allowed_keys() -> None:
    assert message({"colour": "red"}) == (
        "study.toml: colour: expected no such key (allowed: seed, title, epoch, model, "
        "stations, sigmas_m) (got 'red')")


def test_a_misspelled_key_names_itself_not_the_key_it_hides() -> None:
    text = message({"sed": 1969})
    assert text.startswith("study.toml: sed: expected no such key (allowed: seed, ")
    assert text.endswith("(got 1969)")


def test_unknown_sections_and_nested_unknown_keys_carry_their_path() -> None:
    assert message({"extra": {"a": 1}}).startswith("study.toml: extra: expected no such key")
    assert message({"model": {"rtol": 1e-9}}) == (
        "study.toml: model.rtol: expected no such key (allowed: gravity, tol, max_pass_s) "
        "(got 1e-09)")
    assert message({"stations": {"Q": {"lat_deg": 1, "h_m": 3}}}).startswith(
        "study.toml: stations.Q.h_m: expected no such key (allowed: lat_deg, h_km)")


def test_booleans_are_not_numbers() -> None:
    assert message({"seed": True}) == "study.toml: seed: expected an integer (got True)"
    assert message({"stations": {"Q": {"lat_deg": True}}}) == (
        "study.toml: stations.Q.lat_deg: expected a number (got True)")


def test_strings_are_not_numbers_and_numbers_are_not_strings() -> None:
    assert message({"stations": {"Q": {"lat_deg": "10"}}}) == (
        "study.toml: stations.Q.lat_deg: expected a number (got '10')")
    assert message({"title": 3}) == "study.toml: title: expected text (a quoted string) (got 3)"
    assert message({"seed": 1.5}) == "study.toml: seed: expected an integer (got 1.5)"


def test_union_members_are_joined_not_listed_as_separate_errors() -> None:
    assert message({"epoch": 5}) == (
        "study.toml: epoch: expected text (a quoted string) or a date and time (got 5)")


def test_floats_are_finite_unless_declared_otherwise() -> None:
    assert message({"model": {"tol": math.inf}}) == (
        "study.toml: model.tol: expected a finite number (got inf)")
    assert message({"model": {"tol": 0}}) == (
        "study.toml: model.tol: expected a finite number > 0 (got 0)")
    assert validate(Study, {"model": {"max_pass_s": math.inf}}, "s").model.max_pass_s == math.inf
    assert "not nan" in message({"model": {"max_pass_s": math.nan}})


def test_choices_missing_keys_and_tables() -> None:
    assert message({"model": {"gravity": "J3"}}) == (
        "study.toml: model.gravity: expected one of 'J2' or 'J0' (got 'J3')")
    assert message({"stations": {"Q": {}}}) == (
        "study.toml: stations.Q.lat_deg: expected a value (the key is required)")
    assert message({"model": 3}) == "study.toml: model: expected a table (got 3)"


def test_list_items_are_named_by_index() -> None:
    assert message({"sigmas_m": [1.0, 2.0, "x"]}) == (
        "study.toml: sigmas_m[2]: expected a number (got 'x')")


def test_validator_failures_are_reported_like_type_errors() -> None:
    assert message({"seed": -1}) == "study.toml: seed: expected a seed >= 0 (got -1)"


def test_the_prefix_places_a_table_within_its_file() -> None:
    with pytest.raises(InputError, match=r"^f\.toml: model\.gravity: expected one of"):
        validate(Model, {"gravity": "x"}, "f.toml", prefix="model")


def test_load_reads_and_validates_a_file(tmp_path: Path) -> None:
    path = tmp_path / "study.toml"
    path.write_text('seed = 3\n[model]\ngravity = "J0"\n')
    assert load(Study, path).model.gravity == "J0"
    path.write_text("sed = 1969\n")
    with pytest.raises(InputError, match=rf"^{path}: sed: expected no such key"):
        load(Study, path)
    path.write_text("seed = [\n")
    with pytest.raises(InputError, match=rf"^{path}: TOML: expected valid TOML"):
        load(Study, path)


def test_unique_lists_name_the_repeated_item() -> None:
    from tapp.io.schema import Unique

    class Bodies(Schema):
        third_bodies: Annotated[list[str], Unique] = []

    with pytest.raises(InputError) as info:
        validate(Bodies, {"third_bodies": ["sun", "moon", "sun"]}, "m.toml")
    assert str(info.value) == ("m.toml: third_bodies: expected each item once ('sun' is "
                               "repeated) (got ['sun', 'moon', 'sun'])")


class Elimination(Schema):
    command: Literal["eliminate"]
    parameters: list[str]


class Recycle(Schema):
    command: Literal["recycle"]
    times: int


class Deck(Schema):
    steps: list[Annotated[Elimination | Recycle, Field(discriminator="command")]] = []
    window_s: tuple[float, float] = (0.0, 1.0)


def test_tagged_tables_name_the_tag_and_their_own_fields() -> None:
    deck = validate(Deck, {"steps": [{"command": "recycle", "times": 2}]}, "deck.toml")
    assert isinstance(deck.steps[0], Recycle)
    with pytest.raises(InputError, match=r"^deck\.toml: steps\[1\]\.command: expected one of "
                       r"'eliminate', 'recycle' \(got 'recylce'\)$"):
        validate(Deck, {"steps": [{"command": "recycle", "times": 2},
                                  {"command": "recylce", "times": 2}]}, "deck.toml")
    with pytest.raises(InputError, match=r"^deck\.toml: steps\[0\]\.times: expected an integer"):
        validate(Deck, {"steps": [{"command": "recycle", "times": 1.5}]}, "deck.toml")
    with pytest.raises(InputError, match=r"^deck\.toml: steps\[0\]\.command: expected a value"):
        validate(Deck, {"steps": [{"times": 1}]}, "deck.toml")


def test_a_tuple_field_takes_a_toml_array() -> None:
    assert validate(Deck, {"window_s": [2, 3.5]}, "deck.toml").window_s == (2.0, 3.5)
    with pytest.raises(InputError, match=r"^deck\.toml: window_s\[1\]: expected a number"):
        validate(Deck, {"window_s": [2, True]}, "deck.toml")
    with pytest.raises(InputError, match=r"^deck\.toml: window_s\[1\]: expected an item here "
                       r"\(the array is too short\)$"):
        validate(Deck, {"window_s": [2]}, "deck.toml")
