# The texture random generator ("tpr1"). It is part of the texture format: a
# texture is reproducible from its parameter set alone, on every runtime.
#
# Integer core: xoshiro128++ (Blackman & Vigna), 4 x 32-bit words of state,
# period 2^128 - 1. Each 32-bit word is held as two 16-bit halves so that every
# intermediate stays below 2^30: MicroPython small ints are +-2^30 and anything
# larger would be a heap bigint. The integer stream is therefore identical,
# bit for bit, on CPython, MicroPython (any port) and CircuitPython.
#
# Seeding: state = (seed, 0x9E3779B9, 0x243F6A88, 0xB7E15162) for a seed in
# [0, 2^32); the three constants (golden ratio, pi, e fractions) keep the state
# non-zero for seed 0; the first 16 outputs are discarded to mix the seed in.
#
# Floats: u = (x + 0.5) / 2^32 for a 32-bit output x, so 0 < u < 1 exactly.
# z = Phi^-1(u) by Wichura's AS241 (PPND16, |rel. error| < 1e-16), with the
# natural log of its tail branch computed here from frexp and a fixed series
# (only + - * / and correctly rounded sqrt): so u and z are bit-identical on
# every interpreter whose floats are IEEE binary64 (CPython, the unix port),
# and the same formula evaluated in float32 on rp2/stm32 boards.
#
# Draw order (as in the lab's buildFine5.m): one u for the start phase, then
# one z per texel, in texel order; each draw consumes one 32-bit output.
import math

_M16 = 0xFFFF
SEED_CONSTS = ((0x9E37, 0x79B9), (0x243F, 0x6A88), (0xB7E1, 0x5162))
WARMUP = 16
_TWO32 = 4294967296.0


class Rng:
    def __init__(self, seed, ftype=float, consts=SEED_CONSTS):
        # ftype: float type of u and z (tests pass numpy.float32 to evaluate
        # them as a float32 board does; Python float is the interpreter's).
        # consts: SEED_CONSTS (the texture stream) or gen/options.py's
        # REDRAW_CONSTS (the lower bound's redraw stream).
        self.F = ftype
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0 or seed > 0xFFFFFFFF:
            raise ValueError("seed: expected an int in [0, 4294967295], got %r" % (seed,))
        # seed >> 16 is safe even when seed is a bigint on MicroPython.
        self.a_hi = (seed >> 16) & _M16
        self.a_lo = seed & _M16
        self.b_hi, self.b_lo = consts[0]
        self.c_hi, self.c_lo = consts[1]
        self.d_hi, self.d_lo = consts[2]
        for _ in range(WARMUP):
            self.next_hi_lo()

    def next_hi_lo(self):
        """Next 32-bit output as (high 16 bits, low 16 bits)."""
        a_hi = self.a_hi; a_lo = self.a_lo
        b_hi = self.b_hi; b_lo = self.b_lo
        c_hi = self.c_hi; c_lo = self.c_lo
        d_hi = self.d_hi; d_lo = self.d_lo
        # result = rotl(a + d, 7) + a
        lo = a_lo + d_lo
        hi = (a_hi + d_hi + (lo >> 16)) & _M16
        lo &= _M16
        r_hi = ((hi << 7) | (lo >> 9)) & _M16
        r_lo = ((lo << 7) | (hi >> 9)) & _M16
        lo = r_lo + a_lo
        out_hi = (r_hi + a_hi + (lo >> 16)) & _M16
        out_lo = lo & _M16
        # t = b << 9
        t_hi = ((b_hi << 9) | (b_lo >> 7)) & _M16
        t_lo = (b_lo << 9) & _M16
        c_hi ^= a_hi; c_lo ^= a_lo          # c ^= a
        d_hi ^= b_hi; d_lo ^= b_lo          # d ^= b
        b_hi ^= c_hi; b_lo ^= c_lo          # b ^= c
        a_hi ^= d_hi; a_lo ^= d_lo          # a ^= d
        c_hi ^= t_hi; c_lo ^= t_lo          # c ^= t
        # d = rotl(d, 11)
        self.d_hi = ((d_hi << 11) | (d_lo >> 5)) & _M16
        self.d_lo = ((d_lo << 11) | (d_hi >> 5)) & _M16
        self.a_hi = a_hi; self.a_lo = a_lo
        self.b_hi = b_hi; self.b_lo = b_lo
        self.c_hi = c_hi; self.c_lo = c_lo
        return out_hi, out_lo

    def uniform(self):
        """u in (0, 1): (x + 0.5) / 2^32, exact in binary64."""
        hi, lo = self.next_hi_lo()
        return uniform_of(hi, lo, self.F)

    def normal(self):
        """A standard-normal draw: AS241 inverse CDF of one uniform. The
        upper tail uses 1 - u computed from the integer draw itself
        ((2^32 - 1 - x) + 0.5) / 2^32: exact in binary64 (so the same bits as
        1.0 - u there), while in float32 1.0 - u would keep only ~2^-24 of
        absolute resolution and lose the tail (pitch errors of 3e-4)."""
        hi, lo = self.next_hi_lo()
        F = self.F
        u = uniform_of(hi, lo, F)
        uc = uniform_of(0xFFFF - hi, 0xFFFF - lo, F)
        return ppnd16(u, uc)


