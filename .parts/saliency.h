/* adaslice.h part (issue 5): welding within a tolerance, mean curvature, mesh
   saliency and the curvature planner.

   The block under `#if 0` goes into the public declarations, after
   adaslice_mesh_weld (see .parts/hooks.md for the exact places); the rest
   goes into the implementation after the contours section, where
   adaslice__mix, adaslice__table_size, adaslice__float_bits,
   adaslice__same_vertex, ADASLICE__NONE, adaslice__tileable and
   adaslice__plan_fill are already defined. */
#if 0
/* ---------------------------------------------------- curvature and saliency */

/* adaslice_mesh_weld with a tolerance: in vertex order, each vertex merges into
   the first kept vertex (lowest index) within `tolerance` mm, found through a
   hash grid of cells `tolerance` wide, or is kept itself; 0 merges equal
   coordinates only, as adaslice_mesh_weld does. Merging is not transitive: a
   vertex near a merged one but farther than `tolerance` from its
   representative stays. In place, nothing reallocated; triangles keep their
   count and order (so per-triangle data stays aligned), and one whose corners
   merge keeps the repeated index and zero area, which every stage skips. */
ADASLICE_DEF adaslice_result adaslice_mesh_weld_within(adaslice_mesh *mesh, double tolerance, adaslice_error *error);

/* |H| per vertex, 1/mm: half the length of the cotangent Laplacian of the
   position over the mixed Voronoi area (Meyer, Desbrun, Schroeder and Barr
   2003), so a sphere of radius R gives 1/R and a plane 0. Needs shared
   vertices (weld first). Zero-area triangles are skipped. A vertex on an edge
   that has not exactly two triangles (a border, a non-manifold edge) has an
   incomplete fan, so it takes the mean |H| of its regular neighbours (0 if it
   has none); a vertex in no triangle with area gets 0. */
ADASLICE_DEF adaslice_result adaslice_mean_curvature(const adaslice_mesh *mesh, double *curvature,
                                                     const adaslice_allocator *allocator, adaslice_error *error);

