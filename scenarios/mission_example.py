"""The trajectory and the pass schedule of the examples' mission folder, made by tapp.

``python -m scenarios.mission_example [DIR]`` (default: ``tapp/examples/mission``) writes:

- ``transfer.oem``: the mission's ephemeris, as another team would hand it over. It is
  tapp's own OEM of a lunar transfer with a deterministic burn: deep_space.toml's injection,
  force models and DSN stations, and :data:`BURN` (DV1, 3 m/s mostly along the velocity,
  18 hours after injection), flown by ``tapp simulate`` over :data:`SPAN_S` (3.5 days, up to
  the day of the lunar swing-by) with its states every :data:`OEM_STEP_S` (halved near the
  perigee), one segment before DV1 and one after;
- ``dsn_passes.csv``: the DSN passes the mission has booked: of every pass of that
  simulation (a station above its 10° mask), the central :data:`BOOKED_S` (4 hours), its
  ends on the 10-minute grid, range and range rate.

The other files of the folder (``mission.toml``, ``mission_deck.toml``,
``mission_guidance.toml``) are written by hand and read these two. Regenerating gives the same
trajectory (``tests/test_mission_example.py``); the OEM's creation date differs.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import tomli_w

from tapp.examples import FOLDER
from tapp.io.atomic import atomic_write
from tapp.io.tape.t13_hdf5 import read_t13

#: Where the files go by default: the package's mission folder.
MISSION = FOLDER / "mission"
#: The flight: from the injection to 3.5 days, before the lunar periapsis (3.59 days).
SPAN_S = 302400.0
#: Spacing of the OEM's states, s (the simulation's data interval), halved where needed.
OEM_STEP_S = 600.0
#: The deterministic burn (a [[manoeuvre]] table of the flight and of mission.toml).
BURN = {"name": "DV1", "kind": "impulsive", "time": "2026-03-11T06:00:00", "axes": "vnb",
        "dv_m_s": [3.0, 0.0, 0.5]}
#: Length of each booked pass, s, centred on the visibility pass (whole when shorter).
BOOKED_S = 14400.0


def flight_document() -> dict:
    """The lunar transfer that made the OEM: deep_space.toml with :data:`BURN`, over
    :data:`SPAN_S`, sampled every :data:`OEM_STEP_S`, without its stochastic accelerations
    (which do not move the nominal)."""
    doc = tomllib.loads((FOLDER / "deep_space.toml").read_text())
    doc.pop("stochastic")
    doc.update(title="Lunar transfer with a deterministic burn (the mission example's OEM)",
               iden="MISSION-TRANSFER", manoeuvre=[BURN],
               times={"input_step_s": 86400.0, "end": SPAN_S})
    doc["tracking"] = {**doc["tracking"], "data_interval_s": OEM_STEP_S, "end": SPAN_S}
    return doc


def booked_passes(tape) -> str:
    """The CSV of the booked passes (module docstring) from a tape's visibility passes."""
    epoch, p = tape.epoch, tape.passes
    rows = ["# DSN passes booked for the mission: the central 4 hours of each pass above the "
            "10 deg masks (scenarios/mission_example.py)",
            "station,start,end,data_types"]
    for s, a, b in zip(p.station, p.t_start_s, p.t_end_s, strict=True):
        middle, half = 0.5 * (a + b), 0.5 * min(BOOKED_S, b - a)
        start = OEM_STEP_S * np.ceil((middle - half) / OEM_STEP_S)
        end = OEM_STEP_S * np.floor((middle + half) / OEM_STEP_S)
        if end > start:
            rows.append(f"{tape.stations.name[s - 1]},{epoch.iso_after(float(start), 3)},"
                        f"{epoch.iso_after(float(end), 3)},range range_rate")
    return "\n".join(rows) + "\n"


def write(out: Path) -> tuple[Path, Path]:
    """Fly the transfer and write ``transfer.oem`` and ``dsn_passes.csv`` into ``out``."""
    with tempfile.TemporaryDirectory() as tmp:
        flight, tape = Path(tmp) / "transfer.toml", Path(tmp) / "transfer.t13.h5"
        flight.write_text(tomli_w.dumps(flight_document()))
        oem, csv = out / "transfer.oem", out / "dsn_passes.csv"
        proc = subprocess.run([sys.executable, "-m", "tapp.cli", "simulate", str(flight), "-o",
                               str(tape), "--oem", str(oem)], capture_output=True, text=True,
                              check=False)
        if proc.returncode != 0:
            raise SystemExit(f"tapp simulate {flight.name} exited {proc.returncode}: "
                             f"{proc.stderr}")
        text = booked_passes(read_t13(tape))
    atomic_write(csv, lambda tmp: tmp.write_text(text))
    return oem, csv


def main(argv: list[str]) -> None:
    out = Path(argv[0]) if argv else MISSION
    for path in write(out):
        print(f"{path} ({path.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main(sys.argv[1:])
