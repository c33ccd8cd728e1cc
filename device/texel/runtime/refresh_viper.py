# The fused refresh: ADC reading, sensor tracking, scene lookup, duty law and
# the PWM compare store in one viper function, core(), with no Python call
# inside. On an RP2040 it is the refresh interrupt itself: hw/rp2.py points the
# PWM-wrap vector at a 12-instruction Thumb trampoline that calls core()'s
# machine code directly (irq_rp2.native_entry), so neither machine.Timer's
# alarm pool nor MicroPython's IRQ dispatch runs per refresh: 8.1 us per
# refresh over a map and 10.3 us over a texel plan on the emulated RP2040,
# IRQ entry and exit included, against 21.1 and 24.1 us through a hard
# machine.Timer (`texelpad bench-refresh --chip rp2040`, docs/runtime.md).
# It computes exactly what Refresh.step with AdcLinearSensor, Scene.amp and
# DutyLaw.duty compute (tests/runtime/test_refresh_viper.py runs both on the
# same inputs and compares every refresh). Its Python side - FastRefresh,
# the swap, irq_rp2 - is refresh_fast.py, which runs the C core's twin of core()
# instead where the board has it and then never loads this module.
#
# Layout. Everything the refresh touches is reached from one array('I'), the
# word array W (indices below): the state array S (int32 words), the scene's
# region table (core()'s copy) and sample buffers or plans, the duty law's
# fine table, the telemetry ring and (rp2) the registers, each as a 32-bit
# offset from BASE, the lowest of those addresses, kept as two 32-bit halves
# (viper here loads 32-bit words, not machine words: the high half is 0 on
# 32-bit boards and completes the addresses on the 64-bit unix port). core(w)
# gets W's address as its one argument and reads no global, so it has no
# exception frame, no globals swap and no global lookup (viper adds them to a
# function that reads a global: ~250 cycles, 2 us, per call on the emulated
# RP2040, measured with rp2emu's --profile). A scene
# swap builds a new W and publishes its address with one store (_WA for
# refresh(), _ARGS[0] for the trampoline): the refresh sees the old scene or
# the new one, never a mix. The Python objects behind the addresses are kept
# referenced by FastRefresh while they are in use.
#
# Speed on Thumb-1 (armv6m, as mpy-cross compiles it): viper keeps only two
# locals in registers (r4, r5: the argument w and the first local, s); the
# rest live on the stack, so the body reads each value it needs once, and S
# words used in every refresh sit below index 32 (an immediate-offset load).
#
# Kept alone in this file: a port without a native emitter cannot compile it.
import micropython
from micropython import const
from . import refresh_fast as _f

# W: word array indices, one 32-bit word each. Addresses are kept as offsets
# from BASE (words 0 and 1: its low and high halves), so every offset is one
# non-negative word and an address costs core() one load and one add instead
# of rebuilding 64 bits from two halves: BASE is 0 on a 32-bit board (W holds
# the addresses) and the lowest address the refresh uses on a 64-bit port
# (refresh_fast._resolve).
W_BASE = const(0)       # 2 words
W_S = const(2)          # state S (array 'i')
W_TAB = const(3)        # scene region table (array 'i', rows start,end,kind,value + sentinel)
W_FINE = const(4)       # DutyLaw fine table (array 'H')
W_TEL_T = const(5)      # telemetry ring: time (array 'i')
W_TEL_P = const(6)      # telemetry ring: position (array 'i')
W_TEL_A = const(7)      # telemetry ring: amplitude (array 'H')
W_IDLE = const(8)       # scene idle amplitude (uint16; a value, not an address)
W_TIMER = const(9)      # rp2: TIMERAWL register (us counter)
W_ADC = const(10)       # rp2: ADC CS register (RESULT follows)
W_CC = const(11)        # rp2: PWM slice CC register
W_MUL = const(12)       # rp2: CC word = counts * MUL (leg A, and B for a bridge; a value)
W_SINE = const(13)      # sine_table (array 'H') for plan-backed texel regions
W_ROW = const(14)       # the C core's own (its last table row); core() ignores it
W_BUF0 = const(15)      # scene buffer k at W_BUF0 + k (scene.K_CHUNK: its chunk-offset
                        # table); then plan p at W_BUF0 + nbuf + W_PLAN*p: t28, d28,
                        # L, gain Q14, R = 65536 // L + 1 (see the texel branch), or a
                        # few samples' 5 words (kinds/samples.py plan(): the value's
                        # address, then its numbers as they are)
W_FIXED = const(15)
W_PLAN = const(5)

