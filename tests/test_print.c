/* adaslice print against the firmware over pseudo-terminals: the simulator
   port (firmware/ports/sim), a faulty line between them (tests/relay.c), the
   Cortex-M3 image under qemu-system-arm, and printrun's printcore in G-code
   mode. Each check reads what the printer's pins did from the simulator's
   log (tests/zcheck.h) and the host's --report. */
#define _XOPEN_SOURCE 700 /* posix_openpt, ptsname */
#include "cli_run.h"
#include "zcheck.h"
#include "../adaslice.h"
#include "meshgen.h"
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <time.h>

#define SIM_BIN "build/fw-sim"
#define RELAY_BIN "build/relay"
#define SIM_SPEED "100"

typedef struct child { pid_t pid; int out; char line[256]; } child;

/* Starts argv[0] with stdout on a pipe and reads lines until one starts with
   `prefix` (within `seconds`); that line is kept in c->line. */
static int child_start(child *c, char *const argv[], const char *prefix, double seconds)
{
    int fds[2];
    size_t len = 0;
    struct timespec t0, t;
    memset(c, 0, sizeof *c);
    if (pipe(fds) != 0) return 0;
    fflush(NULL);
    c->pid = fork();
    if (c->pid == 0) {
        int null = open("/dev/null", O_RDONLY);
        dup2(null, 0);
        dup2(fds[1], 1);
        dup2(fds[1], 2);
        close(fds[0]);
        execv(argv[0], argv);
        _exit(127);
    }
    close(fds[1]);
    c->out = fds[0];
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (;;) {
        struct pollfd p = {c->out, POLLIN, 0};
        char ch;
        clock_gettime(CLOCK_MONOTONIC, &t);
        if ((t.tv_sec - t0.tv_sec) + (t.tv_nsec - t0.tv_nsec) / 1e9 > seconds) return 0;
        if (poll(&p, 1, 100) <= 0) continue;
        if (read(c->out, &ch, 1) != 1) return 0;
        if (ch != '\n') { if (len + 1 < sizeof c->line) c->line[len++] = ch; continue; }
        c->line[len] = 0;
        if (!strncmp(c->line, prefix, strlen(prefix))) return 1;
        len = 0;
    }
}

/* SIGTERM, then the exit status (-1 if it did not exit normally). */
static int child_stop(child *c)
{
    int st, i;
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGTERM);
    for (i = 0; i < 100; i++) {
        if (waitpid(c->pid, &st, WNOHANG) == c->pid) { close(c->out); c->pid = 0; return WIFEXITED(st) ? WEXITSTATUS(st) : -1; }
        { struct timespec ts = {0, 20000000}; nanosleep(&ts, NULL); }
    }
    kill(c->pid, SIGKILL);
    waitpid(c->pid, &st, 0);
    close(c->out);
    c->pid = 0;
    return -1;
}

/* The simulator's log: events, and its configuration from the "#" header. */
typedef struct sim_log {
    zevent *ev;
    size_t count;
    unsigned long tick_hz, steps_per_mm, max_speed, accel;
    long start_steps;
    size_t link_pauses;            /* state lines: paused with the link-lost flag */
    size_t user_pauses;            /* paused without it (PAUSE, Ctrl-C) */
    uint64_t pause_begin, pause_end;
    int steps_while_paused, uv_while_paused;
    uint64_t worst_step_offset;  /* ticks between a step's emission and its schedule */
    size_t unscheduled;          /* step lines without their scheduled tick */
} sim_log;

