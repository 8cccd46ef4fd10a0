/* The firmware on a Cortex-M3 board: the core's fw_port handed to the
   board's functions (cm3.h), the printer that board.h describes, and the
   serving loop. The board's folder is on the include path, so "board.h" is
   the board's own. */
#include "../../fw.h"
#include "cm3.h"
#include "board.h"

static fw_state fw;
static uint64_t plan_workspace[(FW_PLAN_WORKSPACE(BOARD_MAX_BINS) + 7u) / 8u];

/* How late the step alarm's interrupts came after their ticks. */
static struct { uint32_t steps; uint64_t worst_late; } step_timing;

static void port_write(void *ctx, const uint8_t *data, size_t size) { (void)ctx; board_write(data, size); }
static int port_step_arm(void *ctx, uint64_t when, int dir)
{
    (void)ctx;
    (void)dir; /* the pulse sets the direction pin: a step's direction only changes from rest */
    return cm3_alarm_at(CM3_ALARM_STEP, when);
}
static void port_step_pulse(void *ctx, int dir) { (void)ctx; board_step(dir); }
static int port_endstop(void *ctx) { (void)ctx; return board_endstop(); }
/* The light goes on when the core's loop gets to `when` (at or just after
   it); its end is the UV alarm's, on time. */
static void port_uv(void *ctx, int on, uint64_t when, uint64_t until)
{
    (void)ctx;
    (void)when;
    if (on) {
        board_uv(1);
        if (!cm3_alarm_at(CM3_ALARM_UV, until)) board_uv(0);
    } else {
        (void)cm3_alarm_at(CM3_ALARM_UV, UINT64_MAX);
        board_uv(0);
    }
}

void cm3_alarm_due(int which, uint64_t late)
{
    if (which == CM3_ALARM_UV) {
        board_uv(0);
        return;
    }
    step_timing.steps++;
    if (late > step_timing.worst_late) step_timing.worst_late = late;
    fw_step_interrupt(&fw);
}
static void port_motor(void *ctx, int on) { (void)ctx; board_motor(on); }
static void port_show(void *ctx, int slot, uint64_t when) { (void)ctx; (void)when; board_show(slot); }
static void port_exit(void *ctx, int code) { (void)ctx; board_exit(code); }

static void port_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)ctx;
    board_mask_row(slot, y, row, size);
}

int main(void)
{
    fw_config config;
    fw_port port;
    board_init();
    cm3_z_config(&config, BOARD_CLOCK_HZ, BOARD_STEPS_PER_MM);
    config.display_width = BOARD_DISPLAY_W;
    config.display_height = BOARD_DISPLAY_H;
    config.display_bits = BOARD_DISPLAY_BITS;
    config.pitch_nm = BOARD_PITCH_NM;
    config.max_bins = BOARD_MAX_BINS;
    config.window = BOARD_WINDOW;
    config.watchdog_ms = 0;
    config.step_lead = BOARD_CLOCK_HZ / 1000u; /* 1 ms: the loop's longest pass, and more */
    config.boot_id = 1;
    port.ctx = NULL;
    port.write = port_write;
    port.step_arm = port_step_arm;
    port.step_pulse = port_step_pulse;
    port.watchdog = NULL;
    port.endstop = port_endstop;
    port.uv = port_uv;
    port.motor = port_motor;
    port.mask_row = port_mask_row;
    port.show = port_show;
    port.exit = BOARD_CAN_EXIT ? port_exit : NULL; /* a real board does not end */
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
    cm3_serve(&fw);
}
