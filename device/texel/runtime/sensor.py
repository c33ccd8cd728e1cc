# Position sensing: raw ADC readings -> display position index (portable:
# MicroPython, CircuitPython, CPython). Contract: docs/runtime.md, sensor.py.
#
#   s = make_sensor(board["sensor"], reads, positions, refresh_hz)
#   s.read() -> 0 .. positions-1, or -1 when the finger is lifted
#
# read() runs in the refresh (a hard IRQ at 8,333 Hz on rp2/stm32): small ints
# only, no allocation (proven under micropython.heap_lock() by
# tests/runtime/test_sensor.py), no float, no exception, one internal method call.
# Every intermediate stays below 2^30 (MicroPython small ints are +-2^30; a
# bigger one would be a heap bigint); the bound of each is noted where it is
# computed, for positions <= 2^20 and the other limits checked in _Tracker.
#
# Pipeline per sample (all in Q8 positions, 1/256 of a 5.3 um position):
#   calibrate   d = raw - raw_at_start (or start - raw when mounted reversed),
#               clamped to [0, span]; x = d * (Q8 positions per raw unit),
#               the scale held in Q14 and split in two 14-bit-safe products
#   filter      f += (x - f) / 2^filter_shift           first-order IIR
#   velocity    v += ((f - f_prev) - v) / 2^velocity_shift  Q8 per refresh
#               (both exact: the bits a shift drops are carried, no dead band)
#   compensate  p = f + v * L, L = (2^filter_shift - 1) + latency_us*hz/1e6
#               refreshes: the IIR's lag on a ramp (exactly 2^k - 1 samples)
#               plus the stated sensor/actuation latency, so during a
#               constant-speed swipe p is where the finger is now
#   output      round(p / 256) clamped to 0 .. positions-1
# Touch-down (first sample at or above the lift threshold after a lift)
# re-seeds f = x, v = 0: the first read after touching reports the new
# position, with no glide from where the finger last left. A lift needs
# `lift_debounce` consecutive low samples (default 3 = 360 us at 8,333 Hz);
# until then each low sample dead-reckons one refresh at the current velocity
# (a dropout is bridged, not frozen).
from ..compat import const

_MAX_POSITIONS = const(1048576)   # 2^20: Q8 positions < 2^28, see bounds below
_MAX_FILTER_SHIFT = const(8)      # IIR time constant up to 255 refreshes (31 ms)
_MAX_VELOCITY_SHIFT = const(8)
_MAX_LATENCY_US = const(20000)    # beyond 20 ms "compensation" is guesswork
_MAX_REFRESH_HZ = const(50000)
_MAX_DEBOUNCE = const(1000)
_LIM = const(1073741823)          # 2^30 - 1: largest MicroPython small int

_DEFAULT_VELOCITY_SHIFT = const(4)  # velocity IIR: 16-refresh time constant
_DEFAULT_DEBOUNCE = const(3)        # consecutive low samples that mean lift


def _need_int(cfg, key, lo, hi, default=None):
    # Board data may come from JSON (ints) or a host literal; a float with an
    # integral value (e.g. 150.0) is accepted, anything else is refused.
    if key not in cfg:
        if default is None:
            raise ValueError("sensor.%s: missing" % key)
        return default
    v = cfg[key]
    ok = not isinstance(v, bool) and isinstance(v, (int, float))
    if ok and not isinstance(v, int):
        try:
            ok = v == int(v)
        except (ValueError, OverflowError):      # nan, inf
            ok = False
    if not ok:
        raise ValueError("sensor.%s: expected an integer, got %r" % (key, v))
    v = int(v)
    if v < lo or v > hi:
        raise ValueError("sensor.%s: %d out of range %d..%d" % (key, v, lo, hi))
    return v


def _check_common(positions, refresh_hz):
    if isinstance(positions, bool) or not isinstance(positions, int) \
            or positions < 2 or positions > _MAX_POSITIONS:
        raise ValueError("display.positions: expected an integer 2..%d, got %r"
                         % (_MAX_POSITIONS, positions))
    if isinstance(refresh_hz, bool) or not isinstance(refresh_hz, (int, float)) \
            or not (1 <= refresh_hz <= _MAX_REFRESH_HZ):
        raise ValueError("refresh.hz: expected 1..%d, got %r" % (_MAX_REFRESH_HZ, refresh_hz))


