# The refresh: finger position in, carrier duty out. Refresh.step() is the
# whole body of the 8,333 Hz loop (a hard timer IRQ on rp2/stm32), so it uses
# small ints only and allocates nothing: every callable it uses is stored once
# at construction (calling a stored bound method allocates nothing), counters
# wrap below 2^30 (MicroPython small ints), telemetry goes into preallocated
# arrays. A test proves it with micropython.heap_lock() on the unix port.
from array import array
from ..compat import const

_WRAP = const(0x3FFFFFFF)       # counters wrap here: stay small ints
TELEMETRY_SLOTS = const(256)    # ring of (t_us, position, amplitude) samples


class Refresh:
    """One refresh = read position -> amplitude from the scene -> duty.

    sensor.read() -> position index or -1 (lifted); law.duty(amp16) -> PWM
    counts; set_duty(counts) writes the carrier; ticks_us/ticks_diff are the
    platform's clock (integer microseconds, wrapping)."""

    def __init__(self, sensor, law, set_duty, ticks_us, ticks_diff, period_us, idle_amp=0,
                 cost_ticks=None, cost_every=1):
        # ticks_us: the board's clock (telemetry time stamps); cost_ticks:
        # the clock that measures what a refresh costs - the same on
        # hardware, real time on the virtual board (whose ticks are stepped).
        self.cost_ticks = ticks_us if cost_ticks is None else cost_ticks
        self.sensor = sensor
        self.law = law
        self.set_duty = set_duty
        self.ticks_us = ticks_us
        self.ticks_diff = ticks_diff
        self.period_us = period_us
        self.idle_amp = idle_amp        # used when no scene is loaded
        self.scene = None               # swapped by swap(): one reference store
        self.count = 0                  # refreshes done (wraps at 2^30)
        # the body is timed once in cost_every refreshes: a board whose clock
        # allocates (CircuitPython, compat.py) times few, so the loop seldom
        # collects garbage; overruns and worst_us are of the timed ones
        self.cost_every = cost_every
        self.cost_div = 0
        self.overruns = 0               # refreshes whose body took > period_us
        self.worst_us = 0               # longest body seen (us)
        self.pos = -1                   # last position (-1 lifted)
        self.amp = 0                    # last amplitude (uint16)
        self.duty = 0                   # last duty (counts)
        self.faults = 0                 # exceptions caught in step (carrier forced off)
        self.feed = None                # watchdog feed, if the board has one
        # telemetry: every tel_every-th refresh lands in the ring
        self.tel_every = 0
        self.tel_div = 0
        self.tel_head = 0               # total samples written (wraps at 2^30)
        self.tel_t = array("i", bytes(4 * TELEMETRY_SLOTS))
        self.tel_pos = array("i", bytes(4 * TELEMETRY_SLOTS))
        self.tel_amp = array("H", bytes(2 * TELEMETRY_SLOTS))

    def swap(self, scene):
        """Replace the playing scene between two refreshes (a single store:
        the IRQ sees either the old scene or the new one, never a mix)."""
        old = self.scene
        self.scene = scene
        return old

    def step(self, _timer=None):
        # _timer: machine.Timer / pyb.Timer pass themselves to the callback.
        t = self.cost_div
        c0 = self.cost_ticks() if t == 0 else 0
        try:
            pos = self.sensor.read()
            sc = self.scene
            if sc is None:
                amp = self.idle_amp
            elif pos < 0:
                amp = sc.idle
            else:
                amp = sc.amp(pos)
            d = self.law.duty(amp)
            self.set_duty(d)
        except Exception:
            # never leave the carrier driven by a failed refresh
            self.set_duty(0)
            self.faults = (self.faults + 1) & _WRAP
            pos = -1
            amp = 0
            d = 0
        self.pos = pos
        self.amp = amp
        self.duty = d
        if self.feed is not None:
            self.feed()
        if self.tel_every:
            n = self.tel_div + 1
            if n >= self.tel_every:
                n = 0
                h = self.tel_head
                i = h % TELEMETRY_SLOTS
                self.tel_t[i] = self.ticks_us() & _WRAP
                self.tel_pos[i] = pos
                self.tel_amp[i] = amp
                self.tel_head = (h + 1) & _WRAP
            self.tel_div = n
        self.count = (self.count + 1) & _WRAP
        if t:
            self.cost_div = t - 1
            return
        self.cost_div = self.cost_every - 1
        dt = self.ticks_diff(self.cost_ticks(), c0)
        if dt > self.worst_us:
            self.worst_us = dt
        if dt > self.period_us:
            self.overruns = (self.overruns + 1) & _WRAP

    def _unread(self, tail):
        """(head, tail, n, lost): the ring's head now and the n samples from
        tail still in the ring (lost: lapped before they were read)."""
        head = self.tel_head
        n = (head - tail) & _WRAP
        lost = 0
        if n > TELEMETRY_SLOTS:
            lost = n - TELEMETRY_SLOTS
            tail = (head - TELEMETRY_SLOTS) & _WRAP
            n = TELEMETRY_SLOTS
        return head, tail, n, lost

    def _overwritten(self, head, n):
        """How many of the n samples copied from the oldest on to drop: the
        refresh runs on while they are copied (an IRQ, or the virtual board's
        thread); if it came round to the slots copied first, those may hold
        newer samples (time would go backwards) or half-written ones - drop
        them, and one more for the slot it may have been writing."""
        w = (self.tel_head - head) & _WRAP             # written during the copy
        over = n + w - TELEMETRY_SLOTS
        if not w or over < 0:
            return 0
        return over + 1 if over + 1 < n else n

    def telemetry_packed_since(self, tail):
        """telemetry_since at C speed: (t, pos, amp, count, new tail, lost),
        t and pos the samples' int32 values as bytes, amp their uint16 ones
        (the board's byte order: little-endian on every port texelpad runs
        on). Copied by slicing the rings, not sample by sample: on the
        emulated Pico the Python loop took 40..140 ms of board time for 256
        samples - longer than the ring lasts at 2,083 Hz (123 ms), so the
        refresh lapped what was being copied (texelpad demo lost 2,731 of
        3,302). Same loss rules as telemetry_since."""
        head, tail, n, lost = self._unread(tail)
        i = tail % TELEMETRY_SLOTS          # (2^30 is a multiple of the ring's 256 slots)
        a = n if i + n <= TELEMETRY_SLOTS else TELEMETRY_SLOTS - i
        t = _ring_bytes(self.tel_t, i, a, n - a)
        p = _ring_bytes(self.tel_pos, i, a, n - a)
        m = _ring_bytes(self.tel_amp, i, a, n - a)
        drop = self._overwritten(head, n)
        if drop:
            t, p, m = t[4 * drop:], p[4 * drop:], m[2 * drop:]
        return t, p, m, n - drop, head, lost + drop

    def telemetry_since(self, tail):
        """Samples written since `tail` (a previous tel_head) as a list of
        (t_us, position, amplitude), the new tail, and how many were lost
        because the ring was lapped. Called from the REPL, not the IRQ."""
        head, tail, n, lost = self._unread(tail)
        out = []
        for k in range(n):
            i = ((tail + k) & _WRAP) % TELEMETRY_SLOTS
            out.append((self.tel_t[i], self.tel_pos[i], self.tel_amp[i]))
        drop = self._overwritten(head, n)
        return out[drop:], head, lost + drop


def _ring_bytes(ring, i, a, b):
    """Items i .. i+a of array `ring`, then 0 .. b (the wrap), as one bytes."""
    v = memoryview(ring)
    if b:
        return bytes(v[i:i + a]) + bytes(v[0:b])
    return bytes(v[i:i + a])
