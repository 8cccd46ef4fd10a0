/* Tests of the PNG writer (host/codec/png.c). Every image is decoded by an
   independent decoder, OpenImageIO's oiiotool (libpng and zlib underneath,
   which also check the chunk CRCs and the Adler-32), converted to 8-bit PGM
   and compared pixel for pixel; oiiotool shows 1-bit pixels as 0 and 255.
   Without oiiotool the round-trip cases fail: install openimageio-tools. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp, posix_spawn */
#endif
#include "util.h"
#include "check.h"
#include "maskgen.h"
#include "../host/codec/inflate.h"
#include "../host/codec/png.h"
#include "../adaslice.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

static char dir[64];

static uint32_t rng_state = 12345;

static uint32_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}

static int write_file(const char *path, const unsigned char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    int ok = f && fwrite(data, 1, size, f) == size;
    if (f && fclose(f) != 0) ok = 0;
    return ok;
}


/* ---- images and the round trip ------------------------------------------ */

typedef struct image {
    char png[128], pgm[128]; /* DIR/name.png, DIR/name.pgm */
    int width, height, bits;
    size_t stride;
    unsigned char *pixels;
} image;

enum { MAX_IMAGES = 24 };

typedef struct batch {
    image im[MAX_IMAGES];
    int count;
} batch;

/* A new image of the batch, its rows `pad` bytes longer than needed, filled
   with garbage that must not reach the file. */
static image *add(batch *b, const char *name, int width, int height, int bits, size_t pad)
{
    image *im = &b->im[b->count];
    size_t size;
    if (b->count++ == MAX_IMAGES) {
        fprintf(stderr, "test_png: more than %d images in a batch\n", MAX_IMAGES);
        abort();
    }
    snprintf(im->png, sizeof im->png, "%s/%s.png", dir, name);
    snprintf(im->pgm, sizeof im->pgm, "%s/%s.pgm", dir, name);
    im->width = width;
    im->height = height;
    im->bits = bits;
    im->stride = (bits == 8 ? (size_t)width : ((size_t)width + 7) / 8) + pad;
    size = im->stride * (size_t)height;
    im->pixels = (unsigned char *)malloc(size);
    for (size_t i = 0; im->pixels && i < size; i++) im->pixels[i] = (unsigned char)rng();
    return im;
}

static int pixel(const image *im, int x, int y)
{
    const unsigned char *row = im->pixels + (size_t)y * im->stride;
    return im->bits == 8 ? row[x] : (row[x >> 3] >> (7 - (x & 7)) & 1) * 255;
}

static void set_pixel(image *im, int x, int y, int v)
{
    unsigned char *row = im->pixels + (size_t)y * im->stride;
    if (im->bits == 8) row[x] = (unsigned char)v;
    else if (v >= 128) row[x >> 3] |= (unsigned char)(0x80 >> (x & 7));
    else row[x >> 3] &= (unsigned char)~(0x80 >> (x & 7));
}

/* Coverage (w x h bytes) into the image: as is at 8 bits, packed at 1 bit. */
static void from_coverage(image *im, const unsigned char *coverage)
{
    if (!im->pixels) return;
    if (im->bits == 1) mask_pack(coverage, im->width, im->height, im->pixels, im->stride);
    for (int y = 0; im->bits == 8 && y < im->height; y++)
        memcpy(im->pixels + (size_t)y * im->stride, coverage + (size_t)y * (size_t)im->width, (size_t)im->width);
}

/* Runs oiiotool with args, its output in DIR/oiiotool.log; 0 when it exits 0. */
static int run_oiiotool(char **args)
{
    char log[sizeof dir + 16];
    posix_spawn_file_actions_t fa;
    pid_t pid;
    int st = 0, rc;
    snprintf(log, sizeof log, "%s/oiiotool.log", dir);
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    fflush(NULL);
    rc = posix_spawnp(&pid, "oiiotool", &fa, NULL, args, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc == 0 && waitpid(pid, &st, 0) == pid && WIFEXITED(st) && WEXITSTATUS(st) == 0) return 0;
    if (rc == ENOENT || (rc == 0 && WIFEXITED(st) && WEXITSTATUS(st) == 127)) {
        CHECKF(0, "oiiotool not found: the PNG round trips need OpenImageIO; install it with "
                  "`apt-get install -y openimageio-tools`");
    } else {
        size_t n;
        char *text = (char *)read_whole_file(log, &n), *error = NULL;
        if (text) {
            text[n] = 0;
            error = strstr(text, "ERROR");
            if (error && strchr(error, '\n')) *strchr(error, '\n') = 0;
        }
        CHECKF(0, "oiiotool failed: %s", error ? error : text ? text : "(no output)");
        free(text);
    }
    return -1;
}

/* The P5 PGM (channels 1) or P6 PPM (3) at path as w x h pixels of
   maxval 255, or NULL. */
static unsigned char *read_pnm(const char *path, int w, int h, int channels)
{
    size_t n, size = (size_t)w * (size_t)h * (size_t)channels;
    unsigned char *s = read_whole_file(path, &n), *pixels = NULL;
    int width, height, maxval, used = 0;
    if (s) {
        s[n] = 0;
        if (sscanf((char *)s, channels == 3 ? "P6 %d %d %d%n" : "P5 %d %d %d%n", &width, &height, &maxval,
                   &used) == 3 && width == w && height == h && maxval == 255 && n - (size_t)used - 1 == size &&
            (pixels = (unsigned char *)malloc(size)) != NULL)
            memcpy(pixels, s + used + 1, size);
    }
    free(s);
    return pixels;
}

