/* Part for adaslice.h: vertex welding and contours at many heights in one sweep.

   The public declarations sit in the `#if 0` block below (a block rather than a
   comment because they carry comments of their own): paste them before the
   declarations' closing `#ifdef __cplusplus }`. Paste everything after the block
   just before the `#endif` that closes ADASLICE_IMPLEMENTATION_DONE.

   Manual paragraph for the header's top comment:

   CONTOURS  adaslice_contours_slice cuts the mesh at sorted heights (absolute z,
   mm) in one sweep after Minetto et al., "An optimal algorithm for 3D triangle
   mesh slicing": triangles are bucketed by the first height at or above their
   lowest z, the sweep keeps the triangles spanning the current height, and each
   cut is chained to the next through the mesh edge it ends on, so polygons close
   exactly whatever the rounding: O(n log k + k + m) for n triangles, k heights
   and m cuts. A vertex exactly at a height counts as below it: the contour is
   the limit from just above (a box cut at its bottom face gives its full
   section, at its top face nothing), and faces lying in the plane add nothing.
   Loops turn counter-clockwise seen from +z around material and clockwise around
   holes (from the triangles' winding), so their signed areas add up to the
   section's area. Open meshes and inconsistent winding give open polylines.
   Chaining needs shared vertices: STL gives every triangle its own, so call
   adaslice_mesh_weld first. adaslice_contours_winding is the exact nonzero-rule
   winding number of a point (open polylines closed by their chord).
*/
#if 0 /* ======================= PUBLIC DECLARATIONS (paste) ======================= */

/* --------------------------------------------------------------- contours */

/* Merges vertices whose coordinates are equal bit for bit (+0 and -0 count as
   equal), in place: the vertices keep the order of their first occurrence,
   vertex_count shrinks and triangle indices are rewritten; nothing is
   reallocated, so a mesh pointing at your own arrays stays yours. Expected O(n),
   with a temporary table from mesh->allocator (the default one if zeroed). */
ADASLICE_DEF adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, adaslice_error *error);

typedef struct adaslice_contour_options {
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_contour_options;

typedef struct adaslice_polygon {
    size_t first, count;  /* its points: points[2*first .. 2*(first+count)), x then y */
    int closed;           /* 1: a loop, the last point joins the first (never repeated);
                             0: a polyline ending on an open edge of the mesh */
} adaslice_polygon;

typedef struct adaslice_contours {
    size_t height_count;
    double *heights;            /* the heights cut, mm (a copy) */
    size_t *first_polygon;      /* height_count + 1 entries: height i owns polygons
                                   [first_polygon[i], first_polygon[i + 1]) */
    size_t polygon_count;
    adaslice_polygon *polygons;
    size_t point_count;
    double *points;             /* x, y per point, mm */
    size_t segment_count;       /* triangle cuts made: each triangle once per height
                                   in [its lowest z, its highest z) */
    size_t triangle_visits;     /* sweep work: at most segment_count + triangles */
    adaslice_allocator allocator;
} adaslice_contours;

/* Cross-sections at `count` nondecreasing finite heights (absolute z, mm). */
ADASLICE_DEF adaslice_result adaslice_contours_slice(const adaslice_mesh *mesh, const double *heights,
                                                     size_t count, const adaslice_contour_options *options,
                                                     adaslice_contours *contours, adaslice_error *error);
ADASLICE_DEF void adaslice_contours_free(adaslice_contours *contours);
/* Winding number of (x, y) about every polygon at one height, exact for points
   off the edges (a point on an edge goes to one side consistently); open
   polylines count as closed by the chord between their ends. 0 if
   height_index is out of range. */
ADASLICE_DEF int adaslice_contours_winding(const adaslice_contours *contours, size_t height_index,
                                           double x, double y);
/* Distance from (x, y) to the nearest edge at one height, chords of open
   polylines included; HUGE_VAL if there are none. */
ADASLICE_DEF double adaslice_contours_distance(const adaslice_contours *contours, size_t height_index,
                                               double x, double y);

#endif /* ===================== END OF PUBLIC DECLARATIONS ===================== */

/* ================================================================ contours */

#define ADASLICE__NONE 0xffffffffu

/* Murmur3's finaliser: every input bit moves every output bit. */
static uint64_t adaslice__mix(uint64_t h)
{
    h ^= h >> 33; h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull;
    return h ^ (h >> 33);
}

/* A power of two at least 2n (load at most 1/2), and at least 16. */
static size_t adaslice__table_size(size_t n)
{
    size_t c = 16;
    while (c / 2 < n && c <= SIZE_MAX / 4) c *= 2;
    return c;
}

/* The bits of a coordinate with -0 folded onto +0. */
static uint32_t adaslice__float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u == 0x80000000u ? 0 : u;
}

