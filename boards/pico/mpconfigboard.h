// texelpad firmware for the Raspberry Pi Pico (RP2040, 2 MB flash): MicroPython v1.28 + ulab,
// texelpad in a ROMFS partition (bytecode and the reference maps run from flash in place).
// Flash: firmware [0, 640 KB) | ROMFS [640 KB, 1280 KB) | littlefs [1280 KB, 2048 KB).
// The firmware must end below 640 KB (0xA0000, where the stock Pico's filesystem starts,
// so the emulated Pico of ../shared/instruments keeps its flash file's layout).
#define MICROPY_HW_BOARD_NAME                   "Raspberry Pi Pico (texelpad)"
#define MICROPY_HW_FLASH_STORAGE_BYTES          (768 * 1024)
#define MICROPY_HW_ROMFS_BYTES                  (640 * 1024)

// At the start of every soft reset (Ctrl-D, mpremote's exec/run/cp/fs/mip, Thonny's Stop,
// machine.soft_reset()), before MicroPython stops its PWM slices and sweeps the heap: texelpad's
// refresh interrupt off (NVIC and every slice's wrap enable: its trampoline and machine code are
// in the heap the new interpreter reuses), every PWM slice stopped, and every pin a PWM slice
// drives taken low as a plain output - the carrier off, both bridge legs low, whatever phase the
// carrier was in (a slice that merely stops holds its pin's level, possibly high: a gate driver
// held on). The free-running ADC of the refresh (START_MANY) off. docs/runtime.md, "Soft reset".
// Addresses: RP2040 datasheet 2.3.1.7 (SIO GPIO_OUT_CLR 0xd0000018, GPIO_OE_SET 0xd0000024),
// 2.19.6.1 (IO_BANK0 GPIOn_CTRL 0x40014004 + 8n, FUNCSEL 4 = PWM, 5 = SIO), 4.5.3 (PWM CHn_CSR
// 0x40050000 + 0x14n, INTE 0x400500a8), 4.9.6 (ADC CS 0x4004c000); NVIC ICER 0xe000e180, IRQ 4.
#define MICROPY_BOARD_START_SOFT_RESET() do { \
        *(volatile uint32_t *)0xe000e180u = 1u << 4; \
        *(volatile uint32_t *)0x400500a8u = 0u; \
        for (unsigned tp_g = 0; tp_g < 30u; tp_g++) { \
            volatile uint32_t *tp_ctrl = (volatile uint32_t *)(0x40014004u + 8u * tp_g); \
            if ((*tp_ctrl & 0x1fu) == 4u) { \
                *(volatile uint32_t *)0xd0000018u = 1u << tp_g; \
                *(volatile uint32_t *)0xd0000024u = 1u << tp_g; \
                *tp_ctrl = (*tp_ctrl & ~0x1fu) | 5u; \
            } \
        } \
        for (unsigned tp_s = 0; tp_s < 8u; tp_s++) { \
            *(volatile uint32_t *)(0x40050000u + 0x14u * tp_s) &= ~1u; \
        } \
        *(volatile uint32_t *)0x4004c000u &= ~8u; \
} while (0)
