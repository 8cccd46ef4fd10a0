/* Files the tool writes, and the names it writes in them. A regular file (or
   a new one) is written under "TARGET.tmp.PID" and renamed into place, so a
   failed run leaves no file that looks complete; TARGET is the file a symlink
   leads to (the link stays). Anything else that exists (a device such as
   /dev/null or /dev/full, a FIFO, a terminal, "-" for standard output,
   /dev/stdout) is written straight, never replaced. Every output of every
   command goes through output_open or write_atomic, and every path is
   checked by output_check before the work. */
#ifndef ADASLICE_HOST_OUTPUT_H
#define ADASLICE_HOST_OUTPUT_H
#include <pthread.h>
#include <stdio.h>

/* What is at an output path: nothing yet, a regular file (or a link to one),
   a directory, or something written straight ("-", a device, a FIFO). */
enum { OUT_NEW, OUT_REGULAR, OUT_DIRECTORY, OUT_STRAIGHT };
int output_kind(const char *path);

/* Before the work: path (of command-line option `option`, for the message)
   can take a file: not empty, not a directory, its directory exists and is
   writable. RC_OK or an RC_USAGE complaint made. NULL passes. A path that is
   standard output ("-", /dev/stdout) takes it for the data: what the command
   prints besides (its summary, --json's object) goes to standard error. */
int output_check(const char *option, const char *path);
/* A file the command reads (NULL and "-" ignored): from then on
   output_check refuses it as an output, which would write over it (plan
   MODEL --plot MODEL replaced the model with a picture of its plan). */
void outputs_add_input(const char *path);
/* The same for a job directory: an existing writable directory, or a new
   one in a writable directory. */
int output_check_dir(const char *option, const char *path);
/* Before the work: no two of the n outputs (NULL ones skipped) are one file,
   which would keep only the last written ("-" twice is standard output
   twice; a device such as /dev/null may take them all). RC_OK or an
   RC_USAGE complaint naming both options. */
int output_check_distinct(const char *const *options, const char *const *paths, size_t n);
/* Whether two outputs are one file (links followed, a file not yet made by
   its resolved directory) or one stream ("-", /dev/stdout); a device is
   never the same. */
int output_same(const char *a, const char *b);

/* An output being written: f takes the bytes. */
typedef struct output {
    FILE *f;
    char *path;                  /* as given, for messages */
    char *target;                /* where the rename goes (a symlink's target) */
    char *tmp;                   /* the temporary name; NULL: written straight */
    int straight;                /* no rename: a device, a FIFO, standard output */
    int copy;                    /* straight, but f is a temporary file copied at close
                                    (the writer seeks) */
} output;
/* Opens path for writing (seekable: f can seek, whatever path is). RC_OK,
   or a complaint made and nothing left behind. */
int output_open(output *o, const char *path, int seekable);
/* ok and err 0 (err: the errno of a write the caller saw fail): puts the file
   in place, or finishes writing it straight; else removes what was written.
   RC_OK or a complaint made ("cannot write PATH: why"). */
int output_close(output *o, int ok, int err);

typedef void (*write_fn)(FILE *f, const void *ctx);
/* Writes path through output_open and fill; RC_OK or a complaint made. */
int write_atomic(const char *path, write_fn fill, const void *ctx);
/* The part of path after its last '/'. */
const char *base_name(const char *path);

/* ---- signals and the run's outputs ---------------------------------- */

/* SIGINT, SIGTERM and SIGHUP: before the first output is opened they end
   the run at once ("adaslice: interrupted by SIGINT: nothing written", exit
   128 + the signal); from then on they are noted (output_interrupted), the
   writers stop, and outputs_finish removes what the run wrote. */
void outputs_catch_signals(void);
/* The signal caught, or 0. */
int output_interrupted(void);
/* pthread_create for a worker: the thread starts with the signals above
   blocked, so they reach the main thread, whose blocked write (a FIFO, a
   full pipe) they interrupt; a worker taking one would leave it blocked. */
int output_thread_start(pthread_t *thread, void *(*run)(void *), void *arg);
/* From now on a signal is only noted: the caller polls output_interrupted. */
void outputs_hold_signals(void);
/* A complaint about path's write failing with errno err, unless the run was
   interrupted (then outputs_finish says so, once); returns RC_FAIL. */
int output_failed(const char *path, int err);
/* The end of a command that returned rc: when it failed (1 or 2) or was
   interrupted, every file the run put in place is removed; an interruption
   is said and gives 128 + the signal. Returns the exit status. */
int outputs_finish(int rc);
#endif
