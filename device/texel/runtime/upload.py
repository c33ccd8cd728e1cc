# Uploads: long samples regions arriving over the link as data (base64
# pieces, texel.wire.upload_*), not as a literal the board compiles. In its
# own module so the scene code every board imports stays small (the unix
# port's heap test, tests/runtime/test_scene.py, builds the split screen on
# a 176 KB heap); imported only when an upload begins.
#
# The array <-> bytes conversions below differ between runtimes (a
# MicroPython array reads bytes as raw memory, CPython's needs frombytes)
# and would belong in texel/compat.py, but every board imports compat and
# only an upload needs them: kept here, the unix port's 176 KB heap test
# still builds the split screen (compat grown by them, it did not).
from array import array
from .kinds import CHUNK_BITS, CHUNK_MASK
from .kinds import new_chunks
from .kinds.samples import MAX_SAMPLES


def u16_put_bytes(buf, offset, data):
    """Write the little-endian uint16 values in `data` (bytes, even length)
    into buf[offset:]: how uploaded samples reach their buffer (the link
    carries them as base64 data, never as code). MicroPython and
    CircuitPython read array('H', bytes) as raw memory (every board here is
    little-endian); CPython needs frombytes (and a swap on a big-endian
    host). A port without array slice assignment takes the loop."""
    try:
        part = array("H", data)
    except TypeError:                   # CPython: no bytes initializer for 'H'
        import sys
        part = array("H")
        part.frombytes(data)
        if sys.byteorder == "big":
            part.byteswap()
    k = len(part)
    try:
        buf[offset:offset + k] = part
    except (TypeError, NotImplementedError):     # no MICROPY_PY_ARRAY_SLICE_ASSIGN
        for i in range(k):
            buf[offset + i] = part[i]
    return k


def u16_bytes(buf, start, end):
    """buf[start:end] (an array('H')) as little-endian bytes: the read side
    of u16_put_bytes."""
    part = buf[start:end]
    if hasattr(part, "tobytes"):        # CPython
        import sys
        if sys.byteorder == "big":
            part.byteswap()
        return part.tobytes()
    return bytes(part)                  # MicroPython: an array's raw memory


# Uploaded values are kept in chunks of CHUNK values (1 KB each), never in
# one block: a Pico's heap playing a scene is fragmented. Measured on the
# emulated Pico: with a scene playing the largest free block was ~22-35 KB
# of ~115 KB free, so one 38.4 KB array for a full screen found no room;
# with a first full-screen upload playing, 80 KB were free in holes mostly
# under 4 KB, so 4 KB chunks for a second one failed and 1 KB chunks fit.
# scene.amp reads chunk o >> CHUNK_BITS, value o & CHUNK_MASK (scene.K_CHUNK;
# both refreshes, refresh.py and refresh_viper.py, read them).
CHUNK = 1 << CHUNK_BITS             # 512 values


class Chunks:
    """n uint16 values in chunks (a tuple of array('H'), all CHUNK long but
    the last): a read-only sequence for the scene code (len, [i]) and
    .chunks for its hot path."""

    CHUNKS = True               # what scene.validate/build look for (no literal has it)

    def __init__(self, n):
        self.n = n
        self.chunks = new_chunks(n, 1)     # 1 KB blocks: arriving while a scene plays

    def __len__(self):
        return self.n

    def __getitem__(self, i):
        if i < 0:
            i += self.n
        if not 0 <= i < self.n:
            raise IndexError("upload index out of range")
        return self.chunks[i >> CHUNK_BITS][i & CHUNK_MASK]

    def __setitem__(self, i, v):
        """One value (a brush painting into its region: gen/brush.py)."""
        self.chunks[i >> CHUNK_BITS][i & CHUNK_MASK] = v

    def put(self, offset, data):
        """Little-endian uint16 bytes for values offset..; returns how many."""
        k = len(data) // 2
        done = 0
        while done < k:
            o = offset + done
            c = self.chunks[o >> CHUNK_BITS]
            at = o & CHUNK_MASK
            m = min(k - done, len(c) - at)
            # a piece inside one chunk (the host's pieces are aligned) goes
            # as it is: on a Pico every extra 2-4 KB block may not be there
            u16_put_bytes(c, at, data if m == k else data[2 * done:2 * (done + m)])
            done += m
        return k

    def bytes_of(self, start, end):
        """Values start..end as little-endian bytes (the read side of put)."""
        out = bytearray()
        o = start
        while o < end:
            c = self.chunks[o >> CHUNK_BITS]
            at = o & CHUNK_MASK
            m = min(end - o, len(c) - at)
            out.extend(u16_bytes(c, at, at + m))
            o += m
        return bytes(out)


class Upload:
    """n uint16 samples arriving in pieces over the link (texel.wire.upload_*):
    chunks filled in order, then handed to validate() as a samples region's
    "u16" (which becomes the Chunks); validate refuses it until every value
    has arrived."""

    UPLOAD = True               # what scene.validate looks for (no literal has it)

    def __init__(self, n):
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_SAMPLES:
            raise ValueError("upload: %r values; allowed 1 .. %d" % (n, MAX_SAMPLES))
        self.buf = Chunks(n)
        self.filled = 0

    def write(self, offset, data):
        """The next piece: `data` little-endian uint16 bytes for positions
        offset.. (pieces arrive in order: offset must be what has arrived)."""
        if offset != self.filled:
            raise ValueError("upload: piece at value %d, expected %d (pieces arrive in order)"
                             % (offset, self.filled))
        if len(data) & 1 or offset + len(data) // 2 > len(self.buf):
            raise ValueError("upload: %d bytes at value %d do not fit %d values"
                             % (len(data), offset, len(self.buf)))
        self.filled += self.buf.put(offset, data)
        return self.filled
