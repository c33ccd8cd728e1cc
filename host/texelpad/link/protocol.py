"""Every request the host sends to a board, in one place, and the rule they
all follow: code the host writes itself around `repr()` literals of plain
data; user text is never pasted into code (`literal()` refuses anything
that is not plain data, NaN and inf included: their repr is not a literal).

The board side of the contract is texel.app (the user API) and texel.wire
(what only the link calls), versioned by texel.protocol.PROTOCOL (checked at
the handshake); the requests here import texel modules and call them.
"""
from __future__ import annotations

import json

import math
import struct
import sys
from typing import Any, Sequence

import texel.protocol          # the contract alone: no display runtime on the host

PROTOCOL = texel.protocol.PROTOCOL   # the contract this host speaks
APP = "texel.app"                    # the user API: start, push, status, stop, ...
WIRE = "texel.wire"                  # uploads, JSON scenes, base64 data, the virtual finger

# Largest literal one call may send (bytes of code). An uploaded samples region
# of 19,200 values is ~400 KB as floats, ~120 KB as u16 ints; this bounds what
# a typo can push through a 115,200-baud link (~1 min at the cap).
MAX_CALL_BYTES = 512 * 1024


class LiteralError(ValueError):
    """A value that cannot cross the link as a literal."""


# --- literals -----------------------------------------------------------------

# How deeply a value may nest (a scene needs 5 levels: the scene, its regions,
# a region, its texture, a samples region's values). Bounds the host's own
# walk (no RecursionError on a hostile scene: the board's validation,
# texel.runtime.scene.validate, runs after this check) and what a board's
# parser must take apart on its small stack.
MAX_DEPTH = 16
# Integers cross the link only up to 64 bits (signed or unsigned): the texel
# ranges are far inside, and a 5,000-digit integer is a typo, not a seed
# (Python 3.11's int->str limit would make its repr() fail anyway).
INT_MIN, INT_MAX = -(1 << 63), (1 << 64) - 1


def literal(obj: Any, limit: int = MAX_CALL_BYTES) -> str:
    """`repr()` of plain data (dict with str keys, list, tuple, str, int,
    float, bool, None), after checking that it is exactly that: non-finite
    floats, other types (objects whose repr could be code), cycles, values
    nested deeper than MAX_DEPTH, integers beyond 64 bits and oversized
    values raise LiteralError naming where in the value. numpy scalars and
    arrays are sent as the plain numbers and lists they hold (plain())."""
    text = repr(plain(obj))
    if len(text) > limit:
        raise LiteralError("value is %d bytes as a literal, more than the link's %d-byte limit"
                           % (len(text), limit))
    return text


def plain(obj: Any) -> Any:
    """obj as plain data, checked as literal() checks it: a copy in which numpy
    numbers and arrays are the Python numbers and lists they hold, exactly
    (np.float32(0.1) -> 0.10000000149011612; np.int64 -> int; np.bool_ ->
    bool, which is not a number: the board refuses it where a number goes,
    as it refuses True). The input is not changed. The host converts; device
    code never sees numpy."""
    return _plain(obj, "", set(), 0, sys.modules.get("numpy"))


def _digits(n: int) -> str:
    """How many decimal digits abs(n) has, without str(n) (refused beyond
    4,300 digits since Python 3.11)."""
    n = abs(n)
    d = int(math.log10(n)) + 1
    if d < 100_000 and 10 ** (d - 1) > n:       # log10 rounded up (10**30 - 1)
        d -= 1
    return format(d, ",")


def _plain(v: Any, path: str, seen: set[int], depth: int, np: Any) -> Any:
    # path: where in the value, as the device names it (regions[0].texture.seed)
    t = type(v)
    where = path or "value"
    if v is None or t is bool or t is str:
        return v
    if t is int:
        if not INT_MIN <= v <= INT_MAX:
            raise LiteralError("%s: an integer of about %s digits is too large to send (the link "
                               "carries integers of at most 64 bits)" % (where, _digits(v)))
        return v
    if t is float:
        if not math.isfinite(v):
            # the board's own wording (texel.gen.params, texel.runtime.scene)
            raise LiteralError("%s: %r is not finite" % (where, v))
        return v
    if np is not None and isinstance(v, (np.generic, np.ndarray)):
        conv = _from_numpy(v, where, np)
        if conv is not v:
            return _plain(conv, path, seen, depth, np)
    if t in (dict, list, tuple):
        if depth >= MAX_DEPTH:
            raise LiteralError("%s: nested more than %d levels deep (a scene needs 5)"
                               % (where, MAX_DEPTH))
        if id(v) in seen:
            raise LiteralError("%s: the value contains itself" % where)
        seen.add(id(v))
        if t is dict:
            out: Any = {}
            for k, x in v.items():
                if type(k) is not str:
                    if np is not None and isinstance(k, np.str_):
                        k = str(k)
                    else:
                        raise LiteralError("%s: key %s is not a string" % (where, _show_key(k)))
                out[k] = _plain(x, _join(path, k), seen, depth + 1, np)
        else:
            items = [_plain(x, "%s[%d]" % (where, i), seen, depth + 1, np)
                     for i, x in enumerate(v)]
            out = items if t is list else tuple(items)
        seen.discard(id(v))
        return out
    raise LiteralError("%s: %s values cannot be sent to the board (plain numbers, strings, "
                       "lists and dicts only)" % (where, t.__name__))


