# Boards as data: every board is a JSON file boards/<name>.json (schema in
# docs/runtime.md). This module finds, reads and checks them, and does the
# PWM arithmetic the backends share. It runs on MicroPython (rp2, stm32,
# unix), CircuitPython and CPython, only when a board is loaded (never in the
# refresh), so floats and allocation are fine here.
#
#   load(name, search=None)  -> canonical board dict (every default filled in)
#   names(search=None)       -> sorted names of the boards found
#   validate(d, source)      -> canonical dict, or ValueError
#                               "<source>: <key path>: <what is wrong>"
#   pwm_top(cpu_hz, freq_hz) -> PWM TOP (counts per carrier period - 1)
#   actual_hz(cpu_hz, top)   -> the carrier frequency that TOP really gives
#   board_top(board)         -> the TOP a board's port really programs
#
# Search path (first directory holding <name>.json wins): "/boards" (a board's
# flash root: `mpremote cp -r boards :`), "boards" (relative to the working
# directory), then last <texel package>/boards.d, where the repository, a
# wheel and the installed image (`texelpad deploy`, `mpremote mip install`:
# /lib/texel/boards.d/) keep the shipped boards, so a user's
# /boards/<name>.json still overrides them.
import json

# the checks every device validator shares (their words: gen/check.py)
from ..gen.check import rng, is_int, is_num, finite, fail

try:
    import os
except ImportError:                     # a port without os: load() still works
    os = None

# Carrier frequency limits, Hz. Piezo/glass friction plates resonate at some
# tens of kHz; outside 1 kHz .. 200 kHz the frequency is a typo.
FREQ_MIN_HZ = 1000
FREQ_MAX_HZ = 200000
FREQ_DEFAULT_HZ = 34000                 # the TPaD's carrier
# PWM counts per carrier period: the counters are 16 bit (RP2040 TOP, STM32
# ARR; no prescaler, which would cost resolution), so at most 65,536
# (pwm_top's limit). A board must also keep TOP <= 16,382: the backends
# build compare words (counts << 16, (TOP+1) << 16) that stay small ints
# (< 2^30) on 32-bit ports, so the refresh never allocates. At least 500
# counts keep ~9 bits of amplitude resolution and bound the frequency error
# of nearest-count rounding to 0.5/500 = 0.1 %. CircuitPython's pwmio floors
# TOP (an error of up to one count), so there the minimum is 1,000 counts.
COUNTS_MIN = 500
COUNTS_MAX = 65536
TOP_MAX = 16382
POSITIONS_MAX = 1048576                 # same bound as texel.params LENGTH_MAX
CPU_HZ_MIN = 1000000
CPU_HZ_MAX = 1000000000                 # < 2^30: a small int on every port
U16_MAX = 65535                         # amplitudes and read_u16 raw units

from ..compat import PORT_TABLE, PORTS, ROM, port_of
DRIVES = ("single", "bridge")
SENSOR_KINDS = ("adc_linear", "adc_ratio")
MODES = ("timer_irq", "core1_viper", "loop", "stepped")
# The refresh modes each port can run, its default first (compat.PORT_TABLE;
# docs/runtime.md, refresh/hw/*): CircuitPython has no IRQs, threads or viper;
# the virtual board steps time.
PORT_MODES = {}
DEFAULT_MODE = {}
for _p in PORTS:
    PORT_MODES[_p] = PORT_TABLE[_p]["modes"]
    DEFAULT_MODE[_p] = PORT_TABLE[_p]["modes"][0]

# Keys in a fixed order (MicroPython dicts are unordered): the order keys are
# checked in, so which bad key is named first is the same on every port.
# Entries: (key, kind, default); kind: "i" int, "n" number, "s" string,
# "d" dict, "p" pin list; default None = required, OPTIONAL = left out of
# the canonical dict when absent (the backend has its own default).
OPTIONAL = "(optional)"
TOP_KEYS = (("name", "s", None), ("port", "s", None), ("title", "s", ""),
            ("cpu_hz", "i", None), ("carrier", "d", None), ("sensor", "d", None),
            ("refresh", "d", {}), ("display", "d", {}), ("wiring", "s", ""),
            # the classroom kit (texel/kit.py): the button that steps a playlist
            # and the LED that shows it; rp2's defaults are BOOTSEL and "LED"
            ("button", "d", OPTIONAL), ("led", "d", OPTIONAL))
