/* adaslice orient: the build-direction search of §4.3. Every direction of a
   spherical Fibonacci lattice is planned (threads share the work), scored by
   F(O) = alpha K/max K + (1 - alpha) eps/max eps, and the best direction and
   the best local minima are reported as directions and as rotations. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "json.h"
#include "commands.h"
#include "model.h"
#include "options.h"
#include "output.h"
#include "plan_job.h"
#include "report.h"
#include "search.h"
#include "svg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ORIENT_MAX_DIRS 1000000

/* The rotation that brings d up, as an axis and an angle in degrees. */
static void axis_angle(const double d[3], double axis[3], double *degrees)
{
    double len = sqrt(d[0] * d[0] + d[1] * d[1]);
    axis[0] = len > 0 ? d[1] / len : 1;
    axis[1] = len > 0 ? -d[0] / len : 0;
    axis[2] = 0;
    *degrees = acos(d[2] < -1 ? -1 : d[2] > 1 ? 1 : d[2]) * 180 / 3.14159265358979;
}

typedef struct orient_args {
    size_t dirs;
    double alpha;
    const char *map;
} orient_args;

typedef struct map_ctx {
    const adaslice_direction_score *scores;
    size_t count;
    const size_t *minima;
    size_t minima_count;
    const char *model;
    double alpha;
} map_ctx;

/* Blue (low F, good) through white (halfway) to red (high F); grey: infeasible. */
static void score_colour(double f, double lo, double hi, char out[8])
{
    double t = hi > lo ? (f - lo) / (hi - lo) : 0;
    int r, g, b;
    if (f > 1.5) { strcpy(out, "#b0b0b0"); return; }
    if (t < 0.5) { r = (int)(40 + 430 * t); g = (int)(90 + 330 * t); b = (int)(220 + 70 * t); }
    else { r = 255; g = (int)(255 - 360 * (t - 0.5)); b = (int)(255 - 420 * (t - 0.5)); }
    snprintf(out, 8, "#%02x%02x%02x", r > 255 ? 255 : r, g > 255 ? 255 : g < 0 ? 0 : g, b > 255 ? 255 : b < 0 ? 0 : b);
}

/* The map's grid in pixels: cell i's edges are MAP_X(i) and MAP_X(i + 1), so
   neighbours share their edge exactly, and crispEdges keeps renderers from
   anti-aliasing those edges into seams of the background. */
enum { MAP_W = 180, MAP_H = 90, CELL = 4, MAP_LEFT = 60, MAP_TOP = 50, BAR_LEFT = MAP_LEFT + MAP_W * CELL + 28, BAR_W = 16 };
#define MAP_X(i) (MAP_LEFT + (i) * CELL)
#define MAP_Y(j) (MAP_TOP + (j) * CELL)

static void cell_run(FILE *f, int x0, int x1, int row, const char *colour)
{
    fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"%s\"/>\n", x0, MAP_Y(row), x1 - x0,
            MAP_Y(row + 1) - MAP_Y(row), colour);
}

/* The colour of every F from lo (bottom) to hi (top), one step per map row,
   in the map's own colours; grey below it if some directions have no plan. */
static void colour_bar(FILE *f, double lo, double hi, int infeasible)
{
    char c[8];
    int j;
    fprintf(f, "<g id=\"colour-bar\" data-min=\"%.9g\" data-max=\"%.9g\">\n<g shape-rendering=\"crispEdges\">\n", lo, hi);
    for (j = 0; j < MAP_H; j++) {
        score_colour(lo + (hi - lo) * (MAP_H - j - 0.5) / MAP_H, lo, hi, c);
        cell_run(f, BAR_LEFT, BAR_LEFT + BAR_W, j, c);
    }
    fputs("</g>\n", f);
    fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"black\"/>\n", BAR_LEFT, MAP_Y(0),
            BAR_W, MAP_Y(MAP_H) - MAP_Y(0));
    fprintf(f, "<text x=\"%d\" y=\"%d\" font-weight=\"bold\">F</text>\n", BAR_LEFT, MAP_Y(0) - 8);
    fprintf(f, "<text x=\"%d\" y=\"%d\">%.4g</text><text x=\"%d\" y=\"%d\" fill=\"#555\">max</text>\n",
            BAR_LEFT + BAR_W + 5, MAP_Y(0) + 10, hi, BAR_LEFT + BAR_W + 5, MAP_Y(0) + 24);
    fprintf(f, "<text x=\"%d\" y=\"%d\">%.4g</text><text x=\"%d\" y=\"%d\" fill=\"#555\">min</text>\n",
            BAR_LEFT + BAR_W + 5, MAP_Y(MAP_H), lo, BAR_LEFT + BAR_W + 5, MAP_Y(MAP_H) - 14);
    if (infeasible)
        fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"10\" fill=\"#b0b0b0\" stroke=\"black\"/>"
                   "<text x=\"%d\" y=\"%d\">no plan</text>\n",
                BAR_LEFT, MAP_Y(MAP_H) + 12, BAR_W, BAR_LEFT + BAR_W + 5, MAP_Y(MAP_H) + 21);
    fputs("</g>\n", f);
}