# S: state indices (int32 words; every value non-negative and < 2^30 - the
# velocity is stored biased by V_BIAS - so 32- and 64-bit viper agree). The
# words every refresh reads come first: indices below 32 are one Thumb load.
S_TOUCH = const(0)
S_LOW = const(1)
S_ADC12 = const(2)      # 1: RESULT is a 12-bit RP2040 reading, scaled as read_u16 does
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
S_Q = const(25)         # DutyLaw q
S_HALF = const(26)      # DutyLaw rounding offset
S_MAXC = const(27)      # DutyLaw max_counts
S_WORST = const(28)
S_OVR = const(29)
S_PERIOD = const(30)    # refresh period, us
S_ADC_CS = const(31)    # the word written to the ADC's CS (rp2: starts one conversion)
S_DEB = const(32)       # lift debounce (read only when the finger lifts)
S_TEL_DIV = const(33)
S_TEL_HEAD = const(34)
S_SIZE = const(35)
V_BIAS = const(0x10000000)      # 2^28 > any |v| (v <= qmax < 2^28)
_SLOTS = const(256)             # = refresh.TELEMETRY_SLOTS (checked below)
_FAST_O = const(32768)          # offsets below this divide by reciprocal (texel branch)

_W = None               # the word array in use, kept current by refresh_fast (_viper_loaded)
_WA = 0                 # its address: core()'s argument from refresh()


