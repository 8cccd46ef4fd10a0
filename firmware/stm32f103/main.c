/* The stm32f103 port: the firmware core on an STM32F103C8 (Cortex-M3 at
   72 MHz, 64 KiB flash, 20 KiB RAM) driving a resin printer's Z stepper,
   UV light and endstop (pins in board.h). Built, not run here.

   The display is not this chip's: a resin printer's LCD is fed by its own
   controller (an FPGA or a bridge chip on the mainboard), and the bus to it
   differs from board to board. The core checks each mask's CRC-32 as it
   decodes and hands rows and "show" to the two display functions below,
   which count them until a driver for a particular display goes there. */
#include "../fw.h"
#include "../cm3/cm3.h"
#include "board.h"

/* The printer; -D to change. 400 steps/mm: a 1.8 degree motor at 1/16
   microsteps on an 8 mm lead screw. */
#ifndef STM32_STEPS_PER_MM
#define STM32_STEPS_PER_MM 400u
#endif
#ifndef STM32_DISPLAY_W
#define STM32_DISPLAY_W 2560u
#endif
#ifndef STM32_DISPLAY_H
#define STM32_DISPLAY_H 1440u
#endif
#ifndef STM32_DISPLAY_BITS
#define STM32_DISPLAY_BITS 1u
#endif
#ifndef STM32_PITCH_NM
#define STM32_PITCH_NM 50000u
#endif
#ifndef STM32_MAX_BINS
#define STM32_MAX_BINS 12000u
#endif
/* Frames the host may send ahead: the receive ring (CM3_RX_SIZE, set by
   firmware.mk) holds this many full frames, so a core busy planning never
   makes the USART overrun. */
#ifndef STM32_WINDOW
#define STM32_WINDOW 4u
#endif

static fw_state fw;
static uint64_t plan_workspace[(FW_PLAN_WORKSPACE(STM32_MAX_BINS) + 7u) / 8u];
static uint32_t mask_rows, masks_shown; /* the display stand-in */

static void port_write(void *ctx, const uint8_t *data, size_t size)
{
    (void)ctx;
    board_write(data, size);
}

static void port_step(void *ctx, int dir, uint64_t when)
{
    (void)ctx;
    /* the loop calls at or just after `when`: the pulse goes out now */
    (void)when;
    board_step(dir);
}

static int port_endstop(void *ctx)
{
    (void)ctx;
    return board_endstop();
}

static void port_uv(void *ctx, int on, uint64_t when)
{
    (void)ctx;
    (void)when;
    board_uv(on);
}

static void port_motor(void *ctx, int on)
{
    (void)ctx;
    board_motor(on);
}

static void port_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)ctx;
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    mask_rows++;
}

static void port_show(void *ctx, int slot, uint64_t when)
{
    (void)ctx;
    (void)when;
    if (slot >= 0) masks_shown++;
}

int main(void)
{
    fw_config config;
    fw_port port;
    board_init();
    cm3_z_config(&config, STM32_CLOCK_HZ, STM32_STEPS_PER_MM);
    config.display_width = STM32_DISPLAY_W;
    config.display_height = STM32_DISPLAY_H;
    config.display_bits = STM32_DISPLAY_BITS;
    config.pitch_nm = STM32_PITCH_NM;
    config.max_bins = STM32_MAX_BINS;
    config.window = STM32_WINDOW;
    port.ctx = NULL;
    port.write = port_write;
    port.step = port_step;
    port.endstop = port_endstop;
    port.uv = port_uv;
    port.motor = port_motor;
    port.mask_row = port_mask_row;
    port.show = port_show;
    port.exit = NULL; /* a real board does not end */
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
    cm3_serve(&fw);
}
