/* fw-sim: the firmware core on a pseudo-terminal, for tests and for trying
   the host tool without a printer. It prints "pty /dev/pts/N" once, then
   serves that terminal like a printer's serial port, and writes what the
   printer's pins would have done to a log, one event per line with the tick
   it was scheduled for:

       # fw-sim tick_hz=10000000 steps_per_mm=400 ... start_steps=12000 ...
       <tick> step +1 <sched> | step -1 <sched>
                                         a step pulse up or down, put out by
                                         the step timer at <tick>, scheduled
                                         for tick <sched>
       <tick> uv 1 | uv 0                the UV light
       <tick> show <slot> <crc32> <lit>  a display buffer on the screen: the
                                         CRC-32 of the whole buffer (8 hex
                                         digits) and its lit pixel count
       <tick> show -1                    the screen dark
       <tick> motor 1 | motor 0          the stepper driver enabled
       <tick> state <state> <flags>      the print state and STATUS flags
                                         (link/messages.h) whenever they change
       <tick> hang                       the loop stops (--hang-at-exposure)
       <tick> halt                       the whole MCU stops (--stop-at-state):
                                         the process stops itself (SIGSTOP)
       <tick> late                       the step timer could not be armed
                                         (--late-step-after-exposure)
       <tick> reset watchdog|signal|pin  the MCU restarts: the watchdog was not
                                         refreshed, SIGUSR1 (a reset button), or
                                         --reset-in-exposure
       <tick> screen <n> <layer> <crc32> <lit>
                                         --watch-screen: at the nth UV-on, the
                                         host's screen file then (its CRC-32
                                         and nonzero bytes; a copy in
                                         FILE.uv<n>) and the printing layer
       <tick> screen lit                 --watch-screen: a step pulse while the
                                         file held a nonzero byte (every pulse
                                         is checked)

   --watch-screen FILE is the observer of a host that shows the layers on
   its own screen (adaslice print --screen file:FILE,...): it reads the file
   itself at the pins' edges, whatever the host says.

   Time is virtual: 10 MHz ticks, running --speed times faster than the wall
   clock, so tests can print with real exposure times in a fraction of the
   time. The clock never runs past the next thing due (a timer interrupt,
   the core's deadline): when the wall has run ahead, because the host
   machine was busy, the simulator holds its clock there and catches up.
   So the sim shows the firmware's own timing, not the host's scheduling;
   the cycle counts of real MCUs come from QEMU and simavr. The timers are
   the MCU's: the step timer calls fw_step_interrupt at the tick it was
   armed for, the UV timer puts the light out at the end it was given, the
   watchdog (--watchdog-ms) restarts the MCU when the core has not
   refreshed it for that long. The Z carriage is modelled: it starts
   --z-start mm above the endstop, which is closed while the carriage is at
   or below its switching point. A restart keeps the carriage where it is,
   turns the pins off (UV, motor, display), and starts the core afresh with
   the next boot id.

   It exits 0 on SIGTERM or SIGINT, with the core's code when the core asks to
   exit (the EXIT message), 2 on a bad command line, 3 when the core misused
   the hardware (a mask row of the wrong size, say: also said on stderr). */
/* posix_openpt, grantpt, unlockpt and ptsname are XSI in POSIX.1-2008 */
#define _XOPEN_SOURCE 700
#include "../../fw.h"
#include "board.h"
#include "../../../link/tty.h"
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>

#define SIM_TICK_HZ 10000000u

static const char USAGE[] =
    "usage: fw-sim [options]\n"
    "Runs the adaslice firmware on a pseudo-terminal; prints \"pty PATH\" and serves it.\n"
    "  --log FILE            the pins' events, one per line                 [none]\n"
    "  --speed S             virtual time runs S times the wall clock (>= 1) [1]\n"
    "  --display WxH         display pixels                                  [2560x1440]\n"
    "  --bits 1|8            bits per pixel                                  [1]\n"
    "  --pitch-um P          pixel pitch, micrometres                        [50]\n"
    "  --z-start MM          carriage height above the endstop at start      [30]\n"
    "  --steps-per-mm N      Z steps per millimetre                          [400]\n"
    "  --max-speed MM/S      Z speed limit                                   [10]\n"
    "  --accel MM/S2         Z acceleration                                  [50]\n"
    "  --home-speed MM/S     homing's approach speed                         [5]\n"
    "  --z-max MM            soft limit above the endstop                    [200]\n"
    "  --home-travel MM      the longest homing approach                     [220]\n"
    "  --max-bins N          the planner's largest profile                   [12000]\n"
    "  --window N            frames the host may have unacknowledged         [8]\n"
    "  --link-timeout-ms MS  wall-clock silence that pauses a print          [1000]\n"
    "  --watchdog-ms MS      the watchdog's period, virtual time              [250]\n"
    "  --hang-at-exposure N  the loop hangs as the Nth exposure begins (tests) [never]\n"
    "  --stop-at-state S     the MCU halts (the process stops itself, SIGSTOP: nothing\n"
    "                        read or sent, no timer) when its print state first becomes S\n"
    "                        (link/messages.h: 1 homing, 3 planning, 5 printing) (tests) [never]\n"
    "  --reset-in-exposure N the MCU resets two fifths into the Nth exposure (tests) [never]\n"
    "  --late-step-after-exposure N\n"
    "                        the first step after the Nth exposure cannot be armed in\n"
    "                        time: a STEP_LATE fault (tests)                  [never]\n"
    "  --boot-id N           the first boot id (then one more each restart)   [random]\n"
    "  --watch-screen FILE   the host's screen file, read at every UV-on and step (tests) [none]\n"
    "  --help                this text\n";

