/* make bench: the RAMPS image's arithmetic on the ATmega2560, cycle-exact
   under simavr (bench/bench_avr.c runs it through build/avr-run). Not
   firmware: an image with its own main, linked with the core's motion.c and
   the trimmed planner (firmware/adaslice_fw.c), built as the firmware is.

   It times with Timer1 at clk/1 (datasheet 17.11, TCCR1B CS10; overflows
   counted by TIMER1_OVF) and prints one line on UART0 (polled: 22.10 UCSR0A
   UDRE0), then sleeps with interrupts off, which ends the run:
     - fw_axis_step, one step's computation: the worst and mean cycles over
       a 10 mm move at 10 mm/s and at the board's top speed, with the
       board's acceleration (the accelerating and decelerating ramps and the
       cruise apart), the worst of a halt (brake), and of homing's approach;
     - adaslice_crc32 over a 2560-pixel 1-bit row (320 bytes);
     - the planner: adaslice_dp_init / push / reverse over
       bench/mcu_profile.h's profile cut to AVR_BENCH_BINS bins (the board's
       BOARD_MAX_BINS), cycles per bin, and the plan's hash for the host to
       check against its own. */
#include "../firmware/fw.h"
#include "../firmware/ports/ramps/board.h"
#include "mcu_profile.h"
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>

#ifndef AVR_BENCH_BINS
#define AVR_BENCH_BINS BOARD_MAX_BINS
#endif

static volatile uint16_t overflows;
ISR(TIMER1_OVF_vect) { overflows++; }

static uint32_t cycles(void)
{
    uint8_t sreg = SREG;
    uint16_t t, o;
    cli();
    t = TCNT1;
    o = overflows;
    if ((TIFR1 & _BV(TOV1)) && t < 0x8000u) o++;
    SREG = sreg;
    return ((uint32_t)o << 16) | t;
}

static void put_c(char c)
{
    while (!(UCSR0A & _BV(UDRE0))) {}
    UDR0 = (uint8_t)c;
}
static void put_s(const char *s) { while (*s) put_c(*s++); }
static void put_u(uint32_t v)
{
    char d[12];
    int n = 0;
    do { d[n++] = (char)('0' + (int)(v % 10u)); v /= 10u; } while (v);
    while (n) put_c(d[--n]);
}
static void field(const char *name, uint32_t v)
{
    put_c(' ');
    put_s(name);
    put_c('=');
    put_u(v);
}

static void board_axis(fw_axis *axis, uint32_t max_speed)
{
    fw_axis_config c;
    c.steps_per_mm = BOARD_STEPS_PER_MM;
    c.max_speed = max_speed;
    c.accel = BOARD_ACCEL_STEPS_S2;
    c.home_speed = BOARD_HOME_STEPS_S;
    c.max_steps = (int32_t)BOARD_Z_MAX_STEPS;
    c.home_travel = (int32_t)BOARD_HOME_TRAVEL_STEPS;
    fw_axis_init(axis, &c, BOARD_CLOCK_HZ);
}

typedef struct stat { uint32_t worst, sum, n; } stat;
static void add(stat *s, uint32_t c)
{
    if (c > s->worst) s->worst = c;
    s->sum += c;
    s->n++;
}

static fw_axis axis;
static uint32_t overhead, ticks_hash = MCU_HASH_START;

/* A 10 mm move up from rest at `max_speed` steps/s: each step's cycles into
   `ramp` (accelerating or braking) or `cruise`. */
static void move(uint32_t max_speed, stat *ramp, stat *cruise)
{
    board_axis(&axis, max_speed);
    axis.homed = 1;
    (void)fw_axis_move_to(&axis, (int32_t)(10u * BOARD_STEPS_PER_MM), 0, 0);
    while (fw_axis_busy(&axis)) {
        uint32_t c, t0, done = axis.done;
        int in_ramp = done <= axis.ramp || axis.steps - 1u - done <= axis.ramp;
        t0 = cycles();
        (void)fw_axis_step(&axis, 0);
        c = cycles() - t0 - overhead;
        ticks_hash = mcu_hash(ticks_hash, (uint32_t)axis.last);
        add(in_ramp ? ramp : cruise, c);
    }
}
static uint64_t workspace[(FW_PLAN_WORKSPACE(AVR_BENCH_BINS) + 7u) / 8u];
static adaslice_dp dp;
/* a row of the 2560-pixel display the shipped image drives: its CRC is
   what a pass of mask decoding cannot split */
static uint8_t row[2560u / 8u];

