/* adaslice - the command-line tool over adaslice.h.

   adaslice plan MODEL [options]          plan adaptive layers for a mesh
   adaslice plan --profile FILE [options] plan a metric profile made elsewhere

   Exit status: 0 done; 1 the work failed (a file that cannot be read or written,
   a malformed mesh, constraints that no plan meets); 2 the command line is wrong.
   Every message is one line on stderr that starts with "adaslice: ". */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* getline, clock_gettime */
#endif
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"
#include "cli.h"
#include "curvature.h"
#include "svg.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>


int complain(int rc, const char *fmt, ...)
{
    va_list ap;
    fputs("adaslice: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return rc;
}

/* A parameter the library rejects came from the command line, hence exit 2. */
int library_error(const adaslice_error *e)
{
    return complain(e->result == ADASLICE_ERR_ARGUMENT ? RC_USAGE : RC_FAIL, "%s", e->message);
}

double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* ----------------------------------------------------- names and units */

const char *const METRIC_NAMES[] = {"cusp", "roughness", "area", "volume"};
const char *const METHOD_NAMES[] = {"optimal", "greedy", "finest", "coarsest", "curvature"};
const char *const SAMPLER_NAMES[] = {"exact", "ldi"};

const metric_info METRICS[METRIC_COUNT] = { /* by adaslice_metric */
    {"cusp height", "cusp height per mm of layer (mm/mm)", "mm"},       /* eq. 4-6 */
    {"roughness", "roughness per mm of layer (mm/mm)", "mm"},           /* eq. 8-10 */
    {"area deviation", "area deviation per mm of layer (1/mm)", ""},    /* eq. 12-14 */
    {"volume deviation", "cross-section area A(z) (mm^2)", "mm^3"},     /* eq. 17-20 */
};

static const char *format_name(adaslice_format f)
{
    static const char *const names[] = {"unknown format", "binary STL", "ASCII STL", "OBJ", "PLY"};
    return (unsigned)f < sizeof names / sizeof *names ? names[f] : names[0];
}

/* " mm" or "" for a dimensionless value */
static const char *unit_suffix(const char *unit, char buf[16])
{
    snprintf(buf, 16, "%s%s", *unit ? " " : "", unit);
    return buf;
}

/* ------------------------------------------------------ atomic output */


/* Writes PATH through "PATH.tmp.PID" and renames it into place, so that PATH
   never holds a partial file whatever fails. */
int write_atomic(const char *path, write_fn fill, const void *ctx)
{
    size_t size = strlen(path) + 32;
    char *tmp = malloc(size);
    FILE *f;
    int err = 0;
    if (!tmp) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    snprintf(tmp, size, "%s.tmp.%ld", path, (long)getpid());
    f = fopen(tmp, "w");
    if (!f) {
        err = errno;
    } else {
        errno = 0;
        fill(f, ctx);
        if (ferror(f)) err = errno ? errno : EIO;
        if (fflush(f) != 0 && !err) err = errno;
        if (fclose(f) != 0 && !err) err = errno;
        if (!err && rename(tmp, path) != 0) err = errno;
        if (err) remove(tmp);
    }
    free(tmp);
    return err ? complain(RC_FAIL, "cannot write %s: %s", path, strerror(err)) : RC_OK;
}

void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
        else if (c < 0x20) fprintf(f, "\\u%04x", c);
        else fputc(c, f);
    }
    fputc('"', f);
}

void json_number(FILE *f, double v)
{
    if (isfinite(v)) fprintf(f, "%.17g", v);
    else fputs("null", f);
}

/* ---------------------------------------------------------------- plan */



static void plan_usage(FILE *f)
{
    fputs("usage: adaslice plan MODEL [options]\n"
          "       adaslice plan --profile FILE [options]\n"
          "\n"
          "Finds the slicing plan with the fewest layers whose every layer error stays\n"
          "within eps (Mao et al., Adaptive Slicing Based on Efficient Profile Analysis,\n"
          "section 3.3). MODEL is a binary or ASCII STL, OBJ or PLY file in mm; +z is up.\n"
          "\n", f);
    plan_options_usage(f);
}