typedef struct sim_options {
    const char *log_path, *watch_screen;
    double speed;
    unsigned long width, height, bits;
    double pitch_um, z_start, steps_per_mm, max_speed, accel, home_speed, z_max, home_travel;
    unsigned long max_bins, window, link_timeout_ms, watchdog_ms, boot_id;
    unsigned long hang_at_exposure, late_after_exposure, reset_in_exposure;
    long stop_at_state;
} sim_options;

/* The printer's hardware: the display buffers, the carriage, the log. */
typedef struct sim {
    fw_config config;
    FILE *log;
    int master;
    uint64_t now;                /* the clock: the tick of what runs now */
    uint64_t step_at;            /* the step timer's compare, FW_NEVER disarmed */
    uint64_t uv_off_at;          /* the UV timer's end, FW_NEVER while dark */
    uint64_t watchdog_at;        /* the watchdog bites then, FW_NEVER off */
    uint64_t watchdog_ticks;     /* its period */
    fw_state *fw;
    unsigned long exposures;     /* UV turned on, since the start */
    unsigned long hang_at;       /* the loop hangs at this exposure (0 never) */
    int hang;                    /* ... which has begun */
    long stop_at_state;          /* the MCU halts in this state (-1 never) */
    unsigned long late_after;    /* a step arm fails after this exposure (0 never) */
    unsigned long reset_in;      /* the MCU resets during this exposure (0 never) ... */
    uint64_t reset_at;           /* ... then, FW_NEVER before it begins */
    int32_t true_position;       /* steps above the endstop's switching point */
    uint8_t *display[2];
    size_t stride;               /* bytes per display row */
    int exit_requested, exit_code;
    int faults;                  /* the core misused the hardware */
    int logged_state, logged_flags;
    const char *watch_path;      /* --watch-screen */
    int watch_fd;
    unsigned char *watch_map;
    size_t watch_size;
    unsigned long lit_steps;     /* step pulses under a lit screen file */
} sim;

static volatile sig_atomic_t stop_signal, reset_signal;

static void on_signal(int sig)
{
    if (sig == SIGUSR1) reset_signal = 1;
    else stop_signal = sig;
}

/* ------------------------------------------------------------ the clock */

static struct timespec clock_start;
static double clock_speed = 1.0;
static uint64_t clock_held;      /* ticks the clock was held back for, in all */

static double wall_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - clock_start.tv_sec) * 1e9 + (double)(t.tv_nsec - clock_start.tv_nsec);
}

/* Ticks of 100 ns of virtual time: doubles are exact to 2^53 ticks (28
   years), and the product is monotonic in the wall clock. */
static uint64_t virtual_now(void)
{
    return (uint64_t)(wall_ns() * clock_speed / (1e9 / SIM_TICK_HZ)) - clock_held;
}

/* The clock, never past `due`: what is due runs at its own tick. */
static uint64_t clock_at_most(uint64_t due)
{
    uint64_t t = virtual_now();
    if (t <= due) return t;
    clock_held += t - due;
    return due;
}

/* poll's timeout until tick `deadline` in whole milliseconds, rounded down
   (the loop looks again); 0 below one: a sleep is that coarse, and the
   steps of a move come faster than that at high --speed, so the loop spins
   for them instead. -1 (no timeout) for FW_NEVER. */
static int wall_timeout_ms(uint64_t deadline, uint64_t now)
{
    double ms;
    if (deadline == FW_NEVER) return -1;
    if (deadline <= now) return 0;
    ms = (double)(deadline - now) * (1e3 / SIM_TICK_HZ) / clock_speed;
    return ms >= 1000.0 ? 1000 : (int)ms;
}

/* ------------------------------------------------------------ the hardware */

static void log_line(sim *s, uint64_t when, const char *event)
{
    if (s->log) fprintf(s->log, "%llu %s\n", (unsigned long long)when, event);
}

static void fault(sim *s, const char *what);

