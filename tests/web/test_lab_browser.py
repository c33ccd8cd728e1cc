"""texelpad lab in a real browser: Playwright (PyPI) driving Debian's Chromium
(/usr/bin/chromium; .ci/run installs it) against `texelpad lab` on the
virtual board. A whole pursuit session is clicked through; the session file
holds every answer and the board plays the scene of the last one felt.
Skipped where Chromium or Playwright is missing."""
from __future__ import annotations

import json
import os
import shutil
import urllib.request
from pathlib import Path

import pytest

from texelpad.study.session import Session

from support.lab import lab_process

pytestmark = [pytest.mark.vboard, pytest.mark.slow]
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture
def lab_url(tmp_path):
    with lab_process(tmp_path) as (url, _):
        yield url, tmp_path


def test_a_pursuit_session_clicked_through_in_chromium(lab_url, tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    url, data = lab_url
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS,
                                     chromium_sandbox=False)
        page = browser.new_page()
        page.goto(url)
        page.wait_for_function("document.getElementById('status').textContent.includes('board')")
        page.select_option("#protocol", "pursuit")
        page.fill("#participant", "web01")
        page.click("#start")
        page.wait_for_selector("#feel-1")
        assert "pitch" not in page.inner_text("#question")          # blind
        for i in range(20):
            page.click("#feel-1")
            page.wait_for_function("document.getElementById('feel-1').style.fontWeight"
                                   " === 'bold'")
            page.click("#answer-%d" % (i % 3))                     # A, B, unsure in turn
            page.wait_for_function("document.getElementById('progress').textContent"
                                   ".includes('%s')" % ("finished" if i == 19 else
                                                        ": %d answers" % (i + 1)))
        page.screenshot(path=str(tmp_path / "pursuit-done.png"))
        playing = json.loads(urllib.request.urlopen(url + "api/scene").read())["scene"]
        browser.close()
    (path,) = list(Path(data).glob("web01/pursuit-*.jsonl"))
    s = Session.open(path)
    assert [r["answer"] for r in s.records] == [["A", "B", "unsure"][i % 3] for i in range(20)]
    assert all(r["playing"] == 1 for r in s.records)
    assert playing == s.records[-1]["scene"]
