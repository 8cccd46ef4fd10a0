/* adaslice slice: plan a model, then write its layer masks on a printer's
   pixel grid as a job directory: plan.csv, plot.svg, one PNG per layer, and
   manifest.json, written last, so a job without one is not complete. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "cli.h"
#include "png.h"
#include "printer.h"
#include "contour_svg.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>


static const char *const SLICE_AT[] = {"bottom", "middle", "top"};
static const char *const MIRRORS[] = {"none", "x", "y", "xy"};
static const char *const ROTATIONS[] = {"0", "90", "180", "270"};

void slice_options_usage(FILE *f)
{
    int i;
    fputs("printer\n"
          "  --printer NAME      a preset (below)                            [2k-5.5]\n"
          "  --pixels WxH        pixels of the display, with --pitch\n"
          "  --pitch MM          pixel size\n"
          "  --display WxH       the display's size in mm, instead of --pitch\n"
          "  --mirror M          none, x, y or xy: flip the image as the display needs [none]\n"
          "  --rotate A          0, 90, 180 or 270: turn the image counter-clockwise for a\n"
          "                      display mounted turned (90, 270: W and H are the image's)  [0]\n"
          "masks\n"
          "  --aa S              anti-aliased 8-bit masks from S x S rays per pixel\n"
          "                      (1: 1-bit masks)                            [1]\n"
          "  --slice-at WHERE    bottom, middle or top of each layer (the centre of its\n"
          "                      first, middle or last bin)                  [middle]\n"
          "  --place X,Y         the part's centre, mm from the plate's centre [0,0]\n"
          "  --svg               also each layer's contours: JOBDIR/layer_00001.svg, ...\n", f);
    fputs("printer presets\n", f);
    for (i = 0; i < PRINTER_COUNT; i++)
        fprintf(f, "  %-16s %d x %d px of %g mm: %s\n", PRINTERS[i].name, PRINTERS[i].width, PRINTERS[i].height,
                PRINTERS[i].pitch, PRINTERS[i].about);
}

static void slice_usage(FILE *f)
{
    fputs("usage: adaslice slice MODEL -o JOBDIR [printer] [masks] [plan options]\n"
          "\n"
          "Plans MODEL (as adaslice plan does) and writes JOBDIR/plan.csv, JOBDIR/plot.svg,\n"
          "one PNG mask per layer (JOBDIR/layer_00001.png, ...), the masks as a printer takes\n"
          "them (JOBDIR/masks.rle, for adaslice print) and, last, JOBDIR/manifest.json.\n"
          "A pixel is lit when the winding number of its vertical ray below the slicing\n"
          "height is positive.\n"
          "\n", f);
    slice_options_usage(f);
    fputc('\n', f);
    plan_options_usage(f);
}

int parse_slice(int argc, char **argv, slice_args *s, int *rest_argc, char **rest, int need_dir)
{
    int i, rc = RC_OK;
    memset(s, 0, sizeof *s);
    s->supersample = 1;
    s->slice_at = 1;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (!strcmp(o, "-o") || !strcmp(o, "--output")) rc = file_option(argc, argv, &i, &s->dir);
        else if (!strcmp(o, "--printer")) {
            const char *name = NULL;
            if (!(rc = file_option(argc, argv, &i, &name)) && !(s->preset = printer_find(name)))
                rc = complain(RC_USAGE, "--printer %s: unknown (see adaslice slice --help for the presets)", name);
        } else if (!strcmp(o, "--pixels")) {
            const char *v = NULL;
            char tail;
            if (!(rc = file_option(argc, argv, &i, &v)) &&
                (sscanf(v, "%dx%d%c", &s->width, &s->height, &tail) != 2 || s->width < 1 || s->height < 1 ||
                 s->width > 65536 || s->height > 65536))
                rc = complain(RC_USAGE, "--pixels %s: expected WxH, each 1 to 65536", v);
        } else if (!strcmp(o, "--pitch")) rc = number_option(argc, argv, &i, 0, &s->pitch);
        else if (!strcmp(o, "--display")) {
            const char *v = NULL;
            char tail;
            if (!(rc = file_option(argc, argv, &i, &v)) &&
                (sscanf(v, "%lfx%lf%c", &s->display[0], &s->display[1], &tail) != 2 || !(s->display[0] > 0) ||
                 !(s->display[1] > 0) || !isfinite(s->display[0]) || !isfinite(s->display[1])))
                rc = complain(RC_USAGE, "--display %s: expected WxH in mm", v);
        } else if (!strcmp(o, "--rotate")) rc = name_option(argc, argv, &i, ROTATIONS, 4, "0, 90, 180 or 270", &s->rotate);
        else if (!strcmp(o, "--aa")) {
            size_t n = 0;
            if (!(rc = count_option(argc, argv, &i, &n)) && n > 16) rc = complain(RC_USAGE, "--aa %zu: at most 16", n);
            s->supersample = (int)n;
        } else if (!strcmp(o, "--slice-at")) rc = name_option(argc, argv, &i, SLICE_AT, 3, "bottom, middle or top", &s->slice_at);
        else if (!strcmp(o, "--mirror")) {
            int m = 0;
            rc = name_option(argc, argv, &i, MIRRORS, 4, "none, x, y or xy", &m);
            s->mirror_x = m & 1;
            s->mirror_y = (m >> 1) & 1;
        } else if (!strcmp(o, "--place")) {
            const char *v = NULL;
            char tail;
            if (!(rc = file_option(argc, argv, &i, &v)) &&
                (sscanf(v, "%lf,%lf%c", &s->place[0], &s->place[1], &tail) != 2 || !isfinite(s->place[0]) ||
                 !isfinite(s->place[1])))
                rc = complain(RC_USAGE, "--place %s: expected X,Y in mm", v);
            s->placed = 1;
        } else if (!strcmp(o, "--svg")) {
            s->svg = 1;
        } else if (!strcmp(o, "--help") || !strcmp(o, "-h")) {
            slice_usage(stdout);
            return -1;
        } else rest[(*rest_argc)++] = argv[i];
    }
    if (rc) return rc;
    s->geometry_given = s->preset || s->width || s->pitch || s->display[0];
    if (need_dir && !s->dir) return complain(RC_USAGE, "slice needs -o JOBDIR");
    if (s->preset && (s->width || s->pitch || s->display[0]))
        return complain(RC_USAGE, "--printer %s and --pixels/--pitch/--display: give one or the other", s->preset->name);
    if (s->pitch && s->display[0]) return complain(RC_USAGE, "--pitch and --display: give one or the other");
    if (!s->preset && !s->width && !s->pitch && !s->display[0]) s->preset = &PRINTERS[0];
    if (s->preset) {
        s->width = s->preset->width;
        s->height = s->preset->height;
        s->pitch = s->preset->pitch;
    } else if (!s->width || (!s->pitch && !s->display[0])) {
        return complain(RC_USAGE, "--pixels WxH goes with --pitch MM or --display WxH");
    } else if (s->display[0]) {
        /* square pixels: the two sides must agree */
        double px = s->display[0] / s->width, py = s->display[1] / s->height;
        if (fabs(px - py) > 0.01 * px)
            return complain(RC_USAGE, "--display %gx%g over %dx%d pixels: pixels of %g x %g mm are not square", s->display[0],
                            s->display[1], s->width, s->height, px, py);
        s->pitch = px;
    }
    if (s->rotate & 1) { /* the plate is the image turned a quarter */
        int t = s->width;
        s->width = s->height;
        s->height = t;
    }
    return RC_OK;
}

