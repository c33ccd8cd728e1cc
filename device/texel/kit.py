# The classroom kit: a playlist of scenes stepped by a button, shown on the
# board's LED, with no laptop (docs/kit.md). main.py runs it at power-up
# when /texelpad.json holds scenes "then" the first (`texelpad scene boot A.json B.json`).
# The button is polled and debounced here, in the main loop, never in the
# refresh interrupt; a push builds the next scene as the host's push does
# (app.push: the old one plays until the swap). A Ctrl-C (a laptop's
# texelpad or mpremote) ends the loop and leaves the scene playing: the
# board is then the host's, until the next power-up.
import time

from . import app
from .compat import ticks_add, ticks_diff, ticks_us

POLL_MS = 10            # button read every 10 ms
DEBOUNCE_MS = 30        # a level must hold this long to count (contact bounce: ~1-10 ms)
BLINK_MS = 200          # the LED shows scene k as: off, then k blinks of 200 ms on,
PAUSE_MS = 1000         # 200 ms off, then 1 s off, then on while it plays
# where a board file names no button or LED: the port's (rp2: the Pico's own)
DEFAULTS = {"rp2": ({"pin": "bootsel", "active_low": 0}, {"pin": "LED", "active_low": 0})}


class Debounce:
    """feed(level, now) -> True once per press: when the level has been 1
    for DEBOUNCE_MS after being 0 as long (a release, then a press). now:
    compat.ticks_us(). Pure: no pins, no clock of its own (tests/runtime/test_kit.py)."""

    def __init__(self, hold_ms=DEBOUNCE_MS, level=0):
        self.hold = hold_ms
        self.stable = level         # the debounced level
        self.seen = level           # the last raw level
        self.since = None           # when the raw level last changed (ticks_us)

    def feed(self, level, now):
        if level != self.seen:
            self.seen = level
            self.since = now
            return False
        if level == self.stable or self.since is None:
            return False
        if ticks_diff(now, self.since) < self.hold * 1000:
            return False
        self.stable = level
        return level == 1


class Blinker:
    """The LED's pattern for scene k (0-based): off (so that the first blink
    shows after the steady light of the scene before), k+1 blinks, a pause,
    then on."""

    def __init__(self, write):
        self.write = write
        self.steps = ()
        self.i = 0
        self.until = 0

    def show(self, k, now):
        self.steps = [0] + [1, 0] * (k + 1)
        self.i = 0
        self.until = now
        self.update(now)

    def update(self, now):
        if self.i > len(self.steps) or ticks_diff(now, self.until) < 0:
            return
        if self.i == len(self.steps):
            self.write(1)                   # the pattern is over: on while it plays
        else:
            on = self.steps[self.i]
            self.write(on)
            last = self.i == len(self.steps) - 1
            self.until = ticks_add(now, 1000 * (PAUSE_MS if last else BLINK_MS))
        self.i += 1


def _sleep(ms):
    if hasattr(time, "sleep_ms"):
        time.sleep_ms(ms)
    else:
        time.sleep(ms / 1000)


def io_for(board, hw):
    """(read_button, write_led) for the board playing: the backend's own
    (the virtual board's) or its pins (hw/pins.py) from the board file,
    else the port's DEFAULTS; ValueError when the board names no button."""
    if hasattr(hw, "kit_button"):
        return hw.kit_button(board.get("button")), hw.kit_led(board.get("led"))
    dflt = DEFAULTS.get(board["port"], (None, None))
    b = board.get("button") or dflt[0]
    if b is None:
        raise ValueError("board %r has no button: add \"button\": {\"pin\": ...} to its "
                         "file (runtime/boards.py BUTTON_KEYS)" % board["name"])
    from .hw import pins
    led = board.get("led") or dflt[1]
    return pins.button(b), (pins.led(led) if led is not None else (lambda on: None))


def run(playlist, polls=None, button=None, led=None, log=print):
    """Play `playlist` (scenes; the first is expected to be playing: main.py
    starts it) and step to the next at each press of the button, round and
    round. polls: stop after that many polls (tests); else until Ctrl-C.
    Returns the index of the scene playing. A scene the board refuses is
    skipped with a line on the console (the one before plays on)."""
    rt = app._running()
    if not playlist:
        raise ValueError("the playlist is empty")
    if button is None or led is None:
        b, l = io_for(rt.board, rt.hw)
        button = button or b
        led = led or l
    deb = Debounce(level=button())          # held at power-up: wait for a release
    blink = Blinker(led)
    k = 0
    blink.show(k, ticks_us())
    n = 0
    try:
        while polls is None or n < polls:
            now = ticks_us()
            if deb.feed(button(), now):
                k = _step(playlist, k, log)
                now = ticks_us()            # the push took its time: the pattern starts now
                blink.show(k, now)
            blink.update(now)
            _sleep(POLL_MS)
            n += 1
    except KeyboardInterrupt:
        pass
    return k


def _step(playlist, k, log):
    """Push the scene after k (round and round) and return its index; one
    the board refuses is skipped, so a press always moves on."""
    n = len(playlist)
    for j in range(1, n + 1):
        i = (k + j) % n
        try:
            app.push(playlist[i])
            app.tidy()
            log("texelpad: scene %d of %d" % (i + 1, n))
            return i
        except ValueError as e:
            log("texelpad: scene %d of %d not played: %s" % (i + 1, n, e))
        except KeyboardInterrupt:
            # a laptop's Ctrl-C mid-push: one that made room (app._make_room) may
            # have left nothing playing; the scene before plays again
            if app._rt is not None and app._rt.refresh.scene is None:
                app.push(playlist[k])
            raise
    return k
