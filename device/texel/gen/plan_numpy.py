# The texel plan in numpy: CPython only (texel.compat.numpy_mod). The same
# plans as gen/plan.py's Plan (format 1) and gen/plan_int.py's PlanInt
# (format 2), bit for bit - the same draws, pitches, phases, t28/d28 and
# count above Nyquist (tests/gen/test_plan_numpy.py) - with the per-texel
# work done on whole arrays instead of in an interpreter loop:
#   the draws     xoshiro128++ is a recurrence: one tight loop over 32-bit
#                 Python ints (gen/rng.py holds it as 16-bit halves for
#                 MicroPython's small ints; the outputs are the same)
#   format 1      AS241 (rng.ppnd16, det_log) on every draw at once, the same
#                 operations in the same order; 10 ** pull element by element
#                 with Python's own pow (numpy's power is not libm's pow to the
#                 last bit on every CPU: SVML on AVX-512); the unwrapped phases
#                 by add.accumulate (a left fold: the same sums as the loop)
#   format 2      the integer steps of plan_int.texels_py on int64 arrays
#                 (every intermediate < 2^58); the phase advance's carries as
#                 cumulative sums
#   options       seed 001's lower bound and phase reset (params "min_cpmm",
#                 "phase") are the scalar plans' own post-pass
#                 (gen/options.py: apply_float, apply_int) run on the arrays
#                 made here: the same plan bit for bit (a redraw is a
#                 sequential second stream, tried texel by texel)
# Board code never imports this module (nothing on a board has numpy); it
# stays importable there (numpy comes through compat) as engine_numpy does.
import math
from array import array
from . import params as _params
from .plan import Plan, UNITS_PER_TURN, PHASE_MASK, _TWO_PI, _DX, _check_draws, _frac_u28
from .plan_int import PlanInt, exp2_q24, _round_q, LOG2_LOG2_10, LOG2_STEP0, \
    Y_LO, Y_HI, NYQ_EXP, MASK28, NORM, table, mul28, exp2_m
from .options import apply_float, apply_int
from .grid import mdb
from .rng import WARMUP, SEED_CONSTS, uniform_of, phase_fraction_u28, \
    _A, _B, _C, _D, _E, _F, _INV_ODD, _LN2, _SQRT_HALF, \
    _ratio                          # only * + /: the same Horner steps on arrays
from ..compat import numpy_mod as np

AVAILABLE = np is not None
_M32 = 0xFFFFFFFF


def outputs(seed, count):
    """The texture generator's 32-bit outputs after its warm-up: the start
    phase's draw, then one per texel (count + 1 values, int64; gen/rng.py's
    stream). The loop keeps only the state's first word a: since
    a' = a ^ d ^ b and d' = rotl(d ^ b, 11), each later d is
    rotl(a ^ a', 11), and the outputs rotl(a + d, 7) + a follow on arrays."""
    M = _M32
    a = seed & M
    b = (SEED_CONSTS[0][0] << 16) | SEED_CONSTS[0][1]
    c = (SEED_CONSTS[1][0] << 16) | SEED_CONSTS[1][1]
    d = (SEED_CONSTS[2][0] << 16) | SEED_CONSTS[2][1]
    for _ in range(WARMUP):
        t = (b << 9) & M
        c ^= a
        d ^= b
        b ^= c
        a ^= d
        c ^= t
        d = ((d << 11) & M) | (d >> 21)
    d0 = d
    seq = [a]
    keep = seq.append
    for _ in range(count):
        t = (b << 9) & M
        c ^= a
        d ^= b
        b ^= c
        a ^= d
        c ^= t
        d = ((d << 11) & M) | (d >> 21)
        keep(a)
    a = np.array(seq, dtype=np.int64)
    d = np.empty(count + 1, dtype=np.int64)
    d[0] = d0
    e = a[:-1] ^ a[1:]
    d[1:] = ((e << 11) & M) | (e >> 21)
    r = (a + d) & M
    return ((((r << 7) | (r >> 25)) & M) + a) & M


# --- format 1 -----------------------------------------------------------------

def _det_log(x):
    """rng.det_log of every element (x > 0)."""
    m, e = np.frexp(x)
    low = m < _SQRT_HALF
    m = np.where(low, m * 2.0, m)
    e = np.where(low, e - 1, e)
    s = (m - 1.0) / (m + 1.0)
    s2 = s * s
    acc = _INV_ODD[11]
    for i in range(10, -1, -1):
        acc = acc * s2 + _INV_ODD[i]
    return e * _LN2 + 2.0 * s * acc


