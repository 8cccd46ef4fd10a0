/* The one JSON writer of the tool (cgltf_write's shape): the writer keeps
   the commas and the indentation, the caller names members and values.

       json_writer w;
       json_init(&w, f);
       json_begin_object(&w, NULL, 0);
       json_string(&w, "format", "adaslice-job");
       json_begin_array(&w, "layers", 0);
       json_begin_object(&w, NULL, 1);      one line per layer
       json_number(&w, "z_top", 0.05);
       json_end(&w);
       json_end(&w);
       json_end(&w);                         closes the document with '\n'

   A key is given inside an object and is NULL inside an array (or for the
   document). A container begun with oneline set writes everything in it on
   one line. Numbers are written in the fewest digits that read back to the
   same double; a non-finite one is null. Write errors are the FILE's
   (ferror). */
#ifndef ADASLICE_HOST_JSON_H
#define ADASLICE_HOST_JSON_H
#include <stddef.h>
#include <stdio.h>

#define JSON_MAX_DEPTH 16
#define JSON_MEMO 16
typedef struct json_writer {
    FILE *f;
    int failed;                              /* a write to f failed (glibc's memory streams say so only there) */
    int depth;
    unsigned char members[JSON_MAX_DEPTH];   /* written so far at each depth (0, 1: more) */
    unsigned char oneline[JSON_MAX_DEPTH];
    char close[JSON_MAX_DEPTH];              /* '}' or ']' */
    /* numbers written lately, by their bits: finding the fewest digits
       takes up to three printfs and two strtods, and a job's manifest
       repeats most of its numbers (a layer's bottom is the top below it,
       its thickness and exposure one of a few) */
    struct { unsigned char bits[sizeof(double)]; char text[32]; } memo[JSON_MEMO];
} json_writer;

void json_init(json_writer *w, FILE *f);
void json_begin_object(json_writer *w, const char *key, int oneline);
void json_begin_array(json_writer *w, const char *key, int oneline);
void json_end(json_writer *w);
void json_string(json_writer *w, const char *key, const char *v);   /* v NULL: null */
void json_number(json_writer *w, const char *key, double v);
/* n numbers as an array on one line: a point, a matrix, a pitch. */
void json_numbers(json_writer *w, const char *key, const double *v, size_t n);
void json_int(json_writer *w, const char *key, long long v);
void json_bool(json_writer *w, const char *key, int v);
void json_null(json_writer *w, const char *key);
/* n bytes of JSON made elsewhere (by another writer) as one value. */
void json_raw(json_writer *w, const char *key, const char *json, size_t n);
#endif