/* JOBDIR/layer_00001.EXT: five digits, more if the plan has 100,000 layers or more. */
static int layer_digits(size_t layers)
{
    int digits = 5;
    for (; layers >= 100000 && digits < 20; layers /= 10) digits++;
    return digits;
}

/* "layer_00001.EXT" */
static void layer_name(char name[40], size_t k, int digits, const char *ext)
{
    char number[24];
    int n = 0, i;
    size_t v = k + 1;
    do { number[n++] = (char)('0' + (int)(v % 10)); v /= 10; } while (v && n < 20);
    while (n < digits && n < 20) number[n++] = '0';
    for (i = 0; i < n / 2; i++) { char t = number[i]; number[i] = number[n - 1 - i]; number[n - 1 - i] = t; }
    number[n] = 0;
    snprintf(name, 40, "layer_%s.%s", number, ext);
}

static void layer_path(char *path, size_t size, const char *dir, size_t k, int digits, const char *ext)
{
    char name[40];
    layer_name(name, k, digits, ext);
    snprintf(path, size, "%s/%s", dir, name);
}

typedef struct png_file { const unsigned char *data; size_t size; } png_file;

static void write_png_bytes(FILE *f, const void *ctx)
{
    const png_file *p = (const png_file *)ctx;
    fwrite(p->data, 1, p->size, f);
}

