#!/usr/bin/env python3
"""The screenshots in docs/img/ of texelpad lab: the experimenter's page and
each protocol's participant screen in Chromium (Playwright, Debian's
/usr/bin/chromium) against `texelpad lab` on the virtual board, and each
protocol's summary figure as `texelpad lab export` makes it for sessions the
simulated participant (texelpad.study.participant) answered.

    .venv/bin/python tools/lab_screenshots.py

Writes docs/img/lab-experimenter.png, lab-screen-PROTOCOL.png and
lab-summary-NAME.png.
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
           ("staircase", "staircase"), ("search-4sin", "search"))


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
                    page.check("#confidence-4")
                elif proto in ("pursuit", "staircase", "search"):
                    page.click("#feel-1")
                    page.wait_for_selector("#feel-1.playing")
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


def summaries(data: Path) -> None:
    from texelpad.study import configs, protocols
    from texelpad.study.export import figure
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.references import target_point
    from texelpad.study.session import Session
    runs = (("free-nine", 9), ("quant-exemplars", 12), ("similarity-matrix", 9),
            ("pursuit-4sin", 20), ("staircase", 400), ("search-4sin", 30))
    for name, n in runs:
        c = configs.load(name)
        config = dict(c.get("config", {}))
        if "reference" in c:
            config["reference"] = c["reference"]
        proto = c["protocol"]
        target = target_point(config.get("reference", {}).get("name", "pink"))
        sim = SimulatedParticipant(target, noise=0.02, seed=2, threshold_mm=6.0)
        s = Session.create(data, proto, "sim", dict(config, config_file=name), 5)
        st = protocols.start(proto, config, 5)
        for _ in range(n):
            if st.done:
                break
            if proto == "free":         # the simulated participant aims at each reference
                sim.target = target_point(st.reference)
            a = sim.answer(proto, st)
            protocols.apply(proto, st, a)
            s.append({"answer": a})
        short = name.split("-")[0] if name != "similarity-matrix" else "matrix"
        figure(Session.open(s.path), OUT / ("lab-summary-%s.png" % short))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as td:
        screens(Path(td) / "screen")
        summaries(Path(td) / "sim")
    print("wrote", ", ".join(sorted(p.name for p in OUT.glob("lab-*.png"))))


if __name__ == "__main__":
    main()
