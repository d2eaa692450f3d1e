"""The TAPP III deck (TOML, one file per run): its layout, limits and schema, and reading it.

The deck holds the manual inputs I₃ of the seed (§1 a–i, Appendix A.1). Parameters are named
as on the tape and in the scenario (``"GM_moon_km3_s2"``, ``"GOLDSTONE.spin_radius_km"``:
one spelling, :mod:`tapp.dynamics.parameters`; the earlier ``"GM_moon"``, ``"dr_mars_x"``
are read with a warning naming the new one) or given by their 1-based position as in the
seed; times are T13 time indices (TOML integers, as the seed's POT/RET),
seconds from the tape epoch (floats) or UTC dates (strings), and must be T13 times. Layout::

    title = "..."
    [tape]                      # optional expectations checked against the tape; a deck
    iden = "DSN-LUNAR-2026-03-10"   # that gives parameters by position (numbers, σ lists,
    n_o = 23                    # matrices, permutations) must say which tape they refer to:
    # parameters = ["x_km", ...]  # its iden, or its parameter names in order
    [times]
    print = [1, 86400.0, "2026-03-14T02:05:58.384"]   # print output times (k = 0 always)
    recycle = [2, 3]            # recycle (midcourse) times
    print_output = true         # δ_PM
    recycle_print = true        # δ_P
    recycle_tape = true         # δ_T
    [commands]
    print = ["cov real orbit@current", "I; 0,-,pk; 1,2,fp"]   # either notation
    recycle = "standard"        # Table B-5's ROC, or a list
    [[stations_off]]            # time-station flags: no data from the station in the window
    station = "MADRID"          # name or number (a ΔDOR baseline: "GOLDSTONE-MADRID")
    start = 86400.0             # optional, default the first T13 time
    end = 172800.0              # optional, default the last
    [common]                    # common system: permutation P_c, n_c1, constraints K_c
    eliminated = ["..."]        # readable: these go last and are fixed in both worlds
    # permutation = [[10, 14], [12, "GM_km3_s2"]]   # seed coding: u(a) = v(b), a 1-based
    # n_c1 = 18
    constraints = [["a", "b", 0.5]]                 # x(a) <- x(a) - e x(b)
    [fit]                       # fit system: P_f (an extension), n_f1, K_f, a priori
    fixed = ["GM_moon_km3_s2"]  # readable; or permutation/n_f1 as the seed
    constraints = []
    stochastic = "ignore"       # the tape's stochastic accelerations: "estimate" | "ignore"
    manoeuvres = "ignore"       # the tape's execution errors: "estimate" | "ignore"
    [fit.apriori]
    sigma = { x_km = 1.0, "GM_moon_km3_s2" = 0.0 }  # σ = 0: held fixed; inf: no information
    # sigma = { "GM_moon_km3_s2" = 0.0, "*.rho_km" = 1e-3, "*" = 1.0 }  # patterns (below)
    # sigma = [1.0, 1.0, ...]   # positional over f1 (seed coding), or
    # normal = [[...], ...]     # the n_f1 x n_f1 normal matrix S₀
    [real]                      # real system: P_r, n_r1, K_r, a priori
    certain = []
    stochastic = "include"      # "include" | "ignore"
    manoeuvres = "include"      # "include" | "ignore"
    [real.apriori]
    sigma = { x_km = 1.0, "GM_moon_km3_s2" = 1e-4 }  # σ = 0: certain
    correlation = [["x_km", "y_km", 0.3]]
    # covariance = [[...]]      # the n_r1 x n_r1 covariance Λ₀
    [real.apriori.stations]     # (or [fit.apriori.stations]) station locations as 3 x 3 blocks
    file = "dsn.csv"            # optional: CSV or SINEX excerpt, relative to the deck
    station.GOLDSTONE = { sigma_m = [0.03, 0.03, 0.05], correlation = [0.1, 0.0, 0.2] }
    station.MADRID = { axes = "cylindrical", covariance_m2 = [[...], [...], [...]] }
    frame = { translation_m = [0.02, 0.02, 0.02], rotation_mas = [0.3, 0.3, 0.3] }
    [miss]
    partitions = { m1 = [0, 2], m2 = ["b_dot_t_km", "flight_time_s"] }  # [t, h] or names
    [budget]
    enabled = true
    groups = { "station locations" = ["GOLDSTONE.rho_km", "MADRID.*"] }
    [plots]
    partition = "p@current"     # σ against time of this set
    [output]
    frames = ["inertial", "ric"]    # also give orbit covariances in RIC axes

In the sigma-table form every parameter of the tape needs a σ in the fit world (a parameter
with σ = 0 is fixed, i.e. constrained) and in the real world (σ = 0: certain); the fit and
real permutations that put the fitted/uncertain parameters first are then built by keeping the
tape's order (stable). A key of a σ table may be a shell-style pattern of parameter names
(:func:`fnmatch.fnmatchcase`, with ``*``, ``?`` or ``[``; :data:`PATTERN_CHARS`):
``"*.zenith_wet_km"``, ``"eop.ut1_s.*"``, ``"*"``. It stands, at its place in the table,
for every parameter of the tape it matches, in tape order, that the table does not name
explicitly (by name or position: explicit keys win, so ``"*"`` after them gives the rest); it
must match at least one parameter, and two patterns that match a parameter not named
explicitly must give it the same σ. The table so expanded is what the rest of the binding
reads: a pattern that matches parameters whose a priori the world takes from elsewhere (the
tape's stochastic accelerations or execution errors, a station block below) gives them σ's,
refused as named ones would be. ``[budget.groups]`` takes patterns the same way: each stands
for the parameters it matches, in tape order, that its group does not already have.
Correlation triples, permutations, constraints and the fixed, certain and eliminated lists
take names and positions only. A priori σ's lie in :data:`SIGMA_RANGE` (the reason is given there);
fit normal matrices and real covariances given as matrices must have their diagonal in the
matching range, be symmetric and positive semi-definite, each entry on its own scale
√(a_ii a_jj); constraint coefficients are bounded by :data:`MAX_CONSTRAINT`.

Stochastic accelerations (parameters of kind "stochastic", defined on the tape by TAPP I's
``[stochastic]``: :mod:`tapp.estimation.gauss_markov`) take their a priori from the tape, not
from the σ tables: ``fit.stochastic = "estimate"`` puts them in the estimated set with the
a priori information P⁻¹ of their Gauss-Markov covariance P, ``"ignore"`` (the default) holds
them fixed at 0 (σ = 0); ``real.stochastic = "include"`` gives them the covariance P in the
real world, ``"ignore"`` (the default) makes them certain. So a filter that estimates them is
(estimate, include); one that considers them (the consider covariance of a filter that does
not estimate them: the classic optimistic-filter study) is (ignore, include); neither world
has them with (ignore, ignore); (estimate, ignore) is a filter that estimates what is not
there. Their a priori is generated in the σ-table form only (not with matrices given whole);
the σ tables and correlation triples must not name them (σ = 0 is accepted where they are
fixed), and the error budget counts them as one source, "stochastic accelerations".

Station locations may be given as full blocks in either world (``[fit.apriori.stations]``,
``[real.apriori.stations]``): per station the covariance of its Earth-fixed position in metres,
in ITRF x, y, z (``axes = "ecef"``) or in its cylindrical axes (spin radius, east arc r_s λ, z),
from a CSV file, a SINEX excerpt (:mod:`tapp.io.station_covariance`) or the deck, plus a
common-frame error (σ's of a Helmert translation, rotation and scale shared by all the stations
of the table) that correlates the complexes. They are mapped to the tape's location
parameters (km or (r_s km, lon rad, z km)) to first order at the tape's nominal locations
(:mod:`tapp.processor.station_apriori`) and complete the world's σ table, which must then give
these stations no σ; the correlation triples must not name them. The stations must be on the
tape with their location in q and in the world's set; a block must be symmetric positive
semi-definite (positive definite in the fit world, whose a priori information is its
inverse). The error budget counts them as one source, "station locations" (split by
``[budget.groups]``, the correlations between groups are one more source).

The execution errors of the burns TAPP I flew (parameters of kind "execution", defined on the
tape by the scenario's ``[[manoeuvre]]`` tables: :mod:`tapp.dynamics.manoeuvres`, Gates'
model :mod:`tapp.dynamics.gates`) are generated the same way, with ``fit.manoeuvres`` and
``real.manoeuvres``: their a priori is N(0, σ²) of each, independent, the σ's of the tape.
``fit.manoeuvres = "estimate"`` reconstructs the manoeuvres (the fit estimates their errors),
(ignore, include) considers them, (ignore, ignore) leaves them out of both worlds; the error
budget counts each burn as a source of its own, ``manoeuvre NAME``.

A deck is bound to a T13 tape, these rules checked, by :mod:`tapp.processor.deck_bind`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, ClassVar, Literal

from pydantic import Field

from tapp.io.schema import InfFloat, Schema, load
from tapp.processor.commands import command_language_markdown

Ref = int | str
TimeRef = int | float | str
#: Time coincidence with a T13 time, s (tape times are stored to the microsecond).
TIME_MATCH_S = 1e-3
#: Largest negative eigenvalue of an a priori matrix scaled to a unit diagonal (a correlation
#: matrix) taken as rounding (:func:`tapp.estimation.factors.scaled_min_eigenvalue`).
PSD_TOL = 1e-10
#: Largest relative asymmetry |a_ij − a_ji| / √(a_ii a_jj) of an a priori matrix taken as
#: rounding (:func:`tapp.io.tape.packing.symmetry_defect`).
SYMMETRY_TOL = 1e-12
#: Finite a priori σ's must lie in this range (any unit). Not for lack of doubles (σ² and
#: 1/σ² are finite up to 1e154), but for what the programs do with them: a covariance is
#: mapped by partials and transitions, squared into Gram matrices, and TAPP II raises its
#: Δv's to the 4th power for the sampling error of a variance. With σ = 1e149 the LEO deck's
#: Gram matrices overflowed (NaN in the JSON, variances printed as 0). At σ = 1e30 on every
#: parameter, on the shipped tapes, every output stays finite with orders of magnitude to
#: spare (tests/tapp/processor/test_deck_limits.py); and no quantity of these programs has a
#: σ beyond 1e30 or below 1e-30 in any unit they use (km, km/s, s, rad, km³/s²).
SIGMA_RANGE = (1e-30, 1e30)
#: Diagonal entries of a priori matrices given whole: a covariance σ² and a normal matrix
#: 1/σ², for σ in :data:`SIGMA_RANGE` (0: certain, or no information).
COVARIANCE_RANGE = (SIGMA_RANGE[0] ** 2, SIGMA_RANGE[1] ** 2)
NORMAL_RANGE = (SIGMA_RANGE[1] ** -2, SIGMA_RANGE[0] ** -2)
#: Largest |e| of a constraint x(a) <- x(a) − e x(b), (unit of a)/(unit of b). e σ_b is a σ of
#: the constrained system, and the links of two systems compose (the common world's, then the
#: fit or real world's): e² σ_b stays within 1e50 for σ_b in SIGMA_RANGE, leaving the 1e10
#: that transitions may add below the tapes' bound (:data:`tapp.io.tape.checks.MAX_MAGNITUDE`;
#: the Table D-1 deck at σ = 1e30 and e = 1e20 wrote a factor of 1e70). The seed's
#: coefficients are ratios of σ's (Table D-1: up to 3e5 km per unit of J2).
MAX_CONSTRAINT = 1e10
#: Most commands in a list (``commands.print``, ``commands.recycle``): the seed's Table B-5
#: has 16 recycle commands; 10,000 print commands took 71 s, 3.3 GB and a 507 MB JSON.
MAX_COMMANDS = 500
#: Most times in ``times.print`` or ``times.recycle``, and windows in ``stations_off``:
#: each is matched against the tape's times (a tape has 10 to 1,000 of them).
MAX_TIMES = 10_000
#: Most output entities of a run (each print time by the print commands, each recycle by the
#: recycle commands), and most numbers in their matrices. Measured on the LEO tape (n_o =
#: 38, 2 shared cores): 2,000 real-world orbit covariances (6 x 6, with error budgets) ran in
#: 8 s with 330 MB and wrote a 24 MB JSON and an 18 MB O3; 1,000,000 numbers (692 covariances
#: of the 38 parameters) 16 s, 730 MB, 58 MB and 109 MB: the bound on numbers. Half of it
#: refused make bench's n_o = 100 run (237 entities of up to 100 x 100, 868,000 numbers).
MAX_ENTITIES = 2_000
MAX_ENTITY_NUMBERS = 1_000_000
#: The characters that make a σ-table key or a ``budget.groups`` entry a shell-style pattern
#: of parameter names (:func:`fnmatch.fnmatchcase`: ``*`` any text, ``?`` one character,
#: ``[seq]`` one of seq), unless the key is itself a parameter name of the tape.
PATTERN_CHARS = frozenset("*?[")
#: The seed's nominal optional miss partitions (Appendix A.1), (tail, head).
NOMINAL_MISS = {"m1": (0, 6), "m2": (0, 3), "m3": (3, 6), "m4": (6, 12), "m5": (12, 18)}


class TapeExpect(Schema):
    """``[tape]``: what the deck expects of the tape, checked when it is bound. A deck that
    gives parameters by position must say which tape they refer to: ``iden`` or
    ``parameters``."""

    iden: str | None = Field(None, description="The tape's identification (the scenario's "
                             "iden).")
    n_o: int | None = Field(None, description="The tape's number of parameters.")
    parameters: list[str] | None = Field(None, description="The tape's parameter names in "
                                         "order, which the deck's positions refer to.")


_TIMES = ("T13 times: indices (integers), seconds from the tape epoch (numbers) or UTC dates "
          "(text)")
_PERMUTATION = ("The seed's coding of the permutation: pairs [a, b], position a (1-based) "
                "takes parameter b (name or position).")
_CONSTRAINTS = "Triples [a, b, e]: x(a) <- x(a) - e x(b) (parameters by name or position)."


class Times(Schema):
    """``[times]``: when to print and when to recycle (midcourse times), and the flags."""

    print: Annotated[list[TimeRef], Field(max_length=MAX_TIMES)] = Field(
        [], description=f"Print output times, {_TIMES}; the epoch (k = 0) is always printed.")
    recycle: Annotated[list[TimeRef], Field(max_length=MAX_TIMES)] = Field(
        [], description=f"Recycle (midcourse) times, {_TIMES}.")
    print_output: bool = Field(True, description="Print at the print times (the seed's δ_PM).")
    recycle_print: bool = Field(True, description="Print at the recycle times (δ_P).")
    recycle_tape: bool = Field(True, description="Write the recycle outputs to the T32 tape "
                               "(δ_T).")


class Commands(Schema):
    """``[commands]``: the entities printed and the recycle commands."""

    print: Annotated[list[str], Field(max_length=MAX_COMMANDS)] = Field(
        [], description="Print commands, in the seed's notation (\"I; 0,-,pk; 1,2,fp\") or as "
        "aliases (\"cov real orbit@current\").")
    recycle: Annotated[list[str], Field(max_length=MAX_COMMANDS)] | Literal["standard"] = Field(
        "standard", description="Recycle commands, or \"standard\": the seed's Table B-5 list.")


class StationsOff(Schema):
    """``[[stations_off]]``: a time-station flag: no data from a station in a window."""

    station: Ref = Field(description="The station, by name or number (a ΔDOR baseline by "
                         "its name A-B: its ΔDOR only).")
    start: TimeRef | None = Field(None, description=f"Start of the window ({_TIMES}); default: "
                                  "the first T13 time.")
    end: TimeRef | None = Field(None, description="End of the window; default: the last T13 "
                                "time.")


class Common(Schema):
    """``[common]``: the common system: a permutation P_c with n_c1, and constraints K_c."""

    n_c1: int | None = Field(None, description="Parameters kept (the rest are eliminated); "
                             "with permutation.")
    permutation: list[list[Ref]] = Field([], description=_PERMUTATION)
    eliminated: list[Ref] = Field([], description="Parameters moved last and fixed in both "
                                  "worlds (the readable form of permutation and n_c1).")
    constraints: list[list[Ref | float]] = Field([], description=_CONSTRAINTS)


class StationBlock(Schema):
    """``[<world>.apriori.stations.station.NAME]``: the covariance of one station's position
    (m), in its ``axes``: σ's with correlations, or the 3 x 3 matrix."""

    axes: Literal["ecef", "cylindrical"] = Field(
        "ecef", description="\"ecef\": Earth-fixed (ITRF) x, y, z; \"cylindrical\": the "
        "station's spin radius, east arc along the parallel (r_s λ) and z along the spin axis.")
    sigma_m: Annotated[list[float], Field(min_length=3, max_length=3)] | None = Field(
        None, description="σ along the three axes, m.")
    correlation: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        [0.0, 0.0, 0.0], description="Correlations [ρ12, ρ13, ρ23] of the three axes (with "
        "sigma_m).")
    covariance_m2: list[list[float]] | None = Field(
        None, description="The 3 x 3 covariance along the axes (instead of sigma_m).",
        json_schema_extra={"unit": "m²"})