class _Tracker:
    # The machinery shared by every ADC sensor kind: two-point calibration,
    # IIR filter, touch-down re-seed, lift debounce, latency compensation.
    # A subclass's read() turns its ADC reading(s) into one calibrated-scale
    # value (read_u16 units, 0..65536) or -1 for a no-finger sample, and
    # returns self._track(value).

    def _setup(self, cfg, positions, refresh_hz, compensate):
        _check_common(positions, refresh_hz)
        r0 = _need_int(cfg, "raw_at_start", 0, 65535)
        r1 = _need_int(cfg, "raw_at_end", 0, 65535)
        if r0 == r1:
            raise ValueError("sensor.raw_at_end: equals raw_at_start (%d): no calibration span" % r0)
        k = _need_int(cfg, "filter_shift", 0, _MAX_FILTER_SHIFT)
        kv = _need_int(cfg, "velocity_shift", 0, _MAX_VELOCITY_SHIFT, _DEFAULT_VELOCITY_SHIFT)
        lat = _need_int(cfg, "latency_us", 0, _MAX_LATENCY_US)
        self._debounce = _need_int(cfg, "lift_debounce", 1, _MAX_DEBOUNCE, _DEFAULT_DEBOUNCE)
        self.positions = positions

        # Calibration. span <= 65535 raw units; qmax = (positions-1)*256 < 2^28.
        self._rev = r1 < r0                 # reversed mounting: raw falls along the display
        self._r0 = r0
        span = r1 - r0 if r1 > r0 else r0 - r1
        self._span = span
        qmax = (positions - 1) << 8
        self._qmax = qmax
        # Scale qmax/span Q8 positions per raw unit, as s_hi + s_lo/2^14 with
        # s_lo rounded: x = d*s_hi + (d*s_lo + 2^13) >> 14. d <= span, so
        # d*s_hi <= qmax < 2^28 and d*s_lo + 2^13 <= 65535*16383 + 8192
        # = 1,073,668,097 < 2^30. (A single Q16 scale times a 16-bit d would
        # reach 2^32.) Error <= span/2^15 + 1/2 < 2.5 Q8 units (0.01 position):
        # the calibration points land exactly on 0 and positions-1. Built
        # from small ints only (no bigint needed even at construction).
        s_hi = qmax // span
        s_lo = ((qmax - s_hi * span) * 16384 + (span >> 1)) // span   # rem < span: < 2^30
        if s_lo >= 16384:
            s_hi += 1
            s_lo -= 16384
        self._s_hi = s_hi
        self._s_lo = s_lo

        # Filters: shift k (position) and kv (velocity); each keeps the bits
        # its shift drops in a remainder (0 .. 2^shift - 1), so it is the
        # exact IIR y += (x - y)/2^shift with no dead band: a still input is
        # reached exactly (a plain `f += (x - f) >> k` stalls up to 2^k - 1
        # Q8 units short, and a velocity stalled at a few Q8 per refresh
        # times a lead of hundreds of refreshes is positions of error).
        self._k = k
        self._km = (1 << k) - 1
        self._kv = kv
        self._kvm = (1 << kv) - 1
        self.filter_shift = k
        self.velocity_shift = kv

        # Compensation gain L in Q8 refreshes: (2^k - 1) refreshes of IIR lag
        # + latency_us * hz / 1e6. Integer-rounded when hz is an integer so
        # CPython and every MicroPython agree bit for bit (a float32 board
        # could round the float product differently): 256/1e6 = 32/125000,
        # and t = lat*hz <= 1e9 < 2^30 split so no product reaches 2^30.
        if refresh_hz == int(refresh_hz):
            t = lat * int(refresh_hz)
            q = t // 125000
            lat_q8 = q * 32 + ((t - q * 125000) * 32 + 62500) // 125000
        else:
            lat_q8 = int(lat * refresh_hz * 256 / 1000000 + 0.5)
        lq8 = (((1 << k) - 1) << 8) + lat_q8 if compensate else 0
        # lq8 <= (255 + 20000*50000/1e6) * 256 = 321,280 < 2^19
        self._lq8 = lq8
        self.lead_q8 = lq8                  # public: compensation in Q8 refreshes
        # |v| <= vmax keeps v*lq8 + 128 < 2^30. It bites only when the lead is
        # huge: at the defaults (lq8 = 1,088) vmax is ~3,850 positions per
        # refresh, far beyond any finger; at the extreme limits above it is
        # ~13 positions per refresh. vmax <= qmax too (f moves at most qmax).
        vmax = (_LIM - 128) // lq8 if lq8 else qmax
        if vmax > qmax:
            vmax = qmax
        self._vmax = vmax
        self.reset()

    def reset(self):
        # Lifted, filter empty: the next finger sample re-seeds.
        self.touching = False
        self._low = 0               # consecutive no-finger samples while touching
        self._f = 0                 # filtered position, Q8, 0..qmax (floor)
        self._fr = 0                # its remainder, 0 .. 2^k - 1 (units 2^-k Q8)
        self._v = 0                 # filtered velocity, Q8 per refresh, |v| <= vmax
        self._vr = 0                # its remainder, 0 .. 2^kv - 1

    def _track(self, raw):
        # raw: calibrated-scale reading 0..65536, or -1 = no finger this sample.
        if raw < 0:
            if not self.touching:
                return -1
            n = self._low + 1
            if n >= self._debounce:
                self.touching = False
                self._low = 0
                return -1
            # A dropout, not (yet) a lift: dead-reckon one refresh at the
            # current velocity (the finger keeps moving: a held position would
            # trail by a step, and the next real sample would kick v).
            self._low = n
            v = self._v
            nf = self._f + v        # |.| <= qmax + vmax < 2^29
            if nf < 0:
                nf = 0
            elif nf > self._qmax:
                nf = self._qmax
            self._f = nf
        else:
            self._low = 0
            # Calibration: d in [0, span] (<= 65535), x in [0, qmax] (< 2^28).
            if self._rev:
                d = self._r0 - raw
            else:
                d = raw - self._r0
            if d < 0:
                d = 0
            elif d > self._span:
                d = self._span
            x = d * self._s_hi + ((d * self._s_lo + 8192) >> 14)
            if x > self._qmax:      # scale rounding may overshoot by <= 2 Q8 units
                x = self._qmax
            if self.touching:
                f = self._f
                # e = remainder + x - f: |e| < qmax + 2^8 < 2^29; nf in [0, qmax].
                e = self._fr + x - f
                nf = f + (e >> self._k)
                self._fr = e & self._km
                v = self._v
                # |e| < 2^8 + qmax + vmax <= 2^8 + 2 qmax < 2^29 + 2^8
                e = self._vr + (nf - f) - v
                v += e >> self._kv
                if v > self._vmax:
                    v = self._vmax
                    e = 0
                elif v < -self._vmax:
                    v = -self._vmax
                    e = 0
                self._vr = e & self._kvm
                self._f = nf
                self._v = v
            else:
                # Touch-down: re-seed, no glide from the last lift position
                # and no velocity kick from the jump.
                self.touching = True
                self._f = x
                self._fr = 0
                self._v = 0
                self._vr = 0
                nf = x
                v = 0
        # Output: f + v * lead. |v*lq8| + 128 < 2^30 by vmax, so the lead is
        # < 2^22 and p stays within +-2^29 before the clamp.
        p = nf + ((v * self._lq8 + 128) >> 8)
        if p < 0:
            p = 0
        elif p > self._qmax:
            p = self._qmax
        return (p + 128) >> 8


