"""Wear laws: the wear volume rate of each element of a patch (:mod:`.fastsim`), from its
Hertz pressure, traction and sliding velocity.

- :class:`ArchardKTH`: Archard's law ``dV = k p v_s dA dt / H`` with the wear
  coefficient ``k`` of the KTH wear map (Jendel 2002), a function of the sliding
  velocity ``v_s`` and the contact pressure ``p``.
- :class:`USFD`: the Tgamma/A wear function of the University of Sheffield (Braghin,
  Lewis, Dwyer-Joyce and Bruni 2006): a wear rate [ug per m rolled per mm^2 of
  contact] of the local wear index ``tau . s`` [N/mm^2], in three regions (mild,
  severe, catastrophic).

Each number below carries its source and a tag: [published] as the cited paper gives it (with how
sure: likely = from papers quoting it, not read in the original here), [chosen] a
value picked inside a published range, [unsure] an estimate.

The KTH map is piecewise constant: its coefficient jumps seven- to tenfold at the
edges. Summed over many elements and output times, such jumps make the wear volume a
smooth function of the parameters whose derivative automatic differentiation of the
steps cannot see (the elements crossing an edge). Each edge is therefore blended over
``edge (1 +- transition)`` (default 5 %) with a cubic smoothstep; outside that band the
published values hold exactly, and 0 gives the published steps.
"""

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._float64 import f64

MODELS = ("archard-kth", "usfd")
"""The wear laws by name (:func:`wear_law`)."""

STEEL_DENSITY = 7800.0  # [kg/m^3] wheel and rail steel, converting the USFD mass rate


