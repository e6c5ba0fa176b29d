"""Every how-to guide runs as written (docs/howto/*.md).

Each page's fenced blocks run in order in one fresh Python process, in an empty
temporary folder:

- ```` ```python ```` blocks run in one namespace, as one script would;
- ```` ```bash ```` blocks run in a shell (the ``jaxrail`` command of this environment);
- a block with ``title="NAME"`` (a scenario, a vehicle or a CSV file) is written to
  NAME first, so later blocks can read it;
- other blocks (``text``: printed output) are shown only.

The pages keep their runs tiny (a single wheelset for a few hundredths of a second, four
Monte Carlo samples of a tenth of a second, two fit iterations, a coarse stability
search), so the pages cost little beyond compiling; docs/howto/index.md says the same to
readers. The Monte Carlo page's study has the inputs, samples and duration of
tests/montecarlo/test_batch.py's: it loads that program from the persistent
compilation cache when test_batch ran first with the same cache.
"""

import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest

HOWTO = Path(__file__).parents[1] / "docs" / "howto"
PAGES = sorted(p for p in HOWTO.glob("*.md") if p.name != "index.md")
FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```[ \t]*$", re.S | re.M)
TITLE = re.compile(r'title="([^"]+)"')


def blocks(page):
    """(kind, first line, text, file name or None) of each fenced block of a page."""
    text = page.read_text()
    found = []
    for match in FENCE.finditer(text):
        language, attributes, body = match.groups()
        line = text.count("\n", 0, match.start(3)) + 1
        title = TITLE.search(attributes)
        if title:
            found.append(("file", line, body, title.group(1)))
        elif language in ("python", "bash"):
            found.append((language, line, body, None))
    return found


def script(page):
    """One Python program that runs the page's blocks in order."""
    lines = ["import subprocess, sys", "from pathlib import Path",
             "namespace = {'__name__': '__main__'}"]
    for kind, line, body, name in blocks(page):
        if kind == "file":
            lines.append(f"Path({name!r}).write_text({body!r})")
        elif kind == "python":
            padded = "\n" * (line - 1) + body  # tracebacks give the page's line numbers
            lines.append(f"exec(compile({padded!r}, {str(page)!r}, 'exec'), namespace)")
        else:
            lines.append(f"print('$', {body.strip()!r}, flush=True)")
            lines.append(f"subprocess.run({body!r}, shell=True, check=True, "
                         "executable='/bin/bash')")
    return "\n".join(lines) + "\n"


def test_every_page_has_blocks_that_run():
    assert PAGES
    for page in PAGES:
        assert any(kind in ("python", "bash") for kind, *_ in blocks(page)), page.name


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_howto_page_runs(page, tmp_path):
    (tmp_path / "page.py").write_text(script(page))
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env["MPLBACKEND"] = "Agg"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "page.py"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cost = (f"{time.perf_counter() - start:.0f} s wall, "
            f"{after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime:.0f} s CPU")
    print(f"{page.name}: {cost}")  # shown with -s
    output = (done.stdout + done.stderr)[-6000:]
    assert done.returncode == 0, f"{page.name} failed ({cost}):\n{output}"
