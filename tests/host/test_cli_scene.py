"""The everyday commands of issue 9, end to end against virtual boards on
ptys: `texelpad stop`; `texelpad scene pull` (a pulled scene plays again as
it was; the output file is checked before the board is opened and never
left half-written); `texelpad scene boot` (the power-up file /texelpad.json
is what the board's own main.py starts; a bad scene leaves it unchanged;
--clear removes it); `push --scene -`, `--reference`, `--constant`; the
shipped example scenes (each validates and builds; `texelpad scenes` lists
them; `--scene NAME` finds them); exit codes (a usage error 2, a state of
the world - texelpad not running - 1)."""
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import texel
import texel.app  # noqa: F401 (texel.app.DEFAULT_SCENE below; not imported by texel itself)
import texel.runtime.scene as scene_mod
import texelpad
from texelpad.cli.errors import CliError
from texelpad.cli.scene_files import read_scene_file, shipped_scenes
from texelpad.link.board import host_check
from texelpad.sim.virtual import VirtualBoard
from support.cli import run_cli

ROOT = Path(__file__).resolve().parents[2]
TPAD = {"positions": 19200, "dx_um": 5.3}
SCENES = sorted(shipped_scenes())
NO_PORT = "/dev/ttyTEXELPAD-none"

SPLIT = {"name": "a test split", "notes": "left: 2sin\nright: texel", "regions": [
    {"start_mm": 0, "end_mm": 40, "texture": {"kind": "reference", "name": "2sin"}},
    {"start_mm": 40, "end_mm": 70, "texture": {"kind": "texel", "pitch_db": 3.5,
                                               "irregularity_db": -8, "seed": 5}},
    {"start_mm": 70, "end_mm": 101.76, "texture": {"kind": "samples", "u16": [0, 30000, 65535],
                                                   "fit": "stretch"}}]}


def _plain(v):
    """Scenes compared as JSON sees them (a tuple of u16 values is a list)."""
    return json.loads(json.dumps(v))


# --- the shipped scenes (no board) --------------------------------------------------

@pytest.mark.parametrize("stem", SCENES)
def test_every_shipped_scene_validates_and_builds(stem):
    scene = json.loads(shipped_scenes()[stem].read_text(encoding="utf-8"))
    assert isinstance(scene["name"], str) and 1 <= len(scene["name"]) <= scene_mod.NAME_MAX
    assert isinstance(scene["notes"], str) and len(scene["notes"]) <= scene_mod.NOTES_MAX
    assert scene["notes"].splitlines()[0]
    canonical = scene_mod.validate(host_check(scene, TPAD), TPAD)
    built = scene_mod.build(canonical, TPAD)
    assert built.describe()["name"] == scene["name"]
    assert built.amp(0) >= 0 and built.amp(TPAD["positions"] - 1) >= 0


def test_the_library_has_what_the_issue_asked_for():
    def load(stem):
        return json.loads(shipped_scenes()[stem].read_text(encoding="utf-8"))
    splits = [s for s in SCENES if s.startswith("split-")]
    assert len(splits) >= 3 and "split-4sin" in splits
    for s in splits:                  # reference left, texel right, half a screen each
        left, right = load(s)["regions"]
        assert left["texture"]["kind"] == "reference" and right["texture"]["kind"] == "texel"
        assert left["texture"]["name"] in texel.reference_names()
        assert left["end_mm"] == right["start_mm"] == 50.88
    # the board's default scene is among them, as it plays
    default = load("split-4sin")
    assert default["regions"] == texel.app.DEFAULT_SCENE["regions"]
    kinds = [r["texture"]["name"] for r in load("sine-vs-square")["regions"]]
    assert "square" in kinds and any(k.endswith("sin") for k in kinds)
    (grad,) = load("gradient")["regions"]
    assert grad["texture"] == {"kind": "samples", "u16": [0, 65535], "fit": "stretch"}
    (const,) = load("constant-half")["regions"]
    assert const["texture"] == {"kind": "constant", "level": 0.5}
    sweep = load("texel-sweep")["regions"]
    pitches = [r["texture"]["pitch_db"] for r in sweep]
    assert len(sweep) >= 3 and all(r["texture"]["kind"] == "texel" for r in sweep)
    assert pitches == sorted(pitches) and len(set(pitches)) == len(pitches)


