/* adaslice contour (issue 25): PrusaSlicer slices our 3MF of a shallow dome,
   a gently curved aerofoil-like block and the bundled hand, contour moves
   the surface paths onto the mesh, and the test measures the printed
   surface against the mesh before and after with its own G-code reader and
   its own ray casts (brute force over the triangles, no LDI):
   - in each 0.4 mm cell of the plate whose mesh surface is no steeper than
     15 degrees, the highest extrusion point's vertical distance to the
     mesh: mean and 95th percentile at least 4x smaller after;
   - no printed point in those cells more than 0.03 mm above the mesh;
   - no point below what earlier layers deposited at it;
   - E per layer within 2 % of PrusaSlicer's where following the mesh keeps
     the layer's volume, and everywhere as the height the beads fill;
   - every line contour does not rewrite is in the output, in order.
   And each input contour refuses gets one line, exit 1 and no file;
   --top-skins rises further than modulation and keeps out of later
   nozzles' cones; --svg-path's figure is the G-code's. */
#include "prusa_check.h"
#include <ctype.h>
#include "meshgen.h"
#include "../host/output.h"
#include "../host/codec/zip.h"
#include "../host/formats/threemf.h"

#ifndef CELL_MM
#define CELL_MM 0.8
#endif
#define SAMPLE_MM 0.1
#define COVER_MM 0.05
/* half a bead: PrusaSlicer's perimeters and solid infill are 0.45 mm wide */
#define BEAD_HALF 0.2
#define DEPOSIT_MM 0.1

/* ---- the mesh's top surface, ray against every triangle in a bucket */

typedef struct top_finder {
    const adaslice_mesh *m;
    double lo[2], shift[3];      /* G-code = mesh + shift */
    int w, h;                    /* 1 mm buckets */
    size_t *first, *list;
} top_finder;

static void finder_init(top_finder *f, const adaslice_mesh *m, const double shift[3])
{
    double lo[3], hi[3];
    size_t t, n = 0, *fill;
    int pass;
    memset(f, 0, sizeof *f);
    f->m = m;
    memcpy(f->shift, shift, sizeof f->shift);
    adaslice_mesh_bounds(m, lo, hi);
    f->lo[0] = lo[0] - 1;
    f->lo[1] = lo[1] - 1;
    f->w = (int)(hi[0] - lo[0]) + 3;
    f->h = (int)(hi[1] - lo[1]) + 3;
    f->first = (size_t *)calloc((size_t)(f->w * f->h + 1), sizeof(size_t));
    fill = (size_t *)calloc((size_t)(f->w * f->h + 1), sizeof(size_t));
    for (pass = 0; pass < 2; pass++) {
        for (t = 0; t < m->triangle_count; t++) {
            double a[2] = {HUGE_VAL, HUGE_VAL}, b[2] = {-HUGE_VAL, -HUGE_VAL};
            int c, k, i, j;
            for (c = 0; c < 3; c++)
                for (k = 0; k < 2; k++) {
                    double v = m->vertices[3 * m->triangles[3 * t + c] + k];
                    if (v < a[k]) a[k] = v;
                    if (v > b[k]) b[k] = v;
                }
            for (j = (int)(a[1] - f->lo[1]); j <= (int)(b[1] - f->lo[1]); j++)
                for (i = (int)(a[0] - f->lo[0]); i <= (int)(b[0] - f->lo[0]); i++) {
                    size_t cell = (size_t)(j * f->w + i);
                    if (pass == 0) f->first[cell + 1]++;
                    else f->list[f->first[cell] + fill[cell]++] = t;
                }
        }
        if (pass == 0) {
            for (t = 0; t < (size_t)(f->w * f->h); t++) f->first[t + 1] += f->first[t];
            n = f->first[f->w * f->h];
            f->list = (size_t *)malloc((n ? n : 1) * sizeof(size_t));
        }
    }
    free(fill);
}

static void finder_free(top_finder *f)
{
    free(f->first);
    free(f->list);
}

/* The highest crossing of the vertical line at G-code (x, y) with the mesh
   (above -HUGE_VAL), or the lowest crossing of an upward face above G-code
   Z `above` (the top a point of a layer lies under), in G-code Z, and the
   cosine of its face's slope; 0 where none. */
static int mesh_cross(const top_finder *f, double x, double y, double above, double *z, double *cos_slope)
{
    double mx = x - f->shift[0], my = y - f->shift[1], best = above == -HUGE_VAL ? -HUGE_VAL : HUGE_VAL;
    int i = (int)(mx - f->lo[0]), j = (int)(my - f->lo[1]);
    size_t k;
    if (i < 0 || j < 0 || i >= f->w || j >= f->h) return 0;
    for (k = f->first[j * f->w + i]; k < f->first[j * f->w + i + 1]; k++) {
        const uint32_t *t = f->m->triangles + 3 * f->list[k];
        const float *p = f->m->vertices + 3 * t[0], *q = f->m->vertices + 3 * t[1], *r = f->m->vertices + 3 * t[2];
        double d = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]), u, v, zz;
        double nx, ny;
        if (fabs(d) < 1e-12) continue;
        u = ((mx - p[0]) * (r[1] - p[1]) - (my - p[1]) * (r[0] - p[0])) / d;
        v = ((q[0] - p[0]) * (my - p[1]) - (q[1] - p[1]) * (mx - p[0])) / d;
        if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9) continue;
        zz = p[2] + u * (q[2] - p[2]) + v * (r[2] - p[2]);
        if (above == -HUGE_VAL ? zz <= best : d <= 0 || zz + f->shift[2] <= above || zz >= best) continue;
        best = zz;
        nx = (q[1] - p[1]) * (r[2] - p[2]) - (q[2] - p[2]) * (r[1] - p[1]);
        ny = (q[2] - p[2]) * (r[0] - p[0]) - (q[0] - p[0]) * (r[2] - p[2]);
        *cos_slope = fabs(d) / sqrt(nx * nx + ny * ny + d * d);
    }
    if (best == -HUGE_VAL || best == HUGE_VAL) return 0;
    *z = best + f->shift[2];
    return 1;
}

static int mesh_top(const top_finder *f, double x, double y, double *z, double *cos_slope)
{
    return mesh_cross(f, x, y, -HUGE_VAL, z, cos_slope);
}

/* ---- a G-code reader of the test's own */

typedef struct seg { double a[3], b[3], e; int layer; } seg;

typedef struct printed {
    seg *segs;
    size_t n, cap;
    double e[4096];              /* filament per layer */
    double top[4096], height[4096]; /* ;Z: and the first ;HEIGHT: after it */
    double unscaled[4096];       /* e of each segment times layer height / the height it fills */
    int layers;
    size_t lines;
    double low_travel;           /* the most a travel ran under the layer's highest extrusion so far */
    double steepest;             /* the steepest extrusion segment, dz / length (those over 0.05 mm) */
    double layer_peak;
} printed;

/* Every line is a comment, blank, or words of a letter and a number. The
   extrusions (XY moves with E forward) in layers (;Z:). 0 with a message
   for a line it cannot read. */
static int read_printed(const char *path, printed *p)
{
    char *text = read_whole_text(path), *line, *next;
    double pos[4] = {0, 0, 0, 0};
    int relative = 0;
    memset(p, 0, sizeof *p);
    p->layers = -1;
    CHECKF(text != NULL, "cannot read %.100s", path);
    if (!text) return 0;
    for (line = text; *line; line = next) {
        char *end = strchr(line, '\n'), *c, *w;
        double v[4];
        int has[4] = {0, 0, 0, 0}, g = -1, m = -1, k;
        next = end ? end + 1 : line + strlen(line);
        if (end) *end = 0;
        p->lines++;
        if (!strncmp(line, ";Z:", 3) && p->layers + 1 < 4096) {
            p->top[++p->layers] = atof(line + 3);
            p->layer_peak = -HUGE_VAL;
            continue;
        }
        if (!strncmp(line, ";HEIGHT:", 8) && p->layers >= 0 && !p->height[p->layers]) { p->height[p->layers] = atof(line + 8); continue; }
        if ((c = strchr(line, ';')) != NULL) *c = 0;
        for (w = strtok(line, " \t\r"); w; w = strtok(NULL, " \t\r")) {
            char *after;
            double x = strtod(w + 1, &after);
            if (!isalpha((unsigned char)w[0]) || after == w + 1 || *after) {
                CHECKF(0, "%.100s: line %zu: word %.40s", path, p->lines, w);
                free(text);
                return 0;
            }
            if (w[0] == 'G' && g < 0 && m < 0) g = (int)x;
            else if (w[0] == 'M' && g < 0 && m < 0) m = (int)x;
            else if (strchr("XYZE", w[0])) { k = (int)(strchr("XYZE", w[0]) - "XYZE"); has[k] = 1; v[k] = x; }
        }
        if (m == 82 || m == 83) relative = m == 83;
        if (g == 92 && has[3]) pos[3] = v[3];
        if (g == 0 || g == 1) {
            double before[4];
            memcpy(before, pos, sizeof before);
            for (k = 0; k < 3; k++) if (has[k]) pos[k] = v[k];
            if (has[3]) pos[3] = relative ? pos[3] + v[3] : v[3];
            if ((has[0] || has[1]) && pos[3] > before[3] && p->layers >= 0 && p->layers < 4096) {
                if (p->n == p->cap) p->segs = (seg *)realloc(p->segs, (p->cap = p->cap ? 2 * p->cap : 65536) * sizeof(seg));
                memcpy(p->segs[p->n].a, before, sizeof p->segs->a);
                memcpy(p->segs[p->n].b, pos, sizeof p->segs->b);
                p->segs[p->n].e = pos[3] - before[3];
                p->segs[p->n++].layer = p->layers;
                p->e[p->layers] += pos[3] - before[3];
                if (pos[2] > p->layer_peak) p->layer_peak = pos[2];
                if (before[2] > p->layer_peak) p->layer_peak = before[2];
                if (hypot(pos[0] - before[0], pos[1] - before[1]) > 0.05 &&
                    fabs(pos[2] - before[2]) / hypot(pos[0] - before[0], pos[1] - before[1]) > p->steepest)
                    p->steepest = fabs(pos[2] - before[2]) / hypot(pos[0] - before[0], pos[1] - before[1]);
            } else if ((has[0] || has[1]) && p->layers >= 0 && p->layer_peak - pos[2] > p->low_travel) {
                p->low_travel = p->layer_peak - pos[2];
            }
        }
    }
    p->layers++;
    free(text);
    return 1;
}

