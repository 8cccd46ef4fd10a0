/* The host's screen (host/print/screen.h) and adaslice print --screen on the
   simulator. The screen is a file laid out as a framebuffer
   (--screen file:PATH,WxH,BPP,packing: the drawing code of /dev/fb0 over
   an mmap of the file); the observer is fw-sim --watch-screen, which reads
   the file itself at the printer's pin edges: at every UV-on it logs the
   layer and keeps a copy of the file, at every step pulse it checks that
   the file is all zero. The copies are unpacked here by a reference of our
   own (the packing as the issue states it, pixel by pixel, the turn and
   mirror applied forwards), and their CRC-32 compared with the job's
   masks.rle: the host's own claims take no part. */
#define _XOPEN_SOURCE 700
#include "cli_run.h"
#include "wait.h"
#include "print_report.h"
#include "../adaslice.h"
#include "../host/print/screen.h"
#include "../link/messages.h"
#include <errno.h>
#include <math.h>
#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <time.h>

#define SIM_BIN "build/fw-sim"
#define JOB_SHAPE "--pixels", "240x200", "--pitch", "0.1", "--penetration", "0.1", "--bottom-layers", "2", "--peel", "2", \
                  "--peel-speed", "10", "--return-speed", "10", "--settle", "0.05"
#define JOB_ARGS "--scale", "15", JOB_SHAPE, "--exposure", "0.1"

/* ------------------------------------------------------ the reference */

/* A framebuffer pixel's red, green and blue, 0..255: 24 and 32 bpp hold
   blue, green, red (, unused) bytes; 16 bpp is RGB 5:6:5, little-endian. */
static void fb_rgb(const unsigned char *fb, unsigned fbw, unsigned bpp, unsigned x, unsigned y, unsigned rgb[3])
{
    const unsigned char *p = fb + ((size_t)y * fbw + x) * (bpp / 8);
    if (bpp == 16) {
        unsigned v = p[0] | (unsigned)p[1] << 8;
        rgb[0] = (v >> 11) * 255 / 31;
        rgb[1] = ((v >> 5) & 63) * 255 / 63;
        rgb[2] = (v & 31) * 255 / 31;
    } else {
        rgb[0] = p[2];
        rgb[1] = p[1];
        rgb[2] = p[0];
    }
}

typedef struct fb_layout { unsigned w, h, bpp, packing, rotate, mirror; } fb_layout;

/* The panel's mono pixel (px, py): gray, one a screen pixel (R = G = B,
   else 999); rgb / bgr, three a screen pixel from its red / blue subpixel. */
static unsigned panel_value(const unsigned char *fb, const fb_layout *f, unsigned px, unsigned py)
{
    unsigned rgb[3];
    if (f->packing == SCREEN_GRAY) {
        fb_rgb(fb, f->w, f->bpp, px, py, rgb);
        return rgb[0] == rgb[1] && rgb[1] == rgb[2] ? rgb[0] : 999;
    }
    fb_rgb(fb, f->w, f->bpp, px / 3, py, rgb);
    return f->packing == SCREEN_RGB ? rgb[px % 3] : rgb[2 - px % 3];
}

/* Where the mask's pixel (x, y) of w x h lands: mirrored, then turned
   clockwise. */
static void to_panel(const fb_layout *f, unsigned w, unsigned h, unsigned x, unsigned y, unsigned *px, unsigned *py)
{
    if (f->mirror == SCREEN_MIRROR_X) x = w - 1 - x;
    if (f->mirror == SCREEN_MIRROR_Y) y = h - 1 - y;
    switch (f->rotate) {
    case 1: *px = h - 1 - y; *py = x; break;
    case 2: *px = w - 1 - x; *py = h - 1 - y; break;
    case 3: *px = y; *py = w - 1 - x; break;
    default: *px = x; *py = y; break;
    }
}

/* The mask a framebuffer shows, rows as the job's (1-bit MSB first, or
   8-bit), into mask; the count of pixels that are not a mask's value (a
   1-bit mask's are 0 and 255). */
static size_t unpack(const unsigned char *fb, const fb_layout *f, unsigned w, unsigned h, int bits, unsigned char *mask)
{
    size_t stride = bits == 8 ? w : (w + 7) / 8, bad = 0;
    unsigned x, y;
    memset(mask, 0, stride * h);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            unsigned px, py, v;
            to_panel(f, w, h, x, y, &px, &py);
            v = panel_value(fb, f, px, py);
            if (bits == 8) { if (v > 255) bad++; else mask[y * stride + x] = (unsigned char)v; }
            else if (v == 255) mask[y * stride + x / 8] |= (unsigned char)(0x80u >> (x % 8));
            else if (v != 0) bad++;
        }
    return bad;
}


static int all_zero(const char *path)
{
    size_t n, k;
    unsigned char *b = read_whole_file(path, &n);
    for (k = 0; b && k < n && !b[k]; k++) {}
    free(b);
    return b && n && k == n;
}

/* ------------------------------------------------------ drawing */

/* The mask drawn on a file screen by the tool's code, the file's bytes back. */
static unsigned char *drawn(const char *spec, const screen_options *o_in, const unsigned char *mask, size_t stride,
                            unsigned w, unsigned h, int bits, size_t *size)
{
    screen s;
    screen_options o = *o_in;
    char path[512];
    const char *comma = strchr(spec, ',');
    unsigned char *b = NULL;
    o.device = spec;
    *size = 0;
    snprintf(path, sizeof path, "%.*s", (int)(comma - spec - 5), spec + 5);
    remove(path);
    if (screen_open(&s, &o) != 0) { CHECKF(0, "screen_open %s failed", spec); return NULL; }
    CHECK(screen_show(&s, mask, stride, w, h, bits) == 0);
    b = read_whole_file(path, size);
    screen_close(&s);
    return b;
}

static void check_bytes(const unsigned char *got, size_t n, const unsigned char *want, size_t m, const char *what)
{
    size_t k;
    char g[128] = "", *at = g;
    CHECKF(got && n == m && !memcmp(got, want, m), "%s: %zu bytes, want %zu", what, n, m);
    if (got && n == m && memcmp(got, want, m)) {
        for (k = 0; k < n && at < g + sizeof g - 4; k++) at += sprintf(at, "%02x ", got[k]);
        CHECKF(0, "%s: got %s", what, g);
    }
}

/* A 6 x 2 mask by hand: rows 101100 and 010011. */
static void packing_by_hand(void)
{
    static const unsigned char mask[2] = {0xb0, 0x4c};
    static const unsigned char rgb24[] = {0xff, 0x00, 0xff, 0x00, 0x00, 0xff, 0x00, 0xff, 0x00, 0xff, 0xff, 0x00};
    static const unsigned char bgr24[] = {0xff, 0x00, 0xff, 0xff, 0x00, 0x00, 0x00, 0xff, 0x00, 0x00, 0xff, 0xff};
    static const unsigned char rgb16[] = {0x1f, 0xf8, 0x00, 0xf8, 0xe0, 0x07, 0xff, 0x07};
    /* mirrored: 001101 and 110010 */
    static const unsigned char rgb24x[] = {0xff, 0x00, 0x00, 0xff, 0x00, 0xff, 0x00, 0xff, 0xff, 0x00, 0xff, 0x00};
    /* turned 90 degrees clockwise onto a 2 x 6 gray panel: row y is column x
       of the mask bottom row first (the top row is the right column) */
    static const unsigned char turned[6][2] = {{0, 1}, {1, 0}, {0, 1}, {0, 1}, {1, 0}, {1, 0}};
    unsigned char gray32[6 * 2 * 4];
    screen_options o;
    unsigned char *b;
    size_t n;
    int k;
    memset(&o, 0, sizeof o);
    o.packing = -1;
    {
        char spec[600];
        snprintf(spec, sizeof spec, "file:%s,2x2,24,rgb", cli_path("fb6x2"));
        b = drawn(spec, &o, mask, 1, 6, 2, 1, &n);
        check_bytes(b, n, rgb24, sizeof rgb24, "rgb, 24 bpp");
        free(b);
        snprintf(spec, sizeof spec, "file:%s,2x2,24,bgr", cli_path("fb6x2"));
        b = drawn(spec, &o, mask, 1, 6, 2, 1, &n);
        check_bytes(b, n, bgr24, sizeof bgr24, "bgr, 24 bpp");
        free(b);
        snprintf(spec, sizeof spec, "file:%s,2x2,16", cli_path("fb6x2"));
        o.packing = SCREEN_RGB; /* --screen-packing over the spec's default */
        b = drawn(spec, &o, mask, 1, 6, 2, 1, &n);
        check_bytes(b, n, rgb16, sizeof rgb16, "rgb, 16 bpp");
        free(b);
        snprintf(spec, sizeof spec, "file:%s,2x2,24,rgb", cli_path("fb6x2"));
        o.mirror = SCREEN_MIRROR_X;
        b = drawn(spec, &o, mask, 1, 6, 2, 1, &n);
        check_bytes(b, n, rgb24x, sizeof rgb24x, "rgb, 24 bpp, mirrored");
        free(b);
        for (k = 0; k < 12; k++) {
            unsigned v = turned[k / 2][k % 2] ? 0xff : 0;
            gray32[4 * k] = gray32[4 * k + 1] = gray32[4 * k + 2] = (unsigned char)v;
            gray32[4 * k + 3] = 0;
        }
        snprintf(spec, sizeof spec, "file:%s,2x6,32,gray", cli_path("fb6x2"));
        o.mirror = SCREEN_MIRROR_NONE;
        o.packing = -1;
        o.rotate = 1;
        b = drawn(spec, &o, mask, 1, 6, 2, 1, &n);
        check_bytes(b, n, gray32, sizeof gray32, "gray, 32 bpp, turned 90");
        free(b);
    }
}

