"""What a Monte Carlo study varies, and the samples drawn from it.

A :class:`Variation` names one input and its spread. Inputs: ``speed`` [m/s],
``misalignment`` [m] (the initial lateral shift of the vehicle to the left),
``irregularity_seed`` (the realisation of the scenario's irregularity spectrum, rounded
down to an integer) and ``irregularity_scale`` (a factor on its irregularity) and any
parameter of :mod:`jaxrail.vehicles.parameters` (``friction``, ``contact_stiffness``,
``primary_lateral_stiffness``, ...), in that parameter's units.

Spreads, as written on the command line (``NAME=SPREAD``):

- ``lo:hi``: uniform on [lo, hi];
- ``normal:mean,sd``: normal;
- ``a,b,c``: one of the listed values, with equal probability.

Designs: ``random`` (independent draws), ``latin`` (Latin hypercube: each uniform
range cut into N equal strata, one sample in each, strata paired at random; maps over
two inputs are then evenly covered) and ``grid`` (the full factorial of N^(1/d) values
per input, ranges from lo to hi inclusive). All are reproducible from the seed.
"""

import dataclasses
import math

import numpy as np

BOUNDARY_INPUTS = ("speed", "misalignment", "irregularity_seed", "irregularity_scale")
DESIGNS = ("random", "latin", "grid")


@dataclasses.dataclass(frozen=True)
class Variation:
    """One varied input: ``kind`` is "uniform" (values = (lo, hi)), "normal"
    (values = (mean, sd)) or "choice" (values = the choices)."""

    name: str
    kind: str
    values: tuple

    def __post_init__(self):
        if self.kind not in ("uniform", "normal", "choice"):
            raise ValueError(f"{self.name}: kind must be uniform, normal or choice, "
                             f"got {self.kind!r}")
        v = self.values
        if not all(math.isfinite(x) for x in v):
            raise ValueError(f"{self.name}: values must be finite, got {v}")
        if self.kind == "uniform" and not (len(v) == 2 and v[0] <= v[1]):
            raise ValueError(f"{self.name}: a uniform range needs lo <= hi, got {v}")
        if self.kind == "normal" and not (len(v) == 2 and v[1] >= 0.0):
            raise ValueError(f"{self.name}: normal needs mean,sd with sd >= 0, got {v}")
        if self.kind == "choice" and not v:
            raise ValueError(f"{self.name}: choice needs at least one value")

    def _from_unit(self, u):
        """Values for uniform deviates ``u`` in [0, 1)."""
        if self.kind == "uniform":
            lo, hi = self.values
            return lo + (hi - lo) * u
        if self.kind == "choice":
            return np.asarray(self.values)[np.minimum((u * len(self.values)).astype(int),
                                                      len(self.values) - 1)]
        from statistics import NormalDist

        mean, sd = self.values
        clipped = np.clip(u, 1e-12, 1.0 - 1e-12)
        return np.array([NormalDist(mean, sd).inv_cdf(x) if sd > 0 else mean
                         for x in clipped])

    def _levels(self, n):
        """``n`` grid values (uniform: lo..hi; choice: the choices; normal: mean +- 2 sd)."""
        if self.kind == "choice":
            return np.asarray(self.values, dtype=np.float64)
        lo, hi = (self.values if self.kind == "uniform"
                  else (self.values[0] - 2 * self.values[1], self.values[0] + 2 * self.values[1]))
        return np.linspace(lo, hi, n) if n > 1 else np.array([0.5 * (lo + hi)])


def parse_variation(text: str) -> Variation:
    """A :class:`Variation` from ``NAME=lo:hi``, ``NAME=normal:mean,sd`` or
    ``NAME=a,b,c``; ValueError names what is wrong."""
    name, sep, spread = text.partition("=")
    name, spread = name.strip(), spread.strip()
    if not sep or not name or not spread:
        raise ValueError(f"--vary: expected NAME=lo:hi, NAME=normal:mean,sd or NAME=a,b,c; "
                         f"got {text!r}")
    try:
        if spread.startswith("normal:"):
            return Variation(name, "normal", tuple(float(x) for x in spread[7:].split(",")))
        if ":" in spread:
            return Variation(name, "uniform", tuple(float(x) for x in spread.split(":")))
        return Variation(name, "choice", tuple(float(x) for x in spread.split(",")))
    except ValueError as error:
        raise ValueError(f"--vary {text!r}: {error}") from None


def check_names(names, parameter_names) -> None:
    """ValueError for unknown or repeated input ``names`` (``parameter_names``: the
    fittable parameters, :data:`jaxrail.vehicles.parameters.PARAMETERS`)."""
    names = list(names)
    if len(set(names)) != len(names):
        raise ValueError(f"--vary: each input once, got {names}")
    known = set(BOUNDARY_INPUTS) | set(parameter_names)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"--vary: unknown inputs {unknown}; known: "
                         f"{', '.join(BOUNDARY_INPUTS)}, {', '.join(sorted(parameter_names))}")


def draw(variations, n: int, seed: int = 0, design: str = "latin") -> dict:
    """``{name: array}`` of the samples (``n`` each; the grid design gives the product
    of round(n^(1/d)) values per input instead, choices keeping their own count)."""
    if design not in DESIGNS:
        raise ValueError(f"design must be one of {DESIGNS}, got {design!r}")
    if n < 1:
        raise ValueError(f"the number of samples must be >= 1, got {n}")
    rng = np.random.default_rng(seed)
    if design == "grid":
        per_axis = max(1, round(n ** (1.0 / max(1, len(variations)))))
        levels = [v._levels(per_axis) for v in variations]
        mesh = np.meshgrid(*levels, indexing="ij")
        return {v.name: m.ravel().astype(np.float64) for v, m in zip(variations, mesh)}
    out = {}
    for v in variations:
        if design == "latin":
            u = (rng.permutation(n) + rng.random(n)) / n
        else:
            u = rng.random(n)
        out[v.name] = np.asarray(v._from_unit(u), dtype=np.float64)
    return out
