"""Session files written before the protocols followed the papers (issue 20;
header format "texelpad-session/1") replay as they ran: a /1 header's config
lacks the fields added since, and their defaults changed to the papers'
designs, so reading such a header fills in the OLD defaults (never a field
it has). Headers written since (format /2) hold every field of the
protocol's resolved Config (protocols.resolved), so nothing needs filling.

The fixtures in tests/study/data/legacy/ were made by texelpad before the
change (commit 9ec54e9, tests/study/data/legacy/make_legacy.py); the test
replays them question by question and checks every scene. Pure logic.
"""
from __future__ import annotations

import copy
from typing import Any

OLD_FORMAT = "texelpad-session/1"
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
    """The header as the protocols read it: a /1 header with the old defaults
    filled in (a copy; the file is never rewritten), any other as it is."""
    if header.get("format") != OLD_FORMAT:
        return header
    out = copy.deepcopy(header)
    config = out.setdefault("config", {})
    if not isinstance(config, dict):
        return out                      # (protocols.start says what is wrong with it)
    for key, value in OLD_DEFAULTS.get(str(out.get("protocol")), {}).items():
        config.setdefault(key, copy.deepcopy(value))
    out["legacy"] = True                # (a /1 session: the old defaults filled in)
    return out
