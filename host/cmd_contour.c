/* adaslice contour: PrusaSlicer's G-code of a part planned with plan --3mf,
   with the paths that form the part's top surface moved in Z onto the mesh
   (issue 25; Z modulation after Song et al. 2017, GCodeZAA). See
   contour_usage for what it does and README for how to use it.

   The surface under a point is the first upward crossing above the layer's
   bottom of the z LDI's ray there (adaslice_ldi_ray). PrusaSlicer prints a
   point in a layer when the mesh is solid at the layer's middle, so the
   surface over a layer's top-most paths lies within half a layer of its top,
   and raising a path by up to half of the next layer's height never meets
   what the next layer prints. */
#include "commands.h"
#include "gcode.h"
#include "options.h"
#include "output.h"
#include "path_svg.h"
#include "report.h"
#include "formats/threemf.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* X, Y and Z farther from the origin than any FDM printer reaches: refused */
#define GCODE_REACH_MM 1e4

#define CROSSINGS_MAX 64
/* the thinnest bead a path is lowered to over what lies under it, a
   fraction of the layer's height */
#define MIN_BEAD 0.25
/* how far above the layer's highest contoured point the nozzle travels */
#define TRAVEL_CLEARANCE 0.2
/* the deposit map's cells, mm */
#define CELL 0.1
/* the risen skins' map's squares, mm (travels lift over them) */
#define BLOCK 1.0
/* a bead's width before any ;WIDTH: */
#define DEFAULT_WIDTH 0.45
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct contour_args {
    const char *in, *project, *out;
    double resolution, max_rise, max_angle;
    int top_skins;               /* --top-skins */
    double clearance, clearance_angle; /* --nozzle-clearance, --clearance-angle */
    size_t view_layer;           /* --svg-path: the layer drawn, from 1; 0 none */
    const char *view_out;
} contour_args;

static void contour_usage(FILE *f)
{
    fputs("usage: adaslice contour IN.gcode --project PART.3mf -o OUT.gcode [options]\n"
          "\n"
          "Moves PrusaSlicer's paths that form the part's top surface onto the mesh: the\n"
          "3MF is the one plan --3mf wrote and PrusaSlicer sliced into IN.gcode. Every\n"
          "extrusion of the part's own features (perimeters, solid and top solid infill,\n"
          "gap fill, ironing; not sparse or bridge infill, skirt, brim or support) whose\n"
          "point has the mesh's top within the layer above it, on a surface no steeper\n"
          "than --max-angle, is split into pieces of at most --resolution and each point\n"
          "put at the surface: never lower than what lies under it plus a quarter of\n"
          "the layer, never higher than --max-rise over the layer's top (and half the\n"
          "next layer's height, which that layer leaves free), the path no steeper than\n"
          "--max-angle. Where the surface ends the path ramps back to the layer's plane\n"
          "at that slope. E follows the height each piece fills; travel moves rise\n"
          "over the layer's raised paths; every other line, and every move the surface\n"
          "leaves in the plane, is kept byte for byte.\n"
          "Reads PrusaSlicer 2.5 G-code of flavour reprap, reprapfirmware, marlin,\n"
          "marlin2, klipper, repetier, smoothie, sprinter or teacup: absolute XYZ\n"
          "(G90), absolute or relative E, no arcs.\n"
          "\n"
          "  --project FILE      the 3MF PrusaSlicer sliced\n"
          "  -o, --out FILE      the G-code written\n"
          "  --resolution MM     the longest piece of a contoured path            [0.2]\n"
          "  --max-rise MM       the most a path rises above its layer's top\n"
          "                                                 [half the layer's height]\n"
          "  --max-angle DEG     the steepest surface followed, and path slope      [15]\n"
          "  --top-skins         let the topmost skins rise above --max-rise, up to\n"
          "                      --nozzle-clearance, where no later print comes near:\n"
          "                      true non-planar tops; needs the two options below\n"
          "  --nozzle-clearance MM  the nozzle's free height under its heater block or fan duct\n"
          "  --clearance-angle DEG  the nozzle cone's flank, degrees from horizontal: no path\n"
          "                      is steeper, and no later print's nozzle may meet a risen skin\n"
          "  --svg-path LAYER FILE  also an SVG of the longest contoured move of layer\n"
          "                      LAYER (from 1, as the ;Z: lines count) from the side: Z\n"
          "                      along it before, after, and the mesh's surface under it\n"
          "A project from plan --hybrid carries the limits its plan was made for: they\n"
          "replace the defaults (the options given still win).\n", f);
}

static int parse_contour(int argc, char **argv, contour_args *a, int *help)
{
    int i, rc = RC_OK;
    memset(a, 0, sizeof *a); /* 0: the project's hybrid plan's limit, else the default */
    for (i = 1; i < argc && !rc; i++) {
        const char *o = argv[i];
        if (o[0] != '-' || !o[1]) {
            if (a->in) return complain(RC_USAGE, "unexpected argument %s: IN.gcode is already %s", o, a->in);
            a->in = o;
        }
        else if (!strcmp(o, "--help") || !strcmp(o, "-h")) { *help = 1; return RC_OK; }
        else if (!strcmp(o, "--project")) rc = file_option(argc, argv, &i, &a->project);
        else if (!strcmp(o, "-o") || !strcmp(o, "--out")) rc = file_option(argc, argv, &i, &a->out);
        else if (!strcmp(o, "--resolution")) rc = number_option(argc, argv, &i, 0, &a->resolution);
        else if (!strcmp(o, "--max-rise")) rc = number_option(argc, argv, &i, 0, &a->max_rise); /* 0 read as "not given" */
        else if (!strcmp(o, "--top-skins")) a->top_skins = 1;
        else if (!strcmp(o, "--nozzle-clearance")) rc = number_option(argc, argv, &i, 0, &a->clearance);
        else if (!strcmp(o, "--clearance-angle")) {
            if (!(rc = number_option(argc, argv, &i, 0, &a->clearance_angle)) && a->clearance_angle >= 90)
                return complain(RC_USAGE, "--clearance-angle %g: a flank is under 90 degrees", a->clearance_angle);
        }
        else if (!strcmp(o, "--svg-path")) {
            if ((rc = count_option(argc, argv, &i, (size_t)1 << 30, &a->view_layer))) return rc;
            if (i + 1 >= argc || !strncmp(argv[i + 1], "--", 2))
                return complain(RC_USAGE, "--svg-path %s needs the SVG's path after the layer", argv[i]);
            a->view_out = argv[++i];
        }
        else if (!strcmp(o, "--max-angle")) {
            if (!(rc = number_option(argc, argv, &i, 0, &a->max_angle)))
                rc = contour_limit_check("--max-angle ", "max_angle", a->max_angle, RC_USAGE);
        }
        else return complain(RC_USAGE, "unknown option %s (see adaslice contour --help)", o);
    }
    if (rc) return rc;
    if (!a->in) return complain(RC_USAGE, "contour needs IN.gcode (see adaslice contour --help)");
    if (!a->project) return complain(RC_USAGE, "contour needs --project PART.3mf, the 3MF PrusaSlicer sliced");
    if (!a->out) return complain(RC_USAGE, "contour needs -o OUT.gcode");
    if (a->resolution && (rc = contour_limit_check("--resolution ", "resolution", a->resolution, RC_USAGE))) return rc;
    if (a->max_rise && (rc = contour_limit_check("--max-rise ", "max_rise", a->max_rise, RC_USAGE))) return rc;
    if (a->top_skins && (!a->clearance || !a->clearance_angle))
        return complain(RC_USAGE, "--top-skins needs --nozzle-clearance MM and --clearance-angle DEG, your nozzle's");
    if (!a->top_skins && (a->clearance || a->clearance_angle))
        return complain(RC_USAGE, "--nozzle-clearance and --clearance-angle are for --top-skins");
    return RC_OK;
}

