"""What the nightly fuzz job found in the layers it may fix, kept fixed
(docs/testing.md lists everything it found). Plain tests, not fuzz targets."""
from __future__ import annotations

import numpy as np

from support.cli import run_cli

RENDER = ["render", "--pitch-db", "6", "--irregularity-db", "-10", "--length-samples", "300"]


def _one_line(err: str) -> str:
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def test_render_npy_with_an_upper_case_suffix_writes_that_file(tmp_path, capsys):
    # np.save(path) appended ".npy" to "M.NPY": "wrote M.NPY" named no file
    out = tmp_path / "M.NPY"
    code, so, err = run_cli(capsys, *RENDER, "--out", str(out))
    assert code == 0, err
    assert "wrote %s" % out in so
    assert sorted(p.name for p in tmp_path.iterdir()) == ["M.NPY"]
    assert np.load(out).shape == (300,)


def test_tank_refuses_a_100000_character_quantity_in_one_line(capsys):
    # the prefix search tried float() on every prefix: 7 s for 100,000 characters
    code, so, err = run_cli(capsys, "tank", "-L", "x" + "1" * 100_000, "-f", "34k")
    assert code == 2 and so == ""
    line = _one_line(err)
    assert "--inductance" in line and "(100,001 characters) is too long" in line
    assert len(line) < 300


# --- the eight found in the link, protocol and command-line layers, fixed -------------------

def _stub_link(answer: str):
    from texelpad.link.transport import Link
    link = Link.__new__(Link)
    link.port, link.timeout, link.sent, link.received = "/dev/ttyFAKE", 10.0, 0, 0
    link.exec = lambda code, timeout=None, reply_first=False: answer
    return link


def test_answers_of_the_wrong_shape_are_link_errors():
    import pytest
    from texelpad.link.board import Board
    from texelpad.link.transport import LinkError, NotTexelpad
    for answer in ("{[]: 1}\r\n", "-" * 100_000 + "1", "('ok',)", "42"):
        with pytest.raises(LinkError, match="unexpected answer"):
            _stub_link(answer).call("texel.app", "status")
    for hello in (42, ((), "micropython", (1, 28, 0), 6, "rp2"),
                  (("x", "0.1"), "micropython", (1, 28, 0), 6, "rp2")):
        with pytest.raises(NotTexelpad, match="handshake"):
            Board(_stub_link(""), hello)
    from texelpad.link.protocol import PROTOCOL
    hello = ((PROTOCOL, "0.1.0"), "micropython", (1, 28, 0), 6, "rp2")
    for status in ("5.0", "{'running': True}", "None",
                   "{'running': True, 'display': {'positions': -1, 'dx_um': 5.3}}"):
        b = Board(_stub_link("('ok', %s)" % status), hello)
        with pytest.raises(LinkError, match="unexpected answer .* status"):
            b.status()
    for tel in ("7", "([], None)", "([(1, 2)], 0)"):
        b = Board(_stub_link("('ok', %s)" % tel), hello)
        with pytest.raises(LinkError, match="unexpected answer .* telemetry"):
            b.telemetry()
    b = Board(_stub_link("('ok', {})"), hello)
    with pytest.raises(LinkError, match="unexpected answer .* scene_source"):
        b.scene_source()


def test_a_board_traceback_is_one_line_with_the_whole_text_kept():
    from texelpad.link.transport import BoardError
    e = BoardError("Traceback (most recent call last):\r\n  File \"<stdin>\", line 1\r\n"
                   "MemoryError: memory allocation failed\r\n")
    assert str(e) == "the board raised an error: MemoryError: memory allocation failed"
    assert "line 1" in e.traceback


def test_literal_paths_quote_and_cut_odd_keys():
    import pytest
    from texelpad.link.protocol import LiteralError, literal
    with pytest.raises(LiteralError) as e:
        literal({"regions": [], "a\nb": float("nan")})
    assert str(e.value) == "value['a\\nb']: nan is not finite"
    with pytest.raises(LiteralError) as e:
        literal({"k" * 100_000: float("inf")})
    assert len(str(e.value)) < 120 and "(100000 chars)" in str(e.value)


def test_a_usage_error_echoing_a_line_break_stays_one_line(capsys):
    code, so, err = run_cli(capsys, *RENDER, "a\nb")
    assert code == 2
    assert _one_line(err).endswith("unrecognized arguments: a\\nb (see: texelpad --help)")
