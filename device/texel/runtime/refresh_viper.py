# The fused refresh: ADC reading, sensor tracking, scene lookup, duty law and
# the PWM compare store in one viper function, refresh(), with no Python call
# inside - on an RP2040 it is the hard timer IRQ itself - so a refresh costs
# tens of microseconds on an emulated RP2040 instead of the hundreds a
# Python-level refresh (about ten calls and a hundred bytecodes) would. It computes exactly what Refresh.step with
# AdcLinearSensor, Scene.amp and DutyLaw.duty compute (tests/runtime/test_refresh_viper.py
# runs both on the same inputs and compares every refresh).
#
# Layout. Everything the refresh touches is reached from one array('I'), _W,
# holding each entry as two 32-bit halves (lo, hi): hi is 0 on 32-bit boards
# and completes the address on the 64-bit unix port (viper here can load 32-
# bit words, not machine words). _W holds: the addresses of the state array S (int32 words), the
# scene's region table and sample buffers, the duty law's fine table, the
# telemetry ring, and (rp2) the register addresses. A scene swap builds a new
# word array and replaces _W with one store: the IRQ sees the old scene or the
# new one, never a mix. The Python objects behind the addresses are kept
# referenced by FastRefresh while they are in use.
#
# Kept alone in this file: a port without a native emitter cannot compile it.
import micropython
from array import array
from micropython import const
import uctypes
from .refresh import Refresh, TELEMETRY_SLOTS
from ..gen import sine_table

# _W: word array indices
W_S = const(0)          # state S (array 'i')
W_TAB = const(1)        # scene region table (array 'i', rows start,end,kind,value + sentinel)
W_FINE = const(2)       # DutyLaw fine table (array 'H')
W_TEL_T = const(3)      # telemetry ring: time (array 'i')
W_TEL_P = const(4)      # telemetry ring: position (array 'i')
W_TEL_A = const(5)      # telemetry ring: amplitude (array 'H')
W_IDLE = const(6)       # scene idle amplitude (uint16)
W_TIMER = const(7)      # rp2: TIMERAWL register address (us counter)
W_ADC = const(8)        # rp2: ADC CS register address (RESULT follows)
W_CC = const(9)         # rp2: PWM slice CC register address
W_MUL = const(10)       # rp2: CC word = counts * MUL (leg A, and B for a bridge)
W_SINE = const(11)      # sine_table (array 'H') for plan-backed texel regions
W_NBUF = const(12)      # number of scene buffers
W_BUF0 = const(13)      # scene buffer k at W_BUF0 + k; then plan p at
                        # W_BUF0 + nbuf + 4p: t28 address, d28 address, L, gain Q14
W_FIXED = const(13)

# S: state indices (int32 words; every value non-negative and < 2^30 - the
# velocity is stored biased by V_BIAS - so 32- and 64-bit viper agree)
S_TOUCH = const(0)
S_LOW = const(1)
S_DEB = const(2)
S_F = const(3)
S_V = const(4)
S_FR = const(5)
S_VR = const(6)
S_K = const(7)
S_KM = const(8)
S_KV = const(9)
S_KVM = const(10)
S_VMAX = const(11)
S_QMAX = const(12)
S_REV = const(13)
S_R0 = const(14)
S_SPAN = const(15)
S_SHI = const(16)
S_SLO = const(17)
S_LQ8 = const(18)
S_LIFT = const(19)
S_POS1 = const(20)      # last position + 1 (0 = lifted)
S_AMP = const(21)
S_DUTY = const(22)
S_COUNT = const(23)
S_TEL_EVERY = const(24)
S_TEL_DIV = const(25)
S_TEL_HEAD = const(26)
S_Q = const(27)         # DutyLaw q
S_HALF = const(28)      # DutyLaw rounding offset
S_MAXC = const(29)      # DutyLaw max_counts
S_WORST = const(30)
S_OVR = const(31)
S_PERIOD = const(32)    # refresh period, us
S_ADC_CS = const(33)    # the word written to the ADC's CS (rp2: starts one conversion)
S_ADC12 = const(34)     # 1: RESULT is a 12-bit RP2040 reading, scaled as read_u16 does
S_SIZE = const(35)
V_BIAS = const(0x10000000)      # 2^28 > any |v| (v <= qmax < 2^28)
_SLOTS = const(256)             # = refresh.TELEMETRY_SLOTS (checked below)

