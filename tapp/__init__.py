"""tapp: tracking accuracy prediction and orbit-determination analysis.

Trajectories with separately truncated variational equations, ground-station tracking
simulation (TAPP I), the matrix processor (TAPP III), Monte Carlo guidance (TAPP II) and the
batch/sequential estimators of the approximate-STM study.

The Python front door (:mod:`tapp.api`), one verb per program, each taking paths or objects
in memory and returning a result that renders itself (``to_json()``, a text rendering,
``plot(ax=None)``) as the command does::

    from tapp import read_scenario, simulate, process, guide, search, sweep, fit, ekf, rsig

- ``read_scenario(path)`` -> :class:`Scenario`
- ``simulate(scenario_or_path, *, raw=False, progress=None)`` -> :class:`SimulateResult`
  (``.tape``, ``.write(path)``, ``.to_json()``)
- ``process(t13_or_path, deck_or_path)`` -> :class:`ProcessResult` (``.run``, ``.o3()``,
  ``.to_json()``, ``.t32()``, ``.write_t32(path)``, ``.plot(ax)``)
- ``guide(t32_or_path, guidance_or_path, *, samples, seed, execution=None)`` ->
  :class:`GuideResult` (``.result``, ``.markdown()``, ``.to_json()``, ``.plot(ax)``)
- ``search(path_or_problem)`` -> :class:`TargetingResult` (``.status``, ``.converged``,
  ``.report()``, ``.to_json()``)
- ``sweep(path, *, output_h5=None, execution=None)`` -> :class:`iter.SweepResult`
- ``fit(orbit, *, arc="24h", ..., study=None)`` -> :class:`FitResult` (the batch DC of
  ``tapp dc``: ``.iterations``, ``.linearisation()`` with the STMs and partials,
  ``.status``, ``.text()``, ``.to_json()``, ``.plot(ax)``)
- ``ekf(orbit, *, arc="18h", apriori="1", ..., study=None)`` -> :class:`FilterResult`
  (``.result``: residuals, gains, covariances, process noise per row)
- ``rsig(orbit, *, span="48h", step="300s", ..., study=None)`` -> :class:`RSigResult`
  (``.signature``: R(t))

The names are imported on first use, so that ``import tapp`` (and ``tapp --help``) stays
light.
"""

#: The front door: name -> "module:attribute", imported on first access (PEP 562).
_LAZY = {
    "Scenario": "tapp.tracking.scenario:Scenario",
    "read_scenario": "tapp.tracking.scenario_build:read_scenario",
    "simulate": "tapp.api.tracking:simulate",
    "SimulateResult": "tapp.api.tracking:SimulateResult",
    "process": "tapp.api.processing:process",
    "ProcessResult": "tapp.api.processing:ProcessResult",
    "guide": "tapp.api.guidance:guide",
    "GuideResult": "tapp.api.guidance:GuideResult",
    "search": "tapp.api.targeting:search",
    "TargetingResult": "tapp.api.targeting:TargetingResult",
    "sweep": "tapp.api.sweeps:sweep",
    "fit": "tapp.api.od:fit",
    "FitResult": "tapp.api.od:FitResult",
    "IllConditionedFit": "tapp.od.runs:IllConditionedFit",
    "ekf": "tapp.api.od:ekf",
    "FilterResult": "tapp.api.od:FilterResult",
    "rsig": "tapp.api.od:rsig",
    "RSigResult": "tapp.api.od:RSigResult",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> object:
    """A front-door name of :data:`_LAZY`, or ``__version__`` (read from the installed
    metadata: reading it costs more than the rest of ``import tapp``, which ``tapp --help``
    waits for), imported on first use and kept."""
    if name in _LAZY:
        from importlib import import_module

        module, attribute = _LAZY[name].split(":")
        value = getattr(import_module(module), attribute)
    elif name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("tapp")
        except PackageNotFoundError:  # running from a source tree that is not installed
            value = "0.0.0+unknown"
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names and the front door's, not yet imported."""
    return sorted({*globals(), *__all__})
