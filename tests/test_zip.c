/* Tests of the ZIP writer (host/codec/zip.c). Two readers check what it writes:
   Info-ZIP's unzip, which tests every member's CRC (-t) and extracts it (-p,
   -d) for a byte-for-byte comparison; and, without any program, a walk of
   the archive by the APPNOTE's layouts that holds the end record, the
   central directory and every local header against the members given. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp, dup */
#endif
#include "util.h"
#include "check.h"
#include "maskgen.h"
#include "tool_run.h"
#include "../host/codec/zip.h"
#include "../adaslice_mcu.h"

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[64];

static const char *in_dir(const char *name)
{
    static char ring[16][256];
    static int next;
    char *p = ring[next++ & 15];
    snprintf(p, sizeof ring[0], "%s/%s", dir, name);
    return p;
}

static uint32_t rng_state = 2024;

static uint32_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}


/* The names in the directory besides "." and "..", one per line. */
static void list_dir(char *out, size_t size)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    size_t used = 0;
    out[0] = 0;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            used += (size_t)snprintf(out + used, used < size ? size - used : 0, "%s\n", e->d_name);
    if (d) closedir(d);
}

/* Everything under the directory, folders too. */
static void remove_tree(const char *path)
{
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            char sub[512];
            snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            remove_tree(sub);
        }
    if (d) closedir(d);
    remove(path);
}

/* stderr into a file from capture_start to capture_end, which returns it. */
static int saved_stderr = -1;

static void capture_start(void)
{
    FILE *f;
    fflush(stderr);
    saved_stderr = dup(2);
    f = fopen(in_dir("stderr"), "w");
    if (f) {
        dup2(fileno(f), 2);
        fclose(f);
    }
}

static char *capture_end(void)
{
    size_t n;
    char *s;
    fflush(stderr);
    dup2(saved_stderr, 2);
    close(saved_stderr);
    s = (char *)read_whole_file(in_dir("stderr"), &n);
    if (s) s[n] = 0;
    remove(in_dir("stderr"));
    return s;
}

/* ---- members -------------------------------------------------------------- */

typedef struct member {
    char name[96];
    unsigned char *data;
    size_t size;
    int deflate;
    int method;      /* what the archive must say: 0 stored, 8 deflated, -1 either */
} member;

enum { MAX_MEMBERS = 320 };

typedef struct archive {
    member m[MAX_MEMBERS];
    int count;
} archive;

static member *add_member(archive *a, const char *name, size_t size, int deflate, int method)
{
    member *m = &a->m[a->count++];
    snprintf(m->name, sizeof m->name, "%s", name);
    m->size = size;
    m->deflate = deflate;
    m->method = method;
    m->data = (unsigned char *)malloc(size ? size : 1);
    return m;
}

static void free_members(archive *a)
{
    for (int i = 0; i < a->count; i++) free(a->m[i].data);
    a->count = 0;
}

static void fill_random(member *m)
{
    for (size_t i = 0; m->data && i < m->size; i++) m->data[i] = (unsigned char)(rng() >> 11);
}

/* Bytes of four values in runs of 1 to 300: compressible, not trivially. */
static void fill_runs(member *m)
{
    static const unsigned char values[4] = {0, 255, 17, 128};
    for (size_t i = 0; m->data && i < m->size;) {
        size_t run = 1 + rng() % 300;
        unsigned char v = values[rng() % 4];
        for (; run-- && i < m->size; i++) m->data[i] = v;
    }
}

/* A layer mask of w x h pixels: coverage at 8 bits or packed at 1. */
static member *add_mask(archive *a, const char *name, int w, int h, int bits, int layer)
{
    size_t stride = bits == 8 ? (size_t)w : ((size_t)w + 7) / 8;
    member *m = add_member(a, name, stride * (size_t)h, 1, 8);
    unsigned char *g = (unsigned char *)malloc((size_t)w * (size_t)h);
    if (g && m->data) {
        mask_scene(g, w, h, layer);
        if (bits == 8) memcpy(m->data, g, m->size);
        else mask_pack(g, w, h, m->data, stride);
    }
    free(g);
    return m;
}

