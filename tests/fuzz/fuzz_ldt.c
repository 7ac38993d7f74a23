/* libFuzzer target: the EULUMDAT parser (photometry_parse) on arbitrary
 * bytes (inputs holding "TILT=" would go to the IES parser and are
 * skipped: fuzz_ies.c covers that one). Seeds: fixtures/photometry/. */
#include "fuzz_photometry.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    size_t i;
    for (i = 0; i + 5 <= size; i++)
        if (memcmp(data + i, "TILT=", 5) == 0)
            return 0;
    fuzz_photometry((const char *)data, size);
    return 0;
}
