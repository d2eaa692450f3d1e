"""The examples' mission folder (tapp/examples/mission/, the tutorial's "Your own mission"): its
OEM and its pass schedule are what ``scenarios/mission_example.py`` makes, and the OEM stays
small enough to ship."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from scenarios.mission_example import MISSION, write
from tapp.io.ccsds.oem_read import read_oem

#: One unit of the last digit the OEM prints (1e-9 km, 1e-12 km/s): the same trajectory
#: regenerated on another machine may round a digit the other way (measured here: identical).
PRINTED_KM, PRINTED_KM_S = 1e-9, 1e-12
#: The shipped OEM's size bound, bytes (measured 81 kB: 669 lines).
MAX_OEM_BYTES = 300_000


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("mission")
    write(out)
    return out


def test_regenerating_the_oem_gives_the_same_trajectory(regenerated: Path) -> None:
    shipped, again = read_oem(MISSION / "transfer.oem"), read_oem(regenerated / "transfer.oem")
    assert len(shipped.segments) == len(again.segments) == 2  # before and after DV1
    for ours, theirs in zip(shipped.segments, again.segments, strict=True):
        assert ours.metadata == theirs.metadata
        np.testing.assert_array_equal(ours.jd_whole, theirs.jd_whole)
        np.testing.assert_array_equal(ours.jd_fraction, theirs.jd_fraction)
        np.testing.assert_allclose(ours.states[:, :3], theirs.states[:, :3], rtol=0,
                                   atol=PRINTED_KM)
        np.testing.assert_allclose(ours.states[:, 3:], theirs.states[:, 3:], rtol=0,
                                   atol=PRINTED_KM_S)
    comments = [[line for line in (folder / "transfer.oem").read_text().splitlines()
                 if line.startswith("COMMENT")] for folder in (MISSION, regenerated)]
    assert comments[0] == comments[1]


def test_regenerating_the_booked_passes_gives_the_same_file(regenerated: Path) -> None:
    assert (regenerated / "dsn_passes.csv").read_text() == \
        (MISSION / "dsn_passes.csv").read_text()


def test_the_shipped_oem_is_small() -> None:
    assert (MISSION / "transfer.oem").stat().st_size < MAX_OEM_BYTES
