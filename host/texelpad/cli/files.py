"""Output files: checked before the work that fills them, written
atomically, a failure of the filesystem one line naming the flag (exit 1)."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

from .errors import EXIT_FAIL, CliError, cut_repr


def check_output(flag: str, path: str, suffixes: tuple[str, ...] = ()) -> Path:
    """Check an output file BEFORE the work that fills it: its suffix is one
    of `suffixes` (case-insensitive; any when empty) - else one line naming
    the flag, exit 2 - and its directory exists and takes a new file (a probe
    file is made and removed there) - else one line, exit 1. An existing
    special file (/dev/stdout, a FIFO) is taken as it is."""
    out = Path(path)
    try:
        special = out.exists() and not out.is_file() and not out.is_dir()
    except OSError:
        special = False
    if special:
        return out
    if suffixes and out.suffix.lower() not in suffixes:
        raise CliError(flag, "unsupported file type %r for %s (use %s)"
                       % (out.suffix or out.name, cut_repr(path), ", ".join(suffixes)))
    parent = out.parent if str(out.parent) else Path(".")

    def fail(why: str) -> CliError:
        return CliError(flag, "cannot write %s: %s" % (path, why), EXIT_FAIL)
    if out.is_dir():
        raise fail("it is a directory")
    if not parent.is_dir():
        raise fail("no such directory %s" % parent if not parent.exists()
                   else "%s is not a directory" % parent)
    if out.exists() and not os.access(out, os.W_OK):
        raise fail("permission denied")
    try:
        fd, probe = tempfile.mkstemp(prefix=".texelpad-", dir=parent)
    except OSError as e:
        raise fail(e.strerror or str(e)) from None
    os.close(fd)
    try:
        os.unlink(probe)
    except OSError:
        pass
    return out


def write_output(flag: str, path: str, write: Any) -> None:
    """Run write() (which writes `path`); a failure of the filesystem is one
    line naming the flag and the path, exit 1."""
    try:
        write()
    except OSError as e:
        raise CliError(flag, "cannot write %s: %s" % (path, e.strerror or e), EXIT_FAIL) from None


def write_atomic(path: str, text: str) -> None:
    """Write text to path through a temporary file beside it, renamed over
    it: readers see the old file or the new one, never half of one. A
    special file (/dev/stdout, a FIFO) is written as it is."""
    out = Path(path)
    if out.exists() and not out.is_file():
        with open(out, "w", encoding="utf-8") as f:
            f.write(text)
        return
    parent = out.parent if str(out.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix="." + out.name + ".", suffix=".tmp", dir=parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp makes 0600: give the file the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, out)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