static int adaslice__same_vertex(const float *a, const float *b)
{
    return adaslice__float_bits(a[0]) == adaslice__float_bits(b[0]) &&
           adaslice__float_bits(a[1]) == adaslice__float_bits(b[1]) &&
           adaslice__float_bits(a[2]) == adaslice__float_bits(b[2]);
}

ADASLICE_DEF adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, adaslice_error *err)
{
    adaslice_allocator al;
    uint32_t *slot, *remap, kept = 0;
    size_t n, cap, i;
    if (!mesh || (mesh->vertex_count && !mesh->vertices) || (mesh->triangle_count && !mesh->triangles))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "weld: no mesh given");
    n = mesh->vertex_count;
    if ((uint64_t)n >= ADASLICE__NONE)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "weld: %zu vertices is too many", n);
    for (i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->triangles[i] >= n)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "weld: triangle %zu uses vertex %u of %zu",
                                  i / 3, (unsigned)mesh->triangles[i], n);
    cap = adaslice__table_size(n);
    al = adaslice__allocator(&mesh->allocator);
    slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, cap, sizeof(uint32_t)));
    remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, n, sizeof(uint32_t)));
    if (!slot || !remap) {
        adaslice__free(&al, slot);
        adaslice__free(&al, remap);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "weld: out of memory for %zu vertices", n);
    }
    memset(slot, 0xff, cap * sizeof(uint32_t));
    /* Survivors move down to their new index as they are found; a slot names the
       new index, whose place only ever holds an already visited vertex. */
    for (i = 0; i < n; i++) {
        const float *v = mesh->vertices + 3 * i;
        uint64_t key = (uint64_t)adaslice__float_bits(v[0]) << 32 | adaslice__float_bits(v[1]);
        size_t h = (size_t)adaslice__mix(key ^ adaslice__mix(adaslice__float_bits(v[2]) + 1u)) & (cap - 1);
        while (slot[h] != ADASLICE__NONE && !adaslice__same_vertex(mesh->vertices + 3 * (size_t)slot[h], v))
            h = (h + 1) & (cap - 1);
        if (slot[h] == ADASLICE__NONE) {
            memmove(mesh->vertices + 3 * (size_t)kept, v, 3 * sizeof(float));
            slot[h] = kept++;
        }
        remap[i] = slot[h];
    }
    for (i = 0; i < 3 * mesh->triangle_count; i++) mesh->triangles[i] = remap[mesh->triangles[i]];
    mesh->vertex_count = kept;
    adaslice__free(&al, slot);
    adaslice__free(&al, remap);
    adaslice__ok(err);
    return ADASLICE_OK;
}

/* A cut mesh edge as (its vertex at or below the plane, its vertex above). Both
   triangles sharing the edge name it the same way, so it is the chaining key,
   and its point is interpolated the same way whichever triangle asks. */
typedef struct adaslice__cut { uint32_t below, above; } adaslice__cut;

typedef struct adaslice__segment {
    adaslice__cut from, to;  /* where the triangle's boundary comes down, where it goes up */
    uint32_t next;           /* the segment continuing from `to`, or NONE */
    uint32_t same_from;      /* the next segment filed under the same `from` */
    unsigned char state;     /* ADASLICE__HAS_PREV | ADASLICE__USED */
} adaslice__segment;

#define ADASLICE__HAS_PREV 1
#define ADASLICE__USED 2
#define ADASLICE__NO_KEY (~(uint64_t)0) /* below == above: no edge */

typedef struct adaslice__slot { uint64_t key; uint32_t head; } adaslice__slot;

static uint64_t adaslice__cut_key(adaslice__cut c) { return (uint64_t)c.below << 32 | c.above; }

