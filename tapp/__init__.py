"""tapp: tracking accuracy prediction and orbit-determination analysis.

Trajectories with separately truncated variational equations, ground-station tracking
simulation (TAPP I), the matrix processor (TAPP III), Monte Carlo guidance (TAPP II) and the
batch/sequential estimators of the approximate-STM study.
"""


def __getattr__(name: str) -> str:
    """``__version__``, read from the installed metadata on first use (reading it costs
    more than the rest of ``import tapp``, which ``tapp --help`` waits for)."""
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        value = version("tapp")
    except PackageNotFoundError:  # running from a source tree that is not installed
        value = "0.0.0+unknown"
    globals()["__version__"] = value
    return value
