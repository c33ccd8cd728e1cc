# The fused refresh's Python side: FastRefresh (the scene swap, the word array W
# and the state S every refresh reads, telemetry, status) and irq_rp2 (the RP2040's
# refresh interrupt). The refresh itself is machine code that reads only W: the C
# core's (device/cmod/texelcore/refresh_core.c: the texelpad firmware's module,
# or the native module texelpad deploy installs) where the board has it, else
# refresh_viper.core(), the same computation in viper (tests/gen/test_texel_core.py
# compares them word for word). Apart from refresh_viper.py so that a board with
# the C refresh never loads the viper code: on the texelpad firmware that code is
# copied into RAM at import (host/texelpad/firmware/romfs.py RAM_MODULES), 8.2 KB
# of the heap measured on the emulated Pico; on a stock Pico its bytecode and
# machine code are RAM too. The layout below (W, S) is refresh_viper.py's, which
# keeps its own compile-time copy and checks it against this one at import.
from array import array
from micropython import const
import uctypes
from .refresh import Refresh, TELEMETRY_SLOTS
from ..gen import sine_table

# W: word array indices, one 32-bit word each. Addresses are kept as offsets
# from BASE (words 0 and 1: its low and high halves), so every offset is one
# non-negative word and an address costs core() one load and one add instead
# of rebuilding 64 bits from two halves. On a 32-bit board BASE is 0 - every
# address fits a word, and W holds the addresses themselves: the C core's
# 32-bit build (refresh_core.c tc_base) relies on it and adds nothing; on a
# 64-bit port it is the lowest address the refresh uses (_resolve).
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
W_ROW = const(14)       # the C core's own: the table row the finger was in, in bytes
                        # from the table's start (0 at a swap: a new W); viper ignores it
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

_W = None               # the word array in use (kept referenced here too)
_WA = 0                 # its address: core()'s argument
_S = None               # the state array of the FastRefresh that published _W
# core()'s argument as the RP2040 trampoline passes it: one word holding W's
# address as a MicroPython small-int object ((address << 1) | 1; SRAM
# addresses are below 2^30). Updated with one 32-bit store at each swap.
_ARGS = array("I", [1])
# ... written through a native uint32 field: one 32-bit store whatever the value
# (an array('I') store of a big int - any SRAM address << 1 is above 2^30 - goes
# through mpz_as_bytes, a byte at a time: the interrupt could read a torn address)
_ARGV = uctypes.struct(uctypes.addressof(_ARGS), {"w": uctypes.UINT32 | 0}, uctypes.NATIVE)
_RP2 = None             # the FastRefresh that use_rp2_registers() set up (irq_rp2's)
_VG = None              # refresh_viper's globals once it is loaded (its refresh() reads _WA)
_CORE = None            # (the C core, None) or (None, refresh_viper.core): _engine()


def _viper():
    """refresh_viper, imported at its first use (a port with a native emitter)."""
    from . import refresh_viper
    return refresh_viper


def _engine():
    """(C core, viper core) with exactly one set: what runs a refresh on W."""
    global _CORE
    if _CORE is None:
        c = _c_core()
        _CORE = (c, None) if c is not None else (None, _viper().core)
    return _CORE


def _viper_loaded(g):
    """refresh_viper's import hands its globals here: its refresh() reads
    _W and _WA from them (kept current by every swap)."""
    global _VG
    _VG = g
    g["_W"] = _W
    g["_WA"] = _WA


