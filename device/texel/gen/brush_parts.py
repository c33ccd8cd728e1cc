# A brush painted in parts, from the finger outward (issue 32; docs/brush.md "In parts,
# from the finger outward"; texel.app.PAINT_NEAR_FINGER): the C painter's paint_part and
# skip (device/cmod/texelcore brush_core.c tb_paint_range, tb_skip) called part by part,
# the same integers as gen/brush.py paint() whatever the order
# (tests/brush/test_paint_parts.py). A module of its own: imported only where a push
# paints so (a board with the C painter, the finger on a brush region), its bytecode in
# no other heap.
from array import array

from . import brush as B
from .rng import Rng
from ..compat import ticks_us, ticks_diff

FIRST_WINDOWS = 24          # the first part: 24 windows, 1,008 samples (5.3 mm of the Pico's
                            # display) centred where the finger will be (LEAD_US)
PART_WINDOWS = 8            # each later part: 8 windows (~3.5 ms on an RP2040's firmware)
LEAD_MIN_US = 2000          # no lead from readings closer than this
LEAD_US = 20000             # the first part is centred where the finger, moving as it moved
                            # while the painting's setup ran, will be this much later: the
                            # 20-23 ms from that reading to the first later part on the
                            # emulated Pico's firmware (the generator stepped on, the first
                            # part painted, the swap, the answer; docs/firmware.md)