/* How an image is coded: png_encode_gray; png_encode_mask (8-bit whatever
   came in); png_encode_layer (the PNG of a job directory's layer). */
enum { AS_GRAY, AS_MASK, AS_LAYER };

static int encode_as(const image *im, int as, unsigned char **png, size_t *size)
{
    png_layer layer;
    if (as != AS_LAYER) return (as == AS_MASK ? png_encode_mask : png_encode_gray)(im->pixels, im->width, im->height,
                                                                                  im->stride, im->bits, png, size);
    if (png_encode_layer(im->pixels, im->width, im->height, im->stride, im->bits, NULL, &layer)) return -1;
    free(layer.rle);
    *png = layer.png;
    *size = layer.png_size;
    return 0;
}

/* Encodes every image `as` given, has oiiotool decode them all in one run
   and compares every pixel; frees the images. */
static void round_trip_as(batch *b, int as)
{
    char *args[2 + 5 * MAX_IMAGES] = {(char *)"oiiotool"};
    int n = 1, encoded = 1;
    for (int i = 0; i < b->count; i++) {
        image *im = &b->im[i];
        unsigned char *png = NULL;
        size_t size = 0;
        if (!im->pixels || encode_as(im, as, &png, &size) || !write_file(im->png, png, size)) {
            CHECKF(0, "cannot encode or write %s", im->png);
            encoded = 0;
        }
        free(png);
        args[n++] = im->png;
        args[n++] = (char *)"-d";
        args[n++] = (char *)"uint8";
        args[n++] = (char *)"-o";
        args[n++] = im->pgm;
    }
    args[n] = NULL;
    if (encoded && run_oiiotool(args) == 0) {
        for (int i = 0; i < b->count; i++) {
            image *im = &b->im[i];
            unsigned char *got = read_pnm(im->pgm, im->width, im->height, 1);
            long wrong = 0, first_x = -1, first_y = -1;
            CHECKF(got, "%s: oiiotool wrote no %dx%d 8-bit PGM", im->pgm, im->width, im->height);
            for (int y = 0; got && y < im->height; y++)
                for (int x = 0; x < im->width; x++)
                    if (got[(size_t)y * (size_t)im->width + x] != pixel(im, x, y) && wrong++ == 0) {
                        first_x = x;
                        first_y = y;
                    }
            CHECKF(wrong == 0, "%s (%dx%d, %d-bit): %ld pixels differ, the first at (%ld, %ld)", im->png,
                   im->width, im->height, im->bits, wrong, first_x, first_y);
            free(got);
        }
    }
    for (int i = 0; i < b->count; i++) {
        remove(b->im[i].png);
        remove(b->im[i].pgm);
        free(b->im[i].pixels);
    }
    b->count = 0;
}

static void round_trip(batch *b) { round_trip_as(b, AS_GRAY); }

/* A disc of the given share of a w x h image, centred, anti-aliased. */
static unsigned char *disc_coverage(int w, int h, double share)
{
    unsigned char *g = (unsigned char *)calloc((size_t)w * (size_t)h, 1);
    if (g) mask_disc(g, w, h, w / 2.0, h / 2.0, sqrt(share * w * h / 3.14159265358979));
    return g;
}

static void fill(image *im, int (*f)(int x, int y))
{
    for (int y = 0; im->pixels && y < im->height; y++)
        for (int x = 0; x < im->width; x++) set_pixel(im, x, y, f(x, y));
}

static int black(int x, int y) { (void)x; (void)y; return 0; }
static int white(int x, int y) { (void)x; (void)y; return 255; }
static int noise(int x, int y) { (void)x; (void)y; return (int)(rng() & 255); }
static int checker1(int x, int y) { return (x ^ y) & 1 ? 255 : 0; }
static int checker8(int x, int y) { return (x >> 3 ^ y >> 3) & 1 ? 255 : 0; }
static int hstripes(int x, int y) { (void)x; return y % 5 < 2 ? 255 : 0; }
static int vstripes(int x, int y) { (void)y; return x % 7 < 3 ? 255 : 0; }
static int gradient(int x, int y) { return (x + 3 * y) & 255; }
/* Rows that repeat rows 5 to 40 back, mostly: far matches for the hash */
static int far_rows(int x, int y) { return (int)((x * 2654435761u ^ (uint32_t)(y % 37) * 40503u) >> 7 & 255); }

/* Byte k about Fibonacci(k + 1) times, shuffled: an unlimited Huffman code
   for these literals would need more than deflate's 15 bits. */
static void fill_skewed(image *im)
{
    size_t n = (size_t)im->width * (size_t)im->height, i = 0;
    uint32_t f0 = 1, f1 = 1;
    for (int v = 0; i < n; v++, f1 += f0, f0 = f1 - f0)
        for (uint32_t k = 0; k < f0 && i < n; k++) im->pixels[i++] = (unsigned char)v;
    for (i = n - 1; i > 0; i--) {
        size_t j = rng() % (i + 1);
        unsigned char t = im->pixels[i];
        im->pixels[i] = im->pixels[j];
        im->pixels[j] = t;
    }
}

/* ---- cases -------------------------------------------------------------- */

