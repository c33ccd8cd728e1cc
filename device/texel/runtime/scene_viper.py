# The samples regions' fill in viper (runtime/kinds/samples.py fill_samples, which
# falls back to its Python loop where this module does not load: no native
# emitter, CircuitPython). Integers only, the same arithmetic as the Python
# loop, value for value: a stretched full-screen map took 646 ms in Python
# on an RP2040 (bench/firmware.py, the shipped gradient scene).
# buf: array('H') of n; vals: array('H') of m values.
import micropython
from array import array


def fill(vals, fit, n, buf):
    """samples.fill_samples' work in viper where it can be (vals a tuple of
    ints, buf an array('H'), a stretch over at most 32,769 positions): True
    when done, False to leave it to the Python loop."""
    m = len(vals)
    if type(vals) is not tuple or type(buf) is not array:
        return False
    if fit == "tile" or m == 1 or n == 1:
        fill_tile(buf, array("H", vals), m, n)
        return True
    if n - 1 > 32768:
        return False
    fill_stretch(buf, array("H", vals), m, n)
    return True


@micropython.viper
def fill_tile(buf, vals, m: int, n: int):
    b = ptr16(buf)
    v = ptr16(vals)
    k = 0
    for i in range(n):
        b[i] = v[k]
        k += 1
        if k == m:
            k = 0


@micropython.viper
def fill_stretch(buf, vals, m: int, n: int):
    # n - 1 <= 32768 (scene.py's "small" case): r << 15 stays below 2^30
    b = ptr16(buf)
    v = ptr16(vals)
    den = n - 1
    step = m - 1
    k = 0
    r = 0
    for i in range(n):
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
