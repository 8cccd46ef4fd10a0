/* The Cortex-M3 image's timing and watchdog under qemu-system-arm -icount:
   build/fw-mps2-trace.elf records every step's scheduled tick and the tick
   its alarm interrupt ran (cm3_ticks()), and every UV edge, and writes them
   at exit to fw-mps2-trace.bin in QEMU's directory (16-byte records, see
   firmware/ports/mps2/board.c), with a summary on QEMU's stderr;
   build/fw-mps2-hang.elf is the same image whose loop hangs in layer 2's
   exposure. */
#define _XOPEN_SOURCE 700
#include "cli_run.h"
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <time.h>

#define QEMU_TICK_HZ 25000000u /* the an385's clock: a tick is a cycle */
#define QEMU_STEPS_PER_MM 400u
#define QEMU_START_STEPS (30 * 400) /* MPS2_Z_START_MM */
#define QEMU_MAX_SPEED (10u * 400u) /* cm3_z_config: 10 mm/s */
#define QEMU_WATCHDOG_MS 250u
static const char *MODEL = "examples/models/hand_closed.obj";

typedef struct qemu_run { pid_t pid; char port[64]; } qemu_run;

/* QEMU on `elf` in cli_dir (semihosting files land there), stderr to
   qemu.err there; the pty's name from its first line. */
