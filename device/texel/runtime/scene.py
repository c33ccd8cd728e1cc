# Scenes: what plays where on the display (docs/runtime.md, scene.py).
#
#   validate(scene, display)                  -> canonical dict (no maps allocated)
#   build(canonical, display, engine=None, idle_default=0, max_bytes=None) -> Scene
#   Scene.amp(pos)   uint16 amplitude at display position pos (hard-IRQ safe)
#   Scene.idle, Scene.nbytes, Scene.describe(), Scene.source
#
# A scene is a plain dict that crosses the serial link as a literal:
#   {"regions": [{"start_mm": 0, "end_mm": 50.88,
#                 "texture": {"kind": "reference", "name": "4sin"}}, ...],
#    "idle_amplitude": 0,          # optional uint16; else the board's default
#    "name": "split 4sin | texel", "notes": "..."}   # optional text (NAME_MAX, NOTES_MAX)
#
# Texture kinds (every other key is refused):
#   texel      the texel parameter keys (params.KEYS) except length_samples,
#              which the region sets to its own length, and the texture
#              options (params.OPTION_KEYS: min_cpmm, phase; in the canonical
#              texture only when set); checked by texel.validate, so its
#              messages are the generator's own.
#   reference  "name": one of texel.reference_names(); rendered region-long.
#   constant   "level": friction reduction 0..1 (no buffer: one table entry).
#   samples    an upload: exactly one of "values" (numbers 0..1) or "u16"
#              (ints 0..65535; or an Upload (runtime/upload.py) the host filled
#              through texel.app.upload_* - large data crosses the link as data,
#              not as a literal the board compiles), 1..MAX_SAMPLES of them,
#              and "fit":
#              "tile" (default): value k plays at region position k mod m -
#                  one value per display position (5.3 um), so the spatial
#                  frequencies the host designed are the ones felt;
#              "stretch": the m values are spread over the whole region by
#                  linear interpolation, first value at the region's first
#                  position, last value at its last (no filtering when
#                  m > region length: shrinking picks interpolated points).
#
# Canonical form (what validate returns; validate(canonical) == canonical):
# the same dict with regions sorted by start; numbers as floats/ints; texel
# textures with every default filled in (no length_samples); samples as
# {"kind": "samples", "u16": tuple of ints, "fit": ...} ("values" become
# round(v * 65535), half up; a tuple is kept as it is, a list is copied once;
# an Upload becomes its upload.Chunks, which stay as they are);
# "idle_amplitude", "name" and "notes" only when the scene gave them.
#
# Positions: start_mm/end_mm are converted to display indices by rounding to
# the nearest sample, halves up: pos = floor(mm * 1000 / dx_um + 0.5); the
# region covers positions [start, end) (end exclusive), so regions that touch
# in mm touch in positions. Overlap is judged on these rounded positions;
# a region that rounds to no position at all is refused.
#
# Errors: every problem raises ValueError whose message starts with the path
# of the offending item: "scene", "idle_amplitude", "regions", "regions[1]",
# "regions[1].end_mm", "regions[1].texture.pitch_db", "regions[0].texture.u16[17]".
# Values are shown bounded (long strings cut, containers by type and size,
# huge ints by name), so a hostile literal cannot blow up the message.
#
# Memory: build() holds one uint16 buffer per texel/reference/samples region,
# exactly region-long (2 bytes per position), nothing for constants and gaps,
# plus the region table (4 ints per region). Rendering a texel region also
# needs its plan transiently (about 24 bytes per texel on the unix port,
# 16 on float32 boards) and a reference band-pass region its filter state.
#
# Hot path: Scene.amp() scans a flat array('i') of (start, end, kind, value)
# per region, sorted by start and closed by a sentinel row, and indexes a
# tuple of buffers fixed at build time: small ints only, no allocation.
# Linear scan vs binary search, unix port, us per call without the call
# itself (tests/runtime/test_scene.py measures both): 1 region ~0.17 vs ~0.30,
# 4: ~0.21 vs ~0.40, 16: ~0.44 vs ~0.55 (uniform positions), 16 worst case
# (last region) ~0.70 vs ~0.56. The scan wins for the scenes that matter (the
# study's split screen has 2 regions) and loses ~0.15 us in the worst
# 16-region case: linear scan.
from array import array
from ..compat import u16_one_block
from ..gen.params import validate as texel_validate
from ..gen.params import SPEC as TEXEL_SPEC
from ..gen.params import KEYS as _TEXEL_ALL_KEYS
from ..gen.params import OPTION_KEYS as TEXEL_OPTIONS
from ..gen.params import LENGTH_MAX
# the checks every device validator shares (their words: gen/check.py)
from ..gen.check import BIG, is_int, is_num, finite, show, out_of_range, \
    not_finite, expected, fail

