/* Per-face weights: saliency, a weight file and regions, multiplied face by
   face, or blended with the view importance. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "weights.h"
#include "options.h"
#include "output.h"
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Pixels the view importance may render: about a minute here (1.2e8 a
   second); 8192 views of 8192 x 8192 ran for over an hour, unsaid. */
#define VIEW_PIXELS_LIMIT 8e9

void weights_usage(FILE *f, int saliency_option)
{
    fputs("weights (paper section 4.2), multiplied face by face into the profile\n", f);
    if (saliency_option)
        fputs("  --saliency          weight faces by their mesh saliency (Lee et al. 2005);\n"
              "                      adaslice saliency shows it\n", f);
    fprintf(f, "  --weights FILE      one weight in [0,1] per line for each triangle, in the\n"
          "                      order the model loads (adaslice saliency -o writes one)\n"
          "  --weight REGION=W   weight W in [0,1] for the faces whose centroid lies in\n"
          "                      REGION: box:X0,Y0,Z0,X1,Y1,Z1 or sphere:X,Y,Z,R (mm, after\n"
          "                      --scale). Repeatable; where regions overlap the last one\n"
          "                      given wins; faces in none keep 1\n"
          "  --importance A,B,C  blend instead of multiplying, as saliency-preserving\n"
          "                      slicing does: A saliency + B view importance + C the\n"
          "                      weights above, each in [0,1]; the blend is divided by its\n"
          "                      largest value                         [0.5,0.3,0.2]\n"
          "  --view V            the views of the view importance (implies the blend):\n"
          "                      hemisphere (the upper one, looked at from above the\n"
          "                      plate), all, top, bottom, front (-y), back (+y), left\n"
          "                      (-x), right (+x): that half of the sphere; or\n"
          "                      X,Y,Z[,X,Y,Z...] towards the viewer    [hemisphere]\n"
          "  --view-count N      views in a named half of the sphere (all: twice as many)\n"
          "                                                             [%d]\n"
          "  --view-res PX       pixels across the part in each view        [%d]\n"
          "                      (views x PX x PX: at most %.0e, about a minute)\n",
          ADASLICE_DEFAULT_VIEWS, ADASLICE_DEFAULT_VIEW_RESOLUTION, VIEW_PIXELS_LIMIT);
}

static const struct { const char *name; double axis[3]; } VIEW_NAMES[] = {
    {"hemisphere", {0, 0, 1}}, {"top", {0, 0, 1}}, {"all", {0, 0, 0}}, {"bottom", {0, 0, -1}},
    {"front", {0, -1, 0}}, {"back", {0, 1, 0}}, {"left", {-1, 0, 0}}, {"right", {1, 0, 0}}};

/* --view: a name (the lattice's directions in that half of the sphere; the
   upper hemisphere is the library's default) or a list of directions */
static int parse_view(const char *v, weight_args *w)
{
    size_t i, n;
    const char *p = v;
    for (i = 0; i < sizeof VIEW_NAMES / sizeof *VIEW_NAMES; i++)
        if (!strcmp(v, VIEW_NAMES[i].name)) {
            w->view_half = (int)i;
            return RC_OK;
        }
    w->view_half = -1;
    for (n = 1; *p; p++) n += *p == ',';
    if (n % 3 == 0 && n <= 3 * WEIGHT_VIEWS_MAX && parse_numbers(v, ',', (int)n, w->views)) {
        for (i = 0; i < n / 3; i++)
            if (w->views[3 * i] == 0 && w->views[3 * i + 1] == 0 && w->views[3 * i + 2] == 0)
                return complain(RC_USAGE, "--view %s: direction %zu is 0,0,0", v, i + 1);
        w->view_count = n / 3;
        return RC_OK;
    }
    return complain(RC_USAGE, "--view %s: expected hemisphere, all, top, bottom, front, back, left, right or up to %d "
                              "directions X,Y,Z[,X,Y,Z...]", v, WEIGHT_VIEWS_MAX);
}

int weights_given(const weight_args *w)
{
    return w->saliency || w->file || w->region_count || w->blend;
}

static const struct { const char *name, *numbers; int count; } REGION_KINDS[] = { /* by WEIGHT_BOX, WEIGHT_SPHERE */
    {"box", "X0,Y0,Z0,X1,Y1,Z1", 6}, {"sphere", "X,Y,Z,R", 4}};

