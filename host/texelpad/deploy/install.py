"""`texelpad deploy`: put the device image on a board over the link.

The image (texelpad.image) is compiled for the board's own .mpy format and
architecture, read from sys.implementation at the handshake. Only files
whose sha256 on the board differs are written; each is written beside its
old copy and renamed over it, so an interrupted deploy leaves every module
either old or new, never half-written. Before writing, the space the new
files need is checked against the board's free space.

A display that is playing is stopped first (flash writes stall the timer IRQ
on an RP2040), the texel modules are dropped from sys.modules, and the same
board and scene are started again from the new image: nothing the board
played is lost, and no soft reset is needed.
"""
from __future__ import annotations

import time
from typing import Any, Callable

from . import image
from ..link import protocol
from ..link.transport import LinkError

# Filesystems allocate whole blocks: count each file as its size rounded up to
# 4 KB (littlefs on an RP2040) plus one block, so "fits" means it fits.
BLOCK = 4096



def _blocks(n: int) -> int:
    return (n + BLOCK - 1) // BLOCK * BLOCK + BLOCK


def on_board(board: Any) -> Callable[[str], str]:
    """Image path ("/lib/texel/app.mpy") -> the path to use on this board.
    The unix port (the virtual board) has the host's filesystem: its "/" is
    its flash folder, the working directory, so paths go relative there."""
    if board.firmware["platform"] in ("linux", "darwin", "win32"):
        return lambda p: p.lstrip("/")
    return lambda p: p


def survey(board: Any, files: list[image.ImageFile]) -> tuple[dict, list[str], int | None]:
    """{image path: sha256 hex, '' or None}, the files under the package
    directory (image paths), free bytes (None: unknown)."""
    dev = on_board(board)
    paths = [dev(f.remote) for f in files]
    hashes, present, free = board.link.eval(
        protocol.survey(paths, dev(image.REMOTE_PACKAGE)), timeout=60)
    back = {dev(f.remote): f.remote for f in files}
    lead = "" if dev("/x") == "/x" else "/"
    return ({back[p]: h for p, h in hashes.items()}, [lead + p for p in present], free)


def _mkdirs(board: Any, path: str) -> None:
    parts = path.strip("/").split("/")[:-1]
    lead = "/" if path.startswith("/") else ""
    board.link.exec(protocol.mkdirs([lead + "/".join(parts[:i + 1]) for i in range(len(parts))]))


def deploy(board: Any, source: bool = False, include_main: bool = True, dry_run: bool = False,
           progress: Callable[[str], None] | None = None,
           bar: Callable[[int, int, str], None] | None = None) -> dict[str, Any]:
    """Deploy the image to `board` (a Board from connect(port, check=False)).
    progress: one-line messages; bar(done_bytes, total_bytes, file): upload
    progress. Returns what was done. Raises image.ImageError when the image
    cannot go on this board (too old, other .mpy format, does not fit)."""
    say = progress or (lambda m: None)
    t_start = time.perf_counter()
    fw = board.firmware
    target = image.target_for(fw["implementation"], fw["mpy"], fw["version"], fw["platform"],
                              source=source)
    files = image.build_image(target, include_main=include_main)
    hashes, present, free = survey(board, files)
    todo = image.plan_upload(files, {p: (h or None) for p, h in hashes.items()})
    if any(h == "" for h in hashes.values()):        # no hashlib: cannot compare, write all
        todo = list(files)
    stale = image.plan_remove(files, present)
    need = sum(_blocks(f.size) for f in todo)
    total = sum(f.size for f in todo)
    report: dict[str, Any] = {
        "target": target.name, "form": target.form, "arch": target.arch, "files": len(files),
        "image_bytes": image.image_bytes(files), "written": 0, "bytes_written": 0,
        "removed": stale, "unchanged": len(files) - len(todo), "free_bytes": free,
        "restarted": None, "dry_run": dry_run}
    say("%s image: %d files, %d bytes; %d to write (%d bytes), %d unchanged, %d stale"
        % (target.name, len(files), report["image_bytes"], len(todo), total,
           report["unchanged"], len(stale)))
    if free is not None and need > free:
        raise image.ImageError(
            "the image does not fit: writing %d files needs about %d bytes (in %d-byte blocks) "
            "and the board has %d free; delete files from the board (mpremote fs ls :) or "
            "deploy --no-main" % (len(todo), need, BLOCK, free))
    if dry_run or (not todo and not stale):
        report["seconds"] = time.perf_counter() - t_start
        return report

    # stop a playing display, remembering what it played
    was = None
    if board.image is not None:
        st = board.status()
        if st.get("running"):
            was = (st["board"], board.scene_source(), st["port"] == "virtual")
            say("stopping the display on %s while the image is written" % st["board"])
            board.stop()

    done = 0
    dev = on_board(board)
    for f in todo:
        path = dev(f.remote)
        _mkdirs(board, path)
        tmp = path + ".new"

        def step(n: int, f: image.ImageFile = f) -> None:
            if bar:
                bar(done + n, total, f.remote)
        board.link.write_file(tmp, f.data, progress=step)
        board.link.exec(protocol.replace_file(path, tmp))
        done += f.size
        report["written"] += 1
        report["bytes_written"] += f.size
    for p in stale:
        board.link.exec(protocol.remove_file(dev(p)))
    # the new image: check what the board now holds
    hashes, _, _ = survey(board, files)
    bad = [f.remote for f in files if hashes.get(f.remote) not in (f.sha256, "")]
    if bad:
        raise LinkError("deploy: %d files did not arrive intact (%s); run deploy again"
                        % (len(bad), ", ".join(bad[:3])))
    board.link.exec(protocol.PURGE)
    if was is not None:
        name, scene, virtual = was
        say("starting %s again with the new image and the scene it played" % name)
        # a fresh import on the board: the modules were dropped above
        board.link.exec(protocol.restart(name, scene, virtual), timeout=60)
        report["restarted"] = name
    report["seconds"] = time.perf_counter() - t_start
    return report
