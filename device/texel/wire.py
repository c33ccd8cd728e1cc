# The wire API: what the host's texelpad.link calls on the board besides
# the user API of texel.app (start, push, status, stop), and what a person at
# the REPL never needs (docs/runtime.md). Data crosses as data here: scenes as
# JSON text (staged), long samples regions as base64 pieces (upload_*), maps
# and telemetry back as base64 (samples_b64, telemetry_b64). The virtual
# board's stepped time and scripted finger (advance, finger) are here too:
# the host drives them. Nothing here plays without texel.app.
import gc
# json and binascii at the top: MicroPython never caches an extensible built-in in
# sys.modules, so an import inside a function walks sys.path each time (the
# filesystems' stats: 1.64 ms a call on the emulated RP2040 firmware, most of
# a push's "parse"; bench/request_parts.py, tests/runtime/test_imports.py)
import binascii
import json
import sys
from . import app, compat
from .protocol import UPLOAD_PIECE_MAX      # values per piece (the contract's)
from .runtime import scene as _scene


def board_display(board_name):
    """The display of board file `board_name` if start() would take it
    ({"positions", "dx_um"}), else ValueError in start()'s words: what a
    power-up scene is checked against."""
    d = app._checked_board(board_name)["display"]
    return {"positions": d["positions"], "dx_um": d["dx_um"]}



def scene_source(inline_max=None):
    """The canonical dict of the scene playing (None when stopped): what the
    host needs to redraw it. A samples region longer than inline_max values
    comes back as its count (an int) instead of the values: the host reads
    those with samples_b64() in pieces (a 19,200-value repr would need some
    120 KB of the board's heap at once). inline_max None: everything inline."""
    rt = app._rt
    if rt is None or rt.refresh.scene is None:
        return None
    src = rt.refresh.scene.source
    out = {}
    for k in src:
        out[k] = src[k]
    regs = []
    for r in src["regions"]:
        tex = r["texture"]
        if tex["kind"] == "samples":
            vals = tex["u16"]
            n = len(vals)
            if inline_max is not None and n > inline_max:
                u16 = n                 # its count: the host reads it with samples_b64
            elif isinstance(vals, tuple):
                u16 = vals
            else:                       # an upload's chunks, inline
                u16 = tuple([vals[i] for i in range(n)])
            if u16 is not vals:
                r = {"start_mm": r["start_mm"], "end_mm": r["end_mm"],
                     "texture": {"kind": "samples", "fit": tex["fit"], "u16": u16}}
        regs.append(r)
    out["regions"] = regs
    return out


def samples_b64(region, offset, count):
    """Values offset .. offset+count of the playing scene's samples region
    `region` (its index in the canonical order), as base64 of little-endian
    uint16: the read side of upload_write."""
    rt = app._running()
    sc = rt.refresh.scene
    regs = sc.source["regions"] if sc is not None else ()
    if not (isinstance(region, int) and 0 <= region < len(regs)) \
            or regs[region]["texture"]["kind"] != "samples":
        raise ValueError("samples_b64: region %r is not a samples region of the scene playing"
                         % (region,))
    vals = regs[region]["texture"]["u16"]
    n = len(vals)
    if not (isinstance(offset, int) and isinstance(count, int) and 0 <= offset <= n
            and 0 <= count <= UPLOAD_PIECE_MAX):
        raise ValueError("samples_b64: offset %r, count %r outside 0 .. %d (at most %d per piece)"
                         % (offset, count, n, UPLOAD_PIECE_MAX))
    end = min(n, offset + count)
    if not isinstance(vals, tuple):     # an upload (upload.Chunks): its own bytes
        return binascii.b2a_base64(vals.bytes_of(offset, end)).strip().decode()
    b = bytearray(2 * (end - offset))
    for i in range(offset, end):
        v = vals[i]
        j = 2 * (i - offset)
        b[j] = v & 0xFF
        b[j + 1] = v >> 8
    return binascii.b2a_base64(b).strip().decode()


