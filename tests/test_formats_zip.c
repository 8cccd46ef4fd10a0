/* Tests of the ChiTu G-code zip, Prusa SL1 and UVtools UVJ writers
   (host/formats/fmt_chitu_zip.c, host/formats/fmt_sl1.c, host/formats/fmt_uvj.c). The reader here
   follows the formats' documentation, not the writers: members come out
   through Info-ZIP's unzip -p, images through OpenImageIO's oiiotool;
   run.gcode is run line by line as a printer would (absolute moves after
   G90, M6054 shows an image, the light is on from M106 S255 to M106 S0), so
   a layer's Z is where the moves left the plate when the light went on and
   its exposure the G4 waits while it is on; config.ini is read as slafw
   reads it (first layer layerHeightFirst, then layerHeight each); config.json
   by a strict JSON reader of its own, as UVtools' classes name the keys. Two sources: job_descs made here and handed to the
   formats directly, and jobs written by adaslice slice, held against the
   job directory the same slice writes (masks.rle, manifest.json). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* dup */
#endif
#include "util.h"
#include "check.h"
#include "cli_run.h"
#include "maskgen.h"
#include "tool_run.h"
#include "../host/formats/jobfile.h"
#include "../host/printer.h"
#include "../adaslice_mcu.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* DIR/name, each of the last 16 valid */
static const char *in_dir(const char *name)
{
    static char ring[16][600];
    static int next;
    char *p = ring[next++ & 15];
    snprintf(p, sizeof ring[0], "%s", cli_path(name));
    return p;
}


/* ---- the archive through unzip, the images through oiiotool ----------- */

/* unzip -p ARCHIVE NAME: the member's bytes (NUL-terminated), or NULL. */
static unsigned char *member(const char *archive, const char *name, size_t *size)
{
    char *argv[] = {(char *)"unzip", (char *)"-p", (char *)archive, (char *)name, NULL};
    unsigned char *data;
    int st = tool_run("unzip", argv, in_dir("member"), in_dir("unzip.log"));
    data = st == 0 ? read_whole_file(in_dir("member"), size) : NULL;
    if (!data) *size = 0;
    remove(in_dir("member"));
    remove(in_dir("unzip.log"));
    return data;
}

/* unzip -Z1: the member names, one a line. */
static char *member_names(const char *archive)
{
    char *argv[] = {(char *)"unzip", (char *)"-Z1", (char *)archive, NULL};
    size_t n;
    char *names = tool_run("unzip", argv, in_dir("names"), in_dir("unzip.log")) == 0
                      ? (char *)read_whole_file(in_dir("names"), &n) : NULL;
    remove(in_dir("names"));
    remove(in_dir("unzip.log"));
    return names;
}

static int has_line(const char *text, const char *line)
{
    size_t n = strlen(line);
    for (const char *p = text; p && (p = strstr(p, line)) != NULL; p++)
        if ((p == text || p[-1] == '\n') && p[n] == '\n') return 1;
    return 0;
}

static size_t line_count(const char *text)
{
    size_t n = 0;
    for (; text && *text; text++) n += *text == '\n';
    return n;
}

/* The PNG's IHDR (PNG specification 11.2.2): width, height, depth, colour type. */
static int png_header(const unsigned char *png, size_t size, int *w, int *h, int *depth, int *colour)
{
    if (size < 33 || memcmp(png, "\x89PNG\r\n\x1a\n", 8) || memcmp(png + 12, "IHDR", 4)) return 0;
    *w = (int)((uint32_t)png[16] << 24 | (uint32_t)png[17] << 16 | (uint32_t)png[18] << 8 | png[19]);
    *h = (int)((uint32_t)png[20] << 24 | (uint32_t)png[21] << 16 | (uint32_t)png[22] << 8 | png[23]);
    *depth = png[24];
    *colour = png[25];
    return 1;
}

enum { BATCH = 16 }; /* images per oiiotool run: it takes a while to start */

/* The PNGs, decoded by one oiiotool run, each to w x h pixels of `channels`
   bytes (1 grey, 3 RGB) in out[i], or NULL. */
static void decode_pngs(unsigned char *const *png, const size_t *size, size_t count, int w, int h, int channels,
                        unsigned char **out)
{
    char in[BATCH][600], pnm[BATCH][600], *argv[2 + 5 * BATCH] = {(char *)"oiiotool"};
    size_t want = (size_t)w * (size_t)h * (size_t)channels, i;
    int n = 1, ran;
    for (i = 0; i < count && i < BATCH; i++) {
        char name[32];
        FILE *f;
        out[i] = NULL;
        snprintf(name, sizeof name, "image%zu.png", i);
        snprintf(in[i], sizeof in[i], "%s", in_dir(name));
        snprintf(name, sizeof name, channels == 3 ? "image%zu.ppm" : "image%zu.pgm", i);
        snprintf(pnm[i], sizeof pnm[i], "%s", in_dir(name));
        f = fopen(in[i], "wb");
        CHECKF(f && fwrite(png[i], 1, size[i], f) == size[i] && fclose(f) == 0, "cannot write %.200s", in[i]);
        argv[n++] = in[i];
        argv[n++] = (char *)"-d";
        argv[n++] = (char *)"uint8";
        argv[n++] = (char *)"-o";
        argv[n++] = pnm[i];
    }
    argv[n] = NULL;
    ran = tool_run("openimageio-tools", argv, in_dir("oiiotool.log"), in_dir("oiiotool.log")) == 0;
    CHECKF(ran, "oiiotool cannot read the PNGs");
    for (i = 0; i < count && i < BATCH; i++) {
        size_t got;
        unsigned char *text = ran ? read_whole_file(pnm[i], &got) : NULL;
        int width, height, maxval, used = 0;
        if (text && sscanf((char *)text, channels == 3 ? "P6 %d %d %d%n" : "P5 %d %d %d%n", &width, &height,
                           &maxval, &used) == 3 && width == w && height == h && maxval == 255 &&
            got - (size_t)used - 1 == want && (out[i] = (unsigned char *)malloc(want)) != NULL)
            memcpy(out[i], text + used + 1, want);
        free(text);
        remove(in[i]);
        remove(pnm[i]);
    }
    remove(in_dir("oiiotool.log"));
}

/* Members names[0 .. count) are 8-bit grey PNGs (colour type 0) of w x h
   equal to want[i] (w x h bytes) pixel for pixel. */
static void check_grey_members(const char *archive, char (*names)[96], size_t count, int w, int h,
                               unsigned char *const *want)
{
    for (size_t at = 0; at < count && !check_case_failed(); at += BATCH) {
        size_t m = count - at < BATCH ? count - at : BATCH, size[BATCH];
        unsigned char *png[BATCH] = {NULL}, *got[BATCH] = {NULL};
        for (size_t i = 0; i < m; i++) {
            int pw = 0, ph = 0, depth = 0, colour = -1;
            png[i] = member(archive, names[at + i], &size[i]);
            CHECKF(png[i] && png_header(png[i], size[i], &pw, &ph, &depth, &colour) && pw == w && ph == h &&
                       depth == 8 && colour == 0,
                   "%s: not an 8-bit grey %dx%d PNG (%dx%d, depth %d, colour type %d)", names[at + i], w, h, pw, ph,
                   depth, colour);
        }
        if (!check_case_failed()) decode_pngs(png, size, m, w, h, 1, got);
        for (size_t i = 0; i < m && !check_case_failed(); i++) {
            size_t wrong = 0, first = 0;
            CHECKF(got[i], "%s: oiiotool gave no %dx%d image", names[at + i], w, h);
            for (size_t p = 0; got[i] && p < (size_t)w * (size_t)h; p++)
                if (got[i][p] != want[at + i][p] && wrong++ == 0) first = p;
            CHECKF(wrong == 0, "%s: %zu pixels differ, the first at (%zu, %zu): %d, not %d", names[at + i], wrong,
                   first % (size_t)w, first / (size_t)w, got[i] ? got[i][first] : -1, want[at + i][first]);
        }
        for (size_t i = 0; i < m; i++) {
            free(png[i]);
            free(got[i]);
        }
    }
}

/* ---- run.gcode, run as a printer runs it -------------------------------- */

