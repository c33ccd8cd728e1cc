"""The board commands of the `texelpad` command line, end to end against
virtual boards on ptys (the device image under the MicroPython unix port):
`texelpad virtual` driven by the mpremote command line and by texelpad's own
commands; push from flags and scene files with every kind of bad input
refused (exit 2, one line, the board's state unchanged); deploy copying only
what changed; monitor to CSV; status; ports; demo."""
import ast
import json
import signal
import subprocess
import sys

import pytest

import texelpad
from texelpad.sim.virtual import VirtualBoard
from support.vboard import mpremote
from support.cli import run_cli

pytestmark = [pytest.mark.vboard]

TEXELPAD = [sys.executable, "-m", "texelpad.cli"]


@pytest.fixture(scope="module")
def port():
    with VirtualBoard(image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None, realtime=True)
        yield vb.port


def _state(port):
    with texelpad.connect(port) as b:
        st = b.status()
        return st["pushes"], b.scene_source(), st["refreshes"], st["faults"]




# --- texelpad virtual + mpremote ------------------------------------------------

def test_texelpad_virtual_prints_its_port_first_and_mpremote_drives_it(tmp_path):
    proc = subprocess.Popen(TEXELPAD + ["virtual", "--flash", str(tmp_path / "flash")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        port = proc.stdout.readline().strip()
        assert port.startswith("/dev/pts/"), port
        # the image was deployed into the flash folder, compiled
        assert (tmp_path / "flash" / "lib" / "texel" / "app.mpy").is_file()
        r = mpremote(port, "import texel.app as a; st = a.status(); "
                           "print(repr((st['running'], st['board'], st['refresh'])))")
        assert r.returncode == 0, r.stderr
        assert ast.literal_eval(r.stdout.strip()) == (True, "virtual", "viper")
        with texelpad.connect(port) as b:
            st = b.push_texel({"pitch_db": 2.0, "irregularity_db": -6.0, "seed": 9})
            assert st["scene"]["regions"][0]["seed"] == 9
    finally:
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=20) == 0


@pytest.mark.parametrize("chip, what, fragment, code", [
    ([], "file", "is a file, not a folder: the virtual board's flash is a folder", 2),
    (["--chip", "rp2040"], "file", "is not an emulated RP2040's flash image (10 bytes; an "
                                   "image is 1,441,792", 2),
    (["--chip", "rp2040"], "dir", "is a folder: the emulated RP2040's flash is an image file",
     2),
    ([], "under-file", "cannot make the flash folder", 1),
    (["--chip", "rp2040"], "nowhere", "cannot make", 1),
])
def test_virtual_flash_that_cannot_be_one_is_one_line(capsys, tmp_path, chip, what, fragment,
                                                      code):
    """issue 24: `texelpad virtual --flash FILE` (a file, not a folder; with
    --chip not a flash image) was a FileExistsError traceback (or the
    emulator's own refusal, blamed on --chip). Checked before anything
    starts; the file is left as it was."""
    f = tmp_path / "notes.txt"
    f.write_text("not flash\n")
    flash = {"file": f, "dir": tmp_path, "under-file": f / "flash",
             "nowhere": tmp_path / "no" / "such" / "pico.img"}[what]
    got, out, err = run_cli(capsys, "virtual", "--flash", str(flash), "--seconds", "1", *chip)
    assert got == code and err.startswith("texelpad virtual: error: --flash: "), (got, err)
    assert fragment in err and err.count("\n") == 1 and out == "", err
    assert f.read_text() == "not flash\n" and sorted(p.name for p in tmp_path.iterdir()) == [
        "notes.txt"]


# --- push -------------------------------------------------------------------------

def test_push_flags_then_status(capsys, port):
    code, out, err = run_cli(capsys, "push", "--port", port, "--pitch-db", "4.5",
                             "--irregularity-db", "-9", "--seed", "11")
    assert code == 0, err
    assert "texel pitch 4.5 dB, irregularity -9.0 dB, seed 11" in out
    assert "bytes sent" in out
    code, out, err = run_cli(capsys, "status", "--port", port, "--json")
    assert code == 0, err
    st = json.loads(out)
    assert st["scene"]["regions"][0]["seed"] == 11 and st["faults"] == 0


def test_push_scene_file(capsys, port, tmp_path):
    f = tmp_path / "split.json"
    f.write_text(json.dumps({"regions": [
        {"start_mm": 0, "end_mm": 30, "texture": {"kind": "reference", "name": "2sin"}},
        {"start_mm": 30, "end_mm": 60, "texture": {"kind": "constant", "level": 0.25}}]}))
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", str(f))
    assert code == 0, err
    assert "reference 2sin" in out and "constant 0.2500" in out


BAD_FLAGS = [
    (["--pitch-db", "nan", "--irregularity-db", "-9"], "--pitch-db: nan is not finite"),
    (["--pitch-db", "inf", "--irregularity-db", "-9"], "--pitch-db: inf is not finite"),
    (["--pitch-db", "40", "--irregularity-db", "-9"], "--pitch-db: 40.0 is out of range"),
    (["--pitch-db", "4", "--irregularity-db", "-9", "--seed", "-1"], "--seed: -1 is out of range"),
    (["--pitch-db", "4", "--irregularity-db", "-9", "--gain", "2"], "--gain: 2.0 is out of range"),
    (["--pitch-db", "4"], "--irregularity-db"),
    (["--pitch-db", "'); import os #", "--irregularity-db", "-9"], "invalid float value"),
]


@pytest.mark.parametrize("flags, msg", BAD_FLAGS)
def test_bad_flags_refused_state_unchanged(capsys, port, flags, msg):
    before = _state(port)
    code, out, err = run_cli(capsys, "push", "--port", port, *flags)
    assert code == 2, (out, err)
    assert msg in err, err
    assert err.count("\n") == 1           # one line, no traceback
    after = _state(port)
    assert after[:2] == before[:2] and after[2] > before[2] and after[3] == 0


BAD_SCENES = [
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "texel", '
     '"pitch_db": NaN, "irregularity_db": -9}}]}', "regions[0].texture.pitch_db: nan is not finite"),
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "texel", '
     '"pitch_db": Infinity, "irregularity_db": -9}}]}', "regions[0].texture.pitch_db: inf"),
    ('{"regions": [{"start_mm": 0, "end_mm": 500, "texture": {"kind": "constant", "level": 1}}]}',
     "regions[0].end_mm: 500"),
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "reference", '
     '"name": "4sin\\"); import os; os.system(\\"x"}}]}', "regions[0].texture.name: "),
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "reference", '
     '"name": "a\\nb"}}]}', "regions[0].texture.name: "),
    ('{"regions": [], "colour": "red"}', "unknown key"),
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "texel", '
     '"pitch_db": "3", "irregularity_db": -9}}]}', "regions[0].texture.pitch_db: "),
    ('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "texel", '
     '"pitch_db": true, "irregularity_db": -9}}]}', "regions[0].texture.pitch_db: "),
    ('{"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "samples", '
     '"u16": [%s]}}]}' % ",".join(["1"] * 19201), "regions[0].texture.u16: "),
    ('{"regions": [', "is not valid JSON"),
    ('[1, 2]', "a scene is a JSON object"),
]


