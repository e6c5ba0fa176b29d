"""What a run returns: :class:`SimulationResult` (body states, wheelset positions, the
track's irregularity and deflection, statistics) with the contact details of every wheel
and patch, :class:`WheelOutputs`."""

import diffrax
import equinox as eqx
import jax
import numpy as np


class WheelOutputs(eqx.Module):
    """Contact details at the output times; leading shape (T, W, 2, P): time, wheelset
    (leading first), wheel (left, right), patch slot.

    Fields: active; surface (index into the wheel's surfaces); y_wheel, y_rail [m]
    lateral position of the contact point on the wheel and rail profiles; penetration
    [m]; contact_angle [rad]; normal_force [N]; creep_force_x, creep_force_y [N]
    (contact frame, on the wheel); creepage_x, creepage_y [-], spin [1/m];
    semi_axis_a, semi_axis_b [m]: the Hertz ellipse's semi-axes along the rolling
    direction and across it (zero where the slot is empty).
    Per wheel (T, W, 2): lateral_force and vertical_force Q [N], track frame, on the
    wheel from the rail (lateral positive towards the wheel's own field side, so a
    flanging wheel has a negative value; Nadal's Y, the wheel's force on the rail, is
    its negative: :func:`jaxrail.results.derailment_ratio`).
    """

    active: jax.Array
    surface: jax.Array
    y_wheel: jax.Array
    y_rail: jax.Array
    penetration: jax.Array
    contact_angle: jax.Array
    normal_force: jax.Array
    creep_force_x: jax.Array
    creep_force_y: jax.Array
    creepage_x: jax.Array
    creepage_y: jax.Array
    spin: jax.Array
    semi_axis_a: jax.Array
    semi_axis_b: jax.Array
    lateral_force: jax.Array
    vertical_force: jax.Array


class SimulationResult(eqx.Module):
    """Output of :func:`simulate`.

    Fields:
        t (T,) [s]; q, qdot (T, 7 n): body states (jaxrail.multibody conventions);
        qddot (T, 7 n): their accelerations (eq. 19 with the loads of the outputs; NaN
            after an early stop);
        valid (T,): output times the run reached (False after an early stop);
        wheelset_lateral, wheelset_vertical, wheelset_yaw (T, W): wheelset centre
            relative to the design track centreline [m] and yaw relative to the track
            [rad];
        irregularity (T, W, 4): the track's irregularity channels at each wheelset
            (alignment, vertical level, cross level, gauge; :mod:`jaxrail.track.irregularity`)
            [m], zeros on an ideal track;
        rail_deflection (T, W, 2, 2): on a flexible track, the deflection of the rails
            under each wheelset (left, right; lateral along the canted track frame's
            ``n``, vertical along its ``b``) [m] (:mod:`jaxrail.track.flexible`),
            zeros on rigid rails;
        wheels: :class:`WheelOutputs`;
        constraint_violation (T,): max |Phi| over the joint rows;
        result: diffrax's result code; derailed: the derailment event fired;
        steps, accepted_steps, rejected_steps: integrator statistics;
        rhs_evaluations, jacobian_evaluations: the right-hand sides and load
            Jacobians the integration evaluated (:func:`evaluations_per_step`; -1 for a
            solver it does not know);
        wall_time_s, compile_time_s: host timings (NaN inside jit/vmap).
    """

    t: jax.Array
    q: jax.Array
    qdot: jax.Array
    qddot: jax.Array
    valid: jax.Array
    wheelset_lateral: jax.Array
    wheelset_vertical: jax.Array
    wheelset_yaw: jax.Array
    irregularity: jax.Array
    rail_deflection: jax.Array
    wheels: WheelOutputs
    constraint_violation: jax.Array
    result: jax.Array
    derailed: jax.Array
    steps: jax.Array
    accepted_steps: jax.Array
    rejected_steps: jax.Array
    rhs_evaluations: jax.Array
    jacobian_evaluations: jax.Array
    wall_time_s: jax.Array
    compile_time_s: jax.Array

    @property
    def status(self) -> str:
        """"successful", "derailed", "max_steps_reached", "failed: singular implicit
        solve" (the IMEX step's matrix was not finite or singular) or "failed" (a state
        that turned non-finite, or another diffrax failure) (host only, for an unbatched
        result)."""
        if bool(self.derailed):
            return "derailed"
        if self.result == diffrax.RESULTS.successful:
            return "successful"
        if self.result == diffrax.RESULTS.max_steps_reached:
            return "max_steps_reached"
        if self.result == diffrax.RESULTS.singular:
            return "failed: singular implicit solve"
        return "failed"

    @property
    def simulated_time_s(self) -> float:
        """Last output time the run reached [s]."""
        return float(np.max(np.where(np.asarray(self.valid), np.asarray(self.t), 0.0)))
