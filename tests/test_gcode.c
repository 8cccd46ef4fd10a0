/* G-code mode against a fake host and a fake machine that steps the real
   Z axis (firmware/motion.c) and models its endstop. */
#include "../firmware/gcode.h"
#include "check.h"
#include <string.h>

/* 400 steps/mm (so Z12.345 is step 4938), 10 mm/s, 150 mm of travel. */
static fw_axis_config test_config(void)
{
    fw_axis_config c;
    c.steps_per_mm = 400;
    c.max_speed = 4000;
    c.accel = 40000;
    c.home_speed = 4000;
    c.max_steps = 150 * 400;
    c.home_travel = 170 * 400;
    return c;
}

#define TICK_HZ 1000000u

typedef struct machine {
    fw_axis axis;
    fw_gcode g;
    char out[16384];           /* replies not yet looked at */
    size_t out_len;
    int overflowed;            /* out filled up */
    uint64_t now;
    int32_t phys;              /* steps above the endstop's closing point */
    int endstop_broken;        /* never closes */
    long steps;                /* step pulses so far */
    uint64_t first_step, last_step;
    long steps_at_comp;        /* steps when the last Z_move_comp went out */
    int comps;                 /* Z_move_comp lines so far */
    int uv, motor;             /* as the io left them */
    int uv_calls;
    uint64_t uv_when;
    int uv_end_calls;
    uint64_t uv_end_at;        /* the tick the port's timer was to end the light */
    int not_ascii;             /* a reply byte outside printable ASCII */
} machine;

static void on_write(void *ctx, const uint8_t *data, size_t size)
{
    machine *m = (machine *)ctx;
    size_t i;
    for (i = 0; i < size; i++)
        if (data[i] != '\n' && (data[i] < 0x20 || data[i] > 0x7e)) m->not_ascii = 1;
    CHECK(size > 0 && data[size - 1] == '\n');
    if (size == 12 && !memcmp(data, "Z_move_comp\n", 12)) {
        /* the move is over and its last step already taken */
        CHECK(!fw_axis_busy(&m->axis));
        CHECK(m->steps == 0 || m->now >= m->last_step);
        m->comps++;
        m->steps_at_comp = m->steps;
    }
    if (m->out_len + size >= sizeof m->out) { m->overflowed = 1; return; }
    memcpy(m->out + m->out_len, data, size);
    m->out_len += size;
    m->out[m->out_len] = 0;
}

static void on_uv(void *ctx, int on, uint64_t when)
{
    machine *m = (machine *)ctx;
    m->uv = on;
    m->uv_calls++;
    m->uv_when = when;
    CHECK(!fw_axis_busy(&m->axis)); /* never light while Z moves */
}

static void on_uv_end(void *ctx, uint64_t when)
{
    machine *m = (machine *)ctx;
    CHECK(m->uv == 1); /* only a light M106 put on */
    m->uv_end_calls++;
    m->uv_end_at = when;
}

static void on_motor(void *ctx, int on)
{
    ((machine *)ctx)->motor = on;
}

static void machine_init(machine *m, const fw_axis_config *c, int32_t phys)
{
    fw_gcode_io io;
    memset(m, 0, sizeof *m);
    fw_axis_init(&m->axis, c, TICK_HZ);
    io.ctx = m;
    io.write = on_write;
    io.uv = on_uv;
    io.uv_end = on_uv_end;
    io.motor = on_motor;
    io.moving = NULL;
    fw_gcode_init(&m->g, &m->axis, &io);
    m->phys = phys;
    m->now = 1000;
}

/* The module's pieces of work that are ready at this tick, one a call, as
   a port's loop passes would run them before the next step is due (at
   most four in a row: a move's end, the held line's check, its run, the
   move it starts; a step due now also returns now). */
static void pump(machine *m)
{
    int k;
    for (k = 0; k < 4 && fw_gcode_run(&m->g, m->now) == m->now; k++) {}
}

/* One step of the axis at its scheduled tick, then the module's turn. */
static void step_once(machine *m)
{
    uint64_t t = fw_axis_next(&m->axis);
    int dir;
    if (t > m->now) m->now = t;
    dir = fw_axis_step(&m->axis, !m->endstop_broken && m->phys <= 0);
    if (dir) {
        if (!m->steps) m->first_step = m->now;
        m->steps++;
        m->last_step = m->now;
        m->phys += dir;
    }
    pump(m);
}

/* Steps and waits until nothing is left to do; time jumps to each deadline. */
static void settle(machine *m)
{
    long guard;
    for (guard = 0; guard < 10000000; guard++) {
        uint64_t d;
        if (fw_axis_busy(&m->axis)) { step_once(m); continue; }
        d = fw_gcode_run(&m->g, m->now);
        if (d == FW_NEVER) return;
        if (d > m->now) m->now = d;
    }
    CHECK(!"settle never ended");
}

/* Host bytes, all of them, each line run as it comes: what the module
   does not take yet is offered again after the machine has settled, as a
   port's receive ring would. */
static void feed(machine *m, const char *s, size_t n)
{
    int rounds = 0;
    while (n) {
        size_t used = fw_gcode_receive(&m->g, (const uint8_t *)s, n);
        CHECK(used <= n);
        s += used;
        n -= used;
        pump(m);
        if (n && !used) {
            CHECK(fw_axis_busy(&m->axis) || fw_gcode_run(&m->g, m->now) != FW_NEVER);
            settle(m);
            if (++rounds > 100000) { CHECK(!"feed stuck"); return; }
        }
    }
}

