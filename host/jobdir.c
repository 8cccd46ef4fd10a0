/* The job directory: see jobdir.h. */
#include "jobdir.h"
#include "output.h"
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* JOBDIR/layer_00001.EXT: five digits, more if the plan has 100,000 layers or more. */
int layer_digits(size_t layers)
{
    int digits = 5;
    for (; layers >= 100000 && digits < 20; layers /= 10) digits++;
    return digits;
}

/* "layer_00001.EXT" */
void layer_name(char name[40], size_t k, int digits, const char *ext)
{
    char number[24];
    int n = 0, i;
    size_t v = k + 1;
    do { number[n++] = (char)('0' + (int)(v % 10)); v /= 10; } while (v && n < 20);
    while (n < digits && n < 20) number[n++] = '0';
    for (i = 0; i < n / 2; i++) { char t = number[i]; number[i] = number[n - 1 - i]; number[n - 1 - i] = t; }
    number[n] = 0;
    snprintf(name, 40, "layer_%s.%s", number, ext);
}

void layer_path(char *path, size_t size, const char *dir, size_t k, int digits, const char *ext)
{
    char name[40];
    layer_name(name, k, digits, ext);
    snprintf(path, size, "%s/%s", dir, name);
}

static void write_manifest(FILE *f, const void *ctx)
{
    const job_manifest *m = (const job_manifest *)ctx;
    const slice_args *s = m->s;
    const adaslice_plan *p = &m->j->plan[m->a->method];
    size_t k;
    fputs("{\n  \"format\": \"adaslice-job\",\n  \"version\": ", f);
    json_string(f, ADASLICE_VERSION);
    fputs(",\n  \"complete\": true,\n  \"model\": ", f);
    json_string(f, m->a->model);
    fputs(",\n  \"printer\": {\"name\": ", f);
    if (s->preset) json_string(f, s->preset->name); else fputs("null", f);
    fprintf(f, ", \"width_px\": %d, \"height_px\": %d, \"pitch_mm\": ", (s->rotate & 1) ? s->height : s->width,
            (s->rotate & 1) ? s->width : s->height);
    json_number(f, s->pitch);
    fprintf(f, ", \"mirror\": \"%s\", \"rotate\": %s},\n", MIRRORS[s->mirror_x | (s->mirror_y << 1)], ROTATIONS[s->rotate]);
    fprintf(f, "  \"mask\": {\"bits\": %d, \"supersample\": %d, \"slice_at\": \"%s\"},\n",
            s->supersample > 1 ? 8 : 1, s->supersample, SLICE_AT[s->slice_at]);
    fputs("  \"part_mm\": [", f);
    for (k = 0; k < 3; k++) { if (k) fputs(", ", f); json_number(f, m->part[k]); }
    fputs("],\n  \"place_mm\": [", f);
    json_number(f, s->place[0]);
    fputs(", ", f);
    json_number(f, s->place[1]);
    fprintf(f, "],\n  \"metric\": \"%s\",\n  \"method\": \"%s\",\n  \"eps\": ", METRIC_NAMES[m->a->metric],
            METHOD_NAMES[m->a->method]);
    json_number(f, p->eps);
    fprintf(f, ",\n  \"layer_count\": %zu,\n  \"layers\": [", m->count);
    for (k = 0; k < m->count; k++) {
        const job_layer *l = &m->layers[k];
        char name[40];
        layer_name(name, k, m->digits, "png");
        fprintf(f, "%s\n    {\"index\": %zu, \"file\": \"%s\", \"z_bottom\": ", k ? "," : "", k + 1, name);
        json_number(f, l->z_bottom);
        fputs(", \"z_top\": ", f);
        json_number(f, l->z_top);
        fputs(", \"thickness\": ", f);
        json_number(f, l->thickness);
        fputs(", \"lit_area_mm2\": ", f);
        json_number(f, l->lit_mm2);
        fputc('}', f);
    }
    fputs("\n  ]\n}\n", f);
}


/* DIR/NAME, malloc'd; NULL after a complaint. */
static char *dir_file(const char *dir, const char *name)
{
    size_t n = strlen(dir) + strlen(name) + 2;
    char *path = (char *)malloc(n);
    if (!path) complain(RC_FAIL, "out of memory");
    else snprintf(path, n, "%s/%s", dir, name);
    return path;
}

int jobdir_write_manifest(const char *dir, const job_manifest *m)
{
    char *path = dir_file(dir, "manifest.json");
    int rc = path ? write_atomic(path, write_manifest, m) : RC_FAIL;
    free(path);
    return rc;
}

