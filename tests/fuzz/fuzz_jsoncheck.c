/* libFuzzer target: the streaming loader's JSON checker and in-place reads
 * (src/base/jsoncheck.c, src/base/jsonscan.c) against cJSON itself on
 * arbitrary bytes: the same accept/refuse and error byte, and where cJSON
 * parses, the same kinds, numbers (bit for bit), strings, children and the
 * member found for each key. Seeds: fixtures/ and tests/corpus/. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cjson/cJSON.h>

#include "base/jsonscan.h"
#include "fuzz_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void same_value(const char *t, size_t len, const cJSON *node, size_t off, int depth);

static void same_children(const char *t, size_t len, const cJSON *node, size_t off, int depth)
{
    const cJSON *c;
    size_t mine = jsonscan_first(t, len, off);
    int obj = cJSON_IsObject(node);
    for (c = node->child; c; c = c->next) {
        CHECK(mine != JSONSCAN_NONE);
        same_value(t, len, c, mine, depth + 1);
        if (obj) {
            const cJSON *want = cJSON_GetObjectItemCaseSensitive(node, c->string), *w = node->child;
            size_t k = jsonscan_first(t, len, off);
            while (w != want) {
                w = w->next;
                k = jsonscan_next(t, len, k, 1);
            }
            CHECK(jsonscan_get(t, len, off, c->string) == k);
        }
        mine = jsonscan_next(t, len, mine, obj);
    }
    CHECK(mine == JSONSCAN_NONE);
}

static void same_value(const char *t, size_t len, const cJSON *node, size_t off, int depth)
{
    js_kind k = jsonscan_kind(t, off);
    CHECK(jsonscan_skip(t, len, off) <= len);
    if (cJSON_IsNull(node)) {
        CHECK(k == JS_NULL);
    } else if (cJSON_IsFalse(node)) {
        CHECK(k == JS_FALSE);
    } else if (cJSON_IsTrue(node)) {
        CHECK(k == JS_TRUE);
    } else if (cJSON_IsNumber(node)) {
        size_t n = jsonscan_number_len(t, len, off);
        char *buf = malloc(n + 1);
        double v;
        CHECK(k == JS_NUMBER && n > 0 && buf);
        memcpy(buf, t + off, n);
        buf[n] = '\0';
        v = strtod(buf, NULL);
        CHECK(memcmp(&v, &node->valuedouble, sizeof v) == 0);
        free(buf);
    } else if (cJSON_IsString(node)) {
        size_t n = strlen(node->valuestring);
        char *buf = malloc(n + 1);
        CHECK(k == JS_STRING && buf);
        CHECK(jsonscan_string(t, len, off, buf, n + 1) == n);
        CHECK(strcmp(buf, node->valuestring) == 0);
        CHECK(jsonscan_string_is(t, len, off, node->valuestring));
        free(buf);
    } else if (depth < 64) { /* deeper: the accept/refuse check covers it */
        CHECK(k == (cJSON_IsArray(node) ? JS_ARRAY : JS_OBJECT));
        same_children(t, len, node, off, depth);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* a copy of exactly size bytes, so reading past the end is caught */
    char *t = calloc(size ? size : 1, 1);
    const char *end = NULL;
    cJSON *root;
    size_t at = 0;
    int ok;
    CHECK(t != NULL);
    if (size)
        memcpy(t, data, size);
    root = cJSON_ParseWithLengthOpts(t, size, &end, 0);
    ok = jsonscan_check(t, size, &at);
    CHECK(ok == (root != NULL));
    if (size > 0)
        CHECK(end != NULL && at == (size_t)(end - t));
    if (root) {
        size_t p = size >= 5 && memcmp(t, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
        same_value(t, size, root, jsonscan_ws(t, size, p), 0);
        cJSON_Delete(root);
    }
    free(t);
    return 0;
}