typedef struct adaslice_saliency_options {
    double weld_tolerance;               /* mm, see adaslice_mesh_weld_within; 0: equal
                                            coordinates only */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_saliency_options;

/* Mesh saliency (Lee, Varshney and Jacobs 2005) as one weight in [0,1] per
   triangle, for adaslice_profile_options.weights. The mesh is welded on a
   copy (the caller's is not touched) and |H| taken per vertex as above. With
   eps = 0.3% of the bounding box's diagonal, G(s) at a vertex v is the mean
   of |H| over the vertices within 2s of v weighted by exp(-d^2 / (2 s^2)),
   and for s = 2, 3, 4, 5, 6 eps the map |G(s) - G(2s)| is divided by its
   maximum and multiplied by (1 - m)^2, m the mean of its other local maxima
   (a vertex is one when no vertex within s has a larger value); the maps are
   summed. A triangle's weight is the mean of its corners', divided by the
   largest; all 1 when the mesh has no variation at all.
   Neighbourhoods come from grids, never all pairs: the vertices are pooled
   into cells s/3 wide, each acting as its vertex count at its centroid with
   its mean |H| (the Gaussian's first-order error cancels about a centroid),
   and the cells within 2s are found through a grid of cells s wide. Time and
   memory are linear in the mesh: 200K triangles take well under a second. */
ADASLICE_DEF adaslice_result adaslice_saliency(const adaslice_mesh *mesh, float *face_weight,
                                               const adaslice_saliency_options *options, adaslice_error *error);

/* The curvature-based thickness of the notes (after "Adaptive slicing for FDM
   revisited"): t(z) = tmin + (tmax - tmin) f(k(z) / kmax). */
typedef enum adaslice_mapping {
    ADASLICE_MAPPING_LINEAR = 0, /* f = 1 - min(x, 1) */
    ADASLICE_MAPPING_EXP,        /* f = exp(-alpha x) */
    ADASLICE_MAPPING_STEP        /* f = 1, 2/3, 1/3, 0 for x below 1/4, 1/2, 3/4, and above */
} adaslice_mapping;

#define ADASLICE_DEFAULT_ALPHA 2.0
#define ADASLICE_DEFAULT_KAPPA_PERCENTILE 0.95

typedef struct adaslice_curvature_options {
    adaslice_mapping mapping;
    double tmin, tmax;                   /* mm; 0: the defaults */
    double kappa_max;                    /* 1/mm; 0: the 95th percentile of k over the bins */
    double alpha;                        /* exponential mapping; 0: ADASLICE_DEFAULT_ALPHA */
    double eps;                          /* only counts the layers over it (plan.over_eps);
                                            0: ADASLICE_DEFAULT_EPS */
    double weld_tolerance;               /* adaslice_curvature_profile, as for saliency */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_curvature_options;

/* k per bin of `profile` (its z0, bin and bin_count; the mesh it was made
   from): the area-weighted mean |H| of the surface in the bin, each
   triangle's |H| being its corners' mean and its area spread evenly over the
   bins it meets. A mean over the surface rather than over vertices: vertices
   rarely fall inside a 2 um bin, while every bin the part occupies meets
   triangles, and area weights keep it independent of the tessellation.
   Bins no triangle meets get 0. */
ADASLICE_DEF adaslice_result adaslice_curvature_profile(const adaslice_mesh *mesh, const adaslice_profile *profile,
                                                        const adaslice_curvature_options *options, double *kappa,
                                                        adaslice_error *error);
/* Plans from the bottom up: each layer is t at its first bin, rounded to whole
   bins within tmin..tmax and never leaving a remainder that layers cannot
   fill; then every layer's error is measured on `profile` (the metric profile,
   so the plan compares with the other methods), and plan.over_eps counts those
   above eps. */
ADASLICE_DEF adaslice_result adaslice_plan_curvature(const adaslice_profile *profile, const double *kappa,
                                                     const adaslice_curvature_options *options, adaslice_plan *plan,
                                                     adaslice_error *error);
#endif

/* ============================================= curvature, saliency, welding */

/* ---- welding */

/* Kept vertices sit in a hash table by their cell of the tolerance grid; a slot
   names the cell's most recent kept vertex, and next[] links it to the cell's
   earlier ones. A cell is recognised by recomputing its vertex's cell. */
typedef struct adaslice__weld {
    const float *kept;          /* positions of the kept vertices */
    double inverse;             /* 1 / tolerance */
    double tolerance2;
    uint32_t *slot, *next;
    size_t cap;
} adaslice__weld;

static void adaslice__weld_cell(const adaslice__weld *w, const float *p, int64_t c[3])
{
    int k;
    for (k = 0; k < 3; k++) c[k] = (int64_t)floor((double)p[k] * w->inverse);
}

/* The slot of cell c: the one naming it, or the empty one where it would go. */
static size_t adaslice__weld_slot(const adaslice__weld *w, const int64_t c[3])
{
    uint64_t key = adaslice__mix((uint64_t)c[0] ^ adaslice__mix((uint64_t)c[1] ^ adaslice__mix((uint64_t)c[2])));
    size_t h = (size_t)key & (w->cap - 1);
    while (w->slot[h] != ADASLICE__NONE) {
        int64_t d[3];
        adaslice__weld_cell(w, w->kept + 3 * (size_t)w->slot[h], d);
        if (d[0] == c[0] && d[1] == c[1] && d[2] == c[2]) break;
        h = (h + 1) & (w->cap - 1);
    }
    return h;
}

/* The lowest kept index within the tolerance of p, or NONE. */
static uint32_t adaslice__weld_find(const adaslice__weld *w, const float *p)
{
    uint32_t best = ADASLICE__NONE, k;
    int64_t c[3], d[3];
    int i;
    adaslice__weld_cell(w, p, c);
    for (i = 0; i < 27; i++) {
        d[0] = c[0] + i % 3 - 1; d[1] = c[1] + i / 3 % 3 - 1; d[2] = c[2] + i / 9 - 1;
        for (k = w->slot[adaslice__weld_slot(w, d)]; k != ADASLICE__NONE; k = w->next[k]) {
            const float *q = w->kept + 3 * (size_t)k;
            double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
            if (k < best && dx * dx + dy * dy + dz * dz <= w->tolerance2) best = k;
        }
    }
    return best;
}

/* remap[i] = the index vertex i merges into; the kept vertices are written to
   out in order of first occurrence (out may be v itself: a vertex only ever
   moves down to an index already read). */
static adaslice_result adaslice__weld_map(const float *v, size_t n, double tolerance, const adaslice_allocator *al,
                                          float *out, uint32_t *remap, size_t *kept_count, adaslice_error *err)
{
    adaslice__weld w;
    uint32_t kept = 0;
    size_t i, k;
    double reach = 0;
    if (tolerance > 0) {
        for (i = 0; i < 3 * n; i++) if (fabs((double)v[i]) > reach) reach = fabs((double)v[i]);
        /* cells must be exact integers with room for their neighbours */
        if (reach / tolerance > 4.0e15)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "weld: tolerance %g is too small for coordinates as large as %g (0 welds equal "
                                  "coordinates only)", tolerance, reach);
    }
    memset(&w, 0, sizeof w);
    w.cap = adaslice__table_size(n);
    w.kept = out;
    w.inverse = tolerance > 0 ? 1.0 / tolerance : 0;
    w.tolerance2 = tolerance * tolerance;
    w.slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, w.cap, sizeof(uint32_t)));
    if (tolerance > 0) w.next = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    if (!w.slot || (tolerance > 0 && !w.next)) {
        adaslice__free(al, w.slot);
        adaslice__free(al, w.next);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "weld: out of memory for %zu vertices", n);
    }
    memset(w.slot, 0xff, w.cap * sizeof(uint32_t));
    for (i = 0; i < n; i++) {
        const float *p = v + 3 * i;
        uint32_t to;
        if (tolerance > 0) {
            to = adaslice__weld_find(&w, p);
            if (to == ADASLICE__NONE) {
                int64_t c[3];
                memmove(out + 3 * (size_t)kept, p, 3 * sizeof(float));
                adaslice__weld_cell(&w, out + 3 * (size_t)kept, c);
                k = adaslice__weld_slot(&w, c);
                w.next[kept] = w.slot[k];
                w.slot[k] = to = kept++;
            }
        } else {
            uint64_t key = (uint64_t)adaslice__float_bits(p[0]) << 32 | adaslice__float_bits(p[1]);
            k = (size_t)adaslice__mix(key ^ adaslice__mix(adaslice__float_bits(p[2]) + 1u)) & (w.cap - 1);
            while (w.slot[k] != ADASLICE__NONE && !adaslice__same_vertex(out + 3 * (size_t)w.slot[k], p))
                k = (k + 1) & (w.cap - 1);
            if (w.slot[k] == ADASLICE__NONE) {
                memmove(out + 3 * (size_t)kept, p, 3 * sizeof(float));
                w.slot[k] = kept++;
            }
            to = w.slot[k];
        }
        remap[i] = to;
    }
    adaslice__free(al, w.slot);
    adaslice__free(al, w.next);
    *kept_count = kept;
    return ADASLICE_OK;
}

/* The checks every mesh input here shares; `who` starts the messages. */
static adaslice_result adaslice__mesh_check(const adaslice_mesh *mesh, const char *who, adaslice_error *err)
{
    size_t i;
    if (!mesh || (mesh->vertex_count && !mesh->vertices) || (mesh->triangle_count && !mesh->triangles))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "%s: no mesh given", who);
    if ((uint64_t)mesh->vertex_count >= ADASLICE__NONE)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "%s: %zu vertices is too many", who, mesh->vertex_count);
    for (i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->triangles[i] >= mesh->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "%s: triangle %zu uses vertex %u of %zu", who,
                                  i / 3, (unsigned)mesh->triangles[i], mesh->vertex_count);
    return ADASLICE_OK;
}

static adaslice_result adaslice__tolerance_check(double tolerance, const char *who, adaslice_error *err)
{
    if (!(tolerance >= 0) || tolerance > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "%s: weld tolerance %g is not a finite number >= 0",
                              who, tolerance);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_mesh_weld_within(adaslice_mesh *mesh, double tolerance, adaslice_error *err)
{
    adaslice_allocator al;
    adaslice_result r;
    uint32_t *remap;
    size_t i, kept = 0;
    if ((r = adaslice__mesh_check(mesh, "weld", err)) != ADASLICE_OK ||
        (r = adaslice__tolerance_check(tolerance, "weld", err)) != ADASLICE_OK)
        return r;
    al = adaslice__allocator(&mesh->allocator);
    remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, mesh->vertex_count, sizeof(uint32_t)));
    if (!remap) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "weld: out of memory for %zu vertices", mesh->vertex_count);
    r = adaslice__weld_map(mesh->vertices, mesh->vertex_count, tolerance, &al, mesh->vertices, remap, &kept, err);
    if (r == ADASLICE_OK) {
        for (i = 0; i < 3 * mesh->triangle_count; i++) mesh->triangles[i] = remap[mesh->triangles[i]];
        mesh->vertex_count = kept;
        adaslice__ok(err);
    }
    adaslice__free(&al, remap);
    return r;
}

