"""texelpad lab in a real browser: Playwright (PyPI) driving Debian's Chromium
(/usr/bin/chromium; .ci/run installs it) against `texelpad lab` on the
virtual board. One end-to-end test per protocol: the experimenter's page
starts the session from a shipped config, the participant's page is clicked
through (it shows no parameter value), and the session file holds every
answer with the scene the board played - the scene the board plays at the
end is the one the last answer heard. Skipped where Chromium or Playwright is
missing."""
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
# words a participant's screen must never show (parameter values, the answer)
SECRET = ("pitch_db", "irregularity_db", " dB", "c/mm", "seed", "odd", "4sin", "pink",
          "sawtooth", "sigma", "mm")


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS, chromium_sandbox=False)
        yield b
        b.close()


@pytest.fixture(autouse=True)
def _pages_closed(browser):
    """Every test's pages closed after it: an experimenter's page left open
    polls the server every second, and the next test's clicks queue behind it."""
    yield
    for context in browser.contexts:
        context.close()


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    data = tmp_path_factory.mktemp("lab")
    with lab_process(data) as (url, _):
        yield url, data


def _get(url: str):
    return json.loads(urllib.request.urlopen(url).read())


def _start(browser, url: str, config: str, participant: str, seed: int, **extra):
    """The experimenter's page: pick the config, the participant, the seed;
    start; the participant's page opened from its link."""
    page = browser.new_page()
    page.goto(url)
    page.wait_for_function("document.getElementById('config').options.length > 3")
    page.select_option("#config", config)
    page.fill("#participant", participant)
    page.fill("#seed", str(seed))
    if "matches" in extra:
        page.wait_for_function("[...document.getElementById('matches').options]"
                               ".some(o => o.value === %s)" % json.dumps(extra["matches"]))
        page.select_option("#matches", extra["matches"])
    page.click("#start")
    page.wait_for_selector("#participant-link[href*='/participant?s=%s/']" % participant)
    href = page.get_attribute("#participant-link", "href")
    sid = href.split("s=")[1]
    page.wait_for_selector("#detail")           # the experimenter sees the parameters
    detail = page.inner_text("#detail")
    p = browser.new_page()
    p.goto(url + href.lstrip("/"))
    p.wait_for_selector("#question:not([hidden])")
    return page, p, sid, detail


def _wait_answers(p, n: int, done: bool = False):
    """The page shows n answers (or the end); on a timeout, the page's own
    words (its error line, its progress) say why."""
    try:
        if done:
            p.wait_for_selector("#done:not([hidden])")
        else:
            p.wait_for_function("document.getElementById('progress').textContent"
                                ".includes('%d answer')" % n)
    except Exception as e:
        seen = p.evaluate("[document.getElementById('progress').textContent, "
                          "document.getElementById('error').textContent]")
        raise AssertionError("waiting for answer %d: the page shows progress %r, error %r"
                             % (n, seen[0], seen[1])) from e


def _blind(p):
    text = p.inner_text("body")
    for word in SECRET:
        assert word not in text, word


def _finish(url: str, data: Path, sid: str, n: int) -> Session:
    s = Session.open(Path(data) / (sid + ".jsonl"))
    answers = list(s.answers())
    assert len(answers) == n and s.finished
    assert _get(url + "api/scene")["scene"] == answers[-1]["scene"]
    return s


def test_pursuit_clicked_through(browser, lab):
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "pursuit-4sin", "web01", 4)
    assert "centre\t5 dB pitch, -10 dB irregularity" in detail and "edge" in detail
    _blind(p)
    # seed 000: the reference, A and B, one at a time on the whole display
    assert [p.inner_text("#feel-%d" % k) for k in range(3)] == [
        "feel reference", "feel A", "feel B"]
    assert "one at a time" in p.inner_text("#prompt")
    for i in range(20):
        p.click("#feel-0")
        p.wait_for_selector("#feel-0.playing")
        p.click("#feel-2")
        p.wait_for_selector("#feel-2.playing")
        p.click("#answer-%d" % (i % 3))                     # A, B, unsure in turn
        _wait_answers(p, i + 1, done=i == 19)
    s = _finish(url, data, sid, 20)
    assert [r["answer"] for r in s.answers()] == [["A", "B", "unsure"][i % 3] for i in range(20)]
    assert all(r["playing"] == 2 for r in s.answers())
    # B alone on the whole display, a fresh rendering for every comparison
    assert all(len(r["scene"]["regions"]) == 1 for r in s.answers())
    assert len({r["scene"]["regions"][0]["texture"]["seed"] for r in s.answers()}) == 20