static int read_sim_log(const char *path, sim_log *l)
{
    char *text = cli_read(path), *line, *save = NULL;
    size_t cap = 0;
    int paused = 0;
    memset(l, 0, sizeof *l);
    if (!text) return 0;
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        unsigned long long when;
        char what[16], arg[32];
        int n;
        if (line[0] == '#') {
            const char *f;
            if ((f = strstr(line, "tick_hz="))) l->tick_hz = strtoul(f + 8, NULL, 10);
            if ((f = strstr(line, "steps_per_mm="))) l->steps_per_mm = strtoul(f + 13, NULL, 10);
            if ((f = strstr(line, "max_speed="))) l->max_speed = strtoul(f + 10, NULL, 10);
            if ((f = strstr(line, "accel="))) l->accel = strtoul(f + 6, NULL, 10);
            if ((f = strstr(line, "start_steps="))) l->start_steps = strtol(f + 12, NULL, 10);
            continue;
        }
        n = sscanf(line, "%llu %15s %31s", &when, what, arg);
        if (n < 2) continue;
        if (l->count == cap) {
            zevent *e = (zevent *)realloc(l->ev, (cap = cap ? 2 * cap : 65536) * sizeof *e);
            if (!e) break;
            l->ev = e;
        }
        if (!strcmp(what, "step")) {
            unsigned long long sched;
            if (sscanf(line, "%*u %*s %*d %llu", &sched) != 1) l->unscheduled++;
            else if ((sched > when ? sched - when : when - sched) > l->worst_step_offset)
                l->worst_step_offset = sched > when ? sched - when : when - sched;
            l->ev[l->count].kind = ZEV_STEP;
            l->ev[l->count].value = arg[0] == '-' ? -1 : 1;
            if (paused) l->steps_while_paused++;
        } else if (!strcmp(what, "uv")) {
            l->ev[l->count].kind = ZEV_UV;
            l->ev[l->count].value = atoi(arg);
            if (paused && l->ev[l->count].value) l->uv_while_paused++;
        } else if (!strcmp(what, "show")) {
            unsigned crc = 0;
            int slot = atoi(arg);
            if (slot >= 0) sscanf(line, "%*u %*s %*d %x", &crc);
            l->ev[l->count].kind = ZEV_SHOW;
            l->ev[l->count].value = slot;
            l->ev[l->count].crc = crc;
        } else if (!strcmp(what, "state")) {
            unsigned state = 0, flags = 0;
            sscanf(line, "%*u %*s %u %u", &state, &flags);
            if (state == 6 && !paused) {
                paused = 1;
                if (flags & 8) l->link_pauses++; else l->user_pauses++;
                l->pause_begin = when;
            }
            if (state != 6 && paused) { paused = 0; l->pause_end = when; }
            continue;
        } else continue;
        l->ev[l->count].when = when;
        l->count++;
    }
    free(text);
    return l->tick_hz && l->steps_per_mm && l->max_speed && l->accel;
}

/* The host's --report: each layer's top (bins) and mask CRC. */
typedef struct report { uint32_t layers, first, bin_nm, *tops, *crcs, *exposures; unsigned long retransmits, mask_bytes; int by_printer; } report;

static int read_report(const char *path, report *r)
{
    char *text = cli_read(path), *at;
    uint32_t k = 0;
    const char *f;
    memset(r, 0, sizeof *r);
    if (!text) return 0;
    if ((f = strstr(text, "\"layers\": "))) r->layers = (uint32_t)strtoul(f + 10, NULL, 10);
    if ((f = strstr(text, "\"first_layer\": "))) r->first = (uint32_t)strtoul(f + 15, NULL, 10);
    if ((f = strstr(text, "\"bin_nm\": "))) r->bin_nm = (uint32_t)strtoul(f + 10, NULL, 10);
    if ((f = strstr(text, "\"retransmitted_frames\": "))) r->retransmits = strtoul(f + 24, NULL, 10);
    if ((f = strstr(text, "\"mask_code_bytes\": "))) r->mask_bytes = strtoul(f + 19, NULL, 10);
    r->by_printer = strstr(text, "\"planned_by_printer\": true") != NULL;
    r->tops = (uint32_t *)calloc(r->layers + 1, sizeof *r->tops);
    r->crcs = (uint32_t *)calloc(r->layers + 1, sizeof *r->crcs);
    r->exposures = (uint32_t *)calloc(r->layers + 1, sizeof *r->exposures);
    for (at = strstr(text, "\"masks\""); at && k < r->layers && (at = strstr(at, "\"top_bins\": ")); k++) {
        r->tops[k] = (uint32_t)strtoul(at + 12, &at, 10);
        at = strstr(at, "\"crc32\": \"");
        if (!at) break;
        r->crcs[k] = (uint32_t)strtoul(at + 10, &at, 16);
        at = strstr(at, "\"exposure_ms\": ");
        if (!at) break;
        r->exposures[k] = (uint32_t)strtoul(at + 15, &at, 10);
    }
    free(text);
    return r->layers && k == r->layers;
}

