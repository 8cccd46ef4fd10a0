/* The planner against the paper's worked example and a brute-force reference. */
#include "../adaslice.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>

/* §3.3, Fig. 3: eps = 0.6, 2 to 3 bins per layer. The figure's bar heights are
   not in the text; these eight values satisfy every sum the text states
   (phi3+phi4+phi5 = 0.9, phi4+phi5 = 0.7, and each K and D below). */
static const double fig3_phi[8] = {0.1, 0.2, 0.2, 0.3, 0.4, 0.1, 0.3, 0.2};

static adaslice_profile fig3_profile(void)
{
    adaslice_profile p;
    memset(&p, 0, sizeof p);
    p.metric = ADASLICE_METRIC_CUSP;
    p.bin_count = 8;
    p.bin = 1;
    p.height = 8;
    p.phi = (double *)fig3_phi;
    return p;
}

static void fig3_k_and_d_arrays(void)
{
    /* the integer planner in tenths: K[i] and D[i] as the paper lists them */
    static const uint32_t K[9] = {0, ADASLICE_UNREACHED, 1, 1, 2, ADASLICE_UNREACHED, 3, ADASLICE_UNREACHED, 4};
    static const int D[9] = {-1, -1, 0, 0, 2, -1, 4, -1, 6};
    uint64_t workspace[64];
    adaslice_dp dp;
    int i;
    CHECK(adaslice_dp_workspace(8, 3, 0) <= sizeof workspace);
    CHECK(adaslice_dp_init(&dp, workspace, sizeof workspace, 8, 2, 3, 6, 0, 0) == ADASLICE_OK);
    CHECK(adaslice_dp_init(&dp, workspace, 8, 8, 2, 3, 6, 0, 0) == ADASLICE_ERR_ARGUMENT); /* too little memory */
    CHECK(adaslice_dp_init(&dp, workspace, sizeof workspace, 8, 3, 2, 6, 0, 0) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_dp_init(&dp, workspace, sizeof workspace, 8, 2, 3, 6, 0, 0) == ADASLICE_OK);
    for (i = 1; i <= 8; i++) {
        adaslice_dp_push(&dp, (uint64_t)(fig3_phi[i - 1] * 10 + 0.5), 0);
        CHECKF(adaslice_dp_layers(&dp) == K[i], "K[%d] = %u, paper %u", i, adaslice_dp_layers(&dp), K[i]);
        if (K[i] != ADASLICE_UNREACHED)
            CHECKF((int)(i - adaslice_dp_layer_below(&dp, (uint32_t)i)) == D[i], "D[%d] = %d, paper %d", i,
                   (int)(i - adaslice_dp_layer_below(&dp, (uint32_t)i)), D[i]);
    }
    /* turned around, the plan reads bottom-up: 0, 2, 4, 6, 8; planes off it read 0 */
    CHECK(adaslice_dp_reverse(&dp) == 4);
    for (i = 0; i <= 8; i++)
        CHECKF(adaslice_dp_layer_above(&dp, (uint32_t)i) == (i % 2 == 0 && i < 8 ? 2u : 0u), "above plane %d: %u", i,
               adaslice_dp_layer_above(&dp, (uint32_t)i));
}

static void fig3_plan_and_stuck_greedy(void)
{
    adaslice_profile p = fig3_profile();
    adaslice_plan_options o;
    adaslice_plan plan;
    adaslice_error e;
    static const uint32_t want[5] = {0, 2, 4, 6, 8};
    int k;
    memset(&o, 0, sizeof o);
    o.eps = 0.6; o.tmin = 2; o.tmax = 3; o.sharp = ADASLICE_SHARP_OFF;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_OK);
    CHECK(plan.layer_count == 4);
    for (k = 0; k < 5 && plan.layer_count == 4; k++) CHECKF(plan.planes[k] == want[k], "S plane %d = %u", k, plan.planes[k]);
    CHECK(plan.worst_error <= 0.6 && plan.over_eps == 0);
    adaslice_plan_free(&plan);
    /* the greedy takes phi1..phi3, then is stuck with phi4 + phi5 = 0.7 > eps */
    o.method = ADASLICE_METHOD_GREEDY;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_OK);
    CHECK(plan.layer_count >= 2 && plan.planes[1] == 3 && plan.planes[2] == 5);
    CHECK(plan.layer_count >= 2 && fabs(plan.layers[1].error - 0.7) < 1e-12);
    CHECK(plan.over_eps >= 1);
    adaslice_plan_free(&plan);
}

