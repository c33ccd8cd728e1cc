"""texelpad: host toolkit for the texel friction display."""
__version__ = "0.1.0"
