/* What plan, slice, print and orient share: the plan options of the command
   line and the job they run (load, weight, turn and profile the model, or read
   a profile; then plan), with its outputs (plan.csv, profile.csv, plot.svg). */
#ifndef ADASLICE_HOST_PLAN_JOB_H
#define ADASLICE_HOST_PLAN_JOB_H
#include <pthread.h>
#include <stdio.h>
#include "../adaslice.h"
#include "weights.h"

enum { METRIC_COUNT = 4, METHOD_COUNT = 5, MAPPING_COUNT = 3 };

extern const char *const METRIC_NAMES[];  /* by adaslice_metric */
extern const char *const METHOD_NAMES[];  /* by adaslice_method */
extern const char *const SAMPLER_NAMES[];
extern const char *const MAPPING_NAMES[]; /* by adaslice_mapping */
typedef struct metric_info { const char *label, *phi_axis, *eps_unit; } metric_info;
extern const metric_info METRICS[METRIC_COUNT];

enum { ORIENT_NONE = 0, ORIENT_GIVEN, ORIENT_BEST };

typedef struct plan_args {
    const char *model, *profile;   /* exactly one is set */
    adaslice_metric metric;
    adaslice_method method;
    double bin;                    /* 0: not given (the library's, or a --profile's z column) */
    double eps, tmin, tmax;
    double scale;                  /* 0: not given */
    double sharp;                  /* 0: pre-pass off */
    size_t budget;                 /* 0: none */
    uint32_t eps_units;            /* printer units for the optimal plan (print), 0: fine */
    int sampler;                   /* 0: exact, 1: LDI */
    size_t resolution;             /* LDI pixels across the largest extent */
    double memory_mb;              /* --memory: what the profile may take (slice: and the masks) */
    int orient;                    /* ORIENT_*: --orient X,Y,Z or best */
    double orient_up[3];           /* ORIENT_GIVEN: the direction to turn up */
    const char *out, *profile_out, *plot;
    int json, compare, help;
    int mapping;                   /* --mapping, an adaslice_mapping (--method curvature) */
    weight_args weights;           /* --saliency, --weights, --weight (model only) */
    const adaslice_hybrid_options *hybrid; /* plan --hybrid: contoured faces charged their
                                      residual (model, cusp only); NULL: planar */
} plan_args;

typedef struct plan_job {
    const plan_args *args;
    size_t triangles;              /* model only: after repair */
    adaslice_mesh_report repair;   /* model only: what loading repaired */
    adaslice_format format;
    adaslice_profile profile;
    int profiled;                  /* profile came from the library and needs freeing */
    int keep_mesh;                 /* keep the model loaded (slice needs it) */
    adaslice_mesh mesh;
    double lo[3], hi[3];           /* model only: the turned mesh's box, taken once */
    double up[3];                  /* --orient: the direction turned up; else 0, 0, 1 */
    adaslice_plan plan[METHOD_COUNT];   /* by method: the asked one, all of them with --compare */
    adaslice_error why[METHOD_COUNT];   /* result of each plan that was attempted */
    int planned[METHOD_COUNT];
    adaslice_plan uniform;         /* --compare: plan_uniform_no_worse than the optimal plan */
    int uniform_found;
    double *kappa;                 /* curvature per bin, for the curvature method (model only) */
    /* --hybrid: the plan is on `profile`, the hybrid one; these say what the
       contour leaves and what planar layers of the same printed error take */
    float *residual;               /* per face: -1 planar, else its residual bound (mm) */
    adaslice_hybrid_report hybrid;
    adaslice_profile planar_profile; /* the cusp profile without the contour */
    adaslice_profile walls_profile;  /* ... with the contoured faces weighing 0 */
    double walls_worst;            /* the plan's worst layer error on walls_profile */
    double printed_worst;          /* max(walls_worst, hybrid.residual) */
    adaslice_plan planar;          /* optimal on planar_profile at eps printed_worst */
    adaslice_error planar_why;     /* its result (infeasible: finer than tmin) */
    int planar_found;
    int planar_finest;             /* no plan reaches printed_worst: planar is uniform tmin */
    double fdm_seconds, planar_fdm_seconds; /* --3mf: fdm.h's times of the plan and of planar */
    double ms_load, ms_repair, ms_profile, ms_plan;  /* model only: load without the repair, then the repair */
    /* Called with the mesh loaded and turned, and its box, before it is
       profiled: a check (the plate's fit) that should stop the job before
       the work. */
    int (*loaded)(void *ctx, const adaslice_mesh *mesh, const double lo[3], const double hi[3]);
    void *loaded_ctx;
    /* If not NULL (with keep_mesh): called on a thread of its own beside
       the profile and the plan once the mesh is loaded, turned and checked,
       for what needs only j->mesh (slice sets up its masker there), which
       neither touches. Joined before run_plan returns, whose result it is
       when the rest succeeded. What it starts may outlive it (slice's
       previews): j->mesh stays, even when the plan fails, until job_free,
       which the caller calls after joining that. */
    int (*beside)(void *ctx);
    void *beside_ctx;
    pthread_t beside_thread;
    int beside_running, beside_rc;
} plan_job;

