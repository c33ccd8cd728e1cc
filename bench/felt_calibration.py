"""The felt model's calibration and the encoder against what is published
(texelpad.analysis.calibration; docs/encoder.md, "Calibration"):

1. the fit: the model's assumed constants on a grid, by the loss on the
   trained rater's matches (reference vs the rendering the rater felt) and
   seed 000's six quoted pitches; the best few, and the loss with the
   fingertip's fall or the lines' fusion taken out;
2. per texture, under the fitted model: the reference's felt point, the
   rater's rendering's, and how far apart they feel;
3. leave one texture out: refit without it, then the held-out texture -
   the felt distance between the reference and the rater's rendering, the
   felt pitch against the quoted mean, the fold's encoder against the
   rater's parameters;
4. three encoders side by side on the nine: the felt encoder (the default),
   the previous one (W2 on the felt spectra, no fingertip fall, no fusion)
   and the naive baseline (power-weighted mean and SD of log f,
   texelpad.study.references) - their pitch against the quoted means, their
   parameters against the rater's, how far their texture feels from the
   rater's rendering, the fraction of their texels above Nyquist.

The lab's per-subject result files are the held-out test: never read here.

    .venv/bin/python -m bench.felt_calibration [--json PATH] [--figure PATH]

Prints the tables; --json writes every figure; --figure a PNG/PDF/SVG of
the pitches and the felt plane. Never fails on time.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import statistics
import sys
import time
from typing import Any

from texelpad.analysis import calibration as C
from texelpad.analysis import encoder as E
from texelpad.analysis import perception as P
from texelpad.study import references as R
from . import jsonable

PREVIOUS = P.Model(fingertip_corner_hz=None, line_db=None)     # the encoder before the felt model (docs/encoder.md)
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _texture_point(pitch: float, irr: float, n: int, model: P.Model) -> P.FeltPoint:
    return P.felt_point({"pitch_db": min(pitch, 19.747), "irregularity_db": irr,
                         "texel_samples": C.RATER_TEXEL_SAMPLES, "gain": 1.0}, n, model)


def run(shared: str | None = None, progress: Any = None) -> dict[str, Any]:
    """The whole report (module docstring, 1-4) as a JSON-ready dict."""
    t0 = time.perf_counter()
    data = C.load(shared)
    cal = C.Calibration(data)
    fit = cal.fit(data.names)
    out = _fit_report(data, cal, fit)
    if progress:
        progress("felt_calibration: fit done (%.1f s); leave-one-out ..."
                 % (time.perf_counter() - t0))
    out["leave_one_out"] = C.leave_one_out(cal)
    if progress:
        progress("felt_calibration: leave-one-out done (%.1f s); encoders ..."
                 % (time.perf_counter() - t0))
    pts = data.points(fit.model)
    out["encoders"] = [_encoders(data, n, pts[n], fit.model) for n in data.names]
    out["summary"] = _summary(out["encoders"], fit.model)
    out["seconds"] = time.perf_counter() - t0
    return out


def _fit_report(data: C.Data, cal: C.Calibration, fit: C.Fit) -> dict[str, Any]:
    """1 and 2: the grid's best, the loss without each structural piece, and
    per texture the reference and the rater's rendering under the fit."""
    names = data.names
    ranked = sorted(((C.loss(pts, names), C.constants_of(m)) for m, pts in cal.grid),
                    key=lambda r: r[0])
    variants = {"fitted": fit.model,
                "no fingertip fall": dataclasses.replace(fit.model, fingertip_corner_hz=None),
                "no line fusion": dataclasses.replace(fit.model, line_db=None),
                "neither (the model before)": PREVIOUS}
    var_rows = {}
    for label, m in variants.items():
        vp = data.points(m)
        var_rows[label] = {"loss": C.loss(vp, names),
                           "distances": {n: vp[n][0].distance(vp[n][1]) for n in names}}
    pts = data.points(fit.model)
    per = [{"texture": n, "reference": pts[n][0].as_dict(), "rater_rendering": pts[n][1].as_dict(),
            "felt_distance_db": pts[n][0].distance(pts[n][1]),
            "quoted_pitch_db": C.QUOTED_PITCH_DB.get(n)} for n in names]
    return {"rater_labels": C.rater_label_check(),
            "fit": {"constants": C.constants_of(fit.model), "loss": fit.loss,
                    "model": fit.model.as_dict()},
            "ranked": [{"loss": lo, "constants": c} for lo, c in ranked[:8]],
            "grid_size": len(cal.grid), "variants": var_rows, "per_texture": per,
            "skin_band_hz": list(P.skin_band_hz(fit.model)),
            "skin_top_db": _skin_top_db(fit.model)}


