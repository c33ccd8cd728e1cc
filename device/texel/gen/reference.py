# Reference textures: the nine of the matching study (docs/background.md §2,
# golden/reference_textures.csv) and the earlier paper's band-pass noise family.
#
#   reference(name, length_samples=9600)      -> map in [0, 1] (compat.float_buffer)
#   reference_u16(name, length_samples=9600)  -> uint16 0..65535 (2 bytes/sample)
#       (out= a buffer, or a tuple of uint16 chunks: a board's map in 1 KB
#       pieces, runtime/kinds/reference.py - no block of 38 KB on a stock Pico)
#   bandpass(fc_cpmm, zeta, seed=0, length_samples=9600)   (and bandpass_u16)
#   names()                                   -> every name reference() accepts
#
# Geometry: one sample = 5.3 um (DX_MM); the study's rows are half a screen,
# 9,600 samples = 50.88 mm.
#
# Length rules (length_samples in [1, LENGTH_MAX]):
# - closed forms (2sin, 3sin, 4sin, square, triangle, sawtooth) continue their
#   formula for every n; 3sin/4sin keep the min-max normalisation constants of
#   the 9,600-sample half screen (so a prefix is identical to the study row)
#   and clip to [0, 1] where a longer map exceeds them;
# - stored rows (white, pink, blue): the first length_samples samples when
#   length_samples <= 9600; longer maps repeat the row mirrored
#   (0..9599, 9598..1, 0..9599, ...: period 19,198 samples) so that no seam
#   puts a step into the correlated pink row;
# - band-pass noise is generated for the requested length (normalised over
#   it), so a longer map is a different realisation, not an extension.
#
# Precision: on CPython and the unix port (binary64) the closed forms match
# the study's CSV to ~3e-13. Phases are exact integers (sines: 1e-5 cycle
# units; square/triangle/sawtooth: 1/1919900 cycle units) reduced to one turn
# before any float is formed, so float32 boards lose nothing to a large
# argument (float32 ulp at 50 mm would be 4e-6 mm, a 2.6e-4 rad phase error
# at 11 c/mm) and the square wave's jumps land on the same samples as the CSV.
import math
from array import array      # at the top: an extensible built-in imported inside a function
#                              walks sys.path each time (1.64 ms on the emulated RP2040)
import sys
from ..compat import float_buffer, u16_buffer, ROM
from .params import DX_MM, LENGTH_MAX
from .rng import Rng

STUDY_NAMES = ("2sin", "3sin", "4sin", "white", "pink", "blue",
               "square", "triangle", "sawtooth")
HALF_SCREEN = 9600              # samples in a study row (50.88 mm)

# --- sums of sines ---------------------------------------------------------
# x_n = 0.0053*n mm, so the phase of f c/mm at sample n is f*0.0053*n cycles;
# f*0.0053*1e5 = f*530 is an integer for every frequency used, so the phase in
# units of 1e-5 cycle is (n*step) mod 100000, exact in small ints (< 2^30).
# Steps: 2.5 -> 1325, 6 -> 3180, 8.5 -> 4505, 11 -> 5830 (c/mm -> 1e-5 cycle/sample).
_SINE_TURN = 100000
_RAD_PER_SINE_UNIT = 2.0 * math.pi / _SINE_TURN
_SINES = {
    "2sin": (1325, 3180),
    "3sin": (1325, 3180, 4505),
    "4sin": (1325, 3180, 4505, 5830),
}
# min and max of the sum over the 9,600-sample half screen (n = 0..9599),
# computed in binary64 by this module; the CSV row is (s - lo)/(hi - lo).
# (3sin: min at n=592, max at n=4691; 4sin: min at n=7919, max at n=6798.)
_MINMAX = {
    "3sin": (-2.5949777266493834, 2.594943661202178),
    "4sin": (-3.2360052841030873, 3.236063668205634),
}

