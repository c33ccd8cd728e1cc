"""The texelpad firmware's ROMFS partition and its .uf2 (pure: no link, no build).

The firmware (boards/<name>/, built by texelpad.firmware.build) is stock
MicroPython v1.28 + ulab with a ROMFS partition; texelpad itself lives in that
partition as the same image `texelpad deploy` writes to a stock board's
littlefs (texelpad.image: armv6m .mpy, package data, shipped boards),
laid out as lib/texel/... so that it mounts as /rom/lib/texel (sys.path on the
rp2 port: '', '.frozen', '/rom', '/rom/lib', '/lib'). MicroPython runs
bytecode from a ROMFS in place and gives a memoryview of a ROMFS file's bytes
without copying them (extmod/vfs_rom_file.c has a buffer protocol), so
neither the code nor its data take heap.

    romfs_files(target)          -> {path in the partition: bytes}
    romfs_image(files)           -> bytes (MicroPython's VfsRom format)
    read_uf2(data) / uf2_blocks(payload, base) / join_uf2(firmware, extra)
"""
from __future__ import annotations

import struct
import sys
from typing import Iterable, Mapping

from .. import image

# UF2 (Microsoft's USB flashing format, what the RP2040 boot ROM takes):
# 512-byte blocks, 256 payload bytes each for the RP2040.
UF2_MAGIC0, UF2_MAGIC1, UF2_MAGIC_END = 0x0A324655, 0x9E5D5157, 0x0AB16F30
UF2_FLAG_FAMILY = 0x00002000
RP2040_FAMILY = 0xE48BFF56
XIP_BASE = 0x10000000          # the RP2040's flash as the CPU sees it
UF2_PAYLOAD = 256

# VfsRom records (MicroPython extmod/vfs_rom.c; mpremote/romfs.py writes the same)
ROMFS_HEADER = b"\xd2\xcd\x31"
KIND_PADDING, KIND_DATA, KIND_POINTER, KIND_DIR, KIND_FILE = 1, 2, 3, 4, 5

# texel/main.py compiled as a module: the power-up the frozen main.py imports
# (frozen as texel/main.py in the firmware; here when the partition carries code)
BOOT_MODULE = "lib/texel/main.mpy"
CODE_SUFFIX = ".mpy"


def code_files(target: image.Target | None = None) -> dict[str, bytes]:
    """texelpad's code as the partition would carry it: the target's .mpy image
    (rp2 unless given) under lib/, and lib/texel/main.mpy (the power-up)."""
    target = target or image.TARGETS["rp2"]
    out = {f.remote.lstrip("/"): f.data for f in image.build_image(target, include_main=False)
           if f.remote.endswith(CODE_SUFFIX)}
    out[BOOT_MODULE] = image.compile_module(image.MAIN_PY, "texel/main.py")
    return out


def romfs_files(target: image.Target | None = None, code: bool = True,
                maps: bool | tuple[str, ...] = True, ram: bool = True) -> dict[str, bytes]:
    """The partition's files: texelpad's package data (the shipped boards of
    the port, reference_noise.bin), the references' flash maps (maps: all
    nine, or those named) and the generator's tables under lib/texel/, the
    rp2 RAM modules (ram); with code, code_files() too. The firmware freezes
    the code and carries the data only; `texelpad deploy` adds the code when
    this host's differs. The STM32 firmware's partition has the maps of
    image.MAP_NAMES and no RAM modules (build_stm32)."""
    target = target or image.TARGETS["rp2"]
    out = {f.remote.lstrip("/"): f.data for f in image.build_image(target, include_main=False)
           if not f.remote.endswith(CODE_SUFFIX)}
    if code:
        out.update(code_files(target))
    if ram:
        out.update(ram_modules())
    if maps:
        out.update(reference_maps(None if isinstance(maps, bool) else maps))
    out.update(const_tables())
    return out


def code_digest(target: image.Target | None = None) -> str:
    """sha256 of texelpad's code for the target (code_files, by path): what
    the firmware froze, recorded in its firmware.json, and what deploy
    compares with this host's."""
    import hashlib
    files = code_files(target)
    h = hashlib.sha256()
    for k in sorted(files):
        h.update(k.encode() + b"\0" + files[k])
    return h.hexdigest()


