"""The Python front door: one verb per program, each returning a result that renders itself.

``tapp`` exports these names lazily (:mod:`tapp`); the CLI commands are thin wrappers over
them (argument parsing, progress bars, exit codes).

==========================  ==========================================================
:func:`tracking.simulate`   TAPP I: a scenario -> :class:`tracking.SimulateResult`
:func:`processing.process`  TAPP III: a T13 tape and a deck -> :class:`processing.ProcessResult`
:func:`guidance.guide`      TAPP II: a T32 tape and a guidance file -> :class:`guidance.GuideResult`
:func:`targeting.search`    SEARCH: a B-plane search -> :class:`targeting.TargetingResult`
:func:`sweeps.sweep`        ITER: a sweep file -> :class:`iter.SweepResult`
:func:`od.fit`              DC: an orbit of a study -> :class:`od.FitResult`
:func:`od.ekf`              EKF: an orbit of a study -> :class:`od.FilterResult`
:func:`od.rsig`             R(t): an orbit of a study -> :class:`od.RSigResult`
==========================  ==========================================================

Inputs are paths (str or Path) or the objects the programs take in memory; results are
frozen dataclasses with ``to_json()`` (what the command's ``--json`` writes), a text
rendering where the command prints one, and ``plot(ax=None)``, which draws on the given
Matplotlib axes (or a figure of its own, :func:`tapp.report.figures.subplots`) and never
touches pyplot's state or backend.
"""
