/* The plan job of plan, slice, print and orient: see plan_job.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* getline */
#endif
#include "plan_job.h"
#include "model.h"
#include "options.h"
#include "output.h"
#include "report.h"
#include "search.h"
#include "svg.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
const char *const MAPPING_NAMES[] = {"linear", "exp", "step"};

/* "[0.002]" from ADASLICE_DEFAULT_BIN: the help shows the library's defaults */
#define DEFAULT_OF(x) DEFAULT_TEXT(x)
#define DEFAULT_TEXT(x) "[" #x "]"
enum { FOR_ANY = FOR_PLAN | FOR_SLICE | FOR_ORIENT | FOR_PRINT };

/* The plan options' help, each entry with the commands that take it and use it:
   orient writes no plan files, profiles exactly and unweighted; print plans
   the optimal way, as the printer does, and writes no plan files. */
static const struct plan_help { unsigned commands; const char *text; } PLAN_HELP[] = {
    {FOR_ANY, "input\n"},
    {FOR_PLAN, "  --profile FILE      plan this profile instead of a MODEL: one value per line\n"
               "                      (bins of --bin mm), or CSV z,phi as --profile-out\n"
               "                      writes it: the value last, z first, the bin centres in\n"
               "                      mm, evenly spaced, which give the bin\n"},
    {FOR_ANY, "  --scale S           multiply the model's coordinates by S (metres: 1000)\n"},
    {FOR_ANY, "profile\n"},
    {FOR_ANY, "  --metric NAME       cusp, roughness, area or volume             [cusp]\n"},
    {FOR_ANY, "  --bin MM            bin size                                    " DEFAULT_OF(ADASLICE_DEFAULT_BIN) "\n"},
    {FOR_PLAN | FOR_SLICE | FOR_PRINT,
              "  --sampler NAME      exact (from the triangles) or ldi (the\n"
              "                      paper's sampling by rays along x, y, z)     [exact]\n"
              "  --res R             ldi: pixels across the largest extent       "
              DEFAULT_OF(ADASLICE_DEFAULT_RESOLUTION) "\n"
              "  --orient D          turn the part so direction D points up: X,Y,Z, or best\n"
              "                      (the best of 1000, as adaslice orient finds it)\n"},
    {FOR_ANY, "plan\n"},
    {FOR_PLAN | FOR_SLICE,
              "  --method NAME       optimal, greedy, finest, coarsest or\n"
              "                      curvature (thickness from mean curvature)   [optimal]\n"
              "  --mapping NAME      curvature: linear, exp or step              [linear]\n"},
    {FOR_ORIENT, "  --method NAME       optimal, greedy, finest or coarsest         [optimal]\n"},
    {FOR_ANY, "  --eps E             allowed error per layer (mm; area: none;\n"
              "                      volume: mm^3)                               " DEFAULT_OF(ADASLICE_DEFAULT_EPS) "\n"
              "  --tmin MM           thinnest layer                              " DEFAULT_OF(ADASLICE_DEFAULT_TMIN) "\n"
              "  --tmax MM           thickest layer                              " DEFAULT_OF(ADASLICE_DEFAULT_TMAX) "\n"},
    {FOR_PLAN | FOR_SLICE | FOR_ORIENT,
              "  --uniform T         every layer T mm (--method finest --tmin T --tmax T)\n"},
    {FOR_ANY, "  --sharp T           a plane at each phi jump above T; 0: off    " DEFAULT_OF(ADASLICE_DEFAULT_SHARP) "\n"
              "  --budget K          at most K layers, with the smallest eps that allows it\n"},
    {FOR_PLAN | FOR_SLICE | FOR_ORIENT, "output\n"},
    {FOR_PLAN | FOR_SLICE,
              "  --out FILE          the plan as CSV: layer,z_bottom,z_top,thickness,error\n"
              "  --profile-out FILE  the profile as CSV: z,phi (z: bin centre)\n"
              "  --plot FILE         SVG figure of the profile and the layer thickness\n"},
    {FOR_PLAN | FOR_ORIENT, "  --json              print a JSON object instead of the summary\n"},
    {FOR_PLAN, "  --compare           plan coarsest, optimal, greedy, finest and (for a MODEL)\n"
               "                      curvature on the same profile and print them as in\n"
               "                      the paper's Table 3, with print times, and what optimal\n"
               "                      saves against the thickest uniform layers no worse\n"},
    {FOR_ANY, "Heights are in mm from the part's bottom.\n"},
};

