"""A maker's own board file (issue 19): `texelpad board check` names every
problem of a board file for its chip and firmware - the board's own
validation and the chip's facts (RP2040 GPIO, PWM slices and channels, ADC
pins, PLL clocks; STM32F405 timer and ADC pins) - one line each, exit 2; a
good file exits 0 with a summary. `texelpad board install` refuses the same
files without touching the board, and puts a good one in /boards/NAME.json
on the board's flash, where `texelpad push --board NAME` finds it."""
import json
from pathlib import Path

import pytest

import texelpad
from texel.runtime import boards
from texelpad.deploy import boardcheck as bc
from texelpad.sim.virtual import VirtualBoard
from support.cli import run_cli

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "device" / "texel" / "boards.d").glob("*.json"))
NO_PORT = "/dev/ttyTEXELPAD-none"


def _load(name):
    return json.loads((ROOT / "device" / "texel" / "boards.d" / (name + ".json")).read_text())


def _errors(doc, firmware="stock"):
    return [(p.path, p.message) for p in bc.check(doc, firmware).errors]


def _warnings(doc, firmware="stock"):
    return [(p.path, p.message) for p in bc.check(doc, firmware).warnings]


def _write(tmp_path, doc, name=None):
    f = tmp_path / ("%s.json" % (name or doc["name"]))
    f.write_text(json.dumps(doc, indent=1))
    return f


# --- the checks (pure) --------------------------------------------------------------

@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_every_shipped_board_passes(path, capsys):
    doc, probs = bc.read_board(path.read_bytes())
    assert probs == []
    rep = bc.check(doc, "stock", path.stem)
    assert rep.ok and rep.problems == [], rep.problems
    assert rep.board == boards.validate(doc, str(path))
    if doc["port"] in ("rp2", "virtual"):
        assert bc.check(doc, "texelpad", path.stem).problems == []
    code, out, err = run_cli(capsys, "board", "check", str(path))
    assert code == 0 and err == "", err
    top = boards.board_top(rep.board)
    assert format(top + 1, ",") in out and "%s:" % doc["name"] in out


def test_wrong_slice():
    d = _load("pico")
    d["carrier"]["pwm"]["slice"] = 1
    (path, msg), = _errors(d)
    assert path == "carrier.pwm.slice"
    assert "GPIO 16 is PWM slice 0 channel A" in msg and '"slice": 0' in msg


def test_bridge_pins_on_two_slices():
    d = _load("pico_bridge")
    d["carrier"]["pins"] = [16, 19]
    (path, msg), = _errors(d)
    assert path == "carrier.pins"
    assert "slice 0 channel A" in msg and "slice 1 channel B" in msg and "[16, 17]" in msg
    d["carrier"]["pins"] = [0, 16]           # one slice, but both channel A
    (path, msg), = _errors(d)
    assert path == "carrier.pins" and "same output (slice 0 channel A)" in msg


def test_adc_on_gp16():
    d = _load("pico")
    d["carrier"]["pins"] = [15]
    d["carrier"]["pwm"] = {}
    d["sensor"]["pins"] = [16]
    (path, msg), = _errors(d)
    assert path == "sensor.pins[0]" and "GPIO 16 has no ADC" in msg and "26 .. 29" in msg


def test_pin_collision():
    d = _load("pico")
    d["carrier"]["pins"] = [26]
    d["carrier"]["pwm"] = {}
    (path, msg), = _errors(d)
    assert path == "sensor.pins[0]" and "GPIO 26 is also carrier.pins[0]" in msg
    d = _load("pico")
    d["sensor"]["kind"] = "adc_ratio"
    d["sensor"]["pins"] = [27, 27]
    (path, msg), = _errors(d)
    assert path == "sensor.pins[1]" and "also sensor.pins[0]" in msg