void plan_options_usage(FILE *f)
{
    fprintf(f,
        "input\n"
        "  --profile FILE      plan this profile instead of a MODEL: one value per line,\n"
        "                      or CSV whose last column is the value; bins of --bin mm\n"
        "  --scale S           multiply the model's coordinates by S (metres: 1000)\n"
        "profile\n"
        "  --metric NAME       cusp, roughness, area or volume             [cusp]\n"
        "  --bin MM            bin size                                    [%g]\n"
        "  --sampler NAME      exact (from the triangles) or ldi (the\n"
        "                      paper's sampling by rays along x, y, z)     [exact]\n"
        "  --res R             ldi: pixels across the largest extent       [%d]\n"
        "  --orient D          turn the part so direction D points up: X,Y,Z, or best\n"
        "                      (the best of 1000, as adaslice orient finds it)\n"
        "plan\n"
        "  --method NAME       optimal, greedy, finest, coarsest or\n"
        "                      curvature (thickness from mean curvature)   [optimal]\n"
        "  --mapping NAME      curvature: linear, exp or step              [linear]\n"
        "  --eps E             allowed error per layer (mm; area: none;\n"
        "                      volume: mm^3)                               [%g]\n"
        "  --tmin MM           thinnest layer                              [%g]\n"
        "  --tmax MM           thickest layer                              [%g]\n"
        "  --sharp T           a plane at each phi jump above T; 0: off    [%g]\n"
        "  --budget K          at most K layers, with the smallest eps that allows it\n"
        "output\n"
        "  --out FILE          the plan as CSV: layer,z_bottom,z_top,thickness,error\n"
        "  --profile-out FILE  the profile as CSV: z,phi (z: bin centre)\n"
        "  --plot FILE         SVG figure of the profile and the layer thickness\n"
        "  --json              print a JSON object instead of the summary\n"
        "  --compare           plan coarsest, optimal, greedy, finest and (for a MODEL)\n"
        "                      curvature on the same profile and print them as in\n"
        "                      the paper's Table 3\n"
        "Heights are in mm from the part's bottom.\n",
        ADASLICE_DEFAULT_BIN, ADASLICE_DEFAULT_RESOLUTION, ADASLICE_DEFAULT_EPS, ADASLICE_DEFAULT_TMIN,
        ADASLICE_DEFAULT_TMAX, ADASLICE_DEFAULT_SHARP);
    weights_usage(f);
}

/* The value after option argv[*i]; NULL, said so, if there is none. */
static const char *value_of(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc || !strncmp(argv[*i + 1], "--", 2)) {
        complain(RC_USAGE, "option %s needs a value", argv[*i]);
        return NULL;
    }
    return argv[++*i];
}

int file_option(int argc, char **argv, int *i, const char **out)
{
    *out = value_of(argc, argv, i);
    return *out ? RC_OK : RC_USAGE;
}

int number_option(int argc, char **argv, int *i, int zero_ok, double *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i);
    char *end;
    double d;
    if (!v) return RC_USAGE;
    d = strtod(v, &end);
    if (end == v || *end || !isfinite(d) || d < 0 || (d == 0 && !zero_ok))
        return complain(RC_USAGE, "%s %s: not a %s finite number", opt, v, zero_ok ? "non-negative" : "positive");
    *out = d;
    return RC_OK;
}

int count_option(int argc, char **argv, int *i, size_t *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i);
    char *end;
    unsigned long long n;
    if (!v) return RC_USAGE;
    errno = 0;
    n = strtoull(v, &end, 10);
    /* planes are 32-bit bin indices, so no plan has more layers than that */
    if (*v < '0' || *v > '9' || *end || errno == ERANGE || n == 0 || n > UINT32_MAX)
        return complain(RC_USAGE, "%s %s: not a positive whole number", opt, v);
    *out = (size_t)n;
    return RC_OK;
}

int name_option(int argc, char **argv, int *i, const char *const *names, int count,
                       const char *choices, int *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i);
    int k;
    if (!v) return RC_USAGE;
    for (k = 0; k < count; k++)
        if (!strcmp(v, names[k])) {
            *out = k;
            return RC_OK;
        }
    return complain(RC_USAGE, "%s %s: unknown, expected %s", opt, v, choices);
}

/* --orient best, or a direction X,Y,Z that is not zero */
static int orient_option(int argc, char **argv, int *i, const char **out)
{
    double d[3];
    char tail;
    int rc = file_option(argc, argv, i, out);
    if (rc || !strcmp(*out, "best")) return rc;
    if (sscanf(*out, "%lf,%lf,%lf%c", &d[0], &d[1], &d[2], &tail) != 3 || !isfinite(d[0]) || !isfinite(d[1]) ||
        !isfinite(d[2]) || (d[0] == 0 && d[1] == 0 && d[2] == 0))
        return complain(RC_USAGE, "--orient %s: expected best or a direction X,Y,Z", *out);
    return RC_OK;
}