typedef struct gc_layer {
    double z;            /* where the plate is when the light goes on */
    double peak;         /* the highest it went since the last exposure */
    double lift_f, drop_f; /* feeds of the last move up and the last move down, mm/min */
    double wait_ms, exposure_ms;
    int image;           /* n of the last M6054 "n.png" */
} gc_layer;

typedef struct gcode {
    char key[64][40], value[64][96]; /* the ";key:value" header, in order */
    int keys;
    gc_layer *layers;
    size_t count;
    int absolute, homed_first;       /* G90 seen; G28 before the first move */
    double end_z;                    /* where the last move leaves the plate */
    char error[160];
} gcode;

static const char *gc_value(const gcode *g, const char *key)
{
    for (int i = 0; i < g->keys; i++)
        if (!strcmp(g->key[i], key)) return g->value[i];
    return NULL;
}

static double gc_number(const gcode *g, const char *key)
{
    const char *v = gc_value(g, key);
    return v ? strtod(v, NULL) : NAN;
}

/* A word's number ("Z5.05" in "G0 Z5.05 F65"), if the command has it. */
static int word(const char *cmd, char letter, double *v)
{
    for (const char *p = cmd; (p = strchr(p, letter)) != NULL; p++)
        if (p > cmd && p[-1] == ' ') {
            char *end;
            *v = strtod(p + 1, &end);
            return end > p + 1;
        }
    return 0;
}

static int parse_gcode(const char *text, gcode *g)
{
    size_t cap = 0;
    double z = 0, peak = 0, lift_f = 0, drop_f = 0, wait = 0, exposure = 0;
    int light = 0, image = 0, moved = 0, in_header = 1;
    memset(g, 0, sizeof *g);
    for (const char *line = text; *line;) {
        const char *nl = strchr(line, '\n');
        size_t n = nl ? (size_t)(nl - line) : strlen(line);
        char cmd[256];
        double v;
        if (n >= sizeof cmd) n = sizeof cmd - 1;
        memcpy(cmd, line, n);
        cmd[n] = 0;
        line += n + (nl != NULL);
        if (cmd[0] == ';') {
            char *colon = strchr(cmd, ':');
            if (!strcmp(cmd, ";START_GCODE_BEGIN")) in_header = 0;
            if (in_header && colon && g->keys < 64) {
                *colon = 0;
                snprintf(g->key[g->keys], sizeof g->key[0], "%.39s", cmd + 1);
                snprintf(g->value[g->keys++], sizeof g->value[0], "%.95s", colon + 1);
            }
            continue;
        }
        if (strchr(cmd, ';')) *strchr(cmd, ';') = 0; /* a command's comment */
        if (!strncmp(cmd, "G90", 3)) g->absolute = 1;
        else if (!strncmp(cmd, "G91", 3)) g->absolute = 0;
        else if (!strncmp(cmd, "G28", 3)) { z = 0; g->homed_first = !moved; }
        else if (!strncmp(cmd, "G0 ", 3) || !strncmp(cmd, "G1 ", 3)) {
            double to = z, f = 0;
            if (!g->absolute) {
                snprintf(g->error, sizeof g->error, "a move while not absolute: %.80s", cmd);
                return 0;
            }
            if (word(cmd, 'Z', &to)) {
                word(cmd, 'F', &f);
                if (to > z) lift_f = f;
                if (to < z) drop_f = f;
                z = to;
                if (z > peak) peak = z;
            }
            moved = 1;
        } else if (!strncmp(cmd, "M6054 \"", 7)) {
            image = atoi(cmd + 7);
        } else if (!strncmp(cmd, "G4 ", 3)) {
            if (!word(cmd, 'P', &v)) { snprintf(g->error, sizeof g->error, "G4 without P: %.80s", cmd); return 0; }
            if (light) exposure += v;
            else wait += v;
        } else if (!strncmp(cmd, "M106 S255", 9)) {
            light = 1;
            exposure = 0;
            if (g->count == cap) {
                gc_layer *more = (gc_layer *)realloc(g->layers, (cap = cap * 2 + 16) * sizeof *more);
                if (!more) return 0;
                g->layers = more;
            }
            g->layers[g->count] = (gc_layer){z, peak, lift_f, drop_f, wait, 0, image};
        } else if (!strncmp(cmd, "M106 S0", 7)) {
            if (light) {
                g->layers[g->count++].exposure_ms = exposure;
                peak = z;
                wait = 0;
            }
            light = 0;
        }
    }
    g->end_z = z;
    return 1;
}

/* ---- config.json, read strictly as RFC 8259 has it -------------------- */

/* A JSON value: an object's members keep their order (keys[i], items[i]). */
enum { J_NULL, J_BOOL, J_NUMBER, J_STRING, J_ARRAY, J_OBJECT };
typedef struct jvalue {
    int type;
    double number;               /* J_NUMBER, J_BOOL (0 or 1) */
    int integer;                 /* J_NUMBER written without a fraction or exponent */
    char *string;                /* J_STRING, escapes of ASCII decoded */
    struct jvalue *items;        /* J_ARRAY, J_OBJECT */
    char **keys;                 /* J_OBJECT */
    size_t count;
} jvalue;

typedef struct jparser {
    const char *text, *at;
    char error[160];
} jparser;

static void jfree(jvalue *v)
{
    for (size_t i = 0; i < v->count; i++) {
        jfree(&v->items[i]);
        if (v->keys) free(v->keys[i]);
    }
    free(v->items);
    free(v->keys);
    free(v->string);
    memset(v, 0, sizeof *v);
}

static int jfail(jparser *p, const char *what)
{
    if (!p->error[0]) snprintf(p->error, sizeof p->error, "%s at byte %ld", what, (long)(p->at - p->text));
    return 0;
}

static void jspace(jparser *p)
{
    while (*p->at == ' ' || *p->at == '\t' || *p->at == '\n' || *p->at == '\r') p->at++;
}

static int jstring(jparser *p, char **out)
{
    size_t cap = 16, n = 0;
    char *s = (char *)malloc(cap);
    p->at++; /* the quote */
    while (s && *p->at != '"') {
        int c = (unsigned char)*p->at++;
        if (c < 0x20) { free(s); return jfail(p, "a control character or the end in a string"); }
        if (c == '\\') {
            const char *from = "\"\\/bfnrt", *to = "\"\\/\b\f\n\r\t", *e = strchr(from, *p->at);
            if (*p->at == 'u') {
                unsigned u = 0;
                for (int i = 1; i <= 4; i++) {
                    char h = p->at[i];
                    if (!((h >= '0' && h <= '9') || (h >= 'a' && h <= 'f') || (h >= 'A' && h <= 'F'))) {
                        free(s);
                        return jfail(p, "a bad \\u escape");
                    }
                    u = u * 16 + (unsigned)(h <= '9' ? h - '0' : (h | 32) - 'a' + 10);
                }
                p->at += 5;
                c = u < 0x80 ? (int)u : '?';
            } else if (*p->at && e) {
                c = to[e - from];
                p->at++;
            } else {
                free(s);
                return jfail(p, "a bad escape");
            }
        }
        if (n + 2 > cap) {
            char *more = (char *)realloc(s, cap *= 2);
            if (!more) { free(s); return jfail(p, "out of memory"); }
            s = more;
        }
        s[n++] = (char)c;
    }
    if (!s) return jfail(p, "out of memory");
    s[n] = 0;
    p->at++;
    *out = s;
    return 1;
}

static int jnumber(jparser *p, jvalue *v)
{
    const char *s = p->at;
    int integer = 1;
    if (*s == '-') s++;
    if (*s == '0') s++;
    else if (*s >= '1' && *s <= '9') while (*s >= '0' && *s <= '9') s++;
    else return jfail(p, "a bad number");
    if (*s == '.') {
        integer = 0;
        if (*++s < '0' || *s > '9') return jfail(p, "a bad fraction");
        while (*s >= '0' && *s <= '9') s++;
    }
    if (*s == 'e' || *s == 'E') {
        integer = 0;
        if (*++s == '+' || *s == '-') s++;
        if (*s < '0' || *s > '9') return jfail(p, "a bad exponent");
        while (*s >= '0' && *s <= '9') s++;
    }
    v->type = J_NUMBER;
    v->integer = integer;
    v->number = strtod(p->at, NULL);
    p->at = s;
    return 1;
}

