/* adaslice_mcu.h v0.2.0 — what a resin printer's microcontroller needs of
   adaslice: the integer planner, CRC-32, varints and the mask run-length code.
   MIT No Attribution or public domain: see the end of adaslice.h.

   No float, no libm, no malloc, no stdio: memset, memcpy and memmove from
   <string.h> are all it calls. adaslice.h includes this file (the host plans
   with the very same integer code), a firmware includes only this one.

   DO THIS in exactly one C or C++ file of the firmware:
       #define ADASLICE_MCU_IMPLEMENTATION
       #include "adaslice_mcu.h"
   adaslice.h's implementation brings this one with it: a program that builds
   adaslice.h's must not build this one again in another file.

   REFERENCE, in the order of the data's path; every public function, with
   its signature (make compile-checks holds the list to the declarations)
     results
       adaslice_result                  what every call that can fail returns
     plans: the integer planner (Procedure 1 of the paper, on integers)
       size_t adaslice_dp_workspace(uint32_t bins, uint32_t bins_max, int volume);
           bytes of workspace for N bins
       adaslice_result adaslice_dp_init(adaslice_dp *dp, void *workspace, size_t size, uint32_t bins,
                                        uint32_t bins_min, uint32_t bins_max, uint64_t eps, int volume,
                                        uint64_t slack);
           a planner in the caller's workspace
       void adaslice_dp_push(adaslice_dp *dp, uint64_t units, int forced);
           the next bin's error units (and a forced plane)
       uint32_t adaslice_dp_layers(const adaslice_dp *dp);
           fewest layers up to the last bin pushed
       uint32_t adaslice_dp_bins(const adaslice_dp *dp);
           the bins pushed so far
       uint32_t adaslice_dp_reach(const adaslice_dp *dp);
           the highest plane some plan reaches
       uint32_t adaslice_dp_layer_below(const adaslice_dp *dp, uint32_t plane);
           read the plan top-down
       uint32_t adaslice_dp_reverse(adaslice_dp *dp);
           turn it around in place
       int adaslice_dp_reverse_some(adaslice_dp *dp, uint32_t budget);
           the same, at most so many planes a call
       uint32_t adaslice_dp_layer_above(const adaslice_dp *dp, uint32_t plane);
           read it bottom-up
     job output: what travels to a printer
       uint32_t adaslice_crc32(uint32_t crc, const void *data, size_t size);
           CRC-32 (IEEE 802.3, as zlib and PNG)
       uint32_t adaslice_crc32_mul(uint32_t a, uint32_t b);
           a * b modulo its polynomial: CRCs combined, as zlib's crc32_combine
       size_t adaslice_varint_put(unsigned char *out, uint32_t v);
           a LEB128 varint
       adaslice_result adaslice_varint_push(adaslice_varint *reader, unsigned char byte, int *done, uint32_t *value);
           read one, a byte at a time
       size_t adaslice_rle_bound(uint32_t width, uint32_t height, int bits);
           bytes of mask code an image can need
       adaslice_result adaslice_rle_encode(const unsigned char *image, size_t stride, uint32_t width, uint32_t height,
                                           int bits, unsigned char *out, size_t capacity, size_t *size);
           code a mask
       size_t adaslice_rle_put_repeat(unsigned char *out, uint32_t rows);
       size_t adaslice_rle_put_row(unsigned char *out, uint32_t runs);
       size_t adaslice_rle_put_run(unsigned char *out, int bits, unsigned value, uint32_t length);
           the code's records, for an encoder that finds the runs itself
       adaslice_result adaslice_rle_decoder_init(adaslice_rle_decoder *dec, uint32_t width, uint32_t height, int bits,
                                                 unsigned char *row, size_t row_size);
           a streaming decoder
       adaslice_result adaslice_rle_decode(adaslice_rle_decoder *dec, const unsigned char *data, size_t size,
                                           void (*emit)(void *ctx, uint32_t y, const unsigned char *row), void *ctx);
           decode the next bytes, row by row
       adaslice_result adaslice_rle_decode_rows(adaslice_rle_decoder *dec, const unsigned char *data, size_t size,
                                                uint32_t max_bytes, size_t *used,
                                                void (*emit)(void *ctx, uint32_t y, const unsigned char *row),
                                                void *ctx);
           the same, at most so many row bytes a call
       int adaslice_rle_finished(const adaslice_rle_decoder *dec);
           every row decoded
       ADASLICE_RLE_CRC                 CRC-32 of the rows decoded

   THE INTEGER PLANNER  Bins arrive one at a time as integer error units
   (b * phi rounded up) with eps in the same units. It keeps the last tmax/b
   planes in rings and one back-pointer byte per bin (two when tmax/b > 255):
   12,000 bins with layers of at most 127 bins plan in 15,073 bytes. Among the
   plans with the fewest layers it keeps one whose worst layer is smallest.
   adaslice.h's adaslice_plan_units makes the units a printer is sent, so the
   printer's plan equals the host's bit for bit.

   MASK RUN-LENGTH CODE  How masks travel to a printer. A mask is `height`
   rows of `width` pixels, 1 bit per pixel (rows of (width + 7) / 8 bytes,
   most significant bit first, 1 = lit, padding bits 0) or 8 bits (rows of
   width bytes). The code is a sequence of row records; every number is a
   LEB128 varint (7 bits per byte, low bits first, at most 5 bytes, < 2^32):
       h odd    the previous row again, (h >> 1) + 1 times (before the first
                row the previous row is dark)
       h even   a new row of h >> 1 runs covering exactly width pixels:
                1-bit: a length per run, runs alternating dark, lit, dark...
                       (only the first may be 0, for a row that starts lit)
                8-bit: a value byte and a length (>= 1) per run
   An empty 2560 x 1440 mask is 2 bytes. A decoder checks the CRC-32 of the
   rows it rebuilt, in the layout above, against the sender's.

   OPTIONS (define before including the implementation)
     ADASLICE_MCU_IMPLEMENTATION  the implementation, in one file
     ADASLICE_STATIC              every function static (private to the file)
     ADASLICE_DEF                 the linkage of public functions
     ADASLICE_ASSERT(x)           internal invariant checks (off by default here;
                                  adaslice.h turns them on with assert)
     ADASLICE_CRC32_SMALL         CRC-32 a nibble at a time: 64 bytes of table and
                                  no 16 KiB of stack (microcontrollers)
   LIMITS  N < 2^31 bins; tmax/b <= 65535 bins per layer; masks below 2^24
   pixels a side.
*/
#ifndef ADASLICE_MCU_H
#define ADASLICE_MCU_H

