/* ================================================================ profiles */
/* Bins: N = ceil(H / b); bin i covers [z0 + i*b, z0 + (i+1)*b). */

static size_t adaslice__bin_of(double z, double z0, double bin, size_t n)
{
    double f = (z - z0) / bin;
    size_t i;
    if (!(f > 0)) return 0;
    i = f >= (double)n ? n - 1 : (size_t)f;
    return i < n ? i : n - 1;
}

/* Range-maximum updates in O(log N) each on an implicit segment tree of 2N
   nodes, pushed down to the leaves once at the end: a triangle spanning
   thousands of bins costs the same as one spanning two. */
static void adaslice__rmax_update(double *tree, size_t n, size_t first, size_t last, double v)
{
    size_t l = first + n, r = last + n + 1;
    for (; l < r; l >>= 1, r >>= 1) {
        if (l & 1) { if (tree[l] < v) tree[l] = v; l++; }
        if (r & 1) { --r; if (tree[r] < v) tree[r] = v; }
    }
}

static void adaslice__rmax_push(double *tree, size_t n)
{
    size_t i;
    for (i = 1; i < n; i++) {
        if (tree[2 * i] < tree[i]) tree[2 * i] = tree[i];
        if (tree[2 * i + 1] < tree[i]) tree[2 * i + 1] = tree[i];
    }
}

static void adaslice__corner(const adaslice_mesh *m, size_t t, int k, double p[3])
{
    const float *v = m->vertices + 3 * (size_t)m->triangles[3 * t + k];
    p[0] = v[0]; p[1] = v[1]; p[2] = v[2];
}

