"""A profile from measured points: a natural cubic spline (C2), optionally smoothing.

The spline is stored as knots ``y_i``, knot heights ``g_i`` and knot second derivatives
``m_i`` (natural: ``m_0 = m_{n-1} = 0``), all jax arrays. On ``[y_i, y_{i+1}]`` with
``h = y_{i+1} - y_i``, ``a = (y_{i+1} - y)/h`` and ``b = 1 - a``::

    height(y) = a g_i + b g_{i+1} + ((a^3 - a) m_i + (b^3 - b) m_{i+1}) h^2 / 6

Height, slope and second derivative are continuous across knots. Beyond the end knots
the profile goes on as a straight line with the end slope (this is C2 too, because
``m = 0`` at the ends). The values there are extrapolation; the domain is
``(y_0, y_{n-1})``.

Fitting (:meth:`TabulatedProfile.from_points`, numpy, at construction) minimises::

    sum_i (z_i - f(y_i))^2  +  smoothing * integral f''(y)^2 dy      (all in metres)

over natural cubic splines with knots at the data (Reinsch 1967). ``smoothing = 0``
interpolates. ``smoothing`` has units m^3: the penalty weighs squared curvature [1/m^2]
integrated over a length [m] against squared height residuals [m^2]. The objective is
that of ``scipy.interpolate.make_smoothing_spline(y, z, lam=smoothing)``.

The fields are traced: a batch of profiles on one knot grid (same ``y``, different ``z``)
stacks and vmaps, and heights are differentiable with respect to ``values`` and
``second_derivatives``. The fit itself is not traced, so derivatives with respect to the
raw measured points are not available.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._float64 import require_float64
from ._base import Profile, WheelProfile


def _as_points(name: str, values) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of points, got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f"{name} has a non-finite value (NaN or inf) at index {bad[0]}")
    return array


def _validate_points(y, z) -> tuple[np.ndarray, np.ndarray]:
    """Check measured points; return them as float64 numpy arrays (ValueError if bad)."""
    y = _as_points("y", y)
    z = _as_points("z", z)
    if y.shape != z.shape:
        raise ValueError(f"y and z must have the same length, got {y.size} and {z.size}")
    if y.size < 4:
        raise ValueError(f"a tabulated profile needs at least 4 points, got {y.size}")
    step = np.diff(y)
    repeated = np.flatnonzero(step == 0.0)
    if repeated.size:
        i = repeated[0]
        raise ValueError(f"y has a repeated value {y[i]!r} at indices {i} and {i + 1}")
    unsorted = np.flatnonzero(step < 0.0)
    if unsorted.size:
        i = unsorted[0]
        raise ValueError(
            f"y must be sorted in increasing order: y[{i}] = {y[i]!r} > y[{i + 1}] = {y[i + 1]!r}"
        )
    return y, z


def _solve_banded_spd(diagonals: list[np.ndarray], rhs: np.ndarray) -> np.ndarray:
    """Solve ``A x = rhs`` for symmetric positive definite banded ``A``.

    ``diagonals[k]`` holds the k-th sub-diagonal (length ``N - k``). Cholesky with a loop
    over rows, O(N p^2): profiles have up to a few thousand points and this runs once.
    """
    n = rhs.size
    p = len(diagonals) - 1
    lower = np.zeros((n, p + 1))  # lower[i, k] = L[i, i - k]
    for i in range(n):
        for k in range(min(i, p), 0, -1):
            j = i - k
            acc = diagonals[k][j]
            for q in range(1, p - k + 1):
                if j - q >= 0:
                    acc -= lower[i, k + q] * lower[j, q]
            lower[i, k] = acc / lower[j, 0]
        pivot = diagonals[0][i] - np.sum(lower[i, 1 : min(i, p) + 1] ** 2)
        if pivot <= 0.0:
            raise ValueError("spline system is not positive definite (bad point spacing?)")
        lower[i, 0] = np.sqrt(pivot)
    x = rhs.astype(np.float64).copy()
    for i in range(n):  # L w = rhs
        for k in range(1, min(i, p) + 1):
            x[i] -= lower[i, k] * x[i - k]
        x[i] /= lower[i, 0]
    for i in range(n - 1, -1, -1):  # L^T x = w
        for k in range(1, min(n - 1 - i, p) + 1):
            x[i] -= lower[i + k, k] * x[i + k]
        x[i] /= lower[i, 0]
    return x


def fit_natural_spline(y: np.ndarray, z: np.ndarray, smoothing: float = 0.0):
    """Reinsch smoothing spline. Returns knot heights ``g`` and second derivatives ``m``
    (numpy, length n, ``m[0] = m[-1] = 0``) for validated, increasing ``y``."""
    h = np.diff(y)
    n = y.size
    inv = 1.0 / h
    # Q (n x (n-2)): column j couples points j, j+1, j+2 (second divided differences).
    q_upper, q_mid, q_lower = inv[:-1], -inv[:-1] - inv[1:], inv[1:]
    # R ((n-2) x (n-2)) tridiagonal: Gram matrix of the hat functions of f''.
    r_diag = (h[:-1] + h[1:]) / 3.0
    r_off = h[1:-1] / 6.0
    rhs = q_upper * z[:-2] + q_mid * z[1:-1] + q_lower * z[2:]  # Q^T z
    # Q^T Q is pentadiagonal.
    qtq0 = q_upper**2 + q_mid**2 + q_lower**2
    qtq1 = q_mid[:-1] * q_upper[1:] + q_lower[:-1] * q_mid[1:]
    qtq2 = q_lower[:-2] * q_upper[2:]
    lam = float(smoothing)
    diagonals = [r_diag + lam * qtq0, r_off + lam * qtq1, lam * qtq2]
    if lam == 0.0:
        diagonals = diagonals[:2]
    gamma = _solve_banded_spd(diagonals, rhs)
    # g = z - lam Q gamma
    q_gamma = np.zeros(n)
    q_gamma[:-2] += q_upper * gamma
    q_gamma[1:-1] += q_mid * gamma
    q_gamma[2:] += q_lower * gamma
    g = z - lam * q_gamma
    m = np.concatenate([[0.0], gamma, [0.0]])
    return g, m


class TabulatedProfile(Profile):
    """Cubic-spline profile through (or near) measured points (module docstring).

    Fields:
        knots: lateral knot positions ``y_i`` [m], shape (n,), increasing (traced).
        values: spline heights at the knots [m], shape (n,) (traced).
        second_derivatives: spline ``d^2 height/dy^2`` at the knots [1/m], shape (n,)
            (traced; zero at both ends for a natural spline).
        bounds: the domain ``(y_0, y_{n-1})`` [m] as static floats.
        name: a label (static).
    """

    knots: Float[Array, " n"]
    values: Float[Array, " n"]
    second_derivatives: Float[Array, " n"]
    bounds: tuple[float, float] = eqx.field(static=True)
    name: str = eqx.field(static=True, default="tabulated")

    def __check_init__(self):
        shapes = {np.shape(self.knots), np.shape(self.values), np.shape(self.second_derivatives)}
        if len(shapes) != 1 or len(np.shape(self.knots)) != 1 or np.shape(self.knots)[0] < 2:
            raise ValueError(
                "knots, values and second_derivatives must be 1-D arrays of one length >= 2, "
                f"got shapes {np.shape(self.knots)}, {np.shape(self.values)}, "
                f"{np.shape(self.second_derivatives)}"
            )

    @classmethod
    def from_points(
        cls,
        y: Float[ArrayLike, " n"],
        z: Float[ArrayLike, " n"],
        smoothing: float = 0.0,
        name: str = "tabulated",
    ) -> "TabulatedProfile":
        """Fit a natural cubic spline to points ``(y, z)`` [m] (module conventions).

        Arguments:
            y: lateral positions [m], shape (n,), strictly increasing, n >= 4.
            z: heights [m], shape (n,).
            smoothing: penalty weight on ``integral f''^2`` [m^3]; 0 interpolates.
            name: label of the profile.

        Raises ``ValueError`` for NaN/inf, unsorted or repeated ``y``, fewer than 4
        points, different lengths, or a negative/non-finite ``smoothing``.
        """
        require_float64("TabulatedProfile")
        y, z = _validate_points(y, z)
        if not (np.isfinite(smoothing) and smoothing >= 0.0):
            raise ValueError(f"smoothing must be finite and >= 0, got {smoothing}")
        g, m = fit_natural_spline(y, z, smoothing)
        return cls(
            knots=jnp.asarray(y, dtype=jnp.float64),
            values=jnp.asarray(g, dtype=jnp.float64),
            second_derivatives=jnp.asarray(m, dtype=jnp.float64),
            bounds=(float(y[0]), float(y[-1])),
            name=str(name),
        )

    @property
    def domain(self) -> tuple[float, float]:
        return self.bounds

    def height(self, y: Float[ArrayLike, ""]) -> Float[Array, ""]:
        y = jnp.asarray(y, dtype=jnp.float64)
        t, g, m = self.knots, self.values, self.second_derivatives
        first, last = t[0], t[-1]
        # where (not clip) keeps the full derivative at the end knots themselves.
        inside = jnp.where(y < first, first, jnp.where(y > last, last, y))
        i = jnp.clip(jnp.searchsorted(t, inside, side="right") - 1, 0, t.shape[0] - 2)
        h = t[i + 1] - t[i]
        a = (t[i + 1] - inside) / h
        b = 1.0 - a
        cubic = a * g[i] + b * g[i + 1] + ((a**3 - a) * m[i] + (b**3 - b) * m[i + 1]) * h * h / 6.0
        h0, hn = t[1] - t[0], t[-1] - t[-2]
        slope_first = (g[1] - g[0]) / h0 - h0 * (2.0 * m[0] + m[1]) / 6.0
        slope_last = (g[-1] - g[-2]) / hn + hn * (m[-2] + 2.0 * m[-1]) / 6.0
        beyond = jnp.where(y < first, slope_first * (y - first),
                           jnp.where(y > last, slope_last * (y - last), 0.0))
        return cubic + beyond


def tabulated_wheel(
    y_mm: Float[ArrayLike, " n"],
    z_mm: Float[ArrayLike, " n"],
    nominal_radius: float = 0.46,
    name: str = "tabulated wheel",
    smoothing: float = 0.0,
) -> WheelProfile:
    """A wheel from points in mm: ``y_mm`` = S (from the taping line, flange at negative
    y), ``z_mm`` = height radially outward (flange positive). ``nominal_radius`` [m];
    ``smoothing`` [m^3] as in :meth:`TabulatedProfile.from_points`."""
    if not (np.isfinite(nominal_radius) and nominal_radius > 0.0):
        raise ValueError(f"nominal_radius must be a positive length in m, got {nominal_radius}")
    y, z = _validate_points(y_mm, z_mm)
    surface = TabulatedProfile.from_points(1e-3 * y, 1e-3 * z, smoothing=smoothing, name=name)
    return WheelProfile(
        surfaces=(surface,),
        nominal_radius=jnp.asarray(nominal_radius, dtype=jnp.float64),
        name=str(name),
    )


def tabulated_rail(
    y_mm: Float[ArrayLike, " n"],
    z_mm: Float[ArrayLike, " n"],
    name: str = "tabulated rail",
    smoothing: float = 0.0,
) -> TabulatedProfile:
    """A rail head from points in mm: ``y_mm`` lateral from the rail profile origin,
    positive toward the field side; ``z_mm`` up, in the track plane (cant included)."""
    y, z = _validate_points(y_mm, z_mm)
    return TabulatedProfile.from_points(1e-3 * y, 1e-3 * z, smoothing=smoothing, name=name)