#include <stddef.h>
#include <stdint.h>

#ifndef ADASLICE_DEF
#ifdef ADASLICE_STATIC
#define ADASLICE_DEF static
#else
#define ADASLICE_DEF extern
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- results */

/* What every call that can fail returns (adaslice.h adds a message). */
typedef enum adaslice_result {
    ADASLICE_OK = 0,
    ADASLICE_ERR_ARGUMENT,    /* a parameter is out of range; the message names it */
    ADASLICE_ERR_NOMEM,       /* the allocator returned NULL */
    ADASLICE_ERR_IO,          /* a file could not be read (stdio wrappers only) */
    ADASLICE_ERR_FORMAT,      /* not a mesh we can read: bad magic, header or keyword */
    ADASLICE_ERR_TRUNCATED,   /* the data ends before the header says it should */
    ADASLICE_ERR_COUNT,       /* binary STL: triangle count disagrees with the size */
    ADASLICE_ERR_NUMBER,      /* a number that does not parse */
    ADASLICE_ERR_NONFINITE,   /* a NaN or infinite coordinate (also after scaling) */
    ADASLICE_ERR_INDEX,       /* a face index outside the vertex list */
    ADASLICE_ERR_OVERFLOW,    /* a count whose size would overflow, or output that
                                 does not fit the room given */
    ADASLICE_ERR_EMPTY,       /* no triangles (or none left after dropping degenerate ones) */
    ADASLICE_ERR_UNSUPPORTED, /* well-formed, but a feature we do not read */
    ADASLICE_ERR_INFEASIBLE,  /* no plan meets eps, tmin and tmax */
    ADASLICE_ERR_VARINT,      /* mask code: a number longer than 5 bytes or >= 2^32 */
    ADASLICE_ERR_RUN,         /* mask code: runs that overrun the row, leave it short,
                                 or are 0 long */
    ADASLICE_ERR_ROWS         /* mask code: more rows than the mask has */
} adaslice_result;

/* ---------------------------------------------- plans: the integer planner */

#define ADASLICE_UNREACHED 0xffffffffu

typedef struct adaslice_dp { /* its fields are private */
    uint32_t lo, hi;          /* bins per layer: ceil(tmin/b), floor(tmax/b) */
    uint32_t cap;             /* ring size: a power of two above hi, so % is a mask */
    uint64_t eps;             /* allowed error per layer, in units */
    int volume;               /* eq. 20 instead of an additive sum */
    uint64_t slack;           /* volume: units added per bin for rounding */
    uint32_t plane;           /* the last plane decided */
    uint32_t floor;           /* no layer may start below this plane (last forced plane) */
    uint32_t reach;           /* highest plane any plan reaches */
    uint64_t *prefix;         /* [cap] sum of units below the plane (additive) */
    uint64_t *first;          /* [cap] volume: units of the first bin above the plane */
    uint64_t *run;            /* [cap] volume: error of the layer from the plane up to now */
    uint32_t *layers;         /* [cap] fewest layers reaching the plane, or UNREACHED */
    uint64_t *worst;          /* [cap] smallest worst layer error with that many layers */
    uint32_t *queue;          /* [cap] candidate planes, oldest first (a ring) */
    uint32_t head, count;     /* the queue's first slot and length */
    uint32_t scan;            /* queue positions [0, scan) are known to lose on worst error */
    unsigned char *back;      /* (planes + 1) * width bytes */
    uint32_t width;           /* bytes per back-pointer: 1 while hi <= 255, else 2 */
    /* the reversal, which goes top-down a plane at a time */
    uint32_t turn_at;         /* the next plane it visits */
    uint32_t turn_next;       /* the next plane of the plan below it */
    uint16_t turn_above;      /* the bins of the plan's layer above turn_next */
    unsigned char turning;    /* 0 not begun, 1 under way, 2 done */
} adaslice_dp;

/* Bytes of workspace for `bins` bins with layers of at most bins_max bins. */
ADASLICE_DEF size_t adaslice_dp_workspace(uint32_t bins, uint32_t bins_max, int volume);
/* ADASLICE_ERR_ARGUMENT if the workspace (8-byte aligned) is too small or the
   bounds are wrong (1 <= bins_min <= bins_max <= 65535). volume: eq. 20
   instead of sums, with `slack` units added per bin. */
ADASLICE_DEF adaslice_result adaslice_dp_init(adaslice_dp *dp, void *workspace, size_t size, uint32_t bins,
                                             uint32_t bins_min, uint32_t bins_max, uint64_t eps, int volume,
                                             uint64_t slack);
/* The next bin; `forced` puts a plane on top of it in every plan (§3.3). */
ADASLICE_DEF void adaslice_dp_push(adaslice_dp *dp, uint64_t units, int forced);
/* Fewest layers from the bottom to the plane on the last bin pushed, or ADASLICE_UNREACHED. */
ADASLICE_DEF uint32_t adaslice_dp_layers(const adaslice_dp *dp);
/* The bins pushed so far: the plane adaslice_dp_layers speaks of. */
ADASLICE_DEF uint32_t adaslice_dp_bins(const adaslice_dp *dp);
/* The highest plane some plan reaches: where no plan reaches the top, the
   first height a plan cannot cover. */
ADASLICE_DEF uint32_t adaslice_dp_reach(const adaslice_dp *dp);
/* In that best plan, the bins of the layer whose top is `plane` (0 for plane 0
   or a plane no plan reaches): follow it down from the top to read the plan. */
ADASLICE_DEF uint32_t adaslice_dp_layer_below(const adaslice_dp *dp, uint32_t plane);
/* When the last bin is in: turns the best plan around in place, so it reads
   bottom-up with adaslice_dp_layer_above (no pushes after this). Returns the
   layer count, or ADASLICE_UNREACHED (nothing changes). */
ADASLICE_DEF uint32_t adaslice_dp_reverse(adaslice_dp *dp);
/* The same work in slices, for a caller whose every pass must stay short (a
   firmware: the whole reversal is linear in the planes): at most
   `budget` planes a call. Returns 1 while planes are left, 0 once the plan
   reads bottom-up (at once when no plan reaches the top). */
ADASLICE_DEF int adaslice_dp_reverse_some(adaslice_dp *dp, uint32_t budget);
/* After adaslice_dp_reverse: the bins of the layer whose bottom is `plane`
   (0 for the top plane or a plane not in the plan). */
ADASLICE_DEF uint32_t adaslice_dp_layer_above(const adaslice_dp *dp, uint32_t plane);

/* ------------------------------------------------------------- job output */

