"""See and hear without hardware (issue 11, point 5): texelpad.web.strip and
static/strip.js against a real virtual board (the device image under the
MicroPython unix port, on a pty).

- GET /api/strip is what the board plays: the finger is put at positions in
  every kind of region (and lifted), and the board's own telemetry (t_us,
  position, uint16 amplitude from its refresh) is compared with the strip at
  the position the board sensed. The strip is 8-bit: it pins the amplitude
  to the bin [257*a8 - 128, 257*a8 + 128] of 65535 (a8 = round(a*255/65535)
  = (a + 128) // 257), so the board's duty must lie in [law.duty(bin start),
  law.duty(bin end)] (texel.runtime.duty.DutyLaw, nondecreasing): no fudge
  factor. That interval is 1-2 PWM counts at small amplitudes and widens
  where asin steepens near a = 1 (the test prints its widest). Before the
  8-bit rounding the host's rendering equals the board's amplitude exactly.
- POST /api/finger moves the finger; a bad body is 400 and changes nothing;
  a real board (a stand-in whose board file is not the virtual port) refuses
  with "its own finger sensor" and is never asked to move a finger.
- In Chromium (slow): a drag on the strip page moves the board's finger
  (throttled to ~30 requests a second, the last one a lift), and
  strip.synth over a full-screen texel texture of known pitch swiped at a
  known speed peaks at f*v Hz.
"""
from __future__ import annotations

import base64
import json
import os
import shutil
import statistics
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from starlette.testclient import TestClient

import texel.runtime.scene as S
from texel.runtime.boards import load as load_board
from texel.runtime.duty import DutyLaw
from texelpad.link.board import full_screen_texel
from texelpad.web import strip as strip_mod
from texelpad.web.owner import BoardOwner
from texelpad.web.server import Lab, make_app

from support.lab import lab_process

BASE = "http://127.0.0.1"
DISPLAY = {"positions": 19200, "dx_um": 5.3}
# every region kind, a gap (idle_amplitude plays there) and uneven boundaries
SCENE = {"regions": [
    {"start_mm": 0, "end_mm": 25.0, "texture": {"kind": "reference", "name": "4sin"}},
    {"start_mm": 25.0, "end_mm": 50.0, "texture": {"kind": "texel", "pitch_db": 3.0,
                                                   "irregularity_db": -10.0, "seed": 5, "v": 2}},
    {"start_mm": 50.0, "end_mm": 60.0, "texture": {"kind": "constant", "level": 0.97}},
    {"start_mm": 70.0, "end_mm": 101.76, "texture": {"kind": "samples", "fit": "stretch",
                                                     "values": [0.0, 1.0, 0.2, 0.8]}}],
    "idle_amplitude": 3000}
# where the finger is put: in each region, in the gap, near the ends (mm)
FINGER_MM = [1.0, 12.34, 24.99, 30.0, 37.5, 49.0, 55.0, 65.0, 75.0, 88.8, 101.7]


def _u8(answer: dict[str, Any]) -> np.ndarray:
    return np.frombuffer(base64.b64decode(answer["amplitude"]), dtype=np.uint8)