static void crc32_and_adler32_match_their_definitions(void)
{
    static unsigned char data[70000];
    uint32_t crc_table[256], crc = 0xffffffffu, a = 1, b = 0;
    CHECK(adaslice_crc32(0, "123456789", 9) == 0xCBF43926u);
    CHECK(png_adler32(1, "Wikipedia", 9) == 0x11E60398u);
    CHECK(adaslice_crc32(0, "", 0) == 0 && png_adler32(1, "", 0) == 1);
    CHECK(adaslice_crc32(adaslice_crc32(0, "1234", 4), "56789", 5) == 0xCBF43926u);
    /* runs of 8+ equal bytes take a shortcut in the Adler-32: check it against
       the definition over data of runs and noise, longer than 5552 bytes */
    for (size_t i = 0; i < sizeof data;) {
        size_t run = 1 + rng() % 3000;
        int v = (int)(rng() % 3 ? (rng() & 1) * 255 : rng() & 255), random = rng() % 4 == 0;
        for (; run-- > 0 && i < sizeof data; i++) data[i] = (unsigned char)(random ? rng() : (uint32_t)v);
    }
    for (size_t i = 0; i < sizeof data; i++) {
        a = (a + data[i]) % 65521;
        b = (b + a) % 65521;
    }
    CHECK(png_adler32(1, data, sizeof data) == (b << 16 | a));
    CHECK(png_adler32(png_adler32(1, data, 12345), data + 12345, sizeof data - 12345) == (b << 16 | a));
    for (uint32_t i = 0; i < 256; i++) {
        uint32_t c = i;
        for (int k = 0; k < 8; k++) c = c >> 1 ^ (c & 1 ? 0xEDB88320u : 0);
        crc_table[i] = c;
    }
    for (size_t i = 0; i < sizeof data; i++) crc = crc_table[(crc ^ data[i]) & 255] ^ crc >> 8;
    CHECK(adaslice_crc32(0, data, sizeof data) == ~crc);
}

