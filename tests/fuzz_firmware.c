/* libFuzzer target: the firmware core's frame parser and message handlers.
   The input is a script: each step's first byte picks raw bytes (the
   deframer and the G-code reader see anything) or a message framed with a
   good CRC and the expected sequence number (so the handlers are reached
   past the CRC), then time runs on. The core must never crash, hang or
   corrupt memory. */
#include "fakeport.h"
#include <stddef.h>
#include <stdint.h>

static fake_printer printer;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    size_t at = 0;
    fake_init(&printer, 64, 32, (uint8_t)(size && (data[0] & 1) ? 8 : 1));
    while (at + 2 <= size) {
        uint8_t op = data[at], len = data[at + 1];
        size_t n = len;
        at += 2;
        if (n > size - at) n = size - at;
        switch (op & 3) {
        case 0: /* raw bytes */
            fake_bytes(&printer, data + at, n);
            break;
        case 1: /* a message the core will take: type from op */
        case 2:
            if (n > LINK_PAYLOAD_MAX) n = LINK_PAYLOAD_MAX;
            fake_send(&printer, (uint8_t)(op >> 2 | (op & 2 ? 0x20 : 0)), data + at, n);
            break;
        default: /* time passes */
            fake_run(&printer, printer.now + (uint64_t)len * FAKE_TICK_HZ / 16);
            n = 0;
            break;
        }
        at += n;
    }
    fake_run(&printer, printer.now + 2ull * FAKE_TICK_HZ);
    return 0;
}
