"""Painting a brush in parts, from the finger outward (device/texel/gen/brush_parts.py
Painting; brush_core.c tb_paint_range, tb_skip): whatever sample the painting
starts at, however large its parts, and wherever it stops, the finished map
is paint()'s, value for value - here the Painting class itself on CPython,
calling the C loops through the host's build of the core (tests/support/
core_c.py). Its builds on boards: tests/gen/test_texel_core.py (the x64
native module on the unix port) and tests/firmware (the Pico's firmware)."""
from __future__ import annotations

from array import array

import pytest

from texel.gen import brush as B, brush_parts as P
from texel.runtime.upload import Chunks

from support import core_c

from test_paint import brushes

pytestmark = pytest.mark.skipif(not core_c.available(), reason="no gcc")


@pytest.fixture
def c_painter(monkeypatch):
    """Painting's _native_c(): the host's C core (paint_part and skip only;
    paint() whole by numpy, the same integers: test_paint.py)."""
    fake = core_c.PaintParts()
    monkeypatch.setattr(B, "_native_c", lambda: fake)
    return fake


def whole(brush: dict, seed: int, n: int) -> list[int]:
    return list(B.paint(brush, seed, n, how="numpy"))


def parts(brush: dict, seed: int, n: int, at: int, **kw) -> tuple[list[int], P.Painting]:
    ch = Chunks(n)
    p = P.Painting(brush, seed, n, ch, at, **kw)
    p.finish()
    return [v for c in ch.chunks for v in c], p


def painted_span(n: int, calls: list[tuple[int, int, int]]) -> tuple[int, int]:
    """The samples the first call wrote: lo_emit .. its last complete window."""
    w_from, w_to, lo = calls[0]
    return lo, min(n, B.HOP * w_to - 3 * B.HOP)