void plan_options_usage(FILE *f, unsigned command)
{
    size_t i;
    for (i = 0; i < sizeof PLAN_HELP / sizeof *PLAN_HELP; i++)
        if (PLAN_HELP[i].commands & command) fputs(PLAN_HELP[i].text, f);
    if (command != FOR_ORIENT) weights_usage(f, 1);
}

/* --orient best, or a direction X,Y,Z that is not zero */
static int orient_option(int argc, char **argv, int *i, plan_args *a)
{
    const char *v = *i + 1 < argc ? argv[*i + 1] : NULL;
    double *d = a->orient_up;
    int rc;
    if (v && !strcmp(v, "best")) { ++*i; a->orient = ORIENT_BEST; return RC_OK; }
    if ((rc = numbers_option(argc, argv, i, ',', 3, "best or a direction X,Y,Z", d))) return rc;
    if (d[0] == 0 && d[1] == 0 && d[2] == 0) return complain(RC_USAGE, "--orient %s: the direction has no length", argv[*i]);
    a->orient = ORIENT_GIVEN;
    return RC_OK;
}

int parse_plan(int argc, char **argv, plan_args *a)
{
    int i, rc = RC_OK, metric = ADASLICE_METRIC_CUSP, method = -1, sampler = 0, bounds = 0;
    double uniform = 0;
    memset(a, 0, sizeof *a);
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
        else if (!strcmp(o, "--tmin")) { rc = number_option(argc, argv, &i, 0, &a->tmin); bounds = 1; }
        else if (!strcmp(o, "--tmax")) { rc = number_option(argc, argv, &i, 0, &a->tmax); bounds = 1; }
        else if (!strcmp(o, "--uniform")) rc = number_option(argc, argv, &i, 0, &uniform);
        else if (!strcmp(o, "--scale")) rc = number_option(argc, argv, &i, 0, &a->scale);
        else if (!strcmp(o, "--sharp")) rc = number_option(argc, argv, &i, 1, &a->sharp);
        else if (!strcmp(o, "--budget")) rc = count_option(argc, argv, &i, UINT32_MAX, &a->budget);
        else if (!strcmp(o, "--res")) rc = count_option(argc, argv, &i, 65536, &a->resolution);
        else if (!strcmp(o, "--orient")) rc = orient_option(argc, argv, &i, a);
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
    if (uniform) {
        if (method >= 0 || bounds) return complain(RC_USAGE, "--uniform %g sets the method and both bounds: leave out --method, --tmin and --tmax", uniform);
        method = ADASLICE_METHOD_FINEST;
        a->tmin = a->tmax = uniform;
    }
    a->metric = (adaslice_metric)metric;
    a->method = method < 0 ? ADASLICE_METHOD_OPTIMAL : (adaslice_method)method;
    a->sampler = sampler;
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
    if (a->method == ADASLICE_METHOD_CURVATURE && a->orient == ORIENT_BEST)
        return complain(RC_USAGE, "--orient best searches with the library's methods, not curvature");
    if (a->tmin > a->tmax) return complain(RC_USAGE, "--tmin %g is larger than --tmax %g", a->tmin, a->tmax);
    if (a->budget && a->method != ADASLICE_METHOD_OPTIMAL)
        return complain(RC_USAGE, "--budget works with --method optimal only, not %s", METHOD_NAMES[a->method]);
    return RC_OK;
}


/* k per bin of the profile of `mesh`, for the curvature method; RC_OK or a
   complaint made. */
