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
static void port_watchdog(void *ctx) { (void)ctx; board_watchdog(); }
static int port_step_arm(void *ctx, uint64_t when, int dir)
{
    (void)ctx;
    (void)dir; /* the pulse sets the direction pin: a step's direction only changes from rest */
    return cm3_alarm_at(CM3_ALARM_STEP, when);
}
static void port_step_pulse(void *ctx, int dir) { (void)ctx; board_step(dir); }
static int port_endstop(void *ctx) { (void)ctx; return board_endstop(); }
/* the exposure's end on the UV alarm, and how late its start was */
static uint64_t uv_end, uv_late;

/* The light goes on when the core's loop gets to `when` (at or just after
   it); the UV alarm ends it that much later, so its length is exact. */
static void port_uv(void *ctx, int on, uint64_t when, uint64_t until)
{
    uint64_t now = cm3_ticks();
    (void)ctx;
    if (on) {
        uv_late = now > when ? now - when : 0;
        uv_end = until + uv_late;
        board_uv(1);
        if (!cm3_alarm_at(CM3_ALARM_UV, uv_end)) board_uv(0);
    } else if (when <= now) { /* a pause, an abort, a fault: now */
        (void)cm3_alarm_at(CM3_ALARM_UV, UINT64_MAX);
        board_uv(0);
    } else if (when + uv_late < uv_end) {
        uv_end = when + uv_late;
        if (!cm3_alarm_at(CM3_ALARM_UV, uv_end)) board_uv(0);
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

/* The boot id: a counter in RAM that the reset code leaves alone (.noinit,
   outside .data and .bss), one more at every start. A reset (the button, the
   watchdog, QEMU's system_reset) keeps RAM; after power-up it holds garbage,
   so a magic word tells a counter that survived from one to seed afresh,
   from that garbage. Never 0 (the host's "no boot id"). */
#define BOOT_MAGIC 0xB007C0DEu
static struct { uint32_t magic, count; } boot __attribute__((section(".noinit")));

static uint32_t next_boot_id(void)
{
    if (boot.magic != BOOT_MAGIC) {
        boot.magic = BOOT_MAGIC;
        boot.count = boot.count * 2654435761u + 0x9E3779B9u;
    }
    if (!++boot.count) boot.count = 1;
    return boot.count;
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
    config.watchdog_ms = BOARD_WATCHDOG_MS;
    /* 5 ms: a move's first step is computed in a pass after the one that
       started it, and passes are held under a step interval at the top
       speed (tests/test_qemu_timing.c asserts it), so the lead covers two
       passes with room to spare. */
    config.step_lead = BOARD_CLOCK_HZ / 200u;
    config.boot_id = next_boot_id();
    config.crc_byte_ns = BOARD_CRC_BYTE_NS;
    config.plan_bin_ns = BOARD_PLAN_BIN_NS;
    port.ctx = NULL;
    port.write = port_write;
    port.step_arm = port_step_arm;
    port.step_pulse = port_step_pulse;
    port.watchdog = port_watchdog;
    port.endstop = port_endstop;
    port.uv = port_uv;
    port.motor = port_motor;
    port.mask_row = port_mask_row;
    port.show = port_show;
    port.exit = BOARD_CAN_EXIT ? port_exit : NULL; /* a real board does not end */
    fw_init(&fw, &config, &port, plan_workspace, sizeof plan_workspace);
    cm3_serve(&fw);
}
