/* First touches of new memory were the slicing start's largest cost: on the
   turbine blade (1.8M facets) the load and repair met 4,600 page faults, each
   about 10 us on this kind of machine (a virtual one: a fault goes through
   its hypervisor), 27 of the load's 28 ms and 25 of the repair's 75.
   Huge pages take 512 of them at once. */
#define _DEFAULT_SOURCE /* madvise and MADV_HUGEPAGE, beside POSIX */
#include "pages.h"
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

#define HUGE_PAGE ((size_t)2 << 20)

void *pages_alloc(size_t size)
{
    void *p = NULL;
    size_t whole = (size + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
    /* from 1 MB up, the block is rounded up to whole huge pages: zeroing the
       rest of one costs less than the first touches of half of it */
    if (size < HUGE_PAGE / 2 || whole < size) return malloc(size ? size : 1);
    if (posix_memalign(&p, HUGE_PAGE, whole)) return NULL;
#ifdef MADV_HUGEPAGE
    /* a hint: where the kernel has none to give, the block is plain memory */
    (void)madvise(p, whole, MADV_HUGEPAGE);
#endif
    return p;
}

static void *library_alloc(void *user, size_t size)
{
    (void)user;
    return pages_alloc(size);
}

static void library_free(void *user, void *p)
{
    (void)user;
    free(p);
}

const adaslice_allocator *pages_allocator(void)
{
    static const adaslice_allocator pages = {library_alloc, library_free, NULL};
    return &pages;
}
