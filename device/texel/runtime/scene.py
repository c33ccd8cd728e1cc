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
# Texture kinds: one module each in runtime/kinds/ (its keys, checks,
# memory, rendering and words; kinds/__init__.py lists what a module holds):
#   texel      the Single-Pitch Texel generator's texture (kinds/texel.py)
#   reference  one of the lab's nine reference textures by "name"
#   constant   "level": friction reduction 0..1 (no buffer: one table entry)
#   samples    a map the host made ("values" 0..1 or "u16"; "fit" tile/stretch)
#   brush      a Tactile Paintbrush stroke, painted on the board
#   bump       a virtual bump or edge felt through friction (lateral-force illusion)
# Every other kind and every key a kind does not name is refused.
#
# Canonical form (what validate returns; validate(canonical) == canonical):
# the same dict with regions sorted by start, each texture in its kind's
# canonical form (numbers as floats/ints, defaults filled in: kinds/*.py);
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
from . import kinds
from .kinds import K_CONST, K_BUF, K_PLAN, K_CHUNK, K_TILE, K_STRETCH, CHUNK_BITS, CHUNK_MASK
from ..gen.params import LENGTH_MAX
from ..compat import IMPL as _IMPL
from ..gen import sine_table as _sine_table
# the checks every device validator shares (their words: gen/check.py)
from ..gen.check import BIG, fail, got as _got, qstr as _qstr, check_keys as _check_keys, \
    need_dict as _dict, num as _num, int_in as _int

MAX_REGIONS = 16            # regions per scene (amp() cost grows with the count)
U16_MAX = 65535
KINDS = kinds.NAMES         # one module each: runtime/kinds/
SCENE_KEYS = ("regions", "idle_amplitude", "name", "notes")
# A scene's own words: "name" (shown by status, listed by `texelpad scenes`)
# and "notes" (what it is for, where it comes from). Bounded so a scene file
# stays a scene and status() stays small; any text, checked as a str only.
NAME_MAX = 64
NOTES_MAX = 2000
REGION_KEYS = ("start_mm", "end_mm", "texture")

# Region table: STRIDE ints per region, (start, end, how, value), sorted by
# start, then one sentinel row (SENTINEL, SENTINEL, K_CONST, 0) that ends the
# scan. how (kinds/__init__.py): K_CONST, value is the amplitude; K_BUF and
# K_CHUNK, value indexes the buffers; K_PLAN, K_TILE and K_STRETCH, value indexes
# the plans.
STRIDE = 4
# > any position, and still a small int on a 32-bit board (2^30 - 1): a
# larger value would come out of the array as a heap bigint inside the IRQ.
SENTINEL = 0x3FFFFFFF
_ITEM = len(bytes(array("i", [0])))     # bytes per table int (4)

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
    lim = _lim(total_mm, dx_um)
    if isinstance(v, int) and (v < 0 or v > lim):
        return _num(path, v, 0.0, total_mm)          # refused without float overflow
    if v == v and 0.0 <= v <= lim and to_position(v, dx_um) <= positions:
        return float(v)
    return _num(path, v, 0.0, total_mm)


def _lim(total_mm, dx_um):
    """The pre-check's bound on a boundary in mm (_mm_in; region_check gets it too)."""
    return total_mm + 1.0 + dx_um / 500.0


if _IMPL == "cpython":
    def _mm(pos, dx_um):
        return round(pos * dx_um / 1000.0, 4)
else:
    def _mm(pos, dx_um):
        # MicroPython's round(x, 4) is nearbyint(x * pow(10, 4)) / pow(10, 4)
        # (py/modbuiltins.c): these are its float operations without the pow, so
        # the same float - 26 us a call on the emulated Pico, not 143 (describe()
        # makes two a region; equal at every 7th position of a 19,200-position
        # display in the firmware's float32, tests/runtime/test_scene.py on the unix port)
        return round(pos * dx_um / 1000.0 * 10000.0) / 10000.0


# --- textures ------------------------------------------------------------------
def _texture(path, tex, n):
    if not isinstance(tex, dict):       # (the message built only when needed: 0.5 ms on a Pico)
        _dict(path, tex, "a texture dict with 'kind' (one of: %s)" % ", ".join(KINDS))
    if "kind" not in tex:
        fail(path, "missing required key 'kind' (one of: %s)" % ", ".join(KINDS))
    kind = tex["kind"]
    if not isinstance(kind, str) or kind not in KINDS:
        fail(path + ".kind", "unknown kind %s (one of: %s)"
             % (_qstr(kind) if isinstance(kind, str) else _got(kind), ", ".join(KINDS)))
    return kinds.get(kind).check(path, tex, n)     # its keys, values, canonical form