/* "box:x0,y0,z0,x1,y1,z1=W" or "sphere:x,y,z,r=W" */
static int parse_region(const char *spec, weight_region *r)
{
    const char *colon = strchr(spec, ':'), *equals = strrchr(spec, '='), *p, *end = NULL;
    double v[6], w = 0;
    int n, want;
    if (!colon || !equals || equals < colon)
        return complain(RC_USAGE, "--weight %s: expected box:X0,Y0,Z0,X1,Y1,Z1=W or sphere:X,Y,Z,R=W", spec);
    for (r->kind = 0; r->kind < 2; r->kind++) {
        const char *name = REGION_KINDS[r->kind].name;
        if (strlen(name) == (size_t)(colon - spec) && !strncmp(spec, name, strlen(name))) break;
    }
    if (r->kind == 2)
        return complain(RC_USAGE, "--weight %s: unknown region %.*s, expected box or sphere", spec, (int)(colon - spec), spec);
    want = REGION_KINDS[r->kind].count;
    for (n = 0, p = colon + 1; n < want; n++, p = end + 1)
        if (!(end = decimal_number(p, &v[n])) || *end != (n + 1 < want ? ',' : '=')) break;
    if (n < want || end != equals)
        return complain(RC_USAGE, "--weight %s: a %s takes %d numbers %s", spec, REGION_KINDS[r->kind].name, want,
                        REGION_KINDS[r->kind].numbers);
    if (!(end = decimal_number(equals + 1, &w)) || *end || !(w >= 0 && w <= 1))
        return complain(RC_USAGE, "--weight %s: the weight %s is not a number in [0, 1]", spec, equals + 1);
    if (r->kind == WEIGHT_BOX) {
        int k;
        for (k = 0; k < 3; k++) { /* corners in either order */
            r->a[k] = v[k] < v[k + 3] ? v[k] : v[k + 3];
            r->b[k] = v[k] < v[k + 3] ? v[k + 3] : v[k];
        }
    } else {
        if (!(v[3] > 0)) return complain(RC_USAGE, "--weight %s: the radius %g is not positive", spec, v[3]);
        memcpy(r->a, v, 3 * sizeof *v);
        r->b[0] = v[3];
    }
    r->weight = w;
    return RC_OK;
}

int weights_option(int argc, char **argv, int *i, weight_args *w, int *rc)
{
    const char *o = argv[*i], *v;
    if (!strcmp(o, "--saliency")) {
        w->saliency = 1;
        *rc = RC_OK;
    } else if (!strcmp(o, "--weights")) {
        *rc = w->file ? complain(RC_USAGE, "--weights given twice; give one file") : file_option(argc, argv, i, &w->file);
    } else if (!strcmp(o, "--importance")) {
        double *c = w->importance;
        if ((*rc = numbers_option(argc, argv, i, ',', 3, "three weights A,B,C", c)) != RC_OK) return 1;
        if (!(c[0] >= 0 && c[0] <= 1 && c[1] >= 0 && c[1] <= 1 && c[2] >= 0 && c[2] <= 1) || c[0] + c[1] + c[2] <= 0)
            *rc = complain(RC_USAGE, "--importance %g,%g,%g: each weight must be in [0, 1] and one above 0", c[0], c[1],
                           c[2]);
        w->blend = 2; /* the weights given */
    } else if (!strcmp(o, "--view-count")) {
        *rc = count_option(argc, argv, i, WEIGHT_VIEW_COUNT_MAX, &w->view_lattice);
    } else if (!strcmp(o, "--view-res")) {
        *rc = count_option(argc, argv, i, 8192, &w->view_res);
    } else if (!strcmp(o, "--view")) {
        if ((*rc = file_option(argc, argv, i, &v)) != RC_OK) return 1;
        if ((*rc = parse_view(v, w)) == RC_OK && !w->blend) w->blend = 1;
    } else if (!strcmp(o, "--weight")) {
        if ((*rc = file_option(argc, argv, i, &v)) != RC_OK) return 1;
        if (w->region_count == WEIGHT_REGIONS_MAX)
            *rc = complain(RC_USAGE, "--weight %s: at most %d regions", v, WEIGHT_REGIONS_MAX);
        else if ((*rc = parse_region(v, &w->regions[w->region_count])) == RC_OK)
            w->region_count++;
    } else {
        return 0;
    }
    return 1;
}

/* The blend's shares: --importance's, or the default's for --view alone. */
static const double *weights_importance(const weight_args *w)
{
    static const double defaults[3] = {0.5, 0.3, 0.2};
    return w->blend == 2 ? w->importance : defaults;
}

