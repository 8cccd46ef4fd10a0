/* Mesh loaders: each format written from a generated mesh and read back, the options,
   and every kind of malformed input with the exact place its error names. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"

/* ------------------------------------------------------------ helpers */

typedef struct buf { char *p; size_t n, cap; } buf;

static void put(buf *b, const void *d, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = 2 * (b->n + n) + 64;
        b->p = (char *)realloc(b->p, b->cap);
        if (!b->p) abort();
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}

static void putf(buf *b, const char *fmt, ...)
{
    char tmp[512];
    int n;
    va_list ap;
    va_start(ap, fmt);
    n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    put(b, tmp, (size_t)n);
}

/* `bits` as `size` bytes, little or big endian. */
static void put_int(buf *b, unsigned long long bits, int size, int big)
{
    unsigned char d[8];
    int i;
    for (i = 0; i < size; i++) d[big ? size - 1 - i : i] = (unsigned char)(bits >> (8 * i));
    put(b, d, (size_t)size);
}

static void put_float(buf *b, float f, int big)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_int(b, u, 4, big);
}

/* Offset of the first `needle` in a buffer that holds text. */
static size_t at(const buf *b, const char *needle)
{
    size_t i, n = strlen(needle);
    for (i = 0; i + n <= b->n; i++)
        if (memcmp(b->p + i, needle, n) == 0) return i;
    abort();
}

static void text(buf *b, const char *s) { b->n = 0; put(b, s, strlen(s)); }

/* Counts live blocks, so that every error path can be checked for leaks. */
static long live_blocks;
static void *count_alloc(void *user, size_t size) { (void)user; live_blocks++; return malloc(size); }
static void count_free(void *user, void *p) { (void)user; if (p) live_blocks--; free(p); }
static const adaslice_allocator counting = {count_alloc, count_free, NULL};

static adaslice_result load(const buf *b, adaslice_format format, double scale, adaslice_mesh *m, adaslice_error *e)
{
    adaslice_load_options o;
    memset(&o, 0, sizeof o);
    o.format = format;
    o.scale = scale;
    o.allocator = &counting;
    return adaslice_mesh_load(b->p, b->n, &o, m, e);
}

/* Loads b and expects `code` at exactly this offset and line, a zeroed mesh, a
   one-line message, and nothing left allocated. */
static void expect_fail(const char *what, const buf *b, adaslice_format format, adaslice_result code,
                        size_t offset, size_t line)
{
    adaslice_mesh m, zero;
    adaslice_error e;
    adaslice_result r;
    memset(&zero, 0, sizeof zero);
    live_blocks = 0;
    r = load(b, format, 0, &m, &e);
    CHECKF(r == code && e.result == code && e.offset == offset && e.line == line,
           "%s: got %s at offset %zu line %zu (%s); want %s at offset %zu line %zu", what,
           adaslice_result_name(r), e.offset, e.line, e.message, adaslice_result_name(code), offset, line);
    CHECKF(memcmp(&m, &zero, sizeof m) == 0, "%s: the mesh is not zeroed after an error", what);
    CHECKF(e.message[0] && !strchr(e.message, '\n'), "%s: message '%s'", what, e.message);
    CHECKF(live_blocks == 0, "%s: %ld blocks leaked", what, live_blocks);
    if (r == ADASLICE_OK) adaslice_mesh_free(&m);
}

static void expect_message(const char *what, const buf *b, adaslice_format format, const char *part)
{
    adaslice_mesh m;
    adaslice_error e;
    if (load(b, format, 0, &m, &e) == ADASLICE_OK) adaslice_mesh_free(&m);
    CHECKF(strstr(e.message, part) != NULL, "%s: message '%s' lacks '%s'", what, e.message, part);
}

/* Same triangles in the same order, corner by corner, coordinates times `scale`. */
static void expect_same(const char *what, const adaslice_mesh *want, const adaslice_mesh *got, double scale)
{
    size_t i;
    int c, k;
    CHECKF(got->triangle_count == want->triangle_count, "%s: %zu triangles, want %zu", what,
           got->triangle_count, want->triangle_count);
    if (got->triangle_count != want->triangle_count) return;
    for (i = 0; i < want->triangle_count; i++)
        for (c = 0; c < 3; c++) {
            const float *p = want->vertices + 3 * want->triangles[3 * i + c];
            const float *q = got->vertices + 3 * got->triangles[3 * i + c];
            CHECKF(got->triangles[3 * i + c] < got->vertex_count, "%s: index out of range", what);
            for (k = 0; k < 3; k++)
                if (q[k] != (float)(p[k] * scale)) {
                    CHECKF(0, "%s: triangle %zu corner %d axis %d is %.9g, want %.9g", what, i, c, k, q[k],
                           (float)(p[k] * scale));
                    return;
                }
        }
}

static void expect_roundtrip(const char *what, const buf *b, adaslice_format format, adaslice_format detected,
                             const adaslice_mesh *want)
{
    adaslice_mesh m;
    adaslice_error e;
    adaslice_result r;
    live_blocks = 0;
    r = load(b, format, 0, &m, &e);
    CHECKF(r == ADASLICE_OK, "%s: %s", what, e.message);
    if (r != ADASLICE_OK) return;
    CHECKF(m.format == detected, "%s: format %d, want %d", what, (int)m.format, (int)detected);
    expect_same(what, want, &m, 1);
    adaslice_mesh_free(&m);
    CHECKF(live_blocks == 0, "%s: %ld blocks leaked", what, live_blocks);
}

/* ------------------------------------------------------------ writers */

static void write_stl_binary(buf *b, const adaslice_mesh *m, const char *header)
{
    char h[80];
    size_t i;
    int c, k;
    memset(h, 0, sizeof h);
    memcpy(h, header, strlen(header));
    b->n = 0;
    put(b, h, 80);
    put_int(b, m->triangle_count, 4, 0);
    for (i = 0; i < m->triangle_count; i++) {
        for (k = 0; k < 3; k++) put_float(b, 7.0f, 0); /* a wrong normal, which must be ignored */
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) put_float(b, m->vertices[3 * m->triangles[3 * i + c] + k], 0);
        put_int(b, 0, 2, 0);
    }
}