def test_the_scenes_are_package_data():
    text = (ROOT / "pyproject.toml").read_text()
    assert '"texelpad.scenes" = ["*.json"]' in text
    assert (ROOT / "host" / "texelpad" / "scenes" / "__init__.py").is_file()
    assert set(SCENES) == {p.stem for p in (ROOT / "host/texelpad/scenes").glob("*.json")}


def test_scenes_lists_them(capsys):
    code, out, err = run_cli(capsys, "scenes")
    assert code == 0 and err == ""
    for stem in SCENES:
        scene = json.loads(shipped_scenes()[stem].read_text(encoding="utf-8"))
        line = next(ln for ln in out.splitlines() if ln.startswith(stem + " "))
        assert scene["name"] in line and scene["notes"].splitlines()[0] in line
    code, out, err = run_cli(capsys, "scenes", "--json")
    assert code == 0 and [r["stem"] for r in json.loads(out)] == SCENES


def test_read_scene_file_finds_shipped_scenes_files_first(tmp_path, monkeypatch):
    assert read_scene_file("gradient")["name"] == "gradient 0 -> 1"
    assert read_scene_file("gradient.json")["name"] == "gradient 0 -> 1"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "gradient").write_text(json.dumps({"regions": [], "name": "mine"}))
    assert read_scene_file("gradient")["name"] == "mine"      # a file of that name wins
    with pytest.raises(CliError) as e:
        read_scene_file("no-such-scene")
    assert "cannot read no-such-scene" in str(e.value) and "texelpad scenes" in str(e.value)
    assert e.value.code == 2
    with pytest.raises(CliError) as e:
        read_scene_file("sub/gradient")          # a path is a path
    assert "cannot read sub/gradient" in str(e.value)


def _stdin(monkeypatch, text):
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(text.encode("utf-8"))))


def test_read_scene_file_from_stdin(monkeypatch):
    _stdin(monkeypatch, json.dumps(SPLIT))
    assert read_scene_file("-") == SPLIT
    _stdin(monkeypatch, "{\"regions\": [")
    with pytest.raises(CliError) as e:
        read_scene_file("-")
    assert "--scene: stdin is not valid JSON" in str(e.value)


# --- usage errors: before any board is opened (exit 2) -----------------------------

@pytest.mark.parametrize("argv, msg", [
    (["push"], "nothing to push"),
    (["push", "--scene", "gradient", "--reference", "4sin"], "not --scene and --reference"),
    (["push", "--pitch-db", "3", "--irregularity-db", "-9", "--constant", "0.5"],
     "not texel flags and --constant"),
    (["push", "--reference", "5sin"], "--reference: unknown reference texture '5sin' (known: "
                                      "2sin, 3sin, 4sin"),
    (["push", "--constant", "1.5"], "--constant: must be a friction level 0 .. 1, got 1.5"),
    (["push", "--constant", "nan"], "--constant: must be a friction level 0 .. 1, got nan"),
    (["push", "--constant", "-0.1"], "--constant: must be a friction level 0 .. 1"),
    (["push", "--scene", "no-such-scene"], "nor is it a shipped scene"),
    (["scene", "boot"], "give one of FILE, --current or --clear"),
    (["scene", "boot", "gradient", "--clear"], "not FILE and --clear"),
    (["scene", "boot", "--current", "--clear"], "not --current and --clear"),
    (["scene", "boot", "--clear", "--board", "pico"], "--board: --clear removes"),
    (["scene", "boot", "no-such-scene"], "FILE: cannot read no-such-scene"),
    (["scene"], "say what to do"),
])
def test_usage_errors_are_one_line_exit_2_before_the_board(capsys, argv, msg):
    code, out, err = run_cli(capsys, *argv, "--port", NO_PORT) if argv != ["scene"] else \
        run_cli(capsys, *argv)
    assert code == 2, (out, err)
    assert msg in err, err
    assert err.count("\n") == 1 and "no such port" not in err


