/* Camera paths for polarlux walk: a GeoJSON LineString of eye positions
 * [x, y] or [x, y, z] (z default 1.7 m; lon/lat projected as the scene
 * unless properties.units is "m" on the collection or the feature),
 * optionally with properties.targets, one [x, y, z] per position
 * (keyframes); without targets the eye looks 10 m ahead along the path at
 * its own height, or pitch_tan x that distance below it. */
#ifndef PLX_CLI_WALK_PATH_H
#define PLX_CLI_WALK_PATH_H

#include <stddef.h>
#include <stdint.h>
#include "polarlux.h"

typedef struct walk_path {
    uint32_t n;
    double *eye;      /* 3 n, local metres */
    double *target;   /* 3 n or NULL */
    uint32_t lines;   /* line features in the file (LineString, MultiLineString): the walk follows the first LineString */
    double pitch_tan; /* without targets: the view's drop per metre ahead (walk --pitch; 0: level) */
} walk_path;

/* 0 on success; -1 with "FILE: why" in err. */
int walk_path_read(const char *path, plx_engine *e, walk_path *wp, char *err, size_t errlen);
void walk_path_free(walk_path *wp);
/* Length of the eye polyline, m. */
double walk_path_length(const walk_path *wp);
/* Whether the path gives the camera a direction: targets, or a stretch
 * that moves horizontally. */
int walk_path_moves(const walk_path *wp);
/* The camera at arc length s along the eye polyline. Where the targets
 * or the point ahead give no direction (the target at the eye, the point
 * ahead above or at it), the eye looks 10 m along its walk (the nearest
 * stretch that moves horizontally), or east without one. Without
 * targets the target lies pitch_tan times its horizontal distance below
 * the eye's height. */
void walk_path_camera(const walk_path *wp, double s, double eye[3] /* OUT */, double target[3] /* OUT */);

#endif
