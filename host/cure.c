/* Exposures and motion from the command line: see cure.h. */
#include "cure.h"
#include "options.h"
#include "report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


void cure_defaults(cure_args *c)
{
    memset(c, 0, sizeof *c);
    c->seconds[0] = 2.5;
    c->bottom_layers = 3;
    c->bottom_exposure_s = 25;
    c->motion.lift_mm = c->motion.bottom_lift_mm = 5;
    c->motion.lift_speed = c->motion.bottom_lift_speed = 2;
    c->motion.retract_speed = 4;
    c->motion.wait_before_cure_s = 0.5;
}

/* T defaults to tmin, and Dp to a typical resin's unless a second point or
   --penetration gives it; one point makes the curve (two are fitted later). */
static void default_curve(cure_args *c, double tmin)
{
    if (!c->at_given) c->thickness[0] = tmin;
    if (!c->points && !c->penetration) {
        c->penetration = CURE_TYPICAL_DP;
        c->typical = 1;
    }
    c->cure.seconds = c->seconds[0];
    c->cure.thickness = c->thickness[0];
    c->cure.penetration = c->penetration;
}

void cure_typical(cure_args *c, double tmin)
{
    cure_defaults(c);
    default_curve(c, tmin);
}

void cure_usage(FILE *f)
{
    fputs("exposure (Jacobs' working curve: a layer t mm thick gets E(t) = S exp((t - T) / Dp))\n"
          "  --exposure S@T      S seconds cure a layer of T mm (T: tmin if left out) [2.5]\n"
          "  --exposure S1@T1,S2@T2   two calibrated points; Dp is fitted to them\n"
          "  --penetration DP    the resin's penetration depth Dp, mm, with one point;\n"
          "                      --exposure S alone gives every layer S       [0.098]\n"
          "  --bottom-layers N   layers exposed longer, to stick to the plate (0:\n"
          "                      none; more than the job has: all of them)    [3]\n"
          "  --bottom-exposure S their seconds                                    [25]\n"
          "motion\n"
          "  --peel MM           lift after each layer                            [5]\n"
          "  --peel-speed MM/S   lift speed                                       [2]\n"
          "  --return-speed MM/S speed back down                                  [4]\n"
          "  --settle S          wait before exposing                             [0.5]\n", f);
}

/* "S" or "S@T" */
static int parse_point(const char *text, double *s, double *t, int *at)
{
    const char *end = decimal_number(text, s);
    if (!end) return 0;
    *at = *end == '@';
    if (!*at) return *end == 0;
    return parse_numbers(end + 1, 0, 1, t);
}

static int take(int argc, char **argv, int *i, cure_args *c, int *rc);

int cure_option(int argc, char **argv, int *i, cure_args *c, int *rc)
{
    int taken = take(argc, argv, i, c, rc);
    c->given |= taken;
    return taken;
}

static int take(int argc, char **argv, int *i, cure_args *c, int *rc)
{
    const char *o = argv[*i];
    if (!strcmp(o, "--exposure")) {
        const char *v;
        char first[64];
        const char *comma;
        int at1 = 0, at2 = 0;
        if ((*rc = file_option(argc, argv, i, &v))) return 1;
        comma = strchr(v, ',');
        if (strlen(v) >= sizeof first) { *rc = complain(RC_USAGE, "--exposure %.40s...: too long", v); return 1; }
        strcpy(first, v);
        if (comma) first[comma - v] = 0;
        c->points = comma ? 2 : 1;
        if (!parse_point(first, &c->seconds[0], &c->thickness[0], &at1) ||
            (comma && (!parse_point(comma + 1, &c->seconds[1], &c->thickness[1], &at2) || !at1 || !at2)))
            *rc = complain(RC_USAGE, "--exposure %s: expected S, S@T or S1@T1,S2@T2 (seconds @ mm)", v);
        c->at_given = at1;
        return 1;
    }
    if (!strcmp(o, "--penetration")) { *rc = number_option(argc, argv, i, 0, &c->penetration); return 1; }
    if (!strcmp(o, "--bottom-exposure")) { *rc = number_option(argc, argv, i, 0, &c->bottom_exposure_s); return 1; }
    if (!strcmp(o, "--bottom-layers")) { *rc = whole_option(argc, argv, i, 0, UINT32_MAX, &c->bottom_layers); return 1; }
    if (!strcmp(o, "--peel")) { *rc = number_option(argc, argv, i, 1, &c->motion.lift_mm); c->motion.bottom_lift_mm = c->motion.lift_mm; return 1; }
    if (!strcmp(o, "--peel-speed")) {
        *rc = number_option(argc, argv, i, 0, &c->motion.lift_speed);
        c->motion.bottom_lift_speed = c->motion.lift_speed;
        return 1;
    }
    if (!strcmp(o, "--return-speed")) { *rc = number_option(argc, argv, i, 0, &c->motion.retract_speed); return 1; }
    if (!strcmp(o, "--settle")) { *rc = number_option(argc, argv, i, 1, &c->motion.wait_before_cure_s); return 1; }
    return 0;
}

/* The firmware counts milliseconds (a mask takes 1 ms to an hour) and
   nanometres in 32 bits. */

