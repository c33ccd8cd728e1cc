"""The classroom kit (device/texel/kit.py): the button's debounce and the
LED's pattern as pure logic on CPython, the board file's "button"/"led"
keys, and the kit's loop on the MicroPython unix port's virtual board (a
scripted button, a recording LED). The power-up path (main.py with a
playlist written by `texelpad scene boot A B C`) is in
tests/host/test_cli_scene.py; on the emulated Pico in
tests/firmware/test_kit_pico.py."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from support import mpy
from texel import kit
from texel.runtime import boards

ROOT = Path(__file__).resolve().parents[2]
MS = 1000                   # ticks_us per ms


def _presses(levels, every_ms=kit.POLL_MS):
    """The polls at which Debounce says "pressed", for one level per poll."""
    d = kit.Debounce(level=levels[0])
    return [i for i, lv in enumerate(levels) if d.feed(lv, i * every_ms * MS)]


def test_a_clean_press_counts_once_after_the_hold():
    levels = [0] * 5 + [1] * 10 + [0] * 5
    assert _presses(levels) == [5 + kit.DEBOUNCE_MS // kit.POLL_MS]


def test_contact_bounce_is_one_press():
    bouncy = [0] * 5 + [1, 0, 1, 0, 0, 1] + [1] * 8 + [0, 1, 0] + [0] * 8
    assert len(_presses(bouncy)) == 1


def test_a_glitch_shorter_than_the_hold_is_no_press():
    assert _presses([0] * 5 + [1, 1] + [0] * 10) == []          # 20 ms < 30 ms


def test_held_at_start_waits_for_a_release():
    assert _presses([1] * 20) == []
    assert len(_presses([1] * 10 + [0] * 5 + [1] * 5)) == 1


def test_two_presses_two_steps():
    assert len(_presses(([0] * 6 + [1] * 6) * 2 + [0] * 4)) == 2


def test_the_led_blinks_the_scene_number_then_stays_on():
    writes = []
    b = kit.Blinker(writes.append)
    t = 0
    b.show(2, t)                                # the third scene: three blinks
    while t < 5000 * MS:
        t += 10 * MS
        b.update(t)
    assert writes == [0, 1, 0, 1, 0, 1, 0, 1]


def _pico():
    return json.loads((ROOT / "device/texel/boards.d/pico.json").read_text())


@pytest.mark.parametrize("patch, where", [
    ({"button": {"pin": 16}}, "button.pin: 16 is a carrier, sensor or button pin"),
    ({"button": {"pin": "GP15"}}, "button.pin: 'GP15': a GPIO number, or 'bootsel'"),
    ({"button": {"pin": 40}}, "button.pin: 40 is out of range"),
    ({"led": {"pin": "LED", "active_low": 2}}, "led.active_low: 2 is out of range"),
    ({"led": {"pin": 25, "colour": "red"}}, "led.colour: unknown key"),
    ({"button": {"pin": True}}, "button.pin: expected a pin"),
    ({"button": {"pin": 15}, "led": {"pin": 15}}, "led.pin: 15 is a carrier, sensor or button pin"),
])
def test_bad_button_and_led_keys_are_named(patch, where):
    d = _pico()
    d.update(patch)
    with pytest.raises(ValueError) as e:
        boards.validate(d, "boards/pico.json")
    assert where in str(e.value), str(e.value)


def test_button_and_led_keys_are_canonical():
    d = _pico()
    d.update({"button": {"pin": 15}, "led": {"pin": "LED"}})
    b = boards.validate(copy.deepcopy(d), "boards/pico.json")
    assert b["button"] == {"pin": 15, "active_low": 1}
    assert b["led"] == {"pin": "LED", "active_low": 0}
    assert "button" not in boards.validate(_pico(), "boards/pico.json")   # the port's default


RUN_ON_VIRTUAL = """
import json, texel.app as app, texel.kit as kit
P = %r
app.start('virtual', P[0])
hw = app._rt.hw
hw.button_levels = [0] * 4 + [1, 0, 1] + [1] * 5 + [0] * 6 + [1] * 5 + [0] * 5
lines = []
k = kit.run(P, polls=80, log=lines.append)
st = app.status()
print(json.dumps({"k": k, "name": st["scene"]["name"], "lines": lines,
                  "led": [lv for t, lv in hw.led_log], "faults": st["faults"]}))
"""


def _scene(name, pitch):
    return {"name": name, "regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
        "kind": "texel", "pitch_db": pitch, "irregularity_db": -10.0, "seed": 3}}]}


@pytest.mark.vboard
def test_the_kit_steps_the_playlist_on_the_virtual_board():
    playlist = [_scene("one", 2.0), _scene("two", 4.0),
                {"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "texel",
                                                                   "pitch_db": 99.0}}]},
                _scene("four", 8.0)]
    got = mpy.run_json(RUN_ON_VIRTUAL % (playlist,))
    # two presses (the first bounces): "two", then the refused third is skipped for "four"
    assert got["k"] == 3 and got["name"] == "four", got
    assert got["lines"][0] == "texelpad: scene 2 of 4", got
    assert got["lines"][1].startswith("texelpad: scene 3 of 4 not played: regions[0]"), got
    assert got["lines"][2] == "texelpad: scene 4 of 4", got
    # each pattern starts dark (the power-up's and two steps'), then blinks
    assert got["led"][0] == 0 and got["led"].count(0) >= 3 and 1 in got["led"], got
    assert got["faults"] == 0, got