/* --watch-screen: the file mapped as it is now (remapped when its size
   changes: the host sizes it when it opens it); NULL while it is empty or
   missing. */
static const unsigned char *screen_view(sim *s, size_t *size)
{
    struct stat st;
    if (s->watch_fd < 0) s->watch_fd = open(s->watch_path, O_RDONLY);
    if (s->watch_fd < 0 || fstat(s->watch_fd, &st) != 0) { *size = 0; return NULL; }
    if ((size_t)st.st_size != s->watch_size) {
        if (s->watch_map) munmap(s->watch_map, s->watch_size);
        s->watch_map = NULL;
        s->watch_size = (size_t)st.st_size;
        if (s->watch_size) {
            void *m = mmap(NULL, s->watch_size, PROT_READ, MAP_SHARED, s->watch_fd, 0);
            s->watch_map = m == MAP_FAILED ? NULL : (unsigned char *)m;
        }
    }
    *size = s->watch_map ? s->watch_size : 0;
    return s->watch_map;
}

static size_t nonzero_bytes(const unsigned char *b, size_t n)
{
    size_t k, lit = 0;
    for (k = 0; k < n; k++) lit += b[k] != 0;
    return lit;
}

/* At a UV-on: what the screen file holds, logged, and kept as FILE.uv<n>. */
static void watch_uv_on(sim *s)
{
    size_t n;
    const unsigned char *b;
    char copy[512];
    FILE *f;
    if (!s->watch_path || !s->log) return;
    b = screen_view(s, &n);
    fprintf(s->log, "%llu screen %lu %lu %08lx %zu\n", (unsigned long long)s->now, s->exposures,
            (unsigned long)s->fw->layer, (unsigned long)adaslice_crc32(0, b, n), b ? nonzero_bytes(b, n) : 0);
    snprintf(copy, sizeof copy, "%s.uv%lu", s->watch_path, s->exposures);
    if (b && (f = fopen(copy, "wb")) != NULL) {
        if (fwrite(b, 1, n, f) != n) fault(s, "could not copy the screen file");
        fclose(f);
    }
}

/* At a step pulse: the screen file must be dark. */
static void watch_step(sim *s)
{
    size_t n, k;
    const unsigned char *b;
    if (!s->watch_path) return;
    static const unsigned char zero[4096];
    b = screen_view(s, &n);
    for (k = 0; k < n; k += sizeof zero)
        if (memcmp(b + k, zero, n - k < sizeof zero ? n - k : sizeof zero)) break;
    if (k < n && s->lit_steps++ < 1000) log_line(s, s->now, "screen lit");
}

/* Blocks while the host is not reading (a UART waits the same way), but
   gives up once a signal asks the sim to stop: the master is non-blocking
   so that a stop can never hang in write(). */
static void hw_write(void *ctx, const uint8_t *data, size_t size)
{
    sim *s = (sim *)ctx;
    /* whatever happened before a reply is in the log when the host sees it */
    if (s->log) fflush(s->log);
    while (size && !stop_signal) {
        ssize_t n = write(s->master, data, size);
        if (n > 0) {
            data += n;
            size -= (size_t)n;
        } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            struct pollfd p;
            p.fd = s->master;
            p.events = POLLOUT;
            p.revents = 0;
            poll(&p, 1, 100);
        } else if (!(n < 0 && errno == EINTR)) {
            return;
        }
    }
}

static int hw_step_arm(void *ctx, uint64_t when, int dir)
{
    sim *s = (sim *)ctx;
    (void)dir;
    if (when != FW_NEVER && when < s->now) return 0;
    /* --late-step-after-exposure: once, as a timer that cannot be armed in time */
    if (when != FW_NEVER && s->late_after && s->exposures >= s->late_after && s->uv_off_at == FW_NEVER) {
        s->late_after = 0;
        log_line(s, s->now, "late");
        return 0;
    }
    s->step_at = when;
    return 1;
}

static void hw_step_pulse(void *ctx, int dir)
{
    sim *s = (sim *)ctx;
    const fw_steps *q = &s->fw->steps;
    s->true_position += dir;
    watch_step(s);
    if (s->log)
        fprintf(s->log, "%llu step %+d %llu\n", (unsigned long long)s->now, dir,
                (unsigned long long)q->tick[q->tail % FW_STEP_QUEUE]);
}

static int hw_endstop(void *ctx)
{
    return ((sim *)ctx)->true_position <= 0;
}