def test_pull_to_an_unwritable_path_fails_before_the_board(capsys, tmp_path):
    # the port does not exist: the file's check must come first
    code, out, err = run_cli(capsys, "scene", "pull", str(tmp_path / "no" / "dir.json"),
                             "--port", NO_PORT)
    assert code == 1 and "cannot write" in err and "no such directory" in err, err
    (tmp_path / "afile").write_text("x")
    code, out, err = run_cli(capsys, "scene", "pull", str(tmp_path / "afile" / "s.json"),
                             "--port", NO_PORT)
    assert code == 1 and "is not a directory" in err, err
    code, out, err = run_cli(capsys, "scene", "save", str(tmp_path), "--port", NO_PORT)
    assert code == 1 and "it is a directory" in err, err
    assert "no such port" not in err


# --- against a running virtual board ------------------------------------------------

@pytest.fixture(scope="module")
def port():
    with VirtualBoard(image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None, realtime=True)
        yield vb.port


def _running(port):
    """The board playing (in real time), whatever a test before left."""
    with texelpad.connect(port) as b:
        if not b.status().get("running"):
            b.start("virtual", None, realtime=True)


def _source(port):
    with texelpad.connect(port) as b:
        return b.scene_source()



@pytest.mark.vboard
def test_stop_then_status_says_not_running(capsys, port):
    _running(port)
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", "split-2sin")
    assert code == 0, err
    code, out, err = run_cli(capsys, "stop", "--port", port)
    assert code == 0, err
    assert out.count("\n") == 1
    assert out.startswith("stopped %s (board virtual): it played 'split 2sin | texel 4.8 dB'; "
                          "the carrier is off" % port), out
    code, out, err = run_cli(capsys, "status", "--port", port)
    assert code == 0 and out.startswith("texelpad is not running"), out
    # already stopped: said so, exit 0
    code, out, err = run_cli(capsys, "stop", "--port", port)
    assert code == 0 and out == "texelpad is not running on %s: the carrier is already off\n" % port
    with texelpad.connect(port) as b:
        st = b.status()
        assert not st["running"]


@pytest.mark.vboard
def test_not_running_is_exit_1_everywhere(capsys, port, tmp_path):
    with texelpad.connect(port) as b:
        b.stop()
    want = "texelpad is not running on %s (" % port
    for argv in (["push", "--pitch-db", "3", "--irregularity-db", "-9"],
                 ["push", "--reference", "4sin"],
                 ["monitor", "--seconds", "0.1"],
                 ["scene", "pull", str(tmp_path / "s.json")],
                 ["scene", "boot", "--current"],
                 ["scene", "boot", "gradient"]):
        code, out, err = run_cli(capsys, *argv, "--port", port)
        assert code == 1, (argv, out, err)
        assert want in err and err.count("\n") == 1, (argv, err)
    assert not (tmp_path / "s.json").exists()
    # push --board starts it
    code, out, err = run_cli(capsys, "push", "--port", port, "--board", "virtual",
                             "--constant", "0.25")
    assert code == 0 and "constant 0.2500" in out, err


@pytest.mark.vboard
def test_push_reference_and_constant(capsys, port):
    _running(port)
    code, out, err = run_cli(capsys, "push", "--port", port, "--reference", "bp-4-0.5")
    assert code == 0, err
    assert "reference bp-4-0.5" in out and "1 region," in out
    (r,) = _source(port)["regions"]
    assert r["start_mm"] == 0 and r["texture"] == {"kind": "reference", "name": "bp-4-0.5"}
    code, out, err = run_cli(capsys, "push", "--port", port, "--constant", "0.5", "--json")
    assert code == 0, err
    st = json.loads(out)
    (r,) = st["scene"]["regions"]
    assert r["kind"] == "constant" and r["amplitude"] in (32767, 32768)
    assert r["end"] == st["display"]["positions"]
    before = _source(port)
    code, out, err = run_cli(capsys, "push", "--port", port, "--reference", "4sin; import os")
    assert code == 2 and "--reference: unknown reference texture" in err
    assert _source(port) == before


