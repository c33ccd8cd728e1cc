# Texture format 2: the texel plan in integer arithmetic, from the seed to the
# phase steps, so the same parameter set gives the same plan - and the int
# engine the same map - bit for bit on every runtime (CPython, the MicroPython
# unix port, float32 boards, CircuitPython's 30-bit floats). Format 1
# (gen/plan.py) inherits each runtime's float; it stays for the golden
# comparisons. docs/generator.md ("Texture format 2") states the grids and
# bounds; tests/gen/test_plan_int.py proves them.
#
# Units: z in Q24 (2^-24), log2 quantities in Q24 octaves, phase in 2^-28
# turns (as gen/plan.py's t28/d28, which the int engine and the K_PLAN scene
# refresh read). Per texel:
#   x      one 32-bit draw of the texture generator (gen/rng.py, unchanged)
#   z      inverse normal of (x + 0.5)/2^32: folded at 1/2, the octave of
#          w = 2*min(x, 2^32-1-x) + 1 picks 32 table points (plan_int_tables),
#          linear between them with an 11-bit weight (|error| <= 6.1e-5)
#   y      log2 of the pitch in c/mm = mu + round(sigma*z), clamped to
#          [Y_LO, Y_HI], then quantized: q * round_half_away(y / q)
#   D      phase step per sample = round(2^(y + LOG2_STEP0)) in 2^-28 turns
#          (2^x from two 256-entry tables and a first-order term: relative
#          error <= 1.2e-8); clamped to the band limit D_CAP if one is set
#   d28    D mod 2^28;  t28[i+1] = t28[i] + L * (D with 8 more bits) mod 2^28:
#          each texel starts where the exact step would have taken the last
#          (within 2^-8 unit per sample), so d's rounding does not drift
#          along the map; the seam to where the int engine's accumulator
#          ended is <= L/2 units (as format 1's)
# Parameters on stated grids (params.py rounds them, format 2 only):
#   pitch_db, irregularity_db, quant_db  0.001 dB -> integer mdB
#   mu    = round_half_up(P_mdb * C_DB / 2^16)          Q24 octaves
#   sigma = 2^(LOG2_LOG2_10 + round_half_up(I_mdb * C_DB / 2^16))  Q24 octaves per z
#   q     = round_half_up(Q_mdb * C_DB / 2^16)          Q24 octaves, 0 = off
#   band_limit_cpmm  0.001 c/mm -> D_CAP = round(cap_mc * 53 * 2^28 / 10^7)
# Every intermediate of the per-texel loop stays below 2^30 in magnitude (a
# small int on MicroPython: no heap), except the product sigma*z for draws
# with sigma*|z| > 64 octaves (irregularity near its maximum, |z| > 6); those
# are correct bigints, and viper's 32-bit words hold them (< 2^31). The same
# loop runs compiled by viper where the port has a native emitter
# (plan_int_viper.py), with identical results: nothing exceeds 31 bits.
from array import array
from . import params as _params
from .rng import phase_fraction_u28, uniform_of, WARMUP, SEED_CONSTS
from .plan_int_tables import table, EXP_HI, EXP_MID, NORM
from .grid import mdb
from ..compat import fastest

FORMAT = 2
MASK28 = 0x0FFFFFFF
Q24 = 1 << 24
# mdB -> Q24 octaves with 16 guard bits: log2(10) / 10000 * 2^40 (decibels of
# pitch are tenths of a decade of c/mm).
C_DB = 365249857
# log2(log2(10)) in Q24: sigma in decades -> octaves.
LOG2_LOG2_10 = 29058488
# log2(DX_MM * 2^28) in Q24: y (log2 c/mm) + this = log2 of the step in 2^-28 turns.
LOG2_STEP0 = 342929786
# ln(2) in Q20, for 2^r ~ 1 + r*ln2 over the last 8 bits of the fraction.
LN2_Q20 = 726817
# Clamp of y before quantization: 2^-22 c/mm has a step of 0.34 unit (rounds to
# 0 or 1: standing still); 2^15 c/mm is 347x the Nyquist pitch (a step of 174
# turns per sample, aliased anyway). Keeps every later value a small int.
Y_LO = -22 * Q24
Y_HI = 15 * Q24
NYQ_EXP = 27        # a step of >= 2^27 units is >= half a turn: above Nyquist
# A full-screen texel (384 texels) plan holds 12 bytes per texel (t28, d28, y).


def _round_q(mdb):
    """Q24 octaves of mdb millidecibels (tenths of a decade): round half up."""
    return (mdb * C_DB + 32768) >> 16


