/* The wire protocol's one definition (link/messages.h) against its prose
   (link/PROTOCOL.md): every message's type, direction, size, fields, their
   offsets and types, the state, phase and error tables and the example frames
   must agree, so the document cannot drift from the code. And every message
   survives put and get. */
#include "util.h"
#include "../link/frame.h"
#include "../link/messages.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

#define PROTOCOL_MD "link/PROTOCOL.md"


/* The next line of *at (NUL-terminated in place), or NULL at the end. */
static char *next_line(char **at)
{
    char *line = *at, *end;
    if (!line || !*line) return NULL;
    end = strchr(line, '\n');
    if (end) { *end = 0; *at = end + 1; } else *at = line + strlen(line);
    return line;
}

/* Cells of a table row "| a | b | c |" into cell[] (trimmed; "\|" is a bar
   inside a cell); returns how many. */
static int row_cells(char *line, char **cell, int max)
{
    int n = 0;
    char *p = line;
    if (*p != '|') return 0;
    p++;
    while (*p && n < max) {
        char *start = p, *end;
        while (*p && !(*p == '|' && p[-1] != '\\')) p++;
        if (!*p) break; /* no closing bar: not a cell */
        end = p++;
        while (start < end && *start == ' ') start++;
        while (end > start && end[-1] == ' ') end--;
        *end = 0;
        cell[n++] = start;
    }
    return n;
}

static const char *type_name(int t)
{
    return t == LINK_U8 ? "u8" : t == LINK_U16 ? "u16" : t == LINK_U32 ? "u32" : t == LINK_I32 ? "i32" : "?";
}

static int type_bytes(int t) { return t == LINK_U8 ? 1 : t == LINK_U16 ? 2 : 4; }

/* Every message in the code has a section "### 0xHH NAME (dir), N bytes[ + tail]"
   whose table lists its fields at their offsets, and the document has no
   message the code lacks. */
static void protocol_md_matches_the_messages(void)
{
    char *text = read_whole_text(PROTOCOL_MD), *at = text, *line;
    const link_message *m = NULL;
    unsigned seen[256] = {0}, field = 0, sections = 0, offset = 0;
    const link_message *msg;
    if (!text) { CHECKF(0, "cannot read %s", PROTOCOL_MD); return; }
    while ((line = next_line(&at)) != NULL) {
        unsigned type, size;
        char name[40], dir[16];
        if (!strncmp(line, "#", 1)) {
            if (m) CHECKF(field == m->field_count, "%s: %u fields in the document, %u in the code", m->name, field, m->field_count);
            m = NULL;
        }
        if (sscanf(line, "### 0x%x %39s (%15s to %*[^)]), %u byte", &type, name, dir, &size) == 4) {
            int tail = strstr(line, "+ tail") != NULL;
            sections++;
            m = link_message_of((uint8_t)type);
            field = 0;
            offset = 0;
            if (!m) { CHECKF(0, "%s: message 0x%02x %s is not in link/messages.h", PROTOCOL_MD, type, name); continue; }
            seen[m->type] = 1;
            CHECKF(!strcmp(m->name, name), "0x%02x: %s in the document, %s in the code", type, name, m->name);
            CHECKF(m->size == size, "%s: %u bytes in the document, %u in the code", m->name, size, m->size);
            CHECKF(m->tail == tail, "%s: the document %s a tail", m->name, tail ? "gives" : "gives no");
            CHECKF(m->to_host == !strcmp(dir, "MCU"), "%s: sent by the %s in the document", m->name, dir);
            continue;
        }
        if (m && line[0] == '|') {
            char *cell[8];
            unsigned off;
            int n = row_cells(line, cell, 8);
            if (n < 3 || sscanf(cell[0], "%u", &off) != 1) continue; /* the header and its rule */
            if (field >= m->field_count) { CHECKF(0, "%s: field %s is not in the code", m->name, cell[2]); field++; continue; }
            CHECKF(off == offset, "%s.%s: offset %u in the document, %u in the code", m->name, cell[2], off, offset);
            CHECKF(!strcmp(cell[1], type_name(m->fields[field].type)), "%s.%s: %s in the document, %s in the code",
                   m->name, cell[2], cell[1], type_name(m->fields[field].type));
            CHECKF(!strcmp(cell[2], m->fields[field].name), "%s: field %u is %s in the document, %s in the code", m->name,
                   field, cell[2], m->fields[field].name);
            offset += (unsigned)type_bytes(m->fields[field].type);
            field++;
        }
    }
    if (m) CHECKF(field == m->field_count, "%s: %u fields in the document, %u in the code", m->name, field, m->field_count);
    for (msg = LINK_MESSAGES; msg->name; msg++) CHECKF(seen[msg->type], "%s (0x%02x) has no section in %s", msg->name, msg->type, PROTOCOL_MD);
    CHECK(sections >= 21);
    free(text);
}

