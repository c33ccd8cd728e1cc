"""The host's side of the board: the one place that talks to one.

    transport   mpremote's serial transport in one adapter (Link), the errors
    protocol    every request the host sends, and the repr-literal rule
    board       Board / connect(): the Python API to a board running texelpad

Only the connection: the simulated boards it connects to (the virtual board,
the emulated Pico) are texelpad.sim, above it and deploy; this package imports
neither. Analysis, benchmarks' pure parts, studies and search never import
this package; commands, the simulated boards and the web server do.
"""
from .protocol import PROTOCOL, LiteralError, literal
from .transport import (DeviceError, ImageTooOld, Link, LinkError, LinkTimeout, NoBoard,
                        NotTexelpad, NoUlab, PortBusy, ports)
from .board import Board, connect

__all__ = ["PROTOCOL", "LiteralError", "literal", "DeviceError", "ImageTooOld", "Link",
           "LinkError", "LinkTimeout", "NoBoard", "NotTexelpad", "NoUlab", "PortBusy", "ports",
           "Board", "connect"]
