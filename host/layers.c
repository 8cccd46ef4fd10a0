#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
/* The display and mask options and the layer masks: see layers.h. */
#include "layers.h"
#include "bytes.h"
#include "options.h"
#include "pages.h"
#include "formats/pipeline.h"
#include "report.h"

#include <math.h>
#include <stddef.h>
#include <unistd.h>
#include <stdlib.h>
#include <string.h>

const char *const SLICE_AT[] = {"bottom", "middle", "top", "envelope", "core"};
const char *const SLICE_AT_MEANING[] = {
    "each layer's section at the centre of its first bin",
    "each layer's section at its middle height",
    "each layer's section at the centre of its last bin",
    "lit where the part is inside anywhere in the layer (never cut into)",
    "lit where the part is inside all through the layer (never oversized)"};
/* the library's rule for each of SLICE_AT's names */
static const adaslice_slice_at SLICE_RULES[] = {ADASLICE_SLICE_BOTTOM, ADASLICE_SLICE_MIDDLE, ADASLICE_SLICE_TOP,
                                                ADASLICE_SLICE_ENVELOPE, ADASLICE_SLICE_CORE};
const char *const MIRRORS[] = {"none", "x", "y", "xy"};
const char *const ROTATIONS[] = {"0", "90", "180", "270"};

void slice_options_usage(FILE *f)
{
    int i;
    fputs("printer\n"
          "  --printer NAME      a preset (below)                            [2k-5.5]\n"
          "  --pixels WxH        pixels of the display, with --pitch\n"
          "  --pitch X[,Y]       pixel size in mm, across and down (one number: square)\n"
          "  --display WxH       the display's size in mm, instead of --pitch\n"
          "  --mirror M          none, x, y or xy: flip the image as the display needs\n"
          "                      [the preset's, else none]\n"
          "  --rotate A          0, 90, 180 or 270: turn the image counter-clockwise for a\n"
          "                      display mounted turned (90, 270: W and H are the image's)\n"
          "                      [the preset's, else 0]\n"
          "masks\n"
          "  --aa S              anti-aliased 8-bit masks in S x S + 1 grey levels: each\n"
          "                      pixel's covered area, exact (envelope, core: S x S\n"
          "                      rays per pixel); 1: 1-bit masks             [1]\n"
          "  --slice-at WHERE    bottom, middle or top of each layer (the section at the\n"
          "                      centre of its first, middle or last bin); envelope: lit\n"
          "                      where the part is inside anywhere in the layer (never\n"
          "                      cuts into it, keeps tips thinner than a layer); core:\n"
          "                      inside all through the layer (never oversized) [middle]\n"
          "  --place X,Y         the part's centre, mm from the plate's centre [0,0]\n"
          "  --svg               also each layer's contours: JOBDIR/layer_00001.svg, ...\n"
          "  --force             write a job directory into a directory that holds other files\n"
          "                      and no manifest.json (files of the job's names are written over)\n"
          "  --memory MB         the most the masks or the profile may take\n"
          "                                                    [half the machine's memory]\n"
          "  --threads N         threads rendering (in row bands) and coding layers at once\n"
          "                      (the job is the same bytes)                   [the cores]\n", f);
    fputs("printer presets (each writes the job its printer reads; README cites the figures)\n", f);
    for (i = 0; i < PRINTER_COUNT; i++) {
        const printer *p = &PRINTERS[i];
        fprintf(f, "  %-24s %s, %d x %d px of %g", p->name, p->format, p->width, p->height, p->pitch[0] * 1000);
        if (p->pitch[1] != p->pitch[0]) fprintf(f, " x %g", p->pitch[1] * 1000);
        fprintf(f, " um: %s\n", p->machine);
    }
}


