"""The parameter registry: what a parameter name means, its unit and its one spelling.

Every layer that takes a parameter by name asks :func:`parse` (or :func:`canonical`): the
force model (:mod:`tapp.dynamics.forces`, :mod:`tapp.dynamics.spec`), the propagator, the
scenario's list of q and the T13 tape's names and units (:mod:`tapp.tracking.scenario`), and
the TAPP III deck's name binding (:mod:`tapp.processor.deck_bind`). A name parses into a
:class:`ParameterName`: its kind (:data:`KINDS`), the body, degree and order, axis, station or
burn it refers to, its unit and its canonical spelling.

The spelling: one per parameter, the tape's
------------------------------------------
A name carries its unit where a reader could doubt it (the style guide's rule): a
gravitational parameter is ``GM_km3_s2`` (the model centre's) or ``GM_<body>_km3_s2`` (a third
body's), an ephemeris offset ``dr_<body>_<axis>_km``. Names without a dimension, or whose
dimension their letter fixes by convention, stay as the literature writes them: the zonal
``J<n>``, the normalised ``C<n><m>``/``S<n><m>``, ``Cr``, ``Cd``; the empirical and
stochastic accelerations ``acc_<c>`` and ``acc_<c>_<k>`` (km/s²) and a burn's thrust
``thr_...`` are named as before. These are the spellings the T13 tape has always carried, so
the scenario (``[parameters] dynamic``, ``values``), the deck (σ tables, permutations,
groups) and the tape now read the same: a deck can be written by copying names from the
scenario, and no tape, printout or figure changes.

The scenario used to name ``GM``, ``GM_<body>`` and ``dr_<body>_<axis>`` without their units
(only the tape added them). These :data:`LEGACY` spellings are still read wherever a name is
read, with a :class:`~tapp.errors.DeprecatedSpelling` warning naming the file, the field and
the spelling to write (the CLI prints it as one ``warning:`` line); any other unknown name is
one :class:`~tapp.errors.InputError` naming the file, the field and the names expected.

The other kinds are named by what owns them, ``<owner>.<label>``: a station's location
(``GOLDSTONE.spin_radius_km``), bias (``GOLDSTONE.range_bias_km``) and zenith media
parameters (``GOLDSTONE.zenith_wet_km``, per pass ``.p1``, ``.p2``, ...), a ΔDOR baseline's
quasar (``GOLDSTONE-MADRID.quasar_ra_rad``), a burn's execution errors (``TCM1.mag_prop``), the
Earth orientation offsets (``eop.ut1_s``, per day ``eop.ut1_s.2031-07-22``); their labels are
defined beside their models and read here.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from functools import cache

from tapp.dynamics.empirical import COMPONENTS
from tapp.dynamics.empirical import NAMES as EMPIRICAL_NAMES
from tapp.dynamics.gates import PARAMETERS as GATES_PARAMETERS
from tapp.dynamics.manoeuvres import THRUST_NAMES
from tapp.errors import DeprecatedSpelling, InputError
from tapp.frames.orientation import EOP_KIND, EOP_UNITS

#: The kinds of parameter name. Model parameters of the force model (``dynamic`` on the tape):
#: gm, zonal, harmonic, radiation, drag, ephemeris_offset, empirical, thrust. The others as the
#: tape's kind: orbit (the state at the epoch), stochastic (piecewise-constant accelerations),
#: location, bias, troposphere, ionosphere (a station's), quasar (a ΔDOR baseline's),
#: execution (a burn's), eop.
KINDS = ("orbit", "gm", "zonal", "harmonic", "radiation", "drag", "ephemeris_offset",
         "empirical", "thrust", "stochastic", "location", "bias", "troposphere", "ionosphere",
         "quasar", "execution", "eop")
#: The kinds whose parameters are model parameters of the force model (tape kind "dynamic").
DYNAMIC_KINDS = ("gm", "zonal", "harmonic", "radiation", "drag", "ephemeris_offset",
                 "empirical", "thrust")
#: The p part of x: the Cartesian state at the epoch, with units.
ORBIT_PARAMETERS = (("x_km", "km"), ("y_km", "km"), ("z_km", "km"), ("vx_km_s", "km/s"),
                    ("vy_km_s", "km/s"), ("vz_km_s", "km/s"))
#: The unit of a gravitational parameter and its name suffix.
GM_UNIT, GM_SUFFIX = "km^3/s^2", "_km3_s2"
#: The axes of an ephemeris offset, in the order of its parameters.
OFFSET_AXES = ("x", "y", "z")
#: The surface-force input (:class:`tapp.dynamics.spec.SurfaceForces` field) that is each
#: coefficient parameter's nominal value.
SURFACE_FIELDS = {"Cr": "c_r", "Cd": "c_d"}
#: Earlier spellings, still read with a :class:`~tapp.errors.DeprecatedSpelling` warning.
LEGACY = ("GM", "GM_<body>", "dr_<body>_<axis>")
#: What a model parameter's name may be (for messages).
EXPECTED = ("GM_km3_s2 (the centre's), GM_<body>_km3_s2, J<n>, C<n><m>, S<n><m>, Cr, Cd, "
            "dr_<body>_x_km|y_km|z_km, acc_R|I|C|x|y|z, thr_...")

_GM = re.compile(r"^GM(?:_([a-z]+))?_km3_s2$")
_GM_LEGACY = re.compile(r"^GM(?:_([a-z]+))?$")
_ZONAL = re.compile(r"^J(\d)$")
_HARMONIC = re.compile(r"^([CS])(\d)(\d)$")
_OFFSET = re.compile(r"^dr_([a-z]+)_([xyz])_km$")
_OFFSET_LEGACY = re.compile(r"^dr_([a-z]+)_([xyz])$")
_STOCHASTIC = re.compile(r"^acc_([A-Za-z])_(\d+)$")
_OWNED = re.compile(r"^(.+?)\.([a-z0-9_]+)(?:\.(p\d+|\d{4}-\d{2}-\d{2}))?$")
#: Units of the thrust parameters that are not accelerations (km/s²):
#: :data:`tapp.dynamics.manoeuvres.THRUST_PARAMETERS`.
_THRUST_UNITS = {"thr_flow_1_s": "1/s", "thr_start_s": "s"}
#: Unit of a label from the end of its name, longest first.
_SUFFIX_UNITS = (("_km_s", "km/s"), ("_km", "km"), ("_rad", "rad"), ("_tecu", "TECU"),
                 ("_s", "s"))


@dataclass(frozen=True, slots=True)
class ParameterName:
    """What a parameter name means.

    Attributes
    ----------
    canonical : its one spelling (module docstring).
    kind : one of :data:`KINDS`.
    unit : its unit ("km^3/s^2", "km", "km/s", "km/s^2", "rad", "s", "TECU", "1").
    body : the body of a GM ("" for the model's centre) or of an ephemeris offset.
    degree, order : of a zonal (order 0) or a normalised harmonic.
    coefficient : "J", "C" or "S" for a zonal or a harmonic.
    axis : 0, 1, 2 of an ephemeris offset; -1 otherwise.
    owner : the station, baseline or burn of an owned name, "eop" for an EOP offset.
    label : the name within its owner (``spin_radius_km``, ``ut1_s``, ...).
    span : the pass (``p1``) or UTC day (``2031-07-22``) of a per-pass or per-day parameter.
    """

    canonical: str
    kind: str
    unit: str
    body: str = ""
    degree: int = 0
    order: int = 0
    coefficient: str = ""
    axis: int = -1
    owner: str = ""
    label: str = ""
    span: str = ""

    @property
    def dynamic(self) -> bool:
        """True for a model parameter of the force model (:data:`DYNAMIC_KINDS`)."""
        return self.kind in DYNAMIC_KINDS

    @property
    def tape_kind(self) -> str:
        """Its kind on the T13 tape: "dynamic" for a model parameter, else :attr:`kind`."""
        return "dynamic" if self.dynamic else self.kind

    @property
    def surface_field(self) -> str | None:
        """The :class:`tapp.dynamics.spec.SurfaceForces` field of its nominal value (Cr, Cd)."""
        return SURFACE_FIELDS.get(self.canonical)


def gm_name(body: str = "") -> str:
    """The name of a GM: the model centre's (``body`` "") or a body's."""
    return f"GM_{body}{GM_SUFFIX}" if body else f"GM{GM_SUFFIX}"


def offset_name(body: str, axis: int) -> str:
    """The name of ``body``'s ephemeris offset along ``axis`` (0, 1, 2: x, y, z)."""
    return f"dr_{body}_{OFFSET_AXES[axis]}_km"


def unit_of_label(label: str) -> str:
    """The unit a label's suffix names (``spin_radius_km`` → km, ``lon_rad`` → rad,
    ``zenith_tec_tecu`` → TECU), "1" without one."""
    for suffix, unit in _SUFFIX_UNITS:
        if label.endswith(suffix):
            return unit
    return "1"


def parse(name: str, source: str = "parameters", field: str = "name") -> ParameterName:
    """Return what the parameter ``name`` means.

    An earlier spelling (:data:`LEGACY`) is read with a
    :class:`~tapp.errors.DeprecatedSpelling` warning
    ``SOURCE: FIELD: 'GM_moon' is an earlier spelling: write 'GM_moon_km3_s2'``.

    Raises
    ------
    InputError
        For a name of no kind, naming ``source`` and ``field``.
    """
    text = name if isinstance(name, str) else ""
    found = _model(text) or _other(text)
    if found is None:
        raise InputError(source, field, f"a parameter name: {EXPECTED}, a state component "
                         f"({', '.join(n for n, _ in ORBIT_PARAMETERS)}) or <owner>.<label> "
                         "(a station's, baseline's or burn's; eop.<name>)", name)
    if found.canonical != text:
        _warn_spelling(text, found.canonical, source, field)
    return found


def canonical(name: str, source: str = "parameters", field: str = "name") -> str:
    """Return the one spelling of ``name`` (:func:`parse`: its warning and its error)."""
    return parse(name, source, field).canonical


def model_parameter(name: str, source: str = "model", field: str = "parameters"
                    ) -> ParameterName | None:
    """What a model parameter's name means (:data:`DYNAMIC_KINDS`; an earlier spelling with
    :func:`parse`'s warning), None for any other name: the force model says what it expects."""
    found = _model(name) if isinstance(name, str) else None
    if found is not None and found.canonical != name:
        _warn_spelling(name, found.canonical, source, field)
    return found


def meaning(name: str) -> ParameterName | None:
    """What a name in its one spelling means, None for any other (an earlier spelling too:
    for the kernels' own names, which are canonical; no warning)."""
    found = _model(name) or _other(name)
    return found if found is not None and found.canonical == name else None


def _warn_spelling(name: str, canonical: str, source: str, field: str) -> None:
    """Warn that ``name`` is an earlier spelling of ``canonical`` (at the reader's caller)."""
    warnings.warn(DeprecatedSpelling(f"{source}: {field}: {name!r} is an earlier spelling: "
                                     f"write {canonical!r}"), stacklevel=4)


def _model(name: str) -> ParameterName | None:
    """A model parameter's meaning, in either spelling, or None."""
    if m := _GM.match(name) or _GM_LEGACY.match(name):
        body = m.group(1) or ""
        return ParameterName(gm_name(body), "gm", GM_UNIT, body=body)
    if m := _OFFSET.match(name) or _OFFSET_LEGACY.match(name):
        axis = OFFSET_AXES.index(m.group(2))
        return ParameterName(offset_name(m.group(1), axis), "ephemeris_offset", "km",
                             body=m.group(1), axis=axis)
    if m := _ZONAL.match(name):
        return ParameterName(name, "zonal", "1", degree=int(m.group(1)), coefficient="J")
    if m := _HARMONIC.match(name):
        return ParameterName(name, "harmonic", "1", degree=int(m.group(2)),
                             order=int(m.group(3)), coefficient=m.group(1))
    if name in SURFACE_FIELDS:
        return ParameterName(name, "radiation" if name == "Cr" else "drag", "1")
    if name in EMPIRICAL_NAMES:
        return ParameterName(name, "empirical", "km/s^2", label=name[4:])
    if name in THRUST_NAMES:
        return ParameterName(name, "thrust", _THRUST_UNITS.get(name, "km/s^2"), label=name)
    return None


def _other(name: str) -> ParameterName | None:
    """The meaning of a name that is not a model parameter's, or None."""
    if name in dict(ORBIT_PARAMETERS):
        return ParameterName(name, "orbit", dict(ORBIT_PARAMETERS)[name])
    if (m := _STOCHASTIC.match(name)) and any(m.group(1) in c for c in COMPONENTS.values()):
        return ParameterName(name, "stochastic", "km/s^2", label=m.group(1))
    if not (m := _OWNED.match(name)):
        return None
    owner, label, span = m.group(1), m.group(2), m.group(3) or ""
    if owner == "eop":
        kind = EOP_KIND if label in EOP_UNITS and not span.startswith("p") else None
    else:
        kind = _owned_kinds().get(label)
        if kind in ("location", "bias", "quasar", "execution") and span:
            kind = None  # only zenith parameters have a span (per pass)
    if kind is None:
        return None
    unit = EOP_UNITS[label] if owner == "eop" else unit_of_label(label)
    return ParameterName(name, kind, unit, owner=owner, label=label, span=span)


@cache
def _owned_kinds() -> dict[str, str]:
    """Label → tape kind of the parameters a station, baseline or burn owns."""
    # Imported here, not at the top: these kernels import tapp.dynamics, which imports this
    # module; by the time a name is parsed every one of them is loaded.
    from tapp.measurements.ddor import QUASAR_PARAMETER_NAMES
    from tapp.measurements.media import MEDIA_KINDS, MEDIA_PARAMETER_NAMES
    from tapp.measurements.observables import BIAS_NAMES
    from tapp.measurements.stations import STATION_PARAMETER_NAMES

    kinds = {label: "location" for names in STATION_PARAMETER_NAMES.values() for label in names}
    kinds.update(dict.fromkeys(BIAS_NAMES, "bias"))
    kinds.update(zip(MEDIA_PARAMETER_NAMES, MEDIA_KINDS, strict=True))
    kinds.update(dict.fromkeys(QUASAR_PARAMETER_NAMES, "quasar"))
    kinds.update({label: "execution" for label, _, _ in GATES_PARAMETERS})
    return kinds

