"""What is wrong with a maker's board file, for the firmware and chip it will
run on (`texelpad board check`, `texelpad board install`). Pure: no link.

    read_board(text)                     -> (doc, [Problem]) - JSON, one clear line if not
    check(doc, firmware="stock", file_stem=None) -> Report: every problem found

The board's own validation (texel.runtime.boards.validate, the code the
board runs) is the authority on the schema; it stops at the first problem,
so it is run again after removing what it refused wherever that cannot
change the verdict on anything else (an unknown key; a key with a default
that only a range check of its own reads: INDEPENDENT). The hardware facts
below (which GPIO exists, which pin is on which PWM slice or timer channel,
which pins have an ADC, which clocks the chip makes) are checked beside it,
each only on values of the right type and only where validate did not
already refuse what the fact depends on. A problem found by both at the same
key path is reported once, in the words that say what to do.
"""
from __future__ import annotations

import difflib
import json
from dataclasses import dataclass, field
from typing import Any, TypeGuard

from texel.runtime import boards

FIRMWARES = ("stock", "texelpad")
FIRMWARE_TEXT = {
    "stock": "stock firmware (MicroPython >= 1.26, or CircuitPython) with texelpad deploy",
    # boards/pico, boards/pico_bridge: MicroPython v1.28 + ulab for the Pico, texelpad in ROMFS;
    # boards/pyboard: MicroPython v1.28 for the pyboard v1.1 (STM32F405), texelpad frozen in
    "texelpad": "the texelpad firmware (MicroPython v1.28 + ulab for the Raspberry Pi Pico, "
                "RP2040; MicroPython v1.28 for the pyboard v1.1, STM32F405)",
}
FILE_BYTES_MAX = 65536      # a board file is a few KB; the board json.load()s it whole
READ_BYTES_MAX = 1 << 20    # read (and parsed, for a better diagnosis) up to this

# --- RP2040 (RP2040 datasheet, Raspberry Pi Ltd) ----------------------------------------
RP2040: dict[str, Any] = {
    # 1.4.3 "GPIO Functions" / 2.19 "GPIO": user bank GPIO0 .. GPIO29
    "gpio": range(0, 30),
    # 4.5 "PWM": 8 slices of 2 channels; 4.5.2 "Programmer's Model" (the GPIO -> PWM
    # table): GPIO n is slice (n >> 1) & 7, channel A when n is even, B when odd
    "pwm_slices": 8,
    # 4.9 "ADC and Temperature Sensor": inputs 0..3 are GPIO26..29 (input 4: the sensor)
    "adc": {26: 0, 27: 1, 28: 2, 29: 3},
    # 2.16 "Crystal Oscillator (XOSC)": 12 MHz on the Pico (pico-sdk XOSC_HZ);
    # 2.18 "PLL", "Calculating PLL parameters": REFDIV 1, FBDIV 16..320, VCO 750..1600 MHz,
    # POSTDIV1 and POSTDIV2 1..7 (pico-sdk check_sys_clock_khz: POSTDIV2 <= POSTDIV1)
    "xosc_khz": 12000, "fbdiv": (16, 320), "vco_khz": (750000, 1600000), "postdiv": 7,
    # 1 "Introduction": "Dual ARM Cortex-M0+ @ 133MHz"; the 2025 revision certifies
    # 200 MHz with the core at 1.15 V, which MicroPython's machine.freq() does not set
    "rated_hz": 133000000, "certified_hz": 200000000,
    # pico-sdk platform_defs.h SYS_CLK_HZ: what MicroPython's rp2 port (main.c,
    # set_sys_clock_khz(SYS_CLK_KHZ)) starts an RP2040 at; texelpad never changes it
    "boot_hz": 125000000,
}
# Raspberry Pi Pico datasheet, "Pinout" and "Powerchain": the header has GP0..GP22 and
# GP26..GP28; the others are wired on the board.
PICO: dict[str, Any] = {
    "header": tuple(range(0, 23)) + (26, 27, 28),
    "internal": {23: "drives the SMPS power-save pin (PS)", 24: "senses VBUS",
                 25: "drives the on-board LED", 29: "reads VSYS/3 (ADC3: the supply)"},
}

