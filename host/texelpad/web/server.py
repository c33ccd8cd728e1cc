"""`texelpad lab`'s web server (Starlette, an established ASGI framework; served
by uvicorn on 127.0.0.1 only): the study protocols (texelpad.study,
texelpad.search) on one board (web/owner.py, the only owner of a Board).

    GET  /                                     the page
    GET  /api/status                           the board's status (or why it is lost)
    GET  /api/scene                            the canonical scene it plays
    POST /api/sessions                         {protocol, participant, seed?, config?}
    GET  /api/sessions/{participant}/{name}    the session's question (resumed from its file)
    POST /api/sessions/{participant}/{name}/feel    {option: k}  play option k
    POST /api/sessions/{participant}/{name}/answer  {answer: ...}

Every request is validated (a JSON object of known keys, at most 16 KB; ids
as texelpad.study.session.check_name; the board's own scene validation is the
last word) and a refused one changes nothing: 400 with the reason, 503 when
the board is gone. Every answer is in the session file (fsynced) before the
reply. Questions show no parameter values: the participant screen is blind.
"""
from __future__ import annotations

import json
import random
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from ..link.board import host_check
from ..search.preference import candidate_params
from ..study import protocols
from ..study import scenes as S
from ..study.session import Session, check_name
from .api import BODY_MAX, Refused, body_of, handle, keys as _keys
from . import strip
from .owner import BoardOwner

PROTOCOL_KEYS = {"protocol", "participant", "seed", "config", "reference"}


@dataclass
class Live:
    """A session in memory: its file, the protocol's state, the current
    question (built once per state: None after an answer), its options
    (scenes, server side) and what plays."""
    session: Session
    state: Any
    reference: dict[str, Any]
    question: dict[str, Any] | None = None
    options: list[dict[str, Any]] = field(default_factory=list)
    odd: int | None = None
    playing: int | None = None
    playing_scene: dict[str, Any] | None = None