static void adaslice__normal(const double a[3], const double b[3], const double c[3], double n[3])
{
    double u[3], w[3];
    int k;
    for (k = 0; k < 3; k++) { u[k] = b[k] - a[k]; w[k] = c[k] - a[k]; }
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* Per-triangle value that the max-type profiles take: |n_z| (eq. 4) or
   1/sin(theta) = |n| / |n_xy| clamped at roughness_max (eq. 8), times the weight. */
static double adaslice__facet_value(adaslice_metric metric, const double n[3], double roughness_max)
{
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double xy = sqrt(n[0] * n[0] + n[1] * n[1]);
    if (metric == ADASLICE_METRIC_CUSP) return fabs(n[2]) / len;
    if (xy * roughness_max <= len) return roughness_max;
    return len / xy;
}

/* Piece of a triangle's cut between heights za and zb: the directed segment
   from P(z) to Q(z), both linear in z, contributes sign * cross(P, Q) / 2 to
   the signed area A(z) (Green's theorem over the cross-section's contour). */
typedef struct adaslice__piece {
    double za, zb;       /* the piece is valid for za <= z < zb */
    double p[2], pd[2];  /* P(z) = p + pd * (z - za) */
    double q[2], qd[2];
    double sign;
} adaslice__piece;

#define ADASLICE__BLOCK 256  /* bins per block of the area accumulator */
#define ADASLICE__DIRECT 8   /* pieces spanning at most this many centres are evaluated directly */

static double adaslice__piece_at(const adaslice__piece *pc, double z, double out_p[2], double out_q[2])
{
    double t = z - pc->za;
    out_p[0] = pc->p[0] + pc->pd[0] * t; out_p[1] = pc->p[1] + pc->pd[1] * t;
    out_q[0] = pc->q[0] + pc->qd[0] * t; out_q[1] = pc->q[1] + pc->qd[1] * t;
    return 0.5 * pc->sign * (out_p[0] * out_q[1] - out_p[1] * out_q[0]);
}

typedef struct adaslice__area_acc {
    size_t n;
    double z0, bin;
    double *direct;      /* n: values added at single centres */
    double *coef;        /* 3 * (n + 1): per-bin differences of the block-local quadratic */
} adaslice__area_acc;

static double adaslice__centre(const adaslice__area_acc *acc, size_t i)
{
    return acc->z0 + ((double)i + 0.5) * acc->bin;
}

/* Adds a piece to every bin whose centre lies in [za, zb). Short pieces are
   evaluated at their few centres; long ones become a quadratic per block,
   expanded about the block's first centre so no term is far from its origin. */
static void adaslice__area_add(adaslice__area_acc *acc, const adaslice__piece *pc)
{
    double f = (pc->za - acc->z0) / acc->bin - 0.5, g = (pc->zb - acc->z0) / acc->bin - 0.5;
    size_t first, end, i, k;
    double P[2], Q[2];
    if (g <= 0 || f >= (double)acc->n) return;
    first = f <= 0 ? 0 : (size_t)ceil(f);
    end = g >= (double)acc->n ? acc->n : (size_t)ceil(g);
    while (first > 0 && adaslice__centre(acc, first - 1) >= pc->za) first--;
    while (first < acc->n && adaslice__centre(acc, first) < pc->za) first++;
    while (end < acc->n && adaslice__centre(acc, end) < pc->zb) end++;
    while (end > first && adaslice__centre(acc, end - 1) >= pc->zb) end--;
    if (end <= first) return;
    if (end - first <= ADASLICE__DIRECT) {
        for (i = first; i < end; i++) acc->direct[i] += adaslice__piece_at(pc, adaslice__centre(acc, i), P, Q);
        return;
    }
    for (i = first; i < end; i = k) {
        size_t block_end = (i / ADASLICE__BLOCK + 1) * ADASLICE__BLOCK;
        double origin = adaslice__centre(acc, (i / ADASLICE__BLOCK) * ADASLICE__BLOCK), c[3];
        double *d = acc->coef + 3 * i;
        k = end < block_end ? end : block_end;
        c[0] = adaslice__piece_at(pc, origin, P, Q);
        c[1] = 0.5 * pc->sign * (P[0] * pc->qd[1] - P[1] * pc->qd[0] + pc->pd[0] * Q[1] - pc->pd[1] * Q[0]);
        c[2] = 0.5 * pc->sign * (pc->pd[0] * pc->qd[1] - pc->pd[1] * pc->qd[0]);
        d[0] += c[0]; d[1] += c[1]; d[2] += c[2];
        if (k < block_end) { /* a block's sums restart at its first bin anyway */
            d = acc->coef + 3 * k;
            d[0] -= c[0]; d[1] -= c[1]; d[2] -= c[2];
        }
    }
}

static void adaslice__area_finish(const adaslice__area_acc *acc, double *area)
{
    size_t i;
    double s0 = 0, s1 = 0, s2 = 0, origin = 0;
    for (i = 0; i < acc->n; i++) {
        double t;
        if (i % ADASLICE__BLOCK == 0) { s0 = s1 = s2 = 0; origin = adaslice__centre(acc, i); }
        s0 += acc->coef[3 * i]; s1 += acc->coef[3 * i + 1]; s2 += acc->coef[3 * i + 2];
        t = adaslice__centre(acc, i) - origin;
        area[i] = acc->direct[i] + s0 + (s1 + s2 * t) * t;
    }
}

/* Cross-section area at every bin centre. x and y are taken about the box
   centre, so terms stay small; the sign is fixed by the mesh's signed volume,
   so an inside-out mesh still gives positive areas. */
static void adaslice__areas(const adaslice_mesh *m, const double lo[3], const double hi[3],
                            adaslice__area_acc *acc, double *area)
{
    double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]), cz = 0.5 * (lo[2] + hi[2]);
    double volume = 0;
    size_t t, i;
    for (t = 0; t < m->triangle_count; t++) {
        double v[3][3], n[3], d[2], s, *p0, *p1, *p2, *tmp;
        adaslice__piece pc;
        int k;
        for (k = 0; k < 3; k++) {
            adaslice__corner(m, t, k, v[k]);
            v[k][0] -= cx; v[k][1] -= cy;
        }
        adaslice__normal(v[0], v[1], v[2], n);
        volume += ((v[0][2] - cz) * (v[1][0] * v[2][1] - v[1][1] * v[2][0]) +
                   (v[1][2] - cz) * (v[2][0] * v[0][1] - v[2][1] * v[0][0]) +
                   (v[2][2] - cz) * (v[0][0] * v[1][1] - v[0][1] * v[1][0])) / 6.0;
        p0 = v[0]; p1 = v[1]; p2 = v[2];
        if (p0[2] > p1[2]) { tmp = p0; p0 = p1; p1 = tmp; }
        if (p1[2] > p2[2]) { tmp = p1; p1 = p2; p2 = tmp; }
        if (p0[2] > p1[2]) { tmp = p0; p0 = p1; p1 = tmp; }
        if (!(p2[2] > p0[2])) continue; /* horizontal: no cut */
        /* The contour runs along z x n; the segment from the long edge
           (p0-p2) towards p1 either does or runs against it. */
        d[0] = -n[1]; d[1] = n[0];
        s = (p1[2] - p0[2]) / (p2[2] - p0[2]);
        s = (p1[0] - (p0[0] + s * (p2[0] - p0[0]))) * d[0] + (p1[1] - (p0[1] + s * (p2[1] - p0[1]))) * d[1];
        if (s == 0) continue; /* the triangle is vertical along its cut: zero-width */
        pc.sign = s > 0 ? 1.0 : -1.0;
        pc.pd[0] = (p2[0] - p0[0]) / (p2[2] - p0[2]);
        pc.pd[1] = (p2[1] - p0[1]) / (p2[2] - p0[2]);
        if (p1[2] > p0[2]) {
            pc.za = p0[2]; pc.zb = p1[2];
            pc.p[0] = p0[0]; pc.p[1] = p0[1];
            pc.q[0] = p0[0]; pc.q[1] = p0[1];
            pc.qd[0] = (p1[0] - p0[0]) / (p1[2] - p0[2]);
            pc.qd[1] = (p1[1] - p0[1]) / (p1[2] - p0[2]);
            adaslice__area_add(acc, &pc);
        }
        if (p2[2] > p1[2]) {
            double u = (p1[2] - p0[2]) / (p2[2] - p0[2]);
            pc.za = p1[2]; pc.zb = p2[2];
            pc.p[0] = p0[0] + u * (p2[0] - p0[0]); pc.p[1] = p0[1] + u * (p2[1] - p0[1]);
            pc.q[0] = p1[0]; pc.q[1] = p1[1];
            pc.qd[0] = (p2[0] - p1[0]) / (p2[2] - p1[2]);
            pc.qd[1] = (p2[1] - p1[1]) / (p2[2] - p1[2]);
            adaslice__area_add(acc, &pc);
        }
    }
    adaslice__area_finish(acc, area);
    for (i = 0; i < acc->n; i++) {
        if (volume < 0) area[i] = -area[i];
        if (area[i] < 0) area[i] = 0; /* open or badly wound meshes: see the manual */
    }
}