/* The masker's image (row 0 at the lowest y) as the display shows it: PNG
   row 0 is the top, so +y points up unless mirrored; columns flip with x;
   then the image turns by quarter turns. out holds out_w x out_h pixels. */
static int mask_pixel(const adaslice_masker *mk, int x, int y)
{
    const unsigned char *row = mk->image + (size_t)y * mk->stride;
    return mk->supersample > 1 ? row[x] : (row[x >> 3] >> (7 - (x & 7))) & 1;
}

static void orient_image(const adaslice_masker *mk, const slice_args *s, unsigned char *out, size_t out_stride)
{
    int w = mk->grid.width, h = mk->grid.height, r, i;
    int out_w = (s->rotate & 1) ? h : w, out_h = (s->rotate & 1) ? w : h;
    if (!s->rotate && !s->mirror_x) { /* the common case: whole rows */
        for (r = 0; r < h; r++) memcpy(out + (size_t)r * out_stride, mk->image + (size_t)(s->mirror_y ? r : h - 1 - r) * mk->stride, mk->stride);
        return;
    }
    memset(out, 0, out_stride * (size_t)out_h);
    for (r = 0; r < out_h; r++) {
        unsigned char *dst = out + (size_t)r * out_stride;
        for (i = 0; i < out_w; i++) {
            /* (i, r) in the turned picture back to (x, y) of the upright picture, then to the grid */
            int x, y, v;
            switch (s->rotate) {
            case 1: x = w - 1 - r; y = i; break;
            case 2: x = w - 1 - i; y = h - 1 - r; break;
            case 3: x = r; y = h - 1 - i; break;
            default: x = i; y = r; break;
            }
            if (s->mirror_x) x = w - 1 - x;
            v = mask_pixel(mk, x, s->mirror_y ? y : h - 1 - y);
            if (mk->supersample > 1) dst[i] = (unsigned char)v;
            else if (v) dst[i >> 3] |= (unsigned char)(0x80u >> (i & 7));
        }
    }
}

typedef struct job_layer { double z_bottom, z_top, thickness, lit_mm2; } job_layer;

typedef struct manifest {
    const slice_args *s;
    const plan_args *a;
    const plan_job *j;
    const job_layer *layers;
    size_t count;
    int digits;
    double part[3];              /* size of the part, mm */
} manifest;