def _join(path: str, key: str) -> str:
    """path.key as the board names it; a key that is not a short name is
    quoted and cut as the board's own validation shows it (a line break or
    100,000 characters in a key must not make the message)."""
    if key.isascii() and key.isidentifier() and len(key) <= 40:
        return "%s.%s" % (path, key) if path else key
    from texel.gen.check import qstr
    return "%s[%s]" % (path or "value", qstr(key))


def _show_key(k: Any) -> str:
    if type(k) is int and not INT_MIN <= k <= INT_MAX:
        return "(an integer of about %s digits)" % _digits(k)
    try:
        text = repr(k)
    except Exception:                   # a repr that fails is no reason for a traceback
        text = "of type %s" % type(k).__name__
    return text if len(text) <= 40 else text[:40] + "..."


def _from_numpy(v: Any, where: str, np: Any) -> Any:
    """A numpy scalar or array as the Python value it holds (exactly), or v
    itself when it holds no plain data (refused by the caller, by type)."""
    if isinstance(v, np.ndarray):
        if v.dtype.kind in "biufUO":           # bool, ints, floats, str, objects
            return v.tolist()                 # 0-d: the scalar; elements checked again
        return v
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        f = float(v)
        if f == f and f != v:                 # long double: float64 cannot hold it
            raise LiteralError("%s: %s %s cannot be sent exactly (the link carries float64)"
                               % (where, type(v).__name__, np.format_float_positional(v)))
        return f
    if isinstance(v, np.str_):
        return str(v)
    return v


# --- the handshake and calls into texel.app --------------------------------------------

# The board's protocol and image version, firmware and .mpy format (one line).
# An image that fails to import for any reason (missing, or broken: a corrupt
# .mpy raises ValueError) reports 'missing', so deploy can still connect and
# repair it.
HELLO = """import sys
try:
 import texel
 try:
  import texel.protocol as _a
 except ImportError:
  import texel.app as _a
 _v = (_a.PROTOCOL, texel.__version__)
except Exception as _e:
 _v = ('missing', str(_e))
_i = sys.implementation
print(repr((_v, _i.name, tuple(_i.version[:3]), getattr(_i, '_mpy', None), sys.platform)))
_v = _i = _a = None
"""


# The handshake for deploy: the same answer, but the image is never imported
# from its files - only read from sys.modules when the board already runs it.
# A damaged image file (a truncated .mpy hangs the unix port's loader, and
# can hang a board's) must not keep deploy from replacing it; a display can
# only be playing if texel.app is loaded, so nothing that plays is missed.
HELLO_LOADED = HELLO.replace(
    " import texel\n try:\n  import texel.protocol as _a\n except ImportError:\n  import texel.app as _a\n",
    " _a = sys.modules['texel.app']\n texel = sys.modules['texel']\n").replace(
    "except Exception as _e:\n _v = ('missing', str(_e))",
    "except KeyError:\n _v = ('missing', 'not loaded')")


def call(module: str, func: str, args: Sequence[Any] = (), kwargs: dict | None = None) -> str:
    """`module.func(*args, **kwargs)`, answering ('ok', value) or ('err', the
    device's ValueError text), printed by texel.wire.say (floats as their bits
    where the board's C core writes it: floats_from_bits; repr() on an image
    older than protocol 3, which deploy still talks to)."""
    argtext = ", ".join([literal(a) for a in args] + (["**" + literal(kwargs)] if kwargs else []))
    return ("import %s as _m\ntry:\n _r = ('ok', _m.%s(%s))\nexcept ValueError as _e:\n"
            " _r = ('err', str(_e))\nimport texel.wire as _m\n_m = getattr(_m, 'say', None)\n"
            "_m(_r) if _m else print(repr(_r))\n_m = _r = None" % (module, func, argtext))


