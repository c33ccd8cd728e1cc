#!/usr/bin/env python3
"""The screenshots in docs/img/ of texelpad lab: the pursuit screen in Chromium
(Playwright, Debian's /usr/bin/chromium) against `texelpad lab` on the virtual
board, and the summary figures `texelpad lab export` makes for sessions the
simulated participant (texelpad.study.participant) answered.

    .venv/bin/python tools/lab_screenshots.py
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


def screen(data: Path) -> None:
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
            page = b.new_page(viewport={"width": 900, "height": 420})
            page.goto(url)
            page.wait_for_function("document.getElementById('status').textContent"
                                   ".includes('board')")
            page.fill("#participant", "p01")
            page.click("#start")
            page.wait_for_selector("#feel-1")
            page.click("#feel-1")
            page.screenshot(path=str(OUT / "lab-pursuit.png"))
            b.close()
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(timeout=30)


def summaries(data: Path) -> None:
    from texelpad.study import protocols
    from texelpad.study.export import export
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.session import Session
    from texelpad.study.space import Point
    sim = SimulatedParticipant(Point(0.3, 0.7), noise=0.01, seed=2, threshold_mm=6.0)
    for proto, n in (("pursuit", 20), ("staircase", 400), ("search", 20)):
        s = Session.create(data, proto, "sim", {}, 5)
        st = protocols.start(proto, {}, 5)
        for _ in range(n):
            if proto == "staircase" and st.done:
                break
            a = sim.answer(proto, st)
            protocols.apply(proto, st, a)
            s.append({"answer": a})
    res = export(data, data / "export")
    for f in res["figures"]:
        shutil.copy(f, OUT / ("lab-summary-" + f.name.split("-")[1] + ".png"))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as td:
        screen(Path(td) / "screen")
        summaries(Path(td) / "sim")
    print("wrote", ", ".join(sorted(p.name for p in OUT.glob("lab-*.png"))))


if __name__ == "__main__":
    main()