static adaslice__slot *adaslice__slot_of(adaslice__slot *table, size_t cap, uint64_t key)
{
    size_t i = (size_t)adaslice__mix(key) & (cap - 1);
    while (table[i].key != key && table[i].key != ADASLICE__NO_KEY) i = (i + 1) & (cap - 1);
    return table + i;
}

static void adaslice__cut_point(const adaslice_mesh *m, adaslice__cut c, double h, double xy[2])
{
    const float *a = m->vertices + 3 * (size_t)c.below, *b = m->vertices + 3 * (size_t)c.above;
    double t = (h - a[2]) / ((double)b[2] - a[2]);
    xy[0] = a[0] + t * ((double)b[0] - a[0]);
    xy[1] = a[1] + t * ((double)b[1] - a[1]);
}

static void adaslice__zrange(const adaslice_mesh *m, size_t t, double *lo, double *hi)
{
    const uint32_t *v = m->triangles + 3 * t;
    double a = m->vertices[3 * (size_t)v[0] + 2], b = m->vertices[3 * (size_t)v[1] + 2];
    double c = m->vertices[3 * (size_t)v[2] + 2];
    *lo = a < b ? (a < c ? a : c) : (b < c ? b : c);
    *hi = a > b ? (a > c ? a : c) : (b > c ? b : c);
}

/* The cut of a triangle spanning h (lowest z <= h < highest z). Walking its
   corners in winding order, the walk leaves the side above h once and comes
   back once; the segment runs from the edge where it comes down to the edge
   where it goes up. That is the direction z x n, so a loop turns
   counter-clockwise seen from +z around material. */
static adaslice__segment adaslice__cut_triangle(const adaslice_mesh *m, size_t t, double h)
{
    const uint32_t *v = m->triangles + 3 * t;
    adaslice__segment s;
    int k;
    memset(&s, 0, sizeof s);
    for (k = 0; k < 3; k++) {
        uint32_t a = v[k], b = v[(k + 1) % 3];
        int a_up = m->vertices[3 * (size_t)a + 2] > h, b_up = m->vertices[3 * (size_t)b + 2] > h;
        if (a_up && !b_up) { s.from.below = b; s.from.above = a; }
        if (!a_up && b_up) { s.to.below = a; s.to.above = b; }
    }
    return s;
}

/* Appends a point unless it repeats the last one: a plane through a vertex
   cuts every edge at that vertex in the same place. */
static void adaslice__put_point(adaslice_contours *c, adaslice_polygon *p, const double xy[2])
{
    double *q = c->points + 2 * (p->first + p->count);
    if (p->count && q[-2] == xy[0] && q[-1] == xy[1]) return;
    q[0] = xy[0];
    q[1] = xy[1];
    p->count++;
}

/* Follows `next` from segment i. A loop left with fewer than three distinct
   points (a plane touching a lowest vertex) or a polyline with fewer than two
   has no extent and is dropped. */
static void adaslice__emit(adaslice_contours *c, const adaslice_mesh *m, double h, adaslice__segment *seg,
                           uint32_t i)
{
    adaslice_polygon *p = c->polygons + c->polygon_count;
    uint32_t start = i, last;
    double xy[2];
    const double *q;
    p->first = c->point_count;
    p->count = 0;
    do {
        seg[i].state |= ADASLICE__USED;
        adaslice__cut_point(m, seg[i].from, h, xy);
        adaslice__put_point(c, p, xy);
        last = i;
        i = seg[i].next;
    } while (i != ADASLICE__NONE && !(seg[i].state & ADASLICE__USED));
    p->closed = i == start;
    if (!p->closed) {
        adaslice__cut_point(m, seg[last].to, h, xy);
        adaslice__put_point(c, p, xy);
    }
    q = c->points + 2 * p->first;
    while (p->closed && p->count > 1 && q[2 * p->count - 2] == q[0] && q[2 * p->count - 1] == q[1]) p->count--;
    if (p->count < (p->closed ? 3u : 2u)) return;
    c->point_count += p->count;
    c->polygon_count++;
}