int parse_slice(int argc, char **argv, slice_args *s, int *rest_argc, char **rest, int need_dir)
{
    int i, rc = RC_OK;
    int mirror = -1, rotate = -1;
    memset(s, 0, sizeof *s);
    cure_defaults(&s->cure);
    s->supersample = 1;
    s->slice_at = 1;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (!strcmp(o, "-o") || !strcmp(o, "--output")) rc = file_option(argc, argv, &i, &s->dir);
        else if (!strcmp(o, "--format")) rc = file_option(argc, argv, &i, &s->format);
        else if (!strcmp(o, "--printer")) {
            const char *name = NULL;
            if (!(rc = file_option(argc, argv, &i, &name)) && !(s->preset = printer_find(name)))
                rc = complain(RC_USAGE, "--printer %s: unknown (adaslice printers lists the presets)", name);
        } else if (!strcmp(o, "--pixels")) {
            double wh[2];
            if (!(rc = numbers_option(argc, argv, &i, 'x', 2, "WxH, each 1 to 65536", wh))) {
                if (wh[0] != floor(wh[0]) || wh[1] != floor(wh[1]) || wh[0] < 1 || wh[1] < 1 || wh[0] > 65536 ||
                    wh[1] > 65536)
                    rc = complain(RC_USAGE, "--pixels %s: expected WxH, each 1 to 65536", argv[i]);
                s->width = (int)wh[0];
                s->height = (int)wh[1];
            }
        } else if (!strcmp(o, "--pitch")) {
            const char *v = i + 1 < argc ? argv[i + 1] : "";
            if (!(rc = numbers_option(argc, argv, &i, ',', strchr(v, ',') ? 2 : 1, "X or X,Y in mm", s->pitch))) {
                if (!strchr(v, ',')) s->pitch[1] = s->pitch[0];
                if (!(s->pitch[0] > 0) || !(s->pitch[1] > 0))
                    rc = complain(RC_USAGE, "--pitch %s: pixel sizes are positive mm", argv[i]);
            }
        }
        else if (!strcmp(o, "--display")) {
            if (!(rc = numbers_option(argc, argv, &i, 'x', 2, "WxH in mm", s->display)) &&
                (!(s->display[0] > 0) || !(s->display[1] > 0)))
                rc = complain(RC_USAGE, "--display %s: expected WxH in mm", argv[i]);
        } else if (!strcmp(o, "--rotate")) rc = name_option(argc, argv, &i, ROTATIONS, 4, "0, 90, 180 or 270", &rotate);
        else if (!strcmp(o, "--aa")) {
            size_t n = 1;
            rc = count_option(argc, argv, &i, 16, &n);
            s->supersample = (int)n;
        } else if (!strcmp(o, "--slice-at")) rc = name_option(argc, argv, &i, SLICE_AT, 5, "bottom, middle, top, envelope or core", &s->slice_at);
        else if (!strcmp(o, "--mirror")) rc = name_option(argc, argv, &i, MIRRORS, 4, "none, x, y or xy", &mirror);
        else if (!strcmp(o, "--place")) {
            rc = numbers_option(argc, argv, &i, ',', 2, "X,Y in mm", s->place);
            s->placed = 1;
        } else if (!strcmp(o, "--svg")) {
            s->svg = 1;
        } else if (!strcmp(o, "--force")) {
            s->force = 1;
        } else if (!strcmp(o, "--memory")) {
            rc = memory_option(argc, argv, &i, &s->memory_mb);
        } else if (!strcmp(o, "--threads")) {
            size_t n = 1;
            rc = count_option(argc, argv, &i, 64, &n);
            s->threads = (int)n;
        } else if (!strcmp(o, "--help") || !strcmp(o, "-h")) {
            return -1;
        } else if (cure_option(argc, argv, &i, &s->cure, &rc)) {
            continue;
        } else rest[(*rest_argc)++] = argv[i];
    }
    if (rc) return rc;
    if (!s->memory_mb) s->memory_mb = machine_memory_mb() / 2;
    if (!s->threads) s->threads = pipeline_cores();
    s->geometry_given = s->preset || s->width || s->pitch[0] || s->display[0];
    if (need_dir && !s->dir) return complain(RC_USAGE, "slice needs -o JOBDIR or -o FILE (.ctb, .goo, .zip, .sl1)");
    if (s->preset && (s->width || s->pitch[0] || s->display[0]))
        return complain(RC_USAGE, "--printer %s and --pixels/--pitch/--display: give one or the other", s->preset->name);
    if (s->pitch[0] && s->display[0]) return complain(RC_USAGE, "--pitch and --display: give one or the other");
    if (!s->preset && !s->width && !s->pitch[0] && !s->display[0]) s->preset = &PRINTERS[0];
    if (s->preset) {
        s->width = s->preset->width;
        s->height = s->preset->height;
        s->pitch[0] = s->preset->pitch[0];
        s->pitch[1] = s->preset->pitch[1];
    } else if (!s->width || (!s->pitch[0] && !s->display[0])) {
        return complain(RC_USAGE, "--pixels WxH goes with --pitch MM or --display WxH");
    } else if (s->display[0]) {
        s->pitch[0] = s->display[0] / s->width;
        s->pitch[1] = s->display[1] / s->height;
    }
    s->rotate = rotate >= 0 ? rotate : s->preset ? s->preset->rotate : 0;
    s->mirror_x = mirror >= 0 ? mirror & 1 : s->preset ? s->preset->mirror_x : 0;
    s->mirror_y = mirror >= 0 ? (mirror >> 1) & 1 : s->preset ? s->preset->mirror_y : 0;
    if (s->rotate & 1) { /* the plate is the image turned a quarter */
        int t = s->width;
        double p = s->pitch[0];
        s->width = s->height;
        s->height = t;
        s->pitch[0] = s->pitch[1];
        s->pitch[1] = p;
    }
    return RC_OK;
}


