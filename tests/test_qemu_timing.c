/* The Cortex-M3 image's timing and watchdog under qemu-system-arm -icount:
   build/fw-mps2-trace.elf records every step's scheduled tick and the tick
   its alarm interrupt ran (cm3_ticks()), and every UV edge, and writes them
   at exit to fw-mps2-trace.bin in QEMU's directory (16-byte records, see
   firmware/ports/mps2/board.c), with a summary on QEMU's stderr;
   build/fw-mps2-hang.elf is the same image whose loop hangs in layer 2's
   exposure. */
#define _XOPEN_SOURCE 700
#include "cli_run.h"
#include "zcheck.h"
#include "print_report.h"
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <time.h>

#define QEMU_TICK_HZ 25000000u /* the an385's clock: a tick is a cycle */
#define QEMU_STEPS_PER_MM 400u
#define QEMU_START_STEPS (30 * 400) /* MPS2_Z_START_MM */
#define QEMU_MAX_SPEED (10u * 400u) /* cm3_z_config: 10 mm/s */
#define QEMU_ACCEL (50u * 400u)     /* and 50 mm/s^2 */
#define QEMU_PEEL_UM 500u
/* how late QEMU may take a timer's interrupt: under -icount shift=5 time
   advances 32 ns an instruction and an interrupt is taken at the end of a
   translated block (the notes measured 2-16 us a step); 50 us leaves room
   for a long block, far below the 250 us step interval at full speed */
#define QEMU_LATE_MAX (50u * (QEMU_TICK_HZ / 1000000u))
#define QEMU_WATCHDOG_MS 250u
/* The image's step queue (fw.h's default, 8) and the steps that go out
   before the loop refills it (at most half of it): what is left covers the
   steps due while the loop is away (fw.h's rule for a pass). */
#define QEMU_STEP_QUEUE 8u
#define QEMU_REFILL_GAP (QEMU_STEP_QUEUE / 2u)
/* A move's first step comes 5 ms after the pass that starts it (cm3/main.c,
   step_lead), computed in the next pass: two passes fit in the lead. */
#define QEMU_STEP_LEAD (QEMU_TICK_HZ / 200u)
/* A slice of a held frame's work, one pass: rows' CRC bytes and profile
   bins (fw.h's defaults, FW_CRC_BYTES and FW_PLAN_BINS, which the image keeps). */
#define QEMU_CRC_BYTES 64u
#define QEMU_PLAN_BINS 8u
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

typedef struct trace_record { uint64_t tick; uint32_t late; int32_t kind; } trace_record;

/* A short print with masks streaming, on the trace image: every step was
   emitted at or after its tick and within QEMU's lateness of it, and no
   emitted interval is below the speed limit less that lateness; the
   schedule (exact ticks) and the UV edges (late by as much) pass
   tests/zcheck.h's check, which uses no firmware code: each exposure at its
   layer's top for its time, the light never on while Z moves, speed,
   acceleration and each move's start from rest within the limits, the
   steps the heights moved. No loop pass takes as long as a step interval
   at the top speed. */