static void hw_uv(void *ctx, int on, uint64_t when, uint64_t until)
{
    sim *s = (sim *)ctx;
    if (on) {
        s->uv_off_at = until;
        if (++s->exposures == s->hang_at) s->hang = 1;
        if (s->exposures == s->reset_in) s->reset_at = when + (until - when) * 2u / 5u;
    } else if (s->uv_off_at == FW_NEVER) return; /* its timer put it out already */
    else if (when > s->now) { /* the timer puts it out */
        if (when < s->uv_off_at) s->uv_off_at = when;
        return;
    } else s->uv_off_at = FW_NEVER;
    /* the tick the light really changes: an end already past (a G4 that
       came after its dwell) puts it out now, and the log must show it on
       until then */
    log_line(s, when > s->now ? when : s->now, on ? "uv 1" : "uv 0");
    if (on) watch_uv_on(s);
}

static void hw_watchdog(void *ctx)
{
    sim *s = (sim *)ctx;
    s->watchdog_at = s->now + s->watchdog_ticks;
}

static void hw_motor(void *ctx, int on)
{
    sim *s = (sim *)ctx;
    log_line(s, s->now, on ? "motor 1" : "motor 0");
}

/* The core asked the hardware for something it cannot do: said once per
   kind on stderr, and the exit status says it. */
static void fault(sim *s, const char *what)
{
    if (s->faults++ < 10) fprintf(stderr, "fw-sim: at tick %llu the core %s\n", (unsigned long long)s->now, what);
}

static void hw_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    sim *s = (sim *)ctx;
    char why[128];
    if (slot != 0 && slot != 1) {
        snprintf(why, sizeof why, "wrote a mask row to display buffer %d (there are 0 and 1)", slot);
        fault(s, why);
    } else if (y >= s->config.display_height) {
        snprintf(why, sizeof why, "wrote mask row %lu of a display %u rows high", (unsigned long)y,
                 (unsigned)s->config.display_height);
        fault(s, why);
    } else if (size != s->stride) {
        snprintf(why, sizeof why, "wrote a mask row of %lu bytes; the display's rows are %zu", (unsigned long)size,
                 s->stride);
        fault(s, why);
    } else {
        memcpy(s->display[slot] + (size_t)y * s->stride, row, size);
    }
}

static unsigned long lit_pixels(const sim *s, const uint8_t *buf)
{
    unsigned long lit = 0;
    uint32_t x, y, w = s->config.display_width;
    for (y = 0; y < s->config.display_height; y++, buf += s->stride) {
        for (x = 0; x < w; x++) {
            if (s->config.display_bits == 8) lit += buf[x] != 0;
            else lit += (buf[x / 8u] >> (7u - x % 8u)) & 1u;
        }
    }
    return lit;
}

static void hw_show(void *ctx, int slot, uint64_t when)
{
    sim *s = (sim *)ctx;
    if (slot == -1) {
        log_line(s, when, "show -1");
    } else if (slot == 0 || slot == 1) {
        uint32_t crc = adaslice_crc32(0, s->display[slot], s->stride * s->config.display_height);
        if (s->log)
            fprintf(s->log, "%llu show %d %08lx %lu\n", (unsigned long long)when, slot, (unsigned long)crc,
                    lit_pixels(s, s->display[slot]));
    } else {
        char why[64];
        snprintf(why, sizeof why, "showed display buffer %d (there are 0 and 1)", slot);
        fault(s, why);
    }
}

static void hw_exit(void *ctx, int code)
{
    sim *s = (sim *)ctx;
    s->exit_requested = 1;
    s->exit_code = code;
}

/* The STATUS a host would see, logged when it changes: lets a test find the
   pauses in the record of pins. */
static void log_state(sim *s, const fw_state *fw)
{
    int flags = 0;
    char line[32];
    if (fw->axis.homed) flags |= LINK_FLAG_HOMED;
    if (fw->uv_on) flags |= LINK_FLAG_UV;
    if (fw_axis_busy(&fw->axis)) flags |= LINK_FLAG_MOVING;
    if (fw->paused_by_link) flags |= LINK_FLAG_LINK_LOST;
    if (fw->state == s->logged_state && flags == s->logged_flags) return;
    s->logged_state = fw->state;
    s->logged_flags = flags;
    snprintf(line, sizeof line, "state %d %d", fw->state, flags);
    log_line(s, s->now, line);
    /* --stop-at-state: a halted MCU (a debugger's halt, QEMU's stop), until SIGCONT */
    if (fw->state == s->stop_at_state) {
        s->stop_at_state = -1;
        log_line(s, s->now, "halt");
        if (s->log) fflush(s->log);
        raise(SIGSTOP);
    }
}

/* A start of the MCU: at power-up (why NULL) and at each reset. The pins
   fall back to off before the core starts again with the next boot id. */
