"""Issue 34: the texelpad firmware for the pyboard v1.1 (boards/pyboard: MicroPython v1.28's stm32
port with texel frozen in and its data in a ROMFS partition), built from the stm32 sources the
emulated STM32's kit carries; and its emulated twin (boards/pyboard/qemu: the same firmware with
the kit's QEMU board definition) booted on the emulated STM32F405
(../shared/instruments/stm32emu, `--icount 3`), checked through its serial port as a user's host
sees it: the command line's push/status/stop, TIM8's registers (carrier period, dead time, MOE,
CCR1) as a finger (`--adc file:`) moves over a known texture, bad pushes refused while it plays,
a plain `mpremote exec` on a playing board, format 2's hash. No timing asserted: the figures are
the benchmark's (python -m bench.stm32)."""
from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from support.cli import run_cli
from support.firmware import built
from support.stm32 import emulated_stm32

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

ROOT = Path(__file__).resolve().parents[2]
# TIM8 (the carrier, RM0090 register map): CR1, CCER, ARR, CCR1, BDTR; TIM7 (the refresh): CR1
TIM8, TIM7 = 0x40010400, 0x40001400
REGS = ("import machine; m = machine.mem32; print(repr(tuple(m[a] & 0xFFFFFFFF for a in %r)))"
        % ((TIM8, TIM8 + 0x20, TIM8 + 0x2C, TIM8 + 0x34, TIM8 + 0x44, TIM7),))
FULL = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                     "texture": {"kind": "texel", "pitch_db": 8.0, "irregularity_db": -9.0,
                                 "seed": 21}}]}


@pytest.fixture(scope="module")
def twin():
    return built("pyboard", qemu=True)


@pytest.fixture(scope="module")
def finger(tmp_path_factory):
    f = tmp_path_factory.mktemp("finger") / "adc.txt"
    f.write_text("2000\n")
    return f


@pytest.fixture(scope="module")
def board(twin, finger):
    with emulated_stm32(adc="file:%s" % finger, firmware=twin) as emu:
        yield emu


def _connect(port):
    from texelpad.link.board import connect
    return connect(port, timeout=60)


def _regs(b) -> dict:
    cr1, ccer, arr, ccr1, bdtr, t7 = b.link.eval(REGS)
    return {"tim8_on": cr1 & 1, "outputs": ccer & 0x5, "arr": arr, "ccr1": ccr1,
            "moe": bdtr >> 15 & 1, "dtg": bdtr & 0xFF, "tim7_on": t7 & 1}


def test_the_pyboard_image_builds_as_a_dfu_with_its_romfs():
    """`texelpad firmware --board pyboard`: the .dfu holds the firmware's two blocks and the
    ROMFS partition where the linker script puts them; the DfuSe writer is the stm32
    port's own byte for byte; the partition holds the board file and firmware.json."""
    from texelpad import image
    from texelpad.firmware import build_stm32, dfuse, romfs
    fw = built("pyboard")
    lay = build_stm32.flash_layout(ROOT / "boards" / "pyboard")
    blocks = dfuse.read_dfuse(fw.image.read_bytes())
    assert [a for a, _d in blocks] == [0x08000000, 0x08020000, lay["romfs"][0]] == \
        [0x08000000, 0x08020000, 0x080C0000]
    assert blocks[2][1][:len(fw.romfs.read_bytes())] == fw.romfs.read_bytes()
    assert len(blocks[1][1]) <= lay["text"][1] and fw.romfs_bytes <= lay["romfs"][1]
    port_dfu = (fw.build_dir / "firmware.dfu").read_bytes()      # the Makefile's tools/dfu.py
    assert dfuse.dfuse_file(blocks[:2]) == port_dfu
    files = romfs.read_romfs(fw.romfs.read_bytes())
    info = json.loads(files["firmware.json"])
    assert info["board"] == "pyboard" and info["code_in_romfs"] is False
    assert files["lib/texel/boards.d/pyboard.json"] == (ROOT / "boards/pyboard/board.json").read_bytes()
    # the three slowest references' maps (image.MAP_NAMES), not all nine; no RAM modules
    maps = {k for k in files if k.startswith("lib/texel/gen/ref/")}
    assert maps == {"lib/texel/gen/ref/%s.u16" % n for n in image.MAP_NAMES}
    assert all(files[k] == v for k, v in romfs.reference_maps(image.MAP_NAMES).items())
    assert not any(k.startswith("lib/texel_ram/") for k in files)
    nm = subprocess.run(["arm-none-eabi-nm", str(fw.elf)], capture_output=True, text=True).stdout
    assert "mp_module_usb" in nm or "pyb_usb_vcp_type" in nm          # the real board: USB
    assert "texelcore_module" in nm                                   # the C core
    print("\npyboard image: firmware %s B (FLASH_TEXT %s B), ROMFS %s of %s B, built in %.0f s"
          % (format(fw.firmware_bytes, ","), format(lay["text"][1], ","),
             format(fw.romfs_bytes, ","), format(fw.romfs_capacity, ","), fw.seconds))


