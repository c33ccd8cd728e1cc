# MicroPython's asyncio, then texelpad: its power-up (main.py, boot.py) and the texel package,
# frozen (bytecode and viper code run from flash; docs/firmware.md). `texelpad firmware` puts
# main.py, boot.py and texel/ beside this file in the folder it builds from
# (host/texelpad/firmware: frozen_main.py, frozen_boot.py, the pyboard image's sources);
# texelpad's data (tables, board files) goes into the ROMFS partition.
include("$(MPY_DIR)/extmod/asyncio")
freeze("$(BOARD_DIR)", ("main.py", "boot.py"))
package("texel", base_path="$(BOARD_DIR)")
