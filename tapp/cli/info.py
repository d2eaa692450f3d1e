"""``tapp info``: versions of tapp and its numerical stack, and the bundled data coverage."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from rich.console import Console
from rich.table import Table

from tapp import __version__
from tapp.cli.common import app
from tapp.constants import MAX_DEGREE
from tapp.dynamics.compiled import cache_dir
from tapp.ephemeris import de421_path
from tapp.frames.eop import MJD_OFFSET, finals2000a, iers_data_dir, leap_seconds
from tapp.frames.time import Epoch

_PACKAGES = ("numpy", "scipy", "casadi", "h5py", "filterpy", "jplephem", "skyfield-data",
             "pyerfa", "astropy-iers-data", "dask", "typer")


def _date(mjd: float) -> str:
    return Epoch(MJD_OFFSET + mjd // 1, mjd % 1).iso(0)[:10]


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
    leaps = leap_seconds()
    data.add_row("TAI-UTC", f"1972-01-01 .. (last step {_date(leaps.start_mjd[-1])}: "
                 f"{leaps.tai_minus_utc_s[-1]:g} s; expires {leaps.expires})",
                 str(iers_data_dir() / "Leap_Second.dat"))
    eop = finals2000a()
    data.add_row("IERS EOP (UT1-UTC, pole, dX/dY)", f"{_date(eop.mjd[0])} .. {_date(eop.mjd[-1])}"
                 f" (predicted from {_date(eop.predicted_from_mjd)})", eop.source)
    data.add_row("compiled propagators", "cache", str(cache_dir()))
    console.print(data)
