"""The texel-length oddity staircase (seed 001): which of three textures is
the odd one, the texel length going down 1-up-N-down to a threshold. Its
state: study/staircase.py."""
from __future__ import annotations

from typing import Any

from .. import scenes as S
from .. import staircase as SC
from ..describing import option
from ..question import Question, format_of
from .base import Protocol


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"threshold_mm": st.threshold_mm(),
                                                 "reversals": st.reversals})
    options, odd = S.staircase_scenes(st.texel_samples(), len(st.track), header["seed"],
                                      display, header["config"].get("distribution")
                                      or st.config.texture(), format_of(header),
                                      st.config.remainder_level,
                                      st.config.fit_mm if st.config.whole_texels else None)
    return Question({"done": False, "kind": "three", "trial": len(st.track),
                     "options": ["1", "2", "3"], "answers": [0, 1, 2],
                     "seconds": st.config.trial_seconds},
                    options,
                    {"length_mm": st.length_mm, "step_mm": st.step_mm,
                     "reversals": len(st.reversals), "odd": odd}, odd=odd)


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
               listed: int) -> dict[str, Any]:
    seed, v = header["seed"], format_of(header)
    dist = header.get("config", {}).get("distribution") or st.config.texture()
    trials = []
    q0 = _ask(st, header, display)
    for k in range(listed):
        scs, odd = S.staircase_scenes(st.texel_samples(), k, seed, display, dist, v,
                                      st.config.remainder_level)
        seeds = [sc["regions"][0]["texture"]["seed"] for sc in scs]
        entry: dict[str, Any] = {"trial": k, "seeds": seeds, "odd": odd + 1}
        if k == 0:
            entry["length_mm"] = st.length_mm
            entry["texel_samples"] = st.texel_samples()
            entry["options"] = [option(n, sc, display)
                                for n, sc in zip(q0.public["options"], q0.options)]
        trials.append(entry)
    c = st.config
    return {"trials": trials, "rules": [
        "each trial's three texture seeds and the odd one's position (1..3) come from "
        "(session seed, trial) alone; the first %d trials are listed" % listed,
        "the texel length depends on the answers: 1-up-%d-down from %g mm in %g mm steps, "
        "%g mm after %d reversals, never below %g mm; it stops after %d reversals; threshold "
        "= mean length at reversals %d.." % (c.down_after, c.start_mm, c.step_mm,
                                             c.fine_step_mm, c.fine_after_reversals,
                                             c.floor_mm, c.stop_after_reversals,
                                             c.threshold_from_reversal),
        "each texture fills the display with whole texels of the trial's length, the rest "
        "at level %g" % c.remainder_level]}


def _plot(fig: Any, ax: Any, state: Any) -> None:
    """The staircase's track, its reversals and threshold."""
    track = state.track
    ax.plot([t["length_mm"] for t in track], "-", color="0.6")
    for i, t in enumerate(track):
        ax.plot(i, t["length_mm"], "o" if t["correct"] else "x",
                color="C2" if t["correct"] else "C3")
    rev = [i for i, t in enumerate(track) if t["reversal"]]
    ax.plot(rev, [track[i]["length_mm"] for i in rev], "s", mfc="none", ms=10,
            label="reversals")
    thr = state.threshold_mm()
    if thr is not None:
        ax.axhline(thr, ls="--", label="threshold %.2f mm" % thr)
    ax.set_xlabel("trial")
    ax.set_ylabel("texel length (mm)")
    ax.legend()


class StaircaseProtocol(Protocol):
    NAME = "staircase"
    TITLE = "texel-length oddity staircase (seed 001)"
    RECORDS_FINGER = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return SC.Staircase(SC.Config(**config))

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        return super().normalise(q, state, answer) == q.odd    # what it takes: found or not

    def record(self, q: Question, answer: Any) -> dict[str, Any]:
        return {"picked": answer, "odd": q.odd}

    def result_shown(self, result: dict[str, Any]) -> dict[str, Any] | None:
        return None                     # (whether the odd one was found: never shown)

    def simulate(self, who: Any, state: Any) -> Any:
        return who.odd_one_out(state.length_mm)

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        return dict(correct=a, length_mm=state.length_mm, trial=len(state.track))

    def full_config(self, state: Any, header: dict[str, Any]) -> dict[str, Any]:
        out = self.resolved(state, header)
        if "distribution" not in out:           # the stimulus as it plays
            out["distribution"] = state.config.texture()
        return out


PROTOCOL = StaircaseProtocol()
