/* adaslice print against the firmware over pseudo-terminals: the simulator
   port (firmware/ports/sim), a faulty line between them (tests/relay.c), the
   Cortex-M3 image under qemu-system-arm, and printrun's printcore in G-code
   mode. Each check reads what the printer's pins did from the simulator's
   log (tests/zcheck.h) and the host's --report. */
#define _XOPEN_SOURCE 700 /* posix_openpt, ptsname */
#include "cli_run.h"
#include "wait.h"
#include "zcheck.h"
#include "print_report.h"
#include "../adaslice.h"
#include "../link/frame.h"
#include "../link/messages.h"
#include "../link/tty.h"
#include "../firmware/ports/sim/board.h"
#include "meshgen.h"
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <time.h>
#include <termios.h>
#include <sys/socket.h>
#include <sys/un.h>

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

/* SIGTERM (after SIGCONT, for one a test halted), then the exit status (-1
   if it did not exit normally). */
static int child_stop(child *c)
{
    int st, i;
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGCONT);
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
    char *text = read_whole_text(path), *line, *save = NULL;
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


/* Every print here runs with CURE: 0.1 s cure a layer of tmin on a resin of
   Dp 0.1 mm, two bottom layers of 0.5 s. */
#define CURE "--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", "0.5"

/* The exposures the host sent are Jacobs' working curve, E(t) = 0.1 s x
   exp((t - tmin) / 0.1 mm), to the millisecond the protocol carries. */
static void check_exposures(const print_report *r)
{
    uint32_t k, bad = 0;
    for (k = r->first ? r->first - 1 : 0; k < r->layers; k++) {
        double t = (r->tops[k] - (k ? r->tops[k - 1] : 0)) * (double)r->bin_nm / 1e6;
        double want = k < 2 ? 500 : 100 * exp((t - ADASLICE_DEFAULT_TMIN) / 0.1);
        if (fabs(r->exposures[k] - want) > 0.5 + 1e-9 && bad++ < 3)
            CHECKF(0, "layer %u (%.4f mm): %u ms of exposure, the working curve gives %.2f", k + 1, t, r->exposures[k], want);
    }
}

/* The record from event `from` on against layers first .. of the report;
   with `peel_um`, a whole print's, whose Z visits each layer's top and
   then the peel above it. */
static zsummary check_record_from(const sim_log *l, const print_report *rep, size_t from, uint32_t first, uint32_t peel_um)
{
    size_t k;
    long pos = l->start_steps;
    zexpect e;
    zsummary s;
    uint64_t *path = peel_um ? (uint64_t *)calloc(2u * rep->layers + 1u, sizeof *path) : NULL;
    for (k = 0; k < from; k++) if (l->ev[k].kind == ZEV_STEP) pos += l->ev[k].value;
    for (k = 0; path && k < rep->layers; k++) {
        path[2 * k] = (uint64_t)rep->tops[k] * rep->bin_nm;
        path[2 * k + 1] = path[2 * k] + peel_um * 1000u;
    }
    memset(&e, 0, sizeof e);
    e.tick_hz = l->tick_hz;
    e.steps_per_mm = (uint32_t)l->steps_per_mm;
    e.max_speed = (uint32_t)l->max_speed;
    e.accel = (uint32_t)l->accel;
    e.jitter = 0; /* the sim's clock puts each step out at its tick */
    e.start_position = pos;
    e.layers = rep->layers;
    e.first = first;
    e.top_bins = rep->tops;
    e.bin_nm = rep->bin_nm;
    e.crcs = rep->crcs;
    e.exposure_ms = rep->exposures;
    e.path_nm = path;
    e.path_len = path ? 2u * rep->layers : 0;
    s = zcheck_record(l->ev + from, l->count - from, &e);
    CHECKF(!peel_um || (s.moves >= 2u * rep->layers && s.ramp_windows), "%zu moves from rest and %zu ramp windows checked for %u layers",
           s.moves, s.ramp_windows, rep->layers);
    free(path);
    return s;
}

/* The record against the report: every layer shown once with the host's
   mask, at its exact height, the motion within limits, Z's steps the
   heights moved with a peel of `peel_um` after each layer. */
static void check_print(const char *log_path, const char *report_path, int expect_link_pause, uint32_t peel_um)
{
    sim_log l;
    print_report r;
    zsummary s;
    CHECKF(read_sim_log(log_path, &l), "cannot read the simulator's log %s", log_path);
    CHECKF(read_print_report(report_path, &r), "cannot read the report %s", report_path);
    if (check_case_failed()) { free(l.ev); print_report_free(&r); return; }
    check_exposures(&r);
    s = check_record_from(&l, &r, 0, r.first, peel_um);
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
    print_report_free(&r);
}

static const char *MODEL = "examples/models/hand_closed.obj";

/* The simulator with the display of these tests and `extra` options (or NULL). */
static int start_sim_with(child *sim, const char *log, const char *speed, const char *const *extra)
{
    char *argv[16] = {(char *)SIM_BIN, (char *)"--log", (char *)log, (char *)"--speed", (char *)speed,
                      (char *)"--display", (char *)"240x200", (char *)"--pitch-um", (char *)"100", NULL};
    int n = 9, ok;
    while (extra && *extra && n < 15) argv[n++] = (char *)*extra++;
    argv[n] = NULL;
    ok = child_start(sim, argv, "pty ", 10);
    CHECKF(ok, "the simulator %s did not start (make builds it)", SIM_BIN);
    return ok;
}

static int start_sim(child *sim, const char *log, const char *speed) { return start_sim_with(sim, log, speed, NULL); }

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

/* HUPCL on the terminal `port` (through a descriptor of our own: the
   simulator holds the pty open, so the setting stays): set it when `set`,
   and return whether it is set, -1 if the terminal cannot be read. */
static int port_hupcl(const char *port, int set)
{
    struct termios t;
    int fd = open(port, O_RDWR | O_NOCTTY | O_NONBLOCK), on = -1;
    if (fd < 0) return -1;
    if (tcgetattr(fd, &t) == 0) {
        if (set) { t.c_cflag |= HUPCL; (void)tcsetattr(fd, TCSANOW, &t); (void)tcgetattr(fd, &t); }
        on = (t.c_cflag & HUPCL) != 0;
    }
    close(fd);
    return on;
}

/* A whole print of the bundled hand over a pty: the printer plans, the host
   agrees, every mask reaches the display intact. The host leaves the port
   without HUPCL (set before the print), so a later open raises no DTR edge
   to reset a board whose USB bridge resets on it. */
static void full_print_on_the_simulator(void)
{
    child sim;
    cli_result r;
    if (!start_sim(&sim, cli_path("sim.log"), SIM_SPEED)) return;
    CHECK(port_hupcl(sim.line + 4, 1) == 1);
    r = run_print(sim.line + 4, cli_path("report.json"));
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "planned by the printer, identical to the host's plan") != NULL);
    {
        /* the pace the simulator's board.h declares reached the host
           through IDENTIFY (its time is the host CPU's, which no test may
           measure; the AVR and QEMU images' are held to their passes) */
        double crc_ns = 0, bin_ns = 0;
        CHECKF(print_pace(r.out, &crc_ns, &bin_ns) && crc_ns == BOARD_CRC_BYTE_NS && bin_ns == BOARD_PLAN_BIN_NS,
               "the host says a pace of %g and %g ns, fw-sim's board.h %u and %u: %s", crc_ns, bin_ns,
               (unsigned)BOARD_CRC_BYTE_NS, (unsigned)BOARD_PLAN_BIN_NS, r.out);
    }
    CHECKF(port_hupcl(sim.line + 4, 0) == 0, "HUPCL is %d on the port after the print", port_hupcl(sim.line + 4, 0));
    if (r.status != 0) { cli_free(&r); child_stop(&sim); return; }
    cli_free(&r);
    /* the job is done: a resume of it says so, and names no layer to resume from */
    r = cli_run("print", MODEL, "--scale", "15", "--port", sim.line + 4, CURE, "--peel", "2", "--peel-speed", "10",
                "--return-speed", "10", "--settle", "0.05", "--resume-from", "5", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "finished this job (all ") && !strstr(r.err, "resume from"),
           "a finished job resumed: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    check_print(cli_path("sim.log"), cli_path("report.json"), 0, 2000);
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
        char *stats = read_whole_text(cli_path("relay.txt"));
        unsigned long up = 0, up_drop = 0, up_bad = 0, down = 0, down_drop = 0, down_bad = 0;
        CHECK(stats && sscanf(stats, "up %lu %lu %lu\ndown %lu %lu %lu", &up, &up_drop, &up_bad, &down, &down_drop, &down_bad) == 6);
        /* the faults happened, at about the rate asked */
        CHECKF(up_drop + up_bad > up / 200 && down_drop + down_bad > down / 200, "faults up %lu+%lu of %lu, down %lu+%lu of %lu",
               up_drop, up_bad, up, down_drop, down_bad, down);
        free(stats);
        check_print(cli_path("sim2.log"), cli_path("report2.json"), 0, 2000);
    }
    cli_free(&r);
}

/* The line goes dead for 2 s mid-print, more than the printer's link timeout
   (1 s) and less than the host's --give-up (3 s): the printer pauses itself
   (UV off, Z held), and the print resumes and completes when the line is
   back. */
static void print_survives_a_lost_link(void)
{
    child sim, relay;
    cli_result r;
    const char *faults[] = {"--outage-after", "12000", "--outage-for", "2", NULL};
    if (!start_relayed(&sim, &relay, cli_path("sim3.log"), cli_path("relay3.txt"), faults)) return;
    r = run_print(relay.line + 4, cli_path("report3.json"));
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    child_stop(&relay);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (r.status == 0) check_print(cli_path("sim3.log"), cli_path("report3.json"), 1, 2000);
    cli_free(&r);
}

static int second_host_status(const char *port, uint8_t type, link_status *out);
static void check_resumed_in_place(const char *log_path, const char *report_path, size_t split_min, size_t split_max);

/* The host goes deaf mid-print for 6 s (the printer's replies are lost, the
   host's frames arrive): it hears nothing, resends its window, and gives up
   (exit 5, ~3.4 s). The printer takes the repeats for no word from the host,
   so it has paused itself for the lost link before the host says it stopped,
   and lights nothing after: the layer the host names is where it stood when
   last heard (it may have gone on as far as its masks, two layers at most),
   and a resume from there either resumes it in place or is refused naming
   the layer the printer holds, which then resumes it; every layer gets its
   light exactly. */
