/* adaslice print: drives a printer running the adaslice firmware over a
   serial port (host/print/serial.h: POSIX termios only), after link/PROTOCOL.md.
   The printer plans from the quantised profile (or takes the host's plan:
   plan_upload.h), then the host streams mask k+1 while layer k exposes (the
   job and its masks: print_job.h), or shows it on its own screen
   (screen_print.h). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "../bytes.h"
#include "../commands.h"
#include "../formats/jobdir.h"
#include "../json.h"
#include "../layers.h"
#include "../options.h"
#include "../output.h"
#include "../plan_job.h"
#include "../report.h"
#include "plan_upload.h"
#include "print_job.h"
#include "serial.h"
#include "screen_print.h"

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static volatile sig_atomic_t interrupted;
static void on_sigint(int sig) { (void)sig; interrupted = 1; }

typedef struct print_args {
    const char *port, *report;
    long baud;
    size_t resume_from;
    size_t exposure_left;   /* --exposure-left: ms layer resume_from still owes, 0 all */
    int plan_on_host;
    int home;               /* --home: a resumed print may home Z */
    int then_exit;          /* emulators: EXIT after the print */
    int abort;              /* --abort: abandon the paused print, no job */
    double give_up_s;       /* a printer that answers nothing this long ends the print */
    screen_options screen;  /* --screen: the host shows the masks (print/screen.h) */
} print_args;

/* -------------------------------------------------------------- print */

static int homed(const link_status *s, const void *ctx) { (void)ctx; return s->state != LINK_STATE_HOMING; }

/* Layers done since the first, with the height Z is at. */
static void print_progress(progress *bar, const print_job *pj, const link_status *s, uint32_t first)
{
    char z[32];
    uint32_t done = s->state == LINK_STATE_DONE ? pj->layers - first + 1 : (s->layer > first ? s->layer - first : 0);
    snprintf(z, sizeof z, "z %.3f mm", s->z_nm / 1e6);
    progress_show(bar, done, pj->layers - first + 1, "layers", z);
}

/* While the light may be on, a STATUS this often, ms, not waited for: a
   printer that restarts mid-exposure then leaves the light its layer owes
   known from a STATUS about this old (serial_stopped). The light comes on
   only while Z stands, and Z's steps are left alone. */
#define LIT_POLL_MS 5

static int may_be_lit(const link_status *s)
{
    /* not while the layer's mask still streams: STATUS requests would take
       the window's frames from it (two on the RAMPS board) */
    return s->state == LINK_STATE_PRINTING && !(s->flags & LINK_FLAG_MOVING) &&
           (s->phase == LINK_PHASE_SETTLE || s->phase == LINK_PHASE_EXPOSE || s->mask_ready >= s->layer);
}

/* What was sent of each layer's mask (0 for layers not sent) */
typedef struct report_layer { uint32_t crc, code_bytes; } report_layer;

/* Prints from --resume-from (or 1); in_place: the printer holds this job,
   paused at that layer, with the masks up to mask_ready: it is resumed, not
   started again, and exposes only the light the layer still owes. */
