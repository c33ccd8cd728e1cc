"""See and hear the playing scene (docs/lab.md): the display strip and
the virtual board's finger, for classrooms and anyone without a glass plate.

    GET  /api/strip          the amplitude the board plays at every display
                             position (base64, one uint8 each), the regions,
                             the finger, whether it is the virtual board
    POST /api/finger         {"position_mm": number or null}: the virtual
                             board's finger there now (null: lifted)
    POST /api/strip/texel    {"pitch_db", "irregularity_db", "seed"?}: play
                             one full-screen texel texture (format 2); refused
                             (409) while a study session's question plays
                             (web/server.py Lab.claim_board)
    GET  /classroom          the teachers' page (static/classroom.html)

The amplitude is the canonical scene the board plays (Board.scene_source)
rendered here with the board's own code (texel.runtime.scene.build, and
Scene.amp where a texel region plays from its plan: what the Python refresh
calls per position; the fused viper refresh, runtime/refresh_viper.py, does
the same integer arithmetic), so it IS what the board plays, bit for bit
before the 8-bit rounding: tests/web/test_strip.py checks every telemetry
sample of the virtual board (which runs the viper refresh) against it. The page's script is
static/strip.js (window.texelpadStrip).
"""
from __future__ import annotations

import base64
import hashlib
import json
import math
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from starlette.requests import Request
from starlette.responses import FileResponse
from starlette.routing import Route

import texel
import texel.runtime.scene as _scene
from texel.runtime.kinds import label_of

from ..link.board import full_screen_texel
from .api import Refused, body_of, handle, keys

STATIC_DIR = Path(__file__).with_name("static")
CACHE_SCENES = 16           # renderings kept (a slider pushes many scenes; a few come back)
TEXEL_KEYS = {"pitch_db", "irregularity_db", "seed"}


# --- rendering ------------------------------------------------------------------------
def render(canonical: dict[str, Any] | None, display: dict[str, Any],
           idle: int) -> tuple[np.ndarray, list[tuple[int, int, dict]]]:
    """(the uint16 amplitude 0..65535 the board plays at each display
    position, each region's [start, end) positions and texture, in the
    canonical order). texel.runtime.scene.build is the board's own rendering (integer engine, plans, samples fits); where
    a region plays from its plan (K_PLAN) Scene.amp gives each position, as
    the board's refresh does. Gaps (and every
    position when nothing plays) play `idle`: the scene's idle_amplitude or
    the board's default, as status()["scene"]["idle"] says. A full-screen
    texel scene takes about 20 ms here (measured: build 2-6 ms, the amp()
    loop 16 ms over 19,200 positions; tests/web/test_strip.py prints it)."""
    out = np.full(display["positions"], idle, dtype=np.uint16)
    if canonical is None:
        return out, []
    sc = _scene.build(_scene.validate(canonical, display), display, idle_default=idle)
    bufs = sc.buffers()
    spans = []
    for r, (s, e, kind, value) in zip(sc.source["regions"], sc.spans()):
        spans.append((s, e, r["texture"]))
        if kind == _scene.K_BUF:                # a rendered map: the buffer the board holds
            out[s:e] = np.frombuffer(bufs[value], dtype=np.uint16)   # array('H'): native order
        elif kind == _scene.K_CONST:            # one table entry: value is the amplitude
            out[s:e] = value
        elif kind == _scene.K_CHUNK:            # 1 KB chunks: a brush painted here
            out[s:e] = np.concatenate([np.frombuffer(c, dtype=np.uint16) for c in bufs[value]])
        else:                                   # a plan (K_PLAN, K_TILE, K_STRETCH)
            amp = sc.amp
            out[s:e] = np.fromiter((amp(p) for p in range(s, e)), dtype=np.uint16,
                                   count=e - s)
    return out, spans


