/* libFuzzer target: the IES LM-63 parser (photometry_parse) on arbitrary
 * bytes. An input without a "TILT=" line would be read as EULUMDAT, so one
 * is put in front. Seeds: fixtures/photometry/. */
#include "fuzz_photometry.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char head[] = "IESNA:LM-63-2002\nTILT=NONE\n";
    char *buf;
    size_t i;
    for (i = 0; i + 5 <= size; i++)
        if (memcmp(data + i, "TILT=", 5) == 0)
            break;
    if (i + 5 <= size) {
        fuzz_photometry((const char *)data, size);
        return 0;
    }
    buf = malloc(sizeof head - 1 + size + 1);
    CHECK(buf != NULL);
    memcpy(buf, head, sizeof head - 1);
    if (size)
        memcpy(buf + sizeof head - 1, data, size);
    fuzz_photometry(buf, sizeof head - 1 + size);
    free(buf);
    return 0;
}
