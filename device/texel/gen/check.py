# The checks the device's validators share: gen/params.py (texel parameters),
# gen/brush.py (brushes), runtime/scene.py (scenes) and runtime/boards.py
# (board files). Written once here, so every one of them words a number, a
# range and a key path alike, and a board holds the code once. In gen/ because
# gen never imports runtime (docs/architecture.md); runtime imports gen.
# MicroPython, CircuitPython and CPython; no f-strings. Only for building
# objects and messages: never called from the refresh.
#
# The messages are the validators' own (tests pin them):
#   "pitch_db: 19.75 is out of range [-20.0, 19.747]"       out_of_range
#   "regions[0].texture.level: nan is not finite (allowed [0.0, 1.0])"   not_finite
#   "display.positions: expected an int in [1, 1048576], got str 'x'"  expected
#   "phase: expected one of 'continuous', 'reset', got 'x'"            not_a_word

_INFS = (float("inf"), float("-inf"))
# Ints beyond this are shown by name in a message, not by their digits:
# 10**400 must not make a 400-digit line (show()).
BIG = 1 << 62


def rng(lo, hi):
    """A closed range as messages show it: "[-20.0, 19.747]"."""
    return "[%r, %r]" % (lo, hi)


def is_int(v):
    """An int, not a bool (on CPython bool is an int subclass)."""
    return isinstance(v, int) and not isinstance(v, bool)


def is_num(v):
    """An int or a float, not a bool."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def finite(x):
    """x (a number) is neither NaN nor an infinity. An int beyond a double
    is finite on CPython, an infinity on MicroPython (it compares as a
    float): the validators check ints apart."""
    return x == x and x not in _INFS


def show(v):
    """repr(v), but an int beyond +-2^62 by name."""
    if isinstance(v, int) and not -BIG < v < BIG:
        return "a huge int (beyond 2^62)"
    return repr(v)


def fail(path, msg):
    """The ValueError every validator raises: "<key path>: <what is wrong>"."""
    raise ValueError("%s: %s" % (path, msg))


def out_of_range(path, v, lo, hi):
    fail(path, "%s is out of range %s" % (show(v), rng(lo, hi)))


def not_finite(path, v, lo, hi):
    fail(path, "%r is not finite (allowed %s)" % (v, rng(lo, hi)))


def expected(path, what, lo, hi, got):
    """what: "an int" or "a number"; got: the value as the caller shows it."""
    fail(path, "expected %s in %s, got %s" % (what, rng(lo, hi), got))


def not_a_word(path, v, words):
    """A refused word (params' kind "w"). What it shows of v is bounded: a
    scene passes any value through (runtime/scene.py)."""
    if isinstance(v, str):
        got = repr(v) if len(v) <= 40 else "a str of %d characters" % len(v)
    elif v is None or isinstance(v, (bool, int, float)):
        got = "%s %s" % (type(v).__name__, show(v))
    else:
        got = type(v).__name__
    fail(path, "expected one of %s, got %s" % (", ".join([repr(w) for w in words]), got))