class Painting:
    """gen/brush.py paint() by the C loop (_texelcore paint_part, skip) in parts, so that a
    push can play its brush before the whole map is painted: the windows
    around sample `at` first (in __init__; `at` may be a function that says
    where the finger is now), then step() by step outward, each part on the
    side whose painted edge is nearer the finger, until done; finish()
    paints the rest.
    The integers are paint()'s whatever the order (tests/brush/
    test_paint_parts.py): a part to the right goes on from where the one
    before it ended (its ring of partial sums and generator state kept); a
    part to the left starts afresh from the generator stepped on to its first
    window (skip: K steps a window, its draws dropped), with 4 windows before
    the samples it writes (a sample lies under 4 windows) and writes only
    those its windows cover whole. Memory while it paints: the work array
    (3.9 KB, allocated once) and two rings (768 B each), the generator's
    states where the left parts start (16 B each)."""

    def __init__(self, brush, seed, n, out, at, first=FIRST_WINDOWS, part=PART_WINDOWS,
                 offset=0):
        c = B._native_c()
        if c is None or not hasattr(c, "paint_part"):
            raise ValueError("Painting: this board's C painter has no paint_part")
        if first < 8 or part < 8 or first & 1 or part & 1:
            # (a left part writes from its 4th window on: 8 or more keep them moving)
            raise ValueError("Painting: first and part must be even and >= 8")
        # at: a sample, or a function that says where the finger is now (the display's
        # position, -1 lifted; offset: the region's first position): read again before
        # each part, so the painting follows a moving finger; read around the setup too
        # (its floats: ~7 ms on an RP2040), for the finger's speed
        self._where, self._offset = (at, offset) if callable(at) else (None, 0)
        self._at = at if self._where is None else 0
        self.n = n
        p1, t1 = self._raw(), ticks_us()
        chunks = getattr(out, "chunks", None)
        self._args = ([chunks if chunks is not None else (out,), B._chunk_bits(chunks)],
                      comp_tables(brush))
        self.brush, self.seed, self.out = brush, seed, out
        self.busy = False           # finish() began (a Ctrl-C may have stopped it mid-part)
        self.part = part
        self.work = B.array_i(4 * B.K + 3 * B.WINDOW)
        nw = B.windows(n)
        self.nw = nw
        p2 = self._raw()
        at = self.at()
        dt = ticks_diff(ticks_us(), t1)
        # (a finger on the display at both readings, and a setup long enough that the
        # sensor's jitter is not taken for a speed: ~7 ms on an RP2040)
        if p1 is not None and p2 is not None and p1 >= 0 and p2 >= 0 and \
                dt >= LEAD_MIN_US and p2 != p1:
            at += (p2 - p1) * LEAD_US // dt
            at = 0 if at < 0 else (n - 1 if at >= n else at)
        # the first part's samples centred there
        a0 = (at - (first * B.HOP - 3 * B.HOP) // 2) // B.HOP
        a0 = 0 if a0 < 0 else a0 & ~1
        b0 = a0 + first if a0 + first < nw else nw
        # where the left parts start: each `part` windows, or as many as it is
        # from a0 where that is more (4 of them the samples before it: a part
        # starting afresh writes from its 4th window), so that far from the
        # finger the parts grow and their 4 windows' overhead stays small
        # (at most 40 windows over a full screen: test_paint_parts.py)
        starts = []
        a = a0
        while a > 0:
            size = part if part > a0 - a else a0 - a
            a = a + 4 - size if a + 4 - size > 0 else 0
            starts.append(a)
        st = B.state(Rng(seed))
        self.left = []              # (window, state), the nearest first
        w = 0
        for a in reversed(starts):
            c.skip(st, B.K * (a - w))
            w = a
            self.left.insert(0, (a, array("H", st)))
        c.skip(st, B.K * (a0 - w))
        self.st = st                # the right parts' state and ring
        self.ring = B.array_i(B.WINDOW)
        self.lring = B.array_i(B.WINDOW)
        self._paint(st, self.ring, a0, b0, B.HOP * a0)
        self.right = b0             # the next right part's first window
        self.lo = a0                # the left parts have painted from window lo on

    def _raw(self):
        """Where the finger is now in the region's samples (beyond its ends
        too), None while lifted or where `at` was a sample."""
        if self._where is None:
            return None
        p = self._where()
        return p - self._offset if p >= 0 else None

    def at(self):
        """The sample under the finger in the region, clamped to it (where it
        was last, while the finger is lifted)."""
        at = self._raw()
        if at is None:
            at = self._at
        at = 0 if at < 0 else (self.n - 1 if at >= self.n else at)
        self._at = at
        return at

    def _paint(self, st, ring, w_from, w_to, lo_emit):
        (chunks, bits), (invk, ll, sign, off, tab, t) = self._args
        B._native_c().paint_part(st, invk, ll, sign, off, self.n, chunks, bits, tab, t[4], t[1],
                               t[2], t[3], t[5], ring, w_from, w_to, lo_emit, self.work)

    @property
    def done(self):
        return self.right >= self.nw and not self.left

    def step(self):
        """Paint the next part; False once nothing is left."""
        if self.done:
            return False
        # the side whose painted edge is nearer the finger now, in samples (one the
        # finger is already past: nearer than any); the right edge is 3 windows short
        # of the next right part's first window, whose samples it writes
        at = self.at()
        w = at // B.HOP
        if self.left and (self.right >= self.nw or
                          at - B.HOP * self.lo < B.HOP * self.right - 3 * B.HOP - at):
            a, st = self.left.pop(0)
            ring = self.lring
            B._native_c().zero(ring)              # a fresh start (memset)
            b = self.lo + 4 if self.lo + 4 < self.nw else self.nw
            self._paint(st, ring, a, b, B.HOP * a)
            self.lo = a
        else:
            # `part` windows, or half the distance from the finger where that is more
            # (fewer calls far from it: each costs ~0.3 ms of Python on an RP2040)
            size = ((self.right - w) >> 1) & ~1
            b = self.right + (size if size > self.part else self.part)
            b = b if b < self.nw else self.nw
            self._paint(self.st, self.ring, self.right, b, 0)
            self.right = b
        return not self.done

    def finish(self):
        """Paint what is left. If a finish() before this one was stopped (an
        exception - Ctrl-C - between two statements: a part may be half
        written, a state stepped on), paint the whole map again instead, from
        the generator's start, in the work array it has (nothing allocated but
        the state). Once finished, nothing more."""
        if self.out is None:
            return
        if self.busy:
            ring = self.ring
            B._native_c().zero(ring)
            self._paint(B.state(Rng(self.seed)), ring, 0, self.nw, 0)
        else:
            self.busy = True
            while self.step():
                pass
        self.right, self.left = self.nw, []
        self.work = self.ring = self.lring = self.out = None


def comp_tables(brush):
    """(invk, ll, sign, off, plan_int's table, brush._tables()): what the C painter
    is handed for a brush."""
    invk, ll, sign, off = B.compensated(brush)
    return invk, ll, sign, off, B.table(), B._tables()
