"""The T13 and T32 tapes' HDF5 layouts as tables: one row per dataset or attribute.

One source for the layout: the writers (:mod:`tapp.io.tape.t13_hdf5`,
:mod:`tapp.io.tape.t32_hdf5`) write the rows in table order, the readers read them by the
rows' types, the checks of shapes resolve the rows' symbolic shapes
(:meth:`tapp.io.tape.checks.Checker.rows`), and the format reference
(``docs/reference/tapes.md``, :func:`markdown`) renders the tables. Pure data: no NumPy, no
h5py.

A row (:class:`Field`) names its path in the file (``group/name``; ``attrs/NAME`` a root
attribute, ``PATH.attrs/NAME`` an attribute of a group or dataset; ``{i}`` a recycle number,
``{omega}`` a command number, ``{s}`` a system), its type, its shape in the tape's symbols
(n_o, n_p, n_m, n_ts, n_it, n_pairs, ...; ``L`` the packed length of a matrix of order n_o:
n_o(n_o+1)/2 "TR" or n_o² "full"), the ``units`` attribute the writer gives it, the versions
that carry it, whether it may be absent, and what it holds; ``source`` is where the tape in
memory keeps the value (a dotted attribute path from the tape, or, under ``{i}`` and
``{omega}``, from the recycle or the entity).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

#: Types of a row: text, integers, numbers, booleans, a list of texts (attributes), and the
#: packed upper-triangular factors and symmetric matrices of :func:`tapp.io.tape.hdf5io.
#: write_packed`.
TYPES = ("str", "int", "float", "bool", "str[]", "factor", "symmetric")


@dataclass(frozen=True, slots=True)
class Field:
    """One dataset or attribute of a tape (module docstring).

    Attributes
    ----------
    path : where it is in the file.
    dtype : one of :data:`TYPES`.
    shape : the dataset's shape in symbols (() for an attribute or a scalar).
    unit : the dataset's ``units`` attribute ("" for none); of an attribute, its unit.
    since, until : the first and last versions that carry it (None: every later one).
    optional : the path (a group, a dataset or this row's own) whose absence makes the row
        absent; "" for a row every tape of its versions has.
    description : what it holds.
    source : where the tape in memory keeps the value ("" where the writer computes it); of
        a row only older versions carry, where the reader keeps what it makes of it (the
        factor of a T32 version-1 matrix).
    big : compressed (T32: when n_o > 100).
    finite : numbers checked finite and bounded (:meth:`tapp.io.tape.checks.Checker.rows`).
    """

    path: str
    dtype: str
    shape: tuple[str, ...]
    unit: str
    description: str
    source: str = ""
    since: int = 1
    until: int | None = None
    optional: str = ""
    big: bool = False
    finite: bool = True

    @property
    def is_attr(self) -> bool:
        """Whether the row is an attribute (of the root, a group or a dataset)."""
        return self.path.startswith("attrs/") or ".attrs/" in self.path

    @property
    def owner(self) -> str:
        """The object an attribute belongs to ("" for the root)."""
        return self.path.partition(".attrs/")[0] if ".attrs/" in self.path else ""

    @property
    def name(self) -> str:
        """The last component of the path (an attribute's name)."""
        return self.path.rpartition("/")[2]

    def in_version(self, version: int) -> bool:
        """Whether tapes of ``version`` carry the row."""
        return self.since <= version and (self.until is None or version <= self.until)


def rows(table: tuple[Field, ...], version: int, prefix: str = "", *, attrs: bool | None = None
         ) -> tuple[Field, ...]:
    """The rows of ``table`` that ``version`` carries, under ``prefix``, in table order;
    only attributes (``attrs=True``) or only datasets (False)."""
    return tuple(f for f in table if f.in_version(version) and f.path.startswith(prefix)
                 and (attrs is None or f.is_attr == attrs))


def filled(table: tuple[Field, ...], version: int, prefix: str, **names: object
           ) -> tuple[Field, ...]:
    """The rows of :func:`rows` under ``prefix`` whose paths have as many placeholders
    (``{s}``, ``{i}``, ``{omega}``) as ``names`` gives, with those filled in, in the path and
    in :attr:`Field.optional` (``i=3``: ``recycles/{i}/L`` becomes ``recycles/3/L``; none
    given: the rows without one)."""
    return tuple(replace(f, path=f.path.format(**names), optional=f.optional.format(**names))
                 for f in rows(table, version, prefix) if f.path.count("{") == len(names))


def row(table: tuple[Field, ...], path: str) -> Field:
    """The row of ``path`` (KeyError if the table has none)."""
    for f in table:
        if f.path == path:
            return f
    raise KeyError(path)


def _fields(prefix: str, dtype: str, names: str, shape: tuple[str, ...], unit: str,
            description: str, **kw) -> tuple[Field, ...]:
    """Rows of the same type, shape and meaning, sourced from the same attribute path."""
    source = kw.pop("source", prefix.rstrip("/").replace("/", "."))
    return tuple(Field(f"{prefix}{n}", dtype, shape, unit, description,
                       source=f"{source}.{n}" if source else "", **kw) for n in names.split())


# ---------------------------------------------------------------------------------------------
# Shared by both tapes
# ---------------------------------------------------------------------------------------------

#: Provenance every tape gets (:func:`tapp.io.tape.hdf5io.provenance_attrs`).
STAMPED = ("tapp_version", "git_commit", "created_utc")

_EPOCH = (
    Field("attrs/epoch", "str", (), "", "the tape epoch t_0 = 0 (injection), ISO UTC"),
    Field("attrs/epoch_jd_whole", "float", (), "d", "the epoch's Julian date, whole part"),
    Field("attrs/epoch_jd_fraction", "float", (), "d", "the epoch's Julian date, fraction"),
    Field("attrs/time_scale", "str", (), "", '"UTC"'),
)

_STAMPS = tuple(Field(f"attrs/{name}", "str", (), "", what, optional=f"attrs/{name}")
                for name, what in zip(STAMPED, (
                    "the tapp version that wrote the tape", "its git commit, or unknown",
                    "when it was written, ISO UTC"), strict=True))

PARAMETERS = (
    *_fields("parameters/", "str", "name unit kind", ("n_o",), "",
             "the n_o parameters x = [p; q]: names (carrying units: x_km, GM_km3_s2), units, "
             "kinds (orbit, dynamic, location, bias, troposphere, ionosphere, stochastic, "
             "execution, eop, quasar)"),
    Field("parameters/station", "int", ("n_o",), "", "station number of a station "
          "parameter, 0 otherwise", "parameters.station"),
    Field("parameters/nominal", "float", ("n_o",), "see unit", "values of x at t_0, in "
          "parameters/unit", "parameters.nominal"),
)

# ---------------------------------------------------------------------------------------------
# T13
# ---------------------------------------------------------------------------------------------

#: Provenance attributes the simulator stamps (:data:`tapp.io.tape.t13.SCENARIO_PROVENANCE`).
T13_PROVENANCE = ("scenario", "scenario_source", "earth_orientation", "eop", "relativity",
                  "targeting", "schedule")
_T13_PROVENANCE_TEXT = (
    "the scenario (JSON)", "its file", 'the Earth orientation model ("iau2006" or "gmst")',
    "the EOP source of the run", "the relativistic light-time model",
    "SEARCH's retargeting record (JSON), empty without one",
    "the pass schedule tracked by (FILE (sha256 HEX)), empty by visibility")
_PAIRS_MATRICES = "pairs/dJ pairs/dJt pairs/dJt_parts"
_RAW = (("t_s", "float", ("N",), "s", "time of the observation"),
        ("station", "int", ("N",), "", "station number"),
        ("kind", "int", ("N",), "code into attr kinds", "observable kind (code into the "
         "attribute kinds)"),
        ("record", "int", ("N",), "", "record index k"),
        ("segment", "int", ("N",), "", "block of M: a pass, one kind, split at the T13 times"),
        ("value", "float", ("N",), "km, km/s or rad", "the computed observable"),
        ("A", "float", ("N", "n_o"), "observable unit per parameters/unit",
         "partial row, referred to the epoch t_j of the record"),
        ("weight", "float", ("N",), "1/(observable unit)^2", "fit-world weight 1/σ²"),
        ("m_white_var", "float", ("N",), "(observable unit)^2", "real-world white variance"),
        ("m_bias_var", "float", ("N",), "(observable unit)^2", "real-world per-pass bias "
         "variance"),
        ("m_corr_var", "float", ("N",), "(observable unit)^2", "real-world correlated "
         "variance"),
        ("m_tau_s", "float", ("N",), "s", "its time constant (inf: none)"))

T13_LAYOUT: tuple[Field, ...] = (
    Field("attrs/format", "str", (), "", '"T13"'),
    Field("attrs/version", "int", (), "", "the layout's version"),
    Field("attrs/iden", "str", (), "", "identification of the run", "iden"),
    *(Field(f"attrs/{n}", "int", (), "", what) for n, what in (
        ("n_o", "number of parameters"), ("n_p", "number of orbit parameters"),
        ("n_m", "number of miss parameters"), ("n_ts", "number of stations (and ΔDOR "
                                                      "baselines)"),
        ("n_it", "number of records"))),
    *_EPOCH,
    Field("attrs/frame", "str", (), "", "inertial frame: GCRS (iau2006) or EME2000 (gmst)"),
    Field("attrs/center", "str", (), "", '"earth"'),
    Field("attrs/units", "str", (), "", "note on the units"),
    Field("attrs/packing", "str", (), "", 'storage of the pair matrices: "TR" (upper triangle '
          'by rows) or "full"'),
    *_STAMPS,
    *(Field(f"attrs/{n}", "str", (), "", what, optional=f"attrs/{n}")
      for n, what in zip(T13_PROVENANCE, _T13_PROVENANCE_TEXT, strict=True)),
    *PARAMETERS,
    Field("stations/id", "int", ("n_ts",), "", "station number s = 1..n_ts", "stations.id"),
    *_fields("stations/", "str", "name observables", ("n_ts",), "",
             "names; observables comma-separated (ΔDOR baselines A-B follow the stations)"),
    Field("stations/lat_deg", "float", ("n_ts",), "deg", "geodetic (WGS84) latitude",
          "stations.lat_deg"),
    Field("stations/lon_deg", "float", ("n_ts",), "deg", "longitude", "stations.lon_deg"),
    Field("stations/h_km", "float", ("n_ts",), "km", "height", "stations.h_km"),
    Field("stations/elev_mask_deg", "float", ("n_ts",), "deg", "elevation mask",
          "stations.elev_mask_deg"),
    *_fields("miss/", "str", "name unit", ("n_m",), "", "the miss parameters"),
    Field("miss/nominal", "float", ("n_m",), "see unit", "nominal miss", "miss.nominal"),
    Field("miss/nominal.attrs/kind", "str", (), "", "kind of miss (equinoctial, bplane, ...)",
          "miss.kind", optional="miss/nominal.attrs/kind"),
    Field("miss/nominal.attrs/t_s", "float", (), "s", "time of the miss", "miss.t_s",
          optional="miss/nominal.attrs/t_s"),
    Field("B", "float", ("n_m", "n_o"), "miss/unit per parameters/unit",
          "∂m/∂x at injection (t_0)", "miss.B"),
    Field("times/t_s", "float", ("n_it+1",), "s", "T13 times t_0 = 0 < ... < t_{n_it}, s "
          "from the epoch", "records.times_s"),
    Field("times/is_epoch", "bool", ("n_it+1",), "", "whether each time is an epoch time",
          "records.is_epoch"),
    Field("times/is_input", "bool", ("n_it+1",), "", "whether each time is an input time",
          "records.is_input"),
    Field("records/j", "int", ("n_it",), "", "epoch index j of record k (stays, or changes "
          "to k-1)", "records.j"),
    Field("records/k", "int", ("n_it",), "", "record index k = 1..n_it", "records.k"),
    Field("records/t_s", "float", ("n_it",), "s", "t_k (= times/t_s[1:])", "records.t_s"),
    Field("records/info", "float", ("n_it", "6"), "km, km/s", "state at t_k (attribute "
          "columns: x_km .. vz_km_s), in attrs/frame", "records.info"),
    Field("records/info.attrs/columns", "str[]", (), "", "names of the state's columns"),
    Field("records/U", "float", ("n_it", "n_p", "n_o"),
          "parameters/unit of p(t_k) per parameters/unit of x(t_j)", "∂p(t_k)/∂x(t_j)",
          "records.U", big=True),
    Field("pairs/k", "int", ("n_pairs",), "", "(record, station) pairs with data, each once, "
          "sorted by (k, station): record index", "pairs.k"),
    Field("pairs/station", "int", ("n_pairs",), "", "station number", "pairs.station"),
    Field("pairs/n_obs", "int", ("n_pairs",), "", "scalar observations in the pair",
          "pairs.n_obs"),
    Field("pairs/R", "factor", ("n_pairs", "L"), "1/u_b, u = parameters/unit",
          "square-root information over (t_{k-1}, t_k] referred to t_j: upper-triangular R "
          "(diagonal >= 0), RᵀR = AᵀWA; attrs packing, order (= n_o), form = factor",
          "pairs.R", since=3, big=True),
    Field("pairs/Rt", "factor", ("n_pairs", "L"), "1/u_b, u = parameters/unit",
          "R̃ with R̃ᵀR̃ = AᵀWMWA, as pairs/R", "pairs.Rt", since=3, big=True),
    Field("pairs/Rt_parts", "factor", ("n_pairs", "3", "L"), "1/u_b, u = parameters/unit",
          "the factors of the white-noise, per-pass bias and exponentially correlated parts of "
          "AᵀWMWA (attribute parts), their Gram matrices summing to R̃ᵀR̃", "pairs.Rt_parts",
          since=3, optional="pairs/Rt_parts", big=True),
    Field("pairs/Rt_parts.attrs/parts", "str[]", (), "", "white, bias, correlated "
          "(tapp.measurements.noise.PARTS)", since=3, optional="pairs/Rt_parts"),
    Field("pairs/dJ", "symmetric", ("n_pairs", "L"), "1/(u_a u_b), u = parameters/unit",
          "the normal matrix AᵀWA itself (read, then factored)", "pairs.dJ", until=2,
          big=True),
    Field("pairs/dJt", "symmetric", ("n_pairs", "L"), "1/(u_a u_b), u = parameters/unit",
          "AᵀWMWA itself", "pairs.dJt", until=2, big=True),
    Field("pairs/dJt_parts", "symmetric", ("n_pairs", "3", "L"),
          "1/(u_a u_b), u = parameters/unit", "the parts of AᵀWMWA themselves",
          "pairs.dJt_parts", since=2, until=2, optional="pairs/dJt_parts", big=True),
    Field("pairs/dJt_parts.attrs/parts", "str[]", (), "", "white, bias, correlated",
          since=2, until=2, optional="pairs/dJt_parts"),
    Field("passes/station", "int", ("n_passes",), "", "tracking passes (before any split at "
          "T13 times): station number", "passes.station"),
    Field("passes/t_start_s", "float", ("n_passes",), "s", "first observation",
          "passes.t_start_s"),
    Field("passes/t_end_s", "float", ("n_passes",), "s", "last observation", "passes.t_end_s"),
    Field("passes/n_obs", "int", ("n_passes",), "", "observations", "passes.n_obs"),
    Field("editing/rule", "str", ("n_rules",), "", "what the schedule asked for and what each "
          "rule removed (tapp.io.tape.t13.TapeEditing): the rules, in the order they apply",
          "editing.rule", optional="editing"),
    Field("editing/scheduled_obs", "int", ("n_ts",), "scalar observations", "observations "
          "on the schedule's sample times", "editing.scheduled_obs", optional="editing"),
    Field("editing/removed_obs", "int", ("n_ts", "n_rules"), "scalar observations",
          "observations removed by each rule (under the first that removed each: "
          "scheduled_obs = sum of pairs/n_obs + sum of removed_obs)", "editing.removed_obs",
          optional="editing"),
    Field("editing/removed_passes", "int", ("n_ts", "n_rules"), "passes",
          "passes removed whole by each rule", "editing.removed_passes", optional="editing"),
    Field("editing/added_passes", "int", ("n_ts",), "passes", "passes added by splitting "
          "passes longer than the scenario's max_pass_s", "editing.added_passes",
          optional="editing"),
    Field("stochastic.attrs/frame", "str", (), "", "the parameters of kind stochastic "
          "(tapp.estimation.gauss_markov): frame of the components", "stochastic.frame",
          optional="stochastic"),
    Field("stochastic.attrs/components", "str[]", (), "", "the components",
          "stochastic.components", optional="stochastic"),
    Field("stochastic.attrs/sigma_km_s2", "float", (), "km/s²", "σ of each acceleration",
          "stochastic.sigma_km_s2", optional="stochastic"),
    Field("stochastic.attrs/tau_s", "float", (), "s", "correlation time τ",
          "stochastic.tau_s", optional="stochastic"),
    Field("stochastic/boundaries_s", "float", ("K+1",), "s", "interval boundaries",
          "stochastic.boundaries_s", optional="stochastic", finite=False),
    *_fields("manoeuvres/", "str", "name kind axes", ("n_b",), "",
             'the burns whose execution errors are the parameters of kind execution '
             '(tapp.dynamics.manoeuvres), ascending in time: name, "impulsive" or "finite", '
             '"inertial", "ric" or "vnb"', source="", optional="manoeuvres"),
    Field("manoeuvres/t_start_s", "float", ("n_b",), "s", "time (ignition)",
          optional="manoeuvres"),
    Field("manoeuvres/duration_s", "float", ("n_b",), "s", "duration (0: impulsive)",
          optional="manoeuvres"),
    Field("manoeuvres/thrust_N", "float", ("n_b",), "N", "thrust of a finite burn (0: "
          "impulsive)", optional="manoeuvres"),
    Field("manoeuvres/mass_kg", "float", ("n_b",), "kg", "mass at ignition (0: impulsive)",
          optional="manoeuvres"),
    Field("manoeuvres/mass_flow_kg_s", "float", ("n_b",), "kg/s", "mass flow (0: impulsive)",
          optional="manoeuvres"),
    Field("manoeuvres/vector", "float", ("n_b", "3"),
          "km/s (impulsive) or 1 (finite), in the burn's axes", "Δv (impulsive) or the "
          "thrust's unit direction (finite), in the burn's axes", optional="manoeuvres"),
    Field("manoeuvres/sigma", "float", ("n_b", "4"), "1, km/s, rad, km/s",
          "Gates' σ₁..σ₄ (tapp.dynamics.gates)", optional="manoeuvres"),
    Field("raw.attrs/kinds", "str[]", (), "", "one row per scalar observation, for "
          "validation: the observable kinds the codes of raw/kind index", "raw.kinds",
          optional="raw.attrs/kinds"),
    *(Field(f"raw/{n}", dtype, shape, unit, what, f"raw.{n}", optional="raw", big=True,
            finite=n != "m_tau_s") for n, dtype, shape, unit, what in _RAW),
)

# ---------------------------------------------------------------------------------------------
# T32
# ---------------------------------------------------------------------------------------------

#: Symmetric matrices of a recycle: (name, "normal" or "covariance", units of the matrix,
#: what it is). Version 2 stores the factor of each (``<name>_factor``).
T32_SYMMETRIC = (
    ("S_fit", "normal", "1/(u_a u_b)", "S' fit-world normal matrix (extended)"),
    ("Lambda_fit", "covariance", "u_a u_b", "Λ' fit-world covariance"),
    ("Lambda_real", "covariance", "u_a u_b", "Λ̄' real-world covariance"),
    ("Sigma", "covariance", "u_a u_b", "Σ = Λ' J̃ Λ', this interval's tracking-noise "
     "covariance"),
    ("J", "normal", "1/(u_a u_b)", "AᵀWA from t_l to t_k"),
    ("Jt", "normal", "1/(u_a u_b)", "AᵀWMWA from t_l to t_k"))
#: Units of the factor of a normal matrix and of a covariance.
FACTOR_UNITS = {"normal": "1/u_b", "covariance": "u_b"}
_T32_APRIORI = (("S0_fit", "normal", "S⁰ fit-world a priori normal matrix at injection, in "
                 "x^0"),
                ("Lambda0_real", "covariance", "Λ̄⁰ real-world a priori covariance at "
                 "injection, in x^0"))

T32_LAYOUT: tuple[Field, ...] = (
    Field("attrs/format", "str", (), "", '"T32"'),
    Field("attrs/version", "int", (), "", "the layout's version"),
    Field("attrs/iden", "str", (), "", "identification (of the T13 tape's run)", "iden"),
    *(Field(f"attrs/{n}", "int", (), "", what) for n, what in (
        ("n_o", "number of parameters"), ("n_p", "number of orbit parameters"),
        ("n_m", "number of miss parameters"), ("n_recycles", "number of recycles n_r"),
        ("n_partitions", "number of set partitions"))),
    *_EPOCH,
    Field("attrs/units", "str", (), "", "note on the units"),
    Field("attrs/provenance_keys", "str[]", (), "", "the names of the further provenance "
          "attributes (e.g. deck (JSON), deck_source, t13_source, t13_iden), each a text "
          "root attribute"),
    *_STAMPS,
    *PARAMETERS,
    *(Field(f"miss/{n}", "str", ("n_m",), "", "the miss parameters", f"miss_{n}")
      for n in ("name", "unit")),
    Field("systems/{s}/chain", "float", ("n_o", "n_o"), "(row unit)/(column unit)",
          "∂x^s/∂x, s = common, fit, real: the system chain of the deck (permutations and "
          "constraints of q)"),
    Field("systems/{s}/names", "str", ("n_o",), "", "row names of the system vector x^s"),
    Field("partitions/name", "str", ("n_partitions",), "", "the set partitions of Table "
          "B-4: names"),
    Field("partitions/system", "str", ("n_partitions",), "", "system: standard, common, "
          "fit, real or miss"),
    Field("partitions/tail", "int", ("n_partitions",), "row (0-based)", "rows tail..head-1 "
          "of that system's vector"),
    Field("partitions/head", "int", ("n_partitions",), "row (0-based, exclusive)", "(head "
          "exclusive)"),
    Field("partitions/names", "str", ("Σ(head-tail)",), "", "the row names of every "
          "partition, joined in partition order (the system's names tail..head-1)"),
    *(Field(f"apriori/{n}_factor", "factor", ("L",), FACTOR_UNITS[what], text,
            f"{n}_factor", since=2) for n, what, text in _T32_APRIORI),
    *(Field(f"apriori/{n}", "symmetric", ("L",), "", text + " (the matrix itself)",
            f"{n}_factor", until=1) for n, _, text in _T32_APRIORI),
    Field("recycles/number", "int", ("n_r",), "", "recycle number i' = 1..n_r", "number"),
    Field("recycles/k", "int", ("n_r",), "", "current T13 index (ascending)", "k"),
    Field("recycles/l", "int", ("n_r",), "", "last recycle's T13 index (l_i = k_{i-1})", "l"),
    Field("recycles/j", "int", ("n_r",), "", "program epoch T13 index", "j"),
    Field("recycles/t_s", "float", ("n_r",), "s", "t_k, s from the tape epoch", "t_s"),
    Field("recycles/t_l_s", "float", ("n_r",), "s", "t_l", "t_l_s"),
    Field("recycles/info", "float", ("n_r", "6"), "km, km/s (x, y, z, vx, vy, vz), EME2000",
          "state at t_k", "info"),
    *(Field(f"recycles/{{i}}/{n}_factor", "factor", ("L",), FACTOR_UNITS[what], text,
            f"{n}_factor", since=2, big=True) for n, what, _, text in T32_SYMMETRIC),
    *(Field(f"recycles/{{i}}/{n}", "symmetric", ("L",), "", text + " (the matrix itself)",
            f"{n}_factor", until=1) for n, _, _, text in T32_SYMMETRIC),
    Field("recycles/{i}/L", "float", ("n_o", "n_o"), "u_a/u_b", "∂(a posteriori error)/"
          "∂(a priori error at t_l), both in x^k", "L", big=True),
    Field("recycles/{i}/transition", "float", ("n_o", "n_o"), "u_a/u_b", "∂x^k/∂x^{k_prev}, "
          "from the previous recycle's representation (x^0 for the first)", "transition",
          big=True),
    Field("recycles/{i}/transition_adjoint", "float", ("n_o", "n_o"), "u_b/u_a",
          "its inverse transposed", "transition_adjoint", since=2, big=True),
    Field("recycles/{i}/B", "float", ("n_m", "n_o"), "miss/unit per parameters/unit",
          "∂m/∂x^k", "B"),
    Field("recycles/{i}/entities/{omega}.attrs/command", "str", (), "", "output of recycle "
          'command ω (1-based) of Table B-5: the command in seed notation ("I; 0,-,pk; '
          '1,2,fp")', "command"),
    Field("recycles/{i}/entities/{omega}.attrs/alias", "str", (), "", "its readable form",
          "alias", optional="recycles/{i}/entities/{omega}.attrs/alias"),
    Field("recycles/{i}/entities/{omega}/matrix", "float", ("rows", "cols"),
          "(row unit)/(column unit), or their product for normal and covariance blocks: see "
          "rows, cols", "the output", "matrix", finite=False),
    Field("recycles/{i}/entities/{omega}/rows", "str", ("rows",), "", "row labels "
          "(parameter names with units)", "rows"),
    Field("recycles/{i}/entities/{omega}/cols", "str", ("cols",), "", "column labels",
          "cols"),
)


# ---------------------------------------------------------------------------------------------
# The format reference
# ---------------------------------------------------------------------------------------------


def _versions(f: Field) -> str:
    if f.until is None:
        return "" if f.since == 1 else f"≥ {f.since}"
    return f"{f.since}" if f.since == f.until else f"{f.since}–{f.until}"


def _table(table: tuple[Field, ...]) -> list[str]:
    lines = ["| path | type | shape | units | versions | optional | content |",
             "|---|---|---|---|---|---|---|"]
    for f in table:
        shape = f"({', '.join(f.shape)})" if f.shape else ""
        optional = "" if not f.optional else "yes" if f.optional == f.path else \
            f"with `{f.optional}`"
        text = f.description.replace("|", "\\|")
        lines.append(f"| `{f.path}` | {f.dtype} | {shape} | {f.unit} | {_versions(f)} | "
                     f"{optional} | {text} |")
    return lines


def markdown(t13_version: int, t32_version: int) -> str:
    """The format reference of the tapes (``docs/reference/tapes.md``), from the tables."""
    return "\n".join([
        "# Tapes: T13 (TAPP I → TAPP III) and T32 (TAPP III → TAPP II)", "",
        "HDF5 files read and written through h5py. Generated from the layout tables of "
        "`tapp.io.tape.layout` (which the writers, the readers and their checks use) by "
        "`python -m tapp.io.reference docs/reference`: do not edit.", "",
        "Every dataset has a `units` attribute and, from T13 version 2 and in every T32, is "
        "chunked (whole rows) with a Fletcher-32 checksum; text, in datasets and attributes, "
        "is fixed-length UTF-8. The large datasets are compressed: T13 version 4 by LZ4 "
        "(HDF5 filter 32004: plain h5py reads them after `import hdf5plugin`), version 3 and "
        "T32 by gzip. Packed matrices (types factor and symmetric) store the upper triangle by "
        "rows (\"TR\", L = n_o(n_o+1)/2) or all n_o² entries (\"full\"), with attributes "
        "`packing`, `order` and `form` (\"factor\": M = KᵀK, K upper triangular; "
        "\"symmetric\"). Units: u_a is the unit of parameter a (`parameters/unit`); factors of "
        "normal matrices are in 1/u_b, of covariances in u_b. Writers write to a temporary "
        "file and rename it; readers reject a wrong format, version, shape, non-finite value "
        "or non-symmetric matrix naming the dataset.", "",
        f"## T13, version {t13_version}", "",
        "Symbols: n_o parameters x = [p; q] (n_p orbit parameters p), n_m miss parameters, "
        "n_ts stations, n_it records k = 1..n_it (record k covers (t_{k-1}, t_k] and is "
        "referred to the epoch t_j), n_pairs (record, station) pairs with data, n_passes "
        "passes, n_rules editing rules, K stochastic intervals, n_b burns, N raw rows. "
        "Versions 1 and 2 (still read, with a warning on their precision) carried the normal "
        "matrices `pairs/dJ`, `pairs/dJt` (and, version 2, `pairs/dJt_parts`) in place of the "
        "factors, version 1 without checksums and with variable-length text.", "",
        *_table(T13_LAYOUT), "",
        f"## T32, version {t32_version}", "",
        "Symbols: n_r recycles i' = 1..n_r (`{i}`), the systems s = common, fit, real "
        "(`{s}`), the recycle commands ω (`{omega}`) with their rows and cols. Every n_o × "
        "n_o matrix of a recycle is in x^k = [orbit at t_k; q], k that recycle's record "
        "index. Version 1 (still read, with a warning) stored the symmetric matrices "
        "themselves and no transition adjoint.", "",
        *_table(T32_LAYOUT), ""])


def sourced(obj: object, source: str) -> object:
    """The value at the dotted attribute path ``source`` of ``obj`` (None where the path is
    empty or passes through None: an absent optional part)."""
    if not source:
        return None
    for name in source.split("."):
        if obj is None:
            return None
        obj = getattr(obj, name)
    return obj


def build(cls: type, group: str, values: dict[str, object]) -> object:
    """An instance of the dataclass ``cls`` from values read by source (``group.field`` for
    each of its fields)."""
    return cls(**{f.name: values[f"{group}.{f.name}"] for f in fields(cls)})


def resolve(shape: tuple[str, ...], dims: dict[str, int]) -> tuple[int, ...] | None:
    """The shape in numbers: each symbol a number, a name of ``dims`` or ``name+1``; None
    when ``dims`` lacks a name (a shape checked elsewhere: ``L``, ``K+1``, ``rows``)."""
    out = []
    for symbol in shape:
        name, plus, one = symbol.partition("+")
        if name.isdigit():
            out.append(int(name))
        elif name in dims:
            out.append(dims[name] + (int(one) if plus else 0))
        else:
            return None
    return tuple(out)