/* ---- the surface as printed */

typedef struct surface_error { double mean, p95, worst_above; size_t cells, above; } surface_error;

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The plate at COVER_MM, each square the highest bead top over it: a bead
   is flat across its width, 2 BEAD_HALF. */
typedef struct cover { float *z; int w, h; double lo[2]; } cover;

static void cover_build(cover *c, const printed *p, const double lo[2], const double hi[2])
{
    size_t s;
    int i;
    c->lo[0] = lo[0] - 1;
    c->lo[1] = lo[1] - 1;
    c->w = (int)((hi[0] - lo[0] + 2) / COVER_MM) + 1;
    c->h = (int)((hi[1] - lo[1] + 2) / COVER_MM) + 1;
    c->z = (float *)malloc((size_t)c->w * (size_t)c->h * sizeof *c->z);
    for (i = 0; i < c->w * c->h; i++) c->z[i] = -1e9f;
    for (s = 0; s < p->n; s++) {
        const seg *g = &p->segs[s];
        double len = hypot(g->b[0] - g->a[0], g->b[1] - g->a[1]);
        int q, k, steps = (int)(len / (COVER_MM / 2)) + 1, across = (int)(BEAD_HALF / (COVER_MM / 2));
        if (len <= 0) continue;
        for (q = 0; q <= steps; q++)
            for (k = -across; k <= across; k++) {
                double t = (double)q / steps, off = k * (COVER_MM / 2) / len;
                double x = g->a[0] + t * (g->b[0] - g->a[0]) - off * (g->b[1] - g->a[1]);
                double y = g->a[1] + t * (g->b[1] - g->a[1]) + off * (g->b[0] - g->a[0]);
                float z = (float)(g->a[2] + t * (g->b[2] - g->a[2]));
                int ci = (int)floor((x - c->lo[0]) / COVER_MM), cj = (int)floor((y - c->lo[1]) / COVER_MM);
                if (ci >= 0 && cj >= 0 && ci < c->w && cj < c->h && z > c->z[cj * c->w + ci]) c->z[cj * c->w + ci] = z;
            }
    }
}

/* Per CELL_MM cell of the plate over the mesh's box, the highest extrusion
   point that no other bead covers, against the mesh there, in cells whose
   surface is shallow (within max_angle at the centre and all four
   corners). */
static surface_error measure(const printed *p, const top_finder *f, double max_angle)
{
    double lo[3], hi[3], *top, *dist, blo[2], bhi[2];
    float *px, *py;
    int w, h, i, j;
    size_t s, n = 0;
    surface_error r;
    cover c;
    memset(&r, 0, sizeof r);
    adaslice_mesh_bounds(f->m, lo, hi);
    for (i = 0; i < 2; i++) {
        blo[i] = lo[i] + f->shift[i];
        bhi[i] = hi[i] + f->shift[i];
    }
    cover_build(&c, p, blo, bhi);
    w = (int)((hi[0] - lo[0]) / CELL_MM) + 1;
    h = (int)((hi[1] - lo[1]) / CELL_MM) + 1;
    top = (double *)malloc((size_t)(w * h) * sizeof *top);
    px = (float *)calloc((size_t)(w * h), sizeof *px);
    py = (float *)calloc((size_t)(w * h), sizeof *py);
    dist = (double *)malloc((size_t)(w * h) * sizeof *dist);
    for (i = 0; i < w * h; i++) top[i] = -HUGE_VAL;
    for (s = 0; s < p->n; s++) {
        const seg *g = &p->segs[s];
        double len = hypot(g->b[0] - g->a[0], g->b[1] - g->a[1]);
        int q, steps = (int)(len / SAMPLE_MM) + 1;
        for (q = 0; q <= steps; q++) {
            double t = (double)q / steps, x = g->a[0] + t * (g->b[0] - g->a[0]), y = g->a[1] + t * (g->b[1] - g->a[1]);
            double z = g->a[2] + t * (g->b[2] - g->a[2]);
            int ci = (int)floor((x - f->shift[0] - lo[0]) / CELL_MM), cj = (int)floor((y - f->shift[1] - lo[1]) / CELL_MM);
            int ki = (int)floor((x - c.lo[0]) / COVER_MM), kj = (int)floor((y - c.lo[1]) / COVER_MM);
            if (ci < 0 || cj < 0 || ci >= w || cj >= h || z <= top[cj * w + ci]) continue;
            if (z < c.z[kj * c.w + ki] - 1e-4) continue; /* under another bead */
            top[cj * w + ci] = z;
            px[cj * w + ci] = (float)x;
            py[cj * w + ci] = (float)y;
        }
    }
    for (j = 0; j < h; j++)
        for (i = 0; i < w; i++) {
            double cx = lo[0] + f->shift[0] + (i + 0.5) * CELL_MM, cy = lo[1] + f->shift[1] + (j + 0.5) * CELL_MM, z, c;
            int corner, shallow = top[j * w + i] > -HUGE_VAL;
            for (corner = 0; corner < 5 && shallow; corner++) {
                double dx = corner == 4 ? 0 : (corner & 1 ? 0.5 : -0.5) * CELL_MM;
                double dy = corner == 4 ? 0 : (corner & 2 ? 0.5 : -0.5) * CELL_MM;
                shallow = mesh_top(f, cx + dx, cy + dy, &z, &c) && c >= cos(max_angle * M_PI / 180);
            }
            if (!shallow || !mesh_top(f, px[j * w + i], py[j * w + i], &z, &c)) continue;
            dist[n++] = fabs(top[j * w + i] - z);
            if (top[j * w + i] - z > r.worst_above) r.worst_above = top[j * w + i] - z;
            r.mean += fabs(top[j * w + i] - z);
        }
    r.cells = n;
    if (n) {
        qsort(dist, n, sizeof *dist, by_value);
        r.mean /= (double)n;
        r.p95 = dist[(size_t)(0.95 * (double)(n - 1))];
    }
    free(top);
    free(px);
    free(py);
    free(dist);
    free(c.z);
    return r;
}

/* The worst depth (mm) by which a point of a layer lies under what earlier
   layers put in its DEPOSIT_MM cell; and p->unscaled, each layer's E with
   each segment's taken back to the layer's height from the height it fills
   (its middle's Z less the layer's bottom; a quarter layer at least). */
static double worst_gouge(printed *p, const top_finder *f)
{
    double lo[3], hi[3], worst = 0;
    float *dep;
    int w, h, pass, layer = -1;
    size_t s, start = 0;
    adaslice_mesh_bounds(f->m, lo, hi);
    w = (int)((hi[0] - lo[0]) / DEPOSIT_MM) + 1;
    h = (int)((hi[1] - lo[1]) / DEPOSIT_MM) + 1;
    dep = (float *)malloc((size_t)(w * h) * sizeof *dep);
    for (s = 0; s < (size_t)(w * h); s++) dep[s] = -1e9f;
    for (s = 0; s <= p->n; s++) {
        size_t t;
        if (s < p->n && p->segs[s].layer == layer) continue;
        /* the layer [start, s): checked against the deposit, then added to it */
        for (pass = 0; pass < 2; pass++)
            for (t = start; t < s; t++) {
                const seg *g = &p->segs[t];
                if (pass == 0) {
                    double h = p->height[g->layer], fill = (g->a[2] + g->b[2]) / 2 - (p->top[g->layer] - h);
                    p->unscaled[g->layer] += fill > 0.25 * h ? g->e * h / fill : 4 * g->e;
                }
                double len = hypot(g->b[0] - g->a[0], g->b[1] - g->a[1]);
                int q, k, steps = (int)(len / (DEPOSIT_MM / 2)) + 1, across = (int)(BEAD_HALF / (DEPOSIT_MM / 2));
                /* checked along the centre line, deposited over the bead's width */
                for (q = 0; q <= steps; q++)
                    for (k = pass ? -across : 0; k <= (pass ? across : 0); k++) {
                        double u = (double)q / steps, off = len > 0 ? k * (DEPOSIT_MM / 2) / len : 0;
                        double x = g->a[0] + u * (g->b[0] - g->a[0]) - off * (g->b[1] - g->a[1]) - f->shift[0] - lo[0];
                        double y = g->a[1] + u * (g->b[1] - g->a[1]) + off * (g->b[0] - g->a[0]) - f->shift[1] - lo[1];
                        double z = g->a[2] + u * (g->b[2] - g->a[2]);
                        int i = (int)floor(x / DEPOSIT_MM), j = (int)floor(y / DEPOSIT_MM);
                        if (i < 0 || j < 0 || i >= w || j >= h) continue;
                        if (pass == 0 && dep[j * w + i] - z > worst) worst = dep[j * w + i] - z;
                        if (pass == 1 && z > dep[j * w + i]) dep[j * w + i] = (float)z;
                    }
            }
        start = s;
        if (s < p->n) layer = p->segs[s].layer;
    }
    free(dep);
    return worst;
}

