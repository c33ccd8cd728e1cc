"""Format 2 is the one default (issue 32 item 1; docs/generator.md "Which
format"): a texture without "v" is format 2 everywhere - texel.render, the
device API, scene files, Board.push, the board's own validation; format 1,
the lab's float generator, only by "v": 1.

Every creator writes "v", 2 unless asked for 1: the CLI's texel flags (push,
render) and encode, Board.push_texel, the shipped scenes, the board's
DEFAULT_SCENE, the lab's studies (a config's texture_format, recorded in the
session header) - and `scene pull` writes the canonical scene, which says "v".
A file saved before 0.2 (when no "v" read as format 1) keeps its texture with
`texelpad scene pin FILE`, which writes "v": 1 where a texel says nothing."""
import json

import numpy as np
import pytest

import texel
import texel.app
import texel.runtime.scene as scene_mod
import texelpad
from texel.gen import params as P
from texelpad.cli.scene_files import shipped_scenes
from texelpad.cli.texel_flags import render_params
from texelpad.study import configs as C
from texelpad.study import protocols, questions
from texelpad.study import scenes as S
from texelpad.study.quant import NINE

from support.cli import run_cli
from support.vboard import virtual_board

TPAD = {"positions": 19200, "dx_um": 5.3}
TEX = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}


def _texels(scene):
    return [r["texture"] for r in scene["regions"] if r["texture"]["kind"] == "texel"]


# --- the reading rule: no "v" is format 2 -----------------------------------------

def test_a_texture_without_v_reads_as_format_2():
    assert P.FORMAT_VERSION == 2 and P.FORMAT_NEW == 2
    assert texel.validate(TEX)["v"] == 2
    assert np.array_equal(texel.render_u16(TEX), texel.render_u16(dict(TEX, v=2)))
    assert not np.array_equal(texel.render_u16(TEX), texel.render_u16(dict(TEX, v=1)))
    # a scene file's texel region without "v": format 2
    new = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": dict(TEX, kind="texel")}]}
    (tex,) = _texels(scene_mod.validate(new, TPAD))
    assert tex["v"] == 2
    # format 1 by "v": 1, and logged draws say so when "v" is missing
    assert texel.validate(dict(TEX, v=1))["v"] == 1
    with pytest.raises(ValueError, match=r"draws: .*format 1's \(v=1\)"):
        texel.make_plan(TEX, (0.5, [0.0] * 192))


def test_the_board_reads_no_v_as_format_2_on_micropython():
    """The device code under the MicroPython unix port: validate and the
    scene builder read a texel without "v" as format 2, and it renders the
    same map as CPython (bit for bit)."""
    from support import mpy
    out = mpy.run("import texel\n"
                  "p = {'pitch_db': 6.3, 'irregularity_db': -12.9, 'seed': 7, 'length_samples': 500}\n"
                  "print(texel.validate(p)['v'])\n"
                  "print(list(texel.render_u16(p, engine='int')))\n").splitlines()
    assert out[0] == "2"
    want = texel.render_u16(dict(TEX, length_samples=500), engine="int")
    assert eval(out[1]) == list(want)


# --- texelpad scene pin: an old file keeps its texture --------------------------------

OLD = {"name": "old", "regions": [
    {"start_mm": 0, "end_mm": 40, "texture": dict(TEX, kind="texel")},
    {"start_mm": 40, "end_mm": 80, "texture": dict(TEX, kind="texel", v=2)},
    {"start_mm": 80, "end_mm": 101.76, "texture": {"kind": "reference", "name": "4sin"}}]}


def test_scene_pin_writes_v1_where_a_texel_says_nothing(tmp_path, capsys):
    f, g = tmp_path / "old.json", tmp_path / "new.json"
    f.write_text(json.dumps(OLD))
    g.write_text(json.dumps({"regions": [OLD["regions"][1]]}))
    before_g = g.read_bytes()
    code, out, err = run_cli(capsys, "scene", "pin", "--check", str(f), str(g))
    assert code == 1 and "would pin 1 texel texture" in out, (out, err)
    assert json.loads(f.read_text()) == OLD                   # --check writes nothing
    code, out, err = run_cli(capsys, "scene", "pin", str(f), str(g))
    assert code == 0, err
    assert '%s: pinned 1 texel texture without "v" to format 1' % f in out
    assert "%s: nothing to pin" % g in out
    assert g.read_bytes() == before_g                         # untouched
    pinned = json.loads(f.read_text())
    assert [r["texture"].get("v") for r in pinned["regions"]] == [1, 2, None]
    # it plays what the file played before 0.2: format 1
    (a, b) = _texels(scene_mod.validate(pinned, TPAD))
    assert a["v"] == 1 and b["v"] == 2
    # twice: nothing more to do
    code, out, err = run_cli(capsys, "scene", "pin", "--check", str(f))
    assert code == 0 and "nothing to pin" in out