# --- uploads ---------------------------------------------------------------------------
# Large sample data crosses the link as data: the host stages each long
# samples region with upload_begin, sends it in pieces of base64 text
# (upload_write: one short call each, so the board never compiles a literal
# of thousands of numbers - a 9,000-int list literal overflowed the
# bytecode emitter - and the refresh is never held up for long), then
# pushes the scene with take_upload(slot) in place of the values. Nothing
# plays until that push, which validates the upload like any scene: an
# interrupted upload changes nothing (the next upload_begin frees it).
_uploads = []


STAGED = ("push", "start", "pushed")     # what staged() calls (app's functions)
# the firmware's C reader of a scene's JSON (texelcore_fw.h scene_json: json.loads's
# objects; 16 texel regions' 1,902 bytes in 3.9 ms, json.loads 7.6, on the emulated
# RP2040), else None
_json_c = getattr(compat.core(), "scene_json", None)


def staged(func, text, fill=(), args=(), scene_at=0, kwargs=None):
    """The host's push/start in one call (texelpad.link.protocol.staged_call,
    staged_frame): the scene arrives as JSON text (read by the C core's
    scene_json, else the json module), the samples region i takes upload
    slot k for each (i, k) in fill, then
    func(*args with the scene at scene_at, **kwargs). Returns ('ok', its
    value) or ('err', the ValueError's text). One statement for the board to
    compile instead of eight: 7-11 ms less per push on an RP2040
    (bench/firmware.py)."""
    if func not in STAGED:
        return ("err", "staged: %r is not one of %s" % (func, STAGED))
    try:
        s = _json_c(text) if _json_c is not None else None
        if s is None:                       # no C reader, or text it leaves to json
            s = json.loads(text)
        if fill:
            g = s["regions"]
            for i, k in fill:
                g[i]["texture"]["u16"] = take_upload(k)
        f = getattr(app, func)
        if not args and not kwargs:         # a push: no tuple, list or dict to build
            return ("ok", f(s))
        a = list(args)
        a.insert(scene_at, s)
        return ("ok", f(*a, **(kwargs or {})))
    except ValueError as e:
        return ("err", str(e))


# the C core's answer writer where the board's floats are 32 bits (the texelpad
# firmware, a deployed native module for the RP2040 or STM32), else None
_say_c = getattr(compat.core(), "answer", None)


def say(r):
    """Print the answer r (plain data) as one line for the host's link: the C
    core writes it with each float as its 32 bits (`<bits>j`, which
    texelpad.link.protocol.floats_from_bits turns back into the float): a float's
    repr() takes 0.3-1.7 ms on an RP2040, most of a push's answer
    (docs/firmware.md). Where there is no C core, or r holds what it does not
    write (a long int, a non-ASCII name), print(repr(r)) as before."""
    if _say_c is None or not _say_c(r):
        print(repr(r))


replied_us = None      # ticks_us when reply() printed its last answer (bench/firmware.py)
tidy_us = 0            # how long the collection after it took (us)


def reply(func, text, fill=(), args=(), scene_at=0, kwargs=None):
    """staged(), its answer printed as one repr() line, then the collection
    the push left due (app.tidy()): the host's link takes the line and goes
    on (texelpad.link.transport: reply_first) while the board collects, so
    the board answers before any gc.collect (5-15 ms on an RP2040)."""
    say(staged(func, text, fill, args, scene_at, kwargs))
    _collect()


def _collect():
    """app.tidy() after an answer (reply's, stand's), timed (bench/firmware.py)."""
    global replied_us, tidy_us
    replied_us = t = compat.ticks_us()
    app.tidy()
    tidy_us = compat.ticks_diff(compat.ticks_us(), t)