def test_the_twin_boots_playing_its_power_up_scene_from_frozen_code(board, twin):
    with _connect(board.port) as b:
        st0 = b.status()
        b.link.exec("import time; time.sleep_ms(500)")
        st = b.status()
        where = b.link.eval("import texel, sys\nfrom texel import compat\nprint(repr("
                            "(texel.__file__, sys.path, sys.implementation._build, compat.ROM, "
                            "str(compat.core()))))")
        info = json.loads(b.link.eval("print(repr(open('/rom/firmware.json').read()))"))
        regs = _regs(b)
    assert st["running"] and st["board"] == "pyboard" and st["refresh_mode"] == "timer_irq"
    # the refresh interrupt runs the C core on the chip's registers (texel/hw/stm32_irq.py)
    assert (st["refresh"], st["refresh_code"]) == ("viper-irq", "c"), st
    assert st["refreshes"] > st0["refreshes"] and st["faults"] == 0 and st["overruns"] == 0
    assert where[0] == "texel/__init__.py" and where[2] == "TEXELPAD_PYBOARD" and where[3] is True
    assert "_texelcore" in where[4]
    assert info["board"] == "pyboard"
    # the carrier: 168 MHz / 34 kHz -> ARR 4940; dead time 200 ns = 34 ticks; outputs on
    assert regs["tim8_on"] == regs["moe"] == regs["tim7_on"] == 1 and regs["outputs"] == 0x5
    assert (regs["arr"], regs["dtg"]) == (4940, 34)
    print("\ntwin: %s, heap free playing the power-up scene %s B; since boot %d overruns, "
          "worst %d us" % (st["firmware"], format(st["mem_free"], ","), st["overruns"],
                           st["worst_us"]))


def _expected(raw12: int, texture: dict) -> tuple[int, int]:
    """(position, CCR1) the pyboard's refresh settles on with the finger still at the 12-bit
    ADC value raw12 over a full-screen texel region: the board file's calibration, the
    device's own tracker and duty law run here (CPython), the map rendered here."""
    import texel
    from texel.runtime import boards, duty, sensor
    board = boards.load("pyboard")
    u16 = raw12 << 4 | raw12 >> 8                 # hw/stm32.py: pyb.ADC in read_u16 units
    s = sensor.make_sensor(board["sensor"], [lambda: u16], 19200, board["refresh"]["hz"])
    for _ in range(2000):
        pos = s.read()
    params = {k: v for k, v in texture.items() if k != "kind"}
    m = np.asarray(texel.render_u16(dict(params, v=2, length_samples=19200), engine="int"))
    law = duty.DutyLaw(4940, board["carrier"]["duty_cap"])      # hw.top: ARR
    return pos, law.duty(int(m[pos]))


