# _texelcore as a user C module for MicroPython's make-based ports (the stm32 port:
# `texelpad firmware --board pyboard`, host/texelpad/firmware/build_stm32.py); the rp2 port's
# CMake build reads micropython.cmake beside this file. Same sources; the refresh stays in
# flash here (no TC_IN_RAM: an STM32F4 runs flash code through its ART accelerator at zero
# wait states).
TEXELCORE_DIR := $(USERMOD_DIR)
SRC_USERMOD_C += $(TEXELCORE_DIR)/brush_core.c $(TEXELCORE_DIR)/texel_core.c \
	$(TEXELCORE_DIR)/refresh_core.c $(TEXELCORE_DIR)/modtexelcore.c
CFLAGS_USERMOD += -I$(TEXELCORE_DIR)
# -O2 for the plan's, painter's and refresh's loops (the stm32 port builds with -Os). py/py.mk
# names a user module's objects after the module's folder: $(BUILD)/texelcore/x.o
$(BUILD)/texelcore/brush_core.o: CFLAGS += -O2
$(BUILD)/texelcore/texel_core.o: CFLAGS += -O2
$(BUILD)/texelcore/refresh_core.o: CFLAGS += -O2
