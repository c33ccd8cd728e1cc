# hw/stm32.py -- hardware backend for STM32 boards running MicroPython (pyb).
#
# Hw(board): see docs/runtime.md ("hw/*.py"). Platform modules are imported
# here, never by the texel package: importing this module on CPython raises
# ImportError.
#
# Carrier: an advanced timer, TIM1 or TIM8 (board carrier.pwm = {"timer": n,
# "channel": ch}), counting up 0..ARR at the timer clock (prescaler 0: /1):
# ARR = round(source_freq / freq) - 1 (168 MHz / 34 kHz -> 4940, i.e. 4,941
# counts per period, 34,001 Hz). PWM mode 1: the CHx output is high while
# CNT < CCRx, so the compare value is 0..ARR+1; CCR is preloaded (latched at
# the update event: no glitches).
#   single: pins [CHx pin].
#   bridge: pins [CHx pin, CHxN pin]: pyb starts the complementary CHxN
#           output with every PWM channel on TIM1/8, and the timer inserts
#           the dead time (Timer(deadtime=ticks); carrier.deadtime_ns,
#           default 200 ns = 34 ticks at 168 MHz) between the legs. As on
#           rp2, complementary legs carry a DC part V*(2D-1) (leg B high
#           all period at duty 0); off() takes both legs low.
# The board's cpu_hz must be the carrier timer's clock
# (Timer(n).source_freq(): 168 MHz for TIM1/8 on the F405), checked here.
# Safe state: the timer's main output enable (BDTR.MOE) cleared, with the
# off-state selection OSSI = 1 and idle levels OISx = OISxN = 0, so both legs
# are driven low at once, asynchronously (RM0090, "Output control bits for
# complementary OCx and OCxN channels with break feature"); CCR = 0. pyb sets
# idle levels high and OSSI = 0 (outputs floating when MOE = 0); this
# backend rewrites CR2/BDTR after pyb has configured the timer. set_duty
# stores the CCR and BDTR with MOE set (two 32-bit stores, allocation-free),
# so a set_duty after off() drives again.
#
# The registers are written through machine.mem32 at the timer's address:
# the `stm` module's constants where the firmware has it, else the
# STM32F4/F7/H7 addresses. Construction checks the CCR address against
# pyb's own TimerChannel.pulse_width before trusting it.
#
# Refresh: pyb.Timer(board refresh.timer, default 7, freq=hz, callback=cb):
# pyb Timer callbacks run in a hard IRQ (heap locked).
# Sensor: pyb.ADC(pin).read() (12 bits), scaled to read_u16 units the way
# machine.ADC.read_u16 does (raw << 4 | raw >> 8).
import sys
import time

import pyb
import machine

from ..compat import const

_TIM1 = const(0x40010000)           # STM32F4/F7/H7 APB2 advanced timers
_TIM8 = const(0x40010400)
_CR2 = const(0x04)
_CCR1 = const(0x34)
_BDTR = const(0x44)
_MOE = const(0x8000)                # BDTR: main output enable
_OSSR = const(0x0800)               # BDTR: off-state selection, run mode
_OSSI = const(0x0400)               # BDTR: off-state selection, idle mode
_REFRESH_TIMER = const(7)           # basic timer, unused by pyb itself
_CLOCK_TIMER = const(2)             # 32-bit: the refresh core's microsecond clock
_CNT = const(0x24)
_ARR = const(0x2C)
_EGR = const(0x14)
_ADC_CR2 = const(0x08)


def _f247():
    """True on an STM32F2, F4 or F7 (sys.implementation._machine names the MCU,
    e.g. "PYBv1.1 with STM32F405RG"): their ADC1 (CR2 ADON/SWSTART, DR at 0x4C)
    and TIM2 are what the refresh core drives. Other families (L4, G4, H7, WB)
    lay their ADC out otherwise: there the refresh reads pyb.ADC in Python."""
    m = getattr(sys.implementation, "_machine", "")
    return "STM32F2" in m or "STM32F4" in m or "STM32F7" in m


def _base(name, fallback):
    """A peripheral's base address: the port's stm module knows it for its MCU;
    fallback (the STM32F2/F4/F7's, RM0090) where it has no stm or no name."""
    try:
        import stm
        return getattr(stm, name)
    except (ImportError, AttributeError):
        return fallback