/* eq. 14 with one-sided differences at the top bin; where A(i) is zero the
   neighbour's area is the reference, and where both are zero phi is zero. */
static double adaslice__area_deviation(const double *area, size_t n, size_t i, double bin)
{
    size_t j = i + 1 < n ? i + 1 : (i > 0 ? i - 1 : i);
    double ref = area[i] > 0 ? area[i] : area[j];
    if (!(ref > 0)) return 0;
    return fabs(area[j] - area[i]) / (bin * ref);
}

ADASLICE_DEF adaslice_result adaslice_profile_exact(const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *options,
                                                    adaslice_profile *profile, adaslice_error *err)
{
    adaslice_profile_options opt;
    adaslice_allocator al;
    adaslice__area_acc acc;
    double lo[3], hi[3], bins, *tree = NULL;
    size_t n, t, i;
    int max_type, weighted;

    if (!profile) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: no output given");
    memset(profile, 0, sizeof *profile);
    if (!mesh || !mesh->triangle_count || !mesh->vertices || !mesh->triangles)
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "profile: the mesh has no triangles");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if (opt.bin == 0) opt.bin = ADASLICE_DEFAULT_BIN;
    if (opt.roughness_max == 0) opt.roughness_max = ADASLICE_DEFAULT_ROUGHNESS_MAX;
    if (!(opt.bin > 0) || opt.bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: bin size %g is not a positive number", opt.bin);
    if (!(opt.roughness_max >= 1) || opt.roughness_max > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: roughness clamp %g must be at least 1", opt.roughness_max);
    if ((unsigned)opt.metric > ADASLICE_METRIC_VOLUME)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: unknown metric %d", (int)opt.metric);
    if (opt.weights)
        for (t = 0; t < mesh->triangle_count; t++)
            if (!(opt.weights[t] >= 0 && opt.weights[t] <= 1))
                return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                      "profile: weight of triangle %zu is %g, outside [0, 1]", t, (double)opt.weights[t]);
    for (t = 0; t < 3 * mesh->triangle_count; t++)
        if (mesh->triangles[t] >= mesh->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "profile: triangle %zu uses vertex %u of %zu",
                                  t / 3, (unsigned)mesh->triangles[t], mesh->vertex_count);
    adaslice_mesh_bounds(mesh, lo, hi);
    bins = ceil((hi[2] - lo[2]) / opt.bin - 1e-9);
    if (!(hi[2] > lo[2]))
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "profile: the mesh is flat (height 0 along z)");
    if (bins < 1) bins = 1;
    if (bins > 2147483646.0)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "profile: %g bins of %g mm over %g mm is too many",
                              bins, opt.bin, hi[2] - lo[2]);
    n = (size_t)bins;
    al = adaslice__allocator(opt.allocator);
    max_type = opt.metric == ADASLICE_METRIC_CUSP || opt.metric == ADASLICE_METRIC_ROUGHNESS;
    weighted = opt.weights != NULL;
    profile->phi = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
    if (!max_type) profile->area = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
    if (max_type || weighted) tree = ADASLICE__CAST(double *, adaslice__alloc(&al, 2 * n, sizeof(double)));
    memset(&acc, 0, sizeof acc);
    if (!max_type) {
        acc.n = n; acc.z0 = lo[2]; acc.bin = opt.bin;
        acc.direct = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
        acc.coef = ADASLICE__CAST(double *, adaslice__alloc(&al, 3 * (n + 1), sizeof(double)));
    }
    if (!profile->phi || (!max_type && (!profile->area || !acc.direct || !acc.coef)) ||
        ((max_type || weighted) && !tree)) {
        adaslice__free(&al, profile->phi); adaslice__free(&al, profile->area);
        adaslice__free(&al, tree); adaslice__free(&al, acc.direct); adaslice__free(&al, acc.coef);
        memset(profile, 0, sizeof *profile);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for %zu bins", n);
    }
    profile->metric = opt.metric;
    profile->bin_count = n;
    profile->bin = opt.bin;
    profile->z0 = lo[2];
    profile->height = hi[2] - lo[2];
    profile->allocator = al;

    if (tree) {
        /* max-type profiles (eq. 5, 9, 21, 22), or the max weight per bin (eq. 23, 24) */
        memset(tree, 0, 2 * n * sizeof(double));
        for (t = 0; t < mesh->triangle_count; t++) {
            double v[3][3], nrm[3], zmin, zmax, value;
            int k;
            for (k = 0; k < 3; k++) adaslice__corner(mesh, t, k, v[k]);
            adaslice__normal(v[0], v[1], v[2], nrm);
            if (nrm[0] == 0 && nrm[1] == 0 && nrm[2] == 0) continue; /* degenerate: no normal */
            value = max_type ? adaslice__facet_value(opt.metric, nrm, opt.roughness_max) : 1.0;
            if (weighted) value *= opt.weights[t];
            zmin = v[0][2] < v[1][2] ? v[0][2] : v[1][2]; if (v[2][2] < zmin) zmin = v[2][2];
            zmax = v[0][2] > v[1][2] ? v[0][2] : v[1][2]; if (v[2][2] > zmax) zmax = v[2][2];
            adaslice__rmax_update(tree, n, adaslice__bin_of(zmin, lo[2], opt.bin, n),
                                  adaslice__bin_of(zmax, lo[2], opt.bin, n), value);
        }
        adaslice__rmax_push(tree, n);
    }
    if (max_type) {
        memcpy(profile->phi, tree + n, n * sizeof(double));
    } else {
        memset(acc.direct, 0, n * sizeof(double));
        memset(acc.coef, 0, 3 * (n + 1) * sizeof(double));
        adaslice__areas(mesh, lo, hi, &acc, profile->area);
        for (i = 0; i < n; i++) {
            double phi = opt.metric == ADASLICE_METRIC_AREA
                             ? adaslice__area_deviation(profile->area, n, i, opt.bin)
                             : profile->area[i];
            profile->phi[i] = weighted ? phi * tree[n + i] : phi;
        }
    }
    adaslice__free(&al, tree);
    adaslice__free(&al, acc.direct);
    adaslice__free(&al, acc.coef);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_profile_free(adaslice_profile *profile)
{
    if (!profile) return;
    adaslice__free(&profile->allocator, profile->phi);
    adaslice__free(&profile->allocator, profile->area);
    memset(profile, 0, sizeof *profile);
}