CARRIER_KEYS = (("freq_hz", "i", FREQ_DEFAULT_HZ), ("duty_cap", "n", 0.5),
                ("drive", "s", None), ("pins", "p", None), ("pwm", "d", {}),
                ("idle_amplitude", "i", 0),
                # stm32 bridge only: dead time between CHx and CHxN, ns
                # (hw/stm32's default: 200 ns)
                ("deadtime_ns", "i", OPTIONAL))
# Calibration defaults for a 100 mm membrane potentiometer on a 3.3 V ADC
# with a pull-down on the wiper (lifted finger reads ~0): measure per build.
SENSOR_KEYS = (("kind", "s", None), ("pins", "p", None),
               ("raw_at_start", "i", 2000), ("raw_at_end", "i", 63000),
               ("lift_below", "i", 1000), ("filter_shift", "i", 2),
               ("latency_us", "i", 150),
               # sensor.py's defaults: velocity IIR shift 4, lift after 3
               # consecutive no-finger samples
               ("velocity_shift", "i", 4), ("lift_debounce", "i", 3))
# refresh.timer: stm32 only, the pyb timer that runs the refresh (hw/stm32's
# default: 7, a basic timer without outputs)
REFRESH_KEYS = (("hz", "i", 8333), ("mode", "s", None), ("timer", "i", OPTIONAL))
DISPLAY_KEYS = (("positions", "i", 19200), ("dx_um", "n", 5.3))
# button/led pin: a GPIO number (rp2, virtual), a pin name (stm32 "B3",
# rp2 "LED"), or "bootsel" (rp2's button: rp2.bootsel_button()).
# active_low: a button wired to GND with the pin's pull-up (the usual), an
# LED wired from 3V3 (the Black Pill's C13)
BUTTON_KEYS = (("pin", "x", None), ("active_low", "i", 1))
LED_KEYS = (("pin", "x", None), ("active_low", "i", 0))
# pwm sub-dict keys per port: RP2040 slice (derived from the pin when
# missing), STM32 timer and channel; CircuitPython pwmio and the virtual
# board choose for themselves.
PWM_KEYS = {"rp2": (("slice", "i", -1),),
            "stm32": (("timer", "i", None), ("channel", "i", None)),
            "circuitpython": (), "virtual": ()}

CAL_SPAN_MIN = 256          # |raw_at_end - raw_at_start|, read_u16 units
FILTER_SHIFT_MAX = 8        # IIR time constant 2^8 refreshes = 31 ms at 8,333 Hz
LATENCY_US_MAX = 20000
REFRESH_HZ_MIN = 50
REFRESH_HZ_MAX = 50000
ADVANCED_TIMERS = (1, 8)    # STM32 TIM1, TIM8
DEADTIME_TICKS_MAX = 1008   # pyb.Timer(deadtime=...) accepts 0..1008 timer ticks
DX_UM_MAX = 1000.0
NAME_MAX = 32


