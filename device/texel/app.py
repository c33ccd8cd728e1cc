# The user API, the same on every board (docs/device-api.md; what a person
# types at the REPL or through mpremote, and what texelpad.link calls):
#   texel.app.start(board=None, scene=None)  -> status dict (board: a board
#                                               file's name; None: this board's own)
#   texel.app.push(scene)                    -> status dict (raises ValueError,
#                                               and the old scene keeps playing)
#   texel.app.full_screen(texture)           -> a scene: texture over the whole display
#   texel.app.status()                       -> dict
#   texel.app.stream(rate_hz=125)            -> divider (refreshes per sample; 0 stops)
#   texel.app.telemetry()                    -> ([(t_us, position, amplitude), ...], lost)
#   texel.app.stop()
#   texel.app.run_loop(seconds=None)         CircuitPython: the paced loop (below)
#   texel.app.serve(idle=True, repl=False)   CircuitPython: the paced loop that also
#                                               answers the host's link (texel/serve.py)
# What the host's link calls besides (uploads, JSON scenes, base64 maps, the
# virtual board's time and finger) is texel.wire; the contract's version is
# texel.protocol.PROTOCOL.
# On rp2/stm32 start() returns at once with the refresh running in a hard
# timer IRQ, so the REPL stays free. On the virtual board time is stepped:
# texel.wire.advance(ms) runs the refresh (or start(..., realtime=True)).
# CircuitPython has no timer IRQ (refresh mode "loop", also selectable on
# other ports): start() returns without a timer and run_loop() runs a paced
# loop that measures and reports its own rate.
import gc
import sys
from . import __version__, compat
from .protocol import PROTOCOL
from .runtime import scene as _scene
from .runtime.duty import DutyLaw
from .runtime.refresh import Refresh
from .runtime.sensor import make_sensor


