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