static void deaf_host_gives_up_after_the_printer_paused(void)
{
    child sim, relay;
    const char *faults[] = {"--outage-after", "12000", "--outage-for", "6", "--outage-way", "down", NULL};
    cli_result r;
    sim_log l;
    link_status st;
    size_t lit_at_exit;
    unsigned k = 0;
    char port[256], from[16];
    const char *at;
    int state;
    if (!start_relayed(&sim, &relay, cli_path("sim21.log"), cli_path("relay21.txt"), faults)) return;
    snprintf(port, sizeof port, "%s", relay.line + 4);
    r = run_print(port, cli_path("report21.json"));
    lit_at_exit = lit_so_far(cli_path("sim21.log"));
    CHECK(read_sim_log(cli_path("sim21.log"), &l));
    CHECKF(r.status == 5 && cli_one_message(r.err) && strstr(r.err, "stopped answering"), "deaf: exit %d: %s", r.status, r.err);
    CHECKF(l.link_pauses == 1, "when the host gave up the printer had paused %zu times for the lost link", l.link_pauses);
    free(l.ev);
    at = strstr(r.err, "--resume-from ");
    CHECKF(at && sscanf(at, "--resume-from %u", &k) == 1 && k > 1, "no layer to resume from: %s", r.err);
    cli_free(&r);
    if (check_case_failed()) { child_stop(&relay); child_stop(&sim); return; }
    sleep_ms(4000); /* the outage's end, and a link timeout more */
    CHECKF(lit_so_far(cli_path("sim21.log")) == lit_at_exit, "lit %zu times after the host gave up",
           lit_so_far(cli_path("sim21.log")) - lit_at_exit);
    state = second_host_status(port, LINK_MSG_STATUS, &st);
    /* as far as the masks it had: the layer it was at, and the next */
    CHECKF(state == LINK_STATE_PAUSED && (st.flags & LINK_FLAG_LINK_LOST) && st.exposed + 1 >= k && st.exposed + 1 <= k + 2,
           "the printer is %d (flags %u), layer %u exposed; the host said resume from %u", state, (unsigned)st.flags,
           (unsigned)st.exposed, k);
    if (check_case_failed()) { child_stop(&relay); child_stop(&sim); return; }
    snprintf(from, sizeof from, "%u", k);
#define DEAF_ARGS MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", \
                  "--settle", "0.05", "--home", "--report", cli_path("report21.json"), "--resume-from"
    r = cli_run("print", DEAF_ARGS, from, NULL);
    if (st.exposed + 1 != k) {
        /* the printer went a layer on before it paused: the resume says which */
        char want[64];
        snprintf(want, sizeof want, "resume from %u", (unsigned)st.exposed + 1);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, want), "--resume-from %u: exit %d: %s", k, r.status,
               r.err);
        cli_free(&r);
        snprintf(from, sizeof from, "%u", (unsigned)st.exposed + 1);
        r = cli_run("print", DEAF_ARGS, from, NULL);
    }
#undef DEAF_ARGS
    CHECKF(r.status == 0 && strstr(r.out, "in place"), "resume from %s: exit %d: %s %s", from, r.status, r.out, r.err);
    cli_free(&r);
    child_stop(&relay);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (!check_case_failed()) check_resumed_in_place(cli_path("sim21.log"), cli_path("report21.json"), 0, 1);
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

/* Events from the show of the layer `shows_from_end` shows before the end:
   where a print started again at a layer begins. */
static size_t nth_show_from_end(const sim_log *l, size_t shows_from_end)
{
    size_t k = l->count, seen = 0;
    while (k > 0) {
        k--;
        if (l->ev[k].kind == ZEV_SHOW && l->ev[k].value >= 0 && ++seen == shows_from_end) return k;
    }
    return 0;
}

/* The print of these tests on `port` and `extra` arguments in the background,
   its output (both streams) to out_path. */
static pid_t hand_print_in_background(const char *port, const char *const *extra, const char *out_path)
{
    const char *base[] = {"print", MODEL, "--scale", "15", "--port", port, "--peel", "2", "--peel-speed", "10",
                          "--return-speed", "10", "--settle", "0.05", NULL};
    char *argv[40];
    int n = 0, i;
    for (i = 0; base[i]; i++) argv[n++] = (char *)base[i];
    while (*extra && n < 39) argv[n++] = (char *)*extra++;
    argv[n] = NULL;
    return print_in_background(argv, out_path);
}

/* A print interrupted and resumed in place is one record from the start to
   the end: every layer shown once (with the host's mask where the report
   knows it), exposed at its exact height, with exactly its light in all its
   pieces: one UV-on period a layer, and one more for each of `split_min` ..
   `split_max` exposures a pause split. */
static void check_resumed_in_place(const char *log_path, const char *report_path, size_t split_min, size_t split_max)
{
    sim_log l;
    print_report rep;
    size_t k, on = 0;
    CHECK(read_sim_log(log_path, &l) && read_print_report(report_path, &rep));
    if (check_case_failed()) { free(l.ev); print_report_free(&rep); return; }
    (void)check_record_from(&l, &rep, 0, 1, 0);
    for (k = 0; k < l.count; k++) on += l.ev[k].kind == ZEV_UV && l.ev[k].value;
    CHECKF(on >= rep.layers + split_min && on <= rep.layers + split_max, "%zu UV-on periods for %u layers, %zu to %zu split",
           on, rep.layers, split_min, split_max);
    CHECKF(!l.steps_while_paused && !l.uv_while_paused, "%d steps and %d UV-on while paused", l.steps_while_paused,
           l.uv_while_paused);
    free(l.ev);
    print_report_free(&rep);
}

/* Ctrl-C mid-print: the host pauses the printer (UV off at once, Z held) and
   exits 3 naming the layer; a second run with --resume-from K resumes it in
   place: from the first run's homing to the end, every layer shown once
   with its mask at its exact height and its exposure to the tick. */
static void ctrl_c_pauses_and_resume_finishes(void)
{
    child sim;
    char port[256], *out, *at, k[16];
    const char *extra[] = {CURE, NULL};
    pid_t pid;
    int status;
    unsigned layer = 0;
    cli_result r;
    sim_log l;
    if (!start_sim(&sim, cli_path("sim5.log"), "10")) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print5.out"));
    (void)wait_for_exposures(cli_path("sim5.log"), 6);
    kill(pid, SIGINT);
    status = wait_exit(pid, 30);
    out = read_whole_text(cli_path("print5.out"));
    CHECKF(status == 3, "Ctrl-C: exit %d: %s", status, out ? out : "");
    at = out ? strstr(out, "--resume-from ") : NULL;
    CHECKF(at && sscanf(at + 14, "%u", &layer) == 1 && layer >= 3, "no layer to resume from in: %s", out ? out : "");
    free(out);
    if (check_case_failed()) { child_stop(&sim); return; }
    snprintf(k, sizeof k, "%u", layer);
    r = cli_run("print", MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed",
                "10", "--settle", "0.05", "--resume-from", k, "--report", cli_path("report5.json"), NULL);
    /* a layer owes some of its light, or gets all of it: never "0 ms left" */
    CHECKF(r.status == 0 && strstr(r.out, "in place") && !strstr(r.out, " 0 ms of its exposure left"), "resume: exit %d: %s %s",
           r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    CHECK(read_sim_log(cli_path("sim5.log"), &l));
    CHECKF(l.user_pauses == 1, "%zu pauses", l.user_pauses);
    free(l.ev);
    {
        print_report rep;
        CHECK(read_print_report(cli_path("report5.json"), &rep));
        check_exposures(&rep);
        print_report_free(&rep);
    }
    /* the pause split one exposure, or came between two */
    check_resumed_in_place(cli_path("sim5.log"), cli_path("report5.json"), 0, 1);
}

/* A paused print abandoned (print --abort): a print started over it is
   refused, naming the paused layer, the one to resume from and --abort;
   --abort ends the print (the printer READY, its light off, its display
   dark, and nothing lit after the pause) and lifts the platform to the top
   of Z's travel (--z-max 30), as the printer itself reports; a second
   --abort finds nothing to abandon. */
static int second_host_status(const char *port, uint8_t type, link_status *out);

static void abort_abandons_a_paused_print(void)
{
    child sim;
    char port[256], *out;
    const char *sim_extra[] = {"--z-max", "30", NULL}, *extra[] = {CURE, NULL};
    pid_t pid;
    int status, state;
    unsigned paused_at = 0, from = 0;
    link_status st;
    cli_result r;
    sim_log l;
    size_t k;
    if (!start_sim_with(&sim, cli_path("sim20.log"), "10", sim_extra)) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print20.out"));
    CHECK(wait_for_exposures(cli_path("sim20.log"), 4));
    kill(pid, SIGINT);
    status = wait_exit(pid, 30);
    out = read_whole_text(cli_path("print20.out"));
    CHECKF(status == 3 && out && strstr(out, "paused at layer "), "Ctrl-C: exit %d: %s", status, out ? out : "");
    if (out && strstr(out, "paused at layer ")) sscanf(strstr(out, "paused at layer ") + 16, "%u", &paused_at);
    if (out && strstr(out, "--resume-from ")) sscanf(strstr(out, "--resume-from ") + 14, "%u", &from);
    free(out);
    if (check_case_failed()) { child_stop(&sim); return; }
    r = cli_run("print", MODEL, "--scale", "15", "--port", port, CURE, NULL);
    {
        char paused[64], resume[64];
        snprintf(paused, sizeof paused, "paused at layer %u of ", paused_at);
        snprintf(resume, sizeof resume, "--resume-from %u, or abandon it with adaslice print --abort", from);
        CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, paused) && strstr(r.err, resume) &&
                   !strstr(r.err, "is printing"), "a print over the paused one: exit %d: %s", r.status, r.err);
    }
    cli_free(&r);
    r = cli_run("print", "--abort", "--port", port, NULL);
    CHECKF(r.status == 0 && !*r.err && strstr(r.out, "abandoned the print at layer "), "--abort: exit %d: %s %s", r.status,
           r.out, r.err);
    cli_free(&r);
    state = second_host_status(port, LINK_MSG_STATUS, &st);
    CHECKF(state == LINK_STATE_READY && !(st.flags & (LINK_FLAG_UV | LINK_FLAG_MOVING)) && (st.flags & LINK_FLAG_HOMED) &&
               st.z_nm == 30000000, "after --abort: state %d, flags %u, z %ld nm", state, (unsigned)st.flags, (long)st.z_nm);
    r = cli_run("print", "--abort", "--port", port, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "nothing to abandon"), "--abort again: exit %d: %s",
           r.status, r.err);
    cli_free(&r);
    r = cli_run("print", "--abort", "--port", port, MODEL, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, MODEL), "--abort MODEL: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed() || !read_sim_log(cli_path("sim20.log"), &l)) return;
    {
        int last_uv = -1, last_show = 0;
        size_t lit_after = 0;
        for (k = 0; k < l.count; k++) {
            if (l.ev[k].kind == ZEV_UV) last_uv = l.ev[k].value;
            if (l.ev[k].kind == ZEV_SHOW) last_show = l.ev[k].value;
            if (l.ev[k].kind == ZEV_UV && l.ev[k].value && l.ev[k].when > l.pause_begin) lit_after++;
        }
        CHECKF(l.user_pauses == 1 && last_uv == 0 && last_show < 0 && !lit_after,
               "%zu pauses; the light last %d, the display last %d, %zu lit after the pause", l.user_pauses, last_uv,
               last_show, lit_after);
    }
    free(l.ev);
}

