"""C code generation, compilation and on-disk caching of the propagator.

The CasADi functions of :mod:`tapp.dynamics.equations` are emitted as C and compiled by the
system C compiler (``$CC``, default ``cc``); the driver of the integration method
(:data:`METHODS`: ``dop853_driver.c`` for first-order systems, ``rkn12_driver.c`` for
second-order ones) with the code the drivers share (``driver_common.c``) and its tableau is
compiled once per method, apart, and linked with them into a shared library loaded with
ctypes. Both are cached under ``$TAPP_CACHE_DIR`` (default ``~/.cache/tapp``) by a hash of
their source and the compiler flags, so a second run, or another process, pays no compile
cost, and a new force model pays only for its own functions (the driver was half of each
compile). A cache file is written to a temporary name and renamed, so concurrent workers
never load a half-written library, and made under a lock, so they do not compile it twice.

Status codes returned by the driver:

====  =============================================
code  meaning
====  =============================================
0     ok
1     more steps than ``max_steps``
2     step size underflow (stiff or singular right-hand side)
3     non-finite state
4     a time outside the third-body ephemeris table
5     an event not located (more aimed steps than the driver allows)
6     more events than the log holds
====  =============================================

Events (:mod:`tapp.dynamics.events`): the generated ``f_event`` is compiled beside the
right-hand sides; the driver logs each located event (time, function index, direction) into
arrays of :data:`MAX_EVENTS` entries.
"""

from __future__ import annotations

import ctypes
import fcntl
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop

from tapp.dynamics.rkn12_tableau import rkn12
from tapp.errors import TappError
from tapp.frames.chebyshev import ChebyshevTable

#: Integration methods: name -> the driver file linked with the generated right-hand side.
#: ``dop853`` integrates x' = f(t, x); ``rkn12`` integrates r'' = a(t, r) (second-order form).
METHODS = {"dop853": "dop853_driver.c", "rkn12": "rkn12_driver.c"}

STATUS = {
    0: "ok",
    1: "more steps than max_steps",
    2: "step size underflow",
    3: "non-finite state",
    4: "time outside the ephemeris table",
    5: "an integration event could not be located",
    6: "more integration events than the log holds",
}

#: Most events one call logs: a LEO with SRP meets about 64 shadow boundaries a day, and a
#: Harris-Priester orbit that rises and falls through the table heights a few hundred.
MAX_EVENTS = 1_000_000

_CFLAGS = ("-O3", "-fPIC", "-fno-math-errno")
#: A C ``double *``, passed as an address (:func:`_address`).
_DOUBLE_P = ctypes.c_void_p


def _address(a: np.ndarray) -> int:
    """The address of a C-contiguous float64 array's data: through the buffer protocol when
    the array is writable and not empty (0.3 µs), else ``.ctypes.data`` (1.5 µs)."""
    if a.flags.writeable and a.size:
        return ctypes.addressof(ctypes.c_double.from_buffer(a))
    return a.ctypes.data


class CompileError(TappError):
    """The C compiler is missing or failed; the message carries its output."""


def _c_array(name: str, values: np.ndarray) -> str:
    values = np.asarray(values, dtype=float)
    dims = "".join(f"[{d}]" for d in values.shape)
    body = ", ".join(repr(float(v)) for v in values.ravel())
    return f"static const double {name}{dims} = {{{body}}};\n"


def _dop853_tableau() -> str:
    """The DOP853 tableau as C arrays, from SciPy's copy of Hairer's coefficients."""
    return "".join([
        _c_array("DOP_C", dop.C),
        _c_array("DOP_A", dop.A),
        _c_array("DOP_B", dop.B),
        _c_array("DOP_E3", dop.E3),
        _c_array("DOP_E5", dop.E5),
        _c_array("DOP_D", dop.D),
    ])


def _rkn12_tableau() -> str:
    """The RKN12(10) tableau as C arrays; error weights b - b_hat formed exactly first."""
    tab = rkn12()
    return "".join([
        _c_array("RKN_C", np.array(tab.c, dtype=float)),
        _c_array("RKN_A", np.array(tab.a, dtype=float)),
        _c_array("RKN_B", np.array(tab.b, dtype=float)),
        _c_array("RKN_BP", np.array(tab.bp, dtype=float)),
        _c_array("RKN_EB", np.array([b - bh for b, bh in zip(tab.b, tab.bh, strict=True)],
                                    dtype=float)),
        _c_array("RKN_EBP", np.array([b - bh for b, bh in zip(tab.bp, tab.bph, strict=True)],
                                     dtype=float)),
    ])


_TABLEAUX = {"dop853": _dop853_tableau, "rkn12": _rkn12_tableau}


def generate_source(f_state: ca.Function, f_var: ca.Function, f_event: ca.Function) -> str:
    """Return the C source of the CasADi functions (``driver_common.c`` declares them)."""
    cg = ca.CodeGenerator("tapp_rhs.c", {"with_header": False, "casadi_real": "double",
                                         "casadi_int": "long long int"})
    cg.add(f_state)
    cg.add(f_var)
    cg.add(f_event)
    return cg.dump()


def driver_source(method: str) -> str:
    """Return the C source of the driver of ``method`` (a key of :data:`METHODS`): its
    tableau, the shared code and the driver."""
    here = files("tapp.dynamics")
    return "\n".join([_TABLEAUX[method](), here.joinpath("driver_common.c").read_text(),
                      here.joinpath(METHODS[method]).read_text()])


def cache_dir() -> Path:
    """Directory of compiled libraries (``$TAPP_CACHE_DIR`` or ``~/.cache/tapp``)."""
    return Path(os.environ.get("TAPP_CACHE_DIR", Path.home() / ".cache" / "tapp"))