def normals(x):
    """rng.Rng.normal of every 32-bit output in x (int64 array): AS241 of
    u = (x + 0.5)/2^32 with the upper tail from 1 - u = ((2^32-1-x) + 0.5)/2^32,
    both exact in binary64 as uniform_of makes them."""
    u = (x + 0.5) / 4294967296.0
    uc = ((_M32 - x) + 0.5) / 4294967296.0
    q = u - 0.5
    z = np.empty(x.shape, dtype=np.float64)
    mid = (q >= -0.425) & (q <= 0.425)
    if mid.any():
        qm = q[mid]
        z[mid] = qm * _ratio(_A, _B, 0.180625 - qm * qm)
    tail = ~mid
    if tail.any():
        qt = q[tail]
        r = np.sqrt(-_det_log(np.where(qt < 0.0, u[tail], uc[tail])))
        near = r <= 5.0
        v = np.empty(r.shape, dtype=np.float64)
        if near.any():
            v[near] = _ratio(_C, _D, r[near] - 1.6)
        if not near.all():
            far = ~near
            v[far] = _ratio(_E, _F, r[far] - 5.0)
        z[tail] = np.where(qt < 0.0, -v, v)
    return z


def _round_half_away(x):
    """plan.round_half_away of every element."""
    a = np.where(x < 0, -x, x)
    t = np.floor(a)
    t = np.where(a - t >= 0.5, t + 1.0, t)
    return np.where(x < 0, -t, t)


def _frac_u28_all(x):
    """plan._frac_u28 of every element (x >= 0), as int64."""
    x = x - np.floor(x)
    return np.floor(x * UNITS_PER_TURN + 0.5).astype(np.int64) & PHASE_MASK


def _floats(a):
    """float64 array -> array('d') (what compat.float_buffer is on CPython)."""
    return array("d", np.ascontiguousarray(a, dtype=np.float64).tobytes())


def _int32s(a):
    return array("i", np.ascontiguousarray(a, dtype=np.int32).tobytes())


class PlanNumpy(Plan):
    """gen/plan.py's Plan of a validated format-1 set, built with numpy: the
    same attributes (f, phi array('d'); t28, d28 array('i'); u,
    above_nyquist), bit for bit. Python floats only (no ftype)."""

    def __init__(self, p, draws=None):
        self.params = p
        self.n = p["length_samples"]
        self.L = L = p["texel_samples"]
        self.count = count = _params.texel_count(p)
        self.gain = p["gain"]
        mu = float(p["pitch_db"]) / 10.0
        sigma = 10.0 ** (float(p["irregularity_db"]) / 10.0)
        q = float(p["quant_db"]) / 10.0
        cap = p["band_limit_cpmm"]
        if draws is None:
            xs = outputs(p["seed"], count)
            x0 = int(xs[0])
            hi, lo = x0 >> 16, x0 & 0xFFFF
            u = uniform_of(hi, lo)
            t0 = phase_fraction_u28(hi, lo)
            z = normals(xs[1:])
        else:
            u, zs = _check_draws(draws, count)
            u = float(u)
            t0 = _frac_u28(u)
            z = np.array(zs, dtype=np.float64)
        self.u = u
        pull = mu + sigma * z
        if q > 0.0:
            pull = q * _round_half_away(pull / q)
        # 10.0 ** pull as the loop computes it: CPython's float pow (libm pow)
        f = np.array([10.0 ** v for v in pull.tolist()], dtype=np.float64)
        if cap is not None:
            cap = float(cap)
            f = np.where(f > cap, cap, f)
        self.above_nyquist = int(np.count_nonzero(f > _params.NYQUIST_CPMM))
        Lf = float(L)
        # phi[i] = 2*pi*f[i-1]*DX*L + phi[i-1], from phi[0] = 2*pi*u
        inc = np.empty(count, dtype=np.float64)
        inc[0] = u * _TWO_PI
        inc[1:] = _TWO_PI * f[:-1] * _DX * Lf
        phi = np.add.accumulate(inc)
        step = f * _DX
        step = step - np.floor(step)
        d28 = np.floor(step * UNITS_PER_TURN + 0.5).astype(np.int64) & PHASE_MASK
        # t28[i+1] = t28[i] + frac_u28(step[i] * L) mod 2^28 (sums < 2^48)
        adv = np.empty(count, dtype=np.int64)
        adv[0] = t0
        adv[1:] = _frac_u28_all(step[:-1] * Lf)
        t28 = np.cumsum(adv) & PHASE_MASK
        self.f = _floats(f)
        self.phi = _floats(phi)
        self.t28 = _int32s(t28)
        self.d28 = _int32s(d28)
        if _params.has_options(p):
            apply_float(self)