ADASLICE_DEF adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, adaslice_error *err)
{
    return adaslice_mesh_weld_within(mesh, 0, err);
}

/* ---- mean curvature */

/* LSD radix sort of keys by bytes, carrying a payload each and skipping the
   bytes all keys share; tmp and tmp_payload are scratch. */
static void adaslice__sort_keys(uint64_t *key, uint32_t *payload, uint64_t *tmp, uint32_t *tmp_payload, size_t n)
{
    size_t count[256], i;
    uint64_t *from = key, *to = tmp, *swap;
    uint32_t *pfrom = payload, *pto = tmp_payload, *pswap;
    int shift;
    for (shift = 0; shift < 64; shift += 8) {
        size_t sum = 0;
        memset(count, 0, sizeof count);
        for (i = 0; i < n; i++) count[(from[i] >> shift) & 255]++;
        if (n && count[(from[0] >> shift) & 255] == n) continue;
        for (i = 0; i < 256; i++) { size_t c = count[i]; count[i] = sum; sum += c; }
        for (i = 0; i < n; i++) {
            size_t at = count[(from[i] >> shift) & 255]++;
            to[at] = from[i];
            pto[at] = pfrom[i];
        }
        swap = from; from = to; to = swap;
        pswap = pfrom; pfrom = pto; pto = pswap;
    }
    if (from != key) {
        memcpy(key, from, n * sizeof *key);
        memcpy(payload, pfrom, n * sizeof *payload);
    }
}

/* Twice the area of triangle t and the cotangents of its angles; 0 when it
   has no area (repeated corners included), which callers skip. */
static double adaslice__cotangents(const float *v, const uint32_t *t, double cot[3])
{
    double e[3][3], n[3], len;
    int k, j;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return 0;
    for (k = 0; k < 3; k++) /* e[k]: the edge opposite corner k, from corner k+1 to k+2 */
        for (j = 0; j < 3; j++)
            e[k][j] = (double)v[3 * (size_t)t[(k + 2) % 3] + j] - v[3 * (size_t)t[(k + 1) % 3] + j];
    n[0] = e[1][1] * e[2][2] - e[1][2] * e[2][1];
    n[1] = e[1][2] * e[2][0] - e[1][0] * e[2][2];
    n[2] = e[1][0] * e[2][1] - e[1][1] * e[2][0];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) return 0;
    for (k = 0; k < 3; k++) { /* the angle at k lies between e[k+2] and -e[k+1] */
        const double *a = e[(k + 2) % 3], *b = e[(k + 1) % 3];
        cot[k] = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / len;
    }
    return len;
}

/* |H| per vertex into H and the mixed area into area (both nv long); see
   adaslice_mean_curvature. */
static adaslice_result adaslice__curvature(const float *v, size_t nv, const uint32_t *tri, size_t nt,
                                           const adaslice_allocator *al, double *H, double *area, adaslice_error *err)
{
    double *lap = ADASLICE__CAST(double *, adaslice__alloc(al, nv, 3 * sizeof(double)));
    uint64_t *keys = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, nt, 6 * sizeof(uint64_t)));
    uint32_t *third = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, nt, 6 * sizeof(uint32_t)));
    unsigned char *irregular = ADASLICE__CAST(unsigned char *, adaslice__alloc(al, nv, 1));
    size_t t, i, j, edges = 0;
    int k;
    if (!lap || !keys || !third || !irregular) {
        adaslice__free(al, lap);
        adaslice__free(al, keys);
        adaslice__free(al, third);
        adaslice__free(al, irregular);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "curvature: out of memory for %zu triangles", nt);
    }
    memset(lap, 0, nv * 3 * sizeof(double));
    memset(area, 0, nv * sizeof(double));
    memset(irregular, 0, nv);
    for (t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        double cot[3], twice = adaslice__cotangents(v, c, cot), l2[3];
        int obtuse = -1;
        if (twice == 0) continue;
        for (k = 0; k < 3; k++) { /* edge k joins corners k+1 and k+2 */
            uint32_t a = c[(k + 1) % 3], b = c[(k + 2) % 3];
            const float *p = v + 3 * (size_t)a, *q = v + 3 * (size_t)b;
            l2[k] = 0;
            for (j = 0; j < 3; j++) {
                double d = (double)q[j] - p[j];
                lap[3 * (size_t)a + j] += cot[k] * d;
                lap[3 * (size_t)b + j] -= cot[k] * d;
                l2[k] += d * d;
            }
            if (cot[k] < 0) obtuse = k;
            third[edges] = c[k];
            keys[edges++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
        /* Meyer's mixed area: the Voronoi part where the triangle is not
           obtuse, else half its area to the obtuse corner, a quarter to each other */
        for (k = 0; k < 3; k++) {
            double share = obtuse < 0 ? (l2[(k + 1) % 3] * cot[(k + 1) % 3] + l2[(k + 2) % 3] * cot[(k + 2) % 3]) / 8
                         : twice / (obtuse == k ? 4 : 8);
            area[c[k]] += share;
        }
    }
    /* a full fan needs every edge between exactly two triangles that are not
       the same one twice (scans have two-sided flaps of duplicate faces) */
    adaslice__sort_keys(keys, third, keys + 3 * nt, third + 3 * nt, edges);
    for (i = 0; i < edges; i = j) {
        for (j = i + 1; j < edges && keys[j] == keys[i]; j++) {}
        if (j - i != 2 || third[i] == third[i + 1]) irregular[keys[i] >> 32] = irregular[keys[i] & 0xffffffffu] = 1;
    }
    for (i = 0; i < nv; i++) {
        const double *d = lap + 3 * i;
        H[i] = area[i] > 0 && !irregular[i] ? sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (4 * area[i]) : 0;
    }
    /* an incomplete fan takes its regular neighbours' mean: lap holds sum, count */
    memset(lap, 0, nv * 3 * sizeof(double));
    for (t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        double cot[3];
        if (adaslice__cotangents(v, c, cot) == 0) continue;
        for (k = 0; k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3];
            if (irregular[a] && !irregular[b]) { lap[3 * (size_t)a] += H[b]; lap[3 * (size_t)a + 1] += 1; }
            if (irregular[b] && !irregular[a]) { lap[3 * (size_t)b] += H[a]; lap[3 * (size_t)b + 1] += 1; }
        }
    }
    for (i = 0; i < nv; i++)
        if (irregular[i] && lap[3 * i + 1] > 0) H[i] = lap[3 * i] / lap[3 * i + 1];
    adaslice__free(al, lap);
    adaslice__free(al, keys);
    adaslice__free(al, third);
    adaslice__free(al, irregular);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_mean_curvature(const adaslice_mesh *mesh, double *curvature,
                                                     const adaslice_allocator *allocator, adaslice_error *err)
{
    adaslice_allocator al = adaslice__allocator(allocator);
    adaslice_result r;
    double *area;
    if ((r = adaslice__mesh_check(mesh, "curvature", err)) != ADASLICE_OK) return r;
    if (!curvature) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: no output given");
    area = ADASLICE__CAST(double *, adaslice__alloc(&al, mesh->vertex_count, sizeof(double)));
    if (!area) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "curvature: out of memory for %zu vertices", mesh->vertex_count);
    r = adaslice__curvature(mesh->vertices, mesh->vertex_count, mesh->triangles, mesh->triangle_count, &al, curvature,
                            area, err);
    adaslice__free(&al, area);
    if (r == ADASLICE_OK) adaslice__ok(err);
    return r;
}

