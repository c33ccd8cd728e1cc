"""Make texelpad-session/3 files with texelpad as it was before issue 31 made the
lab's apps' ways the defaults (commit 8c349e6, checked out at /tmp/v3head:
`git worktree add /tmp/v3head 8c349e6`, then
`.venv/bin/python tests/study/data/legacy/make_v3.py /tmp/v3out`): the shipped
similarity matrix (split display, a seeded order, 47-sample texels as the config
said then), a pursuit of sawtooth whose answers always pick the higher pitch,
so its points pass Nyquist (19.747 dB) and were clamped, and a search of 4sin
(cma's active update, no friction slider). `make_v3.py OUT NAME...` writes only
those. Each answer record holds
every scene the question offered."""
import sys
from pathlib import Path
sys.path[:0] = ["/tmp/v3head/host", "/tmp/v3head/device"]
from texelpad.study import configs, protocols, questions as Q
from texelpad.study.session import Session

OUT = Path(sys.argv[1])
DISPLAY = {"positions": 19200, "dx_um": 5.3}


def higher(q):
    a, b = q.detail["A"]["pitch_db"], q.detail["B"]["pitch_db"]
    return "A" if a > b else "B" if b > a else "unsure"


RUNS = (("similarity-matrix", "v3-similarity-matrix", 23, lambda q, k: 1 + (k * 3) % 5),
        ("pursuit-sawtooth", "v3-pursuit-high", 29, lambda q, k: higher(q)),
        ("search-4sin", "v3-search", 31,
         lambda q, k: {"stop": True} if k == 8 else {"save": 1} if k == 4 else {"choose": k % 3}))
ONLY = set(sys.argv[2:])        # (names to write; all without)
for config_name, name, seed, answer in RUNS:
    if ONLY and name not in ONLY:
        continue
    c = configs.load(config_name)
    config = dict(c["config"], config_file=config_name)
    if "reference" in c:
        config["reference"] = c["reference"]
    state = protocols.start(c["protocol"], config, seed)
    full = protocols.resolved(c["protocol"], state, config)
    s = Session.create(OUT, c["protocol"], "legacy", full, seed)
    header = s.header
    k = 0
    while not state.done:
        q = Q.ask(c["protocol"], state, header, DISPLAY)
        a = answer(q, k)
        s.append({"question": q.public, "answer": a, "scene": q.options[-1], "playing": 0,
                  "state": q.detail, "scenes": q.options})
        protocols.apply(c["protocol"], state, a)
        k += 1
    dest = Path(__file__).resolve().parent / (name + ".jsonl")
    dest.write_text(s.path.read_text())
    print("wrote", dest, k)
