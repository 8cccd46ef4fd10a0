/* adaslice plan: the fewest layers within eps for a mesh or a metric profile,
   printed as a summary (with the paper's Table 3 on request) or as JSON. */
#include "json.h"
#include "commands.h"
#include "cure.h"
#include "fdm.h"
#include "model.h"
#include "output.h"
#include "plan_job.h"
#include "report.h"
#include "formats/threemf.h"

#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

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


static void plan_usage(FILE *f)
{
    fputs("usage: adaslice plan MODEL [options]\n"
          "       adaslice plan --profile FILE [options]\n"
          "\n"
          "Finds the slicing plan with the fewest layers whose every layer error stays\n"
          "within eps (Mao et al., Adaptive Slicing Based on Efficient Profile Analysis,\n"
          "section 3.3). MODEL is a binary or ASCII STL, OBJ or PLY file in mm; +z is up.\n"
          "\n", f);
    plan_options_usage(f, FOR_PLAN);
    threemf_usage(f);
}


/* The rows of the paper's Table 3, in its order. */
static const adaslice_method TABLE3[] = {
    ADASLICE_METHOD_COARSEST, ADASLICE_METHOD_OPTIMAL, ADASLICE_METHOD_GREEDY, ADASLICE_METHOD_FINEST,
    ADASLICE_METHOD_CURVATURE};
static const char *const TABLE3_NAMES[] = {"Coarsest", "Optimal", "Greedy", "Finest", "Curvature"};
enum { TABLE3_ROWS = sizeof TABLE3 / sizeof *TABLE3 };

/* --compare's print times: slice's default exposures and motion, so that the
   Optimal row says what slice would. */
static void compare_cure(const plan_args *a, cure_args *c) { cure_typical(c, a->tmin); }

static void print_compare(const plan_args *a, const plan_job *j)
{
    const char *unit = METRICS[a->metric].eps_unit;
    const adaslice_plan *best = &j->plan[ADASLICE_METHOD_OPTIMAL], *uni = &j->uniform;
    char u[16], head[40], when[32], instead[32];
    cure_args c;
    int r;
    compare_cure(a, &c);
    snprintf(head, sizeof head, "worst error%s%s%s", *unit ? " (" : "", unit, *unit ? ")" : "");
    printf("\nTable 3: %s, %s, eps %g%s\n", base_name(plan_source(a)),
           METRICS[a->metric].label, a->eps, unit_suffix(unit, u));
    printf("%-10s %8s %18s %10s %12s\n", "method", "layers", head, "over eps", "print time");
    for (r = 0; r < TABLE3_ROWS; r++) {
        const adaslice_plan *p = &j->plan[TABLE3[r]];
        const adaslice_error *e = &j->why[TABLE3[r]];
        if (!j->planned[TABLE3[r]]) continue; /* curvature, from a --profile */
        if (e->result == ADASLICE_OK) {
            format_duration(when, sizeof when, cure_plan_seconds(&c, p));
            printf("%-10s %8zu %18.6g %10zu %12s\n", TABLE3_NAMES[r], p->layer_count, p->worst_error, p->over_eps, when);
        } else if (e->min_eps > 0)
            printf("%-10s %8s   (feasible from eps %g)\n", TABLE3_NAMES[r], "none", e->min_eps);
        else
            printf("%-10s %8s   (tmin..tmax cannot tile the height)\n", TABLE3_NAMES[r], "none");
    }
    if (j->uniform_found) {
        format_duration(when, sizeof when, cure_plan_seconds(&c, uni));
        printf("%-10s %8zu %18.6g %10zu %12s   (%g mm layers: the thickest no worse than Optimal)\n", "Uniform",
               uni->layer_count, uni->worst_error, uni->over_eps, when, uni->layers[0].thickness);
    }
    if (a->budget)
        printf("(Optimal with a budget of %zu layer%s: eps %g%s)\n", a->budget, plural(a->budget), best->eps, u);
    if (j->uniform_found) {
        double t_best = cure_plan_seconds(&c, best), t_uni = cure_plan_seconds(&c, uni);
        format_duration(when, sizeof when, t_best);
        format_duration(instead, sizeof instead, t_uni);
        printf("\nOptimal against Uniform, no worse: %zu layer%s instead of %zu (%.0f %% fewer), %s instead of %s to print: "
               "%.1f %% saved\n", best->layer_count, plural(best->layer_count), uni->layer_count,
               100 * (1 - (double)best->layer_count / uni->layer_count), when, instead, 100 * (1 - t_best / t_uni));
        printf("(print times as slice estimates them by default: %g s at %g mm on a typical resin's working curve of Dp "
               "%g mm, %zu bottom layers of %g s, a %g mm peel at %g mm/s back at %g mm/s, %g s settle)\n",
               c.cure.seconds, c.cure.thickness, c.cure.penetration, c.bottom_layers, c.bottom_exposure_s,
               c.motion.lift_mm, c.motion.lift_speed, c.motion.retract_speed, c.motion.wait_before_cure_s);
    } else if (j->planned[ADASLICE_METHOD_OPTIMAL] && j->why[ADASLICE_METHOD_OPTIMAL].result == ADASLICE_OK) {
        printf("\nNo uniform layers from %g to %g mm are as good as Optimal (worst error %g%s)\n", a->tmin, a->tmax,
               best->worst_error, u);
    }
}

