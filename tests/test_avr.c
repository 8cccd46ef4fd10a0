/* The RAMPS 1.4 / ATmega2560 image (build/fw-ramps-test.elf) under simavr
   through tests/avr_run.c (build/avr-run), checked from its pin edges, which
   are cycle-exact (the log's cycle / 8 is the firmware's 2 MHz tick). Every
   print's log passes tests/zcheck.h's check, which uses no firmware code
   and takes the board's limits from the log's header (each exposure at its
   layer's top for exactly its time, no light while Z moves, speed and
   acceleration within the limits, each move's first interval the one from
   rest, the steps the heights moved); besides, each step is compared with
   the tick motion.c's closed form gives it (a host fw_axis on the board's
   config replays each move from its first step: within 10 us).
     - G-code mode: a 100-layer print as NanoDLP drives one (each move
       waited for with Z_move_comp, the light on for a G4 dwell) and a
       40-layer file printed by printrun's printcore: every exposure its G4
       dwell to the tick (the dwell after M106 counts from M106 and Timer4
       ends it, so the host's round trips between the lines add nothing
       while the G4 comes within the dwell), no step refused as late, and
       every loop pass shorter than PASS_MAX (below: the time the step queue
       covers at the top speed, less its margin), with every 50th layer's
       peel at the top speed;
     - a binary-protocol print by the host tool (adaslice print), masks
       streaming while Z moves, the peels at the top speed; every loop
       pass, its interrupts included, shorter than PASS_MAX, while Z moves
       and while it is still;
     - a binary MOVE slower than a step a second steps once a second;
     - the watchdog: the main loop made to hang while the light is on; the
       MCU resets within the watchdog period, which switches the light off,
       and it answers again afterwards;
     - the stack: every run's peak (avr-run's, from the stack's room up)
       at least 128 bytes inside the reserve the link made, its canary
       untouched; and a stack made to overrun its room while the light is
       on: the light out within a pass, the halt said, nothing lit or
       moved afterwards. */
#define _XOPEN_SOURCE 700
#include "check.h"
#include "cli_run.h"
#include "zcheck.h"
#include "print_report.h"
#include "avr_passes.h"
#include "../firmware/gcode.h"
#include "../firmware/motion.h"
#include "../firmware/ports/ramps/board.h"
#include "../link/frame.h"
#include "../link/messages.h"
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

/* early: avr-run ended before the test stopped it, with `status` */
/* carry: what the printer sent past the last gline's match, for the next */
typedef struct avr_child { pid_t pid; int out, tty, early, status; char pty[256]; char carry[512]; } avr_child;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* avr-run with `extra` options, its log at `log`; the pty opened raw. */
static int avr_start(avr_child *c, const char *log, const char *const *extra)
{
    char *argv[24], line[256], err[300];
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
    snprintf(err, sizeof err, "%s.err", log);
    c->pid = fork();
    if (c->pid == 0) {
        int fd = open(err, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) dup2(fd, 2);
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

/* 1 once avr-run has ended by itself (its status kept). */
static int avr_ended(avr_child *c)
{
    int st;
    if (c->pid > 0 && waitpid(c->pid, &st, WNOHANG) == c->pid) {
        c->status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
        c->early = 1;
        c->pid = 0;
        close(c->out);
    }
    return c->early;
}

/* SIGTERM; avr-run's exit status (-1 if it did not exit). */
static int avr_stop(avr_child *c)
{
    int st, i;
    if (c->tty > 0) close(c->tty);
    c->tty = 0;
    if (avr_ended(c)) return c->status;
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGTERM);
    for (i = 0; i < 250; i++) {
        struct timespec ts = {0, 20000000};
        if (waitpid(c->pid, &st, WNOHANG) == c->pid) { close(c->out); c->pid = 0; return WIFEXITED(st) ? WEXITSTATUS(st) : -1; }
        nanosleep(&ts, NULL);
    }
    kill(c->pid, SIGKILL);
    waitpid(c->pid, &st, 0);
    close(c->out);
    c->pid = 0;
    return -1;
}

/* avr-run stopped and its end told apart (its stderr is at LOG.err): a
   clean stop, a signal from elsewhere (the harness's failure), the
   image crashed (the firmware's failure), the print outlasting its budget
   of virtual time (the firmware's), or of wall time (the machine's: the
   harness could not run the simulation fast enough). */
static void check_avr_exit(avr_child *c, const char *log)
{
    char path[300], *err;
    int status = avr_stop(c);
    snprintf(path, sizeof path, "%s.err", log);
    err = read_whole_text(path);
    if (c->early && status == 0)
        CHECKF(0, "harness failure, not the firmware's: avr-run was stopped by a signal from outside the test: %.200s", err ? err : "");
    else if (status == 4 && err && strstr(err, "--timeout budget"))
        CHECKF(0, "harness failure, not the firmware's: avr-run's wall-clock budget ran out (a slow or loaded machine): %.200s", err);
    else if (status == 4)
        CHECKF(0, "firmware failure: the print outlasted avr-run's virtual-time budget: %.200s", err ? err : "");
    else if (status == 3)
        CHECKF(0, "firmware failure: the image stopped: %.200s", err ? err : "");
    else
        CHECKF(status == 0, "harness failure: avr-run ended with %d: %.200s", status, err ? err : "");
    free(err);
}

/* Sends a G-code line and reads replies until `until` is seen (or
   `seconds` pass); 1 when seen. Replies are appended to `got`. */
static int gline(avr_child *c, const char *cmd, const char *until, double seconds, char *got, size_t got_size)
{
    char buf[512];
    size_t len;
    double t0 = now_s();
    const char *at;
    /* replies may come in one read with the next one's: what follows a
       match is kept for the next call */
    snprintf(buf, sizeof buf, "%s", c->carry);
    len = strlen(buf);
    c->carry[0] = 0;
    if (cmd) {
        char l[128];
        int n = snprintf(l, sizeof l, "%s\n", cmd);
        if (write(c->tty, l, (size_t)n) != n) return 0;
    }
    for (;;) {
        struct pollfd p = {c->tty, POLLIN, 0};
        ssize_t n;
        if ((at = strstr(buf, until)) != NULL) {
            size_t end = (size_t)(at - buf) + strlen(until);
            snprintf(c->carry, sizeof c->carry, "%s", buf + end);
            buf[end] = 0;
            if (got) strncat(got, buf, got_size - strlen(got) - 1);
            return 1;
        }
        if (now_s() - t0 >= seconds) break;
        if (poll(&p, 1, 50) <= 0) continue;
        n = read(c->tty, buf + len, sizeof buf - 1 - len);
        if (n < 0 && errno != EAGAIN) break; /* avr-run is gone: the pty hung up */
        if (n <= 0) continue;
        len += (size_t)n;
        buf[len] = 0;
        if (len > sizeof buf / 2 && !strstr(buf, until)) { memmove(buf, buf + len / 2, len - len / 2 + 1); len -= len / 2; }
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
    uint64_t canary_at;          /* the cycle the stack's canary changed, 0 never */
    avr_passes pass;             /* the end line */
    long start_steps;
    unsigned long cpu_hz, tick_div, steps_per_mm, max_speed, accel; /* the header: board.h's figures */
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
            if ((v = strstr(line, "cpu_hz="))) l->cpu_hz = strtoul(v + 7, NULL, 10);
            if ((v = strstr(line, "tick_div="))) l->tick_div = strtoul(v + 9, NULL, 10);
            if ((v = strstr(line, "steps_per_mm="))) l->steps_per_mm = strtoul(v + 13, NULL, 10);
            if ((v = strstr(line, "max_speed="))) l->max_speed = strtoul(v + 10, NULL, 10);
            if ((v = strstr(line, "accel="))) l->accel = strtoul(v + 6, NULL, 10);
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
        } else if (!strcmp(what, "canary") && !l->canary_at) {
            l->canary_at = at;
        }
    }
    fclose(f);
    events_to_ticks(l);
    return l->cpu_hz && l->tick_div && l->steps_per_mm && l->max_speed && l->accel;
}

