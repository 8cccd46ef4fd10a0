/* Job previews show the part as it stands on the plate, the build direction
   (+z) up the picture: an upright 10 x 10 x 80 mm box is drawn taller than
   wide and a flat 80 x 80 x 5 mm slab wider than tall, in the CTB and GOO
   previews (read back by tests/job_readers.c), in a job directory's
   preview.png and in saliency --png's picture (read back by oiiotool); and
   the demo hand, stood on its wrist by --orient 0,1,0, is drawn with the
   wrist below the fingers. */
#include "util.h"
#include "check.h"
#include "cli_run.h"
#include "job_readers.h"
#include "meshgen.h"
#include "tool_run.h"
#include "../host/plan_job.h"
#include "../host/report.h"
#include "../adaslice.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The bounding box of the part's pixels, those not of the background (the
   top left pixel's colour: the part is fitted inside a margin), rows top
   first. */
typedef struct lit_box { int left, top, right, bottom; size_t lit; } lit_box;

static lit_box lit_pixels(const unsigned char *rgb, int w, int h)
{
    lit_box b = {w, h, -1, -1, 0};
    int x, y;
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            const unsigned char *p = rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
            if (!memcmp(p, rgb, 3)) continue;
            b.lit++;
            if (x < b.left) b.left = x;
            if (x > b.right) b.right = x;
            if (y < b.top) b.top = y;
            if (y > b.bottom) b.bottom = y;
        }
    return b;
}

/* tall: the box's height over its width is above `factor`; else its width
   over its height is. And the part is drawn at all (1% of the pixels). */
static void check_shape(const char *what, const unsigned char *rgb, int w, int h, int tall, double factor)
{
    lit_box b = lit_pixels(rgb, w, h);
    double bw = b.right - b.left + 1, bh = b.bottom - b.top + 1;
    CHECKF(b.lit * 100 > (size_t)w * (size_t)h && (tall ? bh > factor * bw : bw > factor * bh),
           "%.200s: %zu lit pixels of %dx%d in a box %gx%g (wide x tall); want it %s by more than %g", what, b.lit, w, h,
           bw, bh, tall ? "taller than wide" : "wider than tall", factor);
}

/* Factors with room: from 30 degrees up a box of side s and height z is
   drawn s sqrt 2 wide and z cos 30 + s sqrt 2 sin 30 tall, so the tower is
   several times taller than wide and the slab well over 1.4 times wider than
   tall; tipped over onto the view, either is drawn about as wide as tall. */
#define TOWER_FACTOR 2.0
#define SLAB_FACTOR 1.4

/* The model file of a box x by y by z mm standing on the plate. */
static const char *box_model(const char *name, double x, double y, double z)
{
    const char *path = cli_path(name);
    adaslice_mesh m = gen_box(0, 0, 0, x, y, z);
    cli_write_obj(path, &m);
    gen_free(&m);
    return path;
}

/* A small display and thick layers: the previews, not the masks, are tested. */
static int slice_to(const char *model, const char *format, const char *job)
{
    cli_result r = cli_run("slice", model, "--format", format, "-o", job, "--pixels", "200x200", "--pitch", "0.5",
                           "--uniform", "1", NULL);
    int ok = r.status == 0;
    CHECKF(ok, "slice %.100s --format %s: exit %d: %.200s", model, format, r.status, r.err);
    cli_free(&r);
    return ok;
}


/* Both previews of a CTB or GOO job of the model, checked by check_shape. */
static void check_file_previews(const char *model, const char *format, int tall, double factor)
{
    char job[600], what[700];
    jr_job r;
    size_t size;
    unsigned char *data;
    int k, read;
    snprintf(job, sizeof job, "%s.%s", model, format);
    if (!slice_to(model, format, job)) return;
    data = read_whole_file(job, &size);
    read = data && (!strcmp(format, "ctb") ? jr_read_ctb_ex(data, size, &r, JR_SKIP_IMAGES)
                                           : jr_read_goo_ex(data, size, &r, JR_SKIP_IMAGES)) == 0;
    CHECKF(read, "%.200s: %.200s", job, data ? r.error : "cannot read it");
    for (k = 0; read && k < 2; k++) {
        snprintf(what, sizeof what, "%s, %s preview %dx%d", job, k ? "large" : "small", r.preview_w[k], r.preview_h[k]);
        CHECKF(r.preview_rgb[k] != NULL, "%.300s: not decoded", what);
        if (r.preview_rgb[k]) check_shape(what, r.preview_rgb[k], r.preview_w[k], r.preview_h[k], tall, factor);
    }
    if (read) jr_free(&r);
    free(data);
}