static int curvature_of(const adaslice_mesh *mesh, const adaslice_profile *profile, double **kappa)
{
    adaslice_error e;
    *kappa = (double *)malloc(profile->bin_count * sizeof **kappa);
    if (!*kappa) return complain(RC_FAIL, "out of memory for the curvature of %zu bin%s", profile->bin_count,
                                 plural(profile->bin_count));
    if (adaslice_curvature_profile(mesh, profile, NULL, *kappa, &e) != ADASLICE_OK) {
        free(*kappa);
        *kappa = NULL;
        return library_error(&e);
    }
    return RC_OK;
}

static int profile_model(const plan_args *a, plan_job *j)
{
    adaslice_profile_options po;
    adaslice_mesh mesh;
    adaslice_error err;
    adaslice_result r;
    double t0 = now_ms(), ms_weights;
    float *weights = NULL;
    int rc;

    if ((rc = model_load_timed(a->model, a->scale, &mesh, &j->repair, &j->ms_repair)) != RC_OK) return rc;
    j->ms_load = now_ms() - t0 - j->ms_repair;
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
        if (a->orient == ORIENT_BEST) {
            adaslice_direction_score *scores = NULL;
            size_t minima[SEARCH_MINIMA + 1], count = 0;
            rc = plan_orient_search(a, &mesh, 1000, 0.5, &scores, minima, &count);
            if (!rc && !count) rc = complain(RC_FAIL, "no build direction has a feasible plan");
            if (rc) { free(scores); free(weights); adaslice_mesh_free(&mesh); return rc; }
            memcpy(j->up, scores[minima[0]].direction, sizeof j->up);
            free(scores);
        } else {
            memcpy(j->up, a->orient_up, sizeof j->up);
        }
        /* by the largest component first, so that 1e308,1e308,1e308 does not overflow */
        len = fabs(j->up[0]) > fabs(j->up[1]) ? fabs(j->up[0]) : fabs(j->up[1]);
        if (fabs(j->up[2]) > len) len = fabs(j->up[2]);
        j->up[0] /= len; j->up[1] /= len; j->up[2] /= len;
        len = sqrt(j->up[0] * j->up[0] + j->up[1] * j->up[1] + j->up[2] * j->up[2]);
        j->up[0] /= len; j->up[1] /= len; j->up[2] /= len;
        adaslice_rotation_to_z(j->up, r);
        adaslice_mesh_rotate(&mesh, r);
    }
    j->triangles = mesh.triangle_count;
    j->degenerate = mesh.degenerate_dropped;
    j->format = mesh.format;
    if (j->loaded && (rc = j->loaded(j->loaded_ctx, &mesh)) != RC_OK) {
        free(weights);
        adaslice_mesh_free(&mesh);
        return rc;
    }

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
        rc = curvature_of(&mesh, &j->profile, &j->kappa);
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

/* The z column of a profile so far: the first, second and latest z, and the
   lines of the first two. */
typedef struct z_column { double first, second, last; size_t first_line, second_line; } z_column;

/* The z of value `index`: the first two set the step, which every later one
   keeps to 1 % (a column printed with %.9g is exact to far less). */
static int z_column_add(z_column *c, const char *path, size_t line, size_t index, double z)
{
    double step = c->second - c->first;
    if (index == 0) {
        c->first = c->last = z;
        c->first_line = line;
        return RC_OK;
    }
    if (!(z > c->last)) return complain(RC_FAIL, "%s:%zu: z %g is not above the line before's, %g", path, line, z, c->last);
    if (index == 1) {
        c->second = z;
        c->second_line = line;
    } else if (fabs(z - c->last - step) > 0.01 * step) {
        return complain(RC_FAIL, "%s:%zu: z %g is %g mm above the line before, not %g as from line %zu to %zu: "
                                 "the z column must be evenly spaced", path, line, z, z - c->last, step,
                        c->first_line, c->second_line);
    }
    c->last = z;
    return RC_OK;
}

/* The bin of an evenly spaced z column of n values, to six digits: the %.9g
   centres --profile-out writes give it to about nine, and 0.0099999999 for
   0.01 would change the bins a layer may take (ceil(tmin/b)). */
