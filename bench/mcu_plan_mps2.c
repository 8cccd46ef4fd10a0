/* make bench: the integer planner on QEMU's mps2-an385 (Cortex-M3), N = 12,000.
   Not firmware: a bench image with its own main, linked with the mps2 board
   code (vectors, UART0, semihosting exit), the cm3 reset and tick, and the
   trimmed adaslice.h (firmware/adaslice_fw.c), in the 20 KiB of mps2.ld.

   It generates bench/mcu_profile.h's profile bin by bin, streams it through
   adaslice_dp_init / push / reverse in a workspace of FW_PLAN_WORKSPACE(12000)
   bytes, and prints one line on UART0 with the SysTick counts of each part, a
   calibration and the plan's checksum; bench/bench_mcu_plan.c runs it under

       qemu-system-arm -M mps2-an385 -icount shift=0,align=off,sleep=off ...

   where every instruction takes 1 ns of virtual time and SysTick counts the
   25 MHz core clock: one tick is 40 instructions. The image measures that
   itself with loops of known instruction counts. Exit status 0, or 1 if the
   profile has no plan. */
#include "../firmware/fw.h"
#include "../firmware/ports/cm3/cm3.h"
#include "board.h"
#include "mcu_profile.h"

#define CHUNK 200u /* bins generated ahead of each timed run of pushes */

extern uint32_t __stack_bottom[], __stack_top[];

static uint64_t workspace[(FW_PLAN_WORKSPACE(MCU_BINS) + 7u) / 8u];
static uint32_t chunk[CHUNK];
static adaslice_dp dp;

/* The board's alarms stay unarmed here: the planner alone is timed. */
void cm3_alarm_due(int which, uint64_t late) { (void)which; (void)late; }

/* ---- output without a C library ---------------------------------------- */
static char line[640];
static size_t used;

static void put_str(const char *s)
{
    while (*s && used < sizeof line - 1) line[used++] = *s++;
}

static void put_u64(uint64_t v)
{
    char d[24];
    int n = 0;
    do { d[n++] = (char)('0' + (int)(v % 10u)); v /= 10u; } while (v);
    while (n && used < sizeof line - 1) line[used++] = d[--n];
}

static void put_hex(uint32_t v)
{
    int k;
    put_str("0x");
    for (k = 28; k >= 0; k -= 4)
        if (used < sizeof line - 1) line[used++] = "0123456789abcdef"[(v >> k) & 15u];
}

static void field(const char *name, uint64_t v)
{
    put_str(" ");
    put_str(name);
    put_str("=");
    put_u64(v);
}

