/* make bench: the integer planner's time and RAM on a Cortex-M3, N = 12,000.

       bench_mcu_plan IMAGE.elf [arm-none-eabi-size [arm-none-eabi-nm]]

   IMAGE is bench/mcu_plan_mps2.c built for QEMU's mps2-an385. This
   program plans bench/mcu_profile.h's profile with the host build of
   adaslice_dp, runs the image under QEMU with -icount shift=0 (every
   instruction is 1 ns of virtual time; SysTick counts the 25 MHz core clock,
   so a tick is 40 instructions: the image checks that with loops of known
   length and this program fails unless it holds), and checks that the MCU's
   plan is the host's: the same K and the same hash of the layer lengths, or
   it fails loudly. RAM comes from arm-none-eabi-size and -nm on the image. */
#include "../adaslice.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../link/messages.h"
#include "mcu_profile.h"
#include "timing.h"
#include <string.h>
#include <sys/wait.h>

/* Assumed for the STM32F103 estimate, not measured: a Cortex-M3 at 72 MHz
   runs most instructions in 1 cycle, loads, multiplies and taken branches in
   2-3, plus flash wait states (2 at 72 MHz) the prefetch buffer mostly
   hides; 1.2 cycles per instruction as the central guess, 1.0-1.5 as a range. */
#define STM32_HZ 72e6
#define CPI_LOW 1.0
#define CPI_MID 1.2
#define CPI_HIGH 1.5

static void fail(const char *what)
{
    printf("bench_mcu_plan: FAILED: %s\n", what);
    exit(1);
}

/* The value of " name=" in the image's line. */
static unsigned long long field(const char *text, const char *name)
{
    char key[64];
    const char *p;
    snprintf(key, sizeof key, " %s=", name);
    if (!(p = strstr(text, key))) {
        printf("bench_mcu_plan: the image's line lacks %s\n", name);
        fail("unexpected output from the image");
    }
    return strtoull(p + strlen(key), NULL, 0);
}

