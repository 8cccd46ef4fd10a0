/* adaslice saliency: the per-face weights `plan --saliency` uses, as a file
   `plan --weights` reads, and a mesh coloured by them for any viewer. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "bytes.h"
#include "model.h"
#include "options.h"
#include "output.h"
#include "codec/png.h"
#include "report.h"
#include "weights.h"

#include <stdlib.h>
#include <string.h>

typedef struct saliency_args {
    const char *model, *out, *ply, *png;
    double scale;
    int no_saliency;
    weight_args weights;
} saliency_args;

static void saliency_usage(FILE *f)
{
    fputs("usage: adaslice saliency MODEL -o WEIGHTS [--ply COLOURED.ply] [--png PICTURE.png] [options]\n"
          "\n"
          "Writes the per-face weights that adaslice plan MODEL --saliency uses (mesh\n"
          "saliency after Lee, Varshney and Jacobs 2005, in [0,1], 1 the most salient):\n"
          "one per line for each triangle, as --weights reads them.\n"
          "\n"
          "  -o, --out FILE      the weights\n"
          "  --ply FILE          the mesh coloured by weight, blue 0 .. red 1 (binary PLY;\n"
          "                      each triangle has its own three vertices, all its colour)\n"
          "  --png FILE          a 960 x 720 picture of the part coloured the same way, seen\n"
          "                      from 30 degrees above the plate, at the front right\n"
          "  --scale S           multiply the model's coordinates by S (metres: 1000)\n"
          "  --no-saliency       weights from --weights and --weight alone\n"
          "\n", f);
    weights_usage(f, 0);
}

static int parse_saliency(int argc, char **argv, saliency_args *s, int *help)
{
    int i, rc = RC_OK;
    memset(s, 0, sizeof *s);
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (o[0] != '-') {
            if (s->model) return complain(RC_USAGE, "unexpected argument %s: MODEL is already %s", o, s->model);
            s->model = o;
        }
        else if (!strcmp(o, "--help") || !strcmp(o, "-h")) { *help = 1; return RC_OK; }
        else if (!strcmp(o, "-o") || !strcmp(o, "--out")) rc = file_option(argc, argv, &i, &s->out);
        else if (!strcmp(o, "--ply")) rc = file_option(argc, argv, &i, &s->ply);
        else if (!strcmp(o, "--png")) rc = file_option(argc, argv, &i, &s->png);
        else if (!strcmp(o, "--scale")) rc = number_option(argc, argv, &i, 0, &s->scale);
        else if (!strcmp(o, "--no-saliency")) s->no_saliency = 1;
        else if (!weights_option(argc, argv, &i, &s->weights, &rc))
            return complain(RC_USAGE, "unknown option %s (see adaslice saliency --help)", o);
    }
    if (rc || (rc = weights_check(&s->weights))) return rc;
    /* the blend weighs saliency by --importance's first share: --no-saliency was passed over, unsaid */
    if (s->no_saliency && s->weights.blend)
        return complain(RC_USAGE, "--no-saliency with %s: the blend gives saliency --importance's first share; "
                                  "give --importance 0,V,U instead", s->weights.blend == 2 ? "--importance" : "--view");
    if (!s->model) return complain(RC_USAGE, "saliency needs a MODEL");
    if (!s->out && !s->ply && !s->png)
        return complain(RC_USAGE, "saliency writes -o WEIGHTS, --ply FILE or --png FILE; none is given");
    s->weights.saliency = !s->no_saliency;
    return RC_OK;
}

typedef struct weighted_mesh { const adaslice_mesh *mesh; const float *weight; } weighted_mesh;

static void write_weights(FILE *f, const void *ctx)
{
    const weighted_mesh *w = (const weighted_mesh *)ctx;
    size_t t;
    for (t = 0; t < w->mesh->triangle_count; t++) fprintf(f, "%.9g\n", w->weight[t]);
}