# --- STM32F405 (pyboard v1.x) -----------------------------------------------------------
# STM32F405 datasheet, "Alternate function mapping" (MicroPython
# ports/stm32/boards/stm32f405_af.csv): the advanced timers' outputs
F405_TIMER_PINS = {
    (1, 1): ("PA8", "PE9"), (1, 2): ("PA9", "PE11"), (1, 3): ("PA10", "PE13"),
    (1, 4): ("PA11", "PE14"),
    (1, -1): ("PA7", "PB13", "PE8"), (1, -2): ("PB0", "PB14", "PE10"),
    (1, -3): ("PB1", "PB15", "PE12"),
    (8, 1): ("PC6", "PI5"), (8, 2): ("PC7", "PI6"), (8, 3): ("PC8", "PI7"), (8, 4): ("PC9", "PI2"),
    (8, -1): ("PA5", "PA7", "PH13"), (8, -2): ("PB0", "PB14", "PH14"),
    (8, -3): ("PB1", "PB15", "PH15"),
}                                               # channel -n: the complementary CHnN
# same table: ADC123_IN0..15 (ADC3-only PF3..PF10 are not on a pyboard)
F405_ADC = ("PA0", "PA1", "PA2", "PA3", "PA4", "PA5", "PA6", "PA7", "PB0", "PB1",
            "PC0", "PC1", "PC2", "PC3", "PC4", "PC5", "PF3", "PF4", "PF5", "PF6", "PF7",
            "PF8", "PF9", "PF10")
# MicroPython ports/stm32/boards/PYBV11/pins.csv: the pyboard v1.1's header names
PYBV11_PINS = {
    "X1": "PA0", "X2": "PA1", "X3": "PA2", "X4": "PA3", "X5": "PA4", "X6": "PA5", "X7": "PA6",
    "X8": "PA7", "X9": "PB6", "X10": "PB7", "X11": "PC4", "X12": "PC5", "X17": "PB3",
    "X18": "PC13", "X19": "PC0", "X20": "PC1", "X21": "PC2", "X22": "PC3",
    "Y1": "PC6", "Y2": "PC7", "Y3": "PB8", "Y4": "PB9", "Y5": "PB12", "Y6": "PB13",
    "Y7": "PB14", "Y8": "PB15", "Y9": "PB10", "Y10": "PB11", "Y11": "PB0", "Y12": "PB1",
}
PYBV11_USED = {"PA8": "the SD card switch", "PA9": "USB VBUS sense", "PA10": "USB ID",
               "PA11": "USB D-", "PA12": "USB D+", "PC8": "SD card D0", "PC9": "SD card D1"}
F405_TIM18_HZ = 168000000       # TIM1/TIM8 on APB2: 2 x 84 MHz (pyboard.json's wiring)
# CircuitPython on an RP2040 runs at 125 MHz (microcontroller.cpu.frequency)
CPY_RP2040_HZ = 125000000

# Keys validate reads only for a range or type check of their own, with a default: when
# it refuses one, validating again without it cannot hide or invent another problem.
INDEPENDENT = ("title", "wiring", "carrier.duty_cap", "carrier.idle_amplitude",
               "carrier.pwm.slice", "sensor.filter_shift", "sensor.latency_us",
               "sensor.velocity_shift", "sensor.lift_debounce", "display.positions",
               "display.dx_um")
# texel.app._checked_board refuses it at start although the schema has it
UNBUILT_MODES = {"core1_viper": "is not implemented yet (texel.app refuses it at start): use "
                                "'timer_irq' (a hard timer IRQ on core 0) or 'loop'"}


@dataclass
class Problem:
    path: str                   # the key path ("carrier.pins[1]"); "" for the whole file
    message: str                # what is wrong and what to do
    level: str = "error"        # or "warning" (does not refuse the file)

    def line(self, source: str) -> str:
        where = "%s: " % self.path if self.path else ""
        return "%s: %s%s%s" % (source, "warning: " if self.level == "warning" else "",
                               where, self.message)


@dataclass
class Report:
    problems: list[Problem] = field(default_factory=list)
    board: dict[str, Any] | None = None         # validate's canonical dict when valid
    firmware: str = "stock"

    @property
    def errors(self) -> list[Problem]:
        return [p for p in self.problems if p.level == "error"]

    @property
    def warnings(self) -> list[Problem]:
        return [p for p in self.problems if p.level == "warning"]

    @property
    def ok(self) -> bool:
        return not self.errors and self.board is not None


_KIND = {list: "a list", str: "a string", int: "a number", float: "a number", bool: "a boolean",
         type(None): "null"}


# --- reading ---------------------------------------------------------------------------

