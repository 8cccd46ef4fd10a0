/* The plan job of plan, slice, print and orient: see plan_job.h. */
#include "plan_job.h"
#include "model.h"
#include "profile_csv.h"
#include "options.h"
#include "output.h"
#include "pages.h"
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
    {FOR_PLAN, "  --memory MB         the most the profile may take   [half the machine's memory]\n"},
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
    const char *cmd = argv[0]; /* the command run: its messages name it */
    int i, rc = RC_OK, metric = ADASLICE_METRIC_CUSP, method = -1, sampler = 0, bounds = 0, eps_given = 0;
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
        else if (!strcmp(o, "--eps")) { rc = number_option(argc, argv, &i, 0, &a->eps); eps_given = 1; }
        else if (!strcmp(o, "--tmin")) { rc = number_option(argc, argv, &i, 0, &a->tmin); bounds = 1; }
        else if (!strcmp(o, "--tmax")) { rc = number_option(argc, argv, &i, 0, &a->tmax); bounds = 1; }
        else if (!strcmp(o, "--uniform")) rc = number_option(argc, argv, &i, 0, &uniform);
        else if (!strcmp(o, "--scale")) rc = number_option(argc, argv, &i, 0, &a->scale);
        else if (!strcmp(o, "--sharp")) rc = number_option(argc, argv, &i, 1, &a->sharp);
        else if (!strcmp(o, "--budget")) rc = count_option(argc, argv, &i, UINT32_MAX, &a->budget);
        else if (!strcmp(o, "--res")) rc = count_option(argc, argv, &i, 65536, &a->resolution);
        else if (!strcmp(o, "--memory")) rc = memory_option(argc, argv, &i, &a->memory_mb);
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
        else return complain(RC_USAGE, "unknown option %s (see adaslice %s --help)", o, cmd);
    }
    if (rc || (rc = weights_check(&a->weights))) return rc;
    {
        /* heights past these are no layer: a bin of 1e308 mm made the height inf and the plan's rows NaN */
        const char *const names[] = {"--bin", "--tmin", "--tmax", "--uniform"};
        const double values[] = {a->bin, a->tmin, a->tmax, uniform};
        int k;
        for (k = 0; k < 4; k++)
            if (values[k] > PLAN_LAYER_MAX_MM)
                return complain(RC_USAGE, "%s %g mm is thicker than any layer (%g mm at most)", names[k], values[k], (double)PLAN_LAYER_MAX_MM);
    }
    if (a->budget && eps_given && !a->compare) /* --compare's other methods take --eps */
        return complain(RC_USAGE, "--budget %zu finds the least eps for that many layers: leave out --eps %g", a->budget,
                        a->eps);
    if (!a->memory_mb) a->memory_mb = machine_memory_mb() / 2;
    if (uniform) {
        if (method >= 0 || bounds) return complain(RC_USAGE, "--uniform %g sets the method and both bounds: leave out --method, --tmin and --tmax", uniform);
        method = ADASLICE_METHOD_FINEST;
        a->tmin = a->tmax = uniform;
    }
    a->metric = (adaslice_metric)metric;
    a->method = method < 0 ? ADASLICE_METHOD_OPTIMAL : (adaslice_method)method;
    a->sampler = sampler;
    if (a->resolution && !a->sampler) return complain(RC_USAGE, "--res applies to --sampler ldi");
    if (option_given(argc, argv, "--mapping") && a->method != ADASLICE_METHOD_CURVATURE && !a->compare)
        return complain(RC_USAGE, "--mapping applies to --method curvature (and --compare)");
    if (strcmp(cmd, "plan") && a->profile)
        return complain(RC_USAGE, "%s takes a MODEL, not --profile (adaslice plan --profile plans a profile)", cmd);
    if (!a->model && !a->profile)
        return complain(RC_USAGE, "%s needs %s", cmd, !strcmp(cmd, "plan") ? "a MODEL or --profile FILE"
                                                      : !strcmp(cmd, "print") ? "a MODEL or a JOBDIR" : "a MODEL");
    if (a->model && a->profile)
        return complain(RC_USAGE, "plan takes a MODEL or --profile FILE, not both (%s and --profile %s)",
                        a->model, a->profile);
    if (a->profile && (a->scale || a->orient || option_given(argc, argv, "--sampler")))
        return complain(RC_USAGE, "%s applies to a MODEL, not to --profile (a profile is sampled already)",
                        a->scale ? "--scale" : a->orient ? "--orient" : "--sampler");
    if (a->profile && weights_given(&a->weights))
        return complain(RC_USAGE, "--saliency, --weights and --weight weight a MODEL's faces, not --profile");
    if (a->profile && a->method == ADASLICE_METHOD_CURVATURE)
        return complain(RC_USAGE, "--method curvature needs a MODEL's curvature, not --profile");
    if (a->method == ADASLICE_METHOD_CURVATURE && a->orient == ORIENT_BEST)
        return complain(RC_USAGE, "--orient best searches with the library's methods, not curvature");
    if (a->tmin > a->tmax) return complain(RC_USAGE, "--tmin %g is larger than --tmax %g", a->tmin, a->tmax);
    outputs_add_input(a->model);
    outputs_add_input(a->profile);
    outputs_add_input(a->weights.file);
    if (a->budget && a->method != ADASLICE_METHOD_OPTIMAL)
        return complain(RC_USAGE, "--budget works with --method optimal only, not %s",
                        uniform ? "--uniform (one plan, no choice)" : METHOD_NAMES[a->method]);
    /* print says itself that it plans the optimal way; --sharp 0 is what the others do */
    if (a->sharp > 0 && option_given(argc, argv, "--sharp") && a->method != ADASLICE_METHOD_OPTIMAL && !a->compare &&
        strcmp(cmd, "print"))
        return complain(RC_USAGE, "--sharp applies to --method optimal (and --compare), not %s",
                        uniform ? "--uniform" : METHOD_NAMES[a->method]);
    return RC_OK;
}


