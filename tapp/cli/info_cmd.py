"""``tapp info``: versions of tapp and its numerical stack, and the bundled data coverage."""

from __future__ import annotations

from tapp.cli.common import JsonOpt, app, delivering, json_file, run_guarded

_PACKAGES = ("numpy", "scipy", "casadi", "h5py", "filterpy", "jplephem", "skyfield-data",
             "pyerfa", "astropy-iers-data", "dask", "typer")


def _date(mjd: float) -> str:
    from tapp.frames.eop import MJD_OFFSET
    from tapp.frames.time import Epoch

    return Epoch(MJD_OFFSET + mjd // 1, mjd % 1).iso(0)[:10]


@app.command()
def info(json_out: JsonOpt = None) -> None:
    """Print versions and the time span of each bundled data table."""

    def body() -> None:
        from importlib.metadata import PackageNotFoundError, version

        from rich.console import Console
        from rich.table import Table

        from tapp import __version__
        from tapp.constants import MAX_DEGREE
        from tapp.dynamics.compiled import cache_dir
        from tapp.dynamics.ephemeris import de421_path
        from tapp.frames.iers import iers_data_dir, leap_seconds
        from tapp.io.eop_file import finals2000a
        from tapp.io.outputs import check_paths

        check_paths({}, {"--json": json_file(json_out)})
        versions = {"tapp": __version__}
        for name in _PACKAGES:
            try:
                versions[name] = version(name)
            except PackageNotFoundError:
                versions[name] = "not installed"
        leaps = leap_seconds()
        eop = finals2000a()
        data = [
            ("DE421 ephemeris", "1899-07-29 .. 2053-10-09", str(de421_path())),
            ("EGM96 field", f"degree/order 2..{MAX_DEGREE}",
             "NASA/TP-1998-206861 (tapp/data/egm96_deg8.txt)"),
            ("TAI-UTC", f"1972-01-01 .. (last step {_date(leaps.start_mjd[-1])}: "
             f"{leaps.tai_minus_utc_s[-1]:g} s; expires {leaps.expires})",
             str(iers_data_dir() / "Leap_Second.dat")),
            ("IERS EOP (UT1-UTC, pole, dX/dY)", f"{_date(eop.mjd[0])} .. "
             f"{_date(eop.mjd[-1])} (predicted from {_date(eop.predicted_from_mjd)})",
             eop.source),
            ("compiled propagators", "cache", str(cache_dir()))]
        with delivering(json_out, {"versions": versions, "data": [
                {"table": t, "coverage": c, "source": s} for t, c, s in data]}) as report:
            if report:
                console = Console(width=110)
                table = Table(title="versions")
                table.add_column("package")
                table.add_column("version")
                for name, value in versions.items():
                    table.add_row(name, value)
                console.print(table)
                table = Table(title="bundled data")
                for col in ("table", "coverage", "source"):
                    table.add_column(col)
                for row in data:
                    table.add_row(*row)
                console.print(table)

    run_guarded(body)
