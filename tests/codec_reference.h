/* The mask code's encoder and CRC-32 as they were before they were made
   fast (one pixel and one nibble at a time): the references the fast ones
   must agree with, byte for byte. */
#ifndef ADASLICE_CODEC_REFERENCE_H
#define ADASLICE_CODEC_REFERENCE_H
#include "../adaslice_mcu.h"
#include <string.h>

static uint32_t ref_crc32(uint32_t crc, const void *data, size_t size)
{
    /* a nibble table: 64 bytes of flash instead of 1 KiB, at half the speed */
    static const uint32_t nibble[16] = {
        0x00000000u, 0x1db71064u, 0x3b6e20c8u, 0x26d930acu, 0x76dc4190u, 0x6b6b51f4u, 0x4db26158u, 0x5005713cu,
        0xedb88320u, 0xf00f9344u, 0xd6d6a3e8u, 0xcb61b38cu, 0x9b64c2b0u, 0x86d3d2d4u, 0xa00ae278u, 0xbdbdf21cu};
    const unsigned char *p = (const unsigned char *)data;
    crc = ~crc;
    while (size--) {
        crc ^= *p++;
        crc = (crc >> 4) ^ nibble[crc & 15u];
        crc = (crc >> 4) ^ nibble[crc & 15u];
    }
    return ~crc;
}

static uint32_t ref_rle_stride(uint32_t width, int bits)
{
    return bits == 1 ? (width + 7u) / 8u : width;
}

static int ref_rle_pixel(const unsigned char *row, uint32_t x, int bits)
{
    return bits == 1 ? (row[x >> 3] >> (7u - (x & 7u))) & 1 : row[x];
}

/* The runs of one row into out (NULL: only counted); returns the runs. */
static uint32_t ref_rle_runs(const unsigned char *row, uint32_t width, int bits, unsigned char *out, size_t *size)
{
    uint32_t x = 0, runs = 0;
    int current = 0;
    size_t n = 0;
    while (x < width) {
        uint32_t start = x;
        if (bits == 8) current = row[x];
        while (x < width && ref_rle_pixel(row, x, bits) == current) x++;
        if (bits == 8 && out) out[n] = (unsigned char)current;
        if (bits == 8) n++;
        n += adaslice_varint_put(out ? out + n : NULL, x - start);
        runs++;
        if (bits == 1) current ^= 1;
    }
    *size = n;
    return runs;
}

static adaslice_result ref_rle_encode(const unsigned char *image, size_t stride, uint32_t width,
                                                 uint32_t height, int bits, unsigned char *out, size_t capacity,
                                                 size_t *size)
{
    size_t n = 0, row_bytes;
    uint32_t y = 0, repeat = 0, rs = ref_rle_stride(width, bits);
    const unsigned char *prev = NULL;
    unsigned char header[5];
    if (size) *size = 0;
    if (!image || !out || !size || (bits != 1 && bits != 8) || !width || !height || width >= (1u << 24) ||
        height >= (1u << 24) || stride < rs)
        return ADASLICE_ERR_ARGUMENT;
    for (y = 0; y <= height; y++) {
        const unsigned char *row = y < height ? image + (size_t)y * stride : NULL;
        int same;
        if (row && prev) {
            uint32_t x;
            same = 1;
            /* compare pixels, not bytes: 1-bit padding bits may hold anything */
            for (x = 0; x < width && same; x++)
                same = ref_rle_pixel(row, x, bits) == ref_rle_pixel(prev, x, bits);
        } else if (row) {
            uint32_t x;
            same = 1; /* before the first row, the previous row is dark */
            for (x = 0; x < width && same; x++) same = ref_rle_pixel(row, x, bits) == 0;
        } else {
            same = 0;
        }
        if (same) { repeat++; if (row) prev = row; continue; }
        if (repeat) {
            size_t h = adaslice_varint_put(header, ((repeat - 1u) << 1) | 1u);
            if (capacity - n < h) return ADASLICE_ERR_OVERFLOW;
            memcpy(out + n, header, h); n += h;
            repeat = 0;
        }
        if (!row) break;
        {
            uint32_t runs = ref_rle_runs(row, width, bits, NULL, &row_bytes);
            size_t h = adaslice_varint_put(header, runs << 1);
            if (capacity - n < h + row_bytes) return ADASLICE_ERR_OVERFLOW;
            memcpy(out + n, header, h); n += h;
            (void)ref_rle_runs(row, width, bits, out + n, &row_bytes);
            n += row_bytes;
        }
        prev = row;
    }
    *size = n;
    return ADASLICE_OK;
}

#endif
