/* The FDM project: see threemf.h. The 3MF parts are the 3MF Consortium's
   core specification (1.3): [Content_Types].xml, _rels/.rels and the model
   part 3D/3dmodel.model. */
#include "threemf.h"
#include "../options.h"
#include "../output.h"
#include "../report.h"
#include "../codec/zip.h"
#include "../gcode.h"

#include <errno.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* A number as the file will hold it (%.9g). */
static double as_written(double z)
{
    char text[32];
    snprintf(text, sizeof text, "%.9g", z);
    return strtod(text, NULL);
}

int threemf_options(int argc, char **argv, threemf_args *t, int *rest_argc, char **rest)
{
    int i, rc = RC_OK;
    adaslice_hybrid_options *h = &t->contour;
    memset(t, 0, sizeof *t);
    t->nozzle = 0.4;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (!strcmp(o, "--3mf")) {
            const char *dot;
            rc = file_option(argc, argv, &i, &t->path);
            /* a 3MF named .stl would be read back as an STL; a stream or device has no name to mislead */
            dot = rc ? NULL : strrchr(t->path, '.');
            if (!rc && output_kind(t->path) != OUT_STRAIGHT &&
                (!dot || strchr(dot, '/') || dot[-1] == '/' || dot == t->path || strcasecmp(dot, ".3mf")))
                rc = complain(RC_USAGE, "--3mf %s: the name must end in .3mf", t->path);
        }
        else if (!strcmp(o, "--nozzle")) {
            if (!(rc = number_option(argc, argv, &i, 0, &t->nozzle)) &&
                !(t->nozzle >= THREEMF_MIN_NOZZLE && t->nozzle <= THREEMF_MAX_NOZZLE))
                rc = complain(RC_USAGE, "--nozzle %g: an FDM nozzle is %g to %g mm", t->nozzle, THREEMF_MIN_NOZZLE,
                              THREEMF_MAX_NOZZLE);
            t->nozzle_given = 1;
        }
        else if (!strcmp(o, "--hybrid")) t->hybrid = 1;
        else if (!strcmp(o, "--max-angle")) rc = number_option(argc, argv, &i, 0, &h->max_angle);
        else if (!strcmp(o, "--reach")) rc = number_option(argc, argv, &i, 0, &h->reach);
        else if (!strcmp(o, "--max-rise")) rc = number_option(argc, argv, &i, 0, &h->rise);
        else if (!strcmp(o, "--resolution")) rc = number_option(argc, argv, &i, 0, &h->resolution);
        else { rest[(*rest_argc)++] = argv[i]; continue; }
        if (strcmp(o, "--3mf") && strcmp(o, "--nozzle") && strcmp(o, "--hybrid")) t->contour_given = 1;
    }
    /* what the project says, contour takes: plan --hybrid --resolution 1e-300 made a project contour refused;
       checked as the project will hold it (999999.9999 is written 1000000) */
    if (!rc && h->rise) rc = contour_limit_check("--max-rise ", "max_rise", as_written(h->rise), RC_USAGE);
    if (!rc && h->resolution) rc = contour_limit_check("--resolution ", "resolution", as_written(h->resolution), RC_USAGE);
    if (!rc && h->reach && !(h->reach < CONTOUR_MAX_LIMIT))
        rc = complain(RC_USAGE, "--reach %g: under %g mm", h->reach, CONTOUR_MAX_LIMIT);
    if (!rc && t->nozzle_given && !t->path) rc = complain(RC_USAGE, "--nozzle is the 3MF's printer's: add --3mf FILE");
    if (!rc && t->hybrid && h->max_angle == 0) h->max_angle = ADASLICE_DEFAULT_MAX_ANGLE;
    if (!rc && !(h->max_angle <= 45))
        rc = complain(RC_USAGE, "--max-angle %g: the contour follows faces up to 45 degrees from horizontal, "
                                "no steeper (a nozzle's flanks clear no more)", h->max_angle);
    return rc;
}

