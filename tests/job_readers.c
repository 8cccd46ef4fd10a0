/* Strict readers for ChiTuBox .ctb (v2-v5, unencrypted layout, and the
   encrypted one) and Elegoo .goo V3.0 job files; see job_readers.h.  Written
   from the byte layouts: every access goes through a bounds check, every
   error names a file offset. */
#include "job_readers.h"
#include "../host/codec/aes256.h"
#include "../host/codec/sha256.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Limits, so that a corrupt header cannot make the reader allocate without
   bound.  A 16K display (15120 x 6230) is 94 Mpx. */
#ifndef JR_MAX_PIXELS
#define JR_MAX_PIXELS (1ull << 28)          /* one layer image */
#endif
#ifndef JR_MAX_IMAGE_BYTES
#define JR_MAX_IMAGE_BYTES (1ull << 31)     /* all kept layer images together */
#endif
#ifndef JR_MAX_PREVIEW_PIXELS
#define JR_MAX_PREVIEW_PIXELS (1ull << 22)
#endif

typedef unsigned long long u64;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static int fail(jr_job *job, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(job->error, sizeof job->error, fmt, ap);
    va_end(ap);
    return -1;
}

/* [off, off+len) lies inside a buffer of n bytes. */
static int inside(size_t n, u64 off, u64 len)
{
    return off <= (u64)n && len <= (u64)n - off;
}

static uint32_t le16(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8; }
static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint32_t be16(const unsigned char *p) { return (uint32_t)p[0] << 8 | (uint32_t)p[1]; }
static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}
static double f32_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return (double)f;
}
static double lef(const unsigned char *p) { return f32_bits(le32(p)); }
static double bef(const unsigned char *p) { return f32_bits(be32(p)); }

static void copy_name(char *dst, size_t cap, const unsigned char *src, size_t len)
{
    size_t i;
    for (i = 0; i < len && i + 1 < cap && src[i]; i++) dst[i] = (char)src[i];
    dst[i] = 0;
}

static void free_all(jr_job *job)
{
    unsigned i;
    if (job->layers) {
        for (i = 0; i < job->layer_count; i++) free(job->layers[i].image);
        free(job->layers);
    }
    free(job->preview_rgb[0]);
    free(job->preview_rgb[1]);
    job->layers = NULL;
    job->preview_rgb[0] = job->preview_rgb[1] = NULL;
}

void jr_free(jr_job *job)
{
    if (!job) return;
    free_all(job);
}

unsigned char jr_ctb_grey(unsigned char v)
{
    unsigned s = v >> 1;
    return (unsigned char)(s ? (s << 1) | 1 : 0);
}

/* Checks the image size and, unless images are skipped, that all layers fit
   the memory limit. */
static int check_dims(jr_job *job, const char *fmt, u64 w, u64 h, unsigned layers, unsigned flags,
                      u64 off_w)
{
    if (w == 0 || h == 0)
        return fail(job, "%s: resolution %llux%llu at offset %llu: zero", fmt, w, h, off_w);
    if (w > 0x7fffffff || h > 0x7fffffff || w * h > JR_MAX_PIXELS)
        return fail(job, "%s: resolution %llux%llu at offset %llu exceeds the reader's limit of %llu pixels",
                    fmt, w, h, off_w, (u64)JR_MAX_PIXELS);
    if (!(flags & JR_SKIP_IMAGES) && (u64)layers * w * h > JR_MAX_IMAGE_BYTES)
        return fail(job, "%s: %u layers of %llux%llu need %llu bytes, more than the reader's limit %llu"
                    " (read with JR_SKIP_IMAGES)", fmt, layers, w, h, (u64)layers * w * h,
                    (u64)JR_MAX_IMAGE_BYTES);
    return 0;
}

/* ------------------------------------------------------------------ CTB */

#define CTB_MAGIC_V3 0x12FD0086u
#define CTB_MAGIC_V4 0x12FD0106u
#define CTB_MAGIC_GKTWO 0xFF220810u
#define CTB_MAGIC_CBDDLP 0x12FD0019u
#define CTB_MAGIC_ENCRYPTED 0x12FD0107u
#define CTB_HEADER 112u
#define CTB_PREVIEW_HEADER 32u
#define CTB_PRINT_PARAMS 60u
#define CTB_SLICER_INFO 76u
#define CTB_PARAMS_V4 464u
#define CTB_LAYER_DEF 36u
#define CTB_LAYER_DEF_EX 84u

/* Preview: 32-byte header, then u16 LE words R5 G5 (flag) B5, flag 0x20 =
   a u16 count word (n-1)|0x3000 follows. */
