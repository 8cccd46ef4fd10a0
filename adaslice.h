/* adaslice.h - adaptive slicing for layer-based additive manufacturing.
   Public domain / MIT-0, see the end of the file.

   adaslice.h — adaptive slicing for layer-based additive manufacturing
   (resin SLA/MSLA first), after Mao, Kwok, Chen and Wang, "Adaptive Slicing
   Based on Efficient Profile Analysis". A mesh is turned into a metric
   profile phi(z) — the error density per mm of height — and a dynamic
   program picks the fewest layers whose integrated error each stays within
   eps, with every thickness in [tmin, tmax].

   DO THIS in exactly one C or C++ file:
       #define ADASLICE_IMPLEMENTATION
       #include "adaslice.h"
   and include it without the define anywhere else.

   EXAMPLE (error handling shortened; see examples/plan_model.c)
       adaslice_mesh mesh;  adaslice_profile profile;  adaslice_plan plan;
       adaslice_error err;
       if (adaslice_mesh_load_file("part.stl", NULL, &mesh, &err) ||
           adaslice_profile_exact(&mesh, NULL, &profile, &err) ||   // cusp, b = 2 um
           adaslice_plan_profile(&profile, NULL, &plan, &err))      // eps 0.065 mm
           fprintf(stderr, "%s\n", err.message);
       for (size_t k = 0; k < plan.layer_count; k++)
           printf("%g %g\n", plan.layers[k].z_bottom, plan.layers[k].thickness);
       adaslice_plan_free(&plan); adaslice_profile_free(&profile); adaslice_mesh_free(&mesh);

   Every options struct may be NULL or zero-initialised: zero means the
   documented default (the paper's: cusp height, b = 0.002 mm, eps = 0.065,
   tmin = 0.05 mm, tmax = 0.15 mm, sharp-change threshold 0.5). Every call
   that can fail returns an adaslice_result and, if you pass one, fills an
   adaslice_error with a one-line message naming the problem (byte offset or
   line, height, value). There is no global state: calls are reentrant.

   PIPELINE AND UNITS
   mesh (mm, build direction +z) -> profile: N = ceil(H/b) bins, bin i is
   [z0 + i*b, z0 + (i+1)*b) -> plan: planes 0 = s0 < ... < sK = N on bin
   boundaries; heights in a plan are mm above the part's bottom z0.

   MESHES  adaslice_mesh_load reads binary and ASCII STL, OBJ (polygons fan-
   triangulated, negative indices) and PLY (ascii, binary little and big
   endian; faces of any size; triangle strips) from memory. Zero-area
   triangles are dropped and counted; NaN/Inf, bad numbers, truncation,
   indices out of range and overflowing counts are errors with distinct codes.
   `scale` converts units (scans are often in metres).

   PROFILES (exact: from the triangles, no sampling)
     cusp       eq. 4-6    phi = max |n_z| * w over triangles meeting the bin;
                           eps in mm
     roughness  eq. 8-10   phi = max w / sin(theta), theta the angle between
                           normal and z, clamped at roughness_max (default
                           1/sin 5 deg = 11.47): flat faces print without steps,
                           and the formula is infinite there; eps in mm
     area       eq. 12-14  phi = |A(i+1) - A(i)| / (b A(i)) * wmax, A at bin
                           centres; one-sided at the top bin; if A(i) = 0 the
                           neighbour's area is the reference; dimensionless eps.
                           Tips (A -> 0) make phi large: that is the metric.
     volume     eq. 17-20  phi = A * wmax (mm^2); a layer's error is
                           b * sum |phi[j] - phi[first]| in mm^3
   A(z) is exact: each triangle's cut is a segment whose endpoints move
   linearly with z, so its Green's-theorem term is quadratic in z; the terms
   are summed per block of 256 bins about the block's first centre. Area and
   volume assume a closed mesh: overlapping shells count twice, open or
   inconsistently wound meshes give signed sums (negative areas read as 0).
   w is an optional per-triangle weight in [0,1] (eq. 21-24); wmax the
   largest weight among triangles meeting the bin.

   PLANS
     optimal   Procedure 1 in O(N) for additive metrics: the feasible
               predecessors of a plane form a window whose ends only move
               up, kept in a monotone queue; O(N w) for volume deviation.
               Among plans with the fewest layers it returns one whose worst
               layer error is smallest: the DP orders states by (layers,
               worst) lexicographically, which is exact because any prefix
               of an optimal plan is itself optimal in that order; within
               the queue's front block the best max(worst, layer error) is
               where the two cross, tracked by a forward-only pointer.
               The DP runs on integers: b*phi is quantised up to units of a
               power of two near 2^-40 of the largest layer error, so a
               plan feasible in units is feasible in mm (volume adds one unit
               per bin unless every value was exact). The §3.3 pre-pass
               forces a plane where |phi[i] - phi[i-1]| > sharp, unless that
               would leave a stretch no layers can fill.
               budget > 0: the smallest eps whose plan has at most that many
               layers (bisection over eps in units).
     greedy    ref. [3]: grow each layer while it stays within eps, starting
               from tmin; where even tmin exceeds eps it takes tmin anyway
               and counts the layer in over_eps (the paper's "stuck" greedy).
     finest, coarsest   uniform tmin or tmax; the top layer holds the rest.
   Infeasible: ADASLICE_ERR_INFEASIBLE with error.z (the lowest height no
   plan gets past) and error.min_eps (the smallest eps that works, 0 if the
   thickness range cannot tile the height at all).

   OPTIONS (define before including the implementation)
     ADASLICE_IMPLEMENTATION  the implementation, in one file
     ADASLICE_STATIC          every function static (private to the file)
     ADASLICE_DEF             the linkage of public functions (overrides the above)
     ADASLICE_MALLOC(size), ADASLICE_FREE(ptr)
                              the default allocator (malloc/free); or pass an
                              adaslice_allocator {alloc, free, user} per call
     ADASLICE_NO_MALLOC       no default allocator: every call needs one
     ADASLICE_ASSERT(x)       internal invariant checks (assert by default)
     ADASLICE_NO_STDIO        leaves out adaslice_mesh_load_file, the only
                              stdio user
   LIMITS  N < 2^31 bins; tmax/b <= 65535 bins per layer; 2^32 - 1 vertices.
*/
#ifndef ADASLICE_H
#define ADASLICE_H

