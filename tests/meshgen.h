/* Closed-form test solids, built by the tests themselves. Every mesh is closed,
   wound counter-clockwise seen from outside, its lowest point at z = 0 unless a
   base height is given. Free with gen_free(). */
#ifndef ADASLICE_MESHGEN_H
#define ADASLICE_MESHGEN_H
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "../adaslice.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static inline adaslice_mesh gen_alloc(size_t nv, size_t nt)
{
    adaslice_mesh m;
    memset(&m, 0, sizeof m);
    m.vertices = (float *)calloc(nv * 3 + 3, sizeof(float));
    m.triangles = (uint32_t *)calloc(nt * 3 + 3, sizeof(uint32_t));
    if (!m.vertices || !m.triangles) abort();
    return m;
}

static inline void gen_free(adaslice_mesh *m)
{
    free(m->vertices);
    free(m->triangles);
    memset(m, 0, sizeof *m);
}

static inline uint32_t gen_vertex(adaslice_mesh *m, double x, double y, double z)
{
    float *v = m->vertices + 3 * m->vertex_count;
    v[0] = (float)x; v[1] = (float)y; v[2] = (float)z;
    return (uint32_t)m->vertex_count++;
}

static inline void gen_triangle(adaslice_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t = m->triangles + 3 * m->triangle_count++;
    t[0] = a; t[1] = b; t[2] = c;
}

/* UV sphere of radius r centred on (0, 0, base + r): `slices` around, `stacks`
   from pole to pole (ring k at polar angle pi*k/stacks). */
static inline adaslice_mesh gen_sphere(double r, int slices, int stacks, double base)
{
    adaslice_mesh m = gen_alloc((size_t)(slices * (stacks - 1) + 2), (size_t)(2 * slices * (stacks - 1)));
    uint32_t top = gen_vertex(&m, 0, 0, base + 2 * r), bottom;
    int i, k;
    for (k = 1; k < stacks; k++) {
        double th = M_PI * k / stacks;
        for (i = 0; i < slices; i++) {
            double ph = 2 * M_PI * i / slices;
            gen_vertex(&m, r * sin(th) * cos(ph), r * sin(th) * sin(ph), base + r + r * cos(th));
        }
    }
    bottom = gen_vertex(&m, 0, 0, base);
#define GEN_RING(k, i) ((uint32_t)(1 + ((k) - 1) * slices + ((i) % slices)))
    for (i = 0; i < slices; i++) {
        gen_triangle(&m, top, GEN_RING(1, i), GEN_RING(1, i + 1));
        gen_triangle(&m, bottom, GEN_RING(stacks - 1, i + 1), GEN_RING(stacks - 1, i));
        for (k = 1; k < stacks - 1; k++) {
            gen_triangle(&m, GEN_RING(k, i), GEN_RING(k + 1, i), GEN_RING(k + 1, i + 1));
            gen_triangle(&m, GEN_RING(k, i), GEN_RING(k + 1, i + 1), GEN_RING(k, i + 1));
        }
    }
#undef GEN_RING
    return m;
}

/* Right circular cone: base disc of radius r at z = base, apex at base + h. */
static inline adaslice_mesh gen_cone(double r, double h, int slices, double base)
{
    adaslice_mesh m = gen_alloc((size_t)slices + 2, (size_t)(2 * slices));
    uint32_t apex = gen_vertex(&m, 0, 0, base + h), centre = gen_vertex(&m, 0, 0, base);
    int i;
    for (i = 0; i < slices; i++)
        gen_vertex(&m, r * cos(2 * M_PI * i / slices), r * sin(2 * M_PI * i / slices), base);
    for (i = 0; i < slices; i++) {
        uint32_t a = (uint32_t)(2 + i), b = (uint32_t)(2 + (i + 1) % slices);
        gen_triangle(&m, a, b, apex);
        gen_triangle(&m, centre, b, a);
    }
    return m;
}

/* Right circular cylinder of radius r from z = base to base + h, axis x = y = 0. */
static inline adaslice_mesh gen_cylinder(double r, double h, int slices, double base)
{
    adaslice_mesh m = gen_alloc((size_t)(2 * slices + 2), (size_t)(4 * slices));
    uint32_t cb = gen_vertex(&m, 0, 0, base), ct = gen_vertex(&m, 0, 0, base + h);
    int i;
    for (i = 0; i < slices; i++) {
        double c = r * cos(2 * M_PI * i / slices), s = r * sin(2 * M_PI * i / slices);
        gen_vertex(&m, c, s, base);
        gen_vertex(&m, c, s, base + h);
    }
    for (i = 0; i < slices; i++) {
        uint32_t b0 = (uint32_t)(2 + 2 * i), t0 = b0 + 1;
        uint32_t b1 = (uint32_t)(2 + 2 * ((i + 1) % slices)), t1 = b1 + 1;
        gen_triangle(&m, b0, b1, t1);
        gen_triangle(&m, b0, t1, t0);
        gen_triangle(&m, cb, b1, b0);
        gen_triangle(&m, ct, t0, t1);
    }
    return m;
}

