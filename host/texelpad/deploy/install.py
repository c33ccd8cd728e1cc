"""`texelpad deploy`: put the device image on a board over the link.

The image (texelpad.image) is compiled for the board's own .mpy format and
architecture, read from sys.implementation at the handshake. Only files
whose sha256 on the board differs are written; each is written beside its
old copy ("<file>.new") and renamed over it, so an interrupted deploy leaves
every module either old or new, never half-written.

Every deploy repairs an interrupted one: its leftover "<file>.new" files are
found by the survey, completed (renamed into place) when their hash is the
image's, removed otherwise; files whose hash differs are rewritten.

Nothing changes on the board until every check passed, while a playing
display keeps playing: the image fits the free space, and each path can be
written (no file where a folder must be, a probe file can be created).
Then a playing display is stopped (flash writes stall the timer IRQ on an
RP2040), the files are written, the texel modules are dropped from
sys.modules, and the same board and scene are started again from the new
image: nothing the board played is lost, and no soft reset is needed. If
anything fails after the display was stopped, the display is started again
with the code still in the board's memory, and DeployFailed says what the
board holds and what to run.
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from typing import Any, Callable

from .. import image
from ..link import protocol
from ..link.board import UNIX_PLATFORMS, on_board_path
from ..link.transport import BoardError, LinkError, LinkTimeout

# Filesystems allocate whole blocks: count each file as its size rounded up to
# 4 KB (littlefs on an RP2040) plus one block, so "fits" means it fits.
BLOCK = 4096
# A file is written as "<path>.new" then renamed over "<path>".
TMP = ".new"
ERRNO = {2: "ENOENT", 13: "EACCES", 20: "ENOTDIR", 21: "EISDIR", 28: "ENOSPC", 30: "EROFS"}


class DeployFailed(LinkError):
    """A deploy that failed after it began changing the board: the text says
    what the board holds, whether its display plays, and what to run."""


def _blocks(n: int) -> int:
    return (n + BLOCK - 1) // BLOCK * BLOCK + BLOCK


def on_board(board: Any) -> Callable[[str], str]:
    """Image path ("/lib/texel/app.mpy") -> the path to use on this board.
    The unix port (the virtual board) has the host's filesystem: its "/" is
    its flash folder, the working directory, so paths go relative there."""
    return lambda p: on_board_path(board, p)


SURVEY_BATCH = 12           # paths per survey request on CircuitPython (survey)


def survey(board: Any, files: list[image.ImageFile]) -> tuple[dict, list[str], int | None]:
    """{image path: sha256 hex, '' or None}, also for each file's leftover
    "<path>.new" of an interrupted deploy; the files under the package
    directory (image paths); free bytes (None: unknown)."""
    dev = on_board(board)
    back = {dev(f.remote): f.remote for f in files}
    back.update({dev(f.remote) + TMP: f.remote + TMP for f in files})
    paths = list(back)
    # One round trip on MicroPython; CircuitPython's heap (with its modules compiled
    # from source and a scene playing) has no block for a 100-path request and its
    # answer: SURVEY_BATCH paths a request there, the package listed with the last.
    # A stock Pico playing its power-up scene may have no block for the one request
    # either (8.3 KB for the 63 files with the reference maps): it is asked again so.
    step = SURVEY_BATCH if board.firmware["implementation"] == "circuitpython" else len(paths)
    hashes, present, free = {}, [], None
    i = 0
    while i < len(paths):
        last = i + step >= len(paths)
        try:
            h, p, free = board.link.eval(protocol.survey(
                paths[i:i + step], dev(image.REMOTE_PACKAGE) if last else ""), timeout=60)
        except BoardError as e:
            if "MemoryError" not in e.traceback:
                raise
            if step > SURVEY_BATCH:
                step = SURVEY_BATCH
                continue
            raise image.ImageError(
                "cannot deploy: %s has too little free memory to survey its files (%s); stop "
                "its display (texelpad stop --port %s) or reset it, then deploy again; nothing "
                "was changed" % (board.port, str(e).split(": ", 1)[-1], board.port)) from None
        hashes.update(h)
        present += p
        i += step
    lead = "" if dev("/x") == "/x" else "/"
    return ({back[p]: h for p, h in hashes.items()}, [lead + p for p in present], free)


def _mkdirs(board: Any, path: str) -> None:
    parts = path.strip("/").split("/")[:-1]
    lead = "/" if path.startswith("/") else ""
    board.link.exec(protocol.mkdirs([lead + "/".join(parts[:i + 1]) for i in range(len(parts))]))


def _one_line(e: BaseException) -> str:
    """An error as one line: a board traceback as its last line."""
    text = " ".join(ln.strip() for ln in str(e).splitlines() if ln.strip())
    head = "the board raised an error: "        # transport.BoardError, one line already
    if text.startswith(head):
        return "the board raised " + text[len(head):]
    return text or type(e).__name__


def _errno_text(n: int) -> str:
    return "OSError %d%s" % (n, " " + ERRNO[n] if n in ERRNO else "")


def preflight(board: Any, todo: list[image.ImageFile], touched: list[str],
              probe: bool = True) -> None:
    """Raise ImageError unless the image can be written: no file where a
    folder must be, no folder where a file must be, and each folder a file
    goes into (or its deepest existing ancestor) takes a new file (probe=True
    writes and removes a small file there; a dry run only looks). Runs while
    the display still plays: a refused deploy changes nothing."""
    dev = on_board(board)
    root = "/" if dev("/x") == "/x" else "."

    def show(p: str) -> str:
        return p if p.startswith("/") else "/" + p
    folders = sorted({"/".join(f.remote.split("/")[:i])
                      for f in todo for i in range(2, f.remote.count("/") + 1)})
    paths = [dev(p) for p in folders] + [dev(f.remote) for f in todo]
    dirs = sorted({dev(p).rpartition("/")[0] for p in [f.remote for f in todo] + touched})
    kinds, writable = board.link.eval(protocol.preflight(paths, dirs, root, probe), timeout=60)
    port = board.port
    for p in folders:
        if kinds.get(dev(p)) == "f":
            raise image.ImageError(
                "cannot deploy: %s on the board is a file, where the image needs a folder; "
                "remove it (mpremote connect %s rm :%s) and deploy again" % (p, port, p))
    for f in todo:
        if kinds.get(dev(f.remote)) == "d":
            raise image.ImageError(
                "cannot deploy: %s on the board is a folder, where the image has a file; "
                "remove it (mpremote connect %s rm -r :%s) and deploy again"
                % (f.remote, port, f.remote))
    for d, err in sorted(writable.items()):
        if err is None:
            continue
        where = show(d) if d else "/"
        if err == 20:
            raise image.ImageError(
                "cannot deploy: %s on the board is a file, where the image needs a folder; "
                "remove it (mpremote connect %s rm :%s) and deploy again" % (where, port, where))
        hint = "its filesystem is read-only" if err == 30 else \
            "its filesystem is full" if err == 28 else "the board refuses new files there"
        if board.firmware["implementation"] == "circuitpython" and err in (30, 13):
            hint += (" (CircuitPython: code cannot write while the CIRCUITPY drive is mounted "
                     "by the computer; eject it, or make the filesystem writable for code in "
                     "boot.py with storage.remount('/', readonly=False), and reset the board)")
        raise image.ImageError("cannot deploy: the board cannot write to %s (%s): %s; nothing "
                               "was changed" % (where, _errno_text(err), hint))


@dataclass
class Plan:
    """What a deploy does to the board, found by the survey before anything
    changes: the files to write, the leftovers to complete or drop, the stale
    files to remove; what the display played; the report it fills in."""
    target: image.Target
    files: list[image.ImageFile]        # the whole image (checked after the writes)
    todo: list[image.ImageFile]         # to write: new, or their hash differs
    complete: list[image.ImageFile]     # their "<file>.new" is the image's: renamed into place
    drop: list[str]                     # leftover ".new" files to remove
    stale: list[str]                    # board files the image no longer has
    leftovers: list[str]                # every ".new" an interrupted deploy left
    free: int | None                    # free bytes on the board (None: unknown)
    need: int                           # bytes the writes take, in whole blocks
    total: int                          # bytes to write (the upload bar's total)
    was: tuple | None                   # (board, scene, virtual) the display played
    report: dict[str, Any]

    @property
    def changes(self) -> bool:
        """Whether the board needs anything: a file to write, a leftover, a stale file."""
        return bool(self.todo or self.stale or self.leftovers)


def deploy(board: Any, source: bool = False, include_main: bool = True, dry_run: bool = False,
           progress: Callable[[str], None] | None = None,
           bar: Callable[[int, int, str], None] | None = None,
           force: bool = False, maps: bool = True) -> dict[str, Any]:
    """Deploy the image to `board` (a Board from connect(port, check=False)).
    progress: one-line messages; bar(done_bytes, total_bytes, file): upload
    progress. maps: with the reference maps where the port takes them
    (with_reference_maps; False removes any a board holds). Returns what was
    done. Raises image.ImageError, before anything
    on the board changed, when the image cannot go on this board (too old,
    other .mpy format, does not fit, a path cannot be written); DeployFailed
    when it failed after it changed the board (its text says what state the
    board is in and what to run); other LinkErrors when the board could not
    even be surveyed."""
    say = progress or (lambda m: None)
    t_start = time.perf_counter()
    fw = board.firmware
    from .romfs_install import frozen_stm32_board
    frozen = frozen_stm32_board(board)
    if frozen:                              # its frozen code would shadow files deployed
        raise image.ImageError(
                "%s runs the texelpad firmware for board %s: texelpad's code is frozen in it, "
                "so files deployed to its filesystem would never run. To update it, build "
                "and flash a new one: texelpad firmware --board %s, then dfu-util -a 0 -D "
                "firmware/texelpad-%s.dfu (docs/firmware.md, \"pyboard\")"
                % (board.port, frozen, frozen, frozen))
    if not source:
        from .romfs_install import deploy_romfs, firmware_info
        info = firmware_info(board)
        if info is not None:                # the texelpad firmware: texelpad is its ROMFS
            return deploy_romfs(board, info, force=force, dry_run=dry_run, progress=say, bar=bar)
        if fw.get("platform") == "rp2":
            say("stock MicroPython found: the image goes into its filesystem as .mpy files "
                "(the texelpad firmware keeps it in flash instead: texelpad firmware, "
                "docs/firmware.md)")
    target = image.target_for(fw["implementation"], fw["mpy"], fw["version"], fw["platform"],
                              source=source)
    files = with_native_core(image.build_image(target, include_main=include_main), target, say)
    if maps:
        files = with_reference_maps(files, target, say)
    plan = plan_deploy(board, target, files, include_main=include_main, dry_run=dry_run, say=say)
    say_plan(plan, say)
    check_fits(plan)
    if plan.changes:
        if fw["implementation"] == "circuitpython" and not dry_run:
            _writable_for_code(board, say)
        preflight(board, plan.todo, plan.leftovers + plan.stale, probe=not dry_run)
        if not dry_run:
            write_plan(board, plan, say, bar)
            restart_what_played(board, plan, say)
    plan.report["seconds"] = time.perf_counter() - t_start
    return plan.report


def with_native_core(files: list[image.ImageFile], target: image.Target,
                     say: Callable[[str], None]) -> list[image.ImageFile]:
    """The image plus the C core as a native module (/lib/_texelcore.mpy,
    texelpad.firmware.natmod) where the board's architecture has one, before
    /main.py (the last file: an interrupted deploy never leaves a power-up
    script without what it imports). Without one the board runs the viper and
    Python twins of the same loops (say tells why)."""
    if target.form != "mpy":
        return files
    from ..firmware import natmod
    if target.arch not in natmod.ARCHS:
        return files
    f = natmod.native_module(target.arch, say)
    if f is None:
        return files
    data = f.read_bytes()
    nat = image.ImageFile(natmod.REMOTE, data, hashlib.sha256(data).hexdigest(), f)
    say("with the C core as a native module for %s (%s, %d bytes)"
        % (target.arch, natmod.REMOTE, len(data)))
    return _before_main(files, [nat])


def _before_main(files: list[image.ImageFile],
                 more: list[image.ImageFile]) -> list[image.ImageFile]:
    """files with `more` before /main.py (the last file, when it is there: an
    interrupted deploy never leaves a power-up script without what it needs)."""
    k = len(files)
    if files and files[-1].remote == image.REMOTE_MAIN:
        k -= 1
    return files[:k] + more + files[k:]


def with_reference_maps(files: list[image.ImageFile], target: image.Target,
                        say: Callable[[str], None]) -> list[image.ImageFile]:
    """The image plus the reference maps that are slow to render
    (image.MAP_NAMES) on a port that takes them (image.MAP_PORTS: a stock
    RP2040), before /main.py: the full-screen maps as this host renders them
    (binary64; texelpad.firmware.romfs reference_maps, the firmware's ROMFS
    files), which a reference region reads into its RAM instead of rendering
    (texel/gen/reference.py file_u16: ~12 ms for a full screen on the emulated
    stock Pico, where rendering took 0.96-1.59 s).
    Written once: a later deploy finds their hashes unchanged."""
    if target.port not in image.MAP_PORTS:
        return files
    from ..firmware.romfs import reference_maps
    src = image.PACKAGE_DIR / "gen" / "reference.py"
    maps = [image.ImageFile("/" + p, d, hashlib.sha256(d).hexdigest(), src)
            for p, d in sorted(reference_maps(image.MAP_NAMES).items())]
    say("with the reference maps of %s (%s bytes; --no-maps renders them on the board)"
        % (", ".join(image.MAP_NAMES), format(sum(m.size for m in maps), ",")))
    return _before_main(files, maps)


def plan_deploy(board: Any, target: image.Target, files: list[image.ImageFile],
                include_main: bool, dry_run: bool, say: Callable[[str], None]) -> Plan:
    """Survey the board and plan the deploy: which files to write, complete,
    drop and remove, the report's fields, and what the display plays. Reads
    only: the board is as it was."""
    hashes, present, free = survey(board, files)
    todo = image.plan_upload(files, {p: (h or None) for p, h in hashes.items()})
    if any(h == "" for h in hashes.values()):        # no hashlib: cannot compare, write all
        todo = list(files)
    # An interrupted deploy's leftovers: "<file>.new" beside image files (found
    # by the survey's hashes) and any ".new" under the package directory. One
    # whose hash is the image's completes its file (renamed over it); the rest
    # are removed (their files are rewritten when their hashes differ).
    leftovers = sorted({p for p, h in hashes.items() if p.endswith(TMP) and h is not None}
                       | {p for p in present if p.endswith(TMP)
                          and p.startswith(image.REMOTE_PACKAGE + "/")})
    complete = [f for f in todo if hashes.get(f.remote + TMP) == f.sha256]
    done_by_rename = {f.remote for f in complete}
    todo = [f for f in todo if f.remote not in done_by_rename]
    drop = [p for p in leftovers if p[:-len(TMP)] not in done_by_rename]
    stale = [p for p in image.plan_remove(files, present) if p not in leftovers]
    names = [p.stem for p in image.board_files(target.port)]
    report: dict[str, Any] = {
        "target": target.name, "form": target.form, "arch": target.arch, "files": len(files),
        "image_bytes": image.image_bytes(files), "written": 0, "bytes_written": 0,
        "removed": stale, "unchanged": len(files) - len(todo) - len(complete),
        "free_bytes": free, "repaired": {"completed": [f.remote for f in complete],
                                         "removed": drop},
        "restarted": None, "playing": None, "dry_run": dry_run, "board_port": target.port,
        "boards": names, "main": include_main}
    was = what_plays(board, say)
    report["playing"] = was[0] if was else None
    return Plan(target=target, files=files, todo=todo, complete=complete, drop=drop,
                stale=stale, leftovers=leftovers, free=free,
                need=sum(_blocks(f.size) for f in todo), total=sum(f.size for f in todo),
                was=was, report=report)


def what_plays(board: Any, say: Callable[[str], None]) -> tuple | None:
    """(board, scene, virtual) the display plays, or None."""
    # what the display plays (read only: it keeps playing until every check passed)
    was = None
    if board.image is not None:
        try:
            st = board.status()
            if st.get("running"):
                was = (st["board"], board.scene_source(), st["port"] == "virtual")
        except LinkTimeout:
            raise
        except LinkError as e:
            # an image too old or broken to answer: nothing to restart
            say("could not read the display's state (%s); deploying without stopping it"
                % _one_line(e))
    return was


def say_plan(plan: Plan, say: Callable[[str], None]) -> None:
    """Say what the deploy will write and repair."""
    report, todo, leftovers = plan.report, plan.todo, plan.leftovers
    say("%s image: %d files, %d bytes; %d to write (%d bytes), %d unchanged, %d stale"
        % (plan.target.name, len(plan.files), report["image_bytes"], len(todo), plan.total,
           report["unchanged"], len(plan.stale)))
    if leftovers:
        say("an interrupted deploy left %d .new file%s: %d complete%s (renamed into place), "
            "%d to remove" % (len(leftovers), "" if len(leftovers) == 1 else "s",
                              len(plan.complete), "" if len(plan.complete) == 1 else "s",
                              len(plan.drop)))


def check_fits(plan: Plan) -> None:
    """Raise ImageError, before anything changed, when the writes do not fit
    the board's free space (when the board says it)."""
    if plan.free is not None and plan.need > plan.free:
        maps = sum(f.size for f in plan.todo if f.remote.endswith(".u16"))
        raise image.ImageError(
            "the image does not fit: writing %d files needs about %d bytes (in %d-byte blocks) "
            "and the board has %d free; delete files from the board (mpremote fs ls :) or "
            "deploy --no-main%s" % (len(plan.todo), plan.need, BLOCK, plan.free,
                                    " or --no-maps (the reference maps: %s bytes)"
                                    % format(maps, ",") if maps else ""))


