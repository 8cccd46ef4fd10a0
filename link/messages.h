/* Every message of the serial protocol, defined once (link/PROTOCOL.md is the
   prose; tests/test_link.c holds the two against each other). The host tool,
   the firmware and the tests all encode and decode through the functions this
   file declares. Portable C99, no stdio, no malloc.

   A message is a list of fixed fields, little-endian, back to back:
       LINK_FIELDS_<NAME>(F)   F(type, name) per field, type u8 u16 u32 i32
   and, for a few, a tail of bytes after them (PROFILE_DATA, PLAN_DATA,
   MASK_DATA, PLAN). From each list come
       link_<name>                     a struct with those fields
       LINK_SIZE_<NAME>                the bytes of the fixed part
       link_put_<name>(out, &m)        encodes; returns the bytes written
       link_get_<name>(&m, p, size)    decodes; 0 if size is not the fixed size
                                       (at least it, for a message with a tail)
   and the row of LINK_MESSAGES, the table that describes all of them. */
#ifndef LINK_MESSAGES_H
#define LINK_MESSAGES_H
#include <stddef.h>
#include <stdint.h>

#define LINK_PROTOCOL_VERSION 6

/* ------------------------------------------------------------- the fields */

/* host -> MCU */
#define LINK_FIELDS_HELLO(F) F(u8, version)
#define LINK_FIELDS_PROFILE(F) F(u32, bins) F(u8, bins_min) F(u8, bins_max) F(u32, eps_units) F(u32, bin_nm)
#define LINK_FIELDS_PLAN_GET(F) F(u32, first)
#define LINK_FIELDS_PLAN_SET(F) F(u32, layers) F(u32, bin_nm)
#define LINK_FIELDS_MASK(F) F(u32, layer) F(u32, code_bytes) F(u32, crc32) F(u32, exposure_ms)
/* the host's own screen (a DIY printer's LCD on a Linux board): `layer` is
   drawn whole and on screen, lit for exposure_ms; layer 0: the screen is dark */
#define LINK_FIELDS_SCREEN(F) F(u32, layer) F(u32, exposure_ms)
/* SCREEN's layer for a test pattern of the host's (adaslice show), outside
   a print: EXPOSE may light it */
#define LINK_SCREEN_PATTERN 0xffffffffu
#define LINK_FIELDS_MOVE(F) F(i32, z_nm) F(u32, speed_um_s)
#define LINK_FIELDS_EXPOSE(F) F(u32, ms)
#define LINK_FIELDS_PRINT(F)                                                                                        \
    F(u32, first_layer) F(u32, peel_nm) F(u32, peel_speed_um_s) F(u32, return_speed_um_s) F(u32, settle_ms)        \
    F(u32, job)
#define LINK_FIELDS_EXIT(F) F(u8, code)
/* MCU -> host */
#define LINK_FIELDS_ACK(F) F(u8, nak)
#define LINK_FIELDS_IDENTIFY(F)                                                                                     \
    F(u8, version) F(u8, window) F(u32, max_bins) F(u8, max_layer_bins) F(u32, steps_per_mm) F(u16, width)          \
    F(u16, height) F(u8, bits) F(u32, pitch_nm) F(u32, z_max_nm) F(u32, tick_hz) F(u32, link_timeout_ms)        \
    F(u32, boot_id) F(u32, max_exposure_ms) F(u32, crc_byte_ns) F(u32, plan_bin_ns)
#define LINK_FIELDS_STATUS(F)                                                                                       \
    F(u8, state) F(u8, phase) F(u8, error) F(u8, error_seq) F(u8, flags) F(u32, layer) F(u32, layers)               \
    F(u32, mask_ready) F(u32, mask_layer) F(u32, mask_got) F(u16, masks_refused) F(i32, z_nm) F(u32, bins_in)       \
    F(u32, bad_frames) F(u8, window) F(u32, boot_id) F(u32, exposed) F(u32, exposure_left_ms) F(u32, job)         \
    F(u32, screen)