def _encoders(data: C.Data, n: str, points: tuple[P.FeltPoint, P.FeltPoint],
              model: P.Model) -> dict[str, Any]:
    """4, one texture: the felt encoder, the previous one and the baseline,
    each with its texture's felt point and distances."""
    m = data.reference[n]
    ref_pt, rater_pt = points
    row: dict[str, Any] = {"texture": n, "quoted_pitch_db": C.QUOTED_PITCH_DB.get(n),
                           "rater": {"pitch_db": data.matches[n][0],
                                     "irregularity_db": data.matches[n][1]}}
    felt = E.encode(m, intervals=False)
    prev = E.encode(m, intervals=False, method="w2", model=PREVIOUS)
    base = R.position(n)
    for key, (p, i, alias) in (
            ("felt", (felt["pitch_db"], felt["irregularity_db"],
                      felt["aliasing"]["expected_fraction"])),
            ("previous", (prev["pitch_db"], prev["irregularity_db"],
                          prev["aliasing"]["expected_fraction"])),
            ("baseline", (base[0], base[1], P.expected_aliased_fraction(
                {"pitch_db": min(base[0], 19.747), "irregularity_db": base[1]})))):
        tp = _texture_point(p, i, m.size, model)
        row[key] = {"pitch_db": round(p, 3), "irregularity_db": round(i, 3),
                    "aliased_fraction": round(alias, 4), "felt": tp.as_dict(),
                    "felt_from_rater_rendering_db": round(tp.distance(rater_pt), 3),
                    "felt_from_reference_db": round(tp.distance(ref_pt), 3)}
    row["map_top_band_fraction"] = felt["aliasing"]["map_top_band_fraction"]
    return row


def _summary(enc: list[dict[str, Any]], model: P.Model) -> dict[str, Any]:
    """4, over the nine: each encoder against the quotes, the rater, the band."""
    summary = {}
    for key in ("felt", "previous", "baseline"):
        q = [abs(r[key]["pitch_db"] - r["quoted_pitch_db"]) for r in enc
             if r["quoted_pitch_db"] is not None]
        summary[key] = {
            "quoted_mean_abs_db": statistics.fmean(q), "quoted_max_abs_db": max(q),
            "rater_pitch_median_abs_db": statistics.median(
                abs(r[key]["pitch_db"] - r["rater"]["pitch_db"]) for r in enc),
            "rater_irregularity_median_abs_db": statistics.median(
                abs(r[key]["irregularity_db"] - r["rater"]["irregularity_db"]) for r in enc),
            "felt_from_rater_median_db": statistics.median(
                r[key]["felt_from_rater_rendering_db"] for r in enc),
            "felt_from_reference_median_db": statistics.median(
                r[key]["felt_from_reference_db"] for r in enc),
            "pitch_in_skin_band": sum(r[key]["pitch_db"] <= _skin_top_db(model) for r in enc)}
    return summary


def _skin_top_db(model: P.Model) -> float:
    return 10.0 * math.log10(P.skin_band_hz(model)[1] / model.speed_mm_s)


def _c(c: dict) -> str:
    return "SL %g dB, above 250 Hz %g dB/oct, masking %s" % (
        c["full_scale_sl_db"], c["slope_above_db_per_octave"],
        "off" if c["masking_db"] is None else "%g dB" % c["masking_db"])


def format_report(res: dict) -> str:
    return "\n".join(_format_fit(res) + [""] + _format_per_texture(res) + [""]
                     + _format_loo(res) + [""] + _format_encoders(res))


def _format_fit(res: dict) -> list[str]:
    lab = res["rater_labels"]
    L = ["the rater's pitch file, read by its labels: each row's log mean / log SD (dB) "
         "against its label's match",
         "  " + ", ".join("%s %.2f dB" % (k, v["distance_db"]) for k, v in lab["rows"].items()),
         "  labels' cost %.3f dB^2, the least any assignment has %.3f dB^2" % (
             lab["labels_cost"], lab["best_cost"]), "",
         "1. the fit over %d combinations of the assumed constants: loss (dB^2) = sum |felt(ref) "
         "- felt(rater's rendering)|^2 + (felt pitch - quoted)^2" % res["grid_size"]]
    for r in res["ranked"]:
        L.append("   %7.2f  %s" % (r["loss"], _c(r["constants"])))
    L.append("   with the best constants:")
    for label, v in res["variants"].items():
        L.append("   %-28s loss %7.2f" % (label, v["loss"]))
    return L