class FrameError(Schema):
    """``[<world>.apriori.stations.frame]``: a common-frame error (a 7-parameter Helmert
    transformation shared by every station of the table, independent components): it
    correlates the stations, e.g. the complexes of a network surveyed in one frame."""

    translation_m: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        [0.0, 0.0, 0.0], description="σ of the translation along ITRF x, y, z, m.")
    rotation_mas: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        [0.0, 0.0, 0.0], description="σ of the rotation about ITRF x, y, z.",
        json_schema_extra={"unit": "mas"})
    scale_ppb: float = Field(0.0, description="σ of the scale.",
                             json_schema_extra={"unit": "ppb"})


class StationsApriori(Schema):
    """``[<world>.apriori.stations]``: the a priori of station locations as full 3 x 3 blocks
    of their Earth-fixed positions (m), from a file and/or inline, with a common-frame error
    that correlates the stations; mapped to the tape's location parameters to first order at
    its nominal locations. The world's σ table then gives no σ for these stations."""

    file: str | None = Field(None, description="A station covariance file, relative to the "
                             "deck: CSV (.csv) or a SINEX excerpt (.snx, .sinex) "
                             "(tapp.io.station_covariance).")
    station: dict[str, StationBlock] = Field({}, description="Per station of the tape (by "
                                             "name): its covariance.")
    frame: FrameError = Field(FrameError(), description="The common-frame error of all "
                              "the stations of the table.")