/* The state, phase and error tables list the code's lists in order. */
static void protocol_md_matches_states_phases_and_errors(void)
{
#define NAME_OF(NAME, text) #NAME,
#define TEXT_OF(NAME, text) text,
    static const char *const states[] = {LINK_STATE_LIST(NAME_OF)};
    static const char *const phases[] = {LINK_PHASE_LIST(NAME_OF)};
    static const char *const errors[] = {LINK_ERROR_LIST(NAME_OF)};
    static const char *const error_texts[] = {LINK_ERROR_LIST(TEXT_OF)};
#undef NAME_OF
#undef TEXT_OF
    char *text = read_whole_text(PROTOCOL_MD), *at = text, *line;
    int table = -1, rows[3] = {0, 0, 0};
    if (!text) { CHECKF(0, "cannot read %s", PROTOCOL_MD); return; }
    while ((line = next_line(&at)) != NULL) {
        char *cell[8];
        unsigned k;
        int n = line[0] == '|' ? row_cells(line, cell, 8) : 0;
        if (!n) { table = -1; continue; }
        if (!strcmp(cell[0], "state")) { table = 0; continue; }
        if (!strcmp(cell[0], "phase")) { table = 1; continue; }
        if (!strcmp(cell[0], "error")) { table = 2; continue; }
        if (table < 0 || sscanf(cell[0], "%u", &k) != 1 || n < 2) continue;
        if (table == 0) CHECKF(k < LINK_STATE_COUNT && !strcmp(cell[1], states[k]), "state %u: %s", k, cell[1]);
        if (table == 1) CHECKF(k < LINK_PHASE_COUNT && !strcmp(cell[1], phases[k]), "phase %u: %s", k, cell[1]);
        if (table == 2) {
            CHECKF(k < LINK_ERROR_COUNT && !strcmp(cell[1], errors[k]), "error %u: %s", k, cell[1]);
            CHECKF(n >= 3 && k < LINK_ERROR_COUNT && !strcmp(cell[2], error_texts[k]), "error %u: '%s'", k, n >= 3 ? cell[2] : "");
            CHECK(k >= LINK_ERROR_COUNT || !strcmp(link_error_name(k), error_texts[k]));
        }
        if (k == (unsigned)rows[table]) rows[table]++;
    }
    CHECKF(rows[0] == LINK_STATE_COUNT && rows[1] == LINK_PHASE_COUNT && rows[2] == LINK_ERROR_COUNT,
           "%d states, %d phases, %d errors in order in the document", rows[0], rows[1], rows[2]);
    free(text);
}

/* The example frames in the document are what the code builds. */
static void protocol_md_example_frames_are_exact(void)
{
    char *text = read_whole_text(PROTOCOL_MD), *p, *q;
    uint8_t want[2][LINK_FRAME_MAX], payload[LINK_PAYLOAD_MAX];
    size_t want_n[2];
    link_hello hello;
    link_mask mask;
    int k;
    char says[64];
    if (!text) { CHECKF(0, "cannot read %s", PROTOCOL_MD); return; }
    /* the version the document gives is the one the code speaks */
    snprintf(says, sizeof says, "# The adaslice serial protocol (version %d)", LINK_PROTOCOL_VERSION);
    CHECKF(!strncmp(text, says, strlen(says)), "%s does not open with \"%s\"", PROTOCOL_MD, says);
    snprintf(says, sizeof says, "Example: HELLO (version %d)", LINK_PROTOCOL_VERSION);
    CHECKF(strstr(text, says) != NULL, "%s has no \"%s\"", PROTOCOL_MD, says);
    hello.version = LINK_PROTOCOL_VERSION;
    want_n[0] = link_frame_build(want[0], 0x2a, LINK_MSG_HELLO, payload, link_put_hello(payload, &hello));
    mask.layer = 7;
    mask.code_bytes = 1234;
    mask.crc32 = 0xdeadbeefu;
    mask.exposure_ms = 2500;
    want_n[1] = link_frame_build(want[1], 0x2b, LINK_MSG_MASK | LINK_ROUND_BIT, payload, link_put_mask(payload, &mask));
    p = strstr(text, "Example: ");
    CHECKF(p != NULL, "%s has no example frame", PROTOCOL_MD);
    for (k = 0; p && k < 2; k++) {
        size_t n = 0;
        p = strchr(p, '`');
        q = p ? strchr(p + 1, '`') : NULL;
        if (!p || !q) { CHECKF(0, "example frame %d is missing", k + 1); break; }
        for (p++; p < q;) {
            unsigned byte;
            int used;
            if (sscanf(p, "%2x%n", &byte, &used) != 1) break;
            CHECKF(n < want_n[k] && byte == want[k][n], "example %d, byte %zu: %02x in the document", k + 1, n, byte);
            n++;
            p += used;
            while (*p == ' ') p++;
        }
        CHECKF(n == want_n[k], "example %d: %zu bytes in the document, %zu built", k + 1, n, want_n[k]);
        p = q + 1;
    }
    free(text);
}