/* ratio[k]: layer k's filament if each of p's extrusion samples filled the
   mesh (brute force), over what it has: from the layer's bottom up to the
   surface over the sample where that is an upward face no steeper than 15
   degrees within the layer's reach (half the next layer over its top,
   where PrusaSlicer's slice at the next layer's middle leaves the surface
   exposed), a full layer elsewhere (inside the part). Where this is not 1
   the mesh itself asks for more or less than PrusaSlicer's planar layer. */
static void mesh_filament_ratio(const printed *p, const top_finder *f, double *ratio)
{
    size_t s;
    int k;
    for (k = 0; k < p->layers; k++) ratio[k] = 0;
    for (s = 0; s < p->n; s++) {
        const seg *g = &p->segs[s];
        double h = p->height[g->layer], bottom = p->top[g->layer] - h;
        double reach = g->layer + 1 < p->layers ? p->height[g->layer + 1] / 2 : HUGE_VAL;
        int q, steps = (int)(hypot(g->b[0] - g->a[0], g->b[1] - g->a[1]) / SAMPLE_MM) + 1;
        for (q = 0; q < steps; q++) {
            double t = (q + 0.5) / steps, z, c, fill = h;
            if (mesh_cross(f, g->a[0] + t * (g->b[0] - g->a[0]), g->a[1] + t * (g->b[1] - g->a[1]), bottom, &z, &c) &&
                c >= cos(15 * M_PI / 180) && z <= p->top[g->layer] + reach)
                fill = z - bottom > 0.25 * h ? z - bottom : 0.25 * h;
            ratio[g->layer] += g->e / steps * fill / h;
        }
    }
    for (k = 0; k < p->layers; k++) ratio[k] = p->e[k] > 0 ? ratio[k] / p->e[k] : 1;
}

/* Every line of `in` but the extrusions contour may rewrite is in `out`, in
   order, and out's other lines are G1 moves or G92 E. 0 after a failed check. */
static int kept_byte_for_byte(const char *in_path, const char *out_path)
{
    static const char *const rewritten[] = {"External perimeter", "Perimeter", "Overhang perimeter", "Solid infill",
                                            "Top solid infill", "Gap fill", "Ironing"};
    char *in = read_whole_text(in_path), *out = read_whole_text(out_path), *a, *b, *na, *nb;
    int may = 0, ok = in && out;
    size_t line = 0, k;
    for (a = in, b = out; ok && *a; a = na) {
        size_t len;
        na = strchr(a, '\n') ? strchr(a, '\n') + 1 : a + strlen(a);
        len = (size_t)(na - a);
        line++;
        if (!strncmp(a, ";TYPE:", 6))
            for (may = 0, k = 0; k < sizeof rewritten / sizeof *rewritten; k++)
                may |= !strncmp(a + 6, rewritten[k], strlen(rewritten[k])) && a[6 + strlen(rewritten[k])] == '\n';
        if (may && !strncmp(a, "G1 X", 4) && memchr(a, 'E', len)) continue;
        for (;; b = nb) {
            nb = strchr(b, '\n') ? strchr(b, '\n') + 1 : b + strlen(b);
            if ((size_t)(nb - b) == len && !memcmp(a, b, len)) { b = nb; break; }
            if (!*b || (strncmp(b, "G1 ", 3) && strncmp(b, "G92 E", 5))) {
                CHECKF(0, "%.100s: line %zu (%.60s) is not in %.100s where it belongs", in_path, line, a, out_path);
                ok = 0;
                break;
            }
        }
    }
    free(in);
    free(out);
    return ok;
}

/* ---- the cases */

/* Plans model (a file) into a 3MF, slices it with PrusaSlicer (relative E
   when asked), contours it; the measurements before and after. */
static void contour_case(const char *model, double scale, int relative_e, double min_gain)
{
    char s[32], path3mf[300], before_path[300], after_path[300];
    double lo[3], hi[3], shift[3];
    adaslice_load_options o;
    adaslice_mesh mesh;
    adaslice_error e;
    top_finder f;
    printed before, after;
    surface_error eb, ea;
    cli_result r;
    size_t k, worst_layer = 0;
    double worst_e = 0, worst_flow = 0, gouge, *ratio = (double *)malloc(4096 * sizeof *ratio), worst_even = 0;
    double r_lo = HUGE_VAL, r_hi = -HUGE_VAL;
    size_t even = 0, uneven = 0, even_layer = 0;
    snprintf(s, sizeof s, "%.9g", scale);
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("part.3mf"));
    snprintf(before_path, sizeof before_path, "%s", cli_path("part.gcode"));
    snprintf(after_path, sizeof after_path, "%s", cli_path("contoured.gcode"));
    if (!prusa_gcode_after(cli_run("plan", model, "--scale", s, PRUSA_FDM_ARGS, "--3mf", path3mf, "--out", cli_path("plan.csv"),
                                   NULL),
                           path3mf, before_path, relative_e ? "--use-relative-e-distances" : NULL))
        return;
    r = cli_run("contour", before_path, "--project", path3mf, "-o", after_path, NULL);
    CHECKF(r.status == 0 && !r.err[0], "%.100s: contour: exit %d: %.300s", model, r.status, r.err);
    printf("    %s", r.out);
    cli_free(&r);
    if (check_case_failed()) return;
    /* where PrusaSlicer puts a part: its box centred on the bed, on the bed */
    memset(&o, 0, sizeof o);
    o.scale = scale;
    if (adaslice_mesh_load_file(model, &o, &mesh, &e) != ADASLICE_OK) { CHECKF(0, "%.100s: %.200s", model, e.message); return; }
    adaslice_mesh_bounds(&mesh, lo, hi);
    shift[0] = 125 - (lo[0] + hi[0]) / 2;
    shift[1] = 105 - (lo[1] + hi[1]) / 2;
    shift[2] = -lo[2];
    finder_init(&f, &mesh, shift);
    if (read_printed(before_path, &before) && read_printed(after_path, &after)) {
        eb = measure(&before, &f, 15);
        ea = measure(&after, &f, 15);
        gouge = worst_gouge(&after, &f);
        CHECKF(before.layers == after.layers, "%d layers before, %d after", before.layers, after.layers);
        mesh_filament_ratio(&before, &f, ratio);
        for (k = 0; k < (size_t)before.layers && k < 4096; k++)
            if (before.e[k] > 0) {
                /* the E within 2 % per layer, where following the
                   mesh keeps the layer's volume; elsewhere E follows the
                   height the beads fill (worst_flow, every layer) */
                if (fabs(ratio[k] - 1) <= 0.01) {
                    even++;
                    if (fabs(after.e[k] / before.e[k] - 1) > fabs(worst_even)) {
                        worst_even = after.e[k] / before.e[k] - 1;
                        even_layer = k;
                    }
                } else {
                    uneven++;
                    if (ratio[k] < r_lo) r_lo = ratio[k];
                    if (ratio[k] > r_hi) r_hi = ratio[k];
                }
                if (fabs(after.e[k] / before.e[k] - 1) > fabs(worst_e)) worst_e = after.e[k] / before.e[k] - 1;
                if (fabs(after.unscaled[k] / before.e[k] - 1) > fabs(worst_flow)) {
                    worst_flow = after.unscaled[k] / before.e[k] - 1;
                    worst_layer = k;
                }
            }
        printf("    %s: %zu shallow cells: |printed - mesh| mean %.4f -> %.4f mm (%.1fx), 95th percentile %.4f -> %.4f mm "
               "(%.1fx); highest above the mesh %.4f -> %.4f mm; deepest under the deposit %.4f mm; E per layer within "
               "%+.2f%% of PrusaSlicer's, within %+.2f%% (layer %zu of %d) taken back to the layer's height; steepest path "
               "%.1f degrees; travel under the layer's highest extrusion so far by %.4f mm at most\n",
               base_name(model), ea.cells, eb.mean, ea.mean, eb.mean / ea.mean, eb.p95, ea.p95, eb.p95 / ea.p95,
               eb.worst_above, ea.worst_above, gouge, 100 * worst_e, 100 * worst_flow, worst_layer + 1, before.layers,
               atan(after.steepest) * 180 / M_PI, after.low_travel);
        printf("    E per layer: %zu layers where the mesh holds PrusaSlicer's volume within 1 %%, E within %+.2f%% (layer %zu); "
               "%zu where it does not (mesh / planar %.3f to %.3f), E as the beads fill\n", even, 100 * worst_even,
               even_layer + 1, uneven, uneven ? r_lo : 1.0, uneven ? r_hi : 1.0);
        CHECKF(fabs(worst_even) <= 0.02, "E of layer %zu is %+.2f%% off PrusaSlicer's, where the mesh holds its volume",
               even_layer + 1, 100 * worst_even);
        CHECKF(ea.cells > 100 && eb.cells == ea.cells, "%zu cells measured (%zu before)", ea.cells, eb.cells);
        CHECKF(eb.mean >= min_gain * ea.mean, "mean %.4f -> %.4f mm", eb.mean, ea.mean);
        CHECKF(eb.p95 >= min_gain * ea.p95, "95th percentile %.4f -> %.4f mm", eb.p95, ea.p95);
        CHECKF(ea.worst_above <= 0.03, "a printed point %.4f mm above the mesh", ea.worst_above);
        CHECKF(gouge <= 1e-3, "a point %.4f mm under the deposit", gouge);
        CHECKF(fabs(worst_flow) <= 0.02, "E of layer %zu, taken back to the layer's height, is %+.2f%% off PrusaSlicer's",
               worst_layer + 1, 100 * worst_flow);
        CHECK(kept_byte_for_byte(before_path, after_path));
        /* the slope a path may take, and what 3 decimals of Z over a 0.05 mm piece add to it */
        CHECKF(after.steepest <= tan(15 * M_PI / 180) + 2e-3 / 0.05, "a path %.1f degrees steep", atan(after.steepest) * 180 / M_PI);
        CHECKF(after.low_travel <= 1e-6, "a travel %.4f mm under the layer's highest extrusion so far", after.low_travel);
    }
    free(before.segs);
    free(after.segs);
    free(ratio);
    finder_free(&f);
    adaslice_mesh_free(&mesh);
}

