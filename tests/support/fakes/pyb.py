# A recording stand-in for MicroPython's `pyb` (stm32 port, pyboard F405),
# for tests of device/texel/hw/stm32.py under the MicroPython unix port and
# CPython (tests/support/fakes on the module path).
#
# Models what the backend relies on, after ports/stm32/timer.c and pin.c:
#   - Timer(n) is one object per id; init(freq= | prescaler=, period=,
#     deadtime=, callback=) programs PSC/ARR/BDTR in the register file shared
#     with the machine fake (TIM1 at 0x40010000, TIM8 at 0x40010400);
#   - channel(ch, Timer.PWM, pin=, pulse_width=) sets CCMR (PWM mode 1), the
#     CCR, CR2 idle states OISx = OISxN = 1 (pyb's TIM_OCIDLESTATE_SET),
#     CCER CCxE and, on TIM1/8 channels 1-3, CCxNE (pyb starts the
#     complementary output too) and sets BDTR.MOE (HAL_TIM_PWM_Start);
#   - Pin(name, mode, af=, value=) records the pin's mode/alternate function;
#   - level(pin, count) says what a pin outputs at a counter value, from the
#     registers (RM0090 "Output control bits for complementary OCx and OCxN
#     channels with break feature"; dead time not modelled);
#   - ADC(pin).read() returns scripted 12-bit values.
# Recording on the hot paths (TimerChannel.pulse_width, ADC.read) allocates
# nothing. Plain Python: no type hints, no f-strings.
import machine as _m

_REGS = _m.REGS
EVENTS = []


def _event(*args):
    EVENTS.append(args)


# ---------------------------------------------------------------- Pin
# pyboard v1.1 board names -> cpu pin names (the ones the tests use)
BOARD_PINS = {
    "X1": "A0", "X2": "A1", "X3": "A2", "X4": "A3", "X5": "A4", "X6": "A5", "X7": "A6",
    "X8": "A7", "X9": "B6", "X10": "B7", "X11": "C4", "X12": "C5", "X19": "C0", "X20": "C1",
    "X21": "C2", "X22": "C3", "Y1": "C6", "Y2": "C7", "Y3": "B8", "Y4": "B9", "Y5": "B12",
    "Y6": "B13", "Y7": "B14", "Y8": "B15", "Y9": "B10", "Y10": "B11", "Y11": "B0", "Y12": "B1",
}
# (cpu pin, alternate function) -> (timer, channel, complementary?) (STM32F405 datasheet, table 9)
TIMER_AF = {
    ("A8", 1): (1, 1, False), ("A7", 1): (1, 1, True), ("B13", 1): (1, 1, True),
    ("A9", 1): (1, 2, False), ("B0", 1): (1, 2, True), ("B14", 1): (1, 2, True),
    ("A10", 1): (1, 3, False), ("B1", 1): (1, 3, True), ("B15", 1): (1, 3, True),
    ("A11", 1): (1, 4, False),
    ("C6", 3): (8, 1, False), ("A5", 3): (8, 1, True), ("A7", 3): (8, 1, True),
    ("C7", 3): (8, 2, False), ("B0", 3): (8, 2, True), ("B14", 3): (8, 2, True),
    ("C8", 3): (8, 3, False), ("B1", 3): (8, 3, True), ("B15", 3): (8, 3, True),
    ("C9", 3): (8, 4, False),
}
ADC_PINS = ("A0", "A1", "A2", "A3", "A4", "A5", "A6", "A7", "B0", "B1", "C0", "C1", "C2",
            "C3", "C4", "C5")
PIN_STATE = {}              # cpu name -> {"mode": , "af": , "value": }


def cpu_name(name):
    if isinstance(name, Pin):
        return name._cpu
    if not isinstance(name, str):
        raise TypeError("fake pyb.Pin: expected a pin name, got %r" % (name,))
    n = BOARD_PINS.get(name, name)
    if n.startswith("P") and len(n) > 2:
        n = n[1:]                           # "PA7" -> "A7"
    if len(n) < 2 or n[0] not in "ABCDE" or not n[1:].isdigit():
        raise ValueError("Pin(%s) doesn't exist" % name)
    return n