/* The hybrid plan against planar layers of the same worst printed error. */
static void print_hybrid(const plan_args *a, const plan_job *j)
{
    const adaslice_hybrid_report *h = &j->hybrid;
    const adaslice_plan *p = &j->plan[a->method], *q = &j->planar;
    char when[32], instead[32];
    printf("hybrid     %zu of %zu face%s facing up within %g degrees contoured (%.6g mm^2, z %.6g to %.6g mm); "
           "%zu with the part in the nozzle's cone (%g mm), %zu whose residual costs more than their cusp\n",
           h->contoured, h->candidates, plural(h->candidates), a->hybrid->max_angle, h->area,
           h->contoured ? h->z_low - j->profile.z0 : 0, h->contoured ? h->z_high - j->profile.z0 : 0, h->blocked,
           a->hybrid->reach ? a->hybrid->reach : ADASLICE_DEFAULT_REACH, h->costly);
    printf("           residual after contour at most %.6g mm (rise clamp %.6g mm + chord at %g mm segments)\n",
           h->residual, h->clamp, a->hybrid->resolution ? a->hybrid->resolution : ADASLICE_DEFAULT_PATH_RESOLUTION);
    printf("           printed surface: worst error %.6g mm (walls %.6g mm by the plan's cusp, contoured %.6g mm)\n",
           j->printed_worst, j->walls_worst, h->residual);
    format_duration(when, sizeof when, j->fdm_seconds);
    format_duration(instead, sizeof instead, j->planar_fdm_seconds);
    if (j->planar_finest)
        printf("           no planar plan reaches it (finer than %g mm); uniform %g mm layers (worst %.6g mm): ",
               a->tmin, a->tmin, q->worst_error);
    else
        printf("           planar optimal at %.6g mm: ", j->printed_worst);
    printf("%zu layer%s, %s; hybrid %zu, %s: %ld layer%s (%.1f %%) and %.1f %% of the time saved\n", q->layer_count,
           plural(q->layer_count), instead, p->layer_count, when, (long)q->layer_count - (long)p->layer_count,
           q->layer_count - p->layer_count == 1 ? "" : "s",
           100 * (1 - (double)p->layer_count / q->layer_count), 100 * (1 - j->fdm_seconds / j->planar_fdm_seconds));
}