const char *plan_source(const plan_args *a) { return a->model ? a->model : a->profile; }

void units_hint(double tall_mm, char *out, size_t size)
{
    *out = 0;
    if (tall_mm > UNITS_TALL_MM)
        snprintf(out, size, "; a model in micrometres? --scale 0.001 reads it in millimetres, %g mm tall",
                 tall_mm / 1000);
}

/* More samples than this the LDIs do not take: about 12 s of rasterising
   (3.6e8 samples a second); a mesh of 200,000 facets at the default
   resolution takes under 1e8, one whose facets lie thousands deep (a fan
   wound round and round) 1e11. */
#define LDI_SAMPLES_LIMIT 4e9

/* RC_OK when the profile of `mesh` fits --memory and, sampled, the LDIs'
   limit of work; else a complaint naming the figures: said before any work.
   warn_units: a part over a metre tall that fits is warned about here (slice
   and print check it against the printer). */
static int profile_fits(const plan_args *a, const adaslice_mesh *mesh, const double lo[3], const double hi[3],
                        const adaslice_profile_options *po, int warn_units)
{
    adaslice_profile_cost c;
    adaslice_error err;
    double bin = po->bin ? po->bin : ADASLICE_DEFAULT_BIN;
    char need[32], limit[32], hint[160];
    if (adaslice_profile_estimate(mesh, po, a->sampler, &c, &err) != ADASLICE_OK) return library_error_in(a->model, &err);
    units_hint(hi[2] - lo[2], hint, sizeof hint);
    if (c.bytes > a->memory_mb * 1e6)
        return complain(RC_FAIL, "%s: its profile needs %s (%.0f bins of %g mm over %g mm), more than --memory %s%s; "
                                 "or a larger --bin",
                        a->model, size_text(c.bytes, need), ceil((hi[2] - lo[2]) / bin), bin, hi[2] - lo[2],
                        size_text(a->memory_mb * 1e6, limit), hint);
    if (a->sampler && c.samples > LDI_SAMPLES_LIMIT)
        return complain(RC_FAIL, "%s: its LDIs would take %.2g samples (%zu facets, on average %.0f pixels each), "
                                 "more than %.2g; --sampler exact, or a lower --res",
                        a->model, c.samples, mesh->triangle_count, c.samples / (double)mesh->triangle_count,
                        LDI_SAMPLES_LIMIT);
    if (warn_units && *hint)
        warn("%s: the part is %g mm tall, its profile %s%s", a->model, hi[2] - lo[2],
             size_text(c.bytes, need), hint);
    return RC_OK;
}