static void bad_arguments_are_refused(void)
{
    unsigned char px[64] = {0}, *out = px;
    size_t size = 1;
    CHECK(png_encode_gray(px, 4, 4, 4, 4, &out, &size) == -1 && !out && size == 0);
    CHECK(png_encode_gray(px, 0, 4, 4, 8, &out, &size) == -1);
    CHECK(png_encode_gray(px, 4, 0, 4, 8, &out, &size) == -1);
    CHECK(png_encode_gray(px, 4, 4, 3, 8, &out, &size) == -1);
    CHECK(png_encode_gray(px, 17, 2, 2, 1, &out, &size) == -1);
    CHECK(png_encode_gray(NULL, 4, 4, 4, 8, &out, &size) == -1);
    CHECK(png_encode_gray(px, 65536, 65536, 65536, 8, &out, &size) == -1 && !out); /* 4 GB of rows */
    out = px;
    size = 1;
    CHECK(png_encode_mask(px, 4, 4, 4, 4, &out, &size) == -1 && !out && size == 0);
    CHECK(png_encode_mask(px, 0, 4, 4, 8, &out, &size) == -1);
    CHECK(png_encode_mask(px, 4, 4, 3, 8, &out, &size) == -1);
    CHECK(png_encode_mask(px, 17, 2, 2, 1, &out, &size) == -1);
    CHECK(png_encode_mask(NULL, 4, 4, 4, 8, &out, &size) == -1);
    CHECK(png_encode_mask(px, 1 << 24, 1, 1 << 24, 8, &out, &size) == -1 && !out);
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* The file's layout: signature, IHDR, IDAT with a zlib header, IEND, every
   chunk's CRC; and the padding past the width and the stride do not matter. */
/* A 13 x 5 1-bit image, clean and with garbage in its row padding. */
static void layout_images(batch *b, image **clean, image **padded)
{
    *clean = add(b, "clean", 13, 5, 1, 0);
    *padded = add(b, "padded", 13, 5, 1, 3);
    for (int y = 0; y < 5; y++)
        for (int x = 0; x < 13; x++) {
            int v = (x * y + x) % 3 ? 255 : 0;
            set_pixel(*clean, x, y, v);
            set_pixel(*padded, x, y, v);
        }
    for (int y = 0; y < 5; y++) (*clean)->pixels[y * (*clean)->stride + 1] &= 0xF8; /* zero padding bits */
}

static void chunks_are_laid_out_as_the_specification_says(void)
{
    static const unsigned char sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    batch b = {0};
    image *clean, *padded;
    unsigned char *png = NULL, *png2 = NULL;
    size_t size = 0, size2 = 0, pos = 8;
    int chunks = 0, i;
    layout_images(&b, &clean, &padded);
    CHECK(png_encode_gray(clean->pixels, 13, 5, clean->stride, 1, &png, &size) == 0);
    CHECK(png_encode_gray(padded->pixels, 13, 5, padded->stride, 1, &png2, &size2) == 0);
    CHECK(png && png2 && size == size2 && !memcmp(png, png2, size));
    CHECK(size > 8 && !memcmp(png, sig, 8));
    while (png && pos + 12 <= size) {
        uint32_t len = be32(png + pos);
        const unsigned char *type = png + pos + 4, *body = type + 4;
        if (pos + 12 + len > size) break;
        CHECKF(adaslice_crc32(0, type, len + 4) == be32(body + len), "chunk %d: bad CRC", chunks);
        if (chunks == 0)
            CHECK(!memcmp(type, "IHDR", 4) && len == 13 && be32(body) == 13 && be32(body + 4) == 5 &&
                  body[8] == 1 && body[9] == 0 && body[10] == 0 && body[11] == 0 && body[12] == 0);
        if (chunks == 1)
            CHECK(!memcmp(type, "IDAT", 4) && len > 6 && (body[0] & 15) == 8 && (body[0] << 8 | body[1]) % 31 == 0);
        if (chunks == 2) CHECK(!memcmp(type, "IEND", 4) && len == 0 && pos + 12 == size);
        pos += 12 + len;
        chunks++;
    }
    CHECK(chunks == 3);
    free(png);
    free(png2);
    for (i = 0; i < b.count; i++) free(b.im[i].pixels);
}

/* The same two images, decoded by OpenImageIO. */
static void laid_out_images_decode_in_oiiotool(void)
{
    batch b = {0};
    image *clean, *padded;
    layout_images(&b, &clean, &padded);
    round_trip(&b);
}

static void small_and_odd_images_decode_in_oiiotool(void)
{
    static const int widths[] = {1, 7, 8, 9, 15, 17, 31, 33};
    batch b = {0};
    char name[48];
    for (int bits = 1; bits <= 8; bits += 7) {
        snprintf(name, sizeof name, "one_black_%d", bits);
        fill(add(&b, name, 1, 1, bits, 0), black);
        snprintf(name, sizeof name, "one_white_%d", bits);
        fill(add(&b, name, 1, 1, bits, 2), white);
        snprintf(name, sizeof name, "random_64x48_%d", bits);
        fill(add(&b, name, 64, 48, bits, 5), noise);
    }
    for (int i = 0; i < 8; i++) {
        snprintf(name, sizeof name, "random1_w%d", widths[i]);
        fill(add(&b, name, widths[i], 1 + i % 3 * 2, 1, (size_t)i % 2), noise);
        snprintf(name, sizeof name, "checker1_w%d", widths[i]);
        fill(add(&b, name, widths[i], 1 + i, 1, 0), checker1);
    }
    round_trip(&b);
}

static void masks_decode_in_oiiotool(void)
{
    const int w = 2560, h = 1440;
    unsigned char *disc = disc_coverage(w, h, 0.25), *scene = (unsigned char *)malloc(2561 * 1440);
    batch b = {0};
    image *im;
    CHECK(disc && scene);
    if (!disc || !scene) { free(disc); free(scene); return; }
    from_coverage(add(&b, "disc_aa8", w, h, 8, 0), disc);
    from_coverage(add(&b, "disc1", w, h, 1, 0), disc);
    im = add(&b, "disc_hard8", w, h, 8, 7);
    fill(im, black);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) set_pixel(im, x, y, disc[(size_t)y * w + x] >= 128 ? 255 : 0);
    mask_scene(scene, 2561, 1440, 30);
    from_coverage(add(&b, "scene1_w2561", 2561, 1440, 1, 1), scene);
    from_coverage(add(&b, "scene8_w2561", 2561, 1440, 8, 0), scene);
    fill(add(&b, "black1", w, h, 1, 0), black);
    fill(add(&b, "white1", w, h, 1, 0), white);
    fill(add(&b, "black8", w, h, 8, 0), black);
    fill(add(&b, "white8", w, h, 8, 0), white);
    from_coverage(add(&b, "disc_row8", w, 1, 8, 0), disc + (size_t)(h / 2) * w);
    from_coverage(add(&b, "disc_row1", w, 1, 1, 0), disc + (size_t)(h / 2) * w);
    fill(add(&b, "column1", 1, h, 1, 0), hstripes);
    fill(add(&b, "column8", 1, h, 8, 0), hstripes);
    round_trip(&b);
    free(disc);
    free(scene);
}

static void patterns_decode_in_oiiotool(void)
{
    const int w = 2560, h = 1440;
    batch b = {0};
    image *im;
    for (int bits = 1; bits <= 8; bits += 7) {
        char name[48];
        snprintf(name, sizeof name, "checker1_%d", bits);
        fill(add(&b, name, w, h, bits, 0), checker1);
        snprintf(name, sizeof name, "checker8_%d", bits);
        fill(add(&b, name, w, h, bits, 0), checker8);
        snprintf(name, sizeof name, "hstripes_%d", bits);
        fill(add(&b, name, w, h, bits, 0), hstripes);
        snprintf(name, sizeof name, "vstripes_%d", bits);
        fill(add(&b, name, w, h, bits, 0), vstripes);
    }
    fill(add(&b, "gradient8", w, h, 8, 0), gradient);
    fill(add(&b, "far_rows8", 500, 300, 8, 0), far_rows);
    im = add(&b, "skewed8", 500, 400, 8, 0);
    if (im->pixels) fill_skewed(im);
    /* rows longer than deflate's 32 KB window: no match one row up */
    fill(add(&b, "wide8", 40000, 4, 8, 0), hstripes);
    fill(add(&b, "wide1", 300000, 3, 1, 0), vstripes);
    round_trip(&b);
}

/* The run-driven 8-bit encoder of the ChiTu and Prusa jobs on masks, their
   worst cases (a pixel checkerboard: a run per pixel; noise; rows that
   repeat and rows that do not; a width at deflate's window) and padded
   strides, 1-bit and 8-bit in. */
