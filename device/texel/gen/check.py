# The checks the device's validators share: gen/params.py (texel parameters),
# gen/brush.py (brushes), runtime/scene.py and runtime/kinds/ (scenes and
# their region kinds) and runtime/boards.py (board files). Written once here, so every one of them words a number, a
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


# --- bounded words for untrusted values (scenes, region kinds, the link) --------
_SHOW = 40                  # characters of a string shown in a message (qstr)


def got(v):
    """A bounded description of an untrusted value: type and value, or type
    and size for containers; never a repr of unbounded size."""
    if v is None or isinstance(v, (bool, float)):
        return "%s %r" % (type(v).__name__, v)
    if isinstance(v, int):              # beyond +-2^62 by name only
        return "int %r" % v if -BIG < v < BIG else show(v)
    if isinstance(v, str):
        return "str " + qstr(v)
    if isinstance(v, (list, tuple)):
        return "%s of %d items" % (type(v).__name__, len(v))
    if isinstance(v, dict):
        return "dict of %d keys" % len(v)
    return type(v).__name__


def qstr(s):
    """A string quoted like repr() for printable ASCII, but every other
    character escaped (\\xNN, \\uNNNN, \\UNNNNNNNN) on every port - CPython's
    repr shows printable non-ASCII as is, MicroPython's escapes it - and cut
    to _SHOW characters: messages stay short, ASCII and identical."""
    cut = s[:_SHOW]
    q = '"' if ("'" in cut and '"' not in cut) else "'"
    out = [q]
    for c in cut:
        o = ord(c)
        if c == q or c == "\\":
            out.append("\\" + c)
        elif c == "\n":
            out.append("\\n")
        elif c == "\r":
            out.append("\\r")
        elif c == "\t":
            out.append("\\t")
        elif 32 <= o < 127:
            out.append(c)
        elif o < 256:
            out.append("\\x%02x" % o)
        elif o < 65536:
            out.append("\\u%04x" % o)
        else:
            out.append("\\U%08x" % o)
    out.append(q)
    if len(s) > _SHOW:
        out.append("... (%d chars)" % len(s))
    return "".join(out)


def plain_str(s):
    # short printable ASCII: repr() is the same on every port
    if len(s) > _SHOW:
        return False
    for c in s:
        if not 32 <= ord(c) < 127:
            return False
    return True


def key_shown(k):
    return qstr(k) if isinstance(k, str) else got(k)


def check_keys(path, d, allowed, options=()):
    """Refuse keys not in `allowed` or `options`; with several, name the
    smallest shown form (dict order differs between CPython and MicroPython).
    The message lists `allowed`, then `options` (the texel options:
    docs/generator.md)."""
    bad = None
    for k in d:
        if not (isinstance(k, str) and (k in allowed or k in options)):
            s = key_shown(k)
            if bad is None or s < bad:
                bad = s
    if bad is not None:
        fail(path, "unknown key %s (allowed: %s)" % (bad, ", ".join(tuple(allowed) + tuple(options))))


def need_dict(path, v, what):
    if not isinstance(v, dict):
        fail(path, "expected %s, got %s" % (what, got(v)))
    return v


def num(path, v, lo, hi):
    """A finite number (int accepted, bool refused) in [lo, hi] -> float."""
    if not is_num(v):
        expected(path, "a number", lo, hi, got(v))
    if isinstance(v, int):
        if v < lo or v > hi:            # exact int/float comparison: no overflow
            out_of_range(path, v, lo, hi)
        return float(v)
    if not finite(v):
        not_finite(path, v, lo, hi)
    if v < lo or v > hi:
        out_of_range(path, v, lo, hi)
    return float(v)


def int_in(path, v, lo, hi):
    """An int (bool refused) in [lo, hi]."""
    if not is_int(v):
        expected(path, "an int", lo, hi, got(v))
    if v < lo or v > hi:
        out_of_range(path, v, lo, hi)
    return v
