"""The Python API to a board running texelpad: `texelpad.connect(port)`.

    with texelpad.connect("/dev/ttyACM0") as b:
        b.push_texel({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7})
        print(b.status()["scene"])

Every request is validated on the host first with the same `texel` code the
board runs (a clear error before anything is sent), then again on the board,
which stays the authority: a refused request raises DeviceError with the
board's own words and the board keeps playing what it played.

numpy numbers and arrays are welcome (`np.linspace` sweeps, a samples
region's values): the host converts them exactly to the Python numbers and
lists they hold before checking (protocol.plain); NaN and inf are refused as
plain floats are, and np.bool_ as True is (a bool is not a number).
"""
from __future__ import annotations

import time
from typing import Any, Callable, Iterator

import texel
import texel.app
import texel.runtime.scene

from .. import __version__
from . import protocol
from .protocol import PROTOCOL, literal
from .transport import DeviceError, ImageTooOld, Link, LinkError, NoBoard, NotTexelpad, NoUlab, \
    ports

HOST_IMAGE_VERSION = texel.__version__



def _version_tuple(v: str) -> tuple[int, ...]:
    out = []
    for part in v.split("."):
        digits = "".join(ch for ch in part if ch.isdigit())
        out.append(int(digits) if digits else 0)
    return tuple(out)


