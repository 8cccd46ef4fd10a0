/* The framing both ends of the serial link share (firmware/PROTOCOL.md):
       LEN  SEQ  TYPE  payload...  CRC16-hi  CRC16-lo  0x7E
   LEN counts the whole frame (6..255); the CRC-16 (CCITT, polynomial 0x1021,
   initial 0xFFFF) covers LEN through the payload. Portable C99, no stdio or
   malloc: the host tool and the MCU compile this same file. */
#ifndef FW_LINK_H
#define FW_LINK_H
#include <stddef.h>
#include <stdint.h>

#define FW_FRAME_MIN 6u
#define FW_FRAME_MAX 255u
#define FW_PAYLOAD_MAX (FW_FRAME_MAX - FW_FRAME_MIN)
#define FW_SYNC 0x7eu

uint16_t fw_crc16(const uint8_t *data, size_t size);
/* Builds a frame into out (FW_FRAME_MAX bytes); returns its length, 0 if the
   payload is too long. */
size_t fw_frame_build(uint8_t *out, uint8_t seq, uint8_t type, const uint8_t *payload, size_t size);

/* Reassembles frames from a byte stream. After a frame that fails its CRC or
   sync byte it drops bytes up to the next 0x7E and reads on from there, so a
   good frame after damage is found again. */
typedef struct fw_deframer {
    /* the message types this end takes (NULL: any): a frame of another type
       is damage, dropped at once rather than after LEN bytes */
    int (*accept)(uint8_t type);
    uint8_t buf[FW_FRAME_MAX];
    uint16_t len;
    uint8_t hunting;     /* dropping bytes until a sync byte */
    uint32_t bad;        /* frames that failed their check */
} fw_deframer;

void fw_deframer_init(fw_deframer *d, int (*accept)(uint8_t type));
/* The types each end takes. */
int fw_host_to_mcu_type(uint8_t type);
int fw_mcu_to_host_type(uint8_t type);
/* Appends a byte; then call fw_deframe_next until it returns 0. */
void fw_deframe_push(fw_deframer *d, uint8_t byte);
/* The length of a good frame at d->buf, or 0 when none is complete; the
   caller handles it and calls fw_deframe_consume. */
size_t fw_deframe_next(fw_deframer *d);
void fw_deframe_consume(fw_deframer *d);

/* A LEB128 varint (7 bits a byte, low first; at most 5 bytes) into out. */
size_t fw_varint_put(uint8_t *out, uint32_t v);
/* PROFILE_DATA's payload: bins from *at on, each the varint of
   units << 1 | forced, as many whole ones as fit in `max` bytes (>= 5);
   advances *at and returns the bytes written. forced may be NULL. */
size_t fw_profile_chunk(uint8_t *out, size_t max, const uint32_t *units, const unsigned char *forced, uint32_t n,
                        uint32_t *at);

/* Little-endian fields of payloads. */
static inline uint32_t fw_get32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static inline uint16_t fw_get16(const uint8_t *p) { return (uint16_t)(p[0] | p[1] << 8); }
static inline void fw_put32(uint8_t *p, uint32_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24); }
static inline void fw_put16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
#endif
