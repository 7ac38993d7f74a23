/* ref_light: brute-force reference for SPEC §2, direct light.
 *
 *   E(P) = sum over lamps of V(L,P) * I * max(0, n.w) / d^2 * W(d / R)
 *   w = (L - P) / d,  d = |L - P|,  W(x) = (clamp(1 - x^4, 0, 1))^2
 *
 * Every lamp is tested against every building; no acceleration.
 *
 * Rules for degenerate cases:
 *  - A building's solid interior is (footprint interior) x (min_height,
 *    height), an open set: walls, roofs, the underside of raised buildings
 *    and courtyard walls are boundary, not interior. A segment that runs
 *    along a wall or grazes a roof plane is not blocked. Buildings are
 *    tested one by one, so a segment running exactly along a wall shared by
 *    two adjacent buildings is in neither open interior and is not blocked
 *    (a zero-width leak; moved off the wall by any amount it is blocked).
 *  - The segment is open: its end points never block (a P on a facade or a
 *    roof is fine).
 *  - A contact shorter than 1e-9 m (a segment through a corner, computed
 *    with rounding) is ignored: blocked means the segment has a piece longer
 *    than 1e-9 m inside some solid interior. SPEC allows either answer within
 *    1e-6 m of a shadow boundary.
 *  - d == 0 (P at the lamp): the lamp contributes 0. A lamp with radius
 *    <= 0 contributes 0. n must be a unit vector; it is used as given.
 *  - Lamps inside buildings are the loader's business; here they are taken
 *    as they are (their light is usually blocked by their own building).
 */
#ifndef REF_LIGHT_H
#define REF_LIGHT_H

#include "base/scene.h"

/* 1 if the open segment L->P meets some building's solid interior, else 0;
 * -1 if malloc fails (scratch of 4 + 2 * vertices-of-a-building values). */
int ref_segment_blocked(const scene *s, const double L[3], const double P[3]);

/* E(P) in lux at surface point P with unit normal n, colour ignored.
 * NaN if malloc fails in a segment test. */
double ref_illuminance(const scene *s, const double P[3], const double n[3]);

/* Same with each lamp's term multiplied by its colour, per channel. */
void ref_illuminance_rgb(const scene *s, const double P[3], const double n[3],
                         double rgb[3]);

/* The falloff window W(x) = (clamp(1 - x^4, 0, 1))^2. */
double ref_window(double x);

#endif