static double z_column_bin(const z_column *c, size_t n)
{
    char six[32];
    snprintf(six, sizeof six, "%.6g", (c->last - c->first) / (double)(n - 1));
    return strtod(six, NULL);
}

/* A z in the first column, before the first comma: 1 if there is one. */
static int z_field(const char *s, const char *comma, double *z)
{
    char *end;
    *z = strtod(s, &end);
    while (end < comma && (*end == ' ' || *end == '\t')) end++;
    return end != s && end == comma && isfinite(*z);
}

/* One value per line, or CSV with the value last and, in two or more columns, z
   first: the bin centres as --profile-out writes them, which give the bin and
   z0. Blank lines and # comments are skipped, and so is a first line that is
   not a number (a header). */
static int read_profile(const plan_args *a, plan_job *j)
{
    const char *path = a->profile;
    FILE *f = fopen(path, "r");
    char *line = NULL, q[QUOTE_SIZE];
    size_t line_cap = 0, lineno = 0, n = 0, cap = 0, first_line = 0;
    double *phi = NULL, t0 = now_ms(), bin = a->bin ? a->bin : ADASLICE_DEFAULT_BIN;
    z_column zc = {0, 0, 0, 0, 0};
    int rc = RC_OK, first = 1, has_z = 0;

    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    while (!rc && getline(&line, &line_cap, f) != -1) {
        char *s = trim(line), *comma = strchr(s, ','), *field, *end;
        double v, z = 0;
        lineno++;
        if (!*s || *s == '#') continue;
        field = comma ? trim(strrchr(s, ',') + 1) : s;
        v = strtod(field, &end);
        if (end == field || *end || (comma && !z_field(s, comma, &z))) {
            if (!first) rc = complain(RC_FAIL, "%s:%zu: not a number: '%s'", path, lineno, quote_text(q, s, strlen(s)));
        } else if (!isfinite(v) || v < 0) {
            rc = complain(RC_FAIL, "%s:%zu: '%s': profile values must be finite and >= 0", path, lineno,
                          quote_text(q, s, strlen(s)));
        } else if (n && has_z != (comma != NULL)) {
            rc = complain(RC_FAIL, "%s:%zu: '%s' has %s z column, unlike line %zu", path, lineno,
                          quote_text(q, s, strlen(s)), comma ? "a" : "no", first_line);
        } else if (comma && (rc = z_column_add(&zc, path, lineno, n, z))) {
            /* z_column_add said why */
        } else if (!push(&phi, &n, &cap, v)) {
            rc = complain(RC_FAIL, "%s: out of memory after %zu value%s", path, n, plural(n));
        } else if (n == 1) {
            first_line = lineno;
            has_z = comma != NULL;
        }
        first = 0;
    }
    if (!rc && ferror(f)) rc = complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    if (!rc && !n) rc = complain(RC_FAIL, "%s: no profile values", path);
    if (!rc && has_z && n > 1) {
        double column = z_column_bin(&zc, n);
        if (!a->bin) bin = column;
        else if (fabs(column - a->bin) > 1e-6 * a->bin)
            rc = complain(RC_USAGE, "%s:%zu: the z column has bins of %g mm, but --bin is %g mm", path, zc.second_line,
                          column, a->bin);
    }
    fclose(f);
    free(line);
    j->ms_load = now_ms() - t0;
    if (rc) {
        free(phi);
        return rc;
    }
    j->profile.metric = a->metric;
    j->profile.bin_count = n;
    j->profile.bin = bin;
    j->profile.z0 = has_z ? zc.first - bin / 2 : 0;
    j->profile.height = n * bin;
    j->profile.phi = phi;
    return RC_OK;
}

int plan_orient_search(const plan_args *a, const adaslice_mesh *mesh, size_t count, double alpha,
                       adaslice_direction_score **scores, size_t *minima, size_t *minima_count)
{
    adaslice_profile_options po;
    adaslice_plan_options pl;
    memset(&po, 0, sizeof po);
    po.metric = a->metric;
    po.bin = a->bin;
    plan_options_of(a, a->method, &pl);
    return orient_search(mesh, &po, &pl, count, alpha, scores, minima, minima_count);
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
    o.curvature = j->kappa;
    o.mapping = (adaslice_mapping)a->mapping;
    r = adaslice_plan_profile(&j->profile, &o, &j->plan[method], &j->why[method]);
    j->why[method].result = r;
    j->planned[method] = 1;
    return r;
}