def _law() -> DutyLaw:
    """The virtual board's duty law: its board file (boards.d/virtual.json) and
    the PWM top its backend computes (texel.hw.virtual: round(cpu/freq) - 1)."""
    b = load_board("virtual")
    top = (b["cpu_hz"] + b["carrier"]["freq_hz"] // 2) // b["carrier"]["freq_hz"] - 1
    return DutyLaw(top, b["carrier"]["duty_cap"])


# --- a real virtual board ------------------------------------------------------------
# port and lab: tests/web/conftest.py


@pytest.mark.vboard
def test_the_strip_is_what_the_board_plays(lab):
    owner = lab.lab.owner
    st, canonical = owner.push(SCENE)
    assert st["pwm_top"] == _law().top
    r = lab.get("/api/strip")
    assert r.status_code == 200, r.text
    a = r.json()
    assert (a["positions"], a["dx_um"], a["length_mm"]) == (19200, 5.3, 101.76)
    assert a["virtual"] is True and a["idle"] == 3000
    u8 = _u8(a)
    assert u8.shape == (19200,)
    # boundaries where the board plays them: rounded to positions (25 mm is
    # position 4,717, 25.0001 mm)
    assert [(g["start_mm"], g["end_mm"]) for g in a["regions"]] == \
        [(on_grid(r["start_mm"]), on_grid(r["end_mm"])) for r in SCENE["regions"]]
    assert [g["label"] for g in a["regions"]][0] == "reference 4sin"    # kinds.label_of
    # the host's uint16 rendering (the board's own build and amp) before 8 bits
    u16, _ = strip_mod.render(canonical, DISPLAY, 3000)
    assert np.array_equal(strip_mod.to_u8(u16), u8)
    assert u8[to_pos(65.0)] == round(3000 / 257)                   # the gap plays idle

    law = _law()
    widest = 0
    checked = 0
    for mm in FINGER_MM + [None]:
        r = lab.post("/api/finger", json={"position_mm": mm})
        assert r.status_code == 200 and r.json()["position_mm"] == mm, r.text
        time.sleep(0.03)                     # the sensor's filter settles in ~2 ms
        samples = owner.telemetry(0.15, rate_hz=250)
        assert len(samples) >= 10
        if mm is None:                       # lifted: the scene's idle everywhere
            assert {(p, amp) for _, p, amp in samples} == {(-1, 3000)}
            continue
        # the board senses the finger where it was put (the virtual ADC is 3.2
        # raw units per position: within 1 position once still)
        assert abs(statistics.median(p for _, p, _ in samples) - to_pos(mm)) <= 1
        for _, p, amp in samples:
            assert p >= 0
            assert amp == u16[p], (mm, p)     # exact: the same code, the same scene
            a8 = int(u8[p])
            lo, hi = max(0, 257 * a8 - 128), min(65535, 257 * a8 + 128)
            assert lo <= amp <= hi
            d = law.duty(amp)
            assert law.duty(lo) <= d <= law.duty(hi), (mm, p, amp, a8)
            widest = max(widest, law.duty(hi) - law.duty(lo))
            checked += 1
        # and the duty the board writes now: its status of the last refresh
        st = owner.status()
        if st["position"] >= 0:
            assert st["duty"] == law.duty(int(u16[st["position"]]))
    print("\n%d telemetry samples match the strip; the widest duty interval of an "
          "8-bit bin was %d counts of %d" % (checked, widest, law.period))


def to_pos(mm: float) -> int:
    return S.to_position(mm, DISPLAY["dx_um"])


def on_grid(mm: float) -> float:
    return round(to_pos(mm) * DISPLAY["dx_um"] / 1000.0, 4)


@pytest.mark.vboard
def test_a_strip_is_rendered_once_per_scene_and_new_scenes_show(lab):
    cache = lab.lab.strip_cache
    a = lab.get("/api/strip").json()
    n = cache.renders
    b = lab.get("/api/strip").json()
    assert cache.renders == n and a["scene_id"] == b["scene_id"]
    r = lab.post("/api/strip/texel", json={"pitch_db": 10.0, "irregularity_db": -30.0, "seed": 3})
    assert r.status_code == 200, r.text
    c = r.json()
    assert c["scene_id"] != a["scene_id"] and cache.renders == n + 1
    assert c["regions"] == [{"start_mm": 0.0, "end_mm": 101.76,
                             "label": "texel 10.0/-30.0 dB, seed 3"}]
    tex = lab.lab.owner.scene_source()["regions"][0]["texture"]
    assert (tex["pitch_db"], tex["irregularity_db"], tex["seed"], tex["v"]) == (10.0, -30.0, 3, 2)
    assert lab.get("/api/strip").json() == c
    assert cache.renders == n + 1


@pytest.mark.vboard
def test_the_scene_is_read_from_the_board_once_per_scene_played(lab):
    """Every page's strip asks what plays (the experimenter's every second);
    a long samples region is read over the link in pieces, holding the board.
    The owner asks the board once per scene played, and what it answers is
    what the board says it plays - after a push, after a refused one, after
    a stop (texel.wire through the owner's own Board, read directly here)."""
    owner = lab.lab.owner
    long = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
        "kind": "samples", "fit": "tile", "u16": [(i * 7919) % 65536 for i in range(6000)]}}]}
    owner.push(long)
    reads = owner.source_reads
    for _ in range(3):
        assert lab.get("/api/strip").status_code == 200
    assert owner.source_reads == reads + 1
    truth = owner._board.scene_source()
    assert lab.get("/api/scene").json()["scene"] == truth
    assert truth["regions"][0]["texture"]["u16"] == long["regions"][0]["texture"]["u16"]
    bad = {"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "constant",
                                                                 "level": 2.0}}]}
    with pytest.raises(ValueError):
        owner.push(bad)
    assert lab.get("/api/scene").json()["scene"] == truth          # it plays on
    lab.post("/api/strip/texel", json={"pitch_db": 4.0, "irregularity_db": -20.0, "seed": 1})
    now = lab.get("/api/scene").json()["scene"]
    assert now == owner._board.scene_source() != truth
    assert now["regions"][0]["texture"]["pitch_db"] == 4.0
    edited = lab.get("/api/scene").json()["scene"]          # a caller's copy, not the owner's
    edited["regions"].clear()
    assert lab.get("/api/scene").json()["scene"] == now