int parse_plan(int argc, char **argv, plan_args *a)
{
    int i, rc = RC_OK, metric = ADASLICE_METRIC_CUSP, method = ADASLICE_METHOD_OPTIMAL, sampler = 0;
    memset(a, 0, sizeof *a);
    a->bin = ADASLICE_DEFAULT_BIN;
    a->eps = ADASLICE_DEFAULT_EPS;
    a->tmin = ADASLICE_DEFAULT_TMIN;
    a->tmax = ADASLICE_DEFAULT_TMAX;
    a->sharp = ADASLICE_DEFAULT_SHARP;
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (o[0] != '-') {
            if (a->model) return complain(RC_USAGE, "unexpected argument %s: MODEL is already %s", o, a->model);
            a->model = o;
        }
        else if (!strcmp(o, "--help") || !strcmp(o, "-h")) { a->help = 1; return RC_OK; }
        else if (!strcmp(o, "--json")) a->json = 1;
        else if (!strcmp(o, "--compare")) a->compare = 1;
        else if (!strcmp(o, "--profile")) rc = file_option(argc, argv, &i, &a->profile);
        else if (!strcmp(o, "--out")) rc = file_option(argc, argv, &i, &a->out);
        else if (!strcmp(o, "--profile-out")) rc = file_option(argc, argv, &i, &a->profile_out);
        else if (!strcmp(o, "--plot")) rc = file_option(argc, argv, &i, &a->plot);
        else if (!strcmp(o, "--bin")) rc = number_option(argc, argv, &i, 0, &a->bin);
        else if (!strcmp(o, "--eps")) rc = number_option(argc, argv, &i, 0, &a->eps);
        else if (!strcmp(o, "--tmin")) rc = number_option(argc, argv, &i, 0, &a->tmin);
        else if (!strcmp(o, "--tmax")) rc = number_option(argc, argv, &i, 0, &a->tmax);
        else if (!strcmp(o, "--scale")) rc = number_option(argc, argv, &i, 0, &a->scale);
        else if (!strcmp(o, "--sharp")) rc = number_option(argc, argv, &i, 1, &a->sharp);
        else if (!strcmp(o, "--budget")) rc = count_option(argc, argv, &i, &a->budget);
        else if (!strcmp(o, "--res")) rc = count_option(argc, argv, &i, &a->resolution);
        else if (!strcmp(o, "--orient")) rc = orient_option(argc, argv, &i, &a->orient);
        else if (!strcmp(o, "--sampler")) rc = name_option(argc, argv, &i, SAMPLER_NAMES, 2, "exact or ldi", &sampler);
        else if (!strcmp(o, "--metric"))
            rc = name_option(argc, argv, &i, METRIC_NAMES, METRIC_COUNT, "cusp, roughness, area or volume", &metric);
        else if (!strcmp(o, "--method"))
            rc = name_option(argc, argv, &i, METHOD_NAMES, METHOD_COUNT, "optimal, greedy, finest, coarsest or curvature",
                             &method);
        else if (!strcmp(o, "--mapping"))
            rc = name_option(argc, argv, &i, MAPPING_NAMES, MAPPING_COUNT, "linear, exp or step", &a->mapping);
        else if (weights_option(argc, argv, &i, &a->weights, &rc)) continue;
        else return complain(RC_USAGE, "unknown option %s (see adaslice plan --help)", o);
    }
    if (rc) return rc;
    a->metric = (adaslice_metric)metric;
    a->method = (adaslice_method)method;
    a->sampler = sampler;
    if (a->resolution > 65536) return complain(RC_USAGE, "--res %zu: at most 65536", a->resolution);
    if (a->resolution && !a->sampler) return complain(RC_USAGE, "--res applies to --sampler ldi");
    if (!a->model && !a->profile) return complain(RC_USAGE, "plan needs a MODEL or --profile FILE");
    if (a->model && a->profile)
        return complain(RC_USAGE, "plan takes a MODEL or --profile FILE, not both (%s and --profile %s)",
                        a->model, a->profile);
    if (a->profile && a->scale) return complain(RC_USAGE, "--scale applies to a MODEL, not to --profile");
    if (a->profile && weights_given(&a->weights))
        return complain(RC_USAGE, "--saliency, --weights and --weight weight a MODEL's faces, not --profile");
    if (a->profile && a->method == ADASLICE_METHOD_CURVATURE)
        return complain(RC_USAGE, "--method curvature needs a MODEL's curvature, not --profile");
    if (a->method == ADASLICE_METHOD_CURVATURE && a->orient && !strcmp(a->orient, "best"))
        return complain(RC_USAGE, "--orient best searches with the library's methods, not curvature");
    if (a->tmin > a->tmax) return complain(RC_USAGE, "--tmin %g is larger than --tmax %g", a->tmin, a->tmax);
    if (a->budget && a->method != ADASLICE_METHOD_OPTIMAL)
        return complain(RC_USAGE, "--budget works with --method optimal only, not %s", METHOD_NAMES[a->method]);
    return RC_OK;
}

