# The host <-> board contract's version: texelpad.link checks it at the
# handshake and refuses (deploy again) an image that speaks another. A
# module of its own so the host and the handshake read it without importing
# the display runtime. 2: the wire calls moved from texel.app to texel.wire;
# 3: answers printed by texel.wire.say (a float as its 32 bits, `<bits>j`, where
# the board's C core writes them: texelpad.link.protocol.floats_from_bits).
PROTOCOL = 3

# Values per upload piece (texel.wire.upload_write): 1 KB of data, ~1.4 KB of
# base64 - a few small blocks on the board's heap per piece (the code, the
# text, the bytes, one array). Measured on the emulated Pico: 2,048 failed
# with ~75 KB free but fragmented, and 1,024 (a 2.7 KB text) during a second
# full-screen upload.
UPLOAD_PIECE_MAX = 512