class Lab:
    def __init__(self, owner: BoardOwner, data: str | Path) -> None:
        self.owner = owner
        self.data = Path(data)
        self.data.mkdir(parents=True, exist_ok=True)
        self.live: dict[str, Live] = {}
        self.lock = threading.Lock()       # one request at a time (web/api.handle)

    # --- protocol questions ---------------------------------------------------------
    def _question(self, lv: Live) -> dict[str, Any]:
        """The current question of the session (built when its state changed)."""
        if lv.question is None:
            lv.question = self._build_question(lv)
        return lv.question

    def _build_question(self, lv: Live) -> dict[str, Any]:
        h = lv.session.header
        proto, st = h["protocol"], lv.state
        display = self.owner.display()
        if proto == "pursuit":
            q = st.next_comparison()
            if q is None:
                return {"done": True, "result": {"centre": [st.centre.u, st.centre.v]}}
            lv.options = [S.point_scene(lv.reference, q.a, display, name="A"),
                          S.point_scene(lv.reference, q.b, display, name="B")]
            return {"done": False, "trial": q.trial, "index": q.index, "options": ["A", "B"],
                    "answers": ["A", "B", "unsure"]}
        if proto == "search":
            xs = st.ask()
            lv.options = [S.split(lv.reference, candidate_params(x, st.dims, st.texture_seed),
                                  display, name="candidate %d" % (k + 1))
                          for k, x in enumerate(xs)]
            return {"done": False, "iteration": st.iteration, "options": ["1", "2", "3"],
                    "answers": [{"choose": k} for k in range(3)] + [{"save": k} for k in range(3)]}
        if proto == "staircase":
            if st.done:
                return {"done": True, "result": {"threshold_mm": st.threshold_mm()}}
            lv.options, lv.odd = S.staircase_scenes(st.texel_samples(), len(st.track),
                                                    h["seed"], display,
                                                    h["config"].get("distribution"))
            return {"done": False, "trial": len(st.track), "options": ["1", "2", "3"],
                    "answers": [0, 1, 2]}
        raise Refused("protocol: unknown %r" % proto)

    def _play(self, lv: Live, k: int) -> dict[str, Any]:
        st, canonical = self.owner.push(lv.options[k])
        lv.playing, lv.playing_scene = k, canonical
        return st

    # --- the API ----------------------------------------------------------------------
    def create(self, body: dict[str, Any]) -> dict[str, Any]:
        _keys(body, PROTOCOL_KEYS)
        proto = body.get("protocol")
        if proto not in protocols.PROTOCOLS:
            raise Refused("protocol: expected one of %s, got %r"
                          % (", ".join(protocols.PROTOCOLS), proto))
        participant = check_name("participant", body.get("participant"))
        seed = body.get("seed", random.SystemRandom().randrange(1 << 31))
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 1 << 31:
            raise Refused("seed: expected an int in [0, 2^31), got %r" % (seed,))
        config = body.get("config") or {}
        if not isinstance(config, dict):
            raise Refused("config: expected an object")
        reference = body.get("reference") or S.DEFAULT_REFERENCE
        if not isinstance(reference, dict):
            raise Refused("reference: expected a texture object")
        try:
            state = protocols.start(proto, config, seed)
        except (TypeError, ValueError) as e:
            raise Refused("config: %s" % e) from None
        # the reference must be a texture the board takes: its own validation, here
        display = self.owner.display()
        host_check(S.split(reference, {"pitch_db": 0.0, "irregularity_db": 0.0, "v": 2},
                           display), display)
        sess = Session.create(self.data, proto, participant,
                              dict(config, reference=reference), seed)
        lv = Live(sess, state, reference)
        key = "%s/%s" % (participant, sess.path.stem)
        self.live[key] = lv
        q = self._question(lv)
        if not q["done"]:
            self._play(lv, 0)
        return {"id": key, "question": q, "playing": lv.playing}

    def get(self, participant: str, name: str) -> Live:
        check_name("participant", participant)
        check_name("session", name)
        key = "%s/%s" % (participant, name)
        lv = self.live.get(key)
        if lv is None:                                  # resume from its file
            path = self.data / participant / (name + ".jsonl")
            if not path.is_file():
                raise Refused("no session %s" % key)
            sess = Session.open(path)
            reference = sess.header["config"].get("reference", S.DEFAULT_REFERENCE)
            lv = Live(sess, protocols.replay(sess), reference)
            self.live[key] = lv
        return lv

    def question(self, participant: str, name: str) -> dict[str, Any]:
        lv = self.get(participant, name)
        return {"id": "%s/%s" % (participant, name), "question": self._question(lv),
                "playing": lv.playing, "answers_so_far": len(lv.session.records)}

    def feel(self, participant: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
        _keys(body, {"option"})
        lv = self.get(participant, name)
        q = self._question(lv)
        k = body.get("option")
        if q["done"] or isinstance(k, bool) or not isinstance(k, int) \
                or not 0 <= k < len(lv.options):
            raise Refused("option: expected 0 .. %d, got %r" % (len(lv.options) - 1, k))
        self._play(lv, k)
        return {"playing": k}

    def answer(self, participant: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
        _keys(body, {"answer"})
        lv = self.get(participant, name)
        q = self._question(lv)
        if q["done"]:
            raise Refused("the session is finished")
        a = body.get("answer")
        if a not in q["answers"]:
            raise Refused("answer: expected one of %s, got %r" % (json.dumps(q["answers"]), a))
        proto = lv.session.header["protocol"]
        rec = {"question": q, "answer": a, "scene": lv.playing_scene, "playing": lv.playing}
        if proto == "staircase":
            rec["answer"] = a == lv.odd             # what the protocol takes: found or not
            rec["picked"] = a
            rec["odd"] = lv.odd
        protocols.apply(proto, lv.state, rec["answer"])
        lv.question = None                              # the state moved on
        lv.session.append(rec)
        nq = self._question(lv)
        if not nq["done"]:
            self._play(lv, 0)
        return {"question": nq, "playing": lv.playing, "answers_so_far": len(lv.session.records)}



PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>texelpad lab</title>
<style>
body { font: 16px system-ui, sans-serif; margin: 2em; max-width: 46em; }
button { font-size: 1.1em; margin: 0.2em; padding: 0.4em 1em; }
#question { margin-top: 1em; } .muted { color: #666; } .err { color: #b00; }
</style></head>
<body>
<h1>texelpad lab</h1>
<p id="status" class="muted">connecting to the board ...</p>
<section id="setup">
  <label>protocol <select id="protocol">
    <option value="pursuit">guided exploration (pursuit vector)</option>
    <option value="staircase">texel-length oddity staircase</option>
    <option value="search">preference search</option></select></label>
  <label>participant <input id="participant" value="p01" size="10"></label>
  <button id="start">start</button>
  <label>or resume <input id="resume-id" placeholder="p01/pursuit-1" size="16"></label>
  <button id="resume">resume</button>
</section>
<section id="question" hidden>
  <p id="prompt"></p>
  <div id="feel"></div>
  <div id="answers"></div>
  <p id="progress" class="muted"></p>
</section>
<p id="error" class="err"></p>
<script>
let sid = null;
const $ = (id) => document.getElementById(id);
async function call(method, path, body) {
  const r = await fetch(path, {method, headers: {"content-type": "application/json"},
                               body: body === undefined ? undefined : JSON.stringify(body)});
  const j = await r.json();
  if (!r.ok) { $("error").textContent = j.error || r.statusText; throw new Error(j.error); }
  $("error").textContent = "";
  return j;
}
const PROMPTS = {
  pursuit: "Feel A and B. Which one is closer to the reference on the left?",
  staircase: "Feel the three textures. Which one is different?",
  search: "Feel the three candidates. Which one is closest to the reference on the left?"};
function label(a) {
  if (typeof a === "number") return "texture " + (a + 1) + " is the odd one";
  if (typeof a === "string") return a === "unsure" ? "unsure" : a + " is closer";
  const [k, v] = Object.entries(a)[0];
  return (k === "choose" ? "choose " : "save ") + (v + 1);
}
function show(res) {
  const q = res.question;
  $("setup").hidden = true; $("question").hidden = false;
  if (q.done) {
    $("prompt").textContent = "Done - thank you.";
    $("feel").innerHTML = ""; $("answers").innerHTML = "";
    $("progress").textContent = "session " + sid + " finished";
    return;
  }
  $("prompt").textContent = PROMPTS[$("protocol").value] || "";
  $("feel").innerHTML = "";
  q.options.forEach((name, k) => {
    const b = document.createElement("button");
    b.id = "feel-" + k; b.textContent = "feel " + name;
    if (res.playing === k) b.style.fontWeight = "bold";
    b.onclick = async () => { const r = await call("POST", "/api/sessions/" + sid + "/feel",
                                                  {option: k});
      [...$("feel").children].forEach((c, i) => c.style.fontWeight = i === r.playing ? "bold" : "");
    };
    $("feel").appendChild(b);
  });
  $("answers").innerHTML = "";
  q.answers.forEach((a, i) => {
    const b = document.createElement("button");
    b.id = "answer-" + i; b.textContent = label(a);
    b.onclick = async () => show(await call("POST", "/api/sessions/" + sid + "/answer",
                                            {answer: a}));
    $("answers").appendChild(b);
  });
  $("progress").textContent = "session " + sid + ": " + (res.answers_so_far || 0) + " answers";
}
$("start").onclick = async () => {
  const res = await call("POST", "/api/sessions", {protocol: $("protocol").value,
                                                   participant: $("participant").value});
  sid = res.id; show(res);
};
$("resume").onclick = async () => {
  sid = $("resume-id").value.trim();
  const res = await call("GET", "/api/sessions/" + sid);
  $("protocol").value = sid.split("/")[1].split("-")[0]; show(res);
};
fetch("/api/status").then(r => r.json()).then(s => {
  $("status").textContent = s.error ? s.error :
    "board " + (s.board || "?") + (s.running ? " playing" : " stopped");
});
</script></body></html>"""


STATIC = Path(__file__).with_name("static")   # the pages' scripts and styles
LOCAL_HOSTS = ["127.0.0.1", "localhost"]


def make_app(lab: Lab, allowed_hosts: list[str] | None = None) -> Starlette:
    async def page(request: Request) -> HTMLResponse:
        return HTMLResponse(PAGE)

    async def status(request: Request):
        return lab.owner.status()

    async def scene(request: Request):
        return {"scene": lab.owner.scene_source()}

    async def create(request: Request):
        return lab.create(await body_of(request))

    async def question(request: Request):
        p = request.path_params
        return lab.question(p["participant"], p["name"])

    async def feel(request: Request):
        p = request.path_params
        return lab.feel(p["participant"], p["name"], await body_of(request))

    async def answer(request: Request):
        p = request.path_params
        return lab.answer(p["participant"], p["name"], await body_of(request))

    routes = [Route("/", page),
              Route("/api/status", handle(lab.lock, status)),
              Route("/api/scene", handle(lab.lock, scene)),
              Route("/api/sessions", handle(lab.lock, create), methods=["POST"]),
              Route("/api/sessions/{participant}/{name}", handle(lab.lock, question)),
              Route("/api/sessions/{participant}/{name}/feel", handle(lab.lock, feel), methods=["POST"]),
              Route("/api/sessions/{participant}/{name}/answer", handle(lab.lock, answer),
                    methods=["POST"])]
    routes += strip.routes(lab)
    routes.append(Mount("/static", StaticFiles(directory=STATIC), name="static"))
    return Starlette(routes=routes, middleware=[
        # localhost only, also by name: a page elsewhere cannot reach it by
        # rebinding a DNS name to 127.0.0.1
        Middleware(TrustedHostMiddleware, allowed_hosts=allowed_hosts or LOCAL_HOSTS)])