/* Links each segment to one that starts on the edge it ends on, then emits the
   chains: first those with no predecessor (open), then the loops that remain.
   Pairing is one to one, so on a non-manifold edge it picks arbitrarily, which
   changes neither the signed area nor any winding number. */
static adaslice_result adaslice__chain(adaslice_contours *c, size_t *point_cap, size_t *polygon_cap,
                                       const adaslice_mesh *m, double h, adaslice__segment *seg, size_t s,
                                       adaslice__slot *table, adaslice_error *err)
{
    size_t cap = adaslice__table_size(s), i;
    int pass;
    void *p;
    if (c->point_count + 2 * s > *point_cap) {
        p = adaslice__grow(&c->allocator, c->points, c->point_count, point_cap, c->point_count + 2 * s,
                           2 * sizeof(double));
        if (!p) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory at z = %g", h);
        c->points = ADASLICE__CAST(double *, p);
    }
    if (c->polygon_count + s > *polygon_cap) {
        p = adaslice__grow(&c->allocator, c->polygons, c->polygon_count, polygon_cap, c->polygon_count + s,
                           sizeof(adaslice_polygon));
        if (!p) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory at z = %g", h);
        c->polygons = ADASLICE__CAST(adaslice_polygon *, p);
    }
    for (i = 0; i < cap; i++) table[i].key = ADASLICE__NO_KEY;
    for (i = 0; i < s; i++) {
        uint64_t key = adaslice__cut_key(seg[i].from);
        adaslice__slot *e = adaslice__slot_of(table, cap, key);
        if (e->key == ADASLICE__NO_KEY) { e->key = key; e->head = ADASLICE__NONE; }
        seg[i].same_from = e->head;
        e->head = (uint32_t)i;
    }
    for (i = 0; i < s; i++) {
        adaslice__slot *e = adaslice__slot_of(table, cap, adaslice__cut_key(seg[i].to));
        seg[i].next = e->key == ADASLICE__NO_KEY ? ADASLICE__NONE : e->head;
        if (seg[i].next != ADASLICE__NONE) {
            seg[seg[i].next].state |= ADASLICE__HAS_PREV;
            e->head = seg[seg[i].next].same_from;
        }
    }
    for (pass = 0; pass < 2; pass++)
        for (i = 0; i < s; i++)
            if (!(seg[i].state & ADASLICE__USED) && (pass || !(seg[i].state & ADASLICE__HAS_PREV)))
                adaslice__emit(c, m, h, seg, (uint32_t)i);
    return ADASLICE_OK;
}

static size_t adaslice__first_at_or_above(const double *h, size_t n, double z)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (h[mid] < z) lo = mid + 1; else hi = mid;
    }
    return lo;
}