/* ------------------------------------------------------ brute force */

typedef struct ref_case {
    int n, lo, hi, volume;
    double bin, eps;
    double phi[40];
    unsigned char forced[41];
} ref_case;

typedef struct ref_best {
    int found;
    int layers;       /* fewest layers ... */
    double worst;     /* ... and the smallest worst error among those */
    double min_worst; /* smallest worst error of any plan */
} ref_best;

static double ref_error(const ref_case *c, int l, int i)
{
    double s = 0;
    int j;
    for (j = l; j < i; j++) s += c->volume ? fabs(c->phi[j] - c->phi[l]) : c->phi[j];
    return s * c->bin;
}

/* Every plan, by depth-first search over the next plane: the best (fewest
   layers, then smallest worst) with errors <= eps and layers <= max_layers. */
static void ref_search(const ref_case *c, int at, int layers, double worst, double eps, int max_layers,
                       ref_best *best, int *reach)
{
    int len;
    if (at > *reach) *reach = at;
    if (at == c->n) {
        if (!best->found || layers < best->layers || (layers == best->layers && worst < best->worst)) {
            best->layers = layers; best->worst = worst;
        }
        if (!best->found || worst < best->min_worst) best->min_worst = worst;
        best->found = 1;
        return;
    }
    if (layers >= max_layers) return;
    for (len = c->lo; len <= c->hi && at + len <= c->n; len++) {
        int j, crosses = 0;
        double e = ref_error(c, at, at + len);
        for (j = at + 1; j < at + len; j++) crosses |= c->forced[j];
        if (crosses || e > eps) continue;
        ref_search(c, at + len, layers + 1, worst > e ? worst : e, eps, max_layers, best, reach);
    }
}

static int ref_tileable(int len, int lo, int hi)
{
    int k;
    for (k = 1; k * lo <= len; k++) if (len <= k * hi) return 1;
    return len == 0;
}

static void ref_forced(ref_case *c, double sharp)
{
    int i, last = 0;
    memset(c->forced, 0, sizeof c->forced);
    if (sharp <= 0) return;
    for (i = 1; i < c->n; i++)
        if (fabs(c->phi[i] - c->phi[i - 1]) > sharp && ref_tileable(i - last, c->lo, c->hi) &&
            ref_tileable(c->n - i, c->lo, c->hi)) { c->forced[i] = 1; last = i; }
}

static unsigned rng_state = 12345u;
static unsigned rng(void) { rng_state = rng_state * 1103515245u + 12345u; return (rng_state >> 8) & 0xffffffu; }

static int plan_is_valid(const ref_case *c, const adaslice_plan *plan, double eps)
{
    size_t k;
    if (plan->planes[0] != 0 || plan->planes[plan->layer_count] != (uint32_t)c->n) return 0;
    for (k = 0; k < plan->layer_count; k++) {
        int l = (int)plan->planes[k], i = (int)plan->planes[k + 1], j;
        if (i - l < c->lo || i - l > c->hi) return 0;
        if (ref_error(c, l, i) > eps || plan->layers[k].error != ref_error(c, l, i)) return 0;
        for (j = l + 1; j < i; j++) if (c->forced[j]) return 0;
    }
    return 1;
}

/* The pre-pass's planes (c->forced) as the planner reports it kept them:
   each change moves a wanted plane or drops it. 0 if a change names a plane
   that was not wanted, or moves it onto another. */
static int ref_apply_changes(ref_case *c, const adaslice_plan *plan)
{
    size_t k;
    int i, count = 0;
    for (k = 0; k < plan->plane_changes; k++) {
        const adaslice_plane_change *ch = &plan->changes[k];
        if (ch->wanted < 1 || (int)ch->wanted >= c->n || !c->forced[ch->wanted]) return 0;
        c->forced[ch->wanted] = 0;
    }
    for (k = 0; k < plan->plane_changes; k++) {
        const adaslice_plane_change *ch = &plan->changes[k];
        if (!ch->placed) continue;
        if ((int)ch->placed >= c->n || c->forced[ch->placed]) return 0;
        c->forced[ch->placed] = 1;
    }
    for (i = 1; i < c->n; i++) count += c->forced[i];
    return (size_t)count == plan->forced_planes;
}