@pytest.mark.vboard
def test_push_scene_from_stdin_and_by_shipped_name(capsys, port, monkeypatch):
    _running(port)
    _stdin(monkeypatch, json.dumps(SPLIT))
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", "-")
    assert code == 0, err
    assert "a test split" in out and "reference 2sin" in out and "samples (3 values" in out
    src = _source(port)
    assert src["name"] == SPLIT["name"] and src["notes"] == SPLIT["notes"]
    _stdin(monkeypatch, "[1]")
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", "-")
    assert code == 2 and "--scene: stdin: a scene is a JSON object" in err
    assert _source(port) == src
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", "texel-sweep")
    assert code == 0, err
    assert "texel sweep 0 .. 10 dB" in out and "6 regions" in out


@pytest.mark.vboard
def test_pull_round_trips(capsys, port, tmp_path):
    _running(port)
    f = tmp_path / "split.json"
    f.write_text(json.dumps(SPLIT))
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", str(f))
    assert code == 0, err
    first = _source(port)
    pulled = tmp_path / "pulled.json"
    code, out, err = run_cli(capsys, "scene", "pull", str(pulled), "--port", port)
    assert code == 0, err
    assert out.count("\n") == 1 and str(pulled) in out and "3 regions" in out
    doc = json.loads(pulled.read_text())
    assert list(doc)[:3] == ["name", "notes", "regions"]          # a person's order
    assert _plain(doc) == _plain(first)
    # something else plays, then the pulled file brings the same scene back
    code, out, err = run_cli(capsys, "push", "--port", port, "--constant", "0.1")
    assert code == 0, err
    code, out, err = run_cli(capsys, "push", "--port", port, "--scene", str(pulled))
    assert code == 0, err
    assert _source(port) == first
    # to stdout ("-"): only the JSON
    code, out, err = run_cli(capsys, "scene", "save", "-", "--port", port)
    assert code == 0 and _plain(json.loads(out)) == _plain(first)
    # no temporary file left beside it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pulled.json", "split.json"]


@pytest.mark.vboard
def test_pull_never_leaves_a_half_file(capsys, port, tmp_path, monkeypatch):
    _running(port)
    out_file = tmp_path / "keep.json"
    out_file.write_text("the old content\n")

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", broken_replace)
    code, out, err = run_cli(capsys, "scene", "pull", str(out_file), "--port", port)
    assert code == 1, (out, err)
    assert "cannot write %s: No space left on device" % out_file in err
    assert out_file.read_text() == "the old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.json"]


@pytest.mark.vboard
def test_push_progress_bar_for_a_large_upload(capsys, port):
    _running(port)
    from texelpad.cli.board import PROGRESS_MIN_BYTES
    scene = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
        "kind": "samples", "u16": [(i * 7) % 65536 for i in range(19200)]}}]}
    assert 2 * 19200 >= PROGRESS_MIN_BYTES
    old = sys.stdin
    try:
        sys.stdin = io.TextIOWrapper(io.BytesIO(json.dumps(scene).encode()))
        code, out, err = run_cli(capsys, "push", "--port", port, "--scene", "-")
    finally:
        sys.stdin = old
    assert code == 0, err
    assert "samples (19200 values" in out
    # stderr is no terminal here: one line, then nothing half-drawn
    assert err.startswith("push: "), err
    assert "samples upload" in err and "\r" not in err