void threemf_usage(FILE *f)
{
    fputs("FDM project\n"
          "  --3mf FILE          a 3MF of the model with the plan as PrusaSlicer's and\n"
          "                      OrcaSlicer's variable layer height profile; for a 0.4 mm\n"
          "                      nozzle plan with e.g. --tmin 0.08 --tmax 0.28 --eps 0.1\n"
          "  --nozzle MM         its nozzle: layers up to 75% of it               [0.4]\n"
          "  --hybrid            plan for adaslice contour: faces facing up no steeper\n"
          "                      than --max-angle and reachable print without stair\n"
          "                      steps, so only the walls set the layers; reports the\n"
          "                      layers and time saved against planar layers of the\n"
          "                      same worst printed error (needs --3mf, cusp metric)\n"
          "  --max-angle DEG     the steepest face contoured, from horizontal, (0, 45] [15]\n"
          "  --reach MM          the nozzle cone's radius that must be clear of the part [2]\n"
          "  --max-rise MM       the contour's largest Z offset from a layer [tmax/2]\n"
          "  --resolution MM     the contour's longest path segment              [0.2]\n", f);
}

int threemf_check_bounds(const threemf_args *t, const plan_args *a)
{
    double most = THREEMF_MAX_OF_NOZZLE * t->nozzle;
    if (a->tmax > most * (1 + 1e-9))
        return complain(RC_USAGE, "--tmax %g: a %g mm nozzle lays layers up to %g mm (PrusaSlicer's limit, %g%% of the "
                                  "nozzle); give a lower --tmax or --nozzle", a->tmax, t->nozzle, most,
                        100 * THREEMF_MAX_OF_NOZZLE);
    if (a->tmin < THREEMF_MIN_LAYER)
        return complain(RC_USAGE, "--tmin %g: the slicers' thinnest layer is %g mm", a->tmin, THREEMF_MIN_LAYER);
    return RC_OK;
}

int threemf_check_hybrid(const threemf_args *t, const plan_args *a)
{
    if (t->contour_given && !t->hybrid)
        return complain(RC_USAGE, "--max-angle, --reach, --max-rise and --resolution set up --hybrid: add it");
    if (!t->hybrid) return RC_OK;
    if (!t->path) return complain(RC_USAGE, "--hybrid needs --3mf FILE: the FDM project adaslice contour reads");
    if (a->metric != ADASLICE_METRIC_CUSP)
        return complain(RC_USAGE, "--hybrid charges contoured faces in cusp height, not --metric %s", METRIC_NAMES[a->metric]);
    return RC_OK;
}

typedef struct project {
    const adaslice_mesh *mesh;
    const double *tops;          /* K layer tops, mm above the part's bottom, as written */
    size_t layers;
    double tmin, tmax;
    const threemf_args *args;
    const plan_job *job;         /* --hybrid: its residual per face */
    double z0;
    double (*span)[2];           /* --hybrid: room for a height range per face */
} project;

static void write_content_types(FILE *f, const void *ctx)
{
    (void)ctx;
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
          "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">\n"
          " <Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>\n"
          " <Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/>\n"
          " <Default Extension=\"txt\" ContentType=\"text/plain\"/>\n"
          " <Default Extension=\"config\" ContentType=\"text/plain\"/>\n"
          "</Types>\n", f);
}

static void write_rels(FILE *f, const void *ctx)
{
    (void)ctx;
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
          "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\n"
          " <Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
          "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/>\n"
          "</Relationships>\n", f);
}