/* zip_open, every member, zip_close(ok); RC_OK when all went well. */
static int write_archive(const char *path, const archive *a)
{
    zip_writer *z;
    int rc = zip_open(&z, path);
    for (int i = 0; rc == 0 && i < a->count; i++)
        rc = zip_add(z, a->m[i].name, a->m[i].data, a->m[i].size, a->m[i].deflate);
    if (z) rc = zip_close(z, rc == 0) || rc;
    return rc;
}

/* ---- the archive read by hand --------------------------------------------- */

static unsigned le16(const unsigned char *p) { return (unsigned)p[0] | (unsigned)p[1] << 8; }
static uint32_t le32(const unsigned char *p) { return le16(p) | (uint32_t)le16(p + 2) << 16; }

/* The end record, the central directory and each local header, as APPNOTE
   4.3.7, 4.3.12 and 4.3.16 lay them out, against the members: counts,
   offsets (members back to back, the directory right after them), CRC-32s,
   sizes, methods, the fixed date, and the stored members' bytes. */
static void check_layout(const char *path, const archive *a)
{
    size_t n, offset = 0, cd, cd_size;
    unsigned char *zip = read_whole_file(path, &n);
    const unsigned char *end, *c;
    CHECKF(zip && n >= 22, "%s: no archive", path);
    if (!zip || n < 22) { free(zip); return; }
    end = zip + n - 22;
    cd = le32(end + 16);
    cd_size = le32(end + 12);
    CHECK(le32(end) == 0x06054b50u && le16(end + 4) == 0 && le16(end + 6) == 0 && le16(end + 20) == 0);
    CHECKF(le16(end + 8) == (unsigned)a->count && le16(end + 10) == (unsigned)a->count, "%u members, wanted %d",
           le16(end + 10), a->count);
    CHECKF(cd + cd_size == n - 22, "central directory at %zu, %zu bytes, in a file of %zu", cd, cd_size, n);
    if (cd + cd_size != n - 22) { free(zip); return; }
    c = zip + cd;
    for (int i = 0; i < a->count && !check_case_failed(); i++) {
        const member *m = &a->m[i];
        size_t len = strlen(m->name), csize, local;
        unsigned method;
        if ((size_t)(end - c) < 46 + len) { CHECKF(0, "%s: the central directory ends early", m->name); break; }
        method = le16(c + 10);
        csize = le32(c + 20);
        local = le32(c + 42);
        CHECKF(le32(c) == 0x02014b50u && le16(c + 4) == (3 << 8 | 20), "%s: central header signature", m->name);
        CHECKF(le16(c + 6) == (method ? 20u : 10u) && le16(c + 8) == 0, "%s: version needed, flags", m->name);
        CHECKF(method == 0 || method == 8, "%s: method %u", m->name, method);
        CHECKF(m->method < 0 || method == (unsigned)m->method, "%s: method %u, wanted %d", m->name, method,
               m->method);
        CHECKF(method ? csize < m->size : csize == m->size, "%s: %zu bytes stored of %zu, method %u", m->name,
               csize, m->size, method);
        CHECKF(le16(c + 12) == 0 && le16(c + 14) == (1 << 5 | 1), "%s: not 1980-01-01 00:00", m->name);
        CHECKF(le32(c + 16) == adaslice_crc32(0, m->data, m->size), "%s: CRC-32", m->name);
        CHECKF(le32(c + 24) == m->size && le16(c + 28) == len && le16(c + 30) == 0 && le16(c + 32) == 0,
               "%s: size or lengths", m->name);
        CHECKF(le16(c + 34) == 0 && le16(c + 36) == 0 && le32(c + 38) == (uint32_t)0100644 << 16,
               "%s: disk or attributes", m->name);
        CHECKF(!memcmp(c + 46, m->name, len), "%s: name in the central directory", m->name);
        CHECKF(local == offset, "%s: local header at %zu, the previous member ends at %zu", m->name, local, offset);
        if (local != offset || offset + 30 + len + csize > cd) break;
        CHECKF(le32(zip + local) == 0x04034b50u && !memcmp(zip + local + 4, c + 6, 26) &&
               !memcmp(zip + local + 30, m->name, len), "%s: the local header differs", m->name);
        if (method == 0 && m->size)
            CHECKF(!memcmp(zip + local + 30 + len, m->data, m->size), "%s: stored bytes differ", m->name);
        offset += 30 + len + csize;
        c += 46 + len;
    }
    CHECKF(offset == cd && c == end, "the members end at %zu, the directory starts at %zu", offset, cd);
    free(zip);
}

