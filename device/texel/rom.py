# What the texelpad firmware keeps in flash (host/texelpad/firmware, docs/firmware.md), and
# how texel reads it without copying it into RAM: files of its ROMFS partition (the reference
# maps, package data) and constants frozen into the firmware (the sine and plan tables). Kept
# out of compat.py so that images without flash data import nothing more; every function
# falls back to what other runtimes do (None, the path as it is, an array).
from .compat import ROM             # the texelpad firmware's port: data in ROMFS (compat.PORT_TABLE)
from array import array


def rom_view(path, typecode, n):
    """A read-only view ("H": uint16, "h": int16, "i": int32; index it, uctypes.addressof()
    it, hand it to viper's ptr16/ptr32; it has no len()) of the first n
    little-endian values of a file that the filesystem keeps in memory-mapped
    flash - a ROMFS file: MicroPython gives its bytes in place
    (extmod/vfs_rom_file.c has a buffer protocol), so the view takes no heap
    beyond a few words - or None: another filesystem (littlefs files have no
    buffer protocol), CPython, a port without uctypes or ROMFS, a file too
    short, data not 4-byte aligned (texelpad.firmware.romfs aligns them: a
    Cortex-M0+ faults on an unaligned load)."""
    try:
        import uctypes
        f = open(path, "rb")
    except (ImportError, OSError):
        return None
    try:
        mv = memoryview(f)
    except TypeError:
        f.close()
        return None
    kind, size = ((uctypes.UINT16, 2) if typecode == "H" else (uctypes.INT16, 2)
                  if typecode == "h" else (uctypes.INT32, 4))
    a = uctypes.addressof(mv)
    if len(mv) < size * n or a & 3:
        return None
    return uctypes.struct(a, {"v": (uctypes.ARRAY | 0, kind | n)}, uctypes.LITTLE_ENDIAN).v


def rom_u16(path, n):
    """rom_view(path, "H", n): the texelpad firmware's reference maps
    (texel/gen/ref/*.u16) play so."""
    return rom_view(path, "H", n)


# A module frozen into the texelpad firmware has a __file__ that names no file
# ("texel/gen/reference.py", relative, nothing there): its package data -
# boards.d, the reference maps, reference_noise.bin - is in the firmware's
# ROMFS partition under /rom/lib/texel (texelpad.firmware.romfs).
FROZEN_DATA = "/rom/lib/"


_BESIDE = {}                 # data_beside's answers, by module_file


def data_beside(module_file):
    """The path a package data file beside module_file is read at: the
    module's own when it is a file, the ROMFS's copy for a frozen module.
    Worked out once per module: `import os` searches the filesystem for an
    os.py first on every call (os is an extensible built-in), 2.0 ms of each
    call on the emulated Pico."""
    here = _BESIDE.get(module_file)
    if here is None:
        here = _beside(module_file)
        _BESIDE[module_file] = here
    return here


def _beside(module_file):
    if not ROM or module_file.startswith("/"):
        return module_file              # not the firmware's chip, or a real file's path
    try:
        import os
        os.stat(module_file)
        return module_file              # relative to the working directory, and there
    except (ImportError, OSError):
        pass
    if module_file.startswith(".frozen/"):
        module_file = module_file[len(".frozen/"):]
    return FROZEN_DATA + module_file


def path_beside(module_file, name):
    """The path of data file name beside the module module_file (its
    __file__), where data_beside says it is read."""
    here = data_beside(module_file)
    cut = max(here.rfind("/"), here.rfind("\\"))
    return here[:cut + 1] + name


def const_table(module_file, name, raw, typecode):
    """A read-only table of little-endian values ("H": uint16, "h": int16,
    "i": int32): the texelpad firmware's copy of raw (its bytes, or a tuple of
    its values) in its ROMFS partition (name beside module_file, the module
    that holds raw: texelpad.firmware.romfs puts it there, aligned) as a
    rom_view - no RAM - where there is one; else array(typecode, raw), as on
    every other image."""
    if ROM:
        n = len(raw) if isinstance(raw, tuple) else len(raw) // (4 if typecode == "i" else 2)
        v = rom_view(path_beside(module_file, name), typecode, n)
        if v is not None:
            return v
    if not isinstance(raw, tuple) and typecode in ("H", "i"):
        # no copy in the partition (a ROMFS another tool wrote: a stock pyboard's): a view
        # of the module's own literal where it is aligned, as without ROM (compat.const_view)
        from .compat import const_view
        return const_view(raw, typecode)
    return array(typecode, raw)