# --- regions ---------------------------------------------------------------------
# The C core's fast paths (texelcore_api.h region_check, texel_check): a
# region and a texel texture as they come, checked at C speed; None for
# anything else, which _region and the kinds' checks decide and word. About
# 1.2 + 2.4 ms a texel region on a Pico (bench/firmware.py);
# tests/gen/test_texel_core.py and tests/support/texel_check.py hold them to
# the same canonical scenes.
_fast = None


def _fast_region():
    global _fast
    if _fast is None:
        from ..compat import core
        c = core()
        _fast = (c and getattr(c, "region_check", None)) or False
    return _fast


def fast_texel(tex):
    return kinds.get("texel").fast_check(tex)


def _region(i, r, total_mm, positions, dx_um):
    """Region i checked: (start_mm, end_mm, start, end, canonical texture)."""
    path = "regions[%d]" % i
    r = _dict(path, r, "a region dict with 'start_mm', 'end_mm', 'texture'")
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
    return s_mm, e_mm, s, e, _texture(path + ".texture", r["texture"], e - s)


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
    fast = _fast_region()
    lim = _lim(total_mm, dx_um)
    # the C core's loop over every region (texture checks of texel regions too): one
    # call instead of ~6 a region (kinds/texel.py fast_regions)
    done = kinds.get("texel").fast_regions(regs, lim, positions, dx_um) if fast else None
    if type(done) is tuple:             # (regions, spans): every region whole, sorted, apart
        out["regions"] = done[0]
        return out, done[1], positions, dx_um
    for i in range(len(regs)):
        r = regs[i]
        f = done[i] if done is not None else fast(r, lim, positions, dx_um) if fast else None
        if f is not None and len(f) == 3:   # (region, start, end): checked whole
            canon.append(f[0])
            spans.append((f[1], f[2], i))
            continue
        if f is None:
            s_mm, e_mm, s, e, tex = _region(i, r, total_mm, positions, dx_um)
        else:
            s_mm, e_mm, s, e, tx = f
            tex = fast_texel(tx) if type(tx) is dict and tx.get("kind") == "texel" else None
            if tex is None:
                tex = _texture("regions[%d].texture" % i, tx, e - s)
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


def _need(c, spans, engine=None):
    regions = c["regions"]
    bufs = 0
    for k in range(len(regions)):
        tex = regions[k]["texture"]
        bufs += kinds.get(tex["kind"]).need(tex, spans[k][1] - spans[k][0], engine)
    table = STRIDE * (len(regions) + 1) * _ITEM       # + the sentinel row
    return bufs + table, bufs, table


def _biggest_block(c, spans, engine=None):
    """Bytes of the largest single block the scene's regions take (a region
    rendered by an engine, or samples given inline: exactly region-long);
    0 when every region plays from a plan, chunks or flash."""
    big = 0
    for k in range(len(c["regions"])):
        tex = c["regions"][k]["texture"]
        big = max(big, kinds.get(tex["kind"]).block(tex, spans[k][1] - spans[k][0], engine))
    return big


class OutOfMemory(ValueError):
    """build() found no room for a scene's buffers (a ValueError: callers that
    only refuse need nothing more; texel.app makes room on this one)."""