@pytest.mark.parametrize("k", range(7))
def test_parts_are_the_whole_painting(c_painter, k):
    """Every brush of test_paint.py's range, full screen, from the finger at
    the left edge, the right edge, the middle and three other places."""
    b = B.validate(brushes()[k])
    n = 19200
    ref = whole(b, 40 + k, n)
    for at in (0, n - 1, n // 2, 1234, 9601, 18000):
        got, p = parts(b, 40 + k, n, at)
        assert got == ref, (k, at)
        assert p.done and p.work is None


def test_the_first_part_holds_the_finger_and_is_final(c_painter):
    """After __init__ (what the push waits for) the samples around the finger
    are already their final values, the rest still 0; a full screen needs
    no window twice on the right, 4 more a part on the left, 40 at most."""
    b = B.validate(brushes()[0])
    n = 19200
    ref = whole(b, 7, n)
    for at in (0, 47, 48, 5000, 19199):
        ch = Chunks(n)                  # zeroed as the C core's u16 makes them on a board
        for c in ch.chunks:
            c[:] = array("H", bytes(2 * len(c)))
        c_painter.calls.clear()
        p = P.Painting(b, 7, n, ch, at)
        got = [v for c in ch.chunks for v in c]
        lo, hi = painted_span(n, c_painter.calls)
        assert lo <= max(0, at - 300) and hi >= min(n, at + 200), (at, lo, hi)
        assert got[lo:hi] == ref[lo:hi]
        assert not any(got[:lo]) and not any(got[hi:])
        p.finish()
        assert [v for c in ch.chunks for v in c] == ref
        right = sum(t - f for f, t, e in c_painter.calls if e == 0 and f > 0)
        first = c_painter.calls[0][1] - c_painter.calls[0][0]
        left = [t - f for f, t, e in c_painter.calls[1:] if e > 0 or f == 0]
        assert first + right + sum(left) <= B.windows(n) + 4 * len(left) <= B.windows(n) + 40


@pytest.mark.parametrize("n", [1, 47, 48, 49, 191, 192, 193, 500, 1000, 4803, 9600])
@pytest.mark.parametrize("first,part", [(16, 16), (8, 8), (12, 10), (20, 40)])
def test_lengths_and_part_sizes(c_painter, n, first, part):
    """Short regions (fewer windows than a part), lengths around the hop and
    the window, small and odd-sized parts, one array as the target."""
    b = B.validate(brushes()[4])
    ref = whole(b, 3, n)
    for at in sorted({0, n // 3, n - 1}):
        got, _ = parts(b, 3, n, at, first=first, part=part)
        assert got == ref, (n, at)
        out = array("H", bytes(2 * n))
        P.Painting(b, 3, n, out, at, first=first, part=part).finish()
        assert list(out) == ref


@pytest.mark.parametrize("speed", [-150, 150, -400])
def test_the_parts_follow_a_moving_finger(c_painter, speed):
    """`at` as a function (app._finger: where the finger is now), read before
    each part: a finger moving `speed` samples a part (150: ~230 mm/s on the
    Pico's display at ~3.5 ms a part of 8 windows) finds its sample painted
    after every part; the map whole at the end. Region offset 1000: the
    display's positions."""
    b = B.validate(brushes()[2])
    n = 19200
    ref = whole(b, 5, n)
    ch = Chunks(n)
    trail = [11000]

    def where():
        return trail[-1]
    p = P.Painting(b, 5, n, ch, where, offset=1000)
    misses = 0
    while not p.done:
        trail.append(max(0, min(n + 999, trail[-1] + speed)))
        p.step()
        at = min(n - 1, max(0, trail[-1] - 1000))
        misses += ch[at] != ref[at]
    assert [v for c in ch.chunks for v in c] == ref
    assert misses <= (2 if abs(speed) > 300 else 0), misses


def test_an_interrupted_finish_paints_it_all_again(c_painter, monkeypatch):
    """A Ctrl-C between two parts (any exception in finish()): the next
    finish() paints the whole map again, from the generator's start, in the
    work array it has - not the parts left, whose states the stopped part may
    have stepped on. A finish() after that does nothing."""
    b = B.validate(brushes()[1])
    n = 6000
    ref = whole(b, 11, n)
    ch = Chunks(n)
    p = P.Painting(b, 11, n, ch, 3000, part=8)
    real = c_painter.paint_part
    seen = []

    def stop_third(*a):
        real(*a)
        seen.append(a[15])
        if len(seen) == 3:
            raise KeyboardInterrupt
    monkeypatch.setattr(c_painter, "paint_part", stop_third)
    with pytest.raises(KeyboardInterrupt):
        p.finish()
    assert not p.done
    monkeypatch.setattr(c_painter, "paint_part", real)
    monkeypatch.setattr(B, "paint", lambda *a: pytest.fail("paint() allocates its own work"))
    c_painter.calls.clear()
    p.finish()
    assert c_painter.calls == [(0, B.windows(n), 0)]
    assert [v for c in ch.chunks for v in c] == ref and p.done
    p.finish()
    assert c_painter.calls == [(0, B.windows(n), 0)]


def test_bad_parts_are_refused(c_painter):
    b = B.validate(brushes()[0])
    with pytest.raises(ValueError, match="even"):
        P.Painting(b, 1, 1000, array("H", bytes(2000)), 0, first=9)
    with pytest.raises(ValueError, match="even"):
        P.Painting(b, 1, 1000, array("H", bytes(2000)), 0, part=6)


def test_no_paint_part_no_painting(monkeypatch):
    """A board whose C painter predates paint_part (an older native module)."""
    monkeypatch.setattr(B, "_native_c", lambda: None)
    with pytest.raises(ValueError, match="paint_part"):
        P.Painting(B.validate(brushes()[0]), 1, 100, array("H", bytes(200)), 0)


def test_the_first_part_leads_a_moving_finger(c_painter, monkeypatch):
    """The finger read before and after the painting's setup (7 ms apart on
    this fake clock, 140 samples: ~100 mm/s): the first part is centred
    LEAD_US further on, where it will be about when the push answers."""
    clock = iter([0, 7000])
    monkeypatch.setattr(P, "ticks_us", lambda: next(clock))
    reads = iter([10000, 10140])
    b = B.validate(brushes()[0])
    p = P.Painting(b, 1, 19200, Chunks(19200), lambda: next(reads, 10140))
    w_from, w_to, lo = c_painter.calls[0]
    centre = 10140 + 140 * P.LEAD_US // 7000
    assert w_to - w_from == P.FIRST_WINDOWS and abs(lo + 504 - centre) <= 96, (lo, centre)
    p.finish()


@pytest.mark.parametrize("reads,times", [((-1, 10140), (0, 7000)),     # touched down meanwhile
                                         ((10000, 10140), (0, 500))])  # readings too close
def test_no_lead_without_two_readings_far_enough_apart(c_painter, monkeypatch, reads, times):
    clock = iter(times)
    monkeypatch.setattr(P, "ticks_us", lambda: next(clock))
    it = iter(reads)
    b = B.validate(brushes()[0])
    P.Painting(b, 1, 19200, Chunks(19200), lambda: next(it, 10140))
    w_from, w_to, lo = c_painter.calls[0]
    assert abs(lo + 504 - 10140) <= 96, lo
