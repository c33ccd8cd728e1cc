"""A virtual board on a pty: the MicroPython unix port's REPL on the master
end of a pseudo-terminal, device/ on its path; the slave's /dev/pts path is
the serial port the host tools (mpremote) open, as they would a board's."""
import os
import pty
import subprocess
import tty
from contextlib import contextmanager

import mpy


@contextmanager
def virtual_board():
    master, slave = pty.openpty()
    tty.setraw(slave)
    port = os.ttyname(slave)
    env = dict(os.environ, MICROPYPATH=f"{mpy.DEVICE}:.frozen")
    proc = subprocess.Popen([mpy.micropython_exe(), "-i"], stdin=master, stdout=master,
                            stderr=master, env=env, close_fds=True)
    os.close(master)
    try:
        yield port
    finally:
        proc.kill()
        proc.wait(timeout=10)
        os.close(slave)


def mpremote(port: str, code: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """`mpremote connect PORT resume exec CODE` (resume: never soft-reset a
    running display)."""
    exe = os.path.join(os.path.dirname(mpy.sys.executable), "mpremote")
    if not os.path.exists(exe):
        exe = "mpremote"
    return subprocess.run([exe, "connect", port, "resume", "exec", code],
                          capture_output=True, text=True, timeout=timeout)
