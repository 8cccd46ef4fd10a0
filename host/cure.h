/* The resin's exposure and the printer's motion, as slice and print take
   them from the command line: the working curve (adaslice_cure), the bottom
   layers, the peel. Every layer's exposure follows E(t) = S exp((t - T) / Dp). */
#ifndef ADASLICE_HOST_CURE_H
#define ADASLICE_HOST_CURE_H
#include <stdio.h>
#include "../adaslice.h"
#include "formats/jobfile.h"

typedef struct cure_args {
    double seconds[2], thickness[2];  /* --exposure S[@T][,S2@T2]: one or two points */
    int points;                       /* how many were given (0: the default) */
    int at_given;                     /* a point named its thickness */
    double penetration;               /* --penetration DP, or 0 */
    size_t bottom_layers;
    double bottom_exposure_s;
    job_motion motion;                /* --peel, --peel-speed, --return-speed, --settle */
    int given;                        /* any of these options was given */
    int typical;                      /* no --exposure or --penetration: a typical resin's Dp */
    adaslice_cure cure;               /* made by cure_finish */
} cure_args;

/* The defaults: 2.5 s at tmin on a typical resin's working curve (Dp
   CURE_TYPICAL_DP), 3 bottom layers of 25 s, a 5 mm peel at 2 mm/s back at
   4 mm/s, 0.5 s to settle. */
/* UVtools' maintainer cures 0.05 mm in 1.8 s and 0.10 mm in 3 s of a
   standard resin (UVtools #280): Dp = 0.05 / ln(3 / 1.8). */
#define CURE_TYPICAL_DP 0.098
/* What a job may ask of a printer: exposures and the settle, seconds; the
   peel, mm, and its speeds, mm/s. A job's file is held to them when read. */
#define CURE_MIN_SECONDS 0.001
#define CURE_MAX_SECONDS 3600.0
#define CURE_MAX_PEEL_MM 1000.0
/* speeds are kept in um/s: a slower one would be written as 0, which the
   firmware takes for its top speed */
#define CURE_MIN_SPEED_MM_S 0.001
void cure_defaults(cure_args *c);
/* The defaults with their working curve (T = tmin), for an estimate where no
   printer is involved (plan --compare): slice's exposures without the limits
   a printer counts in. */
void cure_typical(cure_args *c, double tmin);
/* If argv[*i] is one of the options above, takes it (and its value), sets
   *rc (RC_OK or RC_USAGE after a complaint) and returns 1; else 0. */
int cure_option(int argc, char **argv, int *i, cure_args *c, int *rc);
/* The working curve, with T defaulting to tmin; checks Dp, S and T (inside
   [tmin, tmax]), two points' consistency and what a printer can count (32-bit
   milliseconds and nanometres). RC_OK or RC_USAGE after a complaint. */
int cure_finish(cure_args *c, double tmin, double tmax);
void cure_usage(FILE *f);
/* Every layer's thickness, place and exposure (bottom layers get the bottom
   exposure) into out[0 .. K). Warns when one exposure serves layers of
   different thickness. */
void cure_layers(const cure_args *c, const adaslice_plan *plan, job_layer *out);
/* Seconds to print the layers: every exposure, settle, peel and return. */
double cure_print_time(const job_motion *m, const job_layer *layers, size_t count);
/* The same for a plan's layers with c's exposures; NAN without memory. */
double cure_plan_seconds(const cure_args *c, const adaslice_plan *plan);
#endif