static void restart(sim *s, fw_state *fw, const fw_port *port, uint64_t *workspace, size_t ws_bytes, const char *why)
{
    if (why) {
        char line[32];
        snprintf(line, sizeof line, "reset %s", why);
        log_line(s, s->now, line);
        if (s->uv_off_at != FW_NEVER) log_line(s, s->now, "uv 0");
        log_line(s, s->now, "show -1");
        log_line(s, s->now, "motor 0");
        s->config.boot_id++;
    }
    s->step_at = s->uv_off_at = s->reset_at = FW_NEVER;
    s->watchdog_at = s->watchdog_ticks ? s->now + s->watchdog_ticks : FW_NEVER;
    s->logged_state = s->logged_flags = -1;
    memset(workspace, 0, ws_bytes);
    fw_init(fw, &s->config, port, workspace, ws_bytes);
}

/* --------------------------------------------------------- the command line */

static int bad_value(const char *option, const char *value, const char *want)
{
    fprintf(stderr, "fw-sim: %s %s: expected %s (fw-sim --help lists the options)\n", option, value, want);
    return 0;
}

static int parse_number(const char *option, const char *value, double lo, double hi, double *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(value, &end);
    if (end == value || *end || errno || !(v >= lo && v <= hi)) {
        char want[96];
        snprintf(want, sizeof want, "a number from %g to %g", lo, hi);
        return bad_value(option, value, want);
    }
    *out = v;
    return 1;
}

static int parse_whole(const char *option, const char *value, unsigned long lo, unsigned long hi, unsigned long *out)
{
    char *end;
    unsigned long v;
    errno = 0;
    v = strtoul(value, &end, 10);
    if (end == value || *end || errno || value[0] == '-' || value[0] == '+' || v < lo || v > hi) {
        char want[96];
        snprintf(want, sizeof want, "a whole number from %lu to %lu", lo, hi);
        return bad_value(option, value, want);
    }
    *out = v;
    return 1;
}

static int parse_display(const char *value, unsigned long *w, unsigned long *h)
{
    char *end, *end2;
    errno = 0;
    if (value[0] < '0' || value[0] > '9') return bad_value("--display", value, "WxH in pixels, as 2560x1440");
    *w = strtoul(value, &end, 10);
    if (*end != 'x' || end[1] < '0' || end[1] > '9') return bad_value("--display", value, "WxH in pixels, as 2560x1440");
    *h = strtoul(end + 1, &end2, 10);
    if (*end2 || errno || *w < 1 || *h < 1 || *w > 65535 || *h > 65535)
        return bad_value("--display", value, "WxH in pixels, each 1 to 65535");
    return 1;
}

/* 1 when the options are usable; otherwise says why on stderr. */
static int parse_options(int argc, char **argv, sim_options *o)
{
    int i;
    o->log_path = NULL;
    o->watch_screen = NULL;
    o->speed = 1;
    o->width = 2560;
    o->height = 1440;
    o->bits = 1;
    o->pitch_um = 50;
    o->z_start = 30;
    o->steps_per_mm = 400;
    o->max_speed = 10;
    o->accel = 50;
    o->home_speed = 5;
    o->z_max = 200;
    o->home_travel = 220;
    o->max_bins = 12000;
    o->window = 8;
    o->link_timeout_ms = 1000;
    o->watchdog_ms = 250;
    o->hang_at_exposure = 0;
    o->late_after_exposure = 0;
    o->reset_in_exposure = 0;
    o->stop_at_state = -1;
    o->boot_id = 0;
    for (i = 1; i < argc; i++) {
        const char *opt = argv[i], *v;
        int ok;
        if (!strcmp(opt, "--help") || !strcmp(opt, "-h")) {
            fputs(USAGE, stdout);
            exit(0);
        }
        if (strncmp(opt, "--", 2) != 0) {
            fprintf(stderr, "fw-sim: unexpected argument %s: options start with -- (fw-sim --help lists them)\n", opt);
            return 0;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "fw-sim: %s needs a value (fw-sim --help lists the options)\n", opt);
            return 0;
        }
        v = argv[++i];
        if (!strcmp(opt, "--log")) { o->log_path = v; ok = 1; }
        else if (!strcmp(opt, "--speed")) ok = parse_number(opt, v, 1, 1e6, &o->speed);
        else if (!strcmp(opt, "--display")) ok = parse_display(v, &o->width, &o->height);
        else if (!strcmp(opt, "--bits")) {
            ok = parse_whole(opt, v, 1, 8, &o->bits);
            if (ok && o->bits != 1 && o->bits != 8) ok = bad_value(opt, v, "1 or 8");
        }
        else if (!strcmp(opt, "--pitch-um")) ok = parse_number(opt, v, 0.001, 4e6, &o->pitch_um);
        else if (!strcmp(opt, "--z-start")) ok = parse_number(opt, v, -1000, 10000, &o->z_start);
        else if (!strcmp(opt, "--steps-per-mm")) ok = parse_number(opt, v, 1, 100000, &o->steps_per_mm);
        else if (!strcmp(opt, "--max-speed")) ok = parse_number(opt, v, 0.001, 10000, &o->max_speed);
        else if (!strcmp(opt, "--accel")) ok = parse_number(opt, v, 0.001, 1e6, &o->accel);
        else if (!strcmp(opt, "--home-speed")) ok = parse_number(opt, v, 0.001, 10000, &o->home_speed);
        else if (!strcmp(opt, "--z-max")) ok = parse_number(opt, v, 0.001, 10000, &o->z_max);
        else if (!strcmp(opt, "--home-travel")) ok = parse_number(opt, v, 0.001, 10000, &o->home_travel);
        else if (!strcmp(opt, "--max-bins")) ok = parse_whole(opt, v, 1, 1000000000ul, &o->max_bins);
        else if (!strcmp(opt, "--window")) ok = parse_whole(opt, v, 1, 255, &o->window);
        else if (!strcmp(opt, "--link-timeout-ms")) ok = parse_whole(opt, v, 1, 3600000ul, &o->link_timeout_ms);
        else if (!strcmp(opt, "--watchdog-ms")) ok = parse_whole(opt, v, 1, 3600000ul, &o->watchdog_ms);
        else if (!strcmp(opt, "--hang-at-exposure")) ok = parse_whole(opt, v, 1, 0xFFFFFFFFul, &o->hang_at_exposure);
        else if (!strcmp(opt, "--late-step-after-exposure")) ok = parse_whole(opt, v, 1, 0xFFFFFFFFul, &o->late_after_exposure);
        else if (!strcmp(opt, "--reset-in-exposure")) ok = parse_whole(opt, v, 1, 0xFFFFFFFFul, &o->reset_in_exposure);
        else if (!strcmp(opt, "--stop-at-state")) {
            unsigned long st;
            ok = parse_whole(opt, v, 0, LINK_STATE_COUNT - 1, &st);
            o->stop_at_state = (long)st;
        }
        else if (!strcmp(opt, "--watch-screen")) { o->watch_screen = v; ok = 1; }
        else if (!strcmp(opt, "--boot-id")) ok = parse_whole(opt, v, 1, 0xFFFFFFFFul, &o->boot_id);
        else {
            fprintf(stderr, "fw-sim: unknown option %s (fw-sim --help lists the options)\n", opt);
            return 0;
        }
        if (!ok) return 0;
    }
    return 1;
}