static int ctb_preview(jr_job *job, const unsigned char *d, size_t n, uint32_t at, int slot,
                       const char *name)
{
    const unsigned char *p;
    uint32_t w, h, off, len;
    u64 npix, px = 0, i;
    unsigned char *rgb;

    if (at == 0) return 0;
    if (!inside(n, at, CTB_PREVIEW_HEADER))
        return fail(job, "ctb: %s preview header at offset %u runs past the end of the file (%zu bytes)",
                    name, (unsigned)at, n);
    w = le32(d + at);
    h = le32(d + at + 4);
    off = le32(d + at + 8);
    len = le32(d + at + 12);
    if (w == 0 || h == 0 || (u64)w * h > JR_MAX_PREVIEW_PIXELS)
        return fail(job, "ctb: %s preview at offset %u: bad size %ux%u", name, (unsigned)at,
                    (unsigned)w, (unsigned)h);
    if (!inside(n, off, len))
        return fail(job, "ctb: %s preview data [%u, +%u) (header at %u) runs past the end of the file (%zu bytes)",
                    name, (unsigned)off, (unsigned)len, (unsigned)at, n);
    npix = (u64)w * h;
    /* Four bytes cover at most 4096 pixels: reject before allocating. */
    if (npix > ((u64)len / 4 + 1) * 4096)
        return fail(job, "ctb: %s preview at offset %u: %u data bytes cannot cover %ux%u pixels",
                    name, (unsigned)off, (unsigned)len, (unsigned)w, (unsigned)h);
    rgb = (unsigned char *)malloc((size_t)npix * 3);
    if (!rgb) return fail(job, "ctb: out of memory for the %s preview", name);
    p = d + off;
    for (i = 0; i < len;) {
        uint32_t dot, rep = 1;
        unsigned char r, g, b;
        u64 k;
        if (len - i < 2) {
            free(rgb);
            return fail(job, "ctb: %s preview: odd byte at offset %llu at the end of the data", name,
                        (u64)off + i);
        }
        dot = le16(p + i);
        if (dot & 0x20) {
            uint32_t cnt;
            if (len - i < 4) {
                free(rgb);
                return fail(job, "ctb: %s preview: run word at offset %llu has no count word", name,
                            (u64)off + i);
            }
            cnt = le16(p + i + 2);
            if ((cnt & 0xF000) != 0x3000) {
                free(rgb);
                return fail(job, "ctb: %s preview: count word 0x%04X at offset %llu lacks the 0x3000 mark",
                            name, (unsigned)cnt, (u64)off + i + 2);
            }
            rep = (cnt & 0xFFF) + 1;
        }
        if (rep > npix - px) {
            free(rgb);
            return fail(job, "ctb: %s preview: run of %u at offset %llu overruns %ux%u (pixel %llu)", name,
                        (unsigned)rep, (u64)off + i, (unsigned)w, (unsigned)h, px);
        }
        i += (dot & 0x20) ? 4 : 2;
        r = (unsigned char)(((dot >> 11) & 0x1F) << 3);
        g = (unsigned char)(((dot >> 6) & 0x1F) << 3);
        b = (unsigned char)((dot & 0x1F) << 3);
        for (k = 0; k < rep; k++, px++) {
            rgb[px * 3] = r;
            rgb[px * 3 + 1] = g;
            rgb[px * 3 + 2] = b;
        }
    }
    if (px != npix) {
        free(rgb);
        return fail(job, "ctb: %s preview at offset %u covers %llu of %llu pixels", name, (unsigned)off,
                    px, npix);
    }
    job->preview_w[slot] = (int)w;
    job->preview_h[slot] = (int)h;
    job->preview_rgb[slot] = rgb;
    return 0;
}

/* Sequential reader of layer data with the optional XOR stream. */
typedef struct xstream {
    const unsigned char *p;
    size_t n, i;
    uint32_t init, key;
    unsigned idx;
    int on;
} xstream;

static void xs_start(xstream *s, const unsigned char *p, size_t n, uint32_t seed, uint32_t layer)
{
    s->p = p;
    s->n = n;
    s->i = 0;
    s->idx = 0;
    s->on = seed != 0;
    s->init = (uint32_t)((uint32_t)(seed * 0x2D83CDACu) + 0xD8A83423u);
    s->key = (uint32_t)((uint32_t)((uint32_t)(layer * 0x1E1530CDu) + 0xEC3D47CDu) * s->init);
}

static int xs_get(xstream *s, unsigned *out)
{
    unsigned c;
    if (s->i >= s->n) return 0;
    c = s->p[s->i++];
    if (s->on) {
        c ^= (s->key >> (8 * s->idx)) & 0xFF;
        if (++s->idx == 4) {
            s->idx = 0;
            s->key = (uint32_t)(s->key + s->init);
        }
    }
    *out = c;
    return 1;
}

void jr_ctb_decrypt(unsigned key, unsigned layer, const unsigned char *in, size_t n, unsigned char *out)
{
    xstream s;
    unsigned c;
    size_t i = 0;
    xs_start(&s, in, n, (uint32_t)key, (uint32_t)layer);
    while (xs_get(&s, &c)) out[i++] = (unsigned char)c;
}

/* RLE7: byte v (bit 7 clear) = one pixel; bit 7 set = run, length follows
   (0xxxxxxx | 10xxxxxx+1 | 110xxxxx+2 | 1110xxxx+3 bytes, big-endian);
   grey = v ? v<<1|1 : 0. */
static int ctb_decode(jr_job *job, unsigned layer, const unsigned char *p, size_t len, u64 base,
                      uint32_t seed, unsigned char *out, u64 npix)
{
    xstream s;
    u64 px = 0;
    unsigned c;
    xs_start(&s, p, len, seed, layer);
    while (s.i < len) {
        size_t at = s.i;
        u64 run = 1;
        unsigned v, grey;
        if (px == npix)
            return fail(job, "ctb: layer %u: %llu bytes left at offset %llu after the image is complete",
                        layer, (u64)(len - at), base + at);
        xs_get(&s, &c);
        v = c & 0x7F;
        if (c & 0x80) {
            unsigned b, extra, k;
            if (!xs_get(&s, &b))
                return fail(job, "ctb: layer %u: run code at offset %llu has no length byte", layer,
                            base + at);
            if (!(b & 0x80)) { run = b; extra = 0; }
            else if ((b & 0xC0) == 0x80) { run = b & 0x3F; extra = 1; }
            else if ((b & 0xE0) == 0xC0) { run = b & 0x1F; extra = 2; }
            else if ((b & 0xF0) == 0xE0) { run = b & 0x0F; extra = 3; }
            else
                return fail(job, "ctb: layer %u: invalid run-length byte 0x%02X at offset %llu", layer, b,
                            base + at + 1);
            for (k = 0; k < extra; k++) {
                unsigned e;
                if (!xs_get(&s, &e))
                    return fail(job, "ctb: layer %u: run length at offset %llu is cut off by the end of the data",
                                layer, base + at + 1);
                run = run << 8 | e;
            }
            if (run == 0)
                return fail(job, "ctb: layer %u: zero-length run at offset %llu", layer, base + at);
        }
        if (run > npix - px)
            return fail(job, "ctb: layer %u: run of %llu at offset %llu overruns the image (pixel %llu of %llu)",
                        layer, run, base + at, px, npix);
        grey = v ? (v << 1) | 1 : 0;
        if (out) memset(out + px, (int)grey, (size_t)run);
        px += run;
    }
    if (px != npix)
        return fail(job, "ctb: layer %u: data at offset %llu (%zu bytes) decodes to %llu of %llu pixels",
                    layer, base, len, px, npix);
    return 0;
}