/* CRC-32 (IEEE 802.3, as zlib's crc32 and PNG): crc = adaslice_crc32(0, data, n),
   and running: adaslice_crc32(crc, more, m). From 4 KiB on it slices by
   sixteen bytes with 16 KiB of tables on the stack; define ADASLICE_CRC32_SMALL
   for a microcontroller, which then goes a nibble at a time (64 bytes of table). */
ADASLICE_DEF uint32_t adaslice_crc32(uint32_t crc, const void *data, size_t size);

/* a * b over GF(2) modulo CRC-32's polynomial, both bit-reflected (bit 31 is
   x^0): crc(A B) = adaslice_crc32_mul(crc(A), x^(8 |B|)) ^ crc(B) with B's
   CRC begun at 0 and not inverted, as zlib's crc32_combine. */
ADASLICE_DEF uint32_t adaslice_crc32_mul(uint32_t a, uint32_t b);

/* A LEB128 varint: 7 bits a byte, low bits first, at most 5 bytes. */
typedef struct adaslice_varint { uint32_t value; int shift; } adaslice_varint; /* a reader: zero it */
/* The bytes of v's varint into out (NULL: only counted); returns how many. */
ADASLICE_DEF size_t adaslice_varint_put(unsigned char *out, uint32_t v);
/* Reads a varint a byte at a time. ADASLICE_ERR_VARINT when the byte would
   make it longer than 5 bytes or >= 2^32; else ADASLICE_OK, and when this
   byte ends the number *done = 1, *value = the number and the reader starts
   afresh (*done = 0 otherwise). */
ADASLICE_DEF adaslice_result adaslice_varint_push(adaslice_varint *reader, unsigned char byte, int *done,
                                                  uint32_t *value);

/* The mask run-length code (see the manual above). */
/* Bytes of code an image can need at most. */
ADASLICE_DEF size_t adaslice_rle_bound(uint32_t width, uint32_t height, int bits);
/* Codes an image (rows `stride` bytes apart) into out, its length in *size;
   ADASLICE_ERR_OVERFLOW if it would exceed `capacity`, ADASLICE_ERR_ARGUMENT
   for a wrong image. */
ADASLICE_DEF adaslice_result adaslice_rle_encode(const unsigned char *image, size_t stride, uint32_t width,
                                                 uint32_t height, int bits, unsigned char *out, size_t capacity,
                                                 size_t *size);

/* The code's records into out (NULL: only counted), each returning its
   bytes (5 at most; a run of 8-bit pixels 6): `rows` (>= 1) rows the same
   as the row above (before the first row: dark), a row of `runs` runs that
   follow, one run of `length` pixels (8-bit: of grey `value`; 1-bit: dark
   and lit in turn, dark first). adaslice_rle_encode writes with these. */
ADASLICE_DEF size_t adaslice_rle_put_repeat(unsigned char *out, uint32_t rows);
ADASLICE_DEF size_t adaslice_rle_put_row(unsigned char *out, uint32_t runs);
ADASLICE_DEF size_t adaslice_rle_put_run(unsigned char *out, int bits, unsigned value, uint32_t length);

typedef struct adaslice_rle_decoder { /* its fields are private */
    uint32_t width, height, stride;
    unsigned char *row;     /* the caller's buffer of stride bytes */
    uint32_t rows;          /* rows emitted */
    uint32_t x;             /* pixels of the current row decoded */
    uint32_t runs;          /* runs left in the current row */
    uint32_t repeat;        /* rows a repeat record still owes */
    uint32_t crc_left;      /* bytes of the finished row not yet in the CRC */
    adaslice_varint number; /* the varint being read */
    unsigned char bits;     /* 1 or 8 */
    unsigned char state;    /* what the next varint or byte is */
    unsigned char pixel;    /* 8-bit: the current run's value; 1-bit: 0 or 1 */
    unsigned char shift_bits; /* bits of stride still to go into row_shift */
    unsigned char row_alone;  /* row_crc is the current row's own CRC */
    uint32_t row_crc;       /* the CRC before the current row, or the row's own */
    uint32_t row_shift;     /* x^(8 stride) mod the CRC's polynomial */
    uint32_t crc;           /* CRC-32 of the rows emitted */
    uint32_t offset;        /* bytes consumed; at an error, the byte at fault */
    adaslice_result error;
} adaslice_rle_decoder;

/* ADASLICE_ERR_ARGUMENT unless 1 <= width, height < 2^24, bits is 1 or 8 and
   row_size holds a row. */
ADASLICE_DEF adaslice_result adaslice_rle_decoder_init(adaslice_rle_decoder *dec, uint32_t width, uint32_t height,
                                                       int bits, unsigned char *row, size_t row_size);
/* Decodes the next `size` bytes of code, calling emit(ctx, y, row) for each
   finished row, in order. Returns ADASLICE_OK or the error (sticky; the byte
   at fault is dec->offset): ADASLICE_ERR_VARINT, _RUN or _ROWS. */
ADASLICE_DEF adaslice_result adaslice_rle_decode(adaslice_rle_decoder *dec, const unsigned char *data, size_t size,
                                                 void (*emit)(void *ctx, uint32_t y, const unsigned char *row),
                                                 void *ctx);
/* The same, putting at most `max_bytes` (>= 1) bytes of rows through the CRC
   before it returns, for a caller whose every pass must stay short (a
   row's CRC is a table step a byte: long on an 8-bit core). A row is emitted
   once its CRC is complete. A repeated row longer than
   ADASLICE_RLE_REPEAT_COST bytes takes its CRC by one multiplication (as
   zlib's crc32_combine) and costs that many bytes of the budget. *used
   gets the code bytes taken; the rest are to be given again. While
   ADASLICE_RLE_PENDING(dec), a row's CRC or a repeat's rows wait for the
   next call (which may have no bytes). */
ADASLICE_DEF adaslice_result adaslice_rle_decode_rows(adaslice_rle_decoder *dec, const unsigned char *data,
                                                      size_t size, uint32_t max_bytes, size_t *used,
                                                      void (*emit)(void *ctx, uint32_t y, const unsigned char *row),
                                                      void *ctx);
#define ADASLICE_RLE_PENDING(dec) ((dec)->repeat != 0 || (dec)->crc_left != 0)
#define ADASLICE_RLE_REPEAT_COST 8u
/* 1 when every row has been emitted and no record is half read. */
ADASLICE_DEF int adaslice_rle_finished(const adaslice_rle_decoder *dec);
/* CRC-32 of the rows emitted so far. */
#define ADASLICE_RLE_CRC(dec) ((dec)->crc)