static int jvalue_parse(jparser *p, jvalue *v, int depth);

/* An array's or an object's members, after its opening bracket. */
static int jmembers(jparser *p, jvalue *v, int object, int depth)
{
    size_t cap = 0;
    char close = object ? '}' : ']';
    v->type = object ? J_OBJECT : J_ARRAY;
    p->at++;
    jspace(p);
    if (*p->at == close) { p->at++; return 1; }
    for (;;) {
        char *key = NULL;
        jspace(p);
        if (object) {
            if (*p->at != '"' || !jstring(p, &key)) return jfail(p, "a member without a quoted key");
            for (size_t i = 0; i < v->count; i++)
                if (!strcmp(v->keys[i], key)) { free(key); return jfail(p, "a key given twice"); }
            jspace(p);
            if (*p->at++ != ':') { free(key); return jfail(p, "no ':' after a key"); }
        }
        if (v->count == cap) {
            jvalue *items = (jvalue *)realloc(v->items, (cap = cap * 2 + 8) * sizeof *items);
            char **keys = object ? (char **)realloc(v->keys, cap * sizeof *keys) : NULL;
            if (items) v->items = items;
            if (keys) v->keys = keys;
            if (!items || (object && !keys)) { free(key); return jfail(p, "out of memory"); }
        }
        memset(&v->items[v->count], 0, sizeof *v->items);
        if (object) v->keys[v->count] = key;
        v->count++;
        if (!jvalue_parse(p, &v->items[v->count - 1], depth + 1)) return 0;
        jspace(p);
        if (*p->at == ',') { p->at++; continue; }
        if (*p->at == close) { p->at++; return 1; }
        return jfail(p, object ? "no ',' or '}' after a member" : "no ',' or ']' after an item");
    }
}

static int jvalue_parse(jparser *p, jvalue *v, int depth)
{
    jspace(p);
    if (depth > 32) return jfail(p, "nested too deep");
    switch (*p->at) {
    case '{': return jmembers(p, v, 1, depth);
    case '[': return jmembers(p, v, 0, depth);
    case '"': v->type = J_STRING; return jstring(p, &v->string);
    case 't': if (strncmp(p->at, "true", 4)) break; p->at += 4; v->type = J_BOOL; v->number = 1; return 1;
    case 'f': if (strncmp(p->at, "false", 5)) break; p->at += 5; v->type = J_BOOL; return 1;
    case 'n': if (strncmp(p->at, "null", 4)) break; p->at += 4; v->type = J_NULL; return 1;
    default: return jnumber(p, v);
    }
    return jfail(p, "an unknown word");
}

/* The document in text: 1, or 0 with the reason in error. */
static int jparse(const char *text, jvalue *v, char *error, size_t size)
{
    jparser p = {text, text, ""};
    int ok;
    memset(v, 0, sizeof *v);
    ok = jvalue_parse(&p, v, 0);
    if (ok) {
        jspace(&p);
        if (*p.at) ok = jfail(&p, "more after the document");
    }
    if (!ok) jfree(v);
    snprintf(error, size, "%s", p.error);
    return ok;
}

/* The member at a dotted path ("Properties.Size.X") of nested objects, or NULL. */
static const jvalue *jget(const jvalue *v, const char *path)
{
    while (v && *path) {
        const char *dot = strchr(path, '.');
        size_t n = dot ? (size_t)(dot - path) : strlen(path), i;
        const jvalue *next = NULL;
        for (i = 0; v->type == J_OBJECT && i < v->count; i++)
            if (strlen(v->keys[i]) == n && !strncmp(v->keys[i], path, n)) next = &v->items[i];
        v = next;
        path += n + (dot != NULL);
    }
    return v;
}

/* The number at path, NAN if there is none. */
static double jnum(const jvalue *v, const char *path)
{
    const jvalue *m = jget(v, path);
    return m && m->type == J_NUMBER ? m->number : NAN;
}

/* The integer at path if it is one written as an integer in [0, max] (C#'s
   byte, ushort and uint refuse anything else), else -1. */
static long long jint(const jvalue *v, const char *path, double max)
{
    const jvalue *m = jget(v, path);
    return m && m->type == J_NUMBER && m->integer && m->number >= 0 && m->number <= max ? (long long)m->number : -1;
}

/* ---- config.ini, as slafw reads it: "key = value" lines -------------- */

/* The value of key in an ini text, into out; 0 if there is none. */
static int ini_value(const char *ini, const char *key, char *out, size_t size)
{
    size_t n = strlen(key);
    for (const char *p = ini; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL)
        if (!strncmp(p, key, n) && !strncmp(p + n, " = ", 3)) {
            const char *v = p + n + 3, *end = strchr(v, '\n');
            size_t len = end ? (size_t)(end - v) : strlen(v);
            snprintf(out, size, "%.*s", (int)len, v);
            return 1;
        }
    return 0;
}

static double ini_number(const char *ini, const char *key)
{
    char v[96];
    return ini_value(ini, key, v, sizeof v) ? strtod(v, NULL) : NAN;
}

/* An integer as TOML reads one (slafw drops a number that is not). */
static long ini_int(const char *ini, const char *key)
{
    char v[96], *end;
    long n;
    if (!ini_value(ini, key, v, sizeof v)) return -1;
    n = strtol(v, &end, 10);
    return *end || end == v ? -1 : n;
}

/* ---- jobs made here -------------------------------------------------- */

/* A preview anyone can recompute: colour from the place. */
static int test_preview(void *ctx, int w, int h, unsigned char *rgb)
{
    (void)ctx;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            unsigned char *p = rgb + ((size_t)y * (size_t)w + (size_t)x) * 3;
            p[0] = (unsigned char)(x * 255 / w);
            p[1] = (unsigned char)(y * 255 / h);
            p[2] = (unsigned char)((x ^ y) & 255);
        }
    return 0;
}

typedef struct made_job {
    job_desc d;
    job_layer layers[64];
    unsigned char *grey[64];     /* each layer's image as 8-bit grey, as a reader should see it */
    unsigned char *image[64];    /* as handed to `layer` */
    size_t stride;
} made_job;

/* count layers of the given thicknesses from z = 0, bits 1 or 8; images of
   the test scene growing with k, so that neighbours differ. */
static void make_job(made_job *j, const double *thickness, size_t count, int bits, const printer *preset)
{
    const int w = 237, h = 150; /* not whole bytes of 1-bit pixels */
    double z = 0;
    memset(j, 0, sizeof *j);
    j->d.preset = preset;
    j->d.model = "models/test part.stl";
    j->d.width = w;
    j->d.height = h;
    j->d.pitch[0] = j->d.pitch[1] = 0.05;
    j->d.display_mm[0] = w * 0.05;
    j->d.display_mm[1] = h * 0.05;
    j->d.z_max_mm = 150;
    j->d.bits = bits;
    j->d.supersample = bits == 8 ? 4 : 1;
    j->d.mirror_x = 1;
    j->d.layer_count = count;
    j->d.layers = j->layers;
    j->d.bottom_layers = 2;
    j->d.bottom_exposure_s = 20;
    j->d.exposure_s = 2.125;
    j->d.layer_height_mm = 0.05;
    j->d.motion = (job_motion){5, 2, 4, 0.5, 6, 1.5};
    j->d.print_time_s = 1234.5;
    j->d.preview = test_preview;
    j->stride = bits == 8 ? (size_t)w + 3 : ((size_t)w + 7) / 8 + 2; /* padding the formats must skip */
    for (size_t k = 0; k < count; k++) {
        job_layer *l = &j->layers[k];
        unsigned char *g = (unsigned char *)calloc((size_t)w * h, 1);
        l->z_bottom = z;
        l->thickness = thickness[k];
        l->z_top = z += thickness[k];
        l->exposure_s = k < 2 ? 20 : 1.5 + 10 * thickness[k] + 0.0004 * (double)k;
        l->lit_mm2 = 1 + (double)k;
        j->d.volume_mm3 += l->lit_mm2 * l->thickness;
        j->image[k] = (unsigned char *)malloc(j->stride * (size_t)h);
        j->grey[k] = g;
        if (!g || !j->image[k]) continue;
        memset(j->image[k], 0xA5, j->stride * (size_t)h);
        mask_scene(g, w, h, (int)k * 9);
        if (bits == 1) {
            mask_pack(g, w, h, j->image[k], j->stride);
            for (size_t i = 0; i < (size_t)w * h; i++) g[i] = g[i] >= 128 ? 255 : 0;
        } else {
            for (int y = 0; y < h; y++) memcpy(j->image[k] + (size_t)y * j->stride, g + (size_t)y * w, (size_t)w);
        }
    }
}

