"""Normal contact force laws: pure Hertz, the paper's eq. (17), and the compliant-contact
models with damping (Hunt-Crossley, Lankarani-Nikravesh, Flores), behind one interface.

Sign convention (all laws): ``penetration`` delta [m] is the overlap, delta > 0 in
contact; ``penetration_rate`` = d delta / dt [m/s] is **positive while the bodies
approach (compression)** and negative while they separate (restitution). With this
convention every law here dissipates energy. Passing the rate of a signed *gap*
(negative in contact) instead flips loading and unloading, and eq. (17) then *gains*
energy (rebound speed 1/sqrt(c_e) times the impact speed; tested).

For delta <= 0 every law returns exactly 0 with zero gradient. No law returns a
negative (adhesive) force: damped laws are clipped at 0 during fast separation.

Each law is an ``equinox.Module`` whose physical numbers are traced float64 arrays, so
a batch of laws (vmap) or gradients with respect to restitution, v0 or the exponent
work. Which law is used is structure (the Python class). See docs/normal-forces.md.
"""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from jaxrail._float64 import require_float64
from jaxrail.contact._checks import check_range as _check_range


def _as_f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


def hertz_power(
    stiffness: Float[ArrayLike, "..."],
    penetration: Float[ArrayLike, "..."],
    exponent: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """K delta^n [N] for delta > 0, else 0; finite gradient (zero) at delta <= 0."""
    delta = _as_f64(penetration)
    inside = delta > 0.0
    safe = jnp.where(inside, delta, 1.0)
    return jnp.where(inside, _as_f64(stiffness) * safe ** _as_f64(exponent), 0.0)


class NormalLaw(eqx.Module):
    """Interface: normal force from stiffness, penetration and penetration rate."""

    @abc.abstractmethod
    def force(
        self,
        stiffness: Float[ArrayLike, "..."],
        penetration: Float[ArrayLike, "..."],
        penetration_rate: Float[ArrayLike, "..."],
        impact_velocity: Float[ArrayLike, "..."] | None = None,
    ) -> Float[Array, "..."]:
        """Normal force [N] >= 0.

        Arguments:
            stiffness: K [N/m^n] (Hertz: K_H in N/m^1.5, see jaxrail.contact.hertz).
            penetration: delta [m], > 0 in contact.
            penetration_rate: d delta/dt [m/s], > 0 while approaching.
            impact_velocity: delta_dot^- [m/s] > 0 of the current impact, for the laws
                that need it (Hunt-Crossley, Lankarani-Nikravesh, Flores); overrides
                their ``impact_velocity`` field. Ignored by the others.
        """


class Hertz(NormalLaw):
    """Elastic law f = K delta^n (no dissipation).

    Fields:
        exponent: n [-] (1.5 for Hertz point contact).
    """

    exponent: Float[Array, ""]

    def __init__(self, exponent: Float[ArrayLike, ""] = 1.5):
        require_float64("Hertz normal law")
        _check_range("exponent", exponent, 0.0, 10.0)
        self.exponent = _as_f64(exponent)

    def force(self, stiffness, penetration, penetration_rate, impact_velocity=None):
        del penetration_rate, impact_velocity
        return hertz_power(stiffness, penetration, self.exponent)


class Eq17(NormalLaw):
    """The paper's eq. (17): a smoothed loading/unloading hysteresis.

        f = K delta^n c_e                                   for delta_dot <= -v0
        f = K delta^n [c_e + (1 - c_e)(3 r^2 - 2 r^3)],     r = (delta_dot + v0)/(2 v0)
        f = K delta^n                                       for delta_dot >= v0

    Read before use (measured in docs/normal-forces.md):

    - ``restitution`` is the paper's c_e, the scale factor of the unloading branch. The
      **effective coefficient of restitution is sqrt(c_e)** (energy returned is c_e
      times energy stored). To prescribe the true coefficient e, build the law with
      :meth:`Eq17.from_restitution` (c_e = e^2).
    - At delta_dot = 0 (steady rolling) the force is (1 + c_e)/2 of Hertz, so the
      static penetration exceeds Hertz by ((1 + c_e)/2)^(-1/n).
    - Near delta_dot = 0 it acts as a damper c_eq = 0.75 K delta^n (1 - c_e) / v0.

    Fields (traced):
        restitution: c_e in [0, 1] (default 0.8: effective e = 0.894, force at rest
            0.9 of Hertz, i.e. penetration +7 %).
        v0: velocity tolerance [m/s] (default 0.01: impacts faster than 0.1 m/s
            rebound within 0.3 % of sqrt(c_e); in rolling, a 50 kN wheel load with
            1 t on the contact gets c_eq = 7.5e5 N s/m, damping ratio ~0.35 of the
            ~170 Hz contact mode, whereas v0 = 1e-3 m/s is 3.5x overcritical and
            makes the ODE stiff).
        exponent: n [-] (default 1.5).
    """

    restitution: Float[Array, ""]
    v0: Float[Array, ""]
    exponent: Float[Array, ""]

    def __init__(
        self,
        restitution: Float[ArrayLike, ""] = 0.8,
        v0: Float[ArrayLike, ""] = 0.01,
        exponent: Float[ArrayLike, ""] = 1.5,
    ):
        require_float64("Eq17 normal law")
        _check_range("restitution", restitution, 0.0, 1.0, low_open=False)
        _check_range("v0", v0, 0.0, jnp.inf)
        _check_range("exponent", exponent, 0.0, 10.0)
        self.restitution = _as_f64(restitution)
        self.v0 = _as_f64(v0)
        self.exponent = _as_f64(exponent)

    @classmethod
    def from_restitution(
        cls,
        coefficient_of_restitution: Float[ArrayLike, ""],
        v0: Float[ArrayLike, ""] = 0.01,
        exponent: Float[ArrayLike, ""] = 1.5,
    ) -> "Eq17":
        """Eq. (17) tuned so that impacts rebound with the true coefficient e:
        c_e = e^2."""
        e = _as_f64(coefficient_of_restitution)
        return cls(restitution=e * e, v0=v0, exponent=exponent)

    @property
    def effective_restitution(self) -> Float[Array, ""]:
        """Coefficient of restitution of an impact with |delta_dot| >> v0: sqrt(c_e)."""
        return jnp.sqrt(self.restitution)

    def force(self, stiffness, penetration, penetration_rate, impact_velocity=None):
        del impact_velocity
        r = jnp.clip((_as_f64(penetration_rate) + self.v0) / (2.0 * self.v0), 0.0, 1.0)
        blend = r * r * (3.0 - 2.0 * r)
        scale = self.restitution + (1.0 - self.restitution) * blend
        return jnp.maximum(hertz_power(stiffness, penetration, self.exponent) * scale, 0.0)


class _DampedHertz(NormalLaw):
    """f = K delta^n [1 + alpha(c_e) delta_dot / delta_dot^-], clipped at 0.

    Fields (traced):
        restitution: coefficient of restitution c_e in (0, 1].
        exponent: n [-] (default 1.5).
        impact_velocity: reference impact velocity delta_dot^- [m/s] > 0 used when
            ``force`` gets none (default 0.1 m/s). A continuous simulation does not know
            the impact velocity of each contact at each step; with a fixed reference
            the law is a fixed nonlinear damper c = alpha K delta^n / impact_velocity,
            and impacts near that speed rebound with about the nominal e (faster
            impacts lose more energy, slower ones less). Set it to the normal approach
            speed of the impacts you care about (flange impacts: ~0.1 m/s), or pass
            the actual impact speed per contact through ``force(..., impact_velocity)``.
    """

    restitution: Float[Array, ""]
    exponent: Float[Array, ""]
    impact_velocity: Float[Array, ""]

    def __init__(
        self,
        restitution: Float[ArrayLike, ""],
        exponent: Float[ArrayLike, ""] = 1.5,
        impact_velocity: Float[ArrayLike, ""] = 0.1,
    ):
        require_float64(f"{type(self).__name__} normal law")
        _check_range("restitution", restitution, 0.0, 1.0)
        _check_range("exponent", exponent, 0.0, 10.0)
        _check_range("impact_velocity", impact_velocity, 0.0, jnp.inf)
        self.restitution = _as_f64(restitution)
        self.exponent = _as_f64(exponent)
        self.impact_velocity = _as_f64(impact_velocity)

    @abc.abstractmethod
    def damping_factor(self) -> Float[Array, ""]:
        """alpha(c_e) [-]: f = K delta^n (1 + alpha delta_dot / delta_dot^-)."""

    def force(self, stiffness, penetration, penetration_rate, impact_velocity=None):
        _check_range("impact_velocity", impact_velocity, 0.0, jnp.inf)
        v_impact = self.impact_velocity if impact_velocity is None else impact_velocity
        ratio = _as_f64(penetration_rate) / _as_f64(v_impact)
        elastic = hertz_power(stiffness, penetration, self.exponent)
        return jnp.maximum(elastic * (1.0 + self.damping_factor() * ratio), 0.0)


class HuntCrossley(_DampedHertz):
    """Hunt-Crossley: f = K delta^n + chi delta^n delta_dot, chi = 3K(1 - c_e)/(2 delta_dot^-),
    i.e. alpha = 3(1 - c_e)/2. Derived for c_e near 1; dissipates too much for low c_e
    (measured in docs/normal-forces.md)."""

    def damping_factor(self):
        return 1.5 * (1.0 - self.restitution)


class LankaraniNikravesh(_DampedHertz):
    """Lankarani-Nikravesh (1990): alpha = 3(1 - c_e^2)/4. Accurate for c_e near 1
    (restitution overestimated for low c_e); used by Pombo/Ambrosio for wheel-rail."""

    def damping_factor(self):
        return 0.75 * (1.0 - self.restitution**2)


class Flores(_DampedHertz):
    """Flores et al. (2011): alpha = 8(1 - c_e)/(5 c_e). Designed to give the nominal
    c_e over the whole range (0, 1]."""

    def damping_factor(self):
        return 1.6 * (1.0 - self.restitution) / self.restitution
