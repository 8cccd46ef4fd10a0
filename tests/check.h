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

/* Every test file exports its cases through one registration function. */
typedef void (*check_case_fn)(void);
void check_run(const char *name, check_case_fn fn);
#define RUN(fn) check_run(#fn, fn)

/* Path to a file in the repository (tests run from the repository root). */
#endif
