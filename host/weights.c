/* Per-face weights: saliency, a weight file and regions, multiplied face by face. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* getline */
#endif
#include "weights.h"
#include "options.h"
#include "output.h"
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void weights_usage(FILE *f, int saliency_option)
{
    fputs("weights (paper section 4.2), multiplied face by face into the profile\n", f);
    if (saliency_option)
        fputs("  --saliency          weight faces by their mesh saliency (Lee et al. 2005);\n"
              "                      adaslice saliency shows it\n", f);
    fputs("  --weights FILE      one weight in [0,1] per line for each triangle, in the\n"
          "                      order the model loads (adaslice saliency -o writes one)\n"
          "  --weight REGION=W   weight W in [0,1] for the faces whose centroid lies in\n"
          "                      REGION: box:X0,Y0,Z0,X1,Y1,Z1 or sphere:X,Y,Z,R (mm, after\n"
          "                      --scale). Repeatable; where regions overlap the last one\n"
          "                      given wins; faces in none keep 1\n", f);
}

int weights_given(const weight_args *w)
{
    return w->saliency || w->file || w->region_count;
}

static const struct { const char *name, *numbers; int count; } REGION_KINDS[] = { /* by WEIGHT_BOX, WEIGHT_SPHERE */
    {"box", "X0,Y0,Z0,X1,Y1,Z1", 6}, {"sphere", "X,Y,Z,R", 4}};

/* "box:x0,y0,z0,x1,y1,z1=W" or "sphere:x,y,z,r=W" */
static int parse_region(const char *spec, weight_region *r)
{
    const char *colon = strchr(spec, ':'), *equals = strrchr(spec, '='), *p;
    double v[6], w;
    char *end = NULL;
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
    for (n = 0, p = colon + 1; n < want; n++, p = end + 1) {
        v[n] = strtod(p, &end);
        if (end == p || !isfinite(v[n]) || *end != (n + 1 < want ? ',' : '=')) break;
    }
    if (n < want || end != equals)
        return complain(RC_USAGE, "--weight %s: a %s takes %d numbers %s", spec, REGION_KINDS[r->kind].name, want,
                        REGION_KINDS[r->kind].numbers);
    w = strtod(equals + 1, &end);
    if (end == equals + 1 || *end || !(w >= 0 && w <= 1))
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

static char *trim(char *s)
{
    char *end = s + strlen(s);
    while (*s == ' ' || *s == '\t') s++;
    while (end > s && (end[-1] == '\n' || end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t')) *--end = 0;
    return s;
}

/* Multiplies w[t] by line t's weight; blank lines and # comments are skipped. */
static int read_weights(const char *path, size_t count, float *w)
{
    FILE *f = fopen(path, "r");
    char *line = NULL, q[QUOTE_SIZE];
    size_t cap = 0, lineno = 0, n = 0;
    int rc = RC_OK;
    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    while (!rc && getline(&line, &cap, f) != -1) {
        char *s = trim(line), *end;
        double v;
        lineno++;
        if (!*s || *s == '#') continue;
        v = strtod(s, &end);
        if (end == s || *end)
            rc = complain(RC_USAGE, "%s:%zu: '%s' is not a number", path, lineno, quote_text(q, s, strlen(s)));
        else if (!(v >= 0 && v <= 1))
            rc = complain(RC_USAGE, "%s:%zu: %s is not a weight in [0, 1]", path, lineno, quote_text(q, s, strlen(s)));
        else if (n == count)
            rc = complain(RC_USAGE, "%s:%zu: more weights than the model's %zu triangle%s", path, lineno, count,
                          plural(count));
        else
            w[n++] *= (float)v;
    }
    if (!rc && ferror(f)) rc = complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    if (!rc && n != count)
        rc = complain(RC_USAGE, "%s: %zu weight%s for the model's %zu triangle%s (one per line, in the order they load)",
                      path, n, plural(n), count, plural(count));
    fclose(f);
    free(line);
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

int weights_for_plan(const weight_args *w, const adaslice_mesh *mesh, float **out)
{
    size_t t, n = mesh->triangle_count;
    float *f, *s = NULL;
    int rc = RC_OK;
    *out = NULL;
    if (!weights_given(w)) return RC_OK;
    f = (float *)malloc((n ? n : 1) * sizeof *f);
    if (w->saliency) s = (float *)malloc((n ? n : 1) * sizeof *s);
    if (!f || (w->saliency && !s)) rc = complain(RC_FAIL, "out of memory for %zu weight%s", n, plural(n));
    for (t = 0; !rc && t < n; t++) f[t] = 1;
    /* the file first: a mistake there shows before the saliency's second */
    if (!rc && w->file) rc = read_weights(w->file, n, f);
    if (!rc && w->saliency) {
        adaslice_error e;
        if (adaslice_saliency(mesh, s, NULL, &e) != ADASLICE_OK) rc = library_error(&e);
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
