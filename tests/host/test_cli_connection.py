"""The board a command talks to (texelpad.cli.connection): connected_board,
and running_board, the one context manager for "a board that runs texelpad".
Their error paths are the commands' one line, in the same words from every
command: no board (exit 1), texelpad not running on it (exit 1, with the
command's hint), a lost link (exit 1), the board's refusal (exit 2). No
board is needed: texelpad.link.board.connect is replaced by a fake board
that records what it was asked."""
from __future__ import annotations

import argparse

import pytest

import texelpad.link.board
import texelpad.link.transport
import texelpad.sim.virtual
from texelpad.cli.connection import START_HINT, connected_board, running_board
from texelpad.cli.errors import EXIT_FAIL, EXIT_USAGE, CliError
from texelpad.link.transport import DeviceError, LinkTimeout, NoBoard
from support.cli import run_cli

PORT = "/dev/ttyTEXELPAD-fake"
BOOT_HINT = "--board NAME says which board file to start at power-up"


class FakeBoard:
    """What the context managers and the not-running paths use of a Board."""

    port = PORT

    def __init__(self, running: bool):
        self.running = running
        self.calls: list = []
        self.closed = False

    def __enter__(self) -> "FakeBoard":
        return self

    def __exit__(self, *exc) -> None:
        self.closed = True

    def status(self) -> dict:
        self.calls.append("status")
        if not self.running:
            return {"running": False, "mem_free": 100000}
        return {"running": True, "board": "virtual", "display": {"positions": 19200,
                                                                  "dx_um": 5.3}}

    def fitting(self) -> list[str]:
        self.calls.append("fitting")
        return ["pico", "pico_bridge"]

    def start(self, name: str, scene=None, **opts) -> dict:
        self.calls.append(("start", name, opts))
        self.running = True
        return dict(self.status(), board=name)


@pytest.fixture
def fake(monkeypatch):
    """connect() hands out this FakeBoard (stopped unless a test starts it)."""
    board = FakeBoard(running=False)

    def connect(port=None, timeout=10.0, check=True, import_image=True):
        board.calls.append(("connect", port, check, import_image))
        return board
    monkeypatch.setattr(texelpad.link.board, "connect", connect)
    return board


@pytest.fixture
def no_board(monkeypatch):
    """Nothing plugged in, no texelpad virtual running."""
    for mod in (texelpad.link.transport, texelpad.link.board):
        monkeypatch.setattr(mod, "ports", lambda: [])
    monkeypatch.setattr(texelpad.sim.virtual, "running_boards", lambda: [])


def _args(port: str | None = PORT) -> argparse.Namespace:
    return argparse.Namespace(port=port, timeout=10.0)


# --- through the commands: the lines a user sees --------------------------------------

def _connecting_commands(tmp_path) -> list[list[str]]:
    from pathlib import Path
    board_file = Path(__file__).resolve().parents[2] / "boards" / "pico" / "board.json"
    return [["push", "--constant", "0.5"], ["status"], ["stop"], ["monitor", "--seconds", "0.1"],
            ["scene", "pull", str(tmp_path / "s.json")], ["scene", "boot", "--current"],
            ["scene", "boot", "--clear"], ["deploy"], ["board", "install", str(board_file)]]


def test_no_board_is_the_links_words_in_one_line_exit_1_from_every_command(
        capsys, tmp_path, no_board):
    with pytest.raises(NoBoard) as e:
        texelpad.link.board.connect(None)
    for argv in _connecting_commands(tmp_path):
        code, out, err = run_cli(capsys, *argv)
        assert (code, out) == (EXIT_FAIL, ""), (argv, out, err)
        assert err == "texelpad %s: error: %s\n" % (argv[0], e.value), (argv, err)
    assert not (tmp_path / "s.json").exists()


@pytest.mark.parametrize("argv, hint, asked", [
    (["monitor", "--seconds", "0.1"], START_HINT, ["status"]),
    (["scene", "pull", "{tmp}/s.json"], START_HINT, ["status"]),
    (["push", "--pitch-db", "3", "--irregularity-db", "-9"],
     "--board NAME starts it; board files that fit this board: pico, pico_bridge",
     ["status", "fitting"]),
    (["push", "--reference", "4sin"],
     "--board NAME starts it; board files that fit this board: pico, pico_bridge",
     ["status", "fitting"]),
    (["scene", "boot", "gradient"], BOOT_HINT, ["status"]),
    (["scene", "boot", "--current"], BOOT_HINT, ["status"]),
])
def test_not_running_is_one_line_exit_1_with_the_commands_hint(capsys, tmp_path, fake, argv,
                                                               hint, asked):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    code, out, err = run_cli(capsys, *argv, "--port", PORT)
    assert (code, out) == (EXIT_FAIL, "")
    assert err == "texelpad %s: error: texelpad is not running on %s (%s)\n" % (argv[0], PORT,
                                                                               hint)
    assert fake.calls == [("connect", PORT, True, True)] + asked      # nothing else was sent
    assert fake.closed
    assert not (tmp_path / "s.json").exists()