/* ---- unzip ------------------------------------------------------------------ */

/* unzip -t: every CRC checked, "No errors detected". */
static void unzip_tests(const char *path)
{
    char *argv[] = {(char *)"unzip", (char *)"-t", (char *)path, NULL}, *out;
    size_t n;
    int st = tool_run("unzip", argv, in_dir("unzip.log"), in_dir("unzip.log"));
    out = (char *)read_whole_file(in_dir("unzip.log"), &n);
    if (out) out[n] = 0;
    CHECKF(st == 0 && out && strstr(out, "No errors detected"), "unzip -t %s: status %d: %.300s", path, st,
           out ? out : "");
    free(out);
    remove(in_dir("unzip.log"));
}

/* unzip -p, one member, compared byte for byte. */
static void unzip_member_matches(const char *path, const member *m)
{
    char *argv[] = {(char *)"unzip", (char *)"-p", (char *)path, (char *)m->name, NULL};
    unsigned char *got;
    size_t n;
    int st = tool_run("unzip", argv, in_dir("member"), in_dir("unzip.log"));
    got = read_whole_file(in_dir("member"), &n);
    CHECKF(st == 0 && got && n == m->size && !memcmp(got, m->data, n), "unzip -p %s %s: status %d, %zu bytes of %zu%s",
           path, m->name, st, n, m->size, got && n == m->size ? ", bytes differ" : "");
    free(got);
    remove(in_dir("member"));
    remove(in_dir("unzip.log"));
}

/* ---- cases -------------------------------------------------------------- */

/* What a job archive holds: text, an incompressible member (stored although
   deflate was asked), an empty one, masks deflated and stored, subfolders. */
static void job_like(archive *a)
{
    member *m = add_member(a, "run.gcode", 0, 1, 8);
    size_t used = 0;
    free(m->data);
    m->data = (unsigned char *)malloc(40000);
    for (int k = 0; m->data && used + 200 < 40000; k++)
        used += (size_t)snprintf((char *)m->data + used, 40000 - used,
                                 ";LAYER_START:%d\n;currPos:%.3f\nM6054 \"%d.png\";show Image\nG0 Z%.3f F60;\n",
                                 k, 0.05 * (k + 1), k + 1, 0.05 * (k + 1) + 5);
    m->size = used;
    fill_random(add_member(a, "preview.png", 5000, 1, 0));
    add_member(a, "empty", 0, 1, 0);
    add_member(a, "empty_stored", 0, 0, 0);
    add_mask(a, "layers/deep/folder/1.bin", 640, 360, 8, 10);
    add_mask(a, "layers/2.bin", 2560, 1440, 1, 60);
    fill_runs(add_member(a, "stored/runs.bin", 70000, 0, 0));
}

static void archives_are_laid_out_as_the_appnote_says(void)
{
    archive *a = (archive *)calloc(1, sizeof *a);
    unsigned char *one, *two;
    size_t n1, n2;
    char names[256];
    job_like(a);
    CHECK(write_archive(in_dir("job.zip"), a) == 0);
    check_layout(in_dir("job.zip"), a);
    /* the same members give the same bytes, and no temporary file is left */
    CHECK(write_archive(in_dir("again.zip"), a) == 0);
    one = read_whole_file(in_dir("job.zip"), &n1);
    two = read_whole_file(in_dir("again.zip"), &n2);
    CHECK(one && two && n1 == n2 && !memcmp(one, two, n1));
    list_dir(names, sizeof names);
    CHECKF(!strcmp(names, "job.zip\nagain.zip\n") || !strcmp(names, "again.zip\njob.zip\n"), "the directory holds %s",
           names);
    free(one);
    free(two);
    remove(in_dir("job.zip"));
    remove(in_dir("again.zip"));
    free_members(a);
    free(a);
}

static void three_hundred_members(archive *a)
{
    for (int i = 0; i < 300; i++) {
        char name[64];
        snprintf(name, sizeof name, "d%d/%d.bin", i % 7, i);
        if (i % 3 == 0) fill_random(add_member(a, name, (size_t)(rng() % 2000), i % 2, -1));
        else fill_runs(add_member(a, name, (size_t)(rng() % 5000), i % 2, -1));
    }
}

