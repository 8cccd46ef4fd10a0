/* adaslice slice: plan a model, then write its layers as the job a printer
   reads: a ChiTuBox .ctb, an Elegoo .goo, a ChiTu G-code .zip, a Prusa .sl1
   or a job directory (jobfile.h). One loop renders every layer once,
   bottom-up, and hands it to the format. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "commands.h"
#include "contour_svg.h"
#include "cure.h"
#include "formats/jobdir.h"
#include "formats/jobfile.h"
#include "formats/layer_z.h"
#include "layers.h"
#include "output.h"
#include "formats/pipeline.h"
#include "plan_job.h"
#include "report.h"

#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void slice_usage(FILE *f)
{
    int i;
    fputs("usage: adaslice slice MODEL -o JOB [printer] [masks] [exposure] [motion] [plan options]\n"
          "\n"
          "Plans MODEL (as adaslice plan does) and writes the job the printer reads, by the\n"
          "extension of -o or --format NAME:\n", f);
    for (i = 0; JOB_FORMATS[i]; i++)
        fprintf(f, "  %-6s %-13s %s\n", JOB_FORMATS[i]->extension ? JOB_FORMATS[i]->extension : "(none)",
                JOB_FORMATS[i]->name, JOB_FORMATS[i]->what);
    fputs("Without an extension a preset's printer gets its own format (-o job writes job.ctb\n"
          "for a printer that reads .ctb); --format dir keeps a directory. A directory job\n"
          "holds plan.csv, plot.svg, one PNG mask per layer (layer_00001.png, ...), preview.png,\n"
          "masks.rle (for adaslice print) and, last, manifest.json. A pixel is lit when the\n"
          "winding number of its vertical ray below the slicing height is positive.\n"
          "\n"
          "  -o, --output JOB    the job file or directory (required)\n"
          "  --format NAME       the format, whatever the extension\n", f);
    slice_options_usage(f);
    layer_z_table(f);
    cure_usage(f);
    fputc('\n', f);
    plan_options_usage(f, FOR_SLICE);
}


typedef struct contour_file { const adaslice_contours *c; size_t k; contour_layer layer; } contour_file;

static void write_contour_svg(FILE *f, const void *ctx)
{
    const contour_file *cf = (const contour_file *)ctx;
    svg_write_contours(f, cf->c, cf->k, &cf->layer);
}

/* The slice polygons at the masks' heights, one SVG per layer, from the
   welded mesh (see cmd_slice). */
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
    for (k = 0; k < p->layer_count; k++) heights[k] = j->profile.z0 + layer_slice_height(s, j, k);
    if (adaslice_contours_slice(&j->mesh, heights, p->layer_count, NULL, &c, &err) != ADASLICE_OK) {
        free(heights);
        free(path);
        return library_error(&err);
    }
    cf.c = &c;
    cf.layer.model = base_name(a->model);
    cf.layer.count = p->layer_count;
    for (k = 0; k < p->layer_count && !rc; k++) {
        const adaslice_layer *l = &p->layers[k];
        layer_path(path, n, s->dir, k, digits, "svg");
        cf.k = k;
        cf.layer.number = k + 1;
        cf.layer.z_bottom = l->z_bottom; /* the plan's, as the manifest takes them (cure_layers) */
        cf.layer.z_top = l->z_top;
        cf.layer.thickness = l->thickness;
        cf.layer.cut = layer_slice_height(s, j, k);
        rc = write_atomic(path, write_contour_svg, &cf);
    }
    adaslice_contours_free(&c);
    free(heights);
    free(path);
    return rc;
}


/* ------------------------------------------------------------ the format */