/* Where the grid's lines (rows or columns) [lo, hi) land among the n lines
   of the stored image: counted from the other end when flip. */
static void landing(int flip, int n, int lo, int hi, int out[2])
{
    out[0] = flip ? n - hi : lo;
    out[1] = flip ? n - lo : hi;
}

static unsigned char bits_reversed(unsigned b)
{
    b = (b & 0xF0u) >> 4 | (b & 0x0Fu) << 4;
    b = (b & 0xCCu) >> 2 | (b & 0x33u) << 2;
    return (unsigned char)((b & 0xAAu) >> 1 | (b & 0x55u) << 1);
}

/* Row `src` of w pixels into `dst` with its columns counted from the other
   end (dst pixel i = src pixel w - 1 - i), only dst's bytes [lo, hi): the
   pixels outside them are dark in every layer. A 1-bit byte gathers its 8
   pixels from at most two source bytes. */
static void row_flipped(const unsigned char *src, unsigned char *dst, int w, int bits, size_t lo, size_t hi)
{
    size_t b;
    if (bits == 8) {
        for (b = lo; b < hi; b++) dst[b] = src[w - 1 - (int)b];
        return;
    }
    for (b = lo; b < hi; b++) {
        int e = w - 1 - 8 * (int)b, first = e - 7; /* dst's bits 0..7 (MSB first) are src's e down to e - 7 */
        unsigned window;
        if (first >= 0) {
            size_t at = (size_t)first >> 3;
            unsigned two = (unsigned)src[at] << 8 | (at + 1 < ((size_t)w + 7) / 8 ? src[at + 1] : 0u);
            window = (two >> (8 - (first & 7))) & 0xFFu; /* src's bits first .. e, first at the top */
            dst[b] = bits_reversed(window);
        } else { /* the row's last byte: pixels past w are dark */
            unsigned v = 0;
            int j;
            for (j = 0; j <= e; j++) v |= ((src[(e - j) >> 3] >> (7 - ((e - j) & 7))) & 1u) << (7 - j);
            dst[b] = (unsigned char)v;
        }
    }
}

/* The 1-bit pixels of grid columns x .. x + 7 in a band's row, the first
   in the top bit; those outside 0 .. w - 1 dark. */
static unsigned columns8(const unsigned char *row, int w, int x)
{
    unsigned v = 0;
    int j;
    if (x >= 0 && x + 8 <= w) {
        size_t at = (size_t)x >> 3;
        unsigned two = (unsigned)row[at] << 8 | ((x & 7) ? row[at + 1] : 0u); /* x + 7 < w: its byte is the row's */
        return (two >> (8 - (x & 7))) & 0xFFu;
    }
    for (j = 0; j < 8; j++)
        if (x + j >= 0 && x + j < w) v |= ((row[(x + j) >> 3] >> (7 - ((x + j) & 7))) & 1u) << (7 - j);
    return v;
}

/* An 8 x 8 matrix of bits, row j in byte 7 - j (the top byte first), each
   row's first column in its top bit: transposed in place (Hacker's Delight,
   7-3: three swaps of ever larger blocks). */
static uint64_t bits_transposed(uint64_t x)
{
    uint64_t t;
    t = (x ^ (x >> 7)) & 0x00AA00AA00AA00AAull;
    x ^= t ^ (t << 7);
    t = (x ^ (x >> 14)) & 0x0000CCCC0000CCCCull;
    x ^= t ^ (t << 14);
    t = (x ^ (x >> 28)) & 0x00000000F0F0F0F0ull;
    x ^= t ^ (t << 28);
    return x;
}

/* Rows a and b of a matrix of bytes (each a number, column k in byte k from
   the lowest) trade their blocks of `shift` bits across the diagonal: a's
   upper block of each pair with b's lower one. */