static void three_hundred_members_are_listed(void)
{
    archive *a = (archive *)calloc(1, sizeof *a);
    three_hundred_members(a);
    CHECK(write_archive(in_dir("many.zip"), a) == 0);
    check_layout(in_dir("many.zip"), a);
    remove(in_dir("many.zip"));
    free_members(a);
    free(a);
}

/* Each refusal is one line naming the archive, and leaves nothing behind:
   zip_close(ok) after it keeps no archive. */
static void bad_members_are_refused(void)
{
    static const char *bad_names[] = {"", "dir\\file", "/absolute", NULL};
    static unsigned char byte;
    char *long_name = (char *)malloc(65537), *err, names[256], path[128];
    zip_writer *z;
    int refused = 0, lines = 0;
    snprintf(path, sizeof path, "%s", in_dir("bad.zip"));
    memset(long_name, 'a', 65536);
    long_name[65536] = 0;
    capture_start();
    for (int k = 0; k < 6; k++) {
        int rc = zip_open(&z, path);
        if (rc) break;
        CHECK(zip_add(z, "fine.txt", "ok", 2, 1) == 0);
        if (k < 3) rc = zip_add(z, bad_names[k], "x", 1, 0);
        else if (k == 3) rc = zip_add(z, long_name, "x", 1, 0);
        else if (k == 4) rc = zip_add(z, "huge", &byte, (size_t)0xFFFFFFFFu, 1); /* refused before a byte is read */
        else {
            for (int i = 1; i < 65535 && rc == 0; i++) rc = zip_add(z, "e", "", 0, 0);
            CHECKF(rc == 0, "a member before the 65536th refused");
            rc = zip_add(z, "one too many", "", 0, 0);
        }
        refused += rc != 0;
        CHECK(zip_add(z, "after", "x", 1, 0) != 0); /* only closing is left */
        CHECK(zip_close(z, 1) != 0);
    }
    CHECK(zip_open(&z, in_dir("no/such/folder.zip")) != 0 && !z);
    err = capture_end();
    CHECK(refused == 6);
    for (char *line = err ? strtok(err, "\n") : NULL; line; line = strtok(NULL, "\n"), lines++)
        CHECKF(!strncmp(line, "adaslice: cannot write ", 23) && strstr(line, ".zip"),
               "not a complaint naming the archive: %.200s", line);
    CHECKF(lines == 7, "%d lines on stderr, wanted 7", lines);
    list_dir(names, sizeof names);
    CHECKF(!names[0], "left behind: %s", names);
    /* a discarded archive leaves nothing either */
    CHECK(zip_open(&z, path) == 0 && zip_add(z, "a", "a", 1, 1) == 0 && zip_close(z, 0) != 0);
    list_dir(names, sizeof names);
    CHECKF(!names[0], "left behind: %s", names);
    free(err);
    free(long_name);
}

/* zip_member reads a member back; one whose central record claims more
   bytes than deflate can make of its data (1032 to 1), or than the reader
   takes, is refused before anything that size is made. */
static void member_sizes_are_bounded(void)
{
    static char text[5000];
    unsigned char *data, *out = NULL, *cd;
    size_t n, got = 0;
    char why[128], path[128];
    zip_writer *z;
    memset(text, 'a', sizeof text - 1);
    snprintf(path, sizeof path, "%s", in_dir("sizes.zip"));
    CHECK(zip_open(&z, path) == 0 && zip_add(z, "m.txt", text, sizeof text - 1, 1) == 0 && zip_close(z, 1) == 0);
    data = read_whole_file(path, &n);
    CHECK(data && n > 22);
    if (!data || n <= 22) { free(data); return; }
    CHECK(zip_member(data, n, "m.txt", &out, &got, why) == 0 && got == sizeof text - 1 && !memcmp(out, text, got));
    free(out);
    /* the central record (APPNOTE 4.3.12): the end record's offset at 16, the member's uncompressed size at 24 */
    cd = data + (data[n - 6] | data[n - 5] << 8 | data[n - 4] << 16 | (size_t)data[n - 3] << 24);
    cd[24] = 0xff; cd[25] = 0xff; cd[26] = 0xff; cd[27] = 0x3f; /* 1 GiB - 1 from a few bytes */
    out = NULL;
    CHECK(zip_member(data, n, "m.txt", &out, &got, why) < 0 && !out && strstr(why, "more than this reader takes"));
    cd[27] = 0x7f; /* 2 GiB: over the cap whatever the ratio */
    CHECK(zip_member(data, n, "m.txt", &out, &got, why) < 0 && !out && strstr(why, "more than this reader takes"));
    free(data);
    remove(path);
}

