"""`texelpad lab`'s web server (Starlette, an established ASGI framework; served
by uvicorn on 127.0.0.1 only): the study protocols (texelpad.study,
texelpad.search) on one board (web/owner.py, the only owner of a Board).

Two pages: the experimenter's (/) picks a protocol's config, a participant id
and starts or resumes a session, and follows it with the parameters shown;
the participant's (/participant?s=P/NAME) shows only what the participant
may see - option labels and answers, never a parameter value.

    GET  /api/status                            the board's status (or why it is lost)
    GET  /api/scene                             the canonical scene it plays
    GET  /api/configs                           the study configs (texelpad.study.configs)
    GET  /api/sessions                          every session under the data folder
    POST /api/sessions                          {config: NAME | protocol + config?, participant,
                                                 seed?, reference?, matches_from?}
    GET  /api/sessions/P/NAME                   the participant's question (resumed from its file)
    GET  /api/sessions/P/NAME/monitor           the experimenter's view: parameters, state
    POST /api/sessions/P/NAME/feel              {option: k, question: n?} | free: {pitch_db,
                                                 irregularity_db, question: n?}
    POST /api/sessions/P/NAME/answer            {answer: ..., question: n}
    POST /api/sessions/P/NAME/replay            {record: n}: play what answer n heard
    POST /api/board/release                     {}: the session playing lets the board go

Every request is validated (a JSON object of known keys, at most 16 KB; ids
as texelpad.study.session.check_name; the board's own scene validation is the
last word) and a refused one changes nothing: 400 with the reason, 503 when
the board is gone.

One click, one answer (docs/lab.md): every question a session asks has
a number, question.number - the answers given before it - and an answer
names the question it answers ({"question": n}). One for a question already
answered (a double-click, a page that sent twice) or not yet asked is
refused with 409 and changes nothing; so is an answer to a question whose
scene the board no longer plays (another page played something since: the
participant feels it again first). The file records what truly played.

The board belongs to the study (item 4): while a session's question plays
and the session is not finished, the classroom's and the editor's pushes are
refused (409, naming the session); the session lets go when it finishes or
when the experimenter releases it (POST /api/board/release), and takes the
board again at its next question. Another session starting or playing takes
the board; the one it took it from plays its question again before it takes
an answer.

An answer is checked, then written to the session file
(fsynced), and only then moves the protocol's state: a crash at any point
resumes from the file. A board that is gone after an answer was written does
not undo it: the reply says the answer is kept and the board is lost, and the
next question plays when the board answers again.
"""
from __future__ import annotations

import json
import random
import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse
from starlette.routing import BaseRoute, Mount, Route
from starlette.staticfiles import StaticFiles

from ..link.board import host_check
from ..study import configs as C
from ..study import finger
from ..study import matches as M
from ..study import protocols
from ..study import questions as Q
from ..study import scenes as S
from ..study.session import DataLock, Session, SessionError, check_name, sessions
from . import strip
from . import editor
from .api import Conflict, Refused, body_of, handle, keys
from .owner import BoardLost, BoardOwner

CREATE_KEYS = {"config", "protocol", "participant", "seed", "reference", "matches_from"}
STATIC = Path(__file__).with_name("static")   # the pages, their scripts and styles
LOCAL_HOSTS = ["127.0.0.1", "localhost"]


def _plain(v: Any) -> bool:
    return v is None or isinstance(v, (bool, int, float, str))


@dataclass
class Live:
    """A session in memory: its file, the protocol's state, the current
    question (built once per state: None after an answer) and what plays."""
    key: str
    session: Session
    state: Any
    question: Q.Question | None = None
    playing: int | None = None              # the option playing (None: nothing of this session)
    connection: int = 0                     # the owner's connection it played on
    playing_scene: dict[str, Any] | None = None
    moves: int = 0                          # sliding protocols: slider changes this trial
    sliders: tuple[float, float] | None = None
    resume_scene: dict[str, Any] | None = None  # resumed mid-trial: the scene the file last had
    feel: dict[str, Any] | None = None      # the protocol's FEEL_KEYS settings playing (the
                                            # search's friction slider); None: its feel_state

    @property
    def protocol(self) -> str:
        return self.session.header["protocol"]