def test_staircase_clicked_through(browser, lab):
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "staircase", "web02", 3)
    assert "length_mm" in detail and "26" in detail
    _blind(p)
    assert p.inner_text("#timer").endswith(" s")            # 30 s per trial, shown
    for i in range(4):
        p.click("#feel-2")
        p.wait_for_selector("#feel-2.playing")
        p.click("#answer-%d" % (i % 3))
        _wait_answers(p, i + 1)
    s = Session.open(Path(data) / (sid + ".jsonl"))
    answers = list(s.answers())
    assert [r["picked"] for r in answers] == [0, 1, 2, 0]
    assert all(r["answer"] == (r["picked"] == r["odd"]) for r in answers)
    assert all(r["scene"]["regions"][0]["texture"]["texel_samples"] ==
               round(r["state"]["length_mm"] / 0.0053) for r in answers)
    assert _get(url + "api/scene")["scene"]["regions"][0]["texture"]["texel_samples"] == \
        round(_get(url + "api/sessions/%s/monitor" % sid)["detail"]["length_mm"] / 0.0053)


def test_search_clicked_through(browser, lab):
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "search-4sin", "web03", 9)
    assert "sigma" in detail and "candidates" in detail
    _blind(p)
    for i in range(3):
        p.click("#feel-%d" % (i % 3))
        p.wait_for_selector("#feel-%d.playing" % (i % 3))
        if i == 1:          # seed 003's friction slider: the candidate plays again at 0.6
            with p.expect_response(lambda r: r.url.endswith("/feel")):
                p.eval_on_selector("#level", "e => { e.value = '0.6'; "
                                   "e.dispatchEvent(new Event('change')); }")
            assert _get(url + "api/scene")["scene"]["regions"][1]["texture"]["gain"] == 0.6
        p.click("#answer-%d" % (i % 3))                     # choose 1, 2, 3
        _wait_answers(p, i + 1)
    assert p.input_value("#level") == "0.6"                 # (kept across iterations)
    p.click("#answer-4")                                    # save candidate 2
    _wait_answers(p, 4)
    p.click("#feel-2")
    p.wait_for_selector("#feel-2.playing")
    p.click("#answer-6")                                    # satisfied: stop
    _wait_answers(p, 5, done=True)
    s = _finish(url, data, sid, 5)
    assert [r["answer"] for r in s.answers()] == [
        {"choose": 0, "level": 1.0}, {"choose": 1, "level": 0.6}, {"choose": 2, "level": 0.6},
        {"save": 1, "level": 0.6}, {"stop": True}]
    assert len(s.records[-1]["result"]["saved"]) == 1
    assert s.records[-1]["result"]["saved"][0]["params"]["gain"] == 0.6


