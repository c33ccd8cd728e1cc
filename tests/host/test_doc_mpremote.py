"""Every mpremote example in the docs runs as printed (issue 30), on the emulated Pico: stock
MicroPython v1.28 after `texelpad deploy`, playing - a teacher's or maker's board. The
examples are collected from the Markdown (code blocks and inline code), so a new one is run
too; the only change is `connect PORT` after `mpremote` (mpremote's own auto-connect finds
the first USB board, which the emulator is not). Each is the plain form (a soft reset before
and after, which stops a playing display: docs/runtime.md "Soft reset"); afterwards the
board still answers and `texelpad push --board pico` plays again."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from support.cli import run_cli
from support.pico import emulated_pico

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

ROOT = Path(__file__).resolve().parents[2]
DOCS = ["README.md", "hardware/README.md", *sorted(
    str(p.relative_to(ROOT)) for p in [*ROOT.glob("docs/*.md"), *ROOT.glob("boards/*/README.md")])]
# inline mentions that are not commands to type: a placeholder, prose naming a subcommand
NOT_COMMANDS = {"mpremote connect <pty> resume exec \"...\"", "mpremote romfs deploy",
                "mpremote exec", "mpremote mip install"}


def doc_examples() -> list[tuple[str, str]]:
    """(doc, command) of every mpremote command in the docs, in order, each once."""
    out = []
    for doc in DOCS:
        text = (ROOT / doc).read_text()
        for m in re.finditer(r"```[a-z]*\n(.*?)```", text, re.S):
            block = m.group(1)
            # a command may go on over lines inside its quotes: split as a shell would
            lines, cur = [], ""
            for ln in block.splitlines():
                cur = (cur + "\n" + ln.strip()) if cur else ln.strip()
                try:
                    shlex.split(cur)
                except ValueError:          # an open quote: the command goes on
                    continue
                lines.append(cur)
                cur = ""
            out += [(doc, c) for c in lines if c.startswith("mpremote ")]
        for m in re.finditer(r"`(mpremote [^`]+)`", text):
            c = " ".join(m.group(1).split())
            if c not in NOT_COMMANDS:
                out.append((doc, c))
    seen: set[str] = set()                  # one command in two docs runs once
    return [(d, c) for d, c in out if not (c in seen or seen.add(c))]


def test_the_docs_examples_are_the_ones_this_test_runs():
    """The list below changes only with the docs: a new example is run by the next test."""
    assert [(d, c.split("\n")[0][:60]) for d, c in doc_examples()] == [
        ("hardware/README.md", 'mpremote exec "from machine import ADC; import time; a = ADC'),
        ("hardware/README.md", "mpremote cp hardware/sweep.py :sweep.py"),
        ("hardware/README.md", 'mpremote exec "import sweep; sweep.run(\'pico\', pickup_pin=27'),
        ("docs/device-api.md", 'mpremote exec "import texel.app as a; print(a.start(None, a.'),
        ("docs/firmware.md", "mpremote fs cp -r : backup/"),
        ("docs/host.md", "mpremote mip install ./package.json"),
    ]


def test_every_mpremote_example_in_the_docs_runs_as_printed(tmp_path, capsys):
    mp = str(Path(sys.executable).with_name("mpremote"))
    # the examples' working directory: a checkout's (hardware/, package.json and device/
    # reached from it) in which backup/ lands in a temporary folder
    for name in ("hardware", "device", "package.json"):
        (tmp_path / name).symlink_to(ROOT / name)
    with emulated_pico() as emu:
        code, out, err = run_cli(capsys, "deploy", "--port", emu.port)
        assert code == 0, err
        code, out, err = run_cli(capsys, "push", "--port", emu.port, "--board", "pico",
                                 "--constant", "0.3")
        assert code == 0, err
        # mip's source package goes over the image: on a Pico the compiled source leaves
        # too little heap to start (docs/host.md), so that example runs last
        for doc, command in sorted(doc_examples(), key=lambda dc: "mip install" in dc[1]):
            args = shlex.split(command)
            p = subprocess.run([mp, "connect", emu.port, *args[1:]], cwd=tmp_path,
                               capture_output=True, text=True, timeout=600)
            with capsys.disabled():
                print("\n%s: %s -> exit %d, %d lines" % (doc, command.split("\n")[0][:70],
                                                        p.returncode, len(p.stdout.splitlines())))
            assert p.returncode == 0 and "Traceback" not in p.stdout + p.stderr, \
                (doc, command, p.stdout[-800:], p.stderr[-800:])
            assert emu.alive() and "EMULATOR ERROR" not in emu.stderr(), emu.stderr()[-500:]
            if "sweep.run(" in command:
                assert re.search(r"peak .*\d+ Hz", p.stdout, re.I) or "freq_hz" in p.stdout \
                    or re.search(r"^\d+ \d+", p.stdout, re.M), p.stdout[-800:]
            if "ADC(26)" in command:
                vals = [int(x) for x in p.stdout.split() if x.isdigit()]
                assert len(vals) == 100 and all(0 <= v <= 65535 for v in vals), p.stdout[-300:]
        assert (tmp_path / "backup" / "lib" / "texel").is_dir()
        assert (tmp_path / "backup" / "sweep.py").read_bytes() == \
            (ROOT / "hardware" / "sweep.py").read_bytes()
        # the board after all of them: it answers; `texelpad deploy` takes back what mip's
        # source package put over the image (on a Pico the compiled source leaves too little
        # heap to start: docs/host.md), and it plays again
        code, out, err = run_cli(capsys, "deploy", "--port", emu.port)
        assert code == 0, err
        code, out, err = run_cli(capsys, "push", "--port", emu.port, "--board", "pico",
                                 "--constant", "0.3")
        assert code == 0 and "constant 0.3000" in out, err
        assert os.path.isdir(tmp_path / "backup")
