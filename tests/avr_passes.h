/* avr-run's end line in its log ("# end cycles=C worst_pass=P ... late=L",
   written by tests/avr_run.c): the loop's worst passes, the stack's peak,
   reserve and canary, and the steps refused as late. Read by tests/test_avr.c and
   bench/bench_avr.c. */
#ifndef ADASLICE_TESTS_AVR_PASSES_H
#define ADASLICE_TESTS_AVR_PASSES_H
#include <stdlib.h>
#include <string.h>

typedef struct avr_passes {
    unsigned long worst, moving;     /* the longest loop pass, and of those begun while Z moved, in cycles */
    unsigned long work, moving_work; /* the same with the interrupts' cycles out */
    unsigned long stack, late;       /* the stack's peak, bytes; steps refused as late */
    unsigned long reserve;           /* the stack's room the link reserved, bytes */
    int canary;                      /* 1: the stack's canary was overwritten */
} avr_passes;

/* Takes the fields `line` has; others are left as they are. */
static inline void avr_read_passes(const char *line, avr_passes *p)
{
    const char *v;
    if ((v = strstr(line, "worst_pass="))) p->worst = strtoul(v + 11, NULL, 10);
    if ((v = strstr(line, "worst_moving_pass="))) p->moving = strtoul(v + 18, NULL, 10);
    if ((v = strstr(line, "worst_work="))) p->work = strtoul(v + 11, NULL, 10);
    if ((v = strstr(line, "worst_moving_work="))) p->moving_work = strtoul(v + 18, NULL, 10);
    if ((v = strstr(line, "stack_peak="))) p->stack = strtoul(v + 11, NULL, 10);
    if ((v = strstr(line, " late="))) p->late = strtoul(v + 6, NULL, 10);
    if ((v = strstr(line, "stack_reserve="))) p->reserve = strtoul(v + 14, NULL, 10);
    if ((v = strstr(line, " canary="))) p->canary = atoi(v + 8);
}
#endif