def _format_per_texture(res: dict) -> list[str]:
    L = ["2. per texture, fitted model: felt pitch / noisiness (dB) of the reference and of "
         "the rendering the rater felt",
         "%-9s %6s | %15s | %15s | %6s | %s" % ("texture", "quoted", "reference", "rater's rend.",
                                               "dist", "dist without fall / fusion / either"),
         "-" * 100]
    v = res["variants"]
    for r in res["per_texture"]:
        n = r["texture"]
        a, b = r["reference"], r["rater_rendering"]
        L.append("%-9s %6s | %6.2f / %6.2f | %6.2f / %6.2f | %6.2f | %5.2f / %5.2f / %5.2f"
                 % (n, "-" if r["quoted_pitch_db"] is None else "%.1f" % r["quoted_pitch_db"],
                    a["pitch_db"], a["noisiness_db"], b["pitch_db"], b["noisiness_db"],
                    r["felt_distance_db"], v["no fingertip fall"]["distances"][n],
                    v["no line fusion"]["distances"][n],
                    v["neither (the model before)"]["distances"][n]))
    return L


def _format_loo(res: dict) -> list[str]:
    L = ["3. leave one texture out: constants fitted on the other eight; on the held-out one:",
         "%-9s | %-44s | %6s %6s | %-22s %6s" % ("held out", "fold's constants", "dist",
                                                 "p-quot", "encoded (rater)", "felt"),
         "-" * 108]
    for r in res["leave_one_out"]:
        e, rv = r["encoded"], r["rater"]
        L.append("%-9s | %-44s | %6.2f %6s | %6.2f/%6.2f (%5.1f/%5.1f) %6.2f"
                 % (r["texture"], _c(r["constants"]), r["felt_distance_db"],
                    "-" if r["felt_pitch_error_db"] is None else "%+.2f" % r["felt_pitch_error_db"],
                    e["pitch_db"], e["irregularity_db"], rv["pitch_db"], rv["irregularity_db"],
                    r["encoded_vs_rater_db"]["felt"]))
    d = [r["felt_distance_db"] for r in res["leave_one_out"]]
    pe = [abs(r["felt_pitch_error_db"]) for r in res["leave_one_out"]
          if r["felt_pitch_error_db"] is not None]
    L.append("held-out felt distance reference - rater's rendering: median %.2f dB, worst %.2f dB;"
             " |felt pitch - quoted| mean %.2f dB, worst %.2f dB" % (statistics.median(d), max(d),
                                                                    statistics.fmean(pe), max(pe)))
    return L


def _format_encoders(res: dict) -> list[str]:
    L = ["4. three encoders on the nine (half screen): pitch / irregularity (dB), aliased "
         "texels (%), felt distance (dB) of their texture from the rater's rendering",
         "   felt: the default; previous: W2, no fingertip fall, no fusion; baseline: power-"
         "weighted mean and SD of log f. Skin band ends at %.2f dB (%.0f Hz at 86 mm/s)"
         % (res["skin_top_db"], res["skin_band_hz"][1]),
         "%-9s %6s %13s | %-22s | %-22s | %-22s" % ("texture", "quoted", "rater", "felt",
                                                     "previous", "baseline"), "-" * 110]
    for r in res["encoders"]:
        cells = ["%6.2f/%6.2f %4.1f%% %4.2f" % (r[k]["pitch_db"], r[k]["irregularity_db"],
                                                100 * r[k]["aliased_fraction"],
                                                r[k]["felt_from_rater_rendering_db"])
                 for k in ("felt", "previous", "baseline")]
        L.append("%-9s %6s %6.2f/%6.2f | %s" % (
            r["texture"], "-" if r["quoted_pitch_db"] is None else "%.1f" % r["quoted_pitch_db"],
            r["rater"]["pitch_db"], r["rater"]["irregularity_db"], " | ".join(cells)))
    L.append("")
    L.append("%-10s %14s %16s %16s %16s %12s" % ("encoder", "|p - quoted|", "|p - rater| med",
                                                 "|i - rater| med", "felt from rater",
                                                 "p in band"))
    for key, s in res["summary"].items():
        L.append("%-10s %6.2f / %5.2f %16.2f %16.2f %16.2f %9d / 9"
                 % (key, s["quoted_mean_abs_db"], s["quoted_max_abs_db"],
                    s["rater_pitch_median_abs_db"], s["rater_irregularity_median_abs_db"],
                    s["felt_from_rater_median_db"], s["pitch_in_skin_band"]))
    L.append("  (|p - quoted|: mean / max over the six seed 000 quotes; med: median over the nine)")
    return L