def test_progress_callback_draws_and_ends(monkeypatch):
    from texelpad.cli import board as cli_board

    class Tty(io.StringIO):
        def isatty(self):
            return True
    s = Tty()
    monkeypatch.setattr("sys.stderr", s)
    p = cli_board._UploadProgress()
    p(0, 100)
    p(100, 100)
    p.end()
    text = s.getvalue()
    assert "\r[" in text and "100%" in text and text.endswith("\n")
    # not a terminal and a small upload: nothing at all
    s2 = io.StringIO()
    monkeypatch.setattr("sys.stderr", s2)
    p = cli_board._UploadProgress()
    p(0, 100)
    p(100, 100)
    p.end()
    assert s2.getvalue() == ""


# --- the power-up scene ------------------------------------------------------------

MAIN_PY = ROOT / "device" / "texel" / "main.py"


@pytest.fixture()
def flash_board(tmp_path):
    """A virtual board of its own with its flash folder, playing in real time."""
    flash = tmp_path / "flash"
    with VirtualBoard(flash, image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None, realtime=True)
        yield vb.port, flash


def _power_up(port):
    """Run the board's own /main.py (device/texel/main.py) on it as at
    power-up: after a soft reset (mpremote's exec without resume: a fresh
    interpreter, nothing playing); returns what it printed and the scene it
    plays."""
    exe = Path(sys.executable).parent / "mpremote"
    r = subprocess.run([str(exe) if exe.exists() else "mpremote", "connect", port, "exec",
                        MAIN_PY.read_text()], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    with texelpad.connect(port) as b:
        st = b.status()
        return r.stdout, st, b.scene_source()


@pytest.mark.vboard
def test_boot_writes_what_main_py_starts(capsys, flash_board, tmp_path):
    port, flash = flash_board
    code, out, err = run_cli(capsys, "scene", "boot", "texel-sweep", "--port", port)
    assert code == 0, err
    assert out.count("\n") == 1 and "board virtual" in out and "'texel sweep 0 .. 10 dB'" in out
    boot = flash / "texelpad.json"
    cfg = json.loads(boot.read_text())
    assert cfg["board"] == "virtual"
    shipped = read_scene_file("texel-sweep")
    assert cfg["scene"] == _plain(scene_mod.validate(shipped, TPAD))        # canonical
    assert not (flash / "texelpad.json.new").exists()
    # the board's main.py reads exactly this file and starts it
    printed, st, src = _power_up(port)
    assert "texelpad: playing on virtual" in printed, printed
    assert st["running"] and st["scene"]["name"] == "texel sweep 0 .. 10 dB"
    assert _plain(src) == cfg["scene"]


@pytest.mark.vboard
def test_boot_current_stdin_bad_scene_and_clear(capsys, flash_board, tmp_path, monkeypatch):
    port, flash = flash_board
    boot = flash / "texelpad.json"
    code, out, err = run_cli(capsys, "push", "--port", port, "--reference", "triangle")
    assert code == 0, err
    code, out, err = run_cli(capsys, "scene", "boot", "--current", "--port", port)
    assert code == 0, err
    assert "the scene playing now" in out
    good = boot.read_bytes()
    assert json.loads(good)["scene"]["regions"][0]["texture"] == {"kind": "reference",
                                                                  "name": "triangle"}
    # a bad scene (file or stdin) leaves the boot file as it was
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"regions": [{"start_mm": 0, "end_mm": 500, "texture": {
        "kind": "constant", "level": 1}}]}))
    code, out, err = run_cli(capsys, "scene", "boot", str(bad), "--port", port)
    assert code == 2 and "%s: regions[0].end_mm: 500" % bad in err, err
    assert err.count("\n") == 1
    _stdin(monkeypatch, json.dumps(dict(SPLIT, name="x" * 65)))
    code, out, err = run_cli(capsys, "scene", "boot", "-", "--port", port)
    assert code == 2 and err.startswith("texelpad scene: error: stdin: name: "), err
    # a board file this firmware cannot start (the virtual board is no RP2040)
    code, out, err = run_cli(capsys, "scene", "boot", "gradient", "--board", "pico",
                             "--port", port)
    assert code == 2 and "--board: the board refused it: board file 'pico' is for" in err, err
    code, out, err = run_cli(capsys, "scene", "boot", "gradient", "--board", "nosuch",
                             "--port", port)
    assert code == 2 and "board 'nosuch': no nosuch.json" in err, err
    assert boot.read_bytes() == good and not (flash / "texelpad.json.new").exists()
    # a good scene from stdin replaces it
    _stdin(monkeypatch, json.dumps(SPLIT))
    code, out, err = run_cli(capsys, "scene", "boot", "-", "--board", "virtual", "--port", port)
    assert code == 0, err
    assert json.loads(boot.read_text())["scene"]["name"] == "a test split"
    # --clear removes it (and says so when there is none); main.py then plays the default
    code, out, err = run_cli(capsys, "scene", "boot", "--clear", "--port", port)
    assert code == 0 and out.startswith("removed /texelpad.json on %s" % port), out
    assert not boot.exists()
    code, out, err = run_cli(capsys, "scene", "boot", "--clear", "--port", port)
    assert code == 0 and out.startswith("there was no /texelpad.json on %s" % port), out
    printed, st, src = _power_up(port)
    assert "texelpad: playing on virtual" in printed
    assert _plain(src) == _plain(scene_mod.validate(texel.app.DEFAULT_SCENE, TPAD))


