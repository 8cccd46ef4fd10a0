/* Frames on the serial link: see frame.h and link/PROTOCOL.md. */
#include "frame.h"
#include <string.h>

uint16_t link_crc16(const uint8_t *data, size_t size)
{
    uint16_t crc = 0xffffu;
    while (size--) {
        int bit;
        crc ^= (uint16_t)(*data++ << 8);
        for (bit = 0; bit < 8; bit++) crc = (uint16_t)(crc & 0x8000u ? ((unsigned)crc << 1) ^ 0x1021u : (unsigned)crc << 1);
    }
    return crc;
}

size_t link_frame_build(uint8_t *out, uint8_t seq, uint8_t type, const uint8_t *payload, size_t size)
{
    size_t len = size + LINK_FRAME_MIN;
    uint16_t crc;
    if (size > LINK_PAYLOAD_MAX) return 0;
    out[0] = (uint8_t)len;
    out[1] = seq;
    out[2] = type;
    if (size) memcpy(out + 3, payload, size);
    crc = link_crc16(out, len - 3);
    out[len - 3] = (uint8_t)(crc >> 8);
    out[len - 2] = (uint8_t)crc;
    out[len - 1] = LINK_SYNC;
    return len;
}

void link_deframer_init(link_deframer *d, int (*accept)(uint8_t type))
{
    memset(d, 0, sizeof *d);
    d->accept = accept;
}

void link_deframe_push(link_deframer *d, uint8_t byte)
{
    /* next() never lets a full buffer stand, so there is always room */
    if (d->len < LINK_FRAME_MAX) d->buf[d->len++] = byte;
}

static void drop(link_deframer *d, size_t n)
{
    memmove(d->buf, d->buf + n, d->len - n);
    d->len = (uint16_t)(d->len - n);
}

size_t link_deframe_next(link_deframer *d)
{
    for (;;) {
        size_t n;
        if (!d->len) return 0;
        if (d->hunting) {
            uint8_t *sync = (uint8_t *)memchr(d->buf, LINK_SYNC, d->len);
            if (!sync) { d->len = 0; return 0; }
            drop(d, (size_t)(sync - d->buf) + 1);
            d->hunting = 0;
            continue;
        }
        n = d->buf[0];
        if (n < LINK_FRAME_MIN) { drop(d, 1); continue; }
        if (d->len >= 3 && d->accept && !d->accept(d->buf[2])) { d->bad++; drop(d, 1); d->hunting = 1; continue; }
        if (d->len < n) return 0;
        if (d->buf[n - 1] == LINK_SYNC && link_crc16(d->buf, n - 3) == (uint16_t)(d->buf[n - 3] << 8 | d->buf[n - 2]))
            return n;
        d->bad++;
        drop(d, 1);
        d->hunting = 1;
    }
}

void link_deframe_consume(link_deframer *d)
{
    if (d->len && d->buf[0] <= d->len) drop(d, d->buf[0]);
}
