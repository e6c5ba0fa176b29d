"""Files written whole or not at all: into a temporary file in the target's directory,
flushed to disk, given the usual permissions, then moved over the target with
``os.replace``. On any failure the temporary file is removed and an existing target is
left as it was."""

import importlib.resources
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


def builtin_or_file_text(name_or_path, package: str, builtin, kind: str) -> tuple[str, str]:
    """``(text, where)`` of a built-in file by name (one of ``builtin``, read from
    ``package``'s ``data/NAME.toml``) or of a TOML file at ``name_or_path``; ``where``
    names it for errors. ValueError names what is wrong: an unknown name (listing the
    built-in ones), a file that is not UTF-8 text or cannot be read. ``kind``: what the
    file holds ("scenario", "route")."""
    if str(name_or_path) in builtin:
        text = importlib.resources.files(package).joinpath(
            "data", f"{name_or_path}.toml").read_text()
        return text, f"built-in {kind} {name_or_path}"
    path = Path(name_or_path)
    if not path.exists():
        raise ValueError(f"unknown {kind} {str(name_or_path)!r}: use one of "
                         f"{', '.join(builtin)} or a .toml file")
    try:
        return path.read_text(encoding="utf-8"), str(path)
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text (UTF-8) {kind} file") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the {kind} file ({error.strerror})") from None
