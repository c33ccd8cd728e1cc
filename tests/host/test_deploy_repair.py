"""`texelpad deploy` always repairs the board and leaves the display as it
found it, against virtual boards on ptys (their flash a folder here):

- a deploy killed mid-write (the board stopped while a file was written)
  leaves a "<file>.new"; the next deploy completes or removes every leftover
  (hashes decide), rewrites what differs, and starts the display again;
- a failure after the display was stopped starts it again and says so;
- preconditions (a path that cannot be written) are checked while the
  display still plays: a refused deploy changes nothing;
- a successful deploy says what to run next (the board file to start)."""
import hashlib

import pytest

import texelpad
from texelpad.cli.deploy import next_step
from texelpad import image
from texelpad.deploy.install import DeployFailed, deploy
from texelpad.link import protocol
from texelpad.sim.virtual import VirtualBoard
from support.cli import run_cli

pytestmark = [pytest.mark.vboard]

TEXEL = {"pitch_db": 3.0, "irregularity_db": -10.0, "seed": 5}




def _image_files():
    """What deploy writes to the virtual board: the image and, where this
    machine builds it, the C core's native module for x64."""
    from texelpad.deploy.install import with_native_core
    t = image.TARGETS["unix"]
    return with_native_core(image.build_image(t, include_main=True), t, lambda m: None)


def _playing(port):
    """A deployed virtual board playing a pushed texel scene in real time."""
    with texelpad.connect(port) as b:
        b.start("virtual", None, realtime=True)
        b.push_texel(TEXEL)
        return b.scene_source()


def _state(port):
    with texelpad.connect(port) as b:
        st = b.status()
        return st["running"], st["pushes"], st["refreshes"], b.scene_source()


def _leftovers(flash):
    return sorted(str(p.relative_to(flash)) for p in flash.rglob("*.new"))


def _assert_image_intact(flash):
    for f in _image_files():
        p = flash / f.remote.lstrip("/")
        assert hashlib.sha256(p.read_bytes()).hexdigest() == f.sha256, f.remote


@pytest.fixture
def deployed(tmp_path):
    """(flash folder, start(): a started VirtualBoard on it); the first board
    gets the image (a plain deploy); every board is stopped at the end."""
    flash = tmp_path / "flash"
    boards = []

    def start():
        vb = VirtualBoard(flash, image=None)
        boards.append(vb)
        vb.start()
        return vb
    vb = start()
    with texelpad.connect(vb.port, check=False) as b:
        deploy(b)
    yield flash, start
    for vb in boards:
        vb.stop()


def test_a_deploy_killed_mid_write_is_repaired_by_the_next(capsys, deployed):
    """The reported defect: a leftover .new made the next deploy fail with a
    board traceback (OSError ENOENT) after it had stopped the display."""
    flash, start = deployed
    vb = start()                                    # a second interpreter on the same flash
    # (the first board is idle; this one plays)
    scene = _playing(vb.port)
    for rel in ("lib/texel/runtime/duty.mpy", "lib/texel/boards.d/virtual.json"):
        p = flash / rel
        p.write_bytes(p.read_bytes() + b"\n\n")    # changed: deploy rewrites both

    def kill_mid_write(done, total, name):
        if name.endswith("virtual.json"):           # its .new is on the flash, not renamed
            vb.stop()
    with texelpad.connect(vb.port, check=False) as b:
        with pytest.raises(DeployFailed) as e:
            deploy(b, bar=kill_mid_write)
    text = str(e.value)
    assert "\n" not in text
    assert "The display is OFF: it played virtual" in text
    assert "run texelpad deploy --port %s again" % vb.port in text
    assert _leftovers(flash) == ["lib/texel/boards.d/virtual.json.new"]

    vb2 = start()                                   # the board comes back, plays again
    _playing(vb2.port)
    code, out, err = run_cli(capsys, "deploy", "--port", vb2.port)
    assert code == 0, err
    assert "repaired an interrupted deploy (1 .new file completed, 0 removed)" in out
    assert "restarted virtual with its scene" in out
    assert "next: texelpad demo --port %s " % vb2.port in out
    assert _leftovers(flash) == []
    _assert_image_intact(flash)
    running, _, _, now = _state(vb2.port)
    assert running and now == scene