class _Rp2Irq:
    """irq_rp2: the fused refresh as the RP2040's refresh interrupt. Called
    (machine.Timer's hard callback, tests) it runs one refresh; hw/rp2.py's
    Hw.start() asks native_entry() instead and makes the PWM-wrap interrupt
    call core()'s machine code itself - or the C core's (engine: which)."""

    engine = None

    def __call__(self, timer):
        c, v = _engine()
        if c is not None:
            c.refresh(_W)
        else:
            v(_WA)
        return _S[S_DUTY]

    def native_entry(self):
        """(function object address, its machine code address, address of its
        one-word argument array): what a Thumb trampoline passes to call
        core(W) as MicroPython's native calling convention has it - r0 the
        function object, r1 = 1 argument, r2 = 0 keywords, r3 the arguments.
        The refresh that use_rp2_registers() set up switches its ADC to
        free-running conversions (START_MANY).
        The code address is the function object's fourth word
        (py/objfun.h mp_obj_fun_bc_t.bytecode: a viper function's machine
        code); hw/rp2.py checks it before use."""
        if _RP2 is not None and _start_many_is_reset():
            # the ADC converts continuously from now on (core()'s START_MANY
            # branch): the refresh takes the last conversion instead of
            # starting one and waiting 2 us for it
            S = _RP2._S
            S[S_ADC_CS] = (S[S_ADC_CS] & ~4) | 8
        c = _c_core()
        if c is not None:
            # the C core's refresh (device/cmod/texelcore/refresh_core.c:
            # refresh_viper.core() in C, on the same W; in RAM on the firmware),
            # called the same way: the trampoline's function object (this one,
            # in SRAM) goes unused
            self.engine = "c"
            return id(self), c.refresh_entry(), uctypes.addressof(_ARGS)
        rv = _viper()
        a = id(rv.core)
        self.engine = "viper"
        return a, rv._word(a + 12), uctypes.addressof(_ARGS)


def _c_core():
    """The C core when it has the refresh (compat.core(): the firmware's
    _texelcore, or deploy's native module), else None: then the interrupt
    calls core()'s viper machine code."""
    from ..compat import core as _core
    c = _core()
    return c if c is not None and hasattr(c, "refresh_entry") else None


_INSTALL = None          # the C core's install, False where there is none: _c_install()


def _c_install():
    """The C core's install (texelcore_api.h) on a 32-bit board, else None:
    FastRefresh._install's Python builds W there. tests/firmware compare the two."""
    global _INSTALL
    if _INSTALL is None:
        from ..compat import core as _core
        c = _core()
        _INSTALL = (_PTR_BYTES == 4 and c is not None and getattr(c, "install", None)) or False
    return _INSTALL or None


def _start_many_is_reset():
    """True on the texelpad firmware (its board name says so), whose soft-reset
    hook in C turns the free-running ADC off (boards/pico/mpconfigboard.h).
    Stock MicroPython leaves START_MANY on through a soft reset, and then a
    user's machine.ADC(...).read_u16() waits for a READY that never comes: the
    hardware/README calibration loop hung a stock Pico after a plain mpremote
    exec on the emulated chip (tests/host/test_doc_mpremote.py). There the
    refresh starts one conversion each time and waits its 2 us."""
    import sys
    return "(texelpad" in getattr(sys.implementation, "_machine", "")


irq_rp2 = _Rp2Irq()     # what app.py gives the rp2 backend on an RP2040


# bytes per pointer: 4 on a 32-bit board (then W_BASE is 0: _resolve)
_PTR_BYTES = uctypes.sizeof({"p": (uctypes.PTR | 0, uctypes.UINT8)})


def _offset(a, base):
    # an address as core() finds it: one word above BASE
    d = a - base
    if not 0 <= d <= 0xFFFFFFFF:
        raise MemoryError("fused refresh: address %x is more than 4 GB above %x" % (a, base))
    return d


