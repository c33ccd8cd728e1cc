"""The finger during a trial: the board's own telemetry, recorded in the
session beside the answers, and seed 001's measures of it.

Seed 001 (../shared/seeds/001_*.txt, "swipe speeds ... were recorded"; Fig. 3)
reports per subject the average swipe speed and its standard deviation, and
the *directional proportion*: "for each trial, a running tally was
incremented by 1 for every sample where the finger was swiping right, and
decremented by 1 for leftward swipe. The tally was divided by the total
number of samples in that trial". Fig. 3 plots each subject's average
directional proportion against the convergent texel length.

A finger record (kind "finger", written by the lab's server as the board's
telemetry ring is read - every FINGER_POLL_S while a recording session's
question plays, and before each answer and each switch of option - so it is
on disk as it happens and a crash loses at most the samples not yet read):

    {"kind": "finger", "question": n (the answers before it), "trial": k
     (the protocol's trial number), "option": the option playing,
     "rate_hz": samples per second asked, "dx_um": the display's sample pitch,
     "lost": samples the ring lapped before they were read,
     "t_us": [board ticks_us of each sample, wrapping at 2^30],
     "pos": [display position, -1 = no finger]}

Choices the paper leaves open, named here (and in docs/lab.md):
- a sample is *swiping* right (left) when the finger moved right (left) since
  the sample before at MOVING_MM_S or faster, both samples touching; slower
  is resting (a sensor's noise, a turn);
- "the total number of samples in that trial" is every sample of the trial,
  the finger's lifted ones included (the paper's words; `contact_only`
  divides by the touching ones instead);
- a subject's directional proportion (Fig. 3) is the mean over trials of the
  trial's |proportion| (a subject swiping only leftward is as one-directional
  as one swiping only rightward); the signed means are exported too;
- the swipe speed is |velocity| over the swiping samples; a subject's
  average and SD are over all of them, every trial.
Pure logic: no link, no web.
"""
from __future__ import annotations

import math
from typing import Any, Iterable, Sequence

WRAP = 1 << 30              # the board's telemetry clock wraps here (texel/runtime/refresh.py)
MOVING_MM_S = 10.0          # slower: resting, not swiping (the choice above)
FINGER_HZ = 100             # samples per second the lab records by default (staircase Config)
FINGER_POLL_S = 0.5         # how often the lab reads the board's 256-sample ring (2.56 s at 100 Hz)


def record(question: int, trial: int, option: int | None,
           samples: Sequence[tuple[int, int, int]], lost: int, rate_hz: int,
           dx_um: float) -> dict[str, Any]:
    """A session's finger record of telemetry samples (t_us, position,
    amplitude) taken while question number `question` (the answers before
    it), trial `trial` of its protocol, played option `option`."""
    return {"kind": "finger", "question": int(question), "trial": int(trial),
            "option": option, "rate_hz": int(rate_hz),
            "dx_um": float(dx_um), "lost": int(lost),
            "t_us": [int(s[0]) for s in samples], "pos": [int(s[1]) for s in samples]}


def of_question(records: Iterable[dict[str, Any]], question: int) -> list[dict[str, Any]]:
    """The finger records of one question (answer number `question`), in the
    order written."""
    return [r for r in records if r.get("kind") == "finger" and r.get("question") == question]


def unwrap(t_us: Sequence[int]) -> list[float]:
    """Seconds from the first sample, the clock's 2^30 wraps undone (samples
    arrive in order; no gap between two reads lasts 2^30 us = 17.9 min)."""
    out, total = [], 0
    for i, t in enumerate(t_us):
        if i:
            total += (t - t_us[i - 1]) % WRAP
        out.append(total / 1e6)
    return out


def velocities(recs: Sequence[dict[str, Any]]) -> tuple[list[float], int]:
    """(mm/s between each sample and the one before, NaN where either had no
    finger or the two are not neighbours in one record, per sample after a
    record's first; the number of samples)."""
    v: list[float] = []
    n = 0
    for r in recs:
        t = unwrap(r["t_us"])
        pos = r["pos"]
        n += len(pos)
        dx_mm = r["dx_um"] / 1000.0
        for i in range(1, len(pos)):
            dt = t[i] - t[i - 1]
            if pos[i] < 0 or pos[i - 1] < 0 or dt <= 0:
                v.append(math.nan)
            else:
                v.append((pos[i] - pos[i - 1]) * dx_mm / dt)
    return v, n


def measures(recs: Sequence[dict[str, Any]], contact_only: bool = False) -> dict[str, Any]:
    """Seed 001's measures of one trial's finger records: samples, touching
    samples, swiping right / left, the directional proportion ((right - left)
    / samples), the mean and SD of the swipe speed (mm/s), lost samples.
    None for what a trial without samples (or swipes) cannot say."""
    v, n = velocities(recs)
    touching = sum(1 for r in recs for p in r["pos"] if p >= 0)
    right = sum(1 for x in v if x >= MOVING_MM_S)
    left = sum(1 for x in v if x <= -MOVING_MM_S)
    speeds = [abs(x) for x in v if abs(x) >= MOVING_MM_S]
    denom = touching if contact_only else n
    return {"samples": n, "touching": touching, "right": right, "left": left,
            "directional_proportion": (right - left) / denom if denom else None,
            "speed_mm_s": sum(speeds) / len(speeds) if speeds else None,
            "speed_sd_mm_s": sd(speeds), "speeds": speeds,
            "lost": sum(int(r.get("lost", 0)) for r in recs)}


def sd(xs: Sequence[float]) -> float | None:
    """The sample standard deviation (n - 1), None below two values."""
    if len(xs) < 2:
        return None
    m = sum(xs) / len(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def subject(trials: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """A subject's (a session's) Fig. 3 values from its trials' measures:
    the mean |directional proportion| and the signed mean over the trials
    that have samples, the mean and SD of every swiping sample's speed."""
    dps = [m["directional_proportion"] for m in trials if m["directional_proportion"] is not None]
    speeds = [s for m in trials for s in m["speeds"]]
    return {"directional_proportion": sum(abs(d) for d in dps) / len(dps) if dps else None,
            "signed_directional_proportion": sum(dps) / len(dps) if dps else None,
            "per_trial": dps,
            "speed_mm_s": sum(speeds) / len(speeds) if speeds else None,
            "speed_sd_mm_s": sd(speeds)}


def simulated(duration_s: float, rate_hz: int, dx_um: float, positions: int,
              speed_mm_s: float, one_way: bool, start_us: int = 0, margin_mm: float = 5.0
              ) -> list[tuple[int, int, int]]:
    """A simulated finger's telemetry for one trial (texelpad.study.participant):
    swipes across the display at speed_mm_s between margin_mm from its ends -
    back and forth (one_way False), or rightward only, lifted for the way
    back (as long as a swipe). Samples (t_us wrapping at 2^30, position or -1,
    amplitude 0)."""
    length_mm = positions * dx_um / 1000.0
    span = length_mm - 2 * margin_mm
    swipe_s = span / speed_mm_s
    out = []
    for k in range(int(duration_s * rate_hz)):
        t = k / rate_hz
        leg, at = divmod(t, swipe_s)
        frac = at / swipe_s
        if int(leg) % 2 == 0:
            mm = margin_mm + frac * span
        elif one_way:
            mm = None                   # lifted, back to the left end
        else:
            mm = margin_mm + (1.0 - frac) * span
        pos = -1 if mm is None else min(positions - 1, int(mm * 1000.0 / dx_um + 0.5))
        out.append(((start_us + int(round(t * 1e6))) % WRAP, pos, 0))
    return out