static void report_free(report *r) { free(r->tops); free(r->crcs); free(r->exposures); }

/* Every print here runs with CURE: 0.1 s cure a layer of tmin on a resin of
   Dp 0.1 mm, two bottom layers of 0.5 s. */
#define CURE "--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", "0.5"

/* The exposures the host sent are Jacobs' working curve, E(t) = 0.1 s x
   exp((t - tmin) / 0.1 mm), to the millisecond the protocol carries. */
static void check_exposures(const report *r)
{
    uint32_t k, bad = 0;
    for (k = r->first ? r->first - 1 : 0; k < r->layers; k++) {
        double t = (r->tops[k] - (k ? r->tops[k - 1] : 0)) * (double)r->bin_nm / 1e6;
        double want = k < 2 ? 500 : 100 * exp((t - ADASLICE_DEFAULT_TMIN) / 0.1);
        if (fabs(r->exposures[k] - want) > 0.5 + 1e-9 && bad++ < 3)
            CHECKF(0, "layer %u (%.4f mm): %u ms of exposure, the working curve gives %.2f", k + 1, t, r->exposures[k], want);
    }
}

/* The record against the report: every layer shown once with the host's
   mask, at its exact height, the motion within limits. */
static void check_print(const char *log_path, const char *report_path, int expect_link_pause)
{
    sim_log l;
    report r;
    zexpect e;
    zsummary s;
    CHECKF(read_sim_log(log_path, &l), "cannot read the simulator's log %s", log_path);
    CHECKF(read_report(report_path, &r), "cannot read the report %s", report_path);
    if (check_case_failed()) { free(l.ev); report_free(&r); return; }
    memset(&e, 0, sizeof e);
    e.tick_hz = l.tick_hz;
    e.steps_per_mm = (uint32_t)l.steps_per_mm;
    e.max_speed = (uint32_t)l.max_speed;
    e.accel = (uint32_t)l.accel;
    e.start_position = l.start_steps;
    e.layers = r.layers;
    e.first = r.first;
    e.top_bins = r.tops;
    e.bin_nm = r.bin_nm;
    e.crcs = r.crcs;
    e.exposure_ms = r.exposures;
    check_exposures(&r);
    s = zcheck_record(l.ev, l.count, &e);
    CHECKF(s.shows == r.layers, "%zu masks shown for %u layers", s.shows, r.layers);
    /* each step left at its tick: 10 us is 100 ticks of the sim's clock */
    CHECKF(!l.unscheduled && l.worst_step_offset * 100000u <= l.tick_hz,
           "%zu steps without a schedule; one %llu ticks off it", l.unscheduled, (unsigned long long)l.worst_step_offset);
    if (expect_link_pause) {
        CHECKF(l.link_pauses >= 1, "no pause for the lost link in the log");
        CHECKF(!l.steps_while_paused && !l.uv_while_paused, "%d steps and %d UV-on while paused", l.steps_while_paused,
               l.uv_while_paused);
    }
    free(l.ev);
    report_free(&r);
}

static const char *MODEL = "examples/models/hand_closed.obj";

static int start_sim(child *sim, const char *log, const char *speed)
{
    char *argv[] = {(char *)SIM_BIN, (char *)"--log", (char *)log, (char *)"--speed", (char *)speed,
                    (char *)"--display", (char *)"240x200", (char *)"--pitch-um", (char *)"100", NULL};
    int ok = child_start(sim, argv, "pty ", 10);
    CHECKF(ok, "the simulator %s did not start (make builds it)", SIM_BIN);
    return ok;
}

