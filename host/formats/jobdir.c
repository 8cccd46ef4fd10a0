/* The job directory: see jobdir.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "../bytes.h"
#include "../cure.h"
#include "../json.h"
#include "jobdir.h"
#include "jobfile.h"
#include "../layers.h"
#include "../output.h"
#include "../codec/png.h"
#include "../report.h"

#include <errno.h>
#include <dirent.h>
#include <pthread.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* ------------------------------------------------------------ writing */

typedef struct dir_writer {
    const job_desc *d;
    char *dir, *path;            /* the job; room for a file's path in it */
    size_t path_size;
    int digits;
    job_masks masks;
    int whole_bin;               /* the bin is a whole number of nanometres: masks.rle is written */
    FILE *masks_file;            /* masks.rle, written as the layers are put */
    char *masks_path;
    int has_masks;               /* masks.rle written, its CRC-32 below (the manifest names it) */
    uint32_t masks_crc;
    int created;                 /* the directory is this job's: removed with it */
    int writing;                 /* the earlier job is gone: a failure removes this one's files */
    /* the manifest's layers, a line each, written as they are put (by
       whichever thread puts them, while others code): at the end, alone on
       one core, they took 5 ms of the turbine blade's job */
    FILE *lines_file;            /* into lines (open_memstream) */
    char *lines;
    size_t lines_size, *line_end;
    int lines_failed;            /* a line was not written whole: out of memory */
    json_writer lines_json;
} dir_writer;

/* Every file of the job in the directory but its manifest: the caller's
   (plan.csv, plot.svg, layer SVGs), masks.rle, preview.png, the layers. */
static void own_files(const dir_writer *w, void (*fn)(void *ctx, const char *name), void *ctx)
{
    const job_desc *d = w->d;
    char name[40];
    size_t k;
    if (d->dir_extras & DIR_PLAN_CSV) fn(ctx, "plan.csv");
    if (d->dir_extras & DIR_PLOT_SVG) fn(ctx, "plot.svg");
    if (w->whole_bin) fn(ctx, "masks.rle");
    if (d->preview) fn(ctx, "preview.png");
    for (k = 0; k < d->layer_count; k++) {
        layer_name(name, k, w->digits, "png");
        fn(ctx, name);
        if (d->dir_extras & DIR_LAYER_SVGS) {
            layer_name(name, k, w->digits, "svg");
            fn(ctx, name);
        }
    }
}

static void list_file(void *ctx, const char *name) { json_string((json_writer *)ctx, NULL, name); }

static void write_manifest(FILE *f, const void *ctx)
{
    const dir_writer *dw = (const dir_writer *)ctx;
    const job_desc *d = dw->d;
    json_writer w;
    char crc[9];
    size_t k;
    json_init(&w, f);
    json_begin_object(&w, NULL, 0);
    json_string(&w, "format", "adaslice-job");
    json_string(&w, "version", ADASLICE_VERSION);
    json_bool(&w, "complete", 1);
    json_string(&w, "model", d->model);
    json_begin_object(&w, "printer", 1);
    json_string(&w, "name", d->preset ? d->preset->name : NULL);
    json_int(&w, "width_px", d->width);
    json_int(&w, "height_px", d->height);
    json_numbers(&w, "pitch_mm", d->pitch, 2);
    json_string(&w, "mirror", MIRRORS[d->mirror_x | (d->mirror_y << 1)]);
    json_int(&w, "rotate", 90 * d->rotate);
    json_end(&w);
    json_begin_object(&w, "mask", 1);
    json_int(&w, "bits", d->bits);
    json_int(&w, "supersample", d->supersample);
    json_string(&w, "slice_at", d->slice_at);
    json_end(&w);
    json_numbers(&w, "part_mm", d->part_mm, 3);
    json_numbers(&w, "place_mm", d->place_mm, 2);
    json_string(&w, "metric", d->metric);
    json_string(&w, "method", d->method);
    json_number(&w, "eps", d->eps);
    json_begin_object(&w, "working_curve", 1);
    json_number(&w, "seconds", d->cure[0]);
    json_number(&w, "thickness_mm", d->cure[1]);
    if (d->cure[2] > 0) json_number(&w, "penetration_mm", d->cure[2]);
    else json_null(&w, "penetration_mm");
    json_end(&w);
    json_int(&w, "bottom_layers", d->bottom_layers);
    json_number(&w, "bottom_exposure_s", d->bottom_exposure_s);
    json_begin_object(&w, "motion", 1);
    json_number(&w, "peel_mm", d->motion.lift_mm);
    json_number(&w, "peel_speed_mm_s", d->motion.lift_speed);
    json_number(&w, "return_speed_mm_s", d->motion.retract_speed);
    json_number(&w, "settle_s", d->motion.wait_before_cure_s);
    json_end(&w);
    json_number(&w, "print_time_s", d->print_time_s);
    json_number(&w, "volume_mm3", d->volume_mm3);
    /* plan --json's repair.volume_mm3 closes an open mesh otherwise: say which this is */
    json_string(&w, "volume_of", "the resin: each mask's lit area times its layer's thickness");
    snprintf(crc, sizeof crc, "%08x", (unsigned)dw->masks_crc);
    json_string(&w, "masks_rle_crc32", dw->has_masks ? crc : NULL);
    /* what a later slice into this directory removes, and nothing else */
    json_begin_array(&w, "files", 0);
    own_files(dw, list_file, &w);
    json_end(&w);
    json_int(&w, "layer_count", (long long)d->layer_count);
    json_begin_array(&w, "layers", 0);
    for (k = 0; k < d->layer_count; k++) { /* each line but its '\n' */
        size_t start = k ? dw->line_end[k - 1] : 0;
        json_raw(&w, NULL, dw->lines + start, dw->line_end[k] - start - 1);
    }
    json_end(&w);
    json_end(&w);
}

