/* The RAMPS 1.4 / ATmega2560 image (build/fw-ramps-test.elf) under simavr
   through tests/avr_run.c (build/avr-run), checked from its pin edges, which
   are cycle-exact (the log's cycle / 8 is the firmware's 2 MHz tick):
     - G-code mode: a 100-layer print as NanoDLP drives one (each move
       waited for with Z_move_comp, the light on for a G4 dwell) and a
       200-layer file printed by printrun's printcore: every step within
       10 us of the tick motion.c's closed form gives it (a host fw_axis on
       the board's config, the real firmware/motion.c, replays each move
       from its first step), no interval under the speed limit, the step
       count the moves' heights x steps/mm, the light never on while Z
       moves, no step refused as late, every exposure its G4 dwell to
       the tick (the dwell after M106 counts from M106 and Timer4 ends it,
       so the host's round trips between the lines add nothing), and every
       loop pass shorter than PASS_MAX (below: the time the step queue
       covers at the top speed, less its margin), with every 50th layer's
       peel at the top speed;
     - a binary-protocol print by the host tool (adaslice print), masks
       streaming while Z moves: the same step checks, and tests/zcheck.h's
       (each exposure at its layer's height, exactly its exposure in ticks,
       no light while Z moves, acceleration and speed within limits), the
       peels at the top speed; every loop pass, its interrupts included,
       shorter than PASS_MAX, while Z moves and while it is still;
     - the watchdog: the main loop made to hang while the light is on; the
       MCU resets within the watchdog period, which switches the light off,
       and it answers again afterwards. */
#define _XOPEN_SOURCE 700
#include "check.h"
#include "cli_run.h"
#include "zcheck.h"
#include "print_report.h"
#include "avr_passes.h"
#include "../firmware/motion.h"
#include "../firmware/ports/ramps/board.h"
#include "../link/tty.h"
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define AVR_RUN "build/avr-run"
#define AVR_ELF "build/fw-ramps-test.elf"
#define CYCLES_PER_TICK BOARD_TICK_DIV
#define LATE_MAX_CYCLES (BOARD_CPU_HZ / 100000u) /* 10 us */
#define STEP_CYCLES ((unsigned long)(BOARD_CPU_HZ / BOARD_MAX_STEPS_S)) /* the shortest step interval */
/* The step queue never runs dry: the loop refills it once REFILL_GAP steps
   have gone out (FW_STEP_FILL, at most half the queue), and a pass that
   computes no steps (a frame, a piece of G-code or of the print, a slice
   of a mask) begins with more than FW_STEP_QUEUE - REFILL_GAP of them
   (fw.h, Bounded work a pass), so the steps queued when a pass begins are
   due over at least that many intervals at the top speed. Every
   pass, its interrupts included, must end within seven eighths of that:
   the margin (a step interval at the top speed) is for the pass after the
   longest one, which refills the queue while it still drains, and for
   work still to come to a pass. The longest are a move's first steps
   (its shaping, and roots searched from afar), while the queue is still
   empty and its first step a step lead away. */
#define REFILL_GAP (FW_STEP_FILL < FW_STEP_QUEUE / 2u ? FW_STEP_FILL : FW_STEP_QUEUE / 2u)
#define COVER_CYCLES ((unsigned long)(FW_STEP_QUEUE - REFILL_GAP) * STEP_CYCLES)
#define PASS_MAX (COVER_CYCLES * 7u / 8u)

typedef struct avr_child { pid_t pid; int out, tty; char pty[256]; } avr_child;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* avr-run with `extra` options, its log at `log`; the pty opened raw. */
static int avr_start(avr_child *c, const char *log, const char *const *extra)
{
    char *argv[24], line[256];
    int fds[2], n = 0;
    size_t len = 0;
    double t0 = now_s();
    memset(c, 0, sizeof *c);
    argv[n++] = (char *)AVR_RUN;
    argv[n++] = (char *)"--log";
    argv[n++] = (char *)log;
    while (extra && *extra && n < 20) argv[n++] = (char *)*extra++;
    argv[n++] = (char *)AVR_ELF;
    argv[n] = NULL;
    if (pipe(fds) != 0) return 0;
    fflush(NULL);
    c->pid = fork();
    if (c->pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]);
        execv(argv[0], argv);
        _exit(127);
    }
    close(fds[1]);
    c->out = fds[0];
    while (now_s() - t0 < 10) {
        struct pollfd p = {c->out, POLLIN, 0};
        char ch;
        if (poll(&p, 1, 100) <= 0) continue;
        if (read(c->out, &ch, 1) != 1) break;
        if (ch != '\n') { if (len + 1 < sizeof line) line[len++] = ch; continue; }
        line[len] = 0;
        len = 0;
        if (!strncmp(line, "pty ", 4)) {
            snprintf(c->pty, sizeof c->pty, "%s", line + 4);
            c->tty = open(c->pty, O_RDWR | O_NOCTTY | O_NONBLOCK);
            return c->tty >= 0 && tty_raw(c->tty, 0) == 0;
        }
    }
    return 0;
}