static void a_tower_stands_and_a_slab_lies_in_ctb_and_goo_previews(void)
{
    const char *tower, *slab;
    if (!cli_begin("adaslice-previews")) { CHECK(0); return; }
    tower = box_model("tower.obj", 10, 10, 80);
    slab = box_model("slab.obj", 80, 80, 5);
    check_file_previews(tower, "ctb", 1, TOWER_FACTOR);
    check_file_previews(tower, "goo", 1, TOWER_FACTOR);
    check_file_previews(slab, "ctb", 0, SLAB_FACTOR);
    check_file_previews(slab, "goo", 0, SLAB_FACTOR);
    cli_end();
}

/* A PNG of the part, decoded by oiiotool to a PPM, checked by check_shape. */
static void check_png(const char *png, int tall, double factor)
{
    char ppm[700], log[700];
    char *argv[] = {(char *)"oiiotool", (char *)png, (char *)"-d", (char *)"uint8", (char *)"-o", ppm, NULL};
    unsigned char *text;
    size_t size;
    int w = 0, h = 0, maxval = 0, used = 0, picture;
    snprintf(ppm, sizeof ppm, "%s.ppm", png);
    snprintf(log, sizeof log, "%s.log", png);
    if (tool_run("openimageio-tools", argv, log, log) != 0) { CHECKF(0, "oiiotool cannot read %.300s", png); return; }
    text = read_whole_file(ppm, &size);
    picture = text && sscanf((char *)text, "P6 %d %d %d%n", &w, &h, &maxval, &used) == 3 && maxval == 255 && w > 0 &&
              h > 0 && size - (size_t)used - 1 == (size_t)w * (size_t)h * 3;
    CHECKF(picture, "%.300s: not an 8-bit RGB picture", ppm);
    if (picture) check_shape(png, text + used + 1, w, h, tall, factor);
    free(text);
}

/* A job directory's preview.png, and saliency --png's picture (the same
   renderer, on a white ground) of the model as it loads. */
static void check_pngs(const char *model, int tall, double factor)
{
    char job[600], png[700];
    cli_result r;
    snprintf(job, sizeof job, "%s.job", model);
    snprintf(png, sizeof png, "%s/preview.png", job);
    if (slice_to(model, "dir", job)) check_png(png, tall, factor);
    snprintf(png, sizeof png, "%s.saliency.png", model);
    r = cli_run("saliency", model, "--png", png, NULL);
    CHECKF(r.status == 0, "saliency %.200s --png: exit %d: %.200s", model, r.status, r.err);
    if (r.status == 0) check_png(png, tall, factor);
    cli_free(&r);
}

static void a_tower_stands_and_a_slab_lies_in_png_previews(void)
{
    if (!cli_begin("adaslice-previews")) { CHECK(0); return; }
    check_pngs(box_model("tower.obj", 10, 10, 80), 1, TOWER_FACTOR);
    check_pngs(box_model("slab.obj", 80, 80, 5), 0, SLAB_FACTOR);
    cli_end();
}

/* ---- the demo hand, on its wrist */

enum { HAND_W = 400, HAND_H = 300, HAND_DRAWN = 77 };

typedef struct hand_rows { double wrist, fingers; size_t wrist_pixels, finger_pixels; } hand_rows;

/* plan_job's `loaded`: the part as the job turned it, drawn with the faces of
   its lowest tenth of z in red, of its highest tenth in green, the rest
   grey; the mean picture row of each. Stops the job there. */