/* The simulator behind tests/relay.c, which damages the line as `faults`
   (relay options) ask and writes what it did to `stats`; the host talks to
   relay->line + 4. */
static int start_relayed(child *sim, child *relay, const char *log, const char *stats, const char *const *faults)
{
    char mcu[256], *argv[16];
    int n = 0;
    if (!start_sim(sim, log, SIM_SPEED)) return 0;
    snprintf(mcu, sizeof mcu, "%s", sim->line + 4);
    argv[n++] = (char *)RELAY_BIN;
    argv[n++] = mcu;
    while (*faults && n < 12) argv[n++] = (char *)*faults++;
    argv[n++] = (char *)"--stats";
    argv[n++] = (char *)stats;
    argv[n] = NULL;
    if (child_start(relay, argv, "pty ", 10)) return 1;
    CHECK(!"the relay did not start");
    child_stop(relay);
    child_stop(sim);
    return 0;
}

static cli_result run_print(const char *port, const char *report)
{
    return cli_run("print", MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle",
                   "0.05", "--report", report, NULL);
}

/* A whole print of the bundled hand over a pty: the printer plans, the host
   agrees, every mask reaches the display intact. */
static void full_print_on_the_simulator(void)
{
    child sim;
    cli_result r;
    if (!start_sim(&sim, cli_path("sim.log"), SIM_SPEED)) return;
    r = run_print(sim.line + 4, cli_path("report.json"));
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "planned by the printer, identical to the host's plan") != NULL);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (r.status == 0) check_print(cli_path("sim.log"), cli_path("report.json"), 0);
    cli_free(&r);
}

/* 1 % of the bytes dropped or flipped both ways: the print still completes
   with every mask intact, no layer skipped or repeated. */
static void print_through_a_faulty_line(void)
{
    child sim, relay;
    cli_result r;
    const char *faults[] = {"--drop", "0.005", "--corrupt", "0.005", "--seed", "7", NULL};
    if (!start_relayed(&sim, &relay, cli_path("sim2.log"), cli_path("relay.txt"), faults)) return;
    r = run_print(relay.line + 4, cli_path("report2.json"));
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    child_stop(&relay);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (r.status == 0) {
        char *stats = cli_read(cli_path("relay.txt"));
        unsigned long up = 0, up_drop = 0, up_bad = 0, down = 0, down_drop = 0, down_bad = 0;
        CHECK(stats && sscanf(stats, "up %lu %lu %lu\ndown %lu %lu %lu", &up, &up_drop, &up_bad, &down, &down_drop, &down_bad) == 6);
        /* the faults happened, at about the rate asked */
        CHECKF(up_drop + up_bad > up / 200 && down_drop + down_bad > down / 200, "faults up %lu+%lu of %lu, down %lu+%lu of %lu",
               up_drop, up_bad, up, down_drop, down_bad, down);
        free(stats);
        check_print(cli_path("sim2.log"), cli_path("report2.json"), 0);
    }
    cli_free(&r);
}

/* The line goes dead for 5 s mid-print: the printer pauses itself (UV off, Z
   held), and the print resumes and completes when the line is back. */
static void print_survives_a_lost_link(void)
{
    child sim, relay;
    cli_result r;
    const char *faults[] = {"--outage-after", "12000", "--outage-for", "5", NULL};
    if (!start_relayed(&sim, &relay, cli_path("sim3.log"), cli_path("relay3.txt"), faults)) return;
    r = run_print(relay.line + 4, cli_path("report3.json"));
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    child_stop(&relay);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (r.status == 0) check_print(cli_path("sim3.log"), cli_path("report3.json"), 1);
    cli_free(&r);
}