def _writable_for_code(board: Any, say: Callable[[str], None]) -> None:
    """CircuitPython: its CIRCUITPY drive is read-only to code by default;
    storage.remount('/', readonly=False) lends it to code where no computer
    has it mounted (a board whose drive is hidden, the emulated one). Where
    one has, the remount is refused and preflight's EROFS says what to do."""
    if board.link.eval(protocol.FOREIGN_CODE_PY, timeout=30):
        say("CircuitPython runs /code.py before /main.py: this board has a /code.py, so "
            "texelpad's /main.py will not start at power-up (rename or remove code.py, or use "
            "texelpad firmware --circuitpython's code.py)")
    why = board.link.eval(protocol.REMOUNT_WRITABLE, timeout=30)
    if why:
        say("CircuitPython: the drive stays read-only to code (%s)" % why)
    else:
        say("CircuitPython: the drive remounted writable for code (storage.remount), "
            "auto-reload off, until the board resets")


def write_plan(board: Any, plan: Plan, say: Callable[[str], None],
               bar: Callable[[int, int, str], None] | None) -> None:
    """Carry out the plan: stop a playing display, complete and drop the
    leftovers, write the files, remove the stale ones, check what the board
    now holds, drop the texel modules and (not on the virtual board) soft-reset.
    On any failure: start the display again (_recover) and raise DeployFailed
    saying what the board holds (a Ctrl-C is said, then raised again)."""
    dev = on_board(board)
    report = plan.report
    done = 0
    current = "the survey"
    try:
        # stop a playing display (flash writes stall the timer IRQ on an RP2040)
        if plan.was is not None:
            current = "stopping the display"
            say("stopping the display on %s while the image is written" % plan.was[0])
            board.stop()
        for f in plan.complete:
            current = f.remote
            board.link.exec(protocol.replace_file(dev(f.remote), dev(f.remote) + TMP))
        if plan.drop:
            current = "removing leftover .new files"
            board.link.exec(protocol.remove_files([dev(p) for p in plan.drop]))
        for f in plan.todo:
            current = f.remote

            def step(n: int, f: image.ImageFile = f) -> None:
                if bar:
                    bar(done + n, plan.total, f.remote)
            _write_file(board, dev(f.remote), f.data, step)
            done += f.size
            report["written"] += 1
            report["bytes_written"] += f.size
        if plan.stale:
            current = "removing stale files"
            board.link.exec(protocol.remove_files([dev(p) for p in plan.stale]))
        # the new image: check what the board now holds
        current = "checking the new image"
        _check_written(board, plan.files)
        board.link.exec(protocol.PURGE)
        if board.firmware["platform"] not in UNIX_PLATFORMS:     # not the virtual board
            # A clean heap for the new image: deploying leaves a board's heap
            # fragmented (interned paths, the hashing), and on the emulated
            # Pico the next start then failed with 137 KB free and no 19 KB
            # block for the split screen. From the raw REPL a soft reset does
            # not run main.py: nothing starts that was not playing.
            current = "resetting the board (a soft reset: a clean heap)"
            say("soft reset of %s: a clean heap for the new image" % board.port)
            board.link.soft_reset()
    except BaseException as e:
        state = _recover(board, plan.was, report, len(plan.todo) + len(plan.complete))
        text = "deploy to %s failed at %s: %s. %s" % (board.port, current, _one_line(e), state)
        if not isinstance(e, Exception):            # Ctrl-C: say it, then let it end the run
            say(text)
            raise
        raise DeployFailed(text) from None