#define LINK_FIELDS_PLAN(F) F(u32, first) F(u32, layers) F(u32, bin_nm)
/* no fixed fields */
#define LINK_FIELDS_NONE(F)

/* ----------------------------------------------------------- the messages */

/* M(NAME, name, type, direction, fields, tail): tail 0 none, 1 bytes after
   the fixed fields; direction 0 host -> MCU, 1 MCU -> host. */
#define LINK_MESSAGE_LIST(M)                                                                                        \
    M(HELLO, hello, 0x01, 0, LINK_FIELDS_HELLO, 0)                                                                  \
    M(STATUS, status_request, 0x02, 0, LINK_FIELDS_NONE, 0)                                                         \
    M(PROFILE, profile, 0x10, 0, LINK_FIELDS_PROFILE, 0)                                                            \
    M(PROFILE_DATA, profile_data, 0x11, 0, LINK_FIELDS_NONE, 1)                                                     \
    M(PLAN_GET, plan_get, 0x12, 0, LINK_FIELDS_PLAN_GET, 0)                                                         \
    M(PLAN_SET, plan_set, 0x13, 0, LINK_FIELDS_PLAN_SET, 0)                                                         \
    M(PLAN_DATA, plan_data, 0x14, 0, LINK_FIELDS_NONE, 1)                                                           \
    M(MASK, mask, 0x20, 0, LINK_FIELDS_MASK, 0)                                                                     \
    M(MASK_DATA, mask_data, 0x21, 0, LINK_FIELDS_NONE, 1)                                                           \
    M(SCREEN, screen, 0x22, 0, LINK_FIELDS_SCREEN, 0)                                                               \
    M(HOME, home, 0x30, 0, LINK_FIELDS_NONE, 0)                                                                     \
    M(MOVE, move, 0x31, 0, LINK_FIELDS_MOVE, 0)                                                                     \
    M(EXPOSE, expose, 0x32, 0, LINK_FIELDS_EXPOSE, 0)                                                               \
    M(PRINT, print, 0x33, 0, LINK_FIELDS_PRINT, 0)                                                                  \
    M(PAUSE, pause, 0x34, 0, LINK_FIELDS_NONE, 0)                                                                   \
    M(RESUME, resume, 0x35, 0, LINK_FIELDS_NONE, 0)                                                                 \
    M(ABORT, abort, 0x36, 0, LINK_FIELDS_NONE, 0)                                                                   \
    M(EXIT, exit, 0x3f, 0, LINK_FIELDS_EXIT, 0)                                                                     \
    M(ACK, ack, 0x80, 1, LINK_FIELDS_ACK, 0)                                                                        \
    M(IDENTIFY, identify, 0x81, 1, LINK_FIELDS_IDENTIFY, 0)                                                         \
    M(STATUS_REPLY, status, 0x82, 1, LINK_FIELDS_STATUS, 0)                                                         \
    M(PLAN, plan, 0x83, 1, LINK_FIELDS_PLAN, 1)

#define LINK__TYPE(NAME, name, type, dir, FIELDS, tail) LINK_MSG_##NAME = type,
enum { LINK_MESSAGE_LIST(LINK__TYPE) LINK_MSG_END_ };
#undef LINK__TYPE

/* Bit 6 of a host frame's TYPE: the host's resend round (flips at each go-back-N
   resend); a NAK echoes it, so the host can tell a NAK its resend drew from one
   an older copy drew. */
#define LINK_ROUND_BIT 0x40u
/* ACK's nak byte: 0, or LINK_NAK | the round bit of the frame past the gap */
#define LINK_NAK 1u

/* ------------------------------------------- states, phases, flags, errors */

#define LINK_STATE_LIST(S)                                                                                          \
    S(IDLE, "idle") S(HOMING, "homing") S(MOVING, "moving") S(PLANNING, "planning") S(READY, "ready")               \
    S(PRINTING, "printing") S(PAUSED, "paused") S(DONE, "done")
#define LINK_PHASE_LIST(S)                                                                                          \
    S(MOVE, "moving to the layer") S(WAIT_MASK, "waiting for its mask") S(SETTLE, "settling")                       \
    S(EXPOSE, "exposing") S(PEEL, "peeling") S(DARK, "waiting for the host's screen to go dark")
