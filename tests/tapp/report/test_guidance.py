"""The TAPP II report: sections left out with why, and the marks of contradicted linear
values, in the Markdown and the JSON alike."""

from __future__ import annotations

import dataclasses
import json
import re

import pytest

from iter.execute import Execution
from tapp.guidance.guidefile import GuideFile
from tapp.guidance.study import guidance_study
from tapp.io.schema import validate
from tapp.io.tomlfile import read_toml
from tapp.report.guidance import CONTRADICTED, guidance_dict, guidance_markdown
from tests.tapp.guidance.helpers import ELEMENTS, SCENARIOS, deep_space_t32, guide

SERIAL = Execution(serial=True)


@pytest.fixture(scope="module")
def elements():
    """A study of a tape whose miss is (a, e, i): no B-plane, no flight time, no corridor."""
    return guidance_study(deep_space_t32(elements=True),
                          guide(targets={"miss": list(ELEMENTS)}), samples=2000, seed=1,
                          execution=SERIAL)


def test_a_tape_without_bplane_or_flight_time_prints_no_such_table(elements):
    md = guidance_markdown(elements)
    assert "## B-plane dispersion" not in md and "## Flight-time dispersion" not in md
    assert "semi-major" not in md and "σ flight time" not in md and "## Corridor" not in md
    why = {"bplane_ellipse": "the tape has no B-plane miss components (b_dot_t_km, "
                             "b_dot_r_km); its miss components: a_km, e, i_rad",
           "flight_time_sigma_s": "the tape has no flight-time miss component "
                                  "(flight_time_s or ltof_s); its miss components: a_km, e, "
                                  "i_rad",
           "outside_corridor": "the guidance file has no [corridor] table"}
    lines = md.splitlines()
    for what, text in (("B-plane dispersion ellipse", why["bplane_ellipse"]),
                       ("flight-time dispersion", why["flight_time_sigma_s"]),
                       ("corridor", why["outside_corridor"])):
        assert lines.count(f"No {what}: {text}.") == 1
    content = json.loads(json.dumps(guidance_dict(elements)))
    assert content["left_out"] == why and "corridor" not in content
    for method in ("monte_carlo", "linear"):
        assert set(why).isdisjoint(content[method]) and "miss_cov" in content[method]


def test_a_tape_with_a_flight_time_but_no_bplane_prints_the_flight_time_alone():
    """The deep-space tape with its B·R, B·T renamed (so no longer B-plane components)."""
    names = ("r_km", "t_km", "flight_time_s")
    tape = dataclasses.replace(deep_space_t32(), miss_name=names)
    r = guidance_study(tape, guide(targets={"miss": list(names[:2])}), samples=2000, seed=1,
                       execution=SERIAL)
    md = guidance_markdown(r)
    table = md[md.index("## Flight-time dispersion (1σ)"):]
    assert table.splitlines()[2] == "| method | σ flight time (s) |"
    assert "semi-major" not in md and "## B-plane dispersion" not in md
    assert md.splitlines().count("No B-plane dispersion ellipse: the tape has no B-plane miss "
                                 "components (b_dot_t_km, b_dot_r_km); its miss components: "
                                 "r_km, t_km, flight_time_s.") == 1
    content = guidance_dict(r)
    assert set(content["left_out"]) == {"bplane_ellipse", "outside_corridor"}
    assert content["linear"]["flight_time_sigma_s"] > 0 and "bplane_ellipse" not in \
        content["linear"]


@pytest.fixture(scope="module")
def shipped():
    doc = read_toml(SCENARIOS / "tapp2_deep_space.toml")
    return guidance_study(deep_space_t32(), validate(GuideFile, doc, "guide.toml"),
                          samples=100_000, seed=1, execution=SERIAL)


def test_the_marks_are_those_of_the_contradicted_linear_values(shipped):
    md = guidance_markdown(shipped)
    content = json.loads(json.dumps(guidance_dict(shipped)))
    agreement = content["agreement"]
    bad = [k for k, c in agreement["checks"].items() if c["contradicted_by_monte_carlo"]]
    assert bad == agreement["contradicted"] and "outside_corridor.bplane" in bad
    assert {"manoeuvres[1].magnitude.percentiles_km_s.99",
            "manoeuvres[2].magnitude.percentiles_km_s.99"} <= set(bad)
    assert not any(k.startswith("manoeuvres[0]") for k in bad)
    assert content["left_out"] == {} and content["linear"]["bplane_ellipse"]["semi_major_km"]
    # every mark sits on a linear row of a table, one per contradicted statistic
    marked = [line for line in md.splitlines() if CONTRADICTED in line and line.startswith("|")
              and "linear covariance" in line]
    assert sum(line.count(CONTRADICTED) for line in marked) == len(bad)
    assert not any(CONTRADICTED in line for line in md.splitlines()
                   if line.startswith("| 1 |") or "Monte Carlo |" in line)
    # and each is listed with the Monte Carlo value and its sampling error
    section = md[md.index("## Linear covariance against the Monte Carlo"):]
    listed = re.findall(r"^\| ((?:recycle \d:|total) \\\|Δv\\\| [^|]+|outside [^|]+) \|",
                        section, flags=re.MULTILINE)
    assert [s.replace("\\|", "|") for s in listed] == [agreement["checks"][k]["label"]
                                                       for k in bad]
    assert f"{len(bad)} contradicted" in section
