/* The firmware on RAMPS 1.4 / Arduino Mega 2560: the core's fw_port handed
   to the board layer (ramps.c), and the main loop.

   The core runs LEAD ticks ahead of the hardware: it is called with the
   tick LEAD from now, so every step, UV switch and move it starts carries a
   tick that is still in the future, and the timers' compare units carry
   them out at exactly that tick (ramps.c). Only inputs are LEAD old when the
   core sees them: the endstop (homing's one-step phases are slower than
   LEAD) and the host's bytes. */
#include "../../fw.h"
#include "board.h"
#include <avr/io.h>

#define LEAD (BOARD_CLOCK_HZ / 250u) /* 4 ms: 16 steps at 10 mm/s; the step queue holds 32 */
/* Bytes handed to the core per pass; between passes the loop refreshes the
   watchdog and runs the core's timed work. */
#define CHUNK 32u

static fw_state fw;
static uint64_t plan_workspace[(FW_PLAN_WORKSPACE(BOARD_MAX_BINS) + 7u) / 8u];
static uint16_t steps_refused;

static void port_write(void *ctx, const uint8_t *data, size_t size) { (void)ctx; board_write(data, size); }
static void port_step(void *ctx, int dir, uint64_t when)
{
    (void)ctx;
    if (!board_step_at(dir, when)) steps_refused++;
}
static int port_endstop(void *ctx) { (void)ctx; return board_endstop(); }
static void port_uv(void *ctx, int on, uint64_t when) { (void)ctx; board_uv_at(on, when); }
static void port_motor(void *ctx, int on) { (void)ctx; board_motor(on); }
static void port_show(void *ctx, int slot, uint64_t when) { (void)ctx; (void)when; board_show(slot); }
static void port_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)ctx;
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    board_mask_row();
}

int main(void)
{
    fw_config config;
    fw_port port;
    uint64_t deadline = 0;
    board_init();
    config.tick_hz = BOARD_CLOCK_HZ;
    config.axis.steps_per_mm = BOARD_STEPS_PER_MM;
    config.axis.max_speed = BOARD_MAX_SPEED_MM_S * BOARD_STEPS_PER_MM;
    config.axis.accel = BOARD_ACCEL_MM_S2 * BOARD_STEPS_PER_MM;
    config.axis.home_speed = BOARD_HOME_SPEED_MM_S * BOARD_STEPS_PER_MM;
    config.axis.max_steps = (int32_t)(BOARD_Z_MAX_MM * BOARD_STEPS_PER_MM);
    config.axis.home_travel = (int32_t)(BOARD_HOME_TRAVEL_MM * BOARD_STEPS_PER_MM);
    config.display_width = BOARD_DISPLAY_W;
    config.display_height = BOARD_DISPLAY_H;
    config.display_bits = BOARD_DISPLAY_BITS;
    config.pitch_nm = BOARD_PITCH_NM;
    config.max_bins = BOARD_MAX_BINS;
    config.link_timeout_ms = BOARD_LINK_TIMEOUT_MS;
    config.window = BOARD_WINDOW;
    port.ctx = NULL;
    port.write = port_write;
    port.step = port_step;
    port.endstop = port_endstop;
    port.uv = port_uv;
    port.motor = port_motor;
    port.mask_row = port_mask_row;
    port.show = port_show;
    port.exit = NULL; /* a board does not end */
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
    for (;;) {
        const uint8_t *data;
        size_t n;
        uint64_t now;
        GPIOR0 = BOARD_MARK_LOOP;
        board_watchdog();
#ifdef RAMPS_TEST_HANG
        /* test builds only: the simavr harness writes 0xA5 into GPIOR2
           (which nothing else uses) to make the loop hang */
        if (GPIOR2 == 0xA5u) for (;;) {}
#endif
        n = board_rx_peek(&data);
        if (n) {
            if (n > CHUNK) n = CHUNK;
            fw_receive(&fw, data, n, board_ticks() + LEAD);
            board_rx_consume(n);
            deadline = 0; /* what the bytes started may be due before the old deadline */
        }
        now = board_ticks() + LEAD;
        if (now >= deadline) deadline = fw_run(&fw, now);
        else if (!n) board_idle(deadline - LEAD);
    }
}