class FitApriori(Schema):
    """``[fit.apriori]``: the fit world's a priori information: σ's or a normal matrix."""

    sigma: dict[str, InfFloat] | list[InfFloat] | None = Field(
        None, description="σ by parameter name (every parameter) or position, or by a "
        "shell-style pattern of names (*, ?, [...]) for the parameters it matches that are not "
        "named explicitly; or a list over f1 (the seed's coding); 0: held fixed, inf: no "
        "information.", json_schema_extra={"unit": "the parameter's"})
    normal: list[list[float]] | None = Field(None, description="The n_f1 x n_f1 a priori "
                                             "normal matrix S₀ (symmetric).")
    stations: StationsApriori | None = Field(None, description="Station locations as full "
                                             "blocks (with sigma as a table; their σ's are "
                                             "not in it).")


class Fit(Schema):
    """``[fit]``: the fit system: permutation P_f with n_f1, constraints K_f, a priori."""

    n_f1: int | None = Field(None, description="Parameters the fit estimates; with "
                             "permutation.")
    permutation: list[list[Ref]] = Field([], description=_PERMUTATION)
    fixed: list[Ref] = Field([], description="Parameters the fit holds fixed (the readable "
                             "form of permutation and n_f1).")
    constraints: list[list[Ref | float]] = Field([], description=_CONSTRAINTS)
    stochastic: Literal["estimate", "ignore"] = Field(
        "ignore", description="The tape's stochastic accelerations: \"estimate\" them with "
        "the a priori information of their Gauss-Markov covariance, or \"ignore\" them (held "
        "fixed at 0; with real.stochastic = \"include\" they are then considered).")
    manoeuvres: Literal["estimate", "ignore"] = Field(
        "ignore", description="The execution errors of the tape's burns: \"estimate\" them "
        "(manoeuvre reconstruction) with the a priori of their Gates σ's, or \"ignore\" them "
        "(held fixed at 0; with real.manoeuvres = \"include\" they are then considered).")
    apriori: FitApriori = Field(FitApriori(), description="The fit world's a priori.")