# --- the standing reader ----------------------------------------------------------
# A push costs the board a compile of its request before any work (the raw REPL
# compiles what it is sent: 1.8-8.6 ms for the bench's scenes on the emulated
# RP2040, most of it the scene's JSON as a string literal). stand() is one
# command the link runs once and then talks to as data (texelpad.link.transport
# Link.eval_frame): each request is a frame: "[", the data's byte count n, ",",
# the header's h, ",", h bytes of JSON [func, fill, args, scene_at, kwargs],
# then n bytes of the scene's JSON;
# staged() runs it and say() prints its one answer line; nothing is compiled. Any
# other byte where a frame begins (the link's empty line) ends it: the raw REPL again.
# Ctrl-C (mpremote, Thonny's Stop, the link's resync) ends it too, as it ends any
# command: what plays goes on playing (the refresh is an interrupt). Only where
# the console has flow control (USB: the link stands on rp2 boards only; a UART
# drops what its buffer cannot hold while the board collects).
STAND_MARK = "\x1etexel-stand\n"     # what stand() prints first (stdout makes it \r\n)
read_us = None      # ticks_us when stand() had read a frame's last byte (bench/firmware.py)
# stand()'s answer when the answer's own text found no room (allocates nothing)
NO_ANSWER = "('raise', 'MemoryError: no room on the board for the answer')"
BAD_FRAME = "('raise', 'stand: a frame without its byte counts', 'ended')"


def _count(rd, one):
    """The decimal digits up to a comma, read a byte at a time (nothing
    allocated): a frame's byte counts. -1 for anything else."""
    n = 0
    while True:
        rd.readinto(one)
        c = one[0]
        if c == 0x2C:                       # ","
            return n
        if not 0x30 <= c <= 0x39 or n > 10000000:
            return -1
        n = n * 10 + c - 0x30


def stand():
    """Answer the link's frames until a byte that does not begin one (the
    comment above): each with exactly one line, ('raise', its text) for an
    exception other than a refusal - no room for its header or data included:
    they are read past by their counts - and the reader goes on; a frame whose
    counts are not digits is answered ('raise', text, 'ended') and ends it (the
    link resyncs). Ctrl-C ends it. Nothing else may end it while the link
    thinks it reads: on a stock Pico's heap a push's own allocations fail
    (tests/firmware/test_firmware_pico.py sends a frame too large for the heap)."""
    global read_us
    rd = sys.stdin.buffer
    one = bytearray(1)                      # a byte, read without allocating
    sink = bytearray(64)                    # what is read past where there is no room
    sys.stdout.write(STAND_MARK)
    while True:
        if rd.readinto(one) != 1 or one[0] != 0x5B:        # "["
            return
        n = _count(rd, one)                 # the data's bytes
        h = _count(rd, one) if n >= 0 else -1               # the header's
        if h < 0:
            print(BAD_FRAME)
            return
        r = None
        try:
            compat.skip_holes()             # this frame's allocations: above the holes
            head = bytearray(h)             # allocated before reading: a failure here
            rd.readinto(head)               # leaves the bytes to read past
            h = 0
            func, fill, args, scene_at, kwargs = json.loads(head)
            head = bytearray(n)
            rd.readinto(head)
            n = 0
            read_us = compat.ticks_us()
            r = staged(func, head, fill, args, scene_at, kwargs)
        except Exception as e:              # not Ctrl-C (KeyboardInterrupt): that ends it
            head = None
            n += h
            while n > 0:                    # what was not read: read past it, in step again
                n -= rd.readinto(sink, min(n, 64))
            try:
                r = ("raise", "%s: %s" % (type(e).__name__, e))
            except Exception:
                r = None
        head = None
        try:
            if r is None:
                raise MemoryError
            say(r)                          # one line, whatever came
        except Exception:                   # no block for its text (a stock Pico's heap):
            print(NO_ANSWER)                # a line all the same
        r = None
        try:
            _collect()
        except Exception:                   # after the line: the reader goes on
            pass