/* Starts `adaslice print` in the background (for Ctrl-C). */
static pid_t print_in_background(char *const extra[], const char *out_path)
{
    char *argv[48];
    int n = 0, i;
    pid_t pid;
    argv[n++] = (char *)cli_tool;
    for (i = 0; extra[i] && n < 47; i++) argv[n++] = extra[i];
    argv[n] = NULL;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        int o = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644), null = open("/dev/null", O_RDONLY);
        dup2(null, 0);
        dup2(o, 1);
        dup2(o, 2);
        execv(cli_tool, argv);
        _exit(127);
    }
    return pid;
}

/* Events from the show of `layer` in the second run on: where a resumed
   print's record begins. */
static size_t nth_show_from_end(const sim_log *l, size_t shows_from_end)
{
    size_t k = l->count, seen = 0;
    while (k > 0) {
        k--;
        if (l->ev[k].kind == ZEV_SHOW && l->ev[k].value >= 0 && ++seen == shows_from_end) return k;
    }
    return 0;
}

/* Ctrl-C mid-print: the host pauses the printer (UV off at once, Z held) and
   exits 3 naming the layer; a second run with --resume-from K finishes the
   print from layer K, every layer from K on shown once with its mask at its
   exact height. */
static void ctrl_c_pauses_and_resume_finishes(void)
{
    child sim;
    char port[256], *out, *at;
    char *args[] = {(char *)"print", (char *)MODEL, (char *)"--scale", (char *)"15", (char *)"--port", port,
                    (char *)"--exposure", (char *)"0.1", (char *)"--penetration", (char *)"0.1", (char *)"--bottom-layers",
                    (char *)"2", (char *)"--bottom-exposure", (char *)"0.5", (char *)"--peel", (char *)"2", (char *)"--peel-speed", (char *)"10", (char *)"--return-speed",
                    (char *)"10", (char *)"--settle", (char *)"0.05", NULL};
    pid_t pid;
    int st, status = -1, i;
    unsigned layer = 0;
    cli_result r;
    sim_log l;
    report rep;
    if (!start_sim(&sim, cli_path("sim5.log"), "10")) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = print_in_background(args, cli_path("print5.out"));
    /* into the print: the log shows a few exposures */
    for (i = 0; i < 600; i++) {
        char *log = cli_read(cli_path("sim5.log"));
        int lit = 0;
        for (at = log; at && (at = strstr(at, " uv 1")) != NULL; at++) lit++;
        free(log);
        if (lit >= 6) break;
        { struct timespec ts = {0, 20000000}; nanosleep(&ts, NULL); }
    }
    kill(pid, SIGINT);
    if (waitpid(pid, &st, 0) == pid && WIFEXITED(st)) status = WEXITSTATUS(st);
    out = cli_read(cli_path("print5.out"));
    CHECKF(status == 3, "Ctrl-C: exit %d: %s", status, out ? out : "");
    at = out ? strstr(out, "--resume-from ") : NULL;
    CHECKF(at && sscanf(at + 14, "%u", &layer) == 1 && layer >= 3, "no layer to resume from in: %s", out ? out : "");
    free(out);
    if (check_case_failed()) { child_stop(&sim); return; }
    {
        char k[16];
        snprintf(k, sizeof k, "%u", layer);
        r = cli_run("print", MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle",
                    "0.05", "--resume-from", k, "--report", cli_path("report5.json"), NULL);
    }
    CHECKF(r.status == 0, "resume: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    CHECK(read_sim_log(cli_path("sim5.log"), &l) && read_report(cli_path("report5.json"), &rep));
    if (!check_case_failed()) {
        /* the resumed run's record: from its first layer's show to the end */
        size_t from = nth_show_from_end(&l, rep.layers - layer + 1), k;
        long pos = l.start_steps;
        zexpect e;
        for (k = 0; k < from; k++) if (l.ev[k].kind == ZEV_STEP) pos += l.ev[k].value;
        memset(&e, 0, sizeof e);
        e.tick_hz = l.tick_hz;
        e.steps_per_mm = (uint32_t)l.steps_per_mm;
        e.max_speed = (uint32_t)l.max_speed;
        e.accel = (uint32_t)l.accel;
        e.start_position = pos;
        e.layers = rep.layers;
        e.first = layer;
        e.top_bins = rep.tops;
        e.bin_nm = rep.bin_nm;
        e.crcs = rep.crcs;
        e.exposure_ms = rep.exposures;
        check_exposures(&rep);
        CHECK(rep.first == layer);
        (void)zcheck_record(l.ev + from, l.count - from, &e);
        /* between the Ctrl-C and the resume: the light off, Z still */
        CHECKF(l.user_pauses == 1 && !l.steps_while_paused && !l.uv_while_paused,
               "%zu pauses; %d steps and %d UV-on while paused", l.user_pauses, l.steps_while_paused, l.uv_while_paused);
    }
    free(l.ev);
    report_free(&rep);
}

/* adaslice slice writes masks.rle; print JOBDIR sends its plan (PLAN_SET)
   and streams its masks: the display shows exactly the job's masks. */
static void print_a_sliced_job(void)
{
    child sim;
    cli_result r;
    if (!start_sim(&sim, cli_path("sim6.log"), SIM_SPEED)) return;
    r = cli_run("slice", MODEL, "--scale", "15", "--pixels", "240x200", "--pitch", "0.1", "-o", cli_path("job"), CURE,
                "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05", NULL);
    CHECKF(r.status == 0, "slice: %s", r.err);
    cli_free(&r);
    /* the job holds its exposures and motion */
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--exposure", "3", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "slice it again"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--report", cli_path("report6.json"), NULL);
    CHECKF(r.status == 0, "print JOBDIR: exit %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "the host's plan") != NULL);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (!check_case_failed()) check_print(cli_path("sim6.log"), cli_path("report6.json"), 0);
    /* a damaged job: the message names the file and the byte. masks.rle:
       44 bytes of header, then layer 1: bins at 44, exposure at 48, CRC at
       52, code bytes at 56 */
    {
        static const struct { long at; unsigned char v[4]; const char *says; } damage[] = {
            {48, {0, 0, 0, 0}, "masks.rle: byte 48: layer 1's exposure of 0 ms"},
            {56, {0xff, 0xff, 0xff, 0x7f}, "masks.rle: byte 44: layer 1 runs past the end"},
        };
        int d;
        for (d = 0; d < 2; d++) {
            FILE *f = fopen(cli_path("job/masks.rle"), "r+b");
            CHECK(f != NULL);
            if (!f) break;
            fseek(f, damage[d].at, SEEK_SET);
            fwrite(damage[d].v, 1, 4, f);
            fclose(f);
            r = cli_run("print", cli_path("job"), "--port", "/dev/null", NULL);
            CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, damage[d].says), "damaged job: %d %s", r.status,
                   r.err);
            cli_free(&r);
            if (d == 0) { /* put the exposure back for the next damage */
                f = fopen(cli_path("job/masks.rle"), "r+b");
                if (f) { fseek(f, 48, SEEK_SET); fwrite("\xf4\x01\0\0", 1, 4, f); fclose(f); }
            }
        }
    }
}

