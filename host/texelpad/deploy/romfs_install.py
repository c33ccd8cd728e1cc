"""`texelpad deploy` on a board running the texelpad firmware: rewrite its ROMFS partition.

The texelpad firmware (texelpad.firmware, boards/) has texelpad's code frozen in and its data
(reference maps, board files) in a ROMFS partition, which the board reads as /rom. Its
/rom/firmware.json names the board and carries digests of the frozen code and of the
partition's files. deploy builds the partition this host would build for that board
(texelpad.firmware.build.payload_for): the data, plus this host's code when it differs from the
frozen code (or with force; the frozen boot.py then puts the ROMFS's code first on sys.path),
and when the partition's digest differs writes it with MicroPython's vfs.rom_ioctl (the calls
`mpremote romfs deploy` makes: erase, write 4 KB at a time, finish), then soft-resets and starts
again what played. No firmware rebuild.

While the partition is rewritten nothing of texelpad may run: its bytecode and maps are in
that flash. So the display is stopped, texel dropped from sys.modules and /rom unmounted
first; the writes are plain MicroPython (vfs, binascii). A deploy cut off half-way leaves a
partition without a valid image: the board then boots to its REPL saying so (frozen main.py)
and the next deploy writes it whole.
"""
from __future__ import annotations

import binascii
import json
import time
from typing import Any, Callable

from ..link import protocol
from ..link.transport import LinkError

CHUNK = 4096
INFO_PATH = "/rom/firmware.json"

FIRMWARE_INFO = """import sys
_t = None
try:
 import vfs
 if hasattr(vfs, 'rom_ioctl'):
  with open('%s') as _f:
   _t = _f.read()
except OSError:
 pass
print(repr((_t, getattr(sys.implementation, '_build', ''))))
""" % INFO_PATH


def firmware_info(board: Any) -> dict | None:
    """The texelpad firmware's /rom/firmware.json, or None (stock firmware).
    A texelpad firmware whose partition does not read (a deploy cut off
    half-way: the board then boots to its REPL) is known by its build name
    (texelpad.firmware.build.BUILD_PREFIX + the board): everything is unknown
    but the board, so the next deploy writes the partition whole."""
    from ..firmware.build import board_of_build
    if board.firmware.get("platform") != "rp2":
        return None
    text, build = board.link.eval(FIRMWARE_INFO)
    damaged = {"board": board_of_build(build), "image_sha256": None}
    if not text:
        return damaged if damaged["board"] else None
    try:
        info = json.loads(text)
    except ValueError:
        return damaged
    return info if isinstance(info, dict) else damaged


def frozen_stm32_board(board: Any) -> str | None:
    """The board of a texelpad firmware for an STM32 board (texelpad firmware --board pyboard:
    its code frozen in, its ROMFS partition written with it), or None (stock firmware)."""
    from ..firmware.build import board_of_build
    if board.firmware.get("platform") != "pyboard":
        return None
    _text, build = board.link.eval(FIRMWARE_INFO)
    return board_of_build(build)


def _board_json(board: Any, name: str) -> bytes:
    """The board file to carry: the shipped one of that name, else the one the
    partition holds now (a maker's own board, from `texelpad firmware --board-dir`)."""
    from .. import image
    shipped = image.BOARDS_DIR / (name + ".json")
    if shipped.is_file():
        return shipped.read_bytes()
    text = board.link.eval("with open('/rom/lib/texel/boards.d/%s.json') as _f:\n"
                           " print(repr(_f.read()))\n" % name)
    return text.encode()


