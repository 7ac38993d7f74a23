/* lonlat: the projection of SPEC §1 (see lonlat.h). */
#include <math.h>

#include "base/lonlat.h"

double lonlat_cos(double lat0)
{
    return cos(lat0 * 3.14159265358979323846 / 180.0);
}

void lonlat_to_local(double lon0, double lat0, double coslat, double *x, double *y)
{
    *x = (*x - lon0) * LONLAT_M_PER_DEG_LON * coslat;
    *y = (*y - lat0) * LONLAT_M_PER_DEG_LAT;
}

void lonlat_from_local(double lon0, double lat0, double coslat, double *x, double *y)
{
    *x = lon0 + *x / (LONLAT_M_PER_DEG_LON * coslat);
    *y = lat0 + *y / LONLAT_M_PER_DEG_LAT;
}
