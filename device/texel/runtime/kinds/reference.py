# Region kind "reference": one of the lab's nine reference textures (seed 001;
# gen/reference.py, texel.reference_names()), rendered region-long. In the
# texelpad firmware its map may already be in flash (gen/reference.py
# flash_u16): then it plays in place, no RAM, no render; else it is read from
# the map file `texelpad deploy` writes on a stock RP2040 (file_u16) or rendered
# into 1 KB chunks (kinds.new_chunks): a stock Pico's heap seldom has the 19.2 or
# 38.4 KB of a half or full screen in one piece beside a playing scene.
from ...gen.check import fail, got, qstr, check_keys
# at the top, as kinds/__init__.py's: a reference push ran 6-8 import statements here
# and in texel's reference functions, 0.6-1 ms each on a stock Pico
from ...gen.reference import flash_u16 as flash, map_files, file_u16, names, reference_u16
from . import K_BUF, K_CHUNK, CHUNK_BITS, new_chunks

NAME = "reference"
KEYS = ("kind", "name")
OPTIONS = ()
SHARED = True               # its map depends on the name and the length alone


def check(path, tex, n):
    check_keys(path, tex, KEYS)
    if "name" not in tex:
        fail(path, "missing required key 'name' (one of: %s)" % ", ".join(names()))
    name = tex["name"]
    known = names()
    if not isinstance(name, str) or name not in known:
        fail(path + ".name", "unknown reference texture %s (known: %s)"
             % (qstr(name) if isinstance(name, str) else got(name), ", ".join(known)))
    return {"kind": "reference", "name": name}


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
    map_files()
    ch = new_chunks(n)
    return K_CHUNK, ch, ch


def fill(tex, n, chunks, engine, dx_um):
    # a stock RP2040's deployed map file read into the chunks, where there is one
    # (gen/reference.py file_u16); else rendered chunk by chunk (_parts)
    if not file_u16(tex["name"], n, chunks):
        reference_u16(tex["name"], n, chunks)


def describe(tex):
    return {"name": tex["name"]}


def words(d):
    return "reference %s" % d["name"]


label = words