def uniform_of(hi, lo, F=float):
    """u = (x + 0.5) / 2^32 of the 32-bit output x = (hi, lo), in float type F:
    in (0, 1), exact in binary64."""
    return (F(hi) * 65536.0 + (lo + 0.5)) / _TWO32


def phase_fraction_u28(hi, lo):
    """The start phase of the integer engines, in 2^-28 turns, from the same
    32-bit output as u (top 28 bits, rounded the way (x + 0.5)/2^32 is)."""
    # x = 2^32 - 1 rounds up to a whole turn: mask it back to 0.
    return (((hi << 12) | (lo >> 4)) + ((lo >> 3) & 1)) & 0x0FFFFFFF


# --- natural log with a fixed operation sequence ---------------------------
_LN2 = 0.6931471805599453
_SQRT_HALF = 0.7071067811865476
_INV_ODD = (1.0, 1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0, 1.0 / 11.0,
            1.0 / 13.0, 1.0 / 15.0, 1.0 / 17.0, 1.0 / 19.0, 1.0 / 21.0, 1.0 / 23.0)


def det_log(x):
    """ln(x) for x > 0 from frexp and the atanh series (|s| <= 0.172, 12 terms:
    truncation < 1e-20). Same bits wherever floats are binary64."""
    m, e = math.frexp(x)
    m = type(x)(m)          # keep the caller's float type (float32 emulation)
    if m < _SQRT_HALF:
        m = m * 2.0
        e -= 1
    s = (m - 1.0) / (m + 1.0)
    s2 = s * s
    acc = _INV_ODD[11]
    for i in range(10, -1, -1):
        acc = acc * s2 + _INV_ODD[i]
    return e * _LN2 + 2.0 * s * acc


# --- AS241 PPND16 (Wichura 1988), coefficients as published -------------
_A = (3.387132872796366608, 133.14166789178437745, 1971.5909503065514427,
      13731.693765509461125, 45921.953931549871457, 67265.770927008700853,
      33430.575583588128105, 2509.0809287301226727)
_B = (1.0, 42.313330701600911252, 687.1870074920579083, 5394.1960214247511077,
      21213.794301586595867, 39307.89580009271061, 28729.085735721942674,
      5226.495278852545925)
_C = (1.42343711074968357734, 4.6303378461565452959, 5.7694972214606914055,
      3.64784832476320460504, 1.27045825245236838258, 0.24178072517745061177,
      0.0227238449892691845833, 7.7454501427834140764e-4)
_D = (1.0, 2.05319162663775882187, 1.6763848301838038494, 0.68976733498510000455,
      0.14810397642748007459, 0.0151986665636164571966, 5.475938084995344946e-4,
      1.05075007164441684324e-9)
_E = (6.6579046435011037772, 5.4637849111641143699, 1.7848265399172913358,
      0.29656057182850489123, 0.026532189526576123093, 0.0012426609473880784386,
      2.71155556874348757815e-5, 2.01033439929228813265e-7)
_F = (1.0, 0.59983220655588793769, 0.13692988092273580531, 0.0148753612908506148525,
      7.868691311456132591e-4, 1.8463183175100546818e-5, 1.4215117583164458887e-7,
      2.04426310338993978564e-15)


def _ratio(num, den, r):
    n = num[7]
    d = den[7]
    for i in range(6, -1, -1):
        n = n * r + num[i]
        d = d * r + den[i]
    return n / d


def ppnd16(p, pc=None):
    """Phi^-1(p) for 0 < p < 1 (AS241). pc, if given, is 1 - p computed
    exactly by the caller (used in the upper tail)."""
    q = p - 0.5
    if -0.425 <= q <= 0.425:
        r = 0.180625 - q * q
        return q * _ratio(_A, _B, r)
    if q < 0.0:
        r = p
    else:
        r = 1.0 - p if pc is None else pc
    r = math.sqrt(-det_log(r))
    if r <= 5.0:
        v = _ratio(_C, _D, r - 1.6)
    else:
        v = _ratio(_E, _F, r - 5.0)
    return -v if q < 0.0 else v
