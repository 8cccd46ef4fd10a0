/* Atomic files: see output.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "output.h"
#include "report.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int write_atomic(const char *path, write_fn fill, const void *ctx)
{
    size_t size = strlen(path) + 32;
    char *tmp = (char *)malloc(size);
    FILE *f;
    int err = 0;
    if (!tmp) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    snprintf(tmp, size, "%s.tmp.%ld", path, (long)getpid());
    f = fopen(tmp, "w");
    if (!f) {
        err = errno;
    } else {
        errno = 0;
        fill(f, ctx);
        if (ferror(f)) err = errno ? errno : EIO;
        if (fflush(f) != 0 && !err) err = errno;
        if (fclose(f) != 0 && !err) err = errno;
        if (!err && rename(tmp, path) != 0) err = errno;
        if (err) remove(tmp);
    }
    free(tmp);
    return err ? complain(RC_FAIL, "cannot write %s: %s", path, strerror(err)) : RC_OK;
}

const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}