static void free_job(made_job *j)
{
    for (size_t k = 0; k < j->d.layer_count; k++) {
        free(j->grey[k]);
        free(j->image[k]);
    }
}

/* open, every layer, close(ok); the formats' return codes folded */
static int write_job(const job_format *f, const char *path, made_job *j)
{
    job_writer w;
    int rc = job_open(&w, f, path, &j->d);
    for (size_t k = 0; rc == 0 && k < j->d.layer_count; k++) rc = job_write_layer(&w, k, j->image[k], j->stride);
    if (w.state) {
        int closed = job_close(&w, rc == 0);
        if (!rc) rc = closed;
    }
    return rc;
}

/* The preview member is w x h RGB, test_preview's picture. */
static void check_preview(const char *archive, const char *name, int w, int h)
{
    size_t size;
    unsigned char *png = member(archive, name, &size), *got = NULL, *want = (unsigned char *)malloc((size_t)w * h * 3);
    int pw = 0, ph = 0, depth = 0, colour = -1;
    CHECKF(png && png_header(png, size, &pw, &ph, &depth, &colour) && pw == w && ph == h && depth == 8 && colour == 2,
           "%s: not an RGB %dx%d PNG (%dx%d, depth %d, colour type %d)", name, w, h, pw, ph, depth, colour);
    if (png && want && pw == w && ph == h) decode_pngs(&png, &size, 1, w, h, 3, &got);
    if (want) test_preview(NULL, w, h, want);
    CHECKF(got && want && !memcmp(got, want, (size_t)w * h * 3), "%s: the pixels differ from the preview", name);
    free(png);
    free(got);
    free(want);
}

/* ChiTuBox's header keys in its order (its run.gcode of test/_20x20x20,
   see the notes on the format). */
static const char *const CHITU_KEYS[] = {
    "fileName", "machineType", "estimatedPrintTime", "volume", "resin", "weight", "price", "layerHeight",
    "resolutionX", "resolutionY", "machineX", "machineY", "machineZ", "projectType", "transitionLayerCount",
    "transitionLayerType", "normalExposureTime", "bottomLayExposureTime", "bottomLayerExposureTime",
    "normalDropSpeed", "normalLayerLiftHeight", "zSlowUpDistance", "normalLayerLiftSpeed", "bottomLayCount",
    "bottomLayerCount", "shrinkageX", "shrinkageY", "shrinkageZ", "mirror", "totalLayer", "bottomLayerLiftHeight",
    "bottomLayerLiftSpeed", "bottomLightOffTime", "lightOffTime"};

/* run.gcode against what the job says: header, and per layer the image,
   Z, exposure, wait and the peel before it. z_top[k], exposure_s[k]. */
static void check_gcode(const char *archive, const job_desc *d, const double *z_top, const double *exposure_s)
{
    size_t size, k;
    char *text = (char *)member(archive, "run.gcode", &size);
    const job_motion *m = &d->motion;
    gcode g;
    CHECKF(text && parse_gcode(text, &g), "run.gcode: %s", text ? g.error : "missing");
    if (!text) return;
    CHECKF(g.keys == (int)(sizeof CHITU_KEYS / sizeof CHITU_KEYS[0]), "%d header keys", g.keys);
    for (int i = 0; i < g.keys && i < (int)(sizeof CHITU_KEYS / sizeof CHITU_KEYS[0]); i++)
        CHECKF(!strcmp(g.key[i], CHITU_KEYS[i]), "header key %d is %s, ChiTuBox's is %s", i + 1, g.key[i],
               CHITU_KEYS[i]);
    CHECK(g.absolute && g.homed_first);
    CHECK(gc_number(&g, "totalLayer") == (double)d->layer_count && gc_number(&g, "resolutionX") == d->width &&
          gc_number(&g, "resolutionY") == d->height);
    CHECK(fabs(gc_number(&g, "machineX") - d->display_mm[0]) < 1e-6 &&
          fabs(gc_number(&g, "machineY") - d->display_mm[1]) < 1e-6);
    CHECK(gc_number(&g, "bottomLayerCount") == d->bottom_layers &&
          fabs(gc_number(&g, "bottomLayerExposureTime") - d->bottom_exposure_s) < 1e-3 &&
          fabs(gc_number(&g, "normalExposureTime") - d->exposure_s) < 1e-3);
    CHECK(fabs(gc_number(&g, "normalLayerLiftHeight") - m->lift_mm) < 1e-6 &&
          fabs(gc_number(&g, "normalLayerLiftSpeed") - m->lift_speed * 60) < 1e-3 &&
          fabs(gc_number(&g, "normalDropSpeed") - m->retract_speed * 60) < 1e-3 &&
          fabs(gc_number(&g, "bottomLayerLiftHeight") - m->bottom_lift_mm) < 1e-6);
    CHECK(fabs(gc_number(&g, "volume") - d->volume_mm3 / 1000) < 1e-3);
    CHECK(!strcmp(gc_value(&g, "mirror") ? gc_value(&g, "mirror") : "", d->mirror_x || d->mirror_y ? "1" : "0"));
    CHECKF(g.count == d->layer_count, "%zu exposures for %zu layers", g.count, d->layer_count);
    for (k = 0; k < g.count && k < d->layer_count && !check_case_failed(); k++) {
        const gc_layer *l = &g.layers[k];
        int bottom = k < d->bottom_layers;
        double lift = bottom ? m->bottom_lift_mm : m->lift_mm, speed = bottom ? m->bottom_lift_speed : m->lift_speed;
        CHECKF(fabs(l->z - z_top[k]) < 1e-6, "layer %zu exposed at Z %.9g, not %.9g", k + 1, l->z, z_top[k]);
        CHECKF(l->exposure_ms == floor(exposure_s[k] * 1000 + 0.5), "layer %zu: exposed %g ms, not %g s", k + 1,
               l->exposure_ms, exposure_s[k]);
        CHECKF(l->image == (int)k + 1, "layer %zu shows %d.png", k + 1, l->image);
        CHECKF(fabs(l->wait_ms - floor(m->wait_before_cure_s * 1000 + 0.5)) < 0.5, "layer %zu waits %g ms", k + 1,
               l->wait_ms);
        CHECKF(fabs(l->peak - (z_top[k] + lift)) < 1e-6 && fabs(l->lift_f - speed * 60) < 1e-3 &&
                   fabs(l->drop_f - m->retract_speed * 60) < 1e-3,
               "layer %zu: peeled to %g at F%g, back at F%g", k + 1, l->peak, l->lift_f, l->drop_f);
        if (k) CHECKF(l->z > g.layers[k - 1].z, "layer %zu is not above layer %zu", k + 1, k);
    }
    CHECK(g.end_z >= z_top[d->layer_count - 1]);
    free(g.layers);
    free(text);
}

