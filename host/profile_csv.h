/* A metric profile from a file (plan --profile FILE): one value of phi per
   line, or CSV with the value last and, in two or more columns, z first (the
   bin centres, as plan --profile-out writes them), which give the bin and z0.
   Blank lines and # comments are skipped, and so is a first line that is not
   a number (a header). */
#ifndef ADASLICE_HOST_PROFILE_CSV_H
#define ADASLICE_HOST_PROFILE_CSV_H
#include "../adaslice.h"

/* Reads path into *out (its phi malloc'd: the caller frees it)
   with `metric`; bin_given 0 takes the bin from the z column, or the
   default with none; a z column whose bins differ from bin_given is
   refused, and so is a profile whose values pass max_bytes (--memory).
   RC_OK, or a complaint naming the file, line and value, and nothing held. */
int profile_csv_read(const char *path, adaslice_metric metric, double bin_given, double max_bytes,
                     adaslice_profile *out);
#endif
