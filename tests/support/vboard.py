"""A virtual board on a pty: the MicroPython unix port's REPL on the master
end of a pseudo-terminal, device/ on its path; the slave's /dev/pts path is
the serial port the host tools (mpremote) open, as they would a board's."""
import os
import subprocess
import sys
from contextlib import contextmanager

from texelpad.sim.virtual import VirtualBoard


@contextmanager
def virtual_board():
    """The host's own virtual board (texelpad.sim.virtual) with this checkout's
    device/ on its path; yields its serial port."""
    with VirtualBoard(image="source") as vb:
        yield vb.port


def mpremote(port: str, code: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """`mpremote connect PORT resume exec CODE` (resume: never soft-reset a
    running display)."""
    exe = os.path.join(os.path.dirname(sys.executable), "mpremote")
    if not os.path.exists(exe):
        exe = "mpremote"
    return subprocess.run([exe, "connect", port, "resume", "exec", code],
                          capture_output=True, text=True, timeout=timeout)