int job_masks_alloc(job_masks *m, uint32_t layers)
{
    size_t n = layers ? layers : 1;
    m->layers = layers;
    m->lengths = (uint32_t *)calloc(n, sizeof *m->lengths);
    m->codes = (unsigned char **)calloc(n, sizeof *m->codes);
    m->sizes = (size_t *)calloc(n, sizeof *m->sizes);
    m->crcs = (uint32_t *)calloc(n, sizeof *m->crcs);
    return m->lengths && m->codes && m->sizes && m->crcs ? RC_OK : complain(RC_FAIL, "out of memory for %u layers", layers);
}

void job_masks_free(job_masks *m)
{
    uint32_t k;
    for (k = 0; !m->file && m->codes && k < m->layers; k++) free(m->codes[k]);
    free(m->lengths);
    free(m->codes);
    free(m->sizes);
    free(m->crcs);
    free(m->file);
    memset(m, 0, sizeof *m);
}

static void put_u32(FILE *f, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    fwrite(b, 1, 4, f);
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void write_mask_file(FILE *f, const void *ctx)
{
    const job_masks *m = (const job_masks *)ctx;
    uint32_t k;
    fwrite("ADASMSK1", 1, 8, f);
    put_u32(f, m->width);
    put_u32(f, m->height);
    put_u32(f, m->bits);
    put_u32(f, m->layers);
    put_u32(f, m->bin_nm);
    for (k = 0; k < m->layers; k++) {
        put_u32(f, m->lengths[k]);
        put_u32(f, m->crcs[k]);
        put_u32(f, (uint32_t)m->sizes[k]);
        fwrite(m->codes[k], 1, m->sizes[k], f);
    }
}

int jobdir_write_masks(const char *dir, const job_masks *m, double bin_mm)
{
    char *path = dir_file(dir, "masks.rle");
    double nm = bin_mm * 1e6;
    job_masks out = *m;
    int rc = RC_OK;
    if (!path) return RC_FAIL;
    out.bin_nm = (uint32_t)(nm + 0.5);
    if (fabs(nm - out.bin_nm) > 1e-6 * nm) remove(path);
    else rc = write_atomic(path, write_mask_file, &out);
    free(path);
    return rc;
}

int jobdir_read_masks(const char *dir, job_masks *m)
{
    char *path = dir_file(dir, "masks.rle");
    size_t at;
    uint32_t k;
    FILE *f;
    long size;
    int rc = RC_FAIL;
    memset(m, 0, sizeof *m);
    if (!path) return RC_FAIL;
    if (!(f = fopen(path, "rb"))) {
        complain(RC_FAIL, "cannot open %s: %s (was the job written by adaslice slice?)", path, strerror(errno));
        goto done;
    }
    if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0 ||
        !(m->file = (unsigned char *)malloc((size_t)size + 1)) || fread(m->file, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        complain(RC_FAIL, "cannot read %s", path);
        goto done;
    }
    fclose(f);
    m->file_size = (size_t)size;
    if (m->file_size < 28 || memcmp(m->file, "ADASMSK1", 8)) {
        complain(RC_FAIL, "%s: not an adaslice mask file (bad magic at byte 0)", path);
        goto done;
    }
    m->width = get_u32(m->file + 8);
    m->height = get_u32(m->file + 12);
    m->bits = get_u32(m->file + 16);
    k = get_u32(m->file + 20);
    m->bin_nm = get_u32(m->file + 24);
    if (!k || k > m->file_size / 12 || !m->bin_nm) {
        complain(RC_FAIL, "%s: byte 20: %u layers of %u nm do not fit the file", path, k, m->bin_nm);
        goto done;
    }
    if (job_masks_alloc(m, k)) goto done;
    for (at = 28, k = 0; k < m->layers; k++) {
        uint32_t code;
        if (m->file_size - at < 12 || (code = get_u32(m->file + at + 8)) > m->file_size - at - 12) {
            complain(RC_FAIL, "%s: byte %zu: layer %u runs past the end of the file", path, at, k + 1);
            goto done;
        }
        m->lengths[k] = get_u32(m->file + at);
        m->crcs[k] = get_u32(m->file + at + 4);
        m->sizes[k] = code;
        m->codes[k] = m->file + at + 12;
        at += 12 + code;
    }
    if (at != m->file_size) {
        complain(RC_FAIL, "%s: byte %zu: %zu bytes after the last layer", path, at, m->file_size - at);
        goto done;
    }
    rc = RC_OK;
done:
    if (rc) job_masks_free(m);
    free(path);
    return rc;
}
