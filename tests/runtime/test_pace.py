"""texel.runtime.pace: the schedule of the paced refresh loop (CircuitPython's
refresh.mode "loop"; app.run_loop and texel/serve.py), on scripted clocks -
CircuitPython's millisecond one (supervisor.ticks_ms, which starts 65 s
before its 2^29 ms wrap so that wrap bugs show at once) and a microsecond one.
The pacing on the chip itself: bench/circuitpython.py and
tests/host/test_emulated_cpy.py."""
from __future__ import annotations

import pytest

from texel import compat
from texel.runtime.pace import Pacer, clock_of

MS_WRAP = 1 << 29


class _Clock:
    """A clock that moves `step` ticks at every read, wrapping as CircuitPython's
    ms ticks (2^29) or MicroPython's us ticks (2^30); jump() moves it at once."""

    def __init__(self, start: int, step: int, wrap: int):
        self.t, self.step, self.wrap = start, step, wrap

    def __call__(self) -> int:
        self.t = (self.t + self.step) % self.wrap
        return self.t

    def jump(self, ticks: int) -> None:
        self.t = (self.t + ticks) % self.wrap


def _ms_clock(c: _Clock):
    return (c, compat.ms_diff, compat.ms_add, 1000)


def _run(p: Pacer, clock: _Clock, seconds: float, per_s: int) -> int:
    """Poll p until the clock has moved `seconds`: refreshes run."""
    n = 0
    moved = 0
    last = clock.t
    while moved < seconds * per_s:
        if p.due():
            n += 1
        moved += (clock.t - last) % clock.wrap
        last = clock.t
    return n


def test_ms_ticks_wrap_as_circuitpython_s():
    assert compat.ms_diff(5, MS_WRAP - 5) == 10
    assert compat.ms_diff(MS_WRAP - 5, 5) == -10
    assert compat.ms_add(MS_WRAP - 1, 2) == 1


@pytest.mark.parametrize("hz", [1000, 500, 333, 50])
def test_an_ms_clock_paces_any_rate_up_to_1000_hz_across_its_wrap(hz):
    # 1 ms a read; 130 s through the wrap
    c = _Clock(MS_WRAP - 65_000, 1, MS_WRAP)
    p = Pacer(hz, _ms_clock(c))
    n = _run(p, c, 130.0, 1000)
    assert abs(n - 130 * hz) <= 1
    assert p.late == 0
    assert p.refreshes() == n
    assert abs(p.elapsed() - 130_000) <= 2


def test_a_stall_is_counted_late_and_caught_up_back_to_back():
    c = _Clock(MS_WRAP - 10, 1, MS_WRAP)
    p = Pacer(1000, _ms_clock(c))
    n = _run(p, c, 1.0, 1000)
    c.jump(15)                          # a garbage collection: 15 ms without a refresh
    c.step = 0                          # (refreshes that take no time)
    burst = 0
    while p.due():                      # the missed refreshes, back to back
        burst += 1
    c.step = 1
    assert burst >= 14 and p.late >= 13
    n += burst + _run(p, c, 1.0, 1000)
    assert abs(n - 2016) <= 2           # the rate held over the stall


def test_restart_drops_the_missed_refreshes():
    # serve() restarts the schedule after a request: no burst of late refreshes
    c = _Clock(0, 1, MS_WRAP)
    p = Pacer(1000, _ms_clock(c))
    _run(p, c, 0.5, 1000)
    c.jump(200)                         # a request ran 200 ms
    p.restart()
    assert p.late == 0
    n = _run(p, c, 1.0, 1000)
    assert abs(n - 1000) <= 1 and p.late == 0


def test_a_us_clock_paces_fractional_periods():
    # 8333 Hz on microseconds: periods of 120 and 121 us, 8333 a second exactly
    c = _Clock((1 << 30) - 300_000, 7, 1 << 30)
    p = Pacer(8333, (c, compat.ticks_diff, compat.ticks_add, 1))
    n = _run(p, c, 2.0, 1_000_000)
    assert abs(n - 16666) <= 1 and p.late == 0


def test_the_clock_of_a_runtime():
    class Rt:
        pace_clock = None

        def ticks(self):
            return 0

        def diff(self, a, b):
            return a - b
    rt = Rt()
    ticks, diff, add, unit = clock_of(rt)
    assert (ticks, diff, unit) == (rt.ticks, rt.diff, 1)
    rt.pace_clock = ("t", "d", "a", 1000)
    assert clock_of(rt) == rt.pace_clock
    # CPython has no supervisor: compat paces in microseconds here
    assert compat.PACE_CLOCK[3] == 1