/* blue, cyan, green, yellow, red at 0, 1/4, 1/2, 3/4, 1 */
static void ramp(double w, unsigned char rgb[3])
{
    static const unsigned char stops[5][3] = {{0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
    double x = (w < 0 ? 0 : w > 1 ? 1 : w) * 4;
    int i = x >= 4 ? 3 : (int)x, k;
    for (k = 0; k < 3; k++) rgb[k] = (unsigned char)(stops[i][k] + (x - i) * (stops[i + 1][k] - stops[i][k]) + 0.5);
}

/* Colours per vertex, with every triangle on its own vertices, so that every
   viewer shows each face in its weight's colour (per-face colours are often
   ignored); little-endian whatever the host. */
static void write_ply(FILE *f, const void *ctx)
{
    const weighted_mesh *w = (const weighted_mesh *)ctx;
    const adaslice_mesh *m = w->mesh;
    size_t t;
    int c, k;
    fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment adaslice saliency: face weight as colour, blue 0 .. red 1\n"
               "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
               "property uchar red\nproperty uchar green\nproperty uchar blue\n"
               "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
            3 * m->triangle_count, m->triangle_count);
    for (t = 0; t < m->triangle_count; t++) {
        unsigned char rgb[3];
        ramp(w->weight[t], rgb);
        for (c = 0; c < 3; c++) {
            const float *p = m->vertices + 3 * (size_t)m->triangles[3 * t + c];
            unsigned char vertex[15];
            for (k = 0; k < 3; k++) put_le_f32(vertex + 4 * k, p[k]);
            memcpy(vertex + 12, rgb, 3);
            fwrite(vertex, 1, sizeof vertex, f);
        }
    }
    for (t = 0; t < m->triangle_count; t++) {
        unsigned char face[13];
        face[0] = 3;
        for (c = 0; c < 3; c++) put_le32(face + 1 + 4 * c, (uint32_t)(3 * t + (size_t)c));
        fwrite(face, 1, sizeof face, f);
    }
}

typedef struct picture { const unsigned char *png; size_t size; } picture;

static void write_png(FILE *f, const void *ctx)
{
    const picture *p = (const picture *)ctx;
    fwrite(p->png, 1, p->size, f);
}

/* The part as adaslice_preview shows it, each face in its weight's colour. */
static int write_picture(const char *path, const char *model, const weighted_mesh *w)
{
    enum { WIDTH = 960, HEIGHT = 720 };
    adaslice_preview_options o;
    adaslice_error e;
    unsigned char *colours = (unsigned char *)malloc(3 * (w->mesh->triangle_count ? w->mesh->triangle_count : 1));
    unsigned char *rgb = (unsigned char *)malloc((size_t)WIDTH * HEIGHT * 3), *png = NULL;
    picture p;
    size_t t;
    int rc = RC_OK;
    if (!colours || !rgb) rc = complain(RC_FAIL, "out of memory for the picture");
    for (t = 0; !rc && t < w->mesh->triangle_count; t++) ramp(w->weight[t], colours + 3 * t);
    memset(&o, 0, sizeof o);
    o.face_colours = colours;
    o.background[0] = o.background[1] = o.background[2] = 255;
    if (!rc && adaslice_preview(w->mesh, WIDTH, HEIGHT, &o, rgb, &e) != ADASLICE_OK) rc = library_error_in(model, &e);
    if (!rc && png_encode_rgb(rgb, WIDTH, HEIGHT, &png, &p.size)) rc = complain(RC_FAIL, "out of memory for %s", path);
    p.png = png;
    if (!rc) rc = write_atomic(path, write_png, &p);
    free(png);
    free(rgb);
    free(colours);
    return rc;
}

int cmd_saliency(int argc, char **argv)
{
    saliency_args s;
    adaslice_mesh mesh;
    weighted_mesh wm;
    float *weight = NULL;
    double t0, t1, sum = 0, top = 0;
    size_t t, above = 0;
    int help = 0, rc = parse_saliency(argc, argv, &s, &help);
    if (rc) return rc;
    if (help) {
        saliency_usage(stdout);
        return RC_OK;
    }
    outputs_add_input(s.model);
    outputs_add_input(s.weights.file);
    if ((rc = output_check("-o", s.out)) || (rc = output_check("--ply", s.ply)) || (rc = output_check("--png", s.png)))
        return rc;
    {
        const char *const options[] = {"-o", "--ply", "--png"};
        const char *const paths[] = {s.out, s.ply, s.png};
        if ((rc = output_check_distinct(options, paths, 3))) return rc;
    }
    t0 = now_ms();
    if ((rc = model_load(s.model, s.scale, &mesh, NULL)) != RC_OK) return rc;
    t1 = now_ms();
    rc = weights_for_plan(&s.weights, s.model, &mesh, &weight);
    if (!rc && !weight) { /* nothing asked for: every face weighs 1 */
        weight = (float *)malloc(mesh.triangle_count * sizeof *weight);
        if (!weight)
            rc = complain(RC_FAIL, "out of memory for %zu weight%s", mesh.triangle_count, plural(mesh.triangle_count));
        for (t = 0; !rc && t < mesh.triangle_count; t++) weight[t] = 1;
    }
    if (!rc) {
        double done = now_ms();
        wm.mesh = &mesh;
        wm.weight = weight;
        for (t = 0; t < mesh.triangle_count; t++) {
            sum += weight[t];
            if (weight[t] > top) top = weight[t];
            above += weight[t] > 0.5f;
        }
        if (s.out) rc = write_atomic(s.out, write_weights, &wm);
        if (!rc && s.ply) rc = write_atomic(s.ply, write_ply, &wm);
        if (!rc && s.png) rc = write_picture(s.png, s.model, &wm);
        if (!rc) {
            printf("model      %s: %zu triangle%s\n", s.model, mesh.triangle_count, plural(mesh.triangle_count));
            printf("weights    mean %.3g, largest %.3g, %zu face%s above 0.5\n", sum / (double)mesh.triangle_count, top,
                   above, plural(above));
            printf("time       load %.1f ms, weights %.1f ms\n", t1 - t0, done - t1);
        }
    }
    free(weight);
    adaslice_mesh_free(&mesh);
    return rc;
}