static void chitu_zip_holds_every_layer_as_given(void)
{
    /* adaptive, with heights that do not add up exactly in binary */
    static const double t[] = {0.05, 0.05, 0.1, 0.03, 0.07, 0.012, 0.15, 0.1, 0.01, 0.02, 0.064, 0.066};
    const size_t n = sizeof t / sizeof t[0];
    static made_job j;
    char path[512], *names;
    double z[16], e[16];
    char images[16][96];
    snprintf(path, sizeof path, "%s", in_dir("part.zip"));
    for (int bits = 1; bits <= 8; bits += 7) {
        make_job(&j, t, n, bits, printer_find("wanhao-d8"));
        CHECK(write_job(&JOB_FORMAT_CHITU_ZIP, path, &j) == 0);
        names = member_names(path);
        CHECKF(names && line_count(names) == n + 3 && has_line(names, "run.gcode") && has_line(names, "preview.png") &&
                   has_line(names, "preview_cropping.png"), "members: %s", names ? names : "none");
        for (size_t k = 0; k < n; k++) {
            snprintf(images[k], sizeof images[k], "%zu.png", k + 1);
            CHECKF(names && has_line(names, images[k]), "no %s", images[k]);
            z[k] = j.layers[k].z_top;
            e[k] = j.layers[k].exposure_s;
        }
        check_grey_members(path, images, n, j.d.width, j.d.height, j.grey);
        check_gcode(path, &j.d, z, e);
        check_preview(path, "preview.png", 954, 850);
        check_preview(path, "preview_cropping.png", 168, 150);
        free(names);
        free_job(&j);
        remove(path);
    }
}

/* config.ini against the job, as slafw would print it. */
static void check_config(const char *archive, const job_desc *d, const char *job_dir, const double *z_top,
                         double exposure_s, const char *model)
{
    size_t size, n = d->layer_count;
    char *ini = (char *)member(archive, "config.ini", &size), *ps = (char *)member(archive, "prusaslicer.ini", &size);
    char v[96];
    double first, height;
    long fast, slow;
    CHECK(ini && ps);
    if (!ini || !ps) { free(ini); free(ps); return; }
    CHECKF(ini_value(ini, "jobDir", v, sizeof v) && !strcmp(v, job_dir), "jobDir = %s", v);
    CHECKF(ini_value(ini, "printerModel", v, sizeof v) && !strcmp(v, model), "printerModel = %s", v);
    CHECK(ini_value(ini, "printerVariant", v, sizeof v) && !strcmp(v, "default"));
    CHECK(fabs(ini_number(ini, "expTime") - exposure_s) < 1e-6);
    CHECK(fabs(ini_number(ini, "expTimeFirst") - d->bottom_exposure_s) < 1e-6);
    fast = ini_int(ini, "numFast");
    slow = ini_int(ini, "numSlow");
    CHECKF(fast >= 0 && slow >= 0 && (size_t)(fast + slow) == n, "numFast %ld + numSlow %ld, %zu layers", fast, slow,
           n);
    CHECK(ini_int(ini, "numFade") >= 2 && ini_int(ini, "numFade") <= 200);
    first = ini_number(ini, "layerHeightFirst");
    height = ini_number(ini, "layerHeight");
    CHECK(height > 0.0099); /* below that slafw takes the legacy stepnum instead */
    /* slafw: layer 0 is layerHeightFirst thick, every other layerHeight; the
       top layer may be planned thinner, and prints at full height */
    for (size_t k = 0; k < n; k++) {
        double top = first + (double)k * height;
        CHECKF(k + 1 < n ? fabs(top - z_top[k]) < 1e-6 : top >= z_top[k] - 1e-6 && top < z_top[k] + height,
               "layer %zu: slafw puts its top at %.9g, the job at %.9g", k + 1, top, z_top[k]);
    }
    CHECK(ini_value(ps, "printer_technology", v, sizeof v) && !strcmp(v, "SLA"));
    CHECK(ini_value(ps, "display_orientation", v, sizeof v) && (!strcmp(v, "portrait") || !strcmp(v, "landscape")));
    /* portrait: the images are display_pixels_y wide */
    if (!strcmp(v, "portrait"))
        CHECK(ini_int(ps, "display_pixels_x") == d->height && ini_int(ps, "display_pixels_y") == d->width &&
              fabs(ini_number(ps, "display_width") - d->display_mm[1]) < 1e-6);
    else
        CHECK(ini_int(ps, "display_pixels_x") == d->width && ini_int(ps, "display_pixels_y") == d->height &&
              fabs(ini_number(ps, "display_width") - d->display_mm[0]) < 1e-6);
    CHECK(ini_int(ps, "display_mirror_x") >= 0 && ini_int(ps, "display_mirror_y") >= 0 &&
          ini_number(ps, "display_height") > 0);
    free(ini);
    free(ps);
}

/* The layer images are named jobDir00000.png on, and no other PNG starts
   with jobDir (slafw would print it). */
static void check_sl1_names(const char *names, const char *job_dir, size_t n)
{
    size_t pngs = 0, len = strlen(job_dir);
    for (const char *p = names; p && *p; p = strchr(p, '\n') + 1) {
        const char *end = strchr(p, '\n');
        if (!end) break;
        if (!strncmp(p, job_dir, len) && end - p >= 4 && !strncmp(end - 4, ".png", 4)) pngs++;
    }
    CHECKF(pngs == n, "%zu PNGs start with %s, for %zu layers", pngs, job_dir, n);
    for (size_t k = 0; k < n; k++) {
        char name[96];
        snprintf(name, sizeof name, "%s%05zu.png", job_dir, k);
        CHECKF(has_line(names, name), "no %s", name);
    }
}

static void sl1_holds_every_layer_as_given(void)
{
    static const double t[] = {0.1, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.03};
    const size_t n = sizeof t / sizeof t[0];
    static made_job j;
    char path[512], *names, images[16][96];
    double z[16];
    snprintf(path, sizeof path, "%s", in_dir("my part.sl1"));
    for (int bits = 1; bits <= 8; bits += 7) {
        make_job(&j, t, n, bits, printer_find("prusa-sl1s"));
        /* the desc's one exposure, as slice makes it: the regular layers' (layer 3's), not the thin top's */
        j.d.exposure_s = j.layers[2].exposure_s;
        CHECK(write_job(&JOB_FORMAT_SL1, path, &j) == 0);
        names = member_names(path);
        CHECKF(names && line_count(names) == n + 4 && has_line(names, "config.ini") &&
                   has_line(names, "prusaslicer.ini") && has_line(names, "thumbnail/thumbnail400x400.png") &&
                   has_line(names, "thumbnail/thumbnail800x480.png"), "members: %s", names ? names : "none");
        check_sl1_names(names, "my_part", n);
        for (size_t k = 0; k < n; k++) {
            snprintf(images[k], sizeof images[k], "my_part%05zu.png", k);
            z[k] = j.layers[k].z_top;
        }
        check_grey_members(path, images, n, j.d.width, j.d.height, j.grey);
        /* the regular layers' exposure: layer 3's, 0.05 mm past the bottom ones */
        check_config(path, &j.d, "my_part", z, j.layers[2].exposure_s, "SL1S");
        check_preview(path, "thumbnail/thumbnail400x400.png", 400, 400);
        check_preview(path, "thumbnail/thumbnail800x480.png", 800, 480);
        free(names);
        free_job(&j);
        remove(path);
    }
}

/* ---- UVJ: config.json as UVtools reads it ------------------------------ */

/* The lifts of one UVtools Exposure object (the defaults' or a layer's)
   against the job's motion: a one-stage peel that comes all the way back,
   the rest before the light, full power. */
static int uvj_moves_are(const jvalue *e, const job_motion *m, int bottom)
{
    double lift = bottom ? m->bottom_lift_mm : m->lift_mm, speed = 60 * (bottom ? m->bottom_lift_speed : m->lift_speed);
    return fabs(jnum(e, "LiftHeight") - lift) < 1e-9 && fabs(jnum(e, "LiftSpeed") - speed) < 1e-9 &&
           jnum(e, "LiftHeight2") == 0 && jnum(e, "RetractHeight2") == 0 &&
           fabs(jnum(e, "RetractHeight") - lift) < 1e-9 && fabs(jnum(e, "RetractSpeed") - 60 * m->retract_speed) < 1e-9 &&
           fabs(jnum(e, "WaitTimeBeforeCure") - m->wait_before_cure_s) < 1e-9 && jnum(e, "LightOffTime") == 0 &&
           jnum(e, "WaitTimeAfterCure") == 0 && jnum(e, "WaitTimeAfterLift") == 0 && jint(e, "LightPWM", 255) == 255;
}

