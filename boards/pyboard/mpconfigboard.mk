# texelpad firmware for the pyboard v1.1 (texelpad firmware --board pyboard), and its emulated
# twin (--qemu: qemu/ holds only the twin's header and board_init.c, which the stm32 Makefile
# compiles as $(BOARD_DIR)/*.c): MicroPython's boards/PYBV11/mpconfigboard.mk without Mboot,
# linked with texelpad_f405.ld (a ROMFS partition).
MCU_SERIES = f4
CMSIS_MCU = STM32F405xx
AF_FILE = boards/stm32f405_af.csv
LD_FILES = $(BOARD_DIR)/texelpad_f405.ld boards/common_ifs.ld
TEXT0_ADDR = 0x08000000
TEXT1_ADDR = 0x08020000

MICROPY_VFS_LFS2 = 1
# asyncio and texelpad frozen (manifest.py); no micropython-lib package, so no submodule
FROZEN_MANIFEST ?= $(BOARD_DIR)/manifest.py
MPY_LIB_DIR = $(BOARD_DIR)/no-micropython-lib
