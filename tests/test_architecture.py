"""The package's shape, read from its source with :mod:`ast` (nothing is imported, so
this is fast): small modules, private names kept private, imports that only run down
the layers (docs/design.md §1).

**Units.** A module's unit is its subpackage (``jaxrail.contact.table.build`` is in
``contact``) or, for a top-level module, itself (``results``). The top-level private
modules (``jaxrail._float64``, ``jaxrail._constants``, ``jaxrail._files`` and the
other ``jaxrail._*``) are the package's internals, shared by all subpackages: any
module may import them, and they are the foundation layer with ``compilation`` and the
package's own ``__init__`` (whose public names load lazily, by name).

**Private names.** No module imports a name with one leading underscore (``_x``) from
a module of another unit, nor a private module of another subpackage
(``jaxrail.multibody._values``). Within a unit it may. Importing the foundation's
private *modules* is allowed, but the names defined in them are imported only when
public: ``from jaxrail._float64 import f64``, never ``... import _f64``.

**Layers.** :data:`LAYERS`, lowest first. A module imports only from its own layer and
the layers below, never from a layer above, also inside a function (a lazy import is
still a dependency). What two packages of one layer share goes below them.
"""

import ast
import functools
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "jaxrail"
MAX_LINES = 450

FOUNDATION = "foundation"  # jaxrail/__init__.py, jaxrail/_*.py, compilation/
LAYERS = (
    (FOUNDATION,),
    ("profiles", "multibody"),  # wheel and rail profiles; bodies, joints, forces, IMEX
    ("track",),  # the track's layout, irregularities and rails (its rail profiles)
    ("contact",),  # the wheel-rail contact: search, normal laws, creep, tables
    ("geometry", "vehicles"),  # wheel-rail geometry; vehicles on their track
    ("simulation", "results"),  # a run; what a run writes and summarises
    ("scenarios", "stability", "standards"),  # runs set up; stability; assessments
    ("identification", "montecarlo", "wear"),  # studies over many runs of a scenario
    ("plots",),  # figures of all the above
    ("cli",),
)

# Imports that break a rule and are left for now: (importing module, imported module)
# -> why, and the issue that tracks them.
KNOWN_EXCEPTIONS: dict[tuple[str, str], str] = {}


def _module_name(path):
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_package(name):
    return (ROOT.parent / name.replace(".", "/") / "__init__.py").exists()


def _is_module(name):
    return _is_package(name) or (ROOT.parent / (name.replace(".", "/") + ".py")).exists()


def _unit(name):
    parts = name.split(".")
    if len(parts) == 1 or parts[1].startswith("_") or parts[1] == "compilation":
        return FOUNDATION
    return parts[1]


def _private(name):
    return name.startswith("_") and not name.startswith("__")


MODULES = {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


@functools.cache
def _imports(name):
    """``(line, imported module, imported name or None)`` of every import of jaxrail in
    module ``name``, at any depth (functions included); a name that is a submodule
    counts as that module."""
    path = MODULES[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, None) for a in node.names
                    if a.name.split(".")[0] == "jaxrail"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "jaxrail":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.append((node.lineno, sub, None) if _is_module(sub)
                           else (node.lineno, target, alias.name))
    return tuple(out)


def _layer(unit):
    return next(i for i, layer in enumerate(LAYERS) if unit in layer)


def test_every_module_is_at_most_450_lines():
    long = {name: n for name, path in MODULES.items()
            if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert long == {}, f"over {MAX_LINES} lines; split by one idea per module"


def test_every_unit_has_a_layer():
    units = {_unit(name) for name in MODULES}
    listed = [u for layer in LAYERS for u in layer]
    assert len(listed) == len(set(listed))
    assert units == set(listed), "add a new subpackage to LAYERS"


def test_no_module_imports_a_private_name_of_another_subpackage():
    found = []
    for name in MODULES:
        for line, target, imported in _imports(name):
            if _unit(target) == _unit(name) or (name, target) in KNOWN_EXCEPTIONS:
                continue
            # the modules inside a subpackage (jaxrail._float64 itself may be imported)
            below = target.split(".")[2:]
            if any(_private(part) for part in below) or (imported and _private(imported)):
                found.append(f"{name}:{line} imports {target}"
                             + (f".{imported}" if imported else ""))
    assert found == [], "make the name public (or move it to the unit that uses it)"


def test_no_module_imports_from_a_higher_layer():
    found = []
    for name in MODULES:
        for line, target, _ in _imports(name):
            if ((name, target) not in KNOWN_EXCEPTIONS
                    and _layer(_unit(target)) > _layer(_unit(name))):
                found.append(f"{name}:{line} ({_unit(name)}) imports {target} "
                             f"({_unit(target)})")
    assert found == [], "an import runs up the layers (LAYERS, docs/design.md §1)"


def test_every_known_exception_is_still_needed():
    imports = {(name, target) for name in MODULES for _, target, _ in _imports(name)}
    assert set(KNOWN_EXCEPTIONS) <= imports, "remove the exceptions that were fixed"
