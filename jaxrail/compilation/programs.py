"""Traced programs kept on disk, so that a second process neither traces nor compiles.

JAX's persistent compilation cache (:mod:`.compiler`) saves XLA's compile, but a
new process still traces the program in Python first: 3 s for the trailer's initial
equilibrium and 6 s for its integration, most of a cached start. Here the traced
program is exported (``jax.export``, StableHLO) and kept in ``<cache>/programs``
beside the XLA cache; a later process with the same key deserialises it (milliseconds)
and compiles it, which the XLA cache answers.

The key is a SHA-256 of everything the traced program depends on: the function's
module and name; the source of every module of the jaxrail package; the versions of
numpy, jax, jaxlib, equinox, diffrax, optimistix and lineax; the platform; the
argument structure with every static value in it (``jax.tree.structure``, as text)
and each argument's shape and dtype, or ``repr`` for the non-array ones; and the
source file of every module outside those packages that defines a type in the
arguments (a user's own profile class, say). Arguments that cannot be keyed safely,
a text with a memory address (" at 0x") or numpy's elision ("..."), or a type whose
module has no source file, make a program that is traced every time. A file that cannot be read is traced again and
rewritten. Files are written whole or not at all.
"""

import functools
import hashlib
import importlib.metadata
import pickle
import sys
import warnings
from pathlib import Path

import equinox as eqx
import jax
from jax import export

from .._files import write_atomically
from .._time_report import TARGET as TIME_REPORT_TARGET

_PACKAGES = ("numpy", "jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax")
_UNSAFE = (" at 0x", "...")


@functools.cache
def _source_digest() -> str:
    """SHA-256 of every module of the jaxrail package (path and content)."""
    digest = hashlib.sha256()
    root = Path(__file__).parents[1]  # jaxrail
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    for package in _PACKAGES:
        digest.update(f"{package}={importlib.metadata.version(package)}".encode())
    return digest.hexdigest()


def _node_types(treedef):
    """Every type in a tree structure (its nodes, recursively)."""
    data = treedef.node_data()
    found = set() if data is None else {data[0]}
    for child in treedef.children():
        found |= _node_types(child)
    return found


def _outside_source(types):
    """Text identifying the source of the types defined outside jaxrail and the keyed
    packages (their modules' file contents), or None if one has no source file."""
    covered = ("jaxrail", "builtins", *_PACKAGES)
    digest = hashlib.sha256()
    for name in sorted({t.__module__ for t in types} - {None}):
        if name.split(".")[0] in covered:
            continue
        path = getattr(sys.modules.get(name), "__file__", None)
        if path is None or not Path(path).is_file():
            return None
        digest.update(name.encode() + Path(path).read_bytes())
    return digest.hexdigest()


def program_key(function, leaves, treedef, xla_options) -> str | None:
    """Hex key of ``function`` traced for these argument leaves and structure (module
    docstring), or None if they cannot be keyed safely."""
    outside = _outside_source(_node_types(treedef) | {type(x) for x in leaves})
    if outside is None:
        return None
    described = [f"{x.shape}{x.dtype}" if eqx.is_array(x) else f"{type(x).__qualname__}:{x!r}"
                 for x in leaves]
    text = "\n".join([f"{function.__module__}.{function.__qualname__}", str(treedef),
                      *described, repr(sorted(xla_options.items())), jax.default_backend(),
                      _source_digest(), outside])
    if any(marker in text for marker in _UNSAFE):
        return None
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _load(path):
    try:
        blob, skeleton = pickle.loads(path.read_bytes())
        return export.deserialize(blob), skeleton
    except Exception:  # a damaged or foreign file: trace again
        return None


def _keep(path, exported, skeleton):
    """Write the program to ``path``; a folder that cannot be written only costs the
    next process a trace, so the error is a warning."""
    try:
        blob = pickle.dumps((exported.serialize(), skeleton))
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomically(path, lambda temporary: Path(temporary).write_bytes(blob))
    except (OSError, pickle.PicklingError, ImportError) as error:
        warnings.warn(f"jaxrail: traced program not kept in {path.parent}: {error}",
                      stacklevel=3)


def _export(flat, arrays):
    """``flat`` traced and exported for the shapes of ``arrays``. jaxrail's own FFI
    target (the progress report) is registered by every process that loads the program
    (.compiler). An inner jitted function that this process first traced with
    equinox's checks as host callbacks (outside jaxrail's programs, which make them
    NaN) brings its cached trace, callbacks and all, into the program, which cannot be
    exported: then JAX's trace caches are cleared and the program traced once more."""
    def exported():
        return export.export(jax.jit(flat), disabled_checks=[
            export.DisabledSafetyCheck.custom_call(TIME_REPORT_TARGET)])(
            *(jax.ShapeDtypeStruct(x.shape, x.dtype) for x in arrays))

    try:
        return exported()
    except NotImplementedError as error:
        if "host_callbacks" not in str(error):
            raise
        jax.clear_caches()
        return exported()


def compile_through_program_cache(function, folder, xla_options, /, *args, **kwargs):
    """``function(*args, **kwargs)`` compiled with ``xla_options``: a callable of the
    same arguments (the arrays may change, not the rest; its ``compiled``: the XLA
    executable). The traced program comes from
    ``folder`` when it holds one with this key, else it is traced, exported and kept
    there (``folder`` None: traced, not kept)."""
    leaves, treedef = jax.tree.flatten((args, kwargs))
    arrays = [x for x in leaves if eqx.is_array(x)]
    key = None if folder is None else program_key(function, leaves, treedef, xla_options)
    path = None if key is None else Path(folder) / f"{key}.jaxprogram"
    loaded = _load(path) if path is not None and path.exists() else None
    if loaded is None:
        skeleton = []

        def flat(*values):
            values = iter(values)
            a, k = jax.tree.unflatten(treedef, [next(values) if eqx.is_array(x) else x
                                                for x in leaves])
            out = function(*a, **k)
            skeleton.append(jax.tree.map(lambda x: jax.ShapeDtypeStruct(x.shape, x.dtype), out))
            return jax.tree.leaves(out)

        exported = _export(flat, arrays)
        loaded = exported, skeleton[-1]
        if path is not None:
            _keep(path, exported, skeleton[-1])
    exported, skeleton = loaded
    compiled = jax.jit(exported.call).lower(*arrays).compile(xla_options)
    out_tree = jax.tree.structure(skeleton)

    def run(*args, **kwargs):
        values = [x for x in jax.tree.leaves((args, kwargs)) if eqx.is_array(x)]
        return jax.tree.unflatten(out_tree, compiled(*values))

    run.compiled = compiled  # the executable: its optimised HLO for profiles
    return run
