/* ================================================================= planner */
/* The optimal plan (§3.3, Procedure 1) runs on integers: each bin's error
   b*phi[i] is quantised to a count of units q, so prefix sums are exact, plans
   do not depend on summation order, and a microcontroller fed the same
   integers makes the same plan. The core is streaming: bins arrive one at a
   time and only the last tmax/b planes are kept, plus one back-pointer per
   plane (the bottom layer's length in bins). */

#define ADASLICE__UNREACHED 0xffffffffu

typedef struct adaslice__dp {
    uint32_t lo, hi;          /* bins per layer: ceil(tmin/b), floor(tmax/b) */
    uint32_t cap;             /* ring size: a power of two above hi, so % is a mask */
    uint64_t eps;             /* allowed error per layer, in units */
    int volume;               /* eq. 20 instead of an additive sum */
    uint64_t slack;           /* volume: units added per bin for rounding */
    uint32_t plane;           /* the last plane decided */
    uint32_t floor;           /* no layer may start below this plane (last forced plane) */
    uint32_t reach;           /* highest plane any plan reaches */
    uint64_t *prefix;         /* [cap] sum of units below the plane (additive) */
    uint64_t *first;          /* [cap] volume: units of the first bin above the plane */
    uint64_t *run;            /* [cap] volume: error of the layer from the plane up to now */
    uint32_t *layers;         /* [cap] fewest layers reaching the plane, or UNREACHED */
    uint64_t *worst;          /* [cap] smallest worst layer error with that many layers */
    uint32_t *queue;          /* [cap] candidate planes, oldest first (a ring) */
    uint32_t head, count;     /* the queue's first slot and length */
    uint32_t scan;            /* queue positions [0, scan) are known to lose on worst error */
    unsigned char *back;      /* (planes + 1) * width bytes */
    uint32_t width;           /* bytes per back-pointer: 1 while hi <= 255, else 2 */
} adaslice__dp;

static uint32_t adaslice__dp_queue_at(const adaslice__dp *dp, uint32_t k)
{
    return dp->queue[(dp->head + k) & (dp->cap - 1)];
}

static void adaslice__dp_set_back(adaslice__dp *dp, uint32_t plane, uint32_t len)
{
    if (dp->width == 1) dp->back[plane] = (unsigned char)len;
    else { dp->back[2 * (size_t)plane] = (unsigned char)(len & 255u); dp->back[2 * (size_t)plane + 1] = (unsigned char)(len >> 8); }
}

static uint32_t adaslice__dp_back(const adaslice__dp *dp, uint32_t plane)
{
    if (dp->width == 1) return dp->back[plane];
    return (uint32_t)dp->back[2 * (size_t)plane] | ((uint32_t)dp->back[2 * (size_t)plane + 1] << 8);
}

/* Layer from plane l to the current plane: its error in units. */
static uint64_t adaslice__dp_sum(const adaslice__dp *dp, uint32_t l)
{
    return dp->prefix[dp->plane & (dp->cap - 1)] - dp->prefix[l & (dp->cap - 1)];
}

static uint64_t adaslice__dp_error(const adaslice__dp *dp, uint32_t l)
{
    return dp->volume ? dp->run[l & (dp->cap - 1)] : adaslice__dp_sum(dp, l);
}

/* (layers, worst) of plane a is at least that of plane b, lexicographically */
static int adaslice__dp_no_better(const adaslice__dp *dp, uint32_t a, uint32_t b)
{
    uint32_t ka = dp->layers[a & (dp->cap - 1)], kb = dp->layers[b & (dp->cap - 1)];
    return ka != kb ? ka > kb : dp->worst[a & (dp->cap - 1)] >= dp->worst[b & (dp->cap - 1)];
}

static void adaslice__dp_start(adaslice__dp *dp)
{
    dp->plane = 0;
    dp->floor = 0;
    dp->reach = 0;
    dp->head = dp->count = dp->scan = 0;
    dp->prefix[0] = 0;
    dp->layers[0] = 0;
    dp->worst[0] = 0;
    adaslice__dp_set_back(dp, 0, 0);
}