# --- PWM arithmetic -----------------------------------------------------------
def pwm_top(cpu_hz, freq_hz):
    """TOP (= counts per carrier period - 1) of an edge-aligned PWM clocked
    at cpu_hz (the timer's input clock, Hz) for a carrier of freq_hz (Hz),
    rounded to the nearest count: RP2040 125 MHz / 34 kHz = 3,676.47 -> 3675;
    STM32F405 TIM1/TIM8 168 MHz / 34 kHz = 4,941.2 -> 4940. ValueError when
    the counts do not fit a 16-bit counter (or leave under 2 levels)."""
    if not is_int(cpu_hz) or cpu_hz <= 0:
        raise ValueError("cpu_hz: %r is not a positive int (Hz)" % (cpu_hz,))
    if not is_int(freq_hz) or freq_hz <= 0:
        raise ValueError("freq_hz: %r is not a positive int (Hz)" % (freq_hz,))
    counts = (cpu_hz + freq_hz // 2) // freq_hz
    if counts < 2 or counts > COUNTS_MAX:
        raise ValueError("freq_hz: %d Hz on a %d Hz clock gives %d PWM counts per period "
                         "(a 16-bit PWM needs 2 .. %d)" % (freq_hz, cpu_hz, counts, COUNTS_MAX))
    return counts - 1


def actual_hz(cpu_hz, top):
    """The carrier frequency (Hz, float) a PWM of TOP `top` really runs at."""
    return cpu_hz / (top + 1)


def board_top(board):
    """The TOP a (validated) board's PWM really runs with. MicroPython
    backends program the nearest count (pwm_top); CircuitPython's pwmio
    programs TOP = cpu_hz // freq_hz - 1 itself (10.2.1's raspberrypi port,
    common-hal/pwmio/PWMOut.c): 125 MHz / 34 kHz -> TOP 3675, 3,676 clocks
    per period, 34,004.35 Hz (hw/cpy.py)."""
    return _port_top(board["port"], board["cpu_hz"], board["carrier"]["freq_hz"])


def _port_top(port, cpu_hz, freq_hz):
    if port == "circuitpython":
        return cpu_hz // freq_hz - 1
    return (cpu_hz + freq_hz // 2) // freq_hz - 1


# --- finding and reading board files ----------------------------------------
def _norm_up(path, levels):
    """The directory `levels` levels above directory `path`, by string
    operations (MicroPython has no os.path, and ".." may not resolve on every
    VFS): "/a/device/texel" -> "/a"; "texel" -> "."; "." -> "../..".
    Above "/" stays "/"."""
    path = path.replace("\\", "/")
    absolute = path.startswith("/")
    parts = [p for p in path.split("/") if p and p != "."]
    for _ in range(levels):
        if parts and parts[-1] != "..":
            parts.pop()
        elif not absolute:
            parts.append("..")
    text = "/".join(parts)
    if absolute:
        return "/" + text
    return text or "."


# The shipped boards inside the texel package (<texel>/boards.d): the same
# place in the repository (device/texel/boards.d), in an installed wheel and
# on a board (/lib/texel/boards.d), so every copy finds them the same way.
PACKAGE_BOARDS_DIR = "boards.d"


def _installed_boards():
    """<texel package>/boards.d, or None without __file__ (frozen). This
    module is <texel>/runtime/boards.py, so the package is two levels up."""
    try:
        here = __file__
    except NameError:
        return None
    if ROM:
        from ..rom import data_beside
        here = data_beside(here)        # frozen (texelpad firmware): the ROMFS's copy
    pkg = _norm_up(here.replace("\\", "/"), 2)
    if pkg == ".":
        return PACKAGE_BOARDS_DIR
    return ("" if pkg == "/" else pkg) + "/" + PACKAGE_BOARDS_DIR


def search_path(search=None):
    """The directories looked in, in order (search: a directory or a list)."""
    if search is None:
        dirs = ["/boards", "boards"]
        inst = _installed_boards()
        if inst:
            dirs.append(inst)
    elif isinstance(search, str):
        dirs = [search]
    else:
        dirs = list(search)
    out = []
    for d in dirs:
        if not isinstance(d, str):
            raise ValueError("search: directories must be strings, got %r" % (d,))
        d = d.rstrip("/") or "/"
        if d not in out:
            out.append(d)
    return out


def _valid_name(name):
    if not isinstance(name, str) or not 0 < len(name) <= NAME_MAX:
        return False
    for ch in name:
        if not (("a" <= ch <= "z") or ("0" <= ch <= "9") or ch == "_" or ch == "-"):
            return False
    return True


def _file(d, name):
    return ("/" if d == "/" else d + "/") + name + ".json"


def names(search=None):
    """Sorted names of the boards (<name>.json) in the search path."""
    found = []
    if os is None:
        return found
    for d in search_path(search):
        try:
            entries = os.listdir(d)
        except OSError:
            continue
        for fn in entries:
            if fn.endswith(".json") and _valid_name(fn[:-5]) and fn[:-5] not in found:
                found.append(fn[:-5])
    found.sort()
    return found


# What each port's firmware calls itself (sys.platform; CircuitPython by its
# implementation name). Any other platform (the unix port, CPython) is a
# development host: there a board file fits only if its backend's modules
# import (a test puts stand-in machine/pyb/pwmio modules on the path) - or it is "virtual".
# (compat.PORT_TABLE's platform and chip columns.)
PLATFORM_PORT = {}
PORT_CHIP = {}
for _p in PORTS:
    if PORT_TABLE[_p]["platform"]:
        PLATFORM_PORT[PORT_TABLE[_p]["platform"]] = _p
    PORT_CHIP[_p] = PORT_TABLE[_p]["chip"]


def firmware_port():
    """The port this firmware is (rp2, stm32, circuitpython), or None on a
    development host (unix port, CPython)."""
    import sys
    return port_of(sys.implementation.name, sys.platform)


def fits(board):
    """None when this firmware can run `board` (a loaded board dict), else
    why not - one line naming the firmware. Only looks: no pin, timer or
    register is touched, so a running display is not disturbed."""
    import sys
    port = board["port"]
    if port == "virtual":
        return None
    here = firmware_port()
    fw = "%s on %r" % (sys.implementation.name, sys.platform)
    if here is not None:
        if here == port:
            return None
        return ("board file %r is for %s, but this board runs %s (%s)"
                % (board["name"], PORT_CHIP[port], fw, PORT_CHIP[here]))
    probe = PORT_TABLE[port]["probe"]   # a development host: the backend's modules?
    mod, _, attr = probe.partition(".")
    try:
        m = __import__(mod)
        if attr:
            getattr(m, attr)
    except (ImportError, AttributeError) as e:
        return ("board file %r is for %s, but this is %s (%s)"
                % (board["name"], PORT_CHIP[port], fw, e))
    return None


def fitting(check=None, search=None):
    """Names of the board files found that this firmware can run (check: a
    stricter fits(), e.g. texel.app's, which also imports the backend)."""
    out = []
    for n in names(search):
        try:
            if (check or fits)(load(n, search)) is None:
                out.append(n)
        except ValueError:              # a broken file fits nothing
            pass
    return out


def load(name, search=None):
    """Read and validate boards/<name>.json from the first directory of the
    search path that has it. ValueError when there is none, or when the file
    is not JSON or not a valid board (naming the file and the key)."""
    if not _valid_name(name):
        raise ValueError("board name %r: use 1..%d of a-z, 0-9, _ and -" % (name, NAME_MAX))
    dirs = search_path(search)
    for d in dirs:
        path = _file(d, name)
        try:
            f = open(path)
        except OSError:
            continue
        try:
            try:
                # loads(read()), not load(f): MicroPython's json.load reads a
                # stream a byte at a time (~40 ms for a 2 KB board file on a
                # stock Pico, inside main.py's power-up)
                doc = json.loads(f.read())
            except ValueError as e:
                raise ValueError("%s: not valid JSON (%s)" % (path, e))
        finally:
            f.close()
        return validate(doc, path)
    raise ValueError("board %r: no %s.json in %s (boards found: %s)"
                     % (name, name, ", ".join(dirs), ", ".join(names(dirs)) or "none"))


# --- validation -----------------------------------------------------------------
# c, in every check below: the head of its messages, "<source>: " (the file),
# so an error reads "<source>: <key path>: <what is wrong>" (gen/check.fail).
_KIND_NAMES = {"i": "an integer", "n": "a finite number", "s": "a string",
               "d": "an object", "p": "a list of pins", "x": "a pin (a number or a name)"}


def _section(c, path, d, keys):
    """Check d's keys and types against `keys`; return a new dict with the
    defaults filled in (deep-copied for dicts)."""
    if not isinstance(d, dict):
        fail(c + (path or "(top level)"), "expected an object, got %s" % _tname(d))
    known = [k[0] for k in keys]
    unknown = sorted([k for k in d if k not in known])
    if unknown:
        fail(c + _join(path, str(unknown[0])),
                 "unknown key (known: %s)" % (", ".join(known) or "none"))
    out = {}
    for key, kind, default in keys:
        p = _join(path, key)
        if key not in d:
            if default is None:
                fail(c + p, "missing (required)")
            if default is not OPTIONAL:
                out[key] = dict(default) if isinstance(default, dict) else default
            continue
        v = d[key]
        ok = ((kind == "i" and is_int(v)) or (kind == "n" and is_num(v) and finite(v))
              or (kind == "s" and isinstance(v, str)) or (kind == "d" and isinstance(v, dict))
              or (kind == "p" and isinstance(v, list))
              or (kind == "x" and (is_int(v) or (isinstance(v, str) and v != ""))))
        if not ok:
            fail(c + p, "expected %s, got %s" % (_KIND_NAMES[kind], _show(v)))
        out[key] = v
    return out


def _join(path, key):
    return key if not path else path + "." + key


def _tname(v):
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, dict):
        return "an object"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, str):
        return "a string"
    return "a number"