MAX_REGIONS = 16            # regions per scene (amp() cost grows with the count)
MAX_SAMPLES = 19200         # values per samples region (one full TPaD screen)
U16_MAX = 65535
KINDS = ("texel", "reference", "constant", "samples", "brush")
FITS = ("tile", "stretch")
SCENE_KEYS = ("regions", "idle_amplitude", "name", "notes")
# A scene's own words: "name" (shown by status, listed by `texelpad scenes`)
# and "notes" (what it is for, where it comes from). Bounded so a scene file
# stays a scene and status() stays small; any text, checked as a str only.
NAME_MAX = 64
NOTES_MAX = 2000
REGION_KEYS = ("start_mm", "end_mm", "texture")
TEXEL_KEYS = tuple(k for k in _TEXEL_ALL_KEYS if k != "length_samples")
_TEXEL_ANY = TEXEL_KEYS + TEXEL_OPTIONS     # the options: only when set
TEXTURE_KEYS = {
    "texel": ("kind",) + TEXEL_KEYS,
    "reference": ("kind", "name"),
    "constant": ("kind", "level"),
    "samples": ("kind", "values", "u16", "fit"),
    "brush": ("kind", "brush", "seed"),
}

# Region table: STRIDE ints per region, (start, end, kind, value), sorted by
# start, then one sentinel row (SENTINEL, SENTINEL, K_CONST, 0) that ends the
# scan. kind K_CONST: value is the amplitude; K_BUF: value indexes the buffers.
STRIDE = 4
# > any position, and still a small int on a 32-bit board (2^30 - 1): a
# larger value would come out of the array as a heap bigint inside the IRQ.
SENTINEL = 0x3FFFFFFF
K_CONST = 0
K_BUF = 1
K_PLAN = 2              # texel region played from its integer plan, sample by sample
K_CHUNK = 3             # an uploaded map in 1 KB chunks (runtime/upload.py): value
                        # indexes the buffers, whose entry is a tuple of array('H')
CHUNK_BITS = 9          # 512 values (1 KB) per chunk (upload.py and refresh_viper.py use these)
CHUNK_MASK = 511
# A texel region is kept as its plan (t28, d28: 8 bytes per texel) and
# evaluated at the finger's position, instead of rendered (2 bytes per
# sample), when no engine is asked for and its texels are at most PLAN_MAX_L
# samples long (so k*d stays a small int in 16 x 14-bit limb products) and
# longer than 4 samples (where the plan is smaller than the map).
PLAN_MAX_L = 65535
_ITEM = len(bytes(array("i", [0])))     # bytes per table int (4)

_SHOW = 40                  # characters of a string shown in a message


# --- messages ----------------------------------------------------------------
def _got(v):
    """A bounded description of an untrusted value: type and value, or type
    and size for containers; never a repr of unbounded size."""
    if v is None or isinstance(v, (bool, float)):
        return "%s %r" % (type(v).__name__, v)
    if isinstance(v, int):              # beyond +-2^62 by name only
        return "int %r" % v if -BIG < v < BIG else show(v)
    if isinstance(v, str):
        return "str " + _qstr(v)
    if isinstance(v, (list, tuple)):
        return "%s of %d items" % (type(v).__name__, len(v))
    if isinstance(v, dict):
        return "dict of %d keys" % len(v)
    return type(v).__name__


def _qstr(s):
    """A string quoted like repr() for printable ASCII, but every other
    character escaped (\\xNN, \\uNNNN, \\UNNNNNNNN) on every port - CPython's
    repr shows printable non-ASCII as is, MicroPython's escapes it - and cut
    to _SHOW characters: messages stay short, ASCII and identical."""
    cut = s[:_SHOW]
    q = '"' if ("'" in cut and '"' not in cut) else "'"
    out = [q]
    for c in cut:
        o = ord(c)
        if c == q or c == "\\":
            out.append("\\" + c)
        elif c == "\n":
            out.append("\\n")
        elif c == "\r":
            out.append("\\r")
        elif c == "\t":
            out.append("\\t")
        elif 32 <= o < 127:
            out.append(c)
        elif o < 256:
            out.append("\\x%02x" % o)
        elif o < 65536:
            out.append("\\u%04x" % o)
        else:
            out.append("\\U%08x" % o)
    out.append(q)
    if len(s) > _SHOW:
        out.append("... (%d chars)" % len(s))
    return "".join(out)


def _plain_str(s):
    # short printable ASCII: repr() is the same on every port
    if len(s) > _SHOW:
        return False
    for c in s:
        if not 32 <= ord(c) < 127:
            return False
    return True


def _key(k):
    return _qstr(k) if isinstance(k, str) else _got(k)


def _check_keys(path, d, allowed, options=()):
    """Refuse keys not in `allowed` or `options`; with several, name the
    smallest shown form (dict order differs between CPython and MicroPython).
    The message lists `allowed`, then `options` (the texel options:
    docs/generator.md)."""
    bad = None
    for k in d:
        if not (isinstance(k, str) and (k in allowed or k in options)):
            s = _key(k)
            if bad is None or s < bad:
                bad = s
    if bad is not None:
        fail(path, "unknown key %s (allowed: %s)" % (bad, ", ".join(tuple(allowed) + tuple(options))))


def _dict(path, v, what):
    if not isinstance(v, dict):
        fail(path, "expected %s, got %s" % (what, _got(v)))
    return v