/* Random dyadic profiles, so that every sum is exact in double and the
   reference and the planner cannot disagree by rounding. The pre-pass's
   planes are the reference's (ref_forced) as the planner reports it kept,
   moved or dropped them; whenever a plan exists without them, one exists
   with them, with at most one layer more per plane kept. */
static void optimal_equals_brute_force(void)
{
    int trial, feasible = 0, infeasible = 0, volumes = 0, budgets = 0, forced_cases = 0, changed = 0;
    for (trial = 0; trial < 12000; trial++) {
        ref_case c, wanted, free_case;
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan plan;
        adaslice_error e;
        ref_best best, any, orig;
        int i, reach = 0, reach_any = 0, dummy = 0, max_n;
        double sharp = (rng() % 3 == 0) ? 0.25 * (1 + rng() % 4) : ADASLICE_SHARP_OFF;
        adaslice_result r;
        memset(&c, 0, sizeof c);
        c.volume = rng() % 4 == 0;
        c.lo = 1 + (int)(rng() % 4);
        c.hi = c.lo + (int)(rng() % 4);
        max_n = c.lo == 1 ? 14 : c.lo == 2 ? 22 : 34;
        c.n = 1 + (int)(rng() % (unsigned)max_n);
        c.bin = (1 + rng() % 8) / 64.0;
        for (i = 0; i < c.n; i++) c.phi[i] = (rng() % 5 == 0) ? 0 : (rng() % 33) / 16.0;
        c.eps = (1 + rng() % 256) / 256.0 * c.hi * c.bin * (c.volume ? 1.0 : 1.2);
        ref_forced(&c, sharp);
        wanted = c;
        free_case = c;
        memset(free_case.forced, 0, sizeof free_case.forced);
        memset(&p, 0, sizeof p);
        p.metric = c.volume ? ADASLICE_METRIC_VOLUME : ADASLICE_METRIC_CUSP;
        p.bin_count = (size_t)c.n;
        p.bin = c.bin;
        p.height = c.n * c.bin;
        p.phi = c.phi;
        memset(&o, 0, sizeof o);
        o.eps = c.eps;
        o.tmin = (rng() % 2 || c.lo == 1) ? c.lo * c.bin : (c.lo - 0.5) * c.bin;
        o.tmax = (rng() % 2) ? c.hi * c.bin : (c.hi + 0.5) * c.bin;
        o.sharp = sharp;

        /* without the pre-pass: whether any plan exists */
        memset(&best, 0, sizeof best);
        ref_search(&free_case, 0, 0, 0, c.eps, 1 << 30, &best, &reach);
        memset(&any, 0, sizeof any);
        ref_search(&free_case, 0, 0, 0, 1e300, 1 << 30, &any, &reach_any);
        r = adaslice_plan_profile(&p, &o, &plan, &e);
        for (i = 1; i < c.n; i++) forced_cases += c.forced[i];
        if (best.found) {
            ref_best kept;
            int free_layers = best.layers;
            feasible++;
            CHECKF(r == ADASLICE_OK, "trial %d: feasible but planner says %s", trial, e.message);
            if (r != ADASLICE_OK) continue;
            changed += plan.plane_changes > 0;
            CHECKF(ref_apply_changes(&c, &plan), "trial %d: the changes reported do not fit the planes wanted", trial);
            memset(&kept, 0, sizeof kept);
            ref_search(&c, 0, 0, 0, c.eps, 1 << 30, &kept, &dummy);
            CHECKF(kept.found, "trial %d: no plan through the planes kept", trial);
            CHECKF((int)plan.layer_count == kept.layers, "trial %d: %zu layers, brute force %d", trial,
                   plan.layer_count, kept.layers);
            CHECKF(plan.worst_error == kept.worst, "trial %d: worst %.17g, brute force %.17g", trial,
                   plan.worst_error, kept.worst);
            CHECKF(plan.layer_count <= (size_t)free_layers + plan.forced_planes,
                   "trial %d: %zu layers with %zu planes kept, %d without the pre-pass", trial, plan.layer_count,
                   plan.forced_planes, free_layers);
            CHECKF(plan_is_valid(&c, &plan, c.eps), "trial %d: plan breaks a constraint", trial);
            CHECK(plan.over_eps == 0);
            adaslice_plan_free(&plan);
            /* budget (the pre-pass's planes as wanted): the smallest eps with at most B layers */
            memset(&orig, 0, sizeof orig);
            ref_search(&wanted, 0, 0, 0, c.eps, 1 << 30, &orig, &dummy);
            if (trial % 3 == 0 && orig.found) {
                ref_best b;
                o.budget = (size_t)orig.layers + rng() % 3;
                memset(&b, 0, sizeof b);
                ref_search(&wanted, 0, 0, 0, 1e300, (int)o.budget, &b, &dummy);
                r = adaslice_plan_profile(&p, &o, &plan, &e);
                CHECKF(r == ADASLICE_OK && b.found, "trial %d: budget %zu fails: %s", trial, o.budget, e.message);
                if (r == ADASLICE_OK) {
                    CHECKF(plan.worst_error == b.min_worst && plan.eps == b.min_worst,
                           "trial %d: budget %zu gives worst %.17g eps %.17g, brute force %.17g", trial, o.budget,
                           plan.worst_error, plan.eps, b.min_worst);
                    CHECK(plan.layer_count <= o.budget && plan.plane_changes == 0);
                    CHECK(plan_is_valid(&wanted, &plan, plan.eps));
                    adaslice_plan_free(&plan);
                }
                budgets++;
            }
        } else {
            infeasible++;
            CHECKF(r == ADASLICE_ERR_INFEASIBLE, "trial %d: infeasible but planner says %d", trial, (int)r);
            if (r != ADASLICE_ERR_INFEASIBLE) { adaslice_plan_free(&plan); continue; }
            CHECKF(e.z == reach * c.bin, "trial %d: first uncovered z %g, brute force %g", trial, e.z, reach * c.bin);
            if (any.found) {
                CHECKF(e.min_eps >= any.min_worst && e.min_eps <= any.min_worst * (1 + 2e-6),
                       "trial %d: smallest eps %.17g, brute force %.17g", trial, e.min_eps, any.min_worst);
                o.eps = e.min_eps;
                CHECKF(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_OK, "trial %d: the suggested eps fails", trial);
                adaslice_plan_free(&plan);
            } else {
                CHECK(e.min_eps == 0);
            }
        }
        volumes += c.volume;
    }
    CHECKF(feasible > 3000 && infeasible > 1000 && volumes > 1500 && budgets > 800 && forced_cases > 500 && changed > 50,
           "coverage: %d feasible, %d infeasible, %d volume, %d budget, %d forced planes, %d plans with planes changed",
           feasible, infeasible, volumes, budgets, forced_cases, changed);
    printf("  (%d feasible, %d infeasible, %d forced planes wanted, %d plans moved or dropped some)\n", feasible,
           infeasible, forced_cases, changed);
}

