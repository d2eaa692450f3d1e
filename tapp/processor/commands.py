"""Output entities of TAPP III (seed §3.4, §4.2.2, Table B-5): commands in two notations.

An entity Z = (μ₁, τ₁, ρ₁ | σ₀ | μ₂, τ₂, ρ₂) (3-35) is X₁ [σ₀] X₂ᵀ with X = (μ, τ, ρ| the
partials accumulator (:mod:`tapp.processor.representations`) and [σ₀] a matrix option of
Table B-1. Two notations parse to the same :class:`Command` and run the same code:

* the seed's: ``"σ0; μ1,τ1,ρ1; μ2,τ2,ρ2"``, e.g. ``"I; 0,-,pk; 1,2,fp"`` (τ is ``-`` for an
  isolated set), matrix options I, J, J~ (J̃), S, Lb (Λ̄), S', L' (Λ'), Lb' (Λ̄'), Sigma (Σ);
  the Unicode symbols are accepted too;
* a readable alias: ``"<matrix> <rows> [x <cols>]"`` with matrix one of ``info`` (J),
  ``info-real`` (J̃), ``normal-fit-prior`` (S), ``cov-real-prior`` (Λ̄), ``normal-fit`` (S'),
  ``cov-fit`` (Λ'), ``cov-real`` (Λ̄'), ``cov-noise`` (Σ), words joined by spaces or hyphens;
  for the identity ``partials <rows> wrt <cols> [transposed]``. A set is an isolated set
  (``pk``, ``m1``) or ``<partition>@<time>`` with time epoch | current | recycle | injection |
  miss2 | miss3 (τ = 0..5); readable partition names: all (o), orbit (p), constants (q),
  fitted (f1), considered (fz), uncertain (r1), certain (r2), eliminated (c2), miss (m).
  E.g. ``"cov real orbit@current"`` is ``"Lb'; 0,1,p; 0,1,p"``.

Parities (seed §3.4): a covariance (Λ̄, Λ', Λ̄', Σ) has parity (0, 0), a normal matrix (J, J̃,
S, S') (1, 1), the identity (0, 1) or (1, 0); anything else has no physical meaning and is
refused. Normal matrices take system partitions only (isolated sets have no adjoint). The
extended normal matrices S and S' mean something only on the fitted parameters (§3.4.2): in
print and recycle commands their partitions must lie in f1 (f1, fp, fq).

Σ is reconstructed: Table B-1 calls it the "RW tracking noise covariance matrix"; here it is
Λ' J̃ Λ', the tracking noise's share of Λ̄' over the current interval (the second term of 2-46).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from tapp.errors import InputError
from tapp.processor.representations import (
    ISOLATED_SETS,
    ORBIT_SETS,
    PARTITIONS,
    SYSTEM_PARTITIONS,
)

#: Matrix options (internal codes) with their seed symbol, alias and parity.
MATRICES: dict[str, tuple[str, str, tuple[tuple[int, int], ...]]] = {
    "I": ("I", "partials", ((0, 1), (1, 0))),
    "J": ("J", "info", ((1, 1),)),
    "Jt": ("J̃", "info-real", ((1, 1),)),
    "S": ("S", "normal-fit-prior", ((1, 1),)),
    "Lb": ("Λ̄", "cov-real-prior", ((0, 0),)),
    "S'": ("S'", "normal-fit", ((1, 1),)),
    "L'": ("Λ'", "cov-fit", ((0, 0),)),
    "Lb'": ("Λ̄'", "cov-real", ((0, 0),)),
    "Sigma": ("Σ", "cov-noise", ((0, 0),)),
}
_SEED_SYMBOLS = {
    "I": "I", "J": "J", "J~": "Jt", "Jt": "Jt", "J̃": "Jt", "S": "S", "Lb": "Lb", "Λ̄": "Lb",
    "Lambda_bar": "Lb", "S'": "S'", "L'": "L'", "Λ'": "L'", "Lambda'": "L'", "Lb'": "Lb'",
    "Λ̄'": "Lb'", "Lambda_bar'": "Lb'", "Sigma": "Sigma", "Σ": "Sigma",
}
_ALIAS = {alias: code for code, (_, alias, _) in MATRICES.items()}
_SYNONYMS = {"all": "o", "orbit": "p", "constants": "q", "fitted": "f1", "considered": "fz",
             "uncertain": "r1", "certain": "r2", "eliminated": "c2", "miss": "m"}
_TIMES = {name: tau for tau, name in ORBIT_SETS.items()}
#: Covariances: the real-world ones the error budget decomposes.
COVARIANCES = ("Lb", "L'", "Lb'", "Sigma")
_FITTED = ("f1", "fp", "fq")


def command_language_markdown() -> str:
    """The command language of ``[commands]`` as a Markdown section, written from the tables
    the parser reads (:data:`MATRICES`, the partition and time names), for the deck's
    reference page (``docs/reference/deck.md``)."""
    matrices = "\n".join(
        f"| `{alias}` | `{code}` ({symbol}) | {', '.join(f'({a}, {b})' for a, b in parity)} |"
        for code, (symbol, alias, parity) in MATRICES.items())
    words = "\n".join(f"| `{word}` | `{code}` |" for word, code in _SYNONYMS.items())
    times = "\n".join(f"| `{name}` | {tau} |" for tau, name in ORBIT_SETS.items())
    return f"""## The command language of `[commands]`