/* A mesh welded on a copy, with |H| and the mixed area per welded vertex;
   t holds the caller's triangles on the welded vertices, in the same order. */
typedef struct adaslice__surface {
    size_t nv, nt;
    float *v;
    uint32_t *t;
    double *H, *area;
} adaslice__surface;

static void adaslice__surface_free(adaslice__surface *s, const adaslice_allocator *al)
{
    adaslice__free(al, s->v);
    adaslice__free(al, s->t);
    adaslice__free(al, s->H);
    adaslice__free(al, s->area);
    memset(s, 0, sizeof *s);
}

static adaslice_result adaslice__surface_make(const adaslice_mesh *mesh, double tolerance, const char *who,
                                              const adaslice_allocator *al, adaslice__surface *s, adaslice_error *err)
{
    uint32_t *remap;
    size_t i, n = mesh->vertex_count;
    adaslice_result r;
    memset(s, 0, sizeof *s);
    s->nt = mesh->triangle_count;
    remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    s->v = ADASLICE__CAST(float *, adaslice__alloc(al, n, 3 * sizeof(float)));
    s->t = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, s->nt, 3 * sizeof(uint32_t)));
    if (!remap || !s->v || !s->t) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu vertices", who, n);
        goto done;
    }
    if ((r = adaslice__weld_map(mesh->vertices, n, tolerance, al, s->v, remap, &s->nv, err)) != ADASLICE_OK) goto done;
    for (i = 0; i < 3 * s->nt; i++) s->t[i] = remap[mesh->triangles[i]];
    s->H = ADASLICE__CAST(double *, adaslice__alloc(al, s->nv, sizeof(double)));
    s->area = ADASLICE__CAST(double *, adaslice__alloc(al, s->nv, sizeof(double)));
    if (!s->H || !s->area) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu vertices", who, s->nv);
        goto done;
    }
    r = adaslice__curvature(s->v, s->nv, s->t, s->nt, al, s->H, s->area, err);
done:
    adaslice__free(al, remap);
    if (r != ADASLICE_OK) adaslice__surface_free(s, al);
    return r;
}

/* ---- saliency */

/* Points bucketed by the cell of a uniform grid: members[first[c] ..
   first[c+1]) are the points of cell c, whose coordinates (21 bits each from
   the grid's origin) are packed in key[c]; a hash table finds a cell by key. */
typedef struct adaslice__cells {
    double origin[3], inverse;
    size_t count, cap;
    uint64_t *key;
    uint32_t *first, *member, *slot;
} adaslice__cells;

#define ADASLICE__CELL_BITS 21

static void adaslice__cells_free(adaslice__cells *g, const adaslice_allocator *al)
{
    adaslice__free(al, g->key);
    adaslice__free(al, g->first);
    adaslice__free(al, g->member);
    adaslice__free(al, g->slot);
    memset(g, 0, sizeof *g);
}

static uint64_t adaslice__cell_key(const adaslice__cells *g, const float *p)
{
    uint64_t key = 0;
    int k;
    for (k = 2; k >= 0; k--) {
        double f = (p[k] - g->origin[k]) * g->inverse;
        key = key << ADASLICE__CELL_BITS | (f > 0 ? (uint64_t)f : 0); /* a centroid may round below the origin */
    }
    return key;
}

/* The cell with this key, or NONE. */
static uint32_t adaslice__cell_find(const adaslice__cells *g, uint64_t key)
{
    size_t h = (size_t)adaslice__mix(key) & (g->cap - 1);
    while (g->slot[h] != ADASLICE__NONE && g->key[g->slot[h]] != key) h = (h + 1) & (g->cap - 1);
    return g->slot[h];
}

/* Cells `size` wide from `origin`, which lies at or below every point; the
   caller keeps the extent under 2^21 cells. Counting sort through the table. */
