"""A TAPP III deck bound to a T13 tape: a :class:`~tapp.processor.plan.Plan`.

The deck's names, positions and times are resolved against the tape's header into the
systems (permutations, constraints), the a priori of both worlds (σ tables with their
patterns, matrices, the generated kinds, station blocks), the commands, the time-station flags
and the budget groups, each checked against the rules that :mod:`tapp.processor.deck` states;
every error names the deck file and the field.
"""

from __future__ import annotations

from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path

import numpy as np

from tapp.constants import SECONDS_PER_DAY
from tapp.dynamics.parameters import model_parameter
from tapp.errors import InputError
from tapp.estimation.factors import scaled_min_eigenvalue
from tapp.estimation.gauss_markov import KIND as STOCHASTIC
from tapp.frames.time import parse_epoch
from tapp.io.station_covariance import (
    StationCovariance,
    block_m2,
    check_covariance,
    read_station_covariance,
)
from tapp.io.tape.packing import symmetry_defect
from tapp.io.tape.t13 import T13Header
from tapp.measurements import STATION_PARAMETER_NAMES
from tapp.processor.commands import ROC, Command, Side, parse_command
from tapp.processor.deck import (
    COVARIANCE_RANGE,
    MAX_CONSTRAINT,
    MAX_ENTITIES,
    MAX_ENTITY_NUMBERS,
    NOMINAL_MISS,
    NORMAL_RANGE,
    PATTERN_CHARS,
    PSD_TOL,
    SIGMA_RANGE,
    SYMMETRY_TOL,
    TIME_MATCH_S,
    Deck,
    StationsApriori,
)
from tapp.processor.links import Constraint, Permutation
from tapp.processor.plan import Plan, StationOff
from tapp.processor.representations import Systems
from tapp.processor.station_apriori import PER_PPB, RAD_PER_MAS, parameter_covariance, position_km


@dataclass(frozen=True, slots=True, eq=False)
class _Generated:
    """Parameters of one kind whose a priori the tape defines (:mod:`tapp.processor.deck`):
    the deck's ``fit.<key>`` and ``real.<key>`` turn them on, their σ's and correlations are
    generated; or a world's station-location block, which the deck's
    ``<world>.apriori.stations`` gives (key "apriori.stations", :meth:`_Binder._station_block`).

    Attributes
    ----------
    key : the deck's key in [fit] and [real] ("stochastic", "manoeuvres"), or
        "apriori.stations".
    plural, one : what they are, for messages ("stochastic accelerations", "stochastic
        acceleration"); ``article`` goes before ``one`` ("a", "an").
    correlated : why the deck gives them no correlations.
    names : their names, in the tape's order (a station block: in its rows' order).
    covariance, information : their a priori P (n, n) and P⁻¹, in their units squared
        (None: a real world's station block, whose inverse no one needs).
    sources : the error budget's sources among them: (label, names).
    """

    key: str
    plural: str
    one: str
    article: str
    correlated: str
    names: tuple[str, ...]
    covariance: np.ndarray
    information: np.ndarray | None
    sources: tuple[tuple[str, tuple[str, ...]], ...]


def _generated(header: T13Header, names: tuple[str, ...]) -> tuple[_Generated, ...]:
    """The generated kinds of a tape: its stochastic accelerations, its burns' execution
    errors (each when it has them)."""
    kinds = tuple(header.parameters.kind)
    out = []
    sto = header.stochastic
    mine = tuple(n for n, k in zip(names, kinds, strict=True) if k == STOCHASTIC)
    if sto is not None and mine:
        out.append(_Generated("stochastic", "stochastic accelerations",
                              "stochastic acceleration", "a", "their correlations are the "
                              "Gauss-Markov process's", mine, sto.covariance(),
                              sto.information(), (("stochastic accelerations", mine),)))
    burns = header.manoeuvres
    params = [(b.name, p) for b in burns for p in b.parameters()]
    if params:
        variance = np.array([sigma for _, (_, _, sigma) in params]) ** 2
        out.append(_Generated(
            "manoeuvres", "execution errors", "execution error", "an", "Gates' errors are "
            "independent", tuple(n for _, (n, _, _) in params), np.diag(variance),
            np.diag(1.0 / variance), tuple((f"manoeuvre {b.name}", tuple(
                n for n, _, _ in b.parameters())) for b in burns if b.parameters())))
    return tuple(out)


#: The mode of each world that puts a generated kind in it.
_ON = {"fit": "estimate", "real": "include"}
#: The deck's keys of the generated kinds.
_GENERATED_KEYS = ("stochastic", "manoeuvres")