/* The triangles split over `solids` solid blocks, lines ending in `eol`. */
static void write_stl_ascii(buf *b, const adaslice_mesh *m, int solids, const char *eol)
{
    size_t i, per = (m->triangle_count + (size_t)solids - 1) / (size_t)solids;
    int c;
    b->n = 0;
    for (i = 0; i < m->triangle_count; i++) {
        if (i % per == 0) putf(b, "solid part%zu%s", i / per, eol);
        putf(b, "  facet normal 0 0 1%s    outer loop%s", eol, eol);
        for (c = 0; c < 3; c++) {
            const float *v = m->vertices + 3 * m->triangles[3 * i + c];
            putf(b, "      vertex %.9g %.9g %.9g%s", v[0], v[1], v[2], eol);
        }
        putf(b, "    endloop%s  endfacet%s", eol, eol);
        if (i % per == per - 1 || i + 1 == m->triangle_count) putf(b, "endsolid part%zu%s", i / per, eol);
    }
}

/* Corners cycle through the forms a, a/t, a/t/n and a//n; every other face uses
   relative (negative) indices. */
static void write_obj(buf *b, const adaslice_mesh *m)
{
    static const char *const tails[4] = {"", "/1", "/1/1", "//1"};
    size_t i;
    int c;
    b->n = 0;
    putf(b, "# written by test_loaders\nmtllib none.mtl\no sphere\n");
    for (i = 0; i < m->vertex_count; i++)
        putf(b, "v %.9g %.9g %.9g\n", m->vertices[3 * i], m->vertices[3 * i + 1], m->vertices[3 * i + 2]);
    putf(b, "vt 0 0\nvn 0 0 1\ng all\nusemtl none\ns 1\n");
    for (i = 0; i < m->triangle_count; i++) {
        putf(b, "f");
        for (c = 0; c < 3; c++) {
            long long v = m->triangles[3 * i + c];
            putf(b, " %lld%s", i % 2 ? v - (long long)m->vertex_count : v + 1, tails[(i + (size_t)c) % 4]);
        }
        putf(b, "\n");
    }
}

/* One PLY scalar: `type` is a PLY type name, `v` is exact in it. */
static void put_ply_value(buf *b, int encoding, const char *type, double v)
{
    static const char *const names[16] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                           "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32",
                                           "float64"};
    int t = 0, big = encoding == 2;
    while (strcmp(names[t], type) != 0) t++;
    t %= 8;
    if (encoding == 0) {
        if (t == 6) putf(b, " %.9g", v);
        else if (t == 7) putf(b, " %.17g", v);
        else putf(b, " %lld", (long long)v);
    } else if (t == 6) {
        put_float(b, (float)v, big);
    } else if (t == 7) {
        uint64_t u;
        memcpy(&u, &v, 8);
        put_int(b, u, 8, big);
    } else {
        put_int(b, (unsigned long long)(long long)v, 1 << (t / 2), big);
    }
}

typedef struct ply_style {
    int encoding;                /* 0 ascii, 1 little endian, 2 big endian */
    const char *x, *y, *z;       /* coordinate types */
    const char *count, *index;   /* face list types */
    int extras;                  /* properties, a list and an element we must skip */
} ply_style;

static void write_ply(buf *b, const adaslice_mesh *m, const ply_style *s)
{
    static const char *const formats[3] = {"ascii", "binary_little_endian", "binary_big_endian"};
    size_t i;
    int c;
    b->n = 0;
    putf(b, "ply\nformat %s 1.0\ncomment written by test_loaders\n", formats[s->encoding]);
    putf(b, "element vertex %zu\nproperty %s x\nproperty %s y\n", m->vertex_count, s->x, s->y);
    if (s->extras) putf(b, "property uchar red\nproperty list uchar float uv\n");
    putf(b, "property %s z\n", s->z);
    if (s->extras) putf(b, "element material 2\nproperty int8 id\nproperty list ushort double weights\n");
    putf(b, "element face %zu\n", m->triangle_count);
    if (s->extras) putf(b, "property int16 flags\n");
    putf(b, "property list %s %s vertex_indices\n", s->count, s->index);
    if (s->extras) putf(b, "property float quality\n");
    putf(b, "end_header\n");
    for (i = 0; i < m->vertex_count; i++) {
        put_ply_value(b, s->encoding, s->x, m->vertices[3 * i]);
        put_ply_value(b, s->encoding, s->y, m->vertices[3 * i + 1]);
        if (s->extras) {
            put_ply_value(b, s->encoding, "uchar", 200);
            put_ply_value(b, s->encoding, "uchar", (double)(i % 3));
            for (c = 0; c < (int)(i % 3); c++) put_ply_value(b, s->encoding, "float", 0.5);
        }
        put_ply_value(b, s->encoding, s->z, m->vertices[3 * i + 2]);
        if (!s->encoding) putf(b, "\n");
    }
    for (i = 0; s->extras && i < 2; i++) {
        put_ply_value(b, s->encoding, "int8", -5);
        put_ply_value(b, s->encoding, "ushort", 3);
        for (c = 0; c < 3; c++) put_ply_value(b, s->encoding, "double", -1e300);
        if (!s->encoding) putf(b, "\n");
    }
    for (i = 0; i < m->triangle_count; i++) {
        if (s->extras) put_ply_value(b, s->encoding, "int16", -300);
        put_ply_value(b, s->encoding, s->count, 3);
        for (c = 0; c < 3; c++) put_ply_value(b, s->encoding, s->index, m->triangles[3 * i + c]);
        if (s->extras) put_ply_value(b, s->encoding, "float", 1.5);
        if (!s->encoding) putf(b, "\n");
    }
}

/* --------------------------------------------------------- round trips */

