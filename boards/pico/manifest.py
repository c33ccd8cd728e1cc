# MicroPython's own rp2 modules, then texelpad's power-up main.py (frozen: it runs the
# board's /main.py when there is one, else texelpad's power-up from the ROMFS partition).
# `texelpad firmware` puts main.py beside this file in the folder it builds from
# (host/texelpad/firmware/frozen_main.py); texelpad itself is not frozen: it is the ROMFS.
include("$(PORT_DIR)/boards/manifest.py")
freeze("$(BOARD_DIR)", "main.py")