/* ---- the G-code, read whole and checked before anything is written */

typedef struct line_ref { size_t at, len; } line_ref;

typedef struct layer_info {
    double top, height;          /* ;Z: and ;HEIGHT:; top moves up by z_offset once the plan has matched it */
    double mark;                 /* ;Z: as the file says it */
    size_t line;                 /* the ;Z: line's index */
    size_t first_seg;            /* the layer's extrusions: gfile.segs from here to the next layer's */
    double e_in, e_out;          /* filament extruded, before and after */
} layer_info;

/* An extrusion move of the file: its ends on the plate, its bead's width, its line. */
typedef struct path_seg { double a[2], b[2], width; size_t line; } path_seg;

typedef struct gfile {
    char *text;
    size_t size;
    line_ref *lines;
    size_t count;
    layer_info *layers;
    size_t layer_count;
    double lo[2], hi[2];         /* the part's extrusions' extents */
    path_seg *segs;              /* every extrusion, in order */
    size_t seg_count, seg_cap;
    int relative_e_seen;
    double z_offset;             /* PrusaSlicer's z_offset: its moves are there above ;Z: */
} gfile;

/* PrusaSlicer 2.5's feature labels (ExtrusionEntity.cpp's role names):
   2 contoured, 1 the part's but left in the plane (sparse infill, bridges
   over air), 0 not the part. A label not here counts as the part's. */
static const struct { const char *name; int kind; } FEATURES[] = {
    {"External perimeter", 2}, {"Perimeter", 2}, {"Overhang perimeter", 2}, {"Solid infill", 2},
    {"Top solid infill", 2}, {"Gap fill", 2}, {"Ironing", 2}, {"Internal infill", 1}, {"Bridge infill", 1},
    {"Skirt/Brim", 0}, {"Skirt", 0}, {"Support material", 0}, {"Support material interface", 0},
    {"Wipe tower", 0}, {"Custom", 0}, {"Unknown", 0}};

/* The kind of the feature a ;TYPE: line names, -1 for another line. */
static int feature_kind(const char *line, size_t len)
{
    size_t i;
    if (!gcode_is_comment(line, len, "TYPE:")) return -1;
    line += 6;
    len -= 6;
    while (len && (line[len - 1] == '\r' || line[len - 1] == ' ')) len--;
    for (i = 0; i < sizeof FEATURES / sizeof *FEATURES; i++)
        if (strlen(FEATURES[i].name) == len && !memcmp(line, FEATURES[i].name, len)) return FEATURES[i].kind;
    return 1;
}

static void gfile_free(gfile *g)
{
    free(g->text);
    free(g->lines);
    free(g->layers);
    free(g->segs);
    memset(g, 0, sizeof *g);
}

static int read_text(const char *path, gfile *g)
{
    FILE *f = fopen(path, "rb");
    size_t cap = 0, n;
    if (!f) return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno));
    do {
        if (g->size + 1 >= cap) {
            char *t = (char *)realloc(g->text, cap = cap ? 2 * cap : 1 << 20);
            if (!t) { fclose(f); return complain(RC_FAIL, "out of memory"); }
            g->text = t;
        }
        g->size += n = fread(g->text + g->size, 1, cap - 1 - g->size, f);
    } while (n);
    if (ferror(f)) { fclose(f); return complain(RC_FAIL, "cannot read %s: %s", path, strerror(errno)); }
    fclose(f);
    g->text[g->size] = 0;
    return RC_OK;
}

static int split_lines(gfile *g)
{
    size_t i, start = 0, cap = 0;
    for (i = 0; i <= g->size; i++) {
        if (i < g->size && g->text[i] != '\n') continue;
        if (i == g->size && start == i) break;
        if (g->count == cap) {
            line_ref *l = (line_ref *)realloc(g->lines, (cap = cap ? 2 * cap : 1 << 16) * sizeof *l);
            if (!l) return complain(RC_FAIL, "out of memory");
            g->lines = l;
        }
        g->lines[g->count].at = start;
        g->lines[g->count++].len = i - start;
        start = i + 1;
    }
    return RC_OK;
}

/* The machine's state while the file is walked. */
typedef struct machine {
    double pos[4];               /* X Y Z E as the file has them */
    int relative_e;
    int kind;                    /* feature_kind of the feature under way; 0 before the first */
    double width;
    long layer;                  /* -1 before the first ;Z: */
} machine;

/* What a move does: 2 extrudes (XY and E forward), 1 travels (XY, E not
   forward), 0 neither. Updates m. */
static int step(machine *m, const gcode_words *w)
{
    double e = m->pos[3];
    int i, xy = (w->has & (GC_X | GC_Y)) != 0, forward;
    for (i = 0; i < 3; i++)
        if (w->has & (1u << i)) m->pos[i] = w->v[i];
    if (w->has & GC_E) m->pos[3] = m->relative_e ? e + w->v[3] : w->v[3];
    forward = (w->has & GC_E) && m->pos[3] > e;
    return xy ? (forward ? 2 : 1) : 0;
}

static int is_move(const gcode_words *w) { return w->letter == 'G' && (w->code == 0 || w->code == 1); }

/* Reads and checks the file: PrusaSlicer's, a flavour we take, no arcs, no
   relative XYZ, no inches, no shifted axes; the layers and the part's
   extents. RC_OK or a one-line complaint. */