static void masks_from_runs_decode_in_oiiotool(void)
{
    const int w = 2560, h = 1440;
    unsigned char *disc = disc_coverage(w, h, 0.25), *scene = (unsigned char *)malloc(2561 * 1440);
    batch b = {0};
    CHECK(disc && scene);
    if (!disc || !scene) { free(disc); free(scene); return; }
    from_coverage(add(&b, "run_disc_aa8", w, h, 8, 0), disc);
    from_coverage(add(&b, "run_disc1", w, h, 1, 3), disc);
    mask_scene(scene, 2561, 1440, 30);
    from_coverage(add(&b, "run_scene1_w2561", 2561, 1440, 1, 1), scene);
    from_coverage(add(&b, "run_scene8_w2561", 2561, 1440, 8, 5), scene);
    fill(add(&b, "run_black1", w, h, 1, 0), black);
    fill(add(&b, "run_white1", w, h, 1, 0), white);
    fill(add(&b, "run_white8", w, h, 8, 0), white);
    fill(add(&b, "run_checker1", w, 64, 1, 0), checker1);
    fill(add(&b, "run_checker8", w, 64, 8, 0), checker8);
    fill(add(&b, "run_hstripes1", w, h, 1, 0), hstripes);
    fill(add(&b, "run_vstripes8", w, 200, 8, 0), vstripes);
    fill(add(&b, "run_gradient8", 700, 300, 8, 0), gradient);
    add(&b, "run_noise1", 999, 77, 1, 2);
    add(&b, "run_noise8", 333, 55, 8, 0);
    fill(add(&b, "run_column1", 1, h, 1, 0), hstripes);
    fill(add(&b, "run_window8", 32767, 3, 8, 0), vstripes);
    fill(add(&b, "run_wide1", 40000, 4, 1, 0), hstripes); /* rows past deflate's window: no row copies */
    fill(add(&b, "run_wide8", 33000, 3, 8, 0), vstripes);
    round_trip_as(&b, AS_MASK);
    free(disc);
    free(scene);
}

/* Noise does not compress: stored blocks, a little larger than the data. */
static void noise_decodes_in_oiiotool(void)
{
    const int w = 2560, h = 1440;
    batch b = {0};
    image *im8 = add(&b, "noise8", w, h, 8, 0), *im1 = add(&b, "noise1", w, h, 1, 0);
    unsigned char *png = NULL;
    size_t size = 0, raw = (size_t)(w + 1) * h;
    fill(im8, noise);
    fill(im1, noise);
    CHECK(im8->pixels && png_encode_gray(im8->pixels, w, h, im8->stride, 8, &png, &size) == 0);
    CHECKF(size > raw && size < raw + raw / 1000 + 100, "noise, 8-bit: %zu bytes from %zu", size, raw);
    free(png);
    fill(add(&b, "noise1_3840x2400", 3840, 2400, 1, 0), noise);
    round_trip(&b);
}

/* The IDAT of an image's PNG read back with the project's inflate (written
   for the 3MF's ZIP members, apart from the encoder): every row filter None
   or Up, the pixels and the zlib Adler-32 as the definitions say. */
static void decodes_by_inflate(const unsigned char *png, size_t size, const image *im)
{
    size_t row_bytes = im->bits == 8 ? (size_t)im->width : ((size_t)im->width + 7) / 8, n = (row_bytes + 1) * im->height;
    size_t at = 8 + 25, len = at + 8 <= size ? be32(png + at) : 0;
    unsigned char *raw = (unsigned char *)malloc(n), *prev = (unsigned char *)calloc(row_bytes, 1);
    unsigned char last_mask = (unsigned char)(im->bits == 1 && im->width % 8 ? 0xFF << (8 - im->width % 8) : 0xFF);
    uint32_t a = 1, b = 0;
    long wrong = -1;
    CHECKF(len > 6 && at + 12 + len <= size && !memcmp(png + at + 4, "IDAT", 4), "%s: no IDAT after IHDR", im->png);
    if (!raw || !prev || !(len > 6 && at + 12 + len <= size)) { free(raw); free(prev); return; }
    CHECKF(inflate_bytes(png + at + 10, len - 6, raw, n) == 0, "%s: inflate refuses the IDAT or ends short of %zu bytes",
           im->png, n);
    for (size_t i = 0; i < n; i++) a = (a + raw[i]) % 65521, b = (b + a) % 65521;
    CHECKF(be32(png + at + 8 + len - 4) == (b << 16 | a), "%s: Adler-32 %08x, the data's %08x", im->png,
           (unsigned)be32(png + at + 8 + len - 4), (unsigned)(b << 16 | a));
    for (int y = 0; y < im->height && wrong < 0; y++) {
        unsigned char *row = raw + (size_t)y * (row_bytes + 1), filter = row[0];
        const unsigned char *src = im->pixels + (size_t)y * im->stride;
        for (size_t x = 0; x < row_bytes; x++) {
            unsigned char v = (unsigned char)(row[1 + x] + (filter == 2 ? prev[x] : 0)), want = src[x];
            if (x + 1 == row_bytes) v &= last_mask, want &= last_mask;
            if (filter > 2 || filter == 1 || v != want) { wrong = y; break; }
            prev[x] = v;
        }
    }
    CHECKF(wrong < 0, "%s: row %ld is not the image's", im->png, wrong);
    free(raw);
    free(prev);
}