@pytest.mark.vboard
def test_the_finger_moves_and_bad_requests_change_nothing(lab):
    owner = lab.lab.owner
    assert lab.post("/api/finger", json={"position_mm": 40.0}).status_code == 200
    time.sleep(0.03)
    here = owner.status()["position"]
    assert abs(here - to_pos(40.0)) <= 1
    assert lab.get("/api/strip").json()["finger_mm"] == pytest.approx(40.0, abs=0.011)
    for body, fragment in [({"position_mm": -0.1}, "off the display"),
                           ({"position_mm": 101.8}, "off the display"),
                           ({"position_mm": 1e308}, "off the display"),
                           ({"position_mm": "3"}, "expected a number"),
                           ({"position_mm": True}, "expected a number"),
                           ({"position_mm": [1]}, "expected a number"),
                           ({}, "position_mm: required"),
                           ({"position_mm": 3, "x": 1}, "unknown key 'x'"),
                           ([3], "expected a JSON object")]:
        r = lab.post("/api/finger", json=body)
        assert r.status_code == 400 and fragment in r.json()["error"], (body, r.text)
    for raw, fragment in [('{"position_mm": NaN}', "expected a number"),
                          ('{"position_mm": Infinity}', "expected a number"),
                          ("nope", "not JSON"), ("x" * 20000, "over 16384 bytes")]:
        r = lab.post("/api/finger", content=raw, headers={"content-type": "application/json"})
        assert r.status_code == (413 if "over" in fragment else 400) and fragment in r.json()["error"], (raw[:20], r.text)
    # a "simple" POST another site's page could send without asking first
    for ctype in ("text/plain", "application/x-www-form-urlencoded", None):
        r = lab.post("/api/finger", content='{"position_mm": 3}',
                     headers={"content-type": ctype} if ctype else {})
        assert r.status_code == 400 and "application/json" in r.json()["error"], r.text
    assert lab.get("/api/finger").status_code == 405
    time.sleep(0.03)
    assert owner.status()["position"] == here                      # never moved


@pytest.mark.vboard
def test_a_refused_texture_changes_nothing_and_the_pages_are_served(lab):
    before = lab.lab.owner.scene_source()
    for body, fragment in [({"pitch_db": 25, "irregularity_db": -10}, "pitch_db"),
                           ({"pitch_db": 3}, "irregularity_db: required"),
                           ({"pitch_db": "3", "irregularity_db": -10}, "pitch_db"),
                           ({"pitch_db": 3, "irregularity_db": True}, "irregularity_db"),
                           ({"pitch_db": 3, "irregularity_db": -10, "seed": -1}, "seed"),
                           ({"pitch_db": 3, "irregularity_db": -10, "v": 1}, "unknown key 'v'"),
                           ([], "expected a JSON object")]:
        r = lab.post("/api/strip/texel", json=body)
        assert r.status_code == 400 and fragment in r.json()["error"], (body, r.text)
    assert lab.lab.owner.scene_source() == before
    assert lab.get("/api/strip?x=1").status_code == 400
    page = lab.get("/classroom")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    assert '<script src="/static/strip.js">' in page.text
    assert "texelpadStrip" in lab.get("/static/strip.js").text
    assert lab.get("/static/strip-test.html").status_code == 404    # the tests' page: not shipped
    assert lab.get("/classroom", headers={"host": "evil.example"}).status_code == 400


