// texelpad firmware for the Raspberry Pi Pico (RP2040, 2 MB flash): MicroPython v1.28 + ulab,
// texelpad in a ROMFS partition (bytecode and the reference maps run from flash in place).
// Flash: firmware [0, 640 KB) | ROMFS [640 KB, 1280 KB) | littlefs [1280 KB, 2048 KB).
// The firmware must end below 640 KB (0xA0000, where the stock Pico's filesystem starts,
// so the emulated Pico of ../shared/instruments keeps its flash file's layout).
#define MICROPY_HW_BOARD_NAME                   "Raspberry Pi Pico (texelpad)"
#define MICROPY_HW_FLASH_STORAGE_BYTES          (768 * 1024)
#define MICROPY_HW_ROMFS_BYTES                  (640 * 1024)