static int gfile_read(const char *path, gfile *g)
{
    static const char *const FLAVOURS[] = {"reprap", "reprapfirmware", "marlin", "marlin2", "klipper",
                                           "repetier", "smoothie", "sprinter", "teacup"};
    const char *v;
    size_t i, n, cap = 0, f;
    machine m;
    int rc;
    if ((rc = read_text(path, g)) || (rc = split_lines(g))) return rc;
    if (!g->count || g->lines[0].len < 26 || memcmp(g->text + g->lines[0].at, "; generated by PrusaSlicer ", 27)) {
        char q[QUOTE_SIZE];
        return complain(RC_FAIL, "%s: line 1: %s: not PrusaSlicer's G-code (contour reads PrusaSlicer 2.5's)", path,
                        quote_text(q, g->text, g->count ? g->lines[0].len : 0));
    }
    if (!(v = gcode_config_value(g->text, g->size, "gcode_flavor", &n)))
        return complain(RC_FAIL, "%s: no \"; gcode_flavor = \" in the config at its end: a cut-off file?", path);
    for (f = 0; f < sizeof FLAVOURS / sizeof *FLAVOURS; f++)
        if (strlen(FLAVOURS[f]) == n && !memcmp(v, FLAVOURS[f], n)) break;
    if (f == sizeof FLAVOURS / sizeof *FLAVOURS) {
        char q[QUOTE_SIZE];
        return complain(RC_FAIL, "%s: gcode_flavor %s: contour writes G1 with Z for reprap, reprapfirmware, marlin, "
                                 "marlin2, klipper, repetier, smoothie, sprinter or teacup firmware", path,
                        quote_text(q, v, n));
    }
    /* the moves are z_offset above the ;Z: comments (not in the 3MF's plan) */
    if ((v = gcode_config_value(g->text, g->size, "z_offset", &n))) {
        const char *end = decimal_number(v, &g->z_offset);
        if (!end || end != v + n || !(fabs(g->z_offset) <= 10)) {
            char q[QUOTE_SIZE];
            return complain(RC_FAIL, "%s: z_offset %s in the config at its end: not a Z offset in mm (-10 to 10)", path,
                            quote_text(q, v, n));
        }
    }
    if ((v = gcode_config_value(g->text, g->size, "spiral_vase", &n)) && n == 1 && *v == '1')
        return complain(RC_FAIL, "%s: spiral_vase = 1: its Z climbs within each layer; contour reads planar layers", path);
    memset(&m, 0, sizeof m);
    m.layer = -1;
    g->lo[0] = g->lo[1] = HUGE_VAL;
    g->hi[0] = g->hi[1] = -HUGE_VAL;
    for (i = 0; i < g->count; i++) {
        const char *l = g->text + g->lines[i].at;
        size_t len = g->lines[i].len, bad;
        gcode_words w;
        double z;
        int k;
        if ((k = feature_kind(l, len)) >= 0) { m.kind = k; continue; }
        if (gcode_comment_number(l, len, "Z:", &z)) {
            if (g->layer_count == cap) {
                layer_info *t = (layer_info *)realloc(g->layers, (cap = cap ? 2 * cap : 256) * sizeof *t);
                if (!t) return complain(RC_FAIL, "out of memory");
                g->layers = t;
            }
            memset(&g->layers[g->layer_count], 0, sizeof *g->layers);
            g->layers[g->layer_count].top = g->layers[g->layer_count].mark = z;
            g->layers[g->layer_count].line = i;
            g->layers[g->layer_count].first_seg = g->seg_count;
            m.layer = (long)g->layer_count++;
            continue;
        }
        if (gcode_comment_number(l, len, "HEIGHT:", &z)) {
            if (m.layer < 0 || !(z > 0))
                return complain(RC_FAIL, "%s: line %zu: ;HEIGHT:%g %s", path, i + 1, z, m.layer < 0 ? "before the first ;Z:" : "is not a height");
            /* the first after ;Z: is the layer's; later ones are a feature's
               own (a bridge is as thick as the nozzle) */
            if (!(g->layers[m.layer].height > 0)) g->layers[m.layer].height = z;
            continue;
        }
        if (gcode_comment_number(l, len, "WIDTH:", &z)) { m.width = z; continue; }
        if (gcode_parse(l, len, &w, &bad)) {
            char q[QUOTE_SIZE];
            return complain(RC_FAIL, "%s: line %zu, byte %zu: %s: not a G-code word", path, i + 1, bad + 1,
                            quote_text(q, l + bad, len - bad));
        }
        if (w.letter == 'G' && (w.code == 2 || w.code == 3))
            return complain(RC_FAIL, "%s: line %zu: arc G%d: contour follows straight moves only (turn arc_fitting off)",
                            path, i + 1, w.code);
        if (w.letter == 'G' && w.code == 91)
            return complain(RC_FAIL, "%s: line %zu: G91, relative X Y Z: contour reads absolute coordinates", path, i + 1);
        if (w.letter == 'G' && w.code == 20)
            return complain(RC_FAIL, "%s: line %zu: G20, inches: contour reads millimetres", path, i + 1);
        if (w.letter == 'G' && w.code == 92 && (w.has & (GC_X | GC_Y | GC_Z)))
            return complain(RC_FAIL, "%s: line %zu: G92 sets X, Y or Z: contour reads unshifted coordinates", path, i + 1);
        if (w.letter == 'M' && (w.code == 82 || w.code == 83)) { m.relative_e = w.code == 83; g->relative_e_seen |= m.relative_e; }
        if (w.letter == 'G' && w.code == 92 && (w.has & GC_E)) m.pos[3] = w.v[3];
        if (is_move(&w)) {
            double e = m.pos[3], from[2];
            int moved, axis;
            from[0] = m.pos[0];
            from[1] = m.pos[1];
            moved = step(&m, &w);
            /* every move is cut into pieces later: one to 10^19 mm wrapped a count */
            for (axis = 0; axis < 3; axis++)
                if (!(fabs(m.pos[axis]) <= GCODE_REACH_MM))
                    return complain(RC_FAIL, "%s: line %zu: %c %g mm: beyond any printer's reach (%g mm)", path, i + 1,
                                    "XYZ"[axis], m.pos[axis], GCODE_REACH_MM);
            /* contour takes the layer's plane from ;Z:: a ;Z: lost or a Z moved
               within a layer would put the nozzle into what it printed */
            if (moved == 2 && m.layer >= 0 && m.kind &&
                fabs(m.pos[2] - (g->layers[m.layer].top + g->z_offset)) > 2e-3)
                return complain(RC_FAIL, "%s: line %zu: the part extruded at Z %g in the layer that ;Z:%g (line %zu) "
                                         "puts at %g%s: the ;Z: comments do not follow the moves", path, i + 1,
                                m.pos[2], g->layers[m.layer].top, g->layers[m.layer].line + 1,
                                g->layers[m.layer].top + g->z_offset, g->z_offset ? " with its z_offset" : "");
            if (moved == 2 && m.layer >= 0) {
                path_seg *sg;
                if (g->seg_count == g->seg_cap) {
                    path_seg *t = (path_seg *)realloc(g->segs, (g->seg_cap = g->seg_cap ? 2 * g->seg_cap : 4096) * sizeof *t);
                    if (!t) return complain(RC_FAIL, "out of memory");
                    g->segs = t;
                }
                sg = &g->segs[g->seg_count++];
                memcpy(sg->a, from, sizeof sg->a);
                memcpy(sg->b, m.pos, sizeof sg->b);
                sg->width = m.width > 0 && m.width < 10 ? m.width : DEFAULT_WIDTH;
                sg->line = i;
                g->layers[m.layer].e_in += m.pos[3] - e;
                if (m.kind) {
                    int a;
                    for (a = 0; a < 2; a++) {
                        if (m.pos[a] < g->lo[a]) g->lo[a] = m.pos[a];
                        if (m.pos[a] > g->hi[a]) g->hi[a] = m.pos[a];
                    }
                }
            }
        }
    }
    if (!g->layer_count) return complain(RC_FAIL, "%s: no ;Z: layer comments: not PrusaSlicer's print G-code", path);
    for (i = 0; i < g->layer_count; i++)
        if (!(g->layers[i].height > 0)) return complain(RC_FAIL, "%s: layer %zu (;Z:%g) has no ;HEIGHT:", path, i + 1, g->layers[i].top);
    if (!(g->lo[0] <= g->hi[0])) return complain(RC_FAIL, "%s: no extrusions of the part", path);
    return RC_OK;
}

/* ---- the part where PrusaSlicer put it */

typedef struct placement {
    double shift[3];             /* G-code = mesh + shift */
    double size_g[2], size_m[2];
    int bed_centred;             /* 1: the part's centre is the bed's (bed_shape), 0: elsewhere, -1: no bed_shape */
} placement;

/* PrusaSlicer centres the part's box on the bed and puts its bottom on it;
   the extrusions' box is the mesh's less about an extrusion width (the
   outer perimeter's centre line lies half a width in from the section). */
