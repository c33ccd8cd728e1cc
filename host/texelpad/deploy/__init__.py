"""Putting the device image on a board.

    image     which files a board gets, compiled for its .mpy format (offline)
    install   `texelpad deploy`: write only what changed, over the link
"""