def build(canonical, display, engine=None, idle_default=0, max_bytes=None, checked=None,
          reuse=None, words=True, focus=None):
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
    half of a split screen re-renders only the right half. words False: an
    OutOfMemory says no more (the caller tries again in more room); else it
    says the heap's free bytes and largest block, measured by allocating.
    focus: a function giving the display position under the finger (-1:
    lifted), or None: a region under it that can paint in parts (its kind's
    fill_near: a brush on a board with the C painter) paints around it first
    and the Scene's `painting` holds the rest, which the caller finishes once
    the scene plays, following the finger (texel.app._paint_rest).
    Touches no global state: the caller's current scene is unaffected."""
    if checked is not None and checked[0] is canonical:
        c, spans, positions, dx_um = checked
    else:
        c, spans, positions, dx_um = _check(canonical, display)
    if "idle_amplitude" in c:
        idle = c["idle_amplitude"]
    else:
        idle = _int("idle_default", idle_default, 0, U16_MAX)
    # (what the regions need is worked out only where it is used: a budget, a
    # refusal - 0.8 ms of a six-region push on the emulated Pico otherwise)
    if max_bytes is not None:
        need, nbuf, ntab = _need(c, spans, engine)
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
        sc = _make(c, spans, positions, dx_um, idle, engine, reuse, focus)
    except MemoryError:
        pass
    if sc is None:
        if not words:
            # the caller builds again in more room (texel.app._make_room): the heap's
            # words are not worth their trial allocations, each failing one a
            # collection (~25 ms on a stock Pico; ~0.45 s of such a push there)
            raise OutOfMemory("scene: out of memory while building")
        # whatever was allocated is unreachable now: give it back (memory_words collects)
        from ..compat import memory_words
        need, nbuf, ntab = _need(c, spans, engine)
        block = _biggest_block(c, spans, engine)
        raise OutOfMemory("scene: out of memory while building (needs %d bytes: %d of sample "
                         "buffers and plans + %d of region table; %s%s)%s"
                         % (need, nbuf, ntab, memory_words(block, nbuf) or "the heap is full",
                            ", and a region needs one block of %d" % block if block else "",
                            "" if reuse is None or reuse.nbytes < 1024 else
                            "; the scene playing (%d bytes) plays on: to make room, push a "
                            "small scene first (texelpad push --constant 0)" % reuse.nbytes))
    return sc


def _shared(reuse, tex, n):
    """(how, buffer) of reuse's region playing tex over n positions (a kind
    whose map depends on the texture and the length alone: its SHARED), or
    None."""
    if reuse is None or not kinds.get(tex["kind"]).SHARED:
        return None
    src = reuse.source["regions"]
    t = reuse._t
    for k in range(reuse.count):
        j = STRIDE * k
        if t[j + 1] - t[j] == n and t[j + 2] in (K_BUF, K_CHUNK) and src[k]["texture"] == tex:
            return t[j + 2], reuse._bufs[t[j + 3]]
    return None


def _make(c, spans, positions, dx_um, idle, engine, reuse=None, focus=None):
    regions = c["regions"]
    count = len(regions)
    table = array("i", [0] * (STRIDE * (count + 1)))
    table[STRIDE * count] = SENTINEL
    table[STRIDE * count + 1] = SENTINEL
    # 1. every region's memory first, while the heap is least fragmented
    # (rendering leaves garbage behind: plans, boxed floats)
    bufs = []
    plans = []
    todo = []                               # (region, kind module, what its fill() writes)
    for k in range(count):
        s, e = spans[k]
        j = STRIDE * k
        table[j] = s
        table[j + 1] = e
        tex = regions[k]["texture"]
        m = kinds.get(tex["kind"])
        old = _shared(reuse, tex, e - s) if reuse is not None and m.SHARED else None
        if old is not None:                 # the playing scene's, as it is
            how, value, target = old[0], old[1], None
        else:
            how, value, target = m.store(tex, e - s, engine)
        table[j + 2] = how
        if how == K_CONST:
            table[j + 3] = value
        elif how in _PLANNED:
            table[j + 3] = len(plans)
            plans.append(value)
        else:
            table[j + 3] = len(bufs)
            bufs.append(value)
        if target is not None:
            todo.append((k, m, target))
    # 2. write into them: what paints into chunks first (a brush: the board got
    # ~200 numbers, paints here, with the tables store() prepared), then the rest;
    # a region under the finger that can paint in parts, around it (the rest later)
    painting = None
    at = None                               # the finger, read once a region could use it
    for first in (True, False):
        for k, m, target in todo:
            if (table[STRIDE * k + 2] == K_CHUNK) == first:
                s, e = spans[k]
                tex = regions[k]["texture"]
                # (a kind paints in parts into chunks only: no hasattr on the others)
                near = first and focus is not None and hasattr(m, "fill_near")
                if near and at is None:
                    at = focus()
                if near and s <= at < e:
                    p = m.fill_near(tex, e - s, target, focus, s)
                    if p is not None:
                        painting = (painting or []) + [p]
                else:
                    m.fill(tex, e - s, target, engine, dx_um)
    sc = Scene(table, tuple(bufs), idle, c, spans, positions, dx_um, tuple(plans))
    if painting:
        sc.painting = painting
    return sc