def figure(res: dict, path: str) -> None:
    """Left: pitch per texture - quoted, rater, the three encoders, the skin
    band's top. Right: the felt plane - references, the rater's renderings,
    the felt encoder's textures."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [r["texture"] for r in res["encoders"]]
    x = range(len(names))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5.2))
    for key, mk, col, lab in (("felt", "s", "C1", "felt encoder"),
                              ("previous", "^", "C2", "previous encoder (W2)"),
                              ("baseline", "+", "C4", "baseline (power-weighted log f)")):
        ax.plot(x, [r[key]["pitch_db"] for r in res["encoders"]], mk, color=col, ms=8, label=lab,
                ls="none")
    ax.plot(x, [r["rater"]["pitch_db"] for r in res["encoders"]], "o", mfc="none", mec="k",
            ms=10, label="trained rater", ls="none")
    ax.plot([i for i, r in zip(x, res["encoders"]) if r["quoted_pitch_db"] is not None],
            [r["quoted_pitch_db"] for r in res["encoders"] if r["quoted_pitch_db"] is not None],
            "x", color="C3", ms=10, mew=2, label="subjects' mean (seed 000)", ls="none")
    ax.axhline(res["skin_top_db"], color="0.4", ls="--", lw=1,
               label="skin band ends (%.0f Hz)" % res["skin_band_hz"][1])
    ax.set_xticks(list(x))
    ax.set_xticklabels(names)
    ax.set_ylabel("central pitch (dB re 1 c/mm)")
    ax.set_title("pitch chosen for each reference", fontsize="medium")
    ax.legend(fontsize="small", loc="center right")
    ax.grid(True, alpha=0.3)
    for i, r in enumerate(res["per_texture"]):
        a, b = r["reference"], r["rater_rendering"]
        e = res["encoders"][i]["felt"]["felt"]
        bx.annotate("", xy=(b["pitch_db"], b["noisiness_db"]), xytext=(a["pitch_db"],
                                                                      a["noisiness_db"]),
                    arrowprops={"arrowstyle": "-", "color": "0.6", "lw": 0.8})
        bx.plot(a["pitch_db"], a["noisiness_db"], "o", color="C0", ms=7,
                label="reference" if i == 0 else None)
        bx.plot(b["pitch_db"], b["noisiness_db"], "o", mfc="none", mec="k", ms=9,
                label="rater's rendering" if i == 0 else None)
        bx.plot(e["pitch_db"], e["noisiness_db"], "s", color="C1", ms=5,
                label="felt encoder's texture" if i == 0 else None)
        bx.annotate(r["texture"], (a["pitch_db"], a["noisiness_db"]), fontsize="small",
                    xytext=(4, 4), textcoords="offset points")
    bx.set_xlabel("felt pitch (dB re 1 c/mm)")
    bx.set_ylabel("felt noisiness (dB re 1 decade)")
    bx.set_title("the felt plane (fitted model): a match should sit on its reference",
                 fontsize="medium")
    bx.legend(fontsize="small", loc="upper right")
    bx.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.felt_calibration",
                                description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--shared", metavar="DIR", help="the shared folder (default ../shared)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure", metavar="PATH")
    a = p.parse_args(argv)
    if a.figure and not a.figure.lower().endswith(FIGURE_SUFFIXES):
        p.error("--figure: expected %s" % ", ".join(FIGURE_SUFFIXES))
    for flag, path in (("--json", a.json), ("--figure", a.figure)):
        if path:
            try:
                open(path, "a").close()
            except OSError as e:
                print("felt_calibration: %s: cannot write %s: %s" % (flag, path, e.strerror),
                      file=sys.stderr)
                return 1
    try:
        res = run(a.shared, progress=lambda m: print(m, file=sys.stderr, flush=True))
    except FileNotFoundError as e:
        print("felt_calibration: %s" % e, file=sys.stderr)
        return 1
    print(format_report(res))
    print("\ndone in %.1f s" % res["seconds"])
    if a.json:
        with open(a.json, "w") as f:
            json.dump(jsonable(res), f, indent=1)
    if a.figure:
        figure(res, a.figure)
    return 0


if __name__ == "__main__":
    sys.exit(main())
