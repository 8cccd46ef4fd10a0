/* The build-direction search on all of the host's cores: see search.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "search.h"
#include "output.h"
#include "pages.h"
#include "report.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct search {
    const adaslice_orienter *o;
    adaslice_direction_score *scores;
    const double *dirs;
    size_t count, next, done;    /* next direction to take, directions finished */
    pthread_mutex_t lock;
    adaslice_error err;
    int failed;
    progress bar;
} search;

/* Each direction allocates and frees the same large arrays: a worker keeps
   its freed blocks for the next direction, since returning them to the system
   (munmap) and faulting them back in serialises the threads in the kernel. */
typedef struct block_cache {
    void *block[8];
    size_t size[8];
} block_cache;

typedef union block_head { size_t size; double align_d; void *align_p; } block_head;

static void *cache_alloc(void *user, size_t size)
{
    block_cache *c = (block_cache *)user;
    int i, best = -1;
    block_head *h;
    for (i = 0; i < 8; i++)
        if (c->block[i] && c->size[i] >= size && (best < 0 || c->size[i] < c->size[best])) best = i;
    if (best >= 0) {
        void *p = c->block[best];
        c->block[best] = NULL;
        return p;
    }
    h = (block_head *)pages_alloc(sizeof *h + size);
    if (!h) return NULL;
    h->size = size;
    return h + 1;
}

static void cache_free(void *user, void *p)
{
    block_cache *c = (block_cache *)user;
    block_head *h = (block_head *)p - 1;
    int i, smallest = 0;
    for (i = 0; i < 8; i++) {
        if (!c->block[i]) { c->block[i] = p; c->size[i] = h->size; return; }
        if (c->size[i] < c->size[smallest]) smallest = i;
    }
    if (c->size[smallest] < h->size) { /* keep the larger block */
        free((block_head *)c->block[smallest] - 1);
        c->block[smallest] = p;
        c->size[smallest] = h->size;
        return;
    }
    free(h);
}

static void cache_clear(block_cache *c)
{
    int i;
    for (i = 0; i < 8; i++)
        if (c->block[i]) free((block_head *)c->block[i] - 1);
}

/* Workers take directions in small batches until none are left, the batches
   shrinking to one as the end nears, so that the threads finish together (a
   last batch of 8 directions on the plate is 0.2 s that one thread works alone). */
static void *search_worker(void *arg)
{
    search *s = (search *)arg;
    block_cache cache;
    adaslice_allocator al;
    adaslice_orienter mine = *s->o; /* the same options, this worker's allocator */
    memset(&cache, 0, sizeof cache);
    al.alloc = cache_alloc;
    al.free = cache_free;
    al.user = &cache;
    mine.allocator = al;
    mine.profile.allocator = &al;
    mine.plan.allocator = &al;
    for (;;) {
        size_t first, end, i, take;
        pthread_mutex_lock(&s->lock);
        first = s->next;
        take = (s->count - first) / 16;
        take = take < 1 ? 1 : take > 8 ? 8 : take;
        end = s->failed || first == s->count ? first : first + take;
        s->next = end;
        pthread_mutex_unlock(&s->lock);
        if (first == end) break;
        for (i = first; i < end; i++) {
            adaslice_error e;
            if (adaslice_orienter_score(&mine, s->dirs + 3 * i, &s->scores[i], &e) != ADASLICE_OK) {
                pthread_mutex_lock(&s->lock);
                if (!s->failed) { s->failed = 1; s->err = e; }
                s->next = s->count;
                pthread_mutex_unlock(&s->lock);
                break;
            }
        }
        pthread_mutex_lock(&s->lock);
        s->done += end - first;
        progress_show(&s->bar, s->done, s->count, "directions", NULL);
        pthread_mutex_unlock(&s->lock);
    }
    cache_clear(&cache);
    return NULL;
}

/* The most one thread's direction can hold: its profile over the part's
   longest extent (the box's diagonal) in bins, and the range-maximum table
   over it, a level for each doubling of the longest facet (the orienter's
   longest edge: a facet along the whole part defeats the table's chunking),
   twice, as a worker keeps freed blocks for the next direction; plus the
   facets' and corners' own arrays. (A part 4 m tall held 1.36 GB on two
   threads; one in micrometres asked 14 GB a thread of a 23 GB machine and
   was killed.) */