def to_u8(u16: np.ndarray) -> np.ndarray:
    """uint16 amplitudes -> uint8: round(a * 255 / 65535) = (a + 128) // 257
    (65535 / 255 = 257 exactly), so 0 -> 0, 65535 -> 255, error <= 0.5/255
    of full scale (128.5 of 65535)."""
    return ((u16.astype(np.uint32) + 128) // 257).astype(np.uint8)


def regions_of(spans: list[tuple[int, int, dict]], display: dict[str, Any]) -> list[dict]:
    """[{start_mm, end_mm, label}]: each region where the board plays it (its
    positions as build() rounded them: scene.to_position, halves up)."""
    dx = display["dx_um"]
    return [{"start_mm": round(s * dx / 1000.0, 4), "end_mm": round(e * dx / 1000.0, 4),
             "label": label_of(tex)} for s, e, tex in spans]


class StripCache:
    """Renderings by scene (canonical JSON, display, idle), least recently
    used dropped beyond CACHE_SCENES. Its own lock: the routes hold the lab's,
    but the cache must not rely on it."""

    def __init__(self, size: int = CACHE_SCENES) -> None:
        self.size = size
        self._d: OrderedDict[str, dict[str, Any]] = OrderedDict()
        self._lock = threading.Lock()
        self.renders = 0            # renderings done (tests: a cached scene is not redone)

    @staticmethod
    def key(canonical: Any, display: dict[str, Any], idle: int) -> str:
        text = json.dumps([canonical, display["positions"], display["dx_um"], idle],
                          sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def get(self, canonical: dict[str, Any] | None, display: dict[str, Any],
            idle: int) -> dict[str, Any]:
        k = self.key(canonical, display, idle)
        with self._lock:
            hit = self._d.get(k)
            if hit is not None:
                self._d.move_to_end(k)
                return hit
        u16, spans = render(canonical, display, idle)
        item = {"scene_id": k, "u16": u16,
                "amplitude": base64.b64encode(to_u8(u16).tobytes()).decode("ascii"),
                "regions": regions_of(spans, display),
                "name": canonical.get("name") if canonical else None}
        with self._lock:
            self.renders += 1
            self._d[k] = item
            while len(self._d) > self.size:
                self._d.popitem(last=False)
        return item


# --- the requests ----------------------------------------------------------------------
def _length_mm(display: dict[str, Any]) -> float:
    return display["positions"] * display["dx_um"] / 1000.0


def idle_of(st: dict[str, Any]) -> int:
    """The idle amplitude (uint16) the board's status says its scene plays in gaps."""
    sc = st.get("scene")
    return sc["idle"] if isinstance(sc, dict) and isinstance(sc.get("idle"), int) else 0


def status_fields(st: dict[str, Any], display: dict[str, Any], idle: int) -> dict[str, Any]:
    """What every strip answer takes from the board's status: the display,
    the idle amplitude, whether it is the virtual board, the finger."""
    pos = st.get("position", -1)
    return {"positions": display["positions"], "dx_um": display["dx_um"],
            "length_mm": round(_length_mm(display), 6), "idle": idle,
            "virtual": st.get("port") == "virtual",
            # the finger where the board's sensor has it now (None: lifted)
            "finger_mm": None if not isinstance(pos, int) or pos < 0
            else round(pos * display["dx_um"] / 1000.0, 4)}


def strip_answer(cache: StripCache, st: dict[str, Any],
                 canonical: dict[str, Any] | None) -> dict[str, Any]:
    """The /api/strip answer from the board's status (display, idle,
    finger, port) and the canonical scene it plays."""
    display = {"positions": st["display"]["positions"], "dx_um": st["display"]["dx_um"]}
    idle = idle_of(st)
    item = cache.get(canonical, display, idle)
    return dict(status_fields(st, display, idle), amplitude=item["amplitude"],
                regions=item["regions"], name=item["name"], scene_id=item["scene_id"])


def check_position(body: Any, display: dict[str, Any]) -> float | None:
    """{"position_mm": number in [0, display length] or null} -> mm or None."""
    keys(body, {"position_mm"})
    if "position_mm" not in body:
        raise Refused("position_mm: required (a number of mm, or null to lift the finger)")
    x = body["position_mm"]
    if x is None:
        return None
    total = _length_mm(display)
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise Refused("position_mm: expected a number in [0, %g] or null, got %s"
                      % (total, json.dumps(x)[:40]))
    if not 0.0 <= x <= total:
        raise Refused("position_mm: %r is off the display (0 .. %g mm)" % (x, total))
    return float(x)


def check_texel(body: Any) -> dict[str, Any]:
    """{"pitch_db", "irregularity_db", "seed"?} -> texel parameters (format
    2: the same texture on every board), checked by texel.validate (the
    generator's own ranges and words) before anything is sent."""
    keys(body, TEXEL_KEYS)
    for k in ("pitch_db", "irregularity_db"):
        if k not in body:
            raise Refused("%s: required (dB)" % k)
    p = {"pitch_db": body["pitch_db"], "irregularity_db": body["irregularity_db"],
         "seed": body.get("seed", 0), "v": 2}
    try:
        texel.validate(p)
    except ValueError as e:
        raise Refused(str(e)) from None
    return p


def routes(lab: Any) -> list:
    cache = lab.strip_cache = StripCache()

    def strip(request: Request) -> dict[str, Any]:
        if request.query_params:
            raise Refused("GET /api/strip takes no parameters")
        return strip_answer(cache, *lab.owner.playing())

    def finger(request: Request) -> dict[str, Any]:
        body = body_of(request)
        display = lab.owner.display()
        x = check_position(body, display)
        t_us = lab.owner.finger(x)
        return {"position_mm": x, "t_us": t_us}

    def push_texel(request: Request) -> dict[str, Any]:
        params = check_texel(body_of(request))
        claim = getattr(lab, "claim_board", None)   # (a study's scene is not replaced: 409)
        if claim is not None:
            claim("the classroom")
        display = lab.owner.display()
        st, canonical = lab.owner.push(full_screen_texel(params, display))
        return strip_answer(cache, st, canonical)

    async def classroom(request: Request) -> FileResponse:
        return FileResponse(STATIC_DIR / "classroom.html", media_type="text/html")

    return [Route("/api/strip", handle(lab.lock, strip)),
            Route("/api/finger", handle(lab.lock, finger), methods=["POST"]),
            Route("/api/strip/texel", handle(lab.lock, push_texel), methods=["POST"]),
            Route("/classroom", classroom)]