# --- format 2 -----------------------------------------------------------------

_tab64 = None


def _tab():
    """plan_int_tables.table() as an int64 array (cached)."""
    global _tab64
    if _tab64 is None:
        _tab64 = np.array(table(), dtype=np.int64)
    return _tab64


# plan_int's mul28 and exp2_m use only >>, &, *, + and table lookups: on int64
# arrays (and a table as an int64 array) they are the same limbs, the same rounding
_mul28 = mul28
_exp2_m = exp2_m


def norm_q24(x, tab):
    """plan_int.norm_q24 of every 32-bit output in x (int64 array)."""
    upper = x >= 0x80000000
    v = np.where(upper, _M32 - x, x)
    w = 2 * v + 1                               # in [1, 2^32): exact in float64
    e = np.frexp(w.astype(np.float64))[1].astype(np.int64) - 1     # its octave
    top = ((w << 16) >> e) & 0xFFFF             # the 16 bits below its leading one
    i = NORM + (e << 5) + (top >> 11)
    t0 = tab[i]
    a = t0 + (((tab[i + 1] - t0) * (top & 0x7FF) + 1024) >> 11)
    return np.where(upper, a, -a)


def step_d(y, tab):
    """plan_int.step_d of every log pitch y: (d, a, af, e) as int64 arrays."""
    w = y + LOG2_STEP0
    e = w >> 24
    m = _exp2_m(w & 0xFFFFFF, tab)
    # e in [-2, 35] for y in [Y_LO, Y_HI]; every shift below is kept in range
    # on the elements whose branch does not use it (np.where picks)
    big = e >= 28                   # a turn or more per sample
    k = np.clip(e - 28, 0, 27)
    d_big = (m & (MASK28 >> k)) << k
    mid = (e >= 20) & ~big
    ec = np.clip(e, -2, 27)
    d = (m + (1 << (27 - ec))) >> (28 - ec)
    km = np.clip(e - 20, 0, 7)
    a_mid = m >> (28 - ec)
    af_mid = (m & (0xFF >> km)) << km
    xs = (m + (1 << np.clip(19 - ec, 0, 62))) >> np.clip(20 - ec, 0, 62)
    a = np.where(big, d_big, np.where(mid, a_mid, xs >> 8))
    af = np.where(big, 0, np.where(mid, af_mid, xs & 0xFF))
    d = np.where(big, d_big, d)
    gone = e < -2                   # below the clamp: never, kept as the loop has it
    if gone.any():
        d = np.where(gone, 0, d)
        a = np.where(gone, 0, a)
        af = np.where(gone, 0, af)
    return d, a, af, e


