"""Benchmark for texelpad lab: slider change -> the new scene playing on the
virtual board, through the lab's own board owner (texelpad.web.owner: the
host-side check, the push, the board's validation, build and swap, its status
back). Each step is what a pitch or irregularity slider of the free
exploration sends (study/questions.slider_scene): the reference on the left
half, the texel rendering (format 2, 50-sample texels, a fresh seed per change)
on the right.

    .venv/bin/python -m bench.lab [--steps N] [--json PATH]

A third path, "mapping": seed 001's texel parameter mapping
(study/mapping.py) through the owner - its slider scenes carry the band-pass
reference as 9,600 uploaded samples (the left half) and seed 001's texel
options (1 mm texels, min_cpmm, phase reset) on the right, so every change
uploads the reference again.

A fourth, "strip": what every page's strip asks of the board (the scene
playing, BoardOwner.scene_source) after each mapping push and again while
it plays on - read over the link once, then remembered.

Two paths, both measured: "owner" pushes through the lab's BoardOwner in
this process (the board's part); "http" is what a participant's slider does -
`texelpad lab` started as a process, a free exploration session from the
shipped config, and POST /api/sessions/P/NAME/feel {pitch_db,
irregularity_db} over HTTP, timed from the request to the reply, which comes
once the board plays the new scene (the session file has the move by then:
fsynced). Prints median, p95 and max in ms and writes the figures as JSON.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

from texelpad.sim.virtual import open_virtual, stop_on_signals
from texelpad.study.free import Free
from texelpad.study.mapping import Mapping
from texelpad.study.questions import slider_scene
from texelpad.web.owner import BoardOwner


def _through_owner(steps: int, step, path: str) -> dict:
    """Push `steps` slider scenes through the lab's owner on a fresh virtual
    board: step(k, display) -> (scene, the reference it compares against)."""
    with stop_on_signals():
        vb = open_virtual(source=True)
        try:
            owner = BoardOwner(vb.port, "virtual", realtime=True)
            display = owner.display()
            times, refs = [], []
            for k in range(steps):
                scene, ref = step(k, display)
                refs.append(ref)
                t0 = time.perf_counter()
                owner.push(scene)
                times.append((time.perf_counter() - t0) * 1e3)
            last = owner.status()
            owner.close()
        finally:
            vb.stop()
    return dict(_figures(times, refs), overruns=last["overruns"],
                refreshes=last["refreshes"], board="virtual (MicroPython unix port, real time)",
                path=path)


def run(steps: int = 200) -> dict:
    free = Free(1)                  # the free exploration: its nine trials in turn
    per = max(1, steps // len(free.order))

    def step(k: int, display: dict) -> tuple[dict, str]:
        free.trial = min(k // per, len(free.order) - 1)
        # the same slider sweep as run_http: pitch back and forth, irregularity up
        pitch = round(-10 + 30 * abs((k % 40) - 20) / 20, 3)
        irr = round(-30 + 30 * (k % 97) / 97, 3)
        return slider_scene(free, {}, display, pitch, irr, k)[0], free.reference
    return _through_owner(steps, step, "BoardOwner.push in this process")


def run_mapping(steps: int = 200) -> dict:
    """Seed 001's mapping: slider changes through the owner (module docstring)."""
    st = Mapping(1)

    def step(k: int, display: dict) -> tuple[dict, str]:
        pitch = float(abs((k % 40) - 20) * 5)       # 0 .. 100 and back
        irr = float(k % 101)
        return slider_scene(st, {}, display, pitch, irr, k)[0], st.reference
    return _through_owner(steps, step, "BoardOwner.push in this process, seed 001's mapping")


