/* ZIP writer, see zip.h. The layouts are the PKWARE APPNOTE 6.3.x's: 4.3.7
   the local file header, 4.3.12 the central directory header, 4.3.16 the end
   of central directory record; numbers little-endian. Sizes and the CRC are
   known before a member's header goes out (its bytes are in memory), so no
   member needs a data descriptor. */
#include "zip.h"
#include "../bytes.h"
#include "deflate.h"
#include "inflate.h"
#include "png.h"
#include "../report.h"
#include "../../adaslice_mcu.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    LOCAL_HEADER = 30, CENTRAL_HEADER = 46, END_RECORD = 22,
    DOS_DATE = 1 << 5 | 1, /* 1980-01-01, the first day a DOS date can hold; time 00:00:00 is 0 */
    UTF8_NAME = 1 << 11    /* general purpose flag bit 11 (APPNOTE appendix D) */
};
/* 32-bit sizes and offsets stay below this: 0xFFFFFFFF tells a reader to
   look for ZIP64 fields, which this writer has none of. */
#define ZIP_LIMIT 0xFFFFFFFFu

struct zip_writer {
    job_file file;
    uint64_t offset;           /* bytes written so far: the next local header's offset */
    bytebuf central;           /* the central directory, one header per member so far */
    unsigned members;
    int failed;                /* a zip_add failed: the archive is not to be kept */
};

/* The 26 bytes a local header (from its offset 4) and a central header (from
   its offset 6) share: version needed, flags, method, time, date, CRC-32,
   both sizes, name and extra field lengths. */
static void put_common(unsigned char *p, const char *name, size_t len, int method, uint32_t crc, size_t csize,
                       size_t size)
{
    unsigned flags = 0;
    for (size_t i = 0; i < len; i++)
        if ((unsigned char)name[i] >= 0x80) flags = UTF8_NAME; /* names come from the command line */
    put_le16(p, method ? 20 : 10); /* 2.0 for deflate, 1.0 for stored */
    put_le16(p + 2, flags);
    put_le16(p + 4, (unsigned)method);
    put_le16(p + 6, 0);
    put_le16(p + 8, DOS_DATE);
    put_le32(p + 10, crc);
    put_le32(p + 14, (uint32_t)csize);
    put_le32(p + 18, (uint32_t)size);
    put_le16(p + 22, (unsigned)len);
    put_le16(p + 24, 0);
}

static int write_bytes(zip_writer *z, const void *data, size_t size)
{
    job_file_append(&z->file, data, size);
    z->offset += size;
    return job_file_check(&z->file);
}

int zip_open(zip_writer **z, const char *path)
{
    zip_writer *w = (zip_writer *)calloc(1, sizeof *w);
    *z = NULL;
    if (!w) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    if (job_file_open(&w->file, path) != RC_OK) {
        free(w);
        return RC_FAIL;
    }
    *z = w;
    return RC_OK;
}

/* Checks name and size, then writes the member; any complaint leaves
   z->failed set. */