/* ---- calibration loops: exactly 2 and 3 instructions per iteration ------ */
static void __attribute__((noinline)) spin2(uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

static void __attribute__((noinline)) spin3(uint32_t n)
{
    uint32_t scratch;
    /* a load from the stack each time: QEMU counts instructions, not cycles */
    __asm__ volatile("1: ldr %1, [sp]\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n), "=&r"(scratch) : : "cc", "memory");
}

/* The push loop's own cost: the same loop calling a function that does nothing. */
static void __attribute__((noinline)) no_push(adaslice_dp *d, uint64_t units, int forced)
{
    __asm__ volatile("" : : "r"(d), "r"((uint32_t)units), "r"(forced) : "memory");
}

static uint64_t timed_spin(void (*spin)(uint32_t), uint32_t n)
{
    uint64_t t0 = cm3_ticks();
    spin(n);
    return cm3_ticks() - t0;
}

/* ---- the stack's high-water mark ---------------------------------------- */
#define PAINT 0x5A5A5A5Au

static void paint_stack(void)
{
    uint32_t *p = __stack_bottom + 1, *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    while (p < sp - 16) *p++ = PAINT;
}

static uint32_t stack_used(void)
{
    uint32_t *p = __stack_bottom + 1;
    while (p < __stack_top && *p == PAINT) p++;
    return (uint32_t)((uintptr_t)__stack_top - (uintptr_t)p);
}

int main(void)
{
    mcu_gen g;
    uint64_t t0, c2a, c2b, c3, pair = 0, gen, init, push = 0, harness = 0, reverse, read;
    uint32_t i, k, units_hash = MCU_HASH_START, plan_hash = MCU_HASH_START, chunks = 0;
    uint32_t layers, plane, min_len = 0xffffffffu, max_len = 0;
    int forced;

    paint_stack();
    board_init();
    /* SysTick's counter reads 0 until its first reload, one tick after
       cm3_tick_start: until then cm3_ticks() reads 2^24 - 1, then drops to 0 */
    while (cm3_ticks() >= 0x800000u) {}

    /* calibration: instructions per tick, from two lengths of the same loop
       (the difference cancels the call and the tick reads) and a third with
       a load in it */
    c2a = timed_spin(spin2, 500000u);
    c2b = timed_spin(spin2, 1500000u);
    c3 = timed_spin(spin3, 1000000u);
    /* what one measurement costs: 1024 back-to-back reads of the tick */
    for (i = 0; i < 1024u; i++) {
        uint64_t a = cm3_ticks();
        pair += cm3_ticks() - a;
    }

    /* the generator alone (its cost is not the planner's) */
    mcu_gen_init(&g, MCU_BINS, MCU_SEED);
    t0 = cm3_ticks();
    for (i = 0; i < MCU_BINS; i++) {
        uint32_t u = mcu_gen_next(&g, &forced);
        units_hash = mcu_hash(units_hash, link_bin_code(u, forced));
    }
    gen = cm3_ticks() - t0;

    /* the planner: init, then the bins CHUNK at a time (generated untimed),
       each pushed as the firmware does with a PROFILE_DATA varint */
    t0 = cm3_ticks();
    if (adaslice_dp_init(&dp, workspace, FW_PLAN_WORKSPACE(MCU_BINS), MCU_BINS, MCU_BINS_MIN, MCU_BINS_MAX,
                         MCU_EPS_UNITS, 0, 0) != ADASLICE_OK)
        return 2;
    init = cm3_ticks() - t0;
    mcu_gen_init(&g, MCU_BINS, MCU_SEED);
    for (i = 0; i < MCU_BINS; i += k) {
        uint32_t m = MCU_BINS - i < CHUNK ? MCU_BINS - i : CHUNK, j;
        for (k = 0; k < m; k++) {
            uint32_t u = mcu_gen_next(&g, &forced);
            chunk[k] = link_bin_code(u, forced);
        }
        t0 = cm3_ticks();
        for (j = 0; j < m; j++) {
            uint32_t v = chunk[j];
            adaslice_dp_push(&dp, link_bin_units(v), link_bin_forced(v) && i + j + 1 < MCU_BINS);
        }
        push += cm3_ticks() - t0;
        t0 = cm3_ticks();
        for (j = 0; j < m; j++) {
            uint32_t v = chunk[j];
            no_push(&dp, v >> 1, (int)(v & 1u) && i + j + 1 < MCU_BINS);
        }
        harness += cm3_ticks() - t0;
        chunks++;
    }
    t0 = cm3_ticks();
    layers = adaslice_dp_reverse(&dp);
    reverse = cm3_ticks() - t0;
    if (layers == ADASLICE_UNREACHED) {
        put_str("MCUBENCH infeasible END\n");
        board_write((const uint8_t *)line, used);
        return 1;
    }

    /* the plan bottom-up, as the firmware reads it while printing */
    t0 = cm3_ticks();
    for (plane = 0, k = 0; k < layers; k++) {
        uint32_t len = adaslice_dp_layer_above(&dp, plane);
        plan_hash = mcu_hash(plan_hash, len);
        if (len < min_len) min_len = len;
        if (len > max_len) max_len = len;
        plane += len;
    }
    read = cm3_ticks() - t0;

    put_str("MCUBENCH");
    field("tick_hz", BOARD_CLOCK_HZ);
    field("cal2_small_iters", 500000u);
    field("cal2_small_ticks", c2a);
    field("cal2_big_iters", 1500000u);
    field("cal2_big_ticks", c2b);
    field("cal3_iters", 1000000u);
    field("cal3_ticks", c3);
    field("tickread_pairs", 1024u);
    field("tickread_ticks", pair);
    field("bins", MCU_BINS);
    field("gen_ticks", gen);
    field("init_ticks", init);
    field("push_ticks", push);
    field("harness_ticks", harness);
    field("chunks", chunks);
    field("reverse_ticks", reverse);
    field("read_ticks", read);
    field("workspace", FW_PLAN_WORKSPACE(MCU_BINS));
    field("stack_used", stack_used());
    field("layers", layers);
    field("top_plane", plane);
    field("min_len", min_len);
    field("max_len", max_len);
    put_str(" plan_hash=");
    put_hex(plan_hash);
    put_str(" units_hash=");
    put_hex(units_hash);
    put_str(" END\n");
    board_write((const uint8_t *)line, used);
    return 0;
}
