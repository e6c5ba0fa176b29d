"""Profile files: plain two-column text/CSV in mm, and SIMPACK ``.prw`` / ``.prr``.

**Text/CSV** (any extension other than ``.prw``/``.prr``): one point per line,
``y_mm`` then ``z_mm``. Values may be separated by commas, whitespace or semicolons. If a
line contains a semicolon, its values are split on semicolons and a decimal comma is
accepted (``1,5;2,25``). ``#`` starts a comment. One header line (the first line that is
not a comment and not numbers) is allowed. The columns are already in jaxrail
conventions (:mod:`jaxrail.profiles._base`): ``y`` positive toward the field side (for a
wheel: ``S`` from the taping line, flange at negative y), ``z`` is the wheel height
radially outward, or the rail height up. Points may be listed in increasing or
decreasing ``y``. ``mirror_y=True`` flips ``y`` for files written the other way round.

**SIMPACK** ``.prw`` (wheel) / ``.prr`` (rail) profiles, as in CONTACT's
``MBench_S1002_v3.prw`` and ``MBench_UIC60_v3.prr``. The file has ``!`` comments,
``header.begin/end`` and ``spline.begin/end`` blocks of ``key = value`` lines, and
points between ``point.begin`` and ``point.end``. The reader applies the spline block's
processing steps in SIMPACK's order, as CONTACT's ``read_simpack.m`` does:
point.dist.min, shift.y/z, rotate, bound.y (drop), bound.z (clip), mirror.y, mirror.z,
inversion. It divides lengths by ``units.len.f`` (user units per metre). The result is in
SIMPACK's profile frame:
``y`` lateral with the flange / gauge face at negative ``y``, and ``z`` pointing **down**.
Hence wheel height = ``+z`` (radially outward is toward the rail, i.e. down) and rail
height = ``-z``. The traps (profiles.md section 1): the raw MBench ``.prw`` points are
``y = -S`` and the header's ``mirror.y = 1`` undoes that. The ``.prr`` is already canted
(do not add 1:40 again), its origin is the highest point of the head, and negative ``y``
is the gauge side. Point weights (a third column) are ignored.
"""

import os
import re
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .._files import write_text
from ._base import Profile, WheelProfile
from .tabulated import TabulatedProfile, _validate_points, tabulated_rail, tabulated_wheel

_SIMPACK_SUFFIXES = {".prw": "wheel", ".prr": "rail"}


def _parse_number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: cannot read {text!r} as a number") from None


