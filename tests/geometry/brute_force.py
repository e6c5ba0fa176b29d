"""Independent rigid wheel-rail contact in NumPy: dense sampling of both profiles.

No yaw, straight track. For a lateral shift and a roll angle the wheel profile curves
are placed in the track cross-section; the height at which each wheel first touches
its rail is the smallest vertical gap over the densely sampled wheel points (rail
heights by linear interpolation of a dense rail sampling). The roll is then solved with
brentq so that both wheels touch at the same wheelset height.
"""

import numpy as np
from scipy.optimize import brentq

HALF_TAPING = 0.75


def sample(profile, step=5e-6):
    lo, hi = profile.domain
    y = np.arange(lo, hi, step)
    import jax

    return y, np.asarray(jax.jit(jax.vmap(profile.height))(y))


class BruteForce:
    def __init__(self, wheel, rail, offset, step=5e-6):
        self.r0 = float(wheel.nominal_radius)
        self.wheel_y, self.wheel_f = sample(wheel.surfaces[0], step)
        self.rail_y, self.rail_z = sample(rail, step / 2)
        self.offset = float(offset)

    def _touch(self, side, shift, roll):
        """Wheelset centre height at which wheel `side` touches, and the contact's
        wheel profile coordinate and track lateral position."""
        lateral_body = side * (HALF_TAPING + self.wheel_y)
        vertical_body = -(self.r0 + self.wheel_f)
        c, s = np.cos(roll), np.sin(roll)
        lateral = shift + c * lateral_body - s * vertical_body
        vertical = s * lateral_body + c * vertical_body
        u = side * lateral - self.offset
        rail = np.interp(u, self.rail_y, self.rail_z, left=np.nan, right=np.nan)
        gap = vertical - rail
        i = np.nanargmin(gap)
        return -gap[i], self.wheel_y[i], lateral[i]

    def solve(self, shift):
        """(roll, y_wheel_left, y_wheel_right, delta_r, lateral_left, lateral_right)."""
        mismatch = lambda roll: self._touch(1.0, shift, roll)[0] - self._touch(-1.0, shift, roll)[0]  # noqa: E731
        roll = brentq(mismatch, -0.02, 0.02, xtol=1e-13)
        _, y_left, lat_left = self._touch(1.0, shift, roll)
        _, y_right, lat_right = self._touch(-1.0, shift, roll)
        f = lambda y: np.interp(y, self.wheel_y, self.wheel_f)  # noqa: E731
        return roll, y_left, y_right, f(y_left) - f(y_right), lat_left, lat_right
