/* What the tool's figures and reports tell a reader, end to end (the tool
   runs as a child process, as in test_cli.c): the layer SVGs agree with the
   manifest, the orient map tiles and has its colour bar, plan --compare
   gives the saving against uniform layers. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "cli_run.h"
#include "../adaslice.h"
#include "meshgen.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A 10 mm sphere standing 20 mm above the model's origin, so that heights
   above the part's bottom and the model's z differ. */
static const char *raised_sphere(void)
{
    const char *path = cli_path("raised_sphere.obj");
    if (!cli_exists(path)) {
        adaslice_mesh m = gen_sphere(5, 48, 24, 20);
        cli_write_obj(path, &m);
        gen_free(&m);
    }
    return path;
}

/* The number in an XML attribute name="..." after p, or NAN. */
static double attribute(const char *p, const char *name)
{
    char pat[64];
    snprintf(pat, sizeof pat, " %s=\"", name);
    p = p ? strstr(p, pat) : NULL;
    return p ? strtod(p + strlen(pat), NULL) : NAN;
}

/* Every layer's SVG names the layer and gives, in its caption and its data,
   the heights above the part's bottom and the thickness the manifest gives
   that layer; a legend and a scale bar are there. */
static void layer_svgs_agree_with_the_manifest(void)
{
    char job[600], path[800], *manifest;
    cli_result r;
    size_t layers, k;
    snprintf(job, sizeof job, "%s/svgjob", cli_dir);
    r = cli_run("slice", raised_sphere(), "-o", job, "--pixels", "400x400", "--pitch", "0.05", "--svg", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    manifest = cli_read(path);
    CHECK(manifest != NULL);
    if (!manifest) return;
    layers = (size_t)cli_json_number(manifest, "layer_count");
    CHECKF(layers > 50, "%zu layers", layers);
    for (k = 1; k <= layers; k++) {
        char index[32], title[64], *svg;
        const char *entry, *caption, *g;
        double z0, z1, t, shown[2] = {NAN, NAN};
        snprintf(index, sizeof index, "{\"index\": %zu,", k);
        entry = strstr(manifest, index);
        CHECKF(entry != NULL, "the manifest has no layer %zu", k);
        if (!entry) break;
        z0 = cli_json_number(entry, "z_bottom");
        z1 = cli_json_number(entry, "z_top");
        t = cli_json_number(entry, "thickness");
        snprintf(path, sizeof path, "%s/layer_%05zu.svg", job, k);
        svg = cli_read(path);
        CHECKF(svg != NULL, "no layer_%05zu.svg", k);
        if (!svg) continue;
        snprintf(title, sizeof title, "layer %zu of %zu", k, layers);
        CHECKF(strstr(svg, "<title>") && strstr(strstr(svg, "<title>"), title), "layer %zu: no <title> naming it", k);
        caption = strstr(svg, "</title>");
        caption = caption ? strstr(caption, " mm above the part's bottom") : NULL;
        while (caption && caption > svg && caption[-1] != '>') caption--; /* the start of the caption's text */
        CHECKF(caption && sscanf(caption, "%lf to %lf", &shown[0], &shown[1]) == 2 &&
                   fabs(shown[0] - z0) < 1e-6 && fabs(shown[1] - z1) < 1e-6,
               "layer %zu: the caption says %g to %g mm, the manifest %.9g to %.9g", k, shown[0], shown[1], z0, z1);
        CHECKF(strstr(svg, "mm thick"), "layer %zu: no thickness in the caption", k);
        g = strstr(svg, "<g id=\"layer-");
        CHECKF(g && fabs(attribute(g, "data-z-bottom") - z0) < 1e-9 && fabs(attribute(g, "data-z-top") - z1) < 1e-9 &&
                   fabs(attribute(g, "data-thickness") - t) < 1e-9 && attribute(g, "data-layer") == (double)k,
               "layer %zu: data-z-bottom %g, data-z-top %g, data-thickness %g; the manifest %.9g, %.9g, %.9g", k,
               attribute(g, "data-z-bottom"), attribute(g, "data-z-top"), attribute(g, "data-thickness"), z0, z1, t);
        CHECKF(g && attribute(g, "data-cut") >= z0 && attribute(g, "data-cut") <= z1, "layer %zu: cut at %g", k,
               attribute(g, "data-cut"));
        CHECKF(strstr(svg, "inside the part") && strstr(svg, " mm</text>"), "layer %zu: no legend or scale bar", k);
        free(svg);
    }
    free(manifest);
    cli_remove_all(job);
}

void test_outputs(void)
{
    if (!cli_begin("adaslice-outputs")) return;
    RUN(layer_svgs_agree_with_the_manifest);
    cli_end();
}
