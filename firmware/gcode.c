/* G-code mode; the dialect and the decisions behind it are in gcode.h. */
#include "gcode.h"

/* what the last command still waits for; the last three are replies to
   come, each a piece of work of its own */
enum { WAIT_NONE, WAIT_START, WAIT_MOVE, WAIT_HOME, WAIT_DWELL, WAIT_TRAVEL, WAIT_LIMITS, WAIT_OVERRUN };
enum { HELD = 1, CHECKED }; /* g->held: a complete line, then one that passed check() */
/* g->len of a line that outgrew g->line: its rest is dropped */
#define TOO_LONG (FW_GCODE_LINE_MAX + 1)

/* Every number fits in millionths within int64 with room to add two. */
#define NUMBER_MAX 10000000
#define MILLION 1000000u

/* One reply line, sent with one write so a port can hand it to DMA whole;
   the longest is the echo of a whole line. A reply lives only in a
   function that fills and sends it and calls nothing deeper than put_*,
   the arithmetic and send, kept out of line (FW_NOINLINE, motion.h): an
   inlined one's buffer would stay on the stack under every call its caller
   makes, and on an 8 KiB MCU two at once are a good part of the stack.
   check() and run() are kept out of line too: inlined into fw_gcode_run,
   its branches outgrew the AVR's relative jumps (4 KB) and the link
   failed. */
typedef struct reply {
    char b[FW_GCODE_LINE_MAX + 32];
    size_t n;
} reply;

/* s: FW_TEXT (in flash on an AVR) */
static void put(reply *r, const char *s)
{
    char c;
    /* one byte stays free for the newline */
    while ((c = FW_TEXT_BYTE(s)) != 0 && r->n < sizeof r->b - 1) {
        r->b[r->n++] = c;
        s++;
    }
}

static void put_char(reply *r, char c)
{
    if (r->n < sizeof r->b - 1) r->b[r->n++] = c;
}

static uint64_t magnitude(int64_t v)
{
    /* INT64_MIN has no positive int64 */
    return v < 0 ? 0 - (uint64_t)v : (uint64_t)v;
}

/* On an 8-bit core a 64-bit division costs thousands of cycles and a
   32-bit one hundreds; nearly every value here (a position, a speed, a
   dwell) fits 32 bits, so the divisions below take 64 only above that,
   and a digit's takes none. */
static uint32_t tenth(uint32_t u)
{
    /* u / 10, exact for every 32-bit u (2^35 / 10 rounded up); the high
       word, then 3 bits, since a 64-bit shift is a loop on an 8-bit core */
    return (uint32_t)((uint64_t)u * 0xCCCCCCCDu >> 32) >> 3;
}

/* u in decimal, at least `width` digits */
static void put_digits(reply *r, uint32_t u, int width)
{
    char d[10];
    int k = 0;
    do {
        /* the last digits in 16 bits: an 8-bit core divides those in a
           fraction of the 64-bit product's time */
        uint32_t q = u >> 16 ? tenth(u) : (uint16_t)u / 10u;
        d[k++] = (char)('0' + (u - q * 10u));
        u = q;
    } while (u || k < width);
    while (k) put_char(r, d[--k]);
}

static void put_uint(reply *r, uint64_t u)
{
    char low[10];
    int k = 0;
    for (; u >> 32; u /= 10) low[k++] = (char)('0' + u % 10);
    put_digits(r, (uint32_t)u, 1);
    while (k) put_char(r, low[--k]);
}

static void put_int(reply *r, int64_t v)
{
    if (v < 0) put_char(r, '-');
    put_uint(r, magnitude(v));
}

/* thousandths as "-12.345" */
static void put_milli(reply *r, int64_t v)
{
    uint64_t u = magnitude(v), whole = u >> 32 ? u / 1000 : (uint32_t)u / 1000;
    if (v < 0) put_char(r, '-');
    put_uint(r, whole);
    put_char(r, '.');
    put_digits(r, (uint32_t)u - (uint32_t)whole * 1000u, 3); /* below 1000, so exact in 32 bits */
}

static void send(fw_gcode *g, reply *r)
{
    r->b[r->n++] = '\n';
    if (g->io.write) g->io.write(g->io.ctx, (const uint8_t *)r->b, r->n);
    r->n = 0;
}