static void write_manifest(FILE *f, const void *ctx)
{
    const manifest *m = (const manifest *)ctx;
    const slice_args *s = m->s;
    const adaslice_plan *p = &m->j->plan[m->a->method];
    size_t k;
    fputs("{\n  \"format\": \"adaslice-job\",\n  \"version\": ", f);
    json_string(f, ADASLICE_VERSION);
    fputs(",\n  \"complete\": true,\n  \"model\": ", f);
    json_string(f, m->a->model);
    fputs(",\n  \"printer\": {\"name\": ", f);
    if (s->preset) json_string(f, s->preset->name); else fputs("null", f);
    fprintf(f, ", \"width_px\": %d, \"height_px\": %d, \"pitch_mm\": ", (s->rotate & 1) ? s->height : s->width,
            (s->rotate & 1) ? s->width : s->height);
    json_number(f, s->pitch);
    fprintf(f, ", \"mirror\": \"%s\", \"rotate\": %s},\n", MIRRORS[s->mirror_x | (s->mirror_y << 1)], ROTATIONS[s->rotate]);
    fprintf(f, "  \"mask\": {\"bits\": %d, \"supersample\": %d, \"slice_at\": \"%s\"},\n",
            s->supersample > 1 ? 8 : 1, s->supersample, SLICE_AT[s->slice_at]);
    fputs("  \"part_mm\": [", f);
    for (k = 0; k < 3; k++) { if (k) fputs(", ", f); json_number(f, m->part[k]); }
    fputs("],\n  \"place_mm\": [", f);
    json_number(f, s->place[0]);
    fputs(", ", f);
    json_number(f, s->place[1]);
    fprintf(f, "],\n  \"metric\": \"%s\",\n  \"method\": \"%s\",\n  \"eps\": ", METRIC_NAMES[m->a->metric],
            METHOD_NAMES[m->a->method]);
    json_number(f, p->eps);
    fprintf(f, ",\n  \"layer_count\": %zu,\n  \"layers\": [", m->count);
    for (k = 0; k < m->count; k++) {
        const job_layer *l = &m->layers[k];
        char name[40];
        layer_name(name, k, m->digits, "png");
        fprintf(f, "%s\n    {\"index\": %zu, \"file\": \"%s\", \"z_bottom\": ", k ? "," : "", k + 1, name);
        json_number(f, l->z_bottom);
        fputs(", \"z_top\": ", f);
        json_number(f, l->z_top);
        fputs(", \"thickness\": ", f);
        json_number(f, l->thickness);
        fputs(", \"lit_area_mm2\": ", f);
        json_number(f, l->lit_mm2);
        fputc('}', f);
    }
    fputs("\n  ]\n}\n", f);
}

/* A bar on a terminal, nothing otherwise; at most ten redraws a second. */
static void progress(size_t done, size_t total, double started, double *last)
{
    double t = now_ms(), eta;
    int filled, i;
    if (!isatty(2) || (done < total && t - *last < 100)) return;
    *last = t;
    filled = (int)(30.0 * done / total);
    eta = done ? (t - started) * (double)(total - done) / (double)done / 1000 : 0;
    fputs("\r[", stderr);
    for (i = 0; i < 30; i++) fputc(i < filled ? '#' : ' ', stderr);
    fprintf(stderr, "] %zu/%zu layers, %.1f s left ", done, total, eta);
    if (done == total) fputc('\n', stderr);
}

/* Where the grid's pixel (0, 0) lies in the model's coordinates, after
   checking that the part fits on the plate. */
static int place_part(const slice_args *s, const adaslice_mesh *mesh, adaslice_grid *g, double size[3])
{
    double lo[3], hi[3], plate[2], over[2];
    int k;
    adaslice_mesh_bounds(mesh, lo, hi);
    plate[0] = s->width * s->pitch;
    plate[1] = s->height * s->pitch;
    for (k = 0; k < 3; k++) size[k] = hi[k] - lo[k];
    for (k = 0; k < 2; k++) over[k] = fabs(s->place[k]) + size[k] / 2 - plate[k] / 2;
    if (over[0] > 0 || over[1] > 0)
        return complain(RC_FAIL, "the part (%g x %g mm%s) does not fit the %g x %g mm plate: %g mm too wide along %s",
                        size[0], size[1], s->placed ? ", placed off centre" : "", plate[0], plate[1],
                        over[0] > over[1] ? over[0] : over[1], over[0] > over[1] ? "x" : "y");
    *g = adaslice_grid_plate(mesh, s->width, s->height, s->pitch, s->place);
    return RC_OK;
}

