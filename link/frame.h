/* The framing both ends of the serial link share (link/PROTOCOL.md):
       LEN  SEQ  TYPE  payload...  CRC16-hi  CRC16-lo  0x7E
   LEN counts the whole frame (6..255); the CRC-16 (CCITT, polynomial 0x1021,
   initial 0xFFFF) covers LEN through the payload. Portable C99, no stdio or
   malloc: the host tool and the MCU compile this same file. */
#ifndef LINK_FRAME_H
#define LINK_FRAME_H
#include <stddef.h>
#include <stdint.h>

#define LINK_FRAME_MIN 6u
#define LINK_FRAME_MAX 255u
#define LINK_PAYLOAD_MAX (LINK_FRAME_MAX - LINK_FRAME_MIN)
#define LINK_SYNC 0x7eu

uint16_t link_crc16(const uint8_t *data, size_t size);
/* The same carried on over more bytes: link_crc16(a + b) is
   link_crc16_more(link_crc16(a), b), so a frame can be sent in pieces. */
uint16_t link_crc16_more(uint16_t crc, const uint8_t *data, size_t size);
/* Builds a frame into out (LINK_FRAME_MAX bytes); returns its length, 0 if the
   payload is too long. The payload may be at out + 3 already. */
size_t link_frame_build(uint8_t *out, uint8_t seq, uint8_t type, const uint8_t *payload, size_t size);

/* Reassembles frames from a byte stream. After a frame that fails its CRC or
   sync byte it drops bytes up to the next 0x7E and reads on from there, so a
   good frame after damage is found again. */
typedef struct link_deframer {
    /* the message types this end takes (NULL: any): a frame of another type
       is damage, dropped at once rather than after LEN bytes */
    int (*accept)(uint8_t type);
    /* the small fields before the buffer: an 8-bit core reaches them by a
       short displacement, as it does on every byte */
    uint16_t len;
    uint8_t hunting;     /* dropping bytes until a sync byte */
    uint16_t crc;        /* the CRC of buf[0 .. checked), carried as bytes arrive */
    uint8_t checked;
    uint32_t bad;        /* frames that failed their check */
    uint8_t buf[LINK_FRAME_MAX];
} link_deframer;

/* accept: link_host_to_mcu_type or link_mcu_to_host_type (link/messages.h) */
void link_deframer_init(link_deframer *d, int (*accept)(uint8_t type));
/* Appends a byte; then call link_deframe_next until it returns 0. Returns
   0 when that would return 0 at once (a frame still arriving, most bytes),
   so a small core may skip the call. */
int link_deframe_push(link_deframer *d, uint8_t byte);
/* The length of a good frame at d->buf, or 0 when none is complete; the
   caller handles it and calls link_deframe_consume. */
size_t link_deframe_next(link_deframer *d);
void link_deframe_consume(link_deframer *d);
#endif