/* Layer k's line of the manifest's layers: {...}\n. */
static void manifest_line(dir_writer *w, size_t k)
{
    const job_layer *l = &w->d->layers[k];
    json_writer *j = &w->lines_json;
    char name[40];
    long at;
    layer_name(name, k, w->digits, "png");
    json_begin_object(j, NULL, 1);
    json_int(j, "index", (long long)k + 1);
    json_string(j, "file", name);
    json_number(j, "z_bottom", l->z_bottom);
    json_number(j, "z_top", l->z_top);
    json_number(j, "thickness", l->thickness);
    json_number(j, "exposure_s", l->exposure_s);
    json_number(j, "lit_area_mm2", l->lit_mm2);
    json_end(j);
    at = ftell(w->lines_file);
    w->line_end[k] = at > 0 ? (size_t)at : 0;
    w->lines_failed |= j->failed || at <= 0 || (k && w->line_end[k] <= w->line_end[k - 1]);
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

int job_masks_alloc(job_masks *m, uint32_t layers)
{
    size_t n = layers ? layers : 1;
    m->layers = layers;
    m->lengths = (uint32_t *)calloc(n, sizeof *m->lengths);
    m->exposure_ms = (uint32_t *)calloc(n, sizeof *m->exposure_ms);
    m->codes = (unsigned char **)calloc(n, sizeof *m->codes);
    m->sizes = (size_t *)calloc(n, sizeof *m->sizes);
    m->crcs = (uint32_t *)calloc(n, sizeof *m->crcs);
    return m->lengths && m->exposure_ms && m->codes && m->sizes && m->crcs
               ? RC_OK
               : complain(RC_FAIL, "out of memory for %u layer%s", layers, plural(layers));
}

void job_masks_free(job_masks *m)
{
    uint32_t k;
    for (k = 0; !m->file && m->codes && k < m->layers; k++) free(m->codes[k]);
    free(m->lengths);
    free(m->exposure_ms);
    free(m->codes);
    free(m->sizes);
    free(m->crcs);
    free(m->file);
    memset(m, 0, sizeof *m);
}

/* masks.rle's bytes go to the file and into the CRC the manifest keeps of it */
static void masks_out(dir_writer *w, const void *bytes, size_t n)
{
    if (!n) return;
    fwrite(bytes, 1, n, w->masks_file);
    w->masks_crc = adaslice_crc32(w->masks_crc, bytes, n);
}

static void masks_u32(dir_writer *w, uint32_t v)
{
    unsigned char b[4];
    put_le32(b, v);
    masks_out(w, b, 4);
}

#define MASKS_HEADER 44   /* magic and nine u32 */
#define MASKS_LAYER 16    /* bins, exposure, CRC, code bytes */

static void emit_masks_header(dir_writer *w)
{
    const job_masks *m = &w->masks;
    masks_out(w, "ADASMSK2", 8);
    masks_u32(w, m->width);
    masks_u32(w, m->height);
    masks_u32(w, m->bits);
    masks_u32(w, m->layers);
    masks_u32(w, m->bin_nm);
    masks_u32(w, m->peel_nm);
    masks_u32(w, m->peel_speed_um_s);
    masks_u32(w, m->return_speed_um_s);
    masks_u32(w, m->settle_ms);
}

static void emit_masks_layer(dir_writer *w, uint32_t k, const unsigned char *code)
{
    const job_masks *m = &w->masks;
    masks_u32(w, m->lengths[k]);
    masks_u32(w, m->exposure_ms[k]);
    masks_u32(w, m->crcs[k]);
    masks_u32(w, (uint32_t)m->sizes[k]);
    masks_out(w, code, m->sizes[k]);
}

static uint32_t milli(double v) { return (uint32_t)(v * 1000 + 0.5); }

static int dir_close(void *writer, int ok);

/* The files a job writes besides its layers and manifest.json (some jobs
   fewer), and those a manifest from before its "files" list had. */
static const char *const JOB_EXTRAS[] = {"masks.rle", "preview.png", "plan.csv", "plot.svg"};

int jobdir_file_name(const char *name)
{
    size_t k;
    if (!strcmp(name, "manifest.json")) return 1;
    for (k = 0; k < sizeof JOB_EXTRAS / sizeof JOB_EXTRAS[0]; k++)
        if (!strcmp(name, JOB_EXTRAS[k])) return 1;
    if (strncmp(name, "layer_", 6) || !(name[6] >= '0' && name[6] <= '9')) return 0;
    for (name += 6; *name >= '0' && *name <= '9'; name++) {}
    return !strcmp(name, ".png") || !strcmp(name, ".svg");
}

/* A layer PNG under the very name this job of `layers` gives one of its own
   (`digits` wide, 1 to layers). */
static int is_own_layer_png(const char *name, size_t layers, int digits)
{
    char own[40];
    size_t v = 0;
    int n = 0;
    if (strncmp(name, "layer_", 6)) return 0;
    for (; name[6 + n] >= '0' && name[6 + n] <= '9' && n <= digits; n++) v = v * 10 + (size_t)(name[6 + n] - '0');
    if (n != digits || v < 1 || v > layers) return 0;
    layer_name(own, v - 1, digits, "png"); /* the name it would write: same digits, same extension */
    return !strcmp(name, own);
}

/* The whole of a regular file, malloc'd with a NUL after it (its size into
   *size if given); NULL with errno set: EISDIR or EINVAL where the name is a
   directory, a FIFO or a device, whose reading fails, waits or never ends. */
static char *read_whole(const char *path, size_t *size)
{
    struct stat st;
    FILE *f;
    char *data = NULL;
    size_t n;
    int err = 0;
    if (stat(path, &st) != 0) return NULL;
    if (!S_ISREG(st.st_mode)) {
        errno = S_ISDIR(st.st_mode) ? EISDIR : EINVAL;
        return NULL;
    }
    if (!(f = fopen(path, "rb"))) return NULL;
    n = (size_t)st.st_size;
    if ((uint64_t)st.st_size != n || n == (size_t)-1 || !(data = (char *)malloc(n + 1))) err = ENOMEM;
    else if (fread(data, 1, n, f) != n || fgetc(f) != EOF) err = ferror(f) && errno ? errno : EIO; /* it changed */
    fclose(f);
    if (err) {
        free(data);
        errno = err;
        return NULL;
    }
    data[n] = 0;
    if (size) *size = n;
    return data;
}

/* Why read_whole failed, from its errno. */
static const char *read_whole_error(void) { return errno == EINVAL ? "not a regular file" : strerror(errno); }

/* The directory holds something. */
static int has_entries(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int found = 0;
    while (d && !found && (e = readdir(d)) != NULL) found = strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    if (d) closedir(d);
    return found;
}

typedef struct old_job {
    const char *dir;
    char *path;
    size_t size, layers;         /* this job's layers, whose PNGs stay to be written over */
    int digits, rc;
} old_job;

/* One file an earlier manifest names, removed: a plain name in the
   directory, never a path out of it. */
static void remove_named(old_job *o, const char *name, size_t n)
{
    char plain[200];
    if (o->rc || !n || n >= sizeof plain || name[0] == '.' || memchr(name, '/', n) || memchr(name, '\\', n)) return;
    memcpy(plain, name, n);
    plain[n] = 0;
    if (is_own_layer_png(plain, o->layers, o->digits) || strlen(o->dir) + n + 2 > o->size) return;
    snprintf(o->path, o->size, "%s/%s", o->dir, plain);
    if (remove(o->path) != 0 && errno != ENOENT) o->rc = complain(RC_FAIL, "cannot remove %s: %s", o->path, strerror(errno));
}

/* The files an earlier manifest (its text) names: its "files" list, or, in a
   manifest from before the list, its layers' "file"s, their SVGs and the
   four files a slice wrote besides. */
static void remove_listed(old_job *o, const char *text)
{
    const char *p = strstr(text, "\"files\": [");
    size_t i;
    if (p) {
        for (p += 10; *p && *p != ']' && !o->rc; p++) {
            const char *end;
            if (*p != '"') continue;
            for (end = p + 1; *end && *end != '"' && *end != '\\'; end++) {}
            if (*end != '"') break; /* an escape: not a name this tool writes */
            remove_named(o, p + 1, (size_t)(end - p - 1));
            p = end;
        }
        return;
    }
    for (i = 0; i < sizeof JOB_EXTRAS / sizeof JOB_EXTRAS[0]; i++) remove_named(o, JOB_EXTRAS[i], strlen(JOB_EXTRAS[i]));
    for (p = text; !o->rc && (p = strstr(p, "\"file\": \"")) != NULL;) {
        const char *name = p + 9, *end = strchr(name, '"');
        size_t n;
        if (!end) break;
        n = (size_t)(end - name);
        remove_named(o, name, n);
        if (n > 4 && n < 200 && !memcmp(end - 4, ".png", 4)) {
            char svg[200];
            memcpy(svg, name, n - 4);
            memcpy(svg + n - 4, ".svg", 4);
            remove_named(o, svg, n);
        }
        p = end;
    }
}

/* A manifest.json this tool wrote: every one has said "format": "adaslice-job"
   first. Another program's manifest.json (a web app's, a package's) names its
   own files, which a re-slice must not take for an old job's. */
static int manifest_is_a_job(const char *text)
{
    const char *p = strstr(text, "\"format\"");
    if (!p) return 0;
    for (p += 8; *p == ' ' || *p == '\t' || *p == '\r' || *p == '\n' || *p == ':'; p++) {}
    return !strncmp(p, "\"adaslice-job\"", 14);
}

static int foreign_manifest(const char *dir)
{
    return complain(RC_USAGE, "-o %s: its manifest.json is not an adaslice job's (no \"format\": \"adaslice-job\"); the "
                              "job's would replace it and the files it lists were left alone: give a new or empty "
                              "directory", dir);
}

/* What an earlier job left in dir, as its manifest names it: the manifest
   first (so that an interrupted clean leaves no job that looks whole), then
   its files; nothing else. A directory that holds files and no manifest is
   someone's: refused unless force. The layer PNGs this job writes under the
   same names stay, to be overwritten: creating a file costs the file system
   an inode, under the directory's lock, so a re-slice that removed and made
   each again spent a quarter of its time there, and two threads waited on
   each other for it. path is room for a file's path. */
static int remove_old_job(const char *dir, size_t layers, int digits, int force, char *path, size_t size)
{
    old_job o;
    char *text;
    snprintf(path, size, "%s/manifest.json", dir);
    if (!(text = read_whole(path, NULL))) {
        if (errno != ENOENT) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
        return jobdir_check(dir, force);
    }
    if (!manifest_is_a_job(text)) {
        free(text);
        return foreign_manifest(dir);
    }
    if (remove(path) != 0 && errno != ENOENT) {
        free(text);
        return complain(RC_FAIL, "cannot remove %s: %s", path, strerror(errno));
    }
    o.dir = dir;
    o.path = path;
    o.size = size;
    o.layers = layers;
    o.digits = digits;
    o.rc = RC_OK;
    remove_listed(&o, text);
    free(text);
    return o.rc;
}

int jobdir_check(const char *dir, int force)
{
    size_t n = strlen(dir) + 16;
    char *manifest = (char *)malloc(n), *text;
    struct stat st;
    int ours = 0;
    if (!manifest) return complain(RC_FAIL, "out of memory");
    snprintf(manifest, n, "%s/manifest.json", dir);
    if ((text = read_whole(manifest, NULL)) != NULL) {
        ours = manifest_is_a_job(text);
        free(text);
        if (!ours) {
            free(manifest);
            return foreign_manifest(dir);
        }
    }
    free(manifest);
    if (ours || force || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode) || !has_entries(dir)) return RC_OK;
    return complain(RC_USAGE, "-o %s: the directory holds files and no manifest.json of an adaslice job; they are "
                              "left alone: give a new or empty directory, or --force to write the job among them",
                    dir);
}

