/* Frames on the serial link: see frame.h and link/PROTOCOL.md. */
#include "frame.h"
#include <string.h>

/* A byte at a time without a table: 0x1021 has bits 12, 5 and 0, so the
   eight shifts of the bitwise form fold into three, here on the CRC's two
   bytes apart (x << 12 and x << 5 of the byte x fall into the high byte as
   x << 4 and x >> 3): the same CRC in a fraction of the cycles on an 8-bit
   core, and no RAM for a table. */
static uint16_t crc16_byte(uint16_t crc, uint8_t byte)
{
    uint8_t x = (uint8_t)((crc >> 8) ^ byte), hi, lo;
    x ^= (uint8_t)(x >> 4);
    hi = (uint8_t)(crc ^ (uint8_t)(x << 4) ^ (x >> 3));
    lo = (uint8_t)((uint8_t)(x << 5) ^ x);
    return (uint16_t)(hi << 8 | lo);
}

uint16_t link_crc16_more(uint16_t crc, const uint8_t *data, size_t size)
{
    while (size--) crc = crc16_byte(crc, *data++);
    return crc;
}

uint16_t link_crc16(const uint8_t *data, size_t size) { return link_crc16_more(0xffffu, data, size); }

size_t link_frame_build(uint8_t *out, uint8_t seq, uint8_t type, const uint8_t *payload, size_t size)
{
    size_t len = size + LINK_FRAME_MIN;
    uint16_t crc;
    if (size > LINK_PAYLOAD_MAX) return 0;
    out[0] = (uint8_t)len;
    out[1] = seq;
    out[2] = type;
    if (size) memmove(out + 3, payload, size); /* the payload may be built in place, at out + 3 */
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
    d->crc = 0xffffu;
}

/* The CRC of the frame at buf[0], carried over its first `upto` bytes (at
   most those buffered). Each byte pushed carries it one byte on, so a
   frame's check costs no more when its last byte arrives than any other
   byte; only after damage, when the next frame starts further on, does it
   start over from the bytes already there. */
static void crc_upto(link_deframer *d, size_t upto)
{
    if (upto > d->len) upto = d->len;
    while (d->checked < upto) d->crc = crc16_byte(d->crc, d->buf[d->checked++]);
}

/* A frame still arriving, its LEN and type checked when they came (next()
   after each byte): nothing for next() to decide, as on most bytes. */
static int arriving(const link_deframer *d) { return !d->hunting && d->len > 3 && d->len < d->buf[0]; }

int link_deframe_push(link_deframer *d, uint8_t byte)
{
    /* next() never lets a full buffer stand, so there is always room */
    if (d->len < LINK_FRAME_MAX) d->buf[d->len++] = byte;
    if (!d->hunting && d->buf[0] >= LINK_FRAME_MIN) crc_upto(d, d->buf[0] - 3u);
    return !arriving(d);
}

static void drop(link_deframer *d, size_t n)
{
    memmove(d->buf, d->buf + n, d->len - n);
    d->len = (uint16_t)(d->len - n);
    d->crc = 0xffffu;
    d->checked = 0;
}

size_t link_deframe_next(link_deframer *d)
{
    if (arriving(d)) return 0;
    for (;;) {
        size_t n;
        if (!d->len) return 0;
        if (d->hunting) {
            uint8_t *sync = (uint8_t *)memchr(d->buf, LINK_SYNC, d->len);
            if (!sync) { drop(d, d->len); return 0; }
            drop(d, (size_t)(sync - d->buf) + 1);
            d->hunting = 0;
            continue;
        }
        n = d->buf[0];
        if (n < LINK_FRAME_MIN) { drop(d, 1); continue; }
        if (d->len >= 3 && d->accept && !d->accept(d->buf[2])) { d->bad++; drop(d, 1); d->hunting = 1; continue; }
        if (d->len < n) return 0;
        crc_upto(d, n - 3);
        if (d->buf[n - 1] == LINK_SYNC && d->crc == (uint16_t)(d->buf[n - 3] << 8 | d->buf[n - 2])) return n;
        d->bad++;
        drop(d, 1);
        d->hunting = 1;
    }
}

void link_deframe_consume(link_deframer *d)
{
    if (d->len && d->buf[0] <= d->len) drop(d, d->buf[0]);
}