static void binary_stl_round_trips(void)
{
    adaslice_mesh sphere = gen_sphere(3, 16, 9, 1);
    buf b = {0, 0, 0};
    write_stl_binary(&b, &sphere, "made by test_loaders");
    expect_roundtrip("binary STL", &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_STL_BINARY, &sphere);
    expect_roundtrip("binary STL, forced", &b, ADASLICE_FORMAT_STL_BINARY, ADASLICE_FORMAT_STL_BINARY, &sphere);
    /* many exporters start the binary header with "solid" */
    write_stl_binary(&b, &sphere, "solid exported by a careless tool");
    expect_roundtrip("binary STL named solid", &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_STL_BINARY, &sphere);
    gen_free(&sphere);
    free(b.p);
}

static void binary_stl_keeps_its_corners(void)
{
    adaslice_mesh box = gen_box(0, 0, 0, 1, 2, 3), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    write_stl_binary(&b, &box, "");
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK);
    CHECK(m.vertex_count == 36);
    CHECK(m.triangle_count == 12);
    adaslice_mesh_free(&m);
    gen_free(&box);
    free(b.p);
}

static void ascii_stl_round_trips(void)
{
    adaslice_mesh sphere = gen_cone(2.5, 4, 12, 0.5);
    buf b = {0, 0, 0};
    write_stl_ascii(&b, &sphere, 1, "\n");
    expect_roundtrip("ASCII STL", &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_STL_ASCII, &sphere);
    write_stl_ascii(&b, &sphere, 3, "\r\n");
    expect_roundtrip("ASCII STL, 3 solids, CRLF", &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_STL_ASCII, &sphere);
    expect_roundtrip("ASCII STL, forced", &b, ADASLICE_FORMAT_STL_ASCII, ADASLICE_FORMAT_STL_ASCII, &sphere);
    gen_free(&sphere);
    free(b.p);
}

/* The pentagon the polygon cases write, fan-triangulated from corner `apex`. */
static adaslice_mesh pentagon_fan(uint32_t apex)
{
    adaslice_mesh m = gen_alloc(5, 3);
    uint32_t k;
    gen_vertex(&m, 0, 0, 0);
    gen_vertex(&m, 2, 0, 0);
    gen_vertex(&m, 3, 1, 0);
    gen_vertex(&m, 1, 2, 0);
    gen_vertex(&m, -1, 1, 0);
    for (k = 1; k < 4; k++) gen_triangle(&m, apex, (apex + k) % 5, (apex + k + 1) % 5);
    return m;
}

static void ascii_stl_polygons_are_fanned(void)
{
    adaslice_mesh want = pentagon_fan(0), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    text(&b, "SOLID pentagon\nFACET NORMAL 0 0 1\nOUTER LOOP\nvertex 0 0 0\nvertex 2 0 0\nvertex 3 1 0\n"
             "vertex 1 2 0\nvertex -1 1 0\nENDLOOP\nENDFACET\nENDSOLID");
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    expect_same("pentagon facet", &want, &m, 1);
    CHECK(m.vertex_count == 5);
    adaslice_mesh_free(&m);
    gen_free(&want);
    free(b.p);
}

static void obj_round_trips(void)
{
    adaslice_mesh sphere = gen_sphere(1.25, 10, 6, 2), cylinder = gen_cylinder(0.5, 3, 9, 0);
    buf b = {0, 0, 0};
    gen_append(&sphere, &cylinder); /* two shells */
    gen_free(&cylinder);
    write_obj(&b, &sphere);
    expect_roundtrip("OBJ", &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_OBJ, &sphere);
    expect_roundtrip("OBJ, forced", &b, ADASLICE_FORMAT_OBJ, ADASLICE_FORMAT_OBJ, &sphere);
    gen_free(&sphere);
    free(b.p);
}

static void obj_polygons_and_statements_load(void)
{
    adaslice_mesh want = gen_alloc(8, 6), m;
    adaslice_error e;
    double lo[3], hi[3];
    buf b = {0, 0, 0};
    gen_vertex(&want, 0, 0, 0);
    gen_vertex(&want, 1, 0, 0);
    gen_vertex(&want, 1, 1, 0);
    gen_vertex(&want, 0, 1, 0);
    gen_vertex(&want, 0, 0, 1);
    gen_triangle(&want, 0, 1, 2); /* the quad */
    gen_triangle(&want, 0, 2, 3);
    gen_triangle(&want, 0, 1, 4); /* the triangle with relative indices */
    gen_triangle(&want, 4, 1, 2); /* the pentagon */
    gen_triangle(&want, 4, 2, 3);
    gen_triangle(&want, 4, 3, 0);
    text(&b, "# a comment\n\nmtllib a.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n"
             "vt 0.5 0.5\nvn 0 0 1\ng side\nusemtl red\ns off\n"
             "f 1/1/1 2/1/1 3/1/1 4/1/1 # a quad\nl 1 2\np 3\ncurv 0 1 1 2\n"
             "v 0 0 1\nf -5//1 -4//1 -1//1\nv 9 9 9\nf 5/1 2/1 3 4/1 1\n");
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    expect_same("OBJ polygons", &want, &m, 1);
    CHECK(m.vertex_count == 6);
    /* the unreferenced vertex (9, 9, 9) is outside the bounds */
    adaslice_mesh_bounds(&m, lo, hi);
    CHECK(lo[0] == 0 && lo[1] == 0 && lo[2] == 0 && hi[0] == 1 && hi[1] == 1 && hi[2] == 1);
    adaslice_mesh_free(&m);
    gen_free(&want);
    free(b.p);
}