_W = None


@micropython.viper
def refresh(timer) -> int:
    """The whole refresh, with no Python call: the timer IRQ itself on an
    RP2040. Reads its input from the "registers" whose addresses are in _W -
    on an RP2040 the real TIMERAWL, ADC CS/RESULT and the slice's CC; on other
    boards three small arrays that FastRefresh.step fills and reads - tracks
    the finger, looks the scene up, applies the duty law, writes the CC word
    and returns the duty (PWM counts). timer: the Timer object (unused)."""
    w = ptr32(_W)
    s = ptr32((int(w[W_S * 2]) | ((int(w[W_S * 2 + 1]) << 16) << 16)))
    clock = ptr32(int(w[W_TIMER * 2]) | ((int(w[W_TIMER * 2 + 1]) << 16) << 16))
    t0 = int(clock[0])
    adc = ptr32(int(w[W_ADC * 2]) | ((int(w[W_ADC * 2 + 1]) << 16) << 16))
    adc[0] = s[S_ADC_CS]                    # rp2: EN | START_ONCE | AINSEL
    while (int(adc[0]) & 0x100) == 0:       # READY after ~2 us
        pass
    raw = int(adc[1])
    if int(s[S_ADC12]):
        raw = raw & 0xFFF
        raw = (raw << 4) | (raw >> 8)       # read_u16 scaling of a 12-bit result
    t = t0 & 0x3FFFFFFF
    # --- sensor: AdcLinearSensor.read + _Tracker._track ---------------------
    p = -1
    if raw < int(s[S_LIFT]):
        if int(s[S_TOUCH]):
            n = int(s[S_LOW]) + 1
            if n >= int(s[S_DEB]):
                s[S_TOUCH] = 0
                s[S_LOW] = 0
            else:
                # a dropout: dead-reckon one refresh at the current velocity
                s[S_LOW] = n
                v = int(s[S_V]) - V_BIAS
                nf = int(s[S_F]) + v
                if nf < 0:
                    nf = 0
                elif nf > int(s[S_QMAX]):
                    nf = int(s[S_QMAX])
                s[S_F] = nf
                p = nf + ((v * int(s[S_LQ8]) + 128) >> 8)
    else:
        s[S_LOW] = 0
        if int(s[S_REV]):
            d = int(s[S_R0]) - raw
        else:
            d = raw - int(s[S_R0])
        if d < 0:
            d = 0
        elif d > int(s[S_SPAN]):
            d = int(s[S_SPAN])
        x = d * int(s[S_SHI]) + ((d * int(s[S_SLO]) + 8192) >> 14)
        if x > int(s[S_QMAX]):
            x = int(s[S_QMAX])
        if int(s[S_TOUCH]):
            f = int(s[S_F])
            e = int(s[S_FR]) + x - f
            nf = f + (e >> int(s[S_K]))
            s[S_FR] = e & int(s[S_KM])
            v = int(s[S_V]) - V_BIAS
            e = int(s[S_VR]) + (nf - f) - v
            v += e >> int(s[S_KV])
            vmax = int(s[S_VMAX])
            if v > vmax:
                v = vmax
                e = 0
            elif v < 0 - vmax:
                v = 0 - vmax
                e = 0
            s[S_VR] = e & int(s[S_KVM])
            s[S_F] = nf
            s[S_V] = v + V_BIAS
        else:
            # touch-down: re-seed, no glide and no velocity kick
            s[S_TOUCH] = 1
            s[S_F] = x
            s[S_FR] = 0
            s[S_V] = V_BIAS
            s[S_VR] = 0
            nf = x
            v = 0
        p = nf + ((v * int(s[S_LQ8]) + 128) >> 8)
    if p >= 0 or int(s[S_TOUCH]):
        if p < 0:
            p = 0
        elif p > int(s[S_QMAX]):
            p = int(s[S_QMAX])
        p = (p + 128) >> 8
    # --- scene: Scene.amp ----------------------------------------------------
    if p < 0:
        amp = int(w[W_IDLE * 2])
    else:
        tab = ptr32((int(w[W_TAB * 2]) | ((int(w[W_TAB * 2 + 1]) << 16) << 16)))
        i = 1
        while p >= int(tab[i]):
            i += 4
        st = int(tab[i - 1])
        if p < st:
            amp = int(w[W_IDLE * 2])
        elif int(tab[i + 1]) == 1:
            amp = int(ptr16((int(w[(W_BUF0 + int(tab[i + 2])) * 2]) | ((int(w[(W_BUF0 + int(tab[i + 2])) * 2 + 1]) << 16) << 16)))[p - st])
        elif int(tab[i + 1]) == 0:
            amp = int(tab[i + 2])
        elif int(tab[i + 1]) == 3:
            # an uploaded map in chunks (scene.K_CHUNK): the buffer's word is
            # the address of its chunk-address table (lo, hi pairs)
            o = p - st
            ct = ptr32(int(w[(W_BUF0 + int(tab[i + 2])) * 2]) | ((int(w[(W_BUF0 + int(tab[i + 2])) * 2 + 1]) << 16) << 16))
            c = (o >> 9) * 2            # scene.CHUNK_BITS, CHUNK_MASK (checked below)
            amp = int(ptr16(int(ct[c]) | ((int(ct[c + 1]) << 16) << 16))[o & 511])
        else:
            # plan-backed texel region: engine_int's sample, as Scene.amp
            b = W_BUF0 + int(w[W_NBUF * 2]) + 4 * int(tab[i + 2])
            o = p - st
            ln = int(w[(b + 2) * 2])
            j = o // ln
            k = o - j * ln + 1
            # k*d wraps at the machine word on 32-bit ports: the low 28 bits,
            # all that is kept, are exact either way
            t28 = ptr32(int(w[b * 2]) | ((int(w[b * 2 + 1]) << 16) << 16))
            d28 = ptr32(int(w[(b + 1) * 2]) | ((int(w[(b + 1) * 2 + 1]) << 16) << 16))
            ph = (int(t28[j]) + k * int(d28[j])) & 0x0FFFFFFF
            sine = ptr16(int(w[W_SINE * 2]) | ((int(w[W_SINE * 2 + 1]) << 16) << 16))
            ii = ph >> 18
            y0 = int(sine[ii])
            v = y0 + (((int(sine[ii + 1]) - y0) * ((ph >> 2) & 0xFFFF) + 32768) >> 16)
            amp = (v * int(w[(b + 3) * 2]) + 8192) >> 14
    # --- duty: DutyLaw.duty ----------------------------------------------------
    fine = ptr16((int(w[W_FINE * 2]) | ((int(w[W_FINE * 2 + 1]) << 16) << 16)))
    j = amp >> 6
    lo = int(fine[j])
    dc = (lo + (((int(fine[j + 1]) - lo) * (amp & 63)) >> 6) + int(s[S_HALF])) >> int(s[S_Q])
    if dc > int(s[S_MAXC]):
        dc = int(s[S_MAXC])
    # --- bookkeeping and telemetry ------------------------------------------------
    s[S_POS1] = p + 1
    s[S_AMP] = amp
    s[S_DUTY] = dc
    s[S_COUNT] = (int(s[S_COUNT]) + 1) & 0x3FFFFFFF
    every = int(s[S_TEL_EVERY])
    if every:
        n = int(s[S_TEL_DIV]) + 1
        if n >= every:
            n = 0
            h = int(s[S_TEL_HEAD])
            k = h & (_SLOTS - 1)
            ptr32((int(w[W_TEL_T * 2]) | ((int(w[W_TEL_T * 2 + 1]) << 16) << 16)))[k] = t
            ptr32((int(w[W_TEL_P * 2]) | ((int(w[W_TEL_P * 2 + 1]) << 16) << 16)))[k] = p
            ptr16((int(w[W_TEL_A * 2]) | ((int(w[W_TEL_A * 2 + 1]) << 16) << 16)))[k] = amp
            s[S_TEL_HEAD] = (h + 1) & 0x3FFFFFFF
        s[S_TEL_DIV] = n
    ptr32(int(w[W_CC * 2]) | ((int(w[W_CC * 2 + 1]) << 16) << 16))[0] = dc * int(w[W_MUL * 2])
    dt = int(clock[0]) - t0
    if dt > int(s[S_WORST]):
        s[S_WORST] = dt
    if dt > int(s[S_PERIOD]):
        s[S_OVR] = (int(s[S_OVR]) + 1) & 0x3FFFFFFF
    return dc