def test_leftovers_completed_or_removed_and_damaged_files_rewritten(capsys, deployed):
    """Hashes decide: a whole .new (the image's bytes) is renamed into place,
    any other .new is removed, a damaged file - even one that breaks the
    image's import - is rewritten."""
    flash, start = deployed
    files = {f.remote: f for f in _image_files()}
    pkg = flash / "lib" / "texel"
    app = pkg / "app.mpy"
    app.write_bytes(b"junk")                        # damaged: its import fails (ValueError)
    (pkg / "app.mpy.new").write_bytes(files["/lib/texel/app.mpy"].data)      # whole
    duty = pkg / "runtime" / "duty.mpy"
    duty.write_bytes(duty.read_bytes()[:100])       # half-written
    (pkg / "runtime" / "duty.mpy.new").write_bytes(b"half")                  # not whole
    (pkg / "gen" / "gone.mpy.new").write_bytes(b"x")                         # no such module
    (flash / "main.py.new").write_bytes(b"half")                             # outside /lib
    vb = start()
    # a dry run says so and writes nothing
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port, "--dry-run")
    assert code == 0, err
    assert "would repair an interrupted deploy (1 .new file completed, 3 removed)" in out
    assert len(_leftovers(flash)) == 4 and app.read_bytes() == b"junk"
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 0, err
    assert " 1 of %d files written" % len(files) in out          # duty.mpy; app.mpy renamed
    assert "repaired an interrupted deploy (1 .new file completed, 3 removed)" in out
    assert _leftovers(flash) == []
    assert not list(flash.rglob(".texelpad-probe"))  # the writability probe cleaned up
    _assert_image_intact(flash)
    with texelpad.connect(vb.port) as b:            # the handshake passes again
        assert b.start("virtual", None)["running"]


def test_a_failure_after_the_display_stopped_starts_it_again(capsys, deployed, monkeypatch):
    flash, start = deployed
    vb = start()
    scene = _playing(vb.port)
    (flash / "lib/texel/runtime/duty.mpy").write_bytes(b"junk")
    real = protocol.replace_file
    # the board refuses the rename (a full or failing flash): a board traceback
    monkeypatch.setattr(protocol, "replace_file", lambda path, tmp: "raise OSError(28)")
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 1, (out, err)
    line = [ln for ln in err.splitlines() if ln.startswith("texelpad deploy: error:")]
    assert len(line) == 1, err
    assert "failed at /lib/texel/runtime/duty.mpy: the board raised OSError: 28" in line[0]
    assert "The display plays again (virtual, the scene it played)" in line[0]
    assert "run texelpad deploy --port %s again" % vb.port in line[0]
    running, _, _, now = _state(vb.port)
    assert running and now == scene
    # the next deploy finishes the job (duty.mpy.new is whole) and keeps the scene
    monkeypatch.setattr(protocol, "replace_file", real)
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 0, err
    assert "repaired an interrupted deploy (1 .new file completed, 0 removed)" in out
    _assert_image_intact(flash)
    running, _, _, now = _state(vb.port)
    assert running and now == scene