int jobdir_remove(const char *dir)
{
    size_t size = strlen(dir) + 256;
    char *path = (char *)malloc(size);
    int rc;
    if (!path) return complain(RC_FAIL, "out of memory");
    rc = remove_old_job(dir, 0, layer_digits(0), 1, path, size); /* no layer is this job's own: all go */
    free(path);
    return rc;
}

static int dir_open(void **writer, const char *dir, const job_desc *d)
{
    dir_writer *w = (dir_writer *)calloc(1, sizeof *w);
    struct stat st;
    int rc = RC_OK;
    *writer = NULL;
    if (!w || !(w->dir = (char *)malloc(strlen(dir) + 1)) || !(w->path = (char *)malloc(strlen(dir) + 256))) {
        rc = complain(RC_FAIL, "out of memory");
        goto fail;
    }
    strcpy(w->dir, dir);
    w->d = d;
    w->digits = layer_digits(d->layer_count);
    w->path_size = strlen(dir) + 256;
    if (mkdir(dir, 0777) == 0) w->created = 1;
    else if (errno != EEXIST) { rc = complain(RC_FAIL, "cannot create %s: %s", dir, strerror(errno)); goto fail; }
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) { rc = complain(RC_FAIL, "%s is not a directory", dir); goto fail; }
    if ((rc = remove_old_job(dir, d->layer_count, w->digits, d->dir_force, w->path, w->path_size))) goto fail;
    w->writing = 1;
    if ((rc = job_masks_alloc(&w->masks, (uint32_t)d->layer_count))) goto fail;
    if (!(w->line_end = (size_t *)calloc(d->layer_count ? d->layer_count : 1, sizeof *w->line_end)) ||
        !(w->lines_file = open_memstream(&w->lines, &w->lines_size))) {
        rc = complain(RC_FAIL, "out of memory for the manifest of %zu layer%s", d->layer_count, plural(d->layer_count));
        goto fail;
    }
    json_init(&w->lines_json, w->lines_file);
    w->masks.width = (uint32_t)d->width;
    w->masks.height = (uint32_t)d->height;
    w->masks.bits = (uint32_t)d->bits;
    w->masks.peel_nm = (uint32_t)(d->motion.lift_mm * 1e6 + 0.5);
    w->masks.peel_speed_um_s = milli(d->motion.lift_speed);
    w->masks.return_speed_um_s = milli(d->motion.retract_speed);
    w->masks.settle_ms = milli(d->motion.wait_before_cure_s);
    {
        double nm = d->bin_mm * 1e6;
        w->masks.bin_nm = (uint32_t)(nm + 0.5);
        w->whole_bin = fabs(nm - w->masks.bin_nm) <= 1e-6 * nm;
    }
    /* masks.rle, like the layers, straight under its name and written as they
       are put (by whichever thread puts them, while others code): the
       manifest, written last, names its CRC-32. At the end it took the job's
       one thread a hundredth of the time. */
    if (w->whole_bin) {
        if (!(w->masks_path = dir_file(dir, "masks.rle"))) { rc = RC_FAIL; goto fail; }
        if (!(w->masks_file = fopen(w->masks_path, "wb"))) {
            rc = complain(RC_FAIL, "cannot write %s: %s", w->masks_path, strerror(errno));
            goto fail;
        }
        emit_masks_header(w);
    }
    *writer = w;
    return RC_OK;