static int band_ends(int x, int y) /* lit at both ends, a span between that moves every row */
{
    int from = 900 + (y * 37) % 700;
    return x < 80 || x >= 3760 || (x >= from && x < from + 300 + y % 3) ? 255 : 0;
}
static int wide_stripes(int x, int y) { (void)y; return x % 97 < 40 ? 255 : 0; }

/* Layers as the coder meets them, 3840 x 2400 and a width past a byte: all
   dark (one run through every row boundary), all lit, every row the same
   (one copy from a row back through the whole image), and rows lit at both
   ends around a span that moves, whose shared ends go as copies from a row
   back that run from one row's end into the next row's start. Decoded by
   inflate and by OpenImageIO, 1-bit and as the 8-bit masks of the ChiTu and
   Prusa jobs; a dark layer costs about 2 bits a 258-byte copy. */
static void layers_decode_through_row_boundaries(void)
{
    batch b = {0};
    const int w = 3840, h = 2400;
    for (int as_mask = 0; as_mask <= 1; as_mask++) {
        char name[48];
        snprintf(name, sizeof name, "dark_%d", as_mask);
        fill(add(&b, name, w, h, 1, 0), black);
        snprintf(name, sizeof name, "lit_w3839_%d", as_mask);
        fill(add(&b, name, w - 1, h, 1, 1), white);
        snprintf(name, sizeof name, "same_rows_%d", as_mask);
        fill(add(&b, name, w, h, 1, 0), wide_stripes);
        snprintf(name, sizeof name, "band_ends_%d", as_mask);
        fill(add(&b, name, w, h, 1, 0), band_ends);
        snprintf(name, sizeof name, "band_ends_w3837_%d", as_mask);
        fill(add(&b, name, w - 3, 60, 1, 2), band_ends);
        for (int i = 0; i < b.count && !as_mask; i++) {
            unsigned char *png = NULL;
            size_t size = 0;
            image *im = &b.im[i];
            CHECK(im->pixels && png_encode_gray(im->pixels, im->width, im->height, im->stride, 1, &png, &size) == 0);
            if (png) decodes_by_inflate(png, size, im);
            if (png && i == 0)
                CHECKF(size < (size_t)(w / 8 + 1) * h / 258 * 2 / 8 + 200, "a dark layer: %zu bytes", size);
            free(png);
        }
        round_trip_as(&b, as_mask ? AS_MASK : AS_GRAY);
    }
}

/* A job directory's layers (png_encode_layer, whose PNG comes from the
   same one reading of each row as masks.rle's code and the CRC), 3840 x
   2400 and widths past a byte, at 1 and 8 bits: all dark, all lit, every
   row the same, rows that repeat the row above in pixels and not in the
   padding bits of their last byte, a span that moves every row, an
   anti-aliased disc. Decoded by inflate and by OpenImageIO. */
static void job_layers_decode_by_inflate_and_in_oiiotool(void)
{
    const int w = 3840, h = 2400;
    unsigned char *disc = disc_coverage(w, h, 0.25);
    batch b = {0};
    CHECK(disc != NULL);
    for (int bits = 1; bits <= 8; bits += 7) {
        char name[48];
        snprintf(name, sizeof name, "layer_dark%d", bits);
        fill(add(&b, name, w, h, bits, 0), black);
        snprintf(name, sizeof name, "layer_lit_w3839_%d", bits);
        fill(add(&b, name, w - 1, h, bits, 1), white);
        snprintf(name, sizeof name, "layer_same_rows%d", bits);
        fill(add(&b, name, w, h, bits, 0), wide_stripes);
        snprintf(name, sizeof name, "layer_padding_differs_w3837_%d", bits); /* add() leaves the padding random */
        fill(add(&b, name, w - 3, 300, bits, 2), wide_stripes);
        snprintf(name, sizeof name, "layer_band_ends%d", bits);
        fill(add(&b, name, w, h, bits, 0), band_ends);
        snprintf(name, sizeof name, "layer_disc%d", bits);
        if (disc) from_coverage(add(&b, name, w, h, bits, 0), disc);
    }
    for (int i = 0; i < b.count; i++) {
        unsigned char *png = NULL;
        size_t size = 0;
        CHECKF(b.im[i].pixels && encode_as(&b.im[i], AS_LAYER, &png, &size) == 0, "%s: not coded", b.im[i].png);
        if (png) decodes_by_inflate(png, size, &b.im[i]);
        free(png);
    }
    round_trip_as(&b, AS_LAYER);
    free(disc);
}

/* ---- RGB, for previews ---------------------------------------------------- */

/* A picture like a preview: a dark background and a shaded ball. */
static int shaded(int x, int y, int c, int w, int h)
{
    double dx = (x - w / 2.0) / (w / 3.0), dy = (y - h / 2.0) / (h / 3.0), r2 = dx * dx + dy * dy;
    if (r2 >= 1) return 30 + 8 * c;
    return (int)((0.3 + 0.7 * sqrt(1 - r2) * (0.6 - 0.4 * dx - 0.3 * dy)) * (200 + 25 * c)) & 255;
}
static int bands(int x, int y, int c, int w, int h) { (void)y; (void)w; (void)h; return (x / 7 * (c + 1) * 40) & 255; }
static int rgb_noise(int x, int y, int c, int w, int h)
{
    (void)x; (void)y; (void)c; (void)w; (void)h;
    return rng() & 255;
}

