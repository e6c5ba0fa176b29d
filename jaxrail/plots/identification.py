"""Figure of a fit (:func:`jaxrail.identification.identify`): the loss per iteration, each
parameter's trajectory relative to its initial value (and to a known truth, for
synthetic studies), and every measured channel against the fitted simulation."""

import numpy as np

from ._figure import subplots
from ..identification.measurements import UNITS
from .profiles import save_figure


def _unit(channel):
    return next((u for prefix, u in UNITS.items() if channel.startswith(prefix)), "")


def plot_identification(identification, path, truth=None):
    """Write the figure of ``identification`` (an :class:`Identification`) to ``path``
    (PNG). ``truth``: optional {name: value} drawn as dashed lines."""
    fit, measured = identification.fit, identification.measurements
    channels = measured.channels
    fig, axes = subplots(1 + (len(channels) + 1) // 2, 2, figsize=(10.0, 3.0 * (
        1 + (len(channels) + 1) // 2)), squeeze=False, dpi=90)
    iterations = np.arange(len(fit.loss_history))
    axes[0, 0].semilogy(iterations, np.maximum(fit.loss_history, 1e-300), "o-", ms=3)
    axes[0, 0].set(xlabel="iteration", ylabel="loss 0.5 sum r^2", title="loss")
    for k, name in enumerate(fit.names):
        line, = axes[0, 1].plot(iterations, fit.value_history[:, k] / fit.initial[k], "o-",
                                ms=3, label=f"{name} = {fit.values[k]:.4g} +- "
                                            f"{fit.standard_error[k]:.2g}")
        if truth is not None and name in truth:
            axes[0, 1].axhline(truth[name] / fit.initial[k], ls="--", color=line.get_color())
    axes[0, 1].set(xlabel="iteration", ylabel="value / initial value", title="parameters")
    axes[0, 1].legend(fontsize=7)
    for c, channel in enumerate(channels):
        ax = axes[1 + c // 2, c % 2]
        ax.plot(measured.time, measured.values[:, c], ".", ms=3, color="0.5", label="measured")
        ax.plot(measured.time, identification.simulated[:, c], "-", label="fitted")
        ax.set(xlabel="t [s]", ylabel=f"[{_unit(channel)}]", title=channel)
        ax.legend(fontsize=7)
    for ax in axes.flat[2 + len(channels):]:
        ax.set_visible(False)
    fig.tight_layout()
    save_figure(fig, path)
