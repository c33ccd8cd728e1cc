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

import sys
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import texel
import texel.runtime.scene
from texel.compat import UNIX_PLATFORMS
from texel.runtime.kinds import texel as kind_texel
from texel.runtime.refresh import TELEMETRY_SLOTS   # the most one telemetry read returns
from texel.gen.params import FORMAT_NEW

from .. import __version__
from . import protocol
from .protocol import PROTOCOL, literal
from .transport import ImageTooOld, Interrupted, Link, LinkError, LinkTimeout, NoBoard, \
    NotTexelpad, NoUlab, answer, ports
from .transport import unexpected as _bad

HOST_IMAGE_VERSION = texel.__version__
# Where Board.push and start send frames to texel.wire.stand() instead of code for
# the raw REPL (no compile of the request on the board: docs/firmware.md): the
# RP2040's MicroPython, whose console is USB CDC - the host's writes wait while the
# board does not read. Not the STM32 (its REPL is a UART: bytes sent while the board
# collects after an answer overflow its buffer), CircuitPython (serve answers the
# link) or the unix port (the virtual board).
STAND_PLATFORMS = ("rp2",)
# s: what a start or push may take on the board (start + a texel push: ~16 s wall on
# the emulated Pico alone - tests/host/test_emulated_pico.py prints it - and over 30 s
# on a CI host running two emulators at once); --timeout raises it
LONG_WORK_S = 60



def _version_tuple(v: str) -> tuple[int, ...]:
    out = []
    for part in v.split("."):
        digits = "".join(ch for ch in part if ch.isdigit())
        out.append(int(digits) if digits else 0)
    return tuple(out)


# --- answers: the board's words are checked for shape before they are used -----------
# A board that answers with the right framing but the wrong shape (another
# program, an image of another version, a fault) is a LinkError saying so,
# never a TypeError/KeyError deep in a command.

def _is_int(v: Any) -> bool:
    return type(v) is int


def _is_num(v: Any) -> bool:
    return type(v) in (int, float)


# status() while running: each key and what its value must be
_RUNNING = {"board": str, "port": str, "refresh": str, "refresh_hz": int, "refreshes": int,
            "rate_hz": int, "worst_us": int, "overruns": int, "faults": int, "position": int,
            "amplitude": int, "duty": int, "pwm_top": int, "pushes": int}


def check_status(port: str, st: Any) -> dict[str, Any]:
    """status() as the commands use it, or LinkError."""
    ok = type(st) is dict and type(st.get("running")) is bool
    if ok and st["running"]:
        d = st.get("display")
        ok = (all(type(st.get(k)) is t for k, t in _RUNNING.items())
              and _is_num(st.get("carrier_hz")) and st["refresh_hz"] > 0
              and type(d) is dict and _is_int(d.get("positions")) and d["positions"] > 0
              and _is_num(d.get("dx_um")) and d["dx_um"] > 0
              and (st.get("scene") is None or type(st.get("scene")) is dict))
    if not ok:
        raise _bad(port, "status()", st)
    return st


def _check_hello(port: str, hello: Any) -> tuple:
    ok = type(hello) is tuple and len(hello) == 5
    if ok:
        ver, impl, version, mpy, platform = hello
        ok = (type(ver) is tuple and len(ver) == 2 and type(impl) is str
              and type(version) is tuple and all(_is_int(x) for x in version)
              and (mpy is None or _is_int(mpy)) and type(platform) is str
              and (ver[0] == "missing" or (_is_int(ver[0]) and type(ver[1]) is str)))
    if not ok:
        raise NotTexelpad("%s answers, but not as texelpad's handshake expects (%s)"
                          % (port, str(_bad(port, "the handshake", hello)).split(": ", 1)[1]))
    return hello


