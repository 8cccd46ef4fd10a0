/* The line parser of gcode.h. Numbers are copied out before strtod reads
   them, so nothing reads past a line. */
#include "gcode.h"
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The number at line[*at, len) (sign, digits, one point), moving *at past
   it; 0 when there is none or it does not fit. */
static int number_at(const char *line, size_t len, size_t *at, double *v)
{
    char text[40];
    size_t n = 0, i = *at;
    int digits = 0, point = 0;
    char *end;
    while (i < len && line[i] == ' ') i++;
    if (i < len && (line[i] == '-' || line[i] == '+')) text[n++] = line[i++];
    for (; i < len && n + 1 < sizeof text; i++) {
        if (isdigit((unsigned char)line[i])) digits++;
        else if (line[i] == '.' && !point) point = 1;
        else break;
        text[n++] = line[i];
    }
    if (!digits || (i < len && (isdigit((unsigned char)line[i]) || line[i] == '.'))) return 0;
    text[n] = 0;
    *v = strtod(text, &end);
    if (*end || !isfinite(*v)) return 0;
    *at = i;
    return 1;
}

int gcode_parse(const char *line, size_t len, gcode_words *w, size_t *bad)
{
    static const char AXES[] = "XYZEF";
    size_t i = 0;
    memset(w, 0, sizeof *w);
    while (i < len && line[i] != ';') {
        char c = (char)toupper((unsigned char)line[i]);
        double v;
        const char *axis;
        size_t at = i;
        if (c == ' ' || c == '\t' || c == '\r') { i++; continue; }
        i++;
        if (!isalpha((unsigned char)c) || !number_at(line, len, &i, &v)) { *bad = at; return -1; }
        if (!w->letter && (c == 'G' || c == 'M' || c == 'T')) {
            if (!(v >= 0 && v < 10000)) { *bad = at; return -1; }
            w->letter = c;
            w->code = (int)v;
        } else if ((axis = strchr(AXES, c)) != NULL) {
            unsigned bit = 1u << (axis - AXES);
            if (w->has & bit) { *bad = at; return -1; }
            w->has |= bit;
            w->v[axis - AXES] = v;
        }
        /* other words (S, P, R, I, J ...) belong to commands contour leaves alone */
    }
    return 0;
}

int gcode_is_comment(const char *line, size_t len, const char *key)
{
    size_t n = strlen(key);
    return len > n && line[0] == ';' && !memcmp(line + 1, key, n);
}

int gcode_comment_number(const char *line, size_t len, const char *key, double *v)
{
    size_t at = strlen(key) + 1;
    if (!gcode_is_comment(line, len, key)) return 0;
    return number_at(line, len, &at, v) && (at == len || line[at] == '\r' || line[at] == ' ');
}

const char *gcode_config_value(const char *text, size_t len, const char *key, size_t *n)
{
    size_t k = strlen(key), end = len;
    for (;;) {
        size_t start = end, m;
        const char *l;
        while (start > 0 && text[start - 1] != '\n') start--;
        l = text + start;
        m = end - start;
        while (m && l[m - 1] == '\r') m--;
        if (m > k + 5 && !memcmp(l, "; ", 2) && !memcmp(l + 2, key, k) && !memcmp(l + 2 + k, " = ", 3)) {
            *n = m - k - 5;
            return l + k + 5;
        }
        if (!start) return NULL;
        end = start - 1;
    }
}