def upload_begin(sizes):
    """Stage one upload per entry of `sizes` (values each, 1 .. MAX_SAMPLES),
    freeing any earlier one. Returns the number of slots."""
    global _uploads
    _uploads = []
    gc.collect()
    if not isinstance(sizes, (list, tuple)) or not 1 <= len(sizes) <= _scene.MAX_REGIONS:
        raise ValueError("upload_begin: expected a list of 1 .. %d sizes" % _scene.MAX_REGIONS)
    from .runtime.upload import Upload
    try:
        ups = [Upload(n) for n in sizes]
    except MemoryError:
        gc.collect()
        raise ValueError("not enough memory on the board to receive %d sample values (%s) "
                         "beside the scene playing, which keeps playing; to make room, "
                         "play a small scene first (texelpad push --constant 0)"
                         % (sum(sizes), compat.memory_words() or "the heap is full"))
    _uploads = ups
    return len(ups)


def upload_write(slot, offset, b64):
    """The next piece of upload `slot`: base64 text of little-endian uint16
    values starting at value `offset`. Returns the values arrived so far."""
    if not (isinstance(slot, int) and 0 <= slot < len(_uploads)):
        raise ValueError("upload_write: no upload %r (upload_begin first)" % (slot,))
    if not isinstance(b64, str) or len(b64) > 4 * UPLOAD_PIECE_MAX // 3 * 2 + 8:
        raise ValueError("upload_write: a piece is base64 text of at most %d values"
                         % UPLOAD_PIECE_MAX)
    full = ("not enough memory on the board for the next piece of the upload (%s); the "
            "current scene keeps playing")
    try:
        data = binascii.a2b_base64(b64)
    except ValueError:
        raise ValueError("upload_write: the piece is not base64")
    except MemoryError:
        raise ValueError(full % (compat.memory_words() or "the heap is full"))
    try:
        return _uploads[slot].write(offset, data)
    except MemoryError:
        raise ValueError(full % (compat.memory_words() or "the heap is full"))


def take_upload(slot):
    """Upload `slot`, handed over for a scene's samples region (and no longer
    staged). Validation refuses it unless every value arrived."""
    if not (isinstance(slot, int) and 0 <= slot < len(_uploads)) or _uploads[slot] is None:
        raise ValueError("take_upload: no upload %r" % (slot,))
    up = _uploads[slot]
    _uploads[slot] = None
    return up


def upload_discard():
    """Free whatever is staged (an interrupted upload)."""
    global _uploads
    _uploads = []
    gc.collect()



def telemetry_b64():
    """telemetry() for the host: (count, base64 text, lost), the text the
    count's int32 times (us), int32 positions and uint16 amplitudes one
    after the other, little-endian - copied at C speed and ~half the bytes
    of the repr of the same samples (runtime/refresh.py telemetry_packed_since)."""
    rt = app._running()
    t, p, m, n, rt.tel_tail, lost = rt.refresh.telemetry_packed_since(rt.tel_tail)
    return n, binascii.b2a_base64(t + p + m).decode().strip(), lost


def advance(ms):
    """Virtual board only: run `ms` milliseconds of stepped time."""
    rt = app._running()
    if not hasattr(rt.hw, "advance"):
        raise ValueError("advance(): only the virtual board has stepped time")
    return rt.hw.advance(int(ms * 1000))


def finger(keyframes):
    """Virtual board only: script the finger, [(t_ms, position_mm or None)],
    relative to now. Returns now (the board's ticks_us), so the host can line
    the script up with telemetry."""
    rt = app._running()
    if not hasattr(rt.hw, "set_finger"):
        raise ValueError("finger(): only the virtual board has a scripted finger")
    dx = rt.board["display"]["dx_um"] / 1000.0
    return rt.hw.set_finger([(int(t * 1000), None if p is None else int(p / dx + 0.5))
                             for t, p in keyframes])