static int qemu_start(qemu_run *q, const char *elf)
{
    char elf_path[512], err_path[600], line[256];
    int fds[2];
    size_t len = 0;
    struct timespec t0, t;
    memset(q, 0, sizeof *q);
    if (!realpath(elf, elf_path) || pipe(fds) != 0) return 0;
    snprintf(err_path, sizeof err_path, "%s/qemu.err", cli_dir);
    fflush(NULL);
    q->pid = fork();
    if (q->pid == 0) {
        int in = open("/dev/null", O_RDONLY), err = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (in < 0 || err < 0 || chdir(cli_dir) != 0) _exit(126);
        dup2(in, 0);
        dup2(fds[1], 1);
        dup2(err, 2);
        close(fds[0]);
        execl("/usr/bin/timeout", "timeout", "300", "qemu-system-arm", "-M", "mps2-an385", "-nographic", "-monitor", "none",
              "-serial", "pty", "-semihosting-config", "enable=on,target=native", "-icount", "shift=5,align=off,sleep=off",
              "-kernel", elf_path, (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (;;) {
        struct pollfd p = {fds[0], POLLIN, 0};
        char ch;
        clock_gettime(CLOCK_MONOTONIC, &t);
        if (t.tv_sec - t0.tv_sec > 20) break;
        if (poll(&p, 1, 100) <= 0) continue;
        if (read(fds[0], &ch, 1) != 1) break;
        if (ch != '\n') { if (len + 1 < sizeof line) line[len++] = ch; continue; }
        line[len] = 0;
        len = 0;
        if (strstr(line, "char device redirected to /dev/")) {
            const char *at = strstr(line, "/dev/");
            size_t i;
            for (i = 0; at[i] && at[i] != ' ' && i + 1 < sizeof q->port; i++) q->port[i] = at[i];
            q->port[i] = 0;
            break;
        }
    }
    close(fds[0]);
    return q->port[0] != 0;
}

/* Its exit status within `seconds` (-1: killed, or it did not end). */
static int qemu_wait(qemu_run *q, int seconds)
{
    int st, i;
    for (i = 0; i < seconds * 50; i++) {
        if (waitpid(q->pid, &st, WNOHANG) == q->pid) { q->pid = 0; return WIFEXITED(st) ? WEXITSTATUS(st) : -1; }
        { struct timespec ts = {0, 20000000}; nanosleep(&ts, NULL); }
    }
    kill(q->pid, SIGTERM);
    waitpid(q->pid, &st, 0);
    q->pid = 0;
    return -1;
}

/* "PREFIX<number>" in QEMU's stderr: the number of the `nth` such line (0 the first), or -1. */
static long long qemu_said(const char *text, const char *prefix, int nth)
{
    const char *at = text;
    while (at && (at = strstr(at, prefix)) != NULL) {
        if (nth-- == 0) return strtoll(at + strlen(prefix), NULL, 10);
        at += strlen(prefix);
    }
    return -1;
}

/* Each layer's top (bins) and the bin size from the host's --report. */
static uint32_t read_tops(const char *path, uint32_t **tops, uint32_t *bin_nm)
{
    char *text = cli_read(path), *at;
    const char *f;
    uint32_t layers = 0, k = 0;
    *tops = NULL;
    if (!text) return 0;
    if ((f = strstr(text, "\"layers\": "))) layers = (uint32_t)strtoul(f + 10, NULL, 10);
    if ((f = strstr(text, "\"bin_nm\": "))) *bin_nm = (uint32_t)strtoul(f + 10, NULL, 10);
    *tops = (uint32_t *)calloc(layers + 1, sizeof **tops);
    for (at = strstr(text, "\"masks\""); *tops && at && k < layers && (at = strstr(at, "\"top_bins\": ")); k++)
        (*tops)[k] = (uint32_t)strtoul(at + 12, &at, 10);
    free(text);
    return k == layers ? layers : 0;
}

typedef struct trace_record { uint64_t tick; uint32_t late; int32_t kind; } trace_record;

/* A short print with masks streaming, on the trace image: every step was
   emitted at or after its tick and within QEMU's -icount error of it, no
   step interval is below the speed limit, each exposure comes with Z at its
   layer's top (so the steps are the plan's heights x steps/mm), the
   light is never on while Z moves, and no loop pass takes as long as a
   step interval at the top speed. */
static void steps_on_time_under_qemu(void)
{
    qemu_run q;
    cli_result r;
    uint32_t *tops = NULL, bin_nm = 0, layers, k = 0, min_interval = (QEMU_TICK_HZ + QEMU_MAX_SPEED - 1) / QEMU_MAX_SPEED;
    trace_record *rec;
    size_t n, i, steps = 0, lit_steps = 0, bad_height = 0, short_sched = 0, short_emitted = 0;
    uint64_t worst_late = 0, last_sched = 0, last_emitted = 0, shortest = UINT64_MAX;
    long long summary_steps, work, moving_work;
    long pos = QEMU_START_STEPS;
    int status, uv = 0;
    char *err, *bin;
    if (!qemu_start(&q, "build/fw-mps2-trace.elf")) {
        CHECK(!"qemu-system-arm did not start with build/fw-mps2-trace.elf (make build/fw-mps2-trace.elf)");
        if (q.pid > 0) qemu_wait(&q, 0);
        return;
    }
    r = cli_run("print", MODEL, "--scale", "5", "--port", q.port, "--exposure", "0.05", "--penetration", "0.1", "--bottom-layers", "1",
                "--bottom-exposure", "0.1", "--peel", "0.5", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.02",
                "--report", cli_path("report.json"), "--then-exit", NULL);
    CHECKF(r.status == 0, "print on QEMU exited %d: %s", r.status, r.err);
    cli_free(&r);
    status = qemu_wait(&q, 10);
    CHECKF(status == 0, "QEMU ended with %d (0: the firmware exited cleanly on EXIT)", status);
    err = cli_read(cli_path("qemu.err"));
    layers = read_tops(cli_path("report.json"), &tops, &bin_nm);
    CHECKF(layers > 1 && bin_nm, "the report has %u layers", layers);
    {
        FILE *f = fopen(cli_path("fw-mps2-trace.bin"), "rb");
        long size = 0;
        bin = NULL;
        if (f && fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 &&
            (bin = (char *)malloc((size_t)size)) != NULL && fread(bin, 1, (size_t)size, f) != (size_t)size) size = 0;
        if (f) fclose(f);
        n = (size_t)size / sizeof(trace_record);
        rec = (trace_record *)(void *)bin;
    }
    CHECKF(n > 0 && err, "no trace from the image (%s)", err ? err : "no stderr");
    for (i = 0; rec && i < n; i++) {
        const trace_record *e = &rec[i];
        if (e->kind == 1 || e->kind == -1) {
            uint64_t emitted = e->tick + e->late;
            if (steps && e->kind == rec[i - 1].kind) { /* within a move; a reversal starts from rest */
                if (e->tick - last_sched < min_interval) short_sched++;
                if (emitted - last_emitted < shortest) shortest = emitted - last_emitted;
                /* the interval QEMU's error may shorten: the step before late by
                   up to the worst lateness, this one on time */
                if (emitted - last_emitted + worst_late < min_interval) short_emitted++;
            }
            if (e->late > worst_late) worst_late = e->late;
            last_sched = e->tick;
            last_emitted = emitted;
            pos += e->kind;
            lit_steps += uv;
            steps++;
        } else if (e->kind == 3 && !uv) {
            uint64_t want = k < layers ? ((uint64_t)tops[k] * bin_nm * QEMU_STEPS_PER_MM + 500000u) / 1000000u : 0;
            if ((k >= layers || pos != (long)want) && bad_height++ < 3)
                CHECKF(0, "exposure %u at %ld steps, its layer's top is %llu", k + 1, pos, (unsigned long long)want);
            k++;
            uv = 1;
        } else if (e->kind == 2) {
            uv = 0;
        }
    }
    summary_steps = err ? qemu_said(err, "fw-mps2: trace steps ", 0) : -1;
    CHECKF(k == layers && !bad_height, "%u exposures for %u layers, %zu at the wrong height", k, layers, bad_height);
    CHECKF(steps > 1000 && (long long)steps == summary_steps, "%zu steps in the trace, the image counted %lld", steps, summary_steps);
    CHECKF(err && qemu_said(err, "fw-mps2: trace records lost ", 0) == 0 && qemu_said(err, "fw-mps2: replies dropped ", 0) == 0,
           "records or replies dropped: %s", err ? err : "");
    CHECKF(!lit_steps, "%zu steps with the light on", lit_steps);
    CHECKF(!short_sched, "%zu steps scheduled closer than %u ticks (the speed limit)", short_sched, min_interval);
    CHECKF(!short_emitted, "%zu steps emitted closer than the speed limit allows (shortest %llu ticks)", short_emitted,
           (unsigned long long)shortest);
    /* Emitted at or after the schedule is by construction (cm3_alarm runs a
       step only once cm3_ticks() has reached it); how much after is QEMU's:
       under -icount shift=5 time advances 32 ns an instruction and a timer
       interrupt is taken at the end of a translated block, and the notes
       measured 2-16 us per step. 50 us (1250 ticks) leaves room for a long
       block, and stays far below the 250 us step interval at full speed;
       a step later than the core's step lead would have stopped the print. */
    CHECKF(worst_late <= 50u * (QEMU_TICK_HZ / 1000000u), "worst step lateness %llu ticks (%.1f us)", (unsigned long long)worst_late,
           worst_late * 1e6 / QEMU_TICK_HZ);
    /* Bounded work a pass (fw.h): every pass of the loop, while Z moves and
       while it is still (planning, a print's start), is shorter than the
       shortest step interval at the top speed, so the loop computes steps
       faster than they leave whatever else it does. The loop's own work,
       its interrupts' ticks taken out (serve.c): QEMU's UART sends a
       reply's bytes, and takes a burst of the host's, as fast as the
       handlers run, so one pass can carry dozens of their interrupts that a
       line at 115200 baud spreads over milliseconds. */
    work = err ? qemu_said(err, "fw-mps2: the loop's own work, worst pass (cycles) ", 0) : -1;
    moving_work = err ? qemu_said(err, "fw-mps2: the loop's own work, worst pass while Z moves (cycles) ", 0) : -1;
    CHECKF(moving_work > 0 && moving_work < (long long)min_interval, "the loop's worst pass while Z moves took %lld cycles, a step comes every %u",
           moving_work, min_interval);
    CHECKF(work > 0 && work < (long long)min_interval, "the loop's worst pass took %lld cycles, a step comes every %u at the top speed", work,
           min_interval);
    if (!check_case_failed())
        printf("     %zu steps, worst lateness %llu cycles (%.1f us), shortest interval %llu cycles (limit %u); "
               "worst loop pass %lld cycles, %lld while Z moves (its interrupts in: %lld, %lld); stack %lld bytes\n",
               steps, (unsigned long long)worst_late, worst_late * 1e6 / QEMU_TICK_HZ, (unsigned long long)shortest, min_interval,
               work, moving_work, err ? qemu_said(err, "fw-mps2: worst loop pass (cycles) ", 0) : -1,
               err ? qemu_said(err, "fw-mps2: worst loop pass while Z moves (cycles) ", 0) : -1,
               err ? qemu_said(err, "fw-mps2: stack used (bytes) ", 0) : -1);
    free(bin);
    free(err);
    free(tops);
}

/* The hang image stops its loop dead in layer 2's exposure: the UV alarm
   still puts the light out at the exposure's end, the watchdog (250 ms
   without a refresh) turns UV and Z off and resets the MCU, and QEMU starts
   the image again (a second boot line). The host is not asked to notice
   (the boot id is the host's part); it is stopped here. */
static void watchdog_resets_a_hung_loop(void)
{
    qemu_run q;
    pid_t host;
    char *err = NULL;
    int i, booted_again = 0;
    long long hung, expired, uv_off;
    if (!qemu_start(&q, "build/fw-mps2-hang.elf")) {
        CHECK(!"qemu-system-arm did not start with build/fw-mps2-hang.elf");
        if (q.pid > 0) qemu_wait(&q, 0);
        return;
    }
    fflush(NULL);
    host = fork();
    if (host == 0) {
        int null = open("/dev/null", O_RDWR), log = open(cli_path("host.log"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(null, 0);
        dup2(log, 1);
        dup2(log, 2);
        execl(cli_tool, cli_tool, "print", MODEL, "--scale", "5", "--port", q.port, "--exposure", "0.05", "--penetration", "0.1",
              "--bottom-layers", "1", "--bottom-exposure", "0.1", "--peel", "0.5", "--peel-speed", "10", "--return-speed", "10",
              "--settle", "0.02", (char *)NULL);
        _exit(127);
    }
    for (i = 0; i < 60 * 10 && !booted_again; i++) {
        struct timespec ts = {0, 100000000};
        nanosleep(&ts, NULL);
        free(err);
        err = cli_read(cli_path("qemu.err"));
        booted_again = err && qemu_said(err, "fw-mps2: boot", 1) >= 0;
    }
    if (host > 0) { kill(host, SIGTERM); waitpid(host, NULL, 0); }
    qemu_wait(&q, 0);
    if (!booted_again) {
        char *log = cli_read(cli_path("host.log"));
        CHECKF(0, "no second boot within 60 s: %s; the host: %s", err ? err : "", log ? log : "");
        free(log);
    }
    hung = err ? qemu_said(err, "fw-mps2: hung at tick ", 0) : -1;
    expired = err ? qemu_said(err, "fw-mps2: watchdog expired at tick ", 0) : -1;
    uv_off = err ? qemu_said(err, "fw-mps2: the UV light went off at tick ", 0) : -1;
    CHECKF(hung > 0 && expired > hung && expired - hung <= (long long)QEMU_WATCHDOG_MS * (QEMU_TICK_HZ / 1000u),
           "hung at %lld, the watchdog expired at %lld (period %u ms)", hung, expired, QEMU_WATCHDOG_MS);
    /* the light went off while the loop was hung: by its timer, at the
       exposure's end, before the watchdog */
    CHECKF(uv_off > hung && uv_off <= expired, "UV off at %lld; hung at %lld, watchdog at %lld", uv_off, hung, expired);
    if (!check_case_failed())
        printf("     hung at %.3f s, UV off %.1f ms later, watchdog reset %.1f ms after the hang\n", hung / (double)QEMU_TICK_HZ,
               (uv_off - hung) * 1e3 / QEMU_TICK_HZ, (expired - hung) * 1e3 / QEMU_TICK_HZ);
    free(err);
}

void test_qemu_timing(void)
{
    if (!cli_begin("adaslice-qemu")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-trace.elf", steps_on_time_under_qemu);
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-hang.elf", watchdog_resets_a_hung_loop);
    cli_end();
}
