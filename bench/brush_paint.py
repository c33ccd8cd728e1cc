"""Benchmark and report for the Tactile Paintbrush's painting (issue 12 items
3-5): what painting a region costs on every runtime, what a brush weighs
against the map it paints, and the round trip brush -> painted maps -> fitted
brush.

    .venv/bin/python -m bench.brush_paint [--chip] [--json PATH] [--figure PATH]

- synthesis time of a full-screen region (19,200 samples, 404 windows) on
  CPython (texel.gen.brush.paint how="numpy"; and how="python", the Python
  loops), the MicroPython unix port (how="viper", and how="python": a
  1,880-sample region, scaled per window),
  and with --chip the emulated RP2040 (../shared/instruments/rp2emu: a
  half-screen brush scene pushed, the build time on the chip's own clock);
- bytes: the brush as JSON, binary (.tpb), the region as sent to a board
  (the scene's JSON text), against the uint16 map of the same region;
- the round trip: designed brushes (white, pink, brown; shapes 2 and 5)
  painted over 10 full screens, re-analysed and fitted (document.fit): the
  ratio fitted / designed of the scale and the shape at wavenumbers 1 .. 95,
  median and 5th - 95th percentile; and three textures we have (the pink
  and sawtooth references, a texel rendering) fitted, painted, refitted;
- --figure: docs/img/brush-fit.png - each texture's map beside the brush's
  painting of it, and the scale per wavelength fitted to each.
Never fails on time.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from texel.gen import brush as B

from texelpad import toolchain
from texelpad.brush import document as D

FULL = 19200


def _time(fn, repeat=3) -> float:
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def synthesis(chip: bool) -> dict:
    doc = D.design("pink", 0.04)
    v = B.validate({"k": doc["k"], "lam": doc["lam"], "range": doc["range"]})
    out: dict[str, float | None] = {
        "cpython_numpy_s": _time(lambda: B.paint(v, 1, FULL, how="numpy")),
           "cpython_python_s": _time(lambda: B.paint(v, 1, FULL, how="python"), 1)}
    code = """