class RealApriori(Schema):
    """``[real.apriori]``: the real world's a priori covariance: σ's with correlations, or a
    matrix."""

    sigma: dict[str, float] | list[float] | None = Field(
        None, description="σ by parameter name (every parameter) or position, or by a "
        "shell-style pattern of names (*, ?, [...]) for the parameters it matches that are not "
        "named explicitly; or a list over r1; 0: certain.",
        json_schema_extra={"unit": "the parameter's"})
    correlation: list[list[Ref | float]] = Field(
        [], description="Triples [a, b, ρ]: the correlation of parameters a and b.")
    covariance: list[list[float]] | None = Field(
        None, description="The n_r1 x n_r1 a priori covariance Λ₀ (positive semi-definite).")
    stations: StationsApriori | None = Field(None, description="Station locations as full "
                                             "blocks (with sigma as a table; their σ's are "
                                             "not in it).")


class Real(Schema):
    """``[real]``: the real system: permutation P_r with n_r1, constraints K_r, a priori."""

    n_r1: int | None = Field(None, description="Uncertain parameters; with permutation.")
    permutation: list[list[Ref]] = Field([], description=_PERMUTATION)
    certain: list[Ref] = Field([], description="Parameters known exactly in the real world "
                               "(the readable form of permutation and n_r1).")
    constraints: list[list[Ref | float]] = Field([], description=_CONSTRAINTS)
    stochastic: Literal["include", "ignore"] = Field(
        "ignore", description="The tape's stochastic accelerations: \"include\" them with "
        "their Gauss-Markov covariance, or \"ignore\" them (certain, 0).")
    manoeuvres: Literal["include", "ignore"] = Field(
        "ignore", description="The execution errors of the tape's burns: \"include\" them "
        "with their Gates σ's, or \"ignore\" them (certain, 0).")
    apriori: RealApriori = Field(RealApriori(), description="The real world's a priori.")


