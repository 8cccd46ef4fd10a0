/* The library's implementation, compiled once for the tool (and once per
   configuration: the sanitized build links its own). */
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"