/* The host killed (SIGKILL) while layer 2 exposes: the printer pauses itself
   when the link goes silent, keeping the light it still owes; --resume-from
   another layer or with another job is refused (exit 2, naming the layers),
   and --resume-from 2 of the same job resumes in place: layer 2's light in
   two pieces adds up to its exposure to the tick, every layer once. */
static void host_killed_mid_exposure_resumes_in_place(void)
{
    child sim;
    char port[256];
    const char *sim_extra[] = {"--link-timeout-ms", "500", NULL};
    const char *extra[] = {"--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", "20", NULL};
    pid_t pid;
    cli_result r;
    sim_log l;
    if (!start_sim_with(&sim, cli_path("sim8.log"), "10", sim_extra)) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print8.out"));
    CHECK(wait_for_exposures(cli_path("sim8.log"), 2));
    kill(pid, SIGKILL);
    (void)wait_exit(pid, 10);
    sleep_ms(1000); /* the link timeout, twice */
#define RESUME_ARGS "--port", port, "--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", \
                    "20", "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05"
    r = cli_run("print", MODEL, "--scale", "14", RESUME_ARGS, "--resume-from", "2", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--resume-from 2: the printer is paused at layer 2 of another job"),
           "another job: %d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, "--scale", "15", RESUME_ARGS, "--resume-from", "3", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--resume-from 3: the printer is paused at layer 2"),
           "another layer: %d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", MODEL, "--scale", "15", RESUME_ARGS, "--resume-from", "2", "--report", cli_path("report8.json"), NULL);
#undef RESUME_ARGS
    CHECKF(r.status == 0 && strstr(r.out, "resuming layer 2 in place"), "resume: exit %d: %s %s", r.status, r.out, r.err);
    {
        unsigned left = 0;
        const char *at = strstr(r.out, "in place: ");
        CHECKF(at && sscanf(at + 10, "%u", &left) == 1 && left > 0 && left < 20000, "the light left: %s", r.out);
    }
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    CHECK(read_sim_log(cli_path("sim8.log"), &l));
    CHECKF(l.link_pauses == 1 && !l.user_pauses, "%zu pauses for the lost link, %zu others", l.link_pauses, l.user_pauses);
    free(l.ev);
    check_resumed_in_place(cli_path("sim8.log"), cli_path("report8.json"), 1, 1);
}

/* The host's message after the printer restarted mid-print, found in `out`:
   one line, the boot ids, the layer to continue from; 0 if it is not there. */
static unsigned restart_message(const char *out, unsigned *old_id, unsigned *new_id)
{
    const char *at = out ? strstr(out, "restarted (boot id ") : NULL, *line = at;
    unsigned k = 0, lines = 0;
    const char *p;
    for (p = out; p && (p = strstr(p, "adaslice: ")) != NULL; p++) lines++;
    CHECKF(lines == 1, "%u messages: %s", lines, out ? out : "");
    if (!at || sscanf(at, "restarted (boot id %u -> %u)", old_id, new_id) != 2) return 0;
    while (line > out && line[-1] != '\n') line--;
    CHECKF(strstr(line, "Z must be homed") && strstr(line, "was the last fully exposed"), "the message: %s", line);
    at = strstr(at, "--resume-from ");
    if (!at || sscanf(at, "--resume-from %u --home", &k) != 1 || !strstr(at, "--home")) return 0;
    return k;
}

/* SIGUSR1 resets the simulated MCU mid-print (a new boot id, the state lost,
   Z unhomed): the host stops within 5 s with exit 4 and one message naming
   the boot ids, the last layer exposed and how to continue. Resuming there
   without --home is refused (exit 2, naming the layer); with --home the
   printer homes and prints from that layer on, each at its exact height. */
