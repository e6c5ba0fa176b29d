"""Design track layout: straights, circular arcs and clothoid transitions.

A layout is a list of segments laid end to end from a start point and heading:

- ``Straight(length)``: zero curvature, zero cant.
- ``Arc(length, radius, direction="left"|"right", cant=0.0)``: constant curvature
  ``+1/radius`` (left) or ``-1/radius`` (right) and constant cant ``cant`` [m], the
  superelevation of the **outer** rail as railway engineers give it (0.150 m is
  typical); a negative cant lowers the outer rail.
- ``Transition(length)``: a clothoid. Curvature and superelevation vary linearly in
  arc length from the end values of the previous segment to the start values of the
  next, so a transition needs a Straight or Arc on both sides.

Signed cant (see :mod:`jaxrail.track.geometry`): inside a :class:`Track` the cant of
an arc carries the sign of its curvature: positive banks toward the left (right rail
raised). A right-hand arc with ``cant=0.150`` therefore has superelevation -0.150 m.

The track is planar (no vertical gradient) and the centreline stays at ``Z = 0``;
cant rolls the track frame about the centreline.

Segment fields may be Python floats or JAX arrays; they become float64 arrays of the
:class:`Track`, so a track built inside a jitted or differentiated function is
differentiable with respect to lengths, radii and cants. Checks that need values
(positive radius, cant continuity) run only on concrete values and are skipped for
traced ones; structural checks always run.
"""

import dataclasses
import functools
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from .geometry import MIN_SAMPLES_PER_SEGMENT, local_heading, local_offset
from .flexible import FlexibleTrack
from .irregularity import Irregularity
from .rails import Rails, standard_rails


class Straight(eqx.Module):
    """Straight segment of ``length`` [m]."""

    length: Float[ArrayLike, ""]


class Arc(eqx.Module):
    """Circular arc: ``length`` [m], ``radius`` [m] > 0, ``direction`` 'left' or
    'right' (static), ``cant`` [m] superelevation of the outer rail."""

    length: Float[ArrayLike, ""]
    radius: Float[ArrayLike, ""]
    direction: str = eqx.field(static=True, default="left")
    cant: Float[ArrayLike, ""] = 0.0


class Transition(eqx.Module):
    """Clothoid transition of ``length`` [m]; curvature and cant ramp linearly between
    its neighbours' values."""

    length: Float[ArrayLike, ""]


Segment = Straight | Arc | Transition