def _f32(bits: int) -> float:
    """The float32 with these bits, as the shortest decimal that is that
    float32 again (CPython's float of it): 6.3, not 6.300000190734863 -
    numpy's float32 str(), or where there is no numpy the nearest decimal of
    the fewest digits that round-trips (at a power of two, where the float32's
    rounding interval is lopsided, a digit longer than numpy's now and then)."""
    packed = struct.pack("<I", bits)
    x = struct.unpack("<f", packed)[0]
    try:
        import numpy as np
        return float(str(np.frombuffer(packed, dtype="<f4")[0]))
    except ImportError:
        pass
    if math.isfinite(x):
        for digits in range(1, 10):         # 9 significant digits always round-trip
            y = float("%.*g" % (digits, x))
            try:
                if struct.pack("<f", y) == packed:
                    return y
            except OverflowError:           # rounded past the largest float32
                pass
    return x


def floats_from_bits(value: Any) -> Any:
    """An answer printed by the board's C core (texel.wire.say: each float32
    as `<its 32 bits>j`, an imaginary int literal) with every such number
    turned back into its float (_f32); anything else as it is. ValueError for
    a complex that is not 32 bits (no answer holds one)."""
    if isinstance(value, complex):
        b = value.imag
        if value.real != 0 or not (0 <= b < 1 << 32) or b != int(b):
            raise ValueError("not a float's bits: %r" % (value,))
        return _f32(int(b))
    if isinstance(value, dict):
        return {floats_from_bits(k): floats_from_bits(v) for k, v in value.items()}
    if isinstance(value, list):
        return [floats_from_bits(v) for v in value]
    if isinstance(value, tuple):
        return tuple(floats_from_bits(v) for v in value)
    return value


# --- long samples regions: data, not code -------------------------------------------

# A samples region of more values than this crosses the link as an upload
# (texel.wire.upload_*: base64 pieces of UPLOAD_PIECE values) instead of a
# list literal inside the scene. A literal of thousands of numbers is code
# the board must compile in one go: 9,000 ints overflowed MicroPython's
# bytecode emitter, and the compile held the virtual board's refresh for
# 0.33 s. 512 values are ~3.5 KB of literal, compiled in a few ms.
INLINE_SAMPLES_MAX = 512
UPLOAD_PIECE = texel.protocol.UPLOAD_PIECE_MAX


def split_uploads(scene: dict[str, Any]) -> tuple[dict[str, Any], list[tuple[int, list[int]]]]:
    """A checked plain scene -> (the scene with every long samples region's
    values taken out ("u16": None), [(region index, its uint16 values)]).
    "values" (0..1) become uint16 here exactly as the board's validation
    makes them (round(v * 65535), half up; texel.runtime.kinds.samples.check) -
    in float64, where a float32 board would round a few differently."""
    regions = list(scene["regions"])
    out: list[tuple[int, list[int]]] = []
    for i, r in enumerate(regions):
        tex = r["texture"]
        if tex.get("kind") != "samples":
            continue
        key = "u16" if "u16" in tex else "values"
        vals = tex[key]
        if len(vals) <= INLINE_SAMPLES_MAX:
            continue
        u16 = list(vals) if key == "u16" else [int(x * 65535.0 + 0.5) for x in vals]
        regions[i] = dict(r, texture={"kind": "samples", "u16": None,
                                      "fit": tex.get("fit", "tile")})
        out.append((i, u16))
    if not out:
        return scene, out
    return dict(scene, regions=regions), out


def scene_text(scene: Any, limit: int = MAX_CALL_BYTES) -> str:
    """A checked scene as the JSON text the board parses with its json module
    (literal()'s checks first): data for a C parser, not code for the board's
    compiler. On an RP2040 compiling a scene's literal took 3.5 ms for a
    one-region scene and 49.7 ms for 16 regions, json.loads 0.5 and 7.1 ms
    (docs/runtime.md). UTF-8 as is (no \\u escapes: MicroPython's json does
    not join surrogate pairs); no NaN/inf (refused like literal())."""
    literal(scene, limit)
    try:
        text = json.dumps(plain(scene), ensure_ascii=False, allow_nan=False,
                          separators=(",", ":"))
    except (TypeError, ValueError) as e:
        raise LiteralError("scene: not JSON data: %s" % e) from None
    if len(text) > limit:
        raise LiteralError("value is %d bytes as JSON, more than the link's %d-byte limit"
                           % (len(text), limit))
    return text


