"""``tapp info``: versions of tapp and its numerical stack, and the bundled data coverage."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from rich.console import Console
from rich.table import Table

from tapp import __version__
from tapp.cli.common import app
from tapp.constants import MAX_DEGREE
from tapp.dynamics.compiled import cache_dir
from tapp.ephemeris import LEAP_SECONDS, de421_path

_PACKAGES = ("numpy", "scipy", "casadi", "h5py", "filterpy", "jplephem", "skyfield-data",
             "dask", "typer")


@app.command()
def info() -> None:
    """Print versions and the time span of each bundled data table."""
    console = Console(width=110)
    versions = Table(title="versions")
    versions.add_column("package")
    versions.add_column("version")
    versions.add_row("tapp", __version__)
    for name in _PACKAGES:
        try:
            versions.add_row(name, version(name))
        except PackageNotFoundError:
            versions.add_row(name, "not installed")
    console.print(versions)
    data = Table(title="bundled data")
    data.add_column("table")
    data.add_column("coverage")
    data.add_column("source")
    data.add_row("DE421 ephemeris", "1899-07-29 .. 2053-10-09", str(de421_path()))
    data.add_row("EGM96 field", f"degree/order 2..{MAX_DEGREE}",
                 "NASA/TP-1998-206861 (tapp/data/egm96_deg8.txt)")
    data.add_row("TAI-UTC", f"1972-01-01 .. (last step JD {LEAP_SECONDS[-1][0]}: "
                 f"{LEAP_SECONDS[-1][1]} s)", "IERS Bulletin C")
    data.add_row("compiled propagators", "cache", str(cache_dir()))
    console.print(data)