static void mcu_reset_mid_print_on_the_simulator(void)
{
    child sim;
    char port[256], *out, k[16];
    const char *extra[] = {CURE, NULL};
    pid_t pid;
    int status;
    unsigned layer, old_id = 0, new_id = 0;
    double reset_at, took;
    cli_result r;
    sim_log l;
    print_report rep;
    if (!start_sim(&sim, cli_path("sim9.log"), "10")) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print9.out"));
    CHECK(wait_for_exposures(cli_path("sim9.log"), 6));
    kill(sim.pid, SIGUSR1);
    reset_at = seconds_now();
    status = wait_exit(pid, 30);
    took = seconds_now() - reset_at;
    out = read_whole_text(cli_path("print9.out"));
    CHECKF(status == 4 && took < 5, "after the reset: exit %d in %.2f s: %s", status, took, out ? out : "");
    layer = restart_message(out, &old_id, &new_id);
    CHECKF(layer >= 3 && new_id == old_id + 1, "no restart message (boot id %u -> %u, layer %u): %s", old_id, new_id, layer,
           out ? out : "");
    free(out);
    if (check_case_failed()) { child_stop(&sim); return; }
    snprintf(k, sizeof k, "%u", layer);
#define HAND_ARGS MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", \
                  "--settle", "0.05", "--resume-from", k
    r = cli_run("print", HAND_ARGS, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--home") && strstr(r.err, k), "unhomed: %d %s", r.status,
           r.err);
    cli_free(&r);
    r = cli_run("print", HAND_ARGS, "--home", "--report", cli_path("report9.json"), NULL);
#undef HAND_ARGS
    CHECKF(r.status == 0, "--home: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    CHECK(read_sim_log(cli_path("sim9.log"), &l) && read_print_report(cli_path("report9.json"), &rep));
    if (!check_case_failed()) {
        /* from the show of layer K after the restart to the end: homed again, Z at each layer's top */
        size_t from = nth_show_from_end(&l, rep.layers - layer + 1);
        char *log = read_whole_text(cli_path("sim9.log"));
        CHECK(log && strstr(log, " reset signal"));
        free(log);
        CHECK(rep.first == layer);
        check_record_from(&l, &rep, from, layer, 0);
    }
    free(l.ev);
    print_report_free(&rep);
}

/* The MCU resets two fifths into layer 1's exposure of 2 s (fw-sim
   --reset-in-exposure 1; --speed 1, so the MCU keeps the host's time): the
   host exits 4 with one line naming the light layer 1 still owes, as its
   last STATUS said, and how much less it may owe (the time since that
   STATUS was made), and --resume-from 1 --home --exposure-left N. More than
   the layer's exposure is refused (exit 2); that command homes and gives
   layer 1 exactly N ms, so its light in the two pieces of the pins' record
   is its 2 s, never less, more by at most the bound the host stated, not
   the whole exposure again; the layers after it print as planned. */
static void mcu_reset_mid_exposure_owes_only_the_rest(void)
{
    child sim;
    const char *opts[] = {"--reset-in-exposure", "1", "--z-start", "1", NULL};
    char port[256], left[16], *log, *line, *save = NULL;
    const char *at;
    unsigned owed = 0, less = 0, given = 0;
    unsigned long long on = 0, pre = 0, post = 0, reset = 0, e;
    cli_result r;
    sim_log l;
    print_report rep;
    if (!start_sim_with(&sim, cli_path("sim15.log"), "1", opts)) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
#define OWED_ARGS MODEL, "--scale", "3", "--port", port, "--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "1", \
                  "--bottom-exposure", "2", "--peel", "0.5", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05"
    r = cli_run("print", OWED_ARGS, NULL);
    at = strstr(r.err, "layer 1 owes ");
    CHECKF(r.status == 4 && cli_one_message(r.err) && strstr(r.err, "restarted (boot id ") && at &&
               sscanf(at, "layer 1 owes %u ms of its light (or up to %u ms less)", &owed, &less) == 2 && owed && owed < 2000,
           "after the reset: exit %d: %s", r.status, r.err);
    at = strstr(r.err, "--resume-from 1 --home --exposure-left ");
    CHECKF(at && sscanf(at + 39, "%u", &given) == 1 && given == owed, "the way on: %s", r.err);
    cli_free(&r);
    if (check_case_failed()) { child_stop(&sim); return; }
    r = cli_run("print", OWED_ARGS, "--resume-from", "1", "--home", "--exposure-left", "2001", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "layer 1's exposure is 2000 ms"), "%d %s", r.status, r.err);
    cli_free(&r);
    snprintf(left, sizeof left, "%u", owed);
    r = cli_run("print", OWED_ARGS, "--resume-from", "1", "--home", "--exposure-left", left, "--report", cli_path("report15.json"),
                NULL);
#undef OWED_ARGS
    CHECKF(r.status == 0 && strstr(r.out, "light it owes"), "the resume: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    /* layer 1's light: the piece before the reset and the first after it */
    log = read_whole_text(cli_path("sim15.log"));
    for (line = log ? strtok_r(log, "\n", &save) : NULL; line; line = strtok_r(NULL, "\n", &save)) {
        unsigned long long t;
        char what[16], arg[16];
        if (sscanf(line, "%llu %15s %15s", &t, what, arg) != 3) continue;
        if (!strcmp(what, "reset")) {
            CHECKF(!strcmp(arg, "pin") && on && !reset, "%s", line);
            reset = t;
            pre = t - on; /* the light goes out with the reset */
            on = 0;
        } else if (!strcmp(what, "uv") && arg[0] == '1') {
            on = t;
        } else if (!strcmp(what, "uv") && on && reset && !post) {
            post = t - on;
        }
    }
    free(log);
    CHECK(read_sim_log(cli_path("sim15.log"), &l) && read_print_report(cli_path("report15.json"), &rep));
    if (check_case_failed()) { free(l.ev); print_report_free(&rep); return; }
    e = 2ull * l.tick_hz;
    CHECKF(pre && post == (unsigned long long)owed * l.tick_hz / 1000u && post < e,
           "layer 1: %llu ticks of light before the reset, %llu after (%u ms owed)", pre, post, owed);
    CHECKF(pre + post >= e && pre + post <= e + (unsigned long long)less * l.tick_hz / 1000u,
           "layer 1: %llu + %llu ticks of light for %llu, at most %u ms more", pre, post, e, less);
    printf("    reset %.1f ms into layer 1's 2 s: %.1f ms more light after it, %.2f ms over (the host's bound %u ms)\n",
           pre * 1e3 / l.tick_hz, post * 1e3 / l.tick_hz, ((double)pre + (double)post - (double)e) * 1e3 / l.tick_hz, less);
    /* from the show of layer 2 on, every layer at its exact height with its light */
    CHECK(rep.first == 1);
    (void)check_record_from(&l, &rep, nth_show_from_end(&l, rep.layers - 1), 2, 0);
    free(l.ev);
    print_report_free(&rep);
}

/* The port goes away mid-print (the relay between host and printer killed:
   the host's end of its pty then reads and writes EIO, as an unplugged USB
   adapter's does): the host ends at once with exit 5, as for a printer that
   stopped answering, and one line naming the layer, the last fully exposed
   and --resume-from K. The printer lost only the line: it pauses itself,
   and that command on its own port resumes the print in place. */
static void unplugged_port_ends_as_a_lost_printer(void)
{
    child sim, relay;
    const char *faults[] = {NULL}, *extra[] = {CURE, NULL};
    char port[256], *out, k[16], left[16];
    const char *left_option = NULL; /* --exposure-left, if the line gives it */
    const char *at;
    unsigned layer = 0, exposed = 0, from = 0, lines = 0, n;
    int status;
    double gone, took;
    pid_t pid;
    cli_result r;
    if (!start_relayed(&sim, &relay, cli_path("sim16.log"), cli_path("relay16.txt"), faults)) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(relay.line + 4, extra, cli_path("print16.out"));
    CHECK(wait_for_exposures(cli_path("sim16.log"), 4));
    kill(relay.pid, SIGKILL);
    gone = seconds_now();
    status = wait_exit(pid, 30);
    took = seconds_now() - gone;
    child_stop(&relay);
    out = read_whole_text(cli_path("print16.out"));
    for (at = out; at && (at = strstr(at, "adaslice: ")) != NULL; at++) lines++;
    at = out ? strstr(out, " went away (") : NULL;
    CHECKF(status == 5 && took < 5 && lines == 1 && at, "unplugged: exit %d %.2f s after, %u messages: %s", status, took, lines,
           out ? out : "");
    at = at ? strstr(at, ") at layer ") : NULL;
    CHECKF(at && sscanf(at, ") at layer %u", &layer) == 1 && (at = strstr(at, ": layer ")) &&
               sscanf(at, ": layer %u was the last fully exposed", &exposed) == 1 && (at = strstr(at, "--resume-from ")) &&
               sscanf(at, "--resume-from %u --home", &from) == 1 && layer >= 3 && from == exposed + 1 &&
               (layer == exposed || layer == exposed + 1),
           "the layers: %s", out ? out : "");
    if (at && (at = strstr(at, "--exposure-left ")) && sscanf(at, "--exposure-left %u", &n) == 1) {
        snprintf(left, sizeof left, "%u", n);
        left_option = "--exposure-left";
    }
    printf("    unplugged at layer %u: exit %d %.2f s after\n", layer, status, took);
    free(out);
    if (check_case_failed()) { child_stop(&sim); return; }
    sleep_ms(2000); /* the printer's link timeout, 1 s, twice */
    /* the printer went on until that timeout, with the mask it had: the
       resume names the layer it reached, and the command then resumes it */
    for (n = 0; n < 2; n++) {
        const char *said;
        snprintf(k, sizeof k, "%u", from);
        r = cli_run("print", MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed",
                    "10", "--settle", "0.05", "--resume-from", k, "--home", "--report", cli_path("report16.json"), left_option,
                    left, NULL);
        said = strstr(r.err, ": resume from ");
        if (n == 0 && r.status == 2 && said && sscanf(said, ": resume from %u", &from) == 1 && from > exposed + 1) {
            left_option = NULL;
            cli_free(&r);
            continue;
        }
        CHECKF(r.status == 0 && strstr(r.out, "in place"), "resume from %s: exit %d: %s %s", k, r.status, r.out, r.err);
        cli_free(&r);
        break;
    }
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (!check_case_failed()) check_resumed_in_place(cli_path("sim16.log"), cli_path("report16.json"), 0, 1);
}

/* For a failure that came once in many runs (the port hung up 3 s after
   the simulator was halted): whether the simulator still lives, stopped,
   and the end of its log. */
static void say_how_child_is(const child *c, const char *log_path)
{
    char path[64], stat[512] = "", *log, *end;
    FILE *f;
    snprintf(path, sizeof path, "/proc/%ld/stat", (long)c->pid);
    if ((f = fopen(path, "r"))) { /* its size reads as 0: a line, not a file */
        if (!fgets(stat, sizeof stat, f)) stat[0] = 0;
        fclose(f);
    }
    end = strrchr(stat, ')');
    /* T: stopped, as the test left it; Z: it exited */
    printf("    the simulator (pid %ld): state %c\n", (long)c->pid, end && end[1] ? end[2] : '?');
    log = read_whole_text(log_path);
    if (log) {
        size_t n = strlen(log);
        printf("    its log ends: %s\n", log + (n > 600 ? n - 600 : 0));
    }
    free(log);
}

/* The host's one line when the printer stopped answering: exit 5 within 5 s
   of the halt (the bound, --give-up's 3 s and a window of frames' time on
   the line, plus the host's poll). Returns the layer it says to resume from
   (0 when the print had not begun, -1 if the line is not there); `where` is
   what the line must say of the state or layer the printer was in. */
static int check_lost_message(int status, double took, const char *out, const char *where)
{
    const char *at = out ? strstr(out, "stopped answering (nothing for ") : NULL, *p;
    unsigned k = 0, lines = 0;
    double silent = 0;
    for (p = out; p && (p = strstr(p, "adaslice: ")) != NULL; p++) lines++;
    CHECKF(status == 5 && took < 5 && lines == 1, "after the halt: exit %d in %.2f s, %u messages: %s", status, took, lines,
           out ? out : "");
    CHECKF(at && sscanf(at, "stopped answering (nothing for %lf s)", &silent) == 1 && silent >= 3 && silent < 4,
           "the silence: %s", out ? out : "");
    CHECKF(at && strstr(at, where) && strstr(at, "Z must be homed before printing again"), "not '%s': %s", where,
           out ? out : "");
    if (check_case_failed() || !at) return -1;
    if (strstr(at, "before this run exposed a layer")) return 0;
    at = strstr(at, "--resume-from ");
    CHECKF(at && sscanf(at, "--resume-from %u --home", &k) == 1 && strstr(at, "--home"), "no layer to resume from: %s", out);
    return check_case_failed() ? -1 : (int)k;
}

/* The simulated MCU halted mid-exposure (SIGSTOP: no byte read or sent, no
   timer runs): the host exits 5 within 5 s, naming the layer, the last one
   fully exposed, that Z must be homed and how to continue. Let go again
   (SIGCONT), the printer pauses itself for the silent link, keeping the
   light it owes, and the command the line gives resumes it in place: every
   layer gets exactly its light. */
static void mcu_halted_mid_exposure_on_the_simulator(void)
{
    child sim;
    char port[256], *out, k[16];
    /* 20 s bottom exposures: 2 s of the wall at --speed 10 */
    const char *extra[] = {"--exposure", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", "20",
                           "--report", cli_path("report11.json"), NULL};
    pid_t pid;
    int status, layer;
    double halted, took;
    cli_result r;
    if (!start_sim(&sim, cli_path("sim11.log"), "10")) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print11.out"));
    CHECK(wait_for_exposures(cli_path("sim11.log"), 2));
    sleep_ms(300);
    kill(sim.pid, SIGSTOP);
    halted = seconds_now();
    status = wait_exit(pid, 30);
    took = seconds_now() - halted;
    out = read_whole_text(cli_path("print11.out"));
    layer = check_lost_message(status, took, out, "at layer 2 (exposing): layer 1 was the last fully exposed");
    printf("    halted mid-exposure: exit %d %.2f s after SIGSTOP\n", status, took);
    free(out);
    CHECKF(layer == 2, "resume from layer %d", layer);
    if (check_case_failed()) { child_stop(&sim); return; }
    kill(sim.pid, SIGCONT);
    sleep_ms(2000); /* the printer's link timeout, 1 s, twice */
    snprintf(k, sizeof k, "%d", layer);
    r = cli_run("print", MODEL, "--scale", "15", "--port", port, "--exposure", "0.1", "--penetration", "0.1", "--bottom-layers",
                "2", "--bottom-exposure", "20", "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle",
                "0.05", "--resume-from", k, "--home", "--report", cli_path("report11.json"), NULL);
    CHECKF(r.status == 0 && strstr(r.out, "resuming layer 2 in place"), "resume: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    if (!check_case_failed()) check_resumed_in_place(cli_path("sim11.log"), cli_path("report11.json"), 1, 1);
}

/* Halted where the print has not begun: while Z homes (the simulator answers
   STATUS while it homes, so the host holds it to --give-up then too, not to
   the homing allowance of a port that reads nothing while homing) and while
   it plans (fw-sim --stop-at-state 3 stops itself as the profile arrives). */
static void mcu_halted_while_homing_or_planning(void)
{
    int c;
    for (c = 0; c < 2; c++) {
        child sim;
        char port[256], *out, *log = NULL;
        const char *homing[] = {"--z-start", "30", NULL}, *planning[] = {"--stop-at-state", "3", NULL}, *extra[] = {CURE, NULL};
        pid_t pid;
        int status, i;
        double halted = 0, took;
        /* --speed 1: 6 s of homing from 30 mm at 5 mm/s */
        if (!start_sim_with(&sim, cli_path("sim12.log"), c ? "10" : "1", c ? planning : homing)) return;
        snprintf(port, sizeof port, "%s", sim.line + 4);
        pid = hand_print_in_background(port, extra, cli_path("print12.out"));
        for (i = 0; i < 1000 && !halted; i++) {
            free(log);
            log = read_whole_text(cli_path("sim12.log"));
            if (c == 0 && log && strstr(log, " step -1 ")) {
                sleep_ms(500);
                kill(sim.pid, SIGSTOP);
                halted = seconds_now();
            } else if (c == 1 && log && strstr(log, " halt")) {
                halted = seconds_now();
            } else {
                sleep_ms(10);
            }
        }
        free(log);
        CHECKF(halted, "%s never began", c ? "planning" : "homing");
        status = wait_exit(pid, 150);
        took = seconds_now() - halted;
        out = read_whole_text(cli_path("print12.out"));
        CHECK(check_lost_message(status, took, out, c ? "while planning, before" : "while homing, before") == 0);
        if (check_case_failed()) say_how_child_is(&sim, cli_path("sim12.log"));
        printf("    halted while %s: exit %d %.2f s after the halt\n", c ? "planning" : "homing", status, took);
        free(out);
        child_stop(&sim);
        if (check_case_failed()) return;
    }
}

/* Talks to the printer on `port` as a second host would: HELLO, then `type`
   (a message without a payload), then STATUS, each sent again until its
   answer comes (2 s at most). The state the printer reports, -1 if it does
   not answer; its whole STATUS_REPLY in *out (unless NULL). */
static int second_host_status(const char *port, uint8_t type, link_status *out)
{
    const uint8_t types[3] = {LINK_MSG_HELLO, type, LINK_MSG_STATUS};
    uint8_t frame[LINK_FRAME_MAX], hello[LINK_SIZE_HELLO];
    link_deframer rx;
    link_hello h;
    link_status st;
    int fd = open(port, O_RDWR | O_NOCTTY | O_NONBLOCK), step, state = -1;
    if (fd < 0 || tty_raw(fd, 115200)) { if (fd >= 0) close(fd); return -1; }
    link_deframer_init(&rx, link_mcu_to_host_type);
    h.version = LINK_PROTOCOL_VERSION;
    for (step = 0; step < 3; step++) {
        uint8_t seq = (uint8_t)(100 + step);
        size_t n = link_frame_build(frame, seq, types[step], hello, step ? 0 : link_put_hello(hello, &h));
        double t0 = seconds_now(), sent = 0;
        int got = 0;
        while (!got && seconds_now() - t0 < 2) {
            uint8_t b;
            size_t m;
            if (seconds_now() - sent > 0.25) { if (write(fd, frame, n) != (ssize_t)n) break; sent = seconds_now(); }
            if (read(fd, &b, 1) != 1) { sleep_ms(2); continue; }
            link_deframe_push(&rx, b);
            while (!got && (m = link_deframe_next(&rx)) != 0) {
                /* the answer to this step: IDENTIFY, the ACK of `type`, STATUS_REPLY */
                uint8_t t = rx.buf[2];
                if (step == 0) got = t == LINK_MSG_IDENTIFY;
                else if (step == 1) got = t == LINK_MSG_ACK && rx.buf[1] == (uint8_t)(seq + 1);
                else if (t == LINK_MSG_STATUS_REPLY && link_get_status(&st, rx.buf + 3, m - LINK_FRAME_MIN)) {
                    got = 1;
                    state = st.state;
                    if (out) *out = st;
                }
                link_deframe_consume(&rx);
            }
        }
        if (!got) break;
    }
    close(fd);
    return state;
}

static int second_host_sends(const char *port, uint8_t type) { return second_host_status(port, type, NULL); }

/* The host's one line when the printer stopped printing (an ABORT, a fault):
   exit 1, the layer, the last fully exposed, and the layer to continue from
   (returned; 0 if the line is not there), with --home when Z was lost. */
static unsigned check_stop_message(int status, const char *out, const char *why, int z_lost)
{
    const char *at = out ? strstr(out, "stopped printing (") : NULL, *p;
    unsigned k = 0, layer = 0, exposed = 0, lines = 0;
    for (p = out; p && (p = strstr(p, "adaslice: ")) != NULL; p++) lines++;
    CHECKF(status == 1 && lines == 1 && at && !strncmp(at + 18, why, strlen(why)), "exit %d, %u messages: %s", status, lines,
           out ? out : "");
    if (!at || !(at = strstr(at, ") at layer ")) || sscanf(at, ") at layer %u: layer %u was the last fully exposed", &layer,
                                                               &exposed) != 2) {
        CHECKF(0, "no layers in: %s", out ? out : "");
        return 0;
    }
    at = strstr(at, "--resume-from ");
    CHECKF(at && sscanf(at, "--resume-from %u", &k) == 1 && k == exposed + 1 && (strstr(at, "--home") != NULL) == z_lost &&
           (strstr(out, "Z must be homed") != NULL) == z_lost, "the way on: %s", out);
    return k;
}

/* Resumes a print the printer stopped and still knows (the same job, Z as
   `home` asks) from layer k: a layer either side is refused, naming k (exit
   2); k prints the rest, each layer once at its exact height with its light
   to the tick (from the show of layer k on). */
static void resume_a_stopped_print(child *sim, const char *log, unsigned k, int home)
{
    char port[256], wrong[16], right[16];
    cli_result r;
    sim_log l;
    print_report rep;
    snprintf(port, sizeof port, "%s", sim->line + 4);
    snprintf(wrong, sizeof wrong, "%u", k + 1);
    snprintf(right, sizeof right, "%u", k);
#define STOPPED_ARGS MODEL, "--scale", "15", "--port", port, CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", \
                     "--settle", "0.05", "--resume-from"
    r = cli_run("print", STOPPED_ARGS, wrong, NULL);
    snprintf(wrong, sizeof wrong, "resume from %u", k);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, wrong), "--resume-from %u: %d %s", k + 1, r.status, r.err);
    cli_free(&r);
    if (home) {
        r = cli_run("print", STOPPED_ARGS, right, NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "not homed") && strstr(r.err, "--home") &&
               strstr(r.err, right), "unhomed: %d %s", r.status, r.err);
        cli_free(&r);
    }
    r = home ? cli_run("print", STOPPED_ARGS, right, "--home", "--report", cli_path("report13.json"), NULL)
             : cli_run("print", STOPPED_ARGS, right, "--report", cli_path("report13.json"), NULL);