static int profile_model(const plan_args *a, plan_job *j)
{
    adaslice_load_options lo;
    adaslice_profile_options po;
    adaslice_mesh mesh;
    adaslice_error err;
    adaslice_result r;
    double t0 = now_ms(), ms_weights;
    float *weights = NULL;
    int rc;

    memset(&lo, 0, sizeof lo);
    lo.scale = a->scale;
    if (adaslice_mesh_load_file(a->model, &lo, &mesh, &err) != ADASLICE_OK) return library_error(&err);
    j->ms_load = now_ms() - t0;
    /* before any turn, so that regions are in the model's own coordinates */
    t0 = now_ms();
    if ((rc = weights_for_plan(&a->weights, &mesh, &weights)) != RC_OK) {
        adaslice_mesh_free(&mesh);
        return rc;
    }
    ms_weights = now_ms() - t0;
    j->up[0] = j->up[1] = 0;
    j->up[2] = 1;
    if (a->orient) {
        /* turn the part so the chosen direction points up (+z) */
        double r[9], len;
        if (!strcmp(a->orient, "best")) {
            adaslice_direction_score *scores = NULL;
            size_t minima[4], count = 0;
            rc = orient_search(a, &mesh, 1000, 0.5, &scores, minima, &count);
            if (!rc && !count) rc = complain(RC_FAIL, "no build direction has a feasible plan");
            if (rc) { free(scores); free(weights); adaslice_mesh_free(&mesh); return rc; }
            memcpy(j->up, scores[minima[0]].direction, sizeof j->up);
            free(scores);
        } else {
            sscanf(a->orient, "%lf,%lf,%lf", &j->up[0], &j->up[1], &j->up[2]);
        }
        len = sqrt(j->up[0] * j->up[0] + j->up[1] * j->up[1] + j->up[2] * j->up[2]);
        j->up[0] /= len; j->up[1] /= len; j->up[2] /= len;
        adaslice_rotation_to_z(j->up, r);
        adaslice_mesh_rotate(&mesh, r);
    }
    j->triangles = mesh.triangle_count;
    j->degenerate = mesh.degenerate_dropped;
    j->format = mesh.format;

    memset(&po, 0, sizeof po);
    po.metric = a->metric;
    po.bin = a->bin;
    po.resolution = (int)a->resolution;
    po.weights = weights;
    t0 = now_ms();
    r = a->sampler ? adaslice_profile_sampled(&mesh, &po, &j->profile, &err)
                   : adaslice_profile_exact(&mesh, &po, &j->profile, &err);
    free(weights);
    if (r == ADASLICE_OK && (a->method == ADASLICE_METHOD_CURVATURE || a->compare))
        rc = curvature_for_plan(&mesh, &j->profile, &j->kappa);
    j->ms_profile = now_ms() - t0 + ms_weights;
    if (j->keep_mesh) j->mesh = mesh;
    else adaslice_mesh_free(&mesh);
    if (r != ADASLICE_OK) return library_error(&err);
    j->profiled = 1;
    return rc;
}

