/* The adaslice tool's shared parts: messages, atomic files, the plan options
   and the job that plan and slice both run. */
#ifndef ADASLICE_HOST_CLI_H
#define ADASLICE_HOST_CLI_H
#include <stdio.h>
#include "../adaslice.h"
#include "weights.h"
#include "printer.h"

enum { RC_OK = 0, RC_FAIL = 1, RC_USAGE = 2 };
enum { METRIC_COUNT = 4, METHOD_COUNT = 5 };

extern const char *const METRIC_NAMES[];
extern const char *const METHOD_NAMES[];
extern const char *const SAMPLER_NAMES[];
typedef struct metric_info { const char *label, *phi_axis, *eps_unit; } metric_info;
extern const metric_info METRICS[METRIC_COUNT];

/* "adaslice: " + the message on stderr; returns rc. */
int complain(int rc, const char *fmt, ...);
/* The library's message; exit 2 for an argument it rejects, else 1. */
int library_error(const adaslice_error *e);
double now_ms(void);
const char *base_name(const char *path);

typedef void (*write_fn)(FILE *f, const void *ctx);
/* Writes PATH through "PATH.tmp.PID" and renames it into place. */
int write_atomic(const char *path, write_fn fill, const void *ctx);
void json_string(FILE *f, const char *s);
void json_number(FILE *f, double v);

typedef struct plan_args {
    const char *model, *profile;   /* exactly one is set */
    adaslice_metric metric;
    adaslice_method method;
    double bin, eps, tmin, tmax;
    double scale;                  /* 0: not given */
    double sharp;                  /* 0: pre-pass off */
    size_t budget;                 /* 0: none */
    uint32_t eps_units;            /* printer units for the optimal plan (print), 0: fine */
    int sampler;                   /* 0: exact, 1: LDI */
    size_t resolution;             /* LDI pixels across the largest extent */
    const char *orient;            /* --orient best|X,Y,Z, or NULL */
    const char *out, *profile_out, *plot;
    int json, compare, help;
    int mapping;                   /* --mapping, an adaslice_mapping (--method curvature) */
    weight_args weights;           /* --saliency, --weights, --weight (model only) */
} plan_args;

typedef struct plan_job {
    const plan_args *args;
    size_t triangles, degenerate;  /* model only */
    adaslice_format format;
    adaslice_profile profile;
    int profiled;                  /* profile came from the library and needs freeing */
    int keep_mesh;                 /* keep the model loaded (slice needs it) */
    adaslice_mesh mesh;
    double up[3];                  /* --orient: the direction turned up; else 0, 0, 1 */
    adaslice_plan plan[METHOD_COUNT];   /* by method: the asked one, all of them with --compare */
    adaslice_error why[METHOD_COUNT];   /* result of each plan that was attempted */
    int planned[METHOD_COUNT];
    double *kappa;                 /* curvature per bin, for the curvature method (model only) */
    double ms_load, ms_profile, ms_plan;
} plan_job;

/* Option parsing: value_of and friends complain and return non-zero. */
int number_option(int argc, char **argv, int *i, int zero_ok, double *out);
int count_option(int argc, char **argv, int *i, size_t *out);
int name_option(int argc, char **argv, int *i, const char *const *names, int count, const char *choices, int *out);
int file_option(int argc, char **argv, int *i, const char **out);
/* The plan options of `plan` (argv[0] is the command's name). */
int parse_plan(int argc, char **argv, plan_args *a);
void plan_options_usage(FILE *f);
/* Profile (from the model or --profile) and plan; RC_OK or a complaint made. */
int run_plan(const plan_args *a, plan_job *j);
int write_outputs(const plan_args *a, const plan_job *j);
void job_free(plan_job *j);

typedef struct slice_args {
    const char *dir;
    const printer *preset;       /* or the three below */
    int width, height;
    double pitch;
    int supersample;             /* --aa S; 1: 1-bit masks */
    int slice_at;                /* 0 bottom, 1 middle, 2 top of each layer */
    int placed;                  /* --place X,Y given */
    double place[2];             /* the part's centre, mm from the plate's centre */
    int mirror_x, mirror_y;
    int rotate;                  /* quarter turns of the image, counter-clockwise */
    double display[2];           /* --display WxH in mm, or 0 */
    int svg;                     /* also the contours of each layer as SVG */
    int geometry_given;          /* --printer, --pixels, --pitch or --display */
} slice_args;
/* Takes the slice options out of argv; what is left (argv[0] first) goes to
   parse_plan. need_dir: -o JOBDIR is required. -1 after --help. */
int parse_slice(int argc, char **argv, slice_args *s, int *rest_argc, char **rest, int need_dir);
void slice_options_usage(FILE *f);

/* Layer masks as the display shows them, rendered bottom-up in one sweep. */
typedef struct layer_masks {
    const slice_args *s;
    const plan_job *j;
    adaslice_masker masker;
    adaslice_grid grid;
    unsigned char *image;          /* width x height, rows of `stride` bytes */
    size_t stride;
    int width, height, bits;
    double part[3];                /* the part's size, mm */
} layer_masks;
int layer_masks_open(layer_masks *m, const slice_args *s, const plan_job *j);
/* Layer k's (0-based; k never decreasing) mask into m->image. */
int layer_masks_render(layer_masks *m, size_t k);
void layer_masks_close(layer_masks *m);

int cmd_slice(int argc, char **argv);
int cmd_print(int argc, char **argv);
int cmd_orient(int argc, char **argv);
int cmd_saliency(int argc, char **argv);
/* The library's plan options for method m from the command line's. */
void plan_options_of(const plan_args *a, adaslice_method m, adaslice_plan_options *o);
/* Scores `count` directions on all cores; minima (best first, at most 4). */
int orient_search(const plan_args *a, const adaslice_mesh *mesh, size_t count, double alpha,
                  adaslice_direction_score **scores, size_t *minima, size_t *minima_count);
#endif
