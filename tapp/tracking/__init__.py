"""TAPP I: tracking simulation from a scenario to the T13 tape (and a CCSDS OEM trajectory).

- :mod:`tapp.tracking.scenario`: the scenario as frozen dataclasses;
  :mod:`tapp.tracking.scenario_file`: its file's tables and keys (its ``[[manoeuvre]]`` tables:
  :mod:`tapp.tracking.manoeuvres`); :mod:`tapp.tracking.scenario_build`: reading the file and
  building the scenario;
- :mod:`tapp.tracking.pieces`: the trajectory in pieces, restarted at the stochastic
  accelerations' bounds and at the burns, with the partials of their parameters;
- :mod:`tapp.tracking.simulate`: trajectory, partials, records, miss partials ->
  :class:`~tapp.io.tape.t13.T13`;
- :mod:`tapp.tracking.encounter`: a B-plane miss must be an encounter; ``[targeting]``
  retargets the injection by SEARCH first;
- :mod:`tapp.io.ccsds.oem`: CCSDS OEM 2.0 (KVN) writer.
"""

from tapp.tracking.scenario import Parameter, Scenario
from tapp.tracking.scenario_build import parse_scenario, read_scenario
from tapp.tracking.simulate import Simulation, miss_partials, simulate

__all__ = ["Parameter", "Scenario", "Simulation", "miss_partials", "parse_scenario",
           "read_scenario", "simulate"]