int plan_uniform_no_worse(const adaslice_profile *profile, const adaslice_plan *than, adaslice_plan *out)
{
    uint32_t k;
    /* a thinner uniform plan can have a worse layer (its planes fall
       elsewhere), so thicknesses are tried from the thickest down, not bisected */
    for (k = than->bins_max; k >= than->bins_min && k > 0; k--) {
        adaslice_plan_options o;
        memset(&o, 0, sizeof o);
        o.method = ADASLICE_METHOD_FINEST;
        o.tmin = o.tmax = k * profile->bin;
        o.eps = than->eps;
        if (adaslice_plan_profile(profile, &o, out, NULL) != ADASLICE_OK) continue;
        if (out->worst_error <= than->worst_error) return 1;
        adaslice_plan_free(out);
    }
    return 0;
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
    if (a->compare && j->planned[ADASLICE_METHOD_OPTIMAL] && j->why[ADASLICE_METHOD_OPTIMAL].result == ADASLICE_OK)
        j->uniform_found = plan_uniform_no_worse(&j->profile, &j->plan[ADASLICE_METHOD_OPTIMAL], &j->uniform);
    return RC_OK;
}

void job_free(plan_job *j)
{
    int m;
    for (m = 0; m < METHOD_COUNT; m++)
        if (j->planned[m] && j->why[m].result == ADASLICE_OK) adaslice_plan_free(&j->plan[m]);
    if (j->uniform_found) adaslice_plan_free(&j->uniform);
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

int check_plan_outputs(const plan_args *a)
{
    int rc = output_check("--out", a->out);
    if (!rc) rc = output_check("--profile-out", a->profile_out);
    if (!rc) rc = output_check("--plot", a->plot);
    return rc;
}

int write_outputs(const plan_args *a, const plan_job *j)
{
    if (a->out && write_atomic(a->out, write_plan_csv, j)) return RC_FAIL;
    if (a->profile_out && write_atomic(a->profile_out, write_profile_csv, j)) return RC_FAIL;
    if (a->plot && write_atomic(a->plot, write_plot, j)) return RC_FAIL;
    return RC_OK;
}

void plan_changes_line(const adaslice_plan *p, double bin, char *out, size_t cap)
{
    size_t k, n = 0, shown = 6, moved = 0, dropped;
    int why[2] = {0, 0};
    *out = 0;
    if (!p->plane_changes) return;
    for (k = 0; k < p->plane_changes; k++) {
        moved += p->changes[k].placed != 0;
        why[p->changes[k].infeasible != 0] = 1;
    }
    dropped = p->plane_changes - moved;
    n += (size_t)snprintf(out, cap, "the sharp-change pre-pass %s", moved ? "moved " : "dropped ");
    if (moved) n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "%zu plane%s%s", moved, plural(moved), dropped ? " and dropped " : "");
    if (dropped) n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "%zu plane%s", dropped, plural(dropped));
    n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, " so that eps %g stays feasible:", p->eps);
    for (k = 0; k < p->plane_changes && k < shown; k++) {
        const adaslice_plane_change *c = &p->changes[k];
        char to[40];
        if (c->placed) snprintf(to, sizeof to, "to %g mm", c->placed * bin);
        else snprintf(to, sizeof to, "dropped");
        n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "%s z = %g mm %s (%s)", k ? "," : "", c->wanted * bin, to,
                              c->infeasible ? "infeasible" : "cost");
    }
    if (p->plane_changes > shown) n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, ", and %zu more", p->plane_changes - shown);
    if (why[1]) n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "; infeasible: with a plane there no plan keeps every layer within eps");
    if (why[0]) n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "; cost: it would add more than one layer");
    if (n >= cap && cap > 4) memcpy(out + cap - 4, "...", 4);
}
