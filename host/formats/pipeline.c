/* The layer loop on every core: see pipeline.h. A ring of slots, each an
   image and its blob, moves free -> rendering -> rendered -> encoded -> put
   -> free. Every thread, the calling one among them, takes whatever step is
   ready: a band of a layer (each band held by one thread at a time, as its
   masker sweeps bottom-up), a slot's coding, or the next layer into the job
   (the writer held by one thread at a time, the job written in order). One
   masker for the whole layer, held by one thread, left the other waiting
   whenever that thread was descheduled (two threads beside a busy process
   lost to one); a band is an eighth of a layer's masks on two threads. Each
   thread keeps to bands of its own while they can go on (a band's sweep
   state stays in one core's cache: 3 % of the turbine blade's time) and
   takes any other's when they cannot, so one descheduled still holds up
   only its band. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "pipeline.h"
#include "../output.h"
#include "../pages.h"
#include "../report.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { SLOT_FREE, SLOT_RENDERING, SLOT_BUSY, SLOT_RENDERED, SLOT_ENCODED };

typedef struct slot {
    unsigned char *image;        /* or, by_bands, its bands' rows: */
    mask_band *rows;
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
    int threads;                 /* taking steps: 0, 1, ... each (take_steps' me) */
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

/* Four a thread: each band sets up again the facets that cross into it, and
   sixteen on two threads rendered the turbine blade 4 % slower than eight. */
int pipeline_bands(int threads) { return threads > 1 ? 4 * threads : 1; }

/* The lowest layer waiting in `state`, or NULL. */
static slot *lowest(pipeline *p, int state)
{
    slot *best = NULL;
    int i;
    for (i = 0; i < p->count; i++)
        if (p->slots[i].state == state && (!best || p->slots[i].k < best->k)) best = &p->slots[i];
    return best;
}

/* Band b's layer's slot, given one if the layer has none yet, or NULL when
   no image is free for it. */
static slot *band_slot(pipeline *p, int b)
{
    size_t k = p->bands[b].next;
    slot *s;
    int i;
    if (k < p->next_slot) {
        for (i = 0; i < p->count; i++)
            if (p->slots[i].state == SLOT_RENDERING && p->slots[i].k == k) return &p->slots[i];
        return NULL; /* not reached: a layer keeps its slot until every band is in */
    }
    if (!(s = lowest(p, SLOT_FREE))) return NULL;
    s->state = SLOT_RENDERING;
    s->k = p->next_slot++;
    s->unrendered = p->band_count;
    return s;
}

/* The band thread `me` renders next and its layer's slot, or -1: of the
   bands no thread holds, its own one furthest behind if that can go on, else
   any furthest behind, so that the lowest layer is finished first. A
   band's layer has a slot when another band went ahead; else the band waits
   for a free one. */
static int next_band(pipeline *p, int me, slot **into)
{
    int b, best = -1, own = -1;
    for (b = 0; b < p->band_count; b++) {
        if (p->bands[b].busy || p->bands[b].next >= p->job->layers) continue;
        if (best < 0 || p->bands[b].next < p->bands[best].next) best = b;
        if (b * p->threads / p->band_count == me && (own < 0 || p->bands[b].next < p->bands[own].next)) own = b;
    }
    if (own >= 0 && (*into = band_slot(p, own)) != NULL) return own;
    if (best >= 0 && best != own && (*into = band_slot(p, best)) != NULL) return best;
    return -1;
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
static void take_steps(pipeline *p, int me)
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
        } else if ((b = next_band(p, me, &s)) >= 0) {
            size_t k = p->bands[b].next;
            p->bands[b].busy = 1;
            pthread_mutex_unlock(&p->lock);
            t0 = now_ms();
            rc = job->render(job->ctx, b, k, s->image, s->rows ? &s->rows[b] : NULL);
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
            s->rc = s->rows ? job->out->format->encode_bands(job->out->state, s->k, s->rows, p->band_count, &s->blob)
                            : job->out->format->encode(job->out->state, s->k, s->image, job->stride, &s->blob);
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

typedef struct worker { pipeline *p; int me; } worker;

static void *work(void *arg)
{
    worker *w = (worker *)arg;
    take_steps(w->p, w->me);
    return NULL;
}

int pipeline_run(const pipeline_job *job)
{
    pipeline p;
    pthread_t threads[64];
    worker workers[64];
    unsigned char *images = NULL;
    int helpers = job->threads > 1 ? job->threads - 1 : 0, started = 0, i, b, rc = RC_OK;
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
    if (job->by_bands) {
        for (i = 0; i < p.count; i++)
            if (!(p.slots[i].rows = (mask_band *)calloc((size_t)p.band_count, sizeof(mask_band)))) {
                rc = complain(RC_FAIL, "out of memory");
                goto done;
            }
    } else {
        /* one block, in huge pages where there are any: eight 1-bit images of
           3840 x 2400 took 2,250 first touches, 4-7 ms before the first layer */
        if (job->image_bytes > ((size_t)-1) / (size_t)p.count ||
            !(images = (unsigned char *)pages_alloc((size_t)p.count * job->image_bytes))) {
            rc = complain(RC_FAIL, "out of memory for %d layer image%s of %zu bytes", p.count, plural((size_t)p.count),
                          job->image_bytes);
            goto done;
        }
        memset(images, 0, (size_t)p.count * job->image_bytes);
        for (i = 0; i < p.count; i++) p.slots[i].image = images + (size_t)i * job->image_bytes;
    }
    pthread_mutex_init(&p.lock, NULL);
    pthread_cond_init(&p.change, NULL);
    p.threads = helpers + 1;
    for (; started < helpers; started++) { /* fewer threads to be had: the job is the same on fewer */
        workers[started].p = &p;
        workers[started].me = started + 1;
        if (output_thread_start(&threads[started], work, &workers[started]) != 0) break;
    }
    take_steps(&p, 0);
    for (i = 0; i < started; i++) pthread_join(threads[i], NULL);
    rc = p.rc;
    pthread_cond_destroy(&p.change);
    pthread_mutex_destroy(&p.lock);
done:
    for (i = 0; i < p.count; i++) {
        free(p.slots[i].blob.data);
        for (b = 0; p.slots[i].rows && b < p.band_count; b++) mask_band_free(&p.slots[i].rows[b]);
        free(p.slots[i].rows);
    }
    free(images);
    free(p.slots);
    free(p.bands);
    return rc;
}