/* The formats' names, or their extensions, ", " between them. */
static void list_formats(char *out, size_t size, int extensions)
{
    int i;
    *out = 0;
    for (i = 0; JOB_FORMATS[i]; i++) {
        const char *what = extensions ? JOB_FORMATS[i]->extension : JOB_FORMATS[i]->name;
        size_t n = strlen(out), k = strlen(what ? what : "");
        int listed = 0;
        const char *p;
        for (p = out; what && (p = strstr(p, what)) != NULL; p += k) listed |= (p[k] == ',' || !p[k]); /* .ctb is two formats */
        if (what && !listed) snprintf(out + n, size - n, "%s%s", n ? ", " : "", what);
    }
}

/* By --format, else by the extension of -o; a path without one gets the
   preset's format (and its extension). *path is s->dir or, extended, malloc'd. */
static int choose_format(const slice_args *s, const job_format **fmt, char **path)
{
    const printer *preset = s->geometry_given ? s->preset : NULL; /* given, not the default */
    char list[160];
    *path = NULL;
    if (s->format && !(*fmt = job_format_named(s->format))) {
        list_formats(list, sizeof list, 0);
        return complain(RC_USAGE, "--format %s: unknown (%s)", s->format, list);
    }
    {
        /* ".ctb" alone would be a hidden directory, or get its extension twice */
        const char *base = base_name(s->dir);
        const job_format *named;
        char named_x[32];
        snprintf(named_x, sizeof named_x, "x%.30s", base);
        if (base[0] == '.' && (named = job_format_for_path(named_x)) != NULL && named != &JOB_FORMAT_DIR)
            return complain(RC_USAGE, "-o %s: only an extension; give the job a name (job%s)", s->dir, base);
    }
    if (!s->format && !(*fmt = job_format_for_path(s->dir))) {
        list_formats(list, sizeof list, 1);
        return complain(RC_USAGE, "-o %s: %s is no job format's extension (%s, or none for a directory); give "
                                  "--format NAME to keep the name", s->dir, strrchr(s->dir, '.'), list);
    }
    if (!s->format && *fmt == &JOB_FORMAT_DIR && preset && !(*fmt = job_format_named(preset->format)))
        return complain(RC_FAIL, "--printer %s: its format %s is not built in", preset->name, preset->format);
    if (!s->format && preset && (*fmt)->extension) {
        /* .ctb is two formats: the printer's is the one it reads */
        const job_format *own = job_format_named(preset->format);
        if (own && own->extension && !strcmp(own->extension, (*fmt)->extension)) *fmt = own;
    }
    if (*fmt != &JOB_FORMAT_DIR && !s->geometry_given)
        return complain(RC_USAGE, "-o %s: which printer? give --printer NAME (adaslice printers lists them) or "
                                  "--pixels WxH with --pitch MM", s->dir);
    /* a directory and a .uvj (for UVtools to convert) are any printer's */
    if (preset && *fmt != &JOB_FORMAT_DIR && *fmt != &JOB_FORMAT_UVJ && strcmp(preset->format, (*fmt)->name))
        return complain(RC_USAGE, "-o %s: the %s reads %s jobs, not %s (leave the extension out for its own)", s->dir,
                        preset->name, preset->format, (*fmt)->name);
    /* an extension is added to a new name (or a directory's), never to a file,
       a device or a FIFO that exists: -o /dev/null writes /dev/null */
    if ((*fmt)->extension && job_format_for_path(s->dir) == &JOB_FORMAT_DIR &&
        (output_kind(s->dir) == OUT_NEW || output_kind(s->dir) == OUT_DIRECTORY)) {
        size_t n = strlen(s->dir) + strlen((*fmt)->extension) + 1;
        const char *base = base_name(s->dir);
        /* e3/ with a preset wrote the hidden file e3/.ctb */
        if (!*base || !strcmp(base, ".") || !strcmp(base, ".."))
            return complain(RC_USAGE, "-o %s: a directory, and a %s job is one file: give it a name (%s%sjob%s), or "
                                      "--format dir for a job directory", s->dir, (*fmt)->name, s->dir,
                            *base ? "/" : "", (*fmt)->extension);
        if (!(*path = (char *)malloc(n))) return complain(RC_FAIL, "out of memory");
        snprintf(*path, n, "%s%s", s->dir, (*fmt)->extension);
    }
    return RC_OK;
}