#undef STOPPED_ARGS
    CHECKF(r.status == 0, "--resume-from %u: exit %d: %s", k, r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(sim) == 0, "the simulator failed");
    if (check_case_failed()) return;
    CHECK(read_sim_log(log, &l) && read_print_report(cli_path("report13.json"), &rep));
    if (!check_case_failed()) {
        size_t from = nth_show_from_end(&l, rep.layers - k + 1);
        zsummary s;
        CHECK(rep.first == k);
        s = check_record_from(&l, &rep, from, k, 0);
        CHECKF(s.shows == rep.layers - k + 1, "%zu layers shown from layer %u of %u", s.shows, k, rep.layers);
    }
    free(l.ev);
    print_report_free(&rep);
}

/* A second host sends ABORT mid-print (the printing host held still the
   while, SIGSTOP): the printer stops, Z homed, the plan and the job kept.
   The printing host, let go, finds its frames out of step, says HELLO again
   (the same boot id), and ends with exit 1 and one line naming the layer to
   continue from: resuming there prints the rest, without --home. */
static void aborted_print_resumes(void)
{
    child sim;
    char port[256], *out;
    const char *extra[] = {CURE, NULL};
    pid_t pid;
    int status, state;
    unsigned k;
    if (!start_sim(&sim, cli_path("sim13.log"), "10")) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    pid = hand_print_in_background(port, extra, cli_path("print13.out"));
    CHECK(wait_for_exposures(cli_path("sim13.log"), 5));
    kill(pid, SIGSTOP);
    state = second_host_sends(port, LINK_MSG_ABORT);
    kill(pid, SIGCONT);
    CHECKF(state == LINK_STATE_READY, "after ABORT the printer is %s", state < 0 ? "silent" : link_state_name((unsigned)state));
    status = wait_exit(pid, 30);
    out = read_whole_text(cli_path("print13.out"));
    k = check_stop_message(status, out, "aborted", 0);
    free(out);
    CHECKF(k >= 5, "continue from layer %u", k);
    if (check_case_failed()) { child_stop(&sim); return; }
    resume_a_stopped_print(&sim, cli_path("sim13.log"), k, 0);
}

/* A step the timer cannot take on time after the 4th exposure (fw-sim
   --late-step-after-exposure 4): the printer stops dead in the peel, Z
   unhomed (STEP_LATE); the host ends with exit 1 and one line: layer 4 the
   last fully exposed, Z to be homed, --resume-from 5 --home. Without --home
   that is refused (exit 2); with it Z homes and layers 5 on print. */
static void step_late_print_resumes_with_home(void)
{
    child sim;
    const char *opts[] = {"--late-step-after-exposure", "4", NULL};
    cli_result r;
    char *both;
    unsigned k;
    if (!start_sim_with(&sim, cli_path("sim14.log"), "10", opts)) return;
    r = run_print(sim.line + 4, cli_path("report14.json"));
    both = (char *)malloc(strlen(r.out) + strlen(r.err) + 1);
    if (both) { strcpy(both, r.out); strcat(both, r.err); }
    CHECK(cli_one_message(r.err));
    k = check_stop_message(r.status, both, "a Z step could not be issued on time", 1);
    free(both);
    cli_free(&r);
    CHECKF(k == 5, "continue from layer %u", k);
    if (check_case_failed()) { child_stop(&sim); return; }
    {
        char *log = read_whole_text(cli_path("sim14.log"));
        CHECK(log && strstr(log, " late\n"));
        free(log);
    }
    resume_a_stopped_print(&sim, cli_path("sim14.log"), k, 1);
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
    if (!check_case_failed()) check_print(cli_path("sim6.log"), cli_path("report6.json"), 0, 2000);
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

/* masks.rle as its header (tests' own reading of jobdir.h's layout): the
   offset of layer k's (0-based) record, or 0 past the file. */
static size_t layer_record(const unsigned char *f, size_t n, unsigned k)
{
    size_t at = 44;
    while (k-- && at + 16 <= n) at += 16 + ((size_t)f[at + 12] | (size_t)f[at + 13] << 8 | (size_t)f[at + 14] << 16 |
                                           (size_t)f[at + 15] << 24);
    return at + 16 <= n ? at : 0;
}

/* masks.rle damaged (len bytes at `at` replaced), the manifest made to name
   its new CRC-32 so that the damage itself is what the reader meets; then
   `adaslice print DIR --port /dev/null` (or, with spec, `adaslice show DIR
   --layer 1 --screen SPEC`) must exit 1 with one line holding `says`. The
   job is put back as it was after. */
static void damaged_masks_said(const char *dir, size_t at, const void *bytes, size_t len, const char *says,
                               const char *spec)
{
    char mp[600], jp[600], crc[9];
    unsigned char *f, *g = NULL;
    char *man, *key;
    size_t n, mn;
    cli_result r;
    snprintf(mp, sizeof mp, "%s/masks.rle", dir);
    snprintf(jp, sizeof jp, "%s/manifest.json", dir);
    f = read_whole_file(mp, &n);
    man = (char *)read_whole_file(jp, &mn);
    key = man ? strstr(man, "\"masks_rle_crc32\": \"") : NULL;
    CHECK(f && key && at + len <= n);
    if (f && key && at + len <= n && (g = (unsigned char *)malloc(n)) != NULL) {
        char old[8];
        memcpy(old, key + 20, 8);
        memcpy(g, f, n);
        memcpy(g + at, bytes, len);
        snprintf(crc, sizeof crc, "%08x", (unsigned)adaslice_crc32(0, g, n));
        memcpy(key + 20, crc, 8);
        cli_write_bytes(mp, g, n);
        cli_write_bytes(jp, man, mn);
        r = spec ? cli_run("show", dir, "--layer", "1", "--screen", spec, "--seconds", "0.001", NULL)
                 : cli_run("print", dir, "--port", "/dev/null", NULL);
        CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, says), "%s, byte %zu damaged: exit %d: %s (want: %s)",
               spec ? "show" : "print", at, r.status, r.err, says);
        cli_free(&r);
        memcpy(key + 20, old, 8);
        cli_write_bytes(mp, f, n);
        cli_write_bytes(jp, man, mn);
    }
    free(g);
    free(f);
    free(man);
}