static double aerofoil_top(double x, double y)
{
    /* a 60 mm chord, 4 mm of thickness over a 1.5 mm slab, thinning 15 %
       towards the tips: slopes up to 12 degrees */
    double t = 1 - 0.15 * (2 * y / 30 - 1) * (2 * y / 30 - 1);
    return 1.5 + 4 * t * sin(M_PI * x / 60);
}

static void a_shallow_dome_is_printed_on_its_surface(void)
{
    adaslice_mesh m = gen_dome(20, 80, 2, 40, 96);
    cli_write_obj(cli_path("dome.obj"), &m);
    gen_free(&m);
    contour_case(cli_path("dome.obj"), 1, 0, 4);
}

/* The largest offset from the layer tops contour reports on its last line. */
static double reported_rise(const char *out)
{
    const char *at = strstr(out, "lowered, ");
    double lo, hi;
    return at && sscanf(at, "lowered, %lf to %lf", &lo, &hi) == 2 ? hi : -1;
}

/* A project from plan --hybrid carries the limits its residual was bounded
   with: contour takes them where the command line gives none (a smaller
   --max-rise than its default, half the layer, shows in how far it rises),
   and an option given still wins. */
static void a_hybrid_projects_limits_are_taken(void)
{
    char path3mf[300], gcode[300];
    cli_result r;
    double rise;
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("hybrid.3mf"));
    snprintf(gcode, sizeof gcode, "%s", cli_path("hybrid.gcode"));
    if (!prusa_gcode_after(cli_run("plan", "examples/models/shallow_dome.obj", PRUSA_FDM_ARGS, "--3mf", path3mf, "--hybrid",
                                   "--max-rise", "0.02", NULL),
                           path3mf, gcode, NULL))
        return;
    r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("taken.gcode"), NULL);
    rise = reported_rise(r.out);
    CHECKF(r.status == 0 && strstr(r.out, "the hybrid plan's limits: --max-angle 15 --max-rise 0.02 --resolution 0.2"),
           "exit %d: %.300s%.200s", r.status, r.out, r.err);
    CHECKF(rise > 0 && rise <= 0.0205, "rose %.4f mm over a layer top with the plan's --max-rise 0.02: %.300s", rise, r.out);
    cli_free(&r);
    r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("given.gcode"), "--max-rise", "0.04", NULL);
    rise = reported_rise(r.out);
    CHECKF(r.status == 0 && strstr(r.out, "--max-rise 0.04 --resolution 0.2"), "exit %d: %.300s%.200s", r.status, r.out,
           r.err);
    CHECKF(rise > 0.0205 && rise <= 0.0405, "rose %.4f mm with --max-rise 0.04 given", rise);
    cli_free(&r);
}

static void an_aerofoil_is_printed_on_its_surface(void)
{
    adaslice_mesh m = gen_heightfield(120, 30, 0, 0, 60, 30, aerofoil_top);
    cli_write_obj(cli_path("aerofoil.obj"), &m);
    gen_free(&m);
    contour_case(cli_path("aerofoil.obj"), 1, 1, 4);
}

static void the_bundled_hand_is_printed_on_its_surface(void)
{
    contour_case("examples/models/hand_closed.obj", 88.7, 0, 4);
}

/* ---- --top-skins */

#define SKIN_RISE 0.02          /* --max-rise of the top-skin cases: what modulation alone may do */
#define CLEARANCE 1.0           /* --nozzle-clearance */
#define CLEAR_ANGLE 30.0        /* --clearance-angle */
#define SQUAT_ANGLE 10.0        /* ... of a squat nozzle, whose cone reaches out far */

typedef struct spot { double x, y, z; int layer; } spot;

static int by_layer_x(const void *a, const void *b)
{
    int p = ((const spot *)a)->layer, q = ((const spot *)b)->layer;
    double x = ((const spot *)a)->x, y = ((const spot *)b)->x;
    return p != q ? (p < q ? -1 : 1) : x < y ? -1 : x > y;
}

static int by_x(const void *a, const void *b)
{
    double x = ((const spot *)a)->x, y = ((const spot *)b)->x;
    return x < y ? -1 : x > y;
}

/* Points every SAMPLE_MM along p's extrusions; those risen more than
   SKIN_RISE over their layer's top when `skins`. */
static spot *spots(const printed *p, int skins, size_t *count)
{
    size_t s, n = 0, cap = 1024;
    spot *out = (spot *)malloc(cap * sizeof *out);
    for (s = 0; s < p->n; s++) {
        const seg *g = &p->segs[s];
        int q, steps = (int)(hypot(g->b[0] - g->a[0], g->b[1] - g->a[1]) / SAMPLE_MM) + 1;
        for (q = 0; q <= steps; q++) {
            double t = (double)q / steps, z = g->a[2] + t * (g->b[2] - g->a[2]);
            if (skins && z <= p->top[g->layer] + SKIN_RISE + 2e-3) continue;
            if (n == cap) out = (spot *)realloc(out, (cap *= 2) * sizeof *out);
            out[n].x = g->a[0] + t * (g->b[0] - g->a[0]);
            out[n].y = g->a[1] + t * (g->b[1] - g->a[1]);
            out[n].z = z;
            out[n++].layer = g->layer;
        }
    }
    *count = n;
    return out;
}

/* The most by which a risen skin stands inside the nozzle cone of a print
   of a later layer: the cone's apex at the later bead's edge (beads
   2 BEAD_HALF wide, so the edges 2 BEAD_HALF closer than the centres), its
   flank `angle` degrees over the horizontal, up to CLEARANCE, where the heater
   block is. 0 when none does. Later paths of the same layer are left out:
   contour only promises them its layer's lowest, which this reader cannot
   tell apart from a path of the same run. */
static double worst_in_cone(const printed *p, double angle, size_t *skin_count)
{
    size_t ns, nb, i, k;
    spot *skin = spots(p, 1, &ns), *all = spots(p, 0, &nb);
    double worst = 0, t = tan(angle * M_PI / 180), reach = CLEARANCE / t + 2 * BEAD_HALF;
    double top_skin = -HUGE_VAL;
    int first_layer = 1 << 30;
    qsort(skin, ns, sizeof *skin, by_x);
    for (i = 0; i < ns; i++) {
        if (skin[i].z > top_skin) top_skin = skin[i].z;
        if (skin[i].layer < first_layer) first_layer = skin[i].layer;
    }
    for (k = 0; k < nb; k++) {
        size_t lo = 0, hi = ns;
        if (all[k].z >= top_skin || all[k].layer <= first_layer) continue; /* no skin above it, or none earlier */
        while (lo < hi) { /* the first skin at x >= all[k].x - reach */
            size_t mid = (lo + hi) / 2;
            if (skin[mid].x < all[k].x - reach) lo = mid + 1; else hi = mid;
        }
        for (i = lo; i < ns && skin[i].x <= all[k].x + reach; i++) {
            double d = hypot(skin[i].x - all[k].x, skin[i].y - all[k].y) - 2 * BEAD_HALF, up = skin[i].z - all[k].z, over;
            if (skin[i].layer >= all[k].layer || up <= 0) continue;
            over = up - (d > 0 ? d : 0) * t;
            if (up > CLEARANCE && up - CLEARANCE > over) over = up - CLEARANCE;
            if (over > worst) worst = over;
        }
    }
    free(skin);
    free(all);
    *skin_count = ns;
    return worst;
}

/* The shallow dome planned --hybrid and sliced by PrusaSlicer, contoured
   with modulation held to --max-rise SKIN_RISE, then with --top-skins as
   well: the skins' surface as printed comes closer to the mesh, no point
   stands 0.03 mm above it or under the deposit, and no risen skin is
   inside a later layer's nozzle cone. */