fail:
    if (w) dir_close(w, 0);
    return rc;
}

typedef struct bytes { const unsigned char *data; size_t size; } bytes;

static void write_bytes(FILE *f, const void *ctx)
{
    const bytes *b = (const bytes *)ctx;
    fwrite(b->data, 1, b->size, f);
}

static int write_png(const char *path, unsigned char *png, size_t size)
{
    bytes b;
    int rc;
    b.data = png;
    b.size = size;
    rc = write_atomic(path, write_bytes, &b);
    free(png);
    return rc;
}

/* A layer's PNG straight under its name: the manifest, removed before the
   first layer and written after the last, is what says the job is whole, so
   the layers need no temporary name (which would double the directory's
   work); a failed write removes its file. An earlier job's file of the name
   is written over in place and cut to size: truncated to nothing first, the
   file system would free its blocks on open and (ext4, which guards files
   replaced by truncation) write it out to disk on close, a tenth of a
   re-slice's time. */
static int write_layer_png(const char *path, unsigned char *png, size_t size)
{
    /* open, write, cut, close: through stdio a layer took two more calls
       into the kernel (a stat to size its buffer, the PNG in two writes) */
    int fd = open(path, O_RDWR), err = 0;
    size_t done = 0;
    if (fd < 0) fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (fd < 0) err = errno;
    else {
        while (done < size && !err) {
            ssize_t n = write(fd, png + done, size - done);
            if (n > 0) done += (size_t)n;
            else if (n == 0 || errno != EINTR) err = n < 0 ? errno : EIO;
        }
        if (!err && ftruncate(fd, (off_t)size) != 0) err = errno;
        if (close(fd) != 0 && !err) err = errno;
        if (err) remove(path);
    }
    free(png);
    return err ? complain(RC_FAIL, "cannot write %s: %s", path, strerror(err)) : RC_OK;
}