/* --out, --profile-out and --plot into the job directory under one of its
   own names: --out jj/masks.rle replaced the masks with the plan, exit 0,
   and --plot jj/layer_00001.png was replaced by the layer. Its own plan.csv
   and plot.svg are what --out and --plot write there anyway. */
static int outputs_clear_of_the_job(const plan_args *a, const char *dir)
{
    const char *const options[] = {"--out", "--profile-out", "--plot"};
    const char *const paths[] = {a->out, a->profile_out, a->plot};
    const char *const same[] = {"plan.csv", NULL, "plot.svg"};
    int k, rc = RC_OK;
    for (k = 0; k < 3 && !rc; k++) {
        const char *base = paths[k] ? base_name(paths[k]) : NULL;
        size_t n;
        char *own;
        if (!base || !jobdir_file_name(base) || (same[k] && !strcmp(base, same[k]))) continue;
        n = strlen(dir) + strlen(base) + 2;
        if (!(own = (char *)malloc(n))) return complain(RC_FAIL, "out of memory");
        snprintf(own, n, "%s/%s", dir, base);
        if (output_same(paths[k], own))
            rc = complain(RC_USAGE, "%s %s: the job directory %s writes %s itself; give it another name or put it "
                                    "beside the job", options[k], paths[k], dir, base);
        free(own);
    }
    return rc;
}

/* -o's path takes the job: before the model is loaded. */
static int output_check_dir_or_file(const job_format *f, const char *path, int force)
{
    int rc = f == &JOB_FORMAT_DIR ? output_check_dir("-o", path) : output_check("-o", path);
    return !rc && f == &JOB_FORMAT_DIR ? jobdir_check(path, force) : rc;
}

/* The layers below the top one differ in thickness (the top one is what is
   left of the part, thinner in a uniform plan too). */
static int plan_is_adaptive(const adaslice_plan *p)
{
    size_t k;
    for (k = 1; k + 1 < p->layer_count; k++)
        if (fabs(p->layers[k].thickness - p->layers[0].thickness) > 1e-9) return 1;
    return 0;
}

/* What the format cannot hold, said before a byte is written. */
static int check_plan(const job_format *f, const char *path, const adaslice_plan *p, const slice_args *s)
{
    size_t k, n = p->layer_count;
    double lo = HUGE_VAL, hi = 0;
    for (k = 0; k < n; k++) {
        const adaslice_layer *l = &p->layers[k];
        if (l->thickness < f->min_layer_mm * (1 - 1e-9))
            return complain(RC_USAGE, "%s: layer %zu (z %g to %g mm) is %g mm thick; %s stores layers of %g mm or more",
                            path, k + 1, l->z_bottom, l->z_top, l->thickness, f->what, f->min_layer_mm);
        if (l->thickness < lo) lo = l->thickness;
        if (l->thickness > hi) hi = l->thickness;
    }
    if (!f->adaptive && n > 1) {
        double t = p->layers[0].thickness;
        if (plan_is_adaptive(p))
            return complain(RC_USAGE, "%s: %s holds one layer height, and this plan's layers are %g to %g mm: plan "
                                      "uniform layers with --method finest or --method coarsest, or --uniform T",
                            path, f->what, lo, hi);
        if (fabs(p->layers[n - 1].thickness - t) > 1e-9)
            warn("%s: the last layer is %g mm; %s holds one height, so it prints %g mm "
                 "(the top %g mm higher)",
                 path, p->layers[n - 1].thickness, f->what, t, t - p->layers[n - 1].thickness);
    }
    if (f == &JOB_FORMAT_SL1 && s->cure.bottom_layers > 1)
        warn("%s: the SL1 fades its exposure from the bottom exposure to the normal one over "
             "the %zu bottom layers, so only the first gets the full %g s",
             path, s->cure.bottom_layers, s->cure.bottom_exposure_s);
    if (f->max_layers && n > f->max_layers)
        return complain(RC_USAGE, "%s: %zu layer%s; %s holds %zu at most", path, n, plural(n), f->what, f->max_layers);
    return RC_OK;
}

