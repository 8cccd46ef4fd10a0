/* What printing a job costs, as users feel it.
   1. Writing each job format: the whole `adaslice slice` command on the
      turbine blade x4.3 on a 3840 x 2400 display of 50 um, in layers per
      second against the same command writing the PNG directory, each the
      median of FORMAT_RUNS runs taken in turn, and the directory on one thread
      against all the cores; and the directory on one thread held to each
      core in turn, as the cores of a virtual machine need not run alike (a
      busy neighbour on the host's other half of one core slows it by a
      third): what all the cores could do at best is each its share of the
      work at its own speed; and one copy of that job a core, all at once,
      for what the cores give together (a ceiling for one job's threads,
      lower than the sum of the cores alone where they share a physical
      core, its caches or memory). SL1 holds one layer height, so it is timed,
      with the directory beside it, on a uniform plan.
   2. Print time saved: every shared model's estimated print time (each
      layer's exposure by the working curve, settle, peel and return at the
      tool's defaults) with the optimal plan against the uniform plan with the
      thickest layers whose worst cusp error is no larger than the optimal
      plan's.
   3. Against PrusaSlicer: the whole `adaslice slice` (uniform 0.05 mm
      layers, a job directory) against `prusa-slicer --export-sla` on the
      same STL, layer height and 3840 x 2400 display of 35 um (its masks
      anti-aliased, supports and pad off), taken in turn, medians of RUNS:
      our 1-bit masks and our --aa 4 (exact coverage in 17 levels) against
      its anti-aliased export, and what --aa 4 costs against 1-bit, on the
      hand x60 and the turbine blade x4.3.
   usage: bench_jobs TOOL MODELS_DIR */
#ifdef __linux__
#define _GNU_SOURCE /* sched_setaffinity: a run held to one core */
#endif
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "../adaslice.h"
#include "../host/cure.h"
#include "../host/plan_job.h"
#include "models.h"
#include "timing.h"

#include <fcntl.h>
#include <math.h>
#ifdef __linux__
#include <sched.h>
#endif
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

#define RUNS 3
/* the first part's rounds: a round takes a few seconds, and two threads
   against one moved by a fifth from round to round on this project's
   machine, whose cores' speed drifts within seconds */
#define FORMAT_RUNS 7
#define CORES 8 /* held to each of the first CORES cores */

static char work[64];
static char stages[512]; /* the last slice's line of stage times ("time load ..."), or "" */

/* Runs argv with stdout into work/out; its wall time, or -1. */
static double run(char **argv, size_t *layers)
{
    posix_spawn_file_actions_t fa;
    char out[128], line[512];
    double t0 = now(), t;
    pid_t pid;
    int st = 0;
    FILE *f;
    snprintf(out, sizeof out, "%s/out", work);
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&pid, argv[0], &fa, NULL, argv, environ) != 0 || waitpid(pid, &st, 0) != pid || !WIFEXITED(st) ||
        WEXITSTATUS(st) != 0) {
        posix_spawn_file_actions_destroy(&fa);
        return -1;
    }
    t = now() - t0;
    posix_spawn_file_actions_destroy(&fa);
    *layers = 0;
    stages[0] = 0;
    if ((f = fopen(out, "r"))) {
        if (fgets(line, sizeof line, f) && strstr(line, " layers of ")) *layers = strtoul(strstr(line, ": ") + 2, NULL, 10);
        while (fgets(line, sizeof line, f))
            if (!strncmp(line, "time load ", 10)) snprintf(stages, sizeof stages, "%s", line + 5);
        fclose(f);
    }
    return t;
}

/* Runs argv as run() does, on core `core` alone (the child inherits this
   process's affinity); -1 where the cores cannot be chosen. */
static double run_on_core(char **argv, size_t *layers, int core)
{
#ifdef __linux__
    cpu_set_t all, one;
    double t;
    if (sched_getaffinity(0, sizeof all, &all) != 0) return -1;
    CPU_ZERO(&one);
    CPU_SET(core, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0) return -1;
    t = run(argv, layers);
    sched_setaffinity(0, sizeof all, &all);
    return t;
#else
    (void)argv;
    (void)layers;
    (void)core;
    return -1;
#endif
}

