/* lampmerge: lamps at one spot with one radius become one lamp at load
 * (intensities summed, colour weighted by intensity: the same light). */
#ifndef PLX_LAMPMERGE_H
#define PLX_LAMPMERGE_H

#include "scene/loader.h"

/* Merges lamps at one spot with one radius into one, warning once a spot. */
plx_status ld_merge_duplicate_lamps(loader *ld);

#endif
