"""The firmware benchmark (bench.firmware) in its quick mode on the
emulated Pico: every goal of issue 19 has its key in the JSON and no push was
refused. No timing is asserted (the figures are printed: pytest -s)."""
from __future__ import annotations

import json

import pytest

from bench import firmware as bench
from texelpad.sim.emulated import why_not

pytestmark = [pytest.mark.instruments, pytest.mark.slow]


@pytest.fixture(scope="module")
def uf2():
    """The firmware the other firmware tests boot (support.firmware: one build per session),
    or $TEXELPAD_FIRMWARE_UF2."""
    why = why_not()
    if why:
        pytest.skip(why)
    import os
    if os.environ.get("TEXELPAD_FIRMWARE_UF2"):
        return os.environ["TEXELPAD_FIRMWARE_UF2"]
    from support.firmware import built
    return str(built("pico").uf2)


def test_the_quick_benchmark_reports_every_goal_and_refuses_nothing(uf2, tmp_path):
    out_json = tmp_path / "fw.json"
    assert bench.main(["--uf2", uf2, "--quick", "--json", str(out_json)]) == 0
    out = json.loads(out_json.read_text())
    fig = out["firmware"]["figures"]
    for key in bench.GOALS:
        assert key in fig, key
    for key in ("mem_free_slope_per_push", "heap_free_bare_bytes",
                "heap_free_playing_default_bytes", "first_push_to_playing_ms"):
        assert key in fig, key
    assert out["firmware_bytes"] > 0 and out["romfs_bytes"] > 0
    assert fig["pushes"] == bench.QUICK_PUSHES
    assert fig["refused"] == 0, fig["refusals"]
    assert all("refused" not in r for r in out["firmware"]["rows"])