# --- square / triangle / sawtooth -----------------------------------------
# x = linspace(0, 101.76, 19200) as MATLAB forms it, (n*101.76)/19199 mm, at
# 1 c/mm: n*10176/1919900 cycles. The phase is kept as the exact integer
# r = (n*10176) mod 1919900 (always < 2^21); frac = r/1919900. The CSV was
# made by MATLAB's square/sawtooth on t = 2*pi*x: square is 1 while
# mod(t, 2pi) < pi (r < 959950) else 0 at the map level; triangle
# (sawtooth(t, 0.5)+1)/2 is 2*frac up to frac <= 0.5 then 2 - 2*frac;
# sawtooth (sawtooth(t)+1)/2 is frac. On the 9,600 study samples no phase
# comes closer than 2.2e-5 cycle to a jump; no n at all gives frac = 0.5
# exactly (10176*n/1919900 = k + 1/2 has no integer solution).
_WAVE_TURN = 1919900
_WAVE_STEP = 10176
_WAVE_HALF = 959950
_WAVES = ("square", "triangle", "sawtooth")

# --- stored noise rows -----------------------------------------------------
# white, pink, blue: 3 rows x 9,600 uint16 little-endian, q = round(v*65535)
# (|error| <= 0.5/65535 = 7.6e-6), made by tools/pack_reference_noise.py
# from the golden CSV. Read on demand: 57,600 bytes never sit in RAM at once.
NOISE_FILE = "reference_noise.bin"
_NOISE_ROWS = ("white", "pink", "blue")
_MIRROR_PERIOD = 2 * HALF_SCREEN - 2      # 19198
_CHUNK = 256                              # samples per read (512 bytes)

# --- band-pass noise (earlier paper) ---------------------------------------
# name -> (centre frequency c/mm, damping ratio zeta = 1/(2Q)); seed 0.
BANDPASS_FAMILY = (
    ("bp-1-0.05", 1.0, 0.05), ("bp-1-0.5", 1.0, 0.5), ("bp-1-5", 1.0, 5.0),
    ("bp-4-0.05", 4.0, 0.05), ("bp-4-0.5", 4.0, 0.5), ("bp-4-5", 4.0, 5.0),
    ("bp-20-0.05", 20.0, 0.05), ("bp-20-0.5", 20.0, 0.5), ("bp-20-5", 20.0, 5.0),
)
_BANDPASS = {}
for _n, _f, _z in BANDPASS_FAMILY:
    _BANDPASS[_n] = (_f, _z)
del _n, _f, _z
FC_MIN, FC_MAX = 0.01, 94.0         # the paper's pitch limits; < Nyquist 94.34
ZETA_MIN, ZETA_MAX = 0.01, 10.0
SD_SPAN = 6.0                       # map = clip(0.5 + (y - mean)/(6*sd), 0, 1)
# Burn-in: the filter starts from rest; its slowest pole (radius rho) decays
# as rho^n, so after 7 time constants (tau = -1/ln rho samples) the start
# state is down to e^-7 < 1e-3. Rounded up to a multiple of 256 so float32
# boards pick the same count as binary64: for the nine family members 7*tau
# is >= 1.4 % above the next lower multiple (closest: bp-4-5, 519.4 vs 512),
# while float32 evaluation moves 7*tau by ~1e-5 relative. Capped for extreme
# bands (fc*zeta tiny), which then keep part of their start transient.
_BURN_TAUS = 7.0
_BURN_STEP = 256
BURN_MAX = 65536


def names():
    """Every name reference() accepts: the study's nine, then the band-pass family."""
    return list(STUDY_NAMES) + [b[0] for b in BANDPASS_FAMILY]


def _check_length(length_samples):
    if (isinstance(length_samples, bool) or not isinstance(length_samples, int)
            or length_samples < 1 or length_samples > LENGTH_MAX):
        raise ValueError("length_samples: expected an int in [1, %d], got %r"
                         % (LENGTH_MAX, length_samples))
    return length_samples


def _check_name(name):
    if name in STUDY_NAMES or (isinstance(name, str) and name in _BANDPASS):
        return name
    raise ValueError("name: unknown reference texture %r (known: %s)"
                     % (name, ", ".join(names())))