class _Huge(ValueError):
    pass


def _int(text: str) -> int:
    if len(text) > 40:          # beyond any board value (and Python's int->str limit)
        raise _Huge(text[:12])
    return int(text)


def _constant(name: str) -> Any:
    raise ValueError("%s is not a JSON number (nor does the board's json read it)" % name)


def read_board(data: bytes | str) -> tuple[Any, list[Problem]]:
    """(the board file's JSON value, warnings), or (None, [one error]) when
    it is not JSON: too large, not UTF-8, not JSON, nested too deeply. A key given twice
    is a warning (the last one counts, as on the board)."""
    too_big = [Problem("", "%s bytes: a board file is a few KB (the board reads it whole); "
                           "at most %s" % (format(len(data), ","), format(FILE_BYTES_MAX, ",")))]
    if len(data) > READ_BYTES_MAX:
        return None, too_big
    if isinstance(data, bytes):
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            return None, [Problem("", "not UTF-8 text (byte %d): save it as UTF-8 JSON"
                                      % e.start)]
    else:
        text = data
    if text.startswith("\ufeff"):
        text = text[1:]
    if not text.strip():
        return None, [Problem("", "empty: a board file is a JSON object (see "
                                  "device/texel/boards.d/pico.json)")]
    twice: list[str] = []

    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in items:
            if k in out and k not in twice:
                twice.append(k)
            out[k] = v
        return out
    try:
        doc = json.loads(text, parse_int=_int, parse_constant=_constant,
                         object_pairs_hook=pairs)
    except json.JSONDecodeError as e:
        return None, [Problem("", "not valid JSON: %s (line %d, column %d)"
                                  % (e.msg, e.lineno, e.colno))]
    except _Huge as e:
        return None, [Problem("", "an integer of more than 40 digits (%s...): no board value "
                                  "is that large" % e)]
    except ValueError as e:
        return None, [Problem("", "not valid JSON: %s" % e)]
    except RecursionError:
        return None, [Problem("", "nested too deeply to be a board file (it is 3 levels "
                                  "deep: {\"carrier\": {\"pwm\": {...}}})")]
    if len(data) > FILE_BYTES_MAX:
        return None, too_big
    probs = [Problem("", "key %r appears more than once in an object; the last one counts: "
                         "keep one" % k, "warning") for k in twice]
    return doc, probs


# --- the checks ------------------------------------------------------------------------

def _is_int(v: Any) -> TypeGuard[int]:
    return isinstance(v, int) and not isinstance(v, bool)


def _get(d: Any, path: str) -> Any:
    """d["a"]["b"] for "a.b"; None when any part is missing or not an object."""
    for k in path.split("."):
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def _within(refused: str, dep: str) -> bool:
    """Whether validate's refusal at `refused` is about what a hardware check
    read at `dep`: the same key or a part of it ("carrier.pwm.timer" within
    "carrier.pwm"). A refusal of a whole list or section ("carrier.pins: a
    bridge takes ...") leaves its well-typed items to the hardware checks."""
    if not refused or not dep:
        return False
    return refused == dep or refused.startswith(dep + ".") or refused.startswith(dep + "[")


def _sections(port: Any) -> dict[str, tuple]:
    out = {"": boards.TOP_KEYS, "carrier": boards.CARRIER_KEYS, "sensor": boards.SENSOR_KEYS,
           "refresh": boards.REFRESH_KEYS, "display": boards.DISPLAY_KEYS}
    if port in boards.PWM_KEYS:
        out["carrier.pwm"] = boards.PWM_KEYS[port]
    return out


def _unknown_keys(doc: dict[str, Any]) -> tuple[dict[str, Any], list[Problem]]:
    """A copy of doc without the keys the schema does not know, and a
    problem for each (with the nearest known key)."""
    clean = json.loads(json.dumps(doc))
    probs = []
    for path, keys in _sections(doc.get("port")).items():
        sec = _get(clean, path) if path else clean
        if not isinstance(sec, dict):
            continue
        known = [k[0] for k in keys]
        for k in sorted(k for k in sec if k not in known):
            near = difflib.get_close_matches(k, known, 1)
            hint = ("did you mean %r? " % near[0]) if near else ""
            probs.append(Problem(_join(path, k), "unknown key: %sremove it (known: %s)"
                                 % (hint, ", ".join(known) or "none for this port")))
            del sec[k]
    return clean, probs


def _join(path: str, key: str) -> str:
    return key if not path else path + "." + key


