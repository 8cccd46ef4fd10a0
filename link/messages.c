/* The messages of link/messages.h: put, get, the table and the names. */
#include "messages.h"
#include "../adaslice_mcu.h"

/* a function, so no comparison is made against a constant 0 */
static int link__fits(size_t size, size_t fixed, int tail) { return tail ? size >= fixed : size == fixed; }

static size_t link__put_u8(uint8_t *p, uint8_t v) { p[0] = v; return 1; }
static size_t link__put_u16(uint8_t *p, uint16_t v) { link_put16(p, v); return 2; }
static size_t link__put_u32(uint8_t *p, uint32_t v) { link_put32(p, v); return 4; }
static size_t link__put_i32(uint8_t *p, int32_t v) { link_put32(p, (uint32_t)v); return 4; }
static uint8_t link__get_u8(const uint8_t *p) { return p[0]; }
static uint16_t link__get_u16(const uint8_t *p) { return link_get16(p); }
static uint32_t link__get_u32(const uint8_t *p) { return link_get32(p); }
static int32_t link__get_i32(const uint8_t *p) { return (int32_t)link_get32(p); }

#define LINK__PUT(type, name) at += link__put_##type(out + at, m->name);
#define LINK__GET(type, name) m->name = link__get_##type(p + at); at += LINK__BYTES_##type;
#define LINK__IMPLEMENT(NAME, name, FIELDS, tail)                                                                   \
    size_t link_put_##name(uint8_t *out, const link_##name *m)                                                      \
    {                                                                                                               \
        size_t at = 0;                                                                                              \
        FIELDS(LINK__PUT)                                                                                           \
        return at;                                                                                                  \
    }                                                                                                               \
    int link_get_##name(link_##name *m, const uint8_t *p, size_t size)                                              \
    {                                                                                                               \
        size_t at = 0;                                                                                              \
        if (!link__fits(size, LINK_SIZE_##NAME, tail)) return 0;                                                    \
        FIELDS(LINK__GET)                                                                                           \
        return 1;                                                                                                   \
    }
LINK_CODEC_LIST(LINK__IMPLEMENT)

#define LINK__KIND_u8 LINK_U8
#define LINK__KIND_u16 LINK_U16
#define LINK__KIND_u32 LINK_U32
#define LINK__KIND_i32 LINK_I32
#define LINK__FIELD(type, name) {#name, LINK__KIND_##type},
#define LINK__FIELDS(NAME, name, type, dir, FIELDS, tail) static const link_field link__fields_##name[] = {FIELDS(LINK__FIELD){0, 0}};
LINK_MESSAGE_LIST(LINK__FIELDS)
#define LINK__ROW(NAME, name, type, dir, FIELDS, tail)                                                              \
    {#NAME, type, dir, tail, LINK_SIZE_##NAME, link__fields_##name,                                                 \
     (unsigned)(sizeof link__fields_##name / sizeof link__fields_##name[0] - 1)},
const link_message LINK_MESSAGES[] = {LINK_MESSAGE_LIST(LINK__ROW){0, 0, 0, 0, 0, 0, 0}};

const link_message *link_message_of(uint8_t type)
{
    const link_message *m;
    if (!(type & 0x80u)) type &= (uint8_t)~LINK_ROUND_BIT;
    for (m = LINK_MESSAGES; m->name; m++)
        if (m->type == type) return m;
    return 0;
}

/* switches, not the table: the MCU links these without the names */
#define LINK__CASE_TO_MCU(NAME, name, type, dir, FIELDS, tail) case type: return !dir;
#define LINK__CASE_TO_HOST(NAME, name, type, dir, FIELDS, tail) case type: return dir;
#define LINK__CASE_FITS(NAME, name, type, dir, FIELDS, tail)                                                        \
    case type: return link__fits(size, LINK_SIZE_##NAME, tail);

int link_host_to_mcu_type(uint8_t type)
{
    switch (type & (uint8_t)~LINK_ROUND_BIT) {
    LINK_MESSAGE_LIST(LINK__CASE_TO_MCU)
    default: return 0;
    }
}

int link_mcu_to_host_type(uint8_t type)
{
    switch (type) {
    LINK_MESSAGE_LIST(LINK__CASE_TO_HOST)
    default: return 0;
    }
}

int link_payload_fits(uint8_t type, size_t size)
{
    switch (type & (uint8_t)~LINK_ROUND_BIT) {
    LINK_MESSAGE_LIST(LINK__CASE_FITS)
    default: return 0;
    }
}

#define LINK__TEXT(NAME, text) text,
static const char *const link__states[] = {LINK_STATE_LIST(LINK__TEXT)};
static const char *const link__phases[] = {LINK_PHASE_LIST(LINK__TEXT)};
static const char *const link__errors[] = {LINK_ERROR_LIST(LINK__TEXT)};

const char *link_state_name(unsigned s) { return s < LINK_STATE_COUNT ? link__states[s] : "unknown state"; }
const char *link_phase_name(unsigned s) { return s < LINK_PHASE_COUNT ? link__phases[s] : "unknown phase"; }
const char *link_error_name(unsigned e) { return e < LINK_ERROR_COUNT ? link__errors[e] : "unknown error"; }

size_t link_profile_chunk(uint8_t *out, size_t max, const uint32_t *units, const unsigned char *forced, uint32_t n,
                          uint32_t *at)
{
    size_t used = 0;
    for (; *at < n && used + 5 <= max; (*at)++)
        used += adaslice_varint_put(out + used, link_bin_code(units[*at], forced && forced[*at]));
    return used;
}
