"""`texelpad demo`, the quick start's main job, end to end: a virtual board
is started, the compiled image deployed into its empty flash over the link,
the split screen played, a simulated finger swept across it, and one PNG
written. The board must play exactly the map at the position it sensed, and
sense the finger within 3 positions (16 um) of where it truly is - the same
tolerance as the runtime's own swipe test."""
import pytest
import json

from texelpad.cli import main

pytestmark = [pytest.mark.vboard]


def test_demo_on_the_virtual_board(tmp_path, capsys):
    png, rep = tmp_path / "texture.png", tmp_path / "demo.json"
    code = main(["demo", "--out", str(png), "--json", str(rep)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000
    r = json.loads(rep.read_text())
    assert r["board"] == "virtual" and r["faults"] == 0
    assert r["down"] > 1000                      # the sweep was recorded
    assert r["amp_err_max"] == 0                 # played == map at the sensed position
    assert r["pos_err_max"] <= 3
    assert r["push_bytes"] < 2000                # vs the lab's 76,800 per change
    assert "wrote %s" % png in out
    assert "; the board played exactly the map (0 of %s samples differ)" % format(r["down"], ",") in out
    assert "the board sensed the finger " in out and "counts" not in out
    assert "deploy: unix image" in err and "sweeping the simulated finger" in err    # progress shown


def test_demo_refuses_a_bad_scene_before_starting_anything(tmp_path, capsys):
    f = tmp_path / "s.json"
    f.write_text('{"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "nope"}}]}')
    code = main(["demo", "--scene", str(f), "--out", str(tmp_path / "x.png")])
    _, err = capsys.readouterr()
    assert code == 2 and "regions[0].texture.kind" in err
    assert not (tmp_path / "x.png").exists()
