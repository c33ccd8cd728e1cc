#!/usr/bin/env python3
"""The screenshots in docs/img/ of texelpad lab: the experimenter's page and
each protocol's participant screen in Chromium (Playwright, Debian's
/usr/bin/chromium) against `texelpad lab` on the virtual board, and each
protocol's summary figure as `texelpad lab export` makes it for sessions the
simulated participant (texelpad.study.participant) answered.

    .venv/bin/python tools/lab_screenshots.py

Writes docs/img/lab-experimenter.png, lab-screen-PROTOCOL.png,
lab-summary-NAME.png and the papers' study figures (texelpad.study.export
study_figures) over simulated participants as lab-paper-NAME.png.
"""
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "img"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
SCREENS = (("free-nine", "free"), ("quant-exemplars", "quant"), ("pursuit-4sin", "pursuit"),
           ("staircase", "staircase"), ("search-4sin", "search"), ("mapping", "mapping"))


def screens(data: Path) -> None:
    from playwright.sync_api import sync_playwright
    p = subprocess.Popen([sys.executable, "-m", "texelpad", "lab", "--data", str(data)],
                         stdout=subprocess.PIPE, text=True)
    try:
        url = p.stdout.readline().strip()
        for _ in range(150):
            try:
                urllib.request.urlopen(url + "api/status", timeout=5).read()
                break
            except OSError:
                time.sleep(0.2)
        with sync_playwright() as pw:
            b = pw.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS,
                                   chromium_sandbox=False)
            exp = b.new_page(viewport={"width": 1000, "height": 900})
            exp.goto(url)
            exp.wait_for_function("document.getElementById('config').options.length > 3")
            for config, proto in SCREENS:
                exp.select_option("#config", config)
                exp.fill("#participant", "p01")
                exp.fill("#seed", "5")
                exp.click("#start")
                exp.wait_for_selector("#participant-link[href*='%s-']" % proto)
                sid = exp.get_attribute("#participant-link", "href").split("s=")[1]
                exp.wait_for_selector("#detail")
                page = b.new_page(viewport={"width": 900, "height": 640})
                page.goto(url + "participant?s=" + sid)
                page.wait_for_selector("#question:not([hidden])")
                if proto == "free":
                    page.fill("#pitch", "620")
                    page.fill("#irregularity", "380")
                    page.fill("#confidence-slider", "4")
                elif proto == "mapping":
                    page.fill("#pitch", "450")
                    page.fill("#irregularity", "200")
                elif proto in ("pursuit", "staircase", "search"):
                    page.click("#feel-2")
                    page.wait_for_selector("#feel-2.playing")
                page.wait_for_timeout(600)
                page.screenshot(path=str(OUT / ("lab-screen-%s.png" % proto)))
                if proto == "pursuit":
                    exp.wait_for_timeout(1200)      # the monitor's next poll
                    exp.screenshot(path=str(OUT / "lab-experimenter.png"), full_page=True)
                page.close()
            b.close()
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(timeout=30)


def _run(data: Path, name: str, participant: str, seed: int, n: int, sim, config=None):
    """A session of config `name` answered by the simulated participant."""
    from texelpad.study import configs, finger, protocols
    from texelpad.study.describe import TPAD_DISPLAY
    from texelpad.study.references import target_point
    from texelpad.study.session import Session
    c = configs.load(name)
    config = dict(c.get("config", {}), **(config or {}))
    if "reference" in c:
        config["reference"] = c["reference"]
    proto = c["protocol"]
    s = Session.create(data, proto, participant, dict(config, config_file=name), seed)
    st = protocols.start(proto, config, seed)
    for k in range(n):
        if st.done:
            break
        if proto == "free":             # the simulated participant aims at each reference
            sim.target = target_point(st.reference)
        hz = protocols.get(proto).finger_hz(st)
        if hz:                          # the finger, as the lab records it (study/finger.py)
            s.append(finger.record(k, k, 0, sim.finger(4.0, hz, TPAD_DISPLAY), 0, hz,
                                   TPAD_DISPLAY["dx_um"]))
        a = sim.answer(proto, st)
        protocols.apply(proto, st, a)
        scene = {"regions": [{"start_mm": 0, "end_mm": 1, "texture": dict(
            st.texture(a["pitch_db"], a["irregularity_db"], 0), kind="texel")}]} \
            if proto == "free" else None
        s.append({"answer": a, "scene": scene} if scene else {"answer": a})
    if proto == "search" and not st.done:      # (satisfied: a search ends when told)
        protocols.apply(proto, st, {"stop": True})
        s.append({"answer": {"stop": True}})
    return Session.open(s.path), st


def summaries(data: Path) -> None:
    from texelpad.study import matches
    from texelpad.study.export import figure
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.references import target_point
    runs = (("free-nine", 9), ("quant-paper", 27), ("similarity-matrix", 9),
            ("pursuit-4sin", 20), ("staircase", 400), ("search-4sin", 30), ("mapping", 34))
    own = None
    for name, n in runs:
        sim = SimulatedParticipant(target_point("4sin" if "4sin" in name else "pink"),
                                   noise=0.02, seed=2, threshold_mm=6.0)
        extra = {"matches": own} if name == "quant-paper" else None
        s, st = _run(data, name, "sim", 5, n, sim, extra)
        if name == "free-nine":
            own = matches.from_free(s, st)
        short = {"similarity-matrix": "matrix", "quant-paper": "quant"}.get(
            name, name.split("-")[0])
        figure(s, OUT / ("lab-summary-%s.png" % short))


def paper_figures(data: Path) -> None:
    """The papers' figures over eight simulated participants (noise and
    staircase thresholds differ per participant): what `texelpad lab export`
    draws for a study's data folder."""
    from texelpad.study import matches
    from texelpad.study.export import export
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.references import target_point
    for k in range(8):
        who = "sim%02d" % k
        sim = SimulatedParticipant(target_point("pink"), noise=0.01 + 0.005 * k, seed=k,
                                   threshold_mm=3.0 + k, swipe_mm_s=60.0 + 10.0 * k,
                                   one_way=k % 3 == 0)
        s, st = _run(data, "free-nine", who, k, 9, sim)
        _run(data, "quant-paper", who, k, 27, sim, {"matches": matches.from_free(s, st)})
        for e in ("4sin", "pink", "sawtooth"):      # the guided explorations, then the matrix
            sim.target = target_point(e)
            _run(data, "pursuit-%s" % e, who, k, 20, sim)
        _run(data, "similarity-matrix", who, k, 9, sim)
        sim.target = target_point("4sin")
        _run(data, "search-4sin", who, k, 4 + k % 4, sim)
        _run(data, "staircase" if k % 2 else "staircase-wide", who, k, 400, sim)
        _run(data, "mapping", who, k, 34, sim)
    with tempfile.TemporaryDirectory() as td:
        made = export(data, td)["study_figures"]
        for path in sorted(Path(td).glob("seed*.png")):
            shutil.copy(path, OUT / ("lab-paper-%s" % path.name))
    print("paper figures:", ", ".join(sorted(made)))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as td:
        screens(Path(td) / "screen")
        summaries(Path(td) / "sim")
        paper_figures(Path(td) / "paper")
    print("wrote", ", ".join(sorted(p.name for p in OUT.glob("lab-*.png"))))


if __name__ == "__main__":
    main()