def reference(name, length_samples=9600):
    """Reference texture `name` as a friction map in [0, 1], length_samples long
    (compat.float_buffer: float64, 8 bytes/sample, on the host; float32, 4 bytes,
    on boards, where reference_u16 needs half that)."""
    _check_name(name)
    n = _check_length(length_samples)
    if name in _BANDPASS:
        fc, zeta = _BANDPASS[name]
        return bandpass(fc, zeta, 0, n)
    out = float_buffer(n)
    _fill(name, n, [(out, n)], False)
    return out


def reference_u16(name, length_samples=9600, out=None):
    """The same map as uint16, q = round(v*65535) (2 bytes/sample; what a board
    stores). out: an optional uint16 buffer of at least length_samples, or a
    tuple of uint16 chunks that together hold length_samples values (every
    chunk but the last as long as the first: runtime/kinds/__init__.py
    new_chunks) - the same values, written chunk by chunk."""
    _check_name(name)
    n = _check_length(length_samples)
    if out is None:
        out = u16_buffer(n)
    parts = _parts(out, n)
    if name in _BANDPASS:
        fc, zeta = _BANDPASS[name]
        return bandpass_u16(fc, zeta, 0, n, out)
    _fill(name, n, parts, True)
    return out


def _parts(out, n):
    """[(buffer, values it takes)] in order: [(out, n)] for one buffer, one
    pair a chunk for a tuple of chunks; ValueError when they hold fewer than n."""
    if type(out) is not tuple:
        if len(out) < n:
            raise ValueError("out: buffer holds %d samples, %d needed" % (len(out), n))
        return [(out, n)]
    parts = []
    left = n
    size = len(out[0]) if out else 0
    for i, c in enumerate(out):
        if left <= 0:
            break
        if len(c) > size or (len(c) != size and i != len(out) - 1):
            raise ValueError("out: chunk %d holds %d values, the first %d" % (i, len(c), size))
        k = len(c) if len(c) < left else left
        parts.append((c, k))
        left -= k
    if left > 0:
        raise ValueError("out: the chunks hold %d samples, %d needed" % (n - left, n))
    return parts


def _fill(name, n, parts, q16):
    if name in _SINES:
        _fill_sines(name, parts, q16)
    elif name in _WAVES:
        _fill_wave(name, parts, q16)
    else:
        _fill_noise(_NOISE_ROWS.index(name), n, parts, q16)


# A board with viper and float32 renders the uint16 sums of sines in
# machine-word ints (gen/reference_viper.py: within 1 u16 of the binary64 map,
# as its float32 path is, and ~150x faster - a stock Pico's power-up 4sin);
# binary64 interpreters keep the float path, which matches the CSV.
_INT_SINES = None


def _int_sines():
    global _INT_SINES
    if _INT_SINES is None:
        from ..compat import FLOAT_BITS, core, native
        f = None
        if FLOAT_BITS <= 24:
            # the C core's twin first (texel_core.c tc_sines, the same integers): a
            # full-screen 4sin took 220 ms of viper on a stock Pico
            c = core()
            f = (c and getattr(c, "sines", None)) or native("texel.gen.reference_viper", "fill")
        _INT_SINES = f or False
    return _INT_SINES


_SINES_PARTS = None


def _sines_parts():
    # (sine_table, reference_viper.CONSTANTS, steps_of), imported at the first render
    # and kept: two import statements took ~1.9 ms of every sines render on a stock Pico
    global _SINES_PARTS
    if _SINES_PARTS is None:
        from . import sine_table
        from .reference_viper import CONSTANTS, steps_of
        _SINES_PARTS = (sine_table, CONSTANTS, steps_of)
    return _SINES_PARTS