class _Binder:
    """Resolves the deck's names, positions and times against a T13 header."""

    def __init__(self, deck: Deck, header: T13Header, source: str):
        self.deck, self.h, self.source = deck, header, source
        self.names = tuple(header.parameters.name)
        self.n_o, self.n_p = len(self.names), int(header.n_p)
        self.times = np.asarray(header.records.times_s, dtype=float)
        #: Fields that refer to parameters by position (checked in :meth:`_check_positions`).
        self.positional: list[str] = []
        #: The parameters whose a priori the tape defines, by kind.
        self.generated = _generated(header, self.names)
        #: The station-location block of each world that has one (:meth:`_station_block`).
        self.station_blocks: dict[str, _Generated] = {}
        #: Each world's σ table with its patterns expanded, once read (:meth:`sigma_table`).
        self._sigma_tables: dict[str, dict[str, float] | list[float] | None] = {}

    def fail(self, field: str, expected: str, got: object = None) -> InputError:
        return InputError(self.source, field, expected, got)

    # --- references --------------------------------------------------------------------------

    def position(self, ref: object, order: list[str], field: str) -> int:
        """0-based position of a parameter in ``order`` (a name) or a 1-based index."""
        if isinstance(ref, bool) or not isinstance(ref, int | str):
            raise self.fail(field, "a parameter name or 1-based position", ref)
        if isinstance(ref, str) and ref.isdigit():
            ref = int(ref)
        if isinstance(ref, int):
            if not 1 <= ref <= self.n_o:
                raise self.fail(field, f"a position 1..{self.n_o}", ref)
            self.positional.append(field)
            return ref - 1
        ref = self._tape_name(ref, field)
        bare = [n.rstrip("'") for n in order]
        if ref not in bare:
            raise self.fail(field, "a parameter name of the tape (" + ", ".join(self.names)
                            + ")", ref)
        return bare.index(ref)

    def _tape_name(self, ref: str, field: str) -> str:
        """``ref``, or the tape's name of the model parameter it names in an earlier spelling
        (``GM_moon`` for ``GM_moon_km3_s2``: :mod:`tapp.dynamics.parameters`, whose warning
        names ``field``)."""
        if ref in self.names:
            return ref
        found = model_parameter(ref, self.source, field)
        return ref if found is None else found.canonical

    def time_index(self, value: object, field: str) -> int:
        """T13 time index of an index (int), seconds (float) or UTC date (string)."""
        if isinstance(value, bool):
            raise self.fail(field, "a T13 index, seconds or a UTC date", value)
        if isinstance(value, int):
            if not 0 <= value < self.times.size:
                raise self.fail(field, f"a T13 time index 0..{self.times.size - 1}", value)
            return value
        if isinstance(value, str):
            try:
                when = parse_epoch(value, self.source)
            except InputError as exc:
                raise self.fail(field, exc.expected, value) from None
            epoch = self.h.epoch
            t = ((when.jd_whole - epoch.jd_whole) + (when.jd_fraction - epoch.jd_fraction)) \
                * SECONDS_PER_DAY
        else:
            t = float(value)
        i = int(np.argmin(np.abs(self.times - t)))
        if abs(self.times[i] - t) > TIME_MATCH_S:
            near = ", ".join(f"{self.times[j]:.3f}" for j in
                             range(max(0, i - 1), min(self.times.size, i + 2)))
            raise self.fail(field, f"a T13 time of the tape (nearest: {near} s)", value)
        return i

    def time_list(self, values: list, field: str, *, first: int) -> tuple[int, ...]:
        out = sorted({self.time_index(v, f"{field}[{i}]") for i, v in enumerate(values)})
        if out and out[0] < first:
            raise self.fail(field, f"times after the injection (index >= {first})", out[0])
        return tuple(out)

    # --- systems ------------------------------------------------------------------------------

    def _permutation(self, pairs: list, order: list[str], field: str, lo: int, hi: int
                     ) -> Permutation | None:
        if not pairs:
            return None
        self.positional.append(field)
        out = []
        for i, pair in enumerate(pairs):
            if len(pair) != 2 or not isinstance(pair[0], int) or isinstance(pair[0], bool):
                raise self.fail(f"{field}[{i}]", "a pair [a, b]: position a (1-based), "
                                "parameter b (name or position)", pair)
            out.append((pair[0] - 1, self.position(pair[1], order, f"{field}[{i}]")))
        link = Permutation.from_pairs(out, self.n_o, self.n_p, f"{self.source}: {field}")
        moved = set(link.target.tolist())
        if moved and (min(moved) < lo or max(moved) >= hi):
            raise self.fail(field, f"positions within {lo + 1}..{hi}",
                            sorted(m + 1 for m in moved))
        return link

    def _partition_last(self, refs: list, order: list[str], field: str, lo: int, hi: int
                        ) -> Permutation | None:
        """Permutation moving ``refs`` to the end of rows lo..hi-1, others keeping order."""
        moved = [self.position(r, order, f"{field}[{i}]") for i, r in enumerate(refs)]
        for m, r in zip(moved, refs, strict=True):
            if not lo <= m < hi:
                raise self.fail(field, f"parameters at positions {lo + 1}..{hi} (constants "
                                "of this set; the orbit is never fixed)", r)
        if len(set(moved)) != len(moved):
            raise self.fail(field, "each parameter once", refs)
        keep = [i for i in range(lo, hi) if i not in moved]
        new = keep + moved
        pairs = [(lo + a, b) for a, b in enumerate(new) if lo + a != b]
        return Permutation.from_pairs(pairs, self.n_o, self.n_p, field) if pairs else None

    def _constraints(self, triples: list, order: list[str], field: str) -> Constraint | None:
        if not triples:
            return None
        out = []
        for i, tr in enumerate(triples):
            where = f"{field}[{i}]"
            if len(tr) != 3 or isinstance(tr[2], bool) or not isinstance(tr[2], int | float):
                raise self.fail(where, "a triple [a, b, e]: x(a) <- x(a) - e x(b)", tr)
            if not abs(tr[2]) <= MAX_CONSTRAINT:
                raise self.fail(where, f"a coefficient |e| <= {MAX_CONSTRAINT:g} (e σ_b is a σ "
                                "of the constrained system)", tr[2])
            out.append((self.position(tr[0], order, where), self.position(tr[1], order, where),
                        float(tr[2])))
        return Constraint.from_triples(out, self.n_o, self.n_p, f"{self.source}: {field}")

    def _count(self, given: int | None, derived: int, lo: int, hi: int, field: str) -> int:
        n = derived if given is None else given
        if given is not None and given != derived and derived != hi:
            raise self.fail(field, f"{derived} (as the list of fixed parameters gives)", given)
        if not lo <= n <= hi:
            raise self.fail(field, f"a number in {lo}..{hi}", n)
        return n

    def systems(self) -> tuple[Systems, np.ndarray, np.ndarray]:
        d = self.deck
        names = list(self.names)
        com = d.common
        if com.permutation and com.eliminated:
            raise self.fail("common", "either permutation (with n_c1) or eliminated")
        p_c = (self._permutation(com.permutation, names, "common.permutation", self.n_p,
                                 self.n_o)
               or self._partition_last(com.eliminated, names, "common.eliminated", self.n_p,
                                       self.n_o))
        n_c1 = self._count(com.n_c1, self.n_o - len(com.eliminated), self.n_p, self.n_o,
                           "common.n_c1")
        order_c = p_c.move(names) if p_c else names
        k_c = self._constraints(com.constraints, order_c, "common.constraints")
        fit_sigma_fixed = self._sigma_zero(self.sigma_table("fit"), order_c, n_c1,
                                           "fit.apriori")
        p_f, n_f1 = self._world(d.fit.permutation, d.fit.fixed, fit_sigma_fixed, d.fit.n_f1,
                                order_c, n_c1, "fit", "fixed", "n_f1")
        order_f = p_f.move(order_c) if p_f else order_c
        k_f = self._constraints(d.fit.constraints, order_f, "fit.constraints")
        real_sigma_certain = self._sigma_zero(self.sigma_table("real"), order_c, n_c1,
                                              "real.apriori")
        p_r, n_r1 = self._world(d.real.permutation, d.real.certain, real_sigma_certain,
                                d.real.n_r1, order_c, n_c1, "real", "certain", "n_r1")
        order_r = p_r.move(order_c) if p_r else order_c
        k_r = self._constraints(d.real.constraints, order_r, "real.constraints")
        miss = self.miss_partitions()
        sy = Systems(self.n_o, self.n_p, n_c1, n_f1, n_r1, self.names, len(self.h.miss.name),
                     p_c, k_c, p_f, k_f, p_r, k_r, miss)
        return sy, self.fit_normal(order_f, n_f1), self.real_covariance(order_r, n_r1)

    def _on(self, world: str, kind: _Generated) -> bool:
        """Whether the deck puts the generated ``kind`` in ``world``."""
        return getattr(getattr(self.deck, world), kind.key) == _ON[world]

    def _world(self, perm: list, listed: list, from_sigma: list, n_given: int | None,
               order: list[str], n_c1: int, world: str, key: str, count: str
               ) -> tuple[Permutation | None, int]:
        """The world's permutation and n_1; the generated kinds the world ignores join the
        fixed (fit) or certain (real) set."""
        common = [name.rstrip("'") for name in order[:n_c1]]
        off = [g for g in self.generated if not self._on(world, g)
               and any(n in common for n in g.names)]
        generated = [n for g in off for n in g.names if n in common]
        if perm and (listed or from_sigma or generated):
            raise self.fail(world, f"either permutation (with {count}) or {key} / σ = 0"
                            + "".join(f" / {world}.{g.key} = \"ignore\"" for g in off))
        if listed and from_sigma and sorted(map(str, listed)) != sorted(map(str, from_sigma)):
            raise self.fail(f"{world}.{key}", f"the parameters with σ = 0 in {world}.apriori",
                            listed)
        refs = list(listed or from_sigma)
        refs += [n for n in generated if n not in map(str, refs)]
        if perm:
            return (self._permutation(perm, order, f"{world}.permutation", self.n_p, n_c1),
                    self._count(n_given, n_c1, self.n_p, n_c1, f"{world}.{count}"))
        link = self._partition_last(refs, order, f"{world}.{key}", self.n_p, n_c1)
        return link, self._count(n_given, n_c1 - len(refs), self.n_p, n_c1, f"{world}.{count}")

    # --- a priori -----------------------------------------------------------------------------

    def _named(self, key: str) -> str:
        """The name a σ-table key stands for: the parameter at a 1-based position on the tape
        (the standard order), else the key itself."""
        return self.names[int(key) - 1] if key.isdigit() and 1 <= int(key) <= self.n_o else key

    def _key(self, key: str, field: str) -> str:
        """A σ-table key: a name, or a 1-based position on the tape (the standard order)."""
        name = self._named(key)
        if name != key:
            self.positional.append(f"{field}.sigma.{key}")
        return name

    def _is_pattern(self, ref: object) -> bool:
        """Whether a σ-table key or budget-group entry is a pattern of parameter names (it has
        :data:`PATTERN_CHARS`; a parameter name of the tape is never one)."""
        return (isinstance(ref, str) and not PATTERN_CHARS.isdisjoint(ref)
                and ref not in self.names)

    def _matching(self, pattern: str, field: str) -> list[str]:
        """The tape's parameter names ``pattern`` matches (:func:`fnmatch.fnmatchcase`), in
        tape order; a pattern that matches none is refused (a typo, or a deck for another
        tape, would otherwise pass silently)."""
        out = [name for name in self.names if fnmatchcase(name, pattern)]
        if not out:
            raise self.fail(field, "a pattern that matches at least one parameter of the "
                            "tape (" + ", ".join(self.names) + ")", pattern)
        return out

    def sigma_table(self, world: str) -> dict[str, float] | list[float] | None:
        """The σ's of ``world``'s a priori (``{world}.apriori.sigma``) as every part of the
        binding reads them: a table with its patterns expanded (computed once; the deck is
        left as given), a list or None as given.

        A key with pattern characters stands, at its place in the table, for the tape's
        parameters it matches (in tape order) that the table does not name explicitly, by
        name or position: explicit keys win. A parameter matched by several patterns takes
        the first one's place, and they must give it the same σ."""
        if world not in self._sigma_tables:
            self._sigma_tables[world] = self._expand_sigma(
                getattr(self.deck, world).apriori.sigma, f"{world}.apriori.sigma")
        return self._sigma_tables[world]

    def _expand_sigma(self, sigma, field: str) -> dict[str, float] | list[float] | None:
        """A σ table with its patterns expanded (:meth:`sigma_table`); a list or None as is."""
        if not isinstance(sigma, dict):
            return sigma
        named = {key: self._tape_name(key, f"{field}.{key}") for key in sigma
                 if not self._is_pattern(key)}
        explicit = {self._named(key) for key in named.values()}
        out: dict[str, float] = {}
        origin: dict[str, str] = {}
        for key, value in sigma.items():
            if key in named:
                out[named[key]] = value
                continue
            for name in self._matching(key, f"{field}.{key}"):
                if name in explicit:
                    continue
                if name not in origin:
                    out[name], origin[name] = value, key
                elif out[name] != value:
                    raise self.fail(f"{field}.{key}", f"patterns that give {name} one σ, or "
                                    f"{name} named explicitly (ambiguous: it matches "
                                    f"{origin[name]!r} with σ = {out[name]:g} and {key!r})",
                                    value)
        return out

    def _sigma_zero(self, sigma, order: list[str], n_c1: int, field: str) -> list[str]:
        """Names with σ = 0 in a σ table that covers the common parameters (readable form)."""
        if not isinstance(sigma, dict):
            return []
        zero = []
        for key, value in sigma.items():
            pos = self.position(self._key(key, field), order, f"{field}.sigma.{key}")
            if value == 0 and pos < n_c1:
                zero.append(order[pos].rstrip("'"))
        return zero

    def _generated_blocks(self, order: list[str], n1: int, field: str, world: str, sigma
                          ) -> list[tuple[list[int], _Generated]]:
        """Positions in ``order`` of each generated kind the world has (``{world}.<key>``
        on), with the kind, after checking the σ table gives them no σ (their a priori is
        the tape's) and that they are in the world's set."""
        out = []
        for g in self.generated:
            if not self._on(world, g):
                continue
            on = _ON[world]
            if not isinstance(sigma, dict):
                raise self.fail(f"{field}.sigma", f"a σ table with {world}.{g.key} = \"{on}\" "
                                f"(the block of the {g.plural} is generated; no list or matrix)")
            given = [k for k in sigma if self._key(k, field) in g.names]
            if given:
                raise self.fail(f"{field}.sigma.{given[0]}", f"no σ for {g.article} {g.one} "
                                f"(its a priori comes from the tape with {world}.{g.key} = "
                                f"\"{on}\")", sigma[given[0]])
            bare = [n.rstrip("'") for n in order[:n1]]
            outside = [n for n in g.names if n not in bare]
            if outside:
                raise self.fail(f"{world}.{g.key}", f"the {g.plural} in the {world} world's set "
                                "(not fixed, certain or eliminated)", outside[0])
            out.append(([bare.index(n) for n in g.names], g))
        station = self._station_block(order, n1, field, world, sigma)
        if station is not None:
            out.append(station)
        return out

    def _station_covariances(self, table: StationsApriori, where: str
                             ) -> tuple[StationCovariance, ...]:
        """The station covariances of a ``stations`` table: its file's (relative to the deck)
        and its inline stations', checked (:func:`tapp.io.station_covariance.check_covariance`)."""
        out = []
        if table.file is not None:
            out.append(read_station_covariance(Path(self.source).parent / table.file))
        names, axes, blocks = [], [], []
        for name, blk in table.station.items():
            at = f"{where}.station.{name}"
            if (blk.sigma_m is None) == (blk.covariance_m2 is None):
                raise self.fail(at, "exactly one of sigma_m or covariance_m2")
            if blk.covariance_m2 is not None:
                if any(blk.correlation):
                    raise self.fail(f"{at}.correlation", "no correlations with covariance_m2")
                m = np.array(blk.covariance_m2, dtype=float) if all(
                    len(r) == 3 for r in blk.covariance_m2) else None
                if m is None or m.shape != (3, 3):
                    raise self.fail(f"{at}.covariance_m2", "a 3 x 3 matrix, m²",
                                    blk.covariance_m2)
            else:
                if any(v < 0 for v in blk.sigma_m) or any(not -1 <= r <= 1
                                                          for r in blk.correlation):
                    raise self.fail(at, "σ's >= 0 and correlations within -1..1",
                                    {"sigma_m": blk.sigma_m, "correlation": blk.correlation})
                m = block_m2(blk.sigma_m, blk.correlation)
            names.append(name)
            axes.append(blk.axes)
            blocks.append(m)
        if names:
            cov = np.zeros((3 * len(names), 3 * len(names)))
            for i, m in enumerate(blocks):
                cov[3 * i:3 * i + 3, 3 * i:3 * i + 3] = m
            inline = StationCovariance(self.source, tuple(names), tuple(axes), cov)
            check_covariance(inline, f"{where}.station")
            out.append(inline)
        if not out:
            raise self.fail(where, "a file or at least one station")
        if len(out) == 2:
            twice = [n for n in out[1].stations if n in out[0].stations]
            if twice:
                raise self.fail(f"{where}.station.{twice[0]}", f"a station not also in the "
                                f"file {table.file}")
        return tuple(out)

    def _station_block(self, order: list[str], n1: int, field: str, world: str, sigma
                       ) -> tuple[list[int], _Generated] | None:
        """The station-location block of a world's a priori (``{field}.stations``): its
        positions in ``order`` and its covariance in the tape's location parameters, to first
        order at the tape's nominal locations (:mod:`tapp.processor.station_apriori`); None
        when the world has no such table.

        Refused: a σ list or matrix (the block completes a σ table), a station not on the
        tape or whose location is not a parameter of q, a σ given both ways (in the σ table
        and by the block), a station parameter outside the world's set (fixed, certain,
        eliminated), a negative frame σ, and in the fit world a block that is not positive
        definite (its a priori information is the inverse)."""
        table = getattr(self.deck, world).apriori.stations
        if table is None:
            return None
        where = f"{field}.stations"
        if not isinstance(sigma, dict):
            raise self.fail(f"{field}.sigma", f"a σ table with {where} (the station blocks "
                            "complete it; no list or matrix)")
        frame = table.frame
        frame_sigma = np.array([*frame.translation_m,
                                *(np.array(frame.rotation_mas) * RAD_PER_MAS),
                                frame.scale_ppb * PER_PPB])
        if np.any(frame_sigma < 0):
            raise self.fail(f"{where}.frame", "σ's >= 0", frame.model_dump())
        st, par = self.h.stations, self.h.parameters
        names, positions, kinds, axes, covs = [], [], [], [], []
        for given in self._station_covariances(table, where):
            axes += given.axes
            covs.append(given.covariance_m2)
            for station in given.stations:
                at = f"{where}.station.{station}" if given.source == self.source else station
                if station not in st.name:
                    raise InputError(given.source, at, "a station of the tape ("
                                     + ", ".join(st.name) + ")", station)
                number = int(st.id[list(st.name).index(station)])
                mine = [i for i, (k, s) in enumerate(zip(par.kind, par.station, strict=True))
                        if k == "location" and int(s) == number]
                suffixes = tuple(self.names[i].split(".", 1)[1] for i in mine)
                kind = next((k for k, v in STATION_PARAMETER_NAMES.items() if v == suffixes),
                            None)
                if kind is None:
                    raise InputError(given.source, at, "a station whose location is a "
                                     "parameter of the tape (its scenario's location is "
                                     "\"none\")", "no location parameters")
                names += [self.names[i] for i in mine]
                positions.append(position_km(par.nominal[mine], kind))
                kinds.append(kind)
        cov = np.zeros((len(names), len(names)))
        at = 0
        for c in covs:
            cov[at:at + c.shape[0], at:at + c.shape[0]] = c
            at += c.shape[0]
        block = parameter_covariance(np.array(positions), tuple(kinds), tuple(axes), cov,
                                     frame_sigma)
        both = [k for k in sigma if self._key(k, field) in names]
        if both:
            raise self.fail(f"{field}.sigma.{both[0]}", f"no σ for a station location given "
                            f"by {where} (one a priori per parameter: the σ table or the "
                            "block)", sigma[both[0]])
        bare = [n.rstrip("'") for n in order[:n1]]
        outside = [n for n in names if n not in bare]
        if outside:
            raise self.fail(where, f"station locations in the {world} world's set (not "
                            "fixed, certain or eliminated)", outside[0])
        information = None
        if world == "fit":
            smallest = scaled_min_eigenvalue(block)
            if not smallest > PSD_TOL:
                raise self.fail(where, "a positive definite covariance of the station "
                                "locations in the fit world (its a priori information is its "
                                "inverse)", f"smallest eigenvalue {smallest:.3g} of its "
                                "correlation matrix")
            information = np.linalg.solve(block, np.eye(len(names)))
        g = _Generated("apriori.stations", "station locations", "station location", "a",
                       f"their correlations are {where}'s", tuple(names), block, information,
                       (("station locations", tuple(names)),))
        self.station_blocks[world] = g
        return [bare.index(n) for n in names], g

    def _sigmas(self, sigma, order: list[str], n1: int, field: str,
                generated: list[tuple[list[int], _Generated]] = ()) -> np.ndarray:
        """σ of the first n1 parameters of ``order`` from a list or a table; those at the
        positions of the ``generated`` blocks are the σ's of their a priori."""
        if isinstance(sigma, list):
            self.positional.append(f"{field}.sigma")
            if len(sigma) != n1:
                raise self.fail(f"{field}.sigma", f"{n1} values (one per parameter of the set, "
                                "in system order)", len(sigma))
            out = np.array(sigma, dtype=float)
        else:
            out = np.full(n1, np.nan)
            for key, value in sigma.items():
                pos = self.position(self._key(key, field), order, f"{field}.sigma.{key}")
                if pos < n1:
                    out[pos] = value
                elif value != 0:
                    raise self.fail(f"{field}.sigma.{key}", "σ = 0 (the parameter is not in the "
                                    "estimated set of this world)", value)
            for at, g in generated:
                out[at] = np.sqrt(np.diag(g.covariance))
            missing = [order[i] for i in range(n1) if np.isnan(out[i])]
            if missing:
                raise self.fail(f"{field}.sigma", "a σ for every parameter (missing: "
                                + ", ".join(missing) + ")")
        lo, hi = SIGMA_RANGE
        wild = np.flatnonzero(np.isfinite(out) & (out > 0) & ((out < lo) | (out > hi)))
        if wild.size:
            raise self.fail(f"{field}.sigma", f"σ between {lo:g} and {hi:g} (or inf: no a "
                            "priori information)", {order[i]: float(out[i]) for i in wild})
        bad = np.flatnonzero(~(out > 0))
        if bad.size:
            raise self.fail(f"{field}.sigma", "σ > 0 for the estimated parameters (σ = 0 "
                            "moves a parameter to the fixed set in the table form)",
                            {order[i]: float(out[i]) for i in bad})
        return out

    def _matrix(self, rows: list[list[float]], n: int, field: str, order: list[str],
                kind: str) -> np.ndarray:
        """An a priori matrix given whole (kind "normal" or "covariance"), n x n over the
        first n parameters of ``order``: a diagonal in :data:`NORMAL_RANGE` or
        :data:`COVARIANCE_RANGE` (or 0), symmetric and positive semi-definite, each entry
        on its own scale √(a_ii a_jj) (:data:`SYMMETRY_TOL`, :data:`PSD_TOL`)."""
        m = np.array(rows, dtype=float) if rows and all(len(r) == len(rows) for r in rows) \
            else None
        if m is None or m.shape != (n, n):
            raise self.fail(field, f"a {n} x {n} matrix", None if m is None else m.shape)
        self.positional.append(field)  # in the system's order
        names = [name.rstrip("'") for name in order[:n]]
        diag = np.diagonal(m)
        lo, hi = NORMAL_RANGE if kind == "normal" else COVARIANCE_RANGE
        what = "1/σ²" if kind == "normal" else "σ²"
        wild = np.flatnonzero((diag != 0) & ~((diag >= lo) & (diag <= hi)))
        if wild.size:
            raise self.fail(field, f"a diagonal of 0 or {what} between {lo:g} and {hi:g} (σ "
                            f"within {SIGMA_RANGE[0]:g} .. {SIGMA_RANGE[1]:g})",
                            {names[i]: float(diag[i]) for i in wild})
        defect = float(symmetry_defect(m))
        if defect > SYMMETRY_TOL:
            raise self.fail(field, f"a symmetric matrix (|a_ij − a_ji| <= {SYMMETRY_TOL:g} "
                            "√(a_ii a_jj))", f"{defect:.3g} √(a_ii a_jj)")
        m = 0.5 * (m + m.T)
        smallest = scaled_min_eigenvalue(m)
        if smallest < -PSD_TOL:
            raise self.fail(field, f"a positive semi-definite {kind} matrix (eigenvalues of "
                            f"the matrix scaled to a unit diagonal >= {-PSD_TOL:g})",
                            f"smallest {smallest:.3g}")
        return m

    def fit_normal(self, order: list[str], n_f1: int) -> np.ndarray:
        ap = self.deck.fit.apriori
        if (ap.sigma is None) == (ap.normal is None):
            raise self.fail("fit.apriori", "exactly one of sigma or normal")
        table = self.sigma_table("fit")
        blocks = self._generated_blocks(order, n_f1, "fit.apriori", "fit", table)
        if ap.normal is not None:
            return self._matrix(ap.normal, n_f1, "fit.apriori.normal", order, "normal")
        sigma = self._sigmas(table, order, n_f1, "fit.apriori", blocks)
        s0 = np.diag(1.0 / sigma**2)
        for at, g in blocks:
            s0[np.ix_(at, at)] = g.information
        return s0

    def real_covariance(self, order: list[str], n_r1: int) -> np.ndarray:
        ap = self.deck.real.apriori
        if (ap.sigma is None) == (ap.covariance is None):
            raise self.fail("real.apriori", "exactly one of sigma or covariance")
        table = self.sigma_table("real")
        blocks = self._generated_blocks(order, n_r1, "real.apriori", "real", table)
        if ap.covariance is not None:
            if ap.correlation:
                raise self.fail("real.apriori.correlation", "no correlations with a covariance")
            return self._matrix(ap.covariance, n_r1, "real.apriori.covariance", order,
                                "covariance")
        sigma = self._sigmas(table, order, n_r1, "real.apriori", blocks)
        if np.any(~np.isfinite(sigma)):
            raise self.fail("real.apriori.sigma", "finite σ's")
        corr = np.eye(n_r1)
        for i, tr in enumerate(ap.correlation):
            where = f"real.apriori.correlation[{i}]"
            if len(tr) != 3 or isinstance(tr[2], bool) or not isinstance(tr[2], int | float):
                raise self.fail(where, "a triple [a, b, ρ]", tr)
            a, b = (self.position(r, order, where) for r in tr[:2])
            if a >= n_r1 or b >= n_r1 or a == b or not -1 <= tr[2] <= 1:
                raise self.fail(where, "two different uncertain parameters and -1 <= ρ <= 1",
                                tr)
            for at, g in blocks:
                if a in at or b in at:
                    raise self.fail(where, f"no {g.one} ({g.correlated})", tr)
            corr[a, b] = corr[b, a] = float(tr[2])
        for at, g in blocks:
            scale = np.sqrt(np.diag(g.covariance))
            corr[np.ix_(at, at)] = g.covariance / np.outer(scale, scale)
        smallest = scaled_min_eigenvalue(corr)
        if smallest < -PSD_TOL:
            raise self.fail("real.apriori.correlation", "a positive semi-definite real-world "
                            "covariance", f"smallest eigenvalue {smallest:.3g} of its "
                            "correlation matrix")
        return corr * np.outer(sigma, sigma)

    # --- the rest -----------------------------------------------------------------------------

    def miss_partitions(self) -> dict[str, tuple[int, int]]:
        names = list(self.h.miss.name)
        n_m = len(names)
        out = {k: v for k, v in NOMINAL_MISS.items() if v[1] <= n_m}
        out.setdefault("m1", (0, min(6, n_m)))
        for key, value in self.deck.miss.partitions.items():
            field = f"miss.partitions.{key}"
            if key not in {f"m{i}" for i in range(1, 10)}:
                raise self.fail(field, "a partition name m1..m9", key)
            if len(value) != 2:
                raise self.fail(field, "[tail, head] (rows tail+1..head, as the seed's t, h) or "
                                "[first name, last name]", value)
            if all(isinstance(v, str) for v in value):
                missing = [v for v in value if v not in names]
                if missing:
                    raise self.fail(field, "miss parameter names of the tape ("
                                    + ", ".join(names) + ")", missing)
                t, h = names.index(value[0]), names.index(value[1]) + 1
            elif all(isinstance(v, int) and not isinstance(v, bool) for v in value):
                t, h = value
            else:
                raise self.fail(field, "two integers or two names", value)
            if not 0 <= t < h <= n_m:
                raise self.fail(field, f"0 <= tail < head <= n_m = {n_m}", value)
            out[key] = (t, h)
        return out

    def command(self, text: str, field: str, systems: Systems) -> Command:
        try:
            cmd = parse_command(text)
            for side in (cmd.rows, cmd.cols):
                systems.bounds(side.rho)
                if side.tau in (4, 5) and systems.n_m < (side.tau - 2) * systems.n_p:
                    raise InputError("", "", f"an orbit set available on this tape (τ = "
                                     f"{side.tau} needs {(side.tau - 2) * systems.n_p} miss "
                                     f"parameters; the tape has {systems.n_m})", text)
        except InputError as exc:
            raise self.fail(field, exc.expected, exc.got if exc.got is not None else text) \
                from None
        return cmd

    def stations_off(self) -> tuple[StationOff, ...]:
        st = self.h.stations
        out = []
        last = self.times.size - 1
        for i, off in enumerate(self.deck.stations_off):
            field = f"stations_off[{i}]"
            if isinstance(off.station, str):
                if off.station not in st.name:
                    raise self.fail(f"{field}.station", "a station of the tape ("
                                    + ", ".join(st.name) + ")", off.station)
                number = int(st.id[list(st.name).index(off.station)])
            else:
                if off.station not in set(int(s) for s in st.id):
                    raise self.fail(f"{field}.station", "a station number of the tape "
                                    f"(1..{len(st.name)})", off.station)
                number = off.station
            start = 0 if off.start is None else self.time_index(off.start, f"{field}.start")
            end = last if off.end is None else self.time_index(off.end, f"{field}.end")
            if end <= start:
                raise self.fail(field, "start before end", (off.start, off.end))
            out.append(StationOff(number, start + 1, end))
        return tuple(out)

    def budget_groups(self, systems: Systems) -> tuple[tuple[str, tuple[int, ...]], ...]:
        order = systems.system_names(6)
        out, seen = [], set()
        for name, refs in self.deck.budget.groups.items():
            field = f"budget.groups.{name}"
            idx = self._group(refs, order, field)
            bad = [order[i] for i in idx if not systems.n_p <= i < systems.n_r1]
            if bad or not idx:
                raise self.fail(field, "uncertain constants of the real world (rq)", bad or refs)
            if seen & set(idx):
                raise self.fail(field, "groups with no parameter in common")
            seen |= set(idx)
            out.append((name, idx))
        bare = [n.rstrip("'") for n in order]
        real = [self.station_blocks["real"]] if "real" in self.station_blocks else []
        for g in (*self.generated, *real):
            for label, names in g.sources:
                rest = tuple(i for i in (bare.index(n) for n in names)
                             if systems.n_p <= i < systems.n_r1 and i not in seen)
                if rest:
                    out.append((label, rest))
        return tuple(out)

    def _group(self, refs: list, order: list[str], field: str) -> tuple[int, ...]:
        """Positions in ``order`` of a budget group's entries (names or positions): a pattern
        stands, at its place, for the tape's parameters it matches (in tape order) that the
        group does not already have, so that each counts once."""
        given = {k: self.position(r, order, field) for k, r in enumerate(refs)
                 if not self._is_pattern(r)}
        out: list[int] = []
        for k, ref in enumerate(refs):
            if k in given:
                out.append(given[k])
                continue
            matched = (self.position(n, order, field) for n in self._matching(ref, field))
            out += [i for i in matched if i not in out and i not in given.values()]
        return tuple(out)

    def history(self) -> Side:
        text = self.deck.plots.partition
        try:
            cmd = parse_command(f"cov-real {text}")
        except InputError as exc:
            raise self.fail("plots.partition", exc.expected, text) from None
        return cmd.rows

    def frames(self) -> tuple[str, ...]:
        frames = self.deck.output.frames
        if "inertial" not in frames or len(set(frames)) != len(frames):
            raise self.fail("output.frames", "a list with \"inertial\" (always given) and "
                            "optionally \"ric\", each once", frames)
        return tuple(frames)

    def _check_positions(self) -> None:
        """Refuse parameters given by position in a deck that does not say which tape they
        refer to: positions fit any tape with enough parameters (the Table D-1 deck ran on
        the LEO tape and exited 0), names only the right one."""
        tape = self.deck.tape
        if self.positional and tape.iden is None and tape.parameters is None:
            raise self.fail(self.positional[0], "parameter names, or positions with a [tape] "
                            "table that names the tape they refer to (parameters = its "
                            "parameter names in order, or iden)", "positions, and no "
                            "[tape] parameters or iden")

    def _check_output_size(self, systems: Systems, n_print: int, poc: tuple[Command, ...],
                           n_recycle: int, roc: tuple[Command, ...]) -> None:
        """Refuse a run of more than :data:`MAX_ENTITIES` entities or
        :data:`MAX_ENTITY_NUMBERS` numbers in their matrices, before any is computed (a
        covariance of an orbit set counts twice when the deck asks for RIC axes: its copy)."""
        ric = "ric" in self.deck.output.frames

        def numbers(cmd: Command) -> int:
            rows, cols = (systems.bounds(side.rho) for side in (cmd.rows, cmd.cols))
            copies = 2 if (ric and cmd.is_covariance and cmd.rows == cmd.cols and
                           systems.orbit_time(cmd.rows.tau, cmd.rows.rho) is not None) else 1
            return copies * (rows[2] - rows[1]) * (cols[2] - cols[1])

        entities = n_print * len(poc) + n_recycle * len(roc)
        size = n_print * sum(map(numbers, poc)) + n_recycle * sum(map(numbers, roc))
        field = "commands.print" if n_print * len(poc) >= n_recycle * len(roc) \
            else "commands.recycle"
        if entities > MAX_ENTITIES or size > MAX_ENTITY_NUMBERS:
            raise self.fail(field, f"at most {MAX_ENTITIES:,} output entities with at most "
                            f"{MAX_ENTITY_NUMBERS:,} numbers in all (print times x print "
                            "commands + recycles x recycle commands)",
                            f"{entities:,} entities, {size:,} numbers")

    def _check_tape(self) -> None:
        """Refuse a deck written for another tape, by what its [tape] table says of it (the
        first check: a deck for another tape is wrong there first, whatever else does not
        fit), then world modes the tape has nothing for."""
        d = self.deck
        if d.tape.iden is not None and d.tape.iden != self.h.iden:
            raise self.fail("tape.iden", f"the tape's iden {self.h.iden!r}", d.tape.iden)
        if d.tape.n_o is not None and d.tape.n_o != self.n_o:
            raise self.fail("tape.n_o", f"the tape's n_o = {self.n_o}", d.tape.n_o)
        if d.tape.parameters is not None and tuple(d.tape.parameters) != self.names:
            given = tuple(d.tape.parameters)
            i = next((i for i, (a, b) in enumerate(zip(given, self.names, strict=False))
                      if a != b), min(len(given), self.n_o))
            tape_has = self.names[i] if i < self.n_o else "none (the tape ends)"
            raise self.fail("tape.parameters", f"the tape's {self.n_o} parameter names in "
                            f"order (position {i + 1}: {tape_has})",
                            given[i] if i < len(given) else "none (the list ends)")
        have = {g.key for g in self.generated}
        for world, on in _ON.items():
            for key, plural in zip(_GENERATED_KEYS, ("stochastic accelerations", "manoeuvres "
                                                     "with execution errors"), strict=True):
                if getattr(getattr(d, world), key) == on and key not in have:
                    raise self.fail(f"{world}.{key}", f"\"ignore\" (the tape has no {plural})",
                                    on)

    def plan(self) -> Plan:
        d = self.deck
        self._check_tape()
        systems, s0, lam0 = self.systems()
        self._check_positions()
        prints = (0, *self.time_list(d.times.print, "times.print", first=0))
        recycles = self.time_list(d.times.recycle, "times.recycle", first=1)
        poc = tuple(self.command(c, f"commands.print[{i}]", systems)
                    for i, c in enumerate(d.commands.print))
        roc = ROC if d.commands.recycle == "standard" else tuple(
            self.command(c, f"commands.recycle[{i}]", systems)
            for i, c in enumerate(d.commands.recycle))
        if d.commands.recycle == "standard":
            for cmd in roc:
                for side in (cmd.rows, cmd.cols):
                    systems.bounds(side.rho)
        hist = self.history()
        systems.bounds(hist.rho)
        self._check_output_size(systems, len(prints) if d.times.print_output else 0, poc,
                                len(recycles) if d.times.recycle_print or d.times.recycle_tape
                                else 0, roc)
        return Plan(systems, s0, lam0, tuple(sorted(set(prints))), recycles,
                    d.times.print_output, d.times.recycle_print, d.times.recycle_tape, poc, roc,
                    self.stations_off(), d.budget.enabled, self.budget_groups(systems), hist,
                    self.frames())


