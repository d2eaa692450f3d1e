"""A user's IERS EOP file, read within bounds, and the ``eop`` key of the scenario files.

The ``eop`` key (``tapp.io.schema.EopSource``) of a tracking scenario, a SEARCH file and the
study file names the Earth orientation parameters of the iau2006 model: "iers" (the table
shipped in astropy-iers-data, :func:`tapp.frames.iers.shipped_finals2000a`), "none" (UT1 = UTC,
no polar motion or CIP offsets: :meth:`tapp.frames.eop.EopTable.zero`) or the path of an IERS
``finals2000A`` file, opened here as a regular file of at most :data:`MAX_EOP_BYTES`
(:mod:`iter.inputfile`) and parsed and checked by :func:`tapp.frames.iers.parse_finals2000a`.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from iter.inputfile import read_bytes
from tapp.errors import InputError
from tapp.frames.eop import EopTable
from tapp.frames.iers import parse_finals2000a, shipped_finals2000a
from tapp.frames.orientation import EarthOrientation, check_model
from tapp.frames.time import Epoch

#: Largest EOP file read, bytes: finals2000A.all is 3.8 MB (1973-2026) and grows by ~68 kB a
#: year; the 51,135 daily rows that :data:`tapp.frames.iers.MJD_RANGE` allows take 9.6 MB in
#: this format. Measured: the shipped file reads in 0.5 s, 51,135 rows in 0.4 s with 23 MB
#: (2 shared cores).
MAX_EOP_BYTES = 16 * 2**20


@cache
def finals2000a(path: Path | None = None) -> EopTable:
    """Read an IERS ``finals2000A`` file (default: ``finals2000A.all`` of astropy-iers-data).

    Rows without UT1 − UTC or a pole (the empty tail of the file) are dropped; a missing
    dX, dY (old rows, far predictions) is taken as 0. The file is checked as
    :mod:`tapp.frames.iers` says (the gaps when an arc uses the table:
    :meth:`~tapp.frames.eop.EopTable.check_covers`).

    Raises
    ------
    InputError
        Naming the file (and the line and field): not a regular file, larger than
        :data:`MAX_EOP_BYTES`, a field that is not a finite number, dates out of order or
        range, values beyond their bounds, or no usable row.
    """
    if not path:
        return shipped_finals2000a()
    path = Path(path)
    return parse_finals2000a(read_bytes(path, "IERS finals2000A file", max_bytes=MAX_EOP_BYTES,
                                        error=InputError), str(path))


def orientation_for(model: str, epoch: Epoch, eop: str = "iers", base_dir: Path | None = None,
                    source: str = "scenario") -> EarthOrientation:
    """Build a scenario's Earth orientation from its ``earth_orientation`` and ``eop`` keys.

    ``eop``: "iers" (the IERS table shipped in astropy-iers-data), "none" (UT1 = UTC, no polar
    motion or CIP offsets: a study beyond the predictions) or the path of an IERS
    ``finals2000A`` file, relative to ``base_dir``. The gmst model uses no EOP.

    Raises
    ------
    InputError
        Naming ``source``: an unknown model, an unreadable EOP file, an epoch outside the table.
    """
    table = None
    if check_model(model, source) == "iau2006" and eop == "none":
        table = EopTable.zero()
    elif model == "iau2006" and eop != "iers":
        path = Path(eop)
        table = finals2000a((base_dir / path) if base_dir and not path.is_absolute() else path)
    return EarthOrientation.of(model, epoch, table, source)
