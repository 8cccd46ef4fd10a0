/* Waiting on what the print tests start: a child's exit, a simulator's log.
   Every wait has a generous bound, so a slow or loaded machine waits longer
   and never fails for it; only a wait that ends at its bound fails. */
#ifndef ADASLICE_TESTS_WAIT_H
#define ADASLICE_TESTS_WAIT_H
#include "util.h"
#include <signal.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>

static inline void sleep_ms(long ms)
{
    struct timespec t;
    t.tv_sec = ms / 1000;
    t.tv_nsec = (ms % 1000) * 1000000L;
    nanosleep(&t, NULL);
}

static inline double seconds_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + t.tv_nsec / 1e9;
}

/* UV-on periods (exposures begun) in a simulator's log so far. */
static inline size_t lit_so_far(const char *log_path)
{
    char *log = read_whole_text(log_path), *at;
    size_t lit = 0;
    for (at = log; at && (at = strstr(at, " uv 1")) != NULL; at++) lit++;
    free(log);
    return lit;
}

/* Waits (up to 12 s) until a simulator's log shows n exposures begun. */
static inline int wait_for_exposures(const char *log_path, unsigned n)
{
    int i;
    for (i = 0; i < 600; i++) {
        if (lit_so_far(log_path) >= n) return 1;
        sleep_ms(20);
    }
    return 0;
}

/* The exit status of pid within `seconds` (killed and -1 if it has not). */
static inline int wait_exit(pid_t pid, double seconds)
{
    double t0 = seconds_now();
    int st;
    while (seconds_now() - t0 < seconds) {
        if (waitpid(pid, &st, WNOHANG) == pid) return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
        sleep_ms(5);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &st, 0);
    return -1;
}
#endif
