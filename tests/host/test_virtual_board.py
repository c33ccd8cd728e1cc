"""The virtual board behaves like a board around its REPL: mpremote's default
soft reset (Ctrl-D in the raw REPL) restarts the interpreter on the same port
instead of killing it; `texelpad virtual` stops cleanly on SIGTERM (no
MicroPython left running, no temporary flash left behind) and announces
itself to `texelpad ports` / `status` without --port; a stepped (not
realtime) virtual board is reported as such by status."""
import ast
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import texelpad
from texelpad.sim.virtual import VirtualBoard, running_boards
from support.vboard import mpremote
from support.cli import run_cli

pytestmark = [pytest.mark.vboard]

TEXELPAD = [sys.executable, "-m", "texelpad.cli"]
MPREMOTE = os.path.join(os.path.dirname(sys.executable), "mpremote")




def _gone(pid):
    """The process has exited (no such pid, or a zombie awaiting its reaper)."""
    try:
        state = Path("/proc/%d/stat" % pid).read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return True
    return state in ("Z", "X")


def _children(pid):
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if int((d / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    out.append(int(d.name))
            except (OSError, IndexError, ValueError):
                pass
    return out


@pytest.fixture
def registry(tmp_path, monkeypatch):
    """An empty registry of running virtual boards (not the user's)."""
    d = tmp_path / "run"
    monkeypatch.setenv("TEXELPAD_RUNTIME_DIR", str(d))
    return d


def test_mpremote_default_exec_soft_resets_and_the_board_comes_back(capsys):
    with VirtualBoard(image="source") as vb:
        with texelpad.connect(vb.port) as b:
            assert b.start("virtual", None, realtime=True)["running"]
        first = vb.proc.pid
        # mpremote's default: enter the raw REPL with a soft reset (Ctrl-D)
        r = subprocess.run([MPREMOTE, "connect", vb.port, "exec",
                            "import texel.app as a; print(repr(a.status()['running']))"],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        assert ast.literal_eval(r.stdout.strip()) is False   # state cleared: the display stopped
        assert vb.alive() and vb.resets == 1 and vb.proc.pid != first
        assert _gone(first)
        # same port, the next command works
        code, out, err = run_cli(capsys, "status", "--port", vb.port)
        assert code == 0, err
        assert out.startswith("texelpad is not running")
        # sys.exit() resets too (as on a board); resume keeps the fresh state
        r = subprocess.run([MPREMOTE, "connect", vb.port, "exec", "import sys; sys.exit()"],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        r = mpremote(vb.port, "x = 41\nprint(x + 1)")
        assert r.returncode == 0 and r.stdout.strip() == "42", r.stderr
        assert vb.alive() and vb.resets == 3
        # the friendly REPL: Ctrl-D prints the soft reboot and a fresh prompt
        import serial
        with serial.Serial(vb.port, timeout=0.2) as s:
            s.write(b"\r\x02")
            time.sleep(0.2)
            s.read(4096)
            s.write(b"\x04")
            got, t_end = b"", time.monotonic() + 10
            while time.monotonic() < t_end and not got.endswith(b">>> "):
                got += s.read(256)
        assert b"MPY: soft reboot\r\n" in got and got.endswith(b">>> "), got
        r = mpremote(vb.port, "print('still here')")
        assert r.stdout.strip() == "still here", r.stderr
        last = vb.proc.pid
        tmp = vb.flash
    assert _gone(last) and not tmp.exists()


def test_a_stepped_virtual_board_says_so(capsys):
    with VirtualBoard(image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None)                  # no realtime: stepped time
        code, out, err = run_cli(capsys, "status", "--port", vb.port)
        assert code == 0, err
        assert "WARNING: the virtual board's time is stepped" in out
        code, out, err = run_cli(capsys, "status", "--port", vb.port, "--json")
        assert code == 0 and json.loads(out)["running"] is True
        assert "stepped" in err and err.count("\n") == 1
        code, out, err = run_cli(capsys, "monitor", "--port", vb.port, "--seconds", "0.2")
        assert code == 1 and "no samples would come" in err and err.count("\n") == 1
        # push --board starts a board in real time: it plays
        with texelpad.connect(vb.port) as b:
            b.stop()
        code, out, err = run_cli(capsys, "push", "--port", vb.port, "--board", "virtual",
                                 "--pitch-db", "3", "--irregularity-db", "-9")
        assert code == 0, err
        code, out, err = run_cli(capsys, "status", "--port", vb.port)
        assert code == 0 and "WARNING" not in out, out


def test_texelpad_virtual_sigterm_stops_cleanly_and_ports_lists_it(registry, capsys):
    env = dict(os.environ, TEXELPAD_RUNTIME_DIR=str(registry))
    proc = subprocess.Popen(TEXELPAD + ["virtual", "--source"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        port = proc.stdout.readline().strip()
        assert port.startswith("/dev/pts/"), (port, proc.stderr.read() if proc.poll() else "")
        kids = _children(proc.pid)
        assert kids and all(not _gone(k) for k in kids)
        entries = running_boards()
        assert [(e["port"], e["pid"]) for e in entries] == [(port, proc.pid)]
        flash = Path(entries[0]["flash"])
        assert flash.is_dir() and flash.name.startswith("texelpad-flash-")
        code, out, err = run_cli(capsys, "ports")
        assert code == 0 and port in out and "virtual" in out, out
        # status without --port: the one board there is
        code, out, err = run_cli(capsys, "status")
        assert code == 0 and out.startswith("board virtual"), err
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == 0, proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    for k in kids:
        assert _gone(k), "micropython %d left running" % k
    assert not flash.exists()
    assert running_boards() == [] and not list(registry.glob("virtual/*.json"))
    code, out, err = run_cli(capsys, "ports")
    assert port not in out


def test_stale_registry_entries_are_ignored(registry, capsys, tmp_path):
    d = registry / "virtual"
    d.mkdir(parents=True)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    flash = tmp_path / "texelpad-flash-stale"
    flash.mkdir()
    (d / ("%d.json" % dead.pid)).write_text(json.dumps(
        {"port": "/dev/pts/9999", "pid": dead.pid, "flash": str(flash), "temporary": True}))
    (d / "junk.json").write_text("{not json")
    assert running_boards() == []
    assert not (d / ("%d.json" % dead.pid)).exists() and not flash.exists()
    code, out, err = run_cli(capsys, "ports")
    assert code == 0 and "/dev/pts/9999" not in out


def test_stop_on_signals_cleans_up_a_bench_board(tmp_path):
    """bench-link's board: SIGTERM in the middle unwinds through VirtualBoard.stop."""
    script = tmp_path / "b.py"
    script.write_text(
        "import os, signal, sys\n"
        "from texelpad.sim.virtual import VirtualBoard, stop_on_signals\n"
        "with stop_on_signals(), VirtualBoard(image='source') as vb:\n"
        "    print(vb.proc.pid, vb.flash, flush=True)\n"
        "    signal.pause()\n")
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        pid, flash = proc.stdout.readline().split()
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert _gone(int(pid)) and not Path(flash).exists()