def _delete(d: dict[str, Any], path: str) -> None:
    *head, last = path.split(".")
    for k in head:
        d = d[k]
    del d[last]


_SOURCE = "(board file)"


def _validate_all(doc: dict[str, Any]) -> tuple[dict[str, Any] | None, list[Problem]]:
    """validate() again and again, each time without the INDEPENDENT key it
    refused; stops at a refusal that other checks depend on."""
    d = json.loads(json.dumps(doc))
    probs: list[Problem] = []
    for _ in range(len(INDEPENDENT) + 1):
        try:
            return boards.validate(d, _SOURCE), probs
        except ValueError as e:
            text = str(e)
            if text.startswith(_SOURCE + ": "):
                text = text[len(_SOURCE) + 2:]
            path, sep, msg = text.partition(": ")
            if not sep:
                path, msg = "", text
            if path == "(top level)":
                path = ""
            probs.append(Problem(path, msg))
            if path not in INDEPENDENT or _get(d, path) is None:
                return None, probs
            _delete(d, path)
    return None, probs


def check(doc: Any, firmware: str = "stock", file_stem: str | None = None) -> Report:
    """Every problem of board file `doc` for `firmware` (FIRMWARES): the
    board's own validation and the chip's facts. file_stem: the name of the
    file it was read from (without .json), which the board requires to be
    its "name" once it is in /boards (a warning here: `texelpad board
    install` names it)."""
    rep = Report(firmware=firmware)
    if firmware not in FIRMWARES:
        raise ValueError("firmware %r: one of %s" % (firmware, ", ".join(FIRMWARES)))
    if not isinstance(doc, dict):
        rep.problems.append(Problem("", "a board file is a JSON object {\"name\": ..., "
                                        "\"port\": ..., ...}, not %s"
                                        % _KIND.get(type(doc), "that")))
        return rep
    clean, unknown = _unknown_keys(doc)
    board, refused = _validate_all(clean)
    hard = _hardware(clean, firmware)
    # a hardware check whose inputs validate refused is left out; one at the same key
    # path as validate's refusal says the same thing, with what to do: it replaces it
    blocked = [p.path for p in refused]
    kept_hw = [p for p, deps in hard
               if not any(_within(b, dep) for b in blocked for dep in deps if b != p.path)]
    kept_paths = {p.path for p in kept_hw if p.level == "error"}
    probs = unknown + [p for p in refused if p.path not in kept_paths]
    probs += kept_hw
    name = doc.get("name")
    if file_stem is not None and isinstance(name, str) and file_stem != name:
        probs.append(Problem("name", "%r is not the file's name (%s.json): texelpad board "
                                     "install puts it on the board as %s.json; copied by "
                                     "hand it must be named %s.json" % (name, file_stem, name,
                                                                         name), "warning"))
    rep.problems = _ordered(probs)
    rep.board = board if not rep.errors else None
    return rep


_ORDER = ("", "name", "port", "title", "cpu_hz", "carrier", "sensor", "refresh", "display",
          "wiring")


def _ordered(probs: list[Problem]) -> list[Problem]:
    def key(p: Problem) -> tuple:
        head = p.path.split(".")[0].split("[")[0]
        return (_ORDER.index(head) if head in _ORDER else len(_ORDER), p.path)
    seen, out = set(), []
    for p in sorted(probs, key=key):
        if (p.path, p.message) not in seen:
            seen.add((p.path, p.message))
            out.append(p)
    return out


# each hardware problem with the key paths it was computed from
_Found = list[tuple[Problem, tuple[str, ...]]]