/* tests/zcheck.h's expectations from the log's header (avr-run writes
   board.h's millimetre figures as steps, computed on the host): the record
   in ticks, each edge read against its timer's phase, so exact to the tick
   (no jitter). */
static void avr_expect(const avr_log *l, zexpect *e)
{
    memset(e, 0, sizeof *e);
    e->tick_hz = l->cpu_hz / l->tick_div;
    e->steps_per_mm = (uint32_t)l->steps_per_mm;
    e->max_speed = (uint32_t)l->max_speed;
    e->accel = (uint32_t)l->accel;
    e->jitter = 0;
    e->start_position = l->start_steps;
    e->first = 1;
}

static void free_avr_log(avr_log *l) { free(l->step_at); free(l->step_dir); free(l->ev); }

/* The stack's margin the link reserved (firmware.mk's FW_AVR_STACK) over
   the deepest a run went. */
#define STACK_MARGIN 128u

/* A run's stack: its canary untouched, and its peak (avr-run's, from the
   stack's room up) at least STACK_MARGIN inside the reserve. */
static void check_stack(const avr_log *l, const char *who)
{
    CHECKF(!l->pass.canary && !l->canary_at, "%s: the stack's canary was overwritten", who);
    CHECKF(l->pass.reserve && l->pass.stack + STACK_MARGIN <= l->pass.reserve,
           "%s: the stack went %lu bytes deep, the image reserves %lu (%u of them the margin)", who, l->pass.stack, l->pass.reserve,
           STACK_MARGIN);
}

/* The board's Z axis as the firmware configures it (ports/ramps/main.c). */
static void board_axis(fw_axis *axis)
{
    fw_axis_config c;
    c.steps_per_mm = BOARD_STEPS_PER_MM;
    c.max_speed = BOARD_MAX_STEPS_S;
    c.accel = BOARD_ACCEL_STEPS_S2;
    c.home_speed = BOARD_HOME_STEPS_S;
    c.max_steps = (int32_t)BOARD_Z_MAX_STEPS;
    c.home_travel = (int32_t)BOARD_HOME_TRAVEL_STEPS;
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
/* A G4's dwell is a host's round trip's budget: M106's ok, then its G4
   line, before the dwell from M106 is over (a later G4 leaves the light on
   until it comes, an over-exposure the firmware reports). avr-run runs
   these prints at --speed 1, so virtual time never runs ahead of the wall
   clock and a host has the dwell in wall time however loaded the machine. */
#define CYCLES_PER_MS (BOARD_CPU_HZ / 1000u)
#define GCODE_MAX_LAYERS 100

/* A G-code print: the moves its lines ask for (for the closed form), and
   what tests/zcheck.h checks the pins against: the heights Z visits (the
   lines' Z values), each layer's top and its exposure. */
typedef struct gcode_job {
    zmove moves[2 * GCODE_MAX_LAYERS];
    uint64_t path_nm[2 * GCODE_MAX_LAYERS];
    uint32_t top_um[GCODE_MAX_LAYERS], exposure_ms[GCODE_MAX_LAYERS];
    size_t n;
    int layers;
    int dwell_ms;                 /* each layer's G4 */
} gcode_job;

/* A G1's Z in nanometres, from its text. */
static uint64_t z_nm_of(const char *line)
{
    const char *z = strchr(line, 'Z');
    return z ? (uint64_t)llround(strtod(z + 1, NULL) * 1e6) : 0;
}

/* Layer `layer` of a G-code print as resin hosts send it: the lift above
   the last layer (from layer 2 on) and the way down to this one's top,
   then the light on for a dwell and off. The moves go into `job` (F300
   and F180, under the board's top speed; every 50th layer a long peel at
   the top speed, both ways). Returns the number of lines in `lines`: the
   moves first, then M106, G4, M107. */
static int gcode_layer(int layer, char lines[5][48], gcode_job *job)
{
    const int32_t spmm = (int32_t)BOARD_STEPS_PER_MM;
    int32_t top = layer * LAYER_UM * spmm / 1000;
    int k = 0, fast = layer % 50 == 0;
    unsigned up_f = fast ? TOP_F : 300u, down_f = fast ? TOP_F : 180u;
    if (layer > 1) {
        int32_t lift = (layer - 1) * LAYER_UM * spmm / 1000 + (fast ? LONG_PEEL_UM : PEEL_UM) * spmm / 1000;
        snprintf(lines[k], 48, "G1 Z%.3f F%u", lift / (double)spmm, up_f);
        job->path_nm[job->n] = z_nm_of(lines[k++]);
        job->moves[job->n].target = lift;
        job->moves[job->n++].speed = (uint32_t)(up_f * BOARD_STEPS_PER_MM / 60u);
    }
    snprintf(lines[k], 48, "G1 Z%.3f F%u", top / (double)spmm, down_f);
    job->path_nm[job->n] = z_nm_of(lines[k++]);
    job->moves[job->n].target = top;
    job->moves[job->n++].speed = (uint32_t)(down_f * BOARD_STEPS_PER_MM / 60u);
    job->top_um[layer - 1] = (uint32_t)(job->path_nm[job->n - 1] / 1000u);
    job->exposure_ms[layer - 1] = (uint32_t)job->dwell_ms;
    job->layers = layer;
    snprintf(lines[k++], 48, "M106 S255");
    snprintf(lines[k++], 48, "G4 P%d", job->dwell_ms);
    snprintf(lines[k++], 48, "M107");
    return k;
}

/* A G-code print of `layers` from avr-run's log at `path`: every step
   against the closed form, and tests/zcheck.h's check, which uses no
   firmware code (each exposure at its line's Z and its dwell to the tick,
   the light never on while Z moves, speed, acceleration and each move's
   start from rest within the board's limits, the steps the heights moved);
   no step late, every loop pass shorter than PASS_MAX (Bounded work in
   gcode.h: a line is checked in one pass and run in another). */
static void check_gcode_print(const char *path, const gcode_job *job, const char *who)
{
    avr_log l;
    long worst;
    zexpect e;
    zsummary s;
    CHECKF(read_avr_log(path, &l), "cannot read avr-run's log %s (or its header)", path);
    if (check_case_failed()) { free_avr_log(&l); return; }
    worst = check_moves(&l, job->moves, job->n);
    avr_expect(&l, &e);
    e.layers = (uint32_t)job->layers;
    e.top_bins = job->top_um;
    e.bin_nm = 1000;
    e.exposure_ms = job->exposure_ms;
    e.path_nm = job->path_nm;
    e.path_len = job->n;
    s = zcheck_record(l.ev, l.events, &e);
    CHECKF(s.moves >= job->n && s.ramp_windows, "%zu moves from rest and %zu ramp windows checked for %zu moves", s.moves,
           s.ramp_windows, job->n);
    CHECKF(!l.pass.late && !l.resets, "%lu steps refused as late, %zu resets", l.pass.late, l.resets);
    CHECKF(l.pass.worst < PASS_MAX, "a loop pass took %lu cycles (%lu while Z moved), over %lu: the queue covers %lu at the top speed",
           l.pass.worst, l.pass.moving, PASS_MAX, COVER_CYCLES);
    check_stack(&l, who);
    printf("    avr, %s: %d layers, %zu steps, worst step %ld cycles from its tick; every exposure its G4 P%d to the tick; "
           "%zu moves, first intervals within %.1f ticks of sqrt(2/a), %zu ramp windows at %.4f..%.4f of the acceleration; "
           "worst loop pass %lu cycles (%lu while Z moved; the queue covers %lu at the top speed), stack peak %lu bytes of %lu reserved\n",
           who, job->layers, l.steps, worst, job->dwell_ms, s.moves, s.worst_first_ticks, s.ramp_windows, s.lowest_ramp_ratio,
           s.worst_accel_ratio, l.pass.worst, l.pass.moving, COVER_CYCLES, l.pass.stack, l.pass.reserve);
    free_avr_log(&l);
}

/* NanoDLP's way: each move waited for with Z_move_comp, then the light on
   for a dwell, off: this test is the host, C code that answers at once.
   At --speed 1; a wall-clock budget only against a hang, far above what
   the print needs. */
#define NANODLP_LAYERS 100
static void gcode_print_nanodlp_style(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "1", "--speed", "1", "--max-seconds", "600", "--timeout", "1800", NULL};
    static gcode_job job;
    char got[256];
    int layer, ok = 1;
    memset(&job, 0, sizeof job);
    job.dwell_ms = 300;
    if (!avr_start(&c, "build/test_avr/print.log", opts)) { CHECK(!"build/avr-run did not start build/fw-ramps-test.elf (make check builds both)"); avr_stop(&c); return; }
    got[0] = 0;
    ok &= gline(&c, "M115", "ok", 10, got, sizeof got);
    CHECKF(ok && strstr(got, "FIRMWARE_NAME:adaslice"), "M115: %s", got);
    ok &= gline(&c, "G28", "ok", 60, NULL, 0);
    ok &= gline(&c, "G90", "ok", 10, NULL, 0);
    for (layer = 1; ok && layer <= NANODLP_LAYERS; layer++) {
        char lines[5][48];
        int k, count = gcode_layer(layer, lines, &job);
        for (k = 0; ok && k < count; k++) {
            ok &= gline(&c, lines[k], lines[k][0] == 'G' && lines[k][1] == '1' ? "Z_move_comp" : "ok", 60, got, sizeof got);
            CHECKF(!strstr(got, "Exposure ran over"), "harness failure, not the firmware's: this test's G4 came after the dwell's end: %s", got);
            got[0] = 0;
        }
    }
    CHECKF(ok, "the G-code stream stopped at layer %d", layer - 1);
    {
        /* the last exposure ends on Timer4 a shift after its dwell: let the
           simulation run past it */
        struct timespec ts = {0, 200000000};
        nanosleep(&ts, NULL);
    }
    check_avr_exit(&c, "build/test_avr/print.log");
    if (check_case_failed()) return;
    check_gcode_print("build/test_avr/print.log", &job, "NanoDLP-style");
}

