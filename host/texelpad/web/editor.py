"""The scene editor (docs/brush.md, "Painting in the browser"): paint
textures onto spans of the display strip - a brush (a brush file, or a
designed spectral shape), texel parameters, a reference texture, a constant -
and play the result on the board at once.

    GET  /editor                 the page (static/editor.html, static/editor.js)
    GET  /api/editor/palette     what can be painted: the reference names, the brush
                                 files found, the designed shapes and their ranges,
                                 the texel parameters' ranges (texel.gen.params.SPEC)
    GET  /api/editor/scene       the playing scene in the editor's form (below), its
                                 scene_id and strip
    GET  /api/editor/strip       the strip as GET /api/strip answers it, with brush
                                 regions labelled (static/strip.js's `path` option)
    POST /api/editor/scene       {"regions": [...] in painting order, "name"?, "base"?}:
                                 overlaps resolved (below), brushes resolved, the
                                 board's own validation, pushed; answers the regions,
                                 the canonical scene, the board's status, the strip
    POST /api/editor/brushes     {"name", "design": {...}, "replace"?}: save a designed
                                 brush as a file in the brush folder

The editor's form of a region is a scene region whose texture is one the
board takes (texel, reference, constant; texel without "v" is format 2: the
same texture on every board) or a reference the server resolves:

    {"kind": "brush", "file": "NAME.json" | "NAME.tpb", "seed": n}
    {"kind": "brush", "design": {"shape", "level", "mean", "k"?}, "seed": n}
    {"kind": "brush", "brush": {"k", "lam", "range"}, "seed": n}     (as the board takes it)
    {"kind": "kept", "id": "..."}     a texture of the scene the editor loaded from the board
                                      that is too large to send back (an uploaded samples
                                      map, a brush of unknown origin): held here by id

so a page sends a few hundred bytes per region (a brush as the board takes it
is ~3 KB: 16 KB bodies, web/api.py) and the brush file or design it painted
with stays in the scene's list.

Overlaps: the regions are given in painting order and a later region wins
where it overlaps an earlier one; the earlier one is trimmed to what is left
of it, split in two when the new one lies inside it, dropped when covered.
Every piece keeps its texture and is rendered over its own span, from its own
start (texel.runtime.scene.build renders each region from its first
position: a piece that lost its left part plays its texture restarted there,
one that lost its right part plays the same map, cut). Overlap is judged on
the display positions the board rounds to (texel.runtime.scene.to_position),
so regions that touch in positions are left alone, and every boundary is one
of the mm values the page sent. Pieces that round to no position are
dropped. Nothing left: the blank scene, one constant region at the board's
idle level over the whole display (a board always plays a scene of 1..16
regions; this plays what no scene would) - loaded back as no region.

Brush files: the folder `lab.brushes` when it is set (texelpad lab --brushes), else
DATA/brushes (made when missing). A name is NAME.json or NAME.tpb with NAME
as texelpad.study.session.check_name takes it (letters, digits, '_', '-'),
resolved inside that folder and nowhere else (a link out of it is refused).

Every request is checked whole before anything happens: a refused one (400,
the reason with the request's own path, regions[2].texture.design.level)
pushes nothing and writes no file; the board's own validation is the last
word; 503 when the board is gone (web/api.handle). "base" (the scene_id the
page edited) refuses a push when another page changed the board's scene
since: the editor sends the whole scene, and would otherwise silently
replace a study's scene playing for a participant. While a study session's
question plays, a push is refused (409, web/server.py Lab.claim_board)
whatever its base.

The painted scene is validated once on the host (link/board.py, check_scene):
Editor.paint (the request alone: no HTTP, no board) reads the regions,
resolves the overlaps and checks the scene of the pieces with
texelpad.link.board.check_scene; that CheckedScene goes through the owner
and Board.push unchecked, and its canonical form and positions are what the
answer and the strip show. A refusal answers as the request reads, region by
region (the first region whose own check - its texture over its own span,
check_one - fails, before anything found after it): each region is checked
on its own only then, or when the painting has no piece of it (covered by a
later one: not in the scene, still refused when bad).
tests/web/test_editor_push.py counts the checks.
"""
from __future__ import annotations

import base64
import hashlib
import json
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from starlette.requests import Request
from starlette.responses import FileResponse
from starlette.routing import Route

import texel
import texel.runtime.scene as _scene
from texel.runtime import kinds
from texel.gen import brush as B
from texel.gen import params

from ..brush import document as D
from ..link.board import CheckedScene, check_scene
from ..study.session import check_name
from . import strip as _strip
from .api import Refused, body_of, handle, keys