def test_scene_pin_refuses_before_writing_anything(tmp_path, capsys):
    f, bad = tmp_path / "old.json", tmp_path / "bad.json"
    f.write_text(json.dumps(OLD))
    bad.write_text(json.dumps({"regions": [{"start_mm": 0, "end_mm": 1}]}))
    code, out, err = run_cli(capsys, "scene", "pin", str(f), str(bad))
    assert code == 2 and "bad.json: regions[0]: expected" in err
    assert json.loads(f.read_text()) == OLD                   # the good one was not written either
    code, out, err = run_cli(capsys, "scene", "pin", str(tmp_path / "missing.json"))
    assert code == 2 and "no such file" in err
    code, out, err = run_cli(capsys, "scene", "pin", "split-4sin")   # a shipped scene: not a file here
    assert code == 2 and "no such file" in err


# --- the command line ---------------------------------------------------------------

def test_render_default_is_format_2(tmp_path, capsys):
    base = ["render", "--pitch-db", "6.3", "--irregularity-db", "-12.9", "--seed", "7",
            "--engine", "int", "--out"]
    maps = {}
    for name, extra in (("default", []), ("2", ["--format", "2"]), ("1", ["--format", "1"])):
        f = tmp_path / ("%s.npy" % name)
        code, out, err = run_cli(capsys, *(base + [str(f)] + extra))
        assert code == 0, err
        assert "format %s" % ("2" if name == "default" else name) in out
        maps[name] = np.load(f)
    assert np.array_equal(maps["default"], maps["2"])
    assert not np.array_equal(maps["default"], maps["1"])
    # --format 1 is the lab's generator ("v": 1); no "v" is format 2
    assert np.array_equal(maps["1"], np.asarray(texel.render(dict(TEX, v=1), engine="int")))
    assert np.array_equal(maps["default"], np.asarray(texel.render(TEX, engine="int")))


def _args(*argv):
    from texelpad.cli import build_parser
    return build_parser(argv).parse_args(argv)


def test_the_texel_flags_write_v():
    for argv, want in ((["--pitch-db", "6", "--irregularity-db", "-9"], 2),
                       (["--pitch-db", "6", "--irregularity-db", "-9", "--format", "1"], 1),
                       (["--pitch-db", "6", "--irregularity-db", "-9", "--format", "2"], 2)):
        for cmd in ("push", "render"):
            assert render_params(_args(cmd, *argv))["v"] == want, (cmd, argv)
    # no texel flag: no texel texture (push --scene is not a texel push)
    assert render_params(_args("push", "--scene", "split-4sin")) == {}


def test_encode_writes_format_2_unless_asked():
    from texelpad.analysis import encoder as E
    m = np.asarray(texel.render(dict(TEX, length_samples=4800)))
    assert E.encode(m, intervals=False)["texture"]["v"] == 2
    assert E.encode(m, intervals=False, v=1)["texture"]["v"] == 1
    assert _args("encode", "--reference", "4sin").v == 2


# --- the shipped scenes and the board's default --------------------------------------

def test_every_shipped_texel_texture_says_its_format():
    found = 0
    for stem, f in shipped_scenes().items():
        scene = json.loads(f.read_text(encoding="utf-8"))
        for tex in _texels(scene):
            found += 1
            # every shipped texel texture is a demo: format 2 (none needs the lab's exact
            # generator; one that did would say "v": 1 and why in its notes)
            assert tex.get("v") == 2, stem
    assert found >= 6
    (default,) = _texels(texel.app.DEFAULT_SCENE)
    assert default["v"] == 2


# --- the lab's studies ------------------------------------------------------------------

def _header(name):
    c = C.load(name)
    config = dict(c["config"], reference=c.get("reference") or S.DEFAULT_REFERENCE)
    if c["protocol"] == "quant" and "matches" not in config:   # the paper's: the participant's
        config["matches"] = {r: {"pitch_db": 6.0, "irregularity_db": -12.0} for r in NINE}
    if c["protocol"] == "evaluate":     # a search's saved texture, its format not said
        config["textures"] = [{"name": "VTp", "reference": "4sin",
                               "texture": {"pitch_db": 6.0, "irregularity_db": -12.0}}]
        del config["reference"]
    return {"protocol": c["protocol"], "seed": 5, "config": config}


