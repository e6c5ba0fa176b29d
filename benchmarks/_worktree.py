"""A git revision checked out into a temporary worktree, for the benchmarks that
compare revisions."""

import contextlib
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@contextlib.contextmanager
def revision_tree(revision, path):
    """``revision`` checked out (detached) at ``path`` inside the block; the worktree is
    removed after it."""
    subprocess.run(["git", "worktree", "add", "--detach", str(path), revision], cwd=ROOT,
                   check=True, capture_output=True)
    try:
        yield Path(path)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(path)], cwd=ROOT,
                       check=False, capture_output=True)
