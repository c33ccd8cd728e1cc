# Region kind "samples": a map the host made (an upload). Exactly one of
# "values" (numbers 0..1) or "u16" (ints 0..65535; or an Upload (runtime/
# upload.py) the host filled through texel.wire.upload_* - large data crosses
# the link as data, not as a literal the board compiles), 1..MAX_SAMPLES of
# them, and "fit":
#   "tile" (default): value k plays at region position k mod m - one value
#       per display position (5.3 um), so the spatial frequencies the host
#       designed are the ones felt;
#   "stretch": the m values are spread over the whole region by linear
#       interpolation, first value at the region's first position, last value
#       at its last (no filtering when m > region length: shrinking picks
#       interpolated points).
# Canonical: {"kind": "samples", "u16": tuple of ints (or the upload's Chunks,
# as they are), "fit": ...}; "values" become round(v * 65535), half up; a
# tuple is kept as it is, a list is copied once.
from ...compat import u16_one_block, array, core
from ...gen.check import fail, got, num, int_in, check_keys
from . import K_CONST, K_CHUNK, K_TILE, K_STRETCH, CHUNK_BITS, CHUNK_MASK, new_chunks

NAME = "samples"
KEYS = ("kind", "values", "u16", "fit")
OPTIONS = ()
SHARED = False              # the playing scene's upload is kept by plays_as_is instead
MAX_SAMPLES = 19200         # values per samples region (one full TPaD screen)
U16_MAX = 65535
FITS = ("tile", "stretch")


def check(path, tex, n):
    check_keys(path, tex, KEYS)
    has_v = "values" in tex
    has_u = "u16" in tex
    if has_v == has_u:
        fail(path, "give exactly one of 'values' (numbers 0..1) or 'u16' "
             "(ints 0..65535), %d at most" % MAX_SAMPLES)
    fit = tex.get("fit", "tile")
    if not isinstance(fit, str) or fit not in FITS:
        fail(path + ".fit", "expected one of %s, got %s" % (", ".join(FITS), got(fit)))
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
             % ("ints in [0, 65535]" if has_u else "numbers in [0.0, 1.0]", got(seq)))
    m = len(seq)
    if m < 1 or m > MAX_SAMPLES:
        fail(p, "%d values; allowed 1 .. %d" % (m, MAX_SAMPLES))
    # check every element before anything is converted (index in the path)
    if has_u:
        for i in range(m):
            x = seq[i]
            if isinstance(x, bool) or not isinstance(x, int) or x < 0 or x > U16_MAX:
                int_in("%s[%d]" % (p, i), x, 0, U16_MAX)
        # a tuple is immutable: the canonical form may share it
        vals = seq if type(seq) is tuple else tuple(seq)
    else:
        for i in range(m):
            x = seq[i]
            if (isinstance(x, bool) or not isinstance(x, (int, float))
                    or not (0.0 <= x <= 1.0)):      # also catches nan
                num("%s[%d]" % (p, i), x, 0.0, 1.0)
        vals = tuple(int(x * 65535.0 + 0.5) for x in seq)
    return {"kind": "samples", "u16": vals, "fit": fit}


_fast_fill = None           # scene_viper.fill, or False where it does not load


def _fast():
    global _fast_fill
    if _fast_fill is None:
        from ...compat import native
        _fast_fill = native("texel.runtime.scene_viper", "fill") or False
    return _fast_fill


def fill_samples(vals, fit, n, buf, i0=0, count=None):
    """Positions i0 .. i0+count (default: to the end) of a region of n
    positions playing vals with `fit`, into buf[0 .. count)."""
    if count is None:
        count = n - i0
    fast = _fast()
    if fast and fast(vals, fit, n, buf, i0, count):
        return
    _loop(vals, 0, len(vals), fit, n, buf, i0, count)