static int place(const contour_args *a, const gfile *g, const threemf_project *p, placement *pl)
{
    double lo[3], hi[3];
    size_t i, j = 0, n;
    int k;
    memset(pl, 0, sizeof *pl);
    adaslice_mesh_bounds(&p->mesh, lo, hi);
    for (k = 0; k < 2; k++) { /* both sizes first: the message gives x and y */
        pl->size_g[k] = g->hi[k] - g->lo[k];
        pl->size_m[k] = hi[k] - lo[k];
        pl->shift[k] = (g->lo[k] + g->hi[k]) / 2 - (lo[k] + hi[k]) / 2;
    }
    for (k = 0; k < 2; k++) {
        if (pl->size_g[k] > pl->size_m[k] + 0.2 || pl->size_g[k] < pl->size_m[k] - 2)
            return complain(RC_FAIL, "%s: the part is %.3f x %.3f mm in %s but %.3f x %.3f mm in %s: not the part "
                                     "the project holds", a->in, pl->size_g[0], pl->size_g[1], a->in, pl->size_m[0],
                            pl->size_m[1], a->project);
    }
    pl->shift[2] = -lo[2];
    /* PrusaSlicer centres a lone part on the bed (bed_shape "0x0,250x0,...");
       an arranged or moved one is elsewhere, and the extents still find it */
    {
        const char *v = gcode_config_value(g->text, g->size, "bed_shape", &n);
        double b[2] = {HUGE_VAL, HUGE_VAL}, t[2] = {-HUGE_VAL, -HUGE_VAL}, x, y;
        char text[256];
        char *q;
        pl->bed_centred = -1;
        if (v && n < sizeof text) {
            memcpy(text, v, n);
            text[n] = 0;
            /* "250x0" would read as a hexadecimal number */
            for (q = text; (q = strchr(q, 'x')) != NULL;) *q = ' ';
            for (q = text; q && sscanf(q, "%lf %lf", &x, &y) == 2; q = strchr(q, ',') ? strchr(q, ',') + 1 : NULL) {
                b[0] = x < b[0] ? x : b[0];
                b[1] = y < b[1] ? y : b[1];
                t[0] = x > t[0] ? x : t[0];
                t[1] = y > t[1] ? y : t[1];
            }
            if (b[0] < t[0] && b[1] < t[1])
                pl->bed_centred = fabs((g->lo[0] + g->hi[0]) / 2 - (b[0] + t[0]) / 2) < 0.05 &&
                                  fabs((g->lo[1] + g->hi[1]) / 2 - (b[1] + t[1]) / 2) < 0.05;
        }
    }
    /* every layer is one the plan made (PrusaSlicer leaves out empty ones),
       as thick as the plan made it: the beads' E follows the height */
    for (i = 0; i < g->layer_count; i++) {
        layer_info *L = &g->layers[i];
        double planned;
        while (j < p->layers && p->tops[j] < L->top - 2e-3) j++;
        if (j == p->layers || fabs(p->tops[j] - L->top) > 2e-3)
            return complain(RC_FAIL, "%s: layer %zu at Z %g is not one of the %zu layers %s plans: not sliced from this project",
                            a->in, i + 1, L->top, p->layers, a->project);
        planned = p->tops[j] - (j ? p->tops[j - 1] : 0);
        if (fabs(L->height - planned) > 2e-3)
            return complain(RC_FAIL, "%s: layer %zu (;Z:%g, line %zu): ;HEIGHT:%g, but %s plans it %g mm thick", a->in, i + 1,
                            L->top, L->line + 1, L->height, a->project, planned);
    }
    /* from here on every Z is where the moves are */
    for (i = 0; i < g->layer_count; i++) g->layers[i].top += g->z_offset;
    pl->shift[2] += g->z_offset;
    return RC_OK;
}

/* ---- the surface and what lies under the nozzle */

typedef struct surface {
    const adaslice_mesh *mesh;
    adaslice_ldi ldi;
    double shift[3];
    double cos_max;              /* of --max-angle: the steepest face followed */
    /* the deposit: the highest point printed so far per CELL square */
    float *top;
    int w, h;
    double origin[2];
    /* --top-skins, per cell: the lowest a later layer's nozzle may come
       there (the layer's bottom plus MIN_BEAD, as contour lowers no path
       further), and 1 + the last line of the layer being written that
       prints there (0: none); per BLOCK square, the highest risen skin */
    float *later;
    size_t *last_line;
    float *skin;
    int bw, bh;
} surface;

/* The mesh's top over the layer's bottom at G-code point (x, y): the first
   crossing above bottom, when the ray leaves the solid there through a face
   no steeper than --max-angle. 1 and *z (G-code Z), or 0. */
static int surface_at(const surface *s, double x, double y, double bottom, double *z)
{
    adaslice_crossing c[CROSSINGS_MAX];
    size_t n = adaslice_ldi_ray(&s->ldi, s->mesh, x - s->shift[0], y - s->shift[1], c, CROSSINGS_MAX), i;
    if (n > CROSSINGS_MAX) n = CROSSINGS_MAX;
    for (i = 0; i < n; i++) {
        const uint32_t *t;
        const float *p0, *p1, *p2;
        double e1[3], e2[3], nrm[3];
        int k;
        if (c[i].depth + s->shift[2] <= bottom + 1e-6) continue;
        if (!c[i].leaves) return 0;
        t = s->mesh->triangles + 3 * (size_t)c[i].face;
        p0 = s->mesh->vertices + 3 * (size_t)t[0];
        p1 = s->mesh->vertices + 3 * (size_t)t[1];
        p2 = s->mesh->vertices + 3 * (size_t)t[2];
        for (k = 0; k < 3; k++) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
        }
        nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
        nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
        nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
        if (!(nrm[2] > s->cos_max * sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]))) return 0;
        *z = c[i].depth + s->shift[2];
        return 1;
    }
    return 0;
}

/* The cells within r of (x, y) on the map: c[0..1] the columns, c[2..3]
   the rows (inclusive); 0 when none is (any coordinate a file holds). */
static int cell_range(const surface *s, double x, double y, double r, int c[4])
{
    double v[4];
    int k;
    v[0] = floor((x - r - s->origin[0]) / CELL);
    v[1] = floor((x + r - s->origin[0]) / CELL);
    v[2] = floor((y - r - s->origin[1]) / CELL);
    v[3] = floor((y + r - s->origin[1]) / CELL);
    if (!(v[1] >= 0 && v[0] < s->w && v[3] >= 0 && v[2] < s->h)) return 0;
    for (k = 0; k < 4; k++) {
        double most = k < 2 ? s->w - 1 : s->h - 1;
        c[k] = (int)(v[k] < 0 ? 0 : v[k] > most ? most : v[k]);
    }
    return 1;
}

/* The highest deposit within r of (x, y), or -HUGE_VAL where nothing is. */
static double deposit_near(const surface *s, double x, double y, double r)
{
    double best = -HUGE_VAL;
    int c[4], i, j;
    if (cell_range(s, x, y, r, c))
        for (j = c[2]; j <= c[3]; j++)
            for (i = c[0]; i <= c[1]; i++)
                if (s->top[(size_t)j * (size_t)s->w + (size_t)i] > best) best = s->top[(size_t)j * (size_t)s->w + (size_t)i];
    return best;
}

/* A segment printed: its ends and the bead's width. */
typedef struct bead { double a[3], b[3], width; } bead;

/* The bead onto the deposit map: a square of its width around every point
   of its centre line, half a cell apart. */
static void stamp(surface *s, const bead *d)
{
    double len = hypot(d->b[0] - d->a[0], d->b[1] - d->a[1]);
    int n = len < 1e6 ? (int)ceil(len / (CELL / 2)) : 0, q, c[4], i, j;
    for (q = 0; q <= n; q++) {
        double t = n ? (double)q / n : 0, x = d->a[0] + t * (d->b[0] - d->a[0]), y = d->a[1] + t * (d->b[1] - d->a[1]);
        float z = (float)(d->a[2] + t * (d->b[2] - d->a[2]));
        if (!cell_range(s, x, y, d->width / 2, c)) continue;
        for (j = c[2]; j <= c[3]; j++)
            for (i = c[0]; i <= c[1]; i++) {
                float *cell = &s->top[(size_t)j * (size_t)s->w + (size_t)i];
                if (z > *cell) *cell = z;
            }
    }
}

/* The cells of a bead from a to b of width `width` (a square of it around
   every point of its centre line, half a cell apart) to visit(s, cell, v). */
static void bead_cells(surface *s, const double a[2], const double b[2], double width,
                       void (*visit)(surface *s, size_t cell, double v), double v)
{
    double len = hypot(b[0] - a[0], b[1] - a[1]);
    int n = len < 1e6 ? (int)ceil(len / (CELL / 2)) : 0, q, c[4], i, j;
    for (q = 0; q <= n; q++) {
        double t = n ? (double)q / n : 0;
        if (!cell_range(s, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), width / 2, c)) continue;
        for (j = c[2]; j <= c[3]; j++)
            for (i = c[0]; i <= c[1]; i++) visit(s, (size_t)j * (size_t)s->w + (size_t)i, v);
    }
}