#include <stddef.h>
#include <stdint.h>

#ifndef ADASLICE_DEF
#ifdef ADASLICE_STATIC
#define ADASLICE_DEF static
#else
#define ADASLICE_DEF extern
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define ADASLICE_VERSION "0.1.0"

/* ---------------------------------------------------------------- results */

typedef enum adaslice_result {
    ADASLICE_OK = 0,
    ADASLICE_ERR_ARGUMENT,    /* a parameter is out of range; the message names it */
    ADASLICE_ERR_NOMEM,       /* the allocator returned NULL */
    ADASLICE_ERR_IO,          /* a file could not be read (stdio wrappers only) */
    ADASLICE_ERR_FORMAT,      /* not a mesh we can read: bad magic, header or keyword */
    ADASLICE_ERR_TRUNCATED,   /* the data ends before the header says it should */
    ADASLICE_ERR_COUNT,       /* binary STL: triangle count disagrees with the size */
    ADASLICE_ERR_NUMBER,      /* a number that does not parse */
    ADASLICE_ERR_NONFINITE,   /* a NaN or infinite coordinate (also after scaling) */
    ADASLICE_ERR_INDEX,       /* a face index outside the vertex list */
    ADASLICE_ERR_OVERFLOW,    /* a count whose size would overflow */
    ADASLICE_ERR_EMPTY,       /* no triangles (or none left after dropping degenerate ones) */
    ADASLICE_ERR_UNSUPPORTED, /* well-formed, but a feature we do not read */
    ADASLICE_ERR_INFEASIBLE   /* no plan meets eps, tmin and tmax */
} adaslice_result;

/* Filled by every call that can fail; pass NULL if you only want the code. */
typedef struct adaslice_error {
    adaslice_result result;
    size_t offset;      /* byte offset in the input the problem is at (loaders) */
    size_t line;        /* 1-based line for text formats, 0 for binary */
    double z;           /* ADASLICE_ERR_INFEASIBLE: first height (mm above the part's
                           bottom) that no plan can cover */
    double min_eps;     /* ADASLICE_ERR_INFEASIBLE: smallest eps that is feasible with the
                           same tmin/tmax, or 0 if no eps is (the thickness range itself
                           cannot tile the height) */
    char message[320];  /* one line, no trailing newline */
} adaslice_error;