def _fill_sines(name, parts, q16):
    # parts: _parts(); the phases carry from one part to the next
    steps = _SINES[name]
    fill = _int_sines() if q16 else False
    if fill:
        sine_table, CONSTANTS, steps_of = _sines_parts()
        a0, ws, rq = CONSTANTS[name]
        st = array("i", steps_of(steps))
        ph = array("i", bytes(8 * len(steps)))
        tab = sine_table.table()
        for out, c in parts:
            fill(out, c, st, ph, len(steps), tab, a0, ws, rq)
        return
    sin = math.sin
    k = _RAD_PER_SINE_UNIT
    two = name == "2sin"
    if two:
        lo = 0.0
        inv = 1.0
    else:
        lo, hi = _MINMAX[name]
        inv = 1.0 / (hi - lo)
    phases = [0] * len(steps)
    m = len(steps)
    for out, c in parts:
        for i in range(c):
            s = 0.0
            for j in range(m):
                s += sin(phases[j] * k)
                p = phases[j] + steps[j]
                if p >= _SINE_TURN:
                    p -= _SINE_TURN
                phases[j] = p
            if two:
                v = 0.5 + 0.3 * s           # docs/background.md §2: clip(0.5 + 0.3*s, 0, 1)
            else:
                v = (s - lo) * inv
            if v < 0.0:
                v = 0.0
            elif v > 1.0:
                v = 1.0
            out[i] = int(v * 65535.0 + 0.5) if q16 else v


def _fill_wave(name, parts, q16):
    kind = _WAVES.index(name)
    inv = 1.0 / _WAVE_TURN
    r = 0
    for out, c in parts:
        for i in range(c):
            if kind == 0:
                v = 1.0 if r < _WAVE_HALF else 0.0
            else:
                f = r * inv
                if kind == 1:
                    v = 2.0 * f if r <= _WAVE_HALF else 2.0 - 2.0 * f
                else:
                    v = f
            out[i] = int(v * 65535.0 + 0.5) if q16 else v
            r += _WAVE_STEP
            if r >= _WAVE_TURN:
                r -= _WAVE_TURN


# --- stored rows -----------------------------------------------------------
def _here():
    """This module's folder, with its slash ('' for a bare name); NameError
    where the module has no __file__."""
    here = __file__
    return here[:max(here.rfind("/"), here.rfind("\\")) + 1]


def noise_path():
    """Path of reference_noise.bin: next to this module, else texel/gen/ on
    sys.path (frozen modules may have no __file__)."""
    cands = []
    try:
        cands.append(_here() + NOISE_FILE)  # frozen: the sys.path entries below find /rom/lib
    except NameError:
        pass
    for p in sys.path:
        if isinstance(p, str) and not p.startswith("."):
            cands.append((p + "/" if p else "") + "texel/gen/" + NOISE_FILE)
    for c in cands:
        try:
            open(c, "rb").close()
            return c
        except OSError:
            pass
    raise OSError("texel: %s not found (looked in: %s); copy it next to texel/gen/reference.py"
                  % (NOISE_FILE, ", ".join(cands)))


# --- maps in flash (the texelpad firmware) ----------------------------------
# The firmware's ROMFS partition holds every study reference rendered once on
# the host (CPython, binary64: the CSV's values) over the full screen,
# ref/<name>.u16 beside this module (texelpad.firmware.romfs); a region plays
# the first n values in place (every length rule above makes a shorter map a
# prefix of the full one). 19,200 x 2 bytes each.
FLASH_DIR = "ref"
FLASH_SAMPLES = 19200


_FLASH = {}                 # (name, length) -> its view: flash_u16 opens each once
_FLASH_KEEP = 16            # views kept (a few words each; region lengths vary)


def flash_u16(name, length_samples):
    """The map of reference name, length_samples long, as a uint16 view of
    flash (rom.rom_u16), or None where the image has no flash maps. Each view
    is made once: opening it (a path, a stat, an open, a struct) took 2.9 ms
    of every reference region's push on the emulated Pico, twice a region
    (its block() and its store())."""
    v = _FLASH.get((name, length_samples))
    if v is not None:
        return v
    if not ROM or name not in STUDY_NAMES or not 1 <= length_samples <= FLASH_SAMPLES:
        return None
    from ..rom import rom_u16, path_beside
    try:
        here = __file__
    except NameError:
        return None
    # frozen (texelpad firmware): the ROMFS's maps (rom.data_beside)
    v = rom_u16(path_beside(here, "%s/%s.u16" % (FLASH_DIR, name)), length_samples)
    if v is not None:
        if len(_FLASH) >= _FLASH_KEEP:
            _FLASH.clear()
        _FLASH[(name, length_samples)] = v
    return v