static void lower_later(surface *s, size_t cell, double v)
{
    if (v < s->later[cell]) s->later[cell] = (float)v;
}

static void mark_line(surface *s, size_t cell, double v) { s->last_line[cell] = (size_t)v; }

/* --top-skins: the maps of what prints after layer k's runs: every later
   layer's extrusions at that layer's lowest, up to the layers that start
   above the highest a skin of layer k may rise, and the lines of layer k. */
static void map_later_prints(surface *s, const gfile *g, size_t k, double clearance)
{
    size_t i, j, n = (size_t)s->w * (size_t)s->h;
    for (i = 0; i < n; i++) {
        s->later[i] = HUGE_VALF;
        s->last_line[i] = 0;
    }
    for (j = k + 1; j < g->layer_count; j++) {
        const layer_info *L = &g->layers[j];
        double floor_z = L->top - L->height + MIN_BEAD * L->height;
        size_t end = j + 1 < g->layer_count ? g->layers[j + 1].first_seg : g->seg_count;
        if (floor_z > g->layers[k].top + clearance) break;
        for (i = L->first_seg; i < end; i++) bead_cells(s, g->segs[i].a, g->segs[i].b, g->segs[i].width, lower_later, floor_z);
    }
    for (i = g->layers[k].first_seg; i < (k + 1 < g->layer_count ? g->layers[k + 1].first_seg : g->seg_count); i++)
        bead_cells(s, g->segs[i].a, g->segs[i].b, g->segs[i].width, mark_line, (double)(g->segs[i].line + 1));
}

/* The highest a topmost skin point at (x, y), bead `width`, of a run that
   ends before line `end` of layer L may rise: the clearance over the
   layer's top, and under every later print's nozzle cone. A later print at
   floor z_q whose bead lies d beyond this one's edge sees it outside its
   cone while it is under z_q + d tan(angle). */
static double skin_ceiling(const surface *s, const layer_info *L, double x, double y, double width, size_t end,
                           double clearance, double tan_clear)
{
    double cap = L->top + clearance, own = L->top - L->height + MIN_BEAD * L->height;
    double reach = (cap - own) / tan_clear + width / 2 + CELL;
    int c[4], i, j;
    if (!cell_range(s, x, y, reach, c)) return cap;
    for (j = c[2]; j <= c[3]; j++)
        for (i = c[0]; i <= c[1]; i++) {
            size_t cell = (size_t)j * (size_t)s->w + (size_t)i;
            double z = s->later[cell], d;
            if (s->last_line[cell] > end && own < z) z = own;
            if (z >= cap) continue;
            d = hypot(s->origin[0] + (i + 0.5) * CELL - x, s->origin[1] + (j + 0.5) * CELL - y) - CELL * 0.7072 - width / 2;
            if (z + (d > 0 ? d : 0) * tan_clear < cap) cap = z + (d > 0 ? d : 0) * tan_clear;
        }
    return cap;
}

/* The highest risen skin within `reach` of the travel from a to b, or
   -HUGE_VAL. */
static double skin_near(const surface *s, const double a[2], const double b[2], double reach)
{
    double best = -HUGE_VAL;
    int i0 = (int)floor(((a[0] < b[0] ? a[0] : b[0]) - reach - s->origin[0]) / BLOCK);
    int i1 = (int)floor(((a[0] > b[0] ? a[0] : b[0]) + reach - s->origin[0]) / BLOCK);
    int j0 = (int)floor(((a[1] < b[1] ? a[1] : b[1]) - reach - s->origin[1]) / BLOCK);
    int j1 = (int)floor(((a[1] > b[1] ? a[1] : b[1]) + reach - s->origin[1]) / BLOCK), i, j;
    if (!s->skin) return best;
    if (i0 < 0) i0 = 0;
    if (j0 < 0) j0 = 0;
    if (i1 >= s->bw) i1 = s->bw - 1;
    if (j1 >= s->bh) j1 = s->bh - 1;
    for (j = j0; j <= j1; j++)
        for (i = i0; i <= i1; i++)
            if (s->skin[(size_t)j * (size_t)s->bw + (size_t)i] > best) best = s->skin[(size_t)j * (size_t)s->bw + (size_t)i];
    return best;
}

static void note_skin(surface *s, double x, double y, double z)
{
    int i = (int)floor((x - s->origin[0]) / BLOCK), j = (int)floor((y - s->origin[1]) / BLOCK);
    if (i >= 0 && j >= 0 && i < s->bw && j < s->bh && z > s->skin[(size_t)j * (size_t)s->bw + (size_t)i])
        s->skin[(size_t)j * (size_t)s->bw + (size_t)i] = (float)z;
}

/* ---- writing */

typedef struct writer {
    const contour_args *a;
    gfile *g;
    surface *s;
    FILE *f;
    machine m;                   /* the input's state */
    double nozzle_z;             /* where the output has put the nozzle */
    double peak;                 /* the layer's highest contoured point, -HUGE_VAL before one */
    double tan_max;
    bead *beads;                 /* this layer's, stamped when it ends */
    size_t bead_count, bead_cap;
    int failed;
    /* what was done, for the report */
    size_t contoured_moves, points, raised, lowered;
    double dz_min, dz_max;
    size_t skin_points;          /* pieces' ends risen above the rise as top skins */
    double skin_max;             /* the most one rose over its layer's top */
    double tan_clear;            /* of --clearance-angle */
    /* --svg-path: the layer's longest contoured move so far, its ends, its
       Z in the file and its pieces as (s, z) */
    double view_from[2], view_to[2], view_z, view_length;
    double *view_sz;
    size_t view_n;
} writer;

/* Line i as it is, with its newline (the last line may have none). */
static void put_line(writer *w, size_t i)
{
    const line_ref *l = &w->g->lines[i];
    fwrite(w->g->text + l->at, 1, l->len + (l->at + l->len < w->g->size), w->f);
}

static void add_bead(writer *w, const double a[3], const double b[3], double width)
{
    if (w->bead_count == w->bead_cap) {
        bead *t = (bead *)realloc(w->beads, (w->bead_cap = w->bead_cap ? 2 * w->bead_cap : 4096) * sizeof *t);
        if (!t) { w->failed = 1; return; }
        w->beads = t;
    }
    memcpy(w->beads[w->bead_count].a, a, sizeof w->beads->a);
    memcpy(w->beads[w->bead_count].b, b, sizeof w->beads->b);
    w->beads[w->bead_count++].width = width > 0 && width < 10 ? width : DEFAULT_WIDTH;
}

static void end_layer(writer *w)
{
    size_t i;
    for (i = 0; i < w->bead_count; i++) stamp(w->s, &w->beads[i]);
    w->bead_count = 0;
    w->peak = -HUGE_VAL;
}

static void nozzle_to(writer *w, double z)
{
    fprintf(w->f, "G1 Z%.3f\n", z);
    w->nozzle_z = z;
}

/* A point of a contoured run: where it is, its distance along the run, and
   its height over the layer's top (0 where the surface is not followed). */
typedef struct point { double x, y, s, dz; int fixed; } point;

/* Keeps the move from `from` to `to` at Z z_in, contoured into pieces q[0..pieces]
   over the layer's top, for --svg-path. */
static void keep_view(writer *w, const point *q, size_t pieces, double top, const double from[2], const double to[2],
                      double z_in)
{
    double *t = (double *)realloc(w->view_sz, 2 * (pieces + 1) * sizeof *t);
    size_t k;
    if (!t) { w->failed = 1; return; }
    w->view_sz = t;
    for (k = 0; k <= pieces; k++) {
        t[2 * k] = hypot(q[k].x - from[0], q[k].y - from[1]);
        t[2 * k + 1] = top + q[k].dz;
    }
    w->view_n = pieces + 1;
    memcpy(w->view_from, from, sizeof w->view_from);
    memcpy(w->view_to, to, sizeof w->view_to);
    w->view_z = z_in;
    w->view_length = hypot(to[0] - from[0], to[1] - from[1]);
}