@pytest.mark.parametrize("name", sorted(C.available()))
def test_shipped_study_configs_say_format_2_and_play_it(name):
    c = C.load(name)
    assert c["config"]["texture_format"] == 2
    for fmt in (2, 1, None):            # None: a header from before the field played 2
        h = _header(name)
        if fmt is None:
            del h["config"]["texture_format"]
        else:
            h["config"]["texture_format"] = fmt
        state = protocols.start(h["protocol"], h["config"], h["seed"])
        if h["protocol"] == "free":
            scene, _ = questions.slider_scene(state, h, TPAD, 3.0, -10.0, 0)
            scenes = [scene]
        elif h["protocol"] == "mapping":
            scene, _ = questions.slider_scene(state, h, TPAD, 30, 20, 0)
            scenes = [scene]
        else:
            scenes = questions.ask(h["protocol"], state, h, TPAD).options
        while h["protocol"] == "quant" and state.current_source != "own":
            state.answer(3)                 # (the rater's trials play samples: no texel)
        if h["protocol"] == "quant":
            scenes = questions.ask("quant", state, h, TPAD).options
        while h["protocol"] == "evaluate" and not [t for sc in scenes for t in _texels(sc)]:
            state.answer(3)                 # (a real texture plays the reference: no texel)
            scenes = questions.ask("evaluate", state, h, TPAD).options
        assert scenes, name
        texs = [t for sc in scenes for t in _texels(sc)]    # (pursuit: one plays the reference)
        assert texs and all(t["v"] == (fmt or 2) for t in texs), (name, fmt, texs)
        for sc in scenes:
            scene_mod.validate(sc, TPAD)
        if h["protocol"] == "search":
            assert all(p["v"] == (fmt or 2) for p in state.candidates())


@pytest.mark.parametrize("bad", [0, 3, True, "2", 2.0])
def test_a_bad_texture_format_is_refused(bad):
    with pytest.raises(ValueError, match="texture_format"):
        protocols.start("staircase", {"texture_format": bad}, 1)


# --- on a virtual board: push, status, scene pull, the API, a session's header ---------

@pytest.fixture(scope="module")
def port():
    with virtual_board() as p:
        with texelpad.connect(p) as b:
            b.start("virtual", None, realtime=True)
        yield p


@pytest.mark.vboard
def test_cli_push_plays_format_2_and_pull_says_so(port, tmp_path, capsys):
    code, out, err = run_cli(capsys, "push", "--port", port, "--pitch-db", "6.3",
                             "--irregularity-db", "-12.9", "--seed", "7")
    assert code == 0, err
    assert "seed 7, format 2" in out
    code, out, err = run_cli(capsys, "status", "--port", port, "--json")
    assert code == 0, err
    (reg,) = json.loads(out)["scene"]["regions"]
    assert reg["kind"] == "texel" and reg["v"] == 2
    f = tmp_path / "pulled.json"
    code, out, err = run_cli(capsys, "scene", "pull", "--port", port, str(f))
    assert code == 0, err
    (tex,) = _texels(json.loads(f.read_text()))
    assert tex["v"] == 2
    # --format 1: the lab's generator, and the pulled file says 1
    code, out, err = run_cli(capsys, "push", "--port", port, "--pitch-db", "6.3",
                             "--irregularity-db", "-12.9", "--seed", "7", "--format", "1")
    assert code == 0 and "format 1" in out, err
    code, out, err = run_cli(capsys, "scene", "pull", "--port", port, str(f))
    assert code == 0, err
    assert _texels(json.loads(f.read_text()))[0]["v"] == 1


@pytest.mark.vboard
def test_api_push_texel_is_format_2_unless_v_says(port):
    with texelpad.connect(port) as b:
        params = dict(TEX)
        st = b.push_texel(params)
        assert params == TEX                            # the caller's dict is not changed
        assert st["scene"]["regions"][0]["v"] == 2
        assert _texels(b.scene_source())[0]["v"] == 2
        assert b.push_texel(dict(TEX, v=1))["scene"]["regions"][0]["v"] == 1
        # push(scene) reads a file: a texel region without "v" is format 2 on the board
        st = b.push({"regions": [{"start_mm": 0, "end_mm": 101.76,
                                  "texture": dict(TEX, kind="texel")}]})
        assert st["scene"]["regions"][0]["v"] == 2


@pytest.mark.vboard
def test_a_session_header_records_its_texture_format(port, tmp_path):
    from texelpad.study.session import Session
    from texelpad.web.owner import BoardOwner
    from texelpad.web.server import Lab
    owner = BoardOwner(port, "virtual", realtime=True)
    lab = Lab(owner, tmp_path / "data")
    try:
        for body, fmt in (({"config": "pursuit-4sin"}, 2),
                          ({"protocol": "staircase", "config": {}}, 2),
                          ({"protocol": "staircase", "config": {"texture_format": 1}}, 1)):
            view = lab.create(dict(body, participant="p01", seed=3))
            lv = lab.live[view["id"]]
            header = Session.open(lv.session.path).header
            assert header["config"]["texture_format"] == fmt, body
            assert all(t["v"] == fmt for t in _texels(lv.playing_scene)), body
    finally:
        owner.close()
        lab.close()