static void write_model(FILE *f, const void *ctx)
{
    const adaslice_mesh *m = ((const project *)ctx)->mesh;
    size_t i;
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
          "<model unit=\"millimeter\" xml:lang=\"en-US\" "
          "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n"
          " <metadata name=\"Application\">adaslice " ADASLICE_VERSION "</metadata>\n"
          " <resources>\n  <object id=\"1\" type=\"model\">\n   <mesh>\n    <vertices>\n", f);
    /* float32 coordinates, so nine digits give them back exactly */
    for (i = 0; i < m->vertex_count; i++)
        fprintf(f, "     <vertex x=\"%.9g\" y=\"%.9g\" z=\"%.9g\"/>\n", m->vertices[3 * i], m->vertices[3 * i + 1],
                m->vertices[3 * i + 2]);
    fputs("    </vertices>\n    <triangles>\n", f);
    for (i = 0; i < m->triangle_count; i++)
        fprintf(f, "     <triangle v1=\"%u\" v2=\"%u\" v3=\"%u\"/>\n", m->triangles[3 * i], m->triangles[3 * i + 1],
                m->triangles[3 * i + 2]);
    fputs("    </triangles>\n   </mesh>\n  </object>\n </resources>\n <build>\n  <item objectid=\"1\"/>\n </build>\n"
          "</model>\n", f);
}

/* Both slicers read the same line: the 1-based object and (z, h) pairs. */
static void write_profile(FILE *f, const void *ctx)
{
    const project *p = (const project *)ctx;
    double below = 0;
    size_t k;
    fputs("object_id=1|", f);
    for (k = 0; k < p->layers; k++) {
        double h = p->tops[k] - below;
        fprintf(f, "%s%.9g;%.9g;%.9g;%.9g", k ? ";" : "", below, h, p->tops[k], h);
        below = p->tops[k];
    }
    fputc('\n', f);
}

static void write_config(FILE *f, const void *ctx)
{
    const project *p = (const project *)ctx;
    fprintf(f, "; generated by adaslice %s\n; first_layer_height = %.9g\n; min_layer_height = %.9g\n"
               "; max_layer_height = %.9g\n; variable_layer_height = 1\n",
            ADASLICE_VERSION, p->tops[0], p->tmin, p->tmax);
}