/* The paper's Fig. 8 flattened: F of the nearest lattice direction over an
   equirectangular grid of longitude and latitude, runs of equal colour merged. */
static void write_map(FILE *f, const void *ctx)
{
    const map_ctx *m = (const map_ctx *)ctx;
    int width = BAR_LEFT + BAR_W + 60, height = MAP_Y(MAP_H) + 60, x, y, infeasible = 0;
    double lo = 2, hi = 0;
    size_t i;
    for (i = 0; i < m->count; i++)
        if (m->scores[i].score <= 1.5) {
            if (m->scores[i].score < lo) lo = m->scores[i].score;
            if (m->scores[i].score > hi) hi = m->scores[i].score;
        } else infeasible = 1;
    fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
               "font-family=\"sans-serif\" font-size=\"12\">\n", width, height, width, height);
    fputs("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n", f);
    fprintf(f, "<text x=\"%d\" y=\"22\" font-size=\"15\" font-weight=\"bold\">", MAP_LEFT);
    xml_text(f, m->model);
    fprintf(f, ": F over build directions (alpha %g, %zu directions)</text>\n", m->alpha, m->count);
    fprintf(f, "<text x=\"%d\" y=\"40\" fill=\"#555\">blue: low F (good), red: high F; "
               "circles: the best direction and local minima</text>\n", MAP_LEFT);
    fputs("<g id=\"cells\" shape-rendering=\"crispEdges\">\n", f);
    for (y = 0; y < MAP_H; y++) {
        double lat = (90 - (y + 0.5) * 180.0 / MAP_H) * 3.14159265358979 / 180;
        char run[8] = "", c[8];
        int start = 0;
        for (x = 0; x <= MAP_W; x++) {
            if (x < MAP_W) {
                double lon = (-180 + (x + 0.5) * 360.0 / MAP_W) * 3.14159265358979 / 180, best = -2;
                double p[3];
                size_t k, near = 0;
                p[0] = cos(lat) * cos(lon); p[1] = cos(lat) * sin(lon); p[2] = sin(lat);
                for (k = 0; k < m->count; k++) {
                    const double *d = m->scores[k].direction;
                    double dot = d[0] * p[0] + d[1] * p[1] + d[2] * p[2];
                    if (dot > best) { best = dot; near = k; }
                }
                score_colour(m->scores[near].score, lo, hi, c);
            }
            if (x == MAP_W || strcmp(c, run)) {
                if (x > 0) cell_run(f, MAP_X(start), MAP_X(x), y, run);
                if (x < MAP_W) { strcpy(run, c); start = x; }
            }
        }
    }
    fputs("</g>\n", f);
    fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"black\"/>\n", MAP_X(0), MAP_Y(0),
            MAP_X(MAP_W) - MAP_X(0), MAP_Y(MAP_H) - MAP_Y(0));
    colour_bar(f, lo <= hi ? lo : 0, lo <= hi ? hi : 0, infeasible);
    for (x = -180; x <= 180; x += 60)
        fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">%d&#176;</text>\n",
                MAP_LEFT + (x + 180) * CELL * MAP_W / 360, MAP_Y(MAP_H) + 16, x);
    for (y = -90; y <= 90; y += 45)
        fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"end\">%d&#176;</text>\n", MAP_LEFT - 6,
                MAP_TOP + (90 - y) * CELL * MAP_H / 180 + 4, y);
    fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">longitude of the build direction (atan2(y, x))</text>\n",
            MAP_LEFT + MAP_W * CELL / 2, MAP_Y(MAP_H) + 36);
    fprintf(f, "<text transform=\"translate(16 %d) rotate(-90)\" text-anchor=\"middle\">latitude (asin z)</text>\n",
            MAP_TOP + MAP_H * CELL / 2);
    for (i = 0; i < m->minima_count; i++) {
        const double *d = m->scores[m->minima[i]].direction;
        double lon = atan2(d[1], d[0]) * 180 / 3.14159265358979, lat = asin(d[2]) * 180 / 3.14159265358979;
        double cx = MAP_LEFT + (lon + 180) * CELL * MAP_W / 360, cy = MAP_TOP + (90 - lat) * CELL * MAP_H / 180;
        fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"7\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/>"
                   "<text x=\"%.1f\" y=\"%.1f\" font-weight=\"bold\">%s</text>\n",
                cx, cy, cx + 9, cy - 8, i == 0 ? "best" : i == 1 ? "2" : i == 2 ? "3" : "4");
    }
    fputs("</svg>\n", f);
}