#ifdef __cplusplus
}
#endif
#endif /* ADASLICE_MCU_H */

/* ======================================================================== */
/*                              IMPLEMENTATION                              */
/* ======================================================================== */
#ifdef ADASLICE_MCU_IMPLEMENTATION
#ifndef ADASLICE_MCU_IMPLEMENTATION_DONE
#define ADASLICE_MCU_IMPLEMENTATION_DONE

#include <string.h>

#ifndef ADASLICE_ASSERT
#define ADASLICE_ASSERT(x) ((void)0)
#endif

#ifdef __cplusplus
#define ADASLICE__CAST(type, x) static_cast<type>(x)
#else
#define ADASLICE__CAST(type, x) ((type)(x))
#endif

/* ---------------------------------------------- plans: the integer planner */
/* The optimal plan (§3.3, Procedure 1) runs on integers: each bin's error
   b*phi[i] is quantised to a count of units q, so prefix sums are exact, plans
   do not depend on summation order, and a microcontroller fed the same
   integers makes the same plan. The core is streaming: bins arrive one at a
   time and only the last tmax/b planes are kept, plus one back-pointer per
   plane (the bottom layer's length in bins). */

#define ADASLICE__UNREACHED ADASLICE_UNREACHED

static void adaslice__dp_set_back(adaslice_dp *dp, uint32_t plane, uint32_t len)
{
    if (dp->width == 1) dp->back[plane] = (unsigned char)len;
    else { dp->back[2 * (size_t)plane] = (unsigned char)(len & 255u); dp->back[2 * (size_t)plane + 1] = (unsigned char)(len >> 8); }
}

static uint32_t adaslice__dp_back(const adaslice_dp *dp, uint32_t plane)
{
    if (dp->width == 1) return dp->back[plane];
    return (uint32_t)dp->back[2 * (size_t)plane] | ((uint32_t)dp->back[2 * (size_t)plane + 1] << 8);
}

/* Layer from plane l to the current plane: its error in units. */
static uint64_t adaslice__dp_sum(const adaslice_dp *dp, uint32_t l)
{
    return dp->prefix[dp->plane & (dp->cap - 1)] - dp->prefix[l & (dp->cap - 1)];
}

static uint64_t adaslice__dp_error(const adaslice_dp *dp, uint32_t l)
{
    return dp->volume ? dp->run[l & (dp->cap - 1)] : adaslice__dp_sum(dp, l);
}

static void adaslice__dp_start(adaslice_dp *dp)
{
    dp->plane = 0;
    dp->floor = 0;
    dp->reach = 0;
    dp->head = dp->count = dp->scan = 0;
    dp->turning = 0;
    dp->prefix[0] = 0;
    dp->layers[0] = 0;
    dp->worst[0] = 0;
    adaslice__dp_set_back(dp, 0, 0);
}

/* Additive metrics: the feasible predecessors of plane i are a window of
   planes whose both ends only move up (prefix sums never decrease), so a
   queue ordered by plane with strictly increasing (layers, worst) holds every
   candidate that can still win: a newer plane with no more layers and no
   larger worst error beats an older one for good, its layer being shorter.
   The front block (fewest layers) has worst[] increasing and layer error
   decreasing along the queue, so the best max(worst, error) sits where the two
   cross; `scan` finds that point and only moves forward: O(1) amortised.
   The queue's state is held in locals: a store into the rings could be a
   store into the planner's own fields as far as the compiler knows, which
   would reload them after each store. */
static uint32_t adaslice__dp_choose_additive(adaslice_dp *dp)
{
    uint32_t i = dp->plane, m = dp->cap - 1, head = dp->head, count = dp->count, scan = dp->scan, bottom = dp->floor;
    uint32_t kf, a, b, best = ADASLICE__UNREACHED;
    const uint32_t *layers = dp->layers;
    const uint64_t *worst = dp->worst, *prefix = dp->prefix;
    uint32_t *queue = dp->queue;
    uint64_t top = prefix[i & m], va, vb;
    if (i >= dp->lo) {
        uint32_t l = i - dp->lo, kl = layers[l & m];
        if (l >= bottom && kl != ADASLICE__UNREACHED) {
            uint64_t wl = worst[l & m];
            for (; count; count--) { /* drop those (layers, worst) no better than l's */
                uint32_t q = queue[(head + count - 1) & m], kq = layers[q & m];
                if (kq != kl ? kq < kl : worst[q & m] < wl) break;
            }
            if (scan > count) scan = count;
            ADASLICE_ASSERT(count < dp->cap);
            queue[(head + count++) & m] = l;
        }
    }
    for (; count; count--) {
        uint32_t f = queue[head];
        if (f + dp->hi >= i && f >= bottom && top - prefix[f & m] <= dp->eps) break;
        head = (head + 1) & m;
        if (scan) scan--;
    }
    if (count) {
        kf = layers[queue[head] & m];
        for (; scan < count; scan++) {
            uint32_t l = queue[(head + scan) & m];
            if (layers[l & m] != kf || worst[l & m] >= top - prefix[l & m]) break;
        }
        /* candidate before the crossing: its layer error dominates */
        a = scan > 0 ? queue[(head + scan - 1) & m] : ADASLICE__UNREACHED;
        va = a != ADASLICE__UNREACHED ? top - prefix[a & m] : UINT64_MAX;
        /* candidate at the crossing: its worst so far dominates */
        b = scan < count ? queue[(head + scan) & m] : ADASLICE__UNREACHED;
        if (b != ADASLICE__UNREACHED && layers[b & m] != kf) b = ADASLICE__UNREACHED;
        vb = b != ADASLICE__UNREACHED ? worst[b & m] : UINT64_MAX;
        best = va <= vb ? a : b;
    }
    dp->head = head;
    dp->count = count;
    dp->scan = scan;
    return best;
}

/* Volume deviation (eq. 20) is not additive: every plane in the window is
   tried, O(w) per plane. */
static void adaslice__dp_choose_volume(adaslice_dp *dp, uint32_t *best)
{
    uint32_t i = dp->plane, l, start;
    uint32_t best_k = ADASLICE__UNREACHED;
    uint64_t best_w = 0;
    *best = ADASLICE__UNREACHED;
    if (i < dp->lo) return;
    start = i > dp->hi ? i - dp->hi : 0;
    if (start < dp->floor) start = dp->floor;
    for (l = start; l + dp->lo <= i; l++) {
        uint32_t k = dp->layers[l & (dp->cap - 1)];
        uint64_t e = dp->run[l & (dp->cap - 1)], w;
        if (k == ADASLICE__UNREACHED || e > dp->eps) continue;
        w = dp->worst[l & (dp->cap - 1)] > e ? dp->worst[l & (dp->cap - 1)] : e;
        if (k < best_k || (k == best_k && w < best_w)) { best_k = k; best_w = w; *best = l; }
    }
}