def test_gp23_on_a_pico_is_a_warning():
    d = _load("pico")
    d["carrier"]["pins"] = [23]
    d["carrier"]["pwm"] = {}
    assert _errors(d) == []
    (path, msg), = _warnings(d)
    assert path == "carrier.pins[0]" and "GPIO 23" in msg and "Pico" in msg and "SMPS" in msg
    (path, msg), = _warnings(d, "texelpad")
    assert "texelpad firmware" in msg
    d["carrier"]["pins"] = [30]               # no such GPIO at all
    (path, msg), = _errors(d)
    assert path == "carrier.pins[0]" and "does not exist" in msg and "0 .. 29" in msg


def test_carrier_frequency_with_too_few_counts():
    d = _load("pico")
    d["cpu_hz"] = 48000000                    # the PLL makes 48 MHz
    d["carrier"]["freq_hz"] = 150000          # 320 counts
    errs = _errors(d)
    assert len(errs) == 1, errs
    path, msg = errs[0]
    assert path == "carrier.freq_hz" and "320 PWM counts" in msg and "at least 500" in msg
    assert "at most 96,096 Hz" in msg
    hi = 96096
    assert boards.pwm_top(48000000, hi) + 1 >= 500 > boards.pwm_top(48000000, hi + 1) + 1
    # too many counts for the refresh's small-int compare words
    d = _load("pico")
    d["carrier"]["freq_hz"] = 5000
    (path, msg), = _errors(d)
    assert path == "carrier.freq_hz" and "16,382" in msg and "at least 7,630 Hz" in msg


def test_clocks_the_rp2040_cannot_make():
    d = _load("pico")
    d["cpu_hz"] = 125000001
    (path, msg), = _errors(d)
    assert path == "cpu_hz" and "PLL" in msg and "125,000,000" in msg
    d["cpu_hz"] = 250000000
    (path, msg), = _errors(d)
    assert path == "cpu_hz" and "rating" in msg
    d["cpu_hz"] = 133000000                    # fine, but texelpad does not set the clock
    assert _errors(d) == []
    assert [p for p, m in _warnings(d) if "machine.freq(133000000)" in m] == ["cpu_hz"]
    assert 125000 in bc.pll_clocks_khz() and 133000 in bc.pll_clocks_khz()


def test_all_problems_at_once():
    """validate stops at its first refusal; the check goes on."""
    d = _load("pico")
    d["colour"] = "red"                                    # unknown
    d["carrier"]["duty_cap"] = 0.9                         # validate, then again without it
    d["carrier"]["pwm"]["slice"] = 3                       # the chip
    d["sensor"]["pinz"] = [26]                             # unknown, near "pins"
    d["sensor"]["filter_shift"] = 99                       # validate
    d["refresh"]["mode"] = "core1_viper"                   # not built yet
    paths = [p for p, _ in _errors(d)]
    assert sorted(paths) == sorted(["colour", "carrier.duty_cap", "carrier.pwm.slice",
                                    "sensor.pinz", "sensor.filter_shift", "refresh.mode"])
    assert "did you mean 'pins'" in dict(_errors(d))["sensor.pinz"]
    # a refusal of the pin list as a whole (the bridge pair) leaves its pins to the chip
    d = _load("pico_bridge")
    d["carrier"]["pins"] = [18, 21]
    d["sensor"]["pins"] = [18]
    errs = _errors(d)
    assert [p for p, _ in errs] == ["carrier.pins", "carrier.pwm.slice", "sensor.pins[0]",
                                    "sensor.pins[0]"]
    assert 'set "slice": 1' in errs[1][1]


def test_stm32_timer_and_adc_pins():
    d = _load("pyboard")
    d["carrier"]["pins"] = ["Y2", "X8"]
    d["sensor"]["pins"] = ["PC6"]
    errs = dict(_errors(d))
    assert "is not TIM8_CH1" in errs["carrier.pins[0]"] and "Y1 (PC6)" in errs["carrier.pins[0]"]
    assert "no ADC input" in errs["sensor.pins[0]"]
    d = _load("pyboard")
    d["sensor"]["pins"] = ["PC6"]                          # = Y1, the carrier's leg A
    msgs = [m for p, m in _errors(d) if p == "sensor.pins[0]"]
    assert len(msgs) == 2 and "is pin PC6, also carrier.pins[0]" in msgs[0], msgs