int jr_read_ctb_ex(const unsigned char *d, size_t n, jr_job *job, unsigned flags)
{
    uint32_t magic, version, w, h, pv_large, pv_small, table, count, pp_off, pp_size, aa_hdr, key,
        si_off, si_size;
    u64 npix;
    unsigned i;

    memset(job, 0, sizeof *job);
    job->format = JR_CTB;
    if (!d) return fail(job, "ctb: no data");
    if (n < CTB_HEADER)
        return fail(job, "ctb: file is %zu bytes, shorter than the %u-byte header at offset 0", n, CTB_HEADER);
    magic = le32(d);
    version = le32(d + 4);
    job->magic = magic;
    job->version = version;
    if (magic == CTB_MAGIC_CBDDLP) return fail(job, "ctb: magic 0x%08X at offset 0 is cbddlp/photon, not ctb", (unsigned)magic);
    if (magic == CTB_MAGIC_ENCRYPTED) return fail(job, "ctb: magic 0x%08X at offset 0 is encrypted ctb (jr_read_ctb_encrypted)", (unsigned)magic);
    if (magic != CTB_MAGIC_V3 && magic != CTB_MAGIC_V4 && magic != CTB_MAGIC_GKTWO)
        return fail(job, "ctb: unknown magic 0x%08X at offset 0", (unsigned)magic);
    if (version < 2 || version > 5)
        return fail(job, "ctb: version %u at offset 4 not supported (2-5)", (unsigned)version);
    if (magic == CTB_MAGIC_V3 && version > 3)
        return fail(job, "ctb: version %u at offset 4 with magic 0x%08X (v4/v5 use 0x%08X)", (unsigned)version,
                    (unsigned)magic, CTB_MAGIC_V4);
    if (magic != CTB_MAGIC_V3 && version < 4)
        return fail(job, "ctb: version %u at offset 4 with magic 0x%08X (v2/v3 use 0x%08X)", (unsigned)version,
                    (unsigned)magic, CTB_MAGIC_V3);

    job->bed_mm[0] = lef(d + 8);
    job->bed_mm[1] = lef(d + 12);
    job->bed_mm[2] = lef(d + 16);
    job->total_height_mm = lef(d + 28);
    job->layer_height_mm = lef(d + 32);
    job->exposure_s = lef(d + 36);
    job->bottom_exposure_s = lef(d + 40);
    job->light_off_s = lef(d + 44);
    job->bottom_layers = le32(d + 48);
    w = le32(d + 52);
    h = le32(d + 56);
    pv_large = le32(d + 60);
    table = le32(d + 64);
    count = le32(d + 68);
    pv_small = le32(d + 72);
    job->print_time = le32(d + 76);
    job->mirror = (int)le32(d + 80);
    pp_off = le32(d + 84);
    pp_size = le32(d + 88);
    aa_hdr = le32(d + 92);
    key = le32(d + 100);
    si_off = le32(d + 104);
    si_size = le32(d + 108);
    job->ctb_encryption_key = key;
    job->anti_alias = aa_hdr ? (int)aa_hdr : 1;

    if (aa_hdr > 1)
        return fail(job, "ctb: header AntiAliasLevel %u at offset 92: ctb keeps 1 there (AA level is in SlicerInfo)",
                    (unsigned)aa_hdr);
    if (count == 0) return fail(job, "ctb: LayerCount at offset 68 is 0");
    if (!inside(n, table, (u64)count * CTB_LAYER_DEF))
        return fail(job, "ctb: layer table at offset %u (%u entries of %u bytes, from header offsets 64/68) runs past the end of the file (%zu bytes)",
                    (unsigned)table, (unsigned)count, CTB_LAYER_DEF, n);
    if (check_dims(job, "ctb", w, h, count, flags, 52)) return -1;
    job->width = (int)w;
    job->height = (int)h;
    npix = (u64)w * h;

    /* PrintParameters (60 bytes). */
    if (pp_off == 0) return fail(job, "ctb: PrintParametersOffset at offset 84 is 0");
    if (pp_size != CTB_PRINT_PARAMS)
        return fail(job, "ctb: PrintParametersSize at offset 88 is %u, expected %u", (unsigned)pp_size,
                    CTB_PRINT_PARAMS);
    if (!inside(n, pp_off, CTB_PRINT_PARAMS))
        return fail(job, "ctb: PrintParameters at offset %u runs past the end of the file (%zu bytes)",
                    (unsigned)pp_off, n);

    /* SlicerInfo (76 bytes + machine name). */
    if (si_off == 0) return fail(job, "ctb: SlicerOffset at offset 104 is 0");
    if (si_size < CTB_SLICER_INFO)
        return fail(job, "ctb: SlicerSize at offset 108 is %u, less than %u", (unsigned)si_size, CTB_SLICER_INFO);
    if (!inside(n, si_off, CTB_SLICER_INFO))
        return fail(job, "ctb: SlicerInfo at offset %u runs past the end of the file (%zu bytes)", (unsigned)si_off, n);
    {
        const unsigned char *si = d + si_off;
        uint32_t name_at = le32(si + 28), name_len = le32(si + 32);
        if (name_len) {
            if (!inside(n, name_at, name_len))
                return fail(job, "ctb: machine name [%u, +%u) (SlicerInfo+28 at offset %u) runs past the end of the file",
                            (unsigned)name_at, (unsigned)name_len, (unsigned)si_off + 28);
            copy_name(job->machine_name, sizeof job->machine_name, d + name_at, name_len);
        }
        job->ctb_aa_flag = si[36];
        job->per_layer_raw = si[39];
        job->per_layer_settings = si[39] != 0;
        job->anti_alias = (int)le32(si + 44);
        job->ctb_software_version = le32(si + 48);
        job->ctb_transition_layers = le32(si + 60);
        if (version >= 4) {
            uint32_t v4 = le32(si + 64), dis_at, dis_len;
            if (v4 == 0)
                return fail(job, "ctb: v%u: PrintParametersV4Address at offset %u (SlicerInfo+64) is 0",
                            (unsigned)version, (unsigned)si_off + 64);
            if (!inside(n, v4, CTB_PARAMS_V4))
                return fail(job, "ctb: PrintParametersV4 at offset %u (%u bytes) runs past the end of the file (%zu bytes)",
                            (unsigned)v4, CTB_PARAMS_V4, n);
            job->ctb_v4_last_layer_index = le32(d + v4 + 52);
            dis_at = le32(d + v4 + 72);
            dis_len = le32(d + v4 + 76);
            job->ctb_v4_disclaimer_length = dis_len;
            if (dis_at == 0 || dis_len == 0)
                return fail(job, "ctb: v4 disclaimer missing (address %u, length %u at offsets %u/%u)",
                            (unsigned)dis_at, (unsigned)dis_len, (unsigned)v4 + 72, (unsigned)v4 + 76);
            if (!inside(n, dis_at, dis_len))
                return fail(job, "ctb: v4 disclaimer [%u, +%u) (PrintParametersV4+72 at offset %u) runs past the end of the file",
                            (unsigned)dis_at, (unsigned)dis_len, (unsigned)v4 + 72);
        }
    }

    if (!(flags & JR_SKIP_PREVIEWS)) {
        if (ctb_preview(job, d, n, pv_small, 0, "small")) { free_all(job); return -1; }
        if (ctb_preview(job, d, n, pv_large, 1, "large")) { free_all(job); return -1; }
    }

    job->layers = (jr_layer *)calloc(count, sizeof *job->layers);
    if (!job->layers) { free_all(job); return fail(job, "ctb: out of memory for %u layers", (unsigned)count); }
    job->layer_count = count;

    for (i = 0; i < count; i++) {
        const unsigned char *e = d + table + (u64)i * CTB_LAYER_DEF;
        u64 e_off = table + (u64)i * CTB_LAYER_DEF;
        jr_layer *L = &job->layers[i];
        uint32_t addr = le32(e + 12), size = le32(e + 16), page = le32(e + 20), tsize = le32(e + 24);
        u64 abs = (u64)page << 32 | addr;

        L->z_mm = lef(e);
        L->exposure_s = lef(e + 4);
        L->light_off_s = lef(e + 8);
        L->data_offset = abs;
        L->data_size = size;
        if (size == 0)
            return free_all(job), fail(job, "ctb: layer %u: DataSize 0 (table entry at offset %llu)", i, e_off);
        if (!inside(n, abs, size))
            return free_all(job), fail(job, "ctb: layer %u: data [%llu, +%u) (table entry at offset %llu) runs past the end of the file (%zu bytes)",
                                        i, abs, (unsigned)size, e_off, n);
        if (version >= 3) {
            const unsigned char *x;
            uint32_t total;
            if (tsize != CTB_LAYER_DEF_EX)
                return free_all(job), fail(job, "ctb: layer %u: TableSize %u at offset %llu, expected %u for v%u",
                                            i, (unsigned)tsize, e_off + 24, CTB_LAYER_DEF_EX, (unsigned)version);
            if (abs < CTB_LAYER_DEF_EX)
                return free_all(job), fail(job, "ctb: layer %u: no room for the LayerDefEx before data at offset %llu", i, abs);
            x = d + abs - CTB_LAYER_DEF_EX;
            if (memcmp(x, e, CTB_LAYER_DEF) != 0) {
                unsigned k = 0;
                while (k < CTB_LAYER_DEF && x[k] == e[k]) k++;
                return free_all(job), fail(job, "ctb: layer %u: LayerDefEx at offset %llu differs from its table entry at offset %llu (first at byte %u: 0x%02X vs 0x%02X)",
                                            i, abs - CTB_LAYER_DEF_EX, e_off, k, x[k], e[k]);
            }
            total = le32(x + 36);
            if ((u64)total != (u64)size + CTB_LAYER_DEF_EX)
                return free_all(job), fail(job, "ctb: layer %u: LayerDefEx TotalSize %u at offset %llu, expected 84 + %u",
                                            i, (unsigned)total, abs - CTB_LAYER_DEF_EX + 36, (unsigned)size);
            L->lift_mm = lef(x + 40);
            L->lift_speed = lef(x + 44);
            L->lift2_mm = lef(x + 48);
            L->lift2_speed = lef(x + 52);
            L->retract_speed = lef(x + 56);
            L->retract2_mm = lef(x + 60);
            L->retract2_speed = lef(x + 64);
            L->wait_after_cure_s = lef(x + 68);
            L->wait_after_lift_s = lef(x + 72);
            L->wait_before_cure_s = lef(x + 76);
            L->pwm = lef(x + 80);
        } else if (tsize != 0 && tsize != CTB_LAYER_DEF) {
            return free_all(job), fail(job, "ctb: layer %u: TableSize %u at offset %llu, expected 36 for v2", i,
                                        (unsigned)tsize, e_off + 24);
        }
        if (!(flags & JR_SKIP_IMAGES)) {
            L->image = (unsigned char *)malloc((size_t)npix);
            if (!L->image) return free_all(job), fail(job, "ctb: out of memory for layer %u", i);
        }
        if (ctb_decode(job, i, d + abs, size, abs, key, L->image, npix)) { free_all(job); return -1; }
    }
    return 0;
}