/* printrun's printcore (Debian's printrun) prints a 40-layer G-code file
   over avr-run's pty: numbered, checksummed lines, one in flight, each sent
   on the last one's ok (a move's comes as it starts; the firmware holds the
   next line until Z has stopped). At --speed 1, so that printcore has the
   dwell in wall time to send a G4 after M106's ok, a long one: on a machine
   loaded many times over its cores a Python host answers slowly; the
   budgets are against hangs only, far above what the print needs. A failure says whose it is: the harness's (printcore missing or
   crashing, the wall-clock budget, a G4 later than the dwell) or the
   firmware's (an error reply, the virtual-time budget, the pins). */
#define PRINTCORE_LAYERS 40
#define PRINTCORE_DWELL_MS 1500
#define PRINTCORE_WALL_S 1800
static void gcode_print_by_printcore(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "1", "--speed", "1", "--max-seconds", "900", "--timeout", "1800", NULL};
    static gcode_job job;
    char job_path[256], out[256], *text;
    int layer, st = -1, sig = 0, sent = 0, oks = 0, late = 0, errors = 0;
    const char *line;
    FILE *f;
    pid_t pc;
    double t0;
    memset(&job, 0, sizeof job);
    job.dwell_ms = PRINTCORE_DWELL_MS;
    snprintf(job_path, sizeof job_path, "%s", cli_path("printcore.gcode"));
    snprintf(out, sizeof out, "%s", cli_path("printcore.out"));
    f = fopen(job_path, "w");
    if (!f) { CHECK(!"cannot write the G-code file"); return; }
    fputs("; 50 um layers, NanoDLP's layer (lift, down, M106, G4, M107)\nG28\nG90\n", f);
    for (layer = 1; layer <= PRINTCORE_LAYERS; layer++) {
        char lines[5][48];
        int k, count = gcode_layer(layer, lines, &job);
        for (k = 0; k < count; k++) fprintf(f, "%s\n", lines[k]);
    }
    fputs("M18\n", f);
    CHECK(fclose(f) == 0);
    if (access("/usr/bin/printcore", R_OK) != 0) { CHECK(!"harness failure: no /usr/bin/printcore (Debian's printrun)"); return; }
    if (!avr_start(&c, "build/test_avr/printcore.log", opts)) { CHECK(!"harness failure: build/avr-run did not start build/fw-ramps-test.elf"); avr_stop(&c); return; }
    close(c.tty); /* printcore opens the pty itself */
    c.tty = 0;
    fflush(NULL);
    pc = fork();
    if (pc == 0) {
        int fd = open(out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) { dup2(fd, 1); dup2(fd, 2); }
        execl("/usr/bin/python3", "python3", "/usr/bin/printcore", "-v", c.pty, job_path, (char *)NULL);
        _exit(127);
    }
    t0 = now_s();
    while (pc > 0 && now_s() - t0 < PRINTCORE_WALL_S && !avr_ended(&c)) {
        struct timespec ts = {0, 50000000};
        int s;
        if (waitpid(pc, &s, WNOHANG) == pc) {
            st = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
            sig = WIFSIGNALED(s) ? WTERMSIG(s) : 0;
            pc = 0;
            break;
        }
        nanosleep(&ts, NULL);
    }
    if (pc > 0) { kill(pc, SIGKILL); waitpid(pc, NULL, 0); }
    {
        struct timespec ts = {0, 200000000}; /* past the last exposure's end */
        nanosleep(&ts, NULL);
    }
    check_avr_exit(&c, "build/test_avr/printcore.log");
    text = read_whole_text(out);
    for (line = text; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        if (!strncmp(line, "SENT: N", 7) && strncmp(line, "SENT: N-1 ", 10)) sent++;
        if (!strncmp(line, "RECV: ok", 8)) oks++;
        if (!strncmp(line, "RECV: echo:Exposure ran over", 28) && late++ < 3)
            CHECKF(0, "harness failure, not the firmware's: printcore's G4 came after the %d ms dwell (%.70s)", job.dwell_ms, line);
        if (!strncmp(line, "RECV: Error", 11) && errors++ < 3) CHECKF(0, "firmware failure: printcore was told %.70s", line);
    }
    if (st == 127 || sig || (text && strstr(text, "Traceback")))
        CHECKF(0, "harness failure: printcore (Debian printrun) %s after %.0f s: %.300s",
               st == 127 ? "could not be started" : sig ? "was killed by a signal" : "crashed", now_s() - t0, text ? text : "");
    else if (pc > 0 && c.early)
        CHECKF(0, "printcore still printing when avr-run ended, after %.0f s", now_s() - t0);
    else if (pc > 0)
        CHECKF(0, "harness failure: printcore still running after %d s (wall clock)", PRINTCORE_WALL_S);
    else
        CHECKF(st == 0, "printcore exited %d after %.0f s: %.300s", st, now_s() - t0, text ? text : "");
    free(text);
    /* G28, G90, M18 and per layer its moves and three lines */
    CHECKF(sent == 3 + 5 * PRINTCORE_LAYERS - 1 && oks >= sent, "printcore sent %d lines, %d acknowledged", sent, oks);
    if (check_case_failed()) return;
    check_gcode_print("build/test_avr/printcore.log", &job, "printcore");
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
    const char *opts[] = {"--z-start", BPRINT_Z_START, "--max-seconds", "300", "--timeout", "1800", NULL};
    cli_result r;
    avr_log l;
    print_report rep;
    zexpect e;
    zsummary s;
    zmove *moves;
    uint64_t *path;
    size_t n = 0;
    uint32_t k;
    long worst, final_pos;
    int32_t peel;
    fw_axis axis;
    char report[256];
    double crc_ns = 0, bin_ns = 0, pass_ns;
    snprintf(report, sizeof report, "%s", cli_path("avr-report.json"));
    if (!avr_start(&c, "build/test_avr/bprint.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    close(c.tty);
    c.tty = 0;
    r = cli_run("print", "examples/models/hand_closed.obj", "--scale", "5", "--port", c.pty, "--exposure", "0.05", "--penetration", "0.1",
                "--bottom-layers", "1", "--bottom-exposure", "0.1", "--peel", "3", "--peel-speed", "10", "--return-speed", "10",
                "--settle", "0.02", "--report", report, NULL);
    CHECKF(r.status == 0, "print exited %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "planned by the printer, identical to the host's plan") != NULL);
    CHECKF(print_pace(r.out, &crc_ns, &bin_ns), "the host did not say the printer's pace: %s", r.out);
    cli_free(&r);
    check_avr_exit(&c, "build/test_avr/bprint.log");
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
    /* the heights: each layer's top, then the peel above it */
    path = (uint64_t *)calloc(2u * rep.layers + 1u, sizeof *path);
    for (k = 0; path && k < rep.layers; k++) {
        path[2 * k] = (uint64_t)rep.tops[k] * rep.bin_nm;
        path[2 * k + 1] = path[2 * k] + BPRINT_PEEL_UM * 1000u;
    }
    avr_expect(&l, &e);
    e.layers = rep.layers;
    e.first = rep.first ? rep.first : 1;
    e.top_bins = rep.tops;
    e.bin_nm = rep.bin_nm;
    e.crcs = NULL; /* no display on this board: the core checks the CRCs */
    e.exposure_ms = rep.exposures;
    e.path_nm = path;
    e.path_len = path ? 2u * rep.layers : 0;
    s = zcheck_record(l.ev, l.events, &e);
    CHECKF(s.shows == rep.layers, "%zu masks shown for %u layers", s.shows, rep.layers);
    CHECKF(path && s.moves >= 2u * rep.layers && s.ramp_windows, "%zu moves from rest and %zu ramp windows checked for %u layers",
           s.moves, s.ramp_windows, rep.layers);
    free(path);
    CHECKF(!l.pass.late && !l.resets, "%lu steps refused as late, %zu resets", l.pass.late, l.resets);
    {
        /* homing's approach: down from the start to the switch, where the
           first step up (the back-off) comes; longer than the host's
           give-up, so the print's success shows the printer answered the
           status polls meanwhile (how fast, in wall time, is the
           machine's: printed, not asserted) */
        size_t up = 0;
        double homing_s;
        while (up < l.steps && l.step_dir[up] < 0) up++;
        homing_s = up < l.steps ? (double)(l.step_at[up] - l.step_at[0]) / BOARD_CPU_HZ : 0;
        CHECKF(homing_s > 3.5, "homing's approach %.2f s", homing_s);
        printf("    avr: homing's approach took %.2f s; the longest wait for a reply %.1f ms\n", homing_s, rep.longest_wait_ms);
    }
    /* Bounded work a pass (fw.h): every pass of the loop, its interrupts
       included (simavr's UART runs at the line's rate), is shorter than
       PASS_MAX, while Z moves (masks streaming) and while it is still
       (planning, the print's start, homing), so the queue never runs dry
       whatever else the loop does. */
    CHECKF(l.pass.worst < PASS_MAX, "a loop pass took %lu cycles (%lu while Z moved), over %lu: the queue covers %lu at the top speed",
           l.pass.worst, l.pass.moving, PASS_MAX, COVER_CYCLES);
    /* The pace IDENTIFY states, which the host waits by: a slice of a held
       frame's work (FW_CRC_BYTES of rows' CRC, FW_PLAN_BINS bins) is one
       pass and another may come between two, so two of the print's worst
       passes, interrupts in, at the part's 16 MHz, must fit a slice's
       allowance. */
    pass_ns = l.pass.worst * 1e9 / BOARD_CPU_HZ;
    CHECKF(2 * pass_ns <= FW_CRC_BYTES * crc_ns && 2 * pass_ns <= FW_PLAN_BINS * bin_ns,
           "the worst pass took %.0f us: two do not fit the %.0f us a slice of %u bytes of CRC (%.0f us a bin: %.0f us for %u) "
           "IDENTIFY states", pass_ns / 1e3, FW_CRC_BYTES * crc_ns / 1e3, (unsigned)FW_CRC_BYTES, bin_ns / 1e3,
           FW_PLAN_BINS * bin_ns / 1e3, (unsigned)FW_PLAN_BINS);
    printf("    avr: IDENTIFY's pace %.0f us a byte of rows' CRC, %.0f us a bin; two worst passes %.0f us, a slice's allowance "
           "%.0f us of CRC, %.0f us of planning\n", crc_ns / 1e3, bin_ns / 1e3, 2 * pass_ns / 1e3, FW_CRC_BYTES * crc_ns / 1e3,
           FW_PLAN_BINS * bin_ns / 1e3);
    check_stack(&l, "binary print");
    printf("    avr: %u layers, %zu steps, worst step %ld cycles from its tick, every exposure exact to the tick; worst loop pass %lu cycles "
           "(%lu while Z moved; the loop's own work %lu, %lu; the queue covers %lu at the top speed), stack peak %lu bytes of %lu reserved\n",
           rep.layers, l.steps, worst, l.pass.worst, l.pass.moving, l.pass.work, l.pass.moving_work, COVER_CYCLES, l.pass.stack,
           l.pass.reserve);
    free(moves);
    print_report_free(&rep);
    free_avr_log(&l);
}

/* The loop hangs as the light goes on (RAMPS_TEST_HANG): the watchdog
   resets the MCU, the reset switches the light off, and it answers again. */
static void watchdog_resets_a_hung_loop(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "2", "--hang-at-uv", "1", "--speed", "5", "--max-seconds", "300", "--timeout", "1800", NULL};
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
    check_avr_exit(&c, "build/test_avr/wdt.log");
    CHECK(read_avr_log("build/test_avr/wdt.log", &l));
    CHECKF(l.uvs >= 2 && l.uv_on[0] && !l.uv_on[1], "%zu UV edges", l.uvs);
    CHECKF(l.resets == 1, "%zu resets", l.resets);
    check_stack(&l, "watchdog");
    if (l.uvs >= 2 && l.resets == 1) {
        double ms = (double)(l.uv_at[1] - l.uv_at[0]) * 1000.0 / BOARD_CPU_HZ;
        /* the watchdog's nominal period; its oscillator is +-10 % */
        CHECKF(l.uv_at[1] == l.reset_at[0] && ms <= BOARD_WDT_MS * 1.1 + 1, "UV off %.2f ms after the hang", ms);
        printf("    avr: the watchdog reset the hung MCU %.2f ms after the light went on\n", ms);
    }
    free_avr_log(&l);
}

/* `n` bytes to the printer (the pty is non-blocking). */
static int send_all_bytes(avr_child *c, const uint8_t *bytes, size_t n)
{
    size_t at = 0;
    double t0 = now_s();
    while (at < n && now_s() - t0 < 60) {
        ssize_t k = write(c->tty, bytes + at, n - at);
        if (k > 0) { at += (size_t)k; continue; }
        if (k < 0 && errno != EAGAIN) return 0;
        { struct timespec ts = {0, 2000000}; nanosleep(&ts, NULL); }
    }
    return at == n;
}

/* HELLO until IDENTIFY answers (5 s at most); 1 with its fields. The port
   is binary from then on, for a few link timeouts. */
static int avr_identify(avr_child *c, link_identify *id)
{
    uint8_t frame[LINK_FRAME_MAX], hello[LINK_SIZE_HELLO];
    link_deframer rx;
    link_hello h;
    size_t n;
    double t0 = now_s(), sent = 0;
    link_deframer_init(&rx, link_mcu_to_host_type);
    h.version = LINK_PROTOCOL_VERSION;
    n = link_frame_build(frame, 1, LINK_MSG_HELLO, hello, link_put_hello(hello, &h));
    while (now_s() - t0 < 5) {
        uint8_t b;
        size_t m;
        if (now_s() - sent > 0.5) { if (write(c->tty, frame, n) != (ssize_t)n) return 0; sent = now_s(); }
        if (read(c->tty, &b, 1) != 1) { struct timespec ts = {0, 2000000}; nanosleep(&ts, NULL); continue; }
        link_deframe_push(&rx, b);
        while ((m = link_deframe_next(&rx)) != 0) {
            int got = rx.buf[2] == LINK_MSG_IDENTIFY && link_get_identify(id, rx.buf + 3, m - LINK_FRAME_MIN);
            link_deframe_consume(&rx);
            if (got) return 1;
        }
    }
    return 0;
}

/* One frame to the image and its answer: `want`'s (STATUS_REPLY's fields
   into *st) or an ACK acknowledging it; 0 when none comes in `seconds`. */
static int avr_request(avr_child *c, uint8_t *seq, uint8_t type, const uint8_t *payload, size_t size, uint8_t want,
                       link_status *st, double seconds)
{
    uint8_t frame[LINK_FRAME_MAX];
    link_deframer rx;
    size_t n = link_frame_build(frame, *seq, type, payload, size), m;
    double t0 = now_s();
    uint8_t expect = (uint8_t)(*seq + 1);
    link_deframer_init(&rx, link_mcu_to_host_type);
    if (!send_all_bytes(c, frame, n)) return 0;
    *seq = expect;
    while (now_s() - t0 < seconds) {
        uint8_t b;
        if (read(c->tty, &b, 1) != 1) { struct timespec ts = {0, 2000000}; nanosleep(&ts, NULL); continue; }
        link_deframe_push(&rx, b);
        while ((m = link_deframe_next(&rx)) != 0) {
            int got = rx.buf[1] == expect && rx.buf[2] == want &&
                      (want != LINK_MSG_STATUS_REPLY || link_get_status(st, rx.buf + 3, m - LINK_FRAME_MIN));
            link_deframe_consume(&rx);
            if (got) return 1;
        }
    }
    return 0;
}

/* STATUS until Z is still (the MOVING flag off), or `seconds` pass. */
static int avr_wait_still(avr_child *c, uint8_t *seq, link_status *st, double seconds)
{
    double t0 = now_s();
    while (now_s() - t0 < seconds) {
        struct timespec ts = {0, 100000000};
        if (!avr_request(c, seq, LINK_MSG_STATUS, NULL, 0, LINK_MSG_STATUS_REPLY, st, 5)) return 0;
        if (!(st->flags & LINK_FLAG_MOVING) && st->state != LINK_STATE_HOMING && st->state != LINK_STATE_MOVING) return 1;
        nanosleep(&ts, NULL);
    }
    return 0;
}

/* A MOVE slower than a step a second (PROTOCOL.md: "under one step a
   second: one step a second"), on the image: 1 um/s is 0.4 of the board's
   steps a second, which the firmware once took for 0 and ran at the top
   speed (a peel asked at 2 um/s ran at 10 mm/s). Three steps up after
   homing: each a second after the one before by the pins' record (16 M
   cycles, less a tick at most, more by the ramps' v/a at most), and the
   image's own STATUS at the target. The image runs at most 5 times real
   time: unpaced, an idle image's virtual time ran through the budget while a
   loaded host was still sending HOME. */
#define SLOW_MOVE_NM 7500u /* three steps of 2.5 um */
static void slow_move_steps_once_a_second(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "1", "--speed", "5", "--max-seconds", "300", "--timeout", "600", NULL};
    link_identify id;
    link_status st;
    link_move mv;
    uint8_t payload[LINK_SIZE_MOVE], seq;
    avr_log l;
    int ok;
    size_t k;
    /* at v = 1 step/s the ramps to and from it at the board's acceleration a
       take v/a seconds in all, which the steps' times may carry */
    const uint64_t second = BOARD_CPU_HZ, tick = CYCLES_PER_TICK, ramps = BOARD_CPU_HZ / BOARD_ACCEL_STEPS_S2 + 1u;
    memset(&st, 0, sizeof st);
    if (!avr_start(&c, "build/test_avr/slow.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    ok = avr_identify(&c, &id);
    CHECKF(ok, "no IDENTIFY");
    seq = 2; /* avr_identify's HELLO was number 1 */
    ok = ok && avr_request(&c, &seq, LINK_MSG_HOME, NULL, 0, LINK_MSG_ACK, NULL, 5) && avr_wait_still(&c, &seq, &st, 120);
    CHECKF(ok && (st.flags & LINK_FLAG_HOMED) && st.error == LINK_ERR_NONE, "homing: state %u, flags %u, error %u",
           (unsigned)st.state, (unsigned)st.flags, (unsigned)st.error);
    mv.z_nm = (int32_t)SLOW_MOVE_NM;
    mv.speed_um_s = 1;
    (void)link_put_move(payload, &mv);
    ok = ok && avr_request(&c, &seq, LINK_MSG_MOVE, payload, sizeof payload, LINK_MSG_ACK, NULL, 5) &&
         avr_wait_still(&c, &seq, &st, 120);
    CHECKF(ok && st.z_nm == (int32_t)SLOW_MOVE_NM && st.error == LINK_ERR_NONE, "the slow move: STATUS says z %ld nm, error %u",
           (long)st.z_nm, (unsigned)st.error);
    check_avr_exit(&c, "build/test_avr/slow.log");
    if (check_case_failed()) return;
    CHECK(read_avr_log("build/test_avr/slow.log", &l));
    if (check_case_failed()) { free_avr_log(&l); return; }
    CHECKF(l.steps > 3, "%zu steps in the record", l.steps);
    for (k = l.steps > 3 ? l.steps - 3 : 0; k < l.steps && k > 0; k++) {
        uint64_t gap = l.step_at[k] - l.step_at[k - 1];
        CHECKF(l.step_dir[k] > 0, "step %zu of the move went down", k);
        if (k > l.steps - 3) /* the first one's gap holds the wait for MOVE as well */
            CHECKF(gap + tick >= second && gap <= second + ramps + tick, "the move's steps %.6f s apart, not a second", (double)gap / second);
    }
    CHECKF(!l.pass.late && !l.resets, "%lu steps refused as late, %zu resets", l.pass.late, l.resets);
    if (l.steps > 3)
        printf("    avr: a move at 1 um/s: its steps %.6f and %.6f s apart\n", (double)(l.step_at[l.steps - 2] - l.step_at[l.steps - 3]) / second,
               (double)(l.step_at[l.steps - 1] - l.step_at[l.steps - 2]) / second);
    free_avr_log(&l);
}

/* M114's "Count Z:" */
static long count_z(const char *got)
{
    const char *at = strstr(got, "Count Z:");
    return at ? strtol(at + 8, NULL, 10) : -1;
}

/* The figures of the image as it runs, against board.h's millimetres worked
   out here in 64 bits (an ATmega2560's int is 16 bits: 200 mm x 400
   steps/mm once wrapped to 36.16 mm): M115's, IDENTIFY's, and moves past
   int16 (81.9 mm) and uint16 (163.8 mm) step counts after homing from
   190 mm, each landing on its step as M114 and the pins' record say. */
#define TRAVEL_START_MM 190
static void running_image_reports_its_figures(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "190", "--max-seconds", "900", "--timeout", "2400", NULL};
    const uint64_t spmm = BOARD_STEPS_PER_MM;
    char got[512] = "";
    double z_max = 0, speed = 0;
    unsigned steps_per_mm = 0, max_ms = 0;
    const char *at;
    link_identify id;
    avr_log l;
    long pos, lowest;
    size_t k;
    int ok;
    if (!avr_start(&c, "build/test_avr/travel.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    ok = gline(&c, "M115", "ok", 10, got, sizeof got);
    at = strstr(got, "echo:Z_MAX_MM:");
    CHECKF(ok && at && sscanf(at, "echo:Z_MAX_MM:%lf STEPS_PER_MM:%u", &z_max, &steps_per_mm) == 2 &&
           (at = strstr(got, "echo:Z_MAX_SPEED_MM_S:")) != NULL &&
           sscanf(at, "echo:Z_MAX_SPEED_MM_S:%lf MAX_EXPOSURE_MS:%u", &speed, &max_ms) == 2, "M115: %.300s", got);
    CHECKF(z_max == (double)BOARD_Z_MAX_MM && steps_per_mm == spmm && speed * 1000 == (double)BOARD_MAX_SPEED_UM_S &&
           max_ms == FW_EXPOSURE_MAX_MS, "M115 says Z_MAX_MM %.3f, %u steps/mm, %.3f mm/s, %u ms; board.h %u mm, %u, %.3f",
           z_max, steps_per_mm, speed, max_ms, (unsigned)BOARD_Z_MAX_MM, (unsigned)spmm, BOARD_MAX_SPEED_UM_S / 1000.0);
    /* homing from 190 mm: 76,000 steps down, past both 16-bit limits */
    got[0] = 0;
    ok = ok && gline(&c, "G28", "ok", 2000, got, sizeof got);
    CHECKF(ok && strstr(got, "Z_move_comp"), "G28 from %d mm: %.300s", TRAVEL_START_MM, got);
    {
        static const int heights[] = {100, 190};
        for (k = 0; ok && k < 2; k++) {
            char line[32];
            snprintf(line, sizeof line, "G1 Z%d", heights[k]);
            got[0] = 0;
            ok = gline(&c, line, "Z_move_comp", 2000, got, sizeof got) && gline(&c, "M114", "ok", 10, got, sizeof got);
            CHECKF(ok && count_z(got) == (long)((uint64_t)heights[k] * spmm), "%s: %.300s", line, got);
        }
    }
    ok = ok && avr_identify(&c, &id);
    CHECKF(ok, "no IDENTIFY");
    if (ok)
        CHECKF(id.z_max_nm == (uint64_t)BOARD_Z_MAX_MM * 1000000u && id.steps_per_mm == spmm && id.tick_hz == BOARD_CLOCK_HZ &&
               id.max_exposure_ms == FW_EXPOSURE_MAX_MS && id.link_timeout_ms == BOARD_LINK_TIMEOUT_MS,
               "IDENTIFY: z_max_nm %u, %u steps/mm, %u Hz, %u ms of light, link %u ms", (unsigned)id.z_max_nm,
               (unsigned)id.steps_per_mm, (unsigned)id.tick_hz, (unsigned)id.max_exposure_ms, (unsigned)id.link_timeout_ms);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    CHECK(read_avr_log("build/test_avr/travel.log", &l));
    if (check_case_failed()) { free_avr_log(&l); return; }
    /* the carriage as the pins moved it: down to the switch, up to 190 mm */
    pos = lowest = l.start_steps;
    for (k = 0; k < l.steps; k++) {
        pos += l.step_dir[k];
        if (pos < lowest) lowest = pos;
    }
    CHECKF(l.start_steps == (long)(TRAVEL_START_MM * spmm) && lowest <= 0 && lowest > -(long)spmm &&
           pos == (long)(190 * spmm) && !l.pass.late && !l.resets,
           "from %ld steps down to %ld, ending at %ld; %lu late, %zu resets", l.start_steps, lowest, pos, l.pass.late, l.resets);
    printf("    avr: homed from %d mm (%ld steps down), moved to 100 and 190 mm; M115 and IDENTIFY: %.0f mm of travel\n",
           TRAVEL_START_MM, l.start_steps - lowest, z_max);
    free_avr_log(&l);
}

/* The cycles of the log's events named `what`, in order. */
static size_t log_events(const char *path, const char *what, uint64_t *at, size_t cap)
{
    FILE *f = fopen(path, "r");
    char line[256], name[32];
    unsigned long long c;
    size_t n = 0;
    if (!f) return 0;
    while (fgets(line, sizeof line, f))
        if (line[0] != '#' && sscanf(line, "%llu %31s", &c, name) == 2 && !strcmp(name, what) && n < cap) at[n++] = c;
    fclose(f);
    return n;
}

/* All of `text` to the printer. */
static int send_all(avr_child *c, const char *text)
{
    return send_all_bytes(c, (const uint8_t *)text, strlen(text));
}

/* `lines` comment lines of 64 bytes into `out`: G-code replies nothing to
   them, and the UART takes them at its line rate (117,647 baud: 5.4 ms a
   line), so they space the lines around them in the printer's own time,
   whatever the host's speed. */
#define PAD_LINE ";padding......................................................\n"
static char *padded(const char *before, int lines, const char *after)
{
    size_t n = strlen(before) + strlen(after) + (size_t)lines * 64 + 1;
    char *text = (char *)malloc(n), *at;
    int k;
    if (!text) return NULL;
    at = text + sprintf(text, "%s", before);
    for (k = 0; k < lines; k++) at += sprintf(at, "%s", PAD_LINE);
    sprintf(at, "%s", after);
    return text;
}

/* G-code's light and stops on the image itself: M106 then a move puts the
   light out first; M106 and a silent host, out after the link timeout; a
   late G4's overrun figure is the pins' (the AVR's 1000u * 1000u wrapped it
   to 1.7 % of the truth); M112 puts the light out within 1 ms of its line
   end (the receive interrupt) and stops the steps within a loop pass (the
   loop reads the line), unhomes Z and refuses M106 until G28;
   the endstop closing during a move (an obstacle at 5 mm) stops it dead.
   Where lines must be apart in time, comment lines space them in the
   printer's time, not the host's. */
#define CYCLES_PER_MS (BOARD_CPU_HZ / 1000u)
#define PAD_LATE_G4 3    /* 16 ms of line */
#define PAD_MOVING 90    /* 0.5 s: Z well into its move */
#define PAD_LIT 18       /* 0.1 s of light before M112 */
static void gcode_light_and_stops(void)
{
    avr_child c;
    /* at most real time: an idle image would spend its virtual budget while
       the test waits (the lines' spacing is the padding's, not the host's) */
    const char *opts[] = {"--z-start", "2", "--obstacle-at", "5", "--speed", "1", "--max-seconds", "900", "--timeout", "1800", NULL};
    const char *log = "build/test_avr/stops.log";
    char got[1024] = "", *text;
    double over = -1;
    const char *at;
    static uint64_t eol[1024];
    size_t eols;
    avr_log l;
    int ok;
    if (!avr_start(&c, log, opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    ok = gline(&c, "G28", "ok", 600, NULL, 0);
    /* light 1: a G4 P0.1 a few comment lines after M106 */
    text = padded("M106 S255\n", PAD_LATE_G4, "G4 P0.1\n");
    ok = ok && text && send_all(&c, text) && gline(&c, NULL, "after its end", 30, got, sizeof got) && gline(&c, NULL, "ok\n", 10, NULL, 0);
    free(text);
    at = strstr(got, "echo:Exposure ran over: G4 came ");
    CHECKF(ok && at && sscanf(at, "echo:Exposure ran over: G4 came %lf ms", &over) == 1 && over > 10, "G4 after M106: %.300s", got);
    /* light 2: M106 then a move */
    got[0] = 0;
    ok = ok && send_all(&c, "M106 S255\nG1 Z20\n") && gline(&c, NULL, "Z_move_comp", 600, got, sizeof got);
    CHECKF(ok && strstr(got, "echo:UV off: Z moves only in the dark"), "M106 then G1: %.300s", got);
    /* light 3: M106 and silence */
    got[0] = 0;
    ok = ok && gline(&c, "M106 S255", "ok", 10, NULL, 0) && gline(&c, NULL, "echo:UV off: the host went silent", 600, got, sizeof got);
    /* the obstacle: the endstop closes at 5 mm on the way down */
    kill(c.pid, SIGUSR1);
    got[0] = 0;
    ok = ok && gline(&c, "G1 Z1", "Error:Z move stopped at ", 600, got, sizeof got);
    CHECKF(ok && strstr(got, "Error:Z endstop closed during a move") && strstr(got, "Error:Z move stopped at "),
           "G1 into the obstacle: %.300s", got);
    got[0] = 0;
    ok = ok && gline(&c, "G1 Z10", "ok", 10, got, sizeof got);
    CHECKF(ok && strstr(got, "Error:Home Z first"), "after the crash: %.300s", got);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    /* M112 mid-move, and M112 with the light on: no step and no light 1 ms
       after its line end; a fresh board without the obstacle */
    {
        const char *opts2[] = {"--z-start", "2", "--speed", "1", "--max-seconds", "900", "--timeout", "1800", NULL};
        if (!avr_start(&c, "build/test_avr/m112.log", opts2)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    }
    got[0] = 0;
    text = padded("G1 Z30\n", PAD_MOVING, "M112\n");
    ok = ok && gline(&c, "G28", "ok", 600, NULL, 0) && text && send_all(&c, text) && gline(&c, NULL, "Emergency stop", 60, NULL, 0) &&
         gline(&c, NULL, "Error:Z move stopped at ", 30, got, sizeof got);
    free(text);
    CHECKF(ok && strstr(got, "Error:Z move stopped at "), "M112 mid-move: %.300s", got);
    text = padded("M106 S255\n", PAD_LIT, "M112\n");
    ok = ok && gline(&c, "G28", "ok", 600, NULL, 0) && text && send_all(&c, text) && gline(&c, NULL, "Emergency stop", 60, NULL, 0) &&
         gline(&c, NULL, "ok\n", 10, NULL, 0);
    free(text);
    got[0] = 0;
    ok = ok && gline(&c, "G1 Z5", "ok", 10, got, sizeof got);
    CHECKF(ok && strstr(got, "Error:Home Z first"), "G1 after M112: %.300s", got);
    got[0] = 0;
    ok = ok && gline(&c, "M106", "ok", 10, got, sizeof got);
    CHECKF(ok && strstr(got, "Error:Stopped: home Z (G28) before UV"), "M106 after M112: %.300s", got);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    if (check_case_failed()) return;

    /* the stops log: the light's three times, and the crash */
    CHECK(read_avr_log(log, &l));
    if (!check_case_failed()) {
        long pos = l.start_steps, lowest_after = 1L << 30;
        size_t k, obstacle = log_events(log, "obstacle", eol, 1024);
        uint64_t obstacle_at = obstacle ? eol[0] : UINT64_MAX;
        double lit[3] = {0, 0, 0};
        CHECKF(l.uvs == 6 && !l.steps_lit, "%zu UV edges, %zu steps with the light on", l.uvs, l.steps_lit);
        for (k = 0; k < 3 && 2 * k + 1 < l.uvs; k++) lit[k] = (double)(l.uv_at[2 * k + 1] - l.uv_at[2 * k]) / CYCLES_PER_MS;
        if (l.uvs == 6) {
            /* the overrun is the light's time less the dwell (the light's
               start waits up to 128 us for Timer4) */
            CHECKF(fabs(lit[0] - 0.1 - over) < 1, "lit %.3f ms for a G4 P0.1 that said %.3f ms over", lit[0], over);
            CHECKF(fabs(lit[2] - BOARD_LINK_TIMEOUT_MS) < 2, "lit %.3f ms with the host silent, the link timeout is %u ms", lit[2],
                   (unsigned)BOARD_LINK_TIMEOUT_MS);
        }
        for (k = 0; k < l.steps; k++) {
            pos += l.step_dir[k];
            if (l.step_at[k] > obstacle_at && pos < lowest_after) lowest_after = pos;
        }
        /* the switch closes at 5 mm: Z stops within the steps queued (and one pass) */
        CHECKF(obstacle && lowest_after >= 5 * (long)BOARD_STEPS_PER_MM - 2 * (long)FW_STEP_QUEUE && !l.pass.late,
               "the carriage went down to %ld steps into an obstacle at %ld", lowest_after, 5 * (long)BOARD_STEPS_PER_MM);
        printf("    avr: lit %.3f ms for a G4 P0.1 that came late (it said %.3f over), %.3f ms with the host silent; "
               "stopped at %.3f mm by an obstacle at 5 mm\n", lit[0], over, lit[2], (double)lowest_after / BOARD_STEPS_PER_MM);
    }
    free_avr_log(&l);
    /* the M112 log: nothing after its line end + 1 ms */
    CHECK(read_avr_log("build/test_avr/m112.log", &l));
    eols = log_events("build/test_avr/m112.log", "rx_eol", eol, 1024);
    /* the lines' ends: G28, G1 Z30, the padding, M112, G28, M106, the
       padding, M112, G1 Z5, M106 */
    CHECKF(eols == 8 + PAD_MOVING + PAD_LIT, "%zu line ends", eols);
    if (!check_case_failed()) {
        uint64_t first = eol[2 + PAD_MOVING], second = eol[5 + PAD_MOVING + PAD_LIT], last_step = 0;
        size_t k, after = 0;
        for (k = 0; k < l.steps; k++) {
            if (l.step_at[k] < eol[3 + PAD_MOVING]) last_step = l.step_at[k];
        }
        /* the light is put out by the receive interrupt; the steps stop
           when the loop reads the line, within a pass (PASS_MAX) */
        for (after = 0, k = 0; k < l.steps; k++)
            if (l.step_at[k] > first + PASS_MAX && l.step_at[k] < eol[3 + PAD_MOVING]) after++;
        CHECKF(!after && last_step > first - 100u * CYCLES_PER_MS, "%zu steps more than a pass after M112's line end", after);
        CHECKF(l.uvs == 2 && l.uv_on[0] && l.uv_at[0] < second && !l.uv_on[1] && l.uv_at[1] > second &&
               l.uv_at[1] < second + CYCLES_PER_MS, "%zu UV edges around the second M112", l.uvs);
        if (l.uvs == 2)
            printf("    avr: M112: the last step %.3f ms after its line end (Z moving); the light out %.3f ms after\n",
                   ((double)last_step - (double)first) / CYCLES_PER_MS, ((double)l.uv_at[1] - (double)second) / CYCLES_PER_MS);
    }
    free_avr_log(&l);
}

/* The stack overruns its room while the light is on (RAMPS_TEST_OVERRUN:
   every byte from the stack pointer down to the canary written, as frames
   that deep would): the loop's next check puts the light out within a
   pass, the printer says it is halted, and afterwards nothing lights or
   moves whatever G-code asks, until reset. */
static void a_stack_overrun_halts_the_printer(void)
{
    avr_child c;
    const char *opts[] = {"--z-start", "2", "--overrun-at-uv", "1", "--speed", "5", "--max-seconds", "300", "--timeout", "60", NULL};
    char got[512] = "";
    avr_log l;
    size_t k, steps_after = 0;
    int ok = 1;
    if (!avr_start(&c, "build/test_avr/overrun.log", opts)) { CHECK(!"build/avr-run did not start"); avr_stop(&c); return; }
    ok &= gline(&c, "G28", "ok", 30, NULL, 0);
    ok &= gline(&c, "M106", "ok", 5, got, sizeof got);
    /* the halt comes as the light goes on, after M106's ok */
    ok &= strstr(got, "Error:Printer halted") || gline(&c, NULL, "Error:Printer halted", 5, got, sizeof got);
    CHECKF(ok, "no word of the halt: %.200s", got);
    got[0] = 0;
    /* G-code's own refusal after a stop (home first); the pins show no light either way */
    CHECKF(gline(&c, "M106 S255", "ok", 5, got, sizeof got) && strstr(got, "Error:Stopped: home Z (G28) before UV"),
           "M106 after the halt: %.200s", got);
    got[0] = 0;
    CHECKF(gline(&c, "G28", "ok", 10, got, sizeof got) && strstr(got, "Error:Printer halted"), "G28 after the halt: %.200s", got);
    got[0] = 0;
    CHECKF(gline(&c, "G1 Z5", "ok", 5, got, sizeof got) && strstr(got, "Error:"), "G1 after the halt: %.200s", got);
    CHECKF(avr_stop(&c) == 0, "avr-run failed");
    CHECK(read_avr_log("build/test_avr/overrun.log", &l));
    if (check_case_failed()) { free_avr_log(&l); return; }
    CHECKF(l.canary_at && l.pass.canary, "avr-run saw no change of the canary");
    CHECKF(l.uvs == 2 && l.uv_on[0] && !l.uv_on[1], "%zu UV edges (one exposure, put out by the halt)", l.uvs);
    if (l.uvs == 2 && l.canary_at) {
        /* within a pass: every pass is shorter than a step interval at the
           top speed (the print tests assert it) */
        CHECKF(l.uv_at[1] >= l.canary_at && l.uv_at[1] - l.canary_at < PASS_MAX,
               "UV off %lld cycles after the canary changed (a pass is under %lu)", (long long)(l.uv_at[1] - l.canary_at),
               (unsigned long)PASS_MAX);
        printf("    avr: the light out %llu cycles after the stack reached the canary\n",
               (unsigned long long)(l.uv_at[1] - l.canary_at));
    }
    for (k = 0; k < l.steps; k++) steps_after += l.step_at[k] > l.canary_at;
    CHECKF(!steps_after && !l.resets, "%zu steps after the halt, %zu resets", steps_after, l.resets);
    /* avr-run measures from the stack's room up: the overrun filled it */
    CHECKF(l.pass.stack >= l.pass.reserve && l.pass.reserve, "stack peak %lu bytes after an overrun of the whole room (%lu reserved)",
           l.pass.stack, l.pass.reserve);
    free_avr_log(&l);
}

void test_avr(void)
{
    if (system("mkdir -p build/test_avr") != 0) { CHECK(!"mkdir build/test_avr"); return; }
    if (!cli_begin("adaslice-avr")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", watchdog_resets_a_hung_loop);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", a_stack_overrun_halts_the_printer);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", gcode_print_nanodlp_style);
    RUN_NEEDING("simavr, avr-gcc and printcore (Debian printrun): build/avr-run, build/fw-ramps-test.elf", gcode_print_by_printcore);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", binary_print_with_masks_streaming);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", running_image_reports_its_figures);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", gcode_light_and_stops);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", slow_move_steps_once_a_second);
    cli_end();
}
