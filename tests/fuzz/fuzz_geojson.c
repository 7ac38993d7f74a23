/* libFuzzer target: the GeoJSON loader (plx_load_geojson) on arbitrary bytes.
 * Seeds: fixtures/ and tests/corpus/. See fuzz_common.h for the checks. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fuzz_engine lenient, strict;
    static int ready;
    if (!ready) {
        fuzz_engine_open(&lenient, 0);
        fuzz_engine_open(&strict, 1);
        ready = 1;
    }
    fuzz_check_text(&lenient, &strict, (const char *)data, size, fuzz_hash(data, size));
    return 0;
}
