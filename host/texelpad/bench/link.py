"""`texelpad bench-link`: what the link costs, measured on the virtual board
(the device image under the MicroPython unix port, on a pty, playing in real
time while the host talks to it).

- deploy: the whole image into an empty flash (cold), then again with
  nothing changed (warm: the hash check alone);
- push latency: host call -> the board's status confirming the new scene
  plays (Board.push: host-side check, status, push, swap, status back);
- bytes on the wire per texture change, against the original lab's 76,800
  (two 19,200 x int16 maps over serial per change, docs/background.md §4);
- the soak: every push acknowledged with the scene that was sent, and the
  board's free memory (after its gc.collect) across the pushes: its trend
  must not go down.
"""
from __future__ import annotations

import statistics
import time
from typing import Any, Callable

from ..link.transport import LinkError

LAB_BYTES_PER_CHANGE = 2 * 19200 * 2       # two int16 maps of 19,200 samples


def _pct(xs: list[float], q: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * (len(s) - 1) + 0.5))]


def slope_per_push(ys: list[float]) -> float:
    """Least-squares slope of ys against their index (bytes per push)."""
    n = len(ys)
    if n < 2:
        return 0.0
    mx = (n - 1) / 2
    my = sum(ys) / n
    sxx = sum((i - mx) ** 2 for i in range(n))
    return sum((i - mx) * (y - my) for i, y in enumerate(ys)) / sxx


def _board(chip: str | None, deploy: bool) -> Any:
    """The board to measure, not started yet: the unix-port virtual board
    (its `with` starts it) or the emulated chip (sim/emulated.py; started
    by run())."""
    if chip:
        from ..sim.emulated import EmulatedPico
        return EmulatedPico()
    from ..sim.virtual import VirtualBoard
    return VirtualBoard(image=None if deploy else "source")


