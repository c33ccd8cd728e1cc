# numpy engine: float64, the reference. CPython only.
# Same operation order as buildFine5.m:  sin(2*pi*pitch*t + phase),
# pitch = f*0.0053, t = 1..L (1-based: the first sample is one step in).
# Whole arrays, no loop over texels: the map's whole texels as a (texels, L)
# view, each sample (2*pi*pitch_i) * t + phi_i - the same two float64
# roundings per sample as one texel at a time, so the same map bit for bit
# (tests/gen/test_plan_numpy.py) - then one sin over the map.
# Allocates the float64 map (8 bytes/sample) plus one texel of temporaries.
import math
from ..compat import numpy_mod as np

NAME = "numpy"
PRECISION = "float64"


def available():
    return np is not None


def _pitches_phases(plan):
    """The plan's pitches f (c/mm) and start phases phi (rad) as float64
    arrays. A format-2 plan's float views (PlanInt.f/.phi, Python loops)
    are made here with numpy from its log pitches, the same values bit for
    bit (gen/plan_numpy.int_pitches/int_phases)."""
    if getattr(plan, "FORMAT", 1) == 2 and plan.y is not None and plan._f is None:
        from .plan_numpy import int_pitches, int_phases
        f = int_pitches(plan)
        return f, int_phases(plan, f)
    return _f64(plan.f), _f64(plan.phi)


def _f64(a):
    if isinstance(a, np.ndarray):
        return a.astype(np.float64, copy=False)
    try:
        m = memoryview(a)
    except TypeError:
        return np.asarray(a, dtype=np.float64)
    if m.format == "d":
        return np.frombuffer(m, dtype=np.float64)       # array('d'): no copy
    return np.asarray(a, dtype=np.float64)


def render_y(plan):
    """The generator's raw output y in [-1, 1] (float64 array of plan.n)."""
    n, L = plan.n, plan.L
    f, phi = _pitches_phases(plan)
    k = (2 * math.pi) * (f * 0.0053)        # per texel: 2*pi*pitch, then * t
    y = np.empty(n, dtype=np.float64)
    t = np.arange(1, min(L, n) + 1, dtype=np.float64)
    whole = n // L                          # texels played in full
    if whole:
        Y = y[: whole * L].reshape(whole, L)
        np.multiply(k[:whole, None], t, out=Y)
        Y += phi[:whole, None]
    rest = n - whole * L                    # the last texel, cut short
    if rest:
        tail = y[whole * L:]
        np.multiply(k[whole], t[:rest], out=tail)
        tail += phi[whole]
    np.sin(y, out=y)
    return y


def render(plan):
    """Friction map gain*(y+1)/2 in [0, 1], float64."""
    y = render_y(plan)
    y += 1.0
    y *= 0.5 * plan.gain
    return y


def render_u16(plan, out=None):
    m = render(plan)
    m *= 65535.0
    m += 0.5
    np.floor(m, out=m)
    q = m.astype(np.uint16)
    if out is not None:
        # any writable uint16 buffer: ndarray, array('H') (buffer protocol)
        from ..compat import check_u16_out
        check_u16_out(out, plan.n)
        np.frombuffer(out, dtype=np.uint16)[: plan.n] = q
        return out
    return q
