# Find a friction plate's resonance by sweeping the carrier frequency at a
# low amplitude and reading a pickup level (a small piezo disc glued to the
# plate, through an envelope detector, into a spare ADC pin: see
# hardware/README.md). Runs on MicroPython (the board) and CPython (tests).
#
# On a Pico (MicroPython >= 1.26), with texelpad's image on the board (texelpad deploy):
#   mpremote cp hardware/sweep.py :sweep.py
#   mpremote exec "import sweep; sweep.run('pico', pickup_pin=27)"
# prints "freq_hz level" lines, then the peak, the -3 dB bandwidth and Q.
# Set carrier.freq_hz in your board file to the peak.
#
# The core (sweep, analyse) takes callables, so another port (a pyboard's
# pyb.Timer, a signal generator on the bench) plugs in its own.
import math
import time

from texel.runtime.duty import duty_fraction

F_MIN_HZ = 1000
F_MAX_HZ = 200000
AMPLITUDE_MAX = 0.5         # of full drive: a sweep never needs more, and
                            # at resonance even 0.2 can mean 100+ V on the piezo


def _sleep_ms(ms):
    if hasattr(time, "sleep_ms"):
        time.sleep_ms(ms)
    else:                   # CPython
        time.sleep(ms / 1000.0)


def duty_for(amplitude, duty_cap=0.5):
    """PWM duty fraction (0..duty_cap) whose fundamental is `amplitude`
    (0..1) of the fundamental at duty_cap: the runtime's own law
    (texel.runtime.duty.duty_fraction), range-checked for a sweep."""
    if not 0.0 <= amplitude <= 1.0:
        raise ValueError("amplitude: %r is out of range [0, 1]" % (amplitude,))
    return duty_fraction(amplitude, duty_cap)


def sweep(set_carrier, read_level, f_lo, f_hi, step, settle_ms=30, samples=32, sleep_ms=None):
    """Step the carrier from f_lo to f_hi (Hz, inclusive) by step; at each
    frequency call set_carrier(freq_hz), wait settle_ms (the plate and the
    detector settle), then average `samples` calls of read_level() (ints).
    Returns [(freq_hz, level), ...]."""
    if not (F_MIN_HZ <= f_lo < f_hi <= F_MAX_HZ) or step <= 0:
        raise ValueError("sweep: need %d <= f_lo < f_hi <= %d and step > 0, got %r, %r, %r"
                         % (F_MIN_HZ, F_MAX_HZ, f_lo, f_hi, step))
    wait = sleep_ms or _sleep_ms
    out = []
    f = f_lo
    while f <= f_hi:
        set_carrier(f)
        wait(settle_ms)
        acc = 0
        for _ in range(samples):
            acc += read_level()
        out.append((f, acc // samples))
        f += step
    return out


def _cross(f0, l0, f1, l1, level):
    # frequency where the straight line (f0, l0)-(f1, l1) reaches level
    if l1 == l0:
        return f0
    return f0 + (f1 - f0) * (level - l0) / (l1 - l0)


def analyse(points):
    """Peak and -3 dB bandwidth of a sweep's (freq_hz, level) points. The
    level of an envelope detector is proportional to the vibration amplitude,
    so -3 dB is 1/sqrt(2) of the peak height above the sweep's floor.
    Returns {"f0_hz", "level", "floor", "bw_hz", "q"} (bw_hz and q None when
    the sweep does not reach -3 dB on both sides of the peak). The floor is
    the sweep's lowest level: sweep well beyond the peak (+-20 % or more) or
    the resonance's own skirts count as floor and Q comes out too high."""
    n = len(points)
    if n < 3:
        raise ValueError("analyse: need at least 3 points, got %d" % n)
    levels = [p[1] for p in points]
    floor = min(levels)
    k = 0
    for i in range(n):
        if levels[i] > levels[k]:
            k = i
    f0 = float(points[k][0])
    if 0 < k < n - 1:
        # parabola through the peak and its neighbours (equal steps)
        a, b, c = levels[k - 1], levels[k], levels[k + 1]
        den = a - 2 * b + c
        if den != 0:
            f0 += 0.5 * (a - c) / den * (points[k + 1][0] - points[k][0])
    height = levels[k] - floor
    res = {"f0_hz": f0, "level": levels[k], "floor": floor, "bw_hz": None, "q": None}
    if height <= 0:
        return res
    half = floor + height / math.sqrt(2.0)
    lo = hi = None
    for i in range(k, 0, -1):
        if levels[i - 1] < half:
            lo = _cross(points[i - 1][0], levels[i - 1], points[i][0], levels[i], half)
            break
    for i in range(k, n - 1):
        if levels[i + 1] < half:
            hi = _cross(points[i][0], levels[i], points[i + 1][0], levels[i + 1], half)
            break
    if lo is not None and hi is not None and hi > lo:
        res["bw_hz"] = hi - lo
        res["q"] = f0 / (hi - lo)
    return res


def run(board="pico", pickup_pin=27, f_lo=20000, f_hi=60000, step=100, amplitude=0.2,
        settle_ms=30, samples=32):
    """Sweep on an rp2 board (machine.PWM; a bridge board's leg B inverted)
    with the carrier pins of boards/<board>.json, reading the pickup's
    envelope on ADC pin `pickup_pin`. The carrier is off when this returns,
    also after an error or Ctrl-C."""
    from machine import ADC, PWM, Pin
    from texel.runtime import boards
    b = boards.load(board)
    car = b["carrier"]
    if amplitude > AMPLITUDE_MAX:
        raise ValueError("amplitude: %r is above %r (a sweep needs little)" % (amplitude,
                                                                               AMPLITUDE_MAX))
    duty_u16 = int(duty_for(amplitude, car["duty_cap"]) * 65535 + 0.5)
    if pickup_pin in car["pins"] or pickup_pin in b["sensor"]["pins"]:
        raise ValueError("pickup_pin: GPIO %d is already used by the board" % pickup_pin)
    adc = ADC(Pin(pickup_pin))
    legs = [PWM(Pin(car["pins"][0]), freq=f_lo, duty_u16=0)]
    if car["drive"] == "bridge":
        legs.append(PWM(Pin(car["pins"][1]), freq=f_lo, duty_u16=0, invert=True))

    def set_carrier(f):
        for leg in legs:
            leg.freq(f)
            leg.duty_u16(duty_u16)

    try:
        pts = sweep(set_carrier, adc.read_u16, f_lo, f_hi, step, settle_ms, samples)
    finally:
        # duty 0 (an inverted leg at duty 0 is high), then every carrier
        # pin a plain output driven low: the gate drivers' inputs are off
        for leg in legs:
            leg.duty_u16(0)
            leg.deinit()
        for n in car["pins"]:
            Pin(n, Pin.OUT, value=0)
    for f, lev in pts:
        print(f, lev)
    res = analyse(pts)
    print("peak %.0f Hz (level %d, floor %d)" % (res["f0_hz"], res["level"], res["floor"]))
    if res["q"] is None:
        print("-3 dB not reached on both sides: widen the sweep or lower the step")
    else:
        print("-3 dB bandwidth %.0f Hz, Q = %.1f" % (res["bw_hz"], res["q"]))
    return res