def mul28(a, b):
    """round(a * b / 2^28) for 0 <= a, b < 2^29, in 14/15-bit limbs so that
    every partial product stays below 2^30 (a small int on MicroPython)."""
    a1 = a >> 15
    a0 = a & 0x7FFF
    b1 = b >> 15
    b0 = b & 0x7FFF
    t = a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096
    return ((a1 * b1) << 2) + (t >> 13)


def exp2_m(r, tab):
    """2^(r / 2^24) in Q28, for 0 <= r < 2^24 (a value in [2^28, 2^29))."""
    lo = r & 0xFF
    return mul28(mul28(tab[EXP_HI + (r >> 16)], tab[EXP_MID + ((r >> 8) & 0xFF)]),
                 (1 << 28) + ((lo * LN2_Q20 + 32768) >> 16))


def exp2_q24(y, tab):
    """round(2^(y / 2^24) * 2^24): a Q24 value from a Q24 log2 (|y| < 2^29)."""
    e = y >> 24
    m = exp2_m(y & 0xFFFFFF, tab)
    if e >= 4:
        return m << (e - 4)
    return (m + (1 << (3 - e))) >> (4 - e)


def norm_q24(hi, lo, tab):
    """The standard normal draw of the 32-bit output (hi, lo), in Q24."""
    if hi >= 0x8000:                        # upper half: z = -z(2^32-1-x) > 0
        hi = 0xFFFF - hi
        lo = 0xFFFF - lo
        s = 1
    else:
        s = -1
    # w = 2v + 1 in [1, 2^32) as 16-bit halves (w itself may be no small int)
    wh = (hi << 1) | (lo >> 15)
    wl = ((lo << 1) & 0xFFFF) | 1
    # e = bit length of w - 1 (its octave); top = the 16 bits below w's
    # leading one: 5 for the table point j, 11 for the weight f.
    if wh:
        b = wh
        e = 16
    else:
        b = wl
        e = 0
    if b >= 0x100:
        b >>= 8
        e += 8
    if b >= 0x10:
        b >>= 4
        e += 4
    if b >= 0x4:
        b >>= 2
        e += 2
    if b >= 0x2:
        e += 1
    if e >= 16:
        k = e - 16
        top = ((wh << (16 - k)) | (wl >> k)) & 0xFFFF
    else:
        top = (wl << (16 - e)) & 0xFFFF
    i = NORM + (e << 5) + (top >> 11)
    t0 = tab[i]
    a = t0 + (((tab[i + 1] - t0) * (top & 0x7FF) + 1024) >> 11)
    return a * s


def step_d(y, tab):
    """(d, a, af, e) of a log pitch y: the played phase step
    d = round(2^(y + LOG2_STEP0)) in 2^-28 turns per sample (mod 2^28), the
    same step with 8 more bits for the texel's phase advance (a whole units
    mod 2^28, af 1/256 units: so the start phases do not drift by d's
    rounding, up to 0.5 unit per sample, along a long map), and the step's
    binary exponent e (d in [2^e, 2^(e+1)])."""
    w = y + LOG2_STEP0
    e = w >> 24
    m = exp2_m(w & 0xFFFFFF, tab)
    if e >= 28:                 # a turn or more per sample: exact integers
        k = e - 28
        d = (m & (MASK28 >> k)) << k
        return d, d, 0, e
    if e < -2:
        return 0, 0, 0, e
    d = (m + (1 << (27 - e))) >> (28 - e)
    if e >= 20:                 # the step's fraction is m's low 28-e bits
        k = e - 20
        return d, m >> (28 - e), (m & (0xFF >> k)) << k, e
    x = (m + (1 << (19 - e))) >> (20 - e)
    return d, x >> 8, x & 0xFF, e


def mulmod28(L, d):
    """(L * d) mod 2^28 for 0 <= L < 2^21, 0 <= d < 2^28, in 14-bit limbs
    (every partial product < 2^29)."""
    lh = L >> 14
    ll = L & 0x3FFF
    dh = d >> 14
    dl = d & 0x3FFF
    return (ll * dl + (((ll * dh + lh * dl) & 0x3FFF) << 14)) & MASK28