Each print or recycle command is one output entity X₁ [σ₀] X₂ᵀ (seed §3.4, eq. 3-35), in
either notation; both parse to the same command (`tapp.processor.commands`).

- **Readable**: `"<matrix> <rows> [x <cols>]"`, e.g. `"cov real orbit@current"`,
  `"cov-real-prior constants@current"`, `"info f1@recycle x fz@recycle"`; for the identity
  `"partials <rows> wrt <cols> [transposed]"`, e.g. `"partials m wrt fp@current"`. Words
  may be joined by spaces or hyphens.
- **Seed**: `"σ0; μ1,τ1,ρ1; μ2,τ2,ρ2"`, e.g. `"Lb'; 0,1,p; 0,1,p"` (τ is `-` for an
  isolated set); the Unicode symbols are accepted too.

A side (rows or columns) is an isolated set ({', '.join(f'`{k}`' for k in ISOLATED_SETS)}) or
`<partition>@<time>`; the partitions are the seed's ({', '.join(f'`{k}`' for k in
SYSTEM_PARTITIONS)}) or these words:

| word | partition |
|---|---|
{words}

| time | τ |
|---|---|
{times}

| matrix (readable) | seed code (symbol) | parity (μ₁, μ₂) |
|---|---|---|
{matrices}

A covariance has parity (0, 0), a normal matrix (1, 1), the identity (0, 1) or (1, 0);
anything else has no physical meaning and is refused, naming the command. Normal matrices
take system partitions only; the extended normal matrices (`normal-fit-prior`,
`normal-fit`) only partitions of the fitted parameters (f1, fp, fq) in print and recycle
commands. `recycle = "standard"` is the seed's Table B-5 list of recycle commands.
"""


@dataclass(frozen=True, slots=True)
class Side:
    """(μ, τ, ρ): parity, orbit set option (None for an isolated set) and set partition."""

    mu: int
    tau: int | None
    rho: str

    def seed(self) -> str:
        """Seed notation ``μ,τ,ρ``."""
        return f"{self.mu},{'-' if self.tau is None else self.tau},{self.rho}"

    def alias(self) -> str:
        """Readable set ``ρ`` or ``ρ@time``."""
        return self.rho if self.tau is None else f"{self.rho}@{ORBIT_SETS[self.tau]}"


@dataclass(frozen=True, slots=True)
class Command:
    """An output entity (σ₀; μ₁,τ₁,ρ₁; μ₂,τ₂,ρ₂): ``rows`` side 1, ``cols`` side 2."""

    sigma: str
    rows: Side
    cols: Side

    def seed(self) -> str:
        """The seed's notation, e.g. ``I; 0,-,pk; 1,2,fp``."""
        return f"{MATRICES[self.sigma][0]}; {self.rows.seed()}; {self.cols.seed()}"

    def alias(self) -> str:
        """The readable alias, e.g. ``partials pk wrt fp@recycle``."""
        if self.sigma == "I":
            if self.rows.mu == 0:
                return f"partials {self.rows.alias()} wrt {self.cols.alias()}"
            return f"partials {self.cols.alias()} wrt {self.rows.alias()} transposed"
        name = MATRICES[self.sigma][1]
        if self.rows == self.cols:
            return f"{name} {self.rows.alias()}"
        return f"{name} {self.rows.alias()} x {self.cols.alias()}"

    @property
    def is_covariance(self) -> bool:
        """Whether the entity is a covariance matrix (parity (0, 0))."""
        return self.sigma in COVARIANCES


