# hw/rp2.py -- hardware backend for RP2040 boards running MicroPython.
#
# Hw(board): see docs/runtime.md ("hw/*.py"). The carrier is machine.PWM at
# the board's carrier frequency; the compare value is written allocation-free
# (hard-IRQ safe). Platform modules are imported here, never by the texel
# package: importing this module on CPython raises ImportError.
#
# PWM (RP2040 datasheet, section 4.5): a slice counts 0..TOP and wraps
# (TOP+1 clocks per period); an output is high while count < CC, so CC is
# 0 (always low) .. TOP+1 (always high); CC is double-buffered and latched at
# the wrap, so a new duty never glitches a period. MicroPython picks TOP =
# (clk_sys + freq/2) // freq - 1 with divider 1: 125 MHz / 34 kHz -> 3675.
#
# Writes: on an RP2040 (auto-detected) set_duty stores the slice's CC
# register directly, both channel halves in one 32-bit store
# (machine.mem32[0x4005000C + 0x14*slice]): one bytecode store, no method
# call. Elsewhere (RP2350, whose PWM block is at another address, or
# direct=False) it falls back to PWM.duty_u16 with a count -> u16 value that
# MicroPython's rounding maps back to exactly the same CC.
#
# Drive:
#   single: pins [A]. The slice's other channel is written 0 by the 32-bit
#           store: do not use the other pin of the slice for PWM.
#   bridge: pins [A, B] = the two channels of one slice (GPIO 2k and 2k+1);
#           leg B is inverted (machine.PWM(invert=True)) and gets the same
#           CC, so B = not A at every count (complementary). The RP2040 PWM
#           has no dead-time generator: use a gate driver that inserts it.
#           Note: complementary legs carry a DC part V*(2D-1): at duty 0
#           (amplitude 0 while running) leg B is high all period, so the
#           load sits at -V DC with no fundamental; only at D = 0.5 is
#           there no DC. Safe state (off()): CC_A = 0 and CC_B = TOP+1,
#           i.e. both legs low (B inverted and always "high" internally):
#           no voltage across the load.
# The duty is clamped to max_counts = floor(duty_cap * (TOP+1)).
#
# Refresh interrupt (start()). When the callback offers native_entry()
# (texel.runtime.refresh_viper.irq_rp2, on an RP2040) the refresh runs as a
# raw interrupt: a spare PWM slice (TICK_SLICES: 3, 2, 1 or 0, the first one
# free and not the carrier's) counts the refresh period in clk_sys cycles
# (125 MHz * 120 us = 15,000 = TOP+1: the same 120 us as machine.Timer's
# whole microseconds) and its wrap interrupt (PWM_IRQ_WRAP, IRQ 4) jumps
# through the RAM vector table to a 12-instruction Thumb trampoline
# (_TRAMPOLINE below) that acknowledges the wrap and calls the viper
# refresh's machine code. machine.Timer's path - pico-sdk's alarm pool,
# mp_irq_dispatch (scheduler and GC locks, an nlr frame, stack-limit swap),
# mp_call_function - and the viper function's handling of a global took
# 10.7 us of the 21-24 us a refresh cost on the emulated RP2040 (texelpad
# bench-refresh --chip rp2040, docs/runtime.md). The vector handler has the
# highest priority, so other interrupts (USB) delay it less. On this path
# on the texelpad firmware (whose soft-reset hook stops it: refresh_viper
# _start_many_is_reset) the refresh also lets the ADC convert continuously (START_MANY) and takes
# its last conversion, at most 2 us old, instead of starting one and waiting
# 2 us for it (refresh_viper.core). stop() disables the interrupt, the slice
# and the free-running ADC and puts the old vector back.
#
# Why slices 0..3: a soft reset (Ctrl-D, mpremote's exec, Thonny's Stop) does
# not call stop(). MicroPython v1.28's machine_pwm_deinit_all
# (ports/rp2/machine_pwm.c) disables machine_pwm_obj[i].slice for i < 8 -
# the first eight channel objects, which are slices 0, 0, 1, 1, 2, 2, 3, 3 -
# so slices 4..7 keep counting. A tick on slice 7 (texelpad before issue 30)
# kept interrupting through the soft reset into a trampoline and machine code
# in the freed heap, which the new interpreter overwrites: a HardFault (the
# emulated Pico: "read from address ..., which is not 32 bit aligned"). A
# tick on slices 0..3 is stopped by the soft reset itself, before the heap
# is swept, with or without that loop's bug; if none of them is free the
# refresh uses machine.Timer, which soft_timer_deinit stops. The texelpad
# firmware also disarms it in C at the start of every soft reset
# (boards/pico/mpconfigboard.h, MICROPY_BOARD_START_SOFT_RESET). The wrap
# enable bits stay set across a soft reset: clear_stale_tick() disarms them
# (texel/main.py at power-up, texel.app.start(), texel.app.stop()), so a
# machine.PWM on a tick slice's pins cannot take the interrupt into a stale
# vector. Anything unexpected (not an RP2040, the vector table in flash, no
# free slice, a period the slice cannot count exactly) falls back to
# machine.Timer.
import sys
import time
from array import array

