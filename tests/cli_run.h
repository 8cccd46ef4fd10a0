/* Runs the adaslice tool as a child process for end-to-end tests: the binary
   named by $ADASLICE_BIN (default build/adaslice, from the repository root),
   its stdout and stderr captured in files of a temporary directory. One
   includer per test program (the state is static). */
#ifndef ADASLICE_CLI_RUN_H
#define ADASLICE_CLI_RUN_H
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include "check.h"
#include "util.h"
#include "../adaslice.h"

#include <dirent.h>
#include <math.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static const char *cli_tool = "build/adaslice";
static char cli_dir[64];

typedef struct cli_result {
    int status;     /* exit status, -1 if the tool did not exit normally */
    char *out, *err;
} cli_result;

/* The temporary directory; 0 if it cannot be made. */
static inline int cli_begin(const char *prefix)
{
    const char *tmp = getenv("TMPDIR"), *bin = getenv("ADASLICE_BIN");
    if (bin && *bin) cli_tool = bin;
    snprintf(cli_dir, sizeof cli_dir, "%s/%s-XXXXXX", tmp && strlen(tmp) < 32 ? tmp : "/tmp", prefix);
    if (!mkdtemp(cli_dir)) {
        perror("mkdtemp");
        return 0;
    }
    return 1;
}

/* DIR/name; each of the last eight results stays valid. */
static const char *cli_path(const char *name)
{
    static char ring[8][512];
    static int next;
    char *p = ring[next++ & 7];
    snprintf(p, sizeof ring[0], "%s/%s", cli_dir, name);
    return p;
}


static inline void cli_write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    CHECKF(f && fwrite(data, 1, n, f) == n && fclose(f) == 0, "cannot write %.400s", path);
}

static inline void cli_write(const char *path, const char *text) { cli_write_bytes(path, text, strlen(text)); }

/* cli_run(arg, ..., NULL) */
static inline cli_result cli_run(const char *first, ...)
{
    char *argv[40], out[600], err[600];
    cli_result r;
    va_list ap;
    pid_t pid;
    int n = 0, st;
    const char *a;
    snprintf(out, sizeof out, "%s/stdout", cli_dir);
    snprintf(err, sizeof err, "%s/stderr", cli_dir);
    argv[n++] = (char *)cli_tool;
    va_start(ap, first);
    for (a = first; a && n < 39; a = va_arg(ap, const char *)) argv[n++] = (char *)a;
    va_end(ap);
    argv[n] = NULL;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        int i = open("/dev/null", O_RDONLY), o = open(out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int e = open(err, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (i < 0 || o < 0 || e < 0 || dup2(i, 0) < 0 || dup2(o, 1) < 0 || dup2(e, 2) < 0) _exit(126);
        execv(cli_tool, argv);
        _exit(127);
    }
    r.status = -1;
    if (pid > 0 && waitpid(pid, &st, 0) == pid && WIFEXITED(st)) r.status = WEXITSTATUS(st);
    CHECKF(r.status != 127, "cannot run %s (build it first; tests run from the repository root)", cli_tool);
    r.out = read_whole_text(out);
    r.err = read_whole_text(err);
    if (!r.out) r.out = (char *)calloc(1, 1);
    if (!r.err) r.err = (char *)calloc(1, 1);
    return r;
}

static inline void cli_free(cli_result *r)
{
    free(r->out);
    free(r->err);
}

/* exactly one line on stderr, "adaslice: ..." */
static inline int cli_one_message(const char *err)
{
    const char *nl = strchr(err, '\n');
    return !strncmp(err, "adaslice: ", 10) && nl && nl[1] == 0;
}

static inline int cli_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* The number after "key": in a JSON text (its first occurrence), or NAN. */
static inline double cli_json_number(const char *json, const char *key)
{
    char pat[64];
    const char *p;
    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    return p ? strtod(p + strlen(pat), NULL) : NAN;
}

/* How often `what` occurs in s. */
static inline size_t cli_count(const char *s, const char *what)
{
    size_t n = 0;
    while ((s = strstr(s, what)) != NULL) n++, s++;
    return n;
}

/* An OBJ of the mesh (the loader keeps the triangles' order). */
static inline void cli_write_obj(const char *path, const adaslice_mesh *m)
{
    FILE *f = fopen(path, "w");
    size_t i;
    CHECKF(f != NULL, "cannot write %s", path);
    if (!f) return;
    for (i = 0; i < m->vertex_count; i++)
        fprintf(f, "v %.9g %.9g %.9g\n", m->vertices[3 * i], m->vertices[3 * i + 1], m->vertices[3 * i + 2]);
    for (i = 0; i < m->triangle_count; i++)
        fprintf(f, "f %u %u %u\n", m->triangles[3 * i] + 1, m->triangles[3 * i + 1] + 1, m->triangles[3 * i + 2] + 1);
    fclose(f);
}

/* Removes path, a directory with everything in it too. */
static inline void cli_remove_all(const char *path)
{
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            size_t n = strlen(path) + strlen(e->d_name) + 2;
            char *sub = (char *)malloc(n);
            if (!sub) break;
            snprintf(sub, n, "%s/%s", path, e->d_name);
            cli_remove_all(sub);
            free(sub);
        }
    if (d) { closedir(d); rmdir(path); }
    else remove(path);
}

static inline void cli_end(void) { cli_remove_all(cli_dir); }
#endif