def _loop(vals, base, m, fit, n, buf, i0, count):
    """fill_samples in Python: vals[k - base] is value k of the m."""
    if fit == "tile" or m == 1 or n == 1:
        # tile: position i plays value i mod m (stretch of one value or onto one
        # position: the first value)
        k = i0 % m
        for i in range(count):
            buf[i] = vals[k - base]
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
    k, r = divmod(i0 * step, den)   # i*(m-1) = k*(n-1) + r (once per call: may be long)
    k -= base
    for i in range(count):
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


def _copy(dst, at, src, a, b):
    """dst[at .. at+b-a) = src[a .. b) (uint16 arrays): at memcpy speed where
    a memoryview slice can be assigned, else value by value."""
    try:
        memoryview(dst)[at:at + b - a] = memoryview(src)[a:b]
    except (TypeError, ValueError, NotImplementedError):
        for i in range(b - a):
            dst[at + i] = src[a + i]


def _gather(chunks, a, b, dst):
    """Values a .. b of an upload (its chunks) into dst[0 .. b-a)."""
    at = 0
    while a < b:
        c = chunks[a >> CHUNK_BITS]
        off = a & CHUNK_MASK
        take = min(b - a, len(c) - off)
        _copy(dst, at, c, off, off + take)
        at += take
        a += take


