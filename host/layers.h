/* Layer masks as a printer's display shows them: the display and mask
   options of the command line (slice and print), the part placed on the
   plate, and the masker's images turned and mirrored for the display,
   rendered bottom-up in one sweep. */
#ifndef ADASLICE_HOST_LAYERS_H
#define ADASLICE_HOST_LAYERS_H
#include <stdio.h>
#include "../adaslice.h"
#include "cure.h"
#include "plan_job.h"
#include "printer.h"
#include "codec/maskrows.h"

extern const char *const SLICE_AT[];   /* bottom, middle, top, envelope, core */
extern const char *const SLICE_AT_MEANING[]; /* what each gives, for the summary */
extern const char *const MIRRORS[];    /* none, x, y, xy */
extern const char *const ROTATIONS[];  /* 0, 90, 180, 270 */

typedef struct slice_args {
    const char *dir;             /* -o: a job directory, or a job file */
    const char *format;          /* --format, or NULL: by the extension of -o */
    const printer *preset;       /* or the three below */
    int width, height;           /* the plate's pixels along x and y (turned back if --rotate) */
    double pitch[2];             /* mm per plate pixel along x and y */
    int supersample;             /* --aa S; 1: 1-bit masks */
    int slice_at;                /* 0 bottom, 1 middle, 2 top of each layer, 3 envelope, 4 core */
    int placed;                  /* --place X,Y given */
    double place[2];             /* the part's centre, mm from the plate's centre */
    int mirror_x, mirror_y;
    int rotate;                  /* quarter turns of the image, counter-clockwise */
    double display[2];           /* --display WxH in mm, or 0 */
    int svg;                     /* also the contours of each layer as SVG */
    int force;                   /* --force: a job directory into a directory of other files */
    int geometry_given;          /* --printer, --pixels, --pitch or --display */
    cure_args cure;              /* exposure and motion (cure.h) */
    double memory_mb;            /* --memory: what the masks may take [half the memory] */
    int threads;                 /* --threads: layers coded at once [the cores] */
} slice_args;

/* Takes the slice options (with cure.h's) out of argv; what is left (argv[0]
   first) goes to parse_plan. need_dir: -o JOBDIR is required. -1 for --help
   (the caller prints its usage). */
int parse_slice(int argc, char **argv, slice_args *s, int *rest_argc, char **rest, int need_dir);
void slice_options_usage(FILE *f);

typedef struct layer_masks {
    const slice_args *s;
    const plan_job *j;
    adaslice_masker *band;         /* bands maskers, each of some of the part's rows, or one of all */
    int bands;
    adaslice_grid grid;
    unsigned char *image;          /* width x height, rows of `stride` bytes */
    size_t stride;
    int width, height, bits;
    int row_lo, row_hi;            /* the masker's rows [lo, hi) and bytes of a row */
    size_t byte_lo, byte_hi;       /* [lo, hi) the part can light: zero outside, always */
    int lit_rows[2];               /* the rows [0, 1) of the stored (turned) image the part can
                                      light: the others are dark in every layer */
    double part[3];                /* the part's size, mm */
} layer_masks;
/* The bytes the masks of s's grid take with `buffers` layers in flight: the
   masker and, per layer, its image and what coding it needs at worst. */
double layer_masks_bytes(const slice_args *s, int buffers);
/* RC_OK, or RC_USAGE after a complaint naming the grid and the bytes when
   they pass --memory: said before any work. */
int layer_masks_check(const slice_args *s, int buffers);
/* RC_OK when the part, its box lo to hi, fits s's plate where it is
   placed, else a complaint saying by how much it does not. */
int layer_masks_fit(const slice_args *s, const double lo[3], const double hi[3]);
/* Places the part on the plate (a complaint if it does not fit) and sets up
   the masker, split into about `bands` row bands (one for an open mesh,
   whose sections are cut whole), each rendered on its own. Reads only
   j->mesh, its box and j->args, so it may run while the profile and the
   plan are made. */
int layer_masks_open(layer_masks *m, const slice_args *s, const plan_job *j, int bands);
/* Band b's rows of layer k's (0-based; k never decreasing for a band) mask
   into out (m->image or another buffer of m->stride * m->height bytes),
   which holds zeros or an earlier mask of m: where the part cannot reach,
   out is left as it is. Bands write bytes of their own: different bands
   can render into one out at once on different threads. */
int layer_masks_render_band(layer_masks *m, int b, size_t k, unsigned char *out);
/* Whether each band is whole rows of the stored image (neither turned nor
   flipped across), so that it can be read where it is made: */
int layer_masks_band_is_rows(const layer_masks *m);
/* band b's rows of layer k read (mask_band_scan) into rows, in place of
   render_band's image: the stored image's rows the part can light among
   the band's. */
int layer_masks_scan_band(layer_masks *m, int b, size_t k, mask_band *rows);
/* Every band of layer k into out. */
int layer_masks_render(layer_masks *m, size_t k, unsigned char *out);
/* Band b's lit rays in its last layer (lit pixels times s*s): whole
   numbers, so the bands' add up to the whole layer's exactly. */
long long layer_masks_rays(const layer_masks *m, int b);
/* Where layer k is sliced, mm above the part's bottom. */
double layer_slice_height(const slice_args *s, const plan_job *j, size_t k);
void layer_masks_close(layer_masks *m);
#endif