class Track(eqx.Module):
    """A design track: per-segment arrays (traced float64) and static structure.

    Build it with :meth:`Track.from_segments`. Array fields have shape
    ``(n_segments,)`` unless noted; all lengths [m], angles [rad].

    Fields:
        segment_start: arc length at each segment start [m] (first is 0).
        segment_length: segment lengths [m].
        x_start, y_start: global position of each segment start [m].
        heading_start: heading at each segment start [rad] (from +X, counter-clockwise).
        curvature_start: signed curvature at each start [1/m] (> 0 left).
        curvature_rate: d curvature / d s [1/m^2] (non-zero on transitions only).
        superelevation_start: signed cant at each start [m] (> 0 right rail raised).
        superelevation_rate: d superelevation / d s [-].
        rail_centre_distance: lateral distance between rail centres [m] over which the
            cant is measured (scalar).
        sample_s, sample_xy, sample_tangent: coarse centreline samples for the
            projection's initial guess and the centreline's rule from a sample,
            ``(m,)`` [m], ``(m, 2)`` [m] and ``(m, 2)`` the tangent ``(cos h, sin h)``
            there; ``m`` is static.
        rails: the track's :class:`~jaxrail.track.rails.Rails` (their profile and the
            offset that sets the gauge; :meth:`with_rails`), UIC60 1:40 at 1.435 m
            unless given (:func:`~jaxrail.track.rails.standard_rails`).
        kinds: segment kinds ('straight', 'arc', 'transition'), static.
        irregularity: the track's :class:`~jaxrail.track.irregularity.Irregularity`, or
            None for the ideal track (:meth:`with_irregularity`).
        support: the rails' :class:`~jaxrail.track.flexible.FlexibleTrack` under each
            wheel, or None for rigid rails (:meth:`with_support`). The rails'
            deflection is the run's state, not the track's: it is an argument of
            :func:`jaxrail.track.rail_under_wheel` and of the contact search.
    """

    segment_start: Float[Array, " n"]
    segment_length: Float[Array, " n"]
    x_start: Float[Array, " n"]
    y_start: Float[Array, " n"]
    heading_start: Float[Array, " n"]
    curvature_start: Float[Array, " n"]
    curvature_rate: Float[Array, " n"]
    superelevation_start: Float[Array, " n"]
    superelevation_rate: Float[Array, " n"]
    rail_centre_distance: Float[Array, ""]
    sample_s: Float[Array, " m"]
    sample_xy: Float[Array, "m 2"]
    sample_tangent: Float[Array, "m 2"]
    rails: Rails
    kinds: tuple[str, ...] = eqx.field(static=True)
    irregularity: Irregularity | None = None
    support: FlexibleTrack | None = None

    def with_support(self, support: FlexibleTrack | None) -> "Track":
        """This track with flexible rails on ``support`` (None: rigid rails)."""
        if support is not None and not isinstance(support, FlexibleTrack):
            raise TypeError(f"support must be a FlexibleTrack or None, got "
                            f"{type(support).__name__}")
        return dataclasses.replace(self, support=support)

    def with_rails(self, rails: Rails) -> "Track":
        """This layout with ``rails``."""
        return dataclasses.replace(self, rails=_checked_rails(rails))

    def with_irregularity(self, irregularity: Irregularity | None) -> "Track":
        """This layout with ``irregularity`` (None: the ideal track)."""
        if irregularity is not None and not isinstance(irregularity, Irregularity):
            raise TypeError(f"irregularity must be an Irregularity or None, got "
                            f"{type(irregularity).__name__}")
        return dataclasses.replace(self, irregularity=irregularity)

    @property
    def n_segments(self) -> int:
        """Number of segments (static)."""
        return len(self.kinds)

    @property
    def total_length(self) -> Float[Array, ""]:
        """Total arc length of the layout [m]."""
        return self.segment_start[-1] + self.segment_length[-1]

    @classmethod
    def from_segments(
        cls,
        segments: Sequence[Segment],
        start: tuple = (0.0, 0.0, 0.0),
        rail_centre_distance: Float[ArrayLike, ""] = 1.5,
        allow_curvature_jumps: bool = False,
        samples_per_segment: int = 16,
        rails: Rails | None = None,
    ) -> "Track":
        """Build a track from a layout.

        **Arguments:**
            segments: non-empty sequence of Straight, Arc and Transition.
            start: ``(X0, Y0, heading0)`` of the first segment start [m, m, rad].
            rail_centre_distance: distance between rail centres [m] for the cant angle.
            allow_curvature_jumps: accept curvature steps at joints (e.g. a straight
                directly followed by an arc). Cant steps are never accepted.
            samples_per_segment: coarse samples per segment (at least 8, static):
                the projection's initial guess, and where the centreline's integral
                starts (:func:`~jaxrail.track.centreline_position`).
            rails: the track's :class:`~jaxrail.track.rails.Rails` (default
                :func:`~jaxrail.track.rails.standard_rails`).

        Raises ``ValueError`` naming the segment index for non-positive lengths or
        radii, unknown directions, |cant| >= rail_centre_distance, transitions without
        a Straight/Arc on both sides, discontinuous layouts, or an empty layout.
        """
        require_float64("Track")
        segments = list(segments)
        if not segments:
            raise ValueError("segments: empty layout; give at least one segment")
        if len(start) != 3:
            raise ValueError(f"start must be (X0, Y0, heading0), got {start!r}")
        if (not isinstance(samples_per_segment, int)
                or samples_per_segment < MIN_SAMPLES_PER_SEGMENT):
            raise ValueError(
                f"samples_per_segment must be an int >= {MIN_SAMPLES_PER_SEGMENT} (the "
                f"centreline is integrated from the nearest sample), got "
                f"{samples_per_segment!r}")
        base = _scalar(rail_centre_distance, "rail_centre_distance")
        base_value = _concrete(base)
        if base_value is not None and not base_value > 0.0:
            raise ValueError(f"rail_centre_distance must be > 0 m, got {base_value}")

        n = len(segments)
        for i, seg in enumerate(segments):
            _check_segment(i, seg, n, segments, base_value)
        _check_joints(segments, allow_curvature_jumps)

        kinds = tuple(_kind(seg) for seg in segments)
        one = jnp.ones((), dtype=jnp.float64)
        zero = jnp.zeros((), dtype=jnp.float64)
        lengths = jnp.stack([_scalar(seg.length, "length") for seg in segments])
        # Placeholders (radius 1, cant 0) for straights and transitions; unused there.
        radii = jnp.stack([_arc_field(g, "radius", one) for g in segments])
        cants = jnp.stack([_arc_field(g, "cant", zero) for g in segments])
        signs = tuple(_direction_sign(seg) if isinstance(seg, Arc) else 0.0 for seg in segments)
        start = jnp.stack([_scalar(v, "start") for v in start])
        arrays = _assemble(lengths, radii, cants, start, kinds, signs, samples_per_segment)
        rails = standard_rails() if rails is None else _checked_rails(rails)
        return cls(**arrays, rail_centre_distance=base, rails=rails, kinds=kinds)


