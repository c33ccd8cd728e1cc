"""What both firmware builds share (host/texelpad/firmware: build.py for rp2 boards, build_stm32.py
for STM32 boards): the versions, the frozen power-up, the C core's folder, the build name, the
result, the error, the ROMFS payload's last files, the logged run of a build step."""
from __future__ import annotations

import json
import subprocess
from dataclasses import dataclass
from pathlib import Path

from .. import __version__, image
from . import romfs

MICROPYTHON_VERSION = "1.28.0"
FROZEN_MAIN = Path(__file__).with_name("frozen_main.py")
FROZEN_BOOT = Path(__file__).with_name("frozen_boot.py")
FIRMWARE_INFO = "firmware.json"       # at the ROMFS root: /rom/firmware.json on the board
# The C core (MicroPython module _texelcore: texel.compat.core() finds it, and
# format 2's plan, the int engine and the brush painter run it where the
# firmware has it): device/cmod/texelcore in a checkout, beside the texel package.
TEXELCORE_DIR = image.PACKAGE_DIR.parent / "cmod" / "texelcore"


# The firmware's build name (sys.implementation._build on the board) is the
# staged board folder's: BUILD_PREFIX + the board's name in capitals.
BUILD_PREFIX = "TEXELPAD_"


def board_of_build(build: str) -> str | None:
    """The board a texelpad firmware was built for, from its build name
    ("TEXELPAD_PICO_BRIDGE" -> "pico_bridge"), or None for another firmware."""
    if not isinstance(build, str) or not build.startswith(BUILD_PREFIX):
        return None
    return build[len(BUILD_PREFIX):].lower() or None


class FirmwareError(Exception):
    """One line: what is wrong and what to do."""


@dataclass
class Built:
    image: Path                       # what a maker flashes: the .uf2 (rp2), the .dfu (stm32)
    romfs: Path
    elf: Path
    board: str
    firmware_bytes: int               # the MicroPython part (.bin)
    romfs_bytes: int                  # texelpad's image in the partition
    romfs_capacity: int
    romfs_base: int                   # flash offset (rp2) or address (stm32) of the partition
    storage_bytes: int                # the littlefs left for the user's files (rp2)
    seconds: float
    port: str = "rp2"
    qemu: bool = False                # the STM32 board's emulated twin (build_stm32)
    build_dir: Path | None = None     # the MicroPython build's own folder (stm32)

    @property
    def uf2(self) -> Path:
        """The .uf2 (rp2 boards)."""
        if self.port != "rp2":
            raise AttributeError("a %s firmware has no .uf2 (its image is %s)"
                                 % (self.port, self.image.name))
        return self.image


def finish_payload(name: str, board_json: bytes, files: dict[str, bytes], frozen_code: str,
                   code: bool) -> tuple[dict[str, bytes], bytes]:
    """files with the board file and firmware.json added, and their ROMFS image."""
    files["lib/texel/boards.d/%s.json" % name] = board_json
    info = {"board": name, "texelpad": __version__, "micropython": MICROPYTHON_VERSION,
            "frozen_code_sha256": frozen_code, "code_in_romfs": code,
            "image_sha256": image.hashlib.sha256(
                b"".join(k.encode() + v for k, v in sorted(files.items()))).hexdigest()}
    files[FIRMWARE_INFO] = (json.dumps(info, sort_keys=True) + "\n").encode()
    return files, romfs.romfs_image(files)


def run_logged(args: list[str], log: Path, env: dict | None = None) -> None:
    with open(log, "ab") as f:
        p = subprocess.run(args, stdout=f, stderr=subprocess.STDOUT, env=env)
    if p.returncode:
        tail = log.read_text(errors="replace").strip().splitlines()[-12:]
        raise FirmwareError("the MicroPython build failed (exit %d); the end of %s:\n  %s"
                            % (p.returncode, log, "\n  ".join(tail)))