/* The core's configuration from the options, in its units (steps, nm, ms of
   virtual time); 0 and a message when the numbers do not fit them. */
static int make_config(const sim_options *o, fw_config *c)
{
    double spm = floor(o->steps_per_mm + 0.5);
    double steps_max = 2147483647.0;
    double max_steps = floor(o->z_max * spm + 0.5), travel = floor(o->home_travel * spm + 0.5);
    double max_speed = floor(o->max_speed * spm + 0.5), accel = floor(o->accel * spm + 0.5);
    double home_speed = floor(o->home_speed * spm + 0.5);
    double timeout = (double)o->link_timeout_ms * o->speed;
    size_t stride = o->bits == 1 ? (o->width + 7u) / 8u : o->width;
    memset(c, 0, sizeof *c);
    if (spm != o->steps_per_mm) {
        fprintf(stderr, "fw-sim: --steps-per-mm %g: the core takes a whole number of steps per mm\n", o->steps_per_mm);
        return 0;
    }
    if (max_steps > steps_max || travel > steps_max) {
        fprintf(stderr, "fw-sim: --z-max and --home-travel must stay under %.0f steps at %g steps/mm\n", steps_max, spm);
        return 0;
    }
    if (max_speed < 1 || accel < 1 || home_speed < 1 || max_speed > 4e9 || accel > 4e9 || home_speed > 4e9) {
        fprintf(stderr, "fw-sim: --max-speed, --accel and --home-speed must each come to 1 to 4e9 steps at %g steps/mm\n", spm);
        return 0;
    }
    if (stride > FW_ROW_BYTES) {
        fprintf(stderr, "fw-sim: --display %lux%lu at %lu-bit: rows of %zu bytes; the core takes at most %u\n",
                o->width, o->height, o->bits, stride, (unsigned)FW_ROW_BYTES);
        return 0;
    }
    if (timeout > 4e9) {
        fprintf(stderr, "fw-sim: --link-timeout-ms %lu at --speed %g is more virtual time than the core counts\n",
                o->link_timeout_ms, o->speed);
        return 0;
    }
    c->tick_hz = SIM_TICK_HZ;
    c->axis.steps_per_mm = (uint32_t)spm;
    c->axis.max_speed = (uint32_t)max_speed;
    c->axis.accel = (uint32_t)accel;
    c->axis.home_speed = (uint32_t)home_speed;
    c->axis.max_steps = (int32_t)max_steps;
    c->axis.home_travel = (int32_t)travel;
    c->display_width = (uint16_t)o->width;
    c->display_height = (uint16_t)o->height;
    c->display_bits = (uint8_t)o->bits;
    c->pitch_nm = (uint32_t)floor(o->pitch_um * 1000 + 0.5);
    c->max_bins = (uint32_t)o->max_bins;
    /* A silent host is silent in wall-clock time; the core counts virtual. */
    c->link_timeout_ms = (uint32_t)timeout;
    c->window = (uint8_t)o->window;
    c->watchdog_ms = (uint32_t)o->watchdog_ms;
    /* a real step timer needs time to be armed; the sim's does not, but
       moves start as late as on a board */
    c->step_lead = SIM_TICK_HZ / 5000u;
    c->crc_byte_ns = BOARD_CRC_BYTE_NS;
    c->plan_bin_ns = BOARD_PLAN_BIN_NS;
    return 1;
}

