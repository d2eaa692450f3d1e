"""Sweep files: the seed's scenarios load to the right cases; bad input names file and field."""

from __future__ import annotations

from pathlib import Path

import pytest

from iter import CallableBody, ProgramBody, SweepInputError, load_sweep, parse_sweep
from tapp.examples import FOLDER as EXAMPLES

SCENARIOS = EXAMPLES


def test_five_azimuth_scenarios_type_1_and_type_2_give_the_same_cases():
    type_1 = load_sweep(SCENARIOS / "iter_azimuth_type1.toml")
    type_2 = load_sweep(SCENARIOS / "iter_azimuth_type2.toml")
    assert [loop.type for loop in type_1.loops] == [1]
    assert [loop.type for loop in type_2.loops] == [2]
    # Seed VI, CASE 1: 96, 99, 102, 105 and 108 deg.
    expected = [(96.0,), (99.0,), (102.0,), (105.0,), (108.0,)]
    assert [c.values for c in type_1.cases()] == expected
    assert type_1.cases() == type_2.cases()
    assert type_1.body == type_2.body


def test_days_azimuths_scenario_has_the_seed_150_cases_in_order():
    sweep = load_sweep(SCENARIOS / "iter_days_azimuths.toml")
    cases = sweep.cases()
    assert sweep.names == ("launch_day", "azimuth_deg")
    assert len(cases) == sweep.n_cases == 150
    # Hand-computed from the seed's VARY/DELTA cards: case k = (5730 + k // 5, 96 + 3 (k % 5)).
    assert cases[0].kwargs() == {"launch_day": 5730.0, "azimuth_deg": 96.0}
    assert cases[77].kwargs() == {"launch_day": 5745.0, "azimuth_deg": 102.0}
    assert cases[149].kwargs() == {"launch_day": 5759.0, "azimuth_deg": 108.0}


def _document(**loop_overrides):
    loop = {"type": 1, "names": ["azimuth_deg"], "sets": 2, "vary": [96.0, 99.0]}
    loop.update(loop_overrides)
    loop = {k: v for k, v in loop.items() if v is not None}
    return {"body": {"callable": "tapp.targeting.launch_azimuth:launch_azimuth_case"},
            "loop": [loop]}


@pytest.mark.parametrize(("overrides", "field", "fragment"), [
    ({"vary": [96.0, 99.0, 102.0]}, "loop[0].vary", "2 x 1 = 2 values"),
    ({"type": 3}, "loop[0].type", "1 (table) or 2"),
    ({"type": 2, "vary": [96.0]}, "loop[0].delta", "increments for type 2"),
    ({"sets": None}, "loop[0].sets", "the key is required"),
    ({"n": 2}, "loop[0].n", "len(names) = 1"),
    ({"start": [96.0]}, "loop[0].start",
     "no such key (allowed: type, names, n, sets, vary, delta)"),
    ({"sets": True}, "loop[0].sets", "an integer"),
    ({"sets": 2.0}, "loop[0].sets", "an integer"),
    ({"vary": [96.0, "99"]}, "loop[0].vary[1]", "a number"),
    ({"vary": [96.0, True]}, "loop[0].vary[1]", "a number"),
    ({"vary": [96.0, float("nan")]}, "loop[0].vary[1]", "a finite number"),
    ({"type": "1"}, "loop[0].type", "an integer"),
])
def test_bad_loop_fields_name_file_and_field(overrides, field, fragment):
    with pytest.raises(SweepInputError) as info:
        parse_sweep(_document(**overrides), source="bad.toml")
    assert (info.value.source, info.value.field) == ("bad.toml", field)
    assert fragment in info.value.expected
    assert str(info.value).startswith(f"bad.toml: {field}: expected ")