/* The plate's fit, checked before the part is profiled and planned. */
static int fits_the_plate(void *ctx, const adaslice_mesh *mesh, const double lo[3], const double hi[3])
{
    (void)mesh;
    return layer_masks_fit((const slice_args *)ctx, lo, hi);
}

static int draw_picture(const plan_job *j, int w, int h, unsigned char *rgb)
{
    adaslice_error err;
    return adaslice_preview(&j->mesh, w, h, NULL, rgb, &err) == ADASLICE_OK ? 0 : -1;
}

/* The format's previews, drawn ahead on a thread of their own (with
   --threads 2 or more) from when the masker is set up beside the profile
   and the plan, where a core is idle (started with the layers they took a
   core from them), on into the first layers if they take longer: on the
   calling thread they held up the job before or after its layers, alone on
   one core (the directory's took a fortieth of the job). */
typedef struct previews {
    const plan_job *j;
    const job_format *f;
    unsigned char *rgb[2];       /* f->previews[i], or NULL */
    int rc[2];
    pthread_t thread;
    int drawing;                 /* the thread is started and not yet joined */
    int started;                 /* previews_start was called */
} previews;

static void *draw_previews(void *arg)
{
    previews *p = (previews *)arg;
    int i;
    for (i = 0; i < 2; i++) {
        int w = p->f->previews[i][0], h = p->f->previews[i][1];
        if (w <= 0 || h <= 0 || !(p->rgb[i] = (unsigned char *)malloc((size_t)w * (size_t)h * 3))) continue;
        p->rc[i] = draw_picture(p->j, w, h, p->rgb[i]);
    }
    return NULL;
}

static void previews_start(previews *p, const plan_job *j, const job_format *f, int threads)
{
    memset(p, 0, sizeof *p);
    p->j = j;
    p->f = f;
    p->started = 1;
    p->drawing = threads > 1 && f->previews[0][0] > 0 && output_thread_start(&p->thread, draw_previews, p) == 0;
}

static void previews_join(previews *p)
{
    if (p->drawing) pthread_join(p->thread, NULL);
    p->drawing = 0;
}

static void previews_free(previews *p)
{
    previews_join(p);
    free(p->rgb[0]);
    free(p->rgb[1]);
}

/* d->preview: one drawn ahead if it is of this size, else drawn now. */
static int draw_preview(void *ctx, int w, int h, unsigned char *rgb)
{
    previews *p = (previews *)ctx;
    int i;
    previews_join(p);
    for (i = 0; i < 2; i++)
        if (p->rgb[i] && p->f->previews[i][0] == w && p->f->previews[i][1] == h && !p->rc[i]) {
            memcpy(rgb, p->rgb[i], (size_t)w * (size_t)h * 3);
            return 0;
        }
    return draw_picture(p->j, w, h, rgb);
}


/* ------------------------------------------------------------- the layers */

typedef struct job_summary { double lo, hi, e_lo, e_hi; } job_summary;

/* What the pipeline's calls need (pipeline.h). */
typedef struct slice_run {
    layer_masks *masks;
    job_desc *d;
    job_layer *layers;
    long long *rays;             /* lit rays of layer k's band b at [k * bands + b] */
    const char *path;
    progress *bar;
} slice_run;

/* A band's next layer (or its rows read), and its lit rays. */
static int render_band(void *ctx, int b, size_t k, unsigned char *image, mask_band *rows)
{
    slice_run *r = (slice_run *)ctx;
    layer_masks *m = r->masks;
    int rc;
    if (output_interrupted()) return RC_FAIL; /* said once, by outputs_finish */
    if ((rc = rows ? layer_masks_scan_band(m, b, k, rows) : layer_masks_render_band(m, b, k, image))) return rc;
    r->rays[k * (size_t)m->bands + (size_t)b] = layer_masks_rays(m, b);
    return RC_OK;
}