/* Feeds the next bin's units; decides the plane on top of it. `forced` makes
   that plane part of every plan (§3.3 sharp changes). */
ADASLICE_DEF void adaslice_dp_push(adaslice_dp *dp, uint64_t units, int forced)
{
    uint32_t i = dp->plane + 1, best;
    uint32_t c = dp->cap;
    dp->plane = i;
    if (dp->volume) {
        uint32_t l = i > dp->hi ? i - dp->hi : 0;
        dp->first[(i - 1) & (c - 1)] = units;
        dp->run[(i - 1) & (c - 1)] = 0;
        for (; l < i; l++) {
            uint64_t f = dp->first[l & (c - 1)];
            dp->run[l & (c - 1)] += (units > f ? units - f : f - units) + dp->slack;
        }
        adaslice__dp_choose_volume(dp, &best);
    } else {
        dp->prefix[i & (c - 1)] = dp->prefix[(i - 1) & (c - 1)] + units;
        best = adaslice__dp_choose_additive(dp);
    }
    if (best == ADASLICE__UNREACHED) {
        dp->layers[i & (c - 1)] = ADASLICE__UNREACHED;
        dp->worst[i & (c - 1)] = 0;
        adaslice__dp_set_back(dp, i, 0);
    } else {
        uint64_t e = adaslice__dp_error(dp, best);
        dp->layers[i & (c - 1)] = dp->layers[best & (c - 1)] + 1;
        dp->worst[i & (c - 1)] = dp->worst[best & (c - 1)] > e ? dp->worst[best & (c - 1)] : e;
        adaslice__dp_set_back(dp, i, i - best);
        dp->reach = i;
    }
    if (forced) {
        dp->floor = i;
        dp->head = dp->count = dp->scan = 0;
    }
}

static uint32_t adaslice__ring_size(uint32_t bins_max)
{
    uint32_t cap = 2;
    while (cap <= bins_max) cap *= 2;
    return cap;
}

/* The workspace with a ring of `cap` planes: adaslice.h's plane settling
   keeps more than bins_max of them, to go back to a plane it has passed. */
static size_t adaslice__dp_bytes(uint32_t bins, uint32_t bins_max, uint32_t cap, int volume)
{
    size_t width = bins_max <= 255 ? 1 : 2;
    return cap * ((volume ? 4 : 2) * sizeof(uint64_t) + 2 * sizeof(uint32_t)) + width * ((size_t)bins + 1);
}

ADASLICE_DEF size_t adaslice_dp_workspace(uint32_t bins, uint32_t bins_max, int volume)
{
    return adaslice__dp_bytes(bins, bins_max, adaslice__ring_size(bins_max), volume);
}

static adaslice_result adaslice__dp_setup(adaslice_dp *dp, void *workspace, size_t size, uint32_t bins,
                                          uint32_t bins_min, uint32_t bins_max, uint64_t eps, int volume,
                                          uint64_t slack, uint32_t cap)
{
    unsigned char *mem = ADASLICE__CAST(unsigned char *, workspace);
    uint32_t c;
    if (!dp || !mem || bins_min < 1 || bins_min > bins_max || bins_max > 65535 || bins > 0x7ffffffeu ||
        cap <= bins_max || size < adaslice__dp_bytes(bins, bins_max, cap, volume))
        return ADASLICE_ERR_ARGUMENT;
    memset(dp, 0, sizeof *dp);
    dp->lo = bins_min;
    dp->hi = bins_max;
    dp->cap = c = cap;
    dp->eps = eps;
    dp->volume = volume != 0;
    dp->slack = slack;
    dp->width = bins_max <= 255 ? 1 : 2;
    /* the 8-byte arrays first, so they stay aligned */
    dp->prefix = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint64_t);
    dp->worst = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint64_t);
    if (volume) {
        dp->first = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint64_t);
        dp->run = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint64_t);
    }
    dp->layers = ADASLICE__CAST(uint32_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint32_t);
    dp->queue = ADASLICE__CAST(uint32_t *, ADASLICE__CAST(void *, mem)); mem += c * sizeof(uint32_t);
    dp->back = mem;
    adaslice__dp_start(dp);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_dp_init(adaslice_dp *dp, void *workspace, size_t size, uint32_t bins,
                                             uint32_t bins_min, uint32_t bins_max, uint64_t eps, int volume,
                                             uint64_t slack)
{
    return adaslice__dp_setup(dp, workspace, size, bins, bins_min, bins_max, eps, volume, slack,
                              adaslice__ring_size(bins_max));
}

ADASLICE_DEF uint32_t adaslice_dp_layers(const adaslice_dp *dp)
{
    return dp->layers[dp->plane & (dp->cap - 1)];
}

ADASLICE_DEF uint32_t adaslice_dp_bins(const adaslice_dp *dp) { return dp->plane; }

ADASLICE_DEF uint32_t adaslice_dp_reach(const adaslice_dp *dp) { return dp->reach; }

ADASLICE_DEF uint32_t adaslice_dp_layer_below(const adaslice_dp *dp, uint32_t plane)
{
    return plane <= dp->plane ? adaslice__dp_back(dp, plane) : 0;
}

/* One walk down from the top plane: a plane on the best plan gets the
   length of the layer above it in place of the one below (read first, it
   leads to the next plane of the plan); a plane off it is cleared, so that
   it reads 0. */
ADASLICE_DEF int adaslice_dp_reverse_some(adaslice_dp *dp, uint32_t budget)
{
    uint32_t plane, next, above;
    if (dp->turning == 2 || adaslice_dp_layers(dp) == ADASLICE__UNREACHED) return 0;
    if (!budget) return 1;
    if (!dp->turning) {
        dp->turning = 1;
        dp->turn_at = dp->turn_next = dp->plane;
        dp->turn_above = 0;
    }
    plane = dp->turn_at;
    next = dp->turn_next;
    above = dp->turn_above;
    for (;;) {
        uint32_t len = adaslice__dp_back(dp, plane);
        if (plane == next) {
            adaslice__dp_set_back(dp, plane, above);
            above = len;
            next = plane - len;
        } else {
            adaslice__dp_set_back(dp, plane, 0);
        }
        if (!plane) {
            dp->turning = 2;
            return 0;
        }
        plane--;
        if (!--budget) break;
    }
    dp->turn_at = plane;
    dp->turn_next = next;
    dp->turn_above = (uint16_t)above; /* a layer is at most bins_max <= 65535 bins */
    return 1;
}

