/* What many test groups need and none owns: a whole file read into memory. */
#ifndef ADASLICE_TESTS_UTIL_H
#define ADASLICE_TESTS_UTIL_H
#include <stdio.h>
#include <stdlib.h>

/* The file's bytes in a malloc'd buffer with a NUL after them (so text can
   be read as a string), *size set when size is not NULL; NULL when the file
   cannot be opened or read whole. */
static inline unsigned char *read_whole_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *s = NULL;
    long n;
    if (size) *size = 0;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (s = (unsigned char *)malloc((size_t)n + 1)) != NULL) {
        if (fread(s, 1, (size_t)n, f) != (size_t)n) {
            free(s);
            s = NULL;
        } else {
            s[n] = 0;
            if (size) *size = (size_t)n;
        }
    }
    fclose(f);
    return s;
}

/* The same, as text. */
static inline char *read_whole_text(const char *path) { return (char *)read_whole_file(path, NULL); }
#endif