# Every viper module: not frozen but loaded from the ROMFS as texel_ram.<name>,
# which copies its native code into RAM at import; the frozen
# texel.runtime.<name> / texel.gen.<name> hands that module's names on
# (RAM_SHIM). Frozen native code would run from flash through the RP2040's XIP
# cache (slower on misses; the emulated Pico does not model it; hw/rp2.py's
# PWM-wrap vector wants the refresh in RAM) and, worse, MicroPython v1.28's
# mpy-tool aligns a frozen armv6m function to 2 bytes only, while the viper
# code loads its 32-bit constants PC-relative as if it started on 4: a
# function that lands 2 bytes off reads wrong constants and the board
# crashes (found when the brush's viper code grew and moved the generator's
# functions 2 bytes: the firmware no longer booted). Code loaded into RAM is
# word-aligned. tests/firmware/test_romfs.py checks the list is every viper
# module. Their relative imports become absolute.
RAM_MODULES = ("runtime/refresh_viper.py", "runtime/scene_viper.py", "gen/engine_int_viper.py",
               "gen/plan_int_viper.py", "gen/brush_viper.py", "gen/reference_viper.py")
RAM_PACKAGE = "texel_ram"
RAM_SHIM = b"""# texelpad firmware: this module's viper code runs from RAM, loaded from the ROMFS partition as
# %(pkg)s.%(name)s (host/texelpad/firmware/romfs.py RAM_MODULES); its names are handed on here.
import sys
from %(pkg)s import %(name)s as _m
sys.modules[__name__] = _m
globals().update(_m.__dict__)
"""


def _absolute(src: str, rel: str) -> str:
    """rel's source with its relative imports made absolute (texel.runtime.x)."""
    parts = ["texel"] + rel.split("/")[:-1]
    out = []
    for line in src.splitlines(keepends=True):
        stripped = line.lstrip()
        if stripped.startswith("from .") and " import " in stripped:
            dots = len(stripped[5:]) - len(stripped[5:].lstrip("."))
            rest = stripped[5 + dots:]
            base = parts[:len(parts) - dots + 1]
            mod = ".".join(base + ([rest.split(" import ")[0]] if not rest.startswith(" ") else []))
            line = line[:len(line) - len(stripped)] + "from %s import %s" % (
                mod, stripped.split(" import ", 1)[1])
        out.append(line)
    return "".join(out)


def ram_modules() -> dict[str, bytes]:
    """lib/texel_ram/<name>.mpy for RAM_MODULES (armv6m), and the package's __init__."""
    import tempfile
    from pathlib import Path
    out = {}
    with tempfile.TemporaryDirectory() as d:
        init = Path(d) / "__init__.py"
        init.write_text("# texelpad firmware: modules whose native code runs from RAM\n")
        out["lib/%s/__init__.mpy" % RAM_PACKAGE] = image.compile_module(
            init, "%s/__init__.py" % RAM_PACKAGE)
        for rel in RAM_MODULES:
            name = rel.rsplit("/", 1)[-1]
            src = Path(d) / name
            src.write_text(_absolute((image.PACKAGE_DIR / rel).read_text(), rel))
            out["lib/%s/%s" % (RAM_PACKAGE, name[:-3] + ".mpy")] = image.compile_module(
                src, "%s/%s" % (RAM_PACKAGE, name), march=image.TARGETS["rp2"].arch)
    return out


def frozen_sources(target: image.Target | None = None) -> dict[str, bytes]:
    """texel's .py sources the firmware freezes ({"texel/app.py": bytes}):
    the modules of the target's image (image.package_modules: its own
    hardware backend only, no image.HOST_ONLY module) and texel/main.py
    (imported only by the frozen main.py: it starts the display)."""
    target = target or image.TARGETS["rp2"]
    out = {}
    for p in image.package_modules(target.port):
        inner = p.relative_to(image.PACKAGE_DIR).as_posix()
        rel = "texel/" + inner
        # only the rp2 firmware loads its viper modules into RAM (RAM_MODULES): an
        # STM32F4 runs frozen Thumb-2 code from flash at zero wait states (ART)
        if inner in RAM_MODULES and target.port == "rp2":
            name = inner.rsplit("/", 1)[-1][:-3]
            out[rel] = RAM_SHIM % {b"pkg": RAM_PACKAGE.encode(), b"name": name.encode()}
        else:
            out[rel] = p.read_bytes()
    out["texel/main.py"] = image.MAIN_PY.read_bytes()
    return out


