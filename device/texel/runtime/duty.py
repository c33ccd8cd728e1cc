# duty.py -- carrier amplitude (uint16) to PWM compare counts (portable).
#
# The plate is driven by a PWM square wave at the carrier frequency; its
# fundamental for duty D (0..1 of a period) is proportional to sin(pi*D),
# largest at D = 0.5. A linear amplitude a (0..1) therefore needs
#     D(a) = asin(a * sin(pi * duty_cap)) / pi
# so that a = 1 lands exactly on the cap and the plate gets a * (the
# fundamental at the cap). A full bridge doubles the fundamental; the law is
# the same.
#
# The law is evaluated once, when the object is built (floats allowed there);
# duty() is the hot path: small ints only, no allocation (docs/runtime.md).
import math

from ..compat import const, array

_SEGMENTS = const(1024)     # table rows = amp16 >> 6 (0..1023) + 1 end point


def duty_fraction(amplitude, duty_cap=0.5):
    """The law itself: the duty D (0..duty_cap of a period) whose
    fundamental is `amplitude` (0..1) of the fundamental at duty_cap,
    D = asin(a * sin(pi * cap)) / pi. Floats: for building tables and for
    tools (hardware/sweep.py), never the refresh; DutyLaw tabulates it."""
    x = amplitude * math.sin(math.pi * duty_cap)
    if x > 1.0:
        x = 1.0
    return math.asin(x) / math.pi
_SHIFT = const(6)           # low bits of amp16 interpolated between rows
_MASK = const(63)


class DutyLaw:
    """DutyLaw(top, duty_cap=0.5): amplitude -> PWM counts for a PWM with
    top+1 counts per carrier period (compare 0..top+1).

    .lut  array('H') of 1,025 counts (made when read): lut[i] = duty(64*i) for i < 1024,
          i.e. round(D(64*i/65535) * (top+1)); lut[1024] = the cap (a = 1).
    .duty(amp16) -> counts for amplitude 0..65535 (allocation-free).
    .max_counts  = floor(duty_cap * (top+1)); duty() never exceeds it.
    .amplitude_of(counts) -> the uint16 amplitude those counts deliver.

    Accuracy: duty() interpolates a finer copy of the table (counts * 2^q,
    q chosen so it still fits uint16) and rounds once, so the delivered
    fundamental sin(pi*counts/(top+1)) is within one count's worth of the
    commanded a*sin(pi*cap) (worst case 0.56 of a count at top+1 = 3,676;
    tests/runtime/test_duty.py)."""

    def __init__(self, top, duty_cap=0.5):
        if not isinstance(top, int) or not 1 <= top <= 65535:
            raise ValueError("top: expected an int 1..65535 (PWM counts - 1), got %r" % (top,))
        cap = float(duty_cap)
        if not 0.0 < cap <= 0.5:
            # above 50 % the fundamental falls again (sin(pi*D) peaks at D = 0.5)
            raise ValueError("duty_cap: expected 0 < duty_cap <= 0.5, got %r" % (duty_cap,))
        n = top + 1                         # counts per carrier period
        cap_counts = int(cap * n)           # floor: never above duty_cap*(top+1)
        self.top = top
        self.period = n
        self.duty_cap = cap
        self.max_counts = cap_counts
        s = math.sin(math.pi * cap)         # fundamental at the cap (relative)
        self._s = s

        # q: fractional bits of the fine table. The last row may overshoot the
        # cap by 64/63 of the last step, so keep headroom.
        q = 0
        while q < 8 and (((cap_counts + 2) << (q + 1)) * 65) // 64 <= 65535:
            q += 1
        self.q = q
        half = (1 << q) >> 1                # rounding offset (0 when q = 0)
        top_fine = cap_counts << q

        fine = array("H", bytes(2 * (_SEGMENTS + 1)))
        scale = n * (1 << q) / math.pi
        for i in range(_SEGMENTS):
            x = (i << _SHIFT) / 65535.0 * s  # a * sin(pi*cap), < 1
            if x > 1.0:
                x = 1.0
            v = int(math.asin(x) * scale + 0.5)
            if v > top_fine:
                v = top_fine
            fine[i] = v
        # End point of the last segment: amp16 = 65535 (a = 1) is row 1023 plus
        # 63/64 of the step (the row itself, amp16 = 65536, does not exist), so
        # choose the end point that makes that land exactly on the cap: at the
        # largest fine value that still rounds to it (the exact curve ends at
        # duty_cap*(top+1), at or above the floored cap).
        lo = fine[_SEGMENTS - 1]
        want = top_fine + half - 1 if half else top_fine
        g = want - lo
        step = (64 * g + 62) // 63 if g > 0 else 0
        fine[_SEGMENTS] = lo + step
        self._fine = fine
        self._half = half

    @property
    def lut(self):
        # made when asked (tests, docs): the refresh reads _fine, and a board
        # keeps no second 2 KB table for it
        lut = array("H", bytes(2 * (_SEGMENTS + 1)))
        for i in range(_SEGMENTS):
            lut[i] = (self._fine[i] + self._half) >> self.q
        lut[_SEGMENTS] = self.max_counts
        return lut

    def duty(self, amp16):
        # amp16: uint16 amplitude 0..65535 (out-of-range values are clamped).
        # Returns compare counts 0..max_counts. Small ints only.
        if amp16 >> 16:                     # negative or > 65535 (one test)
            amp16 = 0 if amp16 < 0 else 65535
        t = self._fine
        i = amp16 >> _SHIFT
        lo = t[i]
        return (lo + (((t[i + 1] - lo) * (amp16 & _MASK)) >> _SHIFT) + self._half) >> self.q

    def amplitude_of(self, counts):
        """The uint16 amplitude (0..65535) that `counts` delivers: the
        inverse of the law, for tests and telemetry (uses floats)."""
        if counts <= 0:
            return 0
        d = counts / self.period
        if d > 0.5:
            d = 1.0 - d                     # sin(pi*D) is symmetric about 1/2
        a = math.sin(math.pi * d) / self._s
        v = int(a * 65535.0 + 0.5)
        return 65535 if v > 65535 else v