static int by_low(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Ranges "a-b c ..." of the faces the contour may follow, and the heights
   above the part's bottom they span, merged where they overlap. */
static void write_contour(FILE *f, const void *ctx)
{
    const project *p = (const project *)ctx;
    const plan_job *j = p->job;
    const adaslice_hybrid_options *h = &p->args->contour;
    const adaslice_mesh *m = p->mesh;
    size_t t, n = m->triangle_count, run = 0, spans = 0;
    double (*span)[2] = p->span;
    fprintf(f, "; adaslice %s hybrid plan for adaslice contour\n; max_angle = %.9g\n; reach = %.9g\n"
               "; max_rise = %.9g\n; resolution = %.9g\n; residual = %.9g\n; contoured_faces =",
            ADASLICE_VERSION, h->max_angle, h->reach ? h->reach : ADASLICE_DEFAULT_REACH,
            h->rise ? h->rise : j->args->tmax / 2, h->resolution ? h->resolution : ADASLICE_DEFAULT_PATH_RESOLUTION,
            j->hybrid.residual);
    for (t = 0; t <= n; t++) {
        if (t < n && j->residual[t] >= 0) { run++; continue; }
        if (run > 1) fprintf(f, " %zu-%zu", t - run, t - 1);
        else if (run) fprintf(f, " %zu", t - 1);
        run = 0;
    }
    fputs("\n; contoured_heights =", f);
    for (t = 0; t < n; t++) {
        const uint32_t *c = m->triangles + 3 * t;
        double lo = m->vertices[3 * c[0] + 2], hi = lo;
        int k;
        if (j->residual[t] < 0) continue;
        for (k = 1; k < 3; k++) {
            double z = m->vertices[3 * c[k] + 2];
            lo = z < lo ? z : lo;
            hi = z > hi ? z : hi;
        }
        span[spans][0] = lo - p->z0;
        span[spans++][1] = hi - p->z0;
    }
    qsort(span, spans, sizeof *span, by_low);
    for (t = 0; t < spans; t++) {
        double lo = span[t][0], hi = span[t][1];
        for (; t + 1 < spans && span[t + 1][0] <= hi; t++)
            if (span[t + 1][1] > hi) hi = span[t + 1][1];
        fprintf(f, " %.6g-%.6g", lo, hi);
    }
    fputc('\n', f);
}

int threemf_write(const threemf_args *t, const plan_args *a, plan_job *j, FILE *note)
{
    const adaslice_plan *pl = &j->plan[a->method];
    double lo[3], hi[3], height, *tops, below = 0, thinnest = HUGE_VAL, thickest = 0;
    size_t k, n = pl->layer_count;
    adaslice_error err;
    zip_writer *z = NULL;
    project p;
    int rc;
    if (!n) return complain(RC_FAIL, "%s: the plan has no layers", t->path);
    /* the slicers want a connected mesh; STL has no shared vertices */
    if (adaslice_mesh_weld(&j->mesh, NULL, &err) != ADASLICE_OK) return library_error(&err);
    adaslice_mesh_bounds(&j->mesh, lo, hi);
    height = hi[2] - lo[2];
    if (!(tops = (double *)malloc(n * sizeof *tops))) return complain(RC_FAIL, "out of memory");
    for (k = 0; k < n; k++) /* the bins round the height up; the last layer ends on the part's top */
        tops[k] = as_written(k + 1 < n ? pl->layers[k].z_top : height);
    if (n > 1 && tops[n - 1] - tops[n - 2] < a->tmin * (1 - 1e-9)) {
        /* what is left above the last whole layer (a uniform plan's, or the bins' rounding): a layer of it was
           PrusaSlicer's ;HEIGHT:0.0001, laid as one. It joins the layer below, or the two share their height
           where one would pass what the nozzle lays. */
        double top = tops[n - 1] - tops[n - 2], two = tops[n - 1] - (n > 2 ? tops[n - 3] : 0);
        if (two <= THREEMF_MAX_OF_NOZZLE * t->nozzle) {
            tops[n - 2] = tops[n - 1];
            n--;
            warn("%s: the top %.9g mm, under --tmin %g, joins the layer below: %.9g mm",
                 t->path, top, a->tmin, two);
        } else {
            tops[n - 2] = as_written(tops[n - 1] - two / 2);
            warn("%s: the top %.9g mm, under --tmin %g, and the layer below share their "
                 "%.9g mm", t->path, top, a->tmin, two);
        }
    }
    for (k = 0; k < n; k++) {
        if (tops[k] - below < thinnest) thinnest = tops[k] - below;
        if (tops[k] - below > thickest) thickest = tops[k] - below;
        below = tops[k];
    }
    p.mesh = &j->mesh;
    p.tops = tops;
    p.layers = n;
    p.tmin = a->tmin < thinnest ? a->tmin : thinnest;
    p.tmax = a->tmax > thickest ? a->tmax : thickest;
    p.args = t;
    p.job = j;
    p.z0 = lo[2];
    p.span = NULL;
    if (j->residual && !(p.span = (double (*)[2])malloc(j->mesh.triangle_count * sizeof *p.span))) {
        free(tops);
        return complain(RC_FAIL, "out of memory");
    }
    if ((rc = zip_open(&z, t->path))) { free(tops); free(p.span); return rc; }
    if ((rc = zip_add_text(z, "[Content_Types].xml", write_content_types, &p)) ||
        (rc = zip_add_text(z, "_rels/.rels", write_rels, &p)) || (rc = zip_add_text(z, "3D/3dmodel.model", write_model, &p)) ||
        (rc = zip_add_text(z, "Metadata/Slic3r_PE_layer_heights_profile.txt", write_profile, &p)) ||
        (rc = zip_add_text(z, "Metadata/layer_heights_profile.txt", write_profile, &p)) ||
        (rc = zip_add_text(z, "Metadata/Slic3r_PE.config", write_config, &p)) ||
        (j->residual && (rc = zip_add_text(z, THREEMF_CONTOUR_PART, write_contour, &p)))) {
        zip_close(z, 0);
        free(tops);
        free(p.span);
        return rc;
    }
    free(p.span);
    if (!(rc = zip_close(z, 1)))
        fprintf(note,
                "%s: %zu layer%s of %.9g to %.9g mm for PrusaSlicer, OrcaSlicer and Bambu Studio; the printer profile "
                "needs first layer height %.9g mm, minimum layer height %.9g mm or less and maximum %.9g mm or more "
                "(prusa-slicer --first-layer-height %.9g --min-layer-height %.9g --max-layer-height %.9g)\n",
                t->path, n, plural(n), thinnest, thickest, tops[0], p.tmin, p.tmax, tops[0], p.tmin, p.tmax);
    free(tops);
    return rc;
}

/* ---- reading it back */

/* The value of attribute `name` in the tag that starts at tag (up to its
   '>'), or NULL. */
static const char *attribute(const char *tag, const char *name)
{
    size_t n = strlen(name);
    const char *p;
    if (!*tag) return NULL;
    /* from the tag's second byte: p[-1] is in the text even where the tag
       is its first */
    for (p = tag + 1; *p && *p != '>'; p++)
        if (p[-1] == ' ' && !strncmp(p, name, n) && p[n] == '=' && (p[n + 1] == '"' || p[n + 1] == '\'')) return p + n + 2;
    return NULL;
}

/* A number (decimal_number's: no hex, no junk after it) of at most
   CONTOUR_MAX_LIMIT, the attribute's quote right after it. */
static int number_attribute(const char *tag, const char *name, double *v)
{
    const char *a = attribute(tag, name), *end;
    if (!a) return 0;
    end = decimal_number(a, v);
    return end && end != a && end[0] == a[-1] && fabs(*v) < CONTOUR_MAX_LIMIT;
}

/* The number of tags `<name ` in text. */
static size_t count_tags(const char *text, const char *name)
{
    size_t n = 0;
    const char *p = text;
    while ((p = strstr(p, name)) != NULL) { n++; p++; }
    return n;
}

static int read_mesh(const char *path, const char *xml, threemf_project *p)
{
    size_t nv = count_tags(xml, "<vertex "), nt = count_tags(xml, "<triangle "), i;
    const char *tag, *item;
    double m[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    if (count_tags(xml, "<object ") != 1 || count_tags(xml, "<item ") != 1)
        return complain(RC_FAIL, "%s: 3D/3dmodel.model: %zu objects and %zu build items, not one of each", path,
                        count_tags(xml, "<object "), count_tags(xml, "<item "));
    if (!nt || nt > UINT32_MAX / 3 || nv > UINT32_MAX)
        return complain(RC_FAIL, "%s: 3D/3dmodel.model: %zu vertices and %zu triangles", path, nv, nt);
    item = strstr(xml, "<item ");
    if ((tag = attribute(item, "transform")) != NULL) {
        const char *end;
        char quote = tag[-1];
        for (i = 0; i < 12; i++, tag = end) {
            while (*tag == ' ') tag++;
            if (!(end = decimal_number(tag, &m[i])) || !(fabs(m[i]) < CONTOUR_MAX_LIMIT) || (*end != ' ' && *end != quote))
                return complain(RC_FAIL, "%s: the build item's transform is not 12 numbers", path);
        }
        while (*tag == ' ') tag++;
        if (*tag != quote) return complain(RC_FAIL, "%s: the build item's transform is not 12 numbers", path);
        p->transformed = 1;
    }
    p->mesh.vertices = (float *)malloc((nv ? nv : 1) * 3 * sizeof(float));
    p->mesh.triangles = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t));
    if (!p->mesh.vertices || !p->mesh.triangles) return complain(RC_FAIL, "out of memory");
    for (tag = xml, i = 0; i < nv; i++) {
        double v[3];
        tag = strstr(tag, "<vertex ") + 1;
        if (!number_attribute(tag, "x", &v[0]) || !number_attribute(tag, "y", &v[1]) || !number_attribute(tag, "z", &v[2]))
            return complain(RC_FAIL, "%s: 3D/3dmodel.model: vertex %zu has no x, y and z of under %g mm", path, i,
                            CONTOUR_MAX_LIMIT);
        /* 3MF's transform: the row vector (x y z 1) times the 4 x 3 matrix */
        p->mesh.vertices[3 * i] = (float)(m[0] * v[0] + m[3] * v[1] + m[6] * v[2] + m[9]);
        p->mesh.vertices[3 * i + 1] = (float)(m[1] * v[0] + m[4] * v[1] + m[7] * v[2] + m[10]);
        p->mesh.vertices[3 * i + 2] = (float)(m[2] * v[0] + m[5] * v[1] + m[8] * v[2] + m[11]);
    }
    for (tag = xml, i = 0; i < nt; i++) {
        double v[3];
        int c;
        tag = strstr(tag, "<triangle ") + 1;
        if (!number_attribute(tag, "v1", &v[0]) || !number_attribute(tag, "v2", &v[1]) || !number_attribute(tag, "v3", &v[2]))
            return complain(RC_FAIL, "%s: 3D/3dmodel.model: triangle %zu has no v1, v2 and v3", path, i);
        for (c = 0; c < 3; c++) {
            if (!(v[c] >= 0 && v[c] < (double)nv && v[c] == floor(v[c])))
                return complain(RC_FAIL, "%s: 3D/3dmodel.model: triangle %zu names vertex %g of %zu", path, i, v[c], nv);
            p->mesh.triangles[3 * i + c] = (uint32_t)v[c];
        }
    }
    p->mesh.vertex_count = nv;
    p->mesh.triangle_count = nt;
    return RC_OK;
}

