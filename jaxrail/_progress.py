"""A progress bar of simulated seconds with the real-time factor, for diffrax solves.

diffrax's ``TqdmProgressMeter`` counts percent; a railway engineer waiting for a 41 s
run wants to read "12.3/41 s simulated, 0.7 x real time". The bar is drawn by tqdm
on the host from inside the compiled loop (diffrax's callbacks), every
``refresh_steps`` steps.
"""

import diffrax
import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
import numpy as np

_FORMAT = "{n:.2f}/{total:.2f} s simulated |{bar}| [{elapsed}<{remaining}{postfix}]"


def _new_bar():
    import tqdm

    return tqdm.tqdm(total=1.0, bar_format=_FORMAT, dynamic_ncols=True)


def _draw(bar, simulated, duration):
    bar.total = duration
    bar.n = simulated
    elapsed = bar.format_dict["elapsed"]
    if elapsed > 0.0:
        bar.set_postfix_str(f"{simulated / elapsed:.3g} x real time", refresh=False)
    bar.refresh()


def _finish(bar):
    bar.close()


def _step(values, index):
    """Draw the bar of ``index`` with ``values`` = (simulated, duration) [s], through
    diffrax's registry of bars (as its own meter does)."""
    manager = diffrax._progress_meter._progress_meter_manager

    def draw(values, index):
        with manager.lock:
            bar = manager.bars.get(np.unique(index).item())
            if bar is not None:  # None e.g. in the backward pass after a forward pass
                simulated, duration = np.asarray(values).reshape(-1, 2)[0]
                _draw(bar, float(simulated), float(duration))
        return index

    return jax.pure_callback(draw, index, values, index, vmap_method="expand_dims")


class SimulatedTimeProgress(diffrax.TqdmProgressMeter):
    """diffrax progress meter that shows simulated seconds out of ``duration`` [s]
    (traced: a new duration does not recompile) and the real-time factor."""

    duration: jax.Array = eqx.field(converter=lambda x: jnp.asarray(x, dtype=float),
                                    default=1.0)

    def step(self, state, progress):
        values = jnp.stack([progress * self.duration, self.duration * jnp.ones_like(progress)])
        index = jax.lax.cond(
            eqxi.nonbatchable(eqxi.unvmap_max(state.step) % self.refresh_steps == 0),
            lambda i: _step(values, i), lambda i: i, state.meter_idx)
        return type(state)(meter_idx=index, step=state.step + 1)

    @staticmethod
    def _init_bar():
        return _new_bar()

    @staticmethod
    def _close_bar(bar):
        _finish(bar)