static void orient_usage(FILE *f)
{
    fputs("usage: adaslice orient MODEL [--dirs N] [--alpha A] [plan options] [--map map.svg] [--json]\n"
          "\n"
          "Plans MODEL along N build directions of a spherical Fibonacci lattice and the six axis\n"
          "directions (the part as loaded among them) and scores each\n"
          "by F = A K/max K + (1 - A) eps/max eps (eq. 25), eps being the plan's worst layer\n"
          "error; prints the best direction and the best other local minima, each with the\n"
          "rotation that brings it up (apply it with adaslice plan|slice --orient X,Y,Z).\n"
          "\n"
          "  --dirs N            directions on the sphere, 1 to 1000000           [1000]\n"
          "  --alpha A           weight of the layer count against the error, 0..1  [0.5]\n"
          "  --map FILE          SVG map of F over the sphere (longitude, latitude)\n"
          "  --memory MB         the most the search may take  [half the machine's memory]\n"
          "\n", f);
    plan_options_usage(f, FOR_ORIENT);
}

/* Takes the orient options out of argv; the rest goes to parse_plan. */
static int parse_orient(int argc, char **argv, orient_args *o, int *rest_argc, char **rest)
{
    int i, rc = RC_OK;
    o->dirs = 1000;
    o->alpha = 0.5;
    o->map = NULL;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        if (!strcmp(argv[i], "--dirs")) rc = count_option(argc, argv, &i, ORIENT_MAX_DIRS, &o->dirs);
        else if (!strcmp(argv[i], "--alpha")) {
            if (!(rc = number_option(argc, argv, &i, 1, &o->alpha)) && o->alpha > 1)
                rc = complain(RC_USAGE, "--alpha %s: the weight of the layer count is at most 1", argv[i]);
        } else if (!strcmp(argv[i], "--map")) rc = file_option(argc, argv, &i, &o->map);
        else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            orient_usage(stdout);
            return -1;
        } else rest[(*rest_argc)++] = argv[i];
    }
    return rc;
}

/* The options given that orient's scores cannot take, as "A, B and C". */
static const char *unscored_options(int argc, char **argv, const plan_args *a)
{
    static const char *const names[] = {"--saliency", "--weights", "--weight", "--importance", "--view", "--view-count",
                                        "--view-res", "--sampler"};
    static char list[160];
    const char *given[10];
    size_t n = 0, k, used = 0;
    if (a->method == ADASLICE_METHOD_CURVATURE) given[n++] = "--method curvature";
    for (k = 0; k < sizeof names / sizeof *names; k++)
        if (option_given(argc, argv, names[k])) given[n++] = names[k];
    list[0] = 0;
    for (k = 0; k < n; k++)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", k == 0 ? "" : k + 1 < n ? ", " : " and ", given[k]);
    return list;
}