/* A whole layer of random pixels, 1-bit and 8-bit, through every packing,
   depth, turn and mirror, unpacked back by the reference: the same mask. */
static void full_layer_unpacked_back(void)
{
    enum { W = 240, H = 201 };
    static const struct { unsigned bpp, packing, rotate, mirror; int bits; } cases[] = {
        {24, SCREEN_RGB, 0, 0, 1}, {32, SCREEN_BGR, 0, 0, 1}, {16, SCREEN_RGB, 2, 1, 1}, {24, SCREEN_GRAY, 1, 0, 1},
        {32, SCREEN_GRAY, 3, 2, 1}, {24, SCREEN_RGB, 1, 1, 1}, {32, SCREEN_GRAY, 0, 0, 8}, {24, SCREEN_RGB, 3, 2, 8},
        {32, SCREEN_BGR, 2, 0, 8}, {24, SCREEN_GRAY, 1, 1, 8},
    };
    unsigned char *mask = (unsigned char *)malloc(W * H), *back = (unsigned char *)malloc(W * H);
    unsigned c, seed = 12345;
    size_t k;
    if (!mask || !back) { free(mask); free(back); CHECK(!"out of memory"); return; }
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        fb_layout f;
        screen_options o;
        char spec[600];
        size_t stride = cases[c].bits == 8 ? W : (W + 7) / 8, n, bad;
        unsigned pw = cases[c].rotate & 1 ? H : W, ph = cases[c].rotate & 1 ? W : H;
        unsigned char *b;
        if (cases[c].packing != SCREEN_GRAY && pw % 3) continue;
        for (k = 0; k < stride * H; k++) {
            seed = seed * 1103515245u + 12345u;
            mask[k] = (unsigned char)(seed >> 16);
        }
        f.w = cases[c].packing == SCREEN_GRAY ? pw : pw / 3;
        f.h = ph;
        f.bpp = cases[c].bpp;
        f.packing = cases[c].packing;
        f.rotate = cases[c].rotate;
        f.mirror = cases[c].mirror;
        memset(&o, 0, sizeof o);
        o.packing = (int)f.packing;
        o.rotate = (int)f.rotate;
        o.mirror = (int)f.mirror;
        snprintf(spec, sizeof spec, "file:%s,%ux%u,%u", cli_path("fbfull"), f.w, f.h, f.bpp);
        b = drawn(spec, &o, mask, stride, W, H, cases[c].bits, &n);
        CHECKF(b && n == (size_t)f.w * f.h * f.bpp / 8, "case %u: %zu bytes", c, n);
        if (!b || n != (size_t)f.w * f.h * f.bpp / 8) { free(b); continue; }
        bad = unpack(b, &f, W, H, cases[c].bits, back);
        if (cases[c].bits == 8 && f.bpp == 16) bad = 0;
        CHECKF(!bad && !memcmp(mask, back, stride * H) &&
               adaslice_crc32(0, mask, stride * H) == adaslice_crc32(0, back, stride * H),
               "case %u (%u bpp, packing %u, turn %u, mirror %u, %d-bit): %zu odd pixels, the mask %s", c, f.bpp,
               f.packing, f.rotate, f.mirror, cases[c].bits, bad, memcmp(mask, back, stride * H) ? "differs" : "is back");
        free(b);
    }
    free(mask);
    free(back);
}

/* ------------------------------------------------------ on the simulator */

typedef struct child { pid_t pid; int out; char line[256]; } child;

/* argv[0] started, its stdout read until "pty PATH" (in c->line). */
static int start_child(child *c, char *const argv[])
{
    int fds[2];
    size_t len = 0;
    double waited = 0;
    memset(c, 0, sizeof *c);
    if (pipe(fds) != 0) return 0;
    fflush(NULL);
    if ((c->pid = fork()) == 0) {
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
    while (waited < 10000) {
        struct pollfd p;
        char ch;
        p.fd = c->out; p.events = POLLIN; p.revents = 0;
        if (poll(&p, 1, 100) <= 0) { waited += 100; continue; }
        if (read(c->out, &ch, 1) != 1) break;
        if (ch != '\n') { if (len + 1 < sizeof c->line) c->line[len++] = ch; continue; }
        c->line[len] = 0;
        if (!strncmp(c->line, "pty ", 4)) return 1;
        len = 0;
    }
    CHECKF(0, "%s did not start (make builds it)", argv[0]);
    return 0;
}

/* fw-sim with the test display, watching `watch`. */
static int start_sim(child *c, const char *log, const char *speed, const char *watch, const char *const *extra)
{
    char *argv[24];
    int n = 0;
    argv[n++] = (char *)SIM_BIN; argv[n++] = (char *)"--log"; argv[n++] = (char *)log;
    argv[n++] = (char *)"--speed"; argv[n++] = (char *)speed; argv[n++] = (char *)"--display"; argv[n++] = (char *)"240x200";
    argv[n++] = (char *)"--pitch-um"; argv[n++] = (char *)"100"; argv[n++] = (char *)"--watch-screen"; argv[n++] = (char *)watch;
    while (extra && *extra && n < 22) argv[n++] = (char *)*extra++;
    argv[n] = NULL;
    return start_child(c, argv);
}

static int stop_sim(child *c)
{
    int st = 0;
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGTERM);
    waitpid(c->pid, &st, 0);
    close(c->out);
    c->pid = 0;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The CRC-32 of each layer's mask in JOB/masks.rle (the job's own record),
   and the display. */
typedef struct job_crcs { unsigned w, h, bits, layers; uint32_t *crc; } job_crcs;

static int read_job(const char *dir, job_crcs *j)
{
    char path[600];
    size_t n, at = 44;
    unsigned char *b;
    unsigned k;
    snprintf(path, sizeof path, "%s/masks.rle", dir);
    b = read_whole_file(path, &n);
    memset(j, 0, sizeof *j);
    if (!b || n < 44 || memcmp(b, "ADASMSK2", 8)) { free(b); return 0; }
#define U32(p) ((uint32_t)(p)[0] | (uint32_t)(p)[1] << 8 | (uint32_t)(p)[2] << 16 | (uint32_t)(p)[3] << 24)
    j->w = U32(b + 8); j->h = U32(b + 12); j->bits = U32(b + 16); j->layers = U32(b + 20);
    j->crc = (uint32_t *)calloc(j->layers + 1u, sizeof *j->crc);
    for (k = 0; j->crc && k < j->layers && at + 16 <= n; k++) {
        j->crc[k] = U32(b + at + 8);
        at += 16 + U32(b + at + 12);
    }
#undef U32
    free(b);
    return j->crc && k == j->layers;
}

/* What the observer saw: each UV-on's layer and whether the screen file
   then held exactly that layer's mask; lit step pulses; pauses. */
typedef struct seen {
    unsigned exposures, right, wrong, steps, lit_steps, user_pauses, uv_after_pause;
    unsigned *layer_of;              /* the layer of each UV-on, 1-based */
    char first_wrong[160];
} seen;

