"""``tapp tape info``: the summary of any tape (T13 or T32).

An unreadable or corrupt tape is one line on stderr naming the file and the dataset, exit
code 2 (see :mod:`tapp.cli.common`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from tapp.cli.common import Group, JsonOpt, app, delivering, json_file, run_guarded

if TYPE_CHECKING:
    from rich.table import Table

tape_app = typer.Typer(name="tape", cls=Group, help="Inspect tapes (T13, T32).",
                       no_args_is_help=True, add_completion=False)
app.add_typer(tape_app, name="tape")


def editing_table(stations: list[dict]) -> Table:
    """Per station: observations scheduled, kept, removed by each rule (passes removed whole
    in parentheses), passes and those added by splitting at max_pass_s (T13 ``editing/``)."""
    from rich.table import Table

    rules = list(stations[0]["removed"])
    table = Table(title="Observations: scheduled = kept + removed by each rule (passes removed "
                        "whole)")
    for col in ("s", "name", "scheduled", "kept", *(r.replace("_", " ") for r in rules),
                "passes (+ split)"):
        table.add_column(col, justify="right")
    for s in stations:
        removed = [f"{r['observations']}" + (f" ({r['passes']})" if r["passes"] else "")
                   for r in s["removed"].values()]
        table.add_row(str(s["id"]), s["name"], str(s["scheduled_observations"]),
                      str(s["observations"]), *removed,
                      f"{s['passes']} (+{s['passes_added_by_split']})")
    return table


def _print_t13(info: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(width=110)
    dims = info["dimensions"]
    console.print(f"[bold]T13[/bold] v{info['version']}  iden {info['iden']}  epoch "
                  f"{info['epoch_utc']} UTC  span {info['span_s'][1]:.0f} s")
    console.print("  ".join(f"{k} = {v}" for k, v in dims.items() if v is not None))
    table = Table(title="Parameters x = \\[p; q]")
    for col in ("#", "name", "unit", "kind"):
        table.add_column(col)
    for i, p in enumerate(info["parameters"], start=1):
        table.add_row(str(i), p["name"], p["unit"], p["kind"])
    console.print(table)
    table = Table(title="Stations")
    for col in ("s", "name", "observables", "lat (deg)", "lon (deg)", "h (km)", "passes",
                "observations"):
        table.add_column(col, justify="right")
    for s in info["stations"]:
        table.add_row(str(s["id"]), s["name"], s["observables"], f"{s['lat_deg']:.4f}",
                      f"{s['lon_deg']:.4f}", f"{s['h_km']:.3f}", str(s["passes"]),
                      str(s["observations"]))
    console.print(table)
    if "removed" in info["stations"][0]:  # tapes written before the counts have none
        console.print(editing_table(info["stations"]))
    table = Table(title="Epoch times")
    for col in ("index", "t (s)", "UTC"):
        table.add_column(col, justify="right")
    for e in info["epochs"]:
        table.add_row(str(e["index"]), f"{e['t_s']:.3f}", e["utc"])
    console.print(table)
    miss = info["miss"]
    console.print(f"miss ({miss['kind']}, t = {miss['t_s']:.3f} s): " + ", ".join(
        f"{n} = {v:.6g}" for n, v in zip(miss["names"], miss["nominal"], strict=True)))
    prov = info["provenance"]
    console.print(f"{info['observations']} observations, {info['input_times']} input times; "
                  f"written by tapp {prov.get('tapp_version', '?')} on "
                  f"{prov.get('created_utc', '?')} from {prov.get('scenario_source', '?')}; "
                  f"Earth orientation {prov.get('earth_orientation', 'gmst (not recorded)')}"
                  + (f", EOP {prov['eop']}" if prov.get("eop") else ""))
    if prov.get("targeting"):
        record = json.loads(prov["targeting"])
        console.print(f"injection retargeted by SEARCH ({record['status']} in {record['cases']} "
                      "cases) to " + ", ".join(f"{n} = {v:g}" for n, v in record["aim"].items()))


def _print_info(info: dict) -> None:
    """The summary of a tape, its format's (:func:`tapp.io.tape.files.describe`)."""
    from rich.console import Console

    from tapp.io.tape.t32 import format_t32_summary

    if info["format"] == "T13":
        _print_t13(info)
    elif info["format"] == "T32":
        typer.echo(format_t32_summary(info))
    else:
        console = Console(width=110)
        console.print(f"format {info['format']}: "
                      + ", ".join(f"{k} = {v}" for k, v in info["attributes"].items()))
        for name, d in info["datasets"].items():
            console.print(f"  {name}  {tuple(d['shape'])}  {d['dtype']}")


@tape_app.command("info")
def tape_info(
    path: Annotated[Path, typer.Argument(help="Tape file (HDF5).")],
    json_out: JsonOpt = None,
) -> None:
    """Summarise a tape: dimensions, parameters, stations, passes, observations, epochs."""

    def body() -> None:
        from tapp.io.outputs import check_paths
        from tapp.io.tape.files import describe

        check_paths({"PATH": path}, {"--json": json_file(json_out)})
        info = describe(path)
        with delivering(json_out, info) as report:
            if report:
                _print_info(info)

    run_guarded(body)