static void top_skins_follow_the_dome_further(void)
{
    char path3mf[300], gcode[300], mod[300], skins[300], rise[16];
    printed before, mp, sp;
    surface_error em, es;
    cli_result r;
    top_finder f;
    adaslice_load_options o;
    adaslice_mesh mesh;
    adaslice_error e;
    double lo[3], hi[3], shift[3], gouge, cone;
    size_t risen;
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("skins.3mf"));
    snprintf(gcode, sizeof gcode, "%s", cli_path("skins.gcode"));
    snprintf(mod, sizeof mod, "%s", cli_path("skins-mod.gcode"));
    snprintf(skins, sizeof skins, "%s", cli_path("skins-out.gcode"));
    snprintf(rise, sizeof rise, "%g", SKIN_RISE);
    if (!prusa_gcode_after(cli_run("plan", "examples/models/shallow_dome.obj", PRUSA_FDM_ARGS, "--3mf", path3mf, "--hybrid",
                                   NULL),
                           path3mf, gcode, NULL))
        return;
    r = cli_run("contour", gcode, "--project", path3mf, "-o", mod, "--max-rise", rise, NULL);
    CHECKF(r.status == 0, "contour: exit %d: %.300s", r.status, r.err);
    cli_free(&r);
    r = cli_run("contour", gcode, "--project", path3mf, "-o", skins, "--max-rise", rise, "--top-skins", "--nozzle-clearance",
                "1", "--clearance-angle", "30", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "top skins: "), "contour --top-skins: exit %d: %.300s", r.status, r.err);
    printf("    %s", r.out);
    cli_free(&r);
    memset(&o, 0, sizeof o);
    if (check_case_failed() || adaslice_mesh_load_file("examples/models/shallow_dome.obj", &o, &mesh, &e) != ADASLICE_OK)
        return;
    adaslice_mesh_bounds(&mesh, lo, hi);
    shift[0] = 125 - (lo[0] + hi[0]) / 2;
    shift[1] = 105 - (lo[1] + hi[1]) / 2;
    shift[2] = -lo[2];
    finder_init(&f, &mesh, shift);
    if (read_printed(gcode, &before) && read_printed(mod, &mp) && read_printed(skins, &sp)) {
        em = measure(&mp, &f, 15);
        es = measure(&sp, &f, 15);
        gouge = worst_gouge(&sp, &f);
        cone = worst_in_cone(&sp, CLEAR_ANGLE, &risen);
        printf("    shallow dome, --max-rise %g: |printed - mesh| mean %.4f -> %.4f mm with --top-skins, 95th percentile "
               "%.4f -> %.4f mm; highest above the mesh %.4f mm; %zu points risen past the rise, deepest under the deposit "
               "%.4f mm, deepest in a later nozzle's cone %.4f mm\n", SKIN_RISE, em.mean, es.mean, em.p95, es.p95,
               es.worst_above, risen, gouge, cone);
        CHECKF(es.cells == em.cells && es.cells > 100, "%zu cells, %zu with modulation alone", es.cells, em.cells);
        CHECKF(es.mean < 0.9 * em.mean && es.p95 <= em.p95, "mean %.4f, 95th percentile %.4f mm; modulation alone %.4f, %.4f",
               es.mean, es.p95, em.mean, em.p95);
        CHECKF(risen > 100, "%zu points risen past --max-rise", risen);
        CHECKF(es.worst_above <= 0.03, "a printed point %.4f mm above the mesh", es.worst_above);
        CHECKF(gouge <= 1e-3, "a point %.4f mm under the deposit", gouge);
        CHECKF(cone <= 2e-3, "a risen skin %.4f mm inside a later layer's nozzle cone", cone);
        free(mp.segs);
        free(sp.segs);
    }
    free(before.segs);
    finder_free(&f);
    adaslice_mesh_free(&mesh);
}

/* The shallow dome's cap (R 60 mm, 5 mm high on a 3 mm base) centred at
   (22, 20), cut by a 12 mm wall from x = WALL_X on, where the cap is still
   shallow (13.5 degrees). */
#define WALL_X 36.0
static double dome_and_wall(double x, double y)
{
    double r2 = (x - 22) * (x - 22) + (y - 20) * (y - 20);
    if (x >= WALL_X) return 12;
    return r2 < 24 * 24 ? 3 + sqrt(3600 - r2) - 55 : 3;
}

/* The dome beside a wall 12 mm tall (dome_and_wall), planned --hybrid: the
   dome's topmost skins would rise past --max-rise, but PrusaSlicer prints
   the wall's later layers right beside some of them, and contour may lower
   a later layer's path to a quarter layer over its bottom (README), so a
   skin risen there would stand in that nozzle's cone. The test finds those
   points itself: on the output's paths, where the mesh's surface (brute
   force) lies past the rise and within the clearance, no later layer of
   PrusaSlicer's G-code prints over the point, and a later layer's print
   (at its bottom plus a quarter layer) lies closer than the cone allows
   (as worst_in_cone); and contour must have kept every one of them within
   --max-rise, the wall forbidding some, while others rise. */
static void top_skins_keep_clear_of_a_wall_printed_later(void)
{
    char path3mf[300], gcode[300], out[300], rise[16];
    adaslice_mesh m = gen_heightfield(100, 80, 0, 0, 50, 40, dome_and_wall);
    printed before, after;
    cli_result r;
    top_finder f;
    spot *later = NULL, *on = NULL;
    size_t nl, no, k, i, refused = 0, must_refuse = 0, by_wall = 0, risen = 0, wrong = 0;
    double lo[3], hi[3], shift[3], t = tan(SQUAT_ANGLE * M_PI / 180), reach = CLEARANCE / t + 2 * BEAD_HALF, cone;
    char angle[16];
    cli_write_obj(cli_path("wall.obj"), &m);
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("wall.3mf"));
    snprintf(gcode, sizeof gcode, "%s", cli_path("wall.gcode"));
    snprintf(out, sizeof out, "%s", cli_path("wall-out.gcode"));
    snprintf(rise, sizeof rise, "%g", SKIN_RISE);
    if (!prusa_gcode_after(cli_run("plan", cli_path("wall.obj"), PRUSA_FDM_ARGS, "--3mf", path3mf, "--hybrid", NULL), path3mf,
                           gcode, NULL)) {
        gen_free(&m);
        return;
    }
    snprintf(angle, sizeof angle, "%g", SQUAT_ANGLE);
    r = cli_run("contour", gcode, "--project", path3mf, "-o", out, "--max-rise", rise, "--top-skins", "--nozzle-clearance",
                "1", "--clearance-angle", angle, NULL);
    CHECKF(r.status == 0, "contour --top-skins: exit %d: %.300s", r.status, r.err);
    printf("    %s", r.out);
    cli_free(&r);
    adaslice_mesh_bounds(&m, lo, hi);
    shift[0] = 125 - (lo[0] + hi[0]) / 2;
    shift[1] = 105 - (lo[1] + hi[1]) / 2;
    shift[2] = -lo[2];
    finder_init(&f, &m, shift);
    if (!check_case_failed() && read_printed(gcode, &before) && read_printed(out, &after)) {
        later = spots(&before, 0, &nl);
        on = spots(&after, 0, &no);
        for (k = 0; k < nl; k++) /* the lowest contour may print there */
            later[k].z = before.top[later[k].layer] - 0.75 * before.height[later[k].layer];
        qsort(later, nl, sizeof *later, by_layer_x);
        for (k = 0; k < no; k++) {
            const spot *a = &on[k];
            double z, c, top = after.top[a->layer];
            int blocked = 0, wall = 0, covered = 0, layer;
            /* on the dome, where the surface is past what modulation reaches but within the clearance */
            if (!mesh_top(&f, a->x, a->y, &z, &c) || c < cos(15 * M_PI / 180) || z <= top + SKIN_RISE + 5e-3 ||
                z > top + CLEARANCE)
                continue;
            /* the later layers whose lowest lies under the surface: the next one or two */
            for (layer = a->layer + 1; layer < before.layers && before.top[layer] - 0.75 * before.height[layer] < z &&
                                       !covered; layer++) {
                size_t first = 0, last = nl;
                while (first < last) { /* the first of this layer at x >= a->x - reach */
                    size_t mid = (first + last) / 2;
                    if (later[mid].layer < layer || (later[mid].layer == layer && later[mid].x < a->x - reach)) first = mid + 1;
                    else last = mid;
                }
                for (i = first; i < nl && later[i].layer == layer && later[i].x <= a->x + reach && !covered; i++) {
                    double d = hypot(later[i].x - a->x, later[i].y - a->y);
                    covered = d < BEAD_HALF;
                    if (z - later[i].z > (d > 2 * BEAD_HALF ? d - 2 * BEAD_HALF : 0) * t + 1e-3) {
                        blocked = 1;
                        wall |= later[i].x - shift[0] >= WALL_X - BEAD_HALF;
                    }
                }
            }
            if (covered) continue; /* inside the part: a later layer prints over it */
            if (a->z > top + SKIN_RISE + 2e-3) risen++;
            if (!blocked) continue;
            must_refuse++;
            by_wall += wall;
            if (a->z <= top + SKIN_RISE + 2e-3) refused++;
            else if (wrong++ < 3)
                CHECKF(0, "(%.3f, %.3f) of layer %d: risen to %.4f over the top %.4f, into a later print's nozzle cone "
                          "(surface %.4f)", a->x, a->y, a->layer + 1, a->z, top, z);
        }
        cone = worst_in_cone(&after, SQUAT_ANGLE, &i);
        printf("    dome beside a wall: %zu topmost skin points a later layer's nozzle cone forbids rising (%zu of them by "
               "the wall), %zu kept within --max-rise; %zu points risen; deepest in a later nozzle's cone %.4f mm\n",
               must_refuse, by_wall, refused, risen, cone);
        CHECKF(by_wall > 20 && refused == must_refuse, "%zu of %zu refused, %zu by the wall", refused, must_refuse, by_wall);
        CHECKF(risen > 20, "%zu points of the dome risen past --max-rise", risen);
        CHECKF(cone <= 2e-3, "a risen skin %.4f mm inside a later layer's nozzle cone", cone);
        free(later);
        free(on);
        free(before.segs);
        free(after.segs);
    }
    finder_free(&f);
    gen_free(&m);
}