def test_rendering_a_full_screen_texel_scene_is_fast_enough_to_follow_a_slider():
    """Measured, not asserted (tests never assert on time): a full-screen
    texel scene (384 texels, played from its plan) and the study's split
    screen, rendered with the board's own code."""
    import texel.app
    for name, scene in [("full-screen texel", full_screen_texel(
            {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}, DISPLAY)),
                        ("split 4sin | texel", texel.app.DEFAULT_SCENE)]:
        c = S.validate(scene, DISPLAY)
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            u16, _ = strip_mod.render(c, DISPLAY, 0)
            times.append(time.perf_counter() - t0)
        sc = S.build(c, DISPLAY)
        assert all(sc.amp(p) == u16[p] for p in range(0, 19200, 7))
        print("\n%s: %.1f ms per rendering (median of 5)" % (name, 1e3 * statistics.median(times)))


# --- a board with its own finger sensor ----------------------------------------------
class RealBoard:
    """A stand-in for a board whose board file is not the virtual port (a
    Pico): status and scene as a running board gives them; finger() must
    never be called."""

    def __init__(self) -> None:
        self.fingers: list = []
        self.closed = False

    def status(self) -> dict[str, Any]:
        return {"running": True, "board": "pico", "port": "rp2", "display": dict(DISPLAY),
                "position": 1234, "amplitude": 0, "duty": 0, "pwm_top": 3675,
                "scene": {"idle": 0, "regions": []}}

    def scene_source(self) -> dict[str, Any]:
        return {"regions": [{"start_mm": 0.0, "end_mm": 101.76,
                             "texture": {"kind": "constant", "level": 0.5}}]}

    def finger(self, keyframes):
        self.fingers.append(keyframes)
        raise AssertionError("a real board's finger was moved")

    def close(self) -> None:
        self.closed = True


def test_a_real_board_refuses_the_finger(tmp_path):
    board = RealBoard()
    owner = BoardOwner("/dev/ttyACM9", connector=lambda port, timeout: board)
    with TestClient(make_app(Lab(owner, tmp_path)), base_url=BASE) as c:
        a = c.get("/api/strip").json()
        assert a["virtual"] is False and a["finger_mm"] == round(1234 * 0.0053, 4)
        assert set(_u8(a).tolist()) == {128}                        # 0.5 -> 128
        r = c.post("/api/finger", json={"position_mm": 10.0})
        assert r.status_code == 400 and "its own finger sensor" in r.json()["error"]
        assert c.post("/api/finger", json={"position_mm": None}).status_code == 400
    assert board.fingers == [] and owner.is_virtual() is False


# --- in Chromium -----------------------------------------------------------------------
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
# (no --autoplay-policy flag: the page's pointerdown must be the gesture that starts audio)
PITCH_DB = 6.0                      # P = 10^0.6 = 3.981 c/mm (docs/generator.md)
FETCH_LOG = """
window.fingerLog = [];
const _fetch = window.fetch;
window.fetch = function (url, init) {
  if (String(url).endsWith("/api/finger"))
    window.fingerLog.push({t: performance.now(), body: JSON.parse(init.body)});
  return _fetch.apply(this, arguments);
};
"""
# The display strip alone, a page of the tests' (tests/web/static, not shipped): served by
# the browser's route at the lab's own origin, so its /static/strip.js and /api/* are the lab's.
STRIP_PAGE = Path(__file__).with_name("static") / "strip-test.html"


def _open_strip_page(page: Any, url: str) -> None:
    page.route(url + "strip-test", lambda route: route.fulfill(
        path=str(STRIP_PAGE), content_type="text/html; charset=utf-8"))
    page.goto(url + "strip-test")


def _post(url: str, body: Any) -> Any:
    req = urllib.request.Request(url, data=json.dumps(body).encode(), method="POST",
                                 headers={"content-type": "application/json"})
    with urllib.request.urlopen(req, timeout=30) as r:
        return json.loads(r.read())


def _get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=30) as r:
        return json.loads(r.read())


