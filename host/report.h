/* How the adaslice tool reports: exit codes, one-line complaints on stderr,
   the library's messages, and a progress bar on a terminal. */
#ifndef ADASLICE_HOST_REPORT_H
#define ADASLICE_HOST_REPORT_H
#include <stddef.h>
#include "../adaslice.h"

/* 0 done; 1 the work failed; 2 the command line is wrong; 3 a print paused;
   4 the printer restarted mid-print (Z must be homed again); 5 the printer
   stopped answering (mid-print: Z must be homed again if it restarted);
   128 + a signal: interrupted (output.h's outputs_finish) */
enum { RC_OK = 0, RC_FAIL = 1, RC_USAGE = 2, RC_PAUSED = 3, RC_RESET = 4, RC_LOST = 5 };

/* "adaslice: " + the message on stderr, one line (control bytes as \xNN);
   returns rc. */
int complain(int rc, const char *fmt, ...);
/* "adaslice: warning: " + the message, the same way: something was repaired
   or guessed and the work goes on. */
void warn(const char *fmt, ...);
/* rc, or RC_FAIL (said) when rc is RC_OK and standard output could not be
   written (a full disk, a closed pipe): a failure, not a silent success. */
int stdout_written(int rc);
/* The library's message; exit 2 for an argument it rejects, else 1. */
int library_error(const adaslice_error *e);
/* The same about `file` (the model the library worked on): "file: message". */
int library_error_in(const char *file, const adaslice_error *e);
/* "" or "s" after a count's noun: "%zu layer%s", n, plural(n). */
const char *plural(size_t n);
/* Text from an input file as a message quotes it: the first QUOTE_BYTES bytes
   of text[0..n), "..." when there are more, each byte outside printable ASCII
   as \xNN, so that a binary file shows neither raw bytes nor a page of them. */
enum { QUOTE_BYTES = 40, QUOTE_SIZE = 4 * QUOTE_BYTES + 4 };
const char *quote_text(char out[QUOTE_SIZE], const char *text, size_t n);
/* A print's duration as people say it: "1 h 23 min", "12 min", "40 s". */
void format_duration(char *out, size_t size, double seconds);
/* "14.3 GB", "512 MB" */
const char *size_text(double bytes, char out[32]);
/* A monotonic clock, ms. */
double now_ms(void);

/* A bar on stderr while it is a terminal, nothing otherwise:
   "[####    ] 12/367 layers, <detail>, 3.1 s left", redrawn at most every
   100 ms and always at the end. Zero it before the first call. */
typedef struct progress { double started, last; } progress;
void progress_show(progress *p, size_t done, size_t total, const char *what, const char *detail);
#endif