FW_NOINLINE void fw_gcode_say(fw_gcode *g, const char *s)
{
    reply r;
    r.n = 0;
    put(&r, s);
    send(g, &r);
}

/* a * b / d, rounded down (round 0), to nearest (1) or up (2), without the
   128-bit product: a is split at d, which is exact while a / d * b and
   d * b stay below 2^64. Here a < 2^44 (a number in millionths, or a
   position), b < 2^32 and d * b < 2^62. */
static uint64_t muldiv(uint64_t a, uint32_t b, uint32_t d, int round)
{
    uint32_t add = round == 1 ? d / 2 : round == 2 ? d - 1 : 0;
    uint64_t q = a >> 32 ? a / d : (uint32_t)a / d, r;
    r = (uint32_t)a - (uint32_t)q * d; /* a % d: below d, so exact in 32 bits */
    r = r * b + add;
    q = q >> 32 ? q * b : (uint64_t)(uint32_t)q * b;
    return q + (r >> 32 ? r / d : (uint32_t)r / d);
}

static uint32_t steps_per_mm(const fw_gcode *g)
{
    return g->axis->config.steps_per_mm;
}

/* nm >= 0; the axis's own rounding, so G-code and the core agree on every
   height. It saturates far above any soft limit. */
static int64_t steps_of_nm(const fw_gcode *g, int64_t nm)
{
    return fw_axis_steps_of_nm(g->axis, (uint64_t)nm);
}

/* steps to units of 1/scale mm, rounded to nearest */
static int64_t mm_of_steps(const fw_gcode *g, int32_t steps, uint32_t scale)
{
    uint64_t u;
    if (!steps_per_mm(g)) return 0;
    u = muldiv(magnitude(steps), scale, steps_per_mm(g), 1);
    return steps < 0 ? -(int64_t)u : (int64_t)u;
}

/* Where Z is, in nm: the commanded value while the axis stands on its step,
   so relative moves of a fraction of a step add up without drift; what the
   steps say once anything else (a halt, the core's own moves) moved it. */
static int64_t z_now(const fw_gcode *g)
{
    if (g->z_nm >= 0 && steps_of_nm(g, g->z_nm) == g->axis->position) return g->z_nm;
    return mm_of_steps(g, g->axis->position, MILLION);
}

