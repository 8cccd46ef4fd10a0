/* adaslice print's --report read back, for the tests that drive a printer
   (test_print.c on fw-sim and QEMU, test_avr.c under simavr). One includer
   per program (static functions). */
#ifndef ADASLICE_PRINT_REPORT_H
#define ADASLICE_PRINT_REPORT_H
#include "cli_run.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The host's --report: each layer's top (bins), mask CRC and exposure. */
typedef struct print_report {
    uint32_t layers, first, bin_nm, *tops, *crcs, *exposures;
    unsigned long retransmits, mask_bytes;
    double longest_wait_ms;
    int by_printer;
} print_report;

static inline int read_print_report(const char *path, print_report *r)
{
    char *text = read_whole_text(path), *at;
    uint32_t k = 0;
    const char *f;
    memset(r, 0, sizeof *r);
    if (!text) return 0;
    if ((f = strstr(text, "\"layers\": "))) r->layers = (uint32_t)strtoul(f + 10, NULL, 10);
    if ((f = strstr(text, "\"first_layer\": "))) r->first = (uint32_t)strtoul(f + 15, NULL, 10);
    if ((f = strstr(text, "\"bin_nm\": "))) r->bin_nm = (uint32_t)strtoul(f + 10, NULL, 10);
    if ((f = strstr(text, "\"retransmitted_frames\": "))) r->retransmits = strtoul(f + 24, NULL, 10);
    if ((f = strstr(text, "\"mask_code_bytes\": "))) r->mask_bytes = strtoul(f + 19, NULL, 10);
    if ((f = strstr(text, "\"longest_wait_ms\": "))) r->longest_wait_ms = strtod(f + 19, NULL);
    r->by_printer = strstr(text, "\"planned_by_printer\": true") != NULL;
    r->tops = (uint32_t *)calloc(r->layers + 1, sizeof *r->tops);
    r->crcs = (uint32_t *)calloc(r->layers + 1, sizeof *r->crcs);
    r->exposures = (uint32_t *)calloc(r->layers + 1, sizeof *r->exposures);
    for (at = strstr(text, "\"masks\""); at && k < r->layers && (at = strstr(at, "\"top_bins\": ")); k++) {
        r->tops[k] = (uint32_t)strtoul(at + 12, &at, 10);
        at = strstr(at, "\"crc32\": \"");
        if (!at) break;
        r->crcs[k] = (uint32_t)strtoul(at + 10, &at, 16);
        at = strstr(at, "\"exposure_ms\": ");
        if (!at) break;
        r->exposures[k] = (uint32_t)strtoul(at + 15, &at, 10);
    }
    free(text);
    return r->layers && k == r->layers;
}

/* The pace the printer's IDENTIFY stated, as adaslice print's first line
   says it ("its pace X us a byte of rows' CRC, Y us a bin planned"), in
   ns: 1 if `out` has it. */
static inline int print_pace(const char *out, double *crc_byte_ns, double *plan_bin_ns)
{
    const char *at = out ? strstr(out, "its pace ") : NULL;
    double crc, bin;
    if (!at || sscanf(at, "its pace %lf us a byte of rows' CRC, %lf us a bin planned", &crc, &bin) != 2) return 0;
    *crc_byte_ns = crc * 1e3;
    *plan_bin_ns = bin * 1e3;
    return 1;
}

static inline void print_report_free(print_report *r) { free(r->tops); free(r->crcs); free(r->exposures); }
#endif
