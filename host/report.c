/* The tool's messages: see report.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#endif
#include "report.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include <time.h>
#include <unistd.h>

/* One line on stderr: a control byte in the message (a file named with a
   newline in it) is written as \xNN, so one complaint stays one line. */
static void say(const char *prefix, const char *fmt, va_list ap)
{
    char small[1024], *text = small;
    va_list again;
    int n;
    size_t i;
    va_copy(again, ap);
    n = vsnprintf(small, sizeof small, fmt, ap);
    if (n >= (int)sizeof small && (text = (char *)malloc((size_t)n + 1)) != NULL) vsnprintf(text, (size_t)n + 1, fmt, again);
    va_end(again);
    if (!text) text = small; /* no memory: the message cut short */
    fputs(prefix, stderr);
    for (i = 0; n > 0 && text[i]; i++) {
        unsigned char c = (unsigned char)text[i];
        if (c < 32 || c == 127) fprintf(stderr, "\\x%02x", c);
        else fputc(c, stderr);
    }
    fputc('\n', stderr);
    if (text != small) free(text);
}

int complain(int rc, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    say("adaslice: ", fmt, ap);
    va_end(ap);
    return rc;
}

void warn(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    say("adaslice: warning: ", fmt, ap);
    va_end(ap);
}

int stdout_written(int rc)
{
    if (rc == RC_OK && (fflush(stdout) != 0 || ferror(stdout)))
        return complain(RC_FAIL, "cannot write standard output: %s", strerror(errno));
    return rc;
}

/* A parameter the library rejects came from the command line, hence exit 2. */
int library_error(const adaslice_error *e)
{
    return complain(e->result == ADASLICE_ERR_ARGUMENT ? RC_USAGE : RC_FAIL, "%s", e->message);
}

int library_error_in(const char *file, const adaslice_error *e)
{
    return complain(e->result == ADASLICE_ERR_ARGUMENT ? RC_USAGE : RC_FAIL, "%s: %s", file, e->message);
}

const char *plural(size_t n) { return n == 1 ? "" : "s"; }

const char *quote_text(char out[QUOTE_SIZE], const char *text, size_t n)
{
    static const char hex[] = "0123456789abcdef";
    size_t i, k = 0;
    for (i = 0; i < n && i < QUOTE_BYTES; i++) {
        unsigned char c = (unsigned char)text[i];
        if (c >= 32 && c < 127 && c != '\\') {
            out[k++] = (char)c;
        } else {
            out[k++] = '\\';
            out[k++] = 'x';
            out[k++] = hex[c >> 4];
            out[k++] = hex[c & 15];
        }
    }
    if (n > QUOTE_BYTES) for (i = 0; i < 3; i++) out[k++] = '.';
    out[k] = 0;
    return out;
}

void format_duration(char *out, size_t size, double s)
{
    long m = (long)(s / 60 + 0.5);
    if (s < 60) snprintf(out, size, "%.0f s", s);
    else if (m < 60) snprintf(out, size, "%ld min", m);
    else snprintf(out, size, "%ld h %02ld min", m / 60, m % 60);
}

const char *size_text(double bytes, char out[32])
{
    if (bytes >= 1e9) snprintf(out, 32, "%.3g GB", bytes / 1e9);
    else snprintf(out, 32, "%.0f MB", bytes / 1e6);
    return out;
}

double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

void progress_show(progress *p, size_t done, size_t total, const char *what, const char *detail)
{
    double t = now_ms(), eta;
    int filled, i;
    if (!p->started) p->started = t;
    if (done < total && t - p->last < 100) return;
    p->last = t;
    if (!isatty(2)) return; /* asked at most every 100 ms: a call a layer was a system call a layer */
    filled = total ? (int)(30.0 * (double)done / (double)total) : 30;
    eta = done ? (t - p->started) * (double)(total - done) / (double)done / 1000 : 0;
    fputs("\r[", stderr);
    for (i = 0; i < 30; i++) fputc(i < filled ? '#' : ' ', stderr);
    fprintf(stderr, "] %zu/%zu %s, %s%s%.1f s left ", done, total, what, detail ? detail : "", detail ? ", " : "", eta);
    if (done == total) fputc('\n', stderr);
}