import machine
import uctypes

from ..compat import const

# RP2040 PWM registers (datasheet 4.5.3). 0x40050000 exceeds the small-int
# range of a 32-bit port (+-2^30): the address is a heap int, built once in
# __init__ and kept; loading it later allocates nothing.
_PWM_BASE = const(0x40050000)
_SLICE_STRIDE = const(0x14)
_CH_CC = const(0x0C)                # bits 15:0 channel A, 31:16 channel B
_CH_TOP = const(0x10)
_TOP_LIMIT = const(16383)          # TOP+1 < 2^14: (TOP+1) << 16 < 2^30
_CH_CSR = const(0x00)
_CH_DIV = const(0x04)
_CH_CTR = const(0x08)
_PWM_INTR = const(0xA4)            # write 1 to clear a slice's wrap flag
_PWM_INTE = const(0xA8)
_PWM_IRQ = const(4)                # PWM_IRQ_WRAP
_VTOR = const(0xE000ED08)
_NVIC_ISER = const(0xE000E100)
_NVIC_ICER = const(0xE000E180)
_NVIC_ICPR = const(0xE000E280)
_NVIC_IPR1 = const(0xE000E404)     # priorities of IRQ 4..7, one byte each (bits 7:6 used)
_ADC_CS = const(0x4004C000)       # bit 3 START_MANY: free-running conversions
_SRAM = const(0x20000000)
# the slices a soft reset stops (above), in the order tried; their wrap enables
_TICK_SLICES = (3, 2, 1, 0)
_STALE_INTE = const(0xCF)          # slices 0..3 and 6, 7 (the tick before issue 30)
_SRAM_END = const(0x20042000)

# The trampoline, Thumb-1 halfwords (ARMv6-M), then its five literals. The
# exception entry has stacked r0-r3, r12, lr, pc, xPSR and put EXC_RETURN in
# lr; push {r4, lr} keeps the stack 8-byte aligned for the call (AAPCS);
# pop {r4, pc} with EXC_RETURN returns from the exception. Each ldr reads a
# literal 20 bytes past its aligned PC (imm8 = 5): see the byte offsets.
_TRAMPOLINE = (
    0xB510, 0x4805,     # 0: push {r4, lr}      2: ldr r0, [pc, #20] -> 24 PWM INTR address
    0x4905, 0x6001,     # 4: ldr r1, [pc, #20]  -> 28 slice bit      6: str r1, [r0]: acknowledge
    0x4805, 0x2101,     # 8: ldr r0, [pc, #20]  -> 32 function obj   10: movs r1, #1 (n_args)
    0x2200, 0x4B05,     # 12: movs r2, #0 (n_kw) 14: ldr r3, [pc, #20] -> 36 args array
    0x4C05, 0x47A0,     # 16: ldr r4, [pc, #20] -> 40 code | 1       18: blx r4
    0xBD10, 0xBF00)     # 20: pop {r4, pc}      22: nop (literals start word-aligned at 24)