static int print_loop(serial_link *l, const print_args *pa, print_job *pj, int in_place, report_layer *rep,
                      unsigned long *mask_bytes)
{
    uint8_t buf[LINK_PAYLOAD_MAX];
    uint32_t first = pa->resume_from ? (uint32_t)pa->resume_from : 1, next = first, tries = 0;
    double polled = 0, lit_asked = 0;
    progress bar;
    int rc, sending = 0;
    size_t sent = 0;
    uint16_t refused = 0;
    link_print m = pj->motion;
    memset(&bar, 0, sizeof bar);
    m.first_layer = first;
    m.job = pj->job;
    if (in_place) {
        next = l->st.mask_ready + 1;
        /* paused before its light came on, or in the peel after it (the
           layer before is then the one held): the layer gets it all */
        if (l->st.exposure_left_ms)
            printf("resuming layer %u in place: %u ms of its exposure left, masks from layer %u on\n", first,
                   l->st.exposure_left_ms, next);
        else
            printf("resuming layer %u in place: its whole exposure (%u ms) to come, masks from layer %u on\n", first,
                   pj->exposure_ms[first - 1], next);
        fflush(stdout);
        if (l->st.state == LINK_STATE_PAUSED && (rc = serial_send(l, LINK_MSG_RESUME, NULL, 0))) return rc;
        if ((rc = serial_status(l))) return rc;
    } else {
        if ((rc = serial_send(l, LINK_MSG_PRINT, buf, link_put_print(buf, &m))) || (rc = serial_status(l))) return rc;
        if (l->st.state == LINK_STATE_PRINTING) {
            printf("printing layers %u to %u", first, pj->layers);
            if (pa->exposure_left) printf(" (layer %u: the %zu ms of light it owes)", first, pa->exposure_left);
            printf("\n");
            fflush(stdout);
        }
    }
    if (l->st.state != LINK_STATE_PRINTING && l->st.state != LINK_STATE_DONE)
        return complain(RC_FAIL, "the printer would not %s layer %u: %s", in_place ? "resume" : "start", first,
                        serial_why_not(l));
    refused = l->st.masks_refused;
    for (;;) {
        if (interrupted) {
            if ((rc = serial_send(l, LINK_MSG_PAUSE, NULL, 0)) || (rc = serial_status(l))) return rc;
            while (l->st.state == LINK_STATE_PRINTING) if ((rc = serial_pump(l, 50)) || (rc = serial_status(l))) return rc;
            fprintf(stderr, "\nadaslice: paused at layer %u of %u (UV off, Z held at %.3f mm); "
                            "continue with --resume-from %u\n", l->st.layer, pj->layers, l->st.z_nm / 1e6, l->st.exposed + 1);
            return RC_PAUSED;
        }
        /* between masks, and once a mask is all sent, the next STATUS decides what comes next */
        if (now_ms() - polled > 100 || !sending || sent == pj->code_size) {
            if ((rc = serial_status(l))) return rc;
            polled = now_ms();
            print_progress(&bar, pj, &l->st, first);
            if (l->st.state == LINK_STATE_DONE) return RC_OK;
            if (l->st.state == LINK_STATE_PAUSED && (l->st.flags & LINK_FLAG_LINK_LOST)) {
                /* the link came back: the pause was not the operator's */
                if ((rc = serial_send(l, LINK_MSG_RESUME, NULL, 0))) return rc;
                continue;
            }
            if (l->st.state != LINK_STATE_PRINTING && l->st.state != LINK_STATE_PAUSED) {
                /* READY mid-print is the core's abort: an ABORT (Z stays
                   homed), or a fault, which leaves Z unhomed; STATUS's error
                   is the last refusal, so a command refused since (the next
                   mask) may hide the fault's */
                int homed = (l->st.flags & LINK_FLAG_HOMED) != 0;
                char what[96];
                snprintf(what, sizeof what, "stopped printing (%s)",
                         l->st.state != LINK_STATE_READY ? link_state_name(l->st.state)
                         : homed ? "aborted"
                         : l->st.error == LINK_ERR_STEP_LATE || l->st.error == LINK_ERR_STACK ? link_error_name(l->st.error)
                                                                                          : "a fault that left Z unhomed");
                return serial_stopped(l, RC_FAIL, what, 1, homed);
            }
            if (sending && sent == pj->code_size && (l->st.mask_ready >= next || l->st.masks_refused != refused)) {
                if (l->st.mask_ready >= next) { next++; tries = 0; }
                else if (++tries > 5) return complain(RC_FAIL, "layer %u: the printer refused the mask %u times", next, tries);
                refused = l->st.masks_refused;
                sending = 0;
            }
        }
        if (!sending && next <= pj->layers && l->st.mask_ready + 1 == next && next <= l->st.layer + 1) {
            if (!tries && (rc = print_job_mask(pj, next))) return rc;
            link_mask mask;
            mask.layer = next;
            mask.code_bytes = (uint32_t)pj->code_size;
            mask.crc32 = pj->crc;
            mask.exposure_ms = !in_place && next == first && pa->exposure_left ? (uint32_t)pa->exposure_left
                                                                               : pj->exposure_ms[next - 1];
            if ((rc = serial_send(l, LINK_MSG_MASK, buf, link_put_mask(buf, &mask))) || (rc = print_job_send_begin(pj))) return rc;
            rep[next - 1].crc = pj->crc;
            rep[next - 1].code_bytes = (uint32_t)pj->code_size;
            sending = 1;
            sent = 0;
        }
        if (sending && sent < pj->code_size) {
            size_t chunk = pj->code_size - sent > l->data_max ? l->data_max : pj->code_size - sent;
            if ((rc = serial_send_mask_data(l, pj->code + sent, chunk, print_job_send_cost(pj, pj->code + sent, chunk)))) return rc;
            sent += chunk;
            *mask_bytes += chunk;
            continue;
        }
        if (may_be_lit(&l->st) && now_ms() - lit_asked > LIT_POLL_MS) {
            if ((rc = serial_ask_status(l))) return rc;
            lit_asked = now_ms();
        }
        if ((rc = serial_pump(l, may_be_lit(&l->st) ? LIT_POLL_MS : 20))) return rc;
    }
}

typedef struct report {
    const print_job *pj;
    const report_layer *layers;
    const serial_link *l;
    uint32_t first;
    double seconds;
    unsigned long mask_bytes;
    int planned_by_printer;
} report;

