/* libFuzzer target for what contour reads besides the mesh: each line of
   the input through the G-code word parser and the comment readers (which
   must stay inside the line: the line is copied to a buffer of exactly its
   size), and the whole input as a raw deflate stream (inflate.h) into
   outputs of a few sizes. Aborts on a parse that reports what it cannot
   have seen: an offset past the line, a value not finite, a letter that is
   not a command's.
   clang -std=c99 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
       tests/fuzz_contour.c host/gcode.c host/codec/inflate.c -lm -o fuzz_contour */
#include "../host/gcode.h"
#include "../host/codec/inflate.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const size_t outs[] = {0, 1, 100, 4096, 65536};
    size_t start = 0, i, k;
    while (start < size) {
        size_t len = 0, bad = (size_t)-1;
        char *line;
        gcode_words w;
        double v;
        while (start + len < size && data[start + len] != '\n') len++;
        line = (char *)malloc(len ? len : 1);
        if (!line) abort();
        memcpy(line, data + start, len);
        if (gcode_parse(line, len, &w, &bad)) {
            if (bad >= len) abort();
        } else {
            if (w.letter && w.letter != 'G' && w.letter != 'M' && w.letter != 'T') abort();
            if (w.has > 31 || w.code < 0 || w.code >= 10000) abort();
            for (k = 0; k < 5; k++)
                if ((w.has & (1u << k)) && !isfinite(w.v[k])) abort();
        }
        if (gcode_comment_number(line, len, "Z:", &v) && !isfinite(v)) abort();
        if (gcode_comment_number(line, len, "HEIGHT:", &v) && !isfinite(v)) abort();
        (void)gcode_is_comment(line, len, "TYPE:");
        free(line);
        start += len + 1;
    }
    {   /* the config lines, read backwards over a copy of exactly the input's bytes */
        char *text = (char *)malloc(size ? size : 1);
        const char *v;
        size_t n;
        if (!text) abort();
        memcpy(text, data, size);
        if ((v = gcode_config_value(text, size, "bed_shape", &n)) != NULL && (v < text || v + n > text + size)) abort();
        free(text);
    }
    for (i = 0; i < sizeof outs / sizeof *outs; i++) {
        unsigned char *out = (unsigned char *)malloc(outs[i] ? outs[i] : 1);
        if (!out) abort();
        (void)inflate_bytes(data, size, out, outs[i]);
        free(out);
    }
    return 0;
}