#define SWAP_BLOCKS(a, b, low, shift)                                                                              \
    do {                                                                                                           \
        uint64_t t_ = ((a >> (shift)) ^ b) & (low);                                                                \
        a ^= t_ << (shift);                                                                                        \
        b ^= t_;                                                                                                   \
    } while (0)

/* An 8 x 8 matrix of bytes, row j in v[j], its column k in byte k (from the
   lowest): transposed in place, by swapping ever larger blocks (bytes, then
   pairs, then fours) across the diagonal. */
static void bytes_transposed(uint64_t v[8])
{
    const uint64_t b1 = 0x00FF00FF00FF00FFull, b2 = 0x0000FFFF0000FFFFull, b4 = 0x00000000FFFFFFFFull;
    SWAP_BLOCKS(v[0], v[1], b1, 8);
    SWAP_BLOCKS(v[2], v[3], b1, 8);
    SWAP_BLOCKS(v[4], v[5], b1, 8);
    SWAP_BLOCKS(v[6], v[7], b1, 8);
    SWAP_BLOCKS(v[0], v[2], b2, 16);
    SWAP_BLOCKS(v[1], v[3], b2, 16);
    SWAP_BLOCKS(v[4], v[6], b2, 16);
    SWAP_BLOCKS(v[5], v[7], b2, 16);
    SWAP_BLOCKS(v[0], v[4], b4, 32);
    SWAP_BLOCKS(v[1], v[5], b4, 32);
    SWAP_BLOCKS(v[2], v[6], b4, 32);
    SWAP_BLOCKS(v[3], v[7], b4, 32);
}

/* A band's pixels (grid rows b0 .. b1 - 1 of mk's image, row 0 its lowest)
   quarter-turned into out: out's rows rows[0] .. rows[1] - 1 are grid
   columns r (or w - 1 - r when x_down), its columns cols[0] .. cols[1] - 1
   grid rows i (or h - 1 - i when y_down). For a 1-bit image eight out rows
   at a time, each out byte 8 band rows' bytes of 8 grid columns
   transposed; pixel by pixel it was 80 % of a Prusa SL1S job's time. Whole
   out bytes are written: their pixels past the band's rows are past the
   part's (bands end on whole bytes, band_rows), dark in every layer. */
static void turn_quarter(const adaslice_masker *mk, int x_down, int y_down, int b0, int b1, const int rows[2],
                         const int cols[2], int bits, unsigned char *out, size_t out_stride)
{
    int w = mk->grid.width, h = mk->grid.height, y0 = (int)mk->rows[0], r, i, k;
    if (bits == 8) {
        /* 8 x 8 bytes at a time, transposed; 64 out rows at once, so that
           each band row's cache line is read whole */
        ptrdiff_t next = (y_down ? -1 : 1) * (ptrdiff_t)mk->stride;
        for (r = rows[0]; r < rows[1]; r += 64)
            for (i = cols[0]; i < cols[1]; i += 8) {
                int q, ni = cols[1] - i < 8 ? cols[1] - i : 8;
                const unsigned char *first = mk->image + (size_t)((y_down ? h - 1 - i : i) - y0) * mk->stride;
                for (q = r; q < r + 64 && q < rows[1]; q += 8) {
                    int n = rows[1] - q < 8 ? rows[1] - q : 8, x = x_down ? w - 1 - (q + 7) : q, j, c;
                    unsigned char *dst = out + (size_t)q * out_stride + (size_t)i;
                    const unsigned char *src = first;
                    if (n == 8 && ni == 8 && x >= 0 && x + 8 <= w) {
                        uint64_t v[8];
                        for (j = 0; j < 8; j++) v[j] = get_le64(src + j * next + x);
                        bytes_transposed(v);
                        for (c = 0; c < 8; c++) put_le64(dst + (size_t)(x_down ? 7 - c : c) * out_stride, v[c]);
                        continue;
                    }
                    for (j = 0; j < ni; j++)
                        for (c = 0; c < n; c++)
                            dst[(size_t)c * out_stride + (size_t)j] = src[j * next + (x_down ? w - 1 - (q + c) : q + c)];
                }
            }
        return;
    }
    for (r = rows[0]; r < rows[1]; r += 8) {
        int n = rows[1] - r < 8 ? rows[1] - r : 8;
        int x = x_down ? w - 1 - (r + 7) : r; /* the least grid column of out rows r .. r + 7 */
        unsigned char *dst = out + (size_t)r * out_stride;
        for (i = cols[0] & ~7; i < cols[1]; i += 8) {
            uint64_t m = 0;
            int j;
            if (x >= 0 && x + 8 <= w && i >= cols[0] && i + 8 <= cols[1]) {
                /* the 8 grid rows are the band's and the 8 columns the row's: a
                   byte of each, from one or two */
                int gy = y_down ? h - 1 - i : i, step = y_down ? -1 : 1, sh = x & 7;
                const unsigned char *at = mk->image + (size_t)(gy - y0) * mk->stride + (x >> 3);
                ptrdiff_t next = step * (ptrdiff_t)mk->stride;
                if (sh)
                    for (j = 0; j < 8; j++) m = m << 8 | (((unsigned)at[j * next] << 8 | at[j * next + 1]) >> (8 - sh) & 0xFFu);
                else
                    for (j = 0; j < 8; j++) m = m << 8 | at[j * next];
            } else {
                for (j = 0; j < 8; j++) {
                    int gy = y_down ? h - 1 - (i + j) : i + j;
                    m = m << 8 | (gy >= b0 && gy < b1 ? columns8(mk->image + (size_t)(gy - y0) * mk->stride, w, x) : 0u);
                }
            }
            m = bits_transposed(m); /* byte 7 - c: grid column x + c across out's 8 columns */
            for (k = 0; k < n; k++)
                dst[(size_t)k * out_stride + (size_t)(i >> 3)] = (unsigned char)(m >> (8 * (x_down ? k : 7 - k)));
        }
    }
}