static void write_report(FILE *f, const void *ctx)
{
    const report *r = (const report *)ctx;
    const double display[3] = {r->pj->width, r->pj->height, r->pj->bits};
    json_writer w;
    uint32_t k, z = 0;
    json_init(&w, f);
    json_begin_object(&w, NULL, 0);
    json_int(&w, "layers", r->pj->layers);
    json_int(&w, "first_layer", r->first);
    json_int(&w, "bin_nm", r->pj->bin_nm);
    json_bool(&w, "planned_by_printer", r->planned_by_printer);
    json_numbers(&w, "display", display, 3);
    json_number(&w, "seconds", r->seconds);
    json_int(&w, "bytes_out", (long long)r->l->bytes_out);
    json_int(&w, "bytes_in", (long long)r->l->bytes_in);
    json_int(&w, "mask_code_bytes", (long long)r->mask_bytes);
    json_int(&w, "retransmitted_frames", (long long)r->l->retransmits);
    json_int(&w, "naks", (long long)r->l->naks);
    json_number(&w, "longest_wait_ms", r->l->longest_wait);
    json_begin_array(&w, "masks", 0);
    for (k = 0; k < r->pj->layers; k++) {
        char crc[9];
        z += r->pj->lengths[k];
        snprintf(crc, sizeof crc, "%08x", (unsigned)r->layers[k].crc);
        json_begin_object(&w, NULL, 1);
        json_int(&w, "layer", (long long)k + 1);
        json_int(&w, "top_bins", z);
        json_string(&w, "crc32", crc);
        json_int(&w, "code_bytes", (long long)r->layers[k].code_bytes);
        json_int(&w, "exposure_ms", (long long)r->pj->exposure_ms[k]);
        json_end(&w);
    }
    json_end(&w);
    json_end(&w);
}

/* -------------------------------------------------------------- options */

static void print_usage(FILE *f)
{
    fputs("usage: adaslice print MODEL|JOBDIR --port DEV [print options] [masks] [plan options]\n"
          "       adaslice print --abort --port DEV\n"
          "\n"
          "Prints on a printer running the adaslice firmware (link/PROTOCOL.md). With a\n"
          "MODEL the printer plans from the quantised profile and the host checks that the\n"
          "plan equals its own; masks are rendered as they are needed, and each layer's\n"
          "exposure follows its thickness (below). A JOBDIR from adaslice slice is printed\n"
          "with its plan, exposures and motion, from JOBDIR/masks.rle. Ctrl-C pauses\n"
          "(UV off, Z held) and exits 3; --resume-from K continues at layer K. A printer\n"
          "that restarts mid-print ends it with exit 4, one that stops answering with\n"
          "exit 5, each naming the layer to resume from.\n"
          "\n"
          "print options\n"
          "  --port DEV            the printer's serial port (required)\n"
          "  --baud B              9600 ... 230400                               [115200]\n"
          "  --resume-from K       continue at layer K, the one after the last fully\n"
          "                        exposed: a paused print of this job is resumed in\n"
          "                        place, giving only the light the layer still owes;\n"
          "                        a printer that lost the job (restarted) or Z's home\n"
          "                        (a fault) needs --home\n"
          "  --exposure-left MS    with --resume-from K: the light layer K still owes,\n"
          "                        as the message after a stop mid-exposure gives it\n"
          "                        (a print resumed in place gets the printer's own)\n"
          "  --home                home Z before resuming if it is not homed. WARNING:\n"
          "                        homing drives the platform down to the endstop, into\n"
          "                        the vat and the half-built part: clear it first\n"
          "  --plan-on-host        send the host's plan instead of the profile\n"
          "  --give-up S           a printer that answers nothing this long ends      [3]\n"
          "                        the print (exit 5); longer while a mask or profile\n"
          "                        frame is worked through (at the pace the printer\n"
          "                        states) and on slow lines\n"
          "  --report FILE         a JSON record: each layer's mask CRC-32 and code size\n"
          "  --then-exit           end the firmware after the print (emulators and the\n"
          "                        simulator; a real board ignores it)\n"
          "  --abort               abandon the print paused on the printer (no MODEL):\n"
          "                        UV off, the display dark, then the platform lifted\n"
          "                        to the top of Z's travel at 5 mm/s (if Z is homed)\n"
          "\n"
          "masks (the display's size and pitch come from the printer)\n"
          "  --mirror, --rotate, --aa, --slice-at, --place, --memory   as adaslice slice\n"
          "\n", f);
    screen_usage(f);
    fputc('\n', f);
    cure_usage(f);
    fputc('\n', f);
    plan_options_usage(f, FOR_PRINT);
}