def test_free_exploration_then_quantization_clicked_through(browser, lab):
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "free-nine", "web04", 2)
    assert "reference" in detail
    _blind(p)
    for i in range(9):
        # drag the sliders (each change plays), pick a confidence, submit
        for v in (200, 700, 450 + 10 * i):
            p.fill("#pitch", str(v))
        p.fill("#irregularity", str(300 + 20 * i))
        p.fill("#confidence-slider", str(1 + 0.5 * i))     # the app's continuous slider
        p.click("#submit")
        _wait_answers(p, i + 1, done=i == 8)
    s = _finish(url, data, sid, 9)
    answers = list(s.answers())
    # the lab's app's sliders: pitch 0..1000 over -10..20 dB, irregularity linear in sigma
    # over 0..1 decade (position 300: sigma 0.3 decade = 10 log10 0.3 = -5.229 dB)
    assert answers[0]["answer"] == {"pitch_db": 3.5, "irregularity_db": -5.229, "confidence": 1}
    assert [a["answer"]["confidence"] for a in answers] == [1 + 0.5 * i for i in range(9)]
    assert answers[0]["scene"]["regions"][1]["texture"]["pitch_db"] == 3.5
    assert answers[0]["scene"]["regions"][1]["texture"]["texel_samples"] == 50
    moves = [r for r in s.records if r["kind"] == "move" and r["trial"] == 0]
    assert len(moves) >= 3 and moves[-1]["pitch_db"] == 3.5
    # seed 000's quantization test on web04's own matches: 27 trials
    exp2, q, qid, detail = _start(browser, url, "quant-paper", "web04", 5, matches=sid)
    assert "quant_db" in detail and "source" in detail
    _blind(q)
    assert q.get_attribute("#rating", "value") == "3"       # the app's slider starts at 3
    for i in range(27):
        q.fill("#rating", str(round(1 + 0.15 * i, 2)))      # continuous, 1 .. 4.9
        q.click("#submit-rating")
        _wait_answers(q, i + 1, done=i == 26)
    qs = _finish(url, data, qid, 27)
    felt = {a["state"]["reference"]: a["scene"]["regions"][1]["texture"] for a in answers}
    sources = []
    for r in qs.answers():
        tex = r["scene"]["regions"][1]["texture"]
        ref = r["scene"]["regions"][0]["texture"]["name"]
        sources.append((r["state"]["source"], r["state"]["quant_db"]))
        if r["state"]["source"] == "own":       # the texture felt at submission, exactly
            assert (tex["pitch_db"], tex["seed"]) == (felt[ref]["pitch_db"], felt[ref]["seed"])
            assert tex.get("quant_db", 0.0) == r["state"]["quant_db"]
        else:                                   # the rater's logged sequence
            assert tex["kind"] == "samples" and len(tex["u16"]) == 9600
    assert sorted(sources) == sorted([("own", 0.0)] * 9 + [("rater", 0.0)] * 9 +
                                     [("rater", q) for q in (1.0, 3.0, 5.0)] * 3)
    assert [r["answer"] for r in qs.answers()] == [round(1 + 0.15 * i, 2) for i in range(27)]


def test_mapping_clicked_through(browser, lab):
    """Seed 001's second experiment: its own screen - two plain sliders 0..100
    and no confidence, then the 0..10 ratings."""
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "mapping", "web05", 6)
    _blind(p)
    for word in ("bp-", "zeta", "lognormal"):
        assert word not in p.inner_text("body")
    assert p.is_hidden("#confidence")
    for i in range(9):
        p.fill("#pitch", str(100 * i))                  # 0 .. 800 of 1000: P = 0 .. 80
        p.fill("#irregularity", str(1000 - 100 * i))    # I = 100 .. 20
        p.click("#submit")
        _wait_answers(p, i + 1)
    p.wait_for_selector("#answer-10")                   # the ratings: 0 .. 10
    assert "0 = completely different, 10 = identical" in p.inner_text("#prompt")
    for i in range(25):
        p.click("#answer-%d" % (i % 11))
        _wait_answers(p, 10 + i, done=i == 24)
    s = _finish(url, data, sid, 34)
    answers = [r["answer"] for r in s.answers()]
    assert answers[:9] == [{"pitch": 10.0 * i, "irregularity": 100.0 - 10 * i}
                           for i in range(9)]
    assert answers[9:] == [i % 11 for i in range(25)]
    right = s.records[1]["scene"]["regions"][1]["texture"]        # seed 001's stimulus
    assert right["texel_samples"] == 189 and right["phase"] == "reset"
    assert right["min_cpmm"] == 1.0


def test_a_slider_move_lost_on_the_way_is_played_before_the_match_is_answered(browser, lab):
    """A slider move that never reached the board (the connection dropped):
    the server takes only the match that plays, so "this is my match" plays
    the sliders' place first, then answers it - one answer, no silent refusal."""
    url, data = lab
    exp, p, sid, detail = _start(browser, url, "mapping", "web09", 7)
    dropped = []

    def drop_first(route):
        if not dropped:
            dropped.append(route.request.post_data)
            route.abort()
        else:
            route.continue_()
    p.route("**/feel", drop_first)
    p.fill("#pitch", "300")
    p.wait_for_function("document.getElementById('error').textContent.includes('does not answer')")
    p.click("#submit")
    _wait_answers(p, 1)
    assert dropped and p.inner_text("#error") == ""
    s = Session.open(Path(data) / (sid + ".jsonl"))
    first = next(iter(s.answers()))
    assert first["answer"]["pitch"] == 30.0