static int observe(const char *log_path, const char *watch, const fb_layout *f, const job_crcs *j, seen *s)
{
    size_t n;
    char *text, *line, *save = NULL;
    unsigned char *mask = (unsigned char *)malloc((size_t)j->w * j->h);
    int paused = 0;
    memset(s, 0, sizeof *s);
    text = (char *)read_whole_file(log_path, &n);
    if (!text || !mask) { free(text); free(mask); return 0; }
    text[n] = 0;
    s->layer_of = (unsigned *)calloc(4096, sizeof *s->layer_of);
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        unsigned long long when;
        unsigned long nth, layer;
        char what[16];
        if (sscanf(line, "%llu %15s", &when, what) != 2) continue;
        if (!strcmp(what, "step")) s->steps++;
        else if (!strcmp(what, "uv") && strstr(line, " uv 1") && paused) s->uv_after_pause++;
        else if (!strcmp(what, "state")) {
            unsigned st = 0, fl = 0;
            sscanf(line, "%*u %*s %u %u", &st, &fl);
            if (st == 6 && !paused && !(fl & 8)) s->user_pauses++;
            paused = st == 6;
        } else if (!strcmp(what, "screen") && !strcmp(strstr(line, "screen") + 7, "lit")) {
            s->lit_steps++;
        } else if (!strcmp(what, "screen") && sscanf(line, "%*u %*s %lu %lu", &nth, &layer) == 2) {
            char copy[600];
            size_t m, stride = j->bits == 8 ? j->w : (j->w + 7) / 8;
            unsigned char *fb;
            uint32_t crc;
            size_t bad;
            s->exposures++;
            if (!layer) layer = nth; /* avr-run does not see the layer: a print straight through */
            if (nth < 4096) s->layer_of[nth] = (unsigned)layer;
            snprintf(copy, sizeof copy, "%s.uv%lu", watch, nth);
            fb = read_whole_file(copy, &m);
            if (!fb || m != (size_t)f->w * f->h * f->bpp / 8 || !layer || layer > j->layers) {
                s->wrong++;
                if (!s->first_wrong[0])
                    snprintf(s->first_wrong, sizeof s->first_wrong, "UV-on %lu (layer %lu): the screen file was %zu bytes", nth,
                             layer, m);
                free(fb);
                continue;
            }
            bad = unpack(fb, f, j->w, j->h, (int)j->bits, mask);
            crc = adaslice_crc32(0, mask, stride * j->h);
            if (!bad && crc == j->crc[layer - 1]) s->right++;
            else {
                s->wrong++;
                if (!s->first_wrong[0])
                    snprintf(s->first_wrong, sizeof s->first_wrong, "UV-on %lu (layer %lu): the screen held %08x (%zu odd "
                             "pixels); the job's layer is %08x", nth, layer, (unsigned)crc, bad, (unsigned)j->crc[layer - 1]);
            }
            free(fb);
        }
    }
    free(text);
    free(mask);
    return 1;
}

static int slice_job(const char *dir, const char *aa)
{
    cli_result r = aa ? cli_run("slice", "examples/models/hand_closed.obj", JOB_ARGS, "--bottom-exposure", "0.5", "--aa", aa,
                                "-o", dir, NULL)
                      : cli_run("slice", "examples/models/hand_closed.obj", JOB_ARGS, "--bottom-exposure", "0.5", "-o", dir,
                                NULL);
    int ok = r.status == 0;
    CHECKF(ok, "slice: %s", r.err);
    cli_free(&r);
    return ok;
}

/* The job the stop tests print: each layer lit for 1.5 s of the printer's
   time, 150 ms of the wall's at fw-sim --speed 10, longer than the 100 ms
   in which a stop must darken the screen: a screen that goes dark that
   soon after a stop that came while it was lit was put out by the stop,
   not by the layer's own end. A smaller part than the others' (34 layers)
   keeps the time down. */
static int slice_long_job(const char *dir)
{
    cli_result r = cli_run("slice", "examples/models/hand_closed.obj", "--scale", "8", JOB_SHAPE, "--exposure", "1.5",
                           "--bottom-exposure", "1.5", "-o", dir, NULL);
    int ok = r.status == 0;
    CHECKF(ok, "slice: %s", r.err);
    cli_free(&r);
    return ok;
}

/* The bound: the screen dark within this of a stop. */
#define DARK_WITHIN_MS 100

/* pid (0: this thread) at the lowest real-time priority, or the case
   fails saying why (without CAP_SYS_NICE), naming `who`. */
static int realtime(pid_t pid, const char *who)
{
    struct sched_param p;
    memset(&p, 0, sizeof p);
    p.sched_priority = sched_get_priority_min(SCHED_FIFO);
    if (sched_setscheduler(pid, SCHED_FIFO, &p) == 0) return 1;
    CHECKF(0, "the screen's stop tests run %s at real-time priority (SCHED_FIFO): run them as root or give run_tests "
              "CAP_SYS_NICE (%s)", who, strerror(errno));
    return 0;
}

/* The observer (this thread: it stops the host or the printer and polls
   the screen file) at real-time priority while it watches, so that what
   it measures is the tool's reaction and not its own turn on a loaded
   machine; back to normal after. */
static int observer_realtime(int on)
{
    struct sched_param p;
    memset(&p, 0, sizeof p);
    if (!on) return sched_setscheduler(0, SCHED_OTHER, &p) == 0;
    return realtime(0, "the observer that times the dark screen");
}

/* The simulator stands for the printer's MCU, a processor of its own: at
   real-time priority (it blocks in poll between events) it answers the
   host's STATUS and HELLO as promptly on a loaded machine as an MCU would,
   so that a stop's time measures the host (itself real-time when it
   prints on a screen) and not the simulator's turn. */
static int simulator_realtime(const child *sim)
{
    return realtime(sim->pid, "the simulator, an MCU of its own,");
}

/* Polls the screen file every ms until it is lit (want_lit) or dark; the
   ms that took from t0 (seconds_now), or -1 after limit_s. */
static double ms_until(const char *fb, int want_lit, double t0, double limit_s)
{
    while (seconds_now() - t0 < limit_s) {
        if (all_zero(fb) != want_lit) return (seconds_now() - t0) * 1000;
        sleep_ms(1);
    }
    return -1;
}

/* adaslice (args: the command and its arguments) in the background, its stdout into out_path and its
   stderr into a pipe the test filled beforehand: the host's first word on
   stderr (a stop's message) blocks until the test reads the pipe. A host
   that said its stop before it put the screen out would then hold the
   screen lit, so the order (dark first, then the message) is checked, not
   raced. *err is the pipe's end to drain (drain_held). */
static pid_t run_held(char *const args[], const char *out_path, int *err)
{
    char *argv[32], fill[4096];
    int fds[2], n = 0, flags;
    pid_t pid;
    *err = -1;
    if (pipe(fds) != 0) return -1;
    argv[n++] = (char *)cli_tool;
    while (*args && n < 31) argv[n++] = *args++;
    argv[n] = NULL;
    memset(fill, '.', sizeof fill);
    flags = fcntl(fds[1], F_GETFL);
    fcntl(fds[1], F_SETFL, flags | O_NONBLOCK);
    while (write(fds[1], fill, sizeof fill) > 0) {}
    while (write(fds[1], fill, 1) > 0) {}
    fcntl(fds[1], F_SETFL, flags);
    fflush(NULL);
    if ((pid = fork()) == 0) {
        int o = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644), null = open("/dev/null", O_RDONLY);
        dup2(null, 0);
        dup2(o, 1);
        dup2(fds[1], 2);
        close(fds[0]);
        close(fds[1]);
        execv(cli_tool, argv);
        _exit(127);
    }
    close(fds[1]);
    *err = fds[0];
    return pid;
}

/* The held host's stderr past the filler (malloc'd), and its exit status
   in *status (-1 if it did not exit within 30 s). */
static char *drain_held(pid_t pid, int err, int *status)
{
    size_t n = 0, cap = 1 << 17;
    char *text = (char *)malloc(cap + 1), *from;
    double t0 = seconds_now();
    ssize_t k;
    *status = -1;
    fcntl(err, F_SETFL, fcntl(err, F_GETFL) | O_NONBLOCK);
    while (text && seconds_now() - t0 < 30) {
        int st;
        if ((k = read(err, text + n, cap - n)) > 0) { n += (size_t)k; if (n < cap) continue; }
        if (*status < 0 && waitpid(pid, &st, WNOHANG) == pid) *status = WIFEXITED(st) ? WEXITSTATUS(st) : 128;
        /* the guard holds stderr a little longer: its end is the pipe's */
        if (k == 0 || n == cap) break;
        sleep_ms(5);
    }
    if (*status < 0) *status = wait_exit(pid, 1);
    close(err);
    if (!text) return NULL;
    text[n] = 0;
    for (from = text; *from == '.'; from++) {}
    memmove(text, from, strlen(from) + 1);
    return text;
}

/* The job printed with its masks on a file screen, 80 x 200 at 24 bpp, three
   mono pixels a screen pixel (a mono panel): at every UV-on the file held
   exactly the layer's mask, every layer once and in order; not one step
   under a lit screen; dark at the end. */
static void print_shows_each_layer(void)
{
    child sim;
    job_crcs j;
    seen s;
    char spec[600];
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0};
    cli_result r;
    unsigned k, in_order = 1;
    if (!slice_job(cli_path("job"), NULL) || !read_job(cli_path("job"), &j)) { CHECK(!"no job"); return; }
    remove(cli_path("fb"));
    if (!start_sim(&sim, cli_path("sim.log"), "100", cli_path("fb"), NULL)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fb"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 0 && strstr(r.out, "shown on"), "print --screen: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    CHECK(all_zero(cli_path("fb")));
    CHECK(observe(cli_path("sim.log"), cli_path("fb"), &f, &j, &s));
    CHECKF(s.exposures == j.layers && s.right == j.layers && !s.wrong, "%u UV-ons for %u layers, %u right, %u wrong: %s",
           s.exposures, j.layers, s.right, s.wrong, s.first_wrong);
    for (k = 1; k <= s.exposures && k < 4096; k++) in_order &= s.layer_of[k] == k;
    CHECK(in_order);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    free(s.layer_of);
    free(j.crc);
}