ADASLICE_DEF uint32_t adaslice_dp_reverse(adaslice_dp *dp)
{
    uint32_t layers = adaslice_dp_layers(dp);
    while (adaslice_dp_reverse_some(dp, UINT32_MAX)) {}
    return layers;
}

ADASLICE_DEF uint32_t adaslice_dp_layer_above(const adaslice_dp *dp, uint32_t plane)
{
    return plane <= dp->plane ? adaslice__dp_back(dp, plane) : 0;
}
/* ------------------------------------------------------------- job output */

/* A nibble at a time: 64 bytes of table, which is what a microcontroller
   keeps. */
static uint32_t adaslice__crc32_nibbles(uint32_t crc, const unsigned char *p, size_t size)
{
    static const uint32_t nibble[16] = {
        0x00000000u, 0x1db71064u, 0x3b6e20c8u, 0x26d930acu, 0x76dc4190u, 0x6b6b51f4u, 0x4db26158u, 0x5005713cu,
        0xedb88320u, 0xf00f9344u, 0xd6d6a3e8u, 0xcb61b38cu, 0x9b64c2b0u, 0x86d3d2d4u, 0xa00ae278u, 0xbdbdf21cu};
    while (size--) {
        crc ^= *p++;
        crc = (crc >> 4) ^ nibble[crc & 15u];
        crc = (crc >> 4) ^ nibble[crc & 15u];
    }
    return crc;
}