def test_texelpad_firmware_runs_rp2_and_stm32_only():
    assert _errors(_load("pyboard"), "texelpad") == []          # boards/pyboard (issue 34)
    (path, msg), = _errors(_load("pico_cpy"), "texelpad")
    assert path == "port" and "--firmware stock" in msg


@pytest.mark.parametrize("data, words", [
    (b"", "empty"),
    (b"{\"name\": ", "not valid JSON"),
    (b"\xff\xfe", "not UTF-8"),
    (b"[" * 50000 + b"]" * 50000, "nested too deeply"),
    (b"{\"a\": NaN}", "NaN is not a JSON number"),
    (b"{\"a\": " + b"9" * 5000 + b"}", "more than 40 digits"),
    (b"{\"wiring\": \"" + b"x" * 70000 + b"\"}", "a board file is a few KB"),
])
def test_not_a_board_file_is_one_line(tmp_path, capsys, data, words):
    doc, probs = bc.read_board(data)
    assert doc is None and len(probs) == 1 and words in probs[0].message
    f = tmp_path / "x.json"
    f.write_bytes(data)
    code, out, err = run_cli(capsys, "board", "check", str(f))
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 2, err
    assert lines[0].startswith(str(f) + ": ") and words in lines[0]


@pytest.mark.parametrize("doc, words", [([1, 2], "not a list"), ("pico", "not a string"),
                                        (None, "not null")])
def test_not_an_object(tmp_path, capsys, doc, words):
    f = tmp_path / "x.json"
    f.write_text(json.dumps(doc))
    code, out, err = run_cli(capsys, "board", "check", str(f))
    assert code == 2 and words in err.splitlines()[0], err


def test_check_prints_every_problem_a_line(tmp_path, capsys):
    d = _load("pico_bridge")
    d["name"] = "mine"
    d["carrier"]["pins"] = [16, 19]
    d["sensor"]["pins"] = [16]
    f = _write(tmp_path, d)
    code, out, err = run_cli(capsys, "board", "check", str(f))
    lines = err.strip().splitlines()
    assert code == 2 and out == ""
    assert lines[:-1] == [str(f) + ": carrier.pins: " + m for p, m in _errors(d)
                          if p == "carrier.pins"] + [
        str(f) + ": sensor.pins[0]: " + m for p, m in _errors(d) if p == "sensor.pins[0]"]
    assert "3 problems" in lines[-1]


# --- install --------------------------------------------------------------------------

def test_install_refuses_a_bad_file_before_any_board(tmp_path, capsys):
    d = _load("pico")
    d["name"] = "mine"
    d["carrier"]["pwm"]["slice"] = 5
    f = _write(tmp_path, d)
    code, out, err = run_cli(capsys, "board", "install", str(f), "--port", NO_PORT)
    assert code == 2 and "carrier.pwm.slice" in err and "no such" not in err.lower(), err
    code, out, err = run_cli(capsys, "board", "install", str(f), "--name", "Bad Name",
                             "--port", NO_PORT)
    assert code == 2 and err.startswith("texelpad board: error: --name:"), err


@pytest.fixture(scope="module")
def flash_board(tmp_path_factory):
    flash = tmp_path_factory.mktemp("board-flash")
    with VirtualBoard(flash, image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None, realtime=True)
        yield vb.port, flash


def _mine(name="mine"):
    d = _load("virtual")
    d["name"] = name
    d["title"] = "my own virtual board"
    d["refresh"]["hz"] = 5000
    return d