/* SIGTERM; avr-run's exit status (-1 if it did not exit). */
static int avr_stop(avr_child *c)
{
    int st, i;
    if (c->tty > 0) close(c->tty);
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGTERM);
    for (i = 0; i < 250; i++) {
        struct timespec ts = {0, 20000000};
        if (waitpid(c->pid, &st, WNOHANG) == c->pid) { close(c->out); return WIFEXITED(st) ? WEXITSTATUS(st) : -1; }
        nanosleep(&ts, NULL);
    }
    kill(c->pid, SIGKILL);
    waitpid(c->pid, &st, 0);
    close(c->out);
    return -1;
}

/* Sends a G-code line and reads replies until `until` is seen (or
   `seconds` pass); 1 when seen. Replies are appended to `got`. */
static int gline(avr_child *c, const char *cmd, const char *until, double seconds, char *got, size_t got_size)
{
    char buf[512];
    size_t len = 0;
    double t0 = now_s();
    buf[0] = 0;
    if (cmd) {
        char l[128];
        int n = snprintf(l, sizeof l, "%s\n", cmd);
        if (write(c->tty, l, (size_t)n) != n) return 0;
    }
    while (now_s() - t0 < seconds) {
        struct pollfd p = {c->tty, POLLIN, 0};
        ssize_t n;
        if (poll(&p, 1, 50) <= 0) continue;
        n = read(c->tty, buf + len, sizeof buf - 1 - len);
        if (n <= 0) continue;
        len += (size_t)n;
        buf[len] = 0;
        if (strstr(buf, until)) {
            if (got) strncat(got, buf, got_size - strlen(got) - 1);
            return 1;
        }
        if (len > sizeof buf / 2) { memmove(buf, buf + len / 2, len - len / 2 + 1); len -= len / 2; }
    }
    if (got) strncat(got, buf, got_size - strlen(got) - 1);
    CHECKF(0, "%s: no \"%s\" within %.0f s (got \"%.80s\")", cmd ? cmd : "(reading)", until, seconds, buf);
    return 0;
}

/* avr-run's log: steps (cycle, direction), UV edges, resets, the end line. */
typedef struct avr_log {
    uint64_t *step_at;
    int *step_dir;
    size_t steps;
    uint64_t uv_at[1024];
    int uv_on[1024];
    size_t uvs;
    uint64_t reset_at[8];
    size_t resets;
    size_t steps_lit;            /* steps taken with the light on */
    avr_passes pass;             /* the end line */
    long start_steps;
    zevent *ev;                  /* steps, UV, shows: tests/zcheck.h's record, in ticks (cycle / 8) */
    size_t events, events_cap;
} avr_log;

static void add_event(avr_log *l, uint64_t at, int kind, int value)
{
    if (l->events == l->events_cap) {
        size_t cap = l->events_cap ? 2 * l->events_cap : 65536;
        zevent *e = (zevent *)realloc(l->ev, cap * sizeof *e);
        if (!e) return;
        l->ev = e;
        l->events_cap = cap;
    }
    l->ev[l->events].when = at;
    l->ev[l->events].kind = kind;
    l->ev[l->events].value = value;
    l->ev[l->events].crc = 0;
    l->events++;
}

/* The record's cycles as ticks. A compare's edge comes at the end of the
   instruction its cycle falls in (0-4 cycles on), and Timer4 runs a few
   cycles behind Timer5 (their counters were cleared one after the other):
   each timer's edges are read against their own phase, the residue mod 8
   from which all of them fall within the next 8 cycles. */