/* "object_id=1|z;h;z;h;...": the plan's tops are the z that end a layer
   (every second pair, as threemf_write writes a step per layer). */
static int read_profile(const char *path, const char *text, threemf_project *p)
{
    const char *at = strchr(text, '|'), *end_of_line = "";
    size_t n = 0, cap = 0, pair = 0;
    if (!at) return complain(RC_FAIL, "%s: the layer height profile has no '|'", path);
    for (at++; *at && *at != '\n'; pair++) {
        double z, h;
        const char *end;
        if (!(end = decimal_number(at, &z)) || *end != ';') break;
        if (!(end = decimal_number(end + 1, &h)) || !(h > 0 && h < CONTOUR_MAX_LIMIT) || !(fabs(z) < CONTOUR_MAX_LIMIT) ||
            (*end && *end != ';' && *end != '\n'))
            break;
        at = *end == ';' ? end + 1 : end;
        if (pair % 2 == 0) continue;
        if (n && !(z > p->tops[n - 1]))
            return complain(RC_FAIL, "%s: the layer height profile's layer %zu ends at %g mm, not above the one before (%g mm)",
                            path, n + 1, z, p->tops[n - 1]);
        if (n == cap) {
            double *t = (double *)realloc(p->tops, (cap = cap ? 2 * cap : 256) * sizeof *t);
            if (!t) return complain(RC_FAIL, "out of memory");
            p->tops = t;
        }
        p->tops[n++] = z;
    }
    if (*at == '\n') /* one line: after it, only blanks */
        for (end_of_line = at; *end_of_line == '\n' || *end_of_line == '\r' || *end_of_line == ' '; end_of_line++) {}
    if ((*at && *at != '\n') || *end_of_line)
        return complain(RC_FAIL, "%s: the layer height profile is not z;h pairs at byte %zu", path,
                        (size_t)((*at && *at != '\n' ? at : end_of_line) - text));
    if (!n) return complain(RC_FAIL, "%s: the layer height profile has no layers", path);
    p->layers = n;
    return RC_OK;
}