_FILES = None                # the names of the map files beside this module (map_files)
_FILES_DIR = None


def map_files():
    """The references whose map files are beside this module (file_u16),
    listed once: a region of another then allocates nothing to find out (a
    failed open's path and exception, at every push, fragmented a small heap
    between a scene's blocks: tests/runtime/test_scene.py). A deploy resets
    the board or drops the modules, so the list is new after one."""
    global _FILES, _FILES_DIR
    if _FILES is None:
        names = ()
        try:
            _FILES_DIR = _here() + FLASH_DIR    # (a frozen module's is relative: flash_u16's)
            import os
            names = tuple(n[:-4] for n in os.listdir(_FILES_DIR) if n.endswith(".u16"))
        except (NameError, OSError, ImportError):
            pass
        _FILES = names
    return _FILES


def file_u16(name, length_samples, out):
    """Fill out (a uint16 buffer, or new_chunks' chunks: _parts) with the
    first length_samples values of the full-screen map ref/<name>.u16 that
    `texelpad deploy` writes beside this module on a stock RP2040
    (texelpad.deploy.install.with_reference_maps): littlefs files cannot be
    played in place as the firmware's ROMFS maps are (flash_u16), but reading
    a half screen into a region's chunks took 9.2 ms on the emulated stock
    Pico (6.1 of it the open) where rendering a full screen took up to 2.2 s
    (docs/firmware.md) - and the values are the host's binary64 map, the
    firmware's, where the float32 render is within 1 u16 of them. True when filled; False (out
    may be half-written: the caller renders it whole) where there is no such
    file or it is not whole (a deploy with --no-maps, an older one)."""
    if name not in STUDY_NAMES or not 1 <= length_samples <= FLASH_SAMPLES \
            or name not in map_files():
        return False
    try:
        f = open("%s/%s.u16" % (_FILES_DIR, name), "rb")
    except OSError:
        return False
    try:
        if f.seek(0, 2) != 2 * FLASH_SAMPLES:   # a file cut short is not the map
            return False
        f.seek(0)
        return _read_parts(f, _parts(out, length_samples), length_samples)
    except OSError:                             # a damaged filesystem: render it
        return False
    finally:
        f.close()


def _read_parts(f, parts, m):
    """The next m little-endian uint16 values of file f into parts (_parts'
    pairs, in order) in the board's byte order; False when f had fewer."""
    big = getattr(sys, "byteorder", "little") == "big"
    for out, c in parts:
        c = c if c < m else m
        if c <= 0:
            break
        # readinto counts bytes: a view of c uint16 values takes 2 c
        if f.readinto(memoryview(out)[0:c]) != 2 * c:
            return False
        if big:
            _swap16(out, c)
        m -= c
    return True


def _swap16(buf, m):
    for i in range(m):
        v = buf[i]
        buf[i] = ((v & 0xFF) << 8) | (v >> 8)


def _fill_noise(row, n, parts, q16):
    m = n if n < HALF_SCREEN else HALF_SCREEN
    big = getattr(sys, "byteorder", "little") == "big"   # file is little-endian
    with open(noise_path(), "rb") as f:
        f.seek(row * HALF_SCREEN * 2)
        if q16:
            # straight into the caller's uint16 buffers: no temporary
            if not _read_parts(f, parts, m):
                raise OSError("texel: %s is truncated" % NOISE_FILE)
        else:
            out = parts[0][0]
            chunk = u16_buffer(_CHUNK)
            mv = memoryview(chunk)
            inv = 1.0 / 65535.0
            i = 0
            while i < m:
                c = m - i if m - i < _CHUNK else _CHUNK
                if f.readinto(mv[0:c]) != 2 * c:
                    raise OSError("texel: %s is truncated" % NOISE_FILE)
                if big:
                    _swap16(chunk, c)
                for j in range(c):
                    out[i + j] = chunk[j] * inv
                i += c
    # longer than the row: mirrored repeats (sources are always < 9600)
    if n > HALF_SCREEN:
        _mirror(n, parts, q16)