@functools.partial(jax.jit, static_argnums=(4, 5, 6))
def _assemble(lengths, radii, cants, start, kinds, signs, samples_per_segment):
    """Per-segment arrays of a validated layout (jitted: eager building stays fast;
    inside an outer jit or grad it is simply inlined)."""
    n = len(kinds)
    is_arc = np.array([k == "arc" for k in kinds])
    sign = np.array(signs)
    # Constant curvature and signed cant of straights and arcs (placeholders for
    # transitions, which take their neighbours' values below).
    kappa_c = jnp.where(is_arc, sign / radii, 0.0)
    cant_c = jnp.where(is_arc, sign * cants, 0.0)
    is_tr = np.array([k == "transition" for k in kinds])
    prev = np.clip(np.arange(n) - 1, 0, n - 1)
    nxt = np.clip(np.arange(n) + 1, 0, n - 1)
    k0 = jnp.where(is_tr, kappa_c[prev], kappa_c)
    k_rate = jnp.where(is_tr, (kappa_c[nxt] - kappa_c[prev]) / lengths, 0.0)
    e0 = jnp.where(is_tr, cant_c[prev], cant_c)
    e_rate = jnp.where(is_tr, (cant_c[nxt] - cant_c[prev]) / lengths, 0.0)

    zero = jnp.zeros((1,), dtype=jnp.float64)
    seg_start = jnp.concatenate([zero, jnp.cumsum(lengths)[:-1]])
    dh = local_heading(0.0, k0, k_rate, lengths)
    h_start = start[2] + jnp.concatenate([zero, jnp.cumsum(dh)[:-1]])
    dx, dy = jax.vmap(local_offset)(h_start, k0, k_rate, lengths)
    x_start = start[0] + jnp.concatenate([zero, jnp.cumsum(dx)[:-1]])
    y_start = start[1] + jnp.concatenate([zero, jnp.cumsum(dy)[:-1]])

    # Coarse samples (k + 1 per segment, ends included) for the projection guess.
    frac = jnp.linspace(0.0, 1.0, samples_per_segment + 1, dtype=jnp.float64)
    sigma = lengths[:, None] * frac[None, :]
    offsets = jax.vmap(jax.vmap(local_offset, (None, None, None, 0)))
    sx, sy = offsets(h_start, k0, k_rate, sigma)
    sample_xy = jnp.stack(
        [(x_start[:, None] + sx).reshape(-1), (y_start[:, None] + sy).reshape(-1)], axis=1
    )
    # once here, so that no evaluation of the centreline calls cos and sin
    sample_heading = local_heading(h_start[:, None], k0[:, None], k_rate[:, None], sigma)
    sample_tangent = jnp.stack([jnp.cos(sample_heading).reshape(-1),
                                jnp.sin(sample_heading).reshape(-1)], axis=1)
    return dict(
        segment_start=seg_start,
        segment_length=lengths,
        x_start=x_start,
        y_start=y_start,
        heading_start=h_start,
        curvature_start=k0,
        curvature_rate=k_rate,
        superelevation_start=e0,
        superelevation_rate=e_rate,
        sample_s=(seg_start[:, None] + sigma).reshape(-1),
        sample_xy=sample_xy,
        sample_tangent=sample_tangent,
    )


def _checked_rails(rails):
    if not isinstance(rails, Rails):
        raise TypeError(f"rails must be Rails, got {type(rails).__name__}")
    return rails


def _kind(seg) -> str:
    return {Straight: "straight", Arc: "arc", Transition: "transition"}[type(seg)]


def _scalar(x, name: str) -> Float[Array, ""]:
    arr = jnp.asarray(x, dtype=jnp.float64)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar, got shape {arr.shape}")
    return arr


def _arc_field(seg, name: str, default):
    return _scalar(getattr(seg, name), name) if isinstance(seg, Arc) else default


def _concrete(x) -> float | None:
    """The Python value of a scalar, or None when it is traced (checks skipped)."""
    if isinstance(x, jax.core.Tracer):
        return None
    return float(np.asarray(x))


def _direction_sign(seg: Arc) -> float:
    return 1.0 if seg.direction == "left" else -1.0


