"""texelpad: host toolkit for the texel friction display.

    import texelpad
    with texelpad.connect("/dev/ttyACM0") as b:      # or a VirtualBoard's port
        b.push_texel({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7})

    res = texelpad.encode(friction_map)   # map -> the texel parameters that feel the same
    res["texture"]                         # the dict a board plays (b.push_texel)
"""
__version__ = "0.2.0"


def connect(port=None, timeout=10.0, check=True):
    """A Board over the serial link (see texelpad.board.connect)."""
    from .link.board import connect as _connect
    return _connect(port, timeout=timeout, check=check)


def encode(fmap, **kwargs):
    """Encode a friction map (1-D, values 0..1, 5.3 um per sample) as texel
    parameters that feel the same, with the report: a dict with pitch_db,
    irregularity_db, gain, texture (what a board plays), distance_db, ...
    (texelpad.analysis.encoder.encode; docs/encoder.md)."""
    from .analysis.encoder import encode as _encode
    return _encode(fmap, **kwargs)
