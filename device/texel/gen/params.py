# The texture parameter set: a plain dict that crosses the serial link as a
# literal. validate() is the one gate every path goes through (render, scenes,
# the REPL entry points); it never mutates its input and returns a new dict
# with every default filled in, or raises ValueError naming key, value, range,
# in the words every device validator shares (gen/check.py: _words()).

FORMAT_VERSION = 2     # what a parameter set without "v" means (issue 32: format 2 is the one default; "v": 1 asks for the lab's float plan)
FORMAT_LATEST = 2      # texture format 2: the integer plan (gen/plan_int.py)
FORMAT_NEW = 2         # what the host writes into every texture it makes (CLI, push_texel, scenes, the lab)

# Geometry of the TPaD display (docs/background.md §1): 5.3 um per map sample.
DX_MM = 0.0053
NYQUIST_CPMM = 1.0 / (2.0 * DX_MM)          # 94.34 cycles/mm
# 10*log10(94.3396) = 19.7470 dB: the highest pitch the display can show.
PITCH_DB_MAX = 19.747
PITCH_DB_MIN = -20.0                         # 0.01 cycles/mm (paper's limit)
IRREG_DB_MIN = -30.0                         # sigma = 0.001 decade
IRREG_DB_MAX = 5.0                           # sigma = 3.16 decades
QUANT_DB_MAX = 20.0                          # 2 decades: coarser than any spread
# Finest quantization grid: 0.001 dB = 1e-4 decades of log10 f. Finer grids
# are no quantization a finger could feel, and a grid near zero makes the plan's
# log10(f)/q overflow (1e-308 did: an OverflowError after validation passed).
# 1e-4 decades is still ~400 float32 ulps of log10 f at the Nyquist pitch, so
# the grid means the same on a float32 board. 0 stays "off".
QUANT_DB_MIN = 0.001
TEXEL_MAX = 1048576                          # samples; > map length is allowed
LENGTH_MAX = 1048576                         # 5.5 m of display; boards refuse what won't fit
SEED_MAX = 4294967295                        # seeds are 32-bit unsigned

# key: (kind, default, lo, hi); kind "f" float (int accepted), "i" int.
# Required keys have default None.
SPEC = {
    "pitch_db": ("f", None, PITCH_DB_MIN, PITCH_DB_MAX),
    "irregularity_db": ("f", None, IRREG_DB_MIN, IRREG_DB_MAX),
    "texel_samples": ("i", 50, 1, TEXEL_MAX),
    "length_samples": ("i", 9600, 1, LENGTH_MAX),
    "quant_db": ("f", 0.0, 0.0, QUANT_DB_MAX),
    "seed": ("i", 0, 0, SEED_MAX),
    "gain": ("f", 1.0, 0.0, 1.0),
    # Texture format: 1 = the lab's float plan (gen/plan.py, reproduces the
    # original to 1e-9 in float64, each runtime's own float elsewhere),
    # 2 = the integer plan (gen/plan_int.py, bit-identical on every runtime).
    "v": ("i", FORMAT_VERSION, 1, FORMAT_LATEST),
    # Explicit band limit (our addition): None = faithful (no clamping, drawn
    # pitches above Nyquist alias as in the original); a number in cycles/mm
    # clamps every drawn pitch to at most that value.
    "band_limit_cpmm": ("f", None, 0.01, NYQUIST_CPMM),
}

# Texture options: keys in the canonical dict ONLY when set to something else
# than their default, so every texture, scene file, session record and golden
# made before they existed stays byte for byte what it was (and plays the
# same). Kept apart from SPEC/KEYS, which hold the keys every canonical dict
# has (and which the command line, scenes and tests enumerate as such).
# Seed 001's stimulus (../shared/seeds/001_*.txt; docs/generator.md, "Seed
# 001's stimulus"): a lower pitch bound in cycles/mm (None = none; a texel
# drawn below it is redrawn from a second stream: gen/plan.py,
# gen/plan_int.py), and the phase at texel borders. Kind "w": a word, the
# third field holds the allowed words.
PHASES = ("continuous", "reset")
OPTION_SPEC = {
    "min_cpmm": ("f", None, 0.01, NYQUIST_CPMM),
    "phase": ("w", "continuous", PHASES, None),
}

# Spelled out, not tuple(SPEC): MicroPython dicts do not keep insertion order,
# and this order is both the order validate() checks keys in (which bad key is
# named first) and the list in the unknown-key message.
KEYS = ("pitch_db", "irregularity_db", "texel_samples", "length_samples", "quant_db",
        "seed", "gain", "v", "band_limit_cpmm")
OPTION_KEYS = ("min_cpmm", "phase")         # checked after KEYS, in this order
# Keys whose None means "off" (a bound not set).
NONE_OK = ("band_limit_cpmm", "min_cpmm")


_TO_GRID = []


def _to_grid():
    # gen/grid.py's to_grid, imported at the first format-2 texture and kept: an
    # import statement at every texel region's check took ~1 ms each on a stock Pico
    if not _TO_GRID:
        from .grid import to_grid
        _TO_GRID.append(to_grid)
    return _TO_GRID[0]