/* Where layer k is sliced, mm above the part's bottom. */
static double slice_height(const slice_args *s, const plan_job *j, size_t k)
{
    const adaslice_layer *l = &j->plan[j->args->method].layers[k];
    if (s->slice_at == 0) return l->z_bottom + j->profile.bin / 2;
    if (s->slice_at == 2) return l->z_top - j->profile.bin / 2;
    return 0.5 * (l->z_bottom + l->z_top);
}

typedef struct contour_file { const adaslice_contours *c; size_t layer; } contour_file;

static void write_contour_svg(FILE *f, const void *ctx)
{
    const contour_file *cf = (const contour_file *)ctx;
    svg_write_contours(f, cf->c, cf->layer, 1);
}

/* The slice polygons at the masks' heights, one SVG per layer; chaining
   needs shared vertices, so the mesh is welded first (STL has none). */
static int write_contours(const slice_args *s, const plan_args *a, plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    adaslice_contours c;
    adaslice_error err;
    contour_file cf;
    double *heights = (double *)malloc((p->layer_count ? p->layer_count : 1) * sizeof *heights);
    size_t k, n = strlen(s->dir) + 64;
    char *path = (char *)malloc(n);
    int rc = RC_OK, digits = layer_digits(p->layer_count);
    if (!heights || !path) { free(heights); free(path); return complain(RC_FAIL, "out of memory for the contours"); }
    for (k = 0; k < p->layer_count; k++) heights[k] = j->profile.z0 + slice_height(s, j, k);
    if (adaslice_mesh_weld(&j->mesh, NULL, &err) != ADASLICE_OK ||
        adaslice_contours_slice(&j->mesh, heights, p->layer_count, NULL, &c, &err) != ADASLICE_OK) {
        free(heights);
        free(path);
        return library_error(&err);
    }
    cf.c = &c;
    for (k = 0; k < p->layer_count && !rc; k++) {
        layer_path(path, n, s->dir, k, digits, "svg");
        cf.layer = k;
        rc = write_atomic(path, write_contour_svg, &cf);
    }
    adaslice_contours_free(&c);
    free(heights);
    free(path);
    return rc;
}

int layer_masks_open(layer_masks *m, const slice_args *s, const plan_job *j)
{
    adaslice_mask_options mo;
    adaslice_error err;
    int rc;
    memset(m, 0, sizeof *m);
    m->s = s;
    m->j = j;
    if ((rc = place_part(s, &j->mesh, &m->grid, m->part))) return rc;
    memset(&mo, 0, sizeof mo);
    mo.supersample = s->supersample;
    if (adaslice_masker_init(&m->masker, &j->mesh, &m->grid, &mo, &err) != ADASLICE_OK)
        return library_error(&err);
    m->width = (s->rotate & 1) ? m->grid.height : m->grid.width;
    m->height = (s->rotate & 1) ? m->grid.width : m->grid.height;
    m->bits = s->supersample > 1 ? 8 : 1;
    m->stride = m->bits == 8 ? (size_t)m->width : ((size_t)m->width + 7) / 8;
    if (!(m->image = (unsigned char *)malloc(m->stride * (size_t)m->height))) {
        adaslice_masker_free(&m->masker);
        return complain(RC_FAIL, "out of memory for a %d x %d mask", m->width, m->height);
    }
    return RC_OK;
}

int layer_masks_render(layer_masks *m, size_t k)
{
    adaslice_error err;
    if (adaslice_masker_slice(&m->masker, m->j->profile.z0 + slice_height(m->s, m->j, k), &err) != ADASLICE_OK)
        return library_error(&err);
    orient_image(&m->masker, m->s, m->image, m->stride);
    return RC_OK;
}