static void print_summary(const plan_args *a, const plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    const adaslice_profile *pr = &j->profile;
    char u[16];
    const char *eu = unit_suffix(METRICS[a->metric].eps_unit, u);
    if (a->model) {
        printf("model      %s: %s, %zu triangle%s", a->model, format_name(j->format), j->triangles, plural(j->triangles));
        if (j->repair.degenerate_dropped) printf(" (%zu degenerate dropped)", j->repair.degenerate_dropped);
        printf("\n");
    } else {
        printf("profile    %s: %zu value%s\n", a->profile, pr->bin_count, plural(pr->bin_count));
    }
    printf("height     %g mm, %zu bin%s of %g mm\n", pr->height, pr->bin_count, plural(pr->bin_count), pr->bin);
    printf("metric     %s", METRICS[a->metric].label);
    if (a->model && a->sampler)
        printf(", sampled by LDIs of %d pixel%s across (bins no ray reached, which take their neighbours' value: %zu)",
               a->resolution ? (int)a->resolution : ADASLICE_DEFAULT_RESOLUTION,
               plural(a->resolution ? a->resolution : ADASLICE_DEFAULT_RESOLUTION), j->profile.unsampled_bins);
    printf("\n");
    printf("method     %s, eps %g%s", METHOD_NAMES[a->method], p->eps, eu);
    if (a->method == ADASLICE_METHOD_CURVATURE)
        printf(" (%s mapping; eps only counts the layers over it)", MAPPING_NAMES[a->mapping]);
    if (a->budget) printf(" (the smallest that fits %zu layer%s)", a->budget, plural(a->budget));
    printf("\nthickness  %g .. %g mm, %u .. %u bin%s per layer\n", a->tmin, a->tmax, p->bins_min, p->bins_max,
           plural(p->bins_max));
    {
        /* the layers as made: the summary gave a uniform plan's bounds, 0.2 .. 0.2 mm, over a top of 0.002 */
        double thinnest = HUGE_VAL, thickest = 0;
        size_t k;
        for (k = 0; k < p->layer_count; k++) {
            thinnest = p->layers[k].thickness < thinnest ? p->layers[k].thickness : thinnest;
            thickest = p->layers[k].thickness > thickest ? p->layers[k].thickness : thickest;
        }
        printf("layers     %zu", p->layer_count);
        if (p->layer_count) printf(", %g to %g mm", thinnest, thickest);
        if (p->layer_count > 1 && thinnest < a->tmin * (1 - 1e-9)) printf(" (the top layer holds what is left of the height)");
        printf("\n");
    }
    printf("error      worst %g%s, total %g%s", p->worst_error, eu, p->total_error, eu);
    if (p->over_eps) printf(", %zu layer%s over eps", p->over_eps, plural(p->over_eps));
    printf("\n");
    /* the section 3.3 pre-pass belongs to the optimal method only */
    if (a->method == ADASLICE_METHOD_OPTIMAL && a->sharp > 0)
        printf("forced     %zu plane%s at sharp changes (> %g)\n", p->forced_planes, plural(p->forced_planes), a->sharp);
    else if (a->method == ADASLICE_METHOD_OPTIMAL)
        printf("forced     none (sharp-change pre-pass off)\n");
    if (p->plane_changes) {
        char line[1024];
        plan_changes_line(p, pr->bin, line, sizeof line);
        printf("           %s\n", line);
    }
    printf("time       load %.1f ms, repair %.1f ms, profile %.1f ms, plan %.1f ms\n", j->ms_load, j->ms_repair,
           j->ms_profile, j->ms_plan);
    if (j->fdm_seconds > 0) {
        char when[32];
        format_duration(when, sizeof when, j->fdm_seconds);
        printf("FDM time   %s (%d perimeters at %g mm/s, %g %% infill at %g mm/s, %d skin layers at %g mm/s, %g s per layer "
               "change)\n", when, FDM_WALLS, FDM_WALL_SPEED, 100 * FDM_INFILL, FDM_INFILL_SPEED, FDM_SKIN_LAYERS,
               FDM_SKIN_SPEED, FDM_LAYER_CHANGE_S);
    }
    if (a->hybrid) print_hybrid(a, j);
    if (a->compare) print_compare(a, j);
}

static void json_plan_fields(json_writer *w, const adaslice_plan *p)
{
    json_int(w, "layers", (long long)p->layer_count);
    json_number(w, "worst_error", p->worst_error);
    json_number(w, "total_error", p->total_error);
    json_int(w, "over_eps", (long long)p->over_eps);
}