def _words():
    """gen/check.py, imported at the first refusal: the generator alone
    (import texel: a full map on a Pico-sized heap) never holds it."""
    from . import check
    return check


def check_value(key, value):
    """Return value converted to its canonical type, or raise ValueError.
    key: one of KEYS or OPTION_KEYS."""
    kind, default, lo, hi = SPEC[key] if key in SPEC else OPTION_SPEC[key]
    # the common case first (a float in range; NaN fails the comparison):
    # a push validates every texel key, at ~0.25 ms each on a Pico
    if type(value) is float and kind == "f" and lo <= value <= hi and (
            value == 0.0 or key != "quant_db" or value >= QUANT_DB_MIN):
        return value
    if kind == "w":                 # a word: lo holds the allowed ones
        if type(value) is str and value in lo:
            return value
        _words().not_a_word(key, value, lo)
    if value is None:
        if key in NONE_OK:
            return None
        c = _words()
        c.fail(key, "None is not allowed (expected a number in %s)" % c.rng(lo, hi))
    # bool is an int subclass in Python: reject it explicitly.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _words().expected(key, "an int" if kind == "i" else "a number", lo, hi,
                          "%s %r" % (type(value).__name__, value))
    if kind == "i" and not isinstance(value, int):
        _words().expected(key, "an int", lo, hi, "float %r" % (value,))
    if not lo <= value <= hi:
        # (NaN fails the comparison too.) A float is shown as a float; an int
        # in a float field as the float it would become - unless it has none:
        # float(10**400) raised OverflowError on CPython (after the key had
        # been accepted as "a number"), while MicroPython turns it into inf
        # and called it "not finite". Every float range here is far inside
        # +-2^62, so an int beyond that is simply out of range, worded alike
        # on every port and never converted (compared exactly on CPython, as
        # inf on MicroPython: out of range either way).
        c = _words()
        if isinstance(value, float):
            if not c.finite(value):
                c.not_finite(key, value, lo, hi)
            value = float(value)
        elif kind == "f" and -c.BIG < value < c.BIG:
            value = float(value)
        c.out_of_range(key, value, lo, hi)
    if kind == "f":
        value = float(value)
    if key == "quant_db" and 0.0 < value < QUANT_DB_MIN:
        _words().fail(key, "%r is too fine a grid (0 = off, else %r .. %r dB)"
                      % (value, QUANT_DB_MIN, hi))
    return value


def validate(params):
    """Check a parameter dict completely; return a new dict with defaults.

    Raises ValueError naming the first bad key, its value and the allowed
    range. Never changes `params`."""
    if not isinstance(params, dict):
        raise ValueError("texel parameters must be a dict, got %s" % type(params).__name__)
    # Several unknown keys: name the smallest repr, not the first in the dict's
    # iteration order (which differs between CPython and MicroPython).
    unknown = None
    for key in params:
        if key not in SPEC and key not in OPTION_SPEC:
            unknown = [repr(k) for k in params if k not in SPEC and k not in OPTION_SPEC]
            break
    if unknown:
        raise ValueError("unknown key %s (allowed: %s)" % (min(unknown), ", ".join(KEYS + OPTION_KEYS)))
    out = {}
    for key in KEYS:
        kind, default, lo, hi = SPEC[key]
        if key in params:
            out[key] = check_value(key, params[key])
        elif default is None and key != "band_limit_cpmm":
            raise ValueError("missing required key %r (a number in %s)"
                             % (key, _words().rng(lo, hi)))
        else:
            out[key] = default
    for key in OPTION_KEYS:
        if key in params:
            v = check_value(key, params[key])
            if v != OPTION_SPEC[key][1]:        # the default: left out
                out[key] = v
    if out["v"] == 2:
        # format 2's grid (gen/grid.py: imported only here, so format 1 on a
        # Pico-sized heap carries none of it)
        _to_grid()(out, _range_of)
    lo_b = out.get("min_cpmm")
    if lo_b is not None and out["band_limit_cpmm"] is not None and lo_b >= out["band_limit_cpmm"]:
        # (compared on format 2's grid where the plan will use them)
        _words().fail("min_cpmm", "%r must be below band_limit_cpmm %r (cycles/mm)"
                      % (lo_b, out["band_limit_cpmm"]))
    return out


def _range_of(key):
    """(lo, hi) of a key of SPEC or OPTION_SPEC (gen/grid.py keeps values in it)."""
    return (SPEC.get(key) or OPTION_SPEC[key])[2:4]


def has_options(p):
    """A validated set p sets a texture option (gen/options.py applies it)."""
    return p.get("min_cpmm") is not None or p.get("phase", "continuous") != "continuous"


def texel_count(p):
    """Texels needed for the map; the last one is cut short when the map
    length is not a multiple of the texel length."""
    L = p["texel_samples"]
    return (p["length_samples"] + L - 1) // L