def _fail(text: str, expected: str, got: object = None) -> InputError:
    return InputError(f"command {text!r}", "entity", expected, got)


def _check(cmd: Command, text: str, output: bool) -> Command:
    """Refuse parities and partitions without physical meaning (seed §3.4)."""
    parities = MATRICES[cmd.sigma][2]
    if (cmd.rows.mu, cmd.cols.mu) not in parities:
        raise _fail(text, f"parity {' or '.join(str(p) for p in parities)} for "
                          f"{MATRICES[cmd.sigma][0]} (seed §3.4: covariances (0,0), normal "
                          "matrices (1,1), the identity (0,1) or (1,0))",
                    (cmd.rows.mu, cmd.cols.mu))
    for side in (cmd.rows, cmd.cols):
        if side.rho in ISOLATED_SETS and side.mu != 0:
            raise _fail(text, f"parity 0 for the isolated set {side.rho} (no adjoint of a "
                              "stored partials matrix, seed §3.3)", side.mu)
        if output and cmd.sigma in ("S", "S'") and side.rho not in _FITTED:
            raise _fail(text, "a partition of the fitted parameters (f1, fp, fq): the "
                              "extended normal matrices mean nothing elsewhere (seed §3.4.2)",
                        side.rho)
    return cmd


def _side_seed(part: str, text: str) -> Side:
    fields = [f.strip() for f in part.split(",")]
    if len(fields) != 3:
        raise _fail(text, "three fields μ,τ,ρ on each side", part)
    mu, tau, rho = fields
    if mu not in ("0", "1"):
        raise _fail(text, "a parity μ of 0 or 1", mu)
    rho = {"0": "o"}.get(rho, rho)  # the scanned tables print the partition o as 0
    if rho not in PARTITIONS:
        raise _fail(text, f"a set partition ρ, one of {', '.join(PARTITIONS)}", rho)
    if rho in ISOLATED_SETS:
        if tau != "-":
            raise _fail(text, f"'-' as the orbit set of the isolated set {rho}", tau)
        return Side(int(mu), None, rho)
    if tau not in {str(t) for t in ORBIT_SETS}:
        raise _fail(text, f"an orbit set τ of 0..5 for the system partition {rho}", tau)
    return Side(int(mu), int(tau), rho)


def _set_alias(word: str, mu: int, text: str) -> Side:
    rho, _, time = word.partition("@")
    rho = _SYNONYMS.get(rho, rho)
    if rho not in PARTITIONS:
        raise _fail(text, f"a set: one of {', '.join(PARTITIONS)} or {', '.join(_SYNONYMS)}, "
                          "with @time for a system partition", word)
    if rho in ISOLATED_SETS:
        if time:
            raise _fail(text, f"no @time on the isolated set {rho}", word)
        return Side(mu, None, rho)
    if time not in _TIMES:
        raise _fail(text, f"{rho}@<time> with time one of {', '.join(_TIMES)}", word)
    return Side(mu, _TIMES[time], rho)


