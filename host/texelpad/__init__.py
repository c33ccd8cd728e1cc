"""texelpad: host toolkit for the texel friction display.

    import texelpad
    with texelpad.connect("/dev/ttyACM0") as b:      # or a VirtualBoard's port
        b.push_texel({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7})
"""
__version__ = "0.1.0"


def connect(port=None, timeout=10.0, check=True):
    """A Board over the serial link (see texelpad.board.connect)."""
    from .link.board import connect as _connect
    return _connect(port, timeout=timeout, check=check)
