# ulab engine: vectorised float32 (ulab's float on boards). Only functions
# and dtypes ulab 6.x has (SPEC §3): arange with a float dtype, scalar
# arithmetic, sin, slicing, and dtype conversion through np.array(..., dtype=).
# No cumsum/repeat/searchsorted, no int32/float64.
#
# Samples are made in chunks of at most 64 whose start phase comes from the
# fixed-point plan (exact integers), so the float32 phase inside a chunk never
# exceeds 64 turns: |error| <= 64 * 2^-24 turns ~ 2.4e-5 rad (0.05 PWM step)
# whatever the texel and map length.
# Allocation: the output (float32: 4 B/sample, or uint16: 2 B/sample for
# render_u16) plus ~3 chunk temporaries of 64 floats.
import math
from .compat import ulab_numpy

NAME = "ulab"
PRECISION = "float32"
CHUNK = 64
_TWO_PI = 2 * math.pi
_INV_UNITS = 1.0 / (1 << 28)


def available():
    return ulab_numpy() is not None


def _chunks(plan, np, emit):
    n, L = plan.n, plan.L
    kf = np.arange(1, CHUNK + 1, dtype=np.float)
    for i in range(plan.count):
        a = i * L
        b = a + L
        if b > n:
            b = n
        t = plan.t28[i]
        d = plan.d28[i]
        step = (d & 0x3FFFFF) << 6          # (64*d) mod 2^28 without bigints
        w = _TWO_PI * (d * _INV_UNITS)      # rad per sample, reduced
        while a < b:
            m = b - a
            if m > CHUNK:
                m = CHUNK
            seg = kf[:m] * w
            seg += _TWO_PI * (t * _INV_UNITS)
            emit(a, a + m, np.sin(seg))
            t = (t + step) & 0x0FFFFFFF
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
    np = ulab_numpy()
    if out is None:
        out = np.zeros(plan.n, dtype=np.uint16)
    scale = 32767.5 * plan.gain

    def emit(a, b, s):
        s *= scale
        s += scale + 0.5                     # then truncate: round half up
        out[a:b] = np.array(s, dtype=np.uint16)
    _chunks(plan, np, emit)
    return out
