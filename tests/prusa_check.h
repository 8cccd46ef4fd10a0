/* PrusaSlicer, a real client, slices the 3MF adaslice plan writes: the
   G-code's ";Z:" layer tops must be the plan's, layer for layer, within
   1e-3 mm (PrusaSlicer prints six significant digits). Shared by the tests
   (a bundled model) and check_models (every shared model that fits a
   250 x 210 mm bed). Needs cli_run.h's tool and tool_run.h's runner. */
#ifndef ADASLICE_PRUSA_CHECK_H
#define ADASLICE_PRUSA_CHECK_H
#include "cli_run.h"
#include "tool_run.h"

/* The 0.4 mm nozzle's bounds that README suggests for FDM. */
#define PRUSA_FDM_ARGS "--tmin", "0.08", "--tmax", "0.28", "--eps", "0.1"

/* The word after `key ` in text, into out. */
static inline int prusa_word_after(const char *text, const char *key, char *out, size_t size)
{
    const char *p = strstr(text, key);
    size_t n = 0;
    if (!p) return 0;
    for (p += strlen(key); *p == ' '; p++) {}
    while (p[n] && p[n] != ' ' && p[n] != ')' && p[n] != '\n' && n + 1 < size) { out[n] = p[n]; n++; }
    out[n] = 0;
    return n > 0;
}

typedef struct prusa_result {
    size_t planned;              /* layers in the plan */
    size_t printed;              /* ... in the G-code, each at its planned top */
    size_t empty;                /* ... PrusaSlicer reports as empty ("Empty layer between a and b") */
    size_t above;                /* ... above its last printed layer (nothing to extrude up there) */
    int unprintable;             /* PrusaSlicer refuses the model itself (its plain file, scaled) */
} prusa_result;

static inline int prusa_run(char **argv, const char *log_path, char **log)
{
    int status = tool_run("prusa-slicer", argv, log_path, log_path);
    *log = read_whole_text(log_path);
    if (!*log) *log = (char *)calloc(1, 1);
    return status;
}

/* prusa-slicer's command line exporting path3mf's G-code to gcode_path on a
   250 x 210 mm bed, with the layer heights plan --3mf printed; argv gets
   them, a NULL after, and the index of path3mf is returned (more arguments
   may replace it). */
static inline int prusa_export_argv(char **argv, char *data, char *first, char *lo, char *hi, const char *gcode_path,
                                    const char *path3mf)
{
    int a = 0;
    argv[a++] = (char *)"prusa-slicer";
    argv[a++] = (char *)"--datadir";
    argv[a++] = data;
    argv[a++] = (char *)"--export-gcode";
    argv[a++] = (char *)"--first-layer-height";
    argv[a++] = first;
    argv[a++] = (char *)"--min-layer-height";
    argv[a++] = lo;
    argv[a++] = (char *)"--max-layer-height";
    argv[a++] = hi;
    argv[a++] = (char *)"--bed-shape";
    argv[a++] = (char *)"0x0,250x0,250x210,0x210";
    argv[a++] = (char *)"--max-print-height";
    argv[a++] = (char *)"210";
    argv[a++] = (char *)"-o";
    argv[a++] = (char *)gcode_path;
    argv[a] = (char *)path3mf;
    argv[a + 1] = NULL;
    return a;
}

/* `plan` (a finished plan --3mf path3mf run, freed here) handed on to
   PrusaSlicer: its G-code of path3mf to gcode_path with the layer limits plan
   printed, and `extra` (one more option, or NULL) before the 3MF. 1 when
   both ran; 0 after a failed check that says which did not. */
static inline int prusa_gcode_after(cli_result plan, const char *path3mf, const char *gcode_path, const char *extra)
{
    char first[32], lo[32], hi[32], data[300], log_path[300], *argv[24], *log = NULL;
    int a, status, ok = plan.status == 0 && prusa_word_after(plan.out, "--first-layer-height", first, sizeof first) &&
                        prusa_word_after(plan.out, "--min-layer-height", lo, sizeof lo) &&
                        prusa_word_after(plan.out, "--max-layer-height", hi, sizeof hi);
    CHECKF(ok, "%.100s: plan: exit %d: %.200s", path3mf, plan.status, plan.err);
    cli_free(&plan);
    if (!ok) return 0;
    snprintf(log_path, sizeof log_path, "%s", cli_path("prusa.log"));
    snprintf(data, sizeof data, "%s", cli_path("prusa-data"));
    mkdir(data, 0755);
    a = prusa_export_argv(argv, data, first, lo, hi, gcode_path, path3mf);
    if (extra) {
        argv[a++] = (char *)extra;
        argv[a] = (char *)path3mf;
        argv[a + 1] = NULL;
    }
    status = prusa_run(argv, log_path, &log);
    CHECKF(status == 0, "%.100s: prusa-slicer: %.300s", path3mf, log);
    free(log);
    return status == 0;
}

/* Plans `model` at `scale` into a 3MF, slices it with prusa-slicer at the
   first-layer height the tool printed, and holds the G-code's layers against
   the plan's: every ";Z:" is the next planned top (within 1e-3 mm), and a
   planned layer missing from the G-code is one PrusaSlicer says is empty or
   lies above the last it printed. 0 after a failed check. */