STATIC_DIR = Path(__file__).with_name("static")
SCENE_KEYS = {"regions", "name", "base"}
REGION_KEYS = {"start_mm", "end_mm", "texture"}
DESIGN_KEYS = {"shape", "level", "mean", "k"}
SAVE_KEYS = {"name", "design", "replace"}
BRUSH_SUFFIXES = (".json", ".tpb")
PAINT_MAX = 64              # regions in one request, in painting order (later ones cut)
BRUSH_FILE_MAX = 262144     # bytes: a brush is ~4 KB as JSON (document.py), 790 as .tpb
BRUSH_FILES_MAX = 200       # files listed by the palette
# designed brushes (document.design): the scale at wavenumber 4 and the mean
# are amplitudes (0..1 is the display's whole range; the painter clips a
# magnitude at 2.0: texel.gen.brush.MAG_CLIP), the shape k the board's own
# bounds (texel.gen.brush.K_MIN, K_MAX)
DESIGN_RANGES = {"level": (0.0, 1.0, 0.05), "mean": (0.0, 1.0, 0.5),
                 "k": (B.K_MIN, B.K_MAX, 2.0)}
KEPT_MAX = 32               # textures held for "kept" regions
LABELS_MAX = 256            # brush textures whose file or design is remembered
RENDERS_MAX = 64            # regions' renderings kept (<= 38 KB each: a full screen)


# --- small helpers ----------------------------------------------------------------------
def _is_num(v: Any) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, float)) and \
        (isinstance(v, int) or math.isfinite(v))


def _shown(v: Any) -> str:
    """A bounded description of an untrusted value (JSON, cut at 40 chars)."""
    try:
        s = json.dumps(v)
    except (TypeError, ValueError):
        s = type(v).__name__
    return s if len(s) <= 40 else s[:40] + "..."


def _norm(v: Any) -> Any:
    """v with floats as 9 significant digits and sequences as lists: the same
    fingerprint for a texture however its floats came back (the board's repr,
    the host's canonical form)."""
    if isinstance(v, float):
        return "%.9g" % v
    if isinstance(v, dict):
        return {str(k): _norm(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)) or (hasattr(v, "__len__") and hasattr(v, "__getitem__")
                                        and not isinstance(v, (str, bytes))):
        return [_norm(x) for x in v]
    return v