/* Axis-aligned box [x0,x1] x [y0,y1] x [z0,z1]. */
static inline adaslice_mesh gen_box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    static const int quads[6][4] = {
        {0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    adaslice_mesh m = gen_alloc(8, 12);
    int i;
    for (i = 0; i < 8; i++)
        gen_vertex(&m, (i & 1) ? x1 : x0, (i & 2) ? y1 : y0, (i & 4) ? z1 : z0);
    for (i = 0; i < 6; i++) {
        gen_triangle(&m, (uint32_t)quads[i][0], (uint32_t)quads[i][1], (uint32_t)quads[i][2]);
        gen_triangle(&m, (uint32_t)quads[i][0], (uint32_t)quads[i][2], (uint32_t)quads[i][3]);
    }
    return m;
}

/* A shallow dome: the cap of a sphere of radius R over a disc of radius a,
   on a cylinder `base` mm tall; `rings` rings of `slices` vertices on the
   cap. The cap's slope is asin(r / R) at radius r. */
static inline adaslice_mesh gen_dome(double a, double R, double base, int rings, int slices)
{
    adaslice_mesh m = gen_alloc((size_t)((rings + 1) * slices + 2), (size_t)((2 * rings + 2) * slices));
    double cap = R - sqrt(R * R - a * a);
    uint32_t top = gen_vertex(&m, 0, 0, base + cap), centre;
    int i, k;
    for (k = 1; k <= rings; k++)
        for (i = 0; i < slices; i++) {
            double r = a * k / rings, ph = 2 * M_PI * i / slices;
            gen_vertex(&m, r * cos(ph), r * sin(ph), base + sqrt(R * R - r * r) - (R - cap));
        }
    for (i = 0; i < slices; i++) gen_vertex(&m, a * cos(2 * M_PI * i / slices), a * sin(2 * M_PI * i / slices), 0);
    centre = gen_vertex(&m, 0, 0, 0);
#define GEN_RING(k, i) ((uint32_t)(1 + ((k) - 1) * slices + ((i) % slices)))
    for (i = 0; i < slices; i++) {
        gen_triangle(&m, top, GEN_RING(1, i), GEN_RING(1, i + 1));
        for (k = 1; k <= rings; k++) { /* ring rings + 1 is the foot of the wall */
            gen_triangle(&m, GEN_RING(k, i), GEN_RING(k + 1, i), GEN_RING(k + 1, i + 1));
            gen_triangle(&m, GEN_RING(k, i), GEN_RING(k + 1, i + 1), GEN_RING(k, i + 1));
        }
        gen_triangle(&m, centre, GEN_RING(rings + 1, i + 1), GEN_RING(rings + 1, i));
    }
#undef GEN_RING
    return m;
}

/* A closed block over [x0,x1] x [y0,y1] from z = 0 up to the height field
   z = f(x, y) > 0, nx x ny quads on top and on the bottom. */
static inline adaslice_mesh gen_heightfield(int nx, int ny, double x0, double y0, double x1, double y1,
                                            double (*f)(double x, double y))
{
    size_t per = (size_t)(nx + 1) * (size_t)(ny + 1);
    adaslice_mesh m = gen_alloc(2 * per, (size_t)(4 * nx * ny + 4 * (nx + ny)));
    int i, j, side;
    for (side = 0; side < 2; side++)
        for (j = 0; j <= ny; j++)
            for (i = 0; i <= nx; i++) {
                double x = x0 + (x1 - x0) * i / nx, y = y0 + (y1 - y0) * j / ny;
                gen_vertex(&m, x, y, side ? 0 : f(x, y));
            }
#define GEN_AT(s, i, j) ((uint32_t)((s) * per + (size_t)(j) * (size_t)(nx + 1) + (size_t)(i)))
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++) {
            gen_triangle(&m, GEN_AT(0, i, j), GEN_AT(0, i + 1, j), GEN_AT(0, i + 1, j + 1));
            gen_triangle(&m, GEN_AT(0, i, j), GEN_AT(0, i + 1, j + 1), GEN_AT(0, i, j + 1));
            gen_triangle(&m, GEN_AT(1, i, j), GEN_AT(1, i + 1, j + 1), GEN_AT(1, i + 1, j));
            gen_triangle(&m, GEN_AT(1, i, j), GEN_AT(1, i, j + 1), GEN_AT(1, i + 1, j + 1));
        }
    for (i = 0; i < nx; i++) { /* the walls at y0 and y1 */
        gen_triangle(&m, GEN_AT(1, i, 0), GEN_AT(1, i + 1, 0), GEN_AT(0, i + 1, 0));
        gen_triangle(&m, GEN_AT(1, i, 0), GEN_AT(0, i + 1, 0), GEN_AT(0, i, 0));
        gen_triangle(&m, GEN_AT(1, i + 1, ny), GEN_AT(1, i, ny), GEN_AT(0, i, ny));
        gen_triangle(&m, GEN_AT(1, i + 1, ny), GEN_AT(0, i, ny), GEN_AT(0, i + 1, ny));
    }
    for (j = 0; j < ny; j++) { /* at x0 and x1 */
        gen_triangle(&m, GEN_AT(1, 0, j + 1), GEN_AT(1, 0, j), GEN_AT(0, 0, j));
        gen_triangle(&m, GEN_AT(1, 0, j + 1), GEN_AT(0, 0, j), GEN_AT(0, 0, j + 1));
        gen_triangle(&m, GEN_AT(1, nx, j), GEN_AT(1, nx, j + 1), GEN_AT(0, nx, j + 1));
        gen_triangle(&m, GEN_AT(1, nx, j), GEN_AT(0, nx, j + 1), GEN_AT(0, nx, j));
    }
#undef GEN_AT
    return m;
}