def test_push_status_stop_and_the_carrier_follows_the_finger(board, finger, capsys, tmp_path):
    port = board.port
    code, out, err = run_cli(capsys, "push", "--port", port, "--pitch-db", "8",
                             "--irregularity-db", "-9", "--seed", "21")
    assert code == 0, err
    tex = FULL["regions"][0]["texture"]
    f = tmp_path / "s.json"
    code, out, err = run_cli(capsys, "scene", "pull", str(f), "--port", port)
    assert code == 0, err
    regions = json.loads(f.read_text())["regions"]
    got = regions[0]["texture"]
    assert len(regions) == 1 and {k: got[k] for k in tex} == tex and got["v"] == 2, regions
    seen = []
    for raw in (700, 2000, 3100):
        finger.write_text("%d\n" % raw)
        with _connect(port) as b:
            b.link.exec("import time; time.sleep_ms(60)")      # ~500 refreshes: settled
            st = b.status()
            regs = _regs(b)
        pos, ccr = _expected(raw, tex)
        seen.append((raw, st["position"], pos, regs["ccr1"], ccr))
        assert st["position"] == pos and regs["ccr1"] == ccr == st["duty"], seen
    assert len({c for *_x, c in seen}) == 3, seen            # three different duties
    code, out, err = run_cli(capsys, "status", "--port", port)
    assert code == 0 and "board pyboard (stm32), refresh viper-irq at 8333 Hz" in out, out + err
    with _connect(port) as b:
        st = b.status()
    # the refresh keeps its rate through all that traffic, with none overrun (the core times
    # itself on TIM2's microsecond counter)
    assert abs(st["rate_hz"] - 8333) < 84 and st["faults"] == 0 and st["overruns"] == 0, st
    overruns = (st["overruns"], st["worst_us"])
    code, out, err = run_cli(capsys, "stop", "--port", port)
    assert code == 0, err
    with _connect(port) as b:
        regs = _regs(b)
        assert not b.status()["running"]
    assert regs["ccr1"] == 0 and regs["moe"] == 0 and regs["tim7_on"] == 0, regs
    print("\nfinger raw -> position (board, host), CCR1 (board, host): %s; overruns %d, worst "
          "%d us since the push" % ((seen,) + overruns))


def test_a_bad_push_is_refused_and_the_scene_kept(board):
    from texelpad.link.transport import LinkError
    with _connect(board.port) as b:
        b.start("pyboard", FULL)                    # (the test before stopped it)
        before = b.scene_source()
        for bad in ({"regions": [{"start_mm": 0, "end_mm": 50,
                                  "texture": {"kind": "reference", "name": "nope"}}]},
                    {"regions": [{"start_mm": 0, "end_mm": 50,
                                  "texture": {"kind": "texel", "pitch_db": 99}}]}):
            with pytest.raises((ValueError, LinkError)):
                b.push(bad)
            assert b.scene_source() == before and b.status()["running"]