def _show(v):
    if isinstance(v, (dict, list)) or v is None or isinstance(v, bool):
        return _tname(v)
    return "%s %r" % (_tname(v), v)


def _range(c, path, v, lo, hi, unit=""):
    if v < lo or v > hi:
        fail(c + path, "%r%s is out of range %s" % (v, unit, rng(lo, hi)))


def _one_of(c, path, v, choices):
    if v not in choices:
        fail(c + path, "%r is not one of %s" % (v, ", ".join(choices)))


def _pins(c, path, pins, port, n, what, adc):
    """A pin list: n entries of the port's pin type. rp2: GPIO numbers
    (ADC: 26..29); stm32: pyb pin names ("Y1", "X19", "PC6");
    circuitpython: a GPIO number n (= board.GP<n>) or a board attribute name;
    virtual: small ints (labels)."""
    if len(pins) != n:
        fail(c + path, "%s needs %d pin%s, got %d" % (what, n, "" if n == 1 else "s", len(pins)))
    for i in range(n):
        v = pins[i]
        p = "%s[%d]" % (path, i)
        if port == "stm32" or (port == "circuitpython" and isinstance(v, str)):
            if not isinstance(v, str) or not v or " " in v:
                fail(c + p, "expected a pin name such as \"Y1\", got %s" % _show(v))
            continue
        if not is_int(v):
            fail(c + p, "expected a GPIO number, got %s" % _show(v))
        if port == "virtual":
            _range(c, p, v, 0, 255)
        elif adc:
            # RP2040 ADC0..ADC3 are GPIO 26..29 (GPIO 29 reads VSYS/3 on a Pico)
            _range(c, p, v, 26, 29)
        else:
            _range(c, p, v, 0, 29)