def _resolve(words, tab, addr, chunked, nbuf):
    """Fill W (words) and core()'s table (tab) before a swap: every address
    as its offset from BASE (W_BASE holds it, split in two words: 0 on a
    32-bit board, else the lowest address), chunk tables' entries likewise,
    and each table row's value as core() looks it up - a K_PLAN row the index
    of its plan's first word in W, a K_BUF or K_CHUNK row its buffer's offset
    (as an int32: a 32-bit board's address above 2^31 wraps, and core() adds
    it modulo 2^32 there)."""
    if _PTR_BYTES == 4:
        base = 0
    else:
        base = min(a for _, a in addr)
        for ct, cs in chunked:
            base = min(base, min(cs))
    for k, a in addr:
        words[k] = _offset(a, base)
    for ct, cs in chunked:
        for c in range(len(cs)):
            ct[c] = _offset(cs[c], base)
    for r in range(0, len(tab) - 4, 4):      # every row but the sentinel
        kind = tab[r + 2]
        if kind == 2 or kind >= 4:          # scene.K_PLAN, K_TILE, K_STRETCH
            tab[r + 3] = W_BUF0 + nbuf + W_PLAN * tab[r + 3]
        elif kind == 1 or kind == 3:        # scene.K_BUF, K_CHUNK
            v = words[W_BUF0 + tab[r + 3]]
            tab[r + 3] = v - 0x100000000 if v > 0x7FFFFFFF else v
    words[W_BASE] = base & 0xFFFFFFFF
    words[W_BASE + 1] = (base >> 16) >> 16


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
        self._c, self._vcore = _engine()
        self._keep = None
        self._prev = None
        self._drop = None           # the generation _publish dropped, zeroed by _let_go
        self._fixed = None          # _fixed_words() for the C core's install
        self._fixed_regs = None     # the _regs they were made with
        self._fixed_fine = None     # and the duty law's table
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
        global _RP2
        _RP2 = self
        self._S[S_ADC_CS] = 1 | 4 | (adc_channel << 12)
        self._S[S_ADC12] = 1
        self._regs = (timer_addr, adc_addr, cc_addr, mul)
        self._install(self.scene)
        self._let_go()

    def use_stm32_registers(self, clock_addr, adc_addr, ccr_addr):
        """Let hw/stm32_irq.py drive the hardware directly (an STM32F4):
        clock_addr a free-running 32-bit microsecond counter (hw/stm32's TIM2
        CNT), adc_addr ADC1's base (core() reads DR, then starts the next
        conversion: S_ADC_CS bit 4), ccr_addr the carrier channel's CCR."""
        self._S[S_ADC_CS] = 16
        self._S[S_ADC12] = 1
        self._regs = (clock_addr, adc_addr, ccr_addr, 1)
        self._install(self.scene)
        self._let_go()

    def _fixed_words(self):
        """W's first W_FIXED words on a 32-bit board (W_BASE 0): the addresses
        and values that stay from swap to swap, for the C core's install. W_TAB
        (install writes it), W_IDLE (the caller) and W_ROW (0) stay 0 here."""
        f = array("I", bytes(4 * W_FIXED))
        f[W_S] = uctypes.addressof(self._S)
        f[W_FINE] = uctypes.addressof(self.law._fine)
        f[W_TEL_T] = uctypes.addressof(self.tel_t)
        f[W_TEL_P] = uctypes.addressof(self.tel_pos)
        f[W_TEL_A] = uctypes.addressof(self.tel_amp)
        f[W_TIMER] = self._regs[0]
        f[W_ADC] = self._regs[1]
        f[W_CC] = self._regs[2]
        f[W_MUL] = self._regs[3]
        f[W_SINE] = uctypes.addressof(sine_table.table())
        return f

    def _install(self, scene):
        bufs = scene.buffers() if scene is not None else ()
        plans = scene.plans() if scene is not None else ()
        ins = _c_install()
        if ins is not None:
            # the C core builds W and fixes the table in one call (texelcore_api.h
            # install): the same words as below on a 32-bit board, 0.2 ms where
            # this Python took 1.5 (two regions, emulated RP2040)
            # (made again whenever an address in them could have changed: the
            # registers, or the duty law's table)
            if self._fixed is None or self._fixed_regs is not self._regs \
                    or self._fixed_fine is not self.law._fine:
                self._fixed = self._fixed_words()
                self._fixed_regs = self._regs
                self._fixed_fine = self.law._fine
            tab = array("i", scene._t) if scene is not None else array("i", _EMPTY_TABLE)
            words, chunked = ins(self._fixed, tab, bufs, plans)
            words[W_IDLE] = scene.idle if scene is not None else self.idle_amp
            self._publish((words, scene, tab, chunked))
            return
        nbuf = len(bufs)
        words = array("I", [0] * (W_FIXED + nbuf + W_PLAN * len(plans)))
        # core()'s copy of the region table: the same rows, with each row's
        # value resolved to what core() needs - a K_BUF or K_CHUNK row the
        # offset of its buffer (or chunk table), a K_PLAN row the index of its
        # plan's first word in W - so a lookup is one load less (Scene.amp
        # keeps using scene._t)
        if scene is None:
            tab = array("i", _EMPTY_TABLE)
            words[W_IDLE] = self.idle_amp
        else:
            tab = array("i", scene._t)
            words[W_IDLE] = scene.idle
        # (index, address) of everything core() reaches by address; chunked
        # uploads get a table of their chunks' offsets
        addr = [(W_S, uctypes.addressof(self._S)), (W_TAB, uctypes.addressof(tab)),
                (W_FINE, uctypes.addressof(self.law._fine)),
                (W_TEL_T, uctypes.addressof(self.tel_t)),
                (W_TEL_P, uctypes.addressof(self.tel_pos)),
                (W_TEL_A, uctypes.addressof(self.tel_amp)),
                (W_TIMER, self._regs[0]), (W_ADC, self._regs[1]), (W_CC, self._regs[2]),
                (W_SINE, uctypes.addressof(sine_table.table()))]
        words[W_MUL] = self._regs[3]
        chunked = []
        for k in range(nbuf):
            b = bufs[k]
            if isinstance(b, tuple):    # scene.K_CHUNK: a table of its chunks' offsets
                ct = array("I", [0] * len(b))
                chunked.append((ct, [uctypes.addressof(c) for c in b]))
                b = ct
            addr.append((W_BUF0 + k, uctypes.addressof(b)))
        for k in range(len(plans)):
            b = W_BUF0 + nbuf + W_PLAN * k
            pl = plans[k]
            addr.append((b, uctypes.addressof(pl[0])))
            if len(pl) == 5:                # a few samples (kinds/samples.py plan()): as they are
                for i in range(1, 5):
                    words[b + i] = pl[i]
                continue
            t28, d28, ln, g = pl
            addr.append((b + 1, uctypes.addressof(d28)))
            words[b + 2] = ln
            words[b + 3] = g
            words[b + 4] = 65536 // ln + 1      # core()'s reciprocal of L
        _resolve(words, tab, addr, chunked, nbuf)
        chunked = [ct for ct, _ in chunked]
        self._publish((words, scene, tab, chunked))

    def _publish(self, keep):
        """Make keep's W (keep[0]) the one every refresh reads."""
        global _W, _WA, _S
        words = keep[0]
        # The previous generation stays referenced past the store: the viper
        # refresh holds raw addresses the GC cannot see, and on a port with real
        # threads (the unix port's realtime virtual board) a refresh may still be
        # reading the old scene just after it - there until the next swap.
        self._prev = self._keep
        self._keep = keep               # referenced before the refresh can see them
        # the swap: one store each (step() reads _W or _WA; the RP2040
        # trampoline reads _ARGS[0]: the small-int word (address << 1) | 1, one
        # 32-bit store through _ARGV - SRAM addresses are below 2^30; a 64-bit
        # unix port's word is cut, as nothing there reads it)
        _W = words
        _WA = uctypes.addressof(words)
        _S = self._S
        _ARGV.w = ((_WA << 1) | 1) & 0xFFFFFFFF
        if _VG is not None:             # refresh_viper.refresh() reads its own globals
            _VG["_W"] = _W
            _VG["_WA"] = _WA
        if not self.threaded:
            # a hard IRQ (rp2, stm32) runs to its end before this code goes on:
            # now that W is published no refresh can still read the old scene,
            # whose buffers go now (on a Pico, keeping a full-screen upload one
            # swap longer left no room for the next: measured on the emulated
            # Pico). On a port with real threads (the unix port's realtime
            # virtual board) a refresh may still be reading the old scene just
            # after the store: the previous generation stays until the next swap.
            # Zeroed by _let_go (_wipe) once the caller's state is whole: a
            # MemoryError or a Ctrl-C in the zeroing then leaves nothing half done.
            self._drop = self._prev
            self._prev = None
        return self._prev

    def _let_go(self):
        """Zero the generation the last publish dropped (_wipe), if any."""
        old = self._drop
        self._drop = None
        if old is not None:
            _wipe(old)

    def release(self):
        """The refresh has stopped for good (texel.app.stop, after the hardware's
        stop): its W and the one before are zeroed (_wipe), so that no stale slot
        naming them keeps the last scene's maps alive into the next start. Not
        on a threaded port (its refresh thread may still be in a step)."""
        if self.threaded:
            return
        for gen in (self._drop, self._prev, self._keep):
            if gen is not None:
                _wipe(gen)
        self._drop = self._prev = self._keep = None

    def swap(self, scene):
        old = self.scene
        self._install(scene)
        self.scene = scene
        self._let_go()
        return old

    def step(self, _timer=None):
        c0 = self.cost_ticks()
        self._clk[0] = self.ticks_us() & 0x3FFFFFFF
        self._adc[1] = self._read()
        if self._c is not None:
            self._c.refresh(_W)
        else:
            self._vcore(_WA)
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


