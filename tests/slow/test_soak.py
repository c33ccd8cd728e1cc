"""Soak: 1,000 pushes to the virtual board on a pty (the device image under
the MicroPython unix port, playing in real time). Every push must be
acknowledged with the scene that was sent, nothing may fault, and the
board's free memory (read after each push's gc.collect) must not trend down:
a leak of even 8 bytes per push would show as a slope of -8 and as 8 KB
lost between the first and last hundred pushes. No timing is asserted."""
import pytest
from texelpad.bench import link as link_bench

pytestmark = [pytest.mark.slow, pytest.mark.vboard]


def test_slope_per_push_sees_a_leak():
    assert link_bench.slope_per_push([1000 - 8 * i for i in range(100)]) == -8
    assert link_bench.slope_per_push([5, 5, 5]) == 0


def test_thousand_pushes_all_acknowledged_memory_flat():
    r = link_bench.run(pushes=1000, deploy=False)
    assert r["acked"] == 1000
    assert r["faults"] == 0
    assert r["mem_free_slope_per_push"] > -2.0, r
    assert r["mem_free_last"] >= r["mem_free_first"] - 2048, r
    # a texture crosses as a few hundred bytes, not the lab's 76,800
    assert r["bytes_sent_per_push"] < 1000
