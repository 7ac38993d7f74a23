/* lonlat: the one projection of WGS84 lon/lat to local metres (SPEC §1),
 * about a centre (lon0, lat0) the loader picks:
 *   x = (lon - lon0) * 111320 * cos(lat0),  y = (lat - lat0) * 110540
 * used by the loader, lamp layers and plx_lonlat_to_local /
 * plx_local_to_lonlat (the command goes through those). coslat is
 * lonlat_cos(lat0), computed once by the caller. */
#ifndef PLX_LONLAT_H
#define PLX_LONLAT_H

#define LONLAT_M_PER_DEG_LON 111320.0
#define LONLAT_M_PER_DEG_LAT 110540.0

/* cos(lat0), lat0 in degrees. */
double lonlat_cos(double lat0);
/* (*x, *y) from lon/lat to local metres, in place. */
void lonlat_to_local(double lon0, double lat0, double coslat, double *x, double *y);
/* (*x, *y) from local metres back to lon/lat, in place. */
void lonlat_from_local(double lon0, double lat0, double coslat, double *x, double *y);

#endif