static adaslice_result adaslice__contour_check(const adaslice_mesh *m, const double *heights, size_t count,
                                               adaslice_error *err)
{
    size_t i;
    if (!m || (m->triangle_count && (!m->vertices || !m->triangles)))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: no mesh given");
    if (count && !heights) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: heights is NULL");
    if ((uint64_t)m->triangle_count >= ADASLICE__NONE || (uint64_t)count >= ADASLICE__NONE)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "contours: %zu triangles at %zu heights is too many",
                              m->triangle_count, count);
    for (i = 0; i < count; i++) {
        if (!(fabs(heights[i]) <= DBL_MAX))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: height %zu is %g", i, heights[i]);
        if (i && heights[i] < heights[i - 1])
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "contours: heights must not decrease, but height %zu is %g after %g", i,
                                  heights[i], heights[i - 1]);
    }
    for (i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "contours: triangle %zu uses vertex %u of %zu",
                                  i / 3, (unsigned)m->triangles[i], m->vertex_count);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_contours_slice(const adaslice_mesh *mesh, const double *heights,
                                                     size_t count, const adaslice_contour_options *options,
                                                     adaslice_contours *out, adaslice_error *err)
{
    adaslice_result r;
    size_t n, t, j, *bucket, taken = 0, active_count = 0, point_cap = 0, polygon_cap = 0;
    uint32_t *order, *active;
    adaslice__segment *seg;
    adaslice__slot *table;
    if (!out) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: no output given");
    memset(out, 0, sizeof *out);
    if ((r = adaslice__contour_check(mesh, heights, count, err)) != ADASLICE_OK) return r;
    n = mesh->triangle_count;
    out->allocator = adaslice__allocator(options ? options->allocator : NULL);
    out->height_count = count;
    out->heights = ADASLICE__CAST(double *, adaslice__alloc(&out->allocator, count, sizeof(double)));
    out->first_polygon = ADASLICE__CAST(size_t *, adaslice__alloc(&out->allocator, count + 1, sizeof(size_t)));
    bucket = ADASLICE__CAST(size_t *, adaslice__alloc(&out->allocator, count + 1, sizeof(size_t)));
    order = ADASLICE__CAST(uint32_t *, adaslice__alloc(&out->allocator, n, sizeof(uint32_t)));
    active = ADASLICE__CAST(uint32_t *, adaslice__alloc(&out->allocator, n, sizeof(uint32_t)));
    seg = ADASLICE__CAST(adaslice__segment *, adaslice__alloc(&out->allocator, n, sizeof(adaslice__segment)));
    table = ADASLICE__CAST(adaslice__slot *, adaslice__alloc(&out->allocator, adaslice__table_size(n),
                                                             sizeof(adaslice__slot)));
    r = out->heights && out->first_polygon && bucket && order && active && seg && table
            ? ADASLICE_OK
            : adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory for %zu triangles", n);
    if (r == ADASLICE_OK) {
        if (count) memcpy(out->heights, heights, count * sizeof(double));
        /* Counting sort by the first height at or above the triangle's lowest z;
           `active` holds that height for now. Triangles that span no height
           (flat ones among them) are never touched again. */
        memset(bucket, 0, (count + 1) * sizeof(size_t));
        for (t = 0; t < n; t++) {
            const uint32_t *v = mesh->triangles + 3 * t;
            double lo, hi;
            adaslice__zrange(mesh, t, &lo, &hi);
            j = adaslice__first_at_or_above(heights, count, lo);
            /* a triangle repeating a corner has no area and no proper edges */
            if (j < count && heights[j] < hi && v[0] != v[1] && v[1] != v[2] && v[2] != v[0]) {
                active[t] = (uint32_t)j;
                bucket[j + 1]++;
            } else {
                active[t] = ADASLICE__NONE;
            }
        }
        for (j = 0; j < count; j++) bucket[j + 1] += bucket[j];
        for (t = 0; t < n; t++)
            if (active[t] != ADASLICE__NONE) order[bucket[active[t]]++] = (uint32_t)t;
        /* now bucket[j] is where height j's triangles end in `order` */
        out->first_polygon[0] = 0;
        for (j = 0; j < count && r == ADASLICE_OK; j++) {
            double h = heights[j];
            size_t a, s = 0;
            while (taken < bucket[j]) active[active_count++] = order[taken++];
            for (a = 0; a < active_count; a++) {
                double lo, hi;
                adaslice__zrange(mesh, active[a], &lo, &hi);
                if (hi <= h) continue; /* below this height, so below every later one */
                active[s] = active[a];
                seg[s++] = adaslice__cut_triangle(mesh, active[a], h);
            }
            out->triangle_visits += active_count;
            out->segment_count += s;
            active_count = s;
            r = adaslice__chain(out, &point_cap, &polygon_cap, mesh, h, seg, s, table, err);
            out->first_polygon[j + 1] = out->polygon_count;
        }
    }
    adaslice__free(&out->allocator, bucket);
    adaslice__free(&out->allocator, order);
    adaslice__free(&out->allocator, active);
    adaslice__free(&out->allocator, seg);
    adaslice__free(&out->allocator, table);
    if (r != ADASLICE_OK) adaslice_contours_free(out);
    else adaslice__ok(err);
    return r;
}

ADASLICE_DEF void adaslice_contours_free(adaslice_contours *c)
{
    if (!c) return;
    adaslice__free(&c->allocator, c->heights);
    adaslice__free(&c->allocator, c->first_polygon);
    adaslice__free(&c->allocator, c->polygons);
    adaslice__free(&c->allocator, c->points);
    memset(c, 0, sizeof *c);
}

/* (s, e) with s + e == a + b exactly (Knuth's two-sum). */
static double adaslice__two_sum(double a, double b, double *e)
{
    double s = a + b, bv = s - a, av = s - bv;
    *e = (a - av) + (b - bv);
    return s;
}

