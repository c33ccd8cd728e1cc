# texel.runtime.pace -- the schedule of the paced refresh loop (refresh.mode
# "loop": CircuitPython, where no timer interrupt runs the refresh and Python
# calls it when it is due). One schedule for both loops that run it:
# texel.app.run_loop and texel/serve.py (which also answers the host).
#
# Refresh k of a second is due k*per_s//hz clock ticks after the second began
# (per_s: ticks a second); after hz refreshes the schedule moves on by a second,
# so tick differences stay far inside the clock's wrap (2^29 ticks: ~9 minutes
# of microseconds) and k*q stays a small int. A refresh that starts more than a
# period after it was due counts as late; a loop that fell behind runs the
# missed refreshes back to back.
#
# The clock (ticks, diff, add, unit_us): compat.PACE_CLOCK, or the board's (the
# virtual board's stepped one). On CircuitPython it counts milliseconds
# (supervisor.ticks_ms): its microsecond clock allocates (compat.py says why),
# and a paced loop that allocates stalls ~15 ms at every garbage collection.
# So a loop paced there runs at most 1000 Hz (compat.PORT_TABLE loop_hz, which
# runtime/boards.py checks).
from ..compat import ticks_add


def clock_of(rt):
    """The clock that paces rt (texel.app's runtime, or a test's): its
    pace_clock, else its microsecond ticks."""
    c = getattr(rt, "pace_clock", None)
    return c if c is not None else (rt.ticks, rt.diff, ticks_add, 1)


class Pacer:
    def __init__(self, hz, clock):
        self.ticks, self.diff, self.add, unit_us = clock
        self.per_s = 1000000 // unit_us         # ticks a second
        self.hz = hz
        self.q, self.r = divmod(self.per_s, hz)  # a period: q + r/hz ticks
        self.late = 0                           # refreshes started > a period after due
        self.restart()

    def restart(self):
        """Count the schedule from now: after a pause (a request served), no
        burst of late refreshes."""
        self.t0 = self.ticks()
        self.k = 0
        self.secs = 0                           # whole seconds the schedule moved on

    def due(self):
        """True when the next refresh is due: the caller runs it now. Allocates
        nothing on a clock of small ints (the loop calls it while it waits)."""
        k = self.k
        if k >= self.hz:
            k -= self.hz
            self.secs += 1
            self.t0 = self.add(self.t0, self.per_s)
        now = self.diff(self.ticks(), self.t0)
        at = k * self.q + (k * self.r) // self.hz
        if now < at:
            self.k = k
            return False
        if now - at > self.q:
            self.late += 1
        self.k = k + 1
        return True

    def elapsed(self):
        """Ticks since the schedule (re)started."""
        return self.secs * self.per_s + self.diff(self.ticks(), self.t0)

    def refreshes(self):
        return self.secs * self.hz + self.k