int jr_read_ctb(const unsigned char *data, size_t size, jr_job *job)
{
    return jr_read_ctb_ex(data, size, job, 0);
}

/* ------------------------------------------------------- encrypted CTB */

/* Layout: UVtools CTBEncryptedFile.cs @5f33a73e (FileHeader, SlicerSettings,
   ResinParameters, LayerPointer, LayerDef; DecodeInternally), mslicer
   format/ctb_format @ec4374ad. */
#define CTBE_HEADER 48u
#define CTBE_SETTINGS 288u
#define CTBE_POINTER 16u
#define CTBE_LAYER_DEF 88u
#define CTBE_SIGNATURE 32u
#define CTBE_RESIN 40u

/* The key and IV as UVtools publishes them: base64, XORed with "UVtools"
   (CTBEncryptedFile.cs Secret1, Secret2; CryptExtensions.XORCipher). Decoded
   here rather than copied from the writer, so a slip in either shows. */
static size_t ctbe_unveil(const char *b64, unsigned char *out)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    static const char veil[] = "UVtools";
    uint32_t acc = 0;
    int bits = 0;
    size_t n = 0;
    for (; *b64 && *b64 != '='; b64++) {
        acc = acc << 6 | (uint32_t)(strchr(digits, *b64) - digits);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[n] = (unsigned char)((acc >> bits) ^ (unsigned char)veil[n % 7]);
            n++;
        }
    }
    return n;
}