/* Each message with fields encodes to exactly its size and decodes back;
   a payload of another size is refused. */
static void messages_round_trip(void)
{
    uint8_t buf[LINK_PAYLOAD_MAX];
    link_status a, b;
    link_identify ia, ib;
    link_print pa, pb;
    link_plan page;
    const link_message *m;
    memset(&a, 0, sizeof a);
    a.state = LINK_STATE_PAUSED; a.phase = LINK_PHASE_EXPOSE; a.error = LINK_ERR_MASK_CRC; a.error_seq = 200;
    a.flags = LINK_FLAG_HOMED | LINK_FLAG_LINK_LOST; a.layer = 123456; a.layers = 654321; a.mask_ready = 77;
    a.mask_layer = 78; a.mask_got = 9999; a.masks_refused = 65535; a.z_nm = -123456789; a.bins_in = 0xfffffffeu;
    a.bad_frames = 3; a.window = 8;
    CHECK(link_put_status(buf, &a) == LINK_SIZE_STATUS_REPLY);
    memset(&b, 0, sizeof b); /* padding too, for memcmp */
    CHECK(link_get_status(&b, buf, LINK_SIZE_STATUS_REPLY) && !memcmp(&a, &b, sizeof a));
    CHECK(!link_get_status(&b, buf, LINK_SIZE_STATUS_REPLY - 1) && !link_get_status(&b, buf, LINK_SIZE_STATUS_REPLY + 1));
    memset(&ia, 0x5a, sizeof ia);
    ia.version = LINK_PROTOCOL_VERSION;
    CHECK(link_put_identify(buf, &ia) == LINK_SIZE_IDENTIFY);
    memset(&ib, 0x5a, sizeof ib);
    CHECK(link_get_identify(&ib, buf, LINK_SIZE_IDENTIFY) && !memcmp(&ia, &ib, sizeof ia));
    memset(&pa, 0, sizeof pa);
    memset(&pb, 0, sizeof pb);
    pa.first_layer = 5; pa.peel_nm = 2500000; pa.settle_ms = 0xffffffffu;
    CHECK(link_put_print(buf, &pa) == LINK_SIZE_PRINT && link_get_print(&pb, buf, LINK_SIZE_PRINT) && !memcmp(&pa, &pb, sizeof pa));
    /* PLAN has a tail: at least its fixed part */
    page.first = 1; page.layers = 2; page.bin_nm = 2000;
    CHECK(link_put_plan(buf, &page) == LINK_SIZE_PLAN && link_get_plan(&page, buf, LINK_SIZE_PLAN + 5));
    CHECK(!link_get_plan(&page, buf, LINK_SIZE_PLAN - 1));
    /* the filters and sizes the firmware checks frames with */
    for (m = LINK_MESSAGES; m->name; m++) {
        CHECKF(link_host_to_mcu_type(m->type) == !m->to_host && link_mcu_to_host_type(m->type) == m->to_host, "%s", m->name);
        if (!m->to_host) {
            CHECKF(link_host_to_mcu_type((uint8_t)(m->type | LINK_ROUND_BIT)), "%s with the round bit", m->name);
            CHECKF(link_payload_fits(m->type, m->size) && link_payload_fits(m->type, m->size + 1) == m->tail, "%s", m->name);
            CHECKF(!m->size || !link_payload_fits(m->type, m->size - 1), "%s", m->name);
        }
    }
    CHECK(!link_host_to_mcu_type(0x00) && !link_host_to_mcu_type(0x3e) && !link_mcu_to_host_type(0x84));
    CHECK(!strcmp(link_error_name(LINK_ERR_BUSY), "busy") && !strcmp(link_error_name(200), "unknown error"));
}

void test_link(void)
{
    RUN(protocol_md_matches_the_messages);
    RUN(protocol_md_matches_states_phases_and_errors);
    RUN(protocol_md_example_frames_are_exact);
    RUN(messages_round_trip);
}
