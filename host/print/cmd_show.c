/* adaslice show: one layer of a job, or a test pattern, on the printer's
   screen (print/screen.h), for the owner of a DIY printer: a checkerboard
   and a ruler to check the pitch, the turn and the mirror against a printed
   calibration part, all white for an exposure test, dark. It holds the
   image until Ctrl-C (or --seconds), then puts the screen out. The UV light
   is the printer's: show does not switch it. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "screen.h"
#include "screen_print.h"
#include "../commands.h"
#include "../formats/jobdir.h"
#include "../options.h"
#include "../report.h"
#include "../../adaslice_mcu.h"

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { PATTERN_NONE = -1, PATTERN_CHECKER, PATTERN_RULER, PATTERN_WHITE, PATTERN_DARK };
static const char *const PATTERNS[] = {"checker", "ruler", "white", "dark"};

static volatile sig_atomic_t stop;
static void on_stop(int sig) { (void)sig; stop = 1; }

typedef struct show_args {
    screen_options screen;
    const char *job, *port;
    size_t layer, baud;
    int pattern;
    double seconds, cell_mm, expose_s;
} show_args;

static void show_usage(FILE *f)
{
    fputs("usage: adaslice show JOBDIR --layer N --screen DEV [screen options]\n"
          "       adaslice show --pattern checker|ruler|white|dark --screen DEV [screen options]\n"
          "\n"
          "Shows one layer of a job (from JOBDIR/masks.rle, as print shows it), or a test\n"
          "pattern, on the printer's screen until Ctrl-C or --seconds, then puts it out.\n"
          "The patterns: checker, squares of --cell mm (or 32 pixels without a pitch);\n"
          "ruler, a line every mm and a thick one every 10 mm, with a big and a small\n"
          "square in the top-left corner (the turn and the mirror show in a print of\n"
          "it); white, every pixel lit (an exposure test); dark.\n"
          "\n"
          "  --layer N             the job's layer (1-based)\n"
          "  --pattern P           checker, ruler, white or dark\n"
          "  --cell MM             the checker's squares                           [1]\n"
          "  --seconds S           hold the image S seconds           [until Ctrl-C]\n"
          "  --port DEV --expose S the printer (adaslice firmware) on DEV lights the\n"
          "                        image S seconds (an exposure test), then show ends\n"
          "  --baud B              9600 ... 230400                               [115200]\n"
          "\n", f);
    screen_usage(f);
}

static int parse_show(int argc, char **argv, show_args *a)
{
    int i, rc = RC_OK;
    memset(a, 0, sizeof *a);
    a->screen.packing = -1;
    a->pattern = PATTERN_NONE;
    a->cell_mm = 1;
    a->baud = 115200;
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) { show_usage(stdout); return -1; }
        else if (!strcmp(o, "--layer")) rc = count_option(argc, argv, &i, UINT32_MAX, &a->layer);
        else if (!strcmp(o, "--pattern")) rc = name_option(argc, argv, &i, PATTERNS, 4, "checker, ruler, white or dark", &a->pattern);
        else if (!strcmp(o, "--seconds")) rc = number_option(argc, argv, &i, 0, &a->seconds);
        else if (!strcmp(o, "--cell")) rc = number_option(argc, argv, &i, 0, &a->cell_mm);
        else if (!strcmp(o, "--port")) rc = file_option(argc, argv, &i, &a->port);
        else if (!strcmp(o, "--baud")) rc = count_option(argc, argv, &i, 4000000, &a->baud);
        else if (!strcmp(o, "--expose")) rc = number_option(argc, argv, &i, 0, &a->expose_s);
        else if (screen_option(argc, argv, &i, &a->screen, &rc)) {}
        else if (o[0] == '-' && o[1]) rc = complain(RC_USAGE, "show: unknown option %s (adaslice show --help)", o);
        else if (a->job) rc = complain(RC_USAGE, "show: one JOBDIR (%s, then %s)", a->job, o);
        else a->job = o;
    }
    if (rc) return rc;
    if (!a->screen.device) return complain(RC_USAGE, "show needs --screen DEV");
    if (a->pattern == PATTERN_NONE && !a->job) return complain(RC_USAGE, "show needs a JOBDIR and --layer N, or --pattern");
    if (a->pattern != PATTERN_NONE && a->job) return complain(RC_USAGE, "show: a JOBDIR or a --pattern, not both");
    if (a->job && !a->layer) return complain(RC_USAGE, "show %s: which layer? --layer N", a->job);
    if (!a->port != !a->expose_s) return complain(RC_USAGE, "show: --port DEV and --expose S go together");
    if (a->pattern == PATTERN_DARK && a->port) return complain(RC_USAGE, "show --pattern dark: nothing to expose");
    return RC_OK;
}

/* ------------------------------------------------------------ images */