/* A MODEL printed with --screen: the printer plans, the host renders each
   layer as it is needed and shows it. The masks are the host's own here
   (its --report's CRCs, not a slicer's file), so this checks the
   rendering path's placement on the screen; the observer still reads the
   screen itself. */
static void model_print_shows_each_layer(void)
{
    child sim;
    job_crcs j;
    print_report rep;
    seen s;
    char spec[600];
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0};
    cli_result r;
    remove(cli_path("fbm"));
    if (!start_sim(&sim, cli_path("simm.log"), "100", cli_path("fbm"), NULL)) return;
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbm"));
    r = cli_run("print", "examples/models/hand_closed.obj", "--scale", "15", "--port", sim.line + 4, "--exposure", "0.1",
                "--penetration", "0.1", "--bottom-layers", "2", "--bottom-exposure", "0.5", "--peel", "2", "--peel-speed", "10",
                "--return-speed", "10", "--settle", "0.05", "--screen", spec, "--report", cli_path("repm.json"), NULL);
    CHECKF(r.status == 0 && strstr(r.out, "planned by the printer"), "print MODEL --screen: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    if (!read_print_report(cli_path("repm.json"), &rep)) { CHECK(!"no report"); return; }
    j.w = 240; j.h = 200; j.bits = 1; j.layers = rep.layers; j.crc = rep.crcs;
    CHECK(observe(cli_path("simm.log"), cli_path("fbm"), &f, &j, &s));
    CHECKF(s.exposures == j.layers && s.right == j.layers, "%u UV-ons for %u layers, %u right: %s", s.exposures, j.layers,
           s.right, s.first_wrong);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    CHECK(all_zero(cli_path("fbm")));
    free(s.layer_of);
    print_report_free(&rep);
}

/* An anti-aliased (8-bit) job on a gray 32 bpp screen turned a quarter and
   mirrored: grey levels, exactly. */