static double search_thread_bytes(const adaslice_orienter *o, double bin, double *bins, double *diagonal)
{
    double lo[3], hi[3], d = 0, levels;
    int k;
    adaslice_mesh_bounds(o->mesh, lo, hi);
    for (k = 0; k < 3; k++) d += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    *diagonal = sqrt(d);
    *bins = ceil(*diagonal / bin) + 1;
    levels = floor(log2(fmin(*bins, o->longest_edge / bin + 2))) + 1;
    return 8 * *bins * (2 * levels + 3) + 32 * (double)o->mesh->triangle_count + 16 * (double)o->mesh->vertex_count;
}

/* Scores `count` lattice directions on all the host's cores; the minima come
   best first. Returns RC_OK or a complaint made. */
int orient_search(const char *model, const adaslice_mesh *mesh, const adaslice_profile_options *po, const adaslice_plan_options *pl,
                  size_t count, double alpha, double memory_limit, adaslice_direction_score **scores, size_t *minima,
                  size_t *minima_count)
{
    adaslice_orienter o;
    adaslice_error e;
    pthread_t threads[16];
    search s;
    double *dirs;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int n_threads = cores < 1 ? 1 : cores > 16 ? 16 : (int)cores, t, started = 0;

    if (adaslice_orienter_init(&o, mesh, po, pl, &e) != ADASLICE_OK) return library_error_in(model, &e);
    if (memory_limit > 0) {
        double bin = po->bin > 0 ? po->bin : ADASLICE_DEFAULT_BIN, bins, diagonal,
               need = n_threads * search_thread_bytes(&o, bin, &bins, &diagonal);
        char need_text[32], limit_text[32];
        if (!(need < 1e18)) { /* a bin near the smallest double: bins and bytes past any machine */
            adaslice_orienter_free(&o);
            return complain(RC_FAIL, "%s: --bin %g mm is too fine: the part's %g mm diagonal would be %.3g bins",
                            model, bin, diagonal, bins);
        }
        if (need > memory_limit) {
            adaslice_orienter_free(&o);
            return complain(RC_FAIL, "%s: the search needs up to %s (%d thread%s, each a profile of up to %.0f bins of %g mm "
                                     "along the part's %g mm diagonal), more than --memory %s; a model in micrometres? "
                                     "--scale 0.001; or a larger --bin", model, size_text(need, need_text), n_threads,
                            n_threads == 1 ? "" : "s", bins, bin, diagonal, size_text(memory_limit, limit_text));
        }
    }
    memset(&s, 0, sizeof s);
    dirs = (double *)malloc(3 * (count + SEARCH_AXES) * sizeof *dirs);
    *scores = (adaslice_direction_score *)calloc(count + SEARCH_AXES, sizeof **scores);
    if (!dirs || !*scores) {
        free(dirs);
        free(*scores);
        *scores = NULL;
        adaslice_orienter_free(&o);
        return complain(RC_FAIL, "out of memory for %zu direction%s", count, plural(count));
    }
    adaslice_fibonacci_directions(count, dirs);
    {
        static const double axes[SEARCH_AXES][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
        memcpy(dirs + 3 * count, axes, sizeof axes);
    }
    count += SEARCH_AXES;
    s.o = &o;
    s.scores = *scores;
    s.dirs = dirs;
    s.count = count;
    pthread_mutex_init(&s.lock, NULL);
    for (t = 0; t < n_threads; t++)
        if (output_thread_start(&threads[t], search_worker, &s) == 0) started++;
    if (!started) search_worker(&s); /* no threads to be had: do it here */
    for (t = 0; t < started; t++) pthread_join(threads[t], NULL);
    pthread_mutex_destroy(&s.lock);
    free(dirs);
    adaslice_orienter_free(&o);
    if (s.failed) {
        free(*scores);
        *scores = NULL;
        return library_error_in(model, &s.err);
    }
    adaslice_orient_scores(*scores, count, alpha);
    /* neighbours: within 2.5 lattice spacings (the lattice's cells cover 4 pi / n) */
    *minima_count = adaslice_orient_minima(*scores, count,
                                           2.5 * sqrt(4 * 3.14159265358979 / (double)(count - SEARCH_AXES)), minima,
                                           SEARCH_MINIMA + 1);
    return RC_OK;
}

