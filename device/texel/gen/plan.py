# The per-texel plan: pitch f_i and start phase phi_i of every texel.
#
# Float part: exactly the lab's buildFine5.m, operation for operation, so that
# with the same draws the float64 path reproduces the original to < 1e-9:
#   pull   = log10(P) + sigma * z_i
#   pull   = q * round(pull / q)          (q > 0; round half away from zero)
#   f_i    = 10 ^ pull                    (cycles/mm)
#   phi_1  = 2*pi * u
#   phi_i  = 2*pi*f_{i-1}*0.0053*L + phi_{i-1}     (never wrapped)
#
# Fixed-point part, for the device engines: phases in 2^-28 turns (mod 1 turn)
#   t28_i  start phase of texel i       d28_i  phase step per sample
# built by integer accumulation (t28_{i+1} = t28_i + frac(L*f_i*dx)), so the
# per-texel start phase does not degrade with map length even where floats
# are float32: the only float work per texel is f_i and two fractions of it.
import math
from array import array      # at the top: an extensible built-in imported inside a function
#                              walks sys.path each time (1.64 ms on the emulated RP2040)
from . import params as _params
from .rng import Rng, phase_fraction_u28, uniform_of
from ..compat import float_buffer

UNITS_PER_TURN = 1 << 28        # fixed-point phase: 2^28 per turn
PHASE_MASK = UNITS_PER_TURN - 1
_TWO_PI = 2 * math.pi
_DX = _params.DX_MM


def round_half_away(x):
    """MATLAB round(): halves go away from zero (Python's round() is banker's)."""
    a = -x if x < 0 else x
    t = math.floor(a)
    if a - t >= 0.5:
        t += 1.0
    return -t if x < 0 else t


def _frac_u28(x):
    """frac(x) of a non-negative float as an int in [0, 2^28)."""
    x = x - math.floor(x)
    return int(x * UNITS_PER_TURN + 0.5) & PHASE_MASK


class Plan:
    """Per-texel pitches and phases of one parameter set."""

    # seed 001's lower bound (gen/options.py sets them when it applies):
    # texels redrawn, texels left at the bound
    redrawn = 0
    at_min = 0

    def __init__(self, p, draws=None, ftype=float):
        # ftype: the float type of the plan arithmetic. Python float is the
        # interpreter's own (float32 on boards); tests pass numpy.float32 on
        # CPython to run this exact code the way a float32 board does.
        self.params = p
        self.n = p["length_samples"]
        self.L = p["texel_samples"]
        self.count = _params.texel_count(p)
        self.gain = p["gain"]
        F = ftype
        mu = F(p["pitch_db"]) / 10.0                     # log10 of P in c/mm
        sigma = 10.0 ** (F(p["irregularity_db"]) / 10.0)  # decades
        q = F(p["quant_db"]) / 10.0                      # decades, 0 = off
        cap = p["band_limit_cpmm"]
        if cap is not None:
            cap = F(cap)
        count = self.count
        if draws is None:
            rng = Rng(p["seed"], F)
            hi, lo = rng.next_hi_lo()
            u = uniform_of(hi, lo, F)
            t28 = phase_fraction_u28(hi, lo)
            draw_z = rng.normal
        else:
            u, zs = _check_draws(draws, count)
            u = F(u)
            zs = [F(z) for z in zs]
            t28 = _frac_u28(u)
            draw_z = iter(zs).__next__
        self.u = u
        self.f = f = float_buffer(count)         # pitch, cycles/mm
        self.phi = phi = float_buffer(count)     # start phase, rad (unwrapped)
        self.t28 = ta = _int_buffer(count)       # start phase, 2^-28 turns
        self.d28 = da = _int_buffer(count)       # step per sample, 2^-28 turns
        L = self.L
        Lf = F(L)
        phase = u * _TWO_PI     # MATLAB: rand()*2*pi()
        above = 0
        fprev = 0.0
        for i in range(count):
            pull = mu + sigma * draw_z()
            if q > 0.0:
                pull = q * round_half_away(pull / q)
            fi = 10.0 ** pull
            if cap is not None and fi > cap:
                fi = cap
            if fi > _params.NYQUIST_CPMM:
                above += 1
            if i > 0:
                phase = _TWO_PI * fprev * _DX * Lf + phase
            f[i] = fi
            phi[i] = phase
            fprev = fi
            # fixed point: step per sample and start of the next texel
            step = fi * _DX
            step = step - math.floor(step)
            da[i] = int(step * UNITS_PER_TURN + 0.5) & PHASE_MASK
            ta[i] = t28
            t28 = (t28 + _frac_u28(step * Lf)) & PHASE_MASK
        self.above_nyquist = above
        if _params.has_options(p):
            # seed 001's options (gen/options.py: loaded only for them)
            from .options import apply_float
            apply_float(self, F)

    def fraction_above_nyquist(self):
        return self.above_nyquist / self.count

    def pitches_db(self):
        return [10.0 * math.log10(x) for x in self.f]