def clear_stale_tick():
    """Disarm a refresh interrupt left behind by a soft reset that skipped
    stop(): the NVIC enable of PWM_IRQ_WRAP and the tick slices' wrap
    enables stay set across it while the vector points at a trampoline in the
    freed heap, so a later machine.PWM on those slices' pins would jump there.
    Call it only while texelpad's refresh is not running (texel/main.py does
    at power-up, texel.app.start() before it starts, texel.app.stop() when
    nothing runs). Does nothing off an RP2040."""
    if not _is_rp2040():
        return
    m = machine.mem32
    m[_NVIC_ICER] = 1 << _PWM_IRQ
    m[_PWM_BASE + _PWM_INTE] = m[_PWM_BASE + _PWM_INTE] & ~_STALE_INTE
    m[_NVIC_ICPR] = 1 << _PWM_IRQ
    m[_ADC_CS] = m[_ADC_CS] & ~8        # the refresh's free-running ADC (START_MANY)


def _is_rp2040():
    # sys.implementation._machine is e.g. "Raspberry Pi Pico with RP2040"
    return sys.platform == "rp2" and "RP2040" in getattr(sys.implementation, "_machine", "")


def pwm_top(cpu_hz, freq_hz):
    """TOP that ports/rp2/machine_pwm.c programs for freq_hz (divider 1)."""
    return (cpu_hz + freq_hz // 2) // freq_hz - 1


def _carrier(board):
    """The board file's carrier, checked against the RP2040's PWM: (carrier,
    freq_hz, cpu_hz, drive, pins, slice); ValueError names the field."""
    if board.get("port") != "rp2":
        raise ValueError("board %r: port is %r, hw/rp2 drives 'rp2' boards"
                         % (board.get("name"), board.get("port")))
    c = board["carrier"]
    freq = int(c["freq_hz"])
    cpu = int(board["cpu_hz"])
    drive = c.get("drive", "single")
    pins = [int(p) for p in c["pins"]]
    if drive not in ("single", "bridge"):
        raise ValueError("carrier.drive: expected 'single' or 'bridge', got %r" % (drive,))
    if len(pins) != (2 if drive == "bridge" else 1):
        raise ValueError("carrier.pins: %s drive needs %d pin(s), got %r"
                         % (drive, 2 if drive == "bridge" else 1, pins))
    for p in pins:
        if not 0 <= p <= 29:
            raise ValueError("carrier.pins: GPIO %d does not exist on an RP2040" % p)
    sl = (pins[0] >> 1) & 7         # pwm_gpio_to_slice_num on the RP2040
    want = c.get("pwm", {}).get("slice")
    if want is not None and want != sl:
        raise ValueError("carrier.pwm.slice: GPIO %d is on slice %d, board says %d"
                         % (pins[0], sl, want))
    if drive == "bridge" and (((pins[1] >> 1) & 7) != sl or (pins[1] & 1) == (pins[0] & 1)):
        raise ValueError("carrier.pins: bridge legs %r must be the two channels of one "
                         "PWM slice (GPIO 2k and 2k+1)" % (pins,))
    return c, freq, cpu, drive, pins, sl


class Hw:
    """Hw(board, direct=None): the rp2 backend. direct=None writes CC
    registers directly on an RP2040 and uses PWM.duty_u16 elsewhere;
    True/False force it (tests)."""

    def __init__(self, board, direct=None):
        c, freq, cpu, drive, pins, sl = _carrier(board)
        mf = machine.freq()
        if mf != cpu:
            raise ValueError("cpu_hz: board says %d Hz but machine.freq() is %d Hz "
                             "(PWM TOP depends on it)" % (cpu, mf))
        top = pwm_top(cpu, freq)
        if not 1 <= top < _TOP_LIMIT:
            # compare words (counts << 16, TOP+1 << 16) must stay small ints
            # on a 32-bit port (< 2^30), or set_duty would allocate
            raise ValueError("carrier.freq_hz: %d Hz needs TOP %d at %d Hz; supported "
                             "1..%d (carrier above ~7.7 kHz)" % (freq, top, cpu, _TOP_LIMIT - 1))
        cap = float(c.get("duty_cap", 0.5))
        self.top = top
        self.max_counts = int(cap * (top + 1))
        self.freq_hz = freq
        self.drive = drive
        self.pins = tuple(pins)
        self.slice = sl
        if direct is None:
            direct = _is_rp2040()
        self.direct = bool(direct)
        self._timer = None
        self._vector = None             # (trampoline, vector address, old vector, slice)
        self.irq_source = None          # how the refresh runs: for status and benches
        self._cpu_hz = cpu
        self._period = top + 1
        self._half = (top + 1) // 2     # rounding of the duty_u16 fallback

        # CC word for `counts`: counts * _mul puts it in leg A's half (and,
        # bridge, leg B's half too). Off word: A = 0, B (inverted) = TOP+1.
        sa = 16 * (pins[0] & 1)
        if drive == "bridge":
            sb = 16 * (pins[1] & 1)
            self._mul = (1 << sa) | (1 << sb)
            self._off_word = (top + 1) << sb
        else:
            self._mul = 1 << sa
            self._off_word = 0
        base = _PWM_BASE + _SLICE_STRIDE * sl
        self._cc = base + _CH_CC        # a heap int on the board: made here, once
        self._top_reg = base + _CH_TOP
        self._mem = machine.mem32 if self.direct else None

        # Leg A low from the start (duty 0). Leg B is made with CC_B = TOP+1
        # and inverted: low. Current MicroPython configures the slice before
        # muxing the pin, and the direct path latches B's off value before B
        # is made, so B stays low throughout; with older versions (mux first)
        # or the duty_u16 path B may be high for less than one carrier period.
        self._a = machine.PWM(machine.Pin(pins[0]), freq=freq, duty_u16=0)
        self._b = None
        if self.direct:
            if self._mem[self._top_reg] & 0xFFFF != top:
                raise RuntimeError("PWM slice %d TOP reads %d, expected %d: not an RP2040 "
                                   "PWM block (use direct=False)"
                                   % (sl, self._mem[self._top_reg] & 0xFFFF, top))
            self._mem[self._cc] = self._off_word
            time.sleep_us(2 * (1000000 // freq + 1))   # let the wrap latch it
        if drive == "bridge":
            self._b = machine.PWM(machine.Pin(pins[1]), freq=freq, duty_u16=65535,
                                  invert=True)
        self.off()

        s = board.get("sensor", {})
        self._adc = tuple(machine.ADC(machine.Pin(int(p))) for p in s.get("pins", ()))
        # time functions as plain attributes: calling them allocates nothing
        self.ticks_us = time.ticks_us
        self.ticks_diff = time.ticks_diff

    def direct_registers(self):
        """(CC register address, multiplier) for the fused viper IRQ to write
        `counts * multiplier` into the CC register itself, or None when this
        backend writes through PWM.duty_u16 (not an RP2040, or direct=False)."""
        if not self.direct:
            return None
        return self._cc, self._mul

    def set_duty(self, counts):
        # counts: compare value 0..max_counts (clamped). Hot path: small ints
        # only, no allocation (hard-IRQ safe). Takes effect at the next wrap.
        if counts > self.max_counts:
            counts = self.max_counts
        elif counts < 0:
            counts = 0
        if self._mem is not None:
            self._mem[self._cc] = counts * self._mul
        else:
            # u16 whose MicroPython rounding (u*(TOP+1) + 32767) // 65535 is counts
            u = (counts * 65535 + self._half) // self._period
            self._a.duty_u16(u)
            if self._b is not None:
                self._b.duty_u16(u)

    def off(self):
        """Safe state: duty 0, bridge legs both low (from the next wrap,
        <= 1 carrier period). A later set_duty drives again."""
        if self._mem is not None:
            self._mem[self._cc] = self._off_word
        else:
            self._a.duty_u16(0)
            if self._b is not None:
                self._b.duty_u16(65535)

    def adc_read(self, i):
        # raw read_u16 (0..65535) of sensor pin i; allocation-free
        return self._adc[i].read_u16()

    def start(self, callback, hz):
        """Call callback(timer) hz times a second from a hard IRQ
        (machine.Timer(hard=True), MicroPython >= 1.26), or - when callback
        offers native_entry() and this is an RP2040 - its machine code from
        a PWM-wrap interrupt (see the top of this file). The period is whole
        microseconds: 8,333 Hz -> 120 us. The timer object is kept here:
        rp2 Timers stop when garbage-collected."""
        self.stop_timer()
        entry = getattr(callback, "native_entry", None)
        if entry is not None and self.direct and _is_rp2040():
            if self._start_vector(entry(), 1000000 // hz):
                return
        try:
            self._timer = machine.Timer(freq=hz, mode=machine.Timer.PERIODIC,
                                        callback=callback, hard=True)
        except TypeError:
            raise RuntimeError("machine.Timer(hard=True) needs MicroPython >= 1.26 on rp2")
        self.irq_source = "machine.Timer (hard)"

    def _start_vector(self, entry, period_us):
        """The refresh as a PWM-wrap interrupt calling entry = (function object,
        machine code, argument array) addresses; False (nothing changed) when
        it cannot be done here."""
        m = machine.mem32
        fun, code, args = entry
        sl = -1
        for k in _TICK_SLICES:      # a slice a soft reset stops (top of this file)
            if k != self.slice and not m[_PWM_BASE + _SLICE_STRIDE * k + _CH_CSR] & 1:
                sl = k
                break
        if sl < 0:
            return False                # every such slice is in use: machine.Timer
        base = _PWM_BASE + _SLICE_STRIDE * sl
        vtor = m[_VTOR] & 0xFFFFFFFF
        cycles = self._cpu_hz * period_us
        if cycles % 1000000:
            return False                # the slice counts whole clk_sys cycles
        cycles //= 1000000
        div = 1
        while cycles // div > 65536 or cycles % div:
            div += 1
            if div > 255:
                return False
        # a function: push {..., lr} first, or second after one load (the C core's
        # entry as gcc compiles it for a native module: ldr r0, [r3]; push {r4, lr})
        c = code & ~1
        ok = (_SRAM <= vtor < _SRAM_END and _SRAM <= fun < _SRAM_END
              and _SRAM <= code < _SRAM_END and _SRAM <= args < _SRAM_END
              and (machine.mem16[c] & 0xFF00 == 0xB500
                   or machine.mem16[c + 2] & 0xFF00 == 0xB500))
        if not ok:
            return False
        tramp = array("I", [0] * 11)
        for i in range(6):
            tramp[i] = _TRAMPOLINE[2 * i] | (_TRAMPOLINE[2 * i + 1] << 16)
        tramp[6] = _PWM_BASE + _PWM_INTR
        tramp[7] = 1 << sl
        tramp[8] = fun
        tramp[9] = args
        tramp[10] = code | 1
        vec = vtor + 4 * (16 + _PWM_IRQ)
        self._vector = (tramp, vec, m[vec] & 0xFFFFFFFF, sl)
        m[base + _CH_CSR] = 0
        m[base + _CH_DIV] = div << 4    # integer divider, no fraction
        m[base + _CH_CTR] = 0
        m[base + _CH_TOP] = cycles // div - 1
        m[_PWM_BASE + _PWM_INTR] = 1 << sl
        m[_PWM_BASE + _PWM_INTE] = m[_PWM_BASE + _PWM_INTE] | (1 << sl)
        m[vec] = uctypes.addressof(tramp) | 1
        m[_NVIC_IPR1] = m[_NVIC_IPR1] & ~0xFF          # IRQ 4: priority 0 (highest)
        m[_NVIC_ICPR] = 1 << _PWM_IRQ
        m[_NVIC_ISER] = 1 << _PWM_IRQ
        m[base + _CH_CSR] = 1           # free-running: the first wrap in one period
        self.irq_source = "PWM slice %d wrap interrupt -> refresh machine code" % sl
        return True

    def stop_timer(self):
        if self._timer is not None:
            self._timer.deinit()
            self._timer = None
        if self._vector is not None:
            m = machine.mem32
            tramp, vec, old, sl = self._vector
            m[_NVIC_ICER] = 1 << _PWM_IRQ
            m[_PWM_BASE + _PWM_INTE] = m[_PWM_BASE + _PWM_INTE] & ~(1 << sl)
            m[_PWM_BASE + _SLICE_STRIDE * sl + _CH_CSR] = 0
            m[_PWM_BASE + _PWM_INTR] = 1 << sl
            m[_NVIC_ICPR] = 1 << _PWM_IRQ
            m[vec] = old
            self._vector = None         # the trampoline may go: nothing points at it
            # the refresh let the ADC convert continuously (refresh_viper's
            # START_MANY branch): stop that too
            m[_ADC_CS] = m[_ADC_CS] & ~8
        self.irq_source = None

    def stop(self):
        """Stop the refresh, then the safe state."""
        self.stop_timer()
        self.off()