static unsigned edge_phase(const avr_log *l, int kind)
{
    unsigned seen = 0, r, best = 0, best_span = 8;
    size_t i;
    for (i = 0; i < l->events; i++)
        if (l->ev[i].kind == kind) seen |= 1u << (l->ev[i].when % CYCLES_PER_TICK);
    for (r = 0; r < CYCLES_PER_TICK; r++) {
        unsigned span = 0, k;
        for (k = 0; k < CYCLES_PER_TICK; k++)
            if (seen & (1u << ((r + k) % CYCLES_PER_TICK))) span = k + 1;
        if (span < best_span) { best_span = span; best = r; }
    }
    return best;
}

static void events_to_ticks(avr_log *l)
{
    unsigned step_phase = edge_phase(l, ZEV_STEP), uv_phase = edge_phase(l, ZEV_UV);
    size_t i;
    for (i = 0; i < l->events; i++) {
        unsigned phase = l->ev[i].kind == ZEV_UV ? uv_phase : l->ev[i].kind == ZEV_STEP ? step_phase : 0;
        uint64_t c = l->ev[i].when;
        l->ev[i].when = c >= phase ? (c - phase) / CYCLES_PER_TICK : 0;
    }
}

static int read_avr_log(const char *path, avr_log *l)
{
    FILE *f = fopen(path, "r");
    char line[512];
    size_t cap = 0;
    int uv = 0;
    memset(l, 0, sizeof *l);
    if (!f) return 0;
    while (fgets(line, sizeof line, f)) {
        unsigned long long at;
        char what[16], arg[16];
        const char *v;
        if (line[0] == '#') {
            if ((v = strstr(line, "start_steps="))) l->start_steps = strtol(v + 12, NULL, 10);
            avr_read_passes(line, &l->pass);
            continue;
        }
        arg[0] = 0;
        if (sscanf(line, "%llu %15s %15s", &at, what, arg) < 2) continue;
        if (!strcmp(what, "step")) {
            if (l->steps == cap) {
                cap = cap ? 2 * cap : 65536;
                l->step_at = (uint64_t *)realloc(l->step_at, cap * sizeof *l->step_at);
                l->step_dir = (int *)realloc(l->step_dir, cap * sizeof *l->step_dir);
                if (!l->step_at || !l->step_dir) { fclose(f); return 0; }
            }
            l->step_at[l->steps] = at;
            l->step_dir[l->steps++] = arg[0] == '-' ? -1 : 1;
            if (uv) l->steps_lit++;
            add_event(l, at, ZEV_STEP, arg[0] == '-' ? -1 : 1);
        } else if (!strcmp(what, "uv") && l->uvs < 1024) {
            uv = atoi(arg);
            l->uv_at[l->uvs] = at;
            l->uv_on[l->uvs++] = uv;
            add_event(l, at, ZEV_UV, uv);
        } else if (!strcmp(what, "show")) {
            add_event(l, at, ZEV_SHOW, atoi(arg));
        } else if (!strcmp(what, "reset") && l->resets < 8) {
            l->reset_at[l->resets++] = at;
        }
    }
    fclose(f);
    events_to_ticks(l);
    return 1;
}

static void free_avr_log(avr_log *l) { free(l->step_at); free(l->step_dir); free(l->ev); }

/* The board's Z axis as the firmware configures it (ports/ramps/main.c). */
static void board_axis(fw_axis *axis)
{
    fw_axis_config c;
    c.steps_per_mm = BOARD_STEPS_PER_MM;
    c.max_speed = BOARD_MAX_STEPS_S;
    c.accel = BOARD_ACCEL_MM_S2 * BOARD_STEPS_PER_MM;
    c.home_speed = BOARD_HOME_STEPS_S;
    c.max_steps = (int32_t)(BOARD_Z_MAX_MM * BOARD_STEPS_PER_MM);
    c.home_travel = (int32_t)(BOARD_HOME_TRAVEL_MM * BOARD_STEPS_PER_MM);
    fw_axis_init(axis, &c, BOARD_CLOCK_HZ);
}

typedef struct zmove { int32_t target; uint32_t speed; } zmove; /* steps, steps/s */