/* The box [0,10]^3 as a CAD export writes it with a T-junction on top: the
   top's left half ends in the edge A-B (x = 5), its right half meets that line
   at `middles` more points M1..Mk, and zero-area slivers (A, M1, B),
   (M1, M2, B), ... seal the gap, each on the long edge of the one before, the
   first on A-B. Closed and wound outward only through the slivers. */
static inline adaslice_mesh gen_tjunction_box(int middles)
{
    adaslice_mesh m = gen_alloc((size_t)(11 + middles), (size_t)(18 + 2 * middles));
    uint32_t b0 = gen_vertex(&m, 0, 0, 0), b1 = gen_vertex(&m, 10, 0, 0), b2 = gen_vertex(&m, 10, 10, 0),
             b3 = gen_vertex(&m, 0, 10, 0), t0 = gen_vertex(&m, 0, 0, 10), t1 = gen_vertex(&m, 10, 0, 10),
             t2 = gen_vertex(&m, 10, 10, 10), t3 = gen_vertex(&m, 0, 10, 10), a = gen_vertex(&m, 5, 0, 10),
             b = gen_vertex(&m, 5, 10, 10), c = gen_vertex(&m, 8, 5, 10), p[34];
    int i;
    p[0] = a;
    for (i = 1; i <= middles && i < 32; i++) p[i] = gen_vertex(&m, 5, 10.0 * i / (middles + 1), 10);
    p[middles + 1] = b;
    gen_triangle(&m, b0, b2, b1); gen_triangle(&m, b0, b3, b2);             /* bottom */
    gen_triangle(&m, b3, b0, t0); gen_triangle(&m, b3, t0, t3);             /* x = 0 */
    gen_triangle(&m, b1, b2, t2); gen_triangle(&m, b1, t2, t1);             /* x = 10 */
    gen_triangle(&m, b0, b1, t1); gen_triangle(&m, b0, t1, a); gen_triangle(&m, b0, a, t0); /* y = 0 */
    gen_triangle(&m, b2, b3, t3); gen_triangle(&m, b2, t3, b); gen_triangle(&m, b2, b, t2); /* y = 10 */
    gen_triangle(&m, t0, a, b); gen_triangle(&m, t0, b, t3);                /* the top's left half */
    gen_triangle(&m, a, t1, c); gen_triangle(&m, t1, t2, c); gen_triangle(&m, c, t2, b);
    for (i = 0; i <= middles; i++) gen_triangle(&m, p[i], c, p[i + 1]);    /* its right half */
    for (i = 1; i <= middles; i++) gen_triangle(&m, p[i - 1], p[i], b);     /* the slivers */
    return m;
}

/* dst gets src's triangles appended (src is left alone). */
static inline void gen_append(adaslice_mesh *dst, const adaslice_mesh *src)
{
    size_t nv = dst->vertex_count + src->vertex_count, nt = dst->triangle_count + src->triangle_count, i;
    float *v = (float *)realloc(dst->vertices, (nv * 3 + 3) * sizeof(float));
    uint32_t *t = (uint32_t *)realloc(dst->triangles, (nt * 3 + 3) * sizeof(uint32_t));
    if (!v || !t) abort();
    memcpy(v + 3 * dst->vertex_count, src->vertices, src->vertex_count * 3 * sizeof(float));
    for (i = 0; i < src->triangle_count * 3; i++)
        t[3 * dst->triangle_count + i] = src->triangles[i] + (uint32_t)dst->vertex_count;
    dst->vertices = v;
    dst->triangles = t;
    dst->vertex_count = nv;
    dst->triangle_count = nt;
}
#endif