static int add(zip_writer *z, const char *name, const void *data, size_t size, int deflate,
               unsigned char **packed)
{
    const char *path = z->file.path;
    size_t len = strlen(name), csize = size; /* csize: the bytes in the archive */
    const void *body = data;
    unsigned char local[LOCAL_HEADER], *c;
    uint32_t crc;
    int method = 0;

    if (!len || len > 65535 || strchr(name, '\\') || name[0] == '/')
        return complain(RC_FAIL, "cannot write %s: bad member name \"%.80s\": 1 to 65535 bytes, '/' between "
                        "folders, no '\\' and no leading '/'", path, name);
    if (z->members == ZIP_MEMBERS_MAX)
        return complain(RC_FAIL, "cannot write %s: a ZIP holds at most %u members (ZIP64 is not written)", path,
                        ZIP_MEMBERS_MAX);
    if ((uint64_t)size >= ZIP_LIMIT)
        return complain(RC_FAIL, "cannot write %s: member %s has %zu bytes; a ZIP without ZIP64 holds less than "
                        "4 GiB", path, name, size);
    crc = adaslice_crc32(0, data, size);
    if (deflate && size) {
        size_t n;
        if (deflate_bytes((const unsigned char *)data, size, 0, packed, &n))
            return complain(RC_FAIL, "cannot write %s: out of memory deflating %s", path, name);
        if (n < size) {
            body = *packed;
            csize = n;
            method = 8;
        }
    }
    /* the whole archive under 4 GiB keeps every offset and size in 32 bits */
    if (z->offset + LOCAL_HEADER + len + csize + z->central.size + CENTRAL_HEADER + len + END_RECORD >= ZIP_LIMIT)
        return complain(RC_FAIL, "cannot write %s: with %s the archive reaches 4 GiB (ZIP64 is not written)", path,
                        name);
    if (!(c = bytebuf_room(&z->central, CENTRAL_HEADER + len)))
        return complain(RC_FAIL, "cannot write %s: out of memory", path);
    put_le32(c, 0x02014b50);
    put_le16(c + 4, 3 << 8 | 20);  /* made by: UNIX (the attributes below), APPNOTE 2.0 */
    put_common(c + 6, name, len, method, crc, csize, size);
    put_le16(c + 32, 0);           /* comment length */
    put_le16(c + 34, 0);           /* disk number */
    put_le16(c + 36, 0);           /* internal attributes */
    put_le32(c + 38, (uint32_t)0100644 << 16); /* a regular file, rw-r--r-- */
    put_le32(c + 42, (uint32_t)z->offset);
    memcpy(c + CENTRAL_HEADER, name, len);
    put_le32(local, 0x04034b50);
    put_common(local + 4, name, len, method, crc, csize, size);
    if (write_bytes(z, local, LOCAL_HEADER) || write_bytes(z, name, len) || write_bytes(z, body, csize))
        return RC_FAIL;
    z->central.size += CENTRAL_HEADER + len;
    z->members++;
    z->failed = 0;
    return RC_OK;
}

int zip_add(zip_writer *z, const char *name, const void *data, size_t size, int deflate)
{
    unsigned char *packed = NULL;
    int rc;
    if (z->failed) return RC_FAIL;
    z->failed = 1;
    rc = add(z, name, data, size, deflate, &packed);
    free(packed);
    return rc;
}

int zip_close(zip_writer *z, int ok)
{
    int rc = RC_FAIL;
    if (ok && !z->failed) {
        unsigned char end[END_RECORD];
        uint64_t start = z->offset;
        put_le32(end, 0x06054b50);
        put_le16(end + 4, 0);                 /* this disk */
        put_le16(end + 6, 0);                 /* the disk the central directory starts on */
        put_le16(end + 8, z->members);        /* members on this disk */
        put_le16(end + 10, z->members);       /* and in all */
        put_le32(end + 12, (uint32_t)z->central.size);
        put_le32(end + 16, (uint32_t)start);
        put_le16(end + 20, 0);                /* comment length */
        if (write_bytes(z, z->central.data, z->central.size) == RC_OK && write_bytes(z, end, END_RECORD) == RC_OK)
            rc = job_file_commit(&z->file);
        else
            job_file_discard(&z->file);
    } else {
        job_file_discard(&z->file);
    }
    bytebuf_free(&z->central);
    free(z);
    return rc;
}

/* ---- members the zip job formats share ------------------------------- */

void zip_number(FILE *f, double v, int decimals)
{
    char text[DBL_MAX_10_EXP + 32]; /* the longest %.*f there is, decimals <= 16 */
    for (int k = 0; k <= decimals; k++) {
        snprintf(text, sizeof text, "%.*f", k, v);
        if (fabs(strtod(text, NULL) - v) <= 1e-9 * (fabs(v) > 1 ? fabs(v) : 1)) break;
    }
    fputs(text, f);
}

int zip_add_text(zip_writer *z, const char *name, write_fn fill, const void *ctx)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    int bad, rc;
    if (!f) return complain(RC_FAIL, "cannot write %s: out of memory for %s", z->file.path, name);
    fill(f, ctx);
    bad = ferror(f);
    if (fclose(f) != 0 || bad) rc = complain(RC_FAIL, "cannot write %s: out of memory for %s", z->file.path, name);
    else rc = zip_add(z, name, text, size, 1);
    free(text);
    return rc;
}

/* An encoded PNG as a member, or the encoder's failure, which (with the
   sizes a job_desc has) can only be memory. */
static int add_png(zip_writer *z, const char *name, int failed, unsigned char *png, size_t size)
{
    int rc = failed ? complain(RC_FAIL, "cannot write %s: out of memory for %s", z->file.path, name)
                     : zip_add(z, name, png, size, 0);
    free(png);
    return rc;
}