def _parse_alias(text: str) -> Command:
    words = text.split()
    for n in (3, 2, 1):
        head = "-".join(words[:n])
        if head in _ALIAS and len(words) > n:
            code, rest = _ALIAS[head], words[n:]
            break
    else:
        raise _fail(text, "seed notation 'σ0; μ1,τ1,ρ1; μ2,τ2,ρ2' or an alias starting "
                          f"with one of {', '.join(_ALIAS)}")
    if code == "I":
        transposed = rest[-1:] == ["transposed"]
        rest = rest[:-1] if transposed else rest
        if len(rest) != 3 or rest[1] != "wrt":
            raise _fail(text, "'partials <set> wrt <set> [transposed]'")
        a, b = _set_alias(rest[0], 0, text), _set_alias(rest[2], 1, text)
        return Command("I", b, a) if transposed else Command("I", a, b)
    mu = MATRICES[code][2][0][0]
    if len(rest) == 1:
        side = _set_alias(rest[0], mu, text)
        return Command(code, side, side)
    if len(rest) == 3 and rest[1] == "x":
        return Command(code, _set_alias(rest[0], mu, text), _set_alias(rest[2], mu, text))
    raise _fail(text, f"'{MATRICES[code][1]} <set>' or '{MATRICES[code][1]} <set> x <set>'")


def parse_command(text: str, *, output: bool = True) -> Command:
    """Parse an entity in the seed's notation or as an alias (module docstring).

    Parameters
    ----------
    text : the command.
    output : a print or recycle command (the §3.4.2 restriction on S and S' applies); the
        built-in update commands pass False.

    Raises
    ------
    InputError
        Unknown matrix option or partition, a malformed side, or a parity without physical
        meaning, naming the command.

    Examples
    --------
    >>> parse_command("I; 0,-,pk; 1,2,fp") == parse_command("partials pk wrt fp@recycle")
    True
    >>> parse_command("cov real orbit@current").seed()
    "Λ̄'; 0,1,p; 0,1,p"
    """
    if not isinstance(text, str) or not text.strip():
        raise _fail(str(text), "a non-empty command string")
    parts = [p.strip() for p in re.split(r";", text)]
    if len(parts) == 3:
        sigma = _SEED_SYMBOLS.get(parts[0].replace(" ", ""))
        if sigma is None:
            raise _fail(text, "a matrix option σ0, one of I, J, J~, S, Lb, S', L', Lb', Sigma "
                              "(or Λ̄, J̃, Λ', Λ̄', Σ)", parts[0])
        cmd = Command(sigma, _side_seed(parts[1], text), _side_seed(parts[2], text))
    elif len(parts) == 1:
        cmd = _parse_alias(text.strip())
    else:
        raise _fail(text, "'σ0; μ1,τ1,ρ1; μ2,τ2,ρ2' (three fields separated by ';')")
    return _check(cmd, text, output)


def _commands(rows: tuple[str, ...], output: bool) -> tuple[Command, ...]:
    return tuple(parse_command(r, output=output) for r in rows)


#: The update phase commands (Table B-5, UPC), run on an epoch change.
UPC = _commands(("I; 0,-,pl; 1,1,o", "I; 0,-,pi; 1,1,o", "I; 0,-,m; 1,1,o",
                 "J; 1,1,o; 1,1,o", "J~; 1,1,o; 1,1,o", "S; 1,1,o; 1,1,o",
                 "Lb; 0,1,o; 0,1,o"), output=False)
#: The standard recycle output commands (Table B-5, ROC). Reconstructed from the scan: its
#: "f2" is fz (the considered parameters, TAPP II's "z") and its "11" is f1.
ROC = _commands(("I; 0,-,pk; 1,2,fp", "I; 0,-,pk; 1,2,fq", "I; 0,-,pk; 1,2,fz",
                 "J; 1,2,f1; 1,2,f1", "J~; 1,2,f1; 1,2,f1", "J; 1,2,f1; 1,2,fz",
                 "I; 0,-,m1; 1,1,fp", "I; 0,-,m1; 1,1,fq", "I; 0,-,m1; 1,1,fz"), output=True)

__all__ = ["COVARIANCES", "MATRICES", "ROC", "UPC", "Command", "Side", "parse_command",
           "SYSTEM_PARTITIONS"]