/* The layer's PNG goes straight to its own file; the blob is its mask code
   and CRC for masks.rle, all three from one reading of the layer's rows. */
/* A layer's PNG written, its masks.rle code and CRC into blob, or a
   complaint when it could not be coded (failed). */
static int dir_coded(const dir_writer *w, size_t k, int failed, png_layer *coded, job_blob *blob)
{
    char *path = failed ? NULL : (char *)malloc(w->path_size);
    int rc;
    if (!path) {
        free(coded->png);
        free(coded->rle);
        return complain(RC_FAIL, "out of memory encoding layer %zu", k + 1);
    }
    layer_path(path, w->path_size, w->dir, k, w->digits, "png");
    rc = write_layer_png(path, coded->png, coded->png_size);
    free(path);
    free(blob->data);
    blob->data = coded->rle;
    blob->size = blob->cap = coded->rle_size;
    blob->crc = coded->crc;
    return rc;
}

static int dir_encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    const dir_writer *w = (const dir_writer *)writer;
    const job_masks *m = &w->masks;
    png_layer coded;
    int failed = png_encode_layer(image, (int)m->width, (int)m->height, stride, (int)m->bits,
                                  w->d->lit_rows[1] > 0 ? w->d->lit_rows : NULL, &coded);
    return dir_coded(w, k, failed, &coded, blob);
}

static int dir_encode_bands(const void *writer, size_t k, const mask_band *bands, int count, job_blob *blob)
{
    const dir_writer *w = (const dir_writer *)writer;
    const job_masks *m = &w->masks;
    png_layer coded;
    int failed = png_encode_bands(bands, count, (int)m->width, (int)m->height, (int)m->bits, &coded);
    return dir_coded(w, k, failed, &coded, blob);
}

static int dir_put(void *writer, size_t k, job_blob *blob)
{
    dir_writer *w = (dir_writer *)writer;
    job_masks *m = &w->masks;
    const job_layer *l = &w->d->layers[k];
    m->sizes[k] = blob->size;
    m->crcs[k] = blob->crc;
    m->lengths[k] = (uint32_t)(l->thickness / w->d->bin_mm + 0.5);
    m->exposure_ms[k] = milli(l->exposure_s);
    if (w->masks_file) emit_masks_layer(w, (uint32_t)k, blob->data);
    manifest_line(w, k);
    free(blob->data);
    blob->data = NULL;
    return RC_OK;
}

static int write_manifest_file(dir_writer *w)
{
    if (fflush(w->lines_file) != 0 || ferror(w->lines_file) || w->lines_failed)
        return complain(RC_FAIL, "out of memory for the manifest");
    snprintf(w->path, w->path_size, "%s/manifest.json", w->dir);
    return write_atomic(w->path, write_manifest, w);
}

enum { DIR_PREVIEW_W = 400, DIR_PREVIEW_H = 300 };

/* masks.rle (unless the bin is not a whole number of nanometres, which a
   printer cannot count), preview.png, then the manifest. */