def run_strip(steps: int = 200) -> dict:
    """What every page's strip asks (GET /api/strip: BoardOwner.scene_source)
    of seed 001's mapping scenes - 9,600 samples read back over the link:
    once after each push (read from the board) and again while the scene
    plays on (remembered: the experimenter's page asks every second)."""
    st = Mapping(1)
    first: list[float] = []
    again: list[float] = []
    with stop_on_signals():
        vb = open_virtual(source=True)
        try:
            owner = BoardOwner(vb.port, "virtual", realtime=True)
            display = owner.display()
            for k in range(max(1, steps // 10)):
                owner.push(slider_scene(st, {}, display, float(k % 101), 50.0, k)[0])
                for times in (first, again, again, again):
                    t0 = time.perf_counter()
                    owner.scene_source()
                    times.append((time.perf_counter() - t0) * 1e3)
            reads, last = owner.source_reads, owner.status()
            owner.close()
        finally:
            vb.stop()
    return {"after_a_push": _figures(first, [st.reference] * len(first)),
            "unchanged": _figures(again, [st.reference] * len(again)),
            "board_reads": reads, "overruns": last["overruns"], "refreshes": last["refreshes"],
            "board": "virtual (MicroPython unix port, real time)",
            "path": "BoardOwner.scene_source in this process, seed 001's mapping scenes"}


def _figures(times: list[float], refs: list[str]) -> dict:
    s = sorted(times)
    by: dict[str, list[float]] = {}
    for t, r in zip(times, refs):
        by.setdefault(r, []).append(t)
    return {"steps": len(times), "median_ms": statistics.median(times),
            "p95_ms": s[min(len(s) - 1, int(0.95 * (len(s) - 1) + 0.5))], "max_ms": s[-1],
            "median_ms_by_reference": {r: statistics.median(v) for r, v in by.items()}}


def run_http(steps: int = 200) -> dict:
    import subprocess
    import sys
    import tempfile
    import urllib.request

    def call(url: str, body: dict | None = None) -> dict:
        req = urllib.request.Request(url, data=None if body is None else json.dumps(body).encode(),
                                     headers={"content-type": "application/json"},
                                     method="GET" if body is None else "POST")
        with urllib.request.urlopen(req, timeout=30) as r:
            return json.loads(r.read())

    with tempfile.TemporaryDirectory() as data:
        p = subprocess.Popen([sys.executable, "-m", "texelpad", "lab", "--data", data],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        assert p.stdout is not None                 # stdout=PIPE
        try:
            url = p.stdout.readline().strip()
            for _ in range(300):
                try:
                    call(url + "api/status")
                    break
                except OSError:
                    time.sleep(0.1)
            sid = call(url + "api/sessions", {"config": "free-nine", "participant": "bench",
                                              "seed": 1})["id"]
            times, refs = [], []
            pitch, irr = 5.0, -3.01              # where the sliders start (the lab's app)
            per = max(1, steps // 9)
            for k in range(steps):
                if k and k % per == 0 and k // per < 9:      # the next trial: submit a match
                    call(url + "api/sessions/%s/answer" % sid,
                         {"answer": {"pitch_db": pitch, "irregularity_db": irr,
                                     "confidence": 3}, "question": k // per - 1})
                refs.append(call(url + "api/sessions/%s/monitor" % sid)["detail"]["reference"])
                pitch = round(-10 + 30 * abs((k % 40) - 20) / 20, 3)
                irr = round(-30 + 30 * (k % 97) / 97, 3)
                t0 = time.perf_counter()
                call(url + "api/sessions/%s/feel" % sid, {"pitch_db": pitch,
                                                          "irregularity_db": irr})
                times.append((time.perf_counter() - t0) * 1e3)
            last = call(url + "api/scene")["scene"]["regions"][1]["texture"]
            assert last["pitch_db"] == min(pitch, 19.747) and last["irregularity_db"] == irr
            st = call(url + "api/status")
        finally:
            p.terminate()
            p.wait(timeout=30)
    return dict(_figures(times, refs), overruns=st["overruns"], refreshes=st["refreshes"],
                board="virtual (MicroPython unix port, real time)",
                path="HTTP POST .../feel to `texelpad lab` (uvicorn), reply once playing")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.lab", description=__doc__)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--json", metavar="PATH")
    a = p.parse_args(argv)
    out = {}
    for name, fn in (("owner", run), ("http", run_http), ("mapping", run_mapping)):
        res = out[name] = fn(a.steps)
        print("slider change -> new scene playing on the %s, %s: median %.1f ms, p95 %.1f ms, "
              "max %.1f ms over %d changes; %d overruns in %d refreshes"
              % (res["board"], {"owner": "through the lab's owner", "http": "over HTTP from a "
                                 "page", "mapping": "seed 001's mapping through the owner (the "
                                 "reference uploaded as samples)"}[name], res["median_ms"], res["p95_ms"], res["max_ms"],
                 res["steps"], res["overruns"], res["refreshes"]), flush=True)
        print("  median by reference (ms): " + ", ".join(
            "%s %.1f" % kv for kv in res["median_ms_by_reference"].items()), flush=True)
    res = out["strip"] = run_strip(a.steps)
    for k, what in (("after_a_push", "read from the board after a push"),
                    ("unchanged", "the same scene asked again (remembered)")):
        f = res[k]
        print("the scene playing, as every strip asks it (seed 001's mapping, 9,600 samples), "
              "%s: median %.1f ms, p95 %.1f ms, max %.1f ms over %d asks"
              % (what, f["median_ms"], f["p95_ms"], f["max_ms"], f["steps"]), flush=True)
    print("  %d reads reached the board for %d asks"
          % (res["board_reads"], res["after_a_push"]["steps"] + res["unchanged"]["steps"]),
          flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