static adaslice_result adaslice__cells_build(adaslice__cells *g, const float *p, size_t n, const double origin[3],
                                             double size, const adaslice_allocator *al, adaslice_error *err)
{
    uint32_t *cell_of;
    size_t i, c;
    memset(g, 0, sizeof *g);
    memcpy(g->origin, origin, sizeof g->origin);
    g->inverse = 1 / size;
    g->cap = adaslice__table_size(n);
    g->slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, g->cap, sizeof(uint32_t)));
    g->key = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, n, sizeof(uint64_t)));
    g->first = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n + 1, sizeof(uint32_t)));
    g->member = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    cell_of = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    if (!g->slot || !g->key || !g->first || !g->member || !cell_of) {
        adaslice__free(al, cell_of);
        adaslice__cells_free(g, al);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for a grid of %zu points", n);
    }
    memset(g->slot, 0xff, g->cap * sizeof(uint32_t));
    for (i = 0; i < n; i++) {
        uint64_t key = adaslice__cell_key(g, p + 3 * i);
        size_t h = (size_t)adaslice__mix(key) & (g->cap - 1);
        while (g->slot[h] != ADASLICE__NONE && g->key[g->slot[h]] != key) h = (h + 1) & (g->cap - 1);
        if (g->slot[h] == ADASLICE__NONE) {
            g->key[g->count] = key;
            g->first[g->count] = 0;
            g->slot[h] = (uint32_t)g->count++;
        }
        cell_of[i] = g->slot[h];
        g->first[cell_of[i]]++;
    }
    for (c = 0, i = 0; c < g->count; c++) { uint32_t k = g->first[c]; g->first[c] = (uint32_t)i; i += k; }
    g->first[g->count] = (uint32_t)n;
    for (i = 0; i < n; i++) g->member[g->first[cell_of[i]]++] = (uint32_t)i;
    for (c = g->count; c > 0; c--) g->first[c] = g->first[c - 1]; /* the scatter moved each start to the next */
    g->first[0] = 0;
    adaslice__free(al, cell_of);
    return ADASLICE_OK;
}

/* Calls back for every cell of `g` within `reach` cells of the cell packed in
   `key` (a key of a grid with the same origin and cell size). */
#define ADASLICE__CELL_MASK ((1u << ADASLICE__CELL_BITS) - 1)

static size_t adaslice__cells_near(const adaslice__cells *g, uint64_t key, int reach, uint32_t *out)
{
    int64_t c[3], d[3];
    size_t n = 0;
    int k;
    for (k = 0; k < 3; k++) c[k] = (int64_t)(key >> (ADASLICE__CELL_BITS * k) & ADASLICE__CELL_MASK);
    for (d[2] = c[2] - reach; d[2] <= c[2] + reach; d[2]++)
        for (d[1] = c[1] - reach; d[1] <= c[1] + reach; d[1]++)
            for (d[0] = c[0] - reach; d[0] <= c[0] + reach; d[0]++) {
                uint32_t cell;
                if (d[0] < 0 || d[1] < 0 || d[2] < 0 || d[0] > ADASLICE__CELL_MASK || d[1] > ADASLICE__CELL_MASK ||
                    d[2] > ADASLICE__CELL_MASK)
                    continue;
                cell = adaslice__cell_find(g, (uint64_t)d[2] << (2 * ADASLICE__CELL_BITS) |
                                              (uint64_t)d[1] << ADASLICE__CELL_BITS | (uint64_t)d[0]);
                if (cell != ADASLICE__NONE) out[n++] = cell;
            }
    return n;
}

/* The surface's vertices (those in a triangle with area) with their |H|. */
typedef struct adaslice__points {
    size_t n;
    float *p;
    double *H;
    double lo[3];
} adaslice__points;

/* The sums of w n and w h over the candidates (columns x, y, z, h, n of
   `stride` floats; count a multiple of 4), w = exp(-d^2 / (2 sigma^2)) for
   those within 2 sigma of p (r2 = 4 sigma^2, scale = 1 / (2 sigma^2)).
   Branch-free in four lanes, which compilers run as one vector; exp(-t) on
   [0, 2] is e^-1 times the Taylor series of e^s, s = 1 - t, to degree 8:
   within 7e-6 relative. */
static void adaslice__gauss_sums(const float *c, size_t count, size_t stride, const float p[3], float scale,
                                 float r2, double out[2])
{
    float h[4] = {0, 0, 0, 0}, n[4] = {0, 0, 0, 0};
    size_t i;
    int l;
    for (i = 0; i < count; i += 4)
        for (l = 0; l < 4; l++) {
            float dx = c[i + l] - p[0], dy = c[stride + i + l] - p[1], dz = c[2 * stride + i + l] - p[2];
            float d2 = dx * dx + dy * dy + dz * dz, s = 1 - d2 * scale;
            float w = 0.36787944f * (1 + s * (1 + s * (1.0f / 2 + s * (1.0f / 6 + s * (1.0f / 24 + s * (1.0f / 120 +
                      s * (1.0f / 720 + s * (1.0f / 5040 + s * (1.0f / 40320)))))))));
            w = d2 < r2 ? w : 0;
            h[l] += w * c[3 * stride + i + l];
            n[l] += w * c[4 * stride + i + l];
        }
    out[0] = ((double)n[0] + n[1]) + ((double)n[2] + n[3]);
    out[1] = ((double)h[0] + h[1]) + ((double)h[2] + h[3]);
}

/* G(sigma) at every point: the Gaussian-weighted mean |H| within 2 sigma, over
   cells sigma/3 wide pooled at their centroids (see adaslice_saliency). */