static char *trim(char *s)
{
    char *end = s + strlen(s);
    while (*s == ' ' || *s == '\t') s++;
    while (end > s && (end[-1] == '\n' || end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t')) *--end = 0;
    return s;
}

/* Appends v to the growing array *phi of *n values. */
static int push(double **phi, size_t *n, size_t *cap, double v)
{
    if (*n == *cap) {
        size_t grown = *cap ? 2 * *cap : 4096;
        double *p = grown > SIZE_MAX / sizeof *p ? NULL : realloc(*phi, grown * sizeof *p);
        if (!p) return 0;
        *phi = p;
        *cap = grown;
    }
    (*phi)[(*n)++] = v;
    return 1;
}

/* One value per line, or CSV with the value last; blank lines and # comments
   are skipped, and so is a first line that is not a number (a header). */
static int read_profile(const plan_args *a, plan_job *j)
{
    const char *path = a->profile;
    FILE *f = fopen(path, "r");
    char *line = NULL;
    size_t line_cap = 0, lineno = 0, n = 0, cap = 0;
    double *phi = NULL, t0 = now_ms();
    int rc = RC_OK, first = 1;

    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    while (!rc && getline(&line, &line_cap, f) != -1) {
        char *s = trim(line), *field = strrchr(s, ','), *end;
        double v;
        lineno++;
        if (!*s || *s == '#') continue;
        field = field ? trim(field + 1) : s;
        v = strtod(field, &end);
        if (end == field || *end) {
            if (!first) rc = complain(RC_FAIL, "%s:%zu: not a number: %.80s", path, lineno, s);
        } else if (!isfinite(v) || v < 0) {
            rc = complain(RC_FAIL, "%s:%zu: %.80s: profile values must be finite and >= 0", path, lineno, s);
        } else if (!push(&phi, &n, &cap, v)) {
            rc = complain(RC_FAIL, "%s: out of memory after %zu values", path, n);
        }
        first = 0;
    }
    if (!rc && ferror(f)) rc = complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    if (!rc && !n) rc = complain(RC_FAIL, "%s: no profile values", path);
    fclose(f);
    free(line);
    j->ms_load = now_ms() - t0;
    if (rc) {
        free(phi);
        return rc;
    }
    j->profile.metric = a->metric;
    j->profile.bin_count = n;
    j->profile.bin = a->bin;
    j->profile.height = n * a->bin;
    j->profile.phi = phi;
    return RC_OK;
}

void plan_options_of(const plan_args *a, adaslice_method method, adaslice_plan_options *o)
{
    memset(o, 0, sizeof *o);
    o->method = method;
    o->eps = a->eps;
    o->tmin = a->tmin;
    o->tmax = a->tmax;
    o->sharp = a->sharp > 0 ? a->sharp : ADASLICE_SHARP_OFF;
    o->budget = method == ADASLICE_METHOD_OPTIMAL ? a->budget : 0;
    o->eps_units = method == ADASLICE_METHOD_OPTIMAL ? a->eps_units : 0;
}

static adaslice_result plan_with(const plan_args *a, plan_job *j, adaslice_method method)
{
    adaslice_plan_options o;
    adaslice_result r;
    plan_options_of(a, method, &o);
    r = method == ADASLICE_METHOD_CURVATURE ? plan_curvature_with(a, j, &j->plan[method], &j->why[method])
                                   : adaslice_plan_profile(&j->profile, &o, &j->plan[method], &j->why[method]);
    j->why[method].result = r;
    j->planned[method] = 1;
    return r;
}

/* The asked plan must succeed; with --compare the others may be infeasible,
   which their row of the table then says. */
int run_plan(const plan_args *a, plan_job *j)
{
    double t0;
    int rc = a->model ? profile_model(a, j) : read_profile(a, j), m;
    if (rc) return rc;
    t0 = now_ms();
    if (plan_with(a, j, a->method) != ADASLICE_OK) return library_error(&j->why[a->method]);
    j->ms_plan = now_ms() - t0;
    for (m = 0; a->compare && m < METHOD_COUNT; m++) {
        adaslice_result r;
        if (m == ADASLICE_METHOD_CURVATURE && !j->kappa) continue; /* a --profile has no curvature */
        r = j->planned[m] ? ADASLICE_OK : plan_with(a, j, (adaslice_method)m);
        if (r != ADASLICE_OK && r != ADASLICE_ERR_INFEASIBLE) return library_error(&j->why[m]);
    }
    return RC_OK;
}

void job_free(plan_job *j)
{
    int m;
    for (m = 0; m < METHOD_COUNT; m++)
        if (j->planned[m] && j->why[m].result == ADASLICE_OK) adaslice_plan_free(&j->plan[m]);
    if (j->profiled) adaslice_profile_free(&j->profile);
    else free(j->profile.phi);
    free(j->kappa);
    adaslice_mesh_free(&j->mesh);
}

static void write_plan_csv(FILE *f, const void *ctx)
{
    const plan_job *j = (const plan_job *)ctx;
    const adaslice_plan *p = &j->plan[j->args->method];
    size_t k;
    fputs("layer,z_bottom,z_top,thickness,error\n", f);
    for (k = 0; k < p->layer_count; k++) {
        const adaslice_layer *l = &p->layers[k];
        fprintf(f, "%zu,%.9g,%.9g,%.9g,%.9g\n", k + 1, l->z_bottom, l->z_top, l->thickness, l->error);
    }
}

/* phi with 17 digits, so that planning the file with --profile gives this plan. */
static void write_profile_csv(FILE *f, const void *ctx)
{
    const adaslice_profile *pr = &((const plan_job *)ctx)->profile;
    size_t i;
    fputs("z,phi\n", f);
    for (i = 0; i < pr->bin_count; i++) fprintf(f, "%.9g,%.17g\n", (i + 0.5) * pr->bin, pr->phi[i]);
}

static void write_plot(FILE *f, const void *ctx)
{
    const plan_job *j = (const plan_job *)ctx;
    const plan_args *a = j->args;
    svg_plan_figure fig;
    fig.model = base_name(a->model ? a->model : a->profile);
    fig.metric = METRICS[a->metric].label;
    fig.phi_axis = METRICS[a->metric].phi_axis;
    fig.eps_unit = METRICS[a->metric].eps_unit;
    fig.method = METHOD_NAMES[a->method];
    fig.profile = &j->profile;
    fig.plan = &j->plan[a->method];
    svg_write_plan(f, &fig);
}

int write_outputs(const plan_args *a, const plan_job *j)
{
    if (a->out && write_atomic(a->out, write_plan_csv, j)) return RC_FAIL;
    if (a->profile_out && write_atomic(a->profile_out, write_profile_csv, j)) return RC_FAIL;
    if (a->plot && write_atomic(a->plot, write_plot, j)) return RC_FAIL;
    return RC_OK;
}

/* The rows of the paper's Table 3, in its order. */
static const adaslice_method TABLE3[] = {
    ADASLICE_METHOD_COARSEST, ADASLICE_METHOD_OPTIMAL, ADASLICE_METHOD_GREEDY, ADASLICE_METHOD_FINEST,
    ADASLICE_METHOD_CURVATURE};
static const char *const TABLE3_NAMES[] = {"Coarsest", "Optimal", "Greedy", "Finest", "Curvature"};
enum { TABLE3_ROWS = sizeof TABLE3 / sizeof *TABLE3 };

static void print_compare(const plan_args *a, const plan_job *j)
{
    const char *unit = METRICS[a->metric].eps_unit;
    char u[16], head[40];
    int r;
    snprintf(head, sizeof head, "worst error%s%s%s", *unit ? " (" : "", unit, *unit ? ")" : "");
    printf("\nTable 3: %s, %s, eps %g%s\n", base_name(a->model ? a->model : a->profile),
           METRICS[a->metric].label, a->eps, unit_suffix(unit, u));
    printf("%-10s %8s %18s %10s\n", "method", "layers", head, "over eps");
    for (r = 0; r < TABLE3_ROWS; r++) {
        const adaslice_plan *p = &j->plan[TABLE3[r]];
        const adaslice_error *e = &j->why[TABLE3[r]];
        if (!j->planned[TABLE3[r]]) continue; /* curvature, from a --profile */
        if (e->result == ADASLICE_OK)
            printf("%-10s %8zu %18.6g %10zu\n", TABLE3_NAMES[r], p->layer_count, p->worst_error, p->over_eps);
        else if (e->min_eps > 0)
            printf("%-10s %8s   (feasible from eps %g)\n", TABLE3_NAMES[r], "none", e->min_eps);
        else
            printf("%-10s %8s   (tmin..tmax cannot tile the height)\n", TABLE3_NAMES[r], "none");
    }
    if (a->budget)
        printf("(Optimal with a budget of %zu layers: eps %g%s)\n", a->budget, j->plan[ADASLICE_METHOD_OPTIMAL].eps, u);
}

static void print_summary(const plan_args *a, const plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    const adaslice_profile *pr = &j->profile;
    char u[16];
    const char *eu = unit_suffix(METRICS[a->metric].eps_unit, u);
    if (a->model) {
        printf("model      %s: %s, %zu triangles", a->model, format_name(j->format), j->triangles);
        if (j->degenerate) printf(" (%zu degenerate dropped)", j->degenerate);
        printf("\n");
    } else {
        printf("profile    %s: %zu values\n", a->profile, pr->bin_count);
    }
    printf("height     %g mm, %zu bins of %g mm\n", pr->height, pr->bin_count, pr->bin);
    printf("metric     %s", METRICS[a->metric].label);
    if (a->model && a->sampler)
        printf(", sampled by LDIs of %d pixels across (%zu bins no ray reached take their neighbours' value)",
               a->resolution ? (int)a->resolution : ADASLICE_DEFAULT_RESOLUTION, j->profile.unsampled_bins);
    printf("\n");
    printf("method     %s, eps %g%s", METHOD_NAMES[a->method], p->eps, eu);
    if (a->method == ADASLICE_METHOD_CURVATURE)
        printf(" (%s mapping; eps only counts the layers over it)", MAPPING_NAMES[a->mapping]);
    if (a->budget) printf(" (the smallest that fits %zu layers)", a->budget);
    printf("\nthickness  %g .. %g mm, %u .. %u bins per layer\n", a->tmin, a->tmax, p->bins_min, p->bins_max);
    printf("layers     %zu\n", p->layer_count);
    printf("error      worst %g%s, total %g%s", p->worst_error, eu, p->total_error, eu);
    if (p->over_eps) printf(", %zu layers over eps", p->over_eps);
    printf("\n");
    /* the section 3.3 pre-pass belongs to the optimal method only */
    if (a->method == ADASLICE_METHOD_OPTIMAL && a->sharp > 0)
        printf("forced     %zu plane%s at sharp changes (> %g)\n", p->forced_planes,
               p->forced_planes == 1 ? "" : "s", a->sharp);
    else if (a->method == ADASLICE_METHOD_OPTIMAL)
        printf("forced     none (sharp-change pre-pass off)\n");
    printf("time       load %.1f ms, profile %.1f ms, plan %.1f ms\n", j->ms_load, j->ms_profile, j->ms_plan);
    if (a->compare) print_compare(a, j);
}

static void print_json_plan_fields(FILE *f, const adaslice_plan *p)
{
    fprintf(f, "\"layers\": %zu, \"worst_error\": ", p->layer_count);
    json_number(f, p->worst_error);
    fputs(", \"total_error\": ", f);
    json_number(f, p->total_error);
    fprintf(f, ", \"over_eps\": %zu", p->over_eps);
}

static void print_json(const plan_args *a, const plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    const adaslice_profile *pr = &j->profile;
    size_t k;
    int r;
    printf("{\n  \"model\": ");
    json_string(stdout, a->model ? a->model : a->profile);
    printf(",\n  \"source\": \"%s\",\n  \"format\": ", a->model ? "mesh" : "profile");
    if (a->model) json_string(stdout, format_name(j->format));
    else printf("null");
    if (a->model) printf(",\n  \"triangles\": %zu,\n  \"degenerate_dropped\": %zu", j->triangles, j->degenerate);
    else printf(",\n  \"triangles\": null,\n  \"degenerate_dropped\": null");
    printf(",\n  \"metric\": \"%s\",\n  \"sampler\": \"%s\",\n  \"unsampled_bins\": %zu,\n  \"method\": \"%s\",\n  \"eps\": ",
           METRIC_NAMES[a->metric], SAMPLER_NAMES[a->sampler], j->profile.unsampled_bins, METHOD_NAMES[a->method]);
    json_number(stdout, p->eps);
    printf(",\n  \"tmin\": ");
    json_number(stdout, a->tmin);
    printf(",\n  \"tmax\": ");
    json_number(stdout, a->tmax);
    printf(",\n  \"bin\": ");
    json_number(stdout, pr->bin);
    printf(",\n  \"bins\": %zu,\n  \"bins_min\": %u,\n  \"bins_max\": %u,\n  \"height_mm\": ",
           pr->bin_count, p->bins_min, p->bins_max);
    json_number(stdout, pr->height);
    if (a->budget) printf(",\n  \"budget\": %zu", a->budget);
    printf(",\n  \"sharp\": ");
    if (a->sharp > 0) json_number(stdout, a->sharp);
    else printf("null");
    printf(",\n  ");
    print_json_plan_fields(stdout, p);
    printf(",\n  \"forced_planes\": %zu,\n  \"time_ms\": {\"load\": %.3f, \"profile\": %.3f, \"plan\": %.3f}",
           p->forced_planes, j->ms_load, j->ms_profile, j->ms_plan);
    printf(",\n  \"layer_list\": [");
    for (k = 0; k < p->layer_count; k++) {
        const adaslice_layer *l = &p->layers[k];
        printf("%s\n    {\"z_bottom\": ", k ? "," : "");
        json_number(stdout, l->z_bottom);
        printf(", \"z_top\": ");
        json_number(stdout, l->z_top);
        printf(", \"thickness\": ");
        json_number(stdout, l->thickness);
        printf(", \"error\": ");
        json_number(stdout, l->error);
        printf("}");
    }
    printf("\n  ]");
    if (a->compare) {
        printf(",\n  \"compare\": [");
        for (r = 0; r < TABLE3_ROWS; r++) {
            const adaslice_error *e = &j->why[TABLE3[r]];
            if (!j->planned[TABLE3[r]]) continue;
            printf("%s\n    {\"method\": \"%s\", ", r ? "," : "", METHOD_NAMES[TABLE3[r]]);
            if (e->result == ADASLICE_OK) {
                print_json_plan_fields(stdout, &j->plan[TABLE3[r]]);
            } else {
                printf("\"layers\": null, \"min_eps\": ");
                json_number(stdout, e->min_eps);
            }
            printf("}");
        }
        printf("\n  ]");
    }
    printf("\n}\n");
}

static int cmd_plan(int argc, char **argv)
{
    plan_args a;
    plan_job j;
    int rc = parse_plan(argc, argv, &a);
    if (rc) return rc;
    if (a.help) {
        plan_usage(stdout);
        return RC_OK;
    }
    memset(&j, 0, sizeof j);
    j.args = &a;
    rc = run_plan(&a, &j);
    if (!rc) rc = write_outputs(&a, &j);
    if (!rc) (a.json ? print_json : print_summary)(&a, &j);
    job_free(&j);
    return rc;
}

/* ---------------------------------------------------------------- main */

typedef struct command {
    const char *name, *summary;
    int (*run)(int argc, char **argv); /* argv[0] is the command's name */
} command;

static const command COMMANDS[] = {
    {"plan", "plan adaptive layers for a mesh or a metric profile", cmd_plan},
    {"slice", "plan a model and write its layer masks as a printable job", cmd_slice},
    {"orient", "search the build directions for the fewest layers and least error", cmd_orient},
    {"saliency", "per-face weights from mesh saliency, and the mesh coloured by them", cmd_saliency},
    {"print", "print a model or a job on a printer running the adaslice firmware", cmd_print},
};
enum { COMMAND_COUNT = sizeof COMMANDS / sizeof *COMMANDS };

static void usage(FILE *f)
{
    int i;
    fputs("usage: adaslice COMMAND [options]\n"
          "       adaslice --help | --version\n"
          "\n"
          "commands:\n", f);
    for (i = 0; i < COMMAND_COUNT; i++) fprintf(f, "  %-10s %s\n", COMMANDS[i].name, COMMANDS[i].summary);
    fputs("\n'adaslice COMMAND --help' lists the command's options.\n", f);
}

int main(int argc, char **argv)
{
    int i, rc;
    if (argc < 2) {
        usage(stderr);
        return RC_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(stdout);
        rc = RC_OK;
    } else if (!strcmp(argv[1], "--version")) {
        printf("adaslice %s\n", ADASLICE_VERSION);
        rc = RC_OK;
    } else {
        for (i = 0; i < COMMAND_COUNT && strcmp(argv[1], COMMANDS[i].name); i++) {}
        if (i == COMMAND_COUNT)
            return complain(RC_USAGE, "unknown %s %s (see adaslice --help)",
                            argv[1][0] == '-' ? "option" : "command", argv[1]);
        rc = COMMANDS[i].run(argc - 1, argv + 1);
    }
    /* a full disk or closed pipe on stdout is a failure, not a silent success */
    if (fflush(stdout) != 0 || ferror(stdout)) return complain(RC_FAIL, "cannot write standard output: %s", strerror(errno));
    return rc;
}