def full_screen_texel(params: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    """A scene of one texel region over the whole display."""
    total = display["positions"] * display["dx_um"] / 1000.0
    tex = dict(params)
    tex["kind"] = "texel"
    return {"regions": [{"start_mm": 0, "end_mm": round(total, 6), "texture": tex}]}


class Board:
    """A board running texelpad, over one Link. Use connect() to make one."""

    def __init__(self, link: Link, hello: tuple):
        self.link = link
        self.port = link.port
        ver, impl, version, mpy, platform = hello
        self.firmware = {"implementation": impl, "version": tuple(version), "mpy": mpy,
                         "platform": platform}
        self.image = None if ver[0] == "missing" else {"protocol": ver[0], "texel": ver[1]}
        self.lost = 0           # telemetry samples lost during the last monitor()
        self.received = 0       # telemetry samples read during the last monitor()
        self.divider = 0        # refreshes per telemetry sample in the last monitor()

    # context manager
    def __enter__(self) -> "Board":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        self.link.close()

    def _app(self, func: str, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        return self.link.call(protocol.APP, func, *args, timeout=timeout, **kwargs)

    # --- the device entry points ---------------------------------------------
    def status(self) -> dict[str, Any]:
        """texel.app.status() on the board."""
        return self._app("status")

    def start(self, board_name: str, scene: dict[str, Any] | None = None,
              **opts: Any) -> dict[str, Any]:
        """texel.app.start(board_name, scene, **opts): stops what plays and starts
        again (board name = a file in boards/ on the device)."""
        board_name = protocol.plain(board_name)
        if not isinstance(board_name, str):
            raise ValueError("board name: %s is not a string" % type(board_name).__name__)
        if scene is not None:
            scene = host_check(scene)
        for k in opts:
            if not isinstance(k, str) or not k.isidentifier():
                raise ValueError("start(): option %r is not a name" % (k,))
        return self._app("start", board_name, scene, timeout=max(self.link.timeout, 30), **opts)

    def _running_status(self) -> dict[str, Any]:
        st = self.status()
        if not st.get("running"):
            raise LinkError("texelpad is not running on %s: start it first "
                            "(texelpad push --board NAME, or Board.start)" % self.port)
        return st

    def _push(self, scene: dict[str, Any], st: dict[str, Any],
              progress: Callable[[int, int], None] | None = None) -> dict[str, Any]:
        scene = host_check(scene, st["display"])
        return self._app("push", scene, timeout=max(self.link.timeout, 30))

    def push(self, scene: dict[str, Any],
             progress: Callable[[int, int], None] | None = None) -> dict[str, Any]:
        """Play `scene` (a dict of regions). Checked on the host, then on the
        board; returns the board's status with the new scene. On any error
        the board keeps playing what it played. progress(done, total): bytes
        of large sample data sent so far (called during long uploads)."""
        return self._push(scene, self._running_status(), progress)

    def push_texel(self, params: dict[str, Any]) -> dict[str, Any]:
        """Play one texel parameter set over the whole display."""
        if not isinstance(params, dict):
            raise ValueError("texel parameters: expected a dict, got %s" % type(params).__name__)
        st = self._running_status()
        return self._push(full_screen_texel(params, st["display"]), st)

    def stop(self) -> None:
        """Carrier to its safe off state."""
        self._app("stop")

    def scene_source(self) -> dict[str, Any] | None:
        """The canonical scene playing now (to redraw it on the host)."""
        return self._app("scene_source")

    # --- telemetry --------------------------------------------------------------
    def stream(self, rate_hz: int = 125) -> int:
        return self._app("stream", int(rate_hz))

    def telemetry(self) -> tuple[list[tuple[int, int, int]], int]:
        samples, lost = self._app("telemetry")
        return [tuple(s) for s in samples], lost

    def monitor(self, seconds: float | None = None, rate_hz: int = 125,
                poll_s: float | None = None) -> Iterator[tuple[int, int, int]]:
        """Yield (t_us, position, amplitude) samples taken by the board's
        refresh at rate_hz, for `seconds` (None: until the caller stops);
        the stream is turned off again at the end. The board samples every
        `self.divider`-th refresh (its refresh rate // rate_hz, at least 1)
        into a 256-sample ring; the ring is read every `poll_s` seconds
        (default: often enough to read it a quarter full, back to back at
        high rates). self.lost counts the samples the ring lapped before
        they were read, self.received the samples yielded."""
        self.lost = 0
        self.received = 0
        self.divider = self.stream(rate_hz)
        if poll_s is None:
            # the ring (TELEMETRY_SLOTS) fills in 256 / rate s; a read every
            # quarter of that, capped at 50 ms, leaves room for a slow round trip
            poll_s = min(0.05, 64.0 / max(1, rate_hz))
        t_end = None if seconds is None else time.monotonic() + seconds
        try:
            while True:
                t_poll = time.monotonic()
                samples, lost = self.telemetry()
                self.lost += lost
                self.received += len(samples)
                yield from samples
                now = time.monotonic()
                if t_end is not None and now >= t_end:
                    break
                # sleep only what is left of the poll period after the round trip
                wait = poll_s - (now - t_poll)
                if wait > 0:
                    time.sleep(wait)
        finally:
            try:
                self.stream(0)
            except LinkError:
                pass

    # --- virtual board only -----------------------------------------------------
    def finger(self, keyframes: list[tuple[float, float | None]]) -> int:
        """Script the virtual board's finger: [(t_ms, position_mm or None)],
        relative to now; returns the board's ticks_us the script starts at."""
        return self._app("finger", [(float(t), None if p is None else float(p)) for t, p in keyframes])

    # --- the generator on the board ----------------------------------------------
    def render_u16(self, params: dict[str, Any], engine: str | None = None) -> Any:
        """texel.render_u16(params, engine=engine) run ON THE BOARD, the map
        read back as a uint16 numpy array: checks a board's own arithmetic
        (float32, ulab, viper) against the host's reference."""
        import base64

        import numpy as np
        if engine == "ulab" and not self.status().get("ulab"):
            raise NoUlab("the ulab engine needs ulab, and %s's firmware has none (stock "
                         "MicroPython has no ulab: use a ulab build such as Pimoroni's, or "
                         "CircuitPython; or engine='int')" % self.port)
        params = protocol.plain(params)             # numpy numbers -> plain ones, checked
        engine = protocol.plain(engine)
        literal(params)
        texel.validate(params)                      # the board's own check, here first
        code = protocol.render_u16(params, engine)
        kind, value = self.link.eval(code, timeout=max(self.link.timeout, 60))
        if kind == "err":
            raise DeviceError(value)
        return np.frombuffer(base64.b64decode(value), dtype="<u2").copy()


def host_check(scene: Any, display: dict[str, Any] | None = None) -> Any:
    """The literal check, then the board's own validation, run here first;
    returns the scene as plain data to send (numpy numbers and arrays as the
    Python numbers and lists they hold: protocol.plain). The literal check
    comes first: it bounds the nesting depth and the integers before the
    board's validation walks the scene. display None: the TPaD's 19,200 x
    5.3 um (the board's own display is checked again when it is pushed)."""
    scene = protocol.plain(scene)
    literal(scene)
    texel.runtime.scene.validate(scene, display or {"positions": 19200, "dx_um": 5.3})
    return scene


def connect(port: str | None = None, timeout: float = 10.0, check: bool = True) -> Board:
    """Open the board at `port` (None: the one board found) and shake hands:
    the board must run texelpad's device image of this host's protocol and
    version (check=False skips that, e.g. to deploy)."""
    if port is None:
        found = ports()
        if not found:
            raise NoBoard("no board found (texelpad ports lists what is plugged in); "
                          "without --port, texelpad demo runs on the virtual board")
        if len(found) > 1:
            raise NoBoard("%d boards found (%s): say which with --port"
                          % (len(found), ", ".join(p["port"] for p in found)))
        port = found[0]["port"]
    link = Link(port, timeout=timeout)
    try:
        hello = link.eval(protocol.HELLO)
        board = Board(link, hello)
        if check:
            check_image(board)
    except BaseException:
        link.close()
        raise
    return board


def check_image(board: Board) -> None:
    """Refuse a board without texelpad's image, or with one of another
    protocol or an older version than this host."""
    if board.image is None:
        raise NotTexelpad("%s runs %s %s but not texelpad's device image: install it with "
                          "texelpad deploy --port %s" % (
                              board.port, board.firmware["implementation"],
                              ".".join(map(str, board.firmware["version"])), board.port))
    proto, ver = board.image["protocol"], board.image["texel"]
    if proto != PROTOCOL or _version_tuple(ver) < _version_tuple(HOST_IMAGE_VERSION):
        older = proto < PROTOCOL or _version_tuple(ver) < _version_tuple(HOST_IMAGE_VERSION)
        raise ImageTooOld(
            "%s's device image is texel %s (protocol %s), this host is texelpad %s "
            "(protocol %s): %s" % (board.port, ver, proto, __version__, PROTOCOL,
                                   "run texelpad deploy --port %s to update it" % board.port
                                   if older else "update the host (pip install -U texelpad)"))