class Pin:
    IN = 0
    OUT_PP = 1
    OUT_OD = 0x11
    AF_PP = 2
    AF_OD = 0x12
    ANALOG = 3
    PULL_NONE = 0
    PULL_UP = 1
    PULL_DOWN = 2
    AF1_TIM1 = 1
    AF1_TIM2 = 1
    AF2_TIM3 = 2
    AF2_TIM4 = 2
    AF2_TIM5 = 2
    AF3_TIM8 = 3
    AF3_TIM9 = 3

    def __init__(self, id, mode=None, pull=None, af=-1, value=None):
        self._cpu = cpu_name(id)
        self._name = id if isinstance(id, str) else self._cpu
        if mode is not None:
            self.init(mode, pull, af=af, value=value)

    def init(self, mode, pull=None, af=-1, value=None):
        st = PIN_STATE.get(self._cpu)
        if st is None:
            st = {"mode": None, "af": -1, "value": 0}
            PIN_STATE[self._cpu] = st
        if value is not None:               # pyb sets the output data before the mode
            st["value"] = 1 if value else 0
        st["mode"] = mode
        st["af"] = af
        _event("Pin.init", self._cpu, mode, af, value)

    def value(self, v=None):
        st = PIN_STATE.setdefault(self._cpu, {"mode": None, "af": -1, "value": 0})
        if v is None:
            return st["value"]
        st["value"] = 1 if v else 0

    def low(self):
        self.value(0)

    def high(self):
        self.value(1)

    def name(self):
        return self._cpu


# ---------------------------------------------------------------- Timer
SOURCE_FREQ = {1: 168000000, 8: 168000000, 9: 168000000, 10: 168000000, 11: 168000000}
APB1_TIMER_HZ = 84000000    # timers 2-7, 12-14
TIM_BASE = {1: _m.TIM1_BASE, 8: _m.TIM8_BASE}
CR1 = 0x00
CR2 = 0x04
CCMR1 = 0x18
CCMR2 = 0x1C
CCER = 0x20
PSC = 0x28
ARR = 0x2C
CCR1 = 0x34
BDTR = 0x44
MOE = 1 << 15
OSSR = 1 << 11
OSSI = 1 << 10

_TIMERS = {}


def timer(n):
    """The fake Timer object of id n (None if never made)."""
    return _TIMERS.get(n)


