"""A run's settings: the integrator and its step-size control (:class:`SolverOptions`,
static) and the derailment limits that stop it (:class:`DerailmentLimits`, traced)."""

import dataclasses

import diffrax
import equinox as eqx
import jax

from .._constants import INTEGRATORS as INTEGRATORS
from .._float64 import f64
from ..multibody.imex import IMEX, check_jacobian_every


class DerailmentLimits(eqx.Module):
    """A run stops as derailed when any wheelset's centre is more than ``lateral`` [m]
    from the track centreline or any wheel is ``lift`` [m] above its initial height
    (the S1002 flange is 28 mm high: at 25 mm lift the flange is on the rail head).
    Traced: changing them does not recompile."""

    lateral: jax.Array = eqx.field(converter=f64, default=0.035)
    lift: jax.Array = eqx.field(converter=f64, default=0.025)



@dataclasses.dataclass(frozen=True)
class SolverOptions:
    """Integration settings (static: changing them recompiles).

    rtol, atol: PID controller tolerances; dt0 [s]: first step; max_steps: per run;
    n_outputs: number of equally spaced output times (including t = 0 and t1);
    (defaults measured in docs/simulation.md: rtol 1e-4 moves the wheelsets' lateral
    displacement by under 10 um against 1e-5 in 0.5 s, in two thirds of the steps)
    progress: show a progress bar of simulated seconds with the real-time factor.
    pcoeff, icoeff: the PID controller's proportional and integral coefficients
    (0.4 and 0.3: in flange contact the steps are limited by stability, where diffrax's
    plain integral controller (0 and 1) rejects one step in five; see docs/simulation.md).
    fixed_step: a constant step [s] instead of the controller (then rtol, atol, dt0,
    pcoeff and icoeff are unused): the outputs are then smooth functions of the
    parameters, which gradients checked by finite differences and fits need
    (docs/identification.md).
    integrator: one of :data:`INTEGRATORS`: "tsit5" (explicit, held to
    steps of about 0.3 ms by the stiff creep) or "imex" (the creep and the normal
    contact stiffness implicit, :class:`jaxrail.multibody.imex.IMEX`, KenCarp5;
    steps of about 1 ms; docs/simulation.md).
    jacobian_every: with "imex", a new load Jacobian every this many accepted steps,
    carried by the wheelsets' spin in between (1: every step; docs/simulation.md).
    """

    rtol: float = 1e-4
    atol: float = 1e-7
    dt0: float = 1e-4
    max_steps: int = 2_000_000
    n_outputs: int = 201
    progress: bool = False
    pcoeff: float = 0.4
    icoeff: float = 0.3
    fixed_step: float | None = None
    integrator: str = "tsit5"
    jacobian_every: int = 8

    def __post_init__(self):
        if self.fixed_step is not None and not self.fixed_step > 0.0:
            raise ValueError(f"fixed_step must be > 0 [s], got {self.fixed_step}")
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got "
                             f"{self.integrator!r}")
        check_jacobian_every(self.jacobian_every)

    def solver(self):
        """The diffrax solver of ``integrator``."""
        if self.integrator == "imex":
            return IMEX(jacobian_every=self.jacobian_every)
        return diffrax.Tsit5()

    def controller(self):
        """diffrax step-size controller and first step [s]."""
        if self.fixed_step is not None:
            return diffrax.ConstantStepSize(), self.fixed_step
        return diffrax.PIDController(rtol=self.rtol, atol=self.atol, pcoeff=self.pcoeff,
                                     icoeff=self.icoeff), self.dt0