static void json_hybrid(json_writer *w, const plan_args *a, const plan_job *j)
{
    const adaslice_hybrid_report *h = &j->hybrid;
    const adaslice_plan *p = &j->plan[a->method], *q = &j->planar;
    json_begin_object(w, "hybrid", 0);
    json_number(w, "max_angle", a->hybrid->max_angle);
    json_int(w, "candidate_faces", (long long)h->candidates);
    json_int(w, "contoured_faces", (long long)h->contoured);
    json_int(w, "blocked_faces", (long long)h->blocked);
    json_int(w, "costly_faces", (long long)h->costly);
    json_number(w, "contoured_area_mm2", h->area);
    json_number(w, "residual", h->residual);
    json_number(w, "rise_clamp", h->clamp);
    json_number(w, "walls_worst_error", j->walls_worst);
    json_number(w, "printed_worst_error", j->printed_worst);
    json_string(w, "planar_method", j->planar_finest ? "finest" : "optimal");
    json_number(w, "planar_eps", j->printed_worst);
    json_int(w, "planar_layers", (long long)q->layer_count);
    json_number(w, "planar_worst_error", q->worst_error);
    json_number(w, "planar_print_time_s", j->planar_fdm_seconds);
    json_int(w, "layers", (long long)p->layer_count);
    json_number(w, "print_time_s", j->fdm_seconds);
    json_int(w, "layers_saved", (long long)q->layer_count - (long long)p->layer_count);
    json_number(w, "print_time_saved_s", j->planar_fdm_seconds - j->fdm_seconds);
    json_number(w, "print_time_saved_percent", 100 * (1 - j->fdm_seconds / j->planar_fdm_seconds));
    json_end(w);
}

static void print_json(const plan_args *a, const plan_job *j)
{
    const adaslice_plan *p = &j->plan[a->method];
    const adaslice_profile *pr = &j->profile;
    json_writer w;
    size_t k;
    int r;
    cure_args c;
    compare_cure(a, &c);
    json_init(&w, stdout);
    json_begin_object(&w, NULL, 0);
    json_string(&w, "model", plan_source(a));
    json_string(&w, "source", a->model ? "mesh" : "profile");
    json_string(&w, "format", a->model ? format_name(j->format) : NULL);
    if (a->model) {
        json_int(&w, "triangles", (long long)j->triangles);
        model_report_json(&w, "repair", &j->repair);
    } else {
        json_null(&w, "triangles");
        json_null(&w, "repair");
    }
    json_string(&w, "metric", METRIC_NAMES[a->metric]);
    json_string(&w, "sampler", SAMPLER_NAMES[a->sampler]);
    json_int(&w, "unsampled_bins", (long long)j->profile.unsampled_bins);
    json_string(&w, "method", METHOD_NAMES[a->method]);
    json_number(&w, "eps", p->eps);
    json_number(&w, "tmin", a->tmin);
    json_number(&w, "tmax", a->tmax);
    json_number(&w, "bin", pr->bin);
    json_int(&w, "bins", (long long)pr->bin_count);
    json_int(&w, "bins_min", p->bins_min);
    json_int(&w, "bins_max", p->bins_max);
    json_number(&w, "height_mm", pr->height);
    if (a->budget) json_int(&w, "budget", (long long)a->budget);
    if (a->sharp > 0) json_number(&w, "sharp", a->sharp);
    else json_null(&w, "sharp");
    json_plan_fields(&w, p);
    json_int(&w, "forced_planes", (long long)p->forced_planes);
    json_begin_array(&w, "forced_changes", 1);
    for (k = 0; k < p->plane_changes; k++) {
        const adaslice_plane_change *c = &p->changes[k];
        json_begin_object(&w, NULL, 1);
        json_number(&w, "wanted_mm", c->wanted * pr->bin);
        if (c->placed) json_number(&w, "placed_mm", c->placed * pr->bin);
        else json_null(&w, "placed_mm");
        json_string(&w, "why", c->infeasible ? "infeasible" : "cost");
        json_end(&w);
    }
    json_end(&w);
    json_begin_object(&w, "time_ms", 1);
    json_number(&w, "load", j->ms_load);
    json_number(&w, "repair", j->ms_repair);
    json_number(&w, "profile", j->ms_profile);
    json_number(&w, "plan", j->ms_plan);
    json_end(&w);
    json_begin_array(&w, "layer_list", 0);
    for (k = 0; k < p->layer_count; k++) {
        const adaslice_layer *l = &p->layers[k];
        json_begin_object(&w, NULL, 1);
        json_number(&w, "z_bottom", l->z_bottom);
        json_number(&w, "z_top", l->z_top);
        json_number(&w, "thickness", l->thickness);
        json_number(&w, "error", l->error);
        json_end(&w);
    }
    json_end(&w);
    if (j->fdm_seconds > 0) json_number(&w, "fdm_print_time_s", j->fdm_seconds);
    if (a->hybrid) json_hybrid(&w, a, j);
    if (a->compare) {
        json_begin_array(&w, "compare", 0);
        for (r = 0; r < TABLE3_ROWS; r++) {
            const adaslice_error *e = &j->why[TABLE3[r]];
            if (!j->planned[TABLE3[r]]) continue;
            json_begin_object(&w, NULL, 1);
            json_string(&w, "method", METHOD_NAMES[TABLE3[r]]);
            if (e->result == ADASLICE_OK) {
                json_plan_fields(&w, &j->plan[TABLE3[r]]);
                json_number(&w, "print_time_s", cure_plan_seconds(&c, &j->plan[TABLE3[r]]));
            } else {
                json_null(&w, "layers");
                json_number(&w, "min_eps", e->min_eps);
            }
            json_end(&w);
        }
        json_end(&w);
        if (j->uniform_found) {
            const adaslice_plan *best = &j->plan[ADASLICE_METHOD_OPTIMAL];
            double t_best = cure_plan_seconds(&c, best), t_uni = cure_plan_seconds(&c, &j->uniform);
            json_begin_object(&w, "uniform_no_worse", 1);
            json_number(&w, "thickness", j->uniform.layers[0].thickness);
            json_int(&w, "uniform_layers", (long long)j->uniform.layer_count);
            json_number(&w, "uniform_worst_error", j->uniform.worst_error);
            json_number(&w, "uniform_print_time_s", t_uni);
            json_int(&w, "optimal_layers", (long long)best->layer_count);
            json_number(&w, "optimal_print_time_s", t_best);
            json_number(&w, "print_time_saved_percent", 100 * (1 - t_best / t_uni));
            json_end(&w);
        } else {
            json_null(&w, "uniform_no_worse");
        }
    }
    json_end(&w);
}