class Miss(Schema):
    """``[miss]``: optional partitions of the miss parameters."""

    partitions: dict[str, list[Ref]] = Field(
        {}, description="By name (m1 ... m5 as the seed's): [tail, head] positions, or the "
        "names of miss quantities.")


class BudgetTable(Schema):
    """``[budget]``: the error budget of every printed real-world covariance."""

    enabled: bool = Field(True, description="Print error budgets.")
    groups: dict[str, list[Ref]] = Field(
        {}, description="Named groups of parameters (names, positions, or shell-style "
        "patterns of names: *, ?, [...], each for the parameters it matches) whose a priori "
        "errors count as one source.")


class Plots(Schema):
    """``[plots]``: what ``--plots`` draws."""

    partition: str = Field("p@current", description="The set whose σ are plotted against "
                           "time.")


class Output(Schema):
    """``[output]``: the axes orbit covariances are given in."""

    frames: list[Literal["inertial", "ric"]] = Field(
        ["inertial"], description="\"inertial\" (always: the tape's frame, EME2000 or GCRS) "
        "and optionally \"ric\": every covariance of an orbit set (a set that begins with "
        "the 6 position and velocity components at one time, e.g. orbit@current, r1@recycle, "
        "pk), with its σ, correlations and error budget, is also given in the radial R = r/|r|, "
        "cross-track C = (r x v)/|r x v| and in-track I = C x R axes of the nominal state at "
        "that time as the tape stores it (Earth-centred; near the Moon these are still the "
        "Earth's axes) (velocity components along the same axes, without the ω x r term of "
        "rotating axes), the σ history gets the RIC σ of the orbit at each print and recycle "
        "time, and --plots draws them (sigma_ric.png, sigma_ric.csv).")


