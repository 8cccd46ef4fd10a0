/* Minimal test harness: a test case is a void function; CHECK records failures
   inside it; the runner prints one line per case and "N passed, N failed". */
#ifndef ADASLICE_CHECK_H
#define ADASLICE_CHECK_H
#include <stdio.h>

void check_fail(const char *file, int line, const char *what);
int check_case_failed(void);

/* Evaluates cond once; on failure records file:line and the text. */
#define CHECK(cond) do { if (!(cond)) check_fail(__FILE__, __LINE__, #cond); } while (0)
/* Same, with a printf-style explanation printed on failure. */
#define CHECKF(cond, ...) do { if (!(cond)) { char check_msg_[512]; \
    snprintf(check_msg_, sizeof check_msg_, __VA_ARGS__); check_fail(__FILE__, __LINE__, check_msg_); } } while (0)

/* Every test file tests/test_NAME.c exports its cases through one function,
   test_NAME(void), which RUNs them; the Makefile finds the file and the
   runner calls the function (build/test_groups.h). Tests run from the
   repository's root. */
typedef void (*check_case_fn)(void);
void check_run(const char *name, check_case_fn fn);
#define RUN(fn) check_run(#fn, fn)
/* A case that needs a program besides the C compiler (a real client, an
   emulator, a cross compiler's image): make check runs it, and it fails
   there when the program is missing; make test (--without-tools) does not
   run it and says so. */
void check_run_needing(const char *name, check_case_fn fn, const char *tools);
#define RUN_NEEDING(tools, fn) check_run_needing(#fn, fn, tools)
#endif