static void ctbe_cipher(unsigned char *data, size_t n, int decrypt)
{
    unsigned char key[33], iv[17];
    aes256 a;
    ctbe_unveil("hQ36XB6yTk+zO02ysyiowt8yC1buK+nbLWyfY40EXoU=", key);
    ctbe_unveil("Wld+ampndVJecmVjYH5cWQ==", iv);
    aes256_init(&a, key);
    if (decrypt) aes256_cbc_decrypt(&a, iv, data, n);
    else aes256_cbc_encrypt(&a, iv, data, n);
}

int jr_ctb_encrypted_settings(const unsigned char *d, size_t n, unsigned char out[CTBE_SETTINGS])
{
    if (!d || n < CTBE_HEADER || le32(d + 4) != CTBE_SETTINGS || !inside(n, le32(d + 8), CTBE_SETTINGS)) return -1;
    memcpy(out, d + le32(d + 8), CTBE_SETTINGS);
    ctbe_cipher(out, CTBE_SETTINGS, 1);
    return 0;
}

int jr_read_ctb_encrypted_ex(const unsigned char *d, size_t n, jr_job *job, unsigned flags)
{
    static const char disclaimer_begins[] = "Layout and record format for the ctb and cbddlp file types";
    unsigned char s[CTBE_SETTINGS], want_sig[CTBE_SIGNATURE], checksum[8];
    uint32_t set_size, set_at, sig_size, sig_at, w, h, count, pointers, name_at, name_len, dis_at, dis_len, key;
    u64 npix;
    unsigned i;

    memset(job, 0, sizeof *job);
    job->format = JR_CTB_ENCRYPTED;
    if (!d) return fail(job, "ctb-encrypted: no data");
    if (n < CTBE_HEADER)
        return fail(job, "ctb-encrypted: file is %zu bytes, shorter than the %u-byte header", n, CTBE_HEADER);
    job->magic = le32(d);
    job->version = le32(d + 16);
    if (job->magic != CTB_MAGIC_ENCRYPTED)
        return fail(job, "ctb-encrypted: magic 0x%08X at offset 0, expected 0x%08X", job->magic, CTB_MAGIC_ENCRYPTED);
    if (job->version != 4 && job->version != 5)
        return fail(job, "ctb-encrypted: version %u at offset 16 not supported (4, 5)", job->version);
    set_size = le32(d + 4);
    set_at = le32(d + 8);
    sig_size = le32(d + 20);
    sig_at = le32(d + 24);
    if (le32(d + 12) || le32(d + 28) || le16(d + 32) != 1 || le16(d + 34) != 1 || le32(d + 36) || le32(d + 40) != 42)
        return fail(job, "ctb-encrypted: header bytes 12-43 are not the constants 0, 0, 1, 1, 0, 42 UVtools writes");
    if (jr_ctb_encrypted_settings(d, n, s))
        return fail(job, "ctb-encrypted: settings [%u, +%u) (header offsets 8/4): expected %u bytes inside the file (%zu bytes)",
                    (unsigned)set_at, (unsigned)set_size, CTBE_SETTINGS, n);

    /* The signature: SHA-256 of the settings' first 8 bytes, enciphered. */
    if (sig_size != CTBE_SIGNATURE || !inside(n, sig_at, sig_size))
        return fail(job, "ctb-encrypted: signature [%u, +%u) (header offsets 24/20): expected %u bytes inside the file (%zu bytes)",
                    (unsigned)sig_at, (unsigned)sig_size, CTBE_SIGNATURE, n);
    memcpy(checksum, s, 8);
    sha256_digest(checksum, 8, want_sig);
    ctbe_cipher(want_sig, CTBE_SIGNATURE, 0);
    if (memcmp(want_sig, d + sig_at, CTBE_SIGNATURE) != 0)
        return fail(job, "ctb-encrypted: the signature at offset %u is not the enciphered SHA-256 of the checksum "
                         "0x%08X%08X (a damaged file or a wrong key)", (unsigned)sig_at, le32(s + 4), le32(s));

    pointers = le32(s + 8);
    job->bed_mm[0] = lef(s + 12);
    job->bed_mm[1] = lef(s + 16);
    job->bed_mm[2] = lef(s + 20);
    job->total_height_mm = lef(s + 32);
    job->layer_height_mm = lef(s + 36);
    job->exposure_s = lef(s + 40);
    job->bottom_exposure_s = lef(s + 44);
    job->light_off_s = lef(s + 48);
    job->bottom_layers = le32(s + 52);
    w = le32(s + 56);
    h = le32(s + 60);
    count = le32(s + 64);
    job->print_time = le32(s + 76);
    job->mirror = (int)le32(s + 80);
    key = le32(s + 128);
    job->ctb_encryption_key = key;
    name_at = le32(s + 160);
    name_len = le32(s + 164);
    job->ctb_aa_flag = s[168];
    job->per_layer_raw = s[171];
    job->per_layer_settings = s[171] != 0;
    job->anti_alias = (int)le32(s + 176);
    job->ctb_transition_layers = le32(s + 188);
    job->ctb_v4_last_layer_index = le32(s + 244);
    dis_at = le32(s + 264);
    dis_len = le32(s + 268);
    job->ctb_v4_disclaimer_length = dis_len;
    if (count == 0) return fail(job, "ctb-encrypted: LayerCount (settings+64) is 0");
    if (!inside(n, pointers, (u64)count * CTBE_POINTER))
        return fail(job, "ctb-encrypted: layer pointers at offset %u (%u of %u bytes, settings+8/+64) run past the end of the file (%zu bytes)",
                    (unsigned)pointers, (unsigned)count, CTBE_POINTER, n);
    if (check_dims(job, "ctb-encrypted", w, h, count, flags, set_at + 56)) return -1;
    job->width = (int)w;
    job->height = (int)h;
    npix = (u64)w * h;
    if (!inside(n, name_at, name_len))
        return fail(job, "ctb-encrypted: machine name [%u, +%u) (settings+160) runs past the end of the file",
                    (unsigned)name_at, (unsigned)name_len);
    copy_name(job->machine_name, sizeof job->machine_name, d + name_at, name_len);
    if (dis_len != 320 || !inside(n, dis_at, dis_len) ||
        memcmp(d + dis_at, disclaimer_begins, sizeof disclaimer_begins - 1) != 0)
        return fail(job, "ctb-encrypted: no 320-byte disclaimer at offset %u (settings+264/+268 say %u bytes)",
                    (unsigned)dis_at, (unsigned)dis_len);
    if (job->version >= 5) {
        uint32_t resin = le32(s + 276), m_at, m_len;
        if (!inside(n, resin, CTBE_RESIN))
            return fail(job, "ctb-encrypted: v5 resin parameters at offset %u (settings+276) run past the end of the file",
                        (unsigned)resin);
        m_at = le32(d + resin + 8);
        m_len = le32(d + resin + 28);
        if (!inside(n, le32(d + resin + 16), le32(d + resin + 12)) || !inside(n, le32(d + resin + 24), le32(d + resin + 20)) ||
            !inside(n, m_at, m_len) || m_len != name_len || memcmp(d + m_at, d + name_at, m_len) != 0)
            return fail(job, "ctb-encrypted: the resin parameters at offset %u: a string outside the file, or a machine name "
                             "other than the settings'", (unsigned)resin);
    }

    if (!(flags & JR_SKIP_PREVIEWS)) {
        if (ctb_preview(job, d, n, le32(s + 72), 0, "small")) { free_all(job); return -1; }
        if (ctb_preview(job, d, n, le32(s + 68), 1, "large")) { free_all(job); return -1; }
    }

    job->layers = (jr_layer *)calloc(count, sizeof *job->layers);
    if (!job->layers) { free_all(job); return fail(job, "ctb-encrypted: out of memory for %u layers", (unsigned)count); }
    job->layer_count = count;
    for (i = 0; i < count; i++) {
        const unsigned char *p = d + pointers + (u64)i * CTBE_POINTER, *x;
        u64 p_off = pointers + (u64)i * CTBE_POINTER, at = (u64)le32(p + 4) << 32 | le32(p), data_at;
        jr_layer *L = &job->layers[i];
        uint32_t size, secret_at, secret_len;
        unsigned char *clear = NULL;
        int bad;
        if (le32(p + 8) != CTBE_LAYER_DEF || le32(p + 12) != 0)
            return free_all(job), fail(job, "ctb-encrypted: layer %u: pointer at offset %llu has table size %u (expected 88) and padding %u",
                                        i, p_off, (unsigned)le32(p + 8), (unsigned)le32(p + 12));
        if (!inside(n, at, CTBE_LAYER_DEF))
            return free_all(job), fail(job, "ctb-encrypted: layer %u: LayerDef at %llu (pointer at offset %llu) runs past the end of the file",
                                        i, at, p_off);
        x = d + at;
        data_at = (u64)le32(x + 20) << 32 | le32(x + 16);
        size = le32(x + 24);
        secret_at = le32(x + 32);
        secret_len = le32(x + 36);
        /* UVtools reads the data right after the LayerDef, mslicer at its offset: they must agree */
        if (le32(x) != CTBE_LAYER_DEF || data_at != at + CTBE_LAYER_DEF)
            return free_all(job), fail(job, "ctb-encrypted: layer %u: LayerDef at offset %llu has TableSize %u and data at %llu, "
                                             "expected 88 and %llu", i, at, (unsigned)le32(x), data_at, at + CTBE_LAYER_DEF);
        if (size == 0 || !inside(n, data_at, size))
            return free_all(job), fail(job, "ctb-encrypted: layer %u: data [%llu, +%u) (LayerDef at offset %llu) is empty or runs past the end of the file",
                                        i, data_at, (unsigned)size, at);
        L->z_mm = lef(x + 4);
        L->exposure_s = lef(x + 8);
        L->light_off_s = lef(x + 12);
        L->lift_mm = lef(x + 40);
        L->lift_speed = lef(x + 44);
        L->lift2_mm = lef(x + 48);
        L->lift2_speed = lef(x + 52);
        L->retract_speed = lef(x + 56);
        L->retract2_mm = lef(x + 60);
        L->retract2_speed = lef(x + 64);
        L->wait_after_cure_s = lef(x + 68);
        L->wait_after_lift_s = lef(x + 72);
        L->wait_before_cure_s = lef(x + 76);
        L->pwm = lef(x + 80);
        L->data_offset = data_at;
        L->data_size = size;
        /* ChiTuBox may AES-encipher a span of the code; UVtools deciphers it before the key stream */
        if (secret_len) {
            if (secret_len % 16 || !inside(size, secret_at, secret_len))
                return free_all(job), fail(job, "ctb-encrypted: layer %u: enciphered span [%u, +%u) (LayerDef+32 at offset %llu) "
                                                 "is not whole blocks inside its %u bytes", i, (unsigned)secret_at,
                                            (unsigned)secret_len, at + 32, (unsigned)size);
            if (!(clear = (unsigned char *)malloc(size))) return free_all(job), fail(job, "ctb-encrypted: out of memory");
            memcpy(clear, d + data_at, size);
            ctbe_cipher(clear + secret_at, secret_len, 1);
        }
        if (!(flags & JR_SKIP_IMAGES) && !(L->image = (unsigned char *)malloc((size_t)npix))) {
            free(clear);
            return free_all(job), fail(job, "ctb-encrypted: out of memory for layer %u", i);
        }
        bad = ctb_decode(job, i, clear ? clear : d + data_at, size, data_at, key, L->image, npix);
        free(clear);
        if (bad) { free_all(job); return -1; }
    }
    return 0;
}

