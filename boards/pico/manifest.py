# MicroPython's own rp2 modules, then texelpad: its power-up (main.py, boot.py) and the texel
# package, frozen (bytecode and viper code run from flash; docs/firmware.md). `texelpad firmware`
# puts main.py, boot.py and texel/ beside this file in the folder it builds from
# (host/texelpad/firmware: frozen_main.py, frozen_boot.py, the rp2 image's sources); texelpad's
# data (reference maps, board files) goes into the ROMFS partition.
include("$(PORT_DIR)/boards/manifest.py")
freeze("$(BOARD_DIR)", ("main.py", "boot.py"))
package("texel", base_path="$(BOARD_DIR)")
