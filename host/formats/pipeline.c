/* The layer loop on every core: see pipeline.h. A ring of slots, each an
   image and its blob, moves free -> rendering -> rendered -> encoded -> put
   -> free. Every thread, the calling one among them, takes whatever step is
   ready: a band of a layer (each band held by one thread at a time, as its
   masker sweeps bottom-up), a slot's coding, or the next layer into the job
   (the writer held by one thread at a time, the job written in order). One
   masker for the whole layer, held by one thread, left the other waiting
   whenever that thread was descheduled (two threads beside a busy process
   lost to one); a band is a sixteenth of a layer's masks. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "pipeline.h"
#include "../report.h"

#include <pthread.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { SLOT_FREE, SLOT_RENDERING, SLOT_BUSY, SLOT_RENDERED, SLOT_ENCODED };

typedef struct slot {
    unsigned char *image;
    size_t k;
    int state, rc;
    int unrendered;              /* SLOT_RENDERING: its bands not yet rendered */
    job_blob blob;
} slot;

typedef struct band {
    size_t next;                 /* the layer it renders next */
    int busy;                    /* a thread is rendering it */
} band;

typedef struct pipeline {
    const pipeline_job *job;
    slot *slots;
    int count;
    band *bands;
    int band_count;
    pthread_mutex_t lock;
    pthread_cond_t change;       /* a step became ready, or the job is over */
    int waiting;                 /* threads asleep on change */
    size_t next_slot, next_put;  /* layers given a slot so far; the next into the job */
    int putting;                 /* the writer: a thread's */
    int rc;                      /* the first failure, which stops every thread */
} pipeline;

