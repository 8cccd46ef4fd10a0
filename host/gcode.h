/* FDM G-code as a slicer writes it, one line at a time: the words of a move
   and the comments PrusaSlicer labels its layers and features with. Every
   parser here reads only the len bytes it is given (no NUL needed), so any
   bytes are safe input (tests/fuzz_contour.c). */
#ifndef ADASLICE_HOST_GCODE_H
#define ADASLICE_HOST_GCODE_H
#include <stddef.h>

enum { GC_X = 1, GC_Y = 2, GC_Z = 4, GC_E = 8, GC_F = 16 };

typedef struct gcode_words {
    char letter;                 /* 'G', 'M', 'T' ... of the command, 0 for none */
    int code;                    /* its number (G1: 1) */
    unsigned has;                /* GC_* of the axis words present */
    double v[5];                 /* X Y Z E F, where present */
} gcode_words;

/* The words of line[0, len) up to its ';' comment. 0, or -1 for a line this
   reader cannot take (a word without a number, a number out of range, a
   command with a fraction such as G29.1 is kept as letter and code 29 with
   the fraction dropped); *bad is the byte offset of what is wrong. */
int gcode_parse(const char *line, size_t len, gcode_words *w, size_t *bad);
/* The number after the comment `key` ("Z:" for ";Z:0.28") that line[0, len)
   is, or 0 when it is not that comment or has no number there. */
int gcode_comment_number(const char *line, size_t len, const char *key, double *v);
/* 1 when line[0, len) is the comment ";key" followed by anything. */
int gcode_is_comment(const char *line, size_t len, const char *key);
/* The value of the last "; key = value" line of text[0, len): PrusaSlicer's
   config, as it ends its G-code and as a 3MF's Metadata/\*.config holds it.
   NULL when there is none; *n the value's length (a '\r' left out). */
const char *gcode_config_value(const char *text, size_t len, const char *key, size_t *n);
#endif