def _num(path, v, lo, hi):
    """A finite number (int accepted, bool refused) in [lo, hi] -> float."""
    if not is_num(v):
        expected(path, "a number", lo, hi, _got(v))
    if isinstance(v, int):
        if v < lo or v > hi:            # exact int/float comparison: no overflow
            out_of_range(path, v, lo, hi)
        return float(v)
    if not finite(v):
        not_finite(path, v, lo, hi)
    if v < lo or v > hi:
        out_of_range(path, v, lo, hi)
    return float(v)


def _int(path, v, lo, hi):
    """An int (bool refused) in [lo, hi]."""
    if not is_int(v):
        expected(path, "an int", lo, hi, _got(v))
    if v < lo or v > hi:
        out_of_range(path, v, lo, hi)
    return v


# --- display -------------------------------------------------------------------
def _display(display):
    """The board's display dict -> (positions, dx_um). Extra keys are the
    board's business (boards.py validates boards)."""
    _dict("display", display, "the board's display dict {'positions': ..., 'dx_um': ...}")
    for k in ("positions", "dx_um"):
        if k not in display:
            fail("display", "missing required key %r" % (k,))
    positions = _int("display.positions", display["positions"], 1, LENGTH_MAX)
    dx_um = _num("display.dx_um", display["dx_um"], 0.001, 1000000.0)
    return positions, dx_um


def to_position(mm, dx_um):
    """mm from the display's start -> nearest position index (halves up)."""
    return int(mm * 1000.0 / dx_um + 0.5)