@pytest.mark.parametrize("text, msg", BAD_SCENES)
def test_bad_scene_files_refused_state_unchanged(capsys, port, tmp_path, text, msg):
    f = tmp_path / "bad.json"
    f.write_text(text)
    before = _state(port)
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", str(f))
    assert code == 2, (out, err)
    assert msg in err, err
    assert err.count("\n") == 1
    after = _state(port)
    assert after[:2] == before[:2] and after[2] > before[2] and after[3] == 0


def test_missing_scene_file(capsys, port, tmp_path):
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", str(tmp_path / "no.json"))
    assert code == 2 and "cannot read" in err


def test_no_board_is_a_failure_not_a_traceback(capsys):
    code, out, err = run_cli(capsys, "status", "--port", "/dev/ttyTEXELPAD-none")
    assert code == 1 and "no such port" in err and "Traceback" not in err


# --- monitor, ports -----------------------------------------------------------------

def test_monitor_to_csv(capsys, port, tmp_path):
    with texelpad.connect(port) as b:
        b.finger([(0, 20.0), (300, 40.0)])
    f = tmp_path / "m.csv"
    code, out, err = run_cli(capsys, "monitor", "--port", port, "--rate", "250", "--seconds",
                             "0.5", "--csv", str(f))
    assert code == 0, err
    rows = f.read_text().splitlines()
    assert rows[0] == "t_us,position,position_mm,amplitude"
    assert len(rows) > 60                               # 250/s for 0.5 s
    t = [int(r.split(",")[0]) for r in rows[1:]]
    assert t == sorted(t)