@micropython.viper
def core(w: int):
    """The whole refresh, with no Python call. w: the word array W's address
    (an int: the cheapest argument to convert on entry; every use casts it
    with ptr32(w), which costs nothing). Reads its input from the "registers"
    in W - on an RP2040 the real TIMERAWL, ADC CS/RESULT and the slice's CC;
    on other boards three small arrays that FastRefresh.step fills and reads -
    tracks the finger, looks the scene up, applies the duty law and writes the
    CC word. Range checks of the common path are single unsigned compares
    (uint(d) > uint(span) is d < 0 or d > span): each viper comparison costs
    ~15 cycles on Thumb-1."""
    s = ptr32((int(ptr32(w)[W_BASE]) | ((int(ptr32(w)[W_BASE + 1]) << 16) << 16))
              + int(ptr32(w)[W_S]))
    base = int(s) - int(ptr32(w)[W_S])
    adc = ptr32(base + int(ptr32(w)[W_ADC]))
    cs = int(s[S_ADC_CS])                   # rp2: EN | START_ONCE | AINSEL (or START_MANY)
    if not (cs & 24):
        adc[0] = cs                         # start one conversion
    # while the conversion runs (2 us on an RP2040), what does not need it
    clock = ptr32(base + int(ptr32(w)[W_TIMER]))
    t0 = int(clock[0])
    touch = int(s[S_TOUCH])
    if cs & 16:
        # STM32 (hw/stm32_irq.py): adc is ADC1's registers; DR (word 19)
        # holds the conversion the refresh before started, then CR2 (word 2) gets
        # ADON | SWSTART for the next one: no wait (~1.5 us to convert, 120 between)
        raw = int(adc[19]) & 0xFFF
        sw = 1                              # (a literal 1 << 30 would fold to a long int)
        adc[2] = int(adc[2]) | 1 | (sw << 30)
    elif cs & 8:
        # START_MANY (the RP2040's refresh interrupt, irq_rp2.native_entry):
        # the ADC converts continuously and RESULT is its last conversion, at
        # most one conversion (2 us) old: no wait. Other code that used the
        # ADC (machine.ADC on another channel, adc_init) changed CS: convert
        # once, then let it run again.
        raw = int(adc[1])
        if (int(adc[0]) & 0x1F700F) != cs:
            adc[0] = (cs ^ 8) | 4
            while (int(adc[0]) & 0x100) == 0:
                pass
            raw = int(adc[1])
            adc[0] = cs
    else:
        while (int(adc[0]) & 0x100) == 0:   # READY after ~2 us
            pass
        raw = int(adc[1])
    if int(s[S_ADC12]):
        # read_u16 scaling of the RP2040's 12-bit RESULT (bits 31:12 read 0)
        raw = (raw << 4) | (raw >> 8)
    # --- sensor: AdcLinearSensor.read + _Tracker._track ---------------------
    p = -1
    if raw < int(s[S_LIFT]):
        if touch:
            n = int(s[S_LOW]) + 1
            if n >= int(s[S_DEB]):
                touch = 0
                s[S_TOUCH] = 0
                s[S_LOW] = 0
            else:
                # a dropout: dead-reckon one refresh at the current velocity
                s[S_LOW] = n
                v = int(s[S_V]) - V_BIAS
                nf = int(s[S_F]) + v
                if uint(nf) > uint(s[S_QMAX]):
                    nf = 0 if nf < 0 else int(s[S_QMAX])
                s[S_F] = nf
                p = nf + ((v * int(s[S_LQ8]) + 128) >> 8)
    else:
        s[S_LOW] = 0
        d = raw - int(s[S_R0])
        if int(s[S_REV]):
            d = 0 - d
        if uint(d) > uint(s[S_SPAN]):
            d = 0 if d < 0 else int(s[S_SPAN])
        x = d * int(s[S_SHI]) + ((d * int(s[S_SLO]) + 8192) >> 14)
        if x > int(s[S_QMAX]):
            x = int(s[S_QMAX])
        if touch:
            f = int(s[S_F])
            e = int(s[S_FR]) + x - f
            nf = f + (e >> int(s[S_K]))
            s[S_FR] = e & int(s[S_KM])
            v = int(s[S_V]) - V_BIAS
            e = int(s[S_VR]) + (nf - f) - v
            v += e >> int(s[S_KV])
            if uint(v + int(s[S_VMAX])) > uint(int(s[S_VMAX]) << 1):
                v = int(s[S_VMAX]) if v > 0 else 0 - int(s[S_VMAX])
                e = 0
            s[S_VR] = e & int(s[S_KVM])
            s[S_F] = nf
            s[S_V] = v + V_BIAS
        else:
            # touch-down: re-seed, no glide and no velocity kick
            touch = 1
            s[S_TOUCH] = 1
            s[S_F] = x
            s[S_FR] = 0
            s[S_V] = V_BIAS
            s[S_VR] = 0
            nf = x
            v = 0
        p = nf + ((v * int(s[S_LQ8]) + 128) >> 8)
    # --- scene: Scene.amp ----------------------------------------------------
    if touch:                               # p is -1 exactly when not touching
        if uint(p) > uint(s[S_QMAX]):
            p = 0 if p < 0 else int(s[S_QMAX])
        p = (p + 128) >> 8
        tab = ptr32(base + int(ptr32(w)[W_TAB]))
        i = 1
        while p >= int(tab[i]):
            i += 4
        st = int(tab[i - 1])
        kind = int(tab[i + 1])
        if p < st:
            amp = int(ptr32(w)[W_IDLE])
        elif kind == 2:
            # scene.K_PLAN, a texel region played from its plan: engine_int's
            # sample, as Scene.amp (tested first: the costliest kind)
            b = int(tab[i + 2])                 # the plan's first word in W
            o = p - st
            ln = int(ptr32(w)[b + 2])
            if o < _FAST_O:
                # o // ln by reciprocal: R = 65536 // ln + 1 > 2^16/ln, so
                # j = o*R >> 16 is floor(o/ln) or one more (o*(R - 2^16/ln)
                # < o/2^16 < 0.5), corrected below; o*R < 2^15 * 13,108 < 2^29
                j = (o * int(ptr32(w)[b + 4])) >> 16
                k = o - j * ln
                if k < 0:
                    j -= 1
                    k += ln
            else:
                j = o // ln
                k = o - j * ln
            # k*d wraps at the machine word on 32-bit ports: the low 28 bits,
            # all that is kept, are exact either way
            ph = (int(ptr32(base + int(ptr32(w)[b]))[j])
                  + (k + 1) * int(ptr32(base + int(ptr32(w)[b + 1]))[j])) & 0x0FFFFFFF
            sine = ptr16(base + int(ptr32(w)[W_SINE]))
            ii = ph >> 18
            y0 = int(sine[ii])
            v = y0 + (((int(sine[ii + 1]) - y0) * ((ph >> 2) & 0xFFFF) + 32768) >> 16)
            amp = (v * int(ptr32(w)[b + 3]) + 8192) >> 14
        elif kind == 1:
            amp = int(ptr16(base + int(tab[i + 2]))[p - st])
        elif kind == 0:
            amp = int(tab[i + 2])
        elif kind == 3:
            # scene.K_CHUNK, an uploaded map in chunks: the row's value is
            # the offset of its chunk-offset table
            o = p - st
            ct = ptr32(base + int(tab[i + 2]))
            # scene.CHUNK_BITS, CHUNK_MASK (checked below)
            amp = int(ptr16(base + int(ct[o >> 9]))[o & 511])
        elif kind == 4:
            # scene.K_TILE, a few samples tiled: vals[o mod m] (kinds/samples.py
            # plan(): vals, m, R = 65536 // m + 1), the mod as the texel branch's
            b = int(tab[i + 2])
            o = p - st
            m = int(ptr32(w)[b + 1])
            if o < _FAST_O:
                k = o - ((o * int(ptr32(w)[b + 2])) >> 16) * m
                if k < 0:
                    k += m
            else:
                k = o % m
            amp = int(ptr16(base + int(ptr32(w)[b]))[k])
        else:
            # scene.K_STRETCH, a few samples stretched (plan(): vals, A, B, n - 1):
            # q = floor(o*(m-1)*2^15 / (n-1)), its value and 15-bit fraction
            b = int(tab[i + 2])
            o = p - st
            q = o * int(ptr32(w)[b + 1]) + (o * int(ptr32(w)[b + 2])) // int(ptr32(w)[b + 3])
            vals = ptr16(base + int(ptr32(w)[b]))
            k = q >> 15
            v = int(vals[k])
            amp = v + (((int(vals[k + 1]) - v) * (((q & 0x7FFF) + 1) >> 1) + 8192) >> 14)
    else:
        amp = int(ptr32(w)[W_IDLE])
    # --- duty: DutyLaw.duty ----------------------------------------------------
    fine = ptr16(base + int(ptr32(w)[W_FINE]))
    j = amp >> 6
    lo = int(fine[j])
    dc = (lo + (((int(fine[j + 1]) - lo) * (amp & 63)) >> 6) + int(s[S_HALF])) >> int(s[S_Q])
    if dc > int(s[S_MAXC]):
        dc = int(s[S_MAXC])
    ptr32(base + int(ptr32(w)[W_CC]))[0] = dc * int(ptr32(w)[W_MUL])
    # --- bookkeeping and telemetry ------------------------------------------------
    s[S_POS1] = p + 1
    s[S_AMP] = amp
    s[S_DUTY] = dc
    s[S_COUNT] = (int(s[S_COUNT]) + 1) & 0x3FFFFFFF
    if int(s[S_TEL_EVERY]):
        n = int(s[S_TEL_DIV]) + 1
        if n >= int(s[S_TEL_EVERY]):
            n = 0
            h = int(s[S_TEL_HEAD])
            k = h & (_SLOTS - 1)
            ptr32(base + int(ptr32(w)[W_TEL_T]))[k] = t0 & 0x3FFFFFFF
            ptr32(base + int(ptr32(w)[W_TEL_P]))[k] = p
            ptr16(base + int(ptr32(w)[W_TEL_A]))[k] = amp
            s[S_TEL_HEAD] = (h + 1) & 0x3FFFFFFF
        s[S_TEL_DIV] = n
    dt = int(clock[0]) - t0
    if dt > int(s[S_WORST]):
        s[S_WORST] = dt
    if dt > int(s[S_PERIOD]):
        s[S_OVR] = (int(s[S_OVR]) + 1) & 0x3FFFFFFF