/* Baselines never break the thickness bounds (but the uniform remainder) and
   count their layers over eps truthfully. */
static void baselines_keep_their_constraints(void)
{
    int trial;
    for (trial = 0; trial < 2000; trial++) {
        double phi[300];
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan plan;
        int n = 20 + (int)(rng() % 280), i, m;
        memset(&p, 0, sizeof p);
        for (i = 0; i < n; i++) phi[i] = (rng() % 1000) / 1000.0;
        p.bin_count = (size_t)n; p.bin = 0.002; p.phi = phi; p.height = n * 0.002;
        p.metric = trial % 2 ? ADASLICE_METRIC_VOLUME : ADASLICE_METRIC_CUSP;
        for (m = ADASLICE_METHOD_GREEDY; m <= ADASLICE_METHOD_COARSEST; m++) {
            size_t k, over = 0;
            memset(&o, 0, sizeof o);
            o.method = (adaslice_method)m;
            o.eps = 0.0001 * (1 + rng() % 100);
            o.tmin = 0.01; o.tmax = 0.03;
            if (adaslice_plan_profile(&p, &o, &plan, NULL) != ADASLICE_OK) { CHECK(0); continue; }
            CHECK(plan.planes[0] == 0 && plan.planes[plan.layer_count] == (uint32_t)n);
            for (k = 0; k < plan.layer_count; k++) {
                uint32_t len = plan.planes[k + 1] - plan.planes[k];
                int last_uniform = m != ADASLICE_METHOD_GREEDY && k + 1 == plan.layer_count;
                CHECKF(len <= plan.bins_max && (len >= plan.bins_min || last_uniform), "method %d layer %zu: %u bins", m, k, len);
                over += plan.layers[k].error > o.eps;
            }
            CHECK(over == plan.over_eps);
            adaslice_plan_free(&plan);
        }
    }
}

