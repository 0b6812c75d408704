// loddump: inspects a baked pack using only the runtime. TRANSIENT skeleton: the runtime work
// replaces it with the real pack summary before anything lands.
#include <cstdio>

#include "lodrt/lodrt.h"

int main(int argc, char** argv) {
    (void)argv;
    if (argc < 2) {
        std::fprintf(stderr, "usage: loddump PACK [--json]\n");
        return 2;
    }
    std::printf("lodrt %s\n", lodrt::versionString());
    return 0;
}