def _mm_in(path, v, total_mm, positions, dx_um):
    """A region boundary in mm: a finite number in [0, display length]. A
    value past the end by less than half a position is accepted (it rounds
    onto the last boundary: float rounding of positions * dx must not refuse
    the display's own length). The pre-check's slack is two positions, not a
    fixed mm: on CircuitPython's 30-bit floats a display of 16,143 x 652.8 mm
    positions (10.5 km) is 10,538,408 mm, whose float steps are 2 mm, so
    total_mm + 1.0 was total_mm again and its own length (the literal rounding
    to 10,538,410) was refused. Two positions are at least 4 float steps on
    every allowed display: a step there is at most total_mm * 2^-21 (a 22-bit
    significand), and a position is total_mm / positions >= total_mm * 2^-20."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return _num(path, v, 0.0, total_mm)
    lim = total_mm + 1.0 + dx_um / 500.0
    if isinstance(v, int) and (v < 0 or v > lim):
        return _num(path, v, 0.0, total_mm)          # refused without float overflow
    if v == v and 0.0 <= v <= lim and to_position(v, dx_um) <= positions:
        return float(v)
    return _num(path, v, 0.0, total_mm)


def _mm(pos, dx_um):
    return round(pos * dx_um / 1000.0, 4)


# --- textures ------------------------------------------------------------------
def _texel(path, tex, n):
    p = {}
    for k in TEXEL_KEYS:
        if k in tex:
            v = tex[k]
            # texel.validate shows the value with %r: hand it only values
            # whose repr is small and the same on every port; describe the
            # rest here, in its format.
            if not (v is None or isinstance(v, (bool, float))
                    or (isinstance(v, int) and -BIG < v < BIG)
                    or (isinstance(v, str) and _plain_str(v))):
                kind, _, lo, hi = TEXEL_SPEC[k]
                expected(path + "." + k, "an int" if kind == "i" else "a number", lo, hi,
                         _got(v))
            p[k] = v
    for k in TEXEL_OPTIONS:     # texel.validate bounds what it shows of these
        if k in tex:
            p[k] = tex[k]
    p["length_samples"] = n
    try:
        c = texel_validate(p)
        err = None
    except ValueError as e:
        err = str(e)
    if err is not None:
        # "pitch_db: nan is not finite ..." -> "<path>.pitch_db: ..."
        cut = err.find(":")
        if cut > 0 and (err[:cut] in TEXEL_SPEC or err[:cut] in TEXEL_OPTIONS):
            raise ValueError(path + "." + err)
        fail(path, err)
    out = {"kind": "texel"}
    for k in _TEXEL_ANY:
        if k in c:
            out[k] = c[k]
    return out


def _reference(path, tex):
    from .. import reference_names
    if "name" not in tex:
        fail(path, "missing required key 'name' (one of: %s)" % ", ".join(reference_names()))
    name = tex["name"]
    known = reference_names()
    if not isinstance(name, str) or name not in known:
        fail(path + ".name", "unknown reference texture %s (known: %s)"
             % (_qstr(name) if isinstance(name, str) else _got(name), ", ".join(known)))
    return {"kind": "reference", "name": name}


def _constant(path, tex):
    if "level" not in tex:
        fail(path, "missing required key 'level' (a number in [0.0, 1.0])")
    return {"kind": "constant", "level": _num(path + ".level", tex["level"], 0.0, 1.0)}


def _samples(path, tex):
    has_v = "values" in tex
    has_u = "u16" in tex
    if has_v == has_u:
        fail(path, "give exactly one of 'values' (numbers 0..1) or 'u16' "
             "(ints 0..65535), %d at most" % MAX_SAMPLES)
    fit = tex.get("fit", "tile")
    if not isinstance(fit, str) or fit not in FITS:
        fail(path + ".fit", "expected one of %s, got %s" % (", ".join(FITS), _got(fit)))
    key = "u16" if has_u else "values"
    seq = tex[key]
    p = path + "." + key
    if has_u and getattr(seq, "UPLOAD", False):     # texel.runtime.upload.Upload
        if seq.filled != len(seq.buf):
            fail(p, "the upload is incomplete (%d of %d values arrived)"
                 % (seq.filled, len(seq.buf)))
        seq = seq.buf
    if has_u and getattr(seq, "CHUNKS", False):     # upload.Chunks: uint16 by construction
        return {"kind": "samples", "u16": seq, "fit": fit}
    if not isinstance(seq, (list, tuple)):
        fail(p, "expected a list of %s, got %s"
             % ("ints in [0, 65535]" if has_u else "numbers in [0.0, 1.0]", _got(seq)))
    m = len(seq)
    if m < 1 or m > MAX_SAMPLES:
        fail(p, "%d values; allowed 1 .. %d" % (m, MAX_SAMPLES))
    # check every element before anything is converted (index in the path)
    if has_u:
        for i in range(m):
            x = seq[i]
            if isinstance(x, bool) or not isinstance(x, int) or x < 0 or x > U16_MAX:
                _int("%s[%d]" % (p, i), x, 0, U16_MAX)
        # a tuple is immutable: the canonical form may share it
        vals = seq if type(seq) is tuple else tuple(seq)
    else:
        for i in range(m):
            x = seq[i]
            if (isinstance(x, bool) or not isinstance(x, (int, float))
                    or not (0.0 <= x <= 1.0)):      # also catches nan
                _num("%s[%d]" % (p, i), x, 0.0, 1.0)
        vals = tuple(int(x * 65535.0 + 0.5) for x in seq)
    return {"kind": "samples", "u16": vals, "fit": fit}


def _texture(path, tex, n):
    if not isinstance(tex, dict):       # (the message built only when needed: 0.5 ms on a Pico)
        _dict(path, tex, "a texture dict with 'kind' (one of: %s)" % ", ".join(KINDS))
    if "kind" not in tex:
        fail(path, "missing required key 'kind' (one of: %s)" % ", ".join(KINDS))
    kind = tex["kind"]
    if not isinstance(kind, str) or kind not in KINDS:
        fail(path + ".kind", "unknown kind %s (one of: %s)"
             % (_qstr(kind) if isinstance(kind, str) else _got(kind), ", ".join(KINDS)))
    if kind == "texel" and "length_samples" in tex:
        fail(path + ".length_samples", "set by the region (here %d samples); remove it" % n)
    # (the unknown-key message lists TEXTURE_KEYS and the options:
    # tests/runtime/test_scene.py pins it as TEXEL_ALLOWED)
    _check_keys(path, tex, TEXTURE_KEYS[kind], TEXEL_OPTIONS if kind == "texel" else ())
    if kind == "texel":
        return _texel(path, tex, n)
    if kind == "reference":
        return _reference(path, tex)
    if kind == "constant":
        return _constant(path, tex)
    if kind == "brush":                 # (gen/brush.py checks it: scene.py stays small)
        from ..gen.brush import region_texture
        return region_texture(path, tex)
    return _samples(path, tex)


# --- scene -----------------------------------------------------------------------
def _check(scene, display):
    """validate() plus the positions: (canonical, [(start, end), ...] in the
    canonical order, positions, dx_um)."""
    positions, dx_um = _display(display)
    total_mm = positions * dx_um / 1000.0
    _dict("scene", scene, "a dict with 'regions'")
    _check_keys("scene", scene, SCENE_KEYS)
    if "regions" not in scene:
        fail("scene", "missing required key 'regions' (a list of 1 .. %d regions)"
             % MAX_REGIONS)
    regs = scene["regions"]
    if not isinstance(regs, (list, tuple)):
        fail("regions", "expected a list of 1 .. %d regions, got %s" % (MAX_REGIONS, _got(regs)))
    if len(regs) < 1 or len(regs) > MAX_REGIONS:
        fail("regions", "%d regions; allowed 1 .. %d" % (len(regs), MAX_REGIONS))
    out = {}
    if "idle_amplitude" in scene:
        out["idle_amplitude"] = _int("idle_amplitude", scene["idle_amplitude"], 0, U16_MAX)
    for k, top in (("name", NAME_MAX), ("notes", NOTES_MAX)):
        if k in scene:
            v = scene[k]
            if not isinstance(v, str) or (k == "name" and not v) or len(v) > top:
                fail(k, "expected a string of %s%d characters, got %s"
                     % ("1 .. " if k == "name" else "at most ", top,
                        _got(v) if not isinstance(v, str) else "%d characters" % len(v)))
            out[k] = v
    spans = []
    canon = []
    for i in range(len(regs)):
        path = "regions[%d]" % i
        r = _dict(path, regs[i], "a region dict with 'start_mm', 'end_mm', 'texture'")
        _check_keys(path, r, REGION_KEYS)
        for k in REGION_KEYS:
            if k not in r:
                fail(path, "missing required key %r" % (k,))
        s_mm = _mm_in(path + ".start_mm", r["start_mm"], total_mm, positions, dx_um)
        e_mm = _mm_in(path + ".end_mm", r["end_mm"], total_mm, positions, dx_um)
        if not s_mm < e_mm:
            fail(path + ".end_mm", "%r is not after start_mm %r" % (e_mm, s_mm))
        s = to_position(s_mm, dx_um)
        e = to_position(e_mm, dx_um)
        if s >= e:
            fail(path, "%r .. %r mm rounds to no position (one position is %r um)"
                 % (s_mm, e_mm, dx_um))
        tex = _texture(path + ".texture", r["texture"], e - s)
        canon.append({"start_mm": s_mm, "end_mm": e_mm, "texture": tex})
        spans.append((s, e, i))
    order = sorted(spans)
    for j in range(1, len(order)):
        s, e, i = order[j]
        ps, pe, pi = order[j - 1]
        if s < pe:
            raise ValueError("regions[%d]: overlaps regions[%d] (positions %d..%d and %d..%d)"
                             % (i, pi, s, e, ps, pe))
    out["regions"] = [canon[i] for (s, e, i) in order]
    return out, [(s, e) for (s, e, i) in order], positions, dx_um


def check(scene, display):
    """validate() and what build() needs besides: (canonical, spans,
    positions, dx_um). Hand it to build(checked=) to build without checking
    the same scene twice (6.7 of a Pico's 23 ms build of a full-screen texel
    scene were the second check)."""
    return _check(scene, display)


def validate(scene, display):
    """Check a scene completely against the board's display dict
    ({"positions": 19200, "dx_um": 5.3}); return its canonical dict.
    Allocates no sample buffer; never changes `scene`. Raises ValueError
    whose message starts with the path of the bad item."""
    return _check(scene, display)[0]


def buffer_bytes(canonical, display):
    """Bytes build() would hold for the scene (buffers + region table)."""
    c, spans, positions, dx_um = _check(canonical, display)
    return _need(c, spans)[0]


def _on_plan(tex, n, engine):
    """Whether a region plays from its plan (see K_PLAN)."""
    if tex["kind"] != "texel" or engine is not None:
        return False
    L = tex["texel_samples"]
    return 4 < L <= PLAN_MAX_L and L < n


def _need(c, spans, engine=None):
    regions = c["regions"]
    bufs = 0
    for k in range(len(regions)):
        tex = regions[k]["texture"]
        n = spans[k][1] - spans[k][0]
        if _on_plan(tex, n, engine):
            bufs += 8 * ((n + tex["texel_samples"] - 1) // tex["texel_samples"])
        elif tex["kind"] != "constant":
            bufs += 2 * n
    table = STRIDE * (len(regions) + 1) * _ITEM       # + the sentinel row
    return bufs + table, bufs, table


def _biggest_block(c, spans, engine=None):
    """Bytes of the largest single block the scene's regions take (a region
    rendered by an engine, or samples given inline: exactly region-long);
    0 when every region plays from a plan, chunks or flash."""
    big = 0
    for k in range(len(c["regions"])):
        tex = c["regions"][k]["texture"]
        n = spans[k][1] - spans[k][0]
        if tex["kind"] in ("constant", "brush") or _on_plan(tex, n, engine):
            continue
        if tex["kind"] == "reference" and _flash_ref(tex["name"], n) is not None:
            continue                    # the firmware's map in flash
        if tex["kind"] == "samples" and getattr(tex["u16"], "CHUNKS", False):
            continue
        big = max(big, 2 * n)
    return big


def build(canonical, display, engine=None, idle_default=0, max_bytes=None, checked=None,
          reuse=None):
    """Allocate and render what the scene's regions use and return a Scene.

    canonical: a scene (validated again here: build never trusts its input,
    unless `checked` is what check() returned for this very dict - app.push
    checks once). engine: texel engine for texel regions (None = default).
    idle_default: the board's idle amplitude (uint16) when the scene gives
    none. max_bytes: refuse (ValueError) before allocating anything when the
    scene would hold more. A MemoryError while building becomes a ValueError.
    reuse: the Scene playing now; a reference or brush region of the same
    texture and length as one of its regions shares that region's buffer
    instead of rendering it again (buffers are never written after build:
    sharing is safe while both play) - a slider that changes only the right
    half of a split screen re-renders only the right half.
    Touches no global state: the caller's current scene is unaffected."""
    if checked is not None and checked[0] is canonical:
        c, spans, positions, dx_um = checked
    else:
        c, spans, positions, dx_um = _check(canonical, display)
    if "idle_amplitude" in c:
        idle = c["idle_amplitude"]
    else:
        idle = _int("idle_default", idle_default, 0, U16_MAX)
    need, nbuf, ntab = _need(c, spans, engine)
    if max_bytes is not None:
        max_bytes = _int("max_bytes", max_bytes, 0, BIG)
        if need > max_bytes:
            raise ValueError("scene: needs %d bytes (%d of sample buffers and plans + %d of region table), "
                             "over the budget of %d bytes" % (need, nbuf, ntab, max_bytes))
    regions = c["regions"]
    if engine is not None:
        for r in regions:
            if r["texture"]["kind"] == "texel":
                from .. import engines
                if engine not in engines():
                    raise ValueError("engine: %s is not available here (available: %s)"
                                     % (_got(engine), ", ".join(engines())))
                break
    sc = None
    try:
        sc = _make(c, spans, positions, dx_um, idle, engine, reuse)
    except MemoryError:
        pass
    if sc is None:
        # whatever was allocated is unreachable now: give it back (memory_words collects)
        from ..compat import memory_words
        block = _biggest_block(c, spans, engine)
        raise ValueError("scene: out of memory while building (needs %d bytes: %d of sample "
                         "buffers and plans + %d of region table; %s%s)"
                         % (need, nbuf, ntab, memory_words() or "the heap is full",
                            ", and a region needs one block of %d" % block if block else ""))
    return sc