/* Profiles that do not quantise exactly (real numbers): the error of every
   layer of an optimal plan, summed in double, stays within eps. Volume
   deviation rounds to nearest and must add a unit per bin to stay safe. */
static void quantising_never_breaks_eps(void)
{
    int trial, over = 0, plans = 0;
    for (trial = 0; trial < 3000; trial++) {
        double phi[200];
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan plan;
        int n = 40 + (int)(rng() % 160), i;
        size_t k;
        memset(&p, 0, sizeof p);
        for (i = 0; i < n; i++) phi[i] = 0.1 + (rng() % 100000) / 7919.0;
        p.metric = trial % 2 ? ADASLICE_METRIC_VOLUME : ADASLICE_METRIC_CUSP;
        p.bin_count = (size_t)n; p.bin = 0.01 / 3; p.phi = phi; p.height = n * p.bin;
        memset(&o, 0, sizeof o);
        o.tmin = 0.02; o.tmax = 0.1; o.sharp = ADASLICE_SHARP_OFF;
        /* eps just at some layer's error, where rounding decides */
        o.eps = adaslice_layer_error(&p, 0, 6 + rng() % 20) * (1 + (rng() % 3) * 1e-12);
        if (adaslice_plan_profile(&p, &o, &plan, NULL) != ADASLICE_OK) continue;
        plans++;
        for (k = 0; k < plan.layer_count; k++) over += adaslice_layer_error(&p, plan.planes[k], plan.planes[k + 1]) > o.eps;
        adaslice_plan_free(&plan);
    }
    CHECKF(over == 0 && plans > 1000, "%d layers over eps in %d plans", over, plans);
}

/* The sharpest case: one layer of two bins whose error is a hair above eps.
   Rounding either value to the nearest unit may hide the hair, so the
   planner must refuse it every time. */
static void rounding_cannot_hide_an_excess(void)
{
    int trial, accepted = 0;
    for (trial = 0; trial < 2000; trial++) {
        double phi[2];
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan plan;
        memset(&p, 0, sizeof p);
        phi[0] = 0;
        phi[1] = 1 + (rng() % 1000000) / 999983.0;
        p.metric = trial % 2 ? ADASLICE_METRIC_VOLUME : ADASLICE_METRIC_CUSP;
        p.bin_count = 2; p.bin = 0.01; p.phi = phi; p.height = 0.02;
        memset(&o, 0, sizeof o);
        o.tmin = o.tmax = 0.02;
        o.sharp = ADASLICE_SHARP_OFF;
        o.eps = adaslice_layer_error(&p, 0, 2) * (1 - 1e-13);
        if (adaslice_plan_profile(&p, &o, &plan, NULL) == ADASLICE_OK) { accepted++; adaslice_plan_free(&plan); }
    }
    CHECKF(accepted == 0, "%d layers over eps accepted", accepted);
}