@micropython.viper
def refresh(timer) -> int:
    """One refresh (core() on the word array in use); returns the duty (PWM
    counts). timer: the Timer object when machine.Timer calls it (unused)."""
    core(_WA)
    w = ptr32(_WA)
    s = ptr32((int(w[W_BASE]) | ((int(w[W_BASE + 1]) << 16) << 16)) + int(w[W_S]))
    return int(s[S_DUTY])


@micropython.viper
def _word(a: int) -> int:
    return int(ptr32(a)[0])


# FastRefresh and irq_rp2 live in refresh_fast.py (a board with the C refresh never
# loads this module); named here too for the benches and tests that import them so
FastRefresh = _f.FastRefresh
irq_rp2 = _f.irq_rp2
_ARGS = _f._ARGS
_EMPTY_TABLE = _f._EMPTY_TABLE
_c_core = _f._c_core
_start_many_is_reset = _f._start_many_is_reset
_resolve = _f._resolve

# the layout, compiled into core() as literals, is refresh_fast's
for _n in ("W_BASE", "W_S", "W_TAB", "W_FINE", "W_TEL_T", "W_TEL_P", "W_TEL_A", "W_IDLE",
           "W_TIMER", "W_ADC", "W_CC", "W_MUL", "W_SINE", "W_ROW", "W_BUF0", "W_FIXED", "W_PLAN",
           "S_TOUCH", "S_LOW", "S_ADC12", "S_F", "S_V", "S_FR", "S_VR", "S_K", "S_KM", "S_KV",
           "S_KVM", "S_VMAX", "S_QMAX", "S_REV", "S_R0", "S_SPAN", "S_SHI", "S_SLO", "S_LQ8",
           "S_LIFT", "S_POS1", "S_AMP", "S_DUTY", "S_COUNT", "S_TEL_EVERY", "S_Q", "S_HALF",
           "S_MAXC", "S_WORST", "S_OVR", "S_PERIOD", "S_ADC_CS", "S_DEB", "S_TEL_DIV",
           "S_TEL_HEAD", "S_SIZE", "V_BIAS"):
    if globals()[_n] != getattr(_f, _n):
        raise ImportError("refresh_viper: %s differs from refresh_fast.py's" % _n)
if _SLOTS != _f.TELEMETRY_SLOTS:
    raise ImportError("refresh_viper: telemetry ring size differs from refresh.py")
_f._viper_loaded(globals())
