/* What adaslice print sends a printer: the plan (layer lengths in bins,
   exposures), the motion and the masks, from a MODEL (planned for the
   printer's display, its masks rendered as they are sent) or a JOBDIR's
   masks.rle; and the work each mask frame asks of the printer's decoder. */
#ifndef ADASLICE_HOST_PRINT_PRINT_JOB_H
#define ADASLICE_HOST_PRINT_PRINT_JOB_H
#include "../formats/jobdir.h"
#include "../layers.h"
#include "../plan_job.h"
#include "serial.h"

/* What is printed: a plan (layer lengths in bins, exposures), the motion
   and a source of masks. */
typedef struct print_job {
    uint32_t layers, bin_nm;
    uint32_t *lengths;             /* bins per layer: the plan's, or the job's */
    uint32_t *exposure_ms;         /* per layer */
    link_print motion;             /* PRINT's fields but the first layer */
    uint32_t width, height, bits;
    uint32_t job;                  /* the job's hash (job_hash), sent with PRINT */
    int from_model;
    layer_masks masks;             /* a MODEL: rendered as they are needed */
    job_masks file;                /* a JOBDIR: its masks.rle */
    /* the current mask */
    unsigned char *code;
    size_t code_size, code_cap, rendered;
    uint32_t crc;
    /* the mask being sent, decoded as it goes: the CRC work each MASK_DATA
       frame asks of the printer, which it does before it answers */
    adaslice_rle_decoder sending;
    unsigned char *sending_row, *sending_prev; /* the row decoded, the one before */
    uint32_t sending_cost;                     /* the frame's bytes of rows' CRC */
} print_job;

/* A MODEL planned and its masks opened for the printer's display (l's
   IDENTIFY); *planned_by_printer: the printer can plan it too (printer
   units, its bins and layer limits) and plan_on_host does not forbid it. */
int print_job_from_model(print_job *pj, plan_args *a, plan_job *j, slice_args *s, const serial_link *l,
                         int plan_on_host, int *planned_by_printer);
/* A JOBDIR's plan, motion and masks. */
int print_job_from_dir(print_job *pj, const char *dir);
/* Layer k's (1-based) mask code into pj->code, with its CRC-32. */
int print_job_mask(print_job *pj, uint32_t k);
/* Bytes of a mask row. */
size_t print_job_stride(const print_job *pj);
/* The current mask is about to be sent from its start. */
int print_job_send_begin(print_job *pj);
/* The bytes of rows' CRC that the current mask's next n code bytes ask of
   the printer's decoder. */
uint32_t print_job_send_cost(print_job *pj, const unsigned char *code, size_t n);
/* The job's hash, sent with PRINT (never 0); mesh NULL for a JOBDIR. */
uint32_t print_job_hash(const print_job *pj, const adaslice_mesh *mesh, const slice_args *s);
void print_job_free(print_job *pj);
#endif
