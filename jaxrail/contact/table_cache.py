"""Contact tables on disk: built on first use, cached by a hash of what they depend on.

The cache folder is ``$JAXRAIL_CACHE_DIR/tables`` when that variable is set, else
``~/.cache/jaxrail/tables``. A table file (``<key>.npz``) holds the values and a JSON
description (profiles, grid, build time); the key hashes the wheel profile and the
rails' (:class:`jaxrail.track.Rails`: every array and static field of the profiles), the
rails' offset, the search settings, the grid and
:data:`TABLE_VERSION`, so any change to them builds a new table. Files are written
whole or not at all.
"""

import hashlib
import json
import time
from pathlib import Path

import jax
import numpy as np

from .._files import cache_root, write_atomically
from .search import SearchConfig
from .table import FIELDS, ContactTable, TableGrid, build_contact_table

TABLE_VERSION = 13  # bump when the table's content changes for the same inputs


def cache_folder() -> Path:
    """The folder of cached tables (not created)."""
    return cache_root() / "tables"


def _hash_pytree(digest, tree):
    leaves, treedef = jax.tree.flatten(tree)
    digest.update(str(treedef).encode())
    for leaf in leaves:
        array = np.asarray(leaf)
        digest.update(str((array.dtype, array.shape)).encode())
        digest.update(np.ascontiguousarray(array).tobytes())


def table_key(wheel, rails, config: SearchConfig, grid: TableGrid) -> str:
    """Hex key of a table: a hash of everything it depends on, the rails' profile and
    their offset as two parts (so the keys of tables already cached stay valid)."""
    digest = hashlib.sha256()
    digest.update(f"jaxrail contact table v{TABLE_VERSION} {FIELDS}".encode())
    for part in (wheel, rails.profile, config, grid):
        _hash_pytree(digest, part)
    digest.update(repr(float(rails.offset)).encode())
    return digest.hexdigest()[:24]


def table_path(wheel, rails, config=SearchConfig(), grid=TableGrid()) -> Path:
    """Where the table of these inputs is (or would be) cached."""
    return cache_folder() / f"{table_key(wheel, rails, config, grid)}.npz"


def _describe(wheel, rails, config, grid, build_time):
    axes = {name: {"start": axis.start, "step": axis.step, "count": axis.count}
            for name, axis in (("lateral_m", grid.lateral), ("yaw_rad", grid.yaw),
                               ("roll_rad", grid.roll), ("approach_m", grid.approach))}
    return {"version": TABLE_VERSION, "wheel": type(wheel).__name__,
            "rail": type(rails.profile).__name__, "rail_offset_m": float(rails.offset),
            "strip_spacing_m": config.strip_spacing, "max_patches": config.max_patches,
            "grid": axes, "fields": list(FIELDS), "build_time_s": round(build_time, 2)}


def load_table(path) -> tuple[ContactTable, dict]:
    """A cached table and its description; ValueError if the file is not a table."""
    from .table import Axis

    try:
        with np.load(path) as data:
            values = np.array(data["values"])
            info = json.loads(str(data["info"]))
            surfaces = tuple(int(k) for k in data["surfaces"])
            radius = float(data["radius"])
    except (OSError, KeyError, ValueError) as error:
        raise ValueError(f"{path}: not a jaxrail contact table ({error})") from error
    axes = {name: Axis(float(a["start"]), float(a["step"]), int(a["count"]))
            for name, a in info["grid"].items()}
    grid = TableGrid(axes["lateral_m"], axes["yaw_rad"], axes["roll_rad"], axes["approach_m"])
    return ContactTable(jax.numpy.asarray(values), grid, surfaces, radius), info


def contact_table(wheel, rails, config: SearchConfig = SearchConfig(),
                  grid: TableGrid = TableGrid(), progress: bool = False,
                  cache: bool = True) -> tuple[ContactTable, dict]:
    """The contact table of a wheel profile on ``rails`` (:class:`jaxrail.track.Rails`,
    e.g. a track's ``track.rails``): from the cache, or built with
    the paper's search (:func:`jaxrail.contact.table.build_contact_table`) and cached.
    ``progress``: show a progress bar while building. Returns ``(table, description)``
    (the description has the build time and ``"path"``; ``"cached"`` says whether it
    was read from the cache)."""
    path = table_path(wheel, rails, config, grid)
    if cache and path.exists():
        table, info = load_table(path)
        return table, {**info, "path": str(path), "cached": True}
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=1, unit="node", desc="contact table")

    def report(done, total):
        bar.total = total
        bar.n = done
        bar.refresh()

    start = time.perf_counter()
    table, diagnostics = build_contact_table(wheel, rails, config, grid,
                                             progress=report if bar is not None else None)
    build_time = time.perf_counter() - start
    if bar is not None:
        bar.close()
    info = _describe(wheel, rails, config, grid, build_time) | diagnostics
    if cache:
        path.parent.mkdir(parents=True, exist_ok=True)

        def write(temporary):
            with open(temporary, "wb") as stream:
                np.savez(stream, values=np.asarray(table.values), info=json.dumps(info),
                         surfaces=np.asarray(table.surfaces), radius=table.radius)

        write_atomically(path, write)
    return table, {**info, "path": str(path), "cached": False}