/* n copies of argv at once, copy i writing to its own out_i (argv's last
   is the -o name, which it changes and restores); their wall time until the
   last ends, or -1. What the cores give together when each runs a job of
   one thread: a ceiling for one job's threads, set by the machine (cores
   that share a physical core, its caches or its memory slow each other),
   not by the job. */
static double run_together(char **argv, int argc, int n)
{
    char *own = argv[argc - 1], names[CORES][160];
    pid_t pid[CORES];
    double t0, t;
    int i, st, ok = 1;
    t0 = now();
    for (i = 0; i < n; i++) {
        posix_spawn_file_actions_t fa;
        snprintf(names[i], sizeof names[i], "%s_%d", own, i);
        argv[argc - 1] = names[i];
        posix_spawn_file_actions_init(&fa);
        posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
        if (posix_spawn(&pid[i], argv[0], &fa, NULL, argv, environ) != 0) pid[i] = -1, ok = 0;
        posix_spawn_file_actions_destroy(&fa);
    }
    argv[argc - 1] = own;
    for (i = 0; i < n; i++)
        if (pid[i] < 0 || waitpid(pid[i], &st, 0) != pid[i] || !WIFEXITED(st) || WEXITSTATUS(st) != 0) ok = 0;
    t = now() - t0;
    return ok ? t : -1;
}

/* uniform: 1 on --uniform 0.1 (against the uniform directory), 2 on one thread */
typedef struct job { const char *name, *out; int uniform; } job;

