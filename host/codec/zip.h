/* ZIP archives as the job formats need them (a ChiTu G-code .zip, a Prusa
   .sl1): written front to back from members in memory, after the PKWARE
   APPNOTE 6.3 without ZIP64, to a temporary name renamed into place on a good
   close (jobfile.h's job_file). Members are stored or deflated (deflate.h),
   every one dated 1980-01-01 00:00 so the same job gives the same bytes. The
   formats' common members (text, layer PNGs, previews) are made here too. */
#ifndef ADASLICE_HOST_ZIP_H
#define ADASLICE_HOST_ZIP_H
#include <stddef.h>
#include "../formats/jobfile.h"
#include "../output.h"

typedef struct zip_writer zip_writer;

/* Members an archive without ZIP64 holds: the end record counts them in 16 bits. */
#define ZIP_MEMBERS_MAX 65535u

/* Begins an archive at path (written as "PATH.tmp.PID"); RC_OK, or a
   complaint made and *z = NULL. */
int zip_open(zip_writer **z, const char *path);
/* Appends member `name` ('/' between folders, no '\\', no leading '/', 1 to
   65535 bytes) of `size` bytes, deflated when deflate is set and that makes
   it smaller, else stored. Refused with a complaint: a bad name, the 65536th
   member, and a member or archive of 4 GiB or more (ZIP64 is not written).
   After a failure the archive can only be closed, and not kept. */
int zip_add(zip_writer *z, const char *name, const void *data, size_t size, int deflate);
/* ok: writes the central directory and puts the archive in place, RC_OK or a
   complaint made; !ok (or after a failed zip_add): removes what was written
   and returns RC_FAIL. Frees z either way. */
int zip_close(zip_writer *z, int ok);

/* ---- reading --------------------------------------------------------- */

#define ZIP_MEMBER_MAX ((size_t)1 << 30)
/* Member `name` of the archive data[0, size), stored or deflated, its CRC-32
   checked, into *out (malloc'd, a NUL after its *out_size bytes; the caller
   frees it); ZIP_MEMBER_MAX bytes at most. 0; 1 when the archive has no such member; -1 for an archive or
   member that is malformed (what is wrong in why[0, 128)) or out of memory. */
int zip_member(const unsigned char *data, size_t size, const char *name, unsigned char **out, size_t *out_size,
               char why[128]);

/* ---- members the zip job formats share ------------------------------- */

/* v with the fewest decimals, at most `decimals` (16 or less), that read
   back as v (to a billionth of it): 0.05, 5.052, 150, as ChiTuBox and
   PrusaSlicer print numbers; never an exponent. */
void zip_number(FILE *f, double v, int decimals);
/* A text member, deflated, that fill writes through a FILE. */
int zip_add_text(zip_writer *z, const char *name, write_fn fill, const void *ctx);
/* A layer image as `encode` gets it (jobfile.h: d->width x d->height,
   d->bits, rows `stride` apart) as an 8-bit grey PNG in blob; and a blob
   added as a member, stored (a PNG is deflated already), its data freed. */
int zip_layer_png(const job_desc *d, const unsigned char *image, size_t stride, job_blob *blob);
int zip_add_blob(zip_writer *z, const char *name, job_blob *blob);
/* d->preview drawn at w x h as an RGB PNG, stored; nothing without a
   d->preview. */
int zip_add_preview_png(zip_writer *z, const char *name, const job_desc *d, int w, int h);

#endif
