/* photometry: measured luminaire intensity distributions (SPEC §2.1).
 *
 * Parses IES LM-63 (1995, 2002, 2019 syntax; TILT=NONE; photometric type C)
 * and EULUMDAT text from memory (the core reads no files), completes the
 * table by the format's symmetry rule and answers I(C, gamma) bilinearly.
 *
 * The table: ng vertical angles g[] (degrees from nadir, ascending) and nc
 * C angles c[] in [0, 360) ascending, each naming a stored row of ng
 * candela values (multipliers applied). Between the last C angle and the
 * first one + 360 the lookup wraps round. nc == 1: rotationally symmetric.
 * Outside [g[0], g[ng-1]] the intensity is 0.
 *
 * Symmetry rules (README "Photometric lamps"):
 *   IES, by the horizontal angles: one angle -> rotational; 0..90 ->
 *   quadrants (C -> 180 - C, C -> 180 + C, C -> 360 - C); 0..180 or
 *   180..360 -> bilateral about the C0-C180 plane (C -> 360 - C); 90..270
 *   -> bilateral about C90-C270 (C -> 180 - C); anything else starting at
 *   0 -> as given (wrapping round).
 *   EULUMDAT Isym 0 all Mc planes; 1 rotational (one plane); 2 planes
 *   C0..C180 mirrored (C -> 360 - C); 3 planes C90..C270 mirrored
 *   (C -> 180 - C); 4 planes C0..C90 mirrored into four quadrants.
 * Multipliers: IES candela multiplier x ballast factor (x ballast-lamp
 * photometric factor in LM-63-1995); EULUMDAT values (cd/klm) x the
 * conversion factor (line 24) x the first lamp set's flux / 1000.
 */
#ifndef PLX_PHOTOMETRY_H
#define PLX_PHOTOMETRY_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"

#define PHOTOMETRY_MAX_ANGLES 10000   /* per axis; more is refused */
#define PHOTOMETRY_MAX_CD 1e12        /* an intensity above this, multipliers applied, is refused
                                       * (the brightest searchlights are near 1e10 cd) */

typedef struct photometry {
    uint32_t ng, nc, nrows;
    const double *g;          /* ng vertical angles, degrees, ascending */
    const double *c;          /* nc C angles in [0, 360), ascending */
    const uint32_t *row;      /* nc: the stored row of each C angle */
    const double *cd;         /* nrows * ng candela, multipliers applied */
    double peak;              /* largest value of the table (cd) */
    double flux;              /* lm: the integral of the bilinear I over the sphere */
    double gamma_lit;         /* degrees: I = 0 for every gamma >= gamma_lit */
    int format;               /* 1 IES, 2 EULUMDAT */
} photometry;

/* Parses data[0..len) (IES when a line starts with "TILT=", else
 * EULUMDAT) into memory of part 'part' of a. On failure returns
 * PLX_E_PARSE with "NAME: line L: why" in err (or PLX_E_NOMEM; the arena is
 * then back where it was). On success err holds a warning, or is empty:
 * the header's stated flux (EULUMDAT light output ratio x lamp flux, IES
 * lamps x lumens) more than 10% off the table's own (an IES table only
 * above it). */
plx_status photometry_parse(arena *a, plx_part part, const char *data, size_t len, const char *name,
                            const photometry **out /* OUT */, char *err, size_t errlen);

/* I(C, gamma) in cd, angles in degrees (C any value, taken modulo 360). */
double photometry_at(const photometry *p, double c_deg, double gamma_deg);

/* The lamp's frame from its azimuth and tilt (degrees), scene.h fields. */
void photometry_lamp_frame(scene_lamp *lp);

/* The lamp's intensity (cd) toward the unit direction d from the lamp
 * (dimming applied): the isotropic intensity when it has no photometry. */
double lamp_intensity(const scene_lamp *lp, const double d[3]);

/* C and gamma (degrees) of the world direction d (unit) in the lamp's frame. */
void lamp_direction_angles(const scene_lamp *lp, const double d[3], double *c_deg, double *gamma_deg);

/* The lamp's total flux (lm): 4 pi I when isotropic, else dimming x the
 * table's integral (0 while a named photometry file has not been given). */
double lamp_flux(const scene_lamp *lp);

#endif