static int parse_print(int argc, char **argv, print_args *pa, int *rest_argc, char **rest)
{
    int i, rc = RC_OK;
    memset(pa, 0, sizeof *pa);
    pa->baud = 115200;
    pa->give_up_s = 3;
    pa->screen.packing = -1;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        size_t n = 115200;
        if (!strcmp(o, "--port")) rc = file_option(argc, argv, &i, &pa->port);
        else if (!strcmp(o, "--report")) rc = file_option(argc, argv, &i, &pa->report);
        else if (!strcmp(o, "--baud")) { if (!(rc = count_option(argc, argv, &i, 4000000, &n))) pa->baud = (long)n; }
        else if (!strcmp(o, "--resume-from")) rc = count_option(argc, argv, &i, UINT32_MAX, &pa->resume_from);
        else if (!strcmp(o, "--exposure-left")) rc = count_option(argc, argv, &i, UINT32_MAX, &pa->exposure_left);
        else if (!strcmp(o, "--give-up")) rc = number_option(argc, argv, &i, 0, &pa->give_up_s);
        else if (!strcmp(o, "--plan-on-host")) pa->plan_on_host = 1;
        else if (!strcmp(o, "--home")) pa->home = 1;
        else if (!strcmp(o, "--then-exit")) pa->then_exit = 1;
        else if (!strcmp(o, "--abort")) pa->abort = 1;
        else if (screen_option(argc, argv, &i, &pa->screen, &rc)) {}
        else if (!strcmp(o, "--help") || !strcmp(o, "-h")) { print_usage(stdout); return -1; }
        else rest[(*rest_argc)++] = argv[i];
    }
    if (rc) return rc;
    if (!pa->port) return complain(RC_USAGE, "print needs --port DEV");
    if (pa->exposure_left && !pa->resume_from) return complain(RC_USAGE, "--exposure-left: the light of the layer --resume-from K names");
    if (pa->abort && (*rest_argc > 1 || pa->resume_from || pa->home || pa->plan_on_host || pa->report || pa->then_exit ||
                      pa->screen.device))
        return complain(RC_USAGE, "--abort %s: --abort abandons the paused print and takes only --port, --baud and --give-up",
                        *rest_argc > 1 ? rest[1] : "with print options");
    return RC_OK;
}

/* ------------------------------------------------------- the host's screen */

/* What print/screen_print.c asks of the job: layer k's mask as an image. */
typedef struct screen_source {
    print_job *pj;
    report_layer *rep;
    unsigned char *image;          /* a JOBDIR's mask, decoded */
    size_t stride;
} screen_source;

static void screen_row(void *ctx, uint32_t y, const unsigned char *row)
{
    screen_source *src = (screen_source *)ctx;
    memcpy(src->image + (size_t)y * src->stride, row, src->stride);
}

static int screen_mask(void *ctx, uint32_t k, const unsigned char **image, size_t *stride)
{
    screen_source *src = (screen_source *)ctx;
    print_job *pj = src->pj;
    adaslice_rle_decoder dec;
    int rc;
    src->stride = print_job_stride(pj);
    /* a MODEL's layer again (after a pause) is the image rendered last */
    if (!(pj->from_model && k == pj->rendered) && (rc = print_job_mask(pj, k))) return rc;
    src->rep[k - 1].crc = pj->crc;
    src->rep[k - 1].code_bytes = 0;
    if (pj->from_model) {
        *image = pj->masks.image;
        *stride = pj->masks.stride;
        return RC_OK;
    }
    if (!src->image && !(src->image = (unsigned char *)malloc(src->stride * (pj->height + 1u))))
        return complain(RC_FAIL, "out of memory for a mask");
    /* the decoder's row after the image's */
    if (adaslice_rle_decoder_init(&dec, pj->width, pj->height, (int)pj->bits, src->image + src->stride * pj->height,
                                  src->stride) ||
        adaslice_rle_decode(&dec, pj->code, pj->code_size, screen_row, src) || !adaslice_rle_finished(&dec) ||
        ADASLICE_RLE_CRC(&dec) != pj->crc)
        return complain(RC_FAIL, "layer %u: its mask in masks.rle does not decode to its CRC-32 %08x", k, (unsigned)pj->crc);
    *image = src->image;
    *stride = src->stride;
    return RC_OK;
}

/* The print with the masks on the host's screen, already open. */
static int print_on_screen(serial_link *l, const print_args *pa, print_job *pj, screen *scr, int in_place,
                           report_layer *rep)
{
    screen_source src;
    screen_print p;
    int rc;
    memset(&src, 0, sizeof src);
    memset(&p, 0, sizeof p);
    src.pj = pj;
    src.rep = rep;
    p.l = l;
    p.scr = scr;
    p.layers = pj->layers;
    p.width = pj->width;
    p.height = pj->height;
    p.bits = pj->bits;
    p.exposure_ms = pj->exposure_ms;
    p.exposure_left = (uint32_t)pa->exposure_left;
    p.in_place = in_place;
    p.motion = pj->motion;
    p.motion.first_layer = pa->resume_from ? (uint32_t)pa->resume_from : 1;
    p.motion.job = pj->job;
    p.mask = screen_mask;
    p.ctx = &src;
    p.interrupted = &interrupted;
    rc = screen_print_run(&p);
    free(src.image);
    return rc;
}

/* ------------------------------------------------------------ the steps */

/* A job sliced for other pixels prints scaled by the ratio of the pitches
   (0.1 mm pixels on a 0.05 mm display: half size), so it is refused before
   anything moves; a tenth of a percent is rounding in the figures. */
