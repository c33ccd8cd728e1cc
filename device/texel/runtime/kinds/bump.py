# Region kind "bump": a virtual bump or edge at a position, felt through
# friction alone - the lateral-force illusion (Robles-De-La-Torre & Hayward,
# Nature 2001: a finger reads the lateral force of a slope as its shape) as
# friction displays render it, friction rising with the slope's steepness
# (Kim, Israr & Poupyrev, UIST 2013: friction from the gradient's magnitude).
# A static map, the same whichever way the finger moves: the classroom demo.
#
#   {"kind": "bump", "shape": "gaussian", "width_mm": 2.0, "height": 1.0,
#    "at": 0.5, "level": 1.0}              (every key but "kind" optional)
#
# The virtual surface h(x), x in mm from the centre (at: a fraction of the
# region, 0 = its first position, 1 = its end), w = width_mm:
#   gaussian  h = exp(-x^2 / (2 s^2)), s = w / 4 (the bump within +-2 s)
#   cosine    h = (1 + cos(2 pi x / w)) / 2 for |x| < w/2, else 0
#   edge      a raised-cosine step rising over w: (1 - cos(pi (x/w + 1/2))) / 2
# g(x) = |h'(x)| / max |h'| in [0, 1] (gaussian: (|x|/s) e^((1 - x^2/s^2)/2),
# largest at |x| = s; cosine |sin(2 pi x / w)|; edge cos(pi x / w)), and the
# amplitude (friction reduction; less of it is more friction):
#   level * (1 - height * g(x))  ->  round(.. * 65535), half up
# so height 1 makes the steepest slope full friction and the flat display
# plays `level`. A gaussian has two friction ridges (its two flanks), a
# cosine two, an edge one. Position k of the region sits at x = (k + 0.5 -
# at * n) * dx: at 0.5 the map is symmetric.
#
# Memory: 2 bytes a position in 1 KB chunks (upload.Chunks, how K_CHUNK), as
# a brush: a full screen needs no 38 KB block.
# Precision: floats, once, at build (never in the refresh): the map is
# within 1 u16 of CPython's binary64 on float32 and on CircuitPython's 30-bit
# floats (tests/runtime/test_kind_bump.py). Outside the bump (|x| >= w/2;
# gaussian |x| >= 8 s, where g < 1e-12) the map is `level` without math.
import math
from ...gen.check import fail, got, num, check_keys
from . import K_CHUNK

NAME = "bump"
KEYS = ("kind", "shape", "width_mm", "height", "at", "level")
OPTIONS = ()
SHARED = True               # its map depends on the texture and the length alone
SHAPES = ("gaussian", "cosine", "edge")
WIDTH_MM = (0.01, 1000.0)   # mm: a tenth of a texel .. a metre
DEFAULTS = {"shape": "gaussian", "width_mm": 2.0, "height": 1.0, "at": 0.5, "level": 1.0}
FIELDS = (("shape", "word", SHAPES, None, "gaussian", "shape"),
          ("width_mm", "number", WIDTH_MM[0], WIDTH_MM[1], 2.0, "width (mm)"),
          ("height", "number", 0.0, 1.0, 1.0, "height (friction at the steepest slope, 0..1)"),
          ("at", "number", 0.0, 1.0, 0.5, "at (its centre, a fraction of the region)"),
          ("level", "number", 0.0, 1.0, 1.0, "level around it (friction reduction, 0..1)"))


def check(path, tex, n):
    check_keys(path, tex, KEYS)
    shape = tex.get("shape", "gaussian")
    if not isinstance(shape, str) or shape not in SHAPES:
        fail(path + ".shape", "expected one of %s, got %s" % (", ".join(SHAPES), got(shape)))
    out = {"kind": "bump", "shape": shape}
    for k, lo, hi in (("width_mm", WIDTH_MM[0], WIDTH_MM[1]), ("height", 0.0, 1.0),
                      ("at", 0.0, 1.0), ("level", 0.0, 1.0)):
        out[k] = num(path + "." + k, tex[k], lo, hi) if k in tex else DEFAULTS[k]
    return out


def need(tex, n, engine):
    return 2 * n


def block(tex, n, engine):
    return 0                # 1 KB chunks: a full screen fits a fragmented heap


def store(tex, n, engine):
    from ..upload import Chunks
    ch = Chunks(n)
    return K_CHUNK, ch.chunks, ch


def fill(tex, n, buf, engine, dx_um):
    """Render the map into buf (upload.Chunks of n positions of dx_um)."""
    level = tex["level"]
    flat = int(level * 65535.0 + 0.5)
    for c in buf.chunks:
        for i in range(len(c)):
            c[i] = flat
    w = tex["width_mm"] * 1000.0 / dx_um        # in positions
    c = tex["at"] * n - 0.5                     # position k is at x = k - c positions
    shape = tex["shape"]
    if shape == "gaussian":
        s = w / 4.0
        half = 8.0 * s
    else:
        half = w / 2.0
    lo = max(0, int(math.ceil(c - half)))
    hi = min(n, int(math.floor(c + half)) + 1)
    a = level * tex["height"]
    for k in range(lo, hi):
        x = k - c
        if shape == "gaussian":
            u = x / s
            g = abs(u) * math.exp(0.5 * (1.0 - u * u))
        elif shape == "cosine":
            g = abs(math.sin(2.0 * math.pi * x / w))
        else:
            g = math.cos(math.pi * x / w)
        if g > 0.0:
            buf[k] = int((level - a * g) * 65535.0 + 0.5)


def describe(tex):
    return {"shape": tex["shape"], "width_mm": tex["width_mm"], "height": tex["height"],
            "at": tex["at"], "level": tex["level"]}


def words(d):
    return "bump %s, %g mm wide, height %g, at %g of the region, level %g" % (
        d["shape"], d["width_mm"], d["height"], d["at"], d["level"])


def label(d):
    return "bump %s %g mm, height %g" % (d["shape"], d["width_mm"], d["height"])
