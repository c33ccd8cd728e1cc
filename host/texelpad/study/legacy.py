"""Session files written by older texelpads replay as they ran.

- Format "texelpad-session/1" (before the protocols followed the papers,
  issue 20): a /1 header's config lacks the fields added since, and their
  defaults changed to the papers' designs, so reading such a header fills in
  the OLD defaults (never a field it has).
- Format "texelpad-session/2" (before the trained rater's pitch file was
  relabelled, 2026-11-28; ../shared/golden/README.md): its quantization
  sessions read the rater's rows by their statistics, which swapped square's
  and triangle's renderings (identical matches), and its rater_rows "app"
  paired reference k with data row k; the app's reference rows were read in
  the family order. Reading such a header turns its rater_rows into what
  played (study/rater.py LEGACY_ROWS) and fills in lab_rows "family_order".
- Format "texelpad-session/3" (before the protocols took the lab's apps'
  ways as defaults where they differed, issue 31): its headers hold every
  field of the protocol's resolved Config as it was, so only the fields added
  since are missing; reading fills in what played (ADDED_SINCE_V3: the
  similarity matrix on a split display in a seeded order, the pursuit's
  points above Nyquist clamped, no finger recorded in a staircase, the
  search's update cma's active one and no friction slider). Every older format gets the same fills.
Headers written since (format /4) hold every field of the protocol's
resolved Config (protocols.resolved), so nothing needs filling.

The fixtures in tests/study/data/legacy/ were made by the old code
(make_legacy.py: commit 9ec54e9, format /1; make_v2.py: commit 882b9d3,
format /2); the test replays them question by question and checks every
scene. Pure logic.
"""
from __future__ import annotations

import copy
from typing import Any

OLD_FORMAT = "texelpad-session/1"
V2_FORMAT = "texelpad-session/2"
V3_FORMAT = "texelpad-session/3"
OLD_FORMATS = (OLD_FORMAT, V2_FORMAT, V3_FORMAT)
# per protocol: the fields added after format /3 and what every older session played
# (their defaults changed to the lab's apps' ways, docs/lab.md "As the papers ran them")
ADDED_SINCE_V3: dict[str, dict[str, Any]] = {
    "quant": {"order": "seeded", "presentation": "split"},
    "pursuit": {"above_nyquist": "clamp"},
    "staircase": {"finger_hz": 0},          # (no finger was recorded)
    "search": {"cma_update": "active", "level_slider": False},     # (cma's default, no slider)
}
# /1 and /2 quantization sessions: what their rater_rows played (study/rater.py)
V2_RATER_ROWS = {"by_texture": "statistics-2026", "app": "index-2026"}
# per protocol: the field and what a /1 session played when its config did not say
OLD_DEFAULTS: dict[str, dict[str, Any]] = {
    "free": {"irregularity_slider": "db", "start": [5.0, -15.0], "texel_samples": 47,
             "confidence_input": "buttons"},
    "quant": {"design": "levels", "texel_samples": 47, "rating": "buttons"},
    "pursuit": {"presentation": "split", "fresh": False},
    "staircase": {"whole_texels": False,
                  "distribution": {"pitch_db": 10.0, "irregularity_db": -10.0}},
}


def effective_header(header: dict[str, Any]) -> dict[str, Any]:
    """The header as the protocols read it: a /1 or /2 header with what it
    ran filled in (a copy; the file is never rewritten), any other as it is."""
    if header.get("format") not in OLD_FORMATS:
        return header
    out = copy.deepcopy(header)
    config = out.setdefault("config", {})
    if not isinstance(config, dict):
        return out                      # (protocols.start says what is wrong with it)
    if out.get("format") == OLD_FORMAT:
        for key, value in OLD_DEFAULTS.get(str(out.get("protocol")), {}).items():
            config.setdefault(key, copy.deepcopy(value))
    for key, value in ADDED_SINCE_V3.get(str(out.get("protocol")), {}).items():
        config.setdefault(key, copy.deepcopy(value))
    if out.get("format") == V3_FORMAT:
        out["legacy"] = True
        return out
    if out.get("protocol") == "quant":
        rows = config.get("rater_rows", "by_texture")
        config["rater_rows"] = V2_RATER_ROWS.get(rows, rows) if isinstance(rows, str) else rows
        config.setdefault("lab_rows", "family_order")
    out["legacy"] = True                # (an older session: what it ran filled in)
    return out
