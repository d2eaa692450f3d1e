"""The example input files shipped with tapp (``tapp examples DIR`` copies them for a new user).

The files of this folder are package data: every kind of input file, commented, as the
reproduction runs use them (``make scenario``) and as ``tapp examples DIR`` copies them for a
user to start from. ``approx_stm.toml`` is also the study file that ``tapp dc``, ``tapp ekf``,
``tapp rsig`` and ``--orbit SATORB1`` read when no ``--scenario`` is given
(:data:`STUDY_FILE`).

Paths inside the files are relative to their own folder (a pipeline names its scenario,
deck and guidance file; a sweep its pipeline), so the copied set runs from wherever it is
copied to. The kind of each file is the schema that reads it (``tapp schema KIND``), or what
a scenario reads from it: a ``trajectory`` (``[reference] file``) or a ``schedule``
(``[tracking] schedule``).

``mission/`` is a mission of one's own: a scenario whose trajectory is the mission's OEM with a
deterministic burn and whose tracking is a CSV of booked DSN passes, with its deck and
guidance file (the tutorial's "Your own mission"). Its OEM and CSV are made by tapp
(``scenarios/mission_example.py``; regenerating them is tested).

``mars/`` is an interplanetary cruise: a Mars 2028 transfer from the Earth departure, integrated
about the Earth, the Sun and Mars in turn, DSN range, Doppler and ΔDOR for 229 days, four TCMs
to the Mars B-plane, and a trade study (ΔDOR x DSN passes per week) on its simulated tape.
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

#: The shipped files (paths relative to :data:`FOLDER`) and the kind of input each is, in the
#: order a new user meets them.
FILES: dict[str, str] = {
    "leo_equatorial.toml": "scenario",
    "deep_space.toml": "scenario",
    "leo_drag.toml": "scenario",
    "tapp1_table_d1.toml": "scenario",
    "tapp3_leo_equatorial.toml": "deck",
    "tapp3_deep_space.toml": "deck",
    "tapp3_leo_drag.toml": "deck",
    "tapp3_table_d1.toml": "deck",
    "tapp2_deep_space.toml": "guidance",
    "pipeline_deep_space.toml": "pipeline",
    "iter_pipeline_tracking.toml": "sweep",
    "iter_azimuth_type1.toml": "sweep",
    "iter_azimuth_type2.toml": "sweep",
    "iter_days_azimuths.toml": "sweep",
    "iter_lunar_departure.toml": "sweep",
    "search_bplane.toml": "search",
    "approx_stm.toml": "study",
    "mission/mission.toml": "scenario",
    "mission/transfer.oem": "trajectory",
    "mission/dsn_passes.csv": "schedule",
    "mission/mission_deck.toml": "deck",
    "mission/mission_guidance.toml": "guidance",
    "mars/mars.toml": "scenario",
    "mars/mars_deck.toml": "deck",
    "mars/mars_guidance.toml": "guidance",
    "mars/mars_pipeline.toml": "pipeline",
    "mars/mars_trade.toml": "sweep",
}

#: The folder of the shipped files. A package installed from a wheel is a folder of files
#: (pip unpacks wheels), so its resources are paths; ``os.fspath`` refuses any other kind.
FOLDER = Path(os.fspath(files(__name__)))
#: The approximate-STM study file, the default of every command that reads one.
STUDY_FILE = FOLDER / "approx_stm.toml"
