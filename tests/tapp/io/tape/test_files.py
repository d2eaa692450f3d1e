"""Whole tape files whatever their format and version: ``describe`` and ``verify``
(:mod:`tapp.io.tape.files`) and ``tapp tape info`` on T13 versions 1 to 4 and T32 versions 1 and 2.

The summary of a tape does not depend on how its pair matrices are stored, so each old
version must describe as the current one does, with the warning of its reader.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

import tapp.cli.simulate_cmd  # noqa: F401  (registers ``tapp tape info`` until tapp.cli does)
from tapp.cli.common import app
from tapp.errors import TapeError
from tapp.io.tape import format_t32_summary
from tapp.io.tape.files import describe, verify
from tapp.io.tape.hdf5io import write_numbers
from tapp.io.tape.t13 import T13, VERSION
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.io.tape.t32 import T32
from tapp.io.tape.t32_hdf5 import write_t32
from tests.tapp.io.tape.legacy import (
    T32_V1_WARNING,
    refactored_tol,
    t13_read_warnings,
    write_t13_version,
    write_t32_version_1,
)
from tests.tapp.io.tape.synthetic import t13_tape, t32_tape

runner = CliRunner()
# Provenance stamped at writing (the clock differs between the files of one test).
WRITE_TIME = ("created_utc",)


@pytest.fixture(scope="module")
def t13() -> T13:
    return t13_tape(np.random.default_rng(13))


@pytest.fixture(scope="module")
def t32() -> T32:
    return t32_tape(np.random.default_rng(32))


def _t13_file(tmp_path: Path, tape: T13, version: int) -> Path:
    path = tmp_path / f"v{version}.t13.h5"
    if version == VERSION:
        return write_t13(path, tape)
    return write_t13_version(path, tape, version)


def _without(info: dict, *keys: str) -> dict:
    out = {k: v for k, v in info.items() if k not in keys}
    out["provenance"] = {k: v for k, v in info["provenance"].items() if k not in WRITE_TIME}
    return out


@pytest.mark.parametrize("version", [1, 2, 3])
def test_an_old_t13_describes_as_the_current_version(tmp_path: Path, t13: T13, version: int
                                                     ) -> None:
    current = describe(_t13_file(tmp_path, t13, VERSION))
    path = _t13_file(tmp_path, t13, version)
    with t13_read_warnings(version):
        old = describe(path)
    assert (current["version"], old["version"]) == (VERSION, version)
    assert old["verified_datasets"] == len(verify(path))
    assert _without(old, "version", "verified_datasets") == _without(
        current, "version", "verified_datasets")
    assert current["dimensions"]["pairs"] == t13.pairs.k.size


def test_describe_checks_every_pair_factor(tmp_path: Path, t13: T13) -> None:
    """``tapp tape info`` validates the tape as it summarises it: a factor with a negative
    diagonal in the last record fails, naming the dataset and the pair."""
    path = _t13_file(tmp_path, t13, VERSION)
    last = t13.pairs.k.size - 1
    with h5py.File(path, "r+") as f:
        data = f["pairs/R"][()]
        data[last, 0] = -1.0  # entry (0, 0): the first of the upper triangle by rows
        attrs = dict(f["pairs/R"].attrs)
        del f["pairs/R"]
        write_numbers(f["pairs"], "R", data, "")
        f["pairs/R"].attrs.update(attrs)
    assert "pairs/R" in verify(path)  # intact as stored: a checksum matches
    with pytest.raises(TapeError, match=rf"pairs/R: expected factors with a non-negative "
                                        rf"diagonal .* \(got -1 in pair {last}, row 0\)$"):
        describe(path)


@pytest.mark.parametrize("version", [2, 3, 4])
def test_tape_info_of_a_t13(tmp_path: Path, t13: T13, version: int) -> None:
    path = _t13_file(tmp_path, t13, version)
    with t13_read_warnings(version):
        res = runner.invoke(app, ["tape", "info", str(path), "--json", "-"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    assert (info["format"], info["version"], info["iden"]) == ("T13", version, "SYNTHETIC")
    assert info["dimensions"]["n_o"] == t13.n_o
    assert info["observations"] == int(t13.pairs.n_obs.sum())
    with t13_read_warnings(version):
        res = runner.invoke(app, ["tape", "info", str(path)])
    assert res.exit_code == 0, res.output
    for text in (f"T13 v{version}  iden SYNTHETIC", "Stations", "Epoch times", "q1_km"):
        assert text in res.stdout, text


def test_an_old_t32_describes_as_version_1(tmp_path: Path, t32: T32) -> None:
    """Version 1's summary is version 2's but for the σ of each recycle, formed from the
    factors its reader makes: to refactored_tol(n_o) relative (on the diagonal), as those."""
    current = describe(write_t32(tmp_path / "v2.t32.h5", t32))
    path = write_t32_version_1(tmp_path / "v1.t32.h5", t32)
    with pytest.warns(UserWarning, match=T32_V1_WARNING):
        old = describe(path)
    assert (current["version"], old["version"]) == (2, 1)
    assert old["verified_datasets"] == len(verify(path))
    sigma_keys = ("sigma_position_km", "sigma_velocity_km_s")
    for a, b in zip(old["recycles"], current["recycles"], strict=True):
        for key in sigma_keys:
            for world in ("fit", "real"):
                assert a[key][world] == pytest.approx(b[key][world],
                                                      rel=refactored_tol(t32.n_o)), (key, world)
    strip = [{k: v for k, v in rc.items() if k not in sigma_keys} for rc in old["recycles"]]
    assert strip == [{k: v for k, v in rc.items() if k not in sigma_keys}
                     for rc in current["recycles"]]
    assert _without(old, "version", "verified_datasets", "recycles") == _without(
        current, "version", "verified_datasets", "recycles")
    assert format_t32_summary(old).startswith("T32 v1  iden SYNTHETIC")


def test_tape_info_of_a_t32(tmp_path: Path, t32: T32) -> None:
    path = write_t32(tmp_path / "run.t32.h5", t32)
    res = runner.invoke(app, ["tape", "info", str(path)])
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith("T32 v2  iden SYNTHETIC")
    assert "ω  1: I; 0,-,pk; 1,2,fp  (partials pk wrt fp@recycle)  6 x 6" in res.stdout
    old = write_t32_version_1(tmp_path / "v1.t32.h5", t32)
    with pytest.warns(UserWarning, match=T32_V1_WARNING):
        res = runner.invoke(app, ["tape", "info", str(old), "--json", "-"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["version"] == 1
