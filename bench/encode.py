"""Benchmark of the texel encoder (issue 13; texelpad.analysis.encoder,
docs/encoder.md):

1. speed: encode a full-screen map (19,200 samples) - the median of --runs,
   with and without the scan for the ranges that feel the same;
2. against people: seed 000's nine references (the study's half-screen
   rows, 9,600 samples) encoded, beside the subjects' mean Central Pitch that
   seed 000 quotes (texelpad.study.references.PAPER_PITCH_DB) and the
   references' spectral positions of texelpad.study.references; then the
   same with the model's assumed constants changed (masking off, full scale
   30 and 50 dB above threshold, 50 and 150 mm/s) - the model's sensitivity;
3. the analytic expected spectrum against renderings (100 seeds);
   robustness: noisy, clipped, short, NaN-bearing, out-of-range, faint and
   constant maps made from one texture - the answer or the error;
4. against itself: maps rendered from known parameters (pitch -10 .. 19 dB,
   irregularity -30 .. 0 dB, quantization 0, 1 and 3 dB given to the encoder,
   --seeds seeds, 9,600 samples) encoded back: the largest error per cell
   and whether the truth lies within the reported range that feels the same.

    .venv/bin/python -m bench.encode [--seeds N] [--runs N] [--json PATH]

Prints the tables; --json writes every encoded result's figures. Never fails
on time (tests never assert on time: docs/architecture.md).
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from typing import Any

import numpy as np

import texel

from texelpad.analysis import encoder as E
from texelpad.analysis import perception as P
from texelpad.study import references as R

PITCHES = (-10.0, -5.0, 0.0, 5.0, 10.0, 15.0, 19.0)
IRREGS = (-30.0, -20.0, -15.0, -10.0, -5.0, 0.0)
QUANTS = (0.0, 1.0, 3.0)
LENGTH = 9600                   # the study's half screen
FULL_SCREEN = 19200
DEFAULT_SEEDS = 4
DEFAULT_RUNS = 5
VARIANTS = (("default", P.Model()),
            ("no fingertip fall", P.Model(fingertip_corner_hz=None)),
            ("no line fusion", P.Model(line_db=None)),
            ("no masking", P.Model(masking_db=None)),
            ("full scale 30 dB SL", P.Model(full_scale_sl_db=30.0)),
            ("full scale 50 dB SL", P.Model(full_scale_sl_db=50.0)),
            ("50 mm/s", P.Model(speed_mm_s=50.0)),
            ("150 mm/s", P.Model(speed_mm_s=150.0)))


def speed(runs: int) -> dict[str, Any]:
    """Seconds to encode a full-screen texel map (pitch 6.3 dB, irregularity
    -12.9 dB, seed 7: docs/generator.md's example), median of `runs`."""
    m = texel.render({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7,
                      "length_samples": FULL_SCREEN})
    out: dict[str, Any] = {"samples": FULL_SCREEN}
    for key, iv in (("with_ranges", True), ("without_ranges", False)):
        ts, ev = [], 0
        for _ in range(runs):
            t = time.perf_counter()
            r = E.encode(m, intervals=iv)
            ts.append(time.perf_counter() - t)
            ev = r["evaluations"]
        out[key] = {"median_s": statistics.median(ts), "min_s": min(ts), "max_s": max(ts),
                    "candidates": ev}
    return out


def people() -> dict[str, Any]:
    """The nine references encoded (default model and the variants)."""
    rows = []
    for name in R.REFERENCES:
        m = E.reference_map(name)
        r = E.encode(m, source="reference %s" % name)
        w = E.encode(m, method="w2", intervals=False)
        sp, si = R.position(name)
        row = {"reference": name, "family": R.FAMILIES[name],
               "paper_pitch_db": R.PAPER_PITCH_DB.get(name),
               "pitch_db": r["pitch_db"], "irregularity_db": r["irregularity_db"],
               "gain": r["gain"], "distance_db": r["distance_db"], "ranges": r["ranges"],
               "felt_pitch_db": r["felt"]["map"]["pitch_db"],
               "felt_noisiness_db": r["felt"]["map"]["noisiness_db"],
               "texture_felt_pitch_db": r["felt"]["rendering"]["pitch_db"],
               "skin_top_db": r["skin_band"]["pitch_db_max"],
               "w2": [w["pitch_db"], w["irregularity_db"]],
               "spectral_model": [round(sp, 2), round(si, 2)],
               "aliased_fraction": r["aliasing"]["expected_fraction"],
               "map_top_band_fraction": r["aliasing"]["map_top_band_fraction"],
               "quantization_cost_db": r["quantization"]["cost_db"], "variants": {}}
        for label, model in VARIANTS[1:]:
            v = E.encode(m, model=model, intervals=False)
            row["variants"][label] = [v["pitch_db"], v["irregularity_db"]]
        rows.append(row)
    errs: dict[str, list[float]] = {lab: [] for lab, _ in VARIANTS}
    for row in rows:
        if row["paper_pitch_db"] is None:
            continue
        errs["default"].append(row["pitch_db"] - row["paper_pitch_db"])
        for lab, _ in VARIANTS[1:]:
            errs[lab].append(row["variants"][lab][0] - row["paper_pitch_db"])
    summary = {lab: {"mean_abs_db": float(np.mean(np.abs(e))), "max_abs_db":
                     float(np.max(np.abs(e)))} for lab, e in errs.items()}
    sm = [R.position(r["reference"])[0] - r["paper_pitch_db"] for r in rows
          if r["paper_pitch_db"] is not None]
    summary["spectral model"] = {"mean_abs_db": float(np.mean(np.abs(sm))),
                                 "max_abs_db": float(np.max(np.abs(sm)))}
    return {"rows": rows, "pitch_error_vs_paper": summary}


def round_trip(seeds: int, progress: Any = None, method: str = "w2",
               quants: tuple[float, ...] = QUANTS) -> list[dict[str, Any]]:
    """Every (quant, irregularity, pitch, seed) case: truth, encoding, ranges
    (method "w2": the spectral match, whose bounds docs/encoder.md states;
    "felt": the default encoder, measured by how far its texture feels from
    the map)."""
    out = []
    for q in quants:
        for irr in IRREGS:
            for pitch in PITCHES:
                for s in range(1, seeds + 1):
                    p = {"pitch_db": pitch, "irregularity_db": irr, "quant_db": q, "seed": s,
                         "length_samples": LENGTH}
                    plan = texel.make_plan(p)
                    r = E.encode(texel.render(p), quant_db=q, method=method)
                    rg = r["ranges"]
                    out.append({"quant_db": q, "irregularity_db": irr, "pitch_db": pitch,
                                "seed": s, "got": [r["pitch_db"], r["irregularity_db"]],
                                "error": [r["pitch_db"] - pitch, r["irregularity_db"] - irr],
                                "ranges": [rg["pitch_db"], rg["irregularity_db"]],
                                "within": [rg["pitch_db"][0] - 0.005 <= pitch
                                           <= rg["pitch_db"][1] + 0.005,
                                           rg["irregularity_db"][0] - 0.005 <= irr
                                           <= rg["irregularity_db"][1] + 0.005],
                                "distance_db": r["distance_db"],
                                "felt_distance_db": r["felt_distance_db"],
                                "truth_felt_distance_db": P.felt_distance(
                                    r["texture"], dict(p, gain=r["gain"]), n=LENGTH),
                                "aliased_drawn": plan.fraction_above_nyquist(),
                                "seconds": r["seconds"]})
            if progress:
                progress("round trip (%s): quant %g dB, irregularity %g dB done"
                         % (method, q, irr))
    return out


CHECKED = ({"pitch_db": 6.0, "irregularity_db": -12.0},
           {"pitch_db": 6.0, "irregularity_db": -5.0},
           {"pitch_db": 0.0, "irregularity_db": -10.0},
           {"pitch_db": -10.0, "irregularity_db": -20.0},
           {"pitch_db": 15.0, "irregularity_db": -3.0},
           {"pitch_db": 19.0, "irregularity_db": -10.0},
           {"pitch_db": 6.0, "irregularity_db": -5.0, "quant_db": 3.0},
           {"pitch_db": 3.0, "irregularity_db": 0.0},
           {"pitch_db": 12.0, "irregularity_db": -2.0, "band_limit_cpmm": 30.0},
           {"pitch_db": 5.0, "irregularity_db": -8.0, "texel_samples": 20000})
MODEL_SEEDS = 100


def model_check() -> list[dict[str, Any]]:
    """The analytic expected spectrum (perception.expected_periodogram)
    against the mean periodogram of MODEL_SEEDS renderings (seeds 0..99,
    9,600 samples): total power and the W2 distance of the felt patterns."""
    out = []
    for params in CHECKED:
        _, S = P.expected_periodogram(params, LENGTH)
        mean = np.sum([P.periodogram(texel.render(dict(params, length_samples=LENGTH, seed=s)))[1]
                       for s in range(MODEL_SEEDS)], axis=0) / MODEL_SEEDS
        out.append({"params": params, "power_expected": float(S.sum()),
                    "power_rendered": float(mean.sum()),
                    "w2_db": P.w2_db(P.pattern_of_spectrum(S, LENGTH),
                                     P.pattern_of_spectrum(mean, LENGTH))})
    return out


def format_model_check(rows: list[dict[str, Any]]) -> str:
    lines = ["the expected spectrum (analytic) against the mean of %d renderings (%s samples)"
             % (MODEL_SEEDS, format(LENGTH, ",")),
             "%-62s %17s %10s" % ("texture", "power exp./rend.", "W2 (dB)"), "-" * 92]
    for r in rows:
        lines.append("%-62s %8.4f/%.4f %10.3f" % (r["params"], r["power_expected"],
                                                  r["power_rendered"], r["w2_db"]))
    return "\n".join(lines)


def robustness() -> list[dict[str, Any]]:
    """Awkward maps made from one texture (pitch 6 dB, irregularity -10 dB,
    seed 3, 9,600 samples): what the encoder answers, or its error."""
    rng = np.random.default_rng(0)
    b = np.asarray(texel.render({"pitch_db": 6.0, "irregularity_db": -10.0, "seed": 3,
                                 "length_samples": LENGTH}))
    k = np.arange(b.size)
    cases = [("the texture itself", b),
             ("+ noise, SD 0.1", b + rng.normal(0.0, 0.1, b.size)),
             ("+ noise, SD 0.3", b + rng.normal(0.0, 0.3, b.size)),
             ("+ noise SD 0.3, clipped to 0..1", np.clip(b + rng.normal(0.0, 0.3, b.size), 0, 1)),
             ("x3 about 0.5, clipped to 0..1", np.clip((b - 0.5) * 3 + 0.5, 0, 1)),
             ("thresholded at 0.5 (0/1)", (b > 0.5).astype(float)),
             ("first 1,000 samples (5.3 mm)", b[:1000]),
             ("first 200 samples (1.06 mm)", b[:200]),
             ("first 50 samples (one texel)", b[:50]),
             ("first 16 samples", b[:16]),
             ("first 15 samples", b[:15]),
             ("every 500th sample NaN (0.2 %)", np.where(k % 500 == 0, np.nan, b)),
             ("every 10th sample NaN (10 %)", np.where(k % 10 == 0, np.nan, b)),
             ("one inf", np.where(k == 7, np.inf, b)),
             ("as uint16 (render_u16)", (b * 65535 + 0.5).astype(np.uint16)),
             ("x10 - 3 (values -3 .. 7)", b * 10 - 3),
             ("1e-6 of full scale", 0.5 + 1e-6 * (b - 0.5)),
             ("constant 0.3", np.full(LENGTH, 0.3))]
    out = []
    for label, m in cases:
        try:
            r = E.encode(m, intervals=False)
            out.append({"case": label, "pitch_db": r["pitch_db"],
                        "irregularity_db": r["irregularity_db"], "gain": r["gain"],
                        "distance_db": r["distance_db"], "notes": r["notes"]})
        except E.EncodeError as e:
            out.append({"case": label, "error": str(e)})
    return out


def format_robustness(rows: list[dict[str, Any]]) -> str:
    lines = ["robustness: awkward maps made from one texture (pitch 6 dB, irregularity -10 dB, "
             "seed 3, 9,600 samples)",
             "%-32s %s" % ("map", "pitch / irregularity / gain / distance (dB), or the error"),
             "-" * 100]
    for r in rows:
        if "error" in r:
            lines.append("%-32s EncodeError: %s" % (r["case"], r["error"]))
        else:
            lines.append("%-32s %6.2f / %6.2f / %.3g / %.3f%s"
                         % (r["case"], r["pitch_db"], r["irregularity_db"], r["gain"],
                            r["distance_db"], ("  (%d note%s)" % (len(r["notes"]), "" if
                                               len(r["notes"]) == 1 else "s"))
                            if r["notes"] else ""))
    return "\n".join(lines)


def format_people(res: dict[str, Any]) -> str:
    lines = ["against people: the nine references (9,600 samples), the encoder's choice beside "
             "seed 000",
             "  paper: the subjects' mean Central Pitch in the free exploration as seed 000 "
             "quotes it (dB)",
             "  felt: the map's felt pitch / noisiness; dist: felt distance of the texture from "
             "the map; same-feel: the ranges within 1 dB (one difference threshold);",
             "  w2: the spectral match (method w2); spectral: texelpad.study.references; "
             "aliased: the texture's texels above Nyquist / the map's power in the top 0.1 "
             "decade",
             "reference  paper | pitch  irreg  gain  dist |  felt p/n     | same-feel pitch  "
             "same-feel irreg |    w2 p/i      | spectral p/i   | aliased",
             "-" * 132]
    for r in res["rows"]:
        rg = r["ranges"]
        lines.append("%-9s %6s | %5.2f %6.2f %5.3f %5.3f | %5.2f / %6.2f | %6.2f .. %5.2f "
                     "%7.2f .. %5.2f | %6.2f / %6.2f | %6.2f / %6.2f | %4.1f %% / %4.1f %%"
                     % (r["reference"], "-" if r["paper_pitch_db"] is None else
                        "%.1f" % r["paper_pitch_db"], r["pitch_db"], r["irregularity_db"],
                        r["gain"], r["distance_db"], r["felt_pitch_db"],
                        r["felt_noisiness_db"], rg["pitch_db"][0],
                        rg["pitch_db"][1], rg["irregularity_db"][0], rg["irregularity_db"][1],
                        r["w2"][0], r["w2"][1],
                        r["spectral_model"][0], r["spectral_model"][1],
                        100 * r["aliased_fraction"], 100 * r["map_top_band_fraction"]))
    lines.append("the skin's band at the model's 86 mm/s ends at %.2f dB: the felt pitch of "
                 "every encoding is at most %.2f dB, its pitch at most %.2f dB"
                 % (res["rows"][0]["skin_top_db"],
                    max(r["texture_felt_pitch_db"] for r in res["rows"]),
                    max(r["pitch_db"] for r in res["rows"])))
    lines.append("")
    lines.append("the model's assumed constants changed: pitch / irregularity (dB)")
    labels = [lab for lab, _ in VARIANTS]
    lines.append("reference  paper | " + " | ".join("%-13s" % lab[:13] for lab in labels))
    lines.append("-" * (19 + 16 * len(labels)))
    for r in res["rows"]:
        cells = ["%5.2f / %6.2f" % (r["pitch_db"], r["irregularity_db"])]
        cells += ["%5.2f / %6.2f" % tuple(r["variants"][lab]) for lab in labels[1:]]
        lines.append("%-9s %6s | %s" % (r["reference"], "-" if r["paper_pitch_db"] is None else
                                        "%.1f" % r["paper_pitch_db"], " | ".join(cells)))
    e = res["pitch_error_vs_paper"]
    lines.append("|pitch - paper| over the six quoted, mean / max (dB): " + "; ".join(
        "%s %.2f / %.2f" % (lab, e[lab]["mean_abs_db"], e[lab]["max_abs_db"])
        for lab in labels + ["spectral model"]))
    return "\n".join(lines)


def format_round_trip(rows: list[dict[str, Any]], seeds: int) -> str:
    lines = ["against itself: maps rendered from known parameters (%d samples, seeds 1..%d) "
             "encoded back" % (LENGTH, seeds),
             "  cell: max |encoded - true| over the seeds, pitch dB / irregularity dB;",
             "  '*' = the truth outside the reported same-feel range for some seed "
             "(otherwise inside for all)"]
    for q in QUANTS:
        lines.append("")
        lines.append("quantization %g dB (given to the encoder)" % q)
        lines.append("irr \\ pitch " + "".join("%12g" % p for p in PITCHES))
        for irr in IRREGS:
            cells = []
            for p in PITCHES:
                cs = [r for r in rows if r["quant_db"] == q and r["irregularity_db"] == irr
                      and r["pitch_db"] == p]
                dp = max(abs(r["error"][0]) for r in cs)
                di = max(abs(r["error"][1]) for r in cs)
                out = not all(r["within"][0] and r["within"][1] for r in cs)
                cells.append("%5.2f/%5.2f%s" % (dp, di, "*" if out else " "))
            lines.append("%8g    " % irr + " ".join(cells))
    inside = sum(r["within"][0] and r["within"][1] for r in rows)
    lines.append("")
    lines.append("truth within the reported same-feel ranges (both parameters): %d of %d cases"
                 % (inside, len(rows)))
    return "\n".join(lines)


def format_felt_round_trip(rows: list[dict[str, Any]], seeds: int) -> str:
    """The felt encoder on rendered maps: how far its texture feels from the
    map, beside how far the truth does (max over the seeds), and the pitch
    error; a pitch above the skin's band comes back as the texture in it
    that feels the same."""
    top = 10.0 * math.log10(P.skin_band_hz()[1] / P.SPEED_MM_S)
    lines = ["the felt encoder (the default) on the same maps, no quantization (seeds 1..%d): "
             "felt distance of its texture / of the truth from the map, max over the seeds "
             "(dB), and max |pitch error|" % seeds,
             "  the skin's band ends at %.2f dB: above it the truth is not what is felt" % top,
             "irr \\ pitch " + "".join("%19g" % p for p in PITCHES)]
    for irr in IRREGS:
        cells = []
        for p in PITCHES:
            cs = [r for r in rows if r["irregularity_db"] == irr and r["pitch_db"] == p]
            cells.append("%4.2f/%4.2f %6.2f" % (max(r["felt_distance_db"] for r in cs),
                                                 max(r["truth_felt_distance_db"] for r in cs),
                                                 max(abs(r["error"][0]) for r in cs)))
        lines.append("%8g    " % irr + "  ".join("%17s" % c for c in cells))
    within = sum(r["felt_distance_db"] < P.JND_DB for r in rows)
    better = sum(r["felt_distance_db"] <= r["truth_felt_distance_db"] + 0.02 for r in rows)
    inband = [r for r in rows if r["pitch_db"] <= top and -15.0 <= r["irregularity_db"] <= -5.0]
    lines.append("felt distance under one difference threshold (%g dB): %d of %d; no farther "
                 "than the truth (+0.02 dB): %d of %d; in the band, irregularity -15 .. -5 dB: "
                 "|pitch error| max %.2f dB over %d cases"
                 % (P.JND_DB, within, len(rows), better, len(rows),
                    max(abs(r["error"][0]) for r in inband), len(inband)))
    return "\n".join(lines)


def bounds(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The stated bounds by regime (docs/encoder.md): the largest errors seen."""
    def sel(pred: Any) -> list[dict[str, Any]]:
        return [r for r in rows if pred(r)]
    regimes = [
        ("no quantization, irregularity -15 .. -5 dB",
         lambda r: r["quant_db"] == 0 and -15 <= r["irregularity_db"] <= -5),
        ("no quantization, irregularity -30 .. -20 dB",
         lambda r: r["quant_db"] == 0 and r["irregularity_db"] <= -20),
        ("no quantization, irregularity 0 dB",
         lambda r: r["quant_db"] == 0 and r["irregularity_db"] == 0),
        ("quantized 1 dB, irregularity -10 .. -5 dB",
         lambda r: r["quant_db"] == 1 and -10 <= r["irregularity_db"] <= -5),
        ("quantized 3 dB, irregularity -10 .. -5 dB",
         lambda r: r["quant_db"] == 3 and -10 <= r["irregularity_db"] <= -5),
        ("quantized, irregularity <= -15 dB",
         lambda r: r["quant_db"] > 0 and r["irregularity_db"] <= -15),
        ("quantized, irregularity 0 dB",
         lambda r: r["quant_db"] > 0 and r["irregularity_db"] == 0),
    ]
    out = []
    for label, pred in regimes:
        cs = sel(pred)
        out.append({"regime": label, "cases": len(cs),
                    "max_abs_pitch_error_db": max(abs(r["error"][0]) for r in cs),
                    "max_abs_irregularity_error_db": max(abs(r["error"][1]) for r in cs),
                    "median_abs_pitch_error_db": statistics.median(abs(r["error"][0])
                                                                   for r in cs),
                    "median_abs_irregularity_error_db": statistics.median(abs(r["error"][1])
                                                                          for r in cs),
                    "truth_in_ranges": sum(r["within"][0] and r["within"][1] for r in cs)})
    return out


def format_bounds(bs: list[dict[str, Any]]) -> str:
    lines = ["by regime: |error| median / max (dB), truth within the same-feel ranges",
             "%-46s %6s %15s %19s %8s" % ("regime", "cases", "pitch", "irregularity",
                                          "in range")]
    for b in bs:
        lines.append("%-46s %6d %6.2f / %6.2f %8.2f / %7.2f %5d/%d"
                     % (b["regime"], b["cases"], b["median_abs_pitch_error_db"],
                        b["max_abs_pitch_error_db"], b["median_abs_irregularity_error_db"],
                        b["max_abs_irregularity_error_db"], b["truth_in_ranges"], b["cases"]))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.encode", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", type=int, default=DEFAULT_SEEDS,
                   help="round-trip seeds per cell (default %(default)s)")
    p.add_argument("--runs", type=int, default=DEFAULT_RUNS,
                   help="timed encodes of the full-screen map (default %(default)s)")
    p.add_argument("--json", metavar="PATH", help="write every figure here")
    a = p.parse_args(argv)
    if a.seeds < 1 or a.runs < 1:
        p.error("--seeds and --runs: expected >= 1")
    if a.json:
        try:
            open(a.json, "a").close()
        except OSError as e:
            print("encode bench: --json: cannot write %s: %s" % (a.json, e.strerror),
                  file=sys.stderr)
            return 1

    def progress(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    sp = speed(a.runs)
    print("encode a full-screen map (%s samples, pitch 6.3 dB, irregularity -12.9 dB, seed 7), "
          "median of %d runs:" % (format(sp["samples"], ","), a.runs))
    for key in ("with_ranges", "without_ranges"):
        s = sp[key]
        print("  %-15s %.3f s (min %.3f, max %.3f; %d candidate textures)"
              % (key.replace("_", " "), s["median_s"], s["min_s"], s["max_s"], s["candidates"]))
    print()
    ppl = people()
    print(format_people(ppl))
    print()
    mc = model_check()
    print(format_model_check(mc))
    print()
    rob = robustness()
    print(format_robustness(rob))
    print()
    rows = round_trip(a.seeds, progress)
    print(format_round_trip(rows, a.seeds))
    print()
    bs = bounds(rows)
    print(format_bounds(bs))
    print()
    felt_rows = round_trip(a.seeds, progress, method="felt", quants=(0.0,))
    print(format_felt_round_trip(felt_rows, a.seeds))
    print("\nbench done in %.1f s" % (time.perf_counter() - t0))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"speed": sp, "people": ppl, "model_check": mc, "robustness": rob,
                       "round_trip": rows, "bounds": bs, "felt_round_trip": felt_rows,
                       "model": P.Model().as_dict(),
                       "seeds": a.seeds, "length": LENGTH}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
