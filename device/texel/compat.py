# Every difference between CPython, MicroPython and CircuitPython lives here.
# Features are detected, never inferred from version numbers.
import sys

IMPL = sys.implementation.name          # "cpython", "micropython", "circuitpython"
ON_DEVICE_RUNTIME = IMPL != "cpython"

try:
    from micropython import const
except ImportError:                     # CPython
    def const(x):
        return x

try:
    import micropython as _mp
except ImportError:
    _mp = None

# --- the port table: every fact about a port, in one place --------------------
# (docs/architecture.md "A new board port"). Per port:
#   platform   the sys.platform its MicroPython reports (None: told apart otherwise)
#   backend    (module in hw/, class): the hardware backend a board file of the port plays through
#   probe      what a development host (CPython, the unix port) must import to run a
#              board file of the port against a test's stand-ins: a module, or
#              module.attribute (the unix port has a machine module, without freq)
#   arch       mpy-cross -march of its native code (None: no native emitter, or a .mpy
#              format of its own: it gets the sources - CircuitPython)
#   board      the board file start() plays when given none (main.py's default too)
#   modes      refresh modes its board files may name, the default first
#   rom        the texelpad firmware exists for it: package data and tables in its
#              ROMFS partition (rom.py), read in place
#   chip       what messages call it
#   lean       its code takes the heap (CircuitPython compiles the sources into RAM; no
#              ROM, no texelpad .mpy; also a "rom" port without its ROMFS, below ROM:
#              stock MicroPython loads deploy's .mpy into RAM): app.tidy() forgets the
#              board files' checks after a start (13 KB; the next start imports them
#              again). Forgetting the generator after each push too would free 18 KB more, but every push
#              compiled it again (+0.5 s) and soon found the heap too fragmented for
#              its buffers (measured on the emulated Pico): not done.
#   loop_hz    the most refreshes a second its paced loop ("loop" mode) can be
#              asked for: 1000 where that loop is paced in milliseconds
#              (PACE_CLOCK, CircuitPython), else None (runtime/boards.py's bound)
#   holes      allocations start above the heap's small holes (skip_holes, where the
#              C core has heap_hint): speed where maps play from flash and the heap is
#              large (the Pico firmware: 230 KB). Not where maps are rendered into a
#              ~100 KB heap (the pyboard): the hint stays up until a collection, so the
#              small objects after it took the runs a map's blocks need - 42-57 of the
#              100 mixed pushes of bench/stm32.py were refused for memory (8 runs), 22-47
#              with the hint before a map's blocks only, 17 in each of 8 runs without.
# Everything else (which pins, which timer) is the board file's (runtime/boards.py).
PORT_TABLE = {
    "rp2": {"platform": "rp2", "backend": ("rp2", "Hw"), "probe": "machine.freq", "arch": "armv6m",
            "board": "pico", "modes": ("timer_irq", "core1_viper", "loop"), "rom": True,
            "chip": "an RP2040 (MicroPython rp2 port)", "loop_hz": None, "lean": False,
            "holes": True},
    "stm32": {"platform": "pyboard", "backend": ("stm32", "Hw"), "probe": "pyb",
              "arch": "armv7emsp", "board": "pyboard", "modes": ("timer_irq", "loop"),
              "rom": True, "chip": "an STM32 (MicroPython stm32 port, sys.platform 'pyboard')",
              "loop_hz": None, "lean": False, "holes": False},
    "circuitpython": {"platform": None, "backend": ("cpy", "Hw"), "probe": "pwmio", "arch": None,
                      "board": "pico_cpy", "modes": ("loop",), "rom": False,
                      "chip": "CircuitPython", "loop_hz": 1000, "lean": True,
                      "holes": False},
    "virtual": {"platform": None, "backend": ("virtual", "VirtualHw"), "probe": None,
                "arch": "x64", "board": "virtual", "modes": ("stepped",), "rom": False,
                "chip": "any firmware (the virtual board)", "loop_hz": None, "lean": False,
                "holes": False},
}
PORTS = ("rp2", "stm32", "circuitpython", "virtual")     # PORT_TABLE's keys, in this order
# sys.platform of the MicroPython unix port (where the virtual board runs): no
# port of its own - a development host - but the virtual board's image
UNIX_PLATFORMS = ("linux", "darwin", "win32")