static void aa_job_on_a_turned_gray_screen(void)
{
    child sim;
    job_crcs j;
    seen s;
    char spec[600];
    fb_layout f = {200, 240, 32, SCREEN_GRAY, 1, SCREEN_MIRROR_X};
    const char *extra[] = {"--bits", "8", NULL};
    cli_result r;
    if (!slice_job(cli_path("jobaa"), "4") || !read_job(cli_path("jobaa"), &j)) { CHECK(!"no job"); return; }
    CHECK(j.bits == 8);
    remove(cli_path("fbaa"));
    if (!start_sim(&sim, cli_path("simaa.log"), "100", cli_path("fbaa"), extra)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,200x240,32", cli_path("fbaa"));
    r = cli_run("print", cli_path("jobaa"), "--port", sim.line + 4, "--screen", spec, "--screen-rotate", "90",
                "--screen-mirror", "x", "--screen-pitch", "100", NULL);
    CHECKF(r.status == 0, "print --screen: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    CHECK(observe(cli_path("simaa.log"), cli_path("fbaa"), &f, &j, &s));
    CHECKF(s.exposures == j.layers && s.right == j.layers, "%u UV-ons for %u layers, %u right: %s", s.exposures, j.layers,
           s.right, s.first_wrong);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    free(s.layer_of);
    free(j.crc);
}

/* A screen without the job's pixels or pitch is refused before anything
   moves, naming both. */
static void wrong_screen_is_refused(void)
{
    child sim;
    char spec[600];
    cli_result r;
    if (!slice_job(cli_path("job"), NULL)) return;
    if (!start_sim(&sim, cli_path("simw.log"), "100", cli_path("fbw"), NULL)) return;
    snprintf(spec, sizeof spec, "file:%s,100x200,24,rgb", cli_path("fbw"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 1 && strstr(r.err, "the job's masks are 240 x 200 px; the screen") && strstr(r.err, "shows 300 x 200 px"),
           "%d %s", r.status, r.err);
    cli_free(&r);
    /* a file of its own: fbw is now a 100 x 200 screen's image, which an 80 x 200 one does not draw on */
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbw80"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, "--screen-pitch", "50", NULL);
    CHECKF(r.status == 1 && strstr(r.err, "the job's pixels are 100 um") && strstr(r.err, "are 50 um"), "%d %s", r.status, r.err);
    cli_free(&r);
    /* the printer's pitch is 100 um too: the job's own, from its manifest */
    {
        char mpath[600], *m, *at;
        size_t mn;
        FILE *out;
        snprintf(mpath, sizeof mpath, "%s/manifest.json", cli_path("job"));
        m = (char *)read_whole_file(mpath, &mn);
        if (m) m[mn] = 0;
        at = m ? strstr(m, "\"pitch_mm\": [0.1, 0.1]") : NULL;
        CHECK(at != NULL);
        if (at) {
            memcpy(at, "\"pitch_mm\": [0.2, 0.1]", 22);
            if ((out = fopen(mpath, "wb")) != NULL) { CHECK(fwrite(m, 1, mn, out) == mn); fclose(out); }
            r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, "--screen-pitch", "100", NULL);
            /* the printer's own pitch (IDENTIFY) is checked first: oblong job
               pixels on square ones are refused there, naming both */
            CHECKF(r.status == 1 && strstr(r.err, "sliced for pixels of 0.2 x 0.1 mm") && strstr(r.err, "0.1 mm pixels") &&
                       strstr(r.err, "50 % across and 100 % down"),
                   "%d %s", r.status, r.err);
            cli_free(&r);
            memcpy(at, "\"pitch_mm\": [0.1, 0.1]", 22);
            if ((out = fopen(mpath, "wb")) != NULL) { CHECK(fwrite(m, 1, mn, out) == mn); fclose(out); }
        }
        free(m);
    }
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", "file:nowhere", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "file:PATH,WxH,BPP"), "%d %s", r.status, r.err);
    cli_free(&r);
    /* "32junk" is not 32, nor "+80" 80 */
    snprintf(spec, sizeof spec, "file:%s,80x200,24junk", cli_path("fbjunk"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 2 && strstr(r.err, "file:PATH,WxH,BPP"), "%d %s", r.status, r.err);
    cli_free(&r);
    snprintf(spec, sizeof spec, "file:%s,+80x200,24", cli_path("fbjunk"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 2 && strstr(r.err, "file:PATH,WxH,BPP"), "%d %s", r.status, r.err);
    cli_free(&r);
    /* a file that is not a screen's image of this size (the job's own
       masks.rle, named by mistake) is left as it was: it was zeroed and grown */
    {
        char masks[560];
        size_t before_n = 0, after_n = 0;
        unsigned char *before, *after;
        snprintf(masks, sizeof masks, "%s/masks.rle", cli_path("job"));
        before = read_whole_file(masks, &before_n);
        snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", masks);
        r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "masks.rle") && strstr(r.err, "left alone"), "%d %s",
               r.status, r.err);
        cli_free(&r);
        after = read_whole_file(masks, &after_n);
        CHECKF(before && after && before_n == after_n && !memcmp(before, after, before_n), "masks.rle changed: %zu bytes, was %zu",
               after_n, before_n);
        free(before);
        free(after);
    }
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
}

/* Waits (FIFO, see observer_realtime) for the printer's next light (one
   more UV-on in the simulator's log, wait_for_exposures: within 20 ms of
   it), so that a stop sent next comes early in a layer's exposure, 150 ms
   long, with the layer on the screen. The light comes on only once the
   printer has the host's SCREEN for the layer drawn; the screen file alone
   turns lit while the host is still drawing, before it says SCREEN, and a
   stop there found the screen dark in the printer's record (a second host's
   abort lifted Z where the test expected it held: CI, 2026-12-06). */
static int at_lit_start(const char *log, const char *fb)
{
    int ok = wait_for_exposures(log, (unsigned)lit_so_far(log) + 1);
    CHECKF(ok, "the printer's light did not come on within 12 s");
    CHECKF(!ok || !all_zero(fb), "the printer's light is on over a dark screen");
    return ok && !all_zero(fb);
}

/* The long job (slice_long_job, in jobl) printed on the simulator's port
   with the screen file fb, the host's stderr held (run_held); once the
   log shows `exposures` UV-ons, the observer is made real-time and waits
   for a layer's light to begin. 0 if it did not (the host and the
   simulator then stopped, the observer back to normal). */
static int held_print_at_lit(child *sim, const char *log, const char *fb, const char *out, unsigned exposures, pid_t *pid,
                             int *err)
{
    char spec[600], port[256], job[512];
    int status;
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", fb);
    snprintf(port, sizeof port, "%s", sim->line + 4);
    snprintf(job, sizeof job, "%s", cli_path("jobl"));
    if (!simulator_realtime(sim)) {
        stop_sim(sim);
        return 0;
    }
    {
        char *args[] = {(char *)"print", job, (char *)"--port", port, (char *)"--screen", spec, NULL};
        *pid = run_held(args, out, err);
    }
    CHECK(wait_for_exposures(log, exposures));
    if (observer_realtime(1) && at_lit_start(log, fb)) return 1;
    observer_realtime(0);
    kill(*pid, SIGKILL);
    free(drain_held(*pid, *err, &status));
    stop_sim(sim);
    return 0;
}

/* The stop: `sig` to `to` while the held host's layer is lit (after
   held_print_at_lit); the ms until the screen is dark, checked against the
   bound and printed, the observer back to normal. The held host's stderr
   (drain_held) returned, its exit status in *status. */
static char *stop_timed(pid_t to, int sig, const char *what, const char *fb, pid_t host, int err, int *status)
{
    double dark;
    kill(to, sig);
    dark = ms_until(fb, 0, seconds_now(), 5);
    observer_realtime(0);
    CHECKF(dark >= 0 && dark <= DARK_WITHIN_MS, "the screen dark %.0f ms after %s (-1: lit 5 s on: the host's message, "
           "held, said before the dark?)", dark, what);
    printf("     (dark %.0f ms after %s)\n", dark, what);
    return drain_held(host, err, status);
}

/* Ctrl-C mid-print (SIGINT as the terminal sends it, then the printer's
   PAUSE from the host): paused (exit 3), the screen dark within 100 ms and
   before the host says so, no light after it; then a killed host (SIGKILL)
   mid-exposure: its guard pauses the printer and darkens the screen within
   100 ms; each time the print resumes in place with --screen and ends with
   every exposure under its own layer.

   Both hold on a loaded machine by design: the host waits for the
   printer's replies in poll(), so a stop wakes it at once and it puts the
   screen out as soon as the printer says the light is out, before anything
   else; the guard waits in read() on its pipe at real-time priority. */
static void pause_and_killed_host_leave_it_dark(void)
{
    child sim;
    job_crcs j;
    seen s;
    char spec[600], k[16], *out, *at;
    const char *extra[] = {"--link-timeout-ms", "3000", NULL};
    char fb[512];
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0};
    unsigned layer = 0, uv_before;
    pid_t pid;
    int status, err;
    double t0, dark;
    cli_result r;
    if (!slice_long_job(cli_path("jobl")) || !read_job(cli_path("jobl"), &j)) { CHECK(!"no job"); return; }
    snprintf(fb, sizeof fb, "%s", cli_path("fbp")); /* cli_path's own are overwritten eight calls on */
    remove(fb);
    if (!start_sim(&sim, cli_path("simp.log"), "10", fb, extra)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", fb);
    /* Ctrl-C */
    if (!held_print_at_lit(&sim, cli_path("simp.log"), fb, cli_path("p1.out"), 4, &pid, &err)) { free(j.crc); return; }
    out = stop_timed(pid, SIGINT, "Ctrl-C", fb, pid, err, &status);
    CHECKF(status == 3 && out && strstr(out, "the screen dark"), "Ctrl-C: exit %d: %s", status, out ? out : "");
    at = out ? strstr(out, "--resume-from ") : NULL;
    CHECKF(at && sscanf(at + 14, "%u", &layer) == 1 && layer >= 3, "no layer to resume from in: %s", out ? out : "");
    free(out);
    CHECK(all_zero(fb));
    /* the host killed while a layer is lit */
    snprintf(k, sizeof k, "%u", layer);
    fflush(NULL);
    if ((pid = fork()) == 0) {
        int o = open(cli_path("p2.out"), O_WRONLY | O_CREAT | O_TRUNC, 0644), null = open("/dev/null", O_RDONLY);
        dup2(null, 0); dup2(o, 1); dup2(o, 2);
        execl(cli_tool, cli_tool, "print", cli_path("jobl"), "--port", sim.line + 4, "--screen", spec, "--resume-from", k,
              (char *)NULL);
        _exit(127);
    }
    uv_before = (unsigned)lit_so_far(cli_path("simp.log"));
    CHECK(wait_for_exposures(cli_path("simp.log"), uv_before + 2));
    if (!observer_realtime(1) || !at_lit_start(cli_path("simp.log"), fb)) {
        observer_realtime(0);
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
        stop_sim(&sim);
        free(j.crc);
        return;
    }
    kill(pid, SIGKILL);
    t0 = seconds_now();
    dark = ms_until(fb, 0, t0, 10);
    observer_realtime(0);
    (void)wait_exit(pid, 10);
    CHECKF(dark >= 0 && dark <= DARK_WITHIN_MS, "the screen dark %.0f ms after the host was killed (-1: lit 10 s on)", dark);
    printf("     (dark %.0f ms after the host was killed)\n", dark);
    sleep_ms(300);
    r = cli_run("print", cli_path("jobl"), "--port", sim.line + 4, "--screen", spec, "--resume-from", k, NULL);
    /* the guard's pause kept the layer's rest: resumed in place from the
       layer after the last fully exposed */
    if (r.status == 2 && (at = strstr(r.err, "resume from ")) != NULL && sscanf(at + 12, "%u", &layer) == 1) {
        cli_free(&r);
        snprintf(k, sizeof k, "%u", layer);
        r = cli_run("print", cli_path("jobl"), "--port", sim.line + 4, "--screen", spec, "--resume-from", k, NULL);
    }
    CHECKF(r.status == 0 && strstr(r.out, "in place"), "resume after the kill: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    CHECK(all_zero(fb));
    CHECK(observe(cli_path("simp.log"), fb, &f, &j, &s));
    CHECKF(s.right == s.exposures && !s.wrong && s.exposures >= j.layers, "%u UV-ons for %u layers, %u right: %s",
           s.exposures, j.layers, s.right, s.first_wrong);
    CHECKF(s.user_pauses == 2 && !s.uv_after_pause, "%u pauses, %u lights while paused", s.user_pauses, s.uv_after_pause);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    free(s.layer_of);
    free(j.crc);
}

/* The MCU reset mid-exposure (SIGUSR1 to the simulator: the state and Z's
   home lost): the host stops with exit 4, the screen dark within 100 ms of
   the reset and before the host says so; nothing is lit while the printer
   has no job, and the print resumed with --home ends with every exposure
   under its own layer and no step under a lit screen. The host learns of
   the reset from the first STATUS the new boot answers: it asks every 5 ms
   while a layer is lit (screen_print.c) and waits for the answer in
   poll() at real-time priority, as the simulator answers, so the path is
   the same few round trips on a loaded machine. */
static void mcu_reset_leaves_it_dark(void)
{
    child sim;
    job_crcs j;
    seen s;
    char spec[600], k[16], *out, *at;
    char fb[512];
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0};
    unsigned layer = 0;
    pid_t pid;
    int status, err;
    cli_result r;
    if (!slice_long_job(cli_path("jobl")) || !read_job(cli_path("jobl"), &j)) { CHECK(!"no job"); return; }
    snprintf(fb, sizeof fb, "%s", cli_path("fbr"));
    remove(fb);
    if (!start_sim(&sim, cli_path("simr.log"), "10", fb, NULL)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", fb);
    if (!held_print_at_lit(&sim, cli_path("simr.log"), fb, cli_path("r1.out"), 4, &pid, &err)) { free(j.crc); return; }
    out = stop_timed(sim.pid, SIGUSR1, "the reset", fb, pid, err, &status);
    at = out ? strstr(out, "--resume-from ") : NULL;
    CHECKF(status == 4 && at && sscanf(at + 14, "%u", &layer) == 1 && layer >= 3, "the reset: exit %d: %s", status,
           out ? out : "");
    free(out);
    CHECK(all_zero(fb));
    if (check_case_failed()) { stop_sim(&sim); free(j.crc); return; }
    snprintf(k, sizeof k, "%u", layer);
    r = cli_run("print", cli_path("jobl"), "--port", sim.line + 4, "--screen", spec, "--resume-from", k, "--home", NULL);
    CHECKF(r.status == 0, "resume after the reset: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    CHECK(all_zero(fb));
    CHECK(observe(cli_path("simr.log"), fb, &f, &j, &s));
    CHECKF(s.right == s.exposures && !s.wrong && s.exposures >= j.layers, "%u UV-ons for %u layers, %u right: %s",
           s.exposures, j.layers, s.right, s.first_wrong);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    free(s.layer_of);
    free(j.crc);
}

/* Waits (up to 10 s) until a simulator's log shows the print paused for
   the lost link (state PAUSED with LINK_LOST). */
static int wait_for_link_pause(const char *log_path)
{
    double t0 = seconds_now();
    while (seconds_now() - t0 < 10) {
        char *log = read_whole_text(log_path), *at;
        unsigned flags;
        int found = 0;
        for (at = log; at && !found && (at = strstr(at, " state 6 ")) != NULL; at++)
            found = sscanf(at + 9, "%u", &flags) == 1 && (flags & LINK_FLAG_LINK_LOST);
        free(log);
        if (found) return 1;
        sleep_ms(20);
    }
    return 0;
}

/* ABORT from a second host during a screen print. The printing host is
   held still (SIGSTOP: two hosts reading one port take each other's
   replies) while a layer is lit, until the printer pauses itself for the
   lost link; adaslice print --abort from a second host then abandons the
   print, UV off, and leaves Z where it is, since the first host's screen
   still shows a layer. The first host, let go, finds the printer READY:
   its screen dark before it says so (its stderr held), exit 1 and the
   stop's one line ("aborted") with the layer to resume from; the pin log
   has no UV-on after the abort. The host cannot see the abort while it is
   held, so the 100 ms run from SIGCONT: its timers ran out meanwhile, so
   it resends at once, finds the printer's numbering another host's, says
   HELLO and reads READY, each a round trip it waits for in poll(). */
static void second_host_abort_leaves_it_dark(void)
{
    child sim;
    char fb[512], port[256], *out, *log, *at;
    const char *extra[] = {"--link-timeout-ms", "1000", NULL};
    pid_t pid;
    int status, err;
    cli_result r;
    if (!slice_long_job(cli_path("jobl"))) return;
    snprintf(fb, sizeof fb, "%s", cli_path("fba"));
    remove(fb);
    if (!start_sim(&sim, cli_path("sima.log"), "10", fb, extra)) return;
    snprintf(port, sizeof port, "%s", sim.line + 4);
    if (!held_print_at_lit(&sim, cli_path("sima.log"), fb, cli_path("a1.out"), 3, &pid, &err)) return;
    kill(pid, SIGSTOP);
    observer_realtime(0);
    CHECKF(wait_for_link_pause(cli_path("sima.log")), "the printer did not pause for the held host");
    r = cli_run("print", "--abort", "--port", port, NULL);
    CHECKF(r.status == 0 && strstr(r.out, "abandoned the print at layer ") &&
               strstr(r.out, "the host's screen still shows layer"), "--abort: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(!all_zero(fb), "the held host's screen went dark by itself");
    if (!observer_realtime(1)) {
        kill(pid, SIGKILL);
        kill(pid, SIGCONT);
        free(drain_held(pid, err, &status));
        stop_sim(&sim);
        return;
    }
    out = stop_timed(pid, SIGCONT, "the held host was let go", fb, pid, err, &status);
    CHECKF(status == 1 && out && cli_one_message(out) && strstr(out, "stopped printing (aborted)") &&
               strstr(out, "--resume-from "), "the first host: exit %d: %s", status, out ? out : "");
    free(out);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    CHECK(all_zero(fb));
    /* READY after the pause is the abort: no light after it */
    log = read_whole_text(cli_path("sima.log"));
    at = log ? strstr(log, " state 6 ") : NULL;
    at = at ? strstr(at, " state 4 ") : NULL;
    CHECKF(at && !strstr(at, " uv 1"), "the pin log: %s after the abort", at ? "a UV-on" : "no READY");
    free(log);
}

/* A layer the host could not draw (its code in masks.rle damaged: it does
   not decode to its CRC) is found before the print begins: it once paused
   the print at that layer, half a part on the plate. Now nothing is lit and
   the screen stays dark, and the message names the layer and the byte. */
static void damaged_layer_stops_the_print_before_it_begins(void)
{
    child sim;
    job_crcs j;
    char spec[600], path[600];
    size_t n, at = 44;
    unsigned char *b;
    unsigned k;
    FILE *out;
    cli_result r;
    if (!slice_job(cli_path("jobd"), NULL) || !read_job(cli_path("jobd"), &j)) { CHECK(!"no job"); return; }
    /* layer 5's code: past the 16 bytes of each layer before it */
    snprintf(path, sizeof path, "%s/masks.rle", cli_path("jobd"));
    b = read_whole_file(path, &n);
    for (k = 0; b && k < 4; k++) at += 16 + (b[at + 12] | (size_t)b[at + 13] << 8 | (size_t)b[at + 14] << 16);
    CHECK(b && at + 20 < n);
    if (!b || at + 20 >= n) { free(b); free(j.crc); return; }
    b[at + 16 + (b[at + 12] | (size_t)b[at + 13] << 8) / 2] ^= 0x5a;
    if ((out = fopen(path, "wb")) != NULL) { CHECK(fwrite(b, 1, n, out) == n); fclose(out); }
    {
        /* the manifest names masks.rle's CRC-32: made to agree, so that only
           the layer's own check finds the damage */
        char was[9], now[9], mpath[600], *m, *hit;
        size_t mn;
        snprintf(mpath, sizeof mpath, "%s/manifest.json", cli_path("jobd"));
        snprintf(now, sizeof now, "%08x", (unsigned)adaslice_crc32(0, b, n));
        m = (char *)read_whole_file(mpath, &mn);
        CHECK(m != NULL);
        if (m) {
            uint32_t before;
            b[at + 16 + (b[at + 12] | (size_t)b[at + 13] << 8) / 2] ^= 0x5a;
            before = adaslice_crc32(0, b, n);
            b[at + 16 + (b[at + 12] | (size_t)b[at + 13] << 8) / 2] ^= 0x5a;
            snprintf(was, sizeof was, "%08x", (unsigned)before);
            m[mn] = 0;
            hit = strstr(m, was);
            CHECKF(hit != NULL, "manifest.json does not name masks.rle's CRC-32 %s", was);
            if (hit) memcpy(hit, now, 8);
            if (hit && (out = fopen(mpath, "wb")) != NULL) { CHECK(fwrite(m, 1, mn, out) == mn); fclose(out); }
            free(m);
        }
    }
    free(b);
    remove(cli_path("fbd"));
    if (!start_sim(&sim, cli_path("simd.log"), "100", cli_path("fbd"), NULL)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbd"));
    r = cli_run("print", cli_path("jobd"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "masks.rle: byte ") &&
           strstr(r.err, "layer 5's mask") && strstr(r.err, "damaged"), "a damaged layer 5: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    /* the screen never opened (its file was not made), and the printer's
       log has no light and no step */
    CHECK(!cli_exists(cli_path("fbd")));
    {
        char *log = read_whole_text(cli_path("simd.log"));
        CHECKF(log && !cli_count(log, " uv 1") && !cli_count(log, " step "), "the simulator's log: %.300s",
               log ? log : "(none)");
        free(log);
    }
    free(j.crc);
}

/* A fault (a step that cannot be timed) ends the print: the screen dark. */
static void fault_leaves_it_dark(void)
{
    child sim;
    char spec[600];
    const char *extra[] = {"--late-step-after-exposure", "3", NULL};
    cli_result r;
    if (!slice_job(cli_path("job"), NULL)) return;
    remove(cli_path("fbf"));
    if (!start_sim(&sim, cli_path("simf.log"), "100", cli_path("fbf"), extra)) return;
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbf"));
    r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 1 && strstr(r.err, "stopped printing"), "a fault: exit %d: %s", r.status, r.err);
    cli_free(&r);
    CHECK(all_zero(cli_path("fbf")));
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
}

/* adaslice show in the background until it says the image is shown (its
   line on stdout comes once screen_show has returned), then SIGTERM: the
   file's bytes while shown, and whether it was dark after. */
static unsigned char *shown_by(char *const argv[], const char *fb, size_t *n, int *dark_after)
{
    pid_t pid;
    double t0;
    unsigned char *b = NULL;
    const char *said = cli_path("show.out");
    int st;
    remove(fb);
    remove(said);
    fflush(NULL);
    if ((pid = fork()) == 0) {
        int null = open("/dev/null", O_RDWR), o = open(said, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(null, 0); dup2(o, 1);
        execv(cli_tool, argv);
        _exit(127);
    }
    for (t0 = seconds_now(); seconds_now() - t0 < 60; sleep_ms(5)) {
        size_t m;
        char *text = (char *)read_whole_file(said, &m);
        int shown = text && m && memchr(text, '\n', m);
        free(text);
        if (shown) break;
    }
    b = read_whole_file(fb, n);
    kill(pid, SIGTERM);
    waitpid(pid, &st, 0);
    CHECKF(WIFEXITED(st) && WEXITSTATUS(st) == 0, "show: %d", st);
    *dark_after = all_zero(fb);
    return b;
}

/* show: a job's layer exactly (masks.rle's CRC), the patterns as they are
   documented, and dark once it ends. */
static void show_layer_and_patterns(void)
{
    job_crcs j;
    char spec[600];
    size_t n;
    int dark;
    unsigned char *b, *mask = (unsigned char *)malloc(3840 * 2400);
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0}, g = {1280, 2400, 24, SCREEN_RGB, 0, 0};
    if (!mask || !slice_job(cli_path("job"), NULL) || !read_job(cli_path("job"), &j)) { free(mask); CHECK(!"no job"); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbs"));
    {
        char *argv[] = {(char *)cli_tool, (char *)"show", (char *)cli_path("job"), (char *)"--layer", (char *)"30",
                        (char *)"--screen", spec, (char *)"--seconds", (char *)"60", NULL};
        b = shown_by(argv, cli_path("fbs"), &n, &dark);
        CHECK(b && n == 80 * 200 * 3 && !unpack(b, &f, 240, 200, 1, mask) &&
              adaslice_crc32(0, mask, 30 * 200) == j.crc[29]);
        CHECK(dark);
        free(b);
    }
    snprintf(spec, sizeof spec, "file:%s,1280x2400,24", cli_path("fbs"));
    {
        /* the mono 4K panel: 35 um, so a millimetre is 28.57 pixels */
        char *argv[] = {(char *)cli_tool, (char *)"show", (char *)"--pattern", (char *)"ruler", (char *)"--screen", spec,
                        (char *)"--screen-panel", (char *)"mono-4k-6.1", (char *)"--seconds", (char *)"60", NULL};
        unsigned x, lit = 0, want = 0, row = 1014; /* 35.5 mm down: clear of the lines and the squares */
        b = shown_by(argv, cli_path("fbs"), &n, &dark);
        CHECK(b && n == 1280 * 2400 * 3 && !unpack(b, &g, 3840, 2400, 1, mask));
        for (x = 0; b && x < 3840; x++) {
            int on = (mask[row * 480 + x / 8] >> (7 - x % 8)) & 1;
            double mm = x / (1000.0 / 35);
            int line = fabs(mm - floor(mm + 0.5)) * (1000.0 / 35) < 0.5 ||
                       ((int)floor(mm + 0.5) % 10 == 0 && x >= floor(floor(mm + 0.5) * 1000.0 / 35 + 0.5) &&
                        x < floor(floor(mm + 0.5) * 1000.0 / 35 + 0.5) + 3);
            lit += (unsigned)on;
            want += (unsigned)(on == line);
        }
        CHECKF(want == 3840 && lit >= 134, "ruler: row %u has %u lit pixels, %u of 3840 as the pitch puts them", row, lit, want);
        /* the corner's big square (2 .. 7 mm) and the small one right of it (8 .. 10.5 mm, 2 .. 4.5 mm down) */
        CHECK(b && (mask[114 * 480 + 114 / 8] >> (7 - 114 % 8)) & 1);
        CHECK(b && (mask[100 * 480 + 265 / 8] >> (7 - 265 % 8)) & 1);
        CHECK(b && !((mask[170 * 480 + 265 / 8] >> (7 - 265 % 8)) & 1));
        CHECK(dark);
        free(b);
    }
    {
        char *argv[] = {(char *)cli_tool, (char *)"show", (char *)"--pattern", (char *)"white", (char *)"--screen", spec,
                        (char *)"--screen-packing", (char *)"rgb", (char *)"--seconds", (char *)"60", NULL};
        size_t k, bad = 0;
        b = shown_by(argv, cli_path("fbs"), &n, &dark);
        for (k = 0; b && k < n; k++) bad += b[k] != 0xff;
        CHECKF(b && n == 1280 * 2400 * 3 && !bad, "white: %zu bytes, %zu not lit", n, bad);
        CHECK(dark);
        free(b);
    }
    free(mask);
    free(j.crc);
}

/* What show cannot draw is refused at once, naming the value: a ruler whose
   millimetre lines touch (a pitch of 1e12 um looped for ever, deaf to
   Ctrl-C), a checker's square under a pixel (1e-300 mm: a cast past 2^32),
   a pitch out of any screen's range; a job directory that is not there is
   named as such (it was "not whole"). */
static void show_refuses_what_it_cannot_draw(void)
{
    static const char *const cases[][9] = {
        {"--pattern", "ruler", "--screen-pitch", "1e12", NULL},
        {"--pattern", "ruler", "--screen-pitch", "0.5", NULL},
        {"--pattern", "ruler", "--screen-pitch", "300", NULL},
        {"--pattern", "checker", "--screen-pitch", "50", "--cell", "1e-300", NULL},
        {"/nonexistent/job", "--layer", "1", NULL},
    };
    static const char *const named[] = {"--screen-pitch 1e+12", "--screen-pitch 0.5", "would touch", "--cell 1e-300",
                                        "/nonexistent/job: No such file"};
    char spec[600];
    size_t i;
    snprintf(spec, sizeof spec, "file:%s,80x200,24", cli_path("fbq"));
    for (i = 0; i < sizeof cases / sizeof *cases; i++) {
        const char *const *c = cases[i];
        cli_result r = cli_run("show", "--screen", spec, "--seconds", "0.01", c[0], c[1], c[2], c[3], c[4], c[5], NULL);
        CHECKF(r.status != 0 && cli_one_message(r.err) && strstr(r.err, named[i]), "case %zu: exit %d: %s", i, r.status, r.err);
        cli_free(&r);
    }
}

/* show --pattern white --port --expose: an exposure test. The printer
   lights the white screen once, for the time asked, under the observer's
   eyes; the screen is dark after, and the printer takes a print next (the
   host said the screen is dark). */
static void white_exposure_test(void)
{
    child sim;
    char spec[600], copy[600];
    size_t n, k, unlit = 0;
    unsigned char *b;
    unsigned uv_ons = 0;
    char *log, *at;
    cli_result r;
    remove(cli_path("fbx"));
    if (!start_sim(&sim, cli_path("simx.log"), "10", cli_path("fbx"), NULL)) return;
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbx"));
    r = cli_run("show", "--pattern", "white", "--screen", spec, "--port", sim.line + 4, "--expose", "0.5", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "lit for 0.500 s"), "show --expose: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECK(all_zero(cli_path("fbx")));
    r = cli_run("show", "--pattern", "white", "--screen", spec, "--port", sim.line + 4, "--expose", "100000", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "lights 0.001 to"), "show --expose too long: exit %d: %s", r.status, r.err);
    cli_free(&r);
    /* 2^32 ms and a little: it wrapped to 4 ms and lit, exit 0 */
    r = cli_run("show", "--pattern", "white", "--screen", spec, "--port", sim.line + 4, "--expose", "4294967.3", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "lights 0.001 to"), "show --expose 2^32 ms: exit %d: %s", r.status, r.err);
    cli_free(&r);
    {
        /* Ctrl-C in a long exposure test: the screen dark within 100 ms,
           the printer told so (its light out) and only then said (stderr
           held: a message said first would keep the screen lit) */
        char port[256], *out;
        char *args[] = {(char *)"show", (char *)"--pattern", (char *)"white", (char *)"--screen", spec, (char *)"--port",
                        port, (char *)"--expose", (char *)"20", NULL};
        pid_t pid;
        int err, status;
        snprintf(port, sizeof port, "%s", sim.line + 4);
        pid = run_held(args, cli_path("x2.out"), &err);
        CHECK(wait_for_exposures(cli_path("simx.log"), 2));
        if (observer_realtime(1) && simulator_realtime(&sim) && ms_until(cli_path("fbx"), 1, seconds_now(), 10) >= 0) {
            out = stop_timed(pid, SIGINT, "Ctrl-C in the exposure test", cli_path("fbx"), pid, err, &status);
            CHECKF(status == 0 && out && cli_one_message(out) && strstr(out, "interrupted: the light put out"),
                   "show --expose, Ctrl-C: exit %d: %s", status, out ? out : "");
            free(out);
        } else {
            observer_realtime(0);
            kill(pid, SIGKILL);
            free(drain_held(pid, err, &status));
        }
        /* the pin log's last light edge: off */
        log = read_whole_text(cli_path("simx.log"));
        {
            char *last = NULL;
            for (at = log; at && (at = strstr(at, " uv ")) != NULL; at++) last = at;
            CHECKF(last && last[4] == '0', "the light's last edge in the pin log after Ctrl-C: %.12s", last ? last : "none");
        }
        free(log);
    }
    if (slice_job(cli_path("job"), NULL)) {
        r = cli_run("print", cli_path("job"), "--port", sim.line + 4, "--screen", spec, NULL);
        CHECKF(r.status == 0, "a print after the exposure test: exit %d: %s", r.status, r.err);
        cli_free(&r);
    }
    CHECKF(stop_sim(&sim) == 0, "the simulator failed");
    log = (char *)read_whole_file(cli_path("simx.log"), &n);
    if (log) {
        unsigned long long on = 0, off = 0;
        char *first;
        log[n] = 0;
        for (at = log; (at = strstr(at, " uv 1")) != NULL; at++) uv_ons++;
        /* the first light: 0.5 s to the tick (10 MHz) */
        if ((first = strstr(log, " uv 1")) != NULL) {
            while (first > log && first[-1] != '\n') first--;
            sscanf(first, "%llu", &on);
            if ((at = strstr(first, " uv 0")) != NULL) {
                while (at > log && at[-1] != '\n') at--;
                sscanf(at, "%llu", &off);
            }
        }
        CHECKF(off - on == 5000000ull, "the white screen lit %llu ticks", off - on);
    }
    free(log);
    CHECKF(uv_ons > 1, "%u UV-ons", uv_ons);
    snprintf(copy, sizeof copy, "%s.uv1", cli_path("fbx"));
    b = read_whole_file(copy, &n);
    for (k = 0; b && k < n; k++) unlit += b[k] != 0xff;
    CHECKF(b && n == 80 * 200 * 3 && !unlit, "the first light: %zu bytes of screen, %zu not white", n, unlit);
    free(b);
}

/* A real framebuffer where the machine has one (/dev/fb0, or
   $ADASLICE_TEST_FB): a checkerboard drawn through the ioctls and the
   mapping, read back from the mapping, then dark. Skipped, saying why,
   where there is none. */
static void real_framebuffer_if_any(void)
{
    const char *dev = getenv("ADASLICE_TEST_FB") ? getenv("ADASLICE_TEST_FB") : "/dev/fb0";
    screen s;
    screen_options o;
    unsigned char *mask;
    uint32_t w, h, x, y, page_bytes, k, lit = 0;
    int fd = open(dev, O_RDWR);
    if (fd < 0) {
        printf("     (skipped: %s: %s: no framebuffer to check the page flip with FBIOPAN_DISPLAY and the wait with "
               "FBIO_WAITFORVSYNC on; ADASLICE_TEST_FB names another)\n", dev, strerror(errno));
        return;
    }
    close(fd);
    memset(&o, 0, sizeof o);
    o.device = dev;
    o.packing = -1;
    if (screen_open(&s, &o) != 0) {
        printf("     (skipped: %s is not a framebuffer adaslice draws on: the page flip with FBIOPAN_DISPLAY and the "
               "wait with FBIO_WAITFORVSYNC go unchecked)\n", dev);
        return;
    }
    w = s.panel_w;
    h = s.panel_h;
    mask = (unsigned char *)calloc((w + 7) / 8, h);
    for (y = 0; mask && y < h; y++)
        for (x = 0; x < w; x++)
            if ((x / 16 + y / 16) % 2) mask[y * ((w + 7) / 8) + x / 8] |= (unsigned char)(0x80u >> (x % 8));
    CHECK(mask && screen_show(&s, mask, (w + 7) / 8, w, h, 1) == 0);
    page_bytes = s.line_length * s.yres;
    for (k = 0; k < page_bytes; k++) lit += s.map[(size_t)s.shown * page_bytes + k] != 0;
    CHECKF(lit > 0, "%s: nothing drawn on the page shown", dev);
    CHECK(screen_dark(&s) == 0);
    for (k = 0, lit = 0; k < page_bytes; k++) lit += s.map[(size_t)s.shown * page_bytes + k] != 0;
    CHECKF(!lit, "%s: %u bytes lit after dark", dev, lit);
    printf("     %s: %u x %u at %u bpp, %u page%s\n", dev, s.xres, s.yres, s.bpp, s.pages, s.pages > 1 ? "s" : "");
    screen_close(&s);
    free(mask);
}

/* The guard's real-time priority refused (capsh drops CAP_SYS_NICE): the
   tool says so in one line naming the screen and the capability, and shows
   all the same; with it (the tests run as root), not a word. */
static void guard_priority_refused_is_said(void)
{
    char cmd[2048], fb[512], *err;
    pid_t pid;
    int status;
    cli_result r;
    snprintf(fb, sizeof fb, "%s", cli_path("fbn"));
    snprintf(cmd, sizeof cmd, "'%s' show --pattern white --screen file:%s,80x200,24 --seconds 0.1 >'%s' 2>'%s'", cli_tool,
             fb, cli_path("n.out"), cli_path("n.err"));
    fflush(NULL);
    if ((pid = fork()) == 0) {
        execlp("capsh", "capsh", "--drop=cap_sys_nice", "--", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    status = wait_exit(pid, 60);
    err = read_whole_text(cli_path("n.err"));
    CHECKF(status == 0 && err && cli_one_message(err) && strstr(err, "adaslice: warning: --screen ") && strstr(err, fb) &&
               strstr(err, "real-time priority") && strstr(err, "CAP_SYS_NICE"),
           "show without CAP_SYS_NICE: exit %d: %s", status, err ? err : "");
    free(err);
    CHECK(all_zero(fb));
    snprintf(cmd, sizeof cmd, "file:%s,80x200,24", fb);
    r = cli_run("show", "--pattern", "white", "--screen", cmd, "--seconds", "0.1", NULL);
    CHECKF(r.status == 0 && !*r.err, "show as root: exit %d: %s", r.status, r.err);
    cli_free(&r);
}

/* The RAMPS image (ATmega2560) under simavr, its display 240 x 200 as the
   simulator's: the same observer in avr-run, at the MOSFET's and the STEP
   pin's edges. */
static void ramps_print_under_simavr(void)
{
    child avr;
    job_crcs j;
    seen s;
    char spec[600], *argv[] = {(char *)"build/avr-run", (char *)"--log", NULL, (char *)"--z-start", (char *)"20",
                               (char *)"--max-seconds", (char *)"600", (char *)"--timeout", (char *)"1800",
                               (char *)"--watch-screen", NULL, (char *)"build/fw-ramps-test.elf", NULL};
    fb_layout f = {80, 200, 24, SCREEN_RGB, 0, 0};
    cli_result r;
    unsigned k, in_order = 1;
    r = cli_run("slice", "examples/models/hand_closed.obj", "--scale", "5", "--pixels", "240x200", "--pitch", "0.1",
                "--exposure", "0.05", "--penetration", "0.1", "--bottom-layers", "1", "--bottom-exposure", "0.1", "--peel", "3",
                "--peel-speed", "10", "--return-speed", "10", "--settle", "0.02", "-o", cli_path("jobr"), NULL);
    CHECKF(r.status == 0, "slice: %s", r.err);
    cli_free(&r);
    if (!read_job(cli_path("jobr"), &j)) { CHECK(!"no job"); return; }
    argv[2] = (char *)cli_path("avr.log");
    argv[10] = (char *)cli_path("fbr");
    remove(cli_path("fbr"));
    if (!start_child(&avr, argv)) { free(j.crc); return; }
    snprintf(spec, sizeof spec, "file:%s,80x200,24,rgb", cli_path("fbr"));
    r = cli_run("print", cli_path("jobr"), "--port", avr.line + 4, "--screen", spec, NULL);
    CHECKF(r.status == 0, "print --screen on the RAMPS image: exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    CHECKF(stop_sim(&avr) == 0, "avr-run failed");
    CHECK(all_zero(cli_path("fbr")));
    CHECK(observe(cli_path("avr.log"), cli_path("fbr"), &f, &j, &s));
    CHECKF(s.exposures == j.layers && s.right == j.layers && !s.wrong, "%u UV-ons for %u layers, %u right, %u wrong: %s",
           s.exposures, j.layers, s.right, s.wrong, s.first_wrong);
    for (k = 1; k <= s.exposures && k < 4096; k++) in_order &= s.layer_of[k] == k;
    CHECK(in_order);
    CHECKF(s.steps > 1000 && !s.lit_steps, "%u step pulses, %u under a lit screen", s.steps, s.lit_steps);
    printf("     RAMPS: %u layers, each UV-on over its own layer; %u STEP edges, none under a lit screen\n", j.layers, s.steps);
    free(s.layer_of);
    free(j.crc);
}

void test_screen(void)
{
    if (!cli_begin("adaslice-screen")) { CHECK(!"no temporary directory"); return; }
    RUN(packing_by_hand);
    RUN(full_layer_unpacked_back);
    RUN(print_shows_each_layer);
    RUN(model_print_shows_each_layer);
    RUN(aa_job_on_a_turned_gray_screen);
    RUN(wrong_screen_is_refused);
    RUN(show_layer_and_patterns);
    RUN(show_refuses_what_it_cannot_draw);
    RUN(white_exposure_test);
    RUN(real_framebuffer_if_any);
    RUN_NEEDING("capsh (libcap2-bin)", guard_priority_refused_is_said);
    RUN(pause_and_killed_host_leave_it_dark);
    RUN(fault_leaves_it_dark);
    RUN(mcu_reset_leaves_it_dark);
    RUN(second_host_abort_leaves_it_dark);
    RUN(damaged_layer_stops_the_print_before_it_begins);
    RUN_NEEDING("simavr (libsimavr-dev) and avr-gcc: build/avr-run, build/fw-ramps-test.elf", ramps_print_under_simavr);
    cli_end();
}