int jr_read_ctb_encrypted(const unsigned char *data, size_t size, jr_job *job)
{
    return jr_read_ctb_encrypted_ex(data, size, job, 0);
}

/* ------------------------------------------------------------------ GOO */

#define GOO_HEADER 195477u
#define GOO_SMALL 194u
#define GOO_SMALL_DELIM 27106u
#define GOO_BIG 27108u
#define GOO_BIG_DELIM 195308u
#define GOO_LAYER_DEF 70u
#define GOO_ENDING 11u

static const unsigned char goo_magic[8] = {0x07, 0x00, 0x00, 0x00, 0x44, 0x4C, 0x50, 0x00};
static const unsigned char goo_ending[GOO_ENDING] = {0x00, 0x00, 0x00, 0x07, 0x00, 0x00,
                                                     0x00, 0x44, 0x4C, 0x50, 0x00};

static int goo_preview(jr_job *job, const unsigned char *d, u64 off, int side, int slot)
{
    u64 npix = (u64)side * side, i;
    unsigned char *rgb = (unsigned char *)malloc((size_t)npix * 3);
    if (!rgb) return fail(job, "goo: out of memory for a preview");
    for (i = 0; i < npix; i++) {
        uint32_t v = be16(d + off + 2 * i);
        rgb[i * 3] = (unsigned char)((v >> 11) << 3);
        rgb[i * 3 + 1] = (unsigned char)(((v >> 5) & 0x3F) << 2);
        rgb[i * 3 + 2] = (unsigned char)((v & 0x1F) << 3);
    }
    job->preview_w[slot] = job->preview_h[slot] = side;
    job->preview_rgb[slot] = rgb;
    return 0;
}