#define PITCH_TOLERANCE 0.001

static int check_pitch(const print_job *pj, const char *dir, const serial_link *l, const char *port)
{
    double shown = l->id.pitch_nm / 1e6, across = shown / pj->file.pitch_mm[0], down = shown / pj->file.pitch_mm[1];
    char scale[64];
    if (fabs(across - 1) <= PITCH_TOLERANCE && fabs(down - 1) <= PITCH_TOLERANCE) return RC_OK;
    if (fabs(across - down) <= PITCH_TOLERANCE * across) snprintf(scale, sizeof scale, "%.4g %%", across * 100);
    else snprintf(scale, sizeof scale, "%.4g %% across and %.4g %% down", across * 100, down * 100);
    return complain(RC_FAIL, "%s was sliced for pixels of %g x %g mm; the printer on %s shows %g mm pixels, so the part "
                             "would print at %s of its size: slice it again with --pixels %ux%u --pitch %g",
                    dir, pj->file.pitch_mm[0], pj->file.pitch_mm[1], port, shown, scale, l->id.width, l->id.height, shown);
}

/* --resume-from K against what the printer holds: K is the layer after the
   last fully exposed one of this job, which is paused (resumed in place,
   *in_place set) or stopped (an abort or a fault); or, with --home, any
   layer on a printer that lost the job. Every refusal is RC_USAGE and names
   the layer. */
static int check_resume(const serial_link *l, const print_args *pa, const print_job *pj, int *in_place)
{
    const link_status *s = &l->st;
    uint32_t k = (uint32_t)pa->resume_from, from = s->exposed + 1;
    int busy = s->state == LINK_STATE_PRINTING || s->state == LINK_STATE_PAUSED;
    if (s->job && s->job != pj->job)
        return complain(RC_USAGE, "--resume-from %u: the printer %s layer %u of another job (%08x; this one is %08x): "
                                  "give the same model, options and exposures, or print afresh", k,
                        busy ? "is paused at" : "stopped after", busy ? s->layer : s->exposed, (unsigned)s->job,
                        (unsigned)pj->job);
    if (s->job && s->state == LINK_STATE_DONE && s->exposed == s->layers)
        return complain(RC_USAGE, "--resume-from %u: the printer finished this job (all %u layer%s exposed): print it "
                                  "afresh without --resume-from", k, s->layers, plural(s->layers));
    if (busy) {
        /* paused while it peels, the layer it holds is exposed already */
        if (k != from)
            return complain(RC_USAGE, "--resume-from %u: the printer is paused at layer %u, layer %u the last fully exposed: "
                                      "resume from %u", k, s->layer, s->exposed, from);
        if (!(s->flags & LINK_FLAG_HOMED))
            return complain(RC_USAGE, "--resume-from %u: the printer is paused at layer %u with Z unhomed", k, s->layer);
        *in_place = 1;
        return RC_OK;
    }
    if (!s->job && !pa->home)
        return complain(RC_USAGE, "--resume-from %u: the printer does not know the job (it restarted; Z %s): "
                                  "clear the platform and give --home to home Z and print from layer %u", k,
                        s->flags & LINK_FLAG_HOMED ? "homed since" : "not homed", k);
    if (s->job && k != from)
        return complain(RC_USAGE, "--resume-from %u: the printer stopped this job after layer %u was fully exposed: "
                                  "resume from %u", k, s->exposed, from);
    if (!(s->flags & LINK_FLAG_HOMED) && !pa->home)
        return complain(RC_USAGE, "--resume-from %u: Z is not homed: clear the platform and give --home to home it "
                                  "and print from layer %u", k, k);
    return RC_OK;
}

/* A print paused earlier is resumed in place (*in_place) or refused; else
   the plan goes (again), and Z is homed unless it is (a resume only with
   --home). */
static int prepare(serial_link *l, const print_args *pa, const plan_job *j, print_job *pj, int planned_by_printer,
                   const char *name, int *in_place)
{
    adaslice_plan_options o;
    int rc;
    if ((rc = serial_status(l))) return rc;
    if (!pa->resume_from && l->st.state == LINK_STATE_PAUSED)
        return complain(RC_FAIL, "the printer holds a print paused at layer %u of %u (layer %u the last fully exposed): "
                                 "continue it with --resume-from %u, or abandon it with adaslice print --abort --port %s",
                        l->st.layer, l->st.layers, l->st.exposed, l->st.exposed + 1, pa->port);
    if (!pa->resume_from && l->st.state == LINK_STATE_PRINTING)
        return complain(RC_FAIL, "the printer is printing layer %u of %u (another host drives it?); Ctrl-C there pauses it",
                        l->st.layer, l->st.layers);
    if (pa->resume_from && ((rc = check_resume(l, pa, pj, in_place)) || *in_place)) return rc;
    if (planned_by_printer) plan_options_of(j->args, ADASLICE_METHOD_OPTIMAL, &o);
    l->task = planned_by_printer ? "planning" : "taking the plan";
    rc = planned_by_printer ? plan_upload_profile(l, j, &o, pj) : plan_upload_plan(l, pj);
    l->task = NULL;
    if (rc) return rc;
    printf("%s: %u layer%s, %s\n", name, pj->layers, plural(pj->layers),
           planned_by_printer ? "planned by the printer, identical to the host's plan" : "the host's plan");
    fflush(stdout);
    if ((rc = serial_status(l))) return rc;
    if (!(l->st.flags & LINK_FLAG_HOMED)) {
        l->task = "homing";
        if (!(rc = serial_send(l, LINK_MSG_HOME, NULL, 0))) rc = serial_wait(l, homed, NULL, 600000, "home Z");
        l->task = NULL;
        if (rc) return rc;
        if (!(l->st.flags & LINK_FLAG_HOMED)) return complain(RC_FAIL, "homing failed: %s", link_error_name(l->st.error));
    }
    return RC_OK;
}