def staged_call(module: str, func: str, args: Sequence[Any], scene_at: int,
                slots: dict[int, int] | None = None, kwargs: dict | None = None) -> str:
    """call(), with the scene in args[scene_at] sent as JSON text (a repr()'d
    str, parsed by the board's json module: scene_text) and completed on the
    board: the samples region i gets upload slots[i] (texel.wire.take_upload)
    in place of its values before `func` runs. One statement on the board
    (texel.wire.staged): the compile of an eight-line request took 7-11 ms of
    every push on an RP2040. The board prints the answer as one line and
    then collects (texel.wire.reply): the link reads it with
    Link.eval_reply, which does not wait for the collection."""
    rest = [a for k, a in enumerate(args) if k != scene_at]
    fill = tuple(sorted((int(i), int(slot)) for i, slot in (slots or {}).items()))
    # reply(func, text, fill=(), args=(), scene_at=0, kwargs=None): the trailing
    # defaults left out, one statement. The board's parser is slow per token (on
    # the emulated RP2040 the three-line form with every argument compiled in
    # 2.91 ms, `__import__(...).reply(func, text)` in 1.86: bench/request_parts.py)
    parts = [literal(func), repr(scene_text(args[scene_at])), literal(fill),
             literal(tuple(rest)), "%d" % int(scene_at), literal(kwargs or None)]
    defaults = ["()", "()", "0", "None"]
    while len(parts) > 2 and parts[-1] == defaults[len(parts) - 3]:
        parts.pop()
    top, _, sub = module.partition(".")
    return "__import__(%r).%s.reply(%s)" % (module, sub, ", ".join(parts)) if sub else \
        "__import__(%r).reply(%s)" % (top, ", ".join(parts))