from . import kinds as _k
if _k.CHUNK_BITS != 9 or _k.CHUNK_MASK != 511:
    raise ImportError("refresh_fast: scene chunk size differs from the literals in refresh_viper.core()")
if (_k.K_CONST, _k.K_BUF, _k.K_PLAN, _k.K_CHUNK, _k.K_TILE, _k.K_STRETCH) != (0, 1, 2, 3, 4, 5):
    raise ImportError("refresh_fast: the region table's codes (runtime/kinds/__init__.py) "
                      "differ from the literals in refresh_viper.core()")
if TELEMETRY_SLOTS != _SLOTS:
    raise ImportError("refresh_fast: telemetry ring size differs from refresh.py")

def _wipe(gen):
    """Zero a dropped generation's W, table copy and chunk tables (gen: what
    _publish kept). They hold raw addresses of the old scene's buffers, and
    MicroPython's collector reads every word of a block it reaches as a possible
    pointer: one stale stack slot still naming the old W (a refresh interrupt's
    frame) kept a whole full-screen map alive through _publish and the collection
    after it - texel.app._make_room's build in the old scene's room then failed
    and the display played idle, in 1-6 of 60 reference-over-reference pushes
    on the emulated pyboard (tests/firmware/test_firmware_pyboard.py)."""
    words, _scene, tab, chunked = gen
    _zero(words)
    _zero(tab)
    if chunked is None:                 # the C core's install: one array, or None
        return
    if isinstance(chunked, list):       # the Python install: one array per chunked buffer
        for ct in chunked:
            _zero(ct)
    else:
        _zero(chunked)


