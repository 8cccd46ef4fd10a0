/* The layer loop on every core: layers are rendered in order on the calling
   thread (the masker sweeps bottom-up), coded on worker threads (the
   format's `encode`: PNGs, run-length codes), and put into the job in order
   on the calling thread (the format's `put`), so the job is the same bytes
   whatever the number of threads. */
#ifndef ADASLICE_HOST_PIPELINE_H
#define ADASLICE_HOST_PIPELINE_H
#include <stddef.h>
#include "jobfile.h"

typedef struct pipeline_job {
    const job_format *format;
    void *writer;                /* the format's, open */
    size_t layers;
    size_t image_bytes, stride;  /* of each layer's image */
    int threads;                 /* 1: everything on the calling thread */
    /* Layer k into image; RC_OK or a complaint made (which stops the job). */
    int (*render)(void *ctx, size_t k, unsigned char *image);
    /* Layer k is in the job. */
    void (*done)(void *ctx, size_t k);
    void *ctx;
} pipeline_job;

/* Images in flight for `threads` threads (for a memory estimate). */
int pipeline_images(int threads);
/* Every layer through render, encode and put; RC_OK or the first failure,
   complained about. Leaves the writer to the caller's close. */
int pipeline_run(const pipeline_job *job);
/* The cores online, at least 1. */
int pipeline_cores(void);
#endif