def run(pushes: int = 200, deploy: bool = True,
        progress: Callable[[str], None] | None = None, chip: str | None = None) -> dict[str, Any]:
    """chip "rp2040": on the emulated Pico (its figures: the host's wall time
    for the link, the chip's own clock for what the board reports)."""
    from ..link.board import connect
    from ..sim.virtual import stop_on_signals
    say = progress or (lambda m: None)
    res: dict[str, Any] = {"pushes": pushes, "chip": chip}
    timeout = 60.0 if chip else 10.0        # the emulator runs ~3x slower than a chip
    if chip:
        deploy = True                       # its flash starts empty
    # SIGTERM/SIGHUP unwind like Ctrl-C: the board's interpreter and its
    # temporary flash go with it
    with stop_on_signals(), _board(chip, deploy) as vb:
        if chip:
            vb.start()                      # boots the firmware, waits for its port
        if deploy:
            res.update(_deploys(vb.port, timeout, say))
        with connect(vb.port, timeout=timeout) as b:
            if chip:
                t0 = time.perf_counter()
                b.start("pico")
                res["start_s"] = time.perf_counter() - t0
            else:
                b.start("virtual", None, realtime=True)
            display = b.status()["display"]
            t_all = time.perf_counter()
            lat, sent, recv, mem, acked, build = _soak(b, pushes, say if progress else None)
            res["soak_s"] = time.perf_counter() - t_all
            st = b.status()
            try:
                res.update(_upload(b, display, say))
            except LinkError as e:          # a measured outcome too: say it, do not crash
                res["upload_error"] = str(e)
                res["mem_free_at_upload"] = b.status()["mem_free"]
                say("upload refused: %s" % e)
            res.update(_formats(b, display, say))
            # one texture as the bytes of its JSON text alone (what the scene
            # costs on the wire, without the code around it)
            from ..link.board import full_screen_texel
            from ..link.protocol import scene_text
            one = scene_text(full_screen_texel({"pitch_db": 6.3, "irregularity_db": -12.9,
                                             "seed": 7}, display))
    n = max(1, len(mem) // 10)
    res.update({
        "acked": acked, "faults": st["faults"], "overruns": st["overruns"],
        "refreshes": st["refreshes"],
        "push_ms_median": 1e3 * statistics.median(lat), "push_ms_p95": 1e3 * _pct(lat, 0.95),
        "push_ms_max": 1e3 * max(lat),
        "bytes_sent_per_push": statistics.median(sent),
        "bytes_received_per_push": statistics.median(recv),
        "scene_literal_bytes": len(one),
        "lab_bytes_per_change": LAB_BYTES_PER_CHANGE,
        "mem_free_first": statistics.median(mem[:n]), "mem_free_last": statistics.median(mem[-n:]),
        "mem_free_min": min(mem), "mem_free_slope_per_push": slope_per_push(mem),
        "board_push_ms_median": statistics.median(build) / 1e3 if build else None,
        "board_push_ms_max": max(build) / 1e3 if build else None,
        "worst_refresh_us": st["worst_us"], "rate_hz": st["rate_hz"],
    })
    return res


def _deploys(port: str, timeout: float, say: Callable[[str], None]) -> dict[str, Any]:
    """texelpad deploy twice, timed: cold (the board's flash empty) and warm
    (nothing changed)."""
    from ..deploy.install import deploy as do_deploy
    from ..link.board import connect
    res: dict[str, Any] = {}
    for label in ("cold", "warm"):
        with connect(port, check=False, import_image=False, timeout=timeout) as b:
            t0 = time.perf_counter()
            rep = do_deploy(b)
            res["deploy_%s_s" % label] = time.perf_counter() - t0
            res["deploy_%s" % label] = rep
        say("deploy %s: %.2f s, %d files written, %d bytes"
            % (label, res["deploy_%s_s" % label], rep["written"], rep["bytes_written"]))
    return res


def _soak(b: Any, pushes: int, say: Callable[[str], None] | None
          ) -> tuple[list[float], list[int], list[int], list[float], int, list[int]]:
    """`pushes` full-screen texel pushes, each a new pitch and seed: their
    latencies (s), bytes sent and received, mem_free, how many the board
    acknowledged as asked, and the board's own build + swap times (us)."""
    lat: list[float] = []
    sent: list[int] = []
    recv: list[int] = []
    mem: list[float] = []
    build: list[int] = []
    acked = 0
    for i in range(pushes):
        params = {"pitch_db": round(-5.0 + 20.0 * (i % 97) / 97, 3),
                  "irregularity_db": -12.9, "seed": i}
        s0, r0 = b.link.sent, b.link.received
        t0 = time.perf_counter()
        st = b.push_texel(params)
        lat.append(time.perf_counter() - t0)
        sent.append(b.link.sent - s0)
        recv.append(b.link.received - r0)
        reg = st["scene"]["regions"]
        if (st["pushes"] == i + 2 and len(reg) == 1 and reg[0]["seed"] == i
                and reg[0]["pitch_db"] == params["pitch_db"] and st["faults"] == 0):
            acked += 1
        # the heap after the old scene's collection, which comes after the push's answer
        # (texel.wire.reply): the answer itself carries no figure (mem_free None)
        mem.append(b.status()["mem_free"])
        if st.get("last_push"):             # the board's own clock
            build.append(st["last_push"]["build_us"] + st["last_push"]["swap_us"])
        if say and (i + 1) % max(1, pushes // 10) == 0:
            say("push %d/%d: median %.1f ms" % (i + 1, pushes, 1e3 * statistics.median(lat)))
    return lat, sent, recv, mem, acked, build


def _upload(b: Any, display: dict[str, Any], say: Callable[[str], None],
            repeats: int = 5) -> dict[str, Any]:
    """A full-screen samples map (display positions of uint16, 19,200 on the
    TPaD: texel.runtime.kinds.samples.MAX_SAMPLES) pushed as an upload, `repeats`
    times: seconds and bytes per push, and the board's worst refresh over
    them (the refresh keeps running in real time meanwhile)."""
    import random
    from ..link.protocol import UPLOAD_PIECE
    n = min(display["positions"], 19200)
    total = display["positions"] * display["dx_um"] / 1000.0
    rnd = random.Random(7)
    st = b.status()
    worst0 = st["worst_us"]
    times, sent = [], []
    for k in range(repeats):
        u16 = [rnd.randrange(65536) for _ in range(n)]
        scene = {"regions": [{"start_mm": 0, "end_mm": round(total, 6),
                              "texture": {"kind": "samples", "u16": u16}}]}
        s0 = b.link.sent
        t0 = time.perf_counter()
        try:
            b.push(scene)
        except LinkError as e:
            raise LinkError("upload %d of %d: %s" % (k + 1, repeats, e)) from None
        times.append(time.perf_counter() - t0)
        sent.append(b.link.sent - s0)
        if b.scene_source()["regions"][0]["texture"]["u16"] != u16:
            raise RuntimeError("bench-link: the board plays another map than the one uploaded")
    st = b.status()
    say("upload %d values: median %.2f s" % (n, statistics.median(times)))
    return {"upload_values": n, "upload_piece_values": UPLOAD_PIECE,
            "upload_s_median": statistics.median(times), "upload_s_max": max(times),
            "upload_bytes_sent": statistics.median(sent), "upload_repeats": repeats,
            "upload_worst_refresh_us_before": worst0, "upload_worst_refresh_us": st["worst_us"],
            "upload_overruns": st["overruns"]}


# Push to playing, by texture format: what the board spends between the
# request's arrival and the swap (status()["last_push"]: validate, build, swap
# on its own clock) plus parsing the scene's JSON text (timed on the board
# with json.loads of the same text, as the request does before the call).
PUSH_GOALS_MS = {"texel": 20.0, "regions16": 50.0}      # issue 10, on an RP2040


def regions16(display: dict[str, Any], v: int, seed: int) -> dict[str, Any]:
    """16 equal texel regions over the display, each its own texture."""
    total = display["positions"] * display["dx_um"] / 1000.0
    w = total / 16
    regs = []
    for k in range(16):
        regs.append({"start_mm": round(k * w, 6), "end_mm": round((k + 1) * w, 6),
                     "texture": {"kind": "texel", "pitch_db": round(-5.0 + 1.5 * k, 3),
                                 "irregularity_db": -12.9, "seed": seed * 16 + k, "v": v}})
    return {"regions": regs}


def _formats(b: Any, display: dict[str, Any], say: Callable[[str], None],
             repeats: int = 5) -> dict[str, Any]:
    from ..link.board import full_screen_texel
    from ..link.protocol import scene_text
    out: dict[str, Any] = {}
    for what in ("texel", "regions16"):
        for v in (1, 2):
            rows = []
            for k in range(repeats):
                if what == "texel":
                    scene = full_screen_texel({"pitch_db": round(6.3 + 0.1 * k, 3),
                                               "irregularity_db": -12.9, "seed": 100 + k,
                                               "v": v}, display)
                else:
                    scene = regions16(display, v, 100 + k)
                st = b.push(scene)
                lp = st["last_push"]
                rows.append((lp.get("validate_us", 0), lp["build_us"], lp["swap_us"]))
            lit = scene_text(scene)
            parse_us = b.link.eval("import time, json\n_x = %r\n_t = time.ticks_us()\n"
                                   "_s = json.loads(_x)\n"
                                   "print(time.ticks_diff(time.ticks_us(), _t))\ndel _s, _x" % lit)
            tot = [sum(r) / 1000.0 for r in rows]
            key = "%s_v%d" % (what, v)
            out[key] = {"validate_ms": statistics.median(r[0] for r in rows) / 1000.0,
                        "build_ms": statistics.median(r[1] for r in rows) / 1000.0,
                        "swap_ms": statistics.median(r[2] for r in rows) / 1000.0,
                        "parse_ms": None if parse_us is None else parse_us / 1000.0,
                        "board_ms_median": statistics.median(tot), "board_ms_max": max(tot),
                        "literal_bytes": len(lit), "repeats": repeats}
            say("%s format %d: %.1f ms on the board (median of %d)"
                % (what, v, statistics.median(tot), repeats))
    return {"formats": out}


def _ms(v: float | None) -> str:
    return "-" if v is None else "%.1f" % v


def table(res: dict[str, Any]) -> str:
    lines = ["texelpad bench-link: %s" % (
        "the emulated %s on a pty (rp2040js, MicroPython firmware; wall time on this host, "
        "board figures in the chip's own time)" % res["chip"].upper() if res.get("chip") else
        "the virtual board on a pty (MicroPython unix port, real time)")]
    if "deploy_cold_s" in res:
        for label in ("cold", "warm"):
            rep = res["deploy_%s" % label]
            lines.append("deploy %-4s  %6.2f s  %2d of %d files written, %s bytes" % (
                label, res["deploy_%s_s" % label], rep["written"], rep["files"],
                format(rep["bytes_written"], ",")))
    lines += [
        "push        median %.1f ms, p95 %.1f ms, max %.1f ms over %d pushes (host call -> board "
        "confirms the new scene)" % (res["push_ms_median"], res["push_ms_p95"],
                                     res["push_ms_max"], res["pushes"]),
        "wire        %d bytes sent, %d received per push (code + scene + status); the scene's "
        "JSON alone %d bytes; the original lab: %s bytes per change (%.0fx more than we send)"
        % (res["bytes_sent_per_push"], res["bytes_received_per_push"],
           res["scene_literal_bytes"], format(res["lab_bytes_per_change"], ","),
           res["lab_bytes_per_change"] / max(1, res["bytes_sent_per_push"])),
        "board       a full-screen texel push on the board itself (validate, plan, swap): "
        "median %s ms, max %s ms (its own clock)" % (
            _ms(res.get("board_push_ms_median")), _ms(res.get("board_push_ms_max"))),
    ]
    for key, f in sorted(res.get("formats", {}).items()):
        what, v = key.rsplit("_v", 1)
        goal = PUSH_GOALS_MS.get(what)
        tot = f["board_ms_median"] + (f["parse_ms"] or 0.0)
        lines.append(
            "to playing  %-27s %7.1f ms = parse %.1f + validate %.1f + build %.1f + swap %.1f "
            "(median of %d, max %.1f; JSON %d bytes)%s" % (
                ("full-screen texel" if what == "texel" else "16 texel regions")
                + ", format %s" % v, tot, f["parse_ms"] or 0.0, f["validate_ms"], f["build_ms"],
                f["swap_ms"], f["repeats"], f["board_ms_max"] + (f["parse_ms"] or 0.0),
                f["literal_bytes"],
                "" if goal is None or not res.get("chip") else
                "  goal <= %.0f ms: %s" % (goal, "met" if tot <= goal else "NOT met")))
    lines += [
        "soak        %d/%d pushes acknowledged with the scene sent; %d faults, %d overruns over "
        "%s refreshes; worst refresh %s us, rate %s Hz"
        % (res["acked"], res["pushes"], res["faults"], res["overruns"],
           format(res["refreshes"], ","), res.get("worst_refresh_us"), res.get("rate_hz")),
        ("upload      refused by the board: %s" % res["upload_error"]) if "upload_error" in res
        else "upload      %s uint16 values (a full-screen samples map) in pieces of %s: median "
        "%.2f s, max %.2f s, %s bytes sent per push; worst refresh %d us (before: %d us), %d "
        "overruns" % (format(res["upload_values"], ","), format(res["upload_piece_values"], ","),
                      res["upload_s_median"], res["upload_s_max"],
                      format(int(res["upload_bytes_sent"]), ","), res["upload_worst_refresh_us"],
                      res["upload_worst_refresh_us_before"], res["upload_overruns"]),
        "memory      free after each push: first tenth %s, last tenth %s, min %s bytes; trend "
        "%+.2f bytes/push" % (format(int(res["mem_free_first"]), ","),
                              format(int(res["mem_free_last"]), ","),
                              format(int(res["mem_free_min"]), ","),
                              res["mem_free_slope_per_push"]),
    ]
    return "\n".join(lines)