/* ---- contour --svg-path, read back */

/* The numbers of attribute `name` of the first tag of svg that has it, up to n. */
static int svg_numbers(const char *svg, const char *name, double *v, int n)
{
    char key[64];
    const char *at;
    int k = 0;
    snprintf(key, sizeof key, " %s=\"", name);
    if (!(at = strstr(svg, key))) return 0;
    for (at += strlen(key); k < n && *at != '"'; k++) {
        char *end;
        v[k] = strtod(at, &end);
        if (end == at) break;
        for (at = end; *at == ' ' || *at == ','; at++) {}
    }
    return k;
}

/* The (s, z) points (mm) of the polylines with data-role `role`, taken back
   from pixels by the figure's own scales; the count. */
static size_t svg_line(const char *svg, const char *role, double *sz, size_t cap)
{
    double px0, kx, z0, py0, ky;
    char key[64];
    const char *at = svg;
    size_t n = 0;
    if (!svg_numbers(svg, "data-px0", &px0, 1) || !svg_numbers(svg, "data-px-per-mm", &kx, 1) ||
        !svg_numbers(svg, "data-z0", &z0, 1) || !svg_numbers(svg, "data-py0", &py0, 1) ||
        !svg_numbers(svg, "data-py-per-mm", &ky, 1))
        return 0;
    snprintf(key, sizeof key, "data-role=\"%s\"", role);
    while ((at = strstr(at, key)) != NULL) {
        char *end;
        at = strstr(at, "points=\"") + 8;
        while (*at != '"' && n < cap) {
            double x = strtod(at, &end), y;
            if (end == at || *end != ',') break;
            y = strtod(end + 1, &end);
            sz[2 * n] = (x - px0) / kx;
            sz[2 * n + 1] = z0 + (py0 - y) / ky;
            n++;
            for (at = end; *at == ' '; at++) {}
        }
    }
    return n;
}

/* contour --svg-path draws one move of a layer from the side: its ends are
   an extrusion of PrusaSlicer's G-code in that layer, the line before is
   that move's Z, the line after is every piece contour wrote for it (the
   output G-code read by the test's reader, in order), and the mesh line is
   the mesh's top there by brute force. */
static void the_svg_path_is_the_gcodes(void)
{
    char path3mf[300], gcode[300], out[300], svg_path[300], layer_text[16], *svg;
    printed before, after;
    cli_result r;
    double from[2] = {0, 0}, to[2] = {0, 0}, top = 0, *sz = (double *)malloc(2 * 20000 * sizeof *sz), length;
    size_t n, k, s, found = 0, matched = 0;
    int layer;
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("view.3mf"));
    snprintf(gcode, sizeof gcode, "%s", cli_path("view.gcode"));
    snprintf(out, sizeof out, "%s", cli_path("view-out.gcode"));
    snprintf(svg_path, sizeof svg_path, "%s", cli_path("view.svg"));
    if (!prusa_gcode_after(cli_run("plan", "examples/models/shallow_dome.obj", PRUSA_FDM_ARGS, "--3mf", path3mf, "--hybrid",
                                   NULL),
                           path3mf, gcode, NULL) ||
        !read_printed(gcode, &before)) {
        free(sz);
        return;
    }
    /* the layer under the last: a ring of top infill across the dome */
    layer = before.layers - 1;
    snprintf(layer_text, sizeof layer_text, "%d", layer);
    r = cli_run("contour", gcode, "--project", path3mf, "-o", out, "--svg-path", layer_text, svg_path, NULL);
    CHECKF(r.status == 0, "contour --svg-path: exit %d: %.300s", r.status, r.err);
    cli_free(&r);
    svg = read_whole_text(svg_path);
    if (!svg || !read_printed(out, &after)) { CHECK(svg != NULL); free(svg); free(sz); free(before.segs); return; }
    CHECK(svg_numbers(svg, "data-from", from, 2) == 2 && svg_numbers(svg, "data-to", to, 2) == 2 &&
          svg_numbers(svg, "data-z-top", &top, 1) == 1);
    CHECKF(fabs(top - before.top[layer - 1]) < 1e-9, "data-z-top %g, the layer's ;Z: %g", top, before.top[layer - 1]);
    length = hypot(to[0] - from[0], to[1] - from[1]);
    /* before: one of PrusaSlicer's extrusions of that layer, flat at its Z */
    for (s = 0; s < before.n; s++) {
        const seg *g = &before.segs[s];
        if (g->layer == layer - 1 && hypot(g->a[0] - from[0], g->a[1] - from[1]) < 1e-6 &&
            hypot(g->b[0] - to[0], g->b[1] - to[1]) < 1e-6) {
            n = svg_line(svg, "before", sz, 20000);
            CHECKF(n == 2 && fabs(sz[0]) < 1e-3 && fabs(sz[2] - length) < 1e-3 && fabs(sz[1] - g->a[2]) < 1e-5 &&
                       fabs(sz[3] - g->b[2]) < 1e-5,
                   "before: %zu points, (%g, %g) to (%g, %g); the move is %g mm at Z %g", n, sz[0], sz[1], sz[2], sz[3],
                   length, g->a[2]);
            found++;
        }
    }
    CHECKF(found == 1, "%zu extrusions of layer %d run from (%g, %g) to (%g, %g)", found, layer, from[0], from[1], to[0], to[1]);
    /* after: the output's extrusions of the layer on that line, from its start to its end */
    n = svg_line(svg, "after", sz, 20000);
    for (s = 0; s < after.n && matched + 1 < n; s++) {
        const seg *g = &after.segs[s];
        double sa = hypot(g->a[0] - from[0], g->a[1] - from[1]), sb = hypot(g->b[0] - from[0], g->b[1] - from[1]);
        if (g->layer != layer - 1) continue;
        if (matched == 0 && !(sa < 2e-3 && fabs(sz[1] - g->a[2]) < 2e-3)) continue;
        CHECKF(fabs(sa - sz[2 * matched]) < 2e-3 && fabs(g->a[2] - sz[2 * matched + 1]) < 1.5e-3 &&
                   fabs(sb - sz[2 * matched + 2]) < 2e-3 && fabs(g->b[2] - sz[2 * matched + 3]) < 1.5e-3,
               "after, piece %zu: the G-code's (%g, %g) to (%g, %g) mm along and up, the SVG's (%g, %g) to (%g, %g)",
               matched + 1, sa, g->a[2], sb, g->b[2], sz[2 * matched], sz[2 * matched + 1], sz[2 * matched + 2],
               sz[2 * matched + 3]);
        if (check_case_failed()) break;
        matched++;
    }
    CHECKF(n > 2 && matched + 1 == n && fabs(sz[2 * n - 2] - length) < 2e-3,
           "after: %zu of the SVG's %zu points are the output's pieces, in order", matched + 1, n);
    /* the mesh: its top under the path, by the test's own ray casts */
    {
        adaslice_load_options o;
        adaslice_mesh mesh;
        adaslice_error e;
        top_finder f;
        double lo[3], hi[3], shift[3], worst = 0;
        memset(&o, 0, sizeof o);
        if (adaslice_mesh_load_file("examples/models/shallow_dome.obj", &o, &mesh, &e) == ADASLICE_OK) {
            adaslice_mesh_bounds(&mesh, lo, hi);
            shift[0] = 125 - (lo[0] + hi[0]) / 2;
            shift[1] = 105 - (lo[1] + hi[1]) / 2;
            shift[2] = -lo[2];
            finder_init(&f, &mesh, shift);
            n = svg_line(svg, "mesh", sz, 20000);
            for (k = 0; k < n; k++) {
                double t = sz[2 * k] / length, z, c;
                if (mesh_top(&f, from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1]), &z, &c) &&
                    fabs(z - sz[2 * k + 1]) > worst)
                    worst = fabs(z - sz[2 * k + 1]);
            }
            CHECKF(n > length / 0.05 && worst < 2e-3, "mesh: %zu points, %.4f mm off the mesh's top at worst", n, worst);
            finder_free(&f);
            adaslice_mesh_free(&mesh);
        }
    }
    free(svg);
    free(sz);
    free(before.segs);
    free(after.segs);
}

/* text with its first `what` replaced by `with` (malloc'd) */
static char *edited(const char *text, const char *what, const char *with)
{
    const char *at = strstr(text, what);
    size_t n = strlen(text), keep = at ? (size_t)(at - text) : n;
    char *out = (char *)malloc(n + strlen(with) + 1);
    memcpy(out, text, keep);
    strcpy(out + keep, with);
    strcat(out, at ? at + strlen(what) : "");
    return out;
}

/* The 3MF at `from` written to `to` with member `name`'s first `what`
   replaced by `with` (a member that is not there is added, as `with`).
   1 when written. */
