# A recording stand-in for MicroPython's `machine` module (rp2 flavour), for
# tests of device/texel/hw/*.py under the MicroPython unix port (put
# tests/support/fakes before device/ on MICROPYPATH: `machine` is an extensible
# built-in there, so this file shadows it) and under CPython.
#
# It records every write (PWM freq/duty/invert/pin, mem32 stores, Timer init
# arguments, ADC pins) and models the hardware the backends drive, so a test
# can ask what a pin does over one carrier period:
#   - RP2040 PWM block: 8 slices of CSR/DIV/CTR/CC/TOP registers at
#     0x40050000 + 0x14*slice (RP2040 datasheet, section 4.5.3); PWM objects
#     compute TOP and CC exactly as ports/rp2/machine_pwm.c does.
#   - STM32 TIM1 (0x40010000) and TIM8 (0x40010400) register blocks, shared
#     with the pyb fake (tests/support/fakes/pyb.py).
# mem32 stores into unmapped addresses raise (a wrong address is a bug).
#
# Recording is allocation-free (preallocated arrays, existing dict keys), so
# code under micropython.heap_lock() can be tested through this fake.
# Plain Python: no type hints, no f-strings.
from array import array

FREQ = 125000000            # clk_sys in Hz (machine.freq())


def freq(hz=None):
    global FREQ
    if hz is None:
        return FREQ
    FREQ = hz


# ---------------------------------------------------------------- registers
PWM_BASE = 0x40050000       # RP2040 PWM: CH0_CSR; slice n at + 0x14*n
PWM_STRIDE = 0x14
PWM_CSR = 0x00              # bit 0 EN, bit 1 PH_CORRECT, bit 2 A_INV, bit 3 B_INV
PWM_DIV = 0x04              # 8.4 fixed point; 16 = divide by 1
PWM_CTR = 0x08
PWM_CC = 0x0C               # bits 15:0 channel A, 31:16 channel B
PWM_TOP = 0x10
PWM_SLICES = 8
TIM1_BASE = 0x40010000      # STM32F4 TIM1 / TIM8 (RM0090, section 17.4)
TIM8_BASE = 0x40010400
TIM_BLOCK = 0x50            # CR1 .. DMAR

REGS = {}                   # address -> 32-bit value (the register file)


def _map_block(base, size):
    a = base
    while a < base + size:
        REGS[a] = 0
        a += 4


def reset_registers():
    """Zero every modelled register (keys stay: later stores allocate nothing)."""
    for k in list(REGS.keys()):
        REGS[k] = 0


_map_block(PWM_BASE, PWM_STRIDE * PWM_SLICES)
_map_block(TIM1_BASE, TIM_BLOCK)
_map_block(TIM8_BASE, TIM_BLOCK)


def pwm_reg(slice_, offset):
    return PWM_BASE + PWM_STRIDE * slice_ + offset


class _Mem32:
    """machine.mem32: stores go to the register file and into a log of the
    last LOG_SIZE (address, value) pairs (preallocated: no allocation)."""
    LOG_SIZE = 4096

    def __init__(self):
        self.addr = array("I", bytes(4 * self.LOG_SIZE))
        self.value = array("I", bytes(4 * self.LOG_SIZE))
        self.count = 0          # stores since the last clear()
        self.reads = 0

    def __setitem__(self, addr, v):
        if addr not in REGS:
            raise ValueError("fake mem32: store to unmapped address 0x%08x" % addr)
        v = v & 0xFFFFFFFF
        REGS[addr] = v
        i = self.count % self.LOG_SIZE
        self.addr[i] = addr
        self.value[i] = v
        self.count += 1

    def __getitem__(self, addr):
        if addr not in REGS:
            raise ValueError("fake mem32: load from unmapped address 0x%08x" % addr)
        self.reads += 1
        return REGS[addr]

    def clear(self):
        self.count = 0
        self.reads = 0

    def writes(self):
        """[(address, value), ...] oldest first (at most LOG_SIZE)."""
        n = self.count if self.count < self.LOG_SIZE else self.LOG_SIZE
        first = self.count - n
        out = []
        for k in range(first, self.count):
            i = k % self.LOG_SIZE
            out.append((self.addr[i], self.value[i]))
        return out


mem32 = _Mem32()

# ---------------------------------------------------------------- events
# A human-readable log of configuration calls (allocates: never on a hot path).
EVENTS = []


def _event(*args):
    EVENTS.append(args)


# ---------------------------------------------------------------- Pin
MUX = {}                    # gpio -> "PWM" | "OUT" | "IN" | "ADC"
LEVEL = {}                  # gpio -> 0/1 for GPIO outputs


