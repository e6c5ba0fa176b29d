"""Files written whole or not at all: into a temporary file in the target's directory,
flushed to disk, given the usual permissions, then moved over the target with
``os.replace``. On any failure the temporary file is removed and an existing target is
left as it was."""

import os
import tempfile
from pathlib import Path


def cache_root() -> Path:
    """jaxrail's cache folder: ``$JAXRAIL_CACHE_DIR``, else ``~/.cache/jaxrail`` (not
    created)."""
    root = os.environ.get("JAXRAIL_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "jaxrail"


def write_atomically(path, write) -> None:
    """Call ``write(temporary_path)`` to produce the file, then move it to ``path``."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    handle, temporary = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp",
                                         dir=directory)
    os.close(handle)
    try:
        write(temporary)
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)  # mkstemp creates 0600; give the usual mode
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)


def write_text(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all."""

    def write(temporary):
        with open(temporary, "w", encoding="utf-8") as stream:
            stream.write(text)

    write_atomically(path, write)