@pytest.mark.parametrize("damage, message", [
    ("folder_is_a_file", "/lib/texel/hw on the board is a file, where the image needs a folder"),
    ("file_is_a_folder", "/lib/texel/runtime/duty.mpy on the board is a folder, where the "
                         "image has a file"),
])
def test_paths_that_cannot_be_written_are_refused_before_the_display_stops(
        capsys, deployed, damage, message):
    flash, start = deployed
    vb = start()
    scene = _playing(vb.port)
    before = _state(vb.port)
    if damage == "folder_is_a_file":
        hw = flash / "lib/texel/hw"
        for p in hw.iterdir():
            p.unlink()
        hw.rmdir()
        hw.write_bytes(b"")
    else:
        duty = flash / "lib/texel/runtime/duty.mpy"
        duty.unlink()
        duty.mkdir()
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 1, (out, err)
    assert message in err and "stopping the display" not in err
    running, pushes, refreshes, now = _state(vb.port)
    assert running and pushes == before[1] and refreshes > before[2] and now == scene


def test_a_read_only_filesystem_is_refused_before_the_display_stops(capsys, deployed,
                                                                    monkeypatch):
    """The board's answer to the probe write (here: EROFS, as CircuitPython
    gives while its drive is mounted by the computer) refuses the deploy
    while the display still plays."""
    flash, start = deployed
    vb = start()
    scene = _playing(vb.port)
    before = _state(vb.port)
    (flash / "lib/texel/runtime/duty.mpy").write_bytes(b"junk")
    monkeypatch.setattr(protocol, "preflight",
                        lambda paths, dirs, root, probe=True:
                        "print(repr(({}, {'lib/texel/runtime': 30})))")
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 1, (out, err)
    assert ("cannot write to /lib/texel/runtime (OSError 30 EROFS): its filesystem is "
            "read-only; nothing was changed") in err
    assert "stopping the display" not in err
    running, pushes, refreshes, now = _state(vb.port)
    assert running and pushes == before[1] and refreshes > before[2] and now == scene
    assert (flash / "lib/texel/runtime/duty.mpy").read_bytes() == b"junk"


def test_a_deploy_says_what_to_run_next(capsys, tmp_path):
    """The README's flow: deploy, then demo - which needs the board file when
    nothing plays yet. The board file named starts on this firmware."""
    with VirtualBoard(tmp_path / "flash", image=None) as vb:
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port, "--no-main")
        assert code == 0, err
        nxt = out.strip().splitlines()[-1]
        assert nxt.startswith("next: texelpad demo --port %s --board virtual " % vb.port), out
        code, out, err = run_cli(capsys, "push", "--port", vb.port, "--board", "virtual",
                                 "--pitch-db", "3", "--irregularity-db", "-10", "--seed", "5")
        assert code == 0, err
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port, "--no-main")
        assert code == 0, err
        assert out.strip().splitlines()[-1] == (
            "next: texelpad demo --port %s   (texelpad plays virtual on it)" % vb.port)


def test_next_step_names_the_board_files_of_the_firmware():
    rp2 = [p.stem for p in image.board_files("rp2")]
    assert len(rp2) > 1                              # pico, pico_bridge
    text = next_step("/dev/ttyACM0", {"playing": None, "boards": rp2, "board_port": "rp2",
                                       "main": True})
    assert text.startswith("next: texelpad demo --port /dev/ttyACM0 --board %s " % rp2[0])
    assert "rp2 firmware: %s" % ", ".join(rp2) in text and "/main.py" in text
    assert "pyboard" not in text


def test_a_damaged_image_file_is_replaced_without_being_imported(capsys, deployed):
    """A truncated .mpy (a copy cut off by hand, flash trouble) hangs the
    MicroPython loader that imports it. Deploy's handshake never imports the
    image from its files (protocol.HELLO_LOADED), so deploy still reaches the
    board, finds the file by its hash and rewrites it; the board then starts."""
    flash, start = deployed
    app = flash / "lib" / "texel" / "app.mpy"
    app.write_bytes(app.read_bytes()[:300])
    vb = start()                        # a fresh interpreter: nothing of texel imported
    code, out, err = run_cli(capsys, "deploy", "--port", vb.port, "--timeout", "5")
    assert code == 0, err
    assert "1 of" in out and "files written" in out, out
    _assert_image_intact(flash)
    with texelpad.connect(vb.port) as b:
        assert b.start("virtual")["running"]
