# hw/cpy.py -- hardware backend for CircuitPython boards (pwmio, analogio).
#
# Hw(board): see docs/runtime.md ("hw/*.py"). Platform modules are imported
# here, never by the texel package: importing this module on CPython raises
# ImportError.
#
# CircuitPython has no interrupts, threads or viper: start() is not
# available (it raises NotImplementedError) and texel.app runs a paced loop
# instead (refresh.mode "loop": Refresh.step() every 1/hz s as far as the
# interpreter keeps up -- a reduced-rate profile).
#
# Carrier: pwmio.PWMOut(pin, frequency=freq, duty_cycle=0). duty_cycle is a
# 16-bit fraction; the raspberrypi port of CircuitPython 10.2.1 (ports/
# raspberrypi/common-hal/pwmio/PWMOut.c, set_frequency) programs
# TOP = cpu_hz // freq - 1 (125 MHz / 34 kHz -> 3675: TOP+1 = 3,676 clocks per
# period, 34,004.35 Hz - the emulated Pico's pin probe reads 34,004 Hz, tests/
# host/test_emulated_cpy.py) and compare = (duty*TOP + 32767) // 65534, so this
# backend reports top = cpu_hz // freq - 1 and freq_hz = cpu_hz // (TOP+1) as
# pwmio does, and sends duty = (counts*65534 + TOP//2) // TOP, which that
# rounding maps back to exactly `counts` for every count 0..TOP (TOP+1, full
# on, is duty 65535). (On other CircuitPython ports the count is approximate.)
# Only single drive: pwmio has no inverted or phase-locked outputs, so the
# complementary legs of a bridge cannot be made (ValueError); a bridge can be
# built with an external inverter on a single-drive pin.
# Sensor: analogio.AnalogIn(pin).value (already 0..65535, read_u16 units).

import pwmio
import analogio
import board as _pins



def _pin(p):
    # board pin from a GPIO number (16 -> board.GP16) or a name ("GP16", "A0")
    name = ("GP%d" % p) if isinstance(p, int) else p
    try:
        return getattr(_pins, name)
    except AttributeError:
        raise ValueError("pin %r: no board.%s on this board" % (p, name))


# The pins this VM has claimed, (kind, pin[, freq]) -> the pwmio/analogio
# object. A display stopped inside texel.app.serve() (Ctrl-C) stays in the same
# VM, so the next start must take over its pins: CircuitPython refuses a second
# PWMOut/AnalogIn on a pin in use ("GP26_A0 in use") until the old one is
# deinit()ed or the VM restarts.
_claimed = {}


def _claim(key, make):
    """The object claimed for `key`, else a new one from make(): a pin
    claimed under another key (another carrier frequency) is let go first."""
    got = _claimed.get(key)
    if got is not None:
        return got
    for k in list(_claimed):
        if k[1] == key[1]:
            _claimed.pop(k).deinit()
    got = _claimed[key] = make()
    return got


class Hw:
    def __init__(self, board):
        if board.get("port") != "circuitpython":
            raise ValueError("board %r: port is %r, hw/cpy drives 'circuitpython' boards"
                             % (board.get("name"), board.get("port")))
        c = board["carrier"]
        freq = int(c["freq_hz"])
        cpu = int(board["cpu_hz"])
        drive = c.get("drive", "single")
        pins = list(c["pins"])
        if drive != "single":
            raise ValueError("carrier.drive: CircuitPython supports 'single' only (pwmio has no "
                             "complementary outputs for %r); use an external inverter" % (drive,))
        if len(pins) != 1:
            raise ValueError("carrier.pins: single drive needs 1 pin, got %r" % (pins,))
        try:
            import microcontroller
            real = microcontroller.cpu.frequency
        except (ImportError, AttributeError):
            real = cpu
        if real != cpu:
            raise ValueError("cpu_hz: board says %d Hz but microcontroller.cpu.frequency is %d Hz "
                             "(PWM TOP depends on it)" % (cpu, real))
        top = cpu // freq - 1
        if not 1 <= top < 16383:
            raise ValueError("carrier.freq_hz: %d Hz gives TOP %d at %d Hz; supported 1..16382"
                             % (freq, top, cpu))
        cap = float(c.get("duty_cap", 0.5))
        self.top = top
        self.max_counts = int(cap * (top + 1))
        self.freq_hz = cpu // (top + 1)        # what pwmio makes (its actual_frequency)
        self.drive = drive
        self.pins = tuple(pins)
        self._half = top // 2
        self._pwm = _claim(("pwm", pins[0], freq),
                           lambda: pwmio.PWMOut(_pin(pins[0]), frequency=freq, duty_cycle=0))
        self._pwm.duty_cycle = 0
        s = board.get("sensor", {})
        self._adc = tuple(_claim(("adc", p), lambda p=p: analogio.AnalogIn(_pin(p)))
                          for p in s.get("pins", ()))

    # CircuitPython's microsecond clock allocates (compat.PACE_CLOCK): the
    # refresh times its body once in cost_every refreshes (Refresh.cost_every),
    # about once a second at 1000 Hz, so the paced loop seldom collects garbage
    cost_every = 1024

    def set_duty(self, counts):
        # counts: compare value 0..max_counts (clamped); small ints only
        if counts > self.max_counts:
            counts = self.max_counts
        elif counts < 0:
            counts = 0
        self._pwm.duty_cycle = (65535 if counts > self.top
                                else (counts * 65534 + self._half) // self.top)

    def off(self):
        """Safe state: duty 0 (the output low)."""
        self._pwm.duty_cycle = 0

    def adc_read(self, i):
        # AnalogIn.value is 16-bit already
        return self._adc[i].value

    def start(self, callback, hz):
        raise NotImplementedError("CircuitPython has no timer interrupts: run the refresh "
                                  "as a paced loop (refresh.mode 'loop', texel.app does)")

    def stop(self):
        """Duty 0. The pins stay claimed, the carrier driven low (a released
        pin would float at the gate driver's input); the next Hw in this VM
        takes them over (_claim), a VM restart frees them."""
        self.off()