static void steps_on_time_under_qemu(void)
{
    qemu_run q;
    cli_result r;
    print_report rep;
    uint32_t k, min_interval = (QEMU_TICK_HZ + QEMU_MAX_SPEED - 1) / QEMU_MAX_SPEED;
    trace_record *rec;
    zevent *ev = NULL;
    uint64_t *path = NULL;
    zexpect e;
    zsummary s;
    size_t n, i, steps = 0, short_emitted = 0, events = 0;
    uint64_t worst_late = 0, last_emitted = 0, shortest = UINT64_MAX;
    long long summary_steps, work, moving_work, cover;
    double crc_ns = 0, bin_ns = 0, pass_ns;
    int status, have_report;
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
    CHECKF(print_pace(r.out, &crc_ns, &bin_ns), "the host did not say the printer's pace: %s", r.out);
    cli_free(&r);
    status = qemu_wait(&q, 10);
    CHECKF(status == 0, "QEMU ended with %d (0: the firmware exited cleanly on EXIT)", status);
    err = read_whole_text(cli_path("qemu.err"));
    have_report = read_print_report(cli_path("report.json"), &rep);
    CHECKF(have_report && rep.layers > 1, "the report has %u layers", have_report ? rep.layers : 0);
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
    ev = (zevent *)calloc(n + 1, sizeof *ev);
    for (i = 0; rec && ev && i < n; i++) {
        const trace_record *t = &rec[i];
        if (t->kind == 1 || t->kind == -1) {
            uint64_t emitted = t->tick + t->late;
            /* the interval QEMU's lateness may shorten: the step before
               late, this one on time */
            if (steps && emitted - last_emitted < shortest) shortest = emitted - last_emitted;
            if (steps && emitted - last_emitted + QEMU_LATE_MAX < min_interval) short_emitted++;
            if (t->late > worst_late) worst_late = t->late;
            last_emitted = emitted;
            steps++;
            ev[events].kind = ZEV_STEP;
            ev[events].value = t->kind;
            ev[events++].when = t->tick;
        } else if (t->kind == 3 || t->kind == 2) {
            ev[events].kind = ZEV_UV;
            ev[events].value = t->kind == 3;
            ev[events++].when = t->tick;
        }
    }
    if (have_report && ev && !check_case_failed()) {
        path = (uint64_t *)calloc(2u * rep.layers, sizeof *path);
        for (k = 0; path && k < rep.layers; k++) {
            path[2 * k] = (uint64_t)rep.tops[k] * rep.bin_nm;
            path[2 * k + 1] = path[2 * k] + QEMU_PEEL_UM * 1000u;
        }
        memset(&e, 0, sizeof e);
        e.tick_hz = QEMU_TICK_HZ;
        e.steps_per_mm = QEMU_STEPS_PER_MM;
        e.max_speed = QEMU_MAX_SPEED;
        e.accel = QEMU_ACCEL;
        e.jitter = 0;                  /* the steps' scheduled ticks */
        e.uv_jitter = QEMU_LATE_MAX;   /* the UV alarm's interrupt, taken late */
        e.start_position = QEMU_START_STEPS;
        e.layers = rep.layers;
        e.first = 1;
        e.top_bins = rep.tops;
        e.bin_nm = rep.bin_nm;
        e.exposure_ms = rep.exposures;
        e.path_nm = path;
        e.path_len = path ? 2u * rep.layers : 0;
        s = zcheck_record(ev, events, &e);
        CHECKF(path && s.moves >= 2u * rep.layers && s.ramp_windows, "%zu moves from rest and %zu ramp windows checked for %u layers",
               s.moves, s.ramp_windows, rep.layers);
        if (!check_case_failed())
            printf("     %zu moves, first intervals within %.1f ticks of sqrt(2/a), %zu ramp windows at %.4f..%.4f of the acceleration\n",
                   s.moves, s.worst_first_ticks, s.ramp_windows, s.lowest_ramp_ratio, s.worst_accel_ratio);
    }
    summary_steps = err ? qemu_said(err, "fw-mps2: trace steps ", 0) : -1;
    CHECKF(steps > 1000 && (long long)steps == summary_steps, "%zu steps in the trace, the image counted %lld", steps, summary_steps);
    CHECKF(err && qemu_said(err, "fw-mps2: trace records lost ", 0) == 0 && qemu_said(err, "fw-mps2: replies dropped ", 0) == 0,
           "records or replies dropped: %s", err ? err : "");
    CHECKF(!short_emitted, "%zu steps emitted closer than the speed limit less QEMU's lateness allows (shortest %llu ticks)",
           short_emitted, (unsigned long long)shortest);
    /* Emitted at or after the schedule is by construction (cm3_alarm runs a
       step only once cm3_ticks() has reached it); how much after is QEMU's.
       A step later than the core's step lead would have stopped the print. */
    CHECKF(worst_late <= QEMU_LATE_MAX, "worst step lateness %llu ticks (%.1f us)", (unsigned long long)worst_late,
           worst_late * 1e6 / QEMU_TICK_HZ);
    /* Bounded work a pass (fw.h): every pass of the loop while Z moves is
       shorter than the time the queue less a refill covers at the top speed,
       so the steps never wait on the loop whatever else it does (the rule
       the RAMPS image's test holds too), and every pass while Z is still
       (planning, a print's start) is shorter than half the step lead, so a
       move started in one pass has its first step computed in time. The loop's own work, its interrupts' ticks
       taken out (serve.c): QEMU's UART sends a reply's bytes, and takes a
       burst of the host's, as fast as the handlers run, so one pass can
       carry dozens of their interrupts that a line at 115200 baud spreads
       over milliseconds, and a whole chunk of a frame that a line brings
       over several passes: how long the longest pass is then depends on how
       fast the host's process runs, which one step interval cannot bound. */
    CHECKF(err && qemu_said(err, "fw-mps2: passes whose interrupts outran them ", 0) == 0,
           "%lld passes counted more interrupt ticks than they lasted: the own-work figures below are wrong",
           err ? qemu_said(err, "fw-mps2: passes whose interrupts outran them ", 0) : -1);
    work = err ? qemu_said(err, "fw-mps2: the loop's own work, worst pass (cycles) ", 0) : -1;
    moving_work = err ? qemu_said(err, "fw-mps2: the loop's own work, worst pass while Z moves (cycles) ", 0) : -1;
    cover = (long long)(QEMU_STEP_QUEUE - QEMU_REFILL_GAP) * min_interval;
    CHECKF(moving_work > 0 && moving_work < cover, "the loop's worst pass while Z moves took %lld cycles, the queue covers %lld",
           moving_work, cover);
    CHECKF(work > 0 && work < (long long)QEMU_STEP_LEAD / 2, "the loop's worst pass took %lld cycles, half the step lead is %u",
           work, QEMU_STEP_LEAD / 2);
    /* The pace IDENTIFY states, which the host waits by: a slice of a held
       frame's work is one pass and another may come between two, so two of
       the loop's worst passes (its own work: see above) must fit a slice's
       allowance. */
    pass_ns = (double)(work > moving_work ? work : moving_work) * 1e9 / QEMU_TICK_HZ;
    CHECKF(2 * pass_ns <= QEMU_CRC_BYTES * crc_ns && 2 * pass_ns <= QEMU_PLAN_BINS * bin_ns,
           "the worst pass took %.0f us: two do not fit the %.0f us a slice of CRC, %.0f us of planning, IDENTIFY states",
           pass_ns / 1e3, QEMU_CRC_BYTES * crc_ns / 1e3, QEMU_PLAN_BINS * bin_ns / 1e3);
    if (!check_case_failed())
        printf("     IDENTIFY's pace %.1f us a byte of rows' CRC, %.1f us a bin: a slice's allowance %.0f us of CRC, %.0f us of "
               "planning, two worst passes %.0f us\n", crc_ns / 1e3, bin_ns / 1e3, QEMU_CRC_BYTES * crc_ns / 1e3,
               QEMU_PLAN_BINS * bin_ns / 1e3, 2 * pass_ns / 1e3);
    if (!check_case_failed())
        printf("     %zu steps, worst lateness %llu cycles (%.1f us), shortest interval %llu cycles (limit %u); "
               "worst loop pass %lld cycles, %lld while Z moves (its interrupts in: %lld, %lld; the queue covers %lld); stack %lld bytes\n",
               steps, (unsigned long long)worst_late, worst_late * 1e6 / QEMU_TICK_HZ, (unsigned long long)shortest, min_interval,
               work, moving_work, err ? qemu_said(err, "fw-mps2: worst loop pass (cycles) ", 0) : -1,
               err ? qemu_said(err, "fw-mps2: worst loop pass while Z moves (cycles) ", 0) : -1, cover,
               err ? qemu_said(err, "fw-mps2: stack used (bytes) ", 0) : -1);
    free(bin);
    free(err);
    free(ev);
    free(path);
    print_report_free(&rep);
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
        err = read_whole_text(cli_path("qemu.err"));
        booted_again = err && qemu_said(err, "fw-mps2: boot", 1) >= 0;
    }
    if (host > 0) { kill(host, SIGTERM); waitpid(host, NULL, 0); }
    qemu_wait(&q, 0);
    if (!booted_again) {
        char *log = read_whole_text(cli_path("host.log"));
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
