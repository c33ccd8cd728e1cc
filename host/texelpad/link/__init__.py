"""The host's side of the board: the one place that talks to one.

    transport   mpremote's serial transport in one adapter (Link), the errors
    protocol    every request the host sends, and the repr-literal rule
    board       Board / connect(): the Python API to a board running texelpad
    virtual     the virtual board (the MicroPython unix port on a pty)

Analysis, benchmarks' pure parts, studies and search never import this
package; commands and the (coming) web server do.
"""
from .protocol import PROTOCOL, LiteralError, literal
from .transport import (DeviceError, ImageTooOld, Link, LinkError, LinkTimeout, NoBoard,
                        NotTexelpad, NoUlab, PortBusy, ports)
from .board import Board, connect
from .virtual import VirtualBoard, open_virtual

__all__ = ["PROTOCOL", "LiteralError", "literal", "DeviceError", "ImageTooOld", "Link",
           "LinkError", "LinkTimeout", "NoBoard", "NotTexelpad", "NoUlab", "PortBusy", "ports",
           "Board", "connect", "VirtualBoard", "open_virtual"]