def read_text_points(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a two-column text/CSV file; return ``(y_mm, z_mm)`` as in the file."""
    rows = []
    header_seen = False
    with open(path, encoding="utf-8") as stream:
        for number, raw in enumerate(stream, start=1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            if ";" in line:
                fields = [f.strip().replace(",", ".") for f in line.split(";")]
            else:
                fields = [f for f in re.split(r"[,\s]+", line) if f]
            fields = [f for f in fields if f]
            where = f"{path}, line {number}"
            if not rows and not header_seen:
                try:
                    [float(f) for f in fields]
                except ValueError:
                    header_seen = True  # the one allowed header line
                    continue
            if len(fields) != 2:
                raise ValueError(f"{where}: expected 2 columns (y_mm, z_mm), got {len(fields)}")
            rows.append([_parse_number(f, where) for f in fields])
    if not rows:
        raise ValueError(f"{path}: no profile points found")
    data = np.asarray(rows, dtype=np.float64)
    return data[:, 0], data[:, 1]


def _simpack_value(text: str):
    text = text.strip()
    if text.startswith("'") or text.startswith('"'):
        return text.strip("'\"")
    try:
        return float(text)
    except ValueError:
        return text


MIN_WIDTH_M, MAX_WIDTH_M = 0.01, 0.5  # [m] lateral extent of a wheel or rail profile


def read_simpack_points(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, dict]:
    """Read a SIMPACK ``.prw``/``.prr`` file.

    Returns ``(y_m, z_m, fields)``: the points [m] in SIMPACK's profile frame after the
    file's processing steps (module docstring; z down), and a dict of the header and spline
    keys (``"header.type"`` is 1 for a wheel, 0 for a rail).
    """
    fields: dict = {}
    rows = []
    block = None
    in_points = False
    with open(path, encoding="utf-8", errors="replace") as stream:
        for number, raw in enumerate(stream, start=1):
            line = raw.split("!", 1)[0].strip()
            if not line:
                continue
            key = line.split()[0]
            if key.endswith(".begin") or key.endswith(".end"):
                name, _, edge = key.rpartition(".")
                if name == "point":
                    in_points = edge == "begin"
                elif name in ("header", "spline"):
                    block = name if edge == "begin" else None
                else:
                    raise ValueError(f"{path}, line {number}: unknown block {name!r}")
                continue
            if "=" in line:
                if block is None:
                    raise ValueError(f"{path}, line {number}: key outside a block: {line!r}")
                name, _, value = line.partition("=")
                fields[f"{block}.{name.strip()}"] = _simpack_value(value)
                continue
            if not in_points:
                raise ValueError(f"{path}, line {number}: data outside point.begin/end")
            values = line.split()
            if len(values) not in (2, 3):
                raise ValueError(f"{path}, line {number}: expected y z [weight], got {line!r}")
            rows.append([_parse_number(v, f"{path}, line {number}") for v in values[:2]])
    if not rows:
        raise ValueError(f"{path}: no points between point.begin and point.end")
    points = np.asarray(rows, dtype=np.float64)

    def get(name, default=0.0):
        value = fields.get(f"spline.{name}", default)
        if isinstance(value, str) or not np.isfinite(value):
            raise ValueError(f"{path}: spline.{name} must be a number, got {value!r}")
        return float(value)

    def flag(name):
        value = get(name)
        if value not in (0.0, 1.0):
            raise ValueError(f"{path}: spline.{name} must be 0 or 1, got {value:g}")
        return value == 1.0

    min_distance = get("point.dist.min")
    if min_distance >= 1e-12:
        keep = [0]
        for i in range(1, len(points)):
            if abs(points[i, 0] - points[keep[-1], 0]) > min_distance:
                keep.append(i)
        points = points[keep]
    points = points + np.array([get("shift.y"), get("shift.z")])
    angle = get("rotate") / get("units.ang.f", 1.0)
    if angle != 0.0:
        c, s = np.cos(angle), np.sin(angle)
        points = points @ np.array([[c, -s], [s, c]]).T
    y_lo, y_hi = get("bound.y.min", 1.0), get("bound.y.max", 0.0)
    if y_lo < y_hi:
        points = points[(points[:, 0] >= y_lo) & (points[:, 0] <= y_hi)]
    z_lo, z_hi = get("bound.z.min", 1.0), get("bound.z.max", 0.0)
    if z_lo < z_hi:
        points[:, 1] = np.clip(points[:, 1], z_lo, z_hi)
    if flag("mirror.y"):
        points[:, 0] = -points[:, 0]
    if flag("mirror.z"):
        points[:, 1] = -points[:, 1]
    if flag("inversion"):
        points = points[::-1]
    per_metre = get("units.len.f", 1.0)
    if not per_metre > 0.0:
        raise ValueError(f"{path}: units.len.f must be positive, got {per_metre}")
    points = points / per_metre
    return points[:, 0].copy(), points[:, 1].copy(), fields


def _increasing(y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reverse points listed in decreasing y; other orders are left to the validator."""
    if y.size >= 2 and np.all(np.diff(y) < 0.0):
        return y[::-1].copy(), z[::-1].copy()
    return y, z


def read_profile(
    path: str | os.PathLike,
    kind: str | None = None,
    *,
    nominal_radius: float = 0.46,
    smoothing: float = 0.0,
    mirror_y: bool = False,
    name: str | None = None,
) -> WheelProfile | TabulatedProfile:
    """Read a wheel or rail profile file into a spline profile.

    Arguments:
        path: a ``.prw``/``.prr`` SIMPACK file, or a two-column text/CSV file in mm.
        kind: ``"wheel"`` or ``"rail"``. Optional for SIMPACK files (taken from the
            header, and checked against it); required for text files.
        nominal_radius: wheel rolling radius at the taping line [m] (wheels only).
        smoothing: spline smoothing [m^3] (see :class:`TabulatedProfile`); 0 interpolates.
        mirror_y: flip the lateral coordinate after reading (``y -> -y``).
        name: label; default the file name.

    Returns a :class:`WheelProfile` (one :class:`TabulatedProfile` surface) for a wheel,
    a :class:`TabulatedProfile` for a rail. Raises ``ValueError`` for unreadable content,
    a ``kind`` that does not match the file, or a wheel whose flange (its highest point)
    comes out on the field side, which is a sign of a mirrored file.
    """
    path = Path(path)
    if kind not in (None, "wheel", "rail"):
        raise ValueError(f"kind must be 'wheel' or 'rail', got {kind!r}")
    label = name if name is not None else path.name
    suffix = path.suffix.lower()
    if suffix in _SIMPACK_SUFFIXES:
        y_m, z_m, fields = read_simpack_points(path)
        file_type = fields.get("header.type")
        file_kind = {1.0: "wheel", 0.0: "rail"}.get(file_type, _SIMPACK_SUFFIXES[suffix])
        if kind is not None and kind != file_kind:
            raise ValueError(f"kind={kind!r} but {path.name} holds a {file_kind} profile")
        kind = file_kind
        y_mm = 1e3 * y_m
        z_mm = 1e3 * z_m if kind == "wheel" else -1e3 * z_m  # SIMPACK z points down
        width = float(np.ptp(y_m))
        if not MIN_WIDTH_M <= width <= MAX_WIDTH_M:
            stated = (f"{fields['spline.units.len.f']:g} per metre"
                      if "spline.units.len.f" in fields else "missing, so metres")
            raise ValueError(f"{path}: the profile is {width:g} m wide, not a {kind} profile "
                             f"({MIN_WIDTH_M * 1e3:g}-{MAX_WIDTH_M * 1e3:g} mm): check "
                             f"units.len.f ({stated}; 1000 for millimetres)")
    else:
        if kind is None:
            raise ValueError(f"kind must be given ('wheel' or 'rail') for text file {path.name}")
        y_mm, z_mm = read_text_points(path)
    if mirror_y:
        y_mm = -y_mm
    y_mm, z_mm = _increasing(y_mm, z_mm)
    y_mm, z_mm = _validate_points(y_mm, z_mm)
    if kind == "wheel":
        if y_mm[np.argmax(z_mm)] > 0.0:
            raise ValueError(
                f"{path.name}: the flange (highest point) is at y = {y_mm[np.argmax(z_mm)]:.3f} mm"
                " > 0, on the field side; the file is probably mirrored (try mirror_y=True)"
            )
        return tabulated_wheel(y_mm, z_mm, nominal_radius=nominal_radius, name=label,
                               smoothing=smoothing)
    return tabulated_rail(y_mm, z_mm, name=label, smoothing=smoothing)


def write_profile_csv(
    path: str | os.PathLike,
    y_mm: np.ndarray,
    z_mm: np.ndarray,
    header: str | None = None,
) -> None:
    """Write points [mm] as ``y_mm,z_mm`` CSV, whole or nothing.

    ``header`` (may span lines) is written as ``#`` comments above the column line.
    Values are written with 17 significant digits, so reading gives the same floats.
    The file is written to a temporary file in the same directory and then moved over
    ``path`` with ``os.replace``. If writing fails, an existing ``path`` is left as it was.
    """
    y, z = _validate_points(y_mm, z_mm)
    path = Path(path)
    lines = []
    if header:
        lines += [f"# {text}".rstrip() for text in str(header).splitlines()]
    lines.append("y_mm,z_mm")
    lines += [f"{a:.17g},{b:.17g}" for a, b in zip(y, z)]
    write_text(path, "\n".join(lines) + "\n")


@jax.jit
def _heights(profile: Profile, y):
    # the profile is an argument: one compile per profile type, knot count and n
    return jax.vmap(profile.height)(y)


def sample_profile(
    profile: Profile | WheelProfile,
    n: int = 401,
    surface: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Sample a profile at ``n`` evenly spaced points; return ``(y_mm, z_mm)`` (numpy).

    For a :class:`WheelProfile`, ``surface`` picks one surface. With ``None``, the points
    span all surfaces: each point takes the height of the first surface whose domain
    holds it, and points in gaps between domains are dropped.
    """
    if int(n) < 2:
        raise ValueError(f"n must be at least 2, got {n}")
    if isinstance(profile, WheelProfile):
        surfaces = profile.surfaces
        if surface is not None:
            if not 0 <= surface < len(surfaces):
                raise ValueError(f"surface must be in [0, {len(surfaces)}), got {surface}")
            surfaces = (surfaces[surface],)
    elif isinstance(profile, Profile):
        if surface not in (None, 0):
            raise ValueError(f"a single Profile has only surface 0, got {surface}")
        surfaces = (profile,)
    else:
        raise ValueError(f"profile must be a Profile or WheelProfile, got {type(profile).__name__}")
    low = min(s.domain[0] for s in surfaces)
    high = max(s.domain[1] for s in surfaces)
    y = np.linspace(low, high, int(n))
    z = np.full_like(y, np.nan)
    for s in surfaces:
        free = np.isnan(z) & (y >= s.domain[0]) & (y <= s.domain[1])
        if free.any():
            z[free] = np.asarray(_heights(s, jnp.asarray(y, dtype=jnp.float64)))[free]
    keep = ~np.isnan(z)
    return 1e3 * y[keep], 1e3 * z[keep]