/* ------------------------------------------------------------ the terminal */

/* Opens a pty; keeps its slave side open too, so that while no host has it
   open the master does not report a hangup (poll would spin on it) and the
   line settings stay. Returns the slave's fd, -1 on failure. */
static int open_pty(int *master, char *name, size_t name_size)
{
    const char *path;
    int slave;
    *master = posix_openpt(O_RDWR | O_NOCTTY);
    if (*master < 0) return -1;
    if (grantpt(*master) != 0 || unlockpt(*master) != 0 || !(path = ptsname(*master))) return -1;
    if (strlen(path) >= name_size) return -1;
    strcpy(name, path);
    if (fcntl(*master, F_SETFL, fcntl(*master, F_GETFL) | O_NONBLOCK) != 0) return -1;
    slave = open(name, O_RDWR | O_NOCTTY);
    if (slave < 0) return -1;
    /* no echo: the core would read its own replies */
    if (tty_raw(slave, 0) != 0) return -1;
    return slave;
}

/* Gives the host a moment to read the last reply before the pty goes away
   with us: up to a second while the slave still holds unread bytes. */
static void let_host_read(int slave)
{
#ifdef FIONREAD
    int i, pending = 0;
    for (i = 0; i < 100; i++) {
        struct timespec pause = {0, 10000000};
        if (ioctl(slave, FIONREAD, &pending) != 0 || pending <= 0) return;
        nanosleep(&pause, NULL);
    }
#else
    (void)slave;
#endif
}

/* ------------------------------------------------------------------- main */

static uint64_t plan_workspace_for(size_t bytes, uint64_t **ws)
{
    *ws = (uint64_t *)calloc((bytes + 7u) / 8u, 8u);
    return *ws ? bytes : 0;
}

