# Region kinds: what a scene's region can play, one module per kind
# (docs/architecture.md, "A new region kind"). runtime/scene.py keeps the
# region table, the build and the swap; everything a kind decides is here.
#
# A kind's module (kinds/constant.py is the smallest; kinds/bump.py the
# newest) holds:
#   NAME                          its "kind" word (= the module's name)
#   KEYS, OPTIONS                 the texture keys it allows ("kind" first)
#   SHARED                        True when what it plays depends on the texture
#                                 and the region's length alone: a rebuilt scene
#                                 reuses the playing scene's buffer (scene._shared)
#   check(path, tex, n)           -> the canonical texture; ValueError "<path>...: ..."
#                                 (n: the region's positions)
#   need(tex, n, engine)          -> bytes the region holds (buffers, plans)
#   block(tex, n, engine)         -> bytes of its largest single block (0: none)
#   store(tex, n, engine)         -> (how, value, target): how it plays (the codes
#                                 below), the table value or the buffer, and what
#                                 fill() writes into after every region has its
#                                 memory (None: nothing to write)
#   fill(tex, n, target, engine, dx_um)
#   describe(tex)                 -> its fields of status()'s region dict (literals)
#   words(d), label(d)            a region of status() (or describe(tex) with "kind")
#                                 in a line, and in a few words (host labels)
#   FIELDS (optional)             the editor's form: (key, "number"|"int"|"word",
#                                 lo or words, hi, default, label) per key
#
# Imported here, not in the functions that use them: an import statement runs at every
# call, and one took 70-120 us on the emulated Pico's firmware, 0.4-1 ms on a stock Pico
# (new_chunks and _block: 2-7 of them a reference push, 3-9 ms there)
import gc
from ...compat import u16_one_block, skip_holes

# The registry is this tuple: a board's frozen package cannot be listed, so
# the names are written out; tests/runtime/test_kinds.py checks that it and the
# modules in this folder agree. Order: messages list the kinds in it.
NAMES = ("texel", "reference", "constant", "samples", "brush", "bump")

# How a region plays: the "kind" column of the region table (scene.py) - not
# the texture's kind but where amp() finds its value. refresh_viper.py uses the
# numbers as literals and checks them against these at import.
K_CONST = 0             # the row's value is the amplitude
K_BUF = 1               # the value indexes the buffers: an array('H') (or a map in flash)
K_PLAN = 2              # a texel region played from its integer plan, sample by sample
K_CHUNK = 3             # the value indexes the buffers: a tuple of array('H') chunks
# A few samples the refresh plays where they are (kinds/samples.py, SMALL values at
# most): no map at all, so no 38 KB of chunks to allocate and fill for a full-screen
# gradient. The value indexes the plans (as K_PLAN): the plan is a 5-tuple
# (vals, x1, x2, x3, x4) whose numbers samples.py's store() explains.
K_TILE = 4              # value k mod m at region position k
K_STRETCH = 5           # the m values spread linearly over the region
CHUNK_BITS = 9          # 512 values (1 KB) per chunk (upload.py and refresh_viper.py use these)
CHUNK_MASK = 511


# Chunks per block where the heap has room, each chunk a memoryview of its
# block: a full screen is 5 allocations instead of 38. Every allocation above one
# 16-byte block scans MicroPython's allocation table from its lowest free block
# past the heap's small holes: ~0.34 ms a chunk on the emulated RP2040 playing a
# scene, 12.9 of the shipped gradient's 25.6 ms build (docs/firmware.md); on a
# stock Pico 38 chunks took 34.8 ms, 5 blocks 8.2. A block is tried only where
# the heap has one without a collection (_block): a stock heap often has none,
# and a failed try collected first (~24 ms there). An upload's chunks are 1 KB.
SLAB = 8


def new_chunks(n, slab=None):
    """n uint16 values as a tuple of chunks of 2^CHUNK_BITS values each (the
    last shorter): array('H') each, or memoryviews of SLAB-chunk blocks (slab
    1: no block above 1 KB - upload.Chunks holds one; samples and RAM references
    play from them). A block the heap has no room for (one MemoryError without
    a collection: _block) turns the rest of the map into 1 KB chunks.

    Before each block the allocator's search starts above the chunks made
    so far (compat.skip_holes: the Pico firmware's; a no-op elsewhere): else each
    chunk's search walked the ones before it, from the hint or from the first
    free block - 38 chunks took 14.1 ms (9.3 with one hint first) on the
    emulated Pico's firmware, 2.7 ms so."""
    size = 1 << CHUNK_BITS
    per = SLAB if slab is None else slab
    out = []
    o = 0
    try:
        while o < n:
            k = min(n - o, per * size)
            skip_holes()
            if k > size:
                mv = _block(k)
                if mv is None:
                    per = 1
                    continue
                for a in range(0, k, size):
                    out.append(mv[a:a + size])
            else:
                out.append(u16_one_block(k))
            o += k
    except MemoryError:
        # a stale stack slot naming this list (MicroPython's collector scans the C
        # stack conservatively) must not keep the chunks made so far alive while the
        # caller makes room for them (texel.app._make_room)
        out.clear()
        mv = None
        raise
    return tuple(out)


def _block(k):
    """A memoryview of a new block of k uint16 values, or None where the heap
    has no such block without a collection: the allocator's own collection is
    held off for the try (a failed one then costs nothing, and the caller's
    1 KB chunks follow, collecting as they need)."""
    on = gc.isenabled() if hasattr(gc, "isenabled") else True
    try:
        if on:
            gc.disable()
        return memoryview(u16_one_block(k))
    except MemoryError:
        return None
    finally:
        if on:
            gc.enable()

_mods = {}


def get(name):
    """The module of kind `name` (one of NAMES), imported at its first use:
    a board holds the code of the kinds its scenes play, not of all."""
    m = _mods.get(name)
    if m is None:
        if name not in NAMES:
            raise ValueError("kind: unknown kind %r (one of: %s)" % (name, ", ".join(NAMES)))
        m = __import__(__name__ + "." + name, None, None, ("NAME",), 0)
        _mods[name] = m
    return m


def words(d):
    """A region of status() (or {"kind": ..., **describe(tex)}) in a line; a
    kind this code does not know (a board's newer image) by its name."""
    return get(d["kind"]).words(d) if d.get("kind") in NAMES else str(d.get("kind"))


def label(d):
    """The same in a few words (strips, figures, lists)."""
    return get(d["kind"]).label(d) if d.get("kind") in NAMES else str(d.get("kind"))


def label_of(tex):
    """A canonical texture in a few words."""
    m = get(tex["kind"])
    d = m.describe(tex)
    d["kind"] = tex["kind"]
    return m.label(d)