/* The plan options of `plan` (argv[0] is the command's name); RC_OK or a
   complaint made. */
int parse_plan(int argc, char **argv, plan_args *a);
/* The file the plan comes from, for messages: the MODEL, or --profile's. */
const char *plan_source(const plan_args *a);
/* The command whose help lists the plan options: each lists those it takes. */
enum { FOR_PLAN = 1, FOR_SLICE = 2, FOR_ORIENT = 4, FOR_PRINT = 8 };
void plan_options_usage(FILE *f, unsigned command);
/* The library's plan options for method m from the command line's. */
void plan_options_of(const plan_args *a, adaslice_method m, adaslice_plan_options *o);
/* Profile (from the model or --profile) and plan; RC_OK or a complaint made. */
int run_plan(const plan_args *a, plan_job *j);
int write_outputs(const plan_args *a, const plan_job *j);
/* The one line saying which sharp-change planes the planner moved or dropped
   so that eps stays feasible, at which heights and why, into out ("" when
   none was). */
void plan_changes_line(const adaslice_plan *p, double bin, char *out, size_t cap);
/* --out, --profile-out and --plot can be written (output_check), and none
   is another's file or the command's own output `option` `path` (NULL:
   none; checked by its command): before the model is loaded. */
int check_plan_outputs(const plan_args *a, const char *option, const char *path);
/* The thickest uniform layers within the bounds of `than` whose worst error is
   no larger than its worst: what the same quality costs without adaptive
   layers. 1 with *out made (free it), 0 if even the thinnest are worse. */
int plan_uniform_no_worse(const adaslice_profile *profile, const adaslice_plan *than, adaslice_plan *out);
/* The build-direction search (search.h) with these plan options: orient and
   --orient best. */
int plan_orient_search(const plan_args *a, const adaslice_mesh *mesh, size_t count, double alpha,
                       adaslice_direction_score **scores, size_t *minima, size_t *minima_count);
void job_free(plan_job *j);
/* Models come in metres or micrometres as well as millimetres, and the file
   does not say which: a part under a millimetre each way, or over a metre
   tall, was most likely read in the wrong unit. */
#define UNITS_SMALL_MM 1.0
#define UNITS_TALL_MM 1000.0
/* The thickest layer --tmax, --uniform (and --tmin, --bin) may ask: a
   concrete printer's courses are a few cm; past this a value is a typo or
   the wrong unit, and near DBL_MAX heights overflow. */
#define PLAN_LAYER_MAX_MM 100.0
/* "; a model in micrometres? --scale 0.001 ..." for a part over UNITS_TALL_MM
   tall, else "": the tail of a message. */
void units_hint(double tall_mm, char *out, size_t size);
#endif