def _gpio(dest):
    if isinstance(dest, Pin):
        return dest.id
    if isinstance(dest, int):
        return dest
    raise TypeError("fake machine: expected a Pin or a GPIO number, got %r" % (dest,))


class Pin:
    IN = 0
    OUT = 1
    OPEN_DRAIN = 2
    ALT = 3
    PULL_UP = 1
    PULL_DOWN = 2

    def __init__(self, id, mode=-1, pull=-1, value=None, alt=-1):
        if isinstance(id, Pin):
            id = id.id
        if not isinstance(id, int) or not 0 <= id <= 29:
            raise ValueError("fake machine.Pin: invalid pin %r" % (id,))
        self.id = id
        if mode != -1 or value is not None:
            self.init(mode, pull, value=value)

    def init(self, mode=-1, pull=-1, value=None, alt=-1):
        _event("Pin.init", self.id, mode, value)
        if mode == Pin.OUT:
            MUX[self.id] = "OUT"
            LEVEL[self.id] = 1 if value else 0
        elif mode == Pin.IN:
            MUX[self.id] = "IN"
        elif value is not None:
            LEVEL[self.id] = 1 if value else 0

    def value(self, v=None):
        if v is None:
            return LEVEL.get(self.id, 0)
        LEVEL[self.id] = 1 if v else 0

    def low(self):
        self.value(0)

    def high(self):
        self.value(1)

    def __repr__(self):
        return "Pin(%d)" % self.id


# ---------------------------------------------------------------- PWM
PWMS = []                   # every PWM object made, in order


def _slice_of(gpio):
    return (gpio >> 1) & 7


