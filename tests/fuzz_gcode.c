/* libFuzzer target for G-code mode: the input is the host's byte stream,
   fed in pieces of pseudo-random size (drawn from a hash of the input, so
   the input itself stays plain G-code text); between pieces the fake machine
   takes a pseudo-random number of steps or runs to completion, and time
   jumps to each deadline. Aborts on a reply that is not printable ASCII
   lines, a Z_move_comp or UV switch while Z moves, a position beyond the
   soft limits, or a module that stops taking bytes while idle.
   clang -std=c99 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
       tests/fuzz_gcode.c firmware/gcode.c firmware/motion.c -o fuzz_gcode
   mkdir -p /tmp/gcode_corpus && ./fuzz_gcode -max_total_time=60 /tmp/gcode_corpus */
#include "../firmware/gcode.h"
#include <stdlib.h>
#include <string.h>

typedef struct fake {
    fw_axis axis;
    fw_gcode g;
    uint64_t now;
    int32_t phys;
    int endstop_broken;
    long steps;         /* steps this input so far */
    int halted;         /* the move under way was halted */
    int lit;            /* M106 put the light on; no end given yet */
    uint64_t lit_at;
} fake;

static void on_write(void *ctx, const uint8_t *data, size_t size)
{
    fake *f = (fake *)ctx;
    size_t i;
    if (!size || size > FW_GCODE_LINE_MAX + 32 || data[size - 1] != '\n') abort();
    for (i = 0; i + 1 < size; i++)
        if (data[i] < 0x20 || data[i] > 0x7e) abort();
    if (size == 12 && !memcmp(data, "Z_move_comp\n", 12) && fw_axis_busy(&f->axis)) abort();
}

static void on_uv(void *ctx, int on, uint64_t when)
{
    fake *f = (fake *)ctx;
    if ((on != 0 && on != 1) || when != f->now || fw_axis_busy(&f->axis)) abort();
    f->lit = on;
    f->lit_at = when;
}

/* the light's end: never before M106 put it on (the fake keeps that tick) */
static void on_uv_end(void *ctx, uint64_t when)
{
    fake *f = (fake *)ctx;
    if (!f->lit || when <= f->lit_at || fw_axis_busy(&f->axis)) abort();
    f->lit = 0;
}

static void on_motor(void *ctx, int on)
{
    if (on != 0 && on != 1) abort();
    (void)ctx;
}

static uint32_t next_random(uint32_t *s)
{
    *s = *s * 1103515245u + 12345u;
    return *s >> 8;
}

/* Up to `budget` steps, each at its tick, the module after each. Past
   STEP_LIMIT steps an input's moves are halted, which keeps a run short
   and puts halts under test too. */
#define STEP_LIMIT 30000
static void run(fake *f, long budget)
{
    while (budget-- > 0) {
        uint64_t d;
        if (fw_axis_busy(&f->axis)) {
            uint64_t t;
            if (++f->steps > STEP_LIMIT && !f->halted) {
                fw_axis_halt(&f->axis, f->now);
                f->halted = 1;
            }
            t = fw_axis_next(&f->axis);
            if (t > f->now) f->now = t;
            f->phys += fw_axis_step(&f->axis, !f->endstop_broken && f->phys <= 0);
            if (f->axis.homed && !fw_axis_busy(&f->axis) &&
                (f->axis.position < 0 || f->axis.position > f->axis.config.max_steps)) abort();
            if (!fw_axis_busy(&f->axis)) f->halted = 0;
            fw_gcode_run(&f->g, f->now);
            continue;
        }
        d = fw_gcode_run(&f->g, f->now);
        if (d == FW_NEVER) return;
        if (d < f->now) abort();
        f->now = d;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fake f;
    fw_axis_config c;
    fw_gcode_io io;
    uint32_t seed = 2166136261u;
    size_t i, at = 0;
    for (i = 0; i < size; i++) seed = (seed ^ data[i]) * 16777619u;
    memset(&f, 0, sizeof f);
    /* 400 and 333 steps/mm, and a coarse axis of 1 step/mm */
    c.steps_per_mm = seed % 3 == 0 ? 400 : seed % 3 == 1 ? 333 : 1;
    c.max_speed = 4000;
    c.accel = 40000;
    c.home_speed = 2000;
    /* 20 mm of travel: long enough for every path, short enough for
       thousands of inputs a second */
    c.max_steps = (int32_t)(20 * c.steps_per_mm);
    c.home_travel = (int32_t)(25 * c.steps_per_mm);
    fw_axis_init(&f.axis, &c, 1000000);
    io.ctx = &f;
    io.write = on_write;
    io.uv = on_uv;
    io.uv_end = on_uv_end;
    io.motor = on_motor;
    io.moving = NULL;
    fw_gcode_init(&f.g, &f.axis, &io);
    f.phys = (int32_t)(next_random(&seed) % (uint32_t)c.max_steps);
    f.endstop_broken = next_random(&seed) % 16 == 0;
    f.now = next_random(&seed);
    while (at < size) {
        size_t piece = 1 + next_random(&seed) % 64, used;
        if (piece > size - at) piece = size - at;
        used = fw_gcode_receive(&f.g, data + at, piece);
        if (used > piece) abort();
        at += used;
        if (used < piece || next_random(&seed) % 4 == 0) {
            run(&f, next_random(&seed) % 2 ? 1000000000L : (long)(next_random(&seed) % 200));
            /* idle with nothing due: the next byte must go in */
            if (used < piece && !fw_axis_busy(&f.axis) && fw_gcode_run(&f.g, f.now) == FW_NEVER) {
                if (fw_gcode_receive(&f.g, data + at, 1) != 1) abort();
                at++;
            }
        }
        f.now += next_random(&seed) % 1000;
    }
    run(&f, 2000000000L);
    return 0;
}
