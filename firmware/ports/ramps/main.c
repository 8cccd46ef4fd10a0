/* The firmware on RAMPS 1.4 / Arduino Mega 2560: the core's fw_port handed
   to the board layer (ramps.c), and the main loop.

   The core runs at the hardware's tick (Timer5, 2 MHz). Steps leave from
   Timer5's compare unit at the ticks the core's step queue holds (the core
   arms each; the compare interrupt calls fw_step_interrupt), and the UV
   light is switched by Timer4's compare unit at an exposure's two ticks,
   so neither waits for the loop. The loop only has to refill the step
   queue before it runs dry: it does once FW_STEP_FILL steps have gone
   out, and each of its passes is held well under the time the rest covers
   at the top speed (board.h, FW_STEP_FILL and the pieces of a pass; measured under
   simavr by tests/test_avr.c). */
#include "../../fw.h"
#include "board.h"
#include <avr/io.h>

/* Bytes handed to the core per pass; between passes the loop runs the
   core's timed work (and fw_run refreshes the watchdog). Each costs the
   deframer and its CRC a few hundred cycles (avr-run --profile-passes), so
   8 keep a pass's share small; the line brings a byte every 1,389 cycles,
   so the loop still drains the ring faster than it fills. */
#define CHUNK 8u

/* Every figure derived from board.h's, checked at compile time in this
   part's arithmetic (int is 16 bits): a product that wraps fails the
   build here rather than shrinking the travel on the printer. Each is
   checked by undoing it. */
#define BOARD_CHECK(name, ok) typedef char board_check_##name[(ok) ? 1 : -1]
BOARD_CHECK(z_max, BOARD_Z_MAX_STEPS / BOARD_STEPS_PER_MM == BOARD_Z_MAX_MM && BOARD_Z_MAX_STEPS <= 0x7FFFFFFFul);
BOARD_CHECK(home_travel, BOARD_HOME_TRAVEL_STEPS / BOARD_STEPS_PER_MM == BOARD_HOME_TRAVEL_MM &&
                             BOARD_HOME_TRAVEL_STEPS <= 0x7FFFFFFFul);
BOARD_CHECK(accel, BOARD_ACCEL_STEPS_S2 / BOARD_STEPS_PER_MM == BOARD_ACCEL_MM_S2);
BOARD_CHECK(max_speed, BOARD_MAX_STEPS_S == (uint32_t)((uint64_t)BOARD_MAX_SPEED_UM_S * BOARD_STEPS_PER_MM / 1000u));
BOARD_CHECK(home_speed, BOARD_HOME_STEPS_S == (uint32_t)((uint64_t)BOARD_HOME_SPEED_UM_S * BOARD_STEPS_PER_MM / 1000u));
BOARD_CHECK(clock, BOARD_CLOCK_HZ * BOARD_TICK_DIV == BOARD_CPU_HZ);
BOARD_CHECK(step_lead, BOARD_STEP_LEAD * 125u == BOARD_CLOCK_HZ);
BOARD_CHECK(row, FW_ROW_BYTES * 8u >= BOARD_DISPLAY_W);

static fw_state fw BOARD_SAFETY; /* with the step queue and the light's state */
static uint64_t plan_workspace[(FW_PLAN_WORKSPACE(BOARD_MAX_BINS) + 7u) / 8u];

static void port_write(void *ctx, const uint8_t *data, size_t size) { (void)ctx; board_write(data, size); }
static int port_step_arm(void *ctx, uint64_t when, int dir) { (void)ctx; return board_step_arm(when, dir); }
static void port_step_pulse(void *ctx, int dir) { (void)ctx; (void)dir; board_step_pulse(); }
/* 1 when the loop must wake: the queue ran out (or the next step could not be armed) */
int ramps_step_due(void) { fw_step_interrupt(&fw); return !fw.steps.running; }
int ramps_gcode_mode(void) { return fw_gcode_mode(&fw); }
static int port_endstop(void *ctx) { (void)ctx; return board_endstop(); }
static void port_uv(void *ctx, int on, uint64_t when, uint64_t until) { (void)ctx; board_uv(on, when, until); }
static void port_motor(void *ctx, int on) { (void)ctx; board_motor(on); }
static void port_show(void *ctx, int slot, uint64_t when) { (void)ctx; (void)when; board_show(slot); }
static void port_watchdog(void *ctx) { (void)ctx; board_watchdog(); }
static void port_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)ctx;
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    board_mask_row();
}

/* The board and the core started; out of main, whose frame stays under
   every call of the loop: the config and port are needed only until
   fw_init has copied them. */
static __attribute__((noinline)) void start(void)
{
    fw_config config;
    fw_port port;
    board_init();
    config.tick_hz = BOARD_CLOCK_HZ;
    config.axis.steps_per_mm = BOARD_STEPS_PER_MM;
    config.axis.max_speed = BOARD_MAX_STEPS_S;
    config.axis.accel = BOARD_ACCEL_STEPS_S2;
    config.axis.home_speed = BOARD_HOME_STEPS_S;
    config.axis.max_steps = (int32_t)BOARD_Z_MAX_STEPS;
    config.axis.home_travel = (int32_t)BOARD_HOME_TRAVEL_STEPS;
    config.display_width = BOARD_DISPLAY_W;
    config.display_height = BOARD_DISPLAY_H;
    config.display_bits = BOARD_DISPLAY_BITS;
    config.pitch_nm = BOARD_PITCH_NM;
    config.max_bins = BOARD_MAX_BINS;
    config.link_timeout_ms = BOARD_LINK_TIMEOUT_MS;
    config.window = BOARD_WINDOW;
    config.watchdog_ms = BOARD_WDT_MS;
    config.step_lead = BOARD_STEP_LEAD;
    config.boot_id = board_boot_count();
    config.crc_byte_ns = BOARD_CRC_BYTE_NS;
    config.plan_bin_ns = BOARD_PLAN_BIN_NS;
    port.ctx = NULL;
    port.write = port_write;
    port.step_arm = port_step_arm;
    port.step_pulse = port_step_pulse;
    port.endstop = port_endstop;
    port.uv = port_uv;
    port.motor = port_motor;
    port.mask_row = port_mask_row;
    port.show = port_show;
    port.watchdog = port_watchdog;
    port.exit = NULL; /* a board does not end */
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
}

int main(void)
{
    uint64_t deadline = 0;
    start();
    for (;;) {
        const uint8_t *data;
        size_t n;
        uint64_t now;
        GPIOR0 = fw_axis_busy(&fw.axis) || fw.steps.head != fw.steps.tail ? BOARD_MARK_MOVING : BOARD_MARK_LOOP;
#ifdef RAMPS_TEST_HANG
        /* test builds only: the simavr harness writes 0xA5 into GPIOR2
           (which nothing else uses) to make the loop hang */
        if (GPIOR2 == 0xA5u) for (;;) {}
#endif
#ifdef RAMPS_TEST_OVERRUN
        /* and 0x5A to make the stack overrun its room (once) */
        if (GPIOR2 == 0x5Au) { GPIOR2 = 0; board_test_overrun(); }
#endif
        if (!board_stack_ok()) fw_stack_fault(&fw, board_ticks());
        n = board_rx_peek(&data);
        if (n) {
            if (n > CHUNK) n = CHUNK;
            n = fw_receive(&fw, data, n, board_ticks());
            board_rx_consume(n);
            deadline = 0; /* what the bytes started may be due before the old deadline */
        }
        now = board_ticks();
        if (now >= deadline) deadline = fw_run(&fw, now);
        else if (!n) board_idle(deadline);
    }
}
