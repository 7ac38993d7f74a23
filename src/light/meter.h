/* meter: the SPEC §6 pedestrian quantities at a point (E_h, E_v, E_sc,
 * E_hs), direct light through the same visibility as illuminance.c. */
#ifndef PLX_LIGHT_METER_H
#define PLX_LIGHT_METER_H

#include "light/light.h"

/* SPEC §6 at P (direct light, same visibility as light_illuminance):
 * out[0] E_h (= light_illuminance with n = +z), out[1] E_v(u), out[2]
 * E_sc(u), out[3] E_hs, lux; u a horizontal unit vector (x, y), the
 * facing direction (src/light/meter.c). */
plx_status light_meter(light *L, const double P[3], const double u[2], double out[4] /* OUT */);

#endif
