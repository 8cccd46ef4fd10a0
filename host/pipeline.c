/* The layer loop on every core: see pipeline.h. A ring of slots, each an
   image and its blob, moves free -> rendered (by the calling thread) ->
   encoded (by a worker) -> put (by the calling thread, in order) -> free. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "pipeline.h"
#include "report.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { SLOT_FREE, SLOT_RENDERED, SLOT_ENCODING, SLOT_ENCODED };

typedef struct slot {
    unsigned char *image;
    size_t k;
    int state, rc;
    job_blob blob;
} slot;

typedef struct pipeline {
    const pipeline_job *job;
    slot *slots;
    int count;
    pthread_mutex_t lock;
    pthread_cond_t work;         /* a slot was rendered, or the job is over */
    pthread_cond_t coded;        /* a slot was encoded */
    int over;
} pipeline;

int pipeline_cores(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

/* Two images a worker: one it codes while the next waits for it. */
int pipeline_images(int threads) { return threads > 1 ? 2 * threads : 1; }

static void encode_slot(const pipeline_job *job, slot *s)
{
    s->rc = job->format->encode(job->writer, s->k, s->image, job->stride, &s->blob);
}

/* The lowest layer waiting in `state`, or NULL. */
static slot *lowest(pipeline *p, int state)
{
    slot *best = NULL;
    int i;
    for (i = 0; i < p->count; i++)
        if (p->slots[i].state == state && (!best || p->slots[i].k < best->k)) best = &p->slots[i];
    return best;
}

static void *worker(void *arg)
{
    pipeline *p = (pipeline *)arg;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        slot *s = lowest(p, SLOT_RENDERED);
        if (!s) {
            if (p->over) break;
            pthread_cond_wait(&p->work, &p->lock);
            continue;
        }
        s->state = SLOT_ENCODING;
        pthread_mutex_unlock(&p->lock);
        encode_slot(p->job, s);
        pthread_mutex_lock(&p->lock);
        s->state = SLOT_ENCODED;
        pthread_cond_signal(&p->coded);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

int pipeline_run(const pipeline_job *job)
{
    pipeline p;
    pthread_t threads[64];
    int workers = job->threads > 1 ? job->threads : 0, started = 0, i, rc = RC_OK;
    size_t next_render = 0, next_put = 0;
    if (workers > 64) workers = 64;
    memset(&p, 0, sizeof p);
    p.job = job;
    p.count = pipeline_images(workers ? workers : 1);
    if (!(p.slots = (slot *)calloc((size_t)p.count, sizeof *p.slots))) return complain(RC_FAIL, "out of memory");
    for (i = 0; i < p.count; i++)
        if (!(p.slots[i].image = (unsigned char *)malloc(job->image_bytes ? job->image_bytes : 1))) {
            rc = complain(RC_FAIL, "out of memory for %d layer image%s of %zu bytes", p.count, plural((size_t)p.count),
                          job->image_bytes);
            goto done;
        }
    pthread_mutex_init(&p.lock, NULL);
    pthread_cond_init(&p.work, NULL);
    pthread_cond_init(&p.coded, NULL);
    for (; started < workers; started++)
        if (pthread_create(&threads[started], NULL, worker, &p) != 0) break;
    if (workers && !started) workers = 0; /* no thread to be had: all on this one */

    pthread_mutex_lock(&p.lock);
    while (next_put < job->layers && !rc) {
        slot *s = lowest(&p, SLOT_ENCODED);
        if (s && s->k == next_put) { /* the next layer is coded: into the job */
            pthread_mutex_unlock(&p.lock);
            rc = s->rc;
            if (!rc) {
                rc = job->format->put(job->writer, s->k, &s->blob);
                if (!rc && job->done) job->done(job->ctx, s->k);
            }
            pthread_mutex_lock(&p.lock);
            free(s->blob.data);
            memset(&s->blob, 0, sizeof s->blob);
            s->state = SLOT_FREE;
            next_put++;
            continue;
        }
        if (next_render < job->layers && (s = lowest(&p, SLOT_FREE)) != NULL) {
            s->state = SLOT_ENCODING; /* ours while it renders */
            pthread_mutex_unlock(&p.lock);
            s->k = next_render++;
            rc = job->render(job->ctx, s->k, s->image);
            if (!rc && !workers) encode_slot(job, s);
            pthread_mutex_lock(&p.lock);
            s->state = rc ? SLOT_FREE : workers ? SLOT_RENDERED : SLOT_ENCODED;
            if (workers) pthread_cond_signal(&p.work);
            continue;
        }
        pthread_cond_wait(&p.coded, &p.lock);
    }
    p.over = 1;
    pthread_cond_broadcast(&p.work);
    pthread_mutex_unlock(&p.lock);
    for (i = 0; i < started; i++) pthread_join(threads[i], NULL);
    pthread_cond_destroy(&p.coded);
    pthread_cond_destroy(&p.work);
    pthread_mutex_destroy(&p.lock);
done:
    for (i = 0; i < p.count; i++) {
        free(p.slots[i].blob.data);
        free(p.slots[i].image);
    }
    free(p.slots);
    return rc;
}
