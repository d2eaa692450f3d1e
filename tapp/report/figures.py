"""Figures drawn without pyplot: no Matplotlib backend is chosen or switched (a notebook's
stays as it is), and no figure is kept in pyplot's registry (none to close). PNG files are
written by :meth:`matplotlib.figure.Figure.savefig`, which picks its canvas by the file's
extension. Matplotlib is imported on the first figure, not with this module."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def subplots(*args: Any, figsize: tuple[float, float], **kwargs: Any) -> tuple[Figure, Any]:
    """A figure of its own (inches) and its axes, as ``pyplot.subplots`` would give them."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)