void layer_masks_close(layer_masks *m)
{
    adaslice_masker_free(&m->masker);
    free(m->image);
    m->image = NULL;
}

/* JOBDIR/masks.rle: what adaslice print streams from a job. Little-endian:
   "ADASMSK1", u32 width, height, bits, layers, bin_nm; then per layer u32
   bins (its thickness), u32 CRC-32 of the mask, u32 code bytes, the code. */
typedef struct rle_file {
    const layer_masks *m;
    unsigned char **codes;
    const size_t *sizes;
    const uint32_t *crcs;
    const adaslice_plan *plan;
    uint32_t bin_nm;
} rle_file;

static void put_u32(FILE *f, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    fwrite(b, 1, 4, f);
}

static void write_rle_file(FILE *f, const void *ctx)
{
    const rle_file *r = (const rle_file *)ctx;
    size_t k;
    fwrite("ADASMSK1", 1, 8, f);
    put_u32(f, (uint32_t)r->m->width);
    put_u32(f, (uint32_t)r->m->height);
    put_u32(f, (uint32_t)r->m->bits);
    put_u32(f, (uint32_t)r->plan->layer_count);
    put_u32(f, r->bin_nm);
    for (k = 0; k < r->plan->layer_count; k++) {
        put_u32(f, r->plan->planes[k + 1] - r->plan->planes[k]);
        put_u32(f, r->crcs[k]);
        put_u32(f, (uint32_t)r->sizes[k]);
        fwrite(r->codes[k], 1, r->sizes[k], f);
    }
}

static int write_masks(const slice_args *s, const plan_args *a, plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    layer_masks m;
    manifest man;
    rle_file rf;
    job_layer *layers = NULL;
    unsigned char **codes = NULL;
    size_t *sizes = NULL, k, path_size = strlen(s->dir) + 64, count = p->layer_count;
    uint32_t *crcs = NULL;
    char *path = NULL;
    double started = now_ms(), last = 0, bin_nm = j->profile.bin * 1e6;
    int rc;

    memset(&man, 0, sizeof man);
    if ((rc = layer_masks_open(&m, s, j))) return rc;
    memcpy(man.part, m.part, sizeof man.part);
    layers = (job_layer *)calloc(count ? count : 1, sizeof *layers);
    codes = (unsigned char **)calloc(count ? count : 1, sizeof *codes);
    sizes = (size_t *)calloc(count ? count : 1, sizeof *sizes);
    crcs = (uint32_t *)calloc(count ? count : 1, sizeof *crcs);
    path = (char *)malloc(path_size);
    if (!layers || !codes || !sizes || !crcs || !path) { rc = complain(RC_FAIL, "out of memory for the masks"); goto done; }
    man.digits = layer_digits(count);
    if (s->svg && (rc = write_contours(s, a, j))) goto done;
    for (k = 0; k < count; k++) {
        png_file png;
        unsigned char *data = NULL;
        size_t bound = adaslice_rle_bound((uint32_t)m.width, (uint32_t)m.height, m.bits);
        if ((rc = layer_masks_render(&m, k))) goto done;
        if (png_encode_gray(m.image, m.width, m.height, m.stride, m.bits, &data, &png.size)) {
            rc = complain(RC_FAIL, "out of memory encoding layer %zu", k + 1);
            goto done;
        }
        png.data = data;
        layer_path(path, path_size, s->dir, k, man.digits, "png");
        rc = write_atomic(path, write_png_bytes, &png);
        free(data);
        if (rc) goto done;
        if (!(codes[k] = (unsigned char *)malloc(bound))) { rc = complain(RC_FAIL, "out of memory coding layer %zu", k + 1); goto done; }
        (void)adaslice_rle_encode(m.image, m.stride, (uint32_t)m.width, (uint32_t)m.height, m.bits, codes[k], bound,
                                  &sizes[k]);
        crcs[k] = adaslice_crc32(0, m.image, m.stride * (size_t)m.height);
        layers[k].z_bottom = p->layers[k].z_bottom;
        layers[k].z_top = p->layers[k].z_top;
        layers[k].thickness = p->layers[k].thickness;
        layers[k].lit_mm2 = m.masker.lit * m.grid.pitch * m.grid.pitch;
        progress(k + 1, count, started, &last);
    }
    rf.m = &m;
    rf.codes = codes;
    rf.sizes = sizes;
    rf.crcs = crcs;
    rf.plan = p;
    rf.bin_nm = (uint32_t)(bin_nm + 0.5);
    snprintf(path, path_size, "%s/masks.rle", s->dir);
    if (fabs(bin_nm - rf.bin_nm) > 1e-6 * bin_nm) remove(path); /* a printer counts whole nanometres */
    else if ((rc = write_atomic(path, write_rle_file, &rf))) goto done;
    man.s = s;
    man.a = a;
    man.j = j;
    man.layers = layers;
    man.count = count;
    snprintf(path, path_size, "%s/manifest.json", s->dir);
    rc = write_atomic(path, write_manifest, &man);
done:
    layer_masks_close(&m);
    for (k = 0; codes && k < count; k++) free(codes[k]);
    free(codes);
    free(sizes);
    free(crcs);
    free(layers);
    free(path);
    return rc;
}

