"""Initial orbits from text: element lists, Cartesian lists, or names in a scenario file.

Grammar of an orbit spec (the ``--orbit`` option):

- ``a=6550.524,e=0,i=30,raan=0,argp=0,M=0``: classical elements, a in km, angles in degrees
  (M is the mean anomaly; ``nu=`` may replace it with the true anomaly);
- ``x=..,y=..,z=..,vx=..,vy=..,vz=..``: Cartesian position (km) and velocity (km/s);
- ``NAME``: an orbit of the ``[orbits.NAME]`` tables of a study file (by default the shipped
  :data:`tapp.examples.STUDY_FILE`), whose keys are those of every orbit table
  (:class:`OrbitTable`, also a scenario's ``[injection]``): ``r_km = [x, y, z]`` and
  ``v_km_s = [vx, vy, vz]``, or ``a_km, e, i_deg, raan_deg, argp_deg`` and ``M_deg`` (or
  ``nu_deg``), and optionally ``allow_subsurface = true``.

All states are EME2000 inertial, centred on the Earth, with the EGM96 GM; a scenario whose
``[model] center`` is another body gives its ``[injection]`` relative to that body, its
elements with that body's GM (``center`` of :meth:`OrbitTable.state`). An ``[injection]`` may
name its own ``center`` (an Earth departure of a Sun-centred cruise given about the Earth):
its state is about that body and is translated to the integration's centre by DE421 at t = 0.

An orbit that would pass below the Earth's surface is refused (:func:`check_perigee`): its
perigee radius is below the equatorial radius ``R_EARTH_km`` and it reaches that perigee (an
ellipse always does; a hyperbola or parabola only while inbound), or it starts below the
surface (about another centre, below its equatorial radius, ``RADIUS_km``).
``allow_subsurface = true`` in the orbit's table, or ``--allow-subsurface`` on the command
line, says the user means it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from tapp.constants import GM_EARTH_km3_s2, GM_km3_s2, RADIUS_km
from tapp.dynamics.ephemeris import BODIES, relative_state
from tapp.errors import InputError
from tapp.examples import STUDY_FILE
from tapp.io.schema import Invalid, Schema, validate
from tapp.io.tomlfile import read_toml
from tapp.orbit.elements import elements_to_cartesian, true_to_mean_anomaly

_ELEMENT_KEYS = ("a", "e", "i", "raan", "argp")
#: The element keys of an orbit table (:class:`OrbitTable`), with units.
_ELEMENT_TABLE_KEYS = ("a_km", "e", "i_deg", "raan_deg", "argp_deg")
_CART_KEYS = ("x", "y", "z", "vx", "vy", "vz")
#: Largest Earth-centred distance of a state, km (6.7 au: beyond Jupiter; DE421 third bodies
#: and an Earth-centred integration make no sense farther out, and squares stay finite).
MAX_DISTANCE_km = 1e9
#: Largest eccentricity of an orbit given by elements.
MAX_ECCENTRICITY = 1e6
#: Largest speed component, km/s (0.3 % of c; solar escape at 1 au is 42 km/s).
MAX_SPEED_km_s = 1e3


def perigee_radius_km(x: np.ndarray, mu_km3_s2: float = GM_EARTH_km3_s2) -> float:
    """Return the osculating perigee radius (km) of a state (6,) km, km/s.

    .. math:: r_p = \\frac{h^2}{\\mu (1 + e)}

    (any conic; 0 for a rectilinear orbit).
    """
    r, v = np.asarray(x[:3], dtype=float), np.asarray(x[3:], dtype=float)
    h = np.cross(r, v)
    e_vec = np.cross(v, h) / mu_km3_s2 - r / np.linalg.norm(r)
    return float(h @ h / (mu_km3_s2 * (1.0 + np.linalg.norm(e_vec))))


def check_state_bounds(x: np.ndarray, source: str, field: str) -> np.ndarray:
    """Return ``x`` (6,) if each position component is within :data:`MAX_DISTANCE_km` and each
    velocity component within :data:`MAX_SPEED_km_s` (an Earth-centred state), else raise.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``, the limit and the largest component.
    """
    x = np.asarray(x, dtype=float)
    r_max, v_max = float(np.abs(x[:3]).max()), float(np.abs(x[3:]).max())
    if not r_max <= MAX_DISTANCE_km:
        raise InputError(source, field, f"position components within {MAX_DISTANCE_km:g} km of "
                         "the Earth (an Earth-centred state)", r_max)
    if not v_max <= MAX_SPEED_km_s:
        raise InputError(source, field, f"velocity components within {MAX_SPEED_km_s:g} km/s",
                         v_max)
    return x


def check_perigee(x: np.ndarray, source: str, field: str, *, allow_subsurface: bool = False,
                  how_to_allow: str = "--allow-subsurface", center: str = "earth"
                  ) -> np.ndarray:
    """Return ``x`` (6,) unless its orbit passes below the surface of ``center`` (the Earth's
    equatorial radius, another body's mean radius; module docstring).

    The state is first held to :func:`check_state_bounds` (even with ``allow_subsurface``).

    Raises
    ------
    InputError
        Naming ``source`` and ``field``, with the perigee radius and altitude, the limit
        (``R_EARTH_km``) and ``how_to_allow`` (the key or option that lifts the check).
    """
    check_state_bounds(x, source, field)
    if allow_subsurface:
        return x
    mu, radius = GM_km3_s2[center], RADIUS_km[center]
    what = f"the {center.capitalize()}'s equatorial radius"
    apsis = "perigee" if center == "earth" else "periapsis"
    r_km = float(np.linalg.norm(x[:3]))
    rp_km = perigee_radius_km(x, mu)
    energy = 0.5 * float(x[3:] @ x[3:]) - mu / r_km
    inbound = float(x[:3] @ x[3:]) < 0
    if r_km < radius:
        raise InputError(source, field, f"a start radius |r| >= {radius} km, {what} "
                         f"({how_to_allow} if you mean it)", round(r_km, 3))
    if rp_km < radius and (energy < 0 or inbound):
        raise InputError(source, field, f"a {apsis} radius r_p >= {radius} km, {what} (this "
                         f"orbit's {apsis} is {radius - rp_km:.1f} km below it; {how_to_allow} "
                         "if you mean it)", round(rp_km, 3))
    return x


def _parse_pairs(text: str, source: str, field: str) -> dict[str, float]:
    pairs: dict[str, float] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key = key.strip()
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not key or not math.isfinite(number):
            raise InputError(source, field, "comma-separated key=number pairs with finite "
                             "numbers", item.strip())
        if key in pairs:
            raise InputError(source, field, "each key once", key)
        pairs[key] = number
    return pairs


def state_from_elements(a_km: float, e: float, i_deg: float, raan_deg: float, argp_deg: float,
                        anomaly_deg: float, *, true_anomaly: bool = False,
                        source: str = "orbit", field: str = "orbit",
                        mu_km3_s2: float = GM_EARTH_km3_s2) -> np.ndarray:
    """Return the Cartesian state (6,) km, km/s of classical elements given in degrees, about
    a body of GM ``mu_km3_s2`` (the Earth's EGM96 GM by default)."""
    if not e >= 0 or (e < 1 and a_km <= 0) or (e > 1 and a_km >= 0):
        raise InputError(source, field, "e >= 0 with a > 0 (ellipse) or a < 0 (hyperbola)",
                         f"a={a_km}, e={e}")
    if not abs(a_km) <= MAX_DISTANCE_km:
        raise InputError(source, field, f"|a| <= {MAX_DISTANCE_km:g} km (an Earth-centred "
                         "orbit)", a_km)
    if not e <= MAX_ECCENTRICITY:
        raise InputError(source, field, f"e <= {MAX_ECCENTRICITY:g} (beyond, a hyperbola is a "
                         "straight line to double precision)", e)
    # Angles reduced to one turn first (1e300 deg is finite but has no meaningful position).
    i_deg, raan_deg, argp_deg, anomaly_deg = (math.remainder(angle, 360.0) for angle in
                                              (i_deg, raan_deg, argp_deg, anomaly_deg))
    anomaly = math.radians(anomaly_deg)
    if true_anomaly:
        if e > 1 and not abs(anomaly) < math.acos(-1.0 / e):
            raise InputError(source, field, "a true anomaly within the asymptotes of the "
                             f"hyperbola, |nu| < acos(-1/e) = {math.degrees(math.acos(-1 / e)):.4f}"
                             " deg", anomaly_deg)
        anomaly = float(true_to_mean_anomaly(anomaly, e))
    elems = np.array([a_km, e, *np.radians([i_deg, raan_deg, argp_deg]), anomaly])
    return np.asarray(elements_to_cartesian(elems, mu_km3_s2), dtype=float)


def _from_mapping(values: Mapping[str, float], source: str, field: str) -> np.ndarray:
    keys = set(values)
    if keys == set(_CART_KEYS):
        return np.array([values[k] for k in _CART_KEYS], dtype=float)
    anomaly = {"M", "nu"} & keys
    if keys - {"M", "nu"} == set(_ELEMENT_KEYS) and len(anomaly) == 1:
        which = anomaly.pop()
        return state_from_elements(*(values[k] for k in _ELEMENT_KEYS), values[which],
                                   true_anomaly=which == "nu", source=source, field=field)
    raise InputError(source, field, "keys a,e,i,raan,argp and M (or nu), or x,y,z,vx,vy,vz",
                     ",".join(sorted(keys)))


#: A Cartesian vector of three components.
Vector3 = Annotated[list[float], Field(min_length=3, max_length=3)]


class OrbitTable(Schema):
    """An orbit, Earth-centred in the EME2000 (GCRS) axes, in exactly one form: ``r_km`` and
    ``v_km_s``; or ``a_km, e, i_deg, raan_deg, argp_deg`` with one of ``M_deg``, ``nu_deg``
    (osculating elements, the EGM96 GM). The same keys in every file: a scenario's or SEARCH
    file's ``[injection]``, the study's ``[orbits.NAME]``.
    """

    renamed_keys = {**{f"{k}_km": "r_km = [x_km, y_km, z_km]" for k in _CART_KEYS[:3]},
                    **{f"{k}_km_s": "v_km_s = [vx_km_s, vy_km_s, vz_km_s]"
                       for k in _CART_KEYS[3:]}}

    r_km: Vector3 | None = Field(None, description="Position (x, y, z): the Cartesian form, "
                                 "with v_km_s.")
    v_km_s: Vector3 | None = Field(None, description="Velocity (vx, vy, vz): the Cartesian "
                                   "form, with r_km.")
    a_km: float | None = Field(None, description="Semi-major axis (< 0 for a hyperbola): the "
                               "elements form, with e, i_deg, raan_deg, argp_deg and M_deg or "
                               "nu_deg.")
    e: float | None = Field(None, description="Eccentricity (>= 0; > 1 with a_km < 0).",
                            json_schema_extra={"unit": "1"})
    i_deg: float | None = Field(None, description="Inclination to the equator.")
    raan_deg: float | None = Field(None, description="Right ascension of the ascending node.")
    argp_deg: float | None = Field(None, description="Argument of periapsis.")
    M_deg: float | None = Field(None, description="Mean anomaly at the epoch (or nu_deg).")
    nu_deg: float | None = Field(None, description="True anomaly at the epoch (or M_deg).")
    allow_subsurface: bool = Field(False, description="Accept an orbit whose perigee is below "
                                   "the Earth's surface (refused otherwise).")
    center: Literal[BODIES] | None = Field(  # type: ignore[valid-type]
        None, description="The body the state is given about (elements with its GM, the "
        "periapsis checked against its surface), translated to the integration's centre "
        "(model.center) by DE421 at t = 0; default: model.center.")

    @model_validator(mode="after")
    def _one_form(self) -> OrbitTable:
        given = {k for k in type(self).model_fields
                 if k not in ("allow_subsurface", "center") and getattr(self, k) is not None}
        if given == {"r_km", "v_km_s"}:
            return self
        anomaly = given & {"M_deg", "nu_deg"}
        if given - anomaly == set(_ELEMENT_TABLE_KEYS) and len(anomaly) == 1:
            return self
        raise Invalid("r_km and v_km_s, or a_km, e, i_deg, raan_deg, argp_deg and M_deg (or "
                      "nu_deg)", ",".join(sorted(given)))

    def state(self, source: str, field: str, *, allow_subsurface: bool = False,
              how_to_allow: str = "", center: str = "earth",
              tdb: Callable[[np.ndarray], tuple] | None = None) -> np.ndarray:
        """Return the Cartesian state (6,) km, km/s relative to ``center`` (elements with its
        GM), periapsis-checked against its surface (module docstring).

        A table with its own :attr:`center` is read about that body (its GM, its surface)
        and translated to ``center`` by the bodies' DE421 states at t = 0, read at the TDB
        date ``tdb(0)`` (the scenario's reader, :func:`tapp.dynamics.ephemeris.tdb_reader`;
        a caller without one, an Earth-centred study, refuses another body).
        ``how_to_allow`` names what lifts the periapsis check in the message (default: this
        table's ``allow_subsurface`` and ``--allow-subsurface``).
        """
        own = center if self.center is None else self.center
        if own != center and tdb is None:
            raise InputError(source, f"{field}.center", f'"{center}" (a state about another '
                             "body needs a scenario's epoch)", own)
        x = self._state(source, field, own, allow_subsurface, how_to_allow)
        if own == center:
            return x
        return x + relative_state(own, center, *tdb(np.zeros(1)))[0]

    def _state(self, source: str, field: str, center: str, allow_subsurface: bool,
               how_to_allow: str) -> np.ndarray:
        if self.r_km is not None:
            x = np.array([*self.r_km, *self.v_km_s], dtype=float)
        else:
            anomaly = "M_deg" if self.M_deg is not None else "nu_deg"
            x = state_from_elements(*(getattr(self, k) for k in (*_ELEMENT_TABLE_KEYS, anomaly)),
                                    true_anomaly=anomaly == "nu_deg", source=source, field=field,
                                    mu_km3_s2=GM_km3_s2[center])
        return check_perigee(x, source, field, center=center,
                             allow_subsurface=allow_subsurface or self.allow_subsurface,
                             how_to_allow=how_to_allow or f"{field}.allow_subsurface = true or "
                             "--allow-subsurface")


class _OrbitsSection(Schema):
    orbits: dict[str, OrbitTable] = {}


def named_orbits(path: Path, *, allow_subsurface: bool = False) -> dict[str, np.ndarray]:
    """Return the states of every ``[orbits.NAME]`` table of a scenario file.

    Raises
    ------
    InputError
        A table breaks :class:`OrbitTable`, or an orbit passes below the surface without
        ``allow_subsurface`` (here or in its table).
    """
    data = read_toml(path)
    section = validate(_OrbitsSection, {"orbits": data.get("orbits", {})}, str(path))
    return _states(section.orbits, path, allow_subsurface)


def _states(tables: Mapping[str, OrbitTable], path: Path, allow_subsurface: bool
            ) -> dict[str, np.ndarray]:
    return {name: table.state(str(path), f"orbits.{name}", allow_subsurface=allow_subsurface)
            for name, table in tables.items()}


def parse_orbit(text: str, *, scenario: Path | None = None, source: str = "--orbit",
                allow_subsurface: bool = False,
                orbits: Mapping[str, OrbitTable] | None = None) -> np.ndarray:
    """Return the initial state (6,) of an orbit spec (module docstring grammar).

    ``allow_subsurface`` (``--allow-subsurface``) accepts an orbit whose perigee is below
    the Earth's surface; otherwise it is refused with its perigee radius and the limit.
    ``orbits``: the ``[orbits.NAME]`` tables of ``scenario``, when the caller has read them
    already (:class:`tapp.od.study_file.Study`); otherwise they are read from it.
    """
    text = text.strip()
    if "=" in text:
        x = _from_mapping(_parse_pairs(text, source, "orbit"), source, "orbit")
        return check_perigee(x, source, "orbit", allow_subsurface=allow_subsurface)
    path = scenario or STUDY_FILE
    orbits = (named_orbits(path, allow_subsurface=allow_subsurface) if orbits is None
              else _states(orbits, path, allow_subsurface))
    if text not in orbits:
        raise InputError(source, "orbit", f"elements, a Cartesian state or an orbit named in "
                         f"{path} ({', '.join(orbits) or 'none'})", text)
    return orbits[text]