/* Additive metrics: the feasible predecessors of plane i are a window of
   planes whose both ends only move up (prefix sums never decrease), so a
   queue ordered by plane with strictly increasing (layers, worst) holds every
   candidate that can still win: a newer plane with no more layers and no
   larger worst error beats an older one for good, its layer being shorter.
   The front block (fewest layers) has worst[] increasing and layer error
   decreasing along the queue, so the best max(worst, error) sits where the two
   cross; `scan` finds that point and only moves forward: O(1) amortised. */
static void adaslice__dp_choose_additive(adaslice__dp *dp, uint32_t *best)
{
    uint32_t i = dp->plane, kf, a, b, pos;
    uint64_t va, vb;
    if (i >= dp->lo) {
        uint32_t l = i - dp->lo;
        if (l >= dp->floor && dp->layers[l & (dp->cap - 1)] != ADASLICE__UNREACHED) {
            while (dp->count && adaslice__dp_no_better(dp, adaslice__dp_queue_at(dp, dp->count - 1), l)) dp->count--;
            if (dp->scan > dp->count) dp->scan = dp->count;
            ADASLICE_ASSERT(dp->count < dp->cap);
            dp->queue[(dp->head + dp->count++) & (dp->cap - 1)] = l;
        }
    }
    while (dp->count) {
        uint32_t f = adaslice__dp_queue_at(dp, 0);
        if (f + dp->hi >= i && f >= dp->floor && adaslice__dp_sum(dp, f) <= dp->eps) break;
        dp->head = (dp->head + 1) & (dp->cap - 1);
        dp->count--;
        if (dp->scan) dp->scan--;
    }
    *best = ADASLICE__UNREACHED;
    if (!dp->count) return;
    kf = dp->layers[adaslice__dp_queue_at(dp, 0) & (dp->cap - 1)];
    while (dp->scan < dp->count) {
        uint32_t l = adaslice__dp_queue_at(dp, dp->scan);
        if (dp->layers[l & (dp->cap - 1)] != kf || dp->worst[l & (dp->cap - 1)] >= adaslice__dp_sum(dp, l)) break;
        dp->scan++;
    }
    pos = dp->scan;
    /* candidate before the crossing: its layer error dominates */
    a = pos > 0 ? adaslice__dp_queue_at(dp, pos - 1) : ADASLICE__UNREACHED;
    va = a != ADASLICE__UNREACHED ? adaslice__dp_sum(dp, a) : UINT64_MAX;
    /* candidate at the crossing: its worst so far dominates */
    b = pos < dp->count ? adaslice__dp_queue_at(dp, pos) : ADASLICE__UNREACHED;
    if (b != ADASLICE__UNREACHED && dp->layers[b & (dp->cap - 1)] != kf) b = ADASLICE__UNREACHED;
    vb = b != ADASLICE__UNREACHED ? dp->worst[b & (dp->cap - 1)] : UINT64_MAX;
    *best = va <= vb ? a : b;
}

/* Volume deviation (eq. 20) is not additive: every plane in the window is
   tried, O(w) per plane. */
static void adaslice__dp_choose_volume(adaslice__dp *dp, uint32_t *best)
{
    uint32_t i = dp->plane, l, start;
    uint32_t best_k = ADASLICE__UNREACHED;
    uint64_t best_w = 0;
    *best = ADASLICE__UNREACHED;
    if (i < dp->lo) return;
    start = i > dp->hi ? i - dp->hi : 0;
    if (start < dp->floor) start = dp->floor;
    for (l = start; l + dp->lo <= i; l++) {
        uint32_t k = dp->layers[l & (dp->cap - 1)];
        uint64_t e = dp->run[l & (dp->cap - 1)], w;
        if (k == ADASLICE__UNREACHED || e > dp->eps) continue;
        w = dp->worst[l & (dp->cap - 1)] > e ? dp->worst[l & (dp->cap - 1)] : e;
        if (k < best_k || (k == best_k && w < best_w)) { best_k = k; best_w = w; *best = l; }
    }
}

