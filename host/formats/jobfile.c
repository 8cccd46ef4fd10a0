/* The job formats and what they share: see jobfile.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "jobfile.h"
#include "../report.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

const job_format *const JOB_FORMATS[] = {&JOB_FORMAT_DIR, &JOB_FORMAT_CTB, &JOB_FORMAT_CTB_ENCRYPTED, &JOB_FORMAT_GOO,
                                         &JOB_FORMAT_PRZ, &JOB_FORMAT_CHITU_ZIP, &JOB_FORMAT_SL1, &JOB_FORMAT_UVJ, NULL};

const job_format *job_format_named(const char *name)
{
    int i;
    for (i = 0; JOB_FORMATS[i]; i++)
        if (!strcmp(JOB_FORMATS[i]->name, name)) return JOB_FORMATS[i];
    return NULL;
}

const job_format *job_format_for_path(const char *path)
{
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    int i;
    if (!dot || (slash && dot < slash) || dot == path || (slash && dot == slash + 1)) return &JOB_FORMAT_DIR;
    for (i = 0; JOB_FORMATS[i]; i++) {
        const char *e = JOB_FORMATS[i]->extension, *d = dot;
        if (!e) continue;
        while (*e && *d && tolower((unsigned char)*d) == *e) { e++; d++; }
        if (!*e && !*d) return JOB_FORMATS[i];
    }
    return NULL;
}


int job_blob_reserve(job_blob *b, size_t more)
{
    size_t cap = b->cap ? b->cap : 4096;
    unsigned char *p;
    if (b->size + more <= b->cap) return 0;
    while (cap < b->size + more) cap = cap / 2 * 3 + more;
    if (!(p = (unsigned char *)realloc(b->data, cap))) return -1;
    b->data = p;
    b->cap = cap;
    return 0;
}

int job_open(job_writer *w, const job_format *f, const char *path, const job_desc *d)
{
    memset(w, 0, sizeof *w);
    w->format = f;
    w->d = d;
    w->path = path;
    if (d->width <= 0 || d->height <= 0 || !d->layer_count || !d->layers || (d->bits != 1 && d->bits != 8))
        return complain(RC_FAIL, "%s: a %s job needs pixels, layers and 1- or 8-bit images (%dx%d, %zu layer%s, %d-bit)",
                        path, f->name, d->width, d->height, d->layer_count, plural(d->layer_count), d->bits);
    return f->open(&w->state, path, d);
}

int job_put(job_writer *w, size_t k, job_blob *blob)
{
    const job_desc *d = w->d;
    int rc;
    if (!w->state || k != w->layers_put || k >= d->layer_count) {
        free(blob->data);
        blob->data = NULL;
        return complain(RC_FAIL, "%s: layer %zu handed to the %s writer after %zu of %zu layer%s", w->path, k,
                        w->format->name, w->layers_put, d->layer_count, plural(d->layer_count));
    }
    rc = w->format->put(w->state, k, blob);
    if (rc == RC_OK) w->layers_put++;
    return rc;
}

int job_close(job_writer *w, int ok)
{
    void *state = w->state;
    int rc = RC_OK, closed;
    if (!state) return ok ? RC_FAIL : RC_OK;
    w->state = NULL;
    if (ok && w->layers_put != w->d->layer_count) {
        rc = complain(RC_FAIL, "%s: only %zu of %zu layer%s written; no file made", w->path, w->layers_put,
                      w->d->layer_count, plural(w->d->layer_count));
        ok = 0;
    }
    closed = w->format->close(state, ok);
    return rc ? rc : closed;
}

int job_write_layer(job_writer *w, size_t k, const unsigned char *image, size_t stride)
{
    job_blob blob;
    int rc;
    memset(&blob, 0, sizeof blob);
    if (!w->state) return job_put(w, k, &blob); /* the complaint */
    rc = w->format->encode(w->state, k, image, stride, &blob);
    if (rc) {
        free(blob.data);
        return rc;
    }
    return job_put(w, k, &blob);
}

time_t job_time(int *fixed)
{
    const char *epoch = getenv("SOURCE_DATE_EPOCH");
    char *end;
    long long v = epoch && *epoch ? strtoll(epoch, &end, 10) : -1;
    *fixed = epoch && *epoch && !*end && v >= 0;
    return *fixed ? (time_t)v : time(NULL);
}

int job_file_open(job_file *jf, const char *path)
{
    memset(jf, 0, sizeof *jf);
    if (output_open(&jf->out, path, 1)) return RC_FAIL;
    jf->f = jf->out.f;
    jf->path = jf->out.path;
    return RC_OK;
}

void job_file_append(job_file *jf, const void *src, size_t n)
{
    static const unsigned char zero[4096];
    if (jf->err) return;
    errno = 0;
    while (n) {
        size_t part = src || n < sizeof zero ? n : sizeof zero;
        if (fwrite(src ? src : zero, 1, part, jf->f) != part) {
            jf->err = errno ? errno : EIO;
            return;
        }
        if (src) src = (const unsigned char *)src + part;
        n -= part;
    }
}

void job_file_write_at(job_file *jf, uint64_t at, const void *src, size_t n)
{
    if (jf->err) return;
    errno = 0;
    if (fseeko(jf->f, (off_t)at, SEEK_SET) != 0) jf->err = errno ? errno : EIO;
    else job_file_append(jf, src, n);
}

int job_file_check(const job_file *jf)
{
    return jf->err ? output_failed(jf->path, jf->err) : output_interrupted() ? RC_FAIL : RC_OK;
}

int job_file_commit(job_file *jf)
{
    /* errno after an earlier failed write may be anyone's: say EIO */
    int rc = output_close(&jf->out, 1, jf->err ? jf->err : jf->f && ferror(jf->f) ? EIO : 0);
    memset(jf, 0, sizeof *jf);
    return rc;
}

void job_file_discard(job_file *jf)
{
    output_close(&jf->out, 0, 0);
    memset(jf, 0, sizeof *jf);
}
