/* Loading and repairing a model file: what plan, slice, print, orient and
   saliency share. */
#include "json.h"
#include "model.h"
#include "output.h"
#include "pages.h"
#include "report.h"
#include <math.h>
#include <string.h>

/* "3 facets" or "1 facet" into a list, comma-separated. */
static void item(char *buf, size_t size, size_t count, const char *one, const char *many)
{
    size_t used = strlen(buf);
    if (!count || used >= size) return;
    snprintf(buf + used, size - used, "%s%zu %s", used ? ", " : "", count, count == 1 ? one : many);
}

static void warn_repairs(const char *path, const adaslice_mesh_report *r)
{
    char fixed[512] = "", left[512] = "";
    item(fixed, sizeof fixed, r->flipped_facets, "facet turned", "facets turned");
    item(fixed, sizeof fixed, r->flipped_shells, "shell turned whole to face the way its nesting says",
         "shells turned whole to face the way their nesting says");
    item(fixed, sizeof fixed, r->welded_nearby, "vertex of a crack welded", "vertices of cracks welded");
    item(fixed, sizeof fixed, r->slivers_collapsed, "facet of zero area sealing a T-junction collapsed onto its long edge",
         "facets of zero area sealing T-junctions collapsed onto their long edges");
    item(fixed, sizeof fixed, r->degenerate_dropped, "facet of zero area dropped", "facets of zero area dropped");
    item(left, sizeof left, r->open_edges, "open edge (masks and areas close each layer's gaps)",
         "open edges (masks and areas close each layer's gaps)");
    item(left, sizeof left, r->nonmanifold_edges, "edge of three or more facets", "edges of three or more facets");
    item(left, sizeof left, r->inconsistent_edges, "edge whose facets cannot be wound alike",
         "edges whose facets cannot be wound alike");
    if (!fixed[0] && !left[0]) return;
    warn("%s:%s%s%s%s%s", path, fixed[0] ? " repaired " : "", fixed,
         fixed[0] && left[0] ? ";" : "", left[0] ? " left " : "", left);
}

/* A float holds a coordinate to 24 bits: far from the origin (CAD or survey
   coordinates) the part's shape is already coarser than a layer's bins when
   loaded. Said, not repaired: the file's own origin is the user's to move. */
static void warn_far_from_origin(const char *path, const adaslice_mesh *m)
{
    double far = 0, lo[3], hi[3], size = 0, ulp;
    size_t i;
    int e;
    for (i = 0; i < 3 * m->vertex_count; i++) {
        double c = fabs((double)m->vertices[i]);
        far = c > far ? c : far;
    }
    adaslice_mesh_bounds(m, lo, hi);
    for (i = 0; i < 3; i++) size = hi[i] - lo[i] > size ? hi[i] - lo[i] : size;
    (void)frexp(far, &e);
    ulp = ldexp(1, e - 24);
    /* a part 100 m tall is that coarse too, but only to 10^-7 of itself */
    if (ulp > 1e-3 && ulp > 1e-5 * size)
        warn("%s: vertices lie up to %g mm from the origin, where a float holds a coordinate "
             "only to %g mm: the part is loaded that coarse; move it near the origin in the file", path, far, ulp);
}

int model_load(const char *path, double scale, adaslice_mesh *mesh, adaslice_mesh_report *report)
{
    return model_load_timed(path, scale, mesh, report, NULL);
}

int model_load_timed(const char *path, double scale, adaslice_mesh *mesh, adaslice_mesh_report *report, double *ms_repair)
{
    adaslice_load_options lo;
    adaslice_repair_options ro;
    adaslice_mesh_report r;
    adaslice_error err;
    double t0;
    memset(&lo, 0, sizeof lo);
    lo.scale = scale;
    lo.allocator = pages_allocator();
    memset(&ro, 0, sizeof ro);
    ro.allocator = pages_allocator();
    if (adaslice_mesh_load_file(path, &lo, mesh, &err) != ADASLICE_OK) return library_error(&err);
    warn_far_from_origin(path, mesh);
    t0 = now_ms();
    if (adaslice_mesh_repair(mesh, &ro, &r, &err) != ADASLICE_OK) {
        adaslice_mesh_free(mesh);
        return complain(RC_FAIL, "%s: %s", path, err.message);
    }
    if (ms_repair) *ms_repair = now_ms() - t0;
    warn_repairs(path, &r);
    if (report) *report = r;
    return RC_OK;
}

void model_report_json(json_writer *w, const char *key, const adaslice_mesh_report *r)
{
    json_begin_object(w, key, 1);
    json_int(w, "shells", (long long)r->shells);
    json_int(w, "closed_shells", (long long)r->closed_shells);
    json_int(w, "open_edges", (long long)r->open_edges);
    json_int(w, "nonmanifold_edges", (long long)r->nonmanifold_edges);
    json_int(w, "inconsistent_edges", (long long)r->inconsistent_edges);
    json_int(w, "welded_nearby", (long long)r->welded_nearby);
    json_int(w, "degenerate_dropped", (long long)r->degenerate_dropped);
    json_int(w, "slivers_collapsed", (long long)r->slivers_collapsed);
    json_int(w, "flipped_facets", (long long)r->flipped_facets);
    json_int(w, "flipped_shells", (long long)r->flipped_shells);
    json_number(w, "volume_mm3", r->volume);
    /* an open mesh encloses no volume: the repair's figure closes each hole by a
       cone to its shell's centroid, the masks (and the resin) by chords */
    json_string(w, "volume_of", r->open_edges ? "the mesh, its holes closed by cones to each shell's centroid: not the "
                                                "resin (slice's manifest volume_mm3, its holes closed by chords)"
                                              : "the mesh");
    json_end(w);
}