# --- the context managers themselves ------------------------------------------------------

def test_running_board_yields_the_board_and_its_status(fake):
    fake.running = True
    with running_board(_args()) as (b, st):
        assert b is fake and st["running"] and st["board"] == "virtual"
        assert not fake.closed
    assert fake.closed and fake.calls == [("connect", PORT, True, True), "status"]


def test_not_running_raises_before_the_block_and_closes_the_board(fake):
    with pytest.raises(CliError) as e:
        with running_board(_args()):
            pytest.fail("the block ran on a board where texelpad does not run")
    assert (str(e.value), e.value.code) == (
        "texelpad is not running on %s (texelpad push --board NAME starts it)" % PORT, EXIT_FAIL)
    assert fake.closed


def test_hint_may_ask_the_board(fake):
    with pytest.raises(CliError) as e:
        with running_board(_args(), lambda b: "fits: " + ", ".join(b.fitting())):
            pass
    assert str(e.value) == "texelpad is not running on %s (fits: pico, pico_bridge)" % PORT


def test_start_starts_the_board_file_in_real_time(fake):
    with running_board(_args(), start="virtual") as (b, st):
        assert st["running"] and st["board"] == "virtual"
    assert fake.calls[1:] == ["status", ("start", "virtual", {"realtime": True}), "status"]


def test_stopped_ok_takes_the_board_as_it_is(fake):
    with running_board(_args(), stopped_ok=True) as (b, st):
        assert st == {"running": False, "mem_free": 100000}
    assert fake.calls[1:] == ["status"]


def test_a_failure_of_the_link_is_one_line_exit_1(fake):
    fake.running = True
    with pytest.raises(CliError) as e:
        with running_board(_args()):
            raise LinkTimeout("%s stopped answering" % PORT)
    assert (str(e.value), e.value.code) == ("%s stopped answering" % PORT, EXIT_FAIL)
    assert e.value.__suppress_context__ and fake.closed


def test_the_boards_refusal_is_exit_2_or_the_commands_own_words(fake):
    fake.running = True
    with pytest.raises(CliError) as e:
        with running_board(_args()):
            raise DeviceError("ValueError: no")
    assert (str(e.value), e.value.code) == ("the board refused it: ValueError: no", EXIT_USAGE)
    # refused: the command names the flag, for the board's refusal and the host's check alike
    for exc in (DeviceError("ValueError: no"), ValueError("regions[0]: no")):
        with pytest.raises(CliError) as e:
            with running_board(_args(), refused=lambda e: CliError("--scene", str(e))):
                raise exc
        assert str(e.value) == "--scene: %s" % exc
    # without refused a ValueError of the host's is no failure of the link: it goes on as it is
    with pytest.raises(ValueError, match="a bug"):
        with connected_board(_args()):
            raise ValueError("a bug")


def test_connecting_fails_in_one_line_exit_1(monkeypatch, no_board):
    with pytest.raises(CliError) as e:
        with connected_board(_args("/dev/ttyTEXELPAD-none")):
            pytest.fail("connected to no board")
    assert e.value.code == EXIT_FAIL and "/dev/ttyTEXELPAD-none" in str(e.value)
    with pytest.raises(CliError) as e:
        with running_board(_args(None)):
            pass
    assert e.value.code == EXIT_FAIL and str(e.value).startswith("no board found")


def test_one_board_of_several_must_be_named(monkeypatch):
    monkeypatch.setattr(texelpad.link.transport, "ports", lambda: [{"port": "/dev/ttyACM0"}])
    monkeypatch.setattr(texelpad.sim.virtual, "running_boards", lambda: [{"port": "/dev/pts/9"}])
    with pytest.raises(CliError) as e:
        with connected_board(_args(None)):
            pass
    assert (str(e.value), e.value.code) == (
        "--port: 2 boards found (/dev/ttyACM0, /dev/pts/9 (virtual)): say which with --port",
        EXIT_FAIL)