static void ply_round_trips(void)
{
    static const ply_style styles[] = {
        {0, "float", "float", "float", "uchar", "int", 0},
        {1, "float", "float", "float", "uchar", "int", 0},
        {2, "float", "float", "float", "uchar", "int", 0},
        {0, "double", "float32", "float64", "uint8", "uint32", 1},
        {1, "float64", "float", "double", "ushort", "uint", 1},
        {2, "double", "float32", "float", "int", "int32", 1},
        {2, "float", "float", "float", "uint16", "ushort", 1},
    };
    adaslice_mesh sphere = gen_sphere(0.75, 14, 8, 0.5);
    buf b = {0, 0, 0};
    char what[64];
    size_t i;
    for (i = 0; i < sizeof styles / sizeof *styles; i++) {
        write_ply(&b, &sphere, &styles[i]);
        snprintf(what, sizeof what, "PLY style %zu", i);
        expect_roundtrip(what, &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_PLY, &sphere);
    }
    gen_free(&sphere);
    free(b.p);
}

/* Coordinates of integer types: a box with integer corners. */
static void ply_integer_coordinates_load(void)
{
    static const ply_style styles[] = {
        {0, "int8", "int16", "uint32", "uchar", "uint8", 1},
        {1, "char", "short", "uint", "uchar", "uchar", 1},
        {2, "int8", "int", "ushort", "int8", "short", 1},
    };
    adaslice_mesh box = gen_box(-100, -3000, 0, 120, 30000, 60000);
    buf b = {0, 0, 0};
    char what[64];
    size_t i;
    for (i = 0; i < sizeof styles / sizeof *styles; i++) {
        write_ply(&b, &box, &styles[i]);
        snprintf(what, sizeof what, "PLY integer style %zu", i);
        expect_roundtrip(what, &b, ADASLICE_FORMAT_AUTO, ADASLICE_FORMAT_PLY, &box);
    }
    gen_free(&box);
    free(b.p);
}

static void ply_polygons_are_fanned(void)
{
    adaslice_mesh want = pentagon_fan(4), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    text(&b, "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_index\nend_header\n"
             "0 0 0\n2 0 0\n3 1 0\n1 2 0\n-1 1 0\n5 4 0 1 2 3\n");
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    expect_same("PLY pentagon", &want, &m, 1);
    adaslice_mesh_free(&m);
    text(&b, "ply\r\nformat ascii 1.0\r\nelement vertex 5\r\nproperty float x\r\nproperty float y\r\n"
             "property float z\r\nelement face 1\r\nproperty list uchar int vertex_index\r\nend_header\r\n"
             "0 0 0\r\n2 0 0\r\n3 1 0\r\n1 2 0\r\n-1 1 0\r\n5 4 0 1 2 3\r\n");
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    expect_same("PLY pentagon, CRLF", &want, &m, 1);
    adaslice_mesh_free(&m);
    gen_free(&want);
    free(b.p);
}

/* Binary faces that are mostly triangles with a polygon among them (the
   loader reads plain little-endian triangles on a path of their own and
   leaves the rest to the general one): the fans and the triangles after the
   polygon as written, either byte order, signed and unsigned indices. */
static void ply_binary_triangles_around_a_polygon(void)
{
    static const int faces[] = {3, 0, 1, 2, 4, 0, 2, 3, 4, 3, 1, 2, 3, 3, 4, 3, 1};
    static const char *const index[2] = {"int", "uint"};
    adaslice_mesh want = gen_alloc(5, 5), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    int enc, t, i;
    gen_vertex(&want, 0, 0, 0);
    gen_vertex(&want, 2, 0, 0);
    gen_vertex(&want, 3, 1, 0);
    gen_vertex(&want, 1, 2, 1);
    gen_vertex(&want, -1, 1, 0);
    gen_triangle(&want, 0, 1, 2);
    gen_triangle(&want, 0, 2, 3); /* the quad 0 2 3 4, fanned */
    gen_triangle(&want, 0, 3, 4);
    gen_triangle(&want, 1, 2, 3);
    gen_triangle(&want, 4, 3, 1);
    for (enc = 1; enc < 3; enc++)
        for (t = 0; t < 2; t++) {
            b.n = 0;
            putf(&b, "ply\nformat %s 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 4\nproperty list uchar %s vertex_indices\nend_header\n",
                 enc == 1 ? "binary_little_endian" : "binary_big_endian", index[t]);
            for (i = 0; i < 15; i++) put_ply_value(&b, enc, "float", want.vertices[i]);
            for (i = 0; i < (int)(sizeof faces / sizeof *faces); i++)
                put_ply_value(&b, enc, i == 0 || i == 4 || i == 9 || i == 13 ? "uchar" : index[t], faces[i]);
            CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
            expect_same(enc == 1 ? "PLY little endian, a quad among triangles" : "PLY big endian, a quad among triangles",
                        &want, &m, 1);
            adaslice_mesh_free(&m);
        }
    gen_free(&want);
    free(b.p);
}

/* Two strips: 0 1 2 3 and, after a -1 restart, 2 3 4 5; the second triangle of each
   runs backwards so that all face the same way. The repeated last index makes a
   degenerate stitching triangle, which is dropped. */
static void ply_triangle_strips_load(void)
{
    adaslice_mesh want = gen_alloc(6, 4), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    int enc, i;
    static const int strip[] = {0, 1, 2, 3, -1, 2, 3, 4, 5, 5};
    for (i = 0; i < 3; i++) {
        gen_vertex(&want, i, 0, 0);
        gen_vertex(&want, i, 1, 0);
    }
    gen_triangle(&want, 0, 1, 2);
    gen_triangle(&want, 2, 1, 3);
    gen_triangle(&want, 2, 3, 4);
    gen_triangle(&want, 4, 3, 5);
    for (enc = 0; enc < 3; enc++) {
        b.n = 0;
        putf(&b, "ply\nformat %s 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                 "element tristrips 1\nproperty list int int vertex_indices\nend_header\n",
             enc == 0 ? "ascii" : enc == 1 ? "binary_little_endian" : "binary_big_endian");
        for (i = 0; i < 6; i++) {
            put_ply_value(&b, enc, "float", want.vertices[3 * i]);
            put_ply_value(&b, enc, "float", want.vertices[3 * i + 1]);
            put_ply_value(&b, enc, "float", want.vertices[3 * i + 2]);
        }
        put_ply_value(&b, enc, "int", 10);
        for (i = 0; i < 10; i++) put_ply_value(&b, enc, "int", strip[i]);
        CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
        expect_same("PLY tristrips", &want, &m, 1); /* the join (a repeated index) is no triangle */
        adaslice_mesh_free(&m);
    }
    gen_free(&want);
    free(b.p);
}