/* Every step of `moves` (after homing, which ends at the switch) against
   the closed form: each move's first step is its start, and step j must
   come t(j) ticks after it. Returns the worst lateness in cycles. */
static long check_moves(const avr_log *l, const zmove *moves, size_t count)
{
    size_t total = 0, k, i, at, bad = 0, short_intervals = 0;
    int32_t from = 0;
    long worst = 0;
    uint64_t min_cycles = (uint64_t)CYCLES_PER_TICK * ((BOARD_CLOCK_HZ + BOARD_MAX_STEPS_S - 1) /
                                                       (BOARD_MAX_STEPS_S));
    for (k = 0; k < count; k++) { total += (size_t)labs((long)(moves[k].target - from)); from = moves[k].target; }
    CHECKF(l->steps >= total, "%zu steps in the record, the moves need %zu after homing", l->steps, total);
    if (l->steps < total) return -1;
    at = l->steps - total;
    {
        long pos = l->start_steps;
        for (i = 0; i < at; i++) pos += l->step_dir[i];
        CHECKF(pos == 0, "homing ended %ld steps from the switch", pos);
    }
    from = 0;
    for (k = 0; k < count; k++) {
        fw_axis axis;
        uint64_t start = l->step_at[at];
        board_axis(&axis);
        axis.homed = 1;
        axis.position = from;
        CHECK(fw_axis_move_to(&axis, moves[k].target, moves[k].speed, 0) == FW_AXIS_OK);
        while (fw_axis_busy(&axis)) {
            uint64_t want = fw_axis_next(&axis) * CYCLES_PER_TICK;
            int dir = fw_axis_step(&axis, 0);
            long late = (long)(l->step_at[at] - start) - (long)want;
            if (labs(late) > worst) worst = labs(late);
            if ((labs(late) > (long)LATE_MAX_CYCLES || dir != l->step_dir[at]) && bad++ < 3)
                CHECKF(0, "move %zu step %zu: %ld cycles from its tick (dir %d, pin %d)", k, at, late, dir, l->step_dir[at]);
            at++;
        }
        from = moves[k].target;
    }
    /* intervals: the closed form allows none under the speed limit. simavr
       puts a compare's edge at the end of the instruction it falls in, 0-4
       cycles on, so an interval may read up to 4 cycles short of the
       hardware's (the pin itself is set by the compare unit, exactly) */
    for (i = 1; i < l->steps; i++)
        if (l->step_at[i] - l->step_at[i - 1] + 4u < min_cycles) short_intervals++;
    CHECKF(!short_intervals, "%zu step intervals under %llu cycles", short_intervals, (unsigned long long)min_cycles);
    return worst;
}

#define LAYER_UM 50
#define PEEL_UM 100
/* every 50th layer's peel: long enough to cruise at the top speed (its
   ramps are 1 mm at 10 mm/s and 50 mm/s^2) */
#define LONG_PEEL_UM 3000
#define TOP_F (BOARD_MAX_SPEED_UM_S * 60u / 1000u) /* the top speed in mm/min */
/* a dwell well above a host's round trip, even a loaded machine's (the
   light is on longer when the G4 comes after its end) */
#define EXPOSE_MS 100
#define CYCLES_PER_MS (BOARD_CPU_HZ / 1000u)

/* Layer `layer` of a G-code print as resin hosts send it: the lift above
   the last layer (from layer 2 on) and the way down to this one's top,
   then the light on for a dwell and off. The moves go into `moves` (F300
   and F180, under the board's top speed; every 50th layer a long peel at
   the top speed, both ways). Returns the number of lines in `lines`: the
   moves first, then M106, G4, M107. */
static int gcode_layer(int layer, char lines[5][48], zmove *moves, size_t *n)
{
    const int32_t spmm = (int32_t)BOARD_STEPS_PER_MM;
    int32_t top = layer * LAYER_UM * spmm / 1000;
    int k = 0, fast = layer % 50 == 0;
    unsigned up_f = fast ? TOP_F : 300u, down_f = fast ? TOP_F : 180u;
    if (layer > 1) {
        int32_t lift = (layer - 1) * LAYER_UM * spmm / 1000 + (fast ? LONG_PEEL_UM : PEEL_UM) * spmm / 1000;
        snprintf(lines[k++], 48, "G1 Z%.3f F%u", lift / (double)spmm, up_f);
        moves[*n].target = lift;
        moves[(*n)++].speed = (uint32_t)(up_f * BOARD_STEPS_PER_MM / 60u);
    }
    snprintf(lines[k++], 48, "G1 Z%.3f F%u", top / (double)spmm, down_f);
    moves[*n].target = top;
    moves[(*n)++].speed = (uint32_t)(down_f * BOARD_STEPS_PER_MM / 60u);
    snprintf(lines[k++], 48, "M106 S255");
    snprintf(lines[k++], 48, "G4 P%d", EXPOSE_MS);
    snprintf(lines[k++], 48, "M107");
    return k;
}

