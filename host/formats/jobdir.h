/* The job directory, written by adaslice slice (JOB_FORMAT_DIR of jobfile.h)
   and read by adaslice print: one PNG per layer named layer_00001.png, a
   shaded preview.png, masks.rle (the masks as a printer takes them) and,
   written last, manifest.json: a job without one is not complete. The
   manifest lists every file of the job ("files"), which is all a later slice
   into the directory removes; a directory of other files and no manifest is
   refused unless --force.
   Little-endian masks.rle: "ADASMSK2", u32 width, height, bits, layers,
   bin_nm, peel_nm, peel_speed_um_s, return_speed_um_s, settle_ms; then per
   layer u32 bins (its thickness), u32 exposure_ms, u32 CRC-32 of the mask,
   u32 code bytes, the code (adaslice_mcu.h's run-length code). */
#ifndef ADASLICE_HOST_JOBDIR_H
#define ADASLICE_HOST_JOBDIR_H
#include <stddef.h>
#include <stdint.h>

/* Digits of a layer's number: five, more from 100,000 layers on. */
int layer_digits(size_t layers);
/* "layer_00001.EXT" for layer k (0-based). */
void layer_name(char name[40], size_t k, int digits, const char *ext);
/* "DIR/layer_00001.EXT" */
void layer_path(char *path, size_t size, const char *dir, size_t k, int digits, const char *ext);

/* Removes the job in DIR: its manifest first, then the files it names (its
   "files" list; in a manifest from before the list, its layers' files, their
   SVGs, masks.rle, preview.png, plan.csv and plot.svg), leaving DIR and
   anything else in it. */
int jobdir_remove(const char *dir);
/* 1 when a job directory may write or remove a file of this name: its
   manifest, masks, preview, plan, plot, or a layer's PNG or SVG. */
int jobdir_file_name(const char *name);
/* Before the work: a DIR that holds files and no manifest.json is someone
   else's, refused (RC_USAGE, said) unless force. */
int jobdir_check(const char *dir, int force);

/* The masks of a job as a printer takes them, with its exposures and motion. */
typedef struct job_masks {
    uint32_t width, height, bits, layers, bin_nm;
    uint32_t peel_nm, peel_speed_um_s, return_speed_um_s, settle_ms;
    uint32_t *lengths;           /* bins per layer */
    uint32_t *exposure_ms;       /* per layer */
    unsigned char **codes;       /* per layer */
    size_t *sizes;
    uint32_t *crcs;
    double pitch_mm[2];          /* read: the manifest's pixel pitch, mm across and down */
    unsigned char *file;         /* read: the whole file, which codes[] point into */
    size_t file_size;
} job_masks;
/* Room for `layers` layers (codes allocated by the caller, freed here). */
int job_masks_alloc(job_masks *m, uint32_t layers);
void job_masks_free(job_masks *m);
/* Reads and checks DIR/masks.rle, naming the file and byte at fault, and
   the pixel pitch its manifest names: its header and layer table (what
   slice would write, cure.h's limits), not the layers' codes. */
int jobdir_read_masks(const char *dir, job_masks *m);
/* Decodes layer k (0-based) of m, each row into `row` (a row's bytes) and
   to emit(ctx, y, row) if given, and checks the rows against the layer's
   CRC-32; a complaint names masks.rle's byte at fault. */
int jobdir_decode_layer(const char *dir, const job_masks *m, uint32_t k, unsigned char *row,
                        void (*emit)(void *ctx, uint32_t y, const unsigned char *row), void *ctx);
/* Every layer so decoded and checked: before a print begins, so that a
   damaged layer does not stop it half way up the part (about a second for
   1,400 layers of 3840 x 2400 px). */
int jobdir_check_layers(const char *dir, const job_masks *m);
#endif