# --- issue 24: one click, one answer; the experimenter sees every refusal -------------------

def _answer_posts(page) -> list:
    posts = []
    page.on("request", lambda r: posts.append(r.post_data)
            if r.method == "POST" and r.url.endswith("/answer") else None)
    return posts


def test_a_double_click_gives_one_answer(browser, lab):
    """A double-click on a rating, or on "this is my match", answered the
    next trial too (trial 1 -> trial 3, the same match in the file twice):
    the page disables its buttons while the answer is in flight, and the
    answer names its question (a repeat would be refused, 409)."""
    url, data = lab
    exp, p, sid, _ = _start(browser, url, "quant-exemplars", "web06", 1)
    posts = _answer_posts(p)
    assert p.inner_text("#progress").startswith("trial 1 of 12 - 0 answers")
    p.fill("#rating", "3")
    p.dblclick("#submit-rating")
    _wait_answers(p, 1)
    p.wait_for_selector("#submit-rating:not([disabled])")
    assert p.inner_text("#progress").startswith("trial 2 of 12 - 1 answer")
    p.fill("#rating", "5")
    p.dblclick("#submit-rating")
    _wait_answers(p, 2)
    p.wait_for_selector("#submit-rating:not([disabled])")
    assert p.inner_text("#progress").startswith("trial 3 of 12 - 2 answers")
    s = Session.open(Path(data) / (sid + ".jsonl"))
    assert [r["answer"] for r in s.answers()] == [3, 5]
    assert [json.loads(x)["question"] for x in posts] == [0, 1]     # one request per click
    assert p.inner_text("#error") == ""
    # the free exploration's "this is my match"
    exp2, f, fid, _ = _start(browser, url, "free-nine", "web06", 2)
    posts = _answer_posts(f)
    f.fill("#pitch", "300")
    f.fill("#confidence-slider", "4")
    f.dblclick("#submit")
    _wait_answers(f, 1)
    f.wait_for_selector("#submit:not([disabled])")
    assert f.inner_text("#progress").startswith("trial 2 of 9 - 1 answer")
    s = Session.open(Path(data) / (fid + ".jsonl"))
    assert [r["answer"]["confidence"] for r in s.answers()] == [4]
    assert len(posts) == 1


def test_the_experimenter_sees_a_refused_start_until_the_next_action(browser, lab):
    """The 1 s monitor poll cleared #error ~50 ms after a refusal was shown,
    so a refused start was invisible while the monitor still showed the
    previous participant; a seed typed as 12a became a random seed."""
    url, data = lab
    exp, p, sid, _ = _start(browser, url, "pursuit-4sin", "web07", 1)
    exp.fill("#participant", "no such id!")
    exp.click("#start")
    exp.wait_for_function("document.getElementById('error').textContent.includes('not started')")
    for _ in range(2):                  # two polls of the monitor later, still shown
        with exp.expect_response(lambda r: r.url.endswith("/monitor")):
            pass
    assert "not started: participant" in exp.inner_text("#error")
    exp.fill("#participant", "web08")
    exp.fill("#seed", "12a")
    exp.click("#start")
    exp.wait_for_function("document.getElementById('error').textContent.includes('12a')")
    assert "seed \"12a\" is not a whole number" in exp.inner_text("#error")
    with exp.expect_response(lambda r: r.url.endswith("/monitor")):
        pass
    assert "12a" in exp.inner_text("#error") and not (Path(data) / "web08").exists()
    exp.fill("#seed", "12")
    exp.click("#start")                 # the next action that succeeds clears it
    exp.wait_for_selector("#participant-link[href*='web08/']")
    assert exp.inner_text("#error") == ""
    s = Session.open(next((Path(data) / "web08").glob("*.jsonl")))
    assert s.header["seed"] == 12
