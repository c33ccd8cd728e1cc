# The sums of sines (2sin, 3sin, 4sin) as uint16 maps in machine-word ints:
# a board's fast path for reference_u16 (gen/reference.py _fill_sines). The
# float path costs a stock Pico 3.5 s for a half-screen 4sin (38,400 float
# sines and their heap floats), all of it inside main.py's power-up scene,
# so a friendly Ctrl-D left the REPL waiting for it (issue 30: the REPL
# answers within 1 s of board time); this takes 110 ms there
# (bench/results/reference_sines.txt).
#
# Per sine and sample: the exact integer phase p (1e-5 cycle units, as the
# float path) indexes gen/sine_table.py's Q16 (sin+1)/2 at 1024 points a turn
# (step k, remainder r of p*1024/100000, carried from sample to sample),
# interpolated at fq = r*4096/100000 (by a multiply, 1/4096 of a step), kept
# with 4 extra bits (Q20): v < 2^20.
# Their sum A (< 2^22) maps linearly to the map value; u = round((A - A0)/W),
# W = WS/2^16 A per u16 step, from a reciprocal estimate made exact by its
# remainder (see fill), clipped to 0..65535. Every intermediate < 2^31, so 32-bit
# (rp2, stm32) and 64-bit (unix) words give identical results.
#
# Precision (tests/gen/test_reference_viper.py, every sample of 2sin/3sin/4sin
# up to 200,000): within 1 u16 (1.5e-5 of the map) of the binary64 map's
# rounding, as float32 boards' float path (~13 % of samples off by 1; float32
# ~0.2 %): the table's Q16 rounding, 0.5/65535 a sine, dominates. 1 u16 is
# 0.06 of a PWM count at the Pico's 3,676 (boards/pico/board.json).
# Kept alone in this file: ports without a native emitter cannot compile it.
import micropython

TURN = 100000           # gen/reference.py _SINE_TURN

# name -> (A0, WS, RQ): A0 = the sum A whose map value is 0 (rounded), WS = W
# (A per u16 step) * 2^16 (rounded), RQ = 2^36 // WS, from gen/reference.py's
# _SINES and _MINMAX; literals, so a float32 board computes nothing
# (tests/gen/test_reference_viper.py derives and checks them).
CONSTANTS = {"2sin": (174760, 1747627, 39321), "3sin": (212345, 2721014, 25255),
             "4sin": (400547, 3393228, 20251)}


@micropython.viper
def fill(out: ptr16, n: int, steps: ptr32, ph: ptr32, m: int, tab: ptr16, a0: int, ws: int,
         rq: int):
    # ph[2j], ph[2j+1]: sine j's table position p*1024/100000 as the step k
    # (0..1023) and its remainder r (0..99999), both exact; steps[2j], [2j+1]:
    # what a sample adds to them (step*1024 as divmod by 100000), so no
    # division runs per sample (a viper // is a call into the runtime).
    i = 0
    m2 = 2 * m
    hw = ws >> 1
    while i < n:
        a = 0
        j = 0
        while j < m2:
            k = ph[j]
            r = ph[j + 1]
            y0 = int(tab[k])
            # fq = r*4096/100000 (0..4095, by a multiply: 99999*21475 < 2^31)
            a += (y0 << 4) + (((int(tab[k + 1]) - y0) * ((r * 21475) >> 19)) >> 8)
            r += steps[j + 1]
            k += steps[j]
            if r >= 100000:
                r -= 100000
                k += 1
            if k >= 1024:
                k -= 1024
            ph[j] = k
            ph[j + 1] = r
            j += 2
        x = a - a0
        if x <= 0:
            out[i] = 0
        elif x >= ws:                       # beyond 65535 (a longer map): clipped
            out[i] = 65535
        else:
            # u = round(x * 2^16 / ws): an estimate from rq = 2^36 // ws
            # (product < 2^30; low by up to ~5), then exact by the remainder
            # e = x*2^16 - u*ws, which is small (< 2^25) although its terms
            # are not: on 32-bit words they wrap and the difference is exact.
            u = ((x >> 6) * rq) >> 14
            e = (x << 16) - u * ws
            while e >= hw:
                u += 1
                e -= ws
            while e < hw - ws:
                u -= 1
                e += ws
            out[i] = u if u < 65535 else 65535
        i += 1


def steps_of(steps):
    """fill's per-sample increments for phase steps (1e-5 cycle units):
    (step*1024) as (quotient, remainder) by 100000, flattened."""
    out = []
    for st in steps:
        out.append(st * 1024 // TURN)
        out.append(st * 1024 % TURN)
    return out


@micropython.viper
def copy16(dst: ptr16, d: int, src: ptr16, s: int, cnt: int, step: int):
    # dst[d + t] = src[s + t*step] for t < cnt (step 1 or -1): one piece of a
    # noise row's mirrored repeats (gen/reference.py _mirror); src and dst may
    # be one chunk, the values read never overlapping the ones written
    e = d + cnt
    while d < e:
        dst[d] = src[s]
        d += 1
        s += step