/* A G-code print of `layers` from avr-run's log at `path`: every step
   against the closed form, the light never on while Z moves, each exposure
   its dwell to the tick, no step late, every loop pass shorter than
   PASS_MAX (Bounded work in gcode.h: a line is checked in one pass and run
   in another). */
static void check_gcode_print(const char *path, const zmove *moves, size_t n, int layers, const char *who)
{
    avr_log l;
    long worst;
    uint64_t longest = 0, shortest = UINT64_MAX;
    const uint64_t want = (uint64_t)EXPOSE_MS * CYCLES_PER_MS;
    size_t k;
    CHECK(read_avr_log(path, &l));
    if (check_case_failed()) { free_avr_log(&l); return; }
    worst = check_moves(&l, moves, n);
    CHECKF(l.uvs == 2u * (size_t)layers, "%zu UV edges for %d layers", l.uvs, layers);
    CHECKF(!l.steps_lit, "%zu steps with the light on", l.steps_lit);
    for (k = 0; k + 1 < l.uvs; k += 2) {
        /* M106's dwell is the exposure, to the tick: Timer4's compare unit
           switches at both ends, whatever the host's round trips (simavr
           puts a compare's pin edge out 0 or 1 cycle after the match) */
        uint64_t lit = l.uv_at[k + 1] - l.uv_at[k];
        if (lit > longest) longest = lit;
        if (lit < shortest) shortest = lit;
        CHECKF(l.uv_on[k] && !l.uv_on[k + 1] && lit + CYCLES_PER_TICK > want && lit < want + CYCLES_PER_TICK,
               "exposure %zu: %llu cycles for a G4 P%d (%llu)", k / 2, (unsigned long long)lit, EXPOSE_MS,
               (unsigned long long)want);
        if (check_case_failed()) break;
    }
    CHECKF(!l.pass.late && !l.resets, "%lu steps refused as late, %zu resets", l.pass.late, l.resets);
    CHECKF(l.pass.worst < PASS_MAX, "a loop pass took %lu cycles (%lu while Z moved), over %lu: the queue covers %lu at the top speed",
           l.pass.worst, l.pass.moving, PASS_MAX, COVER_CYCLES);
    printf("    avr, %s: %d layers, %zu steps, worst step %ld cycles from its tick; light %.4f..%.4f ms for G4 P%d; "
           "worst loop pass %lu cycles (%lu while Z moved; the queue covers %lu at the top speed, a step every %lu), stack peak %lu bytes\n",
           who, layers, l.steps, worst, (double)shortest / CYCLES_PER_MS, (double)longest / CYCLES_PER_MS, EXPOSE_MS,
           l.pass.worst, l.pass.moving, COVER_CYCLES, STEP_CYCLES, l.pass.stack);
    free_avr_log(&l);
}

/* NanoDLP's way: each move waited for with Z_move_comp, then the light on
   for a dwell, off. */