/* Feeds the next bin's units; decides the plane on top of it. `forced` makes
   that plane part of every plan (§3.3 sharp changes). */
static void adaslice__dp_push(adaslice__dp *dp, uint64_t units, int forced)
{
    uint32_t i = dp->plane + 1, best;
    uint32_t c = dp->cap;
    dp->plane = i;
    if (dp->volume) {
        uint32_t l = i > dp->hi ? i - dp->hi : 0;
        dp->first[(i - 1) & (c - 1)] = units;
        dp->run[(i - 1) & (c - 1)] = 0;
        for (; l < i; l++) {
            uint64_t f = dp->first[l & (c - 1)];
            dp->run[l & (c - 1)] += (units > f ? units - f : f - units) + dp->slack;
        }
        adaslice__dp_choose_volume(dp, &best);
    } else {
        dp->prefix[i & (c - 1)] = dp->prefix[(i - 1) & (c - 1)] + units;
        adaslice__dp_choose_additive(dp, &best);
    }
    if (best == ADASLICE__UNREACHED) {
        dp->layers[i & (c - 1)] = ADASLICE__UNREACHED;
        dp->worst[i & (c - 1)] = 0;
        adaslice__dp_set_back(dp, i, 0);
    } else {
        uint64_t e = adaslice__dp_error(dp, best);
        dp->layers[i & (c - 1)] = dp->layers[best & (c - 1)] + 1;
        dp->worst[i & (c - 1)] = dp->worst[best & (c - 1)] > e ? dp->worst[best & (c - 1)] : e;
        adaslice__dp_set_back(dp, i, i - best);
        dp->reach = i;
    }
    if (forced) {
        dp->floor = i;
        dp->head = dp->count = dp->scan = 0;
    }
}

/* ------------------------------------------------- the planner on a profile */

typedef struct adaslice__job {
    const adaslice_profile *profile;
    uint32_t n, lo, hi;
    uint64_t *units;          /* per bin */
    int volume;
    uint64_t slack;
    double quantum;           /* mm (or the metric's unit) per unit */
    unsigned char *forced;    /* per plane, or NULL */
    adaslice__dp dp;
} adaslice__job;

static size_t adaslice__ring_bytes(uint32_t cap)
{
    return (size_t)cap * (4 * sizeof(uint64_t) + 2 * sizeof(uint32_t));
}

/* Runs the DP with the given eps in units; returns the layer count or
   ADASLICE__UNREACHED. */
static uint32_t adaslice__job_run(adaslice__job *job, uint64_t eps)
{
    uint32_t i;
    job->dp.eps = eps;
    adaslice__dp_start(&job->dp);
    for (i = 0; i < job->n; i++)
        adaslice__dp_push(&job->dp, job->units[i], job->forced && job->forced[i + 1] && i + 1 < job->n);
    return job->dp.layers[job->n & (job->dp.cap - 1)];
}

/* The smallest eps (units) whose optimal plan has at most max_layers layers
   (UNREACHED: any count), found by bisection since the count never grows
   with eps; UINT64_MAX if none. */
static uint64_t adaslice__job_min_eps(adaslice__job *job, uint32_t max_layers)
{
    uint64_t lo = 0, hi = 0, k;
    uint32_t i;
    /* no layer's error exceeds hi bins of the largest value */
    for (i = 0; i < job->n; i++) if (job->units[i] > hi) hi = job->units[i];
    hi = (hi + job->slack) * job->hi;
    k = adaslice__job_run(job, hi);
    if (k == ADASLICE__UNREACHED || k > max_layers) return UINT64_MAX;
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        k = adaslice__job_run(job, mid);
        if (k != ADASLICE__UNREACHED && k <= max_layers) hi = mid; else lo = mid + 1;
    }
    return lo;
}