def const_tables() -> dict[str, bytes]:
    """The generator's constant tables beside their modules, aligned: the
    board reads them in place (texel.rom.const_table) instead of copying the
    frozen bytes literal into RAM (a frozen bytes object is not aligned)."""
    from array import array
    from texel.gen import brush, plan_int_tables, sine_table
    out = {"lib/texel/gen/sine_table.u16": bytes(sine_table._RAW),
           "lib/texel/gen/plan_int_tables.i32": bytes(plan_int_tables._RAW)}
    # the brush painter's (gen/brush.py TABLE_FILES), little-endian as the chip reads them
    for (name, code), values in zip(brush.TABLE_FILES, (brush.PHASE, brush.TW, brush.HANN,
                                                        brush.LOG2, brush.POS)):
        a = array(code, values)
        if sys.byteorder != "little":
            a.byteswap()
        out["lib/texel/gen/" + name] = a.tobytes()
    return out


def reference_maps(names: tuple[str, ...] | None = None) -> dict[str, bytes]:
    """lib/texel/gen/ref/<name>.u16 for the study's nine references (or those
    of `names`): the full-screen map (texel.gen.reference.FLASH_SAMPLES) as
    CPython renders it, little-endian; the firmware plays them in place
    (gen/reference.flash_u16), a stock Pico reads them (file_u16)."""
    import numpy as np
    from texel.gen import reference
    return {"lib/texel/gen/%s/%s.u16" % (reference.FLASH_DIR, n):
            np.asarray(reference.reference_u16(n, reference.FLASH_SAMPLES), dtype="<u2").tobytes()
            for n in (reference.STUDY_NAMES if names is None else names)}


def _uint(v: int) -> bytes:
    out = [v & 0x7F]
    v >>= 7
    while v:
        out.insert(0, 0x80 | (v & 0x7F))
        v >>= 7
    return bytes(out)


def _record(kind: int, payload: bytes) -> bytes:
    return _uint(kind) + _uint(len(payload)) + payload


ALIGN = 4                      # file data that code reads as words (the reference maps)
ALIGNED_SUFFIXES = (".u16", ".i16", ".i32")   # ... start on a 4-byte boundary (a Cortex-M0+ faults on an
                               # unaligned halfword load: viper's ptr16 does plain ldrh)
_LEN_BYTES = 5                 # the image's length field, fixed width (0x80 prefixes pad it)


def _fixed_uint(v: int, width: int) -> bytes:
    u = _uint(v)
    if len(u) > width:
        raise ValueError("romfs: %d bytes is too large" % v)
    return b"\x80" * (width - len(u)) + u


def _padding(n: int) -> bytes:
    """A PADDING record n bytes long (n = 0 or n >= 2)."""
    if n == 0:
        return b""
    return _record(KIND_PADDING, b"\0" * (n - 2))


def romfs_image(files: Mapping[str, bytes]) -> bytes:
    """A VfsRom filesystem holding files ({"lib/texel/app.mpy": bytes}),
    directories and names sorted (the same bytes for the same files). Files
    named *.u16, *.i16 and *.i32 keep their data at the top level, ALIGN-aligned from the
    image's start (which is where a partition starts: 4 KB aligned), and
    point to it; the rest is stored inline, as mpremote does."""
    head = len(ROMFS_HEADER) + _LEN_BYTES
    blobs = bytearray()
    where: dict[str, tuple[int, int]] = {}
    for path in sorted(files):
        if not path.endswith(ALIGNED_SUFFIXES):
            continue
        data = bytes(files[path])
        prefix = _uint(KIND_DATA) + _uint(len(data))
        at = head + len(blobs) + len(prefix)
        pad = -at % ALIGN
        if pad == 1:
            pad += ALIGN                 # the smallest record is 2 bytes
        blobs += _padding(pad) + prefix + data
        # a pointer counts from the body (MicroPython's VfsRom enters the
        # filesystem record: extmod/vfs_rom.c, self->filesystem)
        where[path] = (len(blobs) - len(data), len(data))
    tree: dict = {}
    for path, data in files.items():
        parts = path.strip("/").split("/")
        node = tree
        for p in parts[:-1]:
            node = node.setdefault(p, {})
            if not isinstance(node, dict):
                raise ValueError("romfs: %s is both a file and a folder" % p)
        node[parts[-1]] = where.get(path, bytes(data))

    def encode(node: dict) -> bytes:
        out = bytearray()
        for name in sorted(node):
            n = name.encode("ascii")
            v = node[name]
            if isinstance(v, dict):
                out += _record(KIND_DIR, _uint(len(n)) + n + encode(v))
            elif isinstance(v, tuple):   # (offset, size) of aligned top-level data
                out += _record(KIND_FILE, _uint(len(n)) + n
                               + _record(KIND_POINTER, _uint(v[1]) + _uint(v[0])))
            else:
                out += _record(KIND_FILE, _uint(len(n)) + n + _record(KIND_DATA, v))
        return bytes(out)

    body = bytes(blobs) + encode(tree)
    if (head + len(body)) % 2:          # an even total, as mpremote makes it
        body += _padding(3)
    return ROMFS_HEADER + _fixed_uint(len(body), _LEN_BYTES) + body