@pytest.mark.vboard
def test_install_then_push_board_uses_it(capsys, tmp_path, flash_board):
    port, flash = flash_board
    f = _write(tmp_path, _mine())
    code, out, err = run_cli(capsys, "board", "install", str(f), "--port", port)
    assert code == 0, err
    landed = flash / "boards" / "mine.json"
    assert landed.read_bytes() == f.read_bytes()
    assert not (flash / "boards" / "mine.json.new").exists()
    assert "/boards/mine.json" in out and "texelpad push --board mine" in out
    code, out, err = run_cli(capsys, "stop", "--port", port)
    assert code == 0, err
    code, out, err = run_cli(capsys, "push", "--board", "mine", "--port", port,
                             "--constant", "0.5")
    assert code == 0, err
    with texelpad.connect(port) as b:
        st = b.status()
    assert st["board"] == "mine" and st["refresh_hz"] == 5000, st
    code, out, err = run_cli(capsys, "status", "--port", port)
    assert code == 0 and "mine" in out, out

    # installed again under another name: "name" follows the file name; --boot
    code, out, err = run_cli(capsys, "board", "install", str(f), "--name", "mine2", "--boot",
                             "--port", port)
    assert code == 0, err
    again = json.loads((flash / "boards" / "mine2.json").read_text())
    assert again == dict(_mine(), name="mine2")
    boot = json.loads((flash / "texelpad.json").read_text())
    assert boot["board"] == "mine2" and boot["scene"]["regions"]

    # a file the board cannot run (an rp2 board on the unix port) is not written
    rp2 = dict(_load("pico"), name="mypico")
    code, out, err = run_cli(capsys, "board", "install", str(_write(tmp_path, rp2)),
                             "--port", port)
    assert code == 2 and "nothing was written" in err, err
    assert not (flash / "boards" / "mypico.json").exists()


@pytest.mark.vboard
def test_bad_file_installs_nothing_and_keeps_the_old_one(capsys, tmp_path, flash_board):
    port, flash = flash_board
    good = _write(tmp_path, _mine("keep"))
    code, out, err = run_cli(capsys, "board", "install", str(good), "--port", port)
    assert code == 0, err
    before = (flash / "boards" / "keep.json").read_bytes()
    bad = _mine("keep")
    bad["carrier"]["freq_hz"] = 500
    bad["sensor"]["pins"] = [16]
    f = _write(tmp_path, bad)
    code, out, err = run_cli(capsys, "board", "install", str(f), "--port", port)
    assert code == 2 and "carrier.freq_hz" in err, err
    assert (flash / "boards" / "keep.json").read_bytes() == before
    assert sorted(p.name for p in (flash / "boards").iterdir()
                  if p.name.startswith("keep")) == ["keep.json"]
    (tmp_path / "junk.json").write_text("{not json")
    code, out, err = run_cli(capsys, "board", "install", str(tmp_path / "junk.json"),
                             "--port", port)
    assert code == 2 and "not valid JSON" in err
    assert (flash / "boards" / "keep.json").read_bytes() == before


def test_the_black_pill_file_is_clean_and_a_pyboard_pin_still_warns():
    """Issue 34: the WeAct Black Pill (STM32F411CE) board file names pyb's CPU pins (A8, B13,
    A1: its MicroPython names no header pins) and runs TIM1 at 96 MHz: no problem, and none
    of the pyboard-only warnings. A pyboard file (X/Y names) on PA8 still hears of the SD
    card switch."""
    doc = _load("blackpill_f411")
    assert bc.check(doc, "stock").problems == []
    (path, msg), = _errors(doc, "texelpad")           # no texelpad firmware for an F411
    assert path == "cpu_hz" and "--firmware stock" in msg
    rep = bc.check(doc, "stock")
    assert rep.board is not None and rep.board["refresh"]["timer"] == 11
    py = _load("pyboard")
    py["carrier"]["pins"] = ["X19", "A8"]
    py["sensor"]["pins"] = ["X20"]
    assert any("SD card switch" in m for _p, m in _warnings(py))