static unsigned char *rgb_image(int w, int h, int (*f)(int x, int y, int c, int w, int h))
{
    unsigned char *rgb = (unsigned char *)malloc((size_t)w * (size_t)h * 3);
    for (int y = 0; rgb && y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++)
                rgb[((size_t)y * (size_t)w + (size_t)x) * 3 + (size_t)c] = (unsigned char)f(x, y, c, w, h);
    return rgb;
}

/* IHDR says 8-bit truecolour, every chunk's CRC holds; bad sizes are refused. */
static void rgb_header_says_truecolour(void)
{
    unsigned char *rgb = rgb_image(5, 3, bands), *png = NULL, *out = rgb;
    size_t size = 0, pos = 8, one = 1;
    int chunks = 0;
    CHECK(rgb && png_encode_rgb(rgb, 5, 3, &png, &size) == 0);
    while (png && pos + 12 <= size) {
        uint32_t len = be32(png + pos);
        const unsigned char *type = png + pos + 4, *body = type + 4;
        if (pos + 12 + len > size) break;
        CHECKF(adaslice_crc32(0, type, len + 4) == be32(body + len), "chunk %d: bad CRC", chunks);
        if (chunks == 0)
            CHECK(!memcmp(type, "IHDR", 4) && len == 13 && be32(body) == 5 && be32(body + 4) == 3 && body[8] == 8 &&
                  body[9] == 2 && body[10] == 0 && body[11] == 0 && body[12] == 0);
        pos += 12 + len;
        chunks++;
    }
    CHECK(chunks == 3 && pos == size);
    CHECK(png_encode_rgb(rgb, 0, 3, &out, &one) == -1 && !out && one == 0);
    CHECK(png_encode_rgb(rgb, 5, 0, &out, &size) == -1);
    CHECK(png_encode_rgb(NULL, 5, 3, &out, &size) == -1);
    CHECK(png_encode_rgb(rgb, 40000, 40000, &out, &size) == -1 && !out); /* 4.8 GB of rows */
    free(rgb);
    free(png);
}

/* Previews at the formats' sizes and odd small ones, read back through
   OpenImageIO (as P6 PPM) pixel for pixel. */
static void rgb_images_decode_in_oiiotool(void)
{
    static const struct { int w, h; int (*f)(int, int, int, int, int); } cases[] = {
        {1, 1, bands}, {2, 3, rgb_noise}, {7, 5, shaded}, {33, 17, rgb_noise}, {954, 850, shaded},
        {168, 150, shaded}, {400, 400, bands}, {800, 480, rgb_noise}, {3000, 2, shaded},
    };
    enum { N = sizeof cases / sizeof cases[0] };
    char png_path[N][128], ppm_path[N][128], *args[2 + 5 * N] = {(char *)"oiiotool"};
    unsigned char *rgb[N];
    int n = 1, encoded = 1;
    for (int i = 0; i < N; i++) {
        unsigned char *png = NULL;
        size_t size = 0;
        snprintf(png_path[i], sizeof png_path[i], "%s/rgb%d.png", dir, i);
        snprintf(ppm_path[i], sizeof ppm_path[i], "%s/rgb%d.ppm", dir, i);
        rgb[i] = rgb_image(cases[i].w, cases[i].h, cases[i].f);
        if (!rgb[i] || png_encode_rgb(rgb[i], cases[i].w, cases[i].h, &png, &size) ||
            !write_file(png_path[i], png, size)) {
            CHECKF(0, "cannot encode or write %s", png_path[i]);
            encoded = 0;
        }
        free(png);
        args[n++] = png_path[i];
        args[n++] = (char *)"-d";
        args[n++] = (char *)"uint8";
        args[n++] = (char *)"-o";
        args[n++] = ppm_path[i];
    }
    args[n] = NULL;
    if (encoded && run_oiiotool(args) == 0)
        for (int i = 0; i < N; i++) {
            size_t count = (size_t)cases[i].w * (size_t)cases[i].h, wrong = 0, first = 0;
            unsigned char *got = read_pnm(ppm_path[i], cases[i].w, cases[i].h, 3);
            CHECKF(got, "%s: oiiotool wrote no %dx%d 8-bit PPM", ppm_path[i], cases[i].w, cases[i].h);
            for (size_t k = 0; got && k < count; k++)
                if (memcmp(got + 3 * k, rgb[i] + 3 * k, 3) && wrong++ == 0) first = k;
            CHECKF(wrong == 0, "%s (%dx%d RGB): %zu pixels differ, the first at (%zu, %zu)", png_path[i], cases[i].w,
                   cases[i].h, wrong, first % (size_t)cases[i].w, first / (size_t)cases[i].w);
            free(got);
        }
    for (int i = 0; i < N; i++) {
        remove(png_path[i]);
        remove(ppm_path[i]);
        free(rgb[i]);
    }
}

/* A 2560x1440 layer is 460 KB of 1-bit rows or 3.7 MB of 8-bit ones; masks
   must come out at a few KB. The limits are about 1.3-1.5 times the sizes
   measured when they were set (a disc over 25 %: 4.4 KB 1-bit, 13.2 KB 8-bit;
   the bench scene at 30 %: 11.3 KB and 31.7 KB). */