class Deck(Schema):
    """The deck file (module docstring); validated strictly, unknown keys are errors."""

    #: What the reference page adds after the tables (:func:`tapp.io.reference.markdown`).
    reference_appendix: ClassVar[str] = command_language_markdown()

    title: str = Field("", description="Free text, printed in the O3 heading.")
    tape: TapeExpect = Field(TapeExpect(), description="Expectations checked against the tape.")
    times: Times = Field(Times(), description="Print and recycle times.")
    commands: Commands = Field(Commands(), description="Print and recycle commands.")
    stations_off: Annotated[list[StationsOff], Field(max_length=MAX_TIMES)] = Field(
        [], description="Time-station flags.")
    common: Common = Field(Common(), description="The common system.")
    fit: Fit = Field(description="The fit world: what the orbit determination assumes.")
    real: Real = Field(description="The real world: what is true.")
    miss: Miss = Field(Miss(), description="Miss partitions.")
    budget: BudgetTable = Field(BudgetTable(), description="Error budgets.")
    plots: Plots = Field(Plots(), description="Plots.")
    output: Output = Field(Output(), description="Output axes.")


def read_deck(path: Path | str) -> Deck:
    """Read and validate a deck file (errors name the file and the field)."""
    return load(Deck, path)


def deck_json(deck: Deck) -> str:
    """The deck as JSON (provenance on the T32 tape)."""
    return json.dumps(deck.model_dump(mode="json"), sort_keys=True)


__all__ = ["Deck", "deck_json", "read_deck"]
