/* The job directory, written by adaslice slice and read by adaslice print:
   layer files named layer_00001.EXT, manifest.json (written last: a job
   without one is not complete) and masks.rle, the masks as a printer takes
   them. Little-endian masks.rle: "ADASMSK1", u32 width, height, bits, layers,
   bin_nm; then per layer u32 bins (its thickness), u32 CRC-32 of the mask,
   u32 code bytes, the code (adaslice_mcu.h's run-length code). */
#ifndef ADASLICE_HOST_JOBDIR_H
#define ADASLICE_HOST_JOBDIR_H
#include <stddef.h>
#include <stdint.h>
#include "layers.h"
#include "plan_job.h"

/* Digits of a layer's number: five, more from 100,000 layers on. */
int layer_digits(size_t layers);
/* "layer_00001.EXT" for layer k (0-based). */
void layer_name(char name[40], size_t k, int digits, const char *ext);
/* "DIR/layer_00001.EXT" */
void layer_path(char *path, size_t size, const char *dir, size_t k, int digits, const char *ext);

typedef struct job_layer { double z_bottom, z_top, thickness, lit_mm2; } job_layer;

typedef struct job_manifest {
    const slice_args *s;
    const plan_args *a;
    const plan_job *j;
    const job_layer *layers;
    size_t count;
    int digits;
    double part[3];              /* size of the part, mm */
} job_manifest;
int jobdir_write_manifest(const char *dir, const job_manifest *m);

/* The masks of a job as a printer takes them. */
typedef struct job_masks {
    uint32_t width, height, bits, layers, bin_nm;
    uint32_t *lengths;           /* bins per layer */
    unsigned char **codes;       /* per layer */
    size_t *sizes;
    uint32_t *crcs;
    unsigned char *file;         /* read: the whole file, which codes[] point into */
    size_t file_size;
} job_masks;
/* Room for `layers` layers (codes allocated by the caller, freed here). */
int job_masks_alloc(job_masks *m, uint32_t layers);
void job_masks_free(job_masks *m);
/* DIR/masks.rle; none when the bin is not a whole number of nanometres (a
   printer counts those), and any old one is removed. */
int jobdir_write_masks(const char *dir, const job_masks *m, double bin_mm);
/* Reads and checks DIR/masks.rle, naming the file and byte at fault. */
int jobdir_read_masks(const char *dir, job_masks *m);
#endif
