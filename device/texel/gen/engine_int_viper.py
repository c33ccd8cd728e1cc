# The integer engine's inner loop compiled by viper (machine-word ints, no
# heap). Same arithmetic as engine_int._fill_py; every intermediate < 2^31,
# so 32-bit (rp2, stm32) and 64-bit (unix) words give identical results.
# Kept alone in this file: ports without a native emitter cannot compile it.
import micropython


@micropython.viper
def fill(out: ptr16, a: int, b: int, t: int, d: int, tab: ptr16, g: int) -> int:
    while a < b:
        t = (t + d) & 0x0FFFFFFF
        i = t >> 18
        y0 = int(tab[i])
        v = y0 + (((int(tab[i + 1]) - y0) * ((t >> 2) & 0xFFFF) + 32768) >> 16)
        out[a] = (v * g + 8192) >> 14
        a += 1
    return t
