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

/* Every write through these, its failure kept in w->failed: a memory
   stream (glibc's) that cannot grow drops the characters and says so in
   the call's result only, not in ferror. */
static void put(json_writer *w, const char *s, size_t n)
{
    if (n && fwrite(s, 1, n, w->f) != n) w->failed = 1;
}

static void put_s(json_writer *w, const char *s) { put(w, s, strlen(s)); }

static void put_c(json_writer *w, char c)
{
    if (fputc(c, w->f) == EOF) w->failed = 1;
}

/* A line break and `spaces` of indent. */
static void put_indent(json_writer *w, int spaces)
{
    static const char blank[] = "                                ";
    put_c(w, '\n');
    for (; spaces > 0; spaces -= (int)sizeof blank - 1)
        put(w, blank, spaces < (int)sizeof blank - 1 ? (size_t)spaces : sizeof blank - 1);
}

/* The characters that need no escape go a span at a time: a character at a
   time, a job's manifest (a key and a file name for each of thousands of
   layers) took a millisecond or two of its stream's locking. */
static void json_quote(json_writer *w, const char *s)
{
    put_c(w, '"');
    while (*s) {
        size_t n = 0;
        unsigned char c;
        char escape[8];
        while ((c = (unsigned char)s[n]) != 0 && c != '"' && c != '\\' && c >= 0x20) n++;
        put(w, s, n);
        if (!(c = (unsigned char)s[n])) break;
        if (c == '"' || c == '\\') snprintf(escape, sizeof escape, "\\%c", c);
        else snprintf(escape, sizeof escape, "\\u%04x", c);
        put_s(w, escape);
        s += n + 1;
    }
    put_c(w, '"');
}

static void json_write_number(json_writer *w, double v)
{
    unsigned char bits[sizeof(double)];
    unsigned h = 0;
    char *text;
    size_t i;
    int digits;
    if (!isfinite(v)) {
        put_s(w, "null");
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
    put_s(w, text);
}

/* The comma, the line break and the key before a value at the current depth. */
static void json_member(json_writer *w, const char *key)
{
    int d = w->depth;
    if (d > 0) {
        if (w->members[d]) put_c(w, ',');
        if (w->oneline[d]) {
            if (w->members[d]) put_c(w, ' ');
        } else {
            put_indent(w, 2 * d);
        }
        w->members[d] = 1;
    }
    if (key) {
        json_quote(w, key);
        put_s(w, ": ");
    }
}

static void json_begin(json_writer *w, const char *key, int oneline, char open)
{
    json_member(w, key);
    put_c(w, open);
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
    if (w->members[d] && !w->oneline[d]) put_indent(w, 2 * (d - 1));
    put_c(w, w->close[d]);
    w->depth--;
    if (w->depth == 0) put_c(w, '\n');
}

void json_string(json_writer *w, const char *key, const char *v)
{
    json_member(w, key);
    if (v) json_quote(w, v);
    else put_s(w, "null");
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
    char text[24];
    json_member(w, key);
    snprintf(text, sizeof text, "%lld", v);
    put_s(w, text);
}

void json_bool(json_writer *w, const char *key, int v)
{
    json_member(w, key);
    put_s(w, v ? "true" : "false");
}

void json_raw(json_writer *w, const char *key, const char *json, size_t n)
{
    json_member(w, key);
    put(w, json, n);
}

void json_null(json_writer *w, const char *key)
{
    json_member(w, key);
    put_s(w, "null");
}
