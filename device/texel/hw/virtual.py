# The virtual board: the device image running under the MicroPython unix port
# (or CPython) with a scripted finger and a recorded carrier. Time is virtual
# and stepped, so runs are deterministic: refresh k happens at
# t_k = k * 1e6 // hz microseconds. The finger drives a virtual ADC through
# the board's own sensor calibration, so the real sensor code (filter, lift
# detection, latency compensation) runs exactly as on hardware.
#
# Every duty written is recorded with its virtual time into preallocated
# arrays (no allocation per write: set_duty runs inside the refresh).
# Integer math only; the finger interpolation multiplies a position span
# (<= 2^20) by a time span, which stays a small int on the 64-bit unix port.
from array import array
import time
from ..compat import TICKS_MASK as _T_MASK, ticks_us as _real_ticks_us, ticks_diff as _ticks_diff


class Finger:
    """A scripted finger: keyframes [(t_us, position or None), ...] in time
    order, positions in display samples; linear motion between keyframes, None
    = lifted from that keyframe to the next. Preallocated arrays, integer
    interpolation, allocation-free evaluation in time order."""

    def __init__(self, keyframes):
        n = len(keyframes)
        if n == 0:
            raise ValueError("finger: at least one keyframe")
        self.kt = array("i", bytes(4 * n))
        self.kp = array("i", bytes(4 * n))
        last = -1
        for i in range(n):
            t, p = keyframes[i]
            if not isinstance(t, int) or t < last:
                raise ValueError("finger: keyframe times must be increasing ints (us)")
            last = t
            self.kt[i] = t
            self.kp[i] = -1 if p is None else int(p)
        self.n = n
        self.i = 0

    def at(self, t):
        kt = self.kt
        i = self.i
        if i > 0 and t < kt[i]:
            i = 0                       # time went backwards: rescan
        while i + 1 < self.n and kt[i + 1] <= t:
            i += 1
        self.i = i
        p0 = self.kp[i]
        if p0 < 0 or t < kt[i]:
            return -1
        if i + 1 >= self.n:
            return p0
        p1 = self.kp[i + 1]
        if p1 < 0:
            return p0
        dt = kt[i + 1] - kt[i]
        return p0 + ((p1 - p0) * (t - kt[i])) // dt


class VirtualHw:
    """Hw contract of docs/runtime.md for the virtual board."""

    def __init__(self, board, record=1 << 16, noise_raw=0, seed=1):
        c = board["carrier"]
        self.board = board
        self.freq_hz = c["freq_hz"]
        cpu = board.get("cpu_hz", 125000000)
        self.top = (cpu + self.freq_hz // 2) // self.freq_hz - 1   # counts - 1
        s = board["sensor"]
        self.kind = s["kind"]
        self.positions = board["display"]["positions"]
        self.raw0 = s["raw_at_start"]
        self.raw1 = s["raw_at_end"]
        self.noise = noise_raw          # +- raw units of uniform noise
        self.lcg = seed & 0x7FFFFFFF
        self.finger = Finger([(0, None)])
        self.now = 0                    # virtual time, us
        self.k = 0                      # refresh index
        self.hz = 0
        self.cb = None
        self.running = False
        self.cap = record
        self.rec_t = array("i", bytes(4 * record))
        self.rec_d = array("H", bytes(2 * record))
        self.nrec = 0
        self.dropped = 0
        self.duty = 0
        self.real_ticks = _real_ticks_us
        self.thread = False
        self.set_duty(0)                # safe state from the start

    # --- the Hw contract -------------------------------------------------
    def set_duty(self, counts):
        self.duty = counts
        n = self.nrec
        if n < self.cap:
            self.rec_t[n] = self.now & _T_MASK      # wraps like ticks_us
            self.rec_d[n] = counts
            self.nrec = n + 1
        else:
            self.dropped += 1

    def off(self):
        self.set_duty(0)

    def adc_read(self, i):
        p = self.finger.at(self.now)
        if p < 0:
            raw = 0                     # nothing pressed: the strip reads ~0
        else:
            if p >= self.positions:
                p = self.positions - 1
            if self.kind == "adc_ratio":
                a = 2000 + (60000 * p) // (self.positions - 1)
                raw = a if i == 0 else 62000 - a
            else:
                raw = self.raw0 + ((self.raw1 - self.raw0) * p) // (self.positions - 1)
        if self.noise:
            # Park-Miller style LCG kept below 2^31: integer, deterministic
            self.lcg = (self.lcg * 48271) % 0x7FFFFFFF
            raw += (self.lcg % (2 * self.noise + 1)) - self.noise
            if raw < 0:
                raw = 0
            elif raw > 65535:
                raw = 65535
        return raw

    def adc_reader(self, i):
        if i == 0:
            return self._read0
        return self._read1

    def _read0(self):
        return self.adc_read(0)

    def _read1(self):
        return self.adc_read(1)

    def ticks_us(self):
        return self.now & _T_MASK

    def ticks_diff(self, a, b):
        return _ticks_diff(a, b)

    def cost_ticks(self):
        """Real time, for measuring what a refresh costs on this machine."""
        return self.real_ticks()

    def start(self, callback, hz):
        self.cb = callback
        self.hz = hz
        self.running = True

    def stop(self):
        self.running = False
        self.thread = False
        self.cb = None

    # --- virtual-only ----------------------------------------------------
    def set_finger(self, keyframes):
        """Script the finger from now on: keyframe times are relative to now.
        Returns now (virtual us), the time the script starts at."""
        t0 = self.now
        self.finger = Finger([(t0 + t, p) for (t, p) in keyframes])
        return t0

    def advance(self, us):
        """Run the refresh for `us` microseconds of virtual time."""
        if not self.running or self.cb is None:
            self.now += us
            return 0
        end = self.now + us
        hz = self.hz
        cb = self.cb
        steps = 0
        while True:
            t = ((self.k + 1) * 1000000) // hz
            if t > end:
                break
            self.k += 1
            self.now = t
            cb(None)
            steps += 1
        self.now = end
        return steps

    def run_realtime(self):
        """Pace the refresh by the wall clock in a background thread (the
        interactive virtual board): every few ms, run the refreshes that are
        due, each at its exact virtual time."""
        import _thread
        self.thread = True

        def loop():
            last = self.real_ticks()
            while self.thread:
                time.sleep(0.004)
                now = self.real_ticks()
                self.advance(_ticks_diff(now, last))
                last = now
        _thread.start_new_thread(loop, ())

    def recorded(self, start=0):
        """(t_us, duty) pairs recorded from index `start` (host/test side)."""
        return [(self.rec_t[i], self.rec_d[i]) for i in range(start, self.nrec)]

    def clear_record(self):
        self.nrec = 0
        self.dropped = 0

    # --- the classroom kit's button and LED (texel/kit.py) ------------------
    button_levels = ()          # the button's scripted levels, one read each (then 0)
    led_log = None              # [(virtual us, level), ...] the LED was set to

    def kit_button(self, spec):
        """The virtual button: reads button_levels front to back (a test or
        the host scripts it), 0 when they run out. spec: the board file's
        "button" (its pin is only a label here)."""
        self.button_levels = list(self.button_levels)

        def read():
            lv = self.button_levels
            return lv.pop(0) if lv else 0
        return read

    def kit_led(self, spec):
        """The virtual LED: records (now, level) in led_log."""
        self.led_log = []

        def write(on):
            self.led_log.append((self.now, 1 if on else 0))
        return write
