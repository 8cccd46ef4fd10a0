/* Whether a printer takes each layer's own Z: what an adaptive plan needs of
   the job file it reads. One row per job format (jobfile.h's names), so a
   preset's answer is its format's, and a new format adds one row. */
#ifndef ADASLICE_HOST_LAYER_Z_H
#define ADASLICE_HOST_LAYER_Z_H
#include <stdio.h>

typedef enum layer_z_support {
    LAYER_Z_UNKNOWN,          /* a format without a row */
    LAYER_Z_NO,               /* the file holds one layer height: adaptive plans are refused */
    LAYER_Z_FIELD_TROUBLE,    /* the format holds each layer's Z, and printers have been seen to misread it */
    LAYER_Z_PER_FORMAT,       /* the format holds each layer's Z; no report either way from the field */
    LAYER_Z_BY_CONSTRUCTION,  /* the file moves Z itself, layer by layer */
    LAYER_Z_OURS              /* adaslice print and the adaslice firmware */
} layer_z_support;

typedef struct layer_z {
    const char *format;       /* the job_format's name */
    layer_z_support support;
    const char *why;          /* how the file carries each layer's Z, and the evidence */
    const char *risk;         /* for an adaptive job's summary, or NULL */
} layer_z;

/* The row of the format called `format`; a row saying LAYER_Z_UNKNOWN for a
   format that has none. */
const layer_z *layer_z_of(const char *format);
/* "yes by construction", "per the format, not field-verified", ... */
const char *layer_z_says(layer_z_support support);
/* The table, a line per format: for --help and adaslice printers. */
void layer_z_table(FILE *f);
/* The presets (printer.h), each with its format, pixels, pitch, build height
   and per-layer Z, then the table: adaslice printers, slice --printer list. */
void printers_list(FILE *f);
#endif
