# texel: the Single-Pitch Texel generator, one code base for CPython (numpy),
# MicroPython (with or without ulab) and CircuitPython.
#
#   texel.render(params, draws=None, engine=None)  -> friction map in [0, 1]
#   texel.render_u16(params, ...)                   -> uint16 map (0..65535)
#   texel.make_plan(params, draws=None)             -> per-texel pitches/phases
#   texel.engines()                                 -> engines usable here
#   texel.reference(name, length_samples)           -> reference textures
from .gen.params import validate, FORMAT_VERSION, FORMAT_LATEST, DX_MM, NYQUIST_CPMM  # noqa: F401 (the API above)
from . import compat

__version__ = "0.2.0"

_ENGINE_ORDER = ("numpy", "int", "ulab", "pure")


def _engine_module(name):
    """The engine's module where it runs (its available()), else None. The
    numpy engine is not imported without numpy: boards do not carry it
    (host/texelpad/deploy/image.py, HOST_ONLY)."""
    if name == "numpy":
        if compat.numpy_mod is None:
            return None
        from .gen import engine_numpy as m
    elif name == "ulab":
        from .gen import engine_ulab as m
    elif name == "int":
        from .gen import engine_int as m
    elif name == "pure":
        from .gen import engine_pure as m
    else:
        raise ValueError("engine: unknown engine %r (known: %s)"
                         % (name, ", ".join(_ENGINE_ORDER)))
    return m if m.available() else None


def engines():
    """Names of the engines usable on this interpreter, preferred first:
    numpy (CPython float64 reference), int (fixed point, viper where the port
    has it), ulab (float32 vectors), pure (interpreter floats)."""
    return [n for n in _ENGINE_ORDER if _engine_module(n) is not None]


def default_engine():
    return engines()[0]


def _engine(engine):
    if engine is None:
        engine = default_engine()
    m = _engine_module(engine)
    if m is None:
        raise ValueError("engine: %r is not available on %s (available: %s)"
                         % (engine, compat.IMPL, ", ".join(engines())))
    return m


def make_plan(params, draws=None):
    """Validate params and compute the per-texel plan (pitches f in cycles/mm,
    start phases phi in rad, fixed-point t28/d28, fraction above Nyquist):
    format 2 (gen/plan_int.py, integer, the same bits on every runtime) or,
    for "v": 1, format 1 (gen/plan.py, the lab's float plan). draws replays
    the lab's logged float draws: format 1 only."""
    p = validate(params)
    if compat.numpy_mod is not None and compat.IMPL == "cpython":
        # CPython: the same plan bit for bit, built with numpy (gen/plan_numpy.py,
        # docs/generator.md; the loops below 48 texels). Boards never come here:
        # they have no numpy (ulab's is ulab.numpy, never compat.numpy_mod), and
        # plan_numpy is a host-only module.
        from .gen.plan_numpy import make_plan as _make_plan
        return _make_plan(p, draws)
    if p["v"] == 2:
        if draws is not None:
            raise ValueError("draws: replaying logged draws is format 1's (v=1); "
                             "format 2 draws from its seed")
        from .gen.plan_int import PlanInt
        return PlanInt(p)
    # imported here, not at the top: a board playing format 2 never loads the
    # float plan (on a stock Pico a .mpy is copied into RAM, and its load is
    # part of main.py's power-up)
    from .gen.plan import Plan
    return Plan(p, draws)


def render(params, draws=None, engine=None):
    """The friction map gain*(y+1)/2, length_samples long, values in [0, 1].

    draws=(u, z_sequence) replays logged random draws instead of the seeded
    generator. The container is the engine's: numpy float64 array (numpy),
    ulab float array (ulab), array of floats (int, pure)."""
    m = _engine(engine)
    return m.render(make_plan(params, draws))


def render_u16(params, draws=None, engine=None, out=None):
    """The map as uint16, 0..65535 = friction 0..1 (2 bytes/sample)."""
    m = _engine(engine)
    return m.render_u16(make_plan(params, draws), out)


def reference(name, length_samples=9600):
    """A reference texture as a float map in [0, 1]: the matching study's nine
    (2sin 3sin 4sin white pink blue square triangle sawtooth) and the earlier
    paper's band-pass family (bp-<fc>-<zeta>); see gen/reference.py."""
    from .gen.reference import reference as _ref
    return _ref(name, length_samples)


def reference_u16(name, length_samples=9600, out=None):
    """The same as uint16 (0..65535), 2 bytes/sample."""
    from .gen.reference import reference_u16 as _ref
    return _ref(name, length_samples, out)


def reference_names():
    from .gen.reference import names
    return names()
