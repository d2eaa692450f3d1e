"""What a TAPP III run puts on the T32 tape (:mod:`tapp.io.tape.t32`) for TAPP II.

The seed writes the recycle commands' outputs (Table B-5, "always ... under valid TAPP II
assumptions: the fit-world constraints subtracted out of the consider parameters", §1); the
tape here carries those entities and, per recycle, the current statistics and transitions in
the representation of the recycle time, the system chains and the names of every partition.
"""

from __future__ import annotations

from tapp.io.tape.t13 import T13Header
from tapp.io.tape.t32 import T32, T32Partition
from tapp.processor.deck import deck_json
from tapp.processor.plan import Plan
from tapp.processor.representations import ISOLATED_SETS, SYSTEM_PARTITIONS, SYSTEMS
from tapp.processor.sequencing import Run

_SYSTEM = {1: "standard", 3: "common", 4: "fit", 6: "real"}


def _partitions(plan: Plan, miss_names: tuple[str, ...]) -> tuple[T32Partition, ...]:
    sy = plan.systems
    out = []
    for rho, (chi, _, _) in SYSTEM_PARTITIONS.items():
        _, t, h = sy.bounds(rho)
        names = sy.system_names(chi)
        out.append(T32Partition(rho, _SYSTEM[chi], t, h, tuple(names[t:h])))
    for rho in ("m", *sorted(sy.miss_partitions)):
        _, t, h = sy.bounds(rho)
        out.append(T32Partition(rho, "miss", t, h, tuple(miss_names[t:h])))
    return tuple(out)


def build_t32(run: Run, plan: Plan, header: T13Header, provenance: dict[str, str]) -> T32:
    """Return the T32 tape of a run (module docstring)."""
    sy = plan.systems
    miss_names = tuple(header.miss.name)
    return T32(header.iden, header.epoch, sy.n_p, header.parameters, miss_names,
               tuple(header.miss.unit),
               {SYSTEMS[c]: sy.chain_matrix(c) for c in (3, 4, 6)},
               {SYSTEMS[c]: tuple(sy.system_names(c)) for c in (3, 4, 6)},
               _partitions(plan, miss_names), run.S0_fit_factor, run.Lambda0_real_factor,
               run.recycles,
               provenance)


def t32_provenance(header: T13Header, deck, deck_source: str, t13_source: str) -> dict[str, str]:
    """The provenance a T32 tape carries: the deck (JSON) and its file, the T13 tape's file
    and identification, and the T13's Earth orientation model and EOP source."""
    return {"deck": deck_json(deck), "deck_source": deck_source, "t13_source": t13_source,
            "t13_iden": header.iden,
            **{f"t13_{key}": header.provenance[key] for key in ("earth_orientation", "eop")
               if key in header.provenance}}


__all__ = ["ISOLATED_SETS", "build_t32", "t32_provenance"]
