# Pure-Python float engine for stock firmware without ulab (and without a
# native emitter, e.g. CircuitPython). The phase of every sample comes from
# the same fixed-point plan as the integer engine (2^-28 turns), reduced to
# one turn before math.sin, so float32 boards never take the sine of a large
# argument (float32 ulp at 1e4 rad is 1e-3 rad, ~2 PWM steps).
# render() allocates the float map (4 bytes/sample on float32 boards);
# render_u16() converts sample by sample into a uint16 buffer instead.
import math
from ..compat import float_buffer, check_u16_out

NAME = "pure"
PRECISION = "interpreter float (float64 on CPython/unix, float32 on boards)"
_MASK = 0x0FFFFFFF
_RAD_PER_UNIT = 2 * math.pi / (1 << 28)


def available():
    return True                 # the interpreter's own floats: every runtime


def _each(plan, put):
    n, L = plan.n, plan.L
    half_gain = 0.5 * plan.gain
    sin = math.sin
    k = _RAD_PER_UNIT
    for i in range(plan.count):
        a = i * L
        b = a + L
        if b > n:
            b = n
        t = plan.t28[i]
        d = plan.d28[i]
        while a < b:
            t = (t + d) & _MASK
            put(a, (sin(t * k) + 1.0) * half_gain)
            a += 1


def render(plan):
    m = float_buffer(plan.n)

    def put(j, v):
        m[j] = v
    _each(plan, put)
    return m


def render_u16(plan, out=None):
    out = check_u16_out(out, plan.n)

    def put(j, v):
        out[j] = int(v * 65535.0 + 0.5)
    _each(plan, put)
    return out
