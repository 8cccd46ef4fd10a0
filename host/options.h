/* The command line's values, read one way for every command: each parser
   takes the value after argv[*i] (moving *i past it), checks it, and on a bad
   or missing value complains in one line naming the option and returns
   RC_USAGE. */
#ifndef ADASLICE_HOST_OPTIONS_H
#define ADASLICE_HOST_OPTIONS_H
#include <stdio.h>
#include <stddef.h>

/* Any text (a path), not starting with "--". */
int file_option(int argc, char **argv, int *i, const char **out);
/* The one reading of a number, wherever the tool reads one: a plain decimal
   ([+-]digits[.digits][e[+-]digits], a digit on one side of the point at
   least) at the start of text, finite, into *out; returns where it ends, or
   NULL. strtod alone also takes hex (0x10 as 16), inf, nan and leading
   blanks. */
const char *decimal_number(const char *text, double *out);
/* --memory MB: a number, 1 MB at least (1e-300 read as "needs 0 MB, more
   than --memory 0 MB"). */
int memory_option(int argc, char **argv, int *i, double *mb);
/* The lines of the text files of numbers that options name (--profile,
   --weights). text_line_trim: the line without its blanks at either end
   and its line end (cut in place). text_line_read: line `lineno` of f into
   line (TEXT_LINE_MAX bytes, NUL-terminated); 1 when read, 0 at the end of
   the file (*rc RC_OK) or with *rc a complaint made: a line of more than
   TEXT_LINE_MAX - 2 bytes before its line end (/dev/zero as a profile grew one line to 15 GB), a NUL byte
   (not text, and C's strings stop there), or a read error (which getline
   reported as the end: a profile cut short planned, exit 0). `bad` is the
   status for what the file holds. */
#define TEXT_LINE_MAX 4096
char *text_line_trim(char *line);
int text_line_read(FILE *f, const char *path, size_t lineno, char *line, int bad, int *rc);
/* A whole number's digits at the start of text (no sign, no blank) into
   *out, ULLONG_MAX past it; the end of the digits, or NULL when text does
   not start with one. */
const char *whole_number(const char *text, unsigned long long *out);
/* A finite number > 0, or >= 0 when zero_ok. */
int number_option(int argc, char **argv, int *i, int zero_ok, double *out);
/* A whole number from 1 to max. */
int count_option(int argc, char **argv, int *i, size_t max, size_t *out);
/* A whole number from least to max. */
int whole_option(int argc, char **argv, int *i, size_t least, size_t max, size_t *out);
/* One of `count` names; `choices` lists them for the message. */
int name_option(int argc, char **argv, int *i, const char *const *names, int count, const char *choices, int *out);
/* Exactly n finite numbers separated by `sep` ("2560x1440" with 'x',
   "1,2,3" with ','); `form` shows the expected form in the message. */
int numbers_option(int argc, char **argv, int *i, char sep, int n, const char *form, double *out);
/* The same test without an option around it: 1 if text is n numbers. */
int parse_numbers(const char *text, char sep, int n, double *out);
/* 1 if `name` is among argv[1..]: for an option whose parsed value cannot
   tell whether it was given (its default filled in). A value cannot look
   like it: values never start with "--". */
int option_given(int argc, char **argv, const char *name);
/* Physical memory, MB (10^6 bytes); 4096 where the system does not say:
   half of it is what --memory allows unless told. */
double machine_memory_mb(void);
#endif