int cure_finish(cure_args *c, double tmin, double tmax)
{
    adaslice_error e;
    int k;
    if (c->bottom_exposure_s > CURE_MAX_SECONDS || c->motion.wait_before_cure_s > CURE_MAX_SECONDS)
        return complain(RC_USAGE, "--bottom-exposure and --settle are limited to %g s", CURE_MAX_SECONDS);
    if (c->motion.lift_mm > CURE_MAX_PEEL_MM || c->motion.lift_speed > CURE_MAX_PEEL_MM ||
        c->motion.retract_speed > CURE_MAX_PEEL_MM)
        return complain(RC_USAGE, "--peel is limited to %g mm and speeds to %g mm/s", CURE_MAX_PEEL_MM, CURE_MAX_PEEL_MM);
    if (c->motion.lift_speed < CURE_MIN_SPEED_MM_S || c->motion.retract_speed < CURE_MIN_SPEED_MM_S)
        return complain(RC_USAGE, "--peel-speed %g, --return-speed %g: speeds are at least %g mm/s (a job keeps um/s)",
                        c->motion.lift_speed, c->motion.retract_speed, CURE_MIN_SPEED_MM_S);
    default_curve(c, tmin);
    for (k = 0; k < (c->points ? c->points : 1); k++) {
        if (!(c->seconds[k] > 0))
            return complain(RC_USAGE, "--exposure: %g s is not a positive exposure", c->seconds[k]);
        if (!(c->thickness[k] >= tmin * (1 - 1e-9) && c->thickness[k] <= tmax * (1 + 1e-9)))
            return complain(RC_USAGE, "--exposure %g@%g: the layer of %g mm lies outside tmin %g .. tmax %g mm",
                            c->seconds[k], c->thickness[k], c->thickness[k], tmin, tmax);
    }
    if (c->points == 2) {
        if (c->penetration)
            return complain(RC_USAGE, "--penetration and two --exposure points: give one or the other (Dp is fitted to the points)");
        if (adaslice_cure_fit(c->seconds[0], c->thickness[0], c->seconds[1], c->thickness[1], &c->cure, &e) != ADASLICE_OK)
            return complain(RC_USAGE, "--exposure %g@%g,%g@%g: the thicker layer must need the longer exposure",
                            c->seconds[0], c->thickness[0], c->seconds[1], c->thickness[1]);
    }
    /* E(t) grows with t: its ends are the thinnest and thickest exposures */
    for (k = 0; k < 2; k++) {
        double t = k ? tmax : tmin, e_t = adaslice_cure_seconds(&c->cure, t);
        if (e_t >= CURE_MIN_SECONDS && e_t <= CURE_MAX_SECONDS) continue;
        /* Dp 0: no curve, one exposure for every layer */
        if (!(c->cure.penetration > 0))
            return complain(RC_USAGE, "--exposure %g: every layer gets %g s; exposures are %g to %g s", c->cure.seconds,
                            c->cure.seconds, CURE_MIN_SECONDS, CURE_MAX_SECONDS);
        return complain(RC_USAGE, "the working curve (%g s at %g mm, Dp %g mm%s) gives a %g mm layer %.4g s; exposures are %g to "
                                  "%g s", c->cure.seconds, c->cure.thickness, c->cure.penetration,
                        c->typical ? ": a typical resin's, --penetration gives yours" : "", t, e_t, CURE_MIN_SECONDS, CURE_MAX_SECONDS);
    }
    if (c->bottom_layers && c->bottom_exposure_s < CURE_MIN_SECONDS)
        return complain(RC_USAGE, "--bottom-exposure %g: exposures are %g to %g s", c->bottom_exposure_s, CURE_MIN_SECONDS,
                        CURE_MAX_SECONDS);
    return RC_OK;
}

double cure_print_time(const job_motion *m, const job_layer *layers, size_t count)
{
    double per_layer = m->wait_before_cure_s + job_peel_s(m, 0), t = 0;
    size_t k;
    for (k = 0; k < count; k++) t += layers[k].exposure_s + per_layer;
    return t;
}

double cure_plan_seconds(const cure_args *c, const adaslice_plan *plan)
{
    job_layer *layers = (job_layer *)malloc((plan->layer_count ? plan->layer_count : 1) * sizeof *layers);
    double s;
    if (!layers) return NAN;
    cure_layers(c, plan, layers);
    s = cure_print_time(&c->motion, layers, plan->layer_count);
    free(layers);
    return s;
}

void cure_layers(const cure_args *c, const adaslice_plan *p, job_layer *out)
{
    size_t k, thickest = 0;
    double thinnest = HUGE_VAL;
    for (k = 0; k < p->layer_count; k++) {
        const adaslice_layer *l = &p->layers[k];
        out[k].z_bottom = l->z_bottom;
        out[k].z_top = l->z_top;
        out[k].thickness = l->thickness;
        out[k].exposure_s = k < c->bottom_layers ? c->bottom_exposure_s : adaslice_cure_seconds(&c->cure, l->thickness);
        out[k].lit_mm2 = 0;
        if (k < c->bottom_layers) continue;
        if (l->thickness < thinnest) thinnest = l->thickness;
        if (l->thickness > p->layers[thickest].thickness || thickest < c->bottom_layers) thickest = k;
    }
    if (!(c->cure.penetration > 0) && thickest >= c->bottom_layers && thickest < p->layer_count &&
        p->layers[thickest].thickness > thinnest * (1 + 1e-9)) {
        double t = p->layers[thickest].thickness, need = exp((t - thinnest) / CURE_TYPICAL_DP);
        warn("one exposure (%g s) for layers of %g to %g mm: layer %zu (%g mm) needs "
             "%.2gx the dose of a %g mm layer for a resin of Dp %g mm; give --exposure S@T with "
             "--penetration DP, or two points S1@T1,S2@T2",
             c->cure.seconds, thinnest, t, thickest + 1, t, need, thinnest, CURE_TYPICAL_DP);
    }
}