#define NANODLP_LAYERS 100
static void gcode_print_nanodlp_style(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "1", "--speed", "20", "--max-seconds", "600", "--timeout", "300", NULL};
    static zmove moves[2 * NANODLP_LAYERS + 1];
    char got[256];
    size_t n = 0;
    int layer, ok = 1;
    if (!avr_start(&c, "build/test_avr/print.log", opts)) { CHECK(!"build/avr-run did not start build/fw-ramps-test.elf (make check builds both)"); avr_stop(&c); return; }
    got[0] = 0;
    ok &= gline(&c, "M115", "ok", 10, got, sizeof got);
    CHECKF(ok && strstr(got, "FIRMWARE_NAME:adaslice"), "M115: %s", got);
    ok &= gline(&c, "G28", "ok", 30, NULL, 0);
    ok &= gline(&c, "G90", "ok", 5, NULL, 0);
    for (layer = 1; ok && layer <= NANODLP_LAYERS; layer++) {
        char lines[5][48];
        int k, count = gcode_layer(layer, lines, moves, &n);
        for (k = 0; ok && k < count; k++) ok &= gline(&c, lines[k], lines[k][0] == 'G' && lines[k][1] == '1' ? "Z_move_comp" : "ok", 10, NULL, 0);
    }
    CHECKF(ok, "the G-code stream stopped at layer %d", layer - 1);
    {
        /* the last exposure ends on Timer4 a shift after its dwell: let the
           simulation run past it */
        struct timespec ts = {0, 200000000};
        nanosleep(&ts, NULL);
    }
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    if (check_case_failed()) return;
    check_gcode_print("build/test_avr/print.log", moves, n, NANODLP_LAYERS, "NanoDLP-style");
}

/* printrun's printcore (Debian's printrun) prints a 200-layer G-code file
   over avr-run's pty: numbered, checksummed lines, one in flight, each sent
   on the last one's ok (a move's comes as it starts; the firmware holds the
   next line until Z has stopped). */
#define PRINTCORE_LAYERS 200
static void gcode_print_by_printcore(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "1", "--speed", "20", "--max-seconds", "900", "--timeout", "600", NULL};
    static zmove moves[2 * PRINTCORE_LAYERS + 1];
    char job[256], out[256], *text;
    size_t n = 0;
    int layer, st = -1, sent = 0, oks = 0;
    const char *line;
    FILE *f;
    pid_t pc;
    double t0;
    snprintf(job, sizeof job, "%s", cli_path("printcore200.gcode"));
    snprintf(out, sizeof out, "%s", cli_path("printcore200.out"));
    f = fopen(job, "w");
    if (!f) { CHECK(!"cannot write the G-code file"); return; }
    fputs("; 200 layers of 50 um, NanoDLP's layer (lift, down, M106, G4, M107)\nG28\nG90\n", f);
    for (layer = 1; layer <= PRINTCORE_LAYERS; layer++) {
        char lines[5][48];
        int k, count = gcode_layer(layer, lines, moves, &n);
        for (k = 0; k < count; k++) fprintf(f, "%s\n", lines[k]);
    }
    fputs("M18\n", f);
    CHECK(fclose(f) == 0);
    if (!avr_start(&c, "build/test_avr/printcore.log", opts)) { CHECK(!"build/avr-run did not start build/fw-ramps-test.elf"); avr_stop(&c); return; }
    close(c.tty); /* printcore opens the pty itself */
    c.tty = 0;
    fflush(NULL);
    pc = fork();
    if (pc == 0) {
        int fd = open(out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) { dup2(fd, 1); dup2(fd, 2); }
        execl("/usr/bin/python3", "python3", "/usr/bin/printcore", "-v", c.pty, job, (char *)NULL);
        _exit(127);
    }
    t0 = now_s();
    while (pc > 0 && now_s() - t0 < 600) {
        struct timespec ts = {0, 50000000};
        int s;
        if (waitpid(pc, &s, WNOHANG) == pc) { st = WIFEXITED(s) ? WEXITSTATUS(s) : -1; pc = 0; break; }
        nanosleep(&ts, NULL);
    }
    if (pc > 0) { kill(pc, SIGKILL); waitpid(pc, NULL, 0); }
    {
        struct timespec ts = {0, 200000000}; /* past the last exposure's end */
        nanosleep(&ts, NULL);
    }
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    text = cli_read(out);
    CHECKF(st == 0, "printcore (Debian printrun) exited %d after %.0f s: %.300s", st, now_s() - t0, text ? text : "");
    for (line = text; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        if (!strncmp(line, "SENT: N", 7) && strncmp(line, "SENT: N-1 ", 10)) sent++;
        if (!strncmp(line, "RECV: ok", 8)) oks++;
        CHECKF(strncmp(line, "RECV: Error", 11) && strncmp(line, "RECV: echo:Exposure", 19), "printcore was told %.70s", line);
        if (check_case_failed()) break;
    }
    free(text);
    /* G28, G90, M18 and per layer its moves and three lines */
    CHECKF(sent == 3 + 5 * PRINTCORE_LAYERS - 1 && oks >= sent, "printcore sent %d lines, %d acknowledged", sent, oks);
    if (check_case_failed()) return;
    check_gcode_print("build/test_avr/printcore.log", moves, n, PRINTCORE_LAYERS, "printcore");
}

