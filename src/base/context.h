/* context: what the stages may ask of the engine without seeing inside it
 * (the engine's layout, base/engine.h, is for src/api and src/base only):
 * report an error or a warning, log, read the clock and the load options.
 * Implemented in engine.c. */
#ifndef PLX_CONTEXT_H
#define PLX_CONTEXT_H

#include "polarlux.h"
#include "base/arena.h"
#include "base/scene.h"

#define ENGINE_ERR_BYTES 512

/* Sets the last error to 'msg' (the text of 'b' when b is given) and returns s. */
plx_status eng_fail(plx_engine *e, plx_status s, const char *msg);
/* The standard out-of-memory error, naming the part that asked. */
plx_status eng_nomem(plx_engine *e, const char *during);
void eng_clear_error(plx_engine *e);
void eng_log(plx_engine *e, plx_log_level level, const char *msg);
uint64_t eng_clock(plx_engine *e);
/* A warning: counted (plx_warning_count) and logged at PLX_LOG_WARN. */
void eng_warn(plx_engine *e, const char *msg);
/* The config's strict flag: the first bad feature fails the load. */
int eng_strict(const plx_engine *e);
/* The engine's port (its functions may be NULL). */
const plx_port *eng_port(const plx_engine *e);

#endif
