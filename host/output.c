/* Outputs and the signals that interrupt them: see output.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
/* realpath: POSIX.1-2008, which glibc declares for X/Open */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700
#endif
#include "output.h"
#include "report.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------ paths */

/* Names of the streams the tool already has open: written straight even when
   the shell sent them to a regular file (a rename would take the file from
   the shell's redirection). */
static int names_a_stream(const char *path)
{
    return !strcmp(path, "-") || !strcmp(path, "/dev/stdout") || !strcmp(path, "/dev/stderr") ||
           !strncmp(path, "/dev/fd/", 8) || !strncmp(path, "/proc/self/fd/", 14);
}

/* Standard output once an output took it (output_check): the command's
   summary and notes then go to standard error, or they would be mixed into
   the data (a profile CSV written to "-" and read back failed at its line
   4,007, the summary's first). */
static FILE *data_stdout;

static void take_stdout(void)
{
    int fd;
    if (data_stdout) return;
    fflush(stdout);
    if ((fd = dup(STDOUT_FILENO)) < 0) return;
    if (!(data_stdout = fdopen(fd, "wb"))) {
        close(fd);
        return;
    }
    if (dup2(STDERR_FILENO, STDOUT_FILENO) < 0) { /* printf stays where it was: the data with it */
        fclose(data_stdout);
        data_stdout = NULL;
    }
}

/* The stream the tool has open under that name ("-" is standard output),
   written through its FILE (an open of /dev/stdout, when the shell sent it to
   a file, would truncate what was printed and write over it), or NULL. */
static FILE *stream_named(const char *path)
{
    if (!strcmp(path, "-") || !strcmp(path, "/dev/stdout") || !strcmp(path, "/dev/fd/1") ||
        !strcmp(path, "/proc/self/fd/1"))
        return data_stdout ? data_stdout : stdout;
    if (!strcmp(path, "/dev/stderr") || !strcmp(path, "/dev/fd/2") || !strcmp(path, "/proc/self/fd/2")) return stderr;
    return NULL;
}

int output_kind(const char *path)
{
    struct stat st;
    if (names_a_stream(path)) return OUT_STRAIGHT;
    if (stat(path, &st) != 0) return OUT_NEW;
    if (S_ISDIR(st.st_mode)) return OUT_DIRECTORY;
    return S_ISREG(st.st_mode) ? OUT_REGULAR : OUT_STRAIGHT;
}

/* The file path names once its symlinks are followed (a link to a file not
   yet made included), malloc'd; NULL when out of memory. */
static char *resolve_links(const char *path)
{
    char *cur = strdup(path), link[4096];
    int hops;
    for (hops = 0; cur && hops < 40; hops++) {
        struct stat st;
        ssize_t n;
        char *next;
        const char *slash;
        size_t dir;
        if (lstat(cur, &st) != 0 || !S_ISLNK(st.st_mode)) break;
        if ((n = readlink(cur, link, sizeof link - 1)) <= 0) break;
        link[n] = 0;
        slash = strrchr(cur, '/');
        dir = link[0] == '/' || !slash ? 0 : (size_t)(slash - cur) + 1; /* a relative link is read from its directory */
        if ((next = (char *)malloc(dir + (size_t)n + 1)) != NULL) {
            memcpy(next, cur, dir);
            memcpy(next + dir, link, (size_t)n + 1);
        }
        free(cur);
        cur = next;
    }
    return cur;
}

/* The directory that will hold path (its links followed) exists and takes
   new files: a temporary name and a rename. */
static int check_parent(const char *option, const char *path)
{
    char *target = resolve_links(path), *slash;
    const char *dir;
    struct stat st;
    int rc = RC_OK;
    if (!target) return complain(RC_FAIL, "out of memory");
    slash = strrchr(target, '/');
    if (!slash) dir = ".";
    else if (slash == target) dir = "/";
    else { *slash = 0; dir = target; }
    if (stat(dir, &st) != 0)
        rc = complain(RC_USAGE, "%s %s: no directory %s (%s)", option, path, dir, strerror(errno));
    else if (!S_ISDIR(st.st_mode))
        rc = complain(RC_USAGE, "%s %s: %s is not a directory", option, path, dir);
    else if (access(dir, W_OK | X_OK) != 0)
        rc = complain(RC_USAGE, "%s %s: cannot write in %s: %s", option, path, dir, strerror(errno));
    free(target);
    return rc;
}

static const char *inputs[8];
static size_t input_count;

void outputs_add_input(const char *path)
{
    if (path && strcmp(path, "-") && input_count < sizeof inputs / sizeof *inputs) inputs[input_count++] = path;
}


int output_check(const char *option, const char *path)
{
    size_t i;
    if (!path) return RC_OK;
    if (!*path) return complain(RC_USAGE, "%s \"\": an empty file name", option);
    switch (output_kind(path)) {
    case OUT_STRAIGHT:
        if (stream_named(path) == stdout) take_stdout();
        return RC_OK;
    case OUT_DIRECTORY: return complain(RC_USAGE, "%s %s: is a directory; give a file name", option, path);
    default:
        for (i = 0; i < input_count; i++)
            if (output_same(path, inputs[i]))
                return complain(RC_USAGE, "%s %s is %s, which this command reads: it would be written over", option,
                                path, inputs[i]);
        return check_parent(option, path);
    }
}