/* Chunks: byte0[7:6] 00 zeros, 01 grey (next byte), 11 0xFF, with
   byte0[5:4] = 0..3 extra length bytes (run = b1.. << .. | b0[3:0]);
   10 diff: bit5 sign, bit4 run byte follows, b0[3:0] |diff|. */
static int goo_decode(jr_job *job, unsigned layer, const unsigned char *p, size_t len, u64 base,
                      unsigned char *out, u64 npix)
{
    size_t i = 0;
    u64 px = 0;
    int color = 0;
    while (i < len) {
        size_t at = i;
        unsigned b0 = p[i++], type = b0 >> 6;
        u64 run;
        if (px == npix)
            return fail(job, "goo: layer %u: %llu chunk bytes left at offset %llu after the image is complete",
                        layer, (u64)(len - at), base + at);
        if (type == 2) {
            int diff = (int)(b0 & 0x0F);
            job->layers[layer].diff_chunks++;
            if (b0 & 0x20) diff = -diff;
            if (b0 & 0x10) {
                if (i >= len)
                    return fail(job, "goo: layer %u: diff chunk at offset %llu has no run byte", layer, base + at);
                run = p[i++];
            } else {
                run = 1;
            }
            color += diff;
            if (color < 0 || color > 255)
                return fail(job, "goo: layer %u: diff chunk 0x%02X at offset %llu takes the value to %d", layer,
                            b0, base + at, color);
        } else {
            unsigned nlen = (b0 >> 4) & 3, k;
            if (type == 1) {
                unsigned v;
                if (i >= len)
                    return fail(job, "goo: layer %u: grey chunk at offset %llu has no value byte", layer, base + at);
                v = p[i++];
                if (v == 0 || v == 255)
                    return fail(job, "goo: layer %u: grey chunk at offset %llu holds 0x%02X (must be 0x01-0xFE)",
                                layer, base + at, v);
                color = (int)v;
            } else {
                color = type == 0 ? 0 : 255;
            }
            if (len - i < nlen)
                return fail(job, "goo: layer %u: run length of chunk at offset %llu is cut off by the checksum",
                            layer, base + at);
            run = b0 & 0x0F;
            for (k = 0; k < nlen; k++) run |= (u64)p[i + k] << (4 + 8 * (nlen - 1 - k));
            i += nlen;
        }
        if (run == 0)
            return fail(job, "goo: layer %u: zero-length run at offset %llu", layer, base + at);
        if (run > npix - px)
            return fail(job, "goo: layer %u: run of %llu at offset %llu overruns the image (pixel %llu of %llu)",
                        layer, run, base + at, px, npix);
        if (out) memset(out + px, color, (size_t)run);
        px += run;
    }
    if (px != npix)
        return fail(job, "goo: layer %u: chunks at offset %llu (%zu bytes) decode to %llu of %llu pixels",
                    layer, base, len, px, npix);
    return 0;
}

static int goo_bool(jr_job *job, const unsigned char *d, unsigned off, const char *what)
{
    if (d[off] > 1) return fail(job, "goo: %s at offset %u is %u, not 0 or 1", what, off, d[off]);
    return 0;
}