/* A damaged job is refused whole before the print begins, naming masks.rle's
   byte: a layer's code or CRC half way up (the printer would refuse that
   layer and leave half a part on the plate), a header a printer could not
   take or slice would not write (a settle of 49 days hung the print), a
   layer of no thickness, a directory for the file; and show checks a job's
   size and pitch against the screen before it makes an image of that size
   (a header of 16777215 x 16777215 px asked for 256 TB). Reaching the
   refusal, not the port (/dev/null), shows it comes first. */
static void damaged_job_is_refused_before_the_print(void)
{
    char job[300], spec[600], mp[600], want[200];
    static const unsigned char zero[4] = {0, 0, 0, 0}, ones[4] = {0xff, 0xff, 0xff, 0xff};
    static const unsigned char huge_8bit[9] = {0xff, 0xff, 0xff, 0, 0xff, 0xff, 0xff, 0, 8};
    unsigned char *f, crc_flipped, short_code = 0x80;
    unsigned layers, k;
    size_t n, mid, last;
    cli_result r;
    snprintf(job, sizeof job, "%s/damaged", cli_dir);
    snprintf(spec, sizeof spec, "file:%s/damaged-fb,240x200,32", cli_dir);
    snprintf(mp, sizeof mp, "%s/masks.rle", job);
    r = cli_run("slice", MODEL, "--scale", "15", "--pixels", "240x200", "--pitch", "0.1", "--uniform", "0.5", "-o", job,
                CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05", NULL);
    CHECKF(r.status == 0, "slice: %s", r.err);
    cli_free(&r);
    f = read_whole_file(mp, &n);
    CHECK(f != NULL && n > 64);
    if (!f || n <= 64) { free(f); return; }
    layers = (unsigned)(f[20] | f[21] << 8);
    k = layers / 2;
    mid = layer_record(f, n, k);
    last = layer_record(f, n, layers - 1);
    CHECKF(layers > 4 && mid > 44 && last > mid, "%u layers, layer %u at %zu, the last at %zu", layers, k + 1, mid, last);
    if (layers > 4 && mid > 44 && last > mid) {
        /* a row of no runs, half way up */
        snprintf(want, sizeof want, "masks.rle: byte %zu: layer %u's mask code is damaged", mid + 16, k + 1);
        damaged_masks_said(job, mid + 16, zero, 1, want, NULL);
        crc_flipped = (unsigned char)(f[mid + 8] ^ 1);
        snprintf(want, sizeof want, "masks.rle: byte %zu: layer %u's mask decodes to CRC-32", mid + 8, k + 1);
        damaged_masks_said(job, mid + 8, &crc_flipped, 1, want, NULL);
        /* the next layer damaged too (the other thread's): the first is named */
        {
            size_t next = layer_record(f, n, k + 1);
            f[next + 8] ^= 1;
            cli_write_bytes(mp, f, n);
            f[next + 8] ^= 1;
            damaged_masks_said(job, mid + 8, &crc_flipped, 1, want, NULL);
            cli_write_bytes(mp, f, n);
        }
        snprintf(want, sizeof want, "masks.rle: byte %zu: layer %u is 0 bins thick", mid, k + 1);
        damaged_masks_said(job, mid, zero, 4, want, NULL);
        /* the last layer's last byte made a number that goes on: the code ends inside it */
        snprintf(want, sizeof want, "layer %u's mask code", layers);
        damaged_masks_said(job, n - 1, &short_code, 1, want, NULL);
        damaged_masks_said(job, 8, zero, 4, "masks.rle: byte 8: masks of 0 x 200 px", NULL);
        damaged_masks_said(job, 16, "\2", 1, "masks.rle: byte 16: masks of 2 bits", NULL);
        damaged_masks_said(job, 40, ones, 4, "masks.rle: byte 40: a settle of 4294967295 ms", NULL);
        damaged_masks_said(job, 28, ones, 4, "masks.rle: byte 28: a peel of 4294967295 nm", spec);
        /* a peel speed of 0 is the firmware's top speed, which slice never writes */
        damaged_masks_said(job, 32, zero, 4, "masks.rle: byte 28: a peel of", NULL);
        damaged_masks_said(job, 8, huge_8bit, sizeof huge_8bit, "the job's masks are 16777215 x 16777215 px; the screen",
                           spec);
    }
    free(f);
    /* the manifest's pitch written without spaces is still the job's */
    {
        char jp[600], *man, *at;
        size_t mn;
        snprintf(jp, sizeof jp, "%s/manifest.json", job);
        man = (char *)read_whole_file(jp, &mn);
        at = man ? strstr(man, "\"pitch_mm\": [0.1, 0.1]") : NULL;
        CHECK(at != NULL);
        if (at) {
            memcpy(at, "\"pitch_mm\":[0.1,0.1]  ", 22);
            cli_write_bytes(jp, man, mn);
            r = cli_run("show", job, "--layer", "1", "--screen", spec, "--seconds", "0.001", "--screen-pitch", "50", NULL);
            CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "pixels are 100 x 100 um") &&
                       strstr(r.err, "are 50 um"),
                   "%d %s", r.status, r.err);
            cli_free(&r);
        }
        free(man);
    }
    /* a directory where masks.rle should be */
    CHECK(remove(mp) == 0 && mkdir(mp, 0755) == 0);
    r = cli_run("print", job, "--port", "/dev/null", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "masks.rle: Is a directory"), "%d %s", r.status, r.err);
    cli_free(&r);
    rmdir(mp);
}

/* --report to a symlink (its target written, the link kept), a FIFO (a
   reader gets the record, the FIFO stays), /dev/null (stays a device) and
   "-" (standard output) (issue 26). */
static void report_goes_through_links_fifos_devices_and_stdout(void)
{
    char job[300], real[300], link[300], fifo[300], got[300], null_dev[300];
    const char *targets[] = {link, fifo, "/dev/null", "-"};
    cli_result r;
    struct stat null_st;
    int i;
    snprintf(job, sizeof job, "%s/reportjob", cli_dir); /* cli_path keeps only eight */
    snprintf(real, sizeof real, "%s/report-real.json", cli_dir);
    snprintf(link, sizeof link, "%s/report-link.json", cli_dir);
    snprintf(fifo, sizeof fifo, "%s/report-fifo.json", cli_dir);
    snprintf(got, sizeof got, "%s/report-got.json", cli_dir);
    snprintf(null_dev, sizeof null_dev, "%s/report-null", cli_dir);
    /* as root, a null device of the test's own: a regression would replace the machine's */
    if (geteuid() == 0)
        targets[2] = stat("/dev/null", &null_st) == 0 && mknod(null_dev, S_IFCHR | 0666, null_st.st_rdev) == 0 ? null_dev
                                                                                                               : NULL;
    r = cli_run("slice", MODEL, "--scale", "15", "--pixels", "240x200", "--pitch", "0.1", "--uniform", "0.5", "-o", job,
                CURE, "--peel", "2", "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05", NULL);
    CHECKF(r.status == 0, "slice: %s", r.err);
    cli_free(&r);
    cli_write(real, "old");
    CHECK(symlink("report-real.json", link) == 0);
    CHECK(mkfifo(fifo, 0644) == 0);
    for (i = 0; i < 4 && !check_case_failed(); i++) {
        child sim;
        pid_t reader = -1;
        struct stat st;
        unsigned char *text;
        size_t size = 0;
        if (!targets[i]) continue; /* mknod refused */
        if (!start_sim(&sim, cli_path("simreport.log"), SIM_SPEED)) return;
        if (i == 1) {
            fflush(NULL);
            if ((reader = fork()) == 0) {
                char buf[4096];
                ssize_t n;
                int in, out;
                alarm(60);
                in = open(fifo, O_RDONLY);
                out = open(got, O_WRONLY | O_CREAT | O_TRUNC, 0644);
                if (in < 0 || out < 0) _exit(1);
                while ((n = read(in, buf, sizeof buf)) > 0)
                    if (write(out, buf, (size_t)n) != n) _exit(1);
                _exit(n < 0);
            }
        }
        r = cli_run("print", job, "--port", sim.line + 4, "--report", targets[i], NULL);
        CHECKF(r.status == 0, "--report %s: exit %d: %s", targets[i], r.status, r.err);
        CHECKF(child_stop(&sim) == 0, "the simulator failed");
        if (reader > 0) {
            int fd = open(fifo, O_WRONLY | O_NONBLOCK), st2 = 0; /* a reader still waiting gets its end */
            if (fd >= 0) close(fd);
            CHECK(waitpid(reader, &st2, 0) == reader && WIFEXITED(st2) && WEXITSTATUS(st2) == 0);
        }
        if (i == 0) CHECKF(lstat(link, &st) == 0 && S_ISLNK(st.st_mode), "the symlink was replaced");
        if (i == 1) CHECKF(lstat(fifo, &st) == 0 && S_ISFIFO(st.st_mode), "the FIFO was replaced");
        if (i == 2) CHECKF(stat(targets[2], &st) == 0 && S_ISCHR(st.st_mode), "%s is no longer a device", targets[2]);
        text = i == 2 ? NULL : read_whole_file(i == 0 ? real : i == 1 ? got : cli_path("stdout"), &size);
        if (i != 2) CHECKF(text && size > 1 && (i == 3 || text[0] == '{') && strstr((char *)text, "\"layers\""), "--report %s: no record there",
                           targets[i]);
        free(text);
        cli_free(&r);
    }
    remove(link);
    remove(real);
    remove(fifo);
    remove(got);
    if (geteuid() == 0) remove(null_dev);
    cli_remove_all(job);
}

/* A job sliced for other pixels than the printer's is refused before
   anything moves, naming both pitches and the scale it would print at: 0.1 mm
   pixels on 0.05 mm ones print half size, the 2k-5.5's 47.25 um ones 5.8 %
   too large. The printer's log shows no step and no light. */