int output_check_dir(const char *option, const char *path)
{
    if (!*path) return complain(RC_USAGE, "%s \"\": an empty directory name", option);
    switch (output_kind(path)) {
    case OUT_DIRECTORY:
        if (access(path, W_OK | X_OK) != 0)
            return complain(RC_USAGE, "%s %s: cannot write in the directory: %s", option, path, strerror(errno));
        return RC_OK;
    case OUT_NEW: return check_parent(option, path);
    default:
        return complain(RC_USAGE, "%s %s: exists and is not a directory, so a job directory cannot go there (a job "
                                  "file: give its extension, --format NAME or --printer NAME)", option, path);
    }
}

/* The file path names (its links followed, a link to a file not yet made
   included) with its directory resolved (links, "..", "."), malloc'd; NULL
   when that directory does not resolve. */
static char *resolved(const char *path)
{
    char *file = resolve_links(path), *dir = file ? (char *)malloc(strlen(file) + 2) : NULL, *real = NULL, *out = NULL;
    const char *slash = file ? strrchr(file, '/') : NULL;
    if (dir) {
        if (!slash) strcpy(dir, ".");
        else if (slash == file) strcpy(dir, "/");
        else { memcpy(dir, file, (size_t)(slash - file)); dir[slash - file] = 0; }
        if ((real = realpath(dir, NULL)) && (out = (char *)malloc(strlen(real) + strlen(file) + 2)))
            sprintf(out, "%s/%s", real, slash ? slash + 1 : file);
    }
    free(real);
    free(dir);
    free(file);
    return out;
}

int output_same(const char *a, const char *b)
{
    struct stat sa, sb;
    FILE *fa = stream_named(a), *fb = stream_named(b);
    char *ra, *rb;
    int same;
    if (fa || fb) return fa == fb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && !S_ISCHR(sa.st_mode);
    ra = resolved(a);
    rb = resolved(b);
    same = ra && rb ? !strcmp(ra, rb) : !strcmp(a, b);
    free(ra);
    free(rb);
    return same;
}

int output_check_distinct(const char *const *options, const char *const *paths, size_t n)
{
    size_t i, j;
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++)
            if (paths[i] && paths[j] && output_same(paths[i], paths[j]))
                return complain(RC_USAGE, "%s %s and %s %s are one file: %s", options[i], paths[i], options[j], paths[j],
                                stream_named(paths[i]) ? "the two would be mixed in one stream"
                                                       : "the last written would replace the other");
    return RC_OK;
}

/* ------------------------------------------------------------ signals */

/* Set by the handler, read by the pipeline's threads too: a volatile
   sig_atomic_t is only the handler's and the thread it interrupted, so both
   are read and written as atomics (lock-free, safe in a handler). */
static volatile sig_atomic_t caught_flag, holding_flag;
static int caught(void) { return __atomic_load_n(&caught_flag, __ATOMIC_SEQ_CST); }
static int holding(void) { return __atomic_load_n(&holding_flag, __ATOMIC_SEQ_CST); }
#define SET_FLAG(flag, v) __atomic_store_n(&(flag), (v), __ATOMIC_SEQ_CST)

static const char *signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

static void on_signal(int sig)
{
    SET_FLAG(caught_flag, sig);
    if (!holding()) { /* nothing written yet: end here (write and _exit are async-signal-safe) */
        const char *name = signal_name(sig);
        ssize_t ignored;
        ignored = write(2, "adaslice: interrupted by ", 25);
        ignored = write(2, name, strlen(name));
        ignored = write(2, ": nothing written\n", 18);
        (void)ignored;
        _exit(128 + sig);
    }
}

void outputs_catch_signals(void)
{
    static const int signals[] = {SIGINT, SIGTERM, SIGHUP};
    struct sigaction sa;
    size_t i;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0; /* no SA_RESTART: a write blocked on a FIFO returns EINTR */
    for (i = 0; i < sizeof signals / sizeof signals[0]; i++) sigaction(signals[i], &sa, NULL);
}

int output_interrupted(void) { return caught(); }

int output_thread_start(pthread_t *thread, void *(*run)(void *), void *arg)
{
    sigset_t these, before;
    int rc;
    sigemptyset(&these);
    sigaddset(&these, SIGINT);
    sigaddset(&these, SIGTERM);
    sigaddset(&these, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &these, &before); /* the new thread inherits the mask */
    rc = pthread_create(thread, NULL, run, arg);
    pthread_sigmask(SIG_SETMASK, &before, NULL);
    return rc;
}
void outputs_hold_signals(void) { SET_FLAG(holding_flag, 1); }

