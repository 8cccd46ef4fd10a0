/* The layer loop on every core: layers are rendered in row bands, each
   band's layers in order (each band's masker sweeps bottom-up) and
   different bands at once, coded several at once (the format's `encode`:
   PNGs, run-length codes), and put into the job one at a time in order
   (job_put), so the job is the same bytes whatever the number of threads.
   Each step runs on whichever of the threads, the calling one among them,
   is free for it. */
#ifndef ADASLICE_HOST_PIPELINE_H
#define ADASLICE_HOST_PIPELINE_H
#include <stddef.h>
#include "jobfile.h"

typedef struct pipeline_job {
    job_writer *out;             /* open */
    size_t layers;
    size_t image_bytes, stride;  /* of each layer's image */
    int threads;                 /* the calling one and threads - 1 more; 1: all on the calling one */
    int bands;                   /* render's bands of each layer, at least 1 */
    /* Band b of layer k into image, or with by_bands read into rows (image
       NULL); RC_OK or a complaint made (which stops the job). Called for
       each band with k = 0, 1, ... in turn, on any thread; two bands at
       once on different threads (each must write bytes of its own), never
       one band twice at once. The images start zeroed and keep what render
       leaves in them (the coding only reads them), so it need write only
       where a layer can differ. */
    int (*render)(void *ctx, int b, size_t k, unsigned char *image, mask_band *rows);
    /* Each band read where it is made, and the layer coded from the bands'
       rows (the format's encode_bands): no images. */
    int by_bands;
    /* If not NULL: layer k, every band rendered and coded, goes into the
       job next (in turn, on any thread). */
    void (*ready)(void *ctx, size_t k);
    /* Layer k is in the job (in turn, on any thread). */
    void (*done)(void *ctx, size_t k);
    void *ctx;
    /* If not NULL: the milliseconds spent rendering, coding and putting are
       added to [0], [1] and [2], each summed over the threads (so with more
       than one they can add up to more than the run took). */
    double *stage_ms;
} pipeline_job;

/* Images in flight for `threads` threads (for a memory estimate). */
int pipeline_images(int threads);
/* The row bands to render each layer in on `threads` threads: many more
   than the threads, so that one descheduled while it renders a band holds
   up a small part of a layer and the others have bands to go on with. */
int pipeline_bands(int threads);
/* Every layer through render, encode and put; RC_OK or the first failure,
   complained about. Leaves the writer to the caller's close. */
int pipeline_run(const pipeline_job *job);
/* The cores online, at least 1. */
int pipeline_cores(void);
#endif