def _hardware(d: dict[str, Any], firmware: str) -> _Found:
    found: _Found = []
    port: Any = d.get("port")           # unchecked here: a board file's own value
    if firmware == "texelpad" and port not in ("rp2", "stm32", "virtual"):
        found.append((Problem("port", "%r: %s runs 'rp2' and 'stm32' board files (or "
                                      "'virtual'); for this "
                                      "board use --firmware stock" % (port, FIRMWARE_TEXT[
                                          "texelpad"])), ("port",)))
    if firmware == "texelpad" and port == "stm32" and _is_int(d.get("cpu_hz")) \
            and d.get("cpu_hz") != F405_TIM18_HZ:
        # boards/pyboard is the one STM32 texelpad firmware (an F411's 512 KB do not hold it:
        # hardware/README.md, "STM32 boards")
        found.append((Problem("cpu_hz", "%s Hz: the texelpad firmware for STM32 is built for the "
                                        "pyboard's STM32F405 (TIM1/8 at %s Hz) only; for this "
                                        "board use --firmware stock"
                                        % (_n(d["cpu_hz"]), _n(F405_TIM18_HZ))), ("cpu_hz",)))
    pins = _get(d, "carrier.pins")
    sens = _get(d, "sensor.pins")
    pins = pins if isinstance(pins, list) else []
    sens = sens if isinstance(sens, list) else []
    gpio_port = port == "rp2" or (port == "circuitpython"
                                  and any(_is_int(p) for p in pins + sens))
    if gpio_port:
        _rp2_pins(found, d, pins, sens, port, firmware)
    if port == "rp2":
        _rp2_clock(found, d, firmware)
    if port == "stm32":
        _stm32(found, d, pins, sens)
    if port == "circuitpython" and gpio_port:
        cpu = d.get("cpu_hz")
        if _is_int(cpu) and cpu != CPY_RP2040_HZ:
            found.append((Problem("cpu_hz", "%s Hz: CircuitPython runs an RP2040 (board.GP<n> "
                                            "pins) at %s Hz and hw/cpy refuses to start when "
                                            "microcontroller.cpu.frequency differs: set %d"
                                            % (_n(cpu), _n(CPY_RP2040_HZ), CPY_RP2040_HZ),
                                  "warning"), ("cpu_hz",)))
    if port in boards.PORTS:
        _counts(found, d, port)
    mode = _get(d, "refresh.mode")
    if isinstance(mode, str) and mode in UNBUILT_MODES:
        found.append((Problem("refresh.mode", "%r %s" % (mode, UNBUILT_MODES[mode])),
                      ("refresh.mode",)))
    return found


def _n(v: int) -> str:
    return format(v, ",")


def _rp2_pins(found: _Found, d: dict[str, Any], pins: list[Any], sens: list[Any], port: str,
              firmware: str) -> None:
    pico = firmware == "texelpad"
    on = ("the header of the Pico the texelpad firmware is built for" if pico
          else "a Raspberry Pi Pico's header")
    owners: dict[int, str] = {}
    for sensor, lst in ((False, pins), (True, sens)):
        for i, g in enumerate(lst):
            if not _is_int(g):
                continue
            path = "%s[%d]" % ("sensor.pins" if sensor else "carrier.pins", i)
            deps = (path,)
            if g not in RP2040["gpio"]:
                found.append((Problem(path, "GPIO %d does not exist: the RP2040 has GPIO 0 .. 29 "
                                            "(%s)" % (g, "use an ADC pin, 26 .. 29" if sensor
                                                      else "use a PWM pin on the header, e.g. "
                                                           "16")), deps))
                continue
            if g in owners:
                found.append((Problem(path, "GPIO %d is also %s: a pin does one job; wire this "
                                            "one to another pin" % (g, owners[g])), deps))
            else:
                owners[g] = path
            if sensor and g not in RP2040["adc"]:
                found.append((Problem(path, "GPIO %d has no ADC: the RP2040's ADC inputs are "
                                            "GPIO 26 .. 29 (ADC0 .. ADC3); wire the sensor to "
                                            "26, 27 or 28" % g), deps))
            elif g in PICO["internal"]:
                found.append((Problem(path, "GPIO %d is not on %s: there it %s; fine "
                                            "only on an RP2040 board that brings it out"
                                            % (g, on, PICO["internal"][g]), "warning"), deps))
    if port != "rp2":
        return
    ints = [g for g in pins if _is_int(g) and g in RP2040["gpio"]]
    if len(ints) != len(pins) or not pins:
        return
    a = pins[0]
    sl, ch = (a >> 1) & 7, "AB"[a & 1]
    want = _get(d, "carrier.pwm.slice")
    if _is_int(want) and want != -1 and want != sl:
        found.append((Problem("carrier.pwm.slice", "%d, but GPIO %d is PWM slice %d channel %s "
                                                   "(RP2040 datasheet 4.5.2): set \"slice\": %d, "
                                                   "or leave it out (it follows carrier.pins[0])"
                                                   % (want, a, sl, ch, sl)),
                      ("carrier.pwm.slice", "carrier.pins[0]")))
    if _get(d, "carrier.drive") == "bridge" and len(pins) == 2:
        b = pins[1]
        sb, cb = (b >> 1) & 7, "AB"[b & 1]
        if (sb, cb) == (sl, ch):
            why = ("GPIO %d and GPIO %d are the same output (slice %d channel %s)"
                   % (a, b, sl, ch) if a != b else "both legs are GPIO %d" % a)
        elif sb != sl:
            why = ("GPIO %d is slice %d channel %s, GPIO %d is slice %d channel %s"
                   % (a, sl, ch, b, sb, cb))
        else:
            why = None
        if why:
            pair = [a & ~1, a | 1]
            found.append((Problem("carrier.pins", "%s: a bridge's legs are channels A and B of "
                                                  "one PWM slice (leg B inverted): use %r"
                                                  % (why, pair)),
                          ("carrier.pins", "carrier.drive")))