int output_failed(const char *path, int err)
{
    return caught() ? RC_FAIL : complain(RC_FAIL, "cannot write %s: %s", path, strerror(err));
}

/* The files this run put in place (renamed), to remove if it fails. */
static pthread_mutex_t placed_lock = PTHREAD_MUTEX_INITIALIZER;
static char **placed;
static size_t placed_count, placed_cap;

static void note_placed(const char *path)
{
    char *copy = strdup(path);
    pthread_mutex_lock(&placed_lock);
    if (copy && placed_count == placed_cap) {
        size_t cap = placed_cap ? 2 * placed_cap : 16;
        char **more = (char **)realloc(placed, cap * sizeof *more);
        if (more) { placed = more; placed_cap = cap; }
    }
    if (copy && placed_count < placed_cap) placed[placed_count++] = copy;
    else free(copy);
    pthread_mutex_unlock(&placed_lock);
}

int outputs_finish(int rc)
{
    size_t i;
    int sig = caught();
    SET_FLAG(holding_flag, 1); /* what follows is the cleaning: a second signal waits for it */
    for (i = 0; i < placed_count; i++) {
        if (sig || rc == RC_FAIL || rc == RC_USAGE) remove(placed[i]);
        free(placed[i]);
    }
    free(placed);
    placed = NULL;
    placed_count = placed_cap = 0;
    if (!sig) return rc;
    complain(128 + sig, "interrupted by %s: nothing written", signal_name(sig));
    return 128 + sig;
}

/* ------------------------------------------------------------ writing */

static void output_free(output *o)
{
    free(o->path);
    free(o->target);
    free(o->tmp);
    memset(o, 0, sizeof *o);
}

int output_open(output *o, const char *path, int seekable)
{
    int kind = output_kind(path), err = 0;
    memset(o, 0, sizeof *o);
    outputs_hold_signals();
    if (caught()) return RC_FAIL;
    if (kind == OUT_DIRECTORY) return complain(RC_FAIL, "cannot write %s: it is a directory", path);
    if (!(o->path = strdup(path))) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    if (kind == OUT_STRAIGHT) {
        o->straight = 1;
        o->copy = seekable; /* a FIFO or a terminal cannot seek: the bytes go there at close */
        errno = 0;
        o->f = seekable ? tmpfile() : stream_named(path) ? stream_named(path) : fopen(path, "wb");
        if (!o->f) err = errno ? errno : EIO;
    } else {
        size_t n;
        if (!(o->target = resolve_links(path)) || !(o->tmp = (char *)malloc((n = strlen(o->target) + 32)))) {
            output_free(o);
            return complain(RC_FAIL, "cannot write %s: out of memory", path);
        }
        snprintf(o->tmp, n, "%s.tmp.%ld", o->target, (long)getpid());
        if (!(o->f = fopen(o->tmp, "wb"))) err = errno;
    }
    if (err) {
        output_free(o); /* nothing was made to remove */
        return output_failed(path, err);
    }
    return RC_OK;
}

/* A seeking writer's bytes, from its temporary file to where they go. */
static int copy_out(output *o)
{
    char buf[65536];
    FILE *to = stream_named(o->path) ? stream_named(o->path) : fopen(o->path, "wb");
    size_t n;
    int err = 0;
    if (!to) return errno ? errno : EIO;
    rewind(o->f);
    errno = 0;
    while (!err && (n = fread(buf, 1, sizeof buf, o->f)) > 0)
        if (fwrite(buf, 1, n, to) != n) err = errno ? errno : EIO;
    if (!err && ferror(o->f)) err = errno ? errno : EIO;
    if (fflush(to) != 0 && !err) err = errno ? errno : EIO;
    if (!stream_named(o->path) && fclose(to) != 0 && !err) err = errno ? errno : EIO;
    return err;
}

int output_close(output *o, int ok, int err)
{
    int rc;
    if (!o->f) { output_free(o); return ok ? RC_FAIL : RC_OK; }
    if (ok && !err && ferror(o->f)) err = EIO;
    if (ok && !err && fflush(o->f) != 0) err = errno ? errno : EIO;
    if (ok && !err && o->copy) err = copy_out(o);
    if ((o->copy || !stream_named(o->path)) && fclose(o->f) != 0 && ok && !err) err = errno ? errno : EIO;
    o->f = NULL;
    if (caught()) ok = 0;
    if (ok && !err && o->tmp && rename(o->tmp, o->target) != 0) err = errno;
    if (ok && !err) {
        if (o->tmp) note_placed(o->target);
        rc = RC_OK;
    } else {
        if (o->tmp) remove(o->tmp);
        rc = ok ? output_failed(o->path, err) : RC_FAIL;
    }
    output_free(o);
    return rc;
}

int write_atomic(const char *path, write_fn fill, const void *ctx)
{
    output o;
    int err;
    if (output_open(&o, path, 0)) return RC_FAIL;
    errno = 0;
    fill(o.f, ctx);
    err = ferror(o.f) ? (errno ? errno : EIO) : 0;
    return output_close(&o, 1, err);
}

const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}