def deploy_romfs(board: Any, info: dict, force: bool = False, dry_run: bool = False,
                 progress: Callable[[str], None] | None = None,
                 bar: Callable[[int, int, str], None] | None = None) -> dict[str, Any]:
    from ..firmware.build import payload_for
    from ..firmware.romfs import code_digest
    say = progress or (lambda m: None)
    t0 = time.perf_counter()
    name = info.get("board") or "pico"
    mine = code_digest()
    frozen = info.get("frozen_code_sha256")
    code = force or mine != frozen
    files, img = payload_for(name, _board_json(board, name), code=code, frozen_code=frozen or mine)
    want = json.loads(files["firmware.json"])["image_sha256"]
    current = info.get("image_sha256") == want
    report: dict[str, Any] = {
        "target": "rp2-romfs", "form": "romfs", "firmware": "texelpad", "board": name,
        "files": len(files), "image_bytes": len(img), "written": 0, "bytes_written": 0,
        "unchanged": len(files) if current and not force else 0, "removed": [],
        "dry_run": dry_run, "restarted": None, "playing": None, "code_in_romfs": code}
    say("texelpad firmware found (board %s, texelpad %s): %s; its ROMFS partition %s"
        % (name, info.get("texelpad", "?"),
           "its frozen code is this texelpad's" if mine == frozen else
           "this texelpad's code differs from the firmware's frozen copy: the partition gets "
           "this code too, which runs instead of the frozen one (with less heap free: flash a "
           "new texelpad-%s.uf2, texelpad firmware, to have it frozen)" % name,
           "holds what it should" if current else "is rewritten (%d bytes)" % len(img)))
    if (current and not force) or dry_run:
        report["seconds"] = time.perf_counter() - t0
        return report
    was = None
    st = board.status() if board.image is not None else {}
    if st.get("running"):
        was = (st["board"], board.scene_source())
        say("stopping the display on %s while the partition is written" % st["board"])
        board.stop()
    report["playing"] = was[0] if was else None
    _write_partition(board.link, img, say, bar)
    report["written"] = len(files)
    report["bytes_written"] = len(img)
    say("soft reset of %s: the new partition mounts at /rom" % board.port)
    board.link.soft_reset()
    got = firmware_info(board)
    if not got or got.get("image_sha256") != want:
        raise LinkError("the ROMFS partition did not read back as written (%r): run texelpad "
                        "deploy again" % (got,))
    if was is not None:
        say("starting %s again with the scene it played" % was[0])
        board.restart(was[0], was[1], False)
        report["restarted"] = was[0]
    report["playing"] = report["restarted"]
    report["seconds"] = time.perf_counter() - t0
    return report


def _write_partition(link: Any, img: bytes, say: Callable[[str], None],
                     bar: Callable[[int, int, str], None] | None) -> None:
    """Erase what img needs of the ROMFS partition and write img there, then
    read its head back (LinkError when it did not take)."""
    # nothing of texelpad may run from here on: its code is in the flash being rewritten
    link.exec(protocol.PURGE + "import vfs\ntry:\n vfs.umount('/rom')\nexcept OSError:\n pass\n")
    # the partition as rp2's block device (rp2.Flash: vfs.rom_ioctl(2, 0) on this port; the
    # other rom_ioctl calls answer -EINVAL here) - what `mpremote romfs deploy` does on rp2
    n_blocks, block = link.eval("import vfs\n_d = vfs.rom_ioctl(2, 0)\n"
                                "print(repr((_d.ioctl(4, 0), _d.ioctl(5, 0))))")
    size = n_blocks * block
    if len(img) > size:
        raise LinkError("texelpad's image (%d bytes) does not fit this board's ROMFS partition "
                        "(%d bytes): flash a newer texelpad firmware (texelpad firmware)"
                        % (len(img), size))
    used = -(-len(img) // block)
    say("erasing %d blocks of the ROMFS partition" % used)
    for k in range(used):              # BP_IOCTL_SEC_ERASE: 0 when done
        if link.eval("print(repr(_d.ioctl(6, %d)))" % k, timeout=60) not in (0, None):
            raise LinkError("erasing block %d of the ROMFS partition failed" % k)
    link.exec("from binascii import a2b_base64 as _b")
    for off in range(0, len(img), CHUNK):
        piece = img[off:off + CHUNK]
        piece += b"\xff" * (-len(piece) % 4)
        link.exec("_d.writeblocks(%d, _b(%r), %d)" % (
            off // block, binascii.b2a_base64(piece, newline=False).decode("ascii"), off % block),
            timeout=60)
        if bar:
            bar(min(off + CHUNK, len(img)), len(img), "ROMFS")
    # what the partition holds now, before anything is reset
    head = link.eval("print(repr(bytes(memoryview(_d)[:%d])))" % min(len(img), 64))
    if head != img[:len(head)]:
        raise LinkError("the ROMFS partition did not take the image (it reads %r)" % head[:16])