/* Bad ports and arguments: one clear message, a non-zero exit. */
static void bad_ports_are_named(void)
{
    cli_result r = cli_run("print", MODEL, "--port", "/nonexistent/tty", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "/nonexistent/tty"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, "--port", "/dev/null", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "not a serial port"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, "--port", "/dev/null", "--baud", "12345", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "12345"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, NULL);
    CHECKF(r.status == 2 && strstr(r.err, "--port"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, "--port", "/dev/null", "--printer", "2k-5.5", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "reports its display"), "%d %s", r.status, r.err);
    cli_free(&r);
}

/* A silent port: no printer answers within the hello's time. */
static void silent_port_is_named(void)
{
    cli_result r;
    {
        int master = posix_openpt(O_RDWR | O_NOCTTY);
        CHECK(master >= 0 && !grantpt(master) && !unlockpt(master));
        if (master < 0) return;
        r = cli_run("print", MODEL, "--scale", "15", "--port", ptsname(master), NULL);
        CHECKF(r.status == 1 && strstr(r.err, "no adaslice printer answers"), "%d %s", r.status, r.err);
        cli_free(&r);
        close(master);
    }
}

/* A thousand layers on the simulator: a cylinder 100 mm tall in layers of
   0.1 mm, planned on the host (50,000 bins are more than the printer takes)
   and sent as a plan; the pins' record shows Z exactly at every layer's top,
   no drift, the motion within its limits and every mask shown once. */
