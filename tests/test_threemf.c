/* adaslice plan --3mf: PrusaSlicer slices the project layer for layer as
   planned (prusa_check.h), and bounds an FDM nozzle cannot lay are refused
   before anything is written. */
#include "prusa_check.h"

/* The hand is closed and thick: every planned layer is printed. */
static void prusaslicer_slices_the_bundled_hand_as_planned(void)
{
    prusa_result r;
    CHECK(prusa_slices_the_plan("examples/models/hand_closed.obj", 88.7, &r));
    CHECKF(r.planned > 150 && r.printed == r.planned, "%zu of %zu layers printed", r.printed, r.planned);
}

static void bounds_a_nozzle_cannot_lay_are_refused(void)
{
    static const char *const cases[][6] = {
        {"--tmax", "0.35", NULL, NULL, "0.4 mm nozzle lays layers up to 0.3 mm"},
        {"--tmax", "0.35", "--nozzle", "0.6", NULL},
        {"--tmin", "0.005", "--tmax", "0.2", "thinnest layer is 0.01 mm"},
        {"--nozzle", "0", NULL, NULL, "--nozzle"},
    };
    size_t c;
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char out[256];
        cli_result r;
        snprintf(out, sizeof out, "%s", cli_path("bounds.3mf"));
        r = cli_run("plan", "examples/models/hand_closed.obj", "--scale", "88.7", "--3mf", out, cases[c][0], cases[c][1],
                    cases[c][2], cases[c][3], NULL);
        if (cases[c][4]) {
            CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[c][4]), "%s %s: exit %d: %s", cases[c][0],
                   cases[c][1], r.status, r.err);
            CHECKF(!cli_exists(out), "%s %s: %s written", cases[c][0], cases[c][1], out);
        } else {
            CHECKF(r.status == 0 && cli_exists(out), "%s %s %s %s: exit %d: %s", cases[c][0], cases[c][1], cases[c][2],
                   cases[c][3], r.status, r.err);
        }
        remove(out);
        cli_free(&r);
    }
    {
        cli_result r = cli_run("plan", "--profile", "examples/models/README.md", "--3mf", cli_path("p.3mf"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--3mf needs a MODEL"), "%d %s", r.status, r.err);
        cli_free(&r);
        r = cli_run("slice", "examples/models/hand_closed.obj", "-o", cli_path("j"), "--3mf", cli_path("p.3mf"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--3mf"), "%d %s", r.status, r.err);
        cli_free(&r);
    }
}

/* What is left above a uniform plan's last whole layer was a layer of its
   own (a box 8.0091 mm tall in layers of 0.2: PrusaSlicer laid
   ;HEIGHT:0.00909996): it joins the layer below, or, where the two would pass
   what the nozzle lays (0.3 mm for 0.4), they share their height. Held by
   PrusaSlicer's own G-code: every ;HEIGHT: at least the thinnest allowed,
   none over the nozzle's, and the last ;Z: the box's top. */
static void a_sliver_on_top_is_no_layer_of_its_own(void)
{
    static const char *const cases[][3] = {{"8.0091", "0.2", "joins the layer below"},
                                            {"8.1091", "0.3", "share their"}};
    size_t c;
    for (c = 0; c < sizeof cases / sizeof *cases; c++) {
        char obj[1024], *gcode, *at;
        const char *box = cli_path("sliver_box.obj"), *path3mf = cli_path("sliver.3mf"), *gpath = cli_path("sliver.gcode");
        double top = atof(cases[c][0]), least = HUGE_VAL, most = 0, last_z = 0;
        size_t layers = 0;
        cli_result r;
        snprintf(obj, sizeof obj,
                 "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 %s\nv 10 0 %s\nv 10 10 %s\nv 0 10 %s\n"
                 "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n",
                 cases[c][0], cases[c][0], cases[c][0], cases[c][0]);
        cli_write(box, obj);
        r = cli_run("plan", box, "--uniform", cases[c][1], "--3mf", path3mf, NULL);
        CHECKF(r.status == 0 && strstr(r.err, cases[c][2]), "--uniform %s: exit %d: %s", cases[c][1], r.status, r.err);
        if (!prusa_gcode_after(r, path3mf, gpath, NULL)) continue;
        gcode = read_whole_text(gpath);
        for (at = gcode; at && (at = strstr(at, "\n;HEIGHT:")) != NULL; at += 9) {
            double h = strtod(at + 9, NULL);
            least = h < least ? h : least;
            most = h > most ? h : most;
            layers++;
        }
        for (at = gcode; at && (at = strstr(at, "\n;Z:")) != NULL; at += 4) last_z = strtod(at + 4, NULL);
        CHECKF(layers > 20 && least >= 0.15 - 1e-6 && most <= 0.3 + 1e-6 && fabs(last_z - top) < 1e-3,
               "--uniform %s, %s mm: %zu ;HEIGHT: lines of %g to %g mm, the last ;Z:%g", cases[c][1], cases[c][0], layers,
               least, most, last_z);
        free(gcode);
    }
}

void test_threemf(void)
{
    if (!cli_begin("adaslice-3mf")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("prusa-slicer", prusaslicer_slices_the_bundled_hand_as_planned);
    RUN(bounds_a_nozzle_cannot_lay_are_refused);
    RUN_NEEDING("prusa-slicer", a_sliver_on_top_is_no_layer_of_its_own);
    cli_end();
}
