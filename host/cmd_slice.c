/* adaslice slice: plan a model, then write its layer masks on a printer's
   pixel grid as a job directory (jobdir.h): plan.csv, plot.svg, one PNG per
   layer, masks.rle, and manifest.json, written last, so a job without one is
   not complete. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "commands.h"
#include "contour_svg.h"
#include "jobdir.h"
#include "layers.h"
#include "output.h"
#include "plan_job.h"
#include "png.h"
#include "report.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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


typedef struct png_file { const unsigned char *data; size_t size; } png_file;

static void write_png_bytes(FILE *f, const void *ctx)
{
    const png_file *p = (const png_file *)ctx;
    fwrite(p->data, 1, p->size, f);
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
    for (k = 0; k < p->layer_count; k++) heights[k] = j->profile.z0 + layer_slice_height(s, j, k);
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


/* Every layer's PNG, its code for masks.rle, then the manifest, last. */
static int write_masks(const slice_args *s, const plan_args *a, plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    layer_masks m;
    job_manifest man;
    job_masks codes;
    job_layer *layers = NULL;
    size_t k, path_size = strlen(s->dir) + 64, count = p->layer_count;
    char *path = NULL;
    progress bar;
    int rc;

    memset(&man, 0, sizeof man);
    memset(&codes, 0, sizeof codes);
    memset(&bar, 0, sizeof bar);
    if ((rc = layer_masks_open(&m, s, j))) return rc;
    memcpy(man.part, m.part, sizeof man.part);
    layers = (job_layer *)calloc(count ? count : 1, sizeof *layers);
    path = (char *)malloc(path_size);
    if (!layers || !path) { rc = complain(RC_FAIL, "out of memory for the masks"); goto done; }
    if ((rc = job_masks_alloc(&codes, (uint32_t)count))) goto done;
    codes.width = (uint32_t)m.width;
    codes.height = (uint32_t)m.height;
    codes.bits = (uint32_t)m.bits;
    man.digits = layer_digits(count);
    if (s->svg && (rc = write_contours(s, a, j))) goto done;
    for (k = 0; k < count; k++) {
        png_file png;
        unsigned char *data = NULL;
        size_t bound = adaslice_rle_bound(codes.width, codes.height, m.bits);
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
        if (!(codes.codes[k] = (unsigned char *)malloc(bound))) { rc = complain(RC_FAIL, "out of memory coding layer %zu", k + 1); goto done; }
        (void)adaslice_rle_encode(m.image, m.stride, codes.width, codes.height, m.bits, codes.codes[k], bound,
                                  &codes.sizes[k]);
        codes.crcs[k] = adaslice_crc32(0, m.image, m.stride * (size_t)m.height);
        codes.lengths[k] = p->planes[k + 1] - p->planes[k];
        layers[k].z_bottom = p->layers[k].z_bottom;
        layers[k].z_top = p->layers[k].z_top;
        layers[k].thickness = p->layers[k].thickness;
        layers[k].lit_mm2 = m.masker.lit * m.grid.pitch * m.grid.pitch;
        progress_show(&bar, k + 1, count, "layers", NULL);
    }
    if ((rc = jobdir_write_masks(s->dir, &codes, j->profile.bin))) goto done;
    man.s = s;
    man.a = a;
    man.j = j;
    man.layers = layers;
    man.count = count;
    rc = jobdir_write_manifest(s->dir, &man);
done:
    layer_masks_close(&m);
    job_masks_free(&codes);
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
    if (rc < 0) { slice_usage(stdout); free(rest); return RC_OK; }
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

