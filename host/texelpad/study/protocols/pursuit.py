"""The guided exploration (seed 000): the pursuit vector - A or B, which is
closer to the reference - moving a centre on the pitch-irregularity plane.
Its state: study/pursuit.py."""
from __future__ import annotations

from typing import Any

from .. import pursuit as PV
from .. import scenes as S
from ..describing import option
from ..question import Question, played_db, db_of, format_of, reference_of
from ..space import aliased_samples, irregularity_db, is_above_nyquist, pitch_db, texel_params
from .base import Protocol, tuples


def _texture(c: Any, p: Any, seed: int, v: int, n: int) -> dict[str, Any]:
    """A point's texture: its texel texture, or above Nyquist with
    above_nyquist "alias" the n display samples the app's way plays (texelpad.space)."""
    if c.above_nyquist == "alias" and is_above_nyquist(p):
        return aliased_samples(p, n, seed=seed, v=v)
    return texel_params(p, seed=seed, v=v)


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    q = st.next_comparison()
    if q is None:
        return Question({"done": True}, detail={"centre": db_of(st.centre),
                                                 "trials": len(st.history)})
    ref = reference_of(header)
    v = format_of(header)
    c = st.config
    sa, sb = c.seeds(header["seed"], q.trial, q.index)
    n = S.positions(display, whole=c.presentation == "whole")
    ta, tb = (_texture(c, p, s, v, n) for p, s in ((q.a, sa), (q.b, sb)))
    if c.presentation == "whole":
        names = ["reference", "A", "B"]
        options = [S.whole(ref, display, name="reference"), S.whole(ta, display, name="A"),
                   S.whole(tb, display, name="B")]
    else:
        names = ["A", "B"]
        options = [S.split(ref, ta, display, name="A"), S.split(ref, tb, display, name="B")]
    return Question({"done": False, "kind": "pair", "trial": q.trial, "index": q.index,
                     "of": [5, 4], "options": names, "answers": ["A", "B", "unsure"],
                     "presentation": c.presentation},
                    options,
                    {"reference": ref, "centre": db_of(st.centre), "edge": st.edge,
                     "direction": q.direction, "A": db_of(q.a), "B": db_of(q.b),
                     "A_is_plus": q.a_is_plus, "seeds": [sa, sb],
                     "aliased": [t.get("kind") == "samples" for t in (ta, tb)]})


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    c = st.config
    seed = header["seed"]
    first = st.trial
    out = []
    while not st.done:
        q = st.next_comparison()
        sa, sb = c.seeds(seed, q.trial, q.index)
        entry: dict[str, Any] = {"trial": q.trial, "index": q.index, "direction": q.direction,
                                 "A": "+" + q.direction if q.a_is_plus else "-" + q.direction,
                                 "B": "-" + q.direction if q.a_is_plus else "+" + q.direction,
                                 "seeds": [sa, sb]}
        if q.trial == first:            # the centre moves only after a trial's 4th answer
            qq = _ask(st, header, display)
            entry["options"] = [option(n, sc, display)
                                for n, sc in zip(qq.public["options"], qq.options)]
            entry["A_db"], entry["B_db"] = qq.detail["A"], qq.detail["B"]
        else:
            ref = [option("reference", S.whole(reference_of(header), display), display)] \
                if c.presentation == "whole" else []
            where = "whole display" if c.presentation == "whole" else "right half"
            entry["options"] = ref + [
                {"option": n, "where": where, "seed": s, "v": format_of(header),
                 "depends": "the point centre %s edge/4 * d_%s"
                 % ("+" if (n == "A") == q.a_is_plus else "-", q.direction)}
                for n, s in (("A", sa), ("B", sb))]
        out.append(entry)
        st.answer("unsure")             # (no move: the order and sides are the seed's only)
    return {"trials": out, "rules": [
        "the order of the 4 directions and the A/B sides are drawn from the session's seed "
        "alone; the texture seeds from (seed, trial, index)",
        "answers move the centre: centre += (sum r_k d_k) * %.6f (r_k = +1 / -1 / 0 for the "
        "+d_k point, its opposite, unsure), clamped to the unit square; edge -= %g; A and B "
        "are centre +- edge/4 * d_k; it stops when edge < %g (5 trials, 20 comparisons)"
        % (c.step, c.edge_step, c.stop_below),
        "above_nyquist %r: a point above 19.747 dB (the display's Nyquist pitch) %s"
        % (c.above_nyquist, "plays aliased, as the app's: display samples the host renders "
           "from the texel generator's plan at the point's pitch" if c.above_nyquist == "alias"
           else "plays the texel texture at 19.747 dB")]}


def _plot(fig: Any, ax: Any, state: Any) -> None:
    """The pursuit's centre, trial by trial."""
    pts = [state.history[0]["centre_before"]] if state.history else \
        [{"u": state.centre.u, "v": state.centre.v}]
    pts += [e["centre_after"] for e in state.history]
    ax.plot([pitch_db(p["u"]) for p in pts], [irregularity_db(p["v"]) for p in pts], "o-")
    ax.annotate("start", (pitch_db(pts[0]["u"]), irregularity_db(pts[0]["v"])))
    ax.set_xlabel("pitch (dB re 1 c/mm)")
    ax.set_ylabel("irregularity (dB re 1 decade)")


class PursuitProtocol(Protocol):
    NAME = "pursuit"
    TITLE = "guided exploration: pursuit vector (seed 000)"
    REFERENCE_CHOSEN = True
    GIVES_MATCHES = "end point"
    ON_PLANE = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return PV.Pursuit(seed, PV.Config(**tuples(config)))

    def estimate(self, state: Any) -> dict[str, float]:
        return played_db(state.centre)

    def simulate(self, who: Any, state: Any) -> Any:
        q = state.next_comparison()
        return who.compare(q.a, q.b)


PROTOCOL = PursuitProtocol()