int weights_check(const weight_args *w)
{
    const double *c = w->importance;
    if (w->blend && weights_importance(w)[1] > 0) {
        double half = (double)(w->view_lattice ? w->view_lattice : ADASLICE_DEFAULT_VIEWS);
        double views = w->view_half < 0 ? (double)w->view_count : w->view_half == 2 ? 2 * half : half;
        double res = (double)(w->view_res ? w->view_res : ADASLICE_DEFAULT_VIEW_RESOLUTION);
        if (views * res * res > VIEW_PIXELS_LIMIT)
            return complain(RC_USAGE, "the view importance would render %.0f views of %.0f x %.0f pixels, %.3g in all, "
                            "more than %.3g: fewer views (--view-count) or a lower --view-res", views, res, res,
                            views * res * res, VIEW_PIXELS_LIMIT);
    }
    /* the user term is 0 where no weights are given: the blend would weigh nothing */
    if (w->blend == 2 && c[0] == 0 && c[1] == 0 && !w->file && !w->region_count)
        return complain(RC_USAGE, "--importance %g,%g,%g weighs only the user's weights, and no --weights or --weight "
                        "is given", c[0], c[1], c[2]);
    /* and the user's weights given a share of none would do nothing, unread */
    if (w->blend == 2 && c[2] == 0 && (w->file || w->region_count))
        return complain(RC_USAGE, "--importance %g,%g,0 gives the user's weights (%s) no share: drop them, or give "
                        "them one", c[0], c[1], w->file ? "--weights" : "--weight");
    return RC_OK;
}

/* Multiplies w[t] by line t's weight; blank lines and # comments are skipped. */
static int read_weights(const char *path, size_t count, float *w)
{
    FILE *f = fopen(path, "r");
    char line[TEXT_LINE_MAX], q[QUOTE_SIZE];
    size_t lineno = 0, n = 0;
    int rc = RC_OK;
    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    while (!rc && text_line_read(f, path, lineno + 1, line, RC_USAGE, &rc)) {
        char *s;
        const char *end;
        double v = 0;
        lineno++;
        s = text_line_trim(line);
        if (!*s || *s == '#') continue;
        if (!(end = decimal_number(s, &v)) || *end)
            rc = complain(RC_USAGE, "%s:%zu: '%s' is not a number", path, lineno, quote_text(q, s, strlen(s)));
        else if (!(v >= 0 && v <= 1))
            rc = complain(RC_USAGE, "%s:%zu: %s is not a weight in [0, 1]", path, lineno, quote_text(q, s, strlen(s)));
        else if (n == count)
            rc = complain(RC_USAGE, "%s:%zu: more weights than the model's %zu triangle%s", path, lineno, count,
                          plural(count));
        else
            w[n++] *= (float)v;
    }
    if (!rc && n != count)
        rc = complain(RC_USAGE, "%s: %zu weight%s for the model's %zu triangle%s (one per line, in the order they load)",
                      path, n, plural(n), count, plural(count));
    fclose(f);
    return rc;
}

static int in_region(const weight_region *r, const double c[3])
{
    double d2 = 0;
    int k;
    if (r->kind == WEIGHT_BOX) {
        for (k = 0; k < 3; k++)
            if (!(c[k] >= r->a[k] && c[k] <= r->b[k])) return 0;
        return 1;
    }
    for (k = 0; k < 3; k++) d2 += (c[k] - r->a[k]) * (c[k] - r->a[k]);
    return d2 <= r->b[0] * r->b[0];
}

static void apply_regions(const weight_args *w, const adaslice_mesh *mesh, float *out)
{
    size_t t, r;
    int k, j;
    for (t = 0; t < mesh->triangle_count && w->region_count; t++) {
        double c[3] = {0, 0, 0};
        for (j = 0; j < 3; j++)
            for (k = 0; k < 3; k++) c[k] += mesh->vertices[3 * (size_t)mesh->triangles[3 * t + j] + k] / 3.0;
        for (r = w->region_count; r-- > 0;)
            if (in_region(&w->regions[r], c)) {
                out[t] *= (float)w->regions[r].weight;
                break;
            }
    }
}

/* Divides by the largest value, so the term lies in [0, 1] (all 0 stays 0). */
static void normalise(float *v, size_t n)
{
    float top = 0;
    size_t t;
    for (t = 0; t < n; t++) if (v[t] > top) top = v[t];
    for (t = 0; top > 0 && t < n; t++) v[t] /= top;
}