/* ------------------------------------------------------------- options */

static void scale_multiplies_coordinates(void)
{
    adaslice_mesh sphere = gen_sphere(0.1, 8, 5, 0), m;
    adaslice_error e;
    double lo[3], hi[3];
    buf b = {0, 0, 0};
    write_stl_binary(&b, &sphere, "");
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, 1000, &m, &e) == ADASLICE_OK);
    expect_same("scale 1000", &sphere, &m, 1000);
    adaslice_mesh_bounds(&m, lo, hi);
    CHECKF(hi[2] - lo[2] > 199.9 && hi[2] - lo[2] < 200.1, "height %g", hi[2] - lo[2]);
    adaslice_mesh_free(&m);
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK);
    expect_same("scale 0 means 1", &sphere, &m, 1);
    adaslice_mesh_free(&m);
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, -2, &m, &e) == ADASLICE_ERR_ARGUMENT);
    /* finite in the file, but not once scaled into a float */
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1e30 0\nf 1 2 3\n");
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, 1e10, &m, &e) == ADASLICE_ERR_NONFINITE);
    CHECK(e.line == 3 && e.offset == at(&b, "1e30"));
    gen_free(&sphere);
    free(b.p);
}

/* Zero-area triangles are kept, in order (repair collapses those that seal
   T-junctions and drops the rest); a file of nothing else is empty. */