def texels_py(st, count, L, mu, sigma, q, dcap, tab, t28, d28, ys, zs, keep):
    """The per-texel loop (plan_int_viper.texels is the same, compiled).
    st: seeded() - the generator's state before its warm-up as 8 16-bit
    halves (a, b, c, d; high first) and 2 more: the loop draws the warm-up,
    then the start phase's draw (kept in st[8], st[9]; gen/rng.py's order),
    then one per texel. Fills t28/d28, ys if keep & 2, zs if keep & 1;
    returns the number of texels above Nyquist."""
    above = 0
    t = 0
    tf = 0                      # the start phase's 1/256 units
    a_hi = st[0]; a_lo = st[1]; b_hi = st[2]; b_lo = st[3]
    c_hi = st[4]; c_lo = st[5]; d_hi = st[6]; d_lo = st[7]
    for i in range(-WARMUP - 1, count):
        # xoshiro128++ in 16-bit halves: gen/rng.py Rng.next_hi_lo, inlined
        lo = a_lo + d_lo
        hi = (a_hi + d_hi + (lo >> 16)) & 0xFFFF
        lo &= 0xFFFF
        r_hi = ((hi << 7) | (lo >> 9)) & 0xFFFF
        r_lo = ((lo << 7) | (hi >> 9)) & 0xFFFF
        lo = r_lo + a_lo
        x_hi = (r_hi + a_hi + (lo >> 16)) & 0xFFFF
        x_lo = lo & 0xFFFF
        t_hi = ((b_hi << 9) | (b_lo >> 7)) & 0xFFFF
        t_lo = (b_lo << 9) & 0xFFFF
        c_hi ^= a_hi; c_lo ^= a_lo
        d_hi ^= b_hi; d_lo ^= b_lo
        b_hi ^= c_hi; b_lo ^= c_lo
        a_hi ^= d_hi; a_lo ^= d_lo
        c_hi ^= t_hi; c_lo ^= t_lo
        hi = d_hi
        d_hi = ((hi << 11) | (d_lo >> 5)) & 0xFFFF
        d_lo = ((d_lo << 11) | (hi >> 5)) & 0xFFFF
        if i < 0:
            if i == -1:                 # the start phase's draw
                st[8] = x_hi
                st[9] = x_lo
                t = phase_fraction_u28(x_hi, x_lo)
            continue
        z = norm_q24(x_hi, x_lo, tab)
        if keep & 1:
            zs[i] = z
        # y = mu + round(sigma * z / 2^24), rounded half away from zero
        za = -z if z < 0 else z
        s1 = sigma >> 14
        s0 = sigma & 0x3FFF
        z1 = za >> 14
        z0 = za & 0x3FFF
        m = s1 * z0 + s0 * z1 + ((s0 * z0 + 0x800000) >> 14)
        p = ((s1 * z1) << 4) + (m >> 10)
        y = mu - p if z < 0 else mu + p
        if y < Y_LO:
            y = Y_LO
        elif y > Y_HI:
            y = Y_HI
        if q:
            ya = -y if y < 0 else y
            n = (2 * ya + q) // (2 * q)
            y = -n * q if y < 0 else n * q
        if keep & 2:
            ys[i] = y
        d, a, af, e = step_d(y, tab)
        if e >= NYQ_EXP:
            above += 1
        if dcap and (e >= 28 or d > dcap):
            d = dcap
            a = dcap
            af = 0
        d &= MASK28
        d28[i] = d
        t28[i] = t
        tf += L * af
        t = (t + mulmod28(L, a) + (tf >> 8)) & MASK28
        tf &= 0xFF
    return above


def seeded(seed):
    """The generator's state for a seed before its warm-up (gen/rng.py), plus
    two halves for the start phase's draw: array('H') of 10."""
    c = SEED_CONSTS
    return array("H", ((seed >> 16) & 0xFFFF, seed & 0xFFFF, c[0][0], c[0][1],
                       c[1][0], c[1][1], c[2][0], c[2][1], 0, 0))


def _ints(n):
    return array("i", bytes(4 * n))


_ONE = _ints(1)             # where the loop's unkept outputs point (never written)


# The loop that runs: the C core's (compat.core(): the firmware's built-in
# module, or the native .mpy deploy installs), else viper's, else texels_py -
# the same integers (tests/gen/test_texel_core.py compares them).
_texels, ENGINE = fastest("texels", "texel.gen.plan_int_viper", texels_py)
VIPER = ENGINE == "viper"


def texels_for(engine):
    """The per-texel loop of engine "c", "viper" or "py" (None: the one that
    runs); ValueError where this runtime has no such engine."""
    if engine is None:
        return _texels
    return fastest("texels", "texel.gen.plan_int_viper", texels_py, engine)[0]