def _write_file(board: Any, path: str, data: bytes, progress: Callable[[int], None]) -> None:
    """Write `data` as "<path>.new" beside the old copy and rename it over
    `path`: the file is old or new, never half-written."""
    _mkdirs(board, path)
    tmp = path + TMP
    board.link.write_file(tmp, data, progress=progress)
    board.link.exec(protocol.replace_file(path, tmp))


def _check_written(board: Any, files: list[image.ImageFile]) -> None:
    """Raise LinkError unless every image file on the board has the image's
    hash ('': the board cannot hash) and no ".new" is left."""
    hashes, present, _ = survey(board, files)
    bad = [f.remote for f in files if hashes.get(f.remote) not in (f.sha256, "")]
    bad += [p for p, h in hashes.items() if p.endswith(TMP) and h is not None]
    if bad:
        raise LinkError("%d files did not arrive intact (%s)" % (len(bad), ", ".join(bad[:3])))


def restart_what_played(board: Any, plan: Plan, say: Callable[[str], None]) -> None:
    """Start the display again on the new image if it played; the report says
    what plays now."""
    if plan.was is not None:
        plan.report["restarted"] = _restart(board, plan.was, say)
    plan.report["playing"] = plan.report["restarted"]


def _recover(board: Any, was: tuple | None, report: dict[str, Any], planned: int) -> str:
    """After a failure mid-deploy: start the display again if it played, and
    say what state the board is in and what to run. No PURGE: the modules
    still in the board's memory are the code that played it (the files on
    the board may be a mix of old and new); after a reset they are imported
    from the files, which are each whole."""
    port = board.port
    files = ("The board's files are each whole, old or new (%d of %d written, none "
             "half-written): run texelpad deploy --port %s again to finish; it repairs the rest."
             % (report["written"], planned, port))
    if was is None:
        return "The display was not playing. " + files
    name, scene, virtual = was
    try:
        board.link.resync()             # drop a request cut off half-way (Ctrl-C, raw REPL)
        board.restart(name, scene, virtual)
    except Exception as e:
        return ("The display is OFF: it played %s, was stopped for the deploy, and starting it "
                "again failed (%s). %s Then start it: texelpad demo --port %s --board %s."
                % (name, _one_line(e), files, port, name))
    return "The display plays again (%s, the scene it played). %s" % (name, files)


def _restart(board: Any, was: tuple, say: Callable[[str], None]) -> str:
    """Start the display again on the new image with the scene it played (or,
    if the new image refuses that scene, its default scene)."""
    name, scene, virtual = was
    say("starting %s again with the new image and the scene it played" % name)
    err: LinkError
    try:
        # a fresh import on the board: the modules were dropped (PURGE)
        board.restart(name, scene, virtual)
        return name
    except LinkTimeout as e:
        err = e
    except LinkError as e:
        say("the new image did not start the scene it played (%s); starting %s with its "
            "default scene" % (_one_line(e), name))
        try:
            board.link.exec(protocol.PURGE)
            board.restart(name, None, virtual)
            return name
        except LinkError as e2:
            err = e2
    raise DeployFailed(
        "deployed to %s (the new image is whole and checked), but starting the display again "
        "failed: %s. The display is OFF (it played %s): start it with texelpad demo --port %s "
        "--board %s" % (board.port, _one_line(err), name, board.port, name))