static void orient_image(const layer_masks *m, const adaslice_masker *mk, unsigned char *out, size_t out_stride)
{
    const slice_args *s = m->s;
    int w = mk->grid.width, h = mk->grid.height, y0 = (int)mk->rows[0], y1 = (int)mk->rows[1], r;
    int out_w = (s->rotate & 1) ? h : w, out_h = (s->rotate & 1) ? w : h, rows[2] = {0, out_h}, cols[2] = {0, out_w};
    /* the part's pixel columns and, of this band, its rows */
    int c0 = m->bits == 8 ? (int)m->byte_lo : (int)m->byte_lo * 8, c1 = m->bits == 8 ? (int)m->byte_hi : (int)m->byte_hi * 8;
    int b0 = y0 > m->row_lo ? y0 : m->row_lo, b1 = y1 < m->row_hi ? y1 : m->row_hi;
    c1 = c1 < w ? c1 : w;
    if (!(s->rotate & 1)) {
        /* no quarter turn: rows stay rows, perhaps counted from the other
           end and with their columns flipped, and only the part's band of
           each is written (out is zero elsewhere): the copy was the one pass
           over the whole image on the masker's thread, and the slowest to
           share the memory with threads coding other layers; flipped
           pixel by pixel, a mirrored printer's job (most presets) took 16x
           the time of its masks */
        int flip_rows = s->mirror_y != (s->rotate == 2), flip_cols = s->mirror_x != (s->rotate == 2), span[2];
        size_t lo, hi;
        landing(flip_cols, w, c0, c1, span); /* the part's columns in out's rows, as bytes */
        lo = m->bits == 8 ? (size_t)span[0] : (size_t)span[0] / 8;
        hi = m->bits == 8 ? (size_t)span[1] : ((size_t)span[1] + 7) / 8;
        for (r = b0; r < b1; r++) {
            const unsigned char *src = mk->image + (size_t)(r - y0) * mk->stride;
            unsigned char *dst = out + (size_t)(flip_rows ? r : h - 1 - r) * out_stride;
            if (flip_cols) row_flipped(src, dst, w, m->bits, lo, hi);
            else memcpy(dst + lo, src + lo, hi - lo);
        }
        return;
    }
    /* A quarter turn: the band's rows are out's columns, perhaps counted
       from the other end, and the grid's columns out's rows; only the
       part's rows and columns are written, in whole bytes (out is zero
       elsewhere, as above: over the whole width it took 7x the time of an
       upright job) */
    if (b1 <= b0) return;
    landing((s->rotate == 1) != s->mirror_y, h, b0, b1, cols);
    landing((s->rotate == 1) != s->mirror_x, w, c0, c1, rows);
    turn_quarter(mk, (s->rotate == 1) != s->mirror_x, (s->rotate == 1) != s->mirror_y, b0, b1, rows, cols, m->bits, out,
                 out_stride);
}

/* Whether the part, its box lo to hi, fits on the plate where it is placed:
   its size, or a complaint. */
