"""Keep XLA's "Very slow compile?" alarms off the terminal of the ``jaxrail`` command.

XLA logs an alarm at error level (from C++, straight to file descriptor 2) when a
compilation takes long, although nothing is wrong: the trailer's programs take tens of
seconds to compile on a small machine. A newcomer reads it as a failure. Within
:func:`hidden_xla_alarms`, file descriptor 2 goes through a pipe to a thread that
passes everything on unchanged, partial lines (progress bars) at once, except the
alarm's lines: the logging line from ``slow_operation_alarm``, the message and the
rows of asterisks around it.
"""

import contextlib
import os
import re
import sys
import threading

_ALARM_LINE = re.compile(rb"slow_operation_alarm|Very slow compile\?|^\s*\*{8,}\s*$")
_LOG_PREFIX = re.compile(rb"^[EWIF]\d{4} ")


def is_alarm_line(line: bytes) -> bool:
    """Whether ``line`` (without its newline) is part of XLA's slow-compile alarm."""
    return bool(_ALARM_LINE.search(line))


def _pump(read_fd, write_fd):
    """Copy ``read_fd`` to ``write_fd`` until end of file, without the alarm's lines.
    A partial line is held back only while it may still become a logging line."""
    pending = b""
    while chunk := os.read(read_fd, 65536):
        pending += chunk
        *lines, pending = pending.split(b"\n")
        kept = b"".join(line + b"\n" for line in lines if not is_alarm_line(line))
        if pending and not _LOG_PREFIX.match(pending) and len(pending) > 5:
            kept, pending = kept + pending, b""
        if kept:
            os.write(write_fd, kept)
    if pending and not is_alarm_line(pending):
        os.write(write_fd, pending)
    os.close(read_fd)


@contextlib.contextmanager
def hidden_xla_alarms():
    """Filter file descriptor 2 as in the module docstring for the block's duration."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no usable descriptor 2: nothing to filter
        yield
        return
    read_fd, write_fd = os.pipe()
    os.dup2(write_fd, 2)
    os.close(write_fd)
    thread = threading.Thread(target=_pump, args=(read_fd, saved), daemon=True)
    thread.start()
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)  # closes the pipe's last write end: the thread sees end of file
        thread.join(timeout=5.0)
        os.close(saved)
