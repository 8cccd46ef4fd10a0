/* The PNG writer on printer-sized layer masks: synthetic cross-sections (see
   tests/maskgen.h) at 2560x1440 and 3840x2400, 1-bit and anti-aliased 8-bit.
   Only png_encode_gray is timed; prints medians over the layers.
   usage: bench_png [layers per size, default 300] */
#include "../adaslice.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../host/codec/png.h"
#include "../tests/maskgen.h"
#include <stdio.h>
#include "timing.h"
#include <stdlib.h>
#include <time.h>


int main(int argc, char **argv)
{
    static const int sizes[2][2] = {{2560, 1440}, {3840, 2400}};
    int layers = argc > 1 ? atoi(argv[1]) : 300;
    if (layers < 1) { fprintf(stderr, "usage: bench_png [layers]\n"); return 2; }
    printf("%-11s %4s %7s %9s %8s %11s %9s\n", "size", "bits", "layers", "ms/mask", "MB/s", "median B",
           "max B");
    for (int s = 0; s < 2; s++) {
        int w = sizes[s][0], h = sizes[s][1];
        size_t stride = ((size_t)w + 7) / 8;
        unsigned char *gray = (unsigned char *)malloc((size_t)w * (size_t)h);
        unsigned char *packed = (unsigned char *)malloc(stride * (size_t)h);
        double *ms = (double *)malloc((size_t)layers * sizeof *ms);
        double *bytes = (double *)malloc((size_t)layers * sizeof *bytes);
        if (!gray || !packed || !ms || !bytes) { fprintf(stderr, "out of memory\n"); return 1; }
        for (int bits = 1; bits <= 8; bits += 7) {
            double raw = bits == 1 ? (double)stride * h : (double)w * h, max_bytes = 0;
            for (int k = 0; k < layers; k++) {
                unsigned char *png;
                size_t size;
                double t;
                mask_scene(gray, w, h, k);
                if (bits == 1) mask_pack(gray, w, h, packed, stride);
                t = now();
                if (png_encode_gray(bits == 1 ? packed : gray, w, h, bits == 1 ? stride : (size_t)w, bits,
                                    &png, &size)) {
                    fprintf(stderr, "out of memory\n");
                    return 1;
                }
                ms[k] = (now() - t) * 1e3;
                bytes[k] = (double)size;
                if (bytes[k] > max_bytes) max_bytes = bytes[k];
                free(png);
            }
            {
                double m = median(ms, layers);
                printf("%4dx%-6d %4d %7d %9.3f %8.0f %11.0f %9.0f\n", w, h, bits, layers, m, raw / m / 1e3,
                       median(bytes, layers), max_bytes);
            }
        }
        free(gray);
        free(packed);
        free(ms);
        free(bytes);
    }
    return 0;
}