static int dir_finish(dir_writer *w)
{
    const job_desc *d = w->d;
    unsigned char *rgb, *png = NULL;
    size_t size;
    int rc = RC_OK, pw = DIR_PREVIEW_W, ph = DIR_PREVIEW_H;
    if (w->masks_file) {
        FILE *f = w->masks_file;
        int err = ferror(f) ? (errno ? errno : EIO) : 0;
        w->masks_file = NULL;
        if (fclose(f) != 0 && !err) err = errno;
        if (err) return complain(RC_FAIL, "cannot write %s: %s", w->masks_path, strerror(err));
        w->has_masks = 1;
    } else {
        warn("%s: no masks.rle, so adaslice print cannot take this job: its bin of %g mm "
             "is not a whole number of nanometres", w->dir, d->bin_mm);
    }
    if (!d->preview) return write_manifest_file(w);
    if (!(rgb = (unsigned char *)malloc((size_t)pw * ph * 3)) || d->preview(d->preview_ctx, pw, ph, rgb) ||
        png_encode_rgb(rgb, pw, ph, &png, &size)) {
        free(rgb);
        return complain(RC_FAIL, "out of memory for the preview");
    }
    free(rgb);
    snprintf(w->path, w->path_size, "%s/preview.png", w->dir);
    if ((rc = write_png(w->path, png, size))) return rc;
    return write_manifest_file(w);
}

static void remove_own(void *ctx, const char *name)
{
    dir_writer *w = (dir_writer *)ctx;
    snprintf(w->path, w->path_size, "%s/%s", w->dir, name);
    remove(w->path);
}

static int dir_close(void *writer, int ok)
{
    dir_writer *w = (dir_writer *)writer;
    int rc = ok ? dir_finish(w) : RC_FAIL;
    if (w->masks_file) fclose(w->masks_file);
    w->masks_file = NULL;
    if (rc && w->writing) {
        /* a job that failed or was interrupted leaves nothing of its own: no
           manifest, masks, preview, plan or layer (the caller's included) */
        remove_own(w, "manifest.json");
        own_files(w, remove_own, w);
    }
    if (rc && w->created) rmdir(w->dir); /* made by this job: gone with it */
    job_masks_free(&w->masks);
    if (w->lines_file) fclose(w->lines_file);
    free(w->lines);
    free(w->line_end);
    free(w->masks_path);
    free(w->dir);
    free(w->path);
    free(w);
    return rc;
}

const job_format JOB_FORMAT_DIR = {
    .name = "dir",
    .extension = NULL,
    .what = "a job directory: a PNG per layer, masks.rle for adaslice print, manifest.json",
    .min_layer_mm = 0,
    .adaptive = 1,
    .open = dir_open,
    .encode = dir_encode,
    .encode_bands = dir_encode_bands,
    .put = dir_put,
    .close = dir_close,
    .previews = {{DIR_PREVIEW_W, DIR_PREVIEW_H}},
};

/* ------------------------------------------------------------ reading */

/* masks.rle is the job's when the manifest, written after it, names its
   CRC-32: a job without a manifest is not whole, and masks left from
   another job do not match. The manifest's pitch goes into m. */
static int matches_manifest(const char *dir, const char *masks_path, job_masks *m)
{
    char *path = dir_file(dir, "manifest.json"), *text = NULL;
    const char *at;
    unsigned long named = 0;
    uint32_t crc = adaslice_crc32(0, m->file, m->file_size);
    int rc = RC_FAIL;
    if (!path) return RC_FAIL;
    if (!(text = read_whole(path, NULL))) {
        if (errno == ENOENT) complain(RC_FAIL, "%s: missing: the job is not whole (its slice did not finish); slice it again", path);
        else complain(RC_FAIL, "cannot read %s: %s", path, read_whole_error());
        goto done;
    }
    at = strstr(text, "\"masks_rle_crc32\": \"");
    if (!at || sscanf(at + 20, "%8lx", &named) != 1) {
        complain(RC_FAIL, "%s names no masks.rle (masks_rle_crc32): it is not the manifest of this %s", path, masks_path);
        goto done;
    }
    if (named != crc) {
        complain(RC_FAIL, "%s belongs to another job than %s (CRC-32 %08x, the manifest names %08lx): slice it again",
                 masks_path, path, (unsigned)crc, named);
        goto done;
    }
    /* the pitch the part was sliced at: a printer with other pixels prints it scaled */
    at = strstr(text, "\"pitch_mm\"");
    if (!at || sscanf(at + 10, " : [ %lf , %lf", &m->pitch_mm[0], &m->pitch_mm[1]) != 2 ||
        !(m->pitch_mm[0] > 0 && m->pitch_mm[0] <= 1000) || !(m->pitch_mm[1] > 0 && m->pitch_mm[1] <= 1000)) {
        complain(RC_FAIL, "%s names no pixel pitch of 0 to 1000 mm (printer.pitch_mm): slice it again", path);
        goto done;
    }
    rc = RC_OK;
done:
    free(text);
    free(path);
    return rc;
}

/* The bytes of one of m's rows. */
static size_t masks_stride(const job_masks *m) { return m->bits == 8 ? m->width : (m->width + 7) / 8; }

/* Layer k's mask decoded through emit (may be NULL): 0 when it is whole and
   its CRC-32 the one named, else what is wrong (a decoder's result, or
   ADASLICE_ERR_ROWS + 1: too few rows, + 2: another CRC); dec is left as it
   ended, for the message. */
