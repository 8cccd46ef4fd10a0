/* Command-line values: see options.h. */
#include "options.h"
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

char *text_line_trim(char *s)
{
    char *end = s + strlen(s);
    while (*s == ' ' || *s == '\t') s++;
    while (end > s && (end[-1] == '\n' || end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t')) *--end = 0;
    return s;
}

int text_line_read(FILE *f, const char *path, size_t lineno, char *line, int bad, int *rc)
{
    size_t n = 0;
    int c;
    *rc = RC_OK;
    while ((c = getc_unlocked(f)) != EOF) { /* one thread reads the file: no lock a byte */
        if (c == 0) {
            *rc = complain(bad, "%s:%zu: a NUL byte at column %zu: not a text file", path, lineno, n + 1);
            return 0;
        }
        if (c != '\n' && n + 2 == TEXT_LINE_MAX) { /* room for the line end and the NUL */
            *rc = complain(bad, "%s:%zu: a line longer than %d bytes: not a file of numbers", path, lineno, TEXT_LINE_MAX - 2);
            return 0;
        }
        line[n++] = (char)c;
        if (c == '\n') break;
    }
    line[n] = 0;
    if (ferror(f)) {
        *rc = complain(RC_FAIL, "cannot read %s at line %zu: %s", path, lineno, strerror(errno));
        return 0;
    }
    return n > 0;
}

int memory_option(int argc, char **argv, int *i, double *mb)
{
    int rc = number_option(argc, argv, i, 0, mb);
    if (!rc && *mb < 1) rc = complain(RC_USAGE, "--memory %g: 1 MB at least", *mb);
    return rc;
}

double machine_memory_mb(void)
{
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    if (pages > 0 && size > 0) return (double)pages * size / 1e6;
#endif
    return 4096;
}

int option_given(int argc, char **argv, const char *name)
{
    int i;
    for (i = 1; i < argc; i++)
        if (!strcmp(argv[i], name)) return 1;
    return 0;
}

/* The value after option argv[*i]; NULL, said so, if there is none. */
static const char *value_of(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc || !strncmp(argv[*i + 1], "--", 2)) {
        complain(RC_USAGE, "option %s needs a value", argv[*i]);
        return NULL;
    }
    return argv[++*i];
}

int file_option(int argc, char **argv, int *i, const char **out)
{
    *out = value_of(argc, argv, i);
    return *out ? RC_OK : RC_USAGE;
}

const char *decimal_number(const char *text, double *out)
{
    const char *p = text;
    size_t digits = 0;
    char plain[400], *end;
    if (*p == '+' || *p == '-') p++;
    for (; *p >= '0' && *p <= '9'; p++) digits++;
    if (*p == '.')
        for (p++; *p >= '0' && *p <= '9'; p++) digits++;
    if (!digits) return NULL;
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1 + (p[1] == '+' || p[1] == '-');
        if (*q >= '0' && *q <= '9') {
            while (*q >= '0' && *q <= '9') q++;
            p = q;
        }
    }
    /* strtod reads only the digits checked ("0x10" with 'x' between numbers is 0 and 10, not 16) */
    if ((size_t)(p - text) >= sizeof plain) return NULL;
    memcpy(plain, text, (size_t)(p - text));
    plain[p - text] = 0;
    *out = strtod(plain, &end);
    return !*end && isfinite(*out) ? p : NULL;
}

int number_option(int argc, char **argv, int *i, int zero_ok, double *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i), *end;
    double d = 0;
    if (!v) return RC_USAGE;
    end = decimal_number(v, &d);
    if (!end || *end || d < 0 || (d == 0 && !zero_ok))
        return complain(RC_USAGE, "%s %s: not a %s finite number", opt, v, zero_ok ? "non-negative" : "positive");
    *out = d;
    return RC_OK;
}

int count_option(int argc, char **argv, int *i, size_t max, size_t *out)
{
    return whole_option(argc, argv, i, 1, max, out);
}

const char *whole_number(const char *text, unsigned long long *out)
{
    char *end;
    if (*text < '0' || *text > '9') return NULL;
    *out = strtoull(text, &end, 10); /* past the largest: ULLONG_MAX */
    return end;
}

int whole_option(int argc, char **argv, int *i, size_t least, size_t max, size_t *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i), *end;
    unsigned long long n = 0;
    if (!v) return RC_USAGE;
    errno = 0;
    end = whole_number(v, &n);
    if (!end || *end)
        return complain(RC_USAGE, "%s %s: not a whole number from %zu to %zu", opt, v, least, max);
    if (errno == ERANGE || n > max) return complain(RC_USAGE, "%s %s: too large, the most is %zu", opt, v, max);
    if (n < least) return complain(RC_USAGE, "%s %s: too small, the least is %zu", opt, v, least);
    *out = (size_t)n;
    return RC_OK;
}

int name_option(int argc, char **argv, int *i, const char *const *names, int count, const char *choices, int *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i);
    int k;
    if (!v) return RC_USAGE;
    for (k = 0; k < count; k++)
        if (!strcmp(v, names[k])) {
            *out = k;
            return RC_OK;
        }
    return complain(RC_USAGE, "%s %s: unknown, expected %s", opt, v, choices);
}

int parse_numbers(const char *text, char sep, int n, double *out)
{
    const char *p = text;
    int k;
    for (k = 0; k < n; k++) {
        const char *end = decimal_number(p, &out[k]);
        if (!end || *end != (k + 1 < n ? sep : '\0')) return 0;
        p = end + 1;
    }
    return 1;
}

int numbers_option(int argc, char **argv, int *i, char sep, int n, const char *form, double *out)
{
    const char *opt = argv[*i], *v = value_of(argc, argv, i);
    if (!v) return RC_USAGE;
    if (!parse_numbers(v, sep, n, out)) return complain(RC_USAGE, "%s %s: expected %s", opt, v, form);
    return RC_OK;
}
