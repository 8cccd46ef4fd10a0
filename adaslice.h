/* adaslice.h v0.2.0 — adaptive slicing for layer-based additive manufacturing
   (resin SLA/MSLA first). MIT No Attribution or public domain: see the end.

   After Mao, Kwok, Chen and Wang, "Adaptive Slicing Based on Efficient
   Profile Analysis". A mesh is turned into a metric profile phi(z) — the
   error density per mm of height — and a dynamic program picks the fewest
   layers whose integrated error each stays within eps, with every thickness
   in [tmin, tmax]; layer masks for a printer's pixel grid come from the same
   sampling. C99 (and C++), the C library only; adaslice_mcu.h beside it holds
   the integer parts a printer's microcontroller shares with the host.

   DO THIS in exactly one C or C++ file:
       #define ADASLICE_IMPLEMENTATION
       #include "adaslice.h"
   and include it without the define anywhere else.

   EXAMPLE (error handling shortened; see examples/plan_model.c)
       adaslice_mesh mesh;  adaslice_profile profile;  adaslice_plan plan;
       adaslice_error err;
       if (adaslice_mesh_load_file("part.stl", NULL, &mesh, &err) ||
           adaslice_profile_exact(&mesh, NULL, &profile, &err) ||   // cusp, b = 2 um
           adaslice_plan_profile(&profile, NULL, &plan, &err))      // eps 0.065 mm
           fprintf(stderr, "%s\n", err.message);
       for (size_t k = 0; k < plan.layer_count; k++)
           printf("%g %g\n", plan.layers[k].z_bottom, plan.layers[k].thickness);
       adaslice_plan_free(&plan); adaslice_profile_free(&profile); adaslice_mesh_free(&mesh);

   REFERENCE, in the order of the data's path (and of this file); every
   public function, with its signature (make compile-checks holds the list to
   the declarations)
     conventions
       adaslice_result, adaslice_error  what every call that can fail returns and fills
       const char *adaslice_result_name(adaslice_result r);
           a result's name
       adaslice_allocator               how every call allocates (an options field)
     mesh
       adaslice_result adaslice_mesh_load(const void *data, size_t size, const adaslice_load_options *options,
                                          adaslice_mesh *mesh, adaslice_error *error);
           STL, OBJ or PLY from memory
       adaslice_result adaslice_mesh_load_file(const char *path, const adaslice_load_options *options,
                                               adaslice_mesh *mesh, adaslice_error *error);
           the same from a file (not under ADASLICE_NO_STDIO)
       void adaslice_mesh_free(adaslice_mesh *mesh);
       void adaslice_mesh_bounds(const adaslice_mesh *mesh, double lo[3], double hi[3]);
           the box around the vertices triangles use
       adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, const adaslice_weld_options *options,
                                          adaslice_error *error);
           merge equal (or nearby) vertices in place
       adaslice_result adaslice_mesh_repair(adaslice_mesh *mesh, const adaslice_repair_options *options,
                                            adaslice_mesh_report *report, adaslice_error *error);
           weld, drop, wind and turn shells as a slicer does on load
       void adaslice_rotation_to_z(const double d[3], double r[9]);
           the rotation turning a direction up
       void adaslice_mesh_rotate(adaslice_mesh *mesh, const double r[9]);
           turn every vertex
     sampling
       adaslice_grid adaslice_grid_fit(const adaslice_mesh *mesh, adaslice_axis axis, int resolution);
           a square grid of rays covering the mesh
       adaslice_result adaslice_ldi_build(const adaslice_mesh *mesh, const adaslice_grid *grid,
                                          const adaslice_ldi_options *options, adaslice_ldi *ldi,
                                          adaslice_error *error);
           a layered depth image: every ray's surface samples
       void adaslice_ldi_free(adaslice_ldi *ldi);
       size_t adaslice_ldi_ray(const adaslice_ldi *ldi, const adaslice_mesh *mesh, double u, double v,
                               adaslice_crossing *out, size_t max);
           every crossing of the ray through a point
     profiles
       adaslice_result adaslice_profile_exact(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                              adaslice_profile *profile, adaslice_error *error);
           phi(z) from the triangles themselves
       adaslice_result adaslice_profile_sampled(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                                adaslice_profile *profile, adaslice_error *error);
           phi(z) from LDIs along x, y, z (the paper's method)
       void adaslice_profile_free(adaslice_profile *profile);
       adaslice_result adaslice_profile_estimate(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                                 int sampled, adaslice_profile_cost *cost, adaslice_error *error);
           the bytes and samples a profile will take, before it does
       adaslice_result adaslice_mean_curvature(const adaslice_mesh *mesh, double *curvature,
                                               const adaslice_surface_options *options, adaslice_error *error);
           |H| per vertex (the weights' raw material)
       adaslice_result adaslice_saliency(const adaslice_mesh *mesh, float *face_weight,
                                         const adaslice_surface_options *options, adaslice_error *error);
           a weight in [0,1] per triangle (Lee et al. 2005)
       adaslice_result adaslice_view_importance(const adaslice_mesh *mesh, float *importance,
                                                const adaslice_view_options *options, adaslice_error *error);
           the fraction of view directions from which each triangle is seen
       adaslice_result adaslice_curvature_profile(const adaslice_mesh *mesh, const adaslice_profile *profile,
                                                  const adaslice_surface_options *options, double *kappa,
                                                  adaslice_error *error);
           mean |H| of the surface per bin
       adaslice_result adaslice_hybrid_faces(const adaslice_mesh *mesh, const adaslice_hybrid_options *options,
                                             float *residual, float *weights, adaslice_hybrid_report *report,
                                             adaslice_error *error);
           faces an FDM contour pass prints without steps, and the error it leaves them
     plans
       adaslice_result adaslice_plan_profile(const adaslice_profile *profile, const adaslice_plan_options *options,
                                             adaslice_plan *plan, adaslice_error *error);
           the plan: optimal, greedy, uniform or curvature
       void adaslice_plan_free(adaslice_plan *plan);
       double adaslice_layer_error(const adaslice_profile *profile, size_t first, size_t end);
           one layer's error under the profile's metric
       adaslice_result adaslice_plan_units(const adaslice_profile *profile, const adaslice_plan_options *options,
                                           uint32_t *units, unsigned char *forced, adaslice_error *error);
           the integers a printer plans on
       adaslice_dp_*
           the integer planner itself (adaslice_mcu.h)
     orientation
       void adaslice_fibonacci_directions(size_t n, double *xyz);
           n directions spread evenly on the sphere
       adaslice_result adaslice_orienter_init(adaslice_orienter *orienter, const adaslice_mesh *mesh,
                                              const adaslice_profile_options *profile,
                                              const adaslice_plan_options *plan, adaslice_error *error);
           the mesh and options, read-only, shared by threads
       adaslice_result adaslice_profile_along(const adaslice_orienter *orienter, const double d[3],
                                              adaslice_profile *profile, adaslice_error *error);
           the profile with a direction turned up
       adaslice_result adaslice_orienter_score(const adaslice_orienter *orienter, const double d[3],
                                               adaslice_direction_score *score, adaslice_error *error);
           K and the worst layer error along a direction
       void adaslice_orient_scores(adaslice_direction_score *scores, size_t n, double alpha);
           F(O) of eq. 25 over the directions scored
       size_t adaslice_orient_minima(const adaslice_direction_score *scores, size_t n, double radius, size_t *out,
                                     size_t max);
           the directions better than their neighbours
       void adaslice_orienter_free(adaslice_orienter *orienter);
     masks and contours
       adaslice_grid adaslice_grid_plate(const adaslice_mesh *mesh, int width, int height, double pitch_x,
                                         double pitch_y, const double offset[2]);
           a printer's display as a grid of z rays
       adaslice_result adaslice_masker_init(adaslice_masker *masker, const adaslice_mesh *mesh,
                                            const adaslice_grid *grid, const adaslice_mask_options *options,
                                            adaslice_error *error);
           layer masks, made bottom-up in one sweep
       adaslice_result adaslice_masker_slice(adaslice_masker *masker, double height, adaslice_error *error);
           the mask at the next height
       adaslice_result adaslice_masker_layer(adaslice_masker *masker, double z_bottom, double z_top,
                                             adaslice_error *error);
           the mask of the next layer by a rule: a section, envelope (union) or core
       adaslice_result adaslice_masker_bands(const adaslice_masker *whole, const uint32_t *rows, size_t count,
                                             adaslice_masker *bands, adaslice_error *error);
           a masker split into row bands, to be swept on several threads at once
       void adaslice_masker_free(adaslice_masker *masker);
       size_t adaslice_masker_bytes(uint32_t width, uint32_t height, int supersample, adaslice_slice_at slice_at,
                                    size_t triangles);
           what a masker will allocate, before it does
       adaslice_result adaslice_contours_slice(const adaslice_mesh *mesh, const double *heights, size_t count,
                                               const adaslice_contour_options *options, adaslice_contours *contours,
                                               adaslice_error *error);
           cross-section polygons at sorted heights
       int adaslice_contours_winding(const adaslice_contours *contours, size_t height_index, double x, double y);
           winding number of a point at one height
       double adaslice_contours_distance(const adaslice_contours *contours, size_t height_index, double x, double y);
           distance to the nearest edge at one height
       void adaslice_contours_free(adaslice_contours *contours);
     job output
       adaslice_result adaslice_cure_fit(double s1, double t1, double s2, double t2, adaslice_cure *cure,
                                         adaslice_error *error);
           the resin's working curve through two points
       double adaslice_cure_seconds(const adaslice_cure *cure, double thickness);
           a layer's exposure for its thickness
       adaslice_result adaslice_preview(const adaslice_mesh *mesh, int width, int height,
                                        const adaslice_preview_options *options, unsigned char *rgb,
                                        adaslice_error *error);
           a shaded picture of the part for a job's preview
       adaslice_crc32, adaslice_varint_*, adaslice_rle_*
           CRC-32, varints and the mask run-length code (adaslice_mcu.h)

   CONVENTIONS  Every options struct may be NULL or zero-initialised: zero
   means the documented default (the paper's: cusp height, b = 0.002 mm,
   eps = 0.065, tmin = 0.05 mm, tmax = 0.15 mm, sharp-change threshold 0.5).
   Every call that can fail returns an adaslice_result and, if you pass one,
   fills an adaslice_error with a one-line message naming the problem (byte
   offset or line, height, value). Every call that allocates takes an
   adaslice_allocator (alloc, free and a user pointer) from its options; NULL
   means ADASLICE_MALLOC / ADASLICE_FREE. An object that owns memory keeps
   the allocator it was made with and frees through it. There is no global
   state: calls are reentrant, and threads may read one mesh at once.

   PIPELINE AND UNITS
   mesh (mm, build direction +z) -> profile: N = ceil(H/b) bins (H less its
   float rounding), bin i is [z0 + i*b, z0 + (i+1)*b) -> plan: planes
   0 = s0 < ... < sK = N on bin
   boundaries; heights in a plan are mm above the part's bottom z0 -> masks at
   absolute heights on a printer's grid.

   MESH  adaslice_mesh_load reads binary and ASCII STL, OBJ (polygons fan-
   triangulated, negative indices) and PLY (ascii, binary little and big
   endian; faces of any size; triangle strips) from memory. Zero-area
   triangles are kept (every stage skips them; repair collapses or drops
   them), a strip's joins are not triangles; NaN/Inf, bad numbers, truncation,
   indices out of range and overflowing counts are errors with distinct codes.
   `scale` converts units (scans are often in metres). adaslice_mesh_weld
   merges vertices with equal coordinates, or within a tolerance, in place
   (STL gives every triangle its own corners; contours and curvature need
   them shared). adaslice_mesh_repair does what a slicer does on load (weld,
   stitch cracks, drop degenerate facets, wind each shell one way and turn it
   to face out, or in for a cavity) and reports what it found
   (adaslice_mesh_report: shells, open and non-manifold edges, facets turned,
   volume).

   SAMPLING  adaslice_ldi_build rasterises every triangle scan line by scan
   line at the pixel centres of a grid of rays along x, y or z. Vertices snap
   to 1/256 pixel and inside tests are exact integer edge functions with a
   top-left rule, so a ray through a shared edge or vertex meets exactly one
   of the triangles there (watertight). Each sample keeps its depth, triangle
   and whether the ray enters or leaves the solid: 8 bytes (float depth,
   uint32 triangle | leave bit); samples per pixel are sorted by depth; 8 more
   bytes per pixel index them. The same rasteriser feeds the sampled profiles
   and the masks. No threads.

   PROFILES (exact: from the triangles, no sampling)
     cusp       eq. 4-6    phi = max |n_z| * w over triangles meeting the bin;
                           eps in mm
     roughness  eq. 8-10   phi = max w / sin(theta), theta the angle between
                           normal and z, clamped at roughness_max (default
                           1/sin 5 deg = 11.47): flat faces print without steps,
                           and the formula is infinite there; eps in mm
     area       eq. 12-14  phi = |A(i+1) - A(i)| / (b A(i)) * wmax, A at bin
                           centres; one-sided at the top bin; if A(i) = 0 the
                           neighbour's area is the reference; dimensionless eps.
                           Tips (A -> 0) make phi large: that is the metric.
     volume     eq. 17-20  phi = A * wmax (mm^2); a layer's error is
                           b * sum |phi[j] - phi[first]| in mm^3
   A(z) is exact: each triangle's cut is a segment whose endpoints move
   linearly with z, so its Green's-theorem term is quadratic in z; the terms
   are summed per block of 256 bins about the block's first centre. Area and
   volume assume a closed mesh: overlapping shells count twice, open or
   inconsistently wound meshes give signed sums (negative areas read as 0).
   w is an optional per-triangle weight in [0,1] (eq. 21-24); wmax the
   largest weight among triangles meeting the bin.

   SAMPLED PROFILES  adaslice_profile_sampled is the paper's method (§3.2):
   LDIs along x, y and z with `resolution` pixels (default 2048) across the
   largest extent. Each sample puts its triangle's value in the bin of its
   height (cusp, roughness, the max weight); areas (eq. 13) count the z rays
   whose winding number is positive at each bin centre. The z LDI for areas is
   built in bands of rows within memory_limit (default 512 MiB) with identical
   results; cusp and roughness need no stored LDI at all. A bin no sample
   reaches (thinner than the x and y rays' spacing, with no surface facing z)
   takes the larger value of its nearest reached neighbours, never a silent
   zero, and is counted in profile.unsampled_bins.

   WEIGHTS AND CURVATURE  §4.2 slices salient faces thinner through the
   profiles' per-triangle weights. adaslice_saliency makes them after Lee,
   Varshney and Jacobs, "Mesh saliency" (2005): |H| per vertex from the
   cotangent Laplacian over Meyer's mixed area (adaslice_mean_curvature), its
   Gaussian-weighted means G(s) at s = 2..6 eps and 2s (eps 0.3% of the box
   diagonal), the centre-surround maps |G(s) - G(2s)| normalised after Itti
   and summed; a triangle weighs the mean of its corners, the heaviest 1.
   Neighbourhoods come from grids with vertices pooled in cells s/3 wide:
   time linear in the triangles. Multiply in weights of your
   own (the tool reads a file and regions). All three read the surface with
   vertices within weld_tolerance merged, on a copy. adaslice_curvature_profile
   gives k(z), the area-weighted mean |H| of the surface in each bin, for the
   curvature planner.

   HYBRID (FDM)  A contour pass (adaslice contour) moves Z along the top
   surface paths of planar layers to follow the mesh, so the faces it prints
   leave no stair step; adaslice_hybrid_faces says which, and what they keep:
   a face is contoured when it faces up no steeper than max_angle (15 deg),
   it is reachable and its residual costs less than its cusp. Reachable: no
   z ray meets it under another surface, and the mesh nowhere rises above the
   cone over it whose flanks climb at max_angle out to `reach` mm (the
   nozzle's; its own surface, no steeper, never does); z rays `pitch` apart
   test it (reach / 8 apart), and a face no ray meets is judged at the ray
   nearest its centroid: clear if that ray's top is a clear candidate near
   the face's plane. Residual (mm): max(0, tmax/2 - rise), as planar layers sliced at
   their middle leave the surface within half a layer of their top, plus
   resolution * D / 4, the chord error of a path sampled every `resolution`
   mm across a crease whose gradient changes by D (the largest change to a
   contoured face sharing a corner; exact for faces wider than a segment).
   The cusp profile charges a contoured face residual / tmin per mm instead
   of |n_z|, which bounds it in any layer from tmin up (a face where that is
   not less than |n_z| is left planar).

   PLANS
     optimal   Procedure 1 in O(N) for additive metrics: the feasible
               predecessors of a plane form a window whose ends only move
               up, kept in a monotone queue; O(N w) for volume deviation.
               Among plans with the fewest layers it returns one whose worst
               layer error is smallest: the DP orders states by (layers,
               worst) lexicographically, which is exact because any prefix
               of an optimal plan is itself optimal in that order; within
               the queue's front block the best max(worst, layer error) is
               where the two cross, tracked by a forward-only pointer.
               The DP runs on integers: b*phi is quantised up to units of a
               power of two near 2^-40 of the largest layer error, so a
               plan feasible in units is feasible in mm (volume adds one unit
               per bin unless every value was exact). The §3.3 pre-pass
               forces a plane where |phi[i] - phi[i-1]| > sharp, unless that
               would leave a stretch no layers can fill. It never makes a
               feasible eps infeasible: bottom-up, a plane is kept where some
               plan through it and the planes kept below stays within eps and
               has at most one layer more per plane kept than the plan
               without the pre-pass; else it moves to the nearest plane
               (within tmax) that does, else it is dropped; plan.changes
               lists those, and why. (Budget mode keeps the planes as they
               are.)
               budget > 0: the smallest eps whose plan has at most that many
               layers (bisection over eps in units).
     greedy    ref. [3], local: each layer as thick as the profile at its
               bottom plane allows (eps / (b phi) bins, clamped to tmin..tmax);
               its real error is only known afterwards, and layers over eps are
               counted in over_eps (the paper's greedy that gets "stuck").
     finest, coarsest   uniform tmin or tmax; the top layer holds the rest.
     curvature the curvature-based planner of the slicing notes (after
               "Adaptive slicing for FDM revisited"): each layer is
               t = tmin + (tmax - tmin) f(k / kmax) at its first bin, k from
               options.curvature (adaslice_curvature_profile), f linear,
               exponential or a step; kmax the 95th percentile of k unless
               given. Its layer errors are measured on the metric profile, so
               it compares with the other plans; over_eps counts those above
               eps.
   Greedy and curvature lay layers bottom-up, each rounded to whole bins
   within tmin..tmax and never leaving a rest that layers cannot fill.
   Infeasible: ADASLICE_ERR_INFEASIBLE with error.z (the lowest height no
   plan gets past) and error.min_eps (the smallest eps that works, 0 if the
   thickness range cannot tile the height at all).

   ORIENTATION  adaslice_orienter_score plans the part along a direction d
   (§4.3): the profile is exactly adaslice_profile_exact of the mesh turned by
   adaslice_mesh_rotate(adaslice_rotation_to_z(d)), so planning the turned part
   later gives the same K. adaslice_fibonacci_directions spreads n directions
   evenly; adaslice_orient_scores computes F = alpha K / max K + (1 - alpha)
   eps / max eps with eps the plan's worst layer error (the paper's
   "geometric error", §5.2; a mean error would drop as near-zero-error layers
   are added); adaslice_orient_minima finds directions lower than all their
   neighbours. An orienter is read-only: threads may score directions at once.

   MASKS  adaslice_masker_init / adaslice_masker_slice make layer masks on a
   printer's pixel grid bottom-up in one sweep: each slice applies the z-ray
   samples between the previous height and this one, so every sample is
   rasterised once per print. A pixel is lit when its ray's winding number
   below the height is positive (overlapping shells stay lit); where an open or
   badly wound mesh leaves a ray unbalanced it must be positive counted from
   above too, so no column is ever lit above the part. supersample s > 1 gives
   8-bit masks of s*s + 1 levels: at a height, each pixel's covered fraction
   of the section measured exactly (signed area and cover per edge pixel, as
   font rasterisers do), over a layer's range (envelope, core) s x s rays per
   pixel. Memory: 2 bytes per ray; 4 per pixel for an anti-aliased section.
   adaslice_masker_layer takes a layer's range and the options' slice_at:
   the section at its middle (default; dimensionally right on average, but a
   layer t thick drops a feature thinner than t/2 and undersizes a face
   sloping away below by up to t/2), at its first or last bin, or over the
   whole range, read from each ray's crossings in one pass: ENVELOPE lights a
   ray inside anywhere in the range (the union of the layer's sections, as a
   merged layer of thin slices: no detail is lost; a wall at theta to the
   plate is oversized by up to t cot(theta)), CORE one inside all through it
   (the intersection: never oversized, undersized as much). A tip thinner than a layer survives in
   the envelope. Both cost a bit per ray, the layer's rasterised spans
   (as many as its rasterising makes) and one ray row's crossings sorted;
   no pass over the grid.

   CONTOURS  adaslice_contours_slice cuts the mesh at sorted heights (absolute z,
   mm) in one sweep after Minetto et al., "An optimal algorithm for 3D triangle
   mesh slicing": triangles are bucketed by the first height at or above their
   lowest z, the sweep keeps the triangles spanning the current height, and each
   cut is chained to the next through the mesh edge it ends on, so polygons close
   exactly whatever the rounding: O(n log k + k + m) for n triangles, k heights
   and m cuts. A vertex exactly at a height counts as below it: the contour is
   the limit from just above (a box cut at its bottom face gives its full
   section, at its top face nothing), and faces lying in the plane add nothing.
   Loops turn counter-clockwise seen from +z around material and clockwise around
   holes (from the triangles' winding), so their signed areas add up to the
   section's area. Open meshes and inconsistent winding give open polylines.
   Chaining needs shared vertices: weld an STL first. Polylines are joined
   end to start by the chords the masks close gaps with (`next`);
   adaslice_contours_winding is the exact winding number of a point about
   the loops and the polylines so closed.

   JOB OUTPUT  A layer of thickness t needs the dose that cures t: Jacobs'
   working curve, cure depth Cd = Dp ln(E / Ec), gives E(t) = S exp((t - T) /
   Dp) from one calibrated point (S seconds cure T mm) and the resin's
   penetration depth Dp, or Dp from two points (adaslice_cure_fit).
   adaslice_preview draws the part for a job's previews from an LDI along the
   view, no graphics library. What travels to a printer's MCU lives in
   adaslice_mcu.h, which the printer compiles too: CRC-32, varints and the
   mask run-length code.

   OPTIONS (define before including the implementation)
     ADASLICE_IMPLEMENTATION  the implementation, in one file (adaslice_mcu.h's
                              comes with it)
     ADASLICE_STATIC          every function static (private to the file)
     ADASLICE_DEF             the linkage of public functions (overrides the above)
     ADASLICE_MALLOC(size), ADASLICE_FREE(ptr)
                              the default allocator (malloc/free); or pass an
                              adaslice_allocator {alloc, free, user} in the options
     ADASLICE_NO_MALLOC       no default allocator: every call needs one
     ADASLICE_ASSERT(x)       internal invariant checks (assert by default)
     ADASLICE_NO_STDIO        leaves out adaslice_mesh_load_file, the only
                              stdio user
   Feature switches, each leaving out a part (and its declarations):
     ADASLICE_NO_LOADERS      the STL, OBJ and PLY readers (a mesh you fill
                              yourself is planned as any other)
     ADASLICE_NO_SAMPLED      adaslice_profile_sampled (the exact profiles stay)
     ADASLICE_NO_WEIGHTS      mean curvature, saliency, the curvature profile
     ADASLICE_NO_ORIENT       the build-direction search
     ADASLICE_NO_CONTOURS     the slice contours
     ADASLICE_NO_HYBRID       the hybrid planar / contoured face classification
   LIMITS  N < 2^31 bins; tmax/b <= 65535 bins per layer; 2^32 - 1 vertices;
   grids of at most 2^21 pixels a side. adaslice_mesh_load_file finds a
   file's size with ftell: 2 GiB at most where a long has 32 bits.
   FLOATING POINT  What this file promises bit for bit (a direction's profile
   equal to the turned mesh's, a plan's heights its planes times the bin)
   needs each double rounded to 64 bits as it is made (FLT_EVAL_METHOD 0):
   64-bit targets and 32-bit ARM do; on 32-bit x86 build with -msse2
   -mfpmath=sse, as x87 arithmetic keeps 80 bits between steps.

   HISTORY
     0.2.0  2026-12-05  adaslice_dp_bins and adaslice_dp_reach, so that the
                        host plans through the integer planner's public calls
                        only; the REFERENCE gives every signature
     0.1.0  2026-11-22  loaders, repair, LDI, the four metrics' profiles, the
                        optimal planner and its baselines, orientation,
                        saliency, masks, contours, cure and previews; the
                        integer planner and mask code in adaslice_mcu.h
*/
#ifndef ADASLICE_H
#define ADASLICE_H

#include "adaslice_mcu.h" /* results, the integer planner, CRC-32, the mask code */

#ifdef __cplusplus
extern "C" {
#endif

#define ADASLICE_VERSION "0.2.0"

/* ============================================================ conventions */

/* Filled by every call that can fail; pass NULL if you only want the code. */
typedef struct adaslice_error {
    adaslice_result result;
    size_t offset;      /* byte offset in the input the problem is at (loaders) */
    size_t line;        /* 1-based line for text formats, 0 for binary */
    double z;           /* ADASLICE_ERR_INFEASIBLE: first height (mm above the part's
                           bottom) that no plan can cover */
    double min_eps;     /* ADASLICE_ERR_INFEASIBLE: smallest eps that is feasible with the
                           same tmin/tmax, or 0 if no eps is (the thickness range itself
                           cannot tile the height) */
    char message[320];  /* one line, no trailing newline */
} adaslice_error;

ADASLICE_DEF const char *adaslice_result_name(adaslice_result r);

/* Every allocation goes through this. `user` is passed back untouched. A NULL
   allocator pointer means ADASLICE_MALLOC / ADASLICE_FREE (malloc/free unless
   overridden; under ADASLICE_NO_MALLOC there is no default and NULL fails). */
typedef struct adaslice_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} adaslice_allocator;

/* =================================================================== mesh */

typedef enum adaslice_format {
    ADASLICE_FORMAT_AUTO = 0, /* detect from the content */
    ADASLICE_FORMAT_STL_BINARY,
    ADASLICE_FORMAT_STL_ASCII,
    ADASLICE_FORMAT_OBJ,
    ADASLICE_FORMAT_PLY
} adaslice_format;

typedef struct adaslice_load_options {
    adaslice_format format;              /* 0: detect */
    double scale;                        /* 0: 1; every coordinate is multiplied by it
                                            (scans are often in metres: 1000) */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_load_options;

/* An indexed triangle mesh in millimetres, build direction +z. A mesh you fill
   yourself (pointers to your own arrays, allocator zeroed) needs no free. */
typedef struct adaslice_mesh {
    size_t vertex_count;
    float *vertices;            /* x, y, z per vertex */
    size_t triangle_count;
    uint32_t *triangles;        /* three vertex indices per triangle */
    adaslice_format format;     /* what the loader read */
    adaslice_allocator allocator;
} adaslice_mesh;

#ifndef ADASLICE_NO_LOADERS
ADASLICE_DEF adaslice_result adaslice_mesh_load(const void *data, size_t size,
                                                const adaslice_load_options *options,
                                                adaslice_mesh *mesh, adaslice_error *error);
#ifndef ADASLICE_NO_STDIO
/* Reads a whole file and loads it; errors name the path. */
ADASLICE_DEF adaslice_result adaslice_mesh_load_file(const char *path,
                                                     const adaslice_load_options *options,
                                                     adaslice_mesh *mesh, adaslice_error *error);
#endif
#endif
ADASLICE_DEF void adaslice_mesh_free(adaslice_mesh *mesh);
/* Lowest and highest corner of the box around the vertices that triangles
   use (a zero as +0). Allocates nothing. */
ADASLICE_DEF void adaslice_mesh_bounds(const adaslice_mesh *mesh, double lo[3], double hi[3]);

typedef struct adaslice_weld_options {
    double tolerance;                    /* mm; 0: equal coordinates only */
    const adaslice_allocator *allocator; /* NULL: default (a temporary table) */
} adaslice_weld_options;

/* Merges vertices, in place: in vertex order, each vertex merges into the
   first kept vertex (lowest index) within `tolerance` mm, found through a hash
   grid of cells `tolerance` wide, or is kept itself. Tolerance 0 merges
   coordinates equal bit for bit (+0 and -0 count as equal), in expected O(n).
   Merging is not transitive: a vertex near a merged one but farther than
   `tolerance` from its representative stays. The kept vertices keep the order
   of their first occurrence, vertex_count shrinks and triangle indices are
   rewritten; nothing is reallocated, so a mesh pointing at your own arrays
   stays yours. Triangles keep their count and order (per-triangle data stays
   aligned); one whose corners merge keeps the repeated index and zero area,
   which every stage skips. */
ADASLICE_DEF adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, const adaslice_weld_options *options,
                                                adaslice_error *error);

typedef struct adaslice_repair_options {
    double tolerance;                    /* mm: vertices on open edges this close are one;
                                            0: 1e-4 of the box's diagonal */
    const adaslice_allocator *allocator; /* NULL: default (temporary tables) */
} adaslice_repair_options;

/* What adaslice_mesh_repair found and did. A shell is a set of facets
   connected through edges that exactly two facets share. */
typedef struct adaslice_mesh_report {
    size_t shells;
    size_t closed_shells;        /* shells with no open edge */
    size_t open_edges;           /* edges of one facet (holes, cracks), after repair */
    size_t nonmanifold_edges;    /* edges of three or more facets */
    size_t inconsistent_edges;   /* edges whose two facets still run the same way
                                    (a one-sided surface cannot be wound) */
    size_t welded_nearby;        /* open-edge vertices merged within the tolerance */
    size_t degenerate_dropped;   /* facets of zero area after welding, dropped */
    size_t slivers_collapsed;    /* facets of zero area sealing a T-junction (three
                                    points on a line), collapsed onto their long edge:
                                    the facet across it split at the middle point */
    size_t flipped_facets;       /* facets turned, to agree with their shell or to face out */
    size_t flipped_shells;       /* shells turned whole to face the way their nesting says */
    double volume;               /* mm^3 enclosed, after repair (open shells: about
                                    their centroid) */
    size_t edge_steps;           /* half-edges met walking the edges: the repair's work,
                                    at most 9 per facet however many share an edge */
} adaslice_mesh_report;

/* Repairs a mesh in place as a slicer does on load: welds equal vertices;
   collapses each zero-area facet whose corners lie on a line (a CAD export's
   seal of a T-junction, where one facet's edge meets two of the other side's)
   onto its long edge, splitting the one facet across that edge at the middle
   corner in its place, so the junction stays closed; then welds vertices on
   open edges within `tolerance` (cracks between patches); drops facets left
   with zero area; winds every shell consistently by flood
   fill (keeping the winding of most of its facets); then turns each shell
   whole so that it faces the way its nesting says: a shell inside an even
   number of closed shells (none: the outside of a part) encloses positive
   volume, one inside an odd number (a cavity) negative, so a hollow part
   stays hollow. Nesting comes from z rays from a few points of the shell
   against the other closed shells; a shell whose points disagree about
   another (they intersect) does not count that one. Vertices no facet uses
   are dropped; the order of the rest and of the facets is kept. Nothing is
   reallocated. report (may be NULL) says what was found. A mesh that was
   closed and wound one way keeps its facets, their corners and their order. */
ADASLICE_DEF adaslice_result adaslice_mesh_repair(adaslice_mesh *mesh, const adaslice_repair_options *options,
                                                  adaslice_mesh_report *report, adaslice_error *error);
/* The rotation (row-major 3x3) turning unit direction d onto +z by the
   smallest angle; its last row is d. */
ADASLICE_DEF void adaslice_rotation_to_z(const double d[3], double r[9]);
/* Turns every vertex by r (row-major). */
ADASLICE_DEF void adaslice_mesh_rotate(adaslice_mesh *mesh, const double r[9]);

/* =============================================================== sampling */

/* A grid of parallel rays along +x, +y or +z. Pixel (i, j) has its centre at
   (origin[0] + (i + 0.5) pitch[0], origin[1] + (j + 0.5) pitch[1]) in the
   plane's coordinates (u, v): (y, z) for rays along x, (z, x) along y, (x, y)
   along z (a cyclic order, so u x v = the ray direction). Pixels need not be
   square: many printers' panels are not (19 x 24 um). */
typedef enum adaslice_axis { ADASLICE_AXIS_X = 0, ADASLICE_AXIS_Y, ADASLICE_AXIS_Z } adaslice_axis;

typedef struct adaslice_grid {
    adaslice_axis axis;
    double origin[2];   /* mm */
    double pitch[2];    /* mm per pixel along u and along v */
    int width, height;  /* pixels, at most 2^21 each */
} adaslice_grid;

/* Where a ray meets the surface. 8 bytes: depth along the ray relative to the
   LDI's depth_origin (float: 2^-24 of the part's extent), and the triangle
   index with the top bit set when the ray leaves the solid there. */
typedef struct adaslice_sample {
    float depth;
    uint32_t face;
} adaslice_sample;

#define ADASLICE_SAMPLE_LEAVES 0x80000000u
#define ADASLICE_SAMPLE_FACE(s) ((s).face & 0x7fffffffu)

/* Samples of pixel p are samples[first[p] .. first[p+1]), sorted by depth;
   p = j * width + i. */
typedef struct adaslice_ldi {
    adaslice_grid grid;
    double depth_origin;       /* mm along the ray where depth 0 lies */
    size_t *first;             /* width * height + 1 */
    adaslice_sample *samples;
    size_t sample_count;
    adaslice_allocator allocator;
} adaslice_ldi;

typedef struct adaslice_ldi_options {
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_ldi_options;

/* The square grid along `axis` with `resolution` pixels across the mesh's
   largest extent (the paper's LDI resolution), covering the mesh. */
ADASLICE_DEF adaslice_grid adaslice_grid_fit(const adaslice_mesh *mesh, adaslice_axis axis, int resolution);
/* Rasterises every triangle scan line by scan line at pixel centres. Vertices
   are snapped to 1/256 pixel and edges tested exactly with a top-left rule,
   so a ray through a shared edge or vertex meets exactly one of the triangles
   there (or, on a silhouette, an entering and a leaving one together). */
ADASLICE_DEF adaslice_result adaslice_ldi_build(const adaslice_mesh *mesh, const adaslice_grid *grid,
                                                const adaslice_ldi_options *options, adaslice_ldi *ldi,
                                                adaslice_error *error);
ADASLICE_DEF void adaslice_ldi_free(adaslice_ldi *ldi);

/* Where the ray through a point meets the surface: depth in mm along the
   LDI's axis in the mesh's own coordinates (z for a z LDI), the triangle,
   and whether the ray leaves the solid there (looking up +z: a surface
   turned upwards, a top). */
typedef struct adaslice_crossing {
    double depth;
    uint32_t face;
    int leaves;
} adaslice_crossing;

/* Every surface crossing along the ray through (u, v) of the LDI's plane
   ((x, y) for a z LDI), in order along the ray, for rays between the LDI's
   pixel centres: the nearest pixel's samples, each put on its own
   triangle's plane at (u, v), so a crossing is exact where (u, v) lies on
   that triangle and, off it (less than half a pixel away), off by the
   plane's tilt times that distance. mesh is the one the LDI was built from
   (NULL: the pixel's depths as stored, to float precision). Fills up to max
   crossings and returns how many the ray has (0 outside the grid). */
ADASLICE_DEF size_t adaslice_ldi_ray(const adaslice_ldi *ldi, const adaslice_mesh *mesh, double u, double v,
                                     adaslice_crossing *out, size_t max);
/* n directions of a spherical Fibonacci lattice, x y z each, near-uniform on
   the sphere, from near +z down to near -z: the first n/2 are the upper
   hemisphere's. */
ADASLICE_DEF void adaslice_fibonacci_directions(size_t n, double *xyz);

/* =============================================================== profiles */

typedef enum adaslice_metric {
    ADASLICE_METRIC_CUSP = 0,  /* eq. 4-6: max |n_z|, per mm; eps in mm */
    ADASLICE_METRIC_ROUGHNESS, /* eq. 8-10: max 1/sin(theta), clamped; eps in mm */
    ADASLICE_METRIC_AREA,      /* eq. 12-14: |A'(z)| / A(z), per mm; eps dimensionless */
    ADASLICE_METRIC_VOLUME     /* eq. 17-20: A(z) in mm^2; eps in mm^3 (not additive) */
} adaslice_metric;

#define ADASLICE_DEFAULT_BIN 0.002
/* 1/sin(5 degrees): surfaces flatter than 5 degrees count as 5 degrees, since
   1/sin(theta) is infinite on horizontal faces (which print without steps). */
#define ADASLICE_DEFAULT_ROUGHNESS_MAX 11.473713245669855
#define ADASLICE_DEFAULT_RESOLUTION 2048
#define ADASLICE_DEFAULT_MEMORY_LIMIT ((size_t)512 << 20)

typedef struct adaslice_profile_options {
    adaslice_metric metric;
    double bin;                          /* b in mm; 0: ADASLICE_DEFAULT_BIN */
    double roughness_max;                /* 0: ADASLICE_DEFAULT_ROUGHNESS_MAX */
    const float *weights;                /* NULL, or one weight in [0,1] per triangle
                                            (eq. 21-24) */
    int resolution;                      /* sampled only: LDI pixels across the mesh's
                                            largest extent; 0: ADASLICE_DEFAULT_RESOLUTION */
    size_t memory_limit;                 /* sampled only: bytes of LDI held at once (it is
                                            built in bands of rows); 0: the default */
    const adaslice_allocator *allocator; /* NULL: default */
    void (*progress)(void *user, double done); /* NULL, or told the share done (0 to 1)
                                            now and then, and 1 at the end */
    void *progress_user;
} adaslice_profile_options;

/* phi[i] belongs to bin i = [z0 + i*bin, z0 + (i+1)*bin). A profile you fill
   yourself (your own phi, allocator zeroed) can be planned and needs no free. */
typedef struct adaslice_profile {
    adaslice_metric metric;
    size_t bin_count;   /* N = ceil(height / bin) */
    double bin;         /* b, mm */
    double z0;          /* lowest z of the mesh, mm */
    double height;      /* H, mm */
    double *phi;        /* N values, all finite and >= 0 */
    double *area;       /* area and volume metrics: A at each bin's centre (mm^2); else NULL */
    size_t unsampled_bins; /* sampled profiles: bins no ray sample fell in (see the manual) */
    adaslice_allocator allocator;
} adaslice_profile;

/* The exact profile, computed from the triangles themselves (no sampling). */
ADASLICE_DEF adaslice_result adaslice_profile_exact(const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *options,
                                                    adaslice_profile *profile,
                                                    adaslice_error *error);
#ifndef ADASLICE_NO_SAMPLED
/* The paper's sampled profile (§3.2, eq. 5, 9, 13-14, 19-20): LDIs along x, y
   and z at `resolution` pixels across the largest extent; each sample adds its
   triangle's value to the bin of its height; areas count the z rays inside at
   each bin centre. */
ADASLICE_DEF adaslice_result adaslice_profile_sampled(const adaslice_mesh *mesh,
                                                      const adaslice_profile_options *options,
                                                      adaslice_profile *profile, adaslice_error *error);
#endif
ADASLICE_DEF void adaslice_profile_free(adaslice_profile *profile);
/* What a profile will take, before it is made (exact, or sampled when
   `sampled`): the most bytes it holds at once, and for the sampled profile
   its work, the samples its rays take (each a pixel a triangle covers; rays
   along x one per span), both estimated from above. For a caller's limits. */
typedef struct adaslice_profile_cost {
    double bytes;
    double samples;
} adaslice_profile_cost;
ADASLICE_DEF adaslice_result adaslice_profile_estimate(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                                       int sampled, adaslice_profile_cost *cost, adaslice_error *error);

#ifndef ADASLICE_NO_HYBRID
/* Hybrid planar / contoured slicing for FDM: which faces a contour pass (Z
   moved along the surface paths to follow the mesh) will print without stair
   steps, and what error it leaves them, so that the cusp profile can charge
   them that instead of their cusp. See HYBRID in the manual. */
#define ADASLICE_DEFAULT_MAX_ANGLE 15.0        /* degrees from horizontal */
#define ADASLICE_DEFAULT_REACH 2.0             /* mm */
#define ADASLICE_DEFAULT_PATH_RESOLUTION 0.2   /* mm */

typedef struct adaslice_hybrid_options {
    double max_angle;    /* the steepest face contoured, degrees from horizontal,
                            in (0, 45]; 0: ADASLICE_DEFAULT_MAX_ANGLE */
    double reach;        /* mm: radius of the nozzle cone that must be clear;
                            0: ADASLICE_DEFAULT_REACH */
    double resolution;   /* mm: the contour's longest path segment;
                            0: ADASLICE_DEFAULT_PATH_RESOLUTION */
    double rise;         /* mm: the farthest the contour moves Z off a layer's
                            plane; 0: tmax / 2 */
    double tmin, tmax;   /* mm: the plan's layer bounds; 0: the defaults */
    double pitch;        /* mm between the z rays of the reach test; 0: reach / 8,
                            or coarser to keep 2048 rays across */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_hybrid_options;

typedef struct adaslice_hybrid_report {
    size_t candidates;   /* faces facing up, no steeper than max_angle */
    size_t contoured;    /* ... of them reachable and worth it */
    size_t blocked;      /* candidates with part of the mesh in the nozzle's cone */
    size_t costly;       /* candidates whose residual costs more than their cusp */
    double area;         /* mm^2 contoured */
    double z_low, z_high;/* absolute z (mm) the contoured faces span; 0, 0 if none */
    double residual;     /* mm: the largest residual bound of a contoured face */
    double clamp;        /* mm: the part of every residual the rise leaves,
                            max(0, tmax / 2 - rise) */
} adaslice_hybrid_report;

/* Classifies every face: residual[t] is -1 for a face printed planar, else
   the bound (mm) on the vertical distance between the contoured path and the
   mesh over face t. weights (NULL, or one per face, e.g. saliency, all 1 if
   you have none) are multiplied, for contoured faces, by
   residual / (tmin |n_z|), so adaslice_profile_exact or _sampled with them
   gives the hybrid cusp profile. report may be NULL. */
ADASLICE_DEF adaslice_result adaslice_hybrid_faces(const adaslice_mesh *mesh, const adaslice_hybrid_options *options,
                                                   float *residual, float *weights, adaslice_hybrid_report *report,
                                                   adaslice_error *error);
#endif

#ifndef ADASLICE_NO_WEIGHTS
/* How the weights read a surface: vertices within weld_tolerance are one
   vertex (welded on a copy; the caller's mesh is not touched). */
typedef struct adaslice_surface_options {
    double weld_tolerance;               /* mm, as adaslice_mesh_weld; 0: equal
                                            coordinates only */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_surface_options;

/* |H| per vertex of `mesh` (vertex_count values), 1/mm: half the length of the
   cotangent Laplacian of the position over the mixed Voronoi area (Meyer,
   Desbrun, Schroeder and Barr 2003), so a sphere of radius R gives 1/R and a
   plane 0; merged vertices share their value. Zero-area triangles are
   skipped. A vertex on an edge that has not exactly two triangles (a border,
   a non-manifold edge) has an incomplete fan, so it takes the mean |H| of its
   regular neighbours (0 if it has none); a vertex in no triangle with area
   gets 0. */
ADASLICE_DEF adaslice_result adaslice_mean_curvature(const adaslice_mesh *mesh, double *curvature,
                                                     const adaslice_surface_options *options, adaslice_error *error);

/* Mesh saliency (Lee, Varshney and Jacobs 2005) as one weight in [0,1] per
   triangle, for adaslice_profile_options.weights. |H| per vertex as above,
   each capped at its largest neighbour's: a lone vertex cannot show a
   feature, and lone spikes (slivers, the tents decimation leaves) would
   otherwise set the scale of every map. With eps = 0.3% of the bounding box's
   diagonal, G(s) at a vertex v is the mean |H| of the vertices within 2s of v
   weighted by exp(-d^2 / (2 s^2)); for s = 2, 3, 4, 5, 6 eps the map
   |G(s) - G(2s)| is divided by its maximum and multiplied by (1 - m)^2, m the
   mean of its other local maxima (a vertex is one when no vertex within s has
   a larger value); the five maps are summed. A triangle's weight is the mean
   of its corners', divided by the largest; all 1 when nothing varies.
   Neighbourhoods come from grids, never all pairs: vertices are pooled into
   cells s/3 wide, each acting as its vertex count at its centroid with its
   mean |H| (the Gaussian's first-order error cancels about a centroid), and
   the cells within 2s come from a grid of cells s wide. Time and memory
   linear in the triangles. */
ADASLICE_DEF adaslice_result adaslice_saliency(const adaslice_mesh *mesh, float *face_weight,
                                               const adaslice_surface_options *options, adaslice_error *error);

#define ADASLICE_DEFAULT_VIEWS 32
#define ADASLICE_DEFAULT_VIEW_RESOLUTION 512

typedef struct adaslice_view_options {
    const double *directions;            /* count directions towards the viewer, x y z each
                                            (any length); NULL: the upper hemisphere, the
                                            first `count` of 2 count Fibonacci directions */
    size_t count;                        /* 0: ADASLICE_DEFAULT_VIEWS */
    int resolution;                      /* LDI pixels across the part per view (1 to 8192);
                                            0: ADASLICE_DEFAULT_VIEW_RESOLUTION */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_view_options;

/* Viewpoint importance (the "viewpoint" term of saliency-preserving slicing,
   after Wang et al. 2015) as one value in [0,1] per triangle: the fraction of
   the view directions from which it is seen. Along each direction the mesh is
   turned to look down +z and rasterised by the LDI's rasteriser into a
   z-buffer (each pixel keeps its ray's sample nearest the viewer, the last of
   its LDI ray): the face it names counts as seen if it is turned towards the
   viewer, so a face behind another, inside a cavity or facing away is unseen.
   A face that covers no pixel centre of a view (small, or seen very
   obliquely) is missed in that view. Time: one raster of the part per view;
   memory: 8 bytes a pixel of a view. */
ADASLICE_DEF adaslice_result adaslice_view_importance(const adaslice_mesh *mesh, float *importance,
                                                      const adaslice_view_options *options, adaslice_error *error);

/* k per bin of `profile` (its z0, bin and bin_count; the mesh it was made
   from), for ADASLICE_METHOD_CURVATURE: the area-weighted mean |H| of the
   surface in the bin, each triangle's |H| being its corners' mean and its
   area spread evenly over the bins it meets. A mean over the surface rather
   than over vertices: vertices rarely fall inside a 2 um bin, while every bin
   the part occupies meets triangles, and area weights keep it independent of
   the tessellation. Bins no triangle meets get 0. */
ADASLICE_DEF adaslice_result adaslice_curvature_profile(const adaslice_mesh *mesh, const adaslice_profile *profile,
                                                        const adaslice_surface_options *options, double *kappa,
                                                        adaslice_error *error);
#endif

/* ================================================================== plans */

typedef enum adaslice_method {
    ADASLICE_METHOD_OPTIMAL = 0, /* Procedure 1: fewest layers, then smallest worst error */
    ADASLICE_METHOD_GREEDY,      /* ref. [3]: thickest layer the local profile allows */
    ADASLICE_METHOD_FINEST,      /* uniform tmin */
    ADASLICE_METHOD_COARSEST,    /* uniform tmax */
    ADASLICE_METHOD_CURVATURE    /* thickness from mean curvature (options.curvature) */
} adaslice_method;

/* How ADASLICE_METHOD_CURVATURE maps x = k / kmax to the share f of tmax - tmin. */
typedef enum adaslice_mapping {
    ADASLICE_MAPPING_LINEAR = 0, /* f = 1 - min(x, 1) */
    ADASLICE_MAPPING_EXP,        /* f = exp(-alpha x) */
    ADASLICE_MAPPING_STEP        /* f = 1, 2/3, 1/3, 0 for x below 1/4, 1/2, 3/4, and above */
} adaslice_mapping;

#define ADASLICE_DEFAULT_EPS 0.065
#define ADASLICE_DEFAULT_TMIN 0.05
#define ADASLICE_DEFAULT_TMAX 0.15
#define ADASLICE_DEFAULT_SHARP 0.5
#define ADASLICE_SHARP_OFF (-1.0)
#define ADASLICE_DEFAULT_ALPHA 2.0
#define ADASLICE_DEFAULT_KAPPA_PERCENTILE 0.95

typedef struct adaslice_plan_options {
    adaslice_method method;
    double eps;         /* allowed error per layer; 0: ADASLICE_DEFAULT_EPS. Greedy and
                           curvature only count the layers over it (over_eps) */
    double tmin, tmax;  /* layer thickness bounds, mm; 0: the defaults */
    double sharp;       /* §3.3 pre-pass threshold on |phi[i] - phi[i-1]|; 0: default
                           0.5; ADASLICE_SHARP_OFF (any negative value): off.
                           Optimal method only. */
    size_t budget;      /* optimal only; 0: none. Otherwise at most this many layers,
                           and eps is replaced by the smallest eps that allows it */
    uint32_t eps_units; /* optimal, additive metrics, no budget; 0: fine units
                           (about 2^-40 of the largest layer error). Otherwise
                           the plan a printer makes from adaslice_plan_units:
                           eps is exactly this many units (ADASLICE_PRINTER_EPS_UNITS) */
    /* curvature method only */
    const double *curvature;   /* k per bin, 1/mm (adaslice_curvature_profile) */
    adaslice_mapping mapping;
    double kappa_max;          /* 1/mm; 0: the 95th percentile of k over the bins */
    double alpha;              /* exponential mapping; 0: ADASLICE_DEFAULT_ALPHA */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_plan_options;

typedef struct adaslice_layer {
    double z_bottom, z_top;   /* mm above the part's bottom */
    double thickness;         /* mm */
    double error;             /* the layer's error under the profile's metric */
} adaslice_layer;

/* A plane the §3.3 pre-pass wanted but did not force where it wanted. */
typedef struct adaslice_plane_change {
    uint32_t wanted;            /* the plane (bin index) at the sharp change */
    uint32_t placed;            /* the nearest plane (within a thickest layer) that keeps
                                   the plan feasible and costs at most one layer more,
                                   or 0: dropped, none does */
    int infeasible;             /* why: 1, with a plane at `wanted` no plan keeps every
                                   layer within eps; 0, one would, with more than one
                                   layer more */
} adaslice_plane_change;

typedef struct adaslice_plan {
    size_t layer_count;         /* K */
    adaslice_layer *layers;     /* K layers, bottom first */
    uint32_t *planes;           /* K+1 bin indices: 0 = s0 < s1 < ... < sK = N */
    double eps;                 /* the eps planned for (budget mode: the one found) */
    double worst_error;         /* max layer error */
    double total_error;         /* sum of layer errors */
    size_t over_eps;            /* layers whose error exceeds eps (baselines only) */
    size_t forced_planes;       /* planes set by the sharp-change pre-pass (moved ones
                                   included): K is at most this many above the plan
                                   without the pre-pass */
    size_t plane_changes;       /* sharp-change planes moved or dropped so that eps
                                   stays feasible, listed bottom first in */
    adaslice_plane_change *changes;
    uint32_t bins_min, bins_max;/* ceil(tmin/b), floor(tmax/b) */
    adaslice_allocator allocator;
} adaslice_plan;

ADASLICE_DEF adaslice_result adaslice_plan_profile(const adaslice_profile *profile,
                                                   const adaslice_plan_options *options,
                                                   adaslice_plan *plan, adaslice_error *error);
ADASLICE_DEF void adaslice_plan_free(adaslice_plan *plan);

/* Error of the layer holding bins [first, end) under the profile's metric:
   b * sum phi (additive metrics), b * sum |phi[j] - phi[first]| (volume, eq. 20). */
ADASLICE_DEF double adaslice_layer_error(const adaslice_profile *profile, size_t first, size_t end);

/* The integers a printer plans on (link/PROTOCOL.md): with eps =
   options->eps_units units, units[i] is b * phi[i] rounded up to whole units
   and capped at eps_units + 1 (a bin above eps fits no layer either way), and
   forced[i] = 1 where the §3.3 pre-pass puts a plane on top of bin i (kept,
   moved or dropped for eps_units as adaslice_plan_profile does). Fed to
   adaslice_dp (eps = eps_units) they give adaslice_plan_profile's planes
   with the same options, bit for bit. units and forced hold N entries. */
#define ADASLICE_PRINTER_EPS_UNITS 1048576u
ADASLICE_DEF adaslice_result adaslice_plan_units(const adaslice_profile *profile, const adaslice_plan_options *options,
                                                 uint32_t *units, unsigned char *forced, adaslice_error *error);

/* ============================================================ orientation */
#ifndef ADASLICE_NO_ORIENT

/* §4.3: the plan seen along many build directions. A direction d means the
   part is rotated so that d points up (+z). */
typedef struct adaslice_orienter {
    const adaslice_mesh *mesh;
    adaslice_profile_options profile;  /* copies of the options given */
    adaslice_plan_options plan;
    adaslice_mesh sorted;              /* max-type metrics: the triangles in space-filling-curve
                                          order and the vertices they use, renumbered */
    float *weights;                    /* the profile's weights in that order, or NULL */
    int16_t *normals;                  /* cusp: each sorted triangle's unit normal in 32767ths and a
                                          bound on how far its value along any direction can be
                                          from it in 32768ths (32767: any) */
    float *boxes;                      /* each ADASLICE__BOX_TRIANGLES sorted triangles' bounding box
                                          (least x, y, z, then largest) and the cone of their normals
                                          (axis, cosine and sine of its angle, their largest bound) */
    uint32_t *firsts;                  /* the corners of each box's first triangle, in a row */
    double longest_edge, reach;        /* of any triangle; the farthest used vertex from the origin */
    adaslice_allocator allocator;
} adaslice_orienter;

typedef struct adaslice_direction_score {
    double direction[3];
    int feasible;          /* 0: no plan meets eps along this direction */
    size_t layers;         /* K */
    double worst_error;    /* the plan's largest layer error: the epsilon(O) of F(O) */
    double mean_error;     /* its total error / K */
    double score;          /* F(O), filled by adaslice_orient_scores */
} adaslice_direction_score;

/* The allocator is the profile options'. */
ADASLICE_DEF adaslice_result adaslice_orienter_init(adaslice_orienter *orienter, const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *profile,
                                                    const adaslice_plan_options *plan, adaslice_error *error);
/* The profile along direction d: adaslice_profile_exact of the mesh turned by
   adaslice_mesh_rotate(adaslice_rotation_to_z(d)), bit for bit. Reentrant:
   threads may share one orienter. */
ADASLICE_DEF adaslice_result adaslice_profile_along(const adaslice_orienter *orienter, const double d[3],
                                                    adaslice_profile *profile, adaslice_error *error);
/* K and the layer errors of the optimal plan along d. */
ADASLICE_DEF adaslice_result adaslice_orienter_score(const adaslice_orienter *orienter, const double d[3],
                                                     adaslice_direction_score *score, adaslice_error *error);
/* F(O) = alpha K / max K + (1 - alpha) eps / max eps over the feasible
   directions (eq. 25), eps being the plan's worst layer error, the paper's
   "geometric error" of §5.2 (a mean would fall as near-zero-error layers are
   added, rewarding the very layers K counts against); infeasible ones get F = 2. */
ADASLICE_DEF void adaslice_orient_scores(adaslice_direction_score *scores, size_t n, double alpha);
/* Indices of directions whose F is lower than every neighbour's within
   `radius` radians, best first; returns how many. Ties go to the direction
   nearer +z (the part as loaded, which needs no turn), then to the lower
   index. */
ADASLICE_DEF size_t adaslice_orient_minima(const adaslice_direction_score *scores, size_t n, double radius,
                                           size_t *out, size_t max);
ADASLICE_DEF void adaslice_orienter_free(adaslice_orienter *orienter);
#endif

/* ===================================================== masks and contours */

/* A printer's plate as a grid of z rays: width x height pixels of pitch_x x
   pitch_y mm, placed so that the centre of the mesh's box lies `offset` mm
   from the plate's centre. */
ADASLICE_DEF adaslice_grid adaslice_grid_plate(const adaslice_mesh *mesh, int width, int height, double pitch_x,
                                               double pitch_y, const double offset[2]);

/* Which heights of a layer its mask shows (adaslice_masker_layer). */
typedef enum adaslice_slice_at {
    ADASLICE_SLICE_MIDDLE = 0, /* the section at the layer's middle height */
    ADASLICE_SLICE_BOTTOM,     /* the section at the centre of its first bin */
    ADASLICE_SLICE_TOP,        /* the section at the centre of its last bin */
    ADASLICE_SLICE_ENVELOPE,   /* lit where the part is inside anywhere in (z_bottom, z_top):
                                  the union of its sections; never cuts into the part */
    ADASLICE_SLICE_CORE        /* lit where it is inside throughout (z_bottom, z_top): the
                                  intersection; never oversized */
} adaslice_slice_at;

typedef struct adaslice_mask_options {
    int supersample;                     /* s; 0 or 1: 1-bit masks, else 8-bit from s x s
                                            rays per pixel (at most 16) */
    const adaslice_allocator *allocator; /* NULL: default */
    adaslice_slice_at slice_at;          /* adaslice_masker_layer's rule; 0: middle */
    double bin;                          /* bottom and top cut at the centre of the first
                                            and last bin of this size, mm; 0:
                                            ADASLICE_DEFAULT_BIN */
    float *fractions;                    /* NULL, or width x height floats (rows from the
                                            grid's row 0): s > 1 and a section's rule, each
                                            mask also leaves every pixel's covered fraction
                                            here, before it is rounded to a grey level
                                            (a band's masker: in its rows) */
    int edges_balance;                   /* 1: the caller knows that every edge of the mesh
                                            is run as often one way as the other (the
                                            repair's report: no open, non-manifold or
                                            inconsistent edge), so the masker need not
                                            group the edges again to look for one that
                                            does not (the repair's work twice). If that
                                            is wrong, an open mesh is masked by rays,
                                            which cannot tell inside from outside at its
                                            holes, instead of by its closed sections. */
} adaslice_mask_options;

/* Layer masks on a printer's pixel grid (§3.4), made bottom-up in one sweep:
   each call applies the z-ray samples between the previous height and this
   one, so every sample is rasterised once over the whole print. A pixel is
   lit when the winding number of its z ray below the height is positive
   (overlapping shells stay lit). A mesh whose edges do not all balance (a
   hole, a crack, facets wound against their neighbours) cannot be read along
   rays, which may cross its surface once: its masks are its sections made
   whole, each gap closed by a chord from where a cut stops to the nearest
   place one starts, filled where the winding is positive (as PrusaSlicer
   closes gaps in 2D; for one gap this is where the generalized winding
   number of the section is >= 1/2). Pixels then differ from the closed
   part's only between each chord and the missing surface. The areas of the
   profiles follow the same rule. Such a mesh costs a sort of its section's
   row crossings per layer instead of the incremental sweep.
   With s > 1 the mask is 8-bit grey in s*s + 1 levels: 255 * k / (s*s),
   rounded, k the covered fraction of the pixel times s*s, rounded. A
   section's rule (middle, bottom, top) measures that fraction exactly, as
   font rasterisers do: the section's edges, cut from the facets, add their
   signed area and cover to the pixels they cross, and a prefix sum along
   each row gives the integral of the winding number over each pixel, clamped
   to [0, 1]. That is the area where the winding is positive wherever a
   pixel's winding takes two neighbouring values (any shells that do not
   overlap, holes, slivers); where the boundaries of overlapping shells cross
   inside one pixel (0, 1 and 2 in it) it over-counts that pixel by at most
   the overlap inside it, never under. The cost is the section's edge
   pixels and a pass over each row the part meets. Envelope and core read
   s x s rays per pixel by their rule instead: 255 * (rays lit) / (s*s).
   Memory: 1-bit, envelope and core 2 bytes per ray, plus 2 per pixel when
   s > 1, plus the image; envelope and core a bit per ray more, the spans of
   a layer's range and a row's crossings. A section's rule with s > 1: the
   image and 4 bytes per pixel.
   Row bands (adaslice_masker_bands): a masker split into maskers of some
   rows each, each keeping the facets that meet its rows and memory for
   those rows only, so the bands of one layer can be made at once on several
   threads (they share only the mesh, read-only) and a band need not wait
   for another. Between them they give the bytes the whole masker gives, bit
   for bit (each facet's cut and each sum of a pixel's are the same
   arithmetic in the same order), and their `lit` adds up to its (each a
   whole number of rays over s*s). An open mesh (`sections`) cannot be
   split: its gaps' chords join cuts from anywhere in the section. */
typedef struct adaslice_masker {
    const adaslice_mesh *mesh;
    adaslice_grid grid;          /* the printer's pixels; axis must be z */
    int supersample;             /* s; 1 gives 1-bit masks */
    unsigned char *image;        /* s = 1: rows of (width + 7) / 8 bytes, MSB first, 1 = lit;
                                    s > 1: rows of width bytes. Row 0 is the grid's row 0 */
    size_t stride;               /* bytes per image row */
    double lit;                  /* lit pixels (fractions with s > 1), in its rows */
    uint32_t rows[2];            /* the grid rows [rows[0], rows[1]) it makes (all but a
                                    band's): the image holds those rows only, rows[0] first */
    int sections;                /* 1: the mesh's edges do not all balance, so each mask is
                                    filled from the layer's whole section, its gaps closed
                                    by chords (and the masker cannot be split into bands) */
    /* private */
    adaslice_grid rays;
    double depth_origin, done;   /* samples below `done` are applied */
    uint32_t *order;             /* triangles by lowest z (those meeting the rows) */
    size_t count;                /* in order */
    size_t next;                 /* order[next] is the lowest not yet active */
    uint32_t *active;
    size_t active_count;
    int16_t *winding;            /* per ray of its rows */
    uint16_t *coverage;          /* per pixel of its rows, s > 1, envelope and core */
    uint32_t box[4];             /* the mesh's footprint in pixels (first column, first row,
                                    columns, rows): only there are cells */
    uint32_t cell_rows[2];       /* the box's rows [0] to [1] within the masker's rows: the
                                    cells' rows (the box's own rows set the edges' arithmetic,
                                    the same in every band) */
    float *cells;                /* s > 1, a section's rule: per cells' row, columns + 1
                                    differences whose prefix sums are the covered fractions */
    uint32_t *extent;            /* per cells' row: the cells touched [0, 1] and the
                                    image's non-zero bytes [2, 3], as [from, to) in it */
    uint32_t *touched;           /* per cells' row, a bit for each cell touched */
    unsigned char bit_at[32];    /* de Bruijn: a word's lowest bit times 0x077CB531, top 5 bits -> its index */
    float *fractions;            /* the options' */
    unsigned char grey[257];     /* coverage -> grey level */
    long long lit_rays;          /* rays inside: lit * s * s */
    struct adaslice__gaps *gaps; /* a mesh whose edges do not balance: its unbalanced
                                    edges, and masks come from its sections */
    double *seg;                 /* a section's directed segments, 4 per segment */
    size_t seg_cap;
    uint64_t *cross;             /* where they cross the ray rows */
    size_t cross_cap;
    adaslice_slice_at slice_at;  /* the options' rule, and its bin */
    double bin;
    int range;                   /* sweeping a layer's range by this rule (envelope, core) */
    unsigned char *changed;      /* envelope, core: a bit per ray shown otherwise than its
                                  inside at the last layer's top */
    struct adaslice__span *spans;/* the samples of the last layer's range, as spans */
    size_t span_count, span_cap;
    struct adaslice__crossing *crossings; /* one ray row's crossings, sorted */
    size_t crossing_cap;
    int nomem;                   /* the spans could not grow during a sweep */
    int zeroed;                  /* the sweep's buffers are zeroed (at the first layer) */
    adaslice_allocator allocator;
} adaslice_masker;

ADASLICE_DEF adaslice_result adaslice_masker_init(adaslice_masker *masker, const adaslice_mesh *mesh,
                                                  const adaslice_grid *grid, const adaslice_mask_options *options,
                                                  adaslice_error *error);
/* The mask at `height` (absolute z, mm) in masker->image; heights must not
   decrease from call to call. */
ADASLICE_DEF adaslice_result adaslice_masker_slice(adaslice_masker *masker, double height, adaslice_error *error);
/* The mask of the layer [z_bottom, z_top] (absolute z, mm) by the options'
   slice_at: a section (middle, bottom, top) or, along each ray's sorted
   crossings, envelope (lit if an inside interval of the ray meets the open
   range (z_bottom, z_top)) or core (lit if one holds all of it: a face
   lying at an end parts two layers and counts in neither); with s > 1 each of the s x s
   rays by the same rule. Layers come bottom-up: z_bottom (envelope, core) or
   the cut's height never below the previous call's. Envelope and core need
   balanced edges (a closed mesh): ADASLICE_ERR_UNSUPPORTED at init otherwise. */
ADASLICE_DEF adaslice_result adaslice_masker_layer(adaslice_masker *masker, double z_bottom, double z_top,
                                                   adaslice_error *error);
/* Splits `whole` (from adaslice_masker_init, before its first layer) into
   `count` maskers, band b over grid rows [rows[b], rows[b + 1]) (rising),
   each with whole's options, the facets that meet its rows and buffers for
   them: bands[b].image holds its rows only. Each band is then swept as a
   masker of its own, layers bottom-up, on any thread; whole is only read
   and can be freed. ADASLICE_ERR_UNSUPPORTED for an open mesh (whole's
   `sections`): one masker makes its masks. */
ADASLICE_DEF adaslice_result adaslice_masker_bands(const adaslice_masker *whole, const uint32_t *rows, size_t count,
                                                   adaslice_masker *bands, adaslice_error *error);
ADASLICE_DEF void adaslice_masker_free(adaslice_masker *masker);
/* The bytes adaslice_masker_init asks for on a width x height grid at
   `supersample` and `slice_at` for a mesh of `triangles`: a caller's limit
   checked before the work (saturates at SIZE_MAX). */
ADASLICE_DEF size_t adaslice_masker_bytes(uint32_t width, uint32_t height, int supersample, adaslice_slice_at slice_at,
                                         size_t triangles);

#ifndef ADASLICE_NO_CONTOURS
typedef struct adaslice_contour_options {
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_contour_options;

typedef struct adaslice_polygon {
    size_t first, count;  /* its points: points[2*first .. 2*(first+count)), x then y */
    int closed;           /* 1: a loop, the last point joins the first (never repeated);
                             0: a polyline ending on an open edge of the mesh */
    size_t next;          /* the polygon (index into polygons) whose first point this
                             one's last point joins: itself for a loop; for a polyline
                             the chord the masks close its gap with (see "sections of
                             open meshes"), so the polylines of a height form cycles,
                             each stored as a run of consecutive polygons */
} adaslice_polygon;

typedef struct adaslice_contours {
    size_t height_count;
    double *heights;            /* the heights cut, mm (a copy) */
    size_t *first_polygon;      /* height_count + 1 entries: height i owns polygons
                                   [first_polygon[i], first_polygon[i + 1]) */
    size_t polygon_count;
    adaslice_polygon *polygons;
    size_t point_count;
    double *points;             /* x, y per point, mm */
    size_t segment_count;       /* triangle cuts made: each triangle once per height
                                   in [its lowest z, its highest z) */
    size_t triangle_visits;     /* sweep work: at most segment_count + triangles */
    adaslice_allocator allocator;
} adaslice_contours;

/* Cross-sections at `count` nondecreasing finite heights (absolute z, mm). */
ADASLICE_DEF adaslice_result adaslice_contours_slice(const adaslice_mesh *mesh, const double *heights,
                                                     size_t count, const adaslice_contour_options *options,
                                                     adaslice_contours *contours, adaslice_error *error);
/* Winding number of (x, y) about every polygon at one height, exact for points
   off the edges (a point on an edge goes to one side consistently); open
   polylines count as closed by their chords (`next`), so a point is lit in
   the masks where this is positive. 0 if height_index is out of range. */
ADASLICE_DEF int adaslice_contours_winding(const adaslice_contours *contours, size_t height_index,
                                           double x, double y);
/* Distance from (x, y) to the nearest edge at one height, chords of open
   polylines included; HUGE_VAL if there are none. */
ADASLICE_DEF double adaslice_contours_distance(const adaslice_contours *contours, size_t height_index,
                                               double x, double y);
ADASLICE_DEF void adaslice_contours_free(adaslice_contours *contours);
#endif

/* ============================================================= job output */
/* CRC-32, varints and the mask run-length code: adaslice_mcu.h. */

/* Jacobs' working curve: a resin cures to the depth Cd = Dp ln(E / Ec) under
   a dose E, so a layer of thickness t needs E(t) = Ec exp(t / Dp). Calibrated
   at one point (S seconds cure a layer of T mm), E(t) = S exp((t - T) / Dp). */
typedef struct adaslice_cure {
    double seconds;     /* S, the exposure that cures a layer of `thickness` */
    double thickness;   /* T, mm */
    double penetration; /* Dp, the resin's penetration depth, mm; 0: one exposure,
                           S, for every thickness */
} adaslice_cure;

/* The curve through two calibrated points (s1 seconds cure t1 mm, s2 cure t2):
   Dp = (t2 - t1) / ln(s2 / s1), the first point kept as S@T. The points must
   be positive and the thicker layer need the longer exposure. */
ADASLICE_DEF adaslice_result adaslice_cure_fit(double s1, double t1, double s2, double t2, adaslice_cure *cure,
                                               adaslice_error *error);
/* The exposure of a layer `thickness` mm thick, s. */
ADASLICE_DEF double adaslice_cure_seconds(const adaslice_cure *cure, double thickness);

typedef struct adaslice_preview_options {
    double elevation, azimuth;           /* degrees: where the viewer stands; 0, 0: 30 and -45,
                                            over the plate's front-right corner: the top in
                                            view, heights drawn at cos 30 of their length */
    unsigned char colour[3];             /* the part's; 0, 0, 0: a resin grey-blue */
    const unsigned char *face_colours;   /* NULL, or R G B per triangle: each face its own
                                            colour (a weight map), shaded the same way */
    unsigned char background[3];         /* 0, 0, 0: black */
    const adaslice_allocator *allocator; /* NULL: default */
} adaslice_preview_options;

/* A shaded picture of the part for a job's preview: width x height pixels,
   3 bytes (R, G, B) each, rows top first. The part is drawn as it stands on
   the plate, +z (the build direction) up the picture: the viewer stands at
   the elevation above the plate and the azimuth from +x towards +y (-y is the
   front), looking down at it. The mesh is rasterised by the LDI's rasteriser
   into a z-buffer at the picture's pixels (the part fitted with a margin,
   pixels square), and each pixel takes the nearest surface's normal, lit from
   above, over the viewer's left shoulder. */
ADASLICE_DEF adaslice_result adaslice_preview(const adaslice_mesh *mesh, int width, int height,
                                              const adaslice_preview_options *options, unsigned char *rgb,
                                              adaslice_error *error);

#ifdef __cplusplus
}
#endif
#endif /* ADASLICE_H */

/* ======================================================================== */
/*                              IMPLEMENTATION                              */
/* ======================================================================== */
#ifdef ADASLICE_IMPLEMENTATION
#ifndef ADASLICE_IMPLEMENTATION_DONE
#define ADASLICE_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>
#include <float.h>
#include <limits.h>
#include <stdarg.h>
#include <stdlib.h> /* strtod, qsort */

#ifndef ADASLICE_ASSERT
#include <assert.h>
#define ADASLICE_ASSERT(x) assert(x)
#endif

#if !defined(ADASLICE_NO_MALLOC) && !defined(ADASLICE_MALLOC)
#define ADASLICE_MALLOC(size) malloc(size)
#define ADASLICE_FREE(ptr) free(ptr)
#endif

#ifndef ADASLICE_NO_STDIO
#include <stdio.h>
#endif

/* the integer planner, CRC-32 and the mask code: the printer's own code */
#ifndef ADASLICE_MCU_IMPLEMENTATION
#define ADASLICE_MCU_IMPLEMENTATION
#endif
#include "adaslice_mcu.h"

/* =========================================================== conventions */

ADASLICE_DEF const char *adaslice_result_name(adaslice_result r)
{
    switch (r) {
    case ADASLICE_OK: return "ok";
    case ADASLICE_ERR_ARGUMENT: return "invalid argument";
    case ADASLICE_ERR_NOMEM: return "out of memory";
    case ADASLICE_ERR_IO: return "cannot read file";
    case ADASLICE_ERR_FORMAT: return "unrecognised format";
    case ADASLICE_ERR_TRUNCATED: return "truncated data";
    case ADASLICE_ERR_COUNT: return "triangle count disagrees with size";
    case ADASLICE_ERR_NUMBER: return "unparsable number";
    case ADASLICE_ERR_NONFINITE: return "non-finite coordinate";
    case ADASLICE_ERR_INDEX: return "index out of range";
    case ADASLICE_ERR_OVERFLOW: return "size overflow";
    case ADASLICE_ERR_EMPTY: return "empty mesh";
    case ADASLICE_ERR_UNSUPPORTED: return "unsupported feature";
    case ADASLICE_ERR_INFEASIBLE: return "infeasible constraints";
    case ADASLICE_ERR_VARINT: return "malformed number in a mask code";
    case ADASLICE_ERR_RUN: return "malformed run in a mask code";
    case ADASLICE_ERR_ROWS: return "too many rows in a mask code";
    }
    return "unknown result";
}

/* A small formatter, so messages need no stdio: %s %c %d %u %zu %g (6 significant
   digits) and %%. */
typedef struct adaslice__out { char *buf; size_t cap, len; } adaslice__out;

static void adaslice__putc(adaslice__out *o, char c)
{
    if (o->len + 1 < o->cap) o->buf[o->len] = c;
    o->len++;
}

static void adaslice__puts(adaslice__out *o, const char *s)
{
    while (*s) adaslice__putc(o, *s++);
}

static void adaslice__putu(adaslice__out *o, unsigned long long v)
{
    char tmp[24];
    int n = 0;
    do { tmp[n++] = (char)('0' + (int)(v % 10u)); v /= 10u; } while (v);
    while (n) adaslice__putc(o, tmp[--n]);
}

static void adaslice__putg(adaslice__out *o, double v)
{
    int exp10 = 0, digits, i, point, last;
    char d[8];
    unsigned long long m;
    double scaled;
    if (v != v) { adaslice__puts(o, "nan"); return; }
    if (v < 0) { adaslice__putc(o, '-'); v = -v; }
    if (v > DBL_MAX) { adaslice__puts(o, "inf"); return; }
    if (v == 0) { adaslice__putc(o, '0'); return; }
    /* normalise to [1e5, 1e6) and round to six digits */
    scaled = v;
    while (scaled >= 1e6) { scaled /= 10; exp10++; }
    while (scaled < 1e5) { scaled *= 10; exp10--; }
    m = (unsigned long long)(scaled + 0.5);
    if (m >= 1000000ull) { m /= 10; exp10++; }
    for (i = 5; i >= 0; i--) { d[i] = (char)('0' + (int)(m % 10)); m /= 10; }
    last = 5;
    while (last > 0 && d[last] == '0') last--;
    digits = exp10 + 5; /* decimal exponent of the first digit */
    if (digits < -4 || digits >= 6) {
        adaslice__putc(o, d[0]);
        if (last > 0) { adaslice__putc(o, '.'); for (i = 1; i <= last; i++) adaslice__putc(o, d[i]); }
        adaslice__putc(o, 'e');
        if (digits < 0) { adaslice__putc(o, '-'); digits = -digits; } else adaslice__putc(o, '+');
        if (digits < 10) adaslice__putc(o, '0');
        adaslice__putu(o, (unsigned long long)digits);
        return;
    }
    if (digits < 0) {
        adaslice__puts(o, "0.");
        for (i = -1; i > digits; i--) adaslice__putc(o, '0');
        for (i = 0; i <= last; i++) adaslice__putc(o, d[i]);
        return;
    }
    point = digits;
    for (i = 0; i <= (last > point ? last : point); i++) {
        adaslice__putc(o, i <= 5 ? d[i] : '0');
        if (i == point && i < last) adaslice__putc(o, '.');
    }
}

static void adaslice__vformat(char *buf, size_t cap, const char *fmt, va_list ap)
{
    adaslice__out o;
    o.buf = buf; o.cap = cap; o.len = 0;
    for (; *fmt; fmt++) {
        if (*fmt != '%') { adaslice__putc(&o, *fmt); continue; }
        fmt++;
        switch (*fmt) {
        case 's': { const char *s = va_arg(ap, const char *); adaslice__puts(&o, s ? s : "(null)"); break; }
        case 'c': adaslice__putc(&o, (char)va_arg(ap, int)); break;
        case 'd': {
            int v = va_arg(ap, int);
            if (v < 0) { adaslice__putc(&o, '-'); adaslice__putu(&o, (unsigned long long)(-(long long)v)); }
            else adaslice__putu(&o, (unsigned long long)v);
            break;
        }
        case 'u': adaslice__putu(&o, va_arg(ap, unsigned)); break;
        case 'z': fmt++; adaslice__putu(&o, (unsigned long long)va_arg(ap, size_t)); break; /* %zu */
        case 'g': adaslice__putg(&o, va_arg(ap, double)); break;
        case '%': adaslice__putc(&o, '%'); break;
        default: adaslice__putc(&o, '?'); if (!*fmt) fmt--; break;
        }
    }
    if (cap) buf[o.len < cap ? o.len : cap - 1] = 0;
}

/* Records a failure and returns its code, so callers can `return adaslice__fail(...)`. */
static adaslice_result adaslice__fail(adaslice_error *err, adaslice_result code, size_t offset,
                                      size_t line, const char *fmt, ...)
{
    va_list ap;
    if (err) {
        err->result = code;
        err->offset = offset;
        err->line = line;
        err->z = 0;
        err->min_eps = 0;
        va_start(ap, fmt);
        adaslice__vformat(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

static void adaslice__ok(adaslice_error *err)
{
    if (err) {
        memset(err, 0, sizeof *err);
        err->result = ADASLICE_OK;
    }
}

/* ---- allocation */

#ifndef ADASLICE_NO_MALLOC
static void *adaslice__default_alloc(void *user, size_t size) { (void)user; return ADASLICE_MALLOC(size); }
static void adaslice__default_free(void *user, void *ptr) { (void)user; ADASLICE_FREE(ptr); }
#endif

static adaslice_allocator adaslice__allocator(const adaslice_allocator *a)
{
    adaslice_allocator r;
    if (a && a->alloc && a->free) return *a;
#ifndef ADASLICE_NO_MALLOC
    r.alloc = adaslice__default_alloc;
    r.free = adaslice__default_free;
#else
    r.alloc = NULL;
    r.free = NULL;
#endif
    r.user = NULL;
    return r;
}

/* count * size bytes, or NULL on overflow or exhaustion */
static void *adaslice__alloc(const adaslice_allocator *a, size_t count, size_t size)
{
    if (!a->alloc || (size && count > SIZE_MAX / size)) return NULL;
    return a->alloc(a->user, count && size ? count * size : 1);
}

static void adaslice__free(const adaslice_allocator *a, void *p)
{
    if (p && a->free) a->free(a->user, p);
}

/* Room for `need` items, at least twice the old capacity so that appending stays
   linear; NULL when out of memory (then `old` is still valid). */
static void *adaslice__grow(const adaslice_allocator *a, void *old, size_t used, size_t *cap,
                            size_t need, size_t item)
{
    size_t n = *cap < SIZE_MAX / 2 ? 2 * *cap : need;
    void *p;
    if (n < need) n = need;
    if (n < 64) n = 64;
    p = adaslice__alloc(a, n, item);
    if (!p) return NULL;
    if (used) memcpy(p, old, used * item);
    adaslice__free(a, old);
    *cap = n;
    return p;
}

/* ================================================================== mesh */
/* Exactly zero area, in double from the stored floats: repeated corners included. */
static int adaslice__zero_area(const float *v, const uint32_t *t)
{
    const float *a = v + 3 * (size_t)t[0], *p = v + 3 * (size_t)t[1], *q = v + 3 * (size_t)t[2];
    double ux = (double)p[0] - a[0], uy = (double)p[1] - a[1], uz = (double)p[2] - a[2];
    double wx = (double)q[0] - a[0], wy = (double)q[1] - a[1], wz = (double)q[2] - a[2];
    return uy * wz - uz * wy == 0 && uz * wx - ux * wz == 0 && ux * wy - uy * wx == 0;
}

#ifndef ADASLICE_NO_LOADERS
/* ---- reading: what every loader shares */

/* Geometry as it is read, before it becomes an adaslice_mesh. */
typedef struct adaslice__build {
    const char *text;           /* the input, which is not NUL-terminated */
    const unsigned char *bytes; /* the same input, for binary reads */
    size_t size;
    const char *name;           /* the format, for messages */
    double scale;
    adaslice_allocator a;
    adaslice_error *err;
    float *v;                   /* x, y, z per vertex */
    size_t nv, vcap;
    uint32_t *t;                /* three vertex indices per triangle */
    size_t nt, tcap;
} adaslice__build;

static size_t adaslice__at(const adaslice__build *b, const char *w) { return (size_t)(w - b->text); }

/* Fails with the place in front of the message: "OBJ line 12: ..." for text,
   "PLY byte 96: ..." for binary data. */
static adaslice_result adaslice__bad(adaslice__build *b, adaslice_result code, size_t offset,
                                     size_t line, const char *fmt, ...)
{
    char what[256];
    va_list ap;
    va_start(ap, fmt);
    adaslice__vformat(what, sizeof what, fmt, ap);
    va_end(ap);
    if (line) return adaslice__fail(b->err, code, offset, line, "%s line %zu: %s", b->name, line, what);
    return adaslice__fail(b->err, code, offset, 0, "%s byte %zu: %s", b->name, offset, what);
}

/* A word of the input, short and printable enough to quote in a one-line message. */
static const char *adaslice__quote(char q[48], const char *w, size_t n)
{
    size_t i, k = n < 40 ? n : 40;
    for (i = 0; i < k; i++) q[i] = (w[i] >= 32 && w[i] < 127) ? w[i] : '?';
    if (n > k) memcpy(q + k, "...", 4);
    else q[k] = 0;
    return q;
}

/* A count's noun in a message: "1 triangle", "2 triangles". */
static const char *adaslice__noun(size_t n, const char *one, const char *many) { return n == 1 ? one : many; }

/* An integral double as exact text: %g keeps only six digits, too few for an index. */
static const char *adaslice__int_text(char buf[24], double v)
{
    adaslice__out o;
    o.buf = buf; o.cap = 24; o.len = 0;
    if (v < 0) { adaslice__putc(&o, '-'); v = -v; }
    adaslice__putu(&o, (unsigned long long)v);
    buf[o.len] = 0;
    return buf;
}

static adaslice_result adaslice__reserve(adaslice__build *b, size_t vertices, size_t triangles)
{
    void *p;
    if (vertices > b->vcap) {
        p = adaslice__grow(&b->a, b->v, b->nv, &b->vcap, vertices, 3 * sizeof(float));
        if (!p) return adaslice__fail(b->err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory", b->name);
        b->v = ADASLICE__CAST(float *, p);
    }
    if (triangles > b->tcap) {
        p = adaslice__grow(&b->a, b->t, b->nt, &b->tcap, triangles, 3 * sizeof(uint32_t));
        if (!p) return adaslice__fail(b->err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory", b->name);
        b->t = ADASLICE__CAST(uint32_t *, p);
    }
    return ADASLICE_OK;
}

/* Scales one coordinate; NaN or infinity, in the file or after scaling, is an error (§1). */
static adaslice_result adaslice__coord(adaslice__build *b, double v, size_t offset, size_t line, float *out)
{
    double s = v * b->scale;
    if (!(fabs(v) <= DBL_MAX))
        return adaslice__bad(b, ADASLICE_ERR_NONFINITE, offset, line, "coordinate %g is not finite", v);
    if (!(fabs(s) <= FLT_MAX))
        return adaslice__bad(b, ADASLICE_ERR_NONFINITE, offset, line,
                             "coordinate %g scaled by %g is not finite as a float", v, b->scale);
    *out = (float)s;
    return ADASLICE_OK;
}

static adaslice_result adaslice__vertex(adaslice__build *b, const float xyz[3])
{
    adaslice_result r;
    if (b->nv == UINT32_MAX)
        return adaslice__fail(b->err, ADASLICE_ERR_OVERFLOW, 0, 0,
                              "%s: more than 4294967295 vertices do not fit 32-bit indices", b->name);
    if (b->nv == b->vcap && (r = adaslice__reserve(b, b->nv + 1, 0))) return r;
    memcpy(b->v + 3 * b->nv++, xyz, 3 * sizeof(float));
    return ADASLICE_OK;
}

/* The caller has checked the indices against the vertex count. */
static adaslice_result adaslice__triangle(adaslice__build *b, uint32_t i, uint32_t j, uint32_t k)
{
    uint32_t *t;
    adaslice_result r;
    if (b->nt == b->tcap && (r = adaslice__reserve(b, 0, b->nt + 1))) return r;
    t = b->t + 3 * b->nt++;
    t[0] = i; t[1] = j; t[2] = k;
    return ADASLICE_OK;
}

/* Hands the arrays over to the mesh. Zero-area triangles stay: every stage
   skips them, and repair needs the ones that seal T-junctions; a file of
   nothing else is empty. */
static adaslice_result adaslice__finish(adaslice__build *b, adaslice_mesh *mesh)
{
    size_t i, kept = 0;
    for (i = 0; i < b->nt; i++) kept += !adaslice__zero_area(b->v, b->t + 3 * i);
    if (!kept && b->nt == 1)
        return adaslice__fail(b->err, ADASLICE_ERR_EMPTY, 0, 0, "%s: its one triangle has zero area", b->name);
    if (!kept && b->nt)
        return adaslice__fail(b->err, ADASLICE_ERR_EMPTY, 0, 0, "%s: all %zu triangles have zero area",
                              b->name, b->nt);
    if (!kept) return adaslice__fail(b->err, ADASLICE_ERR_EMPTY, 0, 0, "%s: no triangles", b->name);
    mesh->vertex_count = b->nv;
    mesh->vertices = b->v;
    mesh->triangle_count = b->nt;
    mesh->triangles = b->t;
    mesh->allocator = b->a;
    b->v = NULL;
    b->t = NULL;
    return ADASLICE_OK;
}

/* ---- text input */

typedef struct adaslice__text {
    const char *p, *end;
    size_t line; /* 1-based line of p */
} adaslice__text;

static adaslice__text adaslice__text_at(const adaslice__build *b)
{
    adaslice__text t;
    t.p = b->text;
    t.end = b->text + b->size;
    t.line = 1;
    return t;
}

static int adaslice__blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next whitespace-separated word and its length; 0 at the end of the data, or
   of the line unless `cross` lets it read on past newlines. */
static size_t adaslice__word(adaslice__text *t, int cross, const char **w)
{
    const char *p = t->p;
    for (; p < t->end; p++) {
        if (*p == '\n') {
            if (!cross) break;
            t->line++;
        } else if (!adaslice__blank(*p)) break;
    }
    *w = p;
    while (p < t->end && *p != '\n' && !adaslice__blank(*p)) p++;
    t->p = p;
    return (size_t)(p - *w);
}

static void adaslice__skip_line(adaslice__text *t)
{
    while (t->p < t->end && *t->p != '\n') t->p++;
    if (t->p < t->end) { t->p++; t->line++; }
}

/* Case-insensitive comparison with a lowercase keyword. */
static int adaslice__is(const char *w, size_t n, const char *kw)
{
    size_t i;
    for (i = 0; i < n; i++) {
        char c = w[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (!kw[i] || c != kw[i]) return 0;
    }
    return kw[n] == 0;
}

/* An optionally signed decimal integer at the front of w[0..n); returns the characters
   read, 0 if there is none. Magnitudes saturate at 2^53: beyond any valid count or
   index, and still exact as a double. */
static size_t adaslice__integer(const char *w, size_t n, long long *out)
{
    size_t i = n && (w[0] == '-' || w[0] == '+'), start = i;
    long long v = 0;
    for (; i < n && w[i] >= '0' && w[i] <= '9'; i++) {
        v = 10 * v + (w[i] - '0');
        if (v > (1LL << 53)) v = 1LL << 53;
    }
    if (i == start) return 0;
    *out = w[0] == '-' ? -v : v;
    return i;
}

/* strtod on a NUL-terminated copy, because the input has no terminator; the whole
   word must be the number. */
static adaslice_result adaslice__number(adaslice__build *b, const char *w, size_t n, size_t line, double *out)
{
    char buf[64], *end, q[48];
    *out = 0;
    if (n < sizeof buf) {
        memcpy(buf, w, n);
        buf[n] = 0;
        *out = strtod(buf, &end);
        if (n && end == buf + n) return ADASLICE_OK;
    }
    return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), line, "'%s' is not a number",
                         adaslice__quote(q, w, n));
}

/* `want` is quoted in the message: pass "facet' or 'endsolid" for two choices. */
static adaslice_result adaslice__unexpected(adaslice__build *b, const adaslice__text *t, const char *w,
                                            size_t n, const char *want)
{
    char q[48];
    if (!n) return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, b->size, t->line,
                                 "the data ends where '%s' was expected", want);
    return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), t->line, "expected '%s', found '%s'",
                         want, adaslice__quote(q, w, n));
}

static adaslice_result adaslice__expect(adaslice__build *b, adaslice__text *t, const char *keyword)
{
    const char *w;
    size_t n = adaslice__word(t, 1, &w);
    return adaslice__is(w, n, keyword) ? ADASLICE_OK : adaslice__unexpected(b, t, w, n, keyword);
}

static adaslice_result adaslice__read_coord(adaslice__build *b, adaslice__text *t, int cross, float *out)
{
    const char *w;
    size_t n = adaslice__word(t, cross, &w);
    double v;
    adaslice_result r;
    if (!n) return adaslice__bad(b, t->p < t->end ? ADASLICE_ERR_FORMAT : ADASLICE_ERR_TRUNCATED,
                                 adaslice__at(b, w), t->line, "the %s ends where a coordinate was expected",
                                 t->p < t->end ? "line" : "data");
    if ((r = adaslice__number(b, w, n, t->line, &v))) return r;
    return adaslice__coord(b, v, adaslice__at(b, w), t->line, out);
}

/* ---- binary data */

enum { ADASLICE__I8 = 1, ADASLICE__U8, ADASLICE__I16, ADASLICE__U16, ADASLICE__I32, ADASLICE__U32,
       ADASLICE__F32, ADASLICE__F64 };
static const unsigned char adaslice__type_size[9] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

/* n bytes at p as an unsigned integer in the given byte order, assembled
   byte by byte so that the host's byte order and alignment do not matter. */
static inline uint64_t adaslice__bits(const unsigned char *p, unsigned n, int big_endian)
{
    uint64_t u = 0;
    unsigned i;
    if (n == 4 && !big_endian) /* the common case without the loop: most of a binary file's load */
        return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    for (i = 0; i < n; i++) u |= (uint64_t)p[big_endian ? n - 1 - i : i] << (8 * i);
    return u;
}

/* One value of a PLY scalar type (binary STL uses U32 and F32). */
static inline double adaslice__scalar(const unsigned char *p, int type, int big_endian)
{
    unsigned n = adaslice__type_size[type];
    uint64_t u = adaslice__bits(p, n, big_endian);
    if (type == ADASLICE__F32) {
        uint32_t bits = (uint32_t)u;
        float f;
        memcpy(&f, &bits, 4);
        return f;
    }
    if (type == ADASLICE__F64) {
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    if (type % 2 && u >> (8 * n - 1)) return (double)u - ldexp(1.0, (int)(8 * n)); /* signed */
    return (double)u;
}

/* ---- STL */

/* 84 bytes of header and count, then 50 per triangle, in data `total` bytes
   long of which b may hold only the first 84 or more (the file loader checks
   the count before it reads the rest). A wrong count and a cut-off file look
   alike, so both are a count mismatch. */
static adaslice_result adaslice__stl_count(adaslice__build *b, size_t total, size_t *count)
{
    if (total < 84)
        return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, total, 0,
                             "the data ends inside the 84-byte header and triangle count");
    *count = (size_t)adaslice__scalar(b->bytes + 80, ADASLICE__U32, 0);
    if ((total - 84) % 50 || (total - 84) / 50 != *count)
        return adaslice__fail(b->err, ADASLICE_ERR_COUNT, 80, 0,
                              "binary STL: header says %zu %s (%zu bytes) but the data is %zu bytes", *count,
                              adaslice__noun(*count, "triangle", "triangles"), 84 + 50 * *count, total);
    return ADASLICE_OK;
}

static adaslice_result adaslice__stl_binary(adaslice__build *b)
{
    size_t count, i, at;
    float xyz[3];
    int corner, k;
    adaslice_result r;
    if ((r = adaslice__stl_count(b, b->size, &count)) || (r = adaslice__reserve(b, 3 * count, count))) return r;
    for (i = 0; i < count; i++) {
        for (corner = 0; corner < 3; corner++) { /* the 12-byte normal is ignored: often wrong */
            for (k = 0; k < 3; k++) {
                at = 84 + 50 * i + 12 + 12 * (size_t)corner + 4 * (size_t)k;
                r = adaslice__coord(b, adaslice__scalar(b->bytes + at, ADASLICE__F32, 0), at, 0, &xyz[k]);
                if (r) return r;
            }
            if ((r = adaslice__vertex(b, xyz))) return r;
        }
        r = adaslice__triangle(b, (uint32_t)(b->nv - 3), (uint32_t)(b->nv - 2), (uint32_t)(b->nv - 1));
        if (r) return r;
    }
    return ADASLICE_OK;
}

/* facet normal n n n / outer loop / vertex x y z (three or more) / endloop / endfacet */
static adaslice_result adaslice__stl_facet(adaslice__build *b, adaslice__text *t)
{
    size_t n, corners = 0, first = b->nv;
    const char *w;
    float xyz[3];
    int k;
    adaslice_result r;
    if ((r = adaslice__expect(b, t, "normal"))) return r;
    for (k = 0; k < 3; k++) /* the stored normal is ignored: often wrong */
        if (!(n = adaslice__word(t, 1, &w))) return adaslice__unexpected(b, t, w, n, "normal component");
    if ((r = adaslice__expect(b, t, "outer")) || (r = adaslice__expect(b, t, "loop"))) return r;
    while (n = adaslice__word(t, 1, &w), adaslice__is(w, n, "vertex")) {
        for (k = 0; k < 3; k++)
            if ((r = adaslice__read_coord(b, t, 1, &xyz[k]))) return r;
        if ((r = adaslice__vertex(b, xyz))) return r;
        if (++corners >= 3 && (r = adaslice__triangle(b, (uint32_t)first, (uint32_t)(b->nv - 2),
                                                      (uint32_t)(b->nv - 1))))
            return r;
    }
    if (!adaslice__is(w, n, "endloop")) return adaslice__unexpected(b, t, w, n, "vertex' or 'endloop");
    if (corners < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), t->line,
                             "a facet needs at least 3 vertices, this one has %zu", corners);
    return adaslice__expect(b, t, "endfacet");
}

/* One or more "solid name ... endsolid name" blocks. */
static adaslice_result adaslice__stl_ascii(adaslice__build *b)
{
    adaslice__text t = adaslice__text_at(b);
    const char *w;
    size_t n = adaslice__word(&t, 1, &w);
    adaslice_result r;
    do {
        if (!adaslice__is(w, n, "solid")) return adaslice__unexpected(b, &t, w, n, "solid");
        adaslice__skip_line(&t);
        while (n = adaslice__word(&t, 1, &w), !adaslice__is(w, n, "endsolid")) {
            if (!adaslice__is(w, n, "facet")) return adaslice__unexpected(b, &t, w, n, "facet' or 'endsolid");
            if ((r = adaslice__stl_facet(b, &t))) return r;
        }
        adaslice__skip_line(&t);
    } while ((n = adaslice__word(&t, 1, &w)) != 0);
    return ADASLICE_OK;
}

/* ---- OBJ */

/* "7", "7/1", "7/1/3", "7//3" or relative "-1": the vertex part, as a 0-based index
   into the vertices read so far. The texture and normal indices are not used, but
   each must be an integer or left out ("7//"), so that "7/a/" is not taken for 7. */
static adaslice_result adaslice__obj_index(adaslice__build *b, const char *w, size_t n, size_t line, uint32_t *out)
{
    long long i, k, unused;
    size_t used = adaslice__integer(w, n, &i), at, slashes = 0;
    char q[48];
    for (at = used; used && at < n && w[at] == '/' && slashes < 2; slashes++) {
        at++;
        at += adaslice__integer(w + at, n - at, &unused);
    }
    if (!used || at < n)
        return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), line,
                             "'%s' is not a vertex reference (v, v/vt, v/vt/vn or v//vn, each an integer)",
                             adaslice__quote(q, w, n));
    if (i == 0)
        return adaslice__bad(b, ADASLICE_ERR_INDEX, adaslice__at(b, w), line,
                             "vertex index 0 is invalid (OBJ counts from 1)");
    k = i < 0 ? (long long)b->nv + i : i - 1;
    if (k < 0 || k >= (long long)b->nv)
        return adaslice__bad(b, ADASLICE_ERR_INDEX, adaslice__at(b, w), line,
                             "vertex index %s is out of range (%zu %s so far)", adaslice__quote(q, w, used),
                             b->nv, adaslice__noun(b->nv, "vertex", "vertices"));
    *out = (uint32_t)k;
    return ADASLICE_OK;
}

/* The corners after "f", fan-triangulated. */
static adaslice_result adaslice__obj_face(adaslice__build *b, adaslice__text *t, const char *keyword)
{
    uint32_t first = 0, prev = 0, cur = 0;
    size_t corners = 0, n;
    const char *w;
    adaslice_result r;
    while ((n = adaslice__word(t, 0, &w)) && w[0] != '#') {
        if ((r = adaslice__obj_index(b, w, n, t->line, &cur))) return r;
        if (corners == 0) first = cur;
        else if (corners >= 2 && (r = adaslice__triangle(b, first, prev, cur))) return r;
        prev = cur;
        corners++;
    }
    if (corners < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, keyword), t->line,
                             "a face needs at least 3 vertices, this one has %zu", corners);
    return ADASLICE_OK;
}

/* Only v and f matter; every other statement (vt, vn, g, usemtl, ...) is skipped. */
static adaslice_result adaslice__obj(adaslice__build *b)
{
    adaslice__text t = adaslice__text_at(b);
    const char *w;
    size_t n;
    float xyz[3];
    int k;
    adaslice_result r;
    while (t.p < t.end) {
        n = adaslice__word(&t, 0, &w);
        if (adaslice__is(w, n, "v")) { /* a w or colours after x y z are ignored */
            for (k = 0; k < 3; k++)
                if ((r = adaslice__read_coord(b, &t, 0, &xyz[k]))) return r;
            if ((r = adaslice__vertex(b, xyz))) return r;
        } else if (adaslice__is(w, n, "f")) {
            if ((r = adaslice__obj_face(b, &t, w))) return r;
        }
        adaslice__skip_line(&t);
    }
    return ADASLICE_OK;
}

/* ---- PLY */

enum { ADASLICE__PLY_OTHER, ADASLICE__PLY_X, ADASLICE__PLY_Y, ADASLICE__PLY_Z, ADASLICE__PLY_INDICES };
enum { ADASLICE__PLY_VERTEX = 1, ADASLICE__PLY_FACE, ADASLICE__PLY_STRIPS };

typedef struct adaslice__ply_prop {
    unsigned char type;       /* ADASLICE__I8 ... ADASLICE__F64 */
    unsigned char count_type; /* lists: the type of the length; 0 for scalars */
    unsigned char role;       /* ADASLICE__PLY_X ...; only vertex indices are a list role */
} adaslice__ply_prop;

typedef struct adaslice__ply_elem {
    char name[48];
    size_t count;             /* records */
    size_t at, line;          /* where the header names it */
    unsigned first, props;    /* its properties in adaslice__ply_reader.props */
    unsigned char kind;       /* ADASLICE__PLY_VERTEX ..., 0 for elements we skip */
} adaslice__ply_elem;

typedef struct adaslice__ply_reader {
    adaslice__build *b;
    adaslice__text t;         /* the header, then ASCII data */
    size_t pos;               /* binary data: offset of the next value */
    size_t at;                /* offset of the value read last */
    int encoding;             /* 0 ASCII, 1 little endian, 2 big endian */
    int has_vertex;
    size_t vertices;          /* records of the vertex element */
    unsigned elem_count, prop_count;
    adaslice__ply_elem elems[32];
    adaslice__ply_prop props[256];
} adaslice__ply_reader;

static size_t adaslice__ply_line(const adaslice__ply_reader *r) { return r->encoding ? 0 : r->t.line; }

static int adaslice__ply_type(const char *w, size_t n)
{
    static const char *const names[16] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                           "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32",
                                           "float64"};
    int i;
    for (i = 0; i < 16; i++)
        if (adaslice__is(w, n, names[i])) return i % 8 + 1;
    return 0;
}

static adaslice_result adaslice__ply_element_line(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    adaslice__ply_elem *e;
    const char *w;
    size_t n;
    long long count;
    char q[48];
    if (r->elem_count == 32)
        return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, r->t.p), r->t.line,
                             "more than 32 elements");
    e = &r->elems[r->elem_count++];
    e->line = r->t.line;
    e->first = r->prop_count;
    e->props = 0;
    n = adaslice__word(&r->t, 0, &w);
    e->at = adaslice__at(b, w);
    adaslice__quote(e->name, w, n);
    e->kind = adaslice__is(w, n, "vertex") ? ADASLICE__PLY_VERTEX
            : adaslice__is(w, n, "face") ? ADASLICE__PLY_FACE
            : adaslice__is(w, n, "tristrips") ? ADASLICE__PLY_STRIPS : 0;
    if (e->kind == ADASLICE__PLY_VERTEX && r->has_vertex)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "a second 'vertex' element");
    n = adaslice__word(&r->t, 0, &w);
    if (!n || adaslice__integer(w, n, &count) != n)
        return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), r->t.line,
                             "element '%s' count '%s' is not a number", e->name, adaslice__quote(q, w, n));
    if (count < 0)
        return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), r->t.line,
                             "element '%s' count %s is negative", e->name, adaslice__quote(q, w, n));
    if (count > UINT32_MAX) /* indices are 32-bit, and no other element gets this big */
        return adaslice__bad(b, ADASLICE_ERR_OVERFLOW, adaslice__at(b, w), r->t.line,
                             "element '%s' count %s exceeds 4294967295", e->name, adaslice__quote(q, w, n));
    e->count = (size_t)count;
    if (e->kind == ADASLICE__PLY_VERTEX) {
        r->has_vertex = 1;
        r->vertices = e->count;
    }
    return ADASLICE_OK;
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" */
static adaslice_result adaslice__ply_property_line(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    adaslice__ply_elem *e;
    adaslice__ply_prop *p;
    const char *w;
    size_t n, line = r->t.line;
    int axis;
    char q[48];
    if (!r->elem_count)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, r->t.p), line, "a property before any element");
    if (r->prop_count == 256)
        return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, r->t.p), line,
                             "more than 256 properties");
    e = &r->elems[r->elem_count - 1];
    p = &r->props[r->prop_count++];
    e->props++;
    p->count_type = 0;
    n = adaslice__word(&r->t, 0, &w);
    if (adaslice__is(w, n, "list")) {
        n = adaslice__word(&r->t, 0, &w);
        p->count_type = (unsigned char)adaslice__ply_type(w, n);
        if (p->count_type >= ADASLICE__F32)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line,
                                 "a list length cannot be of type '%s'", adaslice__quote(q, w, n));
        if (p->count_type) n = adaslice__word(&r->t, 0, &w); /* else the type check names it */
    }
    p->type = (unsigned char)adaslice__ply_type(w, n);
    if (!p->type)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "unknown property type '%s'",
                             adaslice__quote(q, w, n));
    n = adaslice__word(&r->t, 0, &w);
    axis = adaslice__is(w, n, "x") ? 1 : adaslice__is(w, n, "y") ? 2 : adaslice__is(w, n, "z") ? 3 : 0;
    p->role = ADASLICE__PLY_OTHER;
    if (axis && e->kind == ADASLICE__PLY_VERTEX) {
        if (p->count_type)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "vertex '%s' is a list",
                                 adaslice__quote(q, w, n));
        p->role = (unsigned char)axis;
    }
    if ((e->kind == ADASLICE__PLY_FACE && adaslice__is(w, n, "vertex_index")) ||
        ((e->kind == ADASLICE__PLY_FACE || e->kind == ADASLICE__PLY_STRIPS) && adaslice__is(w, n, "vertex_indices"))) {
        if (!p->count_type || p->type >= ADASLICE__F32)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "'%s' is not a list of integers",
                                 adaslice__quote(q, w, n));
        p->role = ADASLICE__PLY_INDICES;
    }
    return ADASLICE_OK;
}

static adaslice_result adaslice__ply_header(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    const char *w;
    size_t n = adaslice__word(&r->t, 0, &w);
    unsigned i, k, roles;
    int has_format = 0;
    char q[48];
    adaslice_result res;
    if (!adaslice__is(w, n, "ply")) return adaslice__bad(b, ADASLICE_ERR_FORMAT, 0, 1, "no 'ply' magic");
    for (;;) {
        adaslice__skip_line(&r->t);
        if (r->t.p == r->t.end)
            return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, b->size, r->t.line, "the header has no 'end_header'");
        n = adaslice__word(&r->t, 0, &w);
        res = ADASLICE_OK;
        if (adaslice__is(w, n, "format")) {
            n = adaslice__word(&r->t, 0, &w);
            r->encoding = adaslice__is(w, n, "ascii") ? 0 : adaslice__is(w, n, "binary_little_endian") ? 1
                        : adaslice__is(w, n, "binary_big_endian") ? 2 : -1;
            if (r->encoding < 0)
                return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "unknown format '%s'",
                                     adaslice__quote(q, w, n));
            n = adaslice__word(&r->t, 0, &w);
            if (!adaslice__is(w, n, "1.0"))
                return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, w), r->t.line,
                                     "version '%s' (only 1.0 is read)", adaslice__quote(q, w, n));
            has_format = 1;
        } else if (adaslice__is(w, n, "element")) {
            res = adaslice__ply_element_line(r);
        } else if (adaslice__is(w, n, "property")) {
            res = adaslice__ply_property_line(r);
        } else if (adaslice__is(w, n, "end_header")) {
            break;
        } else if (n && !adaslice__is(w, n, "comment") && !adaslice__is(w, n, "obj_info")) {
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line,
                                 "unknown header keyword '%s'", adaslice__quote(q, w, n));
        }
        if (res) return res;
    }
    if (!has_format)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "the header has no 'format' line");
    if (!r->has_vertex)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "the header has no 'vertex' element");
    for (i = 0; i < r->elem_count; i++) {
        const adaslice__ply_elem *e = &r->elems[i];
        for (roles = 0, k = 0; k < e->props; k++) roles |= 1u << r->props[e->first + k].role;
        if (e->kind == ADASLICE__PLY_VERTEX && (roles & 14u) != 14u)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, e->at, e->line, "element 'vertex' lacks x, y or z");
        if (e->kind > ADASLICE__PLY_VERTEX && !(roles & 16u))
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, e->at, e->line, "element '%s' has no vertex_indices list",
                                 e->name);
    }
    adaslice__skip_line(&r->t);
    return ADASLICE_OK;
}

/* Reads the next value of `type`. ASCII words are parsed only when `out` is wanted, so
   skipped properties cost no strtod. r->at is where the value began. */
static adaslice_result adaslice__ply_value(adaslice__ply_reader *r, const adaslice__ply_elem *e, size_t record,
                                           int type, double *out)
{
    adaslice__build *b = r->b;
    if (!r->encoding) {
        const char *w;
        size_t n = adaslice__word(&r->t, 1, &w);
        long long i;
        char q[48];
        r->at = adaslice__at(b, w);
        if (!n) goto truncated;
        if (!out) return ADASLICE_OK;
        if (type >= ADASLICE__F32) return adaslice__number(b, w, n, r->t.line, out);
        if (adaslice__integer(w, n, &i) != n)
            return adaslice__bad(b, ADASLICE_ERR_NUMBER, r->at, r->t.line, "'%s' is not an integer",
                                 adaslice__quote(q, w, n));
        *out = (double)i;
        return ADASLICE_OK;
    }
    r->at = r->pos;
    if (b->size - r->pos < adaslice__type_size[type]) goto truncated;
    if (out) *out = adaslice__scalar(b->bytes + r->pos, type, r->encoding == 2);
    r->pos += adaslice__type_size[type];
    return ADASLICE_OK;
truncated:
    return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, r->at, adaslice__ply_line(r),
                         "the data ends inside element '%s' (record %zu of %zu)", e->name, record + 1, e->count);
}

/* A list property: vertex indices become triangles (faces as fans, triangle strips
   with -1 restarts and alternating winding); any other list is walked past. */
static adaslice_result adaslice__ply_list(adaslice__ply_reader *r, const adaslice__ply_elem *e, size_t record,
                                          const adaslice__ply_prop *p)
{
    adaslice__build *b = r->b;
    size_t n, j, at, line, left, run = 0, item = r->encoding ? adaslice__type_size[p->type] : 1;
    uint32_t first = 0, prev = 0, prev2 = 0, cur = 0;
    double v;
    char num[24];
    adaslice_result res;
    if ((res = adaslice__ply_value(r, e, record, p->count_type, &v))) return res;
    at = r->at;
    line = adaslice__ply_line(r);
    if (v < 0) return adaslice__bad(b, ADASLICE_ERR_FORMAT, at, line, "list length %g is negative", v);
    left = r->encoding ? b->size - r->pos : (size_t)(r->t.end - r->t.p);
    if (v > (double)(left / item))
        return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, at, line, "a list of %s %s cannot fit in the %zu %s left",
                             adaslice__int_text(num, v), adaslice__noun((size_t)v, "entry", "entries"), left,
                             adaslice__noun(left, "byte", "bytes"));
    n = (size_t)v;
    for (j = 0; j < n; j++) {
        if ((res = adaslice__ply_value(r, e, record, p->type, p->role ? &v : NULL))) return res;
        if (!p->role) continue;
        if (e->kind == ADASLICE__PLY_STRIPS && v == -1) { run = 0; continue; }
        if (!(v >= 0 && v < (double)r->vertices))
            return adaslice__bad(b, ADASLICE_ERR_INDEX, r->at, adaslice__ply_line(r),
                                 "vertex index %s is out of range (%zu %s)", adaslice__int_text(num, v),
                                 r->vertices, adaslice__noun(r->vertices, "vertex", "vertices"));
        cur = (uint32_t)v;
        if (e->kind == ADASLICE__PLY_FACE) {
            if (j == 0) first = cur;
            else if (j >= 2) res = adaslice__triangle(b, first, prev, cur);
        } else if (run >= 2 && prev != prev2 && cur != prev && cur != prev2) {
            /* odd triangles of a strip run backwards; a repeated index joins strips */
            res = run % 2 ? adaslice__triangle(b, prev, prev2, cur) : adaslice__triangle(b, prev2, prev, cur);
        }
        if (res) return res;
        prev2 = prev;
        prev = cur;
        run++;
    }
    if (p->role && e->kind == ADASLICE__PLY_FACE && n < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, at, line, "a face needs at least 3 vertices, this one has %zu", n);
    return ADASLICE_OK;
}

/* Every record of e takes some bytes (in ASCII a character and a separator per
   value), so a count that the `left` bytes from `at` on cannot hold is refused
   before anything is allocated; *least is the bytes a record takes at least. */
static adaslice_result adaslice__ply_fits(adaslice__ply_reader *r, const adaslice__ply_elem *e, size_t at, size_t left,
                                          size_t *least)
{
    unsigned k;
    *least = 0;
    for (k = 0; k < e->props; k++) {
        const adaslice__ply_prop *p = &r->props[e->first + k];
        *least += r->encoding ? adaslice__type_size[p->count_type ? p->count_type : p->type] : 2;
    }
    if (e->count > (left + !r->encoding) / *least)
        return adaslice__bad(r->b, ADASLICE_ERR_TRUNCATED, at, adaslice__ply_line(r),
                             "element '%s' has %zu %s of at least %zu bytes, but only %zu %s", e->name, e->count,
                             adaslice__noun(e->count, "record", "records"), *least, left,
                             adaslice__noun(left, "byte remains", "bytes remain"));
    return ADASLICE_OK;
}

/* The common binary records, read without the general path's value by
   value decoding (a fifth of the turbine blade's load, 200,000 facets): little
   endian, vertices of x, y and z floats only, faces of a one-byte count and
   32-bit indices only. A face that is not a triangle of indices in range, or
   a record that the data cuts off, is left to the general path, which reads
   it the same way and makes the complaint; returns the records read. */
static size_t adaslice__ply_plain(adaslice__ply_reader *r, const adaslice__ply_elem *e, adaslice_result *res)
{
    adaslice__build *b = r->b;
    const adaslice__ply_prop *p = &r->props[e->first];
    uint32_t limit = r->vertices < 0x80000000u ? (uint32_t)r->vertices : 0x80000000u; /* I32's negatives stay out */
    size_t i = 0;
    int k;
    *res = ADASLICE_OK;
    if (r->encoding != 1) return 0;
    if (e->kind == ADASLICE__PLY_VERTEX && e->props == 3) {
        for (k = 0; k < 3; k++)
            if (p[k].count_type || p[k].type != ADASLICE__F32 || p[k].role != ADASLICE__PLY_X + k) return 0;
        for (; i < e->count && b->size - r->pos >= 12; i++) {
            float xyz[3];
            for (k = 0; k < 3; k++) {
                *res = adaslice__coord(b, adaslice__scalar(b->bytes + r->pos, ADASLICE__F32, 0), r->pos, 0, &xyz[k]);
                if (*res != ADASLICE_OK) return i;
                r->pos += 4;
            }
            if ((*res = adaslice__vertex(b, xyz)) != ADASLICE_OK) return i;
        }
        return i;
    }
    if (e->kind != ADASLICE__PLY_FACE || e->props != 1 || p->role != ADASLICE__PLY_INDICES ||
        adaslice__type_size[p->count_type] != 1 || (p->type != ADASLICE__I32 && p->type != ADASLICE__U32))
        return 0;
    for (; i < e->count && b->size - r->pos >= 13; i++) {
        const unsigned char *q = b->bytes + r->pos;
        uint32_t u = (uint32_t)adaslice__bits(q + 1, 4, 0), v = (uint32_t)adaslice__bits(q + 5, 4, 0),
                 w = (uint32_t)adaslice__bits(q + 9, 4, 0);
        if (q[0] != 3 || u >= limit || v >= limit || w >= limit) break;
        if ((*res = adaslice__triangle(b, u, v, w)) != ADASLICE_OK) break;
        r->pos += 13;
    }
    return i;
}

static adaslice_result adaslice__ply_element(adaslice__ply_reader *r, const adaslice__ply_elem *e)
{
    adaslice__build *b = r->b;
    size_t i, least;
    unsigned k;
    adaslice_result res;
    if (!e->props) return ADASLICE_OK; /* no data, however many records it claims */
    res = r->encoding ? adaslice__ply_fits(r, e, r->pos, b->size - r->pos, &least)
                      : adaslice__ply_fits(r, e, adaslice__at(b, r->t.p), (size_t)(r->t.end - r->t.p), &least);
    if (res) return res;
    if (e->kind == ADASLICE__PLY_VERTEX) res = adaslice__reserve(b, e->count, 0);
    else if (e->kind) res = adaslice__reserve(b, 0, b->nt + e->count);
    if (res) return res;
    i = adaslice__ply_plain(r, e, &res);
    if (res) return res;
    for (; i < e->count; i++) {
        float xyz[3] = {0, 0, 0};
        for (k = 0; k < e->props; k++) {
            const adaslice__ply_prop *p = &r->props[e->first + k];
            double v;
            if (p->count_type) {
                res = adaslice__ply_list(r, e, i, p);
            } else if (p->role) {
                res = adaslice__ply_value(r, e, i, p->type, &v);
                if (!res) res = adaslice__coord(b, v, r->at, adaslice__ply_line(r), &xyz[p->role - 1]);
            } else {
                res = adaslice__ply_value(r, e, i, p->type, NULL);
            }
            if (res) return res;
        }
        if (e->kind == ADASLICE__PLY_VERTEX && (res = adaslice__vertex(b, xyz))) return res;
    }
    return ADASLICE_OK;
}

static adaslice_result adaslice__ply(adaslice__build *b)
{
    adaslice__ply_reader r;
    unsigned i;
    adaslice_result res;
    memset(&r, 0, sizeof r);
    r.b = b;
    r.t = adaslice__text_at(b);
    if ((res = adaslice__ply_header(&r))) return res;
    r.pos = adaslice__at(b, r.t.p);
    for (i = 0; i < r.elem_count; i++)
        if ((res = adaslice__ply_element(&r, &r.elems[i]))) return res;
    return ADASLICE_OK;
}

#ifndef ADASLICE_NO_STDIO
/* The counts of data `total` bytes long against its size, from b, its first
   bytes (the file loader's first look), when they hold the whole header: each
   element that starts at a known place, which is every one up to the first with
   records of varying size (a list, or any ASCII record). A header that the
   first bytes cut off is left for the whole read to judge. */
static adaslice_result adaslice__ply_check_start(adaslice__build *b, size_t total)
{
    adaslice__ply_reader r;
    adaslice_error *error = b->err, cut;
    size_t least;
    unsigned i, k;
    adaslice_result res;
    memset(&r, 0, sizeof r);
    r.b = b;
    r.t = adaslice__text_at(b);
    b->err = &cut;
    res = adaslice__ply_header(&r);
    b->err = error;
    if (res || r.t.p == r.t.end) return ADASLICE_OK; /* cut off, or where the data starts is unsure */
    r.pos = adaslice__at(b, r.t.p);
    for (i = 0; i < r.elem_count; i++) {
        const adaslice__ply_elem *e = &r.elems[i];
        if (!e->props) continue;
        if ((res = adaslice__ply_fits(&r, e, r.pos, total - r.pos, &least))) return res;
        for (k = 0; k < e->props && !r.props[e->first + k].count_type; k++) {}
        if (!r.encoding || k < e->props) break;
        r.pos += e->count * least; /* fixed-size binary records: least is their size */
    }
    return ADASLICE_OK;
}
#endif

/* ---- the loaders */

static int adaslice__obj_keyword(const char *w, size_t n)
{
    static const char *const keywords[] = {"v", "vt", "vn", "vp", "f", "l", "p", "g", "o", "s", "usemtl", "mtllib"};
    size_t i;
    for (i = 0; i < sizeof keywords / sizeof *keywords; i++)
        if (adaslice__is(w, n, keywords[i])) return 1;
    return 0;
}

/* adaslice__detect: the first bytes end before the rules can tell */
#define ADASLICE__UNDECIDED (-1)

/* AUTO, for data `total` bytes long of which b holds all or only the first bytes:
   the first rule that matches wins; ADASLICE_FORMAT_AUTO when none does. A
   binary STL header may start with "solid", so the exact size is tested first;
   text holds no NUL, so the text rules read up to the first one (a binary
   header's count is seldom without one). */
static int adaslice__detect(const adaslice__build *b, size_t total)
{
    adaslice__text text = adaslice__text_at(b), t;
    const char *w, *nul = ADASLICE__CAST(const char *, memchr(b->text, 0, b->size));
    size_t n;
    int open = !nul && b->size < total; /* text rules that read to the end of b need more */
    if (b->size >= 4 && memcmp(b->text, "ply", 3) == 0 && (b->text[3] == '\n' || adaslice__blank(b->text[3])))
        return ADASLICE_FORMAT_PLY;
    if (total >= 84 && (total - 84) % 50 == 0 &&
        (double)((total - 84) / 50) == adaslice__scalar(b->bytes + 80, ADASLICE__U32, 0))
        return ADASLICE_FORMAT_STL_BINARY;
    if (nul) text.end = nul;
    t = text;
    n = adaslice__word(&t, 1, &w);
    if (open && t.p == t.end) return ADASLICE__UNDECIDED;
    if (adaslice__is(w, n, "solid")) {
        adaslice__skip_line(&t);
        n = adaslice__word(&t, 1, &w);
        if (open && t.p == t.end) return ADASLICE__UNDECIDED;
        if (adaslice__is(w, n, "facet") || adaslice__is(w, n, "endsolid")) return ADASLICE_FORMAT_STL_ASCII;
    }
    t = text;
    while ((n = adaslice__word(&t, 1, &w)) && w[0] == '#') adaslice__skip_line(&t);
    if (open && t.p == t.end) return ADASLICE__UNDECIDED;
    if (adaslice__obj_keyword(w, n)) return ADASLICE_FORMAT_OBJ;
    return total >= 84 ? ADASLICE_FORMAT_STL_BINARY : ADASLICE_FORMAT_AUTO;
}

/* What a load and the file loader's first look share: b over `data`, all of the
   data or its first `size` of `total` bytes, and *format, detected when the
   options say AUTO (ADASLICE__UNDECIDED when the first bytes cannot tell). */
static adaslice_result adaslice__begin(adaslice__build *b, const void *data, size_t size, size_t total,
                                       const adaslice_load_options *options, adaslice_error *error, int *format)
{
    static const char *const names[] = {"", "binary STL", "ASCII STL", "OBJ", "PLY"};
    adaslice__text t;
    const char *w;
    memset(b, 0, sizeof *b);
    if (!data && size) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "data is NULL, size %zu", size);
    if (!data) data = ""; /* so that no pointer arithmetic touches NULL */
    b->text = ADASLICE__CAST(const char *, data);
    b->bytes = ADASLICE__CAST(const unsigned char *, data);
    b->size = size;
    b->err = error;
    b->scale = options && options->scale != 0 ? options->scale : 1;
    b->a = adaslice__allocator(options ? options->allocator : NULL);
    if (!(b->scale > 0 && b->scale <= DBL_MAX))
        return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "scale %g is not positive and finite", b->scale);
    *format = options ? (int)options->format : (int)ADASLICE_FORMAT_AUTO;
    if (*format == ADASLICE_FORMAT_AUTO) {
        t = adaslice__text_at(b);
        if (adaslice__word(&t, 1, &w)) *format = adaslice__detect(b, total);
        else if (size < total) *format = ADASLICE__UNDECIDED; /* blank so far */
        else return adaslice__fail(error, ADASLICE_ERR_EMPTY, 0, 0, "the data is empty");
        if (*format == ADASLICE_FORMAT_AUTO)
            return adaslice__fail(error, ADASLICE_ERR_FORMAT, 0, 0,
                                  "not a mesh: no 'ply' magic, STL 'solid ... facet' or OBJ statement, "
                                  "and %zu %s too short for binary STL", total,
                                  adaslice__noun(total, "byte is", "bytes is"));
    }
    if (*format == ADASLICE__UNDECIDED) return ADASLICE_OK;
    if (*format < ADASLICE_FORMAT_STL_BINARY || *format > ADASLICE_FORMAT_PLY)
        return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "unknown format %d", *format);
    b->name = names[*format];
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_mesh_load(const void *data, size_t size, const adaslice_load_options *options,
                                                adaslice_mesh *mesh, adaslice_error *error)
{
    adaslice__build b;
    int format;
    adaslice_result r;
    adaslice__ok(error);
    if (!mesh) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "mesh is NULL");
    memset(mesh, 0, sizeof *mesh);
    if ((r = adaslice__begin(&b, data, size, size, options, error, &format))) return r;
    switch (format) {
    case ADASLICE_FORMAT_STL_BINARY: r = adaslice__stl_binary(&b); break;
    case ADASLICE_FORMAT_STL_ASCII: r = adaslice__stl_ascii(&b); break;
    case ADASLICE_FORMAT_OBJ: r = adaslice__obj(&b); break;
    default: r = adaslice__ply(&b); break;
    }
    if (!r) r = adaslice__finish(&b, mesh);
    if (r) {
        adaslice__free(&b.a, b.v);
        adaslice__free(&b.a, b.t);
        return r;
    }
    mesh->format = (adaslice_format)format;
    return ADASLICE_OK;
}

#ifndef ADASLICE_NO_STDIO
#include <errno.h>

/* The file loader's first look: a binary STL's count and a PLY header are
   checked against the file's size before the rest is read. */
#define ADASLICE__FILE_START 4096

/* What the first `size` bytes of a file `total` bytes long show to be wrong. */
static adaslice_result adaslice__check_start(const unsigned char *start, size_t size, size_t total,
                                             const adaslice_load_options *options, adaslice_error *error)
{
    adaslice__build b;
    size_t count;
    int format;
    adaslice_result r = adaslice__begin(&b, start, size, total, options, error, &format);
    if (r) return r;
    if (format == ADASLICE_FORMAT_STL_BINARY) return adaslice__stl_count(&b, total, &count);
    if (format == ADASLICE_FORMAT_PLY) return adaslice__ply_check_start(&b, total);
    return ADASLICE_OK;
}

/* The first bytes are checked against the size before the rest is read, so that
   a wrong count in a huge file fails at once, not after reading it all. */
ADASLICE_DEF adaslice_result adaslice_mesh_load_file(const char *path, const adaslice_load_options *options,
                                                     adaslice_mesh *mesh, adaslice_error *error)
{
    adaslice_allocator a = adaslice__allocator(options ? options->allocator : NULL);
    adaslice_result r;
    unsigned char start[ADASLICE__FILE_START], *data = NULL;
    size_t first = 0;
    long size = -1;
    int judged = 0; /* r is the loader's, whose message lacks the path */
    FILE *f;
    char why[320];
    if (mesh) memset(mesh, 0, sizeof *mesh);
    if (!path) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "path is NULL");
    if (!(f = fopen(path, "rb")))
        return adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot open: %s", path, strerror(errno));
    /* a directory opens on some systems and fails only when read */
    if (getc(f) == EOF && ferror(f)) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot read: %s", path, strerror(errno));
        fclose(f);
        return r;
    }
    if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size >= 0) first = (size_t)size < sizeof start ? (size_t)size : sizeof start;
    if (size < 0 || size == LONG_MAX || fseek(f, 0, SEEK_SET) != 0) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot find the size: %s", path, strerror(errno));
    } else if (fread(start, 1, first, f) != first) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot read", path);
    } else if ((r = adaslice__check_start(start, first, (size_t)size, options, error)) != ADASLICE_OK) {
        judged = 1;
    } else if (!(data = ADASLICE__CAST(unsigned char *, adaslice__alloc(&a, (size_t)size, 1)))) {
        r = adaslice__fail(error, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu bytes", path, (size_t)size);
    } else if (memcpy(data, start, first), fread(data + first, 1, (size_t)size - first, f) != (size_t)size - first) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot read", path);
    } else {
        r = adaslice_mesh_load(data, (size_t)size, options, mesh, error);
        judged = 1;
    }
    if (r && judged && error) {
        memcpy(why, error->message, sizeof why);
        adaslice__fail(error, r, error->offset, error->line, "%s: %s", path, why);
    }
    fclose(f);
    adaslice__free(&a, data);
    return r;
}
#endif
#endif /* ADASLICE_NO_LOADERS */

ADASLICE_DEF void adaslice_mesh_free(adaslice_mesh *mesh)
{
    if (!mesh) return;
    adaslice__free(&mesh->allocator, mesh->vertices);
    adaslice__free(&mesh->allocator, mesh->triangles);
    memset(mesh, 0, sizeof *mesh);
}

/* l, h grown to take p: branch-free min and max */
static void adaslice__box_grow(const float *p, float l[3], float h[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        l[k] = p[k] < l[k] ? p[k] : l[k];
        h[k] = p[k] > h[k] ? p[k] : h[k];
    }
}

/* Which of the vertices at[0..5] the n corners c use, as bits 0..5. */
static unsigned adaslice__corners_at(const uint32_t *c, size_t n, const uint32_t at[6])
{
    const uint32_t a0 = at[0], a1 = at[1], a2 = at[2], a3 = at[3], a4 = at[4], a5 = at[5];
    unsigned s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0;
    size_t j;
    for (j = 0; j < n; j++) {
        s0 |= c[j] == a0; s1 |= c[j] == a1; s2 |= c[j] == a2;
        s3 |= c[j] == a3; s4 |= c[j] == a4; s5 |= c[j] == a5;
    }
    return s0 | s1 << 1 | s2 << 2 | s3 << 3 | s4 << 4 | s5 << 5;
}

ADASLICE_DEF void adaslice_mesh_bounds(const adaslice_mesh *mesh, double lo[3], double hi[3])
{
    /* in floats, as the slicer takes the bounds several times a job. The
       box of every vertex, read in order, is the box of those the triangles
       use when the vertices that reach its six faces are used, which one
       pass over the corners' numbers (in order too) finds; only a stray
       vertex out there sends it to the corners one by one, each a load from
       anywhere. A zero comes out +0, whichever zero came first. */
    float l[3] = {0, 0, 0}, h[3] = {0, 0, 0};
    uint32_t at[6] = {0, 0, 0, 0, 0, 0}; /* the first vertex on each face: low x, y, z, high x, y, z */
    size_t i, v, corners = 3 * mesh->triangle_count;
    unsigned seen = 0;
    int k;
    if (corners && mesh->vertex_count) {
        for (k = 0; k < 3; k++) l[k] = h[k] = mesh->vertices[k];
        for (v = 1; v < mesh->vertex_count; v++)
            for (k = 0; k < 3; k++) {
                float q = mesh->vertices[3 * v + (size_t)k];
                if (q < l[k]) { l[k] = q; at[k] = (uint32_t)v; }
                if (q > h[k]) { h[k] = q; at[3 + k] = (uint32_t)v; }
            }
        /* a whole block's count fixed, so that compilers compare in vectors */
        for (i = 0; i + 4096 <= corners && seen != 63; i += 4096) seen |= adaslice__corners_at(mesh->triangles + i, 4096, at);
        if (seen != 63) seen |= adaslice__corners_at(mesh->triangles + i, corners - i, at);
    }
    if (corners && seen != 63) {
        for (k = 0; k < 3; k++) l[k] = h[k] = mesh->vertices[3 * (size_t)mesh->triangles[0] + k];
        for (i = 1; i < corners; i++) adaslice__box_grow(mesh->vertices + 3 * (size_t)mesh->triangles[i], l, h);
    }
    for (k = 0; k < 3; k++) { lo[k] = l[k] + 0.0; hi[k] = h[k] + 0.0; }
}

/* The diagonal of the mesh's box: the weld's scale, and past 1e15 mm the
   size at which a turned copy in floats overflows. */
static double adaslice__diagonal(const adaslice_mesh *mesh)
{
    double lo[3], hi[3], d = 0;
    int k;
    adaslice_mesh_bounds(mesh, lo, hi);
    for (k = 0; k < 3; k++) d += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d);
}

/* ---- welding */
#define ADASLICE__NONE 0xffffffffu

/* Murmur3's finaliser: every input bit moves every output bit. */
static uint64_t adaslice__mix(uint64_t h)
{
    h ^= h >> 33; h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull;
    return h ^ (h >> 33);
}

/* A power of two at least 2n (load at most 1/2), and at least 16. */
static size_t adaslice__table_size(size_t n)
{
    size_t c = 16;
    while (c / 2 < n && c <= SIZE_MAX / 4) c *= 2;
    return c;
}

/* The bits of a coordinate with -0 folded onto +0. */
static uint32_t adaslice__float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u == 0x80000000u ? 0 : u;
}

static int adaslice__same_vertex(const float *a, const float *b)
{
    return adaslice__float_bits(a[0]) == adaslice__float_bits(b[0]) &&
           adaslice__float_bits(a[1]) == adaslice__float_bits(b[1]) &&
           adaslice__float_bits(a[2]) == adaslice__float_bits(b[2]);
}


/* Kept vertices sit in a hash table by their cell of the tolerance grid; a slot
   names the cell's most recent kept vertex, and next[] links it to the cell's
   earlier ones. A cell is recognised by recomputing its vertex's cell. */
typedef struct adaslice__weld {
    const float *kept;          /* positions of the kept vertices */
    double inverse;             /* 1 / tolerance */
    double tolerance2;
    uint32_t *slot, *next;
    size_t cap;
} adaslice__weld;

static void adaslice__weld_cell(const adaslice__weld *w, const float *p, int64_t c[3])
{
    int k;
    for (k = 0; k < 3; k++) c[k] = (int64_t)floor((double)p[k] * w->inverse);
}

/* The slot of cell c: the one naming it, or the empty one where it would go. */
static size_t adaslice__weld_slot(const adaslice__weld *w, const int64_t c[3])
{
    uint64_t key = adaslice__mix((uint64_t)c[0] ^ adaslice__mix((uint64_t)c[1] ^ adaslice__mix((uint64_t)c[2])));
    size_t h = (size_t)key & (w->cap - 1);
    while (w->slot[h] != ADASLICE__NONE) {
        int64_t d[3];
        adaslice__weld_cell(w, w->kept + 3 * (size_t)w->slot[h], d);
        if (d[0] == c[0] && d[1] == c[1] && d[2] == c[2]) break;
        h = (h + 1) & (w->cap - 1);
    }
    return h;
}

/* The lowest kept index within the tolerance of p, or NONE. */
static uint32_t adaslice__weld_find(const adaslice__weld *w, const float *p)
{
    uint32_t best = ADASLICE__NONE, k;
    int64_t c[3], d[3];
    int i;
    adaslice__weld_cell(w, p, c);
    for (i = 0; i < 27; i++) {
        d[0] = c[0] + i % 3 - 1; d[1] = c[1] + i / 3 % 3 - 1; d[2] = c[2] + i / 9 - 1;
        for (k = w->slot[adaslice__weld_slot(w, d)]; k != ADASLICE__NONE; k = w->next[k]) {
            const float *q = w->kept + 3 * (size_t)k;
            double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
            if (k < best && dx * dx + dy * dy + dz * dz <= w->tolerance2) best = k;
        }
    }
    return best;
}

/* remap[i] = the index vertex i merges into; the kept vertices are written to
   out in order of first occurrence (out may be v itself: a vertex only ever
   moves down to an index already read). */
static adaslice_result adaslice__weld_map(const float *v, size_t n, double tolerance, const adaslice_allocator *al,
                                          float *out, uint32_t *remap, size_t *kept_count, adaslice_error *err)
{
    adaslice__weld w;
    uint32_t kept = 0;
    size_t i, k;
    double reach = 0;
    if (tolerance > 0) {
        for (i = 0; i < 3 * n; i++) if (fabs((double)v[i]) > reach) reach = fabs((double)v[i]);
        /* cells must be exact integers with room for their neighbours */
        if (reach / tolerance > 4.0e15)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "weld: tolerance %g is too small for coordinates as large as %g (0 welds equal "
                                  "coordinates only)", tolerance, reach);
    }
    memset(&w, 0, sizeof w);
    w.cap = adaslice__table_size(n);
    w.kept = out;
    w.inverse = tolerance > 0 ? 1.0 / tolerance : 0;
    w.tolerance2 = tolerance * tolerance;
    w.slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, w.cap, sizeof(uint32_t)));
    if (tolerance > 0) w.next = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    if (!w.slot || (tolerance > 0 && !w.next)) {
        adaslice__free(al, w.slot);
        adaslice__free(al, w.next);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "weld: out of memory for %zu vertices", n);
    }
    memset(w.slot, 0xff, w.cap * sizeof(uint32_t));
    for (i = 0; i < n; i++) {
        const float *p = v + 3 * i;
        uint32_t to;
        if (tolerance > 0) {
            to = adaslice__weld_find(&w, p);
            if (to == ADASLICE__NONE) {
                int64_t c[3];
                memmove(out + 3 * (size_t)kept, p, 3 * sizeof(float));
                adaslice__weld_cell(&w, out + 3 * (size_t)kept, c);
                k = adaslice__weld_slot(&w, c);
                w.next[kept] = w.slot[k];
                w.slot[k] = to = kept++;
            }
        } else {
            uint64_t key = (uint64_t)adaslice__float_bits(p[0]) << 32 | adaslice__float_bits(p[1]);
            k = (size_t)adaslice__mix(key ^ adaslice__mix(adaslice__float_bits(p[2]) + 1u)) & (w.cap - 1);
            while (w.slot[k] != ADASLICE__NONE && !adaslice__same_vertex(out + 3 * (size_t)w.slot[k], p))
                k = (k + 1) & (w.cap - 1);
            if (w.slot[k] == ADASLICE__NONE) {
                memmove(out + 3 * (size_t)kept, p, 3 * sizeof(float));
                w.slot[k] = kept++;
            }
            to = w.slot[k];
        }
        remap[i] = to;
    }
    adaslice__free(al, w.slot);
    adaslice__free(al, w.next);
    *kept_count = kept;
    return ADASLICE_OK;
}

/* The checks every mesh input here shares; `who` starts the messages. */
static adaslice_result adaslice__mesh_check(const adaslice_mesh *mesh, const char *who, adaslice_error *err)
{
    size_t i;
    if (!mesh || (mesh->vertex_count && !mesh->vertices) || (mesh->triangle_count && !mesh->triangles))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "%s: no mesh given", who);
    if ((uint64_t)mesh->vertex_count >= ADASLICE__NONE)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "%s: %zu vertices is too many", who, mesh->vertex_count);
    for (i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->triangles[i] >= mesh->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "%s: triangle %zu uses vertex %u of %zu", who,
                                  i / 3, (unsigned)mesh->triangles[i], mesh->vertex_count);
    return ADASLICE_OK;
}

static adaslice_result adaslice__tolerance_check(double tolerance, const char *who, adaslice_error *err)
{
    if (!(tolerance >= 0) || tolerance > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "%s: weld tolerance %g is not a finite number >= 0",
                              who, tolerance);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_mesh_weld(adaslice_mesh *mesh, const adaslice_weld_options *options,
                                                adaslice_error *err)
{
    adaslice_allocator al;
    adaslice_result r;
    uint32_t *remap;
    double tolerance = options ? options->tolerance : 0;
    size_t i, kept = 0;
    if ((r = adaslice__mesh_check(mesh, "weld", err)) != ADASLICE_OK ||
        (r = adaslice__tolerance_check(tolerance, "weld", err)) != ADASLICE_OK)
        return r;
    al = adaslice__allocator(options ? options->allocator : NULL);
    remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, mesh->vertex_count, sizeof(uint32_t)));
    if (!remap)
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "weld: out of memory for %zu vertices", mesh->vertex_count);
    r = adaslice__weld_map(mesh->vertices, mesh->vertex_count, tolerance, &al, mesh->vertices, remap, &kept, err);
    if (r == ADASLICE_OK) {
        for (i = 0; i < 3 * mesh->triangle_count; i++) mesh->triangles[i] = remap[mesh->triangles[i]];
        mesh->vertex_count = kept;
        adaslice__ok(err);
    }
    adaslice__free(&al, remap);
    return r;
}

/* ---- repair */
/* Half-edge h = 3t + k runs from corner k of triangle t to corner k + 1. An
   edge is every half-edge joining the same two vertices, either way; a closed
   surface wound one way uses each of its edges once each way. */
static uint32_t adaslice__he_to(const uint32_t *tri, size_t h) { return tri[h % 3 == 2 ? h - 2 : h + 1]; }

/* Half-edges grouped by edge: slot[0 .. cap) names one half-edge of each
   edge, next[] links the rest. They are found by bucketing the half-edges by
   their lower-numbered vertex (a counting sort) and matching the few in each
   bucket by the other vertex, which keeps to arrays walked in order rather
   than a hash table's random probes. Zero-area facets, which every stage
   skips, are left out (`with_area`: the caller knows there are none). */
typedef struct adaslice__edges {
    uint32_t *slot, *next;
    size_t cap;
} adaslice__edges;

static void adaslice__edges_free(const adaslice_allocator *al, adaslice__edges *e)
{
    adaslice__free(al, e->slot);
    adaslice__free(al, e->next);
    memset(e, 0, sizeof *e);
}

static int adaslice__u64_cmp(const void *a, const void *b)
{
    uint64_t x = *ADASLICE__CAST(const uint64_t *, a), y = *ADASLICE__CAST(const uint64_t *, b);
    return x < y ? -1 : x > y;
}

static uint32_t adaslice__he_low(const uint32_t *tri, size_t h)
{
    uint32_t a = tri[h], b = adaslice__he_to(tri, h);
    return a < b ? a : b;
}

static uint32_t adaslice__he_high(const uint32_t *tri, size_t h)
{
    uint32_t a = tri[h], b = adaslice__he_to(tri, h);
    return a < b ? b : a;
}

static adaslice_result adaslice__edges_build(const adaslice_mesh *m, int with_area, const adaslice_allocator *al,
                                             adaslice__edges *e, adaslice_error *err)
{
    const uint32_t *tri = m->triangles;
    size_t n = 3 * m->triangle_count, nv = m->vertex_count, h, v, i, j, used = 0;
    uint32_t *first = NULL, *order = NULL;
    uint64_t *keys = NULL;
    size_t keys_cap = 0;
    adaslice_result r = ADASLICE_OK;
    memset(e, 0, sizeof *e);
    if (m->triangle_count >= ADASLICE__NONE / 3)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "edges: %zu triangles is too many", m->triangle_count);
    e->slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n ? n : 1, sizeof(uint32_t)));
    e->next = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n ? n : 1, sizeof(uint32_t)));
    first = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, nv + 1, sizeof(uint32_t)));
    order = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n ? n : 1, sizeof(uint32_t)));
    if (!e->slot || !e->next || !first || !order) goto nomem;
    memset(first, 0, (nv + 1) * sizeof(uint32_t));
    memset(e->next, 0xff, n * sizeof(uint32_t));
    for (h = 0; h < n; h += 3) {
        int k;
        if (!with_area && adaslice__zero_area(m->vertices, tri + h)) continue;
        for (k = 0; k < 3; k++) first[adaslice__he_low(tri, h + (size_t)k) + 1]++;
    }
    for (v = 0; v < nv; v++) first[v + 1] += first[v];
    for (h = 0; h < n; h += 3) {
        int k;
        if (!with_area && adaslice__zero_area(m->vertices, tri + h)) continue;
        for (k = 0; k < 3; k++) order[first[adaslice__he_low(tri, h + (size_t)k)]++] = (uint32_t)(h + (size_t)k);
    }
    for (v = nv; v > 0; v--) first[v] = first[v - 1];
    first[0] = 0;
    for (v = 0; v < nv; v++) {
        uint32_t *b = order + first[v];
        size_t k = first[v + 1] - first[v];
        if (k > 16) {
            /* a vertex of many facets (a fan's centre): sort its bucket by the other vertex */
            if (k > keys_cap) {
                adaslice__free(al, keys);
                keys_cap = 2 * k;
                keys = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, keys_cap, sizeof(uint64_t)));
                if (!keys) goto nomem;
            }
            for (i = 0; i < k; i++) keys[i] = (uint64_t)adaslice__he_high(tri, b[i]) << 32 | b[i];
            qsort(keys, k, sizeof *keys, adaslice__u64_cmp);
            for (i = 0; i < k; i++) b[i] = (uint32_t)keys[i];
            for (i = 0; i < k; i = j) {
                uint32_t hi = adaslice__he_high(tri, b[i]);
                e->slot[used++] = b[i];
                for (j = i + 1; j < k && adaslice__he_high(tri, b[j]) == hi; j++) e->next[b[j - 1]] = b[j];
            }
            continue;
        }
        for (i = 0; i < k; i++) {
            uint32_t hi, tail;
            if (b[i] == ADASLICE__NONE) continue; /* joined an earlier edge */
            hi = adaslice__he_high(tri, b[i]);
            e->slot[used++] = tail = b[i];
            for (j = i + 1; j < k; j++)
                if (b[j] != ADASLICE__NONE && adaslice__he_high(tri, b[j]) == hi) {
                    e->next[tail] = b[j];
                    tail = b[j];
                    b[j] = ADASLICE__NONE;
                }
        }
    }
    e->cap = used;
    goto done;
nomem:
    adaslice__edges_free(al, e);
    r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "edges: out of memory for %zu triangles", m->triangle_count);
done:
    adaslice__free(al, first);
    adaslice__free(al, order);
    adaslice__free(al, keys);
    return r;
}

/* The facets using an edge, and how many more run from its lower-numbered
   vertex to its higher than back: 0 on a closed surface wound one way. */
static void adaslice__edge_uses(const uint32_t *tri, const adaslice__edges *e, uint32_t first, size_t *uses, long *net)
{
    uint32_t h;
    *uses = 0;
    *net = 0;
    for (h = first; h != ADASLICE__NONE; h = e->next[h]) {
        ++*uses;
        *net += tri[h] < adaslice__he_to(tri, h) ? 1 : -1;
    }
}

/* Drops zero-area facets in place, keeping the order of the rest. */
static size_t adaslice__drop_degenerate(adaslice_mesh *m)
{
    size_t t, kept = 0;
    for (t = 0; t < m->triangle_count; t++) {
        if (adaslice__zero_area(m->vertices, m->triangles + 3 * t)) continue;
        memmove(m->triangles + 3 * kept++, m->triangles + 3 * t, 3 * sizeof(uint32_t));
    }
    t = m->triangle_count - kept;
    m->triangle_count = kept;
    return t;
}

/* A half-edge (sliver 0) or a sliver's long edge (sliver 1: `what` is the
   facet), keyed by its two vertices, lower first. */
typedef struct adaslice__edge_key {
    uint64_t key;
    uint32_t what, sliver;
} adaslice__edge_key;

static int adaslice__edge_key_cmp(const void *a, const void *b)
{
    const adaslice__edge_key *x = ADASLICE__CAST(const adaslice__edge_key *, a), *y = ADASLICE__CAST(const adaslice__edge_key *, b);
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    if (x->sliver != y->sliver) return x->sliver < y->sliver ? -1 : 1;
    return x->what < y->what ? -1 : x->what > y->what;
}

static double adaslice__dist2(const float *v, uint32_t a, uint32_t b)
{
    double d = 0;
    int k;
    for (k = 0; k < 3; k++) {
        double x = (double)v[3 * (size_t)a + (size_t)k] - v[3 * (size_t)b + (size_t)k];
        d += x * x;
    }
    return d;
}

#define ADASLICE__SLIVER_PASSES 16 /* slivers stacked on one edge deeper than this are dropped */

/* Collapses zero-area facets with three distinct corners on a line onto
   their long edge: where exactly one facet with area is across that edge,
   it is split at the sliver's middle corner and its second half takes the
   sliver's place, so the edges the sliver sealed stay shared. Slivers stacked
   on a sliver wait for the next pass (each pass sorts the edges once). */
static adaslice_result adaslice__collapse_slivers(adaslice_mesh *m, const adaslice_allocator *al, size_t *collapsed,
                                                  adaslice_error *err)
{
    uint32_t *tri = m->triangles;
    size_t nt = m->triangle_count, t, n, i, j, done;
    adaslice__edge_key *keys = NULL;
    unsigned char *split = NULL;
    int pass;
    *collapsed = 0;
    for (pass = 0; pass < ADASLICE__SLIVER_PASSES; pass++) {
        for (t = 0; t < nt; t++) {
            const uint32_t *c = tri + 3 * t;
            if (c[0] != c[1] && c[1] != c[2] && c[0] != c[2] && adaslice__zero_area(m->vertices, c)) break;
        }
        if (t == nt) break; /* no sliver left */
        if (!keys) {
            keys = ADASLICE__CAST(adaslice__edge_key *, adaslice__alloc(al, 3 * nt, sizeof *keys));
            split = ADASLICE__CAST(unsigned char *, adaslice__alloc(al, nt, 1));
            if (!keys || !split) {
                adaslice__free(al, keys);
                adaslice__free(al, split);
                return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for %zu facets", nt);
            }
        }
        n = 0;
        for (t = 0; t < nt; t++) {
            const uint32_t *c = tri + 3 * t;
            int k, far = 0;
            if (!adaslice__zero_area(m->vertices, c)) {
                for (k = 0; k < 3; k++) {
                    uint32_t a = c[k], b = c[(k + 1) % 3];
                    keys[n].key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
                    keys[n].what = (uint32_t)(3 * t + (size_t)k);
                    keys[n++].sliver = 0;
                }
                continue;
            }
            if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
            /* the long edge is the one opposite the middle corner */
            for (k = 1; k < 3; k++)
                if (adaslice__dist2(m->vertices, c[(k + 1) % 3], c[(k + 2) % 3]) >
                    adaslice__dist2(m->vertices, c[(far + 1) % 3], c[(far + 2) % 3]))
                    far = k;
            {
                uint32_t a = c[(far + 1) % 3], b = c[(far + 2) % 3];
                keys[n].key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
                keys[n].what = (uint32_t)t;
                keys[n++].sliver = 1;
            }
        }
        qsort(keys, n, sizeof *keys, adaslice__edge_key_cmp);
        memset(split, 0, nt);
        done = 0;
        for (i = 0; i < n; i = j) {
            uint32_t h, f, s, p, q, r, mid;
            for (j = i + 1; j < n && keys[j].key == keys[i].key; j++) {}
            /* one facet with area and one sliver: sorted, the facet first */
            if (j - i != 2 || keys[i].sliver || !keys[i + 1].sliver) continue;
            h = keys[i].what;
            f = h / 3;
            s = keys[i + 1].what;
            if (split[f] || split[s]) continue;
            p = tri[h];
            q = adaslice__he_to(tri, h);
            r = tri[3 * f + (h % 3 + 2) % 3];
            mid = tri[3 * s] != p && tri[3 * s] != q ? tri[3 * s]
                : tri[3 * s + 1] != p && tri[3 * s + 1] != q ? tri[3 * s + 1] : tri[3 * s + 2];
            tri[3 * f] = p; tri[3 * f + 1] = mid; tri[3 * f + 2] = r;
            tri[3 * s] = mid; tri[3 * s + 1] = q; tri[3 * s + 2] = r;
            split[f] = split[s] = 1;
            done++;
        }
        *collapsed += done;
        if (!done) break;
    }
    adaslice__free(al, keys);
    adaslice__free(al, split);
    return ADASLICE_OK;
}

/* Welds the vertices of the open edges of e within `tolerance` of each
   other (0: 1e-4 of the diagonal of the facets' box, taken only when there
   are open edges); the lowest index stays, as adaslice_mesh_weld does.
   *merged counts the moved. */
static adaslice_result adaslice__weld_open(adaslice_mesh *m, const adaslice__edges *e, double tolerance,
                                           const adaslice_allocator *al, size_t *merged, adaslice_error *err)
{
    adaslice_result r;
    uint32_t *index = NULL, *remap = NULL, *first = NULL;
    float *pos = NULL, *kept_pos = NULL;
    size_t i, n = 0, kept = 0;
    *merged = 0;
    /* index[v]: v's place among the open-edge vertices, or NONE */
    index = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, m->vertex_count, sizeof(uint32_t)));
    if (!index) goto nomem;
    memset(index, 0xff, m->vertex_count * sizeof(uint32_t));
    for (i = 0; i < e->cap; i++) {
        uint32_t h = e->slot[i];
        if (h == ADASLICE__NONE || e->next[h] != ADASLICE__NONE) continue;
        index[m->triangles[h]] = index[adaslice__he_to(m->triangles, h)] = 0;
    }
    for (i = 0; i < m->vertex_count; i++) if (index[i] == 0) index[i] = (uint32_t)n++;
    if (n > 1 && tolerance == 0) tolerance = 1e-4 * adaslice__diagonal(m);
    if (n > 1 && tolerance > 0) {
        pos = ADASLICE__CAST(float *, adaslice__alloc(al, n, 3 * sizeof(float)));
        kept_pos = ADASLICE__CAST(float *, adaslice__alloc(al, n, 3 * sizeof(float)));
        remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
        first = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
        if (!pos || !kept_pos || !remap || !first) goto nomem;
        for (i = 0; i < m->vertex_count; i++)
            if (index[i] != ADASLICE__NONE) memcpy(pos + 3 * (size_t)index[i], m->vertices + 3 * i, 3 * sizeof(float));
        if ((r = adaslice__weld_map(pos, n, tolerance, al, kept_pos, remap, &kept, err)) != ADASLICE_OK) goto done;
        /* first[k]: the vertex that kept place k (the first to reach it) */
        memset(first, 0xff, n * sizeof(uint32_t));
        for (i = 0; i < m->vertex_count; i++)
            if (index[i] != ADASLICE__NONE && first[remap[index[i]]] == ADASLICE__NONE) first[remap[index[i]]] = (uint32_t)i;
        for (i = 0; i < 3 * m->triangle_count; i++) {
            uint32_t v = m->triangles[i];
            if (index[v] != ADASLICE__NONE) m->triangles[i] = first[remap[index[v]]];
        }
        *merged = n - kept;
    }
    r = ADASLICE_OK;
    goto done;
nomem:
    r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for %zu vertices", m->vertex_count);
done:
    adaslice__free(al, index);
    adaslice__free(al, pos);
    adaslice__free(al, kept_pos);
    adaslice__free(al, remap);
    adaslice__free(al, first);
    return r;
}

/* Drops the vertices no facet uses, keeping the order of the rest. */
static adaslice_result adaslice__drop_unused(adaslice_mesh *m, const adaslice_allocator *al, adaslice_error *err)
{
    uint32_t *to = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, m->vertex_count, sizeof(uint32_t)));
    size_t i, kept = 0;
    if (!to) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for %zu vertices", m->vertex_count);
    memset(to, 0xff, m->vertex_count * sizeof(uint32_t));
    for (i = 0; i < 3 * m->triangle_count; i++) to[m->triangles[i]] = 0;
    for (i = 0; i < m->vertex_count; i++) {
        if (to[i] == ADASLICE__NONE) continue;
        memmove(m->vertices + 3 * kept, m->vertices + 3 * i, 3 * sizeof(float));
        to[i] = (uint32_t)kept++;
    }
    for (i = 0; i < 3 * m->triangle_count; i++) m->triangles[i] = to[m->triangles[i]];
    m->vertex_count = kept;
    adaslice__free(al, to);
    return ADASLICE_OK;
}

/* Corner k of facet t as doubles. */
static void adaslice__corner(const adaslice_mesh *m, size_t t, int k, double p[3])
{
    const float *v = m->vertices + 3 * (size_t)m->triangles[3 * t + k];
    p[0] = v[0]; p[1] = v[1]; p[2] = v[2];
}

static void adaslice__normal(const double a[3], const double b[3], const double c[3], double n[3])
{
    double u[3], w[3];
    int k;
    for (k = 0; k < 3; k++) { u[k] = b[k] - a[k]; w[k] = c[k] - a[k]; }
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* Which side of the directed xy line a -> b (vertex indices) the point p
   lies on, positive on the left. The line is evaluated from its lower
   numbered end whichever way it is asked, and a point on it goes to the side
   the point moved by (e, e^2) would be on, so the facets on either side of an
   edge never both claim a point. */
static int adaslice__side(const adaslice_mesh *m, uint32_t a, uint32_t b, const double p[2])
{
    int flip = a > b;
    const float *u = m->vertices + 3 * (size_t)(flip ? b : a), *w = m->vertices + 3 * (size_t)(flip ? a : b);
    double dx = (double)w[0] - u[0], dy = (double)w[1] - u[1];
    double s = dx * (p[1] - u[1]) - dy * (p[0] - u[0]);
    if (s == 0) s = dy != 0 ? -dy : dx;
    return (s > 0) != flip ? 1 : -1;
}

/* Whether the z ray up from p crosses facet t. */
static int adaslice__ray_crosses(const adaslice_mesh *m, size_t t, const double p[3])
{
    const uint32_t *c = m->triangles + 3 * t;
    double a[3], b[3], d[3], area, la, lb, lc, z;
    int s0, s1, s2;
    adaslice__corner(m, t, 0, a);
    adaslice__corner(m, t, 1, b);
    adaslice__corner(m, t, 2, d);
    area = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
    if (area == 0) return 0; /* seen edge-on */
    s0 = adaslice__side(m, c[0], c[1], p);
    s1 = adaslice__side(m, c[1], c[2], p);
    s2 = adaslice__side(m, c[2], c[0], p);
    if (s0 != s1 || s1 != s2 || (s0 > 0) != (area > 0)) return 0;
    la = ((b[0] - p[0]) * (d[1] - p[1]) - (b[1] - p[1]) * (d[0] - p[0])) / area;
    lb = ((d[0] - p[0]) * (a[1] - p[1]) - (d[1] - p[1]) * (a[0] - p[0])) / area;
    lc = 1 - la - lb;
    z = la * a[2] + lb * b[2] + lc * d[2];
    return z > p[2];
}

#define ADASLICE__PROBES 7 /* points per shell that test its nesting */

typedef struct adaslice__shells {
    size_t count;
    uint32_t *of;          /* per facet: its shell */
    uint32_t *facets;      /* facets shell by shell */
    size_t *start;         /* count + 1: shell s owns facets[start[s] .. start[s+1]) */
    unsigned char *turn;   /* per facet: 1 to reverse it */
    unsigned char *closed; /* per shell */
    double *probe;         /* ADASLICE__PROBES points per shell, x y z */
    unsigned char *probes; /* per shell: how many */
} adaslice__shells;

#define ADASLICE__OPEN (ADASLICE__NONE - 1) /* a half-edge's mate when it is alone on its edge */

/* Winds each shell one way by flood fill through its two-facet edges; the
   winding of the larger part stays. Counts the open and non-manifold edges
   and what remains inconsistent. */
static adaslice_result adaslice__wind_shells(const adaslice_mesh *m, const adaslice__edges *e, adaslice__shells *s,
                                             const adaslice_allocator *al, adaslice_mesh_report *rep, adaslice_error *err)
{
    const uint32_t *tri = m->triangles;
    size_t nt = m->triangle_count, t, head = 0, tail = 0, i;
    uint32_t *mate = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, 3 * nt, sizeof(uint32_t)));
    size_t *uses = ADASLICE__CAST(size_t *, adaslice__alloc(al, e->cap ? e->cap : 1, sizeof(size_t)));
    if (!mate || !uses) {
        adaslice__free(al, mate);
        adaslice__free(al, uses);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for %zu facets", nt);
    }
    memset(mate, 0xff, 3 * nt * sizeof(uint32_t));
    for (i = 0; i < e->cap; i++) {
        uint32_t h = e->slot[i];
        long net;
        uses[i] = 0;
        if (h == ADASLICE__NONE) continue;
        adaslice__edge_uses(tri, e, h, &uses[i], &net);
        rep->edge_steps += uses[i];
        rep->open_edges += uses[i] == 1;
        rep->nonmanifold_edges += uses[i] > 2;
        if (uses[i] == 1) mate[h] = ADASLICE__OPEN;
        if (uses[i] == 2) { mate[h] = e->next[h]; mate[e->next[h]] = h; }
    }
    memset(s->of, 0xff, nt * sizeof(uint32_t));
    s->count = 0;
    for (t = 0; t < nt; t++) {
        size_t begin = tail, turned = 0;
        if (s->of[t] != ADASLICE__NONE) continue;
        s->start[s->count] = begin;
        s->of[t] = (uint32_t)s->count;
        s->turn[t] = 0;
        s->facets[tail++] = (uint32_t)t;
        for (head = begin; head < tail; head++) {
            uint32_t f = s->facets[head];
            int k;
            for (k = 0; k < 3; k++) {
                uint32_t h = 3 * f + (uint32_t)k, g = mate[h], u;
                unsigned char want;
                if (g >= ADASLICE__OPEN) continue;
                u = g / 3;
                /* the same direction along the edge: one of the two must turn */
                want = (unsigned char)(s->turn[f] ^ (tri[h] == tri[g]));
                if (s->of[u] == ADASLICE__NONE) {
                    s->of[u] = (uint32_t)s->count;
                    s->turn[u] = want;
                    s->facets[tail++] = u;
                } else if (s->turn[u] != want && u > f) {
                    rep->inconsistent_edges++; /* counted once, from the lower facet */
                }
            }
        }
        for (i = begin; i < tail; i++) turned += s->turn[s->facets[i]];
        if (2 * turned > tail - begin)
            for (i = begin; i < tail; i++) s->turn[s->facets[i]] ^= 1;
        s->count++;
    }
    s->start[s->count] = tail;
    /* a shell is closed when it has an even number of facets on each of its
       edges: two on most, more where shells meet (two cubes sharing an
       edge); a piece cut off by edges of three facets has one there. The
       facets of an edge are counted per shell in one walk and judged in a
       second (which clears the counts), so an edge of k facets costs 2k, not k^2. */
    for (i = 0; i < s->count; i++) s->closed[i] = 1;
    memset(mate, 0, s->count * sizeof(uint32_t)); /* now the count per shell */
    for (i = 0; i < e->cap; i++) {
        uint32_t h = e->slot[i], g;
        if (h == ADASLICE__NONE || uses[i] == 2) continue;
        if (uses[i] == 1) { s->closed[s->of[h / 3]] = 0; continue; }
        for (g = h; g != ADASLICE__NONE; g = e->next[g]) mate[s->of[g / 3]]++;
        for (g = h; g != ADASLICE__NONE; g = e->next[g]) {
            uint32_t q = s->of[g / 3];
            if (mate[q] % 2) s->closed[q] = 0;
            mate[q] = 0;
        }
        rep->edge_steps += 2 * uses[i];
    }
    adaslice__free(al, mate);
    adaslice__free(al, uses);
    return ADASLICE_OK;
}

/* Six times the volume facet t (turned as s says) spans with centre c. */
static double adaslice__cone(const adaslice_mesh *m, size_t t, int turned, const double c[3])
{
    double a[3], b[3], d[3], v;
    int k;
    adaslice__corner(m, t, 0, a);
    adaslice__corner(m, t, turned ? 2 : 1, b);
    adaslice__corner(m, t, turned ? 1 : 2, d);
    for (k = 0; k < 3; k++) { a[k] -= c[k]; b[k] -= c[k]; d[k] -= c[k]; }
    v = a[0] * (b[1] * d[2] - b[2] * d[1]) + a[1] * (b[2] * d[0] - b[0] * d[2]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
    return v;
}

static void adaslice__centroid(const adaslice_mesh *m, size_t t, double c[3])
{
    double a[3], b[3], d[3];
    int k;
    adaslice__corner(m, t, 0, a);
    adaslice__corner(m, t, 1, b);
    adaslice__corner(m, t, 2, d);
    for (k = 0; k < 3; k++) c[k] = (a[k] + b[k] + d[k]) / 3;
}

/* A shell's probes: the centroids of its largest facet and of its facets
   lowest and highest along x, y and z (repeats dropped). */
static void adaslice__shell_probes(const adaslice_mesh *m, adaslice__shells *s, size_t shell)
{
    size_t i, pick[ADASLICE__PROBES], n = 0, j;
    double best = -1, lo[3], hi[3];
    int k;
    for (k = 0; k < ADASLICE__PROBES; k++) pick[k] = s->facets[s->start[shell]];
    for (k = 0; k < 3; k++) { lo[k] = DBL_MAX; hi[k] = -DBL_MAX; }
    for (i = s->start[shell]; i < s->start[shell + 1]; i++) {
        size_t t = s->facets[i];
        double c[3], a[3], b[3], d[3], nv[3], n2;
        adaslice__centroid(m, t, c);
        adaslice__corner(m, t, 0, a);
        adaslice__corner(m, t, 1, b);
        adaslice__corner(m, t, 2, d);
        adaslice__normal(a, b, d, nv);
        n2 = nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2];
        if (n2 > best) { best = n2; pick[0] = t; }
        for (k = 0; k < 3; k++) {
            if (c[k] < lo[k]) { lo[k] = c[k]; pick[1 + 2 * k] = t; }
            if (c[k] > hi[k]) { hi[k] = c[k]; pick[2 + 2 * k] = t; }
        }
    }
    for (i = 0; i < ADASLICE__PROBES; i++) {
        for (j = 0; j < i && pick[j] != pick[i]; j++) {}
        if (j < i) continue;
        adaslice__centroid(m, pick[i], s->probe + 3 * (ADASLICE__PROBES * shell + n));
        n++;
    }
    s->probes[shell] = (unsigned char)n;
}

static double adaslice__min3(double a, double b, double c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
static double adaslice__max3(double a, double b, double c) { return a > b ? (a > c ? a : c) : (b > c ? b : c); }

/* The cell of coordinate v in a row of g cells of `size` from lo. */
static size_t adaslice__cell(double v, double lo, double size, size_t g)
{
    double c = (v - lo) / size;
    return c <= 0 ? 0 : c >= (double)(g - 1) ? g - 1 : (size_t)c;
}

/* depth[s]: how many closed shells hold every probe of shell s. Probes sit in
   a grid of xy cells; each facet of a closed shell tests the probes of the
   cells under it, so the work is about the facets plus the crossings. */
static adaslice_result adaslice__nesting(const adaslice_mesh *m, const adaslice__shells *s, const adaslice_allocator *al,
                                         size_t *depth, adaslice_error *err)
{
    size_t np = s->count * ADASLICE__PROBES, g, i, t, pairs = 0, cap = 0, kept = 0, run, *cell_first = NULL, *fill = NULL;
    uint32_t *cell_probe = NULL;
    uint64_t *pair = NULL;
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, size[2];
    adaslice_result r = ADASLICE_OK;
    int a;
    memset(depth, 0, s->count * sizeof *depth);
    for (g = 1; g * g < np; g++) {}
    for (i = 0; i < np; i++) {
        const double *p = s->probe + 3 * i;
        if (i % ADASLICE__PROBES >= s->probes[i / ADASLICE__PROBES]) continue;
        for (a = 0; a < 2; a++) { if (p[a] < lo[a]) lo[a] = p[a]; if (p[a] > hi[a]) hi[a] = p[a]; }
    }
    for (a = 0; a < 2; a++) size[a] = hi[a] > lo[a] ? (hi[a] - lo[a]) / (double)g : 1;
    cell_first = ADASLICE__CAST(size_t *, adaslice__alloc(al, g * g + 1, sizeof(size_t)));
    fill = ADASLICE__CAST(size_t *, adaslice__alloc(al, g * g, sizeof(size_t)));
    cell_probe = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, np, sizeof(uint32_t)));
    if (!cell_first || !fill || !cell_probe) goto nomem;
    memset(cell_first, 0, (g * g + 1) * sizeof(size_t));
    for (i = 0; i < np; i++) {
        const double *p = s->probe + 3 * i;
        if (i % ADASLICE__PROBES >= s->probes[i / ADASLICE__PROBES]) continue;
        cell_first[adaslice__cell(p[1], lo[1], size[1], g) * g + adaslice__cell(p[0], lo[0], size[0], g) + 1]++;
    }
    for (i = 0; i < g * g; i++) cell_first[i + 1] += cell_first[i];
    memcpy(fill, cell_first, g * g * sizeof(size_t));
    for (i = 0; i < np; i++) {
        const double *p = s->probe + 3 * i;
        if (i % ADASLICE__PROBES >= s->probes[i / ADASLICE__PROBES]) continue;
        cell_probe[fill[adaslice__cell(p[1], lo[1], size[1], g) * g + adaslice__cell(p[0], lo[0], size[0], g)]++] = (uint32_t)i;
    }
    for (t = 0; t < m->triangle_count; t++) {
        uint32_t q = s->of[t];
        double c[3][3], xlo, xhi, ylo, yhi;
        size_t x, y, j;
        if (!s->closed[q]) continue;
        for (a = 0; a < 3; a++) adaslice__corner(m, t, a, c[a]);
        xlo = adaslice__min3(c[0][0], c[1][0], c[2][0]); xhi = adaslice__max3(c[0][0], c[1][0], c[2][0]);
        ylo = adaslice__min3(c[0][1], c[1][1], c[2][1]); yhi = adaslice__max3(c[0][1], c[1][1], c[2][1]);
        if (xhi < lo[0] || xlo > hi[0] || yhi < lo[1] || ylo > hi[1]) continue;
        for (y = adaslice__cell(ylo, lo[1], size[1], g); y <= adaslice__cell(yhi, lo[1], size[1], g); y++)
            for (x = adaslice__cell(xlo, lo[0], size[0], g); x <= adaslice__cell(xhi, lo[0], size[0], g); x++)
                for (j = cell_first[y * g + x]; j < cell_first[y * g + x + 1]; j++) {
                    uint32_t p = cell_probe[j];
                    if (p / ADASLICE__PROBES == q || !adaslice__ray_crosses(m, t, s->probe + 3 * (size_t)p)) continue;
                    if (pairs == cap) {
                        uint64_t *more = ADASLICE__CAST(uint64_t *, adaslice__grow(al, pair, pairs, &cap, pairs + 1, sizeof *pair));
                        if (!more) goto nomem;
                        pair = more;
                    }
                    pair[pairs++] = (uint64_t)p << 32 | q;
                }
    }
    /* a probe is inside q when its ray crosses q an odd number of times;
       q holds shell s when it holds every probe of s */
    if (pairs) qsort(pair, pairs, sizeof *pair, adaslice__u64_cmp);
    for (i = 0; i < pairs; i += run) {
        for (run = 1; i + run < pairs && pair[i + run] == pair[i]; run++) {}
        if (run % 2) pair[kept++] = (uint64_t)((uint32_t)(pair[i] >> 32) / ADASLICE__PROBES) << 32 | (uint32_t)pair[i];
    }
    if (kept) qsort(pair, kept, sizeof *pair, adaslice__u64_cmp);
    for (i = 0; i < kept; i += run) {
        for (run = 1; i + run < kept && pair[i + run] == pair[i]; run++) {}
        if (run == s->probes[pair[i] >> 32]) depth[pair[i] >> 32]++;
    }
    goto done;
nomem:
    r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for the nesting of %zu shells", s->count);
done:
    adaslice__free(al, cell_first);
    adaslice__free(al, fill);
    adaslice__free(al, cell_probe);
    adaslice__free(al, pair);
    return r;
}

ADASLICE_DEF adaslice_result adaslice_mesh_repair(adaslice_mesh *m, const adaslice_repair_options *o,
                                                  adaslice_mesh_report *report, adaslice_error *err)
{
    adaslice_allocator al;
    adaslice_mesh_report rep;
    adaslice_weld_options wo;
    adaslice__edges e;
    adaslice__shells s;
    adaslice_result r;
    size_t *depth = NULL, i, t, nt;
    double tolerance = o ? o->tolerance : 0;
    memset(&rep, 0, sizeof rep);
    memset(&e, 0, sizeof e);
    memset(&s, 0, sizeof s);
    if (report) memset(report, 0, sizeof *report);
    if ((r = adaslice__mesh_check(m, "repair", err)) != ADASLICE_OK ||
        (r = adaslice__tolerance_check(tolerance, "repair", err)) != ADASLICE_OK)
        return r;
    al = adaslice__allocator(o ? o->allocator : NULL);
    memset(&wo, 0, sizeof wo);
    wo.allocator = &al;
    if ((r = adaslice_mesh_weld(m, &wo, err)) != ADASLICE_OK) return r;
    if ((r = adaslice__collapse_slivers(m, &al, &rep.slivers_collapsed, err)) != ADASLICE_OK) return r;
    rep.degenerate_dropped = adaslice__drop_degenerate(m);
    if (!m->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "repair: every facet has zero area");
    if ((r = adaslice__edges_build(m, 1, &al, &e, err)) != ADASLICE_OK) return r;
    if ((r = adaslice__weld_open(m, &e, tolerance, &al, &rep.welded_nearby, err)) != ADASLICE_OK) goto done;
    if (rep.welded_nearby) {
        /* the cracks closed: the facets and the edges change */
        rep.degenerate_dropped += adaslice__drop_degenerate(m);
        if (!m->triangle_count) {
            r = adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "repair: every facet has zero area");
            goto done;
        }
        adaslice__edges_free(&al, &e);
        if ((r = adaslice__edges_build(m, 1, &al, &e, err)) != ADASLICE_OK) return r;
    }
    /* last: vertex numbers leave the edges' grouping as it is */
    if ((r = adaslice__drop_unused(m, &al, err)) != ADASLICE_OK) goto done;
    nt = m->triangle_count;
    s.of = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, nt, sizeof(uint32_t)));
    s.facets = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, nt, sizeof(uint32_t)));
    s.start = ADASLICE__CAST(size_t *, adaslice__alloc(&al, nt + 1, sizeof(size_t)));
    s.turn = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, nt, 1));
    s.closed = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, nt, 1));
    if (!s.of || !s.facets || !s.start || !s.turn || !s.closed) goto nomem;
    if ((r = adaslice__wind_shells(m, &e, &s, &al, &rep, err)) != ADASLICE_OK) goto done;
    for (i = 0; i < s.count; i++) rep.closed_shells += s.closed[i];
    depth = ADASLICE__CAST(size_t *, adaslice__alloc(&al, s.count, sizeof(size_t)));
    if (!depth) goto nomem;
    memset(depth, 0, s.count * sizeof *depth);
    if (s.count > 1 && rep.closed_shells) {
        s.probes = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, s.count, 1));
        s.probe = ADASLICE__CAST(double *, adaslice__alloc(&al, s.count, 3 * ADASLICE__PROBES * sizeof(double)));
        if (!s.probes || !s.probe) goto nomem;
        for (i = 0; i < s.count; i++) adaslice__shell_probes(m, &s, i);
        if ((r = adaslice__nesting(m, &s, &al, depth, err)) != ADASLICE_OK) goto done;
    }
    /* each shell faces the way its nesting says: out at even depth, in at odd */
    for (i = 0; i < s.count; i++) {
        double c[3] = {0, 0, 0}, v = 0, area = 0;
        size_t n = s.start[i + 1] - s.start[i], j;
        int k;
        for (j = s.start[i]; j < s.start[i + 1]; j++) {
            double f[3];
            adaslice__centroid(m, s.facets[j], f);
            for (k = 0; k < 3; k++) c[k] += f[k] / (double)n;
        }
        for (j = s.start[i]; j < s.start[i + 1]; j++) {
            double a[3], b[3], d[3], nv[3];
            v += adaslice__cone(m, s.facets[j], s.turn[s.facets[j]], c);
            if (s.closed[i]) continue; /* the area decides for open shells only */
            adaslice__corner(m, s.facets[j], 0, a);
            adaslice__corner(m, s.facets[j], 1, b);
            adaslice__corner(m, s.facets[j], 2, d);
            adaslice__normal(a, b, d, nv);
            area += 0.5 * sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
        }
        /* an open shell only when it clearly holds one side: six times its
           volume about its centroid at least 5% of a sphere's of its area
           (A^1.5 / sqrt(pi)); a patch is left as it is wound */
        if (!s.closed[i] && fabs(v) < 0.05 * area * sqrt(area / 3.14159265358979323846)) v = 0;
        if (v != 0 && (v < 0) != (depth[i] % 2 == 1)) {
            for (j = s.start[i]; j < s.start[i + 1]; j++) s.turn[s.facets[j]] ^= 1;
            rep.flipped_shells++;
            v = -v;
        }
        rep.volume += v / 6;
    }
    for (t = 0; t < nt; t++) {
        uint32_t *c = m->triangles + 3 * t, x;
        if (!s.turn[t]) continue;
        x = c[1]; c[1] = c[2]; c[2] = x;
        rep.flipped_facets++;
    }
    rep.shells = s.count;
    if (report) *report = rep;
    adaslice__ok(err);
    goto done;
nomem:
    r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "repair: out of memory for %zu facets", nt);
done:
    adaslice__edges_free(&al, &e);
    adaslice__free(&al, s.of);
    adaslice__free(&al, s.facets);
    adaslice__free(&al, s.start);
    adaslice__free(&al, s.turn);
    adaslice__free(&al, s.closed);
    adaslice__free(&al, s.probes);
    adaslice__free(&al, s.probe);
    adaslice__free(&al, depth);
    return r;
}

/* ---- sections of open meshes */
/* Where edges do not balance (a hole, a crack, facets wound against their
   neighbours) a ray cannot tell inside from outside: it may cross the surface
   once. There each section is made whole in the plane instead: the facets'
   cuts, run as the contours run (counter-clockwise round material), stop at
   loose ends on the unbalanced edges; each end where a cut stops is joined by
   a straight chord to the nearest loose start, and the closed result is
   filled where its winding number is positive. A section with one gap is
   thereby closed by its chord, which is exactly where the generalized winding
   number (Jacobson, Kavan and Sorkine-Hornung 2013) of the open section is
   >= 1/2; several gaps are joined end to nearest start. Masks, areas and
   the contours' chords (adaslice_polygon.next) use the same rule. */
typedef struct adaslice__loose_edge {
    uint32_t u, v;  /* u < v */
    int32_t net;    /* facets running u -> v minus those running v -> u */
    float lo, hi;   /* z of its ends */
} adaslice__loose_edge;

typedef struct adaslice__gaps adaslice__gaps;
struct adaslice__gaps {
    adaslice__loose_edge *edge; /* by lowest z */
    size_t count, next;
    uint32_t *active;
    size_t active_count;
    double *tail, *head;        /* x, y of the loose ends at the last height */
    size_t tails, heads, tail_cap, head_cap;
    uint32_t *taker;            /* per head: the tail whose chord goes to it */
    size_t taker_cap;
    size_t *cell_first;         /* the heads by grid cell, for joining */
    uint32_t *cell_head;
    size_t cell_cap, slot_cap;
    adaslice_allocator allocator;
};

static int adaslice__loose_cmp(const void *a, const void *b)
{
    const adaslice__loose_edge *x = ADASLICE__CAST(const adaslice__loose_edge *, a), *y = ADASLICE__CAST(const adaslice__loose_edge *, b);
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    return x->u != y->u ? (x->u < y->u ? -1 : 1) : (x->v < y->v ? -1 : x->v > y->v);
}

static void adaslice__gaps_free(adaslice__gaps *g)
{
    adaslice_allocator al;
    if (!g) return;
    al = g->allocator;
    adaslice__free(&al, g->edge);
    adaslice__free(&al, g->active);
    adaslice__free(&al, g->tail);
    adaslice__free(&al, g->head);
    adaslice__free(&al, g->taker);
    adaslice__free(&al, g->cell_first);
    adaslice__free(&al, g->cell_head);
    adaslice__free(&al, g);
}

/* The unbalanced edges of m, or *gaps = NULL when every edge balances (a
   closed mesh wound one way: rays are exact). */
static adaslice_result adaslice__gaps_init(adaslice__gaps **gaps, const adaslice_mesh *m, const adaslice_allocator *al,
                                           adaslice_error *err)
{
    adaslice__edges e;
    adaslice__gaps *g;
    adaslice_result r;
    size_t i, n = 0;
    *gaps = NULL;
    if ((r = adaslice__edges_build(m, 0, al, &e, err)) != ADASLICE_OK) return r;
    for (i = 0; i < e.cap; i++) {
        size_t uses;
        long net;
        if (e.slot[i] == ADASLICE__NONE) continue;
        adaslice__edge_uses(m->triangles, &e, e.slot[i], &uses, &net);
        n += net != 0;
    }
    if (!n) { adaslice__edges_free(al, &e); return ADASLICE_OK; }
    g = ADASLICE__CAST(adaslice__gaps *, adaslice__alloc(al, 1, sizeof *g));
    if (g) {
        memset(g, 0, sizeof *g);
        g->allocator = *al;
        g->edge = ADASLICE__CAST(adaslice__loose_edge *, adaslice__alloc(al, n, sizeof *g->edge));
        g->active = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    }
    if (!g || !g->edge || !g->active) {
        adaslice__gaps_free(g);
        adaslice__edges_free(al, &e);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "sections: out of memory for %zu open edges", n);
    }
    for (i = 0; i < e.cap; i++) {
        uint32_t h = e.slot[i], a, b;
        size_t uses;
        long net;
        adaslice__loose_edge *x;
        float za, zb;
        if (h == ADASLICE__NONE) continue;
        adaslice__edge_uses(m->triangles, &e, h, &uses, &net);
        if (!net) continue;
        a = m->triangles[h];
        b = adaslice__he_to(m->triangles, h);
        x = g->edge + g->count++;
        x->u = a < b ? a : b;
        x->v = a < b ? b : a;
        x->net = (int32_t)net;
        za = m->vertices[3 * (size_t)x->u + 2];
        zb = m->vertices[3 * (size_t)x->v + 2];
        x->lo = za < zb ? za : zb;
        x->hi = za < zb ? zb : za;
    }
    adaslice__edges_free(al, &e);
    qsort(g->edge, g->count, sizeof *g->edge, adaslice__loose_cmp);
    *gaps = g;
    return ADASLICE_OK;
}

/* Where the edge from `below` (z <= height) to `above` (z > height) meets
   the plane: computed the same way by every facet and every chord. */
static void adaslice__cut_point(const adaslice_mesh *m, uint32_t below, uint32_t above, double height, double xy[2])
{
    const float *a = m->vertices + 3 * (size_t)below, *b = m->vertices + 3 * (size_t)above;
    double t = (height - a[2]) / ((double)b[2] - a[2]);
    xy[0] = a[0] + t * ((double)b[0] - a[0]);
    xy[1] = a[1] + t * ((double)b[1] - a[1]);
}

/* Each tail in turn takes the nearest head still free. Heads sit in a grid
   of about one per cell, searched ring by ring outwards from the tail's cell
   until no nearer head can remain, so a section with thousands of loose ends
   (a mesh with many facets wound backwards) is not quadratic. 0 when out of
   memory. */
static int adaslice__join_ends(adaslice__gaps *g)
{
    size_t n = g->heads, side, cells, i, j, points = n ? 1 : 0, *live;
    uint32_t *run_end, *first;
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, size;
    long r;
    /* a cell a point, not a head: thousands of heads on a few points (a fan
       of facets wound round and round) in a grid of thousands of cells had
       each tail search rings of empty cells for them */
    for (j = 1; j < n; j++) points += g->head[2 * j] != g->head[2 * j - 2] || g->head[2 * j + 1] != g->head[2 * j - 1];
    for (side = 1; side * side < points; side++) {}
    cells = side * side;
    if (cells + 1 > g->cell_cap || n > g->slot_cap) {
        adaslice__free(&g->allocator, g->cell_first);
        adaslice__free(&g->allocator, g->cell_head);
        g->cell_cap = g->slot_cap = 0;
        /* cell_cap starts, then as many live[] */
        g->cell_first = ADASLICE__CAST(size_t *, adaslice__alloc(&g->allocator, 2 * 2 * (cells + 1), sizeof(size_t)));
        /* slot_cap heads, then as many run_end[] and first[] */
        g->cell_head = ADASLICE__CAST(uint32_t *, adaslice__alloc(&g->allocator, 3 * 2 * n, sizeof(uint32_t)));
        if (!g->cell_first || !g->cell_head) return 0;
        g->cell_cap = 2 * (cells + 1);
        g->slot_cap = 2 * n;
    }
    for (j = 0; j < n; j++) {
        int a;
        for (a = 0; a < 2; a++) {
            if (g->head[2 * j + a] < lo[a]) lo[a] = g->head[2 * j + a];
            if (g->head[2 * j + a] > hi[a]) hi[a] = g->head[2 * j + a];
        }
    }
    size = (hi[0] - lo[0] > hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1]) / (double)side;
    if (!(size > 0)) size = 1;
    memset(g->cell_first, 0, (cells + 1) * sizeof(size_t));
    for (j = 0; j < n; j++) g->cell_first[adaslice__cell(g->head[2 * j + 1], lo[1], size, side) * side +
                                           adaslice__cell(g->head[2 * j], lo[0], size, side) + 1]++;
    for (i = 0; i < cells; i++) g->cell_first[i + 1] += g->cell_first[i];
    for (j = 0; j < n; j++) {
        size_t c = adaslice__cell(g->head[2 * j + 1], lo[1], size, side) * side + adaslice__cell(g->head[2 * j], lo[0], size, side);
        g->cell_head[g->cell_first[c]++] = (uint32_t)j;
    }
    for (i = cells; i > 0; i--) g->cell_first[i] = g->cell_first[i - 1];
    g->cell_first[0] = 0;
    /* A facet repeated n times puts n ends on one point, one after another
       in its cell: a run, whose heads are equally near any tail, so only its
       first free one (first[] at the run's start) can be the nearest, and
       they go in order. Visiting runs, not heads, keeps that linear, not
       n^2; live[c] is cell c's first run with a head free. */
    run_end = g->cell_head + g->slot_cap;
    first = run_end + g->slot_cap;
    for (i = 0; i < cells; i++) {
        size_t k = g->cell_first[i], e = g->cell_first[i + 1];
        while (k < e) {
            size_t start = k, h = g->cell_head[k];
            while (k < e && g->head[2 * g->cell_head[k]] == g->head[2 * h] &&
                   g->head[2 * g->cell_head[k] + 1] == g->head[2 * h + 1])
                k++;
            run_end[start] = (uint32_t)k;
            first[start] = (uint32_t)start;
        }
    }
    live = g->cell_first + g->cell_cap;
    memcpy(live, g->cell_first, cells * sizeof *live);
    for (j = 0; j < n; j++) g->taker[j] = ADASLICE__NONE;
    for (i = 0; i < g->tails; i++) {
        const double *t = g->tail + 2 * i;
        long cx = (long)adaslice__cell(t[0], lo[0], size, side), cy = (long)adaslice__cell(t[1], lo[1], size, side);
        double best = DBL_MAX;
        size_t pick = ADASLICE__NONE, pick_run = 0;
        /* every head in ring r lies at least (r - 1) cells away */
        for (r = 0; r <= (long)side && !(r > 1 && (double)(r - 1) * size * (double)(r - 1) * size > best); r++) {
            long dx, dy;
            for (dy = -r; dy <= r; dy++)
                for (dx = -r; dx <= r; dx += (dy == -r || dy == r) ? 1 : 2 * r) {
                    long x = cx + dx, y = cy + dy;
                    size_t c = (size_t)y * side + (size_t)x, e, k;
                    if (x < 0 || y < 0 || x >= (long)side || y >= (long)side) { if (!r) break; continue; }
                    e = g->cell_first[c + 1];
                    while (live[c] < e && first[live[c]] == run_end[live[c]]) live[c] = run_end[live[c]];
                    for (k = live[c]; k < e; k = run_end[k]) {
                        size_t h;
                        double ex, ey;
                        if (first[k] == run_end[k]) continue;
                        h = g->cell_head[first[k]];
                        ex = g->head[2 * h] - t[0];
                        ey = g->head[2 * h + 1] - t[1];
                        if (ex * ex + ey * ey < best) { best = ex * ex + ey * ey; pick = h; pick_run = k; }
                    }
                    if (!r) break;
                }
        }
        g->taker[pick] = (uint32_t)i;
        first[pick_run]++;
    }
    return 1;
}

/* Room for `more` points after `used` in *points (x, y pairs). */
static int adaslice__room(const adaslice_allocator *al, double **points, size_t used, size_t *cap, size_t more)
{
    double *p;
    if (2 * (used + more) <= *cap) return 1;
    p = ADASLICE__CAST(double *, adaslice__grow(al, *points, 2 * used, cap, 2 * (used + more), sizeof(double)));
    if (!p) return 0;
    *points = p;
    return 1;
}

/* The loose ends at `height` (not below the last height asked): tails, where
   a cut stops, and heads, where one starts; taker[j] is the tail whose chord
   goes to head j. */
static adaslice_result adaslice__gaps_at(adaslice__gaps *g, const adaslice_mesh *m, double height, adaslice_error *err)
{
    size_t k, kept = 0;
    while (g->next < g->count && (double)g->edge[g->next].lo <= height) g->active[g->active_count++] = (uint32_t)g->next++;
    g->tails = g->heads = 0;
    for (k = 0; k < g->active_count; k++) {
        const adaslice__loose_edge *x = g->edge + g->active[k];
        double xy[2];
        int32_t n = x->net, c;
        int u_below = (double)m->vertices[3 * (size_t)x->u + 2] <= height, tail;
        if (!((double)x->hi > height)) continue; /* ended below: gone for good */
        g->active[kept++] = g->active[k];
        /* a facet running upwards across the plane ends its cut there:
           u -> v runs upwards when u is below */
        tail = (n > 0) == u_below;
        if (n < 0) n = -n;
        if (tail ? !adaslice__room(&g->allocator, &g->tail, g->tails, &g->tail_cap, (size_t)n)
                 : !adaslice__room(&g->allocator, &g->head, g->heads, &g->head_cap, (size_t)n))
            goto nomem;
        adaslice__cut_point(m, u_below ? x->u : x->v, u_below ? x->v : x->u, height, xy);
        for (c = 0; c < n; c++) {
            double *p = tail ? g->tail + 2 * g->tails++ : g->head + 2 * g->heads++;
            p[0] = xy[0];
            p[1] = xy[1];
        }
    }
    g->active_count = kept;
    /* every cut starts once and ends once, so the loose ends pair up */
    if (g->tails != g->heads)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "sections: %zu loose ends against %zu at %g mm", g->tails,
                              g->heads, height);
    if (g->heads > g->taker_cap) {
        adaslice__free(&g->allocator, g->taker);
        g->taker_cap = 0;
        g->taker = ADASLICE__CAST(uint32_t *, adaslice__alloc(&g->allocator, 2 * g->heads, sizeof(uint32_t)));
        if (!g->taker) goto nomem;
        g->taker_cap = 2 * g->heads;
    }
    if (g->heads && !adaslice__join_ends(g)) goto nomem;
    return ADASLICE_OK;
nomem:
    return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "sections: out of memory for the loose ends at %g mm", height);
}

/* ---- turning */
ADASLICE_DEF void adaslice_rotation_to_z(const double d[3], double r[9])
{
    /* Rodrigues about d x z; d = -z turns half a turn about x */
    double c = d[2], vx = d[1], vy = -d[0], k;
    if (c < -1 + 1e-12) {
        r[0] = 1; r[1] = 0; r[2] = 0;
        r[3] = 0; r[4] = -1; r[5] = 0;
    } else {
        k = 1 / (1 + c);
        r[0] = 1 - vy * vy * k; r[1] = vx * vy * k;     r[2] = vy;
        r[3] = vx * vy * k;     r[4] = 1 - vx * vx * k; r[5] = -vx;
    }
    r[6] = d[0]; r[7] = d[1]; r[8] = d[2];
}

/* One expression for a turned coordinate, so the search's heights and a
   turned mesh's z agree to the last bit. */
static double adaslice__turn(const double *row, const float *p)
{
    return row[0] * p[0] + row[1] * p[1] + row[2] * p[2];
}

/* p turned by r into q (which may be p): the only place a vertex is turned */
static inline void adaslice__turn_vertex(const double r[9], const float *p, float *q)
{
    float x = (float)adaslice__turn(r, p), y = (float)adaslice__turn(r + 3, p), z = (float)adaslice__turn(r + 6, p);
    q[0] = x; q[1] = y; q[2] = z;
}

/* mesh's vertices turned by r into a copy (triangles shared); 0 when out of memory */
static int adaslice__turned_copy(const adaslice_mesh *mesh, const double r[9], const adaslice_allocator *al,
                                 adaslice_mesh *turned)
{
    size_t v;
    *turned = *mesh;
    memset(&turned->allocator, 0, sizeof turned->allocator);
    turned->vertices = ADASLICE__CAST(float *, adaslice__alloc(al, mesh->vertex_count ? mesh->vertex_count : 1, 3 * sizeof(float)));
    if (!turned->vertices) return 0;
    for (v = 0; v < mesh->vertex_count; v++) adaslice__turn_vertex(r, mesh->vertices + 3 * v, turned->vertices + 3 * v);
    return 1;
}

ADASLICE_DEF void adaslice_mesh_rotate(adaslice_mesh *mesh, const double r[9])
{
    size_t v;
    for (v = 0; v < mesh->vertex_count; v++) adaslice__turn_vertex(r, mesh->vertices + 3 * v, mesh->vertices + 3 * v);
}

/* ============================================================== sampling */
/* Triangles are rasterised one scan line at a time into spans of pixels; the
   same spans build a stored LDI, feed the sampled profiles, and update layer
   masks. Coordinates are snapped to 1/256 pixel and every inside test is an
   exact integer edge function with a top-left rule. */

#define ADASLICE__SUBPIXEL 256
#define ADASLICE__GRID_LIMIT 2097152.0 /* 2^21 pixels: keeps edge functions within 2^62 */

typedef struct adaslice__span {
    int row, first, end;     /* pixels [first, end) of the row */
    double depth, step;      /* depth at pixel 0's centre in the row, and per pixel */
    double lo, hi;           /* the triangle's depth range: depths are clamped to it */
    uint32_t face;           /* triangle index | ADASLICE_SAMPLE_LEAVES */
} adaslice__span;

/* The depth of pixel i of a span; every user computes it this way, so a
   sample is on the same side of a height wherever it is looked at. */
static double adaslice__span_depth(const adaslice__span *s, int i)
{
    double d = s->depth + s->step * (double)i;
    return d < s->lo ? s->lo : (d > s->hi ? s->hi : d);
}

typedef void (*adaslice__span_fn)(void *ctx, const adaslice__span *span);

typedef struct adaslice__raster {
    const adaslice_grid *grid;
    double depth_origin;
    int row_first, row_end;      /* rows to cover */
    int slab;                    /* only depths in [slab_lo, slab_hi) */
    double slab_lo, slab_hi;
    adaslice__span_fn fn;
    void *ctx;
    void (*progress)(void *user, double done); /* NULL, or told progress_lo + progress_span * */
    void *progress_user;                       /* the share of triangles done */
    double progress_lo, progress_span;
} adaslice__raster;

static void adaslice__project(adaslice_axis axis, const float *p, double out[3])
{
    int a = axis == ADASLICE_AXIS_X ? 1 : (axis == ADASLICE_AXIS_Y ? 2 : 0);
    out[0] = p[a];
    out[1] = p[(a + 1) % 3];
    out[2] = p[(a + 2) % 3];
}

static int64_t adaslice__floor_div(int64_t a, int64_t b) /* b > 0 */
{
    int64_t q = a / b;
    return (a % b != 0 && a < 0) ? q - 1 : q;
}

/* floor(x) for |x| < 2^62, inline: where SSE4.1 is not assumed floor is a
   call into libm, and the rasteriser takes several a triangle and row. */
static double adaslice__floor_near(double x)
{
    double t = (double)(int64_t)x;
    return t > x ? t - 1 : t;
}

/* The smallest i with alpha i + beta >= 0 (alpha > 0), and the largest with
   alpha < 0: a floating-point guess (truncated: the correction makes it
   exact), then exact integer correction (an int64 division per edge and row
   costs more than the rest of the row). */
static int64_t adaslice__first_nonnegative(int64_t alpha, int64_t beta)
{
    int64_t i = (int64_t)(-(double)beta / (double)alpha);
    while (alpha * i + beta < 0) i++;
    while (alpha * (i - 1) + beta >= 0) i--;
    return i;
}

static int64_t adaslice__last_nonnegative(int64_t alpha, int64_t beta)
{
    int64_t i = (int64_t)(-(double)beta / (double)alpha);
    while (alpha * i + beta < 0) i--;
    while (alpha * (i + 1) + beta >= 0) i++;
    return i;
}

/* First pixel in [lo, hi] whose depth is >= bound (or < bound when `below`),
   given that the span's depth is monotone; hi + 1 if none. */
static int adaslice__span_find(const adaslice__span *s, int lo, int hi, double bound, int below)
{
    int a = lo, b = hi + 1;
    /* pred(i) = (depth >= bound) flips once along the span: find where */
    int pred_lo = adaslice__span_depth(s, lo) >= bound;
    if (below) pred_lo = !pred_lo;
    if (pred_lo) return lo;
    if (s->step == 0) return hi + 1;
    while (a + 1 < b) {
        int mid = a + (b - a) / 2;
        int p = adaslice__span_depth(s, mid) >= bound;
        if (below) p = !p;
        if (p) b = mid; else a = mid;
    }
    return b;
}

/* Returns 0, or 1 if a vertex lies so far off the grid that the exact edge
   functions could overflow. */
static int adaslice__raster_triangle(const adaslice__raster *r, const adaslice_mesh *m, uint32_t t)
{
    const adaslice_grid *g = r->grid;
    double P[3][3], U[3], V[3], D[3], nx, ny, nz, gx, gy, dlo, dhi;
    int64_t X[3], Y[3], area, ylo, yhi;
    int k, j, j0, j1;
    adaslice__span s;
    for (k = 0; k < 3; k++) {
        adaslice__project(g->axis, m->vertices + 3 * (size_t)m->triangles[3 * (size_t)t + k], P[k]);
        U[k] = (P[k][0] - g->origin[0]) / g->pitch[0];
        V[k] = (P[k][1] - g->origin[1]) / g->pitch[1];
        D[k] = P[k][2] - r->depth_origin;
        if (!(fabs(U[k]) < ADASLICE__GRID_LIMIT && fabs(V[k]) < ADASLICE__GRID_LIMIT)) return 1;
        X[k] = (int64_t)adaslice__floor_near(U[k] * ADASLICE__SUBPIXEL + 0.5);
        Y[k] = (int64_t)adaslice__floor_near(V[k] * ADASLICE__SUBPIXEL + 0.5);
    }
    area = (X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0]);
    if (area == 0) return 0; /* seen edge-on: the rays graze it */
    ylo = Y[0] < Y[1] ? Y[0] : Y[1]; if (Y[2] < ylo) ylo = Y[2];
    yhi = Y[0] > Y[1] ? Y[0] : Y[1]; if (Y[2] > yhi) yhi = Y[2];
    /* rows whose centre 256 j + 128 lies in [ylo, yhi] */
    j0 = (int)-adaslice__floor_div(-(ylo - ADASLICE__SUBPIXEL / 2), ADASLICE__SUBPIXEL);
    j1 = (int)adaslice__floor_div(yhi - ADASLICE__SUBPIXEL / 2, ADASLICE__SUBPIXEL);
    if (j0 < r->row_first) j0 = r->row_first;
    if (j1 > r->row_end - 1) j1 = r->row_end - 1;
    if (j0 > j1) return 0; /* between two rows' centres (most facets of a fine mesh in a small picture) */
    s.face = t | (area > 0 ? ADASLICE_SAMPLE_LEAVES : 0u); /* normal along +ray: leaving */
    if (area < 0) { /* rasterise counter-clockwise */
        int64_t ti; double td;
        ti = X[1]; X[1] = X[2]; X[2] = ti;
        ti = Y[1]; Y[1] = Y[2]; Y[2] = ti;
        td = U[1]; U[1] = U[2]; U[2] = td;
        td = V[1]; V[1] = V[2]; V[2] = td;
        td = D[1]; D[1] = D[2]; D[2] = td;
    }
    /* the depth plane, from the unsnapped vertices, in pixel units */
    nx = (V[1] - V[0]) * (D[2] - D[0]) - (D[1] - D[0]) * (V[2] - V[0]);
    ny = (D[1] - D[0]) * (U[2] - U[0]) - (U[1] - U[0]) * (D[2] - D[0]);
    nz = (U[1] - U[0]) * (V[2] - V[0]) - (V[1] - V[0]) * (U[2] - U[0]);
    gx = nz != 0 ? -nx / nz : 0;
    gy = nz != 0 ? -ny / nz : 0;
    dlo = D[0] < D[1] ? D[0] : D[1]; if (D[2] < dlo) dlo = D[2];
    dhi = D[0] > D[1] ? D[0] : D[1]; if (D[2] > dhi) dhi = D[2];
    s.lo = dlo; s.hi = dhi; s.step = gx;
    for (j = j0; j <= j1; j++) {
        int64_t yc = (int64_t)j * ADASLICE__SUBPIXEL + ADASLICE__SUBPIXEL / 2, lo = 0, hi = g->width - 1;
        int e, first, last;
        for (e = 0; e < 3 && lo <= hi; e++) {
            int a = e, b = (e + 1) % 3;
            int64_t dx = X[b] - X[a], dy = Y[b] - Y[a];
            int top_left = dy < 0 || (dy == 0 && dx < 0);
            /* inside: dx (y - Ya) - dy (x - Xa) > 0, or = 0 on a top-left edge;
               at x = 256 i + 128 that is alpha i + beta >= 0 */
            int64_t alpha = -dy * ADASLICE__SUBPIXEL;
            int64_t beta = dx * (yc - Y[a]) - dy * (ADASLICE__SUBPIXEL / 2 - X[a]) - (top_left ? 0 : 1);
            if (alpha > 0) { int64_t q = adaslice__first_nonnegative(alpha, beta); if (q > lo) lo = q; }
            else if (alpha < 0) { int64_t q = adaslice__last_nonnegative(alpha, beta); if (q < hi) hi = q; }
            else if (beta < 0) hi = lo - 1;
        }
        if (lo > hi) continue;
        s.row = j;
        s.depth = D[0] + gx * (0.5 - U[0]) + gy * ((double)j + 0.5 - V[0]);
        first = (int)lo;
        last = (int)hi;
        if (r->slab) {
            /* the pixels whose depth is in [slab_lo, slab_hi): a run, as depth is monotone */
            if (s.step >= 0) {
                first = adaslice__span_find(&s, first, last, r->slab_lo, 0);
                last = adaslice__span_find(&s, first, last, r->slab_hi, 0) - 1;
            } else {
                int f2 = adaslice__span_find(&s, first, last, r->slab_hi, 1);
                last = adaslice__span_find(&s, f2, last, r->slab_lo, 1) - 1;
                first = f2;
            }
            if (first > last) continue;
        }
        s.first = first;
        s.end = last + 1;
        r->fn(r->ctx, &s);
    }
    return 0;
}

/* Rasterises every triangle; fails naming the first one too far off the grid. */
static adaslice_result adaslice__raster_mesh(const adaslice__raster *r, const adaslice_mesh *m, adaslice_error *err)
{
    size_t t;
    for (t = 0; t < m->triangle_count; t++) {
        if (r->progress && t % 256 == 0)
            r->progress(r->progress_user, r->progress_lo + r->progress_span * (double)t / (double)m->triangle_count);
        if (adaslice__raster_triangle(r, m, (uint32_t)t))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "LDI: triangle %zu lies more than 2^21 pixels from the grid", t);
    }
    return ADASLICE_OK;
}

/* ---- a stored LDI, or one band of rows of it */

typedef struct adaslice__ldi_fill {
    const adaslice_grid *grid;
    int row_first;
    size_t *first;               /* per pixel of the band */
    adaslice_sample *samples;
    size_t *row_samples;         /* counting pass per row, or NULL */
    int pass;                    /* 0: count rows, 1: count pixels, 2: fill */
} adaslice__ldi_fill;

static void adaslice__ldi_visit(void *ctx, const adaslice__span *s)
{
    adaslice__ldi_fill *f = ADASLICE__CAST(adaslice__ldi_fill *, ctx);
    size_t base = (size_t)(s->row - f->row_first) * (size_t)f->grid->width;
    int i;
    if (f->pass == 0) { f->row_samples[s->row] += (size_t)(s->end - s->first); return; }
    if (f->pass == 1) { for (i = s->first; i < s->end; i++) f->first[base + (size_t)i]++; return; }
    for (i = s->first; i < s->end; i++) {
        adaslice_sample *out = &f->samples[--f->first[base + (size_t)i]];
        out->depth = (float)adaslice__span_depth(s, i);
        out->face = s->face;
    }
}

static int adaslice__sample_before(const adaslice_sample *a, const adaslice_sample *b)
{
    return a->depth < b->depth || (a->depth == b->depth && a->face < b->face);
}

static int adaslice__sample_cmp(const void *a, const void *b)
{
    const adaslice_sample *x = ADASLICE__CAST(const adaslice_sample *, a), *y = ADASLICE__CAST(const adaslice_sample *, b);
    return adaslice__sample_before(x, y) ? -1 : adaslice__sample_before(y, x);
}

/* Builds rows [row_first, row_end) into `ldi` (whose grid is the full grid):
   first[] has (rows * width + 1) entries. */
static adaslice_result adaslice__ldi_band(const adaslice_mesh *m, adaslice_ldi *ldi, int row_first, int row_end,
                                          adaslice_error *err)
{
    adaslice__raster r;
    adaslice__ldi_fill f;
    size_t pixels = (size_t)(row_end - row_first) * (size_t)ldi->grid.width, p, total = 0;
    adaslice_result res;
    memset(&r, 0, sizeof r);
    r.grid = &ldi->grid;
    r.depth_origin = ldi->depth_origin;
    r.row_first = row_first;
    r.row_end = row_end;
    r.fn = adaslice__ldi_visit;
    r.ctx = &f;
    memset(&f, 0, sizeof f);
    f.grid = &ldi->grid;
    f.row_first = row_first;
    f.first = ldi->first;
    f.pass = 1;
    memset(ldi->first, 0, (pixels + 1) * sizeof(size_t));
    if ((res = adaslice__raster_mesh(&r, m, err)) != ADASLICE_OK) return res;
    for (p = 0; p < pixels; p++) { total += ldi->first[p]; ldi->first[p] = total; }
    ldi->first[pixels] = total;
    ldi->sample_count = total;
    ldi->samples = ADASLICE__CAST(adaslice_sample *, adaslice__alloc(&ldi->allocator, total, sizeof(adaslice_sample)));
    if (!ldi->samples)
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "LDI: out of memory for %zu samples", total);
    f.samples = ldi->samples;
    f.pass = 2;
    (void)adaslice__raster_mesh(&r, m, err);
    for (p = 0; p < pixels; p++) { /* insertion sort: a ray meets few surfaces */
        size_t a = ldi->first[p], b = ldi->first[p + 1], i, k;
        /* but facets stacked thousands deep (a fan wound round and round)
           made that quadratic: minutes for one plan --hybrid. A total
           order, so both sorts give the same samples. */
        if (b - a > 32) {
            qsort(ldi->samples + a, b - a, sizeof *ldi->samples, adaslice__sample_cmp);
            continue;
        }
        for (i = a + 1; i < b; i++) {
            adaslice_sample s = ldi->samples[i];
            for (k = i; k > a && adaslice__sample_before(&s, &ldi->samples[k - 1]); k--) ldi->samples[k] = ldi->samples[k - 1];
            ldi->samples[k] = s;
        }
    }
    return ADASLICE_OK;
}

static adaslice_result adaslice__grid_check(const adaslice_grid *g, adaslice_error *err)
{
    if (!g || (unsigned)g->axis > ADASLICE_AXIS_Z || g->width < 1 || g->height < 1 ||
        g->width > (int)ADASLICE__GRID_LIMIT || g->height > (int)ADASLICE__GRID_LIMIT || !(g->pitch[0] > 0) ||
        g->pitch[0] > DBL_MAX || !(g->pitch[1] > 0) || g->pitch[1] > DBL_MAX || !(fabs(g->origin[0]) < DBL_MAX) ||
        !(fabs(g->origin[1]) < DBL_MAX))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "LDI: grid %d x %d pixels of %g x %g mm is not valid (1 to 2^21 pixels a side)",
                              g ? g->width : 0, g ? g->height : 0, g ? g->pitch[0] : 0.0, g ? g->pitch[1] : 0.0);
    return ADASLICE_OK;
}

static double adaslice__depth_origin(const adaslice_mesh *m, adaslice_axis axis)
{
    double lo[3], hi[3];
    adaslice_mesh_bounds(m, lo, hi);
    return lo[axis];
}

/* ---- the face nearest a viewer at +z, per pixel (a z-buffer) */
typedef struct adaslice__nearest {
    const adaslice_grid *grid;
    float *depth;
    uint32_t *face;        /* triangle | ADASLICE_SAMPLE_LEAVES, or ADASLICE__NONE: no surface */
} adaslice__nearest;

static void adaslice__nearest_visit(void *ctx, const adaslice__span *s)
{
    adaslice__nearest *z = ADASLICE__CAST(adaslice__nearest *, ctx);
    size_t row = (size_t)s->row * (size_t)z->grid->width;
    int i;
    for (i = s->first; i < s->end; i++) {
        float d = (float)adaslice__span_depth(s, i);
        size_t p = row + (size_t)i;
        /* on a tie (a silhouette) the face turned towards the viewer wins */
        if (z->face[p] == ADASLICE__NONE || d > z->depth[p] || (d == z->depth[p] && (s->face & ADASLICE_SAMPLE_LEAVES))) {
            z->depth[p] = d;
            z->face[p] = s->face;
        }
    }
}

/* face[p]: the nearest surface of mesh seen from +z at pixel p of grid (axis
   z), with ADASLICE_SAMPLE_LEAVES when it is turned towards the viewer;
   ADASLICE__NONE where no surface is. depth: scratch of a float a pixel. */
/* depth_origin: the mesh's lowest z (adaslice__depth_origin's), which the
   callers have in hand: another pass over 1.8M facets' corners was a tenth of
   a preview. */
static adaslice_result adaslice__nearest_faces(const adaslice_mesh *m, const adaslice_grid *grid, double depth_origin,
                                               float *depth, uint32_t *face, adaslice_error *err)
{
    adaslice__nearest z;
    adaslice__raster r;
    z.grid = grid;
    z.depth = depth;
    z.face = face;
    memset(face, 0xff, (size_t)grid->width * (size_t)grid->height * sizeof(uint32_t));
    memset(&r, 0, sizeof r);
    r.grid = grid;
    r.depth_origin = depth_origin;
    r.row_end = grid->height;
    r.fn = adaslice__nearest_visit;
    r.ctx = &z;
    return adaslice__raster_mesh(&r, m, err);
}

ADASLICE_DEF adaslice_result adaslice_ldi_build(const adaslice_mesh *mesh, const adaslice_grid *grid,
                                                const adaslice_ldi_options *options, adaslice_ldi *ldi,
                                                adaslice_error *err)
{
    adaslice_result r;
    size_t pixels;
    if (!ldi) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "LDI: no output given");
    memset(ldi, 0, sizeof *ldi);
    if ((r = adaslice__grid_check(grid, err)) != ADASLICE_OK) return r;
    if (!mesh || !mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "LDI: the mesh has no triangles");
    ldi->allocator = adaslice__allocator(options ? options->allocator : NULL);
    ldi->grid = *grid;
    ldi->depth_origin = adaslice__depth_origin(mesh, grid->axis);
    pixels = (size_t)grid->width * (size_t)grid->height;
    ldi->first = ADASLICE__CAST(size_t *, adaslice__alloc(&ldi->allocator, pixels + 1, sizeof(size_t)));
    if (!ldi->first) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "LDI: out of memory for %zu pixels", pixels);
    } else if ((r = adaslice__ldi_band(mesh, ldi, 0, grid->height, err)) == ADASLICE_OK) {
        adaslice__ok(err);
        return ADASLICE_OK;
    }
    adaslice_ldi_free(ldi);
    return r;
}

ADASLICE_DEF void adaslice_ldi_free(adaslice_ldi *ldi)
{
    if (!ldi) return;
    adaslice__free(&ldi->allocator, ldi->first);
    adaslice__free(&ldi->allocator, ldi->samples);
    memset(ldi, 0, sizeof *ldi);
}

ADASLICE_DEF size_t adaslice_ldi_ray(const adaslice_ldi *ldi, const adaslice_mesh *mesh, double u, double v,
                                     adaslice_crossing *out, size_t max)
{
    const adaslice_grid *g = &ldi->grid;
    /* the grid's (u, v, depth) as mesh axes: a cyclic turn of (x, y, z) */
    int au = ((int)g->axis + 1) % 3, av = ((int)g->axis + 2) % 3, ad = (int)g->axis;
    double fi = floor((u - g->origin[0]) / g->pitch[0]), fj = floor((v - g->origin[1]) / g->pitch[1]);
    size_t p, a, b, k, n;
    if (!ldi->first || !(fi >= 0 && fi < g->width && fj >= 0 && fj < g->height)) return 0;
    p = (size_t)fj * (size_t)g->width + (size_t)fi;
    a = ldi->first[p];
    b = ldi->first[p + 1];
    for (k = a, n = 0; k < b && n < max; k++, n++) {
        adaslice_sample s = ldi->samples[k];
        adaslice_crossing c;
        size_t m;
        c.depth = ldi->depth_origin + s.depth;
        c.face = ADASLICE_SAMPLE_FACE(s);
        c.leaves = (s.face & ADASLICE_SAMPLE_LEAVES) != 0;
        if (mesh && c.face < mesh->triangle_count) {
            const uint32_t *t = mesh->triangles + 3 * (size_t)c.face;
            const float *p0 = mesh->vertices + 3 * (size_t)t[0], *p1 = mesh->vertices + 3 * (size_t)t[1],
                        *p2 = mesh->vertices + 3 * (size_t)t[2];
            double e1[3], e2[3], nu, nv, nd;
            int i;
            for (i = 0; i < 3; i++) {
                e1[i] = (double)p1[i] - p0[i];
                e2[i] = (double)p2[i] - p0[i];
            }
            nu = e1[av] * e2[ad] - e1[ad] * e2[av];
            nv = e1[ad] * e2[au] - e1[au] * e2[ad];
            nd = e1[au] * e2[av] - e1[av] * e2[au];
            /* a face along the ray has no one depth: the sample's stays */
            if (fabs(nd) > 1e-9 * (fabs(nu) + fabs(nv) + fabs(nd)))
                c.depth = p0[ad] - (nu * (u - p0[au]) + nv * (v - p0[av])) / nd;
        }
        /* moved onto their planes, close crossings may swap */
        for (m = n; m > 0 && out[m - 1].depth > c.depth; m--) out[m] = out[m - 1];
        out[m] = c;
    }
    return b - a;
}

ADASLICE_DEF adaslice_grid adaslice_grid_fit(const adaslice_mesh *mesh, adaslice_axis axis, int resolution)
{
    adaslice_grid g;
    double lo[3], hi[3], extent = 0;
    int k, a = axis == ADASLICE_AXIS_X ? 1 : (axis == ADASLICE_AXIS_Y ? 2 : 0);
    adaslice_mesh_bounds(mesh, lo, hi);
    for (k = 0; k < 3; k++) if (hi[k] - lo[k] > extent) extent = hi[k] - lo[k];
    if (resolution < 1) resolution = 1;
    memset(&g, 0, sizeof g);
    g.axis = axis;
    g.pitch[0] = g.pitch[1] = extent > 0 ? extent / resolution : 1;
    g.origin[0] = lo[a];
    g.origin[1] = lo[(a + 1) % 3];
    /* one pixel more than the extent needs, so the far faces' centres are inside */
    g.width = (int)ceil((hi[a] - lo[a]) / g.pitch[0]) + 1;
    g.height = (int)ceil((hi[(a + 1) % 3] - lo[(a + 1) % 3]) / g.pitch[1]) + 1;
    return g;
}

/* ============================================================== profiles */
/* Bins: N = ceil(H / b); bin i covers [z0 + i*b, z0 + (i+1)*b). */


/* Range-maximum updates in O(1) each: a sparse table whose level k holds
   maxima over runs of 2^k bins; a range [l, r] writes two overlapping runs of
   the largest power of two that fits, and one push down, level by level, at
   the end gives every bin its maximum. Levels stop at the longest range, and
   a level is zeroed when first written: on large profiles the levels are
   tens of MB, and clearing the unused ones cost as much as the updates. */
typedef struct adaslice__rmax {
    size_t n;
    int levels;
    unsigned char zeroed[64];
    double *t;          /* levels * n */
} adaslice__rmax;

/* Bins count below 2^31, so a double holds x exactly and its exponent is
   the answer without a branch. */
static int adaslice__floor_log2(size_t x) /* x >= 1 */
{
    double d = (double)x;
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    return (int)(bits >> 52) - 1023;
}

static int adaslice__rmax_init(adaslice__rmax *r, size_t n, size_t longest, const adaslice_allocator *al)
{
    r->n = n;
    r->levels = adaslice__floor_log2(longest < n ? (longest ? longest : 1) : n) + 1;
    memset(r->zeroed, 0, sizeof r->zeroed);
    r->t = ADASLICE__CAST(double *, adaslice__alloc(al, (size_t)r->levels * n, sizeof(double)));
    return r->t != NULL;
}

static inline double *adaslice__rmax_level(adaslice__rmax *r, int k)
{
    double *level = r->t + (size_t)k * r->n;
    if (!r->zeroed[k]) {
        memset(level, 0, r->n * sizeof(double));
        r->zeroed[k] = 1;
    }
    return level;
}

static inline void adaslice__rmax_update(adaslice__rmax *r, size_t first, size_t last, double v)
{
    int k = adaslice__floor_log2(last - first + 1);
    double *level;
    ADASLICE_ASSERT(k < r->levels); /* the table's height came from a bound on the ranges */
    level = adaslice__rmax_level(r, k);
    size_t second = last + 1 - ((size_t)1 << k);
    /* unconditional stores: the comparisons are unpredictable, a select is not */
    level[first] = level[first] < v ? v : level[first];
    level[second] = level[second] < v ? v : level[second];
}

/* Pushes every written level down; level 0 then holds each bin's maximum. A
   tall part's levels are most of a profile's work: they are its progress. */
static double *adaslice__rmax_finish(adaslice__rmax *r, const adaslice_profile_options *opt)
{
    int k;
    for (k = r->levels - 1; k > 0; k--) {
        if (opt->progress) opt->progress(opt->progress_user, 0.1 + 0.9 * (double)(r->levels - 1 - k) / r->levels);
        const double *up = r->t + (size_t)k * r->n;
        double *down;
        size_t half = (size_t)1 << (k - 1), j, end = r->n - ((size_t)1 << k) + 1;
        if (!r->zeroed[k]) continue;
        down = adaslice__rmax_level(r, k - 1);
        /* each bin below takes the larger of the two above that cover it:
           one store a bin and no bin read after it is stored; two bins a
           step, which gcc -O2 turns into vector maxima (a bin a step it
           does not) */
        for (j = 0; j < half && j < end; j++) down[j] = down[j] < up[j] ? up[j] : down[j];
        for (; j + 2 <= end; j += 2) {
            double a0 = up[j] > up[j - half] ? up[j] : up[j - half];
            double a1 = up[j + 1] > up[j + 1 - half] ? up[j + 1] : up[j + 1 - half];
            double d0 = down[j], d1 = down[j + 1];
            down[j] = d0 < a0 ? a0 : d0;
            down[j + 1] = d1 < a1 ? a1 : d1;
        }
        for (; j < end; j++) {
            double a = up[j] > up[j - half] ? up[j] : up[j - half];
            down[j] = down[j] < a ? a : down[j];
        }
        for (j = j > half ? j : half; j < end + half; j++) down[j] = down[j] < up[j - half] ? up[j - half] : down[j];
    }
    (void)adaslice__rmax_level(r, 0);
    return r->t;
}

/* Per-triangle value that the max-type profiles take: |n_z| (eq. 4) or
   1/sin(theta) = |n| / |n_xy| clamped at roughness_max (eq. 8), times the weight. */
static double adaslice__cusp_value(const double n[3])
{
    return fabs(n[2]) / sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static double adaslice__facet_value(adaslice_metric metric, const double n[3], double roughness_max)
{
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), xy;
    if (metric == ADASLICE_METRIC_CUSP) return adaslice__cusp_value(n);
    xy = sqrt(n[0] * n[0] + n[1] * n[1]);
    if (xy * roughness_max <= len) return roughness_max;
    return len / xy;
}

/* Piece of a triangle's cut between heights za and zb: the directed segment
   from P(z) to Q(z), both linear in z, contributes sign * cross(P, Q) / 2 to
   the signed area A(z) (Green's theorem over the cross-section's contour). */
typedef struct adaslice__piece {
    double za, zb;       /* the piece is valid for za <= z < zb */
    double p[2], pd[2];  /* P(z) = p + pd * (z - za) */
    double q[2], qd[2];
    double sign;
} adaslice__piece;

#define ADASLICE__BLOCK 256  /* bins per block of the area accumulator */
#define ADASLICE__DIRECT 8   /* pieces spanning at most this many centres are evaluated directly */

static double adaslice__piece_at(const adaslice__piece *pc, double z, double out_p[2], double out_q[2])
{
    double t = z - pc->za;
    out_p[0] = pc->p[0] + pc->pd[0] * t; out_p[1] = pc->p[1] + pc->pd[1] * t;
    out_q[0] = pc->q[0] + pc->qd[0] * t; out_q[1] = pc->q[1] + pc->qd[1] * t;
    return 0.5 * pc->sign * (out_p[0] * out_q[1] - out_p[1] * out_q[0]);
}

typedef struct adaslice__area_acc {
    size_t n;
    double z0, bin;
    double *direct;      /* n: values added at single centres */
    double *coef;        /* 3 * (n + 1): per-bin differences of the block-local quadratic */
} adaslice__area_acc;

static double adaslice__centre(const adaslice__area_acc *acc, size_t i)
{
    return acc->z0 + ((double)i + 0.5) * acc->bin;
}

/* Adds a piece to every bin whose centre lies in [za, zb). Short pieces are
   evaluated at their few centres; long ones become a quadratic per block,
   expanded about the block's first centre so no term is far from its origin. */
static void adaslice__area_add(adaslice__area_acc *acc, const adaslice__piece *pc)
{
    double f = (pc->za - acc->z0) / acc->bin - 0.5, g = (pc->zb - acc->z0) / acc->bin - 0.5;
    size_t first, end, i, k;
    double P[2], Q[2];
    if (g <= 0 || f >= (double)acc->n) return;
    first = f <= 0 ? 0 : (size_t)ceil(f);
    end = g >= (double)acc->n ? acc->n : (size_t)ceil(g);
    while (first > 0 && adaslice__centre(acc, first - 1) >= pc->za) first--;
    while (first < acc->n && adaslice__centre(acc, first) < pc->za) first++;
    while (end < acc->n && adaslice__centre(acc, end) < pc->zb) end++;
    while (end > first && adaslice__centre(acc, end - 1) >= pc->zb) end--;
    if (end <= first) return;
    if (end - first <= ADASLICE__DIRECT) {
        for (i = first; i < end; i++) acc->direct[i] += adaslice__piece_at(pc, adaslice__centre(acc, i), P, Q);
        return;
    }
    for (i = first; i < end; i = k) {
        size_t block_end = (i / ADASLICE__BLOCK + 1) * ADASLICE__BLOCK;
        double origin = adaslice__centre(acc, (i / ADASLICE__BLOCK) * ADASLICE__BLOCK), c[3];
        double *d = acc->coef + 3 * i;
        k = end < block_end ? end : block_end;
        c[0] = adaslice__piece_at(pc, origin, P, Q);
        c[1] = 0.5 * pc->sign * (P[0] * pc->qd[1] - P[1] * pc->qd[0] + pc->pd[0] * Q[1] - pc->pd[1] * Q[0]);
        c[2] = 0.5 * pc->sign * (pc->pd[0] * pc->qd[1] - pc->pd[1] * pc->qd[0]);
        d[0] += c[0]; d[1] += c[1]; d[2] += c[2];
        if (k < block_end) { /* a block's sums restart at its first bin anyway */
            d = acc->coef + 3 * k;
            d[0] -= c[0]; d[1] -= c[1]; d[2] -= c[2];
        }
    }
}

static void adaslice__area_finish(const adaslice__area_acc *acc, double *area)
{
    size_t i;
    double s0 = 0, s1 = 0, s2 = 0, origin = 0;
    for (i = 0; i < acc->n; i++) {
        double t;
        if (i % ADASLICE__BLOCK == 0) { s0 = s1 = s2 = 0; origin = adaslice__centre(acc, i); }
        s0 += acc->coef[3 * i]; s1 += acc->coef[3 * i + 1]; s2 += acc->coef[3 * i + 2];
        t = adaslice__centre(acc, i) - origin;
        area[i] = acc->direct[i] + s0 + (s1 + s2 * t) * t;
    }
}

/* Cross-section area at every bin centre. x and y are taken about the box
   centre, so terms stay small; the sign is fixed by the mesh's signed volume,
   so an inside-out mesh still gives positive areas. */
static double adaslice__green_areas(const adaslice_mesh *m, const double lo[3], const double hi[3],
                                    adaslice__area_acc *acc, double *area)
{
    double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]), cz = 0.5 * (lo[2] + hi[2]);
    double volume = 0;
    size_t t;
    for (t = 0; t < m->triangle_count; t++) {
        double v[3][3], n[3], d[2], s, *p0, *p1, *p2, *tmp;
        adaslice__piece pc;
        int k;
        for (k = 0; k < 3; k++) {
            adaslice__corner(m, t, k, v[k]);
            v[k][0] -= cx; v[k][1] -= cy;
        }
        adaslice__normal(v[0], v[1], v[2], n);
        volume += ((v[0][2] - cz) * (v[1][0] * v[2][1] - v[1][1] * v[2][0]) +
                   (v[1][2] - cz) * (v[2][0] * v[0][1] - v[2][1] * v[0][0]) +
                   (v[2][2] - cz) * (v[0][0] * v[1][1] - v[0][1] * v[1][0])) / 6.0;
        p0 = v[0]; p1 = v[1]; p2 = v[2];
        if (p0[2] > p1[2]) { tmp = p0; p0 = p1; p1 = tmp; }
        if (p1[2] > p2[2]) { tmp = p1; p1 = p2; p2 = tmp; }
        if (p0[2] > p1[2]) { tmp = p0; p0 = p1; p1 = tmp; }
        if (!(p2[2] > p0[2])) continue; /* horizontal: no cut */
        /* The contour runs along z x n; the segment from the long edge
           (p0-p2) towards p1 either does or runs against it. */
        d[0] = -n[1]; d[1] = n[0];
        s = (p1[2] - p0[2]) / (p2[2] - p0[2]);
        s = (p1[0] - (p0[0] + s * (p2[0] - p0[0]))) * d[0] + (p1[1] - (p0[1] + s * (p2[1] - p0[1]))) * d[1];
        if (s == 0) continue; /* the triangle is vertical along its cut: zero-width */
        pc.sign = s > 0 ? 1.0 : -1.0;
        pc.pd[0] = (p2[0] - p0[0]) / (p2[2] - p0[2]);
        pc.pd[1] = (p2[1] - p0[1]) / (p2[2] - p0[2]);
        if (p1[2] > p0[2]) {
            pc.za = p0[2]; pc.zb = p1[2];
            pc.p[0] = p0[0]; pc.p[1] = p0[1];
            pc.q[0] = p0[0]; pc.q[1] = p0[1];
            pc.qd[0] = (p1[0] - p0[0]) / (p1[2] - p0[2]);
            pc.qd[1] = (p1[1] - p0[1]) / (p1[2] - p0[2]);
            adaslice__area_add(acc, &pc);
        }
        if (p2[2] > p1[2]) {
            double u = (p1[2] - p0[2]) / (p2[2] - p0[2]);
            pc.za = p1[2]; pc.zb = p2[2];
            pc.p[0] = p0[0] + u * (p2[0] - p0[0]); pc.p[1] = p0[1] + u * (p2[1] - p0[1]);
            pc.q[0] = p1[0]; pc.q[1] = p1[1];
            pc.qd[0] = (p2[0] - p1[0]) / (p2[2] - p1[2]);
            pc.qd[1] = (p2[1] - p1[1]) / (p2[2] - p1[2]);
            adaslice__area_add(acc, &pc);
        }
    }
    adaslice__area_finish(acc, area);
    return volume;
}

/* A(z) at the centres of n bins from z0: Green's theorem over the facets'
   cuts, plus the chords of a mesh with unbalanced edges (see "sections of
   open meshes"), so areas and masks follow one rule. */
static adaslice_result adaslice__section_areas(const adaslice_mesh *m, double z0, double bin, size_t n, double *area,
                                               const adaslice_allocator *al, adaslice_error *err)
{
    adaslice__area_acc acc;
    adaslice__gaps *gaps = NULL;
    adaslice_result r;
    double lo[3], hi[3], cx, cy, volume;
    size_t i, j;
    memset(&acc, 0, sizeof acc);
    acc.n = n; acc.z0 = z0; acc.bin = bin;
    acc.direct = ADASLICE__CAST(double *, adaslice__alloc(al, n, sizeof(double)));
    acc.coef = ADASLICE__CAST(double *, adaslice__alloc(al, 3 * (n + 1), sizeof(double)));
    if (!acc.direct || !acc.coef) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for %zu bins", n);
        goto done;
    }
    memset(acc.direct, 0, n * sizeof(double));
    memset(acc.coef, 0, 3 * (n + 1) * sizeof(double));
    adaslice_mesh_bounds(m, lo, hi);
    volume = adaslice__green_areas(m, lo, hi, &acc, area);
    if ((r = adaslice__gaps_init(&gaps, m, al, err)) != ADASLICE_OK) goto done;
    cx = 0.5 * (lo[0] + hi[0]);
    cy = 0.5 * (lo[1] + hi[1]);
    for (i = 0; gaps && i < n; i++) {
        double sum = 0;
        if ((r = adaslice__gaps_at(gaps, m, adaslice__centre(&acc, i), err)) != ADASLICE_OK) goto done;
        for (j = 0; j < gaps->heads; j++) {
            const double *t = gaps->tail + 2 * (size_t)gaps->taker[j], *h = gaps->head + 2 * j;
            sum += (t[0] - cx) * (h[1] - cy) - (h[0] - cx) * (t[1] - cy);
        }
        area[i] += 0.5 * sum;
    }
    for (i = 0; i < n; i++) {
        if (volume < 0) area[i] = -area[i];
        if (area[i] < 0) area[i] = 0; /* badly wound meshes: see the manual */
    }
    r = ADASLICE_OK;
done:
    adaslice__gaps_free(gaps);
    adaslice__free(al, acc.direct);
    adaslice__free(al, acc.coef);
    return r;
}

/* eq. 14 with one-sided differences at the top bin; where A(i) is zero the
   neighbour's area is the reference, and where both are zero phi is zero. */
static double adaslice__area_deviation(const double *area, size_t n, size_t i, double bin)
{
    size_t j = i + 1 < n ? i + 1 : (i > 0 ? i - 1 : i);
    double ref = area[i] > 0 ? area[i] : area[j];
    if (!(ref > 0)) return 0;
    return fabs(area[j] - area[i]) / (bin * ref);
}

/* The options with their defaults, checked, and the bins: *bin_count of
   them from *z0 to *z1. zrange: the used vertices' lowest and highest z when
   the caller knows them (and has checked the indices), else NULL. */
static adaslice_result adaslice__profile_bins(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                              adaslice_profile_options *opt, const double *zrange, size_t *bin_count,
                                              double *z0, double *z1, adaslice_error *err)
{
    double lo[3], hi[3], bins;
    size_t t;
    if (!mesh || !mesh->triangle_count || !mesh->vertices || !mesh->triangles)
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "profile: the mesh has no triangles");
    if (options) *opt = *options; else memset(opt, 0, sizeof *opt);
    if (opt->bin == 0) opt->bin = ADASLICE_DEFAULT_BIN;
    if (opt->roughness_max == 0) opt->roughness_max = ADASLICE_DEFAULT_ROUGHNESS_MAX;
    if (opt->resolution == 0) opt->resolution = ADASLICE_DEFAULT_RESOLUTION;
    if (opt->memory_limit == 0) opt->memory_limit = ADASLICE_DEFAULT_MEMORY_LIMIT;
    if (!(opt->bin > 0) || opt->bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: bin size %g is not a positive number", opt->bin);
    if (!(opt->roughness_max >= 1) || opt->roughness_max > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: roughness clamp %g must be at least 1", opt->roughness_max);
    if ((unsigned)opt->metric > ADASLICE_METRIC_VOLUME)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: unknown metric %d", (int)opt->metric);
    if (opt->resolution < 1 || opt->resolution > 65536)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: LDI resolution %d is outside 1..65536", opt->resolution);
    if (opt->weights)
        for (t = 0; t < mesh->triangle_count; t++)
            if (!(opt->weights[t] >= 0 && opt->weights[t] <= 1))
                return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                      "profile: weight of triangle %zu is %g, outside [0, 1]", t, (double)opt->weights[t]);
    lo[2] = zrange ? zrange[0] : DBL_MAX;
    hi[2] = zrange ? zrange[1] : -DBL_MAX;
    for (t = 0; !zrange && t < 3 * mesh->triangle_count; t++) {
        double z;
        if (mesh->triangles[t] >= mesh->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "profile: triangle %zu uses vertex %u of %zu",
                                  t / 3, (unsigned)mesh->triangles[t], mesh->vertex_count);
        z = mesh->vertices[3 * (size_t)mesh->triangles[t] + 2];
        lo[2] = z < lo[2] ? z : lo[2];
        hi[2] = z > hi[2] ? z : hi[2];
    }
    if (!(hi[2] > lo[2]))
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "profile: the mesh is flat (height 0 along z)");
    /* the vertices are floats: a height of whole bins (10.3 mm is 10.3000002
       as a float) gets no extra bin for the rounding, which a uniform plan
       made a last layer of one bin (0.002 mm, refused by formats of 0.01) */
    {
        double far = fabs(lo[2]) > fabs(hi[2]) ? fabs(lo[2]) : fabs(hi[2]), noise = 2 * FLT_EPSILON * far / opt->bin;
        bins = ceil((hi[2] - lo[2]) / opt->bin - 1e-9 - (noise < 0.25 ? noise : 0.25));
    }
    if (bins < 1) bins = 1;
    if (bins > 2147483646.0)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "profile: %g bins of %g mm over %g mm is too many",
                              bins, opt->bin, hi[2] - lo[2]);
    *bin_count = (size_t)bins;
    *z0 = lo[2];
    *z1 = hi[2];
    return ADASLICE_OK;
}

/* The same, then phi (and the areas for area and volume) allocated; phi
   cleared unless `zero` is 0 (a caller that writes every bin). */
static adaslice_result adaslice__profile_begin(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                               adaslice_profile *profile, adaslice_profile_options *opt,
                                               const double *zrange, int zero, adaslice_error *err)
{
    adaslice_allocator al;
    adaslice_result r;
    double lo, hi;
    size_t n;
    if (!profile) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: no output given");
    memset(profile, 0, sizeof *profile);
    if ((r = adaslice__profile_bins(mesh, options, opt, zrange, &n, &lo, &hi, err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(opt->allocator);
    profile->phi = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
    if (opt->metric >= ADASLICE_METRIC_AREA)
        profile->area = ADASLICE__CAST(double *, adaslice__alloc(&al, n, sizeof(double)));
    if (!profile->phi || (opt->metric >= ADASLICE_METRIC_AREA && !profile->area)) {
        adaslice__free(&al, profile->phi);
        adaslice__free(&al, profile->area);
        memset(profile, 0, sizeof *profile);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for %zu bins", n);
    }
    if (zero) memset(profile->phi, 0, n * sizeof(double));
    profile->metric = opt->metric;
    profile->bin_count = n;
    profile->bin = opt->bin;
    profile->z0 = lo;
    profile->height = hi - lo;
    profile->allocator = al;
    return ADASLICE_OK;
}

#ifndef ADASLICE_NO_SAMPLED
/* What a triangle contributes to a max-type profile (its value times its
   weight), or to the max weight per bin (area and volume); -1 if it has no
   normal. */
static double adaslice__face_value(const adaslice_mesh *mesh, size_t t, const adaslice_profile_options *opt)
{
    const uint32_t *tri = mesh->triangles + 3 * t;
    const float *a = mesh->vertices + 3 * (size_t)tri[0], *b = mesh->vertices + 3 * (size_t)tri[1],
                *c = mesh->vertices + 3 * (size_t)tri[2];
    double u0 = (double)b[0] - a[0], u1 = (double)b[1] - a[1], u2 = (double)b[2] - a[2];
    double w0 = (double)c[0] - a[0], w1 = (double)c[1] - a[1], w2 = (double)c[2] - a[2];
    double nrm[3], value = 1;
    nrm[0] = u1 * w2 - u2 * w1;
    nrm[1] = u2 * w0 - u0 * w2;
    nrm[2] = u0 * w1 - u1 * w0;
    if (nrm[0] == 0 && nrm[1] == 0 && nrm[2] == 0) return -1;
    if (opt->metric <= ADASLICE_METRIC_ROUGHNESS) value = adaslice__facet_value(opt->metric, nrm, opt->roughness_max);
    return opt->weights ? value * opt->weights[t] : value;
}
#endif

/* Area and volume deviation from the areas (eq. 14, 17), times the largest
   weight in each bin (eq. 23, 24) when there are weights. */
static void adaslice__phi_from_area(adaslice_profile *p, const double *wmax)
{
    size_t i;
    for (i = 0; i < p->bin_count; i++) {
        double phi = p->metric == ADASLICE_METRIC_AREA ? adaslice__area_deviation(p->area, p->bin_count, i, p->bin)
                                                       : p->area[i];
        p->phi[i] = wmax ? phi * wmax[i] : phi;
    }
}

/* The bin that height z falls in, clamped to 0 .. top: selects, not
   branches, as heights arrive in no useful order. Bins count below 2^31, so
   a long holds one (one instruction; a size_t takes a branch). */
static inline size_t adaslice__bin_of(double z0, double inverse, double top, double z)
{
    double f = (z - z0) * inverse;
    f = f > 0 ? f : 0;
    f = f < top ? f : top;
    return (size_t)(long)f;
}

/* adaslice__face_value on the corners at hand, for the loops over every
   triangle; -1 if the facet has no normal. Inline, as a call costs a third
   of it, and the call to adaslice__facet_value cost a tenth of the profile,
   so cusp is its own case. */
static inline double adaslice__corner_value(const float *a, const float *b, const float *c, adaslice_metric metric,
                                            double rough)
{
    double u0 = (double)b[0] - a[0], u1 = (double)b[1] - a[1], u2 = (double)b[2] - a[2];
    double w0 = (double)c[0] - a[0], w1 = (double)c[1] - a[1], w2 = (double)c[2] - a[2];
    double nrm[3];
    nrm[0] = u1 * w2 - u2 * w1;
    nrm[1] = u2 * w0 - u0 * w2;
    nrm[2] = u0 * w1 - u1 * w0;
    /* a zero length (one predictable test) is rare: only then look closer, as
       tiny normals' squares can underflow */
    if (!(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2] > 0) && nrm[0] == 0 && nrm[1] == 0 && nrm[2] == 0)
        return -1;
    if (metric == ADASLICE_METRIC_CUSP) return adaslice__cusp_value(nrm);
    if (metric == ADASLICE_METRIC_ROUGHNESS) return adaslice__facet_value(metric, nrm, rough);
    return 1;
}

/* Each triangle's value (adaslice__face_value) over every bin its z-range
   meets (eq. 5, 9, 21-24), in one pass. longest: an upper bound on the bins
   a triangle meets, or 0 to have it found by a pass over the heights (it
   sizes the table). Returns the per-bin maxima (the table, which the caller
   frees), or NULL when out of memory. */
static double *adaslice__max_over_bins(const adaslice_mesh *mesh, const adaslice_profile_options *opt,
                                       const adaslice_profile *p, size_t longest, adaslice__rmax *rmax)
{
    size_t t, found = 1;
    /* locals, as the table's stores could otherwise be the options' doubles */
    double inverse = 1.0 / p->bin, top = (double)(long)(p->bin_count - 1), z0 = p->z0, rough = opt->roughness_max;
    adaslice_metric metric = opt->metric;
    const float *weights = opt->weights;
    for (t = 0; !longest && t < mesh->triangle_count; t++) {
        const uint32_t *tri = mesh->triangles + 3 * t;
        float a = mesh->vertices[3 * (size_t)tri[0] + 2], b = mesh->vertices[3 * (size_t)tri[1] + 2],
              c = mesh->vertices[3 * (size_t)tri[2] + 2], lo = a < b ? a : b, hi = a > b ? a : b;
        size_t run;
        lo = c < lo ? c : lo;
        hi = c > hi ? c : hi;
        run = adaslice__bin_of(z0, inverse, top, hi) - adaslice__bin_of(z0, inverse, top, lo) + 1;
        found = run > found ? run : found;
    }
    if (!longest) longest = found;
    if (!adaslice__rmax_init(rmax, p->bin_count, longest, &p->allocator)) return NULL;
    for (t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *tri = mesh->triangles + 3 * t;
        const float *a = mesh->vertices + 3 * (size_t)tri[0], *b = mesh->vertices + 3 * (size_t)tri[1],
                    *c = mesh->vertices + 3 * (size_t)tri[2];
        double value = adaslice__corner_value(a, b, c, metric, rough), lo, hi;
        if (opt->progress && t % 65536 == 0) opt->progress(opt->progress_user, 0.1 * (double)t / (double)mesh->triangle_count);
        if (value < 0) continue;
        if (weights) value *= weights[t];
        lo = a[2] < b[2] ? a[2] : b[2];
        hi = a[2] > b[2] ? a[2] : b[2];
        lo = c[2] < lo ? c[2] : lo;
        hi = c[2] > hi ? c[2] : hi;
        adaslice__rmax_update(rmax, adaslice__bin_of(z0, inverse, top, lo), adaslice__bin_of(z0, inverse, top, hi), value);
    }
    return adaslice__rmax_finish(rmax, opt);
}

/* longest: see adaslice__max_over_bins */
static adaslice_result adaslice__profile_exact(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                               const double *zrange, size_t longest, adaslice_profile *profile,
                                               adaslice_error *err)
{
    adaslice_profile_options opt;
    adaslice__rmax rmax;
    adaslice_result r;
    double *tree = NULL;
    size_t n;
    int max_type;

    if ((r = adaslice__profile_begin(mesh, options, profile, &opt, zrange, 1, err)) != ADASLICE_OK) return r;
    if (opt.progress) opt.progress(opt.progress_user, 0);
    n = profile->bin_count;
    max_type = opt.metric <= ADASLICE_METRIC_ROUGHNESS;
    if (max_type || opt.weights) {
        tree = adaslice__max_over_bins(mesh, &opt, profile, longest, &rmax);
        if (!tree) {
            adaslice_profile_free(profile);
            return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for %zu bins", n);
        }
    }
    if (max_type) {
        memcpy(profile->phi, tree, n * sizeof(double));
    } else {
        r = adaslice__section_areas(mesh, profile->z0, opt.bin, n, profile->area, &profile->allocator, err);
        if (r != ADASLICE_OK) {
            adaslice__free(&profile->allocator, tree);
            adaslice_profile_free(profile);
            return r;
        }
        adaslice__phi_from_area(profile, tree);
    }
    adaslice__free(&profile->allocator, tree);
    if (opt.progress) opt.progress(opt.progress_user, 1);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_profile_exact(const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *options,
                                                    adaslice_profile *profile, adaslice_error *err)
{
    return adaslice__profile_exact(mesh, options, NULL, 0, profile, err);
}

#ifndef ADASLICE_NO_SAMPLED
/* The pixels of grid g (axis a) that a triangle's spans cover at most, and its rows. */
static void adaslice__raster_size(const adaslice_mesh *m, size_t t, const adaslice_grid *g, double *pixels, double *rows)
{
    double P[3][3], lo = DBL_MAX, hi = -DBL_MAX, cross;
    int k;
    for (k = 0; k < 3; k++) {
        adaslice__project(g->axis, m->vertices + 3 * (size_t)m->triangles[3 * t + (size_t)k], P[k]);
        P[k][0] /= g->pitch[0];
        P[k][1] /= g->pitch[1];
        lo = P[k][1] < lo ? P[k][1] : lo;
        hi = P[k][1] > hi ? P[k][1] : hi;
    }
    cross = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[2][0] - P[0][0]) * (P[1][1] - P[0][1]);
    *rows = hi - lo + 1;
    /* each row's span is within a pixel of the triangle at either end */
    *pixels = 0.5 * fabs(cross) + 2 * *rows;
}
#endif

ADASLICE_DEF adaslice_result adaslice_profile_estimate(const adaslice_mesh *mesh, const adaslice_profile_options *options,
                                                       int sampled, adaslice_profile_cost *cost, adaslice_error *err)
{
    adaslice_profile_options opt;
    adaslice_result r;
    double lo, hi, n, nt, inverse, longest = 1, bytes;
    size_t bins, t;
    int max_type, axis;
    if (!cost) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "profile: no output given");
    memset(cost, 0, sizeof *cost);
    if ((r = adaslice__profile_bins(mesh, options, &opt, NULL, &bins, &lo, &hi, err)) != ADASLICE_OK) return r;
    n = (double)bins;
    nt = (double)mesh->triangle_count;
    max_type = opt.metric <= ADASLICE_METRIC_ROUGHNESS;
    inverse = 1.0 / opt.bin;
    bytes = 8 * n * (max_type ? 1 : 2); /* phi, areas */
    if (!sampled) {
        /* the range-maximum table: a level for each doubling of the longest run of bins */
        if (max_type || opt.weights) {
            for (t = 0; t < mesh->triangle_count; t++) {
                const uint32_t *tri = mesh->triangles + 3 * t;
                double a = mesh->vertices[3 * (size_t)tri[0] + 2], b = mesh->vertices[3 * (size_t)tri[1] + 2],
                       c = mesh->vertices[3 * (size_t)tri[2] + 2];
                double run = floor((adaslice__max3(a, b, c) - lo) * inverse) - floor((adaslice__min3(a, b, c) - lo) * inverse) + 1;
                longest = run > longest ? run : longest;
            }
            longest = longest < n ? longest : n;
            bytes += 16 * nt + 8 * n * (floor(log2(longest)) + 1);
        }
        /* the areas' accumulators, and the edges that find an open mesh's gaps */
        if (!max_type) bytes += 8 * (4 * n + 3) + 48 * nt + 4 * ((double)mesh->vertex_count + 1);
        cost->bytes = bytes;
        adaslice__ok(err);
        return ADASLICE_OK;
    }
#ifndef ADASLICE_NO_SAMPLED
    bytes += 8 * nt + n + (max_type ? 0 : 8 * (n + 1) + (opt.weights ? 8 * n : 0) + 48 * nt +
                           4 * ((double)mesh->vertex_count + 1));
    for (axis = ADASLICE_AXIS_X; axis <= ADASLICE_AXIS_Z; axis++) {
        adaslice_grid g = adaslice_grid_fit(mesh, (adaslice_axis)axis, opt.resolution);
        double pixels = 0, rows = 0;
        for (t = 0; t < mesh->triangle_count; t++) {
            double p, w;
            adaslice__raster_size(mesh, t, &g, &p, &w);
            pixels += p;
            rows += w;
        }
        /* rays along x take one sample a span, the others one a pixel */
        cost->samples += axis == ADASLICE_AXIS_X ? rows : pixels;
        if (!max_type && axis == ADASLICE_AXIS_Z) {
            /* the stored LDI: a start per pixel, a count per row, its samples a band at a time */
            double held = pixels * (double)sizeof(adaslice_sample);
            bytes += 8 * ((double)g.width * g.height + 1) + 8 * (double)g.height +
                     (held < (double)opt.memory_limit ? held : (double)opt.memory_limit);
        }
    }
#else
    (void)axis;
#endif
    cost->bytes = bytes;
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_fibonacci_directions(size_t n, double *xyz)
{
    const double golden = 3.14159265358979323846 * (3 - sqrt(5.0));
    size_t i;
    for (i = 0; i < n; i++) {
        double z = 1 - (2.0 * (double)i + 1) / (double)n, r = sqrt(1 - z * z), phi = golden * (double)i;
        xyz[3 * i] = r * cos(phi);
        xyz[3 * i + 1] = r * sin(phi);
        xyz[3 * i + 2] = z;
    }
}

#ifndef ADASLICE_NO_SAMPLED
/* ---- sampled profiles (§3.2, §4.1): the paper's method, from LDIs along x, y, z */

typedef struct adaslice__sampling {
    adaslice_profile *profile;
    const double *face_value;    /* per triangle, see adaslice__face_value */
    double *wmax;                /* per bin, or NULL */
    unsigned char *reached;      /* per bin: some sample fell in it */
    long long *inside;           /* z rays, area: per bin-centre difference counts */
    double inverse_bin;
} adaslice__sampling;

/* Smallest bin index whose centre is at or above z (N if none). */
static size_t adaslice__centre_at_or_above(const adaslice_profile *p, double z)
{
    double f = ceil((z - p->z0) / p->bin - 0.5);
    size_t i;
    if (!(f > 0)) return 0;
    i = f >= (double)p->bin_count ? p->bin_count : (size_t)f;
    while (i > 0 && p->z0 + ((double)(i - 1) + 0.5) * p->bin >= z) i--;
    while (i < p->bin_count && p->z0 + ((double)i + 0.5) * p->bin < z) i++;
    return i;
}

/* Samples straight from the spans, with nothing stored: each covered pixel
   is one sample at its depth (rays along z) or at its row's or column's height
   (rays along x or y). */
typedef struct adaslice__direct {
    adaslice__sampling *s;
    const adaslice_grid *grid;
    double depth_origin;
} adaslice__direct;

static size_t adaslice__sample_bin(const adaslice__sampling *s, double z)
{
    double f = (z - s->profile->z0) * s->inverse_bin;
    if (!(f > 0)) return 0;
    return f >= (double)(s->profile->bin_count - 1) ? s->profile->bin_count - 1 : (size_t)f;
}

/* Samples of one triangle in bins first..last (every bin between them: the
   caller only asks when consecutive samples are at most a bin apart). */
static void adaslice__sample_bins(adaslice__sampling *s, size_t first, size_t last, uint32_t face)
{
    adaslice_profile *p = s->profile;
    double v = s->face_value[face & ~ADASLICE_SAMPLE_LEAVES];
    size_t b;
    for (b = first; b <= last; b++) {
        s->reached[b] = 1;
        if (p->metric <= ADASLICE_METRIC_ROUGHNESS) { if (v > p->phi[b]) p->phi[b] = v; }
        else if (s->wmax && v > s->wmax[b]) s->wmax[b] = v;
    }
}

static void adaslice__sample_one(adaslice__sampling *s, double z, uint32_t face)
{
    size_t b = adaslice__sample_bin(s, z);
    adaslice__sample_bins(s, b, b, face);
}

static void adaslice__direct_visit(void *ctx, const adaslice__span *span)
{
    adaslice__direct *d = ADASLICE__CAST(adaslice__direct *, ctx);
    const adaslice_grid *g = d->grid;
    int i;
    if (g->axis == ADASLICE_AXIS_X) { /* one height for the whole row */
        adaslice__sample_one(d->s, g->origin[1] + (span->row + 0.5) * g->pitch[1], span->face);
    } else if (g->axis == ADASLICE_AXIS_Z && fabs(span->step) <= d->s->profile->bin) {
        /* depth moves at most a bin per pixel: the samples hit every bin
           between the span's two ends, and only those */
        size_t a = adaslice__sample_bin(d->s, adaslice__span_depth(span, span->first) + d->depth_origin);
        size_t b = adaslice__sample_bin(d->s, adaslice__span_depth(span, span->end - 1) + d->depth_origin);
        adaslice__sample_bins(d->s, a < b ? a : b, a < b ? b : a, span->face);
    } else {
        for (i = span->first; i < span->end; i++)
            adaslice__sample_one(d->s, g->axis == ADASLICE_AXIS_Z ? adaslice__span_depth(span, i) + d->depth_origin
                                                                  : g->origin[0] + (i + 0.5) * g->pitch[0], span->face);
    }
}

static void adaslice__sample_band(adaslice__sampling *s, const adaslice_ldi *ldi, int row_first, int row_end)
{
    const adaslice_grid *g = &ldi->grid;
    adaslice_profile *p = s->profile;
    int i, j;
    for (j = row_first; j < row_end; j++) {
        for (i = 0; i < g->width; i++) {
            size_t px = (size_t)(j - row_first) * (size_t)g->width + (size_t)i, k;
            size_t a = ldi->first[px], b = ldi->first[px + 1];
            int winding = 0;
            double entered = 0;
            for (k = a; k < b; k++) {
                const adaslice_sample *smp = &ldi->samples[k];
                double z = g->axis == ADASLICE_AXIS_Z ? smp->depth + ldi->depth_origin
                         : g->axis == ADASLICE_AXIS_X ? g->origin[1] + (j + 0.5) * g->pitch[1]
                                                      : g->origin[0] + (i + 0.5) * g->pitch[0];
                adaslice__sample_one(s, z, smp->face);
                if (s->inside) {
                    /* eq. 13: pixels inside at each bin centre, from the ray's
                       intervals of positive winding number */
                    int before = winding;
                    winding += (smp->face & ADASLICE_SAMPLE_LEAVES) ? -1 : 1;
                    if (before <= 0 && winding > 0) entered = z;
                    if (before > 0 && winding <= 0) {
                        s->inside[adaslice__centre_at_or_above(p, entered)]++;
                        s->inside[adaslice__centre_at_or_above(p, z)]--;
                    }
                }
            }
        }
    }
}

typedef struct adaslice__row_count { size_t *rows; } adaslice__row_count;

static void adaslice__row_visit(void *ctx, const adaslice__span *s)
{
    ADASLICE__CAST(adaslice__row_count *, ctx)->rows[s->row] += (size_t)(s->end - s->first);
}

/* The LDI of one axis, band by band so that a band's pixels and samples stay
   within the memory limit; every band sees every triangle, so the result does
   not depend on where the bands are cut. */
static adaslice_result adaslice__sample_axis(adaslice__sampling *s, const adaslice_mesh *mesh, adaslice_axis axis,
                                             const adaslice_profile_options *opt, adaslice_error *err)
{
    adaslice_allocator *al = &s->profile->allocator;
    adaslice_ldi ldi;
    adaslice__raster r;
    adaslice__row_count rc;
    adaslice_result res = ADASLICE_OK;
    int row = 0;
    memset(&ldi, 0, sizeof ldi);
    ldi.allocator = *al;
    ldi.grid = adaslice_grid_fit(mesh, axis, opt->resolution);
    ldi.depth_origin = adaslice__depth_origin(mesh, axis);
    if (!s->inside) { /* no areas wanted from these rays: nothing to store */
        adaslice__direct d;
        d.s = s;
        d.grid = &ldi.grid;
        d.depth_origin = ldi.depth_origin;
        memset(&r, 0, sizeof r);
        r.grid = &ldi.grid;
        r.depth_origin = ldi.depth_origin;
        r.row_end = ldi.grid.height;
        r.fn = adaslice__direct_visit;
        r.ctx = &d;
        r.progress = opt->progress;
        r.progress_user = opt->progress_user;
        r.progress_lo = (double)axis / 3;
        r.progress_span = 1.0 / 3;
        return adaslice__raster_mesh(&r, mesh, err);
    }
    rc.rows = ADASLICE__CAST(size_t *, adaslice__alloc(al, (size_t)ldi.grid.height, sizeof(size_t)));
    ldi.first = ADASLICE__CAST(size_t *, adaslice__alloc(al, (size_t)ldi.grid.width * ldi.grid.height + 1, sizeof(size_t)));
    if (!rc.rows || !ldi.first) {
        res = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for a %d x %d LDI",
                             ldi.grid.width, ldi.grid.height);
        goto done;
    }
    memset(rc.rows, 0, (size_t)ldi.grid.height * sizeof(size_t));
    memset(&r, 0, sizeof r);
    r.grid = &ldi.grid;
    r.depth_origin = ldi.depth_origin;
    r.row_end = ldi.grid.height;
    r.fn = adaslice__row_visit;
    r.ctx = &rc;
    if ((res = adaslice__raster_mesh(&r, mesh, err)) != ADASLICE_OK) goto done;
    while (row < ldi.grid.height) {
        size_t bytes = 0;
        int end = row;
        while (end < ldi.grid.height) {
            size_t more = rc.rows[end] * sizeof(adaslice_sample) + (size_t)ldi.grid.width * sizeof(size_t);
            if (end > row && bytes + more > opt->memory_limit) break;
            bytes += more;
            end++;
        }
        if ((res = adaslice__ldi_band(mesh, &ldi, row, end, err)) != ADASLICE_OK) goto done;
        adaslice__sample_band(s, &ldi, row, end);
        adaslice__free(al, ldi.samples);
        ldi.samples = NULL;
        row = end;
        if (opt->progress) opt->progress(opt->progress_user, ((double)axis + (double)row / ldi.grid.height) / 3);
    }
done:
    adaslice__free(al, rc.rows);
    adaslice__free(al, ldi.first);
    adaslice__free(al, ldi.samples);
    return res;
}

/* A bin no ray reached (thinner than the spacing of the x and y rays, with no
   surface facing z) takes the larger value of its nearest reached neighbours:
   never zero by mere lack of samples. */
static void adaslice__fill_unreached(double *v, const unsigned char *reached, size_t n)
{
    size_t i = 0, k;
    while (i < n) {
        double fill;
        if (reached[i]) { i++; continue; }
        for (k = i; k < n && !reached[k]; k++) {} /* the run [i, k) */
        fill = i > 0 ? v[i - 1] : 0;
        if (k < n && v[k] > fill) fill = v[k];
        for (; i < k; i++) v[i] = fill;
    }
}

ADASLICE_DEF adaslice_result adaslice_profile_sampled(const adaslice_mesh *mesh,
                                                      const adaslice_profile_options *options,
                                                      adaslice_profile *profile, adaslice_error *err)
{
    adaslice_profile_options opt;
    adaslice__sampling s;
    adaslice_result r;
    double *face_value = NULL;
    size_t n, t, i;
    int axis, max_type;

    if ((r = adaslice__profile_begin(mesh, options, profile, &opt, NULL, 1, err)) != ADASLICE_OK) return r;
    n = profile->bin_count;
    max_type = opt.metric <= ADASLICE_METRIC_ROUGHNESS;
    memset(&s, 0, sizeof s);
    s.profile = profile;
    s.inverse_bin = 1.0 / profile->bin;
    face_value = ADASLICE__CAST(double *, adaslice__alloc(&profile->allocator, mesh->triangle_count, sizeof(double)));
    s.reached = ADASLICE__CAST(unsigned char *, adaslice__alloc(&profile->allocator, n, 1));
    if (opt.weights && !max_type) s.wmax = ADASLICE__CAST(double *, adaslice__alloc(&profile->allocator, n, sizeof(double)));
    if (!max_type) s.inside = ADASLICE__CAST(long long *, adaslice__alloc(&profile->allocator, n + 1, sizeof(long long)));
    if (!face_value || !s.reached || (opt.weights && !max_type && !s.wmax) || (!max_type && !s.inside)) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "profile: out of memory for %zu bins", n);
        goto done;
    }
    for (t = 0; t < mesh->triangle_count; t++) face_value[t] = adaslice__face_value(mesh, t, &opt);
    s.face_value = face_value;
    memset(s.reached, 0, n);
    if (s.wmax) memset(s.wmax, 0, n * sizeof(double));
    if (s.inside) memset(s.inside, 0, (n + 1) * sizeof(long long));
    for (axis = ADASLICE_AXIS_X; axis <= ADASLICE_AXIS_Z; axis++) {
        long long *inside = s.inside;
        if (axis != ADASLICE_AXIS_Z) s.inside = NULL; /* areas come from the z rays */
        r = adaslice__sample_axis(&s, mesh, (adaslice_axis)axis, &opt, err);
        s.inside = inside;
        if (r != ADASLICE_OK) goto done;
    }
    if (opt.progress) opt.progress(opt.progress_user, 1);
    for (i = 0; i < n; i++) profile->unsampled_bins += !s.reached[i];
    if (max_type) {
        adaslice__fill_unreached(profile->phi, s.reached, n);
    } else {
        if (s.wmax) adaslice__fill_unreached(s.wmax, s.reached, n);
        long long count = 0;
        double pixel = 0;
        adaslice_grid gz = adaslice_grid_fit(mesh, ADASLICE_AXIS_Z, opt.resolution);
        pixel = gz.pitch[0] * gz.pitch[1];
        adaslice__gaps *gaps;
        int open;
        for (i = 0; i < n; i++) {
            count += s.inside[i];
            profile->area[i] = (double)count * pixel;
        }
        /* rays cannot read a mesh whose edges do not balance: its areas
           come from its sections, as its masks do */
        if ((r = adaslice__gaps_init(&gaps, mesh, &profile->allocator, err)) != ADASLICE_OK) goto done;
        open = gaps != NULL;
        adaslice__gaps_free(gaps);
        if (open && (r = adaslice__section_areas(mesh, profile->z0, profile->bin, n, profile->area, &profile->allocator,
                                                 err)) != ADASLICE_OK)
            goto done;
        adaslice__phi_from_area(profile, s.wmax);
    }
    r = ADASLICE_OK;
    adaslice__ok(err);
done:
    adaslice__free(&profile->allocator, face_value);
    adaslice__free(&profile->allocator, s.reached);
    adaslice__free(&profile->allocator, s.wmax);
    adaslice__free(&profile->allocator, s.inside);
    if (r != ADASLICE_OK) adaslice_profile_free(profile);
    return r;
}

#endif /* ADASLICE_NO_SAMPLED */

#ifndef ADASLICE_NO_HYBRID
/* ============================================================== hybrid */

/* Every face's incident faces by shared (welded) corner, as CSR: the faces at
   vertex v are face[first[v] .. first[v+1]). Only faces with keep[t] set. */
typedef struct adaslice__fan {
    size_t *first;
    uint32_t *face;
    uint32_t *corner;   /* the welded triangles: 3 per face */
} adaslice__fan;

static void adaslice__fan_free(adaslice__fan *f, const adaslice_allocator *al)
{
    adaslice__free(al, f->first);
    adaslice__free(al, f->face);
    adaslice__free(al, f->corner);
}

static adaslice_result adaslice__fan_make(const adaslice_mesh *mesh, const unsigned char *keep,
                                          const adaslice_allocator *al, adaslice__fan *f, adaslice_error *err)
{
    adaslice_mesh w = *mesh;
    adaslice_weld_options wo;
    float *v = ADASLICE__CAST(float *, adaslice__alloc(al, 3 * mesh->vertex_count, sizeof(float)));
    size_t t, k, n = mesh->triangle_count, nv;
    adaslice_result r;
    memset(f, 0, sizeof *f);
    f->corner = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, 3 * n, sizeof(uint32_t)));
    if (!v || !f->corner) {
        adaslice__free(al, v);
        adaslice__fan_free(f, al);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "hybrid: out of memory for %zu faces", n);
    }
    /* corners equal bit for bit are one: an STL repeats them per face */
    memcpy(v, mesh->vertices, 3 * mesh->vertex_count * sizeof(float));
    memcpy(f->corner, mesh->triangles, 3 * n * sizeof(uint32_t));
    w.vertices = v;
    w.triangles = f->corner;
    memset(&w.allocator, 0, sizeof w.allocator);
    memset(&wo, 0, sizeof wo);
    wo.allocator = al;
    r = adaslice_mesh_weld(&w, &wo, err);
    adaslice__free(al, v);
    nv = w.vertex_count;
    if (r == ADASLICE_OK) {
        f->first = ADASLICE__CAST(size_t *, adaslice__alloc(al, nv + 1, sizeof(size_t)));
        f->face = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, 3 * n, sizeof(uint32_t)));
        if (!f->first || !f->face)
            r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "hybrid: out of memory for %zu faces", n);
    }
    if (r != ADASLICE_OK) {
        adaslice__fan_free(f, al);
        return r;
    }
    memset(f->first, 0, (nv + 1) * sizeof(size_t));
    for (t = 0; t < n; t++)
        for (k = 0; keep[t] && k < 3; k++) f->first[f->corner[3 * t + k] + 1]++;
    for (k = 0; k < nv; k++) f->first[k + 1] += f->first[k];
    for (t = 0; t < n; t++)
        for (k = 0; keep[t] && k < 3; k++) f->face[f->first[f->corner[3 * t + k]]++] = (uint32_t)t;
    for (k = nv; k > 0; k--) f->first[k] = f->first[k - 1];
    f->first[0] = 0;
    return ADASLICE_OK;
}

/* The surface's gradient (dz/dx, dz/dy) over face t, its unit n_z and its
   area; 0 for a face with no area. */
static int adaslice__face_slope(const adaslice_mesh *m, size_t t, double g[2], double *nz, double *area)
{
    double a[3], b[3], c[3], n[3], len;
    adaslice__corner(m, t, 0, a);
    adaslice__corner(m, t, 1, b);
    adaslice__corner(m, t, 2, c);
    adaslice__normal(a, b, c, n);
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) return 0;
    *nz = n[2] / len;
    *area = len / 2;
    g[0] = n[2] != 0 ? -n[0] / n[2] : 0;
    g[1] = n[2] != 0 ? -n[1] / n[2] : 0;
    return 1;
}

/* The reach test on a z LDI: blocked[t] = 1 for a candidate face that some
   ray meets below another surface, or where the mesh rises within `reach` of
   it (xy distance d) more than d tan(max_angle) above it; seen[t] = 1 for a
   face that is some ray's top. */
static adaslice_result adaslice__hybrid_reach(const adaslice_mesh *mesh, const adaslice_hybrid_options *o,
                                              const unsigned char *candidate, unsigned char *blocked,
                                              unsigned char *seen, const adaslice_allocator *al, adaslice_error *err)
{
    adaslice_grid g;
    adaslice_ldi ldi;
    adaslice_ldi_options lo;
    double b0[3], b1[3], g0[2], extent, pitch = o->pitch, slope = tan(o->max_angle * 3.14159265358979323846 / 180), slack;
    float *top;
    int m, di, dj, i, j;
    size_t p, s, t, pixels;
    adaslice_result r;
    adaslice_mesh_bounds(mesh, b0, b1);
    extent = b1[0] - b0[0] > b1[1] - b0[1] ? b1[0] - b0[0] : b1[1] - b0[1];
    if (pitch <= 0) pitch = o->reach / 8; /* 200 rays a disc: the cone's cost stays linear */
    if (pitch < extent / 2048) pitch = extent / 2048;
    /* the float depths and the surface between ray centres on a face as steep as max_angle */
    slack = 1e-4 + 1e-6 * (extent + b1[2] - b0[2]);
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.origin[0] = g0[0] = b0[0];
    g.origin[1] = g0[1] = b0[1];
    g.pitch[0] = g.pitch[1] = pitch;
    g.width = (int)ceil((b1[0] - b0[0]) / pitch) + 1;
    g.height = (int)ceil((b1[1] - b0[1]) / pitch) + 1;
    memset(&lo, 0, sizeof lo);
    lo.allocator = al;
    if ((r = adaslice_ldi_build(mesh, &g, &lo, &ldi, err)) != ADASLICE_OK) return r;
    pixels = (size_t)g.width * (size_t)g.height;
    top = ADASLICE__CAST(float *, adaslice__alloc(al, pixels, sizeof(float)));
    if (!top) {
        adaslice_ldi_free(&ldi);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "hybrid: out of memory for %zu rays", pixels);
    }
    for (p = 0; p < pixels; p++) {
        size_t a = ldi.first[p], e = ldi.first[p + 1];
        top[p] = a < e ? ldi.samples[e - 1].depth : -FLT_MAX;
        for (s = a; s + 1 < e; s++) /* under another surface: an overhang, or inside */
            if (candidate[ADASLICE_SAMPLE_FACE(ldi.samples[s])]) blocked[ADASLICE_SAMPLE_FACE(ldi.samples[s])] = 1;
    }
    m = (int)floor(o->reach / pitch);
    for (j = 0; j < g.height; j++)
        for (i = 0; i < g.width; i++) {
            size_t q = (size_t)j * g.width + i;
            uint32_t t;
            if (ldi.first[q] == ldi.first[q + 1]) continue;
            t = ADASLICE_SAMPLE_FACE(ldi.samples[ldi.first[q + 1] - 1]);
            if (!candidate[t]) continue;
            seen[t] = 1;
            for (dj = -m; dj <= m && !blocked[t]; dj++) {
                if (j + dj < 0 || j + dj >= g.height) continue;
                for (di = -m; di <= m; di++) {
                    double d = pitch * sqrt((double)di * di + (double)dj * dj);
                    if (d > o->reach || i + di < 0 || i + di >= g.width) continue;
                    if (top[q + (ptrdiff_t)dj * g.width + di] - top[q] > d * slope + slack) { blocked[t] = 1; break; }
                }
            }
        }
    /* A face too small for any ray is judged at the ray nearest its centroid:
       clear if that ray's top is a clear candidate on its plane there (the
       two faces meet within the ray's reach of each other), else planar. */
    for (t = 0; t < mesh->triangle_count; t++) {
        double c[3] = {0, 0, 0}, v[3], grad[2], nz, area, x, y;
        size_t q, e;
        int k;
        if (!candidate[t] || seen[t] || blocked[t]) continue;
        for (k = 0; k < 3; k++) {
            adaslice__corner(mesh, t, k, v);
            c[0] += v[0] / 3; c[1] += v[1] / 3; c[2] += v[2] / 3;
        }
        i = (int)floor((c[0] - g0[0]) / pitch);
        j = (int)floor((c[1] - g0[1]) / pitch);
        q = (size_t)j * g.width + i;
        e = ldi.first[q + 1];
        x = g0[0] + (i + 0.5) * pitch;
        y = g0[1] + (j + 0.5) * pitch;
        adaslice__face_slope(mesh, t, grad, &nz, &area);
        blocked[t] = 2;
        if (e > ldi.first[q] && candidate[ADASLICE_SAMPLE_FACE(ldi.samples[e - 1])] &&
            !blocked[ADASLICE_SAMPLE_FACE(ldi.samples[e - 1])] &&
            fabs(ldi.depth_origin + top[q] - (c[2] + grad[0] * (x - c[0]) + grad[1] * (y - c[1]))) <= 2 * pitch * slope + slack)
            blocked[t] = 0;
    }
    adaslice__free(al, top);
    adaslice_ldi_free(&ldi);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_hybrid_faces(const adaslice_mesh *mesh, const adaslice_hybrid_options *options,
                                                   float *residual, float *weights, adaslice_hybrid_report *report,
                                                   adaslice_error *err)
{
    adaslice_hybrid_options o;
    adaslice_hybrid_report rep;
    adaslice_allocator al;
    adaslice__fan fan;
    unsigned char *flag;
    double *slope, cos_max;
    size_t t, n, k, x;
    adaslice_result r;
    if (options) o = *options; else memset(&o, 0, sizeof o);
    if (o.max_angle == 0) o.max_angle = ADASLICE_DEFAULT_MAX_ANGLE;
    if (o.reach == 0) o.reach = ADASLICE_DEFAULT_REACH;
    if (o.resolution == 0) o.resolution = ADASLICE_DEFAULT_PATH_RESOLUTION;
    if (o.tmin == 0) o.tmin = ADASLICE_DEFAULT_TMIN;
    if (o.tmax == 0) o.tmax = ADASLICE_DEFAULT_TMAX;
    if (o.rise == 0) o.rise = o.tmax / 2;
    if (!(o.max_angle > 0 && o.max_angle <= 45))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "hybrid: max angle %g degrees is outside (0, 45]", o.max_angle);
    if (!(o.reach > 0 && o.resolution > 0 && o.rise > 0 && o.tmin > 0 && o.tmax >= o.tmin && o.pitch >= 0) ||
        o.reach > 1e6 || o.resolution > 1e6 || o.tmax > 1e6 || o.pitch > 1e6)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "hybrid: reach %g, resolution %g, rise %g, tmin %g, tmax %g and pitch %g mm must be positive "
                              "(pitch 0: default) and tmin <= tmax", o.reach, o.resolution, o.rise, o.tmin, o.tmax, o.pitch);
    if (!mesh || !mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "hybrid: the mesh has no triangles");
    if (!residual) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "hybrid: no residual array given");
    n = mesh->triangle_count;
    al = adaslice__allocator(o.allocator);
    cos_max = cos(o.max_angle * 3.14159265358979323846 / 180);
    /* per face: candidate, blocked, seen (flag + 0, n, 2n); gradient and n_z (slope + 3t) */
    flag = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, 3, n));
    slope = ADASLICE__CAST(double *, adaslice__alloc(&al, 3 * n, sizeof(double)));
    if (!flag || !slope) {
        adaslice__free(&al, flag);
        adaslice__free(&al, slope);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "hybrid: out of memory for %zu faces", n);
    }
    memset(flag, 0, 3 * n);
    memset(&rep, 0, sizeof rep);
    for (t = 0; t < n; t++) {
        double area;
        flag[t] = adaslice__face_slope(mesh, t, slope + 3 * t, slope + 3 * t + 2, &area) && slope[3 * t + 2] >= cos_max;
        rep.candidates += flag[t];
    }
    r = adaslice__hybrid_reach(mesh, &o, flag, flag + n, flag + 2 * n, &al, err);
    if (r == ADASLICE_OK) r = adaslice__fan_make(mesh, flag, &al, &fan, err);
    if (r != ADASLICE_OK) {
        adaslice__free(&al, flag);
        adaslice__free(&al, slope);
        return r;
    }
    rep.clamp = o.tmax / 2 > o.rise ? o.tmax / 2 - o.rise : 0;
    for (t = 0; t < n; t++) {
        double change = 0, rt;
        residual[t] = -1;
        if (!flag[t]) continue;
        if (flag[n + t]) { rep.blocked++; continue; }
        /* Z is exact at path points resolution apart and linear between: a
           segment over a crease whose slope changes by D is off by at most
           resolution * D / 4 (at the crease, halfway), for faces wider than a
           segment; D is the largest gradient change to a reachable candidate
           sharing a corner. */
        for (k = 0; k < 3; k++) {
            uint32_t v = fan.corner[3 * t + k];
            for (x = fan.first[v]; x < fan.first[v + 1]; x++) {
                const double *gn = slope + 3 * (size_t)fan.face[x];
                double dx = slope[3 * t] - gn[0], dy = slope[3 * t + 1] - gn[1];
                if (flag[n + fan.face[x]]) continue;
                if (sqrt(dx * dx + dy * dy) > change) change = sqrt(dx * dx + dy * dy);
            }
        }
        rt = rep.clamp + o.resolution * change / 4;
        /* charged per mm of the thinnest layer, so any layer's charge covers
           it; not worth it where that is more than the stair step's */
        if (rt / o.tmin >= slope[3 * t + 2]) { rep.costly++; continue; }
        residual[t] = (float)rt;
        rep.contoured++;
        for (k = 0; k < 3; k++) {
            double c[3];
            adaslice__corner(mesh, t, (int)k, c);
            if (rep.contoured == 1 && k == 0) rep.z_low = rep.z_high = c[2];
            rep.z_low = c[2] < rep.z_low ? c[2] : rep.z_low;
            rep.z_high = c[2] > rep.z_high ? c[2] : rep.z_high;
        }
        {
            double g[2], nz, area;
            adaslice__face_slope(mesh, t, g, &nz, &area);
            rep.area += area;
        }
        if (rt > rep.residual) rep.residual = rt;
        if (weights) weights[t] *= (float)(rt / (o.tmin * slope[3 * t + 2]));
    }
    adaslice__fan_free(&fan, &al);
    adaslice__free(&al, flag);
    adaslice__free(&al, slope);
    if (report) *report = rep;
    adaslice__ok(err);
    return ADASLICE_OK;
}
#endif /* ADASLICE_NO_HYBRID */

ADASLICE_DEF void adaslice_profile_free(adaslice_profile *profile)
{
    if (!profile) return;
    adaslice__free(&profile->allocator, profile->phi);
    adaslice__free(&profile->allocator, profile->area);
    memset(profile, 0, sizeof *profile);
}


#if !defined(ADASLICE_NO_WEIGHTS) || !defined(ADASLICE_NO_ORIENT)
/* LSD radix sort of keys by bytes, carrying a payload each and skipping the
   bytes all keys share; tmp and tmp_payload are scratch. */
static void adaslice__sort_keys(uint64_t *key, uint32_t *payload, uint64_t *tmp, uint32_t *tmp_payload, size_t n)
{
    size_t count[256], i;
    uint64_t *from = key, *to = tmp, *swap;
    uint32_t *pfrom = payload, *pto = tmp_payload, *pswap;
    int shift;
    for (shift = 0; shift < 64; shift += 8) {
        size_t sum = 0;
        memset(count, 0, sizeof count);
        for (i = 0; i < n; i++) count[(from[i] >> shift) & 255]++;
        if (n && count[(from[0] >> shift) & 255] == n) continue;
        for (i = 0; i < 256; i++) { size_t c = count[i]; count[i] = sum; sum += c; }
        for (i = 0; i < n; i++) {
            size_t at = count[(from[i] >> shift) & 255]++;
            to[at] = from[i];
            pto[at] = pfrom[i];
        }
        swap = from; from = to; to = swap;
        pswap = pfrom; pfrom = pto; pto = pswap;
    }
    if (from != key) {
        memcpy(key, from, n * sizeof *key);
        memcpy(payload, pfrom, n * sizeof *payload);
    }
}
#endif

#ifndef ADASLICE_NO_WEIGHTS
/* ---- weights: mean curvature */

/* Twice the area of triangle t and the cotangents of its angles; 0 when it
   has no area (repeated corners included), which callers skip. */
static double adaslice__cotangents(const float *v, const uint32_t *t, double cot[3])
{
    double e[3][3], n[3], len;
    int k, j;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return 0;
    for (k = 0; k < 3; k++) /* e[k]: the edge opposite corner k, from corner k+1 to k+2 */
        for (j = 0; j < 3; j++)
            e[k][j] = (double)v[3 * (size_t)t[(k + 2) % 3] + j] - v[3 * (size_t)t[(k + 1) % 3] + j];
    n[0] = e[1][1] * e[2][2] - e[1][2] * e[2][1];
    n[1] = e[1][2] * e[2][0] - e[1][0] * e[2][2];
    n[2] = e[1][0] * e[2][1] - e[1][1] * e[2][0];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) return 0;
    for (k = 0; k < 3; k++) { /* the angle at k lies between e[k+2] and -e[k+1] */
        const double *a = e[(k + 2) % 3], *b = e[(k + 1) % 3];
        cot[k] = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / len;
    }
    return len;
}

/* |H| per vertex into H and the mixed area into area (both nv long); see
   adaslice_mean_curvature. */
static adaslice_result adaslice__curvature(const float *v, size_t nv, const uint32_t *tri, size_t nt,
                                           const adaslice_allocator *al, double *H, double *area, adaslice_error *err)
{
    double *lap = ADASLICE__CAST(double *, adaslice__alloc(al, nv, 3 * sizeof(double)));
    uint64_t *keys = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, nt, 6 * sizeof(uint64_t)));
    uint32_t *third = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, nt, 6 * sizeof(uint32_t)));
    unsigned char *irregular = ADASLICE__CAST(unsigned char *, adaslice__alloc(al, nv, 1));
    size_t t, i, j, edges = 0;
    int k;
    if (!lap || !keys || !third || !irregular) {
        adaslice__free(al, lap);
        adaslice__free(al, keys);
        adaslice__free(al, third);
        adaslice__free(al, irregular);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "curvature: out of memory for %zu triangles", nt);
    }
    memset(lap, 0, nv * 3 * sizeof(double));
    memset(area, 0, nv * sizeof(double));
    memset(irregular, 0, nv);
    for (t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        double cot[3], twice = adaslice__cotangents(v, c, cot), l2[3];
        int obtuse = -1;
        if (twice == 0) continue;
        for (k = 0; k < 3; k++) { /* edge k joins corners k+1 and k+2 */
            uint32_t a = c[(k + 1) % 3], b = c[(k + 2) % 3];
            const float *p = v + 3 * (size_t)a, *q = v + 3 * (size_t)b;
            l2[k] = 0;
            for (j = 0; j < 3; j++) {
                double d = (double)q[j] - p[j];
                lap[3 * (size_t)a + j] += cot[k] * d;
                lap[3 * (size_t)b + j] -= cot[k] * d;
                l2[k] += d * d;
            }
            if (cot[k] < 0) obtuse = k;
            third[edges] = c[k];
            keys[edges++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
        /* Meyer's mixed area: the Voronoi part where the triangle is not
           obtuse, else half its area to the obtuse corner, a quarter to each other */
        for (k = 0; k < 3; k++) {
            double share = obtuse < 0 ? (l2[(k + 1) % 3] * cot[(k + 1) % 3] + l2[(k + 2) % 3] * cot[(k + 2) % 3]) / 8
                         : twice / (obtuse == k ? 4 : 8);
            area[c[k]] += share;
        }
    }
    /* a full fan needs every edge between exactly two triangles that are not
       the same one twice (scans have two-sided flaps of duplicate faces) */
    adaslice__sort_keys(keys, third, keys + 3 * nt, third + 3 * nt, edges);
    for (i = 0; i < edges; i = j) {
        for (j = i + 1; j < edges && keys[j] == keys[i]; j++) {}
        if (j - i != 2 || third[i] == third[i + 1]) irregular[keys[i] >> 32] = irregular[keys[i] & 0xffffffffu] = 1;
    }
    for (i = 0; i < nv; i++) {
        const double *d = lap + 3 * i;
        H[i] = area[i] > 0 && !irregular[i] ? sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (4 * area[i]) : 0;
    }
    /* an incomplete fan takes its regular neighbours' mean: lap holds sum, count */
    memset(lap, 0, nv * 3 * sizeof(double));
    for (t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        double cot[3];
        if (adaslice__cotangents(v, c, cot) == 0) continue;
        for (k = 0; k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3];
            if (irregular[a] && !irregular[b]) { lap[3 * (size_t)a] += H[b]; lap[3 * (size_t)a + 1] += 1; }
            if (irregular[b] && !irregular[a]) { lap[3 * (size_t)b] += H[a]; lap[3 * (size_t)b + 1] += 1; }
        }
    }
    for (i = 0; i < nv; i++)
        if (irregular[i] && lap[3 * i + 1] > 0) H[i] = lap[3 * i] / lap[3 * i + 1];
    adaslice__free(al, lap);
    adaslice__free(al, keys);
    adaslice__free(al, third);
    adaslice__free(al, irregular);
    return ADASLICE_OK;
}

/* A mesh welded on a copy, with |H| and the mixed area per welded vertex;
   t holds the caller's triangles on the welded vertices, in the same order. */
typedef struct adaslice__surface {
    size_t nv, nt;
    float *v;
    uint32_t *t;
    double *H, *area;
} adaslice__surface;

static void adaslice__surface_free(adaslice__surface *s, const adaslice_allocator *al)
{
    adaslice__free(al, s->v);
    adaslice__free(al, s->t);
    adaslice__free(al, s->H);
    adaslice__free(al, s->area);
    memset(s, 0, sizeof *s);
}

/* remap_out (NULL: not wanted) receives each vertex's welded index; the
   caller frees it. */
static adaslice_result adaslice__surface_make(const adaslice_mesh *mesh, double tolerance, const char *who,
                                              const adaslice_allocator *al, adaslice__surface *s, uint32_t **remap_out,
                                              adaslice_error *err)
{
    uint32_t *remap;
    size_t i, n = mesh->vertex_count;
    adaslice_result r;
    memset(s, 0, sizeof *s);
    s->nt = mesh->triangle_count;
    remap = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    s->v = ADASLICE__CAST(float *, adaslice__alloc(al, n, 3 * sizeof(float)));
    s->t = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, s->nt, 3 * sizeof(uint32_t)));
    if (!remap || !s->v || !s->t) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu vertices", who, n);
        goto done;
    }
    if ((r = adaslice__weld_map(mesh->vertices, n, tolerance, al, s->v, remap, &s->nv, err)) != ADASLICE_OK) goto done;
    for (i = 0; i < 3 * s->nt; i++) s->t[i] = remap[mesh->triangles[i]];
    s->H = ADASLICE__CAST(double *, adaslice__alloc(al, s->nv, sizeof(double)));
    s->area = ADASLICE__CAST(double *, adaslice__alloc(al, s->nv, sizeof(double)));
    if (!s->H || !s->area) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu vertices", who, s->nv);
        goto done;
    }
    r = adaslice__curvature(s->v, s->nv, s->t, s->nt, al, s->H, s->area, err);
done:
    if (r == ADASLICE_OK && remap_out) *remap_out = remap;
    else adaslice__free(al, remap);
    if (r != ADASLICE_OK) adaslice__surface_free(s, al);
    return r;
}

ADASLICE_DEF adaslice_result adaslice_mean_curvature(const adaslice_mesh *mesh, double *curvature,
                                                     const adaslice_surface_options *options, adaslice_error *err)
{
    adaslice_allocator al;
    adaslice__surface s;
    adaslice_result r;
    uint32_t *remap = NULL;
    double tolerance = options ? options->weld_tolerance : 0;
    size_t i;
    if ((r = adaslice__mesh_check(mesh, "curvature", err)) != ADASLICE_OK) return r;
    if (!curvature) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: no output given");
    if ((r = adaslice__tolerance_check(tolerance, "curvature", err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(options ? options->allocator : NULL);
    if ((r = adaslice__surface_make(mesh, tolerance, "curvature", &al, &s, &remap, err)) != ADASLICE_OK) return r;
    for (i = 0; i < mesh->vertex_count; i++) curvature[i] = s.H[remap[i]];
    adaslice__free(&al, remap);
    adaslice__surface_free(&s, &al);
    adaslice__ok(err);
    return ADASLICE_OK;
}

/* ---- saliency */

/* Points bucketed by the cell of a uniform grid: members[first[c] ..
   first[c+1]) are the points of cell c, whose coordinates (21 bits each from
   the grid's origin) are packed in key[c]; a hash table finds a cell by key. */
typedef struct adaslice__cells {
    double origin[3], inverse;
    size_t count, cap;
    uint64_t *key;
    uint32_t *first, *member, *slot;
} adaslice__cells;

#define ADASLICE__CELL_BITS 21

static void adaslice__cells_free(adaslice__cells *g, const adaslice_allocator *al)
{
    adaslice__free(al, g->key);
    adaslice__free(al, g->first);
    adaslice__free(al, g->member);
    adaslice__free(al, g->slot);
    memset(g, 0, sizeof *g);
}

static uint64_t adaslice__cell_key(const adaslice__cells *g, const float *p)
{
    uint64_t key = 0;
    int k;
    for (k = 2; k >= 0; k--) {
        double f = (p[k] - g->origin[k]) * g->inverse;
        key = key << ADASLICE__CELL_BITS | (f > 0 ? (uint64_t)f : 0); /* a centroid may round below the origin */
    }
    return key;
}

/* The slot naming the cell with this key, or the empty one where it would go. */
static size_t adaslice__cell_slot(const adaslice__cells *g, uint64_t key)
{
    size_t h = (size_t)adaslice__mix(key) & (g->cap - 1);
    while (g->slot[h] != ADASLICE__NONE && g->key[g->slot[h]] != key) h = (h + 1) & (g->cap - 1);
    return h;
}

/* Cells `size` wide from `origin`, which lies at or below every point; the
   caller keeps the extent under 2^21 cells. Counting sort through the table. */
static adaslice_result adaslice__cells_build(adaslice__cells *g, const float *p, size_t n, const double origin[3],
                                             double size, const adaslice_allocator *al, adaslice_error *err)
{
    uint32_t *cell_of;
    size_t i, c;
    memset(g, 0, sizeof *g);
    memcpy(g->origin, origin, sizeof g->origin);
    g->inverse = 1 / size;
    g->cap = adaslice__table_size(n);
    g->slot = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, g->cap, sizeof(uint32_t)));
    g->key = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, n, sizeof(uint64_t)));
    g->first = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n + 1, sizeof(uint32_t)));
    g->member = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    cell_of = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, sizeof(uint32_t)));
    if (!g->slot || !g->key || !g->first || !g->member || !cell_of) {
        adaslice__free(al, cell_of);
        adaslice__cells_free(g, al);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for a grid of %zu points", n);
    }
    memset(g->slot, 0xff, g->cap * sizeof(uint32_t));
    for (i = 0; i < n; i++) {
        uint64_t key = adaslice__cell_key(g, p + 3 * i);
        size_t h = adaslice__cell_slot(g, key);
        if (g->slot[h] == ADASLICE__NONE) {
            g->key[g->count] = key;
            g->first[g->count] = 0;
            g->slot[h] = (uint32_t)g->count++;
        }
        cell_of[i] = g->slot[h];
        g->first[cell_of[i]]++;
    }
    for (c = 0, i = 0; c < g->count; c++) { uint32_t k = g->first[c]; g->first[c] = (uint32_t)i; i += k; }
    g->first[g->count] = (uint32_t)n;
    for (i = 0; i < n; i++) g->member[g->first[cell_of[i]]++] = (uint32_t)i;
    for (c = g->count; c > 0; c--) g->first[c] = g->first[c - 1]; /* the scatter moved each start to the next */
    g->first[0] = 0;
    adaslice__free(al, cell_of);
    return ADASLICE_OK;
}

#define ADASLICE__CELL_MASK ((1u << ADASLICE__CELL_BITS) - 1)

/* The cells of g within `reach` cells (per axis) of the cell packed in `key`,
   which may come from another grid with the same origin and cell size, into
   out; returns how many. */
static size_t adaslice__cells_near(const adaslice__cells *g, uint64_t key, int reach, uint32_t *out)
{
    int64_t c[3], d[3];
    size_t n = 0;
    int k;
    for (k = 0; k < 3; k++) c[k] = (int64_t)(key >> (ADASLICE__CELL_BITS * k) & ADASLICE__CELL_MASK);
    for (d[2] = c[2] - reach; d[2] <= c[2] + reach; d[2]++)
        for (d[1] = c[1] - reach; d[1] <= c[1] + reach; d[1]++)
            for (d[0] = c[0] - reach; d[0] <= c[0] + reach; d[0]++) {
                uint32_t cell;
                if (d[0] < 0 || d[1] < 0 || d[2] < 0 || d[0] > ADASLICE__CELL_MASK || d[1] > ADASLICE__CELL_MASK ||
                    d[2] > ADASLICE__CELL_MASK)
                    continue;
                cell = g->slot[adaslice__cell_slot(g, (uint64_t)d[2] << (2 * ADASLICE__CELL_BITS) |
                                                         (uint64_t)d[1] << ADASLICE__CELL_BITS | (uint64_t)d[0])];
                if (cell != ADASLICE__NONE) out[n++] = cell;
            }
    return n;
}

/* The surface's vertices (those in a triangle with area) with their |H|. */
typedef struct adaslice__points {
    size_t n;
    float *p;
    double *H;
    double lo[3];
} adaslice__points;

/* The sums of w n and w h over the candidates (columns x, y, z, h, n of
   `stride` floats; count a multiple of 4), w = exp(-d^2 / (2 sigma^2)) for
   those within 2 sigma of p (r2 = 4 sigma^2, scale = 1 / (2 sigma^2)).
   Branch-free in four lanes, which compilers can run as one vector (clang
   does, at twice the speed); exp(-t) on
   [0, 2] is e^-1 times the Taylor series of e^s, s = 1 - t, to degree 8:
   within 7e-6 relative. */
static void adaslice__gauss_sums(const float *c, size_t count, size_t stride, const float p[3], float scale,
                                 float r2, double out[2])
{
    float h[4] = {0, 0, 0, 0}, n[4] = {0, 0, 0, 0};
    size_t i;
    int l;
    for (i = 0; i < count; i += 4)
        for (l = 0; l < 4; l++) {
            float dx = c[i + l] - p[0], dy = c[stride + i + l] - p[1], dz = c[2 * stride + i + l] - p[2];
            float d2 = dx * dx + dy * dy + dz * dz, s = 1 - d2 * scale;
            float w = 0.36787944f * (1 + s * (1 + s * (1.0f / 2 + s * (1.0f / 6 + s * (1.0f / 24 + s * (1.0f / 120 +
                      s * (1.0f / 720 + s * (1.0f / 5040 + s * (1.0f / 40320)))))))));
            w = d2 < r2 ? w : 0;
            h[l] += w * c[3 * stride + i + l];
            n[l] += w * c[4 * stride + i + l];
        }
    out[0] = ((double)n[0] + n[1]) + ((double)n[2] + n[3]);
    out[1] = ((double)h[0] + h[1]) + ((double)h[2] + h[3]);
}

/* G(sigma) at every point: the Gaussian-weighted mean |H| within 2 sigma, over
   cells sigma/3 wide pooled at their centroids (see adaslice_saliency). */
static adaslice_result adaslice__gaussian_mean(const adaslice__points *pt, double sigma, double *G,
                                               const adaslice_allocator *al, adaslice_error *err)
{
    adaslice__cells pool, centres, queries;
    float *cp = NULL, *cw = NULL, *cand = NULL;
    uint32_t near[125];
    size_t c, q, m, k;
    float r2 = (float)(4 * sigma * sigma), scale = (float)(0.5 / (sigma * sigma));
    adaslice_result r;
    memset(&centres, 0, sizeof centres);
    memset(&queries, 0, sizeof queries);
    if ((r = adaslice__cells_build(&pool, pt->p, pt->n, pt->lo, sigma / 3, al, err)) != ADASLICE_OK) return r;
    m = pool.count;
    cp = ADASLICE__CAST(float *, adaslice__alloc(al, m, 3 * sizeof(float)));
    cw = ADASLICE__CAST(float *, adaslice__alloc(al, m, 2 * sizeof(float)));
    cand = ADASLICE__CAST(float *, adaslice__alloc(al, m + 3, 5 * sizeof(float)));
    if (!cp || !cw || !cand) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu cells", m);
        goto done;
    }
    for (c = 0; c < m; c++) {
        double s[3] = {0, 0, 0}, h = 0;
        uint32_t a = pool.first[c], b = pool.first[c + 1], j;
        for (j = a; j < b; j++) {
            const float *p = pt->p + 3 * (size_t)pool.member[j];
            s[0] += p[0]; s[1] += p[1]; s[2] += p[2];
            h += pt->H[pool.member[j]];
        }
        for (k = 0; k < 3; k++) cp[3 * c + k] = (float)(s[k] / (b - a));
        cw[2 * c] = (float)h; /* the cell's sum of |H| and its count */
        cw[2 * c + 1] = (float)(b - a);
    }
    if ((r = adaslice__cells_build(&centres, cp, m, pt->lo, sigma, al, err)) != ADASLICE_OK ||
        (r = adaslice__cells_build(&queries, pt->p, pt->n, pt->lo, sigma, al, err)) != ADASLICE_OK)
        goto done;
    /* a point sees the centres within 2 sigma, all in the 5^3 cells around its own */
    for (q = 0; q < queries.count; q++) {
        size_t cells = adaslice__cells_near(&centres, queries.key[q], 2, near), count = 0;
        float *x = cand, *y = cand + m + 3, *z = cand + 2 * (m + 3), *hs = cand + 3 * (m + 3), *ns = cand + 4 * (m + 3);
        /* the centres of those cells, as columns x, y, z, sum of |H|, count */
        for (k = 0; k < cells; k++) {
            uint32_t j;
            for (j = centres.first[near[k]]; j < centres.first[near[k] + 1]; j++) {
                uint32_t e = centres.member[j];
                x[count] = cp[3 * (size_t)e]; y[count] = cp[3 * (size_t)e + 1]; z[count] = cp[3 * (size_t)e + 2];
                hs[count] = cw[2 * (size_t)e]; ns[count] = cw[2 * (size_t)e + 1];
                count++;
            }
        }
        while (count % 4) { /* weightless copies of the first fill the last lanes */
            x[count] = x[0]; y[count] = y[0]; z[count] = z[0]; hs[count] = ns[count] = 0;
            count++;
        }
        for (k = queries.first[q]; k < queries.first[q + 1]; k++) {
            uint32_t v = queries.member[k];
            double sums[2];
            adaslice__gauss_sums(cand, count, m + 3, pt->p + 3 * (size_t)v, scale, r2, sums);
            G[v] = sums[1] / sums[0]; /* the point's own cell is within sigma: the weight is positive */
        }
    }
    r = ADASLICE_OK;
done:
    adaslice__cells_free(&pool, al);
    adaslice__cells_free(&centres, al);
    adaslice__cells_free(&queries, al);
    adaslice__free(al, cp);
    adaslice__free(al, cw);
    adaslice__free(al, cand);
    return r;
}

/* Itti's normalisation of one map S (changed in place): S / max, times
   (1 - m)^2 with m the mean of the local maxima other than the global one. A
   point is a local maximum when no point within `radius` has a larger value. */
static adaslice_result adaslice__normalise_map(const adaslice__points *pt, double *S, double radius,
                                               const adaslice_allocator *al, adaslice_error *err)
{
    adaslice__cells g;
    uint32_t near[27];
    size_t i, c, k, top = 0, others = 0;
    double sum = 0, r2 = radius * radius, factor;
    adaslice_result r;
    for (i = 1; i < pt->n; i++) if (S[i] > S[top]) top = i;
    if (!(S[top] > 0)) return ADASLICE_OK; /* a flat map stays 0 */
    if ((r = adaslice__cells_build(&g, pt->p, pt->n, pt->lo, radius, al, err)) != ADASLICE_OK) return r;
    for (c = 0; c < g.count; c++) {
        size_t cells = adaslice__cells_near(&g, g.key[c], 1, near), m;
        for (m = g.first[c]; m < g.first[c + 1]; m++) {
            uint32_t v = g.member[m], j;
            const float *p = pt->p + 3 * (size_t)v;
            int peak = v != top;
            for (k = 0; k < cells && peak; k++)
                for (j = g.first[near[k]]; j < g.first[near[k] + 1] && peak; j++) {
                    const float *o = pt->p + 3 * (size_t)g.member[j];
                    double dx = (double)o[0] - p[0], dy = (double)o[1] - p[1], dz = (double)o[2] - p[2];
                    if (S[g.member[j]] > S[v] && dx * dx + dy * dy + dz * dz <= r2) peak = 0;
                }
            if (peak) { sum += S[v]; others++; }
        }
    }
    adaslice__cells_free(&g, al);
    factor = others ? 1 - sum / (others * S[top]) : 1;
    factor = factor * factor / S[top];
    for (i = 0; i < pt->n; i++) S[i] *= factor;
    return ADASLICE_OK;
}

/* sigma / eps for the G maps; the surround of scale i (sigma = 2..6 eps) is
   map SURROUND[i]. */
static const double adaslice__sigmas[8] = {2, 3, 4, 5, 6, 8, 10, 12};
static const int adaslice__surround[5] = {2, 4, 5, 6, 7};
#define ADASLICE__SALIENCY_EPS 0.003 /* eps: 0.3% of the bounding box's diagonal (Lee et al.) */

/* Saliency per point into out (pt->n long). */
static adaslice_result adaslice__saliency_points(const adaslice__points *pt, double eps, double *out,
                                                 const adaslice_allocator *al, adaslice_error *err)
{
    double *G = ADASLICE__CAST(double *, adaslice__alloc(al, pt->n, 9 * sizeof(double))), *S;
    size_t i;
    int s;
    adaslice_result r = ADASLICE_OK;
    if (!G) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu vertices", pt->n);
    S = G + 8 * pt->n;
    for (s = 0; s < 8 && r == ADASLICE_OK; s++)
        r = adaslice__gaussian_mean(pt, adaslice__sigmas[s] * eps, G + s * pt->n, al, err);
    memset(out, 0, pt->n * sizeof(double));
    for (s = 0; s < 5 && r == ADASLICE_OK; s++) {
        const double *centre = G + s * pt->n, *surround = G + adaslice__surround[s] * pt->n;
        for (i = 0; i < pt->n; i++) S[i] = fabs(centre[i] - surround[i]);
        if ((r = adaslice__normalise_map(pt, S, adaslice__sigmas[s] * eps, al, err)) != ADASLICE_OK) break;
        for (i = 0; i < pt->n; i++) out[i] += S[i];
    }
    adaslice__free(al, G);
    return r;
}

/* The mean saliency of triangle t's corners; index maps welded vertices to
   points (NONE: off the surface, 0). */
static double adaslice__face_saliency(const adaslice__surface *s, const uint32_t *index, const double *sal, size_t t)
{
    double w = 0;
    int k;
    for (k = 0; k < 3; k++) {
        uint32_t j = index[s->t[3 * t + k]];
        if (j != ADASLICE__NONE) w += sal[j];
    }
    return w / 3;
}

/* Caps each |H| at the largest of its neighbours': a single vertex cannot
   show a feature, and lone spikes (slivers, the tents decimation leaves)
   would otherwise set the maximum every map is divided by. top is scratch. */
static void adaslice__cap_spikes(const adaslice__surface *s, double *top)
{
    size_t t, i;
    int k;
    memset(top, 0, s->nv * sizeof(double));
    for (t = 0; t < s->nt; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = s->t[3 * t + k], b = s->t[3 * t + (k + 1) % 3];
            if (a == b) continue;
            if (s->H[b] > top[a]) top[a] = s->H[b];
            if (s->H[a] > top[b]) top[b] = s->H[a];
        }
    for (i = 0; i < s->nv; i++) if (s->H[i] > top[i]) s->H[i] = top[i];
}

ADASLICE_DEF adaslice_result adaslice_saliency(const adaslice_mesh *mesh, float *face_weight,
                                               const adaslice_surface_options *options, adaslice_error *err)
{
    adaslice_surface_options opt;
    adaslice_allocator al;
    adaslice__surface s;
    adaslice__points pt;
    uint32_t *index = NULL;
    double *sal = NULL, hi[3] = {0, 0, 0}, diagonal = 0, top = 0;
    size_t i, t;
    int k;
    adaslice_result r;
    if ((r = adaslice__mesh_check(mesh, "saliency", err)) != ADASLICE_OK) return r;
    if (!face_weight) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "saliency: no output given");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if ((r = adaslice__tolerance_check(opt.weld_tolerance, "saliency", err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(opt.allocator);
    if ((r = adaslice__surface_make(mesh, opt.weld_tolerance, "saliency", &al, &s, NULL, err)) != ADASLICE_OK) return r;
    memset(&pt, 0, sizeof pt);
    pt.p = ADASLICE__CAST(float *, adaslice__alloc(&al, s.nv, 3 * sizeof(float)));
    pt.H = ADASLICE__CAST(double *, adaslice__alloc(&al, s.nv, sizeof(double)));
    sal = ADASLICE__CAST(double *, adaslice__alloc(&al, s.nv, sizeof(double)));
    index = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, s.nv, sizeof(uint32_t)));
    if (!pt.p || !pt.H || !sal || !index) {
        r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "saliency: out of memory for %zu vertices", s.nv);
        goto done;
    }
    adaslice__cap_spikes(&s, sal);
    for (i = 0; i < s.nv; i++) {
        index[i] = ADASLICE__NONE;
        if (!(s.area[i] > 0)) continue; /* in no triangle with area: not on the surface */
        for (k = 0; k < 3; k++) {
            float c = s.v[3 * i + k];
            pt.p[3 * pt.n + k] = c;
            if (!pt.n || c < pt.lo[k]) pt.lo[k] = c;
            if (!pt.n || c > hi[k]) hi[k] = c;
        }
        pt.H[pt.n] = s.H[i];
        index[i] = (uint32_t)pt.n++;
    }
    if (!pt.n) {
        r = adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "saliency: the mesh has no triangle with area");
        goto done;
    }
    for (k = 0; k < 3; k++) diagonal += (hi[k] - pt.lo[k]) * (hi[k] - pt.lo[k]);
    /* the curvatures and distances are floats, squared: a part 1e20 mm across
       (or 1e-20) got every weight 1 without a word; 1e-18 .. 1e18 gave the
       same weights as 1 mm */
    if (sqrt(diagonal) < 1e-15 || sqrt(diagonal) > 1e15) {
        r = adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "saliency: the part is %g mm across: outside 1e-15 .. 1e15 mm, "
                           "where its curvatures leave the range of floats", sqrt(diagonal));
        goto done;
    }
    /* a triangle with area has distinct corners: the diagonal is positive */
    r = adaslice__saliency_points(&pt, ADASLICE__SALIENCY_EPS * sqrt(diagonal), sal, &al, err);
    if (r != ADASLICE_OK) goto done;
    for (t = 0; t < s.nt; t++) {
        double w = adaslice__face_saliency(&s, index, sal, t);
        if (w > top) top = w;
    }
    /* w / top never rounds above 1, and the heaviest face is exactly 1 */
    for (t = 0; t < s.nt; t++) face_weight[t] = top > 0 ? (float)(adaslice__face_saliency(&s, index, sal, t) / top) : 1.0f;
done:
    adaslice__surface_free(&s, &al);
    adaslice__free(&al, pt.p);
    adaslice__free(&al, pt.H);
    adaslice__free(&al, sal);
    adaslice__free(&al, index);
    if (r == ADASLICE_OK) adaslice__ok(err);
    return r;
}

/* ---- weights: viewpoint importance */
ADASLICE_DEF adaslice_result adaslice_view_importance(const adaslice_mesh *mesh, float *importance,
                                                      const adaslice_view_options *options, adaslice_error *err)
{
    adaslice_allocator al;
    adaslice_result r;
    adaslice_mesh turned;
    size_t n = options && options->count ? options->count : ADASLICE_DEFAULT_VIEWS, k, t, p, pixels = 0;
    float *depth = NULL;
    uint32_t *face = NULL;
    int res = options && options->resolution ? options->resolution : ADASLICE_DEFAULT_VIEW_RESOLUTION;
    const double *given = options ? options->directions : NULL;
    double *dirs = NULL;
    uint32_t *stamp = NULL, *seen = NULL;
    if ((r = adaslice__mesh_check(mesh, "view importance", err)) != ADASLICE_OK) return r;
    if (!importance) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "view importance: no output given");
    if (!mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "view importance: the mesh has no triangles");
    if (res < 1 || res > 8192)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "view importance: resolution %d is outside 1..8192", res);
    { /* turned in floats, a part near their largest overflowed to inf: a grid of NaN pixels, "out of memory" */
        double across = adaslice__diagonal(mesh);
        if (!(across <= 1e15))
            return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "view importance: the part is %g mm across: over "
                                  "1e15 mm, where its turned views leave the range of floats", across);
    }
    if (n > 1000000 || (given && !options->count))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "view importance: %zu directions (1 to 1000000, and a count "
                              "for the ones given)", given ? options->count : n);
    for (k = 0; given && k < n; k++) {
        const double *d = given + 3 * k;
        int finite = fabs(d[0]) <= DBL_MAX && fabs(d[1]) <= DBL_MAX && fabs(d[2]) <= DBL_MAX;
        if (!finite || (d[0] == 0 && d[1] == 0 && d[2] == 0))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "view importance: direction %zu (%g, %g, %g) is not a "
                                  "direction", k + 1, d[0], d[1], d[2]);
    }
    al = adaslice__allocator(options ? options->allocator : NULL);
    dirs = ADASLICE__CAST(double *, adaslice__alloc(&al, 2 * n, 3 * sizeof(double)));
    stamp = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, mesh->triangle_count, sizeof(uint32_t)));
    seen = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, mesh->triangle_count, sizeof(uint32_t)));
    turned.vertices = NULL;
    if (!dirs || !stamp || !seen) goto nomem;
    if (given) {
        for (k = 0; k < n; k++) {
            /* by the largest component first, so that huge ones do not overflow */
            const double *d = given + 3 * k;
            double big = fabs(d[0]) > fabs(d[1]) ? fabs(d[0]) : fabs(d[1]), len;
            int c;
            if (fabs(d[2]) > big) big = fabs(d[2]);
            for (c = 0; c < 3; c++) dirs[3 * k + c] = d[c] / big;
            len = sqrt(dirs[3 * k] * dirs[3 * k] + dirs[3 * k + 1] * dirs[3 * k + 1] + dirs[3 * k + 2] * dirs[3 * k + 2]);
            for (c = 0; c < 3; c++) dirs[3 * k + c] /= len;
        }
    } else {
        adaslice_fibonacci_directions(2 * n, dirs); /* the first half: z > 0 */
    }
    memset(stamp, 0, mesh->triangle_count * sizeof(uint32_t));
    memset(seen, 0, mesh->triangle_count * sizeof(uint32_t));
    for (k = 0; k < n; k++) {
        double rot[9];
        adaslice_grid g;
        adaslice_rotation_to_z(dirs + 3 * k, rot);
        if (!turned.vertices && !adaslice__turned_copy(mesh, rot, &al, &turned)) goto nomem;
        for (p = 0; p < mesh->vertex_count; p++) adaslice__turn_vertex(rot, mesh->vertices + 3 * p, turned.vertices + 3 * p);
        g = adaslice_grid_fit(&turned, ADASLICE_AXIS_Z, res);
        if ((size_t)g.width * (size_t)g.height > pixels) {
            adaslice__free(&al, depth);
            adaslice__free(&al, face);
            pixels = (size_t)g.width * (size_t)g.height;
            depth = ADASLICE__CAST(float *, adaslice__alloc(&al, pixels, sizeof(float)));
            face = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, pixels, sizeof(uint32_t)));
            if (!depth || !face) goto nomem;
        }
        if ((r = adaslice__nearest_faces(&turned, &g, adaslice__depth_origin(&turned, ADASLICE_AXIS_Z), depth, face, err)) !=
            ADASLICE_OK)
            goto done;
        /* the face a pixel sees counts when it is turned towards the viewer;
           one turned away is nearest only through the hole of an open mesh,
           or by rounding on a silhouette */
        for (p = 0; p < (size_t)g.width * (size_t)g.height; p++) {
            if (face[p] == ADASLICE__NONE || !(face[p] & ADASLICE_SAMPLE_LEAVES)) continue;
            t = face[p] & ~ADASLICE_SAMPLE_LEAVES;
            if (stamp[t] != (uint32_t)(k + 1)) { stamp[t] = (uint32_t)(k + 1); seen[t]++; }
        }
    }
    for (t = 0; t < mesh->triangle_count; t++) importance[t] = (float)((double)seen[t] / (double)n);
    r = ADASLICE_OK;
    adaslice__ok(err);
    goto done;
nomem:
    r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "view importance: out of memory for %zu triangles", mesh->triangle_count);
done:
    adaslice__free(&al, dirs);
    adaslice__free(&al, stamp);
    adaslice__free(&al, seen);
    adaslice__free(&al, depth);
    adaslice__free(&al, face);
    adaslice__free(&al, turned.vertices);
    return r;
}

/* ---- weights: the curvature profile */
/* The bin of height z, the top one included. */
static size_t adaslice__kappa_bin(const adaslice_profile *p, double z)
{
    double f = (z - p->z0) / p->bin;
    if (!(f > 0)) return 0;
    return f >= (double)(p->bin_count - 1) ? p->bin_count - 1 : (size_t)f;
}

ADASLICE_DEF adaslice_result adaslice_curvature_profile(const adaslice_mesh *mesh, const adaslice_profile *profile,
                                                        const adaslice_surface_options *options, double *kappa,
                                                        adaslice_error *err)
{
    adaslice_surface_options opt;
    adaslice_allocator al;
    adaslice__surface s;
    adaslice_result r;
    double *sum, *weight;
    uint32_t *meets;
    size_t n, t, i;
    if ((r = adaslice__mesh_check(mesh, "curvature", err)) != ADASLICE_OK) return r;
    if (!profile || !profile->bin_count || !(profile->bin > 0))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: the profile has no bins");
    if (!kappa) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "curvature: no output given");
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if ((r = adaslice__tolerance_check(opt.weld_tolerance, "curvature", err)) != ADASLICE_OK) return r;
    al = adaslice__allocator(opt.allocator);
    n = profile->bin_count;
    sum = ADASLICE__CAST(double *, adaslice__alloc(&al, n + 1, 2 * sizeof(double)));
    meets = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, n + 1, sizeof(uint32_t)));
    if (!sum || !meets) {
        adaslice__free(&al, sum);
        adaslice__free(&al, meets);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "curvature: out of memory for %zu bins", n);
    }
    if ((r = adaslice__surface_make(mesh, opt.weld_tolerance, "curvature", &al, &s, NULL, err)) != ADASLICE_OK) {
        adaslice__free(&al, sum);
        adaslice__free(&al, meets);
        return r;
    }
    weight = sum + n + 1;
    memset(sum, 0, 2 * (n + 1) * sizeof(double));
    memset(meets, 0, (n + 1) * sizeof(uint32_t));
    /* per-bin differences of area x |H|, area and triangle count, summed up
       below; the count tells empty bins from rounding left in the sums */
    for (t = 0; t < s.nt; t++) {
        const uint32_t *c = s.t + 3 * t;
        double cot[3], area = adaslice__cotangents(s.v, c, cot) / 2, zmin = HUGE_VAL, zmax = -HUGE_VAL, h = 0;
        size_t first, last;
        int k;
        if (area == 0) continue;
        for (k = 0; k < 3; k++) {
            double z = mesh->vertices[3 * (size_t)mesh->triangles[3 * t + k] + 2];
            if (z < zmin) zmin = z;
            if (z > zmax) zmax = z;
            h += s.H[c[k]] / 3;
        }
        first = adaslice__kappa_bin(profile, zmin);
        last = adaslice__kappa_bin(profile, zmax);
        area /= (double)(last - first + 1);
        sum[first] += area * h; sum[last + 1] -= area * h;
        weight[first] += area; weight[last + 1] -= area;
        meets[first]++; meets[last + 1]--;
    }
    {
        double a = 0, w = 0;
        uint32_t count = 0;
        for (i = 0; i < n; i++) {
            a += sum[i]; w += weight[i]; count += meets[i];
            if (!count) a = w = 0; /* no rounding carried across a gap */
            kappa[i] = count && w > 0 && a > 0 ? a / w : 0;
        }
    }
    adaslice__surface_free(&s, &al);
    adaslice__free(&al, sum);
    adaslice__free(&al, meets);
    adaslice__ok(err);
    return ADASLICE_OK;
}

#endif /* ADASLICE_NO_WEIGHTS */

/* ================================================================= plans */

typedef struct adaslice__job {
    const adaslice_profile *profile;
    uint32_t n, lo, hi;
    uint64_t *units;          /* per bin */
    int volume;
    uint64_t slack;
    double quantum;           /* mm (or the metric's unit) per unit */
    unsigned char *forced;    /* per plane, or NULL */
    adaslice_dp dp;
    void *ring;               /* the planner's workspace */
    size_t ring_size;
    int planned;              /* dp holds the plan with the forced planes */
} adaslice__job;

/* Runs the DP with the given eps in units; returns the layer count or
   ADASLICE__UNREACHED. */
static uint32_t adaslice__job_run(adaslice__job *job, uint64_t eps)
{
    uint32_t i;
    (void)adaslice_dp_init(&job->dp, job->ring, job->ring_size, job->n, job->lo, job->hi, eps, job->volume, job->slack);
    for (i = 0; i < job->n; i++)
        adaslice_dp_push(&job->dp, job->units[i], job->forced && job->forced[i + 1] && i + 1 < job->n);
    return adaslice_dp_layers(&job->dp);
}

/* The smallest eps (units) whose optimal plan has at most max_layers layers
   (UNREACHED: any count), found by bisection since the count never grows
   with eps; UINT64_MAX if none. */
static uint64_t adaslice__job_min_eps(adaslice__job *job, uint32_t max_layers)
{
    uint64_t lo = 0, hi = 0, k;
    uint32_t i;
    /* no layer's error exceeds hi bins of the largest value */
    for (i = 0; i < job->n; i++) if (job->units[i] > hi) hi = job->units[i];
    hi = (hi + job->slack) * job->hi;
    k = adaslice__job_run(job, hi);
    if (k == ADASLICE__UNREACHED || k > max_layers) return UINT64_MAX;
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        k = adaslice__job_run(job, mid);
        if (k != ADASLICE__UNREACHED && k <= max_layers) hi = mid; else lo = mid + 1;
    }
    return lo;
}

/* b * phi[i] as units of a power-of-two quantum chosen so the largest layer
   error is about 2^40 units: additive metrics round up, so a plan feasible in
   units is feasible in millimetres; volume rounds to nearest and, unless all
   values were exact, adds a unit per bin to stay on the safe side. */
static void adaslice__quantise(adaslice__job *job)
{
    const adaslice_profile *p = job->profile;
    double top = 0, per_unit = 1;
    int ex = 0;
    uint32_t i;
    for (i = 0; i < job->n; i++)
        if (p->phi[i] > top) top = p->phi[i];
    job->quantum = 1;
    if (top * p->bin > 0) {
        (void)frexp(top * p->bin * job->hi, &ex);
        /* errors under 2^-900 mm in all: a coarser unit, so that b / quantum
           and eps / quantum stay finite (they rounded to inf below 2^-980) */
        ex = ex > -900 ? ex : -900;
        job->quantum = ldexp(1.0, ex - 40);
        per_unit = ldexp(p->bin, 40 - ex); /* b / quantum, exact: a power of two apart */
    }
    job->slack = 0;
    if (job->volume) {
        for (i = 0; i < job->n; i++) {
            double x = p->phi[i] * per_unit, r = floor(x + 0.5);
            if (r != x) job->slack = 1;
            job->units[i] = (uint64_t)r;
        }
    } else {
        /* ceil without a call (x86-64 has no rounding instruction before
           SSE4.1, and a plan along each of a search's directions takes it
           per bin): x is at most 2^40, so its truncation is exact */
        for (i = 0; i < job->n; i++) {
            double x = p->phi[i] * per_unit;
            uint64_t whole = (uint64_t)x;
            job->units[i] = whole + ((double)whole < x);
        }
    }
}

/* A printer's units: eps is exactly eps_units of them. Rounded up (with a
   margin of 2^-40 for the division's rounding) so a plan feasible in units is
   feasible in mm; capped at eps_units + 1 to keep them small on the wire. */
static uint32_t adaslice__printer_units(double phi, double bin, double eps, uint32_t eps_units)
{
    double x = phi * bin / eps * eps_units;
    x += x * (1.0 / 1099511627776.0);
    return x >= eps_units + 1.0 ? eps_units + 1u : (uint32_t)ceil(x);
}

static uint64_t adaslice__eps_units(double eps, double quantum)
{
    double x = eps / quantum;
    return x >= 4.0e18 ? (uint64_t)4000000000000000000ull : (uint64_t)floor(x);
}

ADASLICE_DEF double adaslice_layer_error(const adaslice_profile *p, size_t first, size_t end)
{
    double sum = 0;
    size_t j;
    if (p->metric == ADASLICE_METRIC_VOLUME)
        for (j = first; j < end; j++) sum += fabs(p->phi[j] - p->phi[first]);
    else
        for (j = first; j < end; j++) sum += p->phi[j];
    return sum * p->bin;
}

/* Whether r bins can be cut into layers of lo..hi bins, for every r <= n.
   After lo lengths in a row that can, every longer one can: one layer more
   reaches the next from one of them. */
static void adaslice__tileable(unsigned char *ok, uint32_t n, uint32_t lo, uint32_t hi)
{
    uint32_t r, in_window = 0, run = 1;
    ok[0] = 1;
    for (r = 1; r <= n; r++) {
        if (run >= lo) {
            memset(ok + r, 1, (size_t)n + 1 - r);
            return;
        }
        if (r >= lo) in_window += ok[r - lo];
        if (r >= hi + 1) in_window -= ok[r - hi - 1];
        ok[r] = in_window > 0;
        run = ok[r] ? run + 1 : 0;
    }
}

/* The local greedy of ref. [3] (Dolenc and Makela): each layer is as thick as
   the profile at its bottom plane allows, as if phi stayed at its value there:
   eps / (b phi) bins for additive metrics, and for volume deviation the n with
   b * |phi[s+1] - phi[s]| * n(n-1)/2 <= eps. What the layer really costs is
   only known afterwards: that is what makes it local. */
static double adaslice__greedy_bins(const adaslice_profile *p, uint32_t s, uint32_t n, uint32_t hi, double eps)
{
    double rate = p->phi[s] * p->bin;
    if (p->metric == ADASLICE_METRIC_VOLUME) {
        double d = s + 1 < n ? fabs(p->phi[s + 1] - p->phi[s]) * p->bin : 0;
        return d > 0 ? floor(0.5 + sqrt(0.25 + 2 * eps / d)) : hi;
    }
    return rate > 0 ? floor(eps / rate) : hi;
}

/* The share f of tmax - tmin at x = kappa / kappa_max (the curvature method). */
static double adaslice__mapping(adaslice_mapping m, double x, double alpha)
{
    switch (m) {
    case ADASLICE_MAPPING_EXP: return exp(-alpha * x);
    case ADASLICE_MAPPING_STEP: return x < 0.25 ? 1 : x < 0.5 ? 2.0 / 3 : x < 0.75 ? 1.0 / 3 : 0;
    default: return x < 1 ? 1 - x : 0;
    }
}

/* The curvature planner of the notes: t(z) = tmin + (tmax - tmin) f(k(z) / kmax)
   at the layer's first bin, in whole bins. */
static double adaslice__curvature_bins(const adaslice_profile *p, const adaslice_plan_options *o, double kmax, uint32_t s)
{
    double x = kmax > 0 ? o->curvature[s] / kmax : 0;
    double tau = o->tmin + (o->tmax - o->tmin) * adaslice__mapping(o->mapping, x, o->alpha);
    return floor(tau / p->bin + 0.5);
}

/* Greedy and curvature plans, laid bottom-up: each layer takes the bins its
   method wants, clamped to lo..hi and to what is left, then the nearest
   length at or below (else above) that leaves a rest layers of lo..hi bins
   can fill (ok[], see adaslice__tileable). */
static uint32_t adaslice__bottom_up(const adaslice_profile *p, const adaslice_plan_options *o, double kmax, uint32_t n,
                                    uint32_t lo, uint32_t hi, const unsigned char *ok, uint32_t *planes)
{
    uint32_t s = 0, k = 0;
    planes[k++] = 0;
    while (s < n) {
        double want = o->method == ADASLICE_METHOD_CURVATURE ? adaslice__curvature_bins(p, o, kmax, s)
                                                             : adaslice__greedy_bins(p, s, n, hi, o->eps);
        uint32_t left = n - s, len = want < lo ? lo : want > hi ? hi : (uint32_t)want, pick;
        if (len > left) len = left;
        pick = len;
        while (pick >= lo && !ok[left - pick]) pick--;
        if (pick < lo) { pick = len; while (!ok[left - pick]) pick++; }
        s += pick;
        planes[k++] = s;
    }
    return k;
}

static int adaslice__by_value(const void *a, const void *b)
{
    double x = *ADASLICE__CAST(const double *, a), y = *ADASLICE__CAST(const double *, b);
    return x < y ? -1 : x > y;
}

/* kappa_max, or the 95th percentile of k when it is 0; a negative value
   when out of memory. */
static double adaslice__kappa_max(const adaslice_plan_options *o, uint32_t n, const adaslice_allocator *al)
{
    double *sorted, k;
    if (o->kappa_max > 0) return o->kappa_max;
    sorted = ADASLICE__CAST(double *, adaslice__alloc(al, n, sizeof(double)));
    if (!sorted) return -1;
    memcpy(sorted, o->curvature, n * sizeof(double));
    qsort(sorted, n, sizeof(double), adaslice__by_value);
    k = sorted[(size_t)ceil(ADASLICE_DEFAULT_KAPPA_PERCENTILE * n) - 1];
    adaslice__free(al, sorted);
    return k;
}

static uint32_t adaslice__uniform(uint32_t n, uint32_t len, uint32_t *planes)
{
    uint32_t k = 0, s = 0;
    planes[k++] = 0;
    while (s < n) { s = n - s > len ? s + len : n; planes[k++] = s; }
    return k;
}

static adaslice_result adaslice__plan_fill(const adaslice_profile *p, const uint32_t *planes, uint32_t count,
                                           double eps, adaslice_plan *plan, adaslice_error *err)
{
    uint32_t k;
    adaslice_allocator *al = &plan->allocator;
    plan->layer_count = count - 1;
    plan->planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, count, sizeof(uint32_t)));
    plan->layers = ADASLICE__CAST(adaslice_layer *, adaslice__alloc(al, count, sizeof(adaslice_layer)));
    if (!plan->planes || !plan->layers)
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory for %u layers", (unsigned)count);
    memcpy(plan->planes, planes, count * sizeof(uint32_t));
    plan->eps = eps;
    plan->worst_error = plan->total_error = 0;
    plan->over_eps = 0;
    for (k = 0; k + 1 < count; k++) {
        adaslice_layer *L = &plan->layers[k];
        L->z_bottom = planes[k] * p->bin;
        L->z_top = planes[k + 1] * p->bin;
        L->thickness = (planes[k + 1] - planes[k]) * p->bin;
        L->error = adaslice_layer_error(p, planes[k], planes[k + 1]);
        plan->total_error += L->error;
        if (L->error > plan->worst_error) plan->worst_error = L->error;
        if (L->error > eps) plan->over_eps++;
    }
    return ADASLICE_OK;
}

/* §3.3 pre-pass: a jump of more than `sharp` between consecutive bins forces
   a plane at the upper bin's bottom. A jump is skipped where a plane there
   would leave a stretch, below it or above it, that no layers of lo..hi bins
   can fill (such as two jumps closer than tmin): the pre-pass never makes a
   plan impossible by thickness alone. */
static uint32_t adaslice__sharp_planes(const adaslice_profile *p, uint32_t n, double sharp,
                                       const unsigned char *ok, unsigned char *forced)
{
    uint32_t i, last = 0, count = 0;
    memset(forced, 0, n + 1);
    for (i = 1; i < n; i++) {
        if (fabs(p->phi[i] - p->phi[i - 1]) > sharp && ok[i - last] && ok[n - i]) {
            forced[i] = 1;
            last = i;
            count++;
        }
    }
    return count;
}

/* Fewest layers from plane i to the top, for every i (UNREACHED where none
   within eps): the DP run down from the top on the bins reversed (an
   additive layer error reads the same either way), or for volume deviation,
   whose error hangs on a layer's first bin, straight down in O(N w). */
static void adaslice__layers_above(adaslice__job *job, uint64_t eps, void *ring, size_t ring_size, uint32_t *above)
{
    uint32_t n = job->n, i, l;
    if (!job->volume) {
        adaslice_dp dp;
        (void)adaslice_dp_init(&dp, ring, ring_size, n, job->lo, job->hi, eps, 0, 0);
        above[n] = 0;
        for (i = 1; i <= n; i++) {
            adaslice_dp_push(&dp, job->units[n - i], 0);
            above[n - i] = adaslice_dp_layers(&dp);
        }
        return;
    }
    above[n] = 0;
    for (i = n; i-- > 0;) {
        uint64_t run = 0;
        uint32_t best = ADASLICE__UNREACHED;
        for (l = 1; l <= job->hi && i + l <= n; l++) {
            uint64_t u = job->units[i + l - 1], f = job->units[i];
            run += (u > f ? u - f : f - u) + job->slack;
            if (run > eps) break;
            if (l >= job->lo && above[i + l] != ADASLICE__UNREACHED && above[i + l] + 1 < best) best = above[i + l] + 1;
        }
        above[i] = best;
    }
}

/* The DP pushed on up to plane `to` (no forced plane between), the fewest
   layers to each plane into layers[plane]. */
static void adaslice__layers_to(adaslice__job *job, uint32_t to, uint32_t *layers)
{
    uint32_t at;
    while ((at = adaslice_dp_bins(&job->dp)) < to) {
        adaslice_dp_push(&job->dp, job->units[at], 0);
        layers[at + 1] = adaslice_dp_layers(&job->dp);
    }
}

/* Makes `plane`, which the DP has passed by less than its ring, the last one
   pushed and a forced one: what the DP pushed after it is forgotten, and it
   stands as adaslice_dp_push with `forced` would have left it. */
static void adaslice__dp_force_back(adaslice_dp *dp, uint32_t plane)
{
    ADASLICE_ASSERT(plane <= dp->plane && dp->plane - plane < dp->cap && dp->layers[plane & (dp->cap - 1)] != ADASLICE__UNREACHED);
    dp->plane = dp->floor = dp->reach = plane;
    dp->head = dp->count = dp->scan = 0;
}

/* Workspace for adaslice__sharp_settle: the DP's ring holds twice its
   thickest layer, as settling goes back that far. */
static size_t adaslice__settle_workspace(uint32_t n, uint32_t hi, int volume)
{
    return adaslice__dp_bytes(n, hi, adaslice__ring_size(2 * hi), volume);
}

/* §3.3 without making eps infeasible: the pre-pass's planes (job->forced),
   bottom-up, each kept, moved or dropped so that with the planes kept below
   it a plan within eps exists whose count is at most K0 (no pre-pass) plus
   the planes kept: with L the last plane kept and C the fewest layers up to
   it, a plane f is kept when C + S(L, f) + S(f, N) <= K0 + kept + 1 (S: the
   fewest layers between two planes). That holds at the top by induction, so
   the plan exists and has at most K0 + kept layers. Tried at the plane
   wanted, then 1, 2, ... bins below and above it, up to a thickest layer
   away, never onto or past a neighbour. The DP runs bottom-up once: C +
   S(L, f) is its count at f, and a plane kept is one it goes back to and
   forces, so that it ends as adaslice__job_run with the planes kept would,
   and job->planned says so. job->ring: adaslice__settle_workspace bytes.
   Changes go to *changes (allocated, `*count` of them); returns the planes
   kept, or UNREACHED out of memory. No plan at all within eps: every plane
   is dropped, silently (the error then is the plan's own). */
static uint32_t adaslice__sharp_settle(adaslice__job *job, uint64_t eps, const adaslice_allocator *al,
                                       adaslice_plane_change **changes, size_t *count)
{
    uint32_t n = job->n, i, L = 0, kept = 0, K0, *above, *upto, *wanted, wanted_count = 0;
    size_t cap = 0;
    adaslice_result r;
    *changes = NULL;
    *count = 0;
    for (i = 1; i < n; i++) wanted_count += job->forced[i] != 0;
    if (!wanted_count) return 0;
    above = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, (size_t)n + 1, 2 * sizeof(uint32_t)));
    wanted = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, (size_t)wanted_count + 1, sizeof(uint32_t)));
    if (!above || !wanted) goto nomem;
    upto = above + n + 1;
    for (i = 1, wanted_count = 0; i < n; i++) if (job->forced[i]) wanted[wanted_count++] = i;
    wanted[wanted_count] = n;
    memset(job->forced, 0, (size_t)n + 1);
    adaslice__layers_above(job, eps, job->ring, job->ring_size, above);
    K0 = above[0];
    if (K0 == ADASLICE__UNREACHED) goto done;
    r = adaslice__dp_setup(&job->dp, job->ring, job->ring_size, n, job->lo, job->hi, eps, job->volume, job->slack,
                           adaslice__ring_size(2 * job->hi));
    ADASLICE_ASSERT(r == ADASLICE_OK); /* job->ring: adaslice__settle_workspace bytes */
    (void)r;
    for (i = 0; i < wanted_count; i++) {
        uint32_t c = wanted[i], next = wanted[i + 1], d, placed = 0, reach = c + job->hi < next ? c + job->hi : next - 1;
        int infeasible;
        adaslice__layers_to(job, reach, upto);
        infeasible = upto[c] == ADASLICE__UNREACHED || above[c] == ADASLICE__UNREACHED;
        for (d = 0; d <= job->hi && !placed; d++) {
            int side;
            for (side = 0; side < 2 && !placed; side++) {
                uint32_t f = side ? c + d : c - d;
                if ((side && (d == 0 || f > reach)) || (!side && d >= c - L)) continue;
                if (upto[f] != ADASLICE__UNREACHED && above[f] != ADASLICE__UNREACHED &&
                    (uint64_t)upto[f] + above[f] <= (uint64_t)K0 + kept + 1)
                    placed = f;
            }
        }
        if (placed != c) {
            if (*count == cap) {
                adaslice_plane_change *more = ADASLICE__CAST(adaslice_plane_change *,
                    adaslice__grow(al, *changes, *count, &cap, *count + 1, sizeof(adaslice_plane_change)));
                if (!more) goto nomem;
                *changes = more;
            }
            (*changes)[*count].wanted = c;
            (*changes)[*count].placed = placed;
            (*changes)[(*count)++].infeasible = infeasible;
        }
        if (!placed) continue;
        job->forced[placed] = 1;
        L = placed;
        kept++;
        adaslice__dp_force_back(&job->dp, placed);
    }
    adaslice__layers_to(job, n, upto);
    job->planned = 1;
done:
    adaslice__free(al, above);
    adaslice__free(al, wanted);
    return kept;
nomem:
    adaslice__free(al, *changes);
    *changes = NULL;
    *count = 0;
    kept = ADASLICE__UNREACHED;
    goto done;
}

static adaslice_result adaslice__plan_optimal(adaslice__job *job, const adaslice_plan_options *opt,
                                              double eps, adaslice_plan *plan, adaslice_error *err)
{
    const adaslice_profile *p = job->profile;
    uint64_t eps_units;
    uint32_t layers, i, k;
    uint32_t *planes;
    adaslice_result r;
    if (opt->eps_units) {
        for (i = 0; i < job->n; i++) job->units[i] = adaslice__printer_units(p->phi[i], p->bin, eps, opt->eps_units);
        job->quantum = eps / opt->eps_units;
        job->slack = 0;
        eps_units = opt->eps_units;
    } else if (adaslice__quantise(job), opt->budget) {
        uint32_t budget = opt->budget > 0xfffffffeu ? 0xfffffffeu : (uint32_t)opt->budget;
        eps_units = adaslice__job_min_eps(job, budget);
        if (eps_units == UINT64_MAX) {
            uint32_t fewest = adaslice__job_run(job, UINT64_MAX >> 2);
            if (fewest == ADASLICE__UNREACHED)
                return adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                                      "plan: layers of %u to %u bins cannot tile the height %g mm",
                                      (unsigned)job->lo, (unsigned)job->hi, job->n * p->bin);
            return adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                                  "plan: no plan has %zu layers or fewer: at least %u are needed with layers of at most %g mm",
                                  opt->budget, (unsigned)fewest, job->hi * p->bin);
        }
        eps = eps_units * job->quantum;
    } else {
        eps_units = adaslice__eps_units(eps, job->quantum);
    }
    if (job->forced && !opt->budget &&
        adaslice__sharp_settle(job, eps_units, &plan->allocator, &plan->changes, &plan->plane_changes) == ADASLICE__UNREACHED)
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory");
    layers = job->planned ? adaslice_dp_layers(&job->dp) : adaslice__job_run(job, eps_units);
    if (layers == ADASLICE__UNREACHED) {
        uint32_t reach = adaslice_dp_reach(&job->dp);
        uint64_t need;
        /* printer units are capped above eps: search the smallest eps in fine
           units, and allow for the printer's coarser rounding */
        double margin = opt->eps_units ? 1e-6 + (double)job->hi / opt->eps_units : 1e-6;
        if (opt->eps_units) adaslice__quantise(job);
        need = adaslice__job_min_eps(job, ADASLICE__UNREACHED);
        if (need == UINT64_MAX) {
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: no plan covers the part above z = %g mm for any eps: layers of %u to %u bins "
                               "(%g to %g mm) cannot tile the height %g mm between forced planes",
                               reach * p->bin, (unsigned)job->lo, (unsigned)job->hi, job->lo * p->bin,
                               job->hi * p->bin, job->n * p->bin);
            if (err) err->z = reach * p->bin;
            return r;
        } else {
            /* rounded up so that passing the printed value back succeeds */
            double min_eps = (double)need * job->quantum * (1 + margin);
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: eps %g is too small: no plan covers the part above z = %g mm; "
                               "the smallest feasible eps is %g", eps, reach * p->bin, min_eps);
            if (err) { err->z = reach * p->bin; err->min_eps = min_eps; }
            return r;
        }
    }
    planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(&plan->allocator, (size_t)layers + 1, sizeof(uint32_t)));
    if (!planes) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory");
    for (i = job->n, k = layers; ; k--) {
        uint32_t len;
        planes[k] = i;
        if (!i) break;
        len = adaslice_dp_layer_below(&job->dp, i);
        ADASLICE_ASSERT(len >= job->lo && len <= job->hi && len <= i && k > 0);
        i -= len;
    }
    r = adaslice__plan_fill(p, planes, layers + 1, eps, plan, err);
    /* eps found by the budget is the plan's worst error in units; the error
       summed in double may differ from it in the last bit */
    if (opt->budget && plan->worst_error > plan->eps) { plan->eps = plan->worst_error; plan->over_eps = 0; }
    adaslice__free(&plan->allocator, planes);
    return r;
}

/* The profile's bins and the thickness bounds as whole bins per layer,
   [*lo, *hi], with the checks both planners need. */
static adaslice_result adaslice__layer_bins(const adaslice_profile *p, double tmin, double tmax, uint32_t *lo,
                                            uint32_t *hi, adaslice_error *err)
{
    double lo_f, hi_f;
    if (!(p->bin > 0) || p->bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: bin size %g is not a positive number", p->bin);
    if (!(tmin > 0) || tmin > DBL_MAX || !(tmax > 0) || tmax > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: tmin %g and tmax %g must be positive numbers", tmin, tmax);
    if (tmin > tmax)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: tmin %g mm is larger than tmax %g mm", tmin, tmax);
    if (p->bin > tmin * (1 + 1e-9))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: bin size %g mm is larger than tmin %g mm; use a bin of at most tmin", p->bin, tmin);
    /* b rarely divides tmin and tmax exactly in binary: allow a relative 1e-9 */
    lo_f = ceil(tmin / p->bin - 1e-9);
    hi_f = floor(tmax / p->bin + 1e-9);
    if (lo_f > hi_f)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: no multiple of the bin size %g mm lies between tmin %g and tmax %g", p->bin, tmin, tmax);
    if (hi_f > 65535)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: tmax / bin = %g bins per layer; at most 65535 are supported", hi_f);
    *lo = lo_f < 1 ? 1 : (uint32_t)lo_f;
    *hi = (uint32_t)hi_f;
    return ADASLICE_OK;
}

/* The curvature method's own inputs (plan_setup has done the rest). */
static adaslice_result adaslice__curvature_check(const adaslice_profile *p, adaslice_plan_options *opt,
                                                 adaslice_error *err)
{
    size_t i;
    if (opt->alpha == 0) opt->alpha = ADASLICE_DEFAULT_ALPHA;
    if (!opt->curvature) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: no curvature given");
    if ((unsigned)opt->mapping > ADASLICE_MAPPING_STEP)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: unknown mapping %d", (int)opt->mapping);
    if (!(opt->alpha > 0) || opt->alpha > DBL_MAX || !(opt->kappa_max >= 0) || opt->kappa_max > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: alpha %g and kappa_max %g must be finite and positive (kappa_max: or 0)",
                              opt->alpha, opt->kappa_max);
    for (i = 0; i < p->bin_count; i++)
        if (!(opt->curvature[i] >= 0) || opt->curvature[i] > DBL_MAX)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "plan: curvature %g at bin %zu (z = %g mm) is not a finite number >= 0",
                                  opt->curvature[i], i, (double)i * p->bin);
    return ADASLICE_OK;
}

/* Defaults and the checks every plan needs. */
static adaslice_result adaslice__plan_setup(const adaslice_profile *p, const adaslice_plan_options *options,
                                            adaslice_plan_options *opt, uint32_t *lo, uint32_t *hi, adaslice_error *err)
{
    adaslice_result r;
    size_t i;
    double total = 0;
    if (!p || !p->phi || !p->bin_count)
        return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "plan: the profile is empty");
    if (options) *opt = *options; else memset(opt, 0, sizeof *opt);
    if (opt->eps == 0) opt->eps = ADASLICE_DEFAULT_EPS;
    if (opt->tmin == 0) opt->tmin = ADASLICE_DEFAULT_TMIN;
    if (opt->tmax == 0) opt->tmax = ADASLICE_DEFAULT_TMAX;
    if (opt->sharp == 0) opt->sharp = ADASLICE_DEFAULT_SHARP;
    if (!(opt->eps > 0) || opt->eps > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: eps %g is not a positive number", opt->eps);
    if ((r = adaslice__layer_bins(p, opt->tmin, opt->tmax, lo, hi, err)) != ADASLICE_OK) return r;
    if ((unsigned)opt->method > ADASLICE_METHOD_CURVATURE)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: unknown method %d", (int)opt->method);
    if (opt->eps_units && (opt->method != ADASLICE_METHOD_OPTIMAL || opt->budget || p->metric == ADASLICE_METRIC_VOLUME))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: printer units (eps_units) need the optimal method, an additive metric and no budget");
    if (opt->eps_units && *hi > 255)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "plan: a printer plans layers of at most 255 bins; tmax / bin is %u", (unsigned)*hi);
    for (i = 0; i < p->bin_count; i++) {
        if (!(p->phi[i] >= 0) || p->phi[i] > DBL_MAX)
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "plan: profile value %g at bin %zu (z = %g mm) is not a finite number >= 0",
                                  p->phi[i], i, (double)i * p->bin);
        total += p->phi[i];
    }
    /* every layer's error is at most twice the whole sum times the bin (the
       volume metric's differences), in any order of adding: a plan whose
       errors overflowed to inf passed as feasible */
    if (!(4 * total * p->bin <= DBL_MAX))
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0,
                              "plan: the profile's values sum to %g: its layers' errors would pass the largest double",
                              total);
    if (opt->method == ADASLICE_METHOD_CURVATURE) return adaslice__curvature_check(p, opt, err);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_plan_profile(const adaslice_profile *p, const adaslice_plan_options *options,
                                                   adaslice_plan *plan, adaslice_error *err)
{
    adaslice_plan_options opt;
    adaslice__job job;
    adaslice_allocator al;
    adaslice_result r = ADASLICE_OK;
    unsigned char *ok = NULL;
    uint32_t *planes = NULL, count, forced = 0, lo, hi, i;
    void *ring = NULL;

    if (!plan) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan: no output given");
    memset(plan, 0, sizeof *plan);
    if ((r = adaslice__plan_setup(p, options, &opt, &lo, &hi, err)) != ADASLICE_OK) return r;

    memset(&job, 0, sizeof job);
    job.profile = p;
    job.n = (uint32_t)p->bin_count;
    job.lo = lo;
    job.hi = hi;
    job.volume = p->metric == ADASLICE_METRIC_VOLUME;
    al = adaslice__allocator(opt.allocator);
    plan->allocator = al;
    plan->bins_min = job.lo;
    plan->bins_max = job.hi;
    if (job.n < job.lo) {
        r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                           "plan: the part is %g mm tall, thinner than one layer of tmin %g mm",
                           p->height > 0 ? p->height : job.n * p->bin, opt.tmin); /* bins round a sliver up to one */
        if (err) err->z = 0;
        return r;
    }
    ok = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)job.n + 1, 1));
    planes = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, (size_t)job.n + 1, sizeof(uint32_t)));
    if (!ok || !planes) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); goto done; }

    if (opt.method == ADASLICE_METHOD_GREEDY || opt.method == ADASLICE_METHOD_CURVATURE ||
        (opt.method == ADASLICE_METHOD_OPTIMAL && opt.sharp > 0))
        adaslice__tileable(ok, job.n, job.lo, job.hi);
    switch (opt.method) {
    case ADASLICE_METHOD_FINEST:
    case ADASLICE_METHOD_COARSEST:
        count = adaslice__uniform(job.n, opt.method == ADASLICE_METHOD_FINEST ? job.lo : job.hi, planes);
        r = adaslice__plan_fill(p, planes, count, opt.eps, plan, err);
        break;
    case ADASLICE_METHOD_GREEDY:
    case ADASLICE_METHOD_CURVATURE: {
        double kmax = opt.method == ADASLICE_METHOD_CURVATURE ? adaslice__kappa_max(&opt, job.n, &al) : 0;
        if (!ok[job.n]) {
            r = adaslice__fail(err, ADASLICE_ERR_INFEASIBLE, 0, 0,
                               "plan: %u bins cannot be cut into layers of %u to %u bins", (unsigned)job.n,
                               (unsigned)job.lo, (unsigned)job.hi);
            break;
        }
        if (kmax < 0) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); break; }
        count = adaslice__bottom_up(p, &opt, kmax, job.n, job.lo, job.hi, ok, planes);
        r = adaslice__plan_fill(p, planes, count, opt.eps, plan, err);
        break;
    }
    case ADASLICE_METHOD_OPTIMAL: {
        size_t need = opt.sharp > 0 ? adaslice__settle_workspace(job.n, job.hi, job.volume)
                                    : adaslice_dp_workspace(job.n, job.hi, job.volume);
        job.units = ADASLICE__CAST(uint64_t *, adaslice__alloc(&al, job.n, sizeof(uint64_t)));
        ring = adaslice__alloc(&al, 1, need);
        if (!job.units || !ring) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); break; }
        job.ring = ring;
        job.ring_size = need;
        if (opt.sharp > 0) {
            job.forced = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)job.n + 1, 1));
            if (!job.forced) { r = adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan: out of memory"); break; }
            forced = adaslice__sharp_planes(p, job.n, opt.sharp, ok, job.forced);
        }
        r = adaslice__plan_optimal(&job, &opt, opt.eps, plan, err);
        if (job.forced) /* those kept, moved or not */
            for (forced = 0, i = 1; i < job.n; i++) forced += job.forced[i] != 0;
        plan->forced_planes = forced;
        if (r == ADASLICE_ERR_INFEASIBLE && forced && err) {
            size_t len = strlen(err->message);
            adaslice__out o;
            o.buf = err->message; o.cap = sizeof err->message; o.len = len;
            adaslice__puts(&o, " (the sharp-change pre-pass forced planes: ");
            adaslice__putu(&o, forced);
            adaslice__puts(&o, "; without them a smaller eps may be feasible)");
            err->message[o.len < o.cap ? o.len : o.cap - 1] = 0;
        }
        break;
    }
    }
done:
    adaslice__free(&al, job.units);
    adaslice__free(&al, ring);
    adaslice__free(&al, job.forced);
    adaslice__free(&al, ok);
    adaslice__free(&al, planes);
    if (r != ADASLICE_OK) {
        adaslice_plan_free(plan);
        return r;
    }
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_plan_units(const adaslice_profile *p, const adaslice_plan_options *options,
                                                 uint32_t *units, unsigned char *forced, adaslice_error *err)
{
    adaslice_plan_options opt;
    adaslice_allocator al;
    adaslice_result r;
    unsigned char *ok, *planes;
    uint32_t lo, hi, i, n;
    if ((r = adaslice__plan_setup(p, options, &opt, &lo, &hi, err)) != ADASLICE_OK) return r;
    if (!opt.eps_units || !units || !forced)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "plan units: need eps_units and the two outputs");
    n = (uint32_t)p->bin_count;
    for (i = 0; i < n; i++) units[i] = adaslice__printer_units(p->phi[i], p->bin, opt.eps, opt.eps_units);
    memset(forced, 0, n);
    if (!(opt.sharp > 0)) { adaslice__ok(err); return ADASLICE_OK; }
    al = adaslice__allocator(opt.allocator);
    ok = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)n + 1, 1));
    planes = ADASLICE__CAST(unsigned char *, adaslice__alloc(&al, (size_t)n + 1, 1));
    if (!ok || !planes) {
        adaslice__free(&al, ok);
        adaslice__free(&al, planes);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan units: out of memory");
    }
    adaslice__tileable(ok, n, lo, hi);
    (void)adaslice__sharp_planes(p, n, opt.sharp, ok, planes);
    {   /* kept, moved or dropped for eps_units as adaslice_plan_profile does */
        adaslice__job job;
        adaslice_plane_change *changes = NULL;
        size_t count = 0;
        uint32_t kept = ADASLICE__UNREACHED;
        memset(&job, 0, sizeof job);
        job.profile = p;
        job.n = n;
        job.lo = lo;
        job.hi = hi;
        job.forced = planes;
        job.units = ADASLICE__CAST(uint64_t *, adaslice__alloc(&al, n, sizeof(uint64_t)));
        job.ring_size = adaslice__settle_workspace(n, hi, 0);
        job.ring = adaslice__alloc(&al, 1, job.ring_size);
        if (job.units && job.ring) {
            for (i = 0; i < n; i++) job.units[i] = units[i];
            kept = adaslice__sharp_settle(&job, opt.eps_units, &al, &changes, &count);
        }
        adaslice__free(&al, changes);
        adaslice__free(&al, job.units);
        adaslice__free(&al, job.ring);
        if (kept == ADASLICE__UNREACHED) {
            adaslice__free(&al, ok);
            adaslice__free(&al, planes);
            return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "plan units: out of memory");
        }
    }
    /* the plane on top of bin i is plane i + 1; the top plane is never forced */
    for (i = 0; i + 1 < n; i++) forced[i] = planes[i + 1];
    adaslice__free(&al, ok);
    adaslice__free(&al, planes);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_plan_free(adaslice_plan *plan)
{
    adaslice_allocator al;
    if (!plan) return;
    al = plan->allocator;
    adaslice__free(&al, plan->planes);
    adaslice__free(&al, plan->layers);
    adaslice__free(&al, plan->changes);
    memset(plan, 0, sizeof *plan);
}


/* =========================================================== orientation */
#ifndef ADASLICE_NO_ORIENT
/* x's low 10 bits spread out to every third bit: a coordinate's share of a
   30-bit Morton code. */
static uint64_t adaslice__spread10(uint32_t x)
{
    uint64_t v = x & 1023u;
    v = (v | v << 16) & 0x030000ffu;
    v = (v | v << 8) & 0x0300f00fu;
    v = (v | v << 4) & 0x030c30c3u;
    v = (v | v << 2) & 0x09249249u;
    return v;
}

/* Sorted triangles to a box: few enough that a box is little larger than
   its triangles, many enough that boxes are few against the triangles. */
#define ADASLICE__BOX_TRIANGLES 16

static size_t adaslice__box_count(size_t triangles)
{
    return (triangles + ADASLICE__BOX_TRIANGLES - 1) / ADASLICE__BOX_TRIANGLES;
}

/* A facet's bound of adaslice__orienter_bounds as a number (32767: any). */
static double adaslice__value_bound(int16_t e)
{
    return e * (1.0 / 32768) + (e == 32767) * 2.0;
}

/* The cone of the normals of sorted triangles first..end-1 (each taken
   either way: a value is |n . d|) into cone: its axis, the cosine and sine of
   an angle a little over its own (10^-5, for the floats' rounding), and the
   largest of their bounds. */
static void adaslice__box_cone(const adaslice_orienter *o, size_t first, size_t end, float *cone)
{
    const int16_t *ref = o->normals + 4 * first;
    double axis[3] = {0, 0, 0}, len, least = 1, bound = 0, angle;
    size_t t;
    int k;
    for (t = first; t < end; t++) {
        const int16_t *nn = o->normals + 4 * t;
        double side = (double)nn[0] * ref[0] + (double)nn[1] * ref[1] + (double)nn[2] * ref[2] < 0 ? -1 : 1;
        double e = adaslice__value_bound(nn[3]);
        for (k = 0; k < 3; k++) axis[k] += side * nn[k];
        bound = e > bound ? e : bound;
    }
    len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (k = 0; k < 3; k++) axis[k] = len > 0 ? axis[k] / len : k == 2;
    for (t = first; t < end; t++) {
        const int16_t *nn = o->normals + 4 * t;
        double l = sqrt((double)nn[0] * nn[0] + (double)nn[1] * nn[1] + (double)nn[2] * nn[2]);
        double c = l > 0 ? fabs(axis[0] * nn[0] + axis[1] * nn[1] + axis[2] * nn[2]) / l : 0;
        least = c < least ? c : least;
    }
    angle = acos(least < 1 ? least : 1) + 1e-5;
    for (k = 0; k < 3; k++) cone[k] = (float)axis[k];
    cone[3] = angle < 1.5707963267948966 ? (float)cos(angle) : 0;
    cone[4] = angle < 1.5707963267948966 ? (float)sin(angle) : 1;
    cone[5] = (float)(bound * (1 + 1e-6));
}

/* What the cusp profile along a direction may skip by (adaslice__prune):
   each sorted triangle's unit normal n and a bound e on how far the value
   the profile computes for it, from its corners turned and rounded to float,
   can be from |n . d| along any d; and the boxes around runs of triangles.
   The turned corners are off by at most r = sqrt(3) 2^-24 of the farthest
   corner's distance each (plus the double sums' rounding, far less), so its
   edges u, w by 2r, its normal u x w by 2r (|u| + |w|) + 4r^2, and the
   normal's unit vector, whose z is the value, by twice that over |u x w|.
   e is that doubled, plus 10^-6 for the sums' rounding and 2.7 10^-5 for n
   kept in 32767ths (sqrt(3) / 2 of one at most), rounded up to 32768ths; a
   facet without a normal (skipped by the profile) or a sliver whose bound
   nears 1 gets 32767, which keeps it in every profile. Eight bytes a facet:
   the search reads them all for every direction. 0 when out of memory. */
static int adaslice__orienter_bounds(adaslice_orienter *o)
{
    const adaslice_mesh *m = &o->sorted;
    const adaslice_allocator *al = &o->allocator;
    double r = 1.7320508075688772 / 16777216.0 * o->reach * 1.01;
    size_t t, boxes = adaslice__box_count(m->triangle_count);
    int k, c;
    o->normals = ADASLICE__CAST(int16_t *, adaslice__alloc(al, m->triangle_count, 4 * sizeof(int16_t)));
    o->boxes = ADASLICE__CAST(float *, adaslice__alloc(al, boxes, 12 * sizeof(float)));
    o->firsts = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, boxes, 3 * sizeof(uint32_t)));
    if (!o->normals || !o->boxes || !o->firsts) return 0;
    for (t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        const float *a = m->vertices + 3 * (size_t)tri[0], *b = m->vertices + 3 * (size_t)tri[1],
                    *cc = m->vertices + 3 * (size_t)tri[2];
        float *box = o->boxes + 12 * (t / ADASLICE__BOX_TRIANGLES);
        int16_t *out = o->normals + 4 * t;
        double u[3], w[3], n[3], len, lu, lw, e;
        for (k = 0; k < 3; k++) { u[k] = (double)b[k] - a[k]; w[k] = (double)cc[k] - a[k]; }
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        lw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        e = len > 0 ? 2 * 2 * (2 * r * (lu + lw) + 4 * r * r) / len + 1e-6 + 2.7e-5 : 1;
        for (k = 0; k < 3; k++) out[k] = (int16_t)(len > 0 ? floor(n[k] / len * 32767 + 0.5) : 0);
        out[3] = (int16_t)(e < 32766.0 / 32768 ? ceil(e * 32768) : 32767);
        for (c = 0; c < 3; c++) {
            const float *q = m->vertices + 3 * (size_t)tri[c];
            int first = t % ADASLICE__BOX_TRIANGLES == 0 && c == 0;
            for (k = 0; k < 3; k++) {
                box[k] = first || q[k] < box[k] ? q[k] : box[k];
                box[3 + k] = first || q[k] > box[3 + k] ? q[k] : box[3 + k];
            }
        }
        if (t % ADASLICE__BOX_TRIANGLES == 0) memcpy(o->firsts + 3 * (t / ADASLICE__BOX_TRIANGLES), tri, 3 * sizeof *tri);
        if (t % ADASLICE__BOX_TRIANGLES == ADASLICE__BOX_TRIANGLES - 1 || t + 1 == m->triangle_count)
            adaslice__box_cone(o, t - t % ADASLICE__BOX_TRIANGLES, t + 1, box + 6);
    }
    return 1;
}

/* The triangles sorted along a Morton curve through their centroids, their
   vertices numbered in the order the sorted triangles first use them (the
   unused ones left out), a facet's corners kept in their order. Triangles
   near in space are then near in memory whatever the direction, and so are
   the bins of the profile they update: the search gathers corners and
   writes the table in cache instead of across a whole model's worth of
   memory. A maximum does not depend on the order of its terms, so the
   profiles are as before, bit for bit. */
static int adaslice__orienter_sort(adaslice_orienter *o, const double lo[3], const double hi[3])
{
    const adaslice_mesh *m = o->mesh;
    const adaslice_allocator *al = &o->allocator;
    size_t n = m->triangle_count, t, used = 0;
    uint64_t *key = ADASLICE__CAST(uint64_t *, adaslice__alloc(al, 2 * n, sizeof *key));
    uint32_t *order = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, 2 * n, sizeof *order));
    uint32_t *number = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, m->vertex_count, sizeof *number));
    adaslice_mesh *s = &o->sorted;
    double scale[3], extent;
    int k, ok = 0;
    s->vertices = ADASLICE__CAST(float *, adaslice__alloc(al, m->vertex_count, 3 * sizeof(float)));
    s->triangles = ADASLICE__CAST(uint32_t *, adaslice__alloc(al, n, 3 * sizeof(uint32_t)));
    if (o->profile.weights) o->weights = ADASLICE__CAST(float *, adaslice__alloc(al, n, sizeof(float)));
    if (!key || !order || !number || !s->vertices || !s->triangles || (o->profile.weights && !o->weights)) goto done;
    /* one cell size on every axis: cells as long as the part along its
       longest axis and thin across made boxes of 16 facets ten times longer
       than wide on bench's plate (1,043 x 144 x 91 mm), 15 mm on average
       for facets of 1 mm, and their bounds of the profile too low to skip */
    extent = 0;
    for (k = 0; k < 3; k++) extent = hi[k] - lo[k] > extent ? hi[k] - lo[k] : extent;
    for (k = 0; k < 3; k++) scale[k] = extent > 0 ? 1023.0 / (3 * extent) : 0;
    for (t = 0; t < n; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        uint64_t code = 0;
        for (k = 0; k < 3; k++) {
            double q = ((double)m->vertices[3 * (size_t)tri[0] + k] + m->vertices[3 * (size_t)tri[1] + k] +
                        m->vertices[3 * (size_t)tri[2] + k] - 3 * lo[k]) * scale[k];
            code |= adaslice__spread10(q >= 0 && q <= 1023 ? (uint32_t)q : 0) << k;
        }
        key[t] = code;
        order[t] = (uint32_t)t;
    }
    adaslice__sort_keys(key, order, key + n, order + n, n);
    memset(number, 0xff, m->vertex_count * sizeof *number);
    for (t = 0; t < n; t++) {
        for (k = 0; k < 3; k++) {
            uint32_t v = m->triangles[3 * (size_t)order[t] + k];
            if (number[v] == 0xffffffffu) {
                memcpy(s->vertices + 3 * used, m->vertices + 3 * (size_t)v, 3 * sizeof(float));
                number[v] = (uint32_t)used++;
            }
            s->triangles[3 * t + k] = number[v];
        }
        if (o->weights) o->weights[t] = o->profile.weights[order[t]];
    }
    s->vertex_count = used;
    s->triangle_count = n;
    ok = 1;
done:
    adaslice__free(al, key);
    adaslice__free(al, order);
    adaslice__free(al, number);
    return ok;
}

ADASLICE_DEF adaslice_result adaslice_orienter_init(adaslice_orienter *o, const adaslice_mesh *mesh,
                                                    const adaslice_profile_options *profile,
                                                    const adaslice_plan_options *plan, adaslice_error *err)
{
    size_t t;
    double edge2 = 0, reach2 = 0, lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    int k;
    if (!o) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "orient: no orienter given");
    memset(o, 0, sizeof *o);
    if (!mesh || !mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "orient: the mesh has no triangles");
    o->mesh = mesh;
    if (profile) o->profile = *profile;
    if (plan) o->plan = *plan;
    o->allocator = adaslice__allocator(profile ? profile->allocator : NULL);
    /* indices are checked here once, not for every direction */
    for (t = 0; t < 3 * mesh->triangle_count; t++)
        if (mesh->triangles[t] >= mesh->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "orient: triangle %zu uses vertex %u of %zu", t / 3,
                                  (unsigned)mesh->triangles[t], mesh->vertex_count);
    /* the square roots of the largest squares: sqrt keeps the order */
    for (t = 0; t < 3 * mesh->triangle_count; t++) {
        const float *p = mesh->vertices + 3 * (size_t)mesh->triangles[t],
                    *q = mesh->vertices + 3 * (size_t)mesh->triangles[t % 3 == 2 ? t - 2 : t + 1];
        double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
        double e2 = dx * dx + dy * dy + dz * dz, r2 = (double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2];
        edge2 = e2 > edge2 ? e2 : edge2;
        reach2 = r2 > reach2 ? r2 : reach2;
        for (k = 0; k < 3; k++) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    o->longest_edge = sqrt(edge2);
    o->reach = sqrt(reach2);
    if ((o->profile.metric < ADASLICE_METRIC_AREA && !adaslice__orienter_sort(o, lo, hi)) ||
        (o->profile.metric == ADASLICE_METRIC_CUSP && !o->profile.weights && !adaslice__orienter_bounds(o))) {
        adaslice_orienter_free(o);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "orient: out of memory");
    }
    adaslice__ok(err);
    return ADASLICE_OK;
}

/* Bins a triangle meets along any direction, at most (0: unknown): its
   height is at most its longest edge, plus the turned corners' rounding to
   float (2^-24 of their distance from the origin each), and its ends fall in
   bins at most two apart beyond that. Sizes the profile's table without a
   pass over the heights. */
static size_t adaslice__longest_run(const adaslice_orienter *o)
{
    double bin = o->profile.bin > 0 ? o->profile.bin : ADASLICE_DEFAULT_BIN;
    double bins = (o->longest_edge + 1e-5 * o->reach) / bin + 3;
    return bins < 2147483647.0 ? (size_t)bins : 0;
}

ADASLICE_DEF void adaslice_orienter_free(adaslice_orienter *o)
{
    if (!o) return;
    adaslice__free(&o->allocator, o->sorted.vertices);
    adaslice__free(&o->allocator, o->sorted.triangles);
    adaslice__free(&o->allocator, o->weights);
    adaslice__free(&o->allocator, o->normals);
    adaslice__free(&o->allocator, o->boxes);
    adaslice__free(&o->allocator, o->firsts);
    memset(o, 0, sizeof *o);
}

/* A turned vertex as the profile along a direction reads it: its corner, for
   the facets' normals, and the bin its height falls in (the bin of a facet's
   lowest corner is the least of its corners' bins, as adaslice__bin_of keeps
   the order of heights). */
typedef struct adaslice__turned_corner {
    float p[3];
    uint32_t bin;
} adaslice__turned_corner;

/* A facet's value over bins first..last. */
typedef struct adaslice__run {
    uint32_t first, last;
    double value;
} adaslice__run;

/* Doubles in the range-maximum table of a chunk of bins (512 KB, half a
   core's L2: it shares it with the corners and runs streaming through; a
   whole L2's worth was 8 % slower on the plate), and
   in the largest table kept whole (2 MB: the turbine blade's 1.7 MB was 5 %
   quicker whole than sorted into chunks). */
#define ADASLICE__CHUNK_TABLE 65536
#define ADASLICE__WHOLE_TABLE 262144

/* Bins to a block of the lower bound adaslice__prune keeps, as a shift: the
   fewest, down to 16, whose range-minimum table stays within a chunk's
   (ADASLICE__CHUNK_TABLE doubles). A finer bound leaves out more facets: in
   blocks of 64 bins the turbine blade kept 48 % of its facets over 200
   directions, in 16 27 % (its 1,000 directions took 12 % less time); the
   plate's 289,000 bins stay in blocks of 64, where finer tables outgrew the
   cache and cost more than they saved. */
static int adaslice__bound_shift(size_t bins)
{
    int shift = 4;
    for (;;) {
        size_t blocks = ((bins - 1) >> shift) + 1;
        if (blocks * (size_t)(adaslice__floor_log2(blocks) + 1) <= ADASLICE__CHUNK_TABLE) return shift;
        shift++;
    }
}

/* A facet's run: the least and the largest of its corners' bins. */
static inline void adaslice__corner_run(uint32_t a, uint32_t b, uint32_t c, uint32_t *first, uint32_t *last)
{
    uint32_t lo = a < b ? a : b, hi = a > b ? a : b;
    *first = c < lo ? c : lo;
    *last = c > hi ? c : hi;
}

/* Facet t's runs in the chunks of 2^shift bins its corners meet (two at
   most: a chunk is longer than any facet), counted into runs[chunk + 1]. */
static void adaslice__count_runs(const adaslice_mesh *m, const adaslice__turned_corner *cv, size_t t, int shift,
                                 size_t *runs)
{
    const uint32_t *tri = m->triangles + 3 * t;
    uint32_t first, last;
    adaslice__corner_run(cv[tri[0]].bin, cv[tri[1]].bin, cv[tri[2]].bin, &first, &last);
    runs[(first >> shift) + 1]++;
    runs[(last >> shift) + 1] += first >> shift != last >> shift;
}

/* The cusp profile's facets that can raise it, into keep in order (their
   count returned), the others left out: a facet whose value is at most the
   profile's over all its bins cannot change a maximum. Of the plate of
   bench's, along any direction, 99 % are such; the bound below leaves out 76 %
   of its facets (200 directions), 73 % of the turbine blade's. The profile is bounded below
   per block of bins by each box's first facet, computed exactly as the
   profile does and always kept: a block within that facet's bins is at least
   its value. A facet is left out when |n . d| plus its bound
   (adaslice__orienter_bounds) is at most the least such block bound over its
   box's bins, and a whole box when its cone of normals bounds them all so:
   their values cannot pass the profile there. The box's bins come from its
   corners' heights along d with the margin of adaslice__longest_run's
   rounding. `lower`: levels x blocks doubles, the bound's range-minimum
   table; a block is 2^shift bins. `runs` (NULL: one chunk): room for the
   kept facets' runs per chunk of 2^chunk_shift bins, added to runs[chunk + 1]:
   a box's facets lie within its bins, and a facet has one run at most in
   each chunk, so a box across one border reserves a run a facet on either
   side of it (gathering each facet's corners to count them exactly cost as
   much as gathering them for their values). */
static size_t adaslice__prune(const adaslice_orienter *o, const adaslice__turned_corner *cv, const double up[3],
                              const adaslice_profile *p, double *lower, int levels, int shift, uint32_t *keep,
                              int chunk_shift, size_t *runs)
{
    const adaslice_mesh *m = &o->sorted;
    size_t n = p->bin_count, blocks = ((n - 1) >> shift) + 1, boxes = adaslice__box_count(m->triangle_count);
    size_t block = (size_t)1 << shift;
    size_t b, t, g, kept = 0, box_kept, bin_lo, bin_hi;
    double inverse = 1.0 / p->bin, top = (double)(long)(n - 1), margin = 1e-5 * o->reach;
    double s[3]; /* d over 32767, for the normals in 32767ths */
    int k;
    for (k = 0; k < 3; k++) s[k] = up[k] / 32767;
    memset(lower, 0, blocks * sizeof *lower);
    for (b = 0; b < boxes; b++) {
        const uint32_t *tri = o->firsts + 3 * b; /* not m->triangles: a line read for 12 bytes */
        const adaslice__turned_corner *c0 = cv + tri[0], *c1 = cv + tri[1], *c2 = cv + tri[2];
        double value = adaslice__corner_value(c0->p, c1->p, c2->p, ADASLICE_METRIC_CUSP, 0);
        uint32_t lo, hi;
        adaslice__corner_run(c0->bin, c1->bin, c2->bin, &lo, &hi);
        /* the blocks wholly within lo..hi */
        for (g = (lo + block - 1) >> shift; (g + 1) << shift <= hi + 1; g++)
            lower[g] = lower[g] < value ? value : lower[g];
    }
    for (k = 1; k < levels; k++) { /* level k: the least of 2^k blocks from each */
        const double *below = lower + (size_t)(k - 1) * blocks;
        double *level = lower + (size_t)k * blocks;
        size_t half = (size_t)1 << (k - 1);
        for (g = 0; g + 2 * half <= blocks; g++) level[g] = below[g] < below[g + half] ? below[g] : below[g + half];
    }
    for (b = 0; b < boxes; b++) {
        const float *box = o->boxes + 12 * b, *cone = box + 6;
        size_t first = b * ADASLICE__BOX_TRIANGLES, end = first + ADASLICE__BOX_TRIANGLES, g0, g1;
        double zlo = 0, zhi = 0, least, cos_d, sin_d, most;
        for (k = 0; k < 3; k++) {
            zlo += up[k] * (up[k] >= 0 ? box[k] : box[3 + k]);
            zhi += up[k] * (up[k] >= 0 ? box[3 + k] : box[k]);
        }
        bin_lo = adaslice__bin_of(p->z0, inverse, top, zlo - margin);
        bin_hi = adaslice__bin_of(p->z0, inverse, top, zhi + margin);
        g0 = bin_lo >> shift;
        g1 = bin_hi >> shift;
        k = adaslice__floor_log2(g1 - g0 + 1);
        least = lower[(size_t)k * blocks + g0];
        g = g1 + 1 - ((size_t)1 << k);
        least = lower[(size_t)k * blocks + g] < least ? lower[(size_t)k * blocks + g] : least;
        box_kept = kept;
        keep[kept++] = (uint32_t)first;
        /* the largest |n . d| in the cone: the cosine of d's angle to the
           axis less the cone's, or 1 within it (normals in 32767ths are up
           to 3 10^-5 longer than 1) */
        cos_d = fabs(cone[0] * up[0] + cone[1] * up[1] + cone[2] * up[2]);
        cos_d = cos_d < 1 ? cos_d : 1;
        sin_d = sqrt(1 - cos_d * cos_d);
        most = cos_d >= cone[3] ? 1 : cos_d * cone[3] + sin_d * cone[4];
        end = end < m->triangle_count ? end : m->triangle_count;
        if (most * (1 + 3e-5) + 1e-6 + cone[5] <= least) end = first + 1;
        for (t = first + 1; t < end; t++) {
            const int16_t *nn = o->normals + 4 * t;
            double a = fabs(nn[0] * s[0] + nn[1] * s[1] + nn[2] * s[2]);
            keep[kept] = (uint32_t)t; /* a store and a count: whether it stays is unpredictable */
            kept += a + adaslice__value_bound(nn[3]) > least;
        }
        if (!runs) continue;
        g0 = bin_lo >> chunk_shift;
        g1 = bin_hi >> chunk_shift;
        if (g1 <= g0 + 1) {
            runs[g0 + 1] += kept - box_kept;
            if (g1 != g0) runs[g1 + 1] += kept - box_kept;
        } else {
            for (; box_kept < kept; box_kept++) adaslice__count_runs(m, cv, keep[box_kept], chunk_shift, runs);
        }
    }
    return kept;
}

/* The max-type profile (cusp, roughness, or the weights alone) along a
   direction from its turned corners: adaslice__max_over_bins of the turned
   mesh, bit for bit, as a maximum does not depend on the order of its terms
   nor on a run being cut in two. Along a long part the range-maximum table
   grows to tens of MB, cleared, updated at random and pushed down for every
   direction, and memory bounds the search; so the bins are cut into chunks
   whose table stays in cache, the facets' runs sorted into them by their
   counts per chunk (those crossing a border cut there). For the cusp metric
   unweighted, only the facets adaslice__prune keeps, which it counts;
   otherwise a pass over every facet's corners counts them. */
static adaslice_result adaslice__max_along(const adaslice_orienter *o, const adaslice__turned_corner *cv,
                                           const double up[3], const adaslice_profile_options *opt,
                                           adaslice_profile *p, adaslice_error *err)
{
    const adaslice_mesh *m = &o->sorted;
    adaslice_allocator al = p->allocator;
    adaslice_profile_options quiet;
    adaslice__rmax rmax;
    adaslice__run *sorted = NULL;
    uint32_t *keep = NULL;
    size_t *start = NULL, *begin = NULL, n = p->bin_count, longest = adaslice__longest_run(o), span, chunk, chunks, t, c, i;
    size_t count = m->triangle_count;
    adaslice_metric metric = opt->metric;
    const float *weights = o->weights;
    double rough = opt->roughness_max;
    int levels, shift;

    span = longest && longest < n ? longest : n;
    levels = adaslice__floor_log2(span) + 1;
    /* a power of two longer than any run, so a shift finds a run's chunk
       and a run meets two chunks at most */
    shift = adaslice__floor_log2(ADASLICE__CHUNK_TABLE / (size_t)levels);
    shift = shift >= levels ? shift : levels;
    chunk = (size_t)1 << shift;
    chunks = n * (size_t)levels <= ADASLICE__WHOLE_TABLE ? 1 : ((n - 1) >> shift) + 1;
    if (chunks == 1) chunk = n;
    memset(&quiet, 0, sizeof quiet);
    memset(&rmax, 0, sizeof rmax);
    if (chunks > 1) {
        /* two runs a facet at most: the same size for every direction, so
           a search's allocator can keep it */
        sorted = ADASLICE__CAST(adaslice__run *, adaslice__alloc(&al, 2 * m->triangle_count, sizeof *sorted));
        /* start[c]: where chunk c's runs begin, then its cursor; begin: a copy */
        start = ADASLICE__CAST(size_t *, adaslice__alloc(&al, 2 * (chunks + 1), sizeof *start));
        if (!sorted || !start) goto nomem;
        memset(start, 0, (chunks + 1) * sizeof *start);
        begin = start + chunks + 1;
    }
    if (o->normals) { /* the prune counts the runs of the facets it keeps */
        int bound_shift = adaslice__bound_shift(n);
        size_t blocks = ((n - 1) >> bound_shift) + 1;
        int bound_levels = adaslice__floor_log2(blocks) + 1;
        double *lower = ADASLICE__CAST(double *, adaslice__alloc(&al, blocks * (size_t)bound_levels, sizeof(double)));
        keep = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, count, sizeof *keep));
        if (lower && keep) count = adaslice__prune(o, cv, up, p, lower, bound_levels, bound_shift, keep, shift, start);
        adaslice__free(&al, lower);
        if (!lower || !keep) goto nomem;
    } else if (chunks > 1) {
        for (i = 0; i < count; i++) adaslice__count_runs(m, cv, i, shift, start);
    }
    if (chunks > 1) {
        for (c = 1; c <= chunks; c++) start[c] += start[c - 1]; /* chunk c's runs go from start[c] */
        memcpy(begin, start, (chunks + 1) * sizeof *start);
    }
    if (!adaslice__rmax_init(&rmax, chunk, span, &al)) goto nomem;
    for (i = 0; i < count; i++) {
        const uint32_t *tri = m->triangles + 3 * (t = keep ? keep[i] : i);
        const adaslice__turned_corner *a = cv + tri[0], *b = cv + tri[1], *cc = cv + tri[2];
        double value = adaslice__corner_value(a->p, b->p, cc->p, metric, rough);
        uint32_t first, last;
        adaslice__run piece;
        size_t cf, cl;
        if (value < 0) {
            if (chunks == 1) continue;
            value = 0; /* its counted place filled with a run that changes nothing */
        }
        if (weights) value *= weights[t];
        adaslice__corner_run(a->bin, b->bin, cc->bin, &first, &last);
        if (chunks == 1) {
            adaslice__rmax_update(&rmax, first, last, value);
            continue;
        }
        piece.first = first;
        piece.last = last;
        piece.value = value;
        cf = first >> shift;
        cl = last >> shift;
        if (cf != cl) {
            piece.last = (uint32_t)(cl << shift) - 1;
            ADASLICE_ASSERT(start[cf] < begin[cf + 1]);
            sorted[start[cf]++] = piece;
            piece.first = piece.last + 1;
            piece.last = last;
        }
        /* the room came from the corners' bins, or the prune's boxes' that hold them */
        ADASLICE_ASSERT(start[cl] < begin[cl + 1]);
        sorted[start[cl]++] = piece;
    }
    for (c = 0; c < chunks; c++) {
        size_t c0 = c * chunk, j;
        if (chunks > 1) {
            memset(rmax.zeroed, 0, sizeof rmax.zeroed);
            for (j = begin[c]; j < start[c]; j++)
                adaslice__rmax_update(&rmax, sorted[j].first - c0, sorted[j].last - c0, sorted[j].value);
        }
        memcpy(p->phi + c0, adaslice__rmax_finish(&rmax, &quiet), (n - c0 < chunk ? n - c0 : chunk) * sizeof(double));
    }
    adaslice__free(&al, rmax.t);
    adaslice__free(&al, sorted);
    adaslice__free(&al, start);
    adaslice__free(&al, keep);
    return ADASLICE_OK;
nomem:
    adaslice__free(&al, rmax.t);
    adaslice__free(&al, sorted);
    adaslice__free(&al, start);
    adaslice__free(&al, keep);
    adaslice_profile_free(p);
    return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "orient: out of memory for %zu bins", n);
}

ADASLICE_DEF adaslice_result adaslice_profile_along(const adaslice_orienter *o, const double d[3],
                                                    adaslice_profile *profile, adaslice_error *err)
{
    const adaslice_mesh *m = &o->sorted;
    adaslice_allocator al = o->allocator;
    adaslice_profile_options opt;
    adaslice__turned_corner *cv;
    adaslice_result r;
    double rot[9], len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), u[3], zrange[2], inverse, top;
    size_t v;
    if (!(len > 0) || len > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "orient: direction (%g, %g, %g) has no length", d[0], d[1], d[2]);
    u[0] = d[0] / len; u[1] = d[1] / len; u[2] = d[2] / len;
    adaslice_rotation_to_z(u, rot);
    if (o->profile.metric >= ADASLICE_METRIC_AREA) {
        /* a turned copy of the vertices, exactly as adaslice_mesh_rotate
           makes it, so that planning the turned mesh later gives this very
           profile */
        adaslice_mesh turned;
        if (!adaslice__turned_copy(o->mesh, rot, &al, &turned))
            return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "orient: out of memory");
        r = adaslice__profile_exact(&turned, &o->profile, NULL, 0, profile, err);
        adaslice__free(&al, turned.vertices);
        return r;
    }
    /* the corners turned as adaslice_mesh_rotate turns them, so that planning
       the turned mesh later gives this very profile */
    cv = ADASLICE__CAST(adaslice__turned_corner *, adaslice__alloc(&al, m->vertex_count, sizeof *cv));
    if (!cv) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "orient: out of memory");
    zrange[0] = DBL_MAX;
    zrange[1] = -DBL_MAX;
    for (v = 0; v < m->vertex_count; v++) { /* every one used */
        float *q = cv[v].p;
        adaslice__turn_vertex(rot, m->vertices + 3 * v, q);
        zrange[0] = q[2] < zrange[0] ? q[2] : zrange[0];
        zrange[1] = q[2] > zrange[1] ? q[2] : zrange[1];
    }
    /* phi not cleared: adaslice__max_along writes every bin */
    if ((r = adaslice__profile_begin(m, &o->profile, profile, &opt, zrange, 0, err)) != ADASLICE_OK) {
        adaslice__free(&al, cv);
        return r;
    }
    if (opt.progress) opt.progress(opt.progress_user, 0);
    inverse = 1.0 / profile->bin;
    top = (double)(long)(profile->bin_count - 1);
    for (v = 0; v < m->vertex_count; v++) cv[v].bin = (uint32_t)adaslice__bin_of(profile->z0, inverse, top, cv[v].p[2]);
    r = adaslice__max_along(o, cv, rot + 6, &opt, profile, err);
    adaslice__free(&al, cv);
    if (r != ADASLICE_OK) return r;
    if (opt.progress) opt.progress(opt.progress_user, 1);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_orienter_score(const adaslice_orienter *o, const double d[3],
                                                     adaslice_direction_score *s, adaslice_error *err)
{
    adaslice_profile p;
    adaslice_plan plan;
    adaslice_error e;
    adaslice_result r;
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    memset(s, 0, sizeof *s);
    if (len > 0) { s->direction[0] = d[0] / len; s->direction[1] = d[1] / len; s->direction[2] = d[2] / len; }
    /* no height along d (a sheet seen edge-on): no layers, no plan */
    if ((r = adaslice_profile_along(o, d, &p, err)) == ADASLICE_ERR_EMPTY) { adaslice__ok(err); return ADASLICE_OK; }
    if (r != ADASLICE_OK) return r;
    r = adaslice_plan_profile(&p, &o->plan, &plan, &e);
    adaslice_profile_free(&p);
    if (r == ADASLICE_ERR_INFEASIBLE) { adaslice__ok(err); return ADASLICE_OK; }
    if (r != ADASLICE_OK) {
        if (err) *err = e;
        return r;
    }
    s->feasible = 1;
    s->layers = plan.layer_count;
    s->worst_error = plan.worst_error;
    s->mean_error = plan.layer_count ? plan.total_error / (double)plan.layer_count : 0;
    adaslice_plan_free(&plan);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_orient_scores(adaslice_direction_score *s, size_t n, double alpha)
{
    double kmax = 0, emax = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        if (!s[i].feasible) continue;
        if ((double)s[i].layers > kmax) kmax = (double)s[i].layers;
        if (s[i].worst_error > emax) emax = s[i].worst_error;
    }
    for (i = 0; i < n; i++)
        s[i].score = !s[i].feasible ? 2
                   : alpha * (kmax > 0 ? (double)s[i].layers / kmax : 0) +
                     (1 - alpha) * (emax > 0 ? s[i].worst_error / emax : 0);
}

/* Whether direction a goes before b: a lower F, on a tie nearer +z, then the lower index. */
static int adaslice__orient_before(const adaslice_direction_score *s, size_t a, size_t b)
{
    if (s[a].score != s[b].score) return s[a].score < s[b].score;
    if (s[a].direction[2] != s[b].direction[2]) return s[a].direction[2] > s[b].direction[2];
    return a < b;
}

/* Runs of falling z that adaslice_orient_minima bisects; more (directions in
   no order) and it tries every pair. A lattice and the axes make three. */
#define ADASLICE__MINIMA_RUNS 64

ADASLICE_DEF size_t adaslice_orient_minima(const adaslice_direction_score *s, size_t n, double radius,
                                           size_t *out, size_t max)
{
    double c = cos(radius), reach = sqrt(2 - 2 * c + 1e-9);
    size_t run_end[ADASLICE__MINIMA_RUNS], runs = 0, i, j, r, count = 0;
    int windowed = 1;
    /* unit neighbours within the angle are within `reach` of each other, so
       in z: each run of falling z is searched only there (a million
       directions tried every pair for a quarter of an hour) */
    for (i = 0; i < n && windowed; i++) {
        const double *a = s[i].direction;
        if (!(fabs(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] - 1) <= 1e-9)) windowed = 0;
        if (i + 1 == n || !(s[i + 1].direction[2] <= a[2])) {
            if (runs == ADASLICE__MINIMA_RUNS) windowed = 0;
            else run_end[runs++] = i + 1;
        }
    }
    if (!windowed) {
        runs = 1;
        run_end[0] = n;
    }
    for (i = 0; i < n; i++) {
        double z = s[i].direction[2];
        int lowest = 1;
        for (r = 0; r < runs && lowest; r++) {
            size_t lo = r ? run_end[r - 1] : 0, hi = run_end[r];
            if (windowed) /* the first with z at most z + reach */
                while (lo < hi) {
                    size_t mid = lo + (hi - lo) / 2;
                    if (s[mid].direction[2] > z + reach) lo = mid + 1;
                    else hi = mid;
                }
            for (j = lo; j < run_end[r] && lowest; j++) {
                const double *a = s[i].direction, *b = s[j].direction;
                if (windowed && b[2] < z - reach) break;
                if (j == i || a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < c) continue;
                if (adaslice__orient_before(s, j, i)) lowest = 0;
            }
        }
        if (!lowest) continue;
        /* insert by score into the best `max` */
        for (j = count < max ? count++ : max; j > 0 && adaslice__orient_before(s, i, out[j - 1]); j--)
            if (j < max) out[j] = out[j - 1];
        if (j < max) out[j] = i;
    }
    return count;
}

#endif /* ADASLICE_NO_ORIENT */

/* ==================================================== masks and contours */

/* A triangle under its lowest z as an unsigned key in the same order. */
typedef struct adaslice__zkey { uint32_t z, t; } adaslice__zkey;

/* -0 counts as +0; then the sign bit set for positives, every bit flipped
   for negatives, so unsigned order is the floats' order. */
static uint32_t adaslice__zbits(float z)
{
    uint32_t u;
    z += 0.0f;
    memcpy(&u, &z, sizeof u);
    return (u & 0x80000000u) ? ~u : u | 0x80000000u;
}

/* keys (given in triangle order) by z, ties by triangle: a stable radix
   sort a byte at a time, through tmp (as many keys). qsort's comparisons
   took most of the masker's set-up, which no other thread can share.
   Returns where the sorted keys are: keys or tmp. */
static adaslice__zkey *adaslice__sort_zkeys(adaslice__zkey *keys, adaslice__zkey *tmp, size_t n)
{
    size_t count[4][256], i;
    int d, b;
    memset(count, 0, sizeof count);
    for (i = 0; i < n; i++)
        for (d = 0; d < 4; d++) count[d][(keys[i].z >> (8 * d)) & 255]++;
    for (d = 0; d < 4 && n; d++) {
        size_t sum = 0;
        adaslice__zkey *t;
        if (count[d][(keys[0].z >> (8 * d)) & 255] == n) continue; /* one byte for all: in order */
        for (b = 0; b < 256; b++) { size_t c = count[d][b]; count[d][b] = sum; sum += c; }
        for (i = 0; i < n; i++) tmp[count[d][(keys[i].z >> (8 * d)) & 255]++] = keys[i];
        t = keys; keys = tmp; tmp = t;
    }
    return keys;
}

static float adaslice__tri_z(const adaslice_mesh *m, size_t t, int highest)
{
    float a = m->vertices[3 * (size_t)m->triangles[3 * t] + 2], b = m->vertices[3 * (size_t)m->triangles[3 * t + 1] + 2],
          c = m->vertices[3 * (size_t)m->triangles[3 * t + 2] + 2], r = a;
    if (highest) { if (b > r) r = b; if (c > r) r = c; }
    else { if (b < r) r = b; if (c < r) r = c; }
    return r;
}

ADASLICE_DEF size_t adaslice_masker_bytes(uint32_t width, uint32_t height, int supersample, adaslice_slice_at slice_at,
                                         size_t triangles)
{
    /* as adaslice_masker_init allocates: the image; a winding per ray (and
       a bit for envelope and core) and a coverage per pixel when
       anti-aliased, or for an anti-aliased section the cells, a bit for
       each and the rows' extents; and three words per triangle */
    double s = supersample > 1 ? supersample : 1, pixels = (double)width * height, bytes;
    int exact = s > 1 && slice_at < ADASLICE_SLICE_ENVELOPE;
    bytes = (s > 1 ? pixels : (width + 7.0) / 8 * height) + (double)triangles * (2 * sizeof(uint32_t) + 2 * sizeof(adaslice__zkey));
    if (exact) bytes += ((double)width + 1) * height * sizeof(float) + (4.0 + width / 32 + 1) * height * sizeof(uint32_t);
    else bytes += pixels * s * s * (sizeof(int16_t) + 1.0 / 8) + (s > 1 ? pixels * sizeof(uint16_t) : 0);
    return bytes >= (double)SIZE_MAX ? SIZE_MAX : (size_t)bytes;
}

ADASLICE_DEF void adaslice_masker_free(adaslice_masker *mk)
{
    adaslice_allocator al;
    if (!mk) return;
    al = mk->allocator;
    adaslice__free(&al, mk->image);
    adaslice__free(&al, mk->order);
    adaslice__free(&al, mk->active);
    adaslice__free(&al, mk->winding);
    adaslice__free(&al, mk->coverage);
    adaslice__free(&al, mk->cells);
    adaslice__free(&al, mk->extent);
    adaslice__free(&al, mk->touched);
    adaslice__free(&al, mk->seg);
    adaslice__free(&al, mk->cross);
    adaslice__free(&al, mk->changed);
    adaslice__free(&al, mk->spans);
    adaslice__free(&al, mk->crossings);
    adaslice__gaps_free(mk->gaps);
    memset(mk, 0, sizeof *mk);
}

ADASLICE_DEF adaslice_grid adaslice_grid_plate(const adaslice_mesh *mesh, int width, int height, double pitch_x,
                                               double pitch_y, const double offset[2])
{
    adaslice_grid g;
    double lo[3], hi[3];
    adaslice_mesh_bounds(mesh, lo, hi);
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = pitch_x;
    g.pitch[1] = pitch_y;
    g.width = width;
    g.height = height;
    g.origin[0] = 0.5 * (lo[0] + hi[0]) - (offset ? offset[0] : 0) - 0.5 * width * pitch_x;
    g.origin[1] = 0.5 * (lo[1] + hi[1]) - (offset ? offset[1] : 0) - 0.5 * height * pitch_y;
    return g;
}

/* The sizes of the buffers of the masker's rows: rays, pixels, cells and
   words of touched bits (anti-aliased sections: of the box's rows among
   them, which it sets in cell_rows). */
static void adaslice__masker_sizes(adaslice_masker *mk, size_t size[4])
{
    size_t s = (size_t)mk->supersample, rows = mk->rows[1] - mk->rows[0];
    size[0] = (size_t)mk->rays.width * rows * s;
    size[1] = (size_t)mk->grid.width * rows;
    mk->cell_rows[0] = mk->rows[0] > mk->box[1] ? mk->rows[0] - mk->box[1] : 0;
    mk->cell_rows[1] = mk->rows[1] > mk->box[1] ? mk->rows[1] - mk->box[1] : 0;
    if (mk->cell_rows[1] > mk->box[3]) mk->cell_rows[1] = mk->box[3];
    if (mk->cell_rows[0] > mk->cell_rows[1]) mk->cell_rows[0] = mk->cell_rows[1];
    rows = mk->cell_rows[1] - mk->cell_rows[0];
    size[2] = ((size_t)mk->box[2] + 1) * rows + 1;
    size[3] = ((size_t)mk->box[2] / 32 + 1) * rows + 1;
}

/* The sweep's buffers zeroed, at the first layer rather than at init: a
   whole masker that is only split into bands never touches them (18 MB of
   windings at 3840 x 2400), and bands zero theirs on the threads that sweep
   them. */
static void adaslice__masker_zero(adaslice_masker *mk)
{
    size_t size[4];
    adaslice__masker_sizes(mk, size);
    if (mk->changed) memset(mk->changed, 0, size[0] / 8 + 1);
    if (mk->winding) memset(mk->winding, 0, size[0] * sizeof(int16_t));
    if (mk->coverage) memset(mk->coverage, 0, size[1] * sizeof(uint16_t));
    if (mk->cells) {
        memset(mk->cells, 0, size[2] * sizeof(float));
        memset(mk->extent, 0, (4 * (size_t)(mk->cell_rows[1] - mk->cell_rows[0]) + 1) * sizeof(uint32_t));
        memset(mk->touched, 0, size[3] * sizeof(uint32_t));
    }
    mk->zeroed = 1;
}

/* The buffers of the masker's rows (mk->rows), its settings made: the
   image, and a winding per ray (a bit more for envelope and core, a
   coverage per pixel anti-aliased) or an anti-aliased section's cells for
   the box's rows among them; order and active for `triangles`. */
static adaslice_result adaslice__masker_buffers(adaslice_masker *mk, size_t triangles, adaslice_error *err)
{
    size_t size[4], rays, rows = mk->rows[1] - mk->rows[0];
    int range = mk->slice_at >= ADASLICE_SLICE_ENVELOPE;
    adaslice__masker_sizes(mk, size);
    rays = size[0];
    if (range) mk->changed = ADASLICE__CAST(unsigned char *, adaslice__alloc(&mk->allocator, rays / 8 + 1, 1));
    mk->image = ADASLICE__CAST(unsigned char *, adaslice__alloc(&mk->allocator, mk->stride, rows));
    mk->order = ADASLICE__CAST(uint32_t *, adaslice__alloc(&mk->allocator, triangles + 1, sizeof(uint32_t)));
    mk->active = ADASLICE__CAST(uint32_t *, adaslice__alloc(&mk->allocator, triangles + 1, sizeof(uint32_t)));
    if (!mk->image || !mk->order || !mk->active || (range && !mk->changed)) goto nomem;
    memset(mk->image, 0, mk->stride * rows);
    if (mk->supersample > 1 && !range) {
        mk->cells = ADASLICE__CAST(float *, adaslice__alloc(&mk->allocator, size[2], sizeof(float)));
        mk->extent = ADASLICE__CAST(uint32_t *, adaslice__alloc(&mk->allocator, 4 * (size_t)(mk->cell_rows[1] - mk->cell_rows[0]) + 1,
                                                                sizeof(uint32_t)));
        mk->touched = ADASLICE__CAST(uint32_t *, adaslice__alloc(&mk->allocator, size[3], sizeof(uint32_t)));
        if (!mk->cells || !mk->extent || !mk->touched) goto nomem;
    } else {
        /* sections need no winding per ray */
        if (!mk->gaps && !(mk->winding = ADASLICE__CAST(int16_t *, adaslice__alloc(&mk->allocator, rays, sizeof(int16_t))))) goto nomem;
        if (mk->supersample > 1 && !(mk->coverage = ADASLICE__CAST(uint16_t *, adaslice__alloc(&mk->allocator, size[1], sizeof(uint16_t)))))
            goto nomem;
    }
    return ADASLICE_OK;
nomem:
    adaslice_masker_free(mk);
    return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for %zu rays", rays);
}

ADASLICE_DEF adaslice_result adaslice_masker_init(adaslice_masker *mk, const adaslice_mesh *mesh,
                                                  const adaslice_grid *grid, const adaslice_mask_options *options,
                                                  adaslice_error *err)
{
    adaslice_result r, res;
    adaslice__zkey *keys, *sorted;
    double lo[3], hi[3];
    size_t t;
    int k, s = options && options->supersample ? options->supersample : 1;
    if (!mk) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: no masker given");
    memset(mk, 0, sizeof *mk);
    if ((r = adaslice__grid_check(grid, err)) != ADASLICE_OK) return r;
    if (grid->axis != ADASLICE_AXIS_Z)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: the grid's rays must run along z");
    if (s < 1 || s > 16 || (double)grid->width * s > ADASLICE__GRID_LIMIT || (double)grid->height * s > ADASLICE__GRID_LIMIT)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: supersampling %d is outside 1..16 (or too fine for the grid)", s);
    if (!mesh || !mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "masks: the mesh has no triangles");
    mk->slice_at = options ? options->slice_at : ADASLICE_SLICE_MIDDLE;
    mk->bin = options && options->bin != 0 ? options->bin : ADASLICE_DEFAULT_BIN;
    if ((unsigned)mk->slice_at > ADASLICE_SLICE_CORE || !(mk->bin > 0) || mk->bin > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: slice_at %d or bin %g is not one of the rules",
                              (int)mk->slice_at, mk->bin);
    mk->allocator = adaslice__allocator(options ? options->allocator : NULL);
    mk->mesh = mesh;
    mk->grid = *grid;
    mk->supersample = s;
    mk->rays = *grid;
    mk->rays.pitch[0] = grid->pitch[0] / s;
    mk->rays.pitch[1] = grid->pitch[1] / s;
    mk->rays.width = grid->width * s;
    mk->rays.height = grid->height * s;
    mk->rows[1] = (uint32_t)grid->height;
    adaslice_mesh_bounds(mesh, lo, hi); /* once: the depths' origin, and an anti-aliased section's box */
    mk->depth_origin = lo[2];
    mk->done = -DBL_MAX;
    mk->stride = s == 1 ? ((size_t)grid->width + 7) / 8 : (size_t)grid->width;
    if (!(options && options->edges_balance) && (res = adaslice__gaps_init(&mk->gaps, mesh, &mk->allocator, err)) != ADASLICE_OK)
        return res;
    mk->sections = mk->gaps != NULL;
    if (mk->gaps && mk->slice_at >= ADASLICE_SLICE_ENVELOPE) {
        size_t loose = mk->gaps->count;
        adaslice_masker_free(mk);
        return adaslice__fail(err, ADASLICE_ERR_UNSUPPORTED, 0, 0,
                              "masks: envelope and core masks read the part along rays and need a closed mesh; "
                              "this one has %zu unbalanced edges (repair it, or slice at a height)", loose);
    }
    if (s > 1 && mk->slice_at < ADASLICE_SLICE_ENVELOPE) {
        /* an anti-aliased section: its exact coverage, from the section's
           edges, which stay within the mesh's box (a large display's cells
           cost their first touch) */
        double box[4];
        box[0] = floor((lo[0] - grid->origin[0]) / grid->pitch[0]);
        box[1] = floor((lo[1] - grid->origin[1]) / grid->pitch[1]);
        box[2] = ceil((hi[0] - grid->origin[0]) / grid->pitch[0]) + 1;
        box[3] = ceil((hi[1] - grid->origin[1]) / grid->pitch[1]) + 1;
        for (k = 0; k < 4; k++) {
            double most = k & 1 ? grid->height : grid->width;
            box[k] = box[k] < 0 ? 0 : box[k] > most ? most : box[k];
        }
        mk->box[0] = (uint32_t)box[0];
        mk->box[1] = (uint32_t)box[1];
        mk->box[2] = (uint32_t)(box[2] - box[0]);
        mk->box[3] = (uint32_t)(box[3] - box[1]);
        mk->fractions = options ? options->fractions : NULL;
        for (k = 0; k < 32; k++) mk->bit_at[(uint32_t)(0x077CB531u << k) >> 27] = (unsigned char)k;
    }
    for (k = 0; k <= s * s; k++) mk->grey[k] = (unsigned char)((255 * k + (s * s) / 2) / (s * s));
    if ((res = adaslice__masker_buffers(mk, mesh->triangle_count, err)) != ADASLICE_OK) return res;
    keys = ADASLICE__CAST(adaslice__zkey *, adaslice__alloc(&mk->allocator, 2 * mesh->triangle_count, sizeof(adaslice__zkey)));
    if (!keys) {
        adaslice_masker_free(mk);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for %zu triangles", mesh->triangle_count);
    }
    for (t = 0; t < mesh->triangle_count; t++) { keys[t].z = adaslice__zbits(adaslice__tri_z(mesh, t, 0)); keys[t].t = (uint32_t)t; }
    sorted = adaslice__sort_zkeys(keys, keys + mesh->triangle_count, mesh->triangle_count);
    for (t = 0; t < mesh->triangle_count; t++) mk->order[t] = sorted[t].t;
    mk->count = mesh->triangle_count;
    adaslice__free(&mk->allocator, keys);
    adaslice__ok(err);
    return ADASLICE_OK;
}

/* The bands [b0, b1] of `rows` (count + 1 bounds) that triangle t can reach:
   its rows with a pixel to spare either way; every band for one so far off
   the grid that rasterising it fails, so that every band fails as the whole
   masker does. 0 when it reaches none. */
static int adaslice__band_span(const adaslice_masker *mk, const uint32_t *rows, size_t count, uint32_t t, size_t *b0, size_t *b1)
{
    const adaslice_grid *g = &mk->grid;
    const adaslice_mesh *m = mk->mesh;
    double lo = DBL_MAX, hi = -DBL_MAX, far = ADASLICE__GRID_LIMIT / 2 / mk->supersample;
    size_t a, b;
    int k;
    for (k = 0; k < 3; k++) {
        const float *p = m->vertices + 3 * (size_t)m->triangles[3 * (size_t)t + k];
        double u = (p[0] - g->origin[0]) / g->pitch[0], v = (p[1] - g->origin[1]) / g->pitch[1];
        if (!(fabs(u) < far && fabs(v) < far)) { *b0 = 0; *b1 = count - 1; return 1; }
        if (v < lo) lo = v;
        if (v > hi) hi = v;
    }
    lo -= 1;
    hi += 1;
    if (hi < (double)rows[0] || lo >= (double)rows[count]) return 0;
    /* the last band starting at or below lo, and at or below hi */
    for (a = 0, b = count; a + 1 < b;) { size_t c = (a + b) / 2; if ((double)rows[c] <= lo) a = c; else b = c; }
    *b0 = a;
    for (b = count; a + 1 < b;) { size_t c = (a + b) / 2; if ((double)rows[c] <= hi) a = c; else b = c; }
    *b1 = a;
    return 1;
}

ADASLICE_DEF adaslice_result adaslice_masker_bands(const adaslice_masker *whole, const uint32_t *rows, size_t count,
                                                   adaslice_masker *bands, adaslice_error *err)
{
    size_t b, b0, b1, t, *kept;
    uint32_t *span;
    adaslice_allocator al;
    adaslice_result r;
    if (!whole || !rows || !bands || !count) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: no masker or bands given");
    if (whole->sections)
        return adaslice__fail(err, ADASLICE_ERR_UNSUPPORTED, 0, 0,
                              "masks: an open mesh's masks are filled from its whole sections (its gaps closed by "
                              "chords): one masker makes them");
    if (whole->done != -DBL_MAX || whole->rows[0] != 0 || whole->rows[1] != (uint32_t)whole->grid.height)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: bands are split from a whole masker before its first layer");
    if (rows[count] > (uint32_t)whole->grid.height)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: the bands end at row %u, past the %d-row grid",
                              (unsigned)rows[count], whole->grid.height);
    for (b = 0; b < count; b++)
        if (!(rows[b] < rows[b + 1]))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: band %zu's rows [%u, %u) are none", b,
                                  (unsigned)rows[b], (unsigned)rows[b + 1]);
    al = whole->allocator;
    kept = ADASLICE__CAST(size_t *, adaslice__alloc(&al, count, sizeof(size_t)));
    /* each facet's first and last band, found once (finding them again to
       fill the bands took a third of the split), in the mesh's order: in the
       masker's, by height, each facet's corners were a load from anywhere */
    span = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, 2 * whole->mesh->triangle_count + 1, sizeof(uint32_t)));
    if (!kept || !span) {
        adaslice__free(&al, kept);
        adaslice__free(&al, span);
        return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for %zu bands", count);
    }
    memset(kept, 0, count * sizeof(size_t));
    memset(bands, 0, count * sizeof *bands);
    for (t = 0; t < whole->mesh->triangle_count; t++) {
        span[2 * t] = 1;
        span[2 * t + 1] = 0; /* none */
        if (!adaslice__band_span(whole, rows, count, (uint32_t)t, &b0, &b1)) continue;
        span[2 * t] = (uint32_t)b0;
        span[2 * t + 1] = (uint32_t)b1;
    }
    for (t = 0; t < whole->count; t++) /* whole's own: all of the mesh's unless a band was split again */
        for (b = span[2 * (size_t)whole->order[t]]; b <= span[2 * (size_t)whole->order[t] + 1]; b++) kept[b]++;
    for (b = 0; b < count; b++) {
        adaslice_masker *mk = &bands[b];
        /* the settings; no buffer, nothing swept */
        mk->mesh = whole->mesh;
        mk->grid = whole->grid;
        mk->supersample = whole->supersample;
        mk->stride = whole->stride;
        mk->rays = whole->rays;
        mk->depth_origin = whole->depth_origin;
        mk->done = whole->done;
        memcpy(mk->box, whole->box, sizeof mk->box);
        memcpy(mk->bit_at, whole->bit_at, sizeof mk->bit_at);
        mk->fractions = whole->fractions;
        memcpy(mk->grey, whole->grey, sizeof mk->grey);
        mk->slice_at = whole->slice_at;
        mk->bin = whole->bin;
        mk->allocator = al;
        mk->rows[0] = rows[b];
        mk->rows[1] = rows[b + 1];
        if ((r = adaslice__masker_buffers(mk, kept[b], err)) != ADASLICE_OK) {
            while (b--) adaslice_masker_free(&bands[b]);
            adaslice__free(&al, kept);
            adaslice__free(&al, span);
            return r;
        }
    }
    /* whole's order filtered keeps its order: the same facets in the same
       sequence, so each band's sums run as the whole masker's */
    for (t = 0; t < whole->count; t++) {
        uint32_t f = whole->order[t];
        for (b = span[2 * f]; b <= span[2 * f + 1]; b++) bands[b].order[bands[b].count++] = f;
    }
    adaslice__free(&al, kept);
    adaslice__free(&al, span);
    adaslice__ok(err);
    return ADASLICE_OK;
}

/* Ray i of ray row `row` turns on or off in the image. */
static void adaslice__mask_show(adaslice_masker *mk, size_t row, size_t i, int on)
{
    size_t s = (size_t)mk->supersample, r = row / s - mk->rows[0];
    mk->lit_rays += on ? 1 : -1;
    if (s == 1) {
        mk->image[r * mk->stride + (i >> 3)] ^= (unsigned char)(0x80u >> (i & 7));
    } else {
        size_t px = r * mk->stride + i / s;
        mk->coverage[px] = (uint16_t)(mk->coverage[px] + (on ? 1 : -1));
        mk->image[px] = mk->grey[mk->coverage[px]];
    }
}

/* A ray's winding number changes by one at each sample; a pixel changes
   when one of its rays crosses between zero and positive. Sweeping a
   layer's range (envelope, core) the samples come triangle by triangle, not
   in depth order along each ray: the windings are summed (their total
   needs no order), the image still shows the range's bottom, and the spans
   are kept for adaslice__mask_range to read each ray's crossings in order. */
static void adaslice__mask_visit(void *ctx, const adaslice__span *span)
{
    adaslice_masker *mk = ADASLICE__CAST(adaslice_masker *, ctx);
    int16_t step = (span->face & ADASLICE_SAMPLE_LEAVES) ? -1 : 1;
    int16_t *w = mk->winding + ((size_t)span->row - (size_t)mk->rows[0] * mk->supersample) * (size_t)mk->rays.width;
    int i;
    if (mk->range) {
        if (mk->span_count == mk->span_cap) {
            adaslice__span *more = ADASLICE__CAST(adaslice__span *, adaslice__grow(&mk->allocator, mk->spans, mk->span_count,
                                                                                   &mk->span_cap, mk->span_count + 1, sizeof *more));
            if (!more) { mk->nomem = 1; return; }
            mk->spans = more;
        }
        mk->spans[mk->span_count++] = *span;
        for (i = span->first; i < span->end; i++) w[i] = (int16_t)(w[i] + step);
        return;
    }
    for (i = span->first; i < span->end; i++) {
        int before = w[i] > 0, after;
        w[i] = (int16_t)(w[i] + step);
        after = w[i] > 0;
        if (before != after) adaslice__mask_show(mk, (size_t)span->row, (size_t)i, after);
    }
}

typedef struct adaslice__crossing {
    uint32_t ray;   /* in the row */
    int32_t step;   /* +1 enters, -1 leaves */
    double depth;
} adaslice__crossing;

static int adaslice__crossing_cmp(const void *a, const void *b)
{
    const adaslice__crossing *x = ADASLICE__CAST(const adaslice__crossing *, a), *y = ADASLICE__CAST(const adaslice__crossing *, b);
    if (x->ray != y->ray) return x->ray < y->ray ? -1 : 1;
    return x->depth < y->depth ? -1 : x->depth > y->depth;
}

static int adaslice__span_row_cmp(const void *a, const void *b)
{
    const adaslice__span *x = ADASLICE__CAST(const adaslice__span *, a), *y = ADASLICE__CAST(const adaslice__span *, b);
    return x->row != y->row ? (x->row < y->row ? -1 : 1) : (x->first < y->first ? -1 : x->first > y->first);
}

/* After a layer's range is swept: row by row, each ray's crossings in the
   range sorted by depth, its winding w0 at the bottom (its winding now less
   their sum) carried through them, a depth's crossings at once. Envelope:
   lit if w0 or the winding after some depth is positive (an inside interval
   meets the range); core: lit if w0 and every one is. Rays shown otherwise
   than their inside at the top get a bit, set right before the next sweep. */
static adaslice_result adaslice__mask_range(adaslice_masker *mk, adaslice_error *err)
{
    size_t a = 0, b, k, n, c, width = (size_t)mk->rays.width, first = (size_t)mk->rows[0] * mk->supersample;
    int envelope = mk->range == ADASLICE_SLICE_ENVELOPE;
    if (mk->span_count) qsort(mk->spans, mk->span_count, sizeof *mk->spans, adaslice__span_row_cmp);
    for (; a < mk->span_count; a = b) {
        size_t row = (size_t)mk->spans[a].row;
        for (n = 0, b = a; b < mk->span_count && (size_t)mk->spans[b].row == row; b++)
            n += (size_t)(mk->spans[b].end - mk->spans[b].first);
        if (n > mk->crossing_cap) {
            adaslice__crossing *more = ADASLICE__CAST(adaslice__crossing *, adaslice__grow(&mk->allocator, mk->crossings, 0,
                                                                                           &mk->crossing_cap, n, sizeof *more));
            if (!more) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for a row's %zu crossings", n);
            mk->crossings = more;
        }
        for (n = 0, k = a; k < b; k++) {
            const adaslice__span *sp = &mk->spans[k];
            int i;
            for (i = sp->first; i < sp->end; i++, n++) {
                mk->crossings[n].ray = (uint32_t)i;
                mk->crossings[n].step = (sp->face & ADASLICE_SAMPLE_LEAVES) ? -1 : 1;
                mk->crossings[n].depth = adaslice__span_depth(sp, i);
            }
        }
        qsort(mk->crossings, n, sizeof *mk->crossings, adaslice__crossing_cmp);
        for (c = 0; c < n;) {
            size_t end = c, ray = (row - first) * width + mk->crossings[c].ray;
            long w1 = mk->winding[ray], w, sum = 0;
            int before, lit;
            for (; end < n && mk->crossings[end].ray == mk->crossings[c].ray; end++) sum += mk->crossings[end].step;
            w = w1 - sum;
            before = lit = w > 0;
            while (c < end) {
                double d = mk->crossings[c].depth;
                for (; c < end && mk->crossings[c].depth == d; c++) w += mk->crossings[c].step;
                if (envelope ? w > 0 : w <= 0) lit = envelope;
            }
            if (lit != before) adaslice__mask_show(mk, row, ray % width, lit);
            if (lit != (w1 > 0)) mk->changed[ray >> 3] |= (unsigned char)(1u << (ray & 7));
        }
    }
    return ADASLICE_OK;
}

/* The rays the last range showed otherwise than their inside at its top
   show it again. */
static void adaslice__mask_settle(adaslice_masker *mk)
{
    size_t k, width = (size_t)mk->rays.width, first = (size_t)mk->rows[0] * mk->supersample;
    for (k = 0; k < mk->span_count; k++) {
        const adaslice__span *sp = &mk->spans[k];
        size_t row = (size_t)sp->row, i;
        for (i = (size_t)sp->first; i < (size_t)sp->end; i++) {
            size_t ray = (row - first) * width + i;
            unsigned char bit = (unsigned char)(1u << (ray & 7));
            if (!(mk->changed[ray >> 3] & bit)) continue; /* shown right, or set right through another span */
            mk->changed[ray >> 3] &= (unsigned char)~bit;
            adaslice__mask_show(mk, row, i, mk->winding[ray] > 0);
        }
    }
    mk->span_count = 0;
}

/* ---- masks of open meshes: each layer's section filled in the plane */
static void adaslice__set_bits(unsigned char *row, size_t a, size_t b)
{
    for (; a < b && (a & 7); a++) row[a >> 3] |= (unsigned char)(0x80u >> (a & 7));
    for (; a + 8 <= b; a += 8) row[a >> 3] = 0xff;
    for (; a < b; a++) row[a >> 3] |= (unsigned char)(0x80u >> (a & 7));
}

static int adaslice__push_segment(adaslice_masker *mk, size_t *count, const double from[2], const double to[2])
{
    double *s;
    if (4 * (*count + 1) > mk->seg_cap) {
        s = ADASLICE__CAST(double *, adaslice__grow(&mk->allocator, mk->seg, 4 * *count, &mk->seg_cap, 4 * (*count + 1), sizeof(double)));
        if (!s) return 0;
        mk->seg = s;
    }
    s = mk->seg + 4 * (*count)++;
    s[0] = from[0]; s[1] = from[1]; s[2] = to[0]; s[3] = to[1];
    return 1;
}

/* The centre of ray row j: one expression, so cuts that share an end agree. */
static double adaslice__row_centre(const adaslice_grid *g, long j) { return g->origin[1] + ((double)j + 0.5) * g->pitch[1]; }

/* The first ray row whose centre is at or above y, within [0, rows]. */
static long adaslice__first_row(const adaslice_grid *g, double y)
{
    double c = ceil((y - g->origin[1]) / g->pitch[1] - 0.5);
    long j = c < 0 ? 0 : c > g->height ? g->height : (long)c;
    while (j > 0 && adaslice__row_centre(g, j - 1) >= y) j--;
    while (j < g->height && adaslice__row_centre(g, j) < y) j++;
    return j;
}

/* Fills the mask from the directed segments: each crosses the ray rows whose
   centres lie in [its lower y, its upper y), one going down (in y) raising
   the winding to its right by one; a ray is lit where the winding is positive. */
static adaslice_result adaslice__fill_section(adaslice_masker *mk, size_t segments, double height, adaslice_error *err)
{
    const adaslice_grid *g = &mk->rays;
    size_t k, n = 0, c;
    for (k = 0; k < segments; k++) {
        const double *p = mk->seg + 4 * k;
        double ylo = p[1] < p[3] ? p[1] : p[3], yhi = p[1] < p[3] ? p[3] : p[1];
        long j, j0, j1;
        if (!(yhi > ylo)) continue; /* along a row: crosses none */
        j0 = adaslice__first_row(g, ylo);
        j1 = adaslice__first_row(g, yhi);
        if (j0 < (long)mk->rows[0]) j0 = (long)mk->rows[0]; /* s is 1: ray rows are pixel rows */
        if (j1 > (long)mk->rows[1]) j1 = (long)mk->rows[1];
        if (j1 > j0 && n + (size_t)(j1 - j0) > mk->cross_cap) {
            uint64_t *more = ADASLICE__CAST(uint64_t *, adaslice__grow(&mk->allocator, mk->cross, n, &mk->cross_cap, n + (size_t)(j1 - j0), sizeof(uint64_t)));
            if (!more) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for the section at %g mm", height);
            mk->cross = more;
        }
        for (j = j0; j < j1; j++) {
            double v = adaslice__row_centre(g, j), x = p[0] + (v - p[1]) * (p[2] - p[0]) / (p[3] - p[1]);
            double t = (x - g->origin[0]) / g->pitch[0] - 0.5;
            uint64_t i = t < 0 ? 0 : t >= g->width ? (uint64_t)g->width : (uint64_t)floor(t) + 1;
            if (i > (uint64_t)g->width) i = (uint64_t)g->width;
            mk->cross[n++] = (uint64_t)j << 32 | i << 1 | (p[3] < p[1]);
        }
    }
    if (n) qsort(mk->cross, n, sizeof *mk->cross, adaslice__u64_cmp);
    memset(mk->image, 0, mk->stride * (size_t)(mk->rows[1] - mk->rows[0]));
    mk->lit_rays = 0;
    for (c = 0; c < n;) {
        size_t row = (size_t)(mk->cross[c] >> 32);
        int w = 0;
        for (; c < n && (size_t)(mk->cross[c] >> 32) == row; c++) {
            size_t a = (size_t)((mk->cross[c] >> 1) & 0x7fffffffu), b;
            w += (mk->cross[c] & 1) ? 1 : -1;
            b = c + 1 < n && (size_t)(mk->cross[c + 1] >> 32) == row ? (size_t)((mk->cross[c + 1] >> 1) & 0x7fffffffu) : (size_t)g->width;
            if (w <= 0 || b <= a) continue;
            mk->lit_rays += (long long)(b - a);
            adaslice__set_bits(mk->image + (row - mk->rows[0]) * mk->stride, a, b);
        }
    }
    return ADASLICE_OK;
}

/* ---- anti-aliased sections: exact coverage (signed area and cover, as
   font rasterisers accumulate it). In pixel units, a piece of an edge
   inside pixel row r and column c, going down by h (the winding to its
   +x side rises by h) at mean x = c + f, adds to the integral of the
   winding over pixel c the area h (1 - f) to its right there, and h to
   every pixel after. Kept as differences, d[c] += h (1 - f) and
   d[c + 1] += h f, a prefix sum along the row gives every pixel's
   integral; pieces left of the grid count at its left edge. */
static void adaslice__cover_cell(float *d, uint32_t *bits, uint32_t *ext, long c, double h, double f)
{
    if (f < 0) f = 0;
    if (f > 1) f = 1;
    d[c] += (float)(h * (1 - f));
    d[c + 1] += (float)(h * f);
    bits[c >> 5] |= 1u << (c & 31);
    bits[(c + 1) >> 5] |= 1u << ((c + 1) & 31);
    if ((uint32_t)c < ext[0] || ext[1] == 0) ext[0] = (uint32_t)c;
    if ((uint32_t)c + 2 > ext[1]) ext[1] = (uint32_t)c + 2;
}

/* The piece of an edge within pixel row r, from (xa, ya) to (xb, yb). */
static void adaslice__cover_piece(adaslice_masker *mk, long r, double xa, double ya, double xb, double yb)
{
    long width = (long)mk->box[2], c;
    size_t at = (size_t)(r - (long)mk->cell_rows[0]);
    float *d = mk->cells + at * ((size_t)width + 1);
    uint32_t *ext = mk->extent + 4 * at, *bits = mk->touched + at * ((size_t)width / 32 + 1);
    double h = ya - yb, x0 = xa < xb ? xa : xb, x1 = xa < xb ? xb : xa, u, v;
    if (h == 0 || x0 >= (double)width) return;
    if (x1 == x0) {
        c = x0 < 0 ? 0 : (long)x0;
        adaslice__cover_cell(d, bits, ext, c, h, x0 - (double)c);
        return;
    }
    /* split where it crosses pixel columns, each part's height in proportion */
    u = x0;
    if (u < 0) {
        v = x1 < 0 ? x1 : 0;
        adaslice__cover_cell(d, bits, ext, 0, h * (v - u) / (x1 - x0), 0);
        u = v;
    }
    while (u < x1 && u < (double)width) {
        c = (long)u;
        v = (double)(c + 1) < x1 ? (double)(c + 1) : x1;
        adaslice__cover_cell(d, bits, ext, c, h * (v - u) / (x1 - x0), 0.5 * (u + v) - (double)c);
        u = v;
    }
}

/* An edge from (x0, y0) to (x1, y1), mm, cut at the pixel rows it crosses,
   in pixels from the box's corner. Each cut point is computed from the
   edge's own ends, one expression for both rows that share it. */
static void adaslice__cover_edge(adaslice_masker *mk, const double *p)
{
    const adaslice_grid *g = &mk->grid;
    double x0 = (p[0] - g->origin[0]) / g->pitch[0] - mk->box[0], y0 = (p[1] - g->origin[1]) / g->pitch[1] - mk->box[1];
    double x1 = (p[2] - g->origin[0]) / g->pitch[0] - mk->box[0], y1 = (p[3] - g->origin[1]) / g->pitch[1] - mk->box[1];
    double ylo = y0 < y1 ? y0 : y1, yhi = y0 < y1 ? y1 : y0, ya, yb, xa, xb, rows = (double)mk->cell_rows[1];
    long r, r0, r1;
    if (!(yhi > ylo) || yhi <= (double)mk->cell_rows[0] || ylo >= rows) return;
    r0 = ylo < (double)mk->cell_rows[0] ? (long)mk->cell_rows[0] : (long)ylo;
    r1 = yhi >= rows ? (long)rows - 1 : (long)ceil(yhi) - 1;
    for (r = r0; r <= r1; r++) {
        double lo = (double)r > ylo ? (double)r : ylo, hi = (double)(r + 1) < yhi ? (double)(r + 1) : yhi;
        if (!(hi > lo)) continue;
        ya = y0 > y1 ? hi : lo; /* in the edge's direction */
        yb = y0 > y1 ? lo : hi;
        xa = ya == y0 ? x0 : ya == y1 ? x1 : x0 + (ya - y0) * (x1 - x0) / (y1 - y0);
        xb = yb == y0 ? x0 : yb == y1 ? x1 : x0 + (yb - y0) * (x1 - x0) / (y1 - y0);
        adaslice__cover_piece(mk, r, xa, ya, xb, yb);
    }
}

/* Pixels [from, to) of the box's row r covered `f`, at `level`. */
static long long adaslice__cover_run(adaslice_masker *mk, size_t r, size_t from, size_t to, double f, int level, size_t *first,
                                     size_t *end)
{
    size_t c, at = (r + mk->box[1]) * (size_t)mk->grid.width + mk->box[0];
    if (mk->fractions)
        for (c = from; c < to; c++) mk->fractions[at + c] = (float)f;
    if (!level || to <= from) return 0;
    memset(mk->image + (r + mk->box[1] - mk->rows[0]) * mk->stride + mk->box[0] + from, mk->grey[level], to - from);
    if (from < *first) *first = from;
    *end = to;
    return (long long)level * (long long)(to - from);
}

/* The section's edges into grey: each row's prefix sums at the cells it
   touched (found a word of bits at a time), the level between them spread
   as runs; the rows' previous grey cleared first. The covered fraction is
   the integral of the winding clamped to [0, 1], rounded to s*s + 1 levels. */
static void adaslice__fill_coverage(adaslice_masker *mk, size_t segments)
{
    size_t k, width = mk->box[2], words = width / 32 + 1, r, rows = mk->cell_rows[1], r0 = mk->cell_rows[0];
    double levels = (double)mk->supersample * mk->supersample;
    long long lit = 0;
    for (k = 0; k < segments; k++) adaslice__cover_edge(mk, mk->seg + 4 * k);
    if (mk->fractions)
        memset(mk->fractions + (size_t)mk->rows[0] * (size_t)mk->grid.width, 0,
               (size_t)mk->grid.width * (size_t)(mk->rows[1] - mk->rows[0]) * sizeof(float));
    for (r = r0; r < rows; r++) {
        uint32_t *ext = mk->extent + 4 * (r - r0), *bits = mk->touched + (r - r0) * words;
        unsigned char *img = mk->image + (r + mk->box[1] - mk->rows[0]) * mk->stride + mk->box[0];
        float *d = mk->cells + (r - r0) * (width + 1), *fr = mk->fractions ? mk->fractions + (r + mk->box[1]) * (size_t)mk->grid.width + mk->box[0] : NULL;
        size_t w, at = 0, first = width, end = 0;
        double sum = 0, f = 0;
        int level = 0;
        if (ext[3] > ext[2]) memset(img + ext[2], 0, ext[3] - ext[2]);
        ext[2] = ext[3] = 0;
        if (ext[1] == 0) continue;
        for (w = ext[0] / 32; w <= (ext[1] - 1) / 32; w++) {
            while (bits[w]) {
                uint32_t low = bits[w] & (0u - bits[w]);
                size_t c = w * 32 + mk->bit_at[(uint32_t)(low * 0x077CB531u) >> 27];
                bits[w] ^= low;
                /* the pixels since the last cell keep its level */
                lit += adaslice__cover_run(mk, r, at, c, f, level, &first, &end);
                sum += d[c];
                d[c] = 0;
                if (c == width) { at = width; break; }
                f = sum < 0 ? 0 : sum > 1 ? 1 : sum;
                level = (int)(f * levels + 0.5);
                if (fr) fr[c] = (float)f;
                if (level) {
                    img[c] = mk->grey[level];
                    lit += level;
                    if (c < first) first = c;
                    end = c + 1;
                }
                at = c + 1;
            }
        }
        lit += adaslice__cover_run(mk, r, at, width, f, level, &first, &end);
        ext[0] = ext[1] = 0;
        ext[2] = (uint32_t)(first < end ? first : 0);
        ext[3] = (uint32_t)end;
    }
    mk->lit_rays = lit;
}

/* The mask at `height` of a mesh with unbalanced edges: the facets' cuts and
   the chords of the gaps (see "sections of open meshes"), filled. */
static adaslice_result adaslice__masker_section(adaslice_masker *mk, double height, adaslice_error *err)
{
    const adaslice_mesh *m = mk->mesh;
    size_t k, kept = 0, segments = 0, j;
    adaslice_result r;
    /* facets whose lowest corner is at or below the plane join; those whose
       highest is at or below it are done */
    while (mk->next < mk->count && (double)adaslice__tri_z(m, mk->order[mk->next], 0) <= height)
        mk->active[mk->active_count++] = mk->order[mk->next++];
    for (k = 0; k < mk->active_count; k++) {
        uint32_t t = mk->active[k];
        const uint32_t *c = m->triangles + 3 * (size_t)t;
        double from[2] = {0, 0}, to[2] = {0, 0};
        int e;
        if (!((double)adaslice__tri_z(m, t, 1) > height)) continue;
        mk->active[kept++] = t;
        if (adaslice__zero_area(m->vertices, c)) continue;
        for (e = 0; e < 3; e++) {
            uint32_t p = c[e], q = c[(e + 1) % 3];
            int p_below = (double)m->vertices[3 * (size_t)p + 2] <= height, q_below = (double)m->vertices[3 * (size_t)q + 2] <= height;
            if (p_below == q_below) continue;
            /* the facet's boundary going up ends its cut, coming down starts it */
            if (p_below) adaslice__cut_point(m, p, q, height, to);
            else adaslice__cut_point(m, q, p, height, from);
        }
        if (!adaslice__push_segment(mk, &segments, from, to)) goto nomem;
    }
    mk->active_count = kept;
    if (mk->gaps) {
        if ((r = adaslice__gaps_at(mk->gaps, m, height, err)) != ADASLICE_OK) return r;
        for (j = 0; j < mk->gaps->heads; j++)
            if (!adaslice__push_segment(mk, &segments, mk->gaps->tail + 2 * (size_t)mk->gaps->taker[j], mk->gaps->head + 2 * j)) goto nomem;
    }
    if (mk->cells) { adaslice__fill_coverage(mk, segments); return ADASLICE_OK; }
    return adaslice__fill_section(mk, segments, height, err);
nomem:
    return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for the section at %g mm", height);
}

/* Applies the samples below `height` not applied yet; with `past`, those
   at it too. */
static adaslice_result adaslice__masker_sweep(adaslice_masker *mk, double height, int past, adaslice_error *err)
{
    adaslice__raster r;
    const adaslice_mesh *m = mk->mesh;
    double h = height - mk->depth_origin;
    size_t k, kept = 0;
    if (past && h >= mk->done && h < DBL_MAX) h = nextafter(h, DBL_MAX);
    if (!(h >= mk->done) || h > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: height %g mm is below the previous one", height);
    if (!mk->zeroed) adaslice__masker_zero(mk);
    if (mk->gaps || mk->cells) {
        adaslice_result res = adaslice__masker_section(mk, height, err);
        if (res != ADASLICE_OK) return res;
        mk->done = h;
        mk->lit = (double)mk->lit_rays / ((double)mk->supersample * mk->supersample);
        adaslice__ok(err);
        return ADASLICE_OK;
    }
    /* triangles starting below the new height join; those ending below the
       previous height (whose samples are all applied) leave */
    while (mk->next < mk->count && adaslice__tri_z(m, mk->order[mk->next], 0) - mk->depth_origin < h)
        mk->active[mk->active_count++] = mk->order[mk->next++];
    for (k = 0; k < mk->active_count; k++)
        if (adaslice__tri_z(m, mk->active[k], 1) - mk->depth_origin >= mk->done) mk->active[kept++] = mk->active[k];
    mk->active_count = kept;
    memset(&r, 0, sizeof r);
    r.grid = &mk->rays;
    r.depth_origin = mk->depth_origin;
    r.row_first = (int)mk->rows[0] * mk->supersample;
    r.row_end = (int)mk->rows[1] * mk->supersample;
    r.slab = 1;
    r.slab_lo = mk->done;
    r.slab_hi = h;
    r.fn = adaslice__mask_visit;
    r.ctx = mk;
    for (k = 0; k < mk->active_count; k++)
        if (adaslice__raster_triangle(&r, m, mk->active[k]))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "masks: triangle %u lies more than 2^21 pixels from the printer's grid", (unsigned)mk->active[k]);
    mk->done = h;
    mk->lit = (double)mk->lit_rays / ((double)mk->supersample * mk->supersample);
    if (mk->nomem) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "masks: out of memory for the samples below %g mm", height);
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_masker_slice(adaslice_masker *mk, double height, adaslice_error *err)
{
    if (mk->span_count) adaslice__mask_settle(mk);
    return adaslice__masker_sweep(mk, height, 0, err);
}

ADASLICE_DEF adaslice_result adaslice_masker_layer(adaslice_masker *mk, double z_bottom, double z_top, adaslice_error *err)
{
    adaslice_result r;
    double half = 0.5 * mk->bin;
    if (!(z_top >= z_bottom))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "masks: layer [%g, %g] mm is upside down", z_bottom, z_top);
    /* bottom and top: the centre of the first or last bin, the middle if the
       layer is thinner than a bin */
    if (half > 0.5 * (z_top - z_bottom)) half = 0.5 * (z_top - z_bottom);
    switch (mk->slice_at) {
    case ADASLICE_SLICE_BOTTOM: return adaslice_masker_slice(mk, z_bottom + half, err);
    case ADASLICE_SLICE_TOP: return adaslice_masker_slice(mk, z_top - half, err);
    case ADASLICE_SLICE_ENVELOPE:
    case ADASLICE_SLICE_CORE:
        /* the open range (z_bottom, z_top): a face lying at either end is
           the boundary of the layers it parts, inside neither */
        if (mk->span_count) adaslice__mask_settle(mk);
        if ((r = adaslice__masker_sweep(mk, z_bottom, 1, err)) != ADASLICE_OK) return r;
        if (z_top - mk->depth_origin < mk->done) return ADASLICE_OK; /* no thickness: the section */
        mk->range = (int)mk->slice_at;
        r = adaslice__masker_sweep(mk, z_top, 0, err);
        if (r == ADASLICE_OK) r = adaslice__mask_range(mk, err);
        mk->range = 0;
        mk->lit = (double)mk->lit_rays / ((double)mk->supersample * mk->supersample);
        return r;
    default: return adaslice_masker_slice(mk, 0.5 * (z_bottom + z_top), err);
    }
}


#ifndef ADASLICE_NO_CONTOURS
/* ---- contours */
/* A cut mesh edge as (its vertex at or below the plane, its vertex above). Both
   triangles sharing the edge name it the same way, so it is the chaining key,
   and its point is interpolated the same way whichever triangle asks. */
typedef struct adaslice__cut { uint32_t below, above; } adaslice__cut;

typedef struct adaslice__segment {
    adaslice__cut from, to;  /* where the triangle's boundary comes down, where it goes up */
    uint32_t next;           /* the segment continuing from `to`, or NONE */
    uint32_t same_from;      /* the next segment filed under the same `from` */
    unsigned char state;     /* ADASLICE__HAS_PREV | ADASLICE__USED */
} adaslice__segment;

#define ADASLICE__HAS_PREV 1
#define ADASLICE__USED 2
#define ADASLICE__NO_KEY (~(uint64_t)0) /* below == above: no edge */

typedef struct adaslice__slot { uint64_t key; uint32_t head; } adaslice__slot;

static uint64_t adaslice__cut_key(adaslice__cut c) { return (uint64_t)c.below << 32 | c.above; }

static adaslice__slot *adaslice__slot_of(adaslice__slot *table, size_t cap, uint64_t key)
{
    size_t i = (size_t)adaslice__mix(key) & (cap - 1);
    while (table[i].key != key && table[i].key != ADASLICE__NO_KEY) i = (i + 1) & (cap - 1);
    return table + i;
}

static void adaslice__zrange(const adaslice_mesh *m, size_t t, double *lo, double *hi)
{
    const uint32_t *v = m->triangles + 3 * t;
    double a = m->vertices[3 * (size_t)v[0] + 2], b = m->vertices[3 * (size_t)v[1] + 2];
    double c = m->vertices[3 * (size_t)v[2] + 2];
    *lo = a < b ? (a < c ? a : c) : (b < c ? b : c);
    *hi = a > b ? (a > c ? a : c) : (b > c ? b : c);
}

/* The cut of a triangle spanning h (lowest z <= h < highest z). Walking its
   corners in winding order, the walk leaves the side above h once and comes
   back once; the segment runs from the edge where it comes down to the edge
   where it goes up. That is the direction z x n, so a loop turns
   counter-clockwise seen from +z around material. */
static adaslice__segment adaslice__cut_triangle(const adaslice_mesh *m, size_t t, double h)
{
    const uint32_t *v = m->triangles + 3 * t;
    adaslice__segment s;
    int k;
    memset(&s, 0, sizeof s);
    for (k = 0; k < 3; k++) {
        uint32_t a = v[k], b = v[(k + 1) % 3];
        int a_up = m->vertices[3 * (size_t)a + 2] > h, b_up = m->vertices[3 * (size_t)b + 2] > h;
        if (a_up && !b_up) { s.from.below = b; s.from.above = a; }
        if (!a_up && b_up) { s.to.below = a; s.to.above = b; }
    }
    return s;
}

/* Appends a point unless it repeats the last one: a plane through a vertex
   cuts every edge at that vertex in the same place. */
static void adaslice__put_point(adaslice_contours *c, adaslice_polygon *p, const double xy[2])
{
    double *q = c->points + 2 * (p->first + p->count);
    if (p->count && q[-2] == xy[0] && q[-1] == xy[1]) return;
    q[0] = xy[0];
    q[1] = xy[1];
    p->count++;
}

/* Follows `next` from segment i. A loop left with fewer than three distinct
   points (a plane touching a lowest vertex) or a polyline with fewer than two
   has no extent and is dropped. */
static void adaslice__emit(adaslice_contours *c, const adaslice_mesh *m, double h, adaslice__segment *seg,
                           uint32_t i)
{
    adaslice_polygon *p = c->polygons + c->polygon_count;
    uint32_t start = i, last;
    double xy[2];
    const double *q;
    p->first = c->point_count;
    p->count = 0;
    do {
        seg[i].state |= ADASLICE__USED;
        adaslice__cut_point(m, seg[i].from.below, seg[i].from.above, h, xy);
        adaslice__put_point(c, p, xy);
        last = i;
        i = seg[i].next;
    } while (i != ADASLICE__NONE && !(seg[i].state & ADASLICE__USED));
    p->closed = i == start;
    if (!p->closed) {
        adaslice__cut_point(m, seg[last].to.below, seg[last].to.above, h, xy);
        adaslice__put_point(c, p, xy);
    }
    q = c->points + 2 * p->first;
    while (p->closed && p->count > 1 && q[2 * p->count - 2] == q[0] && q[2 * p->count - 1] == q[1]) p->count--;
    if (p->count < (p->closed ? 3u : 2u)) return;
    p->next = c->polygon_count;
    c->point_count += p->count;
    c->polygon_count++;
}

/* Links each segment to one that starts on the edge it ends on, then emits the
   chains: first those with no predecessor (open), then the loops that remain.
   Pairing is one to one, so on a non-manifold edge it picks arbitrarily, which
   changes neither the signed area nor any winding number. */
static adaslice_result adaslice__chain(adaslice_contours *c, size_t *point_cap, size_t *polygon_cap,
                                       const adaslice_mesh *m, double h, adaslice__segment *seg, size_t s,
                                       adaslice__slot *table, adaslice_error *err)
{
    size_t cap = adaslice__table_size(s), i;
    int pass;
    void *p;
    if (c->point_count + 2 * s > *point_cap) {
        p = adaslice__grow(&c->allocator, c->points, c->point_count, point_cap, c->point_count + 2 * s,
                           2 * sizeof(double));
        if (!p) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory at z = %g", h);
        c->points = ADASLICE__CAST(double *, p);
    }
    if (c->polygon_count + s > *polygon_cap) {
        p = adaslice__grow(&c->allocator, c->polygons, c->polygon_count, polygon_cap, c->polygon_count + s,
                           sizeof(adaslice_polygon));
        if (!p) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory at z = %g", h);
        c->polygons = ADASLICE__CAST(adaslice_polygon *, p);
    }
    for (i = 0; i < cap; i++) table[i].key = ADASLICE__NO_KEY;
    for (i = 0; i < s; i++) {
        uint64_t key = adaslice__cut_key(seg[i].from);
        adaslice__slot *e = adaslice__slot_of(table, cap, key);
        if (e->key == ADASLICE__NO_KEY) { e->key = key; e->head = ADASLICE__NONE; }
        seg[i].same_from = e->head;
        e->head = (uint32_t)i;
    }
    for (i = 0; i < s; i++) {
        adaslice__slot *e = adaslice__slot_of(table, cap, adaslice__cut_key(seg[i].to));
        seg[i].next = e->key == ADASLICE__NO_KEY ? ADASLICE__NONE : e->head;
        if (seg[i].next != ADASLICE__NONE) {
            seg[seg[i].next].state |= ADASLICE__HAS_PREV;
            e->head = seg[seg[i].next].same_from;
        }
    }
    for (pass = 0; pass < 2; pass++)
        for (i = 0; i < s; i++)
            if (!(seg[i].state & ADASLICE__USED) && (pass || !(seg[i].state & ADASLICE__HAS_PREV)))
                adaslice__emit(c, m, h, seg, (uint32_t)i);
    return ADASLICE_OK;
}

typedef struct adaslice__end { double x, y; size_t index; } adaslice__end;

static int adaslice__end_cmp(const void *a, const void *b)
{
    const adaslice__end *p = ADASLICE__CAST(const adaslice__end *, a), *q = ADASLICE__CAST(const adaslice__end *, b);
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    return p->y < q->y ? -1 : p->y > q->y;
}

/* The first entry of sorted e[0 .. n) at (x, y) not taken yet (index
   SIZE_MAX: taken), or n. */
static size_t adaslice__end_find(const adaslice__end *e, size_t n, double x, double y)
{
    size_t lo = 0, hi = n;
    adaslice__end key;
    key.x = x;
    key.y = y;
    key.index = 0;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (adaslice__end_cmp(e + mid, &key) < 0) lo = mid + 1; else hi = mid;
    }
    while (lo < n && e[lo].x == x && e[lo].y == y && e[lo].index == SIZE_MAX) lo++;
    return lo < n && e[lo].x == x && e[lo].y == y ? lo : n;
}

/* Joins the open polylines of height h, polygons [first, first + open) (the
   chains emitted first), by the chords the masks close gaps with. The loose
   ends are cut from the same edges by adaslice__cut_point as the polylines'
   ends, so they are found by value: a polyline's last point among the tails,
   the head its chord goes to among the polylines' first points. An end not
   found (a facet of no area leaves loose ends but no polyline) takes its own
   start if free, else any start left, so that `next` stays a permutation.
   The cycles are then laid out one after another. */
static adaslice_result adaslice__contour_chords(adaslice_contours *c, const adaslice_mesh *m, adaslice__gaps **gaps,
                                                size_t first, double h, adaslice_error *err)
{
    adaslice_polygon *poly = c->polygons + first, *cycle;
    adaslice__end *tail, *start;
    size_t open = 0, n, k, pos, *place;
    adaslice__gaps *g;
    adaslice_result r;
    while (first + open < c->polygon_count && !poly[open].closed) open++;
    if (!open) return ADASLICE_OK;
    if (!*gaps && (r = adaslice__gaps_init(gaps, m, &c->allocator, err)) != ADASLICE_OK) return r;
    if (!(g = *gaps)) return ADASLICE_OK;
    if ((r = adaslice__gaps_at(g, m, h, err)) != ADASLICE_OK) return r;
    n = g->tails;
    tail = ADASLICE__CAST(adaslice__end *, adaslice__alloc(&c->allocator, n ? n : 1, sizeof *tail));
    start = ADASLICE__CAST(adaslice__end *, adaslice__alloc(&c->allocator, open, sizeof *start));
    cycle = ADASLICE__CAST(adaslice_polygon *, adaslice__alloc(&c->allocator, open, sizeof *cycle));
    place = ADASLICE__CAST(size_t *, adaslice__alloc(&c->allocator, open, sizeof *place));
    r = tail && start && cycle && place ? ADASLICE_OK
                                        : adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory at z = %g", h);
    if (r == ADASLICE_OK) {
        for (k = 0; k < n; k++) {
            tail[k].x = g->tail[2 * k];
            tail[k].y = g->tail[2 * k + 1];
            tail[k].index = SIZE_MAX;
        }
        for (k = 0; k < g->heads; k++) if (g->taker[k] < n) tail[g->taker[k]].index = k;
        for (k = 0; k < open; k++) {
            const double *q = c->points + 2 * poly[k].first;
            start[k].x = q[0];
            start[k].y = q[1];
            start[k].index = k;
            place[k] = SIZE_MAX; /* the start its chord goes to, for now */
        }
        qsort(tail, n, sizeof *tail, adaslice__end_cmp);
        qsort(start, open, sizeof *start, adaslice__end_cmp);
        for (k = 0; k < open; k++) {
            const double *e = c->points + 2 * (poly[k].first + poly[k].count - 1), *head;
            size_t t = adaslice__end_find(tail, n, e[0], e[1]), s;
            if (t == n) continue;
            head = g->head + 2 * tail[t].index;
            tail[t].index = SIZE_MAX;
            if ((s = adaslice__end_find(start, open, head[0], head[1])) == open) continue;
            place[k] = start[s].index;
            start[s].index = SIZE_MAX;
        }
        /* the starts left, by polygon: start[i].index == SIZE_MAX when taken */
        for (k = 0; k < open; k++) cycle[k].next = 0;
        for (k = 0; k < open; k++) if (start[k].index != SIZE_MAX) cycle[start[k].index].next = 1;
        for (k = 0; k < open; k++)
            if (place[k] == SIZE_MAX && cycle[k].next) { place[k] = k; cycle[k].next = 0; }
        for (k = 0, pos = 0; k < open; k++) {
            if (place[k] != SIZE_MAX) continue;
            while (!cycle[pos].next) pos++;
            place[k] = pos;
            cycle[pos].next = 0;
        }
        for (k = 0; k < open; k++) poly[k].next = place[k];
        /* each cycle as a run: place[k] becomes polygon k's new position */
        for (k = 0; k < open; k++) place[k] = SIZE_MAX;
        for (k = 0, pos = 0; k < open; k++) {
            size_t q = k;
            while (place[q] == SIZE_MAX) {
                place[q] = pos;
                cycle[pos++] = poly[q];
                q = poly[q].next;
            }
        }
        for (k = 0; k < open; k++) cycle[k].next = first + place[cycle[k].next];
        memcpy(poly, cycle, open * sizeof *poly);
    }
    adaslice__free(&c->allocator, tail);
    adaslice__free(&c->allocator, start);
    adaslice__free(&c->allocator, cycle);
    adaslice__free(&c->allocator, place);
    return r;
}

static size_t adaslice__first_at_or_above(const double *h, size_t n, double z)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (h[mid] < z) lo = mid + 1; else hi = mid;
    }
    return lo;
}

static adaslice_result adaslice__contour_check(const adaslice_mesh *m, const double *heights, size_t count,
                                               adaslice_error *err)
{
    size_t i;
    if (!m || (m->triangle_count && (!m->vertices || !m->triangles)))
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: no mesh given");
    if (count && !heights) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: heights is NULL");
    if ((uint64_t)m->triangle_count >= ADASLICE__NONE || (uint64_t)count >= ADASLICE__NONE)
        return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "contours: %zu triangles at %zu heights is too many",
                              m->triangle_count, count);
    for (i = 0; i < count; i++) {
        if (!(fabs(heights[i]) <= DBL_MAX))
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: height %zu is %g", i, heights[i]);
        if (i && heights[i] < heights[i - 1])
            return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                                  "contours: heights must not decrease, but height %zu is %g after %g", i,
                                  heights[i], heights[i - 1]);
    }
    for (i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return adaslice__fail(err, ADASLICE_ERR_INDEX, 0, 0, "contours: triangle %zu uses vertex %u of %zu",
                                  i / 3, (unsigned)m->triangles[i], m->vertex_count);
    return ADASLICE_OK;
}

ADASLICE_DEF adaslice_result adaslice_contours_slice(const adaslice_mesh *mesh, const double *heights,
                                                     size_t count, const adaslice_contour_options *options,
                                                     adaslice_contours *out, adaslice_error *err)
{
    adaslice_result r;
    size_t n, t, j, *bucket, taken = 0, active_count = 0, point_cap = 0, polygon_cap = 0;
    uint32_t *order, *active;
    adaslice__segment *seg;
    adaslice__slot *table;
    adaslice__gaps *gaps = NULL; /* the mesh's unbalanced edges, found at the first open polyline */
    if (!out) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "contours: no output given");
    memset(out, 0, sizeof *out);
    if ((r = adaslice__contour_check(mesh, heights, count, err)) != ADASLICE_OK) return r;
    n = mesh->triangle_count;
    out->allocator = adaslice__allocator(options ? options->allocator : NULL);
    out->height_count = count;
    out->heights = ADASLICE__CAST(double *, adaslice__alloc(&out->allocator, count, sizeof(double)));
    out->first_polygon = ADASLICE__CAST(size_t *, adaslice__alloc(&out->allocator, count + 1, sizeof(size_t)));
    bucket = ADASLICE__CAST(size_t *, adaslice__alloc(&out->allocator, count + 1, sizeof(size_t)));
    order = ADASLICE__CAST(uint32_t *, adaslice__alloc(&out->allocator, n, sizeof(uint32_t)));
    active = ADASLICE__CAST(uint32_t *, adaslice__alloc(&out->allocator, n, sizeof(uint32_t)));
    seg = ADASLICE__CAST(adaslice__segment *, adaslice__alloc(&out->allocator, n, sizeof(adaslice__segment)));
    table = ADASLICE__CAST(adaslice__slot *, adaslice__alloc(&out->allocator, adaslice__table_size(n),
                                                             sizeof(adaslice__slot)));
    r = out->heights && out->first_polygon && bucket && order && active && seg && table
            ? ADASLICE_OK
            : adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "contours: out of memory for %zu triangles", n);
    if (r == ADASLICE_OK) {
        if (count) memcpy(out->heights, heights, count * sizeof(double));
        /* Counting sort by the first height at or above the triangle's lowest z;
           `active` holds that height for now. Triangles that span no height
           (flat ones among them) are never touched again. */
        memset(bucket, 0, (count + 1) * sizeof(size_t));
        for (t = 0; t < n; t++) {
            const uint32_t *v = mesh->triangles + 3 * t;
            double lo, hi;
            adaslice__zrange(mesh, t, &lo, &hi);
            j = adaslice__first_at_or_above(heights, count, lo);
            /* a triangle repeating a corner has no area and no proper edges */
            if (j < count && heights[j] < hi && v[0] != v[1] && v[1] != v[2] && v[2] != v[0]) {
                active[t] = (uint32_t)j;
                bucket[j + 1]++;
            } else {
                active[t] = ADASLICE__NONE;
            }
        }
        for (j = 0; j < count; j++) bucket[j + 1] += bucket[j];
        for (t = 0; t < n; t++)
            if (active[t] != ADASLICE__NONE) order[bucket[active[t]]++] = (uint32_t)t;
        /* now bucket[j] is where height j's triangles end in `order` */
        out->first_polygon[0] = 0;
        for (j = 0; j < count && r == ADASLICE_OK; j++) {
            double h = heights[j];
            size_t a, s = 0;
            while (taken < bucket[j]) active[active_count++] = order[taken++];
            for (a = 0; a < active_count; a++) {
                double lo, hi;
                adaslice__zrange(mesh, active[a], &lo, &hi);
                if (hi <= h) continue; /* below this height, so below every later one */
                active[s] = active[a];
                seg[s++] = adaslice__cut_triangle(mesh, active[a], h);
            }
            out->triangle_visits += active_count;
            out->segment_count += s;
            active_count = s;
            r = adaslice__chain(out, &point_cap, &polygon_cap, mesh, h, seg, s, table, err);
            if (r == ADASLICE_OK) r = adaslice__contour_chords(out, mesh, &gaps, out->first_polygon[j], h, err);
            out->first_polygon[j + 1] = out->polygon_count;
        }
    }
    adaslice__free(&out->allocator, bucket);
    adaslice__free(&out->allocator, order);
    adaslice__free(&out->allocator, active);
    adaslice__free(&out->allocator, seg);
    adaslice__free(&out->allocator, table);
    adaslice__gaps_free(gaps);
    if (r != ADASLICE_OK) adaslice_contours_free(out);
    else adaslice__ok(err);
    return r;
}

ADASLICE_DEF void adaslice_contours_free(adaslice_contours *c)
{
    if (!c) return;
    adaslice__free(&c->allocator, c->heights);
    adaslice__free(&c->allocator, c->first_polygon);
    adaslice__free(&c->allocator, c->polygons);
    adaslice__free(&c->allocator, c->points);
    memset(c, 0, sizeof *c);
}

/* (s, e) with s + e == a + b exactly (Knuth's two-sum). */
static double adaslice__two_sum(double a, double b, double *e)
{
    double s = a + b, bv = s - a, av = s - bv;
    *e = (a - av) + (b - bv);
    return s;
}

/* Exact sign of (bx - ax)(py - ay) - (by - ay)(px - ax): each difference is
   split into two doubles and each product into two by fma, both without error;
   the 16 terms go into a nonoverlapping expansion (Shewchuk's grow-expansion)
   whose largest nonzero component has the sign of the whole. */
static int adaslice__orient_exact(const double a[2], const double b[2], double px, double py)
{
    double d[4][2], term[16], x[17], q, e;
    int i, k, n = 0, len = 0;
    d[0][0] = adaslice__two_sum(b[0], -a[0], &d[0][1]);
    d[1][0] = adaslice__two_sum(py, -a[1], &d[1][1]);
    d[2][0] = adaslice__two_sum(b[1], -a[1], &d[2][1]);
    d[3][0] = adaslice__two_sum(px, -a[0], &d[3][1]);
    for (i = 0; i < 2; i++)
        for (k = 0; k < 2; k++) {
            double p = d[0][i] * d[1][k], r = d[2][i] * d[3][k];
            term[n++] = p;
            term[n++] = fma(d[0][i], d[1][k], -p);
            term[n++] = -r;
            term[n++] = -fma(d[2][i], d[3][k], -r);
        }
    for (i = 0; i < 16; i++) {
        q = term[i];
        for (k = 0; k < len; k++) {
            q = adaslice__two_sum(q, x[k], &e);
            x[k] = e;
        }
        x[len++] = q;
    }
    while (len > 0 && x[len - 1] == 0) len--;
    return len == 0 ? 0 : x[len - 1] > 0 ? 1 : -1;
}

/* Sign of the orientation of p against the edge a -> b. The float value is
   trusted when it exceeds Shewchuk's bound (3 + 16 u) u (|l| + |r|) on its error. */
static int adaslice__orient(const double a[2], const double b[2], double px, double py)
{
    const double u = DBL_EPSILON / 2;
    double l = (b[0] - a[0]) * (py - a[1]), r = (b[1] - a[1]) * (px - a[0]), d = l - r;
    double bound = (3 + 16 * u) * u * (fabs(l) + fabs(r));
    if (d > bound) return 1;
    if (-d > bound) return -1;
    return adaslice__orient_exact(a, b, px, py);
}

/* Where polygon p's edge from its point k ends: its next point, or after its
   last the first point of polygon `next` (its own for a loop). */
static const double *adaslice__edge_end(const adaslice_contours *c, size_t p, size_t k)
{
    const adaslice_polygon *poly = c->polygons + p;
    return c->points + 2 * (k + 1 < poly->count ? poly->first + k + 1 : c->polygons[poly->next].first);
}

ADASLICE_DEF int adaslice_contours_winding(const adaslice_contours *c, size_t height_index, double x, double y)
{
    size_t p, k;
    int w = 0;
    if (!c || height_index >= c->height_count) return 0;
    for (p = c->first_polygon[height_index]; p < c->first_polygon[height_index + 1]; p++) {
        size_t n = c->polygons[p].count;
        const double *a = c->points + 2 * c->polygons[p].first, *b;
        /* an edge counts when it crosses the ray to +x from the point: upward
           with the point on its left, or downward with it on its right; y-ranges
           are half-open, so a ray through a vertex counts it once */
        for (k = 0; k < n; k++, a = b) {
            b = adaslice__edge_end(c, p, k);
            if (a[1] <= y) {
                if (b[1] > y && adaslice__orient(a, b, x, y) > 0) w++;
            } else if (b[1] <= y && adaslice__orient(a, b, x, y) < 0) {
                w--;
            }
        }
    }
    return w;
}

ADASLICE_DEF double adaslice_contours_distance(const adaslice_contours *c, size_t height_index, double x,
                                               double y)
{
    double best = HUGE_VAL;
    size_t p, k;
    if (!c || height_index >= c->height_count) return best;
    for (p = c->first_polygon[height_index]; p < c->first_polygon[height_index + 1]; p++) {
        size_t n = c->polygons[p].count;
        const double *a = c->points + 2 * c->polygons[p].first, *b;
        for (k = 0; k < n; k++, a = b) {
            b = adaslice__edge_end(c, p, k);
            double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy, t = 0, ex, ey;
            if (len2 > 0) t = ((x - a[0]) * dx + (y - a[1]) * dy) / len2;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            ex = a[0] + t * dx - x;
            ey = a[1] + t * dy - y;
            if (ex * ex + ey * ey < best) best = ex * ex + ey * ey;
        }
    }
    return sqrt(best);
}

#endif /* ADASLICE_NO_CONTOURS */

/* ============================================================= job output */

ADASLICE_DEF adaslice_result adaslice_cure_fit(double s1, double t1, double s2, double t2, adaslice_cure *cure,
                                               adaslice_error *err)
{
    double dp;
    if (!cure) return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "exposure: no output given");
    memset(cure, 0, sizeof *cure);
    if (!(s1 > 0) || !(s2 > 0) || !(t1 > 0) || !(t2 > 0) || s1 > DBL_MAX || s2 > DBL_MAX || t1 > DBL_MAX || t2 > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "exposure %g s@%g mm, %g s@%g mm: seconds and thicknesses must be positive", s1, t1, s2, t2);
    dp = (t2 - t1) / log(s2 / s1);
    if (t1 == t2 || s1 == s2 || !(dp > 0) || dp > DBL_MAX)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0,
                              "exposure %g s@%g mm, %g s@%g mm: the thicker layer must need the longer exposure",
                              s1, t1, s2, t2);
    cure->seconds = s1;
    cure->thickness = t1;
    cure->penetration = dp;
    adaslice__ok(err);
    return ADASLICE_OK;
}

ADASLICE_DEF double adaslice_cure_seconds(const adaslice_cure *c, double thickness)
{
    if (!(c->penetration > 0)) return c->seconds;
    return c->seconds * exp((thickness - c->thickness) / c->penetration);
}

/* The preview's camera, rows of rot: the picture's right, its up and the
   direction towards the viewer, who stands el above the plate at az from +x.
   Picture up is +z leaned back along the view, so the build direction stays
   vertical in the picture whatever the viewpoint (turning the view onto +z
   by the shortest rotation, as adaslice_rotation_to_z does, tips it). */
static void adaslice__preview_camera(double el, double az, double rot[9])
{
    rot[0] = -sin(az);           rot[1] = cos(az);            rot[2] = 0;
    rot[3] = -sin(el) * cos(az); rot[4] = -sin(el) * sin(az); rot[5] = cos(el);
    rot[6] = cos(el) * cos(az);  rot[7] = cos(el) * sin(az);  rot[8] = sin(el);
}

ADASLICE_DEF adaslice_result adaslice_preview(const adaslice_mesh *mesh, int width, int height,
                                              const adaslice_preview_options *options, unsigned char *rgb,
                                              adaslice_error *err)
{
    static const unsigned char resin[3] = {96, 132, 168};
    adaslice_preview_options opt;
    adaslice_mesh turned;
    adaslice_grid g;
    adaslice_allocator al;
    adaslice_result r;
    float *depth;
    uint32_t *face;
    /* in the camera's frame: up, towards the viewer and to the left, so the
       top is the brightest and the two sides in view differ */
    double el, az, rot[9], lo3[3], hi3[3], pitch, light[3] = {-0.45, 0.55, 0.70};
    const unsigned char *part, *back;
    size_t p;
    int k;
    if (!rgb || width < 1 || height < 1 || width > 16384 || height > 16384)
        return adaslice__fail(err, ADASLICE_ERR_ARGUMENT, 0, 0, "preview: %d x %d pixels is not a picture (1 to 16384 a side)",
                              width, height);
    if ((r = adaslice__mesh_check(mesh, "preview", err)) != ADASLICE_OK) return r;
    if (!mesh->triangle_count) return adaslice__fail(err, ADASLICE_ERR_EMPTY, 0, 0, "preview: the mesh has no triangles");
    { /* turned in floats, a part near their largest overflows to inf */
        double across = adaslice__diagonal(mesh);
        if (!(across <= 1e15))
            return adaslice__fail(err, ADASLICE_ERR_OVERFLOW, 0, 0, "preview: the part is %g mm across: over 1e15 mm, "
                                  "where its turned view leaves the range of floats", across);
    }
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    el = (opt.elevation == 0 && opt.azimuth == 0 ? 30 : opt.elevation) * 3.14159265358979323846 / 180;
    az = (opt.elevation == 0 && opt.azimuth == 0 ? -45 : opt.azimuth) * 3.14159265358979323846 / 180;
    part = opt.colour[0] | opt.colour[1] | opt.colour[2] ? opt.colour : resin;
    back = opt.background;
    al = adaslice__allocator(opt.allocator);
    /* the viewer's direction turned onto +z: the LDI's last sample is the nearest */
    adaslice__preview_camera(el, az, rot);
    if (!adaslice__turned_copy(mesh, rot, &al, &turned)) return adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "preview: out of memory");
    adaslice_mesh_bounds(&turned, lo3, hi3);
    /* the part fills 90% of the picture's tighter side */
    pitch = (hi3[0] - lo3[0]) / (0.9 * width);
    if ((hi3[1] - lo3[1]) / (0.9 * height) > pitch) pitch = (hi3[1] - lo3[1]) / (0.9 * height);
    if (!(pitch > 0)) pitch = 1;
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = pitch;
    g.width = width;
    g.height = height;
    g.origin[0] = 0.5 * (lo3[0] + hi3[0]) - 0.5 * width * pitch;
    g.origin[1] = 0.5 * (lo3[1] + hi3[1]) - 0.5 * height * pitch;
    depth = ADASLICE__CAST(float *, adaslice__alloc(&al, (size_t)width * (size_t)height, sizeof(float)));
    face = ADASLICE__CAST(uint32_t *, adaslice__alloc(&al, (size_t)width * (size_t)height, sizeof(uint32_t)));
    r = depth && face ? adaslice__nearest_faces(&turned, &g, lo3[2], depth, face, err)
                      : adaslice__fail(err, ADASLICE_ERR_NOMEM, 0, 0, "preview: out of memory");
    adaslice__free(&al, depth);
    if (r != ADASLICE_OK) { adaslice__free(&al, face); adaslice__free(&al, turned.vertices); return r; }
    for (p = 0; p < (size_t)width * (size_t)height; p++) {
        /* LDI row 0 is the lowest y: the picture's bottom row */
        size_t px = (size_t)(height - 1 - (int)(p / (size_t)width)) * (size_t)width + p % (size_t)width;
        unsigned char *out = rgb + 3 * p;
        double a[3], b[3], c[3], n[3], len, shade;
        const unsigned char *colour = part;
        if (face[px] == ADASLICE__NONE) { memcpy(out, back, 3); continue; }
        {
            size_t t = face[px] & ~ADASLICE_SAMPLE_LEAVES;
            adaslice__corner(&turned, t, 0, a);
            adaslice__corner(&turned, t, 1, b);
            adaslice__corner(&turned, t, 2, c);
            if (opt.face_colours) colour = opt.face_colours + 3 * t;
        }
        adaslice__normal(a, b, c, n);
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        /* either side of a face may face the viewer (open or inside-out meshes) */
        shade = len > 0 ? fabs(n[0] * light[0] + n[1] * light[1] + n[2] * light[2]) / len : 0;
        shade = 0.35 + 0.65 * shade;
        for (k = 0; k < 3; k++) out[k] = (unsigned char)(colour[k] * shade + 0.5);
    }
    adaslice__free(&al, face);
    adaslice__free(&al, turned.vertices);
    adaslice__ok(err);
    return ADASLICE_OK;
}

#endif /* ADASLICE_IMPLEMENTATION_DONE */
#endif /* ADASLICE_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under either license, at your choice:
A - MIT No Attribution
Copyright (c) 2026 the adaslice authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
------------------------------------------------------------------------------
*/