/* Layer k's lit area from its bands' (whole numbers of rays, so the sum is
   one masker's), and its resin, added in layer order as one thread did. */
static void layer_ready(void *ctx, size_t k)
{
    slice_run *r = (slice_run *)ctx;
    const layer_masks *m = r->masks;
    long long rays = 0;
    int b;
    for (b = 0; b < m->bands; b++) rays += r->rays[k * (size_t)m->bands + (size_t)b];
    r->layers[k].lit_mm2 = (double)rays / ((double)m->s->supersample * m->s->supersample) * m->grid.pitch[0] * m->grid.pitch[1];
    r->d->volume_mm3 += r->layers[k].lit_mm2 * r->layers[k].thickness;
}

static void layer_done(void *ctx, size_t k)
{
    slice_run *r = (slice_run *)ctx;
    progress_show(r->bar, k + 1, r->d->layer_count, "layers", NULL);
}

/* The masker, set up beside the profile and the plan (plan_job's beside)
   on two threads or more: it needs only the mesh, and its set-up (the
   facets sorted by height and split into bands: 33 ms on the turbine
   blade) held up the first layer while the other core idled. */
typedef struct masks_setup {
    const slice_args *s;
    const plan_job *j;
    const job_format *f;
    layer_masks m;
    int open;
    previews pv;                 /* the format's, drawn meanwhile */
} masks_setup;

static int open_masks(void *ctx)
{
    masks_setup *ms = (masks_setup *)ctx;
    int rc = layer_masks_open(&ms->m, ms->s, ms->j, pipeline_bands(ms->s->threads));
    ms->open = rc == RC_OK;
    return rc;
}

/* plan_job's beside. The previews' thread goes on while the first layers
   are made: waiting for it held up the layers' start by 5 ms on the turbine
   blade, a core idle. It reads j->mesh, which a failing plan leaves to
   job_free, after previews_free has joined it. */
static int open_masks_and_previews(void *ctx)
{
    masks_setup *ms = (masks_setup *)ctx;
    previews_start(&ms->pv, ms->j, ms->f, ms->s->threads);
    return open_masks(ctx);
}