static int decode_quietly(const job_masks *m, uint32_t k, unsigned char *row, adaslice_rle_decoder *dec,
                          void (*emit)(void *ctx, uint32_t y, const unsigned char *row), void *ctx)
{
    adaslice_result r;
    if (adaslice_rle_decoder_init(dec, m->width, m->height, (int)m->bits, row, masks_stride(m))) return ADASLICE_ERR_ARGUMENT;
    r = adaslice_rle_decode(dec, m->codes[k], m->sizes[k], emit, ctx);
    if (r >= ADASLICE_ERR_VARINT && r <= ADASLICE_ERR_ROWS) return (int)r;
    if (r || !adaslice_rle_finished(dec)) return ADASLICE_ERR_ROWS + 1;
    return ADASLICE_RLE_CRC(dec) == m->crcs[k] ? 0 : ADASLICE_ERR_ROWS + 2;
}

int jobdir_decode_layer(const char *dir, const job_masks *m, uint32_t k, unsigned char *row,
                        void (*emit)(void *ctx, uint32_t y, const unsigned char *row), void *ctx)
{
    static const char *const why[] = {"a number longer than 5 bytes", "runs that do not make up a row",
                                      "more rows than the mask's"};
    size_t start = (size_t)(m->codes[k] - m->file);
    adaslice_rle_decoder dec;
    int r = decode_quietly(m, k, row, &dec, emit, ctx);
    if (r == ADASLICE_ERR_ARGUMENT)
        return complain(RC_FAIL, "%s/masks.rle: masks of %u x %u px, %u bits, cannot be decoded", dir, m->width, m->height,
                        m->bits); /* not reached: jobdir_read_masks checks them */
    if (r >= ADASLICE_ERR_VARINT && r <= ADASLICE_ERR_ROWS)
        return complain(RC_FAIL, "%s/masks.rle: byte %zu: layer %u's mask code is damaged: %s", dir, start + dec.offset,
                        k + 1, why[r - ADASLICE_ERR_VARINT]);
    if (r == ADASLICE_ERR_ROWS + 1)
        return complain(RC_FAIL, "%s/masks.rle: byte %zu: layer %u's mask code ends before its %u rows do", dir,
                        start + m->sizes[k], k + 1, m->height);
    if (r)
        return complain(RC_FAIL, "%s/masks.rle: byte %zu: layer %u's mask decodes to CRC-32 %08x, not the %08x named there: "
                                 "the file is damaged", dir, start - MASKS_LAYER + 8, k + 1, (unsigned)ADASLICE_RLE_CRC(&dec),
                        (unsigned)m->crcs[k]);
    return RC_OK;
}

/* Every other layer from `from`, up to the first unsound one. */
typedef struct layer_check {
    const job_masks *m;
    uint32_t from, bad;          /* bad: the first unsound layer, or m->layers */
    unsigned char *row;
} layer_check;

static void *check_every_other(void *arg)
{
    layer_check *c = (layer_check *)arg;
    adaslice_rle_decoder dec;
    uint32_t k;
    for (k = c->from; k < c->m->layers; k += 2)
        if (decode_quietly(c->m, k, c->row, &dec, NULL, NULL)) { c->bad = k; break; }
    return NULL;
}

/* On two threads: a print checks every layer before the port opens (2 s of a
   turbine blade's 1,421 layers at 3840 x 2400 on one). The first damaged
   layer is the one named, as on one thread. */
int jobdir_check_layers(const char *dir, const job_masks *m)
{
    layer_check c[2];
    pthread_t other;
    int t, threaded;
    uint32_t bad;
    for (t = 0; t < 2; t++) {
        c[t].m = m;
        c[t].from = (uint32_t)t;
        c[t].bad = m->layers;
        c[t].row = (unsigned char *)malloc(masks_stride(m));
    }
    if (!c[0].row || !c[1].row) {
        free(c[0].row);
        free(c[1].row);
        return complain(RC_FAIL, "out of memory for a row of %u px", m->width);
    }
    threaded = output_thread_start(&other, check_every_other, &c[1]) == 0;
    check_every_other(&c[0]);
    if (threaded) pthread_join(other, NULL);
    else check_every_other(&c[1]);
    bad = c[0].bad < c[1].bad ? c[0].bad : c[1].bad;
    t = bad < m->layers ? jobdir_decode_layer(dir, m, bad, c[0].row, NULL, NULL) : RC_OK;
    free(c[0].row);
    free(c[1].row);
    return t;
}