static void degenerate_triangles_are_kept(void)
{
    adaslice_mesh m;
    adaslice_error e;
    buf b = {0, 0, 0};
    /* a repeated index, a collinear triangle and two real ones */
    text(&b, "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 1 2\nf 1 2 3\nf 1 2 4\nf 4 2 3\n");
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    CHECK(m.triangle_count == 4);
    CHECK(m.triangles[3] == 0 && m.triangles[4] == 1 && m.triangles[5] == 2);
    adaslice_mesh_free(&m);
    text(&b, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n");
    expect_fail("only degenerate triangles", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    expect_message("only degenerate triangles", &b, ADASLICE_FORMAT_AUTO, "all 2 triangles have zero area");
    free(b.p);
}

static void free_and_bounds(void)
{
    adaslice_mesh m;
    double lo[3], hi[3];
    memset(&m, 0, sizeof m);
    adaslice_mesh_free(&m);
    adaslice_mesh_free(NULL);
    adaslice_mesh_bounds(&m, lo, hi);
    CHECK(lo[0] == 0 && hi[2] == 0);
    CHECK(adaslice_mesh_load(NULL, 0, NULL, &m, NULL) == ADASLICE_ERR_EMPTY);
    CHECK(adaslice_mesh_load(NULL, 5, NULL, &m, NULL) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_mesh_load("v", 1, NULL, NULL, NULL) == ADASLICE_ERR_ARGUMENT);
}

/* The box of the corners, one by one (the reference), a zero as +0. */
static void corner_box(const adaslice_mesh *m, double lo[3], double hi[3])
{
    size_t i;
    int k;
    for (k = 0; k < 3; k++) { lo[k] = DBL_MAX; hi[k] = -DBL_MAX; }
    for (i = 0; i < 3 * m->triangle_count; i++)
        for (k = 0; k < 3; k++) {
            double q = m->vertices[3 * (size_t)m->triangles[i] + k] + 0.0;
            lo[k] = q < lo[k] ? q : lo[k];
            hi[k] = q > hi[k] ? q : hi[k];
        }
}

/* adaslice_mesh_bounds against the corners one by one: a sphere; with an
   unused vertex first (the lowest index, so the first found on its faces)
   beyond the part, then on the part's faces exactly (a tie with used ones);
   zeros of either sign; and no allocation at all, whatever the mesh's
   allocator (threads may read one mesh at once). */
static void *refuse_alloc(void *user, size_t size)
{
    (void)size;
    ++*(long *)user;
    return NULL;
}

static void refuse_free(void *user, void *p)
{
    (void)user;
    (void)p;
}

static void bounds_are_the_corners(void)
{
    adaslice_mesh s = gen_sphere(3, 16, 9, 1), m;
    long asked = 0;
    const adaslice_allocator refuse = {refuse_alloc, refuse_free, &asked};
    double lo[3], hi[3], want_lo[3], want_hi[3], part_lo[3], part_hi[3];
    int c, k, same;
    corner_box(&s, part_lo, part_hi);
    for (c = 0; c < 4; c++) {
        size_t i;
        m = gen_alloc(s.vertex_count + 1, s.triangle_count);
        if (c == 0) {
            memcpy(m.vertices, s.vertices, s.vertex_count * 3 * sizeof(float));
            m.vertex_count = s.vertex_count;
            memcpy(m.triangles, s.triangles, s.triangle_count * 3 * sizeof(uint32_t));
        } else {
            /* vertex 0 unused, the sphere's from 1 on */
            memcpy(m.vertices + 3, s.vertices, s.vertex_count * 3 * sizeof(float));
            m.vertex_count = s.vertex_count + 1;
            for (k = 0; k < 3; k++)
                m.vertices[k] = (float)(c == 1 ? (k == 0 ? -9 : 0.5) /* beyond one face */
                                      : c == 2 ? (k == 2 ? part_hi[2] : part_lo[k]) /* on three faces exactly */
                                               : part_lo[k] - 1); /* beyond three */
            for (i = 0; i < 3 * s.triangle_count; i++) m.triangles[i] = s.triangles[i] + 1;
        }
        m.triangle_count = s.triangle_count;
        m.allocator = refuse;
        adaslice_mesh_bounds(&m, lo, hi);
        corner_box(&m, want_lo, want_hi);
        for (same = 1, k = 0; k < 3; k++) same = same && lo[k] == want_lo[k] && hi[k] == want_hi[k];
        CHECKF(same, "case %d: (%g %g %g)-(%g %g %g) against the corners' (%g %g %g)-(%g %g %g)", c, lo[0], lo[1], lo[2],
               hi[0], hi[1], hi[2], want_lo[0], want_lo[1], want_lo[2], want_hi[0], want_hi[1], want_hi[2]);
        CHECKF(c != 1 || want_lo[0] == part_lo[0], "case 1: the stray vertex is in the corners' box");
        gen_free(&m);
    }
    /* zeros of either sign, -0 met first: the box's zeros are +0 */
    m = gen_alloc(3, 1);
    gen_vertex(&m, -0.0, 0, -0.0);
    gen_vertex(&m, 0.0, -1, 0.0);
    gen_vertex(&m, -1, -0.0, 1);
    gen_triangle(&m, 0, 1, 2);
    m.allocator = refuse;
    adaslice_mesh_bounds(&m, lo, hi);
    CHECKF(lo[0] == -1 && lo[1] == -1 && lo[2] == 0 && !signbit(lo[2]) && hi[0] == 0 && !signbit(hi[0]) &&
           hi[1] == 0 && !signbit(hi[1]) && hi[2] == 1, "(%g %g %g)-(%g %g %g)", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    gen_free(&m);
    CHECKF(asked == 0, "%ld allocations asked for", asked);
    gen_free(&s);
}

/* ----------------------------------------------------------- malformed */

static void malformed_binary_stl_is_refused(void)
{
    adaslice_mesh sphere = gen_sphere(1, 8, 5, 0);
    buf b = {0, 0, 0};
    char want[200];
    float nan = (float)strtod("nan", NULL);
    size_t nan_at = 84 + 50 * 3 + 12 + 12 * 2 + 4 * 1; /* triangle 3, corner 2, y */
    write_stl_binary(&b, &sphere, "");
    b.n = 60;
    expect_fail("binary STL shorter than its header", &b, ADASLICE_FORMAT_STL_BINARY, ADASLICE_ERR_TRUNCATED, 60, 0);
    write_stl_binary(&b, &sphere, "");
    b.n -= 30;
    expect_fail("binary STL cut short", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_COUNT, 80, 0);
    snprintf(want, sizeof want, "binary STL: header says %zu triangles (%zu bytes) but the data is %zu bytes",
             sphere.triangle_count, 84 + 50 * sphere.triangle_count, b.n);
    expect_message("binary STL cut short", &b, ADASLICE_FORMAT_AUTO, want);
    b.n += 30;
    put(&b, "extra", 5);
    expect_fail("binary STL with trailing bytes", &b, ADASLICE_FORMAT_STL_BINARY, ADASLICE_ERR_COUNT, 80, 0);
    b.n -= 5;
    memcpy(b.p + nan_at, &nan, 4);
    expect_fail("binary STL NaN", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NONFINITE, nan_at, 0);
    expect_message("binary STL NaN", &b, ADASLICE_FORMAT_AUTO, "coordinate nan is not finite");
    b.n = 84;
    memset(b.p + 80, 0, 4);
    expect_fail("binary STL with no triangles", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    gen_free(&sphere);
    free(b.p);
}

#define STL_HEAD "solid t\n facet normal 0 0 1\n  outer loop\n"

static void malformed_ascii_stl_is_refused(void)
{
    buf b = {0, 0, 0};
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 1.2.3 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n");
    expect_fail("ASCII STL 1.2.3", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "1.2.3"), 5);
    expect_message("ASCII STL 1.2.3", &b, ADASLICE_FORMAT_AUTO, "ASCII STL line 5: '1.2.3' is not a number");
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 -inf 0\n  endloop\n endfacet\nendsolid t\n");
    expect_fail("ASCII STL -inf", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NONFINITE, at(&b, "-inf"), 6);
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n");
    expect_fail("ASCII STL without endsolid", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n, 9);
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 0");
    expect_fail("ASCII STL cut in a vertex", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n, 5);
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n endfacet\nendsolid t\n");
    expect_fail("ASCII STL two-vertex loop", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "endloop"), 6);
    text(&b, STL_HEAD "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n"
                      "garbage\n");
    expect_fail("ASCII STL trailing junk", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "garbage"), 10);
    text(&b, "facet normal 0 0 1\n");
    expect_fail("ASCII STL forced, no solid", &b, ADASLICE_FORMAT_STL_ASCII, ADASLICE_ERR_FORMAT, 0, 1);
    free(b.p);
}

static void malformed_obj_is_refused(void)
{
    buf b = {0, 0, 0};
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n");
    expect_fail("OBJ index 0", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, at(&b, "f 1 2 0") + 6, 4);
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1/1 2/1 4/1\n");
    expect_fail("OBJ index past the end", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, at(&b, "4/1"), 5);
    expect_message("OBJ index past the end", &b, ADASLICE_FORMAT_AUTO,
                   "OBJ line 5: vertex index 4 is out of range (3 vertices so far)");
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
    expect_fail("OBJ index too negative", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, at(&b, "-4"), 4);
    text(&b, "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    expect_fail("OBJ face before its vertices", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, 2, 1);
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n");
    expect_fail("OBJ nan", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NONFINITE, at(&b, "nan"), 3);
    expect_message("OBJ nan", &b, ADASLICE_FORMAT_AUTO, "OBJ line 3: coordinate nan is not finite");
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n");
    expect_fail("OBJ short vertex", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "\nf"), 3);
    text(&b, "v 0 0 0\nv 1 0x 0\n");
    expect_fail("OBJ 0x", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "0x"), 2);
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n");
    expect_fail("OBJ word index", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "three"), 4);
    text(&b, "v 0 0 0\nv 1 0 0\n\nf 1 2\n");
    expect_fail("OBJ two-corner face", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "f"), 4);
    text(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    expect_fail("OBJ without faces", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    free(b.p);
}

#define PLY_BIN_HEAD "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n" \
                     "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n" \
                     "end_header\n"

/* A valid binary triangle after PLY_BIN_HEAD; returns the header length. */
static size_t ply_binary_triangle(buf *b)
{
    static const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    int i;
    text(b, PLY_BIN_HEAD);
    for (i = 0; i < 9; i++) put_float(b, xyz[i], 0);
    put_int(b, 3, 1, 0);
    for (i = 0; i < 3; i++) put_int(b, (unsigned)i, 4, 0);
    return strlen(PLY_BIN_HEAD);
}

static void malformed_ply_is_refused(void)
{
    buf b = {0, 0, 0};
    size_t head = ply_binary_triangle(&b), face = head + 36;
    float nan = (float)strtod("nan", NULL);
    adaslice_mesh sphere = gen_sphere(1, 8, 6, 0);
    const ply_style extras = {1, "float", "float", "float", "uchar", "int", 1};
    char want[100];
    adaslice_mesh m;
    adaslice_error e;
    CHECKF(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK, "%s", e.message);
    CHECK(m.triangle_count == 1);
    adaslice_mesh_free(&m);
    b.n = head + 30;
    expect_fail("PLY vertices cut short", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, head, 0);
    expect_message("PLY vertices cut short", &b, ADASLICE_FORMAT_AUTO,
                   "element 'vertex' has 3 records of at least 12 bytes, but only 30 bytes remain");
    ply_binary_triangle(&b);
    b.n -= 2;
    expect_fail("PLY face list cut short", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, face, 0);
    write_ply(&b, &sphere, &extras);
    b.n -= 2;
    expect_fail("PLY cut inside the last value", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n - 2, 0);
    expect_message("PLY cut inside the last value", &b, ADASLICE_FORMAT_AUTO, "(record 80 of 80)");
    ply_binary_triangle(&b);
    b.p[face] = 100;
    expect_fail("PLY list longer than the data", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, face, 0);
    expect_message("PLY list longer than the data", &b, ADASLICE_FORMAT_AUTO,
                   "a list of 100 entries cannot fit in the 12 bytes left");
    ply_binary_triangle(&b);
    b.p[face + 1 + 4] = 3;
    expect_fail("PLY index out of range", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, face + 1 + 4, 0);
    snprintf(want, sizeof want, "PLY byte %zu: vertex index 3 is out of range (3 vertices)", face + 5);
    expect_message("PLY index out of range", &b, ADASLICE_FORMAT_AUTO, want);
    ply_binary_triangle(&b);
    memset(b.p + face + 1 + 8, 0xff, 4);
    expect_fail("PLY index -1 in a face", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, face + 1 + 8, 0);
    ply_binary_triangle(&b);
    memcpy(b.p + head + 4 * 7, &nan, 4);
    expect_fail("PLY NaN", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NONFINITE, head + 28, 0);
    ply_binary_triangle(&b);
    b.p[face] = 2;
    expect_fail("PLY two-corner face", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, face, 0);
    gen_free(&sphere);
    free(b.p);
}

static void malformed_ply_headers_are_refused(void)
{
    buf b = {0, 0, 0};
    text(&b, "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n");
    expect_fail("PLY unknown format", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "binary_middle"), 2);
    text(&b, "ply\nformat ascii 2.0\nend_header\n");
    expect_fail("PLY version", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_UNSUPPORTED, at(&b, "2.0"), 2);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n");
    expect_fail("PLY without end_header", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n, 7);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty quad z\n"
             "end_header\n");
    expect_fail("PLY unknown type", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "quad"), 6);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nend_header\n");
    expect_fail("PLY without z", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "vertex 3"), 3);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar float vertex_indices\nend_header\n");
    expect_fail("PLY float indices", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "vertex_indices"), 8);
    text(&b, "ply\nformat ascii 1.0\nbogus line\nend_header\n");
    expect_fail("PLY unknown keyword", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, at(&b, "bogus"), 3);
    text(&b, "plx\nformat ascii 1.0\n");
    expect_fail("PLY forced, no magic", &b, ADASLICE_FORMAT_PLY, ADASLICE_ERR_FORMAT, 0, 1);
    /* absurd counts are refused before anything is allocated */
    text(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
             "property float y\nproperty float z\nend_header\n0123456789");
    expect_fail("PLY 4e9 vertices in a few bytes", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n - 10, 0);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 5000000000\nproperty float x\nend_header\n");
    expect_fail("PLY vertex count over 32 bits", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_OVERFLOW, at(&b, "5000"), 3);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 99999999999999999999999999\nproperty list uchar int vertex_indices\nend_header\n");
    expect_fail("PLY face count overflow", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_OVERFLOW, at(&b, "9999"), 7);
    text(&b, "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n");
    expect_fail("PLY negative count", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "-3"), 3);
    text(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uint uint vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n");
    expect_fail("PLY ASCII list longer than the data", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED,
                at(&b, "4000000000"), 13);
    free(b.p);
}