static void thousand_layers_on_the_simulator(void)
{
    adaslice_mesh m = gen_cylinder(3, 100, 24, 0);
    child sim;
    cli_result r;
    cli_write_obj(cli_path("column.obj"), &m);
    gen_free(&m);
    if (!start_sim(&sim, cli_path("sim7.log"), "1000")) return;
    r = cli_run("print", cli_path("column.obj"), "--tmax", "0.1", "--port", sim.line + 4, CURE, "--peel", "0.5", "--peel-speed", "10",
                "--return-speed", "10", "--settle", "0.02", "--report", cli_path("report7.json"), NULL);
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "1000 layers, the host's plan") != NULL);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (!check_case_failed()) check_print(cli_path("sim7.log"), cli_path("report7.json"), 0);
}

/* The Cortex-M3 image (20 KiB of RAM) under qemu-system-arm prints a short
   job from the same host code; the image's exit status (semihosting) says
   it ended cleanly. QEMU counts instructions for time (-icount): its clock
   otherwise follows the host's, and a host busy elsewhere stalls the guest
   for milliseconds, which the firmware rightly refuses as late steps. The
   image spins instead of sleeping (notes: a core in WFI under -icount can
   wake a period late). */
static void short_print_under_qemu(void)
{
    child qemu;
    cli_result r;
    char *argv[] = {(char *)"/usr/bin/timeout", (char *)"300", (char *)"qemu-system-arm", (char *)"-M", (char *)"mps2-an385",
                    (char *)"-nographic", (char *)"-monitor", (char *)"none", (char *)"-serial", (char *)"pty",
                    (char *)"-semihosting-config", (char *)"enable=on,target=native", (char *)"-icount",
                    (char *)"shift=5,align=off,sleep=off", (char *)"-kernel", (char *)"build/fw-mps2-busy.elf", NULL};
    char port[64] = "", *at;
    int st, status = -1, i;
    if (!child_start(&qemu, argv, "char device redirected to ", 20)) {
        CHECK(!"qemu-system-arm did not start with build/fw-mps2-busy.elf (make firmware; apt-get install qemu-system-arm)");
        child_stop(&qemu);
        return;
    }
    at = strstr(qemu.line, "/dev/");
    for (i = 0; at && at[i] && at[i] != ' ' && i < 63; i++) port[i] = at[i];
    port[i] = 0;
    r = cli_run("print", MODEL, "--scale", "5", "--port", port, "--exposure", "0.05", "--penetration", "0.1", "--bottom-layers", "1",
                "--bottom-exposure", "0.1", "--peel", "0.5", "--peel-speed", "10", "--return-speed", "10", "--settle",
                "0.02", "--then-exit", NULL);
    CHECKF(r.status == 0, "print on QEMU exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "planned by the printer, identical to the host's plan") != NULL);
    for (i = 0; i < 250 && qemu.pid; i++) {
        if (waitpid(qemu.pid, &st, WNOHANG) == qemu.pid) { status = WIFEXITED(st) ? WEXITSTATUS(st) : -1; qemu.pid = 0; }
        else { struct timespec ts = {0, 20000000}; nanosleep(&ts, NULL); }
    }
    if (qemu.pid) child_stop(&qemu);
    else close(qemu.out);
    CHECKF(status == 0, "QEMU ended with %d (0: the firmware exited cleanly on EXIT)", status);
    cli_free(&r);
}

/* printrun's printcore sends a G-code file to the simulator in G-code mode:
   every line is acknowledged, Z lands where the file says, the light is on
   only while Z stands still. */
static void printcore_drives_gcode_mode(void)
{
    child sim, pc;
    char *text, *argv[6];
    int sent = 0, oks = 0, status;
    const char *line;
    sim_log l;
    size_t k;
    int uv = 0, moving_lit = 0;
    long pos;
    cli_write(cli_path("job.gcode"), "; a layer by hand\nG28\nG90\nG1 Z5 F300\nG4 P100\nM106 S255\nG4 P300\nM107\n"
                                     "G91\nG1 Z1.5 F600 ; relative\nG90\nM114\nG1 Z10\nM400\nM18\n");
    {
        char *sargv[] = {(char *)SIM_BIN, (char *)"--log", (char *)cli_path("sim4.log"), (char *)"--speed", (char *)"20", NULL};
        if (!child_start(&sim, sargv, "pty ", 10)) { CHECK(!"the simulator did not start"); return; }
    }
    argv[0] = (char *)"/usr/bin/python3";
    argv[1] = (char *)"/usr/bin/printcore";
    argv[2] = (char *)"-v";
    argv[3] = sim.line + 4;
    argv[4] = (char *)cli_path("job.gcode");
    argv[5] = NULL;
    if (!child_start(&pc, argv, "SENT: N-1 M110*15", 10)) { CHECK(!"printcore (Debian printrun) did not start its print"); child_stop(&sim); return; }
    /* the rest of its output, until it exits */
    {
        size_t cap = 1 << 16, n = 0;
        ssize_t got;
        text = (char *)calloc(cap, 1);
        while (text && n + 1 < cap && (got = read(pc.out, text + n, cap - 1 - n)) > 0) n += (size_t)got;
    }
    status = -1;
    {
        int st;
        if (waitpid(pc.pid, &st, 0) == pc.pid && WIFEXITED(st)) status = WEXITSTATUS(st);
        close(pc.out);
        pc.pid = 0;
    }
    CHECKF(status == 0, "printcore exited %d", status);
    for (line = text; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        if (!strncmp(line, "SENT: N", 7) && strncmp(line, "SENT: N-1 ", 10)) sent++;
        if (!strncmp(line, "RECV: ok", 8)) oks++;
        CHECKF(strncmp(line, "RECV: Error", 11), "printcore was told %.60s", line);
    }
    CHECKF(sent == 14 && oks >= sent, "%d lines sent, %d acknowledged", sent, oks);
    CHECK(text && strstr(text, "Z:6.500") && strstr(text, "Z_move_comp"));
    free(text);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    CHECK(read_sim_log(cli_path("sim4.log"), &l));
    pos = l.start_steps;
    for (k = 0; k < l.count; k++) {
        if (l.ev[k].kind == ZEV_STEP) { pos += l.ev[k].value; moving_lit += uv; }
        if (l.ev[k].kind == ZEV_UV) uv = l.ev[k].value;
    }
    CHECKF(pos == 10 * (long)l.steps_per_mm && !moving_lit && !uv, "ends at %ld steps; %d steps lit", pos, moving_lit);
    free(l.ev);
}

void test_print(void)
{
    if (!cli_begin("adaslice-print")) { CHECK(!"no temporary directory"); return; }
    RUN(full_print_on_the_simulator);
    RUN(print_through_a_faulty_line);
    RUN(print_survives_a_lost_link);
    RUN(thousand_layers_on_the_simulator);
    RUN(ctrl_c_pauses_and_resume_finishes);
    RUN(print_a_sliced_job);
    RUN(bad_ports_are_named);
    RUN(silent_port_is_named);
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-busy.elf (arm-none-eabi-gcc)", short_print_under_qemu);
    RUN_NEEDING("printcore (Debian printrun)", printcore_drives_gcode_mode);
    cli_end();
}