ADASLICE_DEF uint32_t adaslice_crc32(uint32_t crc, const void *data, size_t size)
{
    const unsigned char *p = ADASLICE__CAST(const unsigned char *, data);
    crc = ~crc;
#ifndef ADASLICE_CRC32_SMALL
    /* Slicing by sixteen: sixteen tables of 256 built on the stack for this
       call (about 8,000 operations, so nothing is global and nothing is
       written out by hand), then sixteen bytes a step, read byte by byte so
       that the order of bytes in a word does not matter. */
    if (size >= 4096) {
        uint32_t t[16][256], i, k;
        for (i = 0; i < 256; i++) {
            uint32_t c = i;
            for (k = 0; k < 8; k++) c = c & 1u ? (c >> 1) ^ 0xedb88320u : c >> 1;
            t[0][i] = c;
        }
        for (i = 0; i < 256; i++)
            for (k = 1; k < 16; k++) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xffu];
        for (; size >= 16; p += 16, size -= 16) {
            uint32_t a = crc ^ ((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
            crc = t[15][a & 0xffu] ^ t[14][(a >> 8) & 0xffu] ^ t[13][(a >> 16) & 0xffu] ^ t[12][a >> 24] ^
                  t[11][p[4]] ^ t[10][p[5]] ^ t[9][p[6]] ^ t[8][p[7]] ^ t[7][p[8]] ^ t[6][p[9]] ^ t[5][p[10]] ^
                  t[4][p[11]] ^ t[3][p[12]] ^ t[2][p[13]] ^ t[1][p[14]] ^ t[0][p[15]];
        }
    }
#endif
    return ~adaslice__crc32_nibbles(crc, p, size);
}

ADASLICE_DEF size_t adaslice_varint_put(unsigned char *out, uint32_t v)
{
    size_t n = 0;
    while (v >= 0x80u) {
        if (out) out[n] = (unsigned char)(v | 0x80u);
        n++;
        v >>= 7;
    }
    if (out) out[n] = (unsigned char)v;
    return n + 1;
}

ADASLICE_DEF adaslice_result adaslice_varint_push(adaslice_varint *r, unsigned char byte, int *done, uint32_t *value)
{
    *done = 0;
    /* the fifth byte may carry only the top 4 bits of 32 */
    if (r->shift == 28 && (byte & 0xf0u)) return ADASLICE_ERR_VARINT;
    r->value |= (uint32_t)(byte & 0x7fu) << r->shift;
    if (byte & 0x80u) { r->shift += 7; return ADASLICE_OK; }
    *value = r->value;
    *done = 1;
    r->value = 0;
    r->shift = 0;
    return ADASLICE_OK;
}

static uint32_t adaslice__rle_stride(uint32_t width, int bits)
{
    return bits == 1 ? (width + 7u) / 8u : width;
}


ADASLICE_DEF size_t adaslice_rle_bound(uint32_t width, uint32_t height, int bits)
{
    /* the worst row alternates every pixel: a header and, per pixel, a
       length of 1 byte (plus the value byte at 8 bits) */
    size_t per_row = 5u + (size_t)width * (bits == 1 ? 1u : 2u) + 1u;
    return per_row * height;
}

/* The encoder works a word at a time: a mask is mostly whole bytes of one
   colour and rows that repeat the row above. */
static uint64_t adaslice__load64(const unsigned char *p)
{
    uint64_t w;
    memcpy(&w, p, 8);
    return w;
}

/* Where bytes equal to `fill` stop, from byte b, at most at `end`. */
static uint32_t adaslice__fill_end(const unsigned char *row, uint32_t b, uint32_t end, unsigned char fill)
{
    const uint64_t all = 0x0101010101010101u * fill;
    while (end - b >= 8 && adaslice__load64(row + b) == all) b += 8;
    while (b < end && row[b] == fill) b++;
    return b;
}

/* 1-bit: the first pixel from x on that is not `lit`, or width. */
static uint32_t adaslice__run_end_1(const unsigned char *row, uint32_t x, uint32_t width, unsigned lit)
{
    while ((x & 7u) && x < width && ((row[x >> 3] >> (7u - (x & 7u))) & 1u) == lit) x++;
    if (x & 7u || x >= width) return x < width ? x : width;
    x = adaslice__fill_end(row, x >> 3, width >> 3, lit ? 0xffu : 0x00u) << 3;
    while (x < width && ((row[x >> 3] >> (7u - (x & 7u))) & 1u) == lit) x++;
    return x;
}

/* Pixels, not bytes: a 1-bit row's padding bits may hold anything. NULL
   for b is a dark row. */
static int adaslice__rows_equal(const unsigned char *a, const unsigned char *b, uint32_t width, int bits)
{
    uint32_t whole = bits == 1 ? width >> 3 : width, tail = bits == 1 ? width & 7u : 0;
    unsigned char pixels = (unsigned char)(0xffu << (8u - tail));
    if (b) {
        if (memcmp(a, b, whole)) return 0;
        return !tail || !((a[whole] ^ b[whole]) & pixels);
    }
    return adaslice__fill_end(a, 0, whole, 0) == whole && (!tail || !(a[whole] & pixels));
}

ADASLICE_DEF size_t adaslice_rle_put_repeat(unsigned char *out, uint32_t rows)
{
    return adaslice_varint_put(out, (rows - 1u) << 1 | 1u);
}

ADASLICE_DEF size_t adaslice_rle_put_row(unsigned char *out, uint32_t runs)
{
    return adaslice_varint_put(out, runs << 1);
}

ADASLICE_DEF size_t adaslice_rle_put_run(unsigned char *out, int bits, unsigned value, uint32_t length)
{
    if (bits != 8) return adaslice_varint_put(out, length);
    if (out) *out++ = (unsigned char)value;
    return 1 + adaslice_varint_put(out, length);
}

/* The runs of one row into out (NULL: only counted); returns the runs. */
static uint32_t adaslice__rle_runs(const unsigned char *row, uint32_t width, int bits, unsigned char *out, size_t *size)
{
    uint32_t x = 0, runs = 0;
    size_t n = 0;
    if (bits == 8) {
        while (x < width) {
            uint32_t start = x;
            x = adaslice__fill_end(row, x, width, row[x]);
            n += adaslice_rle_put_run(out ? out + n : NULL, 8, row[start], x - start);
            runs++;
        }
    } else {
        unsigned lit = 0;
        while (x < width) {
            uint32_t start = x;
            x = adaslice__run_end_1(row, x, width, lit);
            n += adaslice_rle_put_run(out ? out + n : NULL, 1, lit, x - start);
            runs++;
            lit ^= 1u;
        }
    }
    *size = n;
    return runs;
}

ADASLICE_DEF adaslice_result adaslice_rle_encode(const unsigned char *image, size_t stride, uint32_t width,
                                                 uint32_t height, int bits, unsigned char *out, size_t capacity,
                                                 size_t *size)
{
    /* a row's runs go 5 bytes in, after the room for its header, and move
       up to it once the header's size is known; a row takes at most this */
    const size_t worst_row = adaslice_rle_bound(width, 1, bits) + 5u;
    unsigned char spill[5];
    size_t n = 0;
    uint32_t y, repeat = 0, rs = adaslice__rle_stride(width, bits);
    const unsigned char *prev = NULL;
    if (size) *size = 0;
    if (!image || !out || !size || (bits != 1 && bits != 8) || !width || !height || width >= ((uint32_t)1 << 24) ||
        height >= ((uint32_t)1 << 24) || stride < rs)
        return ADASLICE_ERR_ARGUMENT;
    for (y = 0; y <= height; y++) {
        const unsigned char *row = y < height ? image + (size_t)y * stride : NULL;
        if (row && adaslice__rows_equal(row, prev, width, bits)) { repeat++; prev = row; continue; }
        if (repeat) {
            size_t h = adaslice_rle_put_repeat(spill, repeat);
            if (capacity - n < h) return ADASLICE_ERR_OVERFLOW;
            memcpy(out + n, spill, h);
            n += h;
            repeat = 0;
        }
        if (!row) break;
        {
            size_t row_bytes, h;
            uint32_t runs;
            if (capacity - n >= worst_row) {
                runs = adaslice__rle_runs(row, width, bits, out + n + 5, &row_bytes);
                h = adaslice_rle_put_row(spill, runs);
                memmove(out + n + h, out + n + 5, row_bytes);
                memcpy(out + n, spill, h);
            } else { /* near the end of a small buffer: counted first */
                runs = adaslice__rle_runs(row, width, bits, NULL, &row_bytes);
                h = adaslice_rle_put_row(spill, runs);
                if (capacity - n < h + row_bytes) return ADASLICE_ERR_OVERFLOW;
                memcpy(out + n, spill, h);
                (void)adaslice__rle_runs(row, width, bits, out + n + h, &row_bytes);
            }
            n += h + row_bytes;
        }
        prev = row;
    }
    *size = n;
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_rle_decoder_init(adaslice_rle_decoder *dec, uint32_t width, uint32_t height,
                                                       int bits, unsigned char *row, size_t row_size)
{
    if (!dec) return ADASLICE_ERR_ARGUMENT;
    memset(dec, 0, sizeof *dec);
    if (!row || (bits != 1 && bits != 8) || !width || !height || width >= ((uint32_t)1 << 24) || height >= ((uint32_t)1 << 24) ||
        row_size < adaslice__rle_stride(width, bits))
        return dec->error = ADASLICE_ERR_ARGUMENT;
    dec->width = width;
    dec->height = height;
    dec->bits = (unsigned char)bits;
    dec->stride = adaslice__rle_stride(width, bits);
    dec->row = row;
    /* x^0 (CRC-32 is bit-reflected: the top bit is x^0), raised to
       x^(8 stride) a step at a time once a repeat needs it */
    dec->row_shift = 0x80000000u;
    while (dec->stride >> dec->shift_bits) dec->shift_bits++;
    memset(row, 0, dec->stride);
    return ADASLICE_OK;
}

enum { ADASLICE__RLE_HEADER = 0, ADASLICE__RLE_VALUE, ADASLICE__RLE_LENGTH };

static void adaslice__rle_fill(adaslice_rle_decoder *dec, uint32_t len)
{
    uint32_t x = dec->x, end = x + len;
    if (dec->bits == 8) { memset(dec->row + x, dec->pixel, len); return; }
    if (!dec->pixel) return; /* rows start dark */
    while (x < end && (x & 7u)) { dec->row[x >> 3] |= (unsigned char)(0x80u >> (x & 7u)); x++; }
    if (end - x >= 8) { memset(dec->row + (x >> 3), 0xff, (end - x) >> 3); x += (end - x) & ~7u; }
    while (x < end) { dec->row[x >> 3] |= (unsigned char)(0x80u >> (x & 7u)); x++; }
}

ADASLICE_DEF uint32_t adaslice_crc32_mul(uint32_t a, uint32_t b)
{
    uint32_t p = 0;
    for (; a; a <<= 1) {
        if (a & 0x80000000u) p ^= b;
        b = b & 1u ? (b >> 1) ^ 0xedb88320u : b >> 1; /* b * x */
    }
    return p;
}

/* The finished row's CRC, then a repeat's rows, as far as *budget (of a
   call's `whole`) allows. The budget is in row bytes of CRC. A repeated
   row's CRC comes by combination, as zlib's crc32_combine: for rows A then
   B, crc(AB) = crc(A) * x^(8 |B|) + crc(B) mod the polynomial, one
   multiplication where the row's bytes are hundreds of table steps; it costs
   ADASLICE_RLE_REPEAT_COST bytes of the budget, about what the
   multiplication takes (docs/BENCHMARKS.md has the cycles on an ATmega2560). */
static void adaslice__rle_flush(adaslice_rle_decoder *dec, uint32_t *budget, uint32_t whole,
                                void (*emit)(void *, uint32_t, const unsigned char *), void *ctx)
{
    for (;;) {
        uint32_t n;
        /* a repeat of a row emitted before (its CRC began with row_crc) */
        if (!dec->crc_left && dec->repeat && dec->rows && dec->stride > ADASLICE_RLE_REPEAT_COST) {
            /* a call's budget below the cost still makes progress */
            if (*budget < ADASLICE_RLE_REPEAT_COST && *budget != whole) return;
            if (dec->shift_bits) {
                /* x^(8 stride), stride's bits from the top: square, times x^8 for a 1 */
                dec->shift_bits--;
                dec->row_shift = adaslice_crc32_mul(dec->row_shift, dec->row_shift);
                if (dec->stride >> dec->shift_bits & 1u) dec->row_shift = adaslice_crc32_mul(0x00800000u, dec->row_shift);
            } else {
                if (!dec->row_alone) {
                    /* its own: crc(before, row) - crc(before) * x^(8 stride) */
                    dec->row_crc = dec->crc ^ adaslice_crc32_mul(dec->row_crc, dec->row_shift);
                    dec->row_alone = 1;
                }
                dec->crc = adaslice_crc32_mul(dec->crc, dec->row_shift) ^ dec->row_crc;
                dec->repeat--;
                if (emit) emit(ctx, dec->rows, dec->row);
                dec->rows++;
            }
            *budget -= *budget < ADASLICE_RLE_REPEAT_COST ? *budget : ADASLICE_RLE_REPEAT_COST;
            continue;
        }
        if (!dec->crc_left && dec->repeat) {
            dec->repeat--;
            dec->crc_left = dec->stride;
        }
        if (!dec->crc_left || !*budget) return;
        if (dec->crc_left == dec->stride) {
            /* a row's CRC begins: what came before it, for its repeats */
            dec->row_crc = dec->crc;
            dec->row_alone = 0;
        }
        n = dec->crc_left < *budget ? dec->crc_left : *budget;
        dec->crc = adaslice_crc32(dec->crc, dec->row + (dec->stride - dec->crc_left), n);
        dec->crc_left -= n;
        *budget -= n;
        if (!dec->crc_left) {
            if (emit) emit(ctx, dec->rows, dec->row);
            dec->rows++;
        }
    }
}

/* One whole number read: what it means depends on the state. */
static adaslice_result adaslice__rle_number(adaslice_rle_decoder *dec, uint32_t v)
{
    if (dec->state == ADASLICE__RLE_HEADER) {
        if (v & 1u) {
            uint32_t times = (v >> 1) + 1u;
            if (times > dec->height - dec->rows) return ADASLICE_ERR_ROWS;
            dec->repeat = times; /* emitted by the caller, as its budget allows */
            return ADASLICE_OK;
        }
        if (dec->rows >= dec->height) return ADASLICE_ERR_ROWS;
        dec->runs = v >> 1;
        if (!dec->runs) return ADASLICE_ERR_RUN;
        dec->x = 0;
        dec->pixel = 0;
        memset(dec->row, 0, dec->stride);
        dec->state = dec->bits == 8 ? ADASLICE__RLE_VALUE : ADASLICE__RLE_LENGTH;
        return ADASLICE_OK;
    }
    /* a run's length */
    if (v > dec->width - dec->x || (v == 0 && (dec->bits == 8 || dec->x > 0 || dec->pixel))) return ADASLICE_ERR_RUN;
    adaslice__rle_fill(dec, v);
    dec->x += v;
    dec->runs--;
    if (dec->bits == 1) dec->pixel ^= 1u;
    if (!dec->runs) {
        if (dec->x != dec->width) return ADASLICE_ERR_RUN;
        dec->crc_left = dec->stride; /* emitted once its CRC is in */
        dec->state = ADASLICE__RLE_HEADER;
    } else {
        if (dec->x == dec->width) return ADASLICE_ERR_RUN;
        dec->state = dec->bits == 8 ? ADASLICE__RLE_VALUE : ADASLICE__RLE_LENGTH;
    }
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_rle_decode_rows(adaslice_rle_decoder *dec, const unsigned char *data,
                                                      size_t size, uint32_t max_bytes, size_t *used,
                                                      void (*emit)(void *ctx, uint32_t y, const unsigned char *row),
                                                      void *ctx)
{
    size_t i = 0;
    uint32_t budget = max_bytes;
    if (used) *used = 0;
    if (!dec->row || !max_bytes) return dec->error = ADASLICE_ERR_ARGUMENT;
    for (;; i++) {
        unsigned char c;
        adaslice__rle_flush(dec, &budget, max_bytes, emit, ctx);
        if (ADASLICE_RLE_PENDING(dec) || !budget || i >= size || dec->error) break;
        c = data[i];
        if (dec->state == ADASLICE__RLE_VALUE) {
            dec->pixel = c;
            dec->state = ADASLICE__RLE_LENGTH;
        } else {
            uint32_t v = 0;
            int done;
            if ((dec->error = adaslice_varint_push(&dec->number, c, &done, &v)) != ADASLICE_OK) break;
            if (done && (dec->error = adaslice__rle_number(dec, v)) != ADASLICE_OK) break;
        }
        dec->offset++;
    }
    if (used) *used = i;
    return dec->error;
}

ADASLICE_DEF adaslice_result adaslice_rle_decode(adaslice_rle_decoder *dec, const unsigned char *data, size_t size,
                                                 void (*emit)(void *ctx, uint32_t y, const unsigned char *row),
                                                 void *ctx)
{
    return adaslice_rle_decode_rows(dec, data, size, UINT32_MAX, NULL, emit, ctx);
}

ADASLICE_DEF int adaslice_rle_finished(const adaslice_rle_decoder *dec)
{
    return !dec->error && !ADASLICE_RLE_PENDING(dec) && dec->rows == dec->height && dec->state == ADASLICE__RLE_HEADER && dec->number.shift == 0;
}

#endif /* ADASLICE_MCU_IMPLEMENTATION_DONE */
#endif /* ADASLICE_MCU_IMPLEMENTATION */