int jr_read_goo_ex(const unsigned char *d, size_t n, jr_job *job, unsigned flags)
{
    uint32_t count, w, h, lda;
    u64 npix, off, max_layers;
    unsigned i;

    memset(job, 0, sizeof *job);
    job->format = JR_GOO;
    if (!d) return fail(job, "goo: no data");
    if (n < (size_t)GOO_HEADER + GOO_ENDING)
        return fail(job, "goo: file is %zu bytes, shorter than the %u-byte header and %u-byte ending", n,
                    GOO_HEADER, GOO_ENDING);
    if (memcmp(d, "V3.0", 4) != 0) return fail(job, "goo: version at offset 0 is not \"V3.0\"");
    if (memcmp(d + 4, goo_magic, 8) != 0) return fail(job, "goo: magic at offset 4 is not 07 00 00 00 44 4C 50 00");
    if (d[GOO_SMALL_DELIM] != 0x0D || d[GOO_SMALL_DELIM + 1] != 0x0A)
        return fail(job, "goo: no 0D 0A after the small preview at offset %u", GOO_SMALL_DELIM);
    if (d[GOO_BIG_DELIM] != 0x0D || d[GOO_BIG_DELIM + 1] != 0x0A)
        return fail(job, "goo: no 0D 0A after the big preview at offset %u", GOO_BIG_DELIM);
    job->version = 3;
    copy_name(job->machine_name, sizeof job->machine_name, d + 92, 32);
    job->anti_alias = (int)be16(d + 188);
    count = be32(d + 195310);
    w = be16(d + 195314);
    h = be16(d + 195316);
    if (goo_bool(job, d, 195318, "MirrorX") || goo_bool(job, d, 195319, "MirrorY") ||
        goo_bool(job, d, 195340, "DelayMode") || goo_bool(job, d, 195445, "advance mode") ||
        goo_bool(job, d, 195474, "GrayScaleLevel"))
        return -1;
    job->mirror = d[195318] | d[195319] << 1;
    job->bed_mm[0] = bef(d + 195320);
    job->bed_mm[1] = bef(d + 195324);
    job->bed_mm[2] = bef(d + 195328);
    job->layer_height_mm = bef(d + 195332);
    job->exposure_s = bef(d + 195336);
    job->goo_delay_mode = d[195340];
    job->light_off_s = bef(d + 195341);
    job->bottom_exposure_s = bef(d + 195369);
    job->bottom_layers = be32(d + 195373);
    job->per_layer_raw = d[195445];
    job->per_layer_settings = d[195445] != 0;
    job->print_time = be32(d + 195446);
    lda = be32(d + 195470);
    job->goo_grey_scale_level = d[195474];
    job->ctb_transition_layers = be16(d + 195475);
    if (lda != GOO_HEADER)
        return fail(job, "goo: LayerDefAddress at offset 195470 is %u, expected %u", (unsigned)lda, GOO_HEADER);
    if (count == 0) return fail(job, "goo: LayerCount at offset 195310 is 0");
    /* Each layer takes at least 70 + 3 + 2 bytes. */
    max_layers = ((u64)n - GOO_HEADER - GOO_ENDING) / (GOO_LAYER_DEF + 3 + 2);
    if (count > max_layers)
        return fail(job, "goo: LayerCount %u at offset 195310 cannot fit in %zu bytes", (unsigned)count, n);
    if (check_dims(job, "goo", w, h, count, flags, 195314)) return -1;
    job->width = (int)w;
    job->height = (int)h;
    npix = (u64)w * h;

    if (!(flags & JR_SKIP_PREVIEWS)) {
        if (goo_preview(job, d, GOO_SMALL, 116, 0) || goo_preview(job, d, GOO_BIG, 290, 1)) {
            free_all(job);
            return -1;
        }
    }

    job->layers = (jr_layer *)calloc(count, sizeof *job->layers);
    if (!job->layers) { free_all(job); return fail(job, "goo: out of memory for %u layers", (unsigned)count); }
    job->layer_count = count;

    off = GOO_HEADER;
    for (i = 0; i < count; i++) {
        jr_layer *L = &job->layers[i];
        const unsigned char *e, *data;
        uint32_t dl, pause;
        unsigned sum = 0, want;
        u64 k;
        if (!inside(n, off, GOO_LAYER_DEF))
            return free_all(job), fail(job, "goo: layer %u: definition at offset %llu runs past the end of the file (%zu bytes)",
                                        i, off, n);
        e = d + off;
        pause = be16(e);
        if (pause > 1)
            return free_all(job), fail(job, "goo: layer %u: pause flag %u at offset %llu, not 0 or 1", i,
                                        (unsigned)pause, off);
        L->pause = (int)pause;
        L->z_mm = bef(e + 6);
        L->exposure_s = bef(e + 10);
        L->light_off_s = bef(e + 14);
        L->wait_after_cure_s = bef(e + 18);
        L->wait_after_lift_s = bef(e + 22);
        L->wait_before_cure_s = bef(e + 26);
        L->lift_mm = bef(e + 30);
        L->lift_speed = bef(e + 34);
        L->lift2_mm = bef(e + 38);
        L->lift2_speed = bef(e + 42);
        L->retract_mm = bef(e + 46);
        L->retract_speed = bef(e + 50);
        L->retract2_mm = bef(e + 54);
        L->retract2_speed = bef(e + 58);
        L->pwm = (double)be16(e + 62);
        if (e[64] != 0x0D || e[65] != 0x0A)
            return free_all(job), fail(job, "goo: layer %u: no 0D 0A at offset %llu (definition+64)", i, off + 64);
        dl = be32(e + 66);
        L->data_offset = off + GOO_LAYER_DEF;
        L->data_size = dl;
        if (dl < 3)
            return free_all(job), fail(job, "goo: layer %u: DataLength %u at offset %llu is too small (0x55, chunks, checksum)",
                                        i, (unsigned)dl, off + 66);
        if (!inside(n, off + GOO_LAYER_DEF, (u64)dl + 2))
            return free_all(job), fail(job, "goo: layer %u: data [%llu, +%u) and its 0D 0A (DataLength at offset %llu) run past the end of the file (%zu bytes)",
                                        i, off + GOO_LAYER_DEF, (unsigned)dl, off + 66, n);
        data = e + GOO_LAYER_DEF;
        if (data[0] != 0x55)
            return free_all(job), fail(job, "goo: layer %u: image data at offset %llu starts with 0x%02X, not 0x55", i,
                                        off + GOO_LAYER_DEF, data[0]);
        for (k = 1; k + 1 < dl; k++) sum += data[k];
        want = (~sum) & 0xFF;
        L->checksum = data[dl - 1];
        if (data[dl - 1] != want)
            return free_all(job), fail(job, "goo: layer %u: checksum 0x%02X at offset %llu, expected 0x%02X (NOT of the sum of [%llu, +%u))",
                                        i, data[dl - 1], off + GOO_LAYER_DEF + dl - 1, want, off + GOO_LAYER_DEF + 1,
                                        (unsigned)dl - 2);
        if (data[dl] != 0x0D || data[dl + 1] != 0x0A)
            return free_all(job), fail(job, "goo: layer %u: no 0D 0A after the image data at offset %llu", i,
                                        off + GOO_LAYER_DEF + dl);
        if (!(flags & JR_SKIP_IMAGES)) {
            L->image = (unsigned char *)malloc((size_t)npix);
            if (!L->image) return free_all(job), fail(job, "goo: out of memory for layer %u", i);
        }
        if (goo_decode(job, i, data + 1, dl - 2, off + GOO_LAYER_DEF + 1, L->image, npix)) {
            free_all(job);
            return -1;
        }
        off += GOO_LAYER_DEF + (u64)dl + 2;
    }
    if (!inside(n, off, GOO_ENDING))
        return free_all(job), fail(job, "goo: the %u-byte ending string at offset %llu runs past the end of the file (%zu bytes)",
                                    GOO_ENDING, off, n);
    if (memcmp(d + off, goo_ending, GOO_ENDING) != 0)
        return free_all(job), fail(job, "goo: bytes at offset %llu are not the ending 00 00 00 07 00 00 00 44 4C 50 00", off);
    if (off + GOO_ENDING != n)
        return free_all(job), fail(job, "goo: %llu bytes after the ending string at offset %llu", (u64)n - off - GOO_ENDING,
                                    off + GOO_ENDING);
    return 0;
}

int jr_read_goo(const unsigned char *data, size_t size, jr_job *job)
{
    return jr_read_goo_ex(data, size, job, 0);
}
