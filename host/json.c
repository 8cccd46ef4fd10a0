/* The JSON writer: see json.h. */
#include "json.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

void json_init(json_writer *w, FILE *f)
{
    memset(w, 0, sizeof *w);
    w->f = f;
}

/* The characters that need no escape go a span at a time: a character at a
   time, a job's manifest (a key and a file name for each of thousands of
   layers) took a millisecond or two of its stream's locking. */
static void json_quote(FILE *f, const char *s)
{
    fputc('"', f);
    while (*s) {
        size_t n = 0;
        unsigned char c;
        while ((c = (unsigned char)s[n]) != 0 && c != '"' && c != '\\' && c >= 0x20) n++;
        fwrite(s, 1, n, f);
        if (!(c = (unsigned char)s[n])) break;
        if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
        else fprintf(f, "\\u%04x", c);
        s += n + 1;
    }
    fputc('"', f);
}

static void json_write_number(json_writer *w, double v)
{
    unsigned char bits[sizeof(double)];
    unsigned h = 0;
    char *text;
    size_t i;
    int digits;
    if (!isfinite(v)) {
        fputs("null", w->f);
        return;
    }
    memcpy(bits, &v, sizeof bits); /* not ==: 0 and -0 are written apart */
    for (i = 0; i < sizeof bits; i++) h = h * 31 + bits[i];
    text = w->memo[h % JSON_MEMO].text;
    if (!text[0] || memcmp(w->memo[h % JSON_MEMO].bits, bits, sizeof bits)) {
        /* the shortest of %.15g .. %.17g that reads back as v */
        for (digits = 15; digits < 17; digits++) {
            snprintf(text, sizeof w->memo[0].text, "%.*g", digits, v);
            if (strtod(text, NULL) == v) break;
        }
        if (digits == 17) snprintf(text, sizeof w->memo[0].text, "%.17g", v);
        memcpy(w->memo[h % JSON_MEMO].bits, bits, sizeof bits);
    }
    fputs(text, w->f);
}

/* The comma, the line break and the key before a value at the current depth. */
static void json_member(json_writer *w, const char *key)
{
    int d = w->depth;
    if (d > 0) {
        if (w->members[d]) fputc(',', w->f);
        if (w->oneline[d]) {
            if (w->members[d]) fputc(' ', w->f);
        } else {
            fprintf(w->f, "\n%*s", 2 * d, "");
        }
        w->members[d] = 1;
    }
    if (key) {
        json_quote(w->f, key);
        fputs(": ", w->f);
    }
}

static void json_begin(json_writer *w, const char *key, int oneline, char open)
{
    json_member(w, key);
    fputc(open, w->f);
    if (w->depth + 1 >= JSON_MAX_DEPTH) abort();   /* a writer's bug, not the data's */
    w->depth++;
    w->members[w->depth] = 0;
    w->oneline[w->depth] = (unsigned char)(oneline || w->oneline[w->depth - 1]);
    w->close[w->depth] = open == '{' ? '}' : ']';
}

void json_begin_object(json_writer *w, const char *key, int oneline) { json_begin(w, key, oneline, '{'); }
void json_begin_array(json_writer *w, const char *key, int oneline) { json_begin(w, key, oneline, '['); }

void json_end(json_writer *w)
{
    int d = w->depth;
    if (d <= 0) abort();
    if (w->members[d] && !w->oneline[d]) fprintf(w->f, "\n%*s", 2 * (d - 1), "");
    fputc(w->close[d], w->f);
    w->depth--;
    if (w->depth == 0) fputc('\n', w->f);
}

void json_string(json_writer *w, const char *key, const char *v)
{
    json_member(w, key);
    if (v) json_quote(w->f, v);
    else fputs("null", w->f);
}

void json_number(json_writer *w, const char *key, double v)
{
    json_member(w, key);
    json_write_number(w, v);
}

void json_numbers(json_writer *w, const char *key, const double *v, size_t n)
{
    size_t i;
    json_begin_array(w, key, 1);
    for (i = 0; i < n; i++) json_number(w, NULL, v[i]);
    json_end(w);
}

void json_int(json_writer *w, const char *key, long long v)
{
    json_member(w, key);
    fprintf(w->f, "%lld", v);
}

void json_bool(json_writer *w, const char *key, int v)
{
    json_member(w, key);
    fputs(v ? "true" : "false", w->f);
}

void json_raw(json_writer *w, const char *key, const char *json, size_t n)
{
    json_member(w, key);
    fwrite(json, 1, n, w->f);
}

void json_null(json_writer *w, const char *key)
{
    json_member(w, key);
    fputs("null", w->f);
}