/* config.json against the job: UVJFile.cs's Settings class (sn4k3/UVtools
   7b510f0d), its keys as the C# properties are named, matched
   case-sensitively, and integers where C# has byte, ushort and uint; every
   layer's Z and exposure, z_top[k] and exposure_s[k], and the moves of its
   kind. aa: the AntiAliasLevel. */
static void check_uvj_config(const char *archive, const job_desc *d, const double *z_top, const double *exposure_s,
                             int aa)
{
    size_t size, n = d->layer_count, k, bad = 0;
    char *text = (char *)member(archive, "config.json", &size), error[160] = "missing";
    const jvalue *layers;
    jvalue c;
    if (!text || !jparse(text, &c, error, sizeof error)) {
        CHECKF(0, "config.json: %s", error);
        free(text);
        return;
    }
    CHECKF(jint(&c, "Properties.Size.X", 65535) == d->width && jint(&c, "Properties.Size.Y", 65535) == d->height &&
               jint(&c, "Properties.Size.Layers", 4294967295.0) == (long long)n,
           "Size: %g x %g pixels, %g layers", jnum(&c, "Properties.Size.X"), jnum(&c, "Properties.Size.Y"),
           jnum(&c, "Properties.Size.Layers"));
    CHECK(fabs(jnum(&c, "Properties.Size.Millimeter.X") - d->display_mm[0]) < 1e-9 &&
          fabs(jnum(&c, "Properties.Size.Millimeter.Y") - d->display_mm[1]) < 1e-9);
    CHECK(jnum(&c, "Properties.Size.LayerHeight") >= 0.01);
    CHECKF(jint(&c, "Properties.AntiAliasLevel", 255) == aa, "AntiAliasLevel %g, not %d",
           jnum(&c, "Properties.AntiAliasLevel"), aa);
    CHECK(jint(&c, "Properties.Bottom.Count", 65535) == (long long)d->bottom_layers &&
          fabs(jnum(&c, "Properties.Bottom.LightOnTime") - d->bottom_exposure_s) < 1e-9);
    CHECK(jnum(&c, "Properties.Exposure.LightOnTime") > 0);
    CHECK(uvj_moves_are(jget(&c, "Properties.Exposure"), &d->motion, 0) &&
          uvj_moves_are(jget(&c, "Properties.Bottom"), &d->motion, 1));
    layers = jget(&c, "Layers");
    CHECKF(layers && layers->type == J_ARRAY && layers->count == n, "Layers: %zu entries for %zu layers",
           layers ? layers->count : 0, n);
    for (k = 0; layers && k < n && k < layers->count; k++) {
        const jvalue *l = &layers->items[k], *e = jget(l, "Exposure");
        double z = jnum(l, "Z"), t = jnum(e, "LightOnTime");
        if (!(fabs(z - z_top[k]) <= 1e-9 && fabs(t - exposure_s[k]) <= 1e-9 * exposure_s[k] &&
              uvj_moves_are(e, &d->motion, k < d->bottom_layers)) && bad++ < 3) /* NAN: a key missing */
            CHECKF(0, "Layers[%zu]: Z %.9g, exposure %.9g s; the job: %.9g, %.9g s, or its moves differ", k, z, t,
                   z_top[k], exposure_s[k]);
    }
    jfree(&c);
    free(text);
}

/* The members: config.json, the two previews and slice/00000000.png on, one
   a layer and nothing else; names[k] gets layer k's. */
static void check_uvj_members(const char *archive, size_t n, char (*names)[96])
{
    char *list = member_names(archive);
    CHECKF(list && line_count(list) == n + 3 && has_line(list, "config.json") && has_line(list, "preview/tiny.png") &&
               has_line(list, "preview/huge.png"), "members: %.300s", list ? list : "none");
    for (size_t k = 0; k < n; k++) {
        snprintf(names[k], sizeof names[k], "slice/%08zu.png", k);
        CHECKF(list && has_line(list, names[k]), "no %s", names[k]);
    }
    free(list);
}

/* An adaptive job of 1-bit and of 8-bit images: every layer's Z, exposure
   and image, the previews as drawn. */
static void uvj_holds_every_layer_as_given(void)
{
    static const double t[] = {0.05, 0.05, 0.1, 0.03, 0.07, 0.012, 0.15, 0.1, 0.01, 0.02, 0.064, 0.066};
    const size_t n = sizeof t / sizeof t[0];
    static made_job j;
    char path[512], images[16][96];
    double z[16], e[16];
    snprintf(path, sizeof path, "%s", in_dir("part.uvj"));
    for (int bits = 1; bits <= 8; bits += 7) {
        make_job(&j, t, n, bits, NULL);
        CHECK(write_job(&JOB_FORMAT_UVJ, path, &j) == 0);
        check_uvj_members(path, n, images);
        for (size_t k = 0; k < n; k++) {
            z[k] = j.layers[k].z_top;
            e[k] = j.layers[k].exposure_s;
        }
        check_uvj_config(path, &j.d, z, e, bits == 8 ? j.d.supersample : 1);
        check_grey_members(path, images, n, j.d.width, j.d.height, j.grey);
        check_preview(path, "preview/tiny.png", 400, 400);
        check_preview(path, "preview/huge.png", 800, 480);
        free_job(&j);
        remove(path);
    }
}

/* ---- refusals, without a program -------------------------------------- */

/* stderr into a file while fn runs */
static char *stderr_of(int (*fn)(void *), void *ctx, int *rc)
{
    int saved = dup(2);
    FILE *f = fopen(in_dir("stderr"), "w");
    size_t n;
    char *text;
    fflush(stderr);
    if (f) {
        dup2(fileno(f), 2);
        fclose(f);
    }
    *rc = fn(ctx);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    text = (char *)read_whole_file(in_dir("stderr"), &n);
    remove(in_dir("stderr"));
    return text;
}

typedef struct attempt { const job_format *f; const char *path; made_job *j; int layers_then_fail; } attempt;

static int try_job(void *ctx)
{
    attempt *a = (attempt *)ctx;
    job_writer w;
    int rc;
    if (!a->layers_then_fail) return write_job(a->f, a->path, a->j);
    rc = job_open(&w, a->f, a->path, &a->j->d);
    for (size_t k = 0; rc == 0 && k < 3; k++) rc = job_write_layer(&w, k, a->j->image[k], a->j->stride);
    job_close(&w, 0); /* as after a failed render */
    return rc;
}

/* The directory holds nothing but the one file named, if any. */
static int dir_holds_only(const char *keep)
{
    DIR *d = opendir(cli_dir);
    struct dirent *e;
    int others = 0;
    while (d && (e = readdir(d)) != NULL)
        others += strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && (!keep || strcmp(e->d_name, keep));
    if (d) closedir(d);
    return !others;
}

static void sl1_refuses_more_than_one_layer_height(void)
{
    static const double adaptive[] = {0.05, 0.05, 0.05, 0.1, 0.05, 0.05};
    static made_job j;
    attempt a = {&JOB_FORMAT_SL1, NULL, &j, 0};
    char path[512], *err;
    int rc;
    snprintf(path, sizeof path, "%s", in_dir("adaptive.sl1"));
    a.path = path;
    make_job(&j, adaptive, 6, 1, printer_find("prusa-sl1"));
    err = stderr_of(try_job, &a, &rc);
    CHECK(rc != 0);
    CHECKF(err && cli_one_message(err) && strstr(err, path) && strstr(err, "one layer height") &&
               strstr(err, "--method finest") && strstr(err, "--uniform"), "%s", err ? err : "");
    CHECK(dir_holds_only(NULL));
    free(err);
    free_job(&j);
}

/* A job closed as failed, a job of no layers and a path that cannot be
   written leave nothing, each with one line naming the file. */
