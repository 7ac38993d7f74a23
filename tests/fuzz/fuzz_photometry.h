/* Shared by fuzz_ies.c and fuzz_ldt.c: photometry_parse on arbitrary bytes
 * must either fail with one line "NAME: line L: why" and give its memory
 * back, or give a table whose every lookup is finite, within [0, peak],
 * with a finite non-negative flux. A failed check aborts (a crash). */
#ifndef FUZZ_PHOTOMETRY_H
#define FUZZ_PHOTOMETRY_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/photometry.h"
#include "fuzz_check.h"

static void fuzz_photometry(const char *text, size_t len)
{
    static void *mem;
    static arena a;
    const photometry *p = NULL;
    char err[512];
    arena_mark m;
    plx_status st;
    int i, j;
    if (!mem) {
        mem = malloc(64u << 20);
        CHECK(mem != NULL);
        arena_init(&a, mem, 64u << 20);
    }
    m = arena_get_mark(&a);
    st = photometry_parse(&a, PLX_PART_SCENE, text, len, "fuzz.ies", &p, err, sizeof err);
    if (st != PLX_OK) {
        CHECK(st == PLX_E_PARSE || st == PLX_E_NOMEM);
        CHECK(p == NULL);
        CHECK(strncmp(err, "fuzz.ies: ", 10) == 0 && strchr(err, '\n') == NULL);
        CHECK(a.lo == m.lo && a.hi == m.hi);
        return;
    }
    /* success: no message, or the flux check's and the tilt's warnings, one line */
    CHECK(err[0] == '\0' || (strncmp(err, "fuzz.ies: ", 10) == 0 && strchr(err, '\n') == NULL &&
                              (strstr(err, "; the table is used as given") || strstr(err, "every intensity") ||
                               strstr(err, "TILT=INCLUDE"))));
    CHECK(p && p->ng >= 1 && p->nc >= 1 && p->nrows >= 1);
    CHECK(isfinite(p->peak) && p->peak >= 0.0);
    CHECK(isfinite(p->flux) && p->flux >= 0.0);
    CHECK(p->flux <= 4.0 * 3.14159265358979323846 * p->peak * (1.0 + 1e-9) + 1e-300);
    for (i = 0; i < (int)p->nc; i++)
        CHECK(p->c[i] >= 0.0 && p->c[i] < 360.0 && (i == 0 || p->c[i] > p->c[i - 1]) && p->row[i] < p->nrows);
    for (i = -2; i <= 38; i++)
        for (j = -1; j <= 19; j++) {
            double v = photometry_at(p, i * 10.3 - 7.0, j * 9.7);
            CHECK(isfinite(v) && v >= 0.0 && v <= p->peak * (1.0 + 1e-12));
        }
    arena_release(&a, &m);
}

#endif