/* Random bytes of many sizes around deflate's block and window sizes, and
   runs; deflated and stored. */
static void unzip_finds_every_member_intact(void)
{
    static const size_t sizes[] = {0,     1,     2,     3,     4,     5,     7,      8,      31,     255,
                                   256,   257,   1000,  4095,  32767, 32768, 32769,  65535,  65536,  65537,
                                   70000, 99999, 65536 * 3 + 5, 262157, 1 << 20};
    archive *a = (archive *)calloc(1, sizeof *a);
    char name[64];
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        snprintf(name, sizeof name, "random/%zu.bin", sizes[k]);
        fill_random(add_member(a, name, sizes[k], k % 2, k % 2 ? -1 : 0));
        snprintf(name, sizeof name, "runs/%zu.bin", sizes[k]);
        fill_runs(add_member(a, name, sizes[k], 1, sizes[k] > 2000 ? 8 : -1));
    }
    for (int layer = 0; layer < 100; layer += 33) {
        snprintf(name, sizeof name, "masks/8bit_%d.raw", layer);
        add_mask(a, name, 1920, 1080, 8, layer);
        snprintf(name, sizeof name, "masks/1bit_%d.raw", layer);
        add_mask(a, name, 3840, 2400, 1, layer);
    }
    add_mask(a, "masks/wide_rows.raw", 40000, 20, 8, 50); /* rows longer than the window */
    job_like(a);
    CHECK(write_archive(in_dir("all.zip"), a) == 0);
    check_layout(in_dir("all.zip"), a);
    unzip_tests(in_dir("all.zip"));
    for (int i = 0; i < a->count && !check_case_failed(); i++) unzip_member_matches(in_dir("all.zip"), &a->m[i]);
    remove(in_dir("all.zip"));
    free_members(a);
    free(a);
}

/* All 300 extracted at once into their folders. */
static void unzip_extracts_three_hundred_members(void)
{
    archive *a = (archive *)calloc(1, sizeof *a);
    char *argv[] = {(char *)"unzip", (char *)"-q", NULL, (char *)"-d", NULL, NULL};
    char out[128];
    three_hundred_members(a);
    CHECK(write_archive(in_dir("many.zip"), a) == 0);
    unzip_tests(in_dir("many.zip"));
    snprintf(out, sizeof out, "%s", in_dir("out"));
    argv[2] = (char *)in_dir("many.zip");
    argv[4] = out;
    CHECK(tool_run("unzip", argv, in_dir("unzip.log"), in_dir("unzip.log")) == 0);
    for (int i = 0; i < a->count; i++) {
        char path[256];
        size_t n;
        unsigned char *got;
        snprintf(path, sizeof path, "%s/%s", out, a->m[i].name);
        got = read_whole_file(path, &n);
        CHECKF(got && n == a->m[i].size && !memcmp(got, a->m[i].data, n), "%s: extracted %zu bytes of %zu%s", path,
               n, a->m[i].size, got && n == a->m[i].size ? ", bytes differ" : "");
        free(got);
    }
    remove_tree(out);
    remove(in_dir("unzip.log"));
    remove(in_dir("many.zip"));
    free_members(a);
    free(a);
}

void test_zip(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/adaslice-zip-XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("test_zip: mkdtemp");
        return;
    }
    RUN(archives_are_laid_out_as_the_appnote_says);
    RUN(three_hundred_members_are_listed);
    RUN(bad_members_are_refused);
    RUN(member_sizes_are_bounded);
    RUN_NEEDING("unzip", unzip_finds_every_member_intact);
    RUN_NEEDING("unzip", unzip_extracts_three_hundred_members);
    remove_tree(dir);
}