typedef struct image { uint32_t w, h; int bits; size_t stride; unsigned char *px; } image;

static void set_pixel(image *m, uint32_t x, uint32_t y)
{
    if (x < m->w && y < m->h) m->px[(size_t)y * m->stride + x / 8] |= (unsigned char)(0x80u >> (x % 8));
}

static void fill_rect(image *m, double x0, double y0, double x1, double y1)
{
    uint32_t x, y;
    for (y = (uint32_t)(y0 < 0 ? 0 : y0); y < m->h && y < y1; y++)
        for (x = (uint32_t)(x0 < 0 ? 0 : x0); x < m->w && x < x1; x++) set_pixel(m, x, y);
}

/* The pattern on a mask of the panel's size as the job's pixels lie
   (before the turn). */
static int pattern_image(const show_args *a, const screen *s, image *m)
{
    double px_per_mm = s->pitch_um > 0 ? 1000.0 / s->pitch_um : 0;
    uint32_t x, y;
    m->w = (s->rotate & 1) ? s->panel_h : s->panel_w;
    m->h = (s->rotate & 1) ? s->panel_w : s->panel_h;
    m->bits = 1;
    m->stride = (m->w + 7) / 8;
    if (!(m->px = (unsigned char *)calloc(m->stride, m->h))) return complain(RC_FAIL, "out of memory for the pattern");
    switch (a->pattern) {
    case PATTERN_WHITE: memset(m->px, 0xff, m->stride * m->h); break;
    case PATTERN_CHECKER: {
        double cell = px_per_mm ? a->cell_mm * px_per_mm : 32;
        /* a square under a pixel is no checker (and x / cell past 2^32 no count) */
        if (cell < 1)
            return complain(RC_USAGE, "show --cell %g: under one of the screen's %g um pixels", a->cell_mm, s->pitch_um);
        for (y = 0; y < m->h; y++)
            for (x = 0; x < m->w; x++)
                if (((uint32_t)(x / cell) + (uint32_t)(y / cell)) % 2 == 0) set_pixel(m, x, y);
        break;
    }
    case PATTERN_RULER: {
        double step;
        uint32_t k;
        if (!px_per_mm)
            return complain(RC_USAGE, "show --pattern ruler: the screen's pitch? --screen-pitch UM or --screen-panel NAME");
        step = px_per_mm;
        /* lines a millimetre apart that touch would be a solid screen (and a
           step near 0 never ends the loop) */
        if (step < 4)
            return complain(RC_USAGE, "show --pattern ruler: the screen's pixels (%g um) are over a quarter of a millimetre: "
                                      "its millimetre lines would touch", s->pitch_um);
        for (k = 0; k * step < m->w; k++) {
            double x0 = floor(k * step + 0.5);
            fill_rect(m, x0, 0, x0 + (k % 10 ? 1 : 3), m->h);
        }
        for (k = 0; k * step < m->h; k++) {
            double y0 = floor(k * step + 0.5);
            fill_rect(m, 0, y0, m->w, y0 + (k % 10 ? 1 : 3));
        }
        /* the corner: a 5 mm square and a 2.5 mm one to its right */
        fill_rect(m, 2 * step, 2 * step, 7 * step, 7 * step);
        fill_rect(m, 8 * step, 2 * step, 10.5 * step, 4.5 * step);
        break;
    }
    default: break;
    }
    return RC_OK;
}

typedef struct row_sink { image *m; } row_sink;

static void take_row(void *ctx, uint32_t y, const unsigned char *row)
{
    image *m = ((row_sink *)ctx)->m;
    memcpy(m->px + (size_t)y * m->stride, row, m->stride);
}

/* The job's layer, once the job is known to fit the screen: its size
   comes from the job's file, and is the screen's before anything that size
   is made. */
static int job_image(const show_args *a, const screen *s, image *m)
{
    job_masks jm;
    row_sink sink;
    unsigned char *row = NULL;
    uint32_t k = (uint32_t)a->layer;
    int rc;
    memset(&jm, 0, sizeof jm);
    if ((rc = jobdir_read_masks(a->job, &jm))) return rc;
    if (k > jm.layers)
        rc = complain(RC_USAGE, "show %s --layer %u: the job has %u layer%s", a->job, k, jm.layers, plural(jm.layers));
    if (!rc && !(rc = screen_fits(s, jm.width, jm.height, 0))) rc = screen_fits_job(s, a->job, jm.pitch_mm);
    if (rc) {
        job_masks_free(&jm);
        return rc;
    }
    m->w = jm.width;
    m->h = jm.height;
    m->bits = (int)jm.bits;
    m->stride = jm.bits == 8 ? jm.width : (jm.width + 7) / 8;
    sink.m = m;
    m->px = (unsigned char *)malloc(m->stride * m->h);
    row = (unsigned char *)malloc(m->stride);
    if (!m->px || !row) rc = complain(RC_FAIL, "out of memory for a mask of %u x %u px", m->w, m->h);
    else rc = jobdir_decode_layer(a->job, &jm, k - 1, row, take_row, &sink);
    free(row);
    job_masks_free(&jm);
    return rc;
}