@pytest.mark.parametrize(("target", "fragment"), [
    ("no_such_module_xyz:f", "an importable module"),
    ("tapp.targeting.launch_azimuth:no_such_function", "a function 'no_such_function'"),
    ("tapp.targeting.launch_azimuth", '"module:function"'),
    ("tapp.targeting.launch_azimuth:GM_EARTH_km3_s2", "a callable"),
])
def test_unknown_body_callable_is_bad_input(target, fragment):
    document = _document()
    document["body"]["callable"] = target
    with pytest.raises(SweepInputError) as info:
        parse_sweep(document, source="bad.toml")
    assert info.value.field == "body.callable"
    assert fragment in info.value.expected


def test_unknown_program_is_bad_input():
    document = _document()
    document["body"] = {"program": ["no-such-program-xyz", "run"]}
    with pytest.raises(SweepInputError, match="bad.toml: body.program"):
        parse_sweep(document, source="bad.toml")


def test_body_fields_are_checked():
    document = _document()
    document["body"] = {"callable": "tapp.targeting.launch_azimuth:launch_azimuth_case",
                        "program": ["x"]}
    with pytest.raises(SweepInputError, match="exactly one of callable or program"):
        parse_sweep(document)
    document["body"] = {"callable": "tapp.targeting.launch_azimuth:launch_azimuth_case",
                        "json": True}
    with pytest.raises(SweepInputError, match="body.json"):
        parse_sweep(document)
    document["body"] = {"callable": "tapp.targeting.launch_azimuth:launch_azimuth_case",
                        "constants": {"azimuth_deg": 1.0}}
    with pytest.raises(SweepInputError, match=r"loop\[0\]\.names.*not also body.constants"):
        parse_sweep(document)


def test_unknown_tables_and_body_keys_are_named_with_the_allowed_keys():
    document = _document()
    document["sweeps"] = {"description": "typo"}
    with pytest.raises(SweepInputError, match=r"^bad\.toml: sweeps: expected no such key "
                       r"\(allowed: sweep, body, loop\)"):
        parse_sweep(document, source="bad.toml")
    document = _document()
    document["body"]["timeout"] = 5
    with pytest.raises(SweepInputError, match=r"^bad\.toml: body\.timeout: expected no such key "
                       r"\(allowed: callable, program, json, dashes, timeout_s, constants, "
                       r"files\)"):
        parse_sweep(document, source="bad.toml")
    document = _document()
    document["body"]["timeout_s"] = True
    with pytest.raises(SweepInputError, match=r"^bad\.toml: body\.timeout_s: expected a number"):
        parse_sweep(document, source="bad.toml")
    document = _document()
    document["body"] = {"program": ["tapp", "propagate"], "json": 1}
    with pytest.raises(SweepInputError, match=r"^bad\.toml: body\.json: expected true or false"):
        parse_sweep(document, source="bad.toml", check_body=False)


def test_program_body_is_read_with_its_options():
    document = _document()
    document["body"] = {"program": ["tapp", "propagate"], "dashes": True, "timeout_s": 60,
                        "constants": {"step_s": 10.0}}
    sweep = parse_sweep(document, check_body=False)
    assert sweep.body == ProgramBody(argv=("tapp", "propagate"), constants={"step_s": 10.0},
                                     json_option=True, dashes=True, timeout_s=60.0)


def test_file_errors_name_the_file(tmp_path):
    missing = tmp_path / "missing.toml"
    with pytest.raises(SweepInputError, match="missing.toml: file: expected an existing sweep"):
        load_sweep(missing)
    broken = tmp_path / "broken.toml"
    broken.write_text("[body\n")
    with pytest.raises(SweepInputError, match="broken.toml: TOML: expected valid TOML"):
        load_sweep(broken)


def test_loaded_sweep_keeps_the_file_contents(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[sweep]\ndescription = "d"\n[body]\ncallable = "tapp.targeting.launch_azimuth:'
                    'launch_azimuth_case"\n[[loop]]\nnames = ["azimuth_deg"]\nsets = 1\n'
                    "vary = [96.0]\n")
    sweep = load_sweep(path)
    assert sweep.loops[0].type == 1  # the seed's canned TYPE
    assert sweep.body == CallableBody(target="tapp.targeting.launch_azimuth:launch_azimuth_case")
    assert '"description": "d"' in sweep.contents_json()
    assert "description" not in sweep.definition_json()