/* STATUS error: the last command refused, with the sequence number of its frame */
#define LINK_ERROR_LIST(S)                                                                                          \
    S(NONE, "none")                                                                                                 \
    S(MESSAGE, "bad message")                   /* unknown type or a payload of the wrong size */                   \
    S(PROFILE, "bad profile header")            /* a profile header the planner cannot take */                      \
    S(PROFILE_DATA, "bad profile data")         /* more bins than announced, or a bad varint */                     \
    S(INFEASIBLE, "no plan meets eps")          /* with these layer bounds */                                       \
    S(NO_PLAN, "no plan")                       /* the command needs a plan */                                      \
    S(MASK_ORDER, "mask out of order")          /* not the next mask, or its display buffer is in use */            \
    S(MASK_CODE, "malformed mask code")         /* malformed or longer than announced */                            \
    S(MASK_CRC, "mask CRC mismatch")            /* the decoded mask differs: refused, send it again */              \
    S(LIMIT, "outside the soft limits")                                                                             \
    S(NOT_HOMED, "not homed")                                                                                       \
    S(HOME_FAILED, "homing failed")                                                                                 \
    S(BUSY, "busy")                             /* not in this state */                                             \
    S(PLAN_SIZE, "more bins than the printer takes")                                                                \
    S(MASK_EXPOSURE, "bad exposure")            /* 0 ms, or longer than IDENTIFY's max_exposure_ms */               \
    S(STEP_LATE, "a Z step could not be issued on time") /* motion stopped dead, Z unhomed, UV off */                 \
    S(ENDSTOP, "the Z endstop closed during a move")    /* a crash or lost steps: stopped dead, Z unhomed, UV off */  \
    S(WRONG_HEIGHT, "Z was not at the layer's height")  /* the light stayed off: print stopped */                     \
    S(MOVE_FAILED, "the print's move was refused")      /* the light stayed off: print stopped */                     \
    S(STACK, "the stack overran: halted until reset")    /* as STEP_LATE, and nothing lights or moves again */ \
    S(SCREEN_LIT, "the host's screen shows a mask")     /* Z moves only once the host says it is dark */    \
    S(SCREEN_LAYER, "not the layer the print waits for") /* SCREEN of another layer, or while Z moves */

#define LINK__STATE(NAME, text) LINK_STATE_##NAME,
#define LINK__PHASE(NAME, text) LINK_PHASE_##NAME,
#define LINK__ERROR(NAME, text) LINK_ERR_##NAME,
enum { LINK_STATE_LIST(LINK__STATE) LINK_STATE_COUNT };
enum { LINK_PHASE_LIST(LINK__PHASE) LINK_PHASE_COUNT };
enum { LINK_ERROR_LIST(LINK__ERROR) LINK_ERROR_COUNT };
#undef LINK__STATE
#undef LINK__PHASE
#undef LINK__ERROR

/* STATUS flags */
#define LINK_FLAG_HOMED 1u
#define LINK_FLAG_UV 2u
#define LINK_FLAG_MOVING 4u
#define LINK_FLAG_LINK_LOST 8u

/* Names for messages to people ("unknown" past the end). */
const char *link_state_name(unsigned state);
const char *link_phase_name(unsigned phase);
const char *link_error_name(unsigned error);

/* ------------------------------------------- structs, sizes, put and get */

typedef uint8_t link__u8;
typedef uint16_t link__u16;
typedef uint32_t link__u32;
typedef int32_t link__i32;
#define LINK__BYTES_u8 1
#define LINK__BYTES_u16 2
#define LINK__BYTES_u32 4
#define LINK__BYTES_i32 4