/* Emulators end with the print; the acknowledgement may be lost with them. */
static int end_emulator(serial_link *l)
{
    uint8_t code[LINK_SIZE_EXIT];
    link_exit m = {0};
    double asked = now_ms();
    int rc;
    l->ending = 1;
    rc = serial_send(l, LINK_MSG_EXIT, code, link_put_exit(code, &m));
    while (!rc && l->count && now_ms() - asked < 1000 && !serial_pump(l, 20)) {}
    return l->gone ? RC_OK : rc;
}

static int is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* Which other slicer's job `path` is, by its extension (slice -o's) or its
   first bytes (CTB's magic, GOO's, a ZIP's: SL1, ChiTu zip, UVJ); NULL for
   anything else. Those are for a printer's own firmware (its USB stick),
   never a model: the loader would take their bytes for a binary STL. */
static const char *job_file_kind(const char *path)
{
    static const unsigned char goo[8] = {0x07, 0x00, 0x00, 0x00, 0x44, 0x4C, 0x50, 0x00};
    const job_format *f = job_format_for_path(path);
    unsigned char b[12] = {0};
    FILE *in;
    size_t n = 0;
    if (f && f->extension) return f->extension;
    if ((in = fopen(path, "rb")) != NULL) { n = fread(b, 1, sizeof b, in); fclose(in); }
    if (n >= 4 && (get_le32(b) & 0xFFFFFF00u) == 0x12FD0000u) return "CTB";
    if (n >= 12 && !memcmp(b + 4, goo, sizeof goo)) return "GOO";
    if (n >= 4 && !memcmp(b, "PK\3\4", 4)) return "ZIP (SL1, ChiTu or UVJ)";
    return NULL;
}

/* print's own options, then the mask options, then a JOBDIR or a MODEL and
   its plan options; -1 after --help. */
static int parse_target(int argc, char **argv, print_args *pa, slice_args *s, plan_args *a, const char **jobdir)
{
    char **rest = (char **)malloc(((size_t)argc + 4) * sizeof *rest), **rest2 = (char **)malloc(((size_t)argc + 4) * sizeof *rest2);
    int rest_argc = 0, rest2_argc = 0, rc;
    *jobdir = NULL;
    if (!rest || !rest2) { free(rest); free(rest2); return complain(RC_FAIL, "out of memory"); }
    rc = parse_print(argc, argv, pa, &rest_argc, rest);
    if (!rc && pa->abort) { free(rest); free(rest2); return RC_OK; }
    if (!rc) rc = parse_slice(rest_argc, rest, s, &rest2_argc, rest2, 0);
    if (!rc && s->geometry_given) rc = complain(RC_USAGE, "print: the printer reports its display; drop --printer/--pixels/--pitch/--display");
    if (!rc && option_given(rest_argc, rest, "--threads"))
        rc = complain(RC_USAGE, "print: each mask is made on one thread as the printer needs it; drop --threads");
    if (!rc && rest2_argc >= 2 && rest2[1][0] != '-' && is_dir(rest2[1])) {
        *jobdir = rest2[1];
        if (rest2_argc > 2) rc = complain(RC_USAGE, "print JOBDIR: %s: plan and mask options belong to adaslice slice", rest2[2]);
        else if (s->cure.given)
            rc = complain(RC_USAGE, "print JOBDIR: the job holds its exposures and motion; slice it again to change them");
    } else if (!rc) {
        const char *kind;
        if (!(rc = parse_plan(rest2_argc, rest2, a)) && a->help) { print_usage(stdout); rc = -1; }
        a->memory_mb = s->memory_mb; /* print's --memory bounds the profile too */
        if (!rc && (kind = job_file_kind(a->model)) != NULL)
            rc = complain(RC_USAGE, "print %s: a %s job file is for a printer's own firmware; adaslice print takes a MODEL (STL, "
                                    "OBJ or PLY) or a JOBDIR (adaslice slice MODEL -o DIR)", a->model, kind);
        if (!rc && (a->method != ADASLICE_METHOD_OPTIMAL || a->out || a->plot || a->profile_out || a->json || a->compare))
            rc = complain(RC_USAGE, "print plans the optimal way, as the printer does, and writes no plan files: drop "
                                    "--method, --uniform, --out, --plot, --profile-out, --json and --compare");
    }
    free(rest);
    free(rest2);
    return rc;
}

/* The lift after --abort, um/s: the part may still stick to the vat's
   film (paused in its exposure), so a peel's pace, not the axis's fastest. */
#define ABORT_LIFT_UM_S 5000u

static int not_moving(const link_status *s, const void *ctx) { (void)ctx; return s->state != LINK_STATE_MOVING; }

/* --abort: a paused print ends (ABORT: UV off, the display dark; the plan
   and job are kept), and the platform rises out of the vat to the top of
   Z's travel, where a printer's own "stop" leaves it for the part to come
   off. Anything but a paused print is left alone. */
static int abort_paused(const print_args *pa)
{
    serial_link l;
    uint8_t buf[LINK_PAYLOAD_MAX];
    link_move m;
    uint32_t layer, layers, exposed;
    int rc;
    char z[96];
    memset(&l, 0, sizeof l);
    l.fd = -1;
    if ((rc = serial_connect(&l, pa->port, pa->baud, pa->give_up_s)) || (rc = serial_status(&l))) goto done;
    layer = l.st.layer;
    layers = l.st.layers;
    exposed = l.st.exposed;
    if (l.st.state == LINK_STATE_PRINTING) {
        rc = complain(RC_FAIL, "the printer on %s is printing layer %u of %u, not paused: --abort abandons a paused print "
                               "(Ctrl-C in the host printing it pauses it)", pa->port, layer, layers);
        goto done;
    }
    if (l.st.state != LINK_STATE_PAUSED) {
        rc = complain(RC_FAIL, "the printer on %s holds no paused print (it is %s): nothing to abandon", pa->port,
                      link_state_name(l.st.state));
        goto done;
    }
    if ((rc = serial_send(&l, LINK_MSG_ABORT, NULL, 0)) || (rc = serial_status(&l))) goto done;
    if (l.st.state == LINK_STATE_PAUSED || (l.st.flags & LINK_FLAG_UV)) {
        rc = complain(RC_FAIL, "the printer on %s would not abandon the print: %s", pa->port, serial_why_not(&l));
        goto done;
    }
    if (!(l.st.flags & LINK_FLAG_HOMED)) {
        snprintf(z, sizeof z, "Z stays at %.3f mm (not homed: lifting it could not be trusted)", l.st.z_nm / 1e6);
    } else if (l.st.screen) {
        snprintf(z, sizeof z, "Z stays at %.3f mm (the host's screen still shows layer %u)", l.st.z_nm / 1e6, l.st.screen);
    } else {
        m.z_nm = (int32_t)(l.id.z_max_nm > INT32_MAX ? INT32_MAX : l.id.z_max_nm);
        m.speed_um_s = ABORT_LIFT_UM_S;
        if ((rc = serial_send(&l, LINK_MSG_MOVE, buf, link_put_move(buf, &m))) || (rc = serial_status(&l))) goto done;
        if (l.st.state != LINK_STATE_MOVING && l.st.z_nm != m.z_nm) {
            snprintf(z, sizeof z, "Z stays at %.3f mm (the lift was refused: %s)", l.st.z_nm / 1e6, serial_why_not(&l));
        } else {
            /* the travel at the lift's speed, twice over, and a minute */
            double ms = 2e6 * (m.z_nm - l.st.z_nm) / 1e6 / (ABORT_LIFT_UM_S / 1e3) + 60000;
            l.task = "lifting Z";
            rc = serial_wait(&l, not_moving, NULL, ms, "lift Z");
            l.task = NULL;
            if (rc) goto done;
            snprintf(z, sizeof z, "Z lifted to %.3f mm, the top of its travel", l.st.z_nm / 1e6);
        }
    }
    printf("abandoned the print at layer %u of %u (layer %u the last fully exposed): UV off, the display dark; %s\n", layer,
           layers, exposed, z);
done:
    serial_close(&l);
    return rc;
}

int cmd_print(int argc, char **argv)
{
    print_args pa;
    slice_args s;
    plan_args a;
    plan_job j;
    print_job pj;
    serial_link l;
    screen scr;
    report_layer *rep = NULL;
    int rc, planned_by_printer = 0, in_place = 0;
    unsigned long mask_bytes = 0;
    double started;
    const char *jobdir;
    struct sigaction sa;

    memset(&j, 0, sizeof j);
    memset(&pj, 0, sizeof pj);
    memset(&a, 0, sizeof a);
    memset(&l, 0, sizeof l);
    memset(&scr, 0, sizeof scr);
    l.fd = scr.fd = scr.guard_fd = -1;
    if ((rc = parse_target(argc, argv, &pa, &s, &a, &jobdir))) return rc < 0 ? RC_OK : rc;
    if (pa.abort) return abort_paused(&pa);
    if ((rc = output_check("--report", pa.report))) return rc; /* before hours of printing */
    pj.from_model = !jobdir;
    if ((jobdir && (rc = print_job_from_dir(&pj, jobdir))) || (rc = serial_connect(&l, pa.port, pa.baud, pa.give_up_s))) goto done;
    printf("printer on %s: %u x %u px of %g mm, %u-bit; %u steps/mm; plans up to %u bins; its pace %g us a byte of "
           "rows' CRC, %g us a bin planned\n", pa.port, l.id.width, l.id.height, l.id.pitch_nm / 1e6, l.id.bits,
           l.id.steps_per_mm, l.id.max_bins, l.id.crc_byte_ns / 1e3, l.id.plan_bin_ns / 1e3);
    fflush(stdout);
    if (jobdir && (rc = check_pitch(&pj, jobdir, &l, pa.port))) goto done;
    if (!jobdir && (rc = print_job_from_model(&pj, &a, &j, &s, &l, pa.plan_on_host, &planned_by_printer))) goto done;
    if (pj.width != l.id.width || pj.height != l.id.height || pj.bits != l.id.bits) {
        rc = complain(RC_FAIL, "the masks are %u x %u px, %u-bit; the printer shows %u x %u px, %u-bit", pj.width, pj.height,
                      pj.bits, l.id.width, l.id.height, l.id.bits);
        goto done;
    }
    {
        /* the printer refuses such a mask, so say it before the print starts */
        uint32_t k, worst = 0;
        for (k = 1; k < pj.layers; k++)
            if (pj.exposure_ms[k] > pj.exposure_ms[worst]) worst = k;
        if (pj.layers && pj.exposure_ms[worst] > l.id.max_exposure_ms) {
            rc = complain(RC_FAIL, "layer %u's exposure is %.3f s; the printer on %s lights at most %.3f s at once", worst + 1,
                          pj.exposure_ms[worst] / 1000.0, pa.port, l.id.max_exposure_ms / 1000.0);
            goto done;
        }
    }
    if (pa.resume_from > pj.layers) {
        rc = complain(RC_USAGE, "--resume-from %zu: the plan has %u layer%s", pa.resume_from, pj.layers, plural(pj.layers));
        goto done;
    }
    if (pa.exposure_left > (pa.resume_from ? pj.exposure_ms[pa.resume_from - 1] : 0)) {
        rc = complain(RC_USAGE, "--exposure-left %zu: layer %zu's exposure is %u ms", pa.exposure_left, pa.resume_from,
                      pj.exposure_ms[pa.resume_from - 1]);
        goto done;
    }
    if (pa.screen.device && ((rc = screen_open(&scr, &pa.screen)) || (rc = screen_fits(&scr, pj.width, pj.height, l.id.pitch_nm)) ||
                             (jobdir && (rc = screen_fits_job(&scr, jobdir, pj.file.pitch_mm))) ||
                             (rc = screen_guard(&scr, l.fd)) || (rc = screen_print_said_dark(&l))))
        goto done;
    if (!(rep = (report_layer *)calloc(pj.layers, sizeof *rep))) { rc = complain(RC_FAIL, "out of memory"); goto done; }
    pj.job = print_job_hash(&pj, jobdir ? NULL : &j.mesh, &s);
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    started = now_ms();
    if ((rc = prepare(&l, &pa, &j, &pj, planned_by_printer, base_name(jobdir ? jobdir : a.model), &in_place))) goto done;
    rc = pa.screen.device ? print_on_screen(&l, &pa, &pj, &scr, in_place, rep) : print_loop(&l, &pa, &pj, in_place, rep, &mask_bytes);
    if (!rc && pa.then_exit) rc = end_emulator(&l);
    if (!rc) {
        uint32_t printed = pj.layers - (pa.resume_from ? (uint32_t)pa.resume_from - 1 : 0);
        printf("printed %u layer%s in %.1f s; %lu byte%s of mask code, %lu retransmitted frame%s\n", printed,
               plural(printed), (now_ms() - started) / 1000, mask_bytes, plural(mask_bytes), l.retransmits,
               plural(l.retransmits));
    }
    if (pa.report && (rc == RC_OK || rc == RC_PAUSED)) {
        report r;
        int wrc;
        r.pj = &pj;
        r.layers = rep;
        r.l = &l;
        r.first = pa.resume_from ? (uint32_t)pa.resume_from : 1;
        r.seconds = (now_ms() - started) / 1000;
        r.mask_bytes = mask_bytes;
        r.planned_by_printer = planned_by_printer;
        if ((wrc = write_atomic(pa.report, write_report, &r))) rc = wrc;
    }
done:
    screen_close(&scr);
    serial_close(&l);
    print_job_free(&pj);
    free(rep);
    job_free(&j);
    return rc;
}