def _check_segment(i, seg, n, segments, base_value):
    """Validate segment ``i`` (structure always; values when concrete)."""
    if not isinstance(seg, (Straight, Arc, Transition)):
        raise TypeError(
            f"segments[{i}] must be Straight, Arc or Transition, got {type(seg).__name__}"
        )
    name = f"segments[{i}] ({type(seg).__name__})"
    length = _concrete(_scalar(seg.length, f"{name}.length"))
    if length is not None and not length > 0.0:
        raise ValueError(f"{name}: length must be > 0 m, got {length}")
    if isinstance(seg, Straight):
        return
    if isinstance(seg, Transition):
        if i == 0 or i == n - 1:
            where = "start" if i == 0 else "end"
            raise ValueError(
                f"{name}: a transition at the {where} of the layout has no neighbour to "
                "take its end curvature and cant from; put a Straight or Arc there"
            )
        for j in (i - 1, i + 1):
            if isinstance(segments[j], Transition):
                raise ValueError(
                    f"{name}: neighbour segments[{j}] is also a Transition; a transition "
                    "needs a Straight or Arc on both sides"
                )
        return
    if seg.direction not in ("left", "right"):
        raise ValueError(
            f"{name}: unknown direction {seg.direction!r}; use 'left' or 'right'"
        )
    radius = _scalar(seg.radius, f"{name}.radius")
    r = _concrete(radius)
    if r is not None and not r > 0.0:
        raise ValueError(f"{name}: radius must be > 0 m, got {r}")
    cant = _scalar(seg.cant, f"{name}.cant")
    c = _concrete(cant)
    if c is not None and base_value is not None and not abs(c) < base_value:
        raise ValueError(
            f"{name}: |cant| must be < rail_centre_distance = {base_value} m, got {c}"
        )


def _joint_values(seg):
    """(curvature, signed cant) of a Straight/Arc as Python floats (None if traced)."""
    if isinstance(seg, Straight):
        return 0.0, 0.0
    r, c = _concrete(jnp.asarray(seg.radius)), _concrete(jnp.asarray(seg.cant))
    sign = _direction_sign(seg)
    return (None if r is None else sign / r), (None if c is None else sign * c)


def _check_joints(segments, allow_curvature_jumps: bool) -> None:
    for i in range(len(segments) - 1):
        a, b = segments[i], segments[i + 1]
        if isinstance(a, Transition) or isinstance(b, Transition):
            continue  # transitions match their neighbours by construction
        (ka, ca), (kb, cb) = _joint_values(a), _joint_values(b)
        joint = (
            f"the joint between segments[{i}] ({type(a).__name__}) and "
            f"segments[{i + 1}] ({type(b).__name__})"
        )
        if ca is not None and cb is not None and abs(ca - cb) > 1e-12:
            raise ValueError(
                f"discontinuous layout: cant jumps from {ca} m to {cb} m (signed) at "
                f"{joint}; insert a Transition between them (cant jumps are never allowed)"
            )
        if allow_curvature_jumps:
            continue
        # A straight next to an arc, or arcs turning opposite ways, always jump.
        structural = isinstance(a, Arc) != isinstance(b, Arc) or (
            isinstance(a, Arc) and a.direction != b.direction
        )
        valued = ka is not None and kb is not None and abs(ka - kb) > 1e-12 * max(abs(ka), abs(kb))
        if structural or valued:
            raise ValueError(
                f"discontinuous layout: curvature jumps from {ka} to {kb} 1/m at {joint}; "
                "insert a Transition between them (or pass allow_curvature_jumps=True)"
            )


def curve_layout(
    radius: Float[ArrayLike, ""],
    direction: str = "left",
    cant: Float[ArrayLike, ""] = 0.0,
    straight_in: Float[ArrayLike, ""] = 100.0,
    transition_length: Float[ArrayLike, ""] = 100.0,
    arc_length: Float[ArrayLike, ""] = 300.0,
    straight_out: Float[ArrayLike, ""] = 100.0,
) -> list[Segment]:
    """Segments of the common curve: straight, transition, arc, transition, straight.

    All lengths [m] must be > 0; ``cant`` [m] is the outer-rail superelevation of the
    arc, ramped linearly along both transitions. Pass the list to
    :meth:`Track.from_segments`.
    """
    return [
        Straight(straight_in),
        Transition(transition_length),
        Arc(arc_length, radius, direction, cant),
        Transition(transition_length),
        Straight(straight_out),
    ]


def straight_track(
    length: Float[ArrayLike, ""],
    start: tuple = (0.0, 0.0, 0.0),
    rail_centre_distance: Float[ArrayLike, ""] = 1.5,
    rails: Rails | None = None,
) -> Track:
    """A :class:`Track` of one straight of ``length`` [m] from ``start`` (X0, Y0, heading0)
    with ``rails`` (default :func:`~jaxrail.track.rails.standard_rails`)."""
    return Track.from_segments(
        [Straight(length)], start=start, rail_centre_distance=rail_centre_distance,
        rails=rails)