static void bad_arguments_are_named(void)
{
    adaslice_profile p = fig3_profile();
    adaslice_plan_options o;
    adaslice_plan plan;
    adaslice_error e;
    double bad[3] = {0.1, -1, 0.2};
    memset(&o, 0, sizeof o);
    o.tmin = 2; o.tmax = 1;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "tmin"));
    o.tmin = 0.5; o.tmax = 3;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "bin size"));
    o.tmin = 2.2; o.tmax = 2.8;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "multiple"));
    o.tmin = 2; o.tmax = 3; o.eps = -1;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "eps"));
    o.eps = 0.6;
    p.phi = bad; p.bin_count = 3;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "bin 1"));
    p = fig3_profile();
    o.eps = 0.25; /* phi4 + phi5 needs 0.7 ... every 2-bin window must fit */
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_INFEASIBLE);
    CHECKF(strstr(e.message, "smallest feasible eps") && e.z == 0 && e.min_eps >= 0.5 && e.min_eps < 0.5001,
           "%s (z %g, min eps %g)", e.message, e.z, e.min_eps);
    p.bin_count = 1; /* thinner than tmin */
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_INFEASIBLE && strstr(e.message, "thinner"));
}

/* Profiles of a few thousand bins, smooth stretches parted by jumps (as a
   part's walls meet its flats), and eps from the smallest any plan allows
   without the pre-pass up to twice that: with the pre-pass (sharp 0.5) a
   plan always exists, its worst error is within eps, it has a plane at each
   plane the pre-pass kept (those wanted, as the changes say), and it has at
   most one layer more per plane kept than the plan without the pre-pass. */
static void the_pre_pass_never_makes_eps_infeasible(void)
{
    static double phi[4000];
    static unsigned char wanted[4001];
    static const double steps[] = {1, 1.0000001, 1.001, 1.01, 1.03, 1.1, 1.3, 2};
    int trial, plans = 0, changed = 0, moved = 0, dropped = 0;
    size_t most_over = 0;
    for (trial = 0; trial < 120; trial++) {
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan with, without;
        adaslice_error e;
        int n = 800 + (int)(rng() % 3000), i, last = 0, lo, hi, volume = trial % 5 == 4;
        double level = (rng() % 64) / 64.0, min_eps;
        size_t st;
        for (i = 0; i < n; i++) {
            if (rng() % 97 == 0) level = (rng() % 64) / 64.0;              /* a jump */
            else level += ((double)(rng() % 9) - 4) / 1024;                 /* a slope */
            if (level < 0) level = 0;
            if (level > 1) level = 1;
            phi[i] = volume ? 20 * level : level;
        }
        memset(&p, 0, sizeof p);
        p.metric = volume ? ADASLICE_METRIC_VOLUME : ADASLICE_METRIC_CUSP;
        p.bin_count = (size_t)n;
        p.bin = 0.002;
        p.height = n * p.bin;
        p.phi = phi;
        memset(&o, 0, sizeof o);
        o.tmin = (double)(10 + rng() % 16) * p.bin;
        o.tmax = (double)(40 + rng() % 36) * p.bin;
        lo = (int)(o.tmin / p.bin + 0.5);
        hi = (int)(o.tmax / p.bin + 0.5);
        /* the planes the pre-pass wants: jumps > 0.5, skipping those no thickness fits */
        memset(wanted, 0, sizeof wanted);
        for (i = 1; i < n; i++)
            if (fabs(phi[i] - phi[i - 1]) > 0.5 && ref_tileable(i - last, lo, hi) && ref_tileable(n - i, lo, hi)) {
                wanted[i] = 1;
                last = i;
            }
        o.sharp = ADASLICE_SHARP_OFF;
        o.eps = 1e-9;
        CHECK(adaslice_plan_profile(&p, &o, &without, &e) == ADASLICE_ERR_INFEASIBLE && e.min_eps > 0);
        min_eps = e.min_eps;
        for (st = 0; st < sizeof steps / sizeof *steps; st++) {
            size_t k, c;
            int kept = 0, missing = 0;
            o.eps = min_eps * steps[st];
            o.sharp = ADASLICE_SHARP_OFF;
            CHECKF(adaslice_plan_profile(&p, &o, &without, &e) == ADASLICE_OK, "trial %d: eps %.9g: %s", trial, o.eps, e.message);
            o.sharp = 0.5;
            if (adaslice_plan_profile(&p, &o, &with, &e) != ADASLICE_OK) {
                CHECKF(0, "trial %d (%s, %d bins, %d..%d per layer): eps %.9g (%g x the smallest) is feasible without "
                       "the pre-pass but not with it: %s", trial, volume ? "volume" : "cusp", n, lo, hi, o.eps, steps[st], e.message);
                adaslice_plan_free(&without);
                continue;
            }
            plans++;
            changed += with.plane_changes > 0;
            /* the planes kept: those wanted, moved or dropped as reported */
            {
                static unsigned char kept_at[4001];
                memcpy(kept_at, wanted, (size_t)n + 1);
                for (c = 0; c < with.plane_changes; c++) {
                    CHECK(kept_at[with.changes[c].wanted]);
                    kept_at[with.changes[c].wanted] = 0;
                    if (with.changes[c].placed) moved++; else dropped++;
                }
                for (c = 0; c < with.plane_changes; c++) if (with.changes[c].placed) kept_at[with.changes[c].placed] = 1;
                for (i = 1; i < n; i++) {
                    int on_plan = 0;
                    if (!kept_at[i]) continue;
                    kept++;
                    for (k = 0; k <= with.layer_count && !on_plan; k++) on_plan = with.planes[k] == (uint32_t)i;
                    missing += !on_plan;
                }
            }
            CHECKF(missing == 0 && (size_t)kept == with.forced_planes, "trial %d: %d of %d planes kept are not on the plan (%zu reported)",
                   trial, missing, kept, with.forced_planes);
            CHECKF(with.worst_error <= o.eps && with.over_eps == 0, "trial %d: worst %.9g over eps %.9g", trial, with.worst_error, o.eps);
            CHECKF(with.layer_count <= without.layer_count + with.forced_planes,
                   "trial %d: eps %.9g: %zu layers with %zu planes kept, %zu without the pre-pass", trial, o.eps,
                   with.layer_count, with.forced_planes, without.layer_count);
            if (with.layer_count > without.layer_count && with.layer_count - without.layer_count > most_over)
                most_over = with.layer_count - without.layer_count;
            adaslice_plan_free(&with);
            adaslice_plan_free(&without);
        }
    }
    CHECKF(plans == 120 * 8 && changed > 20, "%d plans, %d with planes moved or dropped", plans, changed);
    printf("  (%d plans, %d with planes changed: %d moved, %d dropped; at most %zu layers over the plan without)\n",
           plans, changed, moved, dropped, most_over);
}