def pll_clocks_khz() -> list[int]:
    """Every system clock (kHz) the RP2040's PLL makes from the 12 MHz
    crystal the way pico-sdk's check_sys_clock_khz searches it (what
    MicroPython's machine.freq() accepts; it raises "cannot change frequency"
    for any other)."""
    out = set()
    lo, hi = RP2040["vco_khz"]
    for fb in range(RP2040["fbdiv"][0], RP2040["fbdiv"][1] + 1):
        vco = fb * RP2040["xosc_khz"]
        if not lo <= vco <= hi:
            continue
        for p1 in range(1, RP2040["postdiv"] + 1):
            for p2 in range(1, p1 + 1):
                if vco % (p1 * p2) == 0:
                    out.add(vco // (p1 * p2))
    return sorted(out)


def _rp2_clock(found: _Found, d: dict[str, Any], firmware: str) -> None:
    cpu = d.get("cpu_hz")
    if not _is_int(cpu) or cpu <= 0:
        return
    deps = ("cpu_hz",)
    clocks = pll_clocks_khz()
    if cpu % 1000 or cpu // 1000 not in clocks:
        below = [c for c in clocks if c * 1000 < cpu]
        above = [c for c in clocks if c * 1000 > cpu]
        near = [x * 1000 for x in (below[-1:] + above[:1])]
        found.append((Problem("cpu_hz", "%s Hz is not a clock the RP2040's PLL makes from its "
                                        "12 MHz crystal (datasheet 2.18): machine.freq() "
                                        "refuses it; nearest: %s Hz"
                                        % (_n(cpu), " or ".join(_n(x) for x in near))), deps))
        return
    if cpu > RP2040["certified_hz"]:
        found.append((Problem("cpu_hz", "%s Hz is beyond the RP2040's rating (%s MHz; %s MHz "
                                        "certified only with a 1.15 V core, which MicroPython "
                                        "does not set): use at most %s"
                                        % (_n(cpu), RP2040["rated_hz"] // 1000000,
                                           RP2040["certified_hz"] // 1000000,
                                           _n(RP2040["rated_hz"]))), deps))
        return
    if cpu > RP2040["rated_hz"]:
        found.append((Problem("cpu_hz", "%s Hz overclocks the RP2040 (rated %s MHz; %s MHz is "
                                        "certified only with a 1.15 V core, which MicroPython "
                                        "does not set)" % (_n(cpu), RP2040["rated_hz"] // 1000000,
                                                          RP2040["certified_hz"] // 1000000),
                              "warning"), deps))
    if cpu != RP2040["boot_hz"]:
        found.append((Problem("cpu_hz", "%s Hz: MicroPython starts the RP2040 at %s Hz and "
                                        "texelpad does not change the clock, so hw/rp2 refuses "
                                        "to start unless /boot.py runs machine.freq(%d) first"
                                        % (_n(cpu), _n(RP2040["boot_hz"]), cpu), "warning"),
                      deps))


def _counts(found: _Found, d: dict[str, Any], port: str) -> None:
    cpu = d.get("cpu_hz")
    freq = _get(d, "carrier.freq_hz") if isinstance(d.get("carrier"), dict) else None
    if freq is None and isinstance(d.get("carrier"), dict):
        freq = boards.FREQ_DEFAULT_HZ
    if not (_is_int(cpu) and boards.CPU_HZ_MIN <= cpu <= boards.CPU_HZ_MAX and _is_int(freq)
            and boards.FREQ_MIN_HZ <= freq <= boards.FREQ_MAX_HZ):
        return
    top = boards.board_top({"port": port, "cpu_hz": cpu, "carrier": {"freq_hz": freq}})
    least = boards.COUNTS_MIN * (2 if port == "circuitpython" else 1)
    counts = top + 1
    deps = ("carrier.freq_hz", "cpu_hz")
    def top_at(f: int) -> int:
        return boards.board_top({"port": port, "cpu_hz": cpu, "carrier": {"freq_hz": f}})
    if top < least - 1:
        hi = cpu // (least - 1) + 2
        while hi > 1 and top_at(hi) < least - 1:
            hi -= 1
        found.append((Problem("carrier.freq_hz", "%s Hz on the %s Hz clock gives %s PWM counts "
                                                 "per period; at least %s keep ~9 bits of "
                                                 "amplitude and the frequency within 0.1 %%: "
                                                 "at this cpu_hz the carrier can be at most %s Hz"
                                                 % (_n(freq), _n(cpu), _n(counts), _n(least),
                                                    _n(hi))), deps))
    elif top > boards.TOP_MAX:
        lo = max(1, cpu // (boards.TOP_MAX + 2) - 2)
        while top_at(lo) > boards.TOP_MAX:
            lo += 1
        found.append((Problem("carrier.freq_hz", "%s Hz on the %s Hz clock gives PWM TOP %s; "
                                                 "the refresh keeps TOP <= %s (compare words "
                                                 "stay small ints): at this cpu_hz the carrier "
                                                 "must be at least %s Hz"
                                                 % (_n(freq), _n(cpu), _n(top), _n(boards.TOP_MAX),
                                                    _n(lo))), deps))


def _stm32(found: _Found, d: dict[str, Any], pins: list[Any], sens: list[Any]) -> None:
    def cpu_pin(name: Any) -> str | None:
        if not isinstance(name, str):
            return None
        n = name.upper()
        if n in PYBV11_PINS:
            return PYBV11_PINS[n]
        if len(n) >= 3 and n[0] == "P" and n[1] in "ABCDEFGHI" and n[2:].isdigit() \
                and int(n[2:]) <= 15:
            return n[:2] + str(int(n[2:]))
        # pyb's own CPU pin names (pyb.Pin("A8") = Pin.cpu.A8; pyb has no "PA8")
        if len(n) >= 2 and n[0] in "ABCDEFGHI" and n[1:].isdigit() and int(n[1:]) <= 15:
            return "P" + n[0] + str(int(n[1:]))
        return None
    # a pyboard's file names its header pins (X1 .. Y12); a file naming CPU pins only is
    # another STM32 board (a Black Pill): no pyboard-only warnings for it
    pyboard = any(isinstance(n, str) and n.upper()[:1] in ("X", "Y") for n in pins + sens)
    owners: dict[str, str] = {}
    for sensor, lst in ((False, pins), (True, sens)):
        for i, name in enumerate(lst):
            path = "%s[%d]" % ("sensor.pins" if sensor else "carrier.pins", i)
            cp = cpu_pin(name)
            if cp is None:
                if isinstance(name, str) and name:
                    found.append((Problem(path, "%r is neither a pyboard v1.1 name (X1 .. X22, "
                                                "Y1 .. Y12) nor an STM32 pin (PC6): not checked "
                                                "against the STM32F405's pins" % name,
                                          "warning"), (path,)))
                continue
            if cp in owners:
                found.append((Problem(path, "%r is pin %s, also %s: a pin does one job"
                                            % (name, cp, owners[cp])), (path,)))
            else:
                owners[cp] = path
            if sensor and cp not in F405_ADC:
                adc = [k for k, v in PYBV11_PINS.items() if v in F405_ADC]
                found.append((Problem(path, "%r (%s) has no ADC input on an STM32F405: use one "
                                            "of %s" % (name, cp, ", ".join(adc))), (path,)))
            if not sensor and pyboard and cp in PYBV11_USED:
                found.append((Problem(path, "%r (%s) is %s on a pyboard v1.1"
                                            % (name, cp, PYBV11_USED[cp]), "warning"), (path,)))
    timer, chan = _get(d, "carrier.pwm.timer"), _get(d, "carrier.pwm.channel")
    drive = _get(d, "carrier.drive")
    if timer in (1, 8) and _is_int(chan) and 1 <= chan <= 4:
        legs = [(0, chan, "CH%d" % chan)]
        if drive == "bridge" and chan <= 3:
            legs.append((1, -chan, "CH%dN" % chan))
        for i, key, label in legs:
            if i >= len(pins):
                continue
            cp = cpu_pin(pins[i])
            ok = F405_TIMER_PINS.get((timer, key), ())
            if cp is not None and cp not in ok:
                names = ["%s (%s)" % (k, v) for v in ok for k, w in PYBV11_PINS.items() if w == v]
                names += [v for v in ok if v not in PYBV11_PINS.values()]
                found.append((Problem("carrier.pins[%d]" % i, "%r (%s) is not TIM%d_%s: on an "
                                                              "STM32F405 that is %s"
                                      % (pins[i], cp, timer, label, ", ".join(names))),
                              ("carrier.pins[%d]" % i, "carrier.pwm")))
    cpu = d.get("cpu_hz")
    if pyboard and _is_int(cpu) and cpu != F405_TIM18_HZ:
        found.append((Problem("cpu_hz", "%s Hz: on a pyboard v1.x (STM32F405) TIM1 and TIM8 "
                                        "run at %s Hz (Timer(n).source_freq()); hw/stm32 refuses "
                                        "to start when they differ" % (_n(cpu), _n(F405_TIM18_HZ)),
                              "warning"), ("cpu_hz",)))


# --- the summary of a good file ---------------------------------------------------------

def summary(board: dict[str, Any], firmware: str = "stock") -> list[str]:
    """What a valid board file makes the chip do, a line each."""
    port = board["port"]
    car, sen, ref, disp = board["carrier"], board["sensor"], board["refresh"], board["display"]
    top = boards.board_top(board)
    hz = boards.actual_hz(board["cpu_hz"], top)
    want = car["freq_hz"]
    clocks = top + 1
    on = {"rp2": "MicroPython's rp2 port", "stm32": "MicroPython's stm32 port",
          "circuitpython": "CircuitPython", "virtual": "the virtual board, any firmware"}[port]
    if firmware == "texelpad" and port == "rp2":
        on = "the texelpad firmware (MicroPython v1.28 + ulab, Raspberry Pi Pico)"
    elif firmware == "texelpad" and port == "stm32":
        on = "the texelpad firmware (MicroPython v1.28, pyboard v1.1 / STM32F405)"
    elif port in ("rp2", "stm32"):
        on = "stock %s (MicroPython >= 1.26: hard timer IRQs)" % on
    lines = ["%s: fine: port %s, for %s" % (board["name"], port, on)]
    pins = car["pins"]
    if port == "rp2":
        legs = ["GP%d = PWM slice %d channel %s%s" % (g, (g >> 1) & 7, "AB"[g & 1],
                                                      " (inverted)" if i else "")
                for i, g in enumerate(pins)]
        carrier = ", ".join(legs)
    elif port == "stm32":
        pw = car["pwm"]
        carrier = ", ".join("%s = TIM%d_CH%d%s" % (p, pw["timer"], pw["channel"], "N" if i else "")
                            for i, p in enumerate(pins))
    elif port == "circuitpython":
        carrier = ", ".join(("board.GP%d" % p) if isinstance(p, int) else "board." + p
                            for p in pins)
    else:
        carrier = ", ".join("pin %s" % p for p in pins)
    lines.append("  carrier  %s; %s drive" % (carrier, car["drive"]))
    lines.append("           %s Hz asked, %s Hz played: %s / %s = %s counts per period "
                 "(TOP %s, %+.3f %%)" % (_n(want), format(round(hz, 2), ",.2f"),
                                         _n(board["cpu_hz"]), _n(want), _n(clocks), _n(top),
                                         (hz - want) / want * 100))
    if port == "rp2" and car["drive"] == "single":
        other = pins[0] ^ 1
        lines.append("           GP%d (slice %d channel %s) is held low by the carrier's "
                     "writes: do not use it for PWM" % (other, (other >> 1) & 7, "AB"[other & 1]))
    sp = []
    for p in sen["pins"]:
        if _is_int(p) and port in ("rp2", "circuitpython") and p in RP2040["adc"]:
            sp.append("GP%d = ADC%d" % (p, RP2040["adc"][p]))
        else:
            sp.append(str(p))
    lines.append("  sensor   %s (%s)" % (", ".join(sp), sen["kind"]))
    lines.append("  refresh  %s Hz, %s" % (_n(ref["hz"]), ref["mode"]))
    lines.append("  display  %s positions x %g um = %g mm" % (
        _n(disp["positions"]), disp["dx_um"], round(disp["positions"] * disp["dx_um"] / 1000, 3)))
    return lines