class AdcLinearSensor(_Tracker):
    # One ADC channel whose reading moves linearly with the finger (an optical
    # or resistive position sensor). read: zero-argument callable returning
    # read_u16 units 0..65535 (on a board a bound ADC.read_u16, stored once so
    # the refresh does not build a bound method). A reading below lift_below
    # is a no-finger sample; lift_below must lie below both calibration
    # points, or part of the display could never be reported.
    def __init__(self, read, cfg, positions, refresh_hz, compensate=True):
        self._setup(cfg, positions, refresh_hz, compensate)
        lift = _need_int(cfg, "lift_below", 0, 65535)
        lo = self._r0 - self._span if self._rev else self._r0   # lower calibration point
        if lift > lo:
            raise ValueError("sensor.lift_below: %d is above the calibration point %d "
                             "(that end of the display would read as lifted)" % (lift, lo))
        self._lift = lift
        self._read = read

    def read(self):
        raw = self._read()
        if raw < self._lift:
            return self._track(-1)
        return self._track(raw)


class AdcRatioSensor(_Tracker):
    # Two ADC channels a, b whose share a/(a+b) moves with the finger (the two
    # ends of a resistive strip, or two photodiodes): the ratio cancels supply
    # and illumination drift. The ratio is put on the read_u16 scale,
    # r = floor(65536 * a / (a+b)) in 0..65536, and raw_at_start/raw_at_end
    # are calibration points on that scale (what r reads at the display's
    # first and last position). lift_below is a threshold on a+b (0..131070):
    # little total signal = no finger; at least 1 (no division by zero).
    def __init__(self, read_a, read_b, cfg, positions, refresh_hz, compensate=True):
        self._setup(cfg, positions, refresh_hz, compensate)
        self._lift = _need_int(cfg, "lift_below", 1, 131070)
        self._read_a = read_a
        self._read_b = read_b

    def read(self):
        a = self._read_a()
        s = a + self._read_b()          # <= 131070
        if s < self._lift:
            return self._track(-1)
        # floor(a * 2^16 / s) in two exact steps: a << 16 would reach 2^32,
        # a << 14 <= 1,073,725,440 < 2^30; the remainder < s, so rem << 2 < 2^19.
        n = a << 14
        q = n // s
        return self._track((q << 2) + (((n - q * s) << 2) // s))


class ScriptedSensor:
    # Virtual board: the finger follows a script. script is either a callable
    # t_us -> position index (or -1 = lifted), or a preallocated table of
    # indices (array / list of small ints), entry i covering
    # [i*step_us, (i+1)*step_us); before 0 or past its end the finger is
    # lifted. Values are clamped to 0..positions-1; any negative is -1.
    # set_time(t_us) then read(); allocation-free when the script is.
    def __init__(self, script, positions, step_us=120):
        _check_common(positions, 1)
        if isinstance(step_us, bool) or not isinstance(step_us, int) or step_us < 1:
            raise ValueError("step_us: expected a positive integer, got %r" % (step_us,))
        self.positions = positions
        self._last = positions - 1
        self._call = callable(script)
        if not self._call:
            try:
                n = len(script)
            except TypeError:
                raise ValueError("script: expected a callable t_us -> position or a table")
            self._n = n
        else:
            self._n = 0
        self._script = script
        self._step = step_us
        self._t = 0
        self.touching = False

    def set_time(self, t_us):
        self._t = t_us

    def reset(self):
        self.touching = False

    def read(self):
        if self._call:
            p = self._script(self._t)
        else:
            t = self._t
            if t < 0:
                p = -1
            else:
                i = t // self._step
                p = self._script[i] if i < self._n else -1
        if p < 0:
            self.touching = False
            return -1
        self.touching = True
        if p > self._last:
            return self._last
        return p


def make_sensor(cfg, reads, positions, refresh_hz, compensate=True):
    """Sensor for a board's `sensor` dict. reads: sequence of zero-argument
    callables returning read_u16 units, one per entry of cfg["pins"] (kind
    "adc_linear": 1, "adc_ratio": 2). Kind "scripted" (virtual board) takes
    reads[0] as the script of ScriptedSensor."""
    kind = cfg.get("kind") if isinstance(cfg, dict) else None
    need = {"adc_linear": 1, "adc_ratio": 2, "scripted": 1}
    if kind not in need:
        raise ValueError("sensor.kind: expected adc_linear, adc_ratio or scripted, got %r" % (kind,))
    if len(reads) < need[kind]:
        raise ValueError("sensor.pins: kind %s needs %d ADC reads, got %d"
                         % (kind, need[kind], len(reads)))
    if kind == "adc_linear":
        return AdcLinearSensor(reads[0], cfg, positions, refresh_hz, compensate)
    if kind == "adc_ratio":
        return AdcRatioSensor(reads[0], reads[1], cfg, positions, refresh_hz, compensate)
    return ScriptedSensor(reads[0], positions)