def staged_frame(func: str, args: Sequence[Any], scene_at: int,
                 slots: dict[int, int] | None = None, kwargs: dict | None = None
                 ) -> tuple[bytes, bytes]:
    """staged_call() as a frame for the board's standing reader
    (texel.wire.stand): (its head, the scene's JSON as bytes). The head is
    "[", the data's byte count, ",", the header's byte count, ",", then the
    header, JSON [func, fill, the other args, scene_at, kwargs]: data the
    board's json module reads, never code. The counts come first so that the
    board can read past both where it has no room for them. The same checks
    as staged_call (literal(), scene_text())."""
    rest = [a for k, a in enumerate(args) if k != scene_at]
    fill = sorted([int(i), int(slot)] for i, slot in (slots or {}).items())
    literal(rest)
    literal(kwargs)
    data = scene_text(args[scene_at]).encode("utf-8")
    try:
        header = json.dumps([func, fill, plain(rest), int(scene_at),
                             plain(kwargs) if kwargs else None],
                            ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    except (TypeError, ValueError) as e:
        raise LiteralError("request: not JSON data: %s" % e) from None
    hb = header.encode("utf-8")
    return b"[%d,%d," % (len(data), len(hb)) + hb, data


def render_u16(params: dict[str, Any], engine: str | None) -> str:
    """texel.render_u16 on the board, the map back as base64 of its bytes."""
    return ("import texel, binascii\ntry:\n _m = texel.render_u16(%s, engine=%s)\n"
            " _r = ('ok', binascii.b2a_base64(bytes(_m)).strip())\nexcept ValueError as _e:\n"
            " _r = ('err', str(_e))\nprint(repr(_r))\n_m = _r = None"
            % (literal(params), literal(engine)))


# --- deploy: the board's files ---------------------------------------------------------

# What the board reports for the image's paths: sha256 hex ('' when it has
# no hashlib; hashlib.sha256, or CircuitPython's hashlib.new('sha256')), None when missing or unreadable, e.g. a folder in its place), the files under the package directory, and
# free bytes - all files in one round trip (mpremote's fs_hashfile takes three
# round trips per file; an unchanged 30-file image is checked in ~0.1 s).
_SURVEY_CODE = """import os
try:
 import hashlib, binascii
 try:
  _H = hashlib.sha256
 except AttributeError:
  # CircuitPython: hashlib.new('sha256') only (no hexdigest: binascii below)
  _H = lambda: hashlib.new('sha256')
except ImportError:
 _H = None
def _h(p):
 try:
  f = open(p, 'rb')
 except OSError:
  return None
 try:
  if _H is None:
   return ''
  h = _H()
  b = bytearray(512)
  while True:
   n = f.readinto(b)
   if not n:
    break
   h.update(b if n == 512 else b[:n])
  return binascii.hexlify(h.digest()).decode()
 except OSError:
  return None
 finally:
  f.close()
def _ls(d):
 out = []
 if not d:
  return out
 try:
  # CircuitPython has no os.ilistdir: os.listdir and os.stat's mode
  for n in os.listdir(d):
   p = d + '/' + n
   if os.stat(p)[0] & 0x4000:
    out += _ls(p)
   else:
    out.append(p)
 except OSError:
  pass
 return out
try:
 _s = os.statvfs('/')
 _free = _s[0] * _s[4]
except (AttributeError, OSError):
 _free = None
print(repr(({p: _h(p) for p in %s}, _ls(%s), _free)))
_h = _ls = _H = _s = _free = None
"""


def survey(paths: Sequence[str], package_dir: str) -> str:
    return _SURVEY_CODE % (literal(list(paths)), literal(package_dir))


# CircuitPython: lend the CIRCUITPY drive to code (deploy); prints '' or why not.
# Auto-reload off first: with it on (code.py running serve), the writes restart the VM
# in the middle of the deploy (on until the board resets).
REMOUNT_WRITABLE = """try:
 import storage, supervisor
 supervisor.runtime.autoreload = False
 storage.remount('/', readonly=False)
 print(repr(''))
except Exception as _e:
 print(repr(str(_e) or type(_e).__name__))
 _e = None
"""


# CircuitPython: True when /code.py exists and is not texelpad's power-up script (the zip's)
FOREIGN_CODE_PY = """try:
 with open('/code.py') as _f:
  print(repr('texel.app' not in _f.read()))
except OSError:
 print(repr(False))
_f = None
"""


# Drop the texel modules from sys.modules, so the next import loads the new image.
PURGE = """import sys, gc
for _k in [k for k in sys.modules if k == 'texel' or k.startswith('texel.')]:
 del sys.modules[_k]
_k = None
gc.collect()
"""


def mkdirs(dirs: Sequence[str]) -> str:
    """Make each directory (parents first); existing ones are fine."""
    return "import os\nfor _d in %s:\n try:\n  os.mkdir(_d)\n except OSError:\n  pass\n" % (
        literal(list(dirs)))


def replace_file(path: str, tmp: str) -> str:
    """Rename tmp over path (a file written beside its old copy). The old copy
    is removed first (FAT cannot rename over a file): an interruption between
    the two leaves path missing and tmp whole, which the next deploy's survey
    finds (tmp's hash is the image's) and completes."""
    return ("import os\ntry:\n os.remove(%s)\nexcept OSError:\n pass\nos.rename(%s, %s)"
            % (literal(path), literal(tmp), literal(path)))


def remove_files(paths: Sequence[str]) -> str:
    """Remove each file; one already gone is fine (ENOENT), any other error
    is raised."""
    return ("import os\nfor _p in %s:\n try:\n  os.remove(_p)\n except OSError as _e:\n"
            "  if _e.args[0] != 2:\n   raise\n_p = None" % literal(list(paths)))


def remove_file(path: str) -> str:
    return remove_files([path])


# Before the display is stopped: can the image be written? For each path the
# kind of what is there ('d' folder, 'f' file, None nothing), and for each
# folder a file will be written into, the errno of creating and removing a
# probe file in it - or in its deepest existing ancestor, where deploy's
# mkdirs will start (None: writable).
_PREFLIGHT_CODE = """import os
def _k(p):
 try:
  return 'd' if os.stat(p or %(root)s)[0] & 0x4000 else 'f'
 except OSError:
  return None
_r = {p: _k(p) for p in %(paths)s}
_w = {}
for _d in %(dirs)s:
 while _d and _k(_d) is None:
  _d = _d.rpartition('/')[0]
 if _d in _w:
  continue
 if _k(_d) != 'd':
  _w[_d] = 20
  continue
 _t = (_d or %(root)s.rstrip('/')) + '/.texelpad-probe'
 if %(probe)s:
  try:
   open(_t, 'w').close()
   os.remove(_t)
   _w[_d] = None
  except OSError as _e:
   _w[_d] = _e.args[0]
 else:
  _w[_d] = None
print(repr((_r, _w)))
_k = _r = _w = _d = _t = None
"""


def preflight(paths: Sequence[str], dirs: Sequence[str], root: str, probe: bool = True) -> str:
    """What is at `paths`, and whether each of `dirs` (or its deepest
    existing ancestor) takes a new file; root: the filesystem's root as the
    board names it ('/' on a board, '.' on the unix port, whose paths are
    relative). probe=False only looks (a dry run writes nothing)."""
    return _PREFLIGHT_CODE % {"paths": literal(list(paths)), "dirs": literal(list(dirs)),
                              "root": literal(root), "probe": literal(bool(probe))}
