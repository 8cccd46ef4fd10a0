/* make bench: bytes on the serial line per layer, for every shared model.

       bench_wire MODELS_DIR

   Each model is planned as adaslice print plans it (exact cusp profile,
   b = 2 um, the optimal plan in printer units: eps_units =
   ADASLICE_PRINTER_EPS_UNITS, defaults otherwise), placed on the "2k-5.5"
   printer's plate (2560 x 1440 pixels of 0.04725 mm, host/printer.c), and
   every layer's 1-bit mask is rendered (sliced at the layer's middle, as
   adaslice slice does by default), turned top row first as the tool sends it,
   and coded with adaslice_rle_encode. Scans in metres or normalised units get
   bench/bench.c's scales; a part still wider than 95 % of the plate along x
   or y is scaled down uniformly to 95 % (the table says by how much).

   On the wire (link/PROTOCOL.md), host to MCU: frames of at most 255
   bytes carry 249 of payload and 6 of overhead; a mask is one MASK frame
   (12 bytes of payload: 18 on the wire) and MASK_DATA frames of 249 bytes of
   code (adaslice print sends full frames while the line is clean). At
   115200 baud 8N1 a byte is 10 bits: 11,520 bytes/s. Mask k+1 may stream
   while layer k is printed (the MCU takes it once layer k has begun), so the
   budget is one layer's cycle: return move, settle, exposure and peel. Not
   counted: STATUS heartbeats, resends, the MCU's acknowledgements (the other
   direction of the full-duplex line).

   The profile upload is what adaslice print sends when the MCU plans: a
   PROFILE frame (14 bytes of payload) and PROFILE_DATA frames of whole
   varints of units << 1 | forced (adaslice_plan_units), cut as the tool cuts
   them (a frame is sent when 5 more bytes might not fit in 249). The
   firmware images take at most 12,000 bins; above that the tool plans and
   sends the plan (PLAN_SET, 8 bytes, and PLAN_DATA, a byte per layer),
   shown alongside. */
#include "../adaslice.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../link/frame.h"
#include "../link/messages.h"
#include "models.h"
#include "timing.h"
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PX_W 2560
#define PX_H 1440
#define PITCH 0.04725            /* mm, the 2k-5.5 preset */
#define MARGIN 0.95              /* parts fill at most this share of the plate */
#define STRIDE ((PX_W + 7) / 8)  /* 320 bytes per 1-bit row */
#define RAW ((size_t)STRIDE * PX_H)
#define PAYLOAD_MAX LINK_PAYLOAD_MAX
#define FRAME_OVERHEAD LINK_FRAME_MIN
#define MASK_FRAME (LINK_SIZE_MASK + FRAME_OVERHEAD)
#define PROFILE_FRAME (LINK_SIZE_PROFILE + FRAME_OVERHEAD)
#define PLAN_SET_FRAME (LINK_SIZE_PLAN_SET + FRAME_OVERHEAD)
#define BYTES_PER_S (115200.0 / 10.0)
#define MCU_MAX_BINS 12000u

/* The print cycle the link must keep ahead of. */
#define EXPOSURE_S 2.5
#define SETTLE_S 0.5
#define PEEL_MM 5.0
#define PEEL_UP_MM_S 2.0
#define PEEL_DOWN_MM_S 4.0
#define ACCEL_MM_S2 50.0

/* A trapezoidal move of d mm: accelerate at a to v, cruise, decelerate
   (a triangle when d is too short to reach v). */
static double move_time(double d, double v, double a)
{
    if (d >= v * v / a) return d / v + v / a;
    return 2.0 * sqrt(d / a);
}