def full_screen_texel(params: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    """A scene of one texel region over the whole display."""
    return full_screen(dict(params, kind="texel"), display)


class Board:
    """A board running texelpad, over one Link. Use connect() to make one."""

    def __init__(self, link: Link, hello: tuple):
        self.link = link
        self.port = link.port
        ver, impl, version, mpy, platform = _check_hello(link.port, hello)
        self.firmware = {"implementation": impl, "version": tuple(version), "mpy": mpy,
                         "platform": platform}
        # pushes go to the board's standing reader (Link.eval_frame) where its console
        # has flow control: MicroPython on an RP2040 (USB CDC)
        self.stands = impl == "micropython" and platform in STAND_PLATFORMS
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
        # CircuitPython: leaving the raw REPL restarts its VM, so a display that
        # plays is handed to texel.app.serve() instead (transport.Link.close)
        self.link.close(serve=self.firmware["implementation"] == "circuitpython"
                        and self.image is not None)

    def _app(self, func: str, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        """texel.app.func(...): the board's user API."""
        return self.link.call(protocol.APP, func, *args, timeout=timeout, **kwargs)

    def _wire(self, func: str, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        """texel.wire.func(...): what only the link calls (uploads, base64 data, the
        virtual board's finger)."""
        keep = func in self._KEEPS and self._known_at == self.link.commands
        out = self.link.call(protocol.WIRE, func, *args, timeout=timeout, **kwargs)
        if keep:
            self._known_at = self.link.commands
        return out

    # --- the status this Board knows -------------------------------------------
    # A push needs the board's display (and, for a scene whose texels are planned
    # whole, its free heap) before it is sent. Asking status() for it before every
    # push took 29.3 ms of the emulated Pico's clock each time (compile 2.1, then
    # the collection, the heap walk and a 1 KB repr: bench/request_parts.py), more than
    # the push itself. So a Board remembers the status it read or a push made
    # (texel.app.pushed's answer merged), for as long as nothing else ran on the
    # board (Link.commands: any other command, a resync or a reset forgets it).
    _known: dict[str, Any] | None = None
    _known_at = -1
    # texel.wire calls after which what status() says of the display still holds
    _KEEPS = frozenset(("telemetry_b64", "samples_b64", "scene_source", "finger"))

    def _remember(self, st: dict[str, Any]) -> dict[str, Any]:
        self._known, self._known_at = st, self.link.commands
        return st

    def _known_status(self) -> dict[str, Any]:
        """The running status this Board read or made last, if nothing else
        ran on the board since; else a fresh one (_running_status)."""
        st = self._known
        if st is not None and self._known_at == self.link.commands and st.get("running"):
            return st
        return self._running_status()

    # --- the device entry points ---------------------------------------------
    def status(self) -> dict[str, Any]:
        """texel.app.status() on the board."""
        return self._remember(check_status(self.port, self._app("status")))

    def start(self, board_name: str, scene: dict[str, Any] | None = None,
              progress: Callable[[int, int], None] | None = None, **opts: Any) -> dict[str, Any]:
        """texel.app.start(board_name, scene, **opts): stops what plays and starts
        again (board name = a file in boards/ on the device). The board checks
        the board file against its firmware and the scene first: a start that
        cannot succeed leaves what plays playing."""
        board_name = protocol.plain(board_name)
        if not isinstance(board_name, str):
            raise ValueError("board name: %s is not a string" % type(board_name).__name__)
        if scene is not None:
            scene = host_check(scene)
        for k in opts:
            if not isinstance(k, str) or not k.isidentifier():
                raise ValueError("start(): option %r is not a name" % (k,))
        return self._send("start", [board_name, scene], 1, opts, progress)

    def fitting(self) -> list[str]:
        """The board files on the board that its firmware and image can run."""
        names = self._app("fitting")
        if type(names) is not list or not all(type(n) is str for n in names):
            raise _bad(self.port, "fitting()", names)
        return names

    def restart(self, board_name: str, scene: dict[str, Any] | None,
                realtime: bool = False) -> dict[str, Any]:
        """Start the display again with a scene this board played (its own
        canonical form from scene_source(), checked by the board alone: it
        fits the board's display, which need not be the TPaD's)."""
        return self._send("start", [board_name, protocol.plain(scene)], 1,
                          {"realtime": True} if realtime else None, None)

    def _running_status(self) -> dict[str, Any]:
        st = self.status()
        if not st.get("running"):
            raise LinkError("texelpad is not running on %s: start it first "
                            "(texelpad push --board NAME, or Board.start)" % self.port)
        return st

    def _push(self, scene: "dict[str, Any] | CheckedScene", st: dict[str, Any],
              progress: Callable[[int, int], None] | None = None,
              ) -> tuple[dict[str, Any], "CheckedScene"]:
        checked = checked_for(scene, st["display"])
        if st.get("mem_free") is None and planned_whole(checked):
            st = self._running_status()         # the heap figure refuse_what_cannot_fit needs
            checked = checked_for(checked, st["display"])   # checked again only if it differs
        refuse_what_cannot_fit(checked, st)
        return self._send("push", [checked.plain], 0, None, progress, st), checked

    def _send(self, func: str, args: list[Any], scene_at: int, kwargs: dict | None,
              progress: Callable[[int, int], None] | None,
              before: dict[str, Any] | None = None) -> dict[str, Any]:
        """texel.app.push / start with the scene in args[scene_at]: its long
        samples regions go first as uploads (data in pieces, with progress),
        then the call takes them in place of their values. Ctrl-C on the host
        (KeyboardInterrupt) interrupts the board too and says exactly what
        the board plays afterwards (Interrupted)."""
        timeout = self._long_work_s()
        scene = args[scene_at]
        try:
            if scene is None:
                return check_status(self.port, self._app(func, *args, timeout=timeout,
                                                         **(kwargs or {})))
            scene, uploads = protocol.split_uploads(scene)
            args = list(args)
            args[scene_at] = scene
            if uploads:
                self._upload([u for _, u in uploads], progress)
            # a push with the status read before it (Board._push) asks texel.app.pushed:
            # its answer is only what a push changes (app.changes), merged here into
            # that status - the board's answer 4.5 ms, not 7.0 (bench/request_parts.py)
            lean = func == "push" and before is not None
            f = "pushed" if lean else func
            slots = {i: k for k, (i, _) in enumerate(uploads)}
            if self.stands:         # no compile on the board: a frame to texel.wire.stand()
                ans = self.link.eval_frame(*protocol.staged_frame(f, args, scene_at, slots,
                                                                  kwargs), timeout)
            else:
                ans = self.link.eval_reply(protocol.staged_call(
                    protocol.WIRE, f, args, scene_at, slots, kwargs), timeout)
            got = answer(self.port, ans, func + "()")
            if lean and type(got) is dict:
                got = dict(before or {}, **got)
            return self._remember(check_status(self.port, got))
        except KeyboardInterrupt:
            raise self._interrupted(func, before) from None
        except LinkTimeout:
            # the board is still at it (a build, an upload) or hung: interrupt it, so
            # nothing finishes later behind the user's back, and say what plays now
            raise LinkTimeout("%s did not finish %s() within %g s; %s (a board slower than "
                              "a chip, e.g. an emulated one, may need --timeout S)"
                              % (self.port, func, timeout, self._interrupted(func, before))
                              ) from None

    def _long_work_s(self) -> float:
        """s a start or push may take on the board (the link's timeout, at least LONG_WORK_S)."""
        return max(self.link.timeout, LONG_WORK_S)

    def _upload(self, values: list[list[int]],
                progress: Callable[[int, int], None] | None) -> None:
        """Stage each list of uint16 values on the board (texel.wire.upload_*),
        in pieces of protocol.UPLOAD_PIECE values; progress(bytes done, total)."""
        import base64
        from array import array
        self._wire("upload_begin", [len(v) for v in values])
        total = 2 * sum(len(v) for v in values)
        done = 0
        if progress:
            progress(0, total)
        for slot, vals in enumerate(values):
            for o in range(0, len(vals), protocol.UPLOAD_PIECE):
                part = array("H", vals[o:o + protocol.UPLOAD_PIECE])
                if sys.byteorder == "big":
                    part.byteswap()
                self._wire("upload_write", slot, o, base64.b64encode(part.tobytes()).decode())
                done += 2 * len(part)
                if progress:
                    progress(done, total)

    def _interrupted(self, func: str, before: dict[str, Any] | None) -> Interrupted:
        """After Ctrl-C on the host: stop the board's half-done request
        (Ctrl-C to the board: an upload or a scene still being built is
        dropped), free what was staged, and find out what plays now. A push
        switched if the board counted it or what plays changed (the swap and
        the count are two steps on the board; either shows it)."""
        try:
            self.link.resync()
            self._wire("upload_discard")
            st = self.status()
        except LinkError as e:
            return Interrupted("interrupted; the board did not answer afterwards (%s), so what "
                               "it plays is unknown: texelpad status tells" % e)
        if func == "push" and before is not None:
            if st.get("pushes") != before.get("pushes") or st.get("scene") != before.get("scene"):
                return Interrupted("interrupted too late: the board had already switched to the "
                                   "new scene (texelpad status shows it)")
            return Interrupted("interrupted: nothing changed, the board plays what it played")
        if st.get("running"):
            return Interrupted("interrupted: the board runs board file %r (texelpad status "
                               "shows what it plays)" % st.get("board"))
        return Interrupted("interrupted: the display is stopped")

    def push(self, scene: "dict[str, Any] | CheckedScene",
             progress: Callable[[int, int], None] | None = None) -> dict[str, Any]:
        """Play `scene` (a dict of regions, or what check_scene made of one).
        Checked on the host once (a CheckedScene checked for this board's
        display is not checked again), then on the board; returns the
        board's status with the new scene. On any error the board keeps
        playing what it played. progress(done, total): bytes of large sample
        data sent so far (called during long uploads)."""
        return self._push(scene, self._known_status(), progress)[0]

    def push_checked(self, scene: "dict[str, Any] | CheckedScene",
                     progress: Callable[[int, int], None] | None = None,
                     ) -> tuple[dict[str, Any], "CheckedScene"]:
        """push(), handing back the checked scene it sent with the status:
        (the board's status, the CheckedScene - its canonical form is what
        the board now plays, as the host's check made it)."""
        return self._push(scene, self._known_status(), progress)

    def push_texel(self, params: dict[str, Any]) -> dict[str, Any]:
        """Play one texel parameter set over the whole display. A set without
        "v" is made format 2 (texel.gen.params.FORMAT_NEW: the same map on
        every board), as texel.render and the board read it too (since 0.2:
        texel.gen.params.FORMAT_VERSION); say "v": 1 for the lab's float
        generator."""
        if not isinstance(params, dict):
            raise ValueError("texel parameters: expected a dict, got %s" % type(params).__name__)
        if "v" not in params:
            params = dict(params, v=FORMAT_NEW)
        st = self._known_status()
        return self._push(full_screen_texel(params, st["display"]), st)[0]

    def stop(self) -> None:
        """Carrier to its safe off state."""
        self._app("stop")

    def scene_source(self) -> dict[str, Any] | None:
        """The canonical scene playing now (to redraw it on the host, save it
        or play it again); long samples regions are read in pieces."""
        import base64
        from array import array
        src = self._wire("scene_source", protocol.INLINE_SAMPLES_MAX)
        if src is None:
            return None
        if not (type(src) is dict and type(src.get("regions")) is list
                and all(type(r) is dict and type(r.get("texture")) is dict
                        and type(r["texture"].get("kind")) is str for r in src["regions"])):
            raise _bad(self.port, "scene_source()", src)
        for i, r in enumerate(src["regions"]):
            tex = r["texture"]
            if tex["kind"] == "samples" and isinstance(tex["u16"], int):
                n = tex["u16"]
                vals = array("H")
                while len(vals) < n:
                    piece = self._wire("samples_b64", i, len(vals), protocol.UPLOAD_PIECE)
                    try:
                        data = base64.b64decode(piece, validate=True)
                    except (TypeError, ValueError):
                        raise _bad(self.port, "samples_b64()", piece) from None
                    if not data or len(data) & 1:
                        raise _bad(self.port, "samples_b64()", piece)
                    vals.frombytes(data)
                if sys.byteorder == "big":
                    vals.byteswap()
                tex["u16"] = vals.tolist()
            elif tex["kind"] == "samples":
                tex["u16"] = list(tex["u16"])
        return src

    # --- telemetry --------------------------------------------------------------
    def stream(self, rate_hz: int = 125) -> int:
        every = self._app("stream", int(rate_hz))
        if not _is_int(every) or every < 0:
            raise _bad(self.port, "stream()", every)
        return every

    def telemetry(self) -> tuple[list[tuple[int, int, int]], int]:
        """The samples since the last call, (t_us, position, amplitude), and how
        many the ring lapped: texel.wire.telemetry_b64 (the ring copied at C speed,
        base64 of little-endian int32 times, int32 positions, uint16 amplitudes)."""
        import base64
        import binascii
        from array import array
        ans = self._wire("telemetry_b64")
        if not (type(ans) in (tuple, list) and len(ans) == 3 and _is_int(ans[0])
                and 0 <= ans[0] <= TELEMETRY_SLOTS and type(ans[1]) is str and _is_int(ans[2])
                and ans[2] >= 0):
            raise _bad(self.port, "telemetry_b64()", ans)
        n, text, lost = ans
        try:
            raw = base64.b64decode(text, validate=True)
        except (binascii.Error, ValueError):
            raise _bad(self.port, "telemetry_b64()", ans) from None
        if len(raw) != 10 * n:
            raise _bad(self.port, "telemetry_b64()", ans)
        t, p, a = array("i"), array("i"), array("H")
        t.frombytes(raw[:4 * n])
        p.frombytes(raw[4 * n:8 * n])
        a.frombytes(raw[8 * n:])
        if sys.byteorder != "little":           # the board's order (every port's)
            for x in (t, p, a):
                x.byteswap()
        return list(zip(t.tolist(), p.tolist(), a.tolist())), lost

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
        return self._wire("finger", [(float(t), None if p is None else float(p)) for t, p in keyframes])

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
        text = answer(self.port, self.link.eval(code, timeout=max(self.link.timeout, 60)),
                      "render_u16()")
        try:
            data = base64.b64decode(text, validate=True)
        except (TypeError, ValueError):
            raise _bad(self.port, "render_u16()", text) from None
        if len(data) & 1:
            raise _bad(self.port, "render_u16()", text)
        return np.frombuffer(data, dtype="<u2").copy()


TPAD_DISPLAY = {"positions": 19200, "dx_um": 5.3}


@dataclass(frozen=True, eq=False)
class CheckedScene:
    """A scene the host has checked (check_scene, the only maker): `plain`,
    what is sent (numpy as plain numbers and lists: protocol.plain);
    `canonical`, the board's own canonical form of it (every default filled
    in, regions sorted: what the board will play and scene_source() will
    answer); `display`, the display it was checked for; `spans`, each
    canonical region's [start, end) positions (texel.runtime.scene.check).
    Board.push takes it without checking it again when `display` is the
    board's. Treat it as read-only: its dicts are not copies."""
    plain: Any
    canonical: dict[str, Any]
    display: dict[str, Any]
    spans: tuple[tuple[int, int], ...]

    def fits(self, display: dict[str, Any]) -> bool:
        """Whether it was checked for this display (positions and dx_um)."""
        return (self.display["positions"] == display["positions"]
                and self.display["dx_um"] == display["dx_um"])


# Bytes the generator holds per planned texel on a board (gen/plan_int.py:
# t28 and d28, 4 bytes each; format 2 adds its 4-byte log pitch, format 1 its
# pitch and phase as a board's float32 - a 64-bit unix port's floats take more,
# so this is a lower bound there).
PLAN_BYTES = {2: 12, 1: 16}


def planned_whole(checked: CheckedScene) -> list[tuple[int, dict[str, Any], int]]:
    """(region index, texture, texels) of each texel region the board renders to
    a map, planning all its texels at once first (texel.runtime.kinds.texel
    .on_plan says which play from a plan instead)."""
    out = []
    regions = checked.canonical["regions"]
    for k, (a, b) in enumerate(checked.spans):
        tex = regions[k]["texture"]
        if tex["kind"] == "texel" and not kind_texel.on_plan(tex, b - a, None):
            out.append((k, tex, (b - a + tex["texel_samples"] - 1) // tex["texel_samples"]))
    return out


def refuse_what_cannot_fit(checked: CheckedScene, st: dict[str, Any]) -> None:
    """Refuse before sending (ValueError) a scene the board cannot build
    however its heap lies: a texel region of 1-4-sample texels (or one texel
    over the region) is rendered to a map, and the generator plans every
    texel of it at once first (texel.runtime.kinds.texel.on_plan says which
    regions play from a plan instead); when that plan alone is more than the
    board's whole free heap (status "mem_free", beside the scene playing)
    nothing can make it fit (issue 30: `push --texel-samples 1` on a Pico,
    230,400 bytes of plan against ~200 KB). What passes is still checked by
    the board, which sees its own blocks (scene.build's out-of-memory
    message names the largest free one)."""
    free = st.get("mem_free")
    if isinstance(free, bool) or not isinstance(free, int):
        return
    for k, tex, count in planned_whole(checked):
        size = tex["texel_samples"]
        each = PLAN_BYTES[tex["v"]]
        if count * each > free:
            raise ValueError(
                "scene: region %d renders %d texels (texel_samples %d): the generator plans "
                "them all first, %d bytes a texel (%d bytes) besides its map; texel_samples "
                "5 .. %d plays from the plan instead (8 bytes a texel); the board has %d bytes "
                "free in all (refused before sending)"
                % (k, count, size, each, count * each, kind_texel.PLAN_MAX_L, free))


def check_scene(scene: Any, display: dict[str, Any] | None = None) -> CheckedScene:
    """THE host's check of a scene, run once per push: the literal check,
    then the board's own validation (texel.runtime.scene.check). The literal
    check comes first: it bounds the nesting depth and the integers before
    the board's validation walks the scene. display None: the TPaD's 19,200
    x 5.3 um (the board's own display is checked again when it is pushed).
    ValueError with the board's words when it would be refused."""
    display = display or TPAD_DISPLAY
    plain = protocol.plain(scene)
    literal(plain)
    canonical, spans, _, _ = texel.runtime.scene.check(plain, display)
    return CheckedScene(plain, canonical, {"positions": display["positions"],
                                           "dx_um": display["dx_um"]}, tuple(spans))


def checked_for(scene: Any, display: dict[str, Any]) -> CheckedScene:
    """scene checked for `display`: a CheckedScene checked for it as it is,
    anything else (a dict; a CheckedScene checked for another display: its
    plain form) through check_scene."""
    if isinstance(scene, CheckedScene):
        if scene.fits(display):
            return scene
        scene = scene.plain
    return check_scene(scene, display)


def host_check(scene: Any, display: dict[str, Any] | None = None) -> Any:
    """check_scene's plain form: the scene as plain data to send (numpy
    numbers and arrays as the Python numbers and lists they hold:
    protocol.plain), checked."""
    return check_scene(scene, display).plain


def connect(port: str | None = None, timeout: float = 10.0, check: bool = True,
            import_image: bool = True) -> Board:
    """Open the board at `port` (None: the one board found) and shake hands:
    the board must run texelpad's device image of this host's protocol and
    version (check=False skips that, e.g. to deploy). import_image=False
    (deploy): the handshake never imports the image from its files
    (protocol.HELLO_LOADED); board.image is None unless the board runs it."""
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
        hello = link.eval(protocol.HELLO if import_image else protocol.HELLO_LOADED)
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


def full_screen(texture: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    """A scene of one region of `texture` (any kind: {"kind": "reference",
    "name": "4sin"}, {"kind": "constant", "level": 0.5}, ...) over the whole
    display."""
    total = display["positions"] * display["dx_um"] / 1000.0
    return {"regions": [{"start_mm": 0, "end_mm": round(total, 6), "texture": dict(texture)}]}


# --- the power-up scene -----------------------------------------------------------
# The board's /main.py (texel/main.py) starts {"board": NAME, "scene": {...}}
# from this file at power-up when it is there; `texelpad deploy` leaves it
# alone (it is not an image file).
BOOT_FILE = "/texelpad.json"
# The unix port's sys.platform values (texel.compat.UNIX_PLATFORMS): the virtual
# board, a host process whose "/" is its flash folder (texel.app.CONFIG follows
# the same rule)


def on_board_path(board: Board, path: str) -> str:
    """A board path ("/texelpad.json") as this board names it: the unix port
    (the virtual board) has the host's filesystem, its "/" is its flash
    folder, the working directory, so paths go relative there (deploy's
    image paths too; the board's main.py follows the same rule)."""
    if board.firmware["platform"] in UNIX_PLATFORMS:
        return path.lstrip("/")
    return path


def board_display(board: Board, name: str) -> dict[str, Any]:
    """The display of board file `name` as this board would start it (its own
    /boards/NAME.json first), after checking that it fits the firmware;
    DeviceError (the board's words) when it has no such file or it does not
    fit. Nothing that plays is touched."""
    name = protocol.plain(name)
    if not isinstance(name, str):
        raise ValueError("board name: %s is not a string" % type(name).__name__)
    d = board._wire("board_display", name)
    if not (type(d) is dict and _is_int(d.get("positions")) and d["positions"] > 0
            and _is_num(d.get("dx_um")) and d["dx_um"] > 0):
        raise _bad(board.port, "board_display()", d)
    return d


def boot_config(board_name: str, scene: Any, display: dict[str, Any], more: Any = (),
                refused: Any = None) -> dict[str, Any]:
    """{"board": NAME, "scene": canonical} for the power-up file, the scene
    checked here first (host_check) and kept in its canonical form: every
    default filled in, so it plays the same after the board's texel is
    updated; ValueError (the board's own words) when it would not start.
    more: scenes after it, a playlist the board's button steps (texel/kit.py):
    "then" holds them (canonical, each checked; the board's main.py plays
    "scene", then these); refused(i, error) makes the error of scene i
    (0-based, the first is "scene")."""
    if not isinstance(board_name, str) or not board_name:
        raise ValueError("board name: expected a board file's name, got %r" % (board_name,))
    config = {"board": board_name, "scene": protocol.plain(check_scene(scene, display).canonical)}
    if more:
        then = []
        for i, sc in enumerate(more, 1):
            try:
                then.append(protocol.plain(check_scene(sc, display).canonical))
            except ValueError as e:
                raise (refused(i, e) if refused else e) from None
        config["then"] = then
    return config


def write_boot(board: Board, config: dict[str, Any]) -> int:
    """Write `config` (boot_config()) to BOOT_FILE: beside the old copy
    ("<file>.new"), then renamed over it, so a failure half-way leaves the
    old file whole (a half-written ".new" is removed). Returns its size."""
    import json
    data = (json.dumps(config, separators=(",", ":"), allow_nan=False) + "\n").encode("utf-8")
    path = on_board_path(board, BOOT_FILE)
    tmp = path + ".new"
    try:
        board.link.write_file(tmp, data)
        board.link.exec(protocol.replace_file(path, tmp))
    except LinkError:
        try:
            board.link.exec(protocol.remove_file(tmp))
        except LinkError:
            pass
        raise
    return len(data)


def clear_boot(board: Board) -> bool:
    """Remove BOOT_FILE (and a leftover "<file>.new"); False when there was none."""
    path = on_board_path(board, BOOT_FILE)
    # protocol.preflight only looking (probe=False, no folders): what is there
    ans = board.link.eval(protocol.preflight([path, path + ".new"], [], "/", probe=False))
    if not (type(ans) is tuple and len(ans) == 2 and type(ans[0]) is dict):
        raise _bad(board.port, "which files are there", ans)
    found = ans[0]
    if any(found.values()):
        board.link.exec(protocol.remove_files([path, path + ".new"]))
    return found.get(path) is not None
