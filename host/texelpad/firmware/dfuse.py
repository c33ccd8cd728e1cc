"""ST's DfuSe file format (.dfu) for `texelpad firmware --board pyboard` (pure: no build, no link).

    dfuse_file([(address, bytes), ...]) -> bytes      one target, one element per block
    read_dfuse(data) -> [(address, bytes), ...]       the inverse (checks the CRC)

What dfu-util (`dfu-util -a 0 -D file.dfu`) and MicroPython's tools/pydfu.py flash onto an
STM32 in its DFU bootloader (BOOT0 high): the pyboard's firmware (two blocks, 0x08000000 and
0x08020000) and texelpad's ROMFS partition (0x080C0000) in one file. The layout is the one
MicroPython v1.28's tools/dfu.py writes (ST's UM0391: prefix "DfuSe" v1, a "Target" prefix with
alternate setting 0, elements padded to 8 bytes, a 16-byte suffix "UFD" DFU 1.1a for USB
0483:df11, CRC-32 of everything before it stored as its one's complement);
tests/firmware/test_stm32_build.py checks it byte for byte against the stm32 port's own
firmware.dfu.
"""
from __future__ import annotations

import struct
import zlib

ST_DFU_VID, ST_DFU_PID = 0x0483, 0xDF11       # STM32's system bootloader in DFU mode
_PREFIX = "<5sBIB"
_TARGET = "<6sBI255s2I"
_ELEMENT = "<2I"
_SUFFIX = "<4H3sB"


def _crc(data: bytes) -> int:
    return 0xFFFFFFFF & (-zlib.crc32(data) - 1)


def dfuse_file(blocks: list[tuple[int, bytes]], vid: int = ST_DFU_VID,
               pid: int = ST_DFU_PID) -> bytes:
    """A DfuSe file writing each (flash address, bytes) block, in order."""
    if not blocks:
        raise ValueError("a .dfu needs at least one block")
    body = b""
    for address, data in blocks:
        if not 0 <= address <= 0xFFFFFFFF:
            raise ValueError("address 0x%x is not a 32-bit address" % address)
        data = bytes(data) + bytes((8 - len(data) % 8) % 8)
        body += struct.pack(_ELEMENT, address, len(data)) + data
    target = struct.pack(_TARGET, b"Target", 0, 1, b"ST...", len(body), len(blocks)) + body
    out = struct.pack(_PREFIX, b"DfuSe", 1, len(target) + 11, 1) + target
    out += struct.pack(_SUFFIX, 0, pid, vid, 0x011A, b"UFD", 16)
    return out + struct.pack("<I", _crc(out))


def read_dfuse(data: bytes) -> list[tuple[int, bytes]]:
    """The (address, bytes) blocks of a one-target DfuSe file (padding kept)."""
    n = struct.calcsize(_PREFIX)
    if len(data) < n + 16 or data[:5] != b"DfuSe":
        raise ValueError("not a DfuSe file")
    if struct.unpack("<I", data[-4:])[0] != _crc(data[:-4]):
        raise ValueError("DfuSe file: CRC mismatch (a damaged or cut file)")
    _sig, _ver, size, targets = struct.unpack(_PREFIX, data[:n])
    if targets != 1 or size != len(data) - 16:
        raise ValueError("DfuSe file: %d targets, image size %d (expected 1 target)"
                         % (targets, size))
    t = struct.calcsize(_TARGET)
    _tsig, _alt, _named, _name, tsize, elements = struct.unpack(_TARGET, data[n:n + t])
    pos, out = n + t, []
    for _ in range(elements):
        address, esize = struct.unpack(_ELEMENT, data[pos:pos + 8])
        out.append((address, data[pos + 8:pos + 8 + esize]))
        pos += 8 + esize
    if pos != n + t + tsize:
        raise ValueError("DfuSe file: its elements do not fill its target")
    return out