static int is_model(const char *name)
{
    const char *dot = strrchr(name, '.');
    static const char *ext[] = {".stl", ".STL", ".obj", ".OBJ", ".ply", ".PLY"};
    size_t i;
    if (!dot) return 0;
    for (i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (!strcmp(dot, ext[i])) return 1;
    return 0;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static double mask_wire(size_t code)
{
    return MASK_FRAME + (double)code + FRAME_OVERHEAD * (double)((code + PAYLOAD_MAX - 1) / PAYLOAD_MAX);
}

typedef struct row {
    char name[28];
    double scale, fit, size[3];
    size_t layers, bins, varint_bytes;
    uint32_t bins_max;
    double code_mean, code_median, code_max, ratio, wire_mean, wire_median, wire_max, wire_total;
    double profile_wire, plan_wire, encode_s, memcpy_s;
    int decoded_ok;
} row;

static void fail(const char *model, const char *what, const adaslice_error *e)
{
    printf("bench_wire: %s: %s%s%s\n", model, what, e ? ": " : "", e ? e->message : "");
    exit(1);
}

static int load_scaled(const char *path, double scale, adaslice_mesh *m, adaslice_error *e)
{
    adaslice_load_options lo;
    memset(&lo, 0, sizeof lo);
    lo.scale = scale;
    /* repaired as the tool repairs what it loads */
    return adaslice_mesh_load_file(path, &lo, m, e) == ADASLICE_OK && adaslice_mesh_repair(m, NULL, NULL, e) == ADASLICE_OK;
}

static void bench_model(const char *dir, const char *name, row *r)
{
    char path[4096];
    adaslice_mesh m;
    adaslice_profile p;
    adaslice_plan plan;
    adaslice_plan_options o;
    adaslice_masker mk;
    adaslice_grid g;
    adaslice_error e;
    double lo[3], hi[3], fit, *code_sizes, *wire;
    unsigned char *top, *copy, *code, *forced, row_buf[STRIDE];
    uint32_t *units;
    size_t k, cap = adaslice_rle_bound(PX_W, PX_H, 1), best = 0, frames, i;

    memset(r, 0, sizeof *r);
    snprintf(r->name, sizeof r->name, "%.27s", name);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    r->scale = bench_model_scale(name);
    if (!load_scaled(path, r->scale, &m, &e)) fail(name, "load", &e);
    adaslice_mesh_bounds(&m, lo, hi);
    fit = 1;
    if (hi[0] - lo[0] > MARGIN * PX_W * PITCH) fit = MARGIN * PX_W * PITCH / (hi[0] - lo[0]);
    if (hi[1] - lo[1] > MARGIN * PX_H * PITCH && MARGIN * PX_H * PITCH / (hi[1] - lo[1]) < fit)
        fit = MARGIN * PX_H * PITCH / (hi[1] - lo[1]);
    if (fit < 1) { /* loaded again at the final scale, as adaslice slice --scale would */
        adaslice_mesh_free(&m);
        if (!load_scaled(path, r->scale * fit, &m, &e)) fail(name, "load", &e);
        adaslice_mesh_bounds(&m, lo, hi);
    }
    r->fit = fit;
    for (i = 0; i < 3; i++) r->size[i] = hi[i] - lo[i];

    /* the plan adaslice print makes when the MCU plans */
    memset(&o, 0, sizeof o);
    o.eps_units = ADASLICE_PRINTER_EPS_UNITS;
    if (adaslice_profile_exact(&m, NULL, &p, &e) != ADASLICE_OK) fail(name, "profile", &e);
    if (adaslice_plan_profile(&p, &o, &plan, &e) != ADASLICE_OK) fail(name, "plan", &e);
    r->layers = plan.layer_count;
    r->bins = p.bin_count;
    r->bins_max = plan.bins_max;

    /* the profile upload, cut into frames as host/print/cmd_print.c cuts it */
    units = (uint32_t *)malloc(p.bin_count * sizeof *units);
    forced = (unsigned char *)malloc(p.bin_count);
    if (!units || !forced) fail(name, "out of memory", NULL);
    if (adaslice_plan_units(&p, &o, units, forced, &e) != ADASLICE_OK) fail(name, "plan units", &e);
    frames = 0;
    {
        uint8_t payload[LINK_PAYLOAD_MAX];
        uint32_t at = 0;
        while (at < p.bin_count) {
            r->varint_bytes += link_profile_chunk(payload, LINK_PAYLOAD_MAX, units, forced, (uint32_t)p.bin_count, &at);
            frames++;
        }
    }
    r->profile_wire = PROFILE_FRAME + (double)r->varint_bytes + FRAME_OVERHEAD * (double)frames;
    r->plan_wire = PLAN_SET_FRAME + (double)r->layers + FRAME_OVERHEAD * (double)((r->layers + PAYLOAD_MAX - 1) / PAYLOAD_MAX);
    free(units);
    free(forced);

    /* every layer's mask, coded */
    g = adaslice_grid_plate(&m, PX_W, PX_H, PITCH, PITCH, NULL);
    if (adaslice_masker_init(&mk, &m, &g, &(adaslice_mask_options){1, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, &e) != ADASLICE_OK) fail(name, "masker", &e);
    if (mk.stride != STRIDE) fail(name, "unexpected mask stride", NULL);
    top = (unsigned char *)malloc(RAW);
    copy = (unsigned char *)malloc(RAW);
    code = (unsigned char *)malloc(cap);
    code_sizes = (double *)malloc((plan.layer_count + 1) * sizeof *code_sizes);
    wire = (double *)malloc((plan.layer_count + 1) * sizeof *wire);
    if (!top || !copy || !code || !code_sizes || !wire) fail(name, "out of memory", NULL);
    r->decoded_ok = 1;
    for (k = 0; k < plan.layer_count; k++) {
        double t0, t1, t2;
        size_t n, y;
        if (adaslice_masker_slice(&mk, p.z0 + 0.5 * (plan.layers[k].z_bottom + plan.layers[k].z_top), &e) != ADASLICE_OK)
            fail(name, "slice", &e);
        /* the display's top row first: the grid's last row (adaslice slice's default) */
        for (y = 0; y < PX_H; y++) memcpy(top + y * STRIDE, mk.image + (PX_H - 1 - y) * mk.stride, STRIDE);
        t0 = now();
        memcpy(copy, top, RAW);
        t1 = now();
        if (adaslice_rle_encode(copy, STRIDE, PX_W, PX_H, 1, code, cap, &n) != ADASLICE_OK) n = 0;
        t2 = now();
        if (!n) fail(name, "adaslice_rle_encode returned 0", NULL);
        r->memcpy_s += t1 - t0;
        r->encode_s += t2 - t1;
        code_sizes[k] = (double)n;
        wire[k] = mask_wire(n);
        r->code_mean += (double)n;
        r->wire_total += wire[k];
        /* each new largest code is decoded again and checked against the mask */
        if (n > best) {
            adaslice_rle_decoder dec;
            best = n;
            if (adaslice_rle_decoder_init(&dec, PX_W, PX_H, 1, row_buf, sizeof row_buf) != ADASLICE_OK ||
                adaslice_rle_decode(&dec, code, n, NULL, NULL) != ADASLICE_OK || !adaslice_rle_finished(&dec) ||
                ADASLICE_RLE_CRC(&dec) != adaslice_crc32(0, top, RAW))
                r->decoded_ok = 0;
        }
    }
    r->ratio = (double)RAW * (double)plan.layer_count / r->code_mean;
    r->code_mean /= (double)plan.layer_count;
    r->wire_mean = r->wire_total / (double)plan.layer_count;
    r->code_max = (double)best;
    r->wire_max = mask_wire(best);
    r->code_median = median(code_sizes, (int)plan.layer_count);
    r->wire_median = median(wire, (int)plan.layer_count);
    free(top);
    free(copy);
    free(code);
    free(code_sizes);
    free(wire);
    adaslice_masker_free(&mk);
    adaslice_plan_free(&plan);
    adaslice_profile_free(&p);
    adaslice_mesh_free(&m);
    if (!r->decoded_ok) fail(name, "a mask's code did not decode to the mask", NULL);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "../shared/models";
    DIR *d = opendir(dir);
    struct dirent *ent;
    char **names = NULL;
    row *rows, all;
    size_t count = 0, i;
    double up = move_time(PEEL_MM, PEEL_UP_MM_S, ACCEL_MM_S2), down = move_time(PEEL_MM, PEEL_DOWN_MM_S, ACCEL_MM_S2);
    double cycle = EXPOSURE_S + SETTLE_S + up + down, started = now();

    if (!d) { printf("bench_wire: cannot open %s\n", dir); return 1; }
    while ((ent = readdir(d)) != NULL) {
        char **more;
        if (!is_model(ent->d_name)) continue;
        if (!(more = (char **)realloc(names, (count + 1) * sizeof *names))) return 1;
        names = more;
        if (!(names[count] = (char *)malloc(strlen(ent->d_name) + 1))) return 1;
        strcpy(names[count++], ent->d_name);
    }
    closedir(d);
    if (!count) { printf("bench_wire: no models in %s\n", dir); return 1; }
    qsort(names, count, sizeof *names, by_name);
    if (!(rows = (row *)calloc(count, sizeof *rows))) return 1;
    for (i = 0; i < count; i++) bench_model(dir, names[i], &rows[i]);

    memset(&all, 0, sizeof all);
    printf("wire  masks for the 2k-5.5 display, %d x %d px of %.5f mm, 1-bit (%zu bytes raw per layer), "
           "cusp plan b = 2 um, eps_units %u, sliced at mid-layer\n", PX_W, PX_H, PITCH, RAW, ADASLICE_PRINTER_EPS_UNITS);
    printf("wire  %-27s %7s %5s %17s %6s %10s %8s %8s %7s %8s %9s %9s %9s\n", "model", "scale", "fit", "size x*y*z mm",
           "layers", "N bins", "mean B", "median B", "max B", "raw/code", "wire mean", "wire med", "wire max");
    for (i = 0; i < count; i++) {
        const row *r = &rows[i];
        char size[32], fit[16];
        snprintf(size, sizeof size, "%.1f*%.1f*%.1f", r->size[0], r->size[1], r->size[2]);
        if (r->fit < 1) snprintf(fit, sizeof fit, "x%.3f", r->fit);
        else snprintf(fit, sizeof fit, "-");
        printf("wire  %-27s %7g %5s %17s %6zu %10zu %8.0f %8.0f %7.0f %7.0fx %9.0f %9.0f %9.0f\n", r->name, r->scale, fit, size,
               r->layers, r->bins, r->code_mean, r->code_median, r->code_max, r->ratio, r->wire_mean, r->wire_median,
               r->wire_max);
        all.layers += r->layers;
        all.wire_total += r->wire_total;
        all.code_mean += r->code_mean * (double)r->layers;
        all.encode_s += r->encode_s;
        all.memcpy_s += r->memcpy_s;
        if (r->wire_max > all.wire_max) all.wire_max = r->wire_max;
    }
    printf("wire  (fit: scaled down uniformly so the part spans at most %.0f %% of the %.2f x %.2f mm plate; "
           "scale x fit is the --scale that reproduces it)\n", MARGIN * 100, PX_W * PITCH, PX_H * PITCH);

    printf("\nwire  link at 115200 baud 8N1 (%.0f B/s), host to MCU; cycle = exposure %.1f s + settle %.1f s + peel %.0f mm up "
           "at %.0f mm/s (%.3f s) + back at %.0f mm/s (%.3f s), %.0f mm/s^2 trapezoids = %.3f s\n",
           BYTES_PER_S, EXPOSURE_S, SETTLE_S, PEEL_MM, PEEL_UP_MM_S, up, PEEL_DOWN_MM_S, down, ACCEL_MM_S2, cycle);
    printf("wire  %-27s %11s %11s %12s %12s %10s | %8s %9s %9s %7s %11s\n", "model", "stream med", "stream max",
           "max / cycle", "print MB", "link busy", "N bins", "varint B", "wire B", "upload", "MCU plans?");
    for (i = 0; i < count; i++) {
        const row *r = &rows[i];
        int mcu = r->bins <= MCU_MAX_BINS && r->bins_max <= 127;
        char plans[40];
        if (mcu) snprintf(plans, sizeof plans, "yes");
        else snprintf(plans, sizeof plans, "no: PLAN %.0f B, %.2f s", r->plan_wire, r->plan_wire / BYTES_PER_S);
        printf("wire  %-27s %9.3f s %9.3f s %11.1f %% %12.2f %9.1f %% | %8zu %9zu %9.0f %5.2f s  %s\n", r->name,
               r->wire_median / BYTES_PER_S, r->wire_max / BYTES_PER_S, 100 * r->wire_max / BYTES_PER_S / cycle,
               r->wire_total / 1e6, 100 * r->wire_total / BYTES_PER_S / (cycle * (double)r->layers), r->bins,
               r->varint_bytes, r->profile_wire, r->profile_wire / BYTES_PER_S, plans);
    }
    printf("wire  (link busy: all masks' wire time over the print's cycles; the first mask streams before the print starts)\n");

    printf("\nwire  coding: adaslice_rle_encode against memcpy of the same %zu-byte mask, same process, per layer\n", RAW);
    printf("wire  %-27s %10s %12s %12s %10s\n", "model", "layers/s", "encode ms", "memcpy ms", "encode/cpy");
    for (i = 0; i < count; i++) {
        const row *r = &rows[i];
        printf("wire  %-27s %10.0f %12.3f %12.4f %9.1fx\n", r->name, (double)r->layers / r->encode_s,
               r->encode_s * 1e3 / (double)r->layers, r->memcpy_s * 1e3 / (double)r->layers, r->encode_s / r->memcpy_s);
    }
    printf("wire  %-27s %10.0f %12.3f %12.4f %9.1fx\n", "all", (double)all.layers / all.encode_s,
           all.encode_s * 1e3 / (double)all.layers, all.memcpy_s * 1e3 / (double)all.layers, all.encode_s / all.memcpy_s);
    printf("wire  all %zu models: %zu layers, %.0f code bytes per layer on average (%.0fx), worst mask %.0f B on the wire "
           "= %.3f s = %.1f %% of a cycle; bench %.1f s\n", count, all.layers, all.code_mean / (double)all.layers,
           (double)RAW * (double)all.layers / all.code_mean, all.wire_max, all.wire_max / BYTES_PER_S,
           100 * all.wire_max / BYTES_PER_S / cycle, now() - started);
    for (i = 0; i < count; i++) free(names[i]);
    free(names);
    free(rows);
    return 0;
}