/* k per bin of the profile of `mesh`, for the curvature method; RC_OK or a
   complaint made. */
static int curvature_of(const char *model, const adaslice_mesh *mesh, const adaslice_profile *profile, double **kappa)
{
    adaslice_error e;
    *kappa = (double *)malloc(profile->bin_count * sizeof **kappa);
    if (!*kappa) return complain(RC_FAIL, "%s: out of memory for the curvature of %zu bin%s", model, profile->bin_count,
                                 plural(profile->bin_count));
    if (adaslice_curvature_profile(mesh, profile, NULL, *kappa, &e) != ADASLICE_OK) {
        free(*kappa);
        *kappa = NULL;
        return library_error_in(model, &e);
    }
    return RC_OK;
}

static adaslice_result profile_with(const plan_args *a, const adaslice_mesh *mesh, adaslice_profile_options *po,
                                    const float *weights, adaslice_profile *out, adaslice_error *err)
{
    po->weights = weights;
    return a->sampler ? adaslice_profile_sampled(mesh, po, out, err) : adaslice_profile_exact(mesh, po, out, err);
}

/* --hybrid: the planar profile (the user's weights only), then *weights
   (made all 1 if there were none) turned into the hybrid weights the job's
   profile is made with, and the walls' profile (contoured faces weighing 0). */
static int profile_planar_parts(const plan_args *a, plan_job *j, const adaslice_mesh *mesh, adaslice_profile_options *po,
                                float **weights)
{
    adaslice_hybrid_options ho = *a->hybrid;
    adaslice_error err;
    float *walls;
    size_t t, n = mesh->triangle_count;
    if (!*weights && (*weights = (float *)malloc(n * sizeof **weights)))
        for (t = 0; t < n; t++) (*weights)[t] = 1;
    j->residual = (float *)malloc(n * sizeof *j->residual);
    walls = (float *)malloc(n * sizeof *walls);
    if (!*weights || !j->residual || !walls) {
        free(walls);
        return complain(RC_FAIL, "out of memory for the weights of %zu triangle%s", n, plural(n));
    }
    ho.tmin = a->tmin;
    ho.tmax = a->tmax;
    if (profile_with(a, mesh, po, *weights, &j->planar_profile, &err) != ADASLICE_OK ||
        adaslice_hybrid_faces(mesh, &ho, j->residual, *weights, &j->hybrid, &err) != ADASLICE_OK) {
        free(walls);
        if (j->planar_profile.phi) adaslice_profile_free(&j->planar_profile);
        return library_error_in(plan_source(a), &err);
    }
    /* faces left planar keep their weights */
    for (t = 0; t < n; t++) walls[t] = j->residual[t] < 0 ? (*weights)[t] : 0;
    if (profile_with(a, mesh, po, walls, &j->walls_profile, &err) != ADASLICE_OK) {
        free(walls);
        adaslice_profile_free(&j->planar_profile);
        return library_error_in(plan_source(a), &err);
    }
    free(walls);
    return RC_OK;
}

/* The profile's bar, once it has taken a second: a quick one says nothing. */
typedef struct profile_bar { progress bar; double started; int shown; } profile_bar;

static void profile_progress(void *user, double done)
{
    profile_bar *p = (profile_bar *)user;
    if (!p->shown && now_ms() - p->started < 1000) return;
    p->shown = 1;
    progress_show(&p->bar, (size_t)(100 * done), 100, "% of the profile", NULL);
}