def _tim_base(n):
    return _base("TIM%d" % n, _TIM1 if n == 1 else _TIM8)


def timer_period(source_hz, freq_hz):
    """ARR for freq_hz with prescaler 1: round(source/freq) - 1."""
    return (source_hz + freq_hz // 2) // freq_hz - 1


def _carrier(board):
    """The board file's carrier and refresh timer, checked against what this
    backend drives: (carrier, freq_hz, drive, pins, timer, channel, refresh
    timer); ValueError names the field."""
    if board.get("port") != "stm32":
        raise ValueError("board %r: port is %r, hw/stm32 drives 'stm32' boards"
                         % (board.get("name"), board.get("port")))
    c = board["carrier"]
    freq = int(c["freq_hz"])
    drive = c.get("drive", "single")
    pins = list(c["pins"])
    pwm = c.get("pwm", {})
    n = int(pwm.get("timer", 8))
    ch = int(pwm.get("channel", 1))
    if drive not in ("single", "bridge"):
        raise ValueError("carrier.drive: expected 'single' or 'bridge', got %r" % (drive,))
    if len(pins) != (2 if drive == "bridge" else 1):
        raise ValueError("carrier.pins: %s drive needs %d pin(s), got %r"
                         % (drive, 2 if drive == "bridge" else 1, pins))
    if n not in (1, 8):
        # only the advanced timers have complementary outputs, dead time
        # and the MOE safe state this backend relies on
        raise ValueError("carrier.pwm.timer: expected 1 or 8 (advanced timers), got %r" % (n,))
    if not 1 <= ch <= (3 if drive == "bridge" else 4):
        raise ValueError("carrier.pwm.channel: expected 1..%d for %s drive, got %r"
                         % (3 if drive == "bridge" else 4, drive, ch))
    rt = int(board.get("refresh", {}).get("timer", _REFRESH_TIMER))
    if rt in (1, 8):
        raise ValueError("refresh.timer: %d is a carrier timer" % rt)
    if rt == _CLOCK_TIMER:
        raise ValueError("refresh.timer: %d is the refresh's microsecond clock (TIM2)" % rt)
    return c, freq, drive, pins, n, ch, rt


class Hw:
    def __init__(self, board):
        c, freq, drive, pins, n, ch, rt = _carrier(board)

        # 1. legs as plain outputs, low, while the timer is set up
        for p in pins:
            pyb.Pin(p, pyb.Pin.OUT_PP, value=0)

        # 2. the carrier timer
        tim = pyb.Timer(n)
        src = tim.source_freq()
        if src != int(board["cpu_hz"]):
            # boards/*.json keep the carrier timer's clock in cpu_hz (on the
            # F405, TIM1/8 run at 2 x APB2 = 168 MHz = the core clock)
            raise ValueError("cpu_hz: board says %d Hz but Timer(%d).source_freq() is %d Hz "
                             "(the carrier period depends on it)" % (int(board["cpu_hz"]), n, src))
        top = timer_period(src, freq)
        if not 1 <= top < 16383:
            # compare values stay small ints and the law's table fits
            raise ValueError("carrier.freq_hz: %d Hz needs ARR %d at %d Hz; supported 1..16382"
                             % (freq, top, src))
        dead = 0
        if drive == "bridge":
            ns = int(c.get("deadtime_ns", 200))
            dead = (ns * (src // 1000000) + 500) // 1000   # timer ticks
            if not 0 <= dead <= 1008:
                raise ValueError("carrier.deadtime_ns: %d ns is %d ticks, pyb allows 0..1008"
                                 % (ns, dead))
        tim.init(prescaler=0, period=top, deadtime=dead)
        self._ch = tim.channel(ch, pyb.Timer.PWM, pulse_width=0)
        self._tim = tim
        if tim.period() != top:
            raise RuntimeError("Timer(%d) period reads %d, expected %d" % (n, tim.period(), top))

        # 3. registers: check the CCR address with pyb's own write, then the
        #    safe state (idle levels low, OSSI/OSSR, MOE off)
        base = _tim_base(n)
        m = machine.mem32
        self._mem = m
        self._ccr = base + _CCR1 + 4 * (ch - 1)
        self._bdtr = base + _BDTR
        self._ch.pulse_width(1)
        ok = m[self._ccr] & 0xFFFF == 1
        self._ch.pulse_width(0)
        if not ok or m[self._ccr] & 0xFFFF != 0:
            raise RuntimeError("Timer(%d) CCR%d is not at 0x%08x on this chip" % (n, ch, self._ccr))
        k = ch - 1
        m[base + _CR2] = m[base + _CR2] & ~(3 << (8 + 2 * k))    # OISx = OISxN = 0
        bdtr = m[self._bdtr] & 0xFFFF
        self._run = bdtr | _MOE | _OSSI | _OSSR
        self._safe = (bdtr | _OSSI | _OSSR) & ~_MOE
        m[self._bdtr] = self._safe

        # 4. legs to the timer (alternate function): now driven low by it
        af = pyb.Pin.AF1_TIM1 if n == 1 else pyb.Pin.AF3_TIM8
        for p in pins:
            pyb.Pin(p, pyb.Pin.AF_PP, af=af)

        cap = float(c.get("duty_cap", 0.5))
        self.top = top
        self.max_counts = int(cap * (top + 1))
        self.freq_hz = freq
        self.drive = drive
        self.pins = tuple(pins)
        self.timer_id = n
        self.channel = ch
        self.deadtime_ticks = dead
        self._refresh_id = rt
        self._rt = None
        self._direct = False
        self._clock = None

        s = board.get("sensor", {})
        self._adc = tuple(pyb.ADC(pyb.Pin(p)) for p in s.get("pins", ()))
        self.ticks_us = time.ticks_us
        self.ticks_diff = time.ticks_diff

    def set_duty(self, counts):
        # counts: compare value 0..max_counts (clamped). Hot path: two 32-bit
        # stores, small ints only, no allocation (hard-IRQ safe).
        if counts > self.max_counts:
            counts = self.max_counts
        elif counts < 0:
            counts = 0
        m = self._mem
        m[self._ccr] = counts
        m[self._bdtr] = self._run

    def off(self):
        """Safe state at once: outputs disabled to their idle level (low),
        both bridge legs included; CCR = 0. A later set_duty drives again."""
        m = self._mem
        m[self._bdtr] = self._safe
        m[self._ccr] = 0

    def stm32_registers(self):
        """(microsecond clock, ADC1, CCR) register addresses for the refresh core
        to read the finger and write the duty itself (app.py, runtime/
        stm32_irq.py): TIM2 set free-running at 1 MHz over all 32 bits (the
        core's clock: worst_us, overruns, telemetry stamps), ADC1 converting the
        sensor's channel (one pyb read selects it; the core sets ADON and starts
        each next conversion itself), and this carrier's CCR. A drive that
        goes through these registers sets MOE itself when the timer starts."""
        if len(self._adc) != 1 or not _f247():
            return None                             # pyb.ADC.read() in Python, as before
        clock = pyb.Timer(_CLOCK_TIMER, prescaler=pyb.Timer(_CLOCK_TIMER).source_freq()
                          // 1000000 - 1, period=0x3FFFFFFF)
        base = _base("TIM2", 0x40000000)
        # wrap at 2^32, as the core's diff does: ARR is preloaded (pyb sets ARPE), so an
        # update event (EGR UG) loads it now, not at the first wrap 2^30 us away
        self._mem[base + _ARR] = 0xFFFFFFFF
        self._mem[base + _EGR] = 1
        self._clock = clock
        self._adc[0].read()                         # pyb selects the channel (SQR3)
        adc = _base("ADC1", 0x40012000)
        self._mem[adc + _ADC_CR2] = self._mem[adc + _ADC_CR2] | 1      # ADON
        self._direct = True
        return base + _CNT, adc, self._ccr

    def adc_read(self, i):
        # 12-bit pyb.ADC reading in read_u16 units (0..65535); allocation-free
        raw = self._adc[i].read()
        return (raw << 4) | (raw >> 8)

    def start(self, callback, hz):
        """Call callback(timer) hz times a second from the hard IRQ of
        pyb.Timer(refresh timer) (8,333 Hz on TIM7: 84 MHz / 10,080)."""
        self.stop_timer()
        if self._direct:
            self._mem[self._bdtr] = self._run      # the core writes only the CCR
        self._rt = pyb.Timer(self._refresh_id, freq=hz, callback=callback)

    def stop_timer(self):
        if self._rt is not None:
            self._rt.deinit()
            self._rt = None

    def stop(self):
        """Stop the refresh, then the safe state."""
        self.stop_timer()
        self.off()
