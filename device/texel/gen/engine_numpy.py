# numpy engine: float64, the reference. CPython only.
# Same operation order as buildFine5.m:  sin(2*pi*pitch*t + phase),
# pitch = f*0.0053, t = 1..L (1-based: the first sample is one step in).
# Allocates the float64 map (8 bytes/sample) plus one texel of temporaries.
import math
from ..compat import numpy_mod as np

NAME = "numpy"
AVAILABLE = np is not None
PRECISION = "float64"


def render_y(plan):
    """The generator's raw output y in [-1, 1] (float64 array of plan.n)."""
    n, L = plan.n, plan.L
    y = np.empty(n, dtype=np.float64)
    t = np.arange(1, L + 1, dtype=np.float64)
    two_pi = 2 * math.pi
    for i in range(plan.count):
        a = i * L
        b = min(a + L, n)
        pitch = plan.f[i] * 0.0053
        y[a:b] = np.sin(two_pi * pitch * t[: b - a] + plan.phi[i])
    return y


def render(plan):
    """Friction map gain*(y+1)/2 in [0, 1], float64."""
    y = render_y(plan)
    y += 1.0
    y *= 0.5 * plan.gain
    return y


def render_u16(plan, out=None):
    m = render(plan)
    q = np.floor(m * 65535.0 + 0.5).astype(np.uint16)
    if out is not None:
        # any writable uint16 buffer: ndarray, array('H') (buffer protocol)
        from ..compat import check_u16_out
        check_u16_out(out, plan.n)
        np.frombuffer(out, dtype=np.uint16)[: plan.n] = q
        return out
    return q
