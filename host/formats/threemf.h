/* A 3MF project for FDM slicers: the model (the core 3MF schema) with the
   plan as a variable-layer-height profile that PrusaSlicer
   (Metadata/Slic3r_PE_layer_heights_profile.txt) and OrcaSlicer / Bambu
   Studio (Metadata/layer_heights_profile.txt) slice layer for layer.

   The profile is one step per layer, "object_id=1|0;h1;z1;h1;z1;h2;...;H;hK":
   the slicers look a layer's height up just above its bottom and add it to
   the layers below, so a flat step per layer reproduces every top exactly.
   The last top is the object's height (both slicers drop a profile that ends
   more than 1e-3 mm off it), each h comes from the tops as written (the
   slicers sum h, so no rounding adds up), and the first layer is the
   printer's first-layer height, which must equal h1 (OrcaSlicer compares
   them exactly). Metadata/Slic3r_PE.config carries first, minimum and
   maximum layer heights for PrusaSlicer. */
#ifndef ADASLICE_HOST_THREEMF_H
#define ADASLICE_HOST_THREEMF_H
#include "../plan_job.h"

/* The thickest layer a nozzle lays in PrusaSlicer unless told otherwise
   (max_layer_height 0: 75 % of the nozzle), and its floor for any layer. */
#define THREEMF_MAX_OF_NOZZLE 0.75
#define THREEMF_MIN_LAYER 0.01
/* The --nozzle range: micro nozzles are 0.1 mm, large-format printers'
   2-3 mm; from 0.05 a layer shared by two (threemf_write) stays over
   THREEMF_MIN_LAYER. */
#define THREEMF_MIN_NOZZLE 0.05
#define THREEMF_MAX_NOZZLE 10.0

typedef struct threemf_args {
    const char *path;            /* --3mf FILE, or NULL */
    double nozzle;               /* --nozzle MM */
    int nozzle_given;
    int hybrid;                  /* --hybrid */
    adaslice_hybrid_options contour; /* --max-angle, --reach, --max-rise, --resolution */
    int contour_given;           /* one of those was */
} threemf_args;

/* The optional part a hybrid plan adds for adaslice contour: the contour's
   limits and the faces (0-based, in the model's order) and heights it may
   contour, "; key = value" lines as Slic3r_PE.config's. */
#define THREEMF_CONTOUR_PART "Metadata/adaslice_contour.config"
/* What contour takes for its limits, from its command line or that part:
   slopes under CONTOUR_MAX_ANGLE degrees, pieces of CONTOUR_MIN_PIECE mm or
   more, and no limit of CONTOUR_MAX_LIMIT or more. */
#define CONTOUR_MAX_ANGLE 90.0
#define CONTOUR_MIN_PIECE 0.01
#define CONTOUR_MAX_LIMIT 1e6
/* The contour's limits by name, as that part and contour's options give
   them ("max_angle", "max_rise", "resolution"): RC_OK when contour takes
   x, else a complaint (status rc): `where` ("--max-rise ", "FILE: ... =
   "), the value and the range. */
int contour_limit_check(const char *where, const char *key, double x, int rc);

/* Takes --3mf FILE, --nozzle MM and the --hybrid options out of argv
   (argv[0] kept); RC_OK or RC_USAGE after a complaint. */
int threemf_options(int argc, char **argv, threemf_args *t, int *rest_argc, char **rest);
void threemf_usage(FILE *f);
/* The layer bounds against the nozzle, before planning; RC_OK or RC_USAGE
   after a complaint. */
int threemf_check_bounds(const threemf_args *t, const plan_args *a);
/* The --hybrid options against the plan's: RC_OK or RC_USAGE after a
   complaint. */
int threemf_check_hybrid(const threemf_args *t, const plan_args *a);
/* Writes t->path from the job's mesh (welded here) and plan; says on `note`
   which first-layer height and layer limits the printer profile needs.
   RC_OK or a complaint made, and no file. */
int threemf_write(const threemf_args *t, const plan_args *a, plan_job *j, FILE *note);

/* The project read back (for contour): the mesh as placed by the build
   item's transform, and the plan's layer tops (mm above the part's bottom). */
typedef struct threemf_project {
    adaslice_mesh mesh;
    double *tops;
    size_t layers;
    int transformed;             /* the build item had a transform */
    /* THREEMF_CONTOUR_PART's limits (a hybrid plan's), each 0 when absent */
    double max_angle, max_rise, resolution;
} threemf_project;
/* Reads the 3MF at path as threemf_write writes it (any 3MF with one object
   of one mesh and PrusaSlicer's layer height profile, and a hybrid plan's
   THREEMF_CONTOUR_PART if it has one); RC_OK, or a complaint naming the file
   and what is wrong, and nothing held. */
int threemf_read(const char *path, threemf_project *p);
void threemf_project_free(threemf_project *p);
#endif
