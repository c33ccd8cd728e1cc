# Region kind "reference": one of the lab's nine reference textures (seed 001;
# gen/reference.py, texel.reference_names()), rendered region-long. In the
# texelpad firmware its map may already be in flash (gen/reference.py
# flash_u16): then it plays in place, no RAM, no render; else it is read from
# the map file `texelpad deploy` writes on a stock RP2040 (file_u16) or rendered
# into 1 KB chunks (kinds.new_chunks): a stock Pico's heap seldom has the 19.2 or
# 38.4 KB of a half or full screen in one piece beside a playing scene.
from ...gen.check import fail, got, qstr, check_keys
from . import K_BUF, K_CHUNK, CHUNK_BITS, new_chunks

NAME = "reference"
KEYS = ("kind", "name")
OPTIONS = ()
SHARED = True               # its map depends on the name and the length alone

_flash_u16 = None           # gen.reference.flash_u16, imported at the first reference region


def check(path, tex, n):
    from ... import reference_names
    check_keys(path, tex, KEYS)
    if "name" not in tex:
        fail(path, "missing required key 'name' (one of: %s)" % ", ".join(reference_names()))
    name = tex["name"]
    known = reference_names()
    if not isinstance(name, str) or name not in known:
        fail(path + ".name", "unknown reference texture %s (known: %s)"
             % (qstr(name) if isinstance(name, str) else got(name), ", ".join(known)))
    return {"kind": "reference", "name": name}


def flash(name, n):
    """The reference's map in flash (texelpad firmware), or None."""
    global _flash_u16
    if _flash_u16 is None:
        from ...gen.reference import flash_u16
        _flash_u16 = flash_u16
    return _flash_u16(name, n)


def need(tex, n, engine):
    return 2 * n


def block(tex, n, engine):
    return 0 if flash(tex["name"], n) is not None else 2 * min(n, 1 << CHUNK_BITS)


def store(tex, n, engine):
    rom = flash(tex["name"], n)
    if rom is not None:
        return K_BUF, rom, None             # the firmware's map, played in place
    # which map files there are (fill's file_u16), found out before the chunks are made:
    # its garbage then leaves no hole between them
    from ...gen.reference import map_files
    map_files()
    ch = new_chunks(n)
    return K_CHUNK, ch, ch


def fill(tex, n, chunks, engine, dx_um):
    # a stock RP2040's deployed map file read into the chunks, where there is one
    # (gen/reference.py file_u16); else rendered chunk by chunk (_parts)
    from ...gen.reference import file_u16
    if not file_u16(tex["name"], n, chunks):
        from ... import reference_u16
        reference_u16(tex["name"], n, chunks)


def describe(tex):
    return {"name": tex["name"]}


def words(d):
    return "reference %s" % d["name"]


label = words