/* Limits |dz| to the slope tan_max along the run, towards 0 only: the
   largest and smallest functions of that slope under and over dz (two
   passes each), and 0 clamped between them, which has the slope too. */
static void limit_slope(point *p, size_t n, double t, double *lo, double *hi)
{
    size_t i;
    for (i = 0; i < n; i++) lo[i] = hi[i] = p[i].dz;
    for (i = 1; i < n; i++) {
        double d = t * (p[i].s - p[i - 1].s);
        if (lo[i - 1] + d < lo[i]) lo[i] = lo[i - 1] + d;
        if (hi[i - 1] - d > hi[i]) hi[i] = hi[i - 1] - d;
    }
    for (i = n - 1; i-- > 0;) {
        double d = t * (p[i + 1].s - p[i].s);
        if (lo[i + 1] + d < lo[i]) lo[i] = lo[i + 1] + d;
        if (hi[i + 1] - d > hi[i]) hi[i] = hi[i + 1] - d;
    }
    for (i = 0; i < n; i++) p[i].dz = lo[i] > 0 ? lo[i] : hi[i] < 0 ? hi[i] : 0;
}

/* Writes lines [first, end) of layer `layer`: a run of contoured extrusions
   with comments and feed rates between them. Starts at the machine's
   position; fixed_start/fixed_end: the neighbouring line prints in the
   plane, so the run starts or ends on it. */
static int write_run(writer *w, size_t first, size_t end, size_t layer, int fixed_start, int fixed_end)
{
    const layer_info *L = &w->g->layers[layer];
    double top = L->top, bottom = top - L->height, rise = w->a->max_rise > 0 ? w->a->max_rise : L->height / 2;
    double next = layer + 1 < w->g->layer_count ? w->g->layers[layer + 1].height / 2 : HUGE_VAL;
    point *p = NULL, *q;
    double *scratch = NULL;
    size_t n = 0, cap = 0, i, k;
    double e_out;
    machine m = w->m;
    if (next < rise) rise = next;
    /* the points: the start, then each move cut into pieces */
    for (i = first; i <= end; i++) {
        gcode_words g;
        size_t bad, pieces;
        double x0 = m.pos[0], y0 = m.pos[1], len;
        if (i < end) {
            gcode_parse(w->g->text + w->g->lines[i].at, w->g->lines[i].len, &g, &bad);
            if (!is_move(&g) || !(g.has & (GC_X | GC_Y))) continue;
            step(&m, &g);
        }
        len = hypot(m.pos[0] - x0, m.pos[1] - y0);
        pieces = i == end ? 0 : (size_t)ceil(len / w->a->resolution);
        if (i < end && !pieces) pieces = 1;
        if (n + pieces + 1 > cap) {
            point *t = (point *)realloc(p, (cap = 2 * (n + pieces + 1)) * sizeof *t);
            if (!t) {
                free(p);
                w->failed = 1;
                return complain(RC_FAIL, "out of memory for %zu points of layer %zu", n + pieces + 1, layer + 1);
            }
            p = t;
        }
        if (!n) {
            p[0].x = x0;
            p[0].y = y0;
            p[0].s = 0;
            n = 1;
        }
        for (k = 1; k <= pieces; k++, n++) {
            double t = (double)k / pieces;
            p[n].x = x0 + t * (m.pos[0] - x0);
            p[n].y = y0 + t * (m.pos[1] - y0);
            p[n].s = p[n - 1].s + len / pieces;
        }
    }
    for (k = 0; k < n; k++) {
        double width = w->m.width > 0 ? w->m.width : DEFAULT_WIDTH;
        double z, lo = bottom, dep = deposit_near(w->s, p[k].x, p[k].y, width / 2), ceiling;
        int followed;
        if (dep > lo) lo = dep;
        lo += MIN_BEAD * L->height;
        followed = surface_at(w->s, p[k].x, p[k].y, bottom, &z);
        ceiling = top + rise;
        if (followed && z > ceiling + 1e-9 && w->a->top_skins) {
            /* a topmost skin: on the surface if no later print's nozzle
               meets it there; a surface out of reach is inside the part */
            double cap = skin_ceiling(w->s, L, p[k].x, p[k].y, width, end, w->a->clearance, w->tan_clear);
            if (cap > ceiling) ceiling = cap;
        }
        /* a point the surface is more than rise above is inside the part:
           a later layer covers it */
        p[k].fixed = (k == 0 && fixed_start) || (k == n - 1 && fixed_end) || !followed || z > ceiling + 1e-9;
        if (p[k].fixed) z = top;
        if (z < lo) z = lo;
        p[k].dz = p[k].fixed ? 0 : z - top;
    }
    if (!(scratch = (double *)malloc(2 * n * sizeof *scratch))) {
        free(p);
        w->failed = 1;
        return complain(RC_FAIL, "out of memory for %zu points of layer %zu", n, layer + 1);
    }
    limit_slope(p, n, w->tan_max, scratch, scratch + n);
    free(scratch);
    /* the output: the nozzle onto the start, then every piece */
    if (fabs(w->nozzle_z - (top + p[0].dz)) > 5e-4) nozzle_to(w, top + p[0].dz);
    m = w->m;
    e_out = m.pos[3];
    q = p;
    for (i = first; i < end; i++) {
        gcode_words g;
        size_t bad, pieces;
        double x0 = m.pos[0], y0 = m.pos[1], e0 = m.pos[3], len, de;
        gcode_parse(w->g->text + w->g->lines[i].at, w->g->lines[i].len, &g, &bad);
        if (!is_move(&g) || !(g.has & (GC_X | GC_Y))) {
            /* comments, feature and width labels, feed rates: as they are */
            int kind = feature_kind(w->g->text + w->g->lines[i].at, w->g->lines[i].len);
            double width;
            if (kind >= 0) m.kind = kind;
            if (gcode_comment_number(w->g->text + w->g->lines[i].at, w->g->lines[i].len, "WIDTH:", &width)) m.width = width;
            put_line(w, i);
            continue;
        }
        step(&m, &g);
        de = m.pos[3] - e0;
        len = hypot(m.pos[0] - x0, m.pos[1] - y0);
        pieces = (size_t)ceil(len / w->a->resolution);
        if (!pieces) pieces = 1;
        for (k = 0; k <= pieces && fabs(q[k].dz) <= 5e-4; k++) {}
        if (k > pieces && fabs(w->nozzle_z - top) <= 5e-4) {
            /* a move the surface leaves in the plane: the file's own line */
            double from[3], to[3];
            if (!m.relative_e && fabs(e_out - e0) > 5e-6) fprintf(w->f, "G92 E%.5f\n", e0);
            put_line(w, i);
            e_out = m.pos[3];
            w->g->layers[layer].e_out += de;
            from[0] = x0; from[1] = y0; from[2] = top;
            to[0] = m.pos[0]; to[1] = m.pos[1]; to[2] = top;
            add_bead(w, from, to, m.width);
            q += pieces;
            continue;
        }
        w->contoured_moves++;
        if (layer + 1 == w->a->view_layer && len > w->view_length) {
            double from[2], to[2];
            from[0] = x0; from[1] = y0; to[0] = m.pos[0]; to[1] = m.pos[1];
            keep_view(w, q, pieces, top, from, to, m.pos[2]);
        }
        for (k = 1; k <= pieces; k++) {
            const point *a = q + k - 1, *b = q + k;
            double za = top + a->dz, zb = top + b->dz, fill, piece;
            double from[3], to[3];
            /* contoured runs of successive layers do not overlap (the rise
               stops at the next layer's half), so a piece fills from the
               layer's bottom */
            fill = (za + zb) / 2 - bottom;
            if (fill < MIN_BEAD * L->height) fill = MIN_BEAD * L->height;
            piece = de / pieces * fill / L->height;
            e_out += piece;
            w->g->layers[layer].e_out += piece;
            fprintf(w->f, "G1 X%.3f Y%.3f Z%.3f E%.5f", b->x, b->y, zb, m.relative_e ? piece : e_out);
            if (k == 1 && (g.has & GC_F)) fprintf(w->f, " F%.9g", g.v[4]);
            fputc('\n', w->f);
            from[0] = a->x; from[1] = a->y; from[2] = za;
            to[0] = b->x; to[1] = b->y; to[2] = zb;
            add_bead(w, from, to, m.width);
            w->nozzle_z = zb;
            if (za > w->peak) w->peak = za;
            if (zb > w->peak) w->peak = zb;
            if (b->dz > 5e-4) w->raised++;
            if (b->dz > rise + 1e-6) {
                w->skin_points++;
                if (b->dz > w->skin_max) w->skin_max = b->dz;
                note_skin(w->s, a->x, a->y, za);
                note_skin(w->s, b->x, b->y, zb);
            }
            if (b->dz < -5e-4) w->lowered++;
            if (b->dz < w->dz_min) w->dz_min = b->dz;
            if (b->dz > w->dz_max) w->dz_max = b->dz;
            w->points++;
        }
        q += pieces;
    }
    /* absolute E: the extruder's count back where the file has it, so the
       lines after keep theirs */
    if (!m.relative_e && fabs(e_out - m.pos[3]) > 5e-6) fprintf(w->f, "G92 E%.5f\n", m.pos[3]);
    w->m = m;
    free(p);
    return RC_OK;
}

