"""Figures without pyplot: a ``matplotlib.figure.Figure`` is drawn and saved by its own
canvas, so drawing selects no backend and leaves no figure open in pyplot's registry
(nothing of matplotlib's global state changes when jaxrail draws or is imported)."""

from matplotlib.figure import Figure


def subplots(*args, figsize=None, dpi=None, **kwargs):
    """Like ``matplotlib.pyplot.subplots``: a new Figure of ``figsize`` [in] at ``dpi``
    and its axes (``Figure.subplots`` arguments)."""
    figure = Figure(figsize=figsize, dpi=dpi)
    return figure, figure.subplots(*args, **kwargs)
