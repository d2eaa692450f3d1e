"""The exit codes of a DC's outcomes, for ``tapp dc`` and the JSON that reports them (no
numpy: the CLI imports this module on ``--help``).

= ============================================================================================
0 converged: the RMS settled within the fit limit
3 diverged: the RMS grew, or failed to settle within the iteration limit
4 ill-conditioned: the normal matrix of the first iteration is too ill-conditioned for the
  data to determine the state
5 stalled: the RMS settled above the fit limit (the data are not fitted)
6 converging: the iteration limit was reached while the RMS was still falling geometrically
7 converged, residuals inconsistent with the noise model: the RMS settled within the fit
  limit but above the 99.9 % χ² bound of the residuals (:func:`tapp.od.batch.rms_bound`)
= ============================================================================================
"""

EXIT_DIVERGED = 3
EXIT_ILL_CONDITIONED = 4
EXIT_STALLED = 5
EXIT_CONVERGING = 6
EXIT_INCONSISTENT = 7
#: The status of a DC that did not iterate (:class:`tapp.od.batch.IllConditionedError`).
ILL_CONDITIONED = "ill-conditioned"

#: Exit code per DC status (the values of :class:`tapp.od.batch.DCOutcome`, and
#: :data:`ILL_CONDITIONED`).
EXIT_CODES = {"converged": 0, "diverged": EXIT_DIVERGED, ILL_CONDITIONED: EXIT_ILL_CONDITIONED,
              "stalled": EXIT_STALLED, "converging": EXIT_CONVERGING,
              "converged, residuals inconsistent with the noise model": EXIT_INCONSISTENT}


def exit_code(status: str) -> int:
    """The exit code of a DC status (module docstring)."""
    return EXIT_CODES[status]