irq_rp2 = refresh       # the name app.py gives the timer on an RP2040


def _state(i, bias=0):
    # a Refresh attribute kept in S[i] (stored + bias: positions may be -1)
    def get(self):
        return self._S[i] - bias

    def put(self, v):
        self._S[i] = v + bias
    return property(get, put)


_RP2_TIMERAWL = const(0x40054028)
_RP2_ADC_CS = const(0x4004C000)


class FastRefresh(Refresh):
    """Refresh with the fused viper core: same attributes and telemetry API,
    state kept in S (read back through properties for status())."""

    def __init__(self, sensor, law, set_duty, read, ticks_us, ticks_diff, period_us,
                 idle_amp=0, cost_ticks=None):
        self._S = array("i", bytes(4 * S_SIZE))
        self._keep = None
        self._prev = None
        # True when the refresh may run in another thread (the unix port's
        # real-time virtual board): the previous scene is kept one swap longer
        self.threaded = False
        Refresh.__init__(self, sensor, law, set_duty, ticks_us, ticks_diff, period_us,
                         idle_amp, cost_ticks)
        S = self._S
        sn = sensor
        S[S_DEB] = sn._debounce
        S[S_K] = sn._k
        S[S_KM] = sn._km
        S[S_KV] = sn._kv
        S[S_KVM] = sn._kvm
        S[S_VMAX] = sn._vmax
        S[S_QMAX] = sn._qmax
        S[S_REV] = 1 if sn._rev else 0
        S[S_R0] = sn._r0
        S[S_SPAN] = sn._span
        S[S_SHI] = sn._s_hi
        S[S_SLO] = sn._s_lo
        S[S_LQ8] = sn._lq8
        S[S_LIFT] = sn._lift
        S[S_V] = V_BIAS
        S[S_Q] = law.q
        S[S_HALF] = law._half
        S[S_MAXC] = law.max_counts
        S[S_PERIOD] = period_us
        self._read = read
        # the generic path's "registers": a clock word, an ADC (CS with READY
        # always set, RESULT = the raw read_u16 value) and a CC word (MUL 1)
        self._clk = array("I", [0])
        self._adc = array("I", [0x100, 0])
        self._cc = array("I", [0])
        S[S_ADC_CS] = 0x100
        S[S_ADC12] = 0
        self._regs = (uctypes.addressof(self._clk), uctypes.addressof(self._adc),
                      uctypes.addressof(self._cc), 1)
        self._install(None)

    def use_rp2_registers(self, cc_addr, mul, adc_channel, timer_addr=_RP2_TIMERAWL,
                          adc_addr=_RP2_ADC_CS):
        """Let irq_rp2 drive the hardware directly (RP2040)."""
        self._S[S_ADC_CS] = 1 | 4 | (adc_channel << 12)
        self._S[S_ADC12] = 1
        self._regs = (timer_addr, adc_addr, cc_addr, mul)
        self._install(self.scene)

    def _install(self, scene):
        global _W
        bufs = scene.buffers() if scene is not None else ()
        plans = scene.plans() if scene is not None else ()
        words = array("I", [0] * (2 * (W_FIXED + len(bufs) + 4 * len(plans))))

        def put(k, v):
            words[2 * k] = v & 0xFFFFFFFF
            words[2 * k + 1] = (v >> 16) >> 16

        if scene is None:
            tab = _EMPTY_TABLE
            put(W_IDLE, self.idle_amp)
        else:
            tab = scene._t
            put(W_IDLE, scene.idle)
        put(W_S, uctypes.addressof(self._S))
        put(W_TAB, uctypes.addressof(tab))
        put(W_FINE, uctypes.addressof(self.law._fine))
        put(W_TEL_T, uctypes.addressof(self.tel_t))
        put(W_TEL_P, uctypes.addressof(self.tel_pos))
        put(W_TEL_A, uctypes.addressof(self.tel_amp))
        for k in range(4):
            put(W_TIMER + k, self._regs[k])
        chunked = []
        for k in range(len(bufs)):
            b = bufs[k]
            if isinstance(b, tuple):    # scene.K_CHUNK: a table of its chunks' addresses
                ct = array("I", [0] * (2 * len(b)))
                for c in range(len(b)):
                    a = uctypes.addressof(b[c])
                    ct[2 * c] = a & 0xFFFFFFFF
                    ct[2 * c + 1] = (a >> 16) >> 16
                chunked.append(ct)
                b = ct
            put(W_BUF0 + k, uctypes.addressof(b))
        put(W_SINE, uctypes.addressof(sine_table.table()))
        put(W_NBUF, len(bufs))
        for k in range(len(plans)):
            b = W_BUF0 + len(bufs) + 4 * k
            t28, d28, ln, g = plans[k]
            put(b, uctypes.addressof(t28))
            put(b + 1, uctypes.addressof(d28))
            put(b + 2, ln)
            put(b + 3, g)
        keep = (words, scene, tab, chunked)
        # The previous generation stays referenced until the next swap: the
        # viper refresh holds raw addresses the GC cannot see, and on a port
        # with real threads (the unix port's realtime virtual board) a refresh
        # may still be reading the old scene just after this store.
        self._prev = self._keep
        self._keep = keep               # referenced before the IRQ can see them
        if not self.threaded:
            # a hard IRQ (rp2, stm32) runs to its end before this code goes on:
            # once _W is stored no refresh can still read the old scene, whose
            # buffers go now (on a Pico, keeping a full-screen upload one swap
            # longer left no room for the next: measured on the emulated Pico)
            self._prev = None
        _W = words                      # the swap: one store
        return self._prev

    def swap(self, scene):
        old = self.scene
        self._install(scene)
        self.scene = scene
        return old

    def step(self, _timer=None):
        c0 = self.cost_ticks()
        self._clk[0] = self.ticks_us() & 0x3FFFFFFF
        self._adc[1] = self._read()
        refresh(None)
        self.set_duty(self._cc[0])
        dt = self.ticks_diff(self.cost_ticks(), c0)
        S = self._S
        if dt > S[S_WORST]:
            S[S_WORST] = dt
        if dt > self.period_us:
            S[S_OVR] = (S[S_OVR] + 1) & 0x3FFFFFFF

    # Refresh's attributes, backed by S (read by status() and telemetry)
    count = _state(S_COUNT)
    amp = _state(S_AMP)
    duty = _state(S_DUTY)
    worst_us = _state(S_WORST)
    overruns = _state(S_OVR)
    tel_every = _state(S_TEL_EVERY)
    tel_div = _state(S_TEL_DIV)
    tel_head = _state(S_TEL_HEAD)
    pos = _state(S_POS1, 1)


from .scene import CHUNK_BITS as _CB, CHUNK_MASK as _CM
if _CB != 9 or _CM != 511:
    raise ImportError("refresh_viper: scene chunk size differs from the literals in refresh()")
if TELEMETRY_SLOTS != _SLOTS:
    raise ImportError("refresh_viper: telemetry ring size differs from refresh.py")

# a scene-less table: the sentinel row alone (every position is a gap)
_EMPTY_TABLE = array("i", [0x3FFFFFFF, 0x3FFFFFFF, 0, 0])
