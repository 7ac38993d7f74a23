/* jsonscan: reading JSON text in place, without building a tree.
 *
 * jsoncheck.c checks the whole text once (the grammar cJSON 1.7.15 parses,
 * with its error positions); after that, a value is named by the byte offset
 * of its first character and read straight from the text: its kind, its
 * members and elements, its string (unescaped on the fly) or number. The
 * reads below assume text[0..len) passed jsonscan_check; they allocate
 * nothing and hold no state. */
#ifndef PLX_JSONSCAN_H
#define PLX_JSONSCAN_H

#include <stddef.h>
#include <stdint.h>

/* No value (a missing member, the end of an array). */
#define JSONSCAN_NONE ((size_t)-1)
/* Containers nested deeper than this are refused (cJSON's limit). */
#define JSONSCAN_DEPTH 1000

typedef enum js_kind { JS_NONE = 0, JS_NULL, JS_FALSE, JS_TRUE, JS_NUMBER, JS_STRING, JS_ARRAY, JS_OBJECT } js_kind;

/* Checks the text (jsoncheck.c). 1: a value was read, *at is the offset just
 * after it (what follows is the caller's business). 0: malformed, *at is the
 * offset cJSON reports (len - 1 when it ran off the end). Allocates nothing;
 * its own state is a bounded stack of JSONSCAN_DEPTH bits. */
int jsonscan_check(const char *text, size_t len, size_t *at /* OUT */);

/* The offset of the first byte from off that is not white space to cJSON
 * (bytes 0..32); len when none. */
size_t jsonscan_ws(const char *text, size_t len, size_t off);

/* After a document's value ending at end: the offset of the first byte
 * that is not JSON white space (space, tab, CR, LF), or len when there is
 * none or only NUL bytes follow (a C string's terminator; a NUL with text
 * after it is that text's start: before 2026-12-03 a NUL ended the text and
 * what followed was ignored). Text after the value is malformed: the scene
 * loader and the command's paths refuse it alike. */
size_t jsonscan_trailing(const char *text, size_t len, size_t end);

/* The containers open just before offset off (strings skipped): at an
 * error where a '[' or '{' opens the JSONSCAN_DEPTH-th, the text is nested
 * deeper than cJSON parses, not malformed. */
long jsonscan_depth_at(const char *text, size_t len, size_t off);

/* The kind of the value at off (JS_NONE for JSONSCAN_NONE). */
js_kind jsonscan_kind(const char *text, size_t off);

/* The offset just after the value at off. */
size_t jsonscan_skip(const char *text, size_t len, size_t off);

/* Children of the container at c: the elements of an array, the values of
 * an object's members (as cJSON's child list). jsonscan_first gives the first
 * (JSONSCAN_NONE for an empty container or another kind); jsonscan_next the
 * one after the child at off, whose container is an object when in_object. */
size_t jsonscan_first(const char *text, size_t len, size_t c);
size_t jsonscan_next(const char *text, size_t len, size_t off, int in_object);

/* The value of the first member of the object at obj whose unescaped key
 * (up to a NUL, as a C string) equals key; JSONSCAN_NONE when none or when
 * obj is not an object. */
size_t jsonscan_get(const char *text, size_t len, size_t obj, const char *key);

/* 1 when the key (a string) at off equals key, as jsonscan_get compares. */
int jsonscan_key_is(const char *text, size_t len, size_t off, const char *key);

/* The string at off unescaped, up to its first NUL (a C string): copies at
 * most cap - 1 bytes and a NUL into buf (cap may be 0) and returns the full
 * length. */
size_t jsonscan_string(const char *text, size_t len, size_t off, char *buf, size_t cap);

/* The \uXXXX escape at s (with its low surrogate when s holds a high one)
 * as a code point: the bytes it takes (6 or 12), or 0 when cJSON refuses it
 * (fewer than avail bytes, a lone or reversed surrogate). */
size_t jsonscan_utf16(const char *s, size_t avail, unsigned long *cp /* OUT */);

/* 1 when the string at off, unescaped up to its first NUL, equals s. */
int jsonscan_string_is(const char *text, size_t len, size_t off, const char *s);

/* The bytes of the number at off that strtod reads (cJSON's rule: the run of
 * 0-9 + - e E . is cut to its longest prefix in strtod's decimal form); 0
 * when no number starts there. */
size_t jsonscan_number_len(const char *text, size_t len, size_t off);

/* Line (1-based) and column (1-based) of byte offset 'off'. */
void jsonscan_line_col(const char *text, size_t len, size_t off, uint32_t *line, uint32_t *col);

/* 1 when the text ends inside a string or with brackets still open. */
int jsonscan_truncated(const char *text, size_t len);

/* Where to report a parse that stopped at byte 'at' (cJSON's error
 * pointer as an offset; past len or unknown: len): the end of the text
 * when cJSON ran off it (it reports the last byte of a text cut short)
 * or the text is empty or white space (after a UTF-8 byte-order mark,
 * which the readers skip), else 'at'; *tail gets the words for the end
 * (": the file is empty", ": the text holds only white space", ": the
 * text holds only a UTF-8 byte-order mark" [" and white space"], ": the
 * text ends early", ": unexpected end"), or the slip found at 'at' (": JSON
 * has no NaN or Infinity ...", ": JSON strings take double quotes", ": a
 * comma before the closing bracket", ": JSON has no comments"), or "". */
size_t jsonscan_error_at(const char *text, size_t len, size_t at, const char **tail /* OUT */);

#endif