/* Runs a command and returns its output (at most size - 1 bytes) and exit status. */
static int run(const char *cmd, char *out, size_t size)
{
    FILE *f = popen(cmd, "r");
    size_t n = 0, got;
    int status;
    if (!f) return -1;
    while (n + 1 < size && (got = fread(out + n, 1, size - 1 - n, f)) > 0) n += got;
    out[n] = 0;
    status = pclose(f);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

typedef struct plan_check { uint32_t layers, hash, units_hash, min_len, max_len, top, forced; double mean_units; } plan_check;

/* The host's plan of the same profile, with the host build of adaslice_dp. */
static plan_check host_plan(double *ns_per_bin)
{
    plan_check c;
    mcu_gen g;
    uint32_t *v = (uint32_t *)malloc(MCU_BINS * sizeof *v), i, k, plane;
    size_t need = adaslice_dp_workspace(MCU_BINS, MCU_BINS_MAX, 0);
    uint64_t *ws = (uint64_t *)malloc(need + 8);
    adaslice_dp dp;
    double t[31];
    int r, forced;
    if (!v || !ws) fail("out of memory");
    mcu_gen_init(&g, MCU_BINS, MCU_SEED);
    c.units_hash = MCU_HASH_START;
    c.forced = 0;
    c.mean_units = 0;
    for (i = 0; i < MCU_BINS; i++) {
        uint32_t u = mcu_gen_next(&g, &forced);
        v[i] = link_bin_code(u, forced);
        c.units_hash = mcu_hash(c.units_hash, v[i]);
        c.forced += (uint32_t)forced;
        c.mean_units += u / (double)MCU_BINS;
    }
    for (r = 0; r < 31; r++) {
        double t0 = now();
        if (adaslice_dp_init(&dp, ws, need, MCU_BINS, MCU_BINS_MIN, MCU_BINS_MAX, MCU_EPS_UNITS, 0, 0) != ADASLICE_OK)
            fail("adaslice_dp_init");
        for (i = 0; i < MCU_BINS; i++) adaslice_dp_push(&dp, link_bin_units(v[i]), link_bin_forced(v[i]) && i + 1 < MCU_BINS);
        c.layers = adaslice_dp_reverse(&dp);
        t[r] = now() - t0;
    }
    *ns_per_bin = median(t, 31) * 1e9 / MCU_BINS;
    if (c.layers == ADASLICE_UNREACHED) fail("the generated profile has no plan on the host");
    c.hash = MCU_HASH_START;
    c.min_len = UINT32_MAX;
    c.max_len = 0;
    for (plane = 0, k = 0; k < c.layers; k++) {
        uint32_t len = adaslice_dp_layer_above(&dp, plane);
        c.hash = mcu_hash(c.hash, len);
        if (len < c.min_len) c.min_len = len;
        if (len > c.max_len) c.max_len = len;
        plane += len;
    }
    c.top = plane;
    free(ws);
    free(v);
    return c;
}

/* Size of a section from `size -A`, or of a symbol from `nm -S` (0 if absent). */
static unsigned long section_size(const char *listing, const char *name)
{
    const char *p = listing;
    size_t n = strlen(name);
    while ((p = strstr(p, name)) != NULL) {
        if ((p == listing || p[-1] == '\n') && (p[n] == ' ' || p[n] == '\t')) return strtoul(p + n, NULL, 10);
        p += n;
    }
    return 0;
}

static unsigned long symbol_size(const char *listing, const char *name)
{
    const char *line = listing;
    while (line && *line) {
        unsigned long addr, size;
        char type, sym[128];
        if (sscanf(line, "%lx %lx %c %127s", &addr, &size, &type, sym) == 4 && !strcmp(sym, name)) return size;
        line = strchr(line, '\n');
        if (line) line++;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *elf = argc > 1 ? argv[1] : "build/bench-plan-mps2.elf";
    const char *size_tool = argc > 2 ? argv[2] : "arm-none-eabi-size";
    const char *nm_tool = argc > 3 ? argv[3] : "arm-none-eabi-nm";
    static char out[8192], sizes[4096], syms[16384];
    char cmd[2048];
    plan_check host, mcu;
    double host_ns, wall, ipt2, ipt3, pair, gen, init, push, harness, reverse, read, planner;
    int rc;

    host = host_plan(&host_ns);

    /* -icount shift=0: 2^0 ns of virtual time per instruction; align and
       sleep off so that nothing but instructions moves the clock */
    snprintf(cmd, sizeof cmd,
             "timeout 30 qemu-system-arm -M mps2-an385 -nographic -monitor none -serial stdio "
             "-semihosting-config enable=on,target=native -icount shift=0,align=off,sleep=off -kernel '%s' < /dev/null 2>&1",
             elf);
    wall = now();
    rc = run(cmd, out, sizeof out);
    wall = now() - wall;
    if (rc == 124) fail("QEMU timed out (30 s)");
    if (rc != 0 || !strstr(out, "MCUBENCH") || !strstr(out, " END")) {
        printf("bench_mcu_plan: QEMU exit status %d, output:\n%s\n", rc, out);
        fail(strstr(out, "MCUBENCH infeasible") ? "the MCU found no plan" : "the image did not run to its end");
    }

    /* calibration: instructions per SysTick tick, from the difference of
       two runs of a 2-instruction loop, and from a 3-instruction loop with a
       load; both must be 1e9 / 25e6 = 40 */
    ipt2 = 2.0 * (double)(field(out, "cal2_big_iters") - field(out, "cal2_small_iters")) /
           (double)(field(out, "cal2_big_ticks") - field(out, "cal2_small_ticks"));
    ipt3 = 3.0 * (double)field(out, "cal3_iters") / (double)field(out, "cal3_ticks");
    if (ipt2 < 39.96 || ipt2 > 40.04 || ipt3 < 39.96 || ipt3 > 40.04) {
        printf("bench_mcu_plan: %.4f and %.4f instructions per tick; 40 expected\n", ipt2, ipt3);
        fail("the instruction count calibration does not hold (is -icount shift=0 on?)");
    }
    pair = 40.0 * (double)field(out, "tickread_ticks") / (double)field(out, "tickread_pairs");
    gen = 40.0 * (double)field(out, "gen_ticks");
    init = 40.0 * (double)field(out, "init_ticks");
    /* each chunk's measurement includes one tick read's worth of instructions */
    push = 40.0 * (double)field(out, "push_ticks") - pair * (double)field(out, "chunks");
    harness = 40.0 * (double)field(out, "harness_ticks") - pair * (double)field(out, "chunks");
    reverse = 40.0 * (double)field(out, "reverse_ticks");
    read = 40.0 * (double)field(out, "read_ticks");
    planner = init + push + reverse;

    mcu.layers = (uint32_t)field(out, "layers");
    mcu.hash = (uint32_t)field(out, "plan_hash");
    mcu.units_hash = (uint32_t)field(out, "units_hash");
    mcu.min_len = (uint32_t)field(out, "min_len");
    mcu.max_len = (uint32_t)field(out, "max_len");
    mcu.top = (uint32_t)field(out, "top_plane");

    snprintf(cmd, sizeof cmd, "'%s' -A '%s'", size_tool, elf);
    if (run(cmd, sizes, sizeof sizes) != 0) fail("arm-none-eabi-size");
    snprintf(cmd, sizeof cmd, "'%s' -S '%s'", nm_tool, elf);
    if (run(cmd, syms, sizeof syms) != 0) fail("arm-none-eabi-nm");

    printf("mcu-plan  integer planner on QEMU mps2-an385 (Cortex-M3, -Os as the firmware), N = %u bins, "
           "layers %u..%u bins, eps %u units; QEMU %.2f s wall\n", MCU_BINS, MCU_BINS_MIN, MCU_BINS_MAX, MCU_EPS_UNITS, wall);
    printf("mcu-plan  profile (bench/mcu_profile.h, generated on both sides): mean %.0f units per bin = eps/%.1f, "
           "%u forced planes; plan: K = %u, mean layer %.1f bins\n", host.mean_units, MCU_EPS_UNITS / host.mean_units,
           host.forced, host.layers, (double)MCU_BINS / host.layers);
    printf("mcu-plan  calibration: %.4f (2-instruction loop) and %.4f (3, with a load) instructions per SysTick tick "
           "(expected 40: 1 ns per instruction, 25 MHz tick); a tick read costs %.0f instructions\n", ipt2, ipt3, pair);
    printf("mcu-plan  %-34s %12s %10s %12s %12s\n", "part", "instructions", "per bin", "72 MHz, 1.2", "(1.0-1.5)");
    {
        struct { const char *name; double instr; } rows[] = {
            {"adaslice_dp_init", init},
            {"adaslice_dp_push x N (loop incl.)", push},
            {"  of which the calling loop", harness},
            {"adaslice_dp_reverse", reverse},
            {"planner: init + push + reverse", planner},
            {"reading the plan bottom-up (K)", read},
            {"profile generator (not planner)", gen},
        };
        size_t r;
        for (r = 0; r < sizeof rows / sizeof rows[0]; r++)
            printf("mcu-plan  %-34s %12.0f %10.1f %9.2f ms %5.1f-%.1f ms\n", rows[r].name, rows[r].instr,
                   rows[r].instr / MCU_BINS, rows[r].instr * CPI_MID / STM32_HZ * 1e3, rows[r].instr * CPI_LOW / STM32_HZ * 1e3,
                   rows[r].instr * CPI_HIGH / STM32_HZ * 1e3);
    }
    printf("mcu-plan  (STM32F103 times are estimates: instructions x an assumed 1.2 cycles per instruction, range "
           "1.0-1.5, at 72 MHz; not measured on the part)\n");
    printf("mcu-plan  host build of the same planner: %.1f ns per bin (median of 31, this machine)\n", host_ns);
    printf("mcu-plan  RAM: workspace FW_PLAN_WORKSPACE(%u) = %lu bytes (adaslice_dp_workspace: %zu) + adaslice_dp %lu bytes; "
           "image .data %lu + .bss %lu = %lu bytes, + stack %lu (used %llu) = %lu of 20480; "
           ".bss: workspace %lu, bench chunk %lu, output line %lu, UART ring %lu; .text %lu bytes\n",
           MCU_BINS, (unsigned long)field(out, "workspace"), adaslice_dp_workspace(MCU_BINS, MCU_BINS_MAX, 0),
           symbol_size(syms, "dp"), section_size(sizes, ".data"), section_size(sizes, ".bss"),
           section_size(sizes, ".data") + section_size(sizes, ".bss"), section_size(sizes, ".stack"),
           field(out, "stack_used"), section_size(sizes, ".data") + section_size(sizes, ".bss") + section_size(sizes, ".stack"),
           symbol_size(syms, "workspace"), symbol_size(syms, "chunk"), symbol_size(syms, "line"),
           symbol_size(syms, "rx_buf"), section_size(sizes, ".text"));
    printf("mcu-plan  plan: MCU K = %u, layer hash 0x%08x, lengths %u..%u, top plane %u, profile hash 0x%08x\n",
           mcu.layers, mcu.hash, mcu.min_len, mcu.max_len, mcu.top, mcu.units_hash);
    printf("mcu-plan  plan: host K = %u, layer hash 0x%08x, lengths %u..%u, top plane %u, profile hash 0x%08x\n",
           host.layers, host.hash, host.min_len, host.max_len, host.top, host.units_hash);
    if (mcu.units_hash != host.units_hash) fail("the MCU generated another profile than the host");
    if (mcu.layers != host.layers || mcu.hash != host.hash || mcu.min_len != host.min_len || mcu.max_len != host.max_len ||
        mcu.top != host.top || host.top != MCU_BINS)
        fail("MISMATCH: the MCU's plan differs from the host's");
    printf("mcu-plan  the MCU's plan equals the host's\n");
    return 0;
}