static int part_fits(const slice_args *s, const double lo[3], const double hi[3], double size[3])
{
    double plate[2], over[2];
    int k;
    plate[0] = s->width * s->pitch[0];
    plate[1] = s->height * s->pitch[1];
    for (k = 0; k < 3; k++) size[k] = hi[k] - lo[k];
    for (k = 0; k < 2; k++) over[k] = fabs(s->place[k]) + size[k] / 2 - plate[k] / 2;
    if (over[0] > 0 || over[1] > 0) {
        int axis = over[1] > over[0];
        if (!s->placed || size[axis] > plate[axis]) /* centred, it is this much wider than the plate */
            return complain(RC_FAIL, "the part (%g x %g mm) does not fit the %g x %g mm plate: %g mm too wide along %s",
                            size[0], size[1], plate[0], plate[1], size[axis] - plate[axis], axis ? "y" : "x");
        return complain(RC_FAIL, "the part (%g x %g mm), placed at %g, %g mm, overhangs the %g x %g mm plate by %g mm along %s",
                        size[0], size[1], s->place[0], s->place[1], plate[0], plate[1], over[axis], axis ? "y" : "x");
    }
    return RC_OK;
}

double layer_masks_bytes(const slice_args *s, int buffers)
{
    double w = s->width, h = s->height, bits = s->supersample > 1 ? 8 : 1;
    double image = bits == 8 ? w * h : (w + 7) / 8 * h;
    /* the directory's coding at worst: the mask code's bound, the PNG's
       filtered rows and output, and the rows' scan (mask_band_scan: a run
       of 4 bytes a byte of the image, a step a row) */
    double coding = (double)adaslice_rle_bound((uint32_t)w, (uint32_t)h, (int)bits) + 2 * (image + h) + 4 * image +
                    (double)sizeof(mask_band_step) * h;
    /* the masker twice with more than one layer in flight (more than one
       thread): the whole one lives until its row bands are made */
    return (double)adaslice_masker_bytes((uint32_t)s->width, (uint32_t)s->height, s->supersample, SLICE_RULES[s->slice_at], 0) *
               (buffers > 1 ? 2 : 1) +
           buffers * (image + coding);
}

int layer_masks_check(const slice_args *s, int buffers)
{
    double need = layer_masks_bytes(s, buffers), limit = s->memory_mb * 1e6;
    char a[32], b[32], c[32];
    if (need <= limit) return RC_OK;
    return complain(RC_USAGE, "a %d x %d px grid at --aa %d needs %s for its masks (the masker %s%s, %d layer%s in flight), "
                              "more than --memory %s",
                    s->width, s->height, s->supersample, size_text(need, a),
                    size_text((double)adaslice_masker_bytes((uint32_t)s->width, (uint32_t)s->height, s->supersample, SLICE_RULES[s->slice_at], 0), b),
                    buffers > 1 ? " twice, as it is split into row bands" : "", buffers, plural((size_t)buffers), size_text(limit, c));
}

int layer_masks_fit(const slice_args *s, const double lo[3], const double hi[3])
{
    double size[3], tall, most;
    char hint[160] = "";
    tall = hi[2] - lo[2];
    most = hi[0] - lo[0] > hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1];
    if (tall > most) most = tall;
    units_hint(tall, hint, sizeof hint);
    /* the default printer's height too: the job is for it, and a part taller
       than it builds would be sliced to the last layer for nothing */
    if (s->preset && tall > s->preset->z_max)
        return complain(RC_FAIL, "the part is %g mm tall: the %s%s%s builds %g mm%s", tall,
                        s->geometry_given ? "" : "default printer (", s->preset->name,
                        s->geometry_given ? "" : "; --printer NAME for another)", s->preset->z_max, hint);
    if (*hint) warn("the part is %g mm tall%s", tall, hint);
    else if (most < UNITS_SMALL_MM)
        warn("the part is %g x %g x %g mm; a model in metres? --scale 1000 reads it in "
             "millimetres, %g mm tall", hi[0] - lo[0], hi[1] - lo[1], tall, tall * 1000);
    return part_fits(s, lo, hi, size);
}

/* Where layer k is sliced, mm above the part's bottom (as adaslice_masker_layer
   cuts); envelope and core masks, made over the whole layer, say the middle. */
double layer_slice_height(const slice_args *s, const plan_job *j, size_t k)
{
    const adaslice_layer *l = &j->plan[j->args->method].layers[k];
    double half = j->profile.bin / 2;
    if (half > l->thickness / 2) half = l->thickness / 2;
    if (s->slice_at == 0) return l->z_bottom + half;
    if (s->slice_at == 2) return l->z_top - half;
    return 0.5 * (l->z_bottom + l->z_top);
}