def _cached(target: Path, make: Callable[[Path], None]) -> Path:
    """Return ``target``, made first by ``make(temporary path)`` when it is not there: under
    an exclusive lock on ``target``'s lock file (a second process waits for the first's
    file instead of compiling it again), written to a temporary name and renamed."""
    if target.exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target.with_name(f".{target.name}.lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not target.exists():
            with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
                out = Path(tmp) / target.name
                make(out)
                os.replace(out, target)
    return target


def _cc(*args: str | Path) -> None:
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise CompileError(f"C compiler {cc!r} not found: install gcc or set $CC")
    proc = subprocess.run([cc, *map(str, args)], capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise CompileError(f"{cc} failed ({proc.returncode}): {proc.stderr[-2000:]}")


def _digest(*parts: str) -> str:
    return hashlib.sha256(" ".join([*parts, *_CFLAGS]).encode()).hexdigest()[:20]


def _driver_object(method: str) -> Path:
    """The cached object file of the driver of ``method``."""
    source = driver_source(method)

    def make(out: Path) -> None:
        src = out.with_suffix(".c")
        src.write_text(source)
        _cc(*_CFLAGS, "-c", "-o", out, src)

    return _cached(cache_dir() / f"{method}_{_digest(source)}.o", make)


@dataclass(frozen=True, slots=True)
class EventLog:
    """The driver's log: times (s), indices into the event functions, and whether each g
    fell from positive to negative in forward time."""

    t_s: np.ndarray
    index: np.ndarray
    falling: np.ndarray


@dataclass(frozen=True, slots=True)
class CompiledPropagator:
    """A loaded shared library with the driver entry point ``tapp_integrate``."""

    path: Path
    fn: ctypes._CFuncPtr

    def integrate(self, which: int, y0: np.ndarray, t0_s: float, t_out_s: np.ndarray,
                  q: np.ndarray, c: np.ndarray, eph: ChebyshevTable, rtol: float, atol: float,
                  n_err: int, max_steps: int, n_events: int = 0
                  ) -> tuple[int, np.ndarray, np.ndarray, EventLog]:
        """Run the driver; return (status, y (N, ny), stats [accepted, rejected, nfev],
        the events logged).

        For ``rkn12`` y is [z, z'] of the second-order form (ny = 2 n2) and ``n_err`` counts
        components of z (and of z') in the error norm. ``n_events`` is the number of outputs
        of the library's ``f_event``."""
        y0 = np.ascontiguousarray(y0, dtype=float)
        t_out_s = np.ascontiguousarray(t_out_s, dtype=float)
        y_out = np.empty((t_out_s.size, y0.size))  # every row written when status is 0
        stats = np.zeros(4)
        cap = MAX_EVENTS if n_events else 0
        log_t, log_id, log_falling = (np.zeros(max(cap, 1)), np.zeros(max(cap, 1), np.int32),
                                      np.zeros(max(cap, 1), np.int32))
        q = np.ascontiguousarray(q, dtype=float) if len(q) else np.zeros(1)
        c = np.ascontiguousarray(c, dtype=float)
        coeffs = np.ascontiguousarray(eph.coeffs, dtype=float)
        # The arrays go as addresses, taken here: ctypes converts plain numbers in C, where a
        # signal handler cannot run, whereas an ndpointer's conversion runs Python code, and
        # ctypes turns what a handler raises there (the CLI's SIGTERM and Ctrl-C) into an
        # ArgumentError (a traceback instead of a clean stop).
        status = self.fn(which, y0.size, float(t0_s), _address(y0), t_out_s.size,
                         _address(t_out_s), _address(y_out), _address(q), _address(c),
                         _address(coeffs), eph.n_series, eph.n_segments, eph.n_coef,
                         eph.t0_s, eph.h_s, rtol, atol, n_err, max_steps, _address(stats),
                         n_events, cap, _address(log_t), log_id.ctypes.data,
                         log_falling.ctypes.data)
        n = int(stats[3])
        return int(status), y_out, stats[:3], EventLog(log_t[:n].copy(), log_id[:n].copy(),
                                                       log_falling[:n].astype(bool))


@cache
def _load(path: Path) -> CompiledPropagator:
    lib = ctypes.CDLL(str(path))
    fn = lib.tapp_integrate
    fn.restype = ctypes.c_int
    fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_double, _DOUBLE_P, ctypes.c_int,
                   _DOUBLE_P, _DOUBLE_P, _DOUBLE_P, _DOUBLE_P, _DOUBLE_P, ctypes.c_int,
                   ctypes.c_int, ctypes.c_int, ctypes.c_double, ctypes.c_double,
                   ctypes.c_double, ctypes.c_double, ctypes.c_int, ctypes.c_long, _DOUBLE_P,
                   ctypes.c_int, ctypes.c_int, _DOUBLE_P, ctypes.c_void_p, ctypes.c_void_p]
    return CompiledPropagator(path, fn)


def compiled_propagator(f_state: ca.Function, f_var: ca.Function, f_event: ca.Function,
                        method: str = "dop853") -> CompiledPropagator:
    """Return the compiled propagator of a function pair and their event function under the
    driver of ``method``, compiling only on a cache miss. The pair must suit the method:
    first-order right-hand sides for ``dop853``, accelerations of the second-order form for
    ``rkn12``."""
    driver = _driver_object(method)
    source = generate_source(f_state, f_var, f_event)

    def make(out: Path) -> None:
        src = out.with_suffix(".c")
        src.write_text(source)
        _cc(*_CFLAGS, "-shared", "-o", out, src, driver, "-lm")

    return _load(_cached(cache_dir() / f"rhs_{_digest(source, driver.name)}.so", make))