def _mirror(n, parts, q16):
    """Values HALF_SCREEN..n-1 of a noise row's map from its first HALF_SCREEN:
    value i is value k = i mod 19198 (k < 9600) or 19198 - k, a forward or a
    reversed run. Where the port has viper each run is copied chunk by chunk
    (reference_viper.copy16): the per-sample loop was ~0.25 s of a full-screen
    noise reference on a stock Pico (about 0.29 s in all). The same values
    either way. q16: uint16 parts (else floats: the loop)."""
    first = parts[0][0]
    size = len(first)                   # chunks: value i at [i // size][i % size]
    copy = _copy16() if q16 else False
    if not copy:
        if len(parts) == 1:
            for i in range(HALF_SCREEN, n):
                k = i % _MIRROR_PERIOD
                first[i] = first[k if k < HALF_SCREEN else _MIRROR_PERIOD - k]
            return
        for i in range(HALF_SCREEN, n):
            k = i % _MIRROR_PERIOD
            k = k if k < HALF_SCREEN else _MIRROR_PERIOD - k
            parts[i // size][0][i % size] = parts[k // size][0][k % size]
        return
    i = HALF_SCREEN
    while i < n:
        k = i % _MIRROR_PERIOD
        if k < HALF_SCREEN:             # forward from k
            s, step, run = k, 1, HALF_SCREEN - k
        else:                           # backward from 19198 - k
            s, step, run = _MIRROR_PERIOD - k, -1, _MIRROR_PERIOD - k
        if run > n - i:
            run = n - i
        while run > 0:                  # pieces within one chunk of each
            so = s % size
            c = size - i % size
            room = size - so if step == 1 else so + 1
            if room < c:
                c = room
            if run < c:
                c = run
            copy(parts[i // size][0], i % size, parts[s // size][0], so, c, step)
            i += c
            s += c * step
            run -= c


_COPY16 = None


def _copy16():
    """reference_viper.copy16, or False where the port has no viper."""
    global _COPY16
    if _COPY16 is None:
        from ..compat import native
        _COPY16 = native("texel.gen.reference_viper", "copy16") or False
    return _COPY16


# --- band-pass noise ---------------------------------------------------------
def _check_num(key, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError("%s: expected a number in [%r, %r], got %r" % (key, lo, hi, value))
    value = float(value)
    if not (lo <= value <= hi):             # also rejects nan
        raise ValueError("%s: %r is out of range [%r, %r]" % (key, value, lo, hi))
    return value


def bandpass_coefficients(fc_cpmm, zeta):
    """Biquad (b0, a1, a2) of the band-pass H(s) = 2*zeta*w0*s / (s^2 + 2*zeta*w0*s
    + w0^2) by the bilinear transform, pre-warped so the centre lands exactly on
    fc: with K = tan(pi*fc*dx), a0 = 1 + 2*zeta*K + K^2,
    b0 = 2*zeta*K/a0, b1 = 0, b2 = -b0, a1 = 2*(K^2 - 1)/a0, a2 = (1 - 2*zeta*K + K^2)/a0.
    Gain is exactly 1 at fc and 0 at DC and Nyquist."""
    fc = _check_num("fc_cpmm", fc_cpmm, FC_MIN, FC_MAX)
    zeta = _check_num("zeta", zeta, ZETA_MIN, ZETA_MAX)
    K = math.tan(math.pi * fc * DX_MM)
    zk = 2.0 * zeta * K
    kk = K * K
    a0 = 1.0 + zk + kk
    return zk / a0, 2.0 * (kk - 1.0) / a0, (1.0 - zk + kk) / a0


def burn_in_samples(fc_cpmm, zeta):
    """Samples filtered and discarded before the map starts (see _BURN_TAUS)."""
    b0, a1, a2 = bandpass_coefficients(fc_cpmm, zeta)
    d = a1 * a1 - 4.0 * a2
    if d < 0.0:                      # complex pair, |p|^2 = a2
        rho = math.sqrt(a2)
    else:                            # two real poles; the larger one is slowest
        sd = math.sqrt(d)
        rho = max(abs(-a1 + sd), abs(-a1 - sd)) * 0.5
    if rho >= 1.0:                   # cannot happen for valid fc, zeta; be safe
        return BURN_MAX
    tau = -1.0 / math.log(rho)
    need = _BURN_TAUS * tau
    if need >= BURN_MAX:
        return BURN_MAX
    b = _BURN_STEP * int(math.ceil(need / _BURN_STEP))
    return b if b > 0 else _BURN_STEP


def _bp_run(fc, zeta, seed, n, out, mode, mean=0.0, inv=0.0):
    # mode 0: store raw y in out (float); 1: statistics only; 2: store u16 map
    # (out: _parts(), written part by part).
    # Returns (mean, population variance) of y over the n map samples
    # (Welford's update: stable in float32 over 1e5+ samples).
    b0, a1, a2 = bandpass_coefficients(fc, zeta)
    burn = burn_in_samples(fc, zeta)
    rng = Rng(seed)                  # validates seed: int in [0, 2^32)
    normal = rng.normal
    s1 = 0.0
    s2 = 0.0
    # transposed direct form II, b1 = 0, b2 = -b0
    for _ in range(burn):
        x = normal()
        y = b0 * x + s1
        s1 = s2 - a1 * y
        s2 = -b0 * x - a2 * y
    mu = 0.0
    m2 = 0.0
    if mode == 2:
        for buf, c in out:
            for i in range(c):
                x = normal()
                y = b0 * x + s1
                s1 = s2 - a1 * y
                s2 = -b0 * x - a2 * y
                v = 0.5 + (y - mean) * inv
                if v < 0.0:
                    v = 0.0
                elif v > 1.0:
                    v = 1.0
                buf[i] = int(v * 65535.0 + 0.5)
        return mean, 0.0
    for i in range(n):
        x = normal()
        y = b0 * x + s1
        s1 = s2 - a1 * y
        s2 = -b0 * x - a2 * y
        d = y - mu
        mu += d / (i + 1)
        m2 += d * (y - mu)
        if mode == 0:
            out[i] = y
    return mu, m2 / n


def _scale(var):
    # 1/(6*sd): +-3 SD spans the map [0, 1]; about 0.27 % of samples clip.
    if var <= 0.0:
        return 0.0
    return 1.0 / (SD_SPAN * math.sqrt(var))


def bandpass(fc_cpmm, zeta, seed=0, length_samples=9600):
    """White noise (Rng(seed).normal(), after burn_in_samples() discarded draws)
    through bandpass_coefficients(fc_cpmm, zeta); the output y is normalised over
    the map: v = clip(0.5 + (y - mean)/(6*sd), 0, 1) (sd: population SD).
    fc_cpmm in [0.01, 94] c/mm, zeta = 1/(2Q) in [0.01, 10]. Deterministic
    from (fc, zeta, seed, length): bit-identical wherever floats are binary64."""
    n = _check_length(length_samples)
    out = float_buffer(n)
    mean, var = _bp_run(fc_cpmm, zeta, seed, n, out, 0)
    inv = _scale(var)
    for i in range(n):
        v = 0.5 + (out[i] - mean) * inv
        if v < 0.0:
            v = 0.0
        elif v > 1.0:
            v = 1.0
        out[i] = v
    return out


def bandpass_u16(fc_cpmm, zeta, seed=0, length_samples=9600, out=None):
    """bandpass() as uint16 (q = round(v*65535), equal to converting bandpass()
    sample by sample) without a float map in RAM: the noise is generated twice,
    once for mean/SD and once to write (twice the time, half the memory)."""
    n = _check_length(length_samples)
    if out is None:
        out = u16_buffer(n)
    parts = _parts(out, n)              # (a tuple of chunks too: reference_u16)
    mean, var = _bp_run(fc_cpmm, zeta, seed, n, None, 1)
    _bp_run(fc_cpmm, zeta, seed, n, parts, 2, mean, _scale(var))
    return out