int contour_limit_check(const char *where, const char *key, double x, int rc)
{
    int k = !strcmp(key, "max_angle") ? 0 : !strcmp(key, "max_rise") ? 1 : 2;
    static const double least[] = {0, 0, CONTOUR_MIN_PIECE}, most[] = {CONTOUR_MAX_ANGLE, CONTOUR_MAX_LIMIT, CONTOUR_MAX_LIMIT};
    if ((x > least[k] || (k == 2 && x == least[k])) && x < most[k]) return RC_OK;
    return complain(rc, "%s%g: contour takes %s %g and under %g", where, x, k == 2 ? "from" : "over", least[k], most[k]);
}

/* The contour's limits from THREEMF_CONTOUR_PART's "; key = value" lines;
   a key missing stays 0 (the contour's default); one that contour would
   refuse on its command line is refused here. */
static int read_contour_limits(const char *path, const char *text, size_t size, threemf_project *p)
{
    static const char *const keys[] = {"max_angle", "max_rise", "resolution"};
    double *values[3], x;
    size_t k, n;
    char where[512];
    values[0] = &p->max_angle; values[1] = &p->max_rise; values[2] = &p->resolution;
    for (k = 0; k < 3; k++) {
        const char *v = gcode_config_value(text, size, keys[k], &n), *end = v ? decimal_number(v, &x) : NULL;
        int rc;
        if (!v) continue;
        snprintf(where, sizeof where, "%s: %s: %s = ", path, THREEMF_CONTOUR_PART, keys[k]);
        if (!end || end != v + n)
            return complain(RC_FAIL, "%s%.*s: not a number", where, (int)(n < 40 ? n : 40), v);
        if ((rc = contour_limit_check(where, keys[k], x, RC_FAIL))) return rc;
        *values[k] = x;
    }
    return RC_OK;
}