/* Exact sign of (bx - ax)(py - ay) - (by - ay)(px - ax): each difference is
   split into two doubles and each product into two by fma, both without error;
   the 16 terms go into a nonoverlapping expansion (Shewchuk's grow-expansion)
   whose largest nonzero component has the sign of the whole. */
static int adaslice__orient_exact(const double a[2], const double b[2], double px, double py)
{
    double d[4][2], term[16], x[17], q, e;
    int i, k, n = 0, len = 0;
    d[0][0] = adaslice__two_sum(b[0], -a[0], &d[0][1]);
    d[1][0] = adaslice__two_sum(py, -a[1], &d[1][1]);
    d[2][0] = adaslice__two_sum(b[1], -a[1], &d[2][1]);
    d[3][0] = adaslice__two_sum(px, -a[0], &d[3][1]);
    for (i = 0; i < 2; i++)
        for (k = 0; k < 2; k++) {
            double p = d[0][i] * d[1][k], r = d[2][i] * d[3][k];
            term[n++] = p;
            term[n++] = fma(d[0][i], d[1][k], -p);
            term[n++] = -r;
            term[n++] = -fma(d[2][i], d[3][k], -r);
        }
    for (i = 0; i < 16; i++) {
        q = term[i];
        for (k = 0; k < len; k++) {
            q = adaslice__two_sum(q, x[k], &e);
            x[k] = e;
        }
        x[len++] = q;
    }
    while (len > 0 && x[len - 1] == 0) len--;
    return len == 0 ? 0 : x[len - 1] > 0 ? 1 : -1;
}

/* Sign of the orientation of p against the edge a -> b. The float value is
   trusted when it exceeds Shewchuk's bound (3 + 16 u) u (|l| + |r|) on its error. */
static int adaslice__orient(const double a[2], const double b[2], double px, double py)
{
    const double u = DBL_EPSILON / 2;
    double l = (b[0] - a[0]) * (py - a[1]), r = (b[1] - a[1]) * (px - a[0]), d = l - r;
    double bound = (3 + 16 * u) * u * (fabs(l) + fabs(r));
    if (d > bound) return 1;
    if (-d > bound) return -1;
    return adaslice__orient_exact(a, b, px, py);
}

ADASLICE_DEF int adaslice_contours_winding(const adaslice_contours *c, size_t height_index, double x, double y)
{
    size_t p, k;
    int w = 0;
    if (!c || height_index >= c->height_count) return 0;
    for (p = c->first_polygon[height_index]; p < c->first_polygon[height_index + 1]; p++) {
        size_t n = c->polygons[p].count;
        const double *b = c->points + 2 * c->polygons[p].first, *a = b + 2 * (n - 1);
        /* an edge counts when it crosses the ray to +x from the point: upward
           with the point on its left, or downward with it on its right; y-ranges
           are half-open, so a ray through a vertex counts it once */
        for (k = 0; k < n; k++, a = b, b += 2) {
            if (a[1] <= y) {
                if (b[1] > y && adaslice__orient(a, b, x, y) > 0) w++;
            } else if (b[1] <= y && adaslice__orient(a, b, x, y) < 0) {
                w--;
            }
        }
    }
    return w;
}

ADASLICE_DEF double adaslice_contours_distance(const adaslice_contours *c, size_t height_index, double x,
                                               double y)
{
    double best = HUGE_VAL;
    size_t p, k;
    if (!c || height_index >= c->height_count) return best;
    for (p = c->first_polygon[height_index]; p < c->first_polygon[height_index + 1]; p++) {
        size_t n = c->polygons[p].count;
        const double *b = c->points + 2 * c->polygons[p].first, *a = b + 2 * (n - 1);
        for (k = 0; k < n; k++, a = b, b += 2) {
            double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy, t = 0, ex, ey;
            if (len2 > 0) t = ((x - a[0]) * dx + (y - a[1]) * dy) / len2;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            ex = a[0] + t * dx - x;
            ey = a[1] + t * dy - y;
            if (ex * ex + ey * ey < best) best = ex * ex + ey * ey;
        }
    }
    return sqrt(best);
}