# _zero's: the run of zeros for compat.zeroed (W's 4-byte words), then the C core's
# zero (a memset) or False, then compat.zeroed: looked up at the first swap
_ZEROS = [array("I", bytes(4 * 64)), None, None]


def _zero(a):
    # a few words to a few hundred (W: 15 + one per buffer + 5 per plan; a table
    # copy: 4 per region; a chunk table: one per KB of map): the C core's memset,
    # else compat.zeroed's slice stores (the loop took 0.5 ms of a full-screen push's
    # swap on a stock Pico). Both are looked up once and kept in _ZEROS: an import
    # statement at each of a swap's 3-40 calls took 80-120 us each on the emulated
    # Pico's firmware (+0.29 ms a swap), 1.5-3.6 ms a swap on a stock Pico
    # (bench/firmware.py, swap_us; bench/import_cost.py). Kept in _ZEROS, not as globals
    # of their own: the STM32's refresh interrupt looks W up in this module's globals at
    # every refresh (hw/stm32_irq.py), and with one more name here the emulated
    # pyboard's refresh measured 8.06 us, not 6.21 (bench/stm32.py) - though one more
    # global in compat, which the interrupt never reads, did the same: docs/firmware.md
    z = _ZEROS
    c = z[1]
    if c is None:
        from ..compat import core, zeroed
        c = z[1] = getattr(core(), "zero", None) or False
        z[2] = zeroed
    if c:
        c(a)
    else:
        z[2](a, z[0])


# a scene-less table: the sentinel row alone (every position is a gap)
_EMPTY_TABLE = array("i", [0x3FFFFFFF, 0x3FFFFFFF, 0, 0])