static void host(machine *m, const char *s) { feed(m, s, strlen(s)); }

/* The replies since the last call, and forget them. */
static const char *replies(machine *m)
{
    static char copy[sizeof ((machine *)0)->out];
    memcpy(copy, m->out, m->out_len + 1);
    m->out_len = 0;
    m->out[0] = 0;
    return copy;
}

#define EXPECT(m, want) do { const char *got_ = replies(m); \
    CHECKF(!strcmp(got_, want), "replies\n%s\nwanted\n%s", got_, want); } while (0)

static void homed(machine *m)
{
    host(m, "G28\n");
    settle(m);
    EXPECT(m, "Z_move_comp\nok\n");
    CHECK(m->axis.homed && m->axis.position == m->phys);
}

/* "N<n> <cmd>*<xor>" as printcore's _send builds it */
static const char *numbered(long n, const char *cmd)
{
    static char line[160];
    char body[140];
    int x = 0, i;
    snprintf(body, sizeof body, "N%ld %s", n, cmd);
    for (i = 0; body[i]; i++) x ^= (unsigned char)body[i];
    snprintf(line, sizeof line, "%s*%d\n", body, x);
    return line;
}

static void every_command_replies(void)
{
    static machine m;
    fw_axis_config c = test_config();
    machine_init(&m, &c, 8000);
    host(&m, "M105\n"); EXPECT(&m, "ok\n");
    host(&m, "M115\n");
    EXPECT(&m, "FIRMWARE_NAME:adaslice PROTOCOL_VERSION:1.0 MACHINE_TYPE:MSLA EXTRUDER_COUNT:0\n"
               "echo:Z_MAX_MM:150.000 STEPS_PER_MM:400\necho:Z_MAX_SPEED_MM_S:10.000 MAX_EXPOSURE_MS:300000\nok\n");
    host(&m, "G1 Z5\n"); EXPECT(&m, "Error:Home Z first\nok\n");
    CHECK(m.steps == 0 && m.motor == 0);
    host(&m, "G28\n");
    EXPECT(&m, ""); /* homing under way: ok comes at its end */
    CHECK(m.motor == 1);
    settle(&m);
    EXPECT(&m, "Z_move_comp\nok\n");
    CHECK(m.axis.homed);
    host(&m, "G90\n"); EXPECT(&m, "ok\n");
    host(&m, "G91\n"); EXPECT(&m, "ok\n");
    host(&m, "G90\n"); EXPECT(&m, "ok\n");
    host(&m, "M18\n"); EXPECT(&m, "ok\n"); CHECK(m.motor == 0);
    host(&m, "M17\n"); EXPECT(&m, "ok\n"); CHECK(m.motor == 1);
    host(&m, "M84\n"); EXPECT(&m, "ok\n"); CHECK(m.motor == 0);
    host(&m, "M106\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 1 && m.uv_when == m.now);
    host(&m, "M106 S0\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 0);
    host(&m, "M106 S255\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 1);
    host(&m, "M107\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 0 && m.uv_calls == 4);
    host(&m, "M106 S-1\n"); EXPECT(&m, "Error:Number out of range for S\nok\n"); CHECK(m.uv_calls == 4);
    host(&m, "M400\n"); EXPECT(&m, "ok\n");
    host(&m, "G4\n"); EXPECT(&m, "ok\n");
    host(&m, "M114\n"); EXPECT(&m, "X:0.00 Y:0.00 Z:0.000 E:0.00 Count Z:0\nok\n");
    host(&m, "G1 Z12.345 F600\n"); EXPECT(&m, "ok\n");
    CHECK(m.motor == 1); /* a move turns the driver on */
    settle(&m);
    EXPECT(&m, "Z_move_comp\n");
    host(&m, "M114\n"); EXPECT(&m, "X:0.00 Y:0.00 Z:12.345 E:0.00 Count Z:4938\nok\n");
    host(&m, "M110 N41\n"); EXPECT(&m, "ok\n");
    host(&m, numbered(42, "M400")); EXPECT(&m, "ok\n");
    host(&m, "M999\n"); EXPECT(&m, "echo:Unknown command: \"M999\"\nok\n");
    host(&m, "G92 E0\n"); EXPECT(&m, "echo:Unknown command: \"G92 E0\"\nok\n");
    host(&m, "M117 Hello, world!  \n"); EXPECT(&m, "echo:Unknown command: \"M117 Hello, world!\"\nok\n");
    host(&m, "T0\n"); EXPECT(&m, "echo:Unknown command: \"T0\"\nok\n");
    host(&m, "G1.5\n"); EXPECT(&m, "echo:Unknown command: \"G1.5\"\nok\n");
    /* comments and blank lines: nothing, as in Marlin */
    host(&m, "\n\r\n   \n; a comment\n(another)\n  (x) ; y\n"); EXPECT(&m, "");
    host(&m, "m114 ; lower case, comment\n");
    EXPECT(&m, "X:0.00 Y:0.00 Z:12.345 E:0.00 Count Z:4938\nok\n");
    host(&m, "G1 Z1 (to there)\n"); EXPECT(&m, "ok\n");
    settle(&m);
    EXPECT(&m, "Z_move_comp\n");
    CHECK(m.axis.position == 400);
    host(&m, "G1 Z2 X10 Y10 E3\n"); /* other axes are not ours */
    settle(&m);
    EXPECT(&m, "ok\nZ_move_comp\n");
    CHECK(m.axis.position == 800);
    host(&m, "G1 Z2 \x01\n"); EXPECT(&m, "Error:Unexpected character in command\nok\n");
    host(&m, "G1 Zabc\n"); EXPECT(&m, "Error:Bad number for Z\nok\n");
    host(&m, "G1 Z1.2.3\n"); EXPECT(&m, "Error:Bad number for Z\nok\n");
    host(&m, "G1 Z\n"); EXPECT(&m, "Error:Bad number for Z\nok\n");
    CHECK(m.axis.position == 800 && !m.not_ascii && !m.overflowed);
}

/* Each Z_move_comp after the last step of its move, once per move. */
static void moves_reach_exact_steps(void)
{
    static machine m;
    fw_axis_config c = test_config();
    int i, comps;
    machine_init(&m, &c, 3000);
    homed(&m);
    comps = m.comps;
    host(&m, "G90\nG1 Z12.345 F300\n");
    settle(&m);
    CHECK(m.axis.position == 4938 && m.phys == 4938);
    CHECK(m.comps == comps + 1 && m.steps_at_comp == m.steps);
    host(&m, "G1 Z0.0025\n"); settle(&m); CHECK(m.axis.position == 1);
    host(&m, "G1 Z0.00125\n"); settle(&m); CHECK(m.axis.position == 1); /* half a step rounds up */
    host(&m, "G1 Z0.001249\n"); settle(&m); CHECK(m.axis.position == 0);
    host(&m, "G1 Z+3.0000004\n"); settle(&m); CHECK(m.axis.position == 1200);
    /* relative: 200 x 0.05 mm = 10 mm, and back down in 0.0125 mm steps */
    host(&m, "G91\n");
    for (i = 0; i < 200; i++) host(&m, "G1 Z0.05\n");
    settle(&m);
    CHECK(m.axis.position == 1200 + 4000 && m.phys == m.axis.position);
    for (i = 0; i < 800; i++) host(&m, "G1 Z-.0125\n");
    settle(&m);
    CHECK(m.axis.position == 1200);
    CHECK(m.comps == comps + 5 + 1000 && m.steps_at_comp == m.steps);
    replies(&m);
    host(&m, "G90\nM114\n");
    EXPECT(&m, "ok\nX:0.00 Y:0.00 Z:3.000 E:0.00 Count Z:1200\nok\n");
}

/* 333 steps/mm: 0.05 mm is 16.65 steps, so only exact bookkeeping in nm
   lands every relative move on round(k * 16.65). */
static void relative_moves_do_not_drift(void)
{
    static machine m;
    fw_axis_config c = test_config();
    int i;
    c.steps_per_mm = 333;
    c.max_steps = 150 * 333;
    machine_init(&m, &c, 100);
    homed(&m);
    host(&m, "G91\n");
    for (i = 1; i <= 200; i++) {
        host(&m, "G1 Z0.05 F600\n");
        settle(&m);
        CHECKF(m.axis.position == (i * 1665 + 50) / 100, "move %d at %d", i, (int)m.axis.position);
    }
    CHECK(m.axis.position == 3330);
    host(&m, "G90\nG1 Z10\n");
    settle(&m);
    CHECK(m.axis.position == 3330);
    replies(&m);
    host(&m, "M114\n");
    EXPECT(&m, "X:0.00 Y:0.00 Z:10.000 E:0.00 Count Z:3330\nok\n");
    host(&m, "G1 Z0.1\nM114\n");
    settle(&m);
    EXPECT(&m, "ok\nZ_move_comp\nX:0.00 Y:0.00 Z:0.099 E:0.00 Count Z:33\nok\n");
}

static void feed_rates(void)
{
    static machine m;
    fw_axis_config c = test_config();
    uint64_t took;
    machine_init(&m, &c, 10);
    homed(&m);
    host(&m, "G1 Z10 F0\n"); EXPECT(&m, "Error:Number out of range for F\nok\n");
    host(&m, "G1 Z10 F-300\n"); EXPECT(&m, "Error:Number out of range for F\nok\n");
    host(&m, "G1 Z10 F100000000\n"); EXPECT(&m, "Error:Number out of range for F\nok\n");
    host(&m, "G1 Z10 F99999999999999999999999999\n"); EXPECT(&m, "Error:Number out of range for F\nok\n");
    settle(&m);
    CHECK(m.axis.position == 0 && m.comps == 1);
    /* F60 is 1 mm/s: 4000 steps take at least 10 s */
    host(&m, "G1 F60\n"); EXPECT(&m, "ok\n");
    CHECK(!fw_axis_busy(&m.axis));
    m.steps = 0;
    host(&m, "G1 Z10\n");
    settle(&m);
    took = m.last_step - m.first_step;
    CHECKF(took >= 10 * (uint64_t)TICK_HZ - TICK_HZ / 400 && took < 11 * (uint64_t)TICK_HZ, "F60: %llu ticks", (unsigned long long)took);
    /* remembered for the next move */
    m.steps = 0;
    host(&m, "G1 Z0\n");
    settle(&m);
    took = m.last_step - m.first_step;
    CHECKF(took >= 10 * (uint64_t)TICK_HZ - TICK_HZ / 400, "F60 again: %llu ticks", (unsigned long long)took);
    /* above max_speed (600 mm/min): clamped, 10 mm take at least 1 s */
    m.steps = 0;
    host(&m, "G1 Z10 F100000\n");
    settle(&m);
    took = m.last_step - m.first_step;
    CHECKF(took >= TICK_HZ - TICK_HZ / 4000 && took < 2 * (uint64_t)TICK_HZ, "F100000: %llu ticks", (unsigned long long)took);
    /* slower than a step a second still moves */
    m.steps = 0;
    host(&m, "G1 Z10.005 F0.001\n");
    settle(&m);
    CHECK(m.axis.position == 4002 && m.last_step - m.first_step >= TICK_HZ / 2);
}

static void soft_limits(void)
{
    static machine m;
    fw_axis_config c = test_config();
    machine_init(&m, &c, 10);
    homed(&m);
    host(&m, "G1 Z150.0025\n"); EXPECT(&m, "Error:Z outside soft limits 0.000..150.000\nok\n");
    host(&m, "G1 Z-0.05\n"); EXPECT(&m, "Error:Z outside soft limits 0.000..150.000\nok\n");
    host(&m, "G1 Z10000000\n"); EXPECT(&m, "Error:Z outside soft limits 0.000..150.000\nok\n");
    host(&m, "G1 Z10000001\n"); EXPECT(&m, "Error:Number out of range for Z\nok\n");
    host(&m, "G1 Z-18446744073709551616\n"); EXPECT(&m, "Error:Number out of range for Z\nok\n");
    settle(&m);
    CHECK(m.axis.position == 0 && m.comps == 1 && m.steps_at_comp == m.steps);
    host(&m, "G1 Z150\n"); settle(&m); EXPECT(&m, "ok\nZ_move_comp\n");
    CHECK(m.axis.position == 60000);
    host(&m, "G91\nG1 Z0.0025\n"); EXPECT(&m, "ok\nError:Z outside soft limits 0.000..150.000\nok\n");
    host(&m, "G1 Z-150.0025\n"); EXPECT(&m, "Error:Z outside soft limits 0.000..150.000\nok\n");
    host(&m, "G1 Z-150\n"); settle(&m); EXPECT(&m, "ok\nZ_move_comp\n");
    CHECK(m.axis.position == 0 && m.comps == 3);
}

static void homing_failure(void)
{
    static machine m;
    fw_axis_config c = test_config();
    machine_init(&m, &c, 2000);
    m.endstop_broken = 1;
    host(&m, "G28\n");
    settle(&m);
    EXPECT(&m, "Error:Homing failed\nok\n");
    CHECK(m.comps == 0 && !m.axis.homed);
    host(&m, "G1 Z1\n"); EXPECT(&m, "Error:Home Z first\nok\n");
    /* the position counts the steps homing went down */
    host(&m, "M114\n");
    {
        char want[96];
        long at = (long)m.axis.position, micron = (-at * 1000 + 200) / 400; /* to nearest */
        CHECK(at < -400 * 150);
        snprintf(want, sizeof want, "X:0.00 Y:0.00 Z:-%ld.%03ld E:0.00 Count Z:%ld\nok\n",
                 micron / 1000, micron % 1000, at);
        EXPECT(&m, want);
    }
    m.endstop_broken = 0;
    m.phys = 2000; /* the switch mended, the platform put back */
    homed(&m);
}

/* What printcore sends (N-1 M110 first, then N0...) and what it parses. */
static void line_numbers_and_checksums(void)
{
    static machine m;
    fw_axis_config c = test_config();
    char bad[64];
    machine_init(&m, &c, 10);
    host(&m, "N-1 M110*15\n"); EXPECT(&m, "ok\n");
    host(&m, numbered(0, "G90")); EXPECT(&m, "ok\n");
    /* a wrong checksum: not run, resend asked for */
    strcpy(bad, numbered(1, "M106"));
    bad[strlen(bad) - 2] ^= 1;
    host(&m, bad);
    EXPECT(&m, "Error:checksum mismatch, Last Line: 0\nResend: 1\nok\n");
    CHECK(m.uv_calls == 0);
    host(&m, "N1 M106\n");
    EXPECT(&m, "Error:No Checksum with line number, Last Line: 0\nResend: 1\nok\n");
    host(&m, "N1 M106*\n");
    EXPECT(&m, "Error:checksum mismatch, Last Line: 0\nResend: 1\nok\n");
    host(&m, "N1 M106*999\n");
    EXPECT(&m, "Error:checksum mismatch, Last Line: 0\nResend: 1\nok\n");
    host(&m, numbered(2, "M106"));
    EXPECT(&m, "Error:Line Number is not Last Line Number+1, Last Line: 0\nResend: 1\nok\n");
    host(&m, numbered(0, "M106"));
    EXPECT(&m, "Error:Line Number is not Last Line Number+1, Last Line: 0\nResend: 1\nok\n");
    host(&m, "N99999999999 M106*45\n");
    EXPECT(&m, "Error:Line Number is not Last Line Number+1, Last Line: 0\nResend: 1\nok\n");
    CHECK(m.uv_calls == 0);
    host(&m, numbered(1, "M106")); EXPECT(&m, "ok\n");
    CHECK(m.uv_calls == 1 && m.uv == 1);
    host(&m, numbered(2, "M107")); EXPECT(&m, "ok\n");
    /* checksum then blanks or a comment; unnumbered lines between */
    host(&m, "N3 M400*37  \n"); EXPECT(&m, "Error:checksum mismatch, Last Line: 2\nResend: 3\nok\n");
    {
        char line[64];
        strcpy(line, numbered(3, "M400"));
        strcpy(line + strlen(line) - 1, "  ; done\n");
        host(&m, line); EXPECT(&m, "ok\n");
    }
    host(&m, "M400\n"); EXPECT(&m, "ok\n");
    host(&m, "M400*0\n"); EXPECT(&m, "Error:checksum mismatch, Last Line: 3\nok\n");
    host(&m, "M400*121\n"); EXPECT(&m, "ok\n"); /* 'M' ^ '4' ^ '0' ^ '0' */
    host(&m, numbered(4, "M999")); EXPECT(&m, "echo:Unknown command: \"M999\"\nok\n");
    host(&m, numbered(5, "")); EXPECT(&m, "ok\n");
    /* M110 takes any line number, and its N word wins */
    host(&m, numbered(77, "M110 N1000")); EXPECT(&m, "ok\n");
    host(&m, numbered(1001, "M400")); EXPECT(&m, "ok\n");
    host(&m, numbered(-1, "M110")); EXPECT(&m, "ok\n");
    host(&m, numbered(0, "M400")); EXPECT(&m, "ok\n");
    host(&m, "M110 N2147483647\n"); EXPECT(&m, "ok\n");
    host(&m, numbered(-2147483647 - 1L, "M400"));
    EXPECT(&m, "Error:Line Number is not Last Line Number+1, Last Line: 2147483647\nResend: 2147483648\nok\n");
    host(&m, "M110 N2147483648\n"); EXPECT(&m, "Error:Bad line number\nok\n");
    host(&m, "M110 N-2147483647\n"); EXPECT(&m, "ok\n");
    host(&m, numbered(-2147483646L, "M400")); EXPECT(&m, "ok\n");
    /* a line number with CR LF and lower case */
    host(&m, "M110 N0\r\n"); EXPECT(&m, "ok\n");
    host(&m, "n1 m400*38\r\n"); EXPECT(&m, "ok\n");
    CHECK(!m.not_ascii);
}

/* The ok of G1 at its start, the next line held until the move has
   ended, and nothing more taken meanwhile. */
static void held_line_while_moving(void)
{
    static machine m;
    fw_axis_config c = test_config();
    const char *in = "G1 Z10 F600\nM114\nM106\n";
    size_t used;
    machine_init(&m, &c, 10);
    homed(&m);
    /* a line at a time; it runs in fw_gcode_run */
    used = fw_gcode_receive(&m.g, (const uint8_t *)in, strlen(in));
    CHECK(used == strlen("G1 Z10 F600\n"));
    EXPECT(&m, "");
    pump(&m);
    EXPECT(&m, "ok\n");
    CHECK(fw_axis_busy(&m.axis));
    used += fw_gcode_receive(&m.g, (const uint8_t *)in + used, strlen(in) - used);
    CHECK(used == strlen("G1 Z10 F600\nM114\n"));
    pump(&m);
    EXPECT(&m, "");
    CHECK(fw_gcode_receive(&m.g, (const uint8_t *)in + used, strlen(in) - used) == 0);
    CHECK(fw_gcode_run(&m.g, m.now) == fw_axis_next(&m.axis));
    while (fw_axis_busy(&m.axis)) {
        step_once(&m);
        if (fw_axis_busy(&m.axis)) CHECK(m.out_len == 0);
    }
    EXPECT(&m, "Z_move_comp\nX:0.00 Y:0.00 Z:10.000 E:0.00 Count Z:4000\nok\n");
    CHECK(fw_gcode_run(&m.g, m.now) == FW_NEVER);
    used += fw_gcode_receive(&m.g, (const uint8_t *)in + used, strlen(in) - used);
    CHECK(used == strlen(in));
    pump(&m);
    EXPECT(&m, "ok\n");
    CHECK(m.uv == 1 && m.uv_when >= m.last_step);
    /* homing holds the next line too, and its ok waits for it */
    host(&m, "M107\nG28\nG1 Z1\n");
    EXPECT(&m, "ok\n");
    settle(&m);
    EXPECT(&m, "Z_move_comp\nok\nok\nZ_move_comp\n");
    CHECK(m.axis.position == 400);
    /* a CR LF held: the LF waits with the rest */
    in = "G1 Z2\r\nM400\r\n";
    used = fw_gcode_receive(&m.g, (const uint8_t *)in, strlen(in));
    CHECK(used == strlen("G1 Z2\r"));
    pump(&m);
    used += fw_gcode_receive(&m.g, (const uint8_t *)in + used, strlen(in) - used);
    CHECK(used == strlen("G1 Z2\r\nM400\r"));
    settle(&m);
    CHECK(fw_gcode_receive(&m.g, (const uint8_t *)in + used, 1) == 1);
    EXPECT(&m, "ok\nZ_move_comp\nok\n");
}

/* A move the core started itself holds G-code lines the same way, and Z
   follows where it went. */
static void lines_wait_for_the_cores_moves(void)
{
    static machine m;
    fw_axis_config c = test_config();
    machine_init(&m, &c, 10);
    homed(&m);
    host(&m, "G1 Z1\n");
    settle(&m);
    EXPECT(&m, "ok\nZ_move_comp\n");
    CHECK(fw_axis_move_to(&m.axis, 2000, 0, m.now) == FW_AXIS_OK);
    CHECK(fw_gcode_receive(&m.g, (const uint8_t *)"G91\nG1 Z1\n", 10) == 4);
    CHECK(fw_gcode_run(&m.g, m.now) == fw_axis_next(&m.axis));
    EXPECT(&m, "");
    settle(&m);
    EXPECT(&m, "ok\n");
    host(&m, "G1 Z1\n");
    settle(&m);
    EXPECT(&m, "ok\nZ_move_comp\n");
    CHECK(m.axis.position == 2400 && m.phys == 2400);
}

/* Pronterface's jog: G91, G1, G90 sent at once, twice. */
static void unpaced_commands_queue_in_order(void)
{
    static machine m;
    fw_axis_config c = test_config();
    machine_init(&m, &c, 10);
    homed(&m);
    host(&m, "G91\nG1 Z10 F600\nG90\nG91\nG1 Z-2.5 F600\nG90\nM114\n");
    settle(&m);
    EXPECT(&m, "ok\nok\nZ_move_comp\nok\nok\nok\nZ_move_comp\nok\nX:0.00 Y:0.00 Z:7.500 E:0.00 Count Z:3000\nok\n");
}

static void long_lines(void)
{
    static machine m;
    fw_axis_config c = test_config();
    char line[400];
    machine_init(&m, &c, 10);
    host(&m, "M110 N7\n"); EXPECT(&m, "ok\n");
    /* exactly FW_GCODE_LINE_MAX bytes: fine */
    memset(line, ' ', sizeof line);
    memcpy(line, "M400", 4);
    line[FW_GCODE_LINE_MAX] = '\n';
    feed(&m, line, FW_GCODE_LINE_MAX + 1);
    EXPECT(&m, "ok\n");
    /* one more: dropped whole, line number kept */
    memcpy(line, "M106", 4);
    line[FW_GCODE_LINE_MAX] = ' ';
    line[FW_GCODE_LINE_MAX + 1] = '\n';
    feed(&m, line, FW_GCODE_LINE_MAX + 2);
    EXPECT(&m, "Error:Line too long, Last Line: 7\nok\n");
    memset(line, 'G', sizeof line);
    line[sizeof line - 1] = '\r';
    feed(&m, line, sizeof line);
    EXPECT(&m, "Error:Line too long, Last Line: 7\nok\n");
    CHECK(m.uv_calls == 0);
    host(&m, numbered(8, "M400")); EXPECT(&m, "ok\n");
    /* the longest echo fits */
    memset(line, '~', sizeof line);
    line[0] = 'Q';
    line[FW_GCODE_LINE_MAX] = '\n';
    feed(&m, line, FW_GCODE_LINE_MAX + 1);
    {
        const char *got = replies(&m);
        CHECK(strlen(got) == strlen("echo:Unknown command: \"\"\nok\n") + FW_GCODE_LINE_MAX);
        CHECK(!strncmp(got + 23 + FW_GCODE_LINE_MAX - 1, "~\"\nok\n", 6));
    }
}

/* Line noise: every non-blank line still gets one ok and ASCII replies. */
static void binary_noise(void)
{
    static machine m;
    fw_axis_config c = test_config();
    uint32_t seed = 12345;
    char buf[256];
    int round, i, lines = 0, oks = 0, len = 0;
    machine_init(&m, &c, 10);
    homed(&m);
    feed(&m, "\x00\xff\x01 \x80\n", 6);
    EXPECT(&m, "echo:Unknown command: \"?\?? ?\"\nok\n");
    for (round = 0; round < 3000; round++) {
        int n = 0;
        const char *got, *p;
        seed = seed * 1103515245u + 12345u;
        n = 1 + (int)(seed >> 16) % (int)sizeof buf;
        for (i = 0; i < n; i++) {
            seed = seed * 1103515245u + 12345u;
            /* mostly G-code-ish bytes so commands do run */
            buf[i] = (seed >> 24) < 40 ? (char)(seed >> 8) : "G1MZ-0.5 FN*;()\n\r4028911S"[(seed >> 8) % 26];
        }
        /* count what a line would be as the module splits them */
        for (i = 0; i < n; i++) {
            if (buf[i] == '\n' || buf[i] == '\r') {
                if (len) lines++;
                len = 0;
            } else len++;
        }
        feed(&m, buf, (size_t)n);
        settle(&m);
        got = replies(&m);
        for (p = got; (p = strstr(p, "ok\n")) != NULL; p += 3)
            if (p == got || p[-1] == '\n') oks++;
        CHECK(!m.overflowed);
    }
    /* blank-looking lines (only blanks and comments) get nothing */
    CHECKF(oks <= lines && oks > lines / 2, "%d oks for %d lines", oks, lines);
    CHECK(!m.not_ascii);
    CHECK(m.axis.position == m.phys);
}

static void dwell(void)
{
    static machine m;
    fw_axis_config c = test_config();
    uint64_t start, d;
    machine_init(&m, &c, 10);
    start = m.now;
    host(&m, "G4 P1500\n");
    EXPECT(&m, "");
    d = fw_gcode_run(&m.g, start + 1499999);
    CHECK(d == start + 1500000);
    EXPECT(&m, "");
    CHECK(fw_gcode_run(&m.g, start + 1500000) == start + 1500000); /* it ended a dwell */
    CHECK(fw_gcode_run(&m.g, start + 1500000) == FW_NEVER);
    EXPECT(&m, "ok\n");
    host(&m, "G4 S2\n");
    CHECK(fw_gcode_run(&m.g, m.now) == m.now + 2 * (uint64_t)TICK_HZ);
    settle(&m);
    EXPECT(&m, "ok\n");
    host(&m, "G4 P0.0005\n"); /* half a microsecond rounds up to a tick */
    CHECK(fw_gcode_run(&m.g, m.now) == m.now + 1);
    settle(&m);
    host(&m, "G4 P0\nG4 S0\n"); EXPECT(&m, "ok\nok\nok\n");
    host(&m, "G4 P-1\n"); EXPECT(&m, "Error:Number out of range for P\nok\n");
    host(&m, "G4 S10000000\n"); /* 115 days, no overflow */
    CHECK(fw_gcode_run(&m.g, m.now) == m.now + 10000000ull * TICK_HZ);
    /* a line during the dwell waits for it */
    start = m.now;
    host(&m, "M106\n");
    CHECK(m.uv_calls == 0);
    settle(&m);
    CHECK(m.uv_calls == 1 && m.uv_when == start + 10000000ull * TICK_HZ);
    EXPECT(&m, "ok\nok\n");
    /* homing under M106's light: the light goes out first */
    host(&m, "G28\n");
    CHECK(m.uv == 0 && m.uv_calls == 2);
    settle(&m);
    EXPECT(&m, "echo:UV off: Z moves only in the dark\nZ_move_comp\nok\n");
    /* after a move: the dwell starts when the move has ended */
    host(&m, "G1 Z10 F600\nG4 P100\n");
    start = m.now;
    settle(&m);
    CHECK(m.now == m.last_step + 100000);
    CHECK(m.uv_end_calls == 0); /* M106 before the move: not an exposure's dwell */
    EXPECT(&m, "ok\nZ_move_comp\nok\n");
    CHECK(start < m.last_step);
}

/* M106, G4, M107 (NanoDLP's layer): the dwell after M106 counts from M106
   and the port's timer ends the light at its end, so the host's round trips
   between the lines add nothing to the exposure. */
static void lit_dwell_is_the_exposure(void)
{
    static machine m;
    fw_axis_config c = test_config();
    uint64_t lit;
    machine_init(&m, &c, 10);
    lit = m.now;
    host(&m, "M106 S255\n");
    EXPECT(&m, "ok\n");
    m.now += 3000; /* the ok's and the next line's way over the wire */
    host(&m, "G4 P100\n");
    CHECKF(m.uv_end_calls == 1 && m.uv_end_at == lit + 100000, "the light to end at %llu, M106 at %llu",
           (unsigned long long)m.uv_end_at, (unsigned long long)lit);
    CHECK(fw_gcode_run(&m.g, m.now) == lit + 100000);
    EXPECT(&m, "");
    CHECK(fw_gcode_run(&m.g, lit + 100000) == lit + 100000);
    CHECK(fw_gcode_run(&m.g, lit + 100000) == FW_NEVER);
    EXPECT(&m, "ok\n");
    m.now = lit + 100000 + 2000;
    host(&m, "M107\n");
    EXPECT(&m, "ok\n");
    CHECK(m.uv == 0 && m.uv_calls == 2);
    /* a dwell with the light out is a plain one, from its own line */
    host(&m, "G4 P10\n");
    CHECK(m.uv_end_calls == 1 && fw_gcode_run(&m.g, m.now) == m.now + 10000);
    settle(&m);
    EXPECT(&m, "ok\n");
    /* only the first dwell after M106 is the exposure */
    lit = m.now;
    host(&m, "M106\nG4 P5\n");
    settle(&m);
    host(&m, "G4 P5\n");
    settle(&m);
    EXPECT(&m, "ok\nok\nok\n");
    CHECK(m.uv_end_calls == 2 && m.uv_end_at == lit + 5000 && m.now == lit + 10000);
    /* a dwell that comes after its time: the light out at once, ok now */
    lit = m.now;
    host(&m, "M106\n");
    m.now += 50000;
    host(&m, "G4 P20\n");
    EXPECT(&m, "ok\necho:Exposure ran over: G4 came 30.000 ms after its end\nok\n");
    CHECK(m.uv_end_calls == 3 && m.uv_end_at == lit + 20000);
    /* M106 S0 puts it out: the dwell after it is plain */
    host(&m, "M106 S0\nG4 P1\n");
    settle(&m);
    CHECK(m.uv_end_calls == 3);
    EXPECT(&m, "ok\nok\n");
}

/* Z never moves under the light: G0/G1 after M106 (no M107) put it out
   before the first step and say so; a G1 refused (unhomed, out of limits)
   moves nothing and leaves it. */
static void no_move_under_the_light(void)
{
    static machine m;
    fw_axis_config c = test_config();
    long before;
    machine_init(&m, &c, 800);
    homed(&m);
    before = m.steps;
    host(&m, "M106 S255\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 1);
    host(&m, "G1 Z9999\n");
    CHECKF(m.uv == 1 && m.steps == before, "uv %d, %ld steps", m.uv, m.steps - before); /* refused: nothing moves */
    replies(&m);
    host(&m, "G1 Z5\n");
    CHECK(m.uv == 0 && m.uv_calls == 2); /* out before any step (on_uv checks the axis idle) */
    settle(&m);
    EXPECT(&m, "echo:UV off: Z moves only in the dark\nok\nZ_move_comp\n");
    CHECKF(m.steps - before == 2000, "%ld steps", m.steps - before);
    /* a dwell after that move is no exposure's */
    host(&m, "G4 P10\n"); settle(&m); EXPECT(&m, "ok\n");
    CHECK(m.uv_end_calls == 0 && m.uv_calls == 2);
}

/* M106's light with no dwell to end it goes out when the host says nothing
   for the timeout, counted from M106 or its last byte, whichever is later. */
static void silent_host_puts_the_light_out(void)
{
    static machine m;
    fw_axis_config c = test_config();
    const uint64_t timeout = TICK_HZ; /* 1 s */
    uint64_t heard, lit;
    machine_init(&m, &c, 800);
    homed(&m);
    CHECK(fw_gcode_watch(&m.g, m.now, timeout, m.now) == FW_NEVER); /* dark: nothing to watch */
    host(&m, "M106\n"); EXPECT(&m, "ok\n");
    lit = m.now;
    CHECK(fw_gcode_watch(&m.g, lit, timeout, lit) == lit + timeout);
    m.now = lit + timeout / 2;
    host(&m, "M105\n"); EXPECT(&m, "ok\n"); /* a keepalive: heard again */
    heard = m.now;
    CHECK(fw_gcode_watch(&m.g, heard, timeout, lit + timeout) == heard + timeout && m.uv == 1);
    CHECK(fw_gcode_watch(&m.g, heard, timeout, heard + timeout - 1) == heard + timeout && m.uv == 1);
    CHECK(fw_gcode_watch(&m.g, heard, timeout, heard + timeout) == FW_NEVER);
    CHECK(m.uv == 0 && m.uv_when == heard + timeout);
    EXPECT(&m, "echo:UV off: the host went silent after M106\n");
    /* an exposure's dwell is the light's own end: nothing to watch */
    host(&m, "M106\nG4 P3000\n");
    CHECK(fw_gcode_watch(&m.g, m.now, timeout, m.now + 2 * timeout) == FW_NEVER && m.uv == 1);
    settle(&m);
    EXPECT(&m, "ok\nok\n");
    /* after a fault or M112 (fw_gcode_dark halted) M106 waits for G28 */
    fw_gcode_dark(&m.g, 1);
    host(&m, "M106\n"); EXPECT(&m, "Error:Stopped: home Z (G28) before UV\nok\n");
    host(&m, "M106 S0\n"); EXPECT(&m, "ok\n"); /* off is always allowed */
    homed(&m);
    host(&m, "M106\n"); EXPECT(&m, "ok\n"); CHECK(m.uv == 1);
}

/* The core may halt a move; no Z_move_comp then, and Z is where the axis is. */
static void halted_move(void)
{
    static machine m;
    fw_axis_config c = test_config();
    int i;
    machine_init(&m, &c, 10);
    homed(&m);
    host(&m, "G1 Z100 F600\n");
    EXPECT(&m, "ok\n");
    for (i = 0; i < 1000; i++) step_once(&m);
    fw_axis_halt(&m.axis, m.now);
    settle(&m);
    {
        const char *got = replies(&m);
        CHECKF(!strncmp(got, "Error:Z move stopped at ", 24), "%s", got);
    }
    CHECK(m.comps == 1 && m.axis.position >= 1000 && m.axis.position < 40000);
    host(&m, "G91\nG1 Z1\n");
    settle(&m);
    EXPECT(&m, "ok\nok\nZ_move_comp\n");
    CHECK(m.axis.position == m.phys);
}

/* Callbacks may be left out; the state is the caller's, so two instances
   do not meet. */
static void io_without_callbacks(void)
{
    static machine m;
    fw_axis_config c = test_config();
    fw_gcode bare;
    fw_gcode_io none;
    const char *in = "M105\nM106\nM17\nG28\nM999 \xff\n";
    machine_init(&m, &c, 10);
    none.ctx = NULL;
    none.write = NULL;
    none.uv = NULL;
    none.uv_end = NULL;
    none.motor = NULL;
    none.moving = NULL;
    fw_gcode_init(&bare, &m.axis, &none);
    while (*in) {
        in += fw_gcode_receive(&bare, (const uint8_t *)in, strlen(in));
        while (fw_gcode_run(&bare, m.now) == m.now && !fw_axis_busy(&m.axis)) {}
    }
    CHECK(fw_axis_busy(&m.axis));
    while (fw_axis_busy(&m.axis)) {
        uint64_t t = fw_axis_next(&m.axis);
        if (t > m.now) m.now = t;
        m.phys += fw_axis_step(&m.axis, m.phys <= 0);
        fw_gcode_run(&bare, m.now);
    }
    /* homing's end, then the last line's check and run */
    CHECK(fw_gcode_run(&bare, m.now) == m.now && fw_gcode_run(&bare, m.now) == m.now);
    CHECK(fw_gcode_run(&bare, m.now) == FW_NEVER && m.axis.homed);
    /* m's own instance saw none of it */
    CHECK(m.out_len == 0 && m.uv_calls == 0 && m.motor == 0);
    host(&m, "G1 Z1\n");
    settle(&m);
    EXPECT(&m, "ok\nZ_move_comp\n");
}

void test_gcode(void)
{
    RUN(every_command_replies);
    RUN(moves_reach_exact_steps);
    RUN(relative_moves_do_not_drift);
    RUN(feed_rates);
    RUN(soft_limits);
    RUN(homing_failure);
    RUN(line_numbers_and_checksums);
    RUN(held_line_while_moving);
    RUN(lines_wait_for_the_cores_moves);
    RUN(unpaced_commands_queue_in_order);
    RUN(long_lines);
    RUN(binary_noise);
    RUN(dwell);
    RUN(lit_dwell_is_the_exposure);
    RUN(no_move_under_the_light);
    RUN(silent_host_puts_the_light_out);
    RUN(halted_move);
    RUN(io_without_callbacks);
}