static int time_formats(const char *tool, const char *dir)
{
    static const job jobs[] = {
        {"directory (PNG)", "job", 0}, {"ctb", "job.ctb", 0}, {"goo", "job.goo", 0}, {"chitu-zip", "job.zip", 0},
        {"directory, --threads 1", "one", 2},
        {"directory (PNG), uniform 0.1", "uniform", 1}, {"sl1, uniform 0.1", "job.sl1", 1}};
    enum { JOBS = sizeof jobs / sizeof jobs[0] };
    char model[4096], out[JOBS][128], one_out[128];
    double t[JOBS][FORMAT_RUNS], rate[JOBS], ratio[FORMAT_RUNS], on_core[CORES][FORMAT_RUNS], best[FORMAT_RUNS], bound[FORMAT_RUNS], ideal[FORMAT_RUNS],
        together[FORMAT_RUNS], share[FORMAT_RUNS];
    size_t layers[JOBS] = {0}, one_layers = 0;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int r, k, c;
    if (cores > CORES) cores = 0; /* too many to take in turn */
    snprintf(one_out, sizeof one_out, "%s/one", work);
    snprintf(model, sizeof model, "%s/turbineblade.ply", dir);
    for (k = 0; k < JOBS; k++) snprintf(out[k], sizeof out[k], "%s/%s", work, jobs[k].out);
    for (r = 0; r < FORMAT_RUNS; r++)
        for (k = 0; k < JOBS; k++) {
            char *argv[16];
            int a = 0;
            argv[a++] = (char *)tool;
            argv[a++] = (char *)"slice";
            argv[a++] = model;
            argv[a++] = (char *)"--scale";
            argv[a++] = (char *)"4.3";
            argv[a++] = (char *)"--pixels";
            argv[a++] = (char *)"3840x2400";
            argv[a++] = (char *)"--pitch";
            argv[a++] = (char *)"0.05";
            if (jobs[k].uniform == 1) { argv[a++] = (char *)"--uniform"; argv[a++] = (char *)"0.1"; }
            if (jobs[k].uniform == 2) { argv[a++] = (char *)"--threads"; argv[a++] = (char *)"1"; }
            argv[a++] = (char *)"-o";
            argv[a++] = out[k];
            argv[a] = NULL;
            if ((t[k][r] = run(argv, &layers[k])) < 0 || !layers[k]) {
                printf("bench_jobs: %s slice %s -o %s failed\n", tool, model, out[k]);
                return 1;
            }
            /* after the directory on one thread, the same held to each core,
               then one copy a core all at once */
            for (c = 0; jobs[k].uniform == 2 && c < cores; c++)
                if ((on_core[c][r] = run_on_core(argv, &one_layers, c)) < 0) cores = 0; /* not measured */
            if (jobs[k].uniform == 2 && cores > 1 && (together[r] = run_together(argv, a, (int)cores)) < 0) {
                printf("bench_jobs: %ld copies of %s slice %s --threads 1 at once failed\n", cores, tool, model);
                return 1;
            }
        }
    for (r = 0; r < FORMAT_RUNS; r++) { /* before median sorts the times */
        double speed = 0;
        ratio[r] = t[4][r] / t[0][r];
        best[r] = HUGE_VAL;
        for (c = 0; c < cores; c++) {
            speed += 1 / on_core[c][r];
            if (on_core[c][r] < best[r]) best[r] = on_core[c][r];
        }
        ideal[r] = cores ? 1 / speed : 0;  /* every core its share at its own speed */
        bound[r] = best[r] / ideal[r];     /* what that is against the fastest core alone */
        best[r] /= t[0][r];                /* all the cores against the fastest alone */
        ideal[r] = t[0][r] / ideal[r];     /* all the cores against that ideal */
        if (cores > 1) {
            together[r] = cores * t[4][r] / together[r]; /* one-thread jobs' work done at once, against one alone */
            share[r] = ratio[r] / together[r];            /* how much of that ceiling the job's threads reach */
        }
    }
    printf("slice turbineblade.ply x4.3, 3840 x 2400 px of 50 um: the whole command, median of %d\n", FORMAT_RUNS);
    printf("  %-30s %7s %9s %10s %s\n", "format", "layers", "seconds", "layers/s", "against the directory");
    for (k = 0; k < JOBS; k++) {
        double s = median(t[k], FORMAT_RUNS);
        int base = jobs[k].uniform == 1 ? 5 : 0;
        rate[k] = layers[k] / s;
        printf("  %-30s %7zu %9.2f %10.1f", jobs[k].name, layers[k], s, rate[k]);
        if (k != base) printf(" %.2fx", rate[k] / rate[base]);
        printf("\n");
    }
    /* the two threads' ratio run by run (the two jobs of one round of the
       seven), so that a drift of the machine's speed between rounds moves both */
    median(ratio, FORMAT_RUNS); /* sorts */
    printf("  all %ld cores against --threads 1, the directory: %.2fx (median of each run's ratio; %.2f-%.2fx)\n",
           sysconf(_SC_NPROCESSORS_ONLN), ratio[FORMAT_RUNS / 2], ratio[0], ratio[FORMAT_RUNS - 1]);
    if (!cores) {
        printf("  --threads 1 held to each core: not measured (more than %d cores, or they cannot be chosen here)\n", CORES);
        return 0;
    }
    printf("  --threads 1 held to each core, the directory:");
    for (c = 0; c < cores; c++) printf(" core %d %.2f s%s", c, median(on_core[c], FORMAT_RUNS), c + 1 < cores ? "," : "\n");
    /* each a median of its runs' ratios, each run's jobs taken in one round */
    median(best, FORMAT_RUNS);
    median(bound, FORMAT_RUNS);
    median(ideal, FORMAT_RUNS);
    printf("  all %ld cores against the fastest core alone: %.2fx (%.2f-%.2fx); at best %.2fx (%.2f-%.2fx), each core\n"
           "    its share of the whole command at its own speed; all cores took %.2fx (%.2f-%.2fx) that best time\n",
           sysconf(_SC_NPROCESSORS_ONLN), best[FORMAT_RUNS / 2], best[0], best[FORMAT_RUNS - 1], bound[FORMAT_RUNS / 2], bound[0], bound[FORMAT_RUNS - 1],
           ideal[FORMAT_RUNS / 2], ideal[0], ideal[FORMAT_RUNS - 1]);
    if (cores > 1) {
        median(together, FORMAT_RUNS);
        median(share, FORMAT_RUNS);
        printf("  %ld copies of --threads 1 at once, the directory: %.2fx the work of one alone in the time (%.2f-%.2fx),\n"
               "    what these cores give together; all cores on one job reached %.2f of it (%.2f-%.2f)\n",
               cores, together[FORMAT_RUNS / 2], together[0], together[FORMAT_RUNS - 1], share[FORMAT_RUNS / 2], share[0],
               share[FORMAT_RUNS - 1]);
    }
    return 0;
}