int jobdir_read_masks(const char *dir, job_masks *m)
{
    char *path = dir_file(dir, "masks.rle");
    size_t at;
    uint32_t k;
    int rc = RC_FAIL, found;
    struct stat st;
    char *manifest = dir_file(dir, "manifest.json");
    memset(m, 0, sizeof *m);
    if (!path || !manifest) {
        free(manifest);
        free(path);
        return RC_FAIL;
    }
    /* a slice removes the manifest first and writes it last, masks.rle and
       the layers going straight under their names meanwhile: without it the
       job is not whole, whatever masks.rle holds */
    if ((found = stat(dir, &st) == 0) == 0 || !S_ISDIR(st.st_mode)) {
        complain(RC_FAIL, "%s: %s", dir, found ? "not a job directory" : strerror(errno));
        free(manifest);
        goto done;
    }
    if (stat(manifest, &st) != 0 && errno == ENOENT) {
        complain(RC_FAIL, "%s: missing: the job is not whole (its slice did not finish); slice it again", manifest);
        free(manifest);
        goto done;
    }
    free(manifest);
    if (!(m->file = (unsigned char *)read_whole(path, &m->file_size))) {
        if (errno == ENOENT) complain(RC_FAIL, "cannot open %s: %s (was the job written by adaslice slice?)", path, strerror(errno));
        else complain(RC_FAIL, "cannot read %s: %s", path, read_whole_error());
        goto done;
    }
    if (m->file_size >= 8 && !memcmp(m->file, "ADASMSK1", 8)) {
        complain(RC_FAIL, "%s: a job from an adaslice before per-layer exposures: slice it again", path);
        goto done;
    }
    if (m->file_size < MASKS_HEADER || memcmp(m->file, "ADASMSK2", 8)) {
        complain(RC_FAIL, "%s: not an adaslice mask file (bad magic at byte 0)", path);
        goto done;
    }
    m->width = get_le32(m->file + 8);
    m->height = get_le32(m->file + 12);
    m->bits = get_le32(m->file + 16);
    k = get_le32(m->file + 20);
    m->bin_nm = get_le32(m->file + 24);
    m->peel_nm = get_le32(m->file + 28);
    m->peel_speed_um_s = get_le32(m->file + 32);
    m->return_speed_um_s = get_le32(m->file + 36);
    m->settle_ms = get_le32(m->file + 40);
    /* the run-length code's own limits (adaslice_rle_decoder_init) */
    if (m->width < 1 || m->width >= 1u << 24 || m->height < 1 || m->height >= 1u << 24) {
        complain(RC_FAIL, "%s: byte 8: masks of %u x %u px: each side is 1 to %u px", path, m->width, m->height,
                 (1u << 24) - 1);
        goto done;
    }
    if (m->bits != 1 && m->bits != 8) {
        complain(RC_FAIL, "%s: byte 16: masks of %u bits a pixel: 1 or 8", path, m->bits);
        goto done;
    }
    if (!k || k > m->file_size / MASKS_LAYER || !m->bin_nm) {
        complain(RC_FAIL, "%s: byte 20: the file does not hold %u layer%s of %u nm", path, k, plural(k), m->bin_nm);
        goto done;
    }
    /* what slice would have refused to write (cure.h) */
    if (m->peel_nm > CURE_MAX_PEEL_MM * 1e6 || m->peel_speed_um_s > CURE_MAX_PEEL_MM * 1e3 ||
        m->return_speed_um_s > CURE_MAX_PEEL_MM * 1e3 || !m->peel_speed_um_s || !m->return_speed_um_s) {
        complain(RC_FAIL, "%s: byte 28: a peel of %u nm at %u um/s, back at %u um/s: peels are limited to %g mm and "
                          "speeds to 1 um/s .. %g mm/s", path, m->peel_nm, m->peel_speed_um_s, m->return_speed_um_s,
                 CURE_MAX_PEEL_MM, CURE_MAX_PEEL_MM);
        goto done;
    }
    if (m->settle_ms > CURE_MAX_SECONDS * 1e3) {
        complain(RC_FAIL, "%s: byte 40: a settle of %u ms: it is limited to %g s", path, m->settle_ms, CURE_MAX_SECONDS);
        goto done;
    }
    if (job_masks_alloc(m, k)) goto done;
    for (at = MASKS_HEADER, k = 0; k < m->layers; k++) {
        uint32_t code;
        if (m->file_size - at < MASKS_LAYER || (code = get_le32(m->file + at + 12)) > m->file_size - at - MASKS_LAYER) {
            complain(RC_FAIL, "%s: byte %zu: layer %u runs past the end of the file", path, at, k + 1);
            goto done;
        }
        m->lengths[k] = get_le32(m->file + at);
        if (!m->lengths[k]) {
            complain(RC_FAIL, "%s: byte %zu: layer %u is 0 bins thick", path, at, k + 1);
            goto done;
        }
        m->exposure_ms[k] = get_le32(m->file + at + 4);
        if (m->exposure_ms[k] < CURE_MIN_SECONDS * 1e3 || m->exposure_ms[k] > CURE_MAX_SECONDS * 1e3) {
            complain(RC_FAIL, "%s: byte %zu: layer %u's exposure of %u ms is not %g ms to %g s", path, at + 4, k + 1,
                     m->exposure_ms[k], CURE_MIN_SECONDS * 1e3, CURE_MAX_SECONDS);
            goto done;
        }
        m->crcs[k] = get_le32(m->file + at + 8);
        m->sizes[k] = code;
        m->codes[k] = m->file + at + MASKS_LAYER;
        at += MASKS_LAYER + code;
    }
    if (at != m->file_size) {
        complain(RC_FAIL, "%s: byte %zu: %zu byte%s after the last layer", path, at, m->file_size - at,
                 plural(m->file_size - at));
        goto done;
    }
    rc = matches_manifest(dir, path, m);
done:
    if (rc) job_masks_free(m);
    free(path);
    return rc;
}
