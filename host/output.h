/* Files the tool writes: atomically (a failed run leaves no file that looks
   complete), and the names it writes in them. */
#ifndef ADASLICE_HOST_OUTPUT_H
#define ADASLICE_HOST_OUTPUT_H
#include <stdio.h>

typedef void (*write_fn)(FILE *f, const void *ctx);
/* Writes PATH through "PATH.tmp.PID" and renames it into place; RC_OK or a
   complaint made. */
int write_atomic(const char *path, write_fn fill, const void *ctx);
/* The part of path after its last '/'. */
const char *base_name(const char *path);
#endif
