"""Make session files with texelpad as it was before issue 20 (commit 9ec54e9,
checked out at /tmp/legacy: `git worktree add /tmp/legacy 9ec54e9`, then
`.venv/bin/python tests/study/data/legacy/make_legacy.py OUT_DIR`):
the fixtures of tests/study/test_legacy_sessions.py. Each answer record holds
what the old lab recorded: the answer, the scene the question played (option
0, or the free exploration's slider scene) and the question's detail."""
import sys
from pathlib import Path
sys.path[:0] = ["/tmp/legacy/host", "/tmp/legacy/device"]
from texelpad.study import configs as C, protocols, questions as Q
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.references import target_point
from texelpad.study.session import Session

OUT = Path(sys.argv[1])
DISPLAY = {"positions": 19200, "dx_um": 5.3}
RUNS = (("free-nine", 5, 9), ("quant-exemplars", 7, 12), ("similarity-matrix", 11, 9),
        ("pursuit-pink", 3, 20), ("staircase", 4, 30))
for name, seed, n in RUNS:
    cf = C.load(name)
    proto, config = cf["protocol"], dict(cf.get("config", {}))
    if proto == "pursuit":
        config["reference"] = cf.get("reference") or {"kind": "reference", "name": "4sin"}
    config["config_file"] = name
    state = protocols.start(proto, config, seed)
    config["texture_format"] = 2
    s = Session.create(OUT, proto, "legacy", config, seed)
    header = s.header
    sim = SimulatedParticipant(target_point("pink"), noise=0.02, seed=1, threshold_mm=5.0)
    for k in range(n):
        if state.done:
            break
        q = Q.ask(proto, state, header, DISPLAY)
        if proto == "free":
            sim.target = target_point(state.reference)
            a = sim.answer(proto, state)
            scene, _ = Q.slider_scene(state, header, DISPLAY, a["pitch_db"], a["irregularity_db"], 0)
        else:
            a = sim.answer(proto, state)
            if proto == "staircase":
                a = bool(a)
            scene = q.options[0]
        s.append({"question": q.public, "answer": a, "scene": scene, "playing": 0,
                  "state": q.detail})
        protocols.apply(proto, state, a)
    print(name, s.path)
