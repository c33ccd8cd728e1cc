"""Make texelpad-session/2 quant files with texelpad as it was before the rater's
pitch file was relabelled (commit 882b9d3, checked out at /tmp/v2head:
`git worktree add /tmp/v2head 882b9d3`, then
`.venv/bin/python tests/study/data/legacy/make_v2.py /tmp/v2out`): every trial of
the paper's quantization design with the rater's rows as they were then read -
'by_texture' (assigned by statistics) and 'app' (by index), in the seeded and
the app's order. Each answer record holds the scene the question played."""
import sys
from pathlib import Path
sys.path[:0] = ["/tmp/v2head/host", "/tmp/v2head/device"]
from texelpad.study import protocols, questions as Q
from texelpad.study.quant import LAB_EXEMPLARS
from texelpad.study.session import Session

NINE = ("2sin", "3sin", "4sin", "white", "pink", "blue", "square", "triangle", "sawtooth")
OWN = {r: {"pitch_db": 1.0 + i, "irregularity_db": -12.0 + i / 2, "seed": 100 + i,
           "texel_samples": 50, "v": 2} for i, r in enumerate(NINE)}
OUT = Path(sys.argv[1])
DISPLAY = {"positions": 19200, "dx_um": 5.3}
RUNS = (("quant-v2-by-texture", 13, {}),
        ("quant-v2-app-lab", 17, {"order": "lab", "exemplars": list(LAB_EXEMPLARS),
                                  "rater_rows": "app"}))
for name, seed, extra in RUNS:
    config = dict({"matches": OWN, "config_file": name}, **extra)
    state = protocols.start("quant", config, seed)
    full = protocols.resolved("quant", state, dict(config, texture_format=2))
    s = Session.create(OUT, "quant", "legacy", full, seed)
    header = s.header
    k = 0
    while not state.done:
        q = Q.ask("quant", state, header, DISPLAY)
        a = 1 + (k * 7) % 5
        s.append({"question": q.public, "answer": a, "scene": q.options[0], "playing": 0,
                  "state": q.detail})
        protocols.apply("quant", state, a)
        k += 1
    print(name, s.path, k)
    # the rater's renderings are 9,600 samples each: the fixture keeps their digest
    # (tests/study/test_legacy_sessions.py digests the scene it replays the same way)
    import hashlib, json
    lines = s.path.read_text().splitlines()
    out = [lines[0]]
    for line in lines[1:]:
        rec = json.loads(line)
        for reg in rec["scene"].get("regions", []):
            tex = reg.get("texture", reg)
            if "u16" in tex:
                tex["u16"] = "sha256:" + hashlib.sha256(
                    json.dumps(tex["u16"]).encode()).hexdigest()
        out.append(json.dumps(rec, separators=(",", ":")))
    dest = Path(__file__).resolve().parent / (name + ".jsonl")
    dest.write_text("\n".join(out) + "\n")
    print("wrote", dest)