#define PLY_ASCII_HEAD "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n" \
                       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"

static void malformed_ascii_ply_is_refused(void)
{
    buf b = {0, 0, 0};
    text(&b, PLY_ASCII_HEAD "0 0 0\n1 0 0\n0 1 1.2.3\n3 0 1 2\n");
    expect_fail("PLY ASCII 1.2.3", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "1.2.3"), 12);
    text(&b, PLY_ASCII_HEAD "0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n");
    expect_fail("PLY ASCII fractional index", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NUMBER, at(&b, "2.5"), 13);
    text(&b, PLY_ASCII_HEAD "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    expect_fail("PLY ASCII index out of range", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_INDEX, at(&b, "7"), 13);
    text(&b, PLY_ASCII_HEAD "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
    expect_fail("PLY ASCII cut short", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_TRUNCATED, b.n, 14);
    text(&b, PLY_ASCII_HEAD "0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n");
    expect_fail("PLY ASCII inf", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_NONFINITE, at(&b, "inf"), 12);
    free(b.p);
}

static void formats_are_detected(void)
{
    buf b = {0, 0, 0};
    expect_fail("empty data", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    text(&b, " \r\n\t\n");
    expect_fail("only whitespace", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    text(&b, "hello, world\n");
    expect_fail("short text", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, 0, 0);
    text(&b, "# only a comment\n");
    expect_fail("only a comment", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_FORMAT, 0, 0);
    text(&b, "solid x\nendsolid x\n");
    expect_fail("ASCII STL without facets", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_EMPTY, 0, 0);
    expect_message("ASCII STL without facets", &b, ADASLICE_FORMAT_AUTO, "ASCII STL: no triangles");
    /* long enough for binary STL, so it is read as one that disagrees with its count */
    text(&b, "solid but not really an STL, just text that is long enough to be taken as binary.....\n");
    expect_fail("text read as binary STL", &b, ADASLICE_FORMAT_AUTO, ADASLICE_ERR_COUNT, 80, 0);
    free(b.p);
}

static void the_allocator_is_used(void)
{
    adaslice_mesh sphere = gen_sphere(1, 8, 5, 0), m;
    adaslice_error e;
    buf b = {0, 0, 0};
    write_obj(&b, &sphere);
    live_blocks = 0;
    CHECK(load(&b, ADASLICE_FORMAT_AUTO, 0, &m, &e) == ADASLICE_OK);
    CHECK(live_blocks == 2);
    CHECK(m.allocator.alloc == count_alloc && m.allocator.free == count_free);
    adaslice_mesh_free(&m);
    CHECK(live_blocks == 0);
    CHECK(m.vertices == NULL && m.triangle_count == 0);
    gen_free(&sphere);
    free(b.p);
}

/* The n-th allocation fails, for every n until the load succeeds: each failure is
   NOMEM with nothing leaked. */
static long allocs_left;
static void *failing_alloc(void *user, size_t size)
{
    if (allocs_left-- <= 0) return NULL;
    return count_alloc(user, size);
}

static void running_out_of_memory_leaks_nothing(void)
{
    const adaslice_allocator failing = {failing_alloc, count_free, NULL};
    adaslice_mesh sphere = gen_sphere(1, 30, 20, 0), m;
    adaslice_load_options o;
    adaslice_error e;
    adaslice_result r = ADASLICE_ERR_NOMEM;
    buf b = {0, 0, 0};
    long n;
    memset(&o, 0, sizeof o);
    o.allocator = &failing;
    write_obj(&b, &sphere);
    for (n = 0; r == ADASLICE_ERR_NOMEM; n++) {
        allocs_left = n;
        live_blocks = 0;
        r = adaslice_mesh_load(b.p, b.n, &o, &m, &e);
        CHECKF(r == ADASLICE_OK || (r == ADASLICE_ERR_NOMEM && m.vertices == NULL && live_blocks == 0),
               "allocation %ld failing: %s, %ld blocks live", n, e.message, live_blocks);
    }
    CHECKF(n > 3, "only %ld allocations", n); /* the arrays grew a few times */
    adaslice_mesh_free(&m);
    CHECK(live_blocks == 0);
    gen_free(&sphere);
    free(b.p);
}

/* -------------------------------------------------------------- files */

static void file_errors_are_named(void)
{
    adaslice_mesh m;
    adaslice_error e;
    CHECK(adaslice_mesh_load_file("no/such/file.stl", NULL, &m, &e) == ADASLICE_ERR_IO);
    CHECKF(strncmp(e.message, "no/such/file.stl: ", 18) == 0, "%s", e.message);
    /* a text file that is no mesh; the loader's message gets the path in front */
    CHECK(adaslice_mesh_load_file("tests/check.h", NULL, &m, &e) == ADASLICE_ERR_COUNT);
    CHECKF(strncmp(e.message, "tests/check.h: binary STL: header says ", 39) == 0, "%s", e.message);
    CHECK(e.offset == 80);
}

static void bundled_models_load(void)
{
    adaslice_mesh m;
    adaslice_error e;
    adaslice_result r = adaslice_mesh_load_file("examples/models/Spider_ascii.stl", NULL, &m, &e);
    CHECKF(r == ADASLICE_OK, "%s", e.message);
    if (r == ADASLICE_OK) {
        CHECK(m.format == ADASLICE_FORMAT_STL_ASCII);
        CHECKF(m.triangle_count == 1368, "%zu", m.triangle_count);
        adaslice_mesh_free(&m);
    }
    r = adaslice_mesh_load_file("examples/models/hand_closed.obj", NULL, &m, &e);
    CHECKF(r == ADASLICE_OK, "%s", e.message);
    if (r == ADASLICE_OK) {
        CHECK(m.format == ADASLICE_FORMAT_OBJ);
        CHECKF(m.triangle_count == 15982, "%zu", m.triangle_count);
        adaslice_mesh_free(&m);
    }
}

void test_loaders(void)
{
    RUN(binary_stl_round_trips);
    RUN(binary_stl_keeps_its_corners);
    RUN(ascii_stl_round_trips);
    RUN(ascii_stl_polygons_are_fanned);
    RUN(obj_round_trips);
    RUN(obj_polygons_and_statements_load);
    RUN(ply_round_trips);
    RUN(ply_integer_coordinates_load);
    RUN(ply_polygons_are_fanned);
    RUN(ply_triangle_strips_load);
    RUN(ply_binary_triangles_around_a_polygon);
    RUN(scale_multiplies_coordinates);
    RUN(degenerate_triangles_are_kept);
    RUN(free_and_bounds);
    RUN(bounds_are_the_corners);
    RUN(malformed_binary_stl_is_refused);
    RUN(malformed_ascii_stl_is_refused);
    RUN(malformed_obj_is_refused);
    RUN(malformed_ply_is_refused);
    RUN(malformed_ply_headers_are_refused);
    RUN(malformed_ascii_ply_is_refused);
    RUN(formats_are_detected);
    RUN(the_allocator_is_used);
    RUN(running_out_of_memory_leaks_nothing);
    RUN(file_errors_are_named);
    RUN(bundled_models_load);
}
