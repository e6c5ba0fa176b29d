"""A progress bar of simulated seconds with the real-time factor.

A railway engineer waiting for a 41 s run wants to read "12.3/41 s simulated, 0.7 x
real time", not a percentage. :func:`jaxrail.simulate` draws it while its one
compiled program runs, from the times the program's loop reports
(:mod:`jaxrail._time_report`).
"""

_FORMAT = "{n:.2f}/{total:.2f} s simulated |{bar}| [{elapsed}<{remaining}{postfix}]"


class SimulatedTimeBar:
    """tqdm bar of ``duration`` [s] simulated; ``update(simulated)`` redraws it at
    ``simulated`` [s] with the real-time factor since the bar was made. A context
    manager (closes the bar)."""

    def __init__(self, duration: float):
        import tqdm

        self._bar = tqdm.tqdm(total=float(duration), bar_format=_FORMAT, dynamic_ncols=True)

    def update(self, simulated: float):
        self._bar.n = float(simulated)
        elapsed = self._bar.format_dict["elapsed"]
        if elapsed > 0.0:
            self._bar.set_postfix_str(f"{simulated / elapsed:.3g} x real time", refresh=False)
        self._bar.refresh()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._bar.close()