static void compression_stays_within_its_bounds(void)
{
    const int w = 2560, h = 1440;
    static const struct { const char *what; int bits; double share; size_t limit; } cases[] = {
        {"disc 25 %, 1-bit", 1, 0.25, 6000},   {"disc 25 %, 8-bit anti-aliased", 8, 0.25, 20000},
        {"disc 5 %, 1-bit", 1, 0.05, 3000},    {"disc 5 %, 8-bit anti-aliased", 8, 0.05, 11000},
        {"all black, 1-bit", 1, 0, 1000},      {"all black, 8-bit", 8, 0, 5000},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        unsigned char *disc = disc_coverage(w, h, cases[k].share), *png = NULL;
        batch b = {0};
        image *im = add(&b, "disc", w, h, cases[k].bits, 0);
        size_t size = 0;
        if (disc && im->pixels) {
            from_coverage(im, disc);
            CHECK(png_encode_gray(im->pixels, w, h, im->stride, im->bits, &png, &size) == 0);
            CHECKF(size < cases[k].limit, "%s: %zu bytes, more than %zu", cases[k].what, size, cases[k].limit);
        }
        free(png);
        free(disc);
        free(im->pixels);
    }
    {
        unsigned char *scene = (unsigned char *)malloc((size_t)w * h), *png = NULL;
        batch b = {0};
        image *im8 = add(&b, "scene8", w, h, 8, 0), *im1 = add(&b, "scene1", w, h, 1, 0);
        size_t size8 = 0, size1 = 0;
        if (scene && im8->pixels && im1->pixels) {
            mask_scene(scene, w, h, 99); /* the largest: 30 % */
            from_coverage(im8, scene);
            from_coverage(im1, scene);
            CHECK(png_encode_gray(im8->pixels, w, h, im8->stride, 8, &png, &size8) == 0);
            free(png);
            CHECK(png_encode_gray(im1->pixels, w, h, im1->stride, 1, &png, &size1) == 0);
            free(png);
            CHECKF(size8 < 40000 && size1 < 15000, "bench scene: %zu bytes 8-bit, %zu bytes 1-bit", size8, size1);
        }
        free(scene);
        free(im8->pixels);
        free(im1->pixels);
    }
}

static void remove_dir(void)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            char path[sizeof dir + sizeof e->d_name];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            remove(path);
        }
    if (d) closedir(d);
    rmdir(dir);
}

/* The masks adaslice slice writes: the masker's in-memory images, 1-bit and
   4 x 4 anti-aliased, of the bundled hand on a 2560 x 1440 plate, read back
   through OpenImageIO bit for bit. */
static void the_maskers_images_decode_in_oiiotool(void)
{
    adaslice_load_options lo;
    adaslice_mesh m;
    adaslice_error e;
    double a[3], b[3];
    int s, k;
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECKF(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &m, &e) == ADASLICE_OK, "%s", e.message);
    if (!m.triangle_count) return;
    adaslice_mesh_bounds(&m, a, b);
    for (s = 1; s <= 4; s += 3) {
        adaslice_masker mk;
        adaslice_grid g;
        batch bt;
        g = adaslice_grid_plate(&m, 2560, 1440, 0.04725, 0.04725, NULL);
        bt.count = 0;
        CHECK(adaslice_masker_init(&mk, &m, &g, &(adaslice_mask_options){s, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, &e) == ADASLICE_OK);
        for (k = 0; k < 4; k++) {
            char name[32];
            image *im;
            snprintf(name, sizeof name, "hand_s%d_%d", s, k);
            im = add(&bt, name, g.width, g.height, s > 1 ? 8 : 1, 0);
            CHECK(adaslice_masker_slice(&mk, a[2] + (b[2] - a[2]) * (k + 0.5) / 4, &e) == ADASLICE_OK);
            CHECK(mk.lit > 1000 && im->stride == mk.stride);
            if (im->pixels) memcpy(im->pixels, mk.image, mk.stride * (size_t)g.height);
        }
        round_trip(&bt);
        adaslice_masker_free(&mk);
    }
    adaslice_mesh_free(&m);
}

void test_png(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/adaslice-png-XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("test_png: mkdtemp");
        return;
    }
    RUN(crc32_and_adler32_match_their_definitions);
    RUN(bad_arguments_are_refused);
    RUN(chunks_are_laid_out_as_the_specification_says);
    RUN_NEEDING("oiiotool", laid_out_images_decode_in_oiiotool);
    RUN_NEEDING("oiiotool", small_and_odd_images_decode_in_oiiotool);
    RUN_NEEDING("oiiotool", masks_decode_in_oiiotool);
    RUN_NEEDING("oiiotool", patterns_decode_in_oiiotool);
    RUN_NEEDING("oiiotool", masks_from_runs_decode_in_oiiotool);
    RUN_NEEDING("oiiotool", noise_decodes_in_oiiotool);
    RUN_NEEDING("oiiotool", layers_decode_through_row_boundaries);
    RUN_NEEDING("oiiotool", job_layers_decode_by_inflate_and_in_oiiotool);
    RUN(rgb_header_says_truecolour);
    RUN_NEEDING("oiiotool", rgb_images_decode_in_oiiotool);
    RUN(compression_stays_within_its_bounds);
    RUN_NEEDING("oiiotool", the_maskers_images_decode_in_oiiotool);
    remove_dir();
}