static int print_time_saved(const char *dir)
{
    double saved[BENCH_MODEL_COUNT];
    int n = 0;
    size_t i;
    cure_args c;
    cure_defaults(&c);
    if (cure_finish(&c, ADASLICE_DEFAULT_TMIN, ADASLICE_DEFAULT_TMAX)) return 1;
    printf("\nprint time, optimal plan against uniform layers of no larger worst cusp error (default eps, tmin, tmax;\n"
           "exposure %.3g s at %g mm, Dp %g mm; %g mm peel at %g mm/s, back at %g mm/s, %g s settle; %zu bottom layers of %g s)\n",
           c.cure.seconds, c.cure.thickness, c.cure.penetration, c.motion.lift_mm, c.motion.lift_speed,
           c.motion.retract_speed, c.motion.wait_before_cure_s, c.bottom_layers, c.bottom_exposure_s);
    printf("  %-28s %8s %9s %8s %9s %9s %7s\n", "model", "optimal", "time", "uniform", "at mm", "time", "saved");
    for (i = 0; i < BENCH_MODEL_COUNT; i++) {
        char path[4096];
        adaslice_load_options lo;
        adaslice_profile_options po;
        adaslice_plan_options o;
        adaslice_mesh m;
        adaslice_profile p;
        adaslice_plan best, uni;
        adaslice_error e;
        double t_best, t_uni;
        snprintf(path, sizeof path, "%s/%s", dir, BENCH_MODELS[i].name);
        memset(&lo, 0, sizeof lo);
        lo.scale = BENCH_MODELS[i].scale;
        memset(&po, 0, sizeof po);
        memset(&o, 0, sizeof o);
        if (adaslice_mesh_load_file(path, &lo, &m, &e) != ADASLICE_OK) { printf("  %s: %s\n", path, e.message); return 1; }
        if (adaslice_profile_exact(&m, &po, &p, &e) != ADASLICE_OK || adaslice_plan_profile(&p, &o, &best, &e) != ADASLICE_OK) {
            printf("  %-28.28s no plan: %s\n", BENCH_MODELS[i].name, e.message);
            adaslice_mesh_free(&m);
            continue;
        }
        if (!plan_uniform_no_worse(&p, &best, &uni)) {
            printf("  %-28.28s no uniform plan within %g\n", BENCH_MODELS[i].name, best.worst_error);
        } else {
            t_best = cure_plan_seconds(&c, &best);
            t_uni = cure_plan_seconds(&c, &uni);
            saved[n++] = 1 - t_best / t_uni;
            printf("  %-28.28s %8zu %8.0fs %8zu %9.3f %8.0fs %6.1f%%\n", BENCH_MODELS[i].name, best.layer_count, t_best,
                   uni.layer_count, uni.layers[0].thickness, t_uni, 100 * (1 - t_best / t_uni));
            adaslice_plan_free(&uni);
        }
        adaslice_plan_free(&best);
        adaslice_profile_free(&p);
        adaslice_mesh_free(&m);
    }
    if (n) printf("  median saving over %d models: %.1f%%\n", n, 100 * median(saved, n));
    return 0;
}

/* A binary STL of the model at scale, for PrusaSlicer, which reads no PLY. */
static int write_stl(const char *model, double scale, const char *out)
{
    adaslice_load_options lo;
    adaslice_mesh m;
    adaslice_error e;
    unsigned char head[84] = "adaslice bench", rec[50];
    size_t t;
    FILE *f;
    memset(&lo, 0, sizeof lo);
    lo.scale = scale;
    if (adaslice_mesh_load_file(model, &lo, &m, &e) != ADASLICE_OK) { printf("bench_jobs: %s: %s\n", model, e.message); return 1; }
    if (!(f = fopen(out, "wb"))) { adaslice_mesh_free(&m); return 1; }
    head[80] = (unsigned char)m.triangle_count;
    head[81] = (unsigned char)(m.triangle_count >> 8);
    head[82] = (unsigned char)(m.triangle_count >> 16);
    head[83] = (unsigned char)(m.triangle_count >> 24);
    fwrite(head, 1, 84, f);
    memset(rec, 0, sizeof rec);
    for (t = 0; t < m.triangle_count; t++) {
        int c;
        for (c = 0; c < 3; c++) memcpy(rec + 12 + 12 * c, m.vertices + 3 * m.triangles[3 * t + c], 12); /* little-endian floats */
        fwrite(rec, 1, 50, f);
    }
    adaslice_mesh_free(&m);
    return fclose(f) != 0;
}

