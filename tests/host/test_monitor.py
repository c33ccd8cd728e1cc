"""`texelpad monitor` tells the truth about its samples: --rate is checked
against the board's refresh rate (exit 2, one line naming the flag), lost
samples are reported (CSV or not), an unwritable --csv fails before the board
is opened (exit 1, one line), and Board.monitor polls the 256-sample ring
fast enough at high rates that every sample is either read or counted lost."""
import pytest

import texelpad
from texelpad.link.board import Board
from texelpad.sim.virtual import VirtualBoard
from support.cli import run_cli

pytestmark = [pytest.mark.vboard]


@pytest.fixture(scope="module")
def port():
    with VirtualBoard(image="source") as vb:
        with texelpad.connect(vb.port) as b:
            b.start("virtual", None, realtime=True)
        yield vb.port




@pytest.mark.parametrize("rate", ["50000", "8334"])
def test_rate_above_the_refresh_rate_is_refused(capsys, port, tmp_path, rate):
    f = tmp_path / "m.csv"
    code, out, err = run_cli(capsys, "monitor", "--port", port, "--rate", rate,
                             "--seconds", "0.2", "--csv", str(f))
    assert code == 2, (out, err)
    assert "--rate: must be 1 .. 8333" in err and err.count("\n") == 1, err
    assert not f.exists()                       # refused: no file left behind


@pytest.mark.parametrize("rate", ["0", "-5", "50001"])
def test_rate_out_of_any_range_refused_before_connecting(capsys, rate):
    code, out, err = run_cli(capsys, "monitor", "--port", "/dev/ttyTEXELPAD-none",
                             "--rate", rate)
    assert code == 2 and "--rate: must be" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("where", ["missing/dir/m.csv", "."])
def test_unwritable_csv_fails_up_front(capsys, tmp_path, where):
    path = tmp_path / where if where != "." else tmp_path
    # the port does not exist: the CSV error comes first, before any board
    code, out, err = run_cli(capsys, "monitor", "--port", "/dev/ttyTEXELPAD-none",
                             "--csv", str(path))
    assert code == 1, (out, err)
    assert err.startswith("texelpad monitor: error: --csv: cannot write ")
    assert err.count("\n") == 1 and "Traceback" not in err


def test_full_rate_samples_are_read_or_counted_lost(port):
    with texelpad.connect(port) as b:
        hz = b.status()["refresh_hz"]
        t = [s[0] for s in b.monitor(0.6, rate_hz=hz)]
        assert b.divider == 1 and b.received == len(t)
        first = b.status()
    assert t == sorted(t) and len(t) > 0
    # every refresh in the span is a sample read or one counted lost (the
    # ring's own accounting); generous: the span is measured on the board
    span = (t[-1] - t[0]) * hz // 1_000_000
    assert len(t) + b.lost >= 0.9 * span, (len(t), b.lost, span)
    assert first["faults"] == 0


def _lossy(monkeypatch, lost=1234):
    real = Board.telemetry
    calls = []

    def telemetry(self):
        samples, n = real(self)
        calls.append(1)
        return samples, n + (lost if len(calls) == 1 else 0)
    monkeypatch.setattr(Board, "telemetry", telemetry)


def test_lost_samples_are_reported_with_csv(capsys, port, tmp_path, monkeypatch):
    _lossy(monkeypatch)
    f = tmp_path / "m.csv"
    code, out, err = run_cli(capsys, "monitor", "--port", port, "--rate", "250",
                             "--seconds", "0.3", "--csv", str(f))
    assert code == 0, err
    rows = f.read_text().splitlines()
    assert rows[0] == "t_us,position,position_mm,amplitude" and len(rows) > 1
    assert "samples written to %s" % f in err
    assert "monitor: warning: 1,2" in err and "samples lost" in err, err


def test_lost_samples_are_reported_on_the_terminal(capsys, port, monkeypatch):
    _lossy(monkeypatch, lost=7)
    code, out, err = run_cli(capsys, "monitor", "--port", port, "--rate", "125",
                             "--seconds", "0.2")
    assert code == 0, err
    assert out.splitlines()[0].split() == ["t_ms", "mm", "amp", "amplitude"]
    assert "monitor: warning: 7 of " in err, err


def test_no_loss_no_warning_and_rate_rounding_said(capsys, port, tmp_path):
    f = tmp_path / "m.csv"
    code, out, err = run_cli(capsys, "monitor", "--port", port, "--rate", "5000",
                             "--seconds", "0.2", "--csv", str(f))
    assert code == 0, err
    # 8333 // 5000 = 1: the board samples every refresh, and says so
    assert "sampled every refresh of 8333 Hz: 8333.0 samples/s, not 5000" in err, err