/* Whether move g is a contoured extrusion (1), another extrusion (2) or
   neither (0) from state m. */
static int move_role(const machine *m, const gcode_words *g)
{
    machine t = *m;
    if (!is_move(g) || step(&t, g) != 2) return 0;
    return m->kind == 2 && m->layer >= 0 && !(g->has & GC_Z) ? 1 : 2;
}

/* Lines inside a run that leave it whole: comments, labels, feed rates. */
static int inert(const writer *w, size_t i, const gcode_words *g)
{
    const char *l = w->g->text + w->g->lines[i].at;
    size_t len = w->g->lines[i].len;
    int kind;
    if (gcode_is_comment(l, len, "Z:") || gcode_is_comment(l, len, "LAYER_CHANGE")) return 0;
    if ((kind = feature_kind(l, len)) >= 0) return kind == 2;
    if (!g->letter) return 1;
    return is_move(g) && g->has == GC_F;
}

static int write_all(writer *w)
{
    size_t i, n = w->g->count;
    int prev_extrudes = 0;
    for (i = 0; i < n && !w->failed; i++) {
        const char *l = w->g->text + w->g->lines[i].at;
        size_t len = w->g->lines[i].len, bad, j, k, last;
        gcode_words g;
        double v;
        int kind, role;
        if ((kind = feature_kind(l, len)) >= 0) w->m.kind = kind;
        if (gcode_comment_number(l, len, "WIDTH:", &v)) w->m.width = v;
        if (gcode_comment_number(l, len, "Z:", &v)) {
            if (w->m.layer >= 0) end_layer(w);
            w->m.layer++;
            if (w->a->top_skins) map_later_prints(w->s, w->g, (size_t)w->m.layer, w->a->clearance);
        }
        gcode_parse(l, len, &g, &bad);
        if (g.letter == 'M' && (g.code == 82 || g.code == 83)) w->m.relative_e = g.code == 83;
        if (g.letter == 'G' && g.code == 92 && (g.has & GC_E)) w->m.pos[3] = g.v[3];
        role = move_role(&w->m, &g);
        if (role == 1) {
            /* the run: this move and the contoured moves after it, with the
               inert lines between them */
            machine mm = w->m;
            gcode_words h;
            int next_extrudes = 0;
            step(&mm, &g);
            for (j = i + 1; j < n; j++) {
                const char *lj = w->g->text + w->g->lines[j].at;
                size_t lenj = w->g->lines[j].len;
                gcode_parse(lj, lenj, &h, &bad);
                if ((kind = feature_kind(lj, lenj)) >= 0) {
                    if (kind != 2) break;
                    mm.kind = kind;
                } else if (is_move(&h) && (h.has & (GC_X | GC_Y))) {
                    if (move_role(&mm, &h) != 1) break;
                    step(&mm, &h);
                } else if (!inert(w, j, &h)) {
                    break;
                }
            }
            /* does the next move print in the plane straight after the run? */
            for (last = j, k = j; k < n; k++) {
                const char *lk = w->g->text + w->g->lines[k].at;
                gcode_parse(lk, w->g->lines[k].len, &h, &bad);
                if ((kind = feature_kind(lk, w->g->lines[k].len)) >= 0) mm.kind = kind;
                else if (is_move(&h) && (h.has & (GC_X | GC_Y))) { next_extrudes = move_role(&mm, &h) != 0; break; }
                else if (h.letter) break;
            }
            if (write_run(w, i, last, (size_t)w->m.layer, prev_extrudes, next_extrudes)) return RC_FAIL;
            prev_extrudes = 1;
            i = last - 1;
            continue;
        }
        if (is_move(&g)) {
            double before[3], after[3];
            machine m = w->m;
            int what = step(&m, &g);
            memcpy(before, w->m.pos, sizeof before);
            if (what == 1 && !(g.has & GC_Z)) {
                /* a travel: over the layer's raised paths, never through the
                   layer's plane */
                double want = w->peak > m.pos[2] + 5e-4 ? w->peak + TRAVEL_CLEARANCE : m.pos[2];
                double skin = skin_near(w->s, before, m.pos, w->a->clearance + 2 * DEFAULT_WIDTH);
                if (skin + TRAVEL_CLEARANCE > want && skin > m.pos[2] - 5e-4) want = skin + TRAVEL_CLEARANCE;
                if (w->nozzle_z < want - 5e-4) nozzle_to(w, want);
            } else if (what == 2 && !(g.has & GC_Z) && fabs(w->nozzle_z - m.pos[2]) > 5e-4) {
                nozzle_to(w, m.pos[2]);
            }
            put_line(w, i);
            if (g.has & GC_Z) w->nozzle_z = m.pos[2];
            if (what == 2 && m.layer >= 0) {
                memcpy(after, m.pos, sizeof after);
                before[2] = after[2] = w->nozzle_z;
                add_bead(w, before, after, m.width);
                w->g->layers[m.layer].e_out += m.pos[3] - w->m.pos[3];
            }
            w->m = m;
            prev_extrudes = what == 2;
            continue;
        }
        put_line(w, i);
    }
    return w->failed ? complain(RC_FAIL, "out of memory") : RC_OK;
}

static void put_view(FILE *f, const void *fig) { svg_write_path(f, (const path_figure *)fig); }

/* The --svg-path figure: the kept move before (flat at its Z in the file),
   after, and the mesh's surface under it every quarter piece, where contour
   follows it. */