def validate(d, source="board"):
    """Check a board dict against the schema of docs/runtime.md and return a
    canonical copy with every default filled in. Errors name the source file
    and the key path: "boards/x.json: carrier.freq_hz: 500 is out of range
    [1000, 200000]"."""
    c = "%s: " % (source,)
    b = _section(c, "", d, TOP_KEYS)

    # name: must be the file's name, so load("pico") is the board "pico"
    name = b["name"]
    if not _valid_name(name):
        fail(c + "name", "%r: use 1..%d of a-z, 0-9, _ and -" % (name, NAME_MAX))
    stem = _stem(source)
    if stem is not None and stem != name:
        fail(c + "name", "%r does not match the file name (%s.json)" % (name, stem))
    port = b["port"]
    _one_of(c, "port", port, PORTS)
    if not b["title"]:
        b["title"] = name
    _range(c, "cpu_hz", b["cpu_hz"], CPU_HZ_MIN, CPU_HZ_MAX, " Hz")
    car = _carrier(c, b, port)
    _sensor(c, b, port, car["pins"])
    _refresh(c, b, port, car["freq_hz"])
    _display(c, b)
    _kit(c, b, port, car["pins"] + b["sensor"]["pins"])
    return b


def _kit(c, b, port, used):
    """b["button"] and b["led"] (the classroom kit, texel/kit.py) checked and
    made canonical when present: a pin of the port's kind, none of the
    carrier's or sensor's."""
    for key, keys in (("button", BUTTON_KEYS), ("led", LED_KEYS)):
        if key not in b:
            continue
        k = _section(c, key, b[key], keys)
        b[key] = k
        pin = k["pin"]
        p = key + ".pin"
        _range(c, key + ".active_low", k["active_low"], 0, 1)
        if port == "circuitpython":
            fail(c + key, "the kit's button runs beside a timer IRQ; CircuitPython's paced "
                     "loop has none (leave %r out)" % key)
        named = isinstance(pin, str)
        if port == "rp2" and named and pin != ("bootsel" if key == "button" else "LED"):
            fail(c + p, "%r: a GPIO number, or %r" % (pin, "bootsel" if key == "button" else "LED"))
        if port == "stm32" and not named:
            fail(c + p, "%r: a pin name such as \"B3\"" % (pin,))
        if port in ("rp2", "virtual") and not named:
            _range(c, p, pin, 0, 29 if port == "rp2" else 255)
        if pin in used:
            fail(c + p, "%r is a carrier, sensor or button pin (pins are compared as "
                     "written: \"Y1\" and \"C6\" are not known to be one)" % (pin,))
        used = used + [pin]             # the LED may not be the button's pin either


