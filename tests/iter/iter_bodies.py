"""Bodies for the iter tests; imported as ``iter_bodies`` with this folder put on sys.path.

Each call is logged, one line per call, in ``<calls_dir>/calls.txt`` so a test can check
which cases a run did (and did not) call.
"""

from __future__ import annotations

from pathlib import Path

from iter import SweepInputError, input_check

#: Azimuth at which :func:`counting_body` fails while the flag file exists, deg.
FAILING_AZIMUTH_deg = 102.0
#: Azimuth at which :func:`interrupting_body` raises KeyboardInterrupt, deg.
INTERRUPT_AZIMUTH_deg = 105.0


def calls(calls_dir: str | Path) -> list[float]:
    """Return the azimuths the bodies were called with, in call order, deg."""
    log = Path(calls_dir) / "calls.txt"
    if not log.exists():
        return []
    return [float(line) for line in log.read_text().split()]


def _log(calls_dir: str, azimuth_deg: float) -> None:
    with (Path(calls_dir) / "calls.txt").open("a") as stream:
        stream.write(f"{azimuth_deg!r}\n")


def counting_body(azimuth_deg: float, calls_dir: str) -> dict[str, float]:
    """Return twice the azimuth; raise at 102 deg while ``<calls_dir>/fail`` exists."""
    _log(calls_dir, azimuth_deg)
    if azimuth_deg == FAILING_AZIMUTH_deg and (Path(calls_dir) / "fail").exists():
        raise ValueError(f"cannot fly at {azimuth_deg} deg")
    return {"double_deg": 2.0 * azimuth_deg}


def interrupting_body(azimuth_deg: float, calls_dir: str) -> dict[str, float]:
    """Like counting_body, but Ctrl-C at 105 deg while ``<calls_dir>/interrupt`` exists."""
    if azimuth_deg == INTERRUPT_AZIMUTH_deg and (Path(calls_dir) / "interrupt").exists():
        raise KeyboardInterrupt
    _log(calls_dir, azimuth_deg)
    return {"double_deg": 2.0 * azimuth_deg}


def not_a_mapping(azimuth_deg: float) -> list[float]:
    """Return a list, which is not a valid set of outputs."""
    return [azimuth_deg]


def hanging_body(azimuth_deg: float, hang_at_deg: float) -> dict[str, float]:
    """Return twice the azimuth; never return at ``hang_at_deg`` (makes a temporary folder,
    as a real program would, then sleeps an hour)."""
    if azimuth_deg == hang_at_deg:
        import tempfile
        import time

        tempfile.mkdtemp(prefix="hanging-")
        time.sleep(3600.0)
    print("printed by the body, not an output")
    return {"double_deg": 2.0 * azimuth_deg}


def raising_body(azimuth_deg: float) -> dict[str, float]:
    """Raise ValueError for every case."""
    raise ValueError(f"cannot fly at {azimuth_deg} deg")


def read_scale(scale_file: str, **_: object) -> float:
    """Return the number written in ``scale_file``: the input check of :func:`scaled_body`.

    Raises
    ------
    SweepInputError
        Naming the file: its text is not a number.
    """
    text = Path(scale_file).read_text().strip()
    try:
        return float(text)
    except ValueError:
        raise SweepInputError(scale_file, "file", "a number", text) from None


@input_check(read_scale)
def scaled_body(azimuth_deg: float, scale_file: str, calls_dir: str) -> dict[str, float]:
    """Return the azimuth times the number in ``scale_file`` (a file the body reads)."""
    _log(calls_dir, azimuth_deg)
    return {"scaled_deg": read_scale(scale_file) * azimuth_deg}


def keywords_body(**values: float) -> dict[str, float]:
    """Return the sum of whatever keyword arguments it is given."""
    return {"total": sum(values.values())}


def process_facts(azimuth_deg: float) -> dict[str, object]:
    """The process a case ran in: its id, its BLAS threads (NumPy's libraries loaded) and
    its ``MALLOC_TRIM_THRESHOLD_`` ("" when unset)."""
    import os

    import numpy  # noqa: F401  (threadpoolctl sees only the BLAS libraries loaded)
    from threadpoolctl import threadpool_info

    return {"pid": os.getpid(),
            "blas_threads": max(lib["num_threads"] for lib in threadpool_info()
                                if lib["user_api"] == "blas"),
            "malloc_trim": os.environ.get("MALLOC_TRIM_THRESHOLD_", "")}