class PlanIntNumpy(PlanInt):
    """gen/plan_int.py's PlanInt of a validated format-2 set, built with
    numpy: the same attributes (t28/d28 as halves of one array('i'), y and z
    array('i'), x0, above_nyquist) and float views f/phi, bit for bit."""

    def __init__(self, p, keep_z=False, keep_y=True):
        self.params = p
        self.n = p["length_samples"]
        self.L = L = p["texel_samples"]
        self.count = count = _params.texel_count(p)
        self.gain = p["gain"]
        T = _tab()
        self.mu = mu = _round_q(mdb(p["pitch_db"]))
        self.sigma = sigma = exp2_q24(LOG2_LOG2_10 + _round_q(mdb(p["irregularity_db"])),
                                      table())
        self.q = q = _round_q(mdb(p["quant_db"])) if p["quant_db"] else 0
        cap = p["band_limit_cpmm"]
        self.cap_mc = mdb(cap) if cap is not None else 0
        self.dcap = dcap = ((self.cap_mc * 53 * (1 << 28) + 5000000) // 10000000
                            if cap is not None else 0)
        xs = outputs(p["seed"], count)
        x0 = int(xs[0])
        self.x0 = (x0 >> 16, x0 & 0xFFFF)              # the start phase's draw
        t0 = phase_fraction_u28(x0 >> 16, x0 & 0xFFFF)
        z = norm_q24(xs[1:], T)
        # y = mu + round(sigma * z / 2^24), half away from zero (texels_py's limbs)
        za = np.abs(z)
        s1 = sigma >> 14
        s0 = sigma & 0x3FFF
        z1 = za >> 14
        z0 = za & 0x3FFF
        m = s1 * z0 + s0 * z1 + ((s0 * z0 + 0x800000) >> 14)
        pz = ((s1 * z1) << 4) + (m >> 10)
        y = np.where(z < 0, mu - pz, mu + pz)
        y = np.clip(y, Y_LO, Y_HI)
        if q:
            n = (2 * np.abs(y) + q) // (2 * q)
            y = np.where(y < 0, -n * q, n * q)
        d, a, af, e = step_d(y, T)
        self.above_nyquist = int(np.count_nonzero(e >= NYQ_EXP))
        if dcap:
            over = (e >= 28) | (d > dcap)
            d = np.where(over, dcap, d)
            a = np.where(over, dcap, a)
            af = np.where(over, 0, af)
        d &= MASK28
        # t[i+1] = t[i] + (L * a[i]) mod 2^28 + the carries of tf, the 1/256
        # units: tf after texel i is S_i mod 256 with S_i = the sum of
        # L * af[j <= i], so the carries up to i add to S_i >> 8. (L * a) mod
        # 2^28 is plan_int.mulmod28(L, a): L < 2^21 and a < 2^28 (its limbs
        # are exact there); the sums stay below 2^49.
        t = np.empty(count, dtype=np.int64)
        t[0] = t0
        if count > 1:
            t[1:] = t0 + np.cumsum((L * a[:-1]) & MASK28) + (np.cumsum(L * af[:-1]) >> 8)
        t &= MASK28
        # t28 and d28 as the two halves of one array, as PlanInt holds them
        both = memoryview(_int32s(np.concatenate((t, d))))
        self.t28 = both[:count]
        self.d28 = both[count:]
        ys = _int32s(y) if keep_y or p.get("min_cpmm") is not None else None
        self.y = ys if keep_y else None
        self.z = _int32s(z) if keep_z else None
        self._f = None
        self._phi = None
        if _params.has_options(p):
            apply_int(self, ys, table())

    @property
    def f(self):
        if self._f is None:
            self._f = _floats(int_pitches(self))
        return self._f

    @property
    def phi(self):
        if self._phi is None:
            self._phi = _floats(int_phases(self, np.frombuffer(self.f, dtype=np.float64)))
        return self._phi


def int_pitches(plan):
    """PlanInt.f of a format-2 plan from its log pitches y, as a float64
    array: 2.0 ** (y / 2^24) with Python's pow element by element (as the
    property), capped at the band limit."""
    y = np.frombuffer(plan.y, dtype=np.int32) / 16777216.0
    f = np.array([2.0 ** v for v in y.tolist()], dtype=np.float64)
    if plan.params["band_limit_cpmm"] is not None:
        cap = plan.cap_mc / 1000.0
        f = np.where(f > cap, cap, f)
    if plan.min_mc:
        mn = plan.min_mc / 1000.0                   # a texel at the lower bound
        f = np.where(f < mn, mn, f)
    return f


def int_phases(plan, f):
    """PlanInt.phi from its pitches f (float64 array): ph[0] = 2*pi*u,
    ph[i+1] = ph[i] + (2*pi*DX*L) * f[i], the same left fold (every texel
    at ph[0] with "phase": "reset")."""
    if plan.params.get("phase", "continuous") == "reset":
        return np.full(plan.count, 2 * math.pi * plan.u, dtype=np.float64)
    step = 2 * math.pi * _params.DX_MM * plan.L
    inc = np.empty(plan.count, dtype=np.float64)
    inc[0] = 2 * math.pi * plan.u
    inc[1:] = step * f[:-1]
    return np.add.accumulate(inc)


# Below this many texels the loops are quicker: the arrays cost ~0.2 ms of
# numpy calls whatever their length, the loops ~5 us a texel (the crossover
# measured at 40-48 texels in both formats on CPython 3.11, numpy 2.4).
LOOP_BELOW = 48


def make_plan(p, draws=None):
    """texel.make_plan's plan of a VALIDATED parameter set, whichever way is
    quicker - the same plan either way: PlanIntNumpy (or, for fewer than
    LOOP_BELOW texels, PlanInt) for "v": 2, which replays no draws;
    PlanNumpy (or Plan) otherwise."""
    few = _params.texel_count(p) < LOOP_BELOW
    if p["v"] == 2:
        if draws is not None:
            raise ValueError("draws: replaying logged draws is format 1's (v=1); "
                             "format 2 draws from its seed")
        return PlanInt(p) if few else PlanIntNumpy(p)
    return Plan(p, draws) if few else PlanNumpy(p, draws)
