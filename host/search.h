/* The build-direction search (§4.3) on all of the host's cores, for
   adaslice orient and plan|slice --orient best. */
#ifndef ADASLICE_HOST_SEARCH_H
#define ADASLICE_HOST_SEARCH_H
#include <stddef.h>
#include "../adaslice.h"

/* the local minima reported besides the best direction */
#define SEARCH_MINIMA 3

/* Scores `count` Fibonacci-lattice directions with these options into
   *scores (malloc'd), F(O) with `alpha`; minima[0 .. *minima_count) are the
   best local minima, best first (at most SEARCH_MINIMA + 1). RC_OK or a
   complaint made. */
int orient_search(const adaslice_mesh *mesh, const adaslice_profile_options *po, const adaslice_plan_options *pl,
                  size_t count, double alpha, adaslice_direction_score **scores, size_t *minima, size_t *minima_count);
#endif
