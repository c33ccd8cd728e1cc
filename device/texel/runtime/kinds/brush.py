# Region kind "brush": a Tactile Paintbrush stroke (seed 002; gen/brush.py,
# docs/brush.md): the board gets the brush's ~200 numbers and a seed and
# paints the region itself, into 1 KB chunks (upload.Chunks, how K_CHUNK):
# no block over 1 KB, so a heap the brush's numbers fragmented still takes a
# full screen. gen/brush.py checks the texture (region_texture).
from . import K_CHUNK

NAME = "brush"
KEYS = ("kind", "brush", "seed")
OPTIONS = ()
SHARED = True               # what it paints depends on the brush, seed and length alone


def check(path, tex, n):
    from ...gen.check import check_keys
    from ...gen.brush import region_texture
    check_keys(path, tex, KEYS)
    return region_texture(path, tex)


def need(tex, n, engine):
    return 2 * n


def block(tex, n, engine):
    return 0


def store(tex, n, engine):
    # the painter's tables first, while the heap has blocks their size
    # (gen/brush.py prepare)
    from ..upload import Chunks
    from ...gen.brush import prepare
    prepare()
    ch = Chunks(n)
    return K_CHUNK, ch.chunks, ch


def fill(tex, n, ch, engine, dx_um):
    from ...gen.brush import paint
    paint(tex["brush"], tex["seed"], len(ch), ch)


def fill_near(tex, n, ch, where, offset):
    """fill() with the samples around the finger painted first (where(): its
    display position now, -1 lifted; offset: the region's first position):
    the rest as a gen/brush_parts.py Painting to finish after the swap, following
    the finger (app._paint_rest), or None where this board's C painter
    cannot paint in parts (the whole painted here then)."""
    from ...gen.brush import _native_c
    c = _native_c()
    if c is None or not hasattr(c, "paint_part"):
        fill(tex, n, ch, None, 0)
        return None
    from ...gen.brush_parts import Painting
    return Painting(tex["brush"], tex["seed"], len(ch), ch, where, offset=offset)


def describe(tex):
    return {"seed": tex["seed"]}


def words(d):
    return "brush, seed %s" % d["seed"]


label = words