def _carrier(c, b, port):
    """b["carrier"] checked and made canonical (in b); returns it."""
    car = _section(c, "carrier", b["carrier"], CARRIER_KEYS)
    b["carrier"] = car
    freq = car["freq_hz"]
    _range(c, "carrier.freq_hz", freq, FREQ_MIN_HZ, FREQ_MAX_HZ, " Hz")
    top = _port_top(port, b["cpu_hz"], freq)
    least = COUNTS_MIN * (2 if port == "circuitpython" else 1)     # floored TOP: 2x
    if top < least - 1 or top > TOP_MAX:
        fail(c + "carrier.freq_hz", "%d Hz on the %d Hz clock (cpu_hz) gives PWM TOP %d; need "
                 "%d .. %d (>= %d counts for resolution and frequency accuracy; compare words "
                 "within small ints)" % (freq, b["cpu_hz"], top, least - 1, TOP_MAX, least))
    cap = car["duty_cap"]
    if not 0 < cap <= 0.5:
        # above 50 % the PWM fundamental (sin(pi*D)) falls again
        fail(c + "carrier.duty_cap", "%r is out of range (0, 0.5]" % (cap,))
    drive = car["drive"]
    _one_of(c, "carrier.drive", drive, DRIVES)
    if drive == "bridge" and port == "circuitpython":
        fail(c + "carrier.drive", "'bridge' needs an inverted (complementary) PWM output, which "
                 "CircuitPython's pwmio cannot make; use 'single'")
    pins = car["pins"]
    _pins(c, "carrier.pins", pins, port, 2 if drive == "bridge" else 1,
          "drive '%s'" % drive, False)
    car["pins"] = list(pins)
    _range(c, "carrier.idle_amplitude", car["idle_amplitude"], 0, U16_MAX)
    pwm = _section(c, "carrier.pwm", car["pwm"], PWM_KEYS[port])
    car["pwm"] = pwm
    if port == "rp2":
        # GPIO n is PWM slice (n >> 1) & 7, channel A (even n) or B (odd n)
        sl = (pins[0] >> 1) & 7
        if pwm["slice"] == -1:
            pwm["slice"] = sl
        elif pwm["slice"] != sl:
            fail(c + "carrier.pwm.slice", "%r, but GPIO %d is on PWM slice %d"
                     % (pwm["slice"], pins[0], sl))
        if drive == "bridge" and (pins[0] >> 1 != pins[1] >> 1 or pins[0] == pins[1]):
            fail(c + "carrier.pins", "%r: a bridge takes the two channels of one PWM slice "
                     "(GPIO 2k and 2k+1, e.g. [16, 17]); leg B is inverted" % (pins,))
    if "deadtime_ns" in car:
        ns = car["deadtime_ns"]
        if port != "stm32":
            fail(c + "carrier.deadtime_ns", "only stm32 timers (TIM1, TIM8) have a dead-time "
                     "generator; on %r the gate drivers provide it" % (port,))
        if drive != "bridge":
            fail(c + "carrier.deadtime_ns",
                 "applies to drive 'bridge' (complementary outputs) only")
        # ticks as hw/stm32 computes them (cpu_hz is the timer clock on stm32)
        if ns < 0:
            fail(c + "carrier.deadtime_ns", "%d ns: a dead time cannot be negative" % ns)
        ticks = (ns * (b["cpu_hz"] // 1000000) + 500) // 1000
        if ticks > DEADTIME_TICKS_MAX:
            fail(c + "carrier.deadtime_ns", "%d ns is %d ticks of the %d Hz timer clock; pyb "
                     "allows 0 .. %d" % (ns, ticks, b["cpu_hz"], DEADTIME_TICKS_MAX))
    if port == "stm32":
        # an advanced timer, TIM1 or TIM8: complementary outputs (CHx/CHxN,
        # channels 1..3), dead time, and the MOE safe-off state hw/stm32
        # relies on for either drive
        if pwm["timer"] not in ADVANCED_TIMERS:
            fail(c + "carrier.pwm.timer", "%r: the carrier needs an advanced timer, 1 or 8 "
                     "(complementary outputs, dead time, safe off state)" % (pwm["timer"],))
        _range(c, "carrier.pwm.channel", pwm["channel"], 1, 3 if drive == "bridge" else 4)
    return car


def _sensor(c, b, port, carrier_pins):
    """b["sensor"] checked and made canonical; no pin of the carrier's."""
    s = _section(c, "sensor", b["sensor"], SENSOR_KEYS)
    b["sensor"] = s
    kind = s["kind"]
    _one_of(c, "sensor.kind", kind, SENSOR_KINDS)
    _pins(c, "sensor.pins", s["pins"], port, 2 if kind == "adc_ratio" else 1,
          "kind '%s'" % kind, True)
    s["pins"] = list(s["pins"])
    for key in ("raw_at_start", "raw_at_end", "lift_below"):
        _range(c, "sensor." + key, s[key], 0, U16_MAX)
    a, e = s["raw_at_start"], s["raw_at_end"]
    if abs(e - a) < CAL_SPAN_MIN:
        fail(c + "sensor.raw_at_end", "%d is within %d of raw_at_start (%d): the calibration "
                 "span is too small" % (e, CAL_SPAN_MIN, a))
    if kind == "adc_linear" and s["lift_below"] > min(a, e):
        fail(c + "sensor.lift_below", "%d is above the calibrated range (%d .. %d): a finger "
                 "at the end would read as lifted" % (s["lift_below"], min(a, e), max(a, e)))
    _range(c, "sensor.filter_shift", s["filter_shift"], 0, FILTER_SHIFT_MAX)
    _range(c, "sensor.latency_us", s["latency_us"], 0, LATENCY_US_MAX, " us")
    _range(c, "sensor.velocity_shift", s["velocity_shift"], 0, FILTER_SHIFT_MAX)
    _range(c, "sensor.lift_debounce", s["lift_debounce"], 1, 1000)
    used = list(carrier_pins)
    for i in range(len(s["pins"])):
        if s["pins"][i] in used:
            fail(c + "sensor.pins[%d]" % i, "pin %r is already used" % (s["pins"][i],))
        used.append(s["pins"][i])


def _refresh(c, b, port, freq):
    """b["refresh"] checked and made canonical (freq: the carrier's, Hz)."""
    # the default rate: 8333 Hz, or the most a port's millisecond-paced loop runs
    hz = PORT_TABLE[port]["loop_hz"] or REFRESH_KEYS[0][2]
    r = _section(c, "refresh", b["refresh"],
                 (("hz", "i", hz), ("mode", "s", DEFAULT_MODE[port]), REFRESH_KEYS[2]))
    b["refresh"] = r
    _range(c, "refresh.hz", r["hz"], REFRESH_HZ_MIN, REFRESH_HZ_MAX, " Hz")
    if r["hz"] > freq:
        # the duty is latched once per carrier period: faster refreshes are lost
        fail(c + "refresh.hz", "%d Hz is faster than the carrier (%d Hz)" % (r["hz"], freq))
    _one_of(c, "refresh.mode", r["mode"], MODES)
    if r["mode"] not in PORT_MODES[port]:
        fail(c + "refresh.mode", "%r is not available on port %r (use %s)"
                 % (r["mode"], port, ", ".join(PORT_MODES[port])))
    most = PORT_TABLE[port]["loop_hz"]
    if r["mode"] == "loop" and most is not None and r["hz"] > most:
        # its paced loop counts milliseconds (compat.PACE_CLOCK)
        fail(c + "refresh.hz", "%d Hz: a paced loop on port %r refreshes at most %d times a "
                               "second (its clock counts milliseconds)" % (r["hz"], port, most))
    if "timer" in r:
        if port != "stm32":
            fail(c + "refresh.timer", "only stm32 boards choose the refresh timer (pyb.Timer id)")
        if r["timer"] < 1 or r["timer"] > 14 or r["timer"] in ADVANCED_TIMERS or r["timer"] == 2:
            # (TIM2: hw/stm32's microsecond clock for the refresh core)
            fail(c + "refresh.timer", "%r: need a pyb timer 1 .. 14 other than the carrier "
                     "timers 1 and 8 and TIM2 (the refresh's clock)" % (r["timer"],))


def _display(c, b):
    """b["display"] checked and made canonical."""
    disp = _section(c, "display", b["display"], DISPLAY_KEYS)
    b["display"] = disp
    _range(c, "display.positions", disp["positions"], 1, POSITIONS_MAX)
    dx = disp["dx_um"]
    if not 0 < dx <= DX_UM_MAX:
        fail(c + "display.dx_um", "%r is out of range (0, %r]" % (dx, DX_UM_MAX))


def _stem(source):
    if not isinstance(source, str) or not source.endswith(".json"):
        return None
    cut = max(source.rfind("/"), source.rfind("\\"))
    return source[cut + 1:-5]
