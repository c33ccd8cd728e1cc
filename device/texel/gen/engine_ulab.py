# ulab engine: vectorised float32 (ulab's float on boards). Uses only calls
# every ulab 6.x has, as its source defines them (v923z/micropython-ulab,
# code/numpy/numpy.c, code/ndarray.c, code/numpy/create.c):
#   arange(a, b, dtype=float)  float values (int args alone would give int16)
#   view[:m] * scalar          new float array (the scalar becomes float32)
#   a += scalar, a *= scalar   in place, keeps a's dtype
#   sin(a)                     new float array; no out= (6.2+ and optional)
#   out[i:j] = a               converted to out's dtype on assignment
# Not used because ulab lacks them or not every 6.x has them: cumsum, repeat,
# searchsorted, int32/float64, `%` on arrays (6.9+), .ndim (6.8+).
#
# Phase: samples are made in chunks of at most 64 whose phase comes from the
# fixed-point plan (plan.t28 / plan.d28 in 2^-28 turns, exact integers), so
# float32 never sees a large phase whatever the texel or map length. Inside a
# chunk the argument is j*w + phi_c, centred on the chunk's 32nd sample:
# j = -31..32 and w, phi_c wrapped to [-pi, pi), so |arg| <= 33*pi (104 rad)
# where a float32 ulp is 7.6e-6 rad: a few ulps is ~0.03 PWM step.
#
# uint16 output: ulab converts float -> integer with (int32_t)round(f), half
# away from zero, then wraps into 16 bits (ndarray_copy_view_convert_type).
# So the engine hands it gain*32767.5*(y+1) in [0, 65535] and lets it round;
# adding 0.5 and expecting truncation (numpy's astype) would be off by one
# half the time, and a sample at y = +1.0 (float32 sin gives exactly 1.0
# within 2.4e-4 rad of the peak) would become 65536 -> 0: no friction
# reduction at a crest.
#
# Allocation: the output (4 B/sample float, or 2 B/sample uint16 for
# render_u16) plus per chunk three short-lived arrays of <= 64 floats (the
# argument, the sine, ulab's converted copy on slice assignment).
import math
from ..compat import ulab_numpy, const

NAME = "ulab"
PRECISION = "ulab float (float32 on boards; float64 on a double-precision build)"
CHUNK = 64
_CENTRE = const(32)               # phase reference: the chunk's 32nd sample
_MASK = const(0x0FFFFFFF)         # one turn in 2^-28 units
_HALF = const(0x08000000)         # half a turn
_RAD_PER_UNIT = 2 * math.pi / (1 << 28)


def available():
    return ulab_numpy() is not None


def _signed(x):
    # a phase in [0, 2^28) as the same angle in [-2^27, 2^27): |angle| <= pi
    return x - (1 << 28) if x >= _HALF else x


def _chunks(plan, np, emit):
    n, L = plan.n, plan.L
    # offsets from the chunk's centre sample: -31 .. 32 (float: exact ints)
    kf = np.arange(1 - _CENTRE, CHUNK + 1 - _CENTRE, dtype=np.float)
    k = _RAD_PER_UNIT
    for i in range(plan.count):
        a = i * L
        b = a + L
        if b > n:
            b = n
        t = plan.t28[i]               # phase before the texel's first sample
        d = plan.d28[i]               # phase step per sample
        # all below are small ints (< 2^30) on every port: no bigints
        step = (d & 0x3FFFFF) << 6    # 64*d mod 2^28
        half = (d & 0x7FFFFF) << 5    # 32*d mod 2^28
        w = _signed(d) * k            # rad per sample, |w| <= pi
        while a < b:
            m = b - a
            if m > CHUNK:
                m = CHUNK
            # full chunks use kf itself: no view object to allocate
            seg = (kf if m == CHUNK else kf[:m]) * w
            seg += _signed((t + half) & _MASK) * k
            emit(a, a + m, np.sin(seg))
            t = (t + step) & _MASK
            a += m


def render(plan):
    np = ulab_numpy()
    out = np.zeros(plan.n, dtype=np.float)
    hg = 0.5 * plan.gain

    def emit(a, b, s):
        s += 1.0
        s *= hg
        out[a:b] = s
    _chunks(plan, np, emit)
    return out


def render_u16(plan, out=None):
    """uint16 map; out: a ulab uint16 array or any writable buffer of >= n
    uint16 (array('H'), bytearray): ulab's frombuffer shares its memory."""
    np = ulab_numpy()
    if out is None:
        out = np.zeros(plan.n, dtype=np.uint16)
    elif not isinstance(out, np.ndarray):
        out = np.frombuffer(out, dtype=np.uint16)
    elif out.dtype != np.uint16:
        raise ValueError("render_u16: out must be uint16, got dtype %r" % (out.dtype,))
    if len(out) < plan.n:
        raise ValueError("render_u16: out holds %d samples, the map has %d" % (len(out), plan.n))
    scale = 32767.5 * plan.gain

    def emit(a, b, s):
        # scale*(s+1) in [0, 65535]: the assignment rounds half away from zero
        s *= scale
        s += scale
        out[a:b] = s
    _chunks(plan, np, emit)
    return out