static int draw_hand(void *ctx, const adaslice_mesh *m, const double box_lo[3], const double box_hi[3])
{
    hand_rows *rows = (hand_rows *)ctx;
    unsigned char *colours = (unsigned char *)malloc(3 * m->triangle_count);
    unsigned char *rgb = (unsigned char *)malloc((size_t)HAND_W * HAND_H * 3);
    adaslice_preview_options o;
    double lo[3], hi[3], wrist_sum = 0, finger_sum = 0;
    size_t t, p;
    if (!colours || !rgb) { free(colours); free(rgb); CHECK(0); return HAND_DRAWN; }
    adaslice_mesh_bounds(m, lo, hi);
    /* the box the hook is given is the turned mesh's */
    CHECK(!memcmp(lo, box_lo, sizeof lo) && !memcmp(hi, box_hi, sizeof hi));
    for (t = 0; t < m->triangle_count; t++) {
        double z = 0;
        int c;
        for (c = 0; c < 3; c++) z += m->vertices[3 * (size_t)m->triangles[3 * t + (size_t)c] + 2] / 3.0;
        colours[3 * t] = colours[3 * t + 1] = colours[3 * t + 2] = 128;
        if (z < lo[2] + 0.1 * (hi[2] - lo[2])) colours[3 * t + 1] = colours[3 * t + 2] = 0;
        else if (z > hi[2] - 0.1 * (hi[2] - lo[2])) colours[3 * t] = colours[3 * t + 2] = 0;
    }
    memset(&o, 0, sizeof o);
    o.face_colours = colours;
    CHECK(adaslice_preview(m, HAND_W, HAND_H, &o, rgb, NULL) == ADASLICE_OK);
    for (p = 0; p < (size_t)HAND_W * HAND_H; p++) {
        const unsigned char *c = rgb + 3 * p;
        double row = (double)(p / HAND_W);
        if (c[0] && !c[1] && !c[2]) { wrist_sum += row; rows->wrist_pixels++; }
        if (!c[0] && c[1] && !c[2]) { finger_sum += row; rows->finger_pixels++; }
    }
    rows->wrist = rows->wrist_pixels ? wrist_sum / (double)rows->wrist_pixels : 0;
    rows->fingers = rows->finger_pixels ? finger_sum / (double)rows->finger_pixels : 0;
    free(colours);
    free(rgb);
    return HAND_DRAWN;
}

/* The settings of `make demo` (the hand stood on its wrist); the wrist is
   drawn well below the fingers, by more than a third of the picture. */
static void the_demo_hand_stands_on_its_wrist(void)
{
    char *argv[] = {(char *)"plan", (char *)"examples/models/hand_closed.obj", (char *)"--scale", (char *)"88.7",
                    (char *)"--orient", (char *)"0,1,0", NULL};
    plan_args a;
    plan_job j;
    hand_rows rows = {0, 0, 0, 0};
    memset(&a, 0, sizeof a);
    memset(&j, 0, sizeof j);
    CHECK(parse_plan(6, argv, &a) == RC_OK);
    j.args = &a;
    j.loaded = draw_hand;
    j.loaded_ctx = &rows;
    CHECK(run_plan(&a, &j) == HAND_DRAWN);
    job_free(&j);
    CHECKF(rows.wrist_pixels > 100 && rows.finger_pixels > 100 && rows.wrist > rows.fingers + HAND_H / 3.0,
           "wrist: %zu pixels, mean row %.1f; fingers: %zu pixels, mean row %.1f (rows top first, %d of them)",
           rows.wrist_pixels, rows.wrist, rows.finger_pixels, rows.fingers, HAND_H);
}

/* A part near the largest float turned to inf in the camera's frame and was
   reported as a triangle far off the grid (exit 2); it is refused as too
   large, and one of 1e14 mm is still drawn. */
static void a_part_too_large_to_turn_is_refused(void)
{
    static const uint32_t tris[] = {0, 1, 2, 0, 2, 3};
    float v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, -1};
    adaslice_mesh m;
    adaslice_error e;
    unsigned char *rgb = (unsigned char *)malloc(64 * 48 * 3);
    static const float scales[] = {1e14f, 3e38f};
    int k, i;
    memset(&m, 0, sizeof m);
    m.vertex_count = 4;
    m.vertices = v;
    m.triangle_count = 2;
    m.triangles = (uint32_t *)tris;
    for (k = 0; rgb && k < 2; k++) {
        adaslice_result r;
        for (i = 0; i < 12; i++) v[i] = v[i] ? (v[i] > 0 ? scales[k] : -scales[k]) : 0;
        r = adaslice_preview(&m, 64, 48, NULL, rgb, &e);
        if (k == 0) CHECKF(r == ADASLICE_OK, "1e14 mm: %s", e.message);
        else CHECKF(r == ADASLICE_ERR_OVERFLOW && strstr(e.message, "mm across"), "3e38 mm: %d %s", (int)r, e.message);
        for (i = 0; i < 12; i++) v[i] = v[i] ? (v[i] > 0 ? 1.0f : -1.0f) : 0;
    }
    CHECK(rgb != NULL);
    free(rgb);
}

void test_previews(void)
{
    RUN(a_part_too_large_to_turn_is_refused);
    RUN(a_tower_stands_and_a_slab_lies_in_ctb_and_goo_previews);
    RUN_NEEDING("oiiotool", a_tower_stands_and_a_slab_lies_in_png_previews);
    RUN(the_demo_hand_stands_on_its_wrist);
}
