"""Profile interface shared by wheels and rails.

Frame and sign conventions (one profile serves both sides of the track, mirrored):

- ``y`` [m] is the lateral coordinate of the profile, positive toward the **field
  side** (away from the track centre). For the left wheel/rail this is the track's +y
  (left); for the right wheel/rail it is the track's -y.
- **Wheel** profiles: ``y`` is measured from the taping line (the ``S`` of EN 13715),
  and ``height(y)`` is the radial distance outward from the taping-line circle, so the
  local rolling radius is ``nominal_radius + height(y)`` and the flange has positive
  height.
- **Rail** profiles: ``y`` is measured from the rail profile origin and ``height(y)``
  is the vertical coordinate, up, in the plane of the track (the rail inclination is
  part of the profile). Over the domain the rail head is a graph ``z(y)``.

All lengths are metres inside the library; files and the command line use mm.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float


class Profile(eqx.Module):
    """A profile curve ``height(y)`` over the lateral domain ``[y_min, y_max]``.

    Subclasses implement :meth:`height`; :meth:`height_derivatives` (height, slope and
    second derivative in one pass), :meth:`slope`, :meth:`second_derivative` and
    :meth:`curvature` follow by automatic differentiation unless a subclass gives
    :meth:`height_derivatives` in closed form. All are pure JAX functions of a scalar
    ``y`` [m]; vmap them for arrays.
    """

    @property
    @abc.abstractmethod
    def domain(self) -> tuple[float, float]:
        """Valid lateral range ``(y_min, y_max)`` [m] (static Python floats)."""

    @abc.abstractmethod
    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        """Profile height [m] at lateral coordinate ``y`` [m] (see module conventions)."""

    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        """``(height [m], d height/dy [-], d^2 height/dy^2 [1/m])`` at ``y`` [m].

        The contact search needs all three at every rail foot Newton step; one pass
        (here forward over forward mode, in closed form where a subclass overrides it)
        costs a fraction of three separate evaluations. Unused outputs cost nothing
        under ``jit``."""
        y = jnp.asarray(y, dtype=jnp.float64)
        one = jnp.ones_like(y)

        def height_and_slope(y):
            return jax.jvp(self.height, (y,), (one,))

        (h, h1), (_, h2) = jax.jvp(height_and_slope, (y,), (one,))
        return h, h1, h2

    def normal_foot(self, eta: Float[ArrayLike, ""], zeta: Float[ArrayLike, ""]):
        """The coordinate ``u`` [m] of the point whose normal passes through the point
        ``(eta, zeta)`` [m] of the profile's plane, in closed form, or None where the
        profile has none (the contact search then takes Newton steps,
        :func:`jaxrail.contact.strip.rail_foot`)."""
        return None

    def normal_foot_depth(self, eta: Float[ArrayLike, ""], zeta: Float[ArrayLike, ""]):
        """The signed depth [m] of the point ``(eta, zeta)`` [m] below the profile along
        the normal at its :meth:`normal_foot` (positive inside), in closed form with
        exact derivatives, or None where the profile has none (the search then measures
        it from the foot, :func:`jaxrail.contact.strip.depth_at_foot`)."""
        return None

    def slope(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        """``d height / d y`` [-] at ``y`` [m]."""
        return self.height_derivatives(y)[1]

    def second_derivative(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        """``d^2 height / d y^2`` [1/m] at ``y`` [m]."""
        return self.height_derivatives(y)[2]

    def curvature(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        """Signed curvature [1/m] of the graph ``height(y)``:
        ``h'' / (1 + h'^2)^(3/2)``; positive where the graph bends upward."""
        h1 = self.slope(y)
        return self.second_derivative(y) / (1.0 + h1 * h1) ** 1.5


class ClosedFormProfile(Profile):
    """A profile that gives :meth:`height_derivatives` in closed form; its height is
    the first of them."""

    @abc.abstractmethod
    def height_derivatives(self, y: Float[ArrayLike, ""]) -> tuple[Array, Array, Array]:
        """``(height [m], slope [-], second derivative [1/m])`` at ``y`` [m]."""

    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        return self.height_derivatives(y)[0]


class WheelProfile(eqx.Module):
    """A wheel: its contact surfaces and nominal rolling radius.

    Fields:
        surfaces: the profile pieces searched for contact independently (static
            tuple). A real profile has one surface; the paper's simplified profile has
            two (tread, flange), each convex.
        nominal_radius: rolling radius at the taping line [m] (traced parameter).
        name: a label for plots and files (static).
    """

    surfaces: tuple[Profile, ...]
    nominal_radius: Float[Array, ""]
    name: str = eqx.field(static=True, default="wheel")

    def rolling_radius(self, y: Float[ArrayLike, ""], surface: int = 0) -> Float[Array, ""]:
        """Rolling radius [m] at lateral coordinate ``y`` [m] of surface ``surface``."""
        return self.nominal_radius + self.surfaces[surface].height(y)


def frozen(tree):
    """``tree`` (a profile, or a profile with the points it is evaluated at) with every
    array leaf behind ``stop_gradient``: for the fixed-count searches on a profile whose
    loops must trace no tangents (the measures' bisections, the rail foot's Newton
    steps), before one last step with the real profile carries the derivatives."""
    return jax.tree.map(lambda x: jax.lax.stop_gradient(x) if eqx.is_array(x) else x, tree)


def below_tangent(eta, zeta, y, height, slope):
    """Signed distance [m] of the point ``(eta, zeta)`` [m] below the line through
    ``(y, height)`` [m] with ``slope`` [-] (positive below): a profile's depth under
    its tangent line at ``y``."""
    return -((zeta - height) - (eta - y) * slope) / jnp.sqrt(1.0 + slope * slope)
