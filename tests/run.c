/* The test runner: every group of cases, then "N passed, N failed".

   run_tests [--without-tools] [--case NAME] [GROUP ...]
   GROUPs (the NAME of tests/test_NAME.c) select what runs; --case runs only
   the cases of that name (tests/under_load.sh repeats one); --without-tools
   leaves out the cases that need programs besides the C compiler and lists
   them. */
#include "../adaslice.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int passed, failed, left, case_failures, without_tools;
static const char *only_case;

void check_fail(const char *file, int line, const char *what)
{
    if (case_failures < 8) printf("    %s:%d: %s\n", file, line, what);
    case_failures++;
}

int check_case_failed(void) { return case_failures > 0; }

void check_run(const char *name, check_case_fn fn)
{
    if (only_case && strcmp(name, only_case)) return;
    struct timespec t0, t1;
    double seconds;
    case_failures = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    fn();
    clock_gettime(CLOCK_MONOTONIC, &t1);
    /* shown, never judged: what makes a group long is worth seeing in its log */
    seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (case_failures) { failed++; printf("FAIL %s (%d checks failed, %.1f s)\n", name, case_failures, seconds); }
    else { passed++; printf("ok   %s (%.1f s)\n", name, seconds); }
    fflush(stdout);
}

void check_run_needing(const char *name, check_case_fn fn, const char *tools)
{
    if (!without_tools) { check_run(name, fn); return; }
    left++;
    printf("--   %s: needs %s, left to make check\n", name, tools);
    fflush(stdout);
}

#define TEST_GROUP(name) void test_##name(void);
#include "test_groups.h"
#undef TEST_GROUP

int main(int argc, char **argv)
{
#define TEST_GROUP(name) {#name, test_##name},
    static const struct { const char *name; void (*fn)(void); } groups[] = {
#include "test_groups.h"
    };
#undef TEST_GROUP
    int i, j, chosen = 0;
    for (j = 1; j < argc; j++) {
        if (!strcmp(argv[j], "--without-tools")) { without_tools = 1; continue; }
        if (!strcmp(argv[j], "--case") && j + 1 < argc) { only_case = argv[++j]; continue; }
        for (i = 0; i < (int)(sizeof groups / sizeof groups[0]) && strcmp(argv[j], groups[i].name); i++) {}
        if (i == (int)(sizeof groups / sizeof groups[0])) { printf("no test group %s\n", argv[j]); return 2; }
        chosen++;
    }
    for (i = 0; i < (int)(sizeof groups / sizeof groups[0]); i++) {
        int want = !chosen;
        for (j = 1; j < argc; j++) if (!strcmp(argv[j], groups[i].name)) want = 1;
        if (want) groups[i].fn();
    }
    if (left) printf("%d passed, %d failed (%d left to make check: they need programs besides gcc)\n", passed, failed, left);
    else printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
