"""CCSDS OEM 2.0 (KVN) writer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tapp.errors import InputError
from tapp.frames.time import parse_epoch
from tapp.tracking.oem import format_oem, write_oem

EPOCH = parse_epoch("2026-03-10T12:00:00")


def test_header_metadata_and_data_lines(tmp_path: Path) -> None:
    t = np.array([0.0, 60.0, 86400.5])
    x = np.arange(18.0).reshape(3, 6) + 7000.0
    text = format_oem(EPOCH, t, x, object_name="SC", object_id="2026-001A",
                      comments=("test",))
    lines = text.splitlines()
    assert lines[0] == "CCSDS_OEM_VERS = 2.0" and lines[1].startswith("CREATION_DATE = ")
    assert "COMMENT test" in lines
    meta = lines[lines.index("META_START") + 1:lines.index("META_STOP")]
    assert meta == ["OBJECT_NAME = SC", "OBJECT_ID = 2026-001A", "CENTER_NAME = EARTH",
                    "REF_FRAME = EME2000", "TIME_SYSTEM = UTC",
                    "START_TIME = 2026-03-10T12:00:00.000000",
                    "STOP_TIME = 2026-03-11T12:00:00.500000"]
    data = [line.split() for line in lines[lines.index("META_STOP") + 2:]]
    assert [d[0] for d in data] == ["2026-03-10T12:00:00.000000", "2026-03-10T12:01:00.000000",
                                    "2026-03-11T12:00:00.500000"]
    np.testing.assert_allclose(np.array([d[1:] for d in data], dtype=float), x, rtol=0,
                               atol=1e-9)
    path = write_oem(tmp_path / "out.oem", text)
    assert path.read_text() == text and path.stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize(("t", "x", "field"), [
    ([0.0, 0.0], np.zeros((2, 6)), "t_s"),
    ([0.0, 1.0], np.zeros((2, 5)), "states"),
    ([0.0, np.nan], np.zeros((2, 6)), "states"),
])
def test_bad_trajectories_are_refused(t, x, field: str) -> None:
    with pytest.raises(InputError) as err:
        format_oem(EPOCH, t, x, object_name="SC", object_id="X")
    assert err.value.field == field
