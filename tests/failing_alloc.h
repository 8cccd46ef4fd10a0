/* An allocator that fails from a chosen allocation on and counts the blocks
   still live, for out-of-memory tests: every failure must leak nothing. */
#ifndef ADASLICE_FAILING_ALLOC_H
#define ADASLICE_FAILING_ALLOC_H
#include <stdlib.h>
#include "../adaslice.h"

typedef struct failing {
    long left;  /* allocations that still succeed */
    long live;  /* blocks allocated and not yet freed */
} failing;

static inline void *failing_alloc(void *user, size_t size)
{
    failing *f = (failing *)user;
    void *p;
    if (f->left-- <= 0) return NULL;
    p = malloc(size);
    if (p) f->live++;
    return p;
}

static inline void failing_free(void *user, void *p)
{
    ((failing *)user)->live--;
    free(p);
}

static inline adaslice_allocator failing_allocator(failing *f)
{
    adaslice_allocator a;
    a.alloc = failing_alloc;
    a.free = failing_free;
    a.user = f;
    return a;
}
#endif
