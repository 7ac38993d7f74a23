/* photon_select: photons only from the lamps that can matter for a region
 * (photon_select.c). */
#ifndef PLX_PHOTON_SELECT_H
#define PLX_PHOTON_SELECT_H

#include "photon/photon.h"

/*
 * Photons only from the lamps that can matter for a region
 * (photon_select.c): the lamps whose reach (the disk of radius R about the
 * lamp, horizontally) comes within margin metres of box (x0, y0, x1, y1);
 * box NULL: every lamp again. The frame's photons are shared among the
 * chosen lamps by flux, so each carries the same flux as before and the
 * chosen lamps get more of them; the light of the others is left out (its
 * later bounces reach the region only over more than margin metres).
 * Drops every accumulated photon (photon_reset). Returns the number of
 * lamps chosen. Needs no memory.
 */
uint32_t photon_select_lamps(photon_sys *ps, const double box[4], double margin);

#endif
