/* The build-direction search (§4.3) on all of the host's cores, for
   adaslice orient and plan|slice --orient best. */
#ifndef ADASLICE_HOST_SEARCH_H
#define ADASLICE_HOST_SEARCH_H
#include <stddef.h>
#include "../adaslice.h"

/* the local minima reported besides the best direction */
#define SEARCH_MINIMA 3

/* The axis directions scored besides the lattice, after it: the part as
   loaded (+z) first, then -z, +x, -x, +y, -y. A lattice never holds them, and
   flat-faced parts often plan best along one. */
#define SEARCH_AXES 6

/* Scores `count` Fibonacci-lattice directions and the SEARCH_AXES axis
   directions with these options into *scores (malloc'd, count + SEARCH_AXES
   of them, the axes last), F(O) with `alpha` over all of them;
   minima[0 .. *minima_count) are the best local minima, best first (at most
   SEARCH_MINIMA + 1), so the best never scores worse than the part as
   loaded. A search whose threads' profiles could need more than
   memory_limit bytes (0: no limit) is refused before any work. RC_OK or a
   complaint made, naming `model`. */
int orient_search(const char *model, const adaslice_mesh *mesh, const adaslice_profile_options *po, const adaslice_plan_options *pl,
                  size_t count, double alpha, double memory_limit, adaslice_direction_score **scores, size_t *minima,
                  size_t *minima_count);
#endif