static int is_digit(uint8_t c) { return c >= '0' && c <= '9'; }
static int is_alpha(uint8_t c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
static int is_blank(uint8_t c) { return c == ' ' || c == '\t'; }
static int is_value(uint8_t c) { return is_digit(c) || c == '.' || c == '-' || c == '+'; }
static int upper(uint8_t c) { return c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c; }

/* "[+-]digits[.digits]" in millionths: 1, 0 when malformed, -1 when beyond
   NUMBER_MAX. Decimals past the sixth round at the seventh. */
static int parse_fixed(const uint8_t *s, size_t n, int64_t *out)
{
    size_t i = 0;
    int neg = 0, digits = 0, places = 0, round = -1;
    uint32_t whole = 0, frac = 0; /* 32 bits and no division: see tenth() */
    int64_t v;
    if (i < n && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
    for (; i < n && is_digit(s[i]); i++, digits++)
        if (whole <= NUMBER_MAX) whole = whole * 10 + (uint32_t)(s[i] - '0');
    if (i < n && s[i] == '.')
        for (i++; i < n && is_digit(s[i]); i++, digits++) {
            if (places < 6) { frac = frac * 10 + (uint32_t)(s[i] - '0'); places++; }
            else if (round < 0) round = s[i] >= '5';
        }
    for (; places < 6; places++) frac *= 10;
    if (i != n || !digits) return 0;
    if (whole > NUMBER_MAX) return -1;
    v = (int64_t)((uint64_t)whole * MILLION) + frac + (round > 0);
    if (v > (int64_t)NUMBER_MAX * MILLION) return -1;
    *out = neg ? -v : v;
    return 1;
}

/* "[+-]digits" within int32 */
static int parse_int32(const uint8_t *s, size_t n, int32_t *out)
{
    size_t i = 0;
    int neg = 0;
    int64_t v = 0;
    if (i < n && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
    if (i == n) return 0;
    for (; i < n; i++) {
        if (!is_digit(s[i])) return 0;
        v = v * 10 + (s[i] - '0');
        if (v > INT32_MAX) return 0;
    }
    *out = (int32_t)(neg ? -v : v);
    return 1;
}

/* The next word of b[*i..end), a letter and its run of value characters,
   after blanks and (comments): 1, 0 at the end, -1 at a byte that starts
   no word. */
static int word(const uint8_t *b, size_t *i, size_t end, int *letter, size_t *at, size_t *len)
{
    size_t k = *i;
    for (;;) {
        while (k < end && is_blank(b[k])) k++;
        if (k == end || b[k] != '(') break;
        while (k < end && b[k] != ')') k++;
        if (k < end) k++;
    }
    *i = k;
    if (k == end) return 0;
    if (!is_alpha(b[k])) return -1;
    *letter = upper(b[k]);
    *at = ++k;
    while (k < end && is_value(b[k])) k++;
    *len = k - *at;
    *i = k;
    return 1;
}

/* Where each letter's value is in the line. */
typedef struct words {
    uint8_t at[26], len[26];
    uint32_t seen;
} words;

static int seen(const words *w, int letter)
{
    return (int)(w->seen >> (letter - 'A') & 1u);
}

/* The value of `letter` in millionths; replies the Error: line and returns
   0 when it is malformed or out of range. *has: whether the word is there. */
static FW_NOINLINE void letter_error(fw_gcode *g, const char *what, int letter)
{
    reply r;
    r.n = 0;
    put(&r, what);
    put_char(&r, (char)letter);
    send(g, &r);
}

static void out_of_range(fw_gcode *g, int letter) { letter_error(g, FW_TEXT("Error:Number out of range for "), letter); }

static int number(fw_gcode *g, const words *w, int letter, int64_t *v, int *has)
{
    int k;
    *has = seen(w, letter);
    if (!*has) return 1;
    k = parse_fixed(g->line + w->at[letter - 'A'], w->len[letter - 'A'], v);
    if (k == 1) return 1;
    if (k < 0) out_of_range(g, letter);
    else letter_error(g, FW_TEXT("Error:Bad number for "), letter);
    return 0;
}

static FW_NOINLINE void line_error(fw_gcode *g, const char *what, int resend)
{
    reply r;
    r.n = 0;
    put(&r, FW_TEXT("Error:"));
    put(&r, what);
    put(&r, FW_TEXT(", Last Line: "));
    put_int(&r, g->last_line);
    send(g, &r);
    if (resend) {
        put(&r, FW_TEXT("Resend: "));
        put_int(&r, (int64_t)g->last_line + 1);
        send(g, &r);
    }
    put(&r, FW_TEXT("ok"));
    send(g, &r);
}

/* The light M106 put on goes out now, and the host is told why. */
static void light_out(fw_gcode *g, uint64_t now, const char *why)
{
    g->lit = 0;
    g->lit_at = now;
    if (g->io.uv) g->io.uv(g->io.ctx, 0, now);
    fw_gcode_say(g, why);
}

static void motor(fw_gcode *g, int on)
{
    if (g->io.motor) g->io.motor(g->io.ctx, on);
    g->motor_on = (uint8_t)on;
}

/* `what` and a height in steps as mm: "...12.345" */
static FW_NOINLINE void at_mm(fw_gcode *g, const char *what, int32_t steps)
{
    reply r;
    r.n = 0;
    put(&r, what);
    put_milli(&r, mm_of_steps(g, steps, 1000));
    send(g, &r);
}

/* G0 / G1; 1: ok now, 0: start() sends it */
static int move(fw_gcode *g, const words *w, uint64_t now)
{
    fw_axis *a = g->axis;
    int64_t z = 0, f = 0, target, steps;
    int has_z, has_f;
    if (!number(g, w, 'Z', &z, &has_z) || !number(g, w, 'F', &f, &has_f)) return 1;
    if (has_f) {
        uint64_t speed;
        if (f <= 0) { out_of_range(g, 'F'); return 1; }
        speed = muldiv((uint64_t)f, steps_per_mm(g), 60u * MILLION, 0);
        if (speed > a->config.max_speed) speed = a->config.max_speed;
        /* 0 would mean max_speed to fw_axis_move_to */
        g->speed = speed ? (uint32_t)speed : 1;
    }
    if (!has_z) return 1;
    if (!a->homed) { fw_gcode_say(g, FW_TEXT("Error:Home Z first")); return 1; }
    target = (g->relative ? z_now(g) : 0) + z;
    steps = target < 0 ? -1 : steps_of_nm(g, target);
    if (steps < 0 || steps > a->config.max_steps) {
        at_mm(g, FW_TEXT("Error:Z outside soft limits 0.000.."), a->config.max_steps);
        return 1;
    }
    /* Z never moves under the light: a host that forgot M107 loses the
       rest of that exposure, not the next layer's height */
    if (g->lit) light_out(g, now, FW_TEXT("echo:UV off: Z moves only in the dark"));
    /* started by start(), a piece of its own */
    g->z_nm = target;
    g->target = (int32_t)steps;
    g->wait = WAIT_START;
    return 0;
}

/* The move a G0/G1 asked for, and its ok. */
static void start(fw_gcode *g, uint64_t now)
{
    /* it waited for the axis to be idle; a fault in between unhomes it */
    int refused = fw_axis_move_to(g->axis, g->target, g->speed, now);
    if (refused) {
        fw_gcode_say(g, refused == FW_AXIS_NOT_HOMED ? FW_TEXT("Error:Home Z first") : FW_TEXT("Error:Axis busy"));
        g->wait = WAIT_NONE;
    } else {
        if (!g->motor_on) motor(g, 1);
        g->wait = WAIT_MOVE;
    }
    fw_gcode_say(g, FW_TEXT("ok"));
}

/* G4; 1: ok now */
static int dwell(fw_gcode *g, const words *w, uint64_t now)
{
    int64_t p = 0, s = 0;
    int has_p, has_s;
    uint64_t ticks, from, end;
    if (!number(g, w, 'P', &p, &has_p) || !number(g, w, 'S', &s, &has_s)) return 1;
    if (p < 0 || s < 0) { out_of_range(g, p < 0 ? 'P' : 'S'); return 1; }
    /* at least the time asked for, so round up */
    ticks = has_s ? muldiv((uint64_t)s, g->axis->tick_hz, MILLION, 2)
                  : muldiv((uint64_t)p, g->axis->tick_hz, 1000u * MILLION, 2);
    if (!ticks) return 1;
    /* the exposure's dwell counts from M106 */
    from = g->lit ? g->lit_at : now;
    end = from < FW_NEVER - 1 && ticks < FW_NEVER - 1 - from ? from + ticks : FW_NEVER - 1;
    if (g->lit) {
        /* ended by the port's timer */
        g->lit = 0;
        if (g->io.uv_end) g->io.uv_end(g->io.ctx, end);
        if (end <= now) {
            /* the host was slower than the exposure: overrun() says by
               how much, a piece of its own */
            g->deadline = now - end;
            g->wait = WAIT_OVERRUN;
            return 0;
        }
    }
    g->deadline = end;
    g->wait = WAIT_DWELL;
    return 0;
}

/* M115's lines after Marlin's: this image's figures as it runs (a host,
   and the tests, read the board's travel, speed and light limit here), a
   line a piece of work, since each is a good part of a step interval's
   arithmetic on an 8-bit core. */
static FW_NOINLINE void figures(fw_gcode *g)
{
    const fw_axis_config *c = &g->axis->config;
    reply r;
    r.n = 0;
    if (g->wait == WAIT_TRAVEL) {
        put(&r, FW_TEXT("echo:Z_MAX_MM:"));
        put_milli(&r, mm_of_steps(g, c->max_steps, 1000));
        put(&r, FW_TEXT(" STEPS_PER_MM:"));
        put_uint(&r, c->steps_per_mm);
        send(g, &r);
        g->wait = WAIT_LIMITS;
        return;
    }
    put(&r, FW_TEXT("echo:Z_MAX_SPEED_MM_S:"));
    put_milli(&r, mm_of_steps(g, (int32_t)c->max_speed, 1000));
    put(&r, FW_TEXT(" MAX_EXPOSURE_MS:"));
    put_uint(&r, FW_EXPOSURE_MAX_MS);
    send(g, &r);
    put(&r, FW_TEXT("ok"));
    send(g, &r);
    g->wait = WAIT_NONE;
}

/* The G4 that came g->deadline ticks after its exposure's end, and its ok. */
static FW_NOINLINE void overrun(fw_gcode *g)
{
    /* in us, from the clock in kHz (every port's is whole kHz): 32-bit
       divisions, where 10^6 / tick_hz would take 64 */
    uint32_t khz = g->axis->tick_hz / 1000u;
    reply r;
    r.n = 0;
    put(&r, FW_TEXT("echo:Exposure ran over: G4 came "));
    put_milli(&r, khz ? (int64_t)muldiv(g->deadline, 1000u, khz, 0) : 0);
    put(&r, FW_TEXT(" ms after its end"));
    send(g, &r);
    put(&r, FW_TEXT("ok"));
    send(g, &r);
    g->wait = WAIT_NONE;
}

static FW_NOINLINE void report_position(fw_gcode *g)
{
    reply r;
    r.n = 0;
    put(&r, FW_TEXT("X:0.00 Y:0.00 Z:"));
    put_milli(&r, mm_of_steps(g, g->axis->position, 1000));
    put(&r, FW_TEXT(" E:0.00 Count Z:"));
    put_int(&r, g->axis->position);
    send(g, &r);
}

static FW_NOINLINE void unknown(fw_gcode *g, const uint8_t *b, size_t from, size_t end)
{
    reply r;
    while (end > from && is_blank(b[end - 1])) end--;
    r.n = 0;
    put(&r, FW_TEXT("echo:Unknown command: \""));
    for (; from < end; from++)
        put_char(&r, b[from] >= 0x20 && b[from] <= 0x7e ? (char)b[from] : '?');
    put_char(&r, '"');
    send(g, &r);
}

/* The decimal checksum after b[star] is the XOR of b[0..star); blanks and
   a ;comment may follow it. */
static int checksum_ok(const uint8_t *b, size_t star, size_t n)
{
    size_t i;
    unsigned x = 0, want = 0;
    for (i = 0; i < star; i++) x ^= b[i];
    for (i = star + 1; i < n && is_digit(b[i]); i++)
        if ((want = want * 10 + (unsigned)(b[i] - '0')) > 255) return 0;
    if (i == star + 1) return 0;
    while (i < n && is_blank(b[i])) i++;
    return (i == n || b[i] == ';') && want == x;
}

/* Whether the switch in run() has a case for code (G codes as they are,
   M codes plus 10000): only those reject stray bytes, since unknown ones
   such as M117 carry free text that goes back in the echo. */
static int known(int code)
{
    static const int16_t codes[] = {0, 1, 4, 28, 90, 91, 10017, 10018, 10084, 10105, 10106, 10107, 10110, 10114, 10115, 10400};
    size_t i;
    for (i = 0; i < sizeof codes / sizeof codes[0]; i++)
        if (codes[i] == code) return 1;
    return 0;
}

/* The command's code from its first word: G codes as they are, M codes
   plus 10000, -1 for any other word. */
static int code_of(const uint8_t *b, int k, int letter, size_t at, size_t len)
{
    int code = -1;
    size_t j;
    if (k == 1 && (letter == 'G' || letter == 'M') && len >= 1 && len <= 4) {
        for (code = 0, j = 0; j < len && code >= 0; j++)
            code = is_digit(b[at + j]) ? code * 10 + (b[at + j] - '0') : -1;
        if (code >= 0 && letter == 'M') code += 10000;
    }
    return code;
}

/* The held line's framing: comments, checksum, line number. A line that
   fails gets its replies here; one that passes is cut to its command and
   left for run() with where the command begins. 1: the line is to run. */
static FW_NOINLINE int check(fw_gcode *g)
{
    const uint8_t *b = g->line;
    size_t n = g->len, end = n, star = n, i, at = 0, len = 0, from;
    int letter = 0, k, paren = 0, numbered, code;
    int32_t line = 0;
    if (g->len == TOO_LONG) { line_error(g, FW_TEXT("Line too long"), 0); return 0; }
    for (i = 0; i < n; i++) {
        if (paren) { paren = b[i] != ')'; continue; }
        if (b[i] == '(') paren = 1;
        else if (b[i] == ';' || b[i] == '*') { end = i; star = b[i] == '*' ? i : n; break; }
    }
    i = 0;
    k = word(b, &i, end, &letter, &at, &len);
    if (k == 0 && star == n) return 0; /* blank or only comments: Marlin is silent */
    numbered = k == 1 && letter == 'N';
    if (star < n) {
        if (!checksum_ok(b, star, n)) { line_error(g, FW_TEXT("checksum mismatch"), numbered); return 0; }
    } else if (numbered) {
        line_error(g, FW_TEXT("No Checksum with line number"), 1);
        return 0;
    }
    from = 0;
    if (numbered) {
        if (!parse_int32(b + at, len, &line)) {
            line_error(g, FW_TEXT("Line Number is not Last Line Number+1"), 1);
            return 0;
        }
        from = i;
        k = word(b, &i, end, &letter, &at, &len);
    }
    code = code_of(b, k, letter, at, len);
    if (numbered) {
        if (code != 10110 && (int64_t)line != (int64_t)g->last_line + 1) {
            line_error(g, FW_TEXT("Line Number is not Last Line Number+1"), 1);
            return 0;
        }
        g->last_line = line;
    }
    if (k == 0) { fw_gcode_say(g, FW_TEXT("ok")); return 0; } /* FW_TEXT("N5*cs"): a line number alone */
    g->command = (uint8_t)from;
    g->len = (uint8_t)end;
    return 1;
}

/* Runs the checked line in g->line and sends its replies. */
static FW_NOINLINE void run(fw_gcode *g, uint64_t now)
{
    const uint8_t *b = g->line;
    /* the code word again: check() found it, but keeping it would cost a
       field of RAM, which the smallest board (STM32F103) has almost none of */
    size_t end = g->len, from = g->command, i = from, at = 0, len = 0;
    int letter = 0, k = word(b, &i, end, &letter, &at, &len), code = code_of(b, k, letter, at, len), ok = 1;
    int32_t line = 0;
    words w;
    while (from < end && is_blank(b[from])) from++;
    w.seen = 0;
    while (code >= 0 && (k = word(b, &i, end, &letter, &at, &len)) == 1) {
        w.seen |= (uint32_t)1 << (letter - 'A');
        w.at[letter - 'A'] = (uint8_t)at;
        w.len[letter - 'A'] = (uint8_t)len;
    }
    if (k < 0 && known(code)) {
        fw_gcode_say(g, FW_TEXT("Error:Unexpected character in command"));
        fw_gcode_say(g, FW_TEXT("ok"));
        return;
    }
    switch (code) {
    case 0: case 1: ok = move(g, &w, now); break;
    case 4: ok = dwell(g, &w, now); break;
    case 28:
        if (g->lit) light_out(g, now, FW_TEXT("echo:UV off: Z moves only in the dark"));
        if (fw_axis_home(g->axis, now) == FW_AXIS_OK) {
            if (!g->motor_on) motor(g, 1);
            g->wait = WAIT_HOME;
            ok = 0;
        } else fw_gcode_say(g, FW_TEXT("Error:Homing refused"));
        break;
    case 90: g->relative = 0; break;
    case 91: g->relative = 1; break;
    case 10017: motor(g, 1); break;
    case 10018: case 10084: motor(g, 0); break;
    case 10105: case 10400: break; /* nothing to report; moves have ended */
    case 10106: case 10107: {
        int64_t s = 0;
        int has_s = 0;
        if (code == 10106 && !number(g, &w, 'S', &s, &has_s)) break;
        if (s < 0) { out_of_range(g, 'S'); break; }
        if (code == 10106 && g->halted && (!has_s || s > 0)) { fw_gcode_say(g, FW_TEXT("Error:Stopped: home Z (G28) before UV")); break; }
        g->lit = (uint8_t)(code == 10106 && (!has_s || s > 0));
        g->lit_at = now;
        if (g->io.uv) g->io.uv(g->io.ctx, g->lit, now);
        break;
    }
    case 10110:
        if (seen(&w, 'N')) {
            if (parse_int32(b + w.at['N' - 'A'], w.len['N' - 'A'], &line)) g->last_line = line;
            else fw_gcode_say(g, FW_TEXT("Error:Bad line number"));
        }
        break;
    case 10114: report_position(g); break;
    case 10115:
        fw_gcode_say(g, FW_TEXT("FIRMWARE_NAME:adaslice PROTOCOL_VERSION:1.0 MACHINE_TYPE:MSLA EXTRUDER_COUNT:0"));
        g->wait = WAIT_TRAVEL; /* figures() in the next pieces */
        ok = 0;
        break;
    default: unknown(g, b, from, end); break;
    }
    if (ok) fw_gcode_say(g, FW_TEXT("ok"));
}

/* What a move or homing left to say once the axis stands still. */
static void finish(fw_gcode *g)
{
    fw_axis *a = g->axis;
    if (g->wait == WAIT_HOME) {
        if (a->homed && a->error == FW_AXIS_OK) {
            g->z_nm = mm_of_steps(g, a->position, MILLION);
            g->halted = 0;
            fw_gcode_say(g, FW_TEXT("Z_move_comp"));
        } else fw_gcode_say(g, FW_TEXT("Error:Homing failed"));
        fw_gcode_say(g, FW_TEXT("ok"));
    } else if (a->position == g->target) {
        fw_gcode_say(g, FW_TEXT("Z_move_comp"));
    } else {
        at_mm(g, FW_TEXT("Error:Z move stopped at "), a->position);
    }
    g->wait = WAIT_NONE;
}

static int moving(const fw_gcode *g)
{
    return g->io.moving ? g->io.moving(g->io.ctx) : fw_axis_busy(g->axis);
}

static void line_done(fw_gcode *g)
{
    g->held = 0;
    g->len = 0;
}

/* One piece of work a call, each a good part of a step interval on an
   8-bit core: ends what has ended, starts the move a G0/G1 asked for, or
   checks the held line, or runs it. 1: it did one. */
static int advance(fw_gcode *g, uint64_t now)
{
    if (g->wait == WAIT_DWELL) {
        if (now < g->deadline) return 0;
        g->wait = WAIT_NONE;
        fw_gcode_say(g, FW_TEXT("ok"));
        return 1;
    }
    if (g->wait == WAIT_TRAVEL || g->wait == WAIT_LIMITS) {
        figures(g);
        return 1;
    }
    if (g->wait == WAIT_OVERRUN) {
        overrun(g);
        return 1;
    }
    if (g->wait != WAIT_NONE) {
        if (moving(g)) return 0;
        if (g->wait == WAIT_START) start(g, now);
        else finish(g);
        return 1;
    }
    if (!g->held || moving(g)) return 0;
    if (g->held == HELD) {
        if (check(g)) g->held = CHECKED;
        else line_done(g);
        return 1;
    }
    run(g, now);
    line_done(g);
    return 1;
}

void fw_gcode_init(fw_gcode *g, fw_axis *axis, const fw_gcode_io *io)
{
    g->axis = axis;
    g->io = *io;
    g->len = g->held = g->relative = g->motor_on = g->lit = g->halted = 0;
    g->wait = WAIT_NONE;
    g->last_line = 0;
    g->target = 0;
    g->speed = 0;
    g->z_nm = -1; /* unknown until homed */
    g->deadline = 0;
}

size_t fw_gcode_receive(fw_gcode *g, const uint8_t *data, size_t size)
{
    size_t i;
    for (i = 0; i < size && !g->held; i++) {
        uint8_t c = data[i];
        if (c == '\n' || c == '\r') {
            if (!g->len) continue; /* blank, or the \n of \r\n */
            g->held = HELD;
        } else if (g->len < FW_GCODE_LINE_MAX) {
            g->line[g->len++] = c;
        } else {
            g->len = TOO_LONG;
        }
    }
    return i;
}

uint64_t fw_gcode_run(fw_gcode *g, uint64_t now)
{
    if (advance(g, now)) return now;
    if (g->wait == WAIT_DWELL) return g->deadline;
    if (g->wait != WAIT_NONE || g->held) return fw_axis_next(g->axis);
    return FW_NEVER;
}

void fw_gcode_drop(fw_gcode *g)
{
    line_done(g);
    if (g->wait == WAIT_START || g->wait >= WAIT_TRAVEL) g->wait = WAIT_NONE;
}

void fw_gcode_dark(fw_gcode *g, int halted)
{
    g->lit = 0;
    if (halted) g->halted = 1;
}

uint64_t fw_gcode_watch(fw_gcode *g, uint64_t heard, uint64_t timeout, uint64_t now)
{
    uint64_t from = heard > g->lit_at ? heard : g->lit_at;
    if (!g->lit) return FW_NEVER;
    if (now < from + timeout) return from + timeout;
    light_out(g, now, FW_TEXT("echo:UV off: the host went silent after M106"));
    return FW_NEVER;
}
