"""The documentation site (mkdocs.yml, docs/) builds in strict mode: a broken link, a
missing anchor, a page left out of the navigation or an API reference
(``::: jaxrail.x``) that does not resolve fails the suite with mkdocs' own message."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[1]


def test_site_builds_in_strict_mode(tmp_path):
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
                           "-d", str(tmp_path / "site")], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, (done.stdout + done.stderr)[-8000:]
    assert (tmp_path / "site" / "api" / "simulation" / "index.html").is_file()
    assert (tmp_path / "site" / "howto" / "fitting" / "index.html").is_file()