def read_romfs(img: bytes) -> dict[str, bytes]:
    """The files of a VfsRom image (the inverse of romfs_image; for tests and
    `texelpad deploy`'s comparison)."""
    if not img.startswith(ROMFS_HEADER):
        raise ValueError("not a ROMFS image")

    def uint(b: bytes, i: int) -> tuple[int, int]:
        v = 0
        while True:
            c = b[i]
            i += 1
            v = (v << 7) | (c & 0x7F)
            if not c & 0x80:
                return v, i

    n, i = uint(img, len(ROMFS_HEADER))
    body = i                                # pointers count from here
    out: dict[str, bytes] = {}

    def walk(i: int, end: int, prefix: str) -> None:
        while i < end:
            kind, i = uint(img, i)
            ln, i = uint(img, i)
            nxt = i + ln
            if kind in (KIND_DIR, KIND_FILE):
                nl, j = uint(img, i)
                name = img[j:j + nl].decode("ascii")
                j += nl
                if kind == KIND_DIR:
                    walk(j, nxt, prefix + name + "/")
                else:
                    k, j = uint(img, j)
                    dl, j = uint(img, j)
                    if k == KIND_DATA:
                        out[prefix + name] = bytes(img[j:j + dl])
                    else:
                        size, j = uint(img, j)
                        off, j = uint(img, j)
                        out[prefix + name] = bytes(img[body + off:body + off + size])
            i = nxt

    walk(i, i + n, "")
    return out


def read_uf2(data: bytes) -> list[tuple[int, bytes, int]]:
    """(flash address, payload, family) of each block of a .uf2 file;
    ValueError for anything that is not one."""
    if not data or len(data) % 512:
        raise ValueError("not a UF2 file: its size (%d bytes) is not a multiple of 512" % len(data))
    out = []
    for off in range(0, len(data), 512):
        m0, m1, flags, addr, size, _no, _n, fam = struct.unpack_from("<8I", data, off)
        (mend,) = struct.unpack_from("<I", data, off + 508)
        if (m0, m1, mend) != (UF2_MAGIC0, UF2_MAGIC1, UF2_MAGIC_END) or size > 476:
            raise ValueError("not a UF2 file: block %d is damaged" % (off // 512))
        out.append((addr, bytes(data[off + 32:off + 32 + size]), fam if flags & UF2_FLAG_FAMILY else 0))
    return out


def uf2_blocks(payload: bytes, base: int) -> list[tuple[int, bytes, int]]:
    """payload at flash address base as UF2 blocks (256 bytes each, the last
    one padded with 0xFF, as erased flash reads)."""
    out = []
    for off in range(0, len(payload), UF2_PAYLOAD):
        chunk = payload[off:off + UF2_PAYLOAD]
        out.append((base + off, chunk + b"\xff" * (UF2_PAYLOAD - len(chunk)), RP2040_FAMILY))
    return out


def write_uf2(blocks: Iterable[tuple[int, bytes, int]]) -> bytes:
    blocks = list(blocks)
    out = bytearray()
    for i, (addr, payload, fam) in enumerate(blocks):
        head = struct.pack("<8I", UF2_MAGIC0, UF2_MAGIC1, UF2_FLAG_FAMILY, addr, len(payload),
                           i, len(blocks), fam or RP2040_FAMILY)
        out += head + payload + b"\0" * (476 - len(payload)) + struct.pack("<I", UF2_MAGIC_END)
    return bytes(out)


def join_uf2(firmware: bytes, extra: Iterable[tuple[int, bytes, int]]) -> bytes:
    """The firmware's .uf2 with more blocks after it (renumbered as one file);
    ValueError where they overlap."""
    blocks = read_uf2(firmware)
    ends = [(a, a + len(p)) for a, p, _ in blocks]
    extra = list(extra)
    for a, p, _ in extra:
        for s, e in ends:
            if a < e and s < a + len(p):
                raise ValueError("the ROMFS blocks overlap the firmware at 0x%08x" % a)
    return write_uf2(blocks + extra)