def _dtg(ticks):                            # as compute_dtg_from_ticks
    if ticks <= 0:
        return 0
    if ticks < 128:
        return ticks
    if ticks < 256:
        return 0x80 | ((ticks - 128) // 2)
    if ticks < 512:
        return 0xC0 | ((ticks - 256) // 8)
    if ticks < 1008:
        return 0xE0 | ((ticks - 512) // 16)
    return 0xFF


def deadtime_ticks(dtg):
    if dtg & 0x80 == 0:
        return dtg & 0x7F
    if dtg & 0xC0 == 0x80:
        return 128 + (dtg & 0x3F) * 2
    if dtg & 0xE0 == 0xC0:
        return 256 + (dtg & 0x1F) * 8
    return 512 + (dtg & 0x1F) * 16


class Timer:
    UP = 0
    DOWN = 0x10
    CENTER = 0x20
    PWM = 0
    PWM_INVERTED = 1
    OC_TIMING = 2
    OC_FORCED_INACTIVE = 7
    HIGH = 0
    LOW = 2
    BRK_OFF = 0
    BRK_LOW = 1
    BRK_HIGH = 2

    def __new__(cls, id, *args, **kw):
        t = _TIMERS.get(id)
        if t is None:
            t = object.__new__(cls)
            t._setup(id)
            _TIMERS[id] = t
        return t

    def _setup(self, id):
        if not 1 <= id <= 14:
            raise ValueError("Timer(%d) doesn't exist" % id)
        self.id = id
        self.inits = []                     # every init's keyword arguments
        self._prescaler = 0
        self._period = 0
        self._cb = None
        self.running = False
        self.fired = 0
        self.channels = {}
        # registers of TIM1/TIM8 live in the shared register file
        self._base = TIM_BASE.get(id)

    def __init__(self, id, freq=None, prescaler=None, period=None, mode=0, div=1,
                 callback=None, deadtime=0, brk=0):
        if freq is not None or prescaler is not None or period is not None:
            self.init(freq=freq, prescaler=prescaler, period=period, mode=mode, div=div,
                      callback=callback, deadtime=deadtime, brk=brk)

    def _reg(self, off):
        return self._base + off

    def source_freq(self):
        return SOURCE_FREQ.get(self.id, APB1_TIMER_HZ)

    def init(self, freq=None, prescaler=None, period=None, mode=0, div=1, callback=None,
             deadtime=0, brk=0):
        self.inits.append({"freq": freq, "prescaler": prescaler, "period": period,
                           "mode": mode, "callback": callback is not None,
                           "deadtime": deadtime, "brk": brk})
        if freq is not None:                # compute_prescaler_period_from_freq, int freq
            src = self.source_freq()
            p = 1
            per = src // freq
            while per > 0xFFFF:
                p <<= 1
                per = src // (freq * p)
            self._prescaler = p - 1
            self._period = per - 1
        elif prescaler is not None and period is not None:
            self._prescaler = prescaler
            self._period = period
        else:
            raise TypeError("must specify either freq, period, or prescaler and period")
        if self._period > 0xFFFF and self.id not in (2, 5):
            raise ValueError("period too large for a 16-bit timer")
        if deadtime and self._base is None:
            raise ValueError("deadtime is only available on timers 1 and 8")
        if self._base is not None:
            _REGS[self._reg(PSC)] = self._prescaler
            _REGS[self._reg(ARR)] = self._period
            _REGS[self._reg(BDTR)] = _dtg(deadtime)       # MOE, OSSI, OSSR = 0
            _REGS[self._reg(CR1)] = 0x81                  # CEN | ARPE
        self.deadtime = deadtime
        self._cb = callback
        self.running = True
        _event("Timer.init", self.id, self._prescaler, self._period, deadtime,
               callback is not None)

    def deinit(self):
        self._cb = None
        self.running = False
        self.channels = {}
        if self._base is not None:
            _REGS[self._reg(CCER)] = 0
            _REGS[self._reg(CR1)] = 0
        _event("Timer.deinit", self.id)

    def callback(self, fun):
        self._cb = fun

    def period(self, v=None):
        if v is None:
            return self._period
        self._period = v

    def prescaler(self, v=None):
        if v is None:
            return self._prescaler
        self._prescaler = v

    def freq(self):
        return self.source_freq() // ((self._prescaler + 1) * (self._period + 1))

    def fire(self, n=1):
        """Call the update callback n times (as the hard IRQ would)."""
        for _ in range(n):
            if self._cb is None or not self.running:
                break
            self.fired += 1
            self._cb(self)

    def channel(self, ch, mode=None, callback=None, pin=None, pulse_width=0,
                pulse_width_percent=None, compare=0, polarity=None):
        if mode is None:
            return self.channels.get(ch)
        if not 1 <= ch <= 4:
            raise ValueError("invalid channel (%d)" % ch)
        if pin is not None:
            p = pin if isinstance(pin, Pin) else Pin(pin)
            af = -1
            for (cpu, a), where in TIMER_AF.items():
                if cpu == p._cpu and where[0] == self.id:
                    af = a
            if af < 0:
                raise ValueError("Pin(%s) doesn't have an af for Timer(%d)" % (p._cpu, self.id))
            p.init(Pin.AF_PP, af=af)
        c = TimerChannel(self, ch, mode)
        self.channels[ch] = c
        if self._base is not None and mode in (Timer.PWM, Timer.PWM_INVERTED):
            ccmr = self._reg(CCMR1 if ch <= 2 else CCMR2)
            sh = 4 if ch in (1, 3) else 12
            ocm = 6 if mode == Timer.PWM else 7           # PWM mode 1 / 2
            _REGS[ccmr] = (_REGS[ccmr] & ~(7 << sh)) | (ocm << sh)
            _REGS[self._reg(CCR1 + 4 * (ch - 1))] = pulse_width
            k = ch - 1
            _REGS[self._reg(CR2)] = _REGS[self._reg(CR2)] | (3 << (8 + 2 * k))  # OIS=OISN=1
            ccer = 1 << (4 * k)
            if ch <= 3:
                ccer |= 4 << (4 * k)                      # complementary started too
            _REGS[self._reg(CCER)] = _REGS[self._reg(CCER)] | ccer
            _REGS[self._reg(BDTR)] = _REGS[self._reg(BDTR)] | MOE
        _event("Timer.channel", self.id, ch, mode, pulse_width)
        return c


class TimerChannel:
    def __init__(self, timer, ch, mode):
        self.timer = timer
        self.ch = ch
        self.mode = mode
        self.writes = 0
        self._pw = 0
        self._ccr = timer._reg(CCR1 + 4 * (ch - 1)) if timer._base is not None else None

    def pulse_width(self, v=None):
        if self._ccr is None:
            if v is None:
                return self._pw
            self._pw = v
            self.writes += 1
            return None
        if v is None:
            return _REGS[self._ccr]
        _REGS[self._ccr] = v & 0xFFFF
        self.writes += 1

    compare = pulse_width


# ---------------------------------------------------------------- output model
def _tim_output(tim_id, ch, comp, count):
    base = TIM_BASE[tim_id]
    k = ch - 1
    ccer = _REGS[base + CCER]
    bdtr = _REGS[base + BDTR]
    cr2 = _REGS[base + CR2]
    ce = (ccer >> (4 * k)) & 1
    cne = (ccer >> (4 * k + 2)) & 1
    ccr = _REGS[base + CCR1 + 4 * k]
    ccmr = _REGS[base + (CCMR1 if ch <= 2 else CCMR2)]
    ocm = (ccmr >> (4 if ch in (1, 3) else 12)) & 7
    ref = 1 if count < ccr else 0
    if ocm == 7:
        ref ^= 1
    elif ocm != 6:
        ref = 0
    if not (ce or cne):
        return None                         # output disabled: the pin floats
    if bdtr & MOE:
        if comp:
            if cne:
                return ref ^ 1
            return 0 if (bdtr & OSSR) else None
        if ce:
            return ref
        return 0 if (bdtr & OSSR) else None
    if not (bdtr & OSSI):
        return None                         # MOE = 0, OSSI = 0: not driven
    return (cr2 >> (8 + 2 * k + (1 if comp else 0))) & 1   # idle level OISx / OISxN


def level(pin, count):
    """What `pin` outputs at timer count `count`: 0/1, or None (floating)."""
    cpu = cpu_name(pin)
    st = PIN_STATE.get(cpu)
    if st is None:
        return None
    if st["mode"] in (Pin.OUT_PP, Pin.OUT_OD):
        return st["value"]
    if st["mode"] in (Pin.AF_PP, Pin.AF_OD):
        where = TIMER_AF.get((cpu, st["af"]))
        if where is None:
            return None
        return _tim_output(where[0], where[1], where[2], count)
    return None


def wave(pin, tim_id):
    per = _REGS[TIM_BASE[tim_id] + ARR]
    return [level(pin, c) for c in range(per + 1)]


# ---------------------------------------------------------------- ADC
ADC_VALUES = {}             # cpu pin -> list of scripted 12-bit values (cycled)
ADCS = []


def script_adc(pin, values):
    cpu = cpu_name(pin)
    ADC_VALUES[cpu] = list(values)
    for a in ADCS:
        if a.pin == cpu:
            a._values = ADC_VALUES[cpu]
            a._i = 0


class ADC:
    def __init__(self, pin):
        cpu = cpu_name(pin)
        if cpu not in ADC_PINS:
            raise ValueError("pin %s does not have ADC capabilities" % cpu)
        self.pin = cpu
        self._values = ADC_VALUES.get(cpu) or [0]
        self._i = 0
        self.reads = 0
        PIN_STATE[cpu] = {"mode": Pin.ANALOG, "af": -1, "value": 0}
        _event("ADC", cpu)
        ADCS.append(self)

    def read(self):
        v = self._values[self._i]
        self._i += 1
        if self._i >= len(self._values):
            self._i = 0
        self.reads += 1
        return v


def freq():
    return (168000000, 168000000, 42000000, 84000000)


def reset():
    for n in list(_TIMERS.keys()):
        del _TIMERS[n]
    PIN_STATE.clear()
    ADC_VALUES.clear()
    del ADCS[:]
    del EVENTS[:]
    _m.reset()