int zip_layer_png(const job_desc *d, const unsigned char *image, size_t stride, job_blob *blob)
{
    unsigned char *png = NULL;
    size_t size = 0;
    if (png_encode_mask(image, d->width, d->height, stride, d->bits, &png, &size))
        return complain(RC_FAIL, "out of memory for a %d x %d layer PNG", d->width, d->height);
    blob->data = png;
    blob->size = blob->cap = size;
    return RC_OK;
}

int zip_add_blob(zip_writer *z, const char *name, job_blob *blob)
{
    int rc = zip_add(z, name, blob->data, blob->size, 0);
    free(blob->data);
    blob->data = NULL;
    return rc;
}

int zip_add_preview_png(zip_writer *z, const char *name, const job_desc *d, int w, int h)
{
    unsigned char *rgb, *png = NULL;
    size_t size = 0;
    int rc = -1;
    if (!d->preview) return RC_OK;
    rgb = (unsigned char *)malloc((size_t)w * (size_t)h * 3);
    if (rgb && d->preview(d->preview_ctx, w, h, rgb) == 0)
        rc = png_encode_rgb(rgb, w, h, &png, &size);
    free(rgb);
    return add_png(z, name, rc, png, size);
}

int zip_member(const unsigned char *data, size_t size, const char *name, unsigned char **out, size_t *out_size,
               char why[128])
{
    size_t at, end, i, len = strlen(name);
    *out = NULL;
    *out_size = 0;
    if (size < END_RECORD) { snprintf(why, 128, "%zu bytes, too short for a ZIP archive", size); return -1; }
    /* the end record, behind a comment of up to 65535 bytes */
    for (end = size - END_RECORD + 1; end-- > 0 && size - end <= END_RECORD + 65535u;)
        if (get_le32(data + end) == 0x06054b50u) break;
    if (end == (size_t)-1 || size - end > END_RECORD + 65535u || get_le32(data + end) != 0x06054b50u) {
        snprintf(why, 128, "no ZIP end record");
        return -1;
    }
    at = get_le32(data + end + 16);
    for (i = get_le16(data + end + 10); i > 0; i--) {
        size_t nlen, csize, usize, local, start;
        unsigned method;
        if (at > end || end - at < CENTRAL_HEADER || get_le32(data + at) != 0x02014b50u) {
            snprintf(why, 128, "a broken central directory at byte %zu", at);
            return -1;
        }
        method = get_le16(data + at + 10);
        csize = get_le32(data + at + 20);
        usize = get_le32(data + at + 24);
        nlen = get_le16(data + at + 28);
        local = get_le32(data + at + 42);
        if (nlen > end - at - CENTRAL_HEADER) { snprintf(why, 128, "a broken central directory at byte %zu", at); return -1; }
        if (nlen == len && !memcmp(data + at + CENTRAL_HEADER, name, len)) {
            if (local > size || size - local < LOCAL_HEADER || get_le32(data + local) != 0x04034b50u ||
                (start = local + LOCAL_HEADER + get_le16(data + local + 26) + get_le16(data + local + 28)) > size ||
                csize > size - start) {
                snprintf(why, 128, "%.40s: a broken local header at byte %zu", name, local);
                return -1;
            }
            if ((method != 0 && method != 8) || (method == 0 && csize != usize)) {
                snprintf(why, 128, "%.40s: compression method %u (stored or deflated only)", name, method);
                return -1;
            }
            /* deflate makes at most 1032 bytes of 1; and no member this
               reader is asked for (a 3MF's model, its profile) nears 1 GiB */
            if (usize > ZIP_MEMBER_MAX || (method == 8 && usize / 1032 > csize)) {
                snprintf(why, 128, "%.40s: %zu bytes from %zu: more than this reader takes (%u MiB, 1032 to 1)", name,
                         usize, csize, (unsigned)(ZIP_MEMBER_MAX >> 20));
                return -1;
            }
            if (!(*out = (unsigned char *)malloc(usize + 1))) { snprintf(why, 128, "out of memory"); return -1; }
            if (method == 0) memcpy(*out, data + start, usize);
            if ((method == 8 && inflate_bytes(data + start, csize, *out, usize)) ||
                adaslice_crc32(0, *out, usize) != get_le32(data + at + 16)) {
                free(*out);
                *out = NULL;
                snprintf(why, 128, "%.40s: its data is corrupt", name);
                return -1;
            }
            (*out)[usize] = 0;
            *out_size = usize;
            return 0;
        }
        at += CENTRAL_HEADER + nlen + get_le16(data + at + 30) + get_le16(data + at + 32);
    }
    return 1;
}
