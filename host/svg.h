/* The plan figure: a profile and its slicing plan against height, in the manner
   of the paper's Fig. 1b-c and Fig. 5. */
#ifndef ADASLICE_HOST_SVG_H
#define ADASLICE_HOST_SVG_H
#include <stdio.h>
#include "../adaslice.h"

typedef struct svg_plan_figure {
    const char *model;          /* shown in the title */
    const char *metric;         /* e.g. "cusp height" */
    const char *phi_axis;       /* what phi is, with its unit */
    const char *eps_unit;       /* unit of eps and layer errors, "" if none */
    const char *method;         /* e.g. "optimal" */
    const adaslice_profile *profile;
    const adaslice_plan *plan;  /* at least one layer */
} svg_plan_figure;

/* 1, 2 or 5 times a power of ten, giving about `count` steps over `range`
   (axis ticks, scale bars). */
double svg_nice_step(double range, int count);

/* s as XML character data (escaped). */
void xml_text(FILE *f, const char *s);

/* Writes a standalone SVG document; errors show in ferror(f). */
void svg_write_plan(FILE *f, const svg_plan_figure *fig);

#endif