static int write_view(const contour_args *a, const gfile *g, const surface *s, const writer *w)
{
    const layer_info *L = &g->layers[a->view_layer - 1];
    size_t n, k;
    double before[4], *mesh;
    char title[256];
    path_figure fig;
    int rc;
    if (!w->view_n)
        return complain(RC_FAIL, "--svg-path %zu: layer %zu (;Z:%g) of %s has no contoured move to draw", a->view_layer,
                        a->view_layer, L->mark, a->in);
    n = (size_t)ceil(w->view_length / (a->resolution / 4)) + 1;
    if (!(mesh = (double *)malloc(2 * n * sizeof *mesh))) return complain(RC_FAIL, "out of memory");
    for (k = 0; k < n; k++) {
        double t = (double)k / (double)(n - 1), z;
        mesh[2 * k] = t * w->view_length;
        mesh[2 * k + 1] = surface_at(s, w->view_from[0] + t * (w->view_to[0] - w->view_from[0]),
                                     w->view_from[1] + t * (w->view_to[1] - w->view_from[1]), L->top - L->height, &z) ? z : NAN;
    }
    before[0] = 0;
    before[1] = before[3] = w->view_z;
    before[2] = w->view_length;
    snprintf(title, sizeof title, "%s, layer %zu of %zu at %g mm: its longest contoured move, %.1f mm, from the side",
             base_name(a->project), a->view_layer, g->layer_count, L->top, w->view_length);
    memset(&fig, 0, sizeof fig);
    fig.title = title;
    fig.layer = a->view_layer;
    fig.top = L->top;
    memcpy(fig.from, w->view_from, sizeof fig.from);
    memcpy(fig.to, w->view_to, sizeof fig.to);
    fig.mesh.sz = mesh;
    fig.mesh.count = n;
    fig.before.sz = before;
    fig.before.count = 2;
    fig.after.sz = w->view_sz;
    fig.after.count = w->view_n;
    rc = write_atomic(a->view_out, put_view, &fig);
    free(mesh);
    return rc;
}

int cmd_contour(int argc, char **argv)
{
    contour_args a;
    threemf_project p;
    gfile g;
    placement pl;
    surface s;
    writer w;
    output o;
    adaslice_error err;
    adaslice_grid grid;
    double worst = 0;
    int help = 0, rc, k, limits_from_plan;
    size_t i;
    if ((rc = parse_contour(argc, argv, &a, &help))) return rc;
    if (help) { contour_usage(stdout); return RC_OK; }
    outputs_add_input(a.in);
    outputs_add_input(a.project);
    if ((rc = output_check("-o", a.out)) || (rc = output_check("--svg-path", a.view_out))) return rc;
    {
        const char *const options[] = {"-o", "--svg-path"};
        const char *const paths[] = {a.out, a.view_out};
        if ((rc = output_check_distinct(options, paths, 2))) return rc;
    }
    memset(&g, 0, sizeof g);
    memset(&s, 0, sizeof s);
    if ((rc = gfile_read(a.in, &g))) { gfile_free(&g); return rc; }
    if (a.view_layer > g.layer_count) {
        rc = complain(RC_FAIL, "--svg-path %zu: %s has %zu layers", a.view_layer, a.in, g.layer_count);
        gfile_free(&g);
        return rc;
    }
    if ((rc = threemf_read(a.project, &p))) { gfile_free(&g); return rc; }
    /* the limits a hybrid plan was made for (it bounded its residual with
       them), where the command line gives none */
    limits_from_plan = (!a.max_angle && p.max_angle) || (!a.max_rise && p.max_rise) || (!a.resolution && p.resolution);
    if (!a.max_angle) a.max_angle = p.max_angle ? p.max_angle : 15;
    if (!a.max_rise) a.max_rise = p.max_rise;
    if (!a.resolution) a.resolution = p.resolution ? p.resolution : 0.2;
    if ((rc = place(&a, &g, &p, &pl))) goto done;
    s.mesh = &p.mesh;
    memcpy(s.shift, pl.shift, sizeof s.shift);
    s.cos_max = cos(a.max_angle * M_PI / 180);
    grid = adaslice_grid_fit(&p.mesh, ADASLICE_AXIS_Z, 2048);
    if (adaslice_ldi_build(&p.mesh, &grid, NULL, &s.ldi, &err) != ADASLICE_OK) { rc = library_error(&err); goto done; }
    /* the deposit map over the part's extrusions and a margin */
    for (k = 0; k < 2; k++) s.origin[k] = g.lo[k] - 2;
    s.w = (int)ceil((g.hi[0] - g.lo[0] + 4) / CELL);
    s.h = (int)ceil((g.hi[1] - g.lo[1] + 4) / CELL);
    if (!(s.top = (float *)malloc((size_t)s.w * (size_t)s.h * sizeof *s.top))) { rc = complain(RC_FAIL, "out of memory"); goto done; }
    for (i = 0; i < (size_t)s.w * (size_t)s.h; i++) s.top[i] = -HUGE_VALF;
    if (a.top_skins) {
        s.bw = (int)ceil(s.w * CELL / BLOCK);
        s.bh = (int)ceil(s.h * CELL / BLOCK);
        s.later = (float *)malloc((size_t)s.w * (size_t)s.h * sizeof *s.later);
        s.last_line = (size_t *)malloc((size_t)s.w * (size_t)s.h * sizeof *s.last_line);
        s.skin = (float *)malloc((size_t)s.bw * (size_t)s.bh * sizeof *s.skin);
        if (!s.later || !s.last_line || !s.skin) { rc = complain(RC_FAIL, "out of memory"); goto done; }
        for (i = 0; i < (size_t)s.bw * (size_t)s.bh; i++) s.skin[i] = -HUGE_VALF;
    }
    memset(&w, 0, sizeof w);
    w.a = &a;
    w.g = &g;
    w.s = &s;
    w.m.layer = -1;
    w.peak = -HUGE_VAL;
    /* a top skin's path no steeper than the nozzle's flank */
    w.tan_max = tan((a.top_skins && a.clearance_angle < a.max_angle ? a.clearance_angle : a.max_angle) * M_PI / 180);
    w.tan_clear = a.top_skins ? tan(a.clearance_angle * M_PI / 180) : 0;
    if ((rc = output_open(&o, a.out, 0))) goto done;
    w.f = o.f;
    rc = write_all(&w);
    if (!rc && a.view_out) rc = write_view(&a, &g, &s, &w);
    {
        int closed = output_close(&o, rc == RC_OK, 0); /* says why a write failed */
        if (!rc) rc = closed;
    }
    free(w.beads);
    free(w.view_sz);
    if (rc) goto done;
    for (i = 0; i < g.layer_count; i++)
        if (g.layers[i].e_in > 0 && fabs(g.layers[i].e_out / g.layers[i].e_in - 1) > fabs(worst)) worst = g.layers[i].e_out / g.layers[i].e_in - 1;
    printf("%s: PrusaSlicer G-code, %zu layers, E %s; the part%s %s: shifted %.3f, %.3f, %.3f mm from the project's mesh "
           "(extrusions %.2f x %.2f mm, mesh %.2f x %.2f mm)\n", a.in, g.layer_count, g.relative_e_seen ? "relative" : "absolute",
           p.transformed ? " (through the 3MF's build transform)" : "",
           pl.bed_centred == 1 ? "centred on the bed as PrusaSlicer puts it"
                               : pl.bed_centred == 0 ? "off the bed's centre (arranged or moved), found by its extrusions"
                                                     : "found by its extrusions",
           pl.shift[0], pl.shift[1], pl.shift[2], pl.size_g[0], pl.size_g[1], pl.size_m[0], pl.size_m[1]);
    if (limits_from_plan)
        printf("%s: the hybrid plan's limits: --max-angle %g --max-rise %g --resolution %g\n", a.project, a.max_angle,
               a.max_rise, a.resolution);
    printf("%s: %zu extrusion moves contoured into %zu pieces (%zu raised, %zu lowered, %+.3f to %+.3f mm off the layer "
           "tops); E per layer within %+.2f%%\n", a.out, w.contoured_moves, w.points, w.raised, w.lowered,
           w.points ? w.dz_min : 0.0, w.points ? w.dz_max : 0.0, 100 * worst);
    if (a.top_skins)
        printf("%s: top skins: %zu pieces risen above the layer's rise limit, by up to %.3f mm over the layer's top "
               "(--nozzle-clearance %g, --clearance-angle %g)\n", a.out, w.skin_points, w.skin_max, a.clearance,
               a.clearance_angle);
done:
    adaslice_ldi_free(&s.ldi);
    free(s.top);
    free(s.later);
    free(s.last_line);
    free(s.skin);
    threemf_project_free(&p);
    gfile_free(&g);
    return rc;
}