def _write_sweep(path: Path, body: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'{body}\n[[loop]]\nnames = ["azimuth_deg"]\nsets = 1\nvary = [96.0]\n')
    return path


def test_files_are_taken_from_the_sweep_files_folder_whatever_the_directory(tmp_path,
                                                                           monkeypatch):
    folder = tmp_path / "study"
    (folder / "data").mkdir(parents=True)
    (folder / "data" / "scale.txt").write_text("2")
    absolute = tmp_path / "elsewhere.txt"
    absolute.write_text("3")
    _write_sweep(folder / "sweeps" / "s.toml",
                 '[body]\ncallable = "tapp.targeting.launch_azimuth:launch_azimuth_case"\n'
                 '[body.files]\n'
                 f'scale_file = "../data/scale.txt"\nother = "{absolute}"\n')
    monkeypatch.chdir(tmp_path / "study" / "data")  # neither the repository nor the folder
    sweep = load_sweep(Path("..") / "sweeps" / "s.toml")
    assert sweep.body.files == {"scale_file": str(folder / "data" / "scale.txt"),
                                "other": str(absolute)}
    assert sweep.definition()["body"]["files"] == sweep.body.files
    assert "files" not in load_sweep(SCENARIOS / "iter_azimuth_type1.toml").definition()["body"]


def test_a_missing_file_is_named_with_where_it_was_looked_for(tmp_path, monkeypatch):
    path = _write_sweep(tmp_path / "s.toml", '[body]\ncallable = "tapp.targeting.launch_azimuth:'
                        'launch_azimuth_case"\n[body.files]\nscale_file = "scale.txt"\n')
    (tmp_path / "cwd").mkdir()
    (tmp_path / "cwd" / "scale.txt").write_text("2")  # beside the working directory: not used
    monkeypatch.chdir(tmp_path / "cwd")
    with pytest.raises(SweepInputError) as info:
        load_sweep(path)
    assert info.value.field == "body.files.scale_file"
    assert info.value.got == str(tmp_path / "scale.txt")
    assert "from the sweep file's folder" in info.value.expected


def test_a_program_given_as_a_path_is_taken_from_the_sweep_files_folder(tmp_path):
    by_path = _write_sweep(tmp_path / "a" / "s.toml", '[body]\nprogram = ["bin/run", "x.py"]\n')
    by_name = _write_sweep(tmp_path / "b" / "s.toml", '[body]\nprogram = ["python3", "x.py"]\n')
    assert load_sweep(by_path, check_body=False).body.argv == (
        str(tmp_path / "a" / "bin" / "run"), "x.py")
    assert load_sweep(by_name, check_body=False).body.argv == ("python3", "x.py")


@pytest.mark.parametrize(("files", "constants", "varied", "field"), [
    ({"azimuth_deg": "s.toml"}, {}, "azimuth_deg", "loop[0].names"),
    ({"scale": "s.toml"}, {"scale": 1.0}, "azimuth_deg", "body.files.scale"),
    ({"bad-name": "s.toml"}, {}, "azimuth_deg", "body.files.bad-name"),
])
def test_file_names_are_checked_like_constants(tmp_path, files, constants, varied, field):
    document = {"body": {"callable": "tapp.targeting.launch_azimuth:launch_azimuth_case",
                         "files": files,
                         "constants": constants},
                "loop": [{"names": [varied], "sets": 1, "vary": [96.0]}]}
    (tmp_path / "s.toml").touch()
    with pytest.raises(SweepInputError) as info:
        parse_sweep(document, source="bad.toml", base_dir=tmp_path)
    assert info.value.field == field