def _int_buffer(n):
    return array("i", bytes(4 * n))


# Largest |z| a replayed draw may have (draws=(u, z_sequence), e.g. the lab's
# logged MATLAB randn draws: |z| <= 4.6 in ../shared/golden). A standard
# normal draw beyond 10 has probability 1.5e-23 (the seeded generator's own
# draws stay within 6.4: u >= 2^-33), so no real log is refused. Without a
# bound a finite z broke the plan: pull = mu + sigma*z with sigma up to 3.16
# decades made 10**pull overflow (z = 100: OverflowError on CPython, inf and
# then "can't convert inf to int" on MicroPython), underflow to a pitch of 0
# (z = -1e300: pitches_db() raised "math domain error") or leave float32
# (z = 12: OverflowError on a board; z = -13: a subnormal pitch). With
# |z| <= 10 every pitch is within 10^+-34.6 c/mm (quantization included):
# finite and normal in float32 as in float64, and so are t28/d28. (Only phi,
# the unwrapped float phase the float64 reference engine reads, can pass
# float32's range on a board, for a metre-long map of such draws; board
# engines never read it.)
Z_MAX = 10.0


def _shown(v):
    """A bounded description of a draw for a message."""
    if isinstance(v, float) or (isinstance(v, int) and -(1 << 62) < v < (1 << 62)):
        return repr(v)
    if isinstance(v, int):
        return "a huge int (beyond 2^62)"
    return type(v).__name__


def _check_draws(draws, count):
    try:
        u, zs = draws
    except (TypeError, ValueError):
        raise ValueError("draws: expected (u, z_sequence)")
    if isinstance(u, bool) or not isinstance(u, (int, float)) or not (0.0 <= u <= 1.0):
        raise ValueError("draws: u must be a number in [0, 1], got %s" % _shown(u))
    try:
        m = len(zs)
    except TypeError:
        raise ValueError("draws: z_sequence must be a sequence")
    if m < count:
        raise ValueError("draws: %d z values given, the map needs %d texels" % (m, count))
    # Only the first `count` values are used (and checked); each must be a
    # real number (float() of it: numpy scalars too, never str/bytes, bool or
    # complex - complex and None raised TypeError in the plan) in
    # [-Z_MAX, Z_MAX].
    out = []
    for i in range(count):
        try:
            z = zs[i]
        except (TypeError, KeyError, IndexError):
            raise ValueError("draws: z_sequence must be an indexable sequence (list, tuple, array)")
        ok = not isinstance(z, (bool, str, bytes))
        if ok:
            try:
                f = float(z)
            except (TypeError, ValueError, OverflowError):
                ok = False
        if not ok or not (-Z_MAX <= f <= Z_MAX):       # also refuses nan
            if ok and not isinstance(z, (int, float)):
                z = f                                   # a numpy scalar: show its value
            raise ValueError("draws: z[%d] must be a finite number in [%r, %r], got %s"
                             % (i, -Z_MAX, Z_MAX, _shown(z)))
        out.append(f)
    return float(u), out