static int edited_3mf(const char *from, const char *to, const char *name, const char *what, const char *with)
{
    static const char *const members[] = {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model",
                                          "Metadata/Slic3r_PE_layer_heights_profile.txt",
                                          "Metadata/layer_heights_profile.txt", "Metadata/Slic3r_PE.config",
                                          THREEMF_CONTOUR_PART};
    unsigned char *data, *member;
    zip_writer *z;
    size_t n, size, k;
    char why[128];
    int ok = 1, found = 0;
    if (!(data = read_whole_file(from, &n)) || zip_open(&z, to)) { free(data); return 0; }
    for (k = 0; k < sizeof members / sizeof *members && ok; k++) {
        int got = zip_member(data, n, members[k], &member, &size, why);
        if (got < 0) ok = 0;
        if (got) {
            if (strcmp(members[k], name)) continue;
            member = (unsigned char *)calloc(1, 1);
            size = 0;
        }
        if (!strcmp(members[k], name)) {
            char *changed, *text = (char *)malloc(size + 1);
            memcpy(text, member, size);
            text[size] = 0;
            changed = what && *what ? edited(text, what, with) : (char *)strcpy((char *)malloc(strlen(with) + 1), with);
            ok = ok && strcmp(changed, text) && !zip_add(z, members[k], changed, strlen(changed), 1);
            found = 1;
            free(changed);
            free(text);
        } else ok = ok && !zip_add(z, members[k], member, size, 1);
        free(member);
    }
    free(data);
    return !zip_close(z, ok && found) && ok && found;
}

/* A small dome (stem.obj) planned into stem.3mf and sliced by PrusaSlicer
   into stem.gcode (paths in path3mf and gcode): the G-code's text, NULL
   after a failed check. */
static char *sliced_small_dome(const char *stem, char *path3mf, char *gcode)
{
    adaslice_mesh m = gen_dome(10, 40, 1, 10, 48);
    char obj[300];
    snprintf(obj, sizeof obj, "%s/%s.obj", cli_dir, stem);
    snprintf(path3mf, 300, "%s/%s.3mf", cli_dir, stem);
    snprintf(gcode, 300, "%s/%s.gcode", cli_dir, stem);
    cli_write_obj(obj, &m);
    gen_free(&m);
    if (!prusa_gcode_after(cli_run("plan", obj, PRUSA_FDM_ARGS, "--3mf", path3mf, NULL), path3mf, gcode, NULL)) return NULL;
    return read_whole_text(gcode);
}

static void refused_inputs_get_one_line_and_no_file(void)
{
    static const char *const cases[][3] = {
        /* what, with, the message */
        {"\n;TYPE:Solid infill", "\nG2 X100 Y100 I1 J0 E0.1\n;TYPE:Solid infill", "arc G2"},
        {"\n;TYPE:Solid infill", "\nG3 X100 Y100 I1 J0 E0.1\n;TYPE:Solid infill", "arc G3"},
        {"\nG90 ", "\nG91 ", "G91, relative X Y Z"},
        {"; generated by PrusaSlicer", "; generated by Cura_SteamEngine", "not PrusaSlicer's G-code"},
        {"; gcode_flavor = reprap", "; gcode_flavor = makerware", "gcode_flavor makerware"},
        {"\nG21 ", "\nG20 ", "G20, inches"},
        {"\nG90 ", "\nG92 X10\nG90 ", "G92 sets X, Y or Z"},
        /* a travel to 1.8e18 mm wrapped the count of pieces its run was cut into (ASan: a heap overflow) */
        {"\nG1 X", "\nG1 X1844674407370955300 Y99.809 F7800\nG1 X", "X 1.84467e+18 mm: beyond any printer's reach"},
        /* contour takes each layer's plane from its ;Z: comment: a Z moved
           within the layer lifted every path after it (exit 0) */
        {"\n;TYPE:Solid infill", "\n;TYPE:Solid infill\nG1 Z5", "extruded at Z 5 in the layer that"},
        /* a bead's E follows the layer's height: 0.001 made E 12 times the file's */
        {"\n;HEIGHT:", "\n;HEIGHT:0.001\n;HEIGHT:", ";HEIGHT:0.001, but"},
        {"; z_offset = 0", "; z_offset = 0abc", "z_offset 0abc"},
        {"; spiral_vase = 0", "; spiral_vase = 1", "spiral_vase = 1"},
    };
    char path3mf[300], gcode[300], *text;
    adaslice_mesh other = gen_box(0, 0, 0, 30, 20, 3);
    cli_result r;
    size_t c;
    cli_write_obj(cli_path("other.obj"), &other);
    gen_free(&other);
    if (!(text = sliced_small_dome("small", path3mf, gcode))) return;
    /* the unedited file is taken */
    r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("ok.gcode"), NULL);
    CHECKF(r.status == 0 && cli_exists(cli_path("ok.gcode")), "exit %d: %.300s", r.status, r.err);
    cli_free(&r);
    for (c = 0; c < sizeof cases / sizeof *cases; c++) {
        char *bad = edited(text, cases[c][0], cases[c][1]);
        CHECKF(strcmp(bad, text) != 0, "case %zu: %.40s is not in PrusaSlicer's G-code", c, cases[c][0]);
        cli_write(cli_path("bad.gcode"), bad);
        free(bad);
        r = cli_run("contour", cli_path("bad.gcode"), "--project", path3mf, "-o", cli_path("out.gcode"), NULL);
        CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, cases[c][2]), "%s: exit %d: %.300s", cases[c][2],
               r.status, r.err);
        CHECKF(!cli_exists(cli_path("out.gcode")), "%s: out.gcode written", cases[c][2]);
        cli_free(&r);
    }
    /* a layer's ;Z: lost: its moves taken as the layer below's, whose
       plane is lower; contour put the nozzle into the layer it printed */
    {
        const char *z1 = strstr(text, "\n;Z:"), *z2 = z1 ? strstr(z1 + 1, "\n;Z:") : NULL, *end = z2 ? strchr(z2 + 1, '\n') : NULL;
        CHECK(end);
        if (end) {
            char *bad = (char *)malloc(strlen(text) + 1);
            memcpy(bad, text, (size_t)(z2 - text));
            strcpy(bad + (z2 - text), end);
            cli_write(cli_path("bad.gcode"), bad);
            free(bad);
            r = cli_run("contour", cli_path("bad.gcode"), "--project", path3mf, "-o", cli_path("out.gcode"), NULL);
            CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "the ;Z: comments do not follow the moves"),
                   "a ;Z: removed: exit %d: %.300s", r.status, r.err);
            CHECK(!cli_exists(cli_path("out.gcode")));
            cli_free(&r);
        }
    }
    {
        static const char *const usage[][3] = {{"--max-angle", "90", "--max-angle 90"},
                                                {"--resolution", "0.001", "--resolution 0.001"},
                                                {"--max-rise", "-1", "--max-rise"},
                                                {"--max-rise", "1e300", "--max-rise 1e+300"},
                                                {"--clearance-angle", "90", "--clearance-angle 90"},
                                                {"--nozzle-clearance", "1", "are for --top-skins"},
                                                {"--top-skins", "--top-skins", "--top-skins needs --nozzle-clearance"},
                                                {"--svg-path", "1", "needs the SVG's path after the layer"}};
        for (c = 0; c < sizeof usage / sizeof *usage; c++) {
            r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("out.gcode"), usage[c][0], usage[c][1], NULL);
            CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, usage[c][2]), "exit %d: %.300s", r.status, r.err);
            CHECK(!cli_exists(cli_path("out.gcode")));
            cli_free(&r);
        }
        r = cli_run("contour", gcode, "-o", cli_path("out.gcode"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--project"), "exit %d: %.300s", r.status, r.err);
        cli_free(&r);
        /* the picture onto the G-code: one would replace the other */
        r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("out.gcode"), "--svg-path", "1",
                    cli_path("out.gcode"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "are one file"), "exit %d: %.300s", r.status, r.err);
        CHECK(!cli_exists(cli_path("out.gcode")));
        cli_free(&r);
    }
    /* the project's own parts damaged or crafted: each refused in one line,
       nothing written; and the build item's tag first in the model's text
       (its attributes once read the byte before the text) is read as it is */
    {
        static const char *const projects[][4] = {
            {THREEMF_CONTOUR_PART, "", "; max_angle = 120\n", "max_angle = 120"},
            {THREEMF_CONTOUR_PART, "", "; resolution = 1e-20\n", "resolution = 1e-20"},
            {THREEMF_CONTOUR_PART, "", "; max_rise = 0x10\n", "max_rise = 0x10"},
            {"3D/3dmodel.model", "<vertex x=\"", "<vertex x=\"24abc", "vertex 0 has no x, y and z"},
            {"3D/3dmodel.model", "<vertex x=\"", "<vertex x=\"-1e30", "vertex 0 has no x, y and z"},
            {"Metadata/Slic3r_PE_layer_heights_profile.txt", "|", "|0;0.2;0.2;0.2;0.2;0.2;0.2;0.2;", "not above the one before"},
        };
        char *model_text;
        for (c = 0; c < sizeof projects / sizeof *projects; c++) {
            CHECKF(edited_3mf(path3mf, cli_path("edited.3mf"), projects[c][0], projects[c][1], projects[c][2]),
                   "case %zu: %s not edited", c, projects[c][0]);
            r = cli_run("contour", gcode, "--project", cli_path("edited.3mf"), "-o", cli_path("out.gcode"), NULL);
            CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, projects[c][3]), "%s: exit %d: %.300s",
                   projects[c][3], r.status, r.err);
            CHECKF(!cli_exists(cli_path("out.gcode")), "%s: out.gcode written", projects[c][3]);
            cli_free(&r);
        }
        /* the item's tag moved to the model text's first byte */
        {
            unsigned char *data = read_whole_file(path3mf, NULL), *model = NULL;
            size_t n = 0, size = 0;
            char why[128], *item, *end, *moved;
            FILE *probe = fopen(path3mf, "rb");
            if (probe) { fseek(probe, 0, SEEK_END); n = (size_t)ftell(probe); fclose(probe); }
            CHECK(data && !zip_member(data, n, "3D/3dmodel.model", &model, &size, why));
            model_text = model ? (char *)calloc(size + 1, 1) : NULL;
            if (model_text) memcpy(model_text, model, size);
            item = model_text ? strstr(model_text, "<item ") : NULL;
            end = item ? strchr(item, '>') : NULL;
            CHECK(item && end);
            if (item && end) {
                size_t len = (size_t)(end + 1 - item);
                moved = (char *)malloc(size + 1);
                memcpy(moved, item, len);
                memcpy(moved + len, model_text, (size_t)(item - model_text));
                strcpy(moved + len + (item - model_text), end + 1);
                /* the whole text as the member: edited_3mf replaces it (what "" adds as given) */
                CHECK(edited_3mf(path3mf, cli_path("edited.3mf"), "3D/3dmodel.model", model_text, moved));
                r = cli_run("contour", gcode, "--project", cli_path("edited.3mf"), "-o", cli_path("out.gcode"), NULL);
                CHECKF(r.status == 0, "the item's tag first: exit %d: %.300s", r.status, r.err);
                cli_free(&r);
                remove(cli_path("out.gcode"));
                free(moved);
            }
            free(model_text);
            free(model);
            free(data);
        }
    }
    /* another part's project: a box of another size, and the same part
       planned with other layers */
    r = cli_run("plan", cli_path("other.obj"), PRUSA_FDM_ARGS, "--3mf", cli_path("other.3mf"), NULL);
    CHECKF(r.status == 0, "plan: %.300s", r.err);
    cli_free(&r);
    r = cli_run("plan", cli_path("small.obj"), "--tmin", "0.08", "--tmax", "0.28", "--eps", "0.2", "--3mf",
                cli_path("finer.3mf"), NULL);
    CHECKF(r.status == 0, "plan: %.300s", r.err);
    cli_free(&r);
    r = cli_run("contour", gcode, "--project", cli_path("other.3mf"), "-o", cli_path("out.gcode"), NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "not the part the project holds"), "exit %d: %.300s",
           r.status, r.err);
    CHECK(!cli_exists(cli_path("out.gcode")));
    cli_free(&r);
    r = cli_run("contour", gcode, "--project", cli_path("finer.3mf"), "-o", cli_path("out.gcode"), NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "not sliced from this project"), "exit %d: %.300s",
           r.status, r.err);
    CHECK(!cli_exists(cli_path("out.gcode")));
    cli_free(&r);
    free(text);
}