/* The job's description; every layer rendered once, in order, into the format. */
static int write_job(const slice_args *s, const plan_args *a, plan_job *j, const job_format *f, const char *path,
                     unsigned extras, layer_masks *m, previews *pv, job_desc *d, job_summary *sum, double stage_ms[3])
{
    const adaslice_plan *p = &j->plan[a->method];
    size_t k, count = p->layer_count;
    job_layer *layers;
    long long *rays;
    job_writer out;
    progress bar;
    slice_run run;
    pipeline_job pipe;
    int rc, odd = s->rotate & 1;

    memset(&bar, 0, sizeof bar);
    memset(&out, 0, sizeof out);
    if (!pv->started) previews_start(pv, j, f, s->threads);
    layers = (job_layer *)calloc(count ? count : 1, sizeof *layers);
    rays = (long long *)calloc((count ? count : 1) * (size_t)m->bands, sizeof *rays);
    if (!layers || !rays) {
        free(layers);
        free(rays);
        return complain(RC_FAIL, "out of memory for %zu layer%s", count, plural(count));
    }
    cure_layers(&s->cure, p, layers);
    memset(d, 0, sizeof *d);
    d->preset = s->preset;
    d->model = a->model;
    d->width = m->width;
    d->height = m->height;
    d->pitch[0] = m->grid.pitch[odd];
    d->pitch[1] = m->grid.pitch[!odd];
    d->display_mm[0] = d->width * d->pitch[0];
    d->display_mm[1] = d->height * d->pitch[1];
    d->z_max_mm = s->preset ? s->preset->z_max : 0;
    d->bits = m->bits;
    d->supersample = s->supersample;
    d->mirror_x = s->mirror_x;
    d->mirror_y = s->mirror_y;
    memcpy(d->lit_rows, m->lit_rows, sizeof d->lit_rows);
    d->layer_count = count;
    d->layers = layers;
    d->bottom_layers = (unsigned)(s->cure.bottom_layers < count ? s->cure.bottom_layers : count);
    if (s->cure.bottom_layers > count)
        warn("--bottom-layers %zu: the job has %zu layer%s, all of them bottom layers of "
             "%g s", s->cure.bottom_layers, count, plural(count), s->cure.bottom_exposure_s);
    d->bottom_exposure_s = s->cure.bottom_exposure_s;
    d->exposure_s = s->cure.cure.seconds;
    d->layer_height_mm = HUGE_VAL;
    sum->lo = sum->e_lo = HUGE_VAL;
    sum->hi = sum->e_hi = 0;
    for (k = 0; k < count; k++) {
        double t = layers[k].thickness, e = layers[k].exposure_s;
        if (t < sum->lo) sum->lo = t;
        if (t > sum->hi) sum->hi = t;
        if (k < d->bottom_layers) continue;
        /* the headers' one height and exposure: the thinnest layer's, but not
           the top one, which is what is left of the part (a uniform plan's is
           thinner than the rest) */
        if (t < d->layer_height_mm && (k + 1 < count || k == d->bottom_layers)) { d->layer_height_mm = t; d->exposure_s = e; }
        if (e < sum->e_lo) sum->e_lo = e;
        if (e > sum->e_hi) sum->e_hi = e;
    }
    if (d->layer_height_mm == HUGE_VAL) d->layer_height_mm = count ? sum->lo : a->tmin;
    d->motion = s->cure.motion;
    d->print_time_s = cure_print_time(&d->motion, layers, count);
    d->preview = draw_preview;
    d->preview_ctx = pv;
    d->metric = METRIC_NAMES[a->metric];
    d->method = METHOD_NAMES[a->method];
    d->slice_at = SLICE_AT[s->slice_at];
    d->eps = p->eps;
    d->bin_mm = j->profile.bin;
    d->cure[0] = s->cure.cure.seconds;
    d->cure[1] = s->cure.cure.thickness;
    d->cure[2] = s->cure.cure.penetration;
    memcpy(d->part_mm, m->part, sizeof d->part_mm);
    memcpy(d->place_mm, s->place, sizeof d->place_mm);
    d->rotate = s->rotate;
    d->dir_extras = extras;
    d->dir_force = s->force;

    outputs_hold_signals(); /* from here a signal stops the layers and the job is removed */
    if ((rc = job_open(&out, f, path, d))) goto done;
    if (f == &JOB_FORMAT_DIR) {
        if ((rc = write_outputs(a, j))) goto done;
        if (s->svg && (rc = write_contours(s, a, j))) goto done;
    }
    memset(&run, 0, sizeof run);
    run.masks = m;
    run.d = d;
    run.layers = layers;
    run.rays = rays;
    run.path = path;
    run.bar = &bar;
    memset(&pipe, 0, sizeof pipe);
    pipe.out = &out;
    pipe.layers = count;
    pipe.image_bytes = m->stride * (size_t)m->height;
    pipe.stride = m->stride;
    pipe.threads = s->threads;
    pipe.bands = m->bands;
    pipe.render = render_band;
    pipe.by_bands = f->encode_bands && layer_masks_band_is_rows(m);
    pipe.ready = layer_ready;
    pipe.done = layer_done;
    pipe.ctx = &run;
    pipe.stage_ms = stage_ms;
    rc = pipeline_run(&pipe);
    /* a job that lights nothing prints nothing, silently: said, and removed */
    if (!rc && !(d->volume_mm3 > 0))
        rc = complain(RC_FAIL, "%s: no pixel is lit in its %zu layer%s: the part (%g x %g mm) is smaller "
                                       "than a pixel (%g x %g mm), misses the pixels' centres or encloses no volume; "
                                       "nothing written", path, count, plural(count), d->part_mm[0], d->part_mm[1],
                              m->grid.pitch[0], m->grid.pitch[1]);
done:
    if (out.state) {
        int closed = job_close(&out, rc == RC_OK);
        if (!rc) rc = closed;
    }
    free(layers);
    free(rays);
    d->layers = NULL;
    return rc;
}