#define LINK__MEMBER(type, name) link__##type name;
#define LINK__BYTES(type, name) +LINK__BYTES_##type
#define LINK__DECLARE(NAME, name, type, dir, FIELDS, tail)                                                          \
    enum { LINK_SIZE_##NAME = 0 FIELDS(LINK__BYTES) };
LINK_MESSAGE_LIST(LINK__DECLARE)
#undef LINK__DECLARE

/* Structs, put and get for the messages with fixed fields. */
#define LINK__CODEC(NAME, name, FIELDS, tail)                                                                             \
    typedef struct link_##name { FIELDS(LINK__MEMBER) } link_##name;                                                \
    size_t link_put_##name(uint8_t *out, const link_##name *m);                                                     \
    int link_get_##name(link_##name *m, const uint8_t *p, size_t size);
#define LINK_CODEC_LIST(C)                                                                                          \
    C(HELLO, hello, LINK_FIELDS_HELLO, 0) C(PROFILE, profile, LINK_FIELDS_PROFILE, 0)                               \
    C(PLAN_GET, plan_get, LINK_FIELDS_PLAN_GET, 0) C(PLAN_SET, plan_set, LINK_FIELDS_PLAN_SET, 0)                   \
    C(MASK, mask, LINK_FIELDS_MASK, 0) C(SCREEN, screen, LINK_FIELDS_SCREEN, 0) C(MOVE, move, LINK_FIELDS_MOVE, 0) C(EXPOSE, expose, LINK_FIELDS_EXPOSE, 0)  \
    C(PRINT, print, LINK_FIELDS_PRINT, 0) C(EXIT, exit, LINK_FIELDS_EXIT, 0) C(ACK, ack, LINK_FIELDS_ACK, 0)        \
    C(IDENTIFY, identify, LINK_FIELDS_IDENTIFY, 0) C(STATUS_REPLY, status, LINK_FIELDS_STATUS, 0)                   \
    C(PLAN, plan, LINK_FIELDS_PLAN, 1)
LINK_CODEC_LIST(LINK__CODEC)
#undef LINK__CODEC

/* ------------------------------------------------------------- the table */

enum { LINK_U8 = 1, LINK_U16, LINK_U32, LINK_I32 };

typedef struct link_field {
    const char *name;
    int type;            /* LINK_U8 ...; fields lie back to back from the payload's start */
} link_field;

typedef struct link_message {
    const char *name;    /* NAME as in LINK_MESSAGE_LIST and PROTOCOL.md */
    uint8_t type;
    uint8_t to_host;     /* 1: MCU -> host */
    uint8_t tail;        /* 1: bytes follow the fixed fields */
    unsigned size;       /* the fixed fields' bytes */
    const link_field *fields;
    unsigned field_count;
} link_message;

/* Every message, in LINK_MESSAGE_LIST's order; the last has name NULL. */
extern const link_message LINK_MESSAGES[];
/* The message of `type` (a host frame's round bit ignored), or NULL. */
const link_message *link_message_of(uint8_t type);

/* Whether a frame of `type` may travel this way (the deframers' filters). */
int link_host_to_mcu_type(uint8_t type);
int link_mcu_to_host_type(uint8_t type);
/* Whether `size` bytes are a payload of that host message: its fixed size,
   or at least it when a tail follows. */
int link_payload_fits(uint8_t type, size_t size);

/* ------------------------------------------------------ payload fields */

/* Little-endian fields of payloads. */
static inline uint32_t link_get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint16_t link_get16(const uint8_t *p) { return (uint16_t)(p[0] | p[1] << 8); }
static inline void link_put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline void link_put16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }

/* A PROFILE_DATA bin is the varint of units << 1 | forced: these three are
   the one definition, the host's encoder and the MCU's decoder both use them. */
static inline uint32_t link_bin_code(uint32_t units, int forced) { return units << 1 | (forced ? 1u : 0u); }
static inline uint32_t link_bin_units(uint32_t code) { return code >> 1; }
static inline int link_bin_forced(uint32_t code) { return (int)(code & 1u); }

/* PROFILE_DATA's payload: bins from *at on, each link_bin_code's varint, as
   many whole ones as fit in `max` bytes (>= 5); advances *at and returns the
   bytes written. forced may be NULL. */
size_t link_profile_chunk(uint8_t *out, size_t max, const uint32_t *units, const unsigned char *forced, uint32_t n,
                          uint32_t *at);
#endif