/* text with every move's Z word `dz` higher, as PrusaSlicer's z_offset
   writes it (the ;Z: comments stay), and "; z_offset = 0" said so. */
static char *z_moved(const char *text, double dz, const char *said, size_t *moved)
{
    size_t n = strlen(text), cap = n + n / 4 + 256, len = 0;
    char *out = (char *)malloc(cap), *with;
    const char *line = text;
    *moved = 0;
    while (*line) {
        const char *end = strchr(line, '\n'), *z = NULL, *p;
        size_t l = end ? (size_t)(end + 1 - line) : strlen(line);
        if (!strncmp(line, "G1 ", 3) || !strncmp(line, "G0 ", 3))
            for (p = line; p < line + l && *p != ';'; p++)
                if (p[0] == ' ' && p[1] == 'Z') { z = p + 2; break; }
        if (len + l + 32 > cap) out = (char *)realloc(out, cap *= 2);
        if (z) {
            char *after;
            double v = strtod(z, &after);
            memcpy(out + len, line, (size_t)(z - line));
            len += (size_t)(z - line);
            len += (size_t)sprintf(out + len, "%.3f", v + dz);
            memcpy(out + len, after, l - (size_t)(after - line));
            len += l - (size_t)(after - line);
            (*moved)++;
        } else {
            memcpy(out + len, line, l);
            len += l;
        }
        line += l;
    }
    out[len] = 0;
    with = edited(out, "; z_offset = 0\n", said);
    free(out);
    return with;
}

/* PrusaSlicer's z_offset puts every move that far above the layer's ;Z:
   comment: contour's output of such a file is the plain file's with every
   Z that much higher, line for line (it once put the contoured paths at
   ;Z:, into what the layer printed, 0.15 mm down); and PrusaSlicer's own
   file with --z-offset is taken. */
static void z_offset_moves_every_z(void)
{
    char path3mf[300], gcode[300], *text, *shifted, *a = NULL, *b = NULL, *pa, *pb;
    size_t moved = 0, lines = 0, zs = 0, bad = 0;
    int shown = 0;
    cli_result r;
    if (!(text = sliced_small_dome("zo", path3mf, gcode))) return;
    CHECK(strstr(text, "\n; z_offset = 0\n"));
    if (check_case_failed()) { free(text); return; }
    shifted = z_moved(text, 0.15, "; z_offset = 0.15\n", &moved);
    cli_write(cli_path("zo15.gcode"), shifted);
    free(shifted);
    free(text);
    r = cli_run("contour", gcode, "--project", path3mf, "-o", cli_path("zo.out"), NULL);
    CHECKF(r.status == 0, "exit %d: %.300s", r.status, r.err);
    cli_free(&r);
    r = cli_run("contour", cli_path("zo15.gcode"), "--project", path3mf, "-o", cli_path("zo15.out"), NULL);
    CHECKF(r.status == 0, "z_offset 0.15: exit %d: %.300s", r.status, r.err);
    cli_free(&r);
    a = read_whole_text(cli_path("zo.out"));
    b = read_whole_text(cli_path("zo15.out"));
    CHECK(a && b);
    for (pa = a, pb = b; pa && pb && *pa && *pb; lines++) {
        char *ea = strchr(pa, '\n'), *eb = strchr(pb, '\n'), *za, *zb;
        size_t la = ea ? (size_t)(ea - pa) : strlen(pa), lb = eb ? (size_t)(eb - pb) : strlen(pb);
        /* the same line but for the Z word's number */
        za = !strncmp(pa, "G1 ", 3) ? strstr(pa, " Z") : NULL;
        zb = !strncmp(pb, "G1 ", 3) ? strstr(pb, " Z") : NULL;
        if (za && za - pa < (long)la && zb && zb - pb < (long)lb && za - pa == zb - pb && !strncmp(pa, pb, (size_t)(za - pa))) {
            char *ra, *rb;
            double va = strtod(za + 2, &ra), vb = strtod(zb + 2, &rb);
            zs++;
            if (fabs(vb - va - 0.15) > 1.5e-3 || la - (size_t)(ra - pa) != lb - (size_t)(rb - pb) ||
                strncmp(ra, rb, la - (size_t)(ra - pa)))
                bad++;
        } else if (la != lb || strncmp(pa, pb, la)) {
            if (!strstr(pa, "z_offset")) bad++;
        }
        if (bad && !shown) shown = printf("    first difference, line %zu: %.*s | %.*s\n", lines + 1, (int)la, pa, (int)lb, pb);
        pa = ea ? ea + 1 : pa + la;
        pb = eb ? eb + 1 : pb + lb;
    }
    CHECKF(a && b && !*pa && !*pb && bad == 0 && zs > moved, "%zu lines, %zu of them with Z (%zu in the file), %zu differ",
           lines, zs, moved, bad);
    free(a);
    free(b);
    /* PrusaSlicer's own */
    if (!prusa_gcode_after(cli_run("plan", cli_path("zo.obj"), PRUSA_FDM_ARGS, "--3mf", path3mf, NULL), path3mf,
                           cli_path("zo-prusa.gcode"), "--z-offset=0.15"))
        return;
    r = cli_run("contour", cli_path("zo-prusa.gcode"), "--project", path3mf, "-o", cli_path("zo-prusa.out"), NULL);
    CHECKF(r.status == 0 && strstr(r.out, "shifted") && strstr(r.out, "contoured"), "PrusaSlicer's --z-offset 0.15: exit %d: %.300s",
           r.status, r.err);
    cli_free(&r);
}

void test_contour(void)
{
    if (!cli_begin("adaslice-contour")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("prusa-slicer", a_shallow_dome_is_printed_on_its_surface);
    RUN_NEEDING("prusa-slicer", an_aerofoil_is_printed_on_its_surface);
    RUN_NEEDING("prusa-slicer", the_bundled_hand_is_printed_on_its_surface);
    RUN_NEEDING("prusa-slicer", refused_inputs_get_one_line_and_no_file);
    RUN_NEEDING("prusa-slicer", z_offset_moves_every_z);
    RUN_NEEDING("prusa-slicer", a_hybrid_projects_limits_are_taken);
    RUN_NEEDING("prusa-slicer", the_svg_path_is_the_gcodes);
    RUN_NEEDING("prusa-slicer", top_skins_follow_the_dome_further);
    RUN_NEEDING("prusa-slicer", top_skins_keep_clear_of_a_wall_printed_later);
    cli_end();
}
