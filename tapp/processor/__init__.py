"""TAPP III, the tracking accuracy matrix processor (seed: TAPP III, Lemmon 1963).

Reads a T13 tape (TAPP I's per-station normal matrices AᵀWA, AᵀWMWA), runs the regression to a
constrained parameter set in a *fit world* that may differ from the *real world* (§2), and
writes any requested output entity in any representation and partition (§3) at the print and
recycle times (§4.3): the O3 printout, JSON, plots and the T32 tape for TAPP II.

The regression algorithm of §2.5 is :func:`tapp.estimation.regression` (on square-root
information factors, shared with TAPP II's navigation). Modules: :mod:`.links` (permutation
and constraint links), :mod:`.representations` (orbit sets, systems, partitions: the
partials accumulator), :mod:`.commands` (output entities in the seed's notation and as
aliases), :mod:`.executive`,
:mod:`.plan` and :mod:`.deck` (the manual inputs), :mod:`.deck_bind` (the deck bound to a
tape), :mod:`.sequencing` (the four phases),
:mod:`.printout` (O3 text and JSON).
"""

from tapp.estimation.regression import Regression, SingularFitError, regression
from tapp.processor.commands import ROC, UPC, Command, Side, parse_command

__all__ = ["ROC", "UPC", "Command", "Regression", "Side", "SingularFitError", "parse_command",
           "regression"]
