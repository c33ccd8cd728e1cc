"""Every request the host sends to a board, in one place, and the rule they
all follow: code the host writes itself around `repr()` literals of plain
data; user text is never pasted into code (`literal()` refuses anything
that is not plain data, NaN and inf included: their repr is not a literal).

The board side of the contract is texel.app (PROTOCOL, checked at the
handshake); the requests here import texel modules and call them.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import texel.app

PROTOCOL = texel.app.PROTOCOL        # the contract this host speaks
APP = "texel.app"

# Largest literal one call may send (bytes of code). An uploaded samples region
# of 19,200 values is ~400 KB as floats, ~120 KB as u16 ints; this bounds what
# a typo can push through a 115,200-baud link (~1 min at the cap).
MAX_CALL_BYTES = 512 * 1024


class LiteralError(ValueError):
    """A value that cannot cross the link as a literal."""


# --- literals -----------------------------------------------------------------

def literal(obj: Any, limit: int = MAX_CALL_BYTES) -> str:
    """`repr()` of plain data (dict with str keys, list, tuple, str, int,
    float, bool, None), after checking that it is exactly that: non-finite
    floats, other types (objects whose repr could be code), cycles and
    oversized values raise LiteralError naming where in the value."""
    _check(obj, "", set())
    text = repr(obj)
    if len(text) > limit:
        raise LiteralError("value is %d bytes as a literal, more than the link's %d-byte limit"
                           % (len(text), limit))
    return text


def _check(v: Any, path: str, seen: set[int]) -> None:
    # path: where in the value, as the device names it (regions[0].texture.seed)
    t = type(v)
    where = path or "value"
    if v is None or t in (bool, int, str):
        return
    if t is float:
        if not math.isfinite(v):
            raise LiteralError("%s: %r is not a finite number" % (where, v))
        return
    if t in (dict, list, tuple):
        if id(v) in seen:
            raise LiteralError("%s: the value contains itself" % where)
        seen.add(id(v))
        if t is dict:
            for k, x in v.items():
                if type(k) is not str:
                    raise LiteralError("%s: key %r is not a string" % (where, k))
                _check(x, "%s.%s" % (path, k) if path else k, seen)
        else:
            for i, x in enumerate(v):
                _check(x, "%s[%d]" % (path or "value", i), seen)
        seen.discard(id(v))
        return
    raise LiteralError("%s: %s values cannot be sent to the board (plain numbers, strings, "
                       "lists and dicts only)" % (where, t.__name__))


# --- the handshake and calls into texel.app --------------------------------------------

# The board's protocol and image version, firmware and .mpy format (one line).
HELLO = """import sys
try:
 import texel, texel.app as _a
 _v = (_a.PROTOCOL, texel.__version__)
except ImportError as _e:
 _v = ('missing', str(_e))
_i = sys.implementation
print(repr((_v, _i.name, tuple(_i.version[:3]), getattr(_i, '_mpy', None), sys.platform)))
_v = _i = _a = None
"""


def call(module: str, func: str, args: Sequence[Any] = (), kwargs: dict | None = None) -> str:
    """`module.func(*args, **kwargs)`, answering ('ok', value) or ('err', the
    device's ValueError text)."""
    argtext = ", ".join([literal(a) for a in args] + (["**" + literal(kwargs)] if kwargs else []))
    return ("import %s as _m\ntry:\n _r = ('ok', _m.%s(%s))\nexcept ValueError as _e:\n"
            " _r = ('err', str(_e))\nprint(repr(_r))\n_m = _r = None" % (module, func, argtext))


def render_u16(params: dict[str, Any], engine: str | None) -> str:
    """texel.render_u16 on the board, the map back as base64 of its bytes."""
    return ("import texel, binascii\ntry:\n _m = texel.render_u16(%s, engine=%s)\n"
            " _r = ('ok', binascii.b2a_base64(bytes(_m)).strip())\nexcept ValueError as _e:\n"
            " _r = ('err', str(_e))\nprint(repr(_r))\n_m = _r = None"
            % (literal(params), literal(engine)))


# --- deploy: the board's files ---------------------------------------------------------

# What the board reports for the image's paths: sha256 hex ('' when it has
# no hashlib, None when missing), the files under the package directory, and
# free bytes - all files in one round trip (mpremote's fs_hashfile takes three
# round trips per file; an unchanged 30-file image is checked in ~0.1 s).
_SURVEY_CODE = """import os
try:
 import hashlib, binascii
 _H = hashlib.sha256
except (ImportError, AttributeError):
 _H = None
def _h(p):
 try:
  f = open(p, 'rb')
 except OSError:
  return None
 if _H is None:
  f.close()
  return ''
 h = _H()
 b = bytearray(512)
 while True:
  n = f.readinto(b)
  if not n:
   break
  h.update(b if n == 512 else b[:n])
 f.close()
 return binascii.hexlify(h.digest()).decode()
def _ls(d):
 out = []
 try:
  for e in os.ilistdir(d):
   p = d + '/' + e[0]
   if e[1] & 0x4000:
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
    """Rename tmp over path (a file written beside its old copy)."""
    return ("import os\ntry:\n os.remove(%s)\nexcept OSError:\n pass\nos.rename(%s, %s)"
            % (literal(path), literal(tmp), literal(path)))


def remove_file(path: str) -> str:
    return "import os\nos.remove(%s)" % literal(path)


def restart(board_name: str, scene: Any, realtime: bool) -> str:
    """Start the display again, from a fresh import of the image."""
    return ("import texel.app as _a\n_a.start(%s, %s%s)\n_a = None"
            % (literal(board_name), literal(scene), ", realtime=True" if realtime else ""))