class Lab:
    def __init__(self, owner: BoardOwner, data: str | Path,
                 configs: str | Path | None = None, data_lock: DataLock | None = None) -> None:
        """data_lock: the data folder's lock, already held (texelpad lab takes
        it before it starts the board); without one the Lab takes it here,
        and a folder another lab holds is refused (SessionError, naming the
        process). Lab.close() lets it go."""
        self.owner = owner
        self.data = Path(data)
        self.configs = configs
        C.available(configs)                # a missing --configs folder is said at once
        if data_lock is None:
            data_lock = DataLock(self.data)
            data_lock.acquire()
        self.data_lock = data_lock
        self.live: dict[str, Live] = {}
        self.lock = threading.Lock()        # one request at a time (web/api.handle)
        self.board_session: str | None = None   # the session whose question plays
        # the editor's brush files (web/editor.py): texelpad lab --brushes, else DATA/brushes
        self.brushes: str | Path | None = None
        # what the strip and the editor hold between requests, made with their routes
        self.strip_cache: Any = None        # web/strip.py StripCache
        self.editor: Any = None             # web/editor.py Editor
        # the finger recorder (study/finger.py): a thread reading the board's telemetry
        # while a recording session's question plays, started with the first one
        self._recorder: threading.Thread | None = None
        self._stopping = threading.Event()

    def stop_recording(self) -> None:
        """Stop the finger recorder (before the board's owner closes: the
        recorder would reconnect)."""
        self._stopping.set()
        if self._recorder is not None:
            self._recorder.join(timeout=5.0)

    def close(self) -> None:
        self.stop_recording()
        self.data_lock.release()

    # --- the finger, recorded per trial (study/finger.py) -----------------------------
    def _finger_hz(self, lv: Live) -> int:
        return protocols.get(lv.protocol).finger_hz(lv.state)

    def _finger(self, lv: Live, keep: bool = True) -> None:
        """Read the board's telemetry ring; keep: write what it held as lv's
        finger record of the question asked and the option playing (one
        append, fsynced, as an answer is). Samples of a stream just
        (re)started are from before this moment: dropped."""
        hz = self._finger_hz(lv)
        if not hz:
            return
        samples, lost, fresh = self.owner.finger_samples(hz)
        if self._recorder is None and not self._stopping.is_set():
            self._recorder = threading.Thread(target=self._record_loop, daemon=True,
                                              name="texelpad-lab-finger")
            self._recorder.start()
        if fresh or not keep or not (samples or lost) or lv.session.finished:
            return
        n = self._number(lv)
        trial = lv.question.public.get("trial", n) if lv.question is not None else n
        lv.session.append(finger.record(n, trial, lv.playing, samples, lost, hz,
                                   self.owner.display()["dx_um"]))

    def _plays_now(self, lv: Live) -> bool:
        return (lv.playing is not None and self.board_session == lv.key
                and lv.connection == self.owner.connections)

    def _record_loop(self) -> None:
        """Every FINGER_POLL_S: the session whose question plays, if it records the finger."""
        while not self._stopping.wait(finger.FINGER_POLL_S):
            with self.lock:
                lv = self._owning()
                if lv is None or not self._finger_hz(lv):
                    continue
                try:
                    self._finger(lv)
                except (BoardLost, ValueError, SessionError, OSError):
                    pass        # (a lost board is said by the next request; nothing to keep)
                except Exception as e:      # (never let the recorder die unseen)
                    print("texelpad lab: the finger recorder: %s: %s" % (type(e).__name__, e),
                          file=sys.stderr, flush=True)

    # --- whose scene plays -------------------------------------------------------------
    def _took_board(self, lv: Live) -> None:
        """lv's scene plays now: the session before it (another one) lost it."""
        if self.board_session not in (None, lv.key):
            prev = self.live.get(self.board_session)
            if prev is not None:
                prev.playing = None
        self.board_session = lv.key
        lv.connection = self.owner.connections

    def _owning(self) -> Live | None:
        """The unfinished session whose question the board plays, if any."""
        lv = self.live.get(self.board_session) if self.board_session else None
        if lv is None or lv.playing is None or lv.session.finished or \
                lv.connection != self.owner.connections:
            self.board_session = None
            return None
        return lv

    def claim_board(self, what: str) -> None:
        """Refuse a push that is no session's (the classroom, the editor, a
        replay of another session) while a study session's question plays."""
        lv = self._owning()
        if lv is not None:
            raise Conflict("%s: the board plays session %s, a study running (its participant "
                           "may be feeling it): wait until it is finished, or release the "
                           "board on the experimenter's page" % (what, lv.key))

    def release(self) -> dict[str, Any]:
        """The experimenter lets the board go: the session playing plays its
        question again when it is next asked (or felt)."""
        lv = self._owning()
        self.board_session = None
        if lv is None:
            return {"released": None}
        lv.playing = None
        return {"released": lv.key}

    # --- questions and playing ---------------------------------------------------------
    def _question(self, lv: Live) -> Q.Question:
        if lv.question is None:
            lv.question = Q.ask(lv.protocol, lv.state, lv.session.header, self.owner.display())
        return lv.question

    def _feel(self, lv: Live) -> dict[str, Any]:
        if lv.feel is None:
            lv.feel = protocols.get(lv.protocol).feel_state(lv.state)
        return lv.feel

    def _play(self, lv: Live, k: int, feel: dict[str, Any] | None = None) -> None:
        """Play option k of the question (with the protocol's FEEL_KEYS
        settings: feel, else those playing)."""
        assert lv.question is not None              # an option is played from its question
        p = protocols.get(lv.protocol)
        scene = p.feel_scene(lv.state, lv.question, k, dict(self._feel(lv), **(feel or {})))
        if self._finger_hz(lv):     # what the finger did while the option before played
            try:
                self._finger(lv, keep=self._plays_now(lv))
            except ValueError:      # (the board refused the stream: the push says the rest)
                pass
        _, canonical = self.owner.push(scene)
        if feel:
            lv.feel = dict(lv.feel or {}, **feel)
        lv.playing, lv.playing_scene = k, canonical
        self._took_board(lv)

    def _begin(self, lv: Live) -> None:
        """Play what the current question starts with: option 0; the free
        exploration's sliders at their start (or where they were)."""
        q = self._question(lv)
        if q.done:
            return
        if Q.sliding(lv.protocol, lv.state):
            if lv.resume_scene is not None:     # the very texture the file says was playing
                _, canonical = self.owner.push(lv.resume_scene)
                lv.playing, lv.playing_scene, lv.resume_scene = 0, canonical, None
                self._took_board(lv)
                return
            p, s = lv.sliders or lv.state.config.start
            self._slide(lv, p, s, record=lv.sliders is None)
        else:
            self._play(lv, 0)

    def _slide(self, lv: Live, pitch: Any, irregularity: Any, record: bool = True) -> dict:
        scene, (p, s) = Q.slider_scene(lv.state, lv.session.header, self.owner.display(),
                                       pitch, irregularity, lv.moves)
        _, canonical = self.owner.push(scene)
        lv.playing, lv.playing_scene, lv.sliders = 0, canonical, (p, s)
        self._took_board(lv)
        if record:          # the path the participant took, for analysis (not an answer)
            ka, kb = Q.SLIDER_KEYS[lv.protocol]
            lv.session.append({"kind": "move", "trial": lv.state.trial, "move": lv.moves,
                               ka: p, kb: s, "scene": canonical})
        lv.moves += 1
        return {"playing": 0}

    def _key(self, participant: Any, name: Any) -> str:
        return "%s/%s" % (check_name("participant", participant), check_name("session", name))

    # --- the API ----------------------------------------------------------------------
    def create(self, body: dict[str, Any]) -> dict[str, Any]:
        keys(body, CREATE_KEYS)
        participant = check_name("participant", body.get("participant"))
        if isinstance(body.get("config"), str):         # a config file by name
            if "protocol" in body:
                raise Refused("give a config's name or a protocol, not both")
            cf = C.load(body["config"], self.configs)
            proto, config = cf["protocol"], dict(cf.get("config", {}))
            reference = body.get("reference") or cf.get("reference")
            seed = body.get("seed", cf.get("seed"))
            config["config_file"] = body["config"]
        else:
            proto = body.get("protocol")
            if proto not in protocols.PROTOCOLS:
                raise Refused("protocol: expected one of %s, got %r"
                              % (", ".join(protocols.PROTOCOLS), proto))
            config = body.get("config") or {}
            if not isinstance(config, dict):
                raise Refused("config: expected a config's name or an object")
            config = dict(config)
            reference, seed = body.get("reference"), body.get("seed")
        if "seed" in body and body["seed"] is None:
            raise Refused("seed: expected an int in [0, 2^31), got null (leave it out for a "
                          "random seed)")
        if seed is None:
            seed = random.SystemRandom().randrange(1 << 31)
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 1 << 31:
            raise Refused("seed: expected an int in [0, 2^31), got %r" % (seed,))
        p = protocols.get(proto)
        if p.REFERENCE_CHOSEN:
            reference = reference or S.DEFAULT_REFERENCE
            if not isinstance(reference, dict):
                raise Refused("reference: expected a texture object")
            config["reference"] = reference
        elif reference is not None:
            raise Refused("reference: only the pursuit and the search take one (the free "
                          "exploration and the quantization test name theirs in the config)")
        if body.get("matches_from") is not None:
            if p.TAKES_SAVED:
                config["textures"], config["match_source"] = self._saved_from(
                    body["matches_from"])
            elif not p.TAKES_MATCHES:
                raise Refused("matches_from: only the quantization test and the evaluation "
                              "take matches")
            else:
                config["matches"], config["match_source"] = self._matches_from(
                    body["matches_from"], config)
        if p.TAKES_SAVED and config.get("textures") is None:
            raise Refused("textures: the evaluation rates stopped searches' saved textures: "
                          "give matches_from (the search sessions)")
        if p.TAKES_MATCHES and config.get("matches") is None:
            raise Refused("matches: the quantization test rates the participant's own matches: "
                          "give matches_from (their free exploration session)")
        try:
            state = protocols.start(proto, config, seed)
        except (TypeError, ValueError) as e:
            raise Refused("config: %s" % e) from None
        config["texture_format"] = S.texture_format(config)    # the header says it: 2 unless asked
        config = protocols.resolved(proto, state, config)       # every choice, defaults included
        display = self.owner.display()
        if "reference" in config:   # the board's own validation, before any file is made
            host_check(S.split(config["reference"],
                               {"pitch_db": 0.0, "irregularity_db": 0.0, "v": 2}, display),
                       display)
        sess = Session.create(self.data, proto, participant, config, seed)
        key = "%s/%s" % (participant, sess.path.stem)
        lv = Live(key, sess, state)
        self.live[key] = lv
        self._begin(lv)
        return self._view(key, lv)

    @staticmethod
    def _sids(sids: Any, most: int, distinct: bool = False) -> list[str]:
        """matches_from as a list of session ids P/NAME (one given alone), at
        most `most` of them, each once if `distinct`; else Refused."""
        if isinstance(sids, str):
            sids = [sids]
        if not isinstance(sids, list) or not 1 <= len(sids) <= most or \
                any(not isinstance(x, str) or x.count("/") != 1 for x in sids) or \
                (distinct and len(set(sids)) != len(sids)):
            raise Refused("matches_from: expected a session id P/NAME or a list of %s"
                          % ("different ones" if distinct else "them"))
        return sids

    def _saved_from(self, sids: Any) -> tuple[list[dict[str, Any]], str]:
        """Seed 003's Phase 2: the texture each stopped search saved last."""
        sids = self._sids(sids, 100, distinct=True)     # (the paper's Phase 2 rated 25)
        out = []
        for sid in sids:
            lv = self.get(*sid.split("/"))
            try:
                out.append(M.from_saved(lv.session, lv.state))
            except ValueError as e:
                raise Refused(str(e)) from None
        return out, ", ".join(sids)

    def _matches_from(self, sids: Any, config: dict[str, Any]) -> tuple[dict, str]:
        """The participant's own matches for the quantization test or the
        similarity matrix, from the sessions named: a free exploration's
        matches, a finished guided exploration's end point or a stopped
        search's mean (each for the reference it ran on). Later sessions in
        the list win."""
        sids = self._sids(sids, 20)
        found: dict[str, dict[str, Any]] = {}
        for sid in sids:
            lv = self.get(*sid.split("/"))
            try:
                found.update(M.from_session(lv.protocol, lv.session, lv.state))
            except ValueError as e:
                raise Refused(str(e)) from None
        refs = M.references_of(config)
        missing = [r for r in refs if r not in found]
        if missing:
            raise Refused("matches_from: no match of %s in %s" % (", ".join(missing),
                                                                  ", ".join(sids)))
        return {r: found[r] for r in refs}, ", ".join(sids)

    def get(self, participant: Any, name: Any) -> Live:
        key = self._key(participant, name)
        lv = self.live.get(key)
        if lv is None:                                  # resume from its file
            path = self.data / participant / (name + ".jsonl")
            if not path.is_file():
                raise Refused("no session %s" % key)
            sess = Session.open(path)
            lv = Live(key, sess, protocols.replay(sess))
            if Q.sliding(lv.protocol, lv.state):       # the sliders where they were
                ka, kb = Q.SLIDER_KEYS[lv.protocol]
                moves = [r for r in sess.records if r.get("kind") == "move"
                         and r.get("trial") == lv.state.trial and ka in r]
                if moves:
                    lv.moves = moves[-1]["move"] + 1
                    lv.sliders = (moves[-1][ka], moves[-1][kb])
                    lv.resume_scene = moves[-1].get("scene")
            self.live[key] = lv
        return lv

    @staticmethod
    def _number(lv: Live) -> int:
        """The number of the question asked now: the answers given before it."""
        return sum(1 for _ in lv.session.answers())

    def _view(self, key: str, lv: Live) -> dict[str, Any]:
        q = self._question(lv)
        n = self._number(lv)
        return {"id": key, "protocol": lv.protocol, "question": dict(q.public, number=n),
                "playing": lv.playing,
                "sliders": lv.sliders if Q.sliding(lv.protocol, lv.state) else None,
                "feel": self._feel(lv) or None,    # (the search's friction slider as it plays)
                "answers_so_far": n}

    def _asked(self, lv: Live, n: Any, what: str) -> None:
        """n names the question asked now, or Conflict (409): one answered
        already (a double-click) or one not asked yet."""
        if isinstance(n, bool) or not isinstance(n, int):
            raise Refused("question: expected the number of the question %s (question.number "
                          "of GET /api/sessions/P/NAME), got %s"
                          % (what, json.dumps(n)[:40] if _plain(n) else type(n).__name__))
        now = self._number(lv)
        if self._question(lv).done:
            raise Conflict("question %d: the session is finished (%d answers)" % (n, now))
        if n < now:
            raise Conflict("question %d is answered already (the session is at question %d): "
                           "nothing changed" % (n, now))
        if n > now:
            raise Conflict("question %d is not asked yet (the session is at question %d): "
                           "nothing changed" % (n, now))

    def question(self, participant: str, name: str) -> dict[str, Any]:
        key = self._key(participant, name)
        lv = self.get(participant, name)
        if lv.playing is None:          # (resumed: play where it stopped)
            self._begin(lv)
        return self._view(key, lv)

    def monitor(self, participant: str, name: str) -> dict[str, Any]:
        """The experimenter's view: the participant's, plus the parameters."""
        key = self._key(participant, name)
        lv = self.get(participant, name)
        out = self._view(key, lv)
        h = lv.session.header
        assert lv.question is not None              # _view asked it
        out.update(detail=lv.question.detail, seed=h["seed"], config=h["config"],
                   title=protocols.TITLES[lv.protocol], file=str(lv.session.path),
                   records=len(lv.session.records), finished=lv.session.finished,
                   playing_scene=lv.playing_scene)
        return out

    def feel(self, participant: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
        lv = self.get(participant, name)
        q = self._question(lv)
        if q.done:
            raise Refused("the session is finished")
        if isinstance(body, dict) and "question" in body:   # (a page's late click: 409)
            self._asked(lv, body["question"], "felt")
        if Q.sliding(lv.protocol, lv.state):
            ka, kb = Q.SLIDER_KEYS[lv.protocol]
            keys(body, {ka, kb, "question"})
            return self._slide(lv, body.get(ka), body.get(kb))
        p = protocols.get(lv.protocol)
        keys(body, {"option", "question", *p.FEEL_KEYS})
        k = body.get("option")
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(q.options):
            raise Refused("option: expected 0 .. %d, got %r" % (len(q.options) - 1, k))
        # (a bad setting: _play's feel_scene refuses it, 400, before anything is read or pushed)
        self._play(lv, k, {f: body[f] for f in p.FEEL_KEYS if f in body})
        return {"playing": k}

    def answer(self, participant: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
        keys(body, {"answer", "question"})
        key = self._key(participant, name)
        lv = self.get(participant, name)
        if "question" not in body:
            raise Refused("question: required - the number of the question answered "
                          "(question.number of GET /api/sessions/P/NAME)")
        self._asked(lv, body["question"], "answered")
        q = self._question(lv)
        taken = Q.normalise(lv.protocol, q, lv.state, body.get("answer"))
        if Q.sliding(lv.protocol, lv.state):    # the match is what plays, never another
            answered = tuple(taken[k] for k in Q.SLIDER_KEYS[lv.protocol])
            if lv.sliders is None or answered != tuple(lv.sliders):
                raise Conflict("the sliders answered %s are not what plays (%s): feel it, "
                               "then answer - nothing changed"
                               % (list(answered), list(lv.sliders or ())))
        pr = protocols.get(lv.protocol)
        if pr.FEEL_KEYS and isinstance(taken, dict) and "stop" not in taken:
            base = pr.feel_state(lv.state)          # (what an answer without it keeps)
            for f in pr.FEEL_KEYS:                  # (the search's friction slider)
                said, playing = taken.get(f, base.get(f)), self._feel(lv).get(f)
                if said != playing:
                    raise Conflict("the %s answered (%r) is not what plays (%r): feel it, "
                                   "then answer - nothing changed" % (f, said, playing))
        if lv.playing is None or self.board_session != key or \
                lv.connection != self.owner.connections:
            raise Conflict("the board does not play this question now (%s): feel it again, "
                           "then answer - nothing changed"
                           % ("another page played on it since" if lv.playing is not None
                              else "it played something else since"))
        p = protocols.get(lv.protocol)
        try:
            self._finger(lv)        # the trial's last finger samples, before its answer
        except (BoardLost, ValueError):
            pass                    # (the answer is kept; the next question says the board)
        rec = dict({"question": q.public, "answer": taken, "scene": lv.playing_scene,
                    "playing": lv.playing, "state": q.detail}, **p.record(q, body["answer"]))
        lv.session.append(rec)                          # on disk first, then the state moves
        result = protocols.apply(lv.protocol, lv.state, taken)
        lv.question, lv.sliders, lv.moves, lv.feel = None, None, 0, None
        # (what the finger does until the next question plays is this answer's trial's,
        # read above: not the next question's)
        lv.playing = None
        nq = self._question(lv)
        lost = None
        if nq.done:
            lv.session.append({"kind": "end", "result": nq.detail})
            if self.board_session == key:       # finished: the board is free
                self.board_session = None
        else:
            try:
                self._begin(lv)
            except BoardLost as e:      # the answer is kept; the next one plays when it is back
                lv.playing, lost = None, str(e)
        out = self._view(key, lv)
        if lost:
            out["board_lost"] = lost
        out["result"] = p.result_shown(result)
        return out

    def replay(self, participant: str, name: str, body: dict[str, Any]) -> dict[str, Any]:
        """Play what answer n of a session heard (the recorded canonical scene)."""
        keys(body, {"record"})
        lv = self.get(participant, name)
        n = body.get("record")
        recs = list(lv.session.answers())
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n < len(recs):
            raise Refused("record: expected 0 .. %d, got %r" % (len(recs) - 1, n))
        scene = recs[n].get("scene")
        if not scene:
            raise Refused("answer %d has no scene recorded" % n)
        owning = self._owning()
        if owning is not None and owning is not lv:
            self.claim_board("replay")
        self.owner.push(scene)
        lv.playing = None
        if self.board_session == lv.key:
            self.board_session = None
        return {"replayed": n}

    def list_sessions(self) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for path in sessions(self.data):
            try:
                s = Session.open(path)
            except (OSError, SessionError) as e:
                out.append({"id": "%s/%s" % (path.parent.name, path.stem), "error": str(e)})
                continue
            out.append({"id": "%s/%s" % (path.parent.name, path.stem),
                        "protocol": s.header["protocol"], "time": s.header["time"],
                        "config_file": s.header["config"].get("config_file"),
                        "answers": sum(1 for _ in s.answers()), "finished": s.finished})
        return out


def make_app(lab: Lab, allowed_hosts: list[str] | None = None) -> Starlette:
    def page(name: str):
        async def endpoint(request: Request) -> FileResponse:
            return FileResponse(STATIC / name, media_type="text/html")
        return endpoint

    # plain functions: web.api.handle reads the body first, then runs them
    # in a worker thread under the lab's lock
    def session_route(method):
        def endpoint(request: Request):
            p = request.path_params
            if method in (Lab.question, Lab.monitor):
                return method(lab, p["participant"], p["name"])
            return method(lab, p["participant"], p["name"], body_of(request))
        return endpoint

    def status(request: Request):
        return lab.owner.status()

    def scene(request: Request):
        return {"scene": lab.owner.scene_source()}

    def configs(request: Request):
        return {"configs": C.available(lab.configs), "protocols": protocols.TITLES}

    def list_sessions(request: Request):
        return {"sessions": lab.list_sessions()}

    def create(request: Request):
        return lab.create(body_of(request))

    def release(request: Request):
        keys(body_of(request), set())
        return lab.release()

    h = lambda fn: handle(lab.lock, fn)             # noqa: E731
    s = "/api/sessions/{participant}/{name}"
    routes: list[BaseRoute] = [Route("/", page("experimenter.html")),
              Route("/participant", page("participant.html")),
              Route("/api/status", h(status)),
              Route("/api/scene", h(scene)),
              Route("/api/configs", h(configs)),
              Route("/api/sessions", h(list_sessions)),
              Route("/api/sessions", h(create), methods=["POST"]),
              Route(s, h(session_route(Lab.question))),
              Route(s + "/monitor", h(session_route(Lab.monitor))),
              Route(s + "/feel", h(session_route(Lab.feel)), methods=["POST"]),
              Route(s + "/answer", h(session_route(Lab.answer)), methods=["POST"]),
              Route(s + "/replay", h(session_route(Lab.replay)), methods=["POST"]),
              Route("/api/board/release", h(release), methods=["POST"])]
    routes += strip.routes(lab)
    routes += editor.routes(lab)
    routes.append(Mount("/static", StaticFiles(directory=STATIC), name="static"))
    return Starlette(routes=routes, middleware=[
        # localhost only, also by name: a page elsewhere cannot reach it by
        # rebinding a DNS name to 127.0.0.1
        Middleware(TrustedHostMiddleware, allowed_hosts=allowed_hosts or LOCAL_HOSTS)])