def peak_hz(y: np.ndarray, rate: float) -> float:
    """The spectral peak of y: Hann window, zero-padded to 16x, parabolic
    interpolation of the log magnitude around the largest bin."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    spec = np.abs(np.fft.rfft(y * np.hanning(n), 16 * n))
    k = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[k - 1:k + 2] + 1e-300)
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * rate / (16 * n)


@pytest.mark.slow
@pytest.mark.vboard
def test_dragging_the_strip_in_chromium_moves_the_finger_and_sounds_at_f_times_v(tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    with lab_process(tmp_path) as (url, _):
        # a regular full-screen texture: sigma = 10^-3 decade (0.23 % per texel)
        pushed = _post(url + "api/strip/texel", {"pitch_db": PITCH_DB, "irregularity_db": -30.0,
                                                 "seed": 1})
        assert pushed["virtual"]
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS,
                                         chromium_sandbox=False)
            page = browser.new_page(viewport={"width": 1100, "height": 700})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            # every finger request as the page sends it, timed by the page's clock
            page.add_init_script(FETCH_LOG)
            _open_strip_page(page, url)
            page.wait_for_selector("body[data-ready='1']")
            assert page.evaluate("strip.data.scene_id") == pushed["scene_id"]
            assert page.evaluate("strip.audioState()") == "none"      # no audio before a gesture
            box = page.locator("#strip").bounding_box()
            y = box["y"] + box["height"] / 2
            mm_per_px = 101.76 / box["width"]

            def x_at(f: float) -> float:
                return box["x"] + f * box["width"]

            # a drag of about a second from 20 % to 60 %, a pointer event per frame
            page.mouse.move(x_at(0.2), y)
            page.mouse.down()
            t0 = time.monotonic()
            for i in range(1, 61):
                page.mouse.move(x_at(0.2 + 0.4 * i / 60), y)
                page.wait_for_timeout(16)
            page.wait_for_timeout(300)                   # the last request lands
            drag_s = time.monotonic() - t0
            st = _get(url + "api/status")
            target = 0.6 * box["width"] * mm_per_px      # mm under the pointer
            # one CSS pixel of the pointer is mm_per_px; the sensor 1 position more
            tol = mm_per_px / 0.0053 + 1
            assert abs(st["position"] - target / 0.0053) <= tol, (st["position"], target)
            sent = page.evaluate("window.fingerLog.length")
            page.mouse.up()
            page.wait_for_timeout(300)
            log = page.evaluate("window.fingerLog")
            assert log[-1]["body"] == {"position_mm": None}              # lifted on release
            assert _get(url + "api/status")["position"] == -1
            assert page.evaluate("strip.sent") == len(log) == sent + 1
            # throttled: at most ~30 a second (one in flight, the latest wins)
            assert 5 <= sent <= 30 * drag_s + 2, (sent, drag_s)
            gaps = np.diff([e["t"] for e in log])
            assert gaps.min() >= 1000 / 30 - 2, gaps.min()   # ms; timers may fire a ms early
            # what was sent follows the pointer: from 20 % of the strip to 60 %
            xs = [e["body"]["position_mm"] for e in log[:-1]]
            assert xs == sorted(xs) and abs(xs[-1] - target) <= mm_per_px, xs

            # the drag was heard (sound is on until muted; the pointerdown is the
            # gesture that starts the AudioContext), and muting stops it
            played = page.evaluate("strip.scheduled")
            assert played >= 10, played
            assert page.evaluate("strip.audioState()") == "running"
            assert page.evaluate("strip.muted") is False
            page.click("#mute")
            assert page.evaluate("strip.muted") is True and "off" in page.inner_text("#mute")
            page.mouse.move(x_at(0.5), y)
            page.mouse.down()
            for i in range(10):
                page.mouse.move(x_at(0.5 + 0.01 * i), y)
                page.wait_for_timeout(16)
            page.mouse.up()
            page.wait_for_timeout(200)
            assert page.evaluate("strip.scheduled") == played
            assert errors == []

            # the sound: a swipe at v mm/s over a texture of P c/mm peaks at P*v Hz
            P = 10 ** (PITCH_DB / 10)
            rate = 48000
            for x0, x1, secs in [(10.0, 60.0, 1.0), (90.0, 30.0, 0.5), (5.0, 95.0, 0.4)]:
                v = abs(x1 - x0) / secs
                s = np.array(page.evaluate("Array.from(strip.synth(%r, %r, %r, %d))"
                                           % (x0, x1, secs, rate)), dtype=float)
                assert len(s) == round(secs * rate)
                f = peak_hz(s, rate)
                # tolerance: half an FFT bin of the swipe, 1/(2T) Hz (0.5 Hz for 1 s).
                # The texels' own pitch spread (0.23 % SD each, ~100 texels
                # averaged: ~0.02 %) and the 8-bit strip stay well inside it
                # (measured: 0.02, 0.18, 0.26 Hz off; printed with -s)
                tol_hz = 0.5 / secs
                print("\nswipe %g -> %g mm in %g s: peak %.2f Hz, f*v = %.2f Hz"
                      % (x0, x1, secs, f, P * v))
                assert abs(f - P * v) <= tol_hz, (f, P * v)
            # a still finger is silent; the high-pass leaves no constant part
            still = page.evaluate("Array.from(strip.synth(40, 40, 0.2, 48000))")
            assert max(abs(v) for v in still) == 0
            page.screenshot(path=str(tmp_path / "strip.png"))
            browser.close()


def test_the_strip_labels_a_brush_region(lab, port):
    """A brush scene playing: /api/strip answers (a region label for every
    kind) and its amplitude is the brush painted (texel.gen.brush)."""
    from texel.gen import brush as B
    from texelpad.brush import document as D
    doc = D.design("pink", 0.04)
    lab.lab.owner.push({"regions": [D.region(doc, 5, 0, 20)]})
    r = lab.get("/api/strip")
    assert r.status_code == 200, r.text
    j = r.json()
    assert j["regions"][0]["label"] == "brush, seed 5"
    amp = np.frombuffer(base64.b64decode(j["amplitude"]), dtype=np.uint8)
    n = round(20 / 0.0053)
    want = np.frombuffer(B.paint(B.validate({k: doc[k] for k in ("k", "lam", "range")}), 5, n),
                         dtype=np.uint16)
    assert np.array_equal(amp[:n], (want.astype(int) + 128) // 257)


@pytest.mark.slow
@pytest.mark.vboard
def test_the_strip_zooms_so_a_full_screen_texture_is_not_a_solid_block(tmp_path):
    """Issue 24, item 7: a full-screen texture is 19,200 positions on a canvas
    of ~1,000 pixels, so every column's min..max covered the waveform band (a
    solid block). Zoomed in (the wheel about the pointer, the buttons), each
    column is about one position: the waveform is a line; the finger under
    the pointer is the view's mm, not the whole display's; 'whole display'
    goes back."""
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    # the share of the waveform band's pixels painted (blue) by the strip
    filled = """() => {
      const c = document.getElementById('strip'), g = c.getContext('2d');
      const h = c.height, band = Math.round(h * 0.35), top = band + 8;
      const d = g.getImageData(0, top, c.width, h - top - 16).data;
      let blue = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i + 2] > 150 && d[i] < 120) blue++;
      return blue / (d.length / 4);
    }"""
    with lab_process(tmp_path) as (url, _):
        _post(url + "api/strip/texel", {"pitch_db": 3.0, "irregularity_db": -30.0, "seed": 1})
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS,
                                         chromium_sandbox=False)
            page = browser.new_page(viewport={"width": 1100, "height": 700})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            _open_strip_page(page, url)
            page.wait_for_selector("body[data-ready='1']")
            whole = page.evaluate(filled)
            assert page.evaluate("strip.view") == {"start_mm": 0, "end_mm": 101.76}
            box = page.locator("#strip").bounding_box()
            page.mouse.move(box["x"] + 0.25 * box["width"], box["y"] + box["height"] / 2)
            for _ in range(5):                           # five notches: x32 about the pointer
                page.mouse.wheel(0, -100)
            page.wait_for_function("strip.view.end_mm - strip.view.start_mm < 4")
            v = page.evaluate("strip.view")
            assert v["start_mm"] < 25.44 < v["end_mm"]       # the pointer's mm stays put
            assert abs((v["end_mm"] - v["start_mm"]) - 101.76 / 32) < 1e-6
            zoomed = page.evaluate(filled)
            # the whole display: every column's min..max, a block (0.37 measured for
            # this texture); x32: about one position per column, a line (0.005)
            assert whole > 0.2 and zoomed < whole / 10, (whole, zoomed)
            # the finger lands at the view's mm under the pointer
            page.mouse.move(box["x"] + 0.5 * box["width"], box["y"] + box["height"] / 2)
            page.mouse.down()
            page.mouse.up()
            mid = (v["start_mm"] + v["end_mm"]) / 2
            assert abs(page.evaluate("strip.finger_mm === null ? %r : strip.finger_mm" % mid)
                       - mid) < 0.2
            page.click(".strip-zoom-all")
            assert page.evaluate("strip.view") == {"start_mm": 0, "end_mm": 101.76}
            page.click(".strip-zoom-in")
            v = page.evaluate("strip.view")
            assert abs(v["end_mm"] - v["start_mm"] - 50.88) < 1e-6
            assert not errors, errors
            browser.close()