def _shared(reuse, tex, n):
    """The buffer of reuse's region playing tex over n positions (a reference
    or a brush: what they paint depends on the texture and the length
    alone), or None."""
    if reuse is None or tex["kind"] not in ("reference", "brush"):
        return None
    src = reuse.source["regions"]
    t = reuse._t
    for k in range(reuse.count):
        j = STRIDE * k
        if t[j + 1] - t[j] == n and t[j + 2] in (K_BUF, K_CHUNK) and src[k]["texture"] == tex:
            return t[j + 2], reuse._bufs[t[j + 3]]
    return None


def _make(c, spans, positions, dx_um, idle, engine, reuse=None):
    regions = c["regions"]
    count = len(regions)
    table = array("i", [0] * (STRIDE * (count + 1)))
    table[STRIDE * count] = SENTINEL
    table[STRIDE * count + 1] = SENTINEL
    # 1. every buffer first, while the heap is least fragmented (rendering
    # leaves garbage behind: plans, boxed floats)
    bufs = []
    plans = []
    painted = []                            # (region, Chunks) of brush regions
    shared = []                             # regions playing the playing scene's buffer
    for k in range(count):
        s, e = spans[k]
        j = STRIDE * k
        table[j] = s
        table[j + 1] = e
        tex = regions[k]["texture"]
        old = _shared(reuse, tex, e - s)
        rom = None
        if old is None and tex["kind"] == "reference":
            rom = _flash_ref(tex["name"], e - s)
        if tex["kind"] == "constant":
            table[j + 2] = K_CONST
            table[j + 3] = int(tex["level"] * 65535.0 + 0.5)
        elif _on_plan(tex, e - s, engine):
            table[j + 2] = K_PLAN
            table[j + 3] = len(plans)
            plans.append(_plan_of(tex, e - s))
        elif old is not None:               # the playing scene's, as it is
            table[j + 2] = old[0]
            table[j + 3] = len(bufs)
            bufs.append(old[1])
            shared.append(k)
        elif tex["kind"] == "brush":
            # painted into 1 KB chunks (upload.Chunks), played as an upload is:
            # no block over 1 KB, so a heap the brush's numbers fragmented
            # still takes a full screen; the painter's tables first, while
            # the heap has blocks their size (gen/brush.py prepare)
            from .upload import Chunks
            from ..gen.brush import prepare
            prepare()
            table[j + 2] = K_CHUNK
            table[j + 3] = len(bufs)
            painted.append((k, Chunks(e - s)))
            bufs.append(painted[-1][1].chunks)
        elif rom is not None:
            # the firmware's map in flash, played in place: no heap, no render
            table[j + 2] = K_BUF
            table[j + 3] = len(bufs)
            bufs.append(rom)
            shared.append(k)
        else:
            table[j + 2] = K_BUF
            table[j + 3] = len(bufs)
            if _plays_as_is(tex, e - s):
                table[j + 2] = K_CHUNK
                bufs.append(tex["u16"].chunks)  # the upload itself, exactly region-long
            else:
                bufs.append(u16_one_block(e - s))    # exactly region-long
    # 2. render into them
    for k, ch in painted:                   # the board got ~200 numbers, paints here
        from ..gen.brush import paint
        tex = regions[k]["texture"]
        paint(tex["brush"], tex["seed"], len(ch), ch)
    for k in range(count):
        j = STRIDE * k
        if table[j + 2] != K_BUF or k in shared:   # constants, plans, uploads and the
            continue                                # playing scene's buffers as they are
        n = table[j + 1] - table[j]
        buf = bufs[table[j + 3]]
        tex = regions[k]["texture"]
        kind = tex["kind"]
        if kind == "texel":
            _render_texel(tex, n, engine, buf)
        elif kind == "reference":
            from .. import reference_u16
            reference_u16(tex["name"], n, buf)
        else:
            _fill_samples(tex["u16"], tex["fit"], n, buf)
    return Scene(table, tuple(bufs), idle, c, spans, positions, dx_um, tuple(plans))