#define BPRINT_PEEL_UM 3000 /* at the top speed: 1 mm ramps, 1 mm of cruise */

/* adaslice print over the pty, as tests/test_print.c drives fw-sim: the
   printer plans, the host streams every mask while Z moves (the window of
   frames in flight), and the pins show the print the report describes. It
   homes from 20 mm first, 4 s at the homing speed: longer than the host's
   3 s give-up, so the printer answers the host's status polls while Z
   homes or the print fails. */
#define BPRINT_Z_START "20"
static void binary_print_with_masks_streaming(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", BPRINT_Z_START, "--max-seconds", "300", "--timeout", "300", NULL};
    cli_result r;
    avr_log l;
    print_report rep;
    zexpect e;
    zsummary s;
    zmove *moves;
    size_t n = 0;
    uint32_t k;
    long worst, final_pos;
    int32_t peel;
    fw_axis axis;
    char report[256];
    snprintf(report, sizeof report, "%s", cli_path("avr-report.json"));
    if (!avr_start(&c, "build/test_avr/bprint.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    close(c.tty);
    c.tty = 0;
    r = cli_run("print", "examples/models/hand_closed.obj", "--scale", "5", "--port", c.pty, "--exposure", "0.05", "--penetration", "0.1",
                "--bottom-layers", "1", "--bottom-exposure", "0.1", "--peel", "3", "--peel-speed", "10", "--return-speed", "10",
                "--settle", "0.02", "--report", report, NULL);
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "planned by the printer, identical to the host's plan") != NULL);
    cli_free(&r);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    if (check_case_failed()) return;
    CHECK(read_avr_log("build/test_avr/bprint.log", &l));
    CHECK(read_print_report(report, &rep));
    if (check_case_failed()) { free_avr_log(&l); return; }
    /* the moves the plan makes: to each layer's top, then the peel above it */
    board_axis(&axis);
    peel = fw_axis_steps_of_nm(&axis, (uint64_t)BPRINT_PEEL_UM * 1000u);
    moves = (zmove *)calloc(2u * rep.layers + 1u, sizeof *moves);
    for (k = 0; moves && k < rep.layers; k++) {
        int32_t top = fw_axis_steps_of_nm(&axis, (uint64_t)rep.tops[k] * rep.bin_nm);
        moves[n].target = top;
        moves[n++].speed = 0; /* the peel and return speeds (10 mm/s) are the top speed */
        moves[n].target = fw_axis_steps_of_nm(&axis, (uint64_t)rep.tops[k] * rep.bin_nm + BPRINT_PEEL_UM * 1000u);
        moves[n++].speed = 0;
    }
    (void)peel;
    final_pos = l.start_steps;
    for (k = 0; k < l.steps; k++) final_pos += l.step_dir[k];
    CHECKF(moves && n && final_pos == moves[n - 1].target, "Z ends at %ld steps, the last peel at %ld", final_pos, moves && n ? (long)moves[n - 1].target : -1L);
    worst = moves ? check_moves(&l, moves, n) : -1;
    memset(&e, 0, sizeof e);
    e.tick_hz = BOARD_CLOCK_HZ; /* the record in ticks */
    e.steps_per_mm = BOARD_STEPS_PER_MM;
    e.max_speed = BOARD_MAX_STEPS_S;
    e.accel = (uint32_t)BOARD_ACCEL_MM_S2 * BOARD_STEPS_PER_MM;
    e.start_position = l.start_steps;
    e.layers = rep.layers;
    e.first = rep.first ? rep.first : 1;
    e.top_bins = rep.tops;
    e.bin_nm = rep.bin_nm;
    e.crcs = NULL; /* no display on this board: the core checks the CRCs */
    e.exposure_ms = rep.exposures;
    s = zcheck_record(l.ev, l.events, &e);
    CHECKF(s.shows == rep.layers, "%zu masks shown for %u layers", s.shows, rep.layers);
    CHECKF(!l.pass.late && !l.resets, "%lu steps refused as late, %zu resets", l.pass.late, l.resets);
    {
        /* homing's approach: down from the start to the switch, where the
           first step up (the back-off) comes */
        size_t up = 0;
        double homing_s;
        while (up < l.steps && l.step_dir[up] < 0) up++;
        homing_s = up < l.steps ? (double)(l.step_at[up] - l.step_at[0]) / BOARD_CPU_HZ : 0;
        CHECKF(homing_s > 3.5 && rep.longest_wait_ms < 500, "homing's approach %.2f s; the longest wait for a reply %.1f ms",
               homing_s, rep.longest_wait_ms);
        printf("    avr: homing's approach took %.2f s; the longest wait for a reply %.1f ms\n", homing_s, rep.longest_wait_ms);
    }
    /* Bounded work a pass (fw.h): every pass of the loop, its interrupts
       included (simavr's UART runs at the line's rate), is shorter than
       PASS_MAX, while Z moves (masks streaming) and while it is still
       (planning, the print's start, homing), so the queue never runs dry
       whatever else the loop does. */
    CHECKF(l.pass.worst < PASS_MAX, "a loop pass took %lu cycles (%lu while Z moved), over %lu: the queue covers %lu at the top speed",
           l.pass.worst, l.pass.moving, PASS_MAX, COVER_CYCLES);
    printf("    avr: %u layers, %zu steps, worst step %ld cycles from its tick, every exposure exact to the tick; worst loop pass %lu cycles "
           "(%lu while Z moved; the loop's own work %lu, %lu; the queue covers %lu at the top speed), stack peak %lu bytes\n",
           rep.layers, l.steps, worst, l.pass.worst, l.pass.moving, l.pass.work, l.pass.moving_work, COVER_CYCLES, l.pass.stack);
    free(moves);
    print_report_free(&rep);
    free_avr_log(&l);
}