int main(int argc, char **argv)
{
    sim_options opt;
    static sim s;
    static fw_state fw;
    fw_port port;
    uint64_t *workspace = NULL, deadline = 0;
    int hung = 0;
    static uint8_t rx[4096]; /* read from the terminal: rx[held .. have) not taken yet */
    size_t have = 0, held = 0;
    size_t ws_bytes;
    char name[128];
    int slave;
    struct sigaction sa;

    if (!parse_options(argc, argv, &opt) || !make_config(&opt, &s.config)) return 2;
    s.stride = opt.bits == 1 ? (opt.width + 7u) / 8u : opt.width;
    s.display[0] = (uint8_t *)calloc(s.stride * opt.height, 1);
    s.display[1] = (uint8_t *)calloc(s.stride * opt.height, 1);
    ws_bytes = plan_workspace_for(FW_PLAN_WORKSPACE(opt.max_bins), &workspace);
    if (!s.display[0] || !s.display[1] || !ws_bytes) {
        fprintf(stderr, "fw-sim: out of memory for a %lux%lu display and %lu bins\n", opt.width, opt.height, opt.max_bins);
        return 1;
    }
    if (opt.log_path && !(s.log = fopen(opt.log_path, "w"))) {
        fprintf(stderr, "fw-sim: --log %s: %s\n", opt.log_path, strerror(errno));
        return 2;
    }
    s.true_position = (int32_t)floor(opt.z_start * s.config.axis.steps_per_mm + 0.5);
    s.logged_state = s.logged_flags = -1;
    if (s.log)
        fprintf(s.log, "# fw-sim tick_hz=%lu steps_per_mm=%lu max_speed=%lu accel=%lu home_speed=%lu max_steps=%ld "
                "home_travel=%ld start_steps=%ld display=%lux%lu bits=%lu pitch_nm=%lu speed=%g\n",
                (unsigned long)s.config.tick_hz, (unsigned long)s.config.axis.steps_per_mm,
                (unsigned long)s.config.axis.max_speed, (unsigned long)s.config.axis.accel,
                (unsigned long)s.config.axis.home_speed, (long)s.config.axis.max_steps, (long)s.config.axis.home_travel,
                (long)s.true_position, opt.width, opt.height, opt.bits, (unsigned long)s.config.pitch_nm, opt.speed);

    slave = open_pty(&s.master, name, sizeof name);
    if (slave < 0) {
        fprintf(stderr, "fw-sim: cannot open a pseudo-terminal: %s\n", strerror(errno));
        return 1;
    }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0; /* no SA_RESTART: a blocked poll or write returns to check */
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGUSR1, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);

    port.ctx = &s;
    port.write = hw_write;
    port.step_arm = hw_step_arm;
    port.step_pulse = hw_step_pulse;
    port.endstop = hw_endstop;
    port.uv = hw_uv;
    port.motor = hw_motor;
    port.mask_row = hw_mask_row;
    port.show = hw_show;
    port.watchdog = hw_watchdog;
    port.exit = hw_exit;
    s.fw = &fw;
    s.watchdog_ticks = (uint64_t)opt.watchdog_ms * (SIM_TICK_HZ / 1000u);
    s.config.boot_id = opt.boot_id ? (uint32_t)opt.boot_id : (uint32_t)(time(NULL) ^ (getpid() << 16)) | 1u;
    s.hang_at = opt.hang_at_exposure;
    s.late_after = opt.late_after_exposure;
    s.reset_in = opt.reset_in_exposure;
    s.stop_at_state = opt.stop_at_state;
    s.watch_path = opt.watch_screen;
    s.watch_fd = -1;
    clock_speed = opt.speed;
    clock_gettime(CLOCK_MONOTONIC, &clock_start);
    restart(&s, &fw, &port, workspace, ws_bytes, NULL);

    printf("pty %s\n", name);
    fflush(stdout);

    while (!stop_signal && !s.exit_requested) {
        struct pollfd p;
        int r, timeout;
        uint64_t due = s.step_at < s.uv_off_at ? s.step_at : s.uv_off_at;
        if (s.watchdog_at < due) due = s.watchdog_at;
        if (s.reset_at < due) due = s.reset_at;
        if (!hung && deadline < due) due = deadline;
        if (due < s.now) due = s.now; /* overdue: now, never back in time */
        s.now = clock_at_most(due);
        /* the interrupts first, as on an MCU: they preempt the loop */
        if (s.now >= s.uv_off_at) {
            s.uv_off_at = FW_NEVER;
            log_line(&s, s.now, "uv 0");
            continue;
        }
        if (s.now >= s.step_at) {
            s.step_at = FW_NEVER;
            fw_step_interrupt(&fw);
            continue;
        }
        if (s.now >= s.watchdog_at || s.now >= s.reset_at || reset_signal) {
            restart(&s, &fw, &port, workspace, ws_bytes, reset_signal ? "signal" : s.now >= s.reset_at ? "pin" : "watchdog");
            reset_signal = 0;
            hung = s.hang = 0;
            s.hang_at = 0;
            deadline = 0;
            continue;
        }
        if (!hung && s.hang) {
            hung = 1;
            log_line(&s, s.now, "hang");
            continue;
        }
        if (!hung && s.now >= deadline) {
            deadline = fw_run(&fw, s.now);
            log_state(&s, &fw);
            continue;
        }
        if (!hung && held < have) { /* bytes the core did not take yet */
            held += fw_receive(&fw, rx + held, have - held, s.now);
            if (held == have) held = have = 0;
            log_state(&s, &fw);
            /* what the bytes asked for may be due before the old deadline */
            deadline = s.now;
            continue;
        }
        timeout = wall_timeout_ms(due, s.now);
        if (timeout && s.log) fflush(s.log);
        p.fd = s.master;
        /* a hung loop reads nothing: the bytes wait in the terminal */
        p.events = hung ? 0 : POLLIN;
        p.revents = 0;
        r = poll(&p, 1, timeout);
        if (r < 0 && errno != EINTR) {
            fprintf(stderr, "fw-sim: poll: %s\n", strerror(errno));
            break;
        }
        if (r > 0 && (p.revents & POLLIN)) {
            ssize_t n;
            /* what fell due while waiting runs first, as its interrupt would */
            if (virtual_now() >= due) continue;
            n = read(s.master, rx, sizeof rx);
            if (n > 0) {
                s.now = clock_at_most(due);
                have = (size_t)n;
                held = 0;
            }
        }
    }
    if (s.exit_requested) let_host_read(slave);
    if (s.log && fclose(s.log) != 0) {
        fprintf(stderr, "fw-sim: writing --log %s: %s\n", opt.log_path, strerror(errno));
        return 1;
    }
    close(slave);
    close(s.master);
    free(workspace);
    free(s.display[0]);
    free(s.display[1]);
    if (s.faults) return 3;
    return s.exit_requested ? s.exit_code : 0;
}