/* b * phi[i] as units of a power-of-two quantum chosen so the largest layer
   error is about 2^40 units: additive metrics round up, so a plan feasible in
   units is feasible in millimetres; volume rounds to nearest and, unless all
   values were exact, adds a unit per bin to stay on the safe side. */
static void adaslice__quantise(adaslice__job *job)
{
    const adaslice_profile *p = job->profile;
    double top = 0;
    int ex = 0;
    uint32_t i;
    for (i = 0; i < job->n; i++)
        if (p->phi[i] * p->bin > top) top = p->phi[i] * p->bin;
    if (top > 0) { (void)frexp(top * job->hi, &ex); job->quantum = ldexp(1.0, ex - 40); }
    else job->quantum = 1;
    job->slack = 0;
    for (i = 0; i < job->n; i++) {
        double x = p->phi[i] * p->bin / job->quantum;
        if (job->volume) {
            double r = floor(x + 0.5);
            if (r != x) job->slack = 1;
            job->units[i] = (uint64_t)r;
        } else {
            job->units[i] = (uint64_t)ceil(x);
        }
    }
}

static uint64_t adaslice__eps_units(double eps, double quantum)
{
    double x = eps / quantum;
    return x >= 4.0e18 ? (uint64_t)4000000000000000000ull : (uint64_t)floor(x);
}

ADASLICE_DEF double adaslice_layer_error(const adaslice_profile *p, size_t first, size_t end)
{
    double sum = 0;
    size_t j;
    if (p->metric == ADASLICE_METRIC_VOLUME)
        for (j = first; j < end; j++) sum += fabs(p->phi[j] - p->phi[first]);
    else
        for (j = first; j < end; j++) sum += p->phi[j];
    return sum * p->bin;
}

/* Whether r bins can be cut into layers of lo..hi bins, for every r <= n. */
static void adaslice__tileable(unsigned char *ok, uint32_t n, uint32_t lo, uint32_t hi)
{
    uint32_t r, in_window = 0;
    ok[0] = 1;
    for (r = 1; r <= n; r++) {
        if (r >= lo) in_window += ok[r - lo];
        if (r >= hi + 1) in_window -= ok[r - hi - 1];
        ok[r] = in_window > 0;
    }
}

/* The local greedy of ref. [3]: from each plane, grow the layer while the
   next bin keeps its error within eps; never leave a remainder that layers
   of lo..hi bins cannot fill. Returns the plane count written. */
static uint32_t adaslice__greedy(const adaslice_profile *p, uint32_t n, uint32_t lo, uint32_t hi,
                                 double eps, const unsigned char *ok, uint32_t *planes)
{
    uint32_t s = 0, k = 0;
    planes[k++] = 0;
    while (s < n) {
        uint32_t left = n - s, most = hi < left ? hi : left, len = lo, pick;
        while (len < most && adaslice_layer_error(p, s, s + len + 1) <= eps) len++;
        pick = len;
        while (pick >= lo && !ok[left - pick]) pick--;
        if (pick < lo) { pick = len; while (!ok[left - pick]) pick++; }
        s += pick;
        planes[k++] = s;
    }
    return k;
}

static uint32_t adaslice__uniform(uint32_t n, uint32_t len, uint32_t *planes)
{
    uint32_t k = 0, s = 0;
    planes[k++] = 0;
    while (s < n) { s = n - s > len ? s + len : n; planes[k++] = s; }
    return k;
}