def test_format_2_on_the_twin_hashes_as_on_cpython(board):
    import texel
    cases = [{"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2},
             {"pitch_db": -20.0, "irregularity_db": 5.0, "texel_samples": 1, "seed": 4294967295,
              "v": 2, "length_samples": 600}]
    with _connect(board.port) as b:
        got = b.link.eval("import texel, hashlib, binascii\nprint(repr([binascii.hexlify("
                          "hashlib.sha256(texel.render_u16(p, engine='int')).digest()) "
                          "for p in %r]))" % (cases,))
    want = [hashlib.sha256(np.asarray(texel.render_u16(p, engine="int"), dtype="<u2")
                           .tobytes()).hexdigest() for p in cases]
    assert [g.decode() for g in got] == want


def test_a_plain_mpremote_exec_on_the_playing_twin(board):
    """The teacher's one-liner: mpremote soft-resets around it (raw REPL, so the frozen
    main.py does not run again): the piezo is left undriven, the REPL answers, and texelpad
    starts the display again."""
    with _connect(board.port) as b:
        b.push(FULL)
        assert b.status()["running"]
    mp = str(Path(sys.executable).with_name("mpremote"))
    p = subprocess.run([mp, "connect", board.port, "exec",
                        "import texel.app as app; print(app.status()['running'])"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "False" in p.stdout, p.stdout + p.stderr
    with _connect(board.port) as b:
        regs = _regs(b)
        # the soft reset's safe state (tests/host/test_emulated_stm32.py): both timers
        # stopped, TIM8's outputs disabled (CCR1 keeps its last value, driving nothing)
        assert regs["tim7_on"] == regs["tim8_on"] == regs["outputs"] == 0, regs
        st = b.start("pyboard", FULL)
        assert st["running"] and st["faults"] == 0
    assert board.alive()


def test_deploy_refuses_the_frozen_firmware_and_changes_nothing(board, capsys):
    """`texelpad deploy` onto the pyboard's texelpad firmware: its frozen texel would shadow
    files written to the filesystem, so it refuses, saying how to update, before writing."""
    with _connect(board.port) as b:
        before = b.status()["running"]
    code, out, err = run_cli(capsys, "deploy", "--port", board.port)
    assert code == 1 and "runs the texelpad firmware for board pyboard" in err, out + err
    assert "texelpad firmware --board pyboard" in err
    with _connect(board.port) as b:
        assert b.status()["running"] == before


def test_a_full_screen_reference_over_another_is_built_in_its_room(board):
    """2sin and pink have no map in the pyboard's partition (only image.MAP_NAMES do): a
    full-screen one is 38.4 KB of RAM, and a second does not fit beside the first on the
    F405's heap. texel.app builds it in the playing scene's room (MAKE_ROOM): both pushes
    play, the second says made_room."""
    ref = lambda name: {"regions": [{"start_mm": 0, "end_mm": 101.76,              # noqa: E731
                                     "texture": {"kind": "reference", "name": name}}]}
    with _connect(board.port) as b:
        b.start("pyboard", ref("2sin"))
        st = b.push(ref("pink"))
        assert st["running"] and st["last_push"].get("made_room") is True, st["last_push"]
        src = b.scene_source()
        st = b.status()
    assert [r["texture"]["name"] for r in src["regions"]] == ["pink"]
    assert st["faults"] == 0 and st["overruns"] == 0
    print("\nreference over reference on the twin: made room, building took %.1f ms (the display "
          "idle meanwhile), %s B free after" % (st["last_push"]["build_us"] / 1000.0,
                                                format(st["mem_free"], ",")))


def test_a_slot_naming_the_playing_w_leaves_the_room_to_the_next_reference(board):
    """A refresh interrupt's frame can leave the playing W (refresh_fast: raw addresses of
    the scene's buffers) in a stack slot the collector later scans; MicroPython's collector
    reads every word of a block it reaches, so that one slot kept the old full-screen map
    alive and the push after it found no room: 1-6 of 60 reference-over-reference pushes on
    this twin played idle, and a start over a playing full-screen reference did not start.
    Here the slot is a REPL global holding W through the push and the start: the swap
    zeroes the dropped W (refresh_fast._wipe), the push is built in the room, and stop()
    zeroes the last W (FastRefresh.release) before the new start builds."""
    ref = lambda name: {"regions": [{"start_mm": 0, "end_mm": 101.76,              # noqa: E731
                                     "texture": {"kind": "reference", "name": name}}]}
    with _connect(board.port) as b:
        b.start("pyboard", ref("3sin"))
        b.link.exec("import texel.runtime.refresh_fast as _rf; _held = [_rf._W]")
        st = b.push(ref("blue"))
        held = b.link.eval("print(sum(1 for v in _held[0] if v))")
        # and a start over the playing map (stop() zeroes the W it leaves: release())
        b.link.exec("_held = [_rf._W]")
        again = b.start("pyboard", ref("white"))
        b.link.exec("del _held")
    assert st["running"] and st["last_push"].get("made_room") is True, st["last_push"]
    assert held == 0
    assert again["running"], again


def test_the_slowest_references_play_from_the_partition(board):
    """square, triangle and sawtooth (image.MAP_NAMES) play in place from the partition's
    maps: no RAM for their samples, the same values as the host's map, and one pushed over
    another needs no room made (a render took 266-290 ms of a split screen and 38.4 KB of
    the heap before)."""
    from texelpad import image
    from texelpad.firmware import romfs
    full = lambda name: {"regions": [{"start_mm": 0, "end_mm": 101.76,             # noqa: E731
                                      "texture": {"kind": "reference", "name": name}}]}
    host = {n: np.frombuffer(m, dtype="<u2")
            for n, m in romfs.reference_maps(image.MAP_NAMES).items()}
    with _connect(board.port) as b:
        b.push({"regions": [{"start_mm": 0, "end_mm": 101.76,
                             "texture": {"kind": "constant", "level": 0.5}}]})
        for name in image.MAP_NAMES:
            st = b.push(full(name))
            lp = st["last_push"]
            assert st["running"] and "made_room" not in lp, lp
            assert lp["scene_bytes"] < 1024, lp             # the region table alone
            got = b.link.eval("import texel.app as _A\nprint(repr([_A._rt.refresh.scene.amp(p) "
                              "for p in range(0, 19200, 97)]))")
            want = host["lib/texel/gen/ref/%s.u16" % name]
            assert got == [int(want[p]) for p in range(0, 19200, 97)], name
            print("\n%s from the partition: build %.2f ms" % (name, lp["build_us"] / 1000.0))