@pytest.mark.vboard
def test_boot_when_not_running_needs_a_board_name(capsys, flash_board):
    port, flash = flash_board
    with texelpad.connect(port) as b:
        b.stop()
    code, out, err = run_cli(capsys, "scene", "boot", "constant-half", "--port", port)
    assert code == 1 and "texelpad is not running on %s (--board NAME" % port in err, err
    code, out, err = run_cli(capsys, "scene", "boot", "constant-half", "--board", "virtual",
                             "--port", port)
    assert code == 0, err
    assert json.loads((flash / "texelpad.json").read_text())["board"] == "virtual"
    printed, st, src = _power_up(port)
    assert st["running"] and st["scene"]["name"] == "constant 0.5"


class _Virtual:
    """`texelpad virtual --flash FLASH --source` as a user runs it (a process
    of its own, its registry kept apart from the user's); .port, and on exit
    its stderr in .err after a Ctrl-C (SIGINT), which must end it with 0."""

    def __init__(self, flash, registry):
        self.flash, self.registry = flash, registry

    def __enter__(self):
        env = dict(os.environ, TEXELPAD_RUNTIME_DIR=str(self.registry))
        self.proc = subprocess.Popen([sys.executable, "-m", "texelpad.cli", "virtual", "--flash",
                                      str(self.flash), "--source"], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, env=env)
        self.port = self.proc.stdout.readline().strip()
        assert self.port.startswith("/dev/pts/"), self.proc.stderr.read()
        return self

    def __exit__(self, *exc):
        import signal
        self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout=30)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        self.err = self.proc.stderr.read()
        if exc[0] is None:
            assert code == 0, self.err