static void other_pitch_is_refused_first(void)
{
    static const char *const fine[] = {"--pitch-um", "50", NULL};
    static const struct { const char *pitch, *says[3]; } jobs[] = {
        {"0.1", {"sliced for pixels of 0.1 x 0.1 mm", "shows 0.05 mm pixels", "at 50 % of its size"}},
        {"0.04725", {"sliced for pixels of 0.04725 x 0.04725 mm", "shows 0.05 mm pixels", "at 105.8 % of its size"}},
        {"0.1,0.05", {"sliced for pixels of 0.1 x 0.05 mm", "shows 0.05 mm pixels", "at 50 % across and 100 % down"}},
    };
    child sim;
    cli_result r;
    char *log;
    size_t c;
    if (!start_sim_with(&sim, cli_path("pitch.log"), SIM_SPEED, fine)) return;
    for (c = 0; c < sizeof jobs / sizeof jobs[0]; c++) {
        r = cli_run("slice", MODEL, "--scale", "10", "--pixels", "240x200", "--pitch", jobs[c].pitch, "-o",
                    cli_path("pitch_job"), CURE, NULL);
        CHECKF(r.status == 0, "slice --pitch %s: %s", jobs[c].pitch, r.err);
        cli_free(&r);
        r = cli_run("print", cli_path("pitch_job"), "--port", sim.line + 4, NULL);
        CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, jobs[c].says[0]) && strstr(r.err, jobs[c].says[1]) &&
               strstr(r.err, jobs[c].says[2]) && strstr(r.err, "--pitch 0.05"), "--pitch %s: %d %s", jobs[c].pitch,
               r.status, r.err);
        cli_free(&r);
    }
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    {
        /* a manifest that names no pitch is no job to print */
        char *text = read_whole_text(cli_path("pitch_job/manifest.json")), *at = text ? strstr(text, "\"pitch_mm\"") : NULL;
        if (at) memcpy(at + 7, "xx", 2);
        if (text) cli_write(cli_path("pitch_job/manifest.json"), text);
        free(text);
        r = cli_run("print", cli_path("pitch_job"), "--port", "/dev/null", NULL);
        CHECKF(at && r.status == 1 && cli_one_message(r.err) && strstr(r.err, "names no pixel pitch"), "%d %s", r.status,
               r.err);
        cli_free(&r);
    }
    log = read_whole_text(cli_path("pitch.log"));
    CHECKF(log && !strstr(log, " step ") && !strstr(log, " uv 1"), "the printer moved or lit: %.200s", log ? log : "");
    free(log);
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

/* The printer's light limit (IDENTIFY's max_exposure_ms, 300 s here): a job
   asking for longer is refused before anything moves, naming the layer and
   both times; the printer's log shows no step and no light. */
