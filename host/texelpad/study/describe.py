"""`texelpad lab describe CONFIG`: a study's full trial list before anyone runs
it - what plays on each part of the display in each trial, the order, the
seeds - so a researcher can check a design (and preregister it).

    d = describe("quant-paper", seed=5)          # a dict, JSON-friendly
    print(render_text(d))                        # the table a human reads

Everything here comes from the protocols themselves (the same state machines
and questions.ask / scenes the lab plays), started from the config as the
lab's server starts a session (web/server.py Lab.create: the config file's
"config", its name as config_file, the reference, texture_format). Fixed
designs (free, quant, mapping) are listed trial by trial exactly. Adaptive
ones (pursuit, staircase, search) list what the seed fixes for every trial
and the first question exactly, with the rule for what the answers change.

A display sample array (a rater's logged rendering, a band-pass reference:
9,600 values) is named, not listed: {"kind": "samples", "values": 9600,
"what": "..."}. Pure logic: no link, no web.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from texel.runtime.boards import DX_UM_MAX, POSITIONS_MAX

from . import configs as C
from . import protocols
from . import scenes as S
from .session import SessionError

# the TPaD of seeds 000 and 001: 19,200 positions of 5.3 um (texel.runtime.boards)
TPAD_DISPLAY: dict[str, Any] = {"positions": 19200, "dx_um": 5.3}
# staircase trials listed (its length depends on the answers: the simulated participant with
# a 3 mm threshold, texelpad.study.participant, needs a median 61 trials, 95th percentile 72,
# at most 83 over seeds 0..199; each trial's seeds depend on the session's seed and the
# trial's number only, so the list is what any run plays up to here)
STAIRCASE_LISTED = 150


# --- the config ---------------------------------------------------------------------

def load(name_or_config: Any, configs_dir: str | Path | None = None
         ) -> tuple[str, dict[str, Any]]:
    """(name, config file object): a shipped or configs_dir config's name, a
    path to a config .json file, or the object itself. SessionError says why
    not (an unknown name, a file that is missing, not JSON or not a config)."""
    if isinstance(name_or_config, dict):
        return "(given)", C.check("(given)", dict(name_or_config))
    if not isinstance(name_or_config, str) or not name_or_config:
        raise SessionError("config: expected a config's name or a .json file, got %r"
                           % (name_or_config,))
    path = Path(name_or_config)
    if name_or_config.endswith(".json") or "/" in name_or_config:
        if not path.is_file():
            raise SessionError("config %s: no such file" % path)
        if path.stat().st_size > C.FILE_MAX:
            raise SessionError("config %s: over %d bytes" % (path, C.FILE_MAX))
        try:
            obj = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as e:
            raise SessionError("config %s: not a JSON config (%s)" % (path, str(e)[:120])) \
                from None
        cf = C.check(path.stem, obj)
        return path.stem, dict(cf, file=str(path))
    return name_or_config, C.load(name_or_config, configs_dir)


def header_config(name: str, cf: dict[str, Any]) -> dict[str, Any]:
    """The "config" a session's header records when the lab starts this
    config (web/server.py Lab.create): the file's config, its name, the
    reference (the pursuit's and the search's, 4sin by default) and the
    texture format (2 unless it says 1)."""
    config = dict(cf.get("config", {}))
    config["config_file"] = name
    if protocols.get(cf["protocol"]).REFERENCE_CHOSEN:
        config["reference"] = cf.get("reference") or dict(S.DEFAULT_REFERENCE)
    config["texture_format"] = S.texture_format(config)
    return config


def full_config(proto: str, state: Any, header: dict[str, Any]) -> dict[str, Any]:
    """Every choice field: what a session's header records
    (protocols.resolved: the Config's fields, defaults included, and the
    scenes' keys), plus the search's own fields and the staircase's stimulus
    as it plays (JSON: tuples as lists): the protocol's full_config."""
    return protocols.get(proto).full_config(state, header)


def parse_display(text: str) -> dict[str, Any]:
    """"positions" or "positions,dx_um" (e.g. 19200,5.3) -> a display dict;
    ValueError names the value and the range."""
    parts = [p.strip() for p in str(text).split(",")]
    if not 1 <= len(parts) <= 2:
        raise ValueError("display: expected positions[,dx_um], got %r" % (text,))
    try:
        n = int(parts[0])
        dx = float(parts[1]) if len(parts) == 2 else TPAD_DISPLAY["dx_um"]
    except ValueError:
        raise ValueError("display: expected positions[,dx_um] (numbers), got %r"
                         % (text,)) from None
    if not 1 <= n <= POSITIONS_MAX:
        raise ValueError("display: positions must be 1 .. %d, got %d" % (POSITIONS_MAX, n))
    if not 0 < dx <= DX_UM_MAX:
        raise ValueError("display: dx_um must be in (0, %g], got %r" % (DX_UM_MAX, dx))
    return {"positions": n, "dx_um": dx}


# --- scenes as text: study/describing.py (scene); each protocol's trials: study/protocols ---


def describe(name_or_config: Any, seed: int | None = None,
             display: dict[str, Any] | None = None, configs_dir: str | Path | None = None,
             staircase_trials: int = STAIRCASE_LISTED) -> dict[str, Any]:
    """The study's full trial list (module docstring). seed None: the
    config's seed; a config without one has its session's seed drawn at
    start, and seed 0 is described (said in "seed_source")."""
    name, cf = load(name_or_config, configs_dir)
    if seed is None:
        seed = cf.get("seed")
        source = "the config's" if seed is not None else \
            "none given: a session's seed is drawn at its start; seed 0 described"
        seed = seed or 0
    else:
        source = "given"
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 1 << 31:
        raise SessionError("seed: expected an int in [0, 2^31), got %r" % (seed,))
    display = dict(display or TPAD_DISPLAY)
    proto = cf["protocol"]
    hc = header_config(name, cf)
    header = {"protocol": proto, "config": hc, "seed": seed}
    state = protocols.start(proto, hc, seed)
    config = full_config(proto, state, hc)
    p = protocols.get(proto)
    body = p.trials(state, header, display, staircase_trials)
    fixed = p.FIXED
    for k, t in enumerate(body["trials"]):
        t["question"] = k + 1           # the answers before it, plus one
    return {"config_name": name, "file": cf.get("file"), "protocol": proto,
            "title": cf.get("title", protocols.TITLES[proto]), "note": cf.get("note"),
            "seed": seed, "seed_source": source, "display": display, "config": config,
            "design": "fixed" if fixed else "adaptive", "trials": body["trials"],
            "trial_count": len(body["trials"]) if fixed else None, "rules": body["rules"]}


# --- the text --------------------------------------------------------------------------

def texture_text(t: dict[str, Any]) -> str:
    """One texture as a short line."""
    kind = t.get("kind")
    if kind == "reference":
        return "reference %s" % t.get("name")
    if kind == "samples":
        return "samples: %s (%s values)" % (t.get("what"), format(t.get("values", 0), ","))
    if kind == "constant":
        return "constant level %g" % t.get("level", 0)
    parts = [t["what"]] if "what" in t else []
    if isinstance(t.get("pitch_db"), (int, float)):
        parts.append("pitch %.3f dB, irregularity %.3f dB" % (t["pitch_db"],
                                                               t["irregularity_db"]))
    for key, fmt in (("texel_samples", "%s-sample texels"), ("quant_db", "q %s dB"),
                     ("min_cpmm", "above %s c/mm"), ("phase", "phase %s"),
                     ("gain", "gain %s"), ("seed", "seed %s"), ("v", "format %s")):
        if t.get(key) is not None and not (key == "quant_db" and not t[key]):
            parts.append(fmt % (t[key],))
    return "texel: " + ", ".join(parts)


def _trial_title(d: dict[str, Any], t: dict[str, Any]) -> str:
    keys = [k for k in ("phase", "reference", "move", "match_of", "source", "quant_db",
                        "direction",
                        "A", "B", "seeds", "odd", "length_mm", "A_db", "B_db")
            if k in t]
    head = "question %d%s" % (t["question"], " of %d" % d["trial_count"]
                              if d["trial_count"] else "")
    if "iteration" in t:
        head += " (iteration %d)" % (t["iteration"] + 1)
    else:
        head += " (trial %d%s)" % (t["trial"] + 1, ".%d" % (t["index"] + 1)
                                   if "index" in t else "")
    return head + ": " + ", ".join("%s %s" % (k, json.dumps(t[k])) for k in keys)


def render_text(d: dict[str, Any]) -> str:
    """The description as a table a human reads."""
    lines = ["%s (%s): %s" % (d["config_name"], d["protocol"], d["title"]),
             "seed %d (%s); display %s positions x %g um" % (
                 d["seed"], d["seed_source"], format(d["display"]["positions"], ","),
                 d["display"]["dx_um"]),
             "config: " + json.dumps(d["config"], sort_keys=True)]
    if d.get("note"):
        lines.append("note: " + d["note"])
    lines.append("%s design: %s" % (d["design"], "%d trials" % d["trial_count"]
                                    if d["trial_count"] else "the seed's part of every trial "
                                    "and the first question exactly"))
    lines += ["rule: " + r for r in d["rules"]]
    lines.append("")
    for t in d["trials"]:
        lines.append(_trial_title(d, t))
        for o in t.get("options", []):
            if "regions" not in o:
                lines.append("    %-10s %-13s %23s  %s, seed %s, format %s"
                             % (o["option"], o["where"], "", o["depends"], o["seed"], o["v"]))
                continue
            for r in o["regions"]:
                lines.append("    %-10s %-13s %8.3f .. %8.3f mm  %s"
                             % (o["option"][:10], r["where"], r["start_mm"], r["end_mm"],
                                texture_text(r["texture"])))
        if "answer" in t:
            lines.append("    answer: %s" % t["answer"])
    return "\n".join(lines) + "\n"