static adaslice_result adaslice__gaussian_mean(const adaslice__points *pt, double sigma, double *G,
                                               const adaslice_allocator *al, adaslice_error *err)
{
    adaslice__cells pool, centres, queries;
    float *cp = NULL, *cand = NULL;
    double *csum = NULL, *cn = NULL;
    uint32_t near[125];
    size_t c, q, m, k;
    float r2 = (float)(4 * sigma * sigma), scale = (float)(0.5 / (sigma * sigma));
    adaslice_result r;
    memset(&centres, 0, sizeof centres);
    memset(&queries, 0, sizeof queries);
    if ((r = adaslice__cells_build(&pool, pt->p, pt->n, pt->lo, sigma / 3, al, err)) != ADASLICE_OK) return r;
    m = pool.count;
    cp = ADASLICE__CAST(float *, adaslice__alloc(al, m, 3 * sizeof(float)));
    csum = ADASLICE__CAST(double *, adaslice__alloc(al, m, sizeof(double)));
    cn = ADASLICE__CAST(double *, adaslice__alloc(al, m, sizeof(double)));
    cand = ADASLICE__CAST(float *, adaslice__alloc(al, m + 3, 5 * sizeof(float)));
    if (!cp || !csum || !cn || !cand) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu cells", m);
        goto done;
    }
    for (c = 0; c < m; c++) {
        double s[3] = {0, 0, 0}, h = 0;
        uint32_t a = pool.first[c], b = pool.first[c + 1], j;
        for (j = a; j < b; j++) {
            const float *p = pt->p + 3 * (size_t)pool.member[j];
            s[0] += p[0]; s[1] += p[1]; s[2] += p[2];
            h += pt->H[pool.member[j]];
        }
        for (k = 0; k < 3; k++) cp[3 * c + k] = (float)(s[k] / (b - a));
        csum[c] = h;
        cn[c] = b - a;
    }
    if ((r = adaslice__cells_build(&centres, cp, m, pt->lo, sigma, al, err)) != ADASLICE_OK ||
        (r = adaslice__cells_build(&queries, pt->p, pt->n, pt->lo, sigma, al, err)) != ADASLICE_OK)
        goto done;
    /* a point sees the centres within 2 sigma, all in the 5^3 cells around its own */
    for (q = 0; q < queries.count; q++) {
        size_t cells = adaslice__cells_near(&centres, queries.key[q], 2, near), count = 0;
        float *x = cand, *y = cand + m + 3, *z = cand + 2 * (m + 3), *hs = cand + 3 * (m + 3), *ns = cand + 4 * (m + 3);
        /* the centres of those cells, as columns x, y, z, sum of |H|, count */
        for (k = 0; k < cells; k++) {
            uint32_t j;
            for (j = centres.first[near[k]]; j < centres.first[near[k] + 1]; j++) {
                uint32_t e = centres.member[j];
                x[count] = cp[3 * (size_t)e]; y[count] = cp[3 * (size_t)e + 1]; z[count] = cp[3 * (size_t)e + 2];
                hs[count] = (float)csum[e]; ns[count] = (float)cn[e];
                count++;
            }
        }
        while (count % 4) { /* weightless copies of the first fill the last lanes */
            x[count] = x[0]; y[count] = y[0]; z[count] = z[0]; hs[count] = ns[count] = 0;
            count++;
        }
        for (k = queries.first[q]; k < queries.first[q + 1]; k++) {
            uint32_t v = queries.member[k];
            double sums[2];
            adaslice__gauss_sums(cand, count, m + 3, pt->p + 3 * (size_t)v, scale, r2, sums);
            G[v] = sums[1] / sums[0]; /* the point's own cell is within sigma: the weight is positive */
        }
    }
    r = ADASLICE_OK;
done:
    adaslice__cells_free(&pool, al);
    adaslice__cells_free(&centres, al);
    adaslice__cells_free(&queries, al);
    adaslice__free(al, cp);
    adaslice__free(al, csum);
    adaslice__free(al, cn);
    adaslice__free(al, cand);
    return r;
}

/* Itti's normalisation of one map S (changed in place): S / max, times
   (1 - m)^2 with m the mean of the local maxima other than the global one. A
   point is a local maximum when no point within `radius` has a larger value. */
static adaslice_result adaslice__normalise_map(const adaslice__points *pt, double *S, double radius,
                                               const adaslice_allocator *al, adaslice_error *err)
{
    adaslice__cells g;
    uint32_t near[27];
    size_t i, c, k, top = 0, others = 0;
    double sum = 0, r2 = radius * radius, factor;
    adaslice_result r;
    for (i = 1; i < pt->n; i++) if (S[i] > S[top]) top = i;
    if (!(S[top] > 0)) return ADASLICE_OK; /* a flat map stays 0 */
    if ((r = adaslice__cells_build(&g, pt->p, pt->n, pt->lo, radius, al, err)) != ADASLICE_OK) return r;
    for (c = 0; c < g.count; c++) {
        size_t cells = adaslice__cells_near(&g, g.key[c], 1, near), m;
        for (m = g.first[c]; m < g.first[c + 1]; m++) {
            uint32_t v = g.member[m], j;
            const float *p = pt->p + 3 * (size_t)v;
            int peak = v != top;
            for (k = 0; k < cells && peak; k++)
                for (j = g.first[near[k]]; j < g.first[near[k] + 1] && peak; j++) {
                    const float *o = pt->p + 3 * (size_t)g.member[j];
                    double dx = (double)o[0] - p[0], dy = (double)o[1] - p[1], dz = (double)o[2] - p[2];
                    if (S[g.member[j]] > S[v] && dx * dx + dy * dy + dz * dz <= r2) peak = 0;
                }
            if (peak) { sum += S[v]; others++; }
        }
    }
    adaslice__cells_free(&g, al);
    factor = others ? 1 - sum / (others * S[top]) : 1;
    factor = factor * factor / S[top];
    for (i = 0; i < pt->n; i++) S[i] *= factor;
    return ADASLICE_OK;
}

/* sigma / eps for the G maps; the surround of scale i (sigma = 2..6 eps) is
   map SURROUND[i]. */
static const double adaslice__sigmas[8] = {2, 3, 4, 5, 6, 8, 10, 12};
static const int adaslice__surround[5] = {2, 4, 5, 6, 7};
#define ADASLICE__SALIENCY_EPS 0.003 /* eps: 0.3% of the bounding box's diagonal (Lee et al.) */

/* Saliency per point into out (pt->n long). */
static adaslice_result adaslice__saliency_points(const adaslice__points *pt, double eps, double *out,
                                                 const adaslice_allocator *al, adaslice_error *err)
{
    double *G = ADASLICE__CAST(double *, adaslice__alloc(al, pt->n, 9 * sizeof(double))), *S;
    size_t i;
    int s;
    adaslice_result r = ADASLICE_OK;
    if (!G) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu vertices", pt->n);
    S = G + 8 * pt->n;
    for (s = 0; s < 8 && r == ADASLICE_OK; s++)
        r = adaslice__gaussian_mean(pt, adaslice__sigmas[s] * eps, G + s * pt->n, al, err);
    memset(out, 0, pt->n * sizeof(double));
    for (s = 0; s < 5 && r == ADASLICE_OK; s++) {
        const double *centre = G + s * pt->n, *surround = G + adaslice__surround[s] * pt->n;
        for (i = 0; i < pt->n; i++) S[i] = fabs(centre[i] - surround[i]);
        if ((r = adaslice__normalise_map(pt, S, adaslice__sigmas[s] * eps, al, err)) != ADASLICE_OK) break;
        for (i = 0; i < pt->n; i++) out[i] += S[i];
    }
    adaslice__free(al, G);
    return r;
}