static void too_long_exposure_is_refused_first(void)
{
    child sim;
    cli_result r;
    char *log;
    if (!start_sim(&sim, cli_path("long.log"), SIM_SPEED)) return;
    r = cli_run("print", MODEL, "--scale", "15", "--port", sim.line + 4, "--exposure", "2", "--penetration", "0.1",
                "--bottom-layers", "2", "--bottom-exposure", "300.5", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "layer 1's exposure is 300.500 s") &&
           strstr(r.err, "at most 300.000 s"), "%d %s", r.status, r.err);
    cli_free(&r);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    log = read_whole_text(cli_path("long.log"));
    CHECKF(log && !strstr(log, " step ") && !strstr(log, " uv 1"), "the printer moved or lit: %.200s", log ? log : "");
    free(log);
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
    if (!check_case_failed()) check_print(cli_path("sim7.log"), cli_path("report7.json"), 0, 500);
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
    if (access(argv[sizeof argv / sizeof argv[0] - 2], R_OK) != 0 || /* QEMU names its pty before it fails to load */
        !child_start(&qemu, argv, "char device redirected to ", 20)) {
        CHECK(!"qemu-system-arm did not start with build/fw-mps2-busy.elf (make check builds it; apt-get install qemu-system-arm)");
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

/* The short print under QEMU with its monitor on a socket; about 2 s into
   the printing, `command` goes to the monitor. The host's exit status and
   the seconds from the command to the host's exit; its output (to free),
   NULL if QEMU did not start. */
static char *qemu_print_then(const char *command, const char *out_name, int *status, double *took)
{
    child qemu;
    char monitor[100], mon_opt[140], port[64] = "", *at, *out = NULL;
    const char *extra[] = {"--exposure", "0.3", "--penetration", "0.1", "--bottom-layers", "1", "--bottom-exposure", "0.5", NULL};
    char *argv[] = {(char *)"/usr/bin/timeout", (char *)"300", (char *)"qemu-system-arm", (char *)"-M", (char *)"mps2-an385",
                    (char *)"-nographic", (char *)"-monitor", mon_opt, (char *)"-serial", (char *)"pty",
                    (char *)"-semihosting-config", (char *)"enable=on,target=native", (char *)"-icount",
                    (char *)"shift=5,align=off,sleep=off", (char *)"-kernel", (char *)"build/fw-mps2-busy.elf", NULL};
    const char *base[] = {"print", MODEL, "--scale", "5", "--port", port, "--peel", "0.5", "--peel-speed", "10",
                          "--return-speed", "10", "--settle", "0.02", NULL};
    char *pargv[40];
    struct sockaddr_un addr;
    int i, n = 0, fd;
    double sent_at = 0;
    pid_t pid;
    *status = -1;
    *took = 0;
    /* a socket's path is at most 107 bytes */
    CHECKF(snprintf(monitor, sizeof monitor, "%s", cli_path("qemu.monitor")) < (int)sizeof monitor, "%s: too long", cli_path("qemu.monitor"));
    snprintf(mon_opt, sizeof mon_opt, "unix:%s,server=on,wait=off", monitor);
    if (access(argv[sizeof argv / sizeof argv[0] - 2], R_OK) != 0 || /* QEMU names its pty before it fails to load */
        !child_start(&qemu, argv, "char device redirected to ", 20)) {
        CHECK(!"qemu-system-arm did not start with build/fw-mps2-busy.elf");
        child_stop(&qemu);
        return NULL;
    }
    at = strstr(qemu.line, "/dev/");
    for (i = 0; at && at[i] && at[i] != ' ' && i < 63; i++) port[i] = at[i];
    port[i] = 0;
    for (i = 0; base[i]; i++) pargv[n++] = (char *)base[i];
    for (i = 0; extra[i]; i++) pargv[n++] = (char *)extra[i];
    pargv[n] = NULL;
    pid = print_in_background(pargv, cli_path(out_name));
    /* into the print: planned, homed, printing, a few of its 21 layers */
    for (i = 0; i < 3000; i++) {
        out = read_whole_text(cli_path(out_name));
        if (out && strstr(out, "printing layers 1 to ")) break;
        free(out);
        out = NULL;
        sleep_ms(20);
    }
    CHECKF(out != NULL, "the print on QEMU did not get to printing");
    free(out);
    sleep_ms(2000);
    fd = socket(AF_UNIX, SOCK_STREAM, 0);
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    snprintf(addr.sun_path, sizeof addr.sun_path, "%s", monitor);
    CHECKF(fd >= 0 && connect(fd, (struct sockaddr *)&addr, sizeof addr) == 0, "QEMU's monitor %s: %s", monitor, strerror(errno));
    if (fd >= 0) {
        size_t len = strlen(command);
        CHECK(write(fd, command, len) == (ssize_t)len && write(fd, "\n", 1) == 1);
        sent_at = seconds_now();
    }
    *status = wait_exit(pid, 60);
    *took = seconds_now() - sent_at;
    if (fd >= 0) close(fd);
    child_stop(&qemu);
    return read_whole_text(cli_path(out_name));
}

/* QEMU's system_reset mid-print, from its monitor: the image starts again
   with another boot id (a counter in RAM that startup does not clear), and
   the host stops within 5 s with exit 4 and the restart message. */
static void mcu_reset_mid_print_under_qemu(void)
{
    int status;
    unsigned old_id = 0, new_id = 0, layer;
    double took;
    char *out = qemu_print_then("system_reset", "print10.out", &status, &took);
    if (!out) return;
    CHECKF(status == 4 && took < 5, "after system_reset: exit %d in %.2f s: %s", status, took, out);
    layer = restart_message(out, &old_id, &new_id);
    CHECKF(layer >= 1 && old_id != new_id && old_id && new_id, "no restart message (boot id %u -> %u, layer %u): %s", old_id,
           new_id, layer, out);
    printf("    system_reset: exit %d %.2f s after the command\n", status, took);
    free(out);
}

/* QEMU's stop mid-print: the CPU halts (no byte read or sent, no timer), as
   a board that hangs with its watchdog off or loses power to its MCU; the
   host stops within 5 s with exit 5, naming the layer to resume from. */
static void mcu_halted_mid_print_under_qemu(void)
{
    int status, layer;
    double took;
    char *out = qemu_print_then("stop", "print15.out", &status, &took);
    if (!out) return;
    layer = check_lost_message(status, took, out, "was the last fully exposed");
    CHECKF(layer >= 1, "resume from layer %d: %s", layer, out);
    printf("    stop: exit %d %.2f s after the command\n", status, took);
    free(out);
}

/* printrun's printcore sends a G-code file to the simulator in G-code mode:
   every line is acknowledged, and the log passes tests/zcheck.h's check:
   the one exposure at its line's Z for its G4 to the tick, the light on
   only while Z stands still, the steps the heights the lines move. At
   --speed 1, so that printcore has the dwell's 300 ms of wall time to send
   the G4 after M106's ok however loaded the machine. */
static void printcore_drives_gcode_mode(void)
{
    child sim, pc;
    char *text, *argv[6];
    int sent = 0, oks = 0, status;
    const char *line;
    sim_log l;
    zexpect e;
    zsummary s;
    static const uint32_t top_um[1] = {5000}, exposure_ms[1] = {300};
    static const uint64_t path_nm[3] = {5000000, 6500000, 10000000};
    cli_write(cli_path("job.gcode"), "; a layer by hand\nG28\nG90\nG1 Z5 F300\nG4 P100\nM106 S255\nG4 P300\nM107\n"
                                     "G91\nG1 Z1.5 F600 ; relative\nG90\nM114\nG1 Z10\nM400\nM18\n");
    {
        char *sargv[] = {(char *)SIM_BIN, (char *)"--log", (char *)cli_path("sim4.log"), (char *)"--speed", (char *)"1",
                         (char *)"--z-start", (char *)"6", NULL};
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
        CHECKF(strncmp(line, "RECV: echo:Exposure ran over", 28), "harness failure, not the firmware's: printcore's G4 came after "
               "the dwell: %.60s", line);
    }
    CHECKF(sent == 14 && oks >= sent, "%d lines sent, %d acknowledged", sent, oks);
    CHECK(text && strstr(text, "Z:6.500") && strstr(text, "Z_move_comp"));
    free(text);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    CHECK(read_sim_log(cli_path("sim4.log"), &l));
    memset(&e, 0, sizeof e);
    e.tick_hz = l.tick_hz;
    e.steps_per_mm = (uint32_t)l.steps_per_mm;
    e.max_speed = (uint32_t)l.max_speed;
    e.accel = (uint32_t)l.accel;
    e.start_position = l.start_steps;
    e.layers = e.first = 1;
    e.top_bins = top_um;
    e.bin_nm = 1000;
    e.exposure_ms = exposure_ms;
    e.path_nm = path_nm;
    e.path_len = 3;
    s = zcheck_record(l.ev, l.count, &e);
    CHECKF(s.moves >= 3 && s.ramp_windows, "%zu moves from rest and %zu ramp windows checked", s.moves, s.ramp_windows);
    free(l.ev);
}

/* One G-code line to the port `fd` and its replies up to "ok" (10 s at
   most), appended to `got`; 1 when the ok came. */
static int gcode_exchange(int fd, const char *line, char *got, size_t size)
{
    size_t len = strlen(got);
    double t0 = seconds_now();
    if (write(fd, line, strlen(line)) != (ssize_t)strlen(line)) return 0;
    while (seconds_now() - t0 < 10) {
        struct pollfd p = {fd, POLLIN, 0};
        ssize_t n;
        if (poll(&p, 1, 100) <= 0) continue;
        n = read(fd, got + len, size - 1 - len);
        if (n <= 0) continue;
        len += (size_t)n;
        got[len] = 0;
        if (strstr(got, "ok\n") || len + 1 >= size) return strstr(got, "ok\n") != NULL;
    }
    return 0;
}

/* G-code mode's over-exposure, as the pins show it: M106 S255, then a G4
   P100 that comes 400 ms (wall clock, the sim at --speed 1) after M106,
   later than its dwell's end. The light stays on until the G4 puts it out,
   the firmware says by how much it ran over, and the log shows the light
   on for the dwell and that much more, to the tick the off was processed
   (not the dwell's end the core asked for). */
static void late_g4_shows_in_the_log(void)
{
    char *argv[] = {(char *)SIM_BIN, (char *)"--log", (char *)cli_path("late_g4.log"), (char *)"--speed", (char *)"1",
                    (char *)"--z-start", (char *)"1", NULL};
    char got[512] = "";
    const char *over;
    child sim;
    sim_log l;
    size_t k, exposures = 0;
    uint64_t on = 0, lit = 0;
    double ran_over_ms = -1;
    int fd, ok;
    if (!child_start(&sim, argv, "pty ", 10)) { CHECK(!"the simulator did not start"); child_stop(&sim); return; }
    fd = open(sim.line + 4, O_RDWR | O_NOCTTY | O_NONBLOCK);
    ok = fd >= 0 && tty_raw(fd, 115200) == 0;
    ok = ok && gcode_exchange(fd, "G28\n", got, sizeof got) && gcode_exchange(fd, "M106 S255\n", got, sizeof got);
    CHECKF(ok, "G28 and M106 on the simulator: %.200s", got);
    got[0] = 0;
    sleep_ms(400);
    ok = ok && gcode_exchange(fd, "G4 P100\n", got, sizeof got);
    if ((over = strstr(got, "Exposure ran over: G4 came "))) ran_over_ms = strtod(over + 27, NULL);
    CHECKF(ok && ran_over_ms >= 250, "G4 P100 400 ms after M106: %.200s", got);
    got[0] = 0;
    CHECK(gcode_exchange(fd, "M107\n", got, sizeof got));
    if (fd >= 0) close(fd);
    CHECKF(child_stop(&sim) == 0, "the simulator failed");
    CHECK(read_sim_log(cli_path("late_g4.log"), &l));
    for (k = 0; k < l.count; k++)
        if (l.ev[k].kind == ZEV_UV && l.ev[k].value) on = l.ev[k].when;
        else if (l.ev[k].kind == ZEV_UV) { lit = l.ev[k].when - on; exposures++; }
    /* the message's figure is the same tick's, to its microsecond */
    CHECKF(exposures == 1 && ran_over_ms >= 0 && fabs((double)lit / l.tick_hz * 1e3 - (100 + ran_over_ms)) < 0.002,
           "%zu exposures; the log has the light on %.4f ms, the firmware says 100 ms and %.3f ms over",
           exposures, (double)lit / (l.tick_hz ? l.tick_hz : 1) * 1e3, ran_over_ms);
    free(l.ev);
}

/* The loop hangs as an exposure begins (fw-sim --hang-at-exposure N): the UV
   timer still ends the exposure at its tick, and the watchdog restarts the
   MCU within its period with the light off and Z still. Exposure 1 (a bottom
   layer, 0.5 s) outlasts the 250 ms watchdog, so the restart puts it out;
   exposure 3 (0.1 s) ends by its timer first. */
static void hung_loop_keeps_light_and_watchdog(void)
{
    static const char *const hang_at[2] = {"1", "3"};
    const uint64_t hz = 10000000u, period = hz / 4u;
    int c;
    for (c = 0; c < 2; c++) {
        char log_path[256], port[256], *text = NULL, *line, *save = NULL;
        char *argv[] = {(char *)SIM_BIN, (char *)"--log", log_path, (char *)"--speed", (char *)"10", (char *)"--display",
                        (char *)"240x200", (char *)"--pitch-um", (char *)"100", (char *)"--watchdog-ms", (char *)"250",
                        (char *)"--hang-at-exposure", (char *)hang_at[c], NULL};
        char *args[] = {(char *)"print", (char *)MODEL, (char *)"--scale", (char *)"15", (char *)"--port", port,
                        /* a deep penetration: every layer's exposure is 0.1 s to the ms */
                        (char *)"--exposure", (char *)"0.1", (char *)"--penetration", (char *)"1000",
                        (char *)"--bottom-layers", (char *)"2", (char *)"--bottom-exposure", (char *)"0.5",
                        (char *)"--settle", (char *)"0.05", (char *)"--give-up", (char *)"2", NULL};
        unsigned long long uv_on = 0, hang = 0, uv_off = 0, reset = 0, t;
        int i, moved = 0, lit_again = 0, st;
        child sim;
        pid_t host;
        snprintf(log_path, sizeof log_path, "%s", cli_path(c ? "hang3.log" : "hang1.log"));
        if (!child_start(&sim, argv, "pty ", 10)) { CHECK(!"the simulator did not start"); child_stop(&sim); return; }
        snprintf(port, sizeof port, "%s", sim.line + 4);
        host = print_in_background(args, cli_path("hang.out"));
        for (i = 0; i < 1500; i++) {
            free(text);
            text = read_whole_text(log_path);
            if (text && strstr(text, " reset watchdog")) break;
            { struct timespec ts = {0, 20000000}; nanosleep(&ts, NULL); }
        }
        kill(host, SIGKILL);
        waitpid(host, &st, 0);
        CHECKF(child_stop(&sim) == 0, "the simulator failed");
        free(text);
        text = read_whole_text(log_path);
        for (line = text ? strtok_r(text, "\n", &save) : NULL; line; line = strtok_r(NULL, "\n", &save)) {
            char what[16] = "", arg[32] = "";
            if (line[0] == '#' || sscanf(line, "%llu %15s %31s", &t, what, arg) < 2) continue;
            if (!strcmp(what, "uv") && arg[0] == '1') { if (hang) lit_again = 1; else uv_on = t; }
            else if (!strcmp(what, "uv") && hang && !uv_off) uv_off = t;
            else if (!strcmp(what, "hang")) hang = t;
            else if (!strcmp(what, "reset") && !reset) reset = t;
            else if (!strcmp(what, "step") && hang && !reset) moved = 1;
        }
        free(text);
        CHECKF(hang && reset && uv_off, "exposure %s: hang at %llu, reset at %llu, UV off at %llu", hang_at[c], hang,
               reset, uv_off);
        if (check_case_failed()) return;
        /* the watchdog was last refreshed as the hanging pass began */
        CHECKF(reset > hang && reset - hang <= period, "the watchdog restarted the MCU %llu ticks after the hang",
               reset - hang);
        if (c == 0) CHECKF(uv_off == reset, "exposure 1: UV off at %llu, the restart at %llu", uv_off, reset);
        else CHECKF(uv_off == uv_on + hz / 10u, "exposure 3: UV on at %llu, off at %llu (0.1 s is %llu ticks)", uv_on,
                    uv_off, (unsigned long long)(hz / 10u));
        CHECKF(!moved && !lit_again, "while hung: %s%s", moved ? "Z moved " : "", lit_again ? "UV on again" : "");
    }
}

void test_print(void)
{
    if (!cli_begin("adaslice-print")) { CHECK(!"no temporary directory"); return; }
    RUN(full_print_on_the_simulator);
    RUN(print_through_a_faulty_line);
    RUN(print_survives_a_lost_link);
    RUN(deaf_host_gives_up_after_the_printer_paused);
    RUN(thousand_layers_on_the_simulator);
    RUN(ctrl_c_pauses_and_resume_finishes);
    RUN(abort_abandons_a_paused_print);
    RUN(host_killed_mid_exposure_resumes_in_place);
    RUN(mcu_reset_mid_print_on_the_simulator);
    RUN(mcu_reset_mid_exposure_owes_only_the_rest);
    RUN(unplugged_port_ends_as_a_lost_printer);
    RUN(mcu_halted_mid_exposure_on_the_simulator);
    RUN(mcu_halted_while_homing_or_planning);
    RUN(aborted_print_resumes);
    RUN(step_late_print_resumes_with_home);
    RUN(print_a_sliced_job);
    RUN(damaged_job_is_refused_before_the_print);
    RUN(report_goes_through_links_fifos_devices_and_stdout);
    RUN(other_pitch_is_refused_first);
    RUN(bad_ports_are_named);
    RUN(silent_port_is_named);
    RUN(too_long_exposure_is_refused_first);
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-busy.elf (arm-none-eabi-gcc)", short_print_under_qemu);
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-busy.elf (arm-none-eabi-gcc)", mcu_reset_mid_print_under_qemu);
    RUN_NEEDING("qemu-system-arm and build/fw-mps2-busy.elf (arm-none-eabi-gcc)", mcu_halted_mid_print_under_qemu);
    RUN_NEEDING("printcore (Debian printrun)", printcore_drives_gcode_mode);
    RUN(late_g4_shows_in_the_log);
    RUN(hung_loop_keeps_light_and_watchdog);
    cli_end();
}