static void *run_beside(void *arg)
{
    plan_job *j = (plan_job *)arg;
    j->beside_rc = j->beside(j->beside_ctx);
    return NULL;
}

/* j->beside started, or run here when no thread is to be had. */
static void beside_start(plan_job *j)
{
    if (!j->beside || !j->keep_mesh) return;
    j->beside_running = output_thread_start(&j->beside_thread, run_beside, j) == 0;
    if (!j->beside_running) run_beside(j);
}

static int beside_join(plan_job *j)
{
    if (j->beside_running) pthread_join(j->beside_thread, NULL);
    j->beside_running = 0;
    return j->beside_rc;
}

/* A failure once beside may have started on the mesh: a kept mesh stays
   in j->mesh for job_free (what beside started may still read it until its
   caller joins that), any other is dropped. */
static int drop_mesh(plan_job *j, adaslice_mesh *mesh, float *weights, int rc)
{
    beside_join(j);
    free(weights);
    if (!j->keep_mesh) adaslice_mesh_free(mesh);
    return rc;
}

static int profile_model(const plan_args *a, plan_job *j)
{
    profile_bar bar;
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
    if ((rc = weights_for_plan(&a->weights, a->model, &mesh, &weights)) != RC_OK) {
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
    j->format = mesh.format;
    adaslice_mesh_bounds(&mesh, j->lo, j->hi);
    if (j->loaded && (rc = j->loaded(j->loaded_ctx, &mesh, j->lo, j->hi)) != RC_OK) {
        free(weights);
        adaslice_mesh_free(&mesh);
        return rc;
    }
    if (j->keep_mesh) j->mesh = mesh; /* where it stays: beside keeps pointers to it */
    beside_start(j);

    memset(&po, 0, sizeof po);
    po.metric = a->metric;
    po.bin = a->bin;
    po.allocator = pages_allocator();
    po.resolution = (int)a->resolution;
    po.weights = weights;
    if ((rc = profile_fits(a, &mesh, j->lo, j->hi, &po, !j->loaded)) != RC_OK) return drop_mesh(j, &mesh, weights, rc);
    t0 = now_ms();
    memset(&bar, 0, sizeof bar);
    bar.started = t0;
    po.progress = profile_progress;
    po.progress_user = &bar;
    if (a->hybrid && (rc = profile_planar_parts(a, j, &mesh, &po, &weights)) != RC_OK)
        return drop_mesh(j, &mesh, weights, rc);
    r = profile_with(a, &mesh, &po, weights, &j->profile, &err);
    free(weights);
    if (r == ADASLICE_OK && (a->method == ADASLICE_METHOD_CURVATURE || a->compare))
        rc = curvature_of(a->model, &mesh, &j->profile, &j->kappa);
    j->ms_profile = now_ms() - t0 + ms_weights;
    if (!j->keep_mesh) adaslice_mesh_free(&mesh); /* else j->mesh already */
    if (r != ADASLICE_OK) return library_error_in(a->model, &err);
    j->profiled = 1;
    return rc;
}

/* --profile FILE in place of a model. */
static int read_profile(const plan_args *a, plan_job *j)
{
    double t0 = now_ms();
    int rc = profile_csv_read(a->profile, a->metric, a->bin, a->memory_mb * 1e6, &j->profile);
    j->ms_load = now_ms() - t0;
    return rc;
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
    return orient_search(a->model, mesh, &po, &pl, count, alpha, a->memory_mb * 1e6, scores, minima, minima_count);
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

/* --hybrid: the printed surface's worst error (walls by the plan's cusp,
   contoured faces by their residual) and the optimal planar plan held to it,
   which may need layers thinner than tmin (then planar_why says so). */
static int plan_planar_same_error(const plan_args *a, plan_job *j)
{
    const adaslice_plan *h = &j->plan[a->method];
    adaslice_plan_options o;
    adaslice_result r;
    size_t k;
    j->walls_worst = 0;
    for (k = 0; k < h->layer_count; k++) {
        double e = adaslice_layer_error(&j->walls_profile, h->planes[k], h->planes[k + 1]);
        if (e > j->walls_worst) j->walls_worst = e;
    }
    j->printed_worst = j->walls_worst > j->hybrid.residual ? j->walls_worst : j->hybrid.residual;
    plan_options_of(a, ADASLICE_METHOD_OPTIMAL, &o);
    o.eps = j->printed_worst > 0 ? j->printed_worst : 1e-12; /* 0 would mean the default */
    o.budget = 0;
    r = adaslice_plan_profile(&j->planar_profile, &o, &j->planar, &j->planar_why);
    j->planar_why.result = r;
    if (r == ADASLICE_ERR_INFEASIBLE) {
        /* the best planar layers can do, which is still worse */
        adaslice_error e;
        o.method = ADASLICE_METHOD_FINEST;
        r = adaslice_plan_profile(&j->planar_profile, &o, &j->planar, &e);
        if (r != ADASLICE_OK) return library_error_in(plan_source(a), &e);
        j->planar_finest = 1;
    } else if (r != ADASLICE_OK) {
        return library_error_in(plan_source(a), &j->planar_why);
    }
    j->planar_found = 1;
    return RC_OK;
}

/* The asked plan must succeed; with --compare the others may be infeasible,
   which their row of the table then says. */
static int plan_steps(const plan_args *a, plan_job *j)
{
    double t0;
    int rc = a->model ? profile_model(a, j) : read_profile(a, j), m;
    if (rc) return rc;
    t0 = now_ms();
    if (plan_with(a, j, a->method) != ADASLICE_OK) return library_error_in(plan_source(a), &j->why[a->method]);
    j->ms_plan = now_ms() - t0;
    for (m = 0; a->compare && m < METHOD_COUNT; m++) {
        adaslice_result r;
        if (m == ADASLICE_METHOD_CURVATURE && !j->kappa) continue; /* a --profile has no curvature */
        r = j->planned[m] ? ADASLICE_OK : plan_with(a, j, (adaslice_method)m);
        if (r != ADASLICE_OK && r != ADASLICE_ERR_INFEASIBLE) return library_error_in(plan_source(a), &j->why[m]);
    }
    if (a->compare && j->planned[ADASLICE_METHOD_OPTIMAL] && j->why[ADASLICE_METHOD_OPTIMAL].result == ADASLICE_OK)
        j->uniform_found = plan_uniform_no_worse(&j->profile, &j->plan[ADASLICE_METHOD_OPTIMAL], &j->uniform);
    return a->hybrid ? plan_planar_same_error(a, j) : RC_OK;
}

int run_plan(const plan_args *a, plan_job *j)
{
    int rc = plan_steps(a, j), beside = beside_join(j);
    return rc ? rc : beside;
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
    free(j->residual);
    if (j->planar_found) adaslice_plan_free(&j->planar);
    adaslice_profile_free(&j->planar_profile);
    adaslice_profile_free(&j->walls_profile);
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
    fig.model = base_name(plan_source(a));
    fig.metric = METRICS[a->metric].label;
    fig.phi_axis = METRICS[a->metric].phi_axis;
    fig.eps_unit = METRICS[a->metric].eps_unit;
    fig.method = METHOD_NAMES[a->method];
    fig.profile = &j->profile;
    fig.plan = &j->plan[a->method];
    svg_write_plan(f, &fig);
}

int check_plan_outputs(const plan_args *a, const char *option, const char *path)
{
    const char *const options[] = {"--out", "--profile-out", "--plot", option};
    const char *const paths[] = {a->out, a->profile_out, a->plot, path};
    int rc = output_check("--out", a->out);
    if (!rc) rc = output_check("--profile-out", a->profile_out);
    if (!rc) rc = output_check("--plot", a->plot);
    return rc ? rc : output_check_distinct(options, paths, 4);
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