static adaslice_result adaslice__plan_fill(const adaslice_profile *p, const uint32_t *planes, uint32_t count,
                                           double eps, adaslice_plan *plan, adaslice_error *err)
{
    uint32_t k;
    adaslice_allocator *al = &plan->allocator;
    plan->layer_count = count - 1;
    plan->planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, count, sizeof(uint32_t)));
    plan->layers = ADASLICE__CAST(adaslice_layer *, adaslice__alloc(al, count, sizeof(adaslice_layer)));
    if (!plan->planes || !plan->layers)
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory for %u layers", (unsigned)count);
    memcpy(plan->planes, planes, count * sizeof(uint32_t));
    plan->eps = eps;
    plan->worst_error = plan->total_error = 0;
    plan->over_eps = 0;
    for (k = 0; k + 1 < count; k++) {
        adaslice_layer *L = &plan->layers[k];
        L->z_bottom = planes[k] * p->bin;
        L->z_top = planes[k + 1] * p->bin;
        L->thickness = (planes[k + 1] - planes[k]) * p->bin;
        L->error = adaslice_layer_error(p, planes[k], planes[k + 1]);
        plan->total_error += L->error;
        if (L->error > plan->worst_error) plan->worst_error = L->error;
        if (L->error > eps) plan->over_eps++;
    }
    return ADASLICE_OK;
}

/* §3.3 pre-pass: a jump of more than `sharp` between consecutive bins forces
   a plane at the upper bin's bottom. A jump is skipped where a plane there
   would leave a stretch, below it or above it, that no layers of lo..hi bins
   can fill (such as two jumps closer than tmin): the pre-pass never makes a
   plan impossible by thickness alone. */
static uint32_t adaslice__sharp_planes(const adaslice_profile *p, uint32_t n, double sharp,
                                       const unsigned char *ok, unsigned char *forced)
{
    uint32_t i, last = 0, count = 0;
    memset(forced, 0, n + 1);
    for (i = 1; i < n; i++) {
        if (fabs(p->phi[i] - p->phi[i - 1]) > sharp && ok[i - last] && ok[n - i]) {
            forced[i] = 1;
            last = i;
            count++;
        }
    }
    return count;
}

static adaslice_result adaslice__plan_optimal(adaslice__job *job, const adaslice_plan_options *opt,
                                              double eps, adaslice_plan *plan, adaslice_error *err)
{
    const adaslice_profile *p = job->profile;
    uint64_t eps_units;
    uint32_t layers, i, k;
    uint32_t *planes;
    adaslice_result r;
    adaslice__quantise(job);
    if (opt->budget) {
        uint32_t budget = opt->budget > 0xfffffffeu ? 0xfffffffeu : (uint32_t)opt->budget;
        eps_units = adaslice__job_min_eps(job, budget);
        if (eps_units == UINT64_MAX)
            return adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                                  "plan: no plan has %zu layers or fewer: %u bins need at least %u layers of at most %g mm",
                                  opt->budget, (unsigned)job->n, (unsigned)((job->n + job->hi - 1) / job->hi), job->hi * p->bin);
        eps = eps_units * job->quantum;
    } else {
        eps_units = adaslice__eps_units(eps, job->quantum);
    }
    layers = adaslice__job_run(job, eps_units);
    if (layers == ADASLICE__UNREACHED) {
        uint32_t reach = job->dp.reach;
        uint64_t need = adaslice__job_min_eps(job, ADASLICE__UNREACHED);
        if (need == UINT64_MAX) {
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: no plan covers the part above z = %g mm for any eps: layers of %u to %u bins "
                               "(%g to %g mm) cannot tile the height %g mm between forced planes",
                               reach * p->bin, (unsigned)job->lo, (unsigned)job->hi, job->lo * p->bin,
                               job->hi * p->bin, job->n * p->bin);
            if (err) err->z = reach * p->bin;
            return r;
        } else {
            /* rounded up so that passing the printed value back succeeds */
            double min_eps = (double)need * job->quantum * (1 + 1e-6);
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: eps %g is too small: no plan covers the part above z = %g mm; "
                               "the smallest feasible eps is %g", eps, reach * p->bin, min_eps);
            if (err) { err->z = reach * p->bin; err->min_eps = min_eps; }
            return r;
        }
    }
    planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(&plan->allocator, (size_t)layers + 1, sizeof(uint32_t)));
    if (!planes) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory");
    for (i = job->n, k = layers; ; k--) {
        uint32_t len;
        planes[k] = i;
        if (!i) break;
        len = adaslice__dp_back(&job->dp, i);
        ADASLICE_ASSERT(len >= job->lo && len <= job->hi && len <= i && k > 0);
        i -= len;
    }
    r = adaslice__plan_fill(p, planes, layers + 1, eps, plan, err);
    adaslice__free(&plan->allocator, planes);
    return r;
}