static int against_prusaslicer(const char *tool, const char *dir)
{
    static const struct { const char *file; double scale; } parts[] = {{"hand_closed.obj", 60}, {"turbineblade.ply", 4.3}};
    size_t i;
    printf("\nslice against prusa-slicer --export-sla: the whole command, uniform 0.05 mm, 3840 x 2400 px of 35 um,\n"
           "medians of %d taken in turn (PrusaSlicer's masks are anti-aliased, as ours at --aa 4; supports and pad off;\n"
           "the last three columns: how many times faster than PrusaSlicer, and what --aa 4 costs against 1-bit)\n", RUNS);
    printf("  %-24s %7s %10s %10s %10s %9s %9s %9s\n", "model", "layers", "ours 1-bit", "ours aa 4", "PrusaSlicer", "1-bit",
           "aa 4", "aa/1-bit");
    for (i = 0; i < sizeof parts / sizeof parts[0]; i++) {
        char model[4096], stl[128], job[128], sl1[128], data[128], scale[32], ours_stages[512] = "";
        double t[3][RUNS];
        size_t layers = 0, dummy;
        int r, k;
        snprintf(model, sizeof model, "%s/%s", dir, parts[i].file);
        snprintf(stl, sizeof stl, "%s/part.stl", work);
        snprintf(job, sizeof job, "%s/ours", work);
        snprintf(sl1, sizeof sl1, "%s/theirs.sl1", work);
        snprintf(data, sizeof data, "%s/prusa-data", work);
        snprintf(scale, sizeof scale, "%g", parts[i].scale);
        mkdir(data, 0755);
        if (write_stl(model, parts[i].scale, stl)) return 1;
        for (r = 0; r < RUNS; r++)
            for (k = 0; k < 3; k++) {
                char *ours[] = {(char *)tool, (char *)"slice", stl, (char *)"--method", (char *)"finest",
                                (char *)"--pixels", (char *)"3840x2400", (char *)"--pitch", (char *)"0.035",
                                (char *)"--aa", (char *)(k ? "4" : "1"), (char *)"-o", job, NULL};
                char *theirs[] = {(char *)"/usr/bin/prusa-slicer", (char *)"--datadir", data, (char *)"--export-sla",
                                  (char *)"-o", sl1, (char *)"--printer-technology", (char *)"SLA",
                                  (char *)"--bed-shape", (char *)"0x0,134.4x0,134.4x84,0x84", (char *)"--display-width",
                                  (char *)"134.4", (char *)"--display-height", (char *)"84", (char *)"--display-pixels-x",
                                  (char *)"3840", (char *)"--display-pixels-y", (char *)"2400",
                                  (char *)"--display-orientation", (char *)"landscape", (char *)"--no-display-mirror-x",
                                  (char *)"--no-display-mirror-y", (char *)"--layer-height", (char *)"0.05",
                                  (char *)"--initial-layer-height", (char *)"0.05", (char *)"--max-print-height",
                                  (char *)"200", (char *)"--no-supports-enable", (char *)"--no-pad-enable", stl, NULL};
                t[k][r] = run(k < 2 ? ours : theirs, k < 2 ? &layers : &dummy);
                if (k == 0) memcpy(ours_stages, stages, sizeof stages);
                if (t[k][r] < 0) {
                    printf("bench_jobs: %s failed on %s\n", k < 2 ? tool : "prusa-slicer", parts[i].file);
                    return 1;
                }
            }
        {
            double a = median(t[0], RUNS), b = median(t[1], RUNS), p = median(t[2], RUNS);
            printf("  %-24s %7zu %9.2fs %9.2fs %10.2fs %8.2fx %8.2fx %8.2fx\n", parts[i].file, layers, a, b, p, p / a, p / b, b / a);
            if (ours_stages[0]) printf("    ours 1-bit, last run: %s", ours_stages);
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    int rc;
    char cmd[128];
    if (argc != 3) { fprintf(stderr, "usage: bench_jobs TOOL MODELS_DIR\n"); return 2; }
    snprintf(work, sizeof work, "/tmp/bench-jobs-XXXXXX");
    if (!mkdtemp(work)) { perror("mkdtemp"); return 1; }
    rc = time_formats(argv[1], argv[2]);
    if (!rc) rc = print_time_saved(argv[2]);
    if (!rc) rc = against_prusaslicer(argv[1], argv[2]);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", work);
    if (system(cmd) != 0) fprintf(stderr, "bench_jobs: could not remove %s\n", work);
    return rc;
}