def port_of(impl, platform):
    """The port of an interpreter by its sys.implementation.name and
    sys.platform: "rp2", "stm32", "circuitpython", or None (a development
    host: CPython, the unix port - where the virtual board plays)."""
    if impl == "circuitpython":
        return "circuitpython"
    for name in PORTS:
        if PORT_TABLE[name]["platform"] == platform:
            return name
    return None


PORT = port_of(IMPL, sys.platform)      # this interpreter's port, or None


def forget(name):
    """Drop module `name` from sys.modules and from its package, so that
    once nothing else holds its functions the collector frees its code (a
    lean port, PORT_TABLE); importing it again compiles it afresh."""
    m = sys.modules.pop(name, None)
    if m is None:
        return
    pkg, _, leaf = name.rpartition(".")
    p = sys.modules.get(pkg)
    if p is not None and getattr(p, leaf, None) is m:
        delattr(p, leaf)


def const_view(raw, typecode):
    """raw, a bytes literal of little-endian values ("H": uint16, "i": int32),
    as a read-only table without a copy where the runtime can: a uctypes view
    of the literal's own bytes, 4-byte aligned (a module loaded into RAM -
    a stock board's .mpy, source on the unix port - has its literals on the
    heap: 8 KB of a stock Pico's heap for the sine and plan tables); else
    array(typecode, raw). Like texel.rom's views it has no len()."""
    if typecode not in ("H", "i"):
        raise ValueError("const_view: typecode %r (expected 'H' or 'i')" % (typecode,))
    try:
        import uctypes
        a = uctypes.addressof(raw)
    except (ImportError, TypeError, AttributeError):
        a = 1
    if a & 3 or getattr(sys, "byteorder", "little") != "little":
        return array(typecode, raw)
    kind, size = (uctypes.UINT16, 2) if typecode == "H" else (uctypes.INT32, 4)
    # NATIVE (= little-endian here): aligned loads, not uctypes' byte-by-byte path
    return uctypes.struct(a, {"v": (uctypes.ARRAY | 0, kind | (len(raw) // size))},
                          uctypes.NATIVE).v


def _romfs():
    # a ROMFS partition is there (MicroPython >= 1.25 built with MICROPY_VFS_ROM,
    # as the texelpad firmware is; stock RPI_PICO is not): only then can data be in
    # flash, and only then does texel.rom (4.8 KB of a stock Pico's heap) load
    try:
        import vfs
        return hasattr(vfs, "rom_ioctl")
    except ImportError:
        return False


ROM = PORT is not None and PORT_TABLE[PORT]["rom"] and _romfs()    # data may be in ROMFS
# The port's "lean" (its comment above), or a stock rp2/stm32 MicroPython (no
# ROMFS: texelpad deploy's .mpy files in its filesystem), which loads the code
# into its heap as CircuitPython does. The board checks' 17 KB of a stock Pico's
# heap (measured on the emulated one) come back to the scenes once a start is done.
LEAN = PORT is not None and (PORT_TABLE[PORT]["lean"] or (PORT_TABLE[PORT]["rom"] and not ROM))


def default_board():
    """The board file start() plays when given no name: the port's own, the
    virtual board's on a development host."""
    return PORT_TABLE[PORT or "virtual"]["board"]


def backend(port):
    """The hardware class of a port, imported (ImportError when this board's
    image or firmware does not have it: deploy installs only the board's own
    backend, and a backend imports its port's modules)."""
    row = PORT_TABLE.get(port)
    if row is None:
        raise ImportError("no backend for port %r" % (port,))
    mod, cls = row["backend"]
    pkg = __name__[:__name__.rfind(".")]          # "texel"
    return getattr(__import__(pkg + ".hw." + mod, None, None, (cls,)), cls)


# Float precision of the running interpreter: 53 bits (CPython, unix port) or
# 24 bits (rp2/stm32 MicroPython builds use float32; CircuitPython is 30-bit).
def _mantissa_bits():
    x = 1.0
    bits = 0
    while 1.0 + x != 1.0 and bits < 80:
        x = x / 2.0
        bits += 1
    return bits
FLOAT_BITS = _mantissa_bits()

# numpy (CPython) and ulab (MicroPython/CircuitPython builds that include it).
try:
    import numpy as numpy_mod
    if not hasattr(numpy_mod, "float64"):   # a numpy-named module that is not numpy
        numpy_mod = None                    # (e.g. ulab's, on a build registering it so)
except ImportError:
    numpy_mod = None


def ulab_numpy():
    """ulab's numpy module, or None (a cached import after the first call)."""
    try:
        from ulab import numpy as unp
        return unp
    except ImportError:
        return None


_ULAB = []      # ulab_version()'s answer, found once: it cannot change while the board runs


def ulab_version():
    """ulab's version, "?" where it has none, or None without ulab - looked up
    once: status() asks at every push (app.push returns it), and an import
    statement runs at every call (80-120 us on the emulated Pico's firmware;
    where there is no ulab, a failed one searches the filesystem)."""
    if not _ULAB:
        try:
            import ulab
            _ULAB.append(getattr(ulab, "__version__", "?"))
        except ImportError:
            _ULAB.append(None)
    return _ULAB[0]


# viper: compiled integer code (MicroPython with a native emitter). Probe by
# compiling a tiny function: the decorator exists on ports without an emitter too.
def _detect_viper():
    # micropython.viper is not an attribute: the compiler handles it.
    if _mp is None:
        return False
    try:
        exec("import micropython\n@micropython.viper\ndef _t(a:int)->int:\n    return a+1\n_r=_t(1)")
        return True
    except Exception:
        return False
HAS_VIPER = _detect_viper()


def native(module, name):
    """Function `name` of the viper module `module` ("texel.gen.engine_int_viper"),
    or None where the port has no native emitter or the module does not load.
    Viper code lives in modules of its own: a file holding it does not even
    compile on a port without a native emitter (CircuitPython, mpy-cross
    without -march), and a board's image leaves such modules out."""
    if not HAS_VIPER:
        return None
    try:
        return getattr(__import__(module, None, None, (name,)), name)
    except (ImportError, SyntaxError, MemoryError, AttributeError):
        return None

# The C core (device/cmod/texelcore: format 2's plan and int engine, the brush
# painter): the texelpad firmware's built-in _texelcore, or the native .mpy
# texelpad deploy puts in /lib on a stock board of its architecture. CORE_API
# is what this package calls; another module (a board deployed by an older
# texelpad) is not used: the viper and Python twins give the same integers.
CORE_API = 7                # 7: the refresh keeps its last row in W[14] (W_ROW); 6: the STM32 ADC
_core = None


def core():
    """The _texelcore module, or None (CPython: the tests load its ctypes build)."""
    global _core
    if _core is None:
        _core = False
        if IMPL == "micropython":
            try:
                import _texelcore
                if getattr(_texelcore, "API", 0) == CORE_API:
                    _core = _texelcore
            except (ImportError, ValueError, OSError, MemoryError):
                pass                    # ValueError: a .mpy of another format
    return _core or None


_hint = None


def skip_holes(blocks=64):
    """Start the allocator's search for free memory above the heap's small
    holes: at the first run of `blocks` free blocks (the firmware's C core,
    texelcore_fw.h heap_hint: every allocation of more than 16 bytes walked
    the holes first). Only on a port whose PORT_TABLE "holes" says so; a no-op
    elsewhere. A push calls it before it allocates, a map before each block."""
    global _hint
    if _hint is None:
        _hint = (PORT is not None and PORT_TABLE[PORT]["holes"]
                 and getattr(core(), "heap_hint", None)) or False
    if _hint:
        _hint(blocks)


ENGINES = ("c", "viper", "py")          # fastest first: the same integers on each


def fastest(name, viper_module, py_fn, engine=None):
    """(function, its engine) for a hot loop that has three twins: the C
    core's `name`, viper_module's `name` and py_fn. engine None: the fastest
    this runtime has; "c", "viper" or "py": that one, or ValueError where
    this runtime does not have it (gen/plan_int.py, gen/engine_int.py)."""
    if engine is not None and engine not in ENGINES:
        raise ValueError("engine: expected 'c', 'viper' or 'py', got %r" % (engine,))
    for e in ENGINES if engine is None else (engine,):
        if e == "c":
            f = core() and getattr(core(), name, None)
        elif e == "viper":
            f = native(viper_module, name)
        else:
            f = py_fn
        if f:
            return f, e
    raise ValueError("engine: %r is not on this runtime" % (engine,))

# Microsecond ticks: time.ticks_us/ticks_diff where the port has them
# (MicroPython); elsewhere the same arithmetic over MicroPython's 2^30 tick
# period, from perf_counter_ns (CPython) or monotonic_ns (CircuitPython, which
# has no ticks_us; it allocates bigints, so keep it out of IRQ code), so code
# that measures intervals runs unchanged everywhere.
TICKS_MASK = 0x3FFFFFFF
_ms = None                              # CircuitPython's ms ticks (PACE_CLOCK)
try:
    from time import ticks_us, ticks_diff, ticks_add
except ImportError:
    import time as _time
    try:
        from supervisor import ticks_ms as _ms
    except ImportError:
        pass
    _ns = getattr(_time, "perf_counter_ns", None) or _time.monotonic_ns

    def ticks_us():
        return (_ns() // 1000) & TICKS_MASK

    def ticks_diff(a, b):
        return ((a - b + 0x20000000) & TICKS_MASK) - 0x20000000

    def ticks_add(a, b):
        return (a + b) & TICKS_MASK

# The paced refresh loop's clock (runtime/pace.py): (ticks, diff, add,
# microseconds a tick). The microsecond ticks above where they allocate
# nothing; on CircuitPython they do (time.monotonic_ns: a bigint, 32 B a call
# on the emulated Pico), and a loop that allocates stalls ~15 ms at every
# garbage collection (bench/results/circuitpython.txt), so it is paced there on
# supervisor.ticks_ms: a small int, 1 ms, wrapping at 2^29 ms.
def ms_diff(a, b):
    """supervisor.ticks_ms's difference a - b (it wraps at 2^29 ms)."""
    return ((a - b + 0x10000000) & 0x1FFFFFFF) - 0x10000000


def ms_add(a, b):
    return (a + b) & 0x1FFFFFFF


PACE_CLOCK = (ticks_us, ticks_diff, ticks_add, 1)
if _ms is not None:
    PACE_CLOCK = (_ms, ms_diff, ms_add, 1000)

try:
    from array import array
except ImportError:                     # pragma: no cover - every target has array
    array = None


def u16_buffer(n):
    """A zeroed uint16 buffer of n samples (2 bytes each).

    The fast way briefly needs two 2n-byte blocks (the zeroed bytes, then the
    array); on a fragmented heap the second can fail although one would fit
    (a 19,200-sample map on a 180 KB heap failed so, depending on nothing more
    than the length of the import path's strings). Then the buffer is built in
    one block (u16_one_block) and zeroed by slices. That measured 72 ms against
    7.4 ms for a 19,200-sample map on the emulated Pico, so it is only the
    fallback; callers that build often pass their own buffer (out=). Where
    the C core is, its u16 makes it in one block at C speed."""
    c = core()
    if c and 0 <= n <= 1048576:
        return c.u16(n)
    try:
        return array("H", bytes(2 * n))
    except MemoryError:
        if n > 65536:                   # u16_one_block would take the two-block way
            raise
    return zeroed(u16_one_block(n), array("H", bytes(2 * _ZERO_RUN)))


def u16_one_block(n):
    """An uint16 buffer of n samples, contents undefined (the caller
    overwrites all of it). array('H', range(n)) sizes the array from
    len(range) and allocates just that block; array('H', bytes(2n)) needs a
    second 2n-byte block for the zeroed bytes at the same time - on a
    fragmented board heap that is the difference between fitting and not.
    (MicroPython would silently wrap values above 65535, CPython refuses
    them: longer buffers take the bytes path.) The C core's u16 does the same
    at C speed, zeroed (texelcore_api.h: 0.04 ms for 19,200 samples on x64
    against 0.64 ms, 72 ms by range on an RP2040)."""
    c = core()
    if c and 0 <= n <= 1048576:
        return c.u16(n)
    if n <= 65536:
        return array("H", range(n))
    return array("H", bytes(2 * n))


_ZERO_RUN = 256
_ZERO_C = None          # the C core's zero (texelcore_api.h: a memset), False where there is none


def zeroed(a, run):
    """Array a with every value 0, returned: the C core's memset where it is;
    else slice stores of `run` (an array of zeros of a's item size - a slice
    store checks that alone) and a view of it for the rest, one C memcpy a
    run and no per-value Python loop; a port without array slice stores (the
    MICROPY_PY_ARRAY_SLICE_ASSIGN option), or no room for the view, zeroes
    the rest value by value. (texel.runtime.refresh_fast zeroes a dropped W
    so: 70-95 us for 20-128 words on the emulated stock Pico by slices, 7 us
    a word by the loop.)"""
    global _ZERO_C
    if _ZERO_C is None:
        _ZERO_C = getattr(core(), "zero", None) or False
    if _ZERO_C:
        _ZERO_C(a)
        return a
    n = len(a)
    k = len(run)
    i = 0
    try:
        while n - i >= k:
            a[i:i + k] = run
            i += k
        if i < n:
            a[i:n] = memoryview(run)[:n - i]
            i = n
    except (TypeError, ValueError, NotImplementedError, MemoryError):
        pass
    while i < n:
        a[i] = 0
        i += 1
    return a


def check_u16_out(out, n):
    """A caller-supplied output buffer must hold n uint16 samples. Probed by
    writing (the buffer is about to be overwritten anyway): a bytearray or an
    8-bit array would silently keep only the low byte on MicroPython."""
    if out is None:
        return u16_buffer(n)
    try:
        m = len(out)
        out[0] = 65535
        ok = out[0] == 65535
        out[0] = 0
    except (TypeError, ValueError, OverflowError, IndexError):
        ok = False
        m = n
    if not ok:
        raise ValueError("out: expected a uint16 buffer (array('H')), got %s" % type(out).__name__)
    if m < n:
        raise ValueError("out: holds %d samples, the map needs %d" % (m, n))
    return out


def float_buffer(n):
    # 'f' is float32 (4 bytes/sample): the board's own precision; 'd' keeps the
    # host's float64 exact. Use on the host only for long maps.
    return array("d" if FLOAT_BITS > 24 else "f", bytes((8 if FLOAT_BITS > 24 else 4) * n))


def heap_free():
    try:
        import gc
        gc.collect()
        return gc.mem_free()
    except (ImportError, AttributeError):
        return None


def largest_free_block():
    """Bytes of the largest block the heap can give now (after a collection),
    to 64 bytes, or None where the interpreter has no gc.mem_free (CPython).
    MicroPython's mem_info() prints it but returns nothing; so it is found by
    allocating: a bisection of ~12 trial bytearrays, each freed at once. For
    out-of-memory messages only (a fragmented heap can have 190 KB free and
    no 38 KB block: the free total alone contradicts the refusal)."""
    free = heap_free()
    if free is None:
        return None
    lo, hi = 0, free + 1                # lo fits; hi does not
    while hi - lo > 64:
        mid = (lo + hi) // 2
        try:
            b = bytearray(mid)
            del b
            lo = mid
        except MemoryError:
            hi = mid
    import gc
    gc.collect()
    return lo


def blocks_free(size, most):
    """How many blocks of `size` bytes the heap can give now (up to `most`),
    found by allocating them and letting go: a heap can have the bytes a
    region's 1 KB chunks need and not their 38 pieces (its holes smaller)."""
    held = None
    k = 0
    try:
        held = [None] * most
        while k < most:
            held[k] = bytearray(size)
            k += 1
    except MemoryError:
        pass
    held = None
    import gc
    gc.collect()
    return k


def memory_words(block=0, need=0):
    """'F bytes free, the largest block L bytes' for an out-of-memory
    message ('' on CPython); with a block size (the largest one block a
    scene's region needs) and the bytes needed, also how many blocks of that
    size the heap has room for."""
    big = largest_free_block()
    if big is None:
        return ""
    import gc
    free = gc.mem_free()
    words = "%d bytes free, the largest free block %d bytes" % (free, big)
    if block and need > block:
        words += ", room for %d blocks of %d" % (blocks_free(block, need // block + 1), block)
    return words


# --- the console the host's link talks through (texel/serve.py) -----------------
def console_reader():
    """read() -> the bytes the board's console has received and nobody read
    yet (None when there are none), without waiting: CircuitPython's
    usb_cdc.console (timeout 0; its Ctrl-C still raises KeyboardInterrupt),
    else a select.poll on sys.stdin (MicroPython, CPython), a byte at a time."""
    try:
        import usb_cdc
        con = usb_cdc.console
    except (ImportError, AttributeError):
        con = None
    if con is not None:
        con.timeout = 0

        def read():
            n = con.in_waiting
            return con.read(n) if n else None
        return read
    import select
    p = select.poll()
    p.register(sys.stdin, select.POLLIN)
    inp = getattr(sys.stdin, "buffer", sys.stdin)

    def read():
        return inp.read(1) if p.poll(0) else None
    return read


def print_exception(e):
    """A traceback on stdout, as the raw REPL prints one: MicroPython's
    sys.print_exception, else traceback (CircuitPython, CPython)."""
    pe = getattr(sys, "print_exception", None)
    if pe is not None:
        pe(e)
        return
    try:
        import traceback
    except ImportError:             # CircuitPython's unix build: its last line only
        print("%s: %s" % (type(e).__name__, e))
        return
    traceback.print_exception(e, file=sys.stdout)