def test_ports_lists_nothing_here(capsys):
    code, out, err = run_cli(capsys, "ports")
    assert code == 0 and out.strip()


# --- deploy -------------------------------------------------------------------------

def test_deploy_writes_only_what_changed(capsys, tmp_path):
    flash = tmp_path / "flash"
    with VirtualBoard(flash, image=None) as vb:
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
        assert code == 0, err
        assert "deployed to" in out and "0 unchanged" in out
        assert (flash / "lib" / "texel" / "app.mpy").is_file() and (flash / "main.py").is_file()
        assert (flash / "lib" / "texel" / "boards.d" / "virtual.json").is_file()
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
        assert code == 0 and " 0 of " in out, out
        # a changed file on the board is put back, the rest left alone
        (flash / "lib" / "texel" / "runtime" / "duty.mpy").write_bytes(b"junk")
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port, "--dry-run")
        assert code == 0 and "would deploy to" in out and " 0 of " in out
        assert (flash / "lib" / "texel" / "runtime" / "duty.mpy").read_bytes() == b"junk"
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
        assert code == 0 and " 1 of " in out, out
        assert (flash / "lib" / "texel" / "runtime" / "duty.mpy").read_bytes()[:1] == b"M"
        with texelpad.connect(vb.port) as b:         # the handshake now passes
            st = b.start("virtual", None)
            assert st["running"]


def test_deploy_without_port_finds_the_running_virtual_board(capsys, tmp_path, monkeypatch):
    """issue 24: ports, push and status without --port find a running
    `texelpad virtual` (its registry entry); deploy found none."""
    monkeypatch.setenv("TEXELPAD_RUNTIME_DIR", str(tmp_path / "run"))
    flash = tmp_path / "flash"
    with VirtualBoard(flash, image=None) as vb:
        vb.announce()                                  # as `texelpad virtual` does
        code, out, err = run_cli(capsys, "status")     # status found it (no image yet) ...
        assert code == 1 and "not texelpad's device image" in err and vb.port in err, err
        code, out, err = run_cli(capsys, "deploy", "--dry-run")
        assert code == 0, err                          # ... and so does deploy
        assert out.startswith("would deploy to %s:" % vb.port), out
        code, out, err = run_cli(capsys, "deploy")
        assert code == 0 and out.startswith("deployed to %s:" % vb.port), err
        code, out, err = run_cli(capsys, "status")
        assert code == 0 and out.startswith("texelpad is not running"), (out, err)
    assert (flash / "lib" / "texel" / "app.mpy").is_file()


def test_deploy_refuses_an_image_that_does_not_fit(capsys, tmp_path, monkeypatch):
    from texelpad.deploy import install as deploy_mod
    real = deploy_mod.survey

    def small_flash(board, files):
        hashes, present, _free = real(board, files)
        return hashes, present, 100_000            # bytes free: less than the image needs
    monkeypatch.setattr(deploy_mod, "survey", small_flash)
    flash = tmp_path / "flash"
    with VirtualBoard(flash, image=None) as vb:
        code, out, err = run_cli(capsys, "deploy", "--port", vb.port)
    assert code == 1, (out, err)
    assert "the image does not fit" in err and "has 100000 free" in err
    assert not (flash / "lib").exists()             # nothing written


def test_progress_bar_lines_without_a_terminal():
    import io
    from texelpad.cli.progress import ProgressBar
    s = io.StringIO()
    bar = ProgressBar(s)
    for done, name in ((0, "/lib/texel/a.mpy"), (50, "/lib/texel/a.mpy"), (100, "/main.py")):
        bar(done, 200, name)
    bar.end()
    assert s.getvalue().splitlines() == ["deploy:   0% /lib/texel/a.mpy", "deploy:  50% /main.py"]
