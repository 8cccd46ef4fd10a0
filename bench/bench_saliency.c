/* make bench: mesh saliency and view importance (default views and
   resolution) on the two 200K-triangle shared models, one core, median of 3
   runs; memory as the library's peak of live allocations (a counting
   allocator) and the process's peak resident size.
   usage: bench_saliency [MODELS_DIR]   (default ../shared/models) */
#include "../adaslice.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "timing.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* Each block carries its size in front, so frees can be counted; 16 bytes
   keep the block aligned for anything the library stores. */
#define HEADER 16
typedef struct counter { size_t live, peak; } counter;

static void *count_alloc(void *user, size_t size)
{
    counter *c = (counter *)user;
    size_t *p = (size_t *)malloc(size + HEADER);
    if (!p) return NULL;
    *p = size;
    c->live += size;
    if (c->live > c->peak) c->peak = c->live;
    return (char *)p + HEADER;
}

static void count_free(void *user, void *ptr)
{
    size_t *p = (size_t *)((char *)ptr - HEADER);
    ((counter *)user)->live -= *p;
    free(p);
}

int main(int argc, char **argv)
{
    static const char *const models[] = {"turbineblade.ply", "dragon_vrip_res2.ply"};
    const char *dir = argc > 1 ? argv[1] : "../shared/models";
    int i, r, failed = 0;
    for (i = 0; i < 2; i++) {
        char path[1024];
        adaslice_mesh mesh;
        adaslice_error e;
        adaslice_surface_options o;
        adaslice_allocator al;
        counter c = {0, 0};
        struct rusage ru;
        double t[3], mid, above = 0;
        float *w;
        size_t k;
        snprintf(path, sizeof path, "%s/%s", dir, models[i]);
        if (adaslice_mesh_load_file(path, NULL, &mesh, &e) != ADASLICE_OK) {
            printf("saliency %-22s skipped: %s\n", models[i], e.message);
            continue;
        }
        w = (float *)malloc(mesh.triangle_count * sizeof *w);
        al.alloc = count_alloc;
        al.free = count_free;
        al.user = &c;
        memset(&o, 0, sizeof o);
        o.allocator = &al;
        for (r = 0; r < 3; r++) {
            double t0 = now();
            if (!w || adaslice_saliency(&mesh, w, &o, &e) != ADASLICE_OK) {
                printf("saliency %s failed: %s\n", models[i], w ? e.message : "out of memory");
                failed = 1;
                break;
            }
            t[r] = now() - t0;
        }
        if (r == 3) {
            for (k = 0; k < mesh.triangle_count; k++) above += w[k] > 0.5f;
            mid = median(t, 3); /* and sorts t */
            getrusage(RUSAGE_SELF, &ru);
            printf("saliency %-22s %7zu triangles %7zu vertices  median %6.3f s (%.3f .. %.3f)  "
                   "library peak %5.1f MiB  process max RSS %5.1f MiB  %.2f%% of faces above 0.5\n",
                   models[i], mesh.triangle_count, mesh.vertex_count, mid, t[0], t[2], c.peak / 1048576.0,
                   ru.ru_maxrss / 1024.0, 100.0 * above / (double)mesh.triangle_count);
            if (c.live) { printf("leak: %zu bytes still allocated\n", c.live); failed = 1; }
        }
        {
            adaslice_view_options vo;
            size_t seen = 0;
            memset(&vo, 0, sizeof vo);
            vo.allocator = &al;
            c.peak = c.live = 0;
            for (r = 0; r < 3; r++) {
                double t0 = now();
                if (!w || adaslice_view_importance(&mesh, w, &vo, &e) != ADASLICE_OK) {
                    printf("view importance %s failed: %s\n", models[i], w ? e.message : "out of memory");
                    failed = 1;
                    break;
                }
                t[r] = now() - t0;
            }
            if (r == 3) {
                for (k = 0; k < mesh.triangle_count; k++) seen += w[k] > 0;
                mid = median(t, 3);
                printf("view     %-22s %7zu triangles  %d views of %d px  median %6.3f s (%.3f .. %.3f)  library peak %5.1f MiB  "
                       "%.1f%% of faces seen from some view\n", models[i], mesh.triangle_count, ADASLICE_DEFAULT_VIEWS,
                       ADASLICE_DEFAULT_VIEW_RESOLUTION, mid, t[0], t[2], c.peak / 1048576.0,
                       100.0 * (double)seen / (double)mesh.triangle_count);
                if (c.live) { printf("leak: %zu bytes still allocated\n", c.live); failed = 1; }
            }
        }
        free(w);
        adaslice_mesh_free(&mesh);
    }
    return failed;
}
