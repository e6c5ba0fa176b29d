"""One benchmark variant run in a process of its own (its compile and caches apart)."""

import json
import os
import subprocess


def run_variant(command, variant):
    """The JSON object ``command`` prints on its last line, with the load before it ran
    (``load_1min_before``), or ``{"variant": variant, "error": ...}`` if it failed."""
    load = round(os.getloadavg()[0], 2)
    out = subprocess.run(command, capture_output=True, text=True)
    try:
        row = json.loads(out.stdout.splitlines()[-1]) if out.returncode == 0 else None
    except (IndexError, json.JSONDecodeError):
        row = None
    if row is None:
        row = {"variant": variant, "error": (out.stderr or out.stdout)[-2000:]}
    return dict(row, load_1min_before=load)