int threemf_read(const char *path, threemf_project *p)
{
    FILE *f = fopen(path, "rb");
    unsigned char *data = NULL, *model = NULL, *profile = NULL;
    size_t size = 0, cap = 0, n;
    char why[128];
    int rc = RC_OK, got;
    memset(p, 0, sizeof *p);
    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    do {
        if (size == cap) {
            unsigned char *d = (unsigned char *)realloc(data, cap = cap ? 2 * cap : 1 << 16);
            if (!d) { rc = complain(RC_FAIL, "out of memory"); break; }
            data = d;
        }
        size += n = fread(data + size, 1, cap - size, f);
    } while (n);
    if (!rc && ferror(f)) rc = complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    fclose(f);
    if (!rc && (got = zip_member(data, size, "3D/3dmodel.model", &model, &n, why)) != 0)
        rc = complain(RC_FAIL, "%s: %s", path, got > 0 ? "no 3D/3dmodel.model: not a 3MF" : why);
    if (!rc && (got = zip_member(data, size, "Metadata/Slic3r_PE_layer_heights_profile.txt", &profile, &n, why)) != 0)
        rc = complain(RC_FAIL, "%s: %s", path, got > 0 ? "no layer height profile (plan --3mf writes one)" : why);
    if (!rc) rc = read_mesh(path, (const char *)model, p);
    if (!rc) rc = read_profile(path, (const char *)profile, p);
    if (!rc) {
        unsigned char *limits = NULL;
        if ((got = zip_member(data, size, THREEMF_CONTOUR_PART, &limits, &n, why)) < 0)
            rc = complain(RC_FAIL, "%s: %s", path, why);
        else if (!got) rc = read_contour_limits(path, (const char *)limits, n, p);
        free(limits);
    }
    free(data);
    free(model);
    free(profile);
    if (rc) threemf_project_free(p);
    return rc;
}

void threemf_project_free(threemf_project *p)
{
    free(p->mesh.vertices);
    free(p->mesh.triangles);
    free(p->tops);
    memset(p, 0, sizeof *p);
}
