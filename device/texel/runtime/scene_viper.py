# The samples regions' fill in viper (runtime/kinds/samples.py fill_samples, which
# falls back to its Python loop where this module does not load: no native
# emitter, CircuitPython). Integers only, the same arithmetic as the Python
# loop, value for value: a stretched full-screen map took 646 ms in Python
# on an RP2040 (bench/firmware.py, the shipped gradient scene).
# buf: array('H') of n; vals: array('H') of m values.
import micropython
from array import array


def fill(vals, fit, n, buf, i0=0, count=None):
    """samples.fill_samples' work in viper where it can be (vals a tuple of
    ints or an array('H'), buf an array('H'); a stretch over at most 32,769
    positions): positions i0 .. i0+count of the region into buf[0 .. count).
    True when done, False to leave it to the Python loop."""
    m = len(vals)
    if count is None:
        count = n - i0
    if type(buf) is not array or len(buf) < count:
        return False
    if type(vals) is tuple:
        vals = array("H", vals)
    elif type(vals) is not array:
        return False
    if fit == "tile" or m == 1 or n == 1:
        fill_tile(buf, vals, m, count, i0 % m)
        return True
    if n - 1 > 32768:
        return False
    k, r = divmod(i0 * (m - 1), n - 1)      # < 32,768 x 19,200 < 2^30: a small int
    fill_stretch(buf, vals, m, n, count, k, r)
    return True


@micropython.viper
def fill_tile(buf, vals, m: int, count: int, k: int):
    b = ptr16(buf)
    v = ptr16(vals)
    for i in range(count):
        b[i] = v[k]
        k += 1
        if k == m:
            k = 0


@micropython.viper
def fill_stretch(buf, vals, m: int, n: int, count: int, k: int, r: int):
    # n - 1 <= 32768 (scene.py's "small" case): r << 15 stays below 2^30
    b = ptr16(buf)
    v = ptr16(vals)
    den = n - 1
    step = m - 1
    for i in range(count):
        a = int(v[k])
        if r == 0:
            b[i] = a
        else:
            w = ((r << 15) // den + 1) >> 1
            b[i] = a + (((int(v[k + 1]) - a) * w + 8192) >> 14)
        r += step
        if r >= den:
            k += r // den
            r = r % den


def fill_chunks(vals, fit, n, chunks):
    """fill() into a chunked map (a tuple of array('H'), the region's n
    values in order: kinds/samples.py fill_chunks) in one viper call, so no
    Python runs per chunk. vals a tuple or an array('H'). True when done."""
    m = len(vals)
    if type(vals) is tuple:
        vals = array("H", vals)
    elif type(vals) is not array:
        return False
    if fit == "tile" or m == 1 or n == 1:
        tile_chunks(chunks, len(chunks), vals, m)
        return True
    if n - 1 > 32768:
        return False
    stretch_chunks(chunks, len(chunks), vals, m, n)
    return True


@micropython.viper
def tile_chunks(chunks, nch: int, vals, m: int):
    v = ptr16(vals)
    k = 0
    for j in range(nch):
        c = chunks[j]
        b = ptr16(c)
        L = int(len(c))
        for i in range(L):
            b[i] = v[k]
            k += 1
            if k == m:
                k = 0


@micropython.viper
def stretch_chunks(chunks, nch: int, vals, m: int, n: int):
    # fill_stretch over the chunks in order: n - 1 <= 32768
    v = ptr16(vals)
    den = n - 1
    step = m - 1
    k = 0
    r = 0
    for j in range(nch):
        c = chunks[j]
        b = ptr16(c)
        L = int(len(c))
        for i in range(L):
            a = int(v[k])
            if r == 0:
                b[i] = a
            else:
                w = ((r << 15) // den + 1) >> 1
                b[i] = a + (((int(v[k + 1]) - a) * w + 8192) >> 14)
            r += step
            if r >= den:
                k += r // den
                r = r % den
