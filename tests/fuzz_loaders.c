/* libFuzzer target for the mesh loaders: every input is read in AUTO mode and as
   each format; a mesh that loads must be usable, and a failure must leave a zeroed
   mesh and a one-line message.
   clang -g -O1 -fsanitize=fuzzer,address,undefined tests/fuzz_loaders.c -lm -o fuzz_loaders
   mkdir -p /tmp/corpus && ./fuzz_loaders -max_total_time=60 /tmp/corpus tests/fuzz_seeds/loaders
   (new inputs go to the first directory, so the seeds stay as they are) */
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void check(const uint8_t *data, size_t size, adaslice_format format)
{
    adaslice_load_options options;
    adaslice_mesh m, zero;
    adaslice_error e;
    double lo[3], hi[3];
    size_t i;
    memset(&options, 0, sizeof options);
    memset(&zero, 0, sizeof zero);
    options.format = format;
    if (adaslice_mesh_load(data, size, &options, &m, &e) != ADASLICE_OK) {
        if (memcmp(&m, &zero, sizeof m) != 0 || !e.message[0] || strchr(e.message, '\n')) abort();
        return;
    }
    if (m.triangle_count == 0 || m.vertex_count > UINT32_MAX) abort();
    for (i = 0; i < 3 * m.triangle_count; i++)
        if (m.triangles[i] >= m.vertex_count) abort();
    for (i = 0; i < 3 * m.vertex_count; i++)
        if (!(fabs(m.vertices[i]) <= FLT_MAX)) abort();
    adaslice_mesh_bounds(&m, lo, hi);
    for (i = 0; i < 3; i++)
        if (!(lo[i] <= hi[i])) abort();
    adaslice_mesh_free(&m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const adaslice_format formats[] = {ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_STL_BINARY,
                                              ADASLICE_FORMAT_STL_ASCII, ADASLICE_FORMAT_OBJ, ADASLICE_FORMAT_PLY};
    size_t i;
    for (i = 0; i < sizeof formats / sizeof *formats; i++) check(data, size, formats[i]);
    return 0;
}