int pipeline_cores(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

/* Four images a thread: coded layers wait in them for the one before, which
   may take longer, so that rendering need not wait for a free one. */
int pipeline_images(int threads) { return threads > 1 ? 4 * threads : 1; }

int pipeline_bands(int threads) { return threads > 1 ? 8 * threads : 1; }

/* The lowest layer waiting in `state`, or NULL. */
static slot *lowest(pipeline *p, int state)
{
    slot *best = NULL;
    int i;
    for (i = 0; i < p->count; i++)
        if (p->slots[i].state == state && (!best || p->slots[i].k < best->k)) best = &p->slots[i];
    return best;
}

/* The band to render next and its layer's slot (given one if it has none
   yet), or -1: of the bands no thread holds, the one furthest behind, so
   that the lowest layer is finished first. A band's layer has a slot when
   another band went ahead; else all the free bands wait for the same new one. */
static int next_band(pipeline *p, slot **into)
{
    size_t k;
    int b, best = -1, i;
    for (b = 0; b < p->band_count; b++)
        if (!p->bands[b].busy && p->bands[b].next < p->job->layers && (best < 0 || p->bands[b].next < p->bands[best].next))
            best = b;
    if (best < 0) return -1;
    k = p->bands[best].next;
    if (k < p->next_slot) {
        for (i = 0; i < p->count; i++)
            if (p->slots[i].state == SLOT_RENDERING && p->slots[i].k == k) { *into = &p->slots[i]; return best; }
        return -1; /* not reached: a layer keeps its slot until every band is in */
    }
    if (!(*into = lowest(p, SLOT_FREE))) return -1;
    (*into)->state = SLOT_RENDERING;
    (*into)->k = p->next_slot++;
    (*into)->unrendered = p->band_count;
    return best;
}

/* Called with the lock held, after a step: wakes the threads asleep. */
static void changed(pipeline *p)
{
    if (p->waiting) pthread_cond_broadcast(&p->change);
}

/* One thread's share: steps until every layer is put or one failed. The
   next layer in order goes into the job first (it frees an image), then a
   band is rendered while its layer has an image, else the lowest rendered
   layer is coded. */
static void take_steps(pipeline *p)
{
    const pipeline_job *job = p->job;
    double ms[3] = {0, 0, 0}, t0; /* this thread's, added up under the lock at the end */
    int i, b;
    pthread_mutex_lock(&p->lock);
    while (!p->rc && p->next_put < job->layers) {
        slot *s = lowest(p, SLOT_ENCODED);
        int rc;
        if (!p->putting && s && s->k == p->next_put) {
            s->state = SLOT_BUSY;
            p->putting = 1;
            pthread_mutex_unlock(&p->lock);
            rc = s->rc;
            if (!rc) {
                t0 = now_ms();
                if (job->ready) job->ready(job->ctx, s->k);
                rc = job_put(job->out, s->k, &s->blob);
                ms[2] += now_ms() - t0;
                if (!rc && job->done) job->done(job->ctx, s->k);
            }
            free(s->blob.data);
            memset(&s->blob, 0, sizeof s->blob);
            pthread_mutex_lock(&p->lock);
            s->state = SLOT_FREE;
            p->next_put++;
            p->putting = 0;
            if (rc && !p->rc) p->rc = rc;
        } else if ((b = next_band(p, &s)) >= 0) {
            size_t k = p->bands[b].next;
            p->bands[b].busy = 1;
            pthread_mutex_unlock(&p->lock);
            t0 = now_ms();
            rc = job->render(job->ctx, b, k, s->image);
            ms[0] += now_ms() - t0;
            pthread_mutex_lock(&p->lock);
            p->bands[b].busy = 0;
            p->bands[b].next++;
            if (--s->unrendered == 0) s->state = SLOT_RENDERED;
            if (rc && !p->rc) p->rc = rc;
        } else if ((s = lowest(p, SLOT_RENDERED)) != NULL) {
            s->state = SLOT_BUSY;
            pthread_mutex_unlock(&p->lock);
            t0 = now_ms();
            s->rc = job->out->format->encode(job->out->state, s->k, s->image, job->stride, &s->blob);
            ms[1] += now_ms() - t0;
            pthread_mutex_lock(&p->lock);
            s->state = SLOT_ENCODED;
        } else {
            p->waiting++;
            pthread_cond_wait(&p->change, &p->lock);
            p->waiting--;
            continue;
        }
        changed(p);
    }
    changed(p); /* over: the others leave too */
    for (i = 0; i < 3 && job->stage_ms; i++) job->stage_ms[i] += ms[i];
    pthread_mutex_unlock(&p->lock);
}

static void *worker(void *arg)
{
    take_steps((pipeline *)arg);
    return NULL;
}

void pipeline_keep_memory(void)
{
#ifdef __GLIBC__
    /* The repair's, the profile's and the masker's arrays were each new
       memory, first touched page by page, as glibc hands large freed blocks
       back to the system, and a first touch costs as much as sweeping the
       page many times over (64 MB: 0.2 s against 3 ms here): the turbine
       blade's profile took 31 ms in new pages, 7 ms in the repair's freed
       ones. Fixed thresholds keep freed memory for the next stage. (The
       layers' coders keep their own buffers: png.c's pool.) */
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
}

int pipeline_run(const pipeline_job *job)
{
    pipeline p;
    pthread_t threads[64];
    int helpers = job->threads > 1 ? job->threads - 1 : 0, started = 0, i, rc = RC_OK;
    if (helpers > 63) helpers = 63;
    memset(&p, 0, sizeof p);
    p.job = job;
    p.count = pipeline_images(helpers + 1);
    p.band_count = job->bands > 1 ? job->bands : 1;
    p.slots = (slot *)calloc((size_t)p.count, sizeof *p.slots);
    p.bands = (band *)calloc((size_t)p.band_count, sizeof *p.bands);
    if (!p.slots || !p.bands) {
        free(p.slots);
        free(p.bands);
        return complain(RC_FAIL, "out of memory");
    }
    for (i = 0; i < p.count; i++)
        if (!(p.slots[i].image = (unsigned char *)calloc(job->image_bytes ? job->image_bytes : 1, 1))) {
            rc = complain(RC_FAIL, "out of memory for %d layer image%s of %zu bytes", p.count, plural((size_t)p.count),
                          job->image_bytes);
            goto done;
        }
    pthread_mutex_init(&p.lock, NULL);
    pthread_cond_init(&p.change, NULL);
    for (; started < helpers; started++) /* fewer threads to be had: the job is the same on fewer */
        if (pthread_create(&threads[started], NULL, worker, &p) != 0) break;
    take_steps(&p);
    for (i = 0; i < started; i++) pthread_join(threads[i], NULL);
    rc = p.rc;
    pthread_cond_destroy(&p.change);
    pthread_mutex_destroy(&p.lock);
done:
    for (i = 0; i < p.count; i++) {
        free(p.slots[i].blob.data);
        free(p.slots[i].image);
    }
    free(p.slots);
    free(p.bands);
    return rc;
}