int main(void)
{
    stat ramp10 = {0, 0, 0}, cruise10 = {0, 0, 0}, ramp = {0, 0, 0}, cruise = {0, 0, 0}, halt = {0, 0, 0}, home = {0, 0, 0};
    uint32_t t0, hash = 0, i, init, push = 0, reverse, layers, plane, k, row_crc, row_crc32;
    mcu_gen g;
    int forced;
    UBRR0 = (uint16_t)(BOARD_CPU_HZ / 8u / BOARD_BAUD - 1u);
    UCSR0A = _BV(U2X0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(TXEN0);
    TCCR1A = 0;
    TCCR1B = _BV(CS10);
    TIMSK1 = _BV(TOIE1);
    sei();
    t0 = cycles();
    overhead = cycles() - t0;

    /* a 10 mm move up at 10 mm/s (the speed first configured), then the
       move, halts and homing at the board's top speed */
    move(10u * BOARD_STEPS_PER_MM, &ramp10, &cruise10);
    move(BOARD_MAX_STEPS_S, &ramp, &cruise);
    /* halts: one every 397 steps of the same move down */
    for (i = 1; i < 10u * BOARD_STEPS_PER_MM; i += 397u) {
        uint32_t s;
        board_axis(&axis, BOARD_MAX_STEPS_S);
        axis.homed = 1;
        axis.position = (int32_t)(10u * BOARD_STEPS_PER_MM);
        (void)fw_axis_move_to(&axis, 0, 0, 0);
        for (s = 0; s < i && fw_axis_busy(&axis); s++) (void)fw_axis_step(&axis, 0);
        t0 = cycles();
        fw_axis_halt(&axis, 0);
        if (fw_axis_busy(&axis)) (void)fw_axis_step(&axis, 0);
        add(&halt, cycles() - t0 - overhead);
    }
    /* homing from 5 mm up: the switch closes at 0 */
    board_axis(&axis, BOARD_MAX_STEPS_S);
    (void)fw_axis_home(&axis, 0);
    {
        int32_t z = (int32_t)(5u * BOARD_STEPS_PER_MM);
        while (fw_axis_busy(&axis)) {
            int dir;
            uint32_t c;
            t0 = cycles();
            dir = fw_axis_step(&axis, z <= 0);
            c = cycles() - t0 - overhead;
            add(&home, c);
            z += dir;
        }
    }

    /* a mask row's CRC */
    for (i = 0; i < sizeof row; i++) row[i] = (uint8_t)(i * 37u);
    t0 = cycles();
    row_crc32 = adaslice_crc32(0, row, sizeof row);
    row_crc = cycles() - t0 - overhead;

    /* the planner */
    t0 = cycles();
    if (adaslice_dp_init(&dp, workspace, FW_PLAN_WORKSPACE(AVR_BENCH_BINS), AVR_BENCH_BINS, MCU_BINS_MIN, MCU_BINS_MAX,
                         MCU_EPS_UNITS, 0, 0) != ADASLICE_OK) {
        put_s("AVRBENCH init-failed END\n");
        for (;;) { cli(); sleep_cpu(); }
    }
    init = cycles() - t0;
    mcu_gen_init(&g, AVR_BENCH_BINS, MCU_SEED);
    for (i = 0; i < AVR_BENCH_BINS; i++) {
        uint32_t u = mcu_gen_next(&g, &forced);
        t0 = cycles();
        adaslice_dp_push(&dp, u, forced && i + 1u < AVR_BENCH_BINS);
        push += cycles() - t0 - overhead;
    }
    t0 = cycles();
    layers = adaslice_dp_reverse(&dp);
    reverse = cycles() - t0;
    hash = MCU_HASH_START;
    if (layers != ADASLICE_UNREACHED)
        for (plane = 0, k = 0; k < layers; k++) {
            uint32_t len = adaslice_dp_layer_above(&dp, plane);
            hash = mcu_hash(hash, len);
            plane += len;
        }

    put_s("AVRBENCH");
    field("cpu_hz", BOARD_CPU_HZ);
    field("max_speed", BOARD_MAX_STEPS_S);
    field("accel", BOARD_ACCEL_STEPS_S2);
    field("ramp10_steps", ramp10.n);
    field("ramp10_worst", ramp10.worst);
    field("ramp10_mean", ramp10.n ? ramp10.sum / ramp10.n : 0);
    field("cruise10_worst", cruise10.worst);
    field("cruise10_mean", cruise10.n ? cruise10.sum / cruise10.n : 0);
    field("ramp_steps", ramp.n);
    field("ramp_worst", ramp.worst);
    field("ramp_mean", ramp.n ? ramp.sum / ramp.n : 0);
    field("cruise_steps", cruise.n);
    field("cruise_worst", cruise.worst);
    field("cruise_mean", cruise.n ? cruise.sum / cruise.n : 0);
    field("halt_worst", halt.worst);
    field("home_steps", home.n);
    field("home_worst", home.worst);
    field("row_crc", row_crc);
    field("row_crc32", row_crc32);
    field("ticks_hash", ticks_hash);
    field("bins", AVR_BENCH_BINS);
    field("workspace", (uint32_t)FW_PLAN_WORKSPACE(AVR_BENCH_BINS));
    field("init", init);
    field("push", push);
    field("reverse", reverse);
    field("layers", layers);
    field("plan_hash", hash);
    put_s(" END\n");
    while (!(UCSR0A & _BV(TXC0))) {}
    for (;;) {
        cli();
        sleep_enable();
        sleep_cpu();
    }
}