ADASLICE_DEF adaslice_result adaslice_plan_profile(const adaslice_profile *p, const adaslice_plan_options *options,
                                                   adaslice_plan *plan, adaslice_error *err)
{
    adaslice_plan_options opt;
    adaslice__job job;
    adaslice_allocator al;
    adaslice_result r = ADASLICE_OK;
    double lo_f, hi_f;
    size_t i;
    unsigned char *ok = NULL;
    uint32_t *planes = NULL, count, forced = 0;
    void *ring = NULL;

    if (!plan) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: no output given");
    memset(plan, 0, sizeof *plan);
    if (!p || !p->phi || !p->bin_count)
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "plan: the profile is empty");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if (opt.eps == 0) opt.eps = ADASLICE_DEFAULT_EPS;
    if (opt.tmin == 0) opt.tmin = ADASLICE_DEFAULT_TMIN;
    if (opt.tmax == 0) opt.tmax = ADASLICE_DEFAULT_TMAX;
    if (opt.sharp == 0) opt.sharp = ADASLICE_DEFAULT_SHARP;
    if (!(p->bin > 0) || p->bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: bin size %g is not a positive number", p->bin);
    if (!(opt.eps > 0) || opt.eps > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: eps %g is not a positive number", opt.eps);
    if (!(opt.tmin > 0) || opt.tmin > DBL_MAX || !(opt.tmax > 0) || opt.tmax > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: tmin %g and tmax %g must be positive numbers",
                              opt.tmin, opt.tmax);
    if (opt.tmin > opt.tmax)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: tmin %g mm is larger than tmax %g mm", opt.tmin, opt.tmax);
    if (p->bin > opt.tmin * (1 + 1e-9))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: bin size %g mm is larger than tmin %g mm; use a bin of at most tmin", p->bin, opt.tmin);
    if ((unsigned)opt.method > ADASLICE_METHOD_COARSEST)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: unknown method %d", (int)opt.method);
    if (p->bin_count > 0x7ffffffeu)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "plan: %zu bins is too many", p->bin_count);
    for (i = 0; i < p->bin_count; i++)
        if (!(p->phi[i] >= 0) || p->phi[i] > DBL_MAX)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "plan: profile value %g at bin %zu (z = %g mm) is not a finite number >= 0",
                                  p->phi[i], i, (double)i * p->bin);
    /* b rarely divides tmin and tmax exactly in binary: allow a relative 1e-9 */
    lo_f = ceil(opt.tmin / p->bin - 1e-9);
    hi_f = floor(opt.tmax / p->bin + 1e-9);
    if (lo_f > hi_f)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: no multiple of the bin size %g mm lies between tmin %g and tmax %g", p->bin, opt.tmin, opt.tmax);
    if (hi_f > 65535)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: tmax / bin = %g bins per layer; at most 65535 are supported", hi_f);
    if (lo_f < 1) lo_f = 1;

    memset(&job, 0, sizeof job);
    job.profile = p;
    job.n = (uint32_t)p->bin_count;
    job.lo = (uint32_t)lo_f;
    job.hi = (uint32_t)hi_f;
    job.volume = p->metric == ADASLICE_METRIC_VOLUME;
    al = adaslice__allocator(opt.allocator);
    plan->allocator = al;
    plan->bins_min = job.lo;
    plan->bins_max = job.hi;
    if (job.n < job.lo) {
        r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                           "plan: the part is %g mm tall, thinner than one layer of tmin %g mm", job.n * p->bin, opt.tmin);
        if (err) err->z = 0;
        return r;
    }
    ok = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)job.n + 1, 1));
    planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, (size_t)job.n + 1, sizeof(uint32_t)));
    if (!ok || !planes) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); goto done; }

    adaslice__tileable(ok, job.n, job.lo, job.hi);
    switch (opt.method) {
    case ADASLICE_METHOD_FINEST:
    case ADASLICE_METHOD_COARSEST:
        count = adaslice__uniform(job.n, opt.method == ADASLICE_METHOD_FINEST ? job.lo : job.hi, planes);
        r = adaslice__plan_fill(p, planes, count, opt.eps, plan, err);
        break;
    case ADASLICE_METHOD_GREEDY:
        if (!ok[job.n]) {
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: %u bins cannot be cut into layers of %u to %u bins", (unsigned)job.n,
                               (unsigned)job.lo, (unsigned)job.hi);
            break;
        }
        count = adaslice__greedy(p, job.n, job.lo, job.hi, opt.eps, ok, planes);
        r = adaslice__plan_fill(p, planes, count, opt.eps, plan, err);
        break;
    case ADASLICE_METHOD_OPTIMAL: {
        adaslice__dp *dp = &job.dp;
        unsigned char *mem;
        dp->lo = job.lo; dp->hi = job.hi;
        for (dp->cap = 2; dp->cap <= job.hi; dp->cap *= 2) {}
        dp->volume = job.volume;
        dp->width = job.hi <= 255 ? 1 : 2;
        job.units = ADASLICE__CAST(uint64_t *, adaslice__alloc(&al, job.n, sizeof(uint64_t)));
        ring = adaslice__alloc(&al, 1, adaslice__ring_bytes(dp->cap));
        dp->back = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)job.n + 1, dp->width));
        if (!job.units || !ring || !dp->back) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); break; }
        mem = ADASLICE__CAST(unsigned char *, ring);
        dp->prefix = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += dp->cap * sizeof(uint64_t);
        dp->first = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += dp->cap * sizeof(uint64_t);
        dp->run = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += dp->cap * sizeof(uint64_t);
        dp->worst = ADASLICE__CAST(uint64_t *, ADASLICE__CAST(void *, mem)); mem += dp->cap * sizeof(uint64_t);
        dp->layers = ADASLICE__CAST(uint32_t *, ADASLICE__CAST(void *, mem)); mem += dp->cap * sizeof(uint32_t);
        dp->queue = ADASLICE__CAST(uint32_t *, ADASLICE__CAST(void *, mem));
        if (opt.sharp > 0) {
            job.forced = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)job.n + 1, 1));
            if (!job.forced) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); break; }
            forced = adaslice__sharp_planes(p, job.n, opt.sharp, ok, job.forced);
        }
        r = adaslice__plan_optimal(&job, &opt, opt.eps, plan, err);
        plan->forced_planes = forced;
        if (r == ADASLICE_ERR_INFEASIBLE && forced && err) {
            size_t len = strlen(err->message);
            adaslice__out o;
            o.buf = err->message; o.cap = sizeof err->message; o.len = len;
            adaslice__puts(&o, " (the sharp-change pre-pass forced ");
            adaslice__putu(&o, forced);
            adaslice__puts(&o, " planes; a threshold of 0 turns it off)");
            err->message[o.len < o.cap ? o.len : o.cap - 1] = 0;
        }
        break;
    }
    }
done:
    adaslice__free(&al, job.units);
    adaslice__free(&al, ring);
    adaslice__free(&al, job.dp.back);
    adaslice__free(&al, job.forced);
    adaslice__free(&al, ok);
    adaslice__free(&al, planes);
    if (r != ADASLICE_OK) {
        adaslice_plan_free(plan);
        return r;
    }
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_plan_free(adaslice_plan *plan)
{
    adaslice_allocator al;
    if (!plan) return;
    al = plan->allocator;
    adaslice__free(&al, plan->planes);
    adaslice__free(&al, plan->layers);
    memset(plan, 0, sizeof *plan);
}