def _step(x, edge, relative_width: float):
    """0 below ``edge``, 1 above; a cubic smoothstep (C1) over ``edge (1 +- relative_width)``
    (a static float) and exact outside it, the exact step when it is 0."""
    x = jnp.asarray(x, dtype=jnp.float64)
    if relative_width == 0.0:
        return (x > edge).astype(jnp.float64)
    u = jnp.clip(0.5 + (x - edge) / (2.0 * relative_width * edge), 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


class ArchardKTH(eqx.Module):
    """Archard's law with the KTH wear map (Jendel 2002, Wear 253, 89-99; the map
    compiled from dry pin-on-disc tests of wheel and rail steels at KTH).

    Regions, v_s the sliding velocity, p the contact pressure:
    - ``p < 0.8 H`` and ``v_s < 0.2 m/s``: ``k1``;
    - ``p < 0.8 H`` and ``0.2 <= v_s < 0.7 m/s``: ``k2``;
    - ``p < 0.8 H`` and ``v_s >= 0.7 m/s``: ``k3``;
    - ``p >= 0.8 H``: ``k4`` (seizure).

    The edges 0.2 and 0.7 m/s and 0.8 H [published, likely]; the ranges of k
    (:data:`KTH_RANGES`) [published, likely; k4's range unsure: (300-400)e-4 as read
    from Jendel's map and quoted by Ignesti et al. 2012, Wear 284-285, 1-17; one
    secondary source gives (150-250)e-4]. The defaults are the middles of the ranges
    [chosen]; dry contact (no lubrication factor).

    Fields (traced): hardness H [Pa] ([chosen] 2.45 GPa = 250 HB, the order of R7/R8
    wheel steel); k1..k4 [-]. Static: ``transition`` [-] the relative blend width of
    the region edges (module docstring); ``max_sliding_velocity`` [m/s] and
    ``max_pressure_over_hardness`` [-]: the map's axes [unsure: 1 m/s and 1 H], beyond
    which its outer regions are held (:meth:`extrapolated` reports where).
    """

    hardness: Float[Array, ""] = eqx.field(converter=f64, default=2.45e9)
    k1: Float[Array, ""] = eqx.field(converter=f64, default=5.5e-4)
    k2: Float[Array, ""] = eqx.field(converter=f64, default=35e-4)
    k3: Float[Array, ""] = eqx.field(converter=f64, default=5.5e-4)
    k4: Float[Array, ""] = eqx.field(converter=f64, default=350e-4)
    transition: float = eqx.field(static=True, default=0.05)
    velocity_edges: tuple = eqx.field(static=True, default=(0.2, 0.7))
    pressure_edge: float = eqx.field(static=True, default=0.8)
    max_sliding_velocity: float = eqx.field(static=True, default=1.0)
    max_pressure_over_hardness: float = eqx.field(static=True, default=1.0)

    def coefficient(self, pressure, sliding_velocity):
        """Wear coefficient k [-] at ``pressure`` [Pa] and ``sliding_velocity`` [m/s]."""
        w = self.transition
        v1, v2 = self.velocity_edges
        over_2 = _step(sliding_velocity, v1, w)
        over_3 = _step(sliding_velocity, v2, w)
        low = self.k1 + (self.k2 - self.k1) * over_2 + (self.k3 - self.k2) * over_3
        edge = self.pressure_edge * self.hardness
        return low + (self.k4 - low) * _step(pressure, edge, w)

    def volume_rate(self, grid, speed):
        """Wear volume rate [m^3/s] of each element of ``grid`` (a
        :class:`~jaxrail.wear.fastsim.PatchGrid`) at rolling speed ``speed`` [m/s]:
        ``k p v_s dA / H``, ``v_s = V |s|``."""
        v_s = speed * grid.sliding
        return self.coefficient(grid.pressure, v_s) * grid.pressure * v_s * grid.area \
            / self.hardness

    def extrapolated(self, grid, speed):
        """True for the elements whose sliding velocity or pressure lies beyond the
        map's axes (there its outer regions are held)."""
        return ((speed * grid.sliding > self.max_sliding_velocity)
                | (grid.pressure > self.max_pressure_over_hardness * self.hardness))

    def check(self):
        """A clear error when a wear coefficient lies outside its published range
        (host values; before anything compiles)."""
        check_fields("archard-kth", {name: float(getattr(self, name))
                                     for name in ("hardness", *KTH_RANGES)})
        return self

    @staticmethod
    def _check_values(values: dict) -> None:
        for name, (low, high) in KTH_RANGES.items():
            if name in values and not low <= values[name] <= high:
                raise ValueError(
                    f"wear model archard-kth: {name} = {values[name]:g} lies outside the "
                    f"KTH map's published range [{low:g}, {high:g}] (Jendel 2002)")
        if "hardness" in values and not values["hardness"] > 0.0:
            raise ValueError(f"wear model archard-kth: hardness must be > 0 Pa, got "
                             f"{values['hardness']:g}")


KTH_RANGES = {"k1": (1e-4, 10e-4), "k2": (30e-4, 40e-4), "k3": (1e-4, 10e-4),
              "k4": (300e-4, 400e-4)}
"""The published ranges of the KTH map's wear coefficients [-] (:class:`ArchardKTH`)."""


class USFD(eqx.Module):
    """The USFD Tgamma/A wear function (Braghin, Lewis, Dwyer-Joyce and Bruni 2006,
    Wear 261, 1253-1264; twin-disc tests of R8T wheel against UIC60 900A rail steel,
    dry, Lewis and Dwyer-Joyce 2004), applied per element with the local wear index
    ``I = |tau . s|`` [N/mm^2] (tau the traction, s the local slip), as Braghin et al.
    apply it in the FASTSIM elements.

    Wear rate K [ug/(m mm^2)], I in N/mm^2 [published, likely]:
    - mild, ``I < 10.4``: ``K = 5.3 I``;
    - severe, ``10.4 <= I <= 77.2``: ``K = 55.0``;
    - catastrophic, ``I > 77.2``: ``K = 61.9 I - 4778.7``.

    The published catastrophic line is -0.02 at its edge 77.2 and reaches the severe
    plateau only at I = 78.09; here the plateau holds until the line crosses it
    (``max(55.0, 61.9 I - 4778.7)``), so the rate does not drop to zero past 77.2.
    (At 10.4 the published constants step from 5.3 x 10.4 = 55.12 to 55.0; kept.)

    Fields: density [kg/m^3] converting mass to volume ([chosen] 7800, steel);
    ``max_index`` [N/mm^2] the top of the tests' range ([unsure] 150): above it the
    catastrophic line is extrapolated (:meth:`extrapolated`).
    """

    density: Float[Array, ""] = eqx.field(converter=f64, default=STEEL_DENSITY)
    mild_slope: float = eqx.field(static=True, default=5.3)
    severe_rate: float = eqx.field(static=True, default=55.0)
    catastrophic_slope: float = eqx.field(static=True, default=61.9)
    catastrophic_offset: float = eqx.field(static=True, default=-4778.7)
    edges: tuple = eqx.field(static=True, default=(10.4, 77.2))
    max_index: float = eqx.field(static=True, default=150.0)

    def rate(self, index):
        """Wear rate K [ug/(m mm^2)] at the wear index ``index`` [N/mm^2]."""
        index = jnp.asarray(index, dtype=jnp.float64)
        catastrophic = jnp.maximum(self.severe_rate,
                                   self.catastrophic_slope * index + self.catastrophic_offset)
        upper = jnp.where(index > self.edges[1], catastrophic, self.severe_rate)
        return jnp.where(index < self.edges[0], self.mild_slope * index, upper)

    def index(self, grid):
        """The local wear index ``|tau . s|`` [N/mm^2] of each element."""
        return jnp.abs(grid.traction_x * grid.slip_x + grid.traction_y * grid.slip_y) * 1e-6

    def volume_rate(self, grid, speed):
        """Wear volume rate [m^3/s] of each element: ``K dA V / density``, with dA in
        mm^2, K in ug/(m mm^2), V [m/s]."""
        mass_rate = self.rate(self.index(grid)) * (grid.area * 1e6) * speed * 1e-9  # [kg/s]
        return mass_rate / self.density

    def extrapolated(self, grid, speed):
        """True for the elements whose wear index lies beyond the tests' range."""
        return self.index(grid) > self.max_index

    def check(self):
        """A clear error for a density that is not positive."""
        check_fields("usfd", {"density": float(self.density)})
        return self

    @staticmethod
    def _check_values(values: dict) -> None:
        if "density" in values and not values["density"] > 0.0:
            raise ValueError(f"wear model usfd: density must be > 0 kg/m^3, got "
                             f"{values['density']:g}")


_LAWS = {"archard-kth": ArchardKTH, "usfd": USFD}


def check_fields(name: str, fields: dict) -> None:
    """A clear error for an unknown model ``name``, a field it does not have, a value
    that is not a number, or one outside its published range; on plain values, so a
    route file is checked without building the law (no JAX)."""
    if name not in _LAWS:
        raise ValueError(f"unknown wear model {name!r}: use one of {', '.join(MODELS)}")
    law = _LAWS[name]
    known = [f.name for f in dataclasses.fields(law)]
    unknown = sorted(set(fields) - set(known))
    if unknown:
        raise ValueError(f"wear model {name}: unknown field(s) {unknown}; it has "
                         f"{', '.join(known)}")
    values = {}
    for key, value in fields.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ValueError(f"wear model {name}: {key} must be a finite number, got "
                             f"{value!r}")
        values[key] = float(value)
    law._check_values(values)


def wear_law(name: str, **fields):
    """The wear law ``name`` (one of :data:`MODELS`) with ``fields`` overriding its
    defaults; a clear error for an unknown name."""
    check_fields(name, fields)
    return _LAWS[name](**fields)
