# Integer engine for boards without an FPU: a fixed-point phase accumulator
# (2^28 units per turn) and a 1024-point sine table with linear interpolation.
# Output is uint16 Q16 (0..65535 = friction 0..1), 2 bytes/sample: a full
# 19,200-sample screen is 38.4 KB; the only other allocation is the 2 KB table.
#
# Per sample:  t = (t + d) & (2^28-1)       phase in 2^-28 turns, wraps
#              i = t >> 18, frac = (t >> 2) & 0xFFFF     table index, Q16 weight
#              v = tab[i] + ((tab[i+1]-tab[i]) * frac + 2^15) >> 16
#              out = (v * g + 2^13) >> 14    gain in Q14 (g = 16384: exact)
# Every intermediate stays below 2^30 (small ints on MicroPython: no heap), and
# the same code runs as @micropython.viper where the port has a native
# emitter: there ints are machine words, and the results are identical since
# nothing exceeds 31 bits.
#
# Error against the float64 reference, in 2^-28 turns of phase: the step d is
# rounded (<= 0.5 unit per sample, so <= k/2 units after k samples), the start
# phase t carries <= 0.5 unit per texel boundary; the table adds 2.4e-6 and
# Q16/Q14 rounding <= 1.5 LSB of 65535 -> see tests/gen/test_precision.py.
from ..compat import check_u16_out, core, fastest
from . import sine_table

NAME = "int"
PRECISION = "fixed-point Q28 phase, Q16 output"
_MASK = 0x0FFFFFFF


def available():
    return True                 # integers and a table: every runtime


def _fill_py(out, a, b, t, d, tab, g):
    while a < b:
        t = (t + d) & 0x0FFFFFFF
        i = t >> 18
        y0 = tab[i]
        v = y0 + (((tab[i + 1] - y0) * ((t >> 2) & 0xFFFF) + 32768) >> 16)
        out[a] = (v * g + 8192) >> 14
        a += 1
    return t


# The loop that runs: the C core's (compat.core(): the firmware's, or deploy's
# native module), else viper's, else the Python above - the same integers.
_C = core()
_fill, ENGINE = fastest("fill", "texel.gen.engine_int_viper", _fill_py)
VIPER = ENGINE == "viper"


def gain_q14(gain):
    return int(gain * 16384 + 0.5)


def render_u16(plan, out=None):
    n, L = plan.n, plan.L
    out = check_u16_out(out, n)
    tab = sine_table.table()
    g = gain_q14(plan.gain)
    t28, d28 = plan.t28, plan.d28
    if _C and _fill is _C.fill:         # one call for every texel
        _C.render(out, n, L, plan.count, t28, d28, tab, g)
        return out
    for i in range(plan.count):
        a = i * L
        b = a + L
        if b > n:
            b = n
        _fill(out, a, b, t28[i], d28[i], tab, g)
    return out


def render_chunks(plan, chunks, bits):
    """render_u16 into chunks of 1 << bits values (the last shorter; runtime/
    kinds new_chunks): the same values, and no block of the map's length (a
    region of 1-4-sample texels, or of one texel longer than the region, on a
    board's heap). A texel that straddles two chunks carries its phase from
    one to the next (fill returns it). With the C core and texels that tile
    a chunk (L divides it) one C call a chunk, else one fill a texel piece."""
    n, L = plan.n, plan.L
    tab = sine_table.table()
    g = gain_q14(plan.gain)
    t28, d28 = plan.t28, plan.d28
    size = 1 << bits
    if _C and _fill is _C.fill and size % L == 0:
        per = size // L
        mt, md = memoryview(t28), memoryview(d28)
        for c in range(len(chunks)):
            i0 = c * per
            k = plan.count - i0 if plan.count - i0 < per else per
            _C.render(chunks[c], len(chunks[c]), L, k, mt[i0:i0 + k], md[i0:i0 + k], tab, g)
        return chunks
    for i in range(plan.count):
        a = i * L
        b = a + L if a + L < n else n
        t = t28[i]
        d = d28[i]
        while a < b:
            o = (a >> bits) << bits
            e = o + size if o + size < b else b
            t = _fill(chunks[a >> bits], a - o, e - o, t, d, tab, g)
            a = e
    return chunks


def render(plan):
    from ..compat import float_buffer
    q = render_u16(plan)
    m = float_buffer(plan.n)
    for i in range(plan.n):
        m[i] = q[i] / 65535.0
    return m
