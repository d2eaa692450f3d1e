"""``simulate``: TAPP I on a scenario (a :class:`~tapp.tracking.scenario.Scenario` or its
file), the result holding the T13 tape and rendering ``tapp simulate --json``."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from tapp.io.tape.t13 import T13, summary
from tapp.io.tape.t13_hdf5 import write_t13
from tapp.tracking.scenario import Scenario
from tapp.tracking.scenario_build import read_scenario
from tapp.tracking.simulate import ProgressCallback, Simulation
from tapp.tracking.simulate import simulate as run_simulation

__all__ = ["SimulateResult", "simulate"]


@dataclass(frozen=True, slots=True)
class SimulateResult:
    """A TAPP I run: the simulation (:class:`tapp.tracking.simulate.Simulation`) and its
    wall time (s)."""

    simulation: Simulation
    wall_s: float

    @property
    def tape(self) -> T13:
        """The T13 tape (in memory)."""
        return self.simulation.tape

    def write(self, path: Path | str) -> Path:
        """Write the T13 tape at ``path`` atomically (:func:`tapp.io.tape.t13_hdf5.write_t13`);
        return the path."""
        return write_t13(path, self.tape)

    def to_json(self, *, tape: str | None = None, oem: str | None = None,
                tdm: str | None = None, spk: dict | None = None) -> dict:
        """The content ``tapp simulate --json`` writes, JSON-ready: the tape's dimensions,
        stations, warnings, reference fit, integration events, miss and retargeting.

        ``tape``, ``oem``, ``tdm``, ``spk`` name the files written (None: not written);
        ``bytes`` (the tape file's size) is None here and filled in by whoever writes it.
        ``raw`` says whether the tape holds the raw rows.
        """
        t13 = self.tape
        sim = self.simulation
        miss = t13.miss
        record = t13.provenance.get("targeting")
        return {"tape": tape, "bytes": None, "iden": t13.iden,
                "n_o": t13.n_o, "n_p": t13.n_p, "n_m": t13.n_m, "n_ts": t13.n_ts,
                "n_it": t13.n_it, "pairs": int(t13.pairs.k.size),
                "passes": int(t13.passes.station.size),
                "observations": int(t13.pairs.n_obs.sum()),
                "stations": summary(t13)["stations"], "raw": t13.raw is not None,
                "oem": oem, "tdm": tdm, "spk": spk,
                "wall_s": self.wall_s, "warnings": list(sim.warnings),
                "reference": (None if sim.reference_fit is None
                              else sim.reference_fit.to_json(t13.epoch)),
                "events": [{"t_s": float(t), "utc": t13.epoch.iso_after(float(t), 6),
                            "event": label}
                           for t, label in zip(sim.events.t_s, sim.events.labels(),
                                               strict=True)],
                "miss": {"kind": miss.kind, "t_s": miss.t_s,
                         "utc": t13.epoch.iso_after(miss.t_s, 3), "names": list(miss.name),
                         "nominal": miss.nominal.tolist()},
                "targeting": json.loads(record) if record else None}


def simulate(scenario: Scenario | Path | str, *, raw: bool = False,
             progress: ProgressCallback | None = None, accept_poor_fit: bool = False,
             earth_orientation: str | None = None) -> SimulateResult:
    """Run TAPP I on a scenario or a scenario file; return the tape and what was flown.

    Parameters
    ----------
    scenario : a parsed scenario, or its TOML file (read by
        :func:`tapp.tracking.scenario_build.read_scenario`, ``earth_orientation`` overriding the
        file's model; ignored for a parsed scenario).
    raw : keep every observation's partial row, weight and noise (``tape.raw``).
    progress : called with (stage, step, total) as the work advances.
    accept_poor_fit : fly a ``[reference]`` fit worse than its ``max_fit_error_m``.

    Raises
    ------
    InputError
        A bad scenario file or field (naming both), as ``tapp simulate`` reports it.
    tapp.tracking.encounter.TargetingError
        SEARCH did not reach the ``[targeting]`` aim point (its status says how).
    """
    if not isinstance(scenario, Scenario):
        scenario = read_scenario(scenario, earth_orientation)
    start = time.perf_counter()
    sim = run_simulation(scenario, raw=raw, progress=progress, accept_poor_fit=accept_poor_fit)
    return SimulateResult(sim, time.perf_counter() - start)