/* The rows of the stored image that the grid's columns [c0, c1) and rows
   [row_lo, row_hi) reach, as orient_image turns and mirrors them: the stored
   row r shows grid row h - 1 - r upright (the grid's row 0 is the display's
   bottom), and a quarter turn shows a grid column in each row. */
static void stored_rows(layer_masks *m, int c0, int c1)
{
    const slice_args *s = m->s;
    if (s->rotate & 1) /* flipped: stored row r shows column w - 1 - r */
        landing((s->rotate == 1) != s->mirror_x, m->grid.width, c0, c1, m->lit_rows);
    else /* flipped: stored row r shows grid row h - 1 - r, as orient_image lands the bands' rows */
        landing((s->rotate == 0) != s->mirror_y, m->grid.height, m->row_lo, m->row_hi, m->lit_rows);
}

/* The masker's rows and row bytes the part can light, a pixel of margin
   round its box: a pixel is lit only where a ray inside the part's section
   runs, and an open mesh's section is closed by chords between its own
   points, so no lit pixel lies outside the box. */
static void part_band(layer_masks *m, const double lo[3], const double hi[3])
{
    const adaslice_grid *g = &m->grid;
    double x0, x1, y0, y1;
    x0 = floor((lo[0] - g->origin[0]) / g->pitch[0]) - 1;
    x1 = floor((hi[0] - g->origin[0]) / g->pitch[0]) + 2;
    y0 = floor((lo[1] - g->origin[1]) / g->pitch[1]) - 1;
    y1 = floor((hi[1] - g->origin[1]) / g->pitch[1]) + 2;
    x0 = x0 < 0 ? 0 : x0 > g->width ? g->width : x0;
    x1 = x1 < x0 ? x0 : x1 > g->width ? g->width : x1;
    m->row_lo = (int)(y0 < 0 ? 0 : y0 > g->height ? g->height : y0);
    m->row_hi = (int)(y1 < m->row_lo ? m->row_lo : y1 > g->height ? g->height : y1);
    m->byte_lo = m->bits == 8 ? (size_t)x0 : (size_t)x0 / 8;
    m->byte_hi = m->bits == 8 ? (size_t)x1 : ((size_t)x1 + 7) / 8;
    stored_rows(m, (int)x0, (int)x1);
}

/* The bands' rows: the part's rows cut into about `wanted` bands of whole
   bytes of the displayed image (a quarter-turned 1-bit image packs 8 grid
   rows into a byte, counted from the grid's top or bottom), so no two bands
   write one byte. Returns the count of bands; rows holds count + 1. */
static int band_rows(const layer_masks *m, int wanted, uint32_t *rows)
{
    const slice_args *s = m->s;
    int h = m->grid.height, n = 0, step = ((m->row_hi - m->row_lo) / wanted + 7) / 8 * 8, at;
    int align = (s->rotate & 1) && m->bits == 1 && ((s->rotate == 1) != s->mirror_y) ? h % 8 : 0;
    rows[n++] = (uint32_t)m->row_lo;
    for (at = m->row_lo + step; step && n < wanted; at += step) {
        int cut = at - ((at - align) % 8 + 8) % 8;
        if (cut >= m->row_hi) break;
        if (cut > (int)rows[n - 1]) rows[n++] = (uint32_t)cut;
    }
    rows[n] = (uint32_t)m->row_hi;
    return n;
}