int cmd_orient(int argc, char **argv)
{
    orient_args o;
    plan_args a;
    adaslice_mesh mesh;
    adaslice_mesh_report repair;
    adaslice_direction_score *scores = NULL;
    size_t minima[SEARCH_MINIMA + 1], count = 0, i;
    char **rest = (char **)malloc(((size_t)argc + 1) * sizeof *rest);
    int rest_argc = 0, rc;
    double t0;

    if (!rest) return complain(RC_FAIL, "out of memory");
    rc = parse_orient(argc, argv, &o, &rest_argc, rest);
    if (rc < 0) { free(rest); return RC_OK; }
    if (!rc) rc = parse_plan(rest_argc, rest, &a);
    free(rest);
    if (rc) return rc;
    if (a.help) { orient_usage(stdout); return RC_OK; }
    if (a.orient) return complain(RC_USAGE, "orient searches the directions itself: drop --orient");
    if (a.out || a.plot || a.profile_out || a.compare)
        return complain(RC_USAGE, "orient prints directions: --out, --plot, --profile-out and --compare belong to adaslice "
                                  "plan MODEL --orient X,Y,Z with the direction orient found");
    if (a.method == ADASLICE_METHOD_CURVATURE || weights_given(&a.weights) || a.sampler)
        return complain(RC_USAGE, "orient scores directions by unweighted optimal, greedy, finest or coarsest plans of "
                                  "exact profiles: drop %s", unscored_options(argc, argv, &a));
    if ((rc = output_check("--map", o.map))) return rc;
    if ((rc = model_load(a.model, a.scale, &mesh, &repair)) != RC_OK) return rc;
    t0 = now_ms();
    rc = plan_orient_search(&a, &mesh, o.dirs, o.alpha, &scores, minima, &count);
    if (!rc) { /* a best of none would print as a direction */
        size_t feasible = 0;
        for (i = 0; i < o.dirs + SEARCH_AXES; i++) feasible += scores[i].feasible;
        if (!feasible && a.budget)
            rc = complain(RC_FAIL, "%s: no direction of the %zu and the 6 axes has a plan of at most %zu layers of %g to "
                                   "%g mm: a larger --budget, or check the part's size (--scale)", a.model, o.dirs,
                          a.budget, a.tmin, a.tmax);
        else if (!feasible)
            rc = complain(RC_FAIL, "%s: no direction of the %zu and the 6 axes has a plan within eps %g mm of layers %g to "
                                   "%g mm: a larger --eps, or check the part's size (--scale)", a.model, o.dirs, a.eps,
                          a.tmin, a.tmax);
    }
    if (!rc && o.map) {
        map_ctx m;
        m.scores = scores;
        m.count = o.dirs + SEARCH_AXES;
        m.minima = minima;
        m.minima_count = count;
        m.model = base_name(a.model);
        m.alpha = o.alpha;
        rc = write_atomic(o.map, write_map, &m);
    }
    if (!rc && a.json) {
        json_writer w;
        json_init(&w, stdout);
        json_begin_object(&w, NULL, 0);
        json_string(&w, "model", a.model);
        model_report_json(&w, "repair", &repair);
        json_int(&w, "directions", (long long)o.dirs);
        json_number(&w, "alpha", o.alpha);
        json_string(&w, "metric", METRIC_NAMES[a.metric]);
        json_number(&w, "seconds", (now_ms() - t0) / 1000);
        json_begin_array(&w, "best", 0);
        for (i = 0; i < count; i++) {
            const adaslice_direction_score *s = &scores[minima[i]];
            double r[9], axis[3], deg;
            adaslice_rotation_to_z(s->direction, r);
            axis_angle(s->direction, axis, &deg);
            json_begin_object(&w, NULL, 1);
            json_numbers(&w, "direction", s->direction, 3);
            json_int(&w, "layers", (long long)s->layers);
            json_number(&w, "mean_error", s->mean_error);
            json_number(&w, "worst_error", s->worst_error);
            json_number(&w, "F", s->score);
            json_numbers(&w, "rotation", r, 9);
            json_numbers(&w, "axis", axis, 3);
            json_number(&w, "angle_deg", deg);
            json_end(&w);
        }
        json_end(&w);
        json_begin_object(&w, "as_loaded", 1);
        json_bool(&w, "feasible", scores[o.dirs].feasible);
        if (scores[o.dirs].feasible) {
            json_int(&w, "layers", (long long)scores[o.dirs].layers);
            json_number(&w, "worst_error", scores[o.dirs].worst_error);
            json_number(&w, "F", scores[o.dirs].score);
        } else { /* no plan: no count, error or score (0 layers read as a plan of none) */
            json_null(&w, "layers");
            json_null(&w, "worst_error");
            json_null(&w, "F");
        }
        json_end(&w);
        json_end(&w);
    } else if (!rc) {
        size_t feasible = 0;
        for (i = 0; i < o.dirs + SEARCH_AXES; i++) feasible += scores[i].feasible;
        printf("%s: %zu direction%s and the 6 axes (%zu feasible) in %.2f s, F = %g K/max K + %g eps/max eps (eps: worst "
               "layer error)\n",
               base_name(a.model), o.dirs, plural(o.dirs), feasible, (now_ms() - t0) / 1000, o.alpha, 1 - o.alpha);
        printf("rank  direction (x, y, z)           rotate about (x, y, z)   by deg   layers  mean err   worst err        F\n");
        for (i = 0; i < count && i <= SEARCH_MINIMA; i++) {
            const adaslice_direction_score *s = &scores[minima[i]];
            double axis[3], deg;
            axis_angle(s->direction, axis, &deg);
            printf("%-5s (%7.4f, %7.4f, %7.4f)   (%6.3f, %6.3f, %6.3f)  %7.2f  %7zu  %9.5f  %9.5f  %7.4f\n",
                   i == 0 ? "best" : i == 1 ? "2" : i == 2 ? "3" : "4", s->direction[0], s->direction[1], s->direction[2],
                   axis[0], axis[1], axis[2], deg, s->layers, s->mean_error, s->worst_error, s->score);
        }
        {
            const adaslice_direction_score *s = &scores[o.dirs]; /* +z: the part as loaded */
            if (s->feasible)
                printf("as loaded (%7.4f, %7.4f, %7.4f)   %-31s %7zu  %9.5f  %9.5f  %7.4f\n", 0.0, 0.0, 1.0, "", s->layers,
                       s->mean_error, s->worst_error, s->score);
            else
                printf("as loaded: no plan meets eps\n");
        }
    }
    free(scores);
    adaslice_mesh_free(&mesh);
    return rc;
}
