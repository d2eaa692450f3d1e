"""Covariances of ground-station positions: a CSV table, a SINEX excerpt, or a deck's table.

The TAPP III deck's ``[fit.apriori.stations]`` and ``[real.apriori.stations]``
(:mod:`tapp.processor.deck`) give the a priori of station locations as full 3 x 3 blocks, from
a file (``file = "..."``, relative to the deck) or inline. Either way a station's covariance is
given in one of two sets of axes, in metres:

- ``"ecef"``: the Earth-fixed (ITRF) Cartesian x, y, z;
- ``"cylindrical"``: the local cylindrical axes of the station, (spin radius r_s, east arc
  r_s λ along the parallel, z along the spin axis), the DSN's "spin radius, longitude,
  z-height" set with the longitude as the metres it moves the station.

CSV (``.csv``), one row per station, the columns::

    station,axes,sigma1_m,sigma2_m,sigma3_m,rho12,rho13,rho23
    DSS-14,ecef,0.030,0.030,0.040,0.10,0.00,0.20

the σ's along the three axes (in the order above) and their correlations; ``#`` starts a
comment line. Stations of a CSV file are independent of one another (a common-frame error is
the deck's ``frame`` table).

SINEX (``.snx`` or ``.sinex``; IERS SINEX 2.02, blocks ``SOLUTION/ESTIMATE`` and
``SOLUTION/MATRIX_ESTIMATE {L|U} COVA``): the STAX, STAY, STAZ estimates (m) of each site code,
with the whole covariance between them, cross-station terms included: the axes are "ecef",
the stations are the site codes (4 characters). Other parameter types in the blocks are
skipped; a site without all three of STAX, STAY, STAZ, a matrix of another kind (CORR, INFO)
or an index the estimates do not define is refused.

Every matrix is checked as it is read (:func:`check_covariance`): symmetric, positive
semi-definite, each station's σ's within :data:`MAX_SIGMA_m`; errors name the file (or the
deck's table) and the station.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from iter.inputfile import read_text
from tapp.errors import InputError
from tapp.estimation.factors import scaled_min_eigenvalue
from tapp.io.tape.packing import symmetry_defect
from tapp.io.text import finite_number

#: The axes a station's covariance may be given in (module docstring).
AXES = ("ecef", "cylindrical")
#: Largest σ of a station coordinate, m. The a priori is mapped to the tape's parameters to
#: first order at the nominal location (:mod:`tapp.processor.station_apriori`): at 1 km the
#: neglected second-order terms are ~σ²/r_s ~ 0.2 m of a 5,000 km spin radius (1e-4 of σ); a
#: ground station known worse than that is not a station of a tracking network.
MAX_SIGMA_m = 1000.0
#: Largest relative asymmetry |c_ij − c_ji| / √(c_ii c_jj) taken as rounding (a SINEX matrix
#: is given as one triangle: this bites only on inline 3 x 3 matrices).
SYMMETRY_TOL = 1e-12
#: Largest negative eigenvalue of the covariance scaled to a unit diagonal taken as rounding
#: (:func:`tapp.estimation.factors.scaled_min_eigenvalue`; a SINEX file's 15-digit values
#: keep their correlations to ~1e-14).
PSD_TOL = 1e-10
#: Largest file read, bytes (a full SINEX solution of an ITRF realisation is ~100 MB: a deck
#: wants an excerpt of a few stations).
MAX_FILE_BYTES = 10_000_000
_CSV_COLUMNS = ("station", "axes", "sigma1_m", "sigma2_m", "sigma3_m", "rho12", "rho13",
                "rho23")
_SINEX_TYPES = ("STAX", "STAY", "STAZ")


@dataclass(frozen=True, slots=True, eq=False)
class StationCovariance:
    """Covariance of the positions of N stations, each in its own axes (:data:`AXES`).

    Attributes
    ----------
    source : where it was read (a file, or a deck's table), named in errors.
    stations : the N station names (SINEX: site codes).
    axes : the axes of each station's three coordinates.
    covariance_m2 : (3N, 3N), station-major (station i's coordinates at rows 3i..3i+2), m².
    """

    source: str
    stations: tuple[str, ...]
    axes: tuple[str, ...]
    covariance_m2: np.ndarray


def block_m2(sigma_m, rho) -> np.ndarray:
    """Return the 3 x 3 covariance (m²) of σ's (3,) along three axes and their correlations
    (ρ12, ρ13, ρ23): C_ij = ρ_ij σ_i σ_j, ρ_ii = 1."""
    r12, r13, r23 = (float(r) for r in rho)
    corr = np.array([[1.0, r12, r13], [r12, 1.0, r23], [r13, r23, 1.0]])
    sigma = np.asarray(sigma_m, dtype=float)
    return corr * np.outer(sigma, sigma)


def check_covariance(c: StationCovariance, field: str) -> None:
    """Refuse a covariance that no station network has: non-finite, a σ out of
    0..:data:`MAX_SIGMA_m`, asymmetric, or not positive semi-definite (each station's block
    first, so that the error names the station; then the whole, for cross-station terms).

    Raises
    ------
    InputError
        Naming ``c.source``, ``field`` and the station.
    """
    m = c.covariance_m2
    for i, name in enumerate(c.stations):
        at = f"{field}.{name}"
        block = m[3 * i:3 * i + 3, 3 * i:3 * i + 3]
        if not np.all(np.isfinite(block)):
            raise InputError(c.source, at, "finite covariances", block.tolist())
        diag = np.diagonal(block)
        if np.any(diag < 0) or np.any(diag > MAX_SIGMA_m**2):
            raise InputError(c.source, at, f"σ's between 0 and {MAX_SIGMA_m:g} m",
                             np.sqrt(np.abs(diag)).tolist())
        defect = float(symmetry_defect(block))
        if defect > SYMMETRY_TOL:
            raise InputError(c.source, at, f"a symmetric covariance (|c_ij − c_ji| <= "
                             f"{SYMMETRY_TOL:g} √(c_ii c_jj))", f"{defect:.3g} √(c_ii c_jj)")
        smallest = scaled_min_eigenvalue(0.5 * (block + block.T))
        if smallest < -PSD_TOL:
            raise InputError(c.source, at, "a positive semi-definite covariance (|ρ| <= 1 and "
                             "a realisable set of correlations)", f"smallest eigenvalue "
                             f"{smallest:.3g} of its correlation matrix")
    if not np.all(np.isfinite(m)):
        raise InputError(c.source, field, "finite covariances between the stations")
    defect = float(symmetry_defect(m))
    smallest = scaled_min_eigenvalue(0.5 * (m + m.T))
    if defect > SYMMETRY_TOL or smallest < -PSD_TOL:
        raise InputError(c.source, field, "a symmetric positive semi-definite covariance of "
                         "the stations together (" + ", ".join(c.stations) + ")",
                         f"asymmetry {defect:.3g}, smallest eigenvalue {smallest:.3g} of the "
                         "correlation matrix")


def _index(text: str, source: str, field: str) -> int:
    if not text.isdigit():
        raise InputError(source, field, "a parameter index (a positive integer)", text)
    return int(text)


def parse_csv(text: str, source: str) -> StationCovariance:
    """Parse the CSV form (module docstring); stations are independent of one another."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    rows = list(csv.reader(lines))
    if not rows or tuple(c.strip() for c in rows[0]) != _CSV_COLUMNS:
        raise InputError(source, "header", "the columns " + ",".join(_CSV_COLUMNS),
                         ",".join(rows[0]) if rows else "an empty file")
    names, axes, blocks = [], [], []
    for n, row in enumerate(rows[1:], start=2):
        if len(row) != len(_CSV_COLUMNS):
            raise InputError(source, f"row {n}", f"{len(_CSV_COLUMNS)} columns", len(row))
        name, ax = row[0].strip(), row[1].strip()
        if not name or name in names:
            raise InputError(source, f"row {n}.station", "a station name, each once", name)
        if ax not in AXES:
            raise InputError(source, f"row {n}.axes", " or ".join(map(repr, AXES)), ax)
        values = [finite_number(v, source, f"row {n}.{col}")
                  for v, col in zip(row[2:], _CSV_COLUMNS[2:], strict=True)]
        if any(v < 0 for v in values[:3]):
            raise InputError(source, f"{name}.sigma", "σ's >= 0, m", values[:3])
        if any(not -1.0 <= r <= 1.0 for r in values[3:]):
            raise InputError(source, f"{name}.rho", "correlations within -1..1", values[3:])
        names.append(name)
        axes.append(ax)
        blocks.append(block_m2(values[:3], values[3:]))
    if not names:
        raise InputError(source, "rows", "at least one station after the header", "none")
    cov = np.zeros((3 * len(names), 3 * len(names)))
    for i, b in enumerate(blocks):
        cov[3 * i:3 * i + 3, 3 * i:3 * i + 3] = b
    out = StationCovariance(source, tuple(names), tuple(axes), cov)
    check_covariance(out, "station")
    return out


def _sinex_blocks(text: str, source: str) -> dict[str, tuple[str, list[str]]]:
    """The data lines of each ``+NAME ... -NAME`` block of a SINEX file, with the rest of
    the ``+NAME`` line (the matrix's triangle and kind)."""
    out, current = {}, None
    for line in text.splitlines():
        if line.startswith("+"):
            words = line[1:].split()
            if not words:
                raise InputError(source, "block", "a block name after '+'", line)
            current = words[0]
            out[current] = (" ".join(words[1:]), [])
        elif line.startswith("-"):
            current = None
        elif current is not None and line.strip() and not line.startswith("*"):
            out[current][1].append(line)
    return out


def parse_sinex(text: str, source: str) -> StationCovariance:
    """Parse the STAX, STAY, STAZ covariance of a SINEX excerpt (module docstring).

    SOLUTION/ESTIMATE lines: index, type, site code, point, solution, epoch, unit, constraint,
    value, σ (whitespace-separated); SOLUTION/MATRIX_ESTIMATE lines: row, first column, up to
    three values of that row (the triangle the block's header names).
    """
    blocks = _sinex_blocks(text, source)
    for name in ("SOLUTION/ESTIMATE", "SOLUTION/MATRIX_ESTIMATE"):
        if name not in blocks:
            raise InputError(source, name, "the block (a SINEX file with the covariance of "
                             "STAX, STAY, STAZ)", "none")
    index: dict[int, tuple[str, int]] = {}  # SINEX index -> (site, axis)
    sites: list[str] = []
    for line in blocks["SOLUTION/ESTIMATE"][1]:
        words = line.split()
        if len(words) < 10:
            raise InputError(source, "SOLUTION/ESTIMATE", "lines of 10 fields (index type code "
                             "pt soln epoch unit S value σ)", line.strip())
        if words[1] not in _SINEX_TYPES:
            continue
        if words[6] != "m":
            raise InputError(source, f"SOLUTION/ESTIMATE.{words[2]}.{words[1]}", "unit m",
                             words[6])
        if words[2] not in sites:
            sites.append(words[2])
        at = _index(words[0], source, "SOLUTION/ESTIMATE")
        index[at] = (words[2], _SINEX_TYPES.index(words[1]))
    if not sites:
        raise InputError(source, "SOLUTION/ESTIMATE", "STAX, STAY, STAZ estimates", "none")
    where = {v: k for k, v in index.items()}
    for site in sites:
        missing = [t for a, t in enumerate(_SINEX_TYPES) if (site, a) not in where]
        if missing:
            raise InputError(source, f"SOLUTION/ESTIMATE.{site}", "STAX, STAY and STAZ",
                             f"no {', '.join(missing)}")
    kind = blocks["SOLUTION/MATRIX_ESTIMATE"][0].split()
    if len(kind) != 2 or kind[0] not in ("L", "U") or kind[1] != "COVA":
        raise InputError(source, "SOLUTION/MATRIX_ESTIMATE", "a covariance matrix (L COVA or "
                         "U COVA)", " ".join(kind))
    position = {k: 3 * sites.index(s) + a for k, (s, a) in index.items()}
    cov = np.zeros((3 * len(sites), 3 * len(sites)))
    for line in blocks["SOLUTION/MATRIX_ESTIMATE"][1]:
        words = line.split()
        if not 3 <= len(words) <= 5:
            raise InputError(source, "SOLUTION/MATRIX_ESTIMATE", "lines of a row, a first "
                             "column and 1 to 3 values", line.strip())
        row, col = (_index(w, source, "SOLUTION/MATRIX_ESTIMATE") for w in words[:2])
        for j, value in enumerate(words[2:]):
            pair = (row, col + j)
            if row not in position or col + j not in position:
                continue  # a parameter that is not a station coordinate
            if (kind[0] == "L") != (pair[1] <= pair[0]):
                raise InputError(source, "SOLUTION/MATRIX_ESTIMATE", f"the {kind[0]} triangle",
                                 f"element {pair}")
            a, b = position[row], position[col + j]
            cov[a, b] = cov[b, a] = finite_number(value, source, f"SOLUTION/MATRIX_ESTIMATE{pair}")
    out = StationCovariance(source, tuple(sites), ("ecef",) * len(sites), cov)
    check_covariance(out, "SOLUTION/MATRIX_ESTIMATE")
    return out


def read_station_covariance(path: Path | str) -> StationCovariance:
    """Read a station covariance file: CSV (``.csv``) or SINEX (``.snx``, ``.sinex``)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".snx", ".sinex"):
        raise InputError(str(path), "file", "a .csv or a SINEX (.snx, .sinex) file", suffix)
    text = read_text(path, "station covariance file", max_bytes=MAX_FILE_BYTES,
                     error=InputError)
    return parse_csv(text, str(path)) if suffix == ".csv" else parse_sinex(text, str(path))


__all__ = ["AXES", "MAX_SIGMA_m", "StationCovariance", "block_m2", "check_covariance",
           "parse_csv", "parse_sinex", "read_station_covariance"]