class PlanInt:
    """The format-2 plan of a validated parameter set (v == 2): t28, d28 (the
    int engine's phases), y (log2 pitch, Q24 octaves), and, for the float
    engines and analysis, f and phi computed from them on demand."""

    FORMAT = FORMAT
    # seed 001's lower bound (gen/options.py sets them when it applies):
    # milli-c/mm (0: none), texels redrawn, texels left at the bound
    min_mc = 0
    redrawn = 0
    at_min = 0

    def __init__(self, p, keep_z=False, engine=None, keep_y=True):
        # p: a validated format-2 parameter set. keep_y=False leaves out the
        # log pitches (a board playing the plan needs only t28/d28: one 4-byte
        # array less to allocate, ~1.4 ms on a Pico); engine "py", "viper" or
        # "c" runs that loop (texels_for; tests compare them), None the fastest.
        self.params = p
        self.n = p["length_samples"]
        self.L = L = p["texel_samples"]
        self.count = count = _params.texel_count(p)
        self.gain = p["gain"]
        tab = table()
        self.mu = _round_q(mdb(p["pitch_db"]))
        self.sigma = exp2_q24(LOG2_LOG2_10 + _round_q(mdb(p["irregularity_db"])), tab)
        self.q = _round_q(mdb(p["quant_db"])) if p["quant_db"] else 0
        cap = p["band_limit_cpmm"]
        self.cap_mc = mdb(cap) if cap is not None else 0
        # cap_mc * 53 * 2^28 / 10^7 = cap (c/mm) * DX_MM * 2^28; a bigint
        # on MicroPython, once per texture
        self.dcap = (self.cap_mc * 53 * (1 << 28) + 5000000) // 10000000 if cap is not None else 0
        st = seeded(p["seed"])
        # t28 and d28 as the two halves of one array: on a Pico every large
        # allocation scans the heap (~1.4 ms each for 1.5 KB), so one, not two
        both = memoryview(_ints(2 * count))
        self.t28 = both[:count]
        self.d28 = both[count:]
        self.y = _ints(count) if keep_y else None      # log2 pitch, Q24 octaves
        self.z = _ints(count) if keep_z else None      # the draws, Q24
        # the lower bound needs the log pitches (then dropped if not kept)
        bound = p.get("min_cpmm") is not None
        ys = _ints(count) if bound and not keep_y else self.y
        fill = texels_for(engine)
        self.above_nyquist = fill(st, count, L, self.mu, self.sigma, self.q, self.dcap,
                                  tab, self.t28, self.d28, _ONE if ys is None else ys,
                                  self.z if keep_z else _ONE,
                                  (1 if keep_z else 0) | (0 if ys is None else 2))
        self.x0 = (st[8], st[9])        # the start phase's draw
        if _params.has_options(p):
            # seed 001's options (gen/options.py: loaded only for them)
            from .options import apply_int
            apply_int(self, ys, tab, engine)
        self._f = None
        self._phi = None

    def fraction_above_nyquist(self):
        return self.above_nyquist / self.count

    # --- float views (the float engines and analysis; never on the play path)

    @property
    def u(self):
        return uniform_of(self.x0[0], self.x0[1])

    @property
    def f(self):
        """Pitch of each texel in c/mm: 2^(y / 2^24), at most the band limit."""
        if self._f is None:
            from ..compat import float_buffer
            f = float_buffer(self.count)
            cap = self.cap_mc / 1000.0 if self.params["band_limit_cpmm"] is not None else None
            mn = self.min_mc / 1000.0           # 0: no lower bound
            for i in range(self.count):
                v = 2.0 ** (self.y[i] / 16777216.0)
                if cap is not None and v > cap:
                    v = cap
                elif v < mn:
                    v = mn                      # a texel at the bound
                f[i] = v
            self._f = f
        return self._f

    @property
    def phi(self):
        """Start phase of each texel in rad, unwrapped, accumulated in the
        interpreter's float from the exact pitches (what a float rendering of
        the same draws plays)."""
        if self._phi is None:
            import math
            from ..compat import float_buffer
            f = self.f
            phi = float_buffer(self.count)
            step = 2 * math.pi * _params.DX_MM * self.L
            ph = 2 * math.pi * self.u
            run = self.params.get("phase", "continuous") != "reset"
            for i in range(self.count):
                phi[i] = ph
                if run:                         # "reset": every texel at the start phase
                    ph = ph + step * f[i]
            self._phi = phi
        return self._phi

    def pitches_db(self):
        import math
        return [10.0 * math.log10(x) for x in self.f]
