/* The FDM project: see threemf.h. The 3MF parts are the 3MF Consortium's
   core specification (1.3): [Content_Types].xml, _rels/.rels and the model
   part 3D/3dmodel.model. */
#include "threemf.h"
#include "../options.h"
#include "../output.h"
#include "../report.h"
#include "../codec/zip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

int threemf_options(int argc, char **argv, threemf_args *t, int *rest_argc, char **rest)
{
    int i, rc = RC_OK;
    t->path = NULL;
    t->nozzle = 0.4;
    rest[(*rest_argc)++] = argv[0];
    for (i = 1; i < argc && !rc; i++) {
        if (!strcmp(argv[i], "--3mf")) {
            const char *dot;
            rc = file_option(argc, argv, &i, &t->path);
            /* a 3MF named .stl would be read back as an STL; a stream or device has no name to mislead */
            dot = rc ? NULL : strrchr(t->path, '.');
            if (!rc && output_kind(t->path) != OUT_STRAIGHT &&
                (!dot || strchr(dot, '/') || dot[-1] == '/' || dot == t->path || strcasecmp(dot, ".3mf")))
                rc = complain(RC_USAGE, "--3mf %s: the name must end in .3mf", t->path);
        }
        else if (!strcmp(argv[i], "--nozzle")) rc = number_option(argc, argv, &i, 0, &t->nozzle);
        else rest[(*rest_argc)++] = argv[i];
    }
    return rc;
}

void threemf_usage(FILE *f)
{
    fputs("FDM project\n"
          "  --3mf FILE          a 3MF of the model with the plan as PrusaSlicer's and\n"
          "                      OrcaSlicer's variable layer height profile; for a 0.4 mm\n"
          "                      nozzle plan with e.g. --tmin 0.08 --tmax 0.28 --eps 0.1\n"
          "  --nozzle MM         its nozzle: layers up to 75% of it               [0.4]\n", f);
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

typedef struct project {
    const adaslice_mesh *mesh;
    const double *tops;          /* K layer tops, mm above the part's bottom, as written */
    size_t layers;
    double tmin, tmax;
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

/* A top as the file will hold it. */
static double as_written(double z)
{
    char text[32];
    snprintf(text, sizeof text, "%.9g", z);
    return strtod(text, NULL);
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
    for (k = 0; k < n; k++) {
        /* the bins round the height up; the last layer ends on the part's top */
        tops[k] = as_written(k + 1 < n ? pl->layers[k].z_top : height);
        if (tops[k] - below < thinnest) thinnest = tops[k] - below;
        if (tops[k] - below > thickest) thickest = tops[k] - below;
        below = tops[k];
    }
    p.mesh = &j->mesh;
    p.tops = tops;
    p.layers = n;
    p.tmin = a->tmin < thinnest ? a->tmin : thinnest;
    p.tmax = a->tmax > thickest ? a->tmax : thickest;
    if ((rc = zip_open(&z, t->path))) { free(tops); return rc; }
    if ((rc = zip_add_text(z, "[Content_Types].xml", write_content_types, &p)) ||
        (rc = zip_add_text(z, "_rels/.rels", write_rels, &p)) || (rc = zip_add_text(z, "3D/3dmodel.model", write_model, &p)) ||
        (rc = zip_add_text(z, "Metadata/Slic3r_PE_layer_heights_profile.txt", write_profile, &p)) ||
        (rc = zip_add_text(z, "Metadata/layer_heights_profile.txt", write_profile, &p)) ||
        (rc = zip_add_text(z, "Metadata/Slic3r_PE.config", write_config, &p))) {
        zip_close(z, 0);
        free(tops);
        return rc;
    }
    if (!(rc = zip_close(z, 1)))
        fprintf(note,
                "%s: %zu layer%s of %.9g to %.9g mm for PrusaSlicer, OrcaSlicer and Bambu Studio; the printer profile "
                "needs first layer height %.9g mm, minimum layer height %.9g mm or less and maximum %.9g mm or more "
                "(prusa-slicer --first-layer-height %.9g --min-layer-height %.9g --max-layer-height %.9g)\n",
                t->path, n, plural(n), thinnest, thickest, tops[0], p.tmin, p.tmax, tops[0], p.tmin, p.tmax);
    free(tops);
    return rc;
}