# The study's split screen (docs/background.md §5): a reference texture left, a texel
# rendering right. Played when start() gets no scene. Its texel texture is
# format 2 (the same map on every board, and a fast start on an RP2040).
DEFAULT_SCENE = {"regions": [
    {"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},
    {"start_mm": 50.88, "end_mm": 101.76,
     "texture": {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7,
                 "v": 2}}]}



def _default_scene(d):
    """DEFAULT_SCENE; on CircuitPython its texel half over the whole display
    `d`. CircuitPython's heap also holds every module's bytecode (compiled
    from source at import): with the split screen's 19 KB 4sin map playing,
    ~15 KB were left, and a status, a push or a deploy's survey failed for
    memory there (tests/host/test_emulated_cpy.py; bench/results/
    circuitpython.txt). The format-2 texel half costs a 3 KB plan."""
    if compat.IMPL != "circuitpython":
        return DEFAULT_SCENE
    return {"regions": [{"start_mm": 0, "end_mm": d["positions"] * d["dx_um"] / 1000.0,
                         "texture": DEFAULT_SCENE["regions"][1]["texture"]}]}


_rt = None            # the running runtime (one per board)


class _Runtime:
    """What start() sets up and the rest of this module reads: one per board."""

    def __init__(self):
        self.board = None           # the board file, checked (runtime/boards.py)
        self.start_opts = None      # {"realtime", "fast"} as start() was called
        self.hw = None              # the hardware backend (hw/<port>.py)
        self.hz = 0                 # refreshes per second (the board file's)
        self.period_us = 0          # 1e6 // hz
        self.law = None             # the duty law (runtime/duty.py)
        self.sensor = None          # the finger sensor (runtime/sensor.py)
        self.refresh = None         # Refresh or FastRefresh (runtime/refresh*.py)
        self.mode = ""              # "python", "viper" or "viper-irq"
        self.started_us = 0         # ticks() at start
        self.ticks = None           # the clock (compat.ticks_us / ticks_diff)
        self.diff = None
        self.pace_clock = None      # the paced loop's clock, None: ticks (runtime/pace.py)
        self.pacer = None           # serve()'s schedule, while it serves
        self.last_push = None       # the last push's timings (status()["last_push"])
        self.tel_tail = 0           # telemetry read up to here
        self.pushes = 0
        self.collect_due = False    # a push left the old scene as garbage (tidy())
        self.loop_mode = False      # run() drives the loop instead of a timer
        self.loop = None            # the loop mode's last figures


_backend = compat.backend      # port -> its hardware class (compat.PORT_TABLE)


def _boards():
    # imported where used: a lean port forgets it after a start (_forget_builders)
    from .runtime import boards
    return boards


# Where the code itself takes the heap (compat.LEAN: CircuitPython compiles
# the sources into RAM; stock MicroPython loads deploy's .mpy into it), tidy()
# forgets the board files' checks after a start (runtime.boards, 13 KB on
# CircuitPython, 17 KB on a stock Pico: only start() needs them; the next start
# imports them again). No module a playing board keeps imports it at its top
# (tests/runtime/test_lean.py).
LEAN = compat.LEAN


# The brush painter (gen/brush.py: 22 KB of a stock Pico's heap with its tables)
# is forgotten too while no brush plays: after a brush a stock Pico had no room
# left for a full-screen map (bench/firmware.py --stock). A brush push imports it
# again: loading .mpy. Not on CircuitPython, which would compile its 48 KB source
# again at each such push (forgetting the generator there: docs/runtime.md "The
# heap"); not measured there.
_PAINTER = ("texel.gen.brush", "texel.gen.brush_viper", "texel.gen.brush_parts")
FORGET_PAINTER = LEAN and compat.IMPL != "circuitpython"


def _forget_builders():
    """Forget the board files' checks and, while no brush plays, the brush
    painter (LEAN, above): True when any of them was loaded."""
    gone = False
    if "texel.runtime.boards" in sys.modules:
        compat.forget("texel.runtime.boards")
        gone = True
    if FORGET_PAINTER and _PAINTER[0] in sys.modules and not _plays("brush"):
        for name in _PAINTER:
            compat.forget(name)
        gone = True
    return gone


def _plays(kind):
    """Whether a region of the playing scene is of kind `kind`."""
    sc = _rt.refresh.scene if _rt is not None else None
    return sc is not None and _has(sc.source, kind)


def _has(source, kind):
    """Whether a region of scene `source` is of kind `kind`."""
    for r in source["regions"]:
        if r["texture"]["kind"] == kind:
            return True
    return False


def _fits(board):
    """None when this board can run board file `board`, else why not: the
    firmware's port (runtime.boards.fits), then the backend's import."""
    why = _boards().fits(board)
    if why is None:
        try:
            _backend(board["port"])
        except ImportError as e:
            why = ("board file %r needs the %s backend, which this board does not have (%s)"
                   % (board["name"], board["port"], e))
    return why


def _make_hw(board, opts):
    Hw = _backend(board["port"])
    if board["port"] == "virtual":
        return Hw(board, **opts)
    return Hw(board)


def fitting():
    """Names of the board files on this board that it can run."""
    return _boards().fitting(_fits)


def _reader(hw, i):
    if hasattr(hw, "adc_reader"):
        return hw.adc_reader(i)
    return lambda: hw.adc_read(i)


def _checked_board(board_name):
    """Board file `board_name` loaded and checked as start() needs it (it
    exists and is valid, its refresh mode is built, it fits this firmware):
    the board dict, or ValueError saying what fits. Touches nothing that
    plays."""
    playing = "; the display keeps playing" if _rt is not None else ""
    try:
        board = _boards().load(board_name)
    except ValueError as e:
        raise ValueError(str(e) + playing)
    if board["refresh"]["mode"] == "core1_viper":
        raise ValueError("board %r: refresh.mode 'core1_viper' is not implemented yet; use "
                         "'timer_irq' (a hard timer IRQ on core 0) or 'loop'%s"
                         % (board["name"], playing))
    why = _fits(board)
    if why is not None:
        raise ValueError("%s; board files that fit: %s%s" % (
            why, ", ".join(fitting()) or "none", playing))
    return board


def default_board(config=True):
    """The board file start() plays when given none: /texelpad.json's
    "board" (what `texelpad scene boot` wrote; config=False skips it), else
    the texelpad firmware's own (/rom/firmware.json), else the port's
    (compat.PORT_TABLE) - the board main.py starts at power-up."""
    import json
    for path in ((CONFIG, "/rom/firmware.json") if config else ("/rom/firmware.json",)):
        try:
            with open(path) as f:
                v = json.loads(f.read()).get("board")
            if isinstance(v, str) and v:
                return v
        except (OSError, ValueError, AttributeError):
            pass
    return compat.default_board()


# The power-up file (`texelpad scene boot` writes it). The unix port (the
# virtual board) has the host's filesystem: its "/" is its flash folder, the
# working directory, so the path is relative there (the rule of
# texelpad.deploy.install.on_board).
CONFIG = "texelpad.json" if sys.platform in compat.UNIX_PLATFORMS else "/texelpad.json"


def full_screen(texture):
    """A scene of one region, `texture` over the whole display of the board
    playing (or of the default board when nothing plays):
        app.push(app.full_screen({"kind": "bump", "width_mm": 8}))"""
    if _rt is not None:
        d = _rt.board["display"]
    else:
        d = _boards().load(default_board())["display"]
    return {"regions": [{"start_mm": 0, "end_mm": d["positions"] * d["dx_um"] / 1000.0,
                         "texture": texture}]}


def start(board_name=None, scene=None, realtime=False, fast=None, report=True, **hw_opts):
    """Start the display on board `board_name` (a file in boards/; None:
    this board's own, default_board()) playing `scene` (default: the
    study's split screen). Stops a running display
    first - but only once everything that can be checked was (the board
    file, that it fits this firmware, the scene), and if the new start still
    fails, the display that played is started again. (A lean port whose
    heap has no room for the board checks beside the playing scene stops
    it before it loads them: compat.LEAN.) Returns status(), or
    None with report=False (main.py: status's full collection is ~30 ms of
    a stock Pico's power-up, which a friendly Ctrl-D waits for).

    fast: the fused refresh (runtime/refresh_fast.py: the C core's, or
    refresh_viper.py's in viper) - default on wherever
    the port has viper and the sensor is a linear ADC; on an RP2040 its IRQ
    then reads the ADC and writes the PWM compare register itself."""
    name = default_board() if board_name is None else board_name
    prev = _playing()
    checked = None
    try:
        # the board file and the scene checked before the hardware is touched:
        # a bad one changes nothing
        checked = _checks(name, scene)
    except MemoryError:
        # A lean port (compat.LEAN: the board checks, 17 KB of a stock Pico's heap,
        # and a kind's code load into the heap again) with no room for them beside
        # the playing scene: the display stops first (below, outside this handler:
        # its exception holds the frames), and plays again if the start fails
        if prev is None:
            raise
    if checked is None:
        stop()
        try:
            checked = _checks(name, scene)
        except Exception as e:
            _failed(name, e, prev)
    board, canonical = checked
    stop()          # (nothing running: disarms what a soft reset left, hw/rp2.py clear_stale_tick)
    try:
        try:
            _start(board, canonical, realtime, fast, hw_opts)
        except MemoryError:
            # once more after a full collection: a stale pointer on the C
            # stack (the GC is conservative) can hold the old display's
            # buffers for one more cycle
            gc.collect()
            _start(board, canonical, realtime, fast, hw_opts)
    except Exception as e:
        _failed(board["name"], e, prev)
    return status() if report else None


def _checks(name, scene):
    """(board, canonical scene) for start(), or ValueError."""
    board = _checked_board(name)
    if scene is None:
        scene = _default_scene(board["display"])
    return board, _scene.validate(scene, board["display"])


def _playing():
    """(board name, scene source, start options) of the display that plays,
    or None: what start() plays again when a new start fails. Only the
    source: the old maps go with stop()."""
    if _rt is None:
        return None
    sc = _rt.refresh.scene
    return (_rt.board["name"], sc.source if sc is not None else None, _rt.start_opts)


def _failed(name, e, prev):
    """start() failed after the display stopped: the display that played
    plays again where it can; ValueError, one line for the host whatever the
    hardware raised (a ValueError crosses the link as text; anything else
    would be a board traceback)."""
    why = str(e) if isinstance(e, ValueError) else "%s: %s" % (type(e).__name__, e)
    now = "the display is off"
    if prev is not None:
        try:
            start(prev[0], prev[1], **prev[2])
            if prev[1] is None:         # it played idle (no scene): so again
                _rt.refresh.swap(None)
            now = "the display plays what it played before (board %r)" % prev[0]
        except Exception:
            pass
    raise ValueError("board %r did not start (%s); %s" % (name, why, now))


def _start(board, canonical, realtime, fast, hw_opts):
    global _rt
    mode = board["refresh"]["mode"]
    hw = _make_hw(board, hw_opts)
    hw.off()
    rt = None
    try:
        rt = _Runtime()
        rt.board = board
        rt.start_opts = {"realtime": realtime, "fast": fast}
        rt.start_opts.update(hw_opts)
        rt.hw = hw
        rt.hz = board["refresh"]["hz"]
        rt.period_us = 1000000 // rt.hz
        rt.law = DutyLaw(hw.top, board["carrier"]["duty_cap"])
        s = board["sensor"]
        npins = 2 if s["kind"] == "adc_ratio" else 1
        reads = [_reader(hw, i) for i in range(npins)]
        rt.sensor = make_sensor(s, reads, board["display"]["positions"], rt.hz)
        if hasattr(hw, "ticks_us"):
            ticks, diff = hw.ticks_us, hw.ticks_diff
        else:
            ticks, diff = compat.ticks_us, compat.ticks_diff
        callback = _make_refresh(rt, board, reads, ticks, diff, fast, realtime)
        rt.started_us = ticks()
        rt.ticks = ticks
        # the paced loop's clock (runtime/pace.py clock_of): a board with a clock of
        # its own (the virtual board's stepped one) paces on its ticks (None),
        # the others on compat's (milliseconds on CircuitPython)
        rt.pace_clock = None if hasattr(hw, "ticks_us") else compat.PACE_CLOCK
        rt.diff = diff
        rt.last_push = None
        rt.tel_tail = 0
        rt.pushes = 0
        _rt = rt
        _install(canonical)
        rt.loop_mode = mode == "loop"
        if not rt.loop_mode:
            # the rate counts from here: building the first scene (seconds on
            # a Pico) is no time the refresh ran
            rt.started_us = ticks()
            hw.start(callback, rt.hz)
            if (callback is not rt.refresh.step and "interrupt" in (getattr(hw, "irq_source", "")
                                                                   or "")):
                rt.refresh.irq_code = getattr(callback, "engine", None)
            if realtime and hasattr(hw, "run_realtime"):
                hw.run_realtime()
    except BaseException:
        # also KeyboardInterrupt (Ctrl-C inside the first build, or a host that
        # gave up and interrupts): no half-started runtime that says "running"
        # but never refreshes, no tick left armed; the display is off - and the
        # refresh's W zeroed once it has stopped (stop(): a stale slot naming it
        # would keep the scene's maps from start()'s try again)
        try:
            _halt(hw, rt)
        finally:
            hw.off()
            _rt = None
        raise


def _make_refresh(rt, board, reads, ticks, diff, fast, realtime):
    """rt.refresh and rt.mode for the board: the fused refresh (viper or the C
    core's) where it runs, else the Python one. Returns what the timer calls."""
    hw = rt.hw
    s = board["sensor"]
    idle = board["carrier"].get("idle_amplitude", 0)
    if fast is None:
        fast = compat.HAS_VIPER and s["kind"] == "adc_linear"
    callback = None
    if fast:
        try:
            from .runtime.refresh_fast import FastRefresh, irq_rp2, _engine
            # the refresh's machine code: the C core's, else the viper core (a
            # port without a native emitter cannot compile it)
            _engine()
        except (ImportError, SyntaxError):
            fast = False
    if fast:
        stm = None
        if board["refresh"]["mode"] == "timer_irq" and hasattr(hw, "stm32_registers"):
            # an STM32F2/F4/F7 (hw/stm32.py): the core reads ADC1 and writes the CCR itself,
            # taking the conversion the refresh before started - the finger one period
            # later, which the sensor's lead makes up (runtime/sensor.py, L)
            stm = hw.stm32_registers()
            if stm is not None:
                rt.sensor = make_sensor(dict(s, latency_us=s["latency_us"] + rt.period_us),
                                        reads, board["display"]["positions"], rt.hz)
        rt.refresh = FastRefresh(rt.sensor, rt.law, hw.set_duty, reads[0], ticks, diff,
                                 rt.period_us, idle, getattr(hw, "cost_ticks", None))
        rt.refresh.threaded = realtime and hasattr(hw, "run_realtime")
        regs = hw.direct_registers() if hasattr(hw, "direct_registers") else None
        if regs is not None:
            rt.refresh.use_rp2_registers(regs[0], regs[1], int(s["pins"][0]) - 26)
            callback = irq_rp2
        elif stm is not None:
            from .hw import stm32_irq
            from .runtime import refresh_fast
            rt.refresh.use_stm32_registers(*stm)
            callback = stm32_irq.arm(refresh_fast)
            rt.refresh.irq_code = stm32_irq.ENGINE
        rt.mode = "viper" if callback is None else "viper-irq"
    else:
        rt.refresh = Refresh(rt.sensor, rt.law, hw.set_duty, ticks, diff, rt.period_us, idle,
                             getattr(hw, "cost_ticks", None), getattr(hw, "cost_every", 1))
        rt.mode = "python"
    return rt.refresh.step if callback is None else callback


def _install(canonical, validate_us=0, checked=None):
    rt = _rt
    disp = rt.board["display"]
    idle = rt.board["carrier"].get("idle_amplitude", 0)
    # real time, also on the virtual board (whose ticks are stepped)
    clock = getattr(rt.hw, "cost_ticks", rt.ticks)
    t0 = clock()
    silent = None
    focus = _finger if PAINT_NEAR_FINGER else None       # (scene.build's focus)
    sc = _build_beside(rt, canonical, disp, idle, checked, focus)
    if sc is None:
        # (outside the failed build's frame: MicroPython's collector scans the stack
        # conservatively, and a slot there still naming the playing scene kept its
        # 20-38 KB alive through _make_room - measured on the unix port)
        sc = _make_room(rt, canonical, disp, idle, checked, focus)
        silent = True
    t1 = clock()
    old = rt.refresh.swap(sc)
    t2 = clock()
    # The old scene's buffers are garbage now. No collection here: it took 5-15 ms of
    # every answer on an RP2040 (more with a large scene live; bench/firmware.py). It
    # comes after the answer - tidy(), which texel.wire.reply runs once the host has
    # its reply - or with the allocator's own collection when a later allocation needs
    # the room.
    del old
    rt.collect_due = True
    rt.pushes += 1
    rt.last_push = {"validate_us": validate_us, "build_us": rt.diff(t1, t0),
                    "swap_us": rt.diff(t2, t1), "scene_bytes": sc.nbytes}
    if silent:
        rt.last_push["made_room"] = True        # the display was idle while it built
    return sc


# A push whose scene does not fit beside the one playing (runtime/scene.py OutOfMemory: e.g. a
# full-screen reference rendered into RAM while another plays, on a board without flash maps)
# is built in the playing scene's room: the display plays idle meanwhile (status()'s
# last_push: made_room; build_us is how long), the old scene is dropped and the new one built.
# If even that does not fit, the old scene is built again, plays on, and the push is refused
# saying so. This is what the refusal used to ask the user to do by hand ("push a small scene
# first"). False: refuse at once, the playing scene untouched throughout.
MAKE_ROOM = True


# A brush under the finger is painted from the finger outward (gen/brush_parts.py Painting,
# where the C painter has paint_part): the push swaps its scene in once the part
# around the finger is painted - what plays under the finger is the new brush then -
# and paints the rest part by part after the answer (tidy(); push() before it returns),
# each part on the side the finger is nearer: on the emulated Pico's firmware no sampled
# refresh under a finger sweeping at up to 228 mm/s read an unpainted sample
# (bench/brush_chase.py; docs/firmware.md). The unpainted rest plays amplitude 0
# meanwhile. False: every map whole before the swap.
PAINT_NEAR_FINGER = True


def _finger():
    """The display position under the finger now, -1 lifted."""
    return _rt.refresh.pos if _rt is not None else -1


def _paint_rest():
    """Finish what the playing scene's build left to paint (scene.build's
    focus): after a push's answer (tidy()), before push() returns, and before
    the next push builds (it may share the playing scene's maps)."""
    sc = _rt.refresh.scene if _rt is not None else None
    todo = getattr(sc, "painting", None)
    while todo:
        todo[0].finish()
        todo.pop(0)


def _build_beside(rt, canonical, disp, idle, checked, focus=None):
    """The new scene built beside the playing one (sharing what it can), or
    None when it does not fit there and MAKE_ROOM lets _make_room try."""
    room = MAKE_ROOM and rt.refresh.scene is not None     # a second try in more room
    try:
        return _scene.build(canonical, disp, idle_default=idle, checked=checked,
                            reuse=rt.refresh.scene, words=not room, focus=focus)
    except _scene.OutOfMemory:
        if not room:
            raise
    return None


def _drop_playing(rt):
    """Idle from the next refresh on; the playing scene's canonical source
    (what rebuilds it). A function of its own, so that no slot of the caller's
    frame still names the scene when the collector scans the stack."""
    return rt.refresh.swap(None).source


def _make_room(rt, canonical, disp, idle, checked, focus=None):
    source = _drop_playing(rt)
    gc.collect()
    try:
        return _scene.build(canonical, disp, idle_default=idle, checked=checked, focus=focus)
    except _scene.OutOfMemory as e:
        why = str(e)
    if LEAN and not _has(source, "brush"):
        # what the failed build loaded (a brush's painter: 22 KB of a stock Pico's
        # heap) goes before the old scene is built again: with it, a full-screen
        # reference no longer fitted back after a refused brush (bench/firmware.py
        # --stock), and the display played idle. (An old brush keeps it: _plays
        # cannot say so here, the display is idle.)
        _forget_builders()
    gc.collect()
    try:
        back = _scene.build(source, disp, idle_default=idle)
    except ValueError:
        raise _scene.OutOfMemory(why + "; not even in the playing scene's room, and that scene "
                                 "no longer fits either: the display plays idle, push a "
                                 "smaller scene")
    rt.refresh.swap(back)
    raise _scene.OutOfMemory(why + "; not even in the playing scene's room: that scene was "
                             "built again and plays on")


def push(scene):
    """Validate completely, build (render only what the regions use), then
    swap in between two refreshes. Any error raises ValueError and the
    current scene keeps playing untouched."""
    _push(scene)
    _paint_rest()
    # no collection before the answer (tidy()); and no heap figure in it: gc.mem_free()
    # walks the whole allocation table, 9 ms on an RP2040 (status() measures it)
    return status(collect=False)


def _push(scene):
    rt = _running()
    _paint_rest()
    compat.skip_holes()
    clock = getattr(rt.hw, "cost_ticks", rt.ticks)
    t0 = clock()
    try:
        # (the check inside: on a lean port it may import a kind's code, e.g. the
        # brush painter again, and the heap may have no room for it)
        checked = _scene.check(scene, rt.board["display"])
        _install(checked[0], rt.diff(clock(), t0), checked)
    except MemoryError:
        gc.collect()
        raise ValueError("scene does not fit in memory (%s); the current scene keeps playing"
                         % (compat.memory_words() or "the heap is full"))


def pushed(scene):
    """push() for the host's link (texel.wire.reply("pushed", ...)): the same work,
    answered with changes() only. The host merges that into the status it read
    before the push (texelpad.link.board: Board._send). The keys that do not
    change while texelpad runs are left out of the answer. Building and
    repr()-ing them took 2.5 ms of every answer on the emulated RP2040 (bench/request_parts.py)."""
    _push(scene)
    return changes()


def tidy():
    """Paint what the last push left to paint (_paint_rest), collect what
    it left (the old scene's buffers), if it left anything, and forget what
    LEAN says (_forget_builders):
    texel.wire.reply runs this after the host has its answer, and status()
    collects anyway. Returns True when it collected."""
    rt = _rt
    _paint_rest()
    lean = LEAN and _forget_builders()
    if not lean and (rt is None or not rt.collect_due):
        return False
    if rt is not None:
        rt.collect_due = False
    gc.collect()
    return True


def _running():
    if _rt is None:
        raise ValueError("texel.app is not running: call texel.app.start() first")
    return _rt


def status(collect=True):
    """What is playing and how the loop runs (a dict of literals); mem_free
    after a full collection, or None with collect=False (push's answer,
    which comes before any collection: tidy())."""
    rt = _rt
    if collect:
        if rt is not None:
            rt.collect_due = False
        if LEAN:
            _forget_builders()
        free = compat.heap_free()
    else:
        free = None
    st = {"protocol": PROTOCOL, "texel": __version__,
          "firmware": "%s %s" % (sys.implementation.name,
                                 ".".join(str(x) for x in sys.implementation.version[:3])),
          "ulab": compat.ulab_version(), "viper": compat.HAS_VIPER,
          "running": rt is not None, "mem_free": free}
    if rt is None:
        return st
    st.update({
        "board": rt.board["name"], "port": rt.board["port"], "refresh": rt.mode,
        "display": {"positions": rt.board["display"]["positions"],
                    "dx_um": rt.board["display"]["dx_um"]},
        "refresh_mode": rt.board["refresh"]["mode"],
        # the machine code the RP2040's refresh interrupt calls: "c" (the C
        # core's refresh) or "viper" (refresh_viper.core); None elsewhere
        "refresh_code": getattr(rt.refresh, "irq_code", None),
        "carrier_hz": rt.hw.freq_hz if hasattr(rt.hw, "freq_hz") else rt.board["carrier"]["freq_hz"],
        "pwm_top": rt.hw.top, "refresh_hz": rt.hz,
        "timed_every": getattr(rt.refresh, "cost_every", 1)})
    st.update(changes(free))
    return st


def changes(free=None):
    """The part of status() that a push or time changes (the rest stays as
    start() made it): what pushed() answers. free: its mem_free."""
    rt = _running()
    r = rt.refresh
    elapsed = rt.diff(rt.ticks(), rt.started_us)
    sc = r.scene
    return {
        "running": True, "mem_free": free,
        "refreshes": r.count, "rate_hz": (r.count * 1000000 // elapsed) if elapsed > 0 else 0,
        "worst_us": r.worst_us, "overruns": r.overruns, "faults": r.faults,
        "position": r.pos, "amplitude": r.amp, "duty": r.duty,
        # describe(), not the source: an uploaded samples region would send
        # up to 19,200 ints with every status call
        "scene": sc.describe() if sc is not None else None,
        "pushes": rt.pushes, "last_push": rt.last_push,
        # the paced loop (CircuitPython): refreshes started more than a period
        # late since serve began pacing this display (its start, or serve
        # entered); the refresh's body is timed once in timed_every refreshes
        # (worst_us, overruns)
        "late": rt.pacer.late if rt.pacer is not None else None,
        "loop": getattr(rt, "loop", None)}


def stream(rate_hz=125):
    """Start telemetry: the refresh itself records (t_us, position,
    amplitude) every hz // rate_hz refreshes into a 256-sample ring, so the
    loop is not disturbed; telemetry() drains it. Returns that divider.
    rate_hz=0 stops it. On the virtual board, advance() time meanwhile or
    run realtime."""
    rt = _running()
    r = rt.refresh
    if not rate_hz:
        r.tel_every = 0
        return 0
    every = rt.hz // rate_hz
    if every < 1:
        every = 1
    r.tel_div = 0
    rt.tel_tail = r.tel_head
    r.tel_every = every
    return every


def telemetry():
    """Samples gathered since the last call: (samples, lost)."""
    rt = _running()
    out, rt.tel_tail, lost = rt.refresh.telemetry_since(rt.tel_tail)
    return out, lost


def stop():
    """Stop the refresh and leave the carrier in its safe off state."""
    global _rt
    rt = _rt
    if rt is None:
        if compat.PORT == "rp2":
            # nothing runs here: disarm a refresh interrupt that a soft reset
            # without stop() may have left (hw/rp2.py clear_stale_tick)
            try:
                from .hw.rp2 import clear_stale_tick
                clear_stale_tick()
            except ImportError:
                pass
        return
    try:
        _halt(rt.hw, rt)
    finally:
        rt.hw.off()
        _rt = None
        gc.collect()


def _halt(hw, rt):
    """Stop the refresh's hardware, then zero the W the refresh read
    (FastRefresh.release: only once it has stopped; rt None or without a
    refresh yet: a start that failed early)."""
    hw.stop()
    release = getattr(getattr(rt, "refresh", None), "release", None)
    if release is not None:
        release()


def run_loop(seconds=None):
    """CircuitPython (no timer IRQ): a best-effort loop paced to the board's
    refresh rate on the board's own clock (runtime/pace.py; milliseconds on
    CircuitPython). When the loop falls behind it runs the missed refreshes
    back to back (late ones counted), and it measures the rate it really
    achieved: status()["rate_hz"] and the "loop" entry. Runs until Ctrl-C, or
    for `seconds`."""
    from .runtime.pace import Pacer, clock_of
    rt = _running()
    step = rt.refresh.step
    p = Pacer(rt.hz, clock_of(rt))
    due = p.due
    limit = None if seconds is None else int(seconds * p.per_s)
    try:
        while True:
            if due():
                step()
                if p.k & 31 != 1:       # the time limit: checked while waiting and, for
                    continue            # a loop that never waits, every 32 refreshes
            if limit is not None and p.elapsed() >= limit:
                break
    except KeyboardInterrupt:
        pass
    finally:
        rt.hw.off()
    el = p.elapsed() / p.per_s
    n = p.refreshes()
    rt.loop = {"refreshes": n, "seconds": el, "rate_hz": int(n / el) if el > 0 else 0,
               "late": p.late}
    return rt.loop


def _current():
    return _rt


def serve(idle=True, repl=False):
    """Play (the paced loop, as run_loop) and answer the host's link at the
    same time: how a CircuitPython board keeps playing between texelpad
    commands (texel/serve.py; docs/runtime.md). A Ctrl-C stops the display
    and ends serve (KeyboardInterrupt: code.py ends as CircuitPython's programs
    do); repl=True (the link's hand-over, in the raw REPL): serve goes on
    answering as the raw REPL would. idle=False: return False at once when
    nothing plays in a loop (the hand-over: nothing to keep alive)."""
    if not idle and (_rt is None or not _rt.loop_mode):
        return False
    from .serve import serve as _serve
    _serve(_current, stop, repl=repl)