ADASLICE_DEF adaslice_result adaslice_saliency(const adaslice_mesh *mesh, float *face_weight,
                                               const adaslice_saliency_options *options, adaslice_error *err)
{
    adaslice_saliency_options opt;
    adaslice_allocator al;
    adaslice__surface s;
    adaslice__points pt;
    uint32_t *index = NULL;
    double *sal = NULL, hi[3] = {0, 0, 0}, diagonal = 0, top = 0;
    size_t i, t;
    int k;
    adaslice_result r;
    if ((r = adaslice__mesh_check(mesh, "saliency", err)) != ADASLICE_OK) return r;
    if (!face_weight) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "saliency: no output given");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if ((r = adaslice__tolerance_check(opt.weld_tolerance, "saliency", err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(opt.allocator);
    if ((r = adaslice__surface_make(mesh, opt.weld_tolerance, "saliency", &al, &s, err)) != ADASLICE_OK) return r;
    memset(&pt, 0, sizeof pt);
    pt.p = ADASLICE__CAST(float *, adaslice__alloc(&al, s.nv, 3 * sizeof(float)));
    pt.H = ADASLICE__CAST(double *, adaslice__alloc(&al, s.nv, sizeof(double)));
    sal = ADASLICE__CAST(double *, adaslice__alloc(&al, s.nv, sizeof(double)));
    index = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, s.nv, sizeof(uint32_t)));
    if (!pt.p || !pt.H || !sal || !index) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu vertices", s.nv);
        goto done;
    }
    for (i = 0; i < s.nv; i++) {
        index[i] = ADASLICE__NONE;
        if (!(s.area[i] > 0)) continue; /* in no triangle with area: not on the surface */
        for (k = 0; k < 3; k++) {
            double c = s.v[3 * i + k];
            pt.p[3 * pt.n + k] = s.v[3 * i + k];
            if (!pt.n || c < pt.lo[k]) pt.lo[k] = c;
            if (!pt.n || c > hi[k]) hi[k] = c;
        }
        pt.H[pt.n] = s.H[i];
        index[i] = (uint32_t)pt.n++;
    }
    if (!pt.n) {
        r = adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "saliency: the mesh has no triangle with area");
        goto done;
    }
    for (k = 0; k < 3; k++) diagonal += (hi[k] - pt.lo[k]) * (hi[k] - pt.lo[k]);
    diagonal = sqrt(diagonal);
    if (!(diagonal > 0)) { /* a single point cannot vary */
        for (t = 0; t < s.nt; t++) face_weight[t] = 1;
        goto done;
    }
    if ((r = adaslice__saliency_points(&pt, ADASLICE__SALIENCY_EPS * diagonal, sal, &al, err)) != ADASLICE_OK) goto done;
    for (t = 0; t < s.nt; t++) {
        double w = 0;
        for (k = 0; k < 3; k++) {
            uint32_t j = index[s.t[3 * t + k]];
            if (j != ADASLICE__NONE) w += sal[j];
        }
        face_weight[t] = (float)(w / 3);
        if (w / 3 > top) top = w / 3;
    }
    for (t = 0; t < s.nt; t++) face_weight[t] = top > 0 ? (float)(face_weight[t] / top) : 1.0f;
done:
    adaslice__surface_free(&s, &al);
    adaslice__free(&al, pt.p);
    adaslice__free(&al, pt.H);
    adaslice__free(&al, sal);
    adaslice__free(&al, index);
    if (r == ADASLICE_OK) adaslice__ok(err);
    return r;
}

/* ---- the curvature planner */

/* The bin of height z, the top one included. */
static size_t adaslice__kappa_bin(const adaslice_profile *p, double z)
{
    double f = (z - p->z0) / p->bin;
    if (!(f > 0)) return 0;
    return f >= (double)(p->bin_count - 1) ? p->bin_count - 1 : (size_t)f;
}

ADASLICE_DEF adaslice_result adaslice_curvature_profile(const adaslice_mesh *mesh, const adaslice_profile *profile,
                                                        const adaslice_curvature_options *options, double *kappa,
                                                        adaslice_error *err)
{
    adaslice_curvature_options opt;
    adaslice_allocator al;
    adaslice__surface s;
    adaslice_result r;
    double *sum, *weight;
    uint32_t *meets;
    size_t n, t, i;
    if ((r = adaslice__mesh_check(mesh, "curvature", err)) != ADASLICE_OK) return r;
    if (!profile || !profile->bin_count || !(profile->bin > 0))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: the profile has no bins");
    if (!kappa) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: no output given");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if ((r = adaslice__tolerance_check(opt.weld_tolerance, "curvature", err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(opt.allocator);
    n = profile->bin_count;
    sum = ADASLICE__CAST(double *, adaslice__alloc(&al, n + 1, 2 * sizeof(double)));
    meets = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, n + 1, sizeof(uint32_t)));
    if (!sum || !meets) {
        adaslice__free(&al, sum);
        adaslice__free(&al, meets);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "curvature: out of memory for %zu bins", n);
    }
    if ((r = adaslice__surface_make(mesh, opt.weld_tolerance, "curvature", &al, &s, err)) != ADASLICE_OK) {
        adaslice__free(&al, sum);
        adaslice__free(&al, meets);
        return r;
    }
    weight = sum + n + 1;
    memset(sum, 0, 2 * (n + 1) * sizeof(double));
    memset(meets, 0, (n + 1) * sizeof(uint32_t));
    /* per-bin differences of (area x |H|), area and triangle count; the count
       tells empty bins from rounding left in the running sums */
    for (t = 0; t < s.nt; t++) {
        const uint32_t *c = s.t + 3 * t;
        double cot[3], area = adaslice__cotangents(s.v, c, cot) / 2, zmin = HUGE_VAL, zmax = -HUGE_VAL, h = 0;
        size_t first, last;
        int k;
        if (area == 0) continue;
        for (k = 0; k < 3; k++) {
            double z = mesh->vertices[3 * (size_t)mesh->triangles[3 * t + k] + 2];
            if (z < zmin) zmin = z;
            if (z > zmax) zmax = z;
            h += s.H[c[k]] / 3;
        }
        first = adaslice__kappa_bin(profile, zmin);
        last = adaslice__kappa_bin(profile, zmax);
        area /= (double)(last - first + 1);
        sum[first] += area * h; sum[last + 1] -= area * h;
        weight[first] += area; weight[last + 1] -= area;
        meets[first]++; meets[last + 1]--;
    }
    {
        double a = 0, w = 0;
        uint32_t count = 0;
        for (i = 0; i < n; i++) {
            a += sum[i]; w += weight[i]; count += meets[i];
            kappa[i] = count && w > 0 && a > 0 ? a / w : 0;
        }
    }
    adaslice__surface_free(&s, &al);
    adaslice__free(&al, sum);
    adaslice__free(&al, meets);
    adaslice__ok(err);
    return ADASLICE_OK;
}