int cmd_slice(int argc, char **argv)
{
    slice_args s;
    plan_args a;
    plan_job j;
    masks_setup ms;
    job_desc d;
    job_summary sum;
    const job_format *f = NULL;
    char **rest = (char **)malloc(((size_t)argc + 4) * sizeof *rest), *path = NULL, *extended = NULL, *csv = NULL,
         *svg = NULL, when[32];
    int rest_argc = 0, rc, i;
    double stage_ms[3] = {0, 0, 0}, t0 = now_ms();

    memset(&j, 0, sizeof j);
    memset(&ms, 0, sizeof ms);
    memset(&sum, 0, sizeof sum);
    memset(&d, 0, sizeof d);
    if (!rest) return complain(RC_FAIL, "out of memory");
    for (i = 1; i + 1 < argc; i++)
        if (!strcmp(argv[i], "--printer") && !strcmp(argv[i + 1], "list")) {
            printers_list(stdout);
            free(rest);
            return RC_OK;
        }
    rc = parse_slice(argc, argv, &s, &rest_argc, rest, 1);
    if (rc < 0) { slice_usage(stdout); free(rest); return RC_OK; }
    if (!rc) rc = parse_plan(rest_argc, rest, &a);
    a.memory_mb = s.memory_mb; /* slice's --memory bounds the profile too */
    if (!rc && a.help) { slice_usage(stdout); free(rest); return RC_OK; }
    if (!rc && (a.json || a.compare))
        rc = complain(RC_USAGE, "slice writes a job, not a summary: --json and --compare belong to adaslice plan");
    free(rest);
    if (!rc && s.dir && !*s.dir) rc = complain(RC_USAGE, "-o \"\": an empty name (a job file or directory)");
    if (!rc) rc = choose_format(&s, &f, &extended);
    if (!rc && s.svg && f != &JOB_FORMAT_DIR) rc = complain(RC_USAGE, "--svg writes into a job directory, not a %s file", f->name);
    if (!rc) rc = output_check_dir_or_file(f, extended ? extended : s.dir, s.force);
    if (!rc) rc = check_plan_outputs(&a, "-o", extended ? extended : s.dir);
    if (!rc && f == &JOB_FORMAT_DIR) rc = outputs_clear_of_the_job(&a, s.dir);
    if (!rc) rc = cure_finish(&s.cure, a.tmin, a.tmax);
    if (!rc) rc = layer_masks_check(&s, pipeline_images(s.threads));
    if (rc) { free(extended); return rc; }
    path = extended ? extended : (char *)s.dir;
    if (f == &JOB_FORMAT_DIR) {
        size_t n = strlen(path) + 32;
        csv = (char *)malloc(n);
        svg = (char *)malloc(n);
        if (!csv || !svg) { rc = complain(RC_FAIL, "out of memory"); goto done; }
        snprintf(csv, n, "%s/plan.csv", path);
        snprintf(svg, n, "%s/plot.svg", path);
        if (!a.out) a.out = csv;
        if (!a.plot) a.plot = svg;
    }
    j.args = &a;
    j.keep_mesh = 1;
    j.loaded = fits_the_plate;
    j.loaded_ctx = &s;
    ms.s = &s;
    ms.j = &j;
    ms.f = f;
    /* not with --svg, whose weld comes first; nor for envelope and core
       masks, whose complaint about an open mesh comes in its turn */
    if (s.threads > 1 && !s.svg && s.slice_at <= 2) {
        j.beside = open_masks_and_previews;
        j.beside_ctx = &ms;
    }
    rc = run_plan(&a, &j);
    if (!rc) rc = check_plan(f, path, &j.plan[a.method], &s);
    /* chaining contours needs shared vertices (STL has none); welded before
       the masker keeps a pointer to the mesh */
    if (!rc && s.svg) {
        adaslice_error err;
        if (adaslice_mesh_weld(&j.mesh, NULL, &err) != ADASLICE_OK) rc = library_error(&err);
    }
    if (!rc && f != &JOB_FORMAT_DIR) rc = write_outputs(&a, &j);
    if (!rc && !ms.open) rc = open_masks(&ms);
    if (!rc)
        rc = write_job(&s, &a, &j, f, path,
                       (a.out == csv ? DIR_PLAN_CSV : 0) | (a.plot == svg ? DIR_PLOT_SVG : 0) | (s.svg ? DIR_LAYER_SVGS : 0),
                       &ms.m, &ms.pv, &d, &sum, stage_ms);
    if (!rc) {
        format_duration(when, sizeof when, d.print_time_s);
        printf("%s: %zu layer%s of %g to %g mm for %s on %s, %d x %d px of %g x %g um (%s)\n", path, d.layer_count,
               plural(d.layer_count), sum.lo, sum.hi, base_name(a.model), s.preset ? s.preset->name : "the display",
               d.width, d.height, d.pitch[0] * 1000, d.pitch[1] * 1000, f->name);
        printf("masks %s: %s\n", d.slice_at, SLICE_AT_MEANING[s.slice_at]);
        if (j.plan[a.method].plane_changes) {
            char line[1024];
            plan_changes_line(&j.plan[a.method], j.profile.bin, line, sizeof line);
            printf("%s\n", line);
        }
        if (d.bottom_layers == d.layer_count)
            printf("exposure %g s per layer (%u bottom layer%s of %g s: every layer)", d.bottom_exposure_s,
                   d.bottom_layers, plural(d.bottom_layers), d.bottom_exposure_s);
        else
            printf("exposure %.3g to %.3g s per layer", sum.e_lo <= sum.e_hi ? sum.e_lo : d.exposure_s,
                   sum.e_lo <= sum.e_hi ? sum.e_hi : d.exposure_s);
        if (d.bottom_layers && d.bottom_layers < d.layer_count)
            printf(" (%u bottom layer%s of %g s)", d.bottom_layers, plural(d.bottom_layers), d.bottom_exposure_s);
        printf("; about %s to print, %.3g ml of resin\n", when, d.volume_mm3 / 1000);
        if (plan_is_adaptive(&j.plan[a.method])) {
            const layer_z *z = layer_z_of(f->name);
            printf("adaptive layers: per-layer Z on %s (%s): %s\n", s.preset ? s.preset->name : "the display", f->name,
                   layer_z_says(z->support));
            if (z->risk) printf("%s: %s\n", path, z->risk);
        }
        if (s.cure.typical)
            printf("exposure by the working curve of a typical resin (%g s at %g mm, Dp %g mm): calibrate yours with "
                   "--exposure S1@T1,S2@T2\n", d.cure[0], d.cure[1], d.cure[2]);
        /* the layers' stages overlap on the threads: each is its busy time, summed over them */
        printf("time load %.0f ms, repair %.0f ms, profile %.0f ms, plan %.0f ms, masks %.0f ms, coding %.0f ms, "
               "writing %.0f ms (the last three summed over %d thread%s); %.0f ms in all\n",
               j.ms_load, j.ms_repair, j.ms_profile, j.ms_plan, stage_ms[0], stage_ms[1], stage_ms[2], s.threads,
               plural((size_t)s.threads), now_ms() - t0);
        /* a job directory is no output main removes: it goes here */
        if ((rc = stdout_written(rc)) && f == &JOB_FORMAT_DIR) jobdir_remove(path);
    }
done:
    previews_free(&ms.pv);
    if (ms.open) layer_masks_close(&ms.m);
    job_free(&j);
    free(extended);
    free(csv);
    free(svg);
    return rc;
}