int layer_masks_open(layer_masks *m, const slice_args *s, const plan_job *j, int bands)
{
    adaslice_mask_options mo;
    adaslice_error err;
    adaslice_masker whole;
    uint32_t *rows = NULL;
    int rc;
    memset(m, 0, sizeof *m);
    m->s = s;
    m->j = j;
    if ((rc = part_fits(s, j->lo, j->hi, m->part))) return rc;
    m->grid = adaslice_grid_plate(&j->mesh, s->width, s->height, s->pitch[0], s->pitch[1], s->place);
    memset(&mo, 0, sizeof mo);
    mo.supersample = s->supersample;
    mo.allocator = pages_allocator();
    mo.slice_at = SLICE_RULES[s->slice_at];
    mo.bin = j->args->bin; /* the profile's (0: the library's default for both), which may be in the making */
    mo.edges_balance = j->repair.shells && !j->repair.open_edges && !j->repair.nonmanifold_edges &&
                       !j->repair.inconsistent_edges;
    if (adaslice_masker_init(&whole, &j->mesh, &m->grid, &mo, &err) != ADASLICE_OK) return library_error(&err);
    m->width = (s->rotate & 1) ? m->grid.height : m->grid.width;
    m->height = (s->rotate & 1) ? m->grid.width : m->grid.height;
    m->bits = s->supersample > 1 ? 8 : 1;
    m->stride = m->bits == 8 ? (size_t)m->width : ((size_t)m->width + 7) / 8;
    part_band(m, j->lo, j->hi);
    /* an open mesh's sections are whole: one masker */
    if (bands > 1 && !whole.sections && m->row_hi > m->row_lo) {
        if (!(rows = (uint32_t *)malloc(((size_t)bands + 1) * sizeof *rows))) {
            adaslice_masker_free(&whole);
            return complain(RC_FAIL, "out of memory for %d bands", bands);
        }
        bands = band_rows(m, bands, rows);
    } else bands = 1;
    if (!(m->band = (adaslice_masker *)calloc(bands > 1 ? (size_t)bands : 1, sizeof *m->band))) {
        adaslice_masker_free(&whole);
        free(rows);
        return complain(RC_FAIL, "out of memory for %d bands", bands);
    }
    if (bands <= 1) {
        m->band[0] = whole; /* the masker is the one band */
        m->bands = 1;
    } else {
        if (adaslice_masker_bands(&whole, rows, (size_t)bands, m->band, &err) != ADASLICE_OK) rc = library_error(&err);
        else m->bands = bands;
        adaslice_masker_free(&whole);
    }
    free(rows);
    if (!rc && !(m->image = (unsigned char *)calloc(m->stride * (size_t)m->height, 1)))
        rc = complain(RC_FAIL, "out of memory for a %d x %d mask", m->width, m->height);
    if (rc) layer_masks_close(m);
    return rc;
}

/* Band b's masker on to layer k. */
static int sweep_band(layer_masks *m, int b, size_t k)
{
    adaslice_error err;
    const adaslice_layer *l = &m->j->plan[m->j->args->method].layers[k];
    if (adaslice_masker_layer(&m->band[b], m->j->profile.z0 + l->z_bottom, m->j->profile.z0 + l->z_top, &err) != ADASLICE_OK)
        return library_error(&err);
    return RC_OK;
}

int layer_masks_render_band(layer_masks *m, int b, size_t k, unsigned char *out)
{
    int rc = sweep_band(m, b, k);
    if (!rc) orient_image(m, &m->band[b], out, m->stride);
    return rc;
}

int layer_masks_band_is_rows(const layer_masks *m)
{
    return !m->s->rotate && !m->s->mirror_x;
}

int layer_masks_scan_band(layer_masks *m, int b, size_t k, mask_band *rows)
{
    const adaslice_masker *mk = &m->band[b];
    const int y0 = (int)mk->rows[0], r0 = y0 > m->row_lo ? y0 : m->row_lo;
    int r1 = (int)mk->rows[1] < m->row_hi ? (int)mk->rows[1] : m->row_hi, rc = sweep_band(m, b, k);
    const unsigned char *first = mk->image;
    int stored[2];
    if (rc) return rc;
    if (r1 < r0) r1 = r0;
    /* stored top first: grid row h - 1 - r, so the band's top row first,
       unless mirrored in y (as orient_image lands them) */
    landing(!m->s->mirror_y, m->grid.height, r0, r1, stored);
    if (r1 > r0) first += (size_t)((m->s->mirror_y ? r0 : r1 - 1) - y0) * mk->stride;
    if (mask_band_scan(rows, first, m->s->mirror_y ? (ptrdiff_t)mk->stride : -(ptrdiff_t)mk->stride, stored[0],
                       r1 - r0, m->stride, m->byte_lo, m->byte_hi))
        return complain(RC_FAIL, "out of memory reading the rows of layer %zu", k + 1);
    return RC_OK;
}

int layer_masks_render(layer_masks *m, size_t k, unsigned char *out)
{
    int b, rc = RC_OK;
    for (b = 0; b < m->bands && !rc; b++) rc = layer_masks_render_band(m, b, k, out);
    return rc;
}

long long layer_masks_rays(const layer_masks *m, int b)
{
    double ss = (double)m->band[b].supersample * m->band[b].supersample;
    return llround(m->band[b].lit * ss);
}

void layer_masks_close(layer_masks *m)
{
    int b;
    for (b = 0; b < m->bands; b++) adaslice_masker_free(&m->band[b]);
    free(m->band);
    free(m->image);
    m->band = NULL;
    m->image = NULL;
    m->bands = 0;
}