# status()'s word for how a region plays, by its table kind
MODES = ("constant", "map", "plan", "map", "tile", "stretch")
_PLANNED = (K_PLAN, K_TILE, K_STRETCH)      # rows whose value indexes the plans


class Scene:
    """A built scene. amp(pos) is the only thing the refresh calls."""

    # what is left to paint (build's focus): a list of gen/brush_parts.py Painting on the
    # scene that has any (a class attribute: as one more instance attribute it cost
    # every build 63 us, median over bench/firmware.py's pushes on the emulated Pico)
    painting = ()

    def __init__(self, table, bufs, idle, source, spans, positions, dx_um, plans=()):
        self._t = table                 # array('i'): (start, end, kind, value) per region + sentinel
        self._bufs = bufs               # tuple of array('H'), fixed
        self._plans = plans             # tuple of (t28, d28, L, gain_q14), fixed
        self._sine = _sine_table.table()
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
        for pl in plans:                # a texel plan's two int32 tables, a few samples' values
            self.buffer_bytes += len(pl[0]) * (2 if len(pl) == 5 else 8)
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
        if kind == K_TILE:                  # (vals, m, ...): kinds/samples.py plan()
            pl = self._plans[t[i + 2]]
            return pl[0][(pos - s) % pl[1]]
        if kind == K_STRETCH:               # (vals, A, B, n - 1, ...): the same
            pl = self._plans[t[i + 2]]
            o = pos - s
            q = o * pl[1] + (o * pl[2]) // pl[3]
            v = pl[0]
            k = q >> 15
            a = v[k]
            return a + (((v[k + 1] - a) * (((q & 0x7FFF) + 1) >> 1) + 8192) >> 14)
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
        """What K_PLAN, K_TILE and K_STRETCH rows play, in order: a texel
        region's (t28, d28, L, gain_q14), a few samples' 5-tuple
        (kinds/samples.py plan())."""
        return self._plans

    def spans(self):
        """[(start, end, kind, value)] per region, positions end-exclusive."""
        t = self._t
        return [(t[j], t[j + 1], t[j + 2], t[j + 3]) for j in range(0, STRIDE * self.count, STRIDE)]

    def describe(self):
        """A small dict of literals for status()."""
        src = self.source["regions"]
        fn = _describe_c()                  # the C core's loop (texelcore_api.h describe_regions)
        regs = fn(self._t, src, self.dx_um, self._bufs, self._plans, _WORDS, _own) if fn else None
        if regs is None:
            regs = self._describe()
        out = {"regions": regs, "count": self.count, "idle": self.idle,
                "positions": self.positions, "bytes": self.nbytes,
                "buffer_bytes": self.buffer_bytes, "table_bytes": self.table_bytes}
        if "name" in self.source:
            out["name"] = self.source["name"]
        return out

    def _describe(self):
        regs = []
        src = self.source["regions"]
        t = self._t
        dx = self.dx_um
        get = kinds.get
        for k in range(self.count):
            j = STRIDE * k
            s = t[j]
            e = t[j + 1]
            how = t[j + 2]
            tex = src[k]["texture"]
            kind = tex["kind"]
            mode = MODES[how]
            # a map in flash (the firmware's references, rom.rom_u16: not an array) takes
            # no RAM: its bytes are 0, as in nbytes, and its mode says where it plays from
            if how == K_BUF and not isinstance(self._bufs[t[j + 3]], array):
                n = 0
                mode = "flash"
            elif how == K_BUF or how == K_CHUNK:
                n = 2 * (e - s)
            elif how == K_CONST:
                n = 0
            else:                           # a plan: as in nbytes
                pl = self._plans[t[j + 3]]
                n = len(pl[0]) * (2 if len(pl) == 5 else 8)
            d = {"kind": kind, "start": s, "end": e, "start_mm": _mm(s, dx),
                 "end_mm": _mm(e, dx), "bytes": n, "mode": mode}
            d.update(get(kind).describe(tex))  # its own fields
            regs.append(d)
        return regs


_WORDS = MODES + ("flash",)             # describe_regions' words
_DESCRIBE = None                        # the core's describe_regions; False: none


def _describe_c():
    global _DESCRIBE
    if _DESCRIBE is None:
        from ..compat import core
        _DESCRIBE = getattr(core(), "describe_regions", None) or False
    return _DESCRIBE


def _own(kind, tex):
    # a kind's own fields of its region in status() (describe_regions calls it for
    # every kind but texel, whose fields it copies itself)
    return kinds.get(kind).describe(tex)