import time
from texel.gen import brush as B
b = B.validate(%r)
viper = B._viper() is not None
t0 = time.ticks_us(); B.paint(b, 1, %d, how="viper" if viper else "python"); t1 = time.ticks_us()
B.paint(b, 1, 1880, how="python"); t2 = time.ticks_us()
print(viper, time.ticks_diff(t1, t0), time.ticks_diff(t2, t1))
""" % ({"k": v["k"], "lam": v["lam"], "range": v["range"]}, FULL)
    p = toolchain.run(code, path=[str(Path(B.__file__).parents[2])], timeout=600)
    viper, t_full, t_small = p.stdout.split()
    wins_small = B.windows(1880)
    out["unix_viper_s"] = int(t_full) / 1e6 if viper == "True" else None
    out["unix_python_s"] = int(t_small) / 1e6 / wins_small * B.windows(FULL)
    if chip:
        out.update(_chip(doc))
    return out


def _chip(doc: dict) -> dict:
    from texelpad.deploy.install import deploy
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico, why_not
    why = why_not()
    if why:
        return {"chip": "skipped: %s" % why}
    emu = EmulatedPico()
    emu.start()
    try:
        with connect(emu.port, check=False, import_image=False) as b:
            deploy(b)
        with connect(emu.port, timeout=300) as b:
            if not b.status().get("running"):
                b.start("pico", None)
            b.push({"regions": [{"start_mm": 0, "end_mm": 101.76,
                                 "texture": {"kind": "constant", "level": 0.5}}]})
            res = {}
            for mm in (50.88, 101.76):
                try:
                    st = b.push({"regions": [D.region(doc, 1, 0, mm)]})
                    res["chip_build_%gmm_s" % mm] = st["last_push"]["build_us"] / 1e6
                    res["chip_validate_%gmm_s" % mm] = st["last_push"]["validate_us"] / 1e6
                    b.push({"regions": [{"start_mm": 0, "end_mm": 101.76,
                                         "texture": {"kind": "constant", "level": 0.5}}]})
                except ValueError as e:
                    res["chip_build_%gmm_s" % mm] = "refused: %s" % e
            return res
    finally:
        emu.stop()


def sizes() -> dict:
    from texelpad.link.protocol import scene_text
    doc = D.design("pink", 0.04)
    scene = {"regions": [D.region(doc, 1, 0, 101.76)]}
    return {"brush_json_bytes": len(json.dumps(doc)), "brush_binary_bytes": len(D.to_bytes(doc)),
            "region_sent_bytes": len(scene_text(scene)), "map_u16_bytes": 2 * FULL}


def _ratios(doc: dict, fitted: dict) -> dict:
    # wavenumbers 1 .. NYQ - 1 (the Nyquist bin is real: m_NYQ = 2 A |cos phi|,
    # brush/transform.py)
    ks = np.array(fitted["k"][1:B.NYQ]) / np.array(doc["k"][1:B.NYQ])
    lam = np.array(fitted["lam"][1:B.NYQ]) / np.array(doc["lam"][1:B.NYQ])
    q = lambda a: [round(float(np.percentile(a, p)), 3) for p in (50, 5, 95)]   # noqa: E731
    return {"lam": q(lam), "k": q(ks), "mean_lam": round(fitted["lam"][0] / doc["lam"][0], 3)}


def round_trip(screens: int = 10) -> dict:
    out = {}
    for shape in ("white", "pink", "brown"):
        for k in (2.0, 5.0):
            doc = D.design(shape, 0.03, k=k)
            maps = [D.paint(doc, s, FULL) / 65535.0 for s in range(screens)]
            out["%s k=%g" % (shape, k)] = _ratios(doc, D.fit(maps, "amplitude"))
            print("  round trip %-12s %s" % ("%s k=%g" % (shape, k), out["%s k=%g" % (shape, k)]),
                  file=sys.stderr, flush=True)
    return out


def textures() -> dict:
    """Maps we have -> fitted brush -> painted (10 screens) -> refitted."""
    import texel
    from texelpad.analysis.encoder import reference_map
    maps = {"pink": np.asarray(reference_map("pink", FULL), float),
            "sawtooth": np.asarray(reference_map("sawtooth", FULL), float),
            "texel 6 dB, -15 dB": np.array(texel.render_u16(
                {"pitch_db": 6.0, "irregularity_db": -15.0, "seed": 3, "length_samples": FULL,
                 "v": 2}), float) / 65535.0}
    out = {}
    for name, m in maps.items():
        doc = D.fit([m], "amplitude", name=name)
        painted = [D.paint(doc, s, FULL) / 65535.0 for s in range(10)]
        re = D.fit(painted, "amplitude")
        out[name] = {"map": m, "brush": doc, "painted": painted[0], "refit": re,
                     "ratios": _ratios(doc, re)}
    return out


def figure(tex: dict, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from texelpad.brush.transform import wavelengths_mm
    wl = wavelengths_mm()[1:] * 1000
    n = int(10 / 0.0053)
    x = np.arange(n) * 0.0053
    fig, axes = plt.subplots(len(tex), 2, figsize=(10, 2.4 * len(tex)),
                             gridspec_kw={"width_ratios": [2.2, 1]})
    for row, (name, t) in zip(axes, tex.items()):
        row[0].plot(x, t["map"][:n], lw=0.6, color="0.35", label="original")
        row[0].plot(x, t["painted"][:n] - 1.1, lw=0.6, color="C0", label="painted (seed 0)")
        row[0].set_yticks([])
        row[0].set_title(name, fontsize=9, loc="left")
        row[0].legend(fontsize=7, loc="upper right", ncol=2)
        row[1].loglog(wl, t["brush"]["lam"][1:], lw=1, color="0.35", label="fitted to the original")
        row[1].loglog(wl, t["refit"]["lam"][1:], lw=1, color="C0", ls="--",
                      label="refitted to 10 paintings")
        row[1].invert_xaxis()
        row[1].legend(fontsize=7)
        row[1].set_ylabel("scale lam", fontsize=8)
    axes[-1][0].set_xlabel("position (mm), first 10 mm")
    axes[-1][1].set_xlabel("wavelength (um)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.brush_paint", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--chip", action="store_true", help="also the emulated RP2040 (~2 min)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure", metavar="PATH")
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    print("synthesis of a full-screen brush region (19,200 samples, %d windows):"
          % B.windows(FULL))
    syn = synthesis(a.chip)
    for k, v in syn.items():
        print("  %-26s %s" % (k, "%.3f s" % v if isinstance(v, float) else v))
    sz = sizes()
    print("bytes: brush %(brush_json_bytes)d as JSON, %(brush_binary_bytes)d binary; the region as "
          "sent %(region_sent_bytes)d; the map it paints %(map_u16_bytes)d" % sz)
    print("round trip, designed brushes painted over 10 screens and refitted (fitted / designed "
          "at wavenumbers 1..%d: median [5th, 95th percentile]):" % (B.NYQ - 1))
    rt = round_trip()
    for k, v in rt.items():
        print("  %-12s scale %s  shape %s  mean's scale %s" % (k, v["lam"], v["k"], v["mean_lam"]))
    print("maps we have -> brush -> 10 paintings -> refitted (refitted / fitted):")
    tex = textures()
    for k, v in tex.items():
        r = v["ratios"]
        print("  %-20s scale %s  shape %s  mean's scale %s" % (k, r["lam"], r["k"], r["mean_lam"]))
    if a.figure:
        figure(tex, a.figure)
        print("wrote", a.figure)
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"synthesis": syn, "sizes": sz, "round_trip": rt,
                       "textures": {k: v["ratios"] for k, v in tex.items()}}, f, indent=1)
    print("(%.0f s)" % (time.perf_counter() - t0))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