static void failed_jobs_leave_nothing(void)
{
    static const double t[] = {0.05, 0.05, 0.05, 0.05};
    static made_job j;
    const job_format *formats[] = {&JOB_FORMAT_CHITU_ZIP, &JOB_FORMAT_SL1, &JOB_FORMAT_UVJ};
    char path[512], name[64], *err;
    int rc;
    for (int i = 0; i < 3; i++) {
        attempt a = {formats[i], path, &j, 1};
        make_job(&j, t, 4, 1, NULL);
        snprintf(name, sizeof name, "failed%s", formats[i]->extension);
        snprintf(path, sizeof path, "%s", in_dir(name));
        err = stderr_of(try_job, &a, &rc);
        CHECKF(rc == 0 && err && !*err, "%s: %s", formats[i]->name, err ? err : "");
        CHECKF(dir_holds_only(NULL), "%s: a failed job left files", formats[i]->name);
        free(err);
        j.d.layer_count = 0;
        a.layers_then_fail = 0;
        err = stderr_of(try_job, &a, &rc);
        CHECKF(rc != 0 && err && cli_one_message(err) && strstr(err, path), "%s, no layers: %s", formats[i]->name,
               err ? err : "");
        CHECK(dir_holds_only(NULL));
        free(err);
        j.d.layer_count = 4;
        snprintf(name, sizeof name, "no/such/dir%s", formats[i]->extension);
        snprintf(path, sizeof path, "%s", in_dir(name));
        err = stderr_of(try_job, &a, &rc);
        CHECKF(rc != 0 && err && cli_one_message(err) && strstr(err, path), "%s, bad path: %s", formats[i]->name,
               err ? err : "");
        free(err);
        /* and a good one, for contrast, is the only file */
        snprintf(name, sizeof name, "good%s", formats[i]->extension);
        snprintf(path, sizeof path, "%s", in_dir(name));
        CHECK(write_job(formats[i], path, &j) == 0 && cli_exists(path) && dir_holds_only(name));
        remove(path);
        free_job(&j);
    }
}

/* ---- jobs adaslice slice writes -------------------------------------- */

typedef struct dir_job {
    size_t count;
    double *z_top, *exposure_s;
    double volume_mm3, peel_mm, peel_speed, return_speed, settle_s;
    uint32_t width, height, bits;
    unsigned char **grey;   /* every layer's mask as 8-bit grey */
    char (*names)[96];      /* room for the member name of each */
} dir_job;

static void free_dir_job(dir_job *j)
{
    for (size_t k = 0; j->grey && k < j->count; k++) free(j->grey[k]);
    free(j->grey);
    free(j->names);
    free(j->z_top);
    free(j->exposure_s);
    memset(j, 0, sizeof *j);
}

static uint32_t le32(const unsigned char *p)
{
    return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

typedef struct row_sink { const dir_job *j; unsigned char *grey; } row_sink;

static void take_row(void *ctx, uint32_t y, const unsigned char *row)
{
    row_sink *s = (row_sink *)ctx;
    unsigned char *out = s->grey + (size_t)y * s->j->width;
    for (uint32_t x = 0; x < s->j->width; x++)
        out[x] = s->j->bits == 8 ? row[x] : (row[x >> 3] >> (7 - (x & 7)) & 1) * 255;
}

/* JOBDIR/manifest.json (each layer's z_top and exposure_s) and JOBDIR/masks.rle
   (jobdir.h: "ADASMSK2", u32 width, height, bits, layers, bin_nm, peel_nm,
   peel_speed_um_s, return_speed_um_s, settle_ms; per layer u32 bins,
   exposure_ms, CRC-32, code bytes, the code), every mask decoded; the
   exposures of both agree. */
static int read_dir_job(const char *dir, dir_job *j)
{
    char path[600];
    size_t n, at = 44;
    char *manifest, *p;
    unsigned char *rle;
    memset(j, 0, sizeof *j);
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    manifest = (char *)read_whole_file(path, &n);
    snprintf(path, sizeof path, "%s/masks.rle", dir);
    rle = read_whole_file(path, &n);
    CHECKF(manifest && rle && n >= 44 && !memcmp(rle, "ADASMSK2", 8), "%s: no manifest, or no masks.rle of ADASMSK2",
           dir);
    if (!manifest || !rle || n < 44 || memcmp(rle, "ADASMSK2", 8)) { free(manifest); free(rle); return 0; }
    j->width = le32(rle + 8);
    j->height = le32(rle + 12);
    j->bits = le32(rle + 16);
    j->count = le32(rle + 20);
    j->z_top = (double *)calloc(j->count + 1, sizeof *j->z_top);
    j->exposure_s = (double *)calloc(j->count + 1, sizeof *j->exposure_s);
    j->grey = (unsigned char **)calloc(j->count + 1, sizeof *j->grey);
    j->names = (char (*)[96])calloc(j->count + 1, sizeof *j->names);
    j->volume_mm3 = cli_json_number(manifest, "volume_mm3");
    j->peel_mm = cli_json_number(manifest, "peel_mm");
    j->peel_speed = cli_json_number(manifest, "peel_speed_mm_s");
    j->return_speed = cli_json_number(manifest, "return_speed_mm_s");
    j->settle_s = cli_json_number(manifest, "settle_s");
    p = strstr(manifest, "\"layers\"");
    for (size_t k = 0; p && j->z_top && j->exposure_s && k < j->count; k++) {
        char *z, *e, *end;
        if (!(p = strchr(p, '{')) || !(end = strchr(p, '}'))) break;
        z = strstr(p, "\"z_top\":");
        e = strstr(p, "\"exposure_s\":");
        CHECKF(z && e && z < end && e < end, "%s: layer %zu lacks z_top or exposure_s", dir, k + 1);
        if (!z || !e || z > end || e > end) break;
        j->z_top[k] = strtod(z + 8, NULL);
        j->exposure_s[k] = strtod(e + 13, NULL);
        p = end;
    }
    for (size_t k = 0; j->grey && k < j->count; k++) {
        adaslice_rle_decoder dec;
        unsigned char *row = (unsigned char *)malloc(j->width);
        row_sink sink = {j, (unsigned char *)calloc((size_t)j->width * j->height, 1)};
        uint32_t crc, size;
        j->grey[k] = sink.grey;
        if (at + 16 > n || !row || !sink.grey) {
            free(row);
            CHECKF(0, "%s: masks.rle ends at layer %zu", dir, k + 1);
            break;
        }
        CHECKF(le32(rle + at + 4) == (uint32_t)floor(j->exposure_s[k] * 1000 + 0.5), "layer %zu: %u ms in masks.rle, "
               "%g s in the manifest", k + 1, le32(rle + at + 4), j->exposure_s[k]);
        crc = le32(rle + at + 8);
        size = le32(rle + at + 12);
        at += 16;
        CHECKF(at + size <= n &&
                   adaslice_rle_decoder_init(&dec, j->width, j->height, (int)j->bits, row, j->width) == 0 &&
                   adaslice_rle_decode(&dec, rle + at, size, take_row, &sink) == 0 && adaslice_rle_finished(&dec) &&
                   ADASLICE_RLE_CRC(&dec) == crc, "%s: masks.rle: layer %zu does not decode", dir, k + 1);
        at += size;
        free(row);
    }
    free(manifest);
    free(rle);
    return 1;
}

/* adaslice slice MODEL ARGS... -o OUT: the hand, 1.9 mm tall; args
   NULL-terminated, at most 14 */
static int slice(const char *out, const char *const *args)
{
    const char *v[20] = {"slice", "examples/models/hand_closed.obj", "--scale", "7"};
    cli_result r;
    int n = 4, st;
    while (*args && n < 18) v[n++] = *args++;
    v[n++] = "-o";
    v[n] = out;
    r = cli_run(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11], v[12], v[13], v[14],
                v[15], v[16], v[17], v[18], v[19], (const char *)NULL);
    st = r.status;
    CHECKF(st == 0, "adaslice slice ... -o %s: %s", out, r.err);
    cli_free(&r);
    return st == 0;
}

/* A job directory and its files (it has no folders). */
static void remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            char path[800];
            snprintf(path, sizeof path, "%.500s/%.255s", dir, e->d_name);
            remove(path);
        }
    if (d) closedir(d);
    rmdir(dir);
}

/* The job a slice writes, described as check_gcode and check_config see it:
   the display and what the manifest says. */
