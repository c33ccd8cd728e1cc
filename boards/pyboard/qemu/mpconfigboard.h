// texelpad firmware's emulated twin (texelpad firmware --board pyboard --qemu): the pyboard as
// ../shared/instruments/stm32emu's patched QEMU emulates it - that kit's QEMU_PYBV11 board
// definition (MIT), taken as it is. Its differences from ../mpconfigboard.h are listed in
// docs/firmware.md ("pyboard"); everything else (linker script, frozen texel, ROMFS) is shared.
// QEMU_PYBV11: the pyboard v1.1 (STM32F405RG) as QEMU 7.2's `netduinoplus2` /
// `olimex-stm32-h405` machines emulate it (kit-stm32). Same pins.csv (X/Y names)
// and HSE/PLL numbers as boards/PYBV11; what QEMU lacks is switched off:
//  - RCC is an unimplemented region (reads 0): board_init.c replaces
//    SystemClock_Config (no HSE/PLL wait) and sets SystemCoreClock = 168 MHz,
//    the clock QEMU gives the CPU and SysTick.
//  - no USB OTG, RNG, RTC/LSE, SD card, DAC, accelerometer, LCD, switch (GPIO
//    reads 0, which a real switch would read as "pressed" at boot).
//  - flash is ROM in QEMU (writes ignored): no flash filesystem; a ROMFS
//    partition (read-only, memory-mapped, mounted at /rom) is loaded by QEMU.
//  - REPL on USART1 (PB6/PB7, "XB"), QEMU's first serial port.
#define MICROPY_HW_BOARD_NAME       "PYBv1.1-QEMU"
#define MICROPY_HW_MCU_NAME         "STM32F405RG"

#define MICROPY_HW_HAS_SWITCH       (0)
#define MICROPY_HW_HAS_FLASH        (0)
#define MICROPY_HW_ENABLE_INTERNAL_FLASH_STORAGE (0)
#define MICROPY_HW_HAS_MMA7660      (0)
#define MICROPY_HW_HAS_LCD          (0)
#define MICROPY_HW_ENABLE_RNG       (0)
#define MICROPY_HW_ENABLE_RTC       (0)
#define MICROPY_HW_ENABLE_SERVO     (0)
#define MICROPY_HW_ENABLE_DAC       (0)
#define MICROPY_HW_ENABLE_USB       (0)
#define MICROPY_HW_ENABLE_SDCARD    (0)

// ROMFS partition 0 in internal flash (linker script qemu_f405.ld)
#define MICROPY_HW_ROMFS_ENABLE_INTERNAL_FLASH (1)
#define MICROPY_HW_ROMFS_ENABLE_PART0 (1)

// REPL on USART1 = QEMU's serial0 (-serial stdio / pty)
#define MICROPY_HW_UART_REPL        PYB_UART_1
#define MICROPY_HW_UART_REPL_BAUD   115200

// HSE is 12MHz (as PYBV11; unused under QEMU, see board_init.c)
#define MICROPY_HW_CLK_PLLM (12)
#define MICROPY_HW_CLK_PLLN (336)
#define MICROPY_HW_CLK_PLLP (RCC_PLLP_DIV2)
#define MICROPY_HW_CLK_PLLQ (7)

// UART config
#define MICROPY_HW_UART1_NAME   "XB"
#define MICROPY_HW_UART1_TX     (pin_B6)
#define MICROPY_HW_UART1_RX     (pin_B7)
#define MICROPY_HW_UART2_TX     (pin_A2)
#define MICROPY_HW_UART2_RX     (pin_A3)
#define MICROPY_HW_UART3_NAME   "YB"
#define MICROPY_HW_UART3_TX     (pin_B10)
#define MICROPY_HW_UART3_RX     (pin_B11)
#define MICROPY_HW_UART6_NAME   "YA"
#define MICROPY_HW_UART6_TX     (pin_C6)
#define MICROPY_HW_UART6_RX     (pin_C7)

// I2C buses
#define MICROPY_HW_I2C2_NAME "Y"
#define MICROPY_HW_I2C2_SCL (pin_B10)
#define MICROPY_HW_I2C2_SDA (pin_B11)

// SPI buses
#define MICROPY_HW_SPI1_NAME "X"
#define MICROPY_HW_SPI1_NSS  (pin_A4) // X5
#define MICROPY_HW_SPI1_SCK  (pin_A5) // X6
#define MICROPY_HW_SPI1_MISO (pin_A6) // X7
#define MICROPY_HW_SPI1_MOSI (pin_A7) // X8
#define MICROPY_HW_SPI2_NAME "Y"
#define MICROPY_HW_SPI2_NSS  (pin_B12) // Y5
#define MICROPY_HW_SPI2_SCK  (pin_B13) // Y6
#define MICROPY_HW_SPI2_MISO (pin_B14) // Y7
#define MICROPY_HW_SPI2_MOSI (pin_B15) // Y8

// The pyboard has 4 LEDs (GPIO writes are ignored by QEMU)
#define MICROPY_HW_LED1             (pin_A13) // red
#define MICROPY_HW_LED2             (pin_A14) // green
#define MICROPY_HW_LED3             (pin_A15) // yellow
#define MICROPY_HW_LED4             (pin_B4)  // blue
#define MICROPY_HW_LED_ON(pin)      (mp_hal_pin_high(pin))
#define MICROPY_HW_LED_OFF(pin)     (mp_hal_pin_low(pin))