static int adaslice__by_value(const void *a, const void *b)
{
    double x = *ADASLICE__CAST(const double *, a), y = *ADASLICE__CAST(const double *, b);
    return x < y ? -1 : x > y;
}

/* The share f of tmax - tmin at x = kappa / kappa_max. */
static double adaslice__mapping(adaslice_mapping m, double x, double alpha)
{
    switch (m) {
    case ADASLICE_MAPPING_EXP: return exp(-alpha * x);
    case ADASLICE_MAPPING_STEP: return x < 0.25 ? 1 : x < 0.5 ? 2.0 / 3 : x < 0.75 ? 1.0 / 3 : 0;
    default: return x < 1 ? 1 - x : 0;
    }
}

ADASLICE_DEF adaslice_result adaslice_plan_curvature(const adaslice_profile *p, const double *kappa,
                                                     const adaslice_curvature_options *options, adaslice_plan *plan,
                                                     adaslice_error *err)
{
    adaslice_curvature_options opt;
    adaslice_allocator al;
    adaslice_result r;
    unsigned char *ok = NULL;
    uint32_t *planes = NULL, n, lo, hi, s = 0, count = 0;
    double lo_f, hi_f, kmax;
    size_t i;
    if (!plan) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: no output given");
    memset(plan, 0, sizeof *plan);
    if (!p || !p->phi || !p->bin_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "plan: the profile is empty");
    if (!kappa) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: no curvature given");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if (opt.tmin == 0) opt.tmin = ADASLICE_DEFAULT_TMIN;
    if (opt.tmax == 0) opt.tmax = ADASLICE_DEFAULT_TMAX;
    if (opt.alpha == 0) opt.alpha = ADASLICE_DEFAULT_ALPHA;
    if (opt.eps == 0) opt.eps = ADASLICE_DEFAULT_EPS;
    if (!(p->bin > 0) || p->bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: bin size %g is not a positive number", p->bin);
    if (!(opt.tmin > 0) || !(opt.tmax >= opt.tmin) || opt.tmax > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: tmin %g and tmax %g must be positive with tmin <= tmax",
                              opt.tmin, opt.tmax);
    if (p->bin > opt.tmin * (1 + 1e-9))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: bin size %g mm is larger than tmin %g mm; use a bin of at most tmin", p->bin, opt.tmin);
    if ((unsigned)opt.mapping > ADASLICE_MAPPING_STEP)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: unknown mapping %d", (int)opt.mapping);
    if (!(opt.alpha > 0) || opt.alpha > DBL_MAX || !(opt.kappa_max >= 0) || opt.kappa_max > DBL_MAX ||
        !(opt.eps > 0) || opt.eps > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: alpha %g, kappa_max %g and eps %g must be finite and positive (kappa_max: or 0)",
                              opt.alpha, opt.kappa_max, opt.eps);
    if (p->bin_count > 0x7ffffffeu)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "plan: %zu bins is too many", p->bin_count);
    for (i = 0; i < p->bin_count; i++)
        if (!(kappa[i] >= 0) || kappa[i] > DBL_MAX)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "plan: curvature %g at bin %zu (z = %g mm) is not a finite number >= 0", kappa[i], i,
                                  (double)i * p->bin);
    lo_f = ceil(opt.tmin / p->bin - 1e-9);
    hi_f = floor(opt.tmax / p->bin + 1e-9);
    if (lo_f > hi_f)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: no multiple of the bin size %g mm lies between tmin %g and tmax %g", p->bin, opt.tmin, opt.tmax);
    if (hi_f > 65535)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: tmax / bin = %g bins per layer; at most 65535 are supported", hi_f);
    n = (uint32_t)p->bin_count;
    lo = lo_f < 1 ? 1 : (uint32_t)lo_f;
    hi = (uint32_t)hi_f;
    al = adaslice__allocator(opt.allocator);
    plan->allocator = al;
    plan->bins_min = lo;
    plan->bins_max = hi;
    ok = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)n + 1, 1));
    planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, (size_t)n + 1, sizeof(uint32_t)));
    if (!ok || !planes) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); goto done; }
    adaslice__tileable(ok, n, lo, hi);
    if (!ok[n]) {
        r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0, "plan: %u bins cannot be cut into layers of %u to %u bins",
                           (unsigned)n, (unsigned)lo, (unsigned)hi);
        goto done;
    }
    kmax = opt.kappa_max;
    if (kmax == 0) {
        double *sorted = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
        if (!sorted) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); goto done; }
        memcpy(sorted, kappa, n * sizeof(double));
        qsort(sorted, n, sizeof(double), adaslice__by_value);
        kmax = sorted[(size_t)ceil(ADASLICE_DEFAULT_KAPPA_PERCENTILE * n) - 1];
        adaslice__free(&al, sorted);
    }
    planes[count++] = 0;
    while (s < n) {
        double x = kmax > 0 ? kappa[s] / kmax : 0;
        double tau = opt.tmin + (opt.tmax - opt.tmin) * adaslice__mapping(opt.mapping, x, opt.alpha);
        double bins = floor(tau / p->bin + 0.5);
        uint32_t left = n - s, len = bins < lo ? lo : bins > hi ? hi : (uint32_t)bins, pick;
        if (len > left) len = left;
        /* the nearest length at or below, else above, that leaves a fillable rest */
        pick = len;
        while (pick >= lo && !ok[left - pick]) pick--;
        if (pick < lo) { pick = len; while (!ok[left - pick]) pick++; }
        s += pick;
        planes[count++] = s;
    }
    r = adaslice__plan_fill(p, planes, count, opt.eps, plan, err);
done:
    adaslice__free(&al, ok);
    adaslice__free(&al, planes);
    if (r != ADASLICE_OK) {
        adaslice_plan_free(plan);
        return r;
    }
    adaslice__ok(err);
    return ADASLICE_OK;
}