def fingerprint(v: Any) -> str:
    text = json.dumps(_norm(v), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _mm(v: Any, path: str, display: dict[str, Any]) -> float:
    """A region boundary: a finite number on the display (0 .. its length; a
    hair past the end that rounds onto the last position is the end, as
    texel.runtime.scene takes it)."""
    positions, dx = display["positions"], display["dx_um"]
    total = positions * dx / 1000.0
    if not _is_num(v) or v < 0 or v > total + 1.0 or \
            _scene.to_position(float(v), dx) > positions:
        raise Refused("%s: %s is off the display (a number of mm, 0 .. %g)"
                      % (path, _shown(v), total))
    return float(v)


# --- brush files --------------------------------------------------------------------------
def brush_folder(lab: Any) -> Path:
    """The brush files' folder: lab.brushes, else DATA/brushes; made when missing."""
    folder = getattr(lab, "brushes", None)
    folder = Path(folder) if folder is not None else Path(lab.data) / "brushes"
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def brush_path(folder: Path, name: Any, what: str = "file") -> Path:
    """NAME.json or NAME.tpb inside folder (NAME as check_name takes it);
    anything else - a path, '..', another suffix, a link out of the folder -
    is refused. The file need not exist."""
    if not isinstance(name, str) or "." not in name:
        raise Refused("%s: expected NAME.json or NAME.tpb (NAME: 1..40 letters, digits, "
                      "'_' or '-'), got %s" % (what, _shown(name)))
    stem, suffix = name.rsplit(".", 1)
    if "." + suffix not in BRUSH_SUFFIXES:
        raise Refused("%s: a brush file is NAME.json or NAME.tpb, got %s" % (what, _shown(name)))
    try:
        check_name(what, stem)
    except ValueError as e:
        raise Refused("%s (the brush file's name before .%s)" % (e, suffix)) from None
    root = folder.resolve()
    p = root / name
    if p.exists() and p.resolve().parent != root:
        raise Refused("%s: %s leads out of the brush folder" % (what, _shown(name)))
    return p


def load_brush(folder: Path, name: Any, what: str = "file") -> dict[str, Any]:
    p = brush_path(folder, name, what)
    if not p.is_file():
        raise Refused("%s: no brush %s in the brush folder" % (what, _shown(name)))
    if p.stat().st_size > BRUSH_FILE_MAX:
        raise Refused("%s: %s is over %d bytes: not a brush" % (what, name, BRUSH_FILE_MAX))
    try:
        return D.load(p)
    except (OSError, ValueError) as e:
        raise Refused("%s: %s" % (what, str(e).replace(str(p), name))) from None


def list_brushes(folder: Path) -> list[dict[str, Any]]:
    """Every NAME.json / NAME.tpb in the folder, checked; a broken one listed
    with the reason (as the lab lists a broken study config)."""
    out: list[dict[str, Any]] = []
    if not folder.is_dir():         # (removed while the lab runs: made again on a save)
        return out
    names = sorted(p.name for p in folder.iterdir()
                   if p.suffix in BRUSH_SUFFIXES and not p.name.startswith("."))
    for name in names[:BRUSH_FILES_MAX]:
        try:
            doc = load_brush(folder, name)
        except ValueError as e:
            out.append({"file": name, "error": str(e)})
            continue
        out.append({"file": name, "name": doc["name"], "source": doc["source"],
                    "range": doc["range"]})
    return out


def check_design(d: Any, path: str) -> dict[str, Any]:
    """{"shape": one of document.SHAPES, "level", "mean", "k"?} -> the same,
    complete (k defaults to 2: Rayleigh magnitudes)."""
    if not isinstance(d, dict):
        raise Refused("%s: expected {shape, level, mean, k?}, got %s" % (path, _shown(d)))
    bad = sorted(k for k in d if k not in DESIGN_KEYS)
    if bad:
        raise Refused("%s: unknown key %r (allowed: %s)" % (path, bad[0],
                                                             ", ".join(sorted(DESIGN_KEYS))))
    shape = d.get("shape")
    if not isinstance(shape, str) or shape not in D.SHAPES:
        raise Refused("%s.shape: expected one of %s, got %s"
                      % (path, ", ".join(D.SHAPES), _shown(shape)))
    out: dict[str, Any] = {"shape": shape}
    for key, (lo, hi, default) in DESIGN_RANGES.items():
        if key not in d:
            if key != "k":
                raise Refused("%s: missing required key %r (a number in [%g, %g])"
                              % (path, key, lo, hi))
            out[key] = default
            continue
        v = d[key]
        if not _is_num(v) or not lo <= v <= hi:
            raise Refused("%s.%s: expected a number in [%g, %g], got %s"
                          % (path, key, lo, hi, _shown(v)))
        out[key] = float(v)
    return out


def designed(d: dict[str, Any], path: str, name: str = "") -> dict[str, Any]:
    """The brush document of a checked design (document.design)."""
    try:
        return D.design(d["shape"], d["level"], d["mean"], d["k"], name=name)
    except ValueError as e:         # the board's bounds, by key path (brush.lam[96]: ...)
        raise Refused("%s: %s" % (path, e)) from None


def _design_label(d: dict[str, Any]) -> str:
    return "%s %g/%g" % (d["shape"], d["level"], d["mean"]) + \
        ("" if d["k"] == 2.0 else " k %g" % d["k"])


# --- what the editor remembers ------------------------------------------------------------
class Memory:
    """Per lab: which file or design each brush texture it pushed came from
    (to label the strip and load the scene back in the editor's form), and
    the textures of a loaded scene too large to send back ("kept"). Bounded;
    its own lock (the routes hold the lab's, this must not rely on it)."""

    def __init__(self) -> None:
        self.sources: OrderedDict[str, tuple[dict, str]] = OrderedDict()
        self.kept: OrderedDict[str, tuple[dict, str]] = OrderedDict()
        self._lock = threading.Lock()

    @staticmethod
    def _put(d: OrderedDict, k: str, v: Any, size: int) -> None:
        d[k] = v
        d.move_to_end(k)
        while len(d) > size:
            d.popitem(last=False)

    def remember(self, board_tex: dict[str, Any], editor_tex: dict[str, Any], label: str) -> None:
        # (a kept brush is kept again by the same id when the scene is loaded)
        if board_tex["kind"] == "brush" and editor_tex["kind"] != "kept":
            with self._lock:
                self._put(self.sources, fingerprint(board_tex), (editor_tex, label), LABELS_MAX)

    def source(self, board_tex: dict[str, Any]) -> tuple[dict, str] | None:
        with self._lock:
            return self.sources.get(fingerprint(board_tex))

    def keep(self, board_tex: dict[str, Any], label: str) -> str:
        k = fingerprint(board_tex)
        with self._lock:
            self._put(self.kept, k, (board_tex, label), KEPT_MAX)
        return k

    def kept_texture(self, k: Any) -> tuple[dict, str] | None:
        with self._lock:
            return self.kept.get(k) if isinstance(k, str) else None


# --- textures: the editor's form -> the board's ----------------------------------------
def label_of(tex: dict[str, Any], memory: Memory | None = None,
             dx_um: float = params.DX_MM * 1000) -> str:
    """A board texture in a few words (the strip's labels, the region list);
    dx_um: the display's position (a texel's length in mm)."""
    kind = tex["kind"]
    if kind == "texel":         # the editor's form gives a texel's length in mm: so does its label
        return "texel %.1f/%.1f dB, %.3g mm, seed %d" % (
            tex["pitch_db"], tex["irregularity_db"], tex["texel_samples"] * dx_um / 1000.0,
            tex["seed"])
    known = memory.source(tex) if memory is not None and kind == "brush" else None
    return known[1] if known else kinds.label_of(tex)       # the kind's own words


def resolve(tex: Any, path: str, folder: Path, memory: Memory,
            ) -> tuple[dict[str, Any], dict[str, Any], str]:
    """(the board's texture, the editor's form to send back, a label) of one
    texture of a request; Refused with the request's path."""
    if not isinstance(tex, dict):
        raise Refused("%s: expected a texture object with a kind, got %s" % (path, _shown(tex)))
    kind = tex.get("kind")
    if kind == "kept":
        bad = sorted(k for k in tex if k not in ("kind", "id"))
        if bad:
            raise Refused("%s: unknown key %r (allowed: id, kind)" % (path, bad[0]))
        held = memory.kept_texture(tex.get("id"))
        if held is None:
            raise Refused("%s.id: %s is not held any more (the server restarted or held too "
                          "many): reload the editor" % (path, _shown(tex.get("id"))))
        return held[0], {"kind": "kept", "id": tex["id"]}, held[1]
    if kind == "brush":
        given = [k for k in ("file", "design", "brush") if k in tex]
        if len(given) != 1:
            raise Refused("%s: a brush is exactly one of file (a brush file's name), design "
                          "({shape, level, mean, k?}) or brush ({k, lam, range})" % path)
        src = given[0]
        bad = sorted(k for k in tex if k not in ("kind", "seed", src))
        if bad:
            raise Refused("%s: unknown key %r (allowed: kind, %s, seed)" % (path, bad[0], src))
        seed = tex.get("seed", 0)
        if not _is_num(seed) or not isinstance(seed, int) or not 0 <= seed <= params.SEED_MAX:
            raise Refused("%s.seed: expected an int in [0, %d], got %s"
                          % (path, params.SEED_MAX, _shown(seed)))
        if src == "file":
            doc = load_brush(folder, tex["file"], path + ".file")
            numbers, editor = doc, {"kind": "brush", "file": tex["file"], "seed": seed}
            label = "brush %s, seed %d" % (tex["file"], seed)
        elif src == "design":
            d = check_design(tex["design"], path + ".design")
            numbers = designed(d, path + ".design")
            editor = {"kind": "brush", "design": d, "seed": seed}
            label = "brush %s, seed %d" % (_design_label(d), seed)
        else:
            numbers = tex["brush"]
            editor = None
            label = "brush, seed %d" % seed
        if src != "brush":          # a document: its numbers (its name and source stay here)
            numbers = {"k": numbers["k"], "lam": numbers["lam"], "range": numbers["range"]}
        try:                        # the board's own check, by key path
            board = B.region_texture(path, {"kind": "brush", "seed": seed, "brush": numbers})
        except ValueError as e:
            raise Refused(str(e)) from None
        return board, editor or board, label
    if kind in ("texel", "reference", "constant") or kind in forms():
        board = dict(tex)
        if kind == "texel" and "v" not in board:
            board["v"] = 2          # format 2: the same texture on every board (web/strip.py)
        return board, board, ""     # checked, labelled and made canonical by Editor.paint
    if kind == "samples":
        raise Refused("%s.kind: the editor paints brushes, texel textures, references and "
                      "constants; upload a map with texelpad push --scene" % path)
    raise Refused("%s.kind: expected one of %s, got %s"
                  % (path, ", ".join(("texel", "reference", "constant", "brush") + tuple(forms())),
                     _shown(kind)))


# the editor's own forms: brush (files and designs), texel (mm), reference, constant
HAND_MADE = ("brush", "texel", "reference", "constant")


def forms() -> dict[str, list[dict[str, Any]]]:
    """Every other region kind whose module describes its form (FIELDS:
    texel/runtime/kinds/__init__.py), as the page builds it: a new kind is
    in the editor without a line here or in editor.js."""
    out = {}
    for name in kinds.NAMES:
        fields = getattr(kinds.get(name), "FIELDS", None)
        if name in HAND_MADE or not fields:
            continue
        out[name] = [dict({"key": key, "type": t, "default": default, "label": label},
                          **({"words": list(lo)} if t == "word" else {"min": lo, "max": hi}))
                     for key, t, lo, hi, default, label in fields]
    return out


def check_one(i: int, start: float, end: float, board: dict[str, Any],
              display: dict[str, Any]) -> dict[str, Any]:
    """The board's validation of one region over its own span (its messages,
    renumbered to the request's region); the canonical texture. Editor.paint
    asks it of a region the painting has no piece of, and of each region in
    turn when something is refused (which one the refusal names)."""
    try:
        c = _scene.validate({"regions": [{"start_mm": start, "end_mm": end,
                                          "texture": board}]}, display)
    except ValueError as e:
        msg = str(e)
        if msg.startswith("regions[0]"):
            msg = "regions[%d]" % i + msg[len("regions[0]"):]
        raise Refused(msg) from None
    return c["regions"][0]["texture"]


# --- overlaps ------------------------------------------------------------------------------
def paint_order(regions: list[tuple[float, float, Any]],
                dx_um: float) -> list[tuple[float, float, Any]]:
    """Regions (start_mm, end_mm, payload) in painting order -> disjoint
    pieces sorted by start: a later region wins where it overlaps an earlier
    one, which keeps what is left of it (trimmed, split around the later one,
    or dropped). Judged on display positions (texel.runtime.scene.to_position:
    the board's own rounding); every boundary is one of the given mm values;
    pieces that round to no position are dropped."""
    pos = lambda mm: _scene.to_position(mm, dx_um)      # noqa: E731
    out: list[tuple[float, float, Any]] = []
    for s, e, item in regions:
        ps, pe = pos(s), pos(e)
        if ps >= pe:
            continue
        kept = []
        for a, b, other in out:
            pa, pb = pos(a), pos(b)
            if pb <= ps or pa >= pe:            # no shared position
                kept.append((a, b, other))
                continue
            if pa < ps:
                kept.append((a, s, other))      # what is left on the left
            if pb > pe:
                kept.append((e, b, other))      # ... and on the right
        kept.append((s, e, item))
        out = kept
    return sorted(out, key=lambda r: pos(r[0]))


# --- the strip, labelled ---------------------------------------------------------------------
class Renders:
    """The strip's rendering (web/strip.render: the board's own code), kept
    per region: what a region plays depends on its texture and its length
    only - every kind is rendered from the region's own start
    (texel.runtime.scene: a buffer or a plan indexed by pos - start, a
    brush painted over the region's length) - so an edit renders only the
    regions it made or trimmed, not every brush of the scene again (a
    full-screen brush is ~0.2 s of painting here). tests/web/test_editor.py
    checks the result against strip.render of the whole scene. Least
    recently used dropped beyond RENDERS_MAX regions."""

    def __init__(self) -> None:
        self._d: OrderedDict[str, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self.renders = 0            # regions rendered (the tests: an unchanged one is not)

    def region(self, tex: dict[str, Any], n: int, dx_um: float, idle: int) -> np.ndarray:
        key = fingerprint([tex, n, dx_um])
        with self._lock:
            hit = self._d.get(key)
            if hit is not None:
                self._d.move_to_end(key)
                return hit
        # the region alone on a display of its own length (n positions: n dx
        # rounds back to n, texel.runtime.scene.to_position)
        u16, _ = _strip.render({"regions": [{"start_mm": 0.0, "end_mm": n * dx_um / 1000.0,
                                             "texture": tex}]},
                               {"positions": n, "dx_um": dx_um}, idle)
        with self._lock:
            self.renders += 1
            self._d[key] = u16
            while len(self._d) > RENDERS_MAX:
                self._d.popitem(last=False)
        return u16

    def get(self, canonical: dict[str, Any] | None, display: dict[str, Any],
            idle: int, where: Any = None) -> tuple[str, np.ndarray, list]:
        """(scene_id, the uint16 amplitude at every position, [(start, end,
        texture)] in positions as the board rounds them). where: the
        canonical regions' positions when the host's check of it gave them
        (CheckedScene.spans), else they are found here (scene.check)."""
        out = np.full(display["positions"], idle, dtype=np.uint16)
        spans: list = []
        if canonical is not None:
            if where is None:
                c, where, _, dx = _scene.check(canonical, display)
            else:
                c, dx = canonical, float(display["dx_um"])
            for r, (s, e) in zip(c["regions"], where):
                out[s:e] = self.region(r["texture"], e - s, dx, idle)
                spans.append((s, e, r["texture"]))
        return scene_id(canonical, display, idle), out, spans


def scene_id(canonical: dict[str, Any] | None, display: dict[str, Any], idle: int) -> str:
    """What plays, as an id: the canonical scene (floats to 9 digits: the
    same whether it came back from the board or from the host's check), the
    display and the idle amplitude."""
    return fingerprint([canonical, display["positions"], display["dx_um"], idle])


def strip_answer(renders: Renders, memory: Memory, st: dict[str, Any],
                 canonical: dict[str, Any] | None,
                 checked: CheckedScene | None = None) -> dict[str, Any]:
    """GET /api/strip's answer (web/strip.strip_answer) with the editor's
    labels: a brush region names its file or design. checked: the scene
    just pushed, whose positions are known when `canonical` is its
    canonical form (the board took it as it was checked)."""
    display = {"positions": st["display"]["positions"], "dx_um": st["display"]["dx_um"]}
    idle = _strip.idle_of(st)
    where = checked.spans if checked is not None and checked.canonical is canonical \
        and checked.fits(display) else None
    sid, u16, spans = renders.get(canonical, display, idle, where)
    dx = display["dx_um"]
    return dict(_strip.status_fields(st, display, idle),
                amplitude=base64.b64encode(_strip.to_u8(u16).tobytes()).decode("ascii"),
                regions=[{"start_mm": round(s * dx / 1000.0, 4),
                          "end_mm": round(e * dx / 1000.0, 4),
                          "label": label_of(tex, memory, dx)} for s, e, tex in spans],
                name=canonical.get("name") if canonical else None, scene_id=sid)


def blank(display: dict[str, Any], idle: int, name: str | None) -> dict[str, Any]:
    """The scene of no region: the board's idle level over the whole display."""
    total = round(display["positions"] * display["dx_um"] / 1000.0, 6)
    return {"regions": [{"start_mm": 0.0, "end_mm": total,
                         "texture": {"kind": "constant", "level": idle / 65535.0}}],
            "name": name or "blank"}


def is_blank(canonical: dict[str, Any], display: dict[str, Any], idle: int) -> bool:
    regs = canonical.get("regions") or []
    if len(regs) != 1 or regs[0]["texture"]["kind"] != "constant":
        return False
    r, dx = regs[0], display["dx_um"]
    return (_scene.to_position(r["start_mm"], dx) == 0
            and _scene.to_position(r["end_mm"], dx) >= display["positions"]
            and int(r["texture"]["level"] * 65535.0 + 0.5) == idle)


def editor_regions(canonical: dict[str, Any] | None, display: dict[str, Any], idle: int,
                   memory: Memory) -> list[dict[str, Any]]:
    """The playing scene in the editor's form: a brush the editor pushed
    names its file or design again; an uploaded map and a brush of unknown
    origin are kept here by id."""
    if canonical is None or is_blank(canonical, display, idle):
        return []
    out = []
    for r in canonical["regions"]:
        tex = r["texture"]
        known = memory.source(tex) if tex["kind"] == "brush" else None
        if known:
            editor, label = known
        elif tex["kind"] in ("brush", "samples"):
            label = label_of(tex, memory, display["dx_um"]) + " (as loaded)"
            editor = {"kind": "kept", "id": memory.keep(tex, label)}
        else:
            editor, label = tex, label_of(tex, dx_um=display["dx_um"])
        out.append({"start_mm": r["start_mm"], "end_mm": r["end_mm"], "texture": editor,
                    "label": label})
    return out


# --- the editor: a request painted, pushed -------------------------------------------------
@dataclass(frozen=True)
class Order:
    """A POST /api/editor/scene body, its shape checked (read_order): the
    regions in painting order (each read by Editor.paint), the scene's name,
    the scene_id the page edited."""
    regions: list
    name: str | None
    base: str | None


def read_order(body: Any) -> Order:
    keys(body, SCENE_KEYS)
    regs = body.get("regions")
    if not isinstance(regs, list) or len(regs) > PAINT_MAX:
        raise Refused("regions: expected a list of at most %d regions in painting order "
                      "(a later one wins where they overlap), got %s" % (PAINT_MAX, _shown(regs)))
    name = body.get("name")
    if name is not None and (not isinstance(name, str) or not 1 <= len(name) <=
                             _scene.NAME_MAX):
        raise Refused("name: expected a string of 1 .. %d characters, got %s"
                      % (_scene.NAME_MAX, _shown(name)))
    base = body.get("base")
    if base is not None and not isinstance(base, str):
        raise Refused("base: expected the scene_id the page edited, got %s" % _shown(base))
    return Order(regs, name, base)


# A region read from a request: (start_mm, end_mm, (its index in the request,
# the board's texture, the editor's form to send back, its label))
Read = tuple[float, float, tuple[int, dict, dict, str]]


@dataclass(frozen=True)
class Painting:
    """What Editor.paint made of a request: `pieces`, the regions left after
    the overlaps (Read tuples, sorted by start; the editor's form and label
    of a texel, reference or constant are its canonical form's); `scene`,
    the scene of those pieces as the host's one check made it (link.board.
    check_scene), None when no piece is left (the blank scene: the board's
    idle level, which the board's status tells, not the request)."""
    pieces: list[Read]
    name: str | None
    scene: CheckedScene | None

    def regions(self) -> list[dict[str, Any]]:
        """The pieces as the answer lists them."""
        return [{"start_mm": s, "end_mm": e, "texture": t[2], "label": t[3], "from": t[0]}
                for s, e, t in self.pieces]


class Editor:
    """The scene editor of one lab: its brush folder, what it remembers
    (Memory, Renders), and what each route does. paint() is the request's
    painting alone (no HTTP, no board); push() claims the board, checks the
    page's base, plays the painting and answers."""

    def __init__(self, lab: Any) -> None:
        self.lab = lab
        self.folder = brush_folder(lab)
        self.memory, self.renders = Memory(), Renders()

    # --- what plays --------------------------------------------------------------------
    def palette(self) -> dict[str, Any]:
        display = self.lab.owner.display()
        texel_spec = {}
        for k in ("pitch_db", "irregularity_db", "texel_samples", "seed"):
            kind, default, lo, hi = params.SPEC[k]
            texel_spec[k] = {"kind": "int" if kind == "i" else "number", "default": default,
                             "min": lo, "max": hi}
        return {"references": texel.reference_names(),
                "brushes": list_brushes(self.folder),
                "brush_folder": str(self.folder),
                "shapes": {name: {"slope_db_per_octave": s} for name, s in D.SHAPES.items()},
                "design": {k: {"min": lo, "max": hi, "default": d}
                           for k, (lo, hi, d) in DESIGN_RANGES.items()},
                "texel": texel_spec,
                "display": {"positions": display["positions"], "dx_um": display["dx_um"],
                            "length_mm": round(display["positions"] * display["dx_um"]
                                               / 1000.0, 6)},
                "max_regions": _scene.MAX_REGIONS,
                "forms": forms()}

    def scene(self) -> dict[str, Any]:
        """The playing scene in the editor's form, its scene_id and strip."""
        st, canonical = self.lab.owner.playing()
        display = {"positions": st["display"]["positions"], "dx_um": st["display"]["dx_um"]}
        strip = strip_answer(self.renders, self.memory, st, canonical)
        return {"regions": editor_regions(canonical, display, _strip.idle_of(st), self.memory),
                "name": canonical.get("name") if canonical else None,
                "scene_id": strip["scene_id"], "strip": strip}

    def strip(self) -> dict[str, Any]:
        return strip_answer(self.renders, self.memory, *self.lab.owner.playing())

    # --- painting ------------------------------------------------------------------------
    def paint(self, body: Any, display: dict[str, Any]) -> Painting:
        """A request (its body, or the Order read from it) painted on
        `display`: every region read and its texture resolved (a brush file
        read, a design made), the overlaps resolved (paint_order), and the
        scene of the pieces checked once (check_scene: the board's own
        validation). No HTTP, no board. Refused (400) as the request reads,
        region by region: the first region whose own check fails (its
        texture over its own span: check_one, the request's paths) before
        anything found after it - so a region is checked on its own only
        when the painting has no piece of it (covered by later ones, or
        rounding to no position) or something was refused."""
        order = body if isinstance(body, Order) else read_order(body)
        read: list[Read] = []
        try:
            for i, r in enumerate(order.regions):
                read.append(self._read(i, r, display))
            pieces = paint_order(read, display["dx_um"])
            if len(pieces) > _scene.MAX_REGIONS:
                raise Refused("regions: painting these gives %d regions; a board plays at most "
                              "%d (remove some, or paint over several at once)"
                              % (len(pieces), _scene.MAX_REGIONS))
            kept = {t[0] for _, _, t in pieces}
            for s, e, (i, board, _, _) in read:
                if i not in kept:       # not in the scene: checked alone (refused anywhere)
                    check_one(i, s, e, board, display)
        except Refused:
            _first_refusal(read, display)
            raise
        if not pieces:
            return Painting([], order.name, None)
        scene: dict[str, Any] = {"regions": [{"start_mm": s, "end_mm": e, "texture": t[1]}
                                             for s, e, t in pieces]}
        if order.name is not None:
            scene["name"] = order.name
        try:
            checked = check_scene(scene, display)
        except ValueError as err:
            _first_refusal(read, display)
            raise Refused("the painted scene: %s" % err) from None
        return Painting(_canonical_forms(pieces, checked), order.name, checked)

    def _read(self, i: int, r: Any, display: dict[str, Any]) -> Read:
        """Region i of a request: its span (mm on the display) and its
        texture resolved; Refused with the request's path."""
        path = "regions[%d]" % i
        if not isinstance(r, dict):
            raise Refused("%s: expected {start_mm, end_mm, texture}, got %s" % (path, _shown(r)))
        bad = sorted(k for k in r if k not in REGION_KEYS)
        if bad:
            raise Refused("%s: unknown key %r (allowed: end_mm, start_mm, texture)"
                          % (path, bad[0]))
        for k in REGION_KEYS:
            if k not in r:
                raise Refused("%s: missing required key %r" % (path, k))
        s = _mm(r["start_mm"], path + ".start_mm", display)
        e = _mm(r["end_mm"], path + ".end_mm", display)
        if not s < e:
            raise Refused("%s.end_mm: %g is not after start_mm %g" % (path, e, s))
        board, editor, label = resolve(r["texture"], path + ".texture", self.folder, self.memory)
        return s, e, (i, board, editor, label)

    # --- pushing -------------------------------------------------------------------------
    def push(self, body: Any) -> dict[str, Any]:
        order = read_order(body)        # (a body of the wrong shape: 400 before the board is asked)
        owner = self.lab.owner
        display = owner.display()
        painting = self.paint(order, display)
        claim = getattr(self.lab, "claim_board", None)  # a study's scene is not replaced: 409
        if claim is not None:
            claim("the editor")
        # the board's idle level: to name what plays (base) or to play it (nothing left)
        idle = _strip.idle_of(owner.status()) \
            if order.base is not None or painting.scene is None else 0
        if order.base is not None:
            now = scene_id(owner.scene_source(), display, idle)
            if now != order.base:
                raise Refused("base: the board's scene changed since this page loaded it "
                              "(another page pushed one): reload the editor to edit what "
                              "plays now")
        checked = painting.scene or _blank_checked(display, idle, order.name)
        st, canonical = owner.push(checked)
        for _, _, (i, board, editor, label) in painting.pieces:
            self.memory.remember(board, editor, label)
        strip = strip_answer(self.renders, self.memory, st, canonical, checked)
        return {"regions": painting.regions(), "name": canonical.get("name"),
                "scene_id": strip["scene_id"], "scene": canonical, "status": st, "strip": strip}

    # --- brush files ---------------------------------------------------------------------
    def save_brush(self, body: Any) -> dict[str, Any]:
        keys(body, SAVE_KEYS)
        name = body.get("name")
        if isinstance(name, str) and "." not in name:
            name += ".json"
        p = brush_path(self.folder, name, "name")
        d = check_design(body.get("design"), "design")
        replace = body.get("replace", False)
        if not isinstance(replace, bool):
            raise Refused("replace: expected true or false, got %s" % _shown(replace))
        if (p.exists() or p.is_symlink()) and not replace:
            raise Refused("name: %s exists in the brush folder (send \"replace\": true to "
                          "overwrite it)" % p.name)
        doc = designed(d, "design", name=p.name.rsplit(".", 1)[0])
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            D.save(doc, p)              # beside and renamed: never half a brush
        except OSError as e:
            p.with_name(p.name + ".tmp").unlink(missing_ok=True)
            raise Refused("name: could not write %s in the brush folder: %s"
                          % (p.name, e.strerror or e)) from None
        return {"saved": p.name, "design": d, "brushes": list_brushes(self.folder)}


def _first_refusal(read: list[Read], display: dict[str, Any]) -> None:
    """Each region read so far checked on its own, in the request's order:
    the first refusal raised (what a refused request answers: the first
    region whose own check fails comes before anything found after it)."""
    for s, e, (i, board, _, _) in read:
        check_one(i, s, e, board, display)


def _canonical_forms(pieces: list[Read], checked: CheckedScene) -> list[Read]:
    """The pieces with the canonical texture of a texel, reference or
    constant (the host's check's; the canonical regions are the pieces, in
    the same order: both sorted by start) as the board's texture, the
    editor's form (a kept one stays kept) and the label's source; a brush
    keeps its editor's form (its file or design) and label."""
    out = []
    for (s, e, (i, board, editor, label)), r in zip(pieces, checked.canonical["regions"]):
        canon = r["texture"]
        if canon["kind"] != "brush":
            board = canon
            if editor["kind"] != "kept":
                editor = canon
            label = label or label_of(canon, dx_um=checked.display["dx_um"])
        out.append((s, e, (i, board, editor, label)))
    return out


def _blank_checked(display: dict[str, Any], idle: int, name: str | None) -> CheckedScene:
    try:
        return check_scene(blank(display, idle, name), display)
    except ValueError as err:
        raise Refused("the painted scene: %s" % err) from None


# --- the routes -------------------------------------------------------------------------------
def routes(lab: Any) -> list[Route]:
    editor = lab.editor = Editor(lab)

    async def page(request: Request) -> FileResponse:
        return FileResponse(STATIC_DIR / "editor.html", media_type="text/html")

    def no_query(request: Request) -> None:
        if request.query_params:
            raise Refused("GET %s takes no parameters" % request.url.path)

    def getter(fn: Any) -> Any:
        def get(request: Request) -> dict[str, Any]:
            no_query(request)
            return fn()
        return handle(lab.lock, get)

    def poster(fn: Any) -> Any:
        return handle(lab.lock, lambda request: fn(body_of(request)))

    return [Route("/editor", page),
            Route("/api/editor/palette", getter(editor.palette)),
            Route("/api/editor/scene", getter(editor.scene)),
            Route("/api/editor/scene", poster(editor.push), methods=["POST"]),
            Route("/api/editor/strip", getter(editor.strip)),
            Route("/api/editor/brushes", poster(editor.save_brush), methods=["POST"])]
