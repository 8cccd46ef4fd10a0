/* Rows of layer masks: see maskrows.h. */
#include "maskrows.h"
#include <string.h>

void mask_row_grey(const unsigned char *image, size_t stride, int bits, int width, int y, unsigned char *out)
{
    const unsigned char *row = image + (size_t)y * stride;
    int x;
    if (bits == 8) { memcpy(out, row, (size_t)width); return; }
    for (x = 0; x + 8 <= width; x += 8) { /* a mask is mostly whole bytes of one colour */
        unsigned b = row[x >> 3];
        int i;
        if (b == 0 || b == 0xFF) memset(out + x, (int)(b & 0xFF), 8);
        else for (i = 0; i < 8; i++) out[x + i] = (unsigned char)((b >> (7 - i) & 1) ? 255 : 0);
    }
    for (; x < width; x++) out[x] = (unsigned char)((row[x >> 3] >> (7 - (x & 7)) & 1) ? 255 : 0);
}

/* Where the run of bytes equal to row[x] ends, at most at `end`: eight
   bytes at a time, as most of a mask is long runs of black. */
static int same_bytes_end(const unsigned char *row, int x, int end)
{
    const uint64_t all = 0x0101010101010101u * row[x];
    uint64_t word;
    for (x++; end - x >= 8; x += 8) {
        memcpy(&word, row + x, sizeof word);
        if (word != all) break;
    }
    while (x < end && row[x] == row[x - 1]) x++;
    return x;
}

void mask_row_runs(const unsigned char *row, int bits, int width, mask_run_fn run, void *ctx)
{
    int x = 0;
    if (bits == 8) {
        while (x < width) {
            int from = x;
            x = same_bytes_end(row, x, width);
            run(ctx, row[from], (uint64_t)(x - from));
        }
        return;
    }
    while (x < width) { /* whole 0x00 or 0xFF bytes go as runs of eight pixels a byte */
        const int whole_bytes = width >> 3;
        unsigned char b = row[x >> 3];
        if ((x & 7) == 0 && (x >> 3) < whole_bytes && (b == 0 || b == 0xFF)) {
            int from = x;
            x = same_bytes_end(row, x >> 3, whole_bytes) << 3;
            run(ctx, b, (uint64_t)(x - from));
        } else {
            run(ctx, (b >> (7 - (x & 7)) & 1) ? 255 : 0, 1);
            x++;
        }
    }
}