int cmd_plan(int argc, char **argv)
{
    plan_args a;
    plan_job j;
    threemf_args t;
    char **rest = (char **)malloc(((size_t)argc + 1) * sizeof *rest);
    int rest_argc = 0, rc;
    if (!rest) return complain(RC_FAIL, "out of memory");
    rc = threemf_options(argc, argv, &t, &rest_argc, rest);
    if (!rc) rc = parse_plan(rest_argc, rest, &a);
    free(rest);
    if (rc) return rc;
    if (a.help) {
        plan_usage(stdout);
        return RC_OK;
    }
    if (t.path && !a.model) return complain(RC_USAGE, "--3mf needs a MODEL, not --profile");
    if ((rc = threemf_check_hybrid(&t, &a))) return rc;
    if (t.path && (rc = threemf_check_bounds(&t, &a))) return rc;
    a.hybrid = t.hybrid ? &t.contour : NULL;
    if ((rc = check_plan_outputs(&a, "--3mf", t.path)) || (rc = output_check("--3mf", t.path))) return rc;
    memset(&j, 0, sizeof j);
    j.args = &a;
    j.keep_mesh = t.path != NULL;
    rc = run_plan(&a, &j);
    if (!rc) rc = write_outputs(&a, &j);
    if (!rc && t.path) rc = threemf_write(&t, &a, &j, a.json ? stderr : stdout);
    /* after threemf_write, which welds the mesh the contours need */
    if (!rc && t.path) rc = fdm_plan_seconds(&j.mesh, j.profile.z0, &j.plan[a.method], &j.fdm_seconds);
    if (!rc && j.planar_found) rc = fdm_plan_seconds(&j.mesh, j.profile.z0, &j.planar, &j.planar_fdm_seconds);
    if (!rc) (a.json ? print_json : print_summary)(&a, &j);
    job_free(&j);
    return rc;
}
