/* Large blocks in huge pages: the allocator the host hands the library for
   the slicing path's big arrays, and the host's own big buffers. */
#ifndef ADASLICE_HOST_PAGES_H
#define ADASLICE_HOST_PAGES_H
#include <stddef.h>
#include "../adaslice.h"

/* malloc's, but a block of 1 MB or more is rounded up to whole 2 MB pages,
   starts on a 2 MB boundary and is marked for the kernel's transparent huge
   pages where there are any (Linux's MADV_HUGEPAGE): its first touches then
   cost a fault per 2 MB, not one per 4 KB. Freed with free(). */
void *pages_alloc(size_t size);
/* pages_alloc and free as the library's allocator (no user pointer). */
const adaslice_allocator *pages_allocator(void);
#endif