def bind(deck: Deck, header: T13Header, source: str) -> Plan:
    """Return the :class:`~tapp.processor.plan.Plan` of a deck on a tape.

    Parameters
    ----------
    deck : a validated deck (:func:`tapp.processor.deck.read_deck`).
    header : the tape's T13 header (parameters, stations, miss, records, epoch, iden, n_p).
    source : the deck file, named in errors.

    Raises
    ------
    InputError
        Names, positions, dimensions or times that do not fit the tape; a permutation that is
        not one; a real-world covariance that is not positive semi-definite; commands with an
        unknown partition or a parity without meaning (naming the deck file and the field).
    """
    return _Binder(deck, header, source).plan()


def observations_used(plan: Plan, k: np.ndarray, station: np.ndarray, n_obs: np.ndarray
                      ) -> int:
    """Return the scalar observations TAPP III reads of a tape's (record, station) pairs:
    those in no window of the plan's time-station flags Δ_TS(k, s) = 0 (seed §4.3.4), which
    leave a pair out whole (``Processor._keep`` of :mod:`tapp.processor.sequencing`).

    ``k`` (1-based records), ``station`` (tape numbers) and ``n_obs`` are the tape's
    ``pairs/`` datasets, each (n_pairs,).
    """
    off = np.zeros(np.shape(k), dtype=bool)
    for flag in plan.stations_off:
        off |= (station == flag.station) & (k >= flag.k_first) & (k <= flag.k_last)
    return int(np.sum(np.asarray(n_obs)[~off]))



__all__ = ["bind", "observations_used"]