int cmd_slice(int argc, char **argv)
{
    slice_args s;
    plan_args a;
    plan_job j;
    char **rest = (char **)malloc(((size_t)argc + 4) * sizeof *rest), *csv = NULL, *svg = NULL, *manifest = NULL;
    int rest_argc = 0, rc;
    size_t n;
    struct stat st;

    memset(&j, 0, sizeof j);
    if (!rest) return complain(RC_FAIL, "out of memory");
    rc = parse_slice(argc, argv, &s, &rest_argc, rest, 1);
    if (rc < 0) { free(rest); return RC_OK; }
    if (!rc) rc = parse_plan(rest_argc, rest, &a);
    if (!rc && a.help) { slice_usage(stdout); free(rest); return RC_OK; }
    if (!rc && a.profile) rc = complain(RC_USAGE, "slice needs a MODEL, not --profile");
    free(rest);
    if (rc) return rc;
    if (mkdir(s.dir, 0777) != 0 && errno != EEXIST) return complain(RC_FAIL, "cannot create %s: %s", s.dir, strerror(errno));
    if (stat(s.dir, &st) != 0 || !S_ISDIR(st.st_mode)) return complain(RC_FAIL, "%s is not a directory", s.dir);
    n = strlen(s.dir) + 32;
    csv = (char *)malloc(n);
    svg = (char *)malloc(n);
    manifest = (char *)malloc(n);
    if (!csv || !svg || !manifest) { rc = complain(RC_FAIL, "out of memory"); goto done; }
    snprintf(csv, n, "%s/plan.csv", s.dir);
    snprintf(svg, n, "%s/plot.svg", s.dir);
    snprintf(manifest, n, "%s/manifest.json", s.dir);
    /* an earlier job's manifest must not vouch for layers about to change */
    if (remove(manifest) != 0 && errno != ENOENT) { rc = complain(RC_FAIL, "cannot remove %s: %s", manifest, strerror(errno)); goto done; }
    if (!a.out) a.out = csv;
    if (!a.plot) a.plot = svg;
    j.args = &a;
    j.keep_mesh = 1;
    rc = run_plan(&a, &j);
    if (!rc) rc = write_outputs(&a, &j);
    if (!rc) rc = write_masks(&s, &a, &j);
    if (!rc) printf("%s: %zu layers for %s on %d x %d px of %g mm\n", s.dir, j.plan[a.method].layer_count,
                    base_name(a.model), s.width, s.height, s.pitch);
done:
    job_free(&j);
    free(csv);
    free(svg);
    free(manifest);
    return rc;
}
