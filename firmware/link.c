/* Frames on the serial link: see link.h and firmware/PROTOCOL.md. */
#include "link.h"
#include "protocol.h"
#include <string.h>

uint16_t fw_crc16(const uint8_t *data, size_t size)
{
    uint16_t crc = 0xffffu;
    while (size--) {
        int bit;
        crc ^= (uint16_t)(*data++ << 8);
        for (bit = 0; bit < 8; bit++) crc = (uint16_t)(crc & 0x8000u ? ((unsigned)crc << 1) ^ 0x1021u : (unsigned)crc << 1);
    }
    return crc;
}

size_t fw_frame_build(uint8_t *out, uint8_t seq, uint8_t type, const uint8_t *payload, size_t size)
{
    size_t len = size + FW_FRAME_MIN;
    uint16_t crc;
    if (size > FW_PAYLOAD_MAX) return 0;
    out[0] = (uint8_t)len;
    out[1] = seq;
    out[2] = type;
    if (size) memcpy(out + 3, payload, size);
    crc = fw_crc16(out, len - 3);
    out[len - 3] = (uint8_t)(crc >> 8);
    out[len - 2] = (uint8_t)crc;
    out[len - 1] = FW_SYNC;
    return len;
}

void fw_deframer_init(fw_deframer *d, int (*accept)(uint8_t type))
{
    memset(d, 0, sizeof *d);
    d->accept = accept;
}

int fw_host_to_mcu_type(uint8_t type)
{
    type &= (uint8_t)~FW_ROUND_BIT;
    return type == FW_MSG_HELLO || type == FW_MSG_STATUS || (type >= FW_MSG_PROFILE && type <= FW_MSG_PLAN_DATA) ||
           type == FW_MSG_MASK || type == FW_MSG_MASK_DATA || (type >= FW_MSG_HOME && type <= FW_MSG_ABORT) ||
           type == FW_MSG_EXIT;
}

int fw_mcu_to_host_type(uint8_t type)
{
    return type >= FW_MSG_ACK && type <= FW_MSG_PLAN;
}

void fw_deframe_push(fw_deframer *d, uint8_t byte)
{
    /* next() never lets a full buffer stand, so there is always room */
    if (d->len < FW_FRAME_MAX) d->buf[d->len++] = byte;
}

static void drop(fw_deframer *d, size_t n)
{
    memmove(d->buf, d->buf + n, d->len - n);
    d->len = (uint16_t)(d->len - n);
}

size_t fw_deframe_next(fw_deframer *d)
{
    for (;;) {
        size_t n;
        if (!d->len) return 0;
        if (d->hunting) {
            uint8_t *sync = (uint8_t *)memchr(d->buf, FW_SYNC, d->len);
            if (!sync) { d->len = 0; return 0; }
            drop(d, (size_t)(sync - d->buf) + 1);
            d->hunting = 0;
            continue;
        }
        n = d->buf[0];
        if (n < FW_FRAME_MIN) { drop(d, 1); continue; }
        if (d->len >= 3 && d->accept && !d->accept(d->buf[2])) { d->bad++; drop(d, 1); d->hunting = 1; continue; }
        if (d->len < n) return 0;
        if (d->buf[n - 1] == FW_SYNC && fw_crc16(d->buf, n - 3) == (uint16_t)(d->buf[n - 3] << 8 | d->buf[n - 2]))
            return n;
        d->bad++;
        drop(d, 1);
        d->hunting = 1;
    }
}

void fw_deframe_consume(fw_deframer *d)
{
    if (d->len && d->buf[0] <= d->len) drop(d, d->buf[0]);
}

size_t fw_varint_put(uint8_t *out, uint32_t v)
{
    size_t n = 0;
    while (v >= 0x80u) { out[n++] = (uint8_t)(v | 0x80u); v >>= 7; }
    out[n++] = (uint8_t)v;
    return n;
}

size_t fw_profile_chunk(uint8_t *out, size_t max, const uint32_t *units, const unsigned char *forced, uint32_t n,
                        uint32_t *at)
{
    size_t used = 0;
    for (; *at < n && used + 5 <= max; (*at)++)
        used += fw_varint_put(out + used, units[*at] << 1 | (forced && forced[*at] ? 1u : 0u));
    return used;
}