def fill_chunks(vals, fit, n, chunks):
    """fill_samples into chunks (new_chunks(n): the region's n values),
    chunk by chunk: no block of more than 1 KB for any samples region (a
    tiled or stretched full screen was one 38.4 KB block, which a playing
    Pico's heap often does not have in one piece). An upload's values are
    copied in runs (tile) or gathered per chunk (stretch)."""
    m = len(vals)
    tile = fit == "tile" or m == 1 or n == 1
    src = getattr(vals, "chunks", None) if getattr(vals, "CHUNKS", False) else None
    c = core()
    if src is None and c and len(chunks) <= 128:
        # the C core (texel_core.c tc_samples): 1.7 us a position in viper on an RP2040
        c.samples(chunks, CHUNK_BITS, n, vals if type(vals) is array else
                  array("H", vals), m, 0 if tile else 1)
        return
    if src is None and _fast():
        from ..scene_viper import fill_chunks as fast_chunks
        if fast_chunks(vals, fit, n, chunks):       # one viper call for every chunk
            return
        if type(vals) is tuple and array is not None:
            vals = array("H", vals)         # once (viper reads arrays): m <= 512 from the host
    o = 0
    for c in chunks:
        L = len(c)
        if src is not None and tile:
            at = 0
            while at < L:                   # runs of the upload: value k at position o + at
                k = (o + at) % m
                sc = src[k >> CHUNK_BITS]
                off = k & CHUNK_MASK
                take = min(L - at, len(sc) - off)
                _copy(c, at, sc, off, off + take)
                at += take
        elif src is not None:               # stretch: the chunk's span of values, gathered
            ka = (o * (m - 1)) // (n - 1)
            kb = min(m - 1, ((o + L - 1) * (m - 1)) // (n - 1) + 1)
            tmp = u16_one_block(kb - ka + 1)
            _gather(src, ka, kb + 1, tmp)
            if not (_fast_stretch(tmp, ka, m, n, c, o, L)):
                _loop(tmp, ka, m, fit, n, c, o, L)
            tmp = None
        else:
            fill_samples(vals, fit, n, c, o, L)
        o += L


def _fast_stretch(tmp, base, m, n, buf, i0, count):
    """The viper stretch over a gathered span (value k at tmp[k - base])."""
    if not _fast() or n - 1 > 32768:
        return False
    from ..scene_viper import fill_stretch
    k, r = divmod(i0 * (m - 1), n - 1)
    fill_stretch(buf, tmp, m, n, count, k - base, r)
    return True


def plays_as_is(tex, n):
    """An uploaded samples map (upload.Chunks) that tiles a region of exactly
    its length is played from its own chunks: no second copy (38,400 bytes
    for a full TPaD screen), and no block larger than 1 KB. Nothing ever
    writes to it after the upload."""
    return (tex["fit"] == "tile" and getattr(tex["u16"], "CHUNKS", False)
            and len(tex["u16"]) == n)


# Up to SMALL values the refresh plays where they are, with no map (K_TILE and
# K_STRETCH, runtime/kinds/__init__.py): a full-screen gradient was 38,400 bytes of
# chunks that took 8.9 ms to allocate and fill on the emulated Pico, and is now m + 1
# values. SMALL keeps their block as small as a chunk. A stretch that shrinks (m > n)
# or spans more than 32,769 positions (_loop's "small" case no longer holds) is a map.
SMALL = 1 << CHUNK_BITS
STRETCH_MAX_N = 32769


def how(tex, n):
    """How the refresh plays tex over n positions: K_CONST (one value),
    K_TILE, K_STRETCH (the values where they are) or K_CHUNK (a map)."""
    vals = tex["u16"]
    if getattr(vals, "CHUNKS", False) or len(vals) > SMALL:
        return K_CHUNK
    m = len(vals)
    if m == 1:
        return K_CONST
    if tex["fit"] == "tile" or n == 1:
        return K_TILE
    return K_STRETCH if m <= n <= STRETCH_MAX_N else K_CHUNK


def plan(tex, n, kind):
    """The 5-tuple a K_TILE or K_STRETCH row (kind: how(tex, n)) plays (scene.Scene.amp and the
    three refresh cores compute _loop's values from it, value for value):
    K_TILE (vals, m, 65536 // m + 1, 0, 0): vals[o mod m] at offset o, the mod by
        that reciprocal below offset 32,768 (as a texel plan's texel index);
    K_STRETCH (vals + its last value again, A, B, n - 1, (B << 17) // (n - 1))
        with A, B = divmod((m - 1) << 15, n - 1): at offset o,
        q = o*A + o*B // (n - 1) is floor(o*(m-1)*2^15 / (n-1)) = k*2^15 + f,
        k = floor(o*(m-1) / (n-1)) and f = floor(r*2^15 / (n-1)) for its
        remainder r, so value k + its weight (f + 1) >> 1 is _loop's. Every
        product stays below 2^30 (o, n - 1 <= 32768; A <= 2^15 * m/n). The last
        word is the C refresh's, for its division by multiplication (refresh_core.c
        tc_few; below 2^17: a small int).
        The repeated last value is read, with weight 0, at the last position."""
    vals = tex["u16"]
    m = len(vals)
    if kind == K_TILE:
        return (array("H", vals), m, 65536 // m + 1, 0, 0)
    den = n - 1
    a, b = divmod((m - 1) << 15, den)
    # (b << 17) // den in two steps below 2^30 (b << 17 can reach 2^32: a long int)
    c, r = divmod(b << 13, den)
    # one array of exactly m + 1 (array.append would grow it by 8)
    return (array("H", tuple(vals) + (vals[m - 1],)), a, b, den, (c << 4) + (r << 4) // den)


def _vals_bytes(tex, k):
    # plan()'s array: the m values, and the last once more for a stretch
    return 0 if k == K_CONST else 2 * (len(tex["u16"]) + (k == K_STRETCH))


def need(tex, n, engine):
    k = how(tex, n)
    return 2 * n if k == K_CHUNK else _vals_bytes(tex, k)


def block(tex, n, engine):
    k = how(tex, n)
    if k == K_CHUNK:
        return 2 * min(n, 1 << CHUNK_BITS)     # chunks of 512 values (fill_chunks)
    return _vals_bytes(tex, k)


def store(tex, n, engine):
    k = how(tex, n)
    if k == K_CONST:
        return K_CONST, tex["u16"][0], None
    if k != K_CHUNK:
        return k, plan(tex, n, k), None
    if plays_as_is(tex, n):
        return K_CHUNK, tex["u16"].chunks, None     # the upload itself, exactly region-long
    ch = new_chunks(n)
    return K_CHUNK, ch, ch


def fill(tex, n, target, engine, dx_um):
    fill_chunks(tex["u16"], tex["fit"], n, target)


def describe(tex):
    return {"values": len(tex["u16"]), "fit": tex["fit"]}


def words(d):
    return "samples (%d values, %s)" % (d["values"], d["fit"])


label = words
