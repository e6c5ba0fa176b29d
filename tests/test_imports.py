"""Importing jaxrail has no side effects: every module imports in a fresh process under
JAX's default float32 without starting an XLA backend (so that
``jax.distributed.initialize`` can still run after it) and without pyplot."""

import json
import subprocess
import sys

_CHILD = """
import importlib, json, pathlib, sys
import jaxrail
root = pathlib.Path(jaxrail.__file__).parent
names = sorted("jaxrail." + ".".join(p.relative_to(root).with_suffix("").parts)
               for p in root.rglob("*.py"))
failed = {}
for name in names:
    name = name.removesuffix(".__init__")
    try:
        importlib.import_module(name)
    except Exception as error:
        failed[name] = f"{type(error).__name__}: {error}"
from jax._src import xla_bridge
print(json.dumps({"modules": len(names), "failed": failed,
                  "backends": sorted(xla_bridge._backends),
                  "x64": __import__("jax").config.jax_enable_x64,
                  "pyplot": "matplotlib.pyplot" in sys.modules}))
"""


def test_every_module_imports_under_float32_without_starting_a_backend():
    env = {"JAX_ENABLE_X64": "0", "PATH": "", "HOME": "/tmp"}
    out = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True,
                         text=True, check=True)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert report["modules"] > 50 and report["x64"] is False
    assert report["failed"] == {}
    assert report["backends"] == []
    assert report["pyplot"] is False