/* a S + b V + c U, divided by its largest value: the user term U is the
   weight file and the regions (0 where none are given: nothing is marked). */
static int blend(const weight_args *w, const char *model, const adaslice_mesh *mesh, float *out)
{
    size_t t, n = mesh->triangle_count;
    const double *c = weights_importance(w);
    float *term = (float *)malloc((n ? n : 1) * sizeof *term);
    int rc = RC_OK, user = w->file || w->region_count;
    adaslice_error e;
    if (!term) return complain(RC_FAIL, "out of memory for %zu weight%s", n, plural(n));
    for (t = 0; t < n; t++) out[t] = 0;
    if (c[0] > 0) {
        if (adaslice_saliency(mesh, term, NULL, &e) != ADASLICE_OK) rc = library_error_in(model, &e);
        for (t = 0; !rc && t < n; t++) out[t] += (float)c[0] * term[t];
    }
    if (!rc && c[1] > 0) {
        adaslice_view_options vo;
        size_t half = w->view_lattice ? w->view_lattice : ADASLICE_DEFAULT_VIEWS, k;
        double *lattice = NULL;
        memset(&vo, 0, sizeof vo);
        vo.resolution = (int)w->view_res;
        vo.count = half;
        if (w->view_half < 0) {
            vo.directions = w->views;
            vo.count = w->view_count;
        } else if (w->view_half > 1) {
            /* the lattice's directions in that half of the sphere (all of it for "all") */
            const double *a = VIEW_NAMES[w->view_half].axis;
            lattice = (double *)malloc(2 * half * 3 * sizeof *lattice);
            if (!lattice) rc = complain(RC_FAIL, "out of memory for %zu views", 2 * half);
            if (lattice) adaslice_fibonacci_directions(2 * half, lattice);
            for (k = 0, vo.count = 0; lattice && k < 2 * half; k++)
                if (a[0] * lattice[3 * k] + a[1] * lattice[3 * k + 1] + a[2] * lattice[3 * k + 2] >= 0)
                    memmove(lattice + 3 * vo.count++, lattice + 3 * k, 3 * sizeof *lattice);
            vo.directions = lattice;
        }
        if (!rc && adaslice_view_importance(mesh, term, &vo, &e) != ADASLICE_OK) rc = library_error_in(model, &e);
        free(lattice);
        normalise(term, n);
        for (t = 0; !rc && t < n; t++) out[t] += (float)c[1] * term[t];
    }
    if (!rc && c[2] > 0 && user) {
        for (t = 0; t < n; t++) term[t] = 1;
        if (w->file) rc = read_weights(w->file, n, term);
        if (!rc) apply_regions(w, mesh, term);
        normalise(term, n);
        for (t = 0; !rc && t < n; t++) out[t] += (float)c[2] * term[t];
    }
    free(term);
    if (rc) return rc;
    normalise(out, n);
    return RC_OK;
}

int weights_for_plan(const weight_args *w, const char *model, const adaslice_mesh *mesh, float **out)
{
    size_t t, n = mesh->triangle_count;
    float *f, *s = NULL;
    int rc = RC_OK;
    *out = NULL;
    if (!weights_given(w)) return RC_OK;
    f = (float *)malloc((n ? n : 1) * sizeof *f);
    if (w->saliency) s = (float *)malloc((n ? n : 1) * sizeof *s);
    if (!f || (w->saliency && !s)) rc = complain(RC_FAIL, "out of memory for %zu weight%s", n, plural(n));
    if (!rc && w->blend) {
        rc = blend(w, model, mesh, f);
        free(s);
        if (rc) { free(f); return rc; }
        *out = f;
        return RC_OK;
    }
    for (t = 0; !rc && t < n; t++) f[t] = 1;
    /* the file first: a mistake there shows before the saliency's second */
    if (!rc && w->file) rc = read_weights(w->file, n, f);
    if (!rc && w->saliency) {
        adaslice_error e;
        if (adaslice_saliency(mesh, s, NULL, &e) != ADASLICE_OK) rc = library_error_in(model, &e);
        for (t = 0; !rc && t < n; t++) f[t] *= s[t];
    }
    if (!rc) apply_regions(w, mesh, f);
    free(s);
    if (rc) {
        free(f);
        return rc;
    }
    *out = f;
    return RC_OK;
}