/* ------------------------------------------------------------ the light */

/* The image on screen lit by the printer for a->expose_s: SCREEN says the
   host shows a pattern of its own, EXPOSE lights it (the printer's timer
   ends it); Ctrl-C puts it out (SCREEN 0). */
static int expose(serial_link *l, const show_args *a)
{
    uint8_t buf[LINK_PAYLOAD_MAX];
    link_screen sm;
    link_expose em;
    double t0;
    int rc, lit = 0;
    sm.layer = LINK_SCREEN_PATTERN;
    sm.exposure_ms = 0;
    /* the range in seconds, before a cast that wraps past 2^32 ms */
    if (!(a->expose_s * 1000 + 0.5 >= 1) || a->expose_s * 1000 + 0.5 >= (double)l->id.max_exposure_ms + 1)
        return complain(RC_USAGE, "show --expose %g: the printer on %s lights 0.001 to %.3f s at once", a->expose_s, a->port,
                        l->id.max_exposure_ms / 1000.0);
    em.ms = (uint32_t)(a->expose_s * 1000 + 0.5);
    if ((rc = serial_send(l, LINK_MSG_SCREEN, buf, link_put_screen(buf, &sm))) ||
        (rc = serial_send(l, LINK_MSG_EXPOSE, buf, link_put_expose(buf, &em))) || (rc = serial_status(l)))
        return rc;
    if (!(l->st.flags & LINK_FLAG_UV) && l->st.error != LINK_ERR_NONE)
        return complain(RC_FAIL, "the printer on %s would not light the screen: %s", a->port, link_error_name(l->st.error));
    printf("lit for %.3f s\n", em.ms / 1000.0);
    fflush(stdout);
    for (t0 = now_ms(); !stop && now_ms() - t0 < em.ms + 5000.0;) {
        if ((rc = serial_pump(l, 20)) || (rc = serial_status(l))) return rc;
        if (l->st.flags & LINK_FLAG_UV) lit = 1;
        else if (lit || now_ms() - t0 > em.ms) break;
    }
    return RC_OK;
}

/* ------------------------------------------------------------ the command */

int cmd_show(int argc, char **argv)
{
    show_args a;
    screen s;
    image m;
    serial_link l;
    struct sigaction sa;
    double t0;
    int rc;
    memset(&m, 0, sizeof m);
    memset(&s, 0, sizeof s);
    memset(&l, 0, sizeof l);
    s.fd = s.guard_fd = l.fd = -1;
    if ((rc = parse_show(argc, argv, &a))) return rc < 0 ? RC_OK : rc;
    if ((rc = screen_open(&s, &a.screen))) return rc;
    if (a.pattern == PATTERN_DARK) { screen_close(&s); return RC_OK; }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if ((a.port && (rc = serial_connect(&l, a.port, (long)a.baud, 3))) ||
        (rc = a.job ? job_image(&a, &s, &m) : pattern_image(&a, &s, &m)) ||
        (rc = screen_guard(&s, l.fd)) ||
        (rc = screen_show(&s, m.px, m.stride, m.w, m.h, m.bits)))
        goto done;
    if (a.port) {
        rc = expose(&l, &a);
        goto done;
    }
    if (a.job) printf("layer %zu of %s on %s\n", a.layer, a.job, s.name);
    else printf("%s on %s: %u x %u px%s\n", PATTERNS[a.pattern], s.name, m.w, m.h, s.pitch_um > 0 ? "" : " (pitch unknown)");
    fflush(stdout);
    for (t0 = now_ms(); !stop && (a.seconds <= 0 || now_ms() - t0 < a.seconds * 1000);) {
        struct timespec ts = {0, 20000000L};
        nanosleep(&ts, NULL);
    }
done:
    screen_close(&s); /* dark */
    if (l.fd >= 0) {
        if (screen_print_said_dark(&l) == RC_OK) (void)serial_status(&l);
        serial_close(&l);
        /* said once the screen is dark and the printer told so, not before */
        if (stop && rc == RC_OK) fprintf(stderr, "adaslice: interrupted: the light put out\n");
    }
    free(m.px);
    return rc;
}