class PWM:
    """rp2 machine.PWM: PWM(dest, freq=, *, duty_u16=, duty_ns=, invert=)."""

    def __init__(self, dest, freq=None, duty_u16=None, duty_ns=None, invert=None):
        gpio = _gpio(dest)
        self.gpio = gpio
        self.slice = _slice_of(gpio)
        self.channel = gpio & 1             # 0 = A, 1 = B
        self.invert = False                 # the constructor resets it (as rp2 does)
        self.duty_u16_writes = 0
        self.last_duty_u16 = None
        self.freq_hz = None
        self.deinited = False
        _event("PWM", gpio, freq, duty_u16, invert)
        PWMS.append(self)
        self.init(freq=freq, duty_u16=duty_u16, duty_ns=duty_ns, invert=invert)
        MUX[gpio] = "PWM"                   # current MicroPython muxes last

    def init(self, freq=None, duty_u16=None, duty_ns=None, invert=None):
        if freq is not None:
            self.freq(freq)
        if duty_u16 is not None:
            self.duty_u16(duty_u16)
        if duty_ns is not None:
            raise NotImplementedError("fake PWM: duty_ns")
        if invert is not None:
            self.invert = bool(invert)
        csr = pwm_reg(self.slice, PWM_CSR)
        bit = 4 if self.channel == 0 else 8
        REGS[csr] = (REGS[csr] & ~bit) | (bit if self.invert else 0)
        if self.freq_hz is not None:
            REGS[csr] = REGS[csr] | 1       # enable the slice
        self.deinited = False

    def freq(self, f=None):
        top_reg = pwm_reg(self.slice, PWM_TOP)
        if f is None:
            return (FREQ + (REGS[top_reg] + 1) // 2) // (REGS[top_reg] + 1)
        top = (FREQ + f // 2) // f - 1     # divider 1 (ports/rp2/machine_pwm.c)
        if top + 1 >= 65534:
            raise NotImplementedError("fake PWM: frequencies needing the divider")
        if top < 1:
            raise ValueError("freq too large")
        REGS[top_reg] = top
        REGS[pwm_reg(self.slice, PWM_DIV)] = 16
        self.freq_hz = f

    def duty_u16(self, u=None):
        top = REGS[pwm_reg(self.slice, PWM_TOP)]
        cc_reg = pwm_reg(self.slice, PWM_CC)
        shift = 16 * self.channel
        if u is None:
            cc = (REGS[cc_reg] >> shift) & 0xFFFF
            return (cc * 65535 + (top + 1) // 2) // (top + 1)
        if u > 65535:
            u = 65535
        cc = (u * (top + 1) + 32767) // 65535
        REGS[cc_reg] = (REGS[cc_reg] & ~(0xFFFF << shift)) | (cc << shift)
        self.last_duty_u16 = u
        self.duty_u16_writes += 1

    def deinit(self):
        self.deinited = True
        csr = pwm_reg(self.slice, PWM_CSR)
        REGS[csr] = REGS[csr] & ~1


def pwm_top(slice_):
    return REGS[pwm_reg(slice_, PWM_TOP)]


def pwm_cc(gpio):
    """The compare value of the channel that drives `gpio`."""
    return (REGS[pwm_reg(_slice_of(gpio), PWM_CC)] >> (16 * (gpio & 1))) & 0xFFFF


def level(gpio, count):
    """What pin `gpio` outputs at counter value `count` (0..TOP): 0/1, or
    None when nothing drives it. A PWM output is high while count < CC,
    inverted when the channel's INV bit is set (RP2040 datasheet 4.5.2)."""
    mux = MUX.get(gpio)
    if mux == "OUT":
        return LEVEL.get(gpio, 0)
    if mux != "PWM":
        return None
    s = _slice_of(gpio)
    csr = REGS[pwm_reg(s, PWM_CSR)]
    out = 1 if count < pwm_cc(gpio) else 0
    if csr & (4 if (gpio & 1) == 0 else 8):
        out ^= 1
    return out


def wave(gpio):
    """The pin's level at every count of one period (list of TOP+1 values)."""
    top = pwm_top(_slice_of(gpio))
    return [level(gpio, c) for c in range(top + 1)]


# ---------------------------------------------------------------- ADC
ADC_VALUES = {}             # gpio -> list of scripted read_u16 values (cycled)
ADCS = []


def script_adc(gpio, values):
    """The values ADC(gpio).read_u16() returns, cycled (ints 0..65535)."""
    ADC_VALUES[gpio] = list(values)
    for a in ADCS:
        if a.gpio == gpio:
            a._values = ADC_VALUES[gpio]
            a._i = 0


class ADC:
    def __init__(self, src):
        if isinstance(src, Pin):
            gpio = src.id
        elif isinstance(src, int) and src >= 26:
            gpio = src                      # rp2 accepts a GPIO number too
        else:
            raise ValueError("fake ADC: pass a Pin or a GPIO 26..29, got %r" % (src,))
        if not 26 <= gpio <= 29:
            raise ValueError("Pin doesn't have ADC capabilities")
        self.gpio = gpio
        MUX[gpio] = "ADC"
        self._values = ADC_VALUES.get(gpio) or [0]
        self._i = 0
        self.reads = 0
        _event("ADC", gpio)
        ADCS.append(self)

    def read_u16(self):
        v = self._values[self._i]
        self._i += 1
        if self._i >= len(self._values):
            self._i = 0
        self.reads += 1
        return v


# ---------------------------------------------------------------- Timer
TIMERS = []


class Timer:
    """rp2 machine.Timer (soft alarm pool; `hard` since MicroPython 1.26).
    fire(n) calls the callback n times as the alarm would."""
    ONE_SHOT = 0
    PERIODIC = 1

    def __init__(self, id=-1, mode=1, callback=None, period=-1, tick_hz=1000, freq=None,
                 hard=False):
        if id != -1:
            raise ValueError("Timer doesn't exist")
        self.running = False
        self.args = None
        self.fired = 0
        TIMERS.append(self)
        if callback is not None or freq is not None or period != -1:
            self.init(mode=mode, callback=callback, period=period, tick_hz=tick_hz,
                      freq=freq, hard=hard)

    def init(self, mode=1, callback=None, period=-1, tick_hz=1000, freq=None, hard=False):
        self.args = {"mode": mode, "callback": callback, "period": period,
                     "tick_hz": tick_hz, "freq": freq, "hard": hard}
        if freq is not None:
            self.period_us = int(1000000.0 / freq)   # as ports/rp2/machine_timer.c
        else:
            self.period_us = period * 1000000 // tick_hz
        self.mode = mode
        self.callback = callback
        self.hard = bool(hard)
        self.running = True
        _event("Timer.init", mode, freq, hard)

    def deinit(self):
        self.running = False
        _event("Timer.deinit")

    def fire(self, n=1):
        for _ in range(n):
            if not self.running:
                break
            self.fired += 1
            self.callback(self)
            if self.mode == Timer.ONE_SHOT:
                self.running = False


def reset():
    """Forget everything recorded (a test's fresh start)."""
    global FREQ
    FREQ = 125000000
    reset_registers()
    mem32.clear()
    del EVENTS[:]
    MUX.clear()
    LEVEL.clear()
    del PWMS[:]
    ADC_VALUES.clear()
    del ADCS[:]
    del TIMERS[:]