static inline int prusa_slices_the_plan(const char *model, double scale, prusa_result *res)
{
    char s[32], first[32], lo[32], hi[32], data[300], path3mf[300], gcode_path[300], log_path[300];
    char *csv = NULL, *gcode = NULL, *log = NULL, *row, *line, *argv[20];
    double *tops = NULL, *gaps = NULL, height, b0[3], b1[3];
    size_t k, j = 0, n = 0, cap = 0, g = 0, gap_n = 0, bad = 0;
    double *zs = NULL;
    adaslice_load_options o;
    adaslice_mesh mesh;
    adaslice_error e;
    cli_result r;
    int a = 0, status, more_gaps;
    memset(res, 0, sizeof *res);
    snprintf(s, sizeof s, "%.9g", scale);
    snprintf(path3mf, sizeof path3mf, "%s", cli_path("fdm.3mf"));
    snprintf(gcode_path, sizeof gcode_path, "%s", cli_path("fdm.gcode"));
    snprintf(log_path, sizeof log_path, "%s", cli_path("prusa.log"));
    snprintf(data, sizeof data, "%s", cli_path("prusa-data"));
    memset(&o, 0, sizeof o);
    o.scale = scale;
    if (adaslice_mesh_load_file(model, &o, &mesh, &e) != ADASLICE_OK) { CHECKF(0, "%.200s: %.200s", model, e.message); return 0; }
    adaslice_mesh_bounds(&mesh, b0, b1);
    adaslice_mesh_free(&mesh);
    height = b1[2] - b0[2];
    r = cli_run("plan", model, "--scale", s, PRUSA_FDM_ARGS, "--3mf", path3mf, "--out", cli_path("fdm.csv"), NULL);
    CHECKF(r.status == 0 && prusa_word_after(r.out, "--first-layer-height", first, sizeof first) &&
               prusa_word_after(r.out, "--min-layer-height", lo, sizeof lo) &&
               prusa_word_after(r.out, "--max-layer-height", hi, sizeof hi),
           "%.200s: plan --3mf: exit %d: %.100s%.100s", model, r.status, r.out, r.err);
    cli_free(&r);
    if (check_case_failed()) return 0;
    mkdir(data, 0755);
    a = prusa_export_argv(argv, data, first, lo, hi, gcode_path, path3mf);
    status = prusa_run(argv, log_path, &log);
    if (status != 0 && strstr(log, "no extrusions in the first layer")) {
        /* the model's own file, scaled, the same way: PrusaSlicer's verdict on the model */
        char *plain_log = NULL;
        argv[a++] = (char *)"--scale";
        argv[a++] = s;
        argv[a++] = (char *)model;
        argv[a] = NULL;
        res->unprintable = prusa_run(argv, log_path, &plain_log) != 0 && strstr(plain_log, "no extrusions in the first layer");
        free(plain_log);
        CHECKF(res->unprintable, "%.150s: PrusaSlicer prints the model but not our 3MF: %.250s", model, log);
        free(log);
        return res->unprintable;
    }
    CHECKF(status == 0, "%.150s: prusa-slicer failed: %.250s", model, log);
    if (status != 0) { free(log); return 0; }
    /* the plan's tops: plan.csv's third column; the last ends on the part's
       top, which the bins overshoot by less than one */
    csv = read_whole_text(cli_path("fdm.csv"));
    for (row = csv ? strchr(csv, '\n') : NULL; row && row[1]; row = strchr(row + 1, '\n')) {
        char *p = row + 1;
        int c;
        for (c = 0; c < 2 && p; c++) p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL;
        if (!p) break;
        if (n == cap) tops = (double *)realloc(tops, (cap = cap ? 2 * cap : 256) * sizeof *tops);
        tops[n++] = strtod(p, NULL);
    }
    free(csv);
    if (n) tops[n - 1] = tops[n - 1] < height ? tops[n - 1] : height;
    gcode = read_whole_text(gcode_path);
    for (cap = 0, line = gcode; line && (line = strstr(line, "\n;Z:")) != NULL; line += 4) {
        if (g == cap) zs = (double *)realloc(zs, (cap = cap ? 2 * cap : 256) * sizeof *zs);
        zs[g++] = strtod(line + 4, NULL);
    }
    free(gcode);
    for (cap = 0, line = log; (line = strstr(line, "Empty layer between ")) != NULL; line += 20) {
        if (gap_n == cap) gaps = (double *)realloc(gaps, (cap = cap ? 2 * cap : 16) * 2 * sizeof *gaps);
        if (sscanf(line + 20, "%lf and %lf", &gaps[2 * gap_n], &gaps[2 * gap_n + 1]) == 2) gap_n++;
    }
    more_gaps = strstr(log, "(Some lines not shown)") != NULL;
    free(log);
    for (k = 0; k < n; k++) {
        size_t q;
        int in_gap = 0;
        if (j < g && fabs(zs[j] - tops[k]) <= 1e-3) { j++; res->printed++; continue; }
        for (q = 0; q < gap_n; q++) in_gap |= tops[k] > gaps[2 * q] + 1e-3 && tops[k] <= gaps[2 * q + 1] + 1e-3;
        /* PrusaSlicer lists the first few gaps, then "(Some lines not shown)" */
        if (in_gap || (j > 0 && j < g && gap_n && more_gaps)) res->empty++;
        else if (j == g) res->above++;
        else if (bad++ < 3)
            CHECKF(0, "%.200s: layer %zu: the plan's top %.6g mm, PrusaSlicer's next %.6g", model, k + 1, tops[k], zs[j]);
    }
    res->planned = n;
    CHECKF(j == g && n > 10 && res->printed > 0, "%.200s: %zu of %zu G-code layers are planned tops (%zu planned)", model,
           j, g, n);
    free(tops);
    free(zs);
    free(gaps);
    return !check_case_failed();
}
#endif