/* Errors of 10^-300 mm and subnormal ones fit any eps: the unit they are
   counted in once rounded to inf, and such a profile was called infeasible
   with "the smallest feasible eps is 0". */
static void tiny_errors_fit_any_eps(void)
{
    static double tiny[3] = {1e-300, 0, 0}, sub[4] = {1e-320, 1e-320, 0, 4e-320};
    double *values[2] = {tiny, sub};
    size_t counts[2] = {3, 4};
    int k, metric;
    for (k = 0; k < 2; k++)
        for (metric = 0; metric < 4; metric += 3) { /* cusp and volume */
            adaslice_profile p;
            adaslice_plan_options o;
            adaslice_plan plan;
            adaslice_error e;
            memset(&p, 0, sizeof p);
            p.metric = (adaslice_metric)metric;
            p.bin_count = counts[k];
            p.bin = 0.01;
            p.height = 0.01 * counts[k];
            p.phi = values[k];
            memset(&o, 0, sizeof o);
            o.tmin = 0.01;
            CHECKF(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_OK, "values %d, metric %d: %s", k, metric, e.message);
            CHECK(plan.layer_count == 1 && plan.worst_error < 1e-290 && !plan.over_eps);
            adaslice_plan_free(&plan);
        }
}

void test_planner(void)
{
    RUN(fig3_k_and_d_arrays);
    RUN(fig3_plan_and_stuck_greedy);
    RUN(optimal_equals_brute_force);
    RUN(the_pre_pass_never_makes_eps_infeasible);
    RUN(baselines_keep_their_constraints);
    RUN(quantising_never_breaks_eps);
    RUN(rounding_cannot_hide_an_excess);
    RUN(tiny_errors_fit_any_eps);
    RUN(bad_arguments_are_named);
}
