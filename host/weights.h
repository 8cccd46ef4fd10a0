/* Per-face weights for the profiles (paper §4.2): the mesh's saliency, a
   weight file and regions given on the command line, multiplied face by face;
   or, with --importance or --view, the blend of saliency-preserving slicing:
   a saliency + b view importance + c user weight, each term in [0, 1]. */
#ifndef ADASLICE_HOST_WEIGHTS_H
#define ADASLICE_HOST_WEIGHTS_H
#include <stdio.h>
#include "../adaslice.h"

enum { WEIGHT_BOX = 0, WEIGHT_SPHERE = 1, WEIGHT_REGIONS_MAX = 32, WEIGHT_VIEWS_MAX = 64, WEIGHT_VIEW_COUNT_MAX = 4096 };

/* A face is in a region when its centroid is: inside the box or on its faces,
   or within the sphere's radius of its centre. */
typedef struct weight_region {
    int kind;          /* WEIGHT_BOX or WEIGHT_SPHERE */
    double a[3], b[3]; /* box: lowest and highest corner; sphere: centre, b[0] radius */
    double weight;
} weight_region;

typedef struct weight_args {
    int saliency;                              /* --saliency */
    const char *file;                          /* --weights FILE, or NULL */
    size_t region_count;
    weight_region regions[WEIGHT_REGIONS_MAX]; /* --weight REGION=W, in the order given */
    int blend;                                 /* --importance or --view given */
    double importance[3];                      /* a, b, c (saliency, view, user) */
    int view_half;                             /* --view NAME: an index of the names, -1: a list */
    size_t view_count;                         /* a list's directions */
    double views[3 * WEIGHT_VIEWS_MAX];
    size_t view_lattice;                       /* --view-count: directions in a named half; 0: default */
    size_t view_res;                           /* --view-res: pixels across the part; 0: default */
} weight_args;

/* If argv[*i] is --saliency, --weights, --weight, --importance or --view, takes it (and its value),
   sets *rc (RC_OK, or RC_USAGE after a complaint) and returns 1; else 0. */
int weights_option(int argc, char **argv, int *i, weight_args *w, int *rc);
int weights_given(const weight_args *w);
/* After every option: RC_OK, or RC_USAGE after a complaint when the options
   weigh nothing (--importance 0,0,C with no weights given). */
int weights_check(const weight_args *w);
/* One weight per triangle of `mesh` in *out (malloc'd), or *out = NULL when
   none are asked for. A bad weight file is RC_USAGE, an unreadable one RC_FAIL;
   the complaint is made. */
int weights_for_plan(const weight_args *w, const char *model, const adaslice_mesh *mesh, float **out);
/* The weight options' help; `saliency_option`: with --saliency (adaslice
   saliency weighs by saliency unless told not to). */
void weights_usage(FILE *f, int saliency_option);
#endif
