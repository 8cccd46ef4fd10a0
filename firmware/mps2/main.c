/* The mps2 port: the firmware core on QEMU's mps2-an385 (a Cortex-M3 at
   25 MHz) with the RAM of a 20 KiB part, for end-to-end tests of the real
   image over a pty:

       qemu-system-arm -M mps2-an385 -nographic -monitor none -serial pty \
           -semihosting-config enable=on,target=native -kernel fw-mps2.elf

   QEMU models no GPIO on this board, so the printer's pins are a software
   model like the simulator's: the carriage starts MPS2_Z_START_MM above the
   endstop, which is closed while it is at or below its switching point, and
   the steps, the light and the masks shown are counted. The display buffers
   are not kept (20 KiB could not hold them): the core checks each mask's
   CRC-32 as it decodes, which is what a test needs to know. The EXIT message
   ends QEMU with its code (semihosting); a fault ends it with 101 (stack
   overflow) or 102 (hard fault). The tick is the 25 MHz core clock. */
#include "../fw.h"
#include "../cm3/cm3.h"
#include "board.h"

/* The printer this image pretends to be; -D to change. */
#ifndef MPS2_STEPS_PER_MM
#define MPS2_STEPS_PER_MM 400u
#endif
#ifndef MPS2_DISPLAY_W
#define MPS2_DISPLAY_W 240u
#endif
#ifndef MPS2_DISPLAY_H
#define MPS2_DISPLAY_H 200u
#endif
#ifndef MPS2_DISPLAY_BITS
#define MPS2_DISPLAY_BITS 1u
#endif
#ifndef MPS2_PITCH_NM
#define MPS2_PITCH_NM 100000u
#endif
#ifndef MPS2_Z_START_MM
#define MPS2_Z_START_MM 30u
#endif
#ifndef MPS2_MAX_BINS
#define MPS2_MAX_BINS 12000u
#endif

/* The pins' model: file-static because it is this board's one carriage. */
static struct {
    int32_t true_position;     /* steps above the endstop's switching point */
    uint32_t steps, rows, shows;
    int uv, motor, shown;
} pins;

static fw_state fw;
static uint64_t plan_workspace[(FW_PLAN_WORKSPACE(MPS2_MAX_BINS) + 7u) / 8u];

static void pin_write(void *ctx, const uint8_t *data, size_t size)
{
    (void)ctx;
    board_write(data, size);
}

static void pin_step(void *ctx, int dir, uint64_t when)
{
    (void)ctx;
    (void)when;
    pins.true_position += dir;
    pins.steps++;
}

static int pin_endstop(void *ctx)
{
    (void)ctx;
    return pins.true_position <= 0;
}

static void pin_uv(void *ctx, int on, uint64_t when)
{
    (void)ctx;
    (void)when;
    pins.uv = on;
}

static void pin_motor(void *ctx, int on)
{
    (void)ctx;
    pins.motor = on;
}

static void pin_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)ctx;
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    pins.rows++;
}

static void pin_show(void *ctx, int slot, uint64_t when)
{
    (void)ctx;
    (void)when;
    pins.shown = slot;
    if (slot >= 0) pins.shows++;
}

static void pin_exit(void *ctx, int code)
{
    (void)ctx;
    board_exit(code);
}

int main(void)
{
    fw_config config;
    fw_port port;
    board_init();
    pins.true_position = (int32_t)(MPS2_Z_START_MM * MPS2_STEPS_PER_MM);
    cm3_z_config(&config, MPS2_CLOCK_HZ, MPS2_STEPS_PER_MM);
    config.display_width = MPS2_DISPLAY_W;
    config.display_height = MPS2_DISPLAY_H;
    config.display_bits = MPS2_DISPLAY_BITS;
    config.pitch_nm = MPS2_PITCH_NM;
    config.max_bins = MPS2_MAX_BINS;
    /* QEMU's UART holds the line while the ring is full, so no window
       overruns it; 8 frames keep the link busy. */
    config.window = 8;
    port.ctx = NULL;
    port.write = pin_write;
    port.step = pin_step;
    port.endstop = pin_endstop;
    port.uv = pin_uv;
    port.motor = pin_motor;
    port.mask_row = pin_mask_row;
    port.show = pin_show;
    port.exit = pin_exit;
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
    cm3_serve(&fw);
}