/* The loop hangs as the light goes on (RAMPS_TEST_HANG): the watchdog
   resets the MCU, the reset switches the light off, and it answers again. */
static void watchdog_resets_a_hung_loop(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "2", "--hang-at-uv", "1", "--speed", "5", "--max-seconds", "300", "--timeout", "60", NULL};
    char got[256] = "";
    avr_log l;
    int ok = 1;
    if (!avr_start(&c, "build/test_avr/wdt.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    ok &= gline(&c, "G28", "ok", 30, NULL, 0);
    ok &= gline(&c, "M106", "ok", 5, NULL, 0);
    CHECK(ok);
    /* the hung MCU does not answer; once reset it does */
    {
        /* bytes into a hung loop: nothing comes back */
        struct timespec ts = {1, 0};
        CHECK(write(c.tty, "M115\n", 5) == 5);
        nanosleep(&ts, NULL);
    }
    got[0] = 0;
    ok = gline(&c, "M115", "FIRMWARE_NAME", 5, got, sizeof got);
    CHECKF(ok, "no answer after the reset: %s", got);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    CHECK(read_avr_log("build/test_avr/wdt.log", &l));
    CHECKF(l.uvs >= 2 && l.uv_on[0] && !l.uv_on[1], "%zu UV edges", l.uvs);
    CHECKF(l.resets == 1, "%zu resets", l.resets);
    if (l.uvs >= 2 && l.resets == 1) {
        double ms = (double)(l.uv_at[1] - l.uv_at[0]) * 1000.0 / BOARD_CPU_HZ;
        /* the watchdog's nominal period; its oscillator is +-10 % */
        CHECKF(l.uv_at[1] == l.reset_at[0] && ms <= BOARD_WDT_MS * 1.1 + 1, "UV off %.2f ms after the hang", ms);
        printf("    avr: the watchdog reset the hung MCU %.2f ms after the light went on\n", ms);
    }
    free_avr_log(&l);
}

void test_avr(void)
{
    if (system("mkdir -p build/test_avr") != 0) { CHECK(!"mkdir build/test_avr"); return; }
    if (!cli_begin("adaslice-avr")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", watchdog_resets_a_hung_loop);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", gcode_print_nanodlp_style);
    RUN_NEEDING("simavr, avr-gcc and printcore (Debian printrun): build/avr-run, build/fw-ramps-test.elf", gcode_print_by_printcore);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", binary_print_with_masks_streaming);
    cli_end();
}
