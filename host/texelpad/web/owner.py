"""The one owner of the lab's board: every browser tab's request goes through
here, one at a time (a lock: pushes are serialised, never interleaved), on
the same Board API the command line uses. A board that disappears is said so
plainly, and the next request tries to reach it again.
"""
from __future__ import annotations

import copy
import threading
from typing import Any, Callable

from ..link.board import Board, CheckedScene, board_display, check_scene, connect
from ..link.transport import LinkError


class BoardLost(RuntimeError):
    """The board did not answer; the server goes on and says so."""


class BoardOwner:
    def __init__(self, port: str, board_name: str | None = None, timeout: float = 10.0,
                 connector: Callable[..., Board] = connect, **start_opts: Any) -> None:
        # board_name: the board file to start when texelpad is not running
        # there; start_opts: texel.app.start's options (realtime=True for the
        # virtual board)
        self.port = port
        self.board_name = board_name
        self.start_opts = start_opts
        self.timeout = timeout
        self._connect = connector
        self._board: Board | None = None
        self._lock = threading.Lock()
        # Boards connected so far: a scene pushed on an earlier connection
        # may not play any more (the board was lost, replugged, restarted)
        self.connections = 0
        # the display of the board once texelpad was seen running there: the
        # owner holds the port, so nothing else can stop it or change it; a
        # lost board clears it
        self._display: dict[str, Any] | None = None
        self.lost: str | None = None
        # The canonical scene the board plays, as its scene_source() said,
        # and what the board's status said of it then: every page's strip
        # asks what plays (the experimenter's every second), and a long
        # samples region is ~67 KB read over the link in pieces (0.36 s
        # holding the lock, where a status is ~0.02 s: bench/results/lab.txt,
        # "strip"). The board's status counts its pushes and describes what
        # plays; while those read the same on the same connection, the scene
        # is the one read before.
        self._source_of: tuple[tuple[Any, ...], dict[str, Any] | None] | None = None
        self.source_reads = 0       # scene_source() calls that reached the board

    def _get(self) -> Board:
        if self._board is None:
            try:
                self._board = self._connect(self.port, timeout=self.timeout)
            except (LinkError, OSError) as e:
                self.lost = str(e)
                raise BoardLost("the board on %s does not answer: %s" % (self.port, e)) from None
            self.lost = None
            self.connections += 1
        return self._board

    def _call(self, f: Callable[[Board], Any]) -> Any:
        with self._lock:
            b = self._get()
            try:
                return f(b)
            except LinkError as e:
                if isinstance(e, ValueError):           # the board refused it: still there
                    raise
                try:
                    b.close()
                except Exception:
                    pass
                self._board = None
                self._display = None
                self.lost = str(e)
                raise BoardLost("lost the board on %s: %s" % (self.port, e)) from None

    def status(self) -> dict[str, Any]:
        return self._call(lambda b: b.status())

    def push(self, scene: dict[str, Any] | CheckedScene) -> tuple[dict[str, Any], dict[str, Any]]:
        """Play scene; (the board's status, the canonical scene it plays).
        A refused scene raises ValueError and the board plays on."""
        st, sent = self.push_checked(scene)
        return st, sent.canonical

    def push_checked(self, scene: dict[str, Any] | CheckedScene,
                     ) -> tuple[dict[str, Any], CheckedScene]:
        """Play scene - a dict, checked here once (link.board.check_scene),
        or what check_scene made of one for this board's display, not
        checked again; (the board's status, the CheckedScene sent: its
        canonical form, made by the board's own validation code, is what
        the board plays). A refused scene raises ValueError and the board
        plays on."""
        def go(b: Board) -> tuple[dict[str, Any], CheckedScene]:
            # (no status round trip once seen running)
            display = self._display or self._running(b)
            checked = scene if isinstance(scene, CheckedScene) else check_scene(scene, display)
            return b.push_checked(checked)
        return self._call(go)

    def scene_source(self) -> dict[str, Any] | None:
        """The canonical scene the board plays (to draw the strip): read from
        the board once per scene played, then remembered (see __init__)."""
        return self._call(lambda b: self._source(b, b.status()))

    def playing(self) -> tuple[dict[str, Any], dict[str, Any] | None]:
        """(the board's status, the canonical scene it plays) - what a strip
        draws - with texelpad started first when it is not running (the
        owner's board file, as every page does); one status round trip."""
        def go(b: Board) -> tuple[dict[str, Any], dict[str, Any] | None]:
            st = b.status()
            if not st.get("running") and self._display is None:
                self._running(b)
                st = b.status()         # only after a start: else the first one holds
            return st, self._source(b, st)
        return self._call(go)

    def _source(self, b: Board, st: dict[str, Any]) -> dict[str, Any] | None:
        """The scene b plays, st its status just now (under the lock)."""
        key = (self.connections, st.get("running"), st.get("pushes"), repr(st.get("last_push")),
               repr(st.get("scene")))
        known = self._source_of
        if known is None or known[0] != key:
            known = self._source_of = (key, b.scene_source())
            self.source_reads += 1
        # (a copy: a caller that edits it must not edit the remembered one)
        return copy.deepcopy(known[1])

    def _running(self, b: Board) -> dict[str, Any]:
        """texelpad running on the board (started when it is not): its display."""
        st = b.status()
        if not st.get("running"):
            if not self.board_name:
                raise ValueError("texelpad is not running on %s: start it with texelpad push "
                                 "--board NAME, or give texelpad lab --board" % self.port)
            st = b.start(self.board_name, None, **self.start_opts)
        self._display = st["display"]
        return self._display

    def check_board_name(self) -> None:
        """The board file board_name is one the board has and can run
        (texel.wire.board_display; nothing that plays is touched): ValueError
        with the board's words and the names it can run when not, BoardLost
        when the board does not answer. `texelpad lab --board` asks it at
        startup, not at the first session."""
        name = self.board_name
        if not name:
            return

        def go(b: Board) -> None:
            try:
                board_display(b, name)
            except ValueError as e:
                try:
                    names = b.fitting()
                except (LinkError, ValueError):
                    names = []
                raise ValueError("%s%s" % (e, "; this board can run: %s" % ", ".join(names)
                                           if names else "")) from None
        self._call(go)

    def display(self) -> dict[str, Any]:
        """The display of the board (started first when it is not running;
        asked once, then known)."""
        if self._display is not None:
            return self._display
        return self._call(self._running)

    def close(self) -> None:
        with self._lock:
            if self._board is not None:
                self._board.close()
                self._board = None

    # --- see and hear (web/strip.py; docs/lab.md) ---------------------------------------
    # Whether the board is the virtual one, held per connection: (the Board
    # it was asked of, the answer). A board's kind cannot change while the
    # owner holds its port; a lost board is a new Board object, asked again.
    _virtual_of: tuple[Board, bool] | None = None

    def _virtual(self, b: Board) -> bool:
        known = self._virtual_of
        if known is not None and known[0] is b:
            return known[1]
        st = b.status()
        if not st.get("running"):
            self._running(b)
            st = b.status()
        # the board file's port "virtual" is texel.hw.virtual's VirtualHw, the
        # only backend with a scripted finger (texel.wire.finger)
        v = st.get("port") == "virtual"
        self._virtual_of = (b, v)
        return v

    def is_virtual(self) -> bool:
        """Whether the board is the virtual board (its finger can be moved
        from the host); started first when it is not running."""
        return self._call(self._virtual)

    def finger(self, position_mm: float | None) -> int:
        """Put the virtual board's finger at position_mm (mm from the
        display's start) from now on, or lift it (None); the board's
        ticks_us at that moment. A real board has its own finger sensor:
        ValueError (400), nothing sent."""
        def go(b: Board) -> int:
            if not self._virtual(b):
                raise ValueError("this board has its own finger sensor: the finger is on the "
                                 "glass, it cannot be moved from the page")
            return b.finger([(0.0, position_mm)])
        return self._call(go)

    # the telemetry stream the lab's finger recording set: (the Board, rate_hz)
    _stream_of: tuple[Board, int] | None = None

    def finger_samples(self, rate_hz: int) -> tuple[list[tuple[int, int, int]], int, bool]:
        """The board's telemetry samples since the last read at rate_hz
        (t_us, position or -1, amplitude), how many the ring lapped, and
        whether the stream was (re)started by this call - its samples then
        come from before the caller's moment, and it may drop them
        (a new connection, a replugged board: the stream is set again)."""
        def go(b: Board) -> tuple[list[tuple[int, int, int]], int, bool]:
            fresh = self._stream_of is None or self._stream_of[0] is not b \
                or self._stream_of[1] != rate_hz
            if fresh:
                if self._display is None:   # (texelpad running there first, as a push would)
                    self._running(b)
                b.stream(rate_hz)
                self._stream_of = (b, rate_hz)
            samples, lost = b.telemetry()
            return samples, lost, fresh
        return self._call(go)

    def telemetry(self, seconds: float, rate_hz: int = 125) -> list[tuple[int, int, int]]:
        """The board's own record of what it played for `seconds`: (t_us,
        position or -1, uint16 amplitude) samples taken by its refresh
        (Board.monitor; the stream is turned off again at the end)."""
        def go(b: Board) -> list[tuple[int, int, int]]:
            try:
                return list(b.monitor(seconds, rate_hz))
            finally:
                self._stream_of = None  # (monitor turns the stream off at its end)
        return self._call(go)