static void desc_of(const dir_job *j, double display_w, double display_h, int mirror_x, unsigned bottom, job_desc *d)
{
    memset(d, 0, sizeof *d);
    d->width = (int)j->width;
    d->height = (int)j->height;
    d->display_mm[0] = display_w;
    d->display_mm[1] = display_h;
    d->mirror_x = mirror_x;
    d->layer_count = j->count;
    d->bottom_layers = bottom;
    d->bottom_exposure_s = j->exposure_s[0];
    d->volume_mm3 = j->volume_mm3;
    d->motion = (job_motion){j->peel_mm, j->peel_speed, j->return_speed, j->settle_s, j->peel_mm, j->peel_speed};
}

/* The hand for the Wanhao D8 (adaptive layers, 1-bit), and anti-aliased with
   other motion on a small display of no preset: every layer's Z, exposure
   and peel in run.gcode as in the manifest, every image as in masks.rle. */
static void sliced_chitu_zip_matches_the_job_directory(void)
{
    static const char *const runs[2][11] = {
        {"--printer", "wanhao-d8", NULL},
        {"--pixels", "640x400", "--pitch", "0.1", "--aa", "2", "--bottom-layers", "5", "--peel", "3", NULL}};
    static const struct { int w, h; double mm[2]; int mirror; unsigned bottom; } display[2] = {
        {2560, 1600, {192, 120}, 1, 3}, {640, 400, {64, 40}, 0, 5}};
    for (int r = 0; r < 2; r++) {
        const char *dir_args[13] = {"--format", "dir"};
        char zip[512], dir[512], *text;
        size_t size;
        dir_job j = {0};
        job_desc d;
        gcode g;
        for (int i = 0; i < 10 && runs[r][i]; i++) dir_args[2 + i] = runs[r][i];
        snprintf(zip, sizeof zip, "%s", in_dir("hand.zip"));
        snprintf(dir, sizeof dir, "%s", in_dir("hand_dir"));
        if (!slice(zip, runs[r]) || !slice(dir, dir_args) || !read_dir_job(dir, &j)) {
            free_dir_job(&j);
            remove(zip);
            remove_dir(dir);
            return;
        }
        CHECK(j.count > 20 && j.width == (uint32_t)display[r].w && j.height == (uint32_t)display[r].h &&
              j.bits == (r ? 8u : 1u));
        for (size_t k = 0; j.names && k < j.count; k++) snprintf(j.names[k], sizeof j.names[k], "%zu.png", k + 1);
        desc_of(&j, display[r].mm[0], display[r].mm[1], display[r].mirror, display[r].bottom, &d);
        /* the header's one exposure is the file's own business (the thinnest layer's) */
        text = (char *)member(zip, "run.gcode", &size);
        CHECK(text && parse_gcode(text, &g));
        d.exposure_s = text ? gc_number(&g, "normalExposureTime") : 0;
        if (text) free(g.layers);
        free(text);
        check_gcode(zip, &d, j.z_top, j.exposure_s);
        check_grey_members(zip, j.names, j.count, (int)j.width, (int)j.height, j.grey);
        free_dir_job(&j);
        remove(zip);
        remove_dir(dir);
    }
}

/* The hand for the SL1S in uniform layers: config.ini's heights and
   exposures as the manifest's, every image as in masks.rle. */
static void sliced_sl1_matches_the_job_directory(void)
{
    static const char *const args[] = {"--printer", "prusa-sl1s", "--uniform", "0.05", NULL};
    static const char *const dir_args[] = {"--printer", "prusa-sl1s", "--uniform", "0.05", "--format", "dir", NULL};
    char sl1[512], dir[512], *names;
    dir_job j = {0};
    job_desc d;
    snprintf(sl1, sizeof sl1, "%s", in_dir("hand.sl1"));
    snprintf(dir, sizeof dir, "%s", in_dir("hand_dir"));
    if (!slice(sl1, args) || !slice(dir, dir_args) || !read_dir_job(dir, &j)) {
        free_dir_job(&j);
        remove(sl1);
        remove_dir(dir);
        return;
    }
    CHECK(j.count > 20 && j.width == 1620 && j.height == 2560 && j.bits == 1);
    desc_of(&j, 81, 128, 0, 3, &d);
    check_config(sl1, &d, "hand", j.z_top, j.exposure_s[j.count / 2], "SL1S");
    names = member_names(sl1);
    check_sl1_names(names, "hand", j.count);
    for (size_t k = 0; j.names && k < j.count; k++) snprintf(j.names[k], sizeof j.names[k], "hand%05zu.png", k);
    check_grey_members(sl1, j.names, j.count, (int)j.width, (int)j.height, j.grey);
    free(names);
    free_dir_job(&j);
    remove(sl1);
    remove_dir(dir);
}

/* The hand for the Elegoo Mars 2 Pro, whose own format is CTB (adaptive
   layers, 1-bit), and anti-aliased on a small display of no preset, named
   by --format alone: config.json's Z, exposure and moves of every layer as
   in the manifest, every image as in masks.rle, the previews of UVtools'
   sizes. */
static void sliced_uvj_matches_the_job_directory(void)
{
    static const char *const runs[2][11] = {
        {"--printer", "elegoo-mars-2-pro", NULL},
        {"--pixels", "640x400", "--pitch", "0.1", "--aa", "2", "--bottom-layers", "5", "--peel", "3", NULL}};
    static const struct { int w, h; double mm[2]; unsigned bottom; int aa; } display[2] = {
        {1620, 2560, {82.62, 130.56}, 3, 1}, {640, 400, {64, 40}, 5, 2}};
    for (int r = 0; r < 2; r++) {
        const char *dir_args[13] = {"--format", "dir"}, *uvj_args[13] = {"--format", "uvj"};
        char out[512], uvj[512], dir[512];
        dir_job j = {0};
        job_desc d;
        for (int i = 0; i < 10 && runs[r][i]; i++) dir_args[2 + i] = uvj_args[2 + i] = runs[r][i];
        /* the first by its extension, the second by --format, which adds it */
        snprintf(out, sizeof out, "%s", in_dir(r ? "hand" : "hand.uvj"));
        snprintf(uvj, sizeof uvj, "%s", in_dir("hand.uvj"));
        snprintf(dir, sizeof dir, "%s", in_dir("hand_dir"));
        if (!slice(out, r ? uvj_args : runs[r]) || !slice(dir, dir_args) || !read_dir_job(dir, &j)) {
            free_dir_job(&j);
            remove(uvj);
            remove_dir(dir);
            return;
        }
        CHECK(j.count > 20 && j.width == (uint32_t)display[r].w && j.height == (uint32_t)display[r].h &&
              j.bits == (r ? 8u : 1u));
        desc_of(&j, display[r].mm[0], display[r].mm[1], 0, display[r].bottom, &d);
        check_uvj_members(uvj, j.count, j.names);
        check_uvj_config(uvj, &d, j.z_top, j.exposure_s, display[r].aa);
        check_grey_members(uvj, j.names, j.count, (int)j.width, (int)j.height, j.grey);
        for (int p = 0; p < 2; p++) {
            size_t size;
            unsigned char *png = member(uvj, p ? "preview/huge.png" : "preview/tiny.png", &size);
            int w = 0, h = 0, depth = 0, colour = -1;
            CHECKF(png && png_header(png, size, &w, &h, &depth, &colour) && w == (p ? 800 : 400) &&
                       h == (p ? 480 : 400) && depth == 8 && colour == 2,
                   "preview %d: %dx%d, depth %d, colour type %d", p, w, h, depth, colour);
            free(png);
        }
        free_dir_job(&j);
        remove(uvj);
        remove_dir(dir);
    }
}

void test_formats_zip(void)
{
    if (!cli_begin("adaslice-formats-zip")) return;
    RUN(sl1_refuses_more_than_one_layer_height);
    RUN(failed_jobs_leave_nothing);
    RUN_NEEDING("unzip oiiotool", chitu_zip_holds_every_layer_as_given);
    RUN_NEEDING("unzip oiiotool", sl1_holds_every_layer_as_given);
    RUN_NEEDING("unzip oiiotool", sliced_chitu_zip_matches_the_job_directory);
    RUN_NEEDING("unzip oiiotool", sliced_sl1_matches_the_job_directory);
    RUN_NEEDING("unzip oiiotool", uvj_holds_every_layer_as_given);
    RUN_NEEDING("unzip oiiotool", sliced_uvj_matches_the_job_directory);
    cli_end();
}