_flash_u16 = None           # gen.reference.flash_u16, imported at the first reference region


def _flash_ref(name, n):
    """The reference's map in flash (texelpad firmware), or None."""
    global _flash_u16
    if _flash_u16 is None:
        from ..gen.reference import flash_u16
        _flash_u16 = flash_u16
    return _flash_u16(name, n)


def _plays_as_is(tex, n):
    """An uploaded samples map (upload.Chunks) that tiles a region of exactly
    its length is played from its own chunks: no second copy (38,400 bytes
    for a full TPaD screen), and no block larger than 1 KB. Nothing ever
    writes to it after the upload."""
    return (tex["kind"] == "samples" and tex["fit"] == "tile"
            and getattr(tex["u16"], "CHUNKS", False) and len(tex["u16"]) == n)


_plan_int = None            # gen.plan_int.PlanInt, imported at the first format-2 region
_gain_q14 = None            # gen.engine_int.gain_q14, imported at the first plan


def _plan_of(tex, n):
    """(t28, d28, L, gain_q14) of a texel region n samples long: what
    engine_int needs to make any one sample (the float parts of the plan are
    dropped). Format 2 (gen/plan_int.py) from the region's already validated
    keys, without its log pitches and without a second validation; its class
    is looked up once (an import statement runs the import machinery on every
    call: with the parameter copy, 2 of a Pico's 11.5 ms here)."""
    global _plan_int, _gain_q14
    if _gain_q14 is None:
        from ..gen.engine_int import gain_q14
        _gain_q14 = gain_q14
    p = dict(tex)
    del p["kind"]
    p["length_samples"] = n
    if p["v"] == 2:
        if _plan_int is None:
            from ..gen.plan_int import PlanInt
            _plan_int = PlanInt
        pl = _plan_int(p, keep_y=False)
    else:
        from .. import make_plan
        pl = make_plan(p)
    return (pl.t28, pl.d28, pl.L, _gain_q14(pl.gain))