@pytest.mark.vboard
def test_texelpad_virtual_plays_its_power_up_scene(capsys, tmp_path):
    """issue 24: `texelpad scene boot FILE` had no effect on the virtual board -
    `texelpad virtual` started the default scene whatever its flash held. Now it
    starts what the board's main.py starts at power-up: the power-up file's
    board and scene; a file the board refuses leaves it stopped (main.py's "not
    started"), said on stderr; without one, the default."""
    flash, reg = tmp_path / "flash", tmp_path / "run"
    with _Virtual(flash, reg) as v:
        code, out, err = run_cli(capsys, "scene", "boot", "texel-sweep", "--port", v.port)
        assert code == 0, err
        with texelpad.connect(v.port) as b:             # this run plays on: the default
            assert b.status()["scene"].get("name") != "texel sweep 0 .. 10 dB"
    cfg = json.loads((flash / "texelpad.json").read_text())
    with _Virtual(flash, reg) as v:                     # the next run starts it
        with texelpad.connect(v.port) as b:
            st = b.status()
            src = b.scene_source()
    assert st["running"] and st["board"] == "virtual" and st["refresh_hz"] > 1000
    assert st["scene"].get("name") == "texel sweep 0 .. 10 dB" and _plain(src) == cfg["scene"]
    assert "playing the power-up scene of %s" % (flash / "texelpad.json") in v.err, v.err
    # a power-up file the board refuses: stopped, as main.py leaves a board
    (flash / "texelpad.json").write_text(json.dumps({"board": "pico", "scene": None}))
    with _Virtual(flash, reg) as v:
        code, out, err = run_cli(capsys, "status", "--port", v.port)
        assert code == 0 and out.startswith("texelpad is not running"), (out, err)
        # --clear removes it: the next run plays the default
        code, out, err = run_cli(capsys, "scene", "boot", "--clear", "--port", v.port)
        assert code == 0, err
    assert "not started: the power-up file" in v.err and "board file 'pico'" in v.err, v.err
    with _Virtual(flash, reg) as v:
        with texelpad.connect(v.port) as b:
            src = b.scene_source()
    assert _plain(src) == _plain(scene_mod.validate(texel.app.DEFAULT_SCENE, TPAD))
    assert "power-up" not in v.err


# The host's Ctrl-C, as the kit's loop meets it: after `polls` polls (a test's
# stand-in for a laptop plugged in; the button is the virtual board's scripted one)
KIT_PREFIX = """import texel.kit as _k, texel.hw.virtual as _v
_v.VirtualHw.button_levels = %r
_n = [0]
def _sleep(ms, _t=_k._sleep):
    _n[0] += 1
    if _n[0] > %d:
        raise KeyboardInterrupt
    _t(ms)
_k._sleep = _sleep
"""


@pytest.mark.vboard
def test_boot_with_several_files_is_a_playlist_the_button_steps(capsys, flash_board, tmp_path):
    """`texelpad scene boot A B C`: a playlist in /texelpad.json; at power-up
    main.py plays A and the board's button steps it (two presses: C), and a
    Ctrl-C leaves C playing with the REPL the host's. A bad scene among the
    files is refused and the file is left as it was."""
    port, flash = flash_board
    code, out, err = run_cli(capsys, "scene", "boot", "texel-sweep", "gradient", "constant-half",
                             "--port", port)
    assert code == 0, err
    assert "playlist of 3 scenes (texel-sweep, gradient, constant-half)" in out, out
    cfg = json.loads((flash / "texelpad.json").read_text())
    assert [s.get("name") for s in [cfg["scene"]] + cfg["then"]] == [
        read_scene_file(n).get("name") for n in ("texel-sweep", "gradient", "constant-half")]
    levels = [0] * 4 + [1] * 6 + [0] * 6 + [1, 0, 1] + [1] * 6 + [0] * 4
    exe = Path(sys.executable).parent / "mpremote"
    r = subprocess.run([str(exe) if exe.exists() else "mpremote", "connect", port, "exec",
                        KIT_PREFIX % (levels, len(levels) + 5) + MAIN_PY.read_text()],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "a playlist of 3 scenes" in r.stdout and "texelpad: scene 3 of 3" in r.stdout, r.stdout
    with texelpad.connect(port) as b:
        st = b.status()
    assert st["running"] and st["scene"]["name"] == read_scene_file("constant-half").get("name"), st
    before = (flash / "texelpad.json").read_bytes()
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"regions": [{"start_mm": 0, "end_mm": 10, "texture": {
        "kind": "texel", "pitch_db": 99.0}}]}))
    code, out, err = run_cli(capsys, "scene", "boot", "gradient", str(bad), "--port", port)
    assert code != 0 and "scene 2 of the playlist: regions[0].texture.pitch_db" in err, err
    assert (flash / "texelpad.json").read_bytes() == before