ADASLICE_DEF const char *adaslice_result_name(adaslice_result r);

/* -------------------------------------------------------------- allocator */

/* Every allocation goes through this. `user` is passed back untouched. A NULL
   allocator pointer means ADASLICE_MALLOC / ADASLICE_FREE (malloc/free unless
   overridden; under ADASLICE_NO_MALLOC there is no default and NULL fails). */
typedef struct adaslice_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} adaslice_allocator;

/* ------------------------------------------------------------------- mesh */

typedef enum adaslice_format {
    ADASLICE_FORMAT_AUTO = 0, /* detect from the content */
    ADASLICE_FORMAT_STL_BINARY,
    ADASLICE_FORMAT_STL_ASCII,
    ADASLICE_FORMAT_OBJ,
    ADASLICE_FORMAT_PLY
} adaslice_format;

typedef struct adaslice_load_options {
    adaslice_format format;              /* 0: detect */
    double scale;                        /* 0: 1; every coordinate is multiplied by it
                                            (scans are often in metres: 1000) */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_load_options;

/* An indexed triangle mesh in millimetres, build direction +z. A mesh you fill
   yourself (pointers to your own arrays, allocator zeroed) needs no free. */
typedef struct adaslice_mesh {
    size_t vertex_count;
    float *vertices;            /* x, y, z per vertex */
    size_t triangle_count;
    uint32_t *triangles;        /* three vertex indices per triangle */
    adaslice_format format;     /* what the loader read */
    size_t degenerate_dropped;  /* zero-area triangles dropped while loading */
    adaslice_allocator allocator;
} adaslice_mesh;

ADASLICE_DEF adaslice_result adaslice_mesh_load(const void *data, size_t size,
                                                const adaslice_load_options *options,
                                                adaslice_mesh *mesh, adaslice_error *error);
ADASLICE_DEF void adaslice_mesh_free(adaslice_mesh *mesh);
/* Lowest and highest corner of the box around the vertices that triangles use. */
ADASLICE_DEF void adaslice_mesh_bounds(const adaslice_mesh *mesh, double lo[3], double hi[3]);

/* ---------------------------------------------------------------- profile */

typedef enum adaslice_metric {
    ADASLICE_METRIC_CUSP = 0,  /* eq. 4-6: max |n_z|, per mm; eps in mm */
    ADASLICE_METRIC_ROUGHNESS, /* eq. 8-10: max 1/sin(theta), clamped; eps in mm */
    ADASLICE_METRIC_AREA,      /* eq. 12-14: |A'(z)| / A(z), per mm; eps dimensionless */
    ADASLICE_METRIC_VOLUME     /* eq. 17-20: A(z) in mm^2; eps in mm^3 (not additive) */
} adaslice_metric;

#define ADASLICE_DEFAULT_BIN 0.002
/* 1/sin(5 degrees): surfaces flatter than 5 degrees count as 5 degrees, since
   1/sin(theta) is infinite on horizontal faces (which print without steps). */
#define ADASLICE_DEFAULT_ROUGHNESS_MAX 11.473713245669855

typedef struct adaslice_profile_options {
    adaslice_metric metric;
    double bin;                          /* b in mm; 0: ADASLICE_DEFAULT_BIN */
    double roughness_max;                /* 0: ADASLICE_DEFAULT_ROUGHNESS_MAX */
    const float *weights;                /* NULL, or one weight in [0,1] per triangle
                                            (eq. 21-24) */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_profile_options;

/* phi[i] belongs to bin i = [z0 + i*bin, z0 + (i+1)*bin). A profile you fill
   yourself (your own phi, allocator zeroed) can be planned and needs no free. */
typedef struct adaslice_profile {
    adaslice_metric metric;
    size_t bin_count;   /* N = ceil(height / bin) */
    double bin;         /* b, mm */
    double z0;          /* lowest z of the mesh, mm */
    double height;      /* H, mm */
    double *phi;        /* N values, all finite and >= 0 */
    double *area;       /* area and volume metrics: A at each bin's centre (mm^2); else NULL */
    adaslice_allocator allocator;
} adaslice_profile;

/* The exact profile, computed from the triangles themselves (no sampling). */
ADASLICE_DEF adaslice_result adaslice_profile_exact(const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *options,
                                                    adaslice_profile *profile,
                                                    adaslice_error *error);
ADASLICE_DEF void adaslice_profile_free(adaslice_profile *profile);

/* ------------------------------------------------------------------- plan */

typedef enum adaslice_method {
    ADASLICE_METHOD_OPTIMAL = 0, /* Procedure 1: fewest layers, then smallest worst error */
    ADASLICE_METHOD_GREEDY,      /* ref. [3]: thickest layer the local profile allows */
    ADASLICE_METHOD_FINEST,      /* uniform tmin */
    ADASLICE_METHOD_COARSEST     /* uniform tmax */
} adaslice_method;

#define ADASLICE_DEFAULT_EPS 0.065
#define ADASLICE_DEFAULT_TMIN 0.05
#define ADASLICE_DEFAULT_TMAX 0.15
#define ADASLICE_DEFAULT_SHARP 0.5
#define ADASLICE_SHARP_OFF (-1.0)

typedef struct adaslice_plan_options {
    adaslice_method method;
    double eps;         /* allowed error per layer; 0: ADASLICE_DEFAULT_EPS */
    double tmin, tmax;  /* layer thickness bounds, mm; 0: the defaults */
    double sharp;       /* §3.3 pre-pass threshold on |phi[i] - phi[i-1]|; 0: default
                           0.5; ADASLICE_SHARP_OFF (any negative value): off.
                           Optimal method only. */
    size_t budget;      /* optimal only; 0: none. Otherwise at most this many layers,
                           and eps is replaced by the smallest eps that allows it */
    const adaslice_allocator *allocator;
} adaslice_plan_options;

typedef struct adaslice_layer {
    double z_bottom, z_top;   /* mm above the part's bottom */
    double thickness;         /* mm */
    double error;             /* the layer's error under the profile's metric */
} adaslice_layer;

typedef struct adaslice_plan {
    size_t layer_count;         /* K */
    adaslice_layer *layers;     /* K layers, bottom first */
    uint32_t *planes;           /* K+1 bin indices: 0 = s0 < s1 < ... < sK = N */
    double eps;                 /* the eps planned for (budget mode: the one found) */
    double worst_error;         /* max layer error */
    double total_error;         /* sum of layer errors */
    size_t over_eps;            /* layers whose error exceeds eps (baselines only) */
    size_t forced_planes;       /* planes set by the sharp-change pre-pass */
    uint32_t bins_min, bins_max;/* ceil(tmin/b), floor(tmax/b) */
    adaslice_allocator allocator;
} adaslice_plan;

ADASLICE_DEF adaslice_result adaslice_plan_profile(const adaslice_profile *profile,
                                                   const adaslice_plan_options *options,
                                                   adaslice_plan *plan, adaslice_error *error);
ADASLICE_DEF void adaslice_plan_free(adaslice_plan *plan);

/* Error of the layer holding bins [first, end) under the profile's metric:
   b * sum phi (additive metrics), b * sum |phi[j] - phi[first]| (volume, eq. 20). */
ADASLICE_DEF double adaslice_layer_error(const adaslice_profile *profile, size_t first, size_t end);

/* ------------------------------------------------------------ stdio helpers */
#ifndef ADASLICE_NO_STDIO
/* Reads a whole file and loads it; errors name the path. */
ADASLICE_DEF adaslice_result adaslice_mesh_load_file(const char *path,
                                                     const adaslice_load_options *options,
                                                     adaslice_mesh *mesh, adaslice_error *error);
#endif

#ifdef __cplusplus
}
#endif
#endif /* ADASLICE_H */

/* ======================================================================== */
/*                              IMPLEMENTATION                              */
/* ======================================================================== */
#ifdef ADASLICE_IMPLEMENTATION
#ifndef ADASLICE_IMPLEMENTATION_DONE
#define ADASLICE_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>
#include <float.h>
#include <limits.h>

#ifndef ADASLICE_ASSERT
#include <assert.h>
#define ADASLICE_ASSERT(x) assert(x)
#endif

#if !defined(ADASLICE_NO_MALLOC) && !defined(ADASLICE_MALLOC)
#include <stdlib.h>
#define ADASLICE_MALLOC(size) malloc(size)
#define ADASLICE_FREE(ptr) free(ptr)
#endif

#ifndef ADASLICE_NO_STDIO
#include <stdio.h>
#endif
#include <stdarg.h>
#include <stdlib.h> /* strtod */

#ifdef __cplusplus
#define ADASLICE__CAST(type, x) static_cast<type>(x)
#else
#define ADASLICE__CAST(type, x) ((type)(x))
#endif

/* ------------------------------------------------------- results, messages */

ADASLICE_DEF const char *adaslice_result_name(adaslice_result r)
{
    switch (r) {
    case ADASLICE_OK: return "ok";
    case ADASLICE_ERR_ARGUMENT: return "invalid argument";
    case ADASLICE_ERR_NOMEM: return "out of memory";
    case ADASLICE_ERR_IO: return "cannot read file";
    case ADASLICE_ERR_FORMAT: return "unrecognised format";
    case ADASLICE_ERR_TRUNCATED: return "truncated data";
    case ADASLICE_ERR_COUNT: return "triangle count disagrees with size";
    case ADASLICE_ERR_NUMBER: return "unparsable number";
    case ADASLICE_ERR_NONFINITE: return "non-finite coordinate";
    case ADASLICE_ERR_INDEX: return "index out of range";
    case ADASLICE_ERR_OVERFLOW: return "size overflow";
    case ADASLICE_ERR_EMPTY: return "empty mesh";
    case ADASLICE_ERR_UNSUPPORTED: return "unsupported feature";
    case ADASLICE_ERR_INFEASIBLE: return "infeasible constraints";
    }
    return "unknown result";
}

/* A small formatter, so messages need no stdio: %s %c %d %u %zu %g (6 significant
   digits) and %%. */
typedef struct adaslice__out { char *buf; size_t cap, len; } adaslice__out;

static void adaslice__putc(adaslice__out *o, char c)
{
    if (o->len + 1 < o->cap) o->buf[o->len] = c;
    o->len++;
}

static void adaslice__puts(adaslice__out *o, const char *s)
{
    while (*s) adaslice__putc(o, *s++);
}

static void adaslice__putu(adaslice__out *o, unsigned long long v)
{
    char tmp[24];
    int n = 0;
    do { tmp[n++] = (char)('0' + (int)(v % 10u)); v /= 10u; } while (v);
    while (n) adaslice__putc(o, tmp[--n]);
}

static void adaslice__putg(adaslice__out *o, double v)
{
    int exp10 = 0, digits, i, point, last;
    char d[8];
    unsigned long long m;
    double scaled;
    if (v != v) { adaslice__puts(o, "nan"); return; }
    if (v < 0) { adaslice__putc(o, '-'); v = -v; }
    if (v > DBL_MAX) { adaslice__puts(o, "inf"); return; }
    if (v == 0) { adaslice__putc(o, '0'); return; }
    /* normalise to [1e5, 1e6) and round to six digits */
    scaled = v;
    while (scaled >= 1e6) { scaled /= 10; exp10++; }
    while (scaled < 1e5) { scaled *= 10; exp10--; }
    m = (unsigned long long)(scaled + 0.5);
    if (m >= 1000000ull) { m /= 10; exp10++; }
    for (i = 5; i >= 0; i--) { d[i] = (char)('0' + (int)(m % 10)); m /= 10; }
    last = 5;
    while (last > 0 && d[last] == '0') last--;
    digits = exp10 + 5; /* decimal exponent of the first digit */
    if (digits < -4 || digits >= 6) {
        adaslice__putc(o, d[0]);
        if (last > 0) { adaslice__putc(o, '.'); for (i = 1; i <= last; i++) adaslice__putc(o, d[i]); }
        adaslice__putc(o, 'e');
        if (digits < 0) { adaslice__putc(o, '-'); digits = -digits; } else adaslice__putc(o, '+');
        if (digits < 10) adaslice__putc(o, '0');
        adaslice__putu(o, (unsigned long long)digits);
        return;
    }
    if (digits < 0) {
        adaslice__puts(o, "0.");
        for (i = -1; i > digits; i--) adaslice__putc(o, '0');
        for (i = 0; i <= last; i++) adaslice__putc(o, d[i]);
        return;
    }
    point = digits;
    for (i = 0; i <= (last > point ? last : point); i++) {
        adaslice__putc(o, i <= 5 ? d[i] : '0');
        if (i == point && i < last) adaslice__putc(o, '.');
    }
}

static void adaslice__vformat(char *buf, size_t cap, const char *fmt, va_list ap)
{
    adaslice__out o;
    o.buf = buf; o.cap = cap; o.len = 0;
    for (; *fmt; fmt++) {
        if (*fmt != '%') { adaslice__putc(&o, *fmt); continue; }
        fmt++;
        switch (*fmt) {
        case 's': { const char *s = va_arg(ap, const char *); adaslice__puts(&o, s ? s : "(null)"); break; }
        case 'c': adaslice__putc(&o, (char)va_arg(ap, int)); break;
        case 'd': {
            int v = va_arg(ap, int);
            if (v < 0) { adaslice__putc(&o, '-'); adaslice__putu(&o, (unsigned long long)(-(long long)v)); }
            else adaslice__putu(&o, (unsigned long long)v);
            break;
        }
        case 'u': adaslice__putu(&o, va_arg(ap, unsigned)); break;
        case 'z': fmt++; adaslice__putu(&o, (unsigned long long)va_arg(ap, size_t)); break; /* %zu */
        case 'g': adaslice__putg(&o, va_arg(ap, double)); break;
        case '%': adaslice__putc(&o, '%'); break;
        default: adaslice__putc(&o, '?'); if (!*fmt) fmt--; break;
        }
    }
    if (cap) buf[o.len < cap ? o.len : cap - 1] = 0;
}

/* Records a failure and returns its code, so callers can `return adaslice__fail(...)`. */
static adaslice_result adaslice__fail(adaslice_error *err, adaslice_result code, size_t offset,
                                      size_t line, const char *fmt, ...)
{
    va_list ap;
    if (err) {
        err->result = code;
        err->offset = offset;
        err->line = line;
        err->z = 0;
        err->min_eps = 0;
        va_start(ap, fmt);
        adaslice__vformat(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

static void adaslice__ok(adaslice_error *err)
{
    if (err) {
        memset(err, 0, sizeof *err);
        err->result = ADASLICE_OK;
    }
}

/* -------------------------------------------------------------- allocation */

#ifndef ADASLICE_NO_MALLOC
static void *adaslice__default_alloc(void *user, size_t size) { (void)user; return ADASLICE_MALLOC(size); }
static void adaslice__default_free(void *user, void *ptr) { (void)user; ADASLICE_FREE(ptr); }
#endif

static adaslice_allocator adaslice__allocator(const adaslice_allocator *a)
{
    adaslice_allocator r;
    if (a && a->alloc && a->free) return *a;
#ifndef ADASLICE_NO_MALLOC
    r.alloc = adaslice__default_alloc;
    r.free = adaslice__default_free;
#else
    r.alloc = NULL;
    r.free = NULL;
#endif
    r.user = NULL;
    return r;
}

/* count * size bytes, or NULL on overflow or exhaustion */
static void *adaslice__alloc(const adaslice_allocator *a, size_t count, size_t size)
{
    if (!a->alloc || (size && count > SIZE_MAX / size)) return NULL;
    return a->alloc(a->user, count && size ? count * size : 1);
}

static void adaslice__free(const adaslice_allocator *a, void *p)
{
    if (p && a->free) a->free(a->user, p);
}

@@LOADERS@@

@@PROFILES@@

@@PLANNER@@

#endif /* ADASLICE_IMPLEMENTATION_DONE */
#endif /* ADASLICE_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under either license, at your choice:
A - MIT No Attribution
Copyright (c) 2026 the adaslice authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
------------------------------------------------------------------------------
*/
