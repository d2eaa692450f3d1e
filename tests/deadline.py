"""Guards for tests of inputs that used to hang or exhaust memory: a FIFO blocks ``open()``
until a writer comes, ``/dev/zero`` is read until memory runs out.

:func:`deadline` arms SIGALRM; when it fires, :class:`Hung` (a BaseException, so that no
``except Exception`` of the code under test or of typer's CliRunner swallows it) is raised in
the main thread, where Python interrupts a blocking ``open()`` (PEP 475: the handler runs, and
its exception ends the call). A read of ``/dev/zero`` in one call is not interrupted that way
(it loops in C, at GB/s): :func:`memory_cap` lowers the address-space limit meanwhile, so that
it ends in a MemoryError instead of the machine's OOM killer. :func:`guarded` is both.
"""

from __future__ import annotations

import resource
import signal
from collections.abc import Iterator
from contextlib import contextmanager

#: Long enough for a CLI command that refuses its input on the first read (~2 s here, with
#: its imports), far shorter than a hang.
DEADLINE_S = 30.0
#: Address space the guarded code may add: a command's own needs are ~0.3 GB.
EXTRA_ADDRESS_SPACE_BYTES = 2 << 30


class Hung(BaseException):
    """The code under test was still blocked or reading when the deadline passed."""


@contextmanager
def deadline(seconds: float = DEADLINE_S) -> Iterator[None]:
    """Raise :class:`Hung` if the block runs longer than ``seconds`` (main thread only)."""

    def expire(signum, frame) -> None:
        raise Hung(f"still running after {seconds:g} s: blocked on a FIFO or reading a device?")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


@contextmanager
def memory_cap(extra_bytes: int = EXTRA_ADDRESS_SPACE_BYTES) -> Iterator[None]:
    """Limit this process's address space to its current size plus ``extra_bytes``."""
    with open("/proc/self/statm") as stream:
        size = int(stream.read().split()[0]) * resource.getpagesize()
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = size + extra_bytes
    resource.setrlimit(resource.RLIMIT_AS, (cap if hard == resource.RLIM_INFINITY
                                            else min(cap, hard), hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@contextmanager
def guarded(seconds: float = DEADLINE_S) -> Iterator[None]:
    """:func:`deadline` and :func:`memory_cap` together."""
    with memory_cap(), deadline(seconds):
        yield
