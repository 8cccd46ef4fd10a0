/* A profile read from a file: see profile_csv.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* strncasecmp */
#endif
#include "profile_csv.h"
#include "options.h"
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Appends v to the growing array *phi of *n values. */
static int push(double **phi, size_t *n, size_t *cap, double v)
{
    if (*n == *cap) {
        size_t grown = *cap ? 2 * *cap : 4096;
        double *p = grown > SIZE_MAX / sizeof *p ? NULL : realloc(*phi, grown * sizeof *p);
        if (!p) return 0;
        *phi = p;
        *cap = grown;
    }
    (*phi)[(*n)++] = v;
    return 1;
}

/* The z column of a profile so far: the first, second and latest z, and the
   lines of the first two. */
typedef struct z_column { double first, second, last; size_t first_line, second_line; } z_column;

/* The z of value `index`: the first two set the step, which every later one
   keeps to 1 % (a column printed with %.9g is exact to far less). */
static int z_column_add(z_column *c, const char *path, size_t line, size_t index, double z)
{
    double step = c->second - c->first;
    if (index == 0) {
        c->first = c->last = z;
        c->first_line = line;
        return RC_OK;
    }
    if (!(z > c->last)) return complain(RC_FAIL, "%s:%zu: z %g is not above the line before's, %g", path, line, z, c->last);
    if (index == 1) {
        c->second = z;
        c->second_line = line;
    } else if (fabs(z - c->last - step) > 0.01 * step) {
        return complain(RC_FAIL, "%s:%zu: z %g is %g mm above the line before, not %g as from line %zu to %zu: "
                                 "the z column must be evenly spaced", path, line, z, z - c->last, step,
                        c->first_line, c->second_line);
    }
    c->last = z;
    return RC_OK;
}

/* The bin of an evenly spaced z column of n values, to six digits: the %.9g
   centres --profile-out writes give it to about nine, and 0.0099999999 for
   0.01 would change the bins a layer may take (ceil(tmin/b)). */
static double z_column_bin(const z_column *c, size_t n)
{
    char six[32];
    snprintf(six, sizeof six, "%.6g", (c->last - c->first) / (double)(n - 1));
    return strtod(six, NULL);
}

/* A z in the first column, before the first comma: 1 if there is one. */
static int z_field(const char *s, const char *comma, double *z)
{
    const char *end = decimal_number(s, z);
    while (end && end < comma && (*end == ' ' || *end == '\t')) end++;
    return end == comma;
}

/* A sign, then a digit, a point, or inf or nan in any case. */
static int starts_as_number(const char *s)
{
    s += *s == '+' || *s == '-';
    return (*s >= '0' && *s <= '9') || *s == '.' || !strncasecmp(s, "inf", 3) || !strncasecmp(s, "nan", 3);
}

int profile_csv_read(const char *path, adaslice_metric metric, double bin_given, double max_bytes,
                     adaslice_profile *out)
{
    FILE *f = fopen(path, "r");
    char line[TEXT_LINE_MAX], q[QUOTE_SIZE], limit[32];
    size_t lineno = 0, n = 0, cap = 0, first_line = 0;
    double *phi = NULL, bin = bin_given ? bin_given : ADASLICE_DEFAULT_BIN;
    z_column zc = {0, 0, 0, 0, 0};
    int rc = RC_OK, first = 1, has_z = 0;

    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    while (!rc && text_line_read(f, path, lineno + 1, line, RC_FAIL, &rc)) {
        char *s, *comma, *field;
        const char *end;
        double v = 0, z = 0;
        lineno++;
        /* a spreadsheet's UTF-8 byte order mark */
        s = text_line_trim(lineno == 1 && !strncmp(line, "\xef\xbb\xbf", 3) ? line + 3 : line);
        comma = strchr(s, ',');
        if (!*s || *s == '#') continue;
        field = comma ? text_line_trim(strrchr(s, ',') + 1) : s;
        end = decimal_number(field, &v);
        if (comma && strchr(comma + 1, ',')) {
            /* a plan's rows (layer,z_bottom,...) read as a profile took their last column */
            rc = complain(RC_FAIL, "%s:%zu: '%s': a profile's line is phi or z,phi, not more fields", path, lineno,
                          quote_text(q, s, strlen(s)));
        } else if (!end || *end || (comma && !z_field(s, comma, &z))) {
            /* the first line may be a header, unless it begins as a number does */
            if (!first || starts_as_number(s))
                rc = complain(RC_FAIL, "%s:%zu: not a number: '%s'", path, lineno, quote_text(q, s, strlen(s)));
        } else if (!isfinite(v) || v < 0) {
            rc = complain(RC_FAIL, "%s:%zu: '%s': profile values must be finite and >= 0", path, lineno,
                          quote_text(q, s, strlen(s)));
        } else if (n && has_z != (comma != NULL)) {
            rc = complain(RC_FAIL, "%s:%zu: '%s' has %s z column, unlike line %zu", path, lineno,
                          quote_text(q, s, strlen(s)), comma ? "a" : "no", first_line);
        } else if (comma && (rc = z_column_add(&zc, path, lineno, n, z))) {
            /* z_column_add said why */
        } else if ((double)(n + 1) * sizeof *phi > max_bytes) {
            rc = complain(RC_FAIL, "%s:%zu: the profile passes --memory %s at %zu values; a larger --memory", path,
                          lineno, size_text(max_bytes, limit), n + 1);
        } else if (!push(&phi, &n, &cap, v)) {
            rc = complain(RC_FAIL, "%s: out of memory after %zu value%s", path, n, plural(n));
        } else if (n == 1) {
            first_line = lineno;
            has_z = comma != NULL;
        }
        first = 0;
    }
    if (!rc && !n) rc = complain(RC_FAIL, "%s: no profile values", path);
    if (!rc && has_z && n > 1) {
        double column = z_column_bin(&zc, n);
        if (!bin_given) bin = column;
        else if (fabs(column - bin_given) > 1e-6 * bin_given)
            rc = complain(RC_USAGE, "%s:%zu: the z column has bins of %g mm, but --bin is %g mm", path, zc.second_line,
                          column, bin_given);
    }
    fclose(f);
    if (rc) {
        free(phi);
        return rc;
    }
    memset(out, 0, sizeof *out);
    out->metric = metric;
    out->bin_count = n;
    out->bin = bin;
    out->z0 = has_z ? zc.first - bin / 2 : 0;
    out->height = n * bin;
    out->phi = phi;
    return RC_OK;
}