def _render_texel(tex, n, engine, buf):
    from .. import render_u16
    p = {}
    for k in _TEXEL_ANY:
        if k in tex:
            p[k] = tex[k]
    p["length_samples"] = n
    # A scene plays what a board plays: the integer engine unless the caller
    # asks for another (so a scene is the same texture on every runtime).
    if engine is None:
        engine = "int"
    if engine == "numpy":
        # engine_numpy.render_u16 cannot write an ndarray into an array('H')
        # slice (CPython only; memory is no concern there): render, then copy.
        q = render_u16(p, engine="numpy")
        buf[:] = array("H", q.tobytes())
    else:
        render_u16(p, engine=engine, out=buf)


_fast_fill = None           # scene_viper.fill, or False where it does not load


def _fill_samples(vals, fit, n, buf):
    global _fast_fill
    if _fast_fill is None:
        from ..compat import native
        _fast_fill = native("texel.runtime.scene_viper", "fill") or False
    if _fast_fill and _fast_fill(vals, fit, n, buf):
        return
    m = len(vals)
    if fit == "tile" or m == 1 or n == 1:
        # tile: position i plays vals[i mod m] (stretch of one value or onto one
        # position: the first value)
        k = 0
        for i in range(n):
            buf[i] = vals[k]
            k += 1
            if k == m:
                k = 0
        return
    # stretch: position i sits at x = i*(m-1)/(n-1) in value units, k its
    # integer part, r/(n-1) its fraction; linear interpolation with the
    # fraction rounded to a 14-bit weight w = round(r*2^14/(n-1)), so every
    # intermediate stays a small int on boards (|b-a|*w <= 65535*2^14 < 2^30).
    # floor(r*2^15/(n-1)) is one division while r*2^15 < 2^30 (regions up to
    # 32,768 positions); a longer region (a display may have up to 2^20
    # positions) takes it in two exact steps, 2^9 then 2^6, each below 2^30
    # because r < n-1 < 2^20: r << 15 there was a heap bigint per position on
    # 32-bit ports (694 KB of garbage for a 40,000-position stretch on the
    # CircuitPython build, an OverflowError where a port has no long ints)
    # for the very same weights. Error <= 2.5 LSB (weight rounding 65535/2^15
    # + result rounding 0.5).
    den = n - 1
    step = m - 1
    small = den <= 32768
    k = 0                         # i*(m-1) = k*(n-1) + r
    r = 0
    for i in range(n):
        a = vals[k]
        if r == 0:
            buf[i] = a
        else:
            if small:
                w = ((r << 15) // den + 1) >> 1
            else:
                x = r << 9
                q = x // den
                w = (((q << 6) + (((x - q * den) << 6) // den)) + 1) >> 1
            buf[i] = a + (((vals[k + 1] - a) * w + 8192) >> 14)
        r += step
        if r >= den:
            k += r // den
            r = r % den


class Scene:
    """A built scene. amp(pos) is the only thing the refresh calls."""

    def __init__(self, table, bufs, idle, source, spans, positions, dx_um, plans=()):
        from ..gen import sine_table
        self._t = table                 # array('i'): (start, end, kind, value) per region + sentinel
        self._bufs = bufs               # tuple of array('H'), fixed
        self._plans = plans             # tuple of (t28, d28, L, gain_q14), fixed
        self._sine = sine_table.table()
        self.count = len(table) // STRIDE - 1      # regions (without the sentinel)
        self.idle = idle                # uint16 amplitude in gaps / out of range
        self.source = source            # the canonical dict
        self.positions = positions
        self.dx_um = dx_um
        self.table_bytes = len(table) * _ITEM
        self.buffer_bytes = 0
        for b in bufs:
            if isinstance(b, tuple):    # K_CHUNK
                for c in b:
                    self.buffer_bytes += 2 * len(c)
            elif isinstance(b, array):  # not a map in flash (rom.rom_u16): no RAM
                self.buffer_bytes += 2 * len(b)
        for pl in plans:
            self.buffer_bytes += 4 * len(pl[0]) + 4 * len(pl[1])
        self.nbytes = self.buffer_bytes + self.table_bytes

    def amp(self, pos):
        # Hard-IRQ path: small ints only, no allocation. Regions are sorted
        # and disjoint, so their ends are sorted too: the first region ending
        # after pos either holds pos or lies beyond a gap. The sentinel row
        # (end SENTINEL = 2^30 - 1) stops the scan without a bound check;
        # pos must be below it (every board small int but the largest is).
        t = self._t
        i = 1                           # index of the end field of row 0
        while pos >= t[i]:
            i += 4
        s = t[i - 1]
        if pos < s:                     # a gap, before the first region, or past the last
            return self.idle
        kind = t[i + 1]
        if kind == K_BUF:
            return self._bufs[t[i + 2]][pos - s]
        if kind == K_CONST:
            return t[i + 2]
        if kind == K_CHUNK:
            o = pos - s
            return self._bufs[t[i + 2]][o >> CHUNK_BITS][o & CHUNK_MASK]
        # K_PLAN: engine_int's sample k (1-based) of texel j, computed directly:
        # phase (t28[j] + k*d28[j]) mod 2^28 with k*d in two 14-bit limbs
        # (k <= PLAN_MAX_L < 2^16: each product < 2^30, a small int), then
        # the sine table and the Q14 gain exactly as engine_int._fill_py.
        pl = self._plans[t[i + 2]]
        o = pos - s
        L = pl[2]
        j = o // L
        k = o - j * L + 1
        d = pl[1][j]
        ph = (pl[0][j] + (((k * (d >> 14)) & 0x3FFF) << 14)
              + ((k * (d & 0x3FFF)) & 0x0FFFFFFF)) & 0x0FFFFFFF
        tab = self._sine
        ii = ph >> 18
        y0 = tab[ii]
        v = y0 + (((tab[ii + 1] - y0) * ((ph >> 2) & 0xFFFF) + 32768) >> 16)
        return (v * pl[3] + 8192) >> 14

    def buffers(self):
        """The sample buffers, in region order (constants have none)."""
        return self._bufs

    def plans(self):
        """The plan-backed texel regions' (t28, d28, L, gain_q14), in order."""
        return self._plans

    def spans(self):
        """[(start, end, kind, value)] per region, positions end-exclusive."""
        t = self._t
        return [(t[j], t[j + 1], t[j + 2], t[j + 3]) for j in range(0, STRIDE * self.count, STRIDE)]

    def describe(self):
        """A small dict of literals for status()."""
        regs = []
        src = self.source["regions"]
        t = self._t
        for k in range(self.count):
            j = STRIDE * k
            s, e = t[j], t[j + 1]
            tex = src[k]["texture"]
            how = t[j + 2]
            # a map in flash (the firmware's references, rom.rom_u16: not an array) takes
            # no RAM: its bytes are 0, as in nbytes, and its mode says where it plays from
            flash = how == K_BUF and not isinstance(self._bufs[t[j + 3]], array)
            d = {"kind": tex["kind"], "start": s, "end": e,
                 "start_mm": _mm(s, self.dx_um), "end_mm": _mm(e, self.dx_um),
                 "bytes": (0 if flash else 2 * (e - s) if how in (K_BUF, K_CHUNK) else
                           8 * len(self._plans[t[j + 3]][0]) if how == K_PLAN else 0),
                 "mode": "flash" if flash else ("constant", "map", "plan", "map")[how]}
            kind = tex["kind"]
            if kind == "reference":
                d["name"] = tex["name"]
            elif kind == "texel":
                d["pitch_db"] = tex["pitch_db"]
                d["irregularity_db"] = tex["irregularity_db"]
                d["seed"] = tex["seed"]
                d["v"] = tex["v"]
            elif kind == "constant":
                d["amplitude"] = t[j + 3]
            elif kind == "brush":
                d["seed"] = tex["seed"]
            else:
                d["values"] = len(tex["u16"])
                d["fit"] = tex["fit"]
            regs.append(d)
        out = {"regions": regs, "count": self.count, "idle": self.idle,
                "positions": self.positions, "bytes": self.nbytes,
                "buffer_bytes": self.buffer_bytes, "table_bytes": self.table_bytes}
        if "name" in self.source:
            out["name"] = self.source["name"]
        return out
